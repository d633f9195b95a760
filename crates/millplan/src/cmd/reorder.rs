//! `millplan reorder`: reorder finishing points so the working diameter changes
//! least between successive points (paper 000, thesis 5), with safe links.

use crate::cmd::write_program;
use crate::error::{exit, CliError, CliResult};
use crate::timings::Table as _;
use clap::ValueEnum;
use millplan_driver::feed::file_name;
use millplan_driver::reorder as lib;
use millplan_plan::pipeline::Context;
use millplan_plan::reorder::{Method, Start};
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MethodArg {
    /// The machining as it will run: candidate orders (start corners, one-way,
    /// pass directions) measured with spindle control; the best one worse than
    /// the original on nothing, or the original when none is better.
    AsRun,
    /// The paper's greedy search over single points.
    Paper,
    /// Passes kept as units, improved by 2-opt on |Δn|, link length and turns.
    Optimised,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum StartArg {
    Lowest,
    Highest,
    Random,
}

/// Reorder the points of 3-axis ball-end finishing operations so the spindle,
/// driven for a constant cutting speed, runs better (docs/usage.md says
/// where the method comes from).
///
/// The default judges an order by its machining as it will run: the speeds
/// after the machine's range and acceleration, the share of points where they
/// miss the cutting speed by more than 5 %, Σ|Δn| and the time with links and
/// retracts (estimated with acceleration: the machine's axis limits and
/// look-ahead, as `inspect` prints it). It writes the best candidate (start corners, one-way, planned pass
/// directions and splits) that is worse than the original on none of these
/// (time within 3 %), or, when none is better, the original order (verdict
/// kept). --method paper runs the published greedy search over single
/// points.
///
/// Every cutting point is kept; links between points that are not neighbours
/// are direct only when the drop-cutter check proves them gouge-free, otherwise
/// the tool retracts, rapids and plunges. Spindle control (as `millplan speed`)
/// is applied to the result unless --no-speed. The JSON summary compares the
/// original and the reordered order.
///
/// Before it is written the program is read back from its bytes and checked:
/// the IR verifier, every cutting point of the input cut, S and F within the
/// machine, and no gouge into the part the input did not have (rapids and
/// links too). A check that fails names its line and exits 3 with nothing
/// written, unless --force.
#[derive(clap::Args)]
pub struct Args {
    /// Program to reorder (APT/CL or G-code).
    pub path: PathBuf,
    #[command(flatten)]
    pub part: crate::cmd::args::Part,
    /// How the order is searched: as-run (default) measures candidate orders as the
    /// machine will run them; paper is the published greedy search over single
    /// points; optimised keeps
    /// passes whole.
    #[arg(long, value_enum, default_value = "as-run")]
    pub method: MethodArg,
    /// Start of the paper's search, among the border points.
    #[arg(long, value_enum, default_value = "lowest")]
    pub start: StartArg,
    /// Start at this cutting point (index) instead.
    #[arg(long)]
    pub start_index: Option<usize>,
    /// Seed of --start random: the same seed picks the same start point.
    #[arg(long, default_value_t = millplan_driver::command_defaults::reorder::SEED)]
    pub seed: u64,
    /// Minimum number of candidates of the paper's search.
    #[arg(long, default_value_t = millplan_driver::command_defaults::reorder::N_MIN)]
    pub n_min: usize,
    /// D_w differences within this are ties, broken by continuing straight, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::reorder::TIE)]
    pub tie: f64,
    /// Step guard of the paper search, mm: when every candidate would change
    /// D_w by more than this, the search looks farther (up to 32 × its radius)
    /// for one that does not, linking to it by a retract where it is not a
    /// neighbour. 0 runs the search exactly as published.
    #[arg(long, default_value_t = millplan_driver::command_defaults::reorder::MAX_STEP)]
    pub max_step: f64,
    #[command(flatten)]
    pub cut: super::CuttingData,
    /// Write the reordered points without spindle control.
    #[arg(long)]
    pub no_speed: bool,
    #[command(flatten)]
    pub machine: crate::cmd::args::MachineFile,
    #[command(flatten)]
    pub out: crate::cmd::args::ProgramOutput,
    /// HTML report: both orders side by side (D_w and spindle speed along the
    /// path, the distribution of successive changes, the tour from above).
    #[arg(long)]
    pub report: Option<PathBuf>,
    #[command(flatten)]
    pub units: crate::cmd::args::ProgramUnits,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    #[command(flatten)]
    pub force: crate::cmd::args::Force,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

pub fn run(a: Args) -> CliResult<i32> {
    let mut clock = crate::timings::Clock::start();
    let req = request(&a);
    let rp = req.params().map_err(CliError::input)?;
    let outs = [
        ("-o", Some(&*a.out.output)),
        ("--report", a.report.as_deref()),
    ];
    let inputs = [
        Some(&*a.path),
        Some(&*a.part.stl),
        a.machine.machine.as_deref(),
    ];
    let mut outputs = crate::io::plan(&inputs, &outs, false)?;
    let machine = a.machine.load()?;
    clock.lap("arguments, machine file and outputs checked");
    let quiet = a.notes.quiet;
    let parsed = a.units.read(&a.path, quiet || a.summary.json)?;
    let target = a.out.target(&machine, parsed.program.source)?;
    clock.lap("program read");
    let mesh = a.part.read()?;
    clock.lap("part read");
    let long = millplan_driver::command_defaults::progress::long_program(&parsed.program);
    let bar = crate::progress::Phases::new(!quiet && long);
    let hook = |phase: &str, done: usize, total: usize| bar.report(phase, done, total);
    let cx = Context::new(machine).with_part(&mesh).with_progress(&hook);
    let ran = lib::command(&req, rp, &cx, &parsed.program);
    bar.finish();
    let r = ran.map_err(|e| match e {
        lib::ReorderError::Pass(e) => crate::cmd::pass_error(&a.path, e),
        lib::ReorderError::NoOutcome => CliError::internal("the reorder pass left no outcome"),
    })?;
    clock.lap("reordered and checked");
    let wo = cx.machine.write_options(target);
    let out = write_program(&r.program, wo, &a.path, quiet)?;
    crate::verdict::read_back(&out, target, &r.program, &a.out.output)?;
    let checked = a.force.enforce(&r.checks, &a.path)?;
    outputs.write(&a.out.output, &out)?;
    if let Some(path) = &a.report {
        let names = (file_name(&a.path), file_name(&a.part.stl));
        let on = (&cx.machine, req.cut);
        let html = r.report_html((&parsed.program, &mesh), names, on, method(&a));
        outputs.write(path, html.as_bytes())?;
    }
    outputs.commit()?;
    clock.lap("outputs written, read back and renamed into place");
    let output = a.out.output.display().to_string();
    let summary = lib::Summary::new(Some(method(&a)), &r.outcome, output, &r.checks);
    a.summary.print(&summary, |s| s.render_text());
    clock.end(a.timings.on);
    Ok(exit(!checked))
}

/// The method's name as the option gives it.
fn method(a: &Args) -> String {
    a.method
        .to_possible_value()
        .map(|v| v.get_name().to_string())
        .unwrap_or_default()
}

fn request(a: &Args) -> lib::ReorderRequest {
    lib::ReorderRequest {
        method: match a.method {
            MethodArg::AsRun => Method::AsRun,
            MethodArg::Paper => Method::Paper,
            MethodArg::Optimised => Method::Optimised,
        },
        start: match (a.start_index, a.start) {
            (Some(i), _) => Start::Index(i),
            (None, StartArg::Lowest) => Start::Lowest,
            (None, StartArg::Highest) => Start::Highest,
            (None, StartArg::Random) => Start::Random(a.seed),
        },
        n_min: a.n_min,
        tie: a.tie,
        max_step: a.max_step,
        cut: a.cut.cutting(),
        speed: !a.no_speed,
    }
}
