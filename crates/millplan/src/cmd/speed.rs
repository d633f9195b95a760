//! `millplan speed`: constant-cutting-speed spindle control for ball-end finishing.

use crate::cmd::{print_diagnostics, read_options, write_program_file, TargetArg, UnitArg};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::{read_program, read_surface, Outputs};
use clap::ValueEnum;
use millplan_driver::speed::{self as lib, Convention, Cutting, NormalMode, SpeedRequest, Surface};
use millplan_plan::checks;
use millplan_plan::pipeline::Context;
use millplan_plan::speed::Summary;
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ConventionArg {
    Auto,
    Tip,
    Centre,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum NormalArg {
    Smooth,
    Facet,
    Ball,
}

/// Set the spindle speed per block so the cutting speed stays constant
/// from the working diameter of the ball at each point (docs/usage.md).
///
/// For every cutting point of every ball-end operation millplan finds where the
/// ball touches the part (STL), the surface inclination, the feed direction and
/// which side is already machined, computes the working diameter D_w and sets
/// n = 1000·vc/(π·D_w), within the machine's spindle range and acceleration.
/// By default the feed follows, F = n·z·fz, so the chip load stays constant.
/// Only speeds and feeds change, never positions.
///
/// Exit code 3 (the program is still written) when more than 5 % of the
/// cutting points do not touch the part: the part does not match the program,
/// or the CL points are not what --convention says, and the speeds mean nothing.
///
/// Before it is written the program is checked: the IR verifier, every S
/// within the machine's spindle range, every cutting F above 0 and at most
/// the machine's maximum, every position the input's. A check that fails
/// names its line and exits 3 with nothing written, unless --force.
#[derive(clap::Args)]
pub struct Args {
    /// Toolpath: APT/CL or G-code with a ball-end tool.
    pub path: PathBuf,
    /// Part surface (STL) in the same coordinates as the toolpath.
    #[arg(long)]
    pub stl: PathBuf,
    /// Unit of the STL's numbers (an STL does not say): mm (default) or inch,
    /// converted to mm on reading.
    #[arg(long, value_enum)]
    pub stl_units: Option<UnitArg>,
    /// Cutting speed, m/min.
    #[arg(long)]
    pub vc: f64,
    /// Feed per tooth, mm.
    #[arg(long)]
    pub fz: f64,
    /// Number of flutes.
    #[arg(long, default_value_t = millplan_driver::command_defaults::cutting::FLUTES)]
    pub flutes: u32,
    /// Stock thickness along the surface normal (finishing allowance), mm.
    #[arg(long)]
    pub ap: f64,
    /// Machine file (examples/machine.toml): the spindle range and
    /// acceleration, the feed range and rapid rate, the control's dialect
    /// and its axes for the time estimate; a typical HSC machine by default.
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Output program.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output dialect (default: the machine's, else the input's).
    #[arg(long, value_enum)]
    pub to: Option<TargetArg>,
    /// Ball diameter (mm) for operations whose tool has no geometry, as in
    /// G-code programs that call tools by number only.
    #[arg(long)]
    pub ball_d: Option<f64>,
    /// Keep the programmed feed instead of F = n·z·fz.
    #[arg(long)]
    pub keep_feed: bool,
    /// Write a new S only when the speed changes by more than this, 1/min.
    #[arg(long, default_value_t = millplan_driver::command_defaults::speed::S_THRESHOLD)]
    pub s_threshold: f64,
    /// Which tool point the CL points are.
    #[arg(long, value_enum, default_value = "auto")]
    pub convention: ConventionArg,
    /// Normals at the contact point.
    #[arg(long, value_enum, default_value = "smooth")]
    pub normals: NormalArg,
    /// Use the paper's nearest-in-centre facet mapping (comparison only).
    #[arg(long)]
    pub nearest_incentre: bool,
    /// Per-point table (CSV).
    #[arg(long)]
    pub table: Option<PathBuf>,
    /// Report (self-contained HTML with SVG plots).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Print a JSON summary on standard output.
    #[arg(long)]
    pub json: bool,
    /// Unit of the toolpath when the file does not say.
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    /// Print the wall time of each phase on standard error.
    #[arg(long)]
    pub timings: bool,
    /// Print no warnings or notes about the inputs (errors still print).
    #[arg(long, short)]
    pub quiet: bool,
    /// Write the program even when a check before writing refuses it (an S
    /// or F outside the machine, a position changed); the findings are
    /// printed and the run ends with exit 3.
    #[arg(long)]
    pub force: bool,
}

fn request(a: &Args) -> SpeedRequest {
    SpeedRequest {
        cut: Cutting {
            vc: a.vc,
            fz: a.fz,
            flutes: a.flutes,
            ap: a.ap,
        },
        ball_d: a.ball_d,
        s_threshold: a.s_threshold,
        keep_feed: a.keep_feed,
        convention: match a.convention {
            ConventionArg::Auto => None,
            ConventionArg::Tip => Some(Convention::Tip),
            ConventionArg::Centre => Some(Convention::Centre),
        },
        normals: match a.normals {
            NormalArg::Smooth => NormalMode::Smooth,
            NormalArg::Facet => NormalMode::Facet,
            NormalArg::Ball => NormalMode::Ball,
        },
        nearest_incentre: a.nearest_incentre,
        keep_rows: a.table.is_some() || a.report.is_some(),
    }
}

/// What the reader thread hands back: the program and the cycle time
/// estimated on it, each with its own wall time.
struct ReadBeside {
    parsed: CliResult<millplan_nc::Parsed>,
    read_s: f64,
    time_before: f64,
    estimate_s: f64,
}

type Reader = std::thread::JoinHandle<ReadBeside>;

/// Reads the program on its own thread, and estimates its cycle time there,
/// while the STL is read and its search trees are built.
fn spawn_reader(a: &Args, machine: &millplan_plan::machine::Machine) -> CliResult<Reader> {
    let (path, opts) = (a.path.clone(), read_options(a.units, None)?);
    let machine = machine.clone();
    Ok(std::thread::spawn(move || {
        let t = std::time::Instant::now();
        let parsed = read_program(&path, opts);
        let read_s = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let time_before = match &parsed {
            Ok(p) => millplan_plan::timing::estimate_program(&p.program, &machine).total_s,
            Err(_) => 0.0,
        };
        ReadBeside {
            parsed,
            read_s,
            time_before,
            estimate_s: t.elapsed().as_secs_f64(),
        }
    }))
}

fn join(r: Reader) -> ReadBeside {
    r.join().unwrap_or_else(|e| std::panic::resume_unwind(e))
}

/// The program, table and report, checked against each other and the inputs
/// before any work.
fn plan_outputs(a: &Args) -> CliResult<Outputs> {
    let inputs: Vec<&std::path::Path> = [
        Some(a.path.as_path()),
        Some(a.stl.as_path()),
        a.machine.as_deref(),
    ]
    .into_iter()
    .flatten()
    .collect();
    Outputs::plan(
        &inputs,
        &[
            ("-o", Some(&a.output)),
            ("--table", a.table.as_deref()),
            ("--report", a.report.as_deref()),
        ],
        false,
    )
}

/// The part, read while the program is read on its own thread; the STL's
/// wall time. A program error is still reported first.
fn read_part(
    a: &Args,
    machine: &millplan_plan::machine::Machine,
) -> CliResult<(millplan_geom::TriMesh, Reader, f64)> {
    let t = std::time::Instant::now();
    let reader = spawn_reader(a, machine)?;
    match read_surface(&a.stl, a.stl_units) {
        Ok((m, _)) => Ok((m, reader, t.elapsed().as_secs_f64())),
        Err(e) => Err(join(reader).parsed.err().unwrap_or(e)),
    }
}

/// The reading phases' times in the context's timings.
fn record_reading(
    cx: &Context,
    t_setup: f64,
    [t_mesh, t_surface, t_inputs]: [f64; 3],
    [read_s, estimate_s]: [f64; 2],
) {
    cx.record("arguments, machine file and outputs checked", t_setup);
    cx.record("  read STL", t_mesh);
    cx.record("  surface (BVH, vertex normals)", t_surface);
    cx.record("  read toolpath (its own thread)", read_s);
    cx.record(
        "  time estimate of the input (after it, same thread)",
        estimate_s,
    );
    cx.record("read STL, surface and toolpath", t_inputs);
}

/// The program, unless spindle control finds nothing to act on in it: then
/// that, named, exit 3 and nothing written.
fn something_to_control(
    path: &std::path::Path,
    parsed: millplan_nc::Parsed,
) -> CliResult<millplan_nc::Parsed> {
    match lib::nothing_to_control(&parsed.program) {
        Some(why) => Err(CliError {
            code: EXIT_FINDINGS,
            message: format!("{}: {why}", path.display()),
        }),
        None => Ok(parsed),
    }
}

pub fn run(a: Args) -> CliResult<i32> {
    let t0 = std::time::Instant::now();
    let req = request(&a);
    lib::check(&req).map_err(CliError::input)?;
    let mut outputs = plan_outputs(&a)?;
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    let t_setup = t0.elapsed().as_secs_f64();
    let (mesh, reader, t_mesh) = read_part(&a, &machine)?;
    let t = std::time::Instant::now();
    let surface = Surface::new(&mesh);
    let t_surface = t.elapsed().as_secs_f64();
    let read = join(reader);
    let t_inputs = t0.elapsed().as_secs_f64() - t_setup;
    let parsed = something_to_control(&a.path, read.parsed?)?;
    print_diagnostics(&a.path, &parsed.diagnostics, a.quiet || a.json);
    let target = crate::cmd::target_with_machine(a.to, &a.output, &machine, parsed.program.source)?;
    let bar = crate::progress::Phases::new(!a.quiet && parsed.program.move_count() >= 100_000);
    let hook = |phase: &str, done: usize, total: usize| bar.report(phase, done, total);
    let cx = Context::new(machine)
        .with_surface(surface)
        .with_progress(&hook);
    record_reading(
        &cx,
        t_setup,
        [t_mesh, t_surface, t_inputs],
        [read.read_s, read.estimate_s],
    );
    let input = parsed.program;
    let ran = lib::run(&req, &cx, &input).map_err(|e| crate::cmd::pass_error(&a.path, e));
    bar.finish();
    let (program, mut pass) = ran?;
    let checks = cx.time("checks of the output", || {
        lib::checks(&cx, &input, &program)
    });
    let checked = crate::verdict::enforce(&checks, &a.path, a.force)?;
    cx.time("input freed", || drop(input));
    let Some(summary) = pass.summary.take() else {
        return Err(CliError::internal("the speed pass left no summary"));
    };
    // A part that does not match its path makes every speed meaningless.
    let findings = part_findings(&cx, &mesh, &summary);
    print_diagnostics(&a.stl, &findings, a.quiet || a.json);
    let time_after = write_and_estimate(&a, &cx, &program, target, &mut outputs)?;
    let run = Ran {
        program: &program,
        summary: &summary,
        rows: &pass.rows,
        checks: &checks,
        findings: &findings,
        times: [read.time_before, time_after],
    };
    report_run(&a, &req, &cx, &run, outputs, target)?;
    print_timings(&a, &cx, t0);
    Ok(if checks::untrusted(&summary) || !checked {
        EXIT_FINDINGS
    } else {
        EXIT_OK
    })
}

/// The part's own findings: open edges, points off the part.
fn part_findings(
    cx: &Context,
    mesh: &millplan_geom::TriMesh,
    summary: &Summary,
) -> Vec<millplan_nc::Diagnostic> {
    cx.time("part checks (open edges, points off the part)", || {
        [checks::mesh(mesh), checks::off_surface(summary)]
            .into_iter()
            .flatten()
            .collect()
    })
}

/// The phases' timings on standard error (with --timings).
fn print_timings(a: &Args, cx: &Context, t0: std::time::Instant) {
    if a.timings {
        crate::timings::print(&cx.timings(), t0);
    }
}

/// Writes the program (staged, synced) while its cycle time is estimated on
/// another thread; returns the estimate.
fn write_and_estimate(
    a: &Args,
    cx: &Context,
    program: &millplan_nc::Program,
    target: millplan_nc::write::Target,
    outputs: &mut Outputs,
) -> CliResult<f64> {
    let t = std::time::Instant::now();
    let (written, (time_after, estimate_s)) = std::thread::scope(|s| {
        let estimate = s.spawn(|| {
            let t = std::time::Instant::now();
            let total = millplan_plan::timing::estimate_program(program, &cx.machine).total_s;
            (total, t.elapsed().as_secs_f64())
        });
        let written = write_program_file(
            program,
            cx.machine.write_options(target),
            outputs,
            &a.output,
            &a.path,
            a.quiet,
        );
        let w = t.elapsed().as_secs_f64();
        (
            written.map(|x| (x, w)),
            estimate
                .join()
                .unwrap_or_else(|e| std::panic::resume_unwind(e)),
        )
    });
    let (_, write_s) = written?;
    cx.record("  program written and synced", write_s);
    cx.record("  time estimate of the output (beside it)", estimate_s);
    cx.record(
        "program written, its time estimated",
        t.elapsed().as_secs_f64(),
    );
    Ok(time_after)
}

/// What a run made: the program, the pass's summary and rows, the checks,
/// the part's findings and the times before and after.
struct Ran<'a> {
    program: &'a millplan_nc::Program,
    summary: &'a Summary,
    rows: &'a [millplan_plan::speed::PointRow],
    checks: &'a [millplan_driver::Check],
    findings: &'a [millplan_nc::Diagnostic],
    times: [f64; 2],
}

