//! The IR's text form: `millplan inspect --ir`, golden files and data-driven pass
//! tests (`IR in → IR out`). [`print()`] and [`parse()`] round-trip exactly: numbers
//! are written as the shortest decimal that reads back to the same `f64`
//! (angles in radians), `?` is an unknown coordinate and `-` an absent value.
//!
//! ```text
//! program "DEMO" source=fanuc units=mm/declared
//! op name="ROUGH"
//!   tool number=8 name=- line=3 cutter=ball d=10 r=5 e=0 f=5 a=0 b=0 h=0
//!   start (?, ?, ?)
//!   arc centre=(20, 15, -1) normal=(0, 0, -1) r=10 sweep=4.71238898038469
//!   cycle name="G81" bottom=-12 clear=0 retract=0 feed=100 peck=- dwell=- line=11
//!   orient axis=- abc=(-, 0.5235987755982988, 0)
//!   L6 event spindle cw
//!   L6 rapid (10, 5, 50) F0 S2000 per_minute
//!   L9 arc#0 (30, 15, -1) F250 S2000 per_minute orient#0
//! ```

use crate::diag::ParseError;
use crate::ir::*;
use millplan_geom::{DMat3, DVec3, Frame};
use std::fmt::Write;

fn num(s: &mut String, v: f64) {
    if v.is_nan() {
        s.push('?');
    } else {
        let _ = write!(s, "{v}");
    }
}

fn v3(s: &mut String, v: DVec3) {
    s.push('(');
    num(s, v.x);
    s.push_str(", ");
    num(s, v.y);
    s.push_str(", ");
    num(s, v.z);
    s.push(')');
}

fn opt_num(s: &mut String, v: Option<f64>) {
    match v {
        Some(x) => num(s, x),
        None => s.push('-'),
    }
}

fn quoted(s: &mut String, t: &str) {
    s.push('"');
    for c in t.chars() {
        match c {
            '"' => s.push_str("\\\""),
            '\\' => s.push_str("\\\\"),
            '\n' => s.push_str("\\n"),
            '\r' => s.push_str("\\r"),
            c => s.push(c),
        }
    }
    s.push('"');
}

fn opt_str(s: &mut String, t: &Option<String>) {
    match t {
        Some(t) => quoted(s, t),
        None => s.push('-'),
    }
}

fn feed_mode_name(m: FeedMode) -> &'static str {
    match m {
        FeedMode::PerMinute => "per_minute",
        FeedMode::PerRev => "per_rev",
        FeedMode::InverseTime => "inverse_time",
    }
}

fn units_name(u: LengthUnit) -> &'static str {
    match u {
        LengthUnit::Mm => "mm",
        LengthUnit::Inch => "inch",
    }
}

fn origin_name(o: UnitsOrigin) -> &'static str {
    match o {
        UnitsOrigin::Declared => "declared",
        UnitsOrigin::InferredFromFeed => "inferred_from_feed",
        UnitsOrigin::Assumed => "assumed",
        UnitsOrigin::Override => "override",
    }
}

fn kind_name(k: CutterKind) -> &'static str {
    match k {
        CutterKind::Flat => "flat",
        CutterKind::Ball => "ball",
        CutterKind::Bull => "bull",
        CutterKind::Drill => "drill",
        CutterKind::General => "general",
    }
}

fn dir_name(d: SpindleDir) -> &'static str {
    match d {
        SpindleDir::Cw => "cw",
        SpindleDir::Ccw => "ccw",
        SpindleDir::Off => "off",
    }
}

fn coolant_name(c: Coolant) -> &'static str {
    match c {
        Coolant::Off => "off",
        Coolant::Flood => "flood",
        Coolant::Mist => "mist",
        Coolant::Through => "through",
        Coolant::Air => "air",
    }
}

fn cutcom_name(c: CutCom) -> &'static str {
    match c {
        CutCom::Off => "off",
        CutCom::Left => "left",
        CutCom::Right => "right",
    }
}

/// Prints a program in the IR's text form.
pub fn print(p: &Program) -> String {
    let mut s = String::with_capacity(64 * p.move_count() + 256);
    s.push_str("program ");
    opt_str(&mut s, &p.name);
    let _ = writeln!(
        s,
        " source={} units={}/{}",
        p.source.name(),
        units_name(p.units.source),
        origin_name(p.units.origin)
    );
    for op in &p.operations {
        print_op(&mut s, op);
    }
    s
}

