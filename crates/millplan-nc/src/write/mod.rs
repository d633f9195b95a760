//! Back ends: G-code dialects and APT/CL. Writers produce bytes; the binary puts
//! them in files (through a temporary file and a rename).

pub mod apt;
pub mod gcode;
pub mod krl;
pub mod preflight;

use crate::diag::{Code, Diagnostic, Severity};
use crate::ir::*;
use millplan_geom::DVec3;

/// Where a program goes: the dialect a writer writes. (Where it came from is
/// [`Program::source`].)
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Target {
    Fanuc,
    Sinumerik,
    Heidenhain,
    LinuxCnc,
    Apt,
    /// KUKA KRL, a robot's `.SRC` program (not in [`Target::ALL`], the NC
    /// dialects: a robot program has no spindle, coolant or tool change).
    Krl,
}

impl Target {
    /// The NC dialects.
    pub const ALL: [Target; 5] = [
        Target::Fanuc,
        Target::Sinumerik,
        Target::Heidenhain,
        Target::LinuxCnc,
        Target::Apt,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Target::Fanuc => "fanuc",
            Target::Sinumerik => "sinumerik",
            Target::Heidenhain => "heidenhain",
            Target::LinuxCnc => "linuxcnc",
            Target::Apt => "apt",
            Target::Krl => "krl",
        }
    }

    pub fn from_name(s: &str) -> Option<Target> {
        Target::ALL
            .into_iter()
            .chain([Target::Krl])
            .find(|t| t.name() == s)
    }

    /// The usual file extension of the target's programs.
    pub fn extension(self) -> &'static str {
        match self {
            Target::Fanuc => "nc",
            Target::Sinumerik => "mpf",
            Target::Heidenhain => "h",
            Target::LinuxCnc => "ngc",
            Target::Apt => "apt",
            Target::Krl => "src",
        }
    }

    /// The target a file extension names, when it names exactly one.
    pub fn from_extension(ext: &str) -> Option<Target> {
        match ext.to_ascii_lowercase().as_str() {
            "nc" | "tap" | "ptp" | "eia" | "iso" | "fnc" => Some(Target::Fanuc),
            "mpf" | "spf" => Some(Target::Sinumerik),
            "h" => Some(Target::Heidenhain),
            "ngc" => Some(Target::LinuxCnc),
            "apt" | "cl" | "cls" | "clsf" | "aptsource" => Some(Target::Apt),
            "src" => Some(Target::Krl),
            _ => None,
        }
    }

    /// The target written in a source's own dialect, if millplan writes it.
    pub fn of(d: Dialect) -> Option<Target> {
        match d {
            Dialect::Fanuc => Some(Target::Fanuc),
            Dialect::Sinumerik => Some(Target::Sinumerik),
            Dialect::Heidenhain => Some(Target::Heidenhain),
            Dialect::LinuxCnc => Some(Target::LinuxCnc),
            d if d.is_apt() => Some(Target::Apt),
            Dialect::Krl => Some(Target::Krl),
            _ => None,
        }
    }

    /// Whether words the source kept verbatim mean the same in this target.
    pub fn reads(self, d: Dialect) -> bool {
        Target::of(d) == Some(self)
    }

    pub fn is_gcode(self) -> bool {
        !matches!(self, Target::Apt | Target::Krl)
    }
}

/// Whether a verbatim source block means the same in `target`: always in the
/// source's own dialect; between Fanuc and LinuxCNC (both RS274) also for
/// reference returns and machine-coordinate moves (G28, G30, G53 with G0/G1,
/// G90/G91 and axis words).
pub fn copies_verbatim(source: Dialect, target: Target, p: &Passthrough) -> bool {
    if target.reads(source) {
        return true;
    }
    rs274_common(source, target, p)
}

