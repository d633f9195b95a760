//! Working diameter of a ball-end mill in 3-axis finishing (paper 000, theses 1–4;
//! spec `working-diameter.md` §1, a reconstruction that is the contract here).
//!
//! In the local frame of the contact point — feed direction t, uncut side s,
//! surface normal n — a ball direction d = (d_t, d_s, d_n) is engaged when
//!
//! - (E1) it lies in the stock layer of thickness ap: d_n ≤ −cos θ, cos θ = 1 − 2ap/D;
//! - (E2) it is on the leading half: d_t ≥ 0;
//! - (E3) the neighbouring pass at distance ae on side −s did not remove it:
//!   2R·ae·d_s + ae² − R²·d_t² ≥ 0 (and its mirror when both neighbours are cut).
//!
//! The working diameter is the tool diameter at the highest engaged point:
//! h* = max d·k over E, D_w = D·√(1 − h*²) (D when h* ≥ 0). The maximum of the
//! linear objective lies on the boundary of E, made of the cap rim (B1), the front
//! great circle (B2) and the curve where E3 is tight (B3); B1 and B2 are solved in
//! closed form and B3 by sampling plus golden-section refinement
//! ([`working_diameter`]). [`brute_force`] samples the cap and is the test reference.

use std::f64::consts::PI;

/// Which side of the feed the not-yet-machined material is on, seen from outside
/// the material. With M3, uncut material on the right is climb (down) milling.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Left,
    Right,
}

/// Which neighbouring passes are already machined.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Neighbour {
    /// First or isolated pass (ae = ∞).
    None,
    /// A machined pass at distance `ae` (mm, along the surface) on the side
    /// opposite the uncut side.
    One(f64),
    /// Both sides machined at distance `ae` (a pass filled in between two others).
    Both(f64),
}

/// One evaluation case, in mm and radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Case {
    /// Ball diameter.
    pub d: f64,
    /// Stock thickness along the normal.
    pub ap: f64,
    pub neighbour: Neighbour,
    /// Surface inclination α = arccos(n·k), 0 ≤ α < π/2.
    pub alpha: f64,
    /// Feed direction relative to the uphill direction, 0 = uphill, ±π = downhill,
    /// positive counter-clockwise seen from outside the material.
    pub af: f64,
    /// Uncut side.
    pub side: Side,
}

impl Case {
    /// Distance to the machined neighbour (∞ without one) and whether both sides
    /// are machined.
    pub fn neighbour_ae(&self) -> (f64, bool) {
        match self.neighbour {
            Neighbour::None => (f64::INFINITY, false),
            Neighbour::One(a) => (a, false),
            Neighbour::Both(a) => (a, true),
        }
    }

    /// E2 and E3 for a ball direction with components x = d·t, y = d·s.
    pub fn leading_and_uncut(&self, x: f64, y: f64) -> bool {
        if x < 0.0 {
            return false;
        }
        let (ae, both) = self.neighbour_ae();
        if !ae.is_finite() {
            return true;
        }
        let r = self.d / 2.0;
        let e3 = |y: f64| 2.0 * r * ae * y + ae * ae - r * r * x * x >= 0.0;
        e3(y) && (!both || e3(-y))
    }

    /// Components (k_t, k_s, k_n) of the tool axis in the local frame.
    pub fn axis_local(&self) -> (f64, f64, f64) {
        let (sa, ca) = self.alpha.sin_cos();
        let (sf, cf) = self.af.sin_cos();
        let ks = match self.side {
            Side::Left => -sa * sf,
            Side::Right => sa * sf,
        };
        (sa * cf, ks, ca)
    }

