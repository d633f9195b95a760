//! What the machine can do, in one description: its control (dialect, what an
//! inverse-time F means, spindle-speed decimals), the spindle (range,
//! acceleration, power and torque by speed), feed limits and rapid rate, the
//! five-axis kinematics with axis limits, velocities and accelerations, and
//! the modal parameters stability analysis needs.
//!
//! Read from one TOML file ([`Machine::from_toml`]; the layout, every field
//! commented, is `examples/machine.toml` at the workspace root). The two older
//! single-purpose files (spindle/feed limits only, and kinematics only) still
//! read; see [`Layout`]. A sensible default is built in ([`Machine::default`]).

mod file;

pub use file::Layout;

use crate::timing::Planner;
use millplan_models::kinematics::Kinematics;
use millplan_nc::write::{Target, WriteOptions};

/// A machine description. Everything beyond the spindle and feed basics is
/// optional: `None` (or an empty axis) means "not known", and no pass may read
/// it as a limit of zero.
#[derive(Clone, Debug, PartialEq)]
pub struct Machine {
    pub name: String,
    /// Lowest programmable spindle speed, 1/min.
    pub spindle_min: f64,
    /// Highest spindle speed, 1/min.
    pub spindle_max: f64,
    /// Spindle acceleration, 1/min per second.
    pub spindle_accel: f64,
    /// Power and torque the spindle delivers by speed; `None`: unknown.
    pub spindle_curve: Option<SpindleCurve>,
    /// Lowest programmable feed, mm/min.
    pub feed_min: f64,
    /// Highest cutting feed, mm/min.
    pub feed_max: f64,
    /// Feed of cutting blocks that meet no material (`[feed] air`), mm/min;
    /// `None`: the tool's largest feed per tooth at the block's speed (the
    /// feed pass's rule, [`crate::feed`]).
    pub feed_air: Option<f64>,
    /// Rapid traverse rate, mm/min.
    pub rapid: f64,
    pub control: Control,
    pub kinematics: Option<Kinematics>,
    pub axes: Axes,
    pub modal: Option<Modal>,
    /// What the five-axis post needs of this machine beyond its axes.
    pub post: PostSettings,
}

/// The five-axis post's settings for one machine (`[post]`): the pole cone
/// and its tolerance (spec kinematics-access-tools §1.8) and the retract of
/// a branch change (§1.7).
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct PostSettings {
    /// Half-angle (degrees) of the cone about the pole within which the
    /// turning axis is held.
    #[serde(default = "one_degree")]
    pub pole_cone: f64,
    /// Orientation deviation (degrees) beyond which a pole block is flagged.
    #[serde(default = "one_degree")]
    pub pole_tol: f64,
    /// Retract along the tool axis before the rotaries turn for a branch
    /// change, mm.
    #[serde(default = "fifty_mm")]
    pub clearance: f64,
    /// Post feeds as inverse time (G93, an F on every feed block) rather
    /// than G94 (`millplan optimise`; `millplan post --g93`).
    #[serde(default)]
    pub inverse_time: bool,
}

fn one_degree() -> f64 {
    1.0
}

fn fifty_mm() -> f64 {
    50.0
}

impl Default for PostSettings {
    fn default() -> Self {
        PostSettings {
            pole_cone: one_degree(),
            pole_tol: one_degree(),
            clearance: fifty_mm(),
            inverse_time: false,
        }
    }
}

/// What the control makes of the words a program holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Control {
    /// The dialect the control reads; `None`: the file does not say.
    pub dialect: Option<Target>,
    /// What an F word means under G93 (inverse time).
    pub g93_f: InverseTimeF,
    /// Whether G0 may be programmed while G93 is active (RS274/NGC: yes, G0
    /// ignores F). When not, a writer has to leave G93 around rapids.
    pub g93_rapids: bool,
    /// Decimals of S words; `None`: the dialect's usual (whole numbers for
    /// Fanuc, whose controls refuse `S4200.6`, one decimal elsewhere).
    pub spindle_decimals: Option<u32>,
    /// How the control plans the path through the blocks (the time
    /// estimate's model of it); default the generic planner.
    pub planner: Planner,
}

impl Default for Control {
    fn default() -> Self {
        Control {
            dialect: None,
            g93_f: InverseTimeF::InverseMinutes,
            g93_rapids: true,
            spindle_decimals: None,
            planner: Planner::default(),
        }
    }
}

/// Controls disagree on the unit of an inverse-time F (spec
/// kinematics-access-tools §1.10, process-models §2.5), so the post needs it
/// per control.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum InverseTimeF {
    /// F = 1 / block time in minutes (RS274/NGC: LinuxCNC, Fanuc, Sinumerik).
    InverseMinutes,
    /// F = block time in seconds (Beckhoff/ISG TwinCAT CNC).
    Seconds,
}

impl InverseTimeF {
    /// The F word for a block that takes `minutes`.
    pub fn word(self, minutes: f64) -> f64 {
        match self {
            InverseTimeF::InverseMinutes => 1.0 / minutes,
            InverseTimeF::Seconds => minutes * 60.0,
        }
    }