fn print_op(s: &mut String, op: &Operation) {
    s.push_str("op name=");
    opt_str(s, &op.name);
    s.push('\n');
    if let Some(t) = &op.tool {
        s.push_str("  tool number=");
        match t.number {
            Some(n) => {
                let _ = write!(s, "{n}");
            }
            None => s.push('-'),
        }
        s.push_str(" name=");
        opt_str(s, &t.name);
        let _ = write!(s, " line={}", t.line);
        if let Some(c) = &t.cutter {
            let _ = write!(s, " cutter={}", kind_name(c.kind));
            for (k, v) in [
                ("d", c.d),
                ("r", c.r),
                ("e", c.e),
                ("f", c.f),
                ("a", c.alpha),
                ("b", c.beta),
                ("h", c.h),
            ] {
                let _ = write!(s, " {k}=");
                num(s, v);
            }
        }
        s.push('\n');
    }
    if let Some(f) = &op.frame {
        s.push_str("  frame origin=");
        v3(s, f.origin);
        s.push_str(" x=");
        v3(s, f.rot.x_axis);
        s.push_str(" y=");
        v3(s, f.rot.y_axis);
        s.push_str(" z=");
        v3(s, f.rot.z_axis);
        s.push('\n');
    }
    s.push_str("  start ");
    v3(s, op.start);
    s.push('\n');
    for a in &op.arcs {
        s.push_str("  arc centre=");
        v3(s, a.centre);
        s.push_str(" normal=");
        v3(s, a.normal);
        s.push_str(" r=");
        num(s, a.radius);
        s.push_str(" sweep=");
        num(s, a.sweep);
        s.push('\n');
    }
    for c in &op.cycles {
        s.push_str("  cycle name=");
        quoted(s, &c.name);
        for (k, v) in [
            ("bottom", c.bottom),
            ("clear", c.clearance),
            ("retract", c.retract),
            ("feed", c.feed),
        ] {
            let _ = write!(s, " {k}=");
            num(s, v);
        }
        s.push_str(" peck=");
        opt_num(s, c.peck);
        if c.peck_next.is_some() {
            s.push_str(" peck_next=");
            opt_num(s, c.peck_next);
        }
        s.push_str(" dwell=");
        opt_num(s, c.dwell);
        let _ = writeln!(s, " line={}", c.line);
    }
    for o in &op.orients {
        s.push_str("  orient axis=");
        match o.axis {
            Some(a) => v3(s, a),
            None => s.push('-'),
        }
        s.push_str(" abc=(");
        for (k, a) in o.angles.iter().enumerate() {
            if k > 0 {
                s.push_str(", ");
            }
            opt_num(s, *a);
        }
        s.push_str(")\n");
    }
    let mut ev = op.events.iter().peekable();
    for (i, m) in op.moves.iter().enumerate() {
        while let Some(e) = ev.next_if(|e| e.at as usize <= i) {
            print_event(s, e);
        }
        let _ = write!(s, "  L{} {}", m.line, m.kind.name());
        match m.kind {
            MoveKind::Arc(id) => {
                let _ = write!(s, "#{}", id.index());
            }
            MoveKind::Cycle(id) => {
                let _ = write!(s, "#{}", id.index());
            }
            _ => {}
        }
        s.push(' ');
        v3(s, m.end);
        s.push_str(" F");
        num(s, m.feed);
        s.push_str(" S");
        num(s, m.spindle);
        s.push(' ');
        s.push_str(feed_mode_name(m.feed_mode));
        if let Some(o) = m.orient {
            let _ = write!(s, " orient#{}", o.index());
        }
        s.push('\n');
    }
    for e in ev {
        print_event(s, e);
    }
}

