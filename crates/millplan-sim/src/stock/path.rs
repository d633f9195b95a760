//! A program as the straight strokes the stock simulation runs: arcs cut into
//! chords, canned cycles spelled out, frames applied, the tool axis in part
//! coordinates at both ends.

use crate::stock::tool::ToolBody;
use millplan_geom::DVec3;
use millplan_nc::write::{cycle_moves, CycleStep};
use millplan_nc::{known, FeedMode, Move, MoveKind, Operation, Program};

/// One straight stroke of the tool.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stroke {
    /// Index of the IR move it belongs to, over the whole program.
    pub mv: u32,
    /// Source line (0 for generated moves).
    pub line: u32,
    /// Index into [`Strokes::tools`].
    pub tool: u16,
    pub rapid: bool,
    pub p0: DVec3,
    pub p1: DVec3,
    /// Unit tool axis at both ends, part coordinates.
    pub a0: DVec3,
    pub a1: DVec3,
    /// Duration, minutes (rapids at the rapid rate).
    pub minutes: f64,
}

impl Stroke {
    /// Whether the tool stays along +Z over the whole stroke.
    pub fn vertical(&self) -> bool {
        (self.a0 - DVec3::Z).length_squared() < 1e-18
            && (self.a1 - DVec3::Z).length_squared() < 1e-18
    }

    /// The tool axis at fraction `t`: turning at a constant rate on the great
    /// circle from `a0` to `a1` (the interpolation of the IR,
    /// [`millplan_nc::axis_at`]).
    pub fn axis_at(&self, t: f64) -> DVec3 {
        millplan_nc::axis_at(self.a0, self.a1, t)
    }
}

/// Why IR moves were not simulated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Unsimulated {
    /// The operation's tool has no geometry and none was given.
    pub no_tool: usize,
    /// From or to a position the program has not set.
    pub unknown_position: usize,
    /// Tool axis known only as machine angles.
    pub unknown_axis: usize,
    /// Source line of the first move left out (the first move of a program
    /// usually is: it starts where the machine stood before it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_line: Option<u32>,
}

impl Unsimulated {
    pub fn total(&self) -> usize {
        self.no_tool + self.unknown_position + self.unknown_axis
    }

    /// Notes the source line of a move left out (the first one is kept).
    pub fn at(&mut self, line: u32) {
        self.first_line.get_or_insert(line);
    }

    /// `"; the first at line N"`, or nothing when no move was left out or
    /// its line is unknown: the end of the messages that count them.
    pub fn first(&self) -> String {
        first_line_note(self.first_line)
    }
}

/// `"; the first at line N"` for `Some(N)`, else nothing.
pub fn first_line_note(line: Option<u32>) -> String {
    line.map_or(String::new(), |l| format!("; the first at line {l}"))
}

/// The strokes of a program.
#[derive(Clone, Debug, Default)]
pub struct Strokes {
    pub strokes: Vec<Stroke>,
    pub tools: Vec<ToolBody>,
    /// IR moves in the program.
    pub moves: usize,
    pub skipped: Unsimulated,
}

impl Strokes {
    /// A 64-bit digest of the strokes' geometry: every stroke's tool,
    /// kind, ends and axes bit for bit, and the tool bodies (not the
    /// durations, lines or move indices). Two lists with the same digest
    /// cut the same material the same way but for a hash collision.
    pub fn fingerprint(&self) -> u64 {
        use std::hash::Hasher;
        let mut h = rustc_hash::FxHasher::default();
        for t in &self.tools {
            h.write(format!("{t:?}").as_bytes());
        }
        h.write_u64(self.strokes.len() as u64);
        for s in &self.strokes {
            h.write_u64(u64::from(s.tool) << 1 | u64::from(s.rapid));
            for v in [s.p0, s.p1, s.a0, s.a1] {
                for c in v.to_array() {
                    h.write_u64(c.to_bits());
                }
            }
        }
        h.finish()
    }
}

/// Options of [`strokes`].
#[derive(Clone, Copy, Debug)]
pub struct PathOptions {
    /// Largest deviation of an arc's chords from the arc, mm.
    pub chord: f64,
    /// Rapid rate, mm/min.
    pub rapid_rate: f64,
}

/// Cuts a program into strokes. `tool` gives the body of an operation's tool
/// (`None` leaves the operation out).
pub fn strokes(
    p: &Program,
    tool: impl Fn(&Operation) -> Option<ToolBody>,
    o: &PathOptions,
) -> Strokes {
    let mut out = Strokes::default();
    let mut mv = 0u32;
    let mut returned = None;
    for op in &p.operations {
        let entry = if op.moves.is_empty() {
            returned
        } else {
            returned.take()
        };
        let first = mv;
        mv += op.moves.len() as u32;
        out.moves += op.moves.len();
        let Some(body) = tool(op) else {
            out.skipped.no_tool += op.moves.len();
            if let Some(m) = op.moves.first() {
                out.skipped.at(m.line);
            }
            continue;
        };
        let ti = match out.tools.iter().position(|t| *t == body) {
            Some(i) => i,
            None => {
                out.tools.push(body);
                out.tools.len() - 1
            }
        } as u16;
        returned = op_strokes(op, first, ti, o, &mut out, entry);
    }
    out
}

