//! `millplan robot`: the compliant-joint robot model of Schnoes & Zaeh
//! (deflection at a pose).

use crate::cmd::{arg, Range};
use crate::error::{CliError, CliResult, EXIT_OK};
use clap::{Subcommand, ValueEnum};
use millplan_geom::DVec3;
use millplan_nc::Program;
use millplan_robot::machining::{self, PathLoad, Placement};
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

/// The robot and the process load, shared by `compensate` and `place`.
#[derive(clap::Args)]
pub struct ProcessArgs {
    /// The robot: `kr240` for the bundled KUKA KR 240 R2500, or a robot file.
    #[arg(long, default_value = "kr240")]
    pub robot: String,
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
    pub model: CouplingArgs,
    /// Compliant axes per frame: three (x, y, z) or one (the joint's).
    #[arg(long, value_enum, default_value = "three")]
    pub axes: VariantArg,
    /// Print JSON on standard output; errors too, as JSON on standard error.
    #[arg(long)]
    pub json: bool,
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

/// The force model along the path, as `millplan force` runs it: the
/// program cut through its stock, each move's mean force over a revolution
/// (averaged along the move, zero in air) the load of its points.
#[derive(clap::Args)]
pub struct CouplingArgs {
    /// Initial stock as `millplan force` takes it (box:auto, box:X0,Y0,Z0,X1,Y1,Z1,
    /// cylinder:…, stl:FILE, offset:MM): the load from the force model cutting it.
    #[arg(long, requires = "material")]
    pub stock: Option<String>,
    /// Part surface (STL), for --stock offset:MM.
    #[arg(long)]
    pub stl: Option<std::path::PathBuf>,
    /// Unit of the STL file's numbers (an STL does not say): mm (default) or
    /// inch, converted to mm on reading.
    #[arg(long, value_enum)]
    pub stl_units: Option<crate::cmd::UnitArg>,
    /// Named material (`millplan force materials`; en-aw-2007: the paper's).
    #[arg(long, requires = "stock")]
    pub material: Option<String>,
    /// A TOML file of further materials.
    #[arg(long)]
    pub materials: Option<std::path::PathBuf>,
    /// Cutter where the program gives none, or to override it: ball:D, flat:D, bull:D:R.
    #[arg(long)]
    pub tool: Option<String>,
    /// Flutes of every tool.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::FLUTES)]
    pub flutes: usize,
    /// Helix angle, degrees.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::HELIX_DEG, allow_hyphen_values = true)]
    pub helix: f64,
    /// Spindle speed, 1/min, for the moves of a program that gives none.
    #[arg(long, value_name = "RPM")]
    pub spindle: Option<f64>,
    /// Dexel size of the stock, mm (and the spacing of the loaded poses).
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::RESOLUTION)]
    pub resolution: f64,
}

impl CouplingArgs {
    /// The options as `force` takes them (the others at their defaults).
    fn model(&self, json: bool) -> crate::cmd::feed::ModelArgs {
        use millplan_driver::command_defaults::feed as d;
        crate::cmd::feed::ModelArgs {
            stock: self.stock.clone(),
            stl: self.stl.clone(),
            stl_units: self.stl_units,
            material: self.material.clone(),
            materials: self.materials.clone(),
            machine: None,
            tool: self.tool.clone(),
            flutes: self.flutes,
            helix: self.helix,
            stickout: None,
            flute_length: None,
            modulus: d::MODULUS,
            resolution: self.resolution,
            dz: d::DZ,
            dphi: d::DPHI_DEG,
            fixed_grid: true,
            spindle: self.spindle,
            units: None,
            table: None,
            report: None,
            json,
            quiet: json,
        }
    }
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
    /// The robot: `kr240` for the bundled KUKA KR 240 R2500, or a robot file.
    #[arg(long, default_value = "kr240")]
    pub robot: String,
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
    /// Compliant axes per frame: three (x, y, z) or one (the joint's).
    #[arg(long, value_enum, default_value = "three")]
    pub axes: VariantArg,
    /// Print JSON on standard output; errors too, as JSON on standard error.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: Args) -> CliResult<i32> {
    match a.command {
        RobotCommand::Deflect(d) => deflect(d),
        RobotCommand::Compensate(c) => compensate(c),
        RobotCommand::Place(p) => place(p),
    }
}

