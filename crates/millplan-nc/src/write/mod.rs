//! Back ends: G-code dialects and APT/CL. Writers produce bytes; the binary puts
//! them in files (through a temporary file and a rename).

pub mod apt;
pub mod gcode;

use crate::ir::*;
use millplan_geom::DVec3;

/// Something the target cannot express, which stops writing.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct WriteError {
    pub message: String,
}

/// Where finished text goes while a large program is written: about every
/// [`FLUSH_AT`] bytes the writer hands its buffer's contents over and goes on
/// in the same buffer, so a program of any size is written in a few
/// megabytes. What is left at the end stays in the buffer for the caller.
pub type Sink<'a> = &'a mut dyn FnMut(&[u8]) -> Result<(), WriteError>;

/// Buffer size at which a writer with a [`Sink`] hands its text over.
pub const FLUSH_AT: usize = 1 << 22;

/// Hands `out` to `sink` once it holds [`FLUSH_AT`] bytes.
#[inline]
fn maybe_flush(out: &mut Vec<u8>, sink: &mut Option<Sink>) -> Result<(), WriteError> {
    if let Some(s) = sink {
        if out.len() >= FLUSH_AT {
            s(out)?;
            out.clear();
        }
    }
    Ok(())
}

/// Room a writer reserves for `moves` moves of about `per` bytes each: all of
/// it without a sink, a flush's worth with one.
fn room(moves: usize, per: usize, sink: &Option<Sink>) -> usize {
    let all = moves * per + 1024;
    if sink.is_some() {
        all.min(FLUSH_AT + (1 << 16))
    } else {
        all
    }
}

/// Moves per run of the parallel writers.
const RUN: usize = 1 << 14;
/// Runs written at once: a group's text is held until it is handed on.
const GROUP: usize = 8;
/// Moves written before a run to guess the state it starts from.
const WARM: usize = 64;
/// Operations with at least this many moves are written in parallel runs.
pub(crate) const PARALLEL_MIN: usize = 2 * RUN;

/// A run of moves written on its own: the text, the writer's state after it,
/// and the first error if any.
pub(crate) struct Run<S> {
    pub text: Vec<u8>,
    pub end: S,
    pub result: Result<(), WriteError>,
}

/// Writes moves `0..n` in runs, in parallel, as one pass from state `st`
/// would. `run(a, b, s)` writes moves `a..b` from writer state `s`. Each run
/// but a group's first starts from the state that writing the few moves just
/// before it gives; a run whose guessed start differs from the state the run
/// before it actually ended in is written again from that state. The writer's
/// output must depend only on its state and the moves. The text goes to
/// `out` or, through it, to `sink`; `st` ends as the state after the last move.
pub(crate) fn write_runs<S: Clone + PartialEq + Send + Sync>(
    n: usize,
    st: &mut S,
    out: &mut Vec<u8>,
    sink: &mut Option<Sink>,
    run: impl Fn(usize, usize, S) -> Run<S> + Sync,
) -> Result<(), WriteError> {
    use rayon::prelude::*;
    let mut a = 0;
    while a < n {
        let b = (a + RUN * GROUP).min(n);
        let known = st.clone();
        let starts: Vec<usize> = (a..b).step_by(RUN).collect();
        let runs: Vec<(S, Run<S>)> = starts
            .par_iter()
            .map(|&s| {
                let guess = if s == a {
                    known.clone()
                } else {
                    run(s - WARM.min(s - a), s, known.clone()).end
                };
                (guess.clone(), run(s, (s + RUN).min(b), guess))
            })
            .collect();
        for (&s, (guess, r)) in starts.iter().zip(runs) {
            let r = if *st == guess {
                r
            } else {
                run(s, (s + RUN).min(b), st.clone())
            };
            match sink {
                Some(f) => {
                    if !out.is_empty() {
                        f(out)?;
                        out.clear();
                    }
                    f(&r.text)?;
                }
                None => out.extend_from_slice(&r.text),
            }
            r.result?;
            *st = r.end;
        }
        a = b;
    }
    Ok(())
}

/// The next event before move `i`: events are taken, in their order, before
/// the first move at or after their position.
pub(crate) fn first_event_at(events: &[Event], i: usize) -> usize {
    events
        .iter()
        .position(|e| e.at as usize >= i)
        .unwrap_or(events.len())
}

