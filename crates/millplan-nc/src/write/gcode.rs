//! G-code back end for ISO/Fanuc, LinuxCNC, Sinumerik and Heidenhain plain language.
//!
//! A small explicit subset per target: header (units, plane, absolute, feed mode),
//! tool change, spindle, then G0/G1/G2/G3 (or L/CC/C) with fixed decimals, `S` and
//! `F` on a block wherever the IR changes them, and a footer. Arcs outside the
//! principal planes and canned cycles are written as explicit lines.

use super::{
    arc_points, cycle_moves, first_event_at, maybe_flush, principal_plane, room, write_runs,
    NumFmt, Run, Sink, WriteError, PARALLEL_MIN,
};
use crate::ir::*;
use millplan_geom::DVec3;

/// Writer settings.
#[derive(Clone, Copy, Debug)]
pub struct GcodeOptions {
    pub dialect: Dialect,
    /// Output unit (values in the IR are mm).
    pub unit: LengthUnit,
    /// Block numbers (always on for Heidenhain).
    pub line_numbers: bool,
    /// Chord tolerance (mm) for arcs that must be written as lines.
    pub chord_tol: f64,
}

impl GcodeOptions {
    pub fn new(dialect: Dialect) -> GcodeOptions {
        GcodeOptions {
            dialect,
            unit: LengthUnit::Mm,
            line_numbers: false,
            chord_tol: 0.001,
        }
    }
}

struct W<'a> {
    o: GcodeOptions,
    out: &'a mut Vec<u8>,
    k: f64,
    coord: NumFmt,
    vecf: NumFmt,
    feedf: NumFmt,
    src_dialect: Dialect,
    st: State,
}

/// Everything the writer remembers from block to block: what it writes next
/// depends only on this, the options and the program.
#[derive(Clone, Debug, PartialEq)]
struct State {
    block_no: u64,
    pos: [Option<f64>; 3],
    rot: [Option<f64>; 3],
    vec: Option<DVec3>,
    motion: Option<u8>,
    plane: Option<usize>,
    feed: Option<f64>,
    spindle: Option<f64>,
    spindle_running: bool,
    spindle_dir: SpindleDir,
    cutcom: CutCom,
    heidenhain_rl: &'static str,
    tool_number: Option<u32>,
    fmax_last: bool,
}

fn is_5axis(op: &Operation) -> bool {
    op.orients.iter().any(|o| match o {
        Orient::Vector(v) => (v.z - 1.0).abs() > 1e-9,
        Orient::Rotary(_) => false,
    })
}

