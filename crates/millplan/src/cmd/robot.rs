//! `millplan robot`: the compliant-joint robot model of Schnoes & Zaeh
//! (deflection at a pose).

use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::Outputs;
use crate::timings::{Clock, Table as _};
use clap::{Subcommand, ValueEnum};
use millplan_driver::robot as lib;
use millplan_driver::robot_pass::RobotSetup;
use millplan_nc::Program;
use millplan_robot::machining::PathLoad;
use millplan_robot::{Robot, Variant};
use std::path::Path;

/// Robot machining: how far the tool centre point of a compliant robot gives
/// way under a load.
///
/// The robot is a chain of frames, each a bushing with a torsional
/// stiffness about its three axes (Schnoes & Zaeh, CIRP CMMO 2019: the KUKA
/// KR 240 R2500 with two virtual joints for the bending of the arms).
/// `--robot kr240` is that robot, bundled; a path names a robot file of your
/// own in the same TOML form (see docs/robot.md).
///
/// Exit codes: 0 done; 2 bad arguments or a robot file that cannot be used
/// (the message names file:line:col where it can).
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    pub command: RobotCommand,
}

#[derive(Subcommand)]
pub enum RobotCommand {
    /// The deflection of the tool centre point at one pose under a force
    /// (and moment) acting at it, in the robot's base frame.
    Deflect(DeflectArgs),
    /// Offline compensation of a toolpath (APT/CL or G-code, in the
    /// workpiece frame): the path resampled, the deflection under the load
    /// at every point, the commanded points moved by minus the deflection,
    /// written as a KUKA KRL program.
    Compensate(CompensateArgs),
    /// Where to place the workpiece in the robot's workspace so that the
    /// mean deflection along the path (sampled every 10 mm) is smallest:
    /// constrained simulated annealing over x, y, z and the turn about the
    /// vertical, seeded and reproducible.
    Place(PlaceArgs),
}

/// The robot, shared by `deflect`, `compensate` and `place`.
#[derive(clap::Args)]
pub struct RobotArgs {
    /// The robot: `kr240` for the bundled KUKA KR 240 R2500, or a robot file.
    #[arg(long, default_value = "kr240")]
    pub robot: String,
    /// Compliant axes per frame: three (x, y, z) or one (the joint's).
    #[arg(long, value_enum, default_value = "three")]
    pub axes: VariantArg,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
}

/// The robot and the process load, shared by `compensate` and `place`: a
/// fixed load, or the force model along the path as `millplan force` runs
/// it (the program cut through its stock, each move's mean force over a
/// revolution, averaged along the move and zero in air, the load of its
/// points).
#[derive(clap::Args)]
#[command(
    mut_arg("stock", |a| a.requires("material")),
    mut_arg("material", |a| a.requires("stock"))
)]
pub struct ProcessArgs {
    #[command(flatten)]
    pub robot: RobotArgs,
    /// A fixed process force on the tool in newtons, the same at every
    /// point, in each point's feed frame: along the feed, across it (to the
    /// left seen from the spindle), along the tool axis (toward the
    /// spindle). The alternative to --stock and --material.
    #[arg(
        long,
        allow_hyphen_values = true,
        value_name = "FEED,CROSS,AXIAL",
        required_unless_present = "stock",
        conflicts_with = "stock"
    )]
    pub load: Option<String>,
    #[command(flatten)]
    pub model: crate::cmd::feed::ForceInputs,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

#[derive(clap::Args)]
pub struct CompensateArgs {
    /// The toolpath (APT/CL or G-code), coordinates in the workpiece frame.
    pub path: std::path::PathBuf,
    #[command(flatten)]
    pub process: ProcessArgs,
    /// The workpiece frame in the robot base: origin X,Y,Z in mm and the
    /// turn RZ about the vertical in degrees (as `robot place` prints it).
    #[arg(long, allow_hyphen_values = true, value_name = "X,Y,Z,RZ")]
    pub pose: String,
    /// Distance between the commanded points, mm (the paper: 0.3).
    #[arg(long, default_value_t = millplan_driver::command_defaults::robot::SPACING_MM)]
    pub spacing: f64,
    /// Motions per KRL sub-program (a main program calls them); 0 writes
    /// one file.
    #[arg(long, default_value_t = millplan_driver::command_defaults::robot::MAX_POINTS)]
    pub max_points: usize,
    /// Each point one LIN (approximated with C_DIS), or each run a SPLINE block of SPL points.
    #[arg(long, default_value = "lin", value_name = "lin|spline")]
    pub krl_motion: millplan_nc::write::krl::KrlMotion,
    /// Correct the tool's orientation too: each point is commanded turned
    /// back by the angle the load turns the tool there (A, B, C written from
    /// the turned frame). Without it only the position is corrected and the
    /// tool stays tilted by that angle, a few hundredths of a degree.
    #[arg(long)]
    pub orientation: bool,
    /// The KRL program to write (.src); sub-programs go beside it.
    #[arg(short = 'o', long)]
    pub output: std::path::PathBuf,
}

