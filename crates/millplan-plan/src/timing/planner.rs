//! How each control family plans the path through the blocks: its model of
//! the junctions (exact stop, blending within a tolerance), the
//! acceleration it allows along blends and arcs, its look-ahead depth, its
//! jerk profile and its per-block time (docs/time.md, "Planner models").
//!
//! [`shape`] turns the prepared blocks of one chain, with the program's
//! path-control mode at every block ([`BlockCtl`]), into the blocks the
//! control actually runs (a LinuxCNC 2.9 blend arc is a block of its own)
//! and the highest speed at each junction between them; the look-ahead
//! passes and the closed-form block times of the estimate then apply as
//! before.

use super::{junction_len_rule, Block, Limits};

/// The control family whose trajectory planner the estimate follows
/// (`[control] planner` in the machine file).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum PlannerKind {
    /// No control in particular: corners blended over a fixed distance,
    /// full acceleration everywhere (the estimate before planner models).
    #[serde(rename = "generic")]
    Generic,
    /// LinuxCNC 2.9's trajectory planner (`tp.c`, `blendmath.c`).
    #[serde(rename = "linuxcnc-2.9")]
    LinuxCnc29,
    #[serde(rename = "fanuc")]
    Fanuc,
    #[serde(rename = "sinumerik")]
    Sinumerik,
    #[serde(rename = "heidenhain")]
    Heidenhain,
}

impl PlannerKind {
    pub const ALL: [PlannerKind; 5] = [
        PlannerKind::Generic,
        PlannerKind::LinuxCnc29,
        PlannerKind::Fanuc,
        PlannerKind::Sinumerik,
        PlannerKind::Heidenhain,
    ];

    /// The name the machine file spells.
    pub fn name(self) -> &'static str {
        match self {
            PlannerKind::Generic => "generic",
            PlannerKind::LinuxCnc29 => "linuxcnc-2.9",
            PlannerKind::Fanuc => "fanuc",
            PlannerKind::Sinumerik => "sinumerik",
            PlannerKind::Heidenhain => "heidenhain",
        }
    }

    pub fn from_name(s: &str) -> Option<PlannerKind> {
        PlannerKind::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// The speed profile of a speed change.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Profile {
    /// Constant acceleration, no jerk limit.
    Trapezoid,
    /// Jerk-limited (the axes' jerks, or the planner's path jerk).
    SCurve,
}

/// A control family's planner with its parameters (machine file
/// `[control]`; defaults per family in [`Planner::of`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Planner {
    pub kind: PlannerKind,
    /// Share of the acceleration a block may use while it blends with its
    /// neighbour without a blend arc (LinuxCNC's parabolic blends: 0.5).
    pub blend_accel_scale: f64,
    /// Share of the acceleration along the path on arcs, the rest kept for
    /// the normal acceleration (LinuxCNC: 0.5); 1: arcs as their chords.
    pub arc_tangential_share: f64,
    /// Blocks the control plans ahead (0: as many as needed).
    pub lookahead: usize,
    /// Blocks planned ahead while the control's look-ahead function is off
    /// (Fanuc without G05.1 Q1 or G08 P1); 0: as `lookahead`.
    pub plain_lookahead: usize,
    /// Path jerk, mm/s³, on top of the axes' jerks; `None`: the axes' alone.
    pub jerk: Option<f64>,
    /// Highest acceleration along the path, mm/s², a cap some controls put
    /// on top of the axes' (LinuxCNC 2.9's planner has none); `None`: the
    /// axes' alone.
    pub path_accel: Option<f64>,
    /// The speed profile when the program does not choose one (Sinumerik
    /// SOFT/BRISK do).
    pub profile: Profile,
    /// Shortest time a block may take, s (the control's block cycle): a
    /// short block's speed is at most its length over it.
    pub block_time_s: f64,
    /// Distance over which a corner is blended when the program gives no
    /// tolerance, mm.
    pub blend_mm: f64,
}

impl Planner {
    /// The family's planner with its documented defaults.
    pub fn of(kind: PlannerKind) -> Planner {
        let base = Planner {
            kind,
            blend_accel_scale: 1.0,
            arc_tangential_share: 1.0,
            lookahead: 0,
            plain_lookahead: 0,
            jerk: None,
            path_accel: None,
            profile: Profile::SCurve,
            block_time_s: 0.0,
            blend_mm: super::BLEND_MM,
        };
        match kind {
            PlannerKind::Generic => base,
            PlannerKind::LinuxCnc29 => Planner {
                blend_accel_scale: 0.5,
                arc_tangential_share: 0.5,
                // ARC_BLEND_OPTIMIZATION_DEPTH's default.
                lookahead: 50,
                profile: Profile::Trapezoid,
                // TP_MIN_SEGMENT_CYCLES (1.02) servo periods of 1 ms.
                block_time_s: 0.00102,
                ..base
            },
            PlannerKind::Fanuc => Planner {
                lookahead: 40,
                plain_lookahead: 1,
                block_time_s: 0.001,
                ..base
            },
            PlannerKind::Sinumerik => Planner {
                lookahead: 100,
                profile: Profile::Trapezoid,
                block_time_s: 0.001,
                ..base
            },
            PlannerKind::Heidenhain => Planner {
                lookahead: 1024,
                block_time_s: 0.0005,
                ..base
            },
        }
    }
}

