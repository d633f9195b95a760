//! The estimate of one chain block by block, holding only the blocks whose
//! speeds are not settled yet: the same numbers, to the bit, as planning
//! the whole chain at once ([`super::finish`] over [`super::planner::shape`]).
//!
//! Every step of the whole-chain estimate but one looks a bounded distance
//! ahead: a junction by its two blocks, LinuxCNC's acceleration share by the
//! chords of one arc, the blocks the control runs by the junction after
//! them, the look-ahead depth by its blocks (their lengths summed from the
//! chain's start in the same order, so to the same bits), the forward pass
//! by the block before. The backward pass looks to the chain's end, but not
//! past an *anchor*: a junction whose speed limit `w` the block after it can
//! always brake from, whatever the speed it must leave at. There the pass
//! gives `w` itself (`capped` returns its `want` once the cheap check
//! passes), so every block before it is settled. The check is made with
//! room: a ramp from `v0` to `w` covers at most `w · ramp_time(w)` (its mean
//! speed at most `w`, its time growing with the change), and an anchor asks
//! that bound below the block's length by a relative 1e-9, far above the
//! rounding of the ramp's distance. A junction where the motion stops is an
//! anchor too. Between anchors the blocks wait; a chain without one is held
//! whole, as before.

use super::planner::{self, Joint};
use super::{block_time_at, capped, prepare_one, ramp_time, Block, BlockCtl, Limits, MoveKind};
use super::{AxisMove, PlannerKind, Prepared};
use millplan_geom::DVec3;
use std::collections::VecDeque;

/// A block as the planner shapes it, waiting for the junction after it.
struct Own {
    b: Block,
    ctl: BlockCtl,
    /// How it is entered.
    into: Joint,
    /// Taken off its start by the blend arc before it.
    trimmed: f64,
    /// The share of its acceleration its kinks take (LinuxCNC).
    kinked: f64,
    /// How it is left, and the next block's cap.
    out: Option<(Joint, f64)>,
}

/// A block the control runs, with the speed limit entering it and the path
/// length from the chain's start to it.
#[derive(Clone, Copy)]
struct Run {
    b: Block,
    vj: f64,
    at: f64,
}

/// An input block not timed to the end yet.
struct Pending {
    kind: MoveKind,
    /// A rapid's XYZ length (its nominal time).
    rapid_mm: f64,
    ctl: BlockCtl,
    t: f64,
}

/// One input block's time, in input order.
pub(crate) struct Timed {
    pub(crate) t: f64,
    pub(crate) dwell: bool,
    pub(crate) ctl: BlockCtl,
}

/// A chain's figures (as [`super::TimeEstimate`], without the per-block
/// times, which went to the caller one by one).
#[derive(Default)]
pub(crate) struct ChainTotals {
    pub(crate) total_s: f64,
    pub(crate) nominal_s: f64,
    pub(crate) rapid_s: f64,
    pub(crate) feed_s: f64,
    pub(crate) dwell_s: f64,
    pub(crate) velocity_limited_blocks: usize,
    pub(crate) accel_limited_blocks: usize,
}

/// One chain's estimate, fed block by block ([`ChainStream::push`]).
pub(crate) struct ChainStream<'a> {
    lim: &'a Limits,
    lcnc: bool,
    /// Whether the planner plans a depth of blocks ahead.
    deep: bool,
    /// Where the input stands, and whether the next block starts at rest.
    here: [f64; 6],
    stop: bool,
    /// Input blocks not yet timed; `base` the index of the first.
    moves: VecDeque<Pending>,
    base: usize,
    next: usize,
    /// Shaped blocks waiting for their junction out or their arc's chords.
    own: VecDeque<Own>,
    /// Blocks the control runs, waiting for their look-ahead; `la_first`
    /// the index of the first among the chain's, `runs` how many so far,
    /// `vj_next` the limit entering the next, `length` the path so far.
    la: VecDeque<Run>,
    la_first: usize,
    runs: usize,
    vj_next: f64,
    length: f64,
    /// Blocks with their final limits since the last anchor, and the speed
    /// entering the first of them (final).
    win: VecDeque<Run>,
    v_in: f64,
    back: Vec<f64>,
    /// A window was settled since the input blocks were last let go.
    settled: bool,
    sums: ChainTotals,
}

