//! Forward and inverse kinematics of a robot file's chain.
//!
//! The inverse is analytic for the arms the robot file describes: A1 about
//! the base's vertical through its origin, A2 and A3 parallel and
//! horizontal, the shoulder, elbow and wrist centre in one plane with A1,
//! and a spherical wrist (A4, A5, A6 meeting in one point) at the end of the
//! chain. `IkGeometry::derive` checks all of it when a file is read.
//! KUKA's Status and Turn name the solution ([`Config`]).

use crate::pose::Pose;
use crate::robot::Robot;
use millplan_geom::{DMat3, DVec3};
use std::f64::consts::{PI, TAU};

/// The six KUKA axis angles A1..A6, radians.
pub type Joints = [f64; 6];

/// KUKA's Status and Turn of a configuration.
///
/// Status bit 0: the wrist centre behind A1 (overhead area); bit 1: A3 at or
/// beyond the angle where the arm is stretched; bit 2: A5 ≤ 0. Turn bit i:
/// A(i+1) < 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Config {
    pub status: u8,
    pub turn: u8,
}

/// Why a pose has no solution.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IkError {
    #[error("out of reach")]
    Unreachable,
    #[error("no solution with Status {status} Turn {turn} within the joint limits")]
    NoConfig { status: u8, turn: u8 },
    #[error("no solution within the joint limits")]
    Limits,
}

/// The arm's geometry in its plane at A = 0, derived from the chain.
#[derive(Clone, Debug, Default)]
pub(crate) struct IkGeometry {
    /// Shoulder (A2 axis) in the arm plane (u horizontal, w vertical), mm.
    shoulder: [f64; 2],
    l2: f64,
    l3: f64,
    /// Direction of shoulder → elbow at A = 0.
    angle2: f64,
    /// Angle from shoulder → elbow to elbow → wrist centre at A = 0.
    gamma0: f64,
    /// The arm-plane rotation per radian of A1, A2, A3.
    rate: [f64; 3],
    /// The wrist centre in the last frame.
    wc_in_flange: DVec3,
    /// sin α of the A5 row: the middle wrist rotation is Ry(−s·θ5).
    s5: f64,
}

impl Robot {
    /// Every frame of the chain (in the base) for `q`, plus the TCP.
    pub fn frames(&self, q: &Joints, out: &mut Vec<Pose>) -> Pose {
        self.frames_with(q, |_| DMat3::IDENTITY, out)
    }

    /// As [`Robot::frames`], with `extra(i)` turning frame i in itself after
    /// its θ (the tests bend the bushings with it).
    pub fn frames_with(
        &self,
        q: &Joints,
        extra: impl Fn(usize) -> DMat3,
        out: &mut Vec<Pose>,
    ) -> Pose {
        out.clear();
        let mut t = Pose::IDENTITY;
        for (i, f) in self.frames.iter().enumerate() {
            t = t.mul(&f.fixed);
            t.r = t.r * DMat3::from_rotation_z(f.theta(q)) * extra(i);
            out.push(t);
        }
        t.mul(&self.tool)
    }

    /// The pose of frame `n − 1` for `q` (the identity for `n = 0`), as
    /// [`Robot::frames`] gives it, without the frames after it.
    pub(crate) fn pose_before(&self, q: &Joints, n: usize) -> Pose {
        let mut t = Pose::IDENTITY;
        for f in &self.frames[..n] {
            t = t.mul(&f.fixed);
            t.r *= DMat3::from_rotation_z(f.theta(q));
        }
        t
    }

    /// The TCP's pose in the base for `q`.
    pub fn fk(&self, q: &Joints) -> Pose {
        let mut t = Pose::IDENTITY;
        for f in &self.frames {
            t = t.mul(&f.fixed);
            t.r *= DMat3::from_rotation_z(f.theta(q));
        }
        t.mul(&self.tool)
    }

    /// Status and Turn of `q`.
    pub fn config(&self, q: &Joints) -> Config {
        let g = &self.ik;
        let mut frames = Vec::with_capacity(self.frames.len());
        self.frames(q, &mut frames);
        let last = frames.last().copied().unwrap_or(Pose::IDENTITY);
        let wc = last.apply(g.wc_in_flange);
        let psi = g.rate[0] * q[0];
        let u = wc.x * psi.cos() + wc.y * psi.sin();
        // Stretched: elbow angle γ = 0, i.e. Δφ3 = −γ0.
        let stretched = -g.gamma0 / g.rate[2];
        let mut status = 0;
        if u < 0.0 {
            status |= 1;
        }
        if q[2] >= stretched {
            status |= 2;
        }
        if q[4] <= 0.0 {
            status |= 4;
        }
        let turn = (0..6).fold(0, |t, i| if q[i] < 0.0 { t | (1 << i) } else { t });
        Config { status, turn }
    }

