//! Do two programs command the same thing? Both are run through the same
//! interpreter: every move becomes the positions a control steps through
//! (canned cycles spelled out, arcs kept as arcs), with its feed, feed mode,
//! spindle speed and tool orientation; then the two step lists are walked
//! side by side, axis by axis.
//!
//! The second program may take more steps where the first took one (an arc
//! written as chords, a cycle spelled out as lines), but every extra step must
//! lie on the first program's path, and every step of the first must be
//! reached. An axis unknown in one must be unknown in the other: a writer
//! that invents a position, drops a G90 or loses a rotary axis fails here.
//!
//! [`crate::readback`] runs this on every program a command writes (re-read
//! from its own output with the target's reader) before it is written.

use crate::ir::*;
use crate::write::{cycle_moves, CycleStep};
use millplan_geom::DVec3;

/// How close two programs must agree.
#[derive(Clone, Copy, Debug)]
pub struct Tolerance {
    /// Positions, mm (output decimals round by up to half a unit of the last place).
    pub position: f64,
    /// Distance from the path for intermediate steps (arcs written as chords), mm.
    pub chord: f64,
    /// Rotary angles, radians.
    pub angle: f64,
    /// Tool axes (length of the difference of unit vectors).
    pub axis: f64,
    /// Feeds, relative.
    pub feed: f64,
    /// Spindle speeds, 1/min (Fanuc writes whole numbers).
    pub spindle: f64,
}

impl Tolerance {
    /// Where the tool goes only: feeds and spindle speeds may differ (a pass
    /// that sets them), positions, paths, rapid or feed, angles and tools
    /// may not. Positions within `position` mm.
    pub fn paths_only(position: f64) -> Tolerance {
        Tolerance {
            position,
            feed: f64::INFINITY,
            spindle: f64::INFINITY,
            ..Tolerance::default()
        }
    }
}

impl Default for Tolerance {
    fn default() -> Self {
        Tolerance {
            position: 2e-4,
            chord: 0.002,
            angle: 2e-6,
            axis: 2e-6,
            feed: 1e-3,
            spindle: 0.51,
        }
    }
}

/// Where two programs part.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("line {line_a} against line {line_b}: {message}")]
pub struct Mismatch {
    /// Source line in the first program (0: generated or at its end).
    pub line_a: u32,
    /// Source line in the second.
    pub line_b: u32,
    pub message: String,
}

/// What the comparison walked through.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Walked {
    /// Steps of the first program, all matched.
    pub steps: usize,
    /// Steps of the second that lay on the first's path between them.
    pub intermediate: usize,
    /// Zero-length steps of the first that the second leaves out.
    pub skipped: usize,
}

/// The path a step takes to its end.
#[derive(Clone, Copy, Debug)]
enum Path {
    Line,
    Arc(Arc),
}

/// One position a control steps to.
#[derive(Clone, Copy, Debug)]
struct Step {
    start: DVec3,
    end: DVec3,
    path: Path,
    rapid: bool,
    feed: f64,
    mode: FeedMode,
    spindle: f64,
    angles: [Option<f64>; 3],
    axis: Option<DVec3>,
    tool: Option<u32>,
    line: u32,
}

/// The steps of a program, in order, made as the comparison walks them (a
/// million-move program would otherwise hold hundreds of megabytes of steps
/// twice over).
struct Steps<'a> {
    ops: &'a [Operation],
    op: usize,
    mv: usize,
    cur: DVec3,
    /// The steps of the current move (a cycle makes several), handed out from `next`.
    buf: Vec<Step>,
    next: usize,
}

fn steps(ops: &[Operation]) -> Steps<'_> {
    Steps {
        ops,
        op: 0,
        mv: 0,
        cur: ops.first().map_or(DVec3::NAN, |op| op.start),
        buf: Vec::new(),
        next: 0,
    }
}

impl Iterator for Steps<'_> {
    type Item = Step;

    fn next(&mut self) -> Option<Step> {
        loop {
            if let Some(s) = self.buf.get(self.next) {
                self.next += 1;
                return Some(*s);
            }
            self.buf.clear();
            self.next = 0;
            let op = self.ops.get(self.op)?;
            let Some(m) = op.moves.get(self.mv) else {
                self.op += 1;
                self.mv = 0;
                if let Some(op) = self.ops.get(self.op) {
                    self.cur = op.start;
                }
                continue;
            };
            self.mv += 1;
            self.cur = move_steps(op, m, self.cur, &mut self.buf);
        }
    }
}

