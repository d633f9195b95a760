//! Constant-cutting-speed spindle control for ball-end finishing (paper 000,
//! thesis 3; spec `working-diameter.md` §3.3–3.4 and §5.7).
//!
//! For every cutting point of every ball-end operation: the working diameter D_w
//! from the contact analysis, the spindle speed n = 1000·vc/(π·D_w), clamped to the
//! machine's range; an S word only when the speed moves by more than a threshold;
//! then a forward–backward rate limit so consecutive speeds differ by at most the
//! spindle's acceleration times the block time; finally the feed F = n·z·fz (or the
//! programmed feed). Only spindle speeds and feeds change: positions never do.

use millplan_geom::{DVec3, TriMesh};
use millplan_models::contact::{
    self, Convention, ConventionCheck, NormalMode, PathPoint, PointResult, Surface,
};
use millplan_models::wd::{Neighbour, Side};
use millplan_nc::{CutterKind, FeedMode, Program};
use rayon::prelude::*;

use crate::machine::Machine;
use crate::pipeline::{Changes, Context, Need, Pass, PassError, PassInfo};

/// How the feed follows the spindle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FeedCoupling {
    /// F = n·z·fz: constant chip load (default).
    ChipLoad,
    /// Keep the programmed feed.
    Programmed,
}

#[derive(Clone, Copy, Debug)]
pub struct SpeedParams {
    /// Cutting speed, m/min.
    pub vc: f64,
    /// Feed per tooth, mm.
    pub fz: f64,
    pub flutes: u32,
    /// Stock thickness along the normal, mm.
    pub ap: f64,
    pub feed: FeedCoupling,
    /// Write a new S only when the speed changes by more than this, 1/min.
    pub s_threshold: f64,
    /// Tip or centre; `None` detects it from the data.
    pub convention: Option<Convention>,
    pub normals: NormalMode,
    /// Flag points whose centre-to-mesh distance differs from R by more than this, mm.
    pub gap_tol: f64,
    /// Use the paper's nearest-in-centre facet (comparison only).
    pub nearest_incentre: bool,
    /// Ball diameter for operations whose tool has no geometry (G-code programs
    /// name tools by number only), mm.
    pub ball_d: Option<f64>,
    /// Keep a [`PointRow`] per cutting point (for tables and reports); without
    /// it only the summary is made, in a fraction of the memory.
    pub keep_rows: bool,
}

impl SpeedParams {
    pub fn new(vc: f64, fz: f64, flutes: u32, ap: f64) -> SpeedParams {
        SpeedParams {
            vc,
            fz,
            flutes,
            ap,
            feed: FeedCoupling::ChipLoad,
            s_threshold: 1.0,
            convention: None,
            normals: NormalMode::Smooth,
            gap_tol: 0.02,
            nearest_incentre: false,
            ball_d: None,
            keep_rows: true,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SpeedError {
    #[error("the program has no ball-end operation (CUTTER/d,d/2,0,d/2 or TLDATA/MILL,d,d/2; for G-code name the ball with --ball-d): nothing to control")]
    NoBallOperation,
    #[error("{0}")]
    Invalid(String),
}

/// One row of the per-point table.
#[derive(Clone, Debug, PartialEq)]
pub struct PointRow {
    /// Operation and move index in the program.
    pub op: usize,
    pub mv: usize,
    pub line: u32,
    /// Ball diameter of the operation, mm.
    pub d: f64,
    pub cl: DVec3,
    pub r: PointResult,
    /// Spindle speed for constant vc before any limit.
    pub n_target: f64,
    /// Spindle speed written.
    pub n: f64,
    /// Feed written, mm/min.
    pub feed: f64,
    /// Path length from the previous cutting point, mm.
    pub ds: f64,
    /// Time from the previous cutting point, s.
    pub dt: f64,
    pub clamped: bool,
    pub rate_limited: bool,
    pub held: bool,
    pub gap_flag: bool,
}

/// Range, mean and standard deviation.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Stats {
    pub min: f64,
    pub max: f64,
    pub mean: f64,
    pub std: f64,
}

impl Stats {
    /// One pass over the values (Welford's update for the variance): the
    /// summary reads a million rows, and each extra pass costs a sweep of
    /// them through memory.
    pub fn of(v: impl Iterator<Item = f64>) -> Stats {
        let mut acc = StatsAcc::default();
        v.for_each(|x| acc.push(x));
        acc.finish()
    }
}

/// [`Stats`] gathered one value at a time.
#[derive(Clone, Copy, Debug)]
struct StatsAcc {
    n: usize,
    mean: f64,
    m2: f64,
    min: f64,
    max: f64,
}

impl Default for StatsAcc {
    fn default() -> StatsAcc {
        StatsAcc {
            n: 0,
            mean: 0.0,
            m2: 0.0,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        }
    }
}

impl StatsAcc {
    #[inline]
    fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
        self.min = self.min.min(x);
        self.max = self.max.max(x);
    }

    fn finish(&self) -> Stats {
        if self.n == 0 {
            return Stats::default();
        }
        Stats {
            min: self.min,
            max: self.max,
            mean: self.mean,
            std: (self.m2 / self.n as f64).sqrt(),
        }
    }
}

/// The dynamic-load indicators of spec §3.4 over a sequence of spindle speeds.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Indicators {
    /// Σ|n_{i+1} − n_i|, 1/min.
    pub total_variation: f64,
    /// max |Δn| between successive points, 1/min.
    pub max_step: f64,
    /// max and mean |Δn|/Δt, 1/min per second.
    pub max_accel: f64,
    pub mean_accel: f64,
    /// Σ n_i·Δs_i, (1/min)·mm.
    pub speed_integral: f64,
}

impl Indicators {
    pub fn of(n: &[f64], ds: &[f64], dt: &[f64]) -> Indicators {
        let mut acc = IndicatorsAcc::default();
        for i in 0..n.len() {
            acc.push(n[i], ds[i], dt[i]);
        }
        acc.finish()
    }
}

/// [`Indicators`] gathered one point at a time.
#[derive(Clone, Copy, Debug, Default)]
struct IndicatorsAcc {
    r: Indicators,
    prev: Option<f64>,
    acc_sum: f64,
    acc_n: usize,
}

