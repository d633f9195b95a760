//! APT/CL back end (ISO 4343 style): `CUTTER/` with seven values, `LOADTL/`,
//! `FEDRAT/f,MMPM`, `RAPID`, `MULTAX/ON` with six-value GOTOs, seven-value `CIRCLE/`,
//! `CYCLE/…`/`CYCLE/OFF`, frames as NX-style `MSYS/`. Reading the output again gives
//! the same moves. A GOTO names x, y and z: a move from or to an unknown position,
//! machine rotary angles without a tool axis and G-code machine words cannot be
//! said in APT and stop the writer at their line (with `lossy`: a `PPRINT`).

use super::{
    events_before_tool, first_event_at, lossy, maybe_flush, room, write_runs, NumFmt, Run, Sink,
    WriteError, WriteOptions, Written, PARALLEL_MIN,
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

/// Writes the program as APT/CL.
pub fn write_apt(p: &Program, o: WriteOptions, out: &mut Vec<u8>) -> Result<Written, WriteError> {
    write_apt_to(p, o, out, None)
}

/// [`write_apt`], handing the text to `sink` as it grows (see [`Sink`]).
pub fn write_apt_to(
    p: &Program,
    o: WriteOptions,
    out: &mut Vec<u8>,
    sink: Option<Sink>,
) -> Result<Written, WriteError> {
    write_all(p, o, out, sink, true)
}

/// What every move of the APT writer needs to know of the program and options.
#[derive(Clone, Copy)]
struct Ctx<'a> {
    p: &'a Program,
    o: WriteOptions,
    /// Output units per mm.
    k: f64,
}

