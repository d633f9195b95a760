//! Rigid frames: where a program's coordinates live relative to the part.

use glam::{DMat3, DVec3};

/// A right- or left-handed orthonormal frame given in its parent's coordinates:
/// a point `p` written in this frame is `origin + rot * p` in the parent.
///
/// CAM output frames (NX `MSYS`, SOLIDWORKS `CSYS`) are kept as declared, including
/// the mirrored-looking ones NX writes; [`Frame::is_right_handed`] tells them apart.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub origin: DVec3,
    /// Columns are the frame's X, Y and Z axes in parent coordinates.
    pub rot: DMat3,
}

impl Frame {
    pub const IDENTITY: Frame = Frame {
        origin: DVec3::ZERO,
        rot: DMat3::IDENTITY,
    };

    /// Frame from origin and X and Y axes (NX `MSYS` layout); Z = X × Y.
    /// Returns `None` when the axes are not (nearly) orthonormal.
    pub fn from_origin_xy(origin: DVec3, x: DVec3, y: DVec3) -> Option<Frame> {
        let (xl, yl) = (x.length(), y.length());
        if !(xl > 0.5 && yl > 0.5) {
            return None;
        }
        let x = x / xl;
        let y = y / yl;
        if x.dot(y).abs() > 1e-4 {
            return None;
        }
        let z = x.cross(y);
        Some(Frame {
            origin,
            rot: DMat3::from_cols(x, y, z),
        })
    }

    /// Frame from a 3×4 row-major matrix `[R | t]` (SOLIDWORKS `CSYS`, 12 values).
    pub fn from_rows_3x4(m: &[f64; 12]) -> Option<Frame> {
        let rot = DMat3::from_cols(
            DVec3::new(m[0], m[4], m[8]),
            DVec3::new(m[1], m[5], m[9]),
            DVec3::new(m[2], m[6], m[10]),
        );
        let origin = DVec3::new(m[3], m[7], m[11]);
        let f = Frame { origin, rot };
        f.is_orthonormal(1e-4).then_some(f)
    }

    pub fn is_identity(&self) -> bool {
        self.origin.length() < crate::tol::LINEAR
            && (self.rot - DMat3::IDENTITY)
                .to_cols_array()
                .iter()
                .all(|v| v.abs() < 1e-9)
    }

    pub fn is_orthonormal(&self, tol: f64) -> bool {
        let p = self.rot.transpose() * self.rot;
        (p - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .all(|v| v.abs() <= tol)
    }

    pub fn is_right_handed(&self) -> bool {
        self.rot.determinant() > 0.0
    }

    /// A point given in this frame, in parent coordinates.
    #[inline]
    pub fn to_parent(&self, p: DVec3) -> DVec3 {
        self.origin + self.rot * p
    }

    /// A direction given in this frame, in parent coordinates.
    #[inline]
    pub fn dir_to_parent(&self, v: DVec3) -> DVec3 {
        self.rot * v
    }

    /// A parent point, in this frame's coordinates.
    #[inline]
    pub fn from_parent(&self, p: DVec3) -> DVec3 {
        self.rot.transpose() * (p - self.origin)
    }
}

impl Default for Frame {
    fn default() -> Self {
        Frame::IDENTITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nx_mirrored_msys_has_minus_z() {
        // MSYS/.., 0,1,0, 1,0,0 from nx-clsf-5axis-varcontour: Z = X × Y = (0,0,-1).
        let f = Frame::from_origin_xy(DVec3::ZERO, DVec3::Y, DVec3::X).expect("frame");
        assert_eq!(f.rot.z_axis, DVec3::new(0.0, 0.0, -1.0));
        assert!(!f.is_right_handed() || f.rot.determinant() > 0.0);
        let p = DVec3::new(1.0, 2.0, 3.0);
        crate::assert_near!(f.from_parent(f.to_parent(p)), p, 1e-12);
    }

    #[test]
    fn csys_rows() {
        let f = Frame::from_rows_3x4(&[0., 0., 1., 5., 0., 1., 0., 6., -1., 0., 0., 7.])
            .expect("frame");
        crate::assert_near!(f.to_parent(DVec3::X), DVec3::new(5.0, 6.0, 6.0), 1e-12);
        assert!(Frame::from_rows_3x4(&[2., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0.]).is_none());
    }
}