/// `path exact-stop`, `path blend [tol=T]`, `path stop-once`,
/// `path smoothing ai-contour|look-ahead|high-speed tol=T on|off`, `path soft on|off`.
fn print_path(s: &mut String, pc: &PathControl) {
    let on = |b: bool| if b { "on" } else { "off" };
    match pc {
        PathControl::ExactStop => s.push_str("path exact-stop"),
        PathControl::StopOnce => s.push_str("path stop-once"),
        PathControl::Blend { tolerance } => {
            s.push_str("path blend");
            if let Some(t) = tolerance {
                s.push_str(" tol=");
                num(s, *t);
            }
        }
        PathControl::Smoothing { kind, on: o } => {
            s.push_str("path smoothing ");
            match kind {
                Smoothing::AiContour => s.push_str("ai-contour"),
                Smoothing::LookAhead => s.push_str("look-ahead"),
                Smoothing::HighSpeed { tolerance } => {
                    s.push_str("high-speed tol=");
                    num(s, *tolerance);
                }
            }
            let _ = write!(s, " {}", on(*o));
        }
        PathControl::Soft(o) => {
            let _ = write!(s, "path soft {}", on(*o));
        }
    }
}

/// A path-control mode as the text form writes it, without `path `.
pub fn path_control_name(pc: &PathControl) -> String {
    let mut s = String::new();
    print_path(&mut s, pc);
    s.trim_start_matches("path ").to_string()
}

fn parse_path(c: &mut Cur) -> Result<PathControl, ParseError> {
    let on_off: &[(&str, bool)] = &[("on", true), ("off", false)];
    c.ws();
    let at = c.i;
    Ok(match c.token() {
        "exact-stop" => PathControl::ExactStop,
        "stop-once" => PathControl::StopOnce,
        "blend" => PathControl::Blend {
            tolerance: if c.eat("tol=") { Some(c.num()?) } else { None },
        },
        "smoothing" => {
            let kind = if c.eat("ai-contour") {
                Smoothing::AiContour
            } else if c.eat("look-ahead") {
                Smoothing::LookAhead
            } else {
                c.expect("high-speed")?;
                c.key("tol")?;
                Smoothing::HighSpeed {
                    tolerance: c.num()?,
                }
            };
            let on = pick(c, "smoothing state", on_off)?;
            PathControl::Smoothing { kind, on }
        }
        "soft" => PathControl::Soft(pick(c, "soft state", on_off)?),
        w => {
            let w = w.to_string();
            c.i = at;
            return Err(c.err(format!("`{w}` is not a path-control mode")));
        }
    })
}

fn print_event(s: &mut String, e: &Event) {
    let _ = write!(s, "  L{} event ", e.line);
    match &e.kind {
        EventKind::Comment(t) => {
            s.push_str("comment ");
            quoted(s, t);
        }
        EventKind::Insert(t) => {
            s.push_str("insert ");
            quoted(s, t);
        }
        EventKind::Spindle(d) => {
            let _ = write!(s, "spindle {}", dir_name(*d));
        }
        EventKind::Coolant(c) => {
            let _ = write!(s, "coolant {}", coolant_name(*c));
        }
        EventKind::CutCom { side, register } => {
            let _ = write!(s, "cutcom {}", cutcom_name(*side));
            if let Some(r) = register {
                let _ = write!(s, " D{r}");
            }
        }
        EventKind::ToolLength(ToolLength::Off) => s.push_str("tool-length off"),
        EventKind::ToolLength(ToolLength::On { register }) => {
            s.push_str("tool-length on");
            if let Some(r) = register {
                let _ = write!(s, " H{r}");
            }
        }
        EventKind::Tcp(on) => {
            let _ = write!(s, "tcp {}", if *on { "on" } else { "off" });
        }
        EventKind::WorkOffset(w) => {
            let _ = write!(s, "work-offset {}", w.0);
        }
        EventKind::ToolSelect(n) => {
            let _ = write!(s, "tool-select {n}");
        }
        EventKind::Stop { optional } => {
            s.push_str(if *optional {
                "stop optional"
            } else {
                "stop program"
            });
        }
        EventKind::Dwell(t) => {
            s.push_str("dwell ");
            num(s, *t);
        }
        EventKind::PathControl(pc) => print_path(s, pc),
        EventKind::Passthrough(p) => {
            s.push_str("pass word=");
            quoted(s, &p.word);
            s.push_str(match p.class {
                PassClass::Info => " info",
                PassClass::Machine => " machine",
            });
            if p.modal {
                s.push_str(" modal");
            }
            if p.moves {
                s.push_str(" moves");
            }
            s.push_str(" text=");
            quoted(s, &p.text);
        }
    }
    s.push('\n');
}

