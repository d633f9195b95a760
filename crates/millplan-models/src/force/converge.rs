//! Steps chosen from the engagement: the force integrals refine their slice
//! height and rotation step until the peaks they report have converged, the
//! grid the user gives being the coarsest allowed.
//!
//! One evaluation carries its own error estimate ([`Evaluation::error_dz`],
//! [`Evaluation::error_dphi`]):
//!
//! - *slice height*: at every spindle angle the force is a midpoint sum over
//!   the slices, whose integrand jumps where the flute enters and leaves
//!   material (a first-order error in dz). The even and the odd slices alone,
//!   each doubled, are two sums at twice the height; half their difference
//!   in F_xy,max (and T_max) estimates the error of the whole sum. Where the
//!   integrand is the same on every slice (a flat end mill under a plane)
//!   the halves agree whatever the error, so the boundary cells, where the
//!   flute enters or leaves material, count too: a quarter of their force
//!   ([`BOUNDARY_SHARE`]).
//! - *rotation step*: the force at a spindle angle is exact for the cells it
//!   sums, but the peak over a tooth period is sampled every dφ; the peaks
//!   over the even and the odd angles alone differ by about what sampling
//!   at dφ misses.
//!
//! [`ConvergedModel`] halves the slice height while its estimate is above
//! the tolerance and evaluates again, on the slices around the engaged band
//! of the coarsest grid only (one and a half of its slices more on each
//! side) and at the angles around the peaks only: the samples of F_xy and
//! |T| within a few error estimates of their peak and their neighbours; the
//! coarser grid's samples stand elsewhere, where they lie further below the
//! peaks than their error can lift them. Then it halves the rotation step
//! around the peaks only: the angles between the
//! samples of F_xy and |T| within a few error estimates of their peak (and
//! between those and their neighbours) are evaluated, the coarser grid's
//! samples stand elsewhere (interpolated between them), until the estimate
//! is within the tolerance or the step reaches its floor. A refinement then
//! costs a few angles instead of every angle of the revolution.

use super::engage::Engagement;
use super::quadrature::{BISECTIONS, COLUMNS};
use super::{coeffs::Law, edge::Tool, Cut, Engaged, Evaluation, ForceModel, Grid};
use std::sync::OnceLock;

/// How far [`ConvergedModel`] refines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refine {
    /// Estimated relative error of F_xy,max and T_max to reach.
    pub tol: f64,
    /// Halvings of each step at most (4: sixteen times finer).
    pub halvings: u32,
}

impl Default for Refine {
    /// 0.4 % (so that the result lies within 1 % of a grid four times finer
    /// in both steps, tests/force.rs) and four halvings.
    fn default() -> Refine {
        Refine {
            tol: 0.004,
            halvings: 4,
        }
    }
}

/// The finest slice height refinement goes to, mm.
pub const DZ_FLOOR: f64 = 0.001;
/// The finest rotation step refinement goes to, rad (0.02°: 18,000 angles
/// per revolution).
pub const DPHI_FLOOR: f64 = 0.02 * std::f64::consts::PI / 180.0;

/// A tool and law with the grids from the user's (`grid`, the coarsest) to
/// its steps halved `refine.halvings` times, each built when first needed.
#[derive(Debug)]
pub struct ConvergedModel {
    tool: Tool,
    law: Law,
    /// The user's grid: upper bounds of the steps.
    pub grid: Grid,
    pub refine: Refine,
    /// Grid (a, b) (dz/2^a, dφ/2^b) at a·(halvings + 1) + b; `None` where
    /// it cannot be built (too many slices).
    levels: Vec<OnceLock<Option<ForceModel>>>,
}

/// A converged evaluation with the grids it used, so that the same
/// engagement can be evaluated again at other feeds per tooth
/// ([`Converged::evaluate_at`]).
#[derive(Clone, Debug)]
pub struct Converged<'a> {
    /// The finest grid used.
    pub model: &'a ForceModel,
    /// The engaged cells on the coarsest grid, at every angle (the finer
    /// grids look at the angles around the peaks only).
    pub cells: Engaged,
    pub evaluation: Evaluation,
    /// Halvings of the slice height and of the rotation step used.
    pub halvings: (u32, u32),
    /// The grids evaluated, the coarsest (at every angle) first.
    steps: Vec<Step<'a>>,
}

