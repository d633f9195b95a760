//! A toolpath on the robot: the process load along it, the deflection of
//! the TCP at every point (Equation 2), offline compensation
//! p_cmd = p_ideal − Δp (Equation 11, process-models §4.4) and the
//! workpiece placement that minimises the mean deflection (§4.5).
//!
//! The load is the process force on the tool given in each point's feed
//! frame (along the feed, across it, along the tool axis), so that it turns
//! with the path; it is rotated into the robot base with the workpiece's
//! placement and acts at the TCP.

use crate::anneal::{self, Settings};
use crate::kin::Joints;
use crate::pose::{matrix_to_abc, rotation_vector, Pose};
use crate::robot::Robot;
use crate::stiffness::Variant;
use millplan_geom::{DMat3, DVec3};
use millplan_nc::ir::{MoveKind, Program};
use millplan_nc::krl::{
    abc_for_axis, abc_matrix, Approx, KrlPos, KrlProgram, Located, Motion, Statement,
};
use rayon::prelude::*;

/// One point of a toolpath, in the workpiece frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathPoint {
    /// Tool tip, mm.
    pub p: DVec3,
    /// Unit tool axis (tip toward the spindle).
    pub axis: DVec3,
    /// Feed, mm/min.
    pub feed: f64,
    /// Source line.
    pub line: u32,
    /// Index of the move over the whole program (operations in order), the
    /// key of a per-move load.
    pub mv: u32,
    /// A rotation of the tool's orientation on top of the one its axis
    /// gives (rotation vector, rad, workpiece frame, applied on the left):
    /// zero on a nominal path, −Δθ where the compensation corrects the
    /// orientation.
    pub tilt: DVec3,
}

impl PathPoint {
    /// The tool's orientation in the workpiece frame (KUKA: the tool along
    /// the frame's x): that of the axis, turned by the tilt.
    pub fn orientation(&self) -> DMat3 {
        let r = abc_matrix(abc_for_axis(self.axis));
        if self.tilt == DVec3::ZERO {
            r
        } else {
            rotation(self.tilt) * r
        }
    }

    /// KUKA's A, B, C (degrees) of the orientation: exactly those of the
    /// axis when there is no tilt.
    pub fn abc(&self) -> [f64; 3] {
        if self.tilt == DVec3::ZERO {
            abc_for_axis(self.axis)
        } else {
            matrix_to_abc(&self.orientation())
        }
    }
}

/// The rotation of a rotation vector (axis times angle, rad).
pub fn rotation(v: DVec3) -> DMat3 {
    DMat3::from_quat(glam::DQuat::from_scaled_axis(v))
}

/// The workpiece frame in the robot base: a translation (mm) and a turn
/// about the base's vertical (radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub rz: f64,
}

impl Placement {
    pub fn pose(&self) -> Pose {
        Pose::new(
            DMat3::from_rotation_z(self.rz),
            DVec3::new(self.x, self.y, self.z),
        )
    }
}

/// The process force on the tool in the feed frame, N.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Load {
    /// Along the feed.
    pub feed: f64,
    /// Across the feed: axis × feed (left of the feed seen from the spindle).
    pub cross: f64,
    /// Along the tool axis (toward the spindle).
    pub axial: f64,
}

impl Load {
    /// The force in the workpiece frame at a point with tool axis `axis`
    /// (unit) feeding along `feed` (unit, normal to the axis).
    pub fn force(&self, axis: DVec3, feed: DVec3) -> DVec3 {
        feed * self.feed + axis.cross(feed) * self.cross + axis * self.axial
    }
}

/// The process load along a path, in the feed frame of each point: the same
/// everywhere, or one per move of the program (what the force model with
/// the stock gives: the mean over a revolution, averaged along the move;
/// zero in air), indexed by [`PathPoint::mv`]; a move past the end has
/// none.
#[derive(Clone, Debug, PartialEq)]
pub enum PathLoad {
    Fixed(Load),
    PerMove(Vec<Load>),
}

const NO_LOAD: Load = Load {
    feed: 0.0,
    cross: 0.0,
    axial: 0.0,
};

impl PathLoad {
    /// The load at `pt`.
    pub fn at(&self, pt: &PathPoint) -> Load {
        match self {
            PathLoad::Fixed(l) => *l,
            PathLoad::PerMove(v) => v.get(pt.mv as usize).copied().unwrap_or(NO_LOAD),
        }
    }
}

