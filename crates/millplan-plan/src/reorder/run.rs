//! The default reorder: the machining as it will run.
//!
//! What the user feels of an order is the spindle as the machine drives it:
//! the speeds after its range and acceleration limit (the `speed` pass's
//! model), how often they miss the constant-cutting-speed target
//! ([`crate::speed::VC_DEVIATION`]), their total variation Σ|Δn| (the dynamic
//! load) and the machining time with links and retracts. Each candidate order
//! is built with its links and measured exactly so; the best one that is worse
//! than the original on none of the three (time within the slack) is kept,
//! and when none is better the original stays as it was.

use super::{pass_ranges, xy, Built, LinkStyle, Links, Method, Verdict, APPROACH};
use crate::machine::Machine;
use crate::pipeline::Context;
use crate::speed::{self, SpeedError, SpeedParams};
use millplan_models::contact::{PathPoint, Surface};
use millplan_nc::{Operation, Program};

/// The machining of a program as it will run with spindle control.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct RunMeasures {
    /// Cutting points under spindle control.
    pub points: usize,
    /// Points whose speed misses the constant-cutting-speed target by more
    /// than 5 %, and their share.
    pub vc_deviation_points: usize,
    pub vc_deviation_share: f64,
    /// Σ|Δn| and max |Δn| of the speeds written, 1/min.
    pub total_variation_n: f64,
    pub max_delta_n: f64,
    /// Estimated time with the controlled feeds, links and retracts, s:
    /// the controller-aware estimate (acceleration, look-ahead) of
    /// [`crate::timing`] on the machine.
    pub time_s: f64,
    /// Points whose speed waits for the spindle's acceleration, and points
    /// clamped to its range.
    pub rate_limited: usize,
    pub clamped: usize,
    /// Points whose tool does not touch the part within tolerance, and of
    /// them those without any contact (the part may not match the program).
    pub off_surface: usize,
    pub no_contact: usize,
}

impl RunMeasures {
    /// Worse than `base` on none of the measures: no more points off the
    /// constant cutting speed, no larger Σ|Δn|, and at most `slack` (a
    /// fraction) longer.
    pub fn not_worse_than(&self, base: &RunMeasures, slack: f64) -> bool {
        self.vc_deviation_points <= base.vc_deviation_points
            && self.total_variation_n <= base.total_variation_n * (1.0 + 1e-12)
            && self.time_s <= base.time_s * (1.0 + slack)
    }

    /// One number to rank candidates that are not worse than `base` by: the
    /// sum of each measure relative to the original's.
    fn score(&self, base: &RunMeasures) -> f64 {
        self.vc_deviation_points as f64 / (base.vc_deviation_points.max(1) as f64)
            + self.total_variation_n / base.total_variation_n.max(1.0)
            + self.time_s / base.time_s.max(1e-9)
    }
}

/// The measures of `program` as it will run: spindle control applied as the
/// `speed` pass applies it, the time at the feeds it writes.
pub fn measure(
    program: &Program,
    surface: &Surface,
    machine: &Machine,
    sp: &SpeedParams,
) -> Result<RunMeasures, SpeedError> {
    Ok(measure_targets(program, surface, machine, sp, false)?.0)
}

/// [`measure`], and with `targets` the constant-cutting-speed target of every
/// cutting point in cutting order.
fn measure_targets(
    program: &Program,
    surface: &Surface,
    machine: &Machine,
    sp: &SpeedParams,
    targets: bool,
) -> Result<(RunMeasures, Vec<f64>), SpeedError> {
    let mut q = program.clone();
    let mut sp = *sp;
    sp.keep_rows = targets;
    let (rows, s, _) = speed::apply_in_place(&mut q, surface, machine, &sp)?;
    let t = crate::timing::estimate_program(&q, machine);
    let m = RunMeasures {
        points: s.points,
        vc_deviation_points: s.vc_deviation_points,
        vc_deviation_share: s.vc_deviation_share,
        total_variation_n: s.indicators.total_variation,
        max_delta_n: s.indicators.max_step,
        time_s: t.total_s,
        rate_limited: s.rate_limited,
        clamped: s.clamped,
        off_surface: s.gap_flagged,
        no_contact: s.no_contact,
    };
    Ok((m, rows.iter().map(|r| r.n_target).collect()))
}

/// A candidate order the default method measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Tried {
    /// Index of the operation in the program.
    pub operation: usize,
    pub candidate: String,
    pub measures: RunMeasures,
    /// Not worse than the original on any measure.
    pub admissible: bool,
}

/// What the search found for one operation.
pub(super) struct Search {
    /// The order and its moves; `None`: keep the operation as it is.
    pub chosen: Option<(Vec<usize>, Built)>,
    /// The working diameters the spindle control works from, in cutting
    /// order: of the original and of the chosen order (the original's when
    /// kept).
    pub dw_original: Vec<f64>,
    pub dw_chosen: Vec<f64>,
    pub tried: Vec<Tried>,
    pub verdict: Verdict,
}