impl<'a> ChainStream<'a> {
    pub(crate) fn new(start: [f64; 6], lim: &'a Limits) -> ChainStream<'a> {
        ChainStream {
            lim,
            lcnc: lim.planner.kind == PlannerKind::LinuxCnc29,
            deep: lim.planner.lookahead > 0 || lim.planner.plain_lookahead > 0,
            here: start,
            stop: true,
            moves: VecDeque::new(),
            base: 0,
            next: 0,
            own: VecDeque::new(),
            la: VecDeque::new(),
            la_first: 0,
            runs: 0,
            vj_next: 0.0,
            length: 0.0,
            win: VecDeque::new(),
            v_in: 0.0,
            back: Vec::new(),
            settled: false,
            sums: ChainTotals::default(),
        }
    }

    /// The next input block with its path-control mode; `done` hears every
    /// input block whose time is final, in order.
    pub(crate) fn push(&mut self, m: AxisMove, ctl: BlockCtl, done: &mut dyn FnMut(Timed)) {
        let before = self.here;
        let p = prepare_one(self.next, &m, &mut self.here, self.lim);
        self.push_prepared(m.kind, rapid_mm(&m, &before), p, ctl, done);
    }

    /// [`ChainStream::push`] of a block prepared from where this chain
    /// stands (`prepare_one` at the next index; `rapid_mm` its XYZ length
    /// on a rapid, else 0), moving the chain on to its end.
    pub(crate) fn push_prepared(
        &mut self,
        kind: MoveKind,
        rapid_mm: f64,
        p: Prepared,
        ctl: BlockCtl,
        done: &mut dyn FnMut(Timed),
    ) {
        self.next += 1;
        self.moves.push_back(Pending {
            kind,
            rapid_mm,
            ctl,
            t: 0.0,
        });
        match p {
            Prepared::Dwell => self.stop = true,
            Prepared::Still => {}
            Prepared::Moves(b) => {
                let stop = std::mem::take(&mut self.stop);
                if !b.rapid && b.velocity_limited {
                    self.sums.velocity_limited_blocks += 1;
                }
                self.shape(b, ctl, stop);
            }
        }
        // Only a settled window times blocks (and lets input blocks go).
        if std::mem::take(&mut self.settled) {
            self.release(done);
        }
    }

    /// The chain ends at rest: everything still held is timed; its figures.
    pub(crate) fn finish(mut self, done: &mut dyn FnMut(Timed)) -> ChainTotals {
        if let Some(last) = self.own.back_mut() {
            last.out = Some((Joint::Stop, 0.0));
        }
        self.resolve(true);
        self.look(true);
        self.settle(0.0);
        self.release(done);
        let s = &mut self.sums;
        s.total_s = s.rapid_s + s.feed_s + s.dwell_s;
        self.sums
    }

    /// Block `b` shaped as the planner runs it, joined to the one before.
    fn shape(&mut self, b: Block, ctl: BlockCtl, stop: bool) {
        let pl = &self.lim.planner;
        let own = planner::own_block(&b, b.vcap, &ctl, pl);
        let mut next = Own {
            b: own,
            ctl,
            into: Joint::Stop,
            trimmed: 0.0,
            kinked: 0.0,
            out: None,
        };
        if let Some(prev) = self.own.back_mut() {
            let (j, reduce) = if stop {
                (Joint::Stop, 0.0)
            } else {
                planner::joint(&prev.b, &own, &prev.ctl, &ctl, prev.trimmed, pl, self.lim)
            };
            if reduce > 0.0 {
                prev.kinked = prev.kinked.max(reduce);
                next.kinked = next.kinked.max(reduce);
            }
            if let Joint::Arc(a) = j {
                next.trimmed = a.trim;
            }
            next.into = j;
            prev.out = Some((j, own.vcap));
        }
        self.own.push_back(next);
        self.resolve(false);
        self.look(false);
    }

    /// Hands on the shaped blocks whose acceleration is final: left by a
    /// known junction and, under LinuxCNC, the last chord of their arc (all
    /// of an arc's chords blend alike).
    fn resolve(&mut self, end: bool) {
        loop {
            let upto = if !self.lcnc {
                // Every block but the last knows its junction out.
                match self.own.back() {
                    Some(o) if o.out.is_some() => self.own.len(),
                    _ => self.own.len().saturating_sub(1),
                }
            } else {
                // The first arc's chords up to its last, or all at the end.
                let ends = self
                    .own
                    .iter()
                    .position(|o| o.out.is_some() && !o.ctl.same_move);
                let known = self.own.iter().rposition(|o| o.out.is_some());
                match ends.or(if end { known } else { None }) {
                    Some(i) => i + 1,
                    None => 0,
                }
            };
            if upto == 0 {
                return;
            }
            let half = self.lcnc
                && self.own.iter().take(upto).any(|o| {
                    planner::own_half(&o.ctl, &o.into, &o.out.map_or(Joint::Stop, |x| x.0))
                });
            for _ in 0..upto {
                let Some(mut o) = self.own.pop_front() else {
                    return;
                };
                if self.lcnc {
                    planner::share_accel(&mut o.b, half, o.kinked, &self.lim.planner);
                }
                let (out, next_cap) = o.out.unwrap_or((Joint::Stop, 0.0));
                planner::emit_one(o.b, o.trimmed, out, next_cap, &mut |b, after| {
                    self.enter(b, after)
                });
            }
            if !self.lcnc {
                return;
            }
        }
    }

    /// The next block the control runs, `after` the limit leaving it.
    fn enter(&mut self, b: Block, after: f64) {
        let run = Run {
            b,
            vj: self.vj_next,
            at: self.length,
        };
        self.length += b.len;
        self.vj_next = after;
        self.runs += 1;
        if self.deep {
            self.la.push_back(run);
        } else {
            // No look-ahead depth: the limit is final as it stands.
            self.la_first += 1;
            self.windowed(run);
        }
    }

    /// A block with its final limit into the window, settling the window
    /// first when the block's start is an anchor.
    fn windowed(&mut self, run: Run) {
        if !self.win.is_empty() && anchor(run.vj, &run.b) {
            self.settle(run.vj);
        }
        self.win.push_back(run);
    }

    /// Applies the look-ahead depth to the blocks that have their depth of
    /// blocks after them (all at the chain's end).
    fn look(&mut self, end: bool) {
        let lim = self.lim;
        while let Some(first) = self.la.front() {
            let k = self.la_first;
            let on = self.ctl_of(first.b.index).lookahead_on;
            let d = planner::depth(on, &lim.planner);
            let mut run = *first;
            if k > 0 && d > 0 {
                if !end && self.runs < k + d {
                    return;
                }
                let stop = (k + d).min(self.runs);
                let a = self
                    .la
                    .iter()
                    .take(stop - k)
                    .map(|r| r.b.accel)
                    .fold(f64::INFINITY, f64::min);
                let at_end = self.la.get(stop - k).map_or(self.length, |r| r.at);
                run.vj = planner::stop_within(run.vj, a, at_end - run.at);
            }
            self.la.pop_front();
            self.la_first += 1;
            self.windowed(run);
        }
    }

    /// The mode of input block `index` (still held).
    fn ctl_of(&self, index: usize) -> BlockCtl {
        self.moves
            .get(index - self.base)
            .map_or_else(BlockCtl::default, |m| m.ctl)
    }

    /// The backward pass over the window from `v_out` (the final speed at
    /// its end), the forward pass from the speed entering it, and each
    /// block's time.
    fn settle(&mut self, v_out: f64) {
        let n = self.win.len();
        self.back.clear();
        self.back.resize(n + 1, 0.0);
        self.back[n] = v_out;
        for (k, r) in self.win.iter().enumerate().rev() {
            self.back[k] = capped(self.back[k + 1], r.vj, &r.b);
        }
        let mut v = self.v_in;
        for (k, r) in self.win.drain(..).enumerate() {
            let next = capped(v, self.back[k + 1], &r.b);
            let (t, cruise) = block_time_at(&r.b, r.b.vcap, v, next);
            if let Some(m) = self.moves.get_mut(r.b.index - self.base) {
                m.t += t;
            }
            if !r.b.rapid {
                self.sums.accel_limited_blocks += usize::from(!cruise);
            }
            v = next;
        }
        self.v_in = v;
        self.settled = true;
    }

    /// Hands on the input blocks no held block belongs to, with their
    /// final times and their share of the chain's figures.
    fn release(&mut self, done: &mut dyn FnMut(Timed)) {
        // Blocks go from `own` to `la` to `win` in order: the first held
        // is the oldest.
        let held = match (self.win.front(), self.la.front(), self.own.front()) {
            (Some(r), _, _) | (None, Some(r), _) => r.b.index,
            (None, None, Some(o)) => o.b.index,
            (None, None, None) => self.next,
        };
        if self.base >= held {
            return;
        }
        let rapid = self.lim.rapid;
        while self.base < held {
            let Some(m) = self.moves.pop_front() else {
                return;
            };
            self.base += 1;
            let s = &mut self.sums;
            let mut t = m.t;
            match m.kind {
                MoveKind::Dwell { s: d } => {
                    t = d.max(0.0);
                    s.dwell_s += t;
                    s.nominal_s += t;
                }
                MoveKind::Rapid => {
                    s.nominal_s += m.rapid_mm / rapid;
                    s.rapid_s += t;
                }
                MoveKind::Feed { nominal_min } => {
                    if t == 0.0 {
                        t = nominal_min.max(0.0) * 60.0;
                    }
                    s.nominal_s += nominal_min.max(0.0) * 60.0;
                    s.feed_s += t;
                }
            }
            done(Timed {
                t,
                dwell: matches!(m.kind, MoveKind::Dwell { .. }),
                ctl: m.ctl,
            });
        }
    }
}

/// The XYZ length of `m` from `before` on a rapid (its nominal time), else 0.
pub(crate) fn rapid_mm(m: &AxisMove, before: &[f64; 6]) -> f64 {
    match m.kind {
        MoveKind::Rapid => DVec3::new(
            m.target[0] - before[0],
            m.target[1] - before[1],
            m.target[2] - before[2],
        )
        .length(),
        _ => 0.0,
    }
}

/// Whether the backward pass gives `w` at the start of `b` whatever speed
/// `b` must end at (module doc).
fn anchor(w: f64, b: &Block) -> bool {
    w == 0.0 || w * ramp_time(w, b.accel, b.jerk) <= b.len * (1.0 - 1e-9)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timing::{estimate_controlled, PathMode, Planner, PlannerKind, TimeEstimate};
    use proptest::prelude::*;

    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn pick(&mut self, p: f64) -> bool {
            self.next() < p
        }
    }