    /// A case as a user states it: lengths in mm, angles in degrees (`af` any
    /// finite angle, taken to −180..180), `ae` the distance to the machined
    /// neighbour (`None` or infinite: no neighbour, the first or an isolated
    /// pass), `both` whether it lies on both sides. Checked against the
    /// model's domain: `d` positive, `0 < ap ≤ d/2` (the engaged zone stays
    /// on the ball), `ae` positive, `0 ≤ alpha < 90`. The error names the
    /// argument and says what it must be.
    pub fn from_degrees(
        d: f64,
        ap: f64,
        ae: Option<f64>,
        both: bool,
        alpha_deg: f64,
        af_deg: f64,
        side: Side,
    ) -> Result<Case, String> {
        if !(d > 0.0 && d.is_finite()) {
            return Err(format!("d {d}: must be a positive diameter, mm"));
        }
        if !(ap > 0.0 && ap <= d / 2.0) {
            return Err(format!(
                "ap {ap}: must be above 0 and at most d/2 = {}",
                d / 2.0
            ));
        }
        let ae = ae.filter(|a| *a != f64::INFINITY);
        if let Some(a) = ae {
            if !(a > 0.0 && a.is_finite()) {
                return Err(format!("ae {a}: must be a positive distance, mm"));
            }
        }
        if !(0.0..90.0).contains(&alpha_deg) {
            return Err(format!(
                "alpha {alpha_deg}: must be from 0 to under 90 degrees"
            ));
        }
        if !af_deg.is_finite() {
            return Err(format!("af {af_deg}: must be a finite angle, degrees"));
        }
        let af = (af_deg + 180.0).rem_euclid(360.0) - 180.0;
        Ok(Case {
            d,
            ap,
            neighbour: match (ae, both) {
                (None, _) => Neighbour::None,
                (Some(a), false) => Neighbour::One(a),
                (Some(a), true) => Neighbour::Both(a),
            },
            alpha: alpha_deg.to_radians(),
            af: af.to_radians(),
            side,
        })
    }
}

/// Diameter at the contact point, D·sin α: the lower bound of the working diameter.
pub fn contact_diameter(d: f64, alpha: f64) -> f64 {
    d * alpha.sin().abs()
}

/// h* → D_w.
fn diameter_from_height(d: f64, h: f64) -> f64 {
    if h >= 0.0 {
        d
    } else {
        d * (1.0 - h * h).max(0.0).sqrt()
    }
}

