//! Reordering the points of a ball-end finishing path so the spindle, driven
//! for a constant cutting speed, has less to change between successive points
//! (paper 000, thesis 5; spec `working-diameter.md` §4.4 and §5.8), with safe
//! links.
//!
//! - [`Method::AsRun`] (the default, [`run`]): candidate orders judged by the
//!   machining as it will run with spindle control, the best one worse than
//!   the original on nothing kept, else the original as it was.
//! - [`Method::Paper`]: the paper's greedy search. Start on the border of the point
//!   set; candidates are the unvisited points within a radius grown ×1.5 until at
//!   least `n_min` are found; visited points are tabu; the candidate with the
//!   smallest |ΔD_w| wins, ties continue in the current feed direction. Each
//!   candidate's D_w is evaluated for the direction it would be cut in and the
//!   material already cut around it (not reused from the original order). Where
//!   the tool has just plunged (the start, after a jump) it cuts in the
//!   direction it leaves in, so the current point's D_w is taken for each
//!   candidate's direction. An optional step guard (`max_step`) widens the
//!   search at dead ends, where every candidate would change D_w by more than
//!   the guard, up to `guard_reach` × the radius, preferring a retract to a
//!   large step; without it the search is the published one.
//! - [`Method::Optimised`]: passes of the original path are kept as units and their
//!   order and directions improved by 2-opt from the original order on the cost
//!   w₁·|Δn| + w₂·link length + w₃·direction change (radians) at the joints, so the
//!   result is never worse than the original on that cost.
//!
//! Links: a move between successive points is made directly only when the
//! drop-cutter check along it finds no gouge; otherwise the tool retracts to a
//! clearance height, rapids across and plunges at the plunge feed (the default
//! method: rapids down to 1 mm above the point first, and links only points a
//! jump apart directly).

pub mod run;

use crate::pipeline::{Changes, Context, Need, Pass, PassError, PassInfo};
use crate::speed::SpeedParams;
use millplan_geom::{DVec2, DVec3, TriMesh};
use millplan_models::contact::{self, feed_angle, PathPoint, SideFinder};
use millplan_models::cutter::Shape;
use millplan_models::wd::{self, Case};
use millplan_nc::{EventKind, Move, MoveKind, Operation, Program};
use millplan_sim::dropcutter::DropMesh;
use rustc_hash::{FxHashMap, FxHashSet};

/// Where the paper's search starts, among the points on the border (convex hull)
/// of the point set seen from above.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Start {
    Lowest,
    Highest,
    /// A given point (index into the cutting points).
    Index(usize),
    /// A border point chosen with this seed.
    Random(u64),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// The thesis's greedy search over single points, as published.
    Paper,
    /// Passes as units, 2-opt on |Δn|, link length and turns at the joints.
    Optimised,
    /// The machining as it will run (the default): candidate orders measured
    /// with spindle control, the best one not worse than the original kept
    /// ([`run`]).
    AsRun,
}

/// What the default method concluded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// An order better than the original, and worse on none of the measures.
    Improved,
    /// Nothing better found: the original order, as it was.
    Kept,
}

#[derive(Clone, Copy, Debug)]
pub struct ReorderParams {
    pub method: Method,
    pub start: Start,
    /// Stock thickness along the normal, mm.
    pub ap: f64,
    /// Cutting speed, m/min (for the |Δn| cost of the optimised method).
    pub vc: f64,
    /// Minimum number of candidates.
    pub n_min: usize,
    /// Initial search radius, mm (`None`: 1.5 × the median point spacing).
    pub radius: Option<f64>,
    /// D_w differences closer than this are ties, mm.
    pub tie: f64,
    /// Step guard of the paper search (`None`: the search as published): when
    /// every candidate changes D_w by more than this, mm, the search widens.
    pub max_step: Option<f64>,
    /// How far the step guard widens, as a multiple of the initial radius.
    pub guard_reach: f64,
    /// Cost weights: |Δn| (per 1/min), link length (per mm), direction change (per radian).
    pub weights: [f64; 3],
    /// 2-opt budget: passes over the sequence.
    pub iterations: usize,
    /// Clearance above the part for retracts, mm.
    pub clearance: f64,
    /// Feed of plunges after a retract, as a fraction of the cutting feed.
    pub plunge_factor: f64,
    /// Gouge tolerance of direct links, mm.
    pub gouge_tol: f64,
    /// Spindle control the default method measures its candidates with (and
    /// the written program gets, unless the caller leaves it out).
    pub speed: SpeedParams,
    /// How much longer than the original the default method's result may
    /// take, as a fraction of the original's time.
    pub time_slack: f64,
}

