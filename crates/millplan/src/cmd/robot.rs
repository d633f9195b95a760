//! `millplan robot`: the compliant-joint robot model of Schnoes & Zaeh
//! (deflection at a pose).

use crate::cmd::{arg, Range};
use crate::error::{CliError, CliResult, EXIT_OK};
use clap::{Subcommand, ValueEnum};
use millplan_geom::DVec3;
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
