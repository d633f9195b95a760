//! A machining-time estimate that knows the controller: every block is timed
//! the way a look-ahead controller moves it, not as length / feed.
//!
//! The model (docs/time.md):
//!
//! * Blocks are straight lines in machine-axis space (X Y Z mm, A B C
//!   degrees), interpolated linearly as a controller without TCP does. A
//!   block's path parameter is its XYZ length, or for a rotary-only block its
//!   rotary length in degrees (the G94 convention of spec
//!   kinematics-access-tools §1.10).
//! * Speed along a block is capped by the programmed feed (the block time the
//!   F word asks for, G94 or G93), by the rapid rate on rapids, by the
//!   feed maximum, and by every moving axis's velocity limit; the path
//!   acceleration (and jerk, where the machine file gives it) by every moving
//!   axis's limit scaled by its share of the motion.
//! * Junctions between feed blocks are passed at a speed set by the direction
//!   change and each axis's acceleration: the velocity of axis i jumps by
//!   |Δe_i|·v (e the block's unit direction), and the controller blends that
//!   change over a distance ℓ = min(both block lengths, [`BLEND_MM`]), so
//!   |Δe_i|·v²/ℓ ≤ a_i. A smooth curve cut in short chords then runs at the
//!   centripetal limit v = √(a·R), independent of the chord length; a sharp
//!   corner is slowed to √(a·ℓ/|Δe|). Collinear blocks keep their speed.
//! * Rapids, dwells and changes between XYZ and rotary-only blocks stop the
//!   motion (exact stop, as controls do at G0 ends by default).
//! * A backward and a forward pass over the junction speeds (the look-ahead
//!   of a real controller) make every speed change reachable within its
//!   block; each block then gets its time in closed form: trapezoidal
//!   profiles without jerk, symmetric S-curves (zero acceleration at block
//!   ends) with it.
//!
//! Unknown limits never read as zero: a machine file without axis data gets
//! the conservative defaults of [`DEFAULT_LINEAR_ACCEL`] and friends.

mod planner;
mod stream;

pub use planner::{BlockCtl, PathMode, Planner, PlannerKind, Profile};

use crate::machine::Machine;
use millplan_geom::DVec3;
use millplan_nc::ir::{self, known, FeedMode, Program};
use millplan_nc::write::{cycle_moves, CycleStep};

/// Linear-axis acceleration used when the machine file does not give one,
/// mm/s². Low on purpose (about 0.1 g; machining centres do 2–10 m/s²), so an
/// unknown machine's estimate errs long rather than short.
pub const DEFAULT_LINEAR_ACCEL: f64 = 1000.0;
/// Rotary-axis velocity used when the file does not give one, degrees/min
/// (10 1/min, slow for a trunnion table).
pub const DEFAULT_ROTARY_VELOCITY: f64 = 3600.0;
/// Rotary-axis acceleration used when the file does not give one, degrees/s².
pub const DEFAULT_ROTARY_ACCEL: f64 = 720.0;
/// Distance over which a controller blends the direction change at a
/// junction at most, mm (or degrees between rotary-only blocks): the order of
/// a contour tolerance's rounding zone (Sinumerik G64/G642, Heidenhain cycle
/// 32, LinuxCNC G64 P). A shorter block blends over its own length.
pub const BLEND_MM: f64 = 0.2;

/// One block in machine coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisMove {
    /// X Y Z (mm) and A B C (degrees) at the end of the block, machine
    /// coordinates; an axis the machine lacks stays 0.
    pub target: [f64; 6],
    pub kind: MoveKind,
}

/// What a block asks of the control.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MoveKind {
    /// G0: every axis as fast as it may, within the rapid rate.
    Rapid,
    /// A feed block; `nominal_min` is the block time the programmed F asks
    /// for (G94: length / F, G93: 1 / F), minutes. Zero or less: no feed cap
    /// (the axis limits alone).
    Feed { nominal_min: f64 },
    /// A dwell of `s` seconds (the motion stops).
    Dwell { s: f64 },
}

/// The estimate and what it is made of. All times in seconds.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct TimeEstimate {
    /// With acceleration, jerk and axis velocities.
    pub total_s: f64,
    /// What the program asks for: feed blocks at their F, rapids at the
    /// rapid rate over their XYZ length, dwells.
    pub nominal_s: f64,
    /// Per block of the input, in its order.
    #[serde(skip)]
    pub per_move_s: Vec<f64>,
    /// Of `total_s`: rapids, feed blocks, dwells.
    pub rapid_s: f64,
    pub feed_s: f64,
    pub dwell_s: f64,
    /// Feed blocks whose programmed feed some axis's velocity limit (or the
    /// feed maximum) does not allow.
    pub velocity_limited_blocks: usize,
    /// Feed blocks that never reach their programmed (or axis-capped) speed.
    pub accel_limited_blocks: usize,
    /// The planner model the estimate followed (`generic`, `linuxcnc-2.9`,
    /// ...); empty for a block sequence timed without a program.
    pub planner: &'static str,
    /// Of `total_s` without dwells: the time of the blocks under each
    /// path-control mode, in the order the modes first occur.
    pub by_mode: Vec<ModeTime>,
}

/// The time of the blocks under one path-control mode.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ModeTime {
    /// `exact stop`, `blend`, `blend 0.01 mm`.
    pub mode: String,
    pub time_s: f64,
    /// Machine blocks (arcs in chords, cycles spelled out).
    pub blocks: usize,
}

impl TimeEstimate {
    /// How much longer than nominal, as a fraction (0.08 = 8 % longer).
    pub fn overhead(&self) -> f64 {
        if self.nominal_s > 0.0 {
            self.total_s / self.nominal_s - 1.0
        } else {
            0.0
        }
    }
}

/// Per-axis limits in the units the estimate works in: X Y Z A B C,
/// velocities per second, accelerations per second², jerks per second³
/// (`INFINITY`: not limited).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    pub velocity: [f64; 6],
    pub accel: [f64; 6],
    pub jerk: [f64; 6],
    /// Rapid rate (mm/s, along XYZ).
    pub rapid: f64,
    /// Highest cutting feed (mm/s, along XYZ).
    pub feed_max: f64,
    /// The control's planner (the machine file's `[control] planner`).
    pub planner: Planner,
}

impl Limits {
    /// The machine's limits, with the documented defaults where it has none.
    pub fn of(machine: &Machine) -> Limits {
        let rapid = machine.rapid / 60.0;
        let mut l = Limits {
            velocity: [rapid, rapid, rapid, 0.0, 0.0, 0.0],
            accel: [DEFAULT_LINEAR_ACCEL; 6],
            jerk: [f64::INFINITY; 6],
            rapid,
            feed_max: machine.feed_max / 60.0,
            planner: machine.control.planner,
        };
        for i in 3..6 {
            l.velocity[i] = DEFAULT_ROTARY_VELOCITY / 60.0;
            l.accel[i] = DEFAULT_ROTARY_ACCEL;
        }
        let ax = &machine.axes;
        for (i, a) in [ax.x, ax.y, ax.z].iter().enumerate() {
            if let Some(v) = a.velocity {
                l.velocity[i] = v / 60.0;
            }
            if let Some(v) = a.accel {
                l.accel[i] = v;
            }
            if let Some(v) = a.jerk {
                l.jerk[i] = v;
            }
        }
        if let Some(k) = &machine.kinematics {
            for (d, name) in [ax.first, ax.second].iter().zip(k.kind.rotary_names()) {
                let i = rotary_index(name);
                if let Some(v) = d.velocity {
                    l.velocity[i] = v / 60.0;
                }
                if let Some(v) = d.accel {
                    l.accel[i] = v;
                }
                if let Some(v) = d.jerk {
                    l.jerk[i] = v;
                }
            }
        }
        l
    }
}

/// Index of a rotary axis letter in an [`AxisMove`] target (A 3, B 4, C 5).
pub fn rotary_index(name: char) -> usize {
    match name.to_ascii_uppercase() {
        'A' => 3,
        'B' => 4,
        _ => 5,
    }
}

/// Below this a block does not move (mm or degrees).
const EPS: f64 = 1e-9;

/// One moving block, prepared: its path parameter and what caps its motion.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Block {
    /// Index in the input.
    pub(crate) index: usize,
    /// Path length (XYZ mm, or rotary degrees when `rotary_only`).
    pub(crate) len: f64,
    /// Unit direction: axis displacement per unit of path.
    pub(crate) dir: [f64; 6],
    pub(crate) rotary_only: bool,
    pub(crate) rapid: bool,
    /// Speed cap along the path (per second).
    pub(crate) vcap: f64,
    /// The part of the cap that does not depend on the programmed feed:
    /// the path's rate and the axes' speeds.
    pub(crate) vgeom: f64,
    pub(crate) accel: f64,
    pub(crate) jerk: f64,
    /// The programmed speed is above what the axes allow.
    pub(crate) velocity_limited: bool,
}

/// The blocks that move, and the stops (dwells) between them: `stops[k]` is
/// true when the motion must stop before moving block k.
pub(crate) fn prepare(
    start: [f64; 6],
    moves: &[AxisMove],
    lim: &Limits,
) -> (Vec<Block>, Vec<bool>) {
    let mut blocks = Vec::with_capacity(moves.len());
    let mut stops = Vec::with_capacity(moves.len());
    let mut stop = true;
    let mut here = start;
    for (index, m) in moves.iter().enumerate() {
        match prepare_one(index, m, &mut here, lim) {
            Prepared::Dwell => stop = true,
            Prepared::Still => {}
            Prepared::Moves(b) => {
                blocks.push(b);
                stops.push(stop);
                stop = false;
            }
        }
    }
    (blocks, stops)
}

