//! Finishing rasters made of drop-cutter points: parallel lines at an angle over
//! the part, refined where the surface bends until the chord between neighbouring
//! points stays within a tolerance of the drop-cutter surface.

use crate::dropcutter::DropMesh;
use millplan_geom::{Aabb, DVec2, DVec3};
use millplan_models::cutter::Shape;
use millplan_nc::{
    Coolant, Cutter, Dialect, EventKind, LengthUnit, Move, Operation, Program, SpindleDir, Tool,
    Units, UnitsOrigin,
};
use rayon::prelude::*;

#[derive(Clone, Copy, Debug)]
pub struct RasterParams {
    pub shape: Shape,
    /// Feed direction of the passes, degrees from +X.
    pub angle_deg: f64,
    /// Distance between passes, mm.
    pub stepover: f64,
    /// Distance between points along a pass, mm.
    pub step: f64,
    /// Alternate the direction of the passes (linked along the surface); else
    /// every pass runs the same way with a retract in between.
    pub zigzag: bool,
    /// Margin from the part's xy bounds (negative: beyond them), mm.
    pub margin: f64,
    /// Clearance above the highest point for rapids, mm.
    pub clearance: f64,
    /// Chord tolerance for adaptive refinement, mm (`None`: no refinement).
    pub tol: Option<f64>,
    pub feed: f64,
    pub spindle: f64,
}

impl RasterParams {
    pub fn new(shape: Shape) -> RasterParams {
        RasterParams {
            shape,
            angle_deg: 0.0,
            stepover: 1.0,
            step: 0.5,
            zigzag: true,
            margin: 0.0,
            clearance: 5.0,
            tol: Some(0.002),
            feed: 1500.0,
            spindle: 6000.0,
        }
    }
}

/// Drop-cutter heights along the segment a–b with the given step, refined so
/// every chord stays within `tol` of the drop surface (checked at its midpoint
/// and quarter points). `None` entries: the cutter is off the part.
fn along(
    part: &DropMesh,
    sh: &Shape,
    a: DVec2,
    b: DVec2,
    step: f64,
    tol: Option<f64>,
) -> Vec<Option<DVec3>> {
    let n = (((b - a).length() / step).ceil() as usize).max(1);
    let base: Vec<DVec2> = (0..=n).map(|k| a.lerp(b, k as f64 / n as f64)).collect();
    let mut hint = None;
    let z: Vec<Option<f64>> = base
        .iter()
        .map(|p| {
            let d = part.drop_near(sh, *p, hint);
            hint = d.map(|d| d.triangle);
            d.map(|d| d.z)
        })
        .collect();
    let mut out: Vec<Option<DVec3>> = Vec::with_capacity(base.len());
    for k in 0..base.len() {
        let here = z[k].map(|z| DVec3::new(base[k].x, base[k].y, z));
        if k > 0 {
            if let (Some(t), Some(p), Some(q)) = (tol, out.last().copied().flatten(), here) {
                refine(part, sh, p, q, t, 0, &mut out);
            }
        }
        out.push(here);
    }
    out
}

/// Points between p and q (pushed to `out` in order) that keep the chords
/// within `tol` of the drop surface, halving up to 12 times. A chord is
/// halved where a sample lies more than `tol` off it, above or below: a
/// plateau's edge or a step near one end can stand above the chord while
/// every sample lies below it. A steep chord is halved too where one half
/// holds nearly all of its rise: a step of the drop surface (a vertical
/// wall, the cutter dropping off its edge). Where halving cannot close it,
/// the path rises or falls vertically at the lower end, to the highest
/// height seen between them, and never cuts the corner.
fn refine(
    part: &DropMesh,
    sh: &Shape,
    p: DVec3,
    q: DVec3,
    tol: f64,
    depth: u32,
    out: &mut Vec<Option<DVec3>>,
) {
    let at = |t: f64| {
        let xy = DVec2::new(p.x + (q.x - p.x) * t, p.y + (q.y - p.y) * t);
        part.drop(sh, xy).map(|d| DVec3::new(xy.x, xy.y, d.z))
    };
    let checks = [0.25, 0.5, 0.75].map(|t| (t, at(t)));
    let off = checks.iter().any(|(t, m)| match m {
        Some(m) => (m.z - (p.z + (q.z - p.z) * t)).abs() > tol,
        None => false,
    });
    let rise = (q.z - p.z).abs();
    let step = checks[1].1.is_some_and(|m| {
        rise > 4.0 * tol
            && rise > DVec2::new(q.x - p.x, q.y - p.y).length()
            && (m.z - p.z).abs().max((q.z - m.z).abs()) > 0.75 * rise
    });
    if !(off || step) {
        return;
    }
    if depth >= 12 {
        // Any height at or above a point's drop height is clear there.
        let top = checks
            .iter()
            .filter_map(|(_, m)| m.map(|m| m.z))
            .fold(p.z.max(q.z), f64::max);
        let low = if p.z <= q.z { p } else { q };
        out.push(Some(DVec3::new(low.x, low.y, top)));
        return;
    }
    if let Some(m) = checks[1].1 {
        refine(part, sh, p, m, tol, depth + 1, out);
        out.push(Some(m));
        refine(part, sh, m, q, tol, depth + 1, out);
    }
}