    /// Limits of a machine under planner `kind`, with or without jerk.
    fn limits(rng: &mut Rng, kind: PlannerKind) -> Limits {
        let accel = 200.0 + 2000.0 * rng.next();
        let jerk = if rng.pick(0.5) {
            f64::INFINITY
        } else {
            5e3 + 5e4 * rng.next()
        };
        let mut planner = Planner::of(kind);
        if rng.pick(0.3) {
            planner.jerk = Some(2e4);
            planner.path_accel = Some(accel * 0.8);
        }
        if rng.pick(0.3) && planner.lookahead > 0 {
            // Short look-aheads keep many blocks' limits from it.
            planner.lookahead = 1 + (rng.next() * 6.0) as usize;
        }
        Limits {
            velocity: [60.0 + 200.0 * rng.next(), 150.0, 120.0, 90.0, 90.0, 180.0],
            accel: [accel, accel * 0.7, accel * 1.3, 500.0, 400.0, 700.0],
            jerk: [jerk; 6],
            rapid: 250.0,
            feed_max: 150.0,
            planner,
        }
    }

    /// A chain of `n` blocks: long and short feed blocks, runs straight on,
    /// reversals, rapids, dwells, blocks that do not move, rotary-only
    /// blocks, arcs in chords, and the modes changing now and then.
    fn chain(rng: &mut Rng, n: usize) -> (Vec<AxisMove>, Vec<BlockCtl>) {
        let (mut moves, mut ctl) = (Vec::new(), Vec::new());
        let mut here = [0.0f64; 6];
        let mut dir = [1.0f64, 0.0, 0.0];
        let mut c = BlockCtl::default();
        while moves.len() < n {
            if rng.pick(0.08) {
                c.mode = match (rng.next() * 3.0) as u32 {
                    0 => PathMode::ExactStop,
                    1 => PathMode::Blend { tolerance: None },
                    _ => PathMode::Blend {
                        tolerance: Some(0.001 + 0.2 * rng.next()),
                    },
                };
                c.soft = [None, Some(true), Some(false)][(rng.next() * 3.0) as usize];
                c.lookahead_on = rng.pick(0.5);
            }
            let feed = |len: f64, rng: &mut Rng| MoveKind::Feed {
                nominal_min: if rng.pick(0.05) {
                    0.0
                } else {
                    len / (300.0 + 6000.0 * rng.next())
                },
            };
            let r = rng.next();
            let mut k = c;
            k.stop_after = rng.pick(0.03);
            if r < 0.1 {
                // An arc in chords about Z.
                let chords = 2 + (rng.next() * 12.0) as usize;
                let radius = 0.2 + 20.0 * rng.next();
                let step = (0.02 + 0.1 * rng.next()) * if rng.pick(0.5) { 1.0 } else { -1.0 };
                let (cx, cy) = (here[0] - radius, here[1]);
                for j in 1..=chords {
                    let a = step * j as f64;
                    let mut to = here;
                    to[0] = cx + radius * a.cos();
                    to[1] = cy + radius * a.sin();
                    moves.push(AxisMove {
                        target: to,
                        kind: feed(radius * step.abs(), rng),
                    });
                    let mut kc = c;
                    kc.arc_radius = radius;
                    kc.same_move = j < chords;
                    kc.stop_after = j == chords && k.stop_after;
                    ctl.push(kc);
                }
                here = moves.last().map_or(here, |m| m.target);
                continue;
            }
            let mut to = here;
            let kind = if r < 0.16 {
                MoveKind::Rapid
            } else if r < 0.2 {
                MoveKind::Dwell {
                    s: 0.1 * rng.next(),
                }
            } else if r < 0.23 {
                feed(0.0, rng)
            } else if r < 0.28 {
                to[5] += 40.0 * (rng.next() - 0.5);
                feed(1.0, rng)
            } else {
                if rng.pick(0.3) {
                    dir = [rng.next() - 0.5, rng.next() - 0.5, 0.3 * (rng.next() - 0.5)];
                } else if rng.pick(0.1) {
                    dir = [-dir[0], -dir[1], -dir[2]];
                } else if rng.pick(0.3) {
                    dir[2] += 0.01 * (rng.next() - 0.5);
                }
                let len = if rng.pick(0.6) {
                    0.01 + 0.3 * rng.next()
                } else {
                    1.0 + 30.0 * rng.next()
                };
                for (t, d) in to.iter_mut().zip(dir) {
                    *t += len * d;
                }
                if rng.pick(0.1) {
                    to[3] += 5.0 * rng.next();
                }
                feed(len, rng)
            };
            if !matches!(kind, MoveKind::Dwell { .. }) {
                here = to;
            }
            moves.push(AxisMove { target: to, kind });
            ctl.push(k);
        }
        (moves, ctl)
    }

