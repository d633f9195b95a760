//! A whole program over a stock: what `millplan simulate` reports.

use super::path::{Strokes, Unsimulated};
use super::sim::{per_move, simulate, MoveCut, StrokeCut};
use super::Stock;

/// A move whose rapid, shank or holder went into material.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Collision {
    /// Index of the move over the whole program.
    #[serde(rename = "move")]
    pub mv: u32,
    pub line: u32,
    /// Deepest material met, mm.
    pub depth: f64,
    /// Material removed by the move, mm³.
    pub volume_mm3: f64,
}

/// What a program did to its stock.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SimReport {
    /// Moves in the program.
    pub moves: usize,
    /// Moves simulated.
    pub simulated: usize,
    /// Moves not simulated, by reason.
    pub skipped: Unsimulated,
    /// Cutting moves that removed material, and those that removed none.
    pub cutting_moves: usize,
    pub air_moves: usize,
    pub removed_mm3: f64,
    pub stock_before_mm3: f64,
    pub stock_after_mm3: f64,
    pub max_mrr_mm3_min: f64,
    /// Line of the move with the highest removal rate.
    pub max_mrr_line: u32,
    pub rapid_collisions: Vec<Collision>,
    pub holder_collisions: Vec<Collision>,
    pub resolution_mm: f64,
    /// Estimated time of the simulated moves, minutes.
    pub minutes: f64,
    #[serde(skip)]
    pub per_move: Vec<MoveCut>,
}

/// Runs `strokes` over `stock`. Material deeper than `tol` mm met by a rapid
/// or by the shank or holder is a collision.
pub fn run(
    stock: &mut Stock,
    strokes: &Strokes,
    tol: f64,
    progress: &(dyn Fn(usize) + Sync),
) -> SimReport {
    let before = stock.volume();
    let cuts = simulate(stock, strokes, progress);
    let after = stock.volume();
    let moves = per_move(strokes, &cuts);
    let rapid_collisions = collisions(strokes, &cuts, |s, c| s.rapid && c.depth > tol, |c| c.depth);
    let holder_collisions = collisions(strokes, &cuts, |_, c| c.noncut > tol, |c| c.noncut);
    let (mut max_mrr, mut max_line) = (0.0, 0);
    for m in &moves {
        if !m.rapid && m.mrr > max_mrr {
            max_mrr = m.mrr;
            max_line = m.line;
        }
    }
    SimReport {
        moves: strokes.moves,
        simulated: moves.len(),
        skipped: strokes.skipped,
        cutting_moves: moves.iter().filter(|m| !m.rapid && !m.air).count(),
        air_moves: moves.iter().filter(|m| m.air).count(),
        removed_mm3: before - after,
        stock_before_mm3: before,
        stock_after_mm3: after,
        max_mrr_mm3_min: max_mrr,
        max_mrr_line: max_line,
        rapid_collisions,
        holder_collisions,
        resolution_mm: stock.grid.res,
        minutes: moves.iter().map(|m| m.minutes).sum(),
        per_move: moves,
    }
}

/// One entry per move with a stroke that `hit`, at the deepest `depth`.
fn collisions(
    strokes: &Strokes,
    cuts: &[StrokeCut],
    hit: impl Fn(&super::path::Stroke, &StrokeCut) -> bool,
    depth: impl Fn(&StrokeCut) -> f64,
) -> Vec<Collision> {
    let mut out: Vec<Collision> = Vec::new();
    for (s, c) in strokes.strokes.iter().zip(cuts) {
        if !hit(s, c) {
            continue;
        }
        match out.last_mut() {
            Some(l) if l.mv == s.mv => {
                l.depth = l.depth.max(depth(c));
                l.volume_mm3 += c.removed;
            }
            _ => out.push(Collision {
                mv: s.mv,
                line: s.line,
                depth: depth(c),
                volume_mm3: c.removed,
            }),
        }
    }
    out
}
