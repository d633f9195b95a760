//! Stock simulation against closed forms: the swept ball of the process-models
//! spec (T15), flat-end slots and pockets, a tilted flat end mill, order
//! independence, collisions, the mesh, blanks and the result against a part.

use millplan_geom::{DVec2, DVec3, TriMesh};
use millplan_models::cutter::Shape;
use millplan_sim::stock::path::{Stroke, Strokes};
use millplan_sim::stock::sim::{per_move, simulate, Simulator};
use millplan_sim::stock::tool::ToolBody;
use millplan_sim::stock::{stock_mesh, Stock};

fn stroke(p0: DVec3, p1: DVec3, axis: DVec3, rapid: bool, line: u32) -> Stroke {
    Stroke {
        mv: line,
        line,
        tool: 0,
        rapid,
        p0,
        p1,
        a0: axis,
        a1: axis,
        minutes: (p1 - p0).length() / 1000.0,
    }
}

/// The largest difference between the tops of two stocks on one grid
/// (infinite where a column is empty in one and not the other).
fn worst_column(a: &Stock, b: &Stock) -> f64 {
    let g = a.grid;
    let mut worst = 0.0f64;
    for j in 0..g.ny {
        for i in 0..g.nx {
            let d = match (a.top(i, j), b.top(i, j)) {
                (Some(x), Some(y)) => (x - y).abs(),
                (None, None) => 0.0,
                _ => f64::INFINITY,
            };
            worst = worst.max(d);
        }
    }
    worst
}

fn run(
    stock: &mut Stock,
    tool: ToolBody,
    strokes: Vec<Stroke>,
) -> (f64, Strokes, Vec<millplan_sim::stock::sim::StrokeCut>) {
    let s = Strokes {
        moves: strokes.len(),
        strokes,
        tools: vec![tool],
        skipped: Default::default(),
    };
    let before = stock.volume();
    let cuts = simulate(stock, &s, &|_| {});
    (before - stock.volume(), s, cuts)
}

/// Spec process-models.md T15: ball R = 8, depth ap = 1, a straight pass of
/// 50 mm with its end caps: V = A_seg·L + π·ap²(3R − ap)/3 = 285.695 mm³.
fn t15(res: f64, split: usize) -> f64 {
    let (r, ap, l) = (8.0, 1.0, 50.0);
    let mut stock = Stock::block(
        DVec3::new(-15.0, -10.0, -5.0),
        DVec3::new(65.0, 10.0, 0.0),
        res,
    );
    let tool = ToolBody::new(Shape::Ball { radius: r });
    let z = -ap;
    let mut strokes = vec![stroke(
        DVec3::new(0.0, 0.0, 20.0),
        DVec3::new(0.0, 0.0, z),
        DVec3::Z,
        false,
        1,
    )];
    for k in 0..split {
        let x0 = l * k as f64 / split as f64;
        let x1 = l * (k + 1) as f64 / split as f64;
        strokes.push(stroke(
            DVec3::new(x0, 0.0, z),
            DVec3::new(x1, 0.0, z),
            DVec3::Z,
            false,
            2 + k as u32,
        ));
    }
    run(&mut stock, tool, strokes).0
}

const T15: f64 = 285.695;

#[test]
fn t15_ball_pass_one_stroke_within_1_percent_at_0_05() {
    let v = t15(0.05, 1);
    assert!(((v - T15) / T15).abs() < 0.01, "{v}");
}

#[test]
fn t15_ball_pass_in_short_strokes_within_1_percent_and_converging() {
    // 1000 strokes of 0.05 mm: the tight loop that takes each as the tool at
    // its end.
    let fine = t15(0.05, 1000);
    assert!(((fine - T15) / T15).abs() < 0.01, "{fine}");
    let errs: Vec<f64> = [0.4, 0.2, 0.1, 0.05]
        .iter()
        .map(|r| ((t15(*r, 1) - T15) / T15).abs())
        .collect();
    assert!(errs[3] < errs[0] && errs[3] < 0.005, "{errs:?}");
}

