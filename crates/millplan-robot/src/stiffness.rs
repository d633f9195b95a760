//! The compliance Jacobian and the deflection of the tool centre point
//! (process-models §4.2, Schnoes & Zaeh Equation 2).
//!
//! Every compliant rotational degree of freedom k is a unit axis u_k through
//! a point o_k with a stiffness k_k; its Jacobian column is
//! [u_k × (p_TCP − o_k); u_k], C = J K⁻¹ Jᵀ and Δx = [Δp; Δθ] = C·w for the
//! wrench w = [F; M] at the TCP, all in the base frame. Lengths in mm,
//! forces in N, moments in N·mm, stiffness in N·mm/rad.

use crate::kin::Joints;
use crate::pose::Pose;
use crate::robot::Robot;
use millplan_geom::DVec3;

/// A torsional stiffness. Robot files and the paper give N·m/rad (Table 2's
/// "10⁷ N/rad" is one); the model works in N·mm/rad because lengths are in
/// mm (T12 pins the factor 10³).
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
pub struct Torsional {
    n_mm_per_rad: f64,
}

impl Torsional {
    pub fn from_nm_per_rad(k: f64) -> Torsional {
        Torsional {
            n_mm_per_rad: k * 1e3,
        }
    }

    pub fn n_mm_per_rad(self) -> f64 {
        self.n_mm_per_rad
    }
}

/// One compliant rotational degree of freedom.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spring {
    /// Unit axis, base frame.
    pub u: DVec3,
    /// A point on the axis, mm.
    pub o: DVec3,
    /// Torsional stiffness, N·mm/rad.
    pub k: f64,
}

impl Spring {
    /// The Jacobian column [u × (p − o); u] of this spring for the TCP at `p`.
    pub fn column(&self, p: DVec3) -> [f64; 6] {
        let v = self.u.cross(p - self.o);
        [v.x, v.y, v.z, self.u.x, self.u.y, self.u.z]
    }
}

/// Which springs each frame of the chain carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Variant {
    /// One axis per frame, its z (the joint's axis): J is 6×8 for the KR 240.
    OneAxis,
    /// Three torsional axes per frame, its x, y and z: J is 6×24.
    #[default]
    ThreeAxis,
}

/// The TCP's translation (mm) and rotation (rad) under a wrench.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deflection {
    pub dp: DVec3,
    pub dtheta: DVec3,
}

/// The 6×6 Cartesian compliance C = J K⁻¹ Jᵀ (row-major; rows and columns
/// [x, y, z, rx, ry, rz]): mm/N, 1/N and rad/(N·mm) blocks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Compliance(pub [[f64; 6]; 6]);

impl Compliance {
    /// C of `springs` for the TCP at `p`.
    pub fn of(springs: &[Spring], p: DVec3) -> Compliance {
        let mut c = [[0.0; 6]; 6];
        for s in springs {
            let j = s.column(p);
            for (r, row) in c.iter_mut().enumerate() {
                for (col, v) in row.iter_mut().enumerate() {
                    *v += j[r] * j[col] / s.k;
                }
            }
        }
        Compliance(c)
    }

    /// Δx = C·w for `force` (N) and `moment` (N·mm) at the TCP.
    pub fn apply(&self, force: DVec3, moment: DVec3) -> Deflection {
        let w = [force.x, force.y, force.z, moment.x, moment.y, moment.z];
        let x: Vec<f64> = self
            .0
            .iter()
            .map(|row| row.iter().zip(&w).map(|(a, b)| a * b).sum())
            .collect();
        Deflection {
            dp: DVec3::new(x[0], x[1], x[2]),
            dtheta: DVec3::new(x[3], x[4], x[5]),
        }
    }
}

/// Δx = J K⁻¹ Jᵀ w summed spring by spring (no 6×6 matrix: 12 products a
/// spring), for `force` (N) and `moment` (N·mm) at `p`.
pub fn deflect(springs: &[Spring], p: DVec3, force: DVec3, moment: DVec3) -> Deflection {
    let mut dp = DVec3::ZERO;
    let mut dtheta = DVec3::ZERO;
    for s in springs {
        let v = s.u.cross(p - s.o);
        let tau = (v.dot(force) + s.u.dot(moment)) / s.k;
        dp += v * tau;
        dtheta += s.u * tau;
    }
    Deflection { dp, dtheta }
}

impl Robot {
    /// The springs of the chain at `q` (into `out`) and the TCP's pose.
    pub fn springs(&self, q: &Joints, variant: Variant, out: &mut Vec<Spring>) -> Pose {
        let mut frames = Vec::with_capacity(self.frames.len());
        let tcp = self.frames(q, &mut frames);
        out.clear();
        for (f, row) in frames.iter().zip(&self.frames) {
            match variant {
                Variant::OneAxis => out.push(Spring {
                    u: f.r.col(2),
                    o: f.t,
                    k: row.k[2],
                }),
                Variant::ThreeAxis => {
                    for (a, k) in row.k.iter().enumerate() {
                        out.push(Spring {
                            u: f.r.col(a),
                            o: f.t,
                            k: *k,
                        });
                    }
                }
            }
        }
        tcp
    }

    /// [`Robot::deflect`] with the chain's frames computed into `frames`
    /// (kept between calls: no allocation per pose), the springs taken one
    /// by one as [`deflect`] sums them; also the TCP's pose.
    pub fn deflect_with(
        &self,
        q: &Joints,
        variant: Variant,
        force: DVec3,
        moment: DVec3,
        frames: &mut Vec<Pose>,
    ) -> (Pose, Deflection) {
        let tcp = self.frames(q, frames);
        let axes: &[usize] = match variant {
            Variant::OneAxis => &[2],
            Variant::ThreeAxis => &[0, 1, 2],
        };
        let mut dp = DVec3::ZERO;
        let mut dtheta = DVec3::ZERO;
        for (f, row) in frames.iter().zip(&self.frames) {
            for &a in axes {
                let u = f.r.col(a);
                let v = u.cross(tcp.t - f.t);
                let tau = (v.dot(force) + u.dot(moment)) / row.k[a];
                dp += v * tau;
                dtheta += u * tau;
            }
        }
        (tcp, Deflection { dp, dtheta })
    }

    /// The compliance Jacobian's columns at `q` (6×8 or 6×24 for the KR 240).
    pub fn jacobian(&self, q: &Joints, variant: Variant) -> Vec<[f64; 6]> {
        let mut springs = Vec::new();
        let tcp = self.springs(q, variant, &mut springs);
        springs.iter().map(|s| s.column(tcp.t)).collect()
    }

    /// The Cartesian compliance at the TCP for `q`.
    pub fn compliance(&self, q: &Joints, variant: Variant) -> Compliance {
        let mut springs = Vec::new();
        let tcp = self.springs(q, variant, &mut springs);
        Compliance::of(&springs, tcp.t)
    }

    /// The TCP's deflection at `q` under `force` (N) and `moment` (N·mm)
    /// given in the base frame at the TCP.
    pub fn deflect(&self, q: &Joints, variant: Variant, force: DVec3, moment: DVec3) -> Deflection {
        let mut springs = Vec::new();
        let tcp = self.springs(q, variant, &mut springs);
        deflect(&springs, tcp.t, force, moment)
    }
}
