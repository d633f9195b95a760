//! `millplan raster`: a finishing raster over an STL part.

use crate::cmd::UnitArg;
use crate::cmd::{arg, print_diagnostics, target_for, tool_shape, write_program, Range, TargetArg};
use crate::cmd::{MAX_FEED, MAX_SPINDLE};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::{read_surface, Outputs};
use millplan_geom::limits::{amount, Exceeded};
use millplan_geom::Aabb;
use millplan_models::cutter::Shape;
use millplan_nc::equiv::Tolerance;
use millplan_nc::readback::read_back;
use millplan_nc::write::Target;
use millplan_nc::{Dialect, Program};
use millplan_plan::checks;
use millplan_plan::machine::Machine;
use millplan_plan::safety::{self, Check, Inputs, TipRule, Tolerances};
use millplan_sim::dropcutter::DropMesh;
use millplan_sim::gouge::{GougeParams, GougeReport};
use millplan_sim::raster::{estimate, raster, RasterParams};
use millplan_sim::stock::tool::ToolBody;
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
    /// Unit of the STL's numbers (an STL does not say): mm (default) or inch,
    /// converted to mm on reading.
    #[arg(long, value_enum)]
    pub stl_units: Option<UnitArg>,
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
    /// Print no warnings or notes about the inputs (errors still print).
    #[arg(long, short)]
    pub quiet: bool,
    /// Print a machine-readable summary (JSON) on standard output; errors too,
    /// as JSON on standard error.
    #[arg(long)]
    pub json: bool,
}