/// The work a raster asks for, counted from its grid before any point is
/// dropped (the refinement where the surface bends comes on top).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterEstimate {
    /// Passes that cross the part's bounds.
    pub lines: f64,
    /// Points on them at the step (and so moves of the program).
    pub points: f64,
    /// Memory the grid, the program, its text and its own gouge check take.
    pub bytes: f64,
}

/// Memory per raster point: the grid (position, height, point), the move and
/// its text.
pub const BYTES_PER_POINT: f64 = 16.0 + 16.0 + 32.0 + 24.0 + 64.0 + 48.0;

/// Counts the raster `p` over `bounds` would make, in constant time: a step
/// of 1e-300 or a margin of -1e308 is refused from this, never attempted.
pub fn estimate(bounds: &Aabb, p: &RasterParams, gouge_step: f64) -> RasterEstimate {
    let size = DVec2::new(
        bounds.max.x - bounds.min.x - 2.0 * p.margin,
        bounds.max.y - bounds.min.y - 2.0 * p.margin,
    );
    if !(size.x > 0.0 && size.y > 0.0) {
        return RasterEstimate {
            lines: 0.0,
            points: 0.0,
            bytes: 0.0,
        };
    }
    let (sa, ca) = p.angle_deg.to_radians().sin_cos();
    // The rectangle's width across the passes and along them.
    // (0·∞ is no width: an infinite side along the passes adds none across.)
    let part = |len: f64, f: f64| if f == 0.0 { 0.0 } else { (len * f).abs() };
    let across = part(size.x, sa) + part(size.y, ca);
    let lines = (across / p.stepover).floor() + 1.0;
    let points = size.x * size.y / (p.stepover * p.step) + 2.0 * lines;
    // The raster's own gouge check samples every move at its step.
    let samples = points * (p.step / gouge_step).ceil().max(1.0) + points;
    RasterEstimate {
        lines,
        points,
        bytes: points * BYTES_PER_POINT + samples * crate::gouge::BYTES_PER_SAMPLE,
    }
}

