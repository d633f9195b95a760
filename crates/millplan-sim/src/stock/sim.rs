//! Material removal: each stroke's swept tool body taken out of the stock, in
//! program order, with what it removed and what its non-cutting parts met.
//!
//! A vertical tool sweeps exactly: over each cell, the lowest point of the
//! body moved along the stroke (a capsule for the ball, closed forms for the
//! flat end and the non-cutting cylinders, a convex one-dimensional search for
//! bull and cone), and everything above it goes. A ball-end stroke no longer
//! than a cell is taken as the tool at its end (the material the two
//! positions miss between them is at most s²/8R high, 0.06 µm for s = 0.05 mm
//! and R = 5 mm). A stroke that does not descend cannot lower a cell behind
//! its start below what the previous stroke's end left, so those cells are not
//! visited. A tilted tool is placed at steps along the stroke (position and
//! axis interpolated as the IR defines) at which no point of the cutting part
//! moves more than half a cell.
//!
//! [`simulate`] runs every stroke over bands of rows in parallel: each band
//! sees the strokes in program order, so the result does not depend on the
//! number of threads (the per-stroke sums are added band group by band group
//! in a fixed order).

use super::path::{Stroke, Strokes};
use super::tool::{Pose, ToolBody, VerticalSweep};
use super::{Grid, RowGaps, Stock};
use millplan_geom::{DVec2, DVec3};
use millplan_models::cutter::Shape;
use rayon::prelude::*;

/// Removed material thinner than this (mm) does not count as cutting (float
/// noise of a tool passing exactly where it already cut).
pub const CUT_EPS: f64 = 1e-4;

/// What one stroke did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrokeCut {
    /// Removed volume, mm³.
    pub removed: f64,
    /// Deepest material met by the shank or holder, mm (0: none).
    pub noncut: f64,
    /// Deepest material met by the cutter, measured down from the material's
    /// top (mm; 0: none).
    pub depth: f64,
    /// Highest removed material, mm (−∞: none).
    pub top: f64,
    /// Lateral extent of the cells the stroke cut into, mm, across the feed.
    pub side: [f64; 2],
}

impl Default for StrokeCut {
    fn default() -> Self {
        StrokeCut {
            removed: 0.0,
            noncut: 0.0,
            depth: 0.0,
            top: f64::NEG_INFINITY,
            side: [f64::INFINITY, f64::NEG_INFINITY],
        }
    }
}

impl StrokeCut {
    fn merge(&mut self, o: &StrokeCut) {
        self.removed += o.removed;
        self.noncut = self.noncut.max(o.noncut);
        self.depth = self.depth.max(o.depth);
        self.top = self.top.max(o.top);
        self.side = [self.side[0].min(o.side[0]), self.side[1].max(o.side[1])];
    }

    fn touched(&self) -> bool {
        self.removed > 0.0 || self.noncut > 0.0
    }
}

/// Rows `j0..j0 + rows` of a stock, mutable.
pub struct Band<'a> {
    pub j0: usize,
    pub rows: usize,
    top: &'a mut [f32],
    bot: &'a mut [f32],
    gaps: &'a mut [RowGaps],
    bmax: &'a mut [f32],
    /// Per tile of [`TILE_ROWS`] rows × [`TILE`] cells of this band: at
    /// least the highest top in it (stale values stay bounds).
    tmax: Vec<f32>,
}

/// Cells across and rows down a tile of [`Band::tmax`].
const TILE: usize = 64;
const TILE_ROWS: usize = 16;

impl<'a> Band<'a> {
    fn new(
        j0: usize,
        nx: usize,
        top: &'a mut [f32],
        bot: &'a mut [f32],
        gaps: &'a mut [RowGaps],
        bmax: &'a mut [f32],
    ) -> Band<'a> {
        let rows = gaps.len();
        let mut b = Band {
            j0,
            rows,
            top,
            bot,
            gaps,
            bmax,
            tmax: vec![f32::NEG_INFINITY; rows.div_ceil(TILE_ROWS) * nx.div_ceil(TILE)],
        };
        let ntx = nx.div_ceil(TILE);
        for ty in 0..rows.div_ceil(TILE_ROWS) {
            for tx in 0..ntx {
                b.refresh_tile(nx, ty, tx);
            }
        }
        b
    }

    /// Recomputes tile (ty, tx) from its blocks.
    fn refresh_tile(&mut self, nx: usize, ty: usize, tx: usize) {
        let nb = nx.div_ceil(super::BLOCK);
        let per = TILE / super::BLOCK;
        let mut hi = f32::NEG_INFINITY;
        for r in ty * TILE_ROWS..((ty + 1) * TILE_ROWS).min(self.rows) {
            for kb in tx * per..((tx + 1) * per).min(nb) {
                hi = hi.max(self.bmax[r * nb + kb]);
            }
        }
        self.tmax[ty * nx.div_ceil(TILE) + tx] = hi;
    }
}

/// How a stroke is applied.
#[derive(Clone, Copy, Debug)]
pub struct Apply<'a> {
    pub grid: Grid,
    pub tool: &'a ToolBody,
    /// The previous stroke ended where this one starts, with the same tool,
    /// and was applied.
    pub continues: bool,
    /// Highest material anywhere when the run began: the shank and holder are
    /// tested only where they can reach below it.
    pub max_top: f64,
}

/// The number of ball placements a stroke is applied as, or `None` when it
/// is swept exactly (not a vertical ball, too long, or low enough for the
/// shank or holder to meet material).
fn placements(s: &Stroke, tool: &ToolBody, g: &Grid, max_top: f64) -> Option<usize> {
    if !s.vertical() || !matches!(tool.shape, Shape::Ball { .. }) {
        return None;
    }
    let reach_noncut = s.p0.z.min(s.p1.z) + tool.flute < max_top;
    let len = (s.p1 - s.p0).length();
    if reach_noncut || len > 40.0 * g.res {
        return None;
    }
    // Balls placed δ apart miss at most δ²/8R between them: δ = √(0.08·R·res)
    // keeps that to a hundredth of a cell (and δ is never below a cell).
    let step = g.res.max((0.08 * tool.radius() * g.res).sqrt());
    Some(((len / step).ceil() as usize).max(1))
}

/// Applies one stroke to a band of rows.
pub fn apply(band: &mut Band, s: &Stroke, a: &Apply, out: &mut StrokeCut) {
    if s.vertical() {
        apply_vertical(band, s, a, out);
    } else {
        apply_tilted(band, s, a, out);
    }
}

