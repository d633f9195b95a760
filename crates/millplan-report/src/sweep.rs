//! The working diameter over the study design of thesis 1 (paper 000): a CSV
//! row per case and one SVG plot per tool diameter, stepover, milling side and
//! depth of cut.

use crate::svg::{line_plot, Series};
use millplan_models::wd::{self, Case, Neighbour, Side};
use std::fmt::Write;

/// The grid of cases.
#[derive(Clone, Debug)]
pub struct Design {
    /// Tool diameters, mm.
    pub d: Vec<f64>,
    /// Depths of cut, mm.
    pub ap: Vec<f64>,
    /// Stepovers to the machined neighbour, mm (0: none).
    pub ae: Vec<f64>,
    /// Inclinations, degrees.
    pub alpha: Vec<f64>,
    /// Feed-direction step over 0–180°, degrees.
    pub af_step: f64,
}

impl Design {
    /// Whether every value is in range: diameters and depths positive,
    /// inclinations in [0, 90), the step positive.
    pub fn check(&self) -> Result<(), String> {
        if !(self.af_step > 0.0 && self.af_step.is_finite())
            || self
                .d
                .iter()
                .chain(&self.ap)
                .any(|v| !(*v > 0.0 && v.is_finite()))
            || self.ae.iter().any(|v| !(*v >= 0.0 && v.is_finite()))
            || self.alpha.iter().any(|v| !(0.0..90.0).contains(v))
        {
            return Err(
                "diameters and depths must be positive, stepovers not negative, inclinations in [0, 90), the feed-direction step > 0"
                    .into(),
            );
        }
        Ok(())
    }
}

/// The table (CSV) and the page of plots (HTML body figures) of a design.
pub fn sweep(design: &Design) -> (String, String) {
    let mut csv = String::from("d,ap,ae,alpha_deg,af_deg,uncut_side,milling,d_w,d_cc,n_at_vc63\n");
    let mut html = String::new();
    let colors = [
        "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
    ];
    let steps = (180.0 / design.af_step).round() as usize;
    for &d in &design.d {
        for &ae in &design.ae {
            for side in [Side::Right, Side::Left] {
                // With M3: uncut on the right = climb (down) milling.
                let milling = if side == Side::Right { "down" } else { "up" };
                for &ap in &design.ap {
                    let names: Vec<String> =
                        design.alpha.iter().map(|x| format!("α = {x}°")).collect();
                    let mut series = Vec::new();
                    for (k, &alpha) in design.alpha.iter().enumerate() {
                        let mut pts = Vec::new();
                        for i in 0..=steps {
                            let af = (design.af_step * i as f64).min(180.0);
                            let c = Case {
                                d,
                                ap,
                                neighbour: if ae > 0.0 {
                                    Neighbour::One(ae)
                                } else {
                                    Neighbour::None
                                },
                                alpha: alpha.to_radians(),
                                af: af.to_radians(),
                                side,
                            };
                            let dw = wd::working_diameter(&c);
                            let _ = writeln!(
                                csv,
                                "{d},{ap},{ae},{alpha},{af},{},{milling},{dw:.3},{:.3},{:.1}",
                                if side == Side::Left { "left" } else { "right" },
                                wd::contact_diameter(d, c.alpha),
                                wd::spindle_speed(63.0, dw)
                            );
                            pts.push((af, dw));
                        }
                        series.push(Series {
                            name: &names[k],
                            color: colors[k % colors.len()],
                            points: pts,
                        });
                    }
                    let _ = write!(
                        html,
                        "<figure>{}</figure>",
                        line_plot(
                            &format!("D = {d} mm, ap = {ap} mm, ae = {ae} mm, {milling} milling"),
                            "relative feed direction A_f (°)",
                            "D_w (mm)",
                            &series
                        )
                    );
                }
            }
        }
    }
    (csv, html)
}

/// The whole page around the figures; `fit` adds the surrogate's quality.
pub fn page(figures: &str, fit: Option<&millplan_models::regression::Fit>) -> String {
    let mut html = String::from("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>Working diameter sweep</title></head><body style=\"font-family:sans-serif\"><h1>Working diameter sweep</h1>");
    html.push_str(figures);
    if let Some(f) = fit {
        let _ = write!(
            html,
            "<h2>Regression surrogate (thesis 2)</h2><p>{} samples, R² {:.4}, RMSE {:.4} mm, MAPE {:.2} %</p>",
            f.samples, f.r2, f.rmse, f.mape
        );
    }
    html.push_str("</body></html>");
    html
}
