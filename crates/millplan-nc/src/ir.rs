//! The toolpath IR: one representation for every NC program millplan reads or writes.
//!
//! A [`Program`] is a sequence of [`Operation`]s; an operation has one tool, a frame
//! and a list of [`Move`]s. Everything that is not a move (comments, coolant,
//! spindle direction, cutter compensation, cycles, unknown post words) is an
//! [`Event`] anchored before the move it precedes, so nothing a user wrote is lost.
//!
//! Moves are small plain values (56 bytes) so a million-point finishing path fits in
//! memory comfortably; arcs and tool orientations live in per-operation side tables
//! and moves refer to them by index.
//!
//! Units inside: millimetres, mm/min, 1/min, radians. Readers convert inch files.

use millplan_geom::{Aabb, DVec3, Frame};

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

/// Source format and dialect, as detected from the content.
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
}

impl Dialect {
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
        }
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
        } else if (2.0 * r - d).abs() <= eps && e.abs() <= eps {
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

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
#[repr(u8)]
pub enum MoveKind {
    Rapid,
    Linear,
    /// A circular (or helical) arc; `Move::aux` indexes `Operation::arcs`.
    Arc,
    /// A hole position of the active canned cycle; `Move::aux` indexes `Operation::cycles`.
    Cycle,
}

/// Index meaning "no orientation": a 3-axis move with the operation's fixed axis.
pub const NO_ORIENT: u32 = u32::MAX;

/// One motion, from the previous position to `end`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    /// Tool-tip position at the end of the move, mm, in the operation's frame.
    pub end: DVec3,
    /// Feed in the unit its `feed_mode` says; 0 on rapids.
    pub feed: f64,
    /// Spindle speed in 1/min while the move runs (0 = stopped).
    pub spindle: f64,
    /// 1-based source line; 0 for generated moves.
    pub line: u32,
    /// Index into `Operation::orients`, or [`NO_ORIENT`].
    pub orient: u32,
    /// Index into `Operation::arcs` (arcs) or `Operation::cycles` (cycle points).
    pub aux: u32,
    pub kind: MoveKind,
    pub feed_mode: FeedMode,
}

impl Move {
    pub fn rapid(end: DVec3) -> Move {
        Move {
            end,
            feed: 0.0,
            spindle: 0.0,
            line: 0,
            orient: NO_ORIENT,
            aux: 0,
            kind: MoveKind::Rapid,
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
        matches!(self.kind, MoveKind::Linear | MoveKind::Arc)
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
        if radius < 1e-9 {
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

/// Tool orientation of a 5-axis move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Orient {
    /// Unit tool axis from tip up the spindle, in the operation frame.
    Vector(DVec3),
    /// Machine rotary-axis positions in radians as the program wrote them
    /// (G-code A/B/C words); the tool axis needs the machine's kinematics.
    Rotary([Option<f64>; 3]),
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
    /// Peck depth (deep-hole cycles), mm.
    pub peck: Option<f64>,
    /// Dwell at the bottom, seconds.
    pub dwell: Option<f64>,
    /// Source line of the cycle definition.
    pub line: u32,
}

/// Everything in a program that is not a move.
#[derive(Clone, Debug, PartialEq)]
pub enum EventKind {
    /// A comment (`$$`, `( )`, `;`) or `PPRINT` text.
    Comment(String),
    /// Text passed verbatim to the post (`INSERT/`).
    Insert(String),
    Spindle {
        rpm: f64,
        dir: SpindleDir,
    },
    Coolant(Coolant),
    CutCom(CutCom),
    /// Program stop (`STOP`, M0) or optional stop (`OPSTOP`, M1).
    Stop {
        optional: bool,
    },
    /// Dwell, seconds.
    Dwell(f64),
    /// A record the reader keeps but does not interpret: the major word (or
    /// G-code word) and the whole source text.
    Passthrough {
        word: String,
        text: String,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    /// The index of the move this event precedes (`moves.len()` = after the last move).
    pub at: u32,
    /// 1-based source line; 0 for generated events.
    pub line: u32,
    pub kind: EventKind,
}

/// A run of moves with one tool.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Operation {
    pub name: Option<String>,
    pub tool: Option<Tool>,
    /// The frame the coordinates are written in, relative to the part (NX `MSYS`,
    /// SOLIDWORKS `CSYS`); `None` = part coordinates.
    pub frame: Option<Frame>,
    /// Tool-tip position before the first move, when known.
    pub start: Option<DVec3>,
    pub moves: Vec<Move>,
    pub arcs: Vec<Arc>,
    pub cycles: Vec<Cycle>,
    pub orients: Vec<Orient>,
    /// Sorted by `at`.
    pub events: Vec<Event>,
}

impl Operation {
    /// Tool axis of a move, when it carries a vector.
    pub fn axis(&self, m: &Move) -> Option<DVec3> {
        match self.orients.get(m.orient as usize) {
            Some(Orient::Vector(v)) => Some(*v),
            _ => None,
        }
    }

    pub fn orient(&self, m: &Move) -> Option<&Orient> {
        self.orients.get(m.orient as usize)
    }

    /// Adds an orientation, reusing the previous index when it is the same.
    pub fn intern_orient(&mut self, o: Orient) -> u32 {
        if self.orients.last() == Some(&o) {
            return (self.orients.len() - 1) as u32;
        }
        self.orients.push(o);
        (self.orients.len() - 1) as u32
    }

    /// Start position of move `i`.
    pub fn move_start(&self, i: usize) -> Option<DVec3> {
        if i == 0 {
            self.start
        } else {
            Some(self.moves[i - 1].end)
        }
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
}

/// A whole NC program.
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    pub name: Option<String>,
    pub dialect: Dialect,
    pub units: Units,
    pub operations: Vec<Operation>,
}

impl Program {
    pub fn new(dialect: Dialect) -> Program {
        Program {
            name: None,
            dialect,
            units: Units::default(),
            operations: Vec::new(),
        }
    }

    pub fn moves(&self) -> impl Iterator<Item = &Move> {
        self.operations.iter().flat_map(|o| o.moves.iter())
    }

    pub fn move_count(&self) -> usize {
        self.operations.iter().map(|o| o.moves.len()).sum()
    }

    /// Bounding box of all move end points (arcs included through sampled points),
    /// in the operations' own frames.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for op in &self.operations {
            for (i, m) in op.moves.iter().enumerate() {
                b.extend(m.end);
                if m.kind == MoveKind::Arc {
                    if let (Some(s), Some(a)) = (op.move_start(i), op.arcs.get(m.aux as usize)) {
                        for k in 1..16 {
                            b.extend(a.point_at(s, m.end, k as f64 / 16.0));
                        }
                    }
                }
            }
        }
        b
    }
}
