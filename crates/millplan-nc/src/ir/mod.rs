//! The toolpath IR: one representation for every NC program millplan reads or writes.
//!
//! A [`Program`] is a sequence of [`Operation`]s; an operation has one tool, a frame
//! and a list of [`Move`]s. Everything that is not a move (comments, coolant,
//! spindle direction, cutter and tool-length compensation, work offsets, stops,
//! post words) is an [`Event`] anchored before the move it precedes, so nothing a
//! user wrote is lost.
//!
//! Moves are small plain values (64 bytes) so a million-point finishing path fits
//! in memory comfortably. Arcs, canned cycles and tool orientations live in
//! per-operation side tables and moves name them by typed ids ([`ArcId`],
//! [`CycleId`], [`OrientId`]). Analyses keep their results beside the program,
//! per move in program order (a move's index counted over the operations).
//!
//! **Unknown is not zero.** A program does not know where the tool starts, nor
//! where a reference-point return, a machine-coordinate move or a tool change
//! leaves it. Until a program commands an axis, its coordinate is unknown and the
//! IR stores NaN there: [`Move::known`] says which axes are known, lengths and
//! bounds leave the unknown out, and writers never write an unknown axis.
//!
//! Units inside: millimetres, mm/min, 1/min, radians. Readers convert inch files.

use millplan_geom::{Aabb, DVec3, Frame};
use std::num::NonZeroU32;

/// Length unit of a source or target file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LengthUnit {
    Mm,
    Inch,
}

impl LengthUnit {
    /// Millimetres per unit.
    pub fn mm(self) -> f64 {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::Inch => millplan_geom::tol::MM_PER_INCH,
        }
    }
}

/// How the unit of a source file was established.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum UnitsOrigin {
    /// A unit statement (`UNITS/MM`, `G21`, `G710`, `BEGIN PGM .. MM`).
    Declared,
    /// From a feed word (`MMPM`, `IPM`).
    InferredFromFeed,
    /// Nothing in the file says; millimetres were assumed.
    Assumed,
    /// Given by the user on the command line.
    Override,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Units {
    /// The unit the source file was written in (values in the IR are always mm).
    pub source: LengthUnit,
    pub origin: UnitsOrigin,
}

impl Default for Units {
    fn default() -> Self {
        Units {
            source: LengthUnit::Mm,
            origin: UnitsOrigin::Assumed,
        }
    }
}

/// Where a program came from: the format and dialect of its source, as detected
/// from the content. Where a program goes is a writer's `Target`, not this.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Dialect {
    /// Generic ISO 4343 APT/CLDATA.
    AptIso,
    /// CATIA V5 aptsource.
    AptCatia,
    /// Siemens NX CLSF.
    AptNx,
    /// SOLIDWORKS CAM (CAMWorks) APT.
    AptSolidworks,
    /// ISO 6983 / Fanuc-style G-code (Haas, Mori Seiki, Röders...).
    Fanuc,
    /// Siemens Sinumerik 840D.
    Sinumerik,
    /// LinuxCNC / RS274NGC.
    LinuxCnc,
    /// Heidenhain plain language (Klartext).
    Heidenhain,
    /// Made by millplan (a generator or a pass), not read from a file.
    Generated,
    /// A KUKA KRL robot program (read by `krl`, not by the NC front ends;
    /// not in [`Dialect::ALL`]).
    Krl,
}

impl Dialect {
    pub const ALL: [Dialect; 9] = [
        Dialect::AptIso,
        Dialect::AptCatia,
        Dialect::AptNx,
        Dialect::AptSolidworks,
        Dialect::Fanuc,
        Dialect::Sinumerik,
        Dialect::LinuxCnc,
        Dialect::Heidenhain,
        Dialect::Generated,
    ];

    pub fn is_apt(self) -> bool {
        matches!(
            self,
            Dialect::AptIso | Dialect::AptCatia | Dialect::AptNx | Dialect::AptSolidworks
        )
    }

