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