#[derive(clap::Args)]
pub struct PlaceArgs {
    /// The toolpath (APT/CL or G-code), coordinates in the workpiece frame.
    pub path: std::path::PathBuf,
    #[command(flatten)]
    pub process: ProcessArgs,
    /// The box the workpiece origin may be placed in, in the robot base:
    /// X0,Y0,Z0,X1,Y1,Z1 in mm.
    #[arg(
        long = "box",
        allow_hyphen_values = true,
        value_name = "X0,Y0,Z0,X1,Y1,Z1",
        default_value = millplan_driver::command_defaults::robot::PLACE_BOX
    )]
    pub bounds: String,
    /// Seed of the search: the same seed gives the same placement.
    #[arg(long, default_value_t = millplan_driver::command_defaults::robot::SEED)]
    pub seed: u64,
    /// Independent runs of the search from random starts; the best is kept.
    #[arg(long, default_value_t = millplan_driver::command_defaults::robot::RESTARTS)]
    pub restarts: usize,
}

/// Which compliant axes each frame of the chain has.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum VariantArg {
    /// Three torsional axes per frame (its x, y and z), the paper's bushings.
    Three,
    /// One axis per frame, the joint's own.
    One,
}

#[derive(clap::Args)]
pub struct DeflectArgs {
    /// The six axis angles A1,A2,A3,A4,A5,A6 in degrees, as the controller
    /// shows them.
    #[arg(long, allow_hyphen_values = true, value_name = "A1,A2,A3,A4,A5,A6")]
    pub joints: String,
    /// The force on the tool FX,FY,FZ in newtons, in the base frame.
    #[arg(long, allow_hyphen_values = true, value_name = "FX,FY,FZ")]
    pub force: String,
    /// A moment MX,MY,MZ in newton metres, in the base frame.
    #[arg(long, allow_hyphen_values = true, value_name = "MX,MY,MZ")]
    pub moment: Option<String>,
    #[command(flatten)]
    pub robot: RobotArgs,
}

pub fn run(a: Args) -> CliResult<i32> {
    match a.command {
        RobotCommand::Deflect(d) => deflect(d),
        RobotCommand::Compensate(c) => compensate(c),
        RobotCommand::Place(p) => place(p),
    }
}

/// `kr240`, or a robot file.
fn load_robot(name: &str) -> CliResult<Robot> {
    Ok(millplan_driver::io::inputs::read_robot(name)?)
}

/// Prints a command's summary, as JSON or as text.
fn print<T: serde::Serialize>(json: bool, out: &T, text: impl FnOnce(&T) -> String) {
    if json {
        outln!("{}", serde_json::to_string_pretty(out).unwrap_or_default());
    } else {
        out!("{}", text(out));
    }
}

fn deflect(a: DeflectArgs) -> CliResult<i32> {
    let robot = load_robot(&a.robot.robot)?;
    let req = lib::DeflectRequest {
        joints: a.joints,
        force: a.force,
        moment: a.moment,
        variant: variant(a.robot.axes),
    };
    let out = lib::deflect(&robot, &req).map_err(CliError::input)?;
    print(a.robot.summary.json, &out, lib::DeflectSummary::render_text);
    Ok(EXIT_OK)
}

fn variant(v: VariantArg) -> Variant {
    match v {
        VariantArg::Three => Variant::ThreeAxis,
        VariantArg::One => Variant::OneAxis,
    }
}

/// The robot, the program at `path` and its load: `--load` at every
/// point, or the force model's per move with the stock.
fn process(path: &Path, p: &ProcessArgs) -> CliResult<(Robot, Program, PathLoad)> {
    let robot = load_robot(&p.robot.robot)?;
    if let Some(text) = &p.load {
        let load = lib::fixed_load(text).map_err(CliError::input)?;
        let opts = millplan_nc::ReadOptions::default();
        return Ok((robot, crate::io::read_program(path, opts)?.program, load));
    }
    let m = &p.model;
    let files = m.files(path, None, &crate::cmd::args::ProgramUnits { units: None })?;
    let watch = crate::progress::Watch::new(path, false, p.robot.summary.json);
    let req = lib::CouplingRequest {
        stock: m.stock.clone(),
        material: m.material.clone(),
        tool: m.tool.clone(),
        flutes: m.flutes,
        helix: m.helix,
        spindle: m.spindle,
        resolution: m.resolution,
    };
    let (program, load) = lib::model_load(&files, &req, &watch)?;
    Ok((robot, program, load))
}

fn compensate(a: CompensateArgs) -> CliResult<i32> {
    let req = lib::CompensateRequest {
        pose: a.pose,
        spacing: a.spacing,
        max_points: a.max_points,
        motion: a.krl_motion,
        orientation: a.orientation,
    };
    let mut clock = Clock::start();
    let place = req.check().map_err(CliError::input)?;
    crate::io::Outputs::plan(&[a.path.as_path()], &[("-o", Some(&a.output))], false)?;
    let (robot, program, load) = process(&a.path, &a.process)?;
    clock.lap("robot, program and load read (the force model on the stock with --stock)");
    let name = a.path.display().to_string();
    let p = process_of(&robot, &a.process, (&program, &load), &name);
    let done = lib::compensate(&p, &req, &place, &a.output).map_err(CliError::input)?;
    clock.lap("path resampled, deflected, compensated and checked; KRL made");
    Outputs::stage_krl(&[a.path.as_path()], &a.output, &done.files, 0)?.commit()?;
    clock.lap("KRL files written and renamed into place");
    let json = a.process.robot.summary.json;
    print(json, &done.summary, lib::CompensateSummary::render_text);
    clock.end(a.process.timings.on);
    Ok(EXIT_OK)
}

