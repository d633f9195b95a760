//! Summary figures of a program: move counts, path lengths, bounds, estimated time.

use crate::ir::*;
use millplan_geom::Aabb;

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
    /// Cutting (feed) path length, mm.
    pub cutting_mm: f64,
    /// Rapid path length, mm (cycle positioning included).
    pub rapid_mm: f64,
    /// Estimated time at programmed feeds and `rapid_rate`, seconds.
    pub time_s: f64,
    /// Bounds of all positions, in the operations' own frames.
    pub bounds: Aabb,
    pub five_axis_moves: usize,
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
    };
    let mut minutes = 0.0;
    for op in &p.operations {
        for (i, m) in op.moves.iter().enumerate() {
            let start = op.move_start(i);
            if m.orient != NO_ORIENT {
                if let Some(Orient::Vector(v)) = op.orients.get(m.orient as usize) {
                    if (v.z - 1.0).abs() > 1e-9 {
                        s.five_axis_moves += 1;
                    }
                } else if let Some(Orient::Rotary(r)) = op.orients.get(m.orient as usize) {
                    if r.iter().flatten().any(|a| a.abs() > 1e-12) {
                        s.five_axis_moves += 1;
                    }
                }
            }
            let len = match (m.kind, start) {
                (MoveKind::Arc, Some(st)) => op
                    .arcs
                    .get(m.aux as usize)
                    .map(|a| a.length(st, m.end))
                    .unwrap_or(0.0),
                (_, Some(st)) => (m.end - st).length(),
                (_, None) => 0.0,
            };
            match m.kind {
                MoveKind::Rapid => {
                    s.moves.rapid += 1;
                    s.rapid_mm += len;
                    minutes += len / rapid_rate;
                }
                MoveKind::Linear | MoveKind::Arc => {
                    if m.kind == MoveKind::Arc {
                        s.moves.arc += 1;
                    } else {
                        s.moves.linear += 1;
                    }
                    s.cutting_mm += len;
                    minutes += match m.feed_mode {
                        FeedMode::PerMinute => len / m.feed,
                        FeedMode::PerRev => {
                            if m.spindle > 0.0 {
                                len / (m.feed * m.spindle)
                            } else {
                                0.0
                            }
                        }
                        FeedMode::InverseTime => 1.0 / m.feed,
                    };
                }
                MoveKind::Cycle => {
                    s.moves.cycle += 1;
                    s.rapid_mm += len;
                    minutes += len / rapid_rate;
                    if let Some(c) = op.cycles.get(m.aux as usize) {
                        let depth = (c.clearance - c.bottom).max(0.0);
                        s.cutting_mm += depth;
                        minutes += depth / c.feed + (c.retract - c.bottom).max(0.0) / rapid_rate;
                        minutes += c.dwell.unwrap_or(0.0) / 60.0;
                    }
                }
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
