//! Drop-cutter: the pruned BVH search against the brute-force reference on random
//! meshes and real STL files, and a raster over an analytic surface against its
//! exact offset.

use millplan_geom::analytic::{tessellate, HeightField};
use millplan_geom::{DVec2, DVec3, TriMesh};
use millplan_models::cutter::Shape;
use millplan_sim::dropcutter::{drop_brute, DropMesh};
use proptest::prelude::*;

#[path = "../../millplan-nc/tests/shared_data/mod.rs"]
mod shared_data;

fn shapes() -> Vec<Shape> {
    vec![
        Shape::Flat { radius: 3.0 },
        Shape::Ball { radius: 3.0 },
        Shape::Bull {
            radius: 3.0,
            corner: 1.0,
        },
        Shape::Cone {
            radius: 3.0,
            alpha: 31f64.to_radians(),
        },
    ]
}

fn random_mesh(seed: u64, n: usize) -> TriMesh {
    let mut s = seed
        .wrapping_mul(2862933555777941757)
        .wrapping_add(3037000493);
    let mut r = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut soup = Vec::new();
    for _ in 0..n {
        let c = DVec3::new(20.0 * r(), 20.0 * r(), 5.0 * r());
        let t =
            [0, 1, 2].map(|_| c + DVec3::new(4.0 * r() - 2.0, 4.0 * r() - 2.0, 3.0 * r() - 1.5));
        soup.push(t);
    }
    TriMesh::from_soup(&soup).0
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(60))]

    #[test]
    fn bvh_search_equals_brute_force(seed in any::<u64>(), x in -2.0..22.0f64, y in -2.0..22.0f64, k in 0usize..4) {
        let mesh = random_mesh(seed, 300);
        let dm = DropMesh::new(&mesh);
        let sh = shapes()[k];
        let c = DVec2::new(x, y);
        let brute = drop_brute(&sh, &mesh, c);
        // With and without a warm-start hint (any triangle, even a far one).
        for got in [dm.drop(&sh, c), dm.drop_near(&sh, c, Some((seed % mesh.len() as u64) as u32))] {
            match (got, brute) {
                (Some(a), Some(b)) => prop_assert!((a.z - b.z).abs() < 1e-12, "{:?} vs {:?}", a, b),
                (None, None) => {}
                (a, b) => prop_assert!(false, "{:?} vs {:?}", a, b),
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// A fine tessellation of a smooth surface, where the node bounds (upper
    /// plane over the node's box) are tight and prune the most; and the gouge
    /// question `rises_above` just below, at and just above the drop.
    #[test]
    fn smooth_surface_search_equals_brute_force(x in 0.0..59.0f64, y in 0.0..59.0f64, k in 0usize..4) {
        use std::sync::OnceLock;
        static PART: OnceLock<(TriMesh, DropMesh)> = OnceLock::new();
        let (mesh, dm) = PART.get_or_init(|| {
            let m = tessellate(&millplan_geom::analytic::DemoSurface::default(), 0.6);
            let d = DropMesh::new(&m);
            (m, d)
        });
        let sh = shapes()[k];
        // A small patch of points: contacts anywhere on and between facets.
        for i in 0..25 {
            let c = DVec2::new(x + 0.11 * (i % 5) as f64, y + 0.13 * (i / 5) as f64);
            let brute = drop_brute(&sh, mesh, c).expect("over the part");
            let got = dm.drop(&sh, c).expect("over the part");
            prop_assert!((got.z - brute.z).abs() < 1e-12, "{:?} vs {:?}", got, brute);
            for dz in [-1e-6, 1e-6, 0.01] {
                prop_assert_eq!(dm.rises_above(&sh, c, brute.z + dz), dz < 0.0);
            }
        }
    }
}

/// A gently curved dome: curvature radius about 25 mm, smooth everywhere.
struct Dome;
impl HeightField for Dome {
    fn z(&self, x: f64, y: f64) -> f64 {
        -((x - 5.0).powi(2) + (y - 5.0).powi(2)) / 50.0
    }
    fn grad(&self, x: f64, y: f64) -> DVec2 {
        DVec2::new(-(x - 5.0) / 25.0, -(y - 5.0) / 25.0)
    }
    fn domain(&self) -> (DVec2, DVec2) {
        (DVec2::ZERO, DVec2::splat(10.0))
    }
}

#[test]
fn raster_heights_match_the_analytic_offset_surface() {
    // Facets of 0.05 mm sag by at most 0.05²/(8·25) ≈ 1.3e-5 mm on this dome.
    let mesh = tessellate(&Dome, 0.05);
    let dm = DropMesh::new(&mesh);
    let ball = Shape::Ball { radius: 2.0 };
    let mut worst: f64 = 0.0;
    for i in 0..15 {
        for j in 0..15 {
            // Pick the contact point, place the ball on it: the tip is exact.
            let (x, y) = (3.0 + 4.0 * i as f64 / 14.0, 3.0 + 4.0 * j as f64 / 14.0);
            let p = Dome.point(x, y);
            let tip = p + Dome.normal(x, y) * 2.0 - DVec3::Z * 2.0;
            let d = dm
                .drop(&ball, DVec2::new(tip.x, tip.y))
                .expect("over the part");
            worst = worst.max((d.z - tip.z).abs());
        }
    }
    assert!(
        worst < 1e-4,
        "worst deviation from the offset surface {worst} mm"
    );
}

#[test]
fn opencamlib_meshes_agree_with_brute_force() {
    for name in ["ktoolcav.stl", "beet_mm.stl", "mount_rush.stl"] {
        let Some(path) = shared_data::file(&format!("stl-pitfalls-opencamlib/{name}")) else {
            continue;
        };
        let bytes = std::fs::read(path).expect("a sample reads");
        let (mesh, _) = millplan_geom::stl::read_stl(&bytes).expect("reads");
        let b = mesh.bounds();
        let dm = DropMesh::new(&mesh);
        let scale = b.size().x.max(b.size().y);
        for sh in [
            Shape::Ball {
                radius: scale / 40.0,
            },
            Shape::Bull {
                radius: scale / 40.0,
                corner: scale / 160.0,
            },
        ] {
            for i in 0..12 {
                for j in 0..12 {
                    let c = DVec2::new(
                        b.min.x + b.size().x * (i as f64 + 0.5) / 12.0,
                        b.min.y + b.size().y * (j as f64 + 0.5) / 12.0,
                    );
                    let (a, r) = (dm.drop(&sh, c), drop_brute(&sh, &mesh, c));
                    assert_eq!(
                        a.map(|d| (d.z * 1e9).round()),
                        r.map(|d| (d.z * 1e9).round()),
                        "{name} {sh:?} at {c:?}"
                    );
                }
            }
        }
    }
}
