//! `millplan raster`: a finishing raster over an STL part.

use crate::cmd::{print_diagnostics, target_for, write_program, TargetArg};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::{read_surface, write_atomic};
use millplan_models::cutter::Shape;
use millplan_plan::checks;
use millplan_sim::dropcutter::DropMesh;
use millplan_sim::gouge::{check, GougeParams};
use millplan_sim::raster::{raster, RasterParams};
use std::path::PathBuf;

/// Generate a finishing raster over a part: parallel passes at --angle, every
/// point a drop-cutter position (the cutter just touching the part), refined
/// where the surface bends until the chord stays within --tol of the surface.
/// Zig-zag passes are linked along the surface; one-way passes retract to a
/// clearance plane. Writes APT/CL (or a G-code dialect with --to).
///
/// The raster is then checked for gouges as `millplan gouge` would check it;
/// one that cuts into the part is not written (exit 3) unless --force.
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
    /// Machine file (examples/machine.toml): its control's dialect is the
    /// default target and its S-word decimals are used.
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Write the raster even when its own gouge check finds it cutting into
    /// the part (a mesh with holes or seams can make drop-cutter miss material).
    #[arg(long)]
    pub force: bool,
    #[arg(long, short)]
    pub quiet: bool,
}

fn params(a: &Args) -> CliResult<RasterParams> {
    let shape = Shape::parse(&a.tool).map_err(CliError::input)?;
    let finite = [
        a.stepover,
        a.step,
        a.feed,
        a.spindle,
        a.tol,
        a.angle,
        a.boundary,
        a.clearance,
    ]
    .iter()
    .all(|v| v.is_finite());
    if !(finite
        && a.stepover > 0.0
        && a.step > 0.0
        && a.feed > 0.0
        && a.spindle >= 0.0
        && a.tol >= 0.0)
    {
        return Err(CliError::input(
            "--stepover, --step and --feed must be positive, --tol not negative",
        ));
    }
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
    Ok(p)
}

pub fn run(a: Args) -> CliResult<i32> {
    let p = params(&a)?;
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    let (mesh, _) = read_surface(&a.stl)?;
    let part = DropMesh::new(&mesh);
    print_diagnostics(
        &a.stl,
        &checks::mesh(&mesh).into_iter().collect::<Vec<_>>(),
        a.quiet,
    );
    let prog = raster(&part, &mesh.bounds(), &p);
    if prog.move_count() == 0 {
        return Err(CliError::input(format!(
            "{}: the raster does not cross the part (check --boundary)",
            a.stl.display()
        )));
    }
    let target = match a.to.map(Into::into).or(machine.target()) {
        Some(t) => t,
        None => target_for(None, &a.output, millplan_nc::Dialect::Generated)?,
    };
    // The raster checked as `millplan gouge` would check it.
    let rep = check(&prog, &part, |_| Some(p.shape), &GougeParams::default());
    if !rep.gouges.is_empty() {
        eprintln!(
            "{}: the raster's own gouge check finds {} moves cutting into the part, deepest {:.4} mm{}",
            a.stl.display(),
            rep.gouges.len(),
            rep.max_depth,
            if a.force { "; written anyway (--force)" } else { "; not written (--force writes it)" }
        );
        if !a.force {
            return Ok(EXIT_FINDINGS);
        }
    }
    let out = write_program(&prog, machine.write_options(target), &a.stl, a.quiet)?;
    write_atomic(&a.output, &out, &[a.stl.as_path()])?;
    let s = millplan_nc::stats::summarize(&prog, 15000.0);
    println!(
        "wrote {}: {} moves, {:.0} mm cutting, {:.0} s at {} mm/min; gouge check: {} moves at {} points, {}",
        a.output.display(),
        prog.move_count(),
        s.cutting_mm,
        s.time_s,
        a.feed,
        rep.moves_checked,
        rep.points_checked,
        if rep.gouges.is_empty() { "clean" } else { "gouges" }
    );
    Ok(if rep.gouges.is_empty() {
        EXIT_OK
    } else {
        EXIT_FINDINGS
    })
}