    /// The chain streamed: every block's time and the figures.
    fn streamed(
        start: [f64; 6],
        moves: &[AxisMove],
        ctl: &[BlockCtl],
        lim: &Limits,
    ) -> TimeEstimate {
        let mut s = ChainStream::new(start, lim);
        let mut per = Vec::new();
        for (m, c) in moves.iter().zip(ctl) {
            s.push(*m, *c, &mut |d| per.push(d.t));
        }
        let e = s.finish(&mut |d| per.push(d.t));
        TimeEstimate {
            total_s: e.total_s,
            nominal_s: e.nominal_s,
            per_move_s: per,
            rapid_s: e.rapid_s,
            feed_s: e.feed_s,
            dwell_s: e.dwell_s,
            velocity_limited_blocks: e.velocity_limited_blocks,
            accel_limited_blocks: e.accel_limited_blocks,
            planner: "",
            by_mode: Vec::new(),
        }
    }

    fn bits(e: &TimeEstimate) -> (Vec<u64>, [u64; 5], [usize; 2]) {
        (
            e.per_move_s.iter().map(|t| t.to_bits()).collect(),
            [e.total_s, e.nominal_s, e.rapid_s, e.feed_s, e.dwell_s].map(f64::to_bits),
            [e.velocity_limited_blocks, e.accel_limited_blocks],
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]
        /// Streamed and whole-chain estimates agree to the bit on random
        /// chains under every planner model.
        #[test]
        fn streamed_chain_is_the_whole_chain_to_the_bit(seed in 1u64..u64::MAX, n in 1usize..160) {
            let mut rng = Rng(seed);
            for kind in PlannerKind::ALL {
                let lim = limits(&mut rng, kind);
                let (moves, ctl) = chain(&mut rng, n);
                let start = [0.0; 6];
                let mut whole = estimate_controlled(start, &moves, &ctl, &lim);
                whole.planner = "";
                whole.by_mode.clear();
                let s = streamed(start, &moves, &ctl, &lim);
                prop_assert_eq!(bits(&s), bits(&whole), "{:?}", kind);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// `AxisChains` (the post's three estimates, no modes) agrees to
        /// the bit with the whole chain timed at its own feeds and at other
        /// minutes per block (`estimate_at`), under every planner model.
        #[test]
        fn axis_chains_are_the_whole_chain_at_any_minutes(seed in 1u64..u64::MAX, n in 1usize..160) {
            use crate::timing::{estimate_at, AxisChains};
            let mut rng = Rng(seed);
            for kind in PlannerKind::ALL {
                let lim = limits(&mut rng, kind);
                let (moves, _) = chain(&mut rng, n);
                let start = [1.0, -2.0, 0.5, 0.0, 0.0, 0.0];
                let mut minutes = [Vec::new(), Vec::new()];
                for m in &mut minutes {
                    *m = moves
                        .iter()
                        .map(|_| if rng.pick(0.1) { 0.0 } else { 1e-4 * rng.next() })
                        .collect();
                }
                let mut chains = AxisChains::<3>::new(start, &lim);
                for (i, m) in moves.iter().enumerate() {
                    // The first set of minutes is the blocks' own (and is
                    // ignored on every block that is not a feed block).
                    let own = match m.kind {
                        MoveKind::Feed { nominal_min } => nominal_min,
                        _ => 1.0,
                    };
                    chains.push(*m, [own, minutes[0][i], minutes[1][i]]);
                }
                let got = chains.finish();
                for (k, at) in [None, Some(&minutes[0][..]), Some(&minutes[1][..])].into_iter().enumerate() {
                    let mut whole = estimate_at(start, &moves, at, &lim);
                    whole.per_move_s.clear();
                    prop_assert_eq!(bits(&got[k]), bits(&whole), "{:?} estimate {}", kind, k);
                }
            }
        }
    }

    /// The stream holds only the blocks since the last anchor: a raster's
    /// rows, not the chain.
    #[test]
    fn a_raster_is_settled_row_by_row() {
        let lim = Limits::of(&crate::machine::Machine::default());
        let mut s = ChainStream::new([0.0; 6], &lim);
        let mut most = 0;
        let mut count = 0;
        for row in 0..40 {
            for k in 0..500 {
                let x = if row % 2 == 0 { k } else { 499 - k } as f64 * 0.03;
                let m = AxisMove {
                    target: [x, row as f64 * 0.03, (x * 0.3).sin(), 0.0, 0.0, 0.0],
                    kind: MoveKind::Feed {
                        nominal_min: 0.03 / 2000.0,
                    },
                };
                s.push(m, BlockCtl::default(), &mut |_| count += 1);
                most = most.max(s.win.len() + s.la.len() + s.own.len());
            }
        }
        s.finish(&mut |_| count += 1);
        assert_eq!(count, 20_000);
        assert!(most <= 1_100, "held {most} blocks at most");
    }
}