/// The path on the robot under its load, as the driver takes it.
fn process_of<'a>(
    robot: &'a Robot,
    a: &ProcessArgs,
    (program, load): (&'a Program, &'a PathLoad),
    path: &'a str,
) -> lib::Process<'a> {
    lib::Process {
        robot,
        variant: variant(a.robot.axes),
        program,
        load,
        path,
    }
}

fn place(a: PlaceArgs) -> CliResult<i32> {
    let req = lib::PlaceRequest {
        bounds: a.bounds,
        seed: a.seed,
        restarts: a.restarts,
    };
    let mut clock = Clock::start();
    let search = req.check().map_err(CliError::input)?;
    let (robot, program, load) = process(&a.path, &a.process)?;
    clock.lap("robot, program and load read (the force model on the stock with --stock)");
    let name = a.path.display().to_string();
    let p = process_of(&robot, &a.process, (&program, &load), &name);
    let out = lib::place(&p, &search).map_err(CliError::input)?;
    clock.lap("placement searched (simulated annealing)");
    print(
        a.process.robot.summary.json,
        &out,
        lib::PlaceSummary::render_text,
    );
    clock.end(a.process.timings.on);
    Ok(crate::error::exit(!out.feasible))
}

/// `optimise --robot ROBOT --pose X,Y,Z,RZ`: the optimised program ends
/// with offline compensation for a robot and is written as KRL.
#[derive(clap::Args)]
pub struct OptimiseRobotArgs {
    /// End with offline compensation for a robot (`kr240`, or a robot
    /// file), as `robot compensate` does under the force model's loads on
    /// the stock (--stock, --material): written to -o as KUKA KRL, read back
    /// and run on the robot model again, the tip within --tol of the path.
    #[arg(long, requires = "pose")]
    pub robot: Option<String>,
    /// With --robot: the workpiece frame in the robot base, origin X,Y,Z in
    /// mm and the turn RZ about the vertical in degrees.
    #[arg(
        long,
        allow_hyphen_values = true,
        value_name = "X,Y,Z,RZ",
        requires = "robot"
    )]
    pub pose: Option<String>,
    /// With --robot: motions per KRL sub-program (a main program at -o calls
    /// them, written beside it); 0 writes one file.
    #[arg(
        long,
        default_value_t = millplan_driver::command_defaults::robot::MAX_POINTS,
        requires = "robot"
    )]
    pub max_points: usize,
    /// With --robot: each point one LIN with C_DIS (the default), or each
    /// run a SPLINE block of SPL points. Refused without --robot: only the
    /// robot's program is KRL.
    #[arg(long, value_name = "lin|spline")]
    pub krl_motion: Option<millplan_nc::write::krl::KrlMotion>,
    /// With --robot: correct the tool's orientation too, as `robot
    /// compensate --orientation` does (each point commanded turned back by
    /// the angle the load turns the tool there); without it only the
    /// position is corrected.
    #[arg(long, requires = "robot")]
    pub orientation: bool,
}

impl OptimiseRobotArgs {
    /// The options refused before any work: a KRL motion without --robot.
    pub fn check(&self) -> CliResult<()> {
        millplan_driver::robot_pass::krl_options(self.robot.is_some(), self.krl_motion)
            .map_err(CliError::input)
    }
}

/// The robot pass at the end of `optimise` (nothing without --robot): the
/// KRL main program to write, its sub-programs written beside `output`.
pub fn after_optimise(
    r: &OptimiseRobotArgs,
    run: (&millplan_driver::Job, &millplan_driver::Outcome),
    w: &mut millplan_driver::Written,
    (inputs, output): (&[&Path], &Path),
    (force, quiet): (bool, bool),
) -> CliResult<()> {
    let (Some(name), Some(pose)) = (&r.robot, &r.pose) else {
        return Ok(());
    };
    let tol = run.0.tol;
    let mut setup =
        RobotSetup::new(load_robot(name)?, pose, r.max_points, tol).map_err(CliError::input)?;
    setup.motion = r.krl_motion.unwrap_or_default();
    setup.orientation = r.orientation;
    let done =
        millplan_driver::robot_pass::after_optimise(&setup, run, w, output, crate::limits::get())
            .map_err(CliError::input)?;
    if !quiet {
        eprintln!("{}", done.summary.render_text());
    }
    if w.summary.verdict != millplan_driver::Verdict::Refused || force {
        Outputs::stage_krl(inputs, output, &done.files, 1)?.commit()?;
    }
    Ok(())
}