    /// Whether `q` is within the limits less the margin, and |A5| clear of
    /// the wrist singularity.
    pub fn feasible(&self, q: &Joints) -> bool {
        let m = self.margin;
        q.iter()
            .zip(&self.limits)
            .all(|(a, [lo, hi])| *a >= lo + m && *a <= hi - m)
            && q[4].abs() >= self.wrist_margin
    }

    /// Every solution for the TCP pose `tcp` (base frame) within the joint
    /// limits (the margins not applied), each A1, A4, A6 in every winding
    /// the limits allow. `hint4` is A4 where the wrist is singular.
    pub fn ik_all(&self, tcp: &Pose, hint4: f64) -> Vec<Joints> {
        let mut out = Vec::new();
        for (q, _) in self.ik_base(tcp, hint4) {
            self.windings(q, &mut out);
        }
        out
    }

    /// The solution with Status and Turn `cfg`.
    pub fn ik(&self, tcp: &Pose, cfg: Config) -> Result<Joints, IkError> {
        let all = self.ik_all(tcp, 0.0);
        if all.is_empty() {
            return Err(IkError::Unreachable);
        }
        all.into_iter()
            .find(|q| self.config(q) == cfg)
            .ok_or(IkError::NoConfig {
                status: cfg.status,
                turn: cfg.turn,
            })
    }

    /// The solution closest to `prev` (largest single axis step) with the
    /// same Status, for following a path.
    pub fn ik_near(&self, tcp: &Pose, prev: &Joints) -> Result<Joints, IkError> {
        let status = self.config(prev).status;
        let all = self.ik_all(tcp, prev[3]);
        if all.is_empty() {
            return Err(IkError::Unreachable);
        }
        let step = |q: &Joints| {
            q.iter()
                .zip(prev)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        };
        all.into_iter()
            .filter(|q| self.config(q).status == status)
            .min_by(|a, b| step(a).total_cmp(&step(b)))
            .ok_or(IkError::Limits)
    }

    fn windings(&self, q: Joints, out: &mut Vec<Joints>) {
        let options = |i: usize| -> Vec<f64> {
            [-TAU, 0.0, TAU]
                .iter()
                .map(|k| q[i] + k)
                .filter(|a| *a >= self.limits[i][0] && *a <= self.limits[i][1])
                .collect()
        };
        let (o1, o4, o6) = (options(0), options(3), options(5));
        let in_limits = (1..6)
            .filter(|i| *i != 3 && *i != 5)
            .all(|i| q[i] >= self.limits[i][0] && q[i] <= self.limits[i][1]);
        if !in_limits {
            return;
        }
        for a1 in &o1 {
            for a4 in &o4 {
                for a6 in &o6 {
                    out.push([*a1, q[1], q[2], *a4, q[4], *a6]);
                }
            }
        }
    }

    /// The solution with Status `status` (windings aside: A1, A4, A6 in
    /// (−π, π]), when it exists and some winding of it is [`Robot::feasible`].
    /// What a deflection needs: the winding does not change the pose.
    pub fn ik_status(&self, tcp: &Pose, status: u8) -> Option<Joints> {
        self.ik_base_for(tcp, 0.0, Some(status))
            .into_iter()
            .map(|(q, _)| q)
            .find(|q| self.feasible_winding(q).is_some())
    }

    /// `q` with A1, A4, A6 turned by whole turns into the limits less the
    /// margin, if it can be, and [`Robot::feasible`].
    pub fn feasible_winding(&self, q: &Joints) -> Option<Joints> {
        let mut out = *q;
        let m = self.margin;
        for i in [0, 3, 5] {
            let [lo, hi] = self.limits[i];
            out[i] = [0.0, TAU, -TAU]
                .iter()
                .map(|k| q[i] + k)
                .find(|a| *a >= lo + m && *a <= hi - m)?;
        }
        self.feasible(&out).then_some(out)
    }

    /// Up to eight solutions, angles wrapped into (−π, π], each with whether
    /// it is in the overhead area.
    fn ik_base(&self, tcp: &Pose, hint4: f64) -> Vec<(Joints, bool)> {
        self.ik_base_for(tcp, hint4, None)
    }

