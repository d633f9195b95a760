//! Contact analysis against an analytic surface whose contact points and normals
//! are known exactly (the CL points are generated from them).

use millplan_geom::analytic::{tessellate, DemoSurface, HeightField};
use millplan_geom::DVec3;
use millplan_models::contact::*;
use millplan_models::wd::{self, Neighbour, Side};

/// Zig-zag raster along X, stepover along Y; returns points and their exact contacts.
fn raster(
    s: &DemoSurface,
    d: f64,
    step: f64,
    stepover: f64,
    conv: Convention,
) -> (Vec<PathPoint>, Vec<DVec3>) {
    let r = d / 2.0;
    let mut pts = Vec::new();
    let mut exact = Vec::new();
    let rows = ((50.0 / stepover) as usize).min(60);
    for j in 0..rows {
        let y = 5.0 + stepover * j as f64;
        let n = (50.0 / step) as usize;
        for i in 0..=n {
            let i = if j % 2 == 0 { i } else { n - i };
            let x = 5.0 + step * i as f64;
            let p = s.point(x, y);
            let c = p + s.normal(x, y) * r;
            let cl = match conv {
                Convention::Tip => c - DVec3::Z * r,
                Convention::Centre => c,
            };
            pts.push(PathPoint {
                cl,
                axis: DVec3::Z,
                pass: j as u32,
            });
            exact.push(p);
        }
    }
    (pts, exact)
}

#[test]
fn contact_points_normals_and_neighbours_match_the_analytic_surface() {
    let s = DemoSurface::default();
    let mesh = tessellate(&s, 0.5);
    let surf = Surface::new(&mesh);
    let (pts, exact) = raster(&s, 10.0, 0.5, 1.0, Convention::Tip);
    let check = detect_convention(&surf, &pts, 5.0);
    assert_eq!(check.chosen, Convention::Tip, "{check:?}");
    let res = analyse(&surf, &pts, &Params::new(10.0, 0.3));
    let (mut worst_p, mut worst_n, mut worst_gap) = (0.0f64, 0.0f64, 0.0f64);
    for (k, (r, p)) in res.iter().zip(&exact).enumerate() {
        worst_p = worst_p.max((r.contact - *p).length());
        worst_n = worst_n.max(r.normal.angle_between(s.normal(p.x, p.y)).to_degrees());
        worst_gap = worst_gap.max(r.gap.abs());
        let row = pts[k].pass;
        // Neighbours: the first pass has none; later passes see the previous row.
        match (row, r.neighbour) {
            (0, Neighbour::None) => {}
            (0, other) => panic!("first pass has neighbour {other:?}"),
            (_, Neighbour::One(ae)) => {
                assert!((0.8..1.6).contains(&ae), "row {row}: ae {ae}");
                // Even rows go +X with the previous row on the right: uncut left.
                let want = if row % 2 == 0 {
                    Side::Left
                } else {
                    Side::Right
                };
                if !r.corner {
                    assert_eq!(r.side, want, "row {row} point {k}");
                }
            }
            (_, other) => panic!("row {row}: {other:?}"),
        }
    }
    // Tessellation at 0.5 mm: the closest point on a facet lies up to R·(facet
    // tilt) from the true contact: within 0.1 mm; smooth normal within 1°; gap 0.01 mm.
    eprintln!("contact error {worst_p:.4} mm, normal error {worst_n:.3}°, gap {worst_gap:.4} mm");
    assert!(worst_p < 0.1, "contact error {worst_p}");
    assert!(worst_n < 1.0, "normal error {worst_n}°");
    assert!(worst_gap < 0.01, "gap {worst_gap}");
}

#[test]
fn centre_convention_is_detected_and_flat_dw_is_the_catalogue_value() {
    // A flat plate: D_w = 2·sqrt(ap(D − ap)) everywhere (O1), whatever the order.
    struct Flat;
    impl HeightField for Flat {
        fn z(&self, _: f64, _: f64) -> f64 {
            0.0
        }
        fn grad(&self, _: f64, _: f64) -> millplan_geom::DVec2 {
            millplan_geom::DVec2::ZERO
        }
        fn domain(&self) -> (millplan_geom::DVec2, millplan_geom::DVec2) {
            (
                millplan_geom::DVec2::ZERO,
                millplan_geom::DVec2::splat(60.0),
            )
        }
    }
    let mesh = tessellate(&Flat, 5.0);
    let surf = Surface::new(&mesh);
    let pts: Vec<PathPoint> = (0..200)
        .map(|i| PathPoint {
            cl: DVec3::new(10.0 + (i % 20) as f64, 10.0 + (i / 20) as f64, 6.0),
            axis: DVec3::Z,
            pass: i / 20,
        })
        .collect();
    let check = detect_convention(&surf, &pts, 6.0);
    assert_eq!(check.chosen, Convention::Centre, "{check:?}");
    let mut p = Params::new(12.0, 0.5);
    p.convention = Convention::Centre;
    for r in analyse(&surf, &pts, &p) {
        assert!((r.dw - 2.0 * (0.5f64 * 11.5).sqrt()).abs() < 1e-9);
        assert!(r.inclination.abs() < 1e-9);
    }
}

