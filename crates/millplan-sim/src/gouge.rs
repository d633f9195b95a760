//! Gouge check: sample every cutting move (and optionally the rapids) at a chord
//! step and compare the tool tip with the drop-cutter height there; a tip lower
//! than the drop height by more than a tolerance cuts into the part.

use crate::dropcutter::DropMesh;
use millplan_geom::{DVec2, DVec3};
use millplan_models::cutter::Shape;
use millplan_nc::{known, MoveKind, Operation, Program};
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

/// Why moves were left out of a check.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Skipped {
    /// The operation's tool has no geometry and none was given.
    pub no_tool: usize,
    /// The tool is not along +Z (five-axis), or its axis is known only as
    /// machine angles.
    pub tilted: usize,
    /// Canned-cycle holes.
    pub cycles: usize,
    /// From or to a position the program has not set.
    pub unknown_position: usize,
}

impl Skipped {
    pub fn total(&self) -> usize {
        self.no_tool + self.tilted + self.cycles + self.unknown_position
    }
}

#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct GougeReport {
    pub moves_checked: usize,
    pub points_checked: usize,
    /// Moves left out, all reasons.
    pub moves_skipped: usize,
    pub skipped: Skipped,
    pub gouges: Vec<Gouge>,
    pub max_depth: f64,
}

/// Memory per sample point of a check: the sample and its depth.
pub const BYTES_PER_SAMPLE: f64 =
    (std::mem::size_of::<(u32, u32, DVec3, Shape)>() + std::mem::size_of::<f64>()) as f64;

/// How many points [`check`] would sample (an upper bound: moves it would
/// skip for a tilted tool are counted), in one pass over the moves without
/// allocating: a step of 1e-9 is refused from this, never attempted.
pub fn samples(p: &Program, shape: impl Fn(&Operation) -> Option<Shape>, g: &GougeParams) -> f64 {
    let mut n = 0.0;
    for op in &p.operations {
        if shape(op).is_none() {
            continue;
        }
        for (i, m) in op.moves.iter().enumerate() {
            let wanted = match m.kind {
                MoveKind::Linear | MoveKind::Arc(_) => true,
                MoveKind::Rapid => g.rapids,
                MoveKind::Cycle(_) => false,
            };
            let (Some(start), Some(end)) = (op.known_start(i), known(m.end)) else {
                continue;
            };
            if wanted {
                let len = match op.arc(m) {
                    Some(a) => a.length(start, end),
                    None => (end - start).length(),
                };
                n += (len / g.step).ceil().max(1.0) + 1.0;
            }
        }
    }
    n
}

/// Checks a program against the part. `shape` gives the cutter of an operation
/// (`None` skips the operation).
pub fn check(
    p: &Program,
    part: &DropMesh,
    shape: impl Fn(&Operation) -> Option<Shape>,
    g: &GougeParams,
) -> GougeReport {
    check_with_progress(p, part, shape, g, &|_, _| {})
}

/// Sample points checked between two calls of a progress callback.
pub const PROGRESS_EVERY: usize = 16_384;

/// [`check`], calling `progress(done, total)` with the sample points checked
/// so far (from any thread, every [`PROGRESS_EVERY`] points and at the end).
pub fn check_with_progress(
    p: &Program,
    part: &DropMesh,
    shape: impl Fn(&Operation) -> Option<Shape>,
    g: &GougeParams,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> GougeReport {
    let mut rep = GougeReport::default();
    // (operation, move, sample point, shape index)
    let mut samples: Vec<(u32, u32, DVec3, Shape)> = Vec::new();
    for (oi, op) in p.operations.iter().enumerate() {
        let wanted = |k: MoveKind| match k {
            MoveKind::Linear | MoveKind::Arc(_) => true,
            MoveKind::Rapid => g.rapids,
            MoveKind::Cycle(_) => false,
        };
        let Some(sh) = shape(op) else {
            rep.skipped.no_tool += op.moves.iter().filter(|m| wanted(m.kind)).count();
            continue;
        };
        let to_part = |v: DVec3| op.frame.map(|f| f.to_parent(v)).unwrap_or(v);
        // The tool axis in part coordinates; `None` when only machine angles
        // say where it points.
        let axis_part = |m: &millplan_nc::Move| -> Option<DVec3> {
            let a = match op.orient(m) {
                Some(o) => match o.axis {
                    Some(v) => v,
                    None if o.is_tilted() => return None,
                    None => DVec3::Z,
                },
                None => DVec3::Z,
            };
            Some(op.frame.map(|f| f.dir_to_parent(a)).unwrap_or(a))
        };
        for (i, m) in op.moves.iter().enumerate() {
            if !wanted(m.kind) {
                if m.cycle().is_some() {
                    rep.skipped.cycles += 1;
                }
                continue;
            }
            let (Some(start), Some(end)) = (op.known_start(i), known(m.end)) else {
                rep.skipped.unknown_position += 1;
                continue;
            };
            if axis_part(m).is_none_or(|a| (a - DVec3::Z).length() > 1e-6) {
                rep.skipped.tilted += 1;
                continue;
            }
            rep.moves_checked += 1;
            let pts: Vec<DVec3> = match op.arc(m) {
                Some(a) => {
                    let len = a.length(start, end);
                    let n = ((len / g.step).ceil() as usize).max(1);
                    (0..=n)
                        .map(|k| a.point_at(start, end, k as f64 / n as f64))
                        .collect()
                }
                None => {
                    let len = (end - start).length();
                    let n = ((len / g.step).ceil() as usize).max(1);
                    (0..=n)
                        .map(|k| start.lerp(end, k as f64 / n as f64))
                        .collect()
                }
            };
            samples.extend(
                pts.into_iter()
                    .map(|q| (oi as u32, i as u32, to_part(q), sh)),
            );
        }
    }
    rep.moves_skipped = rep.skipped.total();
    rep.points_checked = samples.len();
    let total = samples.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let depths: Vec<f64> = samples
        .par_iter()
        .map(|(_, _, q, sh)| {
            let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if k.is_multiple_of(PROGRESS_EVERY) || k == total {
                progress(k, total);
            }
            let c = DVec2::new(q.x, q.y);
            let depth = part
                .drop(sh, c)
                .map(|d| d.z - q.z)
                .unwrap_or(f64::NEG_INFINITY);
            if depth <= g.tol {
                return depth;
            }
            // Deeper than the tolerance below where the tool would rest, but
            // is it into the part by more than the tolerance in any direction?
            // A tool standing exactly at a vertical wall is not: the tool
            // shrunk by the tolerance must still meet the part.
            let (inner, rise) = sh.inset(g.tol);
            let into = part.drop(&inner, c).is_some_and(|d| d.z > q.z + rise);
            if into {
                depth
            } else {
                f64::NEG_INFINITY
            }
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