    /// The block time, in minutes, that an F word asks for.
    pub fn minutes(self, f: f64) -> f64 {
        match self {
            InverseTimeF::InverseMinutes => 1.0 / f,
            InverseTimeF::Seconds => f / 60.0,
        }
    }
}

/// One linear axis: travel (mm, machine coordinates), top speed (mm/min),
/// acceleration (mm/s²) and jerk (mm/s³); `None`: not known (the time
/// estimate then uses conservative defaults, and no jerk limit).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct LinearAxis {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub accel: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jerk: Option<f64>,
}

/// The drive of one rotary axis: top speed (degrees/min), acceleration
/// (degrees/s²) and jerk (degrees/s³). Its travel is in the kinematics ([`RotaryAxis`]
/// min/max), the one place the inverse kinematics reads it from.
///
/// [`RotaryAxis`]: millplan_models::kinematics::RotaryAxis
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct RotaryDrive {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub accel: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jerk: Option<f64>,
}

impl RotaryDrive {
    fn is_empty(&self) -> bool {
        *self == RotaryDrive::default()
    }
}

/// Per-axis limits: X, Y, Z, and the kinematics' two rotary axes.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Axes {
    pub x: LinearAxis,
    pub y: LinearAxis,
    pub z: LinearAxis,
    /// The tilting axis ([`Kinematics::first`]).
    pub first: RotaryDrive,
    /// The rotary axis ([`Kinematics::second`]).
    pub second: RotaryDrive,
}

/// One point of the spindle chart: at `speed` (1/min) the spindle delivers at
/// most `power` (kW) and `torque` (N·m); either may be left out, it then
/// follows from the other through P = T·ω.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct CurvePoint {
    pub speed: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub power: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque: Option<f64>,
}

/// What the spindle delivers at one speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpindleLimit {
    /// kW.
    pub power: f64,
    /// N·m.
    pub torque: f64,
}

/// The spindle chart: power and torque by speed, interpolated linearly
/// between its points. Built only through [`SpindleCurve::new`], so its points
/// are always at least two, with strictly increasing speeds.
#[derive(Clone, Debug, PartialEq)]
pub struct SpindleCurve {
    points: Vec<CurvePoint>,
    /// (speed 1/min, power kW, torque N·m) with the missing one of each pair
    /// derived.
    full: Vec<[f64; 3]>,
}

/// rad/s at `n` 1/min.
fn omega(n: f64) -> f64 {
    n * std::f64::consts::TAU / 60.0
}

impl SpindleCurve {
    /// The chart from its points, checked: at least two, speeds finite, not
    /// negative and strictly increasing, power and torque finite and
    /// positive, at least one of them per point (torque at standstill, where
    /// power says nothing about it).
    pub fn new(points: Vec<CurvePoint>) -> Result<SpindleCurve, MachineError> {
        if points.len() < 2 {
            return Err(MachineError::invalid(
                "spindle.curve",
                "needs at least two points (speed, power and/or torque)",
            ));
        }
        let mut full: Vec<[f64; 3]> = Vec::with_capacity(points.len());
        for (i, p) in points.iter().enumerate() {
            let field = |f: &str| format!("spindle.curve[{i}].{f}");
            if !(p.speed.is_finite() && p.speed >= 0.0) {
                return Err(MachineError::invalid(
                    field("speed"),
                    format!("must be a finite speed ≥ 0 (1/min), got {}", p.speed),
                ));
            }
            if let Some(&[prev, ..]) = full.last() {
                if !(p.speed > prev) {
                    return Err(MachineError::invalid(
                        field("speed"),
                        format!(
                            "speeds must increase from point to point ({} after {prev})",
                            p.speed
                        ),
                    ));
                }
            }
            for (name, v, unit) in [("power", p.power, "kW"), ("torque", p.torque, "N·m")] {
                if let Some(v) = v {
                    if !(v.is_finite() && v > 0.0) {
                        return Err(MachineError::invalid(
                            field(name),
                            format!("must be finite and positive ({unit}), got {v}"),
                        ));
                    }
                }
            }
            let w = omega(p.speed);
            let (power, torque) = match (p.power, p.torque) {
                (Some(pw), Some(t)) => (pw, t),
                (None, Some(t)) => (t * w / 1000.0, t),
                (Some(pw), None) if w > 0.0 => (pw, pw * 1000.0 / w),
                (Some(_), None) => {
                    return Err(MachineError::invalid(
                        field("torque"),
                        "is needed at standstill, where power says nothing about torque",
                    ))
                }
                (None, None) => {
                    return Err(MachineError::invalid(
                        format!("spindle.curve[{i}]"),
                        "give power (kW), torque (N·m) or both",
                    ))
                }
            };
            full.push([p.speed, power, torque]);
        }
        Ok(SpindleCurve { points, full })
    }

    /// The points as given.
    pub fn points(&self) -> &[CurvePoint] {
        &self.points
    }