impl IndicatorsAcc {
    #[inline]
    fn push(&mut self, n: f64, ds: f64, dt: f64) {
        let r = &mut self.r;
        r.speed_integral += n * ds;
        if let Some(p) = self.prev {
            let d = (n - p).abs();
            r.total_variation += d;
            r.max_step = r.max_step.max(d);
            if dt > 0.0 {
                let a = d / dt;
                r.max_accel = r.max_accel.max(a);
                self.acc_sum += a;
                self.acc_n += 1;
            }
        }
        self.prev = Some(n);
    }

    fn finish(&self) -> Indicators {
        Indicators {
            mean_accel: if self.acc_n > 0 {
                self.acc_sum / self.acc_n as f64
            } else {
                0.0
            },
            ..self.r
        }
    }
}

/// What the pass did, for the JSON summary and the report.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Summary {
    pub points: usize,
    pub operations: usize,
    pub convention: Convention,
    pub convention_check: Option<ConventionCheck>,
    pub clamped: usize,
    pub rate_limited: usize,
    pub held: usize,
    pub feed_clamped: usize,
    pub gap_flagged: usize,
    pub no_contact: usize,
    pub corners: usize,
    pub first_pass_points: usize,
    pub d_w: Stats,
    pub spindle: Stats,
    /// Spindle speed the program had (the constant one), 1/min.
    pub constant_spindle: f64,
    /// Cutting speed the surface sees at the constant spindle speed, m/min.
    pub vc_constant: Stats,
    /// Cutting speed with control, m/min.
    pub vc_controlled: Stats,
    /// Indicators at the constant spindle speed are all zero but the integral.
    pub indicators: Indicators,
    /// Indicators of the target speeds before machine limits.
    pub indicators_target: Indicators,
    /// Points where the spindle cannot hold the constant cutting speed: the
    /// speed written differs from the target by more than
    /// [`VC_DEVIATION`] of it (the machine's range or acceleration would not
    /// let it follow).
    pub vc_deviation_points: usize,
    /// Their share of the points.
    pub vc_deviation_share: f64,
    /// Share of the points whose cutting speed at the program's constant
    /// spindle speed misses the target by more than [`VC_DEVIATION`]: what
    /// the control is measured against.
    pub vc_constant_deviation_share: f64,
}

/// Relative difference between the written and the target spindle speed
/// above which a point counts as not at the constant cutting speed.
pub const VC_DEVIATION: f64 = 0.05;

/// Whether speed `n` misses the constant-cutting-speed target by more than
/// [`VC_DEVIATION`].
#[inline]
pub fn deviates(n: f64, target: f64) -> bool {
    (n - target).abs() > VC_DEVIATION * target
}

pub struct SpeedResult {
    pub program: Program,
    /// One row per cutting point when [`SpeedParams::keep_rows`], else empty.
    pub rows: Vec<PointRow>,
    pub summary: Summary,
    /// Wall time of each phase (name, seconds), for `--timings`.
    pub timings: Vec<(&'static str, f64)>,
}

/// The ball diameter of a ball-end operation: from its tool, or `fallback` when
/// the tool carries no geometry.
fn is_ball(op: &millplan_nc::Operation, fallback: Option<f64>) -> Option<f64> {
    match op.tool.as_ref()?.cutter {
        Some(c) => (c.kind == CutterKind::Ball).then_some(c.d),
        None => fallback,
    }
}

/// The working-diameter model of a ball holds for stock no thicker than the
/// ball's radius (ap ≤ R); beyond it every point would read D_w = D.
fn ap_within_radius(
    op: &millplan_nc::Operation,
    oi: usize,
    d: f64,
    ap: f64,
) -> Result<(), SpeedError> {
    if ap <= d / 2.0 {
        return Ok(());
    }
    let tool = op
        .tool
        .as_ref()
        .and_then(|t| t.number)
        .map_or(String::new(), |n| format!("T{n}, "));
    Err(SpeedError::Invalid(format!(
        "--ap {ap} mm is more than the radius {} mm of the ball ({tool}D{d}) of operation {}: \
         the working diameter needs the stock no thicker than the ball's radius",
        d / 2.0,
        oi + 1
    )))
}

/// Applies spindle control to every ball-end operation.
///
/// The demo's free-form part and a D10 ball-end raster over it, at the
/// paper's test conditions (vc 63 m/min, fz 0.125 mm, 2 flutes, ap 0.3 mm):
///
/// ```
/// use millplan_geom::analytic::{tessellate, DemoSurface};
/// use millplan_nc::generate::{raster, Raster};
/// use millplan_plan::machine::Machine;
/// use millplan_plan::speed::{apply, SpeedParams};
///
/// let surface = DemoSurface::default();
/// let mesh = tessellate(&surface, 1.0);
/// let coarse = Raster { stepover: 5.0, step: 2.0, ..Raster::default() };
/// let (program, _) = raster(&surface, &coarse);
/// let res = apply(&program, &mesh, &Machine::default(), &SpeedParams::new(63.0, 0.125, 2, 0.3))
///     .expect("runs");
/// let s = &res.summary;
/// assert_eq!(s.points, res.rows.len());
/// // Every speed written lies within the machine's spindle range.
/// assert!(s.spindle.min >= 500.0 && s.spindle.max <= 18000.0);
/// // The spindle pass never moves the tool.
/// assert_eq!(res.program.move_count(), program.move_count());
/// ```
pub fn apply(
    program: &Program,
    mesh: &TriMesh,
    m: &Machine,
    p: &SpeedParams,
) -> Result<SpeedResult, SpeedError> {
    apply_owned(program.clone(), mesh, m, p)
}

/// [`apply`] to a program it may change in place (no copy of a large program).
pub fn apply_owned(
    program: Program,
    mesh: &TriMesh,
    m: &Machine,
    p: &SpeedParams,
) -> Result<SpeedResult, SpeedError> {
    let clock = std::time::Instant::now();
    let surface = Surface::new(mesh);
    let t = clock.elapsed().as_secs_f64();
    let mut res = apply_on(program, &surface, m, p)?;
    res.timings.insert(0, ("surface (BVH, vertex normals)", t));
    Ok(res)
}

/// [`apply_owned`] on a surface prepared beforehand (for example while the
/// program was being read).
pub fn apply_on(
    mut program: Program,
    surface: &Surface,
    m: &Machine,
    p: &SpeedParams,
) -> Result<SpeedResult, SpeedError> {
    let (rows, summary, timings) = apply_in_place(&mut program, surface, m, p)?;
    Ok(SpeedResult {
        program,
        rows,
        summary,
        timings,
    })
}

/// The pass as the pipeline runs it.
pub static INFO: PassInfo = PassInfo {
    name: "speed",
    needs: &[Need::Part, Need::Machine],
    changes: Changes::How,
    does: "spindle speed per block for a constant cutting speed, within the machine's range and acceleration; feeds follow (paper 000, thesis 3)",
};

/// Constant-cutting-speed spindle control as a pass; its table and summary
/// stay with it for the report.
pub struct SpeedPass {
    pub params: SpeedParams,
    /// One row per cutting point when [`SpeedParams::keep_rows`].
    pub rows: Vec<PointRow>,
    pub summary: Option<Summary>,
    /// What [`SpeedPass::plan`] computed, for the next run to write.
    planned: Option<Planned>,
}

impl SpeedPass {
    pub fn new(params: SpeedParams) -> SpeedPass {
        SpeedPass {
            params,
            rows: Vec::new(),
            summary: None,
            planned: None,
        }
    }
}

impl Pass for SpeedPass {
    fn info(&self) -> &'static PassInfo {
        &INFO
    }