/// One grid of a converged evaluation: its model, the cells it evaluated,
/// and where it was evaluated around the peaks only, which angle indices of
/// the tooth period it evaluated (elsewhere the coarser grid's samples
/// stand).
#[derive(Clone, Debug)]
struct Step<'a> {
    model: &'a ForceModel,
    cells: Engaged,
    window: Window,
}

/// Which angles of the tooth period a grid evaluated.
#[derive(Clone, Debug)]
enum Window {
    /// Every angle.
    All,
    /// The slice length halved at these angles (same angles as the grid
    /// before, [`merge_slices`]).
    Slices(Vec<bool>),
    /// The rotation step halved, evaluated at these angles of twice as many
    /// ([`merge_window`]).
    Angles(Vec<bool>),
}

impl Converged<'_> {
    /// The same engagement at the feed per tooth and spindle speed of `cut`
    /// (its lead and tilt those the engagement was converged with), on the
    /// same grids.
    pub fn evaluate_at(&self, cut: &Cut) -> Evaluation {
        let mut rows = Vec::new();
        let mut stats = (f64::INFINITY, f64::NEG_INFINITY);
        let mut cells = 0;
        for s in &self.steps {
            match &s.window {
                Window::All => {
                    (rows, stats) = s.model.rows(cut, &s.cells);
                    cells = s.cells.len();
                }
                Window::Slices(w) => rows = merge_slices(s.model.rows(cut, &s.cells).0, w, &rows),
                Window::Angles(w) => rows = merge_window(s.model.rows(cut, &s.cells).0, w, &rows),
            }
        }
        self.model.finish(cut, &rows, stats, cells)
    }
}

/// The rows of a grid with twice the angles of `coarse`: its own (`fine`)
/// at the indices in `window`, elsewhere the coarser grid's samples (at the
/// even indices, the same angles) and the mean of the two around (at the
/// odd). The means change neither the period's mean nor its extremes.
fn merge_window(
    mut fine: Vec<[f64; COLUMNS]>,
    window: &[bool],
    coarse: &[[f64; COLUMNS]],
) -> Vec<[f64; COLUMNS]> {
    let p = coarse.len();
    debug_assert_eq!(fine.len(), 2 * p);
    for (i, row) in fine.iter_mut().enumerate() {
        if window[i] {
            continue;
        }
        *row = if i % 2 == 0 {
            coarse[i / 2]
        } else {
            let (a, b) = (&coarse[i / 2], &coarse[(i / 2 + 1) % p]);
            std::array::from_fn(|c| 0.5 * (a[c] + b[c]))
        };
    }
    fine
}

/// The rows of a grid with half the slice length of `coarse`'s (the same
/// angles): its own (`fine`) at the indices in `window`, elsewhere the
/// coarser grid's, whose parity and boundary columns are made those of a
/// converged row (the odd and the even slices' quadratures each equal to
/// the whole, no boundary): outside the window a row lies further below
/// the peaks than its error can lift it, so it must not count in the
/// error estimate of the peaks ([`error_estimates`]).
fn merge_slices(
    mut fine: Vec<[f64; COLUMNS]>,
    window: &[bool],
    coarse: &[[f64; COLUMNS]],
) -> Vec<[f64; COLUMNS]> {
    debug_assert_eq!(fine.len(), coarse.len());
    for (i, row) in fine.iter_mut().enumerate() {
        if !window[i] {
            let c = coarse[i];
            *row = c;
            for at in [4, 7] {
                row[at] = c[0];
                row[at + 1] = c[1];
                row[at + 2] = c[3];
            }
            row[10..13].fill(0.0);
        }
    }
    fine
}

/// The angle indices of the tooth period to evaluate again at half the
/// slice length: every sample of F_xy or |T| within `margin` of its peak,
/// and its neighbours (a peak may move by a sample as the slices refine).
fn slice_window(rows: &[[f64; COLUMNS]], margin: f64) -> Vec<bool> {
    let p = rows.len();
    let mut w = vec![false; p];
    for c in 0..2 {
        let v = |r: &[f64; COLUMNS]| if c == 0 { r[0].hypot(r[1]) } else { r[3].abs() };
        let top = rows.iter().map(v).fold(0.0, f64::max);
        for (i, r) in rows.iter().enumerate() {
            if top > 0.0 && v(r) >= top * (1.0 - margin) {
                w[(i + p - 1) % p] = true;
                w[i] = true;
                w[(i + 1) % p] = true;
            }
        }
    }
    w
}

