//! Heidenhain plain-language (Klartext) reader: `BEGIN PGM`, `TOOL DEF`/`TOOL CALL`,
//! `L` lines with `FMAX`, `CC`/`C` and `CR` arcs, `CYCL DEF 1` pecking with `M99`,
//! `~` continuations. Everything else is kept verbatim.

use crate::diag::{parse_num, Code, Diags, ParseError, Parsed};
use crate::ir::*;
use crate::ReadOptions;
use millplan_geom::DVec3;
use std::collections::BTreeMap;

pub struct HeidenhainReader {
    opts: ReadOptions,
    program: Program,
    ops: Vec<Operation>,
    op: Operation,
    diags: Diags,
    line_no: u32,
    /// A `~`-continued block being gathered: its words joined, its first line,
    /// and its lines as written (without the block number).
    cont: Option<(String, u32, String)>,
    /// The lines of the block being read when it was continued, as written.
    raw_block: Option<String>,
    /// A `CYCL DEF 9.0 DWELL TIME` line waiting for its `9.1`: kept as
    /// written with it when that dwell is a parameter.
    dwell_head: Option<(String, u32)>,
    /// M89: the cycle is called after every positioning block until M99.
    modal_call: bool,
    /// The cycle a call would run is one no model covers (`CYCL DEF 2.0
    /// TAPPING`): its number.
    foreign_cycle: Option<u32>,
    saw_content: bool,
    /// The line of END PGM: a control runs nothing after it.
    ended: Option<u32>,
    /// The line of the last block read.
    last_block: u32,
    scale: f64,
    unit: Option<(LengthUnit, UnitsOrigin)>,
    /// Tool-tip position; NaN on an axis the program has not set.
    pos: DVec3,
    rotary: [Option<f64>; 3],
    vector: Option<DVec3>,
    feed: f64,
    feed_seen: bool,
    feed_missing_reported: bool,
    spindle: f64,
    spindle_on: bool,
    feed_mode: FeedMode,
    cutcom: CutCom,
    tcp: bool,
    pole: Option<([Option<f64>; 3], u32)>,
    pole_named: [bool; 3],
    tool_radius: BTreeMap<String, f64>,
    cycle: Cycle,
    cycle_index: Option<CycleId>,
    /// Q parameters of the current 200-series cycle definition.
    cycle_q: Option<BTreeMap<u32, f64>>,
    pub motion_blocks: usize,
}

impl HeidenhainReader {
    pub fn new(opts: ReadOptions) -> HeidenhainReader {
        let unit = opts.units.map(|u| (u, UnitsOrigin::Override));
        HeidenhainReader {
            opts,
            program: Program::new(Dialect::Heidenhain),
            ops: Vec::new(),
            op: Operation::default(),
            diags: Diags::default(),
            line_no: 0,
            cont: None,
            raw_block: None,
            dwell_head: None,
            modal_call: false,
            foreign_cycle: None,
            saw_content: false,
            ended: None,
            last_block: 0,
            scale: unit.map(|(u, _)| u.mm()).unwrap_or(1.0),
            unit,
            pos: UNKNOWN,
            rotary: [None; 3],
            vector: None,
            feed: 0.0,
            feed_seen: false,
            feed_missing_reported: false,
            spindle: 0.0,
            spindle_on: false,
            feed_mode: FeedMode::PerMinute,
            cutcom: CutCom::Off,
            tcp: false,
            pole: None,
            pole_named: [false; 3],
            tool_radius: BTreeMap::new(),
            cycle: Cycle {
                name: "CYCL 1".into(),
                bottom: 0.0,
                clearance: 0.0,
                retract: 0.0,
                feed: 0.0,
                peck: None,
                peck_next: None,
                dwell: None,
                line: 0,
            },
            cycle_index: None,
            cycle_q: None,
            motion_blocks: 0,
        }
    }

    pub fn line(&mut self, raw: &str) -> Result<(), ParseError> {
        self.line_no += 1;
        let ln = self.line_no;
        let raw = raw.strip_suffix('\r').unwrap_or(raw);
        // `~` continues a block on the next line; it may stand after a comment.
        let (raw, continued) = match raw.trim_end().strip_suffix('~') {
            Some(r) => (r, true),
            None => (raw, false),
        };
        let (content, comment) = match raw.find(';') {
            Some(i) => (&raw[..i], Some(raw[i + 1..].trim())),
            None => (raw, None),
        };
        let content = content.trim_end();
        if continued {
            let body = content;
            match &mut self.cont {
                Some((b, _, r)) => {
                    b.push(' ');
                    b.push_str(body.trim());
                    r.push('\n');
                    r.push_str(raw.trim_end());
                    r.push_str(" ~");
                }
                None => {
                    let t = raw.trim();
                    let r = t
                        .trim_start_matches(|c: char| c.is_ascii_digit())
                        .trim_start();
                    self.cont = Some((body.to_string(), ln, format!("{r} ~")))
                }
            }
            return Ok(());
        }
        let (text, first) = match self.cont.take() {
            Some((mut b, f, mut r)) => {
                b.push(' ');
                b.push_str(content.trim());
                r.push('\n');
                r.push_str(raw.trim_end());
                // The comments of a continued block stay with its lines.
                self.raw_block = Some(r);
                (b, f)
            }
            None => {
                self.raw_block = None;
                (content.to_string(), ln)
            }
        };
        if let Some(c) = comment.filter(|c| !c.is_empty() && self.raw_block.is_none()) {
            self.saw_content = true;
            self.op.push_event(ln, EventKind::Comment(c.to_string()));
        }
        let t = text.trim();
        if t.is_empty() {
            return Ok(());
        }
        self.saw_content = true;
        // Strip the block number.
        let body = t
            .trim_start_matches(|c: char| c.is_ascii_digit())
            .trim_start();
        let col0 = (t.len() - body.len() + 1 + (text.len() - text.trim_start().len())) as u32;
        if body.is_empty() {
            return Ok(());
        }
        // After END PGM: a `*` comment block or a Ctrl-Z is let be.
        let after = body.trim_matches(|c: char| c.is_whitespace() || c == '\x1a');
        if self.ended.is_some() && (after.is_empty() || after.starts_with('*')) {
            return Ok(());
        }
        if let Some(end) = self.ended {
            return Err(ParseError::new(
                first,
                col0,
                format!("a block after the end of the program (END PGM at line {end}): a control never runs it, and a second program in the same file is not read (split the file, or remove what follows the end)"),
            ));
        }
        self.last_block = first;
        self.block(body, first, col0)
    }