/// Appends the steps of move `m` of `op`, from `cur`, to `out`; returns where
/// the tool then stands.
fn move_steps(op: &Operation, m: &Move, mut cur: DVec3, out: &mut Vec<Step>) -> DVec3 {
    let tool = op.tool.as_ref().and_then(|t| t.number);
    let o = op.orient(m);
    let base = Step {
        start: cur,
        end: m.end,
        path: Path::Line,
        rapid: m.is_rapid(),
        feed: m.feed,
        mode: m.feed_mode,
        spindle: m.spindle,
        angles: o.map(|o| o.angles).unwrap_or([None; 3]),
        axis: o.and_then(|o| o.axis).filter(|_| op.is_five_axis()),
        tool,
        line: m.line,
    };
    match m.kind {
        MoveKind::Arc(_) => {
            let path = op.arc(m).map_or(Path::Line, |a| Path::Arc(*a));
            out.push(Step { path, ..base });
            m.end
        }
        MoveKind::Cycle(_) => {
            let Some(c) = op.cycle(m) else { return cur };
            // Up to the cycle's level if the tool stands below it (as a
            // control does), across to the hole, then down.
            let axis = op.axis(m).unwrap_or(DVec3::Z);
            let top = m.end + axis * c.retract.max(c.clearance);
            let up = (cur.z < top.z).then(|| DVec3::new(cur.x, cur.y, top.z));
            let z = if cur.z.is_nan() {
                top.z
            } else {
                cur.z.max(top.z)
            };
            let across = DVec3::new(m.end.x, m.end.y, z);
            let mut push = |end: DVec3, rapid: bool, feed: f64| {
                out.push(Step {
                    start: cur,
                    end,
                    rapid,
                    feed,
                    mode: FeedMode::PerMinute,
                    ..base
                });
                cur = end;
            };
            if let Some(up) = up {
                push(up, true, 0.0);
            }
            push(across, true, 0.0);
            // A cycle that cannot be spelled out compares by its hole.
            let v = cycle_moves(c, m.end, axis).unwrap_or_else(|_| vec![CycleStep::Rapid(top)]);
            for s in v {
                match s {
                    CycleStep::Rapid(q) => push(q, true, 0.0),
                    CycleStep::Feed(q, f) => push(q, false, f),
                    CycleStep::Dwell(_) => {}
                }
            }
            cur
        }
        _ => {
            out.push(base);
            m.end
        }
    }
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (0..3).all(|k| {
        (a[k].is_nan() && b[k].is_nan())
            || (!a[k].is_nan() && !b[k].is_nan() && (a[k] - b[k]).abs() <= tol)
    })
}

