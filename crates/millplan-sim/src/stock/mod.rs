//! The workpiece as material: a z-dexel model, material removal by the tool's
//! swept volume, engagement per move and the result against the part.
//!
//! # Representation
//!
//! The stock is a grid of square cells of side `res` over the XY plane. Each
//! cell holds the material on the vertical line through its centre as one
//! interval `[bot, top]` and, where a tilted tool has cut under material
//! (an undercut) or a cast blank has a cavity, the gaps of air inside it.
//! So the model is exact along Z and sampled in X and Y: a volume is the sum
//! of the cells' material lengths times `res²`, and its error shrinks with the
//! cell (tests measure the convergence).
//!
//! Tilted tools are handled by the same columns: a tilted tool's body meets a
//! vertical line in one interval per convex part, and removing an interval
//! that ends below a cell's top opens a gap. Tri-dexels would resolve steep
//! walls better along X and Y; they triple the memory and the work per move,
//! and the five-axis tests (a tilted flat end mill against its analytic swept
//! volume) converge as the cell shrinks with z-dexels alone.
//!
//! # Conventions
//!
//! Part coordinates, mm. The tool axis points from the tip up the spindle.
//! Heights are stored as `f32` (6·10⁻⁵ mm at 1000 mm from the origin, far
//! below any useful cell size); sums are `f64`.

pub mod engage;
mod mesh;
pub mod path;
pub mod remaining;
pub mod run;
pub mod sim;
pub mod snapshot;
pub mod spec;
pub mod tool;

pub use mesh::stock_mesh;

use millplan_geom::{DVec2, DVec3, TriMesh};
use millplan_models::force::engage::floor_i64;
use rustc_hash::FxHashMap;

/// The XY grid of a stock: cell (i, j) has its centre at
/// (x0 + (i + ½)·res, y0 + (j + ½)·res).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub x0: f64,
    pub y0: f64,
    pub res: f64,
    pub nx: usize,
    pub ny: usize,
}

impl Grid {
    /// The grid of cell size `res` covering the rectangle `min`–`max`.
    pub fn covering(min: DVec2, max: DVec2, res: f64) -> Grid {
        let nx = (((max.x - min.x) / res).ceil() as usize).max(1);
        let ny = (((max.y - min.y) / res).ceil() as usize).max(1);
        Grid {
            x0: min.x,
            y0: min.y,
            res,
            nx,
            ny,
        }
    }

    /// The number of cells, saturating at `usize::MAX`: a memory estimate
    /// made from it before allocating never wraps to a small number (a
    /// 2³² × 2³² grid is not 0 cells).
    pub fn cells(&self) -> usize {
        self.nx.saturating_mul(self.ny)
    }

    /// The memory a stock on this grid takes before any gap is cut, bytes,
    /// in floating point so that no grid, however large, wraps it.
    pub fn stock_bytes(&self) -> f64 {
        self.nx as f64 * self.ny as f64 * BYTES_PER_CELL
    }

    #[inline]
    pub fn cx(&self, i: usize) -> f64 {
        self.x0 + (i as f64 + 0.5) * self.res
    }

    #[inline]
    pub fn cy(&self, j: usize) -> f64 {
        self.y0 + (j as f64 + 0.5) * self.res
    }

    /// The cell whose square holds (x, y).
    #[inline]
    pub fn cell_of(&self, x: f64, y: f64) -> Option<(usize, usize)> {
        // Truncation is the floor for u, v ≥ 0 (and NaN fails the test), so
        // no call to the C library's floor on this hot path.
        let u = (x - self.x0) / self.res;
        let v = (y - self.y0) / self.res;
        if !(u >= 0.0 && v >= 0.0) {
            return None;
        }
        let (i, j) = (u as usize, v as usize);
        (i < self.nx && j < self.ny).then_some((i, j))
    }

    /// The column indices whose centres lie in [xa, xb], clamped to the grid.
    #[inline]
    pub fn span(&self, xa: f64, xb: f64) -> Option<(usize, usize)> {
        let a = ceil((xa - self.x0) / self.res - 0.5).max(0.0);
        let b = floor((xb - self.x0) / self.res - 0.5);
        if !(b >= a) || a >= self.nx as f64 {
            return None;
        }
        Some((a as usize, (b as usize).min(self.nx - 1)))
    }

