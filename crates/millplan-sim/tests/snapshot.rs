//! Local copies of the stock before chosen strokes (`stock::snapshot`): a
//! crop holds exactly the cells of its window, and the crops taken along a
//! run are those of the stroke-by-stroke simulator at the same strokes.

use millplan_geom::{DVec2, DVec3};
use millplan_models::cutter::Shape;
use millplan_sim::stock::path::{Stroke, Strokes};
use millplan_sim::stock::sim::Simulator;
use millplan_sim::stock::snapshot::crops_before;
use millplan_sim::stock::tool::ToolBody;
use millplan_sim::stock::{Grid, Stock};

fn stroke(mv: u32, p0: DVec3, p1: DVec3, axis: DVec3) -> Stroke {
    Stroke {
        mv,
        line: mv,
        tool: 0,
        rapid: false,
        p0,
        p1,
        a0: axis,
        a1: axis,
        minutes: (p1 - p0).length() / 1000.0,
    }
}

/// Every material interval of `crop` is that of the same cell of `full`,
/// every cell of `full` whose square lies in the window is in the crop, and
/// points outside the crop are never material.
fn assert_crop_of(full: &Stock, crop: &Stock, lo: DVec2, hi: DVec2) {
    let (g, c) = (full.grid, crop.grid);
    for j in 0..c.ny {
        for i in 0..c.nx {
            let (x, y) = (c.cx(i), c.cy(j));
            let (fi, fj) = g.cell_of(x, y).expect("a crop cell lies in the grid");
            assert_eq!(
                crop.intervals(i, j),
                full.intervals(fi, fj),
                "cell ({x}, {y})"
            );
        }
    }
    for j in 0..g.ny {
        for i in 0..g.nx {
            let (x, y) = (g.cx(i), g.cy(j));
            if x > lo.x && x < hi.x && y > lo.y && y < hi.y {
                assert!(crop.grid.cell_of(x, y).is_some(), "({x}, {y}) left out");
            }
        }
    }
    let outside = DVec3::new(c.max().x + 0.5 * c.res, c.cy(0), -3.0);
    assert!(!crop.contains(outside));
}

#[test]
fn a_crop_keeps_its_window_with_the_gaps() {
    // A block with a cavity in some columns (gaps) and a wavy top.
    let grid = Grid::covering(DVec2::new(-10.0, -8.0), DVec2::new(12.0, 9.0), 0.2);
    let full = Stock::from_columns(grid, |x, y| {
        let top = 1.0 + 0.3 * (0.7 * x).sin() * (0.4 * y).cos();
        if (x - 2.0).hypot(y + 1.0) < 3.0 {
            vec![[-5.0, -3.0], [-2.0, top]]
        } else {
            vec![[-5.0, top]]
        }
    });
    assert!(full.has_gaps());
    for (lo, hi) in [
        (DVec2::new(-1.3, -4.1), DVec2::new(5.7, 2.2)),
        (DVec2::new(-20.0, -20.0), DVec2::new(-9.5, 20.0)),
        (DVec2::new(11.9, 8.9), DVec2::new(30.0, 30.0)),
    ] {
        let c = full.crop(lo, hi);
        assert_crop_of(&full, &c, lo, hi);
    }
    let c = full.crop(DVec2::new(-1.3, -4.1), DVec2::new(5.7, 2.2));
    assert!(c.has_gaps(), "the cavity lies in the window");
    assert!(c.cells() < full.cells() / 4);
    // Beside the grid: one empty cell.
    let none = full.crop(DVec2::new(50.0, 50.0), DVec2::new(60.0, 60.0));
    assert_eq!(none.cells(), 1);
    assert_eq!(none.volume(), 0.0);
}

#[test]
fn crops_along_a_run_are_the_simulators_at_those_strokes() {
    let tool = ToolBody::new(Shape::Ball { radius: 3.0 });
    let mut list = Vec::new();
    // A zig-zag of three passes 1.5 mm deep, then a tilted pass across them.
    for k in 0..3 {
        let y = -3.0 + 2.5 * k as f64;
        let (a, b) = if k % 2 == 0 {
            (-12.0, 12.0)
        } else {
            (12.0, -12.0)
        };
        for s in 0..12 {
            let (x0, x1) = (
                a + (b - a) * s as f64 / 12.0,
                a + (b - a) * (s + 1) as f64 / 12.0,
            );
            let mv = list.len() as u32;
            list.push(stroke(
                mv,
                DVec3::new(x0, y, -1.5),
                DVec3::new(x1, y, -1.5),
                DVec3::Z,
            ));
        }
    }
    let tilt = DVec3::new(0.0, 0.3, 1.0).normalize();
    for s in 0..8 {
        let mv = list.len() as u32;
        let x = -8.0 + 2.0 * s as f64;
        list.push(stroke(
            mv,
            DVec3::new(x, -9.0, -1.0),
            DVec3::new(x + 2.0, 9.0, -1.0),
            tilt,
        ));
    }
    let strokes = Strokes {
        moves: list.len(),
        strokes: list.clone(),
        tools: vec![tool],
        skipped: Default::default(),
    };
    let block = || {
        Stock::block(
            DVec3::new(-15.0, -12.0, -6.0),
            DVec3::new(15.0, 12.0, 0.0),
            0.1,
        )
    };
    let picks = [0usize, 5, 13, 14, 30, 36, 43];
    let window = |_: &Stock, i: usize| {
        let c = list[picks[i]].p1.truncate();
        (c - DVec2::splat(4.0), c + DVec2::splat(4.0))
    };
    let mut stock = block();
    let crops = crops_before(&mut stock, &strokes, &picks, window, &|_| {});
    assert_eq!(crops.len(), picks.len());
    let mut sim = Simulator::new(block());
    let mut at = 0;
    for (n, (k, crop)) in picks.iter().zip(&crops).enumerate() {
        while at < *k {
            sim.step(&list[at], &tool);
            at += 1;
        }
        let (lo, hi) = window(&sim.stock, n);
        let want = sim.stock.crop(lo, hi);
        assert_eq!(want.grid, crop.grid);
        let mut worst = 0.0f64;
        for j in 0..want.grid.ny {
            for i in 0..want.grid.nx {
                let (a, b) = (want.intervals(i, j), crop.intervals(i, j));
                assert_eq!(a.len(), b.len(), "stroke {k}, cell ({i}, {j})");
                for (p, q) in a.iter().zip(&b) {
                    worst = worst.max((p[0] - q[0]).abs()).max((p[1] - q[1]).abs());
                }
            }
        }
        assert!(worst < 1e-5, "stroke {k}: {worst} mm");
        assert_crop_of(&sim.stock, crop, lo, hi);
    }
    // The run stopped before the last pick.
    assert!((stock.volume() - sim.stock.volume()).abs() < 1e-6 * stock.volume());
}
