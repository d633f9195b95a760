//! Closed-form mean forces of a flat end mill over a revolution (spec
//! `process-models.md` T1, T2; Altintas ch. 2), in the textbook form: forces on
//! the tool, x feed, y as in §0, and F̄z with the textbook sign (the axial
//! force taken along +z), as the numeric model of this crate gives it.

use super::coeffs::Coeffs;
use std::f64::consts::PI;

/// Mean (F̄x, F̄y, F̄z) \[N\] of N flutes at axial depth a \[mm\] and feed per tooth
/// c \[mm\] between immersion angles φst and φex \[rad\] (T2).
pub fn mean_forces(co: &Coeffs, flutes: usize, a: f64, c: f64, st: f64, ex: f64) -> [f64; 3] {
    let [ktc, krc, kac] = co.kc;
    let [kte, kre, kae] = co.ke;
    let n = flutes as f64;
    let fx = |p: f64| {
        n * a * c / (8.0 * PI) * (ktc * (2.0 * p).cos() - krc * (2.0 * p - (2.0 * p).sin()))
            + n * a / (2.0 * PI) * (-kte * p.sin() + kre * p.cos())
    };
    let fy = |p: f64| {
        n * a * c / (8.0 * PI) * (ktc * (2.0 * p - (2.0 * p).sin()) + krc * (2.0 * p).cos())
            - n * a / (2.0 * PI) * (kte * p.cos() + kre * p.sin())
    };
    let fz = |p: f64| n * a / (2.0 * PI) * (-kac * c * p.cos() + kae * p);
    [fx(ex) - fx(st), fy(ex) - fy(st), fz(ex) - fz(st)]
}

/// Mean torque [N·mm] of a flat end mill of radius r between φst and φex:
/// T̄ = (N·a·R/2π)·[Ktc·c·(cos φst − cos φex) + Kte·(φex − φst)]; for a slot
/// (N·a·R/2π)·(2·Ktc·c + Kte·π) (T1d).
pub fn mean_torque(co: &Coeffs, flutes: usize, a: f64, c: f64, r: f64, st: f64, ex: f64) -> f64 {
    flutes as f64 * a * r / (2.0 * PI)
        * (co.kc[0] * c * (st.cos() - ex.cos()) + co.ke[0] * (ex - st))
}