    /// The speed range the chart covers, 1/min.
    pub fn range(&self) -> (f64, f64) {
        let first = self.full.first().map_or(0.0, |p| p[0]);
        let last = self.full.last().map_or(0.0, |p| p[0]);
        (first, last)
    }

    /// Power and torque available at `speed` (1/min). Power and torque are
    /// each interpolated linearly between the points, and each is then
    /// capped by what the other allows (P = T·ω): a straight line between two
    /// points of the constant-power hyperbola lies above it, and the cap puts
    /// the torque back on it. Outside the chart the end values hold (a
    /// validated machine's chart covers its spindle range).
    pub fn limit(&self, speed: f64) -> SpindleLimit {
        let (lo, hi) = self.range();
        let n = speed.clamp(lo, hi);
        // The segment [i-1, i] holding n; the constructor guarantees two points.
        let i = self
            .full
            .partition_point(|p| p[0] <= n)
            .clamp(1, self.full.len().saturating_sub(1).max(1));
        let (Some(a), Some(b)) = (self.full.get(i - 1), self.full.get(i)) else {
            return SpindleLimit {
                power: f64::NAN,
                torque: f64::NAN,
            };
        };
        let t = ((n - a[0]) / (b[0] - a[0])).clamp(0.0, 1.0);
        let power = a[1] + t * (b[1] - a[1]);
        let torque = a[2] + t * (b[2] - a[2]);
        let w = omega(n);
        SpindleLimit {
            power: power.min(torque * w / 1000.0),
            torque: if w > 0.0 {
                torque.min(power * 1000.0 / w)
            } else {
                torque
            },
        }
    }
}

/// One vibration mode of the tool–spindle–machine structure in one direction.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Mode {
    /// Natural frequency, Hz.
    pub frequency: f64,
    /// Damping ratio ζ (0 < ζ < 1).
    pub damping: f64,
    /// Modal stiffness k, N/m.
    pub stiffness: f64,
}

impl Mode {
    /// Receptance at `f` Hz, m/N, as (real, imaginary):
    /// G = 1 / (k·(1 − r² + 2iζr)), r = f/f_n (spec process-models §3).
    pub fn frf(&self, f: f64) -> (f64, f64) {
        let r = f / self.frequency;
        let (re, im) = (1.0 - r * r, 2.0 * self.damping * r);
        let d = self.stiffness * (re * re + im * im);
        (re / d, -im / d)
    }
}

/// The modes of the two directions the stability model uses (cross terms
/// ignored, as in the zero-order approximation).
#[derive(Clone, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Modal {
    pub x: Vec<Mode>,
    pub y: Vec<Mode>,
}

impl Modal {
    fn sum(modes: &[Mode], f: f64) -> (f64, f64) {
        modes.iter().fold((0.0, 0.0), |(re, im), m| {
            let (r, i) = m.frf(f);
            (re + r, im + i)
        })
    }

    /// Φxx at `f` Hz, m/N: the sum of the X modes.
    pub fn frf_x(&self, f: f64) -> (f64, f64) {
        Modal::sum(&self.x, f)
    }

    /// Φyy at `f` Hz, m/N: the sum of the Y modes.
    pub fn frf_y(&self, f: f64) -> (f64, f64) {
        Modal::sum(&self.y, f)
    }
}

/// Why a machine description cannot be used: where (line and column in the
/// file, when known), which field (as the file spells it) and what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct MachineError {
    /// 1-based line and column.
    pub at: Option<(usize, usize)>,
    pub field: Option<String>,
    pub message: String,
}

impl MachineError {
    pub fn invalid(field: impl Into<String>, message: impl Into<String>) -> MachineError {
        MachineError {
            at: None,
            field: Some(field.into()),
            message: message.into(),
        }
    }
}

