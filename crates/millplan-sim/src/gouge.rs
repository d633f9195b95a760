//! Gouge check: sample every cutting move (and optionally the rapids) at a chord
//! step and compare the tool tip with the drop-cutter height there; a tip lower
//! than the drop height by more than a tolerance cuts into the part.
//!
//! A ball-end tool whose axis is not vertical is checked by its distance to
//! the part's surface instead: the ball and its flutes, a capsule from the
//! ball centre up the axis (the axis turned along the move as the IR turns
//! it), must stay clear of every triangle by its radius less the tolerance.
//! A distance to a surface cannot tell a tool buried deeper than its radius
//! from one in the air: such a tool is found where it went in, at the
//! samples of the move that entered the part. Other tilted tools are
//! skipped and counted.

use crate::dropcutter::DropMesh;
use crate::stock::tool::ToolBody;
use millplan_geom::{DVec2, DVec3};
use millplan_models::cutter::Shape;
use millplan_nc::{axis_at, known, MoveKind, Operation, Program};
use rayon::prelude::*;

#[derive(Clone, Copy, Debug)]
pub struct GougeParams {
    /// Sampling step along each move, mm.
    pub step: f64,
    /// Depth below the drop height that counts as a gouge, mm.
    pub tol: f64,
    /// Check rapids too.
    pub rapids: bool,
}

impl Default for GougeParams {
    fn default() -> Self {
        GougeParams {
            step: 0.1,
            tol: 0.005,
            rapids: false,
        }
    }
}

/// The deepest gouge of one move.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Gouge {
    pub operation: usize,
    /// Move index within the operation.
    #[serde(rename = "move")]
    pub mv: usize,
    /// Source line of the move.
    pub line: u32,
    /// Tool tip where it is deepest, part coordinates.
    pub at: [f64; 3],
    /// How far the tip is below the drop height, mm (a tilted ball end: how
    /// far its surface reaches into the part's).
    pub depth: f64,
    /// A tilted ball end whose ball alone reaches that deep: the ball's
    /// centre there (a gouge of the ball, which a vertical tool with its
    /// centre at the same place would make too; not of its flutes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ball_centre: Option<[f64; 3]>,
}

/// Why moves were left out of a check.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Skipped {
    /// The operation's tool has no geometry and none was given.
    pub no_tool: usize,
    /// The tool is not along +Z (five-axis) and not a ball end, or its axis
    /// is known only as machine angles.
    pub tilted: usize,
    /// Canned-cycle holes along an axis that is not vertical (a vertical
    /// one is checked from the cycle's highest plane down to its bottom).
    pub cycles: usize,
    /// From or to a position the program has not set.
    pub unknown_position: usize,
    /// Source line of the first move left out.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_line: Option<u32>,
}

impl Skipped {
    pub fn total(&self) -> usize {
        self.no_tool + self.tilted + self.cycles + self.unknown_position
    }

    /// Notes the source line of a move left out (the first one is kept).
    pub fn at(&mut self, line: u32) {
        self.first_line.get_or_insert(line);
    }

    /// `"; the first at line N"`, or nothing.
    pub fn first(&self) -> String {
        crate::stock::path::first_line_note(self.first_line)
    }
}

#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct GougeReport {
    pub moves_checked: usize,
    pub points_checked: usize,
    /// The cutting moves and holes checked (rapids aside).
    pub cutting_moves: usize,
    /// Of those, the moves whose tool tip stands away from the part's
    /// footprint (its xy box grown by the tool's radius and [`NEAR_PART`])
    /// at every sample: most of a path there says the part does not match
    /// the program (its unit, its placement), and no gouge found there
    /// proves anything. A profile beside the part or a hole through it
    /// stands by it; counted by moves, a long link to a park position
    /// weighs one move, not its length.
    pub off_part_moves: usize,
    /// Moves left out, all reasons.
    pub moves_skipped: usize,
    pub skipped: Skipped,
    pub gouges: Vec<Gouge>,
    pub max_depth: f64,
}

/// The largest share of cutting moves away from the part that a check
/// still calls clean: beyond it the part does not match the program (a part
/// in the wrong unit, or placed elsewhere), and no gouge found says little.
pub const OFF_PART_SHARE: f64 = 0.5;

/// How far beyond its radius a tool may stand from the part's xy box and
/// still be by the part, mm (the stock a roughing profile leaves).
pub const NEAR_PART: f64 = 2.0;

