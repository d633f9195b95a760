//! Cutting-force coefficients (spec `process-models.md` §1.5): constant sets,
//! the orthogonal-to-oblique transformation of an orthogonal cutting database,
//! the flute-segment coefficients of Schnoes & Zaeh, and mechanistic
//! calibration from mean slot forces.

/// Cutting coefficients `kc` [N/mm²] and edge coefficients `ke` [N/mm] on three
/// force directions. For [`Law::Rta`] the directions are tangential, radial,
/// axial (Ktc, Krc, Kac / Kte, Kre, Kae); for [`Law::FluteSegment`] they are
/// Schnoes & Zaeh's t (along the flute), d (distal, outward) and n (along the
/// cutting velocity).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coeffs {
    pub kc: [f64; 3],
    pub ke: [f64; 3],
}

impl Coeffs {
    /// Tangential/radial/axial set in the usual order.
    pub const fn rta(ktc: f64, krc: f64, kac: f64, kte: f64, kre: f64, kae: f64) -> Coeffs {
        Coeffs {
            kc: [ktc, krc, kac],
            ke: [kte, kre, kae],
        }
    }

    /// Parses `KTC,KRC,KAC,KTE,KRE,KAE`.
    pub fn parse(s: &str) -> Result<Coeffs, String> {
        let v: Vec<f64> = s
            .split(',')
            .map(|p| p.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("`{s}`: expected six numbers KTC,KRC,KAC,KTE,KRE,KAE"))?;
        if v.len() != 6 || v.iter().any(|x| !x.is_finite() || x.abs() > 1e6) {
            return Err(format!(
                "`{s}`: expected six finite numbers KTC,KRC,KAC,KTE,KRE,KAE (N/mm², N/mm)"
            ));
        }
        Ok(Coeffs::rta(v[0], v[1], v[2], v[3], v[4], v[5]))
    }
}

/// How the normal friction angle follows from the orthogonal one (§1.5a).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BetaRule {
    /// tan βn = tan βa · cos η (Budak, Altintas & Armarego 1996).
    #[default]
    Converted,
    /// βn = βa, as some open-source codes do (Ktc ≈ 4 % higher at i = 30°).
    Same,
}

/// An orthogonal cutting database (Budak, Altintas & Armarego 1996 form):
/// shear stress, friction angle and chip ratio as functions of the normal rake
/// αn (degrees) and chip thickness h (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orthogonal {
    /// Shear stress τs [N/mm²].
    pub tau_s: f64,
    /// βa \[deg\] = beta_a\[0\] + beta_a\[1\]·αn.
    pub beta_a: [f64; 2],
    /// Chip ratio r_c = C0·h^a with C0 = rc_c0\[0\] + rc_c0\[1\]·αn …
    pub rc_c0: [f64; 2],
    /// … and a = rc_a\[0\] + rc_a\[1\]·αn.
    pub rc_a: [f64; 2],
    /// Edge coefficients Kte, Kre, Kae [N/mm].
    pub ke: [f64; 3],
}

impl Orthogonal {
    /// Ti6Al4V with a carbide tool \[P\] (§1.5a).
    pub const TI6AL4V: Orthogonal = Orthogonal {
        tau_s: 613.0,
        beta_a: [19.1, 0.29],
        rc_c0: [1.755, -0.028],
        rc_a: [0.331, -0.0082],
        ke: [24.0, 43.0, 0.0],
    };

    /// Shear angle φn \[rad\] at rake αn \[deg\] and chip thickness h \[mm\].
    pub fn shear_angle(&self, rake_deg: f64, h: f64) -> f64 {
        let an = rake_deg.to_radians();
        let c0 = self.rc_c0[0] + self.rc_c0[1] * rake_deg;
        let a = self.rc_a[0] + self.rc_a[1] * rake_deg;
        let rc = c0 * h.powf(a);
        (rc * an.cos() / (1.0 - rc * an.sin())).atan()
    }