impl Default for Planner {
    fn default() -> Self {
        Planner::of(PlannerKind::Generic)
    }
}

/// The path-control mode in effect at a block, as the estimate needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathMode {
    /// The motion stops at the block's end.
    ExactStop,
    /// Corners blended; `tolerance` mm, `None`: the control's own rule.
    Blend { tolerance: Option<f64> },
}

impl PathMode {
    /// `exact stop`, `blend`, `blend 0.01 mm`.
    pub fn label(self) -> String {
        match self {
            PathMode::ExactStop => "exact stop".into(),
            PathMode::Blend { tolerance: None } => "blend".into(),
            PathMode::Blend { tolerance: Some(t) } => format!("blend {t} mm"),
        }
    }
}

/// What the program asks of the control at one block beyond its geometry
/// and feed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockCtl {
    pub mode: PathMode,
    /// Exact stop at this block's end whatever the mode (G09).
    pub stop_after: bool,
    /// Radius of the arc this block is a chord of, mm; 0: a straight block.
    pub arc_radius: f64,
    /// The next block continues the same programmed move (the chords of one
    /// arc): their junction is tangent.
    pub same_move: bool,
    /// Jerk limitation switched on (SOFT) or off (BRISK); `None`: the
    /// planner's profile.
    pub soft: Option<bool>,
    /// The control's look-ahead function is on (Fanuc G05.1 Q1, G08 P1).
    pub lookahead_on: bool,
}

impl Default for BlockCtl {
    fn default() -> Self {
        BlockCtl {
            mode: PathMode::Blend { tolerance: None },
            stop_after: false,
            arc_radius: 0.0,
            same_move: false,
            soft: None,
            lookahead_on: false,
        }
    }
}

/// The blocks a control runs, each with its cap (`vcap`) and the highest
/// speed at each junction: `vj[k]` entering block k (`vj[0]` and `vj[n]`
/// zero).
pub(crate) struct Shaped {
    pub(crate) blocks: Vec<Block>,
    pub(crate) vj: Vec<f64>,
}

/// How a junction is passed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Joint {
    /// The motion stops.
    Stop,
    /// The motion stops and the first block ends at rest whatever the mode
    /// (LinuxCNC's `TC_TERM_COND_STOP`: a rapid next to a feed move, a sharp
    /// reversal), so it does not blend at its end.
    HardStop,
    /// Tangent: at the lower of the two caps.
    Tangent,
    /// At the given speed, the blocks' accelerations as they are.
    At(f64),
    /// LinuxCNC parabolic blend at the given speed: both blocks at the
    /// blend acceleration share.
    Parabolic(f64),
    /// LinuxCNC blend arc between the two blocks.
    Arc(BlendArc),
    /// LinuxCNC approximate tangent (`tpSetupTangent`): the corner is passed
    /// at the given speed as if the blocks were tangent, no blend.
    Kink(f64),
}

/// LinuxCNC 2.9's `[TRAJ] ARC_BLEND_KINK_RATIO` default: the share of the
/// acceleration a kink between nearly tangent blocks may take.
const KINK_RATIO: f64 = 0.1;
/// LinuxCNC's `TP_MIN_SEGMENT_CYCLES`: a block lasts at least this many
/// servo periods (`block_time_s` is as many periods).
const MIN_SEGMENT_CYCLES: f64 = 1.02;

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct BlendArc {
    /// Acceleration along the arc.
    pub(super) accel: f64,
    /// Taken off the end of the first block and the start of the second.
    pub(super) trim: f64,
    pub(super) len: f64,
    pub(super) vcap: f64,
}

/// Shapes the prepared blocks of one chain for the planner (module doc).
/// `caps` the blocks' speed caps, `stops[k]` a stop before block k (a
/// dwell), `ctl` the program's mode per input move (by `Block::index`).
pub(crate) fn shape(
    blocks: &[Block],
    caps: &[f64],
    stops: &[bool],
    ctl: Option<&[BlockCtl]>,
    pl: &Planner,
    lim: &Limits,
) -> Shaped {
    let n = blocks.len();
    let ctl_of = |k: usize| ctl.map_or_else(BlockCtl::default, |c| c[blocks[k].index]);
    let mut bs: Vec<Block> = (0..n)
        .map(|k| own_block(&blocks[k], caps[k], &ctl_of(k), pl))
        .collect();
    let mut joints = vec![Joint::Stop; n + 1];
    let mut trimmed = vec![0.0f64; n];
    // The share of its acceleration a kink takes from each block (LinuxCNC
    // only: the other planners allocate nothing for it).
    let lcnc = pl.kind == PlannerKind::LinuxCnc29;
    let mut kinked = vec![0.0f64; if lcnc { n } else { 0 }];
    for k in 1..n {
        if stops[k] {
            continue;
        }
        let (j, reduce) = joint(
            &bs[k - 1],
            &bs[k],
            &ctl_of(k - 1),
            &ctl_of(k),
            trimmed[k - 1],
            pl,
            lim,
        );
        joints[k] = j;
        if reduce > 0.0 {
            kinked[k - 1] = kinked[k - 1].max(reduce);
            kinked[k] = kinked[k].max(reduce);
        }
        if let Joint::Arc(a) = joints[k] {
            trimmed[k] = a.trim;
        }
    }
    if lcnc {
        linuxcnc_accels(&mut bs, &joints, &kinked, &ctl_of, pl);
    }
    let mut out = emit(&bs, &joints, &trimmed);
    lookahead(&mut out, ctl, pl);
    out
}

