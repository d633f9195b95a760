//! An independent zero-order stability solver, written from spec
//! `process-models.md` §3 without the library's lobe numbers, phases or
//! branch tracking: at a spindle speed it scans chatter frequencies on a
//! fine uniform grid and solves the characteristic equation for a real
//! depth directly.
//!
//! With Λ = −(N·Ktc/4π)·a·(1 − e^{−iωT}) (the complex form whose real
//! solutions are §3's a_lim = −2πΛ_R(1 + κ²)/(N·Ktc) with ωT = ε + 2kπ),
//! det(I + Λ·A·G) = 1 + Λ·a1 + Λ²·a0 = 1 + a·B + a²·D, a quadratic in the
//! depth a with complex coefficients. Its two (complex) roots, ordered by
//! their real parts, are followed over ω; wherever one's imaginary part
//! changes sign, bisection finds the frequency where it is real, and a real
//! positive root there is a stability limit at that speed. (The roots have
//! to be followed one by one: a negative and a positive root often become
//! real within a tenth of a hertz, so any product of the two changes sign
//! twice within one step.)

use std::f64::consts::PI;

type Cx = (f64, f64);

fn mul(a: Cx, b: Cx) -> Cx {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}

fn add(a: Cx, b: Cx) -> Cx {
    (a.0 + b.0, a.1 + b.1)
}

fn scale(a: Cx, s: f64) -> Cx {
    (a.0 * s, a.1 * s)
}

fn inv(a: Cx) -> Cx {
    let d = a.0 * a.0 + a.1 * a.1;
    (a.0 / d, -a.1 / d)
}

/// One mode: natural frequency [Hz], stiffness [N/m], damping ratio.
#[derive(Clone, Copy, Debug)]
pub struct Sdof {
    pub fn_hz: f64,
    pub k: f64,
    pub zeta: f64,
}

impl Sdof {
    fn g(&self, w: f64) -> Cx {
        let r = w / (2.0 * PI * self.fn_hz);
        scale(inv((1.0 - r * r, 2.0 * self.zeta * r)), 1.0 / self.k)
    }
}

/// The problem, in SI units as §3 states it.
#[derive(Clone, Copy, Debug)]
pub struct Brute {
    pub x: Option<Sdof>,
    pub y: Option<Sdof>,
    pub flutes: f64,
    /// Ktc [N/m²].
    pub kt: f64,
    pub kr: f64,
    pub st: f64,
    pub ex: f64,
}

impl Brute {
    /// (a_xx, a_xy, a_yx, a_yy) of §3, [·] at φex minus at φst.
    fn factors(&self) -> [f64; 4] {
        let kr = self.kr;
        let at = |p: f64| {
            [
                0.5 * ((2.0 * p).cos() - 2.0 * kr * p + kr * (2.0 * p).sin()),
                0.5 * (-(2.0 * p).sin() - 2.0 * p + kr * (2.0 * p).cos()),
                0.5 * (-(2.0 * p).sin() + 2.0 * p + kr * (2.0 * p).cos()),
                0.5 * (-(2.0 * p).cos() - 2.0 * kr * p - kr * (2.0 * p).sin()),
            ]
        };
        let (e, s) = (at(self.ex), at(self.st));
        [e[0] - s[0], e[1] - s[1], e[2] - s[2], e[3] - s[3]]
    }

    /// The roots a [m] of 1 + a·B + a²·D at ω for tooth period t, by
    /// ascending real part (one root where only one direction is flexible).
    fn roots(&self, f: &[f64; 4], w: f64, t: f64) -> Vec<Cx> {
        let gx = self.x.map_or((0.0, 0.0), |m| m.g(w));
        let gy = self.y.map_or((0.0, 0.0), |m| m.g(w));
        let a1 = add(scale(gx, f[0]), scale(gy, f[3]));
        let a0 = scale(mul(gx, gy), f[0] * f[3] - f[1] * f[2]);
        let c = self.flutes * self.kt / (4.0 * PI);
        let e = (1.0 - (w * t).cos(), (w * t).sin()); // 1 − e^{−iωT}
        let b = scale(mul(e, a1), -c);
        let d = scale(mul(mul(e, e), a0), c * c);
        if d.0 == 0.0 && d.1 == 0.0 {
            return vec![scale(inv(b), -1.0)];
        }
        let disc = csqrt(add(mul(b, b), scale(d, -4.0)));
        let den = inv(scale(d, 2.0));
        let mut r = vec![
            mul(add(scale(b, -1.0), disc), den),
            mul(add(scale(b, -1.0), scale(disc, -1.0)), den),
        ];
        r.sort_by(|p, q| p.0.total_cmp(&q.0));
        r
    }

    /// The smallest limiting depth [mm] at n [1/min] over chatter
    /// frequencies (0, f_top] in steps of `df` [Hz]; infinite if none.
    pub fn a_lim(&self, n: f64, f_top: f64, df: f64) -> f64 {
        let f = self.factors();
        let t = 60.0 / (self.flutes * n);
        let steps = (f_top / df).ceil() as usize;
        let mut best = f64::INFINITY;
        let mut prev = self.roots(&f, 2.0 * PI * df, t);
        for i in 2..=steps {
            let w = 2.0 * PI * df * i as f64;
            let cur = self.roots(&f, w, t);
            for (k, (p, q)) in prev.iter().zip(&cur).enumerate() {
                if p.1 * q.1 <= 0.0 && p.1 != q.1 {
                    if let Some(a) = self.bisect(&f, t, w - 2.0 * PI * df, w, k) {
                        best = best.min(a);
                    }
                }
            }
            prev = cur;
        }
        best * 1000.0
    }

    /// Where the imaginary part of root k changes sign between ω = lo and
    /// hi: its depth if the root is real there (not a jump where two roots
    /// swap their order) and positive.
    fn bisect(&self, f: &[f64; 4], t: f64, mut lo: f64, mut hi: f64, k: usize) -> Option<f64> {
        let im = |w: f64| self.roots(f, w, t)[k].1;
        let lo_neg = im(lo) < 0.0;
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if (im(mid) < 0.0) == lo_neg {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let a = self.roots(f, 0.5 * (lo + hi), t)[k];
        (a.0 > 0.0 && a.1.abs() <= 1e-6 * a.0).then_some(a.0)
    }
}

fn csqrt(a: Cx) -> Cx {
    let r = a.0.hypot(a.1);
    let re = ((r + a.0) / 2.0).max(0.0).sqrt();
    let im = ((r - a.0) / 2.0).max(0.0).sqrt();
    (re, if a.1 < 0.0 { -im } else { im })
}
