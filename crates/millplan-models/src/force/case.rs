//! One engagement for process design (`millplan cut`): a tool in a planar
//! raster pass, with the loads that follow (§1.4a, §2).

use super::coeffs::Law;
use super::converge::{ConvergedModel, Refine};
use super::deflect::{Bending, Cantilever};
use super::edge::Tool;
use super::engage::{Engagement, PlanarRaster};
use super::feed::Loads;
use super::{Cut, Evaluation, ForceModel, Grid, Summary};
use rayon::prelude::*;

/// A single engagement: tool, law, cut, depth and stepover, tool holding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutCase {
    pub tool: Tool,
    pub law: Law,
    /// The steps: exactly these without `refine`, else the coarsest.
    pub grid: Grid,
    /// Refine the steps until the peaks converge ([`ConvergedModel`]).
    pub refine: Option<Refine>,
    pub cut: Cut,
    /// Axial depth \[mm\].
    pub ap: f64,
    /// Stepover to the earlier pass \[mm\]; None for a slot.
    pub ae: Option<f64>,
    pub holding: Cantilever,
}

/// Forces of a [`CutCase`] and what follows from them.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseResult {
    pub evaluation: Evaluation,
    pub summary: Summary,
    pub bending: Bending,
    pub loads: Loads,
}

/// Evaluates one planar-raster engagement.
pub fn evaluate_case(c: &CutCase) -> Result<CaseResult, String> {
    c.holding.validate()?;
    if !(c.cut.fz > 0.0 && c.cut.fz < 10.0) {
        return Err(format!(
            "feed per tooth {} mm: must be above 0 and under 10",
            c.cut.fz
        ));
    }
    if !(c.cut.rpm > 0.0 && c.cut.rpm.is_finite()) {
        return Err("the spindle speed must be a positive number".into());
    }
    let eng = PlanarRaster::new(&c.tool, c.ap, c.ae, c.cut.lead, c.cut.tilt)?;
    let evaluation = match c.refine {
        Some(r) => ConvergedModel::new(c.tool, c.law, c.grid, r)?.evaluate(&c.cut, &eng),
        None => ForceModel::new(c.tool, c.law, c.grid)?.evaluate(&c.cut, &eng),
    };
    let summary = evaluation.summary();
    Ok(CaseResult {
        bending: c.holding.bend(summary.fxy_max),
        loads: Loads::new(&summary, &c.holding),
        evaluation,
        summary,
    })
}

impl ForceModel {
    /// Evaluates many engagements in parallel (one task per engagement).
    pub fn evaluate_all<E: Engagement + Sync>(&self, jobs: &[(Cut, E)]) -> Vec<Evaluation> {
        jobs.par_iter().map(|(c, e)| self.evaluate(c, e)).collect()
    }
}
