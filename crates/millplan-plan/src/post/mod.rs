//! The five-axis post-processor (spec kinematics-access-tools §1.7–1.10):
//! CL data with tool axes → machine axes through a machine's kinematics.
//!
//! Per operation:
//! 1. **CL points**: every move's tool tip and unit tool axis in the part
//!    frame (an operation's `MSYS`/`CSYS` frame applied); arcs become chords
//!    within the tolerance, their axis turned by [`axis_at`].
//! 2. **Candidates** ([`ik::candidates`]): both IK branches and every
//!    winding the rotary travel allows; inside the pole cone (§1.8) the
//!    previous point's held (turning) angles are kept and the tilt solved
//!    alone, the orientation deviation recorded.
//! 3. **Dynamic programming** over the operation (§1.7.4): edge cost the
//!    rotary travel in degrees (wrapped for an endless axis), a branch flip
//!    ([`ik::is_flip`]) costs a penalty and is forbidden outright on a
//!    cutting move; a flip on a rapid gets a retract → rotate → approach
//!    inserted at the clearance and is reported. A cut may take the tilt to
//!    its other side only where its tool axis passes the pole (within the
//!    pole cone, [`ik::closest_to_pole`]); elsewhere that is the other
//!    branch too, and forbidden as a flip is.
//! 4. **Linearisation** (§1.7.5, not under TCP, where the control keeps the
//!    tip on the line): between two cutting points the joints move linearly
//!    and the tip bows away from the CL segment; while its sampled distance
//!    exceeds the tolerance the segment is halved, the new CL point's axis
//!    by [`axis_at`] (the IR's interpolation).
//! 5. **Feeds** (§1.9, §1.10): the block time is the tip path relative to
//!    the part over the programmed tip feed (zero-length and rotary-only
//!    blocks: the slowest axis at its top speed, else the feed read as
//!    degrees/min); an axis faster than its top speed slows the block, and
//!    so does the control's block cycle (`[control] block_time`). G93
//!    writes F = 1/time; G94 writes what the control applies to the joint
//!    XYZ distance (TCP: the tip feed itself).
//!
//! The result is a new [`Program`] whose moves are machine positions (X Y Z
//! of the joints and the rotary angles; with TCP, the tool tip and the
//! rotary angles), ready for the G-code writers.

pub mod feed;
pub mod ik;

use crate::machine::{LinearAxis, Machine};
use crate::orient::letters;
use crate::timing::{AxisChains, AxisMove, Limits, MoveKind as AxisKind};
use feed::{
    g94_machine_f, g94_minutes, sampled_deviation, tip_deviation, tip_path_length,
    tip_path_length_from, tip_samples,
};
use ik::{candidates, in_pole, is_flip, roles, wrap180, wrapped, Cand, Roles};
use millplan_geom::DVec3;
use millplan_models::kinematics::{Joints, Kinematics};
use millplan_nc::{
    axis_at, known, write::arc_points, EventKind, FeedMode, Move, MoveKind, Operation, Orient,
    Program, UNKNOWN,
};
use rayon::prelude::*;

/// How to post.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PostOptions {
    /// Largest distance (mm) of the tip path from the CL segment while the
    /// rotaries move, and the chord tolerance of arcs.
    pub tol: f64,
    /// Write tool tips for the control's TCP mode instead of joint positions.
    pub tcp: bool,
    /// Inverse-time feed (G93) instead of G94.
    pub g93: bool,
    /// Half-angle (degrees) of the cone about the pole inside which the
    /// turning axis is held (§1.8).
    pub pole_cone: f64,
    /// Orientation deviation (degrees) beyond which a pole block is flagged.
    pub pole_tol: f64,
    /// Retract distance (mm, along the tool axis) of a branch flip.
    pub clearance: f64,
}

impl Default for PostOptions {
    fn default() -> Self {
        PostOptions {
            tol: 0.01,
            tcp: false,
            g93: false,
            pole_cone: 1.0,
            pole_tol: 1.0,
            clearance: 50.0,
        }
    }
}

/// Cost (degrees of rotary travel) of a branch flip on a rapid.
const FLIP_PENALTY: f64 = 720.0;
/// Deepest halving of one block by linearisation (65,536 pieces; the
/// halving stops where the tip is within the tolerance, so this many only
/// where the turning axis sweeps half a turn while the tip stands nearly
/// still: a cut passing the pole on a table, whose part turns under the
/// tool there).
const MAX_DEPTH: u32 = 16;
/// Margin under the tolerance that the sampled deviation must keep (the
/// samples can miss the true peak by about 2 % of it).
const SAMPLE_MARGIN: f64 = 0.97;

/// A branch change the post made on a rapid, with the retract, rotation
/// and approach it inserted.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Flip {
    /// Source line of the rapid.
    pub line: u32,
    /// Rotary angles (first, second), degrees, before and after.
    pub from: [f64; 2],
    pub to: [f64; 2],
}

/// The travel a rotary axis used against its limits.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct AxisRange {
    pub axis: char,
    /// Degrees; `None` when no block was posted.
    pub min: Option<f64>,
    pub max: Option<f64>,
    pub limit_min: Option<f64>,
    pub limit_max: Option<f64>,
}

