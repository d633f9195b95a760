//! A robot file: the chain of frames, the tool, the joint limits (TOML).
//!
//! Each `[[joint]]` row is one frame of the chain, transformed from the one
//! before by T = Rx(α)·Trans(x, y, z)·Rz(θ) (Schnoes & Zaeh, Equation 1, as
//! its matrix reads), θ = θ0 + sign·(A + offset) with A the KUKA angle of the
//! row's axis, or θ = θ0 for a virtual joint (`axis = 0`), which carries
//! stiffness and no motion. Every frame is a bushing: infinitely stiff in
//! translation, with a torsional stiffness about its x, y and z axes.

use crate::pose::{abc_to_matrix, Pose};
use millplan_geom::{DMat3, DVec3};
use serde::Deserialize;

/// The bundled KUKA KR 240 R2500 of the paper (`--robot kr240`).
pub const KR240_TOML: &str = include_str!("../data/kr240.toml");

/// What is wrong with a robot file, located where the TOML reader can.
#[derive(Debug, thiserror::Error)]
pub enum RobotError {
    #[error("{line}:{col}: {message}")]
    Toml {
        line: usize,
        col: usize,
        message: String,
    },
    #[error("{0}")]
    Invalid(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    name: String,
    joint: Vec<JointRow>,
    tool: ToolRow,
    limits: LimitsRow,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JointRow {
    axis: u8,
    #[serde(default)]
    theta_deg: f64,
    #[serde(default = "one")]
    sign: f64,
    #[serde(default)]
    offset_deg: f64,
    alpha_deg: f64,
    xyz_mm: [f64; 3],
    stiffness_nm_per_rad: [f64; 3],
}

fn one() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ToolRow {
    xyz_mm: [f64; 3],
    abc_deg: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LimitsRow {
    a1_deg: [f64; 2],
    a2_deg: [f64; 2],
    a3_deg: [f64; 2],
    a4_deg: [f64; 2],
    a5_deg: [f64; 2],
    a6_deg: [f64; 2],
    margin_deg: f64,
    wrist_margin_deg: f64,
}

/// One frame of the chain, angles in radians, stiffness in N·mm/rad.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The KUKA axis (1..=6) that turns it, or 0 for a virtual joint.
    pub axis: u8,
    pub theta0: f64,
    pub sign: f64,
    pub offset: f64,
    /// The constant part Rx(α)·Trans(x, y, z).
    pub fixed: Pose,
    /// Torsional stiffness about the frame's x, y, z axes, N·mm/rad.
    pub k: [f64; 3],
}

impl Frame {
    /// θ of this frame for the axis angles `q` (radians).
    pub fn theta(&self, q: &[f64; 6]) -> f64 {
        match self.axis {
            0 => self.theta0,
            a => self.theta0 + self.sign * (q[a as usize - 1] + self.offset),
        }
    }
}

/// A robot: its chain, tool and limits.
#[derive(Clone, Debug)]
pub struct Robot {
    pub name: String,
    pub frames: Vec<Frame>,
    /// The tool centre point in the last frame (KUKA: the tool's x is the
    /// direction the tool points in).
    pub tool: Pose,
    /// Lower and upper limit of A1..A6, radians.
    pub limits: [[f64; 2]; 6],
    /// Kept away from every limit, radians.
    pub margin: f64,
    /// |A5| kept at least this far from the wrist singularity, radians.
    pub wrist_margin: f64,
    pub(crate) ik: crate::kin::IkGeometry,
}

impl Robot {
    /// The bundled KR 240 R2500.
    pub fn kr240() -> Robot {
        Robot::from_toml(KR240_TOML).expect("the bundled robot file is valid")
    }

    /// Reads a robot file; every number is checked and the chain must have a
    /// spherical wrist the analytic inverse kinematics can solve.
    pub fn from_toml(text: &str) -> Result<Robot, RobotError> {
        let file: File = toml::from_str(text).map_err(|e| toml_error(text, &e))?;
        let frames = file
            .joint
            .iter()
            .enumerate()
            .map(|(i, j)| frame(i, j))
            .collect::<Result<Vec<_>, _>>()?;
        let tool = tool_pose(&file.tool)?;
        let (limits, margin, wrist_margin) = limits(&file.limits)?;
        let mut robot = Robot {
            name: file.name,
            frames,
            tool,
            limits,
            margin,
            wrist_margin,
            ik: crate::kin::IkGeometry::default(),
        };
        robot.ik = crate::kin::IkGeometry::derive(&robot).map_err(RobotError::Invalid)?;
        Ok(robot)
    }

    /// Rows of the frame each axis A1..A6 turns.
    pub fn axis_rows(&self) -> [usize; 6] {
        let mut rows = [0; 6];
        for (i, f) in self.frames.iter().enumerate() {
            if f.axis > 0 {
                rows[f.axis as usize - 1] = i;
            }
        }
        rows
    }
}

fn toml_error(text: &str, e: &toml::de::Error) -> RobotError {
    let (line, col) = match e.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            (line, col)
        }
        None => (1, 1),
    };
    RobotError::Toml {
        line,
        col,
        message: e.message().to_string(),
    }
}