/// What one input block is to the motion.
#[derive(Clone, Copy)]
pub(crate) enum Prepared {
    /// A dwell: the motion stops.
    Dwell,
    /// Nothing moves: the control skips the block.
    Still,
    Moves(Block),
}

/// Input block `index`, `m`, from `here` (moved on to its end unless a
/// dwell), prepared.
pub(crate) fn prepare_one(
    index: usize,
    m: &AxisMove,
    here: &mut [f64; 6],
    lim: &Limits,
) -> Prepared {
    let (rapid, nominal_min) = match m.kind {
        MoveKind::Dwell { .. } => return Prepared::Dwell,
        MoveKind::Rapid => (true, 0.0),
        MoveKind::Feed { nominal_min } => (false, nominal_min),
    };
    let mut d = [0.0; 6];
    for (i, di) in d.iter_mut().enumerate() {
        *di = m.target[i] - here[i];
    }
    *here = m.target;
    let lin = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let rot = (d[3] * d[3] + d[4] * d[4] + d[5] * d[5]).sqrt();
    let (len, rotary_only) = if lin > EPS {
        (lin, false)
    } else if rot > EPS {
        (rot, true)
    } else {
        return Prepared::Still;
    };
    let mut dir = [0.0; 6];
    let (mut vaxes, mut accel, mut jerk) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
    for i in 0..6 {
        dir[i] = d[i] / len;
        let e = dir[i].abs();
        if e > 1e-12 {
            vaxes = vaxes.min(lim.velocity[i] / e);
            accel = accel.min(lim.accel[i] / e);
            jerk = jerk.min(lim.jerk[i] / e);
        }
    }
    let path_cap = if rotary_only {
        f64::INFINITY
    } else if rapid {
        lim.rapid
    } else {
        lim.feed_max
    };
    let mut b = Block {
        index,
        len,
        dir,
        rotary_only,
        rapid,
        vcap: 0.0,
        vgeom: path_cap.min(vaxes),
        accel,
        jerk,
        velocity_limited: false,
    };
    b.at_minutes(nominal_min);
    Prepared::Moves(b)
}

impl Block {
    /// The block's cap when it asks for `nominal_min` minutes (a feed
    /// block; a rapid keeps none but its geometry's).
    pub(crate) fn at_minutes(&mut self, nominal_min: f64) {
        let programmed = programmed_speed(self.rapid, self.len, nominal_min);
        self.vcap = programmed.min(self.vgeom);
        self.velocity_limited = !self.rapid && self.vcap < programmed * (1.0 - 1e-12);
    }
}

/// The speed a block's F asks for along its path (per second; unbounded on
/// rapids and blocks without a time).
fn programmed_speed(rapid: bool, len: f64, nominal_min: f64) -> f64 {
    if rapid || nominal_min <= 0.0 {
        f64::INFINITY
    } else {
        len / (nominal_min * 60.0)
    }
}

/// The highest speed at which the junction between `a` and `b` can be passed
/// (the motion stops when the control has to: around rapids and between XYZ
/// and rotary-only blocks).
#[cfg(test)]
pub(crate) fn junction(a: &Block, b: &Block, lim: &Limits) -> f64 {
    junction_at(a, b, a.vcap.min(b.vcap), lim)
}

/// [`junction`] with the lower of the two blocks' caps given.
#[cfg(test)]
fn junction_at(a: &Block, b: &Block, cap: f64, lim: &Limits) -> f64 {
    if a.rapid || b.rapid || a.rotary_only != b.rotary_only {
        return 0.0;
    }
    junction_len_rule(a, b, cap, a.len.min(b.len).min(BLEND_MM), lim)
}

/// The speed (at most `cap`) at which every axis's velocity change
/// |Δe_i|·v, spread over the blend length `blend`, stays within its
/// acceleration.
pub(crate) fn junction_len_rule(a: &Block, b: &Block, cap: f64, blend: f64, lim: &Limits) -> f64 {
    let mut v = cap;
    for i in 0..6 {
        let de = (b.dir[i] - a.dir[i]).abs();
        if de > 1e-12 {
            v = v.min((lim.accel[i] * blend / de).sqrt());
        }
    }
    v
}

/// Time (s) to change speed by `dv` ≥ 0 at acceleration `a` and jerk `j`,
/// starting and ending with zero acceleration.
fn ramp_time(dv: f64, a: f64, j: f64) -> f64 {
    if dv <= 0.0 {
        0.0
    } else if j.is_infinite() {
        dv / a
    } else if dv >= a * a / j {
        dv / a + a / j
    } else {
        2.0 * (dv / j).sqrt()
    }
}

/// Distance covered while changing speed between `v0` and `v1` (either
/// way): the profiles are symmetric, so the mean speed is the average.
fn ramp_dist(v0: f64, v1: f64, a: f64, j: f64) -> f64 {
    0.5 * (v0 + v1) * ramp_time((v1 - v0).abs(), a, j)
}

/// The highest speed reachable from `v0` within `len`.
pub(crate) fn reach(v0: f64, len: f64, a: f64, j: f64) -> f64 {
    if j.is_infinite() {
        return (v0 * v0 + 2.0 * a * len).sqrt();
    }
    // Full-acceleration profile (dv ≥ a²/j): (v0 + x/2)(x/a + a/j) = len, a
    // quadratic in x = dv.
    let dv_full = a * a / j;
    if ramp_dist(v0, v0 + dv_full, a, j) <= len {
        let qa = 0.5 / a;
        let qb = v0 / a + 0.5 * a / j;
        let qc = v0 * a / j - len;
        let x = (-qb + (qb * qb - 4.0 * qa * qc).max(0.0).sqrt()) / (2.0 * qa);
        return v0 + x.max(dv_full);
    }
    // Jerk-only profile: (v0 + u²/2)·2u/√j = len with u = √dv, the cubic
    // u³ + 2·v0·u − len·√j = 0 (one real root, increasing); Newton from an
    // upper bound converges monotonically.
    let (p, q) = (2.0 * v0, len * j.sqrt());
    let mut u = q.cbrt().min(if p > 0.0 { q / p } else { f64::INFINITY });
    for _ in 0..60 {
        let f = u * u * u + p * u - q;
        let step = f / (3.0 * u * u + p);
        u -= step;
        if step.abs() <= 1e-14 * u.max(1e-300) {
            break;
        }
    }
    v0 + (u * u).min(dv_full)
}

/// Time of one block entered at `v0`, left at `v1` (both reachable from
/// each other within it), cruising at most at `b.vcap`. Also whether the
/// cap is reached.
pub(crate) fn block_time(b: &Block, v0: f64, v1: f64) -> (f64, bool) {
    block_time_at(b, b.vcap, v0, v1)
}

/// [`block_time`] cruising at most at `vc`.
fn block_time_at(b: &Block, vc: f64, v0: f64, v1: f64) -> (f64, bool) {
    let (a, j, len) = (b.accel, b.jerk, b.len);
    let need = |vp: f64| ramp_dist(v0, vp, a, j) + ramp_dist(vp, v1, a, j);
    let (d_up, d_down) = (ramp_dist(v0, vc, a, j), ramp_dist(vc, v1, a, j));
    if d_up + d_down <= len {
        let t = ramp_time(vc - v0, a, j) + ramp_time(vc - v1, a, j) + (len - d_up - d_down) / vc;
        return (t, true);
    }
    let lo0 = v0.max(v1);
    let vp = if j.is_infinite() {
        ((2.0 * a * len + v0 * v0 + v1 * v1) / 2.0)
            .sqrt()
            .clamp(lo0, vc)
    } else {
        // need(vp) increases with vp, like √(vp − lo0) near the lower end
        // (jerk-only ramps): Newton's method on u = √(vp − lo0), where it
        // is smooth, kept inside a shrinking bracket (bisection when a step
        // leaves it).
        let slope = |v0: f64, vp: f64| {
            let dv = vp - v0;
            let t = ramp_time(dv, a, j);
            let dt = if dv <= 0.0 {
                0.0
            } else if dv >= a * a / j {
                1.0 / a
            } else {
                1.0 / (j * dv).sqrt()
            };
            0.5 * t + 0.5 * (v0 + vp) * dt
        };
        // Without jerk the peak would be higher: an upper bound.
        let free = ((2.0 * a * len + v0 * v0 + v1 * v1) / 2.0).sqrt();
        let (mut lo, mut hi) = (0.0f64, (vc.min(free) - lo0).max(0.0).sqrt());
        let mut u = hi;
        for _ in 0..100 {
            let x = lo0 + u * u;
            let f = need(x) - len;
            if f <= 0.0 {
                lo = u;
            } else {
                hi = u;
            }
            if hi - lo <= 1e-12 * hi || f.abs() <= 1e-12 * len {
                break;
            }
            // d need / du = need'(vp)·2u; the slope of a ramp of no
            // change is infinite, so it is taken from the other one.
            let s = |v: f64| {
                if x - v > 0.0 {
                    slope(v, x) * 2.0 * u
                } else {
                    0.5 * (v + x) * 2.0 / j.sqrt()
                }
            };
            let d = s(v0) + s(v1);
            let next = u - f / d;
            let prev = u;
            u = if d > 0.0 && d.is_finite() && next > lo && next < hi {
                next
            } else {
                0.5 * (lo + hi)
            };
            if (u - prev).abs() <= 1e-12 * u {
                break;
            }
        }
        lo0 + u.clamp(lo, hi).powi(2)
    };
    let (t_up, t_down) = (ramp_time(vp - v0, a, j), ramp_time(vp - v1, a, j));
    // What is left (rounding, or the bisection's last step) at the peak.
    let rest = (len - need(vp)).max(0.0);
    (
        t_up + t_down + if vp > 0.0 { rest / vp } else { 0.0 },
        false,
    )
}

