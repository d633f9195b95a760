//! `millplan directions`: rank candidate paths of one surface by the spindle's
//! dynamic load under constant-cutting-speed control (paper 000, thesis 3).

use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::read_program;
use crate::timings::{Clock, Table as _};
use clap::ValueEnum;
use millplan_plan::directions::{rank, raster_candidates, Candidate, RankBy as By};
use millplan_plan::pipeline::Context;
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
fn check_rasters(a: &Args, bounds: &millplan_geom::Aabb) -> CliResult<millplan_driver::Shape> {
    let limit = crate::limits::get().moves as f64;
    let spacing = (a.stepover, a.step);
    let (shape, bytes) =
        millplan_driver::directions::rasters_within(&a.tool, &a.angles, spacing, bounds, limit)
            .map_err(CliError::input)?;
    crate::limits::check_memory("the candidate rasters", bytes)?;
    Ok(shape)
}

pub fn run(a: Args) -> CliResult<i32> {
    let mut clock = Clock::start();
    a.cut.check()?;
    let machine = a.machine.load()?;
    let mesh = a.part.read()?;
    let cx = Context::new(machine).with_part(&mesh);
    clock.lap("machine file and part read");
    let mut candidates = Vec::new();
    if !a.angles.is_empty() {
        let shape = check_rasters(&a, &mesh.bounds())?;
        candidates = raster_candidates(&cx, shape, &a.angles, a.stepover, a.step)
            .map_err(|e| crate::cmd::pass_error(&a.part.stl, e))?;
        clock.lap("candidate rasters made (drop-cutter)");
    }
    for p in &a.paths {
        let parsed = read_program(p, a.units.options()?)?;
        candidates.push(Candidate {
            name: p.display().to_string(),
            program: parsed.program,
        });
    }
    let by = match a.by {
        RankBy::Tv => By::TotalVariation,
        RankBy::MaxStep => By::MaxStep,
        RankBy::Accel => By::Accel,
        RankBy::Integral => By::Integral,
    };
    if !a.paths.is_empty() {
        clock.lap("candidate paths read");
    }
    let ranked = rank(candidates, &cx, &a.cut.params(), by)
        .map_err(|e| crate::cmd::pass_error(&a.part.stl, e))?;
    clock.lap("candidates run under spindle control and ranked");
    let j = || millplan_driver::directions::Report::new(format!("{:?}", a.by), &ranked);
    let text = || millplan_driver::directions::render_text(&ranked);
    crate::cmd::print_summary(a.summary.json, j, text);
    clock.end(a.timings.on);
    Ok(EXIT_OK)
}