impl ReorderParams {
    pub fn new(method: Method) -> ReorderParams {
        ReorderParams {
            method,
            start: Start::Lowest,
            ap: 0.3,
            vc: 63.0,
            n_min: 4,
            radius: None,
            tie: 1e-3,
            max_step: None,
            guard_reach: 32.0,
            weights: [1.0, 10.0, 100.0],
            iterations: 20,
            clearance: 5.0,
            plunge_factor: 0.5,
            gouge_tol: 0.005,
            speed: SpeedParams::new(63.0, 0.125, 2, 0.3),
            time_slack: 0.03,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ReorderError {
    #[error("the program has no 3-axis ball-end operation to reorder")]
    NoBallOperation,
    #[error("{0}")]
    Invalid(String),
}

/// How much each cost term changed (optimised method), and what the links did.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ReorderStats {
    pub points: usize,
    pub passes: usize,
    /// Cost terms at the joints of the original and the reordered sequence.
    pub cost_original: [f64; 3],
    pub cost_reordered: [f64; 3],
    pub direct_links: usize,
    pub retracts: usize,
}

/// The reordered program (only ball-end operations change) and statistics.
pub struct Reordered {
    pub program: Program,
    pub stats: ReorderStats,
    /// D_w along the original and the new order (all reordered operations, in
    /// sequence), evaluated by the same rule: arrival direction and material cut
    /// so far.
    pub dw_original: Vec<f64>,
    pub dw_reordered: Vec<f64>,
    /// Whether the step into each position is a jump (a retract and plunge, or a
    /// long direct link), where the spindle has time to change speed.
    pub jump_original: Vec<bool>,
    pub jump_reordered: Vec<bool>,
    /// The default method's conclusion (`None` for the others).
    pub verdict: Option<Verdict>,
    /// The candidates the default method measured, per operation.
    pub tried: Vec<run::Tried>,
}

fn xy(v: DVec3) -> DVec2 {
    DVec2::new(v.x, v.y)
}

/// Indices of the convex hull of the points seen from above (monotone chain).
fn hull(points: &[DVec3]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len()).collect();
    idx.sort_by(|&a, &b| {
        points[a]
            .x
            .total_cmp(&points[b].x)
            .then(points[a].y.total_cmp(&points[b].y))
    });
    let cross = |o: usize, a: usize, b: usize| {
        (xy(points[a]) - xy(points[o])).perp_dot(xy(points[b]) - xy(points[o]))
    };
    let mut h: Vec<usize> = Vec::new();
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &usize>> = if pass == 0 {
            Box::new(idx.iter())
        } else {
            Box::new(idx.iter().rev())
        };
        for &p in iter {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
                h.pop();
            }
            h.push(p);
        }
        h.pop();
    }
    if h.is_empty() && !points.is_empty() {
        h.push(0);
    }
    h
}

/// Unvisited points in an XY grid, removable in O(1).
struct Unvisited {
    cell: f64,
    cells: FxHashMap<(i64, i64), Vec<u32>>,
    slot: Vec<u32>,
    gone: Vec<bool>,
    occupied: FxHashSet<(i64, i64)>,
}

impl Unvisited {
    fn key(&self, p: DVec2) -> (i64, i64) {
        (
            (p.x / self.cell).floor() as i64,
            (p.y / self.cell).floor() as i64,
        )
    }

    fn new(points: &[DVec3], cell: f64) -> Unvisited {
        let mut u = Unvisited {
            cell,
            cells: FxHashMap::default(),
            slot: vec![0; points.len()],
            gone: vec![false; points.len()],
            occupied: FxHashSet::default(),
        };
        for (i, p) in points.iter().enumerate() {
            let k = u.key(xy(*p));
            let v = u.cells.entry(k).or_default();
            u.slot[i] = v.len() as u32;
            v.push(i as u32);
            u.occupied.insert(k);
        }
        u
    }

    fn remove(&mut self, i: usize, p: DVec2) {
        if std::mem::replace(&mut self.gone[i], true) {
            return;
        }
        let k = self.key(p);
        if let Some(v) = self.cells.get_mut(&k) {
            let s = self.slot[i] as usize;
            let last = *v.last().unwrap_or(&(i as u32));
            v.swap_remove(s);
            if s < v.len() {
                self.slot[last as usize] = s as u32;
            }
            if v.is_empty() {
                self.occupied.remove(&k);
            }
        }
    }

    /// Appends the unvisited points farther than `r_in` and within `r` of p.
    fn within_ring(&self, points: &[DVec3], p: DVec2, r_in: f64, r: f64, out: &mut Vec<u32>) {
        let mut ring = Vec::new();
        self.within(points, p, r, &mut ring);
        out.extend(
            ring.into_iter()
                .filter(|&j| (xy(points[j as usize]) - p).length() > r_in),
        );
    }

    /// Unvisited points within `r` of p.
    fn within(&self, points: &[DVec3], p: DVec2, r: f64, out: &mut Vec<u32>) {
        out.clear();
        let k = self.key(p);
        let span = (r / self.cell).ceil() as i64;
        let cells = (2 * span + 1) * (2 * span + 1);
        let mut visit = |v: &Vec<u32>| {
            for &j in v {
                if (xy(points[j as usize]) - p).length() <= r {
                    out.push(j);
                }
            }
        };
        if cells as usize > self.occupied.len() {
            for c in &self.occupied {
                if (c.0 - k.0).abs() <= span && (c.1 - k.1).abs() <= span {
                    if let Some(v) = self.cells.get(c) {
                        visit(v);
                    }
                }
            }
        } else {
            for dx in -span..=span {
                for dy in -span..=span {
                    if let Some(v) = self.cells.get(&(k.0 + dx, k.1 + dy)) {
                        visit(v);
                    }
                }
            }
        }
    }
}

/// The working diameter of a point for a given arrival direction and the points
/// machined so far (the material state the order creates).
struct Evaluator<'a> {
    centres: &'a [DVec3],
    normals: &'a [DVec3],
    d: f64,
    ap: f64,
    side_search: f64,
    machined: FxHashMap<(i64, i64), Vec<u32>>,
}

impl Evaluator<'_> {
    fn key(&self, q: DVec3) -> (i64, i64) {
        (
            (q.x / self.side_search).floor() as i64,
            (q.y / self.side_search).floor() as i64,
        )
    }

    fn mark(&mut self, j: usize) {
        let k = self.key(self.centres[j]);
        self.machined.entry(k).or_default().push(j as u32);
    }

    fn dw(&self, j: usize, dir: DVec3) -> f64 {
        let nj = self.normals[j];
        let t = (dir - nj * dir.dot(nj)).normalize_or_zero();
        let mut sf = SideFinder::new(self.centres[j], nj, t, self.side_search);
        let k = self.key(self.centres[j]);
        for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(v) = self.machined.get(&(k.0 + dx, k.1 + dy)) {
                    for &m in v {
                        sf.machined(self.centres[m as usize]);
                    }
                }
            }
        }
        let (side, neighbour) = sf.result();
        let alpha = nj.dot(DVec3::Z).clamp(-1.0, 1.0).acos();
        wd::working_diameter(&Case {
            d: self.d,
            ap: self.ap,
            neighbour,
            alpha,
            af: feed_angle(nj, DVec3::Z, t),
            side,
        })
    }
}