    fn block(&mut self, body: &str, ln: u32, col0: u32) -> Result<(), ParseError> {
        let up = body.to_ascii_uppercase();
        let words: Vec<&str> = up.split_whitespace().collect();
        match words[0] {
            "BEGIN" | "END" if words.get(1) == Some(&"PGM") => {
                if words[0] == "END" {
                    self.ended = Some(ln);
                }
                if words[0] == "BEGIN" {
                    if let Some(name) = words.get(2) {
                        self.program.name =
                            Some(body.split_whitespace().nth(2).unwrap_or(name).to_string());
                    }
                    match words.last() {
                        Some(&"MM") => self.set_unit(LengthUnit::Mm),
                        Some(&"IN") | Some(&"INCH") => self.set_unit(LengthUnit::Inch),
                        _ => {}
                    }
                }
                Ok(())
            }
            "TOOL" if words.get(1) == Some(&"DEF") => {
                let radius = words
                    .iter()
                    .find_map(|w| w.strip_prefix('R').and_then(parse_num));
                if let (Some(n), Some(r)) = (words.get(2), radius) {
                    self.tool_radius.insert(n.to_string(), r * self.scale);
                }
                // Length and radius deltas of zero change nothing.
                let zero = words.len() > 3
                    && words[3..].iter().all(|w| {
                        let v = w.strip_prefix('L').or(w.strip_prefix('R'));
                        v.and_then(parse_num) == Some(0.0)
                    });
                match (
                    words.get(2).and_then(|n| n.parse::<u32>().ok()),
                    words.len(),
                ) {
                    // `TOOL DEF 9`: tool 9 made ready for the next call.
                    (Some(n), 3) => self.op.push_event(ln, EventKind::ToolSelect(n)),
                    _ => {
                        let class = if zero {
                            PassClass::Info
                        } else {
                            PassClass::Machine
                        };
                        self.passthrough("TOOL DEF", body, class, false, ln)
                    }
                }
                Ok(())
            }
            "TOOL" if words.get(1) == Some(&"CALL") => {
                let id = words.get(2).copied().unwrap_or("");
                // A number or a quoted name calls a tool; `TOOL CALL Z S2000` or
                // `TOOL CALL S2000` only changes the spindle speed (or feed).
                let calls_tool = id.parse::<u32>().is_ok() || id.starts_with('"');
                let name_orig = body
                    .split_whitespace()
                    .nth(2)
                    .unwrap_or("")
                    .trim_matches('"')
                    .to_string();
                let number = id.parse::<u32>().ok();
                let radius = self.tool_radius.get(id).copied().filter(|r| *r > 0.0);
                let from = if calls_tool { 3 } else { 2 };
                // Length and radius deltas (DL, DR, DR2) change the tool the
                // control compensates for: kept with the call.
                let deltas: Vec<&str> = body
                    .split_whitespace()
                    .skip(from)
                    .filter(|w| {
                        let u = w.to_ascii_uppercase();
                        ["DL", "DR2", "DR"].iter().any(|p| {
                            u.strip_prefix(p)
                                .and_then(parse_num)
                                .is_some_and(|v| v != 0.0)
                        })
                    })
                    .collect();
                for w in &words[from..] {
                    if let Some(s) = w.strip_prefix('S').and_then(parse_num) {
                        self.spindle = s;
                    }
                    if let Some(f) = w.strip_prefix('F').and_then(parse_num) {
                        self.feed = f * self.scale;
                        self.feed_seen = f > 0.0;
                    }
                }
                if !calls_tool {
                    // A length delta on the tool in use moves its tip along
                    // the axis: the positions are another's until commanded.
                    let dl = deltas
                        .iter()
                        .any(|w| w.to_ascii_uppercase().starts_with("DL"));
                    if dl {
                        self.pos = UNKNOWN;
                    }
                    if !deltas.is_empty() {
                        self.passthrough("TOOL CALL", body, PassClass::Machine, dl, ln);
                    }
                    return Ok(());
                }
                if !self.op.moves.is_empty() {
                    let prev = std::mem::take(&mut self.op);
                    self.ops.push(prev);
                    self.cycle_index = None;
                }
                // The tool change may move every linear axis.
                self.pos = UNKNOWN;
                self.op.start = UNKNOWN;
                let name = if number.is_none() {
                    Some(name_orig)
                } else {
                    None
                };
                self.op.tool = Some(Tool {
                    number,
                    name,
                    cutter: radius.map(|r| Cutter::flat(2.0 * r)),
                    line: ln,
                });
                if !deltas.is_empty() {
                    let text = deltas.join(" ");
                    self.passthrough(TOOL_DELTAS, &text, PassClass::Machine, false, ln);
                }
                Ok(())
            }
            "L" | "LN" => self.linear(body, &words[1..], ln, col0),
            "CC" => {
                // Coordinates a CC does not name keep the previous pole's.
                let mut p = self.pole.map(|(p, _)| p).unwrap_or([None; 3]);
                self.pole_named = [false; 3];
                for w in &words[1..] {
                    if let Some((k, v, inc)) = coord(w) {
                        let base = if inc { self.pos[k] } else { 0.0 };
                        if base.is_nan() {
                            return Err(ParseError::new(
                                ln,
                                col0,
                                format!(
                                    "incremental `{w}` from a position the program has not set"
                                ),
                            ));
                        }
                        p[k] = Some(base + v * self.scale);
                        self.pole_named[k] = true;
                    }
                }
                self.pole = Some((p, ln));
                Ok(())
            }
            "C" | "CR" => self.arc(&words, ln, col0),
            "CT" | "LP" | "CP" | "RND" | "CHF" | "CTP" => Err(ParseError::new(
                ln,
                col0,
                format!(
                    "`{}` contour elements are not supported; post the program with L/C/CR only",
                    words[0]
                ),
            )),
            "CYCL" if words.get(1) == Some(&"CALL") && words.len() == 2 => {
                self.cycle_call(ln, col0)
            }
            "CYCL" => self.cycle_def(&words, body, ln),
            "M99" => self.cycle_call(ln, col0),
            "STOP" if words.len() == 1 => {
                self.op.push_event(ln, EventKind::Stop { optional: false });
                Ok(())
            }
            "BLK" => {
                // The blank for the control's graphics.
                self.passthrough(words[0], body, PassClass::Info, false, ln);
                Ok(())
            }
            "LBL" | "CALL" | "PLANE" | "STOP" | "FUNCTION" | "FN" | "TCH" | "PGM" => {
                // FUNCTION TCPM / FUNCTION RESET TCPM switch the tool centre
                // point on and off (kept as written): with a rotary axis
                // turned, X, Y and Z name another point, as after M128/M129.
                let tcpm = words[0] == "FUNCTION" && words.contains(&"TCPM");
                let reframes = tcpm && super::tilted(&self.rotary);
                if reframes {
                    self.pos = UNKNOWN;
                }
                let moves = words[0] == "PLANE" || reframes;
                self.passthrough(words[0], body, PassClass::Machine, moves, ln);
                Ok(())
            }
            w if m_number(w).is_some() => {
                let (words, m140) = take_m140(&words);
                self.m_words(&words, ln, Phase::All);
                self.retract(m140, ln);
                Ok(())
            }
            w if coord(w).is_some()
                || w.starts_with("R0")
                || w.starts_with("RL")
                || w.starts_with("RR")
                || w.starts_with('F') =>
            {
                // Positioning block without `L` (seen in NX posts: `Y3.3465 R0 F MAX M99`).
                self.linear(body, &words, ln, col0)
            }
            w if w.starts_with('Q') => {
                self.q_params(&words);
                self.passthrough("Q", body, PassClass::Machine, false, ln);
                Ok(())
            }
            w if w.starts_with('S') && parse_num(&w[1..]).is_some() => {
                self.spindle = parse_num(&w[1..]).unwrap_or(self.spindle);
                self.m_words(&words, ln, Phase::All);
                Ok(())
            }
            _ => {
                self.diags.warn(
                    Code::UnknownWord,
                    ln,
                    col0,
                    format!("`{}` kept verbatim", words[0]),
                );
                self.passthrough(words[0], body, PassClass::Machine, false, ln);
                Ok(())
            }
        }
    }