/// Why a point cannot be machined.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MachiningError {
    #[error("line {line}: the robot cannot reach the point with one configuration within its limits and wrist margin")]
    Unreachable { line: u32, index: usize },
    #[error("the program has no cutting moves")]
    Empty,
    #[error("line {line}: {message}")]
    Program { line: u32, message: String },
}

/// The cutting moves of a program as runs of points (a rapid ends a run;
/// arcs as chords within 0.01 mm).
pub fn cutting_runs(prog: &Program) -> Result<Vec<Vec<PathPoint>>, MachiningError> {
    let mut runs = Vec::new();
    let mut index = 0u32;
    for op in &prog.operations {
        let mut run: Vec<PathPoint> = Vec::new();
        let mut last = op.start;
        for m in &op.moves {
            let axis = op.axis(m).unwrap_or(DVec3::Z);
            let mv = index;
            index += 1;
            let point = |p: DVec3| PathPoint {
                p,
                axis,
                feed: m.feed,
                line: m.line,
                mv,
                tilt: DVec3::ZERO,
            };
            match m.kind {
                MoveKind::Rapid => {
                    if run.len() > 1 {
                        runs.push(std::mem::take(&mut run));
                    }
                    run.clear();
                }
                MoveKind::Cycle(_) => {
                    return Err(MachiningError::Program {
                        line: m.line,
                        message: "a canned cycle: not a path a robot follows".into(),
                    })
                }
                _ if !m.end.is_finite() => {
                    return Err(MachiningError::Program {
                        line: m.line,
                        message: "a position not known here".into(),
                    })
                }
                MoveKind::Arc(_) if last.is_finite() => {
                    if run.is_empty() {
                        run.push(point(last));
                    }
                    let arc = op.arc(m).expect("the move's arc");
                    for p in millplan_nc::write::arc_points(arc, last, m.end, 0.01) {
                        run.push(point(p));
                    }
                }
                _ => {
                    if run.is_empty() && last.is_finite() {
                        run.push(point(last));
                    }
                    run.push(point(m.end));
                }
            }
            last = m.end;
        }
        if run.len() > 1 {
            runs.push(run);
        }
    }
    if runs.is_empty() {
        return Err(MachiningError::Empty);
    }
    Ok(runs)
}

/// A run resampled so that no two points are more than `step` mm apart:
/// every vertex kept, each segment cut into equal parts (the axis
/// interpolated and normalised, the feed and line of the segment).
pub fn resample(run: &[PathPoint], step: f64) -> Vec<PathPoint> {
    let mut out = vec![run[0]];
    for w in run.windows(2) {
        let (a, b) = (w[0], w[1]);
        let n = ((b.p - a.p).length() / step).ceil().max(1.0) as usize;
        for k in 1..=n {
            let t = k as f64 / n as f64;
            let axis = a.axis.lerp(b.axis, t).try_normalize().unwrap_or(b.axis);
            out.push(PathPoint {
                p: a.p.lerp(b.p, t),
                axis,
                ..b
            });
        }
    }
    out
}

/// Points every `step` mm of length along a run (the first and last
/// kept; corners in between are not): the paper's 10 mm samples.
pub fn sample_every(run: &[PathPoint], step: f64) -> Vec<PathPoint> {
    let mut out = vec![run[0]];
    let mut next = step; // length at which the next sample lies
    let mut walked = 0.0;
    for w in run.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len = (b.p - a.p).length();
        while next <= walked + len && len > 0.0 {
            let t = (next - walked) / len;
            let axis = a.axis.lerp(b.axis, t).try_normalize().unwrap_or(b.axis);
            out.push(PathPoint {
                p: a.p.lerp(b.p, t),
                axis,
                ..b
            });
            next += step;
        }
        walked += len;
    }
    if out
        .last()
        .is_some_and(|l| (l.p - run[run.len() - 1].p).length() > 1e-9)
    {
        out.push(run[run.len() - 1]);
    }
    out
}

/// The feed direction at each point: toward the next (the last: from the
/// one before), perpendicular to the tool axis.
pub fn feed_dirs(run: &[PathPoint]) -> Vec<DVec3> {
    let n = run.len();
    let mut out = Vec::with_capacity(n);
    let mut prev = DVec3::X;
    for i in 0..n {
        let d = if i + 1 < n {
            run[i + 1].p - run[i].p
        } else {
            run[i].p - run[i.saturating_sub(1)].p
        };
        let a = run[i].axis;
        let f = (d - a * d.dot(a)).try_normalize().unwrap_or(prev);
        out.push(f);
        prev = f;
    }
    out
}