/// Whether verbatim text means the same in another unit: every number in it
/// is zero or belongs to a code, a register or a count (G, M, H, D, T, N, L, P
/// words), never a length.
pub fn unit_free(text: &str) -> bool {
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_ascii_digit() || c == b'.' {
            let s = i;
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
                i += 1;
            }
            let v: f64 = text[s..i].parse().unwrap_or(1.0);
            // The letter (after any sign) the number belongs to.
            let mut k = s;
            while k > 0 && matches!(b[k - 1], b'-' | b'+' | b'=') {
                k -= 1;
            }
            let letter = (k > 0).then(|| b[k - 1].to_ascii_uppercase());
            let code = matches!(
                letter,
                Some(b'G' | b'M' | b'H' | b'D' | b'T' | b'N' | b'L' | b'P')
            ) && !(k > 1 && b[k - 2].is_ascii_alphanumeric());
            if v != 0.0 && !code {
                return false;
            }
        } else {
            i += 1;
        }
    }
    true
}

fn rs274_common(source: Dialect, target: Target, p: &Passthrough) -> bool {
    let rs274 = |t: Target| matches!(t, Target::Fanuc | Target::LinuxCnc);
    let Some(src) = Target::of(source) else {
        return false;
    };
    if !(rs274(src) && rs274(target)) {
        return false;
    }
    let mut machine = false;
    let ok = p.text.split_whitespace().all(|w| {
        let (letter, num) = w.split_at(1);
        let Ok(v) = num.parse::<f64>() else {
            return false;
        };
        match letter {
            "G" => {
                machine |= matches!(v as i64, 28 | 30 | 53) && v.fract() == 0.0;
                [0.0, 1.0, 90.0, 91.0, 28.0, 30.0, 53.0].contains(&v)
            }
            "X" | "Y" | "Z" | "A" | "B" | "C" => true,
            _ => false,
        }
    });
    ok && machine
}

/// Writer settings, shared by every back end.
#[derive(Clone, Copy, Debug)]
pub struct WriteOptions {
    pub target: Target,
    /// Output unit (values in the IR are mm); `None`: the unit the source was
    /// written in, so that words copied verbatim keep their meaning.
    pub unit: Option<LengthUnit>,
    /// Block numbers (always on for Heidenhain).
    pub line_numbers: bool,
    /// Chord tolerance (mm) for arcs that must be written as lines.
    pub chord_tol: f64,
    /// Write what the target cannot express as comments, with a warning each,
    /// instead of refusing.
    pub lossy: bool,
    /// Decimals of spindle speeds; `None`: the target's usual (whole numbers
    /// for Fanuc, whose controls refuse `S4200.6`, one decimal elsewhere).
    pub spindle_decimals: Option<u32>,
    /// Resource limits: lines an arc may become (`expansion`) and moves of
    /// the program written (`moves`).
    pub limits: millplan_geom::Limits,
    /// Switch tool-centre-point control on at a five-axis tool change of CL
    /// data that say nothing about it (G43.4, TRAORI, M128). A program
    /// posted in machine coordinates must run without it.
    pub auto_tcp: bool,
    /// The control reads a G93 F word as the block time in seconds
    /// (Beckhoff/ISG) rather than as 1/minutes (RS274/NGC).
    pub g93_seconds: bool,
    /// The control takes G0 while G93 is active; when not, the writer states
    /// G94 before a rapid in inverse-time mode.
    pub g93_rapids: bool,
}

impl WriteOptions {
    pub fn new(target: Target) -> WriteOptions {
        WriteOptions {
            target,
            unit: None,
            line_numbers: false,
            chord_tol: 0.001,
            lossy: false,
            spindle_decimals: None,
            limits: millplan_geom::Limits::default(),
            auto_tcp: true,
            g93_seconds: false,
            g93_rapids: true,
        }
    }

    /// The output unit (after [`WriteOptions::resolved`]).
    pub fn unit(&self) -> LengthUnit {
        self.unit.unwrap_or(LengthUnit::Mm)
    }