fn apply_vertical(band: &mut Band, s: &Stroke, a: &Apply, out: &mut StrokeCut) {
    let tool = a.tool;
    let sw = VerticalSweep::new(*tool, s.p0, s.p1);
    let g = &a.grid;
    let reach_noncut = s.p0.z.min(s.p1.z) + tool.flute < a.max_top;
    let n = DVec2::new(-sw.u.y, sw.u.x);
    // A ball on a stroke of up to 40 cells: the ball placed at steps along
    // it (cheaper than the exact capsule over so short a stroke).
    if let Some(k) = placements(s, tool, g, a.max_top) {
        let at = |m: usize| {
            if m == k {
                s.p1
            } else {
                s.p0.lerp(s.p1, m as f64 / k as f64)
            }
        };
        for m in 1..=k {
            // The next placement of the same stroke; the stroke's last
            // leaves nothing to the next stroke, so that each stroke's
            // removal is its own.
            let next = (m < k).then(|| at(m + 1));
            let pose = Placement {
                q0: at(m - 1),
                q1: at(m),
                next,
                cont: m > 1 || a.continues,
            };
            ball_pose(band, &pose, tool.radius(), g, n, out);
        }
        return;
    }
    let rad = if reach_noncut {
        tool.reach()
    } else {
        tool.radius()
    };
    let descending = s.p1.z < s.p0.z - 1e-12;
    // Cells behind the start cannot go lower than the previous stroke's end
    // left them unless the stroke descends.
    let front_only = a.continues && !descending && sw.len > 1e-12;
    let p0 = s.p0.truncate();
    let p1 = s.p1.truncate();
    let Some((ja, jb)) = band_rows(band, g, p0.y.min(p1.y) - rad, p0.y.max(p1.y) + rad) else {
        return;
    };
    for j in ja..=jb {
        let y = g.cy(j);
        let Some((xa, xb)) = stadium_row(p0, p1, sw.u, sw.len, rad, y) else {
            continue;
        };
        let (xa, xb) = if front_only {
            match half_plane_row(p0, sw.u, y, xa, xb) {
                Some(r) => r,
                None => continue,
            }
        } else {
            (xa, xb)
        };
        let Some((i0, i1)) = g.span(xa, xb) else {
            continue;
        };
        let r = j - band.j0;
        let nx = g.nx;
        let row_top = &mut band.top[r * nx..(r + 1) * nx];
        let row_bot = &band.bot[r * nx..(r + 1) * nx];
        let gaps = &mut band.gaps[r];
        let mut acc = StrokeCut::default();
        for i in i0..=i1 {
            let c = DVec2::new(g.cx(i), y);
            let cc = sw.column(c);
            if cc.cut == f64::INFINITY {
                continue;
            }
            let lat = (c - p1).dot(n);
            cut_above(
                &mut row_top[i],
                row_bot[i],
                gaps,
                i as u32,
                cc.cut,
                cc.noncut,
                lat,
                &mut acc,
            );
        }
        acc.removed *= g.res * g.res;
        out.merge(&acc);
    }
}

/// The band's rows whose centres lie in [ya, yb].
fn band_rows(band: &Band, g: &Grid, ya: f64, yb: f64) -> Option<(usize, usize)> {
    let (ja, jb) = g.rows(ya, yb)?;
    let ja = ja.max(band.j0);
    let jb = jb.min(band.j0 + band.rows - 1);
    (ja <= jb).then_some((ja, jb))
}

/// One ball placement: the tip at `q1`, coming from `q0` (applied when
/// `cont`), going on to `next` (to be applied after it).
struct Placement {
    q0: DVec3,
    q1: DVec3,
    next: Option<DVec3>,
    cont: bool,
}

/// How far ahead of the bisector of a–b (horizontal distance, tips at a then
/// b) the ball at b is sure to stand no higher than the ball at a: anywhere
/// ahead when b is not higher; when it rises by Δ, from l/4 + √(l²/16 + Δ·r²/l)
/// on (the mirror of the bound behind a bisector in [`ball_pose`]).
fn lower_ahead(l: f64, rise: f64, r: f64) -> f64 {
    if rise > 0.0 {
        0.25 * l + (l * l / 16.0 + rise * r * r / l.max(1e-12)).sqrt()
    } else {
        0.0
    }
}

