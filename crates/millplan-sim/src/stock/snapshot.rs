//! Local copies of the stock as a run leaves it before chosen strokes: what
//! a process model needs to ask "what would another tool pose meet here"
//! without keeping the whole stock once per question.
//!
//! The run is the parallel one of [`super::sim::simulate`], cut at the
//! chosen strokes: the strokes between two of them are removed together,
//! then the window around the next one is copied ([`Stock::crop`]). A
//! stroke removed at the start of a segment is not told that it continues
//! the one before; that changes only how its volume is counted (its start
//! cap is removed again, where there is no material left), never the stock.

use super::path::Strokes;
use super::sim::simulate;
use super::Stock;
use millplan_geom::DVec2;

/// Runs `strokes` over `stock` up to the last of `picks` (stroke indices,
/// ascending, no repeats) and returns, for each pick, the cells of the stock
/// within `window(stock, i)` (i the pick's place in `picks`) as they are
/// just before that stroke.
/// `stock` is left as it is before the last pick. `progress(done)` counts
/// strokes.
pub fn crops_before(
    stock: &mut Stock,
    strokes: &Strokes,
    picks: &[usize],
    window: impl Fn(&Stock, usize) -> (DVec2, DVec2),
    progress: &(dyn Fn(usize) + Sync),
) -> Vec<Stock> {
    debug_assert!(picks.windows(2).all(|w| w[0] < w[1]));
    let list = &strokes.strokes;
    let mut out = Vec::with_capacity(picks.len());
    let mut at = 0;
    for (i, &k) in picks.iter().enumerate() {
        let k = k.min(list.len().saturating_sub(1));
        if k > at {
            let part = Strokes {
                strokes: list[at..k].to_vec(),
                tools: strokes.tools.clone(),
                moves: strokes.moves,
                skipped: strokes.skipped,
            };
            let base = at;
            simulate(stock, &part, &|d| progress(base + d));
            at = k;
        }
        let (lo, hi) = window(stock, i);
        out.push(stock.crop(lo, hi));
    }
    progress(at);
    out
}