/// D_w along an order: each point cut in the direction it is reached from the
/// previous one, with the points before it machined — the rule the paper search
/// applies to its candidates. A point reached by a jump (farther than `jump`:
/// the tool retracts and plunges there), or with `retract` set, is cut in the
/// direction it leaves in. Returns D_w per position and whether the step into
/// it was a jump. `tick` hears of the positions done now and then.
fn sequence_dw(
    mut ev: Evaluator,
    order: &[usize],
    jump: f64,
    retract: &[bool],
    tick: &dyn Fn(usize),
) -> (Vec<f64>, Vec<bool>) {
    let centres = ev.centres;
    let mut out = Vec::with_capacity(order.len());
    let mut jumps = Vec::with_capacity(order.len());
    for k in 0..order.len() {
        let j = order[k];
        let from_prev = (k > 0).then(|| centres[j] - centres[order[k - 1]]);
        let is_jump = from_prev.map(|v| v.length() > jump).unwrap_or(true)
            || retract.get(k).copied().unwrap_or(false);
        let dir = match from_prev {
            Some(v) if !is_jump => v,
            _ if k + 1 < order.len() => centres[order[k + 1]] - centres[j],
            Some(v) => v,
            None => DVec3::X,
        };
        out.push(ev.dw(j, dir.normalize_or_zero()));
        jumps.push(is_jump && k > 0);
        ev.mark(j);
        if k % TICK == TICK - 1 {
            tick(k + 1);
        }
    }
    tick(order.len());
    (out, jumps)
}

/// The paper's search: the order of the points (indices), and per position
/// whether the step into it retracts (the step guard could not avoid a larger
/// D_w change there: the spindle changes speed while the tool is clear).
/// `tick` hears of the points placed now and then.
#[allow(clippy::too_many_arguments)]
fn paper_search(
    centres: &[DVec3],
    normals: &[DVec3],
    d: f64,
    p: &ReorderParams,
    side_search: f64,
    spacing: f64,
    jump: f64,
    tick: &dyn Fn(usize),
) -> (Vec<usize>, Vec<bool>) {
    let n = centres.len();
    let border = hull(centres);
    let start = match p.start {
        Start::Lowest => *border
            .iter()
            .min_by(|a, b| centres[**a].z.total_cmp(&centres[**b].z))
            .unwrap_or(&0),
        Start::Highest => *border
            .iter()
            .max_by(|a, b| centres[**a].z.total_cmp(&centres[**b].z))
            .unwrap_or(&0),
        Start::Index(i) => i.min(n - 1),
        Start::Random(seed) => {
            border[(seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407)
                >> 33) as usize
                % border.len()]
        }
    };
    let r0 = p.radius.unwrap_or(1.5 * spacing).max(1e-6);
    let mut unv = Unvisited::new(centres, r0);
    let mut ev = Evaluator {
        centres,
        normals,
        d,
        ap: p.ap,
        side_search,
        machined: FxHashMap::default(),
    };
    let mut order = Vec::with_capacity(n);
    let mut retract = vec![false];
    let mut cur = start;
    let mut cur_dir = DVec3::ZERO;
    // D_w at the current point; `None` where the tool has just plunged (at the
    // start, after a jump): it then cuts in the direction it leaves in, so each
    // candidate is compared with the current point's D_w for that direction.
    let mut cur_dw: Option<f64> = None;
    let mut cand = Vec::new();
    loop {
        order.push(cur);
        unv.remove(cur, xy(centres[cur]));
        ev.mark(cur);
        if order.len() % TICK == 0 || order.len() == n {
            tick(order.len());
        }
        if order.len() == n {
            break;
        }
        let mut r = r0;
        loop {
            unv.within(centres, xy(centres[cur]), r, &mut cand);
            if cand.len() >= p.n_min.min(n - order.len()) {
                break;
            }
            r *= 1.5;
        }
        let mut best: Option<(usize, f64, f64, DVec3, f64)> = None;
        let mut seen = 0;
        loop {
            for &j in &cand[seen..] {
                let j = j as usize;
                let dir = (centres[j] - centres[cur]).normalize_or_zero();
                let dw = ev.dw(j, dir);
                let diff = (dw - cur_dw.unwrap_or_else(|| ev.dw(cur, dir))).abs();
                let straight = dir.dot(cur_dir);
                let better = match best {
                    None => true,
                    Some((_, bd, bs, _, _)) => {
                        diff < bd - p.tie || ((diff - bd).abs() <= p.tie && straight > bs)
                    }
                };
                if better {
                    best = Some((j, diff, straight, dir, dw));
                }
            }
            // The step guard: a dead end (every candidate changes D_w by more
            // than max_step) widens the search, up to `guard_reach` × the radius.
            let stuck = matches!((best, p.max_step), (Some((_, bd, ..)), Some(m)) if bd > m);
            if !stuck || r > p.guard_reach * r0 {
                break;
            }
            r *= 1.5;
            seen = cand.len();
            unv.within_ring(centres, xy(centres[cur]), r / 1.5, r, &mut cand);
        }
        let (j, diff, _, dir, dw) = best.unwrap_or((cand[0] as usize, 0.0, 0.0, DVec3::ZERO, 0.0));
        let far = (centres[j] - centres[cur]).length() > jump;
        let forced = !far && p.max_step.is_some_and(|m| diff > m);
        let jumped = far || forced;
        cur_dw = (!jumped).then_some(dw);
        cur_dir = if jumped { DVec3::ZERO } else { dir };
        cur = j;
        retract.push(forced);
    }
    (order, retract)
}