/// A ball of radius `r` placed as `pose` says: when `cont` (the ball at q0
/// was applied) and it does not descend, only the cells ahead of the
/// bisector of q0–q1 can change; with a `next` placement, cells far enough
/// ahead of the bisector of q1–next are left to it, since it cuts them at
/// least as low (and applies to every cell ahead of that bisector).
fn ball_pose(band: &mut Band, pose: &Placement, r: f64, g: &Grid, n: DVec2, out: &mut StrokeCut) {
    let (q0, q1) = (pose.q0, pose.q1);
    let d = (q1 - q0).truncate();
    let l = d.length();
    let front_only = pose.cont && l > 1e-12;
    let u = d.normalize_or_zero();
    // The far side of the strip: cells whose distance ahead of the next
    // bisector is at least `ahead` are the next placement's.
    let back = pose.next.and_then(|qn| {
        let dn = (qn - q1).truncate();
        let ln = dn.length();
        (ln > 1e-12).then(|| {
            let un = dn / ln;
            let ahead = lower_ahead(ln, qn.z - q1.z, r);
            // Points p with (p − m)·un < 0 are kept, m on the line `ahead`
            // beyond the bisector.
            ((q1.truncate() + qn.truncate()) * 0.5 + un * ahead, un)
        })
    });
    // Behind the bisector of q0–q1 (w = distance behind it) the ball rises:
    // d1² − d0² = 2·l·w, so d1 − d0 ≥ l·w/r, and the underside's slope is at
    // least d/r, so it rises by at least l·w·d0/r² ≥ l·w·(w − l/2)/r². A cell
    // can go lower only if that is less than the drop Δ = z0 − z1: none
    // farther behind than w_max = l/4 + √(l²/16 + Δ·r²/l).
    let w_max = lower_ahead(l, q0.z - q1.z, r);
    let mid = (q0.truncate() + q1.truncate()) * 0.5 - u * w_max;
    let c = q1.truncate();
    let Some((ja, jb)) = band_rows(band, g, c.y - r, c.y + r) else {
        return;
    };
    let zc = q1.z + r;
    let nx = g.nx;
    let nb = nx.div_ceil(super::BLOCK);
    let inv_res = 1.0 / g.res;
    // The half-plane on row y: x ≥ (or ≤) mid.x − (y − mid.y)·u.y/u.x.
    let along_x = u.x.abs() >= 1e-15;
    let slope = if along_x { u.y / u.x } else { 0.0 };
    let mut acc = StrokeCut::default();
    let mut lanes = Lanes::new();
    for j in ja..=jb {
        let y = g.cy(j);
        let dy = y - c.y;
        let h2 = r * r - dy * dy;
        if h2 < 0.0 {
            continue;
        }
        let h = h2.sqrt();
        let (mut xa, mut xb) = (c.x - h, c.x + h);
        if front_only {
            if along_x {
                let x = mid.x - (y - mid.y) * slope;
                if u.x > 0.0 {
                    xa = xa.max(x);
                } else {
                    xb = xb.min(x);
                }
            } else if (y - mid.y) * u.y < 0.0 {
                continue;
            }
        }
        if let Some((m, un)) = back {
            // Keep (p − m)·un < 0, with a cell's margin for the rounding of
            // the span to cell centres.
            if un.x.abs() >= 1e-15 {
                let x = m.x - (y - m.y) * un.y / un.x;
                if un.x > 0.0 {
                    xb = xb.min(x + g.res);
                } else {
                    xa = xa.max(x - g.res);
                }
            } else if (y - m.y) * un.y >= g.res {
                continue;
            }
        }
        // The columns whose centres lie in [xa, xb] (Grid::span without
        // its divisions).
        let ia = super::ceil((xa - g.x0) * inv_res - 0.5).max(0.0);
        let ib = super::floor((xb - g.x0) * inv_res - 0.5);
        if !(ib >= ia) || ia >= nx as f64 {
            continue;
        }
        let (i0, i1) = (ia as usize, (ib as usize).min(nx - 1));
        let row = j - band.j0;
        let row_top = &mut band.top[row * nx..(row + 1) * nx];
        let row_bot = &band.bot[row * nx..(row + 1) * nx];
        let gaps = &mut band.gaps[row];
        if gaps.is_empty() {
            ball_row(
                row_top,
                row_bot,
                &mut band.bmax[row * nb..(row + 1) * nb],
                (i0, i1),
                (g.cx(0) - c.x) as f32,
                g.res as f32,
                dy as f32,
                zc as f32,
                r as f32,
                n,
                &mut lanes,
            );
            lanes.flush_removed(&mut acc);
        } else {
            for i in i0..=i1 {
                let p = DVec2::new(g.cx(i), y);
                let under = r * r - (p - c).length_squared();
                if under < 0.0 {
                    continue;
                }
                let lat = (p - c).dot(n);
                cut_above(
                    &mut row_top[i],
                    row_bot[i],
                    gaps,
                    i as u32,
                    zc - under.sqrt(),
                    f64::INFINITY,
                    lat,
                    &mut acc,
                );
            }
        }
    }
    lanes.finish(&mut acc);
    acc.removed *= g.res * g.res;
    out.merge(&acc);
}

