//! Which milling direction loads the spindle least (paper 000, thesis 3):
//! candidate paths of one surface (given, or drop-cutter rasters at several
//! feed directions) each go through spindle control, and are ranked by the
//! dynamic-load indicators of the speeds it writes. The part's analyses are
//! built once for all candidates.

use crate::pipeline::{run, Context, PassError};
use crate::speed::{SpeedParams, SpeedPass, Summary};
use millplan_models::cutter::Shape;
use millplan_nc::Program;
use millplan_sim::raster::{raster, RasterParams};

/// The indicator candidates are ranked by (smaller is better).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RankBy {
    /// Total variation of the spindle speed, Σ|Δn|.
    TotalVariation,
    /// Largest speed step between successive points.
    MaxStep,
    /// Largest spindle acceleration demand.
    Accel,
    /// Integral of the spindle speed over the path, Σ n·Δs.
    Integral,
}

impl RankBy {
    pub fn key(self, s: &Summary) -> f64 {
        let i = &s.indicators;
        match self {
            RankBy::TotalVariation => i.total_variation,
            RankBy::MaxStep => i.max_step,
            RankBy::Accel => i.max_accel,
            RankBy::Integral => i.speed_integral,
        }
    }
}

/// A candidate path.
pub struct Candidate {
    pub name: String,
    pub program: Program,
}

/// A candidate with what spindle control made of it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Ranked {
    pub rank: usize,
    pub name: String,
    pub summary: Summary,
}

/// Drop-cutter rasters over the context's part, one per feed direction (degrees).
pub fn raster_candidates(
    cx: &Context,
    shape: Shape,
    angles: &[f64],
    stepover: f64,
    step: f64,
) -> Result<Vec<Candidate>, PassError> {
    let (Some(mesh), Some(part)) = (cx.mesh(), cx.drop_mesh()) else {
        return Err(PassError::NeedsPart { pass: "directions" });
    };
    let bounds = mesh.bounds();
    Ok(angles
        .iter()
        .map(|&angle| {
            let mut rp = RasterParams::new(shape);
            rp.angle_deg = angle;
            rp.stepover = stepover;
            rp.step = step;
            Candidate {
                name: format!("raster {angle}°"),
                program: cx.time(&format!("raster {angle}°"), || raster(part, &bounds, &rp)),
            }
        })
        .collect())
}

/// Each candidate through spindle control, ranked by `by` (best first).
pub fn rank(
    candidates: Vec<Candidate>,
    cx: &Context,
    params: &SpeedParams,
    by: RankBy,
) -> Result<Vec<Ranked>, PassError> {
    let mut out = Vec::with_capacity(candidates.len());
    for mut c in candidates {
        let mut pass = SpeedPass::new(SpeedParams {
            keep_rows: false,
            ..*params
        });
        run(&mut [&mut pass], &mut c.program, cx).map_err(|e| match e {
            PassError::Input { pass, message } => PassError::Input {
                pass,
                message: format!("{}: {message}", c.name),
            },
            e => e,
        })?;
        if let Some(summary) = pass.summary {
            out.push(Ranked {
                rank: 0,
                name: c.name,
                summary,
            });
        }
    }
    out.sort_by(|x, y| by.key(&x.summary).total_cmp(&by.key(&y.summary)));
    for (k, r) in out.iter_mut().enumerate() {
        r.rank = k + 1;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::Machine;
    use millplan_geom::analytic::{tessellate, DemoSurface};

    #[test]
    fn rasters_are_ranked_and_the_part_is_analysed_once() {
        let mesh = tessellate(&DemoSurface::default(), 1.5);
        let cx = Context::new(Machine::default())
            .with_part(&mesh)
            .verifying();
        let cands = raster_candidates(&cx, Shape::Ball { radius: 5.0 }, &[0.0, 90.0], 3.0, 1.5)
            .expect("rasters");
        let r = rank(
            cands,
            &cx,
            &SpeedParams::new(63.0, 0.125, 2, 0.3),
            RankBy::TotalVariation,
        )
        .expect("ranks");
        assert_eq!(r.len(), 2);
        assert!(r[0].summary.indicators.total_variation <= r[1].summary.indicators.total_variation);
        assert_eq!((r[0].rank, r[1].rank), (1, 2));
        let builds = cx
            .timings()
            .iter()
            .filter(|t| t.name.starts_with("surface"))
            .count();
        assert_eq!(builds, 1, "{:?}", cx.timings());
    }
}