/// The optimised method: passes as units, 2-opt from the original order.
/// `tick(done, total)` hears of the 2-opt's sweeps over the passes.
fn optimised(
    centres: &[DVec3],
    dw: &[f64],
    passes: &[(usize, usize)],
    p: &ReorderParams,
    tick: &dyn Fn(usize, usize),
) -> (Vec<(usize, bool)>, [f64; 3], [f64; 3]) {
    let nspeed = |i: usize| 1000.0 * p.vc / (std::f64::consts::PI * dw[i].max(1e-6));
    // Ends of a pass in a direction: (first point, second, second last, last).
    let ends = |(a, b): (usize, usize), rev: bool| if rev { (b - 1, a) } else { (a, b - 1) };
    let dir_at = |from: usize, to: usize| (centres[to] - centres[from]).normalize_or_zero();
    let joint = |x: (usize, bool), y: (usize, bool)| -> [f64; 3] {
        let (_, xl) = ends(passes[x.0], x.1);
        let (yf, _) = ends(passes[y.0], y.1);
        let dn = (nspeed(xl) - nspeed(yf)).abs();
        let link = (centres[yf] - centres[xl]).length();
        // Direction at the end of x vs the start of y.
        let (xa, xb) = passes[x.0];
        let dx = if xb - xa >= 2 {
            if x.1 {
                dir_at(xa + 1, xa)
            } else {
                dir_at(xb - 2, xb - 1)
            }
        } else {
            DVec3::ZERO
        };
        let (ya, yb) = passes[y.0];
        let dy = if yb - ya >= 2 {
            if y.1 {
                dir_at(yb - 1, yb - 2)
            } else {
                dir_at(ya, ya + 1)
            }
        } else {
            DVec3::ZERO
        };
        let turn = if dx == DVec3::ZERO || dy == DVec3::ZERO {
            0.0
        } else {
            dx.dot(dy).clamp(-1.0, 1.0).acos()
        };
        [dn, link, turn]
    };
    let cost_terms = |seq: &[(usize, bool)]| {
        let mut t = [0.0; 3];
        for w in seq.windows(2) {
            let j = joint(w[0], w[1]);
            for k in 0..3 {
                t[k] += j[k];
            }
        }
        t
    };
    let weighted = |t: [f64; 3]| p.weights[0] * t[0] + p.weights[1] * t[1] + p.weights[2] * t[2];
    let mut seq: Vec<(usize, bool)> = (0..passes.len()).map(|i| (i, false)).collect();
    let original = cost_terms(&seq);
    let jc = |a: (usize, bool), b: (usize, bool)| {
        let j = joint(a, b);
        p.weights[0] * j[0] + p.weights[1] * j[1] + p.weights[2] * j[2]
    };
    // 2-opt: reverse seq[i..=k] (the passes' order and their directions).
    let total = p.iterations * seq.len();
    for it in 0..p.iterations {
        let mut improved = false;
        for i in 1..seq.len() {
            if i % 64 == 0 {
                tick(it * seq.len() + i, total);
            }
            for k in i..seq.len() {
                let before = jc(seq[i - 1], seq[i])
                    + if k + 1 < seq.len() {
                        jc(seq[k], seq[k + 1])
                    } else {
                        0.0
                    };
                let (ri, rk) = ((seq[k].0, !seq[k].1), (seq[i].0, !seq[i].1));
                let after = jc(seq[i - 1], ri)
                    + if k + 1 < seq.len() {
                        jc(rk, seq[k + 1])
                    } else {
                        0.0
                    };
                // Reversing a segment keeps its inner joints (each reversed) — the
                // direction-change term is symmetric, |Δn| and link length too.
                if after < before - 1e-9 {
                    seq[i..=k].reverse();
                    for s in &mut seq[i..=k] {
                        s.1 = !s.1;
                    }
                    improved = true;
                }
            }
        }
        if !improved {
            break;
        }
    }
    tick(total, total);
    let reordered = cost_terms(&seq);
    debug_assert!(weighted(reordered) <= weighted(original) + 1e-6);
    (seq, original, reordered)
}

/// Points between two reports of progress.
const TICK: usize = 4096;

/// The pass as the pipeline runs it.
pub static INFO: PassInfo = PassInfo {
    name: "reorder",
    needs: &[Need::Part, Need::Machine],
    changes: Changes::Order,
    does: "cutting points of 3-axis ball-end operations reordered so the machining runs better with spindle control, or kept; the thesis's search on request; links gouge-checked or retracted (paper 000, thesis 5)",
};

/// Reordering as a pass; what it did stays with it for the report.
pub struct ReorderPass {
    pub params: ReorderParams,
    pub outcome: Option<Outcome>,
}

/// What a reordering did, beside the program.
pub struct Outcome {
    pub stats: ReorderStats,
    pub dw_original: Vec<f64>,
    pub dw_reordered: Vec<f64>,
    pub jump_original: Vec<bool>,
    pub jump_reordered: Vec<bool>,
    /// The indicators of both orders.
    pub before: OrderIndicators,
    pub after: OrderIndicators,
    /// The default method's conclusion (`None` for the others).
    pub verdict: Option<Verdict>,
    /// The candidates the default method measured.
    pub tried: Vec<run::Tried>,
}