/// The speeds at every junction after the look-ahead: `v[k]` entering block
/// k, `v[k + 1]` leaving it (the generic planner, no modes).
#[cfg(test)]
pub(crate) fn plan(blocks: &[Block], stops: &[bool], lim: &Limits) -> Vec<f64> {
    let caps: Vec<f64> = blocks.iter().map(|b| b.vcap).collect();
    let s = planner::shape(blocks, &caps, stops, None, &Planner::default(), lim);
    plan_shaped(&s.blocks, s.vj)
}

/// The junction limits `v` made reachable within every block: a backward
/// and a forward pass.
fn plan_shaped(blocks: &[Block], mut v: Vec<f64>) -> Vec<f64> {
    let n = blocks.len();
    for k in (0..n).rev() {
        v[k] = capped(v[k + 1], v[k], &blocks[k]);
    }
    for k in 0..n {
        v[k + 1] = capped(v[k], v[k + 1], &blocks[k]);
    }
    v
}

/// `want`, or less when it cannot be reached from `from` within the block
/// (the speed is only solved for when the cheap check fails).
fn capped(from: f64, want: f64, b: &Block) -> f64 {
    if want <= from || ramp_dist(from, want, b.accel, b.jerk) <= b.len {
        want
    } else {
        reach(from, b.len, b.accel, b.jerk).min(want)
    }
}

/// Times a block sequence in machine coordinates from `start`, at rest
/// before the first block and after the last.
pub fn estimate_axes(start: [f64; 6], moves: &[AxisMove], machine: &Machine) -> TimeEstimate {
    estimate_with(start, moves, &Limits::of(machine))
}

/// [`estimate_axes`] with explicit limits.
pub fn estimate_with(start: [f64; 6], moves: &[AxisMove], lim: &Limits) -> TimeEstimate {
    estimate_at(start, moves, None, lim)
}

/// [`estimate_axes`] with every feed block asking for the minutes
/// `minutes` gives at its index instead of its own: one program timed at
/// other feeds without a copy of its blocks.
pub fn estimate_axes_at(
    start: [f64; 6],
    moves: &[AxisMove],
    minutes: &[f64],
    machine: &Machine,
) -> TimeEstimate {
    estimate_at(start, moves, Some(minutes), &Limits::of(machine))
}

/// `N` estimates of one chain of machine-axis blocks that differ only in
/// the minutes each feed block asks for, timed as the blocks come, each
/// under the default path-control mode: for each, the figures of
/// [`estimate_with`] over the whole chain, to the bit, without the chain's
/// blocks or a time per block in memory (each holds only the blocks whose
/// speeds the blocks after them may still lower: `stream::ChainStream`).
/// The blocks' geometry is prepared once for all `N`.
pub struct AxisChains<'a, const N: usize> {
    lim: &'a Limits,
    here: [f64; 6],
    next: usize,
    streams: [stream::ChainStream<'a>; N],
}

impl<'a, const N: usize> AxisChains<'a, N> {
    /// The chains from `start`, at rest there, timed within `lim`.
    pub fn new(start: [f64; 6], lim: &'a Limits) -> AxisChains<'a, N> {
        AxisChains {
            lim,
            here: start,
            next: 0,
            streams: std::array::from_fn(|_| stream::ChainStream::new(start, lim)),
        }
    }

    /// The chain's next block: `m` (its own minutes unused) asking for
    /// `minutes[k]` in estimate k when a feed block.
    pub fn push(&mut self, m: AxisMove, minutes: [f64; N]) {
        let before = self.here;
        let prepared = prepare_one(self.next, &m, &mut self.here, self.lim);
        self.next += 1;
        let rapid_mm = stream::rapid_mm(&m, &before);
        for (s, t) in self.streams.iter_mut().zip(minutes) {
            let (kind, p) = match (m.kind, &prepared) {
                (MoveKind::Feed { .. }, Prepared::Moves(b)) => {
                    let mut b = *b;
                    b.at_minutes(t);
                    (MoveKind::Feed { nominal_min: t }, Prepared::Moves(b))
                }
                (MoveKind::Feed { .. }, p) => (MoveKind::Feed { nominal_min: t }, *p),
                (k, p) => (k, *p),
            };
            s.push_prepared(kind, rapid_mm, p, BlockCtl::default(), &mut |_| {});
        }
    }

    /// The chains end at rest: the figures of each (`per_move_s` empty,
    /// `planner` and `by_mode` as [`estimate_with`] leaves them).
    pub fn finish(self) -> [TimeEstimate; N] {
        self.streams.map(|s| {
            let e = s.finish(&mut |_| {});
            TimeEstimate {
                total_s: e.total_s,
                nominal_s: e.nominal_s,
                rapid_s: e.rapid_s,
                feed_s: e.feed_s,
                dwell_s: e.dwell_s,
                velocity_limited_blocks: e.velocity_limited_blocks,
                accel_limited_blocks: e.accel_limited_blocks,
                ..TimeEstimate::default()
            }
        })
    }
}

/// [`estimate_with`] with the program's path-control mode at every block
/// (`ctl[i]` for `moves[i]`), planned as `lim.planner` plans.
pub fn estimate_controlled(
    start: [f64; 6],
    moves: &[AxisMove],
    ctl: &[BlockCtl],
    lim: &Limits,
) -> TimeEstimate {
    assert_eq!(ctl.len(), moves.len(), "one mode per block");
    let (blocks, stops) = prepare(start, moves, lim);
    finish(start, moves, None, &blocks, &stops, Some(ctl), lim)
}

fn estimate_at(
    start: [f64; 6],
    moves: &[AxisMove],
    minutes: Option<&[f64]>,
    lim: &Limits,
) -> TimeEstimate {
    let (blocks, stops) = prepare(start, moves, lim);
    finish(start, moves, minutes, &blocks, &stops, None, lim)
}

/// The estimate of prepared blocks, each feed block asking for the minutes
/// `minutes` gives at its index when given.
fn finish(
    start: [f64; 6],
    moves: &[AxisMove],
    minutes: Option<&[f64]>,
    blocks: &[Block],
    stops: &[bool],
    ctl: Option<&[BlockCtl]>,
    lim: &Limits,
) -> TimeEstimate {
    if let Some(t) = minutes {
        assert_eq!(t.len(), moves.len(), "one time per block");
    }
    let mut e = TimeEstimate {
        per_move_s: vec![0.0; moves.len()],
        ..TimeEstimate::default()
    };
    // Each block's cap and whether it is below what its F asks.
    let cap = |b: &Block| -> (f64, bool) {
        match minutes {
            Some(t) if !b.rapid => {
                let programmed = programmed_speed(false, b.len, t[b.index]);
                let vcap = programmed.min(b.vgeom);
                (vcap, vcap < programmed * (1.0 - 1e-12))
            }
            _ => (b.vcap, b.velocity_limited),
        }
    };
    let caps: Vec<f64> = blocks.iter().map(|b| cap(b).0).collect();
    let shaped = planner::shape(blocks, &caps, stops, ctl, &lim.planner, lim);
    let v = plan_shaped(&shaped.blocks, shaped.vj);
    for (k, b) in shaped.blocks.iter().enumerate() {
        let (t, cruise) = block_time_at(b, b.vcap, v[k], v[k + 1]);
        e.per_move_s[b.index] += t;
        if !b.rapid {
            e.accel_limited_blocks += usize::from(!cruise);
        }
    }
    e.velocity_limited_blocks = blocks.iter().filter(|b| !b.rapid && cap(b).1).count();
    let mut here = start;
    for (i, (m, t)) in moves.iter().zip(e.per_move_s.iter_mut()).enumerate() {
        match m.kind {
            MoveKind::Dwell { s } => {
                *t = s.max(0.0);
                e.dwell_s += *t;
                e.nominal_s += *t;
                continue;
            }
            MoveKind::Rapid => {
                let d = DVec3::new(
                    m.target[0] - here[0],
                    m.target[1] - here[1],
                    m.target[2] - here[2],
                )
                .length();
                e.nominal_s += d / lim.rapid;
                e.rapid_s += *t;
            }
            MoveKind::Feed { nominal_min } => {
                let nominal_min = minutes.map_or(nominal_min, |t| t[i]);
                // A block that does not move takes what it asks for.
                if *t == 0.0 {
                    *t = nominal_min.max(0.0) * 60.0;
                }
                e.nominal_s += nominal_min.max(0.0) * 60.0;
                e.feed_s += *t;
            }
        }
        here = m.target;
    }
    e.total_s = e.rapid_s + e.feed_s + e.dwell_s;
    e
}

/// Time of one straight move by `d` (X Y Z A B C) from rest to rest, s: a
/// link's cost where the motion stops at both ends (a rapid of a
/// retract, for the `reorder` planner's fast model).
pub fn rest_to_rest_s(lim: &Limits, d: [f64; 6], kind: MoveKind) -> f64 {
    let moves = [AxisMove { target: d, kind }];
    let (blocks, _) = prepare([0.0; 6], &moves, lim);
    blocks.first().map_or(0.0, |b| block_time(b, 0.0, 0.0).0)
}

/// Largest angle one chord of an arc may sweep, degrees, when an arc is
/// split into the straight blocks the estimate times.
const ARC_CHORD_DEG: f64 = 5.0;

/// A program as machine-axis blocks: chains of known moves, each with its
/// start, and the dwells that come before any known position.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ProgramBlocks {
    pub chains: Vec<([f64; 6], Vec<AxisMove>)>,
    /// The path-control mode of every block of every chain.
    pub ctl: Vec<Vec<BlockCtl>>,
    pub loose_dwell_s: f64,
}

