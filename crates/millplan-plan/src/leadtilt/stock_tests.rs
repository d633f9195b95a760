//! The stock's engagement against the planar one (process-models §1.4a and
//! §1.4b) and the choice made on it (§2.4).

use super::*;
use crate::force::LIFT_SHARE;
use millplan_models::force::engage::{Engagement, FnEngagement};
use millplan_models::force::Cut;
use millplan_nc::ir::{Cutter, Dialect, Move, Operation, Tool as NcTool};
use millplan_sim::stock::path::{strokes, PathOptions, Strokes};
use millplan_sim::stock::tool::ToolBody;
use millplan_sim::stock::Stock;

const R: f64 = 5.0;

/// A flat 200 × 200 mm plate, top at z = 0: the finished plane.
fn plate() -> TriMesh {
    let v = [
        DVec3::new(-100.0, -100.0, 0.0),
        DVec3::new(100.0, -100.0, 0.0),
        DVec3::new(100.0, 100.0, 0.0),
        DVec3::new(-100.0, 100.0, 0.0),
    ];
    TriMesh::from_soup(&[[v[0], v[1], v[2]], [v[0], v[2], v[3]]]).0
}

fn ball_op() -> Operation {
    Operation {
        start: DVec3::new(-30.0, 0.0, 20.0),
        tool: Some(NcTool {
            number: Some(1),
            name: None,
            cutter: Some(Cutter::ball(2.0 * R)),
            line: 1,
        }),
        ..Operation::default()
    }
}

/// One pass along +X at `y`, tip at `z`, in 1 mm moves from x = −25 to 25,
/// entered from above.
fn pass(op: &mut Operation, y: f64, z: f64) {
    op.moves.push(Move::rapid(DVec3::new(-25.0, y, 20.0)));
    op.moves.push(Move::linear(DVec3::new(-25.0, y, z), 500.0));
    for k in 1..=50 {
        op.moves
            .push(Move::linear(DVec3::new(-25.0 + k as f64, y, z), 1000.0));
    }
    op.moves.push(Move::rapid(DVec3::new(25.0, y, 20.0)));
}

/// The planar tests' tool and cut at `ap`, `ae`, tilt before lead, with
/// no holder.
fn params(ap: f64, ae: f64) -> Params {
    Params {
        variant: Variant::TiltThenLead,
        ap,
        ae,
        holder_radius: 0.0,
        holder_length: 0.0,
        ..super::tests::params()
    }
}

fn strokes_of(p: &Program, res: f64) -> Strokes {
    strokes(
        p,
        |op: &Operation| {
            op.tool
                .as_ref()
                .and_then(|t| t.cutter)
                .and_then(|c| millplan_sim::shape_of(&c))
                .map(ToolBody::new)
        },
        &PathOptions {
            chord: res / 4.0,
            rapid_rate: 10_000.0,
        },
    )
}

/// What `choose_with` builds before the search: the located points and the
/// samples of every operation.
fn sampled(
    p: &Program,
    stock: Stock,
    pr: &Params,
    samples: usize,
) -> (Vec<Vec<Point>>, Vec<Vec<stock::Sample>>) {
    let mesh = plate();
    let bvh = Bvh::build(&mesh);
    let pts: Vec<Vec<Point>> = p
        .operations
        .iter()
        .map(|op| locate(op, R, &mesh, &bvh))
        .collect();
    let st = strokes_of(p, stock.grid.res);
    let n = p.operations.len();
    let s = stock::sample(
        p,
        &pts,
        &vec![R; n],
        &vec![pr.reach.max(2.0 * R); n],
        45.0,
        StockInput {
            stock,
            strokes: &st,
            samples,
            max_bytes: MAX_CROP_BYTES,
        },
        &|_, _| {},
    );
    (pts, s)
}

fn model(pr: &Params) -> (ForceModel, Tool) {
    let tool = Tool {
        shape: millplan_models::cutter::Shape::Ball { radius: R },
        flutes: pr.flutes,
        helix: pr.helix,
        flute_length: pr.reach.max(2.0 * R),
    };
    let m = ForceModel::new(tool, pr.law, Grid::default()).expect("model");
    (m, tool)
}