impl W<'_> {
    fn hh(&self) -> bool {
        self.o.dialect == Dialect::Heidenhain
    }

    fn start_block(&mut self) {
        if self.hh() {
            let s = self.st.block_no.to_string();
            self.out.extend_from_slice(s.as_bytes());
            self.out.push(b' ');
            self.st.block_no += 1;
        } else if self.o.line_numbers {
            self.st.block_no += 10;
            let s = format!("N{} ", self.st.block_no);
            self.out.extend_from_slice(s.as_bytes());
        }
    }

    fn line(&mut self, text: &str) {
        self.start_block();
        self.out.extend_from_slice(text.as_bytes());
        self.out.push(b'\n');
    }

    fn comment(&mut self, text: &str) {
        let clean: String = text
            .chars()
            .map(|c| {
                if c == '(' || c == ')' || c == '\n' {
                    ' '
                } else {
                    c
                }
            })
            .collect();
        match self.o.dialect {
            Dialect::Sinumerik => self.line(&format!("; {clean}")),
            Dialect::Heidenhain => self.line(&format!("; {clean}")),
            _ => {
                let t = format!("({})", clean.trim());
                if self.o.line_numbers {
                    self.line(&t);
                } else {
                    self.out.extend_from_slice(t.as_bytes());
                    self.out.push(b'\n');
                }
            }
        }
    }

    fn word(&mut self, letter: &str, v: f64, f: NumFmt) {
        self.out.push(b' ');
        self.out.extend_from_slice(letter.as_bytes());
        f.push(self.out, v);
    }

    fn end_block(&mut self) {
        self.out.push(b'\n');
    }

    fn header(&mut self, p: &Program) {
        let name = p.name.clone().unwrap_or_else(|| "MILLPLAN".to_string());
        let name: String = name
            .chars()
            .filter(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect::<String>();
        let name = if name.is_empty() {
            "MILLPLAN".to_string()
        } else {
            name
        };
        let inch = self.o.unit == LengthUnit::Inch;
        match self.o.dialect {
            Dialect::Heidenhain => {
                self.line(&format!(
                    "BEGIN PGM {name} {}",
                    if inch { "INCH" } else { "MM" }
                ));
            }
            Dialect::Sinumerik => {
                self.comment(&format!("{name} - written by millplan"));
                self.line(&format!(
                    "G17 {} G90 G94 G40 G64",
                    if inch { "G70" } else { "G71" }
                ));
            }
            Dialect::LinuxCnc => {
                self.out.extend_from_slice(b"%\n");
                self.comment(&format!("{name} - written by millplan"));
                self.line(&format!(
                    "G17 {} G90 G94 G40 G49 G80",
                    if inch { "G20" } else { "G21" }
                ));
            }
            _ => {
                self.out.extend_from_slice(b"%\n");
                self.out
                    .extend_from_slice(format!("O0001 ({name})\n").as_bytes());
                self.comment("written by millplan");
                self.line(&format!(
                    "G17 {} G90 G94 G40 G49 G80",
                    if inch { "G20" } else { "G21" }
                ));
            }
        }
        self.st.plane = Some(2);
    }

    fn footer(&mut self, p: &Program) {
        match self.o.dialect {
            Dialect::Heidenhain => {
                if self.st.spindle_running {
                    self.line("M5");
                }
                self.line("M30");
                let name = p.name.clone().unwrap_or_else(|| "MILLPLAN".to_string());
                let name: String = name
                    .chars()
                    .filter(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                let name = if name.is_empty() {
                    "MILLPLAN".to_string()
                } else {
                    name
                };
                let unit = if self.o.unit == LengthUnit::Inch {
                    "INCH"
                } else {
                    "MM"
                };
                self.line(&format!("END PGM {name} {unit}"));
            }
            _ => {
                if self.st.spindle_running {
                    self.line("M5");
                }
                self.line("M30");
                if self.o.dialect != Dialect::Sinumerik {
                    self.out.extend_from_slice(b"%\n");
                }
            }
        }
    }

    fn tool_change(&mut self, op: &Operation, five: bool) -> Result<(), WriteError> {
        let Some(t) = &op.tool else { return Ok(()) };
        if let Some(c) = &t.cutter {
            self.comment(&format!(
                "TOOL {} {:?} D{:.3} R{:.3}",
                t.name.as_deref().unwrap_or(""),
                c.kind,
                c.d * self.k,
                c.r * self.k
            ));
        }
        let s0 = op.moves.iter().find(|m| m.spindle > 0.0).map(|m| m.spindle);
        match (self.o.dialect, t.number, &t.name) {
            (Dialect::Heidenhain, n, name) => {
                let id = match (n, name) {
                    (Some(n), _) => n.to_string(),
                    (None, Some(nm)) => format!("\"{nm}\""),
                    (None, None) => {
                        self.comment("no tool call in the source program");
                        return Ok(());
                    }
                };
                let s = s0
                    .map(|s| format!(" S{}", crate::gcode::fmt_num((s * 1000.0).round() / 1000.0)))
                    .unwrap_or_default();
                self.line(&format!("TOOL CALL {id} Z{s}"));
                self.st.spindle = s0;
                if five {
                    self.line("M128");
                }
            }
            (Dialect::Sinumerik, n, name) => {
                match (name, n) {
                    (Some(nm), _) => self.line(&format!("T=\"{nm}\"")),
                    (None, Some(n)) => self.line(&format!("T{n}")),
                    (None, None) => {
                        self.comment("no tool call in the source program");
                        return Ok(());
                    }
                }
                self.line("M6");
                self.line("D1");
                if five {
                    self.line("TRAORI");
                    self.line("ORIWKS");
                }
            }
            (d, Some(n), _) => {
                self.line(&format!("T{n} M6"));
                if d == Dialect::LinuxCnc {
                    self.line(&format!("G43 H{n}"));
                } else if five {
                    self.line(&format!("G43.5 H{n}"));
                } else {
                    self.line(&format!("G43 H{n}"));
                }
                self.st.tool_number = Some(n);
            }
            (_, None, Some(nm)) => {
                self.comment(&format!("load tool {nm}: the source names no tool number"));
                self.line("M0");
            }
            (_, None, None) => self.comment("no tool call in the source program"),
        }
        // Positions are unknown to the control after a tool change.
        self.st.pos = [None; 3];
        self.st.rot = [None; 3];
        self.st.vec = None;
        self.st.motion = None;
        self.st.feed = None;
        Ok(())
    }

    fn spindle_block(&mut self, rpm: f64, dir: SpindleDir) {
        let m = match dir {
            SpindleDir::Cw => "M3",
            SpindleDir::Ccw => "M4",
            SpindleDir::Off => "M5",
        };
        if self.hh() {
            if dir != SpindleDir::Off && Some(rpm) != self.st.spindle && rpm > 0.0 {
                self.line(&format!("TOOL CALL S{}", crate::gcode::fmt_num(rpm)));
            }
            self.line(m);
        } else if dir == SpindleDir::Off {
            self.line("M5");
        } else {
            self.start_block();
            self.out.push(b'S');
            NumFmt {
                decimals: 1,
                trailing_point: false,
                plus: false,
                no_leading_zero: false,
            }
            .push(self.out, rpm);
            self.out.push(b' ');
            self.out.extend_from_slice(m.as_bytes());
            self.end_block();
        }
        self.st.spindle = Some(rpm);
        self.st.spindle_running = dir != SpindleDir::Off;
        self.st.spindle_dir = dir;
    }

    fn event(&mut self, e: &Event) {
        match &e.kind {
            EventKind::Comment(t) => self.comment(t),
            EventKind::Insert(t) => self.comment(&format!("INSERT {t}")),
            EventKind::Spindle { rpm, dir } => self.spindle_block(*rpm, *dir),
            EventKind::Coolant(c) => {
                let m = match c {
                    Coolant::Off => "M9",
                    Coolant::Mist | Coolant::Air => "M7",
                    _ => "M8",
                };
                self.line(m);
            }
            EventKind::CutCom(c) => {
                self.st.cutcom = *c;
                if self.hh() {
                    self.st.heidenhain_rl = match c {
                        CutCom::Left => " RL",
                        CutCom::Right => " RR",
                        CutCom::Off => " R0",
                    };
                } else {
                    let d = self
                        .st
                        .tool_number
                        .map(|n| format!(" D{n}"))
                        .unwrap_or_default();
                    match c {
                        CutCom::Off => self.line("G40"),
                        CutCom::Left => self.line(&format!("G41{d}")),
                        CutCom::Right => self.line(&format!("G42{d}")),
                    }
                }
            }
            EventKind::Stop { optional } => self.line(match (optional, self.hh()) {
                (false, true) => "STOP",
                (true, true) => "M1",
                (false, false) => "M0",
                (true, false) => "M1",
            }),
            EventKind::Dwell(t) => match self.o.dialect {
                Dialect::Heidenhain => {
                    self.line("CYCL DEF 9.0 DWELL TIME");
                    self.line(&format!("CYCL DEF 9.1 DWELL {t:.3}"));
                }
                Dialect::Sinumerik => self.line(&format!("G4 F{t:.3}")),
                Dialect::LinuxCnc => self.line(&format!("G4 P{t:.3}")),
                _ => self.line(&format!("G4 P{}", (t * 1000.0).round() as i64)),
            },
            EventKind::Passthrough { text, .. } => {
                if self.src_dialect == self.o.dialect {
                    self.line(text);
                } else {
                    self.comment(&format!("kept from source: {text}"));
                }
            }
        }
    }

    fn coords(&mut self, end: DVec3, force: bool) {
        let names = ["X", "Y", "Z"];
        for k in 0..3 {
            let v = end[k] * self.k;
            let r = (v * 1e4).round() / 1e4;
            if force || self.st.pos[k] != Some(r) {
                let f = self.coord;
                self.word(names[k], v, f);
                self.st.pos[k] = Some(r);
            }
        }
    }

    fn orient_words(&mut self, op: &Operation, m: &Move) -> Result<(), WriteError> {
        match op.orient(m) {
            Some(Orient::Rotary(r)) => {
                for (k, a) in r.iter().enumerate() {
                    if let Some(a) = a {
                        let deg = (a.to_degrees() * 1e4).round() / 1e4;
                        if self.st.rot[k] != Some(deg) {
                            let f = NumFmt {
                                decimals: 4,
                                ..self.coord
                            };
                            self.word(["A", "B", "C"][k], deg, f);
                            self.st.rot[k] = Some(deg);
                        }
                    }
                }
            }
            Some(Orient::Vector(v)) if is_5axis(op) && self.st.vec != Some(*v) => {
                let f = self.vecf;
                match self.o.dialect {
                        Dialect::Sinumerik => {
                            self.word("A3=", v.x, f);
                            self.word("B3=", v.y, f);
                            self.word("C3=", v.z, f);
                        }
                        Dialect::Heidenhain => {
                            self.word("TX", v.x, f);
                            self.word("TY", v.y, f);
                            self.word("TZ", v.z, f);
                        }
                        Dialect::LinuxCnc => {
                            return Err(WriteError {
                                message: format!(
                                    "line {}: LinuxCNC cannot take tool vectors; 5-axis output needs the machine's kinematics",
                                    m.line
                                ),
                            })
                        }
                        _ => {
                            self.word("I", v.x, f);
                            self.word("J", v.y, f);
                            self.word("K", v.z, f);
                        }
                    }
                self.st.vec = Some(*v);
            }
            _ => {}
        }
        Ok(())
    }

    fn feed_spindle(&mut self, m: &Move, feed: f64) {
        if !self.hh()
            && m.spindle > 0.0
            && self.st.spindle_running
            && Some(m.spindle) != self.st.spindle
        {
            let f = NumFmt {
                decimals: 1,
                trailing_point: false,
                plus: false,
                no_leading_zero: false,
            };
            self.word("S", m.spindle, f);
            self.st.spindle = Some(m.spindle);
        }
        let f = if m.feed_mode == FeedMode::InverseTime {
            feed
        } else {
            feed * self.k
        };
        if self.st.feed != Some(f) || self.st.fmax_last {
            let ff = self.feedf;
            self.word("F", f, ff);
            self.st.feed = Some(f);
        }
    }

    fn motion(&mut self, code: u8) {
        if self.st.motion != Some(code) {
            self.out.extend_from_slice(match code {
                0 => b" G0".as_slice(),
                1 => b" G1",
                2 => b" G2",
                _ => b" G3",
            });
            self.st.motion = Some(code);
        }
    }

    fn linear_block(
        &mut self,
        op: &Operation,
        m: &Move,
        end: DVec3,
        rapid: bool,
        feed: f64,
    ) -> Result<(), WriteError> {
        if self.hh() {
            if !rapid
                && m.spindle > 0.0
                && self.st.spindle_running
                && Some(m.spindle) != self.st.spindle
            {
                self.line(&format!(
                    "TOOL CALL S{}",
                    crate::gcode::fmt_num((m.spindle * 10.0).round() / 10.0)
                ));
                self.st.spindle = Some(m.spindle);
            }
            self.start_block();
            let five_vec = matches!(op.orient(m), Some(Orient::Vector(_))) && is_5axis(op);
            self.out
                .extend_from_slice(if five_vec { b"LN".as_slice() } else { b"L" });
            let start = self.out.len();
            self.coords(end, five_vec);
            if five_vec {
                self.st.vec = None;
            }
            self.orient_words(op, m)?;
            if self.out.len() == start {
                // Heidenhain needs at least one coordinate.
                self.coords(end, true);
            }
            let rl = std::mem::take(&mut self.st.heidenhain_rl);
            self.out.extend_from_slice(rl.as_bytes());
            if rapid {
                self.out.extend_from_slice(b" FMAX");
                self.st.fmax_last = true;
            } else {
                self.feed_spindle(m, feed);
                self.st.fmax_last = false;
            }
            self.end_block();
            return Ok(());
        }
        self.start_block();
        let mark = self.out.len();
        self.motion(if rapid { 0 } else { 1 });
        self.coords(end, false);
        self.orient_words(op, m)?;
        if !rapid {
            self.feed_spindle(m, feed);
        }
        if self.out[mark..].first() == Some(&b' ') {
            self.out.remove(mark);
        }
        self.end_block();
        Ok(())
    }

    fn arc_block(&mut self, m: &Move, a: &Arc, start: DVec3, axis: usize) {
        let ccw = a.normal[axis] > 0.0;
        if self.hh() {
            let (p, q) = match axis {
                2 => (0, 1),
                1 => (2, 0),
                _ => (1, 2),
            };
            let names = ["X", "Y", "Z"];
            self.start_block();
            self.out.extend_from_slice(b"CC");
            let f = self.coord;
            self.word(names[p], a.centre[p] * self.k, f);
            self.word(names[q], a.centre[q] * self.k, f);
            self.end_block();
            self.start_block();
            self.out.push(b'C');
            let end = m.end;
            self.word(names[p], end[p] * self.k, f);
            self.word(names[q], end[q] * self.k, f);
            if (end[axis] - start[axis]).abs() > 1e-9 {
                self.word(names[axis], end[axis] * self.k, f);
            }
            for k in 0..3 {
                self.st.pos[k] = Some(((end[k] * self.k) * 1e4).round() / 1e4);
            }
            self.out
                .extend_from_slice(if ccw { b" DR+".as_slice() } else { b" DR-" });
            self.feed_spindle(m, m.feed);
            self.st.fmax_last = false;
            self.end_block();
            return;
        }
        self.start_block();
        let mark = self.out.len();
        if self.st.plane != Some(axis) {
            self.out.extend_from_slice(match axis {
                2 => b" G17".as_slice(),
                1 => b" G18",
                _ => b" G19",
            });
            self.st.plane = Some(axis);
        }
        self.motion(if ccw { 3 } else { 2 });
        // End point always written in full so full circles are unambiguous.
        self.coords(m.end, true);
        let off = a.centre - start;
        let f = self.coord;
        for (k, l) in ["I", "J", "K"].iter().enumerate() {
            if k != axis {
                self.word(l, off[k] * self.k, f);
            }
        }
        self.feed_spindle(m, m.feed);
        if self.out[mark..].first() == Some(&b' ') {
            self.out.remove(mark);
        }
        self.end_block();
    }
    /// Move `i` of `op`, after the events due before it (`ev`: the next event).
    fn write_move(&mut self, op: &Operation, i: usize, ev: &mut usize) -> Result<(), WriteError> {
        let m = &op.moves[i];
        while *ev < op.events.len() && op.events[*ev].at as usize <= i {
            self.event(&op.events[*ev]);
            *ev += 1;
        }
        if m.is_cutting() && !self.st.spindle_running && m.spindle > 0.0 {
            self.spindle_block(m.spindle, SpindleDir::Cw);
        }
        let start = op.move_start(i);
        match m.kind {
            MoveKind::Rapid => self.linear_block(op, m, m.end, true, 0.0)?,
            MoveKind::Linear => self.linear_block(op, m, m.end, false, m.feed)?,
            MoveKind::Arc => {
                let a = op.arcs.get(m.aux as usize).ok_or_else(|| WriteError {
                    message: "arc index out of range".into(),
                })?;
                let s = start.ok_or_else(|| WriteError {
                    message: format!("line {}: arc with unknown start", m.line),
                })?;
                match principal_plane(a) {
                    Some(axis) => self.arc_block(m, a, s, axis),
                    None => {
                        for q in arc_points(a, s, m.end, self.o.chord_tol) {
                            self.linear_block(op, m, q, false, m.feed)?;
                        }
                    }
                }
            }
            MoveKind::Cycle => {
                let c = op.cycles.get(m.aux as usize).ok_or_else(|| WriteError {
                    message: "cycle index out of range".into(),
                })?;
                let axis = op.axis(m).unwrap_or(DVec3::Z);
                self.comment(&format!("cycle {} at this hole, written as lines", c.name));
                // Like the control's own cycle: across at the current height, then down.
                let top = m.end + axis * c.retract.max(c.clearance);
                let z = self.st.pos[2]
                    .map(|z| z / self.k)
                    .unwrap_or(top.z)
                    .max(top.z);
                self.linear_block(op, m, DVec3::new(m.end.x, m.end.y, z), true, 0.0)?;
                for (kind, q, f) in cycle_moves(c, m.end, axis) {
                    let mut mm = *m;
                    mm.kind = kind;
                    mm.feed = f;
                    mm.feed_mode = FeedMode::PerMinute;
                    self.linear_block(op, &mm, q, kind == MoveKind::Rapid, f)?;
                }
                if let Some(t) = c.dwell.filter(|t| *t > 0.0) {
                    self.comment(&format!("dwell {t} s at the bottom is not written"));
                }
            }
        }
        Ok(())
    }

    /// Whether blocks carry numbers (which a block in the middle cannot know).
    fn numbered(&self) -> bool {
        self.hh() || self.o.line_numbers
    }

    /// A writer with these settings writing into `out` from state `st`.
    fn fork<'b>(&self, out: &'b mut Vec<u8>, st: State) -> W<'b> {
        W {
            o: self.o,
            out,
            k: self.k,
            coord: self.coord,
            vecf: self.vecf,
            feedf: self.feedf,
            src_dialect: self.src_dialect,
            st,
        }
    }
}