/// How close to its peak (relative) a sample of F_xy or |T| must be for
/// the intervals around it to be refined, given the rotation step's error
/// estimate: a peak between two samples rises above them by about that
/// estimate, so a sample further below than four times it cannot hide the
/// peak; never less than [`WINDOW_FLOOR`].
fn window_margin(error_dphi: f64) -> f64 {
    (4.0 * error_dphi).clamp(WINDOW_FLOOR, 1.0)
}

/// The least margin of `window_margin`.
pub const WINDOW_FLOOR: f64 = 0.01;

/// The angle indices of a grid with twice the angles of `rows` to
/// evaluate: the two between every sample of F_xy or |T| within `margin`
/// of its peak and its neighbours, and that sample itself where `exact`
/// says it was interpolated.
fn window(rows: &[[f64; COLUMNS]], exact: &[bool], margin: f64) -> Vec<bool> {
    let p = rows.len();
    let mut w = vec![false; 2 * p];
    for c in 0..2 {
        let v = |r: &[f64; COLUMNS]| if c == 0 { r[0].hypot(r[1]) } else { r[3].abs() };
        let top = rows.iter().map(v).fold(0.0, f64::max);
        for (i, r) in rows.iter().enumerate() {
            if top > 0.0 && v(r) >= top * (1.0 - margin) {
                w[(2 * i + 2 * p - 1) % (2 * p)] = true;
                w[2 * i + 1] = true;
                w[2 * i] |= !exact[i];
            }
        }
    }
    w
}

impl ConvergedModel {
    /// Checks the tool, law and coarsest grid.
    pub fn new(tool: Tool, law: Law, grid: Grid, refine: Refine) -> Result<Self, String> {
        let base = ForceModel::new(tool, law, grid)?;
        if !(refine.tol > 0.0 && refine.halvings <= 8) {
            return Err("refinement: the tolerance must be positive, halvings at most 8".into());
        }
        let n = refine.halvings as usize + 1;
        let levels: Vec<OnceLock<Option<ForceModel>>> =
            (0..n * n).map(|_| OnceLock::new()).collect();
        let _ = levels[0].set(Some(base));
        Ok(ConvergedModel {
            tool,
            law,
            grid,
            refine,
            levels,
        })
    }

    /// The tool being modelled.
    pub fn tool(&self) -> &Tool {
        &self.tool
    }

    /// The model on the user's grid.
    pub fn base(&self) -> &ForceModel {
        self.level(0, 0).expect("built in new")
    }

    fn level(&self, a: u32, b: u32) -> Option<&ForceModel> {
        let n = self.refine.halvings + 1;
        self.levels[(a * n + b) as usize]
            .get_or_init(|| {
                // Rotation steps halve the base model's own step, so that
                // every grid's angles are the next coarser grid's and one
                // between each two (a refinement around the peaks keeps the
                // coarser grid's samples elsewhere).
                let base = self.levels[0].get().and_then(Option::as_ref);
                let dphi = base.map_or(self.grid.dphi, ForceModel::dphi);
                let grid = Grid {
                    dz: self.grid.dz / f64::from(1u32 << a),
                    dphi: dphi / f64::from(1u32 << b),
                };
                ForceModel::new(self.tool, self.law, grid).ok()
            })
            .as_ref()
    }

    /// Whether the step may be halved once more from `k` halvings.
    fn may_halve(&self, k: u32, step: f64, floor: f64) -> bool {
        k < self.refine.halvings && step / f64::from(2u32 << k) >= floor
    }