    fn set_unit(&mut self, u: LengthUnit) {
        if !matches!(self.unit, Some((_, UnitsOrigin::Override))) {
            self.unit = Some((u, UnitsOrigin::Declared));
            self.scale = u.mm();
        }
    }

    fn passthrough(&mut self, word: &str, text: &str, class: PassClass, moves: bool, ln: u32) {
        self.op.push_event(
            ln,
            EventKind::Passthrough(Passthrough {
                word: word.to_string(),
                text: text.trim().to_string(),
                class,
                modal: false,
                moves,
            }),
        );
    }

    /// Handles the M words of a block that act at `when`; returns whether the
    /// block calls the cycle (M99). The TNC switches M3, M4, M8 and the like
    /// on as the block starts, and M0, M1, M2, M5, M9, M30 and M99 at its end,
    /// after the move.
    fn m_words(&mut self, words: &[&str], ln: u32, when: Phase) -> bool {
        let mut cycle_call = false;
        for w in words {
            let Some(m) = m_number(w) else {
                continue;
            };
            let at_end = matches!(m, 0 | 1 | 2 | 5 | 9 | 30 | 89 | 99);
            match when {
                Phase::Start if at_end => continue,
                Phase::End if !at_end => continue,
                _ => {}
            }
            match m {
                3 | 4 => {
                    self.spindle_on = true;
                    let dir = if m == 3 {
                        SpindleDir::Cw
                    } else {
                        SpindleDir::Ccw
                    };
                    self.op.push_event(ln, EventKind::Spindle(dir));
                }
                5 => {
                    self.spindle_on = false;
                    self.op.push_event(ln, EventKind::Spindle(SpindleDir::Off));
                }
                8 => self.op.push_event(ln, EventKind::Coolant(Coolant::Flood)),
                9 => self.op.push_event(ln, EventKind::Coolant(Coolant::Off)),
                0 => self.op.push_event(ln, EventKind::Stop { optional: false }),
                1 => self.op.push_event(ln, EventKind::Stop { optional: true }),
                128 | 129 => {
                    if self.tcp != (m == 128) && super::tilted(&self.rotary) {
                        // Tip or pivot: with a rotary axis turned, X, Y and
                        // Z name another point; the program must command them.
                        self.pos = UNKNOWN;
                    }
                    self.tcp = m == 128;
                    self.op.push_event(ln, EventKind::Tcp(m == 128));
                }
                // Tool change and program end: the writer writes its own.
                6 | 2 | 30 => {}
                99 => {
                    cycle_call = true;
                    self.modal_call = false;
                }
                89 => {
                    cycle_call = true;
                    self.modal_call = true;
                }
                // Machine-datum positioning: handled by the block.
                91 | 92 => {}
                _ => self.passthrough(w, w, PassClass::Machine, false, ln),
            }
        }
        cycle_call
    }