#[test]
fn flat_slot_is_area_times_depth() {
    // D10 flat end mill, 2 mm deep, 40 mm long: (40·10 + π·5²)·2.
    let exact = (40.0 * 10.0 + std::f64::consts::PI * 25.0) * 2.0;
    for res in [0.1, 0.05] {
        let mut stock = Stock::block(
            DVec3::new(-10.0, -10.0, -5.0),
            DVec3::new(50.0, 10.0, 0.0),
            res,
        );
        let tool = ToolBody::new(Shape::Flat { radius: 5.0 });
        let (v, _, _) = run(
            &mut stock,
            tool,
            vec![
                stroke(
                    DVec3::new(0.0, 0.0, 10.0),
                    DVec3::new(0.0, 0.0, -2.0),
                    DVec3::Z,
                    false,
                    1,
                ),
                stroke(
                    DVec3::new(0.0, 0.0, -2.0),
                    DVec3::new(40.0, 0.0, -2.0),
                    DVec3::Z,
                    false,
                    2,
                ),
            ],
        );
        assert!(
            ((v - exact) / exact).abs() < 2.0 * res / 10.0,
            "res {res}: {v} vs {exact}"
        );
    }
}

#[test]
fn pocket_clearing_the_whole_block_removes_area_times_depth_exactly() {
    // A 40 × 30 block cleared 2 mm deep by passes that overlap its edges.
    let mut stock = Stock::block(DVec3::new(0.0, 0.0, -5.0), DVec3::new(40.0, 30.0, 0.0), 0.1);
    let tool = ToolBody::new(Shape::Flat { radius: 5.0 });
    let mut s = vec![stroke(
        DVec3::new(-6.0, -2.0, 10.0),
        DVec3::new(-6.0, -2.0, -2.0),
        DVec3::Z,
        false,
        1,
    )];
    let mut y = -2.0;
    let mut x = -6.0;
    while y <= 34.0 {
        let nx = if x < 0.0 { 46.0 } else { -6.0 };
        s.push(stroke(
            DVec3::new(x, y, -2.0),
            DVec3::new(nx, y, -2.0),
            DVec3::Z,
            false,
            2,
        ));
        s.push(stroke(
            DVec3::new(nx, y, -2.0),
            DVec3::new(nx, y + 4.0, -2.0),
            DVec3::Z,
            false,
            3,
        ));
        x = nx;
        y += 4.0;
    }
    let (v, _, _) = run(&mut stock, tool, s);
    assert!((v - 40.0 * 30.0 * 2.0).abs() < 1e-6, "{v}");
}

/// Area of the polygon `poly` (x, z) clipped to z ≤ 0.
fn clipped_area(poly: &[DVec2]) -> f64 {
    let mut out: Vec<DVec2> = Vec::new();
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        let (ina, inb) = (a.y <= 0.0, b.y <= 0.0);
        if ina {
            out.push(a);
        }
        if ina != inb {
            let t = a.y / (a.y - b.y);
            out.push(a + (b - a) * t);
        }
    }
    let mut s = 0.0;
    for k in 0..out.len() {
        let (a, b) = (out[k], out[(k + 1) % out.len()]);
        s += a.x * b.y - b.x * a.y;
    }
    s.abs() / 2.0
}

#[test]
fn tilted_flat_end_mill_sweeps_its_projected_section_times_length() {
    // A flat end mill tilted 20° about Y moves along Y right through a block
    // 30 mm long: the removed volume is 30 × the area of the tool's section
    // projected on XZ (a strip of width 2R along the axis) below the top.
    let (r, th, depth) = (5.0, 20f64.to_radians(), 2.0);
    let axis = DVec3::new(th.sin(), 0.0, th.cos());
    let tip = DVec2::new(0.0, -depth);
    let a = DVec2::new(th.sin(), th.cos());
    let b = DVec2::new(th.cos(), -th.sin());
    let h = 100.0;
    let poly = [
        tip - b * r,
        tip + b * r,
        tip + b * r + a * h,
        tip - b * r + a * h,
    ];
    let exact = 30.0 * clipped_area(&poly);
    let mut errs = Vec::new();
    for res in [0.2, 0.1, 0.05] {
        let mut stock = Stock::block(
            DVec3::new(-20.0, 0.0, -10.0),
            DVec3::new(20.0, 30.0, 0.0),
            res,
        );
        let tool = ToolBody::new(Shape::Flat { radius: r });
        let (v, _, _) = run(
            &mut stock,
            tool,
            vec![stroke(
                DVec3::new(0.0, -12.0, -depth),
                DVec3::new(0.0, 42.0, -depth),
                axis,
                false,
                1,
            )],
        );
        errs.push(((v - exact) / exact).abs());
    }
    assert!(errs[2] < 0.01, "{errs:?} of {exact}");
    assert!(errs[2] <= errs[0], "{errs:?}");
}

