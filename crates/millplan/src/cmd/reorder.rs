//! `millplan reorder`: reorder finishing points so the working diameter changes
//! least between successive points (paper 000, thesis 5), with safe links.

use crate::error::{exit, CliResult};
use clap::ValueEnum;
use millplan_driver::reorder as lib;
use millplan_driver::watch::Watch as _;
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
/// machine, and no gouge into the part, the input's own refused too (rapids and
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
    let watch = crate::progress::Watch::new(&a.path, a.notes.quiet, a.summary.json);
    let watch = watch.bars_under_json();
    let c = lib::ReorderCommand {
        input: &a.path,
        part: a.part.file(),
        machine: a.machine.machine.as_deref(),
        output: &a.out.output,
        to: a.out.to.map(Into::into),
        report: a.report.as_deref(),
        request: request(&a),
        method: method(&a),
        read: a.units.options()?,
        force: a.force.force,
    };
    let r = lib::run_command(&c, &watch)?;
    a.summary.print(&r.summary(&c), |s| s.render_text());
    watch.lap("summary printed");
    watch.print_timings(a.timings.on);
    Ok(exit(!r.checked))
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