/// The units an order is made of: the passes of the operation, with passes of
/// one or two points (the step-over move's end, a lead-in) joined to the pass
/// they lead into.
fn units(pts: &[PathPoint], jump: f64) -> Vec<(usize, usize)> {
    let passes = pass_ranges(pts);
    let mut out: Vec<(usize, usize)> = Vec::with_capacity(passes.len());
    let mut pending: Option<usize> = None;
    for (k, &(a, b)) in passes.iter().enumerate() {
        let start = pending.take().unwrap_or(a);
        let leads_in =
            b - a < 3 && k + 1 < passes.len() && (pts[b].cl - pts[b - 1].cl).length() <= jump;
        if leads_in {
            pending = Some(start);
        } else {
            out.push((start, b));
        }
    }
    out
}

/// A unit or a piece of one, cut in one direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Piece {
    a: usize,
    b: usize,
    /// Cut from its last point to its first.
    rev: bool,
    /// Cut with the units in backward order (its neighbour on the other side
    /// machined before it).
    back: bool,
}

/// One position of a candidate order: a cutting point and the table of
/// targets it is cut with ([`Model::target`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Step {
    k: u32,
    table: u8,
}

fn steps_of(pieces: &[Piece]) -> Vec<Step> {
    let mut out = Vec::new();
    for p in pieces {
        let table = 2 * p.back as u8 + p.rev as u8;
        let step = |k: usize| Step { k: k as u32, table };
        if p.rev {
            out.extend((p.a..p.b).rev().map(step));
        } else {
            out.extend((p.a..p.b).map(step));
        }
    }
    out
}

/// An estimate of a candidate's measures (points off the cutting speed, Σ|Δn|, time).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Approx {
    dev: f64,
    tv: f64,
    time: f64,
}

impl std::ops::Add for Approx {
    type Output = Approx;
    fn add(self, o: Approx) -> Approx {
        Approx {
            dev: self.dev + o.dev,
            tv: self.tv + o.tv,
            time: self.time + o.time,
        }
    }
}

impl std::ops::Sub for Approx {
    type Output = Approx;
    fn sub(self, o: Approx) -> Approx {
        Approx {
            dev: self.dev - o.dev,
            tv: self.tv - o.tv,
            time: self.time - o.time,
        }
    }
}

/// Weights of the measures in the search's single cost.
#[derive(Clone, Copy, Debug)]
struct Weights {
    dev: f64,
    tv: f64,
    time: f64,
}

impl Weights {
    /// Each measure relative to the original's; time counted `mu` times.
    fn relative_to(base: &RunMeasures, mu: f64) -> Weights {
        Weights {
            dev: 1.0 / base.vc_deviation_points.max(1) as f64,
            tv: 1.0 / base.total_variation_n.max(1.0),
            time: mu / base.time_s.max(1e-9),
        }
    }

    fn cost(&self, a: &Approx) -> f64 {
        self.dev * a.dev + self.tv * a.tv + self.time * a.time
    }
}

/// The fast model of a candidate: the spindle control of the `speed` pass
/// (the same function) on targets taken from exactly measured orders.
///
/// A point's working diameter depends on the direction it is cut in and on
/// which side of it is already machined. With the units cut in their order
/// (forwards or backwards) the machined side of a unit is that of the unit
/// before it, whatever the directions of the others; so four orders measured
/// exactly (units forwards or backwards, each as written or reversed) give
/// every point's target for every direction a candidate cuts it in.
struct Model<'a> {
    links: &'a Links<'a>,
    /// Whether a link goes directly, by its points.
    direct: std::cell::RefCell<rustc_hash::FxHashMap<(u32, u32), bool>>,
    /// Targets by table: 2·backwards + reversed, then by point.
    target: [Vec<f64>; 4],
    /// Targets measured at the first and second point after a retract (where
    /// the direction a point is cut in is known from one side only), by
    /// (table, point): learnt from the candidates measured exactly.
    after_retract: std::cell::RefCell<[rustc_hash::FxHashMap<(u8, u32), f64>; 2]>,
    machine: &'a Machine,
    sp: SpeedParams,
}