    pub fn name(self) -> &'static str {
        match self {
            Dialect::AptIso => "iso",
            Dialect::AptCatia => "catia",
            Dialect::AptNx => "nx-clsf",
            Dialect::AptSolidworks => "solidworks-cam",
            Dialect::Fanuc => "fanuc",
            Dialect::Sinumerik => "sinumerik",
            Dialect::LinuxCnc => "linuxcnc",
            Dialect::Heidenhain => "heidenhain",
            Dialect::Generated => "generated",
            Dialect::Krl => "krl",
        }
    }

    pub fn from_name(s: &str) -> Option<Dialect> {
        Dialect::ALL.into_iter().find(|d| d.name() == s)
    }
}

/// The shape class of a cutter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CutterKind {
    Flat,
    Ball,
    /// Torus / bull-nose.
    Bull,
    /// Drill or chamfer point (α > 0).
    Drill,
    /// Anything the seven parameters describe that is none of the above (tapered, …).
    General,
}

/// An axially symmetric cutter by the seven ISO `CUTTER/` parameters, in mm and radians.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Cutter {
    pub kind: CutterKind,
    /// Diameter at the corner.
    pub d: f64,
    /// Corner radius.
    pub r: f64,
    /// Radial distance from the axis to the corner centre.
    pub e: f64,
    /// Axial distance from the tip to the corner centre.
    pub f: f64,
    /// Bottom angle up from the horizontal (radians).
    pub alpha: f64,
    /// Flank angle from the axis (radians).
    pub beta: f64,
    /// Height (flute or gauge length); 0 when unknown.
    pub h: f64,
}

impl Cutter {
    /// The full ISO form; `kind` is classified from the values.
    pub fn from_iso(d: f64, r: f64, e: f64, f: f64, alpha: f64, beta: f64, h: f64) -> Cutter {
        let eps = 1e-6 * d.max(1.0);
        let kind = if alpha > 1e-9 && r <= eps {
            CutterKind::Drill
        } else if beta.abs() > 1e-9 {
            CutterKind::General
        } else if r <= eps {
            CutterKind::Flat
        } else if millplan_geom::tol::is_ball(d, r)
            && e.abs() <= millplan_geom::tol::BALL * d.max(1.0)
        {
            CutterKind::Ball
        } else {
            CutterKind::Bull
        };
        Cutter {
            kind,
            d,
            r,
            e,
            f,
            alpha,
            beta,
            h,
        }
    }

    /// `CUTTER/d` and `CUTTER/d,r` short forms (e and f implied).
    pub fn from_d_r(d: f64, r: f64, h: f64) -> Cutter {
        Cutter::from_iso(d, r, d / 2.0 - r, r, 0.0, 0.0, h)
    }

    pub fn flat(d: f64) -> Cutter {
        Cutter::from_d_r(d, 0.0, 0.0)
    }

    pub fn ball(d: f64) -> Cutter {
        Cutter::from_d_r(d, d / 2.0, 0.0)
    }

    /// Scales all lengths (unit conversion).
    pub fn scaled(self, k: f64) -> Cutter {
        Cutter {
            d: self.d * k,
            r: self.r * k,
            e: self.e * k,
            f: self.f * k,
            h: self.h * k,
            ..self
        }
    }
}

