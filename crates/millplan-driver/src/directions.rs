//! `millplan directions`: the generated rasters' arguments and size, the
//! run (`run_command`), and the ranking as JSON and text.

use crate::check::{arg, raster_spacing, tool_shape, Range};
use millplan_models::cutter::Shape;
use millplan_plan::directions::Ranked;
use millplan_sim::raster::{estimate, RasterParams};
use serde::Serialize;
use std::fmt::Write as _;

mod command;
pub use command::{run_command, DirectionsCommand};

/// The share of the bounds' width the size estimate of a raster allows
/// for (the estimate's margin).
const ESTIMATE_MARGIN: f64 = 0.1;

/// The rasters to generate over `bounds`: the cutter of `tool`, one raster
/// per angle at `stepover` and `step`. Returns the cutter, the points of
/// all rasters and the bytes they take.
pub fn rasters(
    tool: &str,
    angles: &[f64],
    (stepover, step): (f64, f64),
    bounds: &millplan_geom::Aabb,
) -> Result<(Shape, f64, f64), String> {
    let shape = tool_shape("--tool", tool)?;
    let d = 2.0 * shape.radius();
    for angle in angles {
        arg("--angles", *angle, Range::from(-360.0, 360.0, "degrees"))?;
    }
    raster_spacing(d, stepover, step)?;
    let mut p = RasterParams::new(shape);
    (p.stepover, p.step) = (stepover, step);
    let e = estimate(bounds, &p, ESTIMATE_MARGIN);
    let n = angles.len() as f64;
    Ok((shape, e.points * n, e.bytes * n))
}

/// The rasters of [`rasters`] within `max_moves` points: the cutter and
/// the bytes they take; too many points is an error saying what made them.
pub fn rasters_within(
    tool: &str,
    angles: &[f64],
    (stepover, step): (f64, f64),
    bounds: &millplan_geom::Aabb,
    max_moves: f64,
) -> Result<(Shape, f64), String> {
    let (shape, n, bytes) = rasters(tool, angles, (stepover, step), bounds)?;
    if !(n <= max_moves) {
        let needs = format!(
            "{} rasters at --stepover {stepover} and --step {step} make {} points",
            angles.len(),
            millplan_geom::limits::amount(n.ceil())
        );
        return Err(millplan_geom::limits::Exceeded::new("moves", needs, max_moves).to_string());
    }
    Ok((shape, bytes))
}

/// One ranked candidate.
#[derive(Serialize)]
pub struct Row<'a> {
    rank: usize,
    path: &'a str,
    indicators: &'a millplan_plan::speed::Indicators,
    d_w: &'a millplan_plan::speed::Stats,
    vc_constant: &'a millplan_plan::speed::Stats,
    points: usize,
}

/// What `directions --json` prints.
#[derive(Serialize)]
pub struct Report<'a> {
    ranked_by: String,
    candidates: Vec<Row<'a>>,
}

impl<'a> Report<'a> {
    /// The ranking by the measure named `by`.
    pub fn new(by: String, ranked: &'a [Ranked]) -> Self {
        let candidates = ranked
            .iter()
            .map(|r| Row {
                rank: r.rank,
                path: &r.name,
                indicators: &r.summary.indicators,
                d_w: &r.summary.d_w,
                vc_constant: &r.summary.vc_constant,
                points: r.summary.points,
            })
            .collect();
        Report {
            ranked_by: by,
            candidates,
        }
    }
}

/// The ranking as a table.
pub fn render_text(ranked: &[Ranked]) -> String {
    let mut o = String::new();
    let _ = writeln!(
        o,
        "{:>4}  {:<40} {:>12} {:>10} {:>12} {:>12} {:>10}",
        "rank", "path", "Σ|Δn|", "max|Δn|", "max accel", "∫n ds", "σ(D_w)"
    );
    for r in ranked {
        let (i, s) = (&r.summary.indicators, &r.summary);
        let _ = writeln!(
            o,
            "{:>4}  {:<40} {:>12.0} {:>10.0} {:>12.0} {:>12.4e} {:>10.3}",
            r.rank, r.name, i.total_variation, i.max_step, i.max_accel, i.speed_integral, s.d_w.std
        );
    }
    o
}