/// LinuxCNC's acceleration along each block (`tcGetOverallMaxAccel`): the
/// blend share on blocks that blend without an arc (parabolic blends, and
/// a blending block at the end of its chain), less the share its kinks
/// take (`kinked`).
fn linuxcnc_accels(
    bs: &mut [Block],
    joints: &[Joint],
    kinked: &[f64],
    ctl_of: &dyn Fn(usize) -> BlockCtl,
    pl: &Planner,
) {
    let n = bs.len();
    let mut half: Vec<bool> = (0..n)
        .map(|k| own_half(&ctl_of(k), &joints[k], &joints[k + 1]))
        .collect();
    // The chords of one arc are one segment to LinuxCNC: all or none.
    for k in (0..n.saturating_sub(1)).rev() {
        if ctl_of(k).same_move && half[k + 1] {
            half[k] = true;
        }
    }
    for k in 1..n {
        if ctl_of(k - 1).same_move && half[k - 1] {
            half[k] = true;
        }
    }
    for ((b, h), r) in bs.iter_mut().zip(half).zip(kinked) {
        share_accel(b, h, *r, pl);
    }
}

/// Whether LinuxCNC gives block `c` (entered by `into`, left by `out`) the
/// blend share of its acceleration by itself: it blends at its end without
/// an arc, or its start is a parabolic blend.
pub(super) fn own_half(c: &BlockCtl, into: &Joint, out: &Joint) -> bool {
    let parabolic_end = c.mode != PathMode::ExactStop
        && !c.stop_after
        && !matches!(
            out,
            Joint::Tangent | Joint::Arc(_) | Joint::Kink(_) | Joint::HardStop
        );
    parabolic_end || matches!(into, Joint::Parabolic(_))
}

/// A block's acceleration under LinuxCNC: the blend share when `half`, less
/// the share `kinked` its kinks take.
pub(super) fn share_accel(b: &mut Block, half: bool, kinked: f64, pl: &Planner) {
    if half {
        b.accel *= pl.blend_accel_scale;
    }
    b.accel *= 1.0 - kinked;
}

/// The blocks the control runs (blend arcs between their trimmed
/// neighbours) and the speed limit at each junction.
fn emit(bs: &[Block], joints: &[Joint], trimmed: &[f64]) -> Shaped {
    let n = bs.len();
    let mut out = Shaped {
        blocks: Vec::with_capacity(n),
        vj: Vec::with_capacity(n + 1),
    };
    out.vj.push(0.0);
    for k in 0..n {
        let next_cap = bs.get(k + 1).map_or(0.0, |x| x.vcap);
        emit_one(bs[k], trimmed[k], joints[k + 1], next_cap, &mut |b, v| {
            out.blocks.push(b);
            out.vj.push(v);
        });
    }
    if let Some(last) = out.vj.last_mut() {
        *last = 0.0;
    }
    out
}

/// The blocks the control runs for block `b` (its start trimmed by
/// `trimmed`, left by `out`, the next block capped at `next_cap`), each
/// with the speed limit at its end: `b` itself, and the blend arc after it.
pub(super) fn emit_one(
    mut b: Block,
    trimmed: f64,
    out: Joint,
    next_cap: f64,
    push: &mut dyn FnMut(Block, f64),
) {
    let end_trim = match out {
        Joint::Arc(a) => a.trim,
        _ => 0.0,
    };
    b.len = (b.len - trimmed - end_trim).max(0.0);
    match out {
        Joint::Arc(a) => {
            push(b, a.vcap.min(b.vcap));
            let mut arc = b;
            arc.len = a.len;
            arc.vcap = a.vcap;
            arc.vgeom = a.vcap;
            arc.accel = a.accel;
            push(arc, a.vcap.min(next_cap));
        }
        Joint::Stop | Joint::HardStop => push(b, 0.0),
        Joint::Tangent => push(b, b.vcap.min(next_cap)),
        Joint::At(v) | Joint::Parabolic(v) | Joint::Kink(v) => push(b, v.min(b.vcap).min(next_cap)),
    }
}

/// A block as the planner runs it alone: its cap within its block time and,
/// on an arc, within the normal acceleration; its acceleration along an arc
/// and its jerk by the profile in effect.
pub(super) fn own_block(b: &Block, cap: f64, c: &BlockCtl, pl: &Planner) -> Block {
    let mut b = *b;
    b.vcap = cap;
    if let (Some(a), false) = (pl.path_accel, b.rotary_only) {
        b.accel = b.accel.min(a);
    }
    if pl.block_time_s > 0.0 {
        b.vcap = b.vcap.min(b.len / pl.block_time_s);
    }
    if c.arc_radius > 0.0 && pl.arc_tangential_share < 1.0 {
        let a = b.accel;
        let a_n = a * (1.0 - pl.arc_tangential_share.powi(2)).sqrt();
        b.vcap = b.vcap.min((a_n * c.arc_radius).sqrt());
        b.accel = a * pl.arc_tangential_share;
    }
    let soft = c.soft.unwrap_or(pl.profile == Profile::SCurve);
    b.jerk = match (soft, pl.jerk) {
        (false, _) => f64::INFINITY,
        (true, Some(j)) if !b.rotary_only => b.jerk.min(j),
        _ => b.jerk,
    };
    b
}