#[test]
fn disjoint_cuts_give_the_same_stock_in_either_order() {
    let tool = ToolBody::new(Shape::Ball { radius: 3.0 });
    let a = vec![
        stroke(
            DVec3::new(0.0, 0.0, 5.0),
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::Z,
            false,
            1,
        ),
        stroke(
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(10.0, 3.0, -1.5),
            DVec3::Z,
            false,
            2,
        ),
    ];
    let b = vec![
        stroke(
            DVec3::new(0.0, 15.0, 5.0),
            DVec3::new(0.0, 15.0, -2.0),
            DVec3::Z,
            false,
            3,
        ),
        stroke(
            DVec3::new(0.0, 15.0, -2.0),
            DVec3::new(12.0, 12.0, -0.5),
            DVec3::Z,
            false,
            4,
        ),
    ];
    let block = || {
        Stock::block(
            DVec3::new(-5.0, -5.0, -5.0),
            DVec3::new(20.0, 20.0, 0.0),
            0.1,
        )
    };
    let (mut s1, mut s2) = (block(), block());
    let (v1, st1, c1) = run(&mut s1, tool, [a.clone(), b.clone()].concat());
    let (v2, st2, c2) = run(&mut s2, tool, [b, a].concat());
    assert!(v1 > 10.0);
    assert!((v1 - v2).abs() < 1e-9 * v1, "{v1} {v2}");
    let m1 = per_move(&st1, &c1);
    let m2 = per_move(&st2, &c2);
    for m in &m1 {
        let o = m2.iter().find(|o| o.index == m.index).expect("same moves");
        assert!((m.removed_mm3 - o.removed_mm3).abs() < 1e-9 * (1.0 + m.removed_mm3));
    }
    for j in 0..s1.grid.ny {
        for i in 0..s1.grid.nx {
            assert_eq!(s1.top(i, j), s2.top(i, j));
        }
    }
}

#[test]
fn the_parallel_run_and_the_stroke_by_stroke_simulator_agree() {
    let tool = ToolBody::new(Shape::Bull {
        radius: 4.0,
        corner: 1.0,
    });
    let mut strokes = vec![stroke(
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::new(0.0, 0.0, -1.0),
        DVec3::Z,
        false,
        1,
    )];
    for k in 0..40 {
        let t0 = k as f64 * 0.3;
        let t1 = t0 + 0.3;
        strokes.push(stroke(
            DVec3::new(t0 * 3.0, 10.0 * t0.sin().abs(), -1.0 - 0.1 * t0),
            DVec3::new(t1 * 3.0, 10.0 * t1.sin().abs(), -1.0 - 0.1 * t1),
            DVec3::Z,
            false,
            2 + k,
        ));
    }
    let block = || {
        Stock::block(
            DVec3::new(-10.0, -10.0, -6.0),
            DVec3::new(45.0, 20.0, 0.0),
            0.1,
        )
    };
    let mut par = block();
    let (_, st, cuts) = run(&mut par, tool, strokes.clone());
    let mut sim = Simulator::new(block());
    for (s, c) in strokes.iter().zip(&cuts) {
        let one = sim.step(s, &tool);
        assert!(
            (one.removed - c.removed).abs() < 1e-6 * (1.0 + c.removed),
            "{one:?} {c:?}"
        );
    }
    assert!((sim.stock.volume() - par.volume()).abs() < 1e-6);
    assert_eq!(st.strokes.len(), cuts.len());
}