    /// M140 (retract along the tool axis, `MB` distance or `MAX`, its own F):
    /// kept verbatim; the tool stands where the reader cannot know.
    fn retract(&mut self, m140: Option<String>, ln: u32) {
        if let Some(text) = m140 {
            self.pos = UNKNOWN;
            self.passthrough("M140", &text, PassClass::Machine, true, ln);
        }
    }

    fn linear(&mut self, body: &str, words: &[&str], ln: u32, col0: u32) -> Result<(), ParseError> {
        let (words, m140) = take_m140(words);
        let words = &words[..];
        let mut end = self.pos;
        let mut named = [false; 3];
        let mut any = false;
        let mut rapid = false;
        let mut machine = false;
        let mut rot = [None; 3];
        let mut tvec: [Option<f64>; 3] = [None; 3];
        let mut cutcom = None;
        for (k, w) in words.iter().enumerate() {
            if let Some(t) = ["TX", "TY", "TZ"].iter().position(|p| w.starts_with(p)) {
                tvec[t] =
                    Some(parse_num(&w[2..]).ok_or_else(|| {
                        ParseError::new(ln, col0, format!("`{w}` is not a number"))
                    })?);
                any = true;
            } else if ["NX", "NY", "NZ"].iter().any(|p| w.starts_with(p)) {
                // Surface normal of 3D radius compensation: not a tool position.
            } else if let Some((axis, v, inc)) = coord(w) {
                let v = v * self.scale;
                named[axis] = true;
                if !inc {
                    end[axis] = v;
                    any = true;
                } else if !end[axis].is_nan() {
                    end[axis] += v;
                    any = true;
                } else if v != 0.0 {
                    return Err(ParseError::new(
                        ln,
                        col0,
                        format!("incremental `{w}` from a position the program has not set"),
                    ));
                }
            } else if let Some(r) = rotary(w) {
                rot[r.0] = Some(r.1.to_radians());
                any = true;
            } else if *w == "FMAX" || (*w == "F" && words.get(k + 1) == Some(&"MAX")) {
                rapid = true;
            } else if *w == "MAX" || *w == "FAUTO" {
            } else if *w == "R0" {
                if self.cutcom != CutCom::Off {
                    cutcom = Some(CutCom::Off);
                }
            } else if *w == "RL" {
                cutcom = Some(CutCom::Left);
            } else if *w == "RR" {
                cutcom = Some(CutCom::Right);
            } else if let Some(f) = w.strip_prefix('F') {
                // F mm/min, FU mm per revolution, FT seconds for the block.
                let (mode, text) = if let Some(t) = f.strip_prefix('U') {
                    (FeedMode::PerRev, t)
                } else if let Some(t) = f.strip_prefix('T') {
                    (FeedMode::InverseTime, t)
                } else {
                    (FeedMode::PerMinute, f)
                };
                let f = parse_num(text)
                    .ok_or_else(|| ParseError::new(ln, col0, format!("`{w}` is not a feed")))?;
                if !(f > 0.0) {
                    return Err(ParseError::new(
                        ln,
                        col0,
                        format!("feed {w} is not positive"),
                    ));
                }
                self.feed_mode = mode;
                self.feed = match mode {
                    FeedMode::InverseTime => 60.0 / f,
                    _ => f * self.scale,
                };
                self.feed_seen = true;
            } else if let Some(sv) = w.strip_prefix('S').and_then(parse_num) {
                // NX posts put S in L blocks; the control takes it as a speed change.
                self.spindle = sv;
            } else if *w == "M91" || *w == "M92" {
                machine = true;
            } else if m_number(w).is_some() || *w == "M" {
                // A bare `M` (NX posts write one) is no function at all.
            } else {
                return Err(ParseError::new(
                    ln,
                    col0,
                    format!("`{w}` is not a word of an L block"),
                ));
            }
        }
        if let Some(c) = cutcom {
            self.cutcom = c;
            self.op.push_event(
                ln,
                EventKind::CutCom {
                    side: c,
                    register: None,
                },
            );
        }
        self.m_words(words, ln, Phase::Start);
        // M128/M129 on this block may have made the unnamed axes unknown.
        for (k, named) in named.iter().enumerate() {
            if !named {
                end[k] = self.pos[k];
            }
        }
        if machine {
            // Machine-datum coordinates: kept verbatim; its axes are unknown after.
            for (k, named) in named.iter().enumerate() {
                if *named {
                    self.pos[k] = f64::NAN;
                }
            }
            for (k, r) in rot.iter().enumerate() {
                if r.is_some() {
                    self.rotary[k] = None;
                }
            }
            self.passthrough("L", body, PassClass::Machine, true, ln);
            self.m_words(words, ln, Phase::End);
            return Ok(());
        }
        if any {
            for (k, r) in rot.iter().enumerate() {
                if r.is_some() {
                    self.rotary[k] = *r;
                }
            }
            if tvec.iter().any(Option::is_some) {
                let old = self.vector.unwrap_or(DVec3::Z);
                let v = DVec3::new(
                    tvec[0].unwrap_or(old.x),
                    tvec[1].unwrap_or(old.y),
                    tvec[2].unwrap_or(old.z),
                );
                self.vector = Some(v.try_normalize().ok_or_else(|| {
                    ParseError::new(ln, col0, "tool vector TX TY TZ has zero length")
                })?);
            }
            let orient = self.current_orient();
            let mut m = Move::linear(end, self.feed);
            m.line = ln;
            m.orient = orient;
            m.feed_mode = self.feed_mode;
            m.spindle = if self.spindle_on { self.spindle } else { 0.0 };
            if rapid {
                m.kind = MoveKind::Rapid;
                m.feed = 0.0;
                m.feed_mode = FeedMode::PerMinute;
            }
            self.push_move(m, ln);
        }
        // M89 calls the cycle after every positioning block until M99.
        let modal = self.modal_call && any;
        if self.m_words(words, ln, Phase::End) || modal {
            self.cycle_call(ln, col0)?;
        }
        self.retract(m140, ln);
        Ok(())
    }