    /// As [`Robot::ik_base`], only the branches of Status `want` when given
    /// (the arm and wrist branches are chosen before they are solved).
    fn ik_base_for(&self, tcp: &Pose, hint4: f64, want: Option<u8>) -> Vec<(Joints, bool)> {
        let g = &self.ik;
        let stretched = -g.gamma0 / g.rate[2];
        let bit = |b: u8| want.map(|s| s & b != 0);
        let flange = tcp.mul(&self.tool.inverse());
        let wc = flange.apply(g.wc_in_flange);
        let mut out = Vec::with_capacity(8);
        for overhead in [false, true] {
            if bit(1).is_some_and(|o| o != overhead) {
                continue;
            }
            let rho = wc.x.hypot(wc.y) * if overhead { -1.0 } else { 1.0 };
            let psi = wc.y.atan2(wc.x) + if overhead { PI } else { 0.0 };
            let du = rho - g.shoulder[0];
            let dw = wc.z - g.shoulder[1];
            let c = (du * du + dw * dw - g.l2 * g.l2 - g.l3 * g.l3) / (2.0 * g.l2 * g.l3);
            if !(c.abs() <= 1.0 + 1e-12) {
                continue;
            }
            for elbow in [1.0, -1.0] {
                let gamma = elbow * c.clamp(-1.0, 1.0).acos();
                let a2 = dw.atan2(du) - (g.l3 * gamma.sin()).atan2(g.l2 + g.l3 * gamma.cos());
                let q1 = wrap(psi / g.rate[0]);
                let q2 = wrap((a2 - g.angle2) / g.rate[1]);
                let q3 = wrap((gamma - g.gamma0) / g.rate[2]);
                if bit(2).is_some_and(|b| b != (q3 >= stretched)) {
                    continue;
                }
                for flip in [false, true] {
                    if let Some(q) = self.wrist([q1, q2, q3, 0.0, 0.0, 0.0], &flange, flip, hint4) {
                        if bit(4).is_some_and(|b| b != (q[4] <= 0.0)) {
                            continue;
                        }
                        out.push((q, overhead));
                        if want.is_some() {
                            break;
                        }
                    }
                }
            }
        }
        out
    }

    /// A4, A5, A6 that turn the last frame onto `flange`, the arm at `q`.
    fn wrist(&self, mut q: Joints, flange: &Pose, flip: bool, hint4: f64) -> Option<Joints> {
        let rows = self.axis_rows();
        let before = self.pose_before(&q, rows[3]);
        let r_pre = before.r * self.frames[rows[3]].fixed.r;
        let m = r_pre.transpose() * flange.r;
        let e = |i: usize, j: usize| m.col(j)[i];
        let b = e(0, 2).hypot(e(1, 2)).atan2(e(2, 2));
        let (a, b, c) = if b.sin().abs() < 1e-9 {
            // Singular: only A4 + A6 (or A4 − A6) is defined; keep A4 at the hint.
            let f4 = &self.frames[rows[3]];
            let a = f4.theta0 + f4.sign * (hint4 + f4.offset);
            let ang = e(1, 0).atan2(e(0, 0));
            if e(2, 2) > 0.0 {
                (a, 0.0, ang - a) // M = Rz(a + c)
            } else {
                (a, PI, a + PI - ang) // M = Rz(a)·Ry(π)·Rz(c): angle a − c + π
            }
        } else if flip {
            (
                e(1, 2).atan2(e(0, 2)) + PI,
                -b,
                e(2, 1).atan2(-e(2, 0)) + PI,
            )
        } else {
            (e(1, 2).atan2(e(0, 2)), b, e(2, 1).atan2(-e(2, 0)))
        };
        if b.sin().abs() < 1e-9 && flip {
            return None;
        }
        let theta = [a, -b / self.ik.s5, c];
        for (k, th) in theta.iter().enumerate() {
            let f = &self.frames[rows[3 + k]];
            q[3 + k] = wrap((th - f.theta0) / f.sign - f.offset);
        }
        Some(q)
    }
}

/// Into (−π, π].
pub fn wrap(a: f64) -> f64 {
    let w = a.rem_euclid(TAU);
    if w > PI {
        w - TAU
    } else {
        w
    }
}