/// A raster over the part (`bounds`: the part's bounding box).
pub fn raster(part: &DropMesh, bounds: &Aabb, p: &RasterParams) -> Program {
    let (lo, hi) = (
        DVec2::new(bounds.min.x + p.margin, bounds.min.y + p.margin),
        DVec2::new(bounds.max.x - p.margin, bounds.max.y - p.margin),
    );
    let (sa, ca) = p.angle_deg.to_radians().sin_cos();
    let (dir, perp) = (DVec2::new(ca, sa), DVec2::new(-sa, ca));
    // A margin wider than the part leaves nothing to raster (and a rectangle
    // turned inside out would count its lines without end).
    let cross = hi.x > lo.x && hi.y > lo.y;
    let centre = (lo + hi) / 2.0;
    let half = (hi - lo).length() / 2.0;
    // Clip each line to the rectangle [lo, hi].
    let clip = |base: DVec2| -> Option<(DVec2, DVec2)> {
        let (mut t0, mut t1) = (-half, half);
        for k in 0..2 {
            let (o, d) = (base[k], dir[k]);
            if d.abs() < 1e-12 {
                if o < lo[k] || o > hi[k] {
                    return None;
                }
            } else {
                let (a, b) = ((lo[k] - o) / d, (hi[k] - o) / d);
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
        }
        (t1 > t0).then(|| (base + dir * t0, base + dir * t1))
    };
    let lines = if cross {
        (half / p.stepover).floor() as i64
    } else {
        -1
    };
    let segs: Vec<(DVec2, DVec2)> = (-lines..=lines)
        .filter_map(|j| clip(centre + perp * (p.stepover * j as f64)))
        .collect();
    // Each line becomes one or more passes (split where the cutter leaves the part).
    let lines_pts: Vec<Vec<Vec<DVec3>>> = segs
        .par_iter()
        .map(|(a, b)| {
            let mut passes = Vec::new();
            let mut cur = Vec::new();
            for q in along(part, &p.shape, *a, *b, p.step, p.tol) {
                match q {
                    Some(q) => cur.push(q),
                    None => {
                        if cur.len() > 1 {
                            passes.push(std::mem::take(&mut cur));
                        }
                        cur.clear();
                    }
                }
            }
            if cur.len() > 1 {
                passes.push(cur);
            }
            passes
        })
        .collect();
    let mut passes: Vec<Vec<DVec3>> = Vec::new();
    for (j, mut line) in lines_pts.into_iter().enumerate() {
        if p.zigzag && j % 2 == 1 {
            line.reverse();
            for pass in &mut line {
                pass.reverse();
            }
        }
        passes.extend(line);
    }
    let ztop = passes
        .iter()
        .flatten()
        .map(|q| q.z)
        .fold(f64::NEG_INFINITY, f64::max);
    let safe = ztop + p.clearance;
    let r = p.shape.radius();
    let cutter = match p.shape {
        Shape::Flat { .. } => Cutter::flat(2.0 * r),
        Shape::Ball { .. } => Cutter::ball(2.0 * r),
        Shape::Bull { corner, .. } => Cutter::from_d_r(2.0 * r, corner, 0.0),
        Shape::Cone { alpha, .. } => {
            Cutter::from_iso(2.0 * r, 0.0, r, r * alpha.tan(), alpha, 0.0, 0.0)
        }
    };
    let mut op = Operation {
        name: Some(format!("RASTER {:.1} DEG", p.angle_deg)),
        tool: Some(Tool {
            number: Some(1),
            name: None,
            cutter: Some(cutter),
            line: 0,
        }),
        ..Operation::default()
    };
    op.push_event(0, EventKind::Spindle(SpindleDir::Cw));
    op.push_event(0, EventKind::Coolant(Coolant::Flood));
    let push = |op: &mut Operation, m: Move| {
        op.moves.push(Move {
            spindle: p.spindle,
            ..m
        })
    };
    let mut last: Option<DVec3> = None;
    for pass in &passes {
        let first = pass[0];
        match last {
            // Zig-zag: link to the next pass along the surface when it is near.
            Some(l)
                if p.zigzag
                    && (DVec2::new(first.x, first.y) - DVec2::new(l.x, l.y)).length()
                        <= 2.0 * p.stepover + p.step =>
            {
                let link = along(
                    part,
                    &p.shape,
                    DVec2::new(l.x, l.y),
                    DVec2::new(first.x, first.y),
                    p.step,
                    p.tol,
                );
                if link.iter().all(Option::is_some) {
                    for q in link.into_iter().flatten().skip(1) {
                        push(&mut op, Move::linear(q, p.feed));
                    }
                } else {
                    push(&mut op, Move::rapid(DVec3::new(l.x, l.y, safe)));
                    push(&mut op, Move::rapid(DVec3::new(first.x, first.y, safe)));
                    push(&mut op, Move::linear(first, p.feed));
                }
            }
            Some(l) => {
                push(&mut op, Move::rapid(DVec3::new(l.x, l.y, safe)));
                push(&mut op, Move::rapid(DVec3::new(first.x, first.y, safe)));
                push(&mut op, Move::linear(first, p.feed));
            }
            None => {
                push(&mut op, Move::rapid(DVec3::new(first.x, first.y, safe)));
                push(&mut op, Move::linear(first, p.feed));
            }
        }
        for q in &pass[1..] {
            push(&mut op, Move::linear(*q, p.feed));
        }
        last = pass.last().copied();
    }
    if let Some(l) = last {
        push(&mut op, Move::rapid(DVec3::new(l.x, l.y, safe)));
    }
    let n = op.moves.len() as u32;
    op.events.push(millplan_nc::Event {
        at: n,
        line: 0,
        kind: EventKind::Coolant(Coolant::Off),
    });
    let mut prog = Program::new(Dialect::Generated);
    prog.name = Some("MILLPLAN_RASTER".into());
    prog.units = Units {
        source: LengthUnit::Mm,
        origin: UnitsOrigin::Declared,
    };
    prog.operations.push(op);
    prog
}