impl ReorderPass {
    pub fn new(params: ReorderParams) -> ReorderPass {
        ReorderPass {
            params,
            outcome: None,
        }
    }
}

impl Pass for ReorderPass {
    fn info(&self) -> &'static PassInfo {
        &INFO
    }

    fn run(&mut self, program: &mut Program, cx: &Context) -> Result<(), PassError> {
        let input = |message: String| PassError::Input {
            pass: INFO.name,
            message,
        };
        let r = reorder_in(program, cx, &self.params).map_err(|e| input(e.to_string()))?;
        let rapid = cx.machine.rapid;
        let mut before = indicators(
            program,
            &r.dw_original,
            &r.jump_original,
            self.params.vc,
            rapid,
        );
        let mut after = indicators(
            &r.program,
            &r.dw_reordered,
            &r.jump_reordered,
            self.params.vc,
            rapid,
        );
        // Both orders as they will run, with spindle control.
        if let Some(surface) = cx.surface() {
            let phase = "reorder: both orders measured as run";
            let run = |p: &Program, done: usize| {
                cx.progress(phase, done, 2);
                let m = run::measure(p, surface, &cx.machine, &self.params.speed)
                    .map_err(|e| input(e.to_string()));
                cx.progress(phase, done + 1, 2);
                m
            };
            before.as_run = run(program, 0)?;
            after.as_run = if r.verdict == Some(Verdict::Kept) {
                cx.progress(phase, 2, 2);
                before.as_run
            } else {
                run(&r.program, 1)?
            };
            before.vc_deviation_share = before.as_run.vc_deviation_share;
            after.vc_deviation_share = after.as_run.vc_deviation_share;
        }
        *program = r.program;
        self.outcome = Some(Outcome {
            stats: r.stats,
            dw_original: r.dw_original,
            dw_reordered: r.dw_reordered,
            jump_original: r.jump_original,
            jump_reordered: r.jump_reordered,
            before,
            after,
            verdict: r.verdict,
            tried: r.tried,
        });
        Ok(())
    }
}

/// Range of the change of a quantity between successive points.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Steps {
    pub min: f64,
    pub max: f64,
}

/// Range of |ΔD_w| between points cut one after the other, and its largest
/// value across a jump (retract and plunge), mm.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct DwSteps {
    pub min: f64,
    pub max: f64,
    pub max_across_jumps: f64,
}

/// What an order of cutting points costs: successive changes of D_w
/// (evaluated for the direction each point is reached from and the material
/// cut before it) and of the spindle speed for constant cutting speed, plus
/// path figures.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct OrderIndicators {
    pub delta_d_w: DwSteps,
    /// |Δn| between points cut one after the other, 1/min.
    pub delta_n: Steps,
    /// Σ|Δn| between points cut one after the other, 1/min.
    pub total_variation_n: f64,
    pub jumps: usize,
    pub cutting_mm: f64,
    pub link_mm: f64,
    pub rapids: usize,
    pub time_s: f64,
    pub points: usize,
    /// Share of the cutting points whose spindle speed, under control, misses
    /// the constant-cutting-speed target by more than 5 %.
    pub vc_deviation_share: f64,
    /// The order as it will run with spindle control.
    pub as_run: run::RunMeasures,
}

/// The indicators of program `p` whose cutting points have working diameters
/// `dw` (in cutting order) and jumps `jump` before them.
pub fn indicators(
    p: &Program,
    dw: &[f64],
    jump: &[bool],
    vc: f64,
    rapid_rate: f64,
) -> OrderIndicators {
    let n: Vec<f64> = dw.iter().map(|d| wd::spindle_speed(vc, *d)).collect();
    // Changes between points cut one after the other; steps across jumps
    // (retract and plunge) are reported apart: the spindle has time there.
    let steps = |v: &[f64], across: bool| -> (Steps, f64) {
        let d: Vec<f64> = (1..v.len())
            .filter(|&k| jump.get(k).copied().unwrap_or(false) == across)
            .map(|k| (v[k] - v[k - 1]).abs())
            .collect();
        let min = d.iter().copied().fold(f64::INFINITY, f64::min);
        (
            Steps {
                min: if min.is_finite() { min } else { 0.0 },
                max: d.iter().copied().fold(0.0, f64::max),
            },
            d.iter().sum(),
        )
    };
    let (delta_d_w, _) = steps(dw, false);
    let (delta_n, total_variation_n) = steps(&n, false);
    let (across, _) = steps(dw, true);
    let s = millplan_nc::stats::summarize(p, rapid_rate);
    OrderIndicators {
        delta_d_w: DwSteps {
            min: delta_d_w.min,
            max: delta_d_w.max,
            max_across_jumps: across.max,
        },
        delta_n,
        total_variation_n,
        jumps: jump.iter().filter(|j| **j).count(),
        cutting_mm: s.cutting_mm,
        link_mm: s.rapid_mm,
        rapids: s.moves.rapid,
        time_s: s.time_s,
        points: dw.len(),
        vc_deviation_share: 0.0,
        as_run: run::RunMeasures::default(),
    }
}

/// Reorders every 3-axis ball-end operation of a program against `mesh`.
pub fn reorder(
    program: &Program,
    mesh: &TriMesh,
    p: &ReorderParams,
) -> Result<Reordered, ReorderError> {
    let cx = Context::new(crate::machine::Machine::default()).with_part(mesh);
    reorder_in(program, &cx, p)
}