/// Machine-axis blocks of a tool-tip program, in chains of known positions
/// (a move from or to an unset position breaks the chain and is left out,
/// as in the program summary). A rotary position comes from the program's
/// angles when it has them (a posted program), else from the tool axis
/// through the machine's inverse kinematics (nearest solution to the
/// previous one); without kinematics the tool tip moves as X Y Z.
pub fn program_axis_moves(p: &Program, machine: &Machine) -> ProgramBlocks {
    let mut all = Collect::default();
    let loose_dwell_s = walk_program(p, machine, &mut all);
    ProgramBlocks {
        chains: all.chains,
        ctl: all.ctl,
        loose_dwell_s,
    }
}

/// Where [`walk_program`] hands the blocks of a program's chains, in order,
/// each once its path-control mode is final.
pub(crate) trait ChainSink {
    /// The next block of the chain that starts at `start` (a new chain when
    /// none is open).
    fn block(&mut self, start: [f64; 6], m: AxisMove, ctl: BlockCtl);
    /// The open chain ends (called only after a block of it).
    fn end(&mut self);
}

/// The sink that keeps every chain whole ([`ProgramBlocks`]).
#[derive(Default)]
struct Collect {
    chains: Vec<([f64; 6], Vec<AxisMove>)>,
    ctl: Vec<Vec<BlockCtl>>,
    open: bool,
}

impl ChainSink for Collect {
    fn block(&mut self, start: [f64; 6], m: AxisMove, ctl: BlockCtl) {
        if !self.open {
            self.chains.push((start, Vec::new()));
            self.ctl.push(Vec::new());
            self.open = true;
        }
        if let (Some(c), Some(k)) = (self.chains.last_mut(), self.ctl.last_mut()) {
            c.1.push(m);
            k.push(ctl);
        }
    }
    fn end(&mut self) {
        self.open = false;
    }
}

/// How many blocks of a chain [`walk_program`] holds before it hands them on.
const DRAIN_BATCH: usize = 64;

/// Hands the blocks of the open chain whose mode can no longer change (all
/// but the last `keep`) to `sink`, oldest first.
fn drain_final(
    cur: &mut Option<([f64; 6], Vec<AxisMove>)>,
    ctl_cur: &mut Vec<BlockCtl>,
    keep: usize,
    sink: &mut dyn ChainSink,
) {
    if let Some(c) = cur.as_mut() {
        let n = c.1.len().saturating_sub(keep).min(ctl_cur.len());
        for (m, k) in c.1.drain(..n).zip(ctl_cur.drain(..n)) {
            sink.block(c.0, m, k);
        }
    }
}

/// [`program_axis_moves`] block by block into `sink`, holding only the
/// blocks of the move at hand; returns the seconds of dwells before any
/// known position.
pub(crate) fn walk_program(p: &Program, machine: &Machine, sink: &mut dyn ChainSink) -> f64 {
    let kin = machine.kinematics();
    let names = kin.map(|k| k.kind.rotary_names());
    let mut rot = [0.0f64; 3];
    let mut cur: Option<([f64; 6], Vec<AxisMove>)> = None;
    let mut here: Option<[f64; 6]> = None;
    // Joint target of a tip with the move's orientation.
    let joints = |tip: DVec3, o: Option<&ir::Orient>, rot: &mut [f64; 3]| -> [f64; 6] {
        let mut xyz = tip;
        if let Some(o) = o {
            if o.has_angles() {
                for (r, a) in rot.iter_mut().zip(o.angles) {
                    if let Some(a) = a {
                        *r = a.to_degrees();
                    }
                }
            } else if let (Some(k), Some(axis), Some(names)) = (kin, o.axis, names) {
                let (i0, i1) = (rotary_index(names[0]) - 3, rotary_index(names[1]) - 3);
                let (f0, s0) = (rot[i0], rot[i1]);
                let mut cands = k.inverse(tip, axis, s0);
                if cands.is_empty() {
                    cands = k
                        .orientation_ik(axis, s0)
                        .into_iter()
                        .map(|(f, s)| millplan_models::kinematics::Joints {
                            xyz: k.position_ik(tip, f, s),
                            first: f,
                            second: s,
                        })
                        .collect();
                }
                if let Some(j) = cands.into_iter().min_by(|a, b| {
                    let da = (a.first - f0).abs() + (a.second - s0).abs();
                    let db = (b.first - f0).abs() + (b.second - s0).abs();
                    da.total_cmp(&db)
                }) {
                    xyz = j.xyz;
                    rot[i0] = j.first;
                    rot[i1] = j.second;
                }
            }
        }
        [xyz.x, xyz.y, xyz.z, rot[0], rot[1], rot[2]]
    };
    // A dwell where the tool stands; before any known position it still
    // takes its time, outside the chains.
    let loose = std::cell::Cell::new(0.0);
    let dwell = |cur: &mut Option<([f64; 6], Vec<AxisMove>)>, here: Option<[f64; 6]>, t: f64| match (
        cur.as_mut(),
        here,
    ) {
        (Some(c), _) => {
            let at = c.1.last().map_or(c.0, |m| m.target);
            c.1.push(AxisMove {
                target: at,
                kind: MoveKind::Dwell { s: t },
            });
        }
        (None, Some(h)) => {
            *cur = Some((
                h,
                vec![AxisMove {
                    target: h,
                    kind: MoveKind::Dwell { s: t },
                }],
            ))
        }
        (None, None) => loose.set(loose.get() + t.max(0.0)),
    };
    // The path-control mode of every block, in step with the chains: the
    // blocks of a move take the mode in effect for it when the next move
    // (or the end) comes.
    let mut ctl_cur: Vec<BlockCtl> = Vec::new();
    let mut st = BlockCtl::default();
    let mut stop_once = false;
    // Whether the open chain has handed a block to the sink.
    let mut open = false;
    let flush = |cur: &mut Option<([f64; 6], Vec<AxisMove>)>,
                 ctl_cur: &mut Vec<BlockCtl>,
                 st: BlockCtl,
                 open: &mut bool,
                 sink: &mut dyn ChainSink| {
        sync_ctl(cur, ctl_cur, st, false);
        if cur.as_ref().is_some_and(|c| !c.1.is_empty()) {
            drain_final(cur, ctl_cur, 0, sink);
            *open = true;
        }
        if std::mem::take(open) {
            sink.end();
        }
        *cur = None;
        ctl_cur.clear();
    };
    for op in &p.operations {
        for (i, m) in op.moves.iter().enumerate() {
            let o = op.orient(m);
            let start = op.known_start(i);
            sync_ctl(&cur, &mut ctl_cur, st, std::mem::take(&mut stop_once));
            // Only the last block's mode may still change (a G09's stop);
            // the others go on in batches.
            if cur.as_ref().is_some_and(|c| c.1.len() > DRAIN_BATCH) {
                drain_final(&mut cur, &mut ctl_cur, 1, sink);
                open = true;
            }
            for e in op.events_before(i) {
                if let ir::EventKind::PathControl(pc) = &e.kind {
                    apply_path_control(&mut st, &mut stop_once, pc);
                }
                if let ir::EventKind::Dwell(t) = &e.kind {
                    dwell(&mut cur, here, *t);
                }
            }
            if let Some(c) = op.cycle(m) {
                let Some(at) = known(m.end) else {
                    flush(&mut cur, &mut ctl_cur, st, &mut open, sink);
                    here = None;
                    continue;
                };
                let axis = op.axis(m).unwrap_or(DVec3::Z);
                let steps = cycle_moves(c, at, axis).unwrap_or_else(|_| {
                    vec![
                        CycleStep::Rapid(at + axis * c.clearance),
                        CycleStep::Feed(at + axis * c.bottom, c.feed),
                        CycleStep::Rapid(at + axis * c.retract.max(c.clearance)),
                    ]
                });
                let mut steps = steps.into_iter();
                // Across to the hole at the height the tool stands; from an
                // unknown position the cycle's first position starts a chain
                // (as the program summary counts it).
                let prev = match start {
                    Some(s) => {
                        let s6 = joints(s, o, &mut rot);
                        let list = &mut cur
                            .get_or_insert_with(|| (here.unwrap_or(s6), Vec::new()))
                            .1;
                        // Up to the cycle's level first if the tool stands
                        // below it, as the writers spell it out.
                        let top = at.z + c.retract.max(c.clearance);
                        if s.z < top {
                            list.push(AxisMove {
                                target: joints(DVec3::new(s.x, s.y, top), o, &mut rot),
                                kind: MoveKind::Rapid,
                            });
                        }
                        let across = DVec3::new(at.x, at.y, s.z.max(top));
                        list.push(AxisMove {
                            target: joints(across, o, &mut rot),
                            kind: MoveKind::Rapid,
                        });
                        across
                    }
                    None => {
                        flush(&mut cur, &mut ctl_cur, st, &mut open, sink);
                        let first = match steps.next() {
                            Some(CycleStep::Rapid(q) | CycleStep::Feed(q, _)) => q,
                            _ => at,
                        };
                        cur = Some((joints(first, o, &mut rot), Vec::new()));
                        first
                    }
                };
                let mut prev = prev;
                let list = &mut cur.get_or_insert_with(|| ([0.0; 6], Vec::new())).1;
                for st in steps {
                    let (q, kind) = match st {
                        CycleStep::Rapid(q) => (q, MoveKind::Rapid),
                        CycleStep::Feed(q, f) => (
                            q,
                            MoveKind::Feed {
                                nominal_min: (q - prev).length() / f,
                            },
                        ),
                        CycleStep::Dwell(t) => (prev, MoveKind::Dwell { s: t }),
                    };
                    list.push(AxisMove {
                        target: joints(q, o, &mut rot),
                        kind,
                    });
                    prev = q;
                }
                here = list.last().map(|m| m.target).or(cur.as_ref().map(|c| c.0));
                continue;
            }
            let (Some(s), Some(e)) = (start, known(m.end)) else {
                flush(&mut cur, &mut ctl_cur, st, &mut open, sink);
                here = None;
                continue;
            };
            let s6 = here.unwrap_or_else(|| joints(s, o, &mut rot.clone()));
            let list = &mut cur.get_or_insert_with(|| (s6, Vec::new())).1;
            let len = op.move_length(i).unwrap_or(0.0);
            let nominal = |part: f64| -> MoveKind {
                if m.is_rapid() {
                    return MoveKind::Rapid;
                }
                let total = match m.feed_mode {
                    FeedMode::PerMinute => len / m.feed,
                    FeedMode::PerRev if m.spindle > 0.0 => len / (m.feed * m.spindle),
                    FeedMode::PerRev => 0.0,
                    FeedMode::InverseTime => 1.0 / m.feed,
                };
                MoveKind::Feed {
                    nominal_min: if total.is_finite() { total * part } else { 0.0 },
                }
            };
            let mut arc_radius = None;
            match op.arc(m) {
                Some(a) if a.sweep.abs() > 1e-12 => {
                    arc_radius = Some(a.radius);
                    let n = ((a.sweep.abs().to_degrees() / ARC_CHORD_DEG).ceil() as usize).max(1);
                    for k in 1..=n {
                        let t = k as f64 / n as f64;
                        let q = if k == n { e } else { a.point_at(s, e, t) };
                        list.push(AxisMove {
                            target: joints(q, o, &mut rot),
                            kind: nominal(1.0 / n as f64),
                        });
                    }
                }
                _ => list.push(AxisMove {
                    target: joints(e, o, &mut rot),
                    kind: nominal(1.0),
                }),
            }
            here = list.last().map(|m| m.target);
            if let Some(r) = arc_radius {
                let from = ctl_cur.len();
                sync_ctl(&cur, &mut ctl_cur, st, false);
                let last = ctl_cur.len().saturating_sub(1);
                for (k, c) in ctl_cur.iter_mut().enumerate().skip(from) {
                    c.arc_radius = r;
                    c.same_move = k < last;
                }
            }
        }
        // Trailing dwells of the operation.
        for ev in op
            .events
            .iter()
            .filter(|ev| ev.at as usize >= op.moves.len())
        {
            if let ir::EventKind::Dwell(t) = &ev.kind {
                dwell(&mut cur, here, *t);
            }
        }
    }
    sync_ctl(&cur, &mut ctl_cur, st, stop_once);
    flush(&mut cur, &mut ctl_cur, st, &mut open, sink);
    loose.get()
}

