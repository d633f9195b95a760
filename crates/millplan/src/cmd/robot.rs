//! `millplan robot`: the compliant-joint robot model of Schnoes & Zaeh
//! (deflection at a pose).

use crate::cmd::{arg, Range};
use crate::error::{CliError, CliResult, EXIT_OK};
use clap::{Subcommand, ValueEnum};
use millplan_geom::DVec3;
use millplan_robot::machining::{self, Load, Placement};
use millplan_robot::{Robot, Variant};
use serde::Serialize;
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
    /// The process force on the tool in newtons, in each point's feed frame:
    /// along the feed, across it (to the left seen from the spindle), along
    /// the tool axis (toward the spindle).
    #[arg(long, allow_hyphen_values = true, value_name = "FEED,CROSS,AXIAL")]
    pub load: String,
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

/// `n` comma-separated numbers, each checked against `range`; `names`
/// label them in errors (`--joints A6`).
pub fn numbers(flag: &str, text: &str, names: &[&str], range: Range) -> CliResult<Vec<f64>> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != names.len() {
        return Err(CliError::input(format!(
            "{flag} {text}: {} numbers separated by commas were expected ({})",
            names.len(),
            names.join(",")
        )));
    }
    parts
        .iter()
        .zip(names)
        .map(|(p, n)| {
            let v: f64 = p
                .parse()
                .map_err(|_| CliError::input(format!("{flag} {n} {p}: not a number")))?;
            arg(&format!("{flag} {n}"), v, range)
        })
        .collect()
}

fn vec3(flag: &str, text: &str, names: [&str; 3], range: Range) -> CliResult<DVec3> {
    let v = numbers(flag, text, &names, range)?;
    Ok(DVec3::new(v[0], v[1], v[2]))
}

#[derive(Serialize)]
struct DeflectJson {
    robot: String,
    joints_deg: [f64; 6],
    tcp_mm: [f64; 3],
    dp_mm: [f64; 3],
    dtheta_deg: [f64; 3],
    dp_norm_mm: f64,
}

fn deflect(a: DeflectArgs) -> CliResult<i32> {
    let robot = load_robot(&a.robot)?;
    let deg = numbers(
        "--joints",
        &a.joints,
        &["A1", "A2", "A3", "A4", "A5", "A6"],
        Range::from(-360.0, 360.0, "degrees"),
    )?;
    let mut q = [0.0; 6];
    for (qi, d) in q.iter_mut().zip(&deg) {
        *qi = d.to_radians();
    }
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
    let variant = match a.axes {
        VariantArg::Three => Variant::ThreeAxis,
        VariantArg::One => Variant::OneAxis,
    };
    let d = robot.deflect(&q, variant, force, moment);
    let tcp = robot.fk(&q).t;
    let out = DeflectJson {
        robot: robot.name.clone(),
        joints_deg: [deg[0], deg[1], deg[2], deg[3], deg[4], deg[5]],
        tcp_mm: tcp.to_array().map(|x| sig(x, 9)),
        dp_mm: d.dp.to_array().map(|x| sig(x, 6)),
        dtheta_deg: d.dtheta.to_array().map(|x| sig(x.to_degrees(), 6)),
        dp_norm_mm: sig(d.dp.length(), 6),
    };
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&out).unwrap_or_default());
    } else {
        outln!("robot  {}", out.robot);
        outln!(
            "TCP    {:.3} {:.3} {:.3} mm (base frame)",
            tcp.x,
            tcp.y,
            tcp.z
        );
        let [x, y, z] = out.dp_mm;
        outln!("dp     {x} {y} {z} mm  (|dp| {} mm)", out.dp_norm_mm);
        let [x, y, z] = out.dtheta_deg;
        outln!("dtheta {x} {y} {z} degrees");
    }
    Ok(EXIT_OK)
}

/// `x` to `digits` significant digits (deflections are small: a fixed
/// number of decimals would lose them).
fn sig(x: f64, digits: i32) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(digits - 1 - x.abs().log10().floor() as i32);
    (x * scale).round() / scale
}

fn variant(v: VariantArg) -> Variant {
    match v {
        VariantArg::Three => Variant::ThreeAxis,
        VariantArg::One => Variant::OneAxis,
    }
}

fn process(p: &ProcessArgs) -> CliResult<(Robot, Load, Variant)> {
    let robot = load_robot(&p.robot)?;
    let l = numbers(
        "--load",
        &p.load,
        &["FEED", "CROSS", "AXIAL"],
        Range::from(-1e5, 1e5, "N"),
    )?;
    Ok((
        robot,
        Load {
            feed: l[0],
            cross: l[1],
            axial: l[2],
        },
        variant(p.axes),
    ))
}

fn read_path(path: &Path) -> CliResult<millplan_nc::Program> {
    let parsed = crate::io::read_program(path, millplan_nc::ReadOptions::default())?;
    Ok(parsed.program)
}

fn machining_error(path: &Path, e: machining::MachiningError) -> CliError {
    match e {
        machining::MachiningError::Unreachable { line, .. }
        | machining::MachiningError::Program { line, .. } => {
            let msg = e.to_string();
            let rest = msg.split_once(": ").map_or(msg.as_str(), |(_, r)| r);
            CliError::input(format!("{}:{line}:1: {rest}", path.display()))
        }
        machining::MachiningError::Empty => CliError::input(format!("{}: {e}", path.display())),
    }
}

#[derive(Serialize)]
struct CompensateJson {
    mean_deflection_mm: f64,
    max_deflection_mm: f64,
    points: usize,
    files: Vec<String>,
}