/// The span [xa, xb] of row y within `rad` of the segment p0–p1.
fn stadium_row(p0: DVec2, p1: DVec2, u: DVec2, len: f64, rad: f64, y: f64) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for p in [p0, p1] {
        let dy = y - p.y;
        let h2 = rad * rad - dy * dy;
        if h2 >= 0.0 {
            let h = h2.sqrt();
            lo = lo.min(p.x - h);
            hi = hi.max(p.x + h);
        }
    }
    if len > 1e-12 && u.y.abs() > 1e-12 {
        // The band |(q − p0)·n| ≤ rad, 0 ≤ (q − p0)·u ≤ len on the line y.
        let n = DVec2::new(-u.y, u.x);
        let mut a = f64::NEG_INFINITY;
        let mut b = f64::INFINITY;
        // Constraint: lo_c ≤ (x − p0.x)·k.x + (y − p0.y)·k.y ≤ hi_c.
        for (k, lo_c, hi_c) in [(n, -rad, rad), (u, 0.0, len)] {
            let base = (y - p0.y) * k.y;
            if k.x.abs() < 1e-15 {
                if base < lo_c || base > hi_c {
                    a = f64::INFINITY;
                }
                continue;
            }
            let t1 = p0.x + (lo_c - base) / k.x;
            let t2 = p0.x + (hi_c - base) / k.x;
            a = a.max(t1.min(t2));
            b = b.min(t1.max(t2));
        }
        if a <= b {
            lo = lo.min(a);
            hi = hi.max(b);
        }
    } else if len > 1e-12 {
        // Along X: the band is the rectangle between the two discs.
        if (y - p0.y).abs() <= rad {
            lo = lo.min(p0.x.min(p1.x));
            hi = hi.max(p0.x.max(p1.x));
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// The part of [xa, xb] on row y with (q − m)·u ≥ 0.
fn half_plane_row(m: DVec2, u: DVec2, y: f64, xa: f64, xb: f64) -> Option<(f64, f64)> {
    let base = (y - m.y) * u.y;
    if u.x.abs() < 1e-15 {
        return (base >= 0.0).then_some((xa, xb));
    }
    let x = m.x - base / u.x;
    let (a, b) = if u.x > 0.0 {
        (xa.max(x), xb)
    } else {
        (xa, xb.min(x))
    };
    (a <= b).then_some((a, b))
}

const L: usize = 8;

/// Per number of valid lanes: 0 for a valid lane, −∞ for a masked one.
const PAD: [[f32; L]; L + 1] = {
    let mut t = [[0.0f32; L]; L + 1];
    let mut v = 0;
    while v <= L {
        let mut l = v;
        while l < L {
            t[v][l] = f32::NEG_INFINITY;
            l += 1;
        }
        v += 1;
    }
    t
};

/// Per-lane sums of [`ball_row`].
struct Lanes {
    removed: [f32; L],
    depth: [f32; L],
    hi: [f32; L],
    /// Lateral offsets (across the feed) of the cells cut into.
    lmin: [f32; L],
    lmax: [f32; L],
    /// Something was removed since the last flush.
    dirty: bool,
}

impl Lanes {
    fn new() -> Lanes {
        Lanes {
            removed: [0.0; L],
            depth: [0.0; L],
            hi: [f32::NEG_INFINITY; L],
            lmin: [f32::INFINITY; L],
            lmax: [f32::NEG_INFINITY; L],
            dirty: false,
        }
    }

    /// Moves the removed lengths into `out` (in f64, row by row, so small
    /// removals do not vanish in a large f32 sum).
    fn flush_removed(&mut self, out: &mut StrokeCut) {
        if !self.dirty {
            return;
        }
        out.removed += self.removed.iter().map(|v| *v as f64).sum::<f64>();
        self.removed = [0.0; L];
        self.dirty = false;
    }

    fn finish(mut self, out: &mut StrokeCut) {
        self.flush_removed(out);
        let lmin = self.lmin.iter().fold(f32::INFINITY, |a, b| a.min(*b));
        let lmax = self.lmax.iter().fold(f32::NEG_INFINITY, |a, b| a.max(*b));
        if lmin <= lmax {
            out.depth = out
                .depth
                .max(self.depth.iter().fold(0.0f32, |a, b| a.max(*b)) as f64);
            out.top = out
                .top
                .max(self.hi.iter().fold(f32::NEG_INFINITY, |a, b| a.max(*b)) as f64);
            out.side = [out.side[0].min(lmin as f64), out.side[1].max(lmax as f64)];
        }
    }
}

/// A ball standing at one place over a row of cells without gaps: the tight
/// loop of finishing paths. `dx0`: x of the first cell's centre from the ball's
/// axis; `dy`: the row's offset; `zc`: the ball centre's height. Cells go in
/// groups of eight, each loop without branches so that it vectorises; a group
/// the ball cannot lower (tested without the square root) is left alone.
#[allow(clippy::too_many_arguments)]
#[inline]
fn ball_row(
    top: &mut [f32],
    bot: &[f32],
    bmax: &mut [f32],
    (i0, i1): (usize, usize),
    dx0: f32,
    res: f32,
    dy: f32,
    zc: f32,
    r: f32,
    n: DVec2,
    acc: &mut Lanes,
) {
    use super::BLOCK;
    let under0 = r * r - dy * dy;
    let lat = (dy * n.y as f32, n.x as f32);
    // Indexes both the cells and their block maxima.
    #[allow(clippy::needless_range_loop)]
    for kb in i0 / BLOCK..=i1 / BLOCK {
        let a = i0.max(kb * BLOCK);
        let b = i1.min(kb * BLOCK + BLOCK - 1);
        // The ball's lowest point over these cells: a block it passes above
        // is left alone.
        let (xa, xb) = (dx0 + a as f32 * res, dx0 + b as f32 * res);
        let near = if xa <= 0.0 && xb >= 0.0 {
            0.0
        } else {
            xa.abs().min(xb.abs())
        };
        let u = under0 - near * near;
        let gap = zc - bmax[kb];
        // zc − √u ≥ bmax, without the root.
        if u < 0.0 || (gap >= 0.0 && gap * gap >= u) {
            continue;
        }
        let before = acc.removed;
        let mut k0 = a;
        while k0 + L <= b + 1 {
            let t: &mut [f32; L] = (&mut top[k0..k0 + L]).try_into().expect("eight cells");
            let bb: &[f32; L] = bot[k0..k0 + L].try_into().expect("eight cells");
            ball_group(t, bb, L, k0 as f32, dx0, res, under0, zc, lat, acc);
            k0 += L;
        }
        if k0 <= b {
            // The rest: eight cells with those beyond b masked off, or past
            // the row's end a padded copy.
            let m = b + 1 - k0;
            if k0 + L <= top.len() {
                let t: &mut [f32; L] = (&mut top[k0..k0 + L]).try_into().expect("eight cells");
                let bb: &[f32; L] = bot[k0..k0 + L].try_into().expect("eight cells");
                ball_group(t, bb, m, k0 as f32, dx0, res, under0, zc, lat, acc);
            } else {
                let mut t = [0.0f32; L];
                let mut bb = [0.0f32; L];
                t[..m].copy_from_slice(&top[k0..=b]);
                bb[..m].copy_from_slice(&bot[k0..=b]);
                ball_group(&mut t, &bb, m, k0 as f32, dx0, res, under0, zc, lat, acc);
                top[k0..=b].copy_from_slice(&t[..m]);
            }
        }
        if acc.removed != before {
            bmax[kb] = block_max(top, kb);
            acc.dirty = true;
        }
    }
}

/// Eight cells of [`ball_row`] starting at cell `k0` of the row.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn ball_group(
    t: &mut [f32; L],
    b: &[f32; L],
    valid: usize,
    k0: f32,
    dx0: f32,
    res: f32,
    under0: f32,
    zc: f32,
    (lat0, latx): (f32, f32),
    acc: &mut Lanes,
) {
    const LANE: [f32; L] = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];
    let base = dx0 + k0 * res;
    // A masked lane is outside the ball (u = −∞): left as it is.
    let pad = &PAD[valid.min(L)];
    let mut under = [0.0f32; L];
    let mut live = [0u32; L];
    for l in 0..L {
        let dx = base + LANE[l] * res;
        let u = (under0 - dx * dx) + pad[l];
        under[l] = u;
        let gap = zc - t[l];
        // The ball's underside zc − √u is below the top iff gap < 0 or gap² < u.
        live[l] = u32::from((u >= 0.0) & ((gap < 0.0) | (gap * gap < u)));
    }
    if live.iter().fold(0, |a, v| a | v) == 0 {
        return;
    }
    let eps = CUT_EPS as f32;
    for l in 0..L {
        let u = under[l];
        let root = if u > 0.0 { u } else { 0.0 }.sqrt();
        let cut = if u >= 0.0 { zc - root } else { f32::INFINITY };
        let old = t[l];
        let new = if cut < old { cut } else { old };
        let new = if new > b[l] { new } else { b[l] };
        let new = if old > b[l] { new } else { old };
        let d = old - new;
        t[l] = new;
        acc.removed[l] += d;
        let cutting = d > eps;
        let lat = (base + LANE[l] * res) * latx + lat0;
        acc.depth[l] = if cutting & (d > acc.depth[l]) {
            d
        } else {
            acc.depth[l]
        };
        acc.hi[l] = if cutting & (old > acc.hi[l]) {
            old
        } else {
            acc.hi[l]
        };
        acc.lmin[l] = if cutting & (lat < acc.lmin[l]) {
            lat
        } else {
            acc.lmin[l]
        };
        acc.lmax[l] = if cutting & (lat > acc.lmax[l]) {
            lat
        } else {
            acc.lmax[l]
        };
    }
}

