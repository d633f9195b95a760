//! `millplan speed`: constant-cutting-speed spindle control for ball-end finishing.

use crate::cmd::{
    print_diagnostics, read_options, target_for, write_program_file, TargetArg, UnitArg,
};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::{read_program, read_surface, write_atomic};
use clap::ValueEnum;
use millplan_models::contact::{Convention, NormalMode, Surface};
use millplan_nc::write::Target;
use millplan_plan::checks;
use millplan_plan::machine::Machine;
use millplan_plan::pipeline::{self, Context};
use millplan_plan::speed::{FeedCoupling, SpeedParams, SpeedPass, Summary};
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
/// (paper 000, thesis 3).
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
#[derive(clap::Args)]
pub struct Args {
    /// Toolpath: APT/CL or G-code with a ball-end tool.
    pub path: PathBuf,
    /// Part surface (STL) in the same coordinates as the toolpath.
    #[arg(long)]
    pub stl: PathBuf,
    /// Cutting speed, m/min.
    #[arg(long)]
    pub vc: f64,
    /// Feed per tooth, mm.
    #[arg(long)]
    pub fz: f64,
    /// Number of flutes.
    #[arg(long, default_value_t = 2)]
    pub flutes: u32,
    /// Stock thickness along the surface normal (finishing allowance), mm.
    #[arg(long)]
    pub ap: f64,
    /// Machine description (TOML: spindle_min, spindle_max, spindle_accel,
    /// feed_min, feed_max, rapid, dialect); a typical HSC machine by default.
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
    #[arg(long, default_value_t = 1.0)]
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
    #[arg(long, short)]
    pub quiet: bool,
}

type Reader = std::thread::JoinHandle<(CliResult<millplan_nc::Parsed>, f64)>;

/// Reads the program on its own thread, while the STL is read and its
/// search trees are built.
fn spawn_reader(a: &Args, t0: std::time::Instant) -> Reader {
    let (path, opts) = (a.path.clone(), read_options(a.units, None));
    std::thread::spawn(move || {
        let parsed = read_program(&path, opts);
        (parsed, t0.elapsed().as_secs_f64())
    })
}

fn join(r: Reader) -> (CliResult<millplan_nc::Parsed>, f64) {
    r.join().unwrap_or_else(|e| std::panic::resume_unwind(e))
}

fn params(a: &Args) -> SpeedParams {
    let mut p = SpeedParams::new(a.vc, a.fz, a.flutes, a.ap);
    p.feed = if a.keep_feed {
        FeedCoupling::Programmed
    } else {
        FeedCoupling::ChipLoad
    };
    p.s_threshold = a.s_threshold.max(0.0);
    p.convention = match a.convention {
        ConventionArg::Auto => None,
        ConventionArg::Tip => Some(Convention::Tip),
        ConventionArg::Centre => Some(Convention::Centre),
    };
    p.normals = match a.normals {
        NormalArg::Smooth => NormalMode::Smooth,
        NormalArg::Facet => NormalMode::Facet,
        NormalArg::Ball => NormalMode::Ball,
    };
    p.nearest_incentre = a.nearest_incentre;
    p.ball_d = a.ball_d;
    p.keep_rows = a.table.is_some() || a.report.is_some();
    p
}

/// The dialect to write: --to; else the machine's, which the file name must
/// not contradict; else the file name's or the source's.
fn target(a: &Args, machine: &Machine, source: millplan_nc::Dialect) -> CliResult<Target> {
    match (a.to, machine.target()) {
        (None, Some(t)) => {
            let by_name = target_for(None, &a.output, source)?;
            if by_name != t && a.output.extension().is_some() {
                return Err(CliError::input(format!(
                    "{}: the machine file says {} but the file name says {}: give --to",
                    a.output.display(),
                    t.name(),
                    by_name.name()
                )));
            }
            Ok(t)
        }
        (to, _) => target_for(to, &a.output, source),
    }
}

