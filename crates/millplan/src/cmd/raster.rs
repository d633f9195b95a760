//! `millplan raster`: a finishing raster over an STL part.

use crate::cmd::{print_diagnostics, write_program};
use crate::error::{exit, CliError, CliResult};
use crate::timings::Table as _;
use millplan_driver::raster::{self as lib, RasterRequest};
use millplan_plan::checks;

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
    let mut clock = crate::timings::Clock::start();
    let p = lib::params(&request(&a)).map_err(CliError::input)?;
    let (stl, output) = (&a.part.stl, &a.out.output);
    let inputs = [Some(stl.as_path()), a.machine.machine.as_deref()];
    let mut outputs = crate::io::plan(&inputs, &[("-o", Some(output))], false)?;
    let machine = a.machine.load()?;
    clock.lap("arguments, machine file and outputs checked");
    let mesh = a.part.read()?;
    clock.lap("part read");
    let limits = crate::limits::get();
    let (points, bytes) =
        lib::check_grid(&p, &mesh.bounds(), limits.moves as f64).map_err(CliError::input)?;
    let what = format!(
        "a raster of {} points",
        millplan_geom::limits::amount(points.ceil())
    );
    crate::limits::check_memory(&what, bytes)?;
    let found: Vec<_> = checks::mesh(&mesh).into_iter().collect();
    print_diagnostics(stl, &found, a.notes.quiet);
    let (prog, part) = lib::generate(&mesh, &p);
    clock.lap("raster generated (drop-cutter)");
    if prog.move_count() == 0 {
        return Err(CliError::input(format!(
            "{}: the raster does not cross the part (check --boundary)",
            stl.display()
        )));
    }
    let target = a.out.target(&machine, millplan_nc::Dialect::Generated)?;
    let out = write_program(&prog, machine.write_options(target), stl, a.notes.quiet)?;
    clock.lap("program written");
    let (checks, rep) = lib::check((&prog, &out), target, &part, &machine, &p)
        .map_err(|e| CliError::internal(format!("{}: {e}", output.display())))?;
    crate::verdict::enforce(&checks, output, a.force)?;
    clock.lap("written program read back and checked");
    outputs.write(output, &out)?;
    outputs.commit()?;
    clock.lap("output synced and renamed into place");
    let est = millplan_plan::timing::estimate_program(&prog, &machine);
    let output = output.display().to_string();
    let report = lib::Report::new(output, (&prog, &machine, &p), (&rep, &checks), &est);
    a.summary.print(&report, |r| r.render_text());
    clock.lap("time estimate, summary printed");
    clock.print(a.timings.on);
    Ok(exit(!millplan_plan::safety::passed(&checks)))
}