/// Removes everything above `cut` from one cell; material above `noncut`
/// was met by the shank or holder. `lat`: the cell's offset across the feed.
#[allow(clippy::too_many_arguments)]
#[inline]
fn cut_above(
    top: &mut f32,
    bot: f32,
    gaps: &mut RowGaps,
    i: u32,
    cut: f64,
    noncut: f64,
    lat: f64,
    out: &mut StrokeCut,
) {
    let old = *top as f64;
    let b = bot as f64;
    if old <= b || cut >= old {
        return;
    }
    if noncut < old {
        out.noncut = out.noncut.max(old - noncut.max(b));
    }
    let new = cut.max(b);
    let mut removed = old - new;
    let mut new_top = new as f32;
    if let Some(g) = gaps.get_mut(&i) {
        // Air between the new top and the old one was not material.
        let mut keep = Vec::with_capacity(g.len());
        for &[ga, gb] in g.iter() {
            let (ga64, gb64) = (ga as f64, gb as f64);
            if ga64 >= new {
                removed -= gb64 - ga64;
            } else if gb64 > new {
                removed -= gb64 - new;
                new_top = ga;
            } else {
                keep.push([ga, gb]);
            }
        }
        if keep.is_empty() {
            gaps.remove(&i);
        } else {
            *g = keep;
        }
    }
    *top = new_top;
    if removed > 0.0 {
        out.removed += removed;
        if removed > CUT_EPS {
            out.depth = out.depth.max(old - new);
            out.top = out.top.max(old);
            out.side = [out.side[0].min(lat), out.side[1].max(lat)];
        }
    }
}

/// The highest top among the cells of block `kb` of a row.
#[inline]
fn block_max(row: &[f32], kb: usize) -> f32 {
    let b = super::BLOCK;
    row[kb * b..(kb * b + b).min(row.len())]
        .iter()
        .fold(f32::NEG_INFINITY, |m, t| m.max(*t))
}

/// Removes [lo, hi] from cell `i` of band row `r` and adds it to `acc` (a
/// cutting part's removal also to the depth, top and lateral extent).
#[allow(clippy::too_many_arguments)]
fn take_interval(
    band: &mut Band,
    nx: usize,
    (r, i): (usize, usize),
    lo: f64,
    hi: f64,
    cutting: bool,
    lat: f64,
    acc: &mut StrokeCut,
) {
    let k = r * nx + i;
    let (mut tt, mut bb) = (band.top[k], band.bot[k]);
    let old = tt as f64;
    let rem = cut_interval(&mut tt, &mut bb, &mut band.gaps[r], i as u32, lo, hi);
    band.top[k] = tt;
    band.bot[k] = bb;
    if rem > 0.0 {
        acc.removed += rem;
        if cutting && rem > CUT_EPS {
            acc.depth = acc.depth.max(rem);
            acc.top = acc.top.max(old.min(hi));
            acc.side = [acc.side[0].min(lat), acc.side[1].max(lat)];
        }
    }
}

/// Removes [lo, hi] from one cell (a tilted tool's part); returns the material
/// removed, mm.
fn cut_interval(top: &mut f32, bot: &mut f32, gaps: &mut RowGaps, i: u32, lo: f64, hi: f64) -> f64 {
    let (t, b) = (*top as f64, *bot as f64);
    if t <= b || hi <= b || lo >= t {
        return 0.0;
    }
    // Material intervals, then subtract.
    let mut iv: Vec<[f64; 2]> = Vec::with_capacity(2);
    let mut start = b;
    if let Some(g) = gaps.get(&i) {
        for [ga, gb] in g {
            iv.push([start, *ga as f64]);
            start = *gb as f64;
        }
    }
    iv.push([start, t]);
    let mut removed = 0.0;
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(iv.len() + 1);
    for [a, c] in iv {
        let (x, y) = (a.max(lo), c.min(hi));
        if x < y {
            removed += y - x;
            if a < x {
                out.push([a, x]);
            }
            if y < c {
                out.push([y, c]);
            }
        } else {
            out.push([a, c]);
        }
    }
    out.retain(|[a, c]| c > a);
    if out.is_empty() {
        *top = *bot;
        gaps.remove(&i);
        return removed;
    }
    *bot = out[0][0] as f32;
    *top = out[out.len() - 1][1] as f32;
    if out.len() > 1 {
        gaps.insert(
            i,
            out.windows(2)
                .map(|w| [w[0][1] as f32, w[1][0] as f32])
                .collect(),
        );
    } else {
        gaps.remove(&i);
    }
    removed
}

fn apply_tilted(band: &mut Band, s: &Stroke, a: &Apply, out: &mut StrokeCut) {
    let tool = a.tool;
    let g = &a.grid;
    let turn = s.a0.dot(s.a1).clamp(-1.0, 1.0).acos();
    // When the axis turns, a point h up the axis and ρ from it moves by at
    // most turn·(h + ρ); only the part that can be below the highest
    // material counts: a point h up the axis stands at least h·a_z − R·sin γ
    // above the tip.
    let az = s.a0.z.min(s.a1.z);
    let below_top = if az > 0.2 {
        let sin_g = (1.0 - az * az).max(0.0).sqrt();
        ((a.max_top - s.p0.z.min(s.p1.z) + tool.reach() * sin_g) / az).max(0.0)
    } else {
        f64::INFINITY
    };
    let arm = tool.flute.min(10.0 * tool.radius()).min(below_top) + tool.reach();
    let travel = (s.p1 - s.p0).length() + turn * arm;
    // Half a cell; for a ball, placements δ apart miss at most δ²/8R between
    // them, a hundredth of a cell at δ = √(0.08·R·res), as in the vertical case.
    let step = match tool.shape {
        Shape::Ball { radius } => (0.5 * g.res).max((0.08 * radius * g.res).sqrt()),
        _ => 0.5 * g.res,
    };
    let n = ((travel / step).ceil() as usize).clamp(1, 1_000_000);
    let first = if a.continues { 1 } else { 0 };
    let feed = (s.p1 - s.p0).truncate();
    let nrm = DVec2::new(-feed.y, feed.x).normalize_or_zero();
    for k in first..=n {
        let t = k as f64 / n as f64;
        let pose = Pose {
            tool: *tool,
            tip: s.p0.lerp(s.p1, t),
            axis: s.axis_at(t),
        };
        if !ball_capsule(band, &pose, g, a.max_top, nrm, out) {
            apply_pose(band, &pose, g, a.max_top, nrm, out);
        }
    }
}

