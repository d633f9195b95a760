//! The engagement of a re-oriented ball from the simulated stock.
//!
//! A ball whose centre stays where the program has it removes the same
//! material at any orientation (the ball is the set of points within R of
//! the centre), so the program is simulated once, as it is, and at a few
//! sample moves per operation the stock as it is just before the move is
//! kept around the ball ([`crops_before`]). A candidate (lead, tilt) is then
//! judged at every sample by placing the tool with that axis, ball centre
//! fixed, in the sample's crop and asking the force model which edge cells
//! are in material ([`StockEngagement`], as `millplan force` does).
//!
//! Samples: of an operation's moves that touch the part and remove material
//! (the first simulation), the quarter of [`StockInput::samples`] with the
//! highest removal rate, and then, with the moves cut into as many equal runs
//! as samples are left, the highest-rate move of each run not taken yet: the
//! heaviest cuts, and the rest spread along the operation. The engagement of
//! a move is the tool at its end against the stock before its last stroke
//! (the stroke that ends at the re-oriented point).
//!
//! A crop covers what the fluted part of any candidate tool can reach: the
//! candidate axes lie within a cone about the part's normal (the angle
//! between axis and normal is acos(cos L·cos T) in both variants of §2.2),
//! so about the vertical within that cone plus the normal's own angle θ. A
//! point of the flutes h above the ball centre is at least h·cos θ − R·sin θ
//! above it and at most R + h·sin θ from it across; the crop's half-width is
//! R + h·sin θ for the largest h at which the flutes can still reach the
//! highest material near the ball, so a finishing cut keeps about the ball's
//! footprint: (2R/res)² cells. All crops together hold at most
//! [`StockInput::max_bytes`] (by default [`MAX_CROP_BYTES`]): a window that would take more than its share is
//! narrowed to it (never below the ball's footprint), and the sample says it
//! was clipped (flutes high above the ball may then miss material).

use super::Point;
use crate::force::StockEngagement;
use millplan_geom::{DVec2, DVec3};
use millplan_models::force::engage::Engagement;
use millplan_models::force::{Cut, ForceModel};
use millplan_sim::stock::path::Strokes;
use millplan_sim::stock::sim::{per_move, simulate, CUT_EPS};
use millplan_sim::stock::snapshot::crops_before;
use millplan_sim::stock::{Stock, BYTES_PER_CELL};
use rayon::prelude::*;

/// The most memory the crops of all samples hold together, bytes.
pub const MAX_CROP_BYTES: usize = 256 << 20;

/// The stock and the strokes of the program it is cut by.
pub struct StockInput<'a> {
    /// The stock before the program.
    pub stock: Stock,
    /// The program's strokes (`millplan_sim::stock::path::strokes`), every
    /// operation's, in order: the operations that are not re-oriented cut
    /// the stock too.
    pub strokes: &'a Strokes,
    /// Most sample moves per operation.
    pub samples: usize,
    /// The most memory the samples' crops may hold together, bytes.
    pub max_bytes: usize,
}

/// One sample move: the stock around it before it, and how it moves.
pub(super) struct Sample {
    /// Index into the operation's located points.
    pub point: usize,
    /// The ball centre's direction of travel on the move's last stroke.
    pub feed: DVec3,
    pub crop: Stock,
    /// The window was narrowed to the memory budget.
    pub clipped: bool,
}

/// What an operation's samples say about one candidate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Judged {
    /// Largest F_xy,max over the samples, N.
    pub fxy: f64,
    /// Samples at which the zero-speed tip cuts (see [`judge`]).
    pub tip: usize,
}

