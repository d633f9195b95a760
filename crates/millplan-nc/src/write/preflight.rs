//! What every writer checks before it writes a byte: each number it would
//! write is finite (an infinite coordinate, feed or speed is never written:
//! `Xinf`, `FNaN` and `Z-inf` are not NC), and the program written out (arcs
//! outside the XY, ZX and YZ planes as lines, canned cycles spelled out)
//! stays within the `expansion` and `moves` limits.

use super::{principal_plane, Target, WriteError, WriteOptions};
use crate::ir::*;
use millplan_geom::limits::{amount, Exceeded};
use millplan_geom::DVec3;

/// Refuses a program with a number no target can write, or one whose written
/// form would exceed the limits of `o`, at the source line that asks for it.
pub fn check(p: &Program, o: &WriteOptions) -> Result<(), WriteError> {
    finite(p)?;
    p.operations.iter().try_for_each(writable_op)?;
    let mut lines: f64 = 0.0;
    for op in &p.operations {
        lines += written_moves(op, o)?;
    }
    if lines > o.limits.moves as f64 {
        return Err(WriteError::new(
            0,
            Exceeded::new(
                "moves",
                format!(
                    "written out, the program would take up to {} moves",
                    amount(lines.ceil())
                ),
                o.limits.moves as f64,
            )
            .to_string(),
        ));
    }
    Ok(())
}

/// Refuses a program with a number that is not finite (coordinates may be
/// NaN: unknown, never written), at its source line.
pub fn finite(p: &Program) -> Result<(), WriteError> {
    p.operations.iter().try_for_each(finite_op)
}

/// How many lines an arc takes when written as chords of tolerance `tol`
/// (as [`super::arc_points`] writes it, before its own cap).
pub fn arc_lines(a: &Arc, tol: f64) -> f64 {
    let step = if a.radius > tol {
        2.0 * (1.0 - tol / a.radius).acos()
    } else {
        a.sweep
    };
    (a.sweep / step.max(1e-6)).ceil().max(1.0)
}

/// Moves of `op` once written (an upper bound: every cycle spelled out),
/// refusing an arc that alone needs more lines than the `expansion` limit.
fn written_moves(op: &Operation, o: &WriteOptions) -> Result<f64, WriteError> {
    let mut n = 0.0;
    for m in &op.moves {
        n += match m.kind {
            MoveKind::Arc(id) if o.target != Target::Apt => match op.arcs.get(id.index()) {
                Some(a) if principal_plane(a).is_none() => {
                    let k = arc_lines(a, o.chord_tol);
                    if k > o.limits.expansion as f64 {
                        return Err(WriteError::new(
                            m.line,
                            Exceeded::new(
                                "expansion",
                                format!(
                                    "an arc of radius {} mm outside the XY, ZX and YZ planes is written as lines, {} of them at the chord tolerance of {} mm",
                                    amount(a.radius),
                                    amount(k),
                                    o.chord_tol
                                ),
                                o.limits.expansion as f64,
                            )
                            .to_string(),
                        ));
                    }
                    k
                }
                _ => 1.0,
            },
            MoveKind::Cycle(id) => op
                .cycles
                .get(id.index())
                .map_or(1.0, |c| 3.0 * c.pecks().min(MAX_PECKS + 1) as f64 + 4.0),
            _ => 1.0,
        };
    }
    Ok(n)
}