/// The ball diameter of an operation the pass reorders, `None` for one it
/// leaves as it is: the program's ball, or (a tool the program gives no
/// shape: G-code names tools by number) `ball_d`; three-axis operations
/// of straight moves only, since a reordered path links points by straight
/// moves, which would cut arcs short.
pub fn reorderable(op: &millplan_nc::Operation, ball_d: Option<f64>) -> Option<f64> {
    let d = match op.tool.as_ref().and_then(|t| t.cutter) {
        Some(c) if c.kind == millplan_nc::CutterKind::Ball => c.d,
        Some(_) => return None,
        None => ball_d?,
    };
    let tilted = op
        .orients
        .iter()
        .any(|o| o.axis.is_none_or(|v| (v - DVec3::Z).length() >= 1e-9));
    let straight = op.frame.is_none() && op.arcs.is_empty() && op.cycles.is_empty();
    (straight && !tilted).then_some(d)
}

/// [`reorder`] with the part's analyses from a pipeline's context.
pub fn reorder_in(
    program: &Program,
    cx: &Context,
    p: &ReorderParams,
) -> Result<Reordered, ReorderError> {
    if !(p.ap > 0.0
        && p.vc > 0.0
        && p.n_min >= 1
        && p.tie >= 0.0
        && p.plunge_factor > 0.0
        && p.time_slack >= 0.0)
    {
        return Err(ReorderError::Invalid(
            "ap, vc, plunge factor must be positive, n_min ≥ 1, the time slack ≥ 0".into(),
        ));
    }
    let (Some(mesh), Some(surface), Some(part)) = (cx.mesh(), cx.surface(), cx.drop_mesh()) else {
        return Err(ReorderError::Invalid("the part surface is needed".into()));
    };
    let mut out = program.clone();
    let mut stats = ReorderStats::default();
    let (mut dw_original, mut dw_reordered) = (Vec::new(), Vec::new());
    let (mut jump_original, mut jump_reordered) = (Vec::new(), Vec::new());
    let mut tried = Vec::new();
    let mut verdicts = Vec::new();
    let mut any = false;
    // Progress phases name their operation where there are several.
    let several = program.operations.len() > 1;
    for (oi, op) in program.operations.iter().enumerate() {
        let label = if several {
            format!(" (operation {})", oi + 1)
        } else {
            String::new()
        };
        let Some(d) = reorderable(op, p.speed.ball_d) else {
            continue;
        };
        let (pts, idx) = crate::speed::cutting_points(op);
        if pts.len() < 2 {
            continue;
        }
        any = true;
        let mut cp = contact::Params::new(d, p.ap);
        cp.convention = contact::detect_convention(surface, &pts, d / 2.0).chosen;
        let (centres, located) = contact::locate(surface, &pts, &cp);
        let normals: Vec<DVec3> = located.iter().map(|l| l.1).collect();
        let mut spacing: Vec<f64> = pts
            .windows(2)
            .filter(|w| w[0].pass == w[1].pass)
            .map(|w| (w[1].cl - w[0].cl).length())
            .filter(|d| *d > 1e-9)
            .collect();
        spacing.sort_by(f64::total_cmp);
        let spacing = spacing.get(spacing.len() / 2).copied().unwrap_or(1.0);
        let side_search = contact::stepover_search_radius(|i| centres[i], &pts, 0.6 * d);
        // Steps longer than this retract and plunge: the spindle has time there.
        let jump = 3.0 * spacing.max(side_search / 1.6);
        let top = pts
            .iter()
            .map(|q| q.cl.z)
            .fold(f64::NEG_INFINITY, f64::max)
            .max(mesh.bounds().max.z);
        let links = Links {
            op,
            rapid: cx.machine.rapid,
            jump,
            pts: &pts,
            idx: &idx,
            part,
            shape: Shape::Ball { radius: d / 2.0 },
            safe: top + p.clearance,
            p,
        };
        let identity: Vec<usize> = (0..pts.len()).collect();
        let fresh = || Evaluator {
            centres: &centres,
            normals: &normals,
            d,
            ap: p.ap,
            side_search,
            machined: FxHashMap::default(),
        };
        stats.points += pts.len();
        let (order, retract, built) = match p.method {
            Method::Paper => {
                let phase = format!("reorder: thesis search{label}");
                let n = pts.len();
                let (order, retract) =
                    paper_search(&centres, &normals, d, p, side_search, spacing, jump, &|k| {
                        cx.progress(&phase, k, n)
                    });
                let phase = format!("reorder: links checked for gouges{label}");
                let built = links.build_with(&order, &retract, LinkStyle::FromClearance, &|k| {
                    cx.progress(&phase, k, n)
                });
                (order, retract, built)
            }
            Method::Optimised => {
                let res = contact::analyse(surface, &pts, &cp);
                let dw: Vec<f64> = res.iter().map(|r| r.dw).collect();
                let passes = pass_ranges(&pts);
                let phase = format!("reorder: 2-opt over the passes{label}");
                let (seq, before, after) =
                    optimised(&centres, &dw, &passes, p, &|k, n| cx.progress(&phase, k, n));
                stats.passes += passes.len();
                for k in 0..3 {
                    stats.cost_original[k] += before[k];
                    stats.cost_reordered[k] += after[k];
                }
                let order = expand(&passes, &seq);
                let (phase, n) = (
                    format!("reorder: links checked for gouges{label}"),
                    order.len(),
                );
                let built = links.build_with(&order, &[], LinkStyle::FromClearance, &|k| {
                    cx.progress(&phase, k, n)
                });
                (order, Vec::new(), built)
            }
            Method::AsRun => {
                // The working diameters as the spindle control has them.
                let phase = format!("reorder: candidate orders measured{label}");
                let s = run::search(program, oi, cx, &links, jump, &|k, n| {
                    cx.progress(&phase, k, n)
                })
                .map_err(|e| ReorderError::Invalid(e.to_string()))?;
                tried.extend(s.tried);
                verdicts.push(s.verdict);
                let jumps = |order: &[usize], retracted: &[bool]| -> Vec<bool> {
                    (0..order.len())
                        .map(|m| {
                            m > 0
                                && (retracted.get(m).copied().unwrap_or(false)
                                    || (pts[order[m]].cl - pts[order[m - 1]].cl).length() > jump)
                        })
                        .collect()
                };
                jump_original.extend(jumps(&identity, &[]));
                dw_original.extend(s.dw_original);
                dw_reordered.extend(s.dw_chosen);
                let Some((order, built)) = s.chosen else {
                    jump_reordered.extend(jumps(&identity, &[]));
                    continue;
                };
                jump_reordered.extend(jumps(&order, &built.retracted));
                stats.direct_links += built.direct;
                stats.retracts += built.retracts;
                out.operations[oi] = links.operation(built.moves, p.method);
                continue;
            }
        };
        let (phase, n) = (format!("reorder: D_w along both orders{label}"), pts.len());
        let (a, b) = sequence_dw(fresh(), &identity, jump, &[], &|k| {
            cx.progress(&phase, k, 2 * n)
        });
        dw_original.extend(a);
        jump_original.extend(b);
        // D_w by the thesis's rule, where the search forced a retract.
        let (a, b) = sequence_dw(fresh(), &order, jump, &retract, &|k| {
            cx.progress(&phase, n + k, 2 * n)
        });
        dw_reordered.extend(a);
        jump_reordered.extend(b);
        stats.direct_links += built.direct;
        stats.retracts += built.retracts;
        out.operations[oi] = links.operation(built.moves, p.method);
    }
    if !any {
        return Err(ReorderError::NoBallOperation);
    }
    let verdict = (p.method == Method::AsRun).then(|| {
        if verdicts.contains(&Verdict::Improved) {
            Verdict::Improved
        } else {
            Verdict::Kept
        }
    });
    Ok(Reordered {
        program: out,
        stats,
        dw_original,
        dw_reordered,
        jump_original,
        jump_reordered,
        verdict,
        tried,
    })
}