/// A tilted ball-end mill whose shank and holder cannot reach material: its
/// body is the capsule of radius R around the axis from the ball centre up,
/// met by a cell's line in one interval found in closed form (the sphere and
/// the cylinder's roots). Returns false, doing nothing, for any other tool.
fn ball_capsule(
    band: &mut Band,
    pose: &Pose,
    g: &Grid,
    max_top: f64,
    nrm: DVec2,
    out: &mut StrokeCut,
) -> bool {
    use super::BLOCK;
    let tool = &pose.tool;
    let Shape::Ball { radius: r } = tool.shape else {
        return false;
    };
    let a = pose.axis;
    if a.z < 0.2 || tool.shank_r > r + 1e-9 || pose.noncut_lowest() < max_top {
        return false;
    }
    let c = pose.tip + a * r;
    // Up the axis only as far as the capsule can be below the highest material.
    let len = ((max_top - c.z + r) / a.z).clamp(0.0, (tool.flute - r).max(0.0));
    let top = c + a * len;
    let (c2, t2) = (c.truncate(), top.truncate());
    let d = t2 - c2;
    let dl = d.length();
    let u = if dl > 1e-12 { d / dl } else { DVec2::X };
    let Some((ja, jb)) = band_rows(band, g, c2.y.min(t2.y) - r, c2.y.max(t2.y) + r) else {
        return true;
    };
    let nx = g.nx;
    let nb = nx.div_ceil(BLOCK);
    let ca = 1.0 - a.z * a.z;
    // A nearly upright axis: the cylinder is taken as straight up.
    let cyl = ca > 1e-9;
    let inv2ca = if cyl { 0.5 / ca } else { 0.0 };
    let inv_az = 1.0 / a.z;
    let mut acc = StrokeCut::default();
    for j in ja..=jb {
        let y = g.cy(j);
        let Some((xa, xb)) = stadium_row(c2, t2, u, dl, r, y) else {
            continue;
        };
        let Some((i0, i1)) = g.span(xa, xb) else {
            continue;
        };
        let row = j - band.j0;
        let wy = y - c.y;
        for kb in i0 / BLOCK..=i1 / BLOCK {
            let (ba, bb) = (i0.max(kb * BLOCK), i1.min(kb * BLOCK + BLOCK - 1));
            // The capsule is no lower than the centre segment's lowest point
            // within r of these cells, minus r.
            let (mut t0, mut t1) = (0.0, len);
            for (p, dd, lo, hi) in [
                (c.x, a.x, g.cx(ba) - r, g.cx(bb) + r),
                (c.y, a.y, y - r, y + r),
            ] {
                if dd.abs() < 1e-12 {
                    if p < lo || p > hi {
                        t0 = f64::INFINITY;
                    }
                    continue;
                }
                let (v0, v1) = ((lo - p) / dd, (hi - p) / dd);
                t0 = t0.max(v0.min(v1));
                t1 = t1.min(v0.max(v1));
            }
            if t0 > t1 || c.z + a.z * t0 - r >= band.bmax[row * nb + kb] as f64 {
                continue;
            }
            let before = acc.removed;
            // The capsule over the block's cells, without branches so that
            // it vectorises: the sphere, and the cylinder above the centre
            // ((1 − az²) z² − 2 (w·a) az z + (|w|² − (w·a)² − r²) = 0, the far
            // end above all material).
            let mut los = [f64::INFINITY; BLOCK];
            let mut his = [f64::NEG_INFINITY; BLOCK];
            let x0 = g.cx(ba) - c.x;
            for q in 0..BLOCK {
                let wx = x0 + q as f64 * g.res;
                let w2 = wx * wx + wy * wy;
                let wa = wx * a.x + wy * a.y;
                let us = r * r - w2;
                let ss = if us > 0.0 { us } else { 0.0 }.sqrt();
                let (lo_s, hi_s) = if us >= 0.0 {
                    (c.z - ss, c.z + ss)
                } else {
                    (f64::INFINITY, f64::NEG_INFINITY)
                };
                let qb = -2.0 * wa * a.z;
                let qc = w2 - wa * wa - r * r;
                let disc = qb * qb - 4.0 * ca * qc;
                let sq = if disc > 0.0 { disc } else { 0.0 }.sqrt();
                let z1 = (-qb - sq) * inv2ca;
                let z2 = (-qb + sq) * inv2ca;
                let z0 = if z1 > -wa * inv_az { z1 } else { -wa * inv_az };
                let ok = cyl & (disc >= 0.0) & (z0 <= z2);
                let lo_c = c.z + z0;
                let hi_c = c.z + z2;
                los[q] = if ok & (lo_c < lo_s) { lo_c } else { lo_s };
                his[q] = if ok & (hi_c > hi_s) { hi_c } else { hi_s };
                // Straight up: the cylinder above the ball.
                his[q] = if !cyl & (us >= 0.0) {
                    f64::INFINITY
                } else {
                    his[q]
                };
            }
            for i in ba..=bb {
                let k = row * nx + i;
                let (t, b) = (band.top[k] as f64, band.bot[k] as f64);
                let (lo, hi) = (los[i - ba], his[i - ba]);
                if t <= b || lo >= t {
                    continue;
                }
                let lat = (DVec2::new(g.cx(i), y) - pose.tip.truncate()).dot(nrm);
                if hi >= t {
                    cut_above(
                        &mut band.top[k],
                        band.bot[k],
                        &mut band.gaps[row],
                        i as u32,
                        lo,
                        f64::INFINITY,
                        lat,
                        &mut acc,
                    );
                } else {
                    take_interval(band, nx, (row, i), lo, hi, true, lat, &mut acc);
                }
            }
            if acc.removed != before {
                band.bmax[row * nb + kb] = block_max(&band.top[row * nx..(row + 1) * nx], kb);
            }
        }
    }
    acc.removed *= g.res * g.res;
    out.merge(&acc);
    true
}