/// The table and report written, the outputs committed, the summary printed.
fn report_run(
    a: &Args,
    req: &SpeedRequest,
    cx: &Context,
    r: &Ran,
    mut outputs: Outputs,
    target: millplan_nc::write::Target,
) -> CliResult<()> {
    let inputs = || {
        let mut i = report_inputs(
            (&a.path, r.program),
            &a.stl,
            &cx.machine,
            req.cut,
            r.findings,
            r.times,
        );
        i.failed = lib::failed_checks(r.checks);
        i
    };
    cx.time("table and report", || {
        write_table_and_report(a, &mut outputs, r.summary, r.rows, inputs)
    })?;
    cx.time("outputs renamed into place", || outputs.commit())?;
    let out = lib::Report::new(
        (r.summary, r.checks),
        (a.output.display().to_string(), target),
        &cx.machine,
        r.findings,
        r.times,
    );
    if a.json {
        crate::cmd::print_json(serde_json::to_value(&out).unwrap_or_default());
    } else {
        out!("{}", out.render_text());
    }
    Ok(())
}

/// The header, warnings and cycle times of a spindle-control report, the
/// program and the part named by their file names.
pub fn report_inputs(
    program: (&std::path::Path, &millplan_nc::Program),
    part: &std::path::Path,
    machine: &millplan_plan::machine::Machine,
    cut: Cutting,
    findings: &[millplan_nc::Diagnostic],
    times: [f64; 2],
) -> millplan_report::html::SpeedInputs {
    let name = |p: &std::path::Path| {
        p.file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    lib::report_inputs(
        (name(program.0), program.1),
        name(part),
        machine,
        cut,
        findings,
        times,
    )
}

/// The per-point table (--table) and the report (--report), when asked for.
fn write_table_and_report(
    a: &Args,
    outputs: &mut Outputs,
    summary: &Summary,
    rows: &[millplan_plan::speed::PointRow],
    inputs: impl FnOnce() -> millplan_report::html::SpeedInputs,
) -> CliResult<()> {
    if let Some(t) = &a.table {
        let csv = millplan_report::table::points_csv(rows);
        outputs.write(t, csv.as_bytes())?;
    }
    if let Some(r) = &a.report {
        let title = format!(
            "millplan speed: {}",
            a.path
                .file_name()
                .map(|f| f.to_string_lossy())
                .unwrap_or_default()
        );
        let html = millplan_report::html::speed_report(&title, &inputs(), summary, rows);
        outputs.write(r, html.as_bytes())?;
    }
    Ok(())
}