/// Gives the blocks of the open chain that have no mode yet `st`; with
/// `stop_after`, the last block stops at its end (a G09 move's).
fn sync_ctl(
    cur: &Option<([f64; 6], Vec<AxisMove>)>,
    ctl_cur: &mut Vec<BlockCtl>,
    st: BlockCtl,
    stop_after: bool,
) {
    let n = cur.as_ref().map_or(0, |c| c.1.len());
    if ctl_cur.len() < n {
        ctl_cur.resize(n, st);
    }
    if stop_after {
        if let Some(c) = ctl_cur.last_mut() {
            c.stop_after = true;
        }
    }
}

/// The mode after a path-control event. Sinumerik's high-speed settings
/// blend within their tolerance while on and leave the control's own
/// blending when switched off.
fn apply_path_control(st: &mut BlockCtl, stop_once: &mut bool, pc: &ir::PathControl) {
    use ir::{PathControl as P, Smoothing};
    match *pc {
        P::ExactStop => st.mode = PathMode::ExactStop,
        P::Blend { tolerance } => st.mode = PathMode::Blend { tolerance },
        P::StopOnce => *stop_once = true,
        P::Smoothing {
            kind: Smoothing::HighSpeed { tolerance },
            on,
        } => {
            st.mode = PathMode::Blend {
                tolerance: (on && tolerance > 0.0).then_some(tolerance),
            };
            st.lookahead_on = on;
        }
        P::Smoothing { on, .. } => st.lookahead_on = on,
        P::Soft(on) => st.soft = Some(on),
    }
}

/// The same mode to the last bit (so the same label: a tolerance of -0 and
/// one of 0 are labelled apart, as they are told apart here).
fn same_mode(a: PathMode, b: PathMode) -> bool {
    match (a, b) {
        (PathMode::ExactStop, PathMode::ExactStop) => true,
        (PathMode::Blend { tolerance: x }, PathMode::Blend { tolerance: y }) => {
            x.map(f64::to_bits) == y.map(f64::to_bits)
        }
        _ => false,
    }
}

/// The controller-aware time of a tool-tip program on `machine`: every chain
/// of known moves ([`program_axis_moves`]) timed by [`estimate_axes`], the
/// figures summed. `per_move_s` is per machine block (arcs split into
/// chords, cycles spelled out), in program order.
///
/// The chains are timed as they are made, block by block
/// (`stream::ChainStream`, the same numbers to the bit): neither the
/// machine blocks nor the planner's arrays are held for a whole chain.
pub fn estimate_program(p: &Program, machine: &Machine) -> TimeEstimate {
    estimate_program_with(p, machine, true)
}

/// [`estimate_program`] without `per_move_s` (left empty): the figures of
/// a program in memory that does not grow with it.
pub fn estimate_program_totals(p: &Program, machine: &Machine) -> TimeEstimate {
    estimate_program_with(p, machine, false)
}

fn estimate_program_with(p: &Program, machine: &Machine, per_move: bool) -> TimeEstimate {
    let lim = Limits::of(machine);
    let mut s = Streamed {
        per_move,
        lim: &lim,
        chain: None,
        total: TimeEstimate {
            planner: lim.planner.kind.name(),
            ..TimeEstimate::default()
        },
        last: None,
        chains: Vec::new(),
    };
    let loose = if !per_move && p.move_count() >= PIPE_MOVES {
        walk_piped(p, machine, &mut s)
    } else {
        walk_program(p, machine, &mut s)
    };
    let mut total = s.total;
    // The dwells before any known position first, then each chain's
    // figures in order (as they have always been summed).
    total.total_s = loose;
    total.nominal_s = loose;
    total.dwell_s = loose;
    for e in s.chains {
        total.total_s += e.total_s;
        total.nominal_s += e.nominal_s;
        total.rapid_s += e.rapid_s;
        total.feed_s += e.feed_s;
        total.dwell_s += e.dwell_s;
        total.velocity_limited_blocks += e.velocity_limited_blocks;
        total.accel_limited_blocks += e.accel_limited_blocks;
    }
    total
}

/// Moves from which [`estimate_program_totals`] plans on a second thread
/// while the first walks the program: below it a thread costs more than it
/// saves.
const PIPE_MOVES: usize = 1 << 16;
/// Blocks handed from the walk to the planner at a time.
const PIPE_BATCH: usize = 1 << 8;

/// One call of a [`ChainSink`], to be made on the planner's thread.
enum Piece {
    Block([f64; 6], AxisMove, BlockCtl),
    End,
}

/// The sink of [`walk_piped`]'s walk: the calls in batches, in order.
struct Piped {
    batch: Vec<Piece>,
    tx: std::sync::mpsc::SyncSender<Vec<Piece>>,
    /// Batches the planner is done with, to be filled again.
    spare: std::sync::mpsc::Receiver<Vec<Piece>>,
}

impl Piped {
    fn send(&mut self) {
        let next = self
            .spare
            .try_recv()
            .unwrap_or_else(|_| Vec::with_capacity(PIPE_BATCH));
        let full = std::mem::replace(&mut self.batch, next);
        // Refused only when the planner's thread has ended, by a panic,
        // which its join passes on.
        let _ = self.tx.send(full);
    }

    fn push(&mut self, piece: Piece) {
        self.batch.push(piece);
        if self.batch.len() >= PIPE_BATCH {
            self.send();
        }
    }
}

impl ChainSink for Piped {
    fn block(&mut self, start: [f64; 6], m: AxisMove, ctl: BlockCtl) {
        self.push(Piece::Block(start, m, ctl));
    }

    fn end(&mut self) {
        self.push(Piece::End);
    }
}

/// [`walk_program`] into `sink` with the sink on a thread of its own: the
/// walk and the planner, each about half the work, side by side. The sink
/// hears the same calls in the same order, so its figures are the same to
/// the bit.
fn walk_piped(p: &Program, machine: &Machine, sink: &mut Streamed<'_>) -> f64 {
    let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<Piece>>(2);
    let (back, spare) = std::sync::mpsc::channel::<Vec<Piece>>();
    std::thread::scope(|sc| {
        let planner = sc.spawn(move || {
            for mut batch in rx {
                for piece in batch.drain(..) {
                    match piece {
                        Piece::Block(start, m, ctl) => sink.block(start, m, ctl),
                        Piece::End => sink.end(),
                    }
                }
                let _ = back.send(batch);
            }
        });
        let mut pipe = Piped {
            batch: Vec::with_capacity(PIPE_BATCH),
            tx,
            spare,
        };
        let loose = walk_program(p, machine, &mut pipe);
        pipe.send();
        drop(pipe);
        planner
            .join()
            .unwrap_or_else(|e| std::panic::resume_unwind(e));
        loose
    })
}

