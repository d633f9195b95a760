//! The stock as a closed triangle mesh: each cell's material intervals as
//! prisms, their union's boundary without T-junctions (every side face is
//! split wherever a neighbouring column has an end, so every edge is shared
//! by an even number of faces and a viewer sees a watertight solid).

use super::Stock;
use millplan_geom::{DVec3, TriMesh};
use rustc_hash::FxHashMap;

struct Builder<'a> {
    stock: &'a Stock,
    ivs: Vec<Vec<[f32; 2]>>,
    verts: Vec<DVec3>,
    index: FxHashMap<(u32, u32, u32), u32>,
    tris: Vec<[u32; 3]>,
}

impl Builder<'_> {
    fn iv(&self, i: isize, j: isize) -> &[[f32; 2]] {
        let g = self.stock.grid;
        if i < 0 || j < 0 || i as usize >= g.nx || j as usize >= g.ny {
            return &[];
        }
        &self.ivs[j as usize * g.nx + i as usize]
    }

    fn vertex(&mut self, ci: usize, cj: usize, z: f32) -> u32 {
        let key = (ci as u32, cj as u32, z.to_bits());
        if let Some(v) = self.index.get(&key) {
            return *v;
        }
        let g = self.stock.grid;
        let v = self.verts.len() as u32;
        self.verts.push(DVec3::new(
            g.x0 + ci as f64 * g.res,
            g.y0 + cj as f64 * g.res,
            z as f64,
        ));
        self.index.insert(key, v);
        v
    }

    /// Interval ends of the four cells around corner (ci, cj) strictly
    /// between z0 and z1, ascending.
    fn breaks(&self, ci: usize, cj: usize, z0: f32, z1: f32) -> Vec<f32> {
        let (ci, cj) = (ci as isize, cj as isize);
        let mut v: Vec<f32> = Vec::new();
        for (di, dj) in [(-1, -1), (0, -1), (-1, 0), (0, 0)] {
            for [a, b] in self.iv(ci + di, cj + dj) {
                for z in [*a, *b] {
                    if z > z0 && z < z1 {
                        v.push(z);
                    }
                }
            }
        }
        v.sort_by(f32::total_cmp);
        v.dedup();
        v
    }

    /// A vertical face from corner `c0` to corner `c1` between z0 and z1,
    /// facing to the right of c0 → c1 seen from above when `flip` is false.
    fn side(&mut self, c0: (usize, usize), c1: (usize, usize), z0: f32, z1: f32, flip: bool) {
        let mut left = vec![z0];
        left.extend(self.breaks(c0.0, c0.1, z0, z1));
        left.push(z1);
        let mut right = vec![z0];
        right.extend(self.breaks(c1.0, c1.1, z0, z1));
        right.push(z1);
        let l: Vec<u32> = left.iter().map(|z| self.vertex(c0.0, c0.1, *z)).collect();
        let r: Vec<u32> = right.iter().map(|z| self.vertex(c1.0, c1.1, *z)).collect();
        // Zip up the two vertical edges.
        let (mut a, mut b) = (0usize, 0usize);
        while a + 1 < l.len() || b + 1 < r.len() {
            let up_left = b + 1 >= r.len() || (a + 1 < l.len() && left[a + 1] <= right[b + 1]);
            let t = if up_left {
                a += 1;
                [l[a - 1], r[b], l[a]]
            } else {
                b += 1;
                [l[a], r[b - 1], r[b]]
            };
            // [l lower, r, l upper] is counter-clockwise seen from the
            // right of c0 → c1.
            self.tris.push(if flip { [t[0], t[2], t[1]] } else { t });
        }
    }
}

/// `a` minus `b`, both sorted disjoint interval lists.
fn minus(a: &[[f32; 2]], b: &[[f32; 2]]) -> Vec<[f32; 2]> {
    let mut out = Vec::new();
    for &[lo, hi] in a {
        let mut start = lo;
        for &[c, d] in b {
            if d <= start || c >= hi {
                continue;
            }
            if c > start {
                out.push([start, c]);
            }
            start = start.max(d);
        }
        if start < hi {
            out.push([start, hi]);
        }
    }
    out
}

/// The stock's surface, closed, outward-facing.
pub fn stock_mesh(stock: &Stock) -> TriMesh {
    let g = stock.grid;
    let mut ivs = Vec::with_capacity(g.cells());
    for j in 0..g.ny {
        for i in 0..g.nx {
            ivs.push(
                stock
                    .intervals(i, j)
                    .into_iter()
                    .map(|[a, b]| [a as f32, b as f32])
                    .filter(|[a, b]| b > a)
                    .collect(),
            );
        }
    }
    let mut b = Builder {
        stock,
        ivs,
        verts: Vec::new(),
        index: FxHashMap::default(),
        tris: Vec::new(),
    };
    for j in 0..g.ny {
        for i in 0..g.nx {
            let cell = b.iv(i as isize, j as isize).to_vec();
            for [lo, hi] in &cell {
                // Top (+z) and bottom (−z): counter-clockwise seen from outside.
                let t = [
                    b.vertex(i, j, *hi),
                    b.vertex(i + 1, j, *hi),
                    b.vertex(i + 1, j + 1, *hi),
                    b.vertex(i, j + 1, *hi),
                ];
                b.tris.push([t[0], t[1], t[2]]);
                b.tris.push([t[0], t[2], t[3]]);
                let u = [
                    b.vertex(i, j, *lo),
                    b.vertex(i + 1, j, *lo),
                    b.vertex(i + 1, j + 1, *lo),
                    b.vertex(i, j + 1, *lo),
                ];
                b.tris.push([u[0], u[2], u[1]]);
                b.tris.push([u[0], u[3], u[2]]);
            }
            // Faces on this cell's +x and +y sides (and −x, −y at the border).
            let (ii, jj) = (i as isize, j as isize);
            let px = b.iv(ii + 1, jj).to_vec();
            for [z0, z1] in minus(&cell, &px) {
                // Facing +x: to the right of (i+1, j) → (i+1, j+1).
                b.side((i + 1, j), (i + 1, j + 1), z0, z1, false);
            }
            for [z0, z1] in minus(&px, &cell) {
                if i + 1 < g.nx {
                    b.side((i + 1, j), (i + 1, j + 1), z0, z1, true);
                }
            }
            let py = b.iv(ii, jj + 1).to_vec();
            for [z0, z1] in minus(&cell, &py) {
                b.side((i, j + 1), (i + 1, j + 1), z0, z1, true);
            }
            for [z0, z1] in minus(&py, &cell) {
                if j + 1 < g.ny {
                    b.side((i, j + 1), (i + 1, j + 1), z0, z1, false);
                }
            }
            if i == 0 {
                for [z0, z1] in cell.clone() {
                    b.side((0, j), (0, j + 1), z0, z1, true);
                }
            }
            if j == 0 {
                for [z0, z1] in cell.clone() {
                    b.side((i, 0), (i + 1, 0), z0, z1, false);
                }
            }
        }
    }
    TriMesh {
        vertices: b.verts,
        triangles: b.tris,
    }
}
