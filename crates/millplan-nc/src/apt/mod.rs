//! APT / CLDATA reader for every dialect millplan meets: ISO, CATIA, NX CLSF,
//! SOLIDWORKS CAM, and bare GOTO fragments.
//!
//! One tokenizer serves all dialects (join `$` continuations, strip `$$` comments,
//! split on `/` and `,`); one record interpreter keeps the modal state (units, feed,
//! rapid-once flag, tool axis, frame, cutter compensation, cycle) and emits fully
//! resolved moves. The reader is fed line by line so a file never has to be held in
//! memory beside its IR.

pub mod nurbs;

use crate::diag::{parse_num, Code, Diags, ParseError, Parsed};
use crate::ir::*;
use crate::ReadOptions;
use millplan_geom::{DVec3, Frame};

/// Counts of what the file held, for checks against the source.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct AptStats {
    pub goto: usize,
    pub goto_with_axis: usize,
    pub circle: usize,
    pub nurbs: usize,
    pub records: usize,
}

#[derive(Clone, Copy, PartialEq)]
enum CircleLayout {
    /// `CIRCLE/xc,yc,zc,i,j,k` — radius from the start point (SOLIDWORKS CAM).
    NoRadius,
    /// `CIRCLE/xc,yc,zc,i,j,k,r[,...]` (ISO, NX).
    WithRadius(f64),
}

struct PendingCircle {
    centre: DVec3,
    axis: DVec3,
    layout: CircleLayout,
    line: u32,
}

struct PendingNurbs {
    start: DVec3,
    knots: Vec<f64>,
    cntrl: Vec<DVec3>,
    line: u32,
}

/// Incremental APT reader: feed physical lines with [`AptReader::line`], then [`AptReader::finish`].
pub struct AptReader {
    opts: ReadOptions,
    program: Program,
    ops: Vec<Operation>,
    op: Operation,
    diags: Diags,
    pub stats: AptStats,
    /// Unit the file's numbers are in, once known.
    units: Option<(LengthUnit, UnitsOrigin, u32)>,
    feed: f64,
    feed_mode: FeedMode,
    /// The frame in force was set by NX's `MSYS` (not SOLIDWORKS's `CSYS`):
    /// CIRCLE axes are then in the absolute frame.
    msys: bool,
    feed_seen: bool,
    feed_missing_reported: bool,
    spindle: f64,
    last_spindle_on: f64,
    rapid_once: bool,
    axis: Option<DVec3>,
    pos: Option<DVec3>,
    circle: Option<PendingCircle>,
    nurbs: Option<PendingNurbs>,
    cycle: Option<CycleId>,
    /// Continuation buffer: text of the logical line so far and its first line number.
    cont: Option<(String, u32)>,
    line_no: u32,
    saw_content: bool,
    /// The line of FINI: a control runs nothing after it.
    ended: Option<u32>,
    /// The last record (comments aside) ended the program or a path: FINI,
    /// END or NX's END-OF-PATH.
    closed: bool,
    /// The line of the last record, comments aside.
    last_record: u32,
}

/// A tokenized statement: the major word and the raw argument text.
struct Stmt<'a> {
    major: &'a str,
    /// Text after `/` (empty for bare words).
    args: &'a str,
    /// Column (1-based) where `args` starts in the logical line.
    args_col: u32,
}

fn split_stmt(s: &str) -> Stmt<'_> {
    match s.find('/') {
        Some(i) => {
            let after = &s[i + 1..];
            let lead = after.len() - after.trim_start().len();
            Stmt {
                major: s[..i].trim(),
                args: after.trim(),
                args_col: (i + 2 + lead) as u32,
            }
        }
        None => Stmt {
            major: s.trim(),
            args: "",
            args_col: (s.len() + 1) as u32,
        },
    }
}

/// An argument: a number or a minor word, with its column.
#[derive(Clone, Copy, Debug)]
enum Arg<'a> {
    Num(f64),
    Word(&'a str),
}

impl AptReader {
    pub fn new(dialect: Dialect, opts: ReadOptions) -> AptReader {
        let mut units = None;
        if let Some(u) = opts.units {
            units = Some((u, UnitsOrigin::Override, 0));
        }
        AptReader {
            opts,
            program: Program::new(dialect),
            ops: Vec::new(),
            op: Operation::default(),
            diags: Diags::default(),
            stats: AptStats::default(),
            units,
            feed: 0.0,
            feed_mode: FeedMode::PerMinute,
            msys: false,
            feed_seen: false,
            feed_missing_reported: false,
            spindle: 0.0,
            last_spindle_on: 0.0,
            rapid_once: false,
            axis: None,
            pos: None,
            circle: None,
            nurbs: None,
            cycle: None,
            cont: None,
            line_no: 0,
            saw_content: false,
            ended: None,
            closed: false,
            last_record: 0,
        }
    }

    /// Feeds one physical line (without its line terminator; a trailing `\r` is ignored).
    pub fn line(&mut self, raw: &str) -> Result<(), ParseError> {
        self.line_no += 1;
        let ln = self.line_no;
        let raw = raw.strip_suffix('\r').unwrap_or(raw);
        // Fast path for the overwhelmingly common record.
        if self.cont.is_none() && self.nurbs.is_none() && self.ended.is_none() {
            if let Some(args) = raw.strip_prefix("GOTO/") {
                // Plain numbers (no `$` among them) first, without a search
                // for a `$` through the line.
                let mut v = [0.0f64; 6];
                let plain = plain_fields(args.as_bytes(), &mut v);
                if plain.is_some() || !args.contains('$') {
                    self.saw_content = true;
                    (self.closed, self.last_record) = (false, ln);
                    self.stats.records += 1;
                    self.stats.goto += 1;
                    let n = match plain {
                        Some(n) => n,
                        None => self.goto_fields(args, 6, ln, &mut v)?,
                    };
                    return self.goto_values(&v, n, 6, ln);
                }
            }
        }
        let (content, comment) = match raw.find("$$") {
            Some(i) => (&raw[..i], Some(raw[i + 2..].trim())),
            None => (raw, None),
        };
        let trimmed = content.trim_end();
        if let Some(body) = trimmed.strip_suffix('$') {
            // Continued on the next line.
            match &mut self.cont {
                Some((buf, _)) => buf.push_str(body),
                None => self.cont = Some((body.to_string(), ln)),
            }
            if let Some(c) = comment {
                self.comment(c, ln);
            }
            return Ok(());
        }
        if let Some((mut buf, first)) = self.cont.take() {
            buf.push_str(content);
            self.statement(&buf, first)?;
        } else if !content.trim().is_empty() {
            self.statement(content, ln)?;
        }
        if let Some(c) = comment {
            self.comment(c, ln);
        }
        Ok(())
    }

