//! The regression surrogate of thesis 2: the working diameter as first, third and
//! fifth powers of the inclination and of the relative feed direction, with
//! coefficients linear in D (spec `working-diameter.md` §3.2), fitted by least
//! squares on the geometric model — never used as the oracle.
//!
//! Fit ranges: D 6–12 mm, ap 0.1–1.0 mm, inclination 0–85°, relative feed
//! direction 0–180°, both uncut sides, one neighbouring pass at ae = 0.025·D (the
//! thesis's 0.25 mm at D = 10 mm). One coefficient set per side; ap enters
//! linearly (ap and ap·D), since the source form names no ap terms.

use crate::wd::{self, Case, Neighbour, Side};
use std::sync::OnceLock;

/// Number of features: D^m × {1, a, a³, a⁵, f, f³, f⁵, ap} for m ∈ {0, 1}.
const NF: usize = 16;

/// Inclination in units of 90°, feed direction in units of 180° (keeps the
/// fifth powers well conditioned).
fn features(d: f64, ap: f64, alpha: f64, af: f64) -> [f64; NF] {
    let a = alpha / std::f64::consts::FRAC_PI_2;
    let f = af.abs() / std::f64::consts::PI;
    let base = [1.0, a, a.powi(3), a.powi(5), f, f.powi(3), f.powi(5), ap];
    let mut x = [0.0; NF];
    for k in 0..8 {
        x[k] = base[k];
        x[8 + k] = base[k] * d;
    }
    x
}

/// Goodness of fit against the geometric model.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Fit {
    pub samples: usize,
    pub r2: f64,
    /// Root-mean-square error, mm.
    pub rmse: f64,
    /// Mean absolute percentage error, %.
    pub mape: f64,
}

/// Fitted coefficients, one set per uncut side.
#[derive(Clone, Debug, PartialEq)]
pub struct Surrogate {
    pub left: [f64; NF],
    pub right: [f64; NF],
    pub fit: Fit,
}

/// The sample grid of the fit (D, ap, α, A_f, side), with the model's value.
pub fn samples() -> Vec<(f64, f64, f64, f64, Side, f64)> {
    let mut v = Vec::new();
    for d in [6.0, 8.0, 10.0, 12.0] {
        for ap_i in 0..7 {
            let ap = 0.1 + 0.15 * ap_i as f64;
            for a_i in 0..=17 {
                let alpha = (5.0 * a_i as f64).to_radians();
                for f_i in 0..=18 {
                    let af = (10.0 * f_i as f64).to_radians();
                    for side in [Side::Left, Side::Right] {
                        let c = Case {
                            d,
                            ap,
                            neighbour: Neighbour::One(0.025 * d),
                            alpha,
                            af,
                            side,
                        };
                        v.push((d, ap, alpha, af, side, wd::working_diameter(&c)));
                    }
                }
            }
        }
    }
    v
}

impl Surrogate {
    /// Least-squares fit on the given samples.
    pub fn fit(data: &[(f64, f64, f64, f64, Side, f64)]) -> Surrogate {
        let solve_side = |side: Side| {
            let mut ata = [[0.0; NF]; NF];
            let mut atb = [0.0; NF];
            for &(d, ap, a, f, s, y) in data {
                if s != side {
                    continue;
                }
                let x = features(d, ap, a, f);
                for i in 0..NF {
                    atb[i] += x[i] * y;
                    for j in 0..NF {
                        ata[i][j] += x[i] * x[j];
                    }
                }
            }
            solve(ata, atb)
        };
        let mut s = Surrogate {
            left: solve_side(Side::Left),
            right: solve_side(Side::Right),
            fit: Fit::default(),
        };
        s.fit = s.evaluate(data);
        s
    }

    /// The surrogate fitted on [`samples`] (computed once, on first use).
    pub fn standard() -> &'static Surrogate {
        static S: OnceLock<Surrogate> = OnceLock::new();
        S.get_or_init(|| Surrogate::fit(&samples()))
    }

    pub fn predict_raw(&self, d: f64, ap: f64, alpha: f64, af: f64, side: Side) -> f64 {
        let x = features(d, ap, alpha, af);
        let c = if side == Side::Left {
            &self.left
        } else {
            &self.right
        };
        x.iter()
            .zip(c)
            .map(|(a, b)| a * b)
            .sum::<f64>()
            .clamp(wd::contact_diameter(d, alpha).min(d), d)
    }

    pub fn predict(&self, c: &Case) -> f64 {
        self.predict_raw(c.d, c.ap, c.alpha, c.af, c.side)
    }

    /// R², RMSE and MAPE of the surrogate on samples.
    pub fn evaluate(&self, data: &[(f64, f64, f64, f64, Side, f64)]) -> Fit {
        let n = data.len() as f64;
        let mean = data.iter().map(|s| s.5).sum::<f64>() / n;
        let (mut ss_res, mut ss_tot, mut ape) = (0.0, 0.0, 0.0);
        for &(d, ap, a, f, side, y) in data {
            let e = self.predict_raw(d, ap, a, f, side) - y;
            ss_res += e * e;
            ss_tot += (y - mean) * (y - mean);
            ape += (e / y).abs();
        }
        Fit {
            samples: data.len(),
            r2: 1.0 - ss_res / ss_tot,
            rmse: (ss_res / n).sqrt(),
            mape: 100.0 * ape / n,
        }
    }
}

/// Gaussian elimination with partial pivoting (the normal equations are 16×16).
fn solve(mut a: [[f64; NF]; NF], mut b: [f64; NF]) -> [f64; NF] {
    for col in 0..NF {
        let piv = (col..NF)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
            .unwrap_or(col);
        a.swap(col, piv);
        b.swap(col, piv);
        let p = a[col][col];
        if p.abs() < 1e-300 {
            continue;
        }
        let pivot_row = a[col];
        for row in col + 1..NF {
            let f = a[row][col] / p;
            for (x, y) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= f * y;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; NF];
    for row in (0..NF).rev() {
        let s: f64 = (row + 1..NF).map(|k| a[row][k] * x[k]).sum();
        x[row] = if a[row][row].abs() < 1e-300 {
            0.0
        } else {
            (b[row] - s) / a[row][row]
        };
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solver_recovers_a_known_linear_model() {
        // y = 1 + 2a − 0.5f + 0.3·D·a³ exactly representable.
        let mut data = Vec::new();
        for d in [6.0, 9.0, 12.0] {
            for ai in 0..10 {
                for fi in 0..10 {
                    for api in 0..3 {
                        let (a, f, ap) =
                            (0.15 * ai as f64, 0.3 * fi as f64, 0.1 + 0.3 * api as f64);
                        let (an, fnn) = (a / std::f64::consts::FRAC_PI_2, f / std::f64::consts::PI);
                        let y = 1.0 + 2.0 * an - 0.5 * fnn + 0.3 * d * an.powi(3) + 0.2 * ap;
                        data.push((d, ap, a, f, Side::Left, y));
                    }
                }
            }
        }
        let s = Surrogate::fit(&data);
        assert!(
            (s.left[0] - 1.0).abs() < 1e-8
                && (s.left[1] - 2.0).abs() < 1e-8
                && (s.left[10] - 0.3).abs() < 1e-8
                && (s.left[7] - 0.2).abs() < 1e-8
        );
    }

    #[test]
    fn surrogate_fits_the_geometric_model() {
        let s = Surrogate::standard();
        eprintln!("surrogate fit: {:?}", s.fit);
        assert!(s.fit.r2 > 0.9, "{:?}", s.fit);
        assert!(s.fit.rmse < 0.6, "{:?}", s.fit);
    }
}