/// The TCP's pose in the base for a tool tip `p` and axis `axis` in the
/// workpiece placed at `place` (KUKA: the tool along the tool frame's x).
pub fn tcp_pose(place: &Pose, p: DVec3, axis: DVec3) -> Pose {
    Pose::new(place.r * abc_matrix(abc_for_axis(axis)), place.apply(p))
}

/// What a thread keeps between the points of a path: the chain's frames
/// and the last tool axis and tilt with their rotation (a path's axis
/// seldom changes, and turning it into KUKA's A, B, C and back costs a
/// dozen sines).
#[derive(Default)]
struct Scratch {
    frames: Vec<Pose>,
    axis: Option<(DVec3, DVec3, DMat3)>,
}

impl Scratch {
    /// The TCP's pose in the base at `pt` ([`tcp_pose`] with the tilt), the
    /// rotation of the last axis and tilt reused.
    fn tcp_pose(&mut self, place: &Pose, pt: &PathPoint) -> Pose {
        let r = match self.axis {
            Some((a, t, r)) if a == pt.axis && t == pt.tilt => r,
            _ => {
                let r = place.r * pt.orientation();
                self.axis = Some((pt.axis, pt.tilt, r));
                r
            }
        };
        Pose::new(r, place.apply(pt.p))
    }
}

/// The deflection along a run: Δp (workpiece frame, mm) and Δθ (the
/// rotation vector of the tool, workpiece frame, rad) per point.
#[derive(Clone, Debug, PartialEq)]
pub struct Deflections {
    pub dp: Vec<DVec3>,
    pub dtheta: Vec<DVec3>,
    pub mean: f64,
    pub max: f64,
    /// KUKA Status of the configuration used throughout.
    pub status: u8,
}

impl Robot {
    /// The Status to machine a path in: that of the feasible solution at the
    /// first point in the basic area, the wrist farthest from its singularity.
    pub fn choose_status(&self, tcp: &Pose) -> Option<u8> {
        self.ik_all(tcp, 0.0)
            .into_iter()
            .filter_map(|q| self.feasible_winding(&q))
            .max_by(|a, b| {
                let key = |q: &Joints| (u8::from(self.config(q).status & 1 == 0), q[4].abs());
                let (ka, kb) = (key(a), key(b));
                ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
            })
            .map(|q| self.config(&q).status)
    }

    /// The TCP's deflection at every point of `run` under `load`, the
    /// workpiece at `place`; one Status throughout (`status`, or chosen at
    /// the first point).
    pub fn deflections(
        &self,
        variant: Variant,
        place: &Placement,
        run: &[PathPoint],
        load: &Load,
        status: Option<u8>,
    ) -> Result<Deflections, MachiningError> {
        self.deflections_along(variant, place, run, &feed_dirs(run), load, status)
    }

    /// As [`Robot::deflections`] with the feed directions given: the
    /// nominal path's, when the points are the compensated ones (the forces
    /// are those of the nominal path, process-models §4.4).
    pub fn deflections_along(
        &self,
        variant: Variant,
        place: &Placement,
        run: &[PathPoint],
        dirs: &[DVec3],
        load: &Load,
        status: Option<u8>,
    ) -> Result<Deflections, MachiningError> {
        if dirs.len() != run.len() {
            return Err(MachiningError::Program {
                line: run.first().map_or(0, |p| p.line),
                message: format!("{} feed directions for {} points", dirs.len(), run.len()),
            });
        }
        self.deflections_by(variant, place, run, status, |i, pt| {
            load.force(pt.axis, dirs[i])
        })
    }

    /// As [`Robot::deflections_along`] under a [`PathLoad`]: each point's
    /// load in its feed frame (`dirs`, the nominal path's).
    pub fn deflections_loaded(
        &self,
        variant: Variant,
        place: &Placement,
        run: &[PathPoint],
        dirs: &[DVec3],
        load: &PathLoad,
        status: Option<u8>,
    ) -> Result<Deflections, MachiningError> {
        if let PathLoad::Fixed(l) = load {
            return self.deflections_along(variant, place, run, dirs, l, status);
        }
        if dirs.len() != run.len() {
            return Err(MachiningError::Program {
                line: run.first().map_or(0, |p| p.line),
                message: format!("{} feed directions for {} points", dirs.len(), run.len()),
            });
        }
        self.deflections_by(variant, place, run, status, |i, pt| {
            load.at(pt).force(pt.axis, dirs[i])
        })
    }