/// A cursor over one line of the text form.
struct Cur<'a> {
    s: &'a str,
    i: usize,
    ln: u32,
}

impl<'a> Cur<'a> {
    fn err(&self, m: impl Into<String>) -> ParseError {
        ParseError::new(self.ln, self.i as u32 + 1, m)
    }

    fn ws(&mut self) {
        while self.s[self.i..].starts_with(' ') {
            self.i += 1;
        }
    }

    fn done(&mut self) -> bool {
        self.ws();
        self.i >= self.s.len()
    }

    fn eat(&mut self, lit: &str) -> bool {
        self.ws();
        if self.s[self.i..].starts_with(lit) {
            self.i += lit.len();
            true
        } else {
            false
        }
    }

    fn expect(&mut self, lit: &str) -> Result<(), ParseError> {
        if self.eat(lit) {
            Ok(())
        } else {
            Err(self.err(format!("expected `{lit}`")))
        }
    }

    /// A run of characters up to a space, `,`, `)`, `/` or the end.
    fn token(&mut self) -> &'a str {
        self.ws();
        let rest = &self.s[self.i..];
        let n = rest.find([' ', ',', ')', '/']).unwrap_or(rest.len());
        self.i += n;
        &rest[..n]
    }

    fn num(&mut self) -> Result<f64, ParseError> {
        self.ws();
        let at = self.i;
        let t = self.token();
        if t == "?" {
            return Ok(f64::NAN);
        }
        t.parse::<f64>().map_err(|_| {
            self.i = at;
            self.err(format!("`{t}` is not a number"))
        })
    }

    fn opt_num(&mut self) -> Result<Option<f64>, ParseError> {
        if self.eat("-")
            && (self.i >= self.s.len() || self.s[self.i..].starts_with([' ', ',', ')']))
        {
            return Ok(None);
        }
        // A negative number: put the sign back.
        if self.i > 0 && self.s.as_bytes()[self.i - 1] == b'-' {
            self.i -= 1;
        }
        self.num().map(Some)
    }

    fn uint(&mut self) -> Result<u32, ParseError> {
        let t = self.token();
        t.parse::<u32>()
            .map_err(|_| self.err(format!("`{t}` is not a whole number")))
    }

    fn v3(&mut self) -> Result<DVec3, ParseError> {
        self.expect("(")?;
        let x = self.num()?;
        self.expect(",")?;
        let y = self.num()?;
        self.expect(",")?;
        let z = self.num()?;
        self.expect(")")?;
        Ok(DVec3::new(x, y, z))
    }

    fn key(&mut self, k: &str) -> Result<(), ParseError> {
        self.expect(k)?;
        self.expect("=")
    }

    fn string(&mut self) -> Result<String, ParseError> {
        self.ws();
        if !self.s[self.i..].starts_with('"') {
            return Err(self.err("expected a quoted string"));
        }
        let mut out = String::new();
        let mut chars = self.s[self.i + 1..].char_indices();
        while let Some((k, c)) = chars.next() {
            match c {
                '"' => {
                    self.i += k + 2;
                    return Ok(out);
                }
                '\\' => match chars.next() {
                    Some((_, 'n')) => out.push('\n'),
                    Some((_, 'r')) => out.push('\r'),
                    Some((_, c)) => out.push(c),
                    None => break,
                },
                c => out.push(c),
            }
        }
        Err(self.err("unterminated string"))
    }

    fn opt_string(&mut self) -> Result<Option<String>, ParseError> {
        if self.eat("-") {
            Ok(None)
        } else {
            self.string().map(Some)
        }
    }

    fn end(&mut self) -> Result<(), ParseError> {
        if self.done() {
            Ok(())
        } else {
            Err(self.err(format!("unexpected `{}`", &self.s[self.i..])))
        }
    }
}

fn pick<T: Copy>(c: &mut Cur, what: &str, options: &[(&str, T)]) -> Result<T, ParseError> {
    c.ws();
    let at = c.i;
    let t = c.token();
    options
        .iter()
        .find(|(n, _)| *n == t)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            c.i = at;
            c.err(format!("`{t}` is not a {what}"))
        })
}