    fn run(&mut self, program: &mut Program, cx: &Context) -> Result<(), PassError> {
        let planned = match self.planned.take() {
            Some(p) if p.fits(program) => p,
            _ => self.compute(program, cx)?,
        };
        let (rows, summary) = cx.time("  speeds and feeds written", || planned.write(program));
        self.rows = rows;
        self.summary = Some(summary);
        Ok(())
    }
}

impl SpeedPass {
    /// Computes the speeds and feeds on `program` without changing it; the
    /// next [`Pass::run`] on a program of the same operations and moves (a
    /// copy of this one) writes them. A caller that must keep the input
    /// copies it after this, so the copy and the analysis's memory are not
    /// held at once.
    pub fn plan(&mut self, program: &Program, cx: &Context) -> Result<(), PassError> {
        self.planned = Some(self.compute(program, cx)?);
        Ok(())
    }

    fn compute(&self, program: &Program, cx: &Context) -> Result<Planned, PassError> {
        let surface = cx
            .surface()
            .ok_or(PassError::NeedsPart { pass: INFO.name })?;
        let several = program.operations.len() > 1;
        let tick = |oi: usize, done: usize, total: usize| {
            let phase = if several {
                format!("speed: contact and working diameter (operation {})", oi + 1)
            } else {
                "speed: contact and working diameter".to_string()
            };
            cx.progress(&phase, done, total)
        };
        let planned =
            plan_with(program, surface, &cx.machine, &self.params, &tick).map_err(|e| {
                PassError::Input {
                    pass: INFO.name,
                    message: e.to_string(),
                }
            })?;
        for (name, t) in &planned.timings {
            cx.record(&format!("  {name}"), *t);
        }
        Ok(planned)
    }
}