    /// The deflection along a run under a force of its own at every point
    /// (N, in the workpiece frame: what the force model gives along the
    /// path), turned into the base with the placement.
    pub fn deflections_under(
        &self,
        variant: Variant,
        place: &Placement,
        run: &[PathPoint],
        forces: &[DVec3],
        status: Option<u8>,
    ) -> Result<Deflections, MachiningError> {
        if forces.len() != run.len() {
            return Err(MachiningError::Program {
                line: run.first().map_or(0, |p| p.line),
                message: format!(
                    "{} forces for {} points: one force a point was expected",
                    forces.len(),
                    run.len()
                ),
            });
        }
        self.deflections_by(variant, place, run, status, |i, _| forces[i])
    }

    /// The deflection along a run, `force(i, point)` the force on the tool
    /// at point i in the workpiece frame (N).
    fn deflections_by(
        &self,
        variant: Variant,
        place: &Placement,
        run: &[PathPoint],
        status: Option<u8>,
        force: impl Fn(usize, &PathPoint) -> DVec3 + Sync,
    ) -> Result<Deflections, MachiningError> {
        let pose = place.pose();
        let first = run.first().ok_or(MachiningError::Empty)?;
        let status = match status {
            Some(s) => s,
            None => self
                .choose_status(&Pose::new(
                    pose.r * first.orientation(),
                    pose.apply(first.p),
                ))
                .ok_or(MachiningError::Unreachable {
                    line: first.line,
                    index: 0,
                })?,
        };
        let d: Vec<(DVec3, DVec3)> = run
            .par_iter()
            .enumerate()
            .map_init(Scratch::default, |s, (i, pt)| {
                let tcp = s.tcp_pose(&pose, pt);
                let q = self
                    .ik_status(&tcp, status)
                    .ok_or(MachiningError::Unreachable {
                        line: pt.line,
                        index: i,
                    })?;
                let base = pose.r * force(i, pt);
                let (_, d) = self.deflect_with(&q, variant, base, DVec3::ZERO, &mut s.frames);
                let back = pose.r.transpose();
                Ok((back * d.dp, back * d.dtheta))
            })
            .collect::<Result<_, MachiningError>>()?;
        let (dp, dtheta): (Vec<DVec3>, Vec<DVec3>) = d.into_iter().unzip();
        let lens = dp.iter().map(|d| d.length());
        let max = lens.clone().fold(0.0, f64::max);
        let mean = lens.sum::<f64>() / dp.len() as f64;
        Ok(Deflections {
            dp,
            dtheta,
            mean,
            max,
            status,
        })
    }
}

/// p_cmd = p_ideal − Δp (Equation 11).
pub fn compensate(run: &[PathPoint], dp: &[DVec3]) -> Vec<PathPoint> {
    run.iter()
        .zip(dp)
        .map(|(p, d)| PathPoint { p: p.p - *d, ..*p })
        .collect()
}

/// p_cmd = p_ideal − Δp and the orientation turned by −Δθ (the small-angle
/// rotation vector taken as a rotation, composed on the left: in the
/// workpiece frame, which is the base's turned about the vertical, so the
/// same as in the base), in one step as the position.
pub fn compensate_pose(run: &[PathPoint], d: &Deflections) -> Vec<PathPoint> {
    run.iter()
        .zip(d.dp.iter().zip(&d.dtheta))
        .map(|(p, (dp, dth))| {
            let tilt = if p.tilt == DVec3::ZERO {
                -*dth
            } else {
                rotation_vector(&(rotation(-*dth) * rotation(p.tilt)))
            };
            PathPoint {
                p: p.p - *dp,
                tilt,
                ..*p
            }
        })
        .collect()
}

