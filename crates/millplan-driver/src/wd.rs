//! `millplan wd`: one working-diameter case checked, evaluated and printed.

use crate::check::{arg, Range, MAX_TOOL_D, MAX_VC};
pub use millplan_models::wd::Side;
use millplan_models::wd::{self, Case, Neighbour};
use serde::Serialize;
use std::fmt::Write as _;

/// Sample count of the mean diameters over the engaged region.
const MEAN_SAMPLES: usize = 300;

/// The options of `millplan wd`.
#[derive(Clone, Copy, Debug)]
pub struct WdRequest {
    pub d: f64,
    pub ap: f64,
    pub ae: Option<f64>,
    /// The stepover on both sides.
    pub both: bool,
    /// Inclination, degrees.
    pub alpha: f64,
    /// Feed direction, degrees.
    pub af: f64,
    pub side: Side,
    pub vc: Option<f64>,
    /// The regression surrogate rather than the geometric model.
    pub regression: bool,
}

/// The figures of one case.
#[derive(Serialize)]
pub struct WdOutcome {
    d_w: f64,
    d_cc: f64,
    d_mean_area: f64,
    d_mean_chip: f64,
    n: Option<f64>,
    model: &'static str,
    #[serde(skip)]
    vc: Option<f64>,
}

fn check(a: &WdRequest) -> Result<(), String> {
    arg("--d", a.d, Range::positive(MAX_TOOL_D, "mm"))?;
    // The ball model's domain: the stock no thicker than the ball's radius.
    arg("--ap", a.ap, Range::positive(a.d / 2.0, "mm (at most D/2)"))?;
    if let Some(ae) = a.ae {
        arg("--ae", ae, Range::positive(MAX_TOOL_D, "mm"))?;
    }
    if !(0.0..90.0).contains(&a.alpha) {
        return Err(format!(
            "--alpha {}: must be a number from 0 to under 90 degrees",
            a.alpha
        ));
    }
    arg("--af", a.af, Range::from(-360.0, 360.0, "degrees"))?;
    if let Some(vc) = a.vc {
        arg("--vc", vc, Range::positive(MAX_VC, "m/min"))?;
    }
    if a.both && a.ae.is_none() {
        return Err("--both needs --ae".into());
    }
    Ok(())
}

/// Checks the request and evaluates the case.
pub fn run(a: &WdRequest) -> Result<WdOutcome, String> {
    check(a)?;
    let neighbour = match (a.ae, a.both) {
        (None, _) => Neighbour::None,
        (Some(x), false) => Neighbour::One(x),
        (Some(x), true) => Neighbour::Both(x),
    };
    let af = (a.af + 180.0).rem_euclid(360.0) - 180.0;
    let c = Case {
        d: a.d,
        ap: a.ap,
        neighbour,
        alpha: a.alpha.to_radians(),
        af: af.to_radians(),
        side: a.side,
    };
    let d_w = if a.regression {
        millplan_models::regression::Surrogate::standard().predict(&c)
    } else {
        wd::working_diameter(&c)
    };
    Ok(WdOutcome {
        d_w,
        d_cc: wd::contact_diameter(a.d, c.alpha),
        d_mean_area: wd::mean_diameter(&c, wd::MeanWeighting::Area, MEAN_SAMPLES),
        d_mean_chip: wd::mean_diameter(&c, wd::MeanWeighting::ChipThickness, MEAN_SAMPLES),
        n: a.vc.map(|vc| wd::spindle_speed(vc, d_w)),
        model: if a.regression {
            "regression"
        } else {
            "geometric"
        },
        vc: a.vc,
    })
}

impl WdOutcome {
    /// One figure a line.
    pub fn render_text(&self) -> String {
        let mut o = String::new();
        let (dw, dcc) = (self.d_w, self.d_cc);
        let _ = writeln!(
            o,
            "D_w  {dw:.3} mm  (working diameter, highest engaged point)"
        );
        let _ = writeln!(o, "D_cc {dcc:.3} mm  (diameter at the contact point)");
        let _ = writeln!(
            o,
            "D_mean {:.3} mm by area, {:.3} mm by chip thickness (over the engaged region)",
            self.d_mean_area, self.d_mean_chip
        );
        if let (Some(n), Some(vc)) = (self.n, self.vc) {
            let _ = writeln!(o, "n    {n:.0} 1/min for vc = {vc} m/min");
        }
        o
    }
}