/// How the junction from `a` to `b` is passed, and the share of their
/// acceleration it takes from both blocks (LinuxCNC's kinks).
pub(super) fn joint(
    a: &Block,
    b: &Block,
    ca: &BlockCtl,
    cb: &BlockCtl,
    a_trimmed: f64,
    pl: &Planner,
    lim: &Limits,
) -> (Joint, f64) {
    let lcnc = pl.kind == PlannerKind::LinuxCnc29;
    let cap = a.vcap.min(b.vcap);
    // The chords of one arc are one block to the control, whatever the mode.
    if ca.same_move && a.rotary_only == b.rotary_only {
        if pl.arc_tangential_share < 1.0 {
            return (Joint::Tangent, 0.0);
        }
        let ell = a.len.min(b.len).min(pl.blend_mm);
        return (Joint::At(junction_len_rule(a, b, cap, ell, lim)), 0.0);
    }
    if ca.stop_after || a.rotary_only != b.rotary_only {
        return (Joint::Stop, 0.0);
    }
    if lcnc && !a.rotary_only {
        return linuxcnc_joint(a, b, ca, cb, a_trimmed, pl, lim);
    }
    if ca.mode == PathMode::ExactStop || (!lcnc && (a.rapid || b.rapid)) {
        return (Joint::Stop, 0.0);
    }
    (generic_joint(a, b, ca, pl, lim), 0.0)
}

/// The generic rule: the corner blended over the control's distance or the
/// rounding arc of the program's tolerance.
fn generic_joint(a: &Block, b: &Block, ca: &BlockCtl, pl: &Planner, lim: &Limits) -> Joint {
    let cap = a.vcap.min(b.vcap);
    let tol = match ca.mode {
        PathMode::Blend { tolerance } => tolerance,
        PathMode::ExactStop => None,
    };
    let ell = match tol {
        None => a.len.min(b.len).min(pl.blend_mm),
        Some(t) => rounding_len(a, b, t),
    };
    Joint::At(junction_len_rule(a, b, cap, ell, lim))
}

/// Half the angle between the reversed first direction and the second (0:
/// a reversal, π/2: straight on), as LinuxCNC's `findIntersectionAngle`.
fn half_angle(a: &Block, b: &Block) -> f64 {
    let dot: f64 = (0..3).map(|i| a.dir[i] * b.dir[i]).sum();
    (-dot).clamp(-1.0, 1.0).acos() / 2.0
}

/// Length of the rounding arc of a corner within tolerance `t`, its
/// tangent points at most half of either block away from the corner.
fn rounding_len(a: &Block, b: &Block, t: f64) -> f64 {
    let th = half_angle(a, b);
    if std::f64::consts::FRAC_PI_2 - th < 1e-6 {
        return a.len.min(b.len);
    }
    let d_tol = th.cos() * t / (1.0 - th.sin());
    let d = d_tol.min(0.5 * a.len).min(0.5 * b.len);
    (th.tan() * d * (std::f64::consts::PI - 2.0 * th)).max(1e-9)
}

/// The smallest acceleration of the linear axes either block moves.
fn planar_accel(a: &Block, b: &Block, lim: &Limits) -> f64 {
    (0..3)
        .filter(|&i| a.dir[i].abs() > 1e-12 || b.dir[i].abs() > 1e-12)
        .map(|i| lim.accel[i])
        .fold(lim.planner.path_accel.unwrap_or(f64::INFINITY), f64::min)
}

/// The kink of LinuxCNC's `tpSetupTangent` between two XYZ blocks: the
/// largest share of an axis's acceleration the change of direction takes
/// when the speed `v` (the lower of the two caps) turns within one servo
/// period T, each axis's jump |Δe_i|·(v/T + a_b) over its acceleration
/// (doubled where an arc takes part: its tangential share). `None` where
/// LinuxCNC does not look for a kink: between a rapid and a feed move, and
/// at a reversal within 2° (a sharp corner: the motion stops).
fn kink(
    a: &Block,
    b: &Block,
    ca: &BlockCtl,
    cb: &BlockCtl,
    pl: &Planner,
    lim: &Limits,
) -> Option<f64> {
    let sum: f64 = (0..3).map(|i| (a.dir[i] + b.dir[i]).powi(2)).sum();
    if a.rapid != b.rapid || sum < (2f64.to_radians()).powi(2) || pl.block_time_s <= 0.0 {
        return None;
    }
    let period = pl.block_time_s / MIN_SEGMENT_CYCLES;
    let b_accel = (0..3)
        .filter(|&i| b.dir[i].abs() > 1e-12)
        .map(|i| lim.accel[i] / b.dir[i].abs())
        .fold(f64::INFINITY, f64::min);
    let a_inst = a.vcap.min(b.vcap) / period + b_accel;
    let mut scale = (0..3)
        .map(|i| a_inst * (b.dir[i] - a.dir[i]).abs() / lim.accel[i])
        .fold(0.0, f64::max);
    if ca.arc_radius > 0.0 || cb.arc_radius > 0.0 {
        scale /= pl.arc_tangential_share;
    }
    Some(scale)
}