pub fn run(a: Args) -> CliResult<i32> {
    crate::io::distinct_outputs(&[Some(&a.output), a.table.as_deref(), a.report.as_deref()])?;
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    let t0 = std::time::Instant::now();
    let reader = spawn_reader(&a, t0);
    let mesh = match read_surface(&a.stl) {
        Ok((m, _)) => m,
        // A program error is still reported first.
        Err(e) => return Err(join(reader).0.err().unwrap_or(e)),
    };
    let t_mesh = t0.elapsed().as_secs_f64();
    let surface = Surface::new(&mesh);
    let t_surface = t0.elapsed().as_secs_f64() - t_mesh;
    let (parsed, t_read) = join(reader);
    let parsed = parsed?;
    print_diagnostics(&a.path, &parsed.diagnostics, a.quiet || a.json);
    let target = target(&a, &machine, parsed.program.source)?;
    let cx = Context::new(machine).with_surface(surface);
    cx.record("read STL", t_mesh);
    cx.record("surface (BVH, vertex normals)", t_surface);
    cx.record("read toolpath (beside the two above)", t_read);
    let mut program = parsed.program;
    let mut pass = SpeedPass::new(params(&a));
    pipeline::run(&mut [&mut pass], &mut program, &cx)
        .map_err(|e| crate::cmd::pass_error(&a.path, e))?;
    let Some(summary) = pass.summary.take() else {
        return Err(CliError::internal("the speed pass left no summary"));
    };
    // A part that does not match its path makes every speed meaningless.
    let findings: Vec<_> = [checks::mesh(&mesh), checks::off_surface(&summary)]
        .into_iter()
        .flatten()
        .collect();
    print_diagnostics(&a.stl, &findings, a.quiet || a.json);
    let inputs = [a.path.as_path(), a.stl.as_path()];
    cx.time("program written and synced", || {
        write_program_file(
            &program,
            cx.machine.write_options(target),
            &a.output,
            &a.path,
            &inputs,
            a.quiet,
        )
    })?;
    if a.timings {
        for t in cx.timings() {
            eprintln!("{:>8.3} s  {}", t.seconds, t.name);
        }
        eprintln!(
            "{:>8.3} s  total until the program is written",
            t0.elapsed().as_secs_f64()
        );
    }
    write_table_and_report(&a, &summary, &pass.rows)?;
    if a.json {
        let mut j = serde_json::to_value(&summary).unwrap_or_default();
        j["output"] = serde_json::json!(a.output.display().to_string());
        j["dialect"] = serde_json::json!(target.name());
        j["machine"] = serde_json::to_value(&cx.machine).unwrap_or_default();
        j["findings"] = serde_json::to_value(&findings).unwrap_or_default();
        j["trusted"] = serde_json::json!(!checks::untrusted(&summary));
        println!("{}", serde_json::to_string_pretty(&j).unwrap_or_default());
    } else {
        print_summary(&summary, &a.output, target);
    }
    Ok(if checks::untrusted(&summary) {
        EXIT_FINDINGS
    } else {
        EXIT_OK
    })
}

/// The per-point table (--table) and the report (--report), when asked for.
fn write_table_and_report(
    a: &Args,
    summary: &Summary,
    rows: &[millplan_plan::speed::PointRow],
) -> CliResult<()> {
    let inputs = [a.path.as_path(), a.stl.as_path()];
    if let Some(t) = &a.table {
        let csv = millplan_report::table::points_csv(rows);
        write_atomic(t, csv.as_bytes(), &inputs)?;
    }
    if let Some(r) = &a.report {
        let title = format!(
            "millplan speed: {}",
            a.path
                .file_name()
                .map(|f| f.to_string_lossy())
                .unwrap_or_default()
        );
        let html = millplan_report::html::speed_report(&title, summary, rows, a.vc);
        write_atomic(r, html.as_bytes(), &inputs)?;
    }
    Ok(())
}

fn print_summary(s: &Summary, output: &std::path::Path, target: Target) {
    println!(
        "{} cutting points in {} ball-end operation(s), CL points read as {:?}",
        s.points, s.operations, s.convention
    );
    println!(
        "  D_w        {:.3} … {:.3} mm (mean {:.3})",
        s.d_w.min, s.d_w.max, s.d_w.mean
    );
    println!(
        "  spindle    {:.0} … {:.0} 1/min",
        s.spindle.min, s.spindle.max
    );
    println!(
        "  vc         {:.1} … {:.1} m/min with control; {:.1} … {:.1} at constant {:.0} 1/min",
        s.vc_controlled.min,
        s.vc_controlled.max,
        s.vc_constant.min,
        s.vc_constant.max,
        s.constant_spindle
    );
    println!(
        "  limits     {} clamped, {} rate-limited, {} held under the S threshold, {} feeds clamped",
        s.clamped, s.rate_limited, s.held, s.feed_clamped
    );
    if s.gap_flagged > 0 {
        println!("  warning    {} points are not R from the surface (gouge, wrong convention or a different part)", s.gap_flagged);
    }
    println!("  wrote      {} ({})", output.display(), target.name());
}
