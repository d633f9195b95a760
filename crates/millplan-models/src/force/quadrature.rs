//! The axial quadrature of the force integrals: at one spindle angle a
//! flute's edge is the column of cells of one angle index over the slices,
//! and its force is the integral along the edge over the part of it that is
//! in material with a positive chip. A run of engaged slices in a column is
//! one such part. Its interior slices count whole; where the run ends on a
//! slice whose neighbour is not engaged, the edge enters or leaves material
//! somewhere between the two slice centres, and that point is found by
//! bisection of the engagement predicate along the edge ([`BISECTIONS`]
//! steps). The end slice then counts with the share of the edge from its
//! far side to that point (between a half and one and a half slices), so
//! the sum is the midpoint rule of the run's true length: its error falls
//! with the square of the slice height instead of with the slice height,
//! as it does when a slice counts whole or not at all by its centre.
//!
//! For the error estimate ([`super::converge`]) each cell also carries its
//! weight in the quadrature of its own parity: the even slices alone and the
//! odd slices alone, each a midpoint rule over the same run at twice the
//! slice height, with ends weighted the same way. The two differ by about
//! the error a quadrature at twice the height makes.
//!
//! Runs ending on the first or the last slice of the flute end with the
//! edge itself: no bisection there.

use super::engage::Engagement;
use super::ForceModel;

/// Bisection steps locating where a flute enters or leaves material between
/// two slice centres: the point is then known within 1/64 of a slice.
pub const BISECTIONS: u32 = 5;

/// One engaged cell with its weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    pub slice: u32,
    /// Angle index (θ = k·dφ − ψ(z)).
    pub k: u32,
    /// Share of a slice height this cell stands for in the quadrature.
    pub w: f32,
    /// Share of a slice height it stands for in its parity's quadrature.
    pub half: f32,
    /// Whether the run ends at this cell with a bisected boundary.
    pub boundary: bool,
}

/// A cell of a run's interior: whole in both quadratures, no boundary.
const PLAIN: Cell = Cell {
    slice: 0,
    k: 0,
    w: 1.0,
    half: 2.0,
    boundary: false,
};

/// Columns of the per-angle table: Fx, Fy, Fz, T of the quadrature, then
/// Fx, Fy, T of the odd slices' quadrature, of the even slices', and of the
/// boundary cells counted whole.
pub const COLUMNS: usize = 13;

/// Adds a cell's force `q` = (Fx, Fy, Fz, T) per slice height into its row.
#[inline]
pub(crate) fn accumulate(row: &mut [f64; COLUMNS], c: &Cell, q: [f64; 4]) {
    let w = f64::from(c.w);
    row[0] += w * q[0];
    row[1] += w * q[1];
    row[2] += w * q[2];
    row[3] += w * q[3];
    let h = f64::from(c.half);
    let at = if c.slice & 1 == 1 { 4 } else { 7 };
    row[at] += h * q[0];
    row[at + 1] += h * q[1];
    row[at + 2] += h * q[3];
    if c.boundary {
        row[10] += q[0];
        row[11] += q[1];
        row[12] += q[3];
    }
}

/// One run of consecutive engaged slices in one column, as
/// [`ForceModel::cells_of_runs`] rebuilds its cells: angle index `k`, the
/// slices `a` to `a + n − 1`, and where its ends meet material between
/// slice centres as found by bisection (`lo`, `hi`: the midpoint of the last
/// interval is (2j + 1)/2^(BISECTIONS + 1) of the way from the slice
/// outside to the slice inside; 0 where the run ends on the flute's own
/// end). Eight bytes stand for the run's cells (twenty each): a force run's
/// engagements are kept this way for the runs after it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Run {
    pub k: u16,
    pub a: u16,
    pub n: u16,
    pub lo: u8,
    pub hi: u8,
}

impl ForceModel {
    /// The weighted cells of the engaged (slice, angle index) pairs `raw`
    /// (ordered by slice), in column order; `f` is the feed direction in
    /// the tool frame. With `runs`, each run of the cells is added to it.
    pub(crate) fn weigh<E: Engagement + ?Sized>(
        &self,
        raw: &[(u32, u32)],
        eng: &E,
        f: [f64; 3],
        mut runs: Option<&mut Vec<Run>>,
    ) -> Vec<Cell> {
        // Counting sort by angle index; slices stay ascending in a column.
        let mut start = vec![0u32; self.m + 1];
        for &(_, k) in raw {
            start[k as usize + 1] += 1;
        }
        for i in 0..self.m {
            start[i + 1] += start[i];
        }
        let mut cells = vec![PLAIN; raw.len()];
        let mut at = start.clone();
        for &(slice, k) in raw {
            let i = &mut at[k as usize];
            cells[*i as usize].slice = slice;
            cells[*i as usize].k = k;
            *i += 1;
        }
        let mut i = 0;
        while i < cells.len() {
            let (k, mut j) = (cells[i].k, i + 1);
            while j < cells.len() && cells[j].k == k && cells[j].slice == cells[j - 1].slice + 1 {
                j += 1;
            }
            let run = &mut cells[i..j];
            let (a, b) = (run[0].slice as usize, run[run.len() - 1].slice as usize);
            let lo = if a > 0 {
                self.bisect(k as usize, a - 1, a, eng, f)
            } else {
                0
            };
            let hi = if b + 1 < self.slices.len() {
                self.bisect(k as usize, b + 1, b, eng, f)
            } else {
                0
            };
            self.weigh_run(run, lo, hi);
            if let Some(r) = runs.as_deref_mut() {
                r.push(Run {
                    k: k as u16,
                    a: a as u16,
                    n: (j - i) as u16,
                    lo,
                    hi,
                });
            }
            i = j;
        }
        cells
    }