/// A tool as the program names it; geometry is optional (G-code rarely carries it).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Tool {
    pub number: Option<u32>,
    pub name: Option<String>,
    pub cutter: Option<Cutter>,
    /// Source line of the tool definition or call (0 = generated).
    pub line: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SpindleDir {
    /// Clockwise (M3, `CLW`).
    Cw,
    /// Counter-clockwise (M4, `CCLW`).
    Ccw,
    Off,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Coolant {
    Off,
    Flood,
    Mist,
    Through,
    Air,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CutCom {
    Off,
    Left,
    Right,
}

/// How a move's `feed` is to be read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum FeedMode {
    /// mm/min (G94, `MMPM`).
    #[default]
    PerMinute,
    /// mm per spindle revolution (G95, `MMPR`).
    PerRev,
    /// 1/min: the move takes 1/F minutes (G93, `INVERS`).
    InverseTime,
}

macro_rules! entity {
    ($(#[$m:meta])* $name:ident) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $name(u32);

        impl $name {
            /// The id of entry `i` of its side table.
            pub fn new(i: usize) -> $name {
                $name(u32::try_from(i).unwrap_or(u32::MAX))
            }

            pub fn index(self) -> usize {
                self.0 as usize
            }
        }
    };
}

entity!(
    /// An entry of [`Operation::arcs`].
    ArcId
);
entity!(
    /// An entry of [`Operation::cycles`].
    CycleId
);

/// An entry of [`Operation::orients`] (never zero inside, so `Option<OrientId>`
/// costs no more than the id).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct OrientId(NonZeroU32);

impl OrientId {
    pub fn new(i: usize) -> OrientId {
        let v = u32::try_from(i).unwrap_or(u32::MAX - 1).saturating_add(1);
        OrientId(NonZeroU32::new(v).unwrap_or(NonZeroU32::MAX))
    }

    pub fn index(self) -> usize {
        self.0.get() as usize - 1
    }
}

/// What a move does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MoveKind {
    Rapid,
    Linear,
    /// A circular (or helical) arc.
    Arc(ArcId),
    /// A hole position of a canned cycle.
    Cycle(CycleId),
}

impl MoveKind {
    /// The name the text form and reports use.
    pub fn name(self) -> &'static str {
        match self {
            MoveKind::Rapid => "rapid",
            MoveKind::Linear => "linear",
            MoveKind::Arc(_) => "arc",
            MoveKind::Cycle(_) => "cycle",
        }
    }
}

/// Which of X, Y, Z a position knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Axes(pub u8);

impl Axes {
    pub const NONE: Axes = Axes(0);
    pub const XYZ: Axes = Axes(7);

    pub fn of(p: DVec3) -> Axes {
        Axes((!p.x.is_nan()) as u8 | ((!p.y.is_nan()) as u8) << 1 | ((!p.z.is_nan()) as u8) << 2)
    }

    pub fn has(self, k: usize) -> bool {
        self.0 & (1 << k) != 0
    }

    pub fn all(self) -> bool {
        self.0 == 7
    }

    pub fn none(self) -> bool {
        self.0 == 0
    }
}

/// A position whose coordinates are all unknown.
pub const UNKNOWN: DVec3 = DVec3::new(f64::NAN, f64::NAN, f64::NAN);

/// `p` when every coordinate is known.
pub fn known(p: DVec3) -> Option<DVec3> {
    (!p.is_nan()).then_some(p)
}

/// Whether two positions are the same, an unknown coordinate matching only
/// an unknown one.
pub fn same_position(a: DVec3, b: DVec3) -> bool {
    (0..3).all(|k| a[k] == b[k] || (a[k].is_nan() && b[k].is_nan()))
}

/// One motion, from the previous position to `end`.
#[derive(Clone, Copy, Debug)]
pub struct Move {
    /// Tool-tip position at the end of the move, mm, in the operation's frame;
    /// NaN on an axis whose position is unknown (see the module docs).
    pub end: DVec3,
    /// Feed in the unit its `feed_mode` says; 0 on rapids.
    pub feed: f64,
    /// Spindle speed in 1/min while the move runs (0 = stopped). The one place
    /// a speed lives: spindle events carry only the direction.
    pub spindle: f64,
    /// 1-based source line; 0 for generated moves.
    pub line: u32,
    pub kind: MoveKind,
    /// Tool orientation; `None` = the operation's fixed axis (3-axis).
    pub orient: Option<OrientId>,
    pub feed_mode: FeedMode,
}

/// Equal when every field is, an unknown coordinate matching an unknown one.
impl PartialEq for Move {
    fn eq(&self, o: &Move) -> bool {
        same_position(self.end, o.end)
            && self.feed == o.feed
            && self.spindle == o.spindle
            && self.line == o.line
            && self.kind == o.kind
            && self.orient == o.orient
            && self.feed_mode == o.feed_mode
    }
}

impl Move {
    pub fn rapid(end: DVec3) -> Move {
        Move {
            end,
            feed: 0.0,
            spindle: 0.0,
            line: 0,
            kind: MoveKind::Rapid,
            orient: None,
            feed_mode: FeedMode::PerMinute,
        }
    }

    pub fn linear(end: DVec3, feed: f64) -> Move {
        Move {
            kind: MoveKind::Linear,
            feed,
            ..Move::rapid(end)
        }
    }

