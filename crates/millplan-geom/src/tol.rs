//! The workspace-wide tolerances and an `assert_near!` macro for tests.

/// Two positions closer than this (mm) are the same point.
pub const LINEAR: f64 = 1e-6;
/// A vector whose length differs from 1 by more than this is not a unit vector.
pub const UNIT: f64 = 1e-6;
/// Angles closer than this (radians) are equal.
pub const ANGULAR: f64 = 1e-9;
/// Millimetres per inch.
pub const MM_PER_INCH: f64 = 25.4;

/// `true` when `a` and `b` differ by at most `tol`.
#[inline]
pub fn near(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

/// Asserts that two `f64` (or two `DVec3`) values agree within a tolerance.
#[macro_export]
macro_rules! assert_near {
    ($a:expr, $b:expr, $tol:expr) => {{
        let (a, b, tol) = ($a, $b, $tol);
        let d = $crate::tol::Distance::distance(&a, &b);
        assert!(
            d <= tol,
            "assert_near failed: {:?} vs {:?} (|diff| = {:e} > {:e})",
            a,
            b,
            d,
            tol
        );
    }};
}

/// Distance between two values of the same kind, used by [`assert_near!`].
pub trait Distance {
    fn distance(&self, other: &Self) -> f64;
}

impl Distance for f64 {
    fn distance(&self, other: &Self) -> f64 {
        (self - other).abs()
    }
}

impl Distance for glam::DVec3 {
    fn distance(&self, other: &Self) -> f64 {
        (*self - *other).length()
    }
}
