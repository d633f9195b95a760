//! G-code back end for ISO/Fanuc, LinuxCNC, Sinumerik and Heidenhain plain language.
//!
//! A small explicit subset per target: header (units, plane, absolute, feed mode),
//! tool change, spindle, then G0/G1/G2/G3 (or L/CC/C) with fixed decimals, `S` and
//! `F` on a block wherever the IR changes them, and a footer. Arcs outside the
//! principal planes and canned cycles are written as explicit lines.
//!
//! Every block must mean in the target what its source block meant:
//! - only known axes are written, and only when they change: a move from an
//!   unknown position names just the axes its source named;
//! - the writer keeps the modal state of its own output (distance mode, motion,
//!   plane, feed mode); a verbatim source block that changes modes or moves the
//!   machine makes it state its modes and positions again;
//! - feed modes are written as read: G93/G94/G95 (Heidenhain `FT`/`F`/`FU`);
//! - events of one source block (tool-length and cutter compensation, work
//!   offset, spindle, coolant, post words) stay in one output block, with the
//!   move of that block when it has one;
//! - a word the target cannot express is an error at its source line (with
//!   `lossy`, a comment and a warning).

use super::{
    arc_points, cycle_moves, events_before_tool, first_event_at, lossy, maybe_flush,
    principal_plane, room, write_runs, CycleStep, NumFmt, Run, Sink, Target, WriteError,
    WriteOptions, Written, PARALLEL_MIN,
};
use crate::gcode::heidenhain::TOOL_DELTAS;
use crate::ir::*;
use millplan_geom::DVec3;

struct W<'a> {
    o: WriteOptions,
    out: &'a mut Vec<u8>,
    k: f64,
    coord: NumFmt,
    vecf: NumFmt,
    feedf: NumFmt,
    spindlef: NumFmt,
    source: Dialect,
    /// The unit the source's verbatim words are written in.
    source_unit: LengthUnit,
    /// No unit word in the header: the source had none and no unit was asked for.
    unit_silent: bool,
    /// The writer adds tool-length compensation (and, five-axis, TCP) at tool
    /// changes only to CL data that have none of their own.
    auto_tlc: bool,
    auto_tcp: bool,
    st: State,
    warnings: Written,
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
    /// The output is known to be in absolute mode (G90).
    absolute: bool,
    feed_mode: Option<FeedMode>,
    feed: Option<f64>,
    spindle: Option<f64>,
    spindle_running: bool,
    /// The direction the program last started the spindle in.
    spindle_dir: Option<SpindleDir>,
    cutcom: CutCom,
    heidenhain_rl: &'static str,
    tool_number: Option<u32>,
    /// Tool-length compensation on, with its register.
    tlc: Option<Option<u32>>,
    tcp: bool,
    /// The output has said whether TCP is on: a source's `TRAFOOF` at the start
    /// is written, not taken for the default.
    tcp_said: bool,
    /// The work offset last written.
    offset: Option<u16>,
    fmax_last: bool,
    /// The canned cycle the control has active (written as a cycle block).
    cycle: Option<CycleId>,
    /// The height of the hole point that cycle block was written for, mm.
    cycle_z: Option<f64>,
}

/// Where a motion block started in the output.
#[derive(Clone, Copy)]
struct Block {
    line: usize,
    block_no: u64,
    mark: usize,
    absolute: bool,
}

/// What an event writes.
enum Words {
    /// Words that share a block with the other words (and the move) of the
    /// same source block.
    Block(String),
    /// Lines of their own.
    Lines(Vec<String>),
    Comment(String),
    Nothing,
}

fn word_plus(letter: &str, v: u32) -> String {
    format!("{letter}{v}")
}