    fn arc(&mut self, words: &[&str], ln: u32, col0: u32) -> Result<(), ParseError> {
        let start = self.pos;
        let mut given = [None; 3];
        let mut ccw = None;
        let mut radius = None;
        for w in &words[1..] {
            if let Some((k, v, inc)) = coord(w) {
                let v = v * self.scale;
                given[k] = Some(if inc { start[k] + v } else { v });
            } else if *w == "DR+" {
                ccw = Some(true);
            } else if *w == "DR-" {
                ccw = Some(false);
            } else if let Some(r) = w.strip_prefix('R').and_then(parse_num) {
                radius = Some(r * self.scale);
            } else if let Some(f) = w.strip_prefix('F').and_then(parse_num) {
                self.feed = f * self.scale;
                self.feed_seen = f > 0.0;
            }
        }
        self.m_words(words, ln, Phase::Start);
        let ccw = ccw.ok_or_else(|| ParseError::new(ln, col0, "arc without DR+ or DR-"))?;
        let mut end = start;
        for k in 0..3 {
            if let Some(v) = given[k] {
                end[k] = v;
            }
        }
        let (Some(start), Some(end)) = (known(start), known(end)) else {
            return Err(ParseError::new(
                ln,
                col0,
                "arc from or to a position the program has not set (an axis is unknown)",
            ));
        };
        let (normal_axis, centre) = if words[0] == "CR" {
            let r = radius.ok_or_else(|| ParseError::new(ln, col0, "CR without R"))?;
            let n = DVec3::Z;
            let normal = if ccw { n } else { -n };
            let chord = DVec3::new(end.x - start.x, end.y - start.y, 0.0);
            let half = chord.length() / 2.0;
            if half < 1e-9 || half > r.abs() + 1e-6 {
                return Err(ParseError::new(
                    ln,
                    col0,
                    "CR radius does not fit the chord",
                ));
            }
            let h = (r * r - half * half).max(0.0).sqrt();
            let perp = normal.cross(chord).normalize();
            let mid = DVec3::new(start.x, start.y, start.z) + chord * 0.5;
            (
                n,
                if r > 0.0 {
                    mid + perp * h
                } else {
                    mid - perp * h
                },
            )
        } else {
            let (p, pole_line) = self
                .pole
                .ok_or_else(|| ParseError::new(ln, col0, "C without a preceding CC"))?;
            // The plane is the pair of axes the CC block names; failing that (a CC
            // naming three axes, or a start point on the centre in the named plane),
            // the first of XY, ZX, YZ in which the start point is off the centre.
            let planes = [(2usize, 0usize, 1usize), (1, 2, 0), (0, 1, 2)];
            let named: Vec<_> = planes
                .iter()
                .copied()
                .filter(|(n, a, b)| {
                    self.pole_named[*a] && self.pole_named[*b] && !self.pole_named[*n]
                })
                .collect();
            // Among those, the plane in which start and end are equally far from
            // the centre (NX writes CC X.. Y.. Z.. for arcs in the ZX and YZ planes).
            let mut choice: Option<((usize, usize, usize), f64)> = None;
            for (nax, a, b) in named.into_iter().chain(planes) {
                if let (Some(ca), Some(cb)) = (p[a], p[b]) {
                    let rs = ((start[a] - ca).powi(2) + (start[b] - cb).powi(2)).sqrt();
                    let re = ((end[a] - ca).powi(2) + (end[b] - cb).powi(2)).sqrt();
                    if rs <= 1e-9 {
                        continue;
                    }
                    let miss = (rs - re).abs();
                    if miss <= crate::verify::ARC_TOL + 1e-4 * rs {
                        choice = Some(((nax, a, b), miss));
                        break;
                    }
                    if choice.map(|(_, m)| miss < m).unwrap_or(true) {
                        choice = Some(((nax, a, b), miss));
                    }
                }
            }
            let choice = choice.map(|(c, _)| c);
            let (nax, a, b) = choice.ok_or_else(|| {
                ParseError::new(
                    ln,
                    col0,
                    format!("arc start lies on the CC of line {pole_line}"),
                )
            })?;
            let named_plane = self.pole_named[a] && self.pole_named[b] && !self.pole_named[nax];
            if !named_plane {
                self.diags.note(Code::ArcPlane, ln, col0, format!("the arc about the CC of line {pole_line} is taken in the plane normal to {}", ["X", "Y", "Z"][nax]));
            }
            let mut c = start;
            c[a] = p[a].unwrap_or(0.0);
            c[b] = p[b].unwrap_or(0.0);
            let mut n = DVec3::ZERO;
            n[nax] = 1.0;
            (n, c)
        };
        let normal = if ccw { normal_axis } else { -normal_axis };
        let full = (start - end).length() < 1e-9;
        let arc = Arc::from_points(start, end, centre, normal, full)
            .ok_or_else(|| ParseError::new(ln, col0, "arc start lies on its centre"))?;
        let mut m = Move::linear(end, self.feed);
        m.kind = MoveKind::Arc(self.op.push_arc(arc));
        m.orient = self.current_orient();
        m.line = ln;
        m.feed_mode = self.feed_mode;
        m.spindle = if self.spindle_on { self.spindle } else { 0.0 };
        self.push_move(m, ln);
        self.m_words(words, ln, Phase::End);
        Ok(())
    }