    /// Cutting moves are the ones made at feed (linear and arc).
    pub fn is_cutting(&self) -> bool {
        matches!(self.kind, MoveKind::Linear | MoveKind::Arc(_))
    }

    pub fn is_rapid(&self) -> bool {
        self.kind == MoveKind::Rapid
    }

    pub fn arc(&self) -> Option<ArcId> {
        match self.kind {
            MoveKind::Arc(a) => Some(a),
            _ => None,
        }
    }

    pub fn cycle(&self) -> Option<CycleId> {
        match self.kind {
            MoveKind::Cycle(c) => Some(c),
            _ => None,
        }
    }

    /// The axes whose end position is known.
    pub fn known(&self) -> Axes {
        Axes::of(self.end)
    }
}

/// A circular arc from the previous position to the move's end, turning
/// counter-clockwise about `normal` (right-hand rule) by `sweep` radians.
/// A helical arc's end differs from its start along `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arc {
    pub centre: DVec3,
    /// Unit axis.
    pub normal: DVec3,
    pub radius: f64,
    /// 0 < sweep ≤ 2π; a full circle has sweep 2π.
    pub sweep: f64,
}

impl Arc {
    /// Builds an arc from its start, end, centre and axis (the direction is the sign of
    /// `normal`); `full` makes coincident start and end a full circle.
    pub fn from_points(
        start: DVec3,
        end: DVec3,
        centre: DVec3,
        normal: DVec3,
        full: bool,
    ) -> Option<Arc> {
        let n = normal.try_normalize()?;
        let a = start - centre;
        let a = a - n * a.dot(n);
        let b = end - centre;
        let b = b - n * b.dot(n);
        let radius = a.length();
        if !(radius >= 1e-9) {
            return None;
        }
        let mut sweep = n.dot(a.cross(b)).atan2(a.dot(b));
        if sweep <= 1e-12 {
            sweep += std::f64::consts::TAU;
        }
        if !full && (sweep - std::f64::consts::TAU).abs() < 1e-9 && (start - end).length() < 1e-9 {
            return None;
        }
        Some(Arc {
            centre,
            normal: n,
            radius,
            sweep,
        })
    }

    /// Point at fraction `t` ∈ [0, 1] of an arc starting at `start` and ending at `end`.
    pub fn point_at(&self, start: DVec3, end: DVec3, t: f64) -> DVec3 {
        let n = self.normal;
        let a = start - self.centre;
        let h0 = a.dot(n);
        let a = a - n * h0;
        let h1 = (end - self.centre).dot(n);
        let ang = self.sweep * t;
        let (s, c) = ang.sin_cos();
        let rot = a * c + n.cross(a) * s + n * n.dot(a) * (1.0 - c);
        self.centre + rot + n * (h0 + (h1 - h0) * t)
    }

    /// Path length from `start` to `end` (including the helical rise).
    pub fn length(&self, start: DVec3, end: DVec3) -> f64 {
        let rise = (end - start).dot(self.normal);
        (self.radius * self.sweep).hypot(rise)
    }
}

/// The tool orientation of a move: what the program wrote, the tool axis, or both.
///
/// A CL file writes the tool axis (`GOTO/x,y,z,i,j,k`); a posted G-code program
/// writes machine rotary-axis positions (`B-30. C45.`), whose tool axis only the
/// machine's kinematics knows. [`Orient::axis`] is set by the reader when the
/// source gives a vector and by the orientation pass of `millplan-plan` when a
/// machine's kinematics turns the angles into one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orient {
    /// Unit tool axis from tip up the spindle, in the operation frame.
    pub axis: Option<DVec3>,
    /// Rotary-axis positions A, B, C in radians as the program wrote them
    /// (`None`: that axis was never commanded).
    pub angles: [Option<f64>; 3],
}

impl Orient {
    pub fn vector(v: DVec3) -> Orient {
        Orient {
            axis: Some(v),
            angles: [None; 3],
        }
    }

    pub fn angles(a: [Option<f64>; 3]) -> Orient {
        Orient {
            axis: None,
            angles: a,
        }
    }