/// [`estimate_program`]'s sink: each chain timed as its blocks come.
struct Streamed<'a> {
    /// Whether `per_move_s` is kept.
    per_move: bool,
    lim: &'a Limits,
    chain: Option<stream::ChainStream<'a>>,
    total: TimeEstimate,
    /// The entry of `by_mode` the last block went to, by its mode's bits: a
    /// run of blocks under one mode is summed without naming it again.
    last: Option<(PathMode, usize)>,
    /// Each chain's figures, summed once the dwells outside them are known.
    chains: Vec<stream::ChainTotals>,
}

impl ChainSink for Streamed<'_> {
    fn block(&mut self, start: [f64; 6], m: AxisMove, ctl: BlockCtl) {
        let lim = self.lim;
        let chain = self
            .chain
            .get_or_insert_with(|| stream::ChainStream::new(start, lim));
        let (total, last, keep) = (&mut self.total, &mut self.last, self.per_move);
        chain.push(m, ctl, &mut |d| timed(total, last, d, keep));
    }

    fn end(&mut self) {
        let Some(chain) = self.chain.take() else {
            return;
        };
        let (total, last, keep) = (&mut self.total, &mut self.last, self.per_move);
        let e = chain.finish(&mut |d| timed(total, last, d, keep));
        self.chains.push(e);
    }
}

/// One block's final time into the program's: its entry of `per_move_s`
/// and, unless a dwell, the time of its path-control mode.
fn timed(
    total: &mut TimeEstimate,
    last: &mut Option<(PathMode, usize)>,
    d: stream::Timed,
    per_move: bool,
) {
    if per_move {
        total.per_move_s.push(d.t);
    }
    if d.dwell {
        return;
    }
    let at = match *last {
        Some((mode, i)) if same_mode(mode, d.ctl.mode) => i,
        _ => {
            let label = d.ctl.mode.label();
            let i = match total.by_mode.iter().position(|b| b.mode == label) {
                Some(i) => i,
                None => {
                    total.by_mode.push(ModeTime {
                        mode: label,
                        time_s: 0.0,
                        blocks: 0,
                    });
                    total.by_mode.len() - 1
                }
            };
            *last = Some((d.ctl.mode, i));
            i
        }
    };
    let b = &mut total.by_mode[at];
    b.time_s += d.t;
    b.blocks += 1;
}