impl GougeReport {
    /// Whether more than [`OFF_PART_SHARE`] of the cutting moves stood
    /// away from the part.
    pub fn mostly_off_part(&self) -> bool {
        self.cutting_moves > 0
            && self.off_part_moves as f64 > OFF_PART_SHARE * self.cutting_moves as f64
    }

    /// `the tool stands by the part in only K of N cutting moves (P %): the
    /// part does not match the program (its unit? its placement?)`.
    pub fn off_part_words(&self) -> String {
        let by = self.cutting_moves - self.off_part_moves;
        format!(
            "the tool stands by the part in only {by} of {} cutting moves ({:.1} %): the part does not match the program (its unit? its placement?)",
            self.cutting_moves,
            100.0 * by as f64 / self.cutting_moves.max(1) as f64
        )
    }
}

/// One sample of a check: operation, move, tool tip (part coordinates) and,
/// for a tilted ball end, its axis there.
type Sample = (u32, u32, DVec3, Option<DVec3>);

/// Memory per sample point of a check: the sample and its depth.
pub const BYTES_PER_SAMPLE: f64 =
    (std::mem::size_of::<Sample>() + std::mem::size_of::<(f64, bool)>()) as f64;

/// How many points [`check`] would sample (an upper bound: moves it would
/// skip for a tilted tool are counted), in one pass over the moves without
/// allocating: a step of 1e-9 is refused from this, never attempted.
pub fn samples(p: &Program, body: impl Fn(&Operation) -> Option<ToolBody>, g: &GougeParams) -> f64 {
    let mut n = 0.0;
    for op in &p.operations {
        if body(op).is_none() {
            continue;
        }
        for (i, m) in op.moves.iter().enumerate() {
            // A hole: from the cycle's highest plane down to its bottom
            // (`sample_hole`), wherever the tool came from.
            if let Some(c) = op.cycle(m) {
                let depth = c.retract.max(c.clearance).max(c.bottom) - c.bottom;
                n += (depth / g.step).ceil().max(1.0) + 1.0;
                continue;
            }
            let wanted = match m.kind {
                MoveKind::Linear | MoveKind::Arc(_) => true,
                MoveKind::Rapid => g.rapids,
                MoveKind::Cycle(_) => false,
            };
            let (Some(start), Some(end)) = (op.known_start(i), known(m.end)) else {
                continue;
            };
            if wanted {
                let len = match op.arc(m) {
                    Some(a) => a.length(start, end),
                    None => (end - start).length(),
                };
                n += (len / g.step).ceil().max(1.0) + 1.0;
            }
        }
    }
    n
}

/// Checks a program against the part. `body` gives the tool of an operation
/// (`None` skips the operation): its cutter, and for a tilted ball end the
/// flutes' length.
pub fn check(
    p: &Program,
    part: &DropMesh,
    body: impl Fn(&Operation) -> Option<ToolBody>,
    g: &GougeParams,
) -> GougeReport {
    check_with_progress(p, part, body, g, &|_, _| {})
}

/// Sample points checked between two calls of a progress callback.
pub const PROGRESS_EVERY: usize = 16_384;