/// A ball on short strokes (two placements each) climbing, descending and
/// turning: leaving to each placement the cells the next one of its stroke
/// is sure to cut at least as low gives the stock of placing the ball four
/// times as densely, one placement per stroke (which leaves nothing to
/// another), within the placements' own cusp: δ²/8R = 0.0005 mm at
/// δ = √(0.08·R·res), doubled on climbs as steep as 60°, with as much again
/// for the reference's own cusp.
#[test]
fn leaving_cells_to_the_next_ball_placement_changes_no_column() {
    let tool = ToolBody::new(Shape::Ball { radius: 3.0 });
    let mut strokes = Vec::new();
    let mut prev = DVec3::new(-6.0, -2.0, 4.0);
    for k in 0..400 {
        let t = k as f64 * 0.05;
        // A meander: along x, turning back every 100 strokes, the height
        // waving by ±1.5 mm (climbs steeper than 45°, descents, flats).
        let leg = k / 100;
        let s = (k % 100) as f64 * 0.12;
        let x = if leg % 2 == 0 { -6.0 + s } else { 6.0 - s };
        let p = DVec3::new(x, -2.0 + leg as f64 * 1.3, -0.5 + 1.5 * (3.0 * t).sin());
        strokes.push(stroke(prev, p, DVec3::Z, false, 2 + k as u32));
        prev = p;
    }
    let block = || {
        Stock::block(
            DVec3::new(-12.0, -8.0, -6.0),
            DVec3::new(12.0, 10.0, 0.0),
            0.05,
        )
    };
    let mut par = block();
    let (_, _, cuts) = run(&mut par, tool, strokes.clone());
    let mut dense = Simulator::new(block());
    for s in &strokes {
        for q in 0..4 {
            let (t0, t1) = (q as f64 / 4.0, (q + 1) as f64 / 4.0);
            dense.step(
                &Stroke {
                    p0: s.p0.lerp(s.p1, t0),
                    p1: s.p0.lerp(s.p1, t1),
                    ..*s
                },
                &tool,
            );
        }
    }
    let worst = worst_column(&par, &dense.stock);
    let delta = (0.08f64 * 3.0 * 0.05).sqrt();
    let cusp = delta * delta / (8.0 * 3.0);
    assert!(worst < 4.0 * cusp, "a column differs by {worst} mm");
    let removed: f64 = cuts.iter().map(|c| c.removed).sum();
    let reference = block().volume() - dense.stock.volume();
    assert!(removed > 100.0, "the path cuts: {removed} mm³");
    assert!(
        (removed - reference).abs() < 1e-4 * reference,
        "{removed} vs {reference}"
    );
}

#[test]
fn a_turning_axis_is_placed_as_densely_as_the_material_needs() {
    let mut tool = ToolBody::new(Shape::Flat { radius: 3.0 });
    tool.flute = 40.0;
    let tilt = |deg: f64| {
        let t = deg.to_radians();
        DVec3::new(t.sin(), 0.0, t.cos())
    };
    let (p0, p1) = (DVec3::new(-0.1, 0.0, -1.0), DVec3::new(0.1, 0.0, -1.0));
    let block = || {
        Stock::block(
            DVec3::new(-12.0, -6.0, -6.0),
            DVec3::new(12.0, 6.0, 0.0),
            0.05,
        )
    };
    let mut one = Stroke {
        a0: tilt(-15.0),
        a1: tilt(15.0),
        ..stroke(p0, p1, DVec3::Z, false, 1)
    };
    one.mv = 0;
    let mut coarse = block();
    let (_, _, cuts) = run(&mut coarse, tool, vec![one]);
    let mut fine = Simulator::new(block());
    let n = 1000;
    for k in 0..n {
        let (t0, t1) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
        let s = Stroke {
            p0: p0.lerp(p1, t0),
            p1: p0.lerp(p1, t1),
            a0: one.axis_at(t0),
            a1: one.axis_at(t1),
            ..one
        };
        fine.step(&s, &tool);
    }
    let worst = worst_column(&coarse, &fine.stock);
    let removed = cuts[0].removed;
    let fine_removed = block().volume() - fine.stock.volume();
    assert!(worst < 1e-4, "a column differs by {worst} mm");
    assert!(
        (removed - fine_removed).abs() < 1e-5 * fine_removed,
        "{removed} vs {fine_removed} mm³"
    );
}