/// process-models §1.4a against §1.4b: a block whose top is ap above the
/// finished plane, cut by ten one-way passes ae apart, then one more pass:
/// the stock that pass meets is the planar raster's (material up to ap, the
/// scallop of the pass before on the −c side), so the largest F_xy,max over
/// its samples is the planar model's as the stock's engagement sees it: an
/// edge point counts as material a fifth of a dexel below a column's top
/// (`LIFT_SHARE`, so that the tool does not find its own cut's slope), and
/// at ae = 0.5 mm the scallop is only 0.006 mm tall, so that lift takes
/// the sliver of material over the finished plane away. Against the planar
/// raster seen with the same lift the sampled maximum agrees within 1 % of
/// the range the planar model spans when the wall of the pass before moves
/// half a 0.025 mm dexel either way (the columns put it no closer; the
/// force integrals find each flute's run ends on the edge they are given,
/// so that half dexel shows); against the raster itself it is never higher, and
/// within 10 %.
///
/// One convention (process-models §0): the force model's R_wt = Rx(T)·
/// Ry(L) is variant 2 (`TiltThenLead`), so the planar model at (L, T) is
/// the stock at (L, T).
#[test]
fn the_stocks_objective_on_a_planar_raster_is_the_planar_ones() {
    let (ap, ae) = (0.5, 0.5);
    let mut first = ball_op();
    for k in (1..=10).rev() {
        pass(&mut first, -ae * k as f64, 0.0);
    }
    let mut last = ball_op();
    pass(&mut last, 0.0, 0.0);
    let mut p = Program::new(Dialect::Fanuc);
    p.operations.push(first);
    p.operations.push(last);
    let res = 0.025;
    let stock = Stock::block(
        DVec3::new(-20.0, -6.0, -5.0),
        DVec3::new(20.0, 6.0, ap),
        res,
    );
    let pr = params(ap, ae);
    let (pts, samples) = sampled(&p, stock, &pr, 48);
    assert!(samples[1].len() >= 30, "{} samples", samples[1].len());
    let (m, tool) = model(&pr);
    for (l, t) in [
        (5.0, 0.0),
        (10.0, 0.0),
        (20.0, 0.0),
        (15.0, 10.0),
        (15.0, -10.0),
        (25.0, 20.0),
    ] {
        let s = stock::judge(&m, &samples[1], &pts[1], R, 30.0, &pr, l, t);
        let (lr, tr) = (l.to_radians(), t.to_radians());
        let cut = Cut {
            fz: pr.fz,
            rpm: pr.rpm,
            lead: lr,
            tilt: tr,
        };
        // The work frame's up in the tool frame: row 3 of R_wt.
        let up = [-tr.cos() * lr.sin(), tr.sin(), tr.cos() * lr.cos()];
        let lift = LIFT_SHARE * res;
        // The planar raster at a stepover `w`, as is and seen with the lift.
        let planar_at = |w: f64| {
            let e = PlanarRaster::new(&tool, ap, Some(w), lr, tr).expect("raster");
            let (z_lo, z_hi) = e.z_range(&tool);
            let seen = FnEngagement {
                z_lo,
                z_hi,
                f: |q: [f64; 3]| e.contains([0, 1, 2].map(|k| q[k] + lift * up[k])),
            };
            (
                m.evaluate(&cut, &e).summary().fxy_max,
                m.evaluate(&cut, &seen).summary().fxy_max,
            )
        };
        let (planar, lifted) = planar_at(ae);
        // The stock's wall stands where its columns put it, up to half a
        // dexel either way of the pass before: the stock's answer lies
        // between the lifted planar ones of those two walls, within 1 %.
        let (_, near) = planar_at(ae - res / 2.0);
        let (_, far) = planar_at(ae + res / 2.0);
        let (lo, hi) = (near.min(far).min(lifted), near.max(far).max(lifted));
        assert_eq!(s.tip, 0, "lead {l}: the tip never cuts (§1.4c)");
        assert!(
            s.fxy >= 0.99 * lo && s.fxy <= 1.01 * hi,
            "lead {l}, tilt {t}: stock {:.2} N, planar with the lift {lifted:.2} N \
             ({lo:.2}..{hi:.2} N with the wall half a dexel either way)",
            s.fxy
        );
        assert!(
            s.fxy <= planar * (1.0 + 1e-9) && s.fxy >= 0.9 * planar,
            "lead {l}, tilt {t}: stock {:.2} N, planar {planar:.2} N",
            s.fxy
        );
    }
    // The vertical ball's tip cuts on the stock too (lead 0, tilt 0: R(1 −
    // cos 0) = 0 < ap), found from the engagement alone.
    let s = stock::judge(&m, &samples[1], &pts[1], R, 30.0, &pr, 0.0, 0.0);
    assert!(s.tip > 0, "{s:?}");
}