/// Distance of `q` from the path of `s`, when both are known.
fn off_path(s: &Step, q: DVec3) -> Option<f64> {
    let (a, b) = (known(s.start)?, known(s.end)?);
    let q = known(q)?;
    Some(match s.path {
        Path::Line => {
            let d = b - a;
            let t = if d.length_squared() > 0.0 {
                ((q - a).dot(d) / d.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (a + d * t - q).length()
        }
        Path::Arc(arc) => {
            // Nearest of a fine sampling: the step ends are checked exactly.
            let n = ((arc.sweep * arc.radius / 0.05).ceil() as usize).clamp(8, 20_000);
            (0..=n)
                .map(|k| (arc.point_at(a, b, k as f64 / n as f64) - q).length())
                .fold(f64::INFINITY, f64::min)
        }
    })
}

fn same_attrs(a: &Step, b: &Step, tol: &Tolerance) -> Result<(), String> {
    if a.rapid != b.rapid {
        return Err(format!(
            "{} against {}",
            if a.rapid { "rapid" } else { "feed" },
            if b.rapid { "rapid" } else { "feed" }
        ));
    }
    if !a.rapid {
        if a.mode != b.mode {
            let mode = |m: FeedMode| match m {
                FeedMode::PerMinute => "per minute (G94)",
                FeedMode::PerRev => "per revolution (G95)",
                FeedMode::InverseTime => "inverse time (G93)",
            };
            return Err(format!(
                "feed mode {} against {}",
                mode(a.mode),
                mode(b.mode)
            ));
        }
        if (a.feed - b.feed).abs() > tol.feed * a.feed.abs().max(1.0) {
            return Err(format!("feed {} against {}", a.feed, b.feed));
        }
        if (a.spindle - b.spindle).abs() > tol.spindle {
            return Err(format!("spindle {} against {}", a.spindle, b.spindle));
        }
    }
    // The same rotary angles, or the same tool axis (a program whose angles
    // were turned into axes through the machine's kinematics, written as CL
    // data, keeps the axes only).
    let angle_miss = (0..3).find(|&k| match (a.angles[k], b.angles[k]) {
        (None, None) => false,
        (Some(x), Some(y)) => (x - y).abs() > tol.angle,
        _ => true,
    });
    let axes = match (a.axis, b.axis) {
        (Some(u), Some(v)) => Some((u - v).length() <= tol.axis),
        (None, None) => None,
        _ => Some(false),
    };
    let same = match (angle_miss, axes) {
        (None, Some(false)) => a.axis.is_none() || b.axis.is_none(),
        (None, _) => true,
        (Some(_), Some(true)) => true,
        (Some(_), _) => false,
    };
    if !same {
        return Err(match angle_miss {
            Some(k) => {
                let deg = |v: Option<f64>| {
                    v.map_or("unset".to_string(), |r| format!("{:.4}°", r.to_degrees()))
                };
                format!(
                    "{} axis {} against {}",
                    ["A", "B", "C"][k],
                    deg(a.angles[k]),
                    deg(b.angles[k])
                )
            }
            None => {
                let axis = |v: Option<DVec3>| v.map_or("unset".to_string(), fmt);
                format!("tool axis {} against {}", axis(a.axis), axis(b.axis))
            }
        });
    }
    if a.tool != b.tool {
        let tool = |t: Option<u32>| t.map_or("no tool number".to_string(), |t| format!("T{t}"));
        return Err(format!("tool {} against {}", tool(a.tool), tool(b.tool)));
    }
    if let (Path::Arc(x), Path::Arc(y)) = (a.path, b.path) {
        // Rounded end points turn a small arc's sweep by up to their error
        // over its radius.
        let sweep_tol = 1e-4_f64.max(8.0 * tol.position / x.radius.max(1e-9));
        if (x.centre - y.centre).length() > tol.position * 4.0
            || x.normal.dot(y.normal) < 0.999_999
            || (x.sweep - y.sweep).abs() > sweep_tol
        {
            return Err("a different arc to the same end".into());
        }
    }
    Ok(())
}

/// Compares what `a` and `b` command, step by step.
pub fn compare(a: &Program, b: &Program, tol: &Tolerance) -> Result<Walked, Mismatch> {
    compare_operations(&a.operations, &b.operations, tol)
}

/// [`compare`] over two lists of operations (one operation and what it was
/// written as, say).
pub fn compare_operations(
    a: &[Operation],
    b: &[Operation],
    tol: &Tolerance,
) -> Result<Walked, Mismatch> {
    let mut sb = steps(b).peekable();
    let mut w = Walked::default();
    let miss = |x: Option<&Step>, y: Option<&Step>, message: String| Mismatch {
        line_a: x.map_or(0, |s| s.line),
        line_b: y.map_or(0, |s| s.line),
        message,
    };
    for s in steps(a) {
        let s = &s;
        loop {
            let Some(t) = sb.peek() else {
                if close(s.start, s.end, tol.position) {
                    w.skipped += 1;
                    break;
                }
                return Err(miss(
                    Some(s),
                    None,
                    format!("the second program ends before the step to {:?}", s.end),
                ));
            };
            if close(t.end, s.end, tol.position) {
                same_attrs(s, t, tol).map_err(|m| miss(Some(s), Some(t), m))?;
                w.steps += 1;
                sb.next();
                break;
            }
            // A zero-length step the second program leaves out.
            if close(s.start, s.end, tol.position) && same_angles(s, t) {
                w.skipped += 1;
                break;
            }
            match off_path(s, t.end) {
                Some(d) if d <= tol.chord + tol.position => {
                    w.intermediate += 1;
                    sb.next();
                }
                _ => {
                    return Err(miss(
                        Some(s),
                        Some(t),
                        format!("step to {} against {}", fmt(s.end), fmt(t.end)),
                    ))
                }
            }
        }
    }
    if let Some(t) = sb.peek() {
        return Err(miss(
            None,
            Some(t),
            format!("the second program goes on to {}", fmt(t.end)),
        ));
    }
    Ok(w)
}

fn same_angles(s: &Step, t: &Step) -> bool {
    s.angles.iter().zip(&t.angles).all(|(x, y)| match (x, y) {
        (Some(x), Some(y)) => (x - y).abs() < 1e-6,
        _ => true,
    })
}

fn fmt(p: DVec3) -> String {
    let c = |v: f64| {
        if v.is_nan() {
            "?".to_string()
        } else {
            format!("{v:.4}")
        }
    };
    format!("({}, {}, {})", c(p.x), c(p.y), c(p.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{parse_program, ReadOptions};

    fn read(s: &str) -> Program {
        parse_program(s, ReadOptions::default())
            .expect("reads")
            .program
    }

    #[test]
    fn the_same_program_in_other_words_is_the_same() {
        let a = read("G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F100\nX10\nG2 X20 Y0 I5 J0\nM30\n");
        let b = read(
            "G21\nT1 M6\nG90 G0 X0. Y0. Z5.\nG1 Z-1. F100.\nG1 X10.\nX10.\nG2 X20 Y0 R5\nM30\n",
        );
        let w = compare(&a, &b, &Tolerance::default()).expect("same");
        assert_eq!((w.steps, w.intermediate), (4, 1));
    }

    #[test]
    fn incremental_mode_left_on_is_caught() {
        let a = read("G21 G90\nT1 M6\nG0 X10 Y10 Z5\nG1 X20 F100\n");
        let b = read("G21 G90\nT1 M6\nG0 X10 Y10 Z5\nG91\nG1 X20 F100\n");
        let e = compare(&a, &b, &Tolerance::default()).expect_err("differs");
        assert_eq!((e.line_a, e.line_b), (4, 5));
    }

    #[test]
    fn an_invented_position_is_caught() {
        // The source never says where X and Y are; a writer that makes them 0 differs.
        let a = read("G21 G90\nT1 M6\nG0 Z20\nG0 X5 Y5\n");
        let b = read("G21 G90\nT1 M6\nG0 X0 Y0 Z20\nG0 X5 Y5\n");
        assert!(compare(&a, &b, &Tolerance::default()).is_err());
    }

    #[test]
    fn chords_on_the_arc_pass_and_off_it_fail() {
        let a = read("G21 G90\nT1 M6\nG0 X10 Y0 Z0\nG3 X0 Y10 I-10 J0 F100\n");
        let mut chords = String::from("G21 G90\nT1 M6\nG0 X10 Y0 Z0\nG1 F100\n");
        for k in 1..=20 {
            let t = std::f64::consts::FRAC_PI_2 * k as f64 / 20.0;
            chords.push_str(&format!("X{:.5} Y{:.5}\n", 10.0 * t.cos(), 10.0 * t.sin()));
        }
        let w = compare(
            &a,
            &read(&chords),
            &Tolerance {
                chord: 0.2,
                ..Tolerance::default()
            },
        )
        .expect("chords of the arc");
        assert_eq!(w.intermediate, 19);
        let off = "G21 G90\nT1 M6\nG0 X10 Y0 Z0\nG1 X5 Y5 F100\nX0 Y10\n";
        assert!(compare(&a, &read(off), &Tolerance::default()).is_err());
    }

    #[test]
    fn feed_modes_and_rotary_axes_count() {
        let a = read("G21 G90\nT1 M6\nG0 X0 Y0 Z5 B0\nG93 G1 X10 B30 F50\n");
        let b = read("G21 G90\nT1 M6\nG0 X0 Y0 Z5 B0\nG94 G1 X10 B30 F50\n");
        assert!(compare(&a, &b, &Tolerance::default())
            .expect_err("G93 against G94")
            .message
            .contains("feed mode inverse time (G93) against per minute (G94)"));
        let c = read("G21 G90\nT1 M6\nG0 X0 Y0 Z5 B0\nG93 G1 X10 F50\n");
        assert!(compare(&a, &c, &Tolerance::default()).is_err());
        // An axis one program sets and the other does not, in words.
        let d = read("G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 X10 F50\n");
        let e = read("G21 G90\nT1 M6\nG0 X0 Y0 Z5 B0\nG1 X10 F50\n");
        let m = compare(&d, &e, &Tolerance::default()).expect_err("B set in one only");
        assert!(m.message.contains("B axis unset against 0.0000°"), "{m}");
    }
}