    /// Forces of one engagement on the coarsest grid that meets the
    /// tolerance (see the module docs).
    pub fn converge<E: Engagement + ?Sized>(&self, cut: &Cut, eng: &E) -> Converged<'_> {
        self.converge_from(cut, eng, (0, 0), |_| false)
    }

    /// [`ConvergedModel::converge`] starting from the grid with `start`
    /// halvings (a neighbouring engagement's, say: along a move the
    /// engagement changes slowly), and stopping early where `enough` says
    /// that an evaluation, with its error estimates, settles what the caller
    /// needs to know.
    pub fn converge_from<E: Engagement + ?Sized>(
        &self,
        cut: &Cut,
        eng: &E,
        start: (u32, u32),
        enough: impl Fn(&Evaluation) -> bool,
    ) -> Converged<'_> {
        let h = self.refine.halvings;
        let (mut a, b) = (start.0.min(h), start.1.min(h));
        let b = if self.level(a, b).is_some() { b } else { 0 };
        if self.level(a, b).is_none() {
            a = 0;
        }
        let model = self.level(a, b).expect("the coarser grid was built");
        let cells = model.engaged(cut, eng);
        self.converge_on::<E, &E>(model, (a, b), cut, cells, || eng, enough)
    }

    /// [`ConvergedModel::converge_from`] the coarsest grid, of an
    /// engagement whose cells there are known already (`cells`, as
    /// [`ForceModel::engaged`] of [`ConvergedModel::base`] gave them at this
    /// cut's lead and tilt): the engagement itself is built (`eng`) only
    /// where a finer grid is needed. The result is the one
    /// [`ConvergedModel::converge_from`] `(0, 0)` gives.
    pub fn converge_cells<E: Engagement>(
        &self,
        cut: &Cut,
        cells: Engaged,
        eng: impl FnOnce() -> E,
        enough: impl Fn(&Evaluation) -> bool,
    ) -> Converged<'_> {
        self.converge_on::<E, E>(self.base(), (0, 0), cut, cells, eng, enough)
    }

    /// The evaluation of `cells` on `model` (the grid of `halvings`), then
    /// refined on the engagement `eng` gives until `enough` or the
    /// tolerance.
    fn converge_on<'s, E: Engagement + ?Sized, R: std::borrow::Borrow<E>>(
        &'s self,
        model: &'s ForceModel,
        halvings: (u32, u32),
        cut: &Cut,
        cells: Engaged,
        eng: impl FnOnce() -> R,
        enough: impl Fn(&Evaluation) -> bool,
    ) -> Converged<'s> {
        let (rows, stats) = model.rows(cut, &cells);
        let evaluation = model.finish(cut, &rows, stats, cells.len());
        // Finer grids look for cells on the heights the coarsest found
        // engaged (and one and a half of its slices more on each side).
        let band = model.band(&cells);
        let mut c = Converged {
            model,
            cells: cells.clone(),
            evaluation,
            halvings,
            steps: vec![Step {
                model,
                cells,
                window: Window::All,
            }],
        };
        if c.cells.is_empty() || enough(&c.evaluation) {
            return c;
        }
        let eng = eng();
        let eng = eng.borrow();
        let rows = self.refine_slices(&mut c, cut, eng, band, rows, stats, &enough);
        if !enough(&c.evaluation) {
            self.refine_peaks(&mut c, cut, eng, band, rows, stats, &enough);
        }
        c
    }

    /// The slice length: halved around the peaks of F_xy and |T| only
    /// ([`slice_window`]) while its error estimate is over the tolerance,
    /// the rows elsewhere kept from the coarser grid ([`merge_slices`]).
    /// Returns the rows of the last grid.
    #[allow(clippy::too_many_arguments)]
    fn refine_slices<'a, E: Engagement + ?Sized>(
        &'a self,
        c: &mut Converged<'a>,
        cut: &Cut,
        eng: &E,
        band: (f64, f64),
        mut rows: Vec<[f64; COLUMNS]>,
        stats: (f64, f64),
        enough: &impl Fn(&Evaluation) -> bool,
    ) -> Vec<[f64; COLUMNS]> {
        let (mut a, b) = c.halvings;
        let mut refined = vec![false; rows.len()];
        while c.evaluation.error_dz > self.refine.tol && self.may_halve(a, self.grid.dz, DZ_FLOOR) {
            let Some(fine) = self.level(a + 1, b) else {
                break;
            };
            let p = rows.len();
            if fine.per_tooth() != p {
                break;
            }
            // A row refined once stays in the window: its error is that of
            // its own grid, not the peaks' estimate the margin comes from,
            // so it must not be left behind at a coarser grid.
            let mut todo = slice_window(&rows, window_margin(c.evaluation.error_dz));
            for (t, r) in todo.iter_mut().zip(&refined) {
                *t |= *r;
            }
            refined.clone_from(&todo);
            let angles: Vec<usize> = (0..p)
                .filter(|i| todo[*i])
                .flat_map(|i| (0..fine.tool.flutes).map(move |j| i + j * p))
                .collect();
            let cells = fine.engaged_where(cut, eng, band, Some(&angles));
            rows = merge_slices(fine.rows(cut, &cells).0, &todo, &rows);
            a += 1;
            c.evaluation = fine.finish(cut, &rows, stats, c.cells.len());
            c.model = fine;
            c.halvings = (a, b);
            c.steps.push(Step {
                model: fine,
                cells,
                window: Window::Slices(todo),
            });
            if enough(&c.evaluation) {
                break;
            }
        }
        rows
    }

    /// The rotation step: halved around the peaks of F_xy and |T| only
    /// ([`window`]) until its error estimate is within the tolerance, the
    /// samples elsewhere kept from the coarser grid (a peak is where the
    /// step matters: the mean over the period and the extremes elsewhere
    /// are not what the estimate measures). `rows` and `stats` are those
    /// of `c`'s evaluation, `band` the heights its cells were sought in.
    #[allow(clippy::too_many_arguments)]
    fn refine_peaks<'a, E: Engagement + ?Sized>(
        &'a self,
        c: &mut Converged<'a>,
        cut: &Cut,
        eng: &E,
        band: (f64, f64),
        mut rows: Vec<[f64; COLUMNS]>,
        stats: (f64, f64),
        enough: &impl Fn(&Evaluation) -> bool,
    ) {
        let (a, mut b) = c.halvings;
        let mut exact = vec![true; rows.len()];
        while c.evaluation.error_dphi > self.refine.tol
            && self.may_halve(b, self.grid.dphi, DPHI_FLOOR)
        {
            let Some(fine) = self.level(a, b + 1) else {
                break;
            };
            let p = rows.len();
            if fine.per_tooth() != 2 * p {
                break;
            }
            let todo = window(&rows, &exact, window_margin(c.evaluation.error_dphi));
            // The window's angle indices over every flute's tooth period.
            let angles: Vec<usize> = (0..2 * p)
                .filter(|i| todo[*i])
                .flat_map(|i| (0..fine.tool.flutes).map(move |j| i + j * 2 * p))
                .collect();
            let cells = fine.engaged_where(cut, eng, band, Some(&angles));
            rows = merge_window(fine.rows(cut, &cells).0, &todo, &rows);
            exact = (0..2 * p)
                .map(|i| todo[i] || (i % 2 == 0 && exact[i / 2]))
                .collect();
            b += 1;
            c.evaluation = fine.finish(cut, &rows, stats, c.cells.len());
            c.model = fine;
            c.halvings = (a, b);
            c.steps.push(Step {
                model: fine,
                cells,
                window: Window::Angles(todo),
            });
            if enough(&c.evaluation) {
                break;
            }
        }
    }

    /// The converged evaluation alone.
    pub fn evaluate<E: Engagement + ?Sized>(&self, cut: &Cut, eng: &E) -> Evaluation {
        self.converge(cut, eng).evaluation
    }
}