#[test]
fn a_rapid_through_stock_and_a_shank_in_the_material_are_reported_on_their_lines() {
    let mut tool = ToolBody::new(Shape::Flat { radius: 3.0 });
    tool.flute = 5.0;
    let mut stock = Stock::block(
        DVec3::new(-10.0, -10.0, -20.0),
        DVec3::new(40.0, 10.0, 0.0),
        0.1,
    );
    let (_, st, cuts) = run(
        &mut stock,
        tool,
        vec![
            stroke(
                DVec3::new(-8.0, 0.0, 5.0),
                DVec3::new(0.0, 0.0, 5.0),
                DVec3::Z,
                true,
                10,
            ),
            stroke(
                DVec3::new(0.0, 0.0, 5.0),
                DVec3::new(0.0, 0.0, -2.0),
                DVec3::Z,
                false,
                11,
            ),
            stroke(
                DVec3::new(0.0, 0.0, -2.0),
                DVec3::new(10.0, 0.0, -2.0),
                DVec3::Z,
                false,
                12,
            ),
            // Rapid sideways at cutting depth: a crash.
            stroke(
                DVec3::new(10.0, 0.0, -2.0),
                DVec3::new(20.0, 0.0, -2.0),
                DVec3::Z,
                true,
                13,
            ),
            // 8 mm deep with 5 mm of flutes: the shank rubs 3 mm of wall.
            stroke(
                DVec3::new(20.0, 0.0, -2.0),
                DVec3::new(20.0, 0.0, -8.0),
                DVec3::Z,
                false,
                14,
            ),
            stroke(
                DVec3::new(20.0, 0.0, -8.0),
                DVec3::new(30.0, 0.0, -8.0),
                DVec3::Z,
                false,
                15,
            ),
        ],
    );
    let moves = per_move(&st, &cuts);
    let m = |line: u32| {
        moves
            .iter()
            .find(|m| m.line == line)
            .copied()
            .expect("move")
    };
    assert_eq!(m(10).removed_mm3, 0.0);
    assert!(m(13).rapid && m(13).removed_mm3 > 10.0 && (m(13).depth - 2.0).abs() < 0.01);
    assert!(m(12).holder_depth == 0.0);
    assert!((m(15).holder_depth - 3.0).abs() < 0.01, "{:?}", m(15));
    assert!(
        (m(12).ap - 2.0).abs() < 0.01 && (m(12).ae - 6.0).abs() < 0.2,
        "{:?}",
        m(12)
    );
    assert!(!m(12).air);
}

fn edge_counts(m: &TriMesh) -> std::collections::HashMap<(u32, u32), i32> {
    let mut e = std::collections::HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            // +1 one way, −1 the other: a closed, consistently oriented
            // surface sums to zero on every edge.
            *e.entry((a.min(b), a.max(b))).or_insert(0) += if a < b { 1 } else { -1 };
        }
    }
    e
}

fn signed_volume(m: &TriMesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|v| m.vertices[v as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

#[test]
fn the_stock_mesh_is_closed_outward_and_holds_the_stock_volume() {
    let mut stock = Stock::block(DVec3::new(0.0, 0.0, -3.0), DVec3::new(6.0, 5.0, 0.0), 0.25);
    let tool = ToolBody::new(Shape::Ball { radius: 1.5 });
    // A groove and, with a tilted tool, an undercut.
    run(
        &mut stock,
        tool,
        vec![
            stroke(
                DVec3::new(1.0, 1.0, 2.0),
                DVec3::new(1.0, 1.0, -1.0),
                DVec3::Z,
                false,
                1,
            ),
            stroke(
                DVec3::new(1.0, 1.0, -1.0),
                DVec3::new(5.0, 3.0, -0.5),
                DVec3::Z,
                false,
                2,
            ),
        ],
    );
    // Leaning away from the block, the ball reaches under its edge.
    let tilt = DVec3::new(0.0, -0.6, 0.8);
    run(
        &mut stock,
        tool,
        vec![stroke(
            DVec3::new(3.0, 0.4, -3.2),
            DVec3::new(5.5, 0.4, -3.2),
            tilt,
            false,
            3,
        )],
    );
    assert!(stock.has_gaps(), "the tilted pass leaves an undercut");
    let m = stock_mesh(&stock);
    assert!(
        edge_counts(&m).values().all(|c| *c == 0),
        "closed and consistently oriented"
    );
    let v = signed_volume(&m);
    assert!(
        (v - stock.volume()).abs() < 1e-3 * stock.volume(),
        "{v} vs {}",
        stock.volume()
    );
}

fn cube_mesh(min: DVec3, max: DVec3) -> TriMesh {
    let v: Vec<DVec3> = (0..8)
        .map(|k| {
            DVec3::new(
                if k & 1 == 0 { min.x } else { max.x },
                if k & 2 == 0 { min.y } else { max.y },
                if k & 4 == 0 { min.z } else { max.z },
            )
        })
        .collect();
    let q = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut t = Vec::new();
    for f in q {
        t.push([f[0], f[1], f[2]]);
        t.push([f[0], f[2], f[3]]);
    }
    TriMesh {
        vertices: v,
        triangles: t,
    }
}

#[test]
fn a_closed_blank_fills_its_columns_by_winding() {
    // A box with a box-shaped cavity: 10·10·10 − 4·4·4.
    let mut outer = cube_mesh(DVec3::ZERO, DVec3::splat(10.0));
    let inner = cube_mesh(DVec3::splat(3.0), DVec3::splat(7.0));
    let base = outer.vertices.len() as u32;
    outer.vertices.extend(inner.vertices);
    outer.triangles.extend(
        inner
            .triangles
            .iter()
            .map(|t| [t[0] + base, t[2] + base, t[1] + base]),
    );
    let s = Stock::from_solid(&outer, 0.1);
    assert!(
        (s.volume() - (1000.0 - 64.0)).abs() < 1e-6,
        "{}",
        s.volume()
    );
    assert!(s.has_gaps());
    assert!(s.contains(DVec3::new(5.0, 5.0, 2.0)) && !s.contains(DVec3::new(5.0, 5.0, 5.0)));
}

#[test]
fn the_part_with_an_allowance_leaves_that_allowance_on_its_faces() {
    use millplan_sim::stock::remaining::remaining;
    use millplan_sim::stock::spec::offset_stock;
    // A gentle dome as a height-field mesh.
    let n = 40;
    let mut v = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 * 0.5, j as f64 * 0.5);
            v.push(DVec3::new(
                x,
                y,
                2.0 - 0.01 * ((x - 10.0).powi(2) + (y - 10.0).powi(2)),
            ));
        }
    }
    let mut t = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = (j * (n + 1) + i) as u32;
            let (b, c, d) = (a + 1, a + n as u32 + 2, a + n as u32 + 1);
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
    }
    let part = TriMesh {
        vertices: v,
        triangles: t,
    };
    let stock = offset_stock(&part, 0.5, 0.05);
    let r = remaining(&stock, &part, 5.0, 0.01);
    assert!(r.facets > 3000);
    assert!(
        (r.mean - 0.5).abs() < 0.01 && r.min > 0.45 && r.max < 0.55,
        "{r:?}"
    );
    assert_eq!(r.gouged, 0);
}

