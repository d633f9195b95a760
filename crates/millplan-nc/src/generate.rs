//! Toolpath generators for analytic surfaces: the bundled demo's raster and the
//! free-form test cases whose contact points are known exactly.

use crate::ir::*;
use millplan_geom::analytic::HeightField;
use millplan_geom::DVec3;

/// A zig-zag ball-end raster along X over a height field, computed exactly from the
/// surface: each point is a chosen contact point `p`, and the tool tip stands at
/// `p + R·n − R·z` (ball centre offset along the normal). The contact points of
/// move `i` are returned beside the program, as the oracle for contact analyses.
#[derive(Clone, Copy, Debug)]
pub struct Raster {
    /// Ball diameter, mm.
    pub d: f64,
    /// Distance between passes (in Y), mm.
    pub stepover: f64,
    /// Distance between points along a pass (in X), mm.
    pub step: f64,
    /// Margin kept from the domain border, mm.
    pub margin: f64,
    pub feed: f64,
    pub spindle: f64,
    /// Clearance height above the highest surface point for rapids, mm.
    pub clearance: f64,
    /// Feed direction of the passes, degrees from +X (counter-clockwise seen from +Z).
    pub angle_deg: f64,
}

impl Default for Raster {
    fn default() -> Self {
        Raster {
            d: 10.0,
            stepover: 1.0,
            step: 0.5,
            margin: 2.0,
            feed: 1500.0,
            spindle: 6000.0,
            clearance: 5.0,
            angle_deg: 0.0,
        }
    }
}

/// The program and, for every move, the surface contact point (`None` on rapids).
pub fn raster(surface: &dyn HeightField, r: &Raster) -> (Program, Vec<Option<DVec3>>) {
    let rad = r.d / 2.0;
    let (lo, hi) = surface.domain();
    let (x0, x1) = (lo.x + r.margin, hi.x - r.margin);
    let (y0, y1) = (lo.y + r.margin, hi.y - r.margin);
    // Passes along direction `dir`, stepping along `perp`, clipped to the domain.
    let (sa, ca) = r.angle_deg.to_radians().sin_cos();
    let (dir, perp) = (
        millplan_geom::DVec2::new(ca, sa),
        millplan_geom::DVec2::new(-sa, ca),
    );
    let centre = millplan_geom::DVec2::new((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let half = ((x1 - x0).hypot(y1 - y0)) / 2.0;
    let inside = |q: millplan_geom::DVec2| {
        q.x >= x0 - 1e-9 && q.x <= x1 + 1e-9 && q.y >= y0 - 1e-9 && q.y <= y1 + 1e-9
    };
    let lines = (half / r.stepover).floor() as i64;
    let steps = (2.0 * half / r.step).ceil() as i64;
    let mut ztop = f64::NEG_INFINITY;
    let tip = |x: f64, y: f64| {
        let p = surface.point(x, y);
        let n = surface.normal(x, y);
        (p + n * rad - DVec3::Z * rad, p)
    };
    let mut rows: Vec<Vec<(DVec3, DVec3)>> = Vec::new();
    for j in -lines..=lines {
        let base = centre + perp * (r.stepover * j as f64);
        let mut row: Vec<(DVec3, DVec3)> = (0..=steps)
            .map(|i| base + dir * (-half + r.step * i as f64))
            .filter(|q| inside(*q))
            .map(|q| tip(q.x, q.y))
            .collect();
        if row.len() < 2 {
            continue;
        }
        if rows.len() % 2 == 1 {
            row.reverse();
        }
        for (t, _) in &row {
            ztop = ztop.max(t.z);
        }
        rows.push(row);
    }
    let safe = ztop + r.clearance;
    let mut op = Operation {
        name: Some("BALL RASTER".into()),
        tool: Some(Tool {
            number: Some(1),
            name: Some(format!("BALL D{}", r.d)),
            cutter: Some(Cutter::ball(r.d)),
            line: 0,
        }),
        ..Operation::default()
    };
    op.push_event(0, EventKind::Spindle(SpindleDir::Cw));
    op.push_event(0, EventKind::Coolant(Coolant::Flood));
    let mut contacts = Vec::new();
    let mut push = |op: &mut Operation, m: Move, c: Option<DVec3>| {
        op.moves.push(Move {
            spindle: r.spindle,
            ..m
        });
        contacts.push(c);
    };
    let first = rows[0][0].0;
    push(
        &mut op,
        Move::rapid(DVec3::new(first.x, first.y, safe)),
        None,
    );
    for (j, row) in rows.iter().enumerate() {
        if j == 0 {
            push(&mut op, Move::linear(row[0].0, r.feed), Some(row[0].1));
        } else {
            // Step over along the surface to the next pass start.
            push(&mut op, Move::linear(row[0].0, r.feed), Some(row[0].1));
        }
        for (t, p) in &row[1..] {
            push(&mut op, Move::linear(*t, r.feed), Some(*p));
        }
    }
    let last = op.moves.last().map(|m| m.end).unwrap_or(first);
    push(&mut op, Move::rapid(DVec3::new(last.x, last.y, safe)), None);
    op.push_event(0, EventKind::Coolant(Coolant::Off));
    let n = op.moves.len() as u32;
    if let Some(e) = op.events.last_mut() {
        e.at = n;
    }
    let mut p = Program::new(Dialect::Generated);
    p.name = Some("DEMO_FREEFORM".into());
    p.units = Units {
        source: LengthUnit::Mm,
        origin: UnitsOrigin::Declared,
    };
    p.operations.push(op);
    (p, contacts)
}