/// The highest engaged point's height h* = max d·k over the engagement region.
pub fn highest_point(c: &Case) -> f64 {
    let r = c.d / 2.0;
    let cos_t = 1.0 - 2.0 * c.ap / c.d;
    if cos_t <= 0.0 {
        // ap ≥ D/2: the engaged zone reaches the equator (O7).
        return 0.0;
    }
    let sin_t = (1.0 - cos_t * cos_t).sqrt();
    let (kt, ks, kn) = c.axis_local();
    let (ae, both) = c.neighbour_ae();
    let mut best = f64::NEG_INFINITY;

    // Both boundary arcs below run over angles in [−π/2, π/2], so each angle
    // is handled by its sine (the cosine is then √(1 − sin²) ≥ 0) and the
    // angle order by the sine order, without inverse trigonometry.
    let cos_of = |s: f64| (1.0 - s * s).max(0.0).sqrt();

    // B1, the cap rim: d = (sinθ cosψ, sinθ sinψ, −cosθ), ψ ∈ [−π/2, π/2] (E2);
    // E3 on the rim is sinψ ≥ σ = 1 − ae/(R sinθ) (mirror: sinψ ≤ −σ).
    let sigma = if ae.is_finite() {
        1.0 - ae / (r * sin_t)
    } else {
        f64::NEG_INFINITY
    };
    // sin of the ends ψ_lo, ψ_hi.
    let s_lo = if sigma > -1.0 { sigma.min(1.0) } else { -1.0 };
    let s_hi = if both && sigma > -1.0 {
        (-sigma).max(-1.0)
    } else {
        1.0
    };
    if sigma <= 1.0 && s_lo <= s_hi {
        let g = |s: f64| sin_t * (kt * cos_of(s) + ks * s) - cos_t * kn;
        let mut m = g(s_lo).max(g(s_hi));
        // The peak ψ* = atan2(k_s, k_t), where g = sinθ·|(k_t, k_s)| − cosθ·k_n.
        let rho = kt.hypot(ks);
        let s_peak = ks / rho;
        if kt >= 0.0 && s_peak >= s_lo && s_peak <= s_hi {
            m = m.max(sin_t * rho - cos_t * kn);
        }
        best = best.max(m);
    }

    // B2, the front great circle: d = (0, sinφ, −cosφ), |φ| ≤ θ (E1),
    // E3: sinφ ≥ −ae/D (mirror: sinφ ≤ ae/D). θ < π/2 here.
    let s_eps = if ae.is_finite() { ae / c.d } else { 1.0 };
    let s_in = sin_t.min(s_eps);
    let (s0, s1) = (-s_in, if both { s_in } else { sin_t });
    let g2 = |s: f64| ks * s - kn * cos_of(s);
    let mut m2 = g2(s0).max(g2(s1));
    // The peak φ* = atan2(k_s, −k_n), where g2 = |(k_s, k_n)|.
    let rho2 = ks.hypot(kn);
    let s_peak2 = ks / rho2;
    if -kn >= 0.0 && s_peak2 >= s0 && s_peak2 <= s1 {
        m2 = m2.max(rho2);
    }
    best = best.max(m2);

    // B3, E3 tight: d_s = (R²x² − ae²)/(2R·ae), d_t = x ≥ 0, inside the cap while
    // x² + d_s² ≤ sin²θ (monotone in x), and with both neighbours while d_s ≤ 0.
    if ae.is_finite() && ae / c.d <= sin_t {
        let a = (r / (2.0 * ae)).powi(2);
        let q = (ae / c.d).powi(2) - sin_t * sin_t;
        // a·X² + X/2 + q = 0, X = x².
        let xx = (-0.5 + (0.25 - 4.0 * a * q).max(0.0).sqrt()) / (2.0 * a);
        let mut xmax = xx.max(0.0).sqrt();
        if both {
            xmax = xmax.min(ae / r);
        }
        let h3 = |x: f64| {
            let ds = (r * r * x * x - ae * ae) / (2.0 * r * ae);
            let dn = -(1.0 - x * x - ds * ds).max(0.0).sqrt();
            kt * x + ks * ds + kn * dn
        };
        // d/dx: d_s' = R·x/ae, d_n' = (x + d_s·d_s')/(−d_n).
        let dh3 = |x: f64| {
            let ds = (r * r * x * x - ae * ae) / (2.0 * r * ae);
            let dds = r * x / ae;
            let g = (1.0 - x * x - ds * ds).max(1e-300);
            kt + ks * dds + kn * (x + ds * dds) / g.sqrt()
        };
        let (mut m3, _) = maximize_1d(&h3, &dh3, 0.0, xmax);
        if both {
            // The mirror curve gives the mirror values: d_s → −d_s.
            let h3m = |x: f64| {
                let ds = -(r * r * x * x - ae * ae) / (2.0 * r * ae);
                let dn = -(1.0 - x * x - ds * ds).max(0.0).sqrt();
                kt * x + ks * ds + kn * dn
            };
            let dh3m = |x: f64| {
                let ds = -(r * r * x * x - ae * ae) / (2.0 * r * ae);
                let dds = -r * x / ae;
                let g = (1.0 - x * x - ds * ds).max(1e-300);
                kt + ks * dds + kn * (x + ds * dds) / g.sqrt()
            };
            m3 = m3.max(maximize_1d(&h3m, &dh3m, 0.0, xmax).0);
        }
        best = best.max(m3);
    }
    best
}

/// Maximum of a smooth function `f` on [a, b], given its derivative `df`: a
/// coarse scan (the objective has at most a few extrema), then the root of the
/// derivative around the best sample, or golden-section search where the
/// derivative does not bracket one.
fn maximize_1d(f: &impl Fn(f64) -> f64, df: &impl Fn(f64) -> f64, a: f64, b: f64) -> (f64, f64) {
    const SCAN: usize = 24;
    if b <= a {
        return (f(a), a);
    }
    let step = (b - a) / SCAN as f64;
    let (mut best, mut at) = ((f(a), a), 0);
    for i in 1..=SCAN {
        let x = if i == SCAN { b } else { a + step * i as f64 };
        let v = f(x);
        if v > best.0 {
            (best, at) = ((v, x), i);
        }
    }
    let (lo, hi) = ((best.1 - step).max(a), (best.1 + step).min(b));
    let (dlo, dhi) = (df(lo), df(hi));
    let (x, v) = if dlo > 0.0 && dhi < 0.0 {
        let x = falling_root(df, (lo, dlo), (hi, dhi));
        (x, f(x))
    } else if (at == 0 && dlo <= 0.0) || (at == SCAN && dhi >= 0.0) {
        // Falling away from an end of the interval: the end is the maximum.
        return best;
    } else {
        millplan_geom::optimize::golden_max(f, lo, hi, 1e-12, 34)
    };
    if v > best.0 {
        best = (v, x);
    }
    best
}