/// LinuxCNC 2.9's choice at a junction of XYZ blocks (`tpHandleBlendArc`):
/// a rapid next to a feed move and a sharp reversal stop; nearly tangent
/// blocks, whose kink takes less than `KINK_RATIO` of the acceleration,
/// pass at speed with their acceleration reduced by that share, under G61
/// too (LinuxCNC's "exact path"); any other corner under G61 stops, its
/// blocks' acceleration still reduced by `KINK_RATIO`.
fn linuxcnc_joint(
    a: &Block,
    b: &Block,
    ca: &BlockCtl,
    cb: &BlockCtl,
    a_trimmed: f64,
    pl: &Planner,
    lim: &Limits,
) -> (Joint, f64) {
    let Some(scale) = kink(a, b, ca, cb, pl, lim) else {
        return (Joint::HardStop, 0.0);
    };
    if scale < KINK_RATIO {
        return (Joint::Kink(a.vcap.min(b.vcap)), scale);
    }
    if ca.mode == PathMode::ExactStop {
        return (Joint::Stop, KINK_RATIO);
    }
    let kink_vel = a.vcap.min(b.vcap) * KINK_RATIO / scale;
    match linuxcnc_blend(a, b, ca, cb, a_trimmed, pl, lim) {
        Joint::Parabolic(v) if v / 2.0 >= kink_vel => (Joint::Parabolic(v), 0.0),
        Joint::Arc(arc) if arc.vcap >= kink_vel => (Joint::Arc(arc), 0.0),
        _ => (Joint::Kink(kink_vel), KINK_RATIO),
    }
}

/// LinuxCNC 2.9's blend under G64 (`tpChooseBestBlend` between these two):
/// a blend arc within the tolerance (`blendmath.c`,
/// `blendComputeParameters`), unless a parabolic blend is faster or no arc
/// fits.
fn linuxcnc_blend(
    a: &Block,
    b: &Block,
    ca: &BlockCtl,
    cb: &BlockCtl,
    a_trimmed: f64,
    pl: &Planner,
    lim: &Limits,
) -> Joint {
    // Nearly tangent blocks never come here: their kink passes them.
    use std::f64::consts::PI;
    let th = half_angle(a, b);
    let a_max = planar_accel(a, b, lim);
    let a_par = a_max * pl.blend_accel_scale;
    let parabolic = parabolic_speed(a, b, ca, a_par, th);
    if th < 1e-6 {
        return Joint::Parabolic(parabolic);
    }
    let tol_of = |c: &BlockCtl, len: f64| match c.mode {
        PathMode::Blend { tolerance: Some(t) } if t > 0.0 => t,
        _ => 0.25 * len,
    };
    let t = tol_of(ca, a.len)
        .min(tol_of(cb, b.len))
        .min(0.25 * a.len)
        .min(0.25 * b.len);
    let l1 = (a.len - a_trimmed).min(0.5 * a.len);
    let l2 = 0.5 * b.len;
    let d_tol = th.cos() * t / (1.0 - th.sin());
    let d_geom = l1.min(l2).min(d_tol);
    let r_geom = th.tan() * d_geom;
    let a_n = a_max * (1.0 - pl.arc_tangential_share.powi(2)).sqrt();
    let v_goal = a.vgeom.max(b.vgeom).min(a.vcap.max(b.vcap));
    let v_plan = (a_n * r_geom).sqrt().min(v_goal);
    let v_tri = (2.0 * a_par * d_geom).sqrt();
    let phi = PI - 2.0 * th;
    let s_blend = v_tri.min(v_plan) / a_par * v_plan;
    let r_blend = (s_blend / phi).min(r_geom);
    let r_plan = (v_plan * v_plan / a_n).max(r_blend);
    let len = r_plan * phi;
    if r_plan < 1e-12 || len < 1e-6 {
        return Joint::Parabolic(parabolic);
    }
    let mut vcap = v_plan.min(a.vcap.max(b.vcap));
    if pl.block_time_s > 0.0 {
        vcap = vcap.min(len / pl.block_time_s);
    }
    // tpChooseBestBlend: a parabolic blend halves both blocks' acceleration,
    // counted as half its speed.
    if parabolic / 2.0 > vcap {
        return Joint::Parabolic(parabolic);
    }
    Joint::Arc(BlendArc {
        accel: a_max * pl.arc_tangential_share,
        trim: r_plan / th.tan(),
        len,
        vcap,
    })
}

/// The speed of LinuxCNC's parabolic blend (`tpComputeBlendVelocity`): each
/// block's speed when half of the shorter is left at the blend's
/// acceleration, within the tolerance, its component along the blend.
fn parabolic_speed(a: &Block, b: &Block, ca: &BlockCtl, acc: f64, th: f64) -> f64 {
    let reach = |x: &Block| (acc * x.len).sqrt().min(x.vcap);
    let (ra, rb) = (reach(a), reach(b));
    let t_blend = (a.len / ra).min(b.len / rb).min((ra / acc).max(rb / acc));
    let (mut va, mut vb) = (ra.min(t_blend * acc), rb.min(t_blend * acc));
    if let PathMode::Blend { tolerance: Some(t) } = ca.mode {
        let c = th.cos();
        if c > (std::f64::consts::FRAC_PI_2 - 1e-3).cos() {
            let v = 2.0 * (acc * t / c).sqrt();
            va = va.min(v);
            vb = vb.min(v);
        }
    }
    th.sin() * (va + vb) / 2.0
}