    /// Checks that the database gives finite coefficients, the tangential
    /// and radial ones not negative, at rake `rake_deg` for every chip from
    /// `h_min` to 2 mm and every inclination from 0 to 60°: a chip ratio
    /// C0·h^a of 0 or below (`rc_c0 = [0, 0]`) has no shear angle and gives
    /// NaN. The message names the key at fault.
    pub fn check(&self, rake_deg: f64, h_min: f64, rule: BetaRule) -> Result<(), String> {
        let c0 = self.rc_c0[0] + self.rc_c0[1] * rake_deg;
        if !(c0 > 0.0 && c0 <= 10.0) {
            return Err(format!(
                "`rc_c0` gives a chip-ratio factor C0 of {c0} at the rake {rake_deg}°: it must be above 0 and at most 10"
            ));
        }
        let beta = self.beta_a[0] + self.beta_a[1] * rake_deg;
        if !(0.0..80.0).contains(&beta) {
            return Err(format!(
                "`beta_a` gives a friction angle of {beta}° at the rake {rake_deg}°: it must be from 0 to below 80°"
            ));
        }
        let h_min = h_min.clamp(1e-4, 2.0);
        for k in 0..=16 {
            let h = h_min * (2.0 / h_min).powf(k as f64 / 16.0);
            let phi = self.shear_angle(rake_deg, h);
            if !(phi > 0.0 && phi < std::f64::consts::FRAC_PI_2) {
                return Err(format!(
                    "`rc_a` with `rc_c0` gives no shear angle at a chip of {h:.4} mm (chip ratio C0·h^a out of range)"
                ));
            }
            for deg in (0..=60).step_by(10) {
                let [t, r, a] = self.oblique(rake_deg, h, (deg as f64).to_radians(), rule);
                if !(t.is_finite() && r.is_finite() && a.is_finite() && t >= 0.0 && r >= 0.0) {
                    return Err(format!(
                        "`tau_s` with the chip data gives the coefficients [{t}, {r}, {a}] N/mm² at a chip of {h:.4} mm and a helix of {deg}°: the tangential and radial ones must be finite and not negative"
                    ));
                }
            }
        }
        Ok(())
    }

    /// Oblique cutting coefficients (Ktc, Krc, Kac) [N/mm²] at rake αn \[deg\],
    /// chip thickness h \[mm\] and inclination i \[rad\], with chip flow η = i.
    pub fn oblique(&self, rake_deg: f64, h: f64, i: f64, rule: BetaRule) -> [f64; 3] {
        let an = rake_deg.to_radians();
        let phi_n = self.shear_angle(rake_deg, h);
        let beta_a = (self.beta_a[0] + self.beta_a[1] * rake_deg).to_radians();
        let eta = i;
        let beta_n = match rule {
            BetaRule::Converted => (beta_a.tan() * eta.cos()).atan(),
            BetaRule::Same => beta_a,
        };
        let (ti, te, sb) = (i.tan(), eta.tan(), beta_n.sin());
        let c = ((phi_n + beta_n - an).cos().powi(2) + te * te * sb * sb).sqrt();
        let k = self.tau_s / phi_n.sin() / c;
        [
            k * ((beta_n - an).cos() + ti * te * sb),
            k * (beta_n - an).sin() / i.cos(),
            k * ((beta_n - an).cos() * ti - te * sb),
        ]
    }
}

/// Which chip thickness the oblique coefficients are evaluated at (they depend
/// on h through the chip ratio).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChipRule {
    /// Per element, with h clamped from below to `h_min` mm.
    PerElement { h_min: f64 },
    /// Once, at this chip thickness (e.g. the mean chip thickness).
    Fixed(f64),
}

/// Coefficients from an orthogonal database through the oblique transformation,
/// with the local helix i(z) of the edge as inclination.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Oblique {
    pub db: Orthogonal,
    /// Normal rake αn \[deg\].
    pub rake_deg: f64,
    pub beta: BetaRule,
    pub chip: ChipRule,
}

impl Oblique {
    /// (Ktc, Krc, Kac) on this crate's tangential, radial and axial
    /// channels at chip thickness h \[mm\] and inclination i \[rad\]. The
    /// oblique model's axial force of a right-hand helix (Kac > 0 in
    /// [`Orthogonal::oblique`]) presses the rake face toward the tip, along
    /// −z on the cylinder (Lee & Altintas' frame, §1.3); the model's axial
    /// channel is +z there (T1a's sign), so Kac enters with its sign turned.
    pub fn coefficients(&self, h: f64, i: f64) -> [f64; 3] {
        let [t, r, a] = self.db.oblique(self.rake_deg, h, i, self.beta);
        [t, r, -a]
    }
}