#[test]
fn working_diameter_along_the_raster_matches_the_model_with_exact_inputs() {
    let s = DemoSurface::default();
    let mesh = tessellate(&s, 0.25);
    let surf = Surface::new(&mesh);
    let (pts, exact) = raster(&s, 10.0, 0.5, 1.0, Convention::Tip);
    let res = analyse(&surf, &pts, &Params::new(10.0, 0.3));
    let mut worst: f64 = 0.0;
    for (r, p) in res.iter().zip(&exact) {
        if r.corner {
            continue;
        }
        let n = s.normal(p.x, p.y);
        let alpha = n.angle_between(DVec3::Z);
        let c = wd::Case {
            d: 10.0,
            ap: 0.3,
            neighbour: r.neighbour,
            alpha,
            af: r.feed_angle,
            side: r.side,
        };
        worst = worst.max((wd::working_diameter(&c) - r.dw).abs());
    }
    assert!(
        worst < 0.1,
        "D_w with mesh normals vs exact normals: {worst} mm"
    );
}

#[test]
fn sides_and_stepovers_do_not_depend_on_where_the_part_sits() {
    // The same raster and part, moved: which machined centres count as
    // neighbours must not depend on how the neighbour grid's cells fall.
    // Passes bunch up and spread out (stepover 0.6 to 1.4 mm), so some
    // machined centres lie beside the feed direction but outside the search
    // radius, in cells the search happens to scan at one placement and not
    // at another.
    let s = DemoSurface::default();
    let mesh = tessellate(&s, 0.5);
    let (pts, _) = raster(&s, 10.0, 0.5, 1.0, Convention::Tip);
    let rows = pts.iter().map(|q| q.pass).max().unwrap_or(0) + 1;
    let spacing = |j: u32| 0.6 + 0.8 * ((j as f64 * 2.39).sin() * 0.5 + 0.5);
    let mut y_of = vec![0.0; rows as usize];
    for j in 1..rows as usize {
        y_of[j] = y_of[j - 1] + spacing(j as u32);
    }
    // Re-place each pass at its own Y on the surface (the raster helper's rows
    // are 1 mm apart); X and the pass numbers stay.
    let r = 5.0;
    let pts: Vec<PathPoint> = pts
        .iter()
        .map(|q| {
            let (x, y) = (q.cl.x, 5.0 + y_of[q.pass as usize]);
            let c = s.point(x, y) + s.normal(x, y) * r;
            PathPoint {
                cl: c - DVec3::Z * r,
                ..*q
            }
        })
        .filter(|q| q.cl.y < 54.0)
        .collect();
    let params = Params::new(10.0, 0.3);
    let base = analyse(&Surface::new(&mesh), &pts, &params);
    let mut checked = 0;
    for o in [
        DVec3::new(0.37, 0.61, 0.23),
        DVec3::new(-1.13, 0.29, -0.71),
        DVec3::new(0.05, -0.83, 1.41),
    ] {
        let mut moved_mesh = mesh.clone();
        moved_mesh.map_vertices(|v| v + o);
        let moved: Vec<PathPoint> = pts
            .iter()
            .map(|q| PathPoint { cl: q.cl + o, ..*q })
            .collect();
        let res = analyse(&Surface::new(&moved_mesh), &moved, &params);
        for (k, (a, b)) in base.iter().zip(&res).enumerate() {
            let ae = |n: Neighbour| match n {
                Neighbour::None => None,
                Neighbour::One(x) => Some((1, x)),
                Neighbour::Both(x) => Some((2, x)),
            };
            match (ae(a.neighbour), ae(b.neighbour)) {
                (None, None) => {}
                (Some((ka, xa)), Some((kb, xb))) if ka == kb && (xa - xb).abs() < 1e-6 => {}
                (x, y) => panic!("point {k} moved by {o}: neighbour {x:?} against {y:?}"),
            }
            assert_eq!(a.side, b.side, "point {k} moved by {o}");
            checked += 1;
        }
    }
    assert!(checked > 3000, "{checked} points compared");
}