/// The look-ahead depth: the control must be able to stop at the end of
/// the blocks it has seen, so the speed entering block k is at most what
/// stops within the next `depth` blocks.
fn lookahead(s: &mut Shaped, ctl: Option<&[BlockCtl]>, pl: &Planner) {
    let n = s.blocks.len();
    let depth_of = |b: &Block| depth(ctl.is_some_and(|c| c[b.index].lookahead_on), pl);
    if n == 0 || s.blocks.iter().all(|b| depth_of(b) == 0) {
        return;
    }
    let mut prefix = vec![0.0; n + 1];
    for k in 0..n {
        prefix[k + 1] = prefix[k] + s.blocks[k].len;
    }
    for k in 1..n {
        let d = depth_of(&s.blocks[k]);
        if d == 0 {
            continue;
        }
        let end = (k + d).min(n);
        let a = s.blocks[k..end]
            .iter()
            .map(|b| b.accel)
            .fold(f64::INFINITY, f64::min);
        s.vj[k] = stop_within(s.vj[k], a, prefix[end] - prefix[k]);
    }
}

/// The blocks the control plans ahead of a block, its look-ahead function
/// `on` or not (0: as many as needed).
pub(super) fn depth(on: bool, pl: &Planner) -> usize {
    if pl.plain_lookahead > 0 && !on {
        pl.plain_lookahead
    } else {
        pl.lookahead
    }
}

/// Junction speed `v` at most what stops within `seen` at acceleration `a`.
pub(super) fn stop_within(v: f64, a: f64, seen: f64) -> f64 {
    v.min((2.0 * a * seen).sqrt())
}

#[cfg(test)]
mod tests {
    use super::super::{estimate_controlled, AxisMove, Limits, MoveKind};
    use super::*;

    /// X Y Z at 1000 mm/s², fast axes, no jerk, the given planner.
    fn lim(kind: PlannerKind) -> Limits {
        Limits {
            velocity: [1e6; 6],
            accel: [1000.0; 6],
            jerk: [f64::INFINITY; 6],
            rapid: 1e6,
            feed_max: 1e6,
            planner: Planner::of(kind),
        }
    }

    fn feed(x: f64, y: f64, from: [f64; 2], v: f64) -> AxisMove {
        let d = ((x - from[0]).powi(2) + (y - from[1]).powi(2)).sqrt();
        AxisMove {
            target: [x, y, 0.0, 0.0, 0.0, 0.0],
            kind: MoveKind::Feed {
                nominal_min: d / v / 60.0,
            },
        }
    }

    fn ctl(mode: PathMode) -> BlockCtl {
        BlockCtl {
            mode,
            ..BlockCtl::default()
        }
    }

    const STOP: PathMode = PathMode::ExactStop;
    const G64: PathMode = PathMode::Blend { tolerance: None };

    fn close(a: f64, b: f64, tol: f64) {
        assert!((a - b).abs() <= tol * b.abs().max(1.0), "{a} vs {b}");
    }

    /// A zig-zag of `n` strokes (X+10, Y±20), `v` mm/s.
    fn zigzag(n: usize, v: f64) -> Vec<AxisMove> {
        let mut at = [0.0, 0.0];
        (0..n)
            .map(|k| {
                let to = [10.0 * (k + 1) as f64, if k % 2 == 0 { 20.0 } else { 0.0 }];
                let m = feed(to[0], to[1], at, v);
                at = to;
                m
            })
            .collect()
    }

    #[test]
    fn linuxcnc_line_under_g61_is_a_trapezoid_and_under_g64_half_the_acceleration() {
        // tp.c: a segment that ends in a parabolic blend (the last one under
        // G64 too) runs at half its acceleration (tcGetOverallMaxAccel).
        // 100 mm at 100 mm/s, a = 1000: G61 L/v + v/a = 1.1 s (LinuxCNC
        // measured 1.100 s), G64 L/v + v/(a/2) = 1.2 s (measured 1.200 s).
        let l = lim(PlannerKind::LinuxCnc29);
        let m = [feed(100.0, 0.0, [0.0, 0.0], 100.0)];
        let t = |mode| estimate_controlled([0.0; 6], &m, &[ctl(mode)], &l).total_s;
        close(t(STOP), 1.1, 1e-12);
        close(t(G64), 1.2, 1e-12);
        // The generic planner knows no such halving.
        let g = lim(PlannerKind::Generic);
        close(
            estimate_controlled([0.0; 6], &m, &[ctl(G64)], &g).total_s,
            1.1,
            1e-12,
        );
    }

    #[test]
    fn zigzag_under_exact_stop_is_the_sum_of_its_trapezoids() {
        // Every block stops: each 22.36 mm stroke is its own trapezoid at
        // the path acceleration the busier axis allows (Y, 0.894 of the
        // motion: 1118 mm/s²), for every planner.
        let m = zigzag(20, 100.0);
        let len = (10.0f64 * 10.0 + 20.0 * 20.0).sqrt();
        let a = 1000.0 / (20.0 / len);
        let one = len / 100.0 + 100.0 / a;
        for kind in PlannerKind::ALL {
            let mut l = lim(kind);
            l.planner.block_time_s = 0.0;
            l.planner.profile = Profile::Trapezoid;
            let c = vec![ctl(STOP); m.len()];
            close(
                estimate_controlled([0.0; 6], &m, &c, &l).total_s,
                20.0 * one,
                1e-9,
            );
        }
        // LinuxCNC's G61 is exact path: at every corner too sharp for a
        // kink, tpSetupTangent leaves both blocks' acceleration reduced by
        // the kink ratio (tcGetOverallMaxAccel), 0.9·1118 mm/s²:
        // 20·(L/v + v/(0.9·a)) = 6.460 s (LinuxCNC measured 6.460 s).
        let l = lim(PlannerKind::LinuxCnc29);
        let c = vec![ctl(STOP); m.len()];
        let t = estimate_controlled([0.0; 6], &m, &c, &l).total_s;
        close(t, 20.0 * (len / 100.0 + 100.0 / (0.9 * a)), 1e-9);
        close(t, 6.460, 2e-4);
    }

