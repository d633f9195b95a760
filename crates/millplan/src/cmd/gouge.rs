//! `millplan gouge`: does the program cut into the part?

use crate::cmd::print_diagnostics;
use crate::error::{exit, CliError, CliResult};
use crate::timings::Table as _;
use millplan_driver::gouge::{self as lib, GougeRequest, BYTES_PER_SAMPLE};
use millplan_plan::checks;
use std::path::PathBuf;

/// Check a program for gouges: every cutting move (and with --rapids every
/// rapid) is sampled at --step and the tool tip compared with the height at which
/// the cutter would touch the part there (drop-cutter, exact for flat, ball,
/// bull and cone cutters). Deeper than --tol is a gouge.
///
/// Exit code 0 when clean, 3 when gouges were found, 2 when the program does
/// not say its tool's shape (give --tool) or no move could be checked. Moves
/// whose tool axis is not +Z (5-axis), canned cycles and moves from a position
/// the program has not set are counted as not checked, each kind apart.
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
    let mut clock = crate::timings::Clock::start();
    let req = GougeRequest {
        tol: a.tol,
        step: a.step,
        rapids: a.rapids,
        tool: a.tool.clone(),
    };
    let (g, fallback) = lib::params(&req).map_err(CliError::input)?;
    let quiet = a.notes.quiet || a.summary.json;
    let parsed = a.units.read(&a.path, quiet)?;
    let path = a.path.display().to_string();
    if fallback.is_none() {
        lib::shape_is_known(&path, &parsed.program).map_err(CliError::input)?;
    }
    clock.lap("arguments checked, program read");
    let mesh = a.part.read()?;
    let found: Vec<_> = checks::mesh(&mesh).into_iter().collect();
    print_diagnostics(&a.part.stl, &found, quiet);
    // Counted first: a step of 1e-9 on a long program is refused, not run.
    clock.lap("part read");
    let n = lib::sample_count(&parsed.program, fallback, &g);
    crate::limits::check_memory(&lib::samples_needed(a.step, n), n * BYTES_PER_SAMPLE)?;
    let show = !a.notes.quiet && n >= lib::SHOWN_SAMPLES;
    let bar = crate::progress::count(n as u64, "gouge check", "points", show);
    let rep = lib::check(&parsed.program, &mesh, fallback, &g, &|done, _| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    clock.lap("points checked against the part");
    let report = lib::Report::new(&rep, a.tol);
    a.summary.print(&report, |r| r.render_text(&path));
    clock.end(a.timings.on);
    if rep.moves_checked == 0 {
        return Err(CliError::input(format!(
            "{path}: no move could be checked ({})",
            lib::skipped(&rep.skipped)
        )));
    }
    Ok(exit(!rep.gouges.is_empty()))
}