/// `kr240`, or a robot file.
pub fn load_robot(name: &str) -> CliResult<Robot> {
    if name == "kr240" {
        return Ok(Robot::kr240());
    }
    let p = Path::new(name);
    let text = std::fs::read_to_string(p)
        .map_err(|e| CliError::input(format!("{}: cannot read: {e}", p.display())))?;
    Robot::from_toml(&text).map_err(|e| match e {
        millplan_robot::RobotError::Toml { .. } => CliError::input(format!("{}:{e}", p.display())),
        _ => CliError::input(format!("{}: {e}", p.display())),
    })
}

/// `n` comma-separated numbers, each checked against `range`.
pub fn numbers(flag: &str, text: &str, names: &[&str], range: Range) -> CliResult<Vec<f64>> {
    millplan_driver::robot::numbers(flag, text, names, range).map_err(CliError::input)
}

fn vec3(flag: &str, text: &str, names: [&str; 3], range: Range) -> CliResult<DVec3> {
    let v = numbers(flag, text, &names, range)?;
    Ok(DVec3::new(v[0], v[1], v[2]))
}

fn deflect(a: DeflectArgs) -> CliResult<i32> {
    let robot = load_robot(&a.robot)?;
    let deg = numbers(
        "--joints",
        &a.joints,
        &["A1", "A2", "A3", "A4", "A5", "A6"],
        Range::from(-360.0, 360.0, "degrees"),
    )?;
    let force = vec3(
        "--force",
        &a.force,
        ["FX", "FY", "FZ"],
        Range::from(-1e6, 1e6, "N"),
    )?;
    let moment = match &a.moment {
        Some(m) => {
            vec3(
                "--moment",
                m,
                ["MX", "MY", "MZ"],
                Range::from(-1e5, 1e5, "N·m"),
            )? * 1e3
        }
        None => DVec3::ZERO,
    };
    let joints = [deg[0], deg[1], deg[2], deg[3], deg[4], deg[5]];
    let out = millplan_driver::robot::DeflectSummary::new(
        &robot,
        joints,
        variant(a.axes),
        (force, moment),
    );
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&out).unwrap_or_default());
    } else {
        out!("{}", out.render_text());
    }
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
fn process(path: &Path, p: &ProcessArgs) -> CliResult<(Robot, Program, PathLoad, Variant)> {
    let robot = load_robot(&p.robot)?;
    let (prog, load) = match &p.load {
        Some(text) => (
            read_path(path)?,
            millplan_driver::robot::fixed_load(text).map_err(CliError::input)?,
        ),
        None => {
            let m = p.model.model(p.json);
            let prepared = crate::cmd::feed::prepare(path, &m)?;
            let run = crate::cmd::feed::run_forces(
                &prepared,
                &prepared.program,
                &prepared.strokes,
                p.json,
            )?;
            let name = path.display().to_string();
            millplan_driver::feed::stopped_spindle(&name, &run).map_err(CliError::input)?;
            let load = millplan_driver::robot::move_loads(&prepared.program, &run);
            (prepared.program, load)
        }
    };
    Ok((robot, prog, load, variant(p.axes)))
}

fn read_path(path: &Path) -> CliResult<Program> {
    let parsed = crate::io::read_program(path, millplan_nc::ReadOptions::default())?;
    Ok(parsed.program)
}

fn machining_error(path: &Path, e: machining::MachiningError) -> CliError {
    CliError::input(millplan_driver::robot::located(
        &path.display().to_string(),
        &e,
    ))
}

/// KRL files from the `first` (0: the main program, at `output`; its
/// sub-programs beside it) staged against `inputs`: the outputs, the paths.
pub fn stage_krl(
    inputs: &[&Path],
    output: &Path,
    files: &millplan_nc::write::krl::KrlFiles,
    first: usize,
) -> CliResult<(crate::io::Outputs, Vec<std::path::PathBuf>)> {
    let paths = millplan_nc::write::krl::file_paths(output, files);
    let planned: Vec<(&str, Option<&Path>)> = paths[first..]
        .iter()
        .map(|p| ("-o", Some(p.as_path())))
        .collect();
    let mut outputs = crate::io::Outputs::plan(inputs, &planned, false)?;
    for (p, (_, text)) in paths.iter().zip(files).skip(first) {
        outputs.write(p, text.as_bytes())?;
    }
    Ok((outputs, paths))
}