/// Fast fixed-decimal number formatting with trailing zeros removed
/// (`12.5`, `-0.25`, `3`), the inner loop of every writer.
#[derive(Clone, Copy, Debug)]
pub struct NumFmt {
    pub decimals: u32,
    /// Keep a trailing decimal point on whole numbers (`3.`), as Fanuc wants.
    pub trailing_point: bool,
    /// Write `+` on positive numbers (Heidenhain).
    pub plus: bool,
    /// Drop the leading zero (`.5`).
    pub no_leading_zero: bool,
}

impl NumFmt {
    pub fn push(&self, out: &mut Vec<u8>, v: f64) {
        let scale = 10u64.pow(self.decimals) as f64;
        let r = (v * scale).round();
        if !r.is_finite() || r.abs() >= 9.0e18 {
            out.extend_from_slice(format!("{v}").as_bytes());
            return;
        }
        let neg = r < 0.0;
        let mut n = r.abs() as u64;
        let div = 10u64.pow(self.decimals);
        let int = n / div;
        n %= div;
        if neg && (int != 0 || n != 0) {
            out.push(b'-');
        } else if self.plus {
            out.push(b'+');
        }
        if int != 0 || !self.no_leading_zero || n == 0 {
            push_uint(out, int);
        }
        let mut d = self.decimals;
        let mut frac = n;
        while d > 0 && frac.is_multiple_of(10) {
            frac /= 10;
            d -= 1;
        }
        if d > 0 {
            out.push(b'.');
            let s = frac;
            let mut digits = [b'0'; 20];
            let mut x = s;
            for k in (0..d as usize).rev() {
                digits[k] = b'0' + (x % 10) as u8;
                x /= 10;
            }
            out.extend_from_slice(&digits[..d as usize]);
        } else if self.trailing_point {
            out.push(b'.');
        }
    }
}