/// Reads the text form back into a program.
pub fn parse(text: &str) -> Result<Program, ParseError> {
    let mut p: Option<Program> = None;
    for (k, line) in crate::lines::split(text).enumerate() {
        let ln = k as u32 + 1;
        if line.trim().is_empty() {
            continue;
        }
        let mut c = Cur { s: line, i: 0, ln };
        if c.eat("program ") {
            let name = c.opt_string()?;
            c.key("source")?;
            let at = c.i;
            let src = c.token();
            let source = Dialect::from_name(src).ok_or_else(|| {
                c.i = at;
                c.err(format!("`{src}` is not a dialect"))
            })?;
            c.key("units")?;
            let unit = pick(
                &mut c,
                "unit",
                &[("mm", LengthUnit::Mm), ("inch", LengthUnit::Inch)],
            )?;
            c.expect("/")?;
            let origin = pick(
                &mut c,
                "unit origin",
                &[
                    ("declared", UnitsOrigin::Declared),
                    ("inferred_from_feed", UnitsOrigin::InferredFromFeed),
                    ("assumed", UnitsOrigin::Assumed),
                    ("override", UnitsOrigin::Override),
                ],
            )?;
            c.end()?;
            let mut prog = Program::new(source);
            prog.name = name;
            prog.units = Units {
                source: unit,
                origin,
            };
            p = Some(prog);
            continue;
        }
        let Some(prog) = p.as_mut() else {
            return Err(c.err("expected `program` first"));
        };
        if c.eat("op ") {
            c.key("name")?;
            let name = c.opt_string()?;
            c.end()?;
            prog.operations.push(Operation {
                name,
                ..Operation::default()
            });
            continue;
        }
        let Some(op) = prog.operations.last_mut() else {
            return Err(c.err("expected `op` first"));
        };
        parse_op_line(&mut c, op)?;
    }
    p.ok_or_else(|| ParseError::new(1, 1, "no `program` line"))
}

fn parse_op_line(c: &mut Cur, op: &mut Operation) -> Result<(), ParseError> {
    if c.eat("tool ") {
        c.key("number")?;
        let number = if c.eat("-") { None } else { Some(c.uint()?) };
        c.key("name")?;
        let name = c.opt_string()?;
        c.key("line")?;
        let line = c.uint()?;
        let cutter = if c.eat("cutter=") {
            let kind = pick(
                c,
                "cutter kind",
                &[
                    ("flat", CutterKind::Flat),
                    ("ball", CutterKind::Ball),
                    ("bull", CutterKind::Bull),
                    ("drill", CutterKind::Drill),
                    ("general", CutterKind::General),
                ],
            )?;
            let mut v = [0.0; 7];
            for (slot, k) in v.iter_mut().zip(["d", "r", "e", "f", "a", "b", "h"]) {
                c.key(k)?;
                *slot = c.num()?;
            }
            Some(Cutter {
                kind,
                d: v[0],
                r: v[1],
                e: v[2],
                f: v[3],
                alpha: v[4],
                beta: v[5],
                h: v[6],
            })
        } else {
            None
        };
        c.end()?;
        op.tool = Some(Tool {
            number,
            name,
            cutter,
            line,
        });
    } else if c.eat("frame ") {
        c.key("origin")?;
        let origin = c.v3()?;
        c.key("x")?;
        let x = c.v3()?;
        c.key("y")?;
        let y = c.v3()?;
        c.key("z")?;
        let z = c.v3()?;
        c.end()?;
        op.frame = Some(Frame {
            origin,
            rot: DMat3::from_cols(x, y, z),
        });
    } else if c.eat("start ") {
        op.start = c.v3()?;
        c.end()?;
    } else if c.eat("arc ") {
        c.key("centre")?;
        let centre = c.v3()?;
        c.key("normal")?;
        let normal = c.v3()?;
        c.key("r")?;
        let radius = c.num()?;
        c.key("sweep")?;
        let sweep = c.num()?;
        c.end()?;
        op.arcs.push(Arc {
            centre,
            normal,
            radius,
            sweep,
        });
    } else if c.eat("cycle ") {
        c.key("name")?;
        let name = c.string()?;
        let mut v = [0.0; 4];
        for (slot, k) in v.iter_mut().zip(["bottom", "clear", "retract", "feed"]) {
            c.key(k)?;
            *slot = c.num()?;
        }
        c.key("peck")?;
        let peck = c.opt_num()?;
        let peck_next = if c.eat("peck_next=") {
            c.opt_num()?
        } else {
            None
        };
        c.key("dwell")?;
        let dwell = c.opt_num()?;
        c.key("line")?;
        let line = c.uint()?;
        c.end()?;
        op.cycles.push(Cycle {
            name,
            bottom: v[0],
            clearance: v[1],
            retract: v[2],
            feed: v[3],
            peck,
            peck_next,
            dwell,
            line,
        });
    } else if c.eat("orient ") {
        c.key("axis")?;
        let axis = if c.eat("-") { None } else { Some(c.v3()?) };
        c.key("abc")?;
        c.expect("(")?;
        let mut angles = [None; 3];
        for (k, a) in angles.iter_mut().enumerate() {
            if k > 0 {
                c.expect(",")?;
            }
            *a = c.opt_num()?;
        }
        c.expect(")")?;
        c.end()?;
        op.orients.push(Orient { axis, angles });
    } else if c.eat("L") {
        let line = c.uint()?;
        if c.eat("event ") {
            let kind = parse_event(c)?;
            c.end()?;
            op.events.push(Event {
                at: op.moves.len() as u32,
                line,
                kind,
            });
        } else {
            let m = parse_move(c, line)?;
            c.end()?;
            op.moves.push(m);
        }
    } else {
        return Err(c.err("expected tool, frame, start, arc, cycle, orient or a move"));
    }
    Ok(())
}