/// The root of `g` between `lo` and `hi`, given with g(lo) > 0 > g(hi) (where
/// the function `g` is the derivative of has its maximum), by Illinois false
/// position.
fn falling_root(g: &impl Fn(f64) -> f64, lo: (f64, f64), hi: (f64, f64)) -> f64 {
    let ((mut lo, mut glo), (mut hi, mut ghi)) = (lo, hi);
    // Which end the last step moved (+1 low, −1 high): an end kept twice has
    // its value halved, so both ends close in.
    let mut moved = 0;
    for _ in 0..64 {
        let x = (lo * ghi - hi * glo) / (ghi - glo);
        if !(x > lo && x < hi) || hi - lo < 1e-13 {
            break;
        }
        let gx = g(x);
        if gx > 0.0 {
            lo = x;
            glo = gx;
            if moved == 1 {
                ghi *= 0.5;
            }
            moved = 1;
        } else if gx < 0.0 {
            hi = x;
            ghi = gx;
            if moved == -1 {
                glo *= 0.5;
            }
            moved = -1;
        } else {
            return x;
        }
    }
    if glo < -ghi {
        lo
    } else {
        hi
    }
}

/// Working diameter D_w (mm) by the boundary method.
///
/// A D10 ball, 0.3 mm stock, the neighbouring pass 0.25 mm away on the left,
/// the surface inclined by 20° and the feed 45° from uphill:
///
/// ```
/// use millplan_models::wd::{working_diameter, Case, Neighbour, Side};
///
/// let c = Case {
///     d: 10.0,
///     ap: 0.3,
///     neighbour: Neighbour::One(0.25),
///     alpha: 20f64.to_radians(),
///     af: 45f64.to_radians(),
///     side: Side::Left,
/// };
/// let dw = working_diameter(&c);
/// assert!((dw - 4.1301).abs() < 1e-4, "{dw}");
/// // The spindle speed for 63 m/min there: n = 1000·vc/(π·D_w).
/// let n = 1000.0 * 63.0 / (std::f64::consts::PI * dw);
/// assert!((n - 4855.0).abs() < 1.0);
/// ```
pub fn working_diameter(c: &Case) -> f64 {
    diameter_from_height(c.d, highest_point(c))
}

/// Spindle speed (1/min) for cutting speed `vc` (m/min) at diameter `dw` (mm).
pub fn spindle_speed(vc: f64, dw: f64) -> f64 {
    1000.0 * vc / (PI * dw)
}

/// How [`mean_diameter`] weights the engaged region.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeanWeighting {
    /// By area of the engaged ball surface.
    Area,
    /// By area times the local uncut chip thickness, which grows like d·t
    /// (zero on the E2 boundary).
    ChipThickness,
}

/// D_mean (spec §1.3): the tool diameter averaged over the engaged region E, by
/// area or by chip thickness, on an `n` × 4`n` polar grid of the cap.
pub fn mean_diameter(c: &Case, weighting: MeanWeighting, n: usize) -> f64 {
    let cos_t = (1.0 - 2.0 * c.ap / c.d).max(-1.0);
    let theta = cos_t.acos();
    let (kt, ks, kn) = c.axis_local();
    let (np, nr) = (4 * n.max(8), n.max(8));
    let (mut wsum, mut dsum) = (0.0, 0.0);
    for i in 0..nr {
        let rho = theta * (i as f64 + 0.5) / nr as f64;
        let (sr, cr) = rho.sin_cos();
        for j in 0..np {
            let psi = -PI + 2.0 * PI * (j as f64 + 0.5) / np as f64;
            let (sp, cp) = psi.sin_cos();
            let (x, y, z) = (sr * cp, sr * sp, -cr);
            if !c.leading_and_uncut(x, y) {
                continue;
            }
            let h = (kt * x + ks * y + kn * z).clamp(-1.0, 1.0);
            let w = sr
                * if weighting == MeanWeighting::ChipThickness {
                    x
                } else {
                    1.0
                };
            wsum += w;
            dsum += w * c.d * (1.0 - h * h).sqrt();
        }
    }
    if wsum > 0.0 {
        dsum / wsum
    } else {
        contact_diameter(c.d, c.alpha)
    }
}