/// The elemental force law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Law {
    /// Linear edge-force model of Altintas with constant coefficients (§1.3):
    /// dF = Ke·dS + Kc·h·db on the tangential, radial and axial directions.
    Rta(Coeffs),
    /// The same model with coefficients from an orthogonal database (§1.5a).
    Oblique(Oblique),
    /// Flute-segment model of Schnoes & Zaeh (paper 001, eq. 10): each segment
    /// of length db has its own frame (t along the flute toward the shank, d
    /// outward, n along the cutting velocity) and dF = [t d n]·(ke + kc·h)·db,
    /// h measured along d.
    FluteSegment(Coeffs),
}

/// A least-squares line y = intercept + slope·x with its R².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    pub slope: f64,
    pub intercept: f64,
    pub r2: f64,
}

/// Least-squares straight line through (x, y); None with fewer than two
/// distinct x.
pub fn fit_line(x: &[f64], y: &[f64]) -> Option<Line> {
    let n = x.len().min(y.len());
    if n < 2 {
        return None;
    }
    let nf = n as f64;
    let mx = x[..n].iter().sum::<f64>() / nf;
    let my = y[..n].iter().sum::<f64>() / nf;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let (dx, dy) = (x[i] - mx, y[i] - my);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    if !(sxx > 1e-30) {
        return None;
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let sse: f64 = (0..n)
        .map(|i| (y[i] - intercept - slope * x[i]).powi(2))
        .sum();
    let r2 = if syy > 0.0 { 1.0 - sse / syy } else { 1.0 };
    Some(Line {
        slope,
        intercept,
        r2,
    })
}

/// One slot test: feed per tooth c \[mm\] and the measured mean forces on the
/// tool \[N\] in the tool frame (x feed, z toward the shank).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlotTest {
    pub c: f64,
    pub fx: f64,
    pub fy: f64,
    pub fz: f64,
}

/// Result of a mechanistic calibration: the coefficients and the three fits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    pub coeffs: Coeffs,
    pub fit_x: Line,
    pub fit_y: Line,
    pub fit_z: Line,
}

/// Mechanistic calibration from mean slot forces of a flat end mill with
/// `flutes` flutes at axial depth `a` mm (§1.5b), in the textbook form the
/// model follows (forces on the tool, +z toward the shank, T1a):
/// F̄x = −(Na/4)·Krc·c − Na·Kre/π, F̄y = (Na/4)·Ktc·c + Na·Kte/π and
/// F̄z = (Na/π)·(Kac·c + Kae·π/2). None of them depends on the helix: the
/// cutting terms of a slot average over the lag, and the edge terms act on
/// the axial depth (T1a, "helix irrelevant"), so coefficients calibrated
/// here reproduce the measurements through [`super::ForceModel`] at any
/// helix.
pub fn calibrate_slot(tests: &[SlotTest], flutes: usize, a: f64) -> Result<Calibration, String> {
    if tests.len() < 2 {
        return Err(format!(
            "{} measurement(s): the calibration needs slot tests at two or more feeds",
            tests.len()
        ));
    }
    if flutes == 0 || !(a > 0.0) {
        return Err("the calibration needs a flute count and a positive axial depth".into());
    }
    let c: Vec<f64> = tests.iter().map(|t| t.c).collect();
    let col = |f: fn(&SlotTest) -> f64| tests.iter().map(f).collect::<Vec<f64>>();
    let fit = |y: Vec<f64>| {
        fit_line(&c, &y).ok_or_else(|| "the feeds of the slot tests must differ".to_string())
    };
    let fx = fit(col(|t| t.fx))?;
    let fy = fit(col(|t| t.fy))?;
    let fz = fit(col(|t| t.fz))?;
    let na = flutes as f64 * a;
    let pi = std::f64::consts::PI;
    let coeffs = Coeffs::rta(
        4.0 * fy.slope / na,
        -4.0 * fx.slope / na,
        pi * fz.slope / na,
        pi * fy.intercept / na,
        -pi * fx.intercept / na,
        2.0 * fz.intercept / na,
    );
    Ok(Calibration {
        coeffs,
        fit_x: fx,
        fit_y: fy,
        fit_z: fz,
    })
}
