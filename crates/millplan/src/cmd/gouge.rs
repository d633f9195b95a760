//! `millplan gouge`: does the program cut into the part?

use crate::error::{exit, CliError, CliResult};
use millplan_driver::gouge::{self as lib, GougeRequest};
use millplan_driver::watch::Watch as _;
use std::path::PathBuf;

/// Check a program for gouges: every cutting move (and with --rapids every
/// rapid) is sampled at --step and the tool tip compared with the height at which
/// the cutter would touch the part there (drop-cutter, exact for flat, ball,
/// bull and cone cutters). Deeper than --tol is a gouge. A ball end whose
/// axis leans (five-axis CL) is checked by the distance of its ball and
/// flutes (the CUTTER record's height, else the whole tool) to the part.
///
/// A part the tool stands by (within radius + 2 mm of its xy box) in fewer than half of the
/// cutting moves (`off_part_moves` of `cutting_moves`) does not match the program. Exit code 0 when clean, 3 when gouges were found or the part is not the program's, 2
/// when the program does not say its tool's shape (give --tool) or no move could be checked. Moves
/// of other leaning tools or whose axis is known only as machine angles,
/// canned-cycle holes along a leaning axis (a vertical one is checked from
/// its highest plane down) and moves from a position the program has not
/// set are counted as not checked, each kind apart.
#[derive(clap::Args)]
pub struct Args {
    /// Program (APT/CL or G-code).
    pub path: PathBuf,
    #[command(flatten)]
    pub part: crate::cmd::args::Part,
    /// Depth that counts as a gouge, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::gouge::TOL)]
    pub tol: f64,
    /// Sampling step along the moves, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::gouge::STEP)]
    pub step: f64,
    /// Check rapid moves too.
    #[arg(long)]
    pub rapids: bool,
    /// Cutter for operations whose tool has no geometry: ball:D, flat:D, bull:D:R, cone:D:ANGLE.
    #[arg(long)]
    pub tool: Option<String>,
    #[command(flatten)]
    pub units: crate::cmd::args::ProgramUnits,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

pub fn run(a: Args) -> CliResult<i32> {
    let watch = crate::progress::Watch::new(&a.path, a.notes.quiet, a.summary.json);
    let watch = watch.bars_under_json();
    let c = lib::GougeCommand {
        input: &a.path,
        part: a.part.file(),
        request: GougeRequest {
            tol: a.tol,
            step: a.step,
            rapids: a.rapids,
            tool: a.tool.clone(),
        },
        read: a.units.options()?,
    };
    let rep = lib::run_command(&c, &watch)?;
    let path = a.path.display().to_string();
    let report = lib::Report::new(&rep, a.tol);
    a.summary.print(&report, |r| r.render_text(&path));
    watch.lap("summary printed");
    watch.print_timings(a.timings.on);
    if let Some(m) = lib::nothing_checked(&path, &rep) {
        return Err(CliError::input(m));
    }
    Ok(exit(report.found()))
}