impl std::fmt::Display for MachineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some((line, col)) = self.at {
            write!(f, "{line}:{col}: ")?;
        }
        if let Some(field) = &self.field {
            write!(f, "{field}: ")?;
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for MachineError {}

/// The machine in JSON summaries (`speed --json`): the keys of the old
/// speed-only file, as before, then whatever else the file gave, so that a
/// summary of an old file's machine reads as it did.
impl serde::Serialize for Machine {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(serde::Serialize)]
        struct Summary<'a> {
            name: &'a str,
            spindle_min: f64,
            spindle_max: f64,
            spindle_accel: f64,
            feed_min: f64,
            feed_max: f64,
            #[serde(skip_serializing_if = "Option::is_none")]
            feed_air: Option<f64>,
            rapid: f64,
            dialect: Option<&'static str>,
            #[serde(skip_serializing_if = "Option::is_none")]
            spindle_curve: Option<&'a [CurvePoint]>,
            #[serde(skip_serializing_if = "Option::is_none")]
            g93_f: Option<InverseTimeF>,
            #[serde(skip_serializing_if = "Option::is_none")]
            g93_rapids: Option<bool>,
            #[serde(skip_serializing_if = "Option::is_none")]
            spindle_decimals: Option<u32>,
            #[serde(skip_serializing_if = "Option::is_none")]
            kinematics: Option<&'a Kinematics>,
            #[serde(skip_serializing_if = "Option::is_none")]
            axes: Option<&'a Axes>,
            #[serde(skip_serializing_if = "Option::is_none")]
            modal: Option<&'a Modal>,
            #[serde(skip_serializing_if = "Option::is_none")]
            post: Option<&'a PostSettings>,
        }
        let c = &self.control;
        let d = Control::default();
        Summary {
            name: &self.name,
            spindle_min: self.spindle_min,
            spindle_max: self.spindle_max,
            spindle_accel: self.spindle_accel,
            feed_min: self.feed_min,
            feed_max: self.feed_max,
            feed_air: self.feed_air,
            rapid: self.rapid,
            dialect: c.dialect.map(Target::name),
            spindle_curve: self.spindle_curve.as_ref().map(SpindleCurve::points),
            g93_f: (c.g93_f != d.g93_f).then_some(c.g93_f),
            g93_rapids: (c.g93_rapids != d.g93_rapids).then_some(c.g93_rapids),
            spindle_decimals: c.spindle_decimals,
            kinematics: self.kinematics.as_ref(),
            axes: (self.axes != Axes::default()).then_some(&self.axes),
            modal: self.modal.as_ref(),
            post: (self.post != PostSettings::default()).then_some(&self.post),
        }
        .serialize(s)
    }
}

impl Default for Machine {
    /// A typical high-speed machining centre, three axes, nothing known
    /// beyond its spindle and feeds.
    fn default() -> Self {
        Machine {
            name: "default HSC machining centre".into(),
            spindle_min: 500.0,
            spindle_max: 18000.0,
            spindle_accel: 6000.0,
            spindle_curve: None,
            feed_min: 1.0,
            feed_max: 20000.0,
            feed_air: None,
            rapid: 15000.0,
            control: Control::default(),
            kinematics: None,
            axes: Axes::default(),
            modal: None,
            post: PostSettings::default(),
        }
    }
}

/// `Err` naming `field` unless `ok`.
fn need(ok: bool, field: &str, message: String) -> Result<(), MachineError> {
    if ok {
        Ok(())
    } else {
        Err(MachineError::invalid(field, message))
    }
}

/// Finite and within `range`; NaN fails every comparison, so it fails too.
fn plausible(v: f64, range: Plausible, field: &str) -> Result<(), MachineError> {
    let (lo, hi, unit) = range;
    need(
        v >= lo && v <= hi,
        field,
        format!("must be from {lo} to {hi} {unit}, got {}", shown(v)),
    )
}

