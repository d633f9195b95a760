//! Summary figures of a program: move counts, path lengths, bounds, estimated time.
//!
//! A move from or to a position the program has not set (an unknown axis)
//! has no known length: it is counted in `unknown_moves` and left out of
//! lengths and times, never measured from a made-up origin.

use crate::ir::*;
use crate::write::{cycle_moves, CycleStep};
use millplan_geom::{Aabb, DVec3};

#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct MoveCounts {
    pub rapid: usize,
    pub linear: usize,
    pub arc: usize,
    pub cycle: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    pub moves: MoveCounts,
    /// Cutting (feed) path length, mm (canned-cycle feeds included).
    pub cutting_mm: f64,
    /// Rapid path length, mm (cycle positioning and retracts included).
    pub rapid_mm: f64,
    /// Estimated time at programmed feeds and `rapid_rate`, seconds.
    pub time_s: f64,
    /// Bounds of all known positions (cycle depths included), in the
    /// operations' own frames.
    pub bounds: Aabb,
    pub five_axis_moves: usize,
    /// Moves whose length is unknown (from or to an unset axis): left out of
    /// lengths and times.
    pub unknown_moves: usize,
    /// The rotary motion the program commands, A, B and C (`None`: the axis
    /// is never written).
    pub rotary: [Option<RotaryUse>; 3],
}

/// How a rotary axis is used: the range of its positions and the sum of its
/// moves, degrees.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RotaryUse {
    pub min_deg: f64,
    pub max_deg: f64,
    pub travel_deg: f64,
}

/// The rotary motion of a program's written angles.
pub fn rotary_use(p: &Program) -> [Option<RotaryUse>; 3] {
    let mut r: [Option<RotaryUse>; 3] = [None; 3];
    for op in &p.operations {
        let mut last: [Option<f64>; 3] = [None; 3];
        for m in &op.moves {
            let Some(o) = op.orient(m) else { continue };
            for k in 0..3 {
                let Some(a) = o.angles[k].map(f64::to_degrees) else {
                    continue;
                };
                let u = r[k].get_or_insert(RotaryUse {
                    min_deg: a,
                    max_deg: a,
                    travel_deg: 0.0,
                });
                u.min_deg = u.min_deg.min(a);
                u.max_deg = u.max_deg.max(a);
                if let Some(b) = last[k] {
                    u.travel_deg += (a - b).abs();
                }
                last[k] = Some(a);
            }
        }
    }
    r
}

/// Feed time in minutes of a cutting stroke of length `len`.
fn feed_minutes(len: f64, m: &Move) -> f64 {
    match m.feed_mode {
        FeedMode::PerMinute => len / m.feed,
        FeedMode::PerRev => {
            if m.spindle > 0.0 {
                len / (m.feed * m.spindle)
            } else {
                0.0
            }
        }
        FeedMode::InverseTime => 1.0 / m.feed,
    }
}

