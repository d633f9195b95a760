//! Indexed triangle meshes: welding a triangle soup, facet normals, topology checks.

use crate::Aabb;
use glam::DVec3;
use rayon::prelude::*;
use rustc_hash::FxHashMap;

/// An indexed triangle mesh in millimetres. Triangles are counter-clockwise seen
/// from outside; no triangle is degenerate (the constructors drop those).
#[derive(Clone, Debug, Default)]
pub struct TriMesh {
    pub vertices: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// What welding found while building a mesh from a triangle soup.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WeldReport {
    /// Facets dropped because two corners coincide or the area is zero.
    pub degenerate: usize,
    /// Distinct vertices after exact welding.
    pub vertices: usize,
}

/// Edge topology of a mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EdgeReport {
    pub edges: usize,
    /// Edges used by exactly one triangle (holes and the border of an open surface).
    pub open: usize,
    /// Edges used by more than two triangles.
    pub non_manifold: usize,
}

const SHARD_BITS: u32 = 5;
/// Shards of the parallel weld.
const SHARDS: usize = 1 << SHARD_BITS;
/// Corners per block of the parallel weld: whole triangles.
const BLOCK: usize = 3 << 16;
/// Marks a shard-local vertex id at the corner where the vertex first appears.
const FIRST: u32 = 1 << 31;

/// A corner's shard: middle bits of its hash. The shard's map takes its
/// control bytes from the top bits, which would be all alike in a shard
/// chosen by them.
#[inline]
fn shard_of(k: &[u32; 3]) -> usize {
    use std::hash::BuildHasher;
    (rustc_hash::FxBuildHasher.hash_one(k) >> 32) as usize & (SHARDS - 1)
}

/// `v`, laid out shard after shard from `base`, as one slice per shard.
fn by_shard_mut<'a, T>(v: &'a mut [T], base: &[usize; SHARDS + 1]) -> Vec<&'a mut [T]> {
    let mut parts = Vec::with_capacity(SHARDS);
    let mut rest = v;
    for s in 0..SHARDS {
        let (r, tail) = std::mem::take(&mut rest).split_at_mut(base[s + 1] - base[s]);
        parts.push(r);
        rest = tail;
    }
    parts
}

/// The corners of the weld with each shard's ids (in order of appearance).
struct Walk<'a> {
    corners: &'a [[u32; 3]],
    /// Each corner's shard.
    shards: &'a [u8],
    /// Where each block's run starts in its shard's ids.
    offset: &'a [[usize; SHARDS]],
    /// Where each shard's ids start in `ids`.
    base: &'a [usize; SHARDS + 1],
    /// The ids of every shard, one after the other.
    ids: &'a [u32],
}

impl Walk<'_> {
    /// Calls `each(j, corner, shard, id)` for the corners of block b in order.
    #[inline]
    fn block(&self, b: usize, mut each: impl FnMut(usize, &[u32; 3], usize, u32)) {
        let mut cursor = self.offset[b];
        let end = ((b + 1) * BLOCK).min(self.corners.len());
        let corners = self.corners[b * BLOCK..end].iter();
        for (j, (k, &s)) in corners.zip(&self.shards[b * BLOCK..end]).enumerate() {
            let s = s as usize;
            each(j, k, s, self.ids[self.base[s] + cursor[s]]);
            cursor[s] += 1;
        }
    }
}

impl TriMesh {
    /// Welds a triangle soup by exact coordinate match and drops degenerate facets.
    /// The first corner to carry a coordinate gives the vertex its index, so the
    /// result is deterministic and follows the file order.
    pub fn from_soup(soup: &[[DVec3; 3]]) -> (TriMesh, WeldReport) {
        #[inline]
        fn key(p: DVec3) -> [u64; 3] {
            // +0.0 and -0.0 are one point.
            [
                (p.x + 0.0).to_bits(),
                (p.y + 0.0).to_bits(),
                (p.z + 0.0).to_bits(),
            ]
        }
        let mut map: FxHashMap<[u64; 3], u32> = FxHashMap::default();
        map.reserve(soup.len() / 2 + 16);
        let mut vertices: Vec<DVec3> = Vec::with_capacity(soup.len() / 2 + 16);
        let mut corner_tris: Vec<[u32; 3]> = Vec::with_capacity(soup.len());
        for tri in soup {
            let mut idx = [0u32; 3];
            for (slot, p) in idx.iter_mut().zip(tri) {
                let next = vertices.len() as u32;
                *slot = *map.entry(key(*p)).or_insert_with(|| {
                    vertices.push(*p);
                    next
                });
            }
            corner_tris.push(idx);
        }
        Self::assemble(vertices, corner_tris)
    }