/// [`write_apt_to`]; `parallel: false` writes every operation in one pass (the
/// reference the parallel writer is tested against).
pub(super) fn write_all(
    p: &Program,
    o: WriteOptions,
    out: &mut Vec<u8>,
    mut sink: Option<Sink>,
    parallel: bool,
) -> Result<Written, WriteError> {
    let o = o.resolved(p);
    let cx = Ctx {
        p,
        o,
        k: 1.0 / o.unit().mm(),
    };
    let k = cx.k;
    let mut warnings = Vec::new();
    out.reserve(room(p.move_count(), 36, &sink));
    text_line(
        out,
        &format!("PARTNO {}", p.name.as_deref().unwrap_or("MILLPLAN")),
    );
    text_line(
        out,
        if o.unit() == LengthUnit::Inch {
            "UNITS/INCHES"
        } else {
            "UNITS/MM"
        },
    );
    let mut st = State::default();
    for op in &p.operations {
        if let Some(n) = &op.name {
            text_line(out, &format!("PPRINT OPERATION NAME : {n}"));
        }
        let before = events_before_tool(op);
        let mut ev0 = 0;
        write_events_until(out, cx, op, 0, &mut ev0, before, &mut st, &mut warnings)?;
        if let Some(t) = &op.tool {
            if let Some(c) = &t.cutter {
                list(
                    out,
                    "CUTTER",
                    &[
                        (c.d * k, COORD),
                        (c.r * k, COORD),
                        (c.e * k, COORD),
                        (c.f * k, COORD),
                        (c.alpha.to_degrees(), COORD),
                        (c.beta.to_degrees(), COORD),
                        (c.h * k, COORD),
                    ],
                );
            }
            if let Some(n) = t.number {
                text_line(out, &format!("LOADTL/{n}"));
            }
            if let Some(n) = &t.name {
                text_line(out, &format!("PPRINT TOOL NAME : {n}"));
            }
            st.tool_number = t.number;
        }
        if let Some(f) = &op.frame {
            st.framed = true;
            let (og, x, y) = (f.origin * k, f.rot.x_axis, f.rot.y_axis);
            list(
                out,
                "MSYS",
                &[
                    (og.x, COORD),
                    (og.y, COORD),
                    (og.z, COORD),
                    (x.x, VECT),
                    (x.y, VECT),
                    (x.z, VECT),
                    (y.x, VECT),
                    (y.y, VECT),
                    (y.z, VECT),
                ],
            );
        } else if std::mem::take(&mut st.framed) {
            // Back to part coordinates after an earlier operation's frame.
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
        if let Some(s) = known(op.start) {
            let s = s * k;
            list(out, "FROM", &[(s.x, COORD), (s.y, COORD), (s.z, COORD)]);
        }
        st.feed = None;
        st.spindle = None;
        st.cycle = None;
        let n = op.moves.len();
        let mut ev = if parallel && n >= PARALLEL_MIN {
            write_runs(n, &mut st, out, &mut sink, &mut warnings, |a, b, mut s| {
                // GOTO with SPINDL and FEDRAT lines: under 96 bytes a move.
                let mut text = Vec::with_capacity((b - a) * 96);
                let mut ev = first_event_at(&op.events, a).max(before);
                let mut result = Ok(());
                let mut w = Vec::new();
                for i in a..b {
                    if let Err(e) = write_move(&mut text, cx, op, i, &mut ev, &mut s, &mut w) {
                        result = Err(e);
                        break;
                    }
                }
                Run {
                    text,
                    end: s,
                    result,
                    warnings: w,
                }
            })?;
            first_event_at(&op.events, n)
        } else {
            let mut ev = before;
            for i in 0..n {
                maybe_flush(out, &mut sink)?;
                write_move(out, cx, op, i, &mut ev, &mut st, &mut warnings)?;
            }
            ev
        };
        if st.cycle.is_some() {
            text_line(out, "CYCLE/OFF");
            st.cycle = None;
        }
        write_events(out, cx, op, n, &mut ev, &mut st, &mut warnings)?;
    }
    text_line(out, "FINI");
    Ok(warnings)
}

/// What the APT writer remembers from move to move.
#[derive(Clone, Debug, Default, PartialEq)]
struct State {
    feed: Option<(f64, FeedMode)>,
    spindle: Option<f64>,
    cycle: Option<CycleId>,
    multax: bool,
    tool_number: Option<u32>,
    tlc: bool,
    /// A frame other than the part's is in effect.
    framed: bool,
}

/// The events due before move `i` (`ev`: the next event).
fn write_events(
    out: &mut Vec<u8>,
    cx: Ctx,
    op: &Operation,
    i: usize,
    ev: &mut usize,
    st: &mut State,
    warnings: &mut Written,
) -> Result<(), WriteError> {
    write_events_until(out, cx, op, i, ev, op.events.len(), st, warnings)
}

/// [`write_events`] up to event `limit` (exclusive).
#[allow(clippy::too_many_arguments)]
fn write_events_until(
    out: &mut Vec<u8>,
    cx: Ctx,
    op: &Operation,
    i: usize,
    ev: &mut usize,
    limit: usize,
    st: &mut State,
    warnings: &mut Written,
) -> Result<(), WriteError> {
    while *ev < limit && op.events[*ev].at as usize <= i {
        let e = &op.events[*ev];
        *ev += 1;
        match &e.kind {
            EventKind::Comment(t) => text_line(out, &format!("PPRINT {t}")),
            EventKind::Insert(t) => text_line(out, &format!("INSERT/{t}")),
            EventKind::Spindle(dir) => match dir {
                SpindleDir::Off => text_line(out, "SPINDL/OFF"),
                d => {
                    let rpm = op
                        .moves
                        .get(i)
                        .map(|m| m.spindle)
                        .filter(|s| *s > 0.0)
                        .or(st.spindle);
                    out.extend_from_slice(b"SPINDL/");
                    if let Some(r) = rpm {
                        num(out, COORD, r);
                        out.extend_from_slice(b",RPM,");
                    }
                    text_line(out, if *d == SpindleDir::Ccw { "CCLW" } else { "CLW" });
                    st.spindle = rpm;
                }
            },
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
            EventKind::CutCom { side, register } => {
                if let Some(r) = register.filter(|r| Some(*r) != st.tool_number) {
                    lossy(
                        cx.o.lossy,
                        warnings,
                        e.line,
                        format!("APT has no cutter-compensation register (D{r})"),
                    )?;
                }
                text_line(
                    out,
                    match side {
                        CutCom::Off => "CUTCOM/OFF",
                        CutCom::Left => "CUTCOM/LEFT",
                        CutCom::Right => "CUTCOM/RIGHT",
                    },
                )
            }
            // CL data are tool-tip positions: length compensation and tool-centre
            // control are what they mean already; only switching compensation
            // off cannot be said.
            EventKind::ToolLength(ToolLength::On { .. }) => st.tlc = true,
            EventKind::ToolLength(ToolLength::Off) => {
                if st.tlc {
                    lossy(
                        cx.o.lossy,
                        warnings,
                        e.line,
                        "APT cannot switch tool-length compensation off".to_string(),
                    )?;
                    text_line(out, "PPRINT tool-length compensation off");
                }
                st.tlc = false;
            }
            EventKind::Tcp(_) => {}
            EventKind::WorkOffset(WorkOffset(n)) => {
                lossy(
                    cx.o.lossy,
                    warnings,
                    e.line,
                    format!("APT has no work offsets (work offset {n})"),
                )?;
                text_line(out, &format!("PPRINT work offset {n}"));
            }
            EventKind::ToolSelect(n) => text_line(out, &format!("SELECT/TOOL,{n}")),
            EventKind::Stop { optional } => {
                text_line(out, if *optional { "OPSTOP" } else { "STOP" })
            }
            EventKind::Dwell(t) => list(out, "DELAY", &[(*t, COORD)]),
            EventKind::PathControl(pc) => {
                let what = crate::text::path_control_name(pc);
                lossy(
                    cx.o.lossy,
                    warnings,
                    e.line,
                    format!("APT has no path-control mode (`{what}`)"),
                )?;
                text_line(out, &format!("PPRINT path control: {what}"));
            }
            EventKind::Passthrough(pt) => {
                let same_unit = cx.o.unit() == cx.p.units.source || super::unit_free(&pt.text);
                if cx.p.source.is_apt() && same_unit {
                    text_line(out, &pt.text);
                } else if pt.class == PassClass::Info {
                    text_line(out, &format!("PPRINT {}", pt.text));
                } else {
                    lossy(
                        cx.o.lossy,
                        warnings,
                        e.line,
                        if cx.p.source.is_apt() {
                            format!(
                                "`{}` is copied as written, and its numbers are in {:?}: write the program in {:?} (--out-units)",
                                pt.text, cx.p.units.source, cx.p.units.source
                            )
                        } else {
                            format!(
                                "`{}` ({}) has no APT equivalent",
                                pt.text,
                                cx.p.source.name()
                            )
                        },
                    )?;
                    text_line(out, &format!("PPRINT not written: {}", pt.text));
                }
            }
        }
    }
    Ok(())
}

/// Move `i` of `op`, after the events due before it (`ev`: the next event).
fn write_move(
    out: &mut Vec<u8>,
    cx: Ctx,
    op: &Operation,
    i: usize,
    ev: &mut usize,
    st: &mut State,
    warnings: &mut Written,
) -> Result<(), WriteError> {
    let k = cx.k;
    let m = &op.moves[i];
    write_events(out, cx, op, i, ev, st, warnings)?;
    let Some(e) = known(m.end) else {
        lossy(
            cx.o.lossy,
            warnings,
            m.line,
            "APT cannot express a move from or to an unknown position (a GOTO names x, y and z)"
                .to_string(),
        )?;
        text_line(out, "PPRINT move with an unknown coordinate not written");
        return Ok(());
    };
    let e = e * k;
    if m.spindle > 0.0 && st.spindle != Some(m.spindle) && m.is_cutting() {
        out.extend_from_slice(b"SPINDL/");
        num(out, COORD, m.spindle);
        text_line(out, ",RPM,CLW");
        st.spindle = Some(m.spindle);
    }
    if let MoveKind::Cycle(id) = m.kind {
        if st.cycle != Some(id) {
            let c = op
                .cycles
                .get(id.index())
                .ok_or_else(|| WriteError::new(m.line, "cycle id out of range"))?;
            super::check_pecks(c)?;
            let name = super::apt_cycle_name(c).replace(',', " ");
            out.extend_from_slice(format!("CYCLE/{name},FEDTO,").as_bytes());
            num(out, COORD, -c.bottom * k);
            out.extend_from_slice(b",RAPTO,");
            num(out, COORD, c.clearance * k);
            out.extend_from_slice(b",RTRCTO,");
            num(out, COORD, c.retract * k);
            out.extend_from_slice(if cx.o.unit() == LengthUnit::Inch {
                b",IPM,".as_slice()
            } else {
                b",MMPM,"
            });
            num(out, COORD, c.feed * k);
            if let Some(q) = c.peck {
                out.extend_from_slice(b",STEP,");
                num(out, COORD, q * k);
            }
            if let Some(q) = c.peck_next {
                out.extend_from_slice(b",SUBPECK,");
                num(out, COORD, q * k);
            }
            if let Some(t) = c.dwell {
                out.extend_from_slice(b",DWELL,");
                num(out, COORD, t);
            }
            out.push(b'\n');
            st.cycle = Some(id);
        }
    } else if st.cycle.is_some() {
        text_line(out, "CYCLE/OFF");
        st.cycle = None;
    }
    match m.kind {
        MoveKind::Rapid => text_line(out, "RAPID"),
        MoveKind::Linear | MoveKind::Arc(_) => {
            let feed = if m.feed_mode == FeedMode::InverseTime {
                m.feed
            } else {
                m.feed * k
            };
            if st.feed != Some((feed, m.feed_mode)) {
                out.extend_from_slice(b"FEDRAT/");
                num(out, COORD, feed);
                let inch = cx.o.unit() == LengthUnit::Inch;
                text_line(
                    out,
                    match (m.feed_mode, inch) {
                        (FeedMode::PerMinute, false) => ",MMPM",
                        (FeedMode::PerMinute, true) => ",IPM",
                        (FeedMode::PerRev, false) => ",MMPR",
                        (FeedMode::PerRev, true) => ",IPR",
                        (FeedMode::InverseTime, _) => ",INVERS",
                    },
                );
                st.feed = Some((feed, m.feed_mode));
            }
            if let MoveKind::Arc(id) = m.kind {
                let a = op
                    .arcs
                    .get(id.index())
                    .ok_or_else(|| WriteError::new(m.line, "arc id out of range"))?;
                // Under an `MSYS` the axis in the absolute frame, as NX
                // writes it (and the reader reads it); the centre local.
                let normal = op.frame.map_or(a.normal, |f| f.rot * a.normal);
                list(
                    out,
                    "CIRCLE",
                    &[
                        (a.centre.x * k, COORD),
                        (a.centre.y * k, COORD),
                        (a.centre.z * k, COORD),
                        (normal.x, VECT),
                        (normal.y, VECT),
                        (normal.z, VECT),
                        (a.radius * k, COORD),
                    ],
                );
            }
        }
        MoveKind::Cycle(_) => {}
    }
    let orient = op.orient(m);
    match orient.and_then(|o| o.axis) {
        Some(v) => {
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
        None => {
            if let Some(o) = orient.filter(|o| o.has_angles()) {
                let f = |x: Option<f64>| {
                    x.map(|v| format!("{:.4}", v.to_degrees()))
                        .unwrap_or("-".into())
                };
                lossy(
                    cx.o.lossy,
                    warnings,
                    m.line,
                    "APT cannot express machine rotary-axis positions without the machine's kinematics (--machine)".to_string(),
                )?;
                text_line(
                    out,
                    &format!(
                        "PPRINT MACHINE ANGLES A {} B {} C {}",
                        f(o.angles[0]),
                        f(o.angles[1]),
                        f(o.angles[2])
                    ),
                );
            }
            if st.multax {
                text_line(out, "MULTAX/OFF");
                st.multax = false;
            }
            list(out, "GOTO", &[(e.x, COORD), (e.y, COORD), (e.z, COORD)]);
        }
    }
    Ok(())
}