type Applied = (Vec<PointRow>, Summary, Vec<(&'static str, f64)>);

/// Spindle control on `program` in place: its rows, summary and phase times.
/// On an error the program is as it was.
pub fn apply_in_place(
    program: &mut Program,
    surface: &Surface,
    m: &Machine,
    p: &SpeedParams,
) -> Result<Applied, SpeedError> {
    apply_in_place_with(program, surface, m, p, &|_, _, _| {})
}

/// Points analysed between two reports of progress.
const TICK: usize = 4096;

/// [`apply_in_place`], `tick(operation, done, total)` hearing of the points
/// of each operation whose contact and working diameter are done (from any
/// thread, now and then).
pub fn apply_in_place_with(
    program: &mut Program,
    surface: &Surface,
    m: &Machine,
    p: &SpeedParams,
    tick: &(dyn Fn(usize, usize, usize) + Sync),
) -> Result<Applied, SpeedError> {
    let planned = plan_with(program, surface, m, p, tick)?;
    let mut timings = planned.timings.clone();
    let clock = std::time::Instant::now();
    let (rows, summary) = planned.write(program);
    timings.push(("speeds and feeds written", clock.elapsed().as_secs_f64()));
    Ok((rows, summary, timings))
}

/// The speeds (and feeds) of one operation's cutting points, to be written.
struct OpSpeeds {
    op: usize,
    /// The operation's number of moves, to match the program written into.
    moves: usize,
    /// The cutting points' moves.
    idx: Vec<usize>,
    n: Vec<f64>,
    /// The feeds, when the feed follows the spindle.
    feeds: Option<Vec<f64>>,
}

/// Spindle control computed on a program and not yet written into it (or
/// into a copy of it).
pub struct Planned {
    ops: Vec<OpSpeeds>,
    operations: usize,
    rows: Vec<PointRow>,
    summary: Summary,
    /// The phases' wall times.
    pub timings: Vec<(&'static str, f64)>,
}

impl Planned {
    /// Whether `program` has the operations and moves this was computed on.
    fn fits(&self, program: &Program) -> bool {
        program.operations.len() == self.operations
            && self
                .ops
                .iter()
                .all(|o| program.operations[o.op].moves.len() == o.moves)
    }

    /// Writes the speeds and feeds into `program` (the one they were
    /// computed on, or a copy): its rows and summary.
    fn write(self, program: &mut Program) -> (Vec<PointRow>, Summary) {
        for s in self.ops {
            let o = &mut program.operations[s.op];
            for (k, &i) in s.idx.iter().enumerate() {
                let mv = &mut o.moves[i];
                mv.spindle = s.n[k];
                if let Some(f) = &s.feeds {
                    mv.feed = f[k];
                    mv.feed_mode = FeedMode::PerMinute;
                }
            }
            // Non-cutting moves keep the speed of the cutting point before them (the
            // first one's before the first cut), so the spindle does not change on rapids.
            let mut cur = s.n[0];
            let mut next_k = 0;
            for (i, mv) in o.moves.iter_mut().enumerate() {
                if next_k < s.idx.len() && s.idx[next_k] == i {
                    cur = s.n[next_k];
                    next_k += 1;
                } else if mv.spindle > 0.0 || mv.is_rapid() {
                    mv.spindle = cur;
                }
            }
        }
        (self.rows, self.summary)
    }
}

/// Spindle control computed on `program`, which it does not change.
fn plan_with(
    program: &Program,
    surface: &Surface,
    m: &Machine,
    p: &SpeedParams,
    tick: &(dyn Fn(usize, usize, usize) + Sync),
) -> Result<Planned, SpeedError> {
    if !(p.vc > 0.0 && p.fz > 0.0 && p.flutes > 0 && p.ap > 0.0)
        || p.ball_d.map(|d| !(d > 0.0)).unwrap_or(false)
    {
        return Err(SpeedError::Invalid(
            "vc, fz, flutes and ap must be positive".into(),
        ));
    }
    m.validate()
        .map_err(|e| SpeedError::Invalid(e.to_string()))?;
    let mut timings = Vec::new();
    let mut clock = std::time::Instant::now();
    let mut lap = |name: &'static str, timings: &mut Vec<(&'static str, f64)>| {
        timings.push((name, clock.elapsed().as_secs_f64()));
        clock = std::time::Instant::now();
    };
    let out = program;
    // The constant speed the program ran at: the first ball-end operation's
    // programmed spindle speed.
    let n0 = out
        .operations
        .iter()
        .filter(|o| is_ball(o, p.ball_d).is_some() && o.moves.iter().any(|mv| mv.is_cutting()))
        .filter_map(|o| o.moves.iter().find(|mv| mv.spindle > 0.0))
        .map(|mv| mv.spindle)
        .next()
        .unwrap_or(0.0);
    let mut rows: Vec<PointRow> = Vec::new();
    let mut acc = SummaryAcc::new(n0);
    let mut check = None;
    let mut convention = p.convention.unwrap_or(Convention::Tip);
    let mut ops = 0;
    let mut planned = Vec::new();
    for oi in 0..out.operations.len() {
        let op = &out.operations[oi];
        let Some(d) = is_ball(op, p.ball_d) else {
            continue;
        };
        ap_within_radius(op, oi, d, p.ap)?;
        ops += 1;
        let (pts, idx) = cutting_points(op);
        if pts.is_empty() {
            continue;
        }
        if p.convention.is_none() && check.is_none() {
            let c = contact::detect_convention(surface, &pts, d / 2.0);
            convention = c.chosen;
            check = Some(c);
        }
        let mut cp = contact::Params::new(d, p.ap);
        cp.convention = convention;
        cp.normals = p.normals;
        cp.gap_tol = p.gap_tol;
        cp.nearest_incentre = p.nearest_incentre;
        lap("points and convention", &mut timings);
        // The full results only when rows are kept; the control needs D_w and
        // a few flags per point.
        let lite = |r: &PointResult| Lite {
            dw: r.dw,
            gap_flag: r.no_contact || r.gap.abs() > p.gap_tol,
            no_contact: r.no_contact,
            corner: r.corner,
            first_pass: r.neighbour == Neighbour::None,
        };
        let (n, done) = (pts.len(), std::sync::atomic::AtomicUsize::new(0));
        let count = || {
            let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if k % TICK == 0 {
                tick(oi, k, n);
            }
        };
        tick(oi, 0, n);
        let (full, lites) = if p.keep_rows {
            let full = contact::analyse_with(surface, &pts, &cp, |r| {
                count();
                r
            });
            let lites: Vec<Lite> = full.iter().map(lite).collect();
            (full, lites)
        } else {
            (
                Vec::new(),
                contact::analyse_with(surface, &pts, &cp, |r| {
                    count();
                    lite(&r)
                }),
            )
        };
        tick(oi, n, n);
        drop(pts);
        lap("contact and working diameter", &mut timings);
        // Targets, machine range, threshold.
        let target: Vec<f64> = lites
            .iter()
            .map(|l| millplan_models::wd::spindle_speed(p.vc, l.dw))
            .collect();
        // Block times between cutting points need the feeds, which depend on n.
        let len_between = |k: usize| -> (f64, f64) {
            // (cutting length of the move into point k, time of non-cutting moves before it at rapid)
            // Unknown lengths (from a position the program has not set) count 0.
            let i = idx[k];
            let len = op.move_length(i).unwrap_or(0.0);
            let lo = if k == 0 { i } else { idx[k - 1] + 1 };
            let mut rapid_s = 0.0;
            for j in lo..i {
                rapid_s += op.move_length(j).unwrap_or(0.0) / m.rapid * 60.0;
            }
            (len, rapid_s)
        };
        let geo: Vec<(f64, f64)> = (0..idx.len()).into_par_iter().map(len_between).collect();
        // The programmed feed and whether it is per minute, read once (the
        // chip-load coupling needs neither).
        let programmed: Vec<(f64, bool)> = if p.feed == FeedCoupling::Programmed {
            idx.par_iter()
                .map(|&i| {
                    let mv = &op.moves[i];
                    (mv.feed, mv.feed_mode == FeedMode::PerMinute)
                })
                .collect()
        } else {
            Vec::new()
        };
        let Controlled {
            n,
            held,
            before_limit,
            dt,
            feeds,
            feed_clamped,
        } = control(&target, &geo, &programmed, m, p);
        let clamp = |n: f64| n.clamp(m.spindle_min, m.spindle_max);
        if p.keep_rows {
            rows.reserve(n.len());
        }
        let mut full = full.into_iter();
        for k in 0..n.len() {
            let (f, fc) = (feeds[k], feed_clamped[k]);
            let l = &lites[k];
            let flags = Flags {
                clamped: clamp(target[k]) != target[k],
                rate_limited: (n[k] - before_limit[k]).abs() > 1e-9,
                held: held[k],
                feed_clamped: fc,
            };
            acc.push(l, &flags, target[k], n[k], geo[k].0, dt[k]);
            if let Some(r) = full.next() {
                let i = idx[k];
                rows.push(PointRow {
                    op: oi,
                    mv: i,
                    line: op.moves[i].line,
                    d,
                    cl: op.moves[i].end,
                    n_target: target[k],
                    n: n[k],
                    feed: f,
                    ds: geo[k].0,
                    dt: dt[k],
                    clamped: flags.clamped,
                    rate_limited: flags.rate_limited,
                    held: flags.held,
                    gap_flag: l.gap_flag,
                    r,
                });
            }
        }
        drop(geo);
        planned.push(OpSpeeds {
            op: oi,
            moves: op.moves.len(),
            idx,
            n,
            feeds: (p.feed == FeedCoupling::ChipLoad).then_some(feeds),
        });
        lap("spindle limits and feeds", &mut timings);
    }
    if ops == 0 {
        return Err(SpeedError::NoBallOperation);
    }
    let summary = acc.finish(convention, check, ops);
    Ok(Planned {
        ops: planned,
        operations: out.operations.len(),
        rows,
        summary,
        timings,
    })
}

/// Moves per part of the cutting-point scan.
const SCAN_CHUNK: usize = 1 << 15;

/// The cutting points of an operation (in part coordinates, with the tool
/// axis of their moves) and the indices of their moves, with their passes
/// (`speed` and `reorder` both read paths this way): a new pass after every
/// link (non-cutting move) once cutting has begun, and at every reversal
/// sharper than 60° within a pass.
///
/// Scanned in parallel parts: each part starts from the direction the moves
/// before it leave (found by looking back over zero-length moves to the last
/// link or real step), counts its cutting points and new passes, and then
/// writes its points with the passes of the parts before it added.
pub(crate) fn cutting_points(op: &millplan_nc::Operation) -> (Vec<PathPoint>, Vec<usize>) {
    let moves = &op.moves;
    let first_cut = moves.iter().position(|m| m.is_cutting() && !m.end.is_nan());
    let dir_of = |i: usize| {
        op.known_start(i)
            .map(|s| (moves[i].end - s).normalize_or_zero())
            .filter(|d| d.is_finite() && *d != DVec3::ZERO)
    };
    // A cutting move to a position with an unknown axis cannot be analysed:
    // it counts as a link.
    let cuts = |m: &millplan_nc::Move| m.is_cutting() && !m.end.is_nan();
    // The direction of travel entering move `start`: none after a link.
    let dir_before = |start: usize| {
        (0..start)
            .rev()
            .map(|j| (cuts(&moves[j]), j))
            .take_while(|(cutting, _)| *cutting)
            .find_map(|(_, j)| dir_of(j))
    };
    // Scans moves `range`: (cutting points, new passes); with `out`, writes
    // the points, numbering passes from `pass`.
    let scan = |range: std::ops::Range<usize>,
                mut pass: u32,
                mut out: Option<(&mut [PathPoint], &mut [usize])>| {
        let mut prev_dir = dir_before(range.start);
        let (mut count, pass0) = (0usize, pass);
        for i in range {
            let mv = &moves[i];
            if !cuts(mv) {
                if first_cut.is_some_and(|f| f < i) {
                    pass += 1;
                }
                prev_dir = None;
                continue;
            }
            let dir = dir_of(i);
            if let (Some(pd), Some(d)) = (prev_dir, dir) {
                if pd.dot(d) < 0.5 {
                    pass += 1;
                }
            }
            prev_dir = dir.or(prev_dir);
            if let Some((pts, idx)) = out.as_mut() {
                let axis = op.axis(mv).unwrap_or(DVec3::Z);
                let (cl, axis) = match &op.frame {
                    Some(f) => (f.to_parent(mv.end), f.dir_to_parent(axis)),
                    None => (mv.end, axis),
                };
                pts[count] = PathPoint { cl, axis, pass };
                idx[count] = i;
            }
            count += 1;
        }
        (count, pass - pass0)
    };
    let parts: Vec<std::ops::Range<usize>> = (0..moves.len())
        .step_by(SCAN_CHUNK)
        .map(|a| a..(a + SCAN_CHUNK).min(moves.len()))
        .collect();
    let counts: Vec<(usize, u32)> = parts.par_iter().map(|r| scan(r.clone(), 0, None)).collect();
    let total: usize = counts.iter().map(|c| c.0).sum();
    let blank = PathPoint {
        cl: DVec3::ZERO,
        axis: DVec3::Z,
        pass: 0,
    };
    // Filled in parallel, so that fresh memory is first touched (and zeroed
    // by the system) on every thread rather than on one.
    let mut pts: Vec<PathPoint> = (0..total).into_par_iter().map(|_| blank).collect();
    let mut idx = vec![0usize; total];
    // Each part's slice of the output and the pass it starts from.
    let mut jobs = Vec::with_capacity(parts.len());
    let (mut p_rest, mut i_rest) = (pts.as_mut_slice(), idx.as_mut_slice());
    let mut pass = 0u32;
    for (r, &(count, passes)) in parts.iter().zip(&counts) {
        let (p, pr) = std::mem::take(&mut p_rest).split_at_mut(count);
        let (i, ir) = std::mem::take(&mut i_rest).split_at_mut(count);
        (p_rest, i_rest) = (pr, ir);
        jobs.push((r.clone(), pass, p, i));
        pass += passes;
    }
    jobs.into_par_iter().for_each(|(r, pass, p, i)| {
        scan(r, pass, Some((p, i)));
    });
    (pts, idx)
}

/// The spindle as the machine drives it at cutting points with constant-
/// cutting-speed targets `target`.
pub(crate) struct Controlled {
    /// Speeds written.
    pub n: Vec<f64>,
    /// Held at the previous speed (a change under the S threshold).
    pub held: Vec<bool>,
    /// Speeds in the machine's range, before the acceleration limit.
    pub before_limit: Vec<f64>,
    /// Block time into each point, s.
    pub dt: Vec<f64>,
    pub feeds: Vec<f64>,
    pub feed_clamped: Vec<bool>,
}

/// Speeds at points with targets `target` (1/min) and `geo` = (cutting length
/// of the move into the point, time of the non-cutting moves before it, s):
/// the machine's range, the S threshold, then the acceleration limit over
/// block times at the feeds the speeds give (`programmed`: the programmed
/// feed per point and whether it is per minute, read only for
/// [`FeedCoupling::Programmed`]).
pub(crate) fn control(
    target: &[f64],
    geo: &[(f64, f64)],
    programmed: &[(f64, bool)],
    m: &Machine,
    p: &SpeedParams,
) -> Controlled {
    // Small inputs (the reorder's windows) on one thread.
    const PAR: usize = 1 << 12;
    let clamp = |n: f64| n.clamp(m.spindle_min, m.spindle_max);
    let mut n: Vec<f64> = Vec::with_capacity(target.len());
    let mut held = vec![false; target.len()];
    for (k, t) in target.iter().enumerate() {
        let c = clamp(*t);
        match n.last() {
            Some(&last) if (c - last).abs() <= p.s_threshold => {
                n.push(last);
                held[k] = c != last;
            }
            _ => n.push(c),
        }
    }
    let feed_of = |k: usize, n: f64| -> (f64, bool) {
        let f = match p.feed {
            FeedCoupling::ChipLoad => n * p.flutes as f64 * p.fz,
            FeedCoupling::Programmed => match programmed[k] {
                (f, true) => f,
                (f, false) => return (f, false),
            },
        };
        let c = f.clamp(m.feed_min, m.feed_max);
        (c, c != f)
    };
    // Block times of speeds n at their feeds.
    let block_times = |n: &[f64], dt: &mut [f64]| {
        dt.par_iter_mut()
            .with_min_len(PAR)
            .enumerate()
            .for_each(|(k, t)| {
                let (f, _) = feed_of(k, n[k]);
                *t = geo[k].0 / f * 60.0 + geo[k].1;
            });
    };
    let mut dt = vec![0.0; n.len()];
    let before_limit = n.clone();
    // The block time depends on the speed through the feed: iterate until the
    // limited speeds satisfy the bound with their own block times.
    for _ in 0..50 {
        // Block times of these speeds, and whether the speeds respect them.
        block_times(&n, &mut dt);
        let ok = (1..n.len())
            .into_par_iter()
            .with_min_len(PAR)
            .all(|k| (n[k] - n[k - 1]).abs() <= m.spindle_accel * dt[k] * (1.0 + 1e-12) + 1e-9);
        if ok {
            break;
        }
        // Aim slightly inside the bound so the next feeds cannot push it over.
        rate_limit_scaled(&mut n, &dt, 0.999, m.spindle_accel);
    }
    // The final feeds and block times.
    let (feeds, feed_clamped): (Vec<f64>, Vec<bool>) = (0..n.len())
        .into_par_iter()
        .with_min_len(PAR)
        .map(|k| feed_of(k, n[k]))
        .unzip();
    block_times(&n, &mut dt);
    Controlled {
        n,
        held,
        before_limit,
        dt,
        feeds,
        feed_clamped,
    }
}

/// Limits |n_k − n_{k−1}| to `accel`·dt_k: a forward pass, then a backward pass
/// that guarantees the bound for every pair.
pub fn rate_limit(n: &mut [f64], dt: &[f64], accel: f64) {
    rate_limit_scaled(n, dt, 1.0, accel);
}

/// [`rate_limit`] with every block time multiplied by `scale` first.
///
/// Each pass clamps a speed to within the limit of its neighbour's. Written
/// with branches, not min/max: most speeds need no change, and a predicted
/// branch does not make each step wait for the one before (four times faster).
fn rate_limit_scaled(n: &mut [f64], dt: &[f64], scale: f64, accel: f64) {
    let Some(&first) = n.first() else { return };
    let mut prev = first;
    for k in 1..n.len() {
        prev = clamp_near(n[k], prev, accel * (dt[k] * scale));
        n[k] = prev;
    }
    let mut next = n[n.len() - 1];
    for k in (0..n.len() - 1).rev() {
        next = clamp_near(n[k], next, accel * (dt[k + 1] * scale));
        n[k] = next;
    }
}

/// `x` clamped to [`to` − `lim`, `to` + `lim`].
#[inline(always)]
fn clamp_near(x: f64, to: f64, lim: f64) -> f64 {
    if x < to - lim {
        to - lim
    } else if x > to + lim {
        to + lim
    } else {
        x
    }
}

/// What the summary reads of a point's contact analysis.
#[derive(Clone, Copy, Debug)]
struct Lite {
    dw: f64,
    gap_flag: bool,
    no_contact: bool,
    corner: bool,
    first_pass: bool,
}

/// What the control did at a point.
#[derive(Clone, Copy, Debug)]
struct Flags {
    clamped: bool,
    rate_limited: bool,
    held: bool,
    feed_clamped: bool,
}

/// The summary, gathered one point at a time in cutting order.
struct SummaryAcc {
    n0: f64,
    points: usize,
    /// clamped, rate-limited, held, feed clamped, gap, no contact, corner, first pass.
    counts: [usize; 8],
    dw: StatsAcc,
    spindle: StatsAcc,
    vc_constant: StatsAcc,
    vc_controlled: StatsAcc,
    ind: IndicatorsAcc,
    ind_target: IndicatorsAcc,
    /// Points off the target with control, and at the constant speed.
    deviating: [usize; 2],
}

impl SummaryAcc {
    fn new(n0: f64) -> SummaryAcc {
        SummaryAcc {
            n0,
            points: 0,
            counts: [0; 8],
            dw: StatsAcc::default(),
            spindle: StatsAcc::default(),
            vc_constant: StatsAcc::default(),
            vc_controlled: StatsAcc::default(),
            ind: IndicatorsAcc::default(),
            ind_target: IndicatorsAcc::default(),
            deviating: [0; 2],
        }
    }

    #[inline]
    fn push(&mut self, l: &Lite, f: &Flags, n_target: f64, n: f64, ds: f64, dt: f64) {
        let pi = std::f64::consts::PI;
        self.points += 1;
        let flags = [
            f.clamped,
            f.rate_limited,
            f.held,
            f.feed_clamped,
            l.gap_flag,
            l.no_contact,
            l.corner,
            l.first_pass,
        ];
        for (c, x) in self.counts.iter_mut().zip(flags) {
            *c += x as usize;
        }
        self.dw.push(l.dw);
        self.spindle.push(n);
        self.vc_constant.push(pi * l.dw * self.n0 / 1000.0);
        self.vc_controlled.push(pi * l.dw * n / 1000.0);
        self.ind.push(n, ds, dt);
        self.ind_target.push(n_target, ds, dt);
        self.deviating[0] += deviates(n, n_target) as usize;
        self.deviating[1] += deviates(self.n0, n_target) as usize;
    }

    /// `n` as a share of the points (0 without points).
    fn share(&self, n: usize) -> f64 {
        if self.points > 0 {
            n as f64 / self.points as f64
        } else {
            0.0
        }
    }

    fn finish(
        &self,
        convention: Convention,
        check: Option<ConventionCheck>,
        ops: usize,
    ) -> Summary {
        let [clamped, rate_limited, held, feed_clamped, gap_flagged, no_contact, corners, first_pass_points] =
            self.counts;
        Summary {
            points: self.points,
            operations: ops,
            convention,
            convention_check: check,
            clamped,
            rate_limited,
            held,
            feed_clamped,
            gap_flagged,
            no_contact,
            corners,
            first_pass_points,
            d_w: self.dw.finish(),
            spindle: self.spindle.finish(),
            constant_spindle: self.n0,
            vc_constant: self.vc_constant.finish(),
            vc_controlled: self.vc_controlled.finish(),
            indicators: self.ind.finish(),
            indicators_target: self.ind_target.finish(),
            vc_deviation_points: self.deviating[0],
            vc_deviation_share: self.share(self.deviating[0]),
            vc_constant_deviation_share: self.share(self.deviating[1]),
        }
    }
}

/// Text of the uncut side for tables.
pub fn side_name(r: &PointResult) -> &'static str {
    match (r.neighbour, r.side) {
        (Neighbour::None, _) => "none",
        (Neighbour::Both(_), _) => "both",
        (_, Side::Left) => "left",
        (_, Side::Right) => "right",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The cutting-point scan in one sequential pass: the reference for the
    /// parallel one.
    fn cutting_points_in_one_pass(op: &millplan_nc::Operation) -> (Vec<PathPoint>, Vec<usize>) {
        let (mut pts, mut idx) = (Vec::new(), Vec::new());
        let mut pass = 0u32;
        let mut prev_dir: Option<DVec3> = None;
        for (i, mv) in op.moves.iter().enumerate() {
            if !mv.is_cutting() {
                if prev_dir.is_some() || !pts.is_empty() {
                    pass += 1;
                }
                prev_dir = None;
                continue;
            }
            if let Some(s) = op.known_start(i) {
                let dir = (mv.end - s).normalize_or_zero();
                if let Some(pd) = prev_dir {
                    if dir != DVec3::ZERO && pd.dot(dir) < 0.5 {
                        pass += 1;
                    }
                }
                if dir != DVec3::ZERO {
                    prev_dir = Some(dir);
                }
            }
            pts.push(PathPoint {
                cl: mv.end,
                axis: DVec3::Z,
                pass,
            });
            idx.push(i);
        }
        (pts, idx)
    }

    #[test]
    fn parallel_cutting_point_scan_matches_one_pass() {
        use millplan_nc::{Move, Operation};
        // Several parts' worth of moves: rapids before the first cut, links,
        // reversals, and runs of zero-length moves, some of them across the
        // boundaries between parts (where a part must find the direction the
        // moves before it leave).
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            seed >> 33
        };
        let mut op = Operation {
            start: DVec3::new(0.0, 0.0, 50.0),
            ..Operation::default()
        };
        let mut p = DVec3::new(0.0, 0.0, 50.0);
        op.moves.push(Move::rapid(p));
        let mut dir = DVec3::X;
        while op.moves.len() < 5 * SCAN_CHUNK {
            let here = op.moves.len();
            if here.is_multiple_of(SCAN_CHUNK) {
                // A reversal as a part's first move.
                dir = -dir;
            }
            match rnd() % 100 {
                0 => {
                    p += DVec3::new(0.0, 1.0, 5.0);
                    op.moves.push(Move::rapid(p));
                }
                1 => dir = -dir,
                2 => dir = DVec3::new(dir.y, -dir.x, 0.0),
                3 => {
                    // A long run of repeated points, placed across the next
                    // boundary when it is near.
                    let to_boundary = SCAN_CHUNK - here % SCAN_CHUNK;
                    let across = to_boundary < 3000;
                    let n = if across {
                        to_boundary + 59
                    } else {
                        1 + rnd() as usize % 40
                    };
                    for _ in 0..n {
                        op.moves.push(Move::linear(p, 500.0));
                    }
                    if across {
                        // The first real step after them reverses.
                        dir = -dir;
                    }
                }
                _ => {}
            }
            p += dir * (0.1 + (rnd() % 7) as f64 * 0.01);
            op.moves.push(Move::linear(p, 500.0));
        }
        // A link and a reversal exactly at part boundaries too.
        op.moves[3 * SCAN_CHUNK] = Move::rapid(op.moves[3 * SCAN_CHUNK].end);
        let want = cutting_points_in_one_pass(&op);
        let got = cutting_points(&op);
        assert_eq!(got.1, want.1);
        assert_eq!(got.0.len(), want.0.len());
        for (g, w) in got.0.iter().zip(&want.0) {
            assert_eq!((g.cl, g.pass), (w.cl, w.pass));
        }
        assert!(want.0.last().is_some_and(|p| p.pass > 100));
    }

    proptest! {
        #[test]
        fn rate_limit_bounds_every_step(v in proptest::collection::vec((500.0..20000.0f64, 0.001..0.5f64), 2..200), a in 100.0..20000.0f64) {
            let (mut n, dt): (Vec<f64>, Vec<f64>) = v.into_iter().unzip();
            let orig = n.clone();
            rate_limit(&mut n, &dt, a);
            for k in 1..n.len() {
                prop_assert!((n[k] - n[k - 1]).abs() <= a * dt[k] + 1e-6);
            }
            // Values stay inside the range of the input.
            let (lo, hi) = orig.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| (l.min(*x), h.max(*x)));
            prop_assert!(n.iter().all(|x| *x >= lo - 1e-9 && *x <= hi + 1e-9));
        }
    }

    #[test]
    fn summary_and_program_do_not_depend_on_keeping_rows() {
        use millplan_geom::analytic::{tessellate, DemoSurface};
        use millplan_nc::generate::{raster, Raster};
        let s = DemoSurface::default();
        let mesh = tessellate(&s, 1.0);
        let (prog, _) = raster(
            &s,
            &Raster {
                stepover: 1.5,
                step: 0.75,
                ..Raster::default()
            },
        );
        let mut p = SpeedParams::new(63.0, 0.125, 2, 0.3);
        let with = apply(&prog, &mesh, &Machine::default(), &p).expect("applies");
        p.keep_rows = false;
        let without = apply(&prog, &mesh, &Machine::default(), &p).expect("applies");
        assert_eq!(with.rows.len(), with.summary.points);
        assert!(with.summary.points > 1000 && with.summary.rate_limited > 0);
        assert!(without.rows.is_empty());
        assert_eq!(with.summary, without.summary);
        assert_eq!(with.program, without.program);
        // The summary is that of the rows.
        let mean = with.rows.iter().map(|r| r.r.dw).sum::<f64>() / with.rows.len() as f64;
        assert!((with.summary.d_w.mean - mean).abs() < 1e-9);
        let limited = with.rows.iter().filter(|r| r.rate_limited).count();
        assert_eq!(with.summary.rate_limited, limited);
    }

    #[test]
    fn stats_in_one_pass_agree_with_two_passes() {
        let v: Vec<f64> = (0..1000)
            .map(|i| 5000.0 + 1e3 * ((i as f64) * 0.37).sin())
            .collect();
        let s = Stats::of(v.iter().copied());
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64;
        assert!((s.mean - mean).abs() < 1e-9 && (s.std - var.sqrt()).abs() < 1e-9);
        assert_eq!(s.min, v.iter().copied().fold(f64::INFINITY, f64::min));
        assert_eq!(s.max, v.iter().copied().fold(f64::NEG_INFINITY, f64::max));
        assert_eq!(Stats::of(std::iter::empty()), Stats::default());
    }

    #[test]
    fn indicators_by_hand() {
        let i = Indicators::of(
            &[1000.0, 1100.0, 1050.0],
            &[0.0, 1.0, 2.0],
            &[0.0, 0.5, 0.25],
        );
        assert_eq!(i.total_variation, 150.0);
        assert_eq!(i.max_step, 100.0);
        assert_eq!(i.max_accel, 200.0);
        assert_eq!(i.mean_accel, 200.0);
        assert_eq!(i.speed_integral, 1100.0 + 2100.0);
    }
}