#[test]
fn engagement_of_a_slot_is_the_front_half() {
    use millplan_sim::stock::engage::engagement;
    // A flat end mill half-way along a slot: its edge is in material over the
    // front half (φ from 0 to π) on every slice below the top.
    let tool = ToolBody::new(Shape::Flat { radius: 4.0 });
    let mut stock = Stock::block(
        DVec3::new(-10.0, -10.0, -5.0),
        DVec3::new(30.0, 10.0, 0.0),
        0.02,
    );
    run(
        &mut stock,
        tool,
        vec![
            stroke(
                DVec3::new(0.0, 0.0, 5.0),
                DVec3::new(0.0, 0.0, -2.0),
                DVec3::Z,
                false,
                1,
            ),
            stroke(
                DVec3::new(0.0, 0.0, -2.0),
                DVec3::new(10.0, 0.0, -2.0),
                DVec3::Z,
                false,
                2,
            ),
        ],
    );
    let e = engagement(
        &stock,
        &tool,
        DVec3::new(10.1, 0.0, -2.0),
        DVec3::Z,
        DVec3::X,
        0.25,
        1f64.to_radians(),
    );
    assert_eq!(e.slices.len(), 8, "2 mm deep in slices of 0.25");
    for s in &e.slices {
        assert_eq!(s.arcs.len(), 1, "{s:?}");
        let [a, b] = s.arcs[0];
        assert!(
            a.to_degrees() < 8.0 && (b.to_degrees() - 180.0).abs() < 8.0,
            "{s:?}"
        );
    }
    assert!((e.ap() - 2.0).abs() < 1e-9);
    assert!(
        e.in_material(0, std::f64::consts::FRAC_PI_2)
            && !e.in_material(0, 1.5 * std::f64::consts::PI)
    );
}