impl Model<'_> {
    /// Whether the tool goes from point i to point j directly, as the
    /// operation will be built ([`Links::direct`]).
    fn direct(&self, i: usize, j: usize) -> bool {
        if i.abs_diff(j) == 1 && self.links.pts[i].pass == self.links.pts[j].pass {
            return true;
        }
        *self
            .direct
            .borrow_mut()
            .entry((i as u32, j as u32))
            .or_insert_with(|| self.links.direct(i, j, LinkStyle::Low))
    }

    /// (cutting length of the move into point `to`, time of the rapids before
    /// it, s) when it follows point `from` (`None`: the operation's first).
    fn geo(&self, from: Option<usize>, to: usize) -> (f64, f64) {
        let (pts, safe) = (self.links.pts, self.links.safe);
        let q = pts[to].cl;
        // Each rapid of a retract starts and ends at rest: timed as the
        // measure times it (crate::timing), with acceleration.
        let lim = crate::timing::Limits {
            rapid: self.links.rapid / 60.0,
            ..crate::timing::Limits::of(self.machine)
        };
        let rapid = |d: millplan_geom::DVec3| {
            crate::timing::rest_to_rest_s(
                &lim,
                [d.x, d.y, d.z, 0.0, 0.0, 0.0],
                crate::timing::MoveKind::Rapid,
            )
        };
        let down = rapid(millplan_geom::DVec3::new(
            0.0,
            0.0,
            (safe - q.z - APPROACH).max(0.0),
        ));
        match from {
            Some(f) if self.direct(f, to) => ((q - pts[f].cl).length(), 0.0),
            Some(f) => {
                let a = pts[f].cl;
                let up = rapid(millplan_geom::DVec3::new(0.0, 0.0, (safe - a.z).max(0.0)));
                let across = (xy(q) - xy(a)).extend(0.0);
                // The cut before stops, the one after starts from rest: half
                // a ramp each beyond their time at the programmed feed.
                let ramp = |k: usize| {
                    let mv = &self.links.op.moves[self.links.idx[k]];
                    if mv.feed_mode == millplan_nc::FeedMode::PerMinute && mv.feed > 0.0 {
                        let v = mv.feed / 60.0;
                        v / (2.0 * lim.accel[0].min(lim.accel[1]))
                    } else {
                        0.0
                    }
                };
                (APPROACH, up + rapid(across) + down + ramp(f) + ramp(to))
            }
            None => (APPROACH, down),
        }
    }

    /// The estimate of cutting `steps` after point `from`.
    fn evaluate(&self, steps: &[Step], from: Option<usize>) -> Approx {
        let op = self.links.op;
        let mut target = Vec::with_capacity(steps.len());
        let mut geo = Vec::with_capacity(steps.len());
        let mut programmed = Vec::with_capacity(steps.len());
        let mut prev = from;
        let learnt = self.after_retract.borrow();
        let mut since = 2;
        for s in steps {
            let k = s.k as usize;
            since = match prev {
                Some(f) if self.direct(f, k) => since + 1,
                _ => 0,
            };
            let t = learnt
                .get(since)
                .and_then(|m| m.get(&(s.table, s.k)))
                .copied()
                .unwrap_or(self.target[s.table as usize][k]);
            target.push(t);
            geo.push(self.geo(prev, k));
            let mv = &op.moves[self.links.idx[k]];
            programmed.push((mv.feed, mv.feed_mode == millplan_nc::FeedMode::PerMinute));
            prev = Some(k);
        }
        let c = speed::control(&target, &geo, &programmed, self.machine, &self.sp);
        let mut a = Approx::default();
        for (k, (&n, &t)) in c.n.iter().zip(&target).enumerate() {
            a.dev += speed::deviates(n, t) as u8 as f64;
            if k > 0 {
                a.tv += (n - c.n[k - 1]).abs();
            }
            a.time += c.dt[k];
        }
        a
    }

    /// Learns the targets measured at the points after a retract in `steps`.
    fn learn(&self, steps: &[Step], targets: &[f64]) {
        let mut learnt = self.after_retract.borrow_mut();
        let mut since = 2;
        for (m, s) in steps.iter().enumerate() {
            since = if m > 0 && self.direct(steps[m - 1].k as usize, s.k as usize) {
                since + 1
            } else {
                0
            };
            if let (Some(map), Some(&t)) = (learnt.get_mut(since), targets.get(m)) {
                map.insert((s.table, s.k), t);
            }
        }
    }
}

/// A way of cutting one unit: its pieces in order, with what they cost alone.
struct Config {
    steps: Vec<Step>,
    internal: Approx,
}

/// Where a unit is best split: the point where its targets change fastest,
/// when faster than the spindle can follow there (`None` otherwise).
fn split_point(model: &Model, (a, b): (usize, usize), table: usize) -> Option<usize> {
    const W: usize = 3;
    if b - a < 4 * W {
        return None;
    }
    let t = &model.target[table];
    let pts = model.links.pts;
    let (sp, m) = (&model.sp, model.machine);
    let mut best: Option<(usize, f64)> = None;
    for i in a + W..b - W {
        let dn = (t[i + W] - t[i - W]).abs();
        let len: f64 = (i - W + 1..=i + W)
            .map(|k| (pts[k].cl - pts[k - 1].cl).length())
            .sum();
        let n = 0.5 * (t[i + W] + t[i - W]);
        let feed = match sp.feed {
            speed::FeedCoupling::ChipLoad => n * sp.flutes as f64 * sp.fz,
            speed::FeedCoupling::Programmed => model.links.op.moves[model.links.idx[i]].feed,
        }
        .clamp(m.feed_min, m.feed_max);
        let secs = len / feed * 60.0;
        let excess = dn - m.spindle_accel * secs;
        if excess > 0.0 && best.is_none_or(|b| excess > b.1) {
            best = Some((i, excess));
        }
    }
    best.map(|b| b.0)
}

/// The ways of cutting unit `u` (`split`: where it may be cut in two pieces):
/// whole, either way; split, its pieces in either order, each either way.
fn configs(model: &Model, u: (usize, usize), back: bool, split: Option<usize>) -> Vec<Config> {
    let whole = |rev| Piece {
        a: u.0,
        b: u.1,
        rev,
        back,
    };
    let mut ways: Vec<Vec<Piece>> = vec![vec![whole(false)], vec![whole(true)]];
    if let Some(s) = split {
        for first_left in [true, false] {
            for rl in [false, true] {
                for rr in [false, true] {
                    // Whole either way is listed already.
                    if (first_left && !rl && !rr) || (!first_left && rl && rr) {
                        continue;
                    }
                    let l = Piece {
                        a: u.0,
                        b: s,
                        rev: rl,
                        back,
                    };
                    let r = Piece {
                        a: s,
                        b: u.1,
                        rev: rr,
                        back,
                    };
                    ways.push(if first_left { vec![l, r] } else { vec![r, l] });
                }
            }
        }
    }
    ways.into_iter()
        .map(|pieces| {
            let steps = steps_of(&pieces);
            Config {
                internal: model.evaluate(&steps, None),
                steps,
            }
        })
        .collect()
}