/// Reference: samples the cap in polar coordinates (ρ ∈ [0, θ], ψ ∈ [−π, π)) on an
/// `nr` × `npsi` grid, keeps samples in E, then refines around the best few on a
/// finer local grid. Slow; for tests. Underestimates by at most the grid error.
pub fn brute_force(c: &Case, nr: usize, npsi: usize) -> f64 {
    let cos_t = 1.0 - 2.0 * c.ap / c.d;
    if cos_t <= 0.0 {
        return c.d;
    }
    let theta = cos_t.acos();
    let (kt, ks, kn) = c.axis_local();
    let eval = |rho: f64, psi: f64| -> Option<f64> {
        let (sr, cr) = rho.sin_cos();
        let (sp, cp) = psi.sin_cos();
        let (x, y, z) = (sr * cp, sr * sp, -cr);
        // cos(π/2) is not exactly 0 in floating point; the E2 boundary belongs to E.
        if x < -1e-12 {
            return None;
        }
        let x = x.max(0.0);
        if !c.leading_and_uncut(x, y) {
            return None;
        }
        Some(kt * x + ks * y + kn * z)
    };
    // A first pass finds how far from the contact point E reaches (a thin region,
    // such as the lens between two machined neighbours, needs the rows there).
    let dp = 2.0 * PI / npsi as f64;
    let mut reach: f64 = 0.0;
    for i in 0..=nr {
        let rho = theta * i as f64 / nr as f64;
        if (0..npsi).any(|j| eval(rho, -PI + dp * j as f64).is_some()) {
            reach = rho;
        }
    }
    let extent = (reach + 2.0 * theta / nr as f64).min(theta);
    let mut top: Vec<(f64, f64, f64)> = Vec::new();
    let dr = extent / nr as f64;
    for i in 0..=nr {
        let rho = dr * i as f64;
        for j in 0..npsi {
            let psi = -PI + dp * j as f64;
            if let Some(h) = eval(rho, psi) {
                if top.len() < 8 || h > top[top.len() - 1].0 {
                    top.push((h, rho, psi));
                    top.sort_by(|a, b| b.0.total_cmp(&a.0));
                    top.truncate(8);
                }
            }
        }
    }
    let mut best = top.first().map(|t| t.0).unwrap_or(-1.0);
    for &(_, rho, psi) in &top {
        for i in 0..=60 {
            let rr = (rho - dr + 2.0 * dr * i as f64 / 60.0).clamp(0.0, theta);
            for j in 0..=60 {
                let pp = psi - dp + 2.0 * dp * j as f64 / 60.0;
                if let Some(h) = eval(rr, pp) {
                    best = best.max(h);
                }
            }
        }
    }
    diameter_from_height(c.d, best)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn case(d: f64, ap: f64, ae: Option<f64>, alpha_deg: f64, af_deg: f64, side: Side) -> Case {
        Case {
            d,
            ap,
            neighbour: ae.map(Neighbour::One).unwrap_or(Neighbour::None),
            alpha: alpha_deg.to_radians(),
            af: af_deg.to_radians(),
            side,
        }
    }

    /// The scan-and-refine maximum agrees with a fine scan on functions with one
    /// maximum inside, or near or at either end: a·sin(w·x + φ) + b·x over less
    /// than half a period.
    #[test]
    fn maximum_in_one_dimension_agrees_with_a_fine_scan() {
        let mut s = 99u64;
        let mut r = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut inside, mut ends) = (0, 0);
        for k in 0..1000 {
            let (a, w, mut phi, b) = (0.5 + r(), 1.0 + 5.0 * r(), 6.3 * r(), 0.2 * r() - 0.1);
            // Less than half a period: one maximum at most inside.
            let hi = (0.1 + 1.5 * r()).min(3.0 / w);
            // Every third: a peak within half a scan step of an end.
            let near = hi / 48.0 * r();
            match k % 6 {
                0 => phi = std::f64::consts::FRAC_PI_2 - w * near,
                3 => phi = std::f64::consts::FRAC_PI_2 - w * (hi - near),
                _ => {}
            }
            let f = |x: f64| a * (w * x + phi).sin() + b * x;
            let df = |x: f64| a * w * (w * x + phi).cos() + b;
            let (v, x) = maximize_1d(&f, &df, 0.0, hi);
            let n = 50_000;
            let (fine, fx) = (0..=n)
                .map(|i| hi * i as f64 / n as f64)
                .map(|x| (f(x), x))
                .fold(
                    (f64::NEG_INFINITY, 0.0),
                    |m, p| if p.0 > m.0 { p } else { m },
                );
            // The fine scan is within its step of the maximum: below it by
            // at most max|f''|·step²/8.
            let slack = a * w * w * (hi / n as f64).powi(2) / 8.0 + 1e-12;
            assert!(v >= fine - 1e-12 && v <= fine + slack, "{v} vs {fine}");
            assert!((f(x) - v).abs() < 1e-15);
            if fx > 0.0 && fx < hi {
                inside += 1;
            } else {
                ends += 1;
            }
        }
        assert!(
            inside > 150 && ends > 150,
            "{inside} inside, {ends} at an end"
        );
    }

    /// Spec `working-diameter.md` §2.3, the oracle table (D, ap, ae, α°, A_f°, side,
    /// D_w mm, n at vc = 63 m/min).
    /// D, ap, ae, α°, A_f°, uncut side, D_w (mm), n (1/min).
    type Row = (f64, f64, Option<f64>, f64, f64, Side, f64, f64);

    const ORACLE: &[Row] = &[
        (10.0, 0.3, Some(0.25), 0.0, 0.0, Side::Left, 3.4117, 5878.0),
        (10.0, 0.3, Some(0.25), 10.0, 0.0, Side::Left, 4.4638, 4492.0),
        (
            10.0,
            0.3,
            Some(0.25),
            10.0,
            90.0,
            Side::Left,
            2.1651,
            9262.0,
        ),
        (
            10.0,
            0.3,
            Some(0.25),
            10.0,
            90.0,
            Side::Right,
            4.9922,
            4017.0,
        ),
        (
            10.0,
            0.3,
            Some(0.25),
            10.0,
            180.0,
            Side::Left,
            3.7821,
            5302.0,
        ),
        (10.0, 0.3, Some(0.25), 20.0, 0.0, Side::Left, 5.6877, 3526.0),
        (
            10.0,
            0.3,
            Some(0.25),
            20.0,
            45.0,
            Side::Left,
            4.1301,
            4855.0,
        ),
        (
            10.0,
            0.3,
            Some(0.25),
            20.0,
            45.0,
            Side::Right,
            6.3818,
            3142.0,
        ),
        (
            10.0,
            0.3,
            Some(0.25),
            20.0,
            90.0,
            Side::Left,
            3.6541,
            5488.0,
        ),
        (
            10.0,
            0.3,
            Some(0.25),
            20.0,
            135.0,
            Side::Left,
            3.5896,
            5587.0,
        ),
        (
            10.0,
            0.3,
            Some(0.25),
            20.0,
            135.0,
            Side::Right,
            5.9893,
            3348.0,
        ),
        (
            10.0,
            0.3,
            Some(0.25),
            30.0,
            60.0,
            Side::Left,
            5.2502,
            3820.0,
        ),
        (
            10.0,
            0.3,
            Some(0.25),
            45.0,
            90.0,
            Side::Left,
            7.2456,
            2768.0,
        ),
        (10.0, 0.3, Some(0.25), 60.0, 0.0, Side::Left, 9.4876, 2114.0),
        (
            10.0,
            0.3,
            Some(0.25),
            9.75,
            107.0,
            Side::Left,
            1.9300,
            10391.0,
        ),
        (6.0, 0.2, Some(0.3), 25.0, 30.0, Side::Left, 3.5216, 5694.0),
        (
            6.0,
            0.2,
            Some(0.3),
            25.0,
            120.0,
            Side::Right,
            4.1979,
            4777.0,
        ),
        (
            12.0,
            0.5,
            Some(0.4),
            40.0,
            150.0,
            Side::Left,
            7.8700,
            2548.0,
        ),
        (
            12.0,
            0.5,
            Some(0.4),
            10.0,
            120.0,
            Side::Left,
            3.2408,
            6188.0,
        ),
        (10.0, 0.3, None, 20.0, 0.0, Side::Left, 6.4210, 3123.0),
        (10.0, 0.3, None, 20.0, 135.0, Side::Left, 5.9893, 3348.0),
        (10.0, 0.3, None, 20.0, 180.0, Side::Left, 4.6879, 4278.0),
    ];

    #[test]
    fn oracle_table_section_2_3() {
        for &(d, ap, ae, a, f, side, dw, n) in ORACLE {
            let c = case(d, ap, ae, a, f, side);
            let got = working_diameter(&c);
            assert!((got - dw).abs() < 6e-5, "{c:?}: {got:.5} vs {dw}");
            assert!((spindle_speed(63.0, got) - n).abs() <= 1.0, "{c:?}: n");
        }
    }

    #[test]
    fn ae_table_section_2_3() {
        let aes = [0.05, 0.1, 0.25, 0.5, 1.0, 2.0, 3.4];
        let rows: [(f64, f64, [f64; 8]); 3] = [
            (
                20.0,
                0.0,
                [
                    5.1819, 5.3643, 5.6877, 5.9897, 6.2940, 6.4210, 6.4210, 6.4210,
                ],
            ),
            (
                20.0,
                90.0,
                [
                    3.4671, 3.5140, 3.6541, 3.8858, 4.3428, 5.2305, 6.4114, 6.4210,
                ],
            ),
            (
                10.0,
                90.0,
                [
                    1.8239, 1.9151, 2.1651, 2.5249, 3.1154, 4.0231, 4.9851, 4.9922,
                ],
            ),
        ];
        for (a, f, want) in rows {
            for (k, ae) in aes.iter().chain([f64::INFINITY].iter()).enumerate() {
                let c = case(10.0, 0.3, ae.is_finite().then_some(*ae), a, f, Side::Left);
                let got = working_diameter(&c);
                assert!(
                    (got - want[k]).abs() < 6e-5,
                    "α {a} A_f {f} ae {ae}: {got:.5} vs {}",
                    want[k]
                );
            }
        }
    }

    #[test]
    fn closed_forms_o1_to_o7() {
        let (d, ap): (f64, f64) = (10.0, 0.3);
        let theta = (1.0 - 2.0 * ap / d).acos();
        // O1: flat, any feed, any side, any ae.
        for f in [0.0, 37.0, 90.0, 180.0, -120.0] {
            for ae in [Some(0.1), Some(1.0), None] {
                let got = working_diameter(&case(d, ap, ae, 0.0, f, Side::Right));
                assert!((got - 2.0 * (ap * (d - ap)).sqrt()).abs() < 1e-9);
            }
        }
        // O2: no neighbour.
        for a in [5.0, 20.0, 45.0, 80.0] {
            for f in [0.0, 30.0, 90.0, 120.0, 180.0, -150.0] {
                let (ar, fr) = (f64::to_radians(a), f64::to_radians(f));
                let m = if fr.abs() <= FRAC_PI_2 + 1e-12 {
                    1.0
                } else {
                    fr.sin().abs()
                };
                let cc = (theta.cos() * ar.cos() - theta.sin() * ar.sin() * m).max(0.0);
                let want = d * (1.0 - cc * cc).sqrt();
                let got = working_diameter(&case(d, ap, None, a, f, Side::Left));
                assert!(
                    (got - want).abs() < 1e-9,
                    "O2 α {a} A_f {f}: {got} vs {want}"
                );
            }
        }
        // O3: downhill, any ae and side.
        for a in [10.0, 20.0, 40.0] {
            let want = d * (1.0 - (f64::to_radians(a).cos() * theta.cos()).powi(2)).sqrt();
            for ae in [Some(0.05), Some(0.5), None] {
                for s in [Side::Left, Side::Right] {
                    let got = working_diameter(&case(d, ap, ae, a, 180.0, s));
                    assert!((got - want).abs() < 1e-9, "O3 α {a}: {got} vs {want}");
                }
            }
        }
        // O4: contour feed, uncut side uphill.
        for a in [5.0, 20.0, 70.0] {
            let want = d * (f64::to_radians(a) + theta).min(FRAC_PI_2).sin();
            for ae in [0.1, 0.25, 2.0] {
                let g1 = working_diameter(&case(d, ap, Some(ae), a, 90.0, Side::Right));
                let g2 = working_diameter(&case(d, ap, Some(ae), a, -90.0, Side::Left));
                assert!(
                    (g1 - want).abs() < 1e-9 && (g2 - want).abs() < 1e-9,
                    "O4 α {a} ae {ae}"
                );
            }
        }
        // O5: contour feed, uncut side downhill, the cusp point (valid for α ≳ 11° here).
        let ae = 0.25;
        let eps = (ae / d).asin();
        for a in [15.0, 25.0, 40.0] {
            let want = d * (f64::to_radians(a) + eps).sin();
            let got = working_diameter(&case(d, ap, Some(ae), a, 90.0, Side::Left));
            assert!((got - want).abs() < 1e-9, "O5 α {a}: {got} vs {want}");
        }
        // O7: ap ≥ D/2.
        assert_eq!(
            working_diameter(&case(d, 5.0, Some(0.3), 10.0, 45.0, Side::Left)),
            d
        );
        assert_eq!(
            working_diameter(&case(d, 0.3, None, 89.0, 0.0, Side::Left)),
            d
        );
    }

    #[test]
    fn mean_diameter_on_a_flat_cap_and_its_bounds() {
        // Flat, no neighbour: D_mean by area = D(θ/2 − sin 2θ/4)/(1 − cos θ).
        let c = case(10.0, 0.3, None, 0.0, 0.0, Side::Left);
        let th = (1.0f64 - 0.06).acos();
        let want = 10.0 * (th / 2.0 - (2.0 * th).sin() / 4.0) / (1.0 - th.cos());
        assert!((mean_diameter(&c, MeanWeighting::Area, 400) - want).abs() < 1e-3);
        for &(d, ap, ae, a, f, side, _, _) in ORACLE {
            let c = case(d, ap, ae, a, f, side);
            for w in [MeanWeighting::Area, MeanWeighting::ChipThickness] {
                let m = mean_diameter(&c, w, 200);
                // Below the highest point's diameter; it can fall below D_cc where
                // E reaches towards the tip (uncut side downhill).
                assert!(
                    m <= working_diameter(&c) + 1e-9 && m > 0.0,
                    "{c:?} {w:?} {m}"
                );
            }
        }
    }

    #[test]
    fn contact_diameter_is_d_sin_alpha() {
        assert!((contact_diameter(10.0, 30f64.to_radians()) - 5.0).abs() < 1e-12);
    }
}