/// The strokes of one operation; `entry` is where a canned cycle at the end
/// of the operation before left the tool (part coordinates). Returns the
/// same for this operation's end.
fn op_strokes(
    op: &Operation,
    first: u32,
    ti: u16,
    o: &PathOptions,
    out: &mut Strokes,
    entry: Option<DVec3>,
) -> Option<DVec3> {
    let to_part = |v: DVec3| op.frame.map(|f| f.to_parent(v)).unwrap_or(v);
    let dir_part = |v: DVec3| op.frame.map(|f| f.dir_to_parent(v)).unwrap_or(v);
    // The axis in the operation's frame; `None` when only angles say it.
    let axis = |m: &Move| -> Option<DVec3> {
        match op.orient(m) {
            Some(or) => match or.axis {
                Some(v) => Some(v.normalize()),
                None if or.is_tilted() => None,
                None => Some(DVec3::Z),
            },
            None => Some(DVec3::Z),
        }
    };
    let mut prev_axis = DVec3::Z;
    if let Some(m) = op.moves.first() {
        prev_axis = axis(m).unwrap_or(DVec3::Z);
    }
    // Where a canned cycle left the tool: at its return level above the
    // last hole, not at the hole's point the program names.
    let mut after_cycle: Option<DVec3> =
        entry.map(|p| op.frame.map(|f| f.from_parent(p)).unwrap_or(p));
    for (i, m) in op.moves.iter().enumerate() {
        let idx = first + i as u32;
        let returned = after_cycle.take();
        let Some(a1) = axis(m) else {
            out.skipped.unknown_axis += 1;
            out.skipped.at(m.line);
            continue;
        };
        let a0 = prev_axis;
        prev_axis = a1;
        // A known start after a cycle is where the cycle left the tool; an
        // unknown one (a tool change in between) stays unknown.
        let start = op.known_start(i).map(|s| returned.unwrap_or(s));
        let (Some(start), Some(end)) = (start, known(m.end)) else {
            out.skipped.unknown_position += 1;
            out.skipped.at(m.line);
            continue;
        };
        let mut push = |p0: DVec3, p1: DVec3, b0: DVec3, b1: DVec3, rapid: bool, minutes: f64| {
            out.strokes.push(Stroke {
                mv: idx,
                line: m.line,
                tool: ti,
                rapid,
                p0: to_part(p0),
                p1: to_part(p1),
                a0: dir_part(b0),
                a1: dir_part(b1),
                minutes,
            });
        };
        match m.kind {
            MoveKind::Rapid | MoveKind::Linear => {
                let len = (end - start).length();
                let rapid = m.is_rapid();
                let minutes = if rapid {
                    len / o.rapid_rate
                } else {
                    feed_minutes(len, m)
                };
                push(start, end, a0, a1, rapid, minutes);
            }
            MoveKind::Arc(_) => {
                let arc = op.arc(m).expect("arc move has an arc");
                let len = arc.length(start, end);
                // Chord error of a step s on radius r: s²/(8r).
                let step = (8.0 * arc.radius * o.chord).sqrt().max(1e-6);
                let n = ((arc.radius * arc.sweep / step).ceil() as usize).clamp(1, 100_000);
                let total = feed_minutes(len, m);
                let mut q = start;
                for k in 1..=n {
                    let t = k as f64 / n as f64;
                    let r = if k == n {
                        end
                    } else {
                        arc.point_at(start, end, t)
                    };
                    let b0 = millplan_nc::axis_at(a0, a1, (k - 1) as f64 / n as f64);
                    let b1 = millplan_nc::axis_at(a0, a1, t);
                    push(q, r, b0, b1, false, total / n as f64);
                    q = r;
                }
            }
            MoveKind::Cycle(_) => {
                let Some(c) = op.cycle(m) else { continue };
                // Up to the cycle's return level if the tool stands below
                // it, across to the hole at that height (or the tool's, when
                // higher), then the strokes: as the writers spell it out.
                let top = end.z + c.retract.max(c.clearance);
                let mut from = start;
                if start.z < top {
                    let up = DVec3::new(start.x, start.y, top);
                    push(
                        start,
                        up,
                        a0,
                        a0,
                        true,
                        (up - start).length() / o.rapid_rate,
                    );
                    from = up;
                }
                let across = DVec3::new(end.x, end.y, from.z);
                push(
                    from,
                    across,
                    a0,
                    a1,
                    true,
                    (across - from).length() / o.rapid_rate,
                );
                let steps = cycle_moves(c, end, a1).unwrap_or_else(|_| {
                    // Tapping and boring: down at feed and back out at feed.
                    vec![
                        CycleStep::Rapid(end + a1 * c.clearance),
                        CycleStep::Feed(end + a1 * c.bottom, c.feed),
                        CycleStep::Feed(end + a1 * c.retract.max(c.clearance), c.feed),
                    ]
                });
                let mut here = across;
                for st in steps {
                    match st {
                        CycleStep::Rapid(q) => {
                            push(here, q, a1, a1, true, (q - here).length() / o.rapid_rate);
                            here = q;
                        }
                        CycleStep::Feed(q, f) => {
                            let minutes = if f > 0.0 {
                                (q - here).length() / f
                            } else {
                                0.0
                            };
                            push(here, q, a1, a1, false, minutes);
                            here = q;
                        }
                        CycleStep::Dwell(_) => {}
                    }
                }
                after_cycle = Some(here);
            }
        }
    }
    after_cycle.map(to_part)
}

/// Feed time in minutes of a cutting stroke of length `len`.
fn feed_minutes(len: f64, m: &Move) -> f64 {
    if !(m.feed > 0.0) {
        return 0.0;
    }
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