    fn comment(&mut self, text: &str, ln: u32) {
        self.saw_content = true;
        let named = |key: &str| {
            text.trim()
                .strip_prefix(key)
                .and_then(|r| r.trim_start().strip_prefix(':'))
                .map(str::trim)
        };
        // CATIA (and millplan's own APT) name operations and tools in comments.
        if let Some(name) = named("OPERATION NAME") {
            if !self.op.moves.is_empty() {
                self.start_new_op(false);
            }
            self.op.name = Some(name.to_string());
            return;
        }
        if let Some(name) = named("TOOL NAME") {
            let name = name.to_string();
            self.tool_record(ln, |t| t.name = Some(name));
            return;
        }
        self.op.push_event(ln, EventKind::Comment(text.to_string()));
    }

    fn args<'a>(&self, s: &Stmt<'a>, ln: u32) -> Result<Vec<(Arg<'a>, u32)>, ParseError> {
        let mut out = Vec::new();
        if s.args.is_empty() {
            return Ok(out);
        }
        let mut col = s.args_col;
        for piece in s.args.split(',') {
            let lead = (piece.len() - piece.trim_start().len()) as u32;
            let t = piece.trim();
            let c = col + lead;
            col += piece.len() as u32 + 1;
            if t.is_empty() {
                continue;
            }
            let first = t.as_bytes()[0];
            if first.is_ascii_digit() || matches!(first, b'-' | b'+' | b'.') {
                match parse_num(t) {
                    Some(v) => out.push((Arg::Num(v), c)),
                    None => {
                        // `1STPECK` is a word in SOLIDWORKS cycles.
                        let tail = t.trim_start_matches(|c: char| c.is_ascii_digit());
                        if first.is_ascii_digit()
                            && !tail.is_empty()
                            && tail.bytes().all(|b| b.is_ascii_alphabetic())
                        {
                            out.push((Arg::Word(t), c));
                        } else {
                            return Err(ParseError::new(ln, c, format!("`{t}` is not a number")));
                        }
                    }
                }
            } else {
                out.push((Arg::Word(t), c));
            }
        }
        Ok(out)
    }

    /// Arguments that must all be numbers.
    fn nums(&self, s: &Stmt, ln: u32, what: &str) -> Result<Vec<f64>, ParseError> {
        let mut v = Vec::with_capacity(8);
        for (a, c) in self.args(s, ln)? {
            match a {
                Arg::Num(x) => v.push(x),
                Arg::Word(w) => {
                    return Err(ParseError::new(
                        ln,
                        c,
                        format!("{what}: expected a number, found `{w}`"),
                    ))
                }
            }
        }
        Ok(v)
    }

    fn statement(&mut self, text: &str, ln: u32) -> Result<(), ParseError> {
        // After FINI: a PPRINT or a Ctrl-Z is let be.
        let after = text.trim_matches(|c: char| c.is_whitespace() || c == '\x1a');
        let comment = after
            .get(..6)
            .is_some_and(|w| w.eq_ignore_ascii_case("PPRINT"));
        if self.ended.is_some() && (after.is_empty() || comment) {
            return Ok(());
        }
        if let Some(end) = self.ended {
            let col = (text.len() - text.trim_start().len() + 1) as u32;
            return Err(ParseError::new(
                ln,
                col,
                format!("a record after the end of the program (FINI at line {end}): a control never runs it, and a second program in the same file is not read (split the file, or remove what follows the end)"),
            ));
        }
        self.saw_content = true;
        self.stats.records += 1;
        let s = split_stmt(text);
        let major_uc = s.major.to_ascii_uppercase();
        let major = major_uc.as_str();
        if self.nurbs.is_some() && !matches!(major, "KNOT" | "CNTRL") {
            self.flush_nurbs()?;
        }
        // Text-carrying words: everything after the word is text, never split on commas.
        for word in ["PPRINT", "PARTNO", "INSERT"] {
            if major.len() >= word.len()
                && major.starts_with(word)
                && (major.len() == word.len()
                    || !s.args.is_empty()
                    || major.as_bytes()[word.len()] == b' ')
            {
                let rest = text.trim_start();
                let rest = rest[word.len()..].trim_start();
                let rest = rest.strip_prefix('/').unwrap_or(rest).trim();
                let rest = rest.trim_matches('\'').to_string();
                match word {
                    "PPRINT" => self.comment(&rest, ln),
                    "INSERT" => self.op.push_event(ln, EventKind::Insert(rest)),
                    _ => {
                        if self.program.name.is_none() && !rest.is_empty() {
                            self.program.name = Some(rest);
                        }
                    }
                }
                return Ok(());
            }
        }
        (self.closed, self.last_record) = (false, ln);
        match major {
            "GOTO" => self.goto(s.args, s.args_col, ln),
            "FROM" => {
                let v = self.nums(&s, ln, "FROM")?;
                if v.len() < 3 {
                    return Err(ParseError::new(
                        ln,
                        s.args_col,
                        format!("FROM needs x,y,z, found {} values", v.len()),
                    ));
                }
                let p = DVec3::new(v[0], v[1], v[2]);
                if v.len() >= 6 {
                    self.axis = Some(self.unit_axis(v[3], v[4], v[5], ln, s.args_col)?);
                }
                if self.op.moves.is_empty() {
                    self.op.start = p;
                }
                self.pos = Some(p);
                Ok(())
            }
            "GODLTA" => {
                let v = self.nums(&s, ln, "GODLTA")?;
                let base = self
                    .pos
                    .ok_or_else(|| ParseError::new(ln, 1, "GODLTA before any position is known"))?;
                let p = match v.len() {
                    1 => base + self.axis.unwrap_or(DVec3::Z) * v[0],
                    3.. => base + DVec3::new(v[0], v[1], v[2]),
                    n => {
                        return Err(ParseError::new(
                            ln,
                            s.args_col,
                            format!("GODLTA takes 1 or 3 values, found {n}"),
                        ))
                    }
                };
                self.stats.goto += 1;
                self.emit_move(p, ln)
            }
            "RAPID" => {
                self.rapid_once = true;
                Ok(())
            }
            "FEDRAT" => self.fedrat(&s, ln),
            "SPINDL" => self.spindl(&s, ln),
            "CUTTER" => {
                let v = self.nums(&s, ln, "CUTTER")?;
                let cutter = match v.len() {
                    0 => {
                        return Err(ParseError::new(
                            ln,
                            s.args_col,
                            "CUTTER needs at least a diameter",
                        ))
                    }
                    1 => Cutter::from_d_r(v[0], 0.0, 0.0),
                    2 => Cutter::from_d_r(v[0], v[1], 0.0),
                    n => {
                        let g = |i: usize| if i < n { v[i] } else { 0.0 };
                        Cutter::from_iso(
                            g(0),
                            g(1),
                            g(2),
                            g(3),
                            g(4).to_radians(),
                            g(5).to_radians(),
                            g(6),
                        )
                    }
                };
                self.check_cutter(&cutter, ln, s.args_col)?;
                self.tool_record(ln, |t| t.cutter = Some(cutter));
                Ok(())
            }
            "TLDATA" => self.tldata(&s, ln),
            "LOAD" | "LOADTL" | "TOOLNO" => {
                let args = self.args(&s, ln)?;
                let num = args
                    .iter()
                    .find_map(|(a, _)| if let Arg::Num(x) = a { Some(*x) } else { None });
                if let Some(n) = num {
                    if n < 0.0 || n.fract() != 0.0 {
                        return Err(ParseError::new(
                            ln,
                            s.args_col,
                            format!("tool number `{n}` is not a whole number"),
                        ));
                    }
                    self.tool_record(ln, |t| t.number = Some(n as u32));
                } else {
                    self.passthrough(major, text, ln);
                }
                Ok(())
            }
            "TOOL PATH" => {
                self.start_new_op(true);
                let mut parts = s.args.split(',').map(str::trim);
                self.op.name = parts.next().filter(|p| !p.is_empty()).map(str::to_string);
                if parts
                    .next()
                    .map(|w| w.eq_ignore_ascii_case("TOOL"))
                    .unwrap_or(false)
                {
                    if let Some(name) = parts.next() {
                        let name = name.to_string();
                        self.tool_record(ln, |t| t.name = Some(name));
                    }
                }
                Ok(())
            }
            "MULTAX" => {
                if s.args.trim().eq_ignore_ascii_case("OFF") {
                    // Three-axis output again: the tool stands along +Z, not at
                    // the last five-axis orientation.
                    self.axis = self.axis.map(|_| DVec3::Z);
                }
                Ok(())
            }
            "TLAXIS" => {
                let v = self.nums(&s, ln, "TLAXIS")?;
                if v.len() < 3 {
                    return Err(ParseError::new(ln, s.args_col, "TLAXIS needs i,j,k"));
                }
                self.axis = Some(self.unit_axis(v[0], v[1], v[2], ln, s.args_col)?);
                Ok(())
            }
            "CIRCLE" => {
                let v = self.nums(&s, ln, "CIRCLE")?;
                if v.len() < 6 {
                    return Err(ParseError::new(
                        ln,
                        s.args_col,
                        format!("CIRCLE needs centre and axis (6 values), found {}", v.len()),
                    ));
                }
                let mut axis = self.unit_axis(v[3], v[4], v[5], ln, s.args_col)?;
                // Under NX's MSYS a CIRCLE's centre is in the frame, as
                // every position, but its axis in the absolute frame: in
                // each NX file with arcs (MSYS Z turned over) the arcs are
                // tangent to the moves into them only so, and the posts
                // written for those files cut them that way round.
                // SOLIDWORKS's CSYS frames give the axis in the frame.
                if self.msys {
                    if let Some(f) = self.op.frame {
                        axis = f.rot.transpose() * axis;
                    }
                }
                let layout = if v.len() >= 7 {
                    if v[6] <= 0.0 {
                        return Err(ParseError::new(
                            ln,
                            s.args_col,
                            format!("CIRCLE radius {} is not positive", v[6]),
                        ));
                    }
                    CircleLayout::WithRadius(v[6])
                } else {
                    CircleLayout::NoRadius
                };
                self.stats.circle += 1;
                self.circle = Some(PendingCircle {
                    centre: DVec3::new(v[0], v[1], v[2]),
                    axis,
                    layout,
                    line: ln,
                });
                Ok(())
            }
            "NURBS" => {
                let start = self
                    .pos
                    .ok_or_else(|| ParseError::new(ln, 1, "NURBS before any position is known"))?;
                self.stats.nurbs += 1;
                self.nurbs = Some(PendingNurbs {
                    start,
                    knots: Vec::new(),
                    cntrl: Vec::new(),
                    line: ln,
                });
                Ok(())
            }
            "KNOT" | "CNTRL" => {
                let v = self.nums(&s, ln, major)?;
                let Some(n) = self.nurbs.as_mut() else {
                    return Err(ParseError::new(
                        ln,
                        1,
                        format!("{major} outside a NURBS record"),
                    ));
                };
                if major == "KNOT" {
                    n.knots.extend_from_slice(&v);
                } else {
                    if v.len() < 3 {
                        return Err(ParseError::new(ln, s.args_col, "CNTRL needs x,y,z"));
                    }
                    n.cntrl.push(DVec3::new(v[0], v[1], v[2]));
                }
                Ok(())
            }
            "UNITS" | "UNIT" => {
                let w = s.args.trim().to_ascii_uppercase();
                let u = match w.as_str() {
                    "MM" | "MILLIMETERS" | "MILLIMETRES" => LengthUnit::Mm,
                    "INCHES" | "INCH" | "IN" => LengthUnit::Inch,
                    _ => {
                        return Err(ParseError::new(
                            ln,
                            s.args_col,
                            format!("unknown unit `{}`", s.args.trim()),
                        ))
                    }
                };
                self.set_units(u, UnitsOrigin::Declared, ln);
                Ok(())
            }
            "MSYS" => {
                let v = self.nums(&s, ln, "MSYS")?;
                if v.len() < 9 {
                    return Err(ParseError::new(
                        ln,
                        s.args_col,
                        format!("MSYS needs 9 values, found {}", v.len()),
                    ));
                }
                let f = Frame::from_origin_xy(
                    DVec3::new(v[0], v[1], v[2]),
                    DVec3::new(v[3], v[4], v[5]),
                    DVec3::new(v[6], v[7], v[8]),
                )
                .ok_or_else(|| ParseError::new(ln, s.args_col, "MSYS axes are not orthonormal"))?;
                self.msys = true;
                self.set_frame(f);
                Ok(())
            }
            "CSYS" => {
                let v = self.nums(&s, ln, "CSYS")?;
                if v.len() < 12 {
                    return Err(ParseError::new(
                        ln,
                        s.args_col,
                        format!("CSYS needs 12 values, found {}", v.len()),
                    ));
                }
                let mut m = [0.0; 12];
                m.copy_from_slice(&v[..12]);
                let f = Frame::from_rows_3x4(&m).ok_or_else(|| {
                    ParseError::new(ln, s.args_col, "CSYS rotation is not orthonormal")
                })?;
                self.msys = false;
                self.set_frame(f);
                Ok(())
            }
            "CUTCOM" => {
                let w = s
                    .args
                    .split(',')
                    .next()
                    .unwrap_or("")
                    .trim()
                    .to_ascii_uppercase();
                let c = match w.as_str() {
                    "LEFT" => CutCom::Left,
                    "RIGHT" => CutCom::Right,
                    "OFF" => CutCom::Off,
                    _ => {
                        self.passthrough(major, text, ln);
                        return Ok(());
                    }
                };
                self.op.push_event(
                    ln,
                    EventKind::CutCom {
                        side: c,
                        register: None,
                    },
                );
                Ok(())
            }
            "COOLNT" => {
                let w = s
                    .args
                    .split(',')
                    .next()
                    .unwrap_or("")
                    .trim()
                    .to_ascii_uppercase();
                let c = match w.as_str() {
                    "ON" | "FLOOD" => Coolant::Flood,
                    "MIST" => Coolant::Mist,
                    "THRU" | "TAPKUL" => Coolant::Through,
                    "AIR" => Coolant::Air,
                    "OFF" => Coolant::Off,
                    _ => {
                        self.passthrough(major, text, ln);
                        return Ok(());
                    }
                };
                self.op.push_event(ln, EventKind::Coolant(c));
                Ok(())
            }
            "CYCLE" => self.cycle_record(&s, text, ln),
            "STOP" => {
                self.op.push_event(ln, EventKind::Stop { optional: false });
                Ok(())
            }
            "OPSTOP" => {
                self.op.push_event(ln, EventKind::Stop { optional: true });
                Ok(())
            }
            "DELAY" | "DWELL" => {
                let v = self.nums(&s, ln, major)?;
                self.op
                    .push_event(ln, EventKind::Dwell(v.first().copied().unwrap_or(0.0)));
                Ok(())
            }
            "END" | "FINI" | "END-OF-PATH" => {
                self.closed = true;
                if major == "FINI" {
                    self.ended = Some(ln);
                }
                Ok(())
            }
            // Known post and display words, kept verbatim without a diagnostic.
            "SELECT" | "SELCTL" => {
                let args = self.args(&s, ln)?;
                let num = args
                    .iter()
                    .find_map(|(a, _)| if let Arg::Num(x) = a { Some(*x) } else { None });
                let tool = args.first().is_some_and(
                    |(a, _)| matches!(a, Arg::Word(w) if w.eq_ignore_ascii_case("TOOL")),
                ) || major == "SELCTL";
                match num {
                    Some(n) if tool && n >= 0.0 && n.fract() == 0.0 => {
                        self.op.push_event(ln, EventKind::ToolSelect(n as u32))
                    }
                    _ => self.passthrough(major, text, ln),
                }
                Ok(())
            }
            "PAINT" | "TRNTYP" | "MACHIN" | "SEQNO" | "OPSKIP" | "CLRSRF" | "AUXFUN" | "PREFUN"
            | "RETRCT" | "CLAMP" | "ROTABL" | "ROTATE" | "ORIGIN" | "PITCH" | "THREAD" | "MODE"
            | "OPERATION" | "DISPLY" | "LINTOL" | "INTOL" | "OUTTOL" | "TOLER" | "CATIA0"
            | "TPRINT" | "TMARK" | "PLABEL" | "POSTN" | "INDEX" | "COUPLE" | "LEADER"
            | "CLEARP" | "SAFETY" | "HEAD" | "ROTHED" => {
                self.passthrough(major, text, ln);
                Ok(())
            }
            _ if major.starts_with("CSI_") => {
                self.passthrough(major, text, ln);
                Ok(())
            }
            _ => {
                if major.is_empty()
                    || !major
                        .bytes()
                        .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b' ' || b == b'-')
                {
                    return Err(ParseError::new(
                        ln,
                        1,
                        format!("`{}` is not an APT statement", text.trim()),
                    ));
                }
                self.diags.warn(
                    Code::UnknownWord,
                    ln,
                    1,
                    format!("unknown record `{major}` kept verbatim"),
                );
                self.passthrough(major, text, ln);
                Ok(())
            }
        }
    }

    fn passthrough(&mut self, word: &str, text: &str, ln: u32) {
        // Hints to the CAM system's display or post that no machine acts on.
        const INFO: &[&str] = &[
            "PAINT",
            "TRNTYP",
            "MACHIN",
            "CLRSRF",
            "MODE",
            "OPERATION",
            "DISPLY",
            "LINTOL",
            "INTOL",
            "OUTTOL",
            "TOLER",
            "CATIA0",
            "TPRINT",
            "TMARK",
            "PLABEL",
            "LEADER",
            "SEQNO",
        ];
        // `CYCLE/INIT` marks where a cycle definition starts; the definition
        // that follows says what the machine does.
        let class = if INFO.contains(&word) || word.starts_with("CSI_") || word == "CYCLE/INIT" {
            PassClass::Info
        } else {
            PassClass::Machine
        };
        self.op.push_event(
            ln,
            EventKind::Passthrough(Passthrough {
                word: word.to_string(),
                text: text.trim().to_string(),
                class,
                modal: false,
                moves: false,
            }),
        );
    }

    fn unit_axis(&self, i: f64, j: f64, k: f64, ln: u32, col: u32) -> Result<DVec3, ParseError> {
        let v = DVec3::new(i, j, k);
        let l = v.length();
        if !(l > 1e-6) {
            return Err(ParseError::new(
                ln,
                col,
                "tool axis (i,j,k) has zero length",
            ));
        }
        if (l - 1.0).abs() > 1e-3 {
            return Err(ParseError::new(
                ln,
                col,
                format!("tool axis (i,j,k) has length {l:.6}, not 1"),
            ));
        }
        Ok(v / l)
    }

    fn goto(&mut self, args: &str, col0: u32, ln: u32) -> Result<(), ParseError> {
        self.stats.goto += 1;
        let mut v = [0.0f64; 6];
        let n = match plain_fields(args.as_bytes(), &mut v) {
            Some(n) => n,
            None => self.goto_fields(args, col0, ln, &mut v)?,
        };
        self.goto_values(&v, n, col0, ln)
    }

    /// The move of a GOTO whose `n` numbers are read (the first six in `v`).
    fn goto_values(
        &mut self,
        v: &[f64; 6],
        n: usize,
        col0: u32,
        ln: u32,
    ) -> Result<(), ParseError> {
        match n {
            3 => {}
            6.. => {
                self.stats.goto_with_axis += 1;
                self.axis = Some(self.unit_axis(v[3], v[4], v[5], ln, col0)?);
            }
            _ => {
                return Err(ParseError::new(
                    ln,
                    col0,
                    format!(
                        "GOTO needs x,y,z or x,y,z,i,j,k; found {n} value{}",
                        if n == 1 { "" } else { "s" }
                    ),
                ))
            }
        }
        self.emit_move(DVec3::new(v[0], v[1], v[2]), ln)
    }

    /// The numbers of a GOTO's fields, any that [`plain_fields`] does not
    /// take (spaces, exponents, long digits, empty fields): into `v`, the
    /// count returned; a field that is no number is an error at its column.
    fn goto_fields(
        &self,
        args: &str,
        col0: u32,
        ln: u32,
        v: &mut [f64; 6],
    ) -> Result<usize, ParseError> {
        let mut n = 0;
        let mut col = col0;
        for piece in args.split(',') {
            let t = piece.trim();
            let c = col + (piece.len() - piece.trim_start().len()) as u32;
            col += piece.len() as u32 + 1;
            if t.is_empty() {
                continue;
            }
            let x = parse_num(t)
                .ok_or_else(|| ParseError::new(ln, c, format!("GOTO: `{t}` is not a number")))?;
            if n < 6 {
                v[n] = x;
            }
            n += 1;
        }
        Ok(n)
    }

    fn emit_move(&mut self, end: DVec3, ln: u32) -> Result<(), ParseError> {
        let orient = self.axis.map(|a| self.op.intern_orient(Orient::vector(a)));
        let mut m = Move {
            end,
            feed: self.feed,
            spindle: self.spindle,
            line: ln,
            orient,
            kind: MoveKind::Linear,
            feed_mode: self.feed_mode,
        };
        if self.rapid_once {
            self.rapid_once = false;
            m.kind = MoveKind::Rapid;
            m.feed = 0.0;
            if self.circle.is_some() {
                self.diags.warn(
                    Code::RapidCircle,
                    ln,
                    1,
                    "RAPID before a CIRCLE end point: moved as a rapid line",
                );
                self.circle = None;
            }
        } else if let Some(c) = self.circle.take() {
            let start = self
                .pos
                .ok_or_else(|| ParseError::new(c.line, 1, "CIRCLE before any position is known"))?;
            let full = (start - end).length() < 1e-7 * (1.0 + start.length());
            let arc = Arc::from_points(start, end, c.centre, c.axis, full).ok_or_else(|| {
                ParseError::new(c.line, 1, "CIRCLE: start point lies on the arc axis")
            })?;
            let r_end = {
                let b = end - c.centre;
                (b - c.axis * b.dot(c.axis)).length()
            };
            let tol = crate::verify::ARC_TOL + 1e-4 * arc.radius;
            if (r_end - arc.radius).abs() > tol {
                self.diags.warn(
                    Code::ArcRadius,
                    ln,
                    1,
                    format!(
                        "arc end is {:.4} from the centre, start {:.4}",
                        r_end, arc.radius
                    ),
                );
            }
            if let CircleLayout::WithRadius(r) = c.layout {
                if (r - arc.radius).abs() > tol.max(1e-4 * r) {
                    self.diags.warn(
                        Code::ArcRadius,
                        c.line,
                        1,
                        format!(
                            "CIRCLE radius {r} but the start point is {:.4} from the centre",
                            arc.radius
                        ),
                    );
                }
            }
            m.kind = MoveKind::Arc(self.op.push_arc(arc));
        } else if let Some(cy) = self.cycle {
            m.kind = MoveKind::Cycle(cy);
        }
        if m.is_cutting() && !self.feed_seen {
            m.feed = self.opts.default_feed;
            if !self.feed_missing_reported {
                self.feed_missing_reported = true;
                self.diags.warn(
                    Code::FeedMissing,
                    ln,
                    1,
                    format!(
                        "cutting move before any FEDRAT: read at {} mm/min, the readers' default (a FEDRAT before it gives the feed; `millplan convert --feed` another default)",
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
                "cutting move before any CUTTER, TLDATA or LOADTL: tool unknown",
            );
        }
        if self.op.moves.is_empty() && self.op.start.is_nan() {
            self.op.start = self.pos.unwrap_or(UNKNOWN);
        }
        if self.op.moves.capacity() == 0 && self.opts.expect_moves > 0 {
            // Room may be refused for a wild guess; the moves then grow as usual.
            let _ = self
                .op
                .moves
                .try_reserve_exact(std::mem::take(&mut self.opts.expect_moves));
        }
        self.op.moves.push(m);
        self.pos = Some(end);
        Ok(())
    }

    fn flush_nurbs(&mut self) -> Result<(), ParseError> {
        let Some(n) = self.nurbs.take() else {
            return Ok(());
        };
        let spline = nurbs::BSpline::from_nx(n.start, &n.knots, &n.cntrl)
            .map_err(|e| ParseError::new(n.line, 1, format!("NURBS: {e}")))?;
        let limit = self.opts.limits.expansion;
        let points = spline
            .sample_within(self.opts.chord_tol, limit)
            .map_err(|span| {
                let needs = format!(
                    "NURBS: span {span} needs more than {limit} moves at the chord tolerance of {} mm",
                    self.opts.chord_tol
                );
                let e = crate::Exceeded::new("expansion", needs, limit as f64);
                ParseError::new(n.line, 1, e.to_string())
            })?;
        for p in points {
            self.emit_move(p, n.line)?;
        }
        Ok(())
    }

    fn fedrat(&mut self, s: &Stmt, ln: u32) -> Result<(), ParseError> {
        let mut value = None;
        let mut mode = FeedMode::PerMinute;
        let mut unit = None;
        for (a, c) in self.args(s, ln)? {
            match a {
                Arg::Num(x) => {
                    if value.is_some() {
                        return Err(ParseError::new(ln, c, "FEDRAT has two numbers"));
                    }
                    value = Some(x);
                }
                Arg::Word(w) => match w.to_ascii_uppercase().as_str() {
                    "MMPM" => unit = Some(LengthUnit::Mm),
                    "IPM" => unit = Some(LengthUnit::Inch),
                    "MMPR" => {
                        unit = Some(LengthUnit::Mm);
                        mode = FeedMode::PerRev;
                    }
                    "IPR" => {
                        unit = Some(LengthUnit::Inch);
                        mode = FeedMode::PerRev;
                    }
                    "INVERS" => mode = FeedMode::InverseTime,
                    _ => {
                        self.diags.warn(
                            Code::UnknownWord,
                            ln,
                            c,
                            format!("FEDRAT word `{w}` ignored"),
                        );
                    }
                },
            }
        }
        let v =
            value.ok_or_else(|| ParseError::new(ln, s.args_col, "FEDRAT without a feed value"))?;
        if v <= 0.0 {
            return Err(ParseError::new(
                ln,
                s.args_col,
                format!("feed {v} is not positive"),
            ));
        }
        if let Some(u) = unit {
            match self.units {
                None => self.set_units(u, UnitsOrigin::InferredFromFeed, ln),
                Some((have, _, _)) if have != u => {
                    self.diags.warn(
                        Code::UnitsConflict,
                        ln,
                        s.args_col,
                        format!("feed unit says {u:?} but the file's unit is {have:?}; the file's unit is used"),
                    );
                }
                _ => {}
            }
        }
        self.feed = v;
        self.feed_mode = mode;
        self.feed_seen = true;
        Ok(())
    }

    fn spindl(&mut self, s: &Stmt, ln: u32) -> Result<(), ParseError> {
        let mut rpm = None;
        let mut dir = SpindleDir::Cw;
        let mut on = true;
        for (a, c) in self.args(s, ln)? {
            match a {
                Arg::Num(x) => rpm = rpm.or(Some(x)),
                Arg::Word(w) => match w.to_ascii_uppercase().as_str() {
                    "RPM" | "ON" | "RANGE" | "MAXRPM" => {}
                    "CLW" => dir = SpindleDir::Cw,
                    "CCLW" => dir = SpindleDir::Ccw,
                    "OFF" | "LOCK" => on = false,
                    "SFM" | "SMM" => {
                        self.diags.warn(
                            Code::ConstantSurfaceSpeed,
                            ln,
                            c,
                            "constant surface speed spindle kept as its number",
                        );
                    }
                    _ => self.diags.warn(
                        Code::UnknownWord,
                        ln,
                        c,
                        format!("SPINDL word `{w}` ignored"),
                    ),
                },
            }
        }
        if !on {
            self.spindle = 0.0;
            self.op.push_event(ln, EventKind::Spindle(SpindleDir::Off));
            return Ok(());
        }
        let rpm = rpm.unwrap_or(self.last_spindle_on);
        if rpm < 0.0 {
            return Err(ParseError::new(
                ln,
                s.args_col,
                format!("spindle speed {rpm} is negative"),
            ));
        }
        self.spindle = rpm;
        self.last_spindle_on = rpm;
        self.op.push_event(ln, EventKind::Spindle(dir));
        Ok(())
    }

    fn tldata(&mut self, s: &Stmt, ln: u32) -> Result<(), ParseError> {
        let args = self.args(s, ln)?;
        let nums: Vec<f64> = args
            .iter()
            .filter_map(|(a, _)| if let Arg::Num(x) = a { Some(*x) } else { None })
            .collect();
        let kind = args.iter().find_map(|(a, _)| {
            if let Arg::Word(w) = a {
                Some(w.to_ascii_uppercase())
            } else {
                None
            }
        });
        if nums.is_empty() {
            return Err(ParseError::new(ln, s.args_col, "TLDATA without dimensions"));
        }
        let g = |i: usize| nums.get(i).copied().unwrap_or(0.0);
        let (d, r, len, taper, tip) = (g(0), g(1), g(2), g(3), g(4));
        let cutter = match kind.as_deref() {
            Some("DRILL") => {
                // TLDATA/DRILL,d,point_angle,length,...: point angle is the included angle.
                let alpha = (90.0 - g(1) / 2.0).to_radians();
                Cutter::from_iso(d, 0.0, d / 2.0, d / 2.0 * alpha.tan(), alpha, 0.0, g(2))
            }
            _ => {
                if nums.len() >= 7 {
                    // 7- and 10-value forms carry the corner centre offsets explicitly.
                    Cutter::from_iso(d, r, g(5), g(6), tip.to_radians(), taper.to_radians(), len)
                } else {
                    let alpha = tip.to_radians();
                    let e = d / 2.0 - r;
                    Cutter::from_iso(d, r, e, r, alpha, taper.to_radians(), len)
                }
            }
        };
        self.check_cutter(&cutter, ln, s.args_col)?;
        self.tool_record(ln, |t| t.cutter = Some(cutter));
        Ok(())
    }

    fn check_cutter(&self, c: &Cutter, ln: u32, col: u32) -> Result<(), ParseError> {
        if !(c.d > 0.0) || c.r < 0.0 || c.r > c.d / 2.0 + 1e-5 * c.d.max(1.0) || c.h < 0.0 {
            return Err(ParseError::new(
                ln,
                col,
                format!(
                    "cutter d={} r={} is not a valid tool (need d > 0, 0 ≤ r ≤ d/2)",
                    c.d, c.r
                ),
            ));
        }
        Ok(())
    }

    /// Applies a tool-defining record: to the current operation if it has not moved
    /// yet, otherwise to a new operation.
    fn tool_record(&mut self, ln: u32, f: impl FnOnce(&mut Tool)) {
        if !self.op.moves.is_empty() {
            self.start_new_op(false);
            // A new tool: geometry and number of the previous one no longer apply.
            self.op.tool = None;
        }
        let t = self.op.tool.get_or_insert(Tool {
            number: None,
            name: None,
            cutter: None,
            line: ln,
        });
        f(t);
    }

    fn set_frame(&mut self, f: Frame) {
        let frame = if f.is_identity() { None } else { Some(f) };
        // SOLIDWORKS CAM restates the frame it is in: nothing changes.
        if frame == self.op.frame {
            return;
        }
        if !self.op.moves.is_empty() {
            self.start_new_op(false);
        }
        self.op.frame = frame;
    }

    fn set_units(&mut self, u: LengthUnit, origin: UnitsOrigin, ln: u32) {
        match self.units {
            None => self.units = Some((u, origin, ln)),
            Some((_, UnitsOrigin::Override, _)) => {}
            Some((have, _, first)) if have != u => {
                self.diags.warn(
                    Code::UnitsConflict,
                    ln,
                    1,
                    format!(
                        "unit changes to {u:?} after {have:?} (line {first}); the first is used"
                    ),
                );
            }
            _ => {}
        }
    }

    fn cycle_record(&mut self, s: &Stmt, text: &str, ln: u32) -> Result<(), ParseError> {
        let args = self.args(s, ln)?;
        let Some((Arg::Word(first), _)) = args.first() else {
            return Err(ParseError::new(
                ln,
                s.args_col,
                "CYCLE without a cycle name",
            ));
        };
        let name = first.to_ascii_uppercase();
        match name.as_str() {
            "OFF" => {
                self.cycle = None;
                return Ok(());
            }
            "INIT" | "ON" => {
                self.passthrough(&format!("CYCLE/{name}"), text, ln);
                return Ok(());
            }
            _ => {}
        }
        let mut cy = Cycle {
            name: name.clone(),
            bottom: 0.0,
            clearance: 0.0,
            retract: f64::NAN,
            feed: if self.feed_seen {
                self.feed
            } else {
                self.opts.default_feed
            },
            peck: None,
            peck_next: None,
            dwell: None,
            line: ln,
        };
        // The classic positional form `CYCLE/DRILL, d, MMPM, f, c`: the
        // depth before the feed's unit, the clearance after its feed.
        let (mut depth_seen, mut feed_seen, mut clear_seen) = (false, false, false);
        let mut i = 1;
        while i < args.len() {
            let (a, c) = args[i];
            let next = args
                .get(i + 1)
                .and_then(|(a, _)| if let Arg::Num(x) = a { Some(*x) } else { None });
            match a {
                Arg::Word(w) => {
                    let w = w.to_ascii_uppercase();
                    let take = |i: &mut usize| -> Result<f64, ParseError> {
                        *i += 1;
                        next.ok_or_else(|| {
                            ParseError::new(ln, c, format!("CYCLE: `{w}` needs a number"))
                        })
                    };
                    match w.as_str() {
                        "FEDTO" | "DEPTH" => cy.bottom = -take(&mut i)?.abs(),
                        "RAPTO" | "CLEAR" => cy.clearance = take(&mut i)?,
                        "RTRCTO" => cy.retract = take(&mut i)?,
                        "MMPM" | "IPM" => {
                            cy.feed = take(&mut i)?;
                            feed_seen = true;
                            if w == "IPM" && self.units.is_none() {
                                self.set_units(LengthUnit::Inch, UnitsOrigin::InferredFromFeed, ln);
                            }
                        }
                        "STEP" | "1STPECK" | "PECK" => cy.peck = Some(take(&mut i)?),
                        "SUBPECK" | "STEP2" => cy.peck_next = Some(take(&mut i)?),
                        "DWELL" => cy.dwell = Some(take(&mut i)?),
                        _ => {
                            self.diags.warn(
                                Code::UnknownWord,
                                ln,
                                c,
                                format!("CYCLE word `{w}` is not modelled: the cycle is spelled out without it"),
                            );
                            if next.is_some() {
                                i += 1;
                            }
                        }
                    }
                }
                Arg::Num(x) if !feed_seen && !depth_seen => {
                    cy.bottom = -x.abs();
                    depth_seen = true;
                }
                Arg::Num(x) if feed_seen && !clear_seen => {
                    cy.clearance = x;
                    clear_seen = true;
                }
                Arg::Num(x) => {
                    // A number no word names and no position gives a
                    // meaning: dropping it could lose a depth.
                    return Err(ParseError::new(
                        ln,
                        c,
                        format!(
                            "CYCLE: the number {x} has no word before it (FEDTO, RAPTO, RTRCTO, STEP, DWELL, MMPM ...) and is not the depth or the clearance of the form CYCLE/{name}, depth, MMPM, feed, clearance"
                        ),
                    ));
                }
            }
            i += 1;
        }
        if cy.retract.is_nan() {
            cy.retract = cy.clearance;
        }
        if cy.feed <= 0.0 {
            return Err(ParseError::new(
                ln,
                s.args_col,
                "CYCLE feed is not positive",
            ));
        }
        self.cycle = Some(self.op.push_cycle(cy));
        self.op
            .push_event(ln, EventKind::Comment(format!("cycle {}", text.trim())));
        Ok(())
    }

    fn start_new_op(&mut self, fresh_frame: bool) {
        if self.op.moves.is_empty() && self.op.events.is_empty() && self.op.tool.is_none() {
            return;
        }
        let prev = std::mem::take(&mut self.op);
        self.op.tool = prev.tool.clone();
        self.op.frame = if fresh_frame { None } else { prev.frame };
        self.op.start = self.pos.unwrap_or(UNKNOWN);
        // A new operation ends a cycle: SOLIDWORKS CAM writes no CYCLE/OFF
        // before the contour of its next tool.
        self.cycle = None;
        self.ops.push(prev);
    }

    /// Ends reading: resolves units and returns the program.
    pub fn finish(mut self) -> Result<Parsed, ParseError> {
        if let Some((_, ln)) = &self.cont {
            return Err(ParseError::new(
                *ln,
                1,
                "file ends inside a `$` continuation",
            ));
        }
        self.flush_nurbs()?;
        if let Some(c) = &self.circle {
            return Err(ParseError::new(
                c.line,
                1,
                "CIRCLE without an end point (no GOTO follows)",
            ));
        }
        if !self.saw_content {
            return Err(ParseError::new(1, 1, "empty file: no APT records"));
        }
        if !self.closed && self.last_record > 0 {
            let last = self.last_record;
            self.diags.warn(
                Code::ProgramEnd,
                last,
                1,
                format!("the program has no end (FINI, or NX's END-OF-PATH last): a file cut short ends like this; its last record, line {last}, is read as written"),
            );
            // A bare list of GOTOs is a fragment by nature (warned of,
            // not taken for a program cut short).
            if self.stats.records > self.stats.goto {
                self.program.unterminated = Some(last);
            }
        }
        let prev = std::mem::take(&mut self.op);
        self.ops.push(prev);
        self.ops
            .retain(|o| !(o.moves.is_empty() && o.events.is_empty() && o.tool.is_none()));
        let (unit, origin) = match self.units {
            Some((u, o, _)) => (u, o),
            None => {
                self.diags.warn(
                    Code::UnitsAssumed,
                    0,
                    0,
                    "no unit statement or feed unit: millimetres assumed (override with --units)",
                );
                (LengthUnit::Mm, UnitsOrigin::Assumed)
            }
        };
        self.program.units = Units {
            source: unit,
            origin,
        };
        self.program.operations = self.ops;
        if unit != LengthUnit::Mm {
            crate::transform::scale_lengths(&mut self.program, unit.mm());
        }
        Ok(Parsed {
            program: self.program,
            diagnostics: self.diags.finish(),
        })
    }
}

/// Reads APT/CL text held in memory.
pub fn parse_apt(
    src: &str,
    dialect: Dialect,
    opts: ReadOptions,
) -> Result<(Parsed, AptStats), ParseError> {
    let mut r = AptReader::new(dialect, opts);
    for line in crate::lines::split(src) {
        r.line(line)?;
    }
    let stats = r.stats;
    Ok((r.finish()?, stats))
}

/// The numbers of a GOTO's fields when every field is a plain decimal
/// (`diag::plain_decimal`, after an optional `+`): into `v` (the first six),
/// their count returned; `None` sends the line to the general path.
#[inline]
fn plain_fields(b: &[u8], v: &mut [f64; 6]) -> Option<usize> {
    let mut n = 0;
    let mut i = 0;
    loop {
        i += usize::from(b.get(i) == Some(&b'+'));
        let (x, len) = crate::diag::plain_decimal(&b[i..])?;
        if let Some(slot) = v.get_mut(n) {
            *slot = x;
        }
        n += 1;
        i += len;
        if i == b.len() {
            return Some(n);
        }
        i += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// Whatever the quick scan of a GOTO's fields takes, the general path
        /// reads to the same count and the same bits.
        #[test]
        fn plain_fields_agree_with_the_general_path(args in "[-+ .0-9,e]{0,40}") {
            let r = AptReader::new(Dialect::AptIso, ReadOptions::default());
            let mut quick = [0.0f64; 6];
            if let Some(n) = plain_fields(args.as_bytes(), &mut quick) {
                let mut general = [0.0f64; 6];
                let m = r.goto_fields(&args, 6, 1, &mut general);
                proptest::prop_assert_eq!(m, Ok(n), "{:?}", args);
                for k in 0..n.min(6) {
                    proptest::prop_assert_eq!(quick[k].to_bits(), general[k].to_bits(), "{:?}", args);
                }
            }
        }
    }

    #[test]
    fn plain_fields_take_only_plain_decimals() {
        let mut v = [0.0f64; 6];
        assert_eq!(plain_fields(b"1.5,-2,+.25", &mut v), Some(3));
        assert_eq!(v[..3], [1.5, -2.0, 0.25]);
        assert_eq!(plain_fields(b"1,2,3,0,0,1,9", &mut v), Some(7));
        for not in [
            "1, 2,3", "1,,3", "1,2,", "1e3,2,3", "1,2,3 $", "", "-+1,2,3",
        ] {
            assert_eq!(plain_fields(not.as_bytes(), &mut v), None, "{not}");
        }
    }
}
