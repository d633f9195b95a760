//! `millplan raster`: a finishing raster over an STL part.

use crate::error::{exit, CliResult};
use millplan_driver::raster::{self as lib, RasterRequest};
use millplan_driver::watch::Watch as _;

/// Generate a finishing raster over a part: parallel passes at --angle, every
/// point a drop-cutter position (the cutter just touching the part), refined
/// where the surface bends until the chord stays within --tol of the surface.
/// Zig-zag passes are linked along the surface; one-way passes retract to a
/// clearance plane. Writes APT/CL (or a G-code dialect with --to).
///
/// The raster is then checked before it is written: read back from its
/// bytes, the IR verifier, S and F within the machine (--machine, else a
/// typical HSC machine), and gouges as `millplan gouge` would check it
/// (rapids too). A raster that fails a check is not written (exit 3, the
/// line of the program it would have written and the check named) unless
/// --force.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub part: crate::cmd::args::Part,
    /// Cutter: ball:D, flat:D, bull:D:R (corner radius), cone:D:ANGLE (point angle).
    #[arg(long)]
    pub tool: String,
    /// Feed direction, degrees from +X.
    #[arg(long, default_value_t = millplan_driver::command_defaults::raster::ANGLE_DEG, allow_hyphen_values = true)]
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
    #[arg(long, default_value_t = millplan_driver::command_defaults::raster::BOUNDARY, allow_hyphen_values = true)]
    pub boundary: f64,
    /// Chord tolerance of the adaptive refinement, mm (0: none).
    #[arg(long, default_value_t = millplan_driver::command_defaults::raster::TOL)]
    pub tol: f64,
    /// Clearance above the part for rapids, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::raster::CLEARANCE)]
    pub clearance: f64,
    /// Cutting feed written on every cutting move, mm/min.
    #[arg(long, default_value_t = millplan_driver::command_defaults::raster::FEED)]
    pub feed: f64,
    /// Spindle speed written with the tool, 1/min.
    #[arg(long, default_value_t = millplan_driver::command_defaults::raster::SPINDLE)]
    pub spindle: f64,
    #[command(flatten)]
    pub out: crate::cmd::args::ProgramOutput,
    #[command(flatten)]
    pub machine: crate::cmd::args::MachineFile,
    /// Write the raster even when a check refuses it (its own gouge check
    /// finds it cutting into the part: a mesh with holes or seams can make
    /// drop-cutter miss material; an S or F outside the machine); the run
    /// then ends with exit 3.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

fn request(a: &Args) -> RasterRequest {
    RasterRequest {
        tool: a.tool.clone(),
        angle: a.angle,
        stepover: a.stepover,
        step: a.step,
        oneway: a.oneway,
        boundary: a.boundary,
        tol: a.tol,
        clearance: a.clearance,
        feed: a.feed,
        spindle: a.spindle,
    }
}

pub fn run(a: Args) -> CliResult<i32> {
    let watch = crate::progress::Watch::new(&a.part.stl, a.notes.quiet, false);
    let c = lib::RasterCommand {
        part: a.part.file(),
        machine: a.machine.machine.as_deref(),
        output: &a.out.output,
        to: a.out.to.map(Into::into),
        request: request(&a),
        limits: crate::limits::get(),
        force: a.force,
    };
    let r = lib::run_command(&c, &watch)?;
    a.summary.print(&r.report(&c), |r| r.render_text());
    watch.lap("time estimate, summary printed");
    watch.print_timings(a.timings.on);
    Ok(exit(r.findings()))
}