/// The ranges of the passes of the cutting points (consecutive points of one pass).
fn pass_ranges(pts: &[PathPoint]) -> Vec<(usize, usize)> {
    let mut passes = Vec::new();
    let mut a = 0;
    for i in 1..=pts.len() {
        if i == pts.len() || pts[i].pass != pts[a].pass {
            passes.push((a, i));
            a = i;
        }
    }
    passes
}

/// The points of passes in sequence, each forwards or reversed.
fn expand(passes: &[(usize, usize)], seq: &[(usize, bool)]) -> Vec<usize> {
    seq.iter()
        .flat_map(|&(pi, rev)| {
            let (a, b) = passes[pi];
            let v: Vec<usize> = if rev {
                (a..b).rev().collect()
            } else {
                (a..b).collect()
            };
            v
        })
        .collect()
}

/// How a retract ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LinkStyle {
    /// Plunge at the plunge feed all the way from the clearance height (the
    /// paper and optimised methods).
    FromClearance,
    /// Rapid down to `APPROACH` above the point, then plunge; a direct link
    /// only where it is quicker than a retract.
    Low,
}

/// Height above a point at which a retract's plunge begins (`LinkStyle::Low`), mm.
const APPROACH: f64 = 1.0;

/// An operation rebuilt from an order of its cutting points.
struct Built {
    moves: Vec<Move>,
    direct: usize,
    retracts: usize,
    /// Per position, whether the tool retracted before it.
    retracted: Vec<bool>,
}

/// What it takes to link the cutting points of an operation in a new order.
struct Links<'a> {
    op: &'a Operation,
    /// The machine's rapid rate, mm/min.
    rapid: f64,
    /// Links longer than this retract (`LinkStyle::Low`), mm.
    jump: f64,
    pts: &'a [PathPoint],
    idx: &'a [usize],
    part: &'a DropMesh,
    shape: Shape,
    /// Clearance height of retracts.
    safe: f64,
    p: &'a ReorderParams,
}