/// What the post did.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct PostReport {
    /// Moves of the posted program.
    pub blocks: usize,
    pub flips: Vec<Flip>,
    /// Posted points inside the pole cone (their turning axis held).
    pub pole_blocks: usize,
    /// Source lines of pole blocks whose orientation deviation exceeds the
    /// pole tolerance.
    pub pole_flagged: Vec<u32>,
    pub max_orientation_deviation_deg: f64,
    /// CL points inserted by linearisation.
    pub inserted_points: usize,
    /// Points arcs became.
    pub arc_points: usize,
    /// Moves inserted for flips (retract, rotate, approach).
    pub flip_moves: usize,
    /// Blocks slowed because an axis would exceed its top speed.
    pub slowed_blocks: usize,
    /// Feed moves that move no axis at all, left out (their events kept).
    pub null_moves: usize,
    /// Blocks of a G94 program written in G93 because the F word the
    /// control would need (the joints' XYZ distance over the block time)
    /// falls below the machine's lowest feed: a block that turns the table
    /// far while X, Y and Z hardly move.
    pub g93_blocks: usize,
    /// Largest distance between a posted block's tool tip by forward
    /// kinematics and the CL tip it stands for, mm (a self-check).
    pub max_tip_error_mm: f64,
    /// The block times the posted F words ask for, and rapids at the axes'
    /// top speeds, seconds.
    pub nominal_s: f64,
    /// The same blocks at the programmed tip feed exactly: what G93 asks
    /// for, nominal.
    pub nominal_g93_s: f64,
    /// The same blocks in G94 with the CL feed written as F unconverted (a
    /// plain post): the control applies it to the joints' XYZ distance.
    pub nominal_g94_s: f64,
    /// The controller-aware estimate (axis velocities, accelerations, jerk,
    /// look-ahead: `timing::estimate_axes`) of the posted program, seconds.
    pub time_s: f64,
    /// The same estimate at the exact tip feed (G93) and as a plain G94
    /// post would run.
    pub time_g93_s: f64,
    pub time_g94_s: f64,
    pub rotary: Vec<AxisRange>,
}

/// A posted program and the report.
#[derive(Clone, Debug)]
pub struct Posted {
    pub program: Program,
    pub report: PostReport,
}

#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PostError {
    #[error("the machine file has no [kinematics]: a five-axis post needs the machine's axes")]
    NoKinematics,
    #[error("{line}:1: axis {axis} runs out of range: {wanted:.4} is needed, its travel is {}", range(*min, *max))]
    Unreachable {
        line: u32,
        axis: char,
        wanted: f64,
        min: Option<f64>,
        max: Option<f64>,
    },
    #[error("{line}:1: the rotary limits force a change of IK branch inside the cut ending here; a branch may change only across a rapid")]
    FlipInCut { line: u32 },
    #[error("{line}:1: the tool tip is not known here (X, Y and Z must all be set before a five-axis post)")]
    UnknownPosition { line: u32 },
    #[error("{line}:1: {what}")]
    Unsupported { line: u32, what: String },
    #[error("{0}")]
    Options(String),
}

impl PostError {
    /// Whether the post found a problem with the program on this machine
    /// (exit 3) rather than bad input (exit 2).
    pub fn is_check(&self) -> bool {
        matches!(
            self,
            PostError::Unreachable { .. } | PostError::FlipInCut { .. }
        )
    }

    /// The source line the error is at (0: none).
    pub fn line(&self) -> u32 {
        match self {
            PostError::Unreachable { line, .. }
            | PostError::FlipInCut { line }
            | PostError::UnknownPosition { line }
            | PostError::Unsupported { line, .. } => *line,
            _ => 0,
        }
    }
}

fn range(min: Option<f64>, max: Option<f64>) -> String {
    let f = |v: Option<f64>, inf: &str| v.map_or(inf.to_string(), |v| format!("{v}"));
    format!("{} .. {}", f(min, "-inf"), f(max, "inf"))
}

/// One CL point: tip and unit axis in the part frame.
#[derive(Clone, Copy, Debug)]
struct Cl {
    tip: DVec3,
    k: DVec3,
    line: u32,
    /// The source move it belongs to.
    src: u32,
    rapid: bool,
    /// Tip feed, mm/min (0 on rapids).
    v: f64,
    spindle: f64,
}

/// A posted point: the CL point, its rotary solution and joints.
#[derive(Clone, Copy, Debug)]
struct Pt {
    cl: Cl,
    c: Cand,
    j: Joints,
    /// Inside the pole cone.
    pole: bool,
    /// The tip path length from the point before it, when linearisation
    /// measured it on the way (NaN: not measured).
    len: f64,
}

/// Fits a program posted with TCP to its control. LinuxCNC has no TCP word:
/// its tool-centre-point control is the kinematics module its configuration
/// loads, so the switch becomes a comment saying what the positions are.
/// Fanuc's TCP is `G43.4 H`: an operation without a tool number cannot
/// switch it on, and its tool tips would run as machine positions, so it is
/// refused at its first move.
pub fn for_target(p: &mut Program, target: millplan_nc::write::Target) -> Result<(), PostError> {
    use millplan_nc::write::Target;
    for op in &mut p.operations {
        let tcp = op
            .events
            .iter()
            .any(|e| e.line == 0 && e.kind == EventKind::Tcp(true));
        if !tcp {
            continue;
        }
        match target {
            Target::LinuxCnc => {
                for e in &mut op.events {
                    if e.line == 0 && e.kind == EventKind::Tcp(true) {
                        e.kind = EventKind::Comment(
                            "TOOL TIPS: RUN WITH TCP KINEMATICS (E.G. XYZAC-TRT, XYZBC-TRT)".into(),
                        );
                    }
                }
            }
            Target::Fanuc if op.tool.as_ref().and_then(|t| t.number).is_none() => {
                return Err(PostError::Unsupported {
                    line: op.moves.first().map_or(0, |m| m.line),
                    what: "Fanuc switches TCP on with G43.4 H and a tool number, and this operation has none (post it without --tcp, or give the CL file a LOADTL)".into(),
                });
            }
            _ => {}
        }
    }
    Ok(())
}