#[cfg(test)]
mod from_degrees_tests {
    use super::*;

    /// working-diameter.md §2.3: D 10, ap 0.3, ae 0.25, α 20°, A_f 45°, left → 4.1301 mm.
    #[test]
    fn a_case_in_degrees_gives_the_oracle() {
        let c = Case::from_degrees(10.0, 0.3, Some(0.25), false, 20.0, 45.0, Side::Left)
            .expect("in the domain");
        assert!((working_diameter(&c) - 4.1301).abs() < 1e-4);
        // The same feed direction written one turn later.
        let c2 = Case::from_degrees(10.0, 0.3, Some(0.25), false, 20.0, 405.0, Side::Left)
            .expect("in the domain");
        assert!((c2.af - c.af).abs() < 1e-12);
    }

    #[test]
    fn out_of_domain_cases_name_their_argument() {
        let e = |r: Result<Case, String>| r.expect_err("refused");
        assert!(e(Case::from_degrees(
            0.0,
            0.3,
            None,
            false,
            0.0,
            0.0,
            Side::Left
        ))
        .starts_with("d "));
        assert!(e(Case::from_degrees(
            10.0,
            6.0,
            None,
            false,
            0.0,
            0.0,
            Side::Left
        ))
        .starts_with("ap "));
        assert!(e(Case::from_degrees(
            10.0,
            0.3,
            Some(-1.0),
            false,
            0.0,
            0.0,
            Side::Left
        ))
        .starts_with("ae "));
        assert!(e(Case::from_degrees(
            10.0,
            0.3,
            None,
            false,
            90.0,
            0.0,
            Side::Left
        ))
        .starts_with("alpha "));
        assert!(e(Case::from_degrees(
            10.0,
            0.3,
            None,
            false,
            0.0,
            f64::NAN,
            Side::Left
        ))
        .starts_with("af "));
        let c = Case::from_degrees(10.0, 0.3, Some(f64::INFINITY), false, 10.0, 0.0, Side::Left)
            .expect("no neighbour");
        assert_eq!(c.neighbour, Neighbour::None);
    }
}