/// Every argument in its physical range: the stepover from a thousandth of
/// the tool's diameter, the step from a micrometre, the clearance above the
/// part.
fn params(a: &Args) -> CliResult<RasterParams> {
    let shape = tool_shape("--tool", &a.tool)?;
    let d = 2.0 * shape.radius();
    arg("--angle", a.angle, Range::from(-360.0, 360.0, "degrees"))?;
    crate::cmd::raster_spacing(d, a.stepover, a.step)?;
    if a.tol != 0.0 {
        arg(
            "--tol",
            a.tol,
            Range::from(1e-5, 10.0, "mm (or 0: no refinement)"),
        )?;
    }
    arg("--boundary", a.boundary, Range::from(-1e6, 1e6, "mm"))?;
    arg(
        "--clearance",
        a.clearance,
        Range::positive(1e4, "mm above the part"),
    )?;
    arg("--feed", a.feed, Range::positive(MAX_FEED, "mm/min"))?;
    arg(
        "--spindle",
        a.spindle,
        Range::positive(MAX_SPINDLE, "1/min"),
    )?;
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

/// The margin within the part (at most half its narrower side, or nothing
/// is left) and beyond it by at most its size and the tool, and the raster's
/// points and memory within the limits: counted from the grid, before any
/// point is dropped.
fn check_grid(a: &Args, p: &RasterParams, bounds: &Aabb) -> CliResult<()> {
    let size = bounds.size();
    let (narrow, wide) = (size.x.min(size.y), size.x.max(size.y));
    let reach = wide + 2.0 * p.shape.radius();
    if !(a.boundary < narrow / 2.0 && a.boundary >= -reach) {
        return Err(CliError::input(format!(
            "--boundary {}: must be from {} to under {} mm for this part ({} × {} mm in XY, with this tool)",
            a.boundary,
            amount(-reach),
            amount(narrow / 2.0),
            amount(size.x),
            amount(size.y)
        )));
    }
    let e = estimate(bounds, p, GougeParams::default().step);
    let limits = crate::limits::get();
    if !(e.points <= limits.moves as f64) {
        let needs = format!(
            "--stepover {} and --step {} over {} × {} mm make {} points",
            a.stepover,
            a.step,
            amount(size.x - 2.0 * a.boundary),
            amount(size.y - 2.0 * a.boundary),
            amount(e.points.ceil())
        );
        return Err(CliError::input(
            Exceeded::new("moves", needs, limits.moves as f64).to_string(),
        ));
    }
    crate::limits::check_memory(
        &format!("a raster of {} points", amount(e.points.ceil())),
        e.bytes,
    )
}

pub fn run(a: Args) -> CliResult<i32> {
    let p = params(&a)?;
    let inputs: Vec<&std::path::Path> = [Some(a.stl.as_path()), a.machine.as_deref()]
        .into_iter()
        .flatten()
        .collect();
    let mut outputs = Outputs::plan(&inputs, &[("-o", Some(&a.output))], false)?;
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    let (mesh, _) = read_surface(&a.stl, a.stl_units)?;
    check_grid(&a, &p, &mesh.bounds())?;
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
    let out = write_program(&prog, machine.write_options(target), &a.stl, a.quiet)?;
    let (checks, rep) = check_raster(&a, (&prog, &out), target, &part, &machine, p.shape)?;
    outputs.write(&a.output, &out)?;
    outputs.commit()?;
    let est = millplan_plan::timing::estimate_program(&prog, &machine);
    Ok(print_result(&a, &prog, (&rep, &checks), &est))
}

/// The raster checked before it is written, read back from its bytes (so
/// findings name lines of the written program): the IR verifier, S and F
/// within the machine, and its gouge check as `millplan gouge` would run it
/// (rapids too). A refusal ends the run (exit 3) unless --force.
fn check_raster(
    a: &Args,
    (prog, out): (&Program, &[u8]),
    target: Target,
    part: &DropMesh,
    machine: &Machine,
    shape: Shape,
) -> CliResult<(Vec<Check>, GougeReport)> {
    let back = read_back(out, target, prog, &Tolerance::default()).map_err(|e| {
        CliError::internal(format!(
            "{}: the raster written does not read back ({e}); not written",
            a.output.display()
        ))
    })?;
    // A generated program: every finding is the raster's own.
    let none = Program::new(Dialect::Generated);
    let (mut checks, rep) = safety::check_with_gouges(&Inputs {
        input: &none,
        output: &back.program,
        part: Some(part),
        stock: None,
        tool_body: &|_| Some(ToolBody::new(shape)),
        machine: Some(machine),
        tip: TipRule::Free,
        tol: Tolerances::default(),
        loads: None,
    });
    checks.insert(0, safety::read_back_check(&back));
    crate::verdict::enforce(&checks, &a.output, a.force)?;
    Ok((checks, rep.unwrap_or_default()))
}

/// What was written and what the gouge check found; the exit code.
fn print_result(
    a: &Args,
    prog: &millplan_nc::Program,
    (rep, checks): (&GougeReport, &[Check]),
    est: &millplan_plan::timing::TimeEstimate,
) -> i32 {
    let ok = safety::passed(checks);
    let s = millplan_nc::stats::summarize(prog, 15000.0);
    if a.json {
        let json = serde_json::json!({
            "output": a.output.display().to_string(),
            "moves": prog.move_count(),
            "cutting_mm": s.cutting_mm,
            "time_s": est.total_s,
            "time_nominal_s": est.nominal_s,
            "gouge_check": {
                "moves_checked": rep.moves_checked,
                "points_checked": rep.points_checked,
                "gouges": rep.gouges.len(),
                "max_depth_mm": rep.max_depth,
            },
            "checks": checks,
        });
        crate::cmd::print_json(json);
        return if ok { EXIT_OK } else { EXIT_FINDINGS };
    }
    outln!(
        "wrote {}: {} moves, {:.0} mm cutting, {:.0} s estimated with acceleration ({:.0} s at {} mm/min); gouge check: {} moves at {} points, {}",
        a.output.display(),
        prog.move_count(),
        s.cutting_mm,
        est.total_s,
        est.nominal_s,
        a.feed,
        rep.moves_checked,
        rep.points_checked,
        if rep.gouges.is_empty() { "clean" } else { "gouges" }
    );
    if ok {
        EXIT_OK
    } else {
        EXIT_FINDINGS
    }
}