    /// The mesh from welded vertices and corner indices, dropping degenerate
    /// facets (repeated vertex or zero area).
    fn assemble(vertices: Vec<DVec3>, corner_tris: Vec<[u32; 3]>) -> (TriMesh, WeldReport) {
        let mut triangles = corner_tris;
        let before = triangles.len();
        triangles.retain(|&[a, b, c]| {
            if a == b || b == c || a == c {
                return false;
            }
            let (pa, pb, pc) = (
                vertices[a as usize],
                vertices[b as usize],
                vertices[c as usize],
            );
            (pb - pa).cross(pc - pa).length_squared() != 0.0
        });
        let report = WeldReport {
            degenerate: before - triangles.len(),
            vertices: vertices.len(),
        };
        (
            TriMesh {
                vertices,
                triangles,
            },
            report,
        )
    }

    /// Welds a single-precision soup (binary STL) by exact match on the f32 bit
    /// patterns, with the same result as [`TriMesh::from_soup`].
    pub fn from_f32_soup(soup: &[[[f32; 3]; 3]]) -> (TriMesh, WeldReport) {
        let corners: Vec<[u32; 3]> = soup
            .par_iter()
            .flat_map_iter(|t| t.iter().map(|p| p.map(|c| (c + 0.0).to_bits())))
            .collect();
        TriMesh::from_f32_corners(corners)
    }

