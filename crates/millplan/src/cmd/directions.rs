//! `millplan directions`: rank candidate paths of one surface by the spindle's
//! dynamic load under constant-cutting-speed control (paper 000, thesis 3).

use crate::cmd::{read_options, UnitArg};
use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::{read_program, read_surface};
use clap::ValueEnum;
use millplan_plan::directions::{rank, raster_candidates, Candidate, RankBy as By};
use millplan_plan::pipeline::Context;
use serde_json::json;
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
/// one thesis 3 recommends.
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
    /// Part surface (STL) in the same coordinates as the paths.
    #[arg(long)]
    pub stl: PathBuf,
    /// Unit of the STL's numbers (an STL does not say): mm (default) or inch,
    /// converted to mm on reading.
    #[arg(long, value_enum)]
    pub stl_units: Option<UnitArg>,
    #[command(flatten)]
    pub cut: super::CuttingData,
    /// Machine file (examples/machine.toml): the spindle range and acceleration the
    /// load is judged by; a typical HSC machine by default.
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Indicator to rank by (smaller is better).
    #[arg(long, value_enum, default_value = "tv")]
    pub by: RankBy,
    /// Unit of a program that does not say (NX's Haas posts, bare GOTO files): mm or
    /// inch.
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    /// Print a machine-readable summary (JSON) on standard output; errors too, as JSON
    /// on standard error.
    #[arg(long)]
    pub json: bool,
}

/// The generated rasters' arguments in range, and their points (counted
/// from the grid) within the limits.
fn check_rasters(
    a: &Args,
    bounds: &millplan_geom::Aabb,
) -> CliResult<millplan_models::cutter::Shape> {
    use crate::cmd::{arg, Range};
    let shape = crate::cmd::tool_shape("--tool", &a.tool)?;
    let d = 2.0 * shape.radius();
    for angle in &a.angles {
        arg("--angles", *angle, Range::from(-360.0, 360.0, "degrees"))?;
    }
    crate::cmd::raster_spacing(d, a.stepover, a.step)?;
    let mut p = millplan_sim::raster::RasterParams::new(shape);
    (p.stepover, p.step) = (a.stepover, a.step);
    let e = millplan_sim::raster::estimate(bounds, &p, 0.1);
    let n = e.points * a.angles.len() as f64;
    let limit = crate::limits::get().moves as f64;
    if !(n <= limit) {
        let needs = format!(
            "{} rasters at --stepover {} and --step {} make {} points",
            a.angles.len(),
            a.stepover,
            a.step,
            millplan_geom::limits::amount(n.ceil())
        );
        return Err(CliError::input(
            millplan_geom::limits::Exceeded::new("moves", needs, limit).to_string(),
        ));
    }
    crate::limits::check_memory("the candidate rasters", e.bytes * a.angles.len() as f64)?;
    Ok(shape)
}

pub fn run(a: Args) -> CliResult<i32> {
    a.cut.check()?;
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    let (mesh, _) = read_surface(&a.stl, a.stl_units)?;
    let cx = Context::new(machine).with_part(&mesh);
    let mut candidates = Vec::new();
    if !a.angles.is_empty() {
        let shape = check_rasters(&a, &mesh.bounds())?;
        candidates = raster_candidates(&cx, shape, &a.angles, a.stepover, a.step)
            .map_err(|e| crate::cmd::pass_error(&a.stl, e))?;
    }
    for p in &a.paths {
        let parsed = read_program(p, read_options(a.units, None)?)?;
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
    let ranked = rank(candidates, &cx, &a.cut.params(), by)
        .map_err(|e| crate::cmd::pass_error(&a.stl, e))?;
    if a.json {
        let rows: Vec<_> = ranked
            .iter()
            .map(|r| {
                let s = &r.summary;
                json!({ "rank": r.rank, "path": r.name, "indicators": s.indicators, "d_w": s.d_w, "vc_constant": s.vc_constant, "points": s.points })
            })
            .collect();
        let j = json!({ "ranked_by": format!("{:?}", a.by), "candidates": rows });
        crate::cmd::print_json(j);
    } else {
        outln!(
            "{:>4}  {:<40} {:>12} {:>10} {:>12} {:>12} {:>10}",
            "rank",
            "path",
            "Σ|Δn|",
            "max|Δn|",
            "max accel",
            "∫n ds",
            "σ(D_w)"
        );
        for r in &ranked {
            let (i, s) = (&r.summary.indicators, &r.summary);
            outln!(
                "{:>4}  {:<40} {:>12.0} {:>10.0} {:>12.0} {:>12.4e} {:>10.3}",
                r.rank,
                r.name,
                i.total_variation,
                i.max_step,
                i.max_accel,
                i.speed_integral,
                s.d_w.std
            );
        }
    }
    Ok(EXIT_OK)
}