fn parse_move(c: &mut Cur, line: u32) -> Result<Move, ParseError> {
    c.ws();
    let at = c.i;
    let kind = c.token();
    let (name, id) = match kind.split_once('#') {
        Some((n, id)) => (n, id.parse::<usize>().ok()),
        None => (kind, None),
    };
    let kind = match (name, id) {
        ("rapid", None) => MoveKind::Rapid,
        ("linear", None) => MoveKind::Linear,
        ("arc", Some(i)) => MoveKind::Arc(ArcId::new(i)),
        ("cycle", Some(i)) => MoveKind::Cycle(CycleId::new(i)),
        _ => {
            c.i = at;
            return Err(c.err(format!("`{kind}` is not a move kind")));
        }
    };
    let end = c.v3()?;
    c.expect("F")?;
    let feed = c.num()?;
    c.expect("S")?;
    let spindle = c.num()?;
    let feed_mode = pick(
        c,
        "feed mode",
        &[
            ("per_minute", FeedMode::PerMinute),
            ("per_rev", FeedMode::PerRev),
            ("inverse_time", FeedMode::InverseTime),
        ],
    )?;
    let orient = if c.eat("orient#") {
        Some(OrientId::new(c.uint()? as usize))
    } else {
        None
    };
    Ok(Move {
        end,
        feed,
        spindle,
        line,
        kind,
        orient,
        feed_mode,
    })
}

