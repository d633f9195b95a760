//! `millplan directions`: rank candidate paths of one surface by the spindle's
//! dynamic load under constant-cutting-speed control (paper 000, thesis 3).

use crate::cmd::{read_options, UnitArg};
use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::{read_program, read_surface};
use clap::ValueEnum;
use millplan_plan::speed::{apply, Summary};
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
    #[arg(long, default_value_t = 1.0)]
    pub stepover: f64,
    /// Point spacing of generated rasters, mm.
    #[arg(long, default_value_t = 0.5)]
    pub step: f64,
    #[arg(long)]
    pub stl: PathBuf,
    #[command(flatten)]
    pub cut: super::CuttingData,
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Indicator to rank by (smaller is better).
    #[arg(long, value_enum, default_value = "tv")]
    pub by: RankBy,
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    #[arg(long)]
    pub json: bool,
}

fn key(s: &Summary, by: RankBy) -> f64 {
    let i = &s.indicators;
    match by {
        RankBy::Tv => i.total_variation,
        RankBy::MaxStep => i.max_step,
        RankBy::Accel => i.max_accel,
        RankBy::Integral => i.speed_integral,
    }
}

pub fn run(a: Args) -> CliResult<i32> {
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    let (mesh, _) = read_surface(&a.stl)?;
    let params = a.cut.params();
    let mut results = Vec::new();
    if !a.angles.is_empty() {
        let shape = millplan_models::cutter::Shape::parse(&a.tool).map_err(CliError::input)?;
        if !(a.stepover > 0.0 && a.step > 0.0) {
            return Err(CliError::input("--stepover and --step must be positive"));
        }
        let part = millplan_sim::dropcutter::DropMesh::new(&mesh);
        let bounds = mesh.bounds();
        for &angle in &a.angles {
            let mut rp = millplan_sim::raster::RasterParams::new(shape);
            rp.angle_deg = angle;
            rp.stepover = a.stepover;
            rp.step = a.step;
            let prog = millplan_sim::raster::raster(&part, &bounds, &rp);
            let r = apply(&prog, &mesh, &machine, &params)
                .map_err(|e| CliError::input(format!("raster at {angle}°: {e}")))?;
            results.push((PathBuf::from(format!("raster {angle}°")), r.summary));
        }
    }
    for p in &a.paths {
        let parsed = read_program(p, read_options(a.units, None))?;
        let r = apply(&parsed.program, &mesh, &machine, &params)
            .map_err(|e| CliError::input(format!("{}: {e}", p.display())))?;
        results.push((p.clone(), r.summary));
    }
    results.sort_by(|x, y| key(&x.1, a.by).total_cmp(&key(&y.1, a.by)));
    if a.json {
        let rows: Vec<_> = results
            .iter()
            .enumerate()
            .map(|(rank, (p, s))| json!({ "rank": rank + 1, "path": p.display().to_string(), "indicators": s.indicators, "d_w": s.d_w, "vc_constant": s.vc_constant, "points": s.points }))
            .collect();
        println!(
            "{}",
            serde_json::to_string_pretty(
                &json!({ "ranked_by": format!("{:?}", a.by), "candidates": rows })
            )
            .unwrap_or_default()
        );
    } else {
        println!(
            "{:>4}  {:<40} {:>12} {:>10} {:>12} {:>12} {:>10}",
            "rank", "path", "Σ|Δn|", "max|Δn|", "max accel", "∫n ds", "σ(D_w)"
        );
        for (rank, (p, s)) in results.iter().enumerate() {
            let i = &s.indicators;
            println!(
                "{:>4}  {:<40} {:>12.0} {:>10.0} {:>12.0} {:>12.4e} {:>10.3}",
                rank + 1,
                p.display().to_string(),
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
