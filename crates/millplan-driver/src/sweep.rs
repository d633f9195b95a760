//! `millplan wd-sweep`: the study's design checked, and the regression
//! surrogate's fit against the geometric model.

use crate::check::{arg, Range, MAX_TOOL_D};
pub use millplan_models::regression::Fit;
use millplan_models::regression::{samples, Surrogate};
pub use millplan_report::sweep::Design;

/// Every value in its range: a feed-direction step of 1e-300 would never end.
pub fn check(d: &Design) -> Result<(), String> {
    for v in &d.d {
        arg("--d", *v, Range::positive(MAX_TOOL_D, "mm"))?;
    }
    for ap in &d.ap {
        arg("--ap", *ap, Range::positive(MAX_TOOL_D / 2.0, "mm"))?;
    }
    for ae in &d.ae {
        arg("--ae", *ae, Range::from(0.0, MAX_TOOL_D, "mm"))?;
    }
    for al in &d.alpha {
        arg("--alpha", *al, Range::from(0.0, 89.9, "degrees"))?;
    }
    arg("--af-step", d.af_step, Range::from(0.1, 180.0, "degrees"))?;
    d.check()
}

/// The surrogate fitted to the thesis's samples, and how well it matches.
pub fn fit() -> Fit {
    Surrogate::fit(&samples()).fit
}

/// The sweep's tables and plots as files: the CSV and the HTML page of
/// `fit` (when asked for).
pub fn files(d: &Design, fit: Option<&Fit>) -> (String, String) {
    let (csv, figures) = millplan_report::sweep::sweep(d);
    let html = millplan_report::sweep::page(&figures, fit);
    (csv, html)
}

/// The surrogate's fit as `--json` prints it.
#[derive(Debug, serde::Serialize)]
pub struct FitJson {
    pub samples: usize,
    pub r2: f64,
    pub rmse_mm: f64,
    pub mape_percent: f64,
}

/// What `millplan wd-sweep` prints: the files written and the fit.
#[derive(Debug, serde::Serialize)]
pub struct SweepSummary {
    pub csv: String,
    pub html: String,
    pub fit: Option<FitJson>,
}

impl SweepSummary {
    pub fn new(csv: String, html: String, fit: Option<&Fit>) -> SweepSummary {
        SweepSummary {
            csv,
            html,
            fit: fit.map(|f| FitJson {
                samples: f.samples,
                r2: f.r2,
                rmse_mm: f.rmse,
                mape_percent: f.mape,
            }),
        }
    }

    /// The line on the fit, printed before the files are written.
    pub fn fit_text(f: &Fit) -> String {
        format!(
            "regression surrogate: {} samples, R² {:.4}, RMSE {:.4} mm, MAPE {:.2} %",
            f.samples, f.r2, f.rmse, f.mape
        )
    }

    /// The files written, as text.
    pub fn text(&self) -> String {
        format!("wrote {} and {}\n", self.csv, self.html)
    }
}