fn parse_event(c: &mut Cur) -> Result<EventKind, ParseError> {
    c.ws();
    let at = c.i;
    let word = c.token();
    Ok(match word {
        "comment" => EventKind::Comment(c.string()?),
        "insert" => EventKind::Insert(c.string()?),
        "spindle" => EventKind::Spindle(pick(
            c,
            "spindle direction",
            &[
                ("cw", SpindleDir::Cw),
                ("ccw", SpindleDir::Ccw),
                ("off", SpindleDir::Off),
            ],
        )?),
        "coolant" => EventKind::Coolant(pick(
            c,
            "coolant",
            &[
                ("off", Coolant::Off),
                ("flood", Coolant::Flood),
                ("mist", Coolant::Mist),
                ("through", Coolant::Through),
                ("air", Coolant::Air),
            ],
        )?),
        "cutcom" => {
            let side = pick(
                c,
                "cutter compensation",
                &[
                    ("off", CutCom::Off),
                    ("left", CutCom::Left),
                    ("right", CutCom::Right),
                ],
            )?;
            let register = if c.eat("D") { Some(c.uint()?) } else { None };
            EventKind::CutCom { side, register }
        }
        "tool-length" => {
            if c.eat("off") {
                EventKind::ToolLength(ToolLength::Off)
            } else {
                c.expect("on")?;
                let register = if c.eat("H") { Some(c.uint()?) } else { None };
                EventKind::ToolLength(ToolLength::On { register })
            }
        }
        "tcp" => EventKind::Tcp(pick(c, "tcp state", &[("on", true), ("off", false)])?),
        "work-offset" => EventKind::WorkOffset(WorkOffset(c.uint()? as u16)),
        "tool-select" => EventKind::ToolSelect(c.uint()?),
        "stop" => EventKind::Stop {
            optional: pick(c, "stop kind", &[("optional", true), ("program", false)])?,
        },
        "dwell" => EventKind::Dwell(c.num()?),
        "path" => EventKind::PathControl(parse_path(c)?),
        "pass" => {
            c.key("word")?;
            let word = c.string()?;
            let class = pick(
                c,
                "class",
                &[("info", PassClass::Info), ("machine", PassClass::Machine)],
            )?;
            let modal = c.eat("modal");
            let moves = c.eat("moves");
            c.key("text")?;
            let text = c.string()?;
            EventKind::Passthrough(Passthrough {
                word,
                text,
                class,
                modal,
                moves,
            })
        }
        _ => {
            c.i = at;
            return Err(c.err(format!("`{word}` is not an event")));
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_of_line_round_trips() {
        let text = r#"program "T \"1\"" source=sinumerik units=inch/declared
op name="OP\\1"
  tool number=8 name="EM10" line=3 cutter=bull d=10 r=1 e=4 f=1 a=0 b=0 h=40
  frame origin=(1, 2, 3) x=(0, 1, 0) y=(1, 0, 0) z=(0, 0, -1)
  start (?, 5.5, ?)
  arc centre=(0, 0, 0) normal=(0, 0, 1) r=10 sweep=1.5707963267948966
  cycle name="G83" bottom=-12 clear=0 retract=2.5 feed=100 peck=1.5 peck_next=0.75 dwell=- line=11
  orient axis=- abc=(-, -0.5, 0)
  orient axis=(0, 0.6, 0.8) abc=(-, -, -)
  L3 event comment "a (comment)"
  L3 event insert "raw"
  L4 event spindle ccw
  L4 event coolant mist
  L5 event cutcom left D12
  L5 event tool-length on H8
  L5 event tcp on
  L5 event work-offset 7
  L5 event tool-select 9
  L5 event stop optional
  L5 event dwell 1.25
  L5 event pass word="G5.1" machine modal moves text="G05.1 Q1"
  L6 rapid (?, ?, 20) F0 S0 per_minute
  L7 linear (10, 0, 0) F250.5 S1234.5 inverse_time orient#1
  L8 arc#0 (0, 10, 0) F250 S0 per_rev
  L9 cycle#0 (3, 4, 2) F0 S0 per_minute orient#0
  L10 event tool-length off
  L10 event cutcom off
"#;
        let p = parse(text).expect("parses");
        assert_eq!(print(&p), text);
        let op = &p.operations[0];
        assert!(op.start.x.is_nan() && op.start.y == 5.5);
        assert_eq!(op.moves[3].kind, MoveKind::Cycle(CycleId::new(0)));
        assert_eq!(op.events.len(), 14);
        assert_eq!(op.events[13].at, 4);
        assert_eq!(parse(&print(&p)).expect("again"), p);
    }

    #[test]
    fn numbers_round_trip_exactly() {
        let mut p = Program::new(Dialect::Generated);
        let mut op = Operation::default();
        for v in [0.1 + 0.2, -1e-300, 1.0 / 3.0, 123_456_789.123_456_79, -0.0] {
            op.moves
                .push(Move::linear(DVec3::new(v, v * 7.0, -v), v.abs() + 1.0));
        }
        p.operations.push(op);
        let q = parse(&print(&p)).expect("parses");
        assert_eq!(q, p);
    }

    #[test]
    fn bad_text_is_located() {
        let e = parse("program - source=fanuc units=mm/declared\nop name=-\n  L3 linear (1, x, 3) F1 S0 per_minute\n")
            .expect_err("bad number");
        assert_eq!((e.line, e.col), (3, 17));
        let e = parse("program - source=vms units=mm/declared\n").expect_err("dialect");
        assert_eq!(e.line, 1);
        let e = parse("op name=-\n").expect_err("no program");
        assert_eq!(e.line, 1);
    }
}