/// The best way to cut the units in order by dynamic programming over the
/// units, each cut whole or in two pieces, for the single cost `w`: a unit's
/// cost is its own estimate, a joint's what cutting two units one after the
/// other adds to them cut alone.
fn plan(cfgs: &[Vec<Config>], joints: &[Vec<Vec<Approx>>], w: &Weights) -> Vec<Step> {
    let n = cfgs.len();
    if n == 0 {
        return Vec::new();
    }
    // best[k][c]: least cost of units 0..=k ending with config c.
    let mut best: Vec<Vec<f64>> = Vec::with_capacity(n);
    let mut from: Vec<Vec<usize>> = Vec::with_capacity(n);
    best.push(cfgs[0].iter().map(|c| w.cost(&c.internal)).collect());
    from.push(vec![0; cfgs[0].len()]);
    for k in 1..n {
        let (mut cur, mut par) = (Vec::new(), Vec::new());
        for (c2, cfg) in cfgs[k].iter().enumerate() {
            let (c1, v) = (0..cfgs[k - 1].len())
                .map(|c1| (c1, best[k - 1][c1] + w.cost(&joints[k][c1][c2])))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap_or((0, f64::INFINITY));
            cur.push(v + w.cost(&cfg.internal));
            par.push(c1);
        }
        best.push(cur);
        from.push(par);
    }
    let mut c = (0..cfgs[n - 1].len())
        .min_by(|&a, &b| best[n - 1][a].total_cmp(&best[n - 1][b]))
        .unwrap_or(0);
    let mut chosen = vec![0usize; n];
    for k in (0..n).rev() {
        chosen[k] = c;
        c = from[k][c];
    }
    chosen
        .iter()
        .enumerate()
        .flat_map(|(k, &c)| cfgs[k][c].steps.iter().copied())
        .collect()
}

/// What cutting config c2 of a unit right after config c1 of the one before
/// adds to each alone, over `window` points either side of the link.
fn joint(model: &Model, c1: &Config, c2: &Config, window: usize) -> Approx {
    let tail = &c1.steps[c1.steps.len().saturating_sub(window)..];
    let head = &c2.steps[..c2.steps.len().min(window)];
    let both: Vec<Step> = tail.iter().chain(head).copied().collect();
    model.evaluate(&both, None) - model.evaluate(tail, None) - model.evaluate(head, None)
}

/// The units in order, each cut whole in one direction.
fn whole(units: &[(usize, usize)], back: bool, rev: impl Fn(usize) -> bool) -> Vec<Step> {
    let seq: Vec<usize> = if back {
        (0..units.len()).rev().collect()
    } else {
        (0..units.len()).collect()
    };
    let pieces: Vec<Piece> = seq
        .into_iter()
        .map(|u| Piece {
            a: units[u].0,
            b: units[u].1,
            rev: rev(u),
            back,
        })
        .collect();
    steps_of(&pieces)
}

/// The candidates cut with whole units: the start corners (the units
/// forwards or backwards, each as written or each reversed: a zig-zag stays a
/// zig-zag) and one-way (every unit the way the longest one goes, or against it).
fn fixed_candidates(pts: &[PathPoint], units: &[(usize, usize)]) -> Vec<(String, Vec<Step>)> {
    let way = |b: bool| if b { "backwards" } else { "forwards" };
    let mut out = Vec::new();
    for back in [false, true] {
        for flip in [false, true] {
            out.push((
                format!(
                    "start corner: passes {}, {}",
                    way(back),
                    if flip { "each reversed" } else { "as written" }
                ),
                whole(units, back, |_| flip),
            ));
        }
    }
    let dir = |u: usize| {
        let (a, b) = units[u];
        let v = pts[b - 1].cl - pts[a].cl;
        millplan_geom::DVec2::new(v.x, v.y)
    };
    if let Some(reference) = (0..units.len())
        .map(dir)
        .max_by(|a, b| a.length().total_cmp(&b.length()))
    {
        for back in [false, true] {
            for sign in [1.0, -1.0] {
                out.push((
                    format!(
                        "one-way{}: passes {}",
                        if sign < 0.0 { ", against" } else { "" },
                        way(back)
                    ),
                    whole(units, back, |u| dir(u).dot(reference) * sign < 0.0),
                ));
            }
        }
    }
    out
}