    /// These options with the output unit settled for `p`.
    pub fn resolved(self, p: &Program) -> WriteOptions {
        WriteOptions {
            unit: Some(self.unit.unwrap_or(p.units.source)),
            ..self
        }
    }

    pub fn spindle_decimals(&self) -> u32 {
        self.spindle_decimals
            .unwrap_or(if self.target == Target::Fanuc { 0 } else { 1 })
            .min(6)
    }
}

/// Writes a program for `o.target`, handing the text to `sink` as it grows
/// (see [`Sink`]); what is left stays in `out`.
pub fn write_program_to(
    p: &Program,
    o: WriteOptions,
    out: &mut Vec<u8>,
    sink: Option<Sink>,
) -> Result<Written, WriteError> {
    preflight::check(p, &o)?;
    match o.target {
        Target::Apt => apt::write_apt_to(p, o, out, sink),
        Target::Krl => krl::write_ir_to(p, &o, out, sink),
        _ => gcode::write_gcode_to(p, o, out, sink),
    }
}

/// Writes a program for `o.target` into memory.
///
/// ```
/// use millplan_nc::write::{write_program, Target, WriteOptions};
/// use millplan_nc::{parse_program, ReadOptions};
///
/// let src = "G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F300\nG1 X10\nM30\n";
/// let p = parse_program(src, ReadOptions::default()).expect("reads").program;
/// let (text, _warnings) = write_program(&p, WriteOptions::new(Target::Heidenhain)).expect("writes");
/// let text = String::from_utf8(text).expect("text");
/// assert!(text.contains("TOOL CALL 1"), "{text}");
/// // Read back, it commands what its source did.
/// let back = parse_program(&text, ReadOptions::default()).expect("reads back").program;
/// assert_eq!(back.move_count(), p.move_count());
/// ```
pub fn write_program(p: &Program, o: WriteOptions) -> Result<(Vec<u8>, Written), WriteError> {
    // Room for a typical block per move up front: growing an 80 MB text by
    // doubling copies it and faults in fresh pages each time.
    let mut out = Vec::with_capacity(p.move_count() * 48 + 4096);
    let w = write_program_to(p, o, &mut out, None)?;
    Ok((out, w))
}

/// Something the target cannot express, which stops writing; located by the
/// source line of the move or event that needs it (0: the program as a whole).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}{message}", if *line > 0 { format!("{line}:1: ") } else { String::new() })]
pub struct WriteError {
    pub line: u32,
    pub message: String,
}

impl WriteError {
    pub fn new(line: u32, message: impl Into<String>) -> WriteError {
        WriteError {
            line,
            message: message.into(),
        }
    }
}

/// What a writer reports beside the text: the words written as comments under
/// `lossy` (each a [`Code::LossyWord`] warning at its source line).
pub type Written = Vec<Diagnostic>;

/// A word the target cannot express: an error, or with `lossy` a comment and a
/// warning.
pub(crate) fn lossy(
    lossy: bool,
    warnings: &mut Written,
    line: u32,
    what: String,
) -> Result<(), WriteError> {
    if !lossy {
        return Err(WriteError::new(
            line,
            format!("{what} (give --lossy to write it as a comment instead)"),
        ));
    }
    warnings.push(Diagnostic {
        severity: Severity::Warning,
        code: Code::LossyWord,
        line,
        col: 1,
        message: format!("{what}: written as a comment"),
    });
    Ok(())
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
    pub warnings: Written,
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
    warnings: &mut Written,
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
            warnings.extend(r.warnings);
            r.result?;
            *st = r.end;
        }
        a = b;
    }
    Ok(())
}

/// The next event before move `i`: events are taken, in their order, before
/// the first move at or after their position.
/// How many of `op`'s first events came before its tool change in the source
/// (a retract to the reference point, a comment, a blank form): a writer puts
/// them before the tool change it writes.
pub(crate) fn events_before_tool(op: &Operation) -> usize {
    let Some(t) = &op.tool else { return 0 };
    op.events
        .iter()
        .take_while(|e| e.at == 0 && e.line != 0 && e.line < t.line)
        .count()
}

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