/// One placement of a (possibly tilted) tool. The body lies within `reach`
/// of its axis, so over a rectangle of cells it is no lower than the axis's
/// lowest point within that distance minus `reach`: tiles, then blocks of a
/// row, whose highest material is below that are passed over.
fn apply_pose(
    band: &mut Band,
    pose: &Pose,
    g: &Grid,
    max_top: f64,
    nrm: DVec2,
    out: &mut StrokeCut,
) {
    use super::BLOCK;
    let tool = &pose.tool;
    let a = pose.axis;
    // Only as high up the axis as any point of the body can still be below
    // the highest material.
    let rho = tool.reach();
    let side = rho * (1.0 - a.z * a.z).max(0.0).sqrt();
    let height = ((max_top - pose.tip.z + side) / a.z.max(1e-3)).clamp(0.0, 1e4);
    let height = if pose.tip.z + tool.flute * a.z.min(1.0) < max_top {
        height.max(tool.flute)
    } else {
        height.min(tool.flute)
    };
    let (lo, hi) = pose.xy_box(height);
    let Some((ja, jb)) = band_rows(band, g, lo.y, hi.y) else {
        return;
    };
    let Some((i0, i1)) = g.span(lo.x, hi.x) else {
        return;
    };
    let tip = pose.tip;
    // Lowest possible z of the body over the cell centres in [x0, x1] × [y0, y1].
    let lowest = |x0: f64, x1: f64, y0: f64, y1: f64| -> Option<f64> {
        if a.z <= 0.0 {
            return Some(f64::NEG_INFINITY);
        }
        let (mut t0, mut t1) = (0.0, height);
        for (p, d, lo, hi) in [
            (tip.x, a.x, x0 - rho, x1 + rho),
            (tip.y, a.y, y0 - rho, y1 + rho),
        ] {
            if d.abs() < 1e-12 {
                if p < lo || p > hi {
                    return None;
                }
                continue;
            }
            let (u, v) = ((lo - p) / d, (hi - p) / d);
            t0 = f64::max(t0, u.min(v));
            t1 = f64::min(t1, u.max(v));
        }
        (t0 <= t1).then_some(tip.z + a.z * t0 - rho)
    };
    let nx = g.nx;
    let nb = nx.div_ceil(BLOCK);
    let ntx = nx.div_ceil(TILE);
    let noncut = pose.noncut_lowest() < max_top;
    let mut acc = StrokeCut::default();
    let (ra, rb) = (ja - band.j0, jb - band.j0);
    for ty in ra / TILE_ROWS..=rb / TILE_ROWS {
        let (r0, r1) = (
            ra.max(ty * TILE_ROWS),
            rb.min(ty * TILE_ROWS + TILE_ROWS - 1),
        );
        for tx in i0 / TILE..=i1 / TILE {
            let (c0, c1) = (i0.max(tx * TILE), i1.min(tx * TILE + TILE - 1));
            let (y0, y1) = (g.cy(band.j0 + r0), g.cy(band.j0 + r1));
            match lowest(g.cx(c0), g.cx(c1), y0, y1) {
                Some(z) if z < band.tmax[ty * ntx + tx] as f64 => {}
                _ => continue,
            }
            let mut changed = false;
            for r in r0..=r1 {
                let y = g.cy(band.j0 + r);
                for kb in c0 / BLOCK..=c1 / BLOCK {
                    let (ba, bb) = (c0.max(kb * BLOCK), c1.min(kb * BLOCK + BLOCK - 1));
                    match lowest(g.cx(ba), g.cx(bb), y, y) {
                        Some(z) if z < band.bmax[r * nb + kb] as f64 => {}
                        _ => continue,
                    }
                    let before = acc.removed;
                    for i in ba..=bb {
                        pose_cell(band, pose, g, (r, i), noncut, nrm, &mut acc);
                    }
                    if acc.removed != before {
                        band.bmax[r * nb + kb] = block_max(&band.top[r * nx..(r + 1) * nx], kb);
                        changed = true;
                    }
                }
            }
            if changed {
                band.refresh_tile(nx, ty, tx);
            }
        }
    }
    acc.removed *= g.res * g.res;
    out.merge(&acc);
}

/// One cell (row `r` of the band, column `i`) under a placed tool.
fn pose_cell(
    band: &mut Band,
    pose: &Pose,
    g: &Grid,
    (r, i): (usize, usize),
    noncut: bool,
    nrm: DVec2,
    acc: &mut StrokeCut,
) {
    let k = r * g.nx + i;
    let (t, b) = (band.top[k] as f64, band.bot[k] as f64);
    if t <= b {
        return;
    }
    let c = DVec2::new(g.cx(i), g.cy(band.j0 + r));
    let (cut, noncut) = pose.column_parts(c, noncut);
    if let Some([l, h]) = noncut {
        if h > b && l < t {
            acc.noncut = acc.noncut.max(t.min(h) - l.max(b));
        }
    }
    for (iv, cutting) in [(cut, true), (noncut, false)] {
        let Some([l, h]) = iv else { continue };
        let lat = (c - pose.tip.truncate()).dot(nrm);
        take_interval(band, g.nx, (r, i), l, h, cutting, lat, acc);
    }
}

/// Whether stroke `k` continues stroke `k − 1` (same tool, starts where it
/// ended, same axis).
pub fn continues(strokes: &[Stroke], k: usize) -> bool {
    k > 0 && {
        let (p, s) = (&strokes[k - 1], &strokes[k]);
        p.tool == s.tool && p.p1 == s.p0 && (p.a1 - s.a0).length_squared() < 1e-18
    }
}

/// A stock run stroke by stroke, in order: the library entry point for
/// process models that need the stock as it is before each stroke (engagement
/// and forces), then remove it. A clone carries on exactly where the original
/// stands (the stock and what the last stroke left), so a run can be split at
/// any stroke and its parts continued on other threads.
#[derive(Clone)]
pub struct Simulator {
    pub stock: Stock,
    max_top: f64,
    last: Option<(u16, DVec3, DVec3)>,
    tmax: Vec<f32>,
}

impl Simulator {
    pub fn new(mut stock: Stock) -> Simulator {
        let max_top = stock.max_top();
        let nx = stock.grid.nx;
        let tmax = std::mem::take(
            &mut Band::new(
                0,
                nx,
                &mut stock.top,
                &mut stock.bot,
                &mut stock.gaps,
                &mut stock.bmax,
            )
            .tmax,
        );
        Simulator {
            stock,
            max_top,
            last: None,
            tmax,
        }
    }

    /// Removes one stroke of `tool` and says what it did.
    pub fn step(&mut self, s: &Stroke, tool: &ToolBody) -> StrokeCut {
        let continues = self.last.is_some_and(|(t, p, a)| {
            t == s.tool && p == s.p0 && (a - s.a0).length_squared() < 1e-18
        });
        self.last = Some((s.tool, s.p1, s.a1));
        let grid = self.stock.grid;
        let st = &mut self.stock;
        let mut band = Band {
            j0: 0,
            rows: grid.ny,
            top: &mut st.top,
            bot: &mut st.bot,
            gaps: &mut st.gaps,
            bmax: &mut st.bmax,
            tmax: std::mem::take(&mut self.tmax),
        };
        let mut out = StrokeCut::default();
        apply(
            &mut band,
            s,
            &Apply {
                grid,
                tool,
                continues,
                max_top: self.max_top,
            },
            &mut out,
        );
        self.tmax = std::mem::take(&mut band.tmax);
        out
    }
}