    /// Whether any rotary axis was commanded.
    pub fn has_angles(&self) -> bool {
        self.angles.iter().any(Option::is_some)
    }

    /// Whether the tool is tilted away from +Z (by its axis or any rotary angle).
    pub fn is_tilted(&self) -> bool {
        match self.axis {
            Some(v) => (v.z - 1.0).abs() > 1e-9,
            None => self.angles.iter().flatten().any(|a| a.abs() > 1e-12),
        }
    }
}

/// The tool axis at fraction `t` of a move whose axis turns from `a0` to `a1`
/// (unit vectors): at a constant rate on the great circle between them, the
/// way a controller's tool-centre-point mode interpolates the orientation.
/// Opposite axes have no such circle; the axis then jumps at the middle.
pub fn axis_at(a0: DVec3, a1: DVec3, t: f64) -> DVec3 {
    let c = a0.dot(a1).clamp(-1.0, 1.0);
    if c > 1.0 - 1e-15 {
        return a0;
    }
    let ang = c.acos();
    let s = ang.sin();
    if s < 1e-9 {
        return if t < 0.5 { a0 } else { a1 };
    }
    let w0 = ((1.0 - t) * ang).sin() / s;
    let w1 = (t * ang).sin() / s;
    (a0 * w0 + a1 * w1).normalize()
}

/// A canned cycle's parameters, relative to each cycle point along the tool axis
/// (positive = up the axis from the point).
#[derive(Clone, Debug, PartialEq)]
pub struct Cycle {
    /// What the source called it (`DRILL`, `DEEP2`, `G83` …).
    pub name: String,
    /// Offset of the hole bottom (negative = below the point).
    pub bottom: f64,
    /// Offset of the plane where feeding starts.
    pub clearance: f64,
    /// Offset of the plane the tool returns to after the hole.
    pub retract: f64,
    /// Feed in mm/min.
    pub feed: f64,
    /// Peck depth (deep-hole cycles), mm: the first peck.
    pub peck: Option<f64>,
    /// Depth of the pecks after the first (`None`: the same as the first), mm.
    pub peck_next: Option<f64>,
    /// Dwell at the bottom, seconds.
    pub dwell: Option<f64>,
    /// Source line of the cycle definition.
    pub line: u32,
}

/// Most pecks one hole of a cycle may take: a writer that spells a cycle out
/// refuses more (a peck of `Q0.00001` would otherwise write millions of lines).
pub const MAX_PECKS: usize = 1000;

impl Cycle {
    /// Feed strokes per hole when the cycle is spelled out as moves. A
    /// G-code cycle pecks only as G73 or G83: the Q of another (the shift
    /// of a G76 or G87 boring bar, a Q a G81 ignores) is no peck.
    pub fn pecks(&self) -> usize {
        let total = self.clearance - self.bottom;
        let g = self.name.to_ascii_uppercase();
        let gcode = g.starts_with('G') && g[1..].chars().all(|c| c.is_ascii_digit());
        if gcode && !matches!(g.as_str(), "G73" | "G83") {
            return 1;
        }
        match self.peck {
            Some(q) if q > 0.0 && q < total => {
                let next = self.peck_next.filter(|q| *q > 0.0).unwrap_or(q);
                let n = 1.0 + ((total - q) / next).ceil();
                if n.is_finite() && n < 1e12 {
                    n as usize
                } else {
                    usize::MAX
                }
            }
            _ => 1,
        }
    }
}

/// Tool-length compensation (G43 Hn, G49; Sinumerik `D`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ToolLength {
    Off,
    On { register: Option<u32> },
}

/// A work offset by its ordinal: 1…6 = G54…G59; beyond that the dialect's
/// extended offsets (Fanuc G54.1 Pn = 6 + n, Sinumerik G505… = 5…, LinuxCNC
/// G59.1… = 7…, Heidenhain preset number).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WorkOffset(pub u16);

/// How a verbatim post word matters when the program goes to another dialect.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassClass {
    /// A hint to the CAM system's own display or post that no machine acts on
    /// (NX `PAINT`, SOLIDWORKS `CSI_…`, `TPRINT`): another dialect may keep it as a
    /// comment.
    Info,
    /// It acts on the machine (a cycle, a frame, a reference return, a mode):
    /// another dialect must express it or refuse.
    Machine,
}