impl ForceModel {
    /// Heights (mm above the tip) from one slice below the lowest engaged
    /// slice to one above the highest.
    fn band(&self, e: &Engaged) -> (f64, f64) {
        let lo = e.cells.iter().map(|c| c.slice).min();
        let hi = e.cells.iter().map(|c| c.slice).max();
        match (lo, hi) {
            (Some(lo), Some(hi)) => {
                let z = |u: f64| super::edge::height(&self.tool.shape, u);
                (
                    z(self.slices[lo as usize].u - 1.5 * self.dz),
                    z(self.slices[hi as usize].u + 1.5 * self.dz),
                )
            }
            _ => (0.0, 0.0),
        }
    }
}

/// The share of the even/odd difference taken as the error of the slice
/// height: half the difference is the error of a quadrature at twice the
/// height, whose error falls with the square of the height
/// ([`super::quadrature`]); a half of that (not the quarter the square
/// gives) keeps a margin where the integrand is not smooth.
pub const HALVES_SHARE: f64 = 0.25;

/// The share of a boundary cell's force (counted whole) taken as the error
/// of locating its boundary: bisection leaves the point within
/// 2^-[`BISECTIONS`] of a slice, so half of that is the largest error.
pub const BOUNDARY_SHARE: f64 = 0.5 / (1u32 << BISECTIONS) as f64;