    /// Two 50 mm blocks at 100 mm/s, the second turned by `delta` rad in
    /// X-Y.
    fn bent(delta: f64) -> Vec<AxisMove> {
        let end = [50.0 + 50.0 * delta.cos(), 50.0 * delta.sin()];
        vec![
            feed(50.0, 0.0, [0.0, 0.0], 100.0),
            feed(end[0], end[1], [50.0, 0.0], 100.0),
        ]
    }

    #[test]
    fn linuxcnc_exact_path_passes_a_kink_at_speed() {
        // tp.c, tpSetupTangent: the jump of each axis's velocity at the
        // kink, |Δe_i|·(v/T + a_b) with T the 1 ms servo period and a_b the
        // second block's acceleration (1000/cos δ), is 101,000·sin δ mm/s²
        // on Y: 0.0505 of Y's 1000 mm/s² at δ = 0.0005 rad, below the kink
        // ratio 0.1. Under G61 the blocks pass the kink at 100 mm/s, both
        // with their acceleration reduced by that share: one trapezoid,
        // L/v + v/(2·a_1) + v/(2·a_2).
        let l = lim(PlannerKind::LinuxCnc29);
        let delta = 0.0005f64;
        let m = bent(delta);
        let a_b = 1000.0 / delta.cos();
        let share = (100.0 / 0.001 + a_b) * delta.sin() / 1000.0;
        assert!(share < 0.1, "{share}");
        let (a1, a2) = (1000.0 * (1.0 - share), a_b * (1.0 - share));
        let want = 100.0 / 100.0 + 100.0 / (2.0 * a1) + 100.0 / (2.0 * a2);
        let t = estimate_controlled([0.0; 6], &m, &[ctl(STOP); 2], &l).total_s;
        close(t, want, 1e-9);
        // Turned by 0.002 rad (a share of 0.202): too sharp for a kink, the
        // motion stops, each block at 0.9 of its acceleration.
        let m = bent(0.002);
        let a_b = 1000.0 / 0.002f64.cos();
        let want = 1.0 + 100.0 / 900.0 + 100.0 / (0.9 * a_b);
        let t = estimate_controlled([0.0; 6], &m, &[ctl(STOP); 2], &l).total_s;
        close(t, want, 1e-9);
        // A reversal within 2° (here 0.57°) stops under G64 too, the
        // first block at rest at its end, neither reduced nor halved; the
        // last halved (its end blends with nothing).
        let back = [
            feed(50.0, 0.0, [0.0, 0.0], 100.0),
            feed(0.0, 0.5, [50.0, 0.0], 100.0),
        ];
        let len2 = (50.0f64 * 50.0 + 0.25).sqrt();
        let a2 = 1000.0 * len2 / 50.0;
        let t = estimate_controlled([0.0; 6], &back, &[ctl(G64); 2], &l).total_s;
        close(t, 0.5 + 0.1 + len2 / 100.0 + 100.0 / (0.5 * a2), 1e-9);
    }

    #[test]
    fn linuxcnc_blending_takes_a_kink_where_it_is_the_fastest_blend() {
        // Under G64 P0.01 the same 0.0005 rad kink is passed at 100 mm/s
        // (tpChooseBestBlend: the kink's speed beats the blend arc's), the
        // last block at half its acceleration (it ends in a parabolic
        // blend with nothing), both reduced by the kink's share.
        let l = lim(PlannerKind::LinuxCnc29);
        let delta = 0.0005f64;
        let m = bent(delta);
        let a_b = 1000.0 / delta.cos();
        let share = (100.0 / 0.001 + a_b) * delta.sin() / 1000.0;
        let (a1, a2) = (1000.0 * (1.0 - share), 0.5 * a_b * (1.0 - share));
        let want = 1.0 + 100.0 / (2.0 * a1) + 100.0 / (2.0 * a2);
        let p = ctl(PathMode::Blend {
            tolerance: Some(0.01),
        });
        let t = estimate_controlled([0.0; 6], &m, &[p; 2], &l).total_s;
        close(t, want, 1e-9);
    }