/// Searches the orders of operation `oi` of `program` for one that runs
/// better than the original and worse on nothing.
///
/// The candidates: the start corners and one-way orders, measured exactly;
/// from the start corners' targets the fast model ([`Model`]) then plans, for
/// the units forwards and backwards, how to cut each unit (whole, or split
/// where its targets change faster than the spindle follows, each piece
/// either way; zig-zag or one-way between units) by dynamic programming, with
/// the weight of time that keeps the estimate within the time allowed. The
/// best few plans are built and measured exactly, what they measure teaches
/// the model, and it plans again (`ROUNDS` times). The best candidate worse
/// than the original on no measure wins if it is better on one. `tick(done,
/// total)` hears of every exact measurement (the original's too); the total is
/// what the rounds could measure at most and is reported when the search ends
/// earlier.
pub(super) fn search(
    program: &Program,
    oi: usize,
    cx: &Context,
    links: &Links,
    jump: f64,
    tick: &dyn Fn(usize, usize),
) -> Result<Search, SpeedError> {
    let Some(surface) = cx.surface() else {
        return Err(SpeedError::Invalid("the part surface is needed".into()));
    };
    let p = links.p;
    let single = |op: Operation| Program {
        name: program.name.clone(),
        source: program.source,
        units: program.units,
        operations: vec![op],
        unterminated: None,
    };
    let units = units(links.pts, jump);
    let fixed = fixed_candidates(links.pts, &units);
    let rounds = if links.pts.len() > 200_000 { 1 } else { ROUNDS };
    // Exact measurements at most: the original, the fixed candidates, the plans.
    let total = 1 + fixed.len() + rounds * PLANS_MEASURED;
    let done = std::cell::Cell::new(0);
    let count = || {
        done.set(done.get() + 1);
        tick(done.get(), total);
    };
    tick(0, total);
    let (base, base_targets) = measure_targets(
        &single(links.op.clone()),
        surface,
        &cx.machine,
        &p.speed,
        true,
    )?;
    count();
    let dw_of = |t: &[f64]| -> Vec<f64> {
        t.iter()
            .map(|n| 1000.0 * p.speed.vc / (std::f64::consts::PI * n))
            .collect()
    };
    let mut tried = vec![Tried {
        operation: oi,
        candidate: "original".into(),
        measures: base,
        admissible: true,
    }];
    // Measures a candidate exactly: built with its links, spindle control
    // applied; the targets of its points in cutting order.
    let mut best: Option<(f64, Vec<usize>, Built, Vec<f64>)> = None;
    let mut exact = |name: String, steps: &[Step], tried: &mut Vec<Tried>| {
        let order: Vec<usize> = steps.iter().map(|s| s.k as usize).collect();
        let built = links.build(&order, &[], LinkStyle::Low);
        let op = links.operation(built.moves.clone(), Method::AsRun);
        let (m, t) = measure_targets(&single(op), surface, &cx.machine, &p.speed, true)?;
        count();
        let admissible = m.not_worse_than(&base, p.time_slack);
        let score = m.score(&base);
        if admissible && better(&m, &base) && best.as_ref().is_none_or(|b| score < b.0) {
            best = Some((score, order, built, t.clone()));
        }
        tried.push(Tried {
            operation: oi,
            candidate: name,
            measures: m,
            admissible,
        });
        Ok::<_, SpeedError>(t)
    };
    let mut target: [Vec<f64>; 4] = Default::default();
    let mut measured = Vec::new();
    for (i, (name, steps)) in fixed.iter().enumerate() {
        let t = exact(name.clone(), steps, &mut tried)?;
        if i < 4 {
            // The start corners: every point's target in that direction and order.
            let mut v = vec![0.0; links.pts.len()];
            for (s, &x) in steps.iter().zip(&t) {
                v[s.k as usize] = x;
            }
            target[i] = v;
        }
        measured.push((steps.clone(), t));
    }
    let model = Model {
        links,
        direct: Default::default(),
        target,
        after_retract: Default::default(),
        machine: &cx.machine,
        sp: p.speed,
    };
    for (steps, t) in &measured {
        model.learn(steps, t);
    }
    let window = window(&model, links.pts);
    let mut seen: Vec<Vec<Step>> = measured.into_iter().map(|m| m.0).collect();
    for _ in 0..rounds {
        let mut plans = plans(&model, &units, &base, window);
        plans.retain(|q| !seen.contains(&q.2));
        plans.sort_by(|a, b| a.0.total_cmp(&b.0));
        if plans.is_empty() {
            break;
        }
        for (_, name, steps) in plans.into_iter().take(PLANS_MEASURED) {
            let t = exact(name, &steps, &mut tried)?;
            model.learn(&steps, &t);
            seen.push(steps);
        }
    }
    tick(total, total);
    Ok(Search {
        verdict: if best.is_some() {
            Verdict::Improved
        } else {
            Verdict::Kept
        },
        dw_original: dw_of(&base_targets),
        dw_chosen: dw_of(best.as_ref().map_or(&base_targets, |b| &b.3)),
        chosen: best.map(|(_, o, b, _)| (o, b)),
        tried,
    })
}

/// Rounds of planning and measuring.
const ROUNDS: usize = 3;

/// Plans measured exactly per round.
const PLANS_MEASURED: usize = 4;