/// The share of the whole force's peak |F| below which F_xy,max is not
/// taken as the scale of its own error (in `error_estimates`).
pub const FXY_FLOOR_SHARE: f64 = 0.1;

/// The share of `tent_excess` taken as the error of the rotation step.
pub const TENT_SHARE: f64 = 0.5;

/// How far the peak of quantity `c` (0: F_xy, 1: |T|) over the tooth period
/// may lie above its largest sample when it is a kink (a flute entering or
/// leaving material): the lines through the two samples on each side of the
/// largest, extended to where they meet between its neighbours. The
/// samples at the even and the odd angles alone can agree while both miss
/// such a peak.
fn tent_excess(rows: &[[f64; COLUMNS]], c: usize) -> f64 {
    let p = rows.len();
    if p < 5 {
        return 0.0;
    }
    let v = |i: usize| {
        let r = &rows[i % p];
        if c == 0 {
            r[0].hypot(r[1])
        } else {
            r[3].abs()
        }
    };
    let top = (0..p).max_by(|a, b| v(*a).total_cmp(&v(*b))).unwrap_or(0) + p;
    let (l2, l1, f, r1, r2) = (v(top - 2), v(top - 1), v(top), v(top + 1), v(top + 2));
    // Rising slope on the left, falling slope on the right, per step.
    let (a, b) = (l1 - l2, r1 - r2);
    if !(a > 0.0 && b > 0.0) {
        return 0.0;
    }
    let x = ((r1 - l1 + b - a) / (a + b)).clamp(-1.0, 1.0);
    (l1 + a * (x + 1.0)).min(r1 + b * (1.0 - x)).max(f) - f
}

/// Relative error estimates (slice height, rotation step) of the peaks
/// F_xy,max and T_max over one tooth period, from the table of
/// [`super::quadrature::COLUMNS`].
pub(crate) fn error_estimates(rows: &[[f64; COLUMNS]]) -> (f64, f64) {
    // Peaks of (F_xy, |T|): the quadrature, the odd and the even slices'
    // quadratures; the quadrature at the even and at the odd angles; the
    // boundary cells.
    let mut peak = [[0.0f64; 2]; 6];
    // The whole force's peak |F|², without a square root per angle.
    let mut whole2 = 0.0f64;
    for (i, r) in rows.iter().enumerate() {
        whole2 = whole2.max(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        let q = [
            [r[0].hypot(r[1]), r[3].abs()],
            [r[4].hypot(r[5]), r[6].abs()],
            [r[7].hypot(r[8]), r[9].abs()],
        ];
        let b = [r[10].hypot(r[11]), r[12].abs()];
        for c in 0..2 {
            for (w, v) in q.iter().enumerate() {
                peak[w][c] = peak[w][c].max(v[c]);
            }
            let at = 3 + i % 2;
            peak[at][c] = peak[at][c].max(q[0][c]);
            peak[5][c] = peak[5][c].max(b[c]);
        }
    }
    let (mut dz, mut dphi) = (0.0f64, 0.0f64);
    // Per quantity (F_xy, T): [all, odd, even, even angles, odd angles, boundary].
    let [all, odd, even, at_even, at_odd, boundary] = peak;
    // F_xy's error is relative to F_xy,max, but never to less than a share
    // of the whole force: where the flutes' side forces cancel (a plunge),
    // F_xy is a small difference of large terms and no step makes its
    // relative error small.
    let scale = [all[0].max(FXY_FLOOR_SHARE * whole2.sqrt()), all[1]];
    for c in 0..2 {
        if scale[c] > 0.0 {
            let halves = HALVES_SHARE * (even[c] - odd[c]).abs();
            dz = dz.max((halves + BOUNDARY_SHARE * boundary[c]) / scale[c]);
            let sampled = (at_even[c] - at_odd[c]).abs();
            let kink = TENT_SHARE * tent_excess(rows, c);
            dphi = dphi.max(sampled.max(kink) / scale[c]);
        }
    }
    (dz, dphi)
}