/// The compensated path written as KRL: the main program at `-o`, its
/// sub-programs beside it; the paths written.
fn write_krl(
    a: &CompensateArgs,
    c: &machining::Compensated,
    place: &Placement,
) -> CliResult<Vec<std::path::PathBuf>> {
    let stem = a
        .output
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("millplan");
    let k = machining::krl_program(stem, &c.runs, place, a.spacing / 2.0);
    let o = millplan_nc::write::krl::KrlOptions {
        name: stem.into(),
        max_points: a.max_points,
        ..Default::default()
    };
    let files = millplan_nc::write::krl::write(&k, &o);
    let paths: Vec<std::path::PathBuf> = files
        .iter()
        .enumerate()
        .map(|(i, (name, _))| {
            if i == 0 {
                a.output.clone()
            } else {
                a.output.with_file_name(format!("{name}.src"))
            }
        })
        .collect();
    let planned: Vec<(&str, Option<&Path>)> =
        paths.iter().map(|p| ("-o", Some(p.as_path()))).collect();
    let mut outputs = crate::io::Outputs::plan(&[a.path.as_path()], &planned, false)?;
    for (p, (_, text)) in paths.iter().zip(&files) {
        outputs.write(p, text.as_bytes())?;
    }
    outputs.commit()?;
    Ok(paths)
}

fn compensate(a: CompensateArgs) -> CliResult<i32> {
    let (robot, load, variant) = process(&a.process)?;
    let pose = numbers(
        "--pose",
        &a.pose,
        &["X", "Y", "Z", "RZ"],
        Range::from(-1e5, 1e5, "mm or degrees"),
    )?;
    arg("--spacing", a.spacing, Range::from(0.01, 100.0, "mm"))?;
    let place = Placement {
        x: pose[0],
        y: pose[1],
        z: pose[2],
        rz: pose[3].to_radians(),
    };
    crate::io::Outputs::plan(&[a.path.as_path()], &[("-o", Some(&a.output))], false)?;
    let prog = read_path(&a.path)?;
    let c = machining::compensate_program(&robot, variant, &prog, &place, &load, a.spacing)
        .map_err(|e| machining_error(&a.path, e))?;
    let paths = write_krl(&a, &c, &place)?;
    let out = CompensateJson {
        mean_deflection_mm: sig(c.mean, 6),
        max_deflection_mm: sig(c.max, 6),
        points: c.points,
        files: paths.iter().map(|p| p.display().to_string()).collect(),
    };
    if a.process.json {
        outln!("{}", serde_json::to_string_pretty(&out).unwrap_or_default());
    } else {
        outln!(
            "deflection before compensation: mean {} mm, max {} mm over {} points",
            out.mean_deflection_mm,
            out.max_deflection_mm,
            out.points
        );
        outln!("wrote {}", out.files.join(", "));
    }
    Ok(EXIT_OK)
}

#[derive(Serialize)]
struct PoseJson {
    x: f64,
    y: f64,
    z: f64,
    rz: f64,
}

#[derive(Serialize)]
struct PlaceJson {
    pose: PoseJson,
    mean_deflection_mm: f64,
    max_deflection_mm: f64,
    feasible: bool,
    evaluations: usize,
}

/// The placement found, as JSON or text.
fn print_place(out: &PlaceJson, json: bool) {
    if json {
        outln!("{}", serde_json::to_string_pretty(&out).unwrap_or_default());
    } else if out.feasible {
        let p = &out.pose;
        outln!(
            "placement: X {} Y {} Z {} mm, RZ {} degrees",
            p.x,
            p.y,
            p.z,
            p.rz
        );
        outln!(
            "deflection: mean {} mm, max {} mm ({} evaluations)",
            out.mean_deflection_mm,
            out.max_deflection_mm,
            out.evaluations
        );
    } else {
        outln!(
            "no feasible placement in the box: the robot cannot machine the path anywhere in it"
        );
    }
}

fn place(a: PlaceArgs) -> CliResult<i32> {
    let (robot, load, variant) = process(&a.process)?;
    let b = numbers(
        "--box",
        &a.bounds,
        &["X0", "Y0", "Z0", "X1", "Y1", "Z1"],
        Range::from(-1e5, 1e5, "mm"),
    )?;
    if !(b[0] < b[3] && b[1] < b[4] && b[2] < b[5]) {
        return Err(CliError::input(format!(
            "--box {}: each lower corner coordinate must be below the upper",
            a.bounds
        )));
    }
    arg("--restarts", a.restarts as f64, Range::from(1.0, 100.0, ""))?;
    let prog = read_path(&a.path)?;
    let samples = machining::placement_samples(&prog).map_err(|e| machining_error(&a.path, e))?;
    let search = machining::PlaceSearch {
        lo: DVec3::new(b[0], b[1], b[2]),
        hi: DVec3::new(b[3], b[4], b[5]),
        settings: millplan_robot::anneal::Settings {
            seed: a.seed,
            restarts: a.restarts,
            ..Default::default()
        },
    };
    let found = machining::place(&robot, variant, &samples, &load, &search);
    let out = match &found {
        Some(p) => PlaceJson {
            pose: PoseJson {
                x: sig(p.place.x, 7),
                y: sig(p.place.y, 7),
                z: sig(p.place.z, 7),
                rz: sig(p.place.rz.to_degrees(), 6),
            },
            mean_deflection_mm: sig(p.mean, 6),
            max_deflection_mm: sig(p.max, 6),
            feasible: true,
            evaluations: p.evaluations,
        },
        None => PlaceJson {
            pose: PoseJson {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                rz: 0.0,
            },
            mean_deflection_mm: 0.0,
            max_deflection_mm: 0.0,
            feasible: false,
            evaluations: 0,
        },
    };
    print_place(&out, a.process.json);
    Ok(if out.feasible { EXIT_OK } else { 3 })
}