/// [`check`], calling `progress(done, total)` with the sample points checked
/// so far (from any thread, every [`PROGRESS_EVERY`] points and at the end).
pub fn check_with_progress(
    p: &Program,
    part: &DropMesh,
    body: impl Fn(&Operation) -> Option<ToolBody>,
    g: &GougeParams,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> GougeReport {
    let mut rep = GougeReport::default();
    let bodies: Vec<Option<ToolBody>> = p.operations.iter().map(&body).collect();
    let mut samples: Vec<Sample> = Vec::new();
    for (oi, op) in p.operations.iter().enumerate() {
        let Some(b) = bodies[oi] else {
            let mut left = op.moves.iter().filter(|m| wanted(m.kind, g));
            if let Some(m) = left.next() {
                rep.skipped.at(m.line);
                rep.skipped.no_tool += 1 + left.count();
            }
            continue;
        };
        sample_operation(op, oi, &b, g, &mut rep, &mut samples);
    }
    rep.moves_skipped = rep.skipped.total();
    rep.points_checked = samples.len();
    let total = samples.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    // The depth of each sample, and whether a tilted ball alone reaches it.
    let depths: Vec<(f64, bool)> = samples
        .par_iter()
        .map(|(oi, _, q, axis)| {
            let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if k.is_multiple_of(PROGRESS_EVERY) || k == total {
                progress(k, total);
            }
            let b = bodies[*oi as usize].expect("sampled with a body");
            match axis {
                None => (vertical_depth(part, &b.shape, *q, g.tol), false),
                Some(a) => tilted_depth(part, &b, *q, *a, g.tol),
            }
        })
        .collect();
    let footprint = part.xy_bounds();
    // The cutting move the samples are of, and whether one stood by the part.
    let mut current: Option<((usize, usize), bool)> = None;
    let close = |rep: &mut GougeReport, m: Option<((usize, usize), bool)>| {
        if let Some((_, by)) = m {
            rep.cutting_moves += 1;
            rep.off_part_moves += usize::from(!by);
        }
    };
    for ((oi, mi, q, axis), &(d, ball)) in samples.iter().zip(&depths) {
        let (oi, mi) = (*oi as usize, *mi as usize);
        let mv = &p.operations[oi].moves[mi];
        if mv.kind != MoveKind::Rapid {
            let reach = bodies[oi].map_or(0.0, |b| b.radius()) + NEAR_PART;
            let by = footprint.is_some_and(|(lo, hi)| {
                (lo.x - reach..=hi.x + reach).contains(&q.x)
                    && (lo.y - reach..=hi.y + reach).contains(&q.y)
            });
            match &mut current {
                Some((at, any)) if *at == (oi, mi) => *any |= by,
                _ => {
                    close(&mut rep, current.take());
                    current = Some(((oi, mi), by));
                }
            }
        }
        if d > g.tol {
            let line = mv.line;
            let r = bodies[oi].map_or(0.0, |b| b.radius());
            let ball_centre = axis.filter(|_| ball).map(|a| (*q + a * r).to_array());
            let here = Gouge {
                operation: oi,
                mv: mi,
                line,
                at: q.to_array(),
                depth: d,
                ball_centre,
            };
            match rep.gouges.last_mut() {
                Some(last) if last.operation == oi && last.mv == mi => {
                    if d > last.depth {
                        *last = here;
                    }
                }
                _ => rep.gouges.push(here),
            }
            rep.max_depth = rep.max_depth.max(d);
        }
    }
    close(&mut rep, current);
    rep
}

/// Whether a move of kind `k` is checked.
fn wanted(k: MoveKind, g: &GougeParams) -> bool {
    match k {
        // A hole is sampled along its axis (`sample_hole`).
        MoveKind::Linear | MoveKind::Arc(_) | MoveKind::Cycle(_) => true,
        MoveKind::Rapid => g.rapids,
    }
}

/// The sample points of one operation's moves, every `g.step` along each
/// (the skipped counted in `rep`).
fn sample_operation(
    op: &Operation,
    oi: usize,
    b: &ToolBody,
    g: &GougeParams,
    rep: &mut GougeReport,
    samples: &mut Vec<Sample>,
) {
    let to_part = |v: DVec3| op.frame.map(|f| f.to_parent(v)).unwrap_or(v);
    let axis_part = |m: &millplan_nc::Move| op.axis_in_part(m);
    let vertical = |a: DVec3| (a - DVec3::Z).length() <= 1e-6;
    let ball = matches!(b.shape, Shape::Ball { .. });
    for (i, m) in op.moves.iter().enumerate() {
        if let Some(c) = op.cycle(m) {
            sample_hole(op, (oi, i), c, g, rep, samples);
            continue;
        }
        if !wanted(m.kind, g) {
            continue;
        }
        let (Some(start), Some(end)) = (op.known_start(i), known(m.end)) else {
            rep.skipped.unknown_position += 1;
            rep.skipped.at(m.line);
            continue;
        };
        let Some(a1) = axis_part(m) else {
            rep.skipped.tilted += 1;
            rep.skipped.at(m.line);
            continue;
        };
        // The axis the move starts with: the previous move's (the first
        // move of an operation turns from nowhere: its own).
        let a0 = match i.checked_sub(1).map(|k| axis_part(&op.moves[k])) {
            Some(None) => {
                rep.skipped.tilted += 1;
                rep.skipped.at(m.line);
                continue;
            }
            Some(Some(a)) => a,
            None => a1,
        };
        let upright = vertical(a1) && (vertical(a0) || !ball);
        if !upright && !ball {
            rep.skipped.tilted += 1;
            rep.skipped.at(m.line);
            continue;
        }
        rep.moves_checked += 1;
        let arc = op.arc(m);
        let len = match &arc {
            Some(a) => a.length(start, end),
            None => (end - start).length(),
        };
        let at = |t: f64| match &arc {
            Some(a) => a.point_at(start, end, t),
            None => start.lerp(end, t),
        };
        let n = ((len / g.step).ceil() as usize).max(1);
        samples.extend((0..=n).map(|k| {
            let t = k as f64 / n as f64;
            let axis = (!upright).then(|| axis_at(a0, a1, t));
            (oi as u32, i as u32, to_part(at(t)), axis)
        }));
    }
}

/// The samples of one hole of a canned cycle (move `i` of operation `oi`):
/// along the tool axis from the cycle's highest plane down to its bottom,
/// where its pecks, feeds and rapids all run. A hole at an unknown
/// position, or whose axis is not vertical (`cycles`), is skipped.
fn sample_hole(
    op: &Operation,
    (oi, i): (usize, usize),
    c: &millplan_nc::ir::Cycle,
    g: &GougeParams,
    rep: &mut GougeReport,
    samples: &mut Vec<Sample>,
) {
    let m = &op.moves[i];
    let Some(at) = known(m.end) else {
        rep.skipped.unknown_position += 1;
        rep.skipped.at(m.line);
        return;
    };
    let upright = op
        .axis_in_part(m)
        .is_some_and(|a| (a - DVec3::Z).length() <= 1e-6);
    if !upright {
        rep.skipped.cycles += 1;
        rep.skipped.at(m.line);
        return;
    }
    let axis = op.axis(m).unwrap_or(DVec3::Z);
    let to_part = |v: DVec3| op.frame.map(|f| f.to_parent(v)).unwrap_or(v);
    let top = at + axis * c.retract.max(c.clearance).max(c.bottom);
    let bottom = at + axis * c.bottom;
    rep.moves_checked += 1;
    let n = (((top - bottom).length() / g.step).ceil() as usize).max(1);
    samples.extend((0..=n).map(|k| {
        let q = top.lerp(bottom, k as f64 / n as f64);
        (oi as u32, i as u32, to_part(q), None)
    }));
}

/// How far below the drop-cutter height of the vertical cutter `sh` the tip
/// `q` is (−∞ where the cutter meets no part, or meets it only by the
/// tolerance at a wall).
fn vertical_depth(part: &DropMesh, sh: &Shape, q: DVec3, tol: f64) -> f64 {
    let c = DVec2::new(q.x, q.y);
    let depth = part
        .drop(sh, c)
        .map(|d| d.z - q.z)
        .unwrap_or(f64::NEG_INFINITY);
    if depth <= tol {
        return depth;
    }
    // Deeper than the tolerance below where the tool would rest, but is it
    // into the part by more than the tolerance in any direction? A tool
    // standing exactly at a vertical wall is not: the tool shrunk by the
    // tolerance must still meet the part.
    let (inner, rise) = sh.inset(tol);
    let into = part.drop(&inner, c).is_some_and(|d| d.z > q.z + rise);
    if into {
        depth
    } else {
        f64::NEG_INFINITY
    }
}

/// Flutes longer than this are checked to here, mm (an unknown flute length
/// stands for a tool that cuts all along: a kilometre is all of it).
const FLUTE_REACH: f64 = 1e6;

/// How far the ball end `b` at tip `q` with unit axis `a` reaches into the
/// part: its radius less the distance from the part's surface to the
/// capsule of its ball and flutes (−∞ when that distance is more than the
/// radius less `tol`); and whether the ball alone reaches that deep.
fn tilted_depth(part: &DropMesh, b: &ToolBody, q: DVec3, a: DVec3, tol: f64) -> (f64, bool) {
    let r = b.radius();
    let centre = q + a * r;
    let top = q + a * b.flute.clamp(r, FLUTE_REACH);
    let solid = part.solid();
    let capsule = |radius: f64| solid.capsule_hits(centre, top, radius, None);
    if !capsule(r - tol) {
        return (f64::NEG_INFINITY, false);
    }
    let ball = |radius: f64| solid.capsule_hits(centre, centre, radius, None);
    // The distance of a test that hits at r − tol lies between a radius
    // that misses and one that hits.
    let depth = |hits: &dyn Fn(f64) -> bool| {
        let (mut lo, mut hi) = (0.0, r - tol);
        for _ in 0..24 {
            let mid = 0.5 * (lo + hi);
            if hits(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        r - lo
    };
    let whole = depth(&capsule);
    // The ball alone as deep as the whole tool: a gouge of the ball.
    let alone = ball(r - tol) && depth(&ball) >= whole - 1e-6 * r;
    (whole, alone)
}