/// Posts `p` for `machine` (which must have kinematics).
pub fn post(p: &Program, machine: &Machine, o: &PostOptions) -> Result<Posted, PostError> {
    check_options(o)?;
    let kin = machine.kinematics().ok_or(PostError::NoKinematics)?;
    let mut out = Program {
        operations: Vec::with_capacity(p.operations.len()),
        ..p.clone_header()
    };
    let mut report = PostReport::default();
    let lim = Limits::of(machine);
    let mut times = Times::new(&lim);
    let mut ranges = [[f64::INFINITY, f64::NEG_INFINITY]; 2];
    for op in &p.operations {
        let pts = post_operation(op, kin, machine, o, &mut report)?;
        for q in &pts {
            for (r, v) in ranges.iter_mut().zip([q.c.first, q.c.second]) {
                r[0] = r[0].min(v);
                r[1] = r[1].max(v);
            }
        }
        let new_op = build(op, &pts, kin, machine, o, &mut times, &mut report);
        times.end_operation();
        drop(pts);
        out.operations.push(new_op);
    }
    let names = kin.kind.rotary_names();
    report.rotary = (0..2)
        .map(|i| {
            let lim = if i == 0 { kin.first } else { kin.second };
            let used = ranges[i][0] <= ranges[i][1];
            AxisRange {
                axis: names[i],
                min: used.then_some(ranges[i][0]),
                max: used.then_some(ranges[i][1]),
                limit_min: lim.min,
                limit_max: lim.max,
            }
        })
        .collect();
    report.blocks = out.move_count();
    [report.time_s, report.time_g93_s, report.time_g94_s] = times.totals;
    Ok(Posted {
        program: out,
        report,
    })
}

/// The controller-aware estimates (`timing::AxisChains`: axis velocities,
/// accelerations, jerk, look-ahead) of the posted blocks as written, at
/// the exact tip feed (G93) and as a plain G94 post would run, each
/// operation a chain from its first block's position (the move there comes
/// from an unknown place), timed as `build` makes its blocks.
struct Times<'a> {
    lim: &'a Limits,
    /// The open operation's first block, then its three chains.
    first: Option<[f64; 6]>,
    chains: Option<AxisChains<'a, 3>>,
    /// Seconds, summed over the operations in order.
    totals: [f64; 3],
}