/// The angle (rad) between the deflected tool, commanded with tilt `cmd`
/// and turned by `dtheta`, and the nominal tool with tilt `ideal` (the same
/// axis): |dtheta| itself when neither is tilted.
fn orientation_residual(dtheta: DVec3, cmd: DVec3, ideal: DVec3) -> f64 {
    if cmd == DVec3::ZERO && ideal == DVec3::ZERO {
        return dtheta.length();
    }
    let q = |v: DVec3| glam::DQuat::from_scaled_axis(v);
    let r = q(dtheta) * q(cmd) * q(ideal).inverse();
    2.0 * r.xyz().length().atan2(r.w.abs())
}

/// A KRL program of compensated runs: the workpiece frame as `BASE_DATA`
/// values in a comment (the cell's own taught base is selected), a `PTP`
/// approach to each run's first point, one `LIN` per point with `C_DIS`
/// but the last, `$VEL.CP` in m/s.
pub fn krl_program(
    name: &str,
    runs: &[Vec<PathPoint>],
    place: &Placement,
    cdis: f64,
) -> KrlProgram {
    let mut st = Vec::new();
    let mut push = |line: u32, s: Statement| {
        st.push(Located {
            file: 0,
            line,
            statement: s,
        })
    };
    push(0, Statement::Verbatim("BAS(#INITMOV, 0)".into()));
    push(0, Statement::Verbatim("$ADVANCE = 3".into()));
    push(0, Statement::Verbatim(format!(
        "; workpiece placement: BASE_DATA[1] = {{X {:.3}, Y {:.3}, Z {:.3}, A {:.4}, B 0.0, C 0.0}}",
        place.x, place.y, place.z, place.rz.to_degrees()
    )));
    push(0, Statement::Base("BASE_DATA[1]".into()));
    push(0, Statement::Tool("TOOL_DATA[1]".into()));
    push(0, Statement::ApoCdis(cdis));
    let mut vel = None;
    for run in runs {
        for (i, p) in run.iter().enumerate() {
            let pos = KrlPos {
                xyz: p.p,
                abc: p.abc(),
                e: [None; 6],
                s: None,
                t: None,
            };
            let v = crate::round_vel(p.feed / 60_000.0);
            if i > 0 && vel != Some(v) {
                push(p.line, Statement::VelCp(v));
                vel = Some(v);
            }
            let (motion, approx) = match i {
                0 => (Motion::Ptp(pos), Approx::Exact),
                i if i + 1 == run.len() => (Motion::Lin(pos), Approx::Exact),
                _ => (Motion::Lin(pos), Approx::Dis),
            };
            push(
                p.line,
                Statement::Move {
                    motion,
                    approx,
                    vel_cp: vel,
                    with: Vec::new(),
                },
            );
        }
    }
    let name = millplan_nc::write::krl::krl_name(name);
    KrlProgram {
        name: name.clone(),
        files: vec![name],
        statements: st,
        ..KrlProgram::default()
    }
}

/// The placement search's box and settings.
#[derive(Clone, Copy, Debug)]
pub struct PlaceSearch {
    /// Lower and upper corner of the workpiece origin, mm.
    pub lo: DVec3,
    pub hi: DVec3,
    pub settings: Settings,
}

/// The best placement found, its deflections and the evaluations spent.
#[derive(Clone, Debug)]
pub struct Placed {
    pub place: Placement,
    pub mean: f64,
    pub max: f64,
    pub evaluations: usize,
}

/// Workpiece placement by constrained simulated annealing: x, y, z in the
/// box, the turn about the vertical anywhere; objective the mean |Δp| over
/// `samples` (the path resampled every 10 mm); infeasible placements
/// (unreachable, limits, wrist) rejected.
pub fn place(
    robot: &Robot,
    variant: Variant,
    samples: &[PathPoint],
    load: &PathLoad,
    search: &PlaceSearch,
) -> Option<Placed> {
    let dirs = feed_dirs(samples);
    let placement = |x: &[f64]| Placement {
        x: x[0],
        y: x[1],
        z: x[2],
        rz: x[3],
    };
    let f = |x: &[f64]| {
        robot
            .deflections_loaded(variant, &placement(x), samples, &dirs, load, None)
            .ok()
            .map(|d| d.mean)
    };
    let (lo, hi) = (search.lo, search.hi);
    let pi = std::f64::consts::PI;
    let best = anneal::minimise(
        &f,
        &[lo.x, lo.y, lo.z, -pi],
        &[hi.x, hi.y, hi.z, pi],
        &search.settings,
    )?;
    let p = placement(&best.x);
    let d = robot
        .deflections_loaded(variant, &p, samples, &dirs, load, None)
        .ok()?;
    Some(Placed {
        place: p,
        mean: d.mean,
        max: d.max,
        evaluations: best.evaluations,
    })
}