impl Links<'_> {
    /// Whether points i and j are near enough to link directly
    /// (`LinkStyle::Low`): no farther apart than a jump, or one move of the
    /// original program apart. Farther, a retract is quicker or about as quick.
    fn near(&self, i: usize, j: usize) -> bool {
        (self.pts[j].cl - self.pts[i].cl).length() <= self.jump || self.retraces(i, j)
    }

    /// Whether the tool goes from point i to point j directly: along a move
    /// of the original path, or when the link is proven free of gouges (even
    /// one between neighbouring points can cut into a concave region, and a
    /// chord between passes over a convex one) and, with `LinkStyle::Low`, the
    /// points are [near](Self::near).
    fn direct(&self, i: usize, j: usize, style: LinkStyle) -> bool {
        let pts = self.pts;
        if i.abs_diff(j) == 1 && pts[i].pass == pts[j].pass {
            return true;
        }
        if style == LinkStyle::Low {
            if self.retraces(i, j) {
                return true;
            }
            if !self.near(i, j) {
                return false;
            }
        }
        link_is_clean(
            self.part,
            &self.shape,
            pts[i].cl,
            pts[j].cl,
            self.p.gouge_tol,
        )
    }

    /// Whether the move from point i to point j retraces one move of the
    /// original program (either way): it is then that move.
    fn retraces(&self, i: usize, j: usize) -> bool {
        let (a, b) = (i.min(j), i.max(j));
        b == a + 1 && self.idx[b] == self.idx[a] + 1
    }

    /// The moves of the cutting points in `order`: the first reached by a rapid
    /// and a plunge; each next one [directly](Self::direct) or by a retract, a
    /// rapid and a plunge. `retract` forces a retract before a position.
    fn build(&self, order: &[usize], retract: &[bool], style: LinkStyle) -> Built {
        self.build_with(order, retract, style, &|_| {})
    }

    /// [`Links::build`], `tick` hearing of the links checked now and then
    /// (from any thread).
    fn build_with(
        &self,
        order: &[usize],
        retract: &[bool],
        style: LinkStyle,
        tick: &(dyn Fn(usize) + Sync),
    ) -> Built {
        let (op, pts, idx, p) = (self.op, self.pts, self.idx, self.p);
        let feed_of = |k: usize| op.moves[idx[k]].feed;
        let spindle = op.moves[idx[0]].spindle;
        let tmpl = op.moves[idx[0]];
        // Every new link is checked for gouges (even one between neighbouring
        // points can cut into a concave region), in parallel.
        let checked = std::sync::atomic::AtomicUsize::new(0);
        let clean: Vec<bool> = {
            use rayon::prelude::*;
            (0..order.len())
                .into_par_iter()
                .map(|m| {
                    if m % TICK == TICK - 1 {
                        let done = checked.fetch_add(TICK, std::sync::atomic::Ordering::Relaxed);
                        tick(done + TICK);
                    }
                    m == 0
                        || (!retract.get(m).copied().unwrap_or(false)
                            && self.direct(order[m - 1], order[m], style))
                })
                .collect()
        };
        tick(order.len());
        let mut b = Built {
            moves: Vec::with_capacity(order.len() + 8),
            direct: 0,
            retracts: 0,
            retracted: vec![false; order.len()],
        };
        let mut prev: Option<DVec3> = None;
        for (m, &k) in order.iter().enumerate() {
            let q = pts[k].cl;
            let line = op.moves[idx[k]].line;
            let cut = Move {
                end: q,
                line,
                kind: MoveKind::Linear,
                feed: feed_of(k),
                spindle,
                ..tmpl
            };
            // A rapid at height z above a point.
            let rapid_to = |at: DVec3, z: f64| Move {
                end: DVec3::new(at.x, at.y, z),
                kind: MoveKind::Rapid,
                feed: 0.0,
                line,
                ..tmpl
            };
            let plunge = Move {
                feed: feed_of(k) * p.plunge_factor,
                ..cut
            };
            if m > 0 && clean[m] {
                b.direct += 1;
                b.moves.push(cut);
                prev = Some(q);
                continue;
            }
            if let Some(a) = prev {
                b.retracts += 1;
                b.retracted[m] = true;
                b.moves.push(rapid_to(a, self.safe));
            }
            b.moves.push(rapid_to(q, self.safe));
            if style == LinkStyle::Low && self.safe > q.z + APPROACH {
                b.moves.push(rapid_to(q, q.z + APPROACH));
            }
            b.moves.push(plunge);
            prev = Some(q);
        }
        if let Some(a) = prev {
            b.moves.push(Move {
                end: DVec3::new(a.x, a.y, self.safe),
                kind: MoveKind::Rapid,
                feed: 0.0,
                ..tmpl
            });
        }
        b
    }

    /// The operation with `moves` in place of its own: events keep their
    /// order, those between moves move to the start, the trailing ones stay at
    /// the end, and a comment says what was done.
    fn operation(&self, moves: Vec<Move>, method: Method) -> Operation {
        let mut o = self.op.clone();
        let n_old = o.moves.len() as u32;
        let n_new = moves.len() as u32;
        for e in &mut o.events {
            e.at = if e.at >= n_old { n_new } else { 0 };
        }
        o.events.sort_by_key(|e| e.at);
        o.events.insert(
            0,
            millplan_nc::Event {
                at: 0,
                line: 0,
                kind: EventKind::Comment(format!(
                    "points reordered by millplan ({method:?} method)"
                )),
            },
        );
        o.moves = moves;
        o.arcs.clear();
        o.cycles.clear();
        o.start = millplan_nc::UNKNOWN;
        o
    }
}

/// A straight move from a to b is clean when the tool tip never dips below the
/// drop-cutter height along it (sampled every 0.05 mm; the ends are points of
/// the original path and are not checked again).
fn link_is_clean(part: &DropMesh, shape: &Shape, a: DVec3, b: DVec3, tol: f64) -> bool {
    let n = (((b - a).length() / 0.05).ceil() as usize).max(2);
    (1..n).all(|k| {
        let q = a.lerp(b, k as f64 / n as f64);
        !part.rises_above(shape, xy(q), q.z + tol)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_square_with_inner_points() {
        let pts: Vec<DVec3> = [
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (0.5, 0.5),
            (0.2, 0.7),
        ]
        .iter()
        .map(|(x, y)| DVec3::new(*x, *y, 0.0))
        .collect();
        let mut h = hull(&pts);
        h.sort();
        assert_eq!(h, vec![0, 1, 2, 3]);
    }

    #[test]
    fn unvisited_grid_removes_and_finds() {
        let pts: Vec<DVec3> = (0..100)
            .map(|i| DVec3::new((i % 10) as f64, (i / 10) as f64, 0.0))
            .collect();
        let mut u = Unvisited::new(&pts, 1.5);
        let mut out = Vec::new();
        u.within(&pts, DVec2::new(0.0, 0.0), 1.0, &mut out);
        out.sort();
        assert_eq!(out, vec![0, 1, 10]);
        u.remove(1, DVec2::new(1.0, 0.0));
        u.within(&pts, DVec2::new(0.0, 0.0), 1.0, &mut out);
        out.sort();
        assert_eq!(out, vec![0, 10]);
        for (i, p) in pts.iter().enumerate() {
            u.remove(i, xy(*p));
        }
        u.within(&pts, DVec2::new(5.0, 5.0), 100.0, &mut out);
        assert!(out.is_empty());
    }
}