/// The first word of verbatim block text whose value is not a finite
/// number (`XNAN`, `Y-INF`, `Z=inf`, `Finfinity`), outside comments: a
/// letter at a word's start, an optional `=` and sign, then NaN or
/// inf(inity) ending the word.
pub fn non_finite_word(text: &str) -> Option<&str> {
    let b = text.as_bytes();
    let mut i = 0;
    let mut paren = 0u32;
    while i < b.len() {
        match b[i] {
            b';' if paren == 0 => return None,
            b'(' => paren += 1,
            b')' => paren = paren.saturating_sub(1),
            c if paren == 0
                && c.is_ascii_alphabetic()
                && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_')) =>
            {
                let mut j = i + 1;
                while j < b.len() && matches!(b[j], b'=' | b'+' | b'-' | b' ') {
                    j += 1;
                }
                for name in ["infinity", "inf", "nan"] {
                    let end = j + name.len();
                    if b.get(j..end)
                        .is_some_and(|w| w.eq_ignore_ascii_case(name.as_bytes()))
                        && !b
                            .get(end)
                            .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_')
                    {
                        return Some(&text[i..end]);
                    }
                }
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// What a writer refuses beyond non-finite numbers, at the source line: a
/// feed move (linear or arc) whose feed is not above 0 (`F0`, `FEDRAT/0`
/// stop a control or run at an undefined rate), and text copied verbatim
/// whose words are not finite numbers (`XNAN`, `ZINF`).
fn writable_op(op: &Operation) -> Result<(), WriteError> {
    for m in &op.moves {
        if matches!(m.kind, MoveKind::Linear | MoveKind::Arc(_)) && !(m.feed > 0.0) {
            return Err(WriteError::new(
                m.line,
                format!(
                    "this feed move has a feed of {} (not above 0): no target writes it (a control stops or moves at an undefined rate)",
                    m.feed
                ),
            ));
        }
    }
    if let Some(c) = op.cycles.iter().find(|c| !(c.feed > 0.0)) {
        return Err(WriteError::new(
            c.line,
            format!(
                "cycle {} has a feed of {} (not above 0): no target writes it",
                c.name, c.feed
            ),
        ));
    }
    for e in &op.events {
        if let EventKind::Passthrough(Passthrough { text, .. }) | EventKind::Insert(text) = &e.kind
        {
            if let Some(w) = non_finite_word(text) {
                return Err(WriteError::new(
                    e.line,
                    format!(
                        "the block copied verbatim from the source holds `{w}`, not a finite number: no target writes it"
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn infinite(v: DVec3) -> bool {
    v.to_array().iter().any(|c| c.is_infinite())
}

fn bad(line: u32, what: &str, v: impl std::fmt::Debug) -> WriteError {
    WriteError::new(
        line,
        format!("{what} is not a finite number ({v:?}): no target can write it"),
    )
}

/// Every number of `op` a writer writes is finite; coordinates may be NaN
/// (unknown: never written).
fn finite_op(op: &Operation) -> Result<(), WriteError> {
    let tool_line = op.tool.as_ref().map_or(0, |t| t.line);
    if let Some(c) = op.tool.as_ref().and_then(|t| t.cutter) {
        let v = [c.d, c.r, c.e, c.f, c.alpha, c.beta, c.h];
        if v.iter().any(|x| !x.is_finite()) {
            return Err(bad(tool_line, "the tool's geometry", v));
        }
    }
    if let Some(f) = &op.frame {
        if !f.origin.is_finite() || !f.rot.is_finite() {
            return Err(bad(0, "the operation's frame", f));
        }
    }
    if infinite(op.start) {
        return Err(bad(0, "the operation's start position", op.start));
    }
    for o in &op.orients {
        if o.axis.is_some_and(|a| !a.is_finite())
            || o.angles.iter().flatten().any(|x| !x.is_finite())
        {
            return Err(bad(0, "a tool orientation", o));
        }
    }
    for c in &op.cycles {
        let v = [c.bottom, c.clearance, c.retract, c.feed];
        let opt = [c.peck, c.peck_next, c.dwell];
        if v.iter().chain(opt.iter().flatten()).any(|x| !x.is_finite()) {
            return Err(bad(c.line, &format!("a value of cycle {}", c.name), c));
        }
    }
    for a in &op.arcs {
        if !a.centre.is_finite()
            || !a.normal.is_finite()
            || !a.radius.is_finite()
            || !a.sweep.is_finite()
        {
            return Err(bad(0, "an arc", a));
        }
    }
    for e in &op.events {
        if let EventKind::Dwell(t) = e.kind {
            if !t.is_finite() {
                return Err(bad(e.line, "a dwell time", t));
            }
        }
    }
    for m in &op.moves {
        if infinite(m.end) {
            return Err(bad(m.line, "a coordinate of this move", m.end));
        }
        if !m.feed.is_finite() {
            return Err(bad(m.line, "the feed of this move", m.feed));
        }

        if !m.spindle.is_finite() {
            return Err(bad(m.line, "the spindle speed of this move", m.spindle));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::write::write_program;

    fn program(f: impl FnOnce(&mut Operation)) -> Program {
        let mut op = Operation {
            tool: Some(Tool {
                number: Some(1),
                name: None,
                cutter: Some(Cutter::ball(10.0)),
                line: 1,
            }),
            ..Operation::default()
        };
        let mut m = Move::rapid(DVec3::new(0.0, 0.0, 5.0));
        m.line = 2;
        op.moves.push(m);
        let mut m = Move::linear(DVec3::new(10.0, 0.0, 0.0), 500.0);
        m.line = 3;
        op.moves.push(m);
        f(&mut op);
        let mut p = Program::new(Dialect::Generated);
        p.operations.push(op);
        p
    }

    /// Issue 17: "`raster --clearance nan` writes `ZNaN`; `--angle inf` `XNaN
    /// YNaN ZNaN`; `--tool ball:inf` `Z-inf`; `--feed inf` `Finf`". No target
    /// writes a number that is not finite: every writer refuses at the line.
    #[test]
    fn no_target_writes_a_number_that_is_not_finite() {
        type Break = fn(&mut Operation);
        let breaks: [(&str, Break); 5] = [
            ("coordinate", |op| op.moves[1].end.x = f64::INFINITY),
            ("feed", |op| op.moves[1].feed = f64::NAN),
            ("spindle", |op| op.moves[1].spindle = f64::NEG_INFINITY),
            ("geometry", |op| {
                if let Some(t) = op.tool.as_mut() {
                    t.cutter = Some(Cutter::ball(f64::INFINITY));
                }
            }),
            ("dwell", |op| op.push_event(1, EventKind::Dwell(f64::NAN))),
        ];
        for (what, f) in breaks {
            let p = program(f);
            for t in Target::ALL {
                let e = write_program(&p, WriteOptions::new(t)).expect_err(what);
                assert!(
                    e.message.contains("not a finite number"),
                    "{what} {}: {e}",
                    t.name()
                );
                assert!(e.line > 0, "{what} {}: {e}", t.name());
            }
        }
        // An unknown (NaN) coordinate is no number to write: still written.
        let p = program(|op| op.moves[0].end.x = f64::NAN);
        assert!(write_program(&p, WriteOptions::new(Target::Fanuc)).is_ok());
    }

    /// Issue 17: "30 non-planar CIRCLEs of R 1e6 write 527k lines". An arc
    /// that written as lines would take more than the expansion limit is
    /// refused at its line before anything is written; raised, it is written.
    #[test]
    fn an_arc_written_as_lines_is_bounded() {
        let big = |op: &mut Operation| {
            let r = 1e6;
            let n = DVec3::new(0.0, 0.6, 0.8);
            let start = DVec3::new(r, 0.0, 0.0);
            let end = DVec3::new(0.0, 0.8 * r, -0.6 * r);
            let a = Arc::from_points(start, end, DVec3::ZERO, n, false).expect("arc");
            op.moves[1].end = start;
            let mut m = Move::linear(end, 500.0);
            m.line = 4;
            m.kind = MoveKind::Arc(op.push_arc(a));
            op.moves.push(m);
        };
        let p = program(big);
        let e = write_program(&p, WriteOptions::new(Target::Fanuc)).expect_err("refused");
        assert_eq!(e.line, 4, "{e}");
        assert!(e.message.contains("expansion limit of 10000"), "{e}");
        assert!(write_program(&p, WriteOptions::new(Target::Apt)).is_ok());
        let mut o = WriteOptions::new(Target::Fanuc);
        o.limits.expansion = 100_000;
        assert!(write_program(&p, o).is_ok());
        o.limits.moves = 1000;
        let e = write_program(&p, o).expect_err("too many moves");
        assert!(e.message.contains("moves limit of 1000"), "{e}");
    }
}