/// The whole-chain estimate of a program ([`estimate_program`] as it was
/// before it streamed): the reference the streamed one is tested against.
#[cfg(test)]
pub(crate) fn estimate_program_whole(p: &Program, machine: &Machine) -> TimeEstimate {
    let lim = Limits::of(machine);
    let blocks = program_axis_moves(p, machine);
    let mut total = TimeEstimate {
        total_s: blocks.loose_dwell_s,
        nominal_s: blocks.loose_dwell_s,
        dwell_s: blocks.loose_dwell_s,
        ..TimeEstimate::default()
    };
    total.planner = lim.planner.kind.name();
    let mut last: Option<(PathMode, usize)> = None;
    for ((start, moves), ctl) in blocks.chains.into_iter().zip(&blocks.ctl) {
        let e = estimate_controlled(start, &moves, ctl, &lim);
        for ((m, c), t) in moves.iter().zip(ctl).zip(&e.per_move_s) {
            let d = stream::Timed {
                t: *t,
                dwell: matches!(m.kind, MoveKind::Dwell { .. }),
                ctl: *c,
            };
            timed(&mut total, &mut last, d, false);
        }
        total.total_s += e.total_s;
        total.nominal_s += e.nominal_s;
        total.rapid_s += e.rapid_s;
        total.feed_s += e.feed_s;
        total.dwell_s += e.dwell_s;
        total.velocity_limited_blocks += e.velocity_limited_blocks;
        total.accel_limited_blocks += e.accel_limited_blocks;
        total.per_move_s.extend(e.per_move_s);
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// X Y Z at `accel` mm/s², fast axes, no jerk; A B C likewise in degrees.
    fn lim(accel: f64) -> Limits {
        Limits {
            velocity: [1e6; 6],
            accel: [accel; 6],
            jerk: [f64::INFINITY; 6],
            rapid: 1e6,
            feed_max: 1e6,
            planner: Planner::default(),
        }
    }

    /// A feed block to `x, y` at `v` mm/s.
    fn feed_to(from: [f64; 6], to: [f64; 6], v: f64) -> AxisMove {
        let d = ((to[0] - from[0]).powi(2) + (to[1] - from[1]).powi(2) + (to[2] - from[2]).powi(2))
            .sqrt();
        AxisMove {
            target: to,
            kind: MoveKind::Feed {
                nominal_min: d / v / 60.0,
            },
        }
    }

    fn xy(x: f64, y: f64) -> [f64; 6] {
        [x, y, 0.0, 0.0, 0.0, 0.0]
    }

    fn close(a: f64, b: f64, tol: f64) {
        assert!((a - b).abs() <= tol * b.abs().max(1.0), "{a} vs {b}");
    }

    #[test]
    fn long_move_ramps_trapezoidally() {
        // t = L/v + v/a: 100 mm at 50 mm/s (3000 mm/min), a = 1000 mm/s².
        let e = estimate_with(
            xy(0.0, 0.0),
            &[feed_to(xy(0.0, 0.0), xy(100.0, 0.0), 50.0)],
            &lim(1000.0),
        );
        close(e.total_s, 100.0 / 50.0 + 50.0 / 1000.0, 1e-12);
        close(e.nominal_s, 2.0, 1e-12);
        assert_eq!(e.accel_limited_blocks, 0);
    }

    #[test]
    fn short_move_never_reaches_the_feed() {
        // v²/a = 10 mm > L = 1 mm: triangular, t = 2·√(L/a).
        // The path accelerates at what the busier axis allows: Y carries
        // 0.8 of the motion, so 1000 / 0.8 = 1250 mm/s².
        let e = estimate_with(
            xy(0.0, 0.0),
            &[feed_to(xy(0.0, 0.0), xy(0.6, 0.8), 100.0)],
            &lim(1000.0),
        );
        close(e.total_s, 2.0 * (1.0f64 / 1250.0).sqrt(), 1e-12);
        assert_eq!(e.accel_limited_blocks, 1);
    }

    #[test]
    fn jerk_limited_s_curve_matches_its_closed_form() {
        let mut l = lim(1000.0);
        l.jerk = [20_000.0; 6];
        let one = |len: f64, v: f64| {
            estimate_with(xy(0.0, 0.0), &[feed_to(xy(0.0, 0.0), xy(len, 0.0), v)], &l).total_s
        };
        // v = 100 ≥ a²/J = 50: constant-acceleration phase in each ramp,
        // t = L/v + v/a + a/J.
        close(one(200.0, 100.0), 2.0 + 0.1 + 0.05, 1e-12);
        // v = 20 < a²/J: acceleration never saturates, each ramp takes
        // 2·√(v/J) and covers v·√(v/J): t = L/v + 2·√(v/J).
        close(
            one(200.0, 20.0),
            10.0 + 2.0 * (20.0f64 / 20_000.0).sqrt(),
            1e-12,
        );
        // Too short to reach any cruise, jerk-only: rest to rest over L,
        // peak u² with 2·(u²/2)·2u/√J = L, t = 4u/√J = 4·(L/(2J))^(1/3)·... :
        // the symmetric profile covers L = v_p·2·√(v_p/J), so
        // v_p = (L·√J/2)^(2/3) and t = 4·√(v_p/J).
        let len = 0.01;
        let vp = (len * 20_000.0f64.sqrt() / 2.0).powf(2.0 / 3.0);
        assert!(vp < 50.0, "jerk-only regime");
        close(one(len, 1000.0), 4.0 * (vp / 20_000.0).sqrt(), 1e-9);
    }

    #[test]
    fn right_angle_corner_slows_to_the_acceleration_limit() {
        // X then Y, 100 mm each at 50 mm/s. X may accelerate 1000, Y 500
        // mm/s²: each axis's velocity jumps by v over the blend of
        // BLEND_MM, so v_j = min_i √(a_i·ℓ/|Δe_i|) = √(500·0.2) = 10 mm/s.
        let mut l = lim(1000.0);
        l.accel[1] = 500.0;
        let moves = [
            feed_to(xy(0.0, 0.0), xy(100.0, 0.0), 50.0),
            feed_to(xy(100.0, 0.0), xy(100.0, 100.0), 50.0),
        ];
        let (blocks, stops) = prepare(xy(0.0, 0.0), &moves, &l);
        let v = plan(&blocks, &stops, &l);
        let vj = (500.0 * BLEND_MM).sqrt();
        close(v[1], vj, 1e-12);
        assert_eq!((v[0], v[2]), (0.0, 0.0));
        // Trapezoid times with entry/exit speeds (a of X, then of Y).
        let trap = |v0: f64, v1: f64, vc: f64, a: f64, len: f64| {
            let (d0, d1) = (
                (vc * vc - v0 * v0) / (2.0 * a),
                (vc * vc - v1 * v1) / (2.0 * a),
            );
            (vc - v0) / a + (vc - v1) / a + (len - d0 - d1) / vc
        };
        let e = estimate_with(xy(0.0, 0.0), &moves, &l);
        close(
            e.total_s,
            trap(0.0, vj, 50.0, 1000.0, 100.0) + trap(vj, 0.0, 50.0, 500.0, 100.0),
            1e-12,
        );
    }

    #[test]
    fn collinear_blocks_keep_the_speed_through_the_junction() {
        // Ten 10 mm blocks on one line time like one 100 mm block: the
        // look-ahead keeps 50 mm/s across every junction.
        let mut moves = Vec::new();
        for k in 0..10 {
            let (a, b) = (xy(10.0 * k as f64, 0.0), xy(10.0 * (k + 1) as f64, 0.0));
            moves.push(feed_to(a, b, 50.0));
        }
        let e = estimate_with(xy(0.0, 0.0), &moves, &lim(1000.0));
        close(e.total_s, 100.0 / 50.0 + 50.0 / 1000.0, 1e-12);
        let (blocks, stops) = prepare(xy(0.0, 0.0), &moves, &lim(1000.0));
        let v = plan(&blocks, &stops, &lim(1000.0));
        assert!(v[1..10].iter().all(|&s| (s - 50.0).abs() < 1e-9), "{v:?}");
        // Short collinear blocks: the look-ahead ramps across several.
        let short: Vec<AxisMove> = (0..100)
            .map(|k| feed_to(xy(0.1 * k as f64, 0.0), xy(0.1 * (k + 1) as f64, 0.0), 50.0))
            .collect();
        let e = estimate_with(xy(0.0, 0.0), &short, &lim(1000.0));
        close(e.total_s, 10.0 / 50.0 + 50.0 / 1000.0, 1e-9);
    }

    #[test]
    fn rotary_only_move_is_limited_by_the_rotary_axis() {
        // C turns 90° while XYZ stand; the program asks for 0.1 s, C can do
        // 3600°/min = 60°/s at 720°/s²: t = 90/60 + 60/720.
        let m = Machine {
            kinematics: Some(millplan_models::kinematics::Kinematics::new(
                millplan_models::kinematics::KinKind::TableAc,
            )),
            ..Machine::default()
        };
        let moves = [AxisMove {
            target: [0.0, 0.0, 0.0, 0.0, 0.0, 90.0],
            kind: MoveKind::Feed {
                nominal_min: 0.1 / 60.0,
            },
        }];
        let e = estimate_axes([0.0; 6], &moves, &m);
        close(e.total_s, 1.5 + 60.0 / 720.0, 1e-12);
        close(e.nominal_s, 0.1, 1e-12);
        assert_eq!(e.velocity_limited_blocks, 1);
        // The machine file's figures replace the defaults.
        let mut m = m;
        m.axes.second.velocity = Some(7200.0);
        m.axes.second.accel = Some(1200.0);
        let e = estimate_axes([0.0; 6], &moves, &m);
        close(e.total_s, 90.0 / 120.0 + 120.0 / 1200.0, 1e-12);
    }

    #[test]
    fn default_machine_has_no_zero_limit() {
        let l = Limits::of(&Machine::default());
        for i in 0..6 {
            assert!(l.velocity[i] > 0.0 && l.velocity[i].is_finite(), "{l:?}");
            assert!(l.accel[i] > 0.0 && l.accel[i].is_finite(), "{l:?}");
            assert!(l.jerk[i] > 0.0, "{l:?}");
        }
    }

    /// A slow, independent reference: a point driven along the path in time
    /// steps of `dt`, accelerating at the block's limit and braking whenever
    /// a junction (or the end) ahead would otherwise be passed too fast — the
    /// time-optimal motion under the same limits, without the passes or the
    /// closed-form block times. Only the raw junction limits are shared.
    fn brute_force(start: [f64; 6], moves: &[AxisMove], l: &Limits, dt: f64) -> f64 {
        let (blocks, stops) = prepare(start, moves, l);
        let n = blocks.len();
        let mut vj = vec![0.0; n + 1];
        for k in 1..n {
            vj[k] = if stops[k] {
                0.0
            } else {
                junction(&blocks[k - 1], &blocks[k], l)
            };
        }
        let mut s0 = vec![0.0; n + 1];
        for k in 0..n {
            s0[k + 1] = s0[k] + blocks[k].len;
        }
        let block_at = |s: f64| s0.partition_point(|&b| b <= s).clamp(1, n) - 1;
        // The fastest one may go at `s` and still brake for every junction
        // after `from` (a step that crosses a junction is held to its limit).
        let allowed = |from: f64, s: f64| {
            let k = block_at(from);
            let mut best = blocks[block_at(s)].vcap;
            let mut budget = 0.0;
            let mut at = s;
            for (j, &v_j) in vj.iter().enumerate().skip(k + 1) {
                if s0[j] > at {
                    budget += 2.0 * blocks[j - 1].accel * (s0[j] - at);
                    at = s0[j];
                }
                best = best.min((v_j * v_j + budget).sqrt());
                if v_j == 0.0 {
                    break;
                }
            }
            best
        };
        let mut t: f64 = moves
            .iter()
            .map(|m| match m.kind {
                MoveKind::Dwell { s } => s,
                _ => 0.0,
            })
            .sum();
        let (mut s, mut v) = (0.0f64, 0.0f64);
        let total = s0[n];
        while s < total - 1e-12 {
            let k = block_at(s);
            let a = blocks[k].accel;
            let mut v1 = (v + a * dt).min(blocks[k].vcap);
            let lim1 = allowed(s, (s + 0.5 * (v + v1) * dt).min(total));
            if v1 > lim1 {
                v1 = lim1;
            }
            let ds = 0.5 * (v + v1) * dt;
            if ds <= 1e-13 {
                // At a stop: the last stretch is braking at `a` to rest.
                let next = s0.iter().copied().find(|&b| b > s + 1e-12).unwrap_or(total);
                t += (2.0 * (next - s) / a).sqrt();
                s = next;
                v = 0.0;
                continue;
            }
            s += ds;
            t += dt;
            v = v1;
        }
        t
    }

    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn random_moves(rng: &mut Rng, n: usize) -> Vec<AxisMove> {
        let mut here = [0.0; 6];
        let mut out = Vec::new();
        for _ in 0..n {
            let r = rng.next();
            let mut to = here;
            let scale = if rng.next() < 0.5 { 0.5 } else { 20.0 };
            for (i, t) in to.iter_mut().enumerate().take(3) {
                // Sometimes straight on along the last direction.
                *t += scale * (rng.next() - 0.5) * if i == 2 { 0.3 } else { 1.0 };
            }
            if rng.next() < 0.3 {
                to[5] += 30.0 * (rng.next() - 0.5);
            }
            let kind = if r < 0.1 {
                MoveKind::Rapid
            } else if r < 0.15 {
                to = here;
                MoveKind::Dwell { s: 0.05 }
            } else {
                MoveKind::Feed {
                    nominal_min: scale / (5.0 + 100.0 * rng.next()) / 60.0,
                }
            };
            out.push(AxisMove { target: to, kind });
            here = to;
        }
        out
    }

    #[test]
    fn agrees_with_brute_force_time_stepping() {
        // The stepping is first order in dt: each speed change it makes
        // costs at most about one step, so with dt = 2e-5 s and under 50
        // changes per sequence the two agree within 1e-3 s plus 0.1 %.
        let mut l = lim(800.0);
        l.accel[1] = 400.0;
        l.accel[5] = 300.0;
        l.velocity[5] = 90.0;
        l.rapid = 250.0;
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for case in 0..12 {
            let moves = random_moves(&mut rng, 14);
            let e = estimate_with([0.0; 6], &moves, &l);
            let b = brute_force([0.0; 6], &moves, &l, 2e-5);
            assert!(
                (e.total_s - b).abs() <= 1e-3 + 1e-3 * b,
                "case {case}: {} vs brute force {b}",
                e.total_s
            );
        }
    }

    #[test]
    fn other_minutes_time_as_the_blocks_rewritten_with_them() {
        let mut l = lim(600.0);
        l.velocity[4] = 120.0;
        let mut rng = Rng(0x51ed_2701_3b5f_9c4d);
        for case in 0..8 {
            let moves = random_moves(&mut rng, 30);
            let minutes: Vec<f64> = (0..moves.len())
                .map(|_| 0.001 + 0.02 * rng.next())
                .collect();
            let rewritten: Vec<AxisMove> = moves
                .iter()
                .zip(&minutes)
                .map(|(m, &t)| match m.kind {
                    MoveKind::Feed { .. } => AxisMove {
                        kind: MoveKind::Feed { nominal_min: t },
                        ..*m
                    },
                    _ => *m,
                })
                .collect();
            let at = estimate_at([0.0; 6], &moves, Some(&minutes), &l);
            let want = estimate_with([0.0; 6], &rewritten, &l);
            assert_eq!(at, want, "case {case}");
            let own = estimate_with([0.0; 6], &moves, &l);
            assert_ne!(at.total_s, own.total_s, "case {case}");
            // All at once, the geometry shared: the same two estimates.
            let (blocks, stops) = prepare([0.0; 6], &moves, &l);
            for (m, want) in [(None, &own), (Some(&minutes[..]), &want)] {
                let got = finish([0.0; 6], &moves, m, &blocks, &stops, None, &l);
                assert_eq!(&got, want, "case {case}");
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Acceleration can only add time: every block is at least as long
        /// as the program asks (rapids at the rapid rate).
        #[test]
        fn estimate_is_never_below_nominal(seed in 1u64.., n in 1usize..40, jerk in prop::bool::ANY) {
            let mut rng = Rng(seed);
            let moves = random_moves(&mut rng, n);
            let mut l = lim(700.0);
            l.rapid = 300.0;
            l.velocity[0] = 200.0;
            if jerk {
                l.jerk = [5000.0; 6];
            }
            let e = estimate_with([0.0; 6], &moves, &l);
            prop_assert!(e.total_s >= e.nominal_s * (1.0 - 1e-12), "{} < {}", e.total_s, e.nominal_s);
            prop_assert!(e.per_move_s.iter().all(|t| t.is_finite() && *t >= 0.0));
            prop_assert!((e.per_move_s.iter().sum::<f64>() - e.total_s).abs() <= 1e-9 * e.total_s.max(1.0));
        }
    }

    #[test]
    fn program_estimate_has_the_summary_as_nominal() {
        use millplan_nc::ir::{Dialect, Move, Operation};
        let mut op = Operation {
            start: DVec3::new(0.0, 0.0, 10.0),
            ..Operation::default()
        };
        op.moves.push(Move::rapid(DVec3::new(0.0, 0.0, 1.0)));
        op.moves
            .push(Move::linear(DVec3::new(0.0, 0.0, -1.0), 300.0));
        for k in 0..50 {
            let x = (k + 1) as f64;
            op.moves.push(Move::linear(
                DVec3::new(x, if k % 2 == 0 { 10.0 } else { 0.0 }, -1.0),
                2000.0,
            ));
        }
        op.moves.push(Move::rapid(DVec3::new(50.0, 0.0, 10.0)));
        let mut p = Program::new(Dialect::Fanuc);
        p.operations.push(op);
        let m = Machine::default();
        let e = estimate_program(&p, &m);
        let s = millplan_nc::stats::summarize(&p, m.rapid);
        close(e.nominal_s, s.time_s, 1e-12);
        // A zig-zag of 10 mm strokes with sharp reversals: clearly slower.
        assert!(e.total_s > 1.05 * e.nominal_s, "{e:?}");
        // Drilling cycles, the first from a position the program has not
        // set (NX CLSF drilling): timed from the cycle's own first position,
        // as the summary counts them.
        let mut op = Operation::default();
        let cy = op.push_cycle(millplan_nc::ir::Cycle {
            name: "G81".into(),
            bottom: -12.0,
            clearance: 0.0,
            retract: 3.0,
            feed: 250.0,
            peck: None,
            peck_next: None,
            dwell: Some(0.5),
            line: 1,
        });
        for x in [66.0, -255.0] {
            let mut c = Move::rapid(DVec3::new(x, 0.0, 240.0));
            c.kind = millplan_nc::ir::MoveKind::Cycle(cy);
            op.moves.push(c);
        }
        let mut p = Program::new(Dialect::Fanuc);
        p.operations.push(op.clone());
        let e = estimate_program(&p, &m);
        let s = millplan_nc::stats::summarize(&p, m.rapid);
        close(e.nominal_s, s.time_s, 1e-12);
        assert!(e.total_s > e.nominal_s, "{e:?}");
        // From below the cycle's level (Z 230 under its return plane at
        // 243): up 13 first, then across 66, as the writers spell it out;
        // the nominal time is the summary's.
        op.moves.insert(0, Move::rapid(DVec3::new(0.0, 0.0, 230.0)));
        p.operations[0] = op;
        let e = estimate_program(&p, &m);
        let s = millplan_nc::stats::summarize(&p, m.rapid);
        close(e.nominal_s, s.time_s, 1e-12);
        let first = 13.0 + 66.0 + 3.0 + 12.0 + 15.0;
        assert!(
            (s.rapid_mm - (first - 12.0 + 321.0 + 3.0 + 15.0)).abs() < 1e-9,
            "{s:?}"
        );
    }

    #[test]
    fn five_axis_tool_axes_turn_the_rotary_axes() {
        use millplan_nc::ir::{Dialect, Move, Operation, Orient};
        // The tool tip stands still while the axis swings 40° about X and
        // back: on a table-table A/C machine A moves, so the block takes
        // time; as X Y Z alone it would take nothing beyond nominal.
        let mut op = Operation {
            start: DVec3::new(0.0, 0.0, 0.0),
            ..Operation::default()
        };
        for k in 0..=40 {
            let a = (k as f64).to_radians();
            let id = op.intern_orient(Orient::vector(DVec3::new(0.0, -a.sin(), a.cos())));
            let mut m = Move::linear(DVec3::new(k as f64, 0.0, 0.0), 3000.0);
            m.orient = Some(id);
            op.moves.push(m);
        }
        let mut p = Program::new(Dialect::Fanuc);
        p.operations.push(op);
        let mut m = Machine {
            kinematics: Some(millplan_models::kinematics::Kinematics::new(
                millplan_models::kinematics::KinKind::TableAc,
            )),
            ..Machine::default()
        };
        m.axes.first.velocity = Some(600.0); // 10°/s: 40° take ≥ 4 s
        let e5 = estimate_program(&p, &m);
        let e3 = estimate_program(&p, &Machine::default());
        close(e5.nominal_s, e3.nominal_s, 1e-12);
        assert!(e5.total_s >= 4.0, "{e5:?}");
        assert!(e3.total_s < 2.0, "{e3:?}");
    }

    /// A G-code program of `n` lines: feed and rapid moves, arcs, dwells,
    /// the path-control words (G61, G64, G64 P, G09), feeds changing, a
    /// reference return that leaves the position unknown.
    fn random_gcode(rng: &mut Rng, n: usize) -> String {
        let mut s = String::from("G21 G90 G17\nT1 M6\nS8000 M3\nG0 X0 Y0 Z5\n");
        let (mut x, mut y) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let r = rng.next();
            let (dx, dy) = if rng.next() < 0.6 {
                (0.3 * (rng.next() - 0.5), 0.3 * (rng.next() - 0.5))
            } else {
                (20.0 * (rng.next() - 0.5), 20.0 * (rng.next() - 0.5))
            };
            let line = if r < 0.04 {
                "G61".to_string()
            } else if r < 0.08 {
                "G64".to_string()
            } else if r < 0.12 {
                format!("G64 P{:.3}", 0.001 + 0.1 * rng.next())
            } else if r < 0.14 {
                format!("G4 P{:.2}", rng.next())
            } else if r < 0.16 {
                format!("G9 G1 X{:.4} Y{:.4}", x + dx, y + dy)
            } else if r < 0.18 {
                "G28".to_string()
            } else if r < 0.25 {
                format!("G0 X{:.4} Y{:.4} Z{:.4}", x + dx, y + dy, 5.0 * rng.next())
            } else if r < 0.35 {
                // A half circle through the chord's midpoint.
                let g = if rng.next() < 0.5 { "G2" } else { "G3" };
                format!(
                    "{g} X{:.4} Y{:.4} I{:.4} J{:.4}",
                    x + dx,
                    y + dy,
                    dx / 2.0,
                    dy / 2.0
                )
            } else {
                format!(
                    "G1 X{:.4} Y{:.4} Z{:.4} F{:.0}",
                    x + dx,
                    y + dy,
                    -rng.next(),
                    200.0 + 3000.0 * rng.next()
                )
            };
            if line.starts_with("G0 ")
                || line.starts_with("G1 ")
                || line.starts_with("G2")
                || line.starts_with("G3")
                || line.starts_with("G9")
            {
                x += dx;
                y += dy;
            }
            if line == "G28" {
                x = 0.0;
                y = 0.0;
            }
            s += &line;
            s.push('\n');
        }
        s + "M30\n"
    }

    /// Issue 32: the program's estimate, timed chain by chain as its blocks
    /// come, is the whole-chain estimate to the bit (every figure, every
    /// block's time, the time per mode) under each planner model.
    #[test]
    fn streamed_program_estimate_is_the_whole_one_to_the_bit() {
        let mut rng = Rng(0x2545_f491_4f6c_dd1d);
        for case in 0..60 {
            let src = random_gcode(&mut rng, 40 + case * 7);
            let p = millplan_nc::parse_program(&src, millplan_nc::ReadOptions::default())
                .unwrap_or_else(|e| panic!("{e}\n{src}"))
                .program;
            for kind in PlannerKind::ALL {
                let mut m = Machine::default();
                m.control.planner = Planner::of(kind);
                let (a, b) = (estimate_program(&p, &m), estimate_program_whole(&p, &m));
                let mut c = estimate_program_totals(&p, &m);
                assert!(c.per_move_s.is_empty());
                c.per_move_s.clone_from(&a.per_move_s);
                assert_eq!(c, a, "case {case}, {kind:?}");
                let key = |e: &TimeEstimate| {
                    (
                        [e.total_s, e.nominal_s, e.rapid_s, e.feed_s, e.dwell_s].map(f64::to_bits),
                        e.per_move_s.iter().map(|t| t.to_bits()).collect::<Vec<_>>(),
                        e.by_mode
                            .iter()
                            .map(|m| (m.mode.clone(), m.time_s.to_bits(), m.blocks))
                            .collect::<Vec<_>>(),
                        [e.velocity_limited_blocks, e.accel_limited_blocks],
                        e.planner,
                    )
                };
                assert_eq!(key(&a), key(&b), "case {case}, {kind:?}\n{src}");
            }
        }
    }

    /// A program of more moves than [`PIPE_MOVES`] is planned on a second
    /// thread beside the walk: the same figures, to the bit, as on one.
    #[test]
    fn piped_estimate_is_the_one_thread_one_to_the_bit() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let src = random_gcode(&mut rng, PIPE_MOVES * 5 / 4);
        let p = millplan_nc::parse_program(&src, millplan_nc::ReadOptions::default())
            .expect("reads")
            .program;
        assert!(p.move_count() >= PIPE_MOVES, "{}", p.move_count());
        for kind in PlannerKind::ALL {
            let mut m = Machine::default();
            m.control.planner = Planner::of(kind);
            let mut one = estimate_program(&p, &m);
            one.per_move_s.clear();
            let piped = estimate_program_totals(&p, &m);
            assert_eq!(piped, one, "{kind:?}");
            assert_eq!(piped.total_s.to_bits(), one.total_s.to_bits(), "{kind:?}");
        }
    }
}
