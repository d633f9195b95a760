//! Rigid transforms and KUKA's A, B, C orientation angles.

use millplan_geom::{DMat3, DVec3};

/// A rigid transform: `p' = r·p + t`. A frame's pose in its parent: its axes
/// are the columns of `r`, its origin `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub r: DMat3,
    pub t: DVec3,
}

impl Pose {
    pub const IDENTITY: Pose = Pose {
        r: DMat3::IDENTITY,
        t: DVec3::ZERO,
    };

    pub fn new(r: DMat3, t: DVec3) -> Pose {
        Pose { r, t }
    }

    /// `self ∘ other`: first `other`, then `self`.
    pub fn mul(&self, other: &Pose) -> Pose {
        Pose {
            r: self.r * other.r,
            t: self.r * other.t + self.t,
        }
    }

    pub fn inverse(&self) -> Pose {
        let rt = self.r.transpose();
        Pose {
            r: rt,
            t: -(rt * self.t),
        }
    }

    pub fn apply(&self, p: DVec3) -> DVec3 {
        self.r * p + self.t
    }

    /// A pose from a KUKA frame: position in mm, A, B, C in degrees.
    pub fn from_xyzabc(xyz: DVec3, abc_deg: [f64; 3]) -> Pose {
        Pose {
            r: abc_to_matrix(abc_deg),
            t: xyz,
        }
    }

    /// The KUKA frame `{X, Y, Z, A, B, C}` of this pose (mm, degrees).
    pub fn to_xyzabc(&self) -> (DVec3, [f64; 3]) {
        (self.t, matrix_to_abc(&self.r))
    }
}

/// KUKA's orientation: A about Z, B about the new Y, C about the newest X,
/// R = Rz(A)·Ry(B)·Rx(C) (process-models §5), angles in degrees.
pub fn abc_to_matrix(abc_deg: [f64; 3]) -> DMat3 {
    let [a, b, c] = abc_deg.map(f64::to_radians);
    DMat3::from_rotation_z(a) * DMat3::from_rotation_y(b) * DMat3::from_rotation_x(c)
}

/// The A, B, C angles (degrees, each in (−180, 180], B in [−90, 90]) of a
/// rotation. At B = ±90° only A − C (or A + C) is defined: C is taken as 0.
pub fn matrix_to_abc(r: &DMat3) -> [f64; 3] {
    // glam is column-major: r.col(j)[i] is the element at row i, column j.
    let m = |i: usize, j: usize| r.col(j)[i];
    let cb = m(0, 0).hypot(m(1, 0));
    let b = (-m(2, 0)).atan2(cb);
    let (a, c) = if cb > 1e-12 {
        (m(1, 0).atan2(m(0, 0)), m(2, 1).atan2(m(2, 2)))
    } else {
        ((-m(0, 1)).atan2(m(1, 1)), 0.0)
    };
    [a.to_degrees(), b.to_degrees(), c.to_degrees()]
}

/// The rotation vector (axis times angle, radians, the angle in [0, π]) of
/// a rotation matrix; the angle from the quaternion's vector part, so that
/// small rotations keep their digits.
pub fn rotation_vector(r: &DMat3) -> DVec3 {
    let q = glam::DQuat::from_mat3(r);
    let q = if q.w < 0.0 { -q } else { q };
    let v = q.xyz();
    let s = v.length();
    if s == 0.0 {
        return DVec3::ZERO;
    }
    v * (2.0 * s.atan2(q.w) / s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn near(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-9
    }

    /// T16 (process-models §6): KUKA A, B, C with R = Rz(A)·Ry(B)·Rx(C).
    /// The rotation vector of a rotation about a known axis, large and tiny.
    #[test]
    fn rotation_vector_keeps_small_angles() {
        let axis = DVec3::new(1.0, -2.0, 0.5).normalize();
        for angle in [1e-9, 1e-6, 0.3, 3.0] {
            let r = DMat3::from_axis_angle(axis, angle);
            let v = rotation_vector(&r);
            assert!(
                (v - axis * angle).length() < 1e-12 * angle.max(1.0),
                "{angle}: {v}"
            );
        }
    }

    #[test]
    fn t16_kuka_abc() {
        assert!(near(abc_to_matrix([90.0, 0.0, 0.0]) * DVec3::X, DVec3::Y));
        assert!(near(abc_to_matrix([0.0, 90.0, 0.0]) * DVec3::X, -DVec3::Z));
        assert!(near(abc_to_matrix([0.0, 0.0, 90.0]) * DVec3::Y, DVec3::Z));
        let back = matrix_to_abc(&abc_to_matrix([30.0, 20.0, 10.0]));
        for (got, want) in back.iter().zip([30.0, 20.0, 10.0]) {
            assert!((got - want).abs() < 1e-9, "{back:?}");
        }
    }

    #[test]
    fn abc_round_trips_everywhere_but_the_gimbal() {
        for a in (-170..=180).step_by(35) {
            for b in (-85..=85).step_by(17) {
                for c in (-170..=180).step_by(35) {
                    let abc = [a as f64, b as f64, c as f64];
                    let back = matrix_to_abc(&abc_to_matrix(abc));
                    for (g, w) in back.iter().zip(abc) {
                        assert!((g - w).abs() < 1e-9, "{abc:?} -> {back:?}");
                    }
                }
            }
        }
        // At B = 90° the rotation still comes back, with C = 0.
        let r = abc_to_matrix([40.0, 90.0, 15.0]);
        let back = abc_to_matrix(matrix_to_abc(&r));
        assert!((r - back).abs().to_cols_array().iter().all(|d| *d < 1e-9));
    }
}