/// A record or block part the reader keeps but does not model.
#[derive(Clone, Debug, PartialEq)]
pub struct Passthrough {
    /// The major word or first word (`PAINT`, `G5.1`, `CYCLE800`, `SUPA`).
    pub word: String,
    /// The text as the source wrote it (in its dialect).
    pub text: String,
    pub class: PassClass,
    /// The text changes modal G-code state (distance mode, motion, feed mode,
    /// plane): a writer copying it states its own modes again afterwards.
    pub modal: bool,
    /// The text moves the machine (a reference return, machine coordinates):
    /// a writer copying it no longer knows where the tool is.
    pub moves: bool,
}

/// How the control passes the junctions between blocks: its path-control
/// mode. Modal, except [`PathControl::StopOnce`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathControl {
    /// Exact stop at every block end (Fanuc G61, LinuxCNC G61/G61.1,
    /// Sinumerik G60).
    ExactStop,
    /// Continuous path: corners are blended. `tolerance` (mm) is the
    /// largest deviation from the programmed corner the program allows
    /// (LinuxCNC G64 P, Sinumerik G641 ADIS= or G642 CTOL=, Heidenhain
    /// cycle 32 T); `None`: as the control's own settings allow (G64,
    /// Sinumerik G642 without CTOL, cycle 32 without T).
    Blend { tolerance: Option<f64> },
    /// Exact stop at the end of the next move only (Fanuc G09, Sinumerik G9).
    StopOnce,
    /// A look-ahead or smoothing function of the control on or off.
    Smoothing { kind: Smoothing, on: bool },
    /// Jerk limitation on (Sinumerik SOFT) or off (BRISK).
    Soft(bool),
}

/// The look-ahead and smoothing functions of the controls.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Smoothing {
    /// Fanuc AI contour control (G05.1 Q1 / Q0).
    AiContour,
    /// Fanuc look-ahead control (G08 P1 / P0).
    LookAhead,
    /// Sinumerik high-speed settings (`CYCLE832`): `tolerance` mm, the
    /// contour tolerance it sets (0 when it is switched off).
    HighSpeed { tolerance: f64 },
}

/// Everything in a program that is not a move.
#[derive(Clone, Debug, PartialEq)]
pub enum EventKind {
    /// A comment (`$$`, `( )`, `;`) or `PPRINT` text.
    Comment(String),
    /// Text passed verbatim to the post (`INSERT/`).
    Insert(String),
    /// Spindle start or stop; the speed is on the moves.
    Spindle(SpindleDir),
    Coolant(Coolant),
    /// Cutter radius compensation (G41/G42/G40, `RL`/`RR`/`R0`) with its register.
    CutCom {
        side: CutCom,
        register: Option<u32>,
    },
    ToolLength(ToolLength),
    /// Five-axis tool-centre-point control on or off (G43.4/G43.5, `TRAORI`, M128).
    Tcp(bool),
    WorkOffset(WorkOffset),
    /// A tool made ready for the next tool change (`T9` without M6, `TOOL DEF 9`,
    /// `SELECT/TOOL,9`).
    ToolSelect(u32),
    /// Program stop (`STOP`, M0) or optional stop (`OPSTOP`, M1).
    Stop {
        optional: bool,
    },
    /// Dwell, seconds.
    Dwell(f64),
    /// The path-control mode (exact stop, blending, look-ahead).
    PathControl(PathControl),
    Passthrough(Passthrough),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    /// The index of the move this event precedes (`moves.len()` = after the last move).
    pub at: u32,
    /// 1-based source line; 0 for generated events. Events and a move of the
    /// same source line came from one block.
    pub line: u32,
    pub kind: EventKind,
}

/// A run of moves with one tool.
#[derive(Clone, Debug)]
pub struct Operation {
    pub name: Option<String>,
    pub tool: Option<Tool>,
    /// The frame the coordinates are written in, relative to the part (NX `MSYS`,
    /// SOLIDWORKS `CSYS`); `None` = part coordinates.
    pub frame: Option<Frame>,
    /// Tool-tip position before the first move; NaN where unknown.
    pub start: DVec3,
    pub moves: Vec<Move>,
    pub arcs: Vec<Arc>,
    pub cycles: Vec<Cycle>,
    pub orients: Vec<Orient>,
    /// Sorted by `at`.
    pub events: Vec<Event>,
}