/// The compensated path written as KRL: the main program at `-o`, its
/// sub-programs beside it; the paths written.
fn write_krl(
    a: &CompensateArgs,
    c: &machining::Compensated,
    place: &Placement,
) -> CliResult<Vec<std::path::PathBuf>> {
    let stem = millplan_nc::write::krl::stem(&a.output);
    let k = machining::krl_program(&stem, &c.runs, place, a.spacing / 2.0);
    let o = millplan_nc::write::krl::KrlOptions {
        name: stem,
        max_points: a.max_points,
        ..Default::default()
    };
    let files = millplan_nc::write::krl::write(&k, &o);
    let (outputs, paths) = stage_krl(&[a.path.as_path()], &a.output, &files, 0)?;
    outputs.commit()?;
    Ok(paths)
}

fn compensate(a: CompensateArgs) -> CliResult<i32> {
    let place = millplan_driver::robot::pose(&a.pose).map_err(CliError::input)?;
    arg("--spacing", a.spacing, Range::from(0.01, 100.0, "mm"))?;
    crate::io::Outputs::plan(&[a.path.as_path()], &[("-o", Some(&a.output))], false)?;
    let (robot, prog, load, variant) = process(&a.path, &a.process)?;
    let c = machining::compensate_program_with(
        &robot,
        variant,
        &prog,
        &place,
        &load,
        a.spacing,
        a.orientation,
    )
    .map_err(|e| machining_error(&a.path, e))?;
    let paths = write_krl(&a, &c, &place)?;
    let files = paths.iter().map(|p| p.display().to_string()).collect();
    let out = millplan_driver::robot::CompensateSummary::new(&c, &load, files);
    if a.process.json {
        outln!("{}", serde_json::to_string_pretty(&out).unwrap_or_default());
    } else {
        out!("{}", out.render_text());
    }
    Ok(EXIT_OK)
}

fn place(a: PlaceArgs) -> CliResult<i32> {
    let (lo, hi) = millplan_driver::robot::place_box(&a.bounds).map_err(CliError::input)?;
    arg("--restarts", a.restarts as f64, Range::from(1.0, 100.0, ""))?;
    let (robot, prog, load, variant) = process(&a.path, &a.process)?;
    let samples = machining::placement_samples(&prog).map_err(|e| machining_error(&a.path, e))?;
    let search = machining::PlaceSearch {
        lo,
        hi,
        settings: millplan_robot::anneal::Settings {
            seed: a.seed,
            restarts: a.restarts,
            ..Default::default()
        },
    };
    let found = machining::place(&robot, variant, &samples, &load, &search);
    let out = millplan_driver::robot::PlaceSummary::new(found.as_ref());
    if a.process.json {
        outln!("{}", serde_json::to_string_pretty(&out).unwrap_or_default());
    } else {
        out!("{}", out.render_text());
    }
    Ok(if out.feasible { EXIT_OK } else { 3 })
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
    #[arg(long, default_value_t = millplan_driver::command_defaults::robot::MAX_POINTS)]
    pub max_points: usize,
}

/// The robot pass at the end of `optimise` (nothing without --robot): the
/// KRL main program to write, its sub-programs written beside `output`.
pub fn after_optimise(
    r: &OptimiseRobotArgs,
    (job, outcome): (&millplan_driver::Job, &millplan_driver::Outcome),
    w: &mut millplan_driver::Written,
    (inputs, output): (&[&Path], &Path),
    (force, quiet): (bool, bool),
) -> CliResult<()> {
    let (Some(name), Some(pose)) = (&r.robot, &r.pose) else {
        return Ok(());
    };
    let setup = millplan_driver::robot_pass::RobotSetup::new(
        load_robot(name)?,
        pose,
        r.max_points,
        job.tol,
    )
    .map_err(CliError::input)?;
    let krl = millplan_nc::write::Target::Krl.name();
    if w.summary.dialect == krl {
        let t = millplan_driver::robot_pass::check_target(job.inputs.program.source);
        let wo = millplan_nc::write::WriteOptions {
            limits: crate::limits::get(),
            ..job.inputs.machine.write_options(t)
        };
        *w = job
            .finish(outcome, wo)
            .map_err(|e| CliError::input(e.to_string()))?;
        w.summary.dialect = krl.into();
    }
    let stem = millplan_nc::write::krl::stem(output);
    let posted = outcome.posted.is_some();
    let done = millplan_driver::robot_pass::run(
        &setup,
        (&w.program, posted),
        w.forces_after.as_ref(),
        &stem,
    )
    .map_err(|e| CliError::input(format!("--robot: {e}")))?;
    if !quiet {
        eprintln!("{}", done.summary.render_text());
    }
    w.bytes = done.files[0].1.clone().into_bytes();
    if w.summary.verdict != millplan_driver::Verdict::Refused || force {
        stage_krl(inputs, output, &done.files, 1)?.0.commit()?;
    }
    Ok(())
}
