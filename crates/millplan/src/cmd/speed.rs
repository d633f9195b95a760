//! `millplan speed`: constant-cutting-speed spindle control for ball-end finishing.

use crate::cmd::{print_diagnostics, write_program_file};
use crate::error::{exit, CliError, CliResult};
use crate::io::{read_program, Outputs};
use clap::ValueEnum;
use millplan_driver::feed::file_name;
use millplan_driver::speed::{
    self as lib, Convention, Cutting, NormalMode, SpeedError, SpeedRequest, Surface,
};
use millplan_geom::TriMesh;
use millplan_plan::pipeline::Context;
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
    #[command(flatten)]
    pub part: crate::cmd::args::Part,
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
    #[command(flatten)]
    pub machine: crate::cmd::args::MachineFile,
    #[command(flatten)]
    pub out: crate::cmd::args::ProgramOutput,
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
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub units: crate::cmd::args::ProgramUnits,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    #[command(flatten)]
    pub force: crate::cmd::args::Force,
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

/// The part, read while the program is read (and its cycle time estimated)
/// on a thread of its own; the STL's wall time. A program that does not
/// read is still the error reported first.
fn read_part(
    a: &Args,
    machine: &millplan_plan::machine::Machine,
) -> CliResult<(TriMesh, lib::Reader<CliError>, f64)> {
    let (path, opts) = (a.path.clone(), a.units.options()?);
    let t = std::time::Instant::now();
    let reader = lib::Reader::spawn(machine.clone(), move || read_program(&path, opts));
    match a.part.read() {
        Ok(m) => Ok((m, reader, t.elapsed().as_secs_f64())),
        Err(e) => Err(reader.join().err().unwrap_or(e)),
    }
}

pub fn run(a: Args) -> CliResult<i32> {
    let t0 = std::time::Instant::now();
    let req = request(&a);
    lib::check(&req).map_err(CliError::input)?;
    let (table, report) = (a.table.as_deref(), a.report.as_deref());
    let outs = [("-o", Some(&*a.out.output)), ("--table", table)];
    let outs = [&outs[..], &[("--report", report)]].concat();
    let (stl, machine) = (Some(&*a.part.stl), a.machine.machine.as_deref());
    let mut outputs = crate::io::plan(&[Some(&*a.path), stl, machine], &outs, false)?;
    let machine = a.machine.load()?;
    let t_setup = t0.elapsed().as_secs_f64();
    let (mesh, reader, t_mesh) = read_part(&a, &machine)?;
    let t = std::time::Instant::now();
    let surface = Surface::new(&mesh);
    let t_surface = t.elapsed().as_secs_f64();
    let read = reader.join()?;
    let t_inputs = t0.elapsed().as_secs_f64() - t_setup;
    let parsed = read.parsed;
    if let Some(why) = lib::nothing_to_control(&parsed.program) {
        return Err(CliError::findings(format!("{}: {why}", a.path.display())));
    }
    let quiet = a.notes.quiet;
    print_diagnostics(&a.path, &parsed.diagnostics, quiet || a.summary.json);
    let target = a.out.target(&machine, parsed.program.source)?;
    let long = millplan_driver::command_defaults::progress::long_program(&parsed.program);
    let bar = crate::progress::Phases::new(!quiet && long);
    let hook = |phase: &str, done: usize, total: usize| bar.report(phase, done, total);
    let cx = Context::new(machine)
        .with_surface(surface)
        .with_progress(&hook);
    let times = [t_setup, t_mesh, t_surface, t_inputs];
    lib::record_reading(&cx, times, [read.read_s, read.estimate_s]);
    let ran = lib::command(&req, &cx, &mesh, parsed.program);
    bar.finish();
    let out = ran.map_err(|e| match e {
        SpeedError::Pass(e) => crate::cmd::pass_error(&a.path, e),
        SpeedError::NoSummary => CliError::internal("the speed pass left no summary"),
    })?;
    let checked = a.force.enforce(&out.checks, &a.path)?;
    print_diagnostics(&a.part.stl, &out.findings, quiet || a.summary.json);
    let time_after = write(&a, &cx, &out.program, &mut outputs, target)?;
    let times = [read.time_before, time_after];
    report_run(&a, &req, &cx, (&out, times), outputs, target)?;
    if a.timings.on {
        crate::timings::print(&cx.timings(), t0);
    }
    Ok(exit(out.untrusted() || !checked))
}

/// Writes the program while its time is estimated beside it; that time.
fn write(
    a: &Args,
    cx: &Context,
    p: &millplan_nc::Program,
    outputs: &mut Outputs,
    target: millplan_nc::write::Target,
) -> CliResult<f64> {
    let t = std::time::Instant::now();
    let wo = cx.machine.write_options(target);
    let (o, q) = (&a.out.output, a.notes.quiet);
    let (written, time_after, [write_s, estimate_s]) = lib::write_beside(p, &cx.machine, || {
        write_program_file(p, wo, outputs, o, &a.path, q)
    });
    written?;
    cx.record("  program written and synced", write_s);
    cx.record("  time estimate of the output (beside it)", estimate_s);
    let t_write = t.elapsed().as_secs_f64();
    cx.record("program written, its time estimated", t_write);
    Ok(time_after)
}

/// The table and report written, the outputs committed, the summary printed.
fn report_run(
    a: &Args,
    req: &SpeedRequest,
    cx: &Context,
    (out, times): (&lib::Outcome, [f64; 2]),
    mut outputs: Outputs,
    target: millplan_nc::write::Target,
) -> CliResult<()> {
    cx.time("table and report", || -> CliResult<()> {
        if let Some(t) = &a.table {
            outputs.write(t, out.table_csv().as_bytes())?;
        }
        if let Some(r) = &a.report {
            let names = (file_name(&a.path), file_name(&a.part.stl));
            let html = out.report_html(names, &cx.machine, req.cut, times);
            outputs.write(r, html.as_bytes())?;
        }
        Ok(())
    })?;
    cx.time("outputs renamed into place", || outputs.commit())?;
    let written = (a.out.output.display().to_string(), target);
    let report = out.report(written, &cx.machine, times);
    a.summary.print(&report, |r| r.render_text());
    Ok(())
}
