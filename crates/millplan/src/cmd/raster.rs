//! `millplan raster`: a finishing raster over an STL part.

use crate::cmd::{target_for, write_program, TargetArg};
use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::{read_surface, write_atomic};
use millplan_models::cutter::Shape;
use millplan_nc::write::WriteOptions;
use millplan_sim::dropcutter::DropMesh;
use millplan_sim::raster::{raster, RasterParams};
use std::path::PathBuf;

/// Generate a finishing raster over a part: parallel passes at --angle, every
/// point a drop-cutter position (the cutter just touching the part), refined
/// where the surface bends until the chord stays within --tol of the surface.
/// Zig-zag passes are linked along the surface; one-way passes retract to a
/// clearance plane. Writes APT/CL (or a G-code dialect with --to).
#[derive(clap::Args)]
pub struct Args {
    /// Part surface (STL).
    #[arg(long)]
    pub stl: PathBuf,
    /// Cutter: ball:D, flat:D, bull:D:R (corner radius), cone:D:ANGLE (point angle).
    #[arg(long)]
    pub tool: String,
    /// Feed direction, degrees from +X.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub angle: f64,
    /// Distance between passes, mm.
    #[arg(long)]
    pub stepover: f64,
    /// Distance between points along a pass, mm.
    #[arg(long)]
    pub step: f64,
    /// Alternate pass directions (default).
    #[arg(long, conflicts_with = "oneway")]
    pub zigzag: bool,
    /// All passes in one direction, retracting in between.
    #[arg(long)]
    pub oneway: bool,
    /// Margin inside the part's XY bounds (negative: beyond), mm.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub boundary: f64,
    /// Chord tolerance of the adaptive refinement, mm (0: none).
    #[arg(long, default_value_t = 0.002)]
    pub tol: f64,
    /// Clearance above the part for rapids, mm.
    #[arg(long, default_value_t = 5.0)]
    pub clearance: f64,
    #[arg(long, default_value_t = 1500.0)]
    pub feed: f64,
    #[arg(long, default_value_t = 6000.0)]
    pub spindle: f64,
    /// Output dialect; default: from the output's extension (.apt/.cls APT,
    /// .nc Fanuc, .mpf Sinumerik, .h Heidenhain, .ngc LinuxCNC).
    #[arg(long, value_enum)]
    pub to: Option<TargetArg>,
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(a: Args) -> CliResult<i32> {
    let shape = Shape::parse(&a.tool).map_err(CliError::input)?;
    if !(a.stepover > 0.0 && a.step > 0.0 && a.feed > 0.0 && a.spindle >= 0.0 && a.tol >= 0.0) {
        return Err(CliError::input(
            "--stepover, --step and --feed must be positive, --tol not negative",
        ));
    }
    let (mesh, _) = read_surface(&a.stl)?;
    let part = DropMesh::new(&mesh);
    let mut p = RasterParams::new(shape);
    p.angle_deg = a.angle;
    p.stepover = a.stepover;
    p.step = a.step;
    p.zigzag = !a.oneway;
    p.margin = a.boundary;
    p.tol = (a.tol > 0.0).then_some(a.tol);
    p.clearance = a.clearance;
    p.feed = a.feed;
    p.spindle = a.spindle;
    let prog = raster(&part, &mesh.bounds(), &p);
    if prog.move_count() == 0 {
        return Err(CliError::input(format!(
            "{}: the raster does not cross the part (check --boundary)",
            a.stl.display()
        )));
    }
    let target = target_for(a.to, &a.output, millplan_nc::Dialect::Generated)?;
    let out = write_program(&prog, WriteOptions::new(target), &a.stl, false)?;
    write_atomic(&a.output, &out, &[a.stl.as_path()])?;
    let s = millplan_nc::stats::summarize(&prog, 15000.0);
    println!(
        "wrote {}: {} moves, {:.0} mm cutting, {:.0} s at {} mm/min",
        a.output.display(),
        prog.move_count(),
        s.cutting_mm,
        s.time_s,
        a.feed
    );
    Ok(EXIT_OK)
}