/// About a second of cutting, in points: longer than the spindle takes for
/// any change its targets ask, so the window either side of a joint.
fn window(model: &Model, pts: &[PathPoint]) -> usize {
    let (sp, m) = (&model.sp, model.machine);
    let t = &model.target[0];
    let n = t.iter().sum::<f64>() / t.len().max(1) as f64;
    let feed = (n * sp.flutes as f64 * sp.fz).clamp(m.feed_min, m.feed_max);
    let mut steps: Vec<f64> = pts
        .windows(2)
        .map(|w| (w[1].cl - w[0].cl).length())
        .filter(|d| *d > 1e-9)
        .collect();
    steps.sort_by(f64::total_cmp);
    let spacing = steps.get(steps.len() / 2).copied().unwrap_or(1.0);
    ((feed / 60.0 / spacing).ceil() as usize).clamp(8, 600)
}

/// The model's plans that it expects to be worse than the original on no
/// measure, with its score (lower is better) and a name: for the units
/// forwards and backwards, two weights of Σ|Δn| and three margins under the
/// time allowed, the weight of time found by bisection.
fn plans(
    model: &Model,
    units: &[(usize, usize)],
    base: &RunMeasures,
    window: usize,
) -> Vec<(f64, String, Vec<Step>)> {
    let slack = model.links.p.time_slack;
    let mut plans: Vec<(f64, String, Vec<Step>)> = Vec::new();
    for back in [false, true] {
        let seq: Vec<(usize, usize)> = if back {
            units.iter().rev().copied().collect()
        } else {
            units.to_vec()
        };
        let cfgs: Vec<Vec<Config>> = seq
            .iter()
            .map(|&u| configs(model, u, back, split_point(model, u, 2 * back as usize)))
            .collect();
        let joints: Vec<Vec<Vec<Approx>>> = (0..cfgs.len())
            .map(|k| {
                if k == 0 {
                    return Vec::new();
                }
                cfgs[k - 1]
                    .iter()
                    .map(|c1| {
                        cfgs[k]
                            .iter()
                            .map(|c2| joint(model, c1, c2, window))
                            .collect()
                    })
                    .collect()
            })
            .collect();
        for tv_weight in [1.0, 4.0] {
            for margin in [1.0, 0.99, 0.98] {
                let limit = base.time_s * (1.0 + slack) * margin;
                let run = |mu: f64| {
                    let mut w = Weights::relative_to(base, mu);
                    w.tv *= tv_weight;
                    let steps = plan(&cfgs, &joints, &w);
                    let a = model.evaluate(&steps, None);
                    (steps, a)
                };
                // More weight on time: fewer retracts, quicker directions.
                let (mut lo, mut hi) = (0.0f64, 64.0f64);
                let mut found = run(lo);
                if found.1.time > limit {
                    found = run(hi);
                    for _ in 0..10 {
                        let mid = 0.5 * (lo + hi);
                        let r = run(mid);
                        if r.1.time <= limit {
                            hi = mid;
                            found = r;
                        } else {
                            lo = mid;
                        }
                    }
                }
                let (steps, a) = found;
                let fits = a.dev <= base.vc_deviation_points as f64
                    && a.tv <= base.total_variation_n
                    && a.time <= base.time_s * (1.0 + slack);
                if fits && !plans.iter().any(|q| q.2 == steps) {
                    plans.push((
                        Weights::relative_to(base, 1.0).cost(&a),
                        format!(
                            "planned: passes {}, Σ|Δn| weight {tv_weight}, {:.0} % under the time allowed",
                            if back { "backwards" } else { "forwards" },
                            100.0 * (1.0 - margin)
                        ),
                        steps,
                    ));
                }
            }
        }
    }
    plans
}

/// Better than the original on one measure at least: a point fewer off the
/// cutting speed, or Σ|Δn| or the time down by 0.5 %.
fn better(m: &RunMeasures, base: &RunMeasures) -> bool {
    m.vc_deviation_points < base.vc_deviation_points
        || m.total_variation_n < 0.995 * base.total_variation_n
        || m.time_s < 0.995 * base.time_s
}

#[cfg(test)]
mod tests {
    use super::super::{reorder_in, Method, ReorderParams, Verdict};
    use super::*;
    use millplan_geom::analytic::{tessellate, DemoSurface, HeightField};
    use millplan_geom::{DVec2, DVec3, TriMesh};
    use millplan_models::contact::Surface;
    use millplan_nc::generate::{raster, Raster};
    use millplan_nc::MoveKind;

    /// Free-form test surfaces over a 40 mm square, with exact gradients.
    #[derive(Clone, Copy, Debug)]
    enum Shape {
        /// z = 2·sin(2πx/40)·cos(2πy/40).
        Wave,
        /// A Gaussian dome 8 mm high in the middle.
        Dome,
        /// z = (x'² − y'²)/60 about the middle.
        Saddle,
    }

    impl HeightField for Shape {
        fn z(&self, x: f64, y: f64) -> f64 {
            let (u, v) = (x - 20.0, y - 20.0);
            let k = std::f64::consts::TAU / 40.0;
            match self {
                Shape::Wave => 2.0 * (k * x).sin() * (k * y).cos(),
                Shape::Dome => 8.0 * (-(u * u + v * v) / 120.0).exp(),
                Shape::Saddle => (u * u - v * v) / 60.0,
            }
        }

