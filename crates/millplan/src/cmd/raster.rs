//! `millplan raster`: a finishing raster over an STL part.

use crate::cmd::{print_diagnostics, write_program, TargetArg};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::Outputs;
use crate::timings::Table as _;
use millplan_driver::raster::{self as lib, RasterRequest};
use millplan_plan::checks;
use std::path::PathBuf;

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
    /// Part surface (STL).
    #[arg(long)]
    pub stl: PathBuf,
    #[command(flatten)]
    pub part_units: crate::cmd::args::PartUnits,
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
    /// Output dialect; default: from the output's extension (.apt/.cls APT,
    /// .nc Fanuc, .mpf Sinumerik, .h Heidenhain, .ngc LinuxCNC).
    #[arg(long, value_enum)]
    pub to: Option<TargetArg>,
    /// Raster program to write (APT/CL, or the dialect of --to or the extension).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Machine file (examples/machine.toml): its control's dialect is the
    /// default target and its S-word decimals are used.
    #[arg(long)]
    pub machine: Option<PathBuf>,
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
    let inputs: Vec<&std::path::Path> = [Some(a.stl.as_path()), a.machine.as_deref()]
        .into_iter()
        .flatten()
        .collect();
    let mut outputs = Outputs::plan(&inputs, &[("-o", Some(&a.output))], false)?;
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    clock.lap("arguments, machine file and outputs checked");
    let mesh = a.part_units.read(&a.stl)?;
    clock.lap("part read");
    let limits = crate::limits::get();
    let (points, bytes) =
        lib::check_grid(&p, &mesh.bounds(), limits.moves as f64).map_err(CliError::input)?;
    let what = format!(
        "a raster of {} points",
        millplan_geom::limits::amount(points.ceil())
    );
    crate::limits::check_memory(&what, bytes)?;
    print_diagnostics(
        &a.stl,
        &checks::mesh(&mesh).into_iter().collect::<Vec<_>>(),
        a.notes.quiet,
    );
    let (prog, part) = lib::generate(&mesh, &p);
    clock.lap("raster generated (drop-cutter)");
    if prog.move_count() == 0 {
        return Err(CliError::input(format!(
            "{}: the raster does not cross the part (check --boundary)",
            a.stl.display()
        )));
    }
    let generated = millplan_nc::Dialect::Generated;
    let target = crate::cmd::target_with_machine(a.to, &a.output, &machine, generated)?;
    let out = write_program(&prog, machine.write_options(target), &a.stl, a.notes.quiet)?;
    clock.lap("program written");
    let (checks, rep) = lib::check((&prog, &out), target, &part, &machine, &p)
        .map_err(|e| CliError::internal(format!("{}: {e}", a.output.display())))?;
    crate::verdict::enforce(&checks, &a.output, a.force)?;
    clock.lap("written program read back and checked");
    outputs.write(&a.output, &out)?;
    outputs.commit()?;
    clock.lap("output synced and renamed into place");
    let est = millplan_plan::timing::estimate_program(&prog, &machine);
    let output = a.output.display().to_string();
    let report = lib::Report::new(output, (&prog, &machine, &p), (&rep, &checks), &est);
    a.summary.print(&report, |r| r.render_text());
    clock.lap("time estimate, summary printed");
    clock.print(a.timings.on);
    Ok(if millplan_plan::safety::passed(&checks) {
        EXIT_OK
    } else {
        EXIT_FINDINGS
    })
}
