//! APT/CL back end (ISO 4343 style): `CUTTER/` with seven values, `LOADTL/`,
//! `FEDRAT/f,MMPM`, `RAPID`, `MULTAX/ON` with six-value GOTOs, seven-value `CIRCLE/`,
//! `CYCLE/…`/`CYCLE/OFF`, frames as NX-style `MSYS/`. Reading the output again gives
//! the same moves.

use super::{
    first_event_at, maybe_flush, room, write_runs, NumFmt, Run, Sink, WriteError, PARALLEL_MIN,
};
use crate::ir::*;

const COORD: NumFmt = NumFmt {
    decimals: 6,
    trailing_point: false,
    plus: false,
    no_leading_zero: false,
};
const VECT: NumFmt = NumFmt {
    decimals: 9,
    trailing_point: false,
    plus: false,
    no_leading_zero: false,
};

fn num(out: &mut Vec<u8>, f: NumFmt, v: f64) {
    f.push(out, v);
}

fn list(out: &mut Vec<u8>, major: &str, vals: &[(f64, NumFmt)]) {
    out.extend_from_slice(major.as_bytes());
    out.push(b'/');
    for (i, (v, f)) in vals.iter().enumerate() {
        if i > 0 {
            out.push(b',');
        }
        num(out, *f, *v);
    }
    out.push(b'\n');
}

fn text_line(out: &mut Vec<u8>, s: &str) {
    out.extend_from_slice(s.as_bytes());
    out.push(b'\n');
}

/// Writes the program as APT/CL in millimetres.
pub fn write_apt(p: &Program, out: &mut Vec<u8>) -> Result<(), WriteError> {
    write_apt_to(p, out, None)
}

/// [`write_apt`], handing the text to `sink` as it grows (see [`Sink`]).
pub fn write_apt_to(p: &Program, out: &mut Vec<u8>, sink: Option<Sink>) -> Result<(), WriteError> {
    write_all(p, out, sink, true)
}

/// [`write_apt_to`]; `parallel: false` writes every operation in one pass (the
/// reference the parallel writer is tested against).
pub(super) fn write_all(
    p: &Program,
    out: &mut Vec<u8>,
    mut sink: Option<Sink>,
    parallel: bool,
) -> Result<(), WriteError> {
    out.reserve(room(p.move_count(), 36, &sink));
    text_line(
        out,
        &format!("PARTNO {}", p.name.as_deref().unwrap_or("MILLPLAN")),
    );
    text_line(out, "UNITS/MM");
    let mut st = State::default();
    for op in &p.operations {
        if let Some(n) = &op.name {
            text_line(out, &format!("PPRINT OPERATION NAME : {n}"));
        }
        if let Some(t) = &op.tool {
            if let Some(c) = &t.cutter {
                list(
                    out,
                    "CUTTER",
                    &[
                        (c.d, COORD),
                        (c.r, COORD),
                        (c.e, COORD),
                        (c.f, COORD),
                        (c.alpha.to_degrees(), COORD),
                        (c.beta.to_degrees(), COORD),
                        (c.h, COORD),
                    ],
                );
            }
            if let Some(n) = t.number {
                text_line(out, &format!("LOADTL/{n}"));
            }
            if let Some(n) = &t.name {
                text_line(out, &format!("PPRINT TOOL NAME : {n}"));
            }
        }
        if let Some(f) = &op.frame {
            let (o, x, y) = (f.origin, f.rot.x_axis, f.rot.y_axis);
            list(
                out,
                "MSYS",
                &[
                    (o.x, COORD),
                    (o.y, COORD),
                    (o.z, COORD),
                    (x.x, VECT),
                    (x.y, VECT),
                    (x.z, VECT),
                    (y.x, VECT),
                    (y.y, VECT),
                    (y.z, VECT),
                ],
            );
        } else if p.operations.len() > 1 {
            // Make the frame explicit so a frame of an earlier operation does not carry over.
            list(
                out,
                "MSYS",
                &[
                    (0.0, COORD),
                    (0.0, COORD),
                    (0.0, COORD),
                    (1.0, VECT),
                    (0.0, VECT),
                    (0.0, VECT),
                    (0.0, VECT),
                    (1.0, VECT),
                    (0.0, VECT),
                ],
            );
        }
        if let Some(s) = op.start {
            list(out, "FROM", &[(s.x, COORD), (s.y, COORD), (s.z, COORD)]);
        }
        st.feed = None;
        st.spindle = None;
        st.cycle = None;
        let n = op.moves.len();
        let ev = if parallel && n >= PARALLEL_MIN {
            write_runs(n, &mut st, out, &mut sink, |a, b, mut s| {
                // GOTO with SPINDL and FEDRAT lines: under 96 bytes a move.
                let mut text = Vec::with_capacity((b - a) * 96);
                let mut ev = first_event_at(&op.events, a);
                let mut result = Ok(());
                for i in a..b {
                    if let Err(e) = write_move(&mut text, p, op, i, &mut ev, &mut s) {
                        result = Err(e);
                        break;
                    }
                }
                Run {
                    text,
                    end: s,
                    result,
                }
            })?;
            first_event_at(&op.events, n)
        } else {
            let mut ev = 0;
            for i in 0..n {
                maybe_flush(out, &mut sink)?;
                write_move(out, p, op, i, &mut ev, &mut st)?;
            }
            ev
        };
        if st.cycle.is_some() {
            text_line(out, "CYCLE/OFF");
        }
        for e in &op.events[ev..] {
            match &e.kind {
                EventKind::Comment(t) => text_line(out, &format!("PPRINT {t}")),
                EventKind::Insert(t) => text_line(out, &format!("INSERT/{t}")),
                EventKind::Spindle {
                    dir: SpindleDir::Off,
                    ..
                } => text_line(out, "SPINDL/OFF"),
                EventKind::Coolant(Coolant::Off) => text_line(out, "COOLNT/OFF"),
                EventKind::Passthrough { text, .. } if p.dialect.is_apt() => text_line(out, text),
                EventKind::Passthrough { text, .. } => text_line(out, &format!("PPRINT {text}")),
                _ => {}
            }
        }
    }
    text_line(out, "FINI");
    Ok(())
}

