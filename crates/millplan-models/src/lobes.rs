//! Stability lobes of milling by the zero-order approximation (Altintas &
//! Budak 1995; spec `process-models.md` §3). SI units inside, as in the
//! source: stiffness N/m, cutting coefficient N/m², FRF m/N; the depth limit is
//! returned in mm.

use std::f64::consts::PI;

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

    pub fn validate(&self) -> Result<(), String> {
        if !(self.fn_hz > 0.0 && self.fn_hz < 1e6) {
            return Err(format!(
                "natural frequency {} Hz: must be above 0 and under 1 MHz",
                self.fn_hz
            ));
        }
        if !(self.k > 0.0 && self.k < 1e15) {
            return Err(format!("stiffness {} N/m: must be positive", self.k));
        }
        if !(self.zeta > 0.0 && self.zeta < 1.0) {
            return Err(format!(
                "damping ratio {}: must be between 0 and 1",
                self.zeta
            ));
        }
        Ok(())
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

/// One point of a lobe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LobePoint {
    /// Chatter frequency \[Hz\].
    pub fc_hz: f64,
    /// Spindle speed [1/min].
    pub rpm: f64,
    /// Limiting axial depth \[mm\].
    pub a_lim_mm: f64,
}

/// A lobe: lobe number k and eigenvalue branch (0 or 1).
#[derive(Clone, Debug, PartialEq)]
pub struct Lobe {
    pub k: usize,
    pub branch: usize,
    pub points: Vec<LobePoint>,
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
        if !(self.kt > 0.0 && self.kt.is_finite() && self.kr.is_finite() && self.kr >= 0.0) {
            return Err("Kt must be positive and Kr/Kt non-negative".into());
        }
        if !(self.ex > self.st) {
            return Err("the exit angle must follow the entry angle".into());
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
        self.eigen(w)
            .into_iter()
            .map(|l| {
                if l.re == 0.0 {
                    return None;
                }
                let kappa = l.im / l.re;
                let a = -2.0 * PI * l.re / (self.flutes as f64 * self.kt) * (1.0 + kappa * kappa);
                let eps = PI - 2.0 * kappa.atan();
                (a > 0.0 && a.is_finite()).then_some((a * 1000.0, eps))
            })
            .collect()
    }

    /// Lobes k = 0..lobes over chatter frequencies fc_lo..fc_hi \[Hz\] in
    /// `steps` steps.
    pub fn lobes(&self, fc_lo: f64, fc_hi: f64, steps: usize, lobes: usize) -> Vec<Lobe> {
        let mut out: Vec<Lobe> = (0..lobes)
            .flat_map(|k| {
                (0..2).map(move |branch| Lobe {
                    k,
                    branch,
                    points: Vec::new(),
                })
            })
            .collect();
        let steps = steps.max(2);
        for i in 0..steps {
            let fc = fc_lo + (fc_hi - fc_lo) * i as f64 / (steps - 1) as f64;
            let w = 2.0 * PI * fc;
            // Branch 0 is the lower limit at this frequency, branch 1 the higher.
            let mut roots: Vec<(f64, f64)> = self.limits_at(w).into_iter().flatten().collect();
            roots.sort_by(|a, b| a.0.total_cmp(&b.0));
            for (b, (a, eps)) in roots.into_iter().enumerate() {
                for k in 0..lobes {
                    // Tooth period T = (ε + 2kπ)/ω_c, n = 60/(N·T).
                    let rpm = 60.0 * w / (self.flutes as f64 * (eps + 2.0 * PI * k as f64));
                    out[2 * k + b].points.push(LobePoint {
                        fc_hz: fc,
                        rpm,
                        a_lim_mm: a,
                    });
                }
            }
        }
        out.retain(|l| !l.points.is_empty());
        out
    }

    /// The default chatter-frequency band: from half the lowest to twice the
    /// highest natural frequency.
    pub fn band(&self) -> (f64, f64) {
        let f: Vec<f64> = self
            .x
            .iter()
            .chain(self.y.iter())
            .map(|m| m.fn_hz)
            .collect();
        let lo = f.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = f.iter().cloned().fold(0.0, f64::max);
        (0.5 * lo, 2.0 * hi)
    }
}

/// The smallest a_lim \[mm\] over all lobes at spindle speed `rpm` (linear
/// interpolation along each lobe); None where no lobe covers the speed.
pub fn a_lim_at(lobes: &[Lobe], rpm: f64) -> Option<f64> {
    let mut best: Option<f64> = None;
    for l in lobes {
        for w in l.points.windows(2) {
            let (p, q) = (w[0], w[1]);
            let (lo, hi) = (p.rpm.min(q.rpm), p.rpm.max(q.rpm));
            if rpm < lo || rpm > hi || hi - lo <= 0.0 {
                continue;
            }
            let t = (rpm - p.rpm) / (q.rpm - p.rpm);
            let a = p.a_lim_mm + t * (q.a_lim_mm - p.a_lim_mm);
            best = Some(best.map_or(a, |b: f64| b.min(a)));
        }
    }
    best
}

/// The smallest a_lim over all lobes and the point where it occurs.
pub fn minimum(lobes: &[Lobe]) -> Option<LobePoint> {
    lobes
        .iter()
        .flat_map(|l| l.points.iter().copied())
        .min_by(|a, b| a.a_lim_mm.total_cmp(&b.a_lim_mm))
}

/// The stability limit over spindle speeds n_lo..n_hi [1/min] in `steps`
/// steps: (n, smallest a_lim over the lobes) where a lobe covers n.
pub fn envelope(lobes: &[Lobe], n_lo: f64, n_hi: f64, steps: usize) -> Vec<(f64, f64)> {
    let steps = steps.max(2);
    (0..steps)
        .filter_map(|i| {
            let n = n_lo + (n_hi - n_lo) * i as f64 / (steps - 1) as f64;
            a_lim_at(lobes, n).map(|a| (n, a))
        })
        .collect()
}