/// A tiny deterministic generator for the brute-force comparisons.
struct Lcg(u64);
impl Lcg {
    fn f(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn exact_sweeps_match_the_tool_placed_densely_along_the_stroke() {
    use millplan_sim::stock::tool::{Pose, VerticalSweep};
    let shapes = [
        Shape::Flat { radius: 3.0 },
        Shape::Ball { radius: 3.0 },
        Shape::Bull {
            radius: 3.0,
            corner: 1.0,
        },
        Shape::Cone {
            radius: 3.0,
            alpha: 30f64.to_radians(),
        },
    ];
    let mut rng = Lcg(7);
    for shape in shapes {
        let tool = ToolBody::new(shape);
        for _ in 0..30 {
            let p0 = DVec3::new(rng.f() * 4.0, rng.f() * 4.0, rng.f() * 4.0);
            let p1 = DVec3::new(rng.f() * 4.0, rng.f() * 4.0, rng.f() * 4.0 - 2.0);
            let sw = VerticalSweep::new(tool, p0, p1);
            for _ in 0..20 {
                let c = DVec2::new(rng.f() * 10.0 - 3.0, rng.f() * 10.0 - 3.0);
                let exact = sw.column(c).cut;
                // The tool standing at 4001 places: its lowest point over c.
                let mut brute = f64::INFINITY;
                for k in 0..=4000 {
                    let t = k as f64 / 4000.0;
                    let pose = Pose {
                        tool,
                        tip: p0.lerp(p1, t),
                        axis: DVec3::Z,
                    };
                    if let (Some([lo, _]), _) = pose.column(c) {
                        brute = brute.min(lo);
                    }
                }
                if brute.is_finite() || exact.is_finite() {
                    assert!(
                        (exact - brute).abs() < 2e-3 && exact <= brute + 1e-9,
                        "{shape:?} {p0} {p1} {c}: {exact} vs {brute}"
                    );
                }
            }
        }
    }
}

#[test]
fn a_tilted_pose_meets_a_line_where_the_cutter_profile_says() {
    use millplan_sim::stock::tool::Pose;
    // Tilt a tool, take points on its surface from the profile, and check
    // that the vertical line through each meets the body there.
    let shapes = [
        Shape::Flat { radius: 3.0 },
        Shape::Ball { radius: 3.0 },
        Shape::Bull {
            radius: 3.0,
            corner: 1.0,
        },
        Shape::Cone {
            radius: 3.0,
            alpha: 30f64.to_radians(),
        },
    ];
    let mut rng = Lcg(11);
    for shape in shapes {
        let tool = ToolBody::new(shape);
        for _ in 0..200 {
            let axis = DVec3::new(rng.f() - 0.5, rng.f() - 0.5, 1.0).normalize();
            let tip = DVec3::new(rng.f(), rng.f(), rng.f());
            let pose = Pose { tool, tip, axis };
            let c = DVec2::new(tip.x + rng.f() * 8.0 - 4.0, tip.y + rng.f() * 8.0 - 4.0);
            let (cut, _) = pose.column(c);
            // Brute force: sample the line densely against the profile.
            let inside = |z: f64| {
                let w = DVec3::new(c.x, c.y, z) - tip;
                let h = w.dot(axis);
                let r = (w - axis * h).length();
                h >= 0.0 && h <= tool.flute && r <= tool.cutter_radius_at(h)
            };
            let zs: Vec<f64> = (0..20000)
                .map(|k| tip.z - 5.0 + k as f64 * 0.002)
                .filter(|z| inside(*z))
                .collect();
            match (cut, zs.first()) {
                (Some([lo, _]), Some(first)) => {
                    assert!((lo - first).abs() < 3e-3, "{shape:?}: {lo} vs {first}")
                }
                (None, None) => {}
                (a, b) => panic!("{shape:?} {axis} {c}: {a:?} vs {b:?}"),
            }
        }
    }
}

#[test]
fn a_tilted_ball_in_closed_form_removes_what_the_general_parts_do() {
    // The same leaning, rolling ball strokes with the shank as wide as the
    // ball (the capsule in closed form) and a hair wider (the general parts).
    let mut rng = Lcg(5);
    let mut strokes = Vec::new();
    let mut p = DVec3::new(0.0, 0.0, -1.0);
    let mut a = DVec3::Z;
    for k in 0..120 {
        let q = p + DVec3::new(0.3, 0.05 * (rng.f() - 0.5), 0.1 * (rng.f() - 0.5));
        let b =
            (DVec3::Z + DVec3::new(-0.3 + 0.1 * rng.f(), 0.4 * (rng.f() - 0.5), 0.0)).normalize();
        let mut s = stroke(p, q, a, false, k);
        s.a1 = b;
        strokes.push(s);
        p = q;
        a = b;
    }
    let block = || {
        Stock::block(
            DVec3::new(-6.0, -8.0, -6.0),
            DVec3::new(42.0, 8.0, 0.0),
            0.1,
        )
    };
    let mut tool = ToolBody::new(Shape::Ball { radius: 3.0 });
    let (mut s1, mut s2) = (block(), block());
    let (v1, _, _) = run(&mut s1, tool, strokes.clone());
    tool.shank_r = 3.0 + 1e-6;
    let (v2, _, _) = run(&mut s2, tool, strokes);
    assert!(v1 > 100.0);
    assert!((v1 - v2).abs() < 1e-6 * v1, "{v1} vs {v2}");
}

/// A small deterministic generator for the brute-force checks below.
fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*seed >> 11) as f64 / (1u64 << 53) as f64
}