impl IkGeometry {
    /// The planar arm and the wrist of `robot`, or why the analytic inverse
    /// cannot solve its chain.
    pub(crate) fn derive(robot: &Robot) -> Result<IkGeometry, String> {
        let rows = chain_rows(robot)?;
        let mut frames = Vec::new();
        robot.frames(&[0.0; 6], &mut frames);
        let axis = |k: usize| frames[rows[k]].r.col(2);
        let origin = |k: usize| frames[rows[k]].t;
        let a1 = axis(0);
        if (a1.z.abs() - 1.0).abs() > 1e-9 || origin(0).truncate().length() > 1e-6 {
            return Err("A1 must turn about the base's vertical axis through its origin".into());
        }
        for k in [1, 2] {
            if (axis(k).y.abs() - 1.0).abs() > 1e-9 {
                return Err(format!(
                    "A{} must be horizontal, along the base's y at A = 0",
                    k + 1
                ));
            }
        }
        let wc = wrist_centre(&frames, &rows)?;
        let (s, e) = (origin(1), origin(2));
        for (what, p) in [("shoulder", s), ("elbow", e), ("wrist centre", wc)] {
            if p.y.abs() > 1e-6 {
                return Err(format!(
                    "the {what} must lie in the base's x-z plane at A = 0"
                ));
            }
        }
        let f = |k: usize| &robot.frames[rows[k]];
        // A turn by Δθ about the axis d·y turns the arm plane by −d·Δθ (u → w).
        let rate = [
            a1.z * f(0).sign,
            -axis(1).y * f(1).sign,
            -axis(2).y * f(2).sign,
        ];
        let (se, ew) = (e - s, wc - e);
        let angle2 = se.z.atan2(se.x);
        let gamma0 = wrap(ew.z.atan2(ew.x) - angle2);
        let last = frames.last().copied().unwrap_or(Pose::IDENTITY);
        Ok(IkGeometry {
            shoulder: [s.x, s.z],
            l2: (se.x * se.x + se.z * se.z).sqrt(),
            l3: (ew.x * ew.x + ew.z * ew.z).sqrt(),
            angle2,
            gamma0,
            rate,
            wc_in_flange: last.inverse().apply(wc),
            s5: -robot.frames[rows[4]].fixed.r.col(2).y,
        })
    }
}

/// The rows of A1..A6, checked: each axis once, in order, A4..A6 the last
/// three rows, the wrist's α alternating by a right angle.
fn chain_rows(robot: &Robot) -> Result<[usize; 6], String> {
    let axes: Vec<u8> = robot
        .frames
        .iter()
        .map(|f| f.axis)
        .filter(|a| *a > 0)
        .collect();
    if axes != [1, 2, 3, 4, 5, 6] {
        return Err(
            "the chain must name axes 1 to 6 once each, in order (0 for virtual joints)".into(),
        );
    }
    let rows = robot.axis_rows();
    let n = robot.frames.len();
    if rows[3] + 3 != n || rows[4] + 2 != n {
        return Err("A4, A5 and A6 must be the last three rows (a spherical wrist)".into());
    }
    let s5 = robot.frames[rows[4]].fixed.r.col(2).y;
    let s6 = robot.frames[rows[5]].fixed.r.col(2).y;
    if (s5.abs() - 1.0).abs() > 1e-9 || (s5 + s6).abs() > 1e-9 {
        return Err("the wrist's alpha must be +90 then -90 degrees, or -90 then +90".into());
    }
    Ok(rows)
}

/// The point where A4, A5 and A6 meet.
fn wrist_centre(frames: &[Pose], rows: &[usize; 6]) -> Result<DVec3, String> {
    let (o4, z4) = (frames[rows[3]].t, frames[rows[3]].r.col(2));
    let (o5, z5) = (frames[rows[4]].t, frames[rows[4]].r.col(2));
    let (o6, z6) = (frames[rows[5]].t, frames[rows[5]].r.col(2));
    // Closest point of A4's line to A5's.
    let w = o4 - o5;
    let (b, d, e) = (z4.dot(z5), z4.dot(w), z5.dot(w));
    let den = 1.0 - b * b;
    if den < 1e-12 {
        return Err("A4 and A5 must not be parallel".into());
    }
    let t4 = (b * e - d) / den;
    let p = o4 + z4 * t4;
    let miss = |o: DVec3, z: DVec3| (p - o).cross(z).length();
    if miss(o5, z5) > 1e-6 || miss(o6, z6) > 1e-6 {
        return Err("A4, A5 and A6 must meet in one point (a spherical wrist)".into());
    }
    Ok(p)
}