/// Appends the decimal digits of `v` (no allocation: this runs for every
/// number of every block).
fn push_uint(out: &mut Vec<u8>, mut v: u64) {
    let mut b = [0u8; 20];
    let mut i = b.len();
    loop {
        i -= 1;
        b[i] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    out.extend_from_slice(&b[i..]);
}

/// Is this arc in a principal plane (normal along ±X, ±Y or ±Z)? Returns the axis index.
pub fn principal_plane(a: &Arc) -> Option<usize> {
    let n = a.normal.abs();
    (0..3).find(|&k| (n[k] - 1.0).abs() < 1e-9)
}

/// Points (after the start) that follow an arc within `tol`.
pub fn arc_points(a: &Arc, start: DVec3, end: DVec3, tol: f64) -> Vec<DVec3> {
    let step = if a.radius > tol {
        2.0 * (1.0 - tol / a.radius).acos()
    } else {
        a.sweep
    };
    let n = ((a.sweep / step.max(1e-6)).ceil() as usize).clamp(1, 100_000);
    (1..=n)
        .map(|k| {
            if k == n {
                end
            } else {
                a.point_at(start, end, k as f64 / n as f64)
            }
        })
        .collect()
}

/// Explicit moves (rapid, feed down with pecks, rapid out) for one hole of a cycle,
/// along the tool axis `axis` from the cycle point `p`.
pub fn cycle_moves(c: &Cycle, p: DVec3, axis: DVec3) -> Vec<(MoveKind, DVec3, f64)> {
    let at = |h: f64| p + axis * h;
    let mut v = vec![(MoveKind::Rapid, at(c.clearance.max(c.bottom)), 0.0)];
    let total = c.clearance - c.bottom;
    match c.peck {
        Some(q) if q > 0.0 && q < total => {
            let mut depth = c.clearance;
            while depth - q > c.bottom + 1e-9 {
                depth -= q;
                v.push((MoveKind::Linear, at(depth), c.feed));
                v.push((MoveKind::Rapid, at(c.clearance), 0.0));
                v.push((MoveKind::Rapid, at(depth + 0.5_f64.min(q / 2.0)), 0.0));
            }
            v.push((MoveKind::Linear, at(c.bottom), c.feed));
        }
        _ => v.push((MoveKind::Linear, at(c.bottom), c.feed)),
    }
    v.push((MoveKind::Rapid, at(c.retract.max(c.clearance)), 0.0));
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_handed_to_a_sink_is_the_text_written_whole() {
        use crate::generate::{raster, Raster};
        use millplan_geom::analytic::DemoSurface;
        // About 460,000 moves: several flushes in both writers.
        let (p, _) = raster(
            &DemoSurface::default(),
            &Raster {
                stepover: 0.25,
                step: 0.03,
                ..Raster::default()
            },
        );
        assert!(p.move_count() > 400_000);
        type Write = fn(&Program, &mut Vec<u8>, Option<Sink>) -> Result<(), WriteError>;
        let writers: [Write; 2] = [
            |p, out, sink| apt::write_apt_to(p, out, sink),
            |p, out, sink| {
                gcode::write_gcode_to(p, gcode::GcodeOptions::new(Dialect::Fanuc), out, sink)
            },
        ];
        for w in writers {
            let mut whole = Vec::new();
            w(&p, &mut whole, None).expect("writes");
            assert!(whole.len() > 2 * FLUSH_AT);
            let (mut streamed, mut flushes) = (Vec::new(), 0);
            let mut buf = Vec::new();
            {
                let mut sink = |b: &[u8]| {
                    flushes += 1;
                    streamed.extend_from_slice(b);
                    Ok(())
                };
                w(&p, &mut buf, Some(&mut sink)).expect("writes");
            }
            streamed.extend_from_slice(&buf);
            assert!(flushes >= 2 && buf.len() < FLUSH_AT + (1 << 16));
            assert!(streamed == whole, "streamed text differs");
            // A sink that fails stops the writer with its error.
            let mut fail = |_: &[u8]| {
                Err(WriteError {
                    message: "disk full".into(),
                })
            };
            let e = w(&p, &mut Vec::new(), Some(&mut fail)).expect_err("fails");
            assert_eq!(e.message, "disk full");
        }
    }

    /// Two long operations of every kind of move (rapids, lines with feeds and
    /// speeds that change now and then, arcs in and out of the principal
    /// planes, canned-cycle points, tool vectors in the second), with events
    /// scattered through them, several just before a parallel run starts or
    /// before the moves it guesses its start from.
    fn varied_program(n: usize) -> Program {
        let mut state = 7u64;
        let mut rnd = move |m: u64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) % m
        };
        let mut p = Program::new(Dialect::Fanuc);
        for k in 0..2 {
            let mut op = Operation {
                name: Some(format!("OP{k}")),
                tool: Some(Tool {
                    number: Some(3 + k as u32),
                    name: Some("BALL".into()),
                    cutter: None,
                    line: 0,
                }),
                cycles: vec![Cycle {
                    name: "DRILL".into(),
                    bottom: 2.0,
                    clearance: 1.0,
                    retract: 3.0,
                    feed: 200.0,
                    peck: None,
                    dwell: None,
                    line: 0,
                }],
                ..Operation::default()
            };
            if k == 1 {
                op.orients = vec![
                    Orient::Vector(DVec3::Z),
                    Orient::Vector(DVec3::new(0.3, 0.0, 1.0).normalize()),
                ];
            }
            let (mut at, mut feed, mut speed) = (DVec3::new(0.0, 0.0, 5.0), 1000.0, 6000.0);
            for i in 0..n {
                if rnd(60) == 0 {
                    feed = [800.0, 1000.0, 1250.5][rnd(3) as usize];
                }
                if rnd(90) == 0 {
                    speed = [5000.0, 6000.0, 7333.3][rnd(3) as usize];
                }
                // Coarse steps, so coordinates repeat and modal words are left out.
                let step = DVec3::new(
                    rnd(5) as f64 * 0.5 - 1.0,
                    rnd(3) as f64 * 0.5 - 0.5,
                    rnd(3) as f64 * 0.25 - 0.25,
                );
                let end = at + step;
                let mut m = match rnd(20) {
                    0 => Move::rapid(end + DVec3::Z * 3.0),
                    1 | 2 => {
                        let normal = if rnd(2) == 0 {
                            DVec3::Z
                        } else {
                            DVec3::new(0.0, 0.6, 0.8)
                        };
                        let centre = at + DVec3::new(1.5, 0.0, 0.0);
                        let e = at + DVec3::new(3.0, 0.0, 0.0);
                        let arc = Arc::from_points(at, e, centre, normal, false).expect("arc");
                        op.arcs.push(arc);
                        let mut m = Move::linear(e, feed);
                        m.kind = MoveKind::Arc;
                        m.aux = op.arcs.len() as u32 - 1;
                        m
                    }
                    3 => {
                        let mut m = Move::linear(end, feed);
                        m.kind = MoveKind::Cycle;
                        m
                    }
                    _ => Move::linear(end, feed),
                };
                m.spindle = speed;
                if k == 1 {
                    m.orient = (rnd(50) == 0) as u32;
                }
                at = m.end;
                op.moves.push(m);
                if (i + 1) % (2 * RUN) == 0 {
                    // Right before the first move of a run.
                    op.events.push(Event {
                        at: i as u32 + 1,
                        line: 0,
                        kind: EventKind::Coolant(Coolant::Mist),
                    });
                }
                if rnd(2500) == 0 || (i % RUN == RUN - 3 * WARM / 2 && rnd(2) == 0) {
                    let kind = match rnd(6) {
                        0 => EventKind::Comment(format!("note {i}")),
                        1 => EventKind::Spindle {
                            rpm: 0.0,
                            dir: SpindleDir::Off,
                        },
                        2 => EventKind::Spindle {
                            rpm: 4500.0,
                            dir: SpindleDir::Cw,
                        },
                        3 => EventKind::Coolant(Coolant::Flood),
                        4 => EventKind::CutCom([CutCom::Left, CutCom::Off][rnd(2) as usize]),
                        _ => EventKind::Stop { optional: true },
                    };
                    op.events.push(Event {
                        at: i as u32 + 1,
                        line: 0,
                        kind,
                    });
                }
            }
            p.operations.push(op);
        }
        p
    }

    /// The parallel writers write the text a single pass writes.
    #[test]
    fn parallel_writers_write_what_one_pass_writes() {
        let p = varied_program(5 * RUN + 777);
        assert!(p.operations[0].moves.len() >= PARALLEL_MIN);
        let mut one = Vec::new();
        apt::write_all(&p, &mut one, None, false).expect("writes");
        let mut par = Vec::new();
        apt::write_all(&p, &mut par, None, true).expect("writes");
        assert!(one.len() > 1 << 20);
        assert!(par == one, "APT text differs");
        // LinuxCNC stops at the first tool vector: the same error after the
        // same text.
        for d in [Dialect::Fanuc, Dialect::LinuxCnc, Dialect::Sinumerik] {
            let mut o = gcode::GcodeOptions::new(d);
            o.chord_tol = 0.01;
            let mut one = Vec::new();
            let r1 = gcode::write_all(&p, o, &mut one, None, false);
            let mut par = Vec::new();
            let r2 = gcode::write_all(&p, o, &mut par, None, true);
            assert_eq!(r1, r2);
            assert_eq!(r1.is_err(), d == Dialect::LinuxCnc);
            assert!(one.len() > 1 << 20);
            assert!(par == one, "{d:?} text differs");
        }
    }

    fn f(v: f64, decimals: u32, tp: bool, plus: bool, nlz: bool) -> String {
        let mut o = Vec::new();
        NumFmt {
            decimals,
            trailing_point: tp,
            plus,
            no_leading_zero: nlz,
        }
        .push(&mut o, v);
        String::from_utf8(o).expect("ascii")
    }

    #[test]
    fn formats_numbers() {
        assert_eq!(f(12.5, 4, false, false, false), "12.5");
        assert_eq!(f(-0.25, 4, false, false, true), "-.25");
        assert_eq!(f(3.0, 4, true, false, false), "3.");
        assert_eq!(f(-0.00001, 4, false, false, false), "0");
        assert_eq!(f(1.23456789, 4, false, true, false), "+1.2346");
        assert_eq!(f(-120.2591, 4, false, false, false), "-120.2591");
        assert_eq!(f(0.0, 3, true, false, true), "0.");
    }
}