/// A program compensated for the robot's deflection.
#[derive(Clone, Debug)]
pub struct Compensated {
    /// The commanded runs, p_cmd = p_ideal − Δp, every `spacing` mm.
    pub runs: Vec<Vec<PathPoint>>,
    /// The nominal runs they were computed from, point for point.
    pub ideal: Vec<Vec<PathPoint>>,
    /// Mean and largest |Δp| over all points before compensation, mm.
    pub mean: f64,
    pub max: f64,
    /// Mean and largest distance of the tip from the nominal path after
    /// compensation, mm: the robot commanded to p_cmd and pushed by the
    /// same loads (the model against itself, T14).
    pub residual_mean: f64,
    pub residual_max: f64,
    /// Mean and largest |Δθ|, the tool's turn under the load, before
    /// compensation, degrees.
    pub rot_mean_deg: f64,
    pub rot_max_deg: f64,
    /// Mean and largest angle between the deflected tool at the commanded
    /// points and the nominal tool, degrees: |Δθ| there when the
    /// orientation is not corrected.
    pub residual_rot_mean_deg: f64,
    pub residual_rot_max_deg: f64,
    /// Whether the orientation was corrected too.
    pub orientation: bool,
    pub points: usize,
}

/// Sums and maxima of the distances and angles over the points.
#[derive(Default)]
struct Tally {
    sum: f64,
    max: f64,
    rot_sum: f64,
    rot_max: f64,
}

impl Tally {
    fn add(&mut self, dist: f64, angle: f64) {
        self.sum += dist;
        self.max = self.max.max(dist);
        self.rot_sum += angle;
        self.rot_max = self.rot_max.max(angle);
    }
}

/// Compensates every cutting run of `prog` (in the workpiece frame, placed
/// at `place`): resampled every `spacing` mm (0.3 in the paper), Δp from
/// the nominal path, p_cmd = p − Δp, one Status throughout each run; then
/// the deflection again at the commanded points under the nominal path's
/// loads, for the residual.
pub fn compensate_program(
    robot: &Robot,
    variant: Variant,
    prog: &Program,
    place: &Placement,
    load: &PathLoad,
    spacing: f64,
) -> Result<Compensated, MachiningError> {
    compensate_program_with(robot, variant, prog, place, load, spacing, false)
}

/// [`compensate_program`], with `orientation` the tool's orientation
/// corrected as well ([`compensate_pose`]).
pub fn compensate_program_with(
    robot: &Robot,
    variant: Variant,
    prog: &Program,
    place: &Placement,
    load: &PathLoad,
    spacing: f64,
    orientation: bool,
) -> Result<Compensated, MachiningError> {
    let (mut runs, mut ideals) = (Vec::new(), Vec::new());
    let (mut before, mut after, mut points) = (Tally::default(), Tally::default(), 0);
    for run in cutting_runs(prog)? {
        let ideal = resample(&run, spacing);
        let dirs = feed_dirs(&ideal);
        let d = robot.deflections_loaded(variant, place, &ideal, &dirs, load, None)?;
        for (dp, dth) in d.dp.iter().zip(&d.dtheta) {
            before.add(dp.length(), dth.length());
        }
        points += ideal.len();
        let cmd = match orientation {
            true => compensate_pose(&ideal, &d),
            false => compensate(&ideal, &d.dp),
        };
        let at = robot.deflections_loaded(variant, place, &cmd, &dirs, load, Some(d.status))?;
        for (((c, a), th), i) in cmd.iter().zip(&at.dp).zip(&at.dtheta).zip(&ideal) {
            after.add(
                (c.p + *a - i.p).length(),
                orientation_residual(*th, c.tilt, i.tilt),
            );
        }
        runs.push(cmd);
        ideals.push(ideal);
    }
    let n = points as f64;
    Ok(Compensated {
        runs,
        ideal: ideals,
        mean: before.sum / n,
        max: before.max,
        residual_mean: after.sum / n,
        residual_max: after.max,
        rot_mean_deg: (before.rot_sum / n).to_degrees(),
        rot_max_deg: before.rot_max.to_degrees(),
        residual_rot_mean_deg: (after.rot_sum / n).to_degrees(),
        residual_rot_max_deg: after.rot_max.to_degrees(),
        orientation,
        points,
    })
}

