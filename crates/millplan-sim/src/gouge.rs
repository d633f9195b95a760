//! Gouge check: sample every cutting move (and optionally the rapids) at a chord
//! step and compare the tool tip with the drop-cutter height there; a tip lower
//! than the drop height by more than a tolerance cuts into the part.

use crate::dropcutter::DropMesh;
use millplan_geom::{DVec2, DVec3};
use millplan_models::cutter::Shape;
use millplan_nc::{MoveKind, Operation, Orient, Program};
use rayon::prelude::*;

#[derive(Clone, Copy, Debug)]
pub struct GougeParams {
    /// Sampling step along each move, mm.
    pub step: f64,
    /// Depth below the drop height that counts as a gouge, mm.
    pub tol: f64,
    /// Check rapids too.
    pub rapids: bool,
}

impl Default for GougeParams {
    fn default() -> Self {
        GougeParams {
            step: 0.1,
            tol: 0.005,
            rapids: false,
        }
    }
}

/// The deepest gouge of one move.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Gouge {
    pub operation: usize,
    /// Move index within the operation.
    #[serde(rename = "move")]
    pub mv: usize,
    /// Source line of the move.
    pub line: u32,
    /// Tool tip where it is deepest, part coordinates.
    pub at: [f64; 3],
    /// How far the tip is below the drop height, mm.
    pub depth: f64,
}

#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct GougeReport {
    pub moves_checked: usize,
    pub points_checked: usize,
    /// Moves left out: tool not along +Z (5-axis), canned cycles, unknown tool.
    pub moves_skipped: usize,
    pub gouges: Vec<Gouge>,
    pub max_depth: f64,
}

/// Checks a program against the part. `shape` gives the cutter of an operation
/// (`None` skips the operation).
pub fn check(
    p: &Program,
    part: &DropMesh,
    shape: impl Fn(&Operation) -> Option<Shape>,
    g: &GougeParams,
) -> GougeReport {
    let mut rep = GougeReport::default();
    // (operation, move, sample point, shape index)
    let mut samples: Vec<(u32, u32, DVec3, Shape)> = Vec::new();
    for (oi, op) in p.operations.iter().enumerate() {
        let Some(sh) = shape(op) else {
            rep.moves_skipped += op.moves.len();
            continue;
        };
        let to_part = |v: DVec3| op.frame.map(|f| f.to_parent(v)).unwrap_or(v);
        let axis_part = |m: &millplan_nc::Move| match op.orient(m) {
            Some(Orient::Vector(v)) => op.frame.map(|f| f.dir_to_parent(*v)).unwrap_or(*v),
            Some(Orient::Rotary(r)) if r.iter().flatten().any(|a| a.abs() > 1e-9) => DVec3::X,
            _ => op
                .frame
                .map(|f| f.dir_to_parent(DVec3::Z))
                .unwrap_or(DVec3::Z),
        };
        for (i, m) in op.moves.iter().enumerate() {
            let wanted = match m.kind {
                MoveKind::Linear | MoveKind::Arc => true,
                MoveKind::Rapid => g.rapids,
                MoveKind::Cycle => false,
            };
            let Some(start) = op.move_start(i) else {
                continue;
            };
            if !wanted {
                if m.kind == MoveKind::Cycle {
                    rep.moves_skipped += 1;
                }
                continue;
            }
            if (axis_part(m) - DVec3::Z).length() > 1e-6 {
                rep.moves_skipped += 1;
                continue;
            }
            rep.moves_checked += 1;
            let pts: Vec<DVec3> = match (m.kind, op.arcs.get(m.aux as usize)) {
                (MoveKind::Arc, Some(a)) => {
                    let len = a.length(start, m.end);
                    let n = ((len / g.step).ceil() as usize).max(1);
                    (0..=n)
                        .map(|k| a.point_at(start, m.end, k as f64 / n as f64))
                        .collect()
                }
                _ => {
                    let len = (m.end - start).length();
                    let n = ((len / g.step).ceil() as usize).max(1);
                    (0..=n)
                        .map(|k| start.lerp(m.end, k as f64 / n as f64))
                        .collect()
                }
            };
            samples.extend(
                pts.into_iter()
                    .map(|q| (oi as u32, i as u32, to_part(q), sh)),
            );
        }
    }
    rep.points_checked = samples.len();
    let depths: Vec<f64> = samples
        .par_iter()
        .map(|(_, _, q, sh)| {
            part.drop(sh, DVec2::new(q.x, q.y))
                .map(|d| d.z - q.z)
                .unwrap_or(f64::NEG_INFINITY)
        })
        .collect();
    for ((oi, mi, q, _), d) in samples.iter().zip(&depths) {
        if *d > g.tol {
            let (oi, mi) = (*oi as usize, *mi as usize);
            let line = p.operations[oi].moves[mi].line;
            match rep.gouges.last_mut() {
                Some(last) if last.operation == oi && last.mv == mi => {
                    if *d > last.depth {
                        last.depth = *d;
                        last.at = q.to_array();
                    }
                }
                _ => rep.gouges.push(Gouge {
                    operation: oi,
                    mv: mi,
                    line,
                    at: q.to_array(),
                    depth: *d,
                }),
            }
            rep.max_depth = rep.max_depth.max(*d);
        }
    }
    rep
}