/// The moves of `op`; returns the next event. Long operations are written in
/// parallel runs (see [`write_runs`]) unless blocks are numbered.
fn write_moves(
    w: &mut W,
    op: &Operation,
    sink: &mut Option<Sink>,
    parallel: bool,
) -> Result<usize, WriteError> {
    let n = op.moves.len();
    if !parallel || n < PARALLEL_MIN || w.numbered() {
        let mut ev = 0;
        for i in 0..n {
            maybe_flush(w.out, sink)?;
            w.write_move(op, i, &mut ev)?;
        }
        return Ok(ev);
    }
    // The settings, for the runs; the state and buffer stay with `w`.
    let mut none = Vec::new();
    let cfg = w.fork(&mut none, w.st.clone());
    write_runs(n, &mut w.st, w.out, sink, |a, b, st| {
        // A block with S and F: under 64 bytes.
        let mut text = Vec::with_capacity((b - a) * 64);
        let mut rw = cfg.fork(&mut text, st);
        let mut ev = first_event_at(&op.events, a);
        let mut result = Ok(());
        for i in a..b {
            if let Err(e) = rw.write_move(op, i, &mut ev) {
                result = Err(e);
                break;
            }
        }
        let end = rw.st;
        Run { text, end, result }
    })?;
    Ok(first_event_at(&op.events, n))
}