/// The samples of every operation (indexed like `points`; empty where the
/// operation is not re-oriented). `progress(done, total)` counts strokes,
/// first of the whole run, then of the run up to the last sample.
pub(super) fn sample(
    program: &millplan_nc::Program,
    points: &[Vec<Point>],
    radius: &[f64],
    reach: &[f64],
    cone_deg: f64,
    input: StockInput,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Vec<Vec<Sample>> {
    let strokes = input.strokes;
    let n = strokes.strokes.len();
    // The removal rate of every move, from the program as it is.
    let mut first = input.stock.clone();
    let cuts = simulate(&mut first, strokes, &|d| progress(d, 2 * n));
    drop(first);
    let moves = per_move(strokes, &cuts);
    drop(cuts);
    let total_moves: usize = program.operations.iter().map(|o| o.moves.len()).sum();
    let mut mrr = vec![None::<f64>; total_moves];
    for m in &moves {
        if !m.rapid && m.removed_mm3 > CUT_EPS * 1e-2 {
            if let Some(x) = mrr.get_mut(m.index as usize) {
                *x = Some(m.mrr);
            }
        }
    }
    let mut last_stroke = vec![u32::MAX; total_moves];
    for (k, s) in strokes.strokes.iter().enumerate() {
        if let Some(x) = last_stroke.get_mut(s.mv as usize) {
            *x = k as u32;
        }
    }
    // Per operation, the chosen points; then all picks in stroke order.
    let mut picks: Vec<(usize, usize, usize)> = Vec::new(); // (stroke, op, point)
    let mut offset = 0;
    for (oi, op) in program.operations.iter().enumerate() {
        let pts = &points[oi];
        let cands: Vec<(usize, f64)> = pts
            .iter()
            .enumerate()
            .filter_map(|(k, q)| {
                let g = offset + q.index;
                let rate = mrr[g]?;
                (last_stroke[g] != u32::MAX).then_some((k, rate))
            })
            .collect();
        for k in choose_samples(&cands, input.samples) {
            picks.push((last_stroke[offset + pts[k].index] as usize, oi, k));
        }
        offset += op.moves.len();
    }
    picks.sort_unstable();
    picks.dedup_by_key(|p| p.0);
    let stroke_ix: Vec<usize> = picks.iter().map(|p| p.0).collect();
    let res = input.stock.grid.res;
    // The widest window a sample's share of the budget allows.
    let share = input.max_bytes as f64 / picks.len().max(1) as f64;
    let widest = 0.5 * res * ((share / BYTES_PER_CELL).sqrt() - 2.0).max(0.0);
    let clipped: Vec<std::cell::Cell<bool>> = picks.iter().map(|_| Default::default()).collect();
    let window = |stock: &Stock, i: usize| {
        let (_, oi, k) = picks[i];
        let q = &points[oi][k];
        let theta = (q.frame.n.z.clamp(-1.0, 1.0).acos() + cone_deg.to_radians())
            .min(std::f64::consts::FRAC_PI_2);
        let (lo, hi) = crop_window(stock, q.centre, radius[oi], reach[oi], theta, res);
        let w = 0.5 * (hi.x - lo.x);
        let cap = widest.max(radius[oi] + 2.0 * res);
        if w > cap {
            clipped[i].set(true);
            let c = q.centre.truncate();
            return (c - DVec2::splat(cap), c + DVec2::splat(cap));
        }
        (lo, hi)
    };
    let mut stock = input.stock;
    let last = stroke_ix.last().copied().unwrap_or(0);
    let crops = crops_before(&mut stock, strokes, &stroke_ix, window, &|d| {
        progress(n + d * n / last.max(1), 2 * n)
    });
    progress(2 * n, 2 * n);
    let mut out: Vec<Vec<Sample>> = points.iter().map(|_| Vec::new()).collect();
    for (((k, oi, pi), crop), clipped) in picks.into_iter().zip(crops).zip(clipped) {
        let s = &strokes.strokes[k];
        let r = radius[oi];
        let d = (s.p1 + s.a1 * r) - (s.p0 + s.a0 * r);
        let feed = if d.length_squared() > 1e-18 {
            d
        } else {
            s.p1 - s.p0
        };
        if feed.length_squared() > 1e-18 {
            out[oi].push(Sample {
                point: pi,
                feed,
                crop,
                clipped: clipped.get(),
            });
        }
    }
    out
}

/// The rectangle around the ball centre `c` that the flutes (up to `flute`
/// above the tip) of a tool of radius `r` within `theta` of the vertical can
/// reach material in (module docs), widened by two cells.
fn crop_window(
    stock: &Stock,
    c: DVec3,
    r: f64,
    flute: f64,
    theta: f64,
    res: f64,
) -> (DVec2, DVec2) {
    let (s, co) = theta.sin_cos();
    let above = (flute - r).max(0.0);
    let w0 = r + above * s + 2.0 * res;
    let top = stock.max_top_in(
        c.truncate() - DVec2::splat(w0),
        c.truncate() + DVec2::splat(w0),
    );
    let up = if !top.is_finite() {
        0.0
    } else if co > 0.05 {
        ((top - c.z + r * s) / co).clamp(0.0, above)
    } else {
        above
    };
    let w = r + up * s + 2.0 * res;
    (
        c.truncate() - DVec2::splat(w),
        c.truncate() + DVec2::splat(w),
    )
}

/// Up to `most` of `cands` (point index, removal rate; in path order): the
/// quarter with the highest rates, then the highest-rate one of each of the
/// equal runs the rest are cut into. Returns indices into the points,
/// ascending.
pub(super) fn choose_samples(cands: &[(usize, f64)], most: usize) -> Vec<usize> {
    if cands.len() <= most {
        return cands.iter().map(|c| c.0).collect();
    }
    let mut taken = vec![false; cands.len()];
    let mut by_rate: Vec<usize> = (0..cands.len()).collect();
    by_rate.sort_by(|a, b| cands[*b].1.total_cmp(&cands[*a].1).then(a.cmp(b)));
    let top = most / 4;
    for &i in &by_rate[..top] {
        taken[i] = true;
    }
    let runs = most - top;
    for r in 0..runs {
        let (a, b) = (r * cands.len() / runs, (r + 1) * cands.len() / runs);
        let best = (a..b)
            .filter(|i| !taken[*i])
            .max_by(|x, y| cands[*x].1.total_cmp(&cands[*y].1).then(y.cmp(x)));
        if let Some(i) = best {
            taken[i] = true;
        }
    }
    (0..cands.len())
        .filter(|i| taken[*i])
        .map(|i| cands[i].0)
        .collect()
}

/// The candidate (lead, tilt) in degrees judged at every sample: the tool
/// with that axis in each sample's frame, its ball centre kept.
///
/// Tip contact (process-models §1.4c) on the stock: the tip, on the axis,
/// moves along the feed; its chip is fz·(−sin L) with L the angle of the
/// feed out of the plane normal to the axis (the lead the force model sees
/// at the sample, which on a ramp is not the candidate's lead). With L
/// above 0.01° it never cuts; otherwise it cuts when it lies in the
/// material the stock holds before the move (the engaged region reaches
/// the axis): the stock's own depth and scallops decide, not `--ap`.
#[allow(clippy::too_many_arguments)]
pub(super) fn judge(
    model: &ForceModel,
    samples: &[Sample],
    points: &[Point],
    r: f64,
    flute: f64,
    p: &super::Params,
    lead: f64,
    tilt: f64,
) -> Judged {
    samples
        .par_iter()
        .map(|s| {
            let q = &points[s.point];
            let axis = q.frame.axis(lead, tilt, p.variant);
            let tip = q.centre - axis * r;
            let eng = StockEngagement::new(&s.crop, r, tip, axis, s.feed, flute);
            let (x, _, z) = eng.frame();
            // The chip depends on the feed's lead at the sample alone; the
            // tilt (the force model's, of the candidate) only turns the
            // workpiece-frame forces.
            let cut = Cut {
                fz: p.fz,
                rpm: p.rpm,
                lead: s.feed.dot(z).atan2(s.feed.dot(x)),
                tilt: p.variant.force_angles(lead, tilt).1,
            };
            let ev = model.evaluate(&cut, &eng);
            let tip = cut.lead.to_degrees() <= super::ZERO_LEAD && eng.contains([0.0; 3]);
            Judged {
                fxy: ev.summary().fxy_max,
                tip: usize::from(tip),
            }
        })
        .reduce(
            || Judged { fxy: 0.0, tip: 0 },
            |a, b| Judged {
                fxy: a.fxy.max(b.fxy),
                tip: a.tip + b.tip,
            },
        )
}

/// Memory the samples' crops hold, bytes.
pub(super) fn bytes(samples: &[Sample]) -> usize {
    samples.iter().map(|s| s.crop.memory_bytes()).sum()
}

#[cfg(test)]
mod tests {
    use super::choose_samples;

    #[test]
    fn samples_take_the_heaviest_cuts_and_spread_the_rest() {
        // 100 moves, rates rising to a peak at 70; 8 samples: 2 by rate
        // (70 and a neighbour), then one per run of ~16 moves.
        let cands: Vec<(usize, f64)> = (0..100)
            .map(|i| (i, 100.0 - (i as f64 - 70.0).abs()))
            .collect();
        let s = choose_samples(&cands, 8);
        assert_eq!(s.len(), 8);
        assert!(s.contains(&70), "{s:?}");
        assert!(s.windows(2).all(|w| w[0] < w[1]));
        // Every sixth of the path holds a sample.
        for r in 0..6 {
            let (a, b) = (r * 100 / 6, (r + 1) * 100 / 6);
            assert!(s.iter().any(|i| (a..b).contains(i)), "{r}: {s:?}");
        }
        // Fewer candidates than samples: all of them.
        assert_eq!(choose_samples(&cands[..5], 8), vec![0, 1, 2, 3, 4]);
    }
}