    #[test]
    fn linuxcnc_blend_arc_follows_blendmath() {
        // Two perpendicular 50 mm lines under G64 P0.01 at 100 mm/s: θ =
        // 45°, the arc's tangent points d = cosθ·T/(1 − sinθ) from the
        // corner, R = tanθ·d, speed √(a·√(1 − 0.5²)·R) (blendmath.c,
        // blendComputeParameters; the parabolic-equivalent radius is
        // smaller here, so R_plan = v²/a_n = R).
        let l = lim(PlannerKind::LinuxCnc29);
        let m = [
            feed(50.0, 0.0, [0.0, 0.0], 100.0),
            feed(50.0, 50.0, [50.0, 0.0], 100.0),
        ];
        let tol = 0.01;
        let c = [ctl(PathMode::Blend {
            tolerance: Some(tol),
        }); 2];
        let (blocks, stops) = super::super::prepare([0.0; 6], &m, &l);
        let caps: Vec<f64> = blocks.iter().map(|b| b.vcap).collect();
        let s = shape(&blocks, &caps, &stops, Some(&c), &l.planner, &l);
        assert_eq!(s.blocks.len(), 3, "line, blend arc, line");
        let th = std::f64::consts::FRAC_PI_4;
        let d = th.cos() * tol / (1.0 - th.sin());
        let r = th.tan() * d;
        let v = (1000.0 * 0.75f64.sqrt() * r).sqrt();
        close(s.blocks[1].vcap, v, 1e-12);
        close(s.blocks[1].len, r * std::f64::consts::FRAC_PI_2, 1e-9);
        close(s.blocks[0].len, 50.0 - d, 1e-12);
        close(s.blocks[2].len, 50.0 - d, 1e-12);
        // Full acceleration on the first line (it meets an arc), half on
        // the last (its end blends parabolically with nothing).
        close(s.blocks[0].accel, 1000.0, 1e-12);
        close(s.blocks[2].accel, 500.0, 1e-12);
        close(s.vj[1], v, 1e-12);
        let want = estimate_controlled([0.0; 6], &m, &c, &l).total_s;
        // A wider tolerance passes the corner faster.
        let wide = [ctl(PathMode::Blend {
            tolerance: Some(1.0),
        }); 2];
        assert!(estimate_controlled([0.0; 6], &m, &wide, &l).total_s < want - 0.05);
    }

    #[test]
    fn stop_once_and_tolerance_change_the_generic_estimate() {
        let l = lim(PlannerKind::Generic);
        let m = [
            feed(50.0, 0.0, [0.0, 0.0], 50.0),
            feed(50.0, 50.0, [50.0, 0.0], 50.0),
        ];
        let t = |c: [BlockCtl; 2]| estimate_controlled([0.0; 6], &m, &c, &l).total_s;
        let blend = t([ctl(G64); 2]);
        let mut once = [ctl(G64); 2];
        once[0].stop_after = true;
        // Stopped at the corner: two rest-to-rest trapezoids.
        close(t(once), 2.0 * (1.0 + 50.0 / 1000.0), 1e-12);
        close(t([ctl(STOP); 2]), t(once), 1e-12);
        assert!(blend < t(once));
        // A tolerance of 0.01 mm rounds over less than the default 0.2 mm:
        // the corner is slower.
        let tight = t([ctl(PathMode::Blend {
            tolerance: Some(0.01),
        }); 2]);
        assert!(tight > blend && tight < t(once), "{tight} {blend}");
    }

    #[test]
    fn a_short_look_ahead_slows_short_blocks() {
        // 100 collinear 0.1 mm blocks at 50 mm/s. Unlimited look-ahead: one
        // trapezoid, L/v + v/a. Seeing one block ahead, the speed entering
        // each is at most √(2·a·0.1) = 14.1 mm/s: about L/14.1.
        let mut l = lim(PlannerKind::Fanuc);
        l.planner.block_time_s = 0.0;
        l.planner.profile = Profile::Trapezoid;
        let m: Vec<AxisMove> = (0..100)
            .map(|k| feed(0.1 * (k + 1) as f64, 0.0, [0.1 * k as f64, 0.0], 50.0))
            .collect();
        let mut c = vec![ctl(G64); 100];
        let plain = estimate_controlled([0.0; 6], &m, &c, &l).total_s;
        for x in &mut c {
            x.lookahead_on = true;
        }
        let on = estimate_controlled([0.0; 6], &m, &c, &l).total_s;
        close(on, 10.0 / 50.0 + 50.0 / 1000.0, 1e-9);
        let vmax = (2.0f64 * 1000.0 * 0.1).sqrt();
        assert!(
            plain > 10.0 / vmax * 0.9 && plain < 10.0 / vmax * 1.2,
            "{plain}"
        );
    }

    #[test]
    fn linuxcnc_arcs_take_half_the_acceleration_along_the_path() {
        // A circle R25 at 50 mm/s in 5° chords (TP_ACC_RATIO_TANGENTIAL):
        // G61 L/v + v/(a/2) (LinuxCNC measured 3.242 s); G64 halves it
        // again (measured 3.342 s). L the chords' length.
        let l = lim(PlannerKind::LinuxCnc29);
        let n = 72;
        let mut at = [0.0, 0.0];
        let m: Vec<AxisMove> = (1..=n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                let to = [25.0 - 25.0 * a.cos(), 25.0 * a.sin()];
                let mv = feed(to[0], to[1], at, 50.0);
                at = to;
                mv
            })
            .collect();
        let len = n as f64 * 2.0 * 25.0 * (std::f64::consts::PI / n as f64).sin();
        let arc = |mode| {
            let mut c = vec![ctl(mode); n];
            for (k, x) in c.iter_mut().enumerate() {
                x.arc_radius = 25.0;
                x.same_move = k + 1 < n;
            }
            estimate_controlled([0.0; 6], &m, &c, &l).total_s
        };
        close(arc(STOP), len / 50.0 + 50.0 / 500.0, 2e-4);
        close(arc(G64), len / 50.0 + 50.0 / 250.0, 2e-4);
    }
}