/// Rows per band of the parallel run: a band is a unit of work, so a stroke
/// touches a few of them and each band group sees most strokes.
const BAND_ROWS: usize = 32;
/// Band groups: fixed, so that sums do not depend on the thread count.
const GROUPS: usize = 16;

/// Runs every stroke over the stock. `progress(done)` is called now and then
/// with the number of strokes the first band group has done (all groups
/// have, at the end of each chunk of strokes); never decreasing.
pub fn simulate(
    stock: &mut Stock,
    strokes: &Strokes,
    progress: &(dyn Fn(usize) + Sync),
) -> Vec<StrokeCut> {
    let grid = stock.grid;
    let max_top = stock.max_top();
    let nx = grid.nx;
    let list = &strokes.strokes;
    let cont: Vec<bool> = (0..list.len()).map(|k| continues(list, k)).collect();
    // Bands, dealt to the groups in turn.
    let mut groups: Vec<Vec<Band>> = (0..GROUPS).map(|_| Vec::new()).collect();
    let nb = nx.div_ceil(super::BLOCK);
    for (b, (((top, bot), gaps), bmax)) in stock
        .top
        .chunks_mut(BAND_ROWS * nx)
        .zip(stock.bot.chunks_mut(BAND_ROWS * nx))
        .zip(stock.gaps.chunks_mut(BAND_ROWS))
        .zip(stock.bmax.chunks_mut(BAND_ROWS * nb))
        .enumerate()
    {
        groups[b % GROUPS].push(Band::new(b * BAND_ROWS, nx, top, bot, gaps, bmax));
    }
    // Strokes in chunks: each band group runs a chunk over its bands, then
    // the chunk's sums are gathered (in group order) before the next.
    let mut out = vec![StrokeCut::default(); list.len()];
    // Large chunks keep both threads busy (a chunk of a raster covers few
    // bands); progress comes from within the chunk.
    const CHUNK: usize = 1 << 19;
    let mut start = 0;
    while start < list.len() {
        let end = (start + CHUNK).min(list.len());
        let results: Vec<Vec<(u32, StrokeCut)>> = groups
            .par_iter_mut()
            .enumerate()
            .map(|(gi, bands)| {
                let mut touched = Vec::new();
                if bands.is_empty() {
                    return touched;
                }
                for k in start..end {
                    // The first group tells how far the run is within a chunk.
                    if gi == 0 && k % 16384 == 0 {
                        progress(k);
                    }
                    let s = &list[k];
                    let tool = &strokes.tools[s.tool as usize];
                    let a = Apply {
                        grid,
                        tool,
                        continues: cont[k],
                        max_top,
                    };
                    let (ylo, yhi) = y_reach(s, tool, max_top);
                    let mut acc = StrokeCut::default();
                    for band in bands.iter_mut() {
                        let (y0, y1) = (
                            grid.cy(band.j0) - grid.res,
                            grid.cy(band.j0 + band.rows - 1) + grid.res,
                        );
                        if y1 < ylo || y0 > yhi {
                            continue;
                        }
                        apply(band, s, &a, &mut acc);
                    }
                    if acc.touched() {
                        touched.push((k as u32, acc));
                    }
                }
                touched
            })
            .collect();
        for group in &results {
            for (k, c) in group {
                out[*k as usize].merge(c);
            }
        }
        progress(end);
        start = end;
    }
    out
}

/// The Y range a stroke's tool body can reach material in.
fn y_reach(s: &Stroke, tool: &ToolBody, max_top: f64) -> (f64, f64) {
    let mut rad = tool.reach();
    if !s.vertical() {
        let az = s.a0.z.min(s.a1.z).max(1e-3);
        let up = ((max_top - s.p0.z.min(s.p1.z) + rad) / az).clamp(0.0, 1e4);
        rad += up * (1.0 - az * az).max(0.0).sqrt();
    }
    (s.p0.y.min(s.p1.y) - rad, s.p0.y.max(s.p1.y) + rad)
}

/// What each IR move did, from its strokes.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MoveCut {
    /// Index of the move over the whole program.
    pub index: u32,
    pub line: u32,
    pub rapid: bool,
    /// Removed volume, mm³.
    pub removed_mm3: f64,
    /// Material removal rate, mm³/min (0 for a move of no duration).
    pub mrr: f64,
    /// Axial depth: the highest removed material above the lowest tool tip
    /// of the move, mm.
    pub ap: f64,
    /// Radial engagement: the width, across the feed, of the cells the move
    /// cut into, mm.
    pub ae: f64,
    /// A cutting move that removed nothing.
    pub air: bool,
    /// Deepest material met by the shank or holder, mm.
    pub holder_depth: f64,
    /// Deepest material met by the cutter, mm.
    pub depth: f64,
    pub minutes: f64,
}

/// Sums the strokes of each IR move (moves with no stroke are left out).
pub fn per_move(strokes: &Strokes, cuts: &[StrokeCut]) -> Vec<MoveCut> {
    let mut out: Vec<MoveCut> = Vec::new();
    let mut low = f64::INFINITY;
    let mut acc = StrokeCut::default();
    let flush = |out: &mut Vec<MoveCut>, acc: &StrokeCut, low: f64| {
        if let Some(m) = out.last_mut() {
            m.removed_mm3 = acc.removed;
            m.mrr = if m.minutes > 0.0 {
                acc.removed / m.minutes
            } else {
                0.0
            };
            m.ap = if acc.top > low { acc.top - low } else { 0.0 };
            m.ae = if acc.side[1] >= acc.side[0] {
                acc.side[1] - acc.side[0]
            } else {
                0.0
            };
            m.air = !m.rapid && acc.removed <= CUT_EPS * 1e-2;
            m.holder_depth = acc.noncut;
            m.depth = acc.depth;
        }
    };
    for (s, c) in strokes.strokes.iter().zip(cuts) {
        if out.last().is_none_or(|m| m.index != s.mv) {
            flush(&mut out, &acc, low);
            acc = StrokeCut::default();
            low = f64::INFINITY;
            out.push(MoveCut {
                index: s.mv,
                line: s.line,
                rapid: s.rapid,
                removed_mm3: 0.0,
                mrr: 0.0,
                ap: 0.0,
                ae: 0.0,
                air: false,
                holder_depth: 0.0,
                depth: 0.0,
                minutes: 0.0,
            });
        }
        let m = out.last_mut().expect("pushed above");
        m.minutes += s.minutes;
        // A cycle's feed strokes make the move a cutting one.
        m.rapid &= s.rapid;
        low = low.min(s.p0.z.min(s.p1.z));
        acc.merge(c);
    }
    flush(&mut out, &acc, low);
    out
}