impl W<'_> {
    fn target(&self) -> Target {
        self.o.target
    }

    fn hh(&self) -> bool {
        self.o.target == Target::Heidenhain
    }

    fn start_block(&mut self) {
        if self.hh() {
            let s = self.st.block_no.to_string();
            self.out.extend_from_slice(s.as_bytes());
            self.out.push(b' ');
            self.st.block_no += 1;
        } else if self.o.line_numbers {
            self.st.block_no += 10;
            // Fanuc and LinuxCNC read five digits of N: the numbers start
            // again (they are labels, not an order).
            if self.o.target != Target::Sinumerik && self.st.block_no > 99_999 {
                self.st.block_no = 10;
            }
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
                if c == '(' || c == ')' || c == '\n' || c == '\r' {
                    ' '
                } else {
                    c
                }
            })
            .collect();
        match self.target() {
            Target::Sinumerik | Target::Heidenhain => self.line(&format!("; {clean}")),
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

    /// A Sinumerik source's `DEF` blocks go to the head of a Sinumerik output.
    fn defs_first(&self) -> bool {
        self.target() == Target::Sinumerik
            && self.source == Dialect::Sinumerik
            && self.o.unit() == self.source_unit
    }

    /// A Heidenhain source's tool-call deltas go into this output's tool calls.
    fn deltas_copied(&self) -> bool {
        self.target() == Target::Heidenhain
            && self.source == Dialect::Heidenhain
            && self.o.unit() == self.source_unit
    }

    fn spindle_text(&self, rpm: f64) -> String {
        let mut b = Vec::new();
        self.spindlef.push(&mut b, rpm);
        String::from_utf8(b).unwrap_or_default()
    }

    fn header(&mut self, p: &Program) {
        let name = program_name(p);
        let inch = self.o.unit() == LengthUnit::Inch;
        let silent = self.unit_silent;
        let unit = |i: &str, m: &str| -> String {
            if silent {
                String::new()
            } else if inch {
                format!(" {i}")
            } else {
                format!(" {m}")
            }
        };
        match self.target() {
            Target::Heidenhain => {
                self.line(&format!(
                    "BEGIN PGM {name} {}",
                    if inch { "INCH" } else { "MM" }
                ));
            }
            Target::Sinumerik => {
                self.comment(&format!("{name} - written by millplan"));
                // Sinumerik takes definitions only before the first
                // executable block.
                if self.defs_first() {
                    for e in p.operations.iter().flat_map(|o| &o.events) {
                        if let EventKind::Passthrough(x) = &e.kind {
                            if x.word == "DEF" {
                                self.line(&x.text);
                            }
                        }
                    }
                }
                self.line(&format!("G17{} G90 G94 G40", unit("G70", "G71")));
            }
            Target::LinuxCnc => {
                self.out.extend_from_slice(b"%\n");
                self.comment(&format!("{name} - written by millplan"));
                // G91.1 (arc centres relative to the start, LinuxCNC's
                // default) says what I/J/K mean, and marks the program as
                // LinuxCNC's, whose dwell P is in seconds, not milliseconds.
                self.line(&format!(
                    "G17{} G90 G91.1 G94 G40 G49 G80",
                    unit("G20", "G21")
                ));
            }
            _ => {
                self.out.extend_from_slice(b"%\n");
                // The source's own program number where it has one (the
                // control stores the program under it), with its title.
                let o = match fanuc_number(p.name.as_deref().unwrap_or("")) {
                    Some((n, title)) if title.is_empty() => format!("O{n:04}\n"),
                    Some((n, title)) => format!("O{n:04} ({title})\n"),
                    None => format!("O0001 ({name})\n"),
                };
                self.out.extend_from_slice(o.as_bytes());
                self.comment("written by millplan");
                self.line(&format!("G17{} G90 G94 G40 G49 G80", unit("G20", "G21")));
            }
        }
        self.st.plane = Some(2);
        self.st.absolute = true;
        self.st.feed_mode = Some(FeedMode::PerMinute);
    }

    fn footer(&mut self, p: &Program) {
        if self.st.spindle_running {
            self.line("M5");
        }
        // A program never leaves the control in inverse-time mode.
        if !self.hh() && self.st.feed_mode == Some(FeedMode::InverseTime) {
            self.line("G94");
            self.st.feed_mode = Some(FeedMode::PerMinute);
        }
        self.line("M30");
        match self.target() {
            Target::Heidenhain => {
                let unit = if self.o.unit() == LengthUnit::Inch {
                    "INCH"
                } else {
                    "MM"
                };
                self.line(&format!("END PGM {} {unit}", program_name(p)));
            }
            Target::Sinumerik => {}
            _ => self.out.extend_from_slice(b"%\n"),
        }
    }

    /// The words that make tool-length compensation (and TCP) what the state says.
    fn tlc_words(&self, five_vectors: bool) -> String {
        match (self.st.tlc, self.st.tcp) {
            (Some(h), true) => {
                let g = if five_vectors { "G43.5" } else { "G43.4" };
                match h {
                    Some(h) => format!("{g} H{h}"),
                    None => g.to_string(),
                }
            }
            (Some(h), false) => match h {
                Some(h) => format!("G43 H{h}"),
                None => "G43".to_string(),
            },
            (None, _) => "G49".to_string(),
        }
    }

    fn tool_change(&mut self, op: &Operation) -> Result<(), WriteError> {
        let Some(t) = &op.tool else { return Ok(()) };
        // LinuxCNC's M6 stops the spindle: its direction is known again
        // only when the program starts it.
        self.st.spindle_dir = None;
        let five = op.is_five_axis();
        let vectors = op
            .orients
            .iter()
            .any(|o| o.axis.is_some() && !o.has_angles());
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
        match (self.target(), t.number, &t.name) {
            (Target::Heidenhain, n, name) => {
                let id = match (n, name) {
                    (Some(n), _) => n.to_string(),
                    (None, Some(nm)) => format!("\"{nm}\""),
                    (None, None) => {
                        self.comment("no tool call in the source program");
                        return Ok(());
                    }
                };
                let s = s0
                    .map(|s| format!(" S{}", self.spindle_text(s)))
                    .unwrap_or_default();
                // The source call's length and radius deltas.
                let deltas = op
                    .events
                    .iter()
                    .find_map(|e| match &e.kind {
                        EventKind::Passthrough(p)
                            if p.word == TOOL_DELTAS && self.deltas_copied() =>
                        {
                            Some(format!(" {}", p.text))
                        }
                        _ => None,
                    })
                    .unwrap_or_default();
                self.line(&format!("TOOL CALL {id} Z{s}{deltas}"));
                self.st.spindle = s0;
                if five && self.auto_tcp {
                    self.line("M128");
                    self.st.tcp = true;
                }
            }
            (Target::Sinumerik, n, name) => {
                // A Sinumerik source called its tools as it did; another names
                // them by number when it has one.
                match (name, n) {
                    (Some(nm), _) if self.source == Dialect::Sinumerik || n.is_none() => {
                        self.line(&format!("T=\"{nm}\""))
                    }
                    (_, Some(n)) => self.line(&format!("T{n}")),
                    (_, None) => {
                        self.comment("no tool call in the source program");
                        return Ok(());
                    }
                }
                self.line("M6");
                if self.auto_tlc {
                    self.line("D1");
                    self.st.tlc = Some(Some(1));
                }
                if five && self.auto_tcp {
                    self.line("TRAORI");
                    self.line("ORIWKS");
                    self.st.tcp = true;
                }
            }
            (target, Some(n), _) => {
                self.line(&format!("T{n} M6"));
                if self.auto_tlc {
                    self.st.tlc = Some(Some(n));
                    self.st.tcp = five && target == Target::Fanuc && self.auto_tcp;
                    let w = self.tlc_words(vectors);
                    self.line(&w);
                }
                self.st.tool_number = Some(n);
            }
            (_, None, Some(nm)) => {
                // The control calls tools by number: the operator loads this one.
                self.comment(&format!("load tool {nm}: the source names no tool number"));
                self.line("M0");
            }
            (_, None, None) => self.comment("no tool call in the source program"),
        }
        // A tool change may move the linear axes; it leaves the rotary ones.
        self.st.pos = [None; 3];
        self.st.motion = None;
        self.st.feed = None;
        Ok(())
    }

    /// The words of an event, with the state it leaves; `next` is the move the
    /// event precedes (its speed is the one a spindle start takes).
    fn event_words(
        &mut self,
        op: &Operation,
        e: &Event,
        next: Option<&Move>,
    ) -> Result<Words, WriteError> {
        let hh = self.hh();
        let target = self.target();
        Ok(match &e.kind {
            EventKind::Comment(t) => Words::Comment(t.clone()),
            EventKind::Insert(t) => Words::Comment(format!("INSERT {t}")),
            EventKind::Spindle(dir) => {
                // The speed of the move it starts for (`S0 M3` stays S0).
                let rpm = next.map(|m| m.spindle).or(self.st.spindle);
                let m = match dir {
                    SpindleDir::Cw => "M3",
                    SpindleDir::Ccw => "M4",
                    SpindleDir::Off => "M5",
                };
                self.st.spindle_running = *dir != SpindleDir::Off;
                self.st.spindle_dir = Some(*dir);
                if *dir == SpindleDir::Off {
                    return Ok(if hh {
                        Words::Lines(vec!["M5".into()])
                    } else {
                        Words::Block("M5".into())
                    });
                }
                if hh {
                    let mut v = Vec::new();
                    if let Some(r) = rpm.filter(|r| Some(*r) != self.st.spindle) {
                        v.push(format!("TOOL CALL S{}", self.spindle_text(r)));
                        self.st.spindle = Some(r);
                    }
                    v.push(m.into());
                    Words::Lines(v)
                } else {
                    let s = match rpm {
                        Some(r) => {
                            self.st.spindle = Some(r);
                            format!("S{} {m}", self.spindle_text(r))
                        }
                        None => m.to_string(),
                    };
                    Words::Block(s)
                }
            }
            EventKind::Coolant(c) => {
                let m = match c {
                    Coolant::Off => "M9",
                    Coolant::Mist | Coolant::Air => "M7",
                    _ => "M8",
                };
                if hh {
                    Words::Lines(vec![m.into()])
                } else {
                    Words::Block(m.into())
                }
            }
            EventKind::CutCom { side, register } => {
                self.st.cutcom = *side;
                if hh {
                    self.st.heidenhain_rl = match side {
                        CutCom::Left => " RL",
                        CutCom::Right => " RR",
                        CutCom::Off => " R0",
                    };
                    Words::Nothing
                } else {
                    // A Fanuc or LinuxCNC G41 without D keeps the control's
                    // active D; CL data, Heidenhain RL and Sinumerik (whose D
                    // counts a tool's edges) compensate by the called tool's.
                    let own_d = matches!(self.source, Dialect::Fanuc | Dialect::LinuxCnc);
                    let default = self.st.tool_number.filter(|_| !own_d);
                    let d = match (target, register.or(default)) {
                        // Sinumerik takes the radius of the active D.
                        (Target::Sinumerik, _) | (_, None) => String::new(),
                        (_, Some(n)) => format!(" D{n}"),
                    };
                    Words::Block(match side {
                        CutCom::Off => "G40".into(),
                        CutCom::Left => format!("G41{d}"),
                        CutCom::Right => format!("G42{d}"),
                    })
                }
            }
            EventKind::ToolLength(t) => {
                let new = match t {
                    ToolLength::Off => None,
                    ToolLength::On { register } => Some(*register),
                };
                // Registers mean different things: Sinumerik's D counts the
                // edges of the tool in the spindle, a Fanuc or LinuxCNC H
                // names a row of the length table (by the usual convention
                // the tool's number), and a Heidenhain TOOL CALL applies the
                // called tool's own length.
                let tool = op.tool.as_ref().and_then(|t| t.number);
                let new = match (new, target) {
                    (Some(d), Target::Fanuc | Target::LinuxCnc)
                        if self.source == Dialect::Sinumerik =>
                    {
                        match (d, tool) {
                            (Some(1) | None, Some(t)) => Some(Some(t)),
                            _ => {
                                let what = format!(
                                    "Sinumerik D{} of {}: no H register of {} is known to hold it",
                                    d.unwrap_or(1),
                                    tool.map_or("a tool without a number".into(), |t| {
                                        format!("tool {t}")
                                    }),
                                    target.name()
                                );
                                lossy(self.o.lossy, &mut self.warnings, e.line, what)?;
                                return Ok(Words::Comment(format!(
                                    "tool length D{}",
                                    d.unwrap_or(1)
                                )));
                            }
                        }
                    }
                    (Some(Some(h)), Target::Sinumerik | Target::Heidenhain)
                        if matches!(self.source, Dialect::Fanuc | Dialect::LinuxCnc) =>
                    {
                        if tool != Some(h) {
                            let what = format!(
                                "H{h} with {}: {} applies the tool's own length",
                                tool.map_or("no tool number".into(), |t| format!("tool {t}")),
                                target.name()
                            );
                            lossy(self.o.lossy, &mut self.warnings, e.line, what)?;
                            return Ok(Words::Comment(format!("tool length H{h}")));
                        }
                        Some(Some(1))
                    }
                    // Heidenhain's TOOL CALL applies edge 1's length only.
                    (Some(Some(d)), Target::Heidenhain)
                        if self.source == Dialect::Sinumerik && d != 1 =>
                    {
                        let what = format!(
                            "Sinumerik D{d}: {} applies the tool's own length",
                            target.name()
                        );
                        lossy(self.o.lossy, &mut self.warnings, e.line, what)?;
                        return Ok(Words::Comment(format!("tool length D{d}")));
                    }
                    _ => new,
                };
                let was = self.st.tlc;
                self.st.tlc = new;
                // A compensation block that moves (`G43 H1 Z20`) moves to
                // that Z under the new length even where the program stood
                // at Z20: its Z is written. One without Z moves nothing (the
                // next move without Z keeps the machine's height).
                let moves_here = e.line != 0 && next.is_some_and(|m| m.line == e.line);
                if moves_here
                    && matches!(target, Target::Fanuc | Target::LinuxCnc | Target::Sinumerik)
                {
                    self.st.pos[2] = None;
                }
                match target {
                    Target::Fanuc | Target::LinuxCnc => {
                        if new.is_none() {
                            self.st.tcp = false;
                        }
                        let vectors = op
                            .orients
                            .iter()
                            .any(|o| o.axis.is_some() && !o.has_angles());
                        Words::Block(self.tlc_words(vectors))
                    }
                    Target::Sinumerik => Words::Block(match new {
                        Some(Some(n)) => word_plus("D", n),
                        Some(None) => "D1".into(),
                        None => "D0".into(),
                    }),
                    // Heidenhain and CL data compensate the called tool's length
                    // always; only switching it off cannot be said.
                    Target::Heidenhain | Target::Apt | Target::Krl => {
                        if new.is_none() && was.is_some() {
                            lossy(
                                self.o.lossy,
                                &mut self.warnings,
                                e.line,
                                format!(
                                    "{} cannot switch tool-length compensation off",
                                    target.name()
                                ),
                            )?;
                            Words::Comment("tool-length compensation off".into())
                        } else {
                            Words::Nothing
                        }
                    }
                }
            }
            EventKind::Tcp(on) => {
                let was = self.st.tcp;
                self.st.tcp = *on;
                if was == *on && std::mem::replace(&mut self.st.tcp_said, true) {
                    return Ok(Words::Nothing);
                }
                if was != *on && e.line != 0 && next.is_some_and(|m| m.line == e.line) {
                    // Positions are the tool tip's with TCP, the machine's
                    // without: a block that switches it and moves states
                    // X, Y and Z (the rotary angles mean the same either way).
                    self.st.pos = [None; 3];
                }
                // `G49` ends both: TCP off with length compensation off in
                // the same source block is that one word, not `G49 G43 Hn G49`.
                let tlc_off_too = !*on
                    && e.line != 0
                    && op.events.iter().any(|x| {
                        x.at == e.at
                            && x.line == e.line
                            && x.kind == EventKind::ToolLength(ToolLength::Off)
                    });
                match target {
                    Target::Fanuc if tlc_off_too => Words::Nothing,
                    Target::Fanuc => {
                        if self.st.tlc.is_some() {
                            let vectors = op
                                .orients
                                .iter()
                                .any(|o| o.axis.is_some() && !o.has_angles());
                            let w = if *on {
                                self.tlc_words(vectors)
                            } else {
                                format!("G49 {}", self.tlc_words(vectors))
                            };
                            Words::Block(w)
                        } else {
                            // G43.4/G43.5 come with the next G43 H.
                            Words::Nothing
                        }
                    }
                    Target::Sinumerik => Words::Lines(vec![if *on {
                        "TRAORI".into()
                    } else {
                        "TRAFOOF".into()
                    }]),
                    Target::Heidenhain => {
                        Words::Lines(vec![if *on { "M128".into() } else { "M129".into() }])
                    }
                    Target::LinuxCnc => {
                        lossy(
                            self.o.lossy,
                            &mut self.warnings,
                            e.line,
                            "LinuxCNC has no tool-centre-point control (G43.4/TRAORI/M128)"
                                .to_string(),
                        )?;
                        // Its length compensation stays plain `G43 Hn`.
                        self.st.tcp = false;
                        Words::Comment(format!("TCP {}", if *on { "on" } else { "off" }))
                    }
                    Target::Apt | Target::Krl => Words::Nothing,
                }
            }
            EventKind::WorkOffset(WorkOffset(n)) => {
                let n = *n;
                // Every position is restated in a new frame.
                if self.st.offset != Some(n) {
                    self.st.offset = Some(n);
                    self.st.pos = [None; 3];
                    self.st.rot = [None; 3];
                }
                let w = match (target, n) {
                    (Target::Fanuc | Target::LinuxCnc, 1..=6) => Some(format!("G{}", 53 + n)),
                    (Target::Fanuc, 7..) => Some(format!("G54.1 P{}", n - 6)),
                    (Target::LinuxCnc, 7..=9) => Some(format!("G59.{}", n - 6)),
                    (Target::Sinumerik, 0) => Some("G500".into()),
                    (Target::Sinumerik, 1..=4) => Some(format!("G{}", 53 + n)),
                    (Target::Sinumerik, 5..=99) => Some(format!("G5{n:02}")),
                    _ => None,
                };
                match w {
                    Some(w) => Words::Block(w),
                    None if target == Target::Heidenhain => Words::Lines(vec![
                        "CYCL DEF 247 DATUM SETTING ~".into(),
                        format!("  Q339=+{n} ;DATUM NUMBER"),
                    ]),
                    None => {
                        lossy(
                            self.o.lossy,
                            &mut self.warnings,
                            e.line,
                            format!("{} has no work offset number {n}", target.name()),
                        )?;
                        Words::Comment(format!("work offset {n}"))
                    }
                }
            }
            EventKind::ToolSelect(n) => match target {
                Target::Heidenhain => Words::Lines(vec![format!("TOOL DEF {n}")]),
                _ => Words::Block(word_plus("T", *n)),
            },
            EventKind::Stop { optional } => {
                let m = match (optional, hh) {
                    (false, true) => "STOP",
                    (true, _) => "M1",
                    (false, false) => "M0",
                };
                if hh {
                    Words::Lines(vec![m.into()])
                } else {
                    Words::Block(m.into())
                }
            }
            EventKind::Dwell(t) => Words::Lines(match target {
                Target::Heidenhain => vec![
                    "CYCL DEF 9.0 DWELL TIME".into(),
                    format!("CYCL DEF 9.1 DWELL {t:.3}"),
                ],
                Target::Sinumerik => vec![format!("G4 F{t:.3}")],
                Target::LinuxCnc => vec![format!("G4 P{t:.3}")],
                _ => vec![format!("G4 P{}", (t * 1000.0).round() as i64)],
            }),
            EventKind::PathControl(pc) => self.path_words(pc, e.line)?,
            EventKind::Passthrough(p) => {
                let same_unit = self.o.unit() == self.source_unit || super::unit_free(&p.text);
                if p.word == TOOL_DELTAS && self.deltas_copied()
                    || p.word == "DEF" && self.defs_first()
                {
                    // Written with the tool call; definitions in the header.
                    Words::Nothing
                } else if super::copies_verbatim(self.source, target, p) && same_unit {
                    if p.modal {
                        self.st.motion = None;
                        self.st.plane = None;
                        self.st.absolute = false;
                        self.st.feed_mode = None;
                    }
                    if p.moves {
                        self.st.pos = [None; 3];
                        self.st.rot = [None; 3];
                        self.st.vec = None;
                    }
                    if hh {
                        Words::Lines(vec![p.text.clone()])
                    } else {
                        Words::Block(p.text.clone())
                    }
                } else if p.class == PassClass::Info {
                    Words::Comment(p.text.clone())
                } else {
                    let why = if super::copies_verbatim(self.source, target, p) {
                        format!(
                            "`{}` is copied as written, and its numbers are in {:?}: write the program in {:?} (--out-units)",
                            p.text,
                            self.source_unit,
                            self.source_unit
                        )
                    } else {
                        format!(
                            "`{}` ({}) has no {} equivalent",
                            p.text,
                            self.source.name(),
                            target.name()
                        )
                    };
                    lossy(self.o.lossy, &mut self.warnings, e.line, why)?;
                    if p.moves {
                        self.st.pos = [None; 3];
                        self.st.rot = [None; 3];
                        self.st.vec = None;
                    }
                    Words::Comment(format!("not written: {}", p.text))
                }
            }
        })
    }

    /// A path-control mode in the target's words; one it cannot express is
    /// refused at its line (a comment under `--lossy`).
    fn path_words(&mut self, pc: &PathControl, line: u32) -> Result<Words, WriteError> {
        let target = self.target();
        // A tolerance in the written unit, on the coordinates' grid.
        let tol = |t: f64| crate::gcode::fmt_num(self.grid(t * self.k));
        let w: Option<Vec<String>> = match (target, pc) {
            (Target::Fanuc | Target::LinuxCnc, PathControl::ExactStop) => Some(vec!["G61".into()]),
            (Target::Sinumerik, PathControl::ExactStop) => Some(vec!["G60".into()]),
            (Target::Fanuc | Target::Sinumerik, PathControl::Blend { tolerance: None })
            | (Target::LinuxCnc, PathControl::Blend { tolerance: None }) => {
                Some(vec!["G64".into()])
            }
            (Target::LinuxCnc, PathControl::Blend { tolerance: Some(t) }) => {
                Some(vec![format!("G64 P{}", tol(*t))])
            }
            (Target::Sinumerik, PathControl::Blend { tolerance: Some(t) }) => {
                Some(vec![format!("G642 CTOL={}", tol(*t))])
            }
            (Target::Heidenhain, PathControl::Blend { tolerance }) => Some(vec![
                "CYCL DEF 32.0 TOLERANCE".into(),
                match tolerance {
                    Some(t) => format!("CYCL DEF 32.1 T{}", tol(*t)),
                    None => "CYCL DEF 32.1".into(),
                },
            ]),
            (Target::Fanuc, PathControl::StopOnce) => Some(vec!["G9".into()]),
            (Target::Sinumerik, PathControl::StopOnce) => Some(vec!["G9".into()]),
            (
                Target::Fanuc,
                PathControl::Smoothing {
                    kind: Smoothing::AiContour,
                    on,
                },
            ) => Some(vec![format!("G5.1 Q{}", u8::from(*on))]),
            (
                Target::Fanuc,
                PathControl::Smoothing {
                    kind: Smoothing::LookAhead,
                    on,
                },
            ) => Some(vec![format!("G8 P{}", u8::from(*on))]),
            (
                Target::Sinumerik,
                PathControl::Smoothing {
                    kind: Smoothing::HighSpeed { tolerance },
                    on,
                },
            ) => Some(vec![if *on {
                format!("CYCLE832({},1,1)", tol(*tolerance))
            } else {
                "CYCLE832(0,0,1)".into()
            }]),
            (Target::Sinumerik, PathControl::Soft(on)) => {
                Some(vec![if *on { "SOFT" } else { "BRISK" }.into()])
            }
            _ => None,
        };
        match w {
            Some(v) if target == Target::Heidenhain => Ok(Words::Lines(v)),
            Some(v) => Ok(Words::Block(v.join(" "))),
            None => {
                let what = crate::text::path_control_name(pc);
                lossy(
                    self.o.lossy,
                    &mut self.warnings,
                    line,
                    format!(
                        "{} cannot express the path-control mode `{what}`",
                        target.name()
                    ),
                )?;
                Ok(Words::Comment(format!("path control: {what}")))
            }
        }
    }

    /// Writes the events due before move `i` (`None`: after the last move) and
    /// returns the words that belong in that move's block.
    fn events(&mut self, op: &Operation, i: usize, ev: &mut usize) -> Result<String, WriteError> {
        self.events_until(op, i, ev, op.events.len())
    }

    /// [`Self::events`], up to event `limit` (exclusive).
    fn events_until(
        &mut self,
        op: &Operation,
        i: usize,
        ev: &mut usize,
        limit: usize,
    ) -> Result<String, WriteError> {
        let next = op.moves.get(i);
        let mut pending = String::new();
        let mut pending_line = 0u32;
        while *ev < limit && op.events[*ev].at as usize <= i {
            let e = &op.events[*ev];
            *ev += 1;
            if e.line != pending_line || e.line == 0 {
                self.flush_words(&mut pending);
            }
            match self.event_words(op, e, next)? {
                Words::Block(w) => {
                    if !pending.is_empty() {
                        pending.push(' ');
                    }
                    pending.push_str(&w);
                    pending_line = e.line;
                }
                Words::Lines(v) => {
                    self.flush_words(&mut pending);
                    for l in v {
                        self.line(&l);
                    }
                }
                Words::Comment(c) => {
                    self.flush_words(&mut pending);
                    self.comment(&c);
                }
                Words::Nothing => {}
            }
        }
        match next {
            Some(m) if m.line != 0 && m.line == pending_line && !self.hh() => Ok(pending),
            _ => {
                self.flush_words(&mut pending);
                Ok(String::new())
            }
        }
    }

    fn flush_words(&mut self, pending: &mut String) {
        if !pending.is_empty() {
            let t = std::mem::take(pending);
            self.line(&t);
        }
    }

    /// `v` (output units) on the grid of the written coordinates: positions
    /// that print alike are the same (4 places in mm, 5 in inches).
    fn grid(&self, v: f64) -> f64 {
        let s = 10f64.powi(self.coord.decimals as i32);
        (v * s).round() / s
    }

    /// Writes the known coordinates of `end` that differ from the state (all
    /// known ones when `force`).
    fn coords(&mut self, end: DVec3, force: bool) {
        let names = ["X", "Y", "Z"];
        for k in 0..3 {
            if end[k].is_nan() {
                continue;
            }
            let v = end[k] * self.k;
            let r = self.grid(v);
            if force || self.st.pos[k] != Some(r) {
                let f = self.coord;
                self.word(names[k], v, f);
                self.st.pos[k] = Some(r);
            }
        }
    }

    fn orient_words(&mut self, op: &Operation, m: &Move) -> Result<(), WriteError> {
        let Some(o) = op.orient(m) else {
            return Ok(());
        };
        if o.has_angles() {
            for (k, a) in o.angles.iter().enumerate() {
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
            return Ok(());
        }
        let Some(v) = o.axis else { return Ok(()) };
        if !op.is_five_axis() || self.st.vec == Some(v) {
            return Ok(());
        }
        let f = self.vecf;
        match self.target() {
            Target::Sinumerik => {
                self.word("A3=", v.x, f);
                self.word("B3=", v.y, f);
                self.word("C3=", v.z, f);
            }
            Target::Heidenhain => {
                self.word("TX", v.x, f);
                self.word("TY", v.y, f);
                self.word("TZ", v.z, f);
            }
            Target::LinuxCnc => {
                lossy(
                    self.o.lossy,
                    &mut self.warnings,
                    m.line,
                    "LinuxCNC cannot take tool vectors; five-axis output needs the machine's kinematics (--machine)".to_string(),
                )?;
            }
            _ => {
                if !self.st.tcp {
                    lossy(
                        self.o.lossy,
                        &mut self.warnings,
                        m.line,
                        "Fanuc takes tool vectors (I J K) only under G43.5 Hn, and no tool number or G43.5 came before".to_string(),
                    )?;
                    return Ok(());
                }
                self.word("I", v.x, f);
                self.word("J", v.y, f);
                self.word("K", v.z, f);
            }
        }
        self.st.vec = Some(v);
        Ok(())
    }

    /// The feed-mode G word when the mode changes (G-code dialects).
    fn feed_mode_word(&mut self, mode: FeedMode) {
        if self.st.feed_mode != Some(mode) {
            self.out.extend_from_slice(match mode {
                FeedMode::PerMinute => b" G94".as_slice(),
                FeedMode::PerRev => b" G95",
                FeedMode::InverseTime => b" G93",
            });
            self.st.feed_mode = Some(mode);
            self.st.feed = None;
        }
    }

    fn feed_spindle(&mut self, m: &Move, feed: f64, mode: FeedMode) {
        if !self.hh()
            && m.spindle > 0.0
            && self.st.spindle_running
            && Some(m.spindle) != self.st.spindle
        {
            let f = self.spindlef;
            self.word("S", m.spindle, f);
            self.st.spindle = Some(m.spindle);
        }
        let f = if mode == FeedMode::InverseTime {
            feed
        } else {
            feed * self.k
        };
        // Inverse time: every block carries its own F.
        if self.st.feed != Some(f) || self.st.fmax_last || mode == FeedMode::InverseTime {
            // Feeds per revolution (0.004 in) and block times need more places
            // than feeds per minute.
            let ff = match mode {
                FeedMode::PerMinute => self.feedf,
                _ => NumFmt {
                    decimals: 6,
                    ..self.feedf
                },
            };
            if self.hh() {
                match mode {
                    FeedMode::PerMinute => self.word("F", f, ff),
                    FeedMode::PerRev => self.word("FU", f, ff),
                    // FT: the block's time in seconds.
                    FeedMode::InverseTime => self.word("FT", 60.0 / f, ff),
                }
                self.st.feed_mode = Some(mode);
            } else if mode == FeedMode::InverseTime && self.o.g93_seconds {
                // The block's time in seconds (Beckhoff/ISG G93).
                self.word("F", 60.0 / f, ff);
            } else {
                self.word("F", f, ff);
            }
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

    /// Starts a G-code motion block with the words of its source block's events.
    fn start_motion(&mut self, extra: &str) -> Block {
        let line = self.out.len();
        let block_no = self.st.block_no;
        self.start_block();
        let mark = self.out.len();
        if !extra.is_empty() {
            self.out.push(b' ');
            self.out.extend_from_slice(extra.as_bytes());
        }
        Block {
            line,
            block_no,
            mark,
            absolute: self.st.absolute,
        }
    }

    /// Ends a motion block; one that says nothing (a move to where the tool
    /// already is, with nothing else) is not written.
    fn finish_motion(&mut self, b: Block) {
        if self.out.len() == b.mark {
            self.out.truncate(b.line);
            self.st.block_no = b.block_no;
            return;
        }
        // A block with words states the distance mode the output needs.
        if !b.absolute {
            self.out.splice(b.mark..b.mark, b" G90".iter().copied());
            self.st.absolute = true;
        }
        if self.out[b.mark..].first() == Some(&b' ') {
            self.out.remove(b.mark);
        }
        self.end_block();
    }

    #[allow(clippy::too_many_arguments)]
    fn linear_block(
        &mut self,
        op: &Operation,
        m: &Move,
        end: DVec3,
        rapid: bool,
        feed: f64,
        mode: FeedMode,
        extra: &str,
    ) -> Result<(), WriteError> {
        if self.hh() {
            if !rapid {
                self.heidenhain_speed(m);
            }
            let (line, block_no) = (self.out.len(), self.st.block_no);
            self.start_block();
            let five_vec = op
                .orient(m)
                .is_some_and(|o| o.axis.is_some() && !o.has_angles())
                && op.is_five_axis();
            self.out
                .extend_from_slice(if five_vec { b"LN".as_slice() } else { b"L" });
            let start = self.out.len();
            self.coords(end, five_vec);
            if five_vec {
                self.st.vec = None;
            }
            self.orient_words(op, m)?;
            if self.out.len() == start {
                if self.st.heidenhain_rl.is_empty() {
                    // A move to where the tool stands, with nothing else to
                    // say: no block (as in the other dialects), rather than one
                    // that names axes its source did not.
                    self.out.truncate(line);
                    self.st.block_no = block_no;
                    return Ok(());
                }
                // Radius compensation needs a block with a coordinate.
                self.coords(end, true);
            }
            let rl = std::mem::take(&mut self.st.heidenhain_rl);
            self.out.extend_from_slice(rl.as_bytes());
            if rapid {
                self.out.extend_from_slice(b" FMAX");
                self.st.fmax_last = true;
            } else {
                self.feed_spindle(m, feed, mode);
                self.st.fmax_last = false;
            }
            self.end_block();
            return Ok(());
        }
        let mark = self.start_motion(extra);
        if !rapid {
            self.feed_mode_word(mode);
        } else if !self.o.g93_rapids && self.st.feed_mode == Some(FeedMode::InverseTime) {
            // This control refuses G0 in inverse-time mode.
            self.feed_mode_word(FeedMode::PerMinute);
        }
        self.motion(if rapid { 0 } else { 1 });
        self.coords(end, false);
        self.orient_words(op, m)?;
        if rapid {
            if m.spindle > 0.0 && self.st.spindle_running && Some(m.spindle) != self.st.spindle {
                let f = self.spindlef;
                self.word("S", m.spindle, f);
                self.st.spindle = Some(m.spindle);
            }
        } else {
            self.feed_spindle(m, feed, mode);
        }
        self.finish_motion(mark);
        Ok(())
    }

    /// `TOOL CALL S…` before a Heidenhain feed block whose speed changes.
    fn heidenhain_speed(&mut self, m: &Move) {
        if m.spindle > 0.0 && self.st.spindle_running && Some(m.spindle) != self.st.spindle {
            let s = self.spindle_text(m.spindle);
            self.line(&format!("TOOL CALL S{s}"));
            self.st.spindle = Some(m.spindle);
        }
    }

    /// An arc in a principal plane (`axis`: its normal); `turn`: the block
    /// also states the move's orientation.
    #[allow(clippy::too_many_arguments)]
    fn arc_block(
        &mut self,
        op: &Operation,
        m: &Move,
        a: &Arc,
        (start, end): (DVec3, DVec3),
        axis: usize,
        turn: bool,
        extra: &str,
    ) -> Result<(), WriteError> {
        let ccw = a.normal[axis] > 0.0;
        if self.hh() {
            self.heidenhain_speed(m);
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
            self.word(names[p], end[p] * self.k, f);
            self.word(names[q], end[q] * self.k, f);
            if (end[axis] - start[axis]).abs() > 1e-9 {
                self.word(names[axis], end[axis] * self.k, f);
            }
            for k in 0..3 {
                self.st.pos[k] = Some(self.grid(end[k] * self.k));
            }
            self.out
                .extend_from_slice(if ccw { b" DR+".as_slice() } else { b" DR-" });
            self.feed_spindle(m, m.feed, m.feed_mode);
            self.st.fmax_last = false;
            self.end_block();
            return Ok(());
        }
        let mark = self.start_motion(extra);
        if self.st.plane != Some(axis) {
            self.out.extend_from_slice(match axis {
                2 => b" G17".as_slice(),
                1 => b" G18",
                _ => b" G19",
            });
            self.st.plane = Some(axis);
        }
        self.feed_mode_word(m.feed_mode);
        self.motion(if ccw { 3 } else { 2 });
        // End point always written in full so full circles are unambiguous.
        self.coords(end, true);
        let off = a.centre - start;
        let f = self.coord;
        for (k, l) in ["I", "J", "K"].iter().enumerate() {
            if k != axis {
                self.word(l, off[k] * self.k, f);
            }
        }
        if turn {
            self.orient_words(op, m)?;
        }
        self.feed_spindle(m, m.feed, m.feed_mode);
        self.finish_motion(mark);
        Ok(())
    }

    /// Whether the control's own canned cycle can say what `c` says: a G-code
    /// cycle (G73, G81…) into Fanuc or LinuxCNC along the program's Z (rotary
    /// tables may stand anywhere), or a Heidenhain cycle, whose definition
    /// was copied, called again. LinuxCNC taps (G84 right-hand, G74
    /// left-hand) only with the spindle turning the tap's way, as it insists
    /// when it runs them.
    fn native_cycle(&self, op: &Operation, m: &Move, c: &Cycle) -> bool {
        let along_z = op.axis(m).is_none_or(|a| (a - DVec3::Z).length() < 1e-9);
        // Only a cycle its source named by its G code: an APT cycle's
        // name says less than a G-code cycle needs (the spindle's direction
        // and the feed's unit of a tap, a return level below R, pecks of
        // two depths), so it is spelled out.
        let code = c.name.strip_prefix('G').and_then(|n| n.parse::<u32>().ok());
        along_z
            && match self.target() {
                Target::Fanuc => matches!(code, Some(73 | 74 | 76 | 81..=89)),
                Target::LinuxCnc => match (code, self.st.spindle_dir) {
                    // Without a peck (LinuxCNC taps take no Q).
                    (Some(84), Some(SpindleDir::Cw)) | (Some(74), Some(SpindleDir::Ccw)) => {
                        c.peck.is_none()
                    }
                    // LinuxCNC refuses a peck of zero or below.
                    (Some(73 | 83), _) => c.peck.is_some_and(|q| q > 0.0),
                    (code, _) => matches!(code, Some(81 | 82 | 85 | 89)),
                },
                // Calls the source's own definition, copied only in its unit.
                Target::Heidenhain => {
                    self.source == Dialect::Heidenhain && self.o.unit() == self.source_unit
                }
                _ => false,
            }
    }

    /// A hole of a canned cycle in the control's own words: the cycle block
    /// at its first hole (from the level it returns to), the position alone
    /// at the next.
    fn cycle_block(
        &mut self,
        m: &Move,
        id: CycleId,
        c: &Cycle,
        extra: &str,
    ) -> Result<(), WriteError> {
        super::check_pecks(c)?;
        if self.hh() {
            // The tool stands over the hole; the copied definition is called.
            self.line("CYCL CALL");
            // The cycle leaves the tool at its own clearance height: the next
            // block states Z again.
            self.st.pos[2] = None;
            return Ok(());
        }
        if let Some(q) = c.peck.filter(|q| *q > 0.0) {
            let scale = 10f64.powi(self.coord.decimals as i32);
            if (q * self.k * scale).round() == 0.0 {
                return Err(WriteError::new(
                    c.line,
                    format!(
                        "{}: a peck of {q:.6} mm is below the {} decimals {} is written with",
                        c.name,
                        self.coord.decimals,
                        self.target().name()
                    ),
                ));
            }
        }
        let top = m.end.z + c.retract.max(0.0);
        // An APT cycle's holes may lie at other heights (its depth and
        // levels are offsets from each point): such a hole states the
        // cycle again, with its own Z, R and return level.
        let fresh = self.st.cycle != Some(id) || self.st.cycle_z != Some(m.end.z);
        if fresh {
            if self.st.cycle.is_some() {
                self.line("G80");
            }
            // The control returns to the level the cycle starts from (G98).
            let start_z = self.grid(top * self.k);
            // From above that level, across first and then down to it, as
            // the cycle spelled out goes (the level it returns to is where
            // it starts, G98).
            let above = self.st.pos[2].is_some_and(|z| z > start_z);
            if c.retract > 0.0 && above && self.st.pos.iter().all(Option::is_some) {
                let mark = self.start_motion("");
                self.motion(0);
                self.coords(DVec3::new(m.end.x, m.end.y, f64::NAN), false);
                self.finish_motion(mark);
            }
            if c.retract > 0.0 && self.st.pos[2] != Some(start_z) {
                let mark = self.start_motion("");
                self.motion(0);
                self.coords(DVec3::new(f64::NAN, f64::NAN, top), false);
                self.finish_motion(mark);
            }
        }
        let mark = self.start_motion(extra);
        if fresh {
            self.feed_mode_word(FeedMode::PerMinute);
            let code = if c.retract > 0.0 { " G98 " } else { " G99 " };
            self.out.extend_from_slice(code.as_bytes());
            self.out.extend_from_slice(c.name.as_bytes());
            let f = self.coord;
            let mut xy = m.end;
            xy.z = f64::NAN;
            self.coords(xy, true);
            self.word("Z", (m.end.z + c.bottom) * self.k, f);
            self.word("R", (m.end.z + c.clearance) * self.k, f);
            if let Some(q) = c.peck {
                self.word("Q", q * self.k, f);
            }
            if let Some(t) = c.dwell {
                // Fanuc counts dwell in whole milliseconds, without a
                // decimal point (`P500.` is refused); LinuxCNC in seconds.
                let (p, pf) = if self.target() == Target::Fanuc {
                    let whole = NumFmt {
                        decimals: 0,
                        trailing_point: false,
                        ..f
                    };
                    ((t * 1000.0).round(), whole)
                } else {
                    (t, NumFmt { decimals: 3, ..f })
                };
                self.word("P", p, pf);
            }
            let ff = self.feedf;
            self.word("F", c.feed * self.k, ff);
            self.st.feed = None;
            self.st.cycle = Some(id);
            self.st.cycle_z = Some(m.end.z);
            self.st.motion = None;
        } else {
            let mut xy = m.end;
            xy.z = f64::NAN;
            self.coords(xy, false);
        }
        self.finish_motion(mark);
        self.st.pos[2] = Some(self.grid(top.max(m.end.z) * self.k));
        Ok(())
    }

    /// Move `i` of `op`, after the events due before it (`ev`: the next event).
    fn write_move(&mut self, op: &Operation, i: usize, ev: &mut usize) -> Result<(), WriteError> {
        let m = &op.moves[i];
        if self.st.cycle.is_some() && m.cycle().is_none() {
            self.line("G80");
            self.st.cycle = None;
            self.st.motion = None;
        }
        let extra = self.events(op, i, ev)?;
        if m.is_cutting() && !self.st.spindle_running && m.spindle > 0.0 {
            // The source cuts with the spindle stopped (a CL file that never
            // starts it): start it, as every post does.
            let s = self.spindle_text(m.spindle);
            if self.hh() {
                if Some(m.spindle) != self.st.spindle {
                    self.line(&format!("TOOL CALL S{s}"));
                }
                self.line("M3");
            } else {
                self.line(&format!("S{s} M3"));
            }
            self.st.spindle = Some(m.spindle);
            self.st.spindle_running = true;
            self.st.spindle_dir = Some(SpindleDir::Cw);
        }
        match m.kind {
            MoveKind::Rapid => self.linear_block(op, m, m.end, true, 0.0, m.feed_mode, &extra)?,
            MoveKind::Linear => {
                self.linear_block(op, m, m.end, false, m.feed, m.feed_mode, &extra)?
            }
            MoveKind::Arc(id) => {
                let a = op
                    .arcs
                    .get(id.index())
                    .ok_or_else(|| WriteError::new(m.line, "arc id out of range"))?;
                let (Some(s), Some(e)) = (op.known_start(i), known(m.end)) else {
                    return Err(WriteError::new(
                        m.line,
                        "an arc from or to an unknown position cannot be written",
                    ));
                };
                // An arc whose own orientation differs from the move before it
                // turns the tool along the way: the arc block says so where the
                // target can (machine angles in G-code, vectors in Sinumerik),
                // else the arc is refused at its line.
                let before = i.checked_sub(1).and_then(|k| op.orient(&op.moves[k]));
                let turns = op.is_five_axis() && op.orient(m).is_some_and(|o| Some(o) != before);
                let plane = principal_plane(a);
                let sayable = turns
                    && plane.is_some()
                    && op.orient(m).is_some_and(|o| match self.target() {
                        Target::Sinumerik => true,
                        Target::Fanuc | Target::LinuxCnc => o.has_angles(),
                        _ => false,
                    });
                if turns && !sayable {
                    let target = self.target().name();
                    lossy(
                        self.o.lossy,
                        &mut self.warnings,
                        m.line,
                        format!(
                            "an arc that turns the tool{} cannot be written in {}: write it as lines (a CAM chord tolerance) or into a dialect that can",
                            if plane.is_some() { "" } else { " outside the XY, ZX and YZ planes" },
                            target
                        ),
                    )?;
                }
                match plane {
                    Some(axis) => self.arc_block(op, m, a, (s, e), axis, sayable, &extra)?,
                    None => {
                        // Each chord of an inverse-time arc takes its share of the time.
                        let pts = arc_points(a, s, e, self.o.chord_tol);
                        let share = pts.len() as f64;
                        let mut extra = extra.as_str();
                        for q in pts {
                            let f = if m.feed_mode == FeedMode::InverseTime {
                                m.feed * share
                            } else {
                                m.feed
                            };
                            self.linear_block(op, m, q, false, f, m.feed_mode, extra)?;
                            extra = "";
                        }
                    }
                }
            }
            MoveKind::Cycle(id) => {
                let c = op
                    .cycles
                    .get(id.index())
                    .ok_or_else(|| WriteError::new(m.line, "cycle id out of range"))?;
                if self.native_cycle(op, m, c) {
                    return self.cycle_block(m, id, c, &extra);
                }
                let axis = op.axis(m).unwrap_or(DVec3::Z);
                super::check_pecking(c)?;
                let steps = cycle_moves(c, m.end, axis)?;
                if !extra.is_empty() {
                    self.line(&extra);
                }
                self.comment(&format!("cycle {} at this hole, written as lines", c.name));
                // Like the control's own cycle: up to its level if below
                // it, across at the current height, then down.
                let top = m.end + axis * c.retract.max(c.clearance);
                let now = self.st.pos[2].map(|z| z / self.k);
                let z = now.unwrap_or(top.z).max(top.z);
                let pm = FeedMode::PerMinute;
                if now.is_some_and(|z| z < top.z) {
                    let up = DVec3::new(f64::NAN, f64::NAN, top.z);
                    self.linear_block(op, m, up, true, 0.0, pm, "")?;
                }
                self.linear_block(op, m, DVec3::new(m.end.x, m.end.y, z), true, 0.0, pm, "")?;
                for step in steps {
                    match step {
                        CycleStep::Rapid(q) => self.linear_block(op, m, q, true, 0.0, pm, "")?,
                        CycleStep::Feed(q, f) => {
                            let mut mm = *m;
                            mm.kind = MoveKind::Linear;
                            self.linear_block(op, &mm, q, false, f, pm, "")?
                        }
                        CycleStep::Dwell(t) => {
                            let d = Event {
                                at: i as u32,
                                line: 0,
                                kind: EventKind::Dwell(t),
                            };
                            if let Words::Lines(v) = self.event_words(op, &d, Some(m))? {
                                for l in v {
                                    self.line(&l);
                                }
                            }
                        }
                    }
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
            spindlef: self.spindlef,
            source: self.source,
            source_unit: self.source_unit,
            unit_silent: self.unit_silent,
            auto_tlc: self.auto_tlc,
            auto_tcp: self.auto_tcp,
            st,
            warnings: Vec::new(),
        }
    }
}

/// A program name that is a Fanuc program number (1 to 9999, up to four
/// digits), alone or before a space or a comment (`1000 (CYCLE TEST)` as
/// read from `O1000 (CYCLE TEST)`; not `3D PART`): the number and the rest
/// as a comment's text (no parentheses).
fn fanuc_number(name: &str) -> Option<(u32, String)> {
    let name = name.trim();
    let end = name
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(name.len());
    let n = name[..end].parse::<u32>().ok()?;
    let apart = name[end..].starts_with([' ', '\t', '(']) || end == name.len();
    if !(1..=9999).contains(&n) || end > 4 || !apart {
        return None;
    }
    let rest: String = name[end..]
        .chars()
        .filter(|c| !matches!(c, '(' | ')'))
        .collect();
    Some((n, rest.trim().to_string()))
}

fn program_name(p: &Program) -> String {
    let name: String = p
        .name
        .clone()
        .unwrap_or_default()
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '_')
        .collect();
    if name.is_empty() {
        "MILLPLAN".to_string()
    } else {
        name
    }
}

/// The moves of `op`; returns the next event. Long operations are written in
/// parallel runs (see [`write_runs`]) unless blocks are numbered.
fn write_moves(
    w: &mut W,
    op: &Operation,
    sink: &mut Option<Sink>,
    parallel: bool,
    written: usize,
) -> Result<usize, WriteError> {
    let n = op.moves.len();
    if !parallel || n < PARALLEL_MIN || w.numbered() {
        let mut ev = written;
        for i in 0..n {
            maybe_flush(w.out, sink)?;
            w.write_move(op, i, &mut ev)?;
        }
        return Ok(ev);
    }
    // The settings, for the runs; the state and buffer stay with `w`.
    let mut none = Vec::new();
    let cfg = w.fork(&mut none, w.st.clone());
    let mut warnings = Vec::new();
    write_runs(n, &mut w.st, w.out, sink, &mut warnings, |a, b, st| {
        // A block with S and F: under 64 bytes.
        let mut text = Vec::with_capacity((b - a) * 64);
        let mut rw = cfg.fork(&mut text, st);
        let mut ev = first_event_at(&op.events, a).max(written);
        let mut result = Ok(());
        for i in a..b {
            if let Err(e) = rw.write_move(op, i, &mut ev) {
                result = Err(e);
                break;
            }
        }
        let (end, warnings) = (rw.st, rw.warnings);
        Run {
            text,
            end,
            result,
            warnings,
        }
    })?;
    w.warnings.extend(warnings);
    Ok(first_event_at(&op.events, n))
}

/// Writes a program as G-code of the chosen target.
pub fn write_gcode(p: &Program, o: WriteOptions, out: &mut Vec<u8>) -> Result<Written, WriteError> {
    write_gcode_to(p, o, out, None)
}

/// [`write_gcode`], handing the text to `sink` as it grows (see [`Sink`]).
pub fn write_gcode_to(
    p: &Program,
    o: WriteOptions,
    out: &mut Vec<u8>,
    sink: Option<Sink>,
) -> Result<Written, WriteError> {
    write_all(p, o, out, sink, true)
}

/// [`write_gcode_to`]; `parallel: false` writes every operation in one pass
/// (the reference the parallel writer is tested against).
pub(super) fn write_all(
    p: &Program,
    o: WriteOptions,
    out: &mut Vec<u8>,
    mut sink: Option<Sink>,
    parallel: bool,
) -> Result<Written, WriteError> {
    if !o.target.is_gcode() {
        return Err(WriteError::new(0, "APT is written by the APT writer"));
    }
    // A source that never said its unit runs in the machine's default unit:
    // the output says nothing either, unless it is asked for a unit.
    let unit_silent = p.units.origin == UnitsOrigin::Assumed && o.unit.is_none();
    let o = o.resolved(p);
    let k = 1.0 / o.unit().mm();
    let decimals = if o.unit() == LengthUnit::Inch { 5 } else { 4 };
    let fanuc_point = o.target == Target::Fanuc;
    let cl_data = p.source.is_apt() || p.source == Dialect::Generated;
    let has = |f: fn(&EventKind) -> bool| {
        p.operations
            .iter()
            .any(|op| op.events.iter().any(|e| f(&e.kind)))
    };
    let mut w = W {
        o,
        out,
        k,
        coord: NumFmt {
            decimals,
            trailing_point: fanuc_point,
            plus: o.target == Target::Heidenhain,
            no_leading_zero: false,
        },
        vecf: NumFmt {
            decimals: 7,
            trailing_point: fanuc_point,
            plus: o.target == Target::Heidenhain,
            no_leading_zero: false,
        },
        feedf: NumFmt {
            decimals: 3,
            trailing_point: fanuc_point,
            plus: false,
            no_leading_zero: false,
        },
        spindlef: NumFmt {
            decimals: o.spindle_decimals(),
            trailing_point: false,
            plus: false,
            no_leading_zero: false,
        },
        source: p.source,
        source_unit: p.units.source,
        unit_silent,
        // CL data are tool-tip positions and leave compensation to the post,
        // and a Heidenhain TOOL CALL applies the tool's length itself; any
        // other G-code program says what it wants, and nothing is added.
        auto_tlc: (cl_data || p.source == Dialect::Heidenhain)
            && !has(|k| matches!(k, EventKind::ToolLength(_))),
        auto_tcp: o.auto_tcp && cl_data && !has(|k| matches!(k, EventKind::Tcp(_))),
        st: State {
            block_no: 0,
            pos: [None; 3],
            rot: [None; 3],
            vec: None,
            motion: None,
            plane: None,
            absolute: false,
            feed_mode: None,
            feed: None,
            spindle: None,
            spindle_running: false,
            spindle_dir: None,
            cutcom: CutCom::Off,
            heidenhain_rl: "",
            tool_number: None,
            tlc: None,
            tcp: false,
            tcp_said: false,
            offset: None,
            fmax_last: false,
            cycle: None,
            cycle_z: None,
        },
        warnings: Vec::new(),
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
        let before = events_before_tool(op);
        let mut ev = 0;
        let rest = w.events_until(op, 0, &mut ev, before)?;
        if !rest.is_empty() {
            w.line(&rest);
        }
        w.tool_change(op)?;
        let mut ev = write_moves(&mut w, op, &mut sink, parallel, ev)?;
        if w.st.cycle.take().is_some() {
            w.line("G80");
            w.st.motion = None;
        }
        let rest = w.events(op, op.moves.len(), &mut ev)?;
        if !rest.is_empty() {
            w.line(&rest);
        }
        if w.st.cutcom != CutCom::Off && !w.hh() {
            w.line("G40");
            w.st.cutcom = CutCom::Off;
        }
    }
    w.footer(p);
    Ok(w.warnings)
}