/// A slot 2 mm deep (full immersion), far from the planar ap = ae = 0.5 mm
/// the planar choice assumes: the choice on the stock differs from the
/// planar one, and no node of the 5° grid that the constraints let through
/// has a lower sampled F_xy,max than the answer (§2.4: the descent starts
/// from the best node and only improves).
#[test]
fn a_deep_slot_chooses_otherwise_than_the_planar_pass() {
    let mut op = ball_op();
    pass(&mut op, 0.0, -2.0);
    let mut p = Program::new(Dialect::Fanuc);
    p.operations.push(op);
    // The part's floor under the slot's bottom.
    let mesh = {
        let v = [
            DVec3::new(-100.0, -100.0, -2.0),
            DVec3::new(100.0, -100.0, -2.0),
            DVec3::new(100.0, 100.0, -2.0),
            DVec3::new(-100.0, 100.0, -2.0),
        ];
        TriMesh::from_soup(&[[v[0], v[1], v[2]], [v[0], v[2], v[3]]]).0
    };
    let block = || {
        Stock::block(
            DVec3::new(-20.0, -10.0, -6.0),
            DVec3::new(20.0, 10.0, 0.0),
            0.1,
        )
    };
    let pr = params(0.5, 0.5);
    let m = Machine::default();
    let planar = choose(&p, &mesh, &m, &pr, &|_, _| {}).expect("planar");
    let st = strokes_of(&p, 0.1);
    let on_stock = choose_with(
        &p,
        &mesh,
        &m,
        &pr,
        Some(StockInput {
            stock: block(),
            strokes: &st,
            samples: 32,
            max_bytes: MAX_CROP_BYTES,
        }),
        &|_, _, _| {},
    )
    .expect("stock");
    let (a, b) = (&planar.chosen[0], &on_stock.chosen[0]);
    assert_eq!(a.engagement, EngagementSource::Planar);
    assert_eq!(b.engagement, EngagementSource::Stock);
    assert!(b.samples > 0 && b.samples <= 32, "{b:?}");
    assert!(b.sample_bytes > 0);
    assert!(
        (a.lead - b.lead).abs().max((a.tilt - b.tilt).abs()) > 2.0,
        "planar ({}, {}), stock ({}, {})",
        a.lead,
        a.tilt,
        b.lead,
        b.tilt
    );
    // Brute force over the grid on the same samples.
    let mesh_bvh = Bvh::build(&mesh);
    let pts = locate(&p.operations[0], R, &mesh, &mesh_bvh);
    let cone = 45.0;
    let samples = stock::sample(
        &p,
        std::slice::from_ref(&pts),
        &[R],
        &[30.0],
        cone,
        StockInput {
            stock: block(),
            strokes: &st,
            samples: 32,
            max_bytes: MAX_CROP_BYTES,
        },
        &|_, _| {},
    );
    let (model, _) = model(&pr);
    let mut best = f64::INFINITY;
    let mut l = 0.0;
    while l <= 30.0 {
        let mut t = -30.0;
        while t <= 30.0 {
            let j = stock::judge(&model, &samples[0], &pts, R, 30.0, &pr, l, t);
            if j.tip == 0 {
                best = best.min(j.fxy);
            }
            t += 5.0;
        }
        l += 5.0;
    }
    assert!(best.is_finite());
    assert!(
        b.objective_after <= best + 1e-9,
        "chosen {} N, best grid node {best} N",
        b.objective_after
    );
    let at = stock::judge(&model, &samples[0], &pts, R, 30.0, &pr, b.lead, b.tilt);
    assert!((at.fxy - b.objective_after).abs() < 1e-9 * at.fxy, "{at:?}");
    assert_eq!(at.tip, 0);
}

/// The crops' memory budget: with room for less than the ball's footprint
/// per sample every window is narrowed to that footprint (never below it)
/// and counted as clipped; the choice still runs, on the ball's material.
#[test]
fn crops_beyond_the_budget_are_narrowed_and_counted() {
    let mut op = ball_op();
    pass(&mut op, 0.0, -2.0);
    let mut p = Program::new(Dialect::Fanuc);
    p.operations.push(op);
    let st = strokes_of(&p, 0.1);
    let stock = || {
        Stock::block(
            DVec3::new(-20.0, -10.0, -6.0),
            DVec3::new(20.0, 10.0, 8.0),
            0.1,
        )
    };
    let run = |max_bytes: usize| {
        choose_with(
            &p,
            &plate(),
            &Machine::default(),
            &params(0.5, 0.5),
            Some(StockInput {
                stock: stock(),
                strokes: &st,
                samples: 8,
                max_bytes,
            }),
            &|_, _, _| {},
        )
        .expect("runs")
    };
    // Material 10 mm over the ball's centre: the flutes reach it, the
    // windows are wide.
    let free = run(MAX_CROP_BYTES);
    let c = &free.chosen[0];
    assert_eq!(c.clipped_samples, 0, "{c:?}");
    let tight = run(1000);
    let t = &tight.chosen[0];
    assert_eq!(t.samples, c.samples);
    assert_eq!(t.clipped_samples, t.samples, "{t:?}");
    // Each crop is the ball's footprint widened by two cells: (2·5.2/0.1
    // + 1)² cells at most.
    let per = t.sample_bytes / t.samples;
    assert!(
        t.sample_bytes < c.sample_bytes,
        "{} vs {}",
        t.sample_bytes,
        c.sample_bytes
    );
    assert!(
        per as f64 <= 106.0 * 106.0 * millplan_sim::stock::BYTES_PER_CELL * 1.1,
        "{per}"
    );
}
