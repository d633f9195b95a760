//! The stock after the program against the part: at each facet of the part,
//! the material left above it (positive) or the depth cut into it (negative,
//! a gouge), along the facet's normal.

use super::Stock;
use millplan_geom::{DVec3, TriMesh};
use rayon::prelude::*;

/// Remaining material over a part.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Remaining {
    /// Per facet, mm: left stock (> 0) or gouge (< 0); NaN outside the stock's
    /// grid.
    #[serde(skip)]
    pub per_facet: Vec<f64>,
    /// Facets measured.
    pub facets: usize,
    pub min: f64,
    pub max: f64,
    pub mean: f64,
    /// Facets cut into by more than the tolerance.
    pub gouged: usize,
    /// Histogram: bins of equal width from `min` to `max`.
    pub histogram: Vec<Bin>,
}

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Bin {
    pub from: f64,
    pub to: f64,
    pub facets: usize,
}

/// Measures up to `reach` mm each way along every facet's normal (farther
/// is reported as ±reach). A facet whose normal points up by more than 17°
/// is measured exactly along its cell's column and scaled to the normal; a
/// steeper one by stepping along the normal at a quarter cell and bisecting.
pub fn remaining(stock: &Stock, part: &TriMesh, reach: f64, tol: f64) -> Remaining {
    let g = stock.grid;
    let per_facet: Vec<f64> = (0..part.len())
        .into_par_iter()
        .map(|t| {
            let [a, b, c] = part.corners(t);
            let q = (a + b + c) / 3.0;
            let n = part.facet_normal(t);
            let Some((i, j)) = g.cell_of(q.x, q.y) else {
                return f64::NAN;
            };
            if n.z > 0.3 {
                column_thickness(stock, i, j, q.z, reach / n.z) * n.z
            } else {
                march(stock, q, n, g.res * 0.25, reach)
            }
        })
        .collect();
    let vals: Vec<f64> = per_facet
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    let facets = vals.len();
    let (min, max) = vals
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        });
    let mean = if facets > 0 {
        vals.iter().sum::<f64>() / facets as f64
    } else {
        f64::NAN
    };
    let gouged = vals.iter().filter(|v| **v < -tol).count();
    let histogram = histogram(&vals, min, max, 20);
    Remaining {
        per_facet,
        facets,
        min: if facets > 0 { min } else { f64::NAN },
        max: if facets > 0 { max } else { f64::NAN },
        mean,
        gouged,
        histogram,
    }
}

fn histogram(vals: &[f64], min: f64, max: f64, bins: usize) -> Vec<Bin> {
    if vals.is_empty() {
        return Vec::new();
    }
    let w = ((max - min) / bins as f64).max(1e-9);
    let mut h = vec![0usize; bins];
    for v in vals {
        let k = (((v - min) / w) as usize).min(bins - 1);
        h[k] += 1;
    }
    h.into_iter()
        .enumerate()
        .map(|(k, facets)| Bin {
            from: min + k as f64 * w,
            to: min + (k + 1) as f64 * w,
            facets,
        })
        .collect()
}

/// Vertical thickness at height z of cell (i, j): material above z up to its
/// interval's top (> 0), or, in air, minus the distance down to material.
fn column_thickness(stock: &Stock, i: usize, j: usize, z: f64, reach: f64) -> f64 {
    let iv = stock.intervals(i, j);
    if let Some([_, t]) = iv.iter().find(|[a, b]| z >= *a && z <= *b) {
        return (t - z).min(reach);
    }
    match iv.iter().rev().find(|[_, b]| *b < z) {
        Some([_, b]) => (b - z).max(-reach),
        None => -reach,
    }
}

/// Signed distance from q to the stock's boundary along n.
fn march(stock: &Stock, q: DVec3, n: DVec3, step: f64, reach: f64) -> f64 {
    let inside = stock.contains(q + n * 1e-6);
    let dir = if inside { n } else { -n };
    let steps = (reach / step).ceil() as usize;
    let mut last = 0.0;
    for k in 1..=steps {
        let s = k as f64 * step;
        if stock.contains(q + dir * s) != inside {
            // Bisect between last and s.
            let (mut a, mut b) = (last, s);
            for _ in 0..30 {
                let m = 0.5 * (a + b);
                if stock.contains(q + dir * m) == inside {
                    a = m;
                } else {
                    b = m;
                }
            }
            let d = 0.5 * (a + b);
            return if inside { d } else { -d };
        }
        last = s;
    }
    if inside {
        reach
    } else {
        -reach
    }
}