    /// Welds triangle corners given as f32 bit patterns (three corners per
    /// triangle; `-0.0` already folded to `+0.0`). Vertices are numbered in
    /// order of first appearance. Every step runs in parallel: blocks of the
    /// soup are split by hash into shards, each shard is welded on its own
    /// (its blocks in file order), and the blocks then number the vertices they
    /// see first from a running count.
    pub fn from_f32_corners(corners: Vec<[u32; 3]>) -> (TriMesh, WeldReport) {
        // Every large array is allocated here, on the calling thread, and
        // filled in parallel: memory a pool thread allocates and this one
        // frees stays with the pool thread's heap, where what runs after the
        // weld (a surface, a pass) cannot use it, and so it added to the
        // process's peak.
        //
        // Each corner's shard (the walks below read it rather than hash
        // again) and each block's count per shard.
        let mut shards = vec![0u8; corners.len()];
        let counts: Vec<[usize; SHARDS]> = corners
            .par_chunks(BLOCK)
            .zip(shards.par_chunks_mut(BLOCK))
            .map(|(block, shards)| {
                let mut c = [0usize; SHARDS];
                for (k, out) in block.iter().zip(shards) {
                    let s = shard_of(k);
                    *out = s as u8;
                    c[s] += 1;
                }
                c
            })
            .collect();
        let blocks = counts.len();
        // Where each block's run starts in its shard's corners and ids.
        let mut offset = vec![[0usize; SHARDS]; blocks + 1];
        for b in 0..blocks {
            for s in 0..SHARDS {
                offset[b + 1][s] = offset[b][s] + counts[b][s];
            }
        }
        // Where each shard starts in the arrays by shard.
        let mut base = [0usize; SHARDS + 1];
        for s in 0..SHARDS {
            base[s + 1] = base[s] + offset[blocks][s];
        }
        // The corners by shard, each shard's in file order: every block
        // writes its runs, one per shard.
        let mut by_shard = vec![[0u32; 3]; corners.len()];
        {
            let mut runs: Vec<Vec<&mut [[u32; 3]]>> = (0..blocks).map(|_| Vec::new()).collect();
            let mut rest = by_shard.as_mut_slice();
            for s in 0..SHARDS {
                for (run, count) in runs.iter_mut().zip(&counts) {
                    let (r, tail) = std::mem::take(&mut rest).split_at_mut(count[s]);
                    run.push(r);
                    rest = tail;
                }
            }
            runs.into_par_iter().enumerate().for_each(|(b, mut run)| {
                let mut cursor = [0usize; SHARDS];
                let end = ((b + 1) * BLOCK).min(corners.len());
                for (k, &s) in corners[b * BLOCK..end].iter().zip(&shards[b * BLOCK..end]) {
                    let s = s as usize;
                    run[s][cursor[s]] = *k;
                    cursor[s] += 1;
                }
            });
        }
        // Weld each shard: local ids in order of appearance, marked FIRST where new.
        let mut ids = vec![0u32; corners.len()];
        let uniques: Vec<usize> = by_shard_mut(&mut ids, &base)
            .into_par_iter()
            .enumerate()
            .map(|(s, ids)| {
                let mut map: FxHashMap<[u32; 3], u32> = FxHashMap::default();
                map.reserve(ids.len() / 4);
                for (k, id) in by_shard[base[s]..base[s + 1]].iter().zip(ids) {
                    let next = map.len() as u32;
                    let v = *map.entry(*k).or_insert(next);
                    *id = if v == next { v | FIRST } else { v };
                }
                map.len()
            })
            .collect();
        drop(by_shard);
        let shard_ids = |s: usize| &ids[base[s]..base[s + 1]];
        // Vertices first seen in each block, and the global number of its first.
        let firsts: Vec<usize> = (0..blocks)
            .into_par_iter()
            .map(|b| {
                (0..SHARDS)
                    .map(|s| {
                        shard_ids(s)[offset[b][s]..offset[b + 1][s]]
                            .iter()
                            .filter(|&&v| v & FIRST != 0)
                            .count()
                    })
                    .sum()
            })
            .collect();
        let mut first = vec![0usize; blocks + 1];
        for b in 0..blocks {
            first[b + 1] = first[b] + firsts[b];
        }
        // Each block walks its corners, numbering and placing the vertices it
        // sees first, and noting each one's shard and local id.
        let mut vertices = vec![DVec3::ZERO; first[blocks]];
        let mut news = vec![(0u32, 0u32); first[blocks]];
        type Part<'a> = (&'a mut [DVec3], &'a mut [(u32, u32)]);
        let mut parts: Vec<Part> = Vec::with_capacity(blocks);
        let (mut rest, mut rest_new) = (vertices.as_mut_slice(), news.as_mut_slice());
        for f in &firsts {
            let (part, tail) = std::mem::take(&mut rest).split_at_mut(*f);
            let (new, tail_new) = std::mem::take(&mut rest_new).split_at_mut(*f);
            parts.push((part, new));
            (rest, rest_new) = (tail, tail_new);
        }
        let walk = Walk {
            corners: &corners,
            shards: &shards,
            offset: &offset,
            base: &base,
            ids: &ids,
        };
        parts
            .into_par_iter()
            .enumerate()
            .for_each(|(b, (part, new))| {
                let mut n = 0;
                walk.block(b, |_, k, s, v| {
                    if v & FIRST != 0 {
                        part[n] = DVec3::new(
                            f32::from_bits(k[0]) as f64,
                            f32::from_bits(k[1]) as f64,
                            f32::from_bits(k[2]) as f64,
                        );
                        new[n] = (s as u32, v & !FIRST);
                        n += 1;
                    }
                });
            });
        let mut global: Vec<Vec<u32>> = uniques.iter().map(|&n| vec![0u32; n]).collect();
        for (j, &(s, l)) in news.iter().enumerate() {
            global[s as usize][l as usize] = j as u32;
        }
        drop(news);
        // Each shard's ids turned into vertex numbers (a shard's numbers
        // stay in cache, where the walk would look them up across all).
        {
            by_shard_mut(&mut ids, &base)
                .into_par_iter()
                .zip(&global)
                .for_each(|(ids, global)| {
                    for v in ids {
                        *v = global[(*v & !FIRST) as usize];
                    }
                });
        }
        drop(global);
        let walk = Walk {
            corners: &corners,
            shards: &shards,
            offset: &offset,
            base: &base,
            ids: &ids,
        };
        // Every corner's vertex number, block by block.
        let mut corner_tris = vec![[0u32; 3]; corners.len() / 3];
        corner_tris
            .par_chunks_mut(BLOCK / 3)
            .enumerate()
            .for_each(|(b, tris)| {
                let tris = tris.as_flattened_mut();
                walk.block(b, |j, _, _, v| tris[j] = v);
            });
        drop(ids);
        drop(shards);
        drop(corners);
        Self::assemble(vertices, corner_tris)
    }

    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    #[inline]
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        ]
    }

    /// Unit facet normal from the vertex order (counter-clockwise = outside).
    #[inline]
    pub fn facet_normal(&self, t: usize) -> DVec3 {
        let [a, b, c] = self.corners(t);
        (b - a).cross(c - a).normalize_or_zero()
    }

    pub fn area(&self) -> f64 {
        (0..self.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    pub fn bounds(&self) -> Aabb {
        self.vertices
            .par_chunks(1 << 14)
            .map(Aabb::from_points)
            .reduce(|| Aabb::EMPTY, |a, b| a.union(&b))
    }

    /// Counts open and non-manifold edges: each edge is listed under its
    /// lower vertex (a counting sort by vertex), then each vertex's short list
    /// is sorted and its runs counted. No hashing, and no sort of all edges.
    pub fn edge_report(&self) -> EdgeReport {
        let edges = |t: &[u32; 3]| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])];
        let n = self
            .triangles
            .par_iter()
            .map(|t| t[0].max(t[1]).max(t[2]) as usize + 1)
            .max()
            .unwrap_or(0);
        // Where each vertex's list starts: the edges it is the lower end of.
        let mut start = vec![0usize; n + 1];
        for t in &self.triangles {
            for (a, b) in edges(t) {
                start[a.min(b) as usize + 1] += 1;
            }
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut next = start.clone();
        let mut upper = vec![0u32; self.triangles.len() * 3];
        for t in &self.triangles {
            for (a, b) in edges(t) {
                let slot = &mut next[a.min(b) as usize];
                upper[*slot] = a.max(b);
                *slot += 1;
            }
        }
        drop(next);
        (0..n)
            .into_par_iter()
            .with_min_len(1 << 12)
            .fold(
                || (EdgeReport::default(), Vec::new()),
                |(mut r, mut list): (EdgeReport, Vec<u32>), v| {
                    list.clear();
                    list.extend_from_slice(&upper[start[v]..start[v + 1]]);
                    list.sort_unstable();
                    let mut i = 0;
                    while i < list.len() {
                        let mut j = i + 1;
                        while j < list.len() && list[j] == list[i] {
                            j += 1;
                        }
                        r.edges += 1;
                        match j - i {
                            1 => r.open += 1,
                            2 => {}
                            _ => r.non_manifold += 1,
                        }
                        i = j;
                    }
                    (r, list)
                },
            )
            .map(|(r, _)| r)
            .reduce(EdgeReport::default, |a, b| EdgeReport {
                edges: a.edges + b.edges,
                open: a.open + b.open,
                non_manifold: a.non_manifold + b.non_manifold,
            })
    }

    /// Applies `f` to every vertex (unit conversion, re-orientation).
    pub fn map_vertices(&mut self, f: impl Fn(DVec3) -> DVec3 + Sync) {
        self.vertices.par_iter_mut().for_each(|v| *v = f(*v));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube_soup() -> Vec<[DVec3; 3]> {
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let quads = [
            [v(0., 0., 0.), v(0., 1., 0.), v(1., 1., 0.), v(1., 0., 0.)],
            [v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)],
            [v(0., 0., 0.), v(1., 0., 0.), v(1., 0., 1.), v(0., 0., 1.)],
            [v(0., 1., 0.), v(0., 1., 1.), v(1., 1., 1.), v(1., 1., 0.)],
            [v(0., 0., 0.), v(0., 0., 1.), v(0., 1., 1.), v(0., 1., 0.)],
            [v(1., 0., 0.), v(1., 1., 0.), v(1., 1., 1.), v(1., 0., 1.)],
        ];
        quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect()
    }

    #[test]
    fn closed_cube_welds_to_8_vertices_and_has_no_open_edges() {
        let (m, r) = TriMesh::from_soup(&cube_soup());
        assert_eq!(
            r,
            WeldReport {
                degenerate: 0,
                vertices: 8
            }
        );
        assert_eq!(m.len(), 12);
        assert_eq!(
            m.edge_report(),
            EdgeReport {
                edges: 18,
                open: 0,
                non_manifold: 0
            }
        );
        crate::assert_near!(m.area(), 6.0, 1e-12);
        // Outward normals: the bottom face points down.
        crate::assert_near!(m.facet_normal(0), DVec3::new(0., 0., -1.), 1e-12);
    }

    /// The soup welded in double precision, and in single precision as
    /// binary STL holds it.
    fn both_welds(soup: &[[DVec3; 3]]) -> ((TriMesh, WeldReport), (TriMesh, WeldReport)) {
        let s32: Vec<[[f32; 3]; 3]> = soup
            .iter()
            .map(|t| t.map(|p| [p.x as f32, p.y as f32, p.z as f32]))
            .collect();
        (TriMesh::from_soup(soup), TriMesh::from_f32_soup(&s32))
    }

    #[test]
    fn f32_weld_matches_f64_weld() {
        let ((a, ra), (b, rb)) = both_welds(&cube_soup());
        assert_eq!(
            (ra, a.triangles.clone(), a.vertices.clone()),
            (rb, b.triangles, b.vertices)
        );
    }

    /// A soup of several welding blocks, its triangles shuffled so vertices
    /// first appear in one block and come back in others, with degenerate
    /// triangles among them: the parallel weld numbers vertices as the serial one.
    #[test]
    fn f32_weld_of_many_blocks_matches_f64_weld() {
        let n = 300;
        let z = |i: usize, j: usize| ((i * 7 + j * 13) % 17) as f64 * 0.25;
        let p = |i: usize, j: usize| DVec3::new(i as f64 * 0.5, j as f64 * 0.5, z(i, j));
        let mut soup: Vec<[DVec3; 3]> = Vec::new();
        for i in 0..n {
            for j in 0..n {
                soup.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                soup.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
                if (i + j) % 97 == 0 {
                    soup.push([p(i, j), p(i, j), p(i + 1, j)]);
                }
            }
        }
        let mut state = 12345u64;
        for k in (1..soup.len()).rev() {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            soup.swap(k, (state >> 33) as usize % (k + 1));
        }
        assert!(soup.len() * 3 > 2 * (3 << 16), "spans several blocks");
        let ((a, ra), (b, rb)) = both_welds(&soup);
        assert!(ra.degenerate > 0);
        assert_eq!(ra, rb);
        assert!(a.triangles == b.triangles);
        assert!(a.vertices == b.vertices);
    }

    /// The edge counts against a sort of all packed edge keys, on a fan
    /// with a triangle repeated (non-manifold edges), open borders and an
    /// edge used three times.
    #[test]
    fn edge_report_matches_a_sort_of_all_edges() {
        let mut triangles: Vec<[u32; 3]> = (1..40u32).map(|i| [0, i, i + 1]).collect();
        triangles.extend([[0, 5, 6], [7, 8, 50], [8, 7, 51], [7, 8, 52], [60, 61, 62]]);
        let mesh = TriMesh {
            vertices: vec![DVec3::ZERO; 63],
            triangles,
        };
        let mut keys: Vec<u64> = mesh
            .triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .map(|(a, b)| ((a.min(b) as u64) << 32) | a.max(b) as u64)
            .collect();
        keys.sort_unstable();
        let mut want = EdgeReport::default();
        for run in keys.chunk_by(|a, b| a == b) {
            want.edges += 1;
            want.open += (run.len() == 1) as usize;
            want.non_manifold += (run.len() > 2) as usize;
        }
        assert!(want.open > 0 && want.non_manifold > 1);
        assert_eq!(mesh.edge_report(), want);
    }

    #[test]
    fn open_box_and_degenerates() {
        let mut soup = cube_soup();
        soup.truncate(10); // remove one face: 4 open edges
        let p = DVec3::new(5., 5., 5.);
        soup.push([p, p, DVec3::ZERO]); // repeated vertex
        soup.push([DVec3::ZERO, DVec3::X, DVec3::X * 2.0]); // collinear
        let (m, r) = TriMesh::from_soup(&soup);
        assert_eq!(r.degenerate, 2);
        assert_eq!(m.edge_report().open, 4);
    }
}