    fn cycle_def(&mut self, words: &[&str], body: &str, ln: u32) -> Result<(), ParseError> {
        // CYCL DEF 1.0 PECKING / 1.1 SET UP s / 1.2 DEPTH d / 1.3 PECKG q / 1.4 DWELL t / 1.5 F f
        let num = |w: Option<&&str>| w.and_then(|w| parse_num(w));
        // The drilling cycles are modelled through their calls (M99); their
        // definitions need no words of their own in another dialect. Any other
        // cycle (datum shift, working plane, tolerance) acts as it stands.
        let number = words
            .get(2)
            .and_then(|w| w.split('.').next()?.parse::<u32>().ok());
        if number == Some(32) && self.tolerance_cycle(words, body, ln)? {
            return Ok(());
        }
        // Cycle 9, DWELL TIME, acts where it is defined: `9.0` opens it,
        // `9.1 DWELL 1.5` (`V.ZEIT` in German) dwells that many seconds.
        if number == Some(9) {
            match words.get(2).copied() {
                Some("9.0") => self.dwell_head = Some((body.to_string(), ln)),
                Some("9.1") => {
                    let last = words.last().copied().unwrap_or("");
                    let head = self.dwell_head.take();
                    match parse_num(last) {
                        Some(t) if t >= 0.0 => self.op.push_event(ln, EventKind::Dwell(t)),
                        Some(_) => {
                            return Err(ParseError::new(
                                ln,
                                1,
                                format!("`{last}` in `{}` is a negative dwell", body.trim()),
                            ))
                        }
                        // A Q parameter (`DWELL Q5`): known only when the
                        // control runs it; kept as written.
                        None => {
                            if let Some((h, hl)) = head {
                                self.passthrough("CYCL", &h, PassClass::Machine, false, hl);
                            }
                            let text = self.raw_block.take().unwrap_or_else(|| body.to_string());
                            self.passthrough("CYCL", &text, PassClass::Machine, false, ln);
                        }
                    }
                }
                _ => {
                    let text = self.raw_block.take().unwrap_or_else(|| body.to_string());
                    self.passthrough("CYCL", &text, PassClass::Machine, false, ln);
                }
            }
            return Ok(());
        }
        if !matches!(number, Some(1 | 200..=209 | 240 | 241)) {
            // Datum shift, mirror, rotation, scaling, program call, spindle
            // orientation, working plane, datum setting act where they are
            // defined; any other cycle is run by the next call, and a call
            // must not run the drilling cycle defined before it.
            if !matches!(
                number,
                Some(7 | 8 | 10 | 11 | 12 | 13 | 19 | 26 | 247 | 248)
            ) {
                self.foreign_cycle = Some(number.unwrap_or(0));
            }
            let text = self.raw_block.take().unwrap_or_else(|| body.to_string());
            self.passthrough("CYCL", &text, PassClass::Machine, false, ln);
            return Ok(());
        }
        self.foreign_cycle = None;
        if let Some(n) = words
            .get(2)
            .and_then(|w| w.parse::<u32>().ok())
            .filter(|n| *n >= 200)
        {
            // 200-series cycles take Q parameters, on this and the following lines.
            self.cycle = Cycle {
                name: format!("CYCL {n} {}", words.get(3).copied().unwrap_or("")),
                line: ln,
                ..self.cycle.clone()
            };
            self.cycle_index = None;
            self.cycle_q = Some(BTreeMap::new());
            // After the number: the cycle's name, then Q parameters only.
            for w in &words[3..] {
                let ok = match w.strip_prefix('Q').and_then(|r| r.split_once('=')) {
                    // A number, or a word (`FAUTO`, `MAX`, `PREDEF`, `Q12`).
                    Some((k, v)) => {
                        k.parse::<u32>().is_ok()
                            && (parse_num(v).is_some()
                                || v.starts_with(|c: char| c.is_ascii_alphabetic())
                                    && v.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'))
                    }
                    None => {
                        w.chars()
                            .all(|c| c.is_ascii_alphabetic() || "_-./".contains(c))
                            && w.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
                    }
                };
                if !ok {
                    return Err(ParseError::new(
                        ln,
                        1,
                        format!("`{w}` is not a Q parameter of CYCL DEF {n}"),
                    ));
                }
            }
            self.q_params(words);
            self.modal_call = false;
            let text = self.raw_block.take().unwrap_or_else(|| body.to_string());
            self.passthrough("CYCL", &text, PassClass::Info, false, ln);
            return Ok(());
        }
        if words.get(2).map(|w| w.contains('.')).unwrap_or(false)
            && words.get(2).map(|w| w.starts_with("1.")).unwrap_or(false)
        {
            self.cycle_q = None;
        }
        // The pecking cycle's values are read: one that is not a number stops here.
        if matches!(
            words.get(2).copied(),
            Some("1.1" | "1.2" | "1.3" | "1.4" | "1.5")
        ) {
            let last = words.last().copied().unwrap_or("");
            let text = last.strip_prefix('F').unwrap_or(last);
            // `CYCL DEF 1.4 DWELL` without a value is none; a value must be a number.
            let word = text.chars().all(|c| c.is_ascii_alphabetic());
            if !word && parse_num(text).is_none() {
                return Err(ParseError::new(
                    ln,
                    1,
                    format!("`{last}` in `{}` is not a number", body.trim()),
                ));
            }
        }
        match words.get(2).copied() {
            Some("1.0") => {
                self.cycle = Cycle {
                    name: "CYCL 1 PECKING".into(),
                    line: ln,
                    ..self.cycle.clone()
                };
                self.cycle_index = None;
            }
            Some("1.1") => {
                self.cycle.clearance = num(words.last()).unwrap_or(0.0).abs() * self.scale
            }
            Some("1.2") => self.cycle.bottom = -num(words.last()).unwrap_or(0.0).abs() * self.scale,
            Some("1.3") => {
                self.cycle.peck = num(words.last())
                    .filter(|q| *q > 0.0)
                    .map(|q| q * self.scale)
            }
            Some("1.4") => self.cycle.dwell = num(words.last()).filter(|t| *t > 0.0),
            Some("1.5") => {
                if let Some(f) = words
                    .last()
                    .and_then(|w| w.strip_prefix('F'))
                    .and_then(parse_num)
                {
                    self.cycle.feed = f * self.scale;
                }
            }
            _ => {}
        }
        self.passthrough("CYCL", body, PassClass::Info, false, ln);
        Ok(())
    }

    /// Cycle 32 TOLERANCE: `32.0` opens it, `32.1 T…` sets the contour
    /// tolerance (without T: the machine's own), read as the blending mode;
    /// `32.2` (HSC mode, axis tolerance) is kept as written. Returns whether
    /// the line was taken.
    fn tolerance_cycle(&mut self, words: &[&str], body: &str, ln: u32) -> Result<bool, ParseError> {
        match words.get(2).copied() {
            Some("32.0") => Ok(true),
            Some("32.1") => {
                let t = match words.get(3) {
                    Some(w) => {
                        let v = w.strip_prefix('T').and_then(parse_num).ok_or_else(|| {
                            ParseError::new(
                                ln,
                                1,
                                format!("`{w}` in `{}` is not a tolerance T", body.trim()),
                            )
                        })?;
                        (v > 0.0).then_some(v * self.scale)
                    }
                    None => None,
                };
                self.op.push_event(
                    ln,
                    EventKind::PathControl(PathControl::Blend { tolerance: t }),
                );
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    fn q_params(&mut self, words: &[&str]) {
        let Some(q) = self.cycle_q.as_mut() else {
            return;
        };
        for w in words {
            if let Some((k, v)) = w.strip_prefix('Q').and_then(|r| r.split_once('=')) {
                if let (Ok(k), Some(v)) = (k.parse::<u32>(), parse_num(v)) {
                    q.insert(k, v);
                }
            }
        }
    }

    fn cycle_call(&mut self, ln: u32, col0: u32) -> Result<(), ParseError> {
        if let Some(n) = self.foreign_cycle {
            // Run where the tool stands, kept as the control's own call; Z
            // after it is the cycle's.
            self.diags.warn(
                Code::UnknownWord,
                ln,
                col0,
                format!(
                    "a call of CYCL DEF {n}, which no model covers: kept verbatim, not simulated"
                ),
            );
            self.passthrough("CYCL CALL", "CYCL CALL", PassClass::Machine, true, ln);
            self.pos.z = f64::NAN;
            return Ok(());
        }
        if self.cycle.line == 0 {
            return Err(ParseError::new(ln, col0, "M99 without a CYCL DEF"));
        }
        if let Some(q) = &self.cycle_q {
            // Q200 set-up clearance, Q201 depth, Q206 plunge feed, Q203 surface,
            // Q204 second set-up clearance, Q202 plunge depth, Q211 dwell.
            let (Some(depth), Some(surface)) = (q.get(&201), q.get(&203)) else {
                self.diags.warn(
                    Code::UnknownWord,
                    ln,
                    col0,
                    format!(
                        "{} call kept verbatim: no Q201/Q203, its motion is not simulated",
                        self.cycle.name
                    ),
                );
                self.passthrough("M99", "M99", PassClass::Machine, false, ln);
                return Ok(());
            };
            let s = self.scale;
            let idx = match self.cycle_index {
                Some(i) => i,
                None => {
                    if let Some(p) = q.get(&202).filter(|p| **p <= 0.0) {
                        self.diags.warn(
                            Code::PeckDepth,
                            ln,
                            col0,
                            format!(
                                "{}: plunging depth Q202={} is not positive; read as one plunge to depth (the control may stop with an error)",
                                self.cycle.name,
                                super::fmt_num(*p)
                            ),
                        );
                    }
                    let feed = q.get(&206).map(|f| f * s).filter(|f| *f > 0.0).unwrap_or(
                        if self.feed_seen {
                            self.feed
                        } else {
                            self.opts.default_feed
                        },
                    );
                    let c = Cycle {
                        name: self.cycle.name.clone(),
                        bottom: -depth.abs() * s,
                        clearance: q.get(&200).copied().unwrap_or(0.0).abs() * s,
                        retract: q.get(&204).copied().unwrap_or(0.0).abs() * s,
                        feed,
                        peck: q.get(&202).map(|p| p.abs() * s).filter(|p| *p > 0.0),
                        peck_next: None,
                        dwell: q.get(&211).copied().filter(|t| *t > 0.0),
                        line: self.cycle.line,
                    };
                    let i = self.op.push_cycle(c);
                    self.cycle_index = Some(i);
                    i
                }
            };
            if self.pos.x.is_nan() || self.pos.y.is_nan() {
                return Err(ParseError::new(
                    ln,
                    col0,
                    "cycle call at a position the program has not set",
                ));
            }
            let mut m = Move::rapid(DVec3::new(self.pos.x, self.pos.y, surface * s));
            m.kind = MoveKind::Cycle(idx);
            m.orient = self.current_orient();
            m.line = ln;
            m.spindle = if self.spindle_on { self.spindle } else { 0.0 };
            self.push_move(m, ln);
            // After the hole the tool stands at the set-up clearance, or at
            // the 2nd set-up clearance (Q204) when that is higher.
            if let Some(c) = self.op.cycle(&m) {
                let axis = self.op.axis(&m).unwrap_or(DVec3::Z);
                self.pos = m.end + axis * c.retract.max(c.clearance);
            }
            return Ok(());
        }
        let idx = match self.cycle_index {
            Some(i) => i,
            None => {
                let mut c = self.cycle.clone();
                if c.feed <= 0.0 {
                    c.feed = if self.feed_seen {
                        self.feed
                    } else {
                        self.opts.default_feed
                    };
                }
                // Cycle 1 starts at set-up clearance above the surface; depths count from the surface.
                c.bottom -= c.clearance;
                c.retract = 0.0;
                c.clearance = 0.0;
                let i = self.op.push_cycle(c);
                self.cycle_index = Some(i);
                i
            }
        };
        if known(self.pos).is_none() {
            return Err(ParseError::new(
                ln,
                col0,
                "cycle call at a position the program has not set",
            ));
        }
        let mut m = Move::rapid(self.pos);
        m.kind = MoveKind::Cycle(idx);
        m.orient = self.current_orient();
        m.line = ln;
        m.spindle = if self.spindle_on { self.spindle } else { 0.0 };
        // A cycle at the position the previous block reached replaces that rapid.
        self.push_move(m, ln);
        Ok(())
    }

    /// The tool orientation in effect: the last tool vector, else the rotary axes.
    fn current_orient(&mut self) -> Option<OrientId> {
        if let Some(v) = self.vector {
            Some(self.op.intern_orient(Orient::vector(v)))
        } else if self.rotary.iter().any(Option::is_some) {
            Some(self.op.intern_orient(Orient::angles(self.rotary)))
        } else {
            None
        }
    }

    fn push_move(&mut self, mut m: Move, ln: u32) {
        self.motion_blocks += 1;
        if m.is_cutting() && !self.feed_seen {
            m.feed = self.opts.default_feed;
            if !self.feed_missing_reported {
                self.feed_missing_reported = true;
                self.diags.warn(
                    Code::FeedMissing,
                    ln,
                    1,
                    format!(
                        "cutting move before any F: using {} mm/min",
                        self.opts.default_feed
                    ),
                );
            }
        }
        if m.is_cutting() && self.op.tool.is_none() {
            self.op.tool = Some(Tool {
                number: None,
                name: None,
                cutter: None,
                line: ln,
            });
            self.diags.warn(
                Code::ToolMissing,
                ln,
                1,
                "cutting move before any TOOL CALL: tool unknown",
            );
        }
        if self.op.moves.is_empty() {
            self.op.start = self.pos;
        }
        if self.op.moves.capacity() == 0 && self.opts.expect_moves > 0 {
            // Room may be refused for a wild guess; the moves then grow as usual.
            let _ = self
                .op
                .moves
                .try_reserve_exact(std::mem::take(&mut self.opts.expect_moves));
        }
        self.op.moves.push(m);
        self.pos = m.end;
    }

    pub fn finish(mut self) -> Result<Parsed, ParseError> {
        if let Some((_, l, _)) = self.cont {
            return Err(ParseError::new(l, 1, "file ends inside a `~` continuation"));
        }
        if !self.saw_content {
            return Err(ParseError::new(1, 1, "empty file: no Heidenhain blocks"));
        }
        if self.ended.is_none() && self.last_block > 0 {
            let last = self.last_block;
            self.diags.warn(
                Code::ProgramEnd,
                last,
                1,
                format!("the program has no END PGM: a file cut short ends like this; its last block, line {last}, is read as written"),
            );
            self.program.unterminated = Some(last);
        }
        self.ops.push(std::mem::take(&mut self.op));
        self.ops
            .retain(|o| !(o.moves.is_empty() && o.events.is_empty() && o.tool.is_none()));
        let (u, origin) = match self.unit {
            Some(x) => x,
            None => {
                self.diags.warn(
                    Code::UnitsAssumed,
                    0,
                    0,
                    "no BEGIN PGM unit: millimetres assumed (override with --units)",
                );
                (LengthUnit::Mm, UnitsOrigin::Assumed)
            }
        };
        self.program.units = Units { source: u, origin };
        self.program.operations = self.ops;
        Ok(Parsed {
            program: self.program,
            diagnostics: self.diags.finish(),
        })
    }
}

/// `X+1.5` → (0, 1.5, false); `IY-2` → (1, -2, true).
fn coord(w: &str) -> Option<(usize, f64, bool)> {
    let (inc, w) = match w.strip_prefix('I') {
        Some(rest) if rest.starts_with(['X', 'Y', 'Z']) => (true, rest),
        _ => (false, w),
    };
    let axis = match w.as_bytes().first()? {
        b'X' => 0,
        b'Y' => 1,
        b'Z' => 2,
        _ => return None,
    };
    parse_num(&w[1..]).map(|v| (axis, v, inc))
}

/// The words of a block without its M140 retract, and that retract's words
/// (`M140 MB MAX F…`, `M140 MB 50`).
fn take_m140<'a>(words: &[&'a str]) -> (Vec<&'a str>, Option<String>) {
    let Some(i) = words.iter().position(|w| *w == "M140") else {
        return (words.to_vec(), None);
    };
    let mut j = i + 1;
    if words.get(j) == Some(&"MB") {
        j += 1;
        if words
            .get(j)
            .is_some_and(|w| *w == "MAX" || parse_num(w).is_some())
        {
            j += 1;
        }
    } else if words.get(j).is_some_and(|w| w.starts_with("MB")) {
        j += 1;
    }
    if words
        .get(j)
        .is_some_and(|w| w.starts_with('F') && *w != "FMAX")
    {
        j += 1;
        if words.get(j) == Some(&"MAX") && words[j - 1] == "F" {
            j += 1;
        }
    }
    let text = words[i..j].join(" ");
    let mut rest = words[..i].to_vec();
    rest.extend_from_slice(&words[j..]);
    (rest, Some(text))
}

/// The word of the pass-through event that carries a `TOOL CALL`'s length and
/// radius deltas (`DL+0.1 DR-0.05`); the Heidenhain writer appends them to its
/// tool call.
pub const TOOL_DELTAS: &str = "TOOL CALL DL DR";

/// When in a block an M function acts.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Phase {
    Start,
    End,
    /// A block of M functions only.
    All,
}

/// `M3` → 3; not `MAX`.
fn m_number(w: &str) -> Option<u32> {
    let d = w.strip_prefix('M')?;
    (!d.is_empty() && d.bytes().all(|c| c.is_ascii_digit()))
        .then(|| d.parse().ok())
        .flatten()
}

fn rotary(w: &str) -> Option<(usize, f64)> {
    let axis = match w.as_bytes().first()? {
        b'A' => 0,
        b'B' => 1,
        b'C' => 2,
        _ => return None,
    };
    parse_num(&w[1..]).map(|v| (axis, v))
}