/// Writes a program as G-code of the chosen dialect.
pub fn write_gcode(p: &Program, o: GcodeOptions, out: &mut Vec<u8>) -> Result<(), WriteError> {
    write_gcode_to(p, o, out, None)
}

/// [`write_gcode`], handing the text to `sink` as it grows (see [`Sink`]).
pub fn write_gcode_to(
    p: &Program,
    o: GcodeOptions,
    out: &mut Vec<u8>,
    sink: Option<Sink>,
) -> Result<(), WriteError> {
    write_all(p, o, out, sink, true)
}

/// [`write_gcode_to`]; `parallel: false` writes every operation in one pass
/// (the reference the parallel writer is tested against).
pub(super) fn write_all(
    p: &Program,
    o: GcodeOptions,
    out: &mut Vec<u8>,
    mut sink: Option<Sink>,
    parallel: bool,
) -> Result<(), WriteError> {
    if p.dialect.is_apt()
        && !matches!(
            o.dialect,
            Dialect::Fanuc | Dialect::LinuxCnc | Dialect::Sinumerik | Dialect::Heidenhain
        )
    {
        return Err(WriteError {
            message: "not a G-code dialect".into(),
        });
    }
    if o.dialect.is_apt() {
        return Err(WriteError {
            message: format!("{} is an APT dialect; use the APT writer", o.dialect.name()),
        });
    }
    let k = 1.0 / o.unit.mm();
    let decimals = if o.unit == LengthUnit::Inch { 5 } else { 4 };
    let fanuc_point = matches!(o.dialect, Dialect::Fanuc);
    let mut w = W {
        o,
        out,
        k,
        coord: NumFmt {
            decimals,
            trailing_point: fanuc_point,
            plus: o.dialect == Dialect::Heidenhain,
            no_leading_zero: false,
        },
        vecf: NumFmt {
            decimals: 7,
            trailing_point: fanuc_point,
            plus: o.dialect == Dialect::Heidenhain,
            no_leading_zero: false,
        },
        feedf: NumFmt {
            decimals: 3,
            trailing_point: fanuc_point,
            plus: false,
            no_leading_zero: false,
        },
        src_dialect: p.dialect,
        st: State {
            block_no: 0,
            pos: [None; 3],
            rot: [None; 3],
            vec: None,
            motion: None,
            plane: None,
            feed: None,
            spindle: None,
            spindle_running: false,
            spindle_dir: SpindleDir::Off,
            cutcom: CutCom::Off,
            heidenhain_rl: "",
            tool_number: None,
            fmax_last: false,
        },
    };
    w.out.reserve(room(p.move_count(), 32, &sink));
    w.header(p);
    for op in &p.operations {
        if let Some(n) = &op.name {
            w.comment(&format!("OPERATION {n}"));
        }
        if let Some(f) = &op.frame {
            w.comment(&format!(
                "coordinates in frame origin {:.4},{:.4},{:.4} X {:.6},{:.6},{:.6} Y {:.6},{:.6},{:.6}",
                f.origin.x, f.origin.y, f.origin.z, f.rot.x_axis.x, f.rot.x_axis.y, f.rot.x_axis.z, f.rot.y_axis.x, f.rot.y_axis.y, f.rot.y_axis.z
            ));
        }
        let five = is_5axis(op);
        w.tool_change(op, five)?;
        let ev = write_moves(&mut w, op, &mut sink, parallel)?;
        for e in &op.events[ev..] {
            w.event(e);
        }
        if w.st.cutcom != CutCom::Off && !w.hh() {
            w.line("G40");
            w.st.cutcom = CutCom::Off;
        }
    }
    w.footer(p);
    Ok(())
}
