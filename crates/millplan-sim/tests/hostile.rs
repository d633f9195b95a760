//! Hostile parts and arguments (issue 17): the work a raster or a gouge check
//! asks for is counted before it is done, and repeated facets cost nothing.

use millplan_geom::analytic::{tessellate, DemoSurface};
use millplan_geom::{DVec2, DVec3, TriMesh};
use millplan_models::cutter::Shape;
use millplan_sim::dropcutter::DropMesh;
use millplan_sim::gouge::{check, samples, GougeParams};
use millplan_sim::raster::{estimate, raster, RasterParams};
use millplan_sim::stock::tool::ToolBody;

fn ball() -> Shape {
    Shape::Ball { radius: 5.0 }
}

/// Issue 17: "200k identical triangles make `raster`/`gouge` run over 60 s".
/// Copies of a facet are one facet to the drop-cutter: the same drops, and a
/// raster over 200,000 copies as quick as over one.
#[test]
fn repeated_facets_are_one_facet() {
    let one = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(60.0, 0.0, 0.0),
        DVec3::new(0.0, 60.0, 5.0),
    ];
    let (single, _) = TriMesh::from_soup(&[one]);
    // Copies in both windings.
    let soup: Vec<[DVec3; 3]> = (0..200_000)
        .map(|k| {
            if k % 2 == 0 {
                one
            } else {
                [one[0], one[2], one[1]]
            }
        })
        .collect();
    let (many, _) = TriMesh::from_soup(&soup);
    assert_eq!(many.len(), 200_000);
    let (a, b) = (DropMesh::new(&single), DropMesh::new(&many));
    for k in 0..50 {
        let c = DVec2::new(1.0 + k as f64, 2.0 + 0.5 * k as f64);
        let (da, db) = (a.drop(&ball(), c), b.drop(&ball(), c));
        assert_eq!(da.map(|d| d.z), db.map(|d| d.z), "{c}");
        // The contact names a facet of the mesh, and its own geometry.
        if let Some(d) = db {
            assert!((d.triangle as usize) < many.len());
            assert_eq!(
                b.drop_near(&ball(), c, Some(d.triangle)).map(|d| d.z),
                Some(d.z)
            );
        }
    }
    let t = std::time::Instant::now();
    let mut p = RasterParams::new(ball());
    p.tol = None;
    let prog = raster(&b, &many.bounds(), &p);
    assert!(prog.move_count() > 1000);
    let rep = check(
        &prog,
        &b,
        |_| Some(ToolBody::new(ball())),
        &GougeParams::default(),
    );
    assert!(rep.points_checked > 1000);
    assert!(
        t.elapsed().as_secs() < 20,
        "raster and check took {:?}",
        t.elapsed()
    );
}

/// The grid count matches the raster made, within its boundary effects; a
/// step of 1e-300 or a margin of -1e308 is counted, not attempted.
#[test]
fn a_raster_is_counted_before_it_is_made() {
    let mesh = tessellate(&DemoSurface::default(), 1.0);
    let part = DropMesh::new(&mesh);
    let b = mesh.bounds();
    for angle in [0.0, 30.0, 90.0, 135.0] {
        let mut p = RasterParams::new(ball());
        p.angle_deg = angle;
        p.tol = None;
        p.margin = 1.0;
        let e = estimate(&b, &p, 0.1);
        let n = raster(&part, &b, &p).move_count() as f64;
        assert!(
            (e.points - n).abs() < 0.1 * n,
            "{angle}°: estimated {} points, made {n}",
            e.points
        );
        assert!(e.bytes > e.points * 100.0);
    }
    let mut p = RasterParams::new(ball());
    p.step = 1e-300;
    assert!(estimate(&b, &p, 0.1).points > 1e300);
    p.step = 0.5;
    p.margin = -1e308;
    assert!(estimate(&b, &p, 0.1).points.is_infinite());
    // A margin wider than the part: nothing to raster, at once.
    p.margin = 1e308;
    assert_eq!(estimate(&b, &p, 0.1).points, 0.0);
    assert_eq!(raster(&part, &b, &p).move_count(), 0);
}

/// The gouge check's sample count, counted first, is the count it samples.
#[test]
fn a_gouge_check_is_counted_before_it_is_made() {
    let mesh = tessellate(&DemoSurface::default(), 1.0);
    let part = DropMesh::new(&mesh);
    let prog = raster(&part, &mesh.bounds(), &RasterParams::new(ball()));
    for step in [0.05, 0.1, 1.0] {
        let g = GougeParams {
            step,
            ..GougeParams::default()
        };
        let rep = check(&prog, &part, |_| Some(ToolBody::new(ball())), &g);
        assert_eq!(
            samples(&prog, |_| Some(ToolBody::new(ball())), &g),
            rep.points_checked as f64
        );
    }
    let g = GougeParams {
        step: 1e-9,
        ..GougeParams::default()
    };
    assert!(samples(&prog, |_| Some(ToolBody::new(ball())), &g) > 1e11);
}

/// Issue 34: "`--stock box:0,0,0,429496729.6,429496729.6,1`: the memory
/// estimate wraps". A 2³² × 2³² grid counted 0 cells, so the estimate made
/// before allocating passed any limit; the count now saturates and the byte
/// estimate is made in floating point.
#[test]
fn huge_stock_grid_estimate_never_wraps() {
    use millplan_sim::stock::{Grid, BYTES_PER_CELL};
    let g = Grid::covering(DVec2::ZERO, DVec2::new(429_496_729.6, 429_496_729.6), 0.1);
    assert_eq!((g.nx, g.ny), (1 << 32, 1 << 32));
    assert_eq!(g.cells(), usize::MAX);
    assert!(g.cells() as f64 * BYTES_PER_CELL > 1e19);
    assert!((g.stock_bytes() / (2f64.powi(64) * BYTES_PER_CELL) - 1.0).abs() < 1e-12);
    // `box:auto:1e18`: the width is beyond usize, the count saturates.
    let g = Grid::covering(DVec2::splat(-1e18), DVec2::splat(1e18), 0.1);
    assert_eq!(g.cells(), usize::MAX);
    let g = Grid::covering(DVec2::splat(-1e308), DVec2::splat(1e308), 0.1);
    assert_eq!(g.cells(), usize::MAX);
    assert!(g.stock_bytes() > 1e30);
}
