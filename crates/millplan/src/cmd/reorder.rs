//! `millplan reorder`: reorder finishing points so the working diameter changes
//! least between successive points (paper 000, thesis 5), with safe links.

use crate::cmd::{print_diagnostics, read_options, write_program, TargetArg, UnitArg};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::{read_program, Outputs};
use clap::ValueEnum;
use millplan_driver::reorder::Summary;
use millplan_nc::Program;
use millplan_plan::machine::Machine;
use millplan_plan::pipeline::{self, Context, Pass};
use millplan_plan::reorder::Outcome;
use millplan_plan::reorder::{Method, ReorderParams, ReorderPass, Start};
use millplan_plan::speed::SpeedPass;
use millplan_report::reorder::{reorder_report, ReorderInputs};
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
    /// Part surface (STL) in the same coordinates as the program.
    #[arg(long)]
    pub stl: PathBuf,
    #[command(flatten)]
    pub part_units: crate::cmd::args::PartUnits,
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
    /// Machine file (examples/machine.toml): spindle range and acceleration, feed
    /// limits, control dialect; a typical HSC machine by default.
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Output dialect; default: the machine file's control, else the output's
    /// extension, else the source's dialect.
    #[arg(long, value_enum)]
    pub to: Option<TargetArg>,
    /// Reordered program to write.
    #[arg(short, long)]
    pub output: PathBuf,
    /// HTML report: both orders side by side (D_w and spindle speed along the
    /// path, the distribution of successive changes, the tour from above).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Unit of a program that does not say (NX's Haas posts, bare GOTO files): mm or
    /// inch.
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    /// Write the program even when a check before writing refuses it (a
    /// cutting point of the input not cut, a gouge the input did not have,
    /// an S or F outside the machine); the run then ends with exit 3.
    #[arg(long)]
    pub force: bool,
}

/// The arguments checked and the outputs planned, before any work.
fn plan(a: &Args) -> CliResult<Outputs> {
    crate::cmd::arg(
        "--max-step",
        a.max_step,
        crate::cmd::Range::from(0.0, 1000.0, "mm"),
    )?;
    crate::cmd::arg("--tie", a.tie, crate::cmd::Range::from(0.0, 100.0, "mm"))?;
    a.cut.check()?;
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
        &[("-o", Some(&a.output)), ("--report", a.report.as_deref())],
        false,
    )
}

pub fn run(a: Args) -> CliResult<i32> {
    let mut outputs = plan(&a)?;
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    let parsed = read_program(&a.path, read_options(a.units, None)?)?;
    print_diagnostics(
        &a.path,
        &parsed.diagnostics,
        a.notes.quiet || a.summary.json,
    );
    let target = crate::cmd::target_with_machine(a.to, &a.output, &machine, parsed.program.source)?;
    let mesh = a.part_units.read(&a.stl)?;
    let mut program = parsed.program.clone();
    // Some 100,000 points a second at the least: from there it takes a while.
    let bar = crate::progress::Phases::new(!a.notes.quiet && program.move_count() >= 100_000);
    let hook = |phase: &str, done: usize, total: usize| bar.report(phase, done, total);
    let cx = Context::new(machine).with_part(&mesh).with_progress(&hook);
    let mut reorder = ReorderPass::new(params(&a));
    let mut speed = SpeedPass::new(a.cut.params());
    let mut passes: Vec<&mut dyn Pass> = vec![&mut reorder];
    if !a.no_speed {
        passes.push(&mut speed);
    }
    let ran = pipeline::run(&mut passes, &mut program, &cx);
    bar.finish();
    ran.map_err(|e| crate::cmd::pass_error(&a.path, e))?;
    let Some(o) = reorder.outcome else {
        return Err(CliError::internal("the reorder pass left no outcome"));
    };
    let out = write_program(
        &program,
        cx.machine.write_options(target),
        &a.path,
        a.notes.quiet,
    )?;
    crate::verdict::read_back(&out, target, &program, &a.output)?;
    let checks = cx.time("checks", || {
        millplan_driver::reorder::check(&parsed.program, &program, &cx)
    });
    let checked = crate::verdict::enforce(&checks, &a.path, a.force)?;
    outputs.write(&a.output, &out)?;
    if let Some(path) = &a.report {
        let html = report(&a, (&parsed.program, &program), &o, &cx.machine, &mesh);
        outputs.write(path, html.as_bytes())?;
    }
    outputs.commit()?;
    let method = a
        .method
        .to_possible_value()
        .map(|v| v.get_name().to_string());
    let summary = Summary::new(method, &o, a.output.display().to_string(), &checks);
    a.summary.print(&summary, |s| s.render_text());
    Ok(if checked { EXIT_OK } else { EXIT_FINDINGS })
}

/// The HTML report: the inputs, warnings (the part's mesh defects, points
/// off the part, a spindle that cannot follow), the verdict and both orders.
fn report(
    a: &Args,
    (original, reordered): (&Program, &Program),
    o: &Outcome,
    machine: &Machine,
    mesh: &millplan_geom::TriMesh,
) -> String {
    let findings: Vec<_> = millplan_plan::checks::mesh(mesh).into_iter().collect();
    let name = millplan_driver::feed::file_name;
    let run = millplan_driver::speed::report_inputs(
        (name(&a.path), original),
        name(&a.stl),
        machine,
        a.cut.cutting(),
        &findings,
        [o.before.as_run.time_s, o.after.as_run.time_s],
    );
    let method = a
        .method
        .to_possible_value()
        .map(|v| v.get_name().to_string())
        .unwrap_or_default();
    reorder_report(original, reordered, o, &ReorderInputs { run, method })
}

fn params(a: &Args) -> ReorderParams {
    let mut rp = ReorderParams::new(match a.method {
        MethodArg::AsRun => Method::AsRun,
        MethodArg::Paper => Method::Paper,
        MethodArg::Optimised => Method::Optimised,
    });
    rp.start = match (a.start_index, a.start) {
        (Some(i), _) => Start::Index(i),
        (None, StartArg::Lowest) => Start::Lowest,
        (None, StartArg::Highest) => Start::Highest,
        (None, StartArg::Random) => Start::Random(a.seed),
    };
    rp.n_min = a.n_min;
    rp.tie = a.tie;
    rp.max_step = (a.max_step > 0.0).then_some(a.max_step);
    rp.ap = a.cut.ap;
    rp.vc = a.cut.vc;
    rp.speed = a.cut.params();
    rp
}