/// A number as written in a message: 1e-300, not three hundred zeros.
fn shown(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-4 || v.abs() >= 1e9) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// A plausibility range of a machine file's number: lowest, highest, unit.
pub type Plausible = (f64, f64, &'static str);

/// The plausibility ranges of a machine file's rates. A number outside its
/// range is no machine's and is refused at its line: a velocity of 1e-300
/// would make every move last forever (an infinite time), a jerk of 1e308 is
/// none. Feeds and speeds share the limit of a program's (`NC_RATE`).
pub mod ranges {
    use super::Plausible;
    use millplan_geom::limits::NC_RATE;
    /// `feed.min`, `feed.max`, `feed.rapid`.
    pub const FEED: Plausible = (0.001, NC_RATE, "mm/min");
    /// `spindle.max` (the lowest speed may be 0).
    pub const SPINDLE: Plausible = (1.0, NC_RATE, "1/min");
    /// `spindle.accel`.
    pub const SPINDLE_ACCEL: Plausible = (1.0, 1e7, "1/min per second");
    /// A linear axis's velocity, acceleration and jerk.
    pub const LINEAR: [Plausible; 3] = [
        (1.0, NC_RATE, "mm/min"),
        (1.0, 1e7, "mm/s²"),
        (1.0, 1e12, "mm/s³"),
    ];
    /// A rotary axis's velocity, acceleration and jerk.
    pub const ROTARY: [Plausible; 3] = [
        (1.0, NC_RATE, "degrees/min"),
        (1.0, 1e8, "degrees/s²"),
        (1.0, 1e13, "degrees/s³"),
    ];
    /// A structural mode's natural frequency (as `lobes`).
    pub const FREQUENCY: Plausible = (1.0, 1e5, "Hz");
    /// A structural mode's stiffness (as `lobes`).
    pub const STIFFNESS: Plausible = (1.0, 1e15, "N/m");
}

/// An axis's velocity, acceleration and jerk, each where given, in `ranges`.
fn check_rates(
    vaj: [Option<f64>; 3],
    ranges: [Plausible; 3],
    f: impl Fn(&str) -> String,
) -> Result<(), MachineError> {
    let ends = ["velocity", "accel", "jerk"];
    for ((v, range), end) in vaj.into_iter().zip(ranges).zip(ends) {
        if let Some(v) = v {
            plausible(v, range, &f(end))?;
        }
    }
    Ok(())
}

fn check_linear(a: &LinearAxis, name: char) -> Result<(), MachineError> {
    let f = |end: &str| format!("axes.{}.{end}", name.to_ascii_lowercase());
    for (end, v) in [("min", a.min), ("max", a.max)] {
        if let Some(v) = v {
            let far = millplan_geom::limits::NC_EXTENT;
            need(
                v.abs() <= far,
                &f(end),
                format!("must be a position within ±{far} mm, got {v}"),
            )?;
        }
    }
    if let (Some(lo), Some(hi)) = (a.min, a.max) {
        need(
            lo < hi,
            &f("max"),
            format!("must be above min ({hi} ≤ {lo})"),
        )?;
    }
    check_rates([a.velocity, a.accel, a.jerk], ranges::LINEAR, f)?;
    Ok(())
}

fn check_planner(p: &Planner) -> Result<(), MachineError> {
    let share = |v: f64, f: &str| {
        need(
            v.is_finite() && v > 0.0 && v <= 1.0,
            f,
            format!("must be a share above 0 and at most 1, got {v}"),
        )
    };
    share(p.blend_accel_scale, "control.blend_accel_scale")?;
    share(p.arc_tangential_share, "control.arc_tangential_share")?;
    for (v, f) in [
        (p.lookahead, "control.lookahead"),
        (p.plain_lookahead, "control.plain_lookahead"),
    ] {
        need(
            v <= 1_000_000,
            f,
            format!("must be at most 1000000 blocks, got {v}"),
        )?;
    }
    if let Some(j) = p.jerk {
        plausible(j, ranges::LINEAR[2], "control.jerk")?;
    }
    if let Some(a) = p.path_accel {
        plausible(a, ranges::LINEAR[1], "control.path_accel")?;
    }
    need(
        p.block_time_s.is_finite() && (0.0..=1.0).contains(&p.block_time_s),
        "control.block_time",
        format!("must be a time from 0 to 1 s, got {}", p.block_time_s),
    )?;
    plausible(p.blend_mm, (1e-6, 1000.0, "mm"), "control.blend_mm")
}

impl Machine {
    /// Reads a machine file in any of its layouts and validates it.
    pub fn from_toml(text: &str) -> Result<Machine, MachineError> {
        file::read(text).map(|(m, _)| m)
    }

    /// Reads a machine file, telling which layout it was written in (so that
    /// a command can suggest rewriting an old one with [`Machine::to_toml`]).
    pub fn read(text: &str) -> Result<(Machine, Layout), MachineError> {
        file::read(text)
    }

    /// The description in the machine-file layout: what an old file should
    /// be rewritten as. Reads back equal.
    pub fn to_toml(&self) -> Result<String, MachineError> {
        self.validate()?;
        file::write(self)
    }

    /// Every number finite and in its range; the field at fault is named as
    /// the machine file spells it (`spindle.max`, `axes.x.accel`, ...).
    pub fn validate(&self) -> Result<(), MachineError> {
        let ps = &self.post;
        need(
            ps.pole_cone.is_finite() && (0.0..=30.0).contains(&ps.pole_cone),
            "post.pole_cone",
            format!(
                "must be an angle from 0 to 30 degrees, got {}",
                ps.pole_cone
            ),
        )?;
        need(
            ps.pole_tol.is_finite() && (0.0..=180.0).contains(&ps.pole_tol),
            "post.pole_tol",
            format!(
                "must be an angle from 0 to 180 degrees, got {}",
                ps.pole_tol
            ),
        )?;
        need(
            ps.clearance.is_finite() && ps.clearance > 0.0 && ps.clearance <= 10_000.0,
            "post.clearance",
            format!(
                "must be a length above 0 and at most 10000 mm, got {}",
                ps.clearance
            ),
        )?;
        let (n0, n1) = (self.spindle_min, self.spindle_max);
        need(
            n0.is_finite() && n0 >= 0.0,
            "spindle.min",
            format!("must be a finite speed ≥ 0 (1/min), got {n0}"),
        )?;
        plausible(n1, ranges::SPINDLE, "spindle.max")?;
        need(
            n1 > n0,
            "spindle.max",
            format!("must be finite and above the lowest speed, {n0} (1/min), got {n1}"),
        )?;
        plausible(self.spindle_accel, ranges::SPINDLE_ACCEL, "spindle.accel")?;
        if let Some(c) = &self.spindle_curve {
            let (lo, hi) = c.range();
            need(
                lo <= n0 && hi >= n1,
                "spindle.curve",
                format!(
                    "covers {lo}..{hi} 1/min, but the spindle runs {n0}..{n1}: \
                     every speed the planner may choose needs a limit"
                ),
            )?;
        }
        let (f0, f1) = (self.feed_min, self.feed_max);
        plausible(f0, ranges::FEED, "feed.min")?;
        plausible(f1, ranges::FEED, "feed.max")?;
        need(
            f1 > f0,
            "feed.max",
            format!("must be finite and above the lowest feed, {f0} (mm/min), got {f1}"),
        )?;
        plausible(self.rapid, ranges::FEED, "feed.rapid")?;
        if let Some(v) = self.feed_air {
            need(
                v.is_finite() && v >= f0 && v <= f1,
                "feed.air",
                format!(
                    "must be a feed from the lowest, {f0}, to the highest, {f1} (mm/min), got {v}"
                ),
            )?;
        }
        if let Some(d) = self.control.spindle_decimals {
            // The writers print at most 6 (and would silently cap more).
            need(
                d <= 6,
                "control.spindle_decimals",
                format!("must be 0 to 6, got {d}"),
            )?;
        }
        check_planner(&self.control.planner)?;
        if let Some(k) = &self.kinematics {
            k.check()
                .map_err(|e| MachineError::invalid(format!("kinematics.{}", e.field), e.message))?;
        }
        for (a, name) in [
            (&self.axes.x, 'X'),
            (&self.axes.y, 'Y'),
            (&self.axes.z, 'Z'),
        ] {
            check_linear(a, name)?;
        }
        let drives = [self.axes.first, self.axes.second];
        match &self.kinematics {
            Some(k) => {
                for (d, name) in drives.iter().zip(k.kind.rotary_names()) {
                    let f = |end: &str| format!("axes.{}.{end}", name.to_ascii_lowercase());
                    check_rates([d.velocity, d.accel, d.jerk], ranges::ROTARY, f)?;
                }
            }
            None => need(
                drives.iter().all(RotaryDrive::is_empty),
                "axes",
                "rotary drive data needs [kinematics] to say which axes there are".into(),
            )?,
        }
        if let Some(m) = &self.modal {
            for (dir, modes) in [("x", &m.x), ("y", &m.y)] {
                need(
                    !modes.is_empty(),
                    &format!("modal.{dir}"),
                    "needs at least one mode".into(),
                )?;
                for (i, mode) in modes.iter().enumerate() {
                    let f = |v: &str| format!("modal.{dir}[{i}].{v}");
                    plausible(mode.frequency, ranges::FREQUENCY, &f("frequency"))?;
                    let z = mode.damping;
                    need(
                        z > 0.0 && z < 1.0,
                        &f("damping"),
                        format!("must be a ratio between 0 and 1 (a structural mode is underdamped), got {z}"),
                    )?;
                    plausible(mode.stiffness, ranges::STIFFNESS, &f("stiffness"))?;
                }
            }
        }
        Ok(())
    }

    /// The dialect the machine's control reads, when the file names it.
    pub fn target(&self) -> Option<Target> {
        self.control.dialect
    }

    /// The machine's kinematics, when it has rotary axes the file describes.
    pub fn kinematics(&self) -> Option<&Kinematics> {
        self.kinematics.as_ref()
    }

    /// Power and torque the spindle delivers at `speed` (1/min), when the
    /// file gives its chart.
    pub fn spindle_limit(&self, speed: f64) -> Option<SpindleLimit> {
        self.spindle_curve.as_ref().map(|c| c.limit(speed))
    }

    /// Writer settings for `target` with what the control dictates (the
    /// decimals of S words).
    pub fn write_options(&self, target: Target) -> WriteOptions {
        WriteOptions {
            spindle_decimals: self.control.spindle_decimals,
            g93_seconds: self.control.g93_f == InverseTimeF::Seconds,
            g93_rapids: self.control.g93_rapids,
            ..WriteOptions::new(target)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) {
        assert!((a - b).abs() <= 1e-9 * b.abs().max(1.0), "{a} vs {b}");
    }

    fn pt(speed: f64, power: Option<f64>, torque: Option<f64>) -> CurvePoint {
        CurvePoint {
            speed,
            power,
            torque,
        }
    }

    #[test]
    fn curve_interpolates_power_and_torque_through_p_equals_t_omega() {
        // Constant torque to the base speed, then constant power: the usual
        // motor-spindle chart.
        let c = SpindleCurve::new(vec![
            pt(0.0, None, Some(100.0)),
            pt(1000.0, None, Some(100.0)),
            pt(4000.0, Some(10.0), None),
        ])
        .expect("valid");
        // Below the base speed: full torque, power T·ω (linear in speed, so
        // the interpolated power is exact there).
        let l = c.limit(500.0);
        close(l.torque, 100.0);
        close(l.power, 100.0 * omega(500.0) / 1000.0);
        close(l.power, 5.235987755982989);
        // At standstill: torque, no power.
        let l = c.limit(0.0);
        assert_eq!((l.power, l.torque), (0.0, 100.0));
        // Between 1000 (10.472 kW, 100 N·m) and 4000 (10 kW, 23.873 N·m) at
        // 2500: power 10.236 kW interpolated; torque interpolated to 61.937,
        // but P/ω = 39.0986 N·m is all the power allows.
        let l = c.limit(2500.0);
        let p = 10.0 + (100.0 * omega(1000.0) / 1000.0 - 10.0) * 0.5;
        close(l.power, p);
        close(l.torque, p * 1000.0 / omega(2500.0));
        close(l.torque, 39.09859317102744);
        // Outside the chart the end values hold.
        assert_eq!(c.limit(9000.0), c.limit(4000.0));
        close(c.limit(4000.0).power, 10.0);
        close(c.limit(4000.0).torque, 10_000.0 / omega(4000.0));
        assert_eq!(c.limit(-5.0), c.limit(0.0));
    }

    #[test]
    fn curve_point_with_both_values_keeps_the_tighter() {
        // 100 N·m at 1000 1/min would be 10.47 kW; the chart says 8 kW.
        let c = SpindleCurve::new(vec![
            pt(1000.0, Some(8.0), Some(100.0)),
            pt(2000.0, Some(8.0), Some(100.0)),
        ])
        .expect("valid");
        let l = c.limit(1000.0);
        close(l.power, 8.0);
        close(l.torque, 8000.0 / omega(1000.0));
        // At 2000 the torque is the tighter bound on power only if T·ω < P:
        // 100 N·m·209.4 rad/s = 20.9 kW > 8 kW, so power still rules.
        close(c.limit(2000.0).power, 8.0);
    }

    #[test]
    fn curve_rejects_bad_points() {
        let field = |pts: Vec<CurvePoint>| {
            SpindleCurve::new(pts)
                .expect_err("invalid")
                .field
                .unwrap_or_default()
        };
        assert_eq!(field(vec![pt(0.0, None, Some(1.0))]), "spindle.curve");
        assert_eq!(
            field(vec![pt(0.0, None, Some(1.0)), pt(0.0, None, Some(1.0))]),
            "spindle.curve[1].speed"
        );
        assert_eq!(
            field(vec![
                pt(f64::NAN, None, Some(1.0)),
                pt(1.0, None, Some(1.0))
            ]),
            "spindle.curve[0].speed"
        );
        assert_eq!(
            field(vec![pt(0.0, None, Some(1.0)), pt(1.0, Some(-2.0), None)]),
            "spindle.curve[1].power"
        );
        assert_eq!(
            field(vec![
                pt(0.0, None, Some(1.0)),
                pt(1.0, None, Some(f64::INFINITY))
            ]),
            "spindle.curve[1].torque"
        );
        assert_eq!(
            field(vec![pt(0.0, Some(5.0), None), pt(1.0, Some(5.0), None)]),
            "spindle.curve[0].torque"
        );
        assert_eq!(
            field(vec![pt(0.0, None, Some(1.0)), pt(1.0, None, None)]),
            "spindle.curve[1]"
        );
    }

    #[test]
    fn curve_must_cover_the_spindle_range() {
        let mut m = Machine {
            spindle_curve: Some(
                SpindleCurve::new(vec![
                    pt(0.0, None, Some(50.0)),
                    pt(12000.0, Some(15.0), None),
                ])
                .expect("valid"),
            ),
            ..Machine::default()
        };
        let e = m.validate().expect_err("18000 is off the chart");
        assert_eq!(e.field.as_deref(), Some("spindle.curve"));
        m.spindle_max = 12000.0;
        m.validate().expect("covered");
        assert!(m.spindle_limit(6000.0).is_some());
        assert_eq!(Machine::default().spindle_limit(6000.0), None);
    }

    #[test]
    fn inverse_time_f_in_either_unit() {
        // A block of 0.5 s: F120 in 1/min, F0.5 in seconds.
        let t = 0.5 / 60.0;
        close(InverseTimeF::InverseMinutes.word(t), 120.0);
        close(InverseTimeF::Seconds.word(t), 0.5);
        for u in [InverseTimeF::InverseMinutes, InverseTimeF::Seconds] {
            close(u.minutes(u.word(t)), t);
        }
    }

    #[test]
    fn single_mode_receptance() {
        // Spec process-models §3 benchmark: fn 922 Hz, ζ 0.011, k 1.34005e6 N/m.
        let m = Mode {
            frequency: 922.0,
            damping: 0.011,
            stiffness: 1.34005e6,
        };
        // Static: 1/k. At resonance: purely imaginary, −1/(2ζk).
        let (re, im) = m.frf(0.0);
        close(re, 1.0 / 1.34005e6);
        assert_eq!(im, 0.0);
        let (re, im) = m.frf(922.0);
        assert!(re.abs() < 1e-20, "{re}");
        close(im, -1.0 / (2.0 * 0.011 * 1.34005e6));
        // Two modes in X add.
        let modal = Modal {
            x: vec![m, m],
            y: vec![m],
        };
        close(modal.frf_x(500.0).0, 2.0 * modal.frf_y(500.0).0);
        close(modal.frf_x(500.0).1, 2.0 * modal.frf_y(500.0).1);
    }

    #[test]
    fn validate_names_every_bad_number() {
        let bad = |f: &dyn Fn(&mut Machine), field: &str| {
            let mut m = Machine::default();
            f(&mut m);
            let e = m.validate().expect_err(field);
            assert_eq!(e.field.as_deref(), Some(field), "{e}");
        };
        bad(&|m| m.spindle_min = f64::NAN, "spindle.min");
        bad(&|m| m.spindle_min = -1.0, "spindle.min");
        bad(&|m| m.spindle_max = f64::INFINITY, "spindle.max");
        bad(&|m| m.spindle_max = 100.0, "spindle.max");
        bad(&|m| m.spindle_accel = 0.0, "spindle.accel");
        bad(&|m| m.spindle_accel = f64::NAN, "spindle.accel");
        bad(&|m| m.feed_min = 0.0, "feed.min");
        bad(&|m| m.feed_max = f64::INFINITY, "feed.max");
        bad(&|m| m.feed_max = 0.5, "feed.max");
        bad(&|m| m.rapid = -15000.0, "feed.rapid");
        bad(&|m| m.feed_air = Some(f64::NAN), "feed.air");
        bad(&|m| m.feed_air = Some(30000.0), "feed.air");
        bad(&|m| m.feed_air = Some(0.5), "feed.air");
        bad(
            &|m| m.control.spindle_decimals = Some(7),
            "control.spindle_decimals",
        );
        bad(&|m| m.axes.x.min = Some(f64::NEG_INFINITY), "axes.x.min");
        bad(
            &|m| {
                m.axes.y.min = Some(10.0);
                m.axes.y.max = Some(10.0);
            },
            "axes.y.max",
        );
        bad(&|m| m.axes.z.velocity = Some(f64::NAN), "axes.z.velocity");
        bad(&|m| m.axes.z.accel = Some(-1.0), "axes.z.accel");
        bad(&|m| m.axes.x.jerk = Some(0.0), "axes.x.jerk");
        bad(&|m| m.axes.first.velocity = Some(100.0), "axes");
        let five_axis = |m: &mut Machine| {
            m.kinematics = Some(Kinematics::new(
                millplan_models::kinematics::KinKind::TableAb,
            ))
        };
        bad(
            &|m| {
                five_axis(m);
                m.axes.second.accel = Some(0.0);
            },
            "axes.b.accel",
        );
        bad(
            &|m| {
                five_axis(m);
                m.axes.first.jerk = Some(f64::NAN);
            },
            "axes.a.jerk",
        );
        bad(
            &|m| {
                five_axis(m);
                if let Some(k) = &mut m.kinematics {
                    k.first.max = Some(f64::NAN);
                }
            },
            "kinematics.first.max",
        );
        let mode = Mode {
            frequency: 900.0,
            damping: 0.02,
            stiffness: 2e7,
        };
        let modal = |x: Vec<Mode>| Modal { x, y: vec![mode] };
        bad(&|m| m.modal = Some(modal(vec![])), "modal.x");
        bad(
            &|m| {
                m.modal = Some(modal(vec![
                    mode,
                    Mode {
                        damping: 1.0,
                        ..mode
                    },
                ]))
            },
            "modal.x[1].damping",
        );
        bad(
            &|m| {
                m.modal = Some(modal(vec![Mode {
                    frequency: f64::NAN,
                    ..mode
                }]))
            },
            "modal.x[0].frequency",
        );
        bad(
            &|m| {
                m.modal = Some(modal(vec![Mode {
                    stiffness: 0.0,
                    ..mode
                }]))
            },
            "modal.x[0].stiffness",
        );
        Machine::default().validate().expect("default is valid");
    }

    /// `speed --json` prints the machine: an old file's machine as before.
    #[test]
    fn json_summary_keeps_the_old_keys() {
        let m = Machine::from_toml(
            "name = \"VMC\"\nspindle_min = 1000\nspindle_max = 12000\nspindle_accel = 4000\nfeed_max = 8000\ndialect = \"sinumerik\"\n",
        )
        .expect("valid");
        assert_eq!(
            serde_json::to_value(&m).expect("json"),
            serde_json::json!({
                "name": "VMC", "spindle_min": 1000.0, "spindle_max": 12000.0,
                "spindle_accel": 4000.0, "feed_min": 1.0, "feed_max": 8000.0,
                "rapid": 15000.0, "dialect": "sinumerik",
            })
        );
        let mut m = Machine::default();
        m.control.g93_f = InverseTimeF::Seconds;
        m.axes.z.accel = Some(3000.0);
        let j = serde_json::to_value(&m).expect("json");
        assert_eq!(j["dialect"], serde_json::Value::Null);
        assert_eq!(j["g93_f"], "seconds");
        assert_eq!(j["axes"]["z"]["accel"], 3000.0);
        assert!(j.get("g93_rapids").is_none() && j.get("modal").is_none());
    }

    #[test]
    fn write_options_carry_the_spindle_decimals() {
        let mut m = Machine::default();
        assert_eq!(m.write_options(Target::Fanuc).spindle_decimals(), 0);
        assert_eq!(m.write_options(Target::Sinumerik).spindle_decimals(), 1);
        m.control.spindle_decimals = Some(2);
        let o = m.write_options(Target::Fanuc);
        assert_eq!((o.target, o.spindle_decimals()), (Target::Fanuc, 2));
    }
}