/// One step of a canned cycle spelled out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CycleStep {
    Rapid(DVec3),
    Feed(DVec3, f64),
    /// Dwell at the bottom, seconds.
    Dwell(f64),
}

/// What a canned cycle does in and out of its hole, from the name its source
/// gave it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CycleKind {
    /// Feed in (with pecks), rapid out: G73, G81, G82, G83, APT `DRILL`/`DEEP`,
    /// Heidenhain cycles 1, 200, 203, 205.
    Drill,
    /// Feed in and feed out: G85, G89, APT `BORE`/`REAM`, Heidenhain 201.
    FeedOut,
    /// Tapping: the spindle reverses at the bottom (G84, G74, APT `TAP`,
    /// Heidenhain 206, 207, 209).
    Tap,
    /// Boring with a spindle stop or orientation, or milled holes (G76,
    /// G86–G88, Heidenhain 202, 204, 208).
    Special,
}

pub fn cycle_kind(name: &str) -> CycleKind {
    let n = name.to_ascii_uppercase();
    let heidenhain = n
        .strip_prefix("CYCL ")
        .and_then(|r| r.split_whitespace().next())
        .and_then(|w| w.parse::<u32>().ok());
    match (n.as_str(), heidenhain) {
        (_, Some(201)) => CycleKind::FeedOut,
        (_, Some(206 | 207 | 209)) => CycleKind::Tap,
        (_, Some(202 | 204 | 208)) => CycleKind::Special,
        (_, Some(_)) => CycleKind::Drill,
        ("G85" | "G89", _) => CycleKind::FeedOut,
        ("G84" | "G74", _) => CycleKind::Tap,
        ("G76" | "G86" | "G87" | "G88", _) => CycleKind::Special,
        (n, _) if n.contains("TAP") => CycleKind::Tap,
        (n, _) if n.contains("BORE") || n.contains("REAM") => CycleKind::FeedOut,
        _ => CycleKind::Drill,
    }
}

/// The name an APT `CYCLE/` record gives `c`: the APT name of a G-code
/// drilling, tapping or boring cycle (G81 and G82 `DRILL`, G83 `DEEP`, G73
/// `BRKCHP`, G84 `TAP`, G85 and G89 `BORE`; the dwell and the peck are
/// words of the record), else the source's own.
pub fn apt_cycle_name(c: &Cycle) -> &str {
    match c.name.as_str() {
        "G81" | "G82" => "DRILL",
        "G83" => "DEEP",
        "G73" => "BRKCHP",
        "G84" => "TAP",
        "G85" | "G89" => "BORE",
        n => n,
    }
}

/// Refuses to spell out a G73 or G83 without a peck depth above 0: read
/// as one stroke (with a `peck-depth` warning), its control stops with an
/// alarm (LinuxCNC: "negative or zero q value") or pecks as the program
/// does not say, and written as lines it would drill the whole depth at
/// once. The control's own cycle, written as its source gave it, stays.
pub fn check_pecking(c: &Cycle) -> Result<(), WriteError> {
    let name = c.name.to_ascii_uppercase();
    if matches!(name.as_str(), "G73" | "G83") && !c.peck.is_some_and(|q| q > 0.0) {
        return Err(WriteError::new(
            c.line,
            format!(
                "{}: a pecking cycle without a peck depth above 0 (Q) cannot be written as lines (it would drill in one stroke); give its Q",
                c.name
            ),
        ));
    }
    Ok(())
}