/// Summarises a program; rapids are timed at `rapid_rate` mm/min.
pub fn summarize(p: &Program, rapid_rate: f64) -> Summary {
    let mut s = Summary {
        moves: MoveCounts::default(),
        cutting_mm: 0.0,
        rapid_mm: 0.0,
        time_s: 0.0,
        bounds: p.bounds(),
        five_axis_moves: 0,
        unknown_moves: 0,
        rotary: rotary_use(p),
    };
    let mut minutes = 0.0;
    for op in &p.operations {
        for (i, m) in op.moves.iter().enumerate() {
            if op.orient(m).is_some_and(Orient::is_tilted) {
                s.five_axis_moves += 1;
            }
            let len = op.move_length(i);
            match m.kind {
                MoveKind::Rapid => s.moves.rapid += 1,
                MoveKind::Linear => s.moves.linear += 1,
                MoveKind::Arc(_) => s.moves.arc += 1,
                MoveKind::Cycle(_) => s.moves.cycle += 1,
            }
            if let MoveKind::Cycle(_) = m.kind {
                // Up to the cycle's level if the tool stands below it,
                // across to the hole, then the cycle's own strokes (as the
                // writers spell it out).
                let (Some(c), Some(at)) = (op.cycle(m), known(m.end)) else {
                    s.unknown_moves += 1;
                    continue;
                };
                let axis = op.axis(m).unwrap_or(DVec3::Z);
                let mut here = op.known_start(i);
                if let Some(h) = here {
                    let top = at.z + c.retract.max(c.clearance);
                    let across = DVec3::new(at.x, at.y, h.z.max(top));
                    let d = (top - h.z).max(0.0) + (across.truncate() - h.truncate()).length();
                    s.rapid_mm += d;
                    minutes += d / rapid_rate;
                    here = Some(across);
                } else {
                    s.unknown_moves += 1;
                }
                let steps = cycle_moves(c, at, axis).unwrap_or_else(|_| {
                    // Too many pecks to spell out: the depth at feed, the way
                    // back at rapid.
                    vec![
                        CycleStep::Rapid(at + axis * c.clearance),
                        CycleStep::Feed(at + axis * c.bottom, c.feed),
                        CycleStep::Rapid(at + axis * c.retract.max(c.clearance)),
                    ]
                });
                for st in steps {
                    match st {
                        CycleStep::Rapid(q) => {
                            let d = here.map_or(0.0, |h| (q - h).length());
                            s.rapid_mm += d;
                            minutes += d / rapid_rate;
                            here = Some(q);
                        }
                        CycleStep::Feed(q, f) => {
                            let d = here.map_or(0.0, |h| (q - h).length());
                            s.cutting_mm += d;
                            minutes += d / f;
                            here = Some(q);
                        }
                        CycleStep::Dwell(t) => minutes += t / 60.0,
                    }
                }
                continue;
            }
            let Some(len) = len else {
                s.unknown_moves += 1;
                continue;
            };
            if m.is_rapid() {
                s.rapid_mm += len;
                minutes += len / rapid_rate;
            } else {
                s.cutting_mm += len;
                minutes += feed_minutes(len, m);
            }
        }
        for e in &op.events {
            if let EventKind::Dwell(t) = e.kind {
                minutes += t / 60.0;
            }
        }
    }
    s.time_s = minutes * 60.0;
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_phantom_move_from_the_origin_and_cycle_depths_count() {
        let mut op = Operation::default();
        // From an unknown start: no length.
        op.moves.push(Move::rapid(DVec3::new(10.0, 0.0, 5.0)));
        op.moves
            .push(Move::linear(DVec3::new(10.0, 0.0, 0.0), 100.0));
        let cy = op.push_cycle(Cycle {
            name: "G81".into(),
            bottom: -12.0,
            clearance: 0.0,
            retract: 3.0,
            feed: 120.0,
            peck: None,
            peck_next: None,
            dwell: None,
            line: 3,
        });
        let mut c = Move::rapid(DVec3::new(20.0, 0.0, 2.0));
        c.kind = MoveKind::Cycle(cy);
        op.moves.push(c);
        let mut p = Program::new(Dialect::Fanuc);
        p.operations.push(op);
        let s = summarize(&p, 6000.0);
        assert_eq!(s.unknown_moves, 1);
        // 5 mm down, then 12 mm into the hole.
        assert!((s.cutting_mm - 17.0).abs() < 1e-9, "{}", s.cutting_mm);
        // Up 5 to the return plane (Z 5), across 10, down 3 to the R
        // plane, out 15.
        assert!(
            (s.rapid_mm - (5.0 + 10.0 + 3.0 + 15.0)).abs() < 1e-9,
            "{}",
            s.rapid_mm
        );
        assert_eq!(s.bounds.min.z, -10.0);
        assert_eq!(s.bounds.min.x, 10.0);
    }
}
