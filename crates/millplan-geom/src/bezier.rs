//! Bicubic Bézier patches and their tessellation, and a free-form test part made
//! of them: a vase-shaped body of revolution (a teapot without spout and handle)
//! for accessibility and setup tests.

use crate::TriMesh;
use glam::DVec3;

/// A bicubic Bézier patch: control points `p[i][j]`, i along u, j along v.
pub type Patch = [[DVec3; 4]; 4];

fn bernstein(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t]
}

/// The point of a patch at (u, v).
pub fn eval(p: &Patch, u: f64, v: f64) -> DVec3 {
    let (bu, bv) = (bernstein(u), bernstein(v));
    let mut q = DVec3::ZERO;
    for i in 0..4 {
        for j in 0..4 {
            q += p[i][j] * (bu[i] * bv[j]);
        }
    }
    q
}

/// Tessellates patches on an n × n grid each, triangles wound so that the
/// normal is ∂P/∂v × ∂P/∂u (flip the patch's j order to turn it around).
pub fn tessellate_patches(patches: &[Patch], n: usize) -> TriMesh {
    let n = n.max(1);
    let mut soup = Vec::with_capacity(patches.len() * n * n * 2);
    for p in patches {
        let g: Vec<Vec<DVec3>> = (0..=n)
            .map(|i| {
                (0..=n)
                    .map(|j| eval(p, i as f64 / n as f64, j as f64 / n as f64))
                    .collect()
            })
            .collect();
        for i in 0..n {
            for j in 0..n {
                let (a, b, c, d) = (g[i][j], g[i + 1][j], g[i + 1][j + 1], g[i][j + 1]);
                soup.push([a, d, c]);
                soup.push([a, c, b]);
            }
        }
    }
    TriMesh::from_soup(&soup).0
}

/// The vase: a profile of three cubic segments (flat bottom, belly, flared neck;
/// 120 mm across the belly, 100 mm tall, open at the top) revolved with four
/// cubic quarter-circle arcs: 12 bicubic patches. The bottom faces −Z at Z = 0.
pub fn vase() -> Vec<Patch> {
    let profile: [[(f64, f64); 4]; 3] = [
        [(0.0, 0.0), (15.0, 0.0), (30.0, 0.0), (40.0, 0.0)],
        [(40.0, 0.0), (62.0, 8.0), (62.0, 52.0), (35.0, 70.0)],
        [(35.0, 70.0), (24.0, 78.0), (24.0, 92.0), (34.0, 100.0)],
    ];
    // A quarter circle as a cubic: (1,0), (1,k), (k,1), (0,1) with k = 4(√2 − 1)/3.
    let k = 4.0 * (2f64.sqrt() - 1.0) / 3.0;
    let arc = [(1.0, 0.0), (1.0, k), (k, 1.0), (0.0, 1.0)];
    let mut out = Vec::new();
    for seg in &profile {
        for q in 0..4 {
            let mut p = [[DVec3::ZERO; 4]; 4];
            for (i, &(r, z)) in seg.iter().enumerate() {
                for (j, &(x, y)) in arc.iter().enumerate() {
                    // Exact quarter turns, so that neighbouring patches share their seams.
                    let (x, y) = [(x, y), (-y, x), (-x, -y), (y, -x)][q];
                    p[i][j] = DVec3::new(r * x, r * y, z);
                }
            }
            out.push(p);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_vase_is_a_body_of_revolution_facing_out() {
        let m = tessellate_patches(&vase(), 12);
        // The four quarter patches meet: only the rim is open (weld is exact).
        let e = m.edge_report();
        assert_eq!(e.non_manifold, 0);
        assert_eq!(e.open, 4 * 12, "open edges: the rim only");
        let b = m.bounds();
        assert!(b.min.z.abs() < 1e-12 && (b.max.z - 100.0).abs() < 1e-12);
        for t in 0..m.len() {
            for v in m.corners(t) {
                assert!((v.x * v.x + v.y * v.y).sqrt() <= 62.0, "{v}");
            }
            let [a, bb, c] = m.corners(t);
            let cen = (a + bb + c) / 3.0;
            let n = m.facet_normal(t);
            // Outward: away from the axis on the wall, down on the bottom.
            if cen.z < 1e-9 {
                assert!(n.z < -0.999);
            } else {
                assert!(
                    DVec3::new(cen.x, cen.y, 0.0).dot(n) > 0.0,
                    "facet {t} at {cen}: {n}"
                );
            }
        }
        // Exact on the circle at the arc ends, within 0.03 % between.
        let p = &vase()[4];
        for k in 0..=20 {
            let q = eval(p, 0.0, k as f64 / 20.0);
            let r = (q.x * q.x + q.y * q.y).sqrt();
            assert!((r - 40.0).abs() < 40.0 * 3e-4, "{r}");
        }
    }
}