    /// Whether every run of this model's cells fits a [`Run`] (angle
    /// indices and slices below 2^16).
    pub fn runs_fit(&self) -> bool {
        self.m <= usize::from(u16::MAX) && self.slices.len() <= usize::from(u16::MAX)
    }

    /// The cells of `runs` (as [`ForceModel::engaged_runs`] listed them), the
    /// same as the engagement they were found in gave, bit for bit.
    pub fn cells_of_runs(&self, runs: &[Run]) -> Vec<Cell> {
        let mut cells = Vec::with_capacity(runs.iter().map(|r| usize::from(r.n)).sum());
        for r in runs {
            let at = cells.len();
            cells.extend((0..u32::from(r.n)).map(|i| Cell {
                slice: u32::from(r.a) + i,
                k: u32::from(r.k),
                ..PLAIN
            }));
            self.weigh_run(&mut cells[at..], r.lo, r.hi);
        }
        cells
    }

    /// Weights of one run of consecutive slices in one column whose ends
    /// meet material where the bisections `lo` and `hi` found
    /// ([`ForceModel::bisect`]; unused where the run ends on the flute's
    /// own end).
    fn weigh_run(&self, run: &mut [Cell], lo: u8, hi: u8) {
        let dz = self.dz;
        let (a, b) = (run[0].slice as usize, run[run.len() - 1].slice as usize);
        let z = |s: usize| self.slices[s].u;
        let lo_open = a > 0;
        let hi_open = b + 1 < self.slices.len();
        let z_lo = if lo_open {
            self.boundary(a - 1, a, lo)
        } else {
            z(a) - 0.5 * dz
        };
        let z_hi = if hi_open {
            self.boundary(b + 1, b, hi)
        } else {
            z(b) + 0.5 * dz
        };
        let n = run.len();
        // The whole quadrature: the ends reach to the boundaries.
        if n == 1 {
            run[0].w = ((z_hi - z_lo) / dz) as f32;
        } else {
            run[0].w = ((z(a) + 0.5 * dz - z_lo) / dz) as f32;
            run[n - 1].w = ((z_hi - z(b) + 0.5 * dz) / dz) as f32;
        }
        run[0].boundary |= lo_open;
        run[n - 1].boundary |= hi_open;
        // Each parity's quadrature: its first and last cells reach to the
        // boundaries, the others stand for two slices.
        for first in [0, 1].into_iter().filter(|i| *i < n) {
            let last = first + (n - 1 - first) / 2 * 2;
            let (zf, zl) = (z(a + first), z(a + last));
            if first == last {
                run[first].half = ((z_hi - z_lo) / dz) as f32;
            } else {
                run[first].half = ((zf + dz - z_lo) / dz) as f32;
                run[last].half = ((z_hi - zl + dz) / dz) as f32;
            }
        }
    }

    /// Where between the centres of the neighbouring slices `out` (not
    /// engaged) and `inside` (engaged) the edge of angle index `k` enters
    /// material with a positive chip: the bisection's last interval, as
    /// its index j ([`Run`], [`ForceModel::boundary`]).
    fn bisect<E: Engagement + ?Sized>(
        &self,
        k: usize,
        out: usize,
        inside: usize,
        eng: &E,
        f: [f64; 3],
    ) -> u8 {
        let (a, b) = (&self.slices[out], &self.slices[inside]);
        // The edge between two slice centres, linear in the share t from
        // `out` toward `inside`: its geometry is smooth there (the ball's
        // tip, where it is not, is the first slice, which has no neighbour
        // below), and the interpolation's error, of order dz² times the
        // profile's curvature, is far below the bisection's last step.
        let (sk, ck) = (self.sin_t[k], self.cos_t[k]);
        let at = |t: f64| {
            let l = |x: f64, y: f64| x + t * (y - x);
            let (sp, cp) = (l(a.sin_psi, b.sin_psi), l(a.cos_psi, b.cos_psi));
            // θ = kδ − ψ.
            let (st, ct) = (sk * cp - ck * sp, ck * cp + sk * sp);
            let (ny, nz, r, z) = (l(a.ny, b.ny), l(a.nz, b.nz), l(a.r, b.r), l(a.z, b.z));
            let h = f[0] * ny * st + f[1] * ny * ct + f[2] * nz;
            h > 0.0 && eng.contains([r * st, r * ct, z])
        };
        let (mut o, mut i) = (0.0, 1.0);
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (o + i);
            if at(mid) {
                i = mid;
            } else {
                o = mid;
            }
        }
        // o is a multiple of 2^-BISECTIONS (exact).
        (o * f64::from(1u32 << BISECTIONS)) as u8
    }

    /// The meridian length where bisection `j` ([`ForceModel::bisect`])
    /// between slices `out` and `inside` places the edge's entry into
    /// material: the midpoint of its last interval.
    fn boundary(&self, out: usize, inside: usize, j: u8) -> f64 {
        let (a, b) = (&self.slices[out], &self.slices[inside]);
        // (2j + 1)/2^(BISECTIONS + 1): exact, as the bisection's own
        // midpoint 0.5·(o + i) is.
        let m = f64::from(2 * u32::from(j) + 1) / f64::from(2u32 << BISECTIONS);
        a.u + m * (b.u - a.u)
    }
}