    /// The row indices whose centres lie in [ya, yb], clamped to the grid.
    #[inline]
    pub fn rows(&self, ya: f64, yb: f64) -> Option<(usize, usize)> {
        let a = ceil((ya - self.y0) / self.res - 0.5).max(0.0);
        let b = floor((yb - self.y0) / self.res - 0.5);
        if !(b >= a) || a >= self.ny as f64 {
            return None;
        }
        Some((a as usize, (b as usize).min(self.ny - 1)))
    }

    pub fn min(&self) -> DVec2 {
        DVec2::new(self.x0, self.y0)
    }

    pub fn max(&self) -> DVec2 {
        DVec2::new(
            self.x0 + self.nx as f64 * self.res,
            self.y0 + self.ny as f64 * self.res,
        )
    }
}

/// `x.floor()` inline (the x86-64 baseline has no rounding instruction, and
/// the library call shows in profiles). Exact for |x| < 2⁵²; NaN and
/// infinities pass through.
#[inline]
fn floor(x: f64) -> f64 {
    if !(x.abs() < 4.5e15) {
        return x;
    }
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

#[inline]
fn ceil(x: f64) -> f64 {
    -floor(-x)
}

/// Air inside the material interval of the cells of one row: cell index →
/// sorted, disjoint gaps strictly inside (bot, top).
pub type RowGaps = FxHashMap<u32, Vec<[f32; 2]>>;

/// A z-dexel stock (see the module docs).
#[derive(Clone, Debug)]
pub struct Stock {
    pub grid: Grid,
    /// Top of the material per cell (row-major, `j * nx + i`); a cell with
    /// `top <= bot` is empty.
    pub(crate) top: Vec<f32>,
    pub(crate) bot: Vec<f32>,
    /// Per row.
    pub(crate) gaps: Vec<RowGaps>,
    /// Per row, per block of [`BLOCK`] cells: at least the highest top in the
    /// block (tops only go down, so a stale value is still a bound), for
    /// skipping blocks a tool passes above.
    pub(crate) bmax: Vec<f32>,
}

/// Cells per block of the stock's block maxima (a row of a block is the unit
/// a tool passing above is skipped by).
pub const BLOCK: usize = 32;

/// The side of the tiles of [`Stock::sector_tops`] for a tool of radius
/// `radius`, cells: about 1/32 of the tool's width.
pub fn sector_tile(radius: f64, res: f64) -> usize {
    ((2.0 * radius / res / 32.0).ceil() as usize).max(1)
}

/// The highest material by distance from an axis and by angle about it
/// ([`Stock::sector_tops`]).
#[derive(Clone, Debug, Default)]
pub struct SectorTops<const N: usize> {
    /// Per distance bin of one cell, per sector.
    pub bins: Vec<[f32; N]>,
    /// Per distance bin, the highest of its sectors.
    pub rings: Vec<f32>,
    /// How far from a point's distance to the axis, in cells, the centre of
    /// the tile holding it can lie: half a tile's diagonal, and a little for
    /// a point on a cell's edge.
    pub slack: f64,
}

/// The largest error of [`fast_atan2`], rad, with a margin.
pub const ATAN_ERROR: f64 = 1e-4;

/// atan2(y, x) within 2·10⁻⁵ rad (a degree-9 odd polynomial on [0, 1] and
/// the octant symmetries): the angle bounds of [`Stock::sector_tops`] add
/// [`ATAN_ERROR`], so they need no exact arctangent per cell.
pub fn fast_atan2(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI};
    let (ax, ay) = (x.abs(), y.abs());
    let (num, den) = if ay > ax { (ax, ay) } else { (ay, ax) };
    if den == 0.0 {
        return 0.0;
    }
    let t = num / den;
    let t2 = t * t;
    let mut a = t
        * (0.999_866_0
            + t2 * (-0.330_299_5 + t2 * (0.180_141_0 + t2 * (-0.085_133_0 + t2 * 0.020_835_1))));
    if ay > ax {
        a = FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    if y < 0.0 {
        -a
    } else {
        a
    }
}

/// Memory per cell of a stock without gaps, bytes.
pub const BYTES_PER_CELL: f64 = 8.0 + std::mem::size_of::<RowGaps>() as f64 / 64.0;

impl Stock {
    /// An empty stock on `grid`.
    pub fn empty(grid: Grid) -> Stock {
        let n = grid.cells();
        Stock {
            grid,
            top: vec![0.0; n],
            bot: vec![0.0; n],
            gaps: vec![RowGaps::default(); grid.ny],
            bmax: vec![0.0; grid.ny * grid.nx.div_ceil(BLOCK)],
        }
    }

    /// Recomputes every block's highest top.
    pub(crate) fn refresh_bmax(&mut self) {
        let nx = self.grid.nx;
        let nb = nx.div_ceil(BLOCK);
        for j in 0..self.grid.ny {
            for b in 0..nb {
                let row = &self.top[j * nx..(j + 1) * nx];
                let hi = row[b * BLOCK..((b + 1) * BLOCK).min(nx)]
                    .iter()
                    .fold(f32::NEG_INFINITY, |a, t| a.max(*t));
                self.bmax[j * nb + b] = hi;
            }
        }
    }

    /// A box from `min` to `max` (z from min.z to max.z).
    pub fn block(min: DVec3, max: DVec3, res: f64) -> Stock {
        let grid = Grid::covering(min.truncate(), max.truncate(), res);
        let mut s = Stock::empty(grid);
        let (lo, hi) = (min.z as f32, max.z as f32);
        for j in 0..grid.ny {
            let y = grid.cy(j);
            if y > max.y {
                continue;
            }
            for i in 0..grid.nx {
                if grid.cx(i) <= max.x {
                    let k = j * grid.nx + i;
                    s.top[k] = hi;
                    s.bot[k] = lo;
                }
            }
        }
        s.refresh_bmax();
        s
    }

    /// An upright cylinder of axis (cx, cy), radius `r`, from z0 to z1.
    pub fn cylinder(c: DVec2, r: f64, z0: f64, z1: f64, res: f64) -> Stock {
        let grid = Grid::covering(c - DVec2::splat(r), c + DVec2::splat(r), res);
        let mut s = Stock::empty(grid);
        for j in 0..grid.ny {
            for i in 0..grid.nx {
                if (DVec2::new(grid.cx(i), grid.cy(j)) - c).length() <= r {
                    let k = j * grid.nx + i;
                    s.top[k] = z1 as f32;
                    s.bot[k] = z0 as f32;
                }
            }
        }
        s.refresh_bmax();
        s
    }

    /// Builds a stock from each cell's material intervals (sorted or not,
    /// overlapping or not), given by `f(x, y)`.
    pub fn from_columns(grid: Grid, f: impl Fn(f64, f64) -> Vec<[f64; 2]> + Sync) -> Stock {
        use rayon::prelude::*;
        let mut s = Stock::empty(grid);
        let nx = grid.nx;
        s.top
            .par_chunks_mut(nx)
            .zip(s.bot.par_chunks_mut(nx))
            .zip(s.gaps.par_iter_mut())
            .enumerate()
            .for_each(|(j, ((top, bot), gaps))| {
                let y = grid.cy(j);
                for i in 0..nx {
                    let mut iv = f(grid.cx(i), y);
                    iv.retain(|[a, b]| b > a);
                    if iv.is_empty() {
                        continue;
                    }
                    iv.sort_by(|a, b| a[0].total_cmp(&b[0]));
                    let mut merged: Vec<[f64; 2]> = Vec::with_capacity(iv.len());
                    for [a, b] in iv {
                        match merged.last_mut() {
                            Some(m) if a <= m[1] => m[1] = m[1].max(b),
                            _ => merged.push([a, b]),
                        }
                    }
                    bot[i] = merged[0][0] as f32;
                    top[i] = merged[merged.len() - 1][1] as f32;
                    if merged.len() > 1 {
                        let g: Vec<[f32; 2]> = merged
                            .windows(2)
                            .map(|w| [w[0][1] as f32, w[1][0] as f32])
                            .collect();
                        gaps.insert(i as u32, g);
                    }
                }
            });
        s.refresh_bmax();
        s
    }

    /// A closed mesh (a cast blank): the material of each column is where the
    /// vertical line through the cell's centre is inside the mesh (winding
    /// number of the crossings).
    pub fn from_solid(mesh: &TriMesh, res: f64) -> Stock {
        let b = mesh.bounds();
        let grid = Grid::covering(b.min.truncate(), b.max.truncate(), res);
        let crossings = column_crossings(mesh, &grid);
        Stock::from_columns(grid, |x, y| {
            let Some((i, j)) = grid.cell_of(x, y) else {
                return Vec::new();
            };
            let mut c = crossings[j * grid.nx + i].clone();
            c.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut out = Vec::new();
            let mut wind = 0i32;
            let mut start = 0.0;
            for (z, s) in c {
                let before = wind;
                wind += s;
                if before <= 0 && wind > 0 {
                    start = z;
                } else if before > 0 && wind <= 0 {
                    out.push([start, z]);
                }
            }
            out
        })
    }

    /// Cells in the grid.
    pub fn cells(&self) -> usize {
        self.grid.cells()
    }

    /// Material volume, mm³.
    pub fn volume(&self) -> f64 {
        let a = self.grid.res * self.grid.res;
        let mut v = 0.0;
        for j in 0..self.grid.ny {
            for i in 0..self.grid.nx {
                v += self.length(i, j);
            }
        }
        v * a
    }

    /// Material length of cell (i, j), mm.
    pub fn length(&self, i: usize, j: usize) -> f64 {
        let k = j * self.grid.nx + i;
        let (t, b) = (self.top[k] as f64, self.bot[k] as f64);
        if t <= b {
            return 0.0;
        }
        let air: f64 = self.gaps[j]
            .get(&(i as u32))
            .map_or(0.0, |g| g.iter().map(|[a, b]| (*b - *a) as f64).sum());
        t - b - air
    }

    /// The material intervals of cell (i, j), bottom up.
    pub fn intervals(&self, i: usize, j: usize) -> Vec<[f64; 2]> {
        let k = j * self.grid.nx + i;
        let (t, b) = (self.top[k] as f64, self.bot[k] as f64);
        if t <= b {
            return Vec::new();
        }
        let mut out = Vec::new();
        let mut lo = b;
        if let Some(g) = self.gaps[j].get(&(i as u32)) {
            for [a, c] in g {
                out.push([lo, *a as f64]);
                lo = *c as f64;
            }
        }
        out.push([lo, t]);
        out
    }

    /// Top of the material of cell (i, j); `None` when the cell is empty.
    pub fn top(&self, i: usize, j: usize) -> Option<f64> {
        let k = j * self.grid.nx + i;
        (self.top[k] > self.bot[k]).then_some(self.top[k] as f64)
    }

    /// Memory the stock holds, bytes (its cells, block maxima and gaps).
    pub fn memory_bytes(&self) -> usize {
        let gaps: usize = self
            .gaps
            .iter()
            .map(|r| {
                r.capacity() * (std::mem::size_of::<(u32, Vec<[f32; 2]>)>() + 1)
                    + r.values().map(|g| g.capacity() * 8).sum::<usize>()
            })
            .sum();
        (self.top.len() + self.bot.len() + self.bmax.len()) * 4
            + self.gaps.len() * std::mem::size_of::<RowGaps>()
            + gaps
    }

    /// A 64-bit digest of the material (grid, every column and gap, bit for
    /// bit): two stocks with the same digest hold the same material but
    /// for a hash collision. Work kept from a run over one stock is used
    /// again only on a stock of the same digest.
    pub fn fingerprint(&self) -> u64 {
        use std::hash::Hasher;
        let mut h = rustc_hash::FxHasher::default();
        let g = &self.grid;
        for v in [g.x0.to_bits(), g.y0.to_bits(), g.res.to_bits()] {
            h.write_u64(v);
        }
        h.write_u64(g.nx as u64);
        h.write_u64(g.ny as u64);
        for col in [&self.top, &self.bot] {
            for pair in col.chunks(2) {
                let lo = u64::from(pair[0].to_bits());
                let hi = pair.get(1).map_or(0, |v| u64::from(v.to_bits()));
                h.write_u64(lo | hi << 32);
            }
        }
        for (row, gaps) in self.gaps.iter().enumerate() {
            if gaps.is_empty() {
                continue;
            }
            let mut keys: Vec<&u32> = gaps.keys().collect();
            keys.sort_unstable();
            h.write_u64(row as u64);
            for k in keys {
                h.write_u64(u64::from(*k));
                for [a, b] in &gaps[k] {
                    h.write_u64(u64::from(a.to_bits()) | u64::from(b.to_bits()) << 32);
                }
            }
        }
        h.finish()
    }

    /// Whether `p` lies in material (the cell's column holds p.z).
    #[inline]
    pub fn contains(&self, p: DVec3) -> bool {
        let Some((i, j)) = self.grid.cell_of(p.x, p.y) else {
            return false;
        };
        let k = j * self.grid.nx + i;
        let z = p.z as f32;
        if !(z > self.bot[k] && z < self.top[k]) {
            return false;
        }
        let row = &self.gaps[j];
        row.is_empty() || !Self::in_gap(row, i, z)
    }

    /// Whether height `z` lies in a gap of column `i` of a row with gaps
    /// (kept out of line: most stocks have none, and the force model asks
    /// [`Stock::contains`] at every point of the edge).
    #[cold]
    #[inline(never)]
    fn in_gap(row: &RowGaps, i: usize, z: f32) -> bool {
        row.get(&(i as u32))
            .is_some_and(|g| g.iter().any(|[a, b]| z >= *a && z <= *b))
    }

    /// Highest material, mm (−∞ for an empty stock).
    pub fn max_top(&self) -> f64 {
        self.top
            .iter()
            .zip(&self.bot)
            .filter(|(t, b)| t > b)
            .map(|(t, _)| *t as f64)
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Highest material over the cells whose centres lie in the rectangle
    /// `min`–`max` (−∞ where there is none).
    pub fn max_top_in(&self, min: DVec2, max: DVec2) -> f64 {
        let g = &self.grid;
        let (Some((i0, i1)), Some((j0, j1))) = (g.span(min.x, max.x), g.rows(min.y, max.y)) else {
            return f64::NEG_INFINITY;
        };
        let mut m = f32::NEG_INFINITY;
        for j in j0..=j1 {
            let row = j * g.nx;
            let (t, b) = (
                &self.top[row + i0..=row + i1],
                &self.bot[row + i0..=row + i1],
            );
            for (t, b) in t.iter().zip(b) {
                if t > b && *t > m {
                    m = *t;
                }
            }
        }
        m as f64
    }

    /// An upper bound of the material by distance from a vertical axis
    /// through `centre` and by angle about it, for every point out to
    /// `radius`. The cells are taken in square tiles of [`sector_tile`]
    /// cells a side (about 1/32 of the tool's width, so the work is bounded
    /// whatever the resolution),
    /// a tile standing for the highest top of its cells that hold material.
    /// Entry b of `out.bins` holds, per sector s of the full turn, the
    /// highest tile whose centre lies between b·res and (b + 1)·res from the
    /// axis and whose cells can hold a point at an angle of sector s. The
    /// angle of an offset d from the axis is θ = atan2(d·`ux`, d·`uy`) in
    /// [0, 2π) (the tool frame's, with `ux` and `uy` the unit horizontal
    /// directions of its x and y), sector s covering [s, s + 1)·2π/N. A point
    /// at distance r lies in a tile whose centre is within `out.slack`·res
    /// of r. Returns the highest top of all the cells looked at, empty ones
    /// included.
    pub fn sector_tops<const N: usize>(
        &self,
        centre: DVec2,
        radius: f64,
        (ux, uy): (DVec2, DVec2),
        out: &mut SectorTops<N>,
    ) -> f64 {
        let g = &self.grid;
        let t = sector_tile(radius, g.res);
        out.slack = t as f64 * std::f64::consts::FRAC_1_SQRT_2 + 0.05;
        let reach = radius + out.slack * g.res;
        out.bins.clear();
        out.rings.clear();
        let bins = (reach / g.res).ceil() as usize + 1;
        out.bins.resize(bins, [f32::NEG_INFINITY; N]);
        out.rings.resize(bins, f32::NEG_INFINITY);
        let lo = centre - DVec2::splat(reach);
        let hi = centre + DVec2::splat(reach);
        let (Some((i0, i1)), Some((j0, j1))) = (g.span(lo.x, hi.x), g.rows(lo.y, hi.y)) else {
            return f64::NEG_INFINITY;
        };
        let last = bins - 1;
        let w = std::f64::consts::TAU / N as f64;
        // A tile lies within slack·res of its centre, so seen from the axis
        // at distance ≥ b·res its points are at most asin(slack/b) off the
        // centre's angle (in sectors, with a margin for the approximate
        // arctangent and rounding).
        let half: Vec<f64> = (0..bins)
            .map(|b| {
                let q = out.slack / b as f64;
                if q >= 1.0 {
                    N as f64
                } else {
                    (q.asin() + ATAN_ERROR) / w
                }
            })
            .collect();
        let mut cols = vec![f32::NEG_INFINITY; i1 - i0 + 1];
        // The highest top per column, material or not (reduced at the end:
        // element-wise selects vectorise, a running maximum does not).
        let mut highest = vec![f32::NEG_INFINITY; i1 - i0 + 1];
        let mut j = j0;
        while j <= j1 {
            let je = (j + t - 1).min(j1);
            cols.fill(f32::NEG_INFINITY);
            for jj in j..=je {
                let k = jj * g.nx;
                let (top, bot) = (&self.top[k + i0..=k + i1], &self.bot[k + i0..=k + i1]);
                for (((c, h), t), b) in cols.iter_mut().zip(&mut highest).zip(top).zip(bot) {
                    let (t, b) = (*t, *b);
                    *h = if t > *h { t } else { *h };
                    let v = if t > b { t } else { f32::NEG_INFINITY };
                    *c = if v > *c { v } else { *c };
                }
            }
            let dy = 0.5 * (g.cy(j) + g.cy(je)) - centre.y;
            for (k, tile) in cols.chunks(t).enumerate() {
                let top = tile
                    .iter()
                    .fold(f32::NEG_INFINITY, |a, b| if *b > a { *b } else { a });
                if top == f32::NEG_INFINITY {
                    continue;
                }
                let (ia, ie) = (i0 + k * t, i0 + k * t + tile.len() - 1);
                let d = DVec2::new(0.5 * (g.cx(ia) + g.cx(ie)) - centre.x, dy);
                let bin = ((d.length() / g.res) as usize).min(last);
                let h = half[bin];
                out.rings[bin] = out.rings[bin].max(top);
                let slot = &mut out.bins[bin];
                if h >= N as f64 / 2.0 {
                    for v in slot.iter_mut() {
                        *v = v.max(top);
                    }
                } else {
                    let a = fast_atan2(d.dot(ux), d.dot(uy));
                    let a = if a < 0.0 {
                        a + std::f64::consts::TAU
                    } else {
                        a
                    } / w;
                    for s in floor_i64(a - h)..=floor_i64(a + h) {
                        let v = &mut slot[s.rem_euclid(N as i64) as usize];
                        *v = v.max(top);
                    }
                }
            }
            j = je + 1;
        }
        highest.iter().fold(f32::NEG_INFINITY, |a, b| a.max(*b)) as f64
    }

    /// Whether any cell has gaps.
    pub fn has_gaps(&self) -> bool {
        self.gaps.iter().any(|g| !g.is_empty())
    }

    /// A copy of the cells whose squares meet the rectangle `min`–`max`
    /// (the same cells, heights and gaps; nothing outside). A rectangle
    /// beside the grid gives one empty cell.
    pub fn crop(&self, min: DVec2, max: DVec2) -> Stock {
        let g = &self.grid;
        let lo = |v: f64, o: f64, n: usize| (floor((v - o) / g.res).max(0.0) as usize).min(n);
        let hi = |v: f64, o: f64, n: usize| (ceil((v - o) / g.res).max(0.0) as usize).min(n);
        let (i0, i1) = (lo(min.x, g.x0, g.nx), hi(max.x, g.x0, g.nx));
        let (j0, j1) = (lo(min.y, g.y0, g.ny), hi(max.y, g.y0, g.ny));
        if i1 <= i0 || j1 <= j0 {
            return Stock::empty(Grid {
                x0: min.x,
                y0: min.y,
                res: g.res,
                nx: 1,
                ny: 1,
            });
        }
        let grid = Grid {
            x0: g.x0 + i0 as f64 * g.res,
            y0: g.y0 + j0 as f64 * g.res,
            res: g.res,
            nx: i1 - i0,
            ny: j1 - j0,
        };
        let mut s = Stock::empty(grid);
        for j in j0..j1 {
            let (src, dst) = (j * g.nx, (j - j0) * grid.nx);
            s.top[dst..dst + grid.nx].copy_from_slice(&self.top[src + i0..src + i1]);
            s.bot[dst..dst + grid.nx].copy_from_slice(&self.bot[src + i0..src + i1]);
            let row = &self.gaps[j];
            if !row.is_empty() {
                s.gaps[j - j0] = row
                    .iter()
                    .filter(|(i, _)| (i0..i1).contains(&(**i as usize)))
                    .map(|(i, v)| (*i - i0 as u32, v.clone()))
                    .collect();
            }
        }
        s.refresh_bmax();
        s
    }

    /// A copy keeping every `step`-th cell in X and Y (for a lighter mesh).
    pub fn coarsened(&self, step: usize) -> Stock {
        let step = step.max(1);
        if step == 1 {
            return self.clone();
        }
        let g = self.grid;
        let grid = Grid {
            x0: g.x0,
            y0: g.y0,
            res: g.res * step as f64,
            nx: g.nx.div_ceil(step),
            ny: g.ny.div_ceil(step),
        };
        Stock::from_columns(grid, |x, y| match g.cell_of(x, y) {
            Some((i, j)) => self.intervals(i, j),
            None => Vec::new(),
        })
    }
}

/// Each cell's crossings of the vertical line through its centre with `mesh`:
/// (z, +1) entering the solid going up (a facet facing down), (z, −1) leaving.
/// A centre exactly on a shared edge counts once (half-open edge tests).
fn column_crossings(mesh: &TriMesh, grid: &Grid) -> Vec<Vec<(f64, i32)>> {
    let mut out: Vec<Vec<(f64, i32)>> = vec![Vec::new(); grid.cells()];
    for t in 0..mesh.len() {
        let [a, b, c] = mesh.corners(t);
        let n = (b - a).cross(c - a);
        if n.z == 0.0 {
            continue;
        }
        // Orient the triangle counter-clockwise in XY.
        let (a, b, c) = if n.z > 0.0 { (a, b, c) } else { (a, c, b) };
        let sign = if n.z > 0.0 { -1 } else { 1 };
        let lo = a.truncate().min(b.truncate()).min(c.truncate());
        let hi = a.truncate().max(b.truncate()).max(c.truncate());
        let (Some((j0, j1)), Some((i0, i1))) = (grid.rows(lo.y, hi.y), grid.span(lo.x, hi.x))
        else {
            continue;
        };
        let edge = |p: DVec3, q: DVec3, x: f64, y: f64| -> bool {
            // Inside or on a top-left edge (counter-clockwise triangle).
            let w = (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
            if w != 0.0 {
                return w > 0.0;
            }
            let (dx, dy) = (q.x - p.x, q.y - p.y);
            (dy == 0.0 && dx < 0.0) || dy < 0.0
        };
        for j in j0..=j1 {
            let y = grid.cy(j);
            for i in i0..=i1 {
                let x = grid.cx(i);
                if edge(a, b, x, y) && edge(b, c, x, y) && edge(c, a, x, y) {
                    // Height of the plane at (x, y).
                    let z = a.z - (n.x * (x - a.x) + n.y * (y - a.y)) / n.z;
                    out[j * grid.nx + i].push((z, sign));
                }
            }
        }
    }
    out
}
