//! `millplan directions`: rank candidate paths of one surface by the spindle's
//! dynamic load under constant-cutting-speed control (paper 000, thesis 3).

use crate::error::{CliResult, EXIT_OK};
use clap::ValueEnum;
use millplan_driver::watch::Watch as _;
use millplan_plan::directions::RankBy as By;
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
pub enum RankBy {
    /// Total variation of the spindle speed, Σ|Δn|.
    Tv,
    /// Largest speed step between successive points.
    MaxStep,
    /// Largest spindle acceleration demand.
    Accel,
    /// Integral of the spindle speed over the path, Σ n·Δs.
    Integral,
}

/// Evaluate several finishing paths of the same surface (for example rasters in
/// five feed directions) under spindle control and rank them by the dynamic-load
/// indicators: the milling direction whose spindle speed changes least is the
/// one to choose (docs/usage.md says where the rule comes from).
///
/// Give the candidate paths, or let millplan make drop-cutter rasters with
/// --angles (with --tool, --stepover and --step).
#[derive(clap::Args)]
pub struct Args {
    /// Candidate paths (APT/CL or G-code) with a ball-end tool.
    #[arg(required_unless_present = "angles")]
    pub paths: Vec<PathBuf>,
    /// Generate raster candidates at these feed directions, degrees.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub angles: Vec<f64>,
    /// Ball for generated rasters, e.g. ball:10.
    #[arg(long, default_value = "ball:10")]
    pub tool: String,
    /// Stepover of generated rasters, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::directions::STEPOVER)]
    pub stepover: f64,
    /// Point spacing of generated rasters, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::directions::STEP)]
    pub step: f64,
    #[command(flatten)]
    pub part: crate::cmd::args::Part,
    #[command(flatten)]
    pub cut: super::CuttingData,
    #[command(flatten)]
    pub machine: crate::cmd::args::MachineFile,
    /// Indicator to rank by (smaller is better).
    #[arg(long, value_enum, default_value = "tv")]
    pub by: RankBy,
    #[command(flatten)]
    pub units: crate::cmd::args::ProgramUnits,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

/// The generated rasters' arguments in range, and their points (counted
/// from the grid) within the limits.
pub fn run(a: Args) -> CliResult<i32> {
    let watch = crate::progress::Watch::new(&a.part.stl, false, a.summary.json);
    let c = millplan_driver::directions::DirectionsCommand {
        part: a.part.file(),
        machine: a.machine.machine.as_deref(),
        cut: a.cut.cutting(),
        angles: &a.angles,
        tool: &a.tool,
        stepover: a.stepover,
        step: a.step,
        paths: &a.paths,
        read: a.units.options()?,
        by: match a.by {
            RankBy::Tv => By::TotalVariation,
            RankBy::MaxStep => By::MaxStep,
            RankBy::Accel => By::Accel,
            RankBy::Integral => By::Integral,
        },
    };
    let ranked = millplan_driver::directions::run_command(&c, &watch)?;
    let j = || millplan_driver::directions::Report::new(format!("{:?}", a.by), &ranked);
    let text = || millplan_driver::directions::render_text(&ranked);
    crate::cmd::print_summary(a.summary.json, j, text);
    watch.lap("summary printed");
    watch.print_timings(a.timings.on);
    Ok(EXIT_OK)
}