#[cfg(test)]
mod pass_tests {
    //! The speed pass as data: IR in, IR out.
    use super::*;
    use crate::pipeline::run;
    use millplan_geom::TriMesh;
    use millplan_nc::{same_position, text};

    /// A flat plate at Z 0, 200 mm square around the origin.
    fn plate() -> TriMesh {
        let (a, b, c, d) = (
            DVec3::new(-100.0, -100.0, 0.0),
            DVec3::new(100.0, -100.0, 0.0),
            DVec3::new(100.0, 100.0, 0.0),
            DVec3::new(-100.0, 100.0, 0.0),
        );
        TriMesh::from_soup(&[[a, b, c], [a, c, d]]).0
    }

    /// The pass reports its contact analysis through the pipeline's hook:
    /// counts that only grow, from 0 to every cutting point.
    #[test]
    fn progress_counts_every_point_of_the_contact_analysis() {
        // 10,000 cutting points along X over the plate: more than two reports
        // between the first and the last.
        let mut t = String::from(
            "program - source=generated units=mm/declared
op name=-
  tool number=1 name=- line=1 cutter=ball d=10 r=5 e=0 f=5 a=0 b=0 h=0
  start (?, ?, ?)
  L2 rapid (-50, 0, 5) F0 S3000 per_minute
",
        );
        for k in 0..10_000 {
            t.push_str(&format!(
                "  L{} linear ({}, 0, 0) F600 S3000 per_minute\n",
                k + 3,
                -50.0 + 0.01 * k as f64
            ));
        }
        let heard = std::sync::Mutex::new(Vec::new());
        let hook = |phase: &str, done: usize, total: usize| {
            heard
                .lock()
                .expect("lock")
                .push((phase.to_string(), done, total));
        };
        let mesh = plate();
        let cx = Context::new(Machine::default())
            .with_part(&mesh)
            .with_progress(&hook);
        let mut p = text::parse(&t).expect("parses");
        let mut pass = SpeedPass::new(SpeedParams::new(63.0, 0.125, 2, 0.3));
        run(&mut [&mut pass], &mut p, &cx).expect("runs");
        let heard = heard.lock().expect("lock").clone();
        assert!(heard
            .iter()
            .all(|h| h.0 == "speed: contact and working diameter" && h.2 == 10_000));
        let counts: Vec<usize> = heard.iter().map(|h| h.1).collect();
        assert!(counts.windows(2).all(|w| w[0] <= w[1]), "{counts:?}");
        assert_eq!(counts.first(), Some(&0));
        assert_eq!(counts.last(), Some(&10_000));
        assert!(
            counts.contains(&4096) || counts.contains(&8192),
            "{counts:?}"
        );
    }

