//! The workspace-wide tolerances and an `assert_near!` macro for tests.

/// Two positions closer than this (mm) are the same point.
pub const LINEAR: f64 = 1e-6;
/// A vector whose length differs from 1 by more than this is not a unit vector.
pub const UNIT: f64 = 1e-6;
/// Angles closer than this (radians) are equal.
pub const ANGULAR: f64 = 1e-9;
/// Millimetres per inch.
pub const MM_PER_INCH: f64 = 25.4;
/// A corner radius within this share of the diameter of half the diameter
/// is a ball end's (the cutter records of a program written in inches to six
/// decimals, `CUTTER/0.393701,0.19685`, read back as a bull-nose by 3·10⁻⁶).
pub const BALL: f64 = 1e-5;

/// Whether corner radius `r` makes a cutter of diameter `d` a ball end
/// (within [`BALL`] of `d`/2).
pub fn is_ball(d: f64, r: f64) -> bool {
    (2.0 * r - d).abs() <= 2.0 * BALL * d.max(1.0)
}

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
