//! Stability lobes of milling by the zero-order approximation (Altintas &
//! Budak 1995; spec `process-models.md` §3). SI units inside, as in the
//! source: stiffness N/m, cutting coefficient N/m², FRF m/N; the depth limit is
//! returned in mm.
//!
//! A lobe k is the curve (n_k(ω), a_lim(ω)) over chatter frequencies ω; the
//! stability limit at a spindle speed is the smallest a_lim over *every*
//! lobe and eigenvalue branch that reaches that speed. [`Setup::stability`]
//! computes it that way (see `envelope`): no lobe count is chosen, so none
//! can be left out.

use std::f64::consts::PI;

mod envelope;
pub use envelope::{Chatter, EnvPoint, LobePoint, LobesError, Stability, CEILING_MM, MAX_LOBES};

#[derive(Clone, Copy, Debug, PartialEq)]
struct C {
    re: f64,
    im: f64,
}

impl C {
    fn new(re: f64, im: f64) -> C {
        C { re, im }
    }
    fn add(self, o: C) -> C {
        C::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: C) -> C {
        C::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: C) -> C {
        C::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn scale(self, s: f64) -> C {
        C::new(self.re * s, self.im * s)
    }
    fn div(self, o: C) -> C {
        let d = o.re * o.re + o.im * o.im;
        C::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
    fn sqrt(self) -> C {
        let r = self.re.hypot(self.im);
        let re = ((r + self.re) / 2.0).max(0.0).sqrt();
        let im = ((r - self.re) / 2.0).max(0.0).sqrt();
        C::new(re, if self.im < 0.0 { -im } else { im })
    }
    fn norm(self) -> f64 {
        self.re.hypot(self.im)
    }
}

/// One single-degree-of-freedom mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mode {
    /// Natural frequency \[Hz\].
    pub fn_hz: f64,
    /// Stiffness k = m·ωn² [N/m].
    pub k: f64,
    /// Damping ratio ζ.
    pub zeta: f64,
}

impl Mode {
    /// G(ω) = 1/(k(1 − r² + 2iζr)), r = ω/ωn [m/N], as (Re, Im).
    pub fn frf(&self, w: f64) -> (f64, f64) {
        let c = self.g(w);
        (c.re, c.im)
    }

    fn g(&self, w: f64) -> C {
        let r = w / (2.0 * PI * self.fn_hz);
        C::new(1.0, 0.0).div(C::new(self.k * (1.0 - r * r), self.k * 2.0 * self.zeta * r))
    }

    /// Plausible modes only: 1 Hz to 100 kHz, 1 to 10¹⁵ N/m, damping ratio
    /// from 10⁻⁴ to below 1 (the ranges keep every FRF value finite and the
    /// frequency table of the envelope small).
    pub fn validate(&self) -> Result<(), String> {
        if !(self.fn_hz >= 1.0 && self.fn_hz <= 1e5) {
            return Err(format!(
                "natural frequency {} Hz: must be from 1 Hz to 100 kHz",
                num(self.fn_hz)
            ));
        }
        if !(self.k >= 1.0 && self.k <= 1e15) {
            return Err(format!(
                "stiffness {} N/m: must be from 1 to 1e15 N/m",
                num(self.k)
            ));
        }
        if !(self.zeta >= 1e-4 && self.zeta < 1.0) {
            return Err(format!(
                "damping ratio {}: must be from 0.0001 to below 1",
                num(self.zeta)
            ));
        }
        Ok(())
    }
}

/// A number as written in a message: 1e-18, not eighteen zeros.
fn num(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-4 || v.abs() >= 1e9) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Directional factors (a_xx, a_xy, a_yx, a_yy) between immersion angles
/// φst and φex \[rad\] with Kr = Krc/Ktc (§3).
pub fn directional(kr: f64, st: f64, ex: f64) -> [f64; 4] {
    let f = |p: f64| {
        let (s2, c2) = (2.0 * p).sin_cos();
        [
            0.5 * (c2 - 2.0 * kr * p + kr * s2),
            0.5 * (-s2 - 2.0 * p + kr * c2),
            0.5 * (-s2 + 2.0 * p + kr * c2),
            0.5 * (-c2 - 2.0 * kr * p - kr * s2),
        ]
    };
    let (a, b) = (f(ex), f(st));
    [a[0] - b[0], a[1] - b[1], a[2] - b[2], a[3] - b[3]]
}

/// Immersion angles \[rad\] of a cut of radial depth ae with a tool of
/// diameter d: down-milling exits at π, up-milling enters at 0.
pub fn immersion(ae: f64, d: f64, down: bool) -> (f64, f64) {
    let a = (1.0 - 2.0 * (ae / d).clamp(0.0, 1.0))
        .clamp(-1.0, 1.0)
        .acos();
    if down {
        (PI - a, PI)
    } else {
        (0.0, a)
    }
}

/// The stability problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setup {
    /// Modes in x (feed) and y; a missing direction is rigid.
    pub x: Option<Mode>,
    pub y: Option<Mode>,
    pub flutes: usize,
    /// Ktc [N/m²] and Kr = Krc/Ktc.
    pub kt: f64,
    pub kr: f64,
    /// Immersion \[rad\].
    pub st: f64,
    pub ex: f64,
}