        fn grad(&self, x: f64, y: f64) -> DVec2 {
            let (u, v) = (x - 20.0, y - 20.0);
            let k = std::f64::consts::TAU / 40.0;
            match self {
                Shape::Wave => DVec2::new(
                    2.0 * k * (k * x).cos() * (k * y).cos(),
                    -2.0 * k * (k * x).sin() * (k * y).sin(),
                ),
                Shape::Dome => {
                    let e = 8.0 * (-(u * u + v * v) / 120.0).exp();
                    DVec2::new(-e * 2.0 * u / 120.0, -e * 2.0 * v / 120.0)
                }
                Shape::Saddle => DVec2::new(2.0 * u / 60.0, -2.0 * v / 60.0),
            }
        }

        fn domain(&self) -> (DVec2, DVec2) {
            (DVec2::ZERO, DVec2::splat(40.0))
        }
    }

    /// The paper's conditions: D10 ball, vc 63 m/min, fz 0.125 mm, ap 0.3 mm.
    fn params() -> ReorderParams {
        let mut p = ReorderParams::new(Method::AsRun);
        p.speed = SpeedParams::new(63.0, 0.125, 2, 0.3);
        p
    }

    fn measured(p: &Program, mesh: &TriMesh, machine: &Machine) -> RunMeasures {
        let s = Surface::new(mesh);
        measure(p, &s, machine, &params().speed).expect("measures")
    }

    /// A high-speed machining centre's axes (those of examples/machine.toml):
    /// X and Y 5000 mm/s², Z 4000 mm/s², 40 m/min.
    fn hsc() -> Machine {
        let mut m = Machine::default();
        for (a, acc) in [
            (&mut m.axes.x, 5000.0),
            (&mut m.axes.y, 5000.0),
            (&mut m.axes.z, 4000.0),
        ] {
            a.velocity = Some(40000.0);
            a.accel = Some(acc);
        }
        m
    }

