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
    /// The file a stock specification reads (`stl:FILE`), if any: an input of
    /// the run, which no output may replace. `None` also for a spec that
    /// does not parse (its error comes where it is parsed).
    pub fn file_of(spec: &str) -> Option<PathBuf> {
        match StockSpec::parse(spec) {
            Ok(StockSpec::Stl(p)) => Some(p),
            _ => None,
        }
    }

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

/// Why a stock cannot be built from its spec.
#[derive(Clone, Debug, PartialEq)]
pub enum StockError {
    /// `box:auto`/`cylinder:auto` on a program without a cutting move.
    NoCut,
    /// `offset:MM` without the part.
    NeedsPart,
    /// `stl:FILE` whose mesh is empty or not closed.
    Blank(String),
    /// The dexels would take more memory than the limit.
    Memory(millplan_geom::limits::Exceeded),
}

impl std::fmt::Display for StockError {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            StockError::NoCut => write!(f, "no cutting move to take the stock's bounds from"),
            StockError::NeedsPart => write!(f, "--stock offset:MM needs the part: give --stl"),
            StockError::Blank(m) => write!(f, "{m}"),
            StockError::Memory(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for StockError {}

impl StockSpec {
    /// The stock before the program whose cutting strokes are `s`, as this
    /// spec names it, at cell size `res`: `part` is the part for `offset:`,
    /// `blank` the mesh of `stl:FILE` (read by the caller). Refused before
    /// any allocation when `copies` of its dexels (2 for a run that keeps
    /// the stock before the program beside the copy it cuts) would take more
    /// than `memory` bytes.
    pub fn build(
        &self,
        res: f64,
        s: &Strokes,
        (part, blank): (Option<&TriMesh>, Option<&TriMesh>),
        (memory, copies): (u64, u32),
    ) -> Result<Stock, StockError> {
        let check = |min: DVec2, max: DVec2| {
            let g = Grid::covering(min, max, res);
            let bytes = g.cells() as f64 * super::BYTES_PER_CELL * f64::from(copies.max(1));
            if bytes <= memory as f64 {
                return Ok(());
            }
            let held = if copies > 1 {
                ", held twice (the stock before the program and the copy a run cuts),"
            } else {
                ""
            };
            let needs = format!(
                "a stock of {} × {} dexels at --resolution {res}{held} would take about {} MB",
                g.nx,
                g.ny,
                millplan_geom::limits::amount((bytes / 1e6).ceil())
            );
            let limit = (memory / 1_000_000) as f64;
            Err(StockError::Memory(millplan_geom::limits::Exceeded::new(
                "memory", needs, limit,
            )))
        };
        Ok(match self {
            StockSpec::BoxAuto { margin } => {
                let (lo, hi) = auto_box(s, *margin).ok_or(StockError::NoCut)?;
                check(lo.truncate(), hi.truncate())?;
                Stock::block(lo, hi, res)
            }
            StockSpec::Box { min, max } => {
                check(min.truncate(), max.truncate())?;
                Stock::block(*min, *max, res)
            }
            StockSpec::CylinderAuto { margin } => {
                let (lo, hi) = auto_box(s, *margin).ok_or(StockError::NoCut)?;
                let c = (lo.truncate() + hi.truncate()) / 2.0;
                let r = (hi.truncate() - c).length();
                check(c - DVec2::splat(r), c + DVec2::splat(r))?;
                Stock::cylinder(c, r, lo.z, hi.z, res)
            }
            StockSpec::Cylinder { centre, z0, z1, d } => {
                check(
                    *centre - DVec2::splat(d / 2.0),
                    *centre + DVec2::splat(d / 2.0),
                )?;
                Stock::cylinder(*centre, d / 2.0, *z0, *z1, res)
            }
            StockSpec::Stl(p) => {
                let mesh = blank.ok_or_else(|| {
                    StockError::Blank(format!("{}: the blank was not read", p.display()))
                })?;
                closed_blank(p, mesh)?;
                let b = mesh.bounds();
                check(b.min.truncate(), b.max.truncate())?;
                Stock::from_solid(mesh, res)
            }
            StockSpec::Offset(mm) => {
                let part = part.ok_or(StockError::NeedsPart)?;
                let b = part.bounds();
                let e = DVec2::splat(*mm);
                check(b.min.truncate() - e, b.max.truncate() + e)?;
                offset_stock(part, *mm, res)
            }
        })
    }
}

/// A cast blank must be a non-empty closed mesh.
fn closed_blank(p: &std::path::Path, mesh: &TriMesh) -> Result<(), StockError> {
    if mesh.is_empty() {
        return Err(StockError::Blank(format!(
            "{}: no triangles: not a blank",
            p.display()
        )));
    }
    let e = mesh.edge_report();
    if e.open > 0 || e.non_manifold > 0 {
        return Err(StockError::Blank(format!(
            "{}: a stock blank must be a closed mesh; this one has {} open and {} non-manifold edges",
            p.display(),
            e.open,
            e.non_manifold
        )));
    }
    Ok(())
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