/// Equal when every field is, an unknown coordinate matching an unknown one.
impl PartialEq for Operation {
    fn eq(&self, o: &Operation) -> bool {
        self.name == o.name
            && self.tool == o.tool
            && self.frame == o.frame
            && same_position(self.start, o.start)
            && self.moves == o.moves
            && self.arcs == o.arcs
            && self.cycles == o.cycles
            && self.orients == o.orients
            && self.events == o.events
    }
}

impl Default for Operation {
    fn default() -> Self {
        Operation {
            name: None,
            tool: None,
            frame: None,
            start: UNKNOWN,
            moves: Vec::new(),
            arcs: Vec::new(),
            cycles: Vec::new(),
            orients: Vec::new(),
            events: Vec::new(),
        }
    }
}

impl Operation {
    /// Tool axis of a move, when its orientation has one.
    pub fn axis(&self, m: &Move) -> Option<DVec3> {
        self.orient(m).and_then(|o| o.axis)
    }

    /// The tool axis of a move in part coordinates (the operation's frame
    /// applied): +Z without an orientation, `None` when only machine angles
    /// say where it points.
    pub fn axis_in_part(&self, m: &Move) -> Option<DVec3> {
        let a = match self.orient(m) {
            Some(o) => match o.axis {
                Some(v) => v,
                None if o.is_tilted() => return None,
                None => DVec3::Z,
            },
            None => DVec3::Z,
        };
        Some(self.frame.map_or(a, |f| f.dir_to_parent(a)))
    }

    pub fn orient(&self, m: &Move) -> Option<&Orient> {
        m.orient.and_then(|id| self.orients.get(id.index()))
    }

    pub fn arc(&self, m: &Move) -> Option<&Arc> {
        m.arc().and_then(|id| self.arcs.get(id.index()))
    }

    pub fn cycle(&self, m: &Move) -> Option<&Cycle> {
        m.cycle().and_then(|id| self.cycles.get(id.index()))
    }

    /// Adds an orientation, reusing the previous one when it is the same.
    pub fn intern_orient(&mut self, o: Orient) -> OrientId {
        if self.orients.last() == Some(&o) {
            return OrientId::new(self.orients.len() - 1);
        }
        // A five-axis program has an orientation per move: when the moves
        // have room reserved (a reader's hint), take as much at once rather
        // than grow by copying.
        let room = self.moves.capacity() - self.moves.len();
        if self.orients.len() == self.orients.capacity() && room > self.orients.len() {
            let _ = self.orients.try_reserve_exact(room);
        }
        self.orients.push(o);
        OrientId::new(self.orients.len() - 1)
    }

    pub fn push_arc(&mut self, a: Arc) -> ArcId {
        self.arcs.push(a);
        ArcId::new(self.arcs.len() - 1)
    }

    pub fn push_cycle(&mut self, c: Cycle) -> CycleId {
        self.cycles.push(c);
        CycleId::new(self.cycles.len() - 1)
    }

    /// Start position of move `i`: where the previous move left the tool (after
    /// a canned-cycle hole, the level the cycle returns to); NaN where unknown.
    pub fn move_start(&self, i: usize) -> DVec3 {
        if i == 0 {
            return self.start;
        }
        let p = &self.moves[i - 1];
        match self.cycle(p) {
            Some(c) => p.end + self.axis(p).unwrap_or(DVec3::Z) * c.retract.max(c.clearance),
            None => p.end,
        }
    }

    /// Start position of move `i` when all of it is known.
    pub fn known_start(&self, i: usize) -> Option<DVec3> {
        known(self.move_start(i))
    }

    /// Length of the path of move `i` (arcs along the arc), when its start and end
    /// are known.
    pub fn move_length(&self, i: usize) -> Option<f64> {
        let m = &self.moves[i];
        let s = self.known_start(i)?;
        let e = known(m.end)?;
        Some(match self.arc(m) {
            Some(a) => a.length(s, e),
            None => (e - s).length(),
        })
    }

