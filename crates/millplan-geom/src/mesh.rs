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
    /// triangle; `-0.0` already folded to `+0.0`). The corners are split by hash
    /// into shards welded in parallel, then vertices are numbered in file order.
    pub fn from_f32_corners(corners: Vec<[u32; 3]>) -> (TriMesh, WeldReport) {
        use std::hash::BuildHasher;
        const SHARD_BITS: u32 = 5;
        const SHARDS: usize = 1 << SHARD_BITS;
        let hasher = rustc_hash::FxBuildHasher;
        let shard_of = |k: &[u32; 3]| (hasher.hash_one(k) >> (64 - SHARD_BITS)) as usize;
        let shard: Vec<u8> = corners.par_iter().map(|k| shard_of(k) as u8).collect();
        let mut lists: Vec<Vec<u32>> = (0..SHARDS)
            .map(|_| Vec::with_capacity(corners.len() / SHARDS + 16))
            .collect();
        for (i, s) in shard.iter().enumerate() {
            lists[*s as usize].push(i as u32);
        }
        // Weld each shard on its own: local ids in the order corners appear.
        let local: Vec<(Vec<u32>, Vec<u32>)> = lists
            .par_iter()
            .map(|list| {
                let mut map: FxHashMap<[u32; 3], u32> = FxHashMap::default();
                map.reserve(list.len() / 4);
                let mut ids = Vec::with_capacity(list.len());
                let mut firsts = Vec::new();
                for &i in list {
                    let next = firsts.len() as u32;
                    let id = *map.entry(corners[i as usize]).or_insert_with(|| {
                        firsts.push(i);
                        next
                    });
                    ids.push(id);
                }
                (ids, firsts)
            })
            .collect();
        drop(lists);
        // Number vertices globally in order of first appearance.
        let mut global: Vec<Vec<u32>> =
            local.iter().map(|(_, f)| vec![u32::MAX; f.len()]).collect();
        let mut cursor = [0usize; SHARDS];
        let mut vertices: Vec<DVec3> = Vec::with_capacity(corners.len() / 6 + 16);
        let mut corner_id = vec![0u32; corners.len()];
        for (i, k) in corners.iter().enumerate() {
            let s = shard[i] as usize;
            let l = local[s].0[cursor[s]] as usize;
            cursor[s] += 1;
            if global[s][l] == u32::MAX {
                global[s][l] = vertices.len() as u32;
                vertices.push(DVec3::new(
                    f32::from_bits(k[0]) as f64,
                    f32::from_bits(k[1]) as f64,
                    f32::from_bits(k[2]) as f64,
                ));
            }
            corner_id[i] = global[s][l];
        }
        drop(local);
        drop(global);
        drop(shard);
        drop(corners);
        let corner_tris: Vec<[u32; 3]> = corner_id
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        drop(corner_id);
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

    /// Counts open and non-manifold edges (by sorting packed edge keys: no hashing).
    pub fn edge_report(&self) -> EdgeReport {
        let mut keys: Vec<u64> = Vec::with_capacity(self.triangles.len() * 3);
        for t in &self.triangles {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let (lo, hi) = if a < b { (a, b) } else { (b, a) };
                keys.push(((lo as u64) << 32) | hi as u64);
            }
        }
        keys.par_sort_unstable();
        let mut r = EdgeReport::default();
        let mut i = 0;
        while i < keys.len() {
            let mut j = i + 1;
            while j < keys.len() && keys[j] == keys[i] {
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
        r
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

    #[test]
    fn f32_weld_matches_f64_weld() {
        let soup = cube_soup();
        let s32: Vec<[[f32; 3]; 3]> = soup
            .iter()
            .map(|t| t.map(|p| [p.x as f32, p.y as f32, p.z as f32]))
            .collect();
        let (a, ra) = TriMesh::from_soup(&soup);
        let (b, rb) = TriMesh::from_f32_soup(&s32);
        assert_eq!(
            (ra, a.triangles.clone(), a.vertices.clone()),
            (rb, b.triangles, b.vertices)
        );
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