/// Refuses a cycle of more than [`MAX_PECKS`] pecks a hole, at its
/// definition's line, whether a writer spells it out or leaves it to the
/// control's own cycle: `G83 … Q0.00001` is millions of strokes either way
/// (and its peck is below the decimals any target writes).
pub fn check_pecks(c: &Cycle) -> Result<(), WriteError> {
    let pecks = c.pecks();
    if pecks <= MAX_PECKS {
        return Ok(());
    }
    Err(WriteError::new(
        c.line,
        format!(
            "{}: a peck of {:.6} mm over a depth of {:.3} mm makes {} pecks a hole; at most {MAX_PECKS} are accepted",
            c.name,
            c.peck.unwrap_or(0.0),
            c.clearance - c.bottom,
            if pecks == usize::MAX { "too many".to_string() } else { pecks.to_string() }
        ),
    ))
}

/// How far a chip-breaking cycle (G73) backs off after each peck, mm:
/// LinuxCNC's 0.010 in (its `rs274` shows it); on a Fanuc it is a machine
/// parameter (5114) the program does not say.
pub const CHIP_BREAK: f64 = 0.254;

/// Explicit steps (rapid to the feed plane, feed down with pecks, dwell, rapid
/// or, for boring and reaming, feed out) for one hole of a cycle, along the tool axis `axis` from the cycle
/// point `p`. A cycle needing more than [`MAX_PECKS`] pecks is an error at
/// its definition's line.
pub fn cycle_moves(c: &Cycle, p: DVec3, axis: DVec3) -> Result<Vec<CycleStep>, WriteError> {
    let kind = cycle_kind(&c.name);
    if matches!(kind, CycleKind::Tap | CycleKind::Special) {
        return Err(WriteError::new(
            c.line,
            format!(
                "{}: a {} cycle cannot be spelled out as moves (its spindle reverses or stops in the hole); write it into its source's own dialect",
                c.name,
                if kind == CycleKind::Tap { "tapping" } else { "boring" }
            ),
        ));
    }
    check_pecks(c)?;
    let pecks = c.pecks();
    let at = |h: f64| p + axis * h;
    let mut v = Vec::with_capacity(3 * pecks + 3);
    v.push(CycleStep::Rapid(at(c.clearance.max(c.bottom))));
    // A chip-breaking cycle (G73, APT `BRKCHP`) backs off a little after
    // each peck and feeds on; a deep-hole one (G83, `DEEP`) goes back out
    // to R and rapids down to just above where it stopped.
    let n = c.name.to_ascii_uppercase();
    let chip_break = n == "G73" || n.starts_with("BRKCHP");
    if let (true, Some(first)) = (pecks > 1, c.peck) {
        let next = c.peck_next.filter(|q| *q > 0.0).unwrap_or(first);
        let mut depth = c.clearance;
        let mut q = first;
        while depth - q > c.bottom + 1e-9 {
            depth -= q;
            v.push(CycleStep::Feed(at(depth), c.feed));
            if chip_break {
                v.push(CycleStep::Rapid(at(depth + CHIP_BREAK.min(next / 2.0))));
            } else {
                v.push(CycleStep::Rapid(at(c.clearance)));
                v.push(CycleStep::Rapid(at(depth + 0.5_f64.min(next / 2.0))));
            }
            q = next;
        }
    }
    v.push(CycleStep::Feed(at(c.bottom), c.feed));
    if let Some(t) = c.dwell.filter(|t| *t > 0.0) {
        v.push(CycleStep::Dwell(t));
    }
    if kind == CycleKind::FeedOut {
        v.push(CycleStep::Feed(at(c.clearance.max(c.bottom)), c.feed));
    }
    v.push(CycleStep::Rapid(at(c.retract.max(c.clearance))));
    Ok(v)
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
        type Write = fn(&Program, &mut Vec<u8>, Option<Sink>) -> Result<Written, WriteError>;
        let writers: [Write; 2] = [
            |p, out, sink| apt::write_apt_to(p, WriteOptions::new(Target::Apt), out, sink),
            |p, out, sink| gcode::write_gcode_to(p, WriteOptions::new(Target::Fanuc), out, sink),
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
            let mut fail = |_: &[u8]| Err(WriteError::new(0, "disk full"));
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
                    peck_next: None,
                    dwell: None,
                    line: 0,
                }],
                ..Operation::default()
            };
            if k == 1 {
                op.orients = vec![
                    Orient::vector(DVec3::Z),
                    Orient::vector(DVec3::new(0.3, 0.0, 1.0).normalize()),
                ];
                // Tool vectors with tool-centre-point control.
                op.push_event(0, EventKind::Tcp(true));
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
                        let mut m = Move::linear(e, feed);
                        m.kind = MoveKind::Arc(op.push_arc(arc));
                        m
                    }
                    3 => {
                        let mut m = Move::linear(end, feed);
                        m.kind = MoveKind::Cycle(CycleId::new(0));
                        m
                    }
                    4 => {
                        // Inverse time and per revolution too.
                        let mut m = Move::linear(end, 40.0 + rnd(3) as f64);
                        m.feed_mode = FeedMode::InverseTime;
                        m
                    }
                    5 => {
                        let mut m = Move::linear(end, 0.1);
                        m.feed_mode = FeedMode::PerRev;
                        m
                    }
                    _ => Move::linear(end, feed),
                };
                m.spindle = speed;
                if k == 1 {
                    // Arcs keep the orientation of the move before them (an
                    // arc that turns the tool is refused by Fanuc).
                    let o = rnd(50) == 0;
                    m.orient = match (m.arc(), op.moves.last()) {
                        (Some(_), Some(prev)) => prev.orient,
                        _ => Some(OrientId::new(o as usize)),
                    };
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
                    let kind = match rnd(10) {
                        0 => EventKind::Comment(format!("note {i}")),
                        1 => EventKind::Spindle(SpindleDir::Off),
                        2 => EventKind::Spindle(SpindleDir::Cw),
                        3 => EventKind::Coolant(Coolant::Flood),
                        4 => EventKind::CutCom {
                            side: [CutCom::Left, CutCom::Off][rnd(2) as usize],
                            register: Some(7),
                        },
                        5 => EventKind::ToolLength(ToolLength::On {
                            register: Some(3 + k as u32),
                        }),
                        6 => EventKind::WorkOffset(WorkOffset(1 + rnd(6) as u16)),
                        7 => EventKind::ToolSelect(9),
                        8 => EventKind::Dwell(0.5),
                        _ => EventKind::Stop { optional: true },
                    };
                    // Events of one source block with the move after them.
                    let line = if rnd(2) == 0 { 0 } else { i as u32 + 2 };
                    op.events.push(Event {
                        at: i as u32 + 1,
                        line,
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
        let mut o = WriteOptions::new(Target::Apt);
        o.lossy = true;
        let w1 = apt::write_all(&p, o, &mut one, None, false).expect("writes");
        let mut par = Vec::new();
        let w2 = apt::write_all(&p, o, &mut par, None, true).expect("writes");
        assert!(one.len() > 1 << 20);
        assert!(par == one, "APT text differs");
        assert_eq!(w1, w2);
        // LinuxCNC stops at the first tool vector: the same error after the
        // same text; with `lossy`, the same warnings.
        for (t, lossy) in [
            (Target::Fanuc, false),
            (Target::LinuxCnc, false),
            (Target::LinuxCnc, true),
            (Target::Sinumerik, false),
        ] {
            let mut o = WriteOptions::new(t);
            o.chord_tol = 0.01;
            o.lossy = lossy;
            let mut one = Vec::new();
            let r1 = gcode::write_all(&p, o, &mut one, None, false);
            let mut par = Vec::new();
            let r2 = gcode::write_all(&p, o, &mut par, None, true);
            assert_eq!(r1, r2);
            assert_eq!(r1.is_err(), t == Target::LinuxCnc && !lossy);
            if lossy {
                assert!(!r1.expect("lossy writes").is_empty());
            }
            assert!(one.len() > 1 << 20);
            assert!(par == one, "{t:?} text differs");
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