    /// The end points of the cutting moves, rounded to 0.1 µm, sorted.
    fn cut_points(p: &Program) -> Vec<[i64; 3]> {
        let mut v: Vec<[i64; 3]> = p
            .moves()
            .filter(|m| m.kind == MoveKind::Linear)
            .map(|m| m.end.to_array().map(|x| (x * 1e4).round() as i64))
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// Reorders a zig-zag raster over `s` by the default method; checks that
    /// every point is still cut and that the result is worse than the
    /// original on none of the three measures; returns both measures.
    fn check(s: &dyn HeightField, r: &Raster) -> (RunMeasures, RunMeasures, Verdict) {
        let (prog, _) = raster(s, r);
        check_program(s, prog, &Machine::default())
    }

    fn check_program(
        s: &dyn HeightField,
        prog: Program,
        machine: &Machine,
    ) -> (RunMeasures, RunMeasures, Verdict) {
        let mesh = tessellate(s, 0.5);
        let cx = crate::pipeline::Context::new(machine.clone()).with_part(&mesh);
        let got = reorder_in(&prog, &cx, &params()).expect("reorders");
        millplan_nc::verify::verify(&got.program).expect("verifies");
        assert_eq!(cut_points(&got.program), cut_points(&prog));
        let (before, after) = (
            measured(&prog, &mesh, machine),
            measured(&got.program, &mesh, machine),
        );
        assert_eq!(before.points, after.points);
        assert!(
            after.vc_deviation_points <= before.vc_deviation_points
                && after.total_variation_n <= before.total_variation_n
                && after.time_s <= 1.03 * before.time_s,
            "{before:?}\n{after:?}"
        );
        let verdict = got.verdict.expect("a verdict");
        // What the search reports for its choice is what the program measures.
        let chosen = got
            .tried
            .iter()
            .filter(|t| t.admissible)
            .map(|t| t.measures)
            .find(|m| m.vc_deviation_points == after.vc_deviation_points);
        assert!(chosen.is_some(), "{:?}", got.tried);
        if verdict == Verdict::Kept {
            assert_eq!(got.program, prog);
        }
        (before, after, verdict)
    }

    #[test]
    fn never_worse_on_free_form_surfaces() {
        let r = Raster {
            stepover: 1.5,
            step: 0.75,
            ..Raster::default()
        };
        for s in [Shape::Wave, Shape::Dome, Shape::Saddle] {
            let (before, after, verdict) = check(&s, &r);
            // Measured, not asserted: the share each surface loses.
            eprintln!("{s:?}: {verdict:?}\n  {before:?}\n  {after:?}");
        }
    }

    #[test]
    fn improves_the_demo_part_under_the_papers_conditions() {
        // The demo part (dome, wave, slopes to 40°), a zig-zag raster with
        // 1 mm stepover: the spindle misses the cutting speed where passes turn
        // and cross the dome; the default method cuts that share by a fifth
        // at least, and lowers Σ|Δn|, within 3 % more time. The time is
        // estimated with acceleration on a high-speed machining centre (the
        // paper's kind of machine); on the built-in machine's conservative
        // 1000 mm/s² retracts cost more and the gain is smaller (docs/benchmarks.md).
        let (prog, _) = raster(
            &DemoSurface::default(),
            &Raster {
                stepover: 1.0,
                step: 0.5,
                ..Raster::default()
            },
        );
        let (before, after, verdict) = check_program(&DemoSurface::default(), prog, &hsc());
        assert_eq!(verdict, Verdict::Improved);
        assert!(
            (after.vc_deviation_points as f64) < 0.8 * before.vc_deviation_points as f64,
            "{before:?}\n{after:?}"
        );
        assert!(after.total_variation_n < before.total_variation_n);
    }

    #[test]
    fn keeps_an_order_nothing_beats() {
        // A plate: the same working diameter everywhere, so every order runs
        // at one speed, and none is quicker than the raster as written.
        #[derive(Clone, Copy)]
        struct Plate;
        impl HeightField for Plate {
            fn z(&self, _: f64, _: f64) -> f64 {
                0.0
            }
            fn grad(&self, _: f64, _: f64) -> DVec2 {
                DVec2::ZERO
            }
            fn domain(&self) -> (DVec2, DVec2) {
                (DVec2::ZERO, DVec2::splat(20.0))
            }
        }
        let (mut prog, _) = raster(
            &Plate,
            &Raster {
                stepover: 2.0,
                step: 1.0,
                ..Raster::default()
            },
        );
        // Approached as the reorder approaches: a rapid to 1 mm above the
        // first point, then the plunge.
        let op = &mut prog.operations[0];
        let first = op.moves[1].end;
        op.moves
            .insert(1, millplan_nc::Move::rapid(first + DVec3::Z * APPROACH));
        for e in &mut op.events {
            if e.at >= 1 {
                e.at += 1;
            }
        }
        let (before, after, verdict) = check_program(&Plate, prog, &Machine::default());
        assert_eq!(verdict, Verdict::Kept, "{before:?}");
        assert_eq!(before, after);
    }

    /// Every report the progress hook heard: (phase, done, total).
    type Heard = std::sync::Mutex<Vec<(String, usize, usize)>>;

    /// Runs the reorder pass through the pipeline with a hook that records
    /// what it hears; checks each phase's counts only grow and end at its
    /// total, and returns the phases in the order they began.
    fn phases_heard(method: Method, heard: &Heard) -> (Vec<String>, super::super::Outcome) {
        let (prog, _) = raster(
            &Shape::Wave,
            &Raster {
                stepover: 2.0,
                step: 1.0,
                ..Raster::default()
            },
        );
        let mesh = tessellate(&Shape::Wave, 0.5);
        let hook = |phase: &str, done: usize, total: usize| {
            heard
                .lock()
                .expect("lock")
                .push((phase.to_string(), done, total));
        };
        let cx = crate::pipeline::Context::new(Machine::default())
            .with_part(&mesh)
            .with_progress(&hook);
        let mut pass = super::super::ReorderPass::new(ReorderParams { method, ..params() });
        let mut p = prog.clone();
        crate::pipeline::run(&mut [&mut pass], &mut p, &cx).expect("reorders");
        let heard = heard.lock().expect("lock").clone();
        let mut phases: Vec<String> = Vec::new();
        for (phase, _, _) in &heard {
            if phases.last() != Some(phase) {
                assert!(!phases.contains(phase), "{phase} began twice: {heard:?}");
                phases.push(phase.clone());
            }
        }
        for phase in &phases {
            let counts: Vec<(usize, usize)> = heard
                .iter()
                .filter(|h| &h.0 == phase)
                .map(|h| (h.1, h.2))
                .collect();
            let total = counts[0].1;
            assert!(total > 0, "{phase}");
            assert!(counts.iter().all(|c| c.1 == total), "{phase}: {counts:?}");
            assert!(
                counts.windows(2).all(|w| w[0].0 <= w[1].0),
                "{phase} went back: {counts:?}"
            );
            assert_eq!(counts.last().map(|c| c.0), Some(total), "{phase}");
        }
        (phases, pass.outcome.expect("an outcome"))
    }

    #[test]
    fn progress_hook_hears_every_phase_grow_to_its_total() {
        let heard = Heard::default();
        let (phases, o) = phases_heard(Method::AsRun, &heard);
        assert_eq!(
            phases,
            [
                "reorder: candidate orders measured",
                "reorder: both orders measured as run"
            ]
        );
        // One count per exact measurement: the original and every candidate.
        let counts: Vec<usize> = heard
            .lock()
            .expect("lock")
            .iter()
            .filter(|h| h.0 == phases[0])
            .map(|h| h.1)
            .collect();
        assert_eq!(
            counts[..o.tried.len() + 1],
            (0..=o.tried.len()).collect::<Vec<_>>()[..]
        );
        let heard = Heard::default();
        let (phases, o) = phases_heard(Method::Paper, &heard);
        assert_eq!(
            phases,
            [
                "reorder: thesis search",
                "reorder: links checked for gouges",
                "reorder: D_w along both orders",
                "reorder: both orders measured as run"
            ]
        );
        // The search reports the points placed, then D_w along both orders.
        let totals: Vec<usize> = heard.lock().expect("lock").iter().map(|h| h.2).collect();
        assert_eq!(totals[0], o.before.points);
        assert!(totals.contains(&(2 * o.before.points)));
        let heard = Heard::default();
        let (phases, _) = phases_heard(Method::Optimised, &heard);
        assert_eq!(
            phases[..2],
            [
                "reorder: 2-opt over the passes",
                "reorder: links checked for gouges"
            ]
        );
    }
}