impl Setup {
    pub fn validate(&self) -> Result<(), String> {
        if self.x.is_none() && self.y.is_none() {
            return Err("at least one flexible direction is needed".into());
        }
        for m in self.x.iter().chain(self.y.iter()) {
            m.validate()?;
        }
        if self.flutes == 0 || self.flutes > 64 {
            return Err("the flute count must be from 1 to 64".into());
        }
        if !(self.kt >= 1e6 && self.kt <= 1e11 && self.kr >= 0.0 && self.kr <= 10.0) {
            return Err(
                "Kt must be from 1e6 to 1e11 N/m² (1 to 1e5 N/mm²) and Kr/Kt from 0 to 10".into(),
            );
        }
        if !(self.st >= 0.0 && self.ex <= PI && self.ex > self.st) {
            return Err("the immersion must run forward within 0…π".into());
        }
        Ok(())
    }

    /// The eigenvalue roots Λ at chatter frequency ω [rad/s].
    fn eigen(&self, w: f64) -> Vec<C> {
        let [axx, axy, ayx, ayy] = directional(self.kr, self.st, self.ex);
        let zero = C::new(0.0, 0.0);
        let gx = self.x.map_or(zero, |m| m.g(w));
        let gy = self.y.map_or(zero, |m| m.g(w));
        let a0 = gx.mul(gy).scale(axx * ayy - axy * ayx);
        let a1 = gx.scale(axx).add(gy.scale(ayy));
        if a0.norm() <= 1e-12 * a1.norm() * a1.norm() {
            if a1.norm() == 0.0 {
                return Vec::new();
            }
            return vec![C::new(-1.0, 0.0).div(a1)];
        }
        let d = a1.mul(a1).sub(a0.scale(4.0)).sqrt();
        let den = a0.scale(2.0);
        vec![
            a1.add(d).scale(-1.0).div(den),
            a1.sub(d).scale(-1.0).div(den),
        ]
    }

    /// a_lim \[mm\] and phase ε \[rad\] of each root at ω (None where a_lim ≤ 0).
    pub fn limits_at(&self, w: f64) -> Vec<Option<(f64, f64)>> {
        self.eigen(w).into_iter().map(|l| self.limit(l)).collect()
    }

    /// a_lim \[mm\] and ε of one root Λ (§3): a_lim = −2πΛ_R(1 + κ²)/(N·Ktc),
    /// ε = π − 2·atan κ; None unless a_lim is positive and finite.
    fn limit(&self, l: C) -> Option<(f64, f64)> {
        if l.re == 0.0 {
            return None;
        }
        let kappa = l.im / l.re;
        let a = -2.0 * PI * l.re / (self.flutes as f64 * self.kt) * (1.0 + kappa * kappa);
        let eps = PI - 2.0 * kappa.atan();
        (a > 0.0 && (a * 1000.0).is_finite()).then_some((a * 1000.0, eps))
    }

    /// The modes of the flexible directions.
    fn modes(&self) -> impl Iterator<Item = &Mode> {
        self.x.iter().chain(self.y.iter())
    }

    /// The highest natural frequency \[Hz\].
    pub fn max_fn(&self) -> f64 {
        self.modes().map(|m| m.fn_hz).fold(0.0, f64::max)
    }

    /// A lower bound of a_lim \[mm\] at every chatter frequency above
    /// `f_hz`, which must lie above every natural frequency: −1/Λ is an
    /// eigenvalue of \[A\]·\[G\], so |Λ| ≥ 1/(‖A‖_F·max|G|), and a_lim =
    /// 2π|Λ|²/(N·Ktc·|Λ_R|) ≥ 2π|Λ|/(N·Ktc); above its resonance every |G|
    /// falls with ω.
    pub fn bound_above(&self, f_hz: f64) -> f64 {
        let a = directional(self.kr, self.st, self.ex);
        let norm = a.iter().map(|v| v * v).sum::<f64>().sqrt();
        let g = self
            .modes()
            .map(|m| m.g(2.0 * PI * f_hz).norm())
            .fold(0.0, f64::max);
        2.0 * PI / (self.flutes as f64 * self.kt * norm * g) * 1000.0
    }
}