#[test]
fn fast_arctangent_is_within_its_stated_error() {
    use millplan_sim::stock::{fast_atan2, ATAN_ERROR};
    let mut seed = 7;
    let mut worst = 0.0f64;
    for k in 0..200_000 {
        let (x, y) = if k < 8 {
            let a = k as f64 * std::f64::consts::FRAC_PI_4;
            (a.cos(), a.sin())
        } else {
            (2.0 * lcg(&mut seed) - 1.0, 2.0 * lcg(&mut seed) - 1.0)
        };
        let e = (fast_atan2(y, x) - y.atan2(x)).abs();
        // The branch cut: π and −π are the same angle.
        let e = e.min((e - std::f64::consts::TAU).abs());
        worst = worst.max(e);
    }
    assert!(worst < ATAN_ERROR / 4.0, "worst {worst} rad");
}

/// Every point within reach, by brute force: the top of the cell holding it
/// never exceeds what `sector_tops` says for its distance and angle (the
/// bound the force model skips points by), on a stock with cuts of several
/// heights, from centres anywhere, in any tool frame.
#[test]
fn sector_tops_bound_every_point_within_reach() {
    const N: usize = 64;
    let res = 0.5;
    let mut stock = Stock::block(DVec3::new(0.0, 0.0, 0.0), DVec3::new(30.0, 20.0, 10.0), res);
    let ball = ToolBody::new(Shape::Ball { radius: 3.0 });
    let mut sim = Simulator::new(stock.clone());
    for (k, z) in [7.0, 8.5, 6.0].into_iter().enumerate() {
        let y = 4.0 + 6.0 * k as f64;
        let s = stroke(
            DVec3::new(-5.0, y, z),
            DVec3::new(35.0, y + 3.0, z),
            DVec3::Z,
            false,
            1,
        );
        sim.step(&s, &ball);
    }
    stock = sim.stock;
    let g = stock.grid;
    let mut seed = 42;
    let mut out = millplan_sim::stock::SectorTops::<N>::default();
    let mut cleared = 0usize;
    for _ in 0..200 {
        let c = DVec2::new(34.0 * lcg(&mut seed) - 2.0, 24.0 * lcg(&mut seed) - 2.0);
        let a = std::f64::consts::TAU * lcg(&mut seed);
        let (ux, uy) = (DVec2::new(a.cos(), a.sin()), DVec2::new(-a.sin(), a.cos()));
        let radius = 1.0 + 15.0 * lcg(&mut seed);
        stock.sector_tops(c, radius, (ux, uy), &mut out);
        let last = out.bins.len() - 1;
        for _ in 0..2000 {
            let r = radius * lcg(&mut seed);
            let th = std::f64::consts::TAU * lcg(&mut seed);
            let p = c + ux * (r * th.sin()) + uy * (r * th.cos());
            let Some((i, j)) = g.cell_of(p.x, p.y) else {
                continue;
            };
            let Some(top) = stock.top(i, j) else {
                continue;
            };
            let slack = out.slack;
            let b0 = (((r / res - slack).max(0.0)) as usize).min(last);
            let b1 = (((r / res + slack).max(0.0)) as usize).min(last);
            let s = ((th / std::f64::consts::TAU * N as f64) as usize).min(N - 1);
            let bound = out.bins[b0..=b1]
                .iter()
                .map(|b| b[s])
                .fold(f32::MIN, f32::max);
            assert!(
                top as f32 <= bound,
                "centre {c}, r {r}, θ {th}: cell ({i}, {j}) top {top} above the bound {bound}"
            );
        }
        cleared += out
            .bins
            .iter()
            .flatten()
            .filter(|t| **t == f32::NEG_INFINITY)
            .count();
    }
    assert!(
        cleared > 0,
        "no sector was empty: the test would not see a loose bound"
    );
}