/// What the APT writer remembers from move to move.
#[derive(Clone, Debug, Default, PartialEq)]
struct State {
    feed: Option<(f64, FeedMode)>,
    spindle: Option<f64>,
    cycle: Option<u32>,
    multax: bool,
}

/// Move `i` of `op`, after the events due before it (`ev`: the next event).
fn write_move(
    out: &mut Vec<u8>,
    p: &Program,
    op: &Operation,
    i: usize,
    ev: &mut usize,
    st: &mut State,
) -> Result<(), WriteError> {
    let m = &op.moves[i];
    while *ev < op.events.len() && op.events[*ev].at as usize <= i {
        let e = &op.events[*ev];
        *ev += 1;
        match &e.kind {
            EventKind::Comment(t) => text_line(out, &format!("PPRINT {t}")),
            EventKind::Insert(t) => text_line(out, &format!("INSERT/{t}")),
            EventKind::Spindle { rpm, dir } => {
                match dir {
                    SpindleDir::Off => text_line(out, "SPINDL/OFF"),
                    d => {
                        out.extend_from_slice(b"SPINDL/");
                        num(out, COORD, *rpm);
                        text_line(
                            out,
                            if *d == SpindleDir::Ccw {
                                ",RPM,CCLW"
                            } else {
                                ",RPM,CLW"
                            },
                        );
                    }
                }
                st.spindle = Some(*rpm);
            }
            EventKind::Coolant(c) => text_line(
                out,
                match c {
                    Coolant::Off => "COOLNT/OFF",
                    Coolant::Flood => "COOLNT/FLOOD",
                    Coolant::Mist => "COOLNT/MIST",
                    Coolant::Through => "COOLNT/THRU",
                    Coolant::Air => "COOLNT/AIR",
                },
            ),
            EventKind::CutCom(c) => text_line(
                out,
                match c {
                    CutCom::Off => "CUTCOM/OFF",
                    CutCom::Left => "CUTCOM/LEFT",
                    CutCom::Right => "CUTCOM/RIGHT",
                },
            ),
            EventKind::Stop { optional } => {
                text_line(out, if *optional { "OPSTOP" } else { "STOP" })
            }
            EventKind::Dwell(t) => list(out, "DELAY", &[(*t, COORD)]),
            EventKind::Passthrough { text, .. } => {
                if p.dialect.is_apt() {
                    text_line(out, text);
                } else {
                    text_line(out, &format!("PPRINT {text}"));
                }
            }
        }
    }
    if m.spindle > 0.0 && st.spindle != Some(m.spindle) && m.is_cutting() {
        out.extend_from_slice(b"SPINDL/");
        num(out, COORD, m.spindle);
        text_line(out, ",RPM,CLW");
        st.spindle = Some(m.spindle);
    }
    if m.kind == MoveKind::Cycle {
        if st.cycle != Some(m.aux) {
            let c = op.cycles.get(m.aux as usize).ok_or_else(|| WriteError {
                message: "st.cycle index out of range".into(),
            })?;
            out.extend_from_slice(format!("CYCLE/{},FEDTO,", c.name.replace(',', " ")).as_bytes());
            num(out, COORD, -c.bottom);
            out.extend_from_slice(b",RAPTO,");
            num(out, COORD, c.clearance);
            out.extend_from_slice(b",RTRCTO,");
            num(out, COORD, c.retract);
            out.extend_from_slice(b",MMPM,");
            num(out, COORD, c.feed);
            if let Some(q) = c.peck {
                out.extend_from_slice(b",STEP,");
                num(out, COORD, q);
            }
            if let Some(t) = c.dwell {
                out.extend_from_slice(b",DWELL,");
                num(out, COORD, t);
            }
            out.push(b'\n');
            st.cycle = Some(m.aux);
        }
    } else if st.cycle.is_some() {
        text_line(out, "CYCLE/OFF");
        st.cycle = None;
    }
    match m.kind {
        MoveKind::Rapid => text_line(out, "RAPID"),
        MoveKind::Linear | MoveKind::Arc => {
            if st.feed != Some((m.feed, m.feed_mode)) {
                out.extend_from_slice(b"FEDRAT/");
                num(out, COORD, m.feed);
                text_line(
                    out,
                    match m.feed_mode {
                        FeedMode::PerMinute => ",MMPM",
                        FeedMode::PerRev => ",MMPR",
                        FeedMode::InverseTime => ",INVERS",
                    },
                );
                st.feed = Some((m.feed, m.feed_mode));
            }
            if m.kind == MoveKind::Arc {
                let a = op.arcs.get(m.aux as usize).ok_or_else(|| WriteError {
                    message: "arc index out of range".into(),
                })?;
                list(
                    out,
                    "CIRCLE",
                    &[
                        (a.centre.x, COORD),
                        (a.centre.y, COORD),
                        (a.centre.z, COORD),
                        (a.normal.x, VECT),
                        (a.normal.y, VECT),
                        (a.normal.z, VECT),
                        (a.radius, COORD),
                    ],
                );
            }
        }
        MoveKind::Cycle => {}
    }
    let e = m.end;
    match op.orient(m) {
        Some(Orient::Vector(v)) => {
            if !st.multax {
                text_line(out, "MULTAX/ON");
                st.multax = true;
            }
            list(
                out,
                "GOTO",
                &[
                    (e.x, COORD),
                    (e.y, COORD),
                    (e.z, COORD),
                    (v.x, VECT),
                    (v.y, VECT),
                    (v.z, VECT),
                ],
            );
        }
        Some(Orient::Rotary(r)) => {
            let f = |x: Option<f64>| {
                x.map(|v| format!("{:.4}", v.to_degrees()))
                    .unwrap_or("-".into())
            };
            text_line(
                out,
                &format!(
                    "PPRINT MACHINE ANGLES A {} B {} C {}",
                    f(r[0]),
                    f(r[1]),
                    f(r[2])
                ),
            );
            list(out, "GOTO", &[(e.x, COORD), (e.y, COORD), (e.z, COORD)]);
        }
        None => {
            if st.multax {
                text_line(out, "MULTAX/OFF");
                st.multax = false;
            }
            list(out, "GOTO", &[(e.x, COORD), (e.y, COORD), (e.z, COORD)]);
        }
    }
    Ok(())
}