    /// Events anchored before move `i`.
    pub fn events_before(&self, i: usize) -> &[Event] {
        let lo = self.events.partition_point(|e| (e.at as usize) < i);
        let hi = self.events.partition_point(|e| (e.at as usize) <= i);
        &self.events[lo..hi]
    }

    pub fn push_event(&mut self, line: u32, kind: EventKind) {
        self.events.push(Event {
            at: self.moves.len() as u32,
            line,
            kind,
        });
    }

    /// Whether any move leaves the +Z tool axis.
    pub fn is_five_axis(&self) -> bool {
        self.orients.iter().any(Orient::is_tilted)
    }
}

/// A whole NC program.
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    pub name: Option<String>,
    /// Where the program came from.
    pub source: Dialect,
    pub units: Units,
    pub operations: Vec<Operation>,
    /// The line of the last block of a program read without an end of
    /// program (M30, END PGM, FINI, …): a file that may have been cut short
    /// (the reader's `program-end` warning). `None` when it ends, or when it
    /// was not read from a file.
    pub unterminated: Option<u32>,
}

impl Program {
    pub fn new(source: Dialect) -> Program {
        Program {
            name: None,
            source,
            units: Units::default(),
            operations: Vec::new(),
            unterminated: None,
        }
    }

    pub fn moves(&self) -> impl Iterator<Item = &Move> {
        self.operations.iter().flat_map(|o| o.moves.iter())
    }

    pub fn move_count(&self) -> usize {
        self.operations.iter().map(|o| o.moves.len()).sum()
    }

    /// Bounding box of every known coordinate of the move end points (arcs
    /// included through sampled points), in the operations' own frames. An
    /// axis no move knows stays empty on that axis.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for op in &self.operations {
            for (i, m) in op.moves.iter().enumerate() {
                extend_known(&mut b, m.end);
                if let (Some(a), Some(s), Some(e)) = (op.arc(m), op.known_start(i), known(m.end)) {
                    for k in 1..16 {
                        b.extend(a.point_at(s, e, k as f64 / 16.0));
                    }
                }
                if let (Some(c), Some(e)) = (op.cycle(m), known(m.end)) {
                    let axis = op.axis(m).unwrap_or(DVec3::Z);
                    b.extend(e + axis * c.bottom);
                    b.extend(e + axis * c.retract.max(c.clearance));
                }
            }
        }
        b
    }
}

/// Extends `b` by the known coordinates of `p`, axis by axis.
fn extend_known(b: &mut Aabb, p: DVec3) {
    for k in 0..3 {
        if !p[k].is_nan() {
            b.min[k] = b.min[k].min(p[k]);
            b.max[k] = b.max[k].max(p[k]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_move_is_one_cache_line() {
        assert!(std::mem::size_of::<Move>() <= 64);
        assert_eq!(
            std::mem::size_of::<Option<OrientId>>(),
            std::mem::size_of::<u32>()
        );
    }

    #[test]
    fn ids_round_trip_their_index() {
        for i in [0usize, 1, 7, 1 << 20] {
            assert_eq!(OrientId::new(i).index(), i);
            assert_eq!(ArcId::new(i).index(), i);
        }
    }

    #[test]
    fn unknown_axes_stay_out_of_bounds_and_lengths() {
        let mut op = Operation::default();
        op.moves
            .push(Move::rapid(DVec3::new(f64::NAN, f64::NAN, 20.0)));
        op.moves.push(Move::rapid(DVec3::new(5.0, 6.0, 20.0)));
        op.moves
            .push(Move::linear(DVec3::new(5.0, 6.0, 10.0), 100.0));
        assert_eq!(op.moves[0].known(), Axes(4));
        assert_eq!(op.move_length(0), None);
        assert_eq!(op.move_length(1), None);
        assert_eq!(op.move_length(2), Some(10.0));
        let mut p = Program::new(Dialect::Fanuc);
        p.operations.push(op);
        let b = p.bounds();
        assert_eq!((b.min.x, b.max.x, b.min.z, b.max.z), (5.0, 5.0, 10.0, 20.0));
    }
}