impl<'a> Times<'a> {
    fn new(lim: &'a Limits) -> Times<'a> {
        Times {
            lim,
            first: None,
            chains: None,
            totals: [0.0; 3],
        }
    }

    /// The next block of the open operation as written, and its minutes
    /// at the exact tip feed and in a plain G94 post (ignored on rapids).
    fn push(&mut self, m: AxisMove, exact_min: f64, plain_min: f64) {
        let Some(start) = self.first else {
            self.first = Some(m.target);
            return;
        };
        let own = match m.kind {
            AxisKind::Feed { nominal_min } => nominal_min,
            _ => 0.0,
        };
        let lim = self.lim;
        self.chains
            .get_or_insert_with(|| AxisChains::new(start, lim))
            .push(m, [own, exact_min, plain_min]);
    }

    /// The open operation's chains timed to their end.
    fn end_operation(&mut self) {
        self.first = None;
        if let Some(chains) = self.chains.take() {
            for (t, e) in self.totals.iter_mut().zip(chains.finish()) {
                *t += e.total_s;
            }
        }
    }
}

trait Header {
    fn clone_header(&self) -> Program;
}

impl Header for Program {
    fn clone_header(&self) -> Program {
        Program {
            name: self.name.clone(),
            source: self.source,
            units: self.units,
            operations: Vec::new(),
            unterminated: self.unterminated,
        }
    }
}

fn check_options(o: &PostOptions) -> Result<(), PostError> {
    let bad = |what: &str, v: f64, want: &str| {
        Err(PostError::Options(format!(
            "{what} must be {want}, got {v}"
        )))
    };
    if !(o.tol.is_finite() && o.tol > 0.0 && o.tol <= 10.0) {
        return bad("--tol", o.tol, "a positive length of at most 10 mm");
    }
    if !(o.pole_cone.is_finite() && o.pole_cone >= 0.0 && o.pole_cone <= 30.0) {
        return bad("the pole cone", o.pole_cone, "between 0 and 30 degrees");
    }
    if !(o.pole_tol.is_finite() && o.pole_tol >= 0.0) {
        return bad("the pole tolerance", o.pole_tol, "a finite angle ≥ 0");
    }
    if !(o.clearance.is_finite() && o.clearance > 0.0 && o.clearance <= 10_000.0) {
        return bad("the clearance", o.clearance, "a positive length up to 10 m");
    }
    Ok(())
}

/// The tip feed of a move, mm/min.
fn tip_feed(m: &Move, chord: f64) -> f64 {
    match m.feed_mode {
        FeedMode::PerMinute => m.feed,
        FeedMode::PerRev => m.feed * m.spindle,
        FeedMode::InverseTime => chord * m.feed,
    }
}

/// The CL points of an operation in the part frame.
fn cl_points(op: &Operation, tol: f64, report: &mut PostReport) -> Result<Vec<Cl>, PostError> {
    let frame = op.frame.unwrap_or_default();
    let mut cls = Vec::with_capacity(op.moves.len());
    let mut prev: Option<(DVec3, DVec3)> = None;
    for (i, m) in op.moves.iter().enumerate() {
        if m.cycle().is_some() {
            return Err(PostError::Unsupported {
                line: m.line,
                what: "a canned cycle cannot be posted to five axes (write its holes as moves)"
                    .into(),
            });
        }
        let end = known(m.end).ok_or(PostError::UnknownPosition { line: m.line })?;
        let axis = op
            .axis(m)
            .and_then(|a| a.try_normalize())
            .unwrap_or(DVec3::Z);
        let chord = prev.map_or(0.0, |(s, _)| (end - s).length());
        let v = if m.is_rapid() {
            0.0
        } else {
            tip_feed(m, chord)
        };
        if !(m.is_rapid() || v.is_finite() && v > 0.0) {
            return Err(PostError::Unsupported {
                line: m.line,
                what: "a cutting move without a feed (mm/min) cannot be timed".into(),
            });
        }
        let point = |tip: DVec3, k: DVec3| Cl {
            tip: frame.to_parent(tip),
            k: frame.dir_to_parent(k).normalize(),
            line: m.line,
            src: i as u32,
            rapid: m.is_rapid(),
            v,
            spindle: m.spindle,
        };
        if let (Some(a), Some((s, k0))) = (op.arc(m), prev) {
            let pts = arc_points(a, s, end, tol);
            let n = pts.len();
            report.arc_points += n.saturating_sub(1);
            for (q, at) in pts.into_iter().enumerate() {
                let k = axis_at(k0, axis, (q + 1) as f64 / n as f64);
                cls.push(point(at, k));
            }
        } else if op.arc(m).is_some() {
            return Err(PostError::UnknownPosition { line: m.line });
        } else {
            cls.push(point(end, axis));
        }
        prev = Some((end, axis));
    }
    Ok(cls)
}

/// Rotary distance (degrees) between two solutions, each axis wrapped when
/// it is endless.
#[inline]
fn rot_dist(kin: &Kinematics, a: &Cand, b: &Cand) -> f64 {
    let d = |wr: bool, x: f64, y: f64| {
        if wr {
            wrap180(y - x).abs()
        } else {
            (y - x).abs()
        }
    };
    d(wrapped(&kin.first), a.first, b.first) + d(wrapped(&kin.second), a.second, b.second)
}

fn out_of_range(line: u32, e: ik::OutOfRange) -> PostError {
    PostError::Unreachable {
        line,
        axis: e.axis,
        wanted: e.wanted,
        min: e.min,
        max: e.max,
    }
}

/// Candidates of every CL point, flat; the start of each point's run; and
/// whether the point lies in the pole cone.
type Candidates = (Vec<Cand>, Vec<u32>, Vec<bool>);
/// A chunk's candidates, flat, and their number per point.
type Chunk = (Vec<Cand>, Vec<u32>);

/// Candidates of every CL point, flat, with the start of each point's run.
fn all_candidates(
    cls: &[Cl],
    kin: &Kinematics,
    r: Roles,
    cone: f64,
) -> Result<Candidates, PostError> {
    let pole: Vec<bool> = cls.par_iter().map(|c| in_pole(r, c.k, cone)).collect();
    const CHUNK: usize = 4096;
    // Away from the pole, every point on its own, in parallel.
    let parts: Vec<Result<Chunk, PostError>> = cls
        .par_chunks(CHUNK)
        .zip(pole.par_chunks(CHUNK))
        .map(|(cs, ps)| {
            let mut flat = Vec::with_capacity(cs.len() * 2);
            let mut counts = Vec::with_capacity(cs.len());
            for (c, &p) in cs.iter().zip(ps) {
                let before = flat.len();
                if !p {
                    candidates(kin, r, c.k, None, &mut flat)
                        .map_err(|e| out_of_range(c.line, e))?;
                }
                counts.push((flat.len() - before) as u32);
            }
            Ok((flat, counts))
        })
        .collect();
    // Then in order, the pole points from their predecessor's held angles.
    let mut cands = Vec::with_capacity(cls.len() * 2);
    let mut off = Vec::with_capacity(cls.len() + 1);
    let mut held = Vec::with_capacity(16);
    for (ci, part) in parts.into_iter().enumerate() {
        let (flat, counts) = part?;
        let mut at = 0usize;
        for (k, &n) in counts.iter().enumerate() {
            let i = ci * CHUNK + k;
            off.push(cands.len() as u32);
            if !pole[i] {
                cands.extend_from_slice(&flat[at..at + n as usize]);
                at += n as usize;
                continue;
            }
            held.clear();
            if i == 0 {
                held.push(0.0);
            } else {
                let prev = &cands[off[i - 1] as usize..off[i] as usize];
                for c in prev {
                    let (_, h) = ik::split(r, c.first, c.second);
                    if !held.iter().any(|x: &f64| (x - h).abs() < 1e-9) {
                        held.push(h);
                    }
                }
            }
            candidates(kin, r, cls[i].k, Some(&held), &mut cands)
                .map_err(|e| out_of_range(cls[i].line, e))?;
        }
    }
    off.push(cands.len() as u32);
    Ok((cands, off, pole))
}

/// The DP of §1.7.4: the chosen candidate per point.
fn choose(
    cls: &[Cl],
    cands: &[Cand],
    off: &[u32],
    kin: &Kinematics,
    r: Roles,
    cone: f64,
) -> Result<Vec<Cand>, PostError> {
    let n = cls.len();
    let mut back = vec![0u8; cands.len()];
    let span = |i: usize| off[i] as usize..off[i + 1] as usize;
    // Start: the smallest angles, and the least deviation.
    let mut cost: Vec<f64> = cands[span(0)]
        .iter()
        .map(|c| 1e-3 * (c.first.abs() + c.second.abs()) + 10.0 * c.dev)
        .collect();
    let mut next = Vec::with_capacity(16);
    // Each candidate's side of the pole, the previous point's and this one's.
    let sides = |c: &[Cand], out: &mut Vec<f64>| {
        out.clear();
        out.extend(c.iter().map(|c| ik::side(r, c)));
    };
    let (mut side_a, mut side_b) = (Vec::with_capacity(16), Vec::with_capacity(16));
    sides(&cands[span(0)], &mut side_a);
    for i in 1..n {
        let (prev, cur) = (&cands[span(i - 1)], &cands[span(i)]);
        next.clear();
        let base = off[i] as usize;
        sides(cur, &mut side_b);
        // A cut whose tool axis does not pass the pole cannot take the
        // tilt to its other side: that is the other branch, as a flip is.
        let off_pole = !cls[i].rapid
            && ik::closest_to_pole(r, cls[i - 1].k, cls[i].k) > cone.max(POLE_PASS_DEG);
        for (bi, b) in cur.iter().enumerate() {
            let mut best = f64::INFINITY;
            let mut arg = 0u8;
            for (ai, a) in prev.iter().enumerate() {
                let mut c = cost[ai] + rot_dist(kin, a, b);
                if ik::sides_differ(side_a[ai], side_b[bi]) {
                    if ik::held_turns(r, a, b) {
                        c += if cls[i].rapid {
                            FLIP_PENALTY
                        } else {
                            f64::INFINITY
                        };
                    } else if off_pole {
                        c = f64::INFINITY;
                    }
                }
                if c < best {
                    best = c;
                    arg = ai as u8;
                }
            }
            back[base + bi] = arg;
            next.push(best + 10.0 * b.dev);
        }
        if next.iter().all(|c| c.is_infinite()) {
            return Err(PostError::FlipInCut { line: cls[i].line });
        }
        std::mem::swap(&mut cost, &mut next);
        std::mem::swap(&mut side_a, &mut side_b);
    }
    let mut idx = cost
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .map_or(0, |(i, _)| i);
    let mut chosen = vec![cands[0]; n];
    for i in (0..n).rev() {
        chosen[i] = cands[off[i] as usize + idx];
        idx = back[off[i] as usize + idx] as usize;
    }
    // Endless axes take the representative nearest the previous angle.
    for i in 1..n {
        let p = chosen[i - 1];
        let c = &mut chosen[i];
        if wrapped(&kin.first) {
            c.first = p.first + wrap180(c.first - p.first);
        }
        if wrapped(&kin.second) {
            c.second = p.second + wrap180(c.second - p.second);
        }
    }
    Ok(chosen)
}

/// The pole cone below which a cut is taken to pass the pole whatever the
/// post's own cone (degrees): an axis through the pole, as computed.
const POLE_PASS_DEG: f64 = 1e-4;

/// The solution of `k` nearest the angles `near` (same windings as near as
/// the travel allows), for a point inserted between the two posted ones
/// `ends`: on their side of the pole when they share one (the branch the
/// block runs on), whichever is nearer.
fn nearest(
    kin: &Kinematics,
    r: Roles,
    k: DVec3,
    near: Cand,
    cone: f64,
    ends: (&Cand, &Cand),
) -> Cand {
    // The side the block's ends share, if they do.
    let shared = Some(ik::side(r, ends.0)).filter(|_| !ik::changes_side(r, ends.0, ends.1));
    let sols: Vec<Cand> = if in_pole(r, k, cone) {
        let (_, h) = ik::split(r, near.first, near.second);
        vec![ik::solve_tilt(kin, r, k, h)]
    } else {
        kin.orientation_ik(k, 0.0)
            .into_iter()
            .map(|(f, s)| Cand {
                first: f,
                second: s,
                dev: 0.0,
            })
            .collect()
    };
    sols.into_iter()
        .map(|c| Cand {
            first: near.first + wrap180(c.first - near.first),
            second: near.second + wrap180(c.second - near.second),
            dev: c.dev,
        })
        .min_by(|a, b| {
            // Off the block's side last, then by distance.
            let away = |c: &Cand| shared.is_some_and(|s| ik::sides_differ(s, ik::side(r, c)));
            let d = |c: &Cand| (c.first - near.first).abs() + (c.second - near.second).abs();
            (away(a), d(a))
                .partial_cmp(&(away(b), d(b)))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .unwrap_or(near)
}

fn joints(kin: &Kinematics, tip: DVec3, c: &Cand) -> Joints {
    Joints {
        xyz: kin.position_ik(tip, c.first, c.second),
        first: c.first,
        second: c.second,
    }
}

/// Linearises the cutting block `a`–`b`, pushing the points inserted in
/// order: the block's tip path length when it needs none (measured from
/// the tips its test sampled), else NaN.
fn linearise(
    kin: &Kinematics,
    r: Roles,
    a: &Pt,
    b: &Pt,
    o: &PostOptions,
    out: &mut Vec<Pt>,
) -> f64 {
    let s = tip_samples(kin, &a.j, &b.j);
    if sampled_deviation(s.as_ref(), a.cl.tip, b.cl.tip) <= SAMPLE_MARGIN * o.tol {
        return tip_path_length_from(kin, &a.j, &b.j, s.as_ref());
    }
    halve(kin, r, a, b, o, 0, out);
    f64::NAN
}

/// Halves the block `a`–`b` while the tip strays more than `tol` from the
/// CL segment, pushing the points inserted in order.
fn refine(
    kin: &Kinematics,
    r: Roles,
    a: &Pt,
    b: &Pt,
    o: &PostOptions,
    depth: u32,
    out: &mut Vec<Pt>,
) {
    if depth >= MAX_DEPTH
        || tip_deviation(kin, &a.j, &b.j, a.cl.tip, b.cl.tip) <= SAMPLE_MARGIN * o.tol
    {
        return;
    }
    halve(kin, r, a, b, o, depth, out);
}

/// [`refine`] of the two halves of a block that strays.
fn halve(
    kin: &Kinematics,
    r: Roles,
    a: &Pt,
    b: &Pt,
    o: &PostOptions,
    depth: u32,
    out: &mut Vec<Pt>,
) {
    let tip = (a.cl.tip + b.cl.tip) * 0.5;
    let k = axis_at(a.cl.k, b.cl.k, 0.5);
    let mid = Cand {
        first: 0.5 * (a.c.first + b.c.first),
        second: 0.5 * (a.c.second + b.c.second),
        dev: 0.0,
    };
    // Inside the pole cone the turning axis is held. A point inserted
    // where the block enters (or leaves) the cone holds the angle of its
    // end outside, the exact one there: the mean of the two ends would
    // leave a jump in the turning axis at the cone's edge that no halving
    // removes (on a table, the part turns under the tool there), and the
    // tip between them would stray by the chord of that turn.
    let pole = in_pole(r, k, o.pole_cone);
    let near = match (pole, a.pole, b.pole) {
        (true, false, true) => a.c,
        (true, true, false) => b.c,
        _ => mid,
    };
    let c = nearest(kin, r, k, near, o.pole_cone, (&a.c, &b.c));
    let m = Pt {
        cl: Cl { tip, k, ..b.cl },
        c,
        j: joints(kin, tip, &c),
        pole,
        len: f64::NAN,
    };
    refine(kin, r, a, &m, o, depth + 1, out);
    out.push(m);
    refine(kin, r, &m, b, o, depth + 1, out);
}

/// The posted points of one operation: DP choice, flips, linearisation.
fn post_operation(
    op: &Operation,
    kin: &Kinematics,
    machine: &Machine,
    o: &PostOptions,
    report: &mut PostReport,
) -> Result<Vec<Pt>, PostError> {
    let cls = cl_points(op, o.tol, report)?;
    if cls.is_empty() {
        return Ok(Vec::new());
    }
    let r = roles(kin.kind);
    let (cands, off, pole) = all_candidates(&cls, kin, r, o.pole_cone)?;
    let chosen = choose(&cls, &cands, &off, kin, r, o.pole_cone)?;
    drop((cands, off));
    // Room for the points linearisation inserts (memory not touched
    // until then): they are merged into this array.
    let mut pts: Vec<Pt> = Vec::with_capacity(cls.len() + cls.len() / 4 + 64);
    pts.par_extend(
        cls.par_iter()
            .zip(chosen.par_iter())
            .zip(pole.par_iter())
            .map(|((cl, c), &pole)| Pt {
                cl: *cl,
                c: *c,
                j: joints(kin, cl.tip, c),
                pole,
                len: f64::NAN,
            }),
    );
    drop((cls, chosen, pole));
    // Linearisation, each cutting block on its own, in chunks: the points
    // inserted before each point, flat, their number per point, and the
    // tip path length of each block that needed none.
    const CHUNK: usize = 8192;
    type Part = (Vec<Pt>, Vec<u32>, Vec<f64>);
    let inserted: Vec<Part> = if o.tcp {
        Vec::new()
    } else {
        (0..pts.len())
            .into_par_iter()
            .step_by(CHUNK)
            .map(|start| {
                let end = (start + CHUNK).min(pts.len());
                let mut flat = Vec::new();
                let (mut counts, mut lens) = (Vec::with_capacity(CHUNK), Vec::with_capacity(CHUNK));
                for i in start..end {
                    let before = flat.len();
                    let mut len = f64::NAN;
                    if i > 0 && !pts[i].cl.rapid {
                        len = linearise(kin, r, &pts[i - 1], &pts[i], o, &mut flat);
                    }
                    counts.push((flat.len() - before) as u32);
                    lens.push(len);
                }
                (flat, counts, lens)
            })
            .collect()
    };
    let extra: usize = inserted.iter().map(|c| c.0.len()).sum();
    report.inserted_points += extra;
    let all = merge(pts, &inserted, kin, r, o, report);
    check_travel(&all, kin, machine)?;
    Ok(all)
}

/// The points linearisation inserted before each point (`inserted`: per
/// chunk of points, flat, their number per point and the length of each
/// block that needed none) and the flips' moves merged into `pts` in
/// order, from the end of its own array (which has room for a quarter
/// more: no second array of the whole path).
fn merge(
    pts: Vec<Pt>,
    inserted: &[(Vec<Pt>, Vec<u32>, Vec<f64>)],
    kin: &Kinematics,
    r: Roles,
    o: &PostOptions,
    report: &mut PostReport,
) -> Vec<Pt> {
    let n = pts.len();
    // The flips' moves first, in order (the report's order).
    let mut flips: Vec<(usize, Vec<Pt>)> = Vec::new();
    for i in 1..n {
        if is_flip(r, &pts[i - 1].c, &pts[i].c) {
            let mut v = Vec::with_capacity(3);
            flip_moves(kin, &pts[i - 1], &pts[i], o, &mut v, report);
            flips.push((i, v));
        }
    }
    let extra: usize = inserted.iter().map(|c| c.0.len()).sum::<usize>()
        + flips.iter().map(|f| f.1.len()).sum::<usize>();
    let Some(&filler) = pts.first() else {
        return pts;
    };
    let mut all = pts;
    all.resize(n + extra, filler);
    // Point i's moves go to all[w - k..w]: the flip's, those inserted,
    // the point. They start at or after i, so the points before i are
    // still in place when read.
    let mut w = all.len();
    let mut place = |all: &mut Vec<Pt>, i: usize, v: &[Pt], len: f64| {
        let mut p = all[i];
        let flip = if flips.last().is_some_and(|f| f.0 == i) {
            flips.pop()
        } else {
            None
        };
        // Measured from the point before it in the CL path: that is the
        // point before it here only when nothing came between.
        if v.is_empty() && flip.is_none() {
            p.len = len;
        }
        w -= 1;
        all[w] = p;
        w -= v.len();
        all[w..w + v.len()].copy_from_slice(v);
        if let Some((_, f)) = flip {
            w -= f.len();
            all[w..w + f.len()].copy_from_slice(&f);
        }
    };
    let mut i = n;
    for (flat, counts, lens) in inserted.iter().rev() {
        let mut at = flat.len();
        for (&c, &len) in counts.iter().zip(lens).rev() {
            i -= 1;
            let v = &flat[at - c as usize..at];
            at -= c as usize;
            place(&mut all, i, v, len);
        }
    }
    while i > 0 {
        i -= 1;
        place(&mut all, i, &[], f64::NAN);
    }
    all
}

/// Retract along the old axis, rotate there, approach above the new point:
/// three rapids before the rapid of a flip.
fn flip_moves(
    kin: &Kinematics,
    a: &Pt,
    b: &Pt,
    o: &PostOptions,
    all: &mut Vec<Pt>,
    report: &mut PostReport,
) {
    let up = a.cl.tip + a.cl.k * o.clearance;
    let over = b.cl.tip + b.cl.k * o.clearance;
    let cl = |tip: DVec3, k: DVec3| Cl {
        tip,
        k,
        rapid: true,
        v: 0.0,
        ..b.cl
    };
    for (tip, k, c) in [(up, a.cl.k, a.c), (up, b.cl.k, b.c), (over, b.cl.k, b.c)] {
        all.push(Pt {
            cl: cl(tip, k),
            c,
            j: joints(kin, tip, &c),
            pole: false,
            len: f64::NAN,
        });
    }
    report.flip_moves += 3;
    report.flips.push(Flip {
        line: b.cl.line,
        from: [a.c.first, a.c.second],
        to: [b.c.first, b.c.second],
    });
}

/// Every posted position within the axes' travel: the linear axes, and the
/// rotary ones again for the points linearisation and flips inserted.
fn check_travel(all: &[Pt], kin: &Kinematics, machine: &Machine) -> Result<(), PostError> {
    let names = kin.kind.rotary_names();
    for p in all {
        for (a, v, name) in [
            (&kin.first, p.c.first, names[0]),
            (&kin.second, p.c.second, names[1]),
        ] {
            let lo = a.min.unwrap_or(f64::NEG_INFINITY);
            let hi = a.max.unwrap_or(f64::INFINITY);
            if v < lo - 1e-9 || v > hi + 1e-9 {
                return Err(PostError::Unreachable {
                    line: p.cl.line,
                    axis: name,
                    wanted: v,
                    min: a.min,
                    max: a.max,
                });
            }
        }
    }
    let axes: [(&LinearAxis, char); 3] = [
        (&machine.axes.x, 'X'),
        (&machine.axes.y, 'Y'),
        (&machine.axes.z, 'Z'),
    ];
    for p in all {
        for (k, (a, name)) in axes.iter().enumerate() {
            let v = p.j.xyz[k];
            let lo = a.min.unwrap_or(f64::NEG_INFINITY);
            let hi = a.max.unwrap_or(f64::INFINITY);
            if v < lo - 1e-9 || v > hi + 1e-9 {
                return Err(PostError::Unreachable {
                    line: p.cl.line,
                    axis: *name,
                    wanted: v,
                    min: a.min,
                    max: a.max,
                });
            }
        }
    }
    Ok(())
}

/// The time (minutes) of a move of the joints from `a` to `b` with every
/// axis at most at its top speed (rapid: the rapid rate where a linear
/// axis's is unknown; a rotary axis of unknown speed: `rot_default`
/// degrees/min).
fn axes_minutes(
    machine: &Machine,
    a: &Joints,
    b: &Joints,
    lin_default: f64,
    rot_default: f64,
) -> f64 {
    let ax = &machine.axes;
    let lin = [ax.x.velocity, ax.y.velocity, ax.z.velocity];
    let mut t: f64 = 0.0;
    for (k, v) in lin.iter().enumerate() {
        let d = (b.xyz[k] - a.xyz[k]).abs();
        t = t.max(d / v.unwrap_or(lin_default));
    }
    for (d, v) in [
        ((b.first - a.first).abs(), ax.first.velocity),
        ((b.second - a.second).abs(), ax.second.velocity),
    ] {
        t = t.max(d / v.unwrap_or(rot_default));
    }
    t
}

/// The least time (minutes) the axes with a known top speed allow.
fn known_axes_minutes(machine: &Machine, a: &Joints, b: &Joints) -> f64 {
    axes_minutes(machine, a, b, f64::INFINITY, f64::INFINITY)
}

/// The rotary angles as an orientation: radians on the machine's letters.
fn orient_of(kin: &Kinematics, c: &Cand) -> Orient {
    let (f, s) = letters(kin.kind);
    let mut angles = [None; 3];
    angles[f] = Some(c.first.to_radians());
    angles[s] = Some(c.second.to_radians());
    Orient { axis: None, angles }
}

fn target6(kin: &Kinematics, j: &Joints) -> [f64; 6] {
    let (f, s) = letters(kin.kind);
    let mut t = [j.xyz.x, j.xyz.y, j.xyz.z, 0.0, 0.0, 0.0];
    t[3 + f] = j.first;
    t[3 + s] = j.second;
    t
}

/// Points whose [`Geometry`] is computed at once (in parallel), so that it
/// is not held for the whole operation.
const GEOMETRY_CHUNK: usize = 1 << 16;

/// What `build` needs of a posted point beyond the point itself.
#[derive(Clone, Copy)]
struct Geometry {
    /// The distance of its tip by forward kinematics from the CL tip, mm,
    /// and the angle of its axis from the CL axis, degrees.
    err: f64,
    dev: f64,
    /// The block to it: its path length, the least minutes the axes with a
    /// known top speed allow, and the minutes of a plain G94 post (zeros
    /// for the first point and rapids).
    times: (f64, f64, f64),
}

/// The [`Geometry`] of the points `range` of `pts`, in parallel.
fn geometry(
    pts: &[Pt],
    range: std::ops::Range<usize>,
    kin: &Kinematics,
    machine: &Machine,
    o: &PostOptions,
) -> Vec<Geometry> {
    range
        .into_par_iter()
        .map(|i| {
            let p = &pts[i];
            let (tip, k) = kin.forward(&p.j);
            let (err, dev) = ((tip - p.cl.tip).length(), ik::angle_deg(k, p.cl.k));
            if i == 0 || p.cl.rapid {
                let times = (0.0, 0.0, 0.0);
                return Geometry { err, dev, times };
            }
            let a = &pts[i - 1];
            let len = if o.tcp {
                (p.cl.tip - a.cl.tip).length()
            } else if p.len.is_nan() {
                tip_path_length(kin, &a.j, &p.j)
            } else {
                p.len
            };
            let plain = if o.tcp {
                len / p.cl.v
            } else {
                g94_minutes(&a.j, &p.j, p.cl.v)
            };
            let times = (len, known_axes_minutes(machine, &a.j, &p.j), plain);
            Geometry { err, dev, times }
        })
        .collect()
}

/// The posted operation: moves, orientations, events re-anchored, feeds.
fn build(
    op: &Operation,
    pts: &[Pt],
    kin: &Kinematics,
    machine: &Machine,
    o: &PostOptions,
    timer: &mut Times,
    report: &mut PostReport,
) -> Operation {
    let mut new = Operation {
        name: op.name.clone(),
        tool: op.tool.clone(),
        frame: None,
        start: UNKNOWN,
        moves: Vec::with_capacity(pts.len()),
        arcs: Vec::new(),
        cycles: Vec::new(),
        orients: Vec::with_capacity(pts.len()),
        events: Vec::new(),
    };
    // The first posted move of each source move.
    let mut first_of = vec![u32::MAX; op.moves.len() + 1];
    let rapid_lin = machine.rapid;
    let (mut nominal, mut g93, mut g94) = (0.0, 0.0, 0.0);
    let mut geo = Vec::new();
    for (i, p) in pts.iter().enumerate() {
        if i % GEOMETRY_CHUNK == 0 {
            geo = geometry(pts, i..(i + GEOMETRY_CHUNK).min(pts.len()), kin, machine, o);
        }
        let Geometry {
            err,
            dev,
            times: (len, floor, plain),
        } = geo[i % GEOMETRY_CHUNK];
        report.max_tip_error_mm = report.max_tip_error_mm.max(err);
        report.max_orientation_deviation_deg = report.max_orientation_deviation_deg.max(dev);
        if p.pole {
            report.pole_blocks += 1;
            if dev > o.pole_tol {
                report.pole_flagged.push(p.cl.line);
            }
        }
        let mut m = Move {
            end: if o.tcp { p.cl.tip } else { p.j.xyz },
            feed: 0.0,
            spindle: p.cl.spindle,
            line: p.cl.line,
            kind: MoveKind::Rapid,
            orient: None,
            feed_mode: FeedMode::PerMinute,
        };
        let kind;
        let (mut exact_t, mut plain_t) = (0.0, 0.0);
        if p.cl.rapid || i == 0 {
            let prev = i.checked_sub(1).map(|k| pts[k].j);
            let t = prev.map_or(0.0, |a| {
                axes_minutes(machine, &a, &p.j, rapid_lin, rapid_lin)
            });
            nominal += t;
            g93 += t;
            g94 += t;
            if p.cl.rapid {
                kind = AxisKind::Rapid;
            } else {
                // A first cut from an unknown position: its length and time
                // are unknown, so it keeps the CL feed per minute.
                m.kind = MoveKind::Linear;
                m.feed = p.cl.v;
                kind = AxisKind::Feed { nominal_min: 0.0 };
            }
        } else {
            let a = &pts[i - 1];
            let mut t = if len > 1e-9 {
                len / p.cl.v
            } else {
                // §1.10.4: no tip motion, the slowest axis at its top speed
                // or the feed read as degrees/min.
                axes_minutes(machine, &a.j, &p.j, p.cl.v, p.cl.v)
            };
            if t <= 0.0 {
                report.null_moves += 1;
                continue;
            }
            let exact = t;
            // No block is faster than the machine's feed, nor shorter than
            // the control's block cycle: asking for it (a G93 F of 2·10⁶ on
            // a block of a few µm) would not make it so.
            let mut floor = floor
                .max(len / machine.feed_max)
                .max(machine.control.planner.block_time_s / 60.0);
            if !o.g93 && !o.tcp {
                // A G94 F is the joints' feed, which the control holds to
                // its maximum cutting feed: a block needing more is slower.
                floor = floor.max(g94_minutes(&a.j, &p.j, machine.feed_max));
            }
            if t < floor * (1.0 - 1e-12) {
                t = floor;
                report.slowed_blocks += 1;
            }
            nominal += t;
            g93 += exact;
            g94 += if plain.is_finite() { plain } else { t };
            m.kind = MoveKind::Linear;
            if o.g93 {
                m.feed_mode = FeedMode::InverseTime;
                m.feed = 1.0 / t;
            } else if o.tcp && len > 1e-9 {
                // The control's F is the tip feed along the programmed line.
                m.feed = if t == exact { p.cl.v } else { len / t };
            } else {
                m.feed = g94_machine_f(&a.j, &p.j, t);
            }
            if m.feed_mode == FeedMode::PerMinute && m.feed < machine.feed_min {
                m.feed_mode = FeedMode::InverseTime;
                m.feed = 1.0 / t;
                report.g93_blocks += 1;
            }
            kind = AxisKind::Feed { nominal_min: t };
            exact_t = exact;
            plain_t = if plain.is_finite() { plain } else { t };
        }
        m.orient = Some(new.intern_orient(orient_of(kin, &p.c)));
        let src = p.cl.src as usize;
        if first_of[src] == u32::MAX {
            first_of[src] = new.moves.len() as u32;
        }
        let block = AxisMove {
            target: target6(kin, &p.j),
            kind,
        };
        timer.push(block, exact_t, plain_t);
        new.moves.push(m);
    }
    // Events before source move k go before the first posted move of k or
    // of a later move.
    first_of[op.moves.len()] = new.moves.len() as u32;
    for k in (0..op.moves.len()).rev() {
        if first_of[k] == u32::MAX {
            first_of[k] = first_of[k + 1];
        }
    }
    for e in &op.events {
        // TCP on or off is the post's mode, not the CL file's.
        if matches!(e.kind, EventKind::Tcp(_)) {
            continue;
        }
        let mut e = e.clone();
        e.at = first_of[(e.at as usize).min(op.moves.len())];
        new.events.push(e);
    }
    if o.tcp && !new.moves.is_empty() {
        // After the source's own events before the first move (the tool
        // change, the spindle), before that move.
        let at = new.events.partition_point(|e| e.at == 0);
        new.events.insert(
            at,
            millplan_nc::Event {
                at: 0,
                line: 0,
                kind: EventKind::Tcp(true),
            },
        );
    }
    report.nominal_s += nominal * 60.0;
    report.nominal_g93_s += g93 * 60.0;
    report.nominal_g94_s += g94 * 60.0;
    new
}