    /// On a flat surface D_w = 2·√(ap·(D − ap)) for any feed direction and
    /// stepover (working-diameter.md, oracle O1: D 10, ap 0.3 → 3.4117 mm), so
    /// every cutting block of a pass across the plate gets
    /// n = 1000·vc/(π·D_w) and F = n·z·fz; nothing else changes.
    #[test]
    fn constant_speed_on_a_plate_ir_in_ir_out() {
        let before = "program - source=generated units=mm/declared
op name=-
  tool number=1 name=- line=1 cutter=ball d=10 r=5 e=0 f=5 a=0 b=0 h=0
  start (?, ?, ?)
  L2 event spindle cw
  L3 rapid (-20, 0, 5) F0 S3000 per_minute
  L4 linear (-20, 0, 0) F600 S3000 per_minute
  L5 linear (-10, 0, 0) F600 S3000 per_minute
  L6 linear (0, 0, 0) F600 S3000 per_minute
  L7 linear (10, 0, 0) F600 S3000 per_minute
  L8 rapid (10, 0, 5) F0 S3000 per_minute
";
        let dw = 2.0 * (0.3f64 * (10.0 - 0.3)).sqrt();
        assert!((dw - 3.4117).abs() < 1e-4, "oracle O1");
        let n = 1000.0 * 63.0 / (std::f64::consts::PI * dw);
        let f = n * 2.0 * 0.125;
        let mesh = plate();
        let cx = Context::new(Machine::default())
            .with_part(&mesh)
            .verifying();
        let mut p = text::parse(before).expect("parses");
        let mut pass = SpeedPass::new(SpeedParams::new(63.0, 0.125, 2, 0.3));
        run(&mut [&mut pass], &mut p, &cx).expect("runs");
        let got = text::print(&p);
        // Every speed and feed as the closed form says (within the model's
        // refinement of D_w); positions, kinds and lines as they were.
        let before_p = text::parse(before).expect("parses");
        for (m, was) in p.moves().zip(before_p.moves()) {
            assert!(
                same_position(m.end, was.end) && m.kind == was.kind && m.line == was.line,
                "{got}"
            );
            assert!(
                (m.spindle - n).abs() < 0.5,
                "S {} against {n}\n{got}",
                m.spindle
            );
            if m.is_cutting() {
                assert!(
                    (m.feed - f).abs() < 0.5 * 0.25,
                    "F {} against {f}\n{got}",
                    m.feed
                );
            }
        }
        assert_eq!(p.operations[0].events, before_p.operations[0].events);
    }
}