fn finite(what: &str, values: &[f64]) -> Result<(), RobotError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(RobotError::Invalid(format!(
            "{what}: every number must be finite"
        )))
    }
}

fn frame(i: usize, j: &JointRow) -> Result<Frame, RobotError> {
    let what = format!("joint {} (row {})", j.axis, i + 1);
    finite(&what, &[j.theta_deg, j.sign, j.offset_deg, j.alpha_deg])?;
    finite(&what, &j.xyz_mm)?;
    if j.axis > 6 {
        return Err(RobotError::Invalid(format!(
            "{what}: axis must be 1 to 6, or 0 for a virtual joint"
        )));
    }
    if j.sign != 1.0 && j.sign != -1.0 {
        return Err(RobotError::Invalid(format!("{what}: sign must be 1 or -1")));
    }
    if !j
        .stiffness_nm_per_rad
        .iter()
        .all(|k| k.is_finite() && *k > 0.0)
    {
        return Err(RobotError::Invalid(format!(
            "{what}: every stiffness must be a positive number of N·m/rad"
        )));
    }
    let rx = DMat3::from_rotation_x(j.alpha_deg.to_radians());
    Ok(Frame {
        axis: j.axis,
        theta0: j.theta_deg.to_radians(),
        sign: j.sign,
        offset: j.offset_deg.to_radians(),
        fixed: Pose::new(rx, rx * DVec3::from_array(j.xyz_mm)),
        k: j.stiffness_nm_per_rad
            .map(|k| crate::stiffness::Torsional::from_nm_per_rad(k).n_mm_per_rad()),
    })
}

fn tool_pose(t: &ToolRow) -> Result<Pose, RobotError> {
    finite("tool", &t.xyz_mm)?;
    finite("tool", &t.abc_deg)?;
    Ok(Pose::new(
        abc_to_matrix(t.abc_deg),
        DVec3::from_array(t.xyz_mm),
    ))
}

type Limits = ([[f64; 2]; 6], f64, f64);

fn limits(l: &LimitsRow) -> Result<Limits, RobotError> {
    let rows = [l.a1_deg, l.a2_deg, l.a3_deg, l.a4_deg, l.a5_deg, l.a6_deg];
    let mut out = [[0.0; 2]; 6];
    for (i, r) in rows.iter().enumerate() {
        finite("limits", r)?;
        if !(r[0] < r[1]) || r[0] < -360.0 || r[1] > 360.0 {
            return Err(RobotError::Invalid(format!(
                "limits: a{}_deg must be [lower, upper] with lower < upper, within ±360",
                i + 1
            )));
        }
        out[i] = r.map(f64::to_radians);
    }
    for (what, v) in [
        ("margin_deg", l.margin_deg),
        ("wrist_margin_deg", l.wrist_margin_deg),
    ] {
        if !(0.0..45.0).contains(&v) {
            return Err(RobotError::Invalid(format!(
                "limits: {what} must be at least 0 and below 45"
            )));
        }
    }
    Ok((
        out,
        l.margin_deg.to_radians(),
        l.wrist_margin_deg.to_radians(),
    ))
}