/// The largest distance of the deflected tip from the nominal path when the
/// robot is commanded to `cmd` (runs point for point with `c.ideal`, e.g.
/// the commanded points read back from the KRL written) under `load`, mm.
pub fn residual_max(
    robot: &Robot,
    variant: Variant,
    place: &Placement,
    c: &Compensated,
    cmd: &[Vec<PathPoint>],
    load: &PathLoad,
) -> Result<f64, MachiningError> {
    let mut max = 0.0f64;
    for (ideal, run) in c.ideal.iter().zip(cmd) {
        let d = robot.deflections_loaded(variant, place, run, &feed_dirs(ideal), load, None)?;
        for ((p, dp), i) in run.iter().zip(&d.dp).zip(ideal) {
            max = max.max((p.p + *dp - i.p).length());
        }
    }
    Ok(max)
}

/// The cutting runs of `prog` resampled every 10 mm (the paper's placement
/// objective), as one list.
pub fn placement_samples(prog: &Program) -> Result<Vec<PathPoint>, MachiningError> {
    Ok(cutting_runs(prog)?
        .iter()
        .flat_map(|r| resample(r, 10.0))
        .collect())
}

/// Schnoes & Zaeh Table 3 (process-models §1.5e): the flute-segment
/// coefficients for EN AW-2007, (k_e N/mm, k_c N/mm²) along the flute (t),
/// outward (d) and along the cutting velocity (n).
pub const EN_AW_2007: [(f64, f64); 3] = [(4.63, 57.5), (-11.8, -76.5), (-11.0, -672.0)];

/// The mean force on a flat end mill cutting a full slot with the
/// flute-segment law of Equation 10 and the EN AW-2007 coefficients:
/// straight flutes (the helix shifts the phase, not the mean),
/// h = f_z·sin φ, φ from 0 to π, `flutes` flutes, depth `ap` mm. In closed
/// form, per revolution: F_feed = N·ap/(2π)·(2k_de + k_dc·f_z·π/2),
/// F_cross = N·ap/(2π)·(−2k_ne − k_nc·f_z·π/2), F_axial = N·ap/(2π)·(π·k_te + 2k_tc·f_z).
pub fn slot_mean_load(flutes: f64, ap: f64, fz: f64) -> Load {
    let [(kte, ktc), (kde, kdc), (kne, knc)] = EN_AW_2007;
    let k = flutes * ap / std::f64::consts::TAU;
    let half_pi = std::f64::consts::FRAC_PI_2;
    Load {
        feed: k * (2.0 * kde + kdc * fz * half_pi),
        cross: k * (-2.0 * kne - knc * fz * half_pi),
        axial: k * (std::f64::consts::PI * kte + 2.0 * ktc * fz),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed form against Equation 10 summed edge element by edge
    /// element over a revolution (radial r̂ = (sin φ, cos φ), cutting
    /// velocity v̂ = (cos φ, −sin φ), feed +x).
    #[test]
    fn slot_load_is_equation_10_averaged() {
        let (n, ap, fz) = (3.0, 6.0, 0.08);
        let [(kte, ktc), (kde, kdc), (kne, knc)] = EN_AW_2007;
        let steps = 200_000;
        let mut f = DVec3::ZERO;
        for i in 0..steps {
            let phi = (i as f64 + 0.5) / steps as f64 * std::f64::consts::TAU;
            if phi > std::f64::consts::PI {
                continue;
            }
            let h = fz * phi.sin();
            let d = DVec3::new(phi.sin(), phi.cos(), 0.0);
            let v = DVec3::new(phi.cos(), -phi.sin(), 0.0);
            f += (DVec3::Z * (kte + ktc * h) + d * (kde + kdc * h) + v * (kne + knc * h)) * ap;
        }
        f *= n / steps as f64;
        let l = slot_mean_load(n, ap, fz);
        assert!(
            (f - DVec3::new(l.feed, l.cross, l.axial)).length() < 1e-6,
            "{f} vs {l:?}"
        );
        // The paper's slot (a_e 12, a_p 6, f_z 0.08, three flutes): about a third of a kilonewton.
        assert!(
            (l.feed + 95.1).abs() < 0.1
                && (l.cross - 305.0).abs() < 0.5
                && (l.axial - 68.0).abs() < 0.1,
            "{l:?}"
        );
    }
}
