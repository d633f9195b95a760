//! The initial stock as the user names it: `box:auto[:MARGIN]`,
//! `box:X0,Y0,Z0,X1,Y1,Z1`, `cylinder:auto[:MARGIN]`, `cylinder:CX,CY,Z0,Z1,D`,
//! `stl:FILE` (a closed mesh) or `offset:MM` (the part with a uniform
//! allowance).

use super::path::Strokes;
use super::{Grid, Stock};
use crate::dropcutter::DropMesh;
use millplan_geom::{DVec2, DVec3, TriMesh};
use millplan_models::cutter::Shape;
use std::path::PathBuf;

/// Margin of `box:auto` and `cylinder:auto` when none is given, mm.
pub const AUTO_MARGIN: f64 = 1.0;

#[derive(Clone, Debug, PartialEq)]
pub enum StockSpec {
    /// The cutting moves' bounds: X and Y widened by the tool radius and the
    /// margin, the bottom lowered by the margin, the top at the highest
    /// cutting tip.
    BoxAuto {
        margin: f64,
    },
    Box {
        min: DVec3,
        max: DVec3,
    },
    /// The upright cylinder around `box:auto`'s XY rectangle.
    CylinderAuto {
        margin: f64,
    },
    Cylinder {
        centre: DVec2,
        z0: f64,
        z1: f64,
        d: f64,
    },
    Stl(PathBuf),
    /// The part (`--stl`) grown by this allowance, down to its bounds' bottom.
    Offset(f64),
}

impl StockSpec {
    pub fn parse(s: &str) -> Result<StockSpec, String> {
        let (kind, rest) = s.split_once(':').unwrap_or((s, ""));
        let nums = |want: usize| -> Result<Vec<f64>, String> {
            let v: Result<Vec<f64>, _> = rest.split(',').map(|x| x.trim().parse::<f64>()).collect();
            match v {
                Ok(v) if v.len() == want && v.iter().all(|x| x.is_finite()) => Ok(v),
                _ => Err(format!(
                    "`{s}`: {kind} takes {want} finite numbers separated by commas"
                )),
            }
        };
        let margin = |rest: &str| -> Result<f64, String> {
            match rest.strip_prefix("auto") {
                Some("") => Ok(AUTO_MARGIN),
                Some(m) => match m.strip_prefix(':').map(|m| m.trim().parse::<f64>()) {
                    Some(Ok(v)) if v.is_finite() && v >= 0.0 => Ok(v),
                    _ => Err(format!(
                        "`{s}`: the margin after `auto:` must be a number ≥ 0"
                    )),
                },
                None => Err(String::new()),
            }
        };
        match kind.to_ascii_lowercase().as_str() {
            "box" => {
                if rest.starts_with("auto") {
                    return margin(rest).map(|m| StockSpec::BoxAuto { margin: m });
                }
                let v = nums(6)?;
                let (min, max) = (DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]));
                if !(max.x > min.x && max.y > min.y && max.z > min.z) {
                    return Err(format!("`{s}`: each of X1, Y1, Z1 must exceed X0, Y0, Z0"));
                }
                Ok(StockSpec::Box { min, max })
            }
            "cylinder" | "cyl" => {
                if rest.starts_with("auto") {
                    return margin(rest).map(|m| StockSpec::CylinderAuto { margin: m });
                }
                let v = nums(5)?;
                if !(v[3] > v[2] && v[4] > 0.0) {
                    return Err(format!("`{s}`: needs Z1 > Z0 and a diameter > 0 (CX,CY,Z0,Z1,D)"));
                }
                Ok(StockSpec::Cylinder {
                    centre: DVec2::new(v[0], v[1]),
                    z0: v[2],
                    z1: v[3],
                    d: v[4],
                })
            }
            "stl" if !rest.is_empty() => Ok(StockSpec::Stl(PathBuf::from(rest))),
            "offset" => match rest.trim().parse::<f64>() {
                Ok(v) if v.is_finite() && v >= 0.0 => Ok(StockSpec::Offset(v)),
                _ => Err(format!("`{s}`: offset takes the allowance in mm (≥ 0), e.g. offset:0.5")),
            },
            _ => Err(format!(
                "`{s}`: a stock is box:auto[:MARGIN], box:X0,Y0,Z0,X1,Y1,Z1, cylinder:auto[:MARGIN], cylinder:CX,CY,Z0,Z1,D, stl:FILE or offset:MM"
            )),
        }
    }
}

/// The bounds of the cutting strokes' tips, XY widened by each stroke's tool
/// radius; `None` without cutting strokes.
pub fn cutting_bounds(s: &Strokes) -> Option<(DVec3, DVec3)> {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for st in s.strokes.iter().filter(|s| !s.rapid) {
        let r = s.tools[st.tool as usize].radius();
        let e = DVec3::new(r, r, 0.0);
        for p in [st.p0, st.p1] {
            lo = lo.min(p - e);
            hi = hi.max(p + e);
        }
    }
    (lo.x <= hi.x).then_some((lo, hi))
}

/// The box of `box:auto` with `margin`.
pub fn auto_box(s: &Strokes, margin: f64) -> Option<(DVec3, DVec3)> {
    let (lo, hi) = cutting_bounds(s)?;
    let m = DVec3::new(margin, margin, margin);
    let top = hi.z.max(lo.z + margin.max(1e-3));
    Some((lo - m, DVec3::new(hi.x + margin, hi.y + margin, top)))
}

/// The part grown by `allowance` and everything under that down to the
/// bottom of its bounds: each cell's top is where a ball of that radius
/// resting on the part has its centre.
pub fn offset_stock(part: &TriMesh, allowance: f64, res: f64) -> Stock {
    let b = part.bounds();
    let e = DVec2::splat(allowance);
    let grid = Grid::covering(b.min.truncate() - e, b.max.truncate() + e, res);
    let dm = DropMesh::new(part);
    let ball = Shape::Ball {
        radius: allowance.max(1e-6),
    };
    let bottom = b.min.z - allowance;
    Stock::from_columns(grid, |x, y| match dm.drop(&ball, DVec2::new(x, y)) {
        Some(d) => vec![[bottom, d.z + allowance.max(1e-6)]],
        None => Vec::new(),
    })
}
