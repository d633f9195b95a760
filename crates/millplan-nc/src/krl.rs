//! KUKA KRL robot programs (`.SRC`): the reader (process-models §5).
//!
//! A program is read into a [`KrlProgram`]: its motions (`PTP`, `LIN`,
//! `CIRC` with `E6POS` aggregates `{X, Y, Z, A, B, C, E1..E6, S, T}`, the
//! approximation `C_DIS`/`C_VEL`/`C_ORI`/`C_PTP`, each tag checked against
//! the motion it follows, see [`Approx`]), the path speed `$VEL.CP` (m/s)
//! and approximation distance `$APO.CDIS` (mm) in force at each, `$TOOL` and
//! `$BASE`, and every other statement kept verbatim (user calls such as
//! `MMPM(30000.0)`, `BAS(...)`, FOLD lines). A main program that calls
//! sub-programs declared with `EXT` reads each one beside it through the
//! caller's resolver; a missing one is named with its calling line and the
//! rest is read. [`KrlProgram::to_ir`] turns it into the toolpath IR for the
//! other dialects: the orientation A, B, C (R = Rz(A)·Ry(B)·Rx(C), the
//! tool along the tool frame's x) becomes a tool axis, external axes are
//! refused at their line unless lossy. `write::krl` writes it back.
//!
//! Spline motions (KSS 8.x) read too: a `SPLINE [WITH …]` … `ENDSPLINE
//! [C_SPL]` block of `SPL`, `SLIN` and `SCIRC` segments, and `SLIN`/`SCIRC`
//! alone, with the same aggregates as `LIN`. A segment's path speed is its
//! own `WITH $VEL.CP = v` (or `$VEL = {CP v, …}`, `$VEL = SVEL_CP(v, …)`),
//! else its block's, else the `$VEL.CP` in force; every other option of a
//! `WITH` clause is kept as written (and written back) and named in a
//! warning, the IR not modelling it. Into the IR an `SPL` or `SLIN` segment
//! is a straight move to its point, an `SCIRC` an arc.

use crate::diag::{Code, Diagnostic, ParseError, Parsed, Severity};
use crate::ir::{Dialect, EventKind, FeedMode, Move, MoveKind, Operation, Orient, Program};
use crate::ir::{PassClass, Passthrough};
use millplan_geom::{DMat3, DVec3};

/// A Cartesian KRL target: position (mm), orientation A, B, C (degrees),
/// external axes E1..E6, Status and Turn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KrlPos {
    pub xyz: DVec3,
    pub abc: [f64; 3],
    pub e: [Option<f64>; 6],
    pub s: Option<u32>,
    pub t: Option<u32>,
}

/// The approximation tag of a motion. Which tags a motion takes (KSS 8.x)
/// is checked as it is read: `LIN`, `CIRC` one of `C_DIS`, `C_VEL`,
/// `C_ORI`; `PTP` `C_PTP`, `C_PTP` and one of those three (for a `LIN` or
/// `CIRC` after it), or `C_DIS`; `SPTP` `C_SPL` or `C_PTP`; `SLIN`,
/// `SCIRC` alone `C_SPL`; a segment of a SPLINE block none (its
/// `ENDSPLINE C_SPL` approximates the block).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Approx {
    Exact,
    Dis,
    Vel,
    Ori,
    /// `C_SPL`: a spline motion approximated by `$APO.CDIS`.
    Spl,
    /// `C_PTP`: a point-to-point motion approximated by `$APO.CPTP`.
    Ptp,
    /// `C_PTP C_DIS`, `C_PTP C_ORI`, `C_PTP C_VEL`: a `PTP` approximated
    /// into the `LIN` or `CIRC` after it by that criterion.
    PtpDis,
    PtpOri,
    PtpVel,
}

/// A motion's target.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    Lin(KrlPos),
    /// Through `aux` to `end`.
    Circ {
        aux: KrlPos,
        end: KrlPos,
    },
    /// Point to point to a Cartesian target.
    Ptp(KrlPos),
    /// Point to point to joint angles or a named position (`XHOME`,
    /// `$POS_ACT`): where it ends is not known to the reader.
    PtpOther(String),
    /// A spline segment `SPL` (only inside a SPLINE block).
    Spl(KrlPos),
    /// A straight spline segment `SLIN` (in a block or alone).
    Slin(KrlPos),
    /// A circular spline segment `SCIRC` through `aux` to `end`.
    Scirc {
        aux: KrlPos,
        end: KrlPos,
    },
    /// A spline point-to-point motion `SPTP` (in a block or alone) to a
    /// Cartesian target: a positioning move, as `PTP`.
    Sptp(KrlPos),
    /// `SPTP` to joint angles or a named position: where it ends is not
    /// known to the reader, as [`Motion::PtpOther`].
    SptpOther(String),
}

impl Motion {
    /// Where the motion ends, when the reader knows it.
    pub fn end(&self) -> Option<&KrlPos> {
        match self {
            Motion::Lin(p)
            | Motion::Ptp(p)
            | Motion::Spl(p)
            | Motion::Slin(p)
            | Motion::Sptp(p) => Some(p),
            Motion::Circ { end, .. } | Motion::Scirc { end, .. } => Some(end),
            Motion::PtpOther(_) | Motion::SptpOther(_) => None,
        }
    }

    /// Whether it is a spline motion (`SPL`, `SLIN`, `SCIRC`, `SPTP`).
    pub fn is_spline(&self) -> bool {
        matches!(
            self,
            Motion::Spl(_)
                | Motion::Slin(_)
                | Motion::Scirc { .. }
                | Motion::Sptp(_)
                | Motion::SptpOther(_)
        )
    }
}

/// One statement of a program.
// A move holds its targets inline: programs are mostly moves, so boxing
// them would only add an allocation per line.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum Statement {
    Move {
        motion: Motion,
        approx: Approx,
        /// `$VEL.CP` in force, m/s (`None`: never set in the program); a
        /// spline motion's own or its block's `WITH` speed where it has one.
        vel_cp: Option<f64>,
        /// The options of a spline motion's `WITH` clause other than
        /// `$VEL.CP = v`, as written (`$ACC = {…}`, `$VEL = SVEL_CP(…)`).
        with: Vec<String>,
    },
    /// `SPLINE [WITH …]`: a spline block begins; the options of its `WITH`
    /// clause other than `$VEL.CP = v` (which its segments hold), as written.
    SplineBegin(Vec<String>),
    /// `ENDSPLINE [C_SPL]`: the block ends, approximated or not.
    SplineEnd(bool),
    VelCp(f64),
    /// `$VEL = {…}`: the aggregate as written (the right-hand side) and
    /// its CP component, m/s, which sets the path speed as `$VEL.CP` does;
    /// without one (only ORI1, ORI2) the path speed stays the one in force,
    /// for KRL assigns only the components an aggregate names.
    Vel {
        cp: Option<f64>,
        text: String,
    },
    ApoCdis(f64),
    /// `$TOOL = …` / `$BASE = …`: the right-hand side as written.
    Tool(String),
    Base(String),
    /// Anything else, as written (comments included).
    Verbatim(String),
}

/// A statement and where it was read: the file (0 = the main program, else
/// `files[file]`) and its 1-based line.
#[derive(Clone, Debug, PartialEq)]
pub struct Located {
    pub file: usize,
    pub line: u32,
    pub statement: Statement,
}

/// A KRL program with the sub-programs its main calls, in call order.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct KrlProgram {
    /// The main program's name (its `DEF`).
    pub name: String,
    /// The names of the files read: the main first, then each sub-program.
    pub files: Vec<String>,
    pub statements: Vec<Located>,
    /// Sub-programs called but not found: (name, file index, calling line).
    pub missing: Vec<(String, usize, u32)>,
    /// What was read but is not modelled (a `WITH` option, an `SPTP`):
    /// (file index, line, what), kept as written.
    pub warnings: Vec<(usize, u32, String)>,
}

/// An error in one of the files of a program.
#[derive(Clone, Debug, PartialEq)]
pub struct KrlError {
    /// The sub-program's name, `None` for the main program.
    pub file: Option<String>,
    pub error: ParseError,
}

/// Sub-programs are read at most this deep (a main calling sub-programs
/// that call their own).
const MAX_DEPTH: usize = 8;

/// Whether `src` is a KRL program (its header or `DEF`).
pub fn is_krl(src: &str) -> bool {
    crate::detect::krl_line(src).is_some()
}

/// Reads a main program; `resolve(name)` gives the text of a sub-program
/// declared with `EXT name(…)` and called, or `None` when it is not there.
pub fn read(
    src: &str,
    resolve: &mut dyn FnMut(&str) -> Option<String>,
) -> Result<KrlProgram, KrlError> {
    let mut p = KrlProgram::default();
    let mut vel = None;
    read_file(src, 0, 0, resolve, &mut p, &mut vel)?;
    p.name = p.files.first().cloned().unwrap_or_default();
    Ok(p)
}

/// What a file's reading knows beyond its statements: which file it is,
/// how deep in calls, the sub-programs it declares with `EXT` and the
/// SPLINE block open (its line, its `WITH` speed).
struct FileState {
    file: usize,
    depth: usize,
    ext: Vec<String>,
    block: Option<(u32, Option<f64>)>,
}

/// An error in file `file` of `p`.
fn fail(p: &KrlProgram, file: usize, e: ParseError) -> KrlError {
    KrlError {
        file: if file == 0 {
            None
        } else {
            p.files.get(file).cloned()
        },
        error: e,
    }
}

fn read_file(
    src: &str,
    file: usize,
    depth: usize,
    resolve: &mut dyn FnMut(&str) -> Option<String>,
    p: &mut KrlProgram,
    vel: &mut Option<f64>,
) -> Result<(), KrlError> {
    if p.files.len() <= file {
        p.files.push(String::new());
    }
    let mut fs = FileState {
        file,
        depth,
        ext: Vec::new(),
        block: None,
    };
    for (k, raw) in crate::lines::split(src).enumerate() {
        let line = u32::try_from(k + 1).unwrap_or(u32::MAX);
        let st = parse_line(raw, line, fs.block.is_some()).map_err(|e| fail(p, file, e))?;
        let Some(st) = st else { continue };
        in_block(fs.block, &st, raw, line).map_err(|e| fail(p, file, e))?;
        take(&mut fs, st, line, resolve, p, vel)?;
    }
    match fs.block {
        Some((open, _)) => {
            let m = "SPLINE block not closed: no ENDSPLINE before the end of the file";
            Err(fail(p, file, ParseError::new(open, 1, m)))
        }
        None => Ok(()),
    }
}

/// One statement read at `line` of the file `fs` reads: into `p`, a
/// sub-program called read in its place.
fn take(
    fs: &mut FileState,
    st: Parsed1,
    line: u32,
    resolve: &mut dyn FnMut(&str) -> Option<String>,
    p: &mut KrlProgram,
    vel: &mut Option<f64>,
) -> Result<(), KrlError> {
    let file = fs.file;
    let push = |p: &mut KrlProgram, statement| {
        p.statements.push(Located {
            file,
            line,
            statement,
        })
    };
    match st {
        Parsed1::Def(name) => {
            if p.files[file].is_empty() {
                p.files[file] = name;
            }
        }
        Parsed1::Ext(name) => fs.ext.push(name.to_ascii_uppercase()),
        Parsed1::Call(name, text) if fs.ext.contains(&name.to_ascii_uppercase()) => {
            if fs.depth >= MAX_DEPTH {
                let m = "sub-programs call each other deeper than 8 levels";
                return Err(fail(p, file, ParseError::new(line, 1, m)));
            }
            match resolve(&name) {
                Some(sub) => {
                    let idx = p.files.len();
                    p.files.push(name.clone());
                    read_file(&sub, idx, fs.depth + 1, resolve, p, vel)?;
                }
                None => {
                    p.missing.push((name, file, line));
                    push(p, Statement::Verbatim(text));
                }
            }
        }
        Parsed1::Call(_, text) => push(p, Statement::Verbatim(text)),
        Parsed1::Begin(with, speed) => {
            fs.block = Some((line, speed));
            warn_with(p, file, line, &with);
            push(p, Statement::SplineBegin(with));
        }
        Parsed1::End(approx) => {
            fs.block = None;
            push(p, Statement::SplineEnd(approx));
        }
        Parsed1::St(mut s) => {
            in_force(&mut s, fs, line, p, vel);
            push(p, s);
        }
    }
    Ok(())
}

/// A statement's part in what is in force: a `$VEL.CP` sets the speed, a
/// motion takes its own, its block's or the one in force; what is not
/// modelled is named.
fn in_force(
    s: &mut Statement,
    fs: &FileState,
    line: u32,
    p: &mut KrlProgram,
    vel: &mut Option<f64>,
) {
    match s {
        Statement::VelCp(v) | Statement::Vel { cp: Some(v), .. } => *vel = Some(*v),
        Statement::Move { vel_cp, with, .. } => {
            *vel_cp = vel_cp.or(fs.block.and_then(|b| b.1)).or(*vel);
            warn_with(p, fs.file, line, with);
        }
        _ => {}
    }
}

/// A finding for each option of a `WITH` clause kept as written but not
/// modelled (a speed `$VEL = {CP …}` is read, so not named).
fn warn_with(p: &mut KrlProgram, file: usize, line: u32, with: &[String]) {
    for o in with {
        let m = if sets_path_speed(o) {
            continue;
        } else if is_vel(o) {
            format!("WITH {o}: no CP, so the path speed stays the one in force; the orientation speeds are kept as written, the toolpath read does not model them")
        } else {
            format!("WITH {o}: kept as written; the toolpath read does not model it")
        };
        p.warnings.push((file, line, m));
    }
}

/// Whether an assignment is to `$VEL`, not to another variable whose name
/// starts alike (`$VEL_EXTAX`, `$VEL_AXIS`) or to one component (`$VEL.CP`).
fn is_vel(option: &str) -> bool {
    option
        .split('=')
        .next()
        .is_some_and(|l| l.trim().eq_ignore_ascii_case("$VEL"))
}

/// Whether a `WITH` option sets the path speed: `$VEL = {CP …}` or
/// `$VEL = SVEL_CP(…)`, read as the motion's speed; a `$VEL = {ORI1 …}`
/// without CP does not.
pub(crate) fn sets_path_speed(option: &str) -> bool {
    is_vel(option)
        && option
            .split_once('=')
            .is_some_and(|(_, r)| matches!(vel_value(r.trim()), Ok(Some(_))))
}

/// Whether a `WITH` option moves the motion's frame (`$BASE`, `$TOOL`, the
/// interpolation mode `$IPO_MODE` that swaps them): its point is then not
/// in the frame the program's other points are read in.
fn moves_frame(option: &str) -> bool {
    let name = option.split('=').next().unwrap_or("").trim();
    ["$BASE", "$TOOL", "$IPO_MODE"]
        .iter()
        .any(|f| name.eq_ignore_ascii_case(f))
}

/// The line's first word, upper case.
fn first_word(t: &str) -> String {
    let w = t.split(|c: char| c.is_whitespace() || c == '(' || c == '{');
    w.map(str::trim)
        .find(|w| !w.is_empty())
        .unwrap_or("")
        .to_ascii_uppercase()
}

/// Whether `st` may stand where it is: a SPLINE block (open at `block`)
/// holds only spline segments, `SPTP`, `TRIGGER` and comments; `SPL` only
/// stands inside one; blocks do not nest.
fn in_block(
    block: Option<(u32, Option<f64>)>,
    st: &Parsed1,
    raw: &str,
    line: u32,
) -> Result<(), ParseError> {
    let col = col_of(raw, raw.trim_start());
    let err = |m: String| Err(ParseError::new(line, col, m));
    let Some((open, _)) = block else {
        return match st {
            Parsed1::End(_) => err("ENDSPLINE without a SPLINE block open".into()),
            Parsed1::St(Statement::Move {
                motion: Motion::Spl(_),
                ..
            }) => err(
                "SPL outside a SPLINE block: SPL segments stand between SPLINE and ENDSPLINE"
                    .into(),
            ),
            _ => Ok(()),
        };
    };
    let fits = match st {
        Parsed1::End(_) => true,
        Parsed1::St(Statement::Move { motion, .. }) => motion.is_spline(),
        Parsed1::St(Statement::Verbatim(t)) => t.starts_with(';') || first_word(t) == "TRIGGER",
        _ => false,
    };
    if fits {
        return Ok(());
    }
    let what = if matches!(st, Parsed1::Begin(..)) {
        "SPLINE inside a SPLINE block".to_string()
    } else {
        format!("{}: not a spline segment", first_word(raw.trim()))
    };
    err(format!(
        "{what}: the block opened at line {open} holds only SPL, SLIN, SCIRC and SPTP segments, TRIGGER and comments until its ENDSPLINE"
    ))
}

#[allow(clippy::large_enum_variant)]
enum Parsed1 {
    Def(String),
    Ext(String),
    /// A call `name(…)`: the name and the statement as written.
    Call(String, String),
    /// `SPLINE [WITH …]`: the options kept and the block's speed.
    Begin(Vec<String>, Option<f64>),
    /// `ENDSPLINE [C_SPL]`.
    End(bool),
    St(Statement),
}

/// The 1-based column of `sub`, a slice of `raw`, in `raw`.
fn col_of(raw: &str, sub: &str) -> u32 {
    let off = (sub.as_ptr() as usize).saturating_sub(raw.as_ptr() as usize);
    u32::try_from(off.min(raw.len()) + 1).unwrap_or(u32::MAX)
}

/// One line (`in_block`: inside a SPLINE block): `None` for blank lines,
/// headers and `END`.
fn parse_line(raw: &str, line: u32, in_block: bool) -> Result<Option<Parsed1>, ParseError> {
    let text = raw.trim();
    let code = text.split(';').next().unwrap_or("").trim();
    if text.is_empty() || text.starts_with('&') {
        return Ok(None);
    }
    if code.is_empty() {
        return Ok(Some(Parsed1::St(Statement::Verbatim(text.to_string()))));
    }
    let up = code.to_ascii_uppercase();
    let word = up
        .split(|c: char| c.is_whitespace() || c == '(' || c == '{')
        .next()
        .unwrap_or("");
    let col = col_of(raw, code);
    match word {
        "DEF" | "GLOBAL" if up.contains("DEF ") => {
            let name = name_before_paren(&code[up.find("DEF ").unwrap_or(0) + 4..]);
            Ok(Some(Parsed1::Def(name)))
        }
        "END" => Ok(None),
        "EXT" => Ok(Some(Parsed1::Ext(name_before_paren(&code[3..])))),
        "LIN" | "PTP" | "CIRC" | "SPL" | "SLIN" | "SCIRC" | "SPTP" => {
            motion(word, code, (raw, line, in_block)).map(|s| Some(Parsed1::St(s)))
        }
        "SPLINE" => {
            let rest = code[word.len()..].trim();
            let (speed, with) = with_clause(rest, raw, line)?;
            Ok(Some(Parsed1::Begin(with, speed)))
        }
        "ENDSPLINE" => match up[word.len()..].trim() {
            "" => Ok(Some(Parsed1::End(false))),
            "C_SPL" => Ok(Some(Parsed1::End(true))),
            other => Err(ParseError::new(
                line,
                col_of(raw, code[word.len()..].trim()),
                format!("ENDSPLINE {other}: only C_SPL may follow ENDSPLINE"),
            )),
        },
        _ => Ok(Some(assignment_or_call(code, text, &up, line, col)?)),
    }
}

fn name_before_paren(s: &str) -> String {
    s.trim().split('(').next().unwrap_or("").trim().to_string()
}

fn assignment_or_call(
    code: &str,
    text: &str,
    up: &str,
    line: u32,
    col: u32,
) -> Result<Parsed1, ParseError> {
    if let Some((lhs, rhs)) = code.split_once('=') {
        let (l, r) = (lhs.trim().to_ascii_uppercase(), rhs.trim());
        let number = |what: &str| {
            r.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| {
                    ParseError::new(
                        line,
                        col,
                        format!("{what} = {r}: a number from 0 up was expected"),
                    )
                })
        };
        match l.as_str() {
            "$VEL.CP" => return Ok(Parsed1::St(Statement::VelCp(number("$VEL.CP")?))),
            "$VEL" if r.starts_with('{') => {
                let cp = vel_value(r).map_err(|()| {
                    ParseError::new(
                        line,
                        col,
                        format!("$VEL = {r}: its CP, the path speed (m/s, a number from 0 up), is not read from it"),
                    )
                })?;
                let text = r.to_string();
                return Ok(Parsed1::St(Statement::Vel { cp, text }));
            }
            "$APO.CDIS" => return Ok(Parsed1::St(Statement::ApoCdis(number("$APO.CDIS")?))),
            "$TOOL" => return Ok(Parsed1::St(Statement::Tool(r.to_string()))),
            "$BASE" => return Ok(Parsed1::St(Statement::Base(r.to_string()))),
            _ => {}
        }
    }
    let is_call = up.ends_with(')')
        && up.split('(').next().is_some_and(|n| {
            let n = n.trim();
            !n.is_empty() && n.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
        });
    if is_call {
        return Ok(Parsed1::Call(name_before_paren(code), text.to_string()));
    }
    Ok(Parsed1::St(Statement::Verbatim(text.to_string())))
}

fn motion(
    word: &str,
    code: &str,
    (raw, line, in_block): (&str, u32, bool),
) -> Result<Statement, ParseError> {
    let rest = code[word.len()..].trim();
    // The target's closing brace (a circle's second): a `WITH` clause after
    // it may hold aggregates of its own.
    let skip = usize::from(word.ends_with("CIRC"));
    let close = rest.match_indices('}').nth(skip).map(|(i, _)| i);
    let (targets, tail) = match close {
        Some(end) if rest.starts_with('{') => (&rest[..=end], rest[end + 1..].trim()),
        _ => ("", rest),
    };
    let (tail, approx) = approximation(word, tail, (raw, line, in_block))?;
    let spline = matches!(word, "SPL" | "SLIN" | "SCIRC" | "SPTP");
    let (vel_cp, with) = if spline {
        with_clause(tail, raw, line)?
    } else if tail.trim().is_empty() || targets.is_empty() {
        // No aggregate: a named position or joint angles, kept as written.
        (None, Vec::new())
    } else {
        // Read past, `CIRC …, CA 90` would end the arc at its target
        // whatever angle it asks for.
        let t = tail.trim();
        let what = if t
            .trim_start_matches(',')
            .trim_start()
            .to_ascii_uppercase()
            .starts_with("CA")
        {
            "a circle's angle (CA) is not read: the arc would be taken to end at its target"
        } else {
            "only an approximation is read after the target"
        };
        return Err(ParseError::new(
            line,
            col_of(raw, t),
            format!("{t}: {what}"),
        ));
    };
    let named = || {
        ParseError::new(
            line,
            col_of(raw, rest),
            format!("{word} to a named position: only aggregates {{X …}} are read"),
        )
    };
    let motion = match word {
        "PTP" if targets.is_empty() || targets.to_ascii_uppercase().contains("A1 ") => {
            Motion::PtpOther(rest.to_string())
        }
        "PTP" => Motion::Ptp(aggregate(targets, raw, line)?),
        "SPTP" if targets.is_empty() || targets.to_ascii_uppercase().contains("A1 ") => {
            Motion::SptpOther(rest.to_string())
        }
        "SPTP" => Motion::Sptp(aggregate(targets, raw, line)?),
        "LIN" | "SPL" | "SLIN" if targets.is_empty() => return Err(named()),
        "LIN" => Motion::Lin(aggregate(targets, raw, line)?),
        "SPL" => Motion::Spl(aggregate(targets, raw, line)?),
        "SLIN" => Motion::Slin(aggregate(targets, raw, line)?),
        _ => {
            let (aux, end) = circle_targets(word, targets, raw, line)?;
            if word == "CIRC" {
                Motion::Circ { aux, end }
            } else {
                Motion::Scirc { aux, end }
            }
        }
    };
    Ok(Statement::Move {
        motion,
        approx,
        vel_cp,
        with,
    })
}

/// The approximation tags ending the tail of a motion `word` (inside a
/// SPLINE block when `in_block`), checked against those the motion takes
/// (see [`Approx`]), and what is before them; a tag the motion does not
/// take is an error at its column.
fn approximation<'a>(
    word: &str,
    tail: &'a str,
    (raw, line, in_block): (&str, u32, bool),
) -> Result<(&'a str, Approx), ParseError> {
    let tags = trailing_tags(tail);
    let Some(&(first, _)) = tags.first() else {
        return Ok((tail, Approx::Exact));
    };
    let up: Vec<String> = tags.iter().map(|t| t.1.to_ascii_uppercase()).collect();
    let up: Vec<&str> = up.iter().map(String::as_str).collect();
    let segment = in_block && word.starts_with('S');
    let taken = if segment { Err(0) } else { takes(word, &up) };
    match taken {
        Ok(a) => Ok((tail[..first].trim_end(), a)),
        Err(k) => {
            let what = if segment || word == "SPL" {
                "a segment of a SPLINE block is not approximated alone: the block's ENDSPLINE C_SPL approximates it"
            } else {
                match word {
                    "LIN" | "CIRC" => "LIN and CIRC take one of C_DIS, C_VEL, C_ORI",
                    "PTP" => "PTP takes C_PTP, C_PTP and one of C_DIS, C_ORI, C_VEL (for a LIN or CIRC after it), or C_DIS",
                    "SPTP" => "SPTP takes C_SPL or C_PTP",
                    _ => "SLIN and SCIRC outside a SPLINE block take C_SPL",
                }
            };
            let before = up[..k].iter().fold(word.to_string(), |w, t| w + " " + t);
            Err(ParseError::new(
                line,
                col_of(raw, tags[k].1),
                format!("{} after {before}: {what}", up[k]),
            ))
        }
    }
}

/// The approximation of a motion `word` from its tags `t` (upper case), or
/// the index of the first tag it does not take.
fn takes(word: &str, t: &[&str]) -> Result<Approx, usize> {
    let cp = |s: &str| match s {
        "C_DIS" => Some(Approx::Dis),
        "C_VEL" => Some(Approx::Vel),
        "C_ORI" => Some(Approx::Ori),
        _ => None,
    };
    let found = match (word, t) {
        ("LIN" | "CIRC", [a]) => cp(a),
        // KSS 8's inline forms write `LIN XP1 C_DIS C_DIS`.
        ("LIN" | "CIRC", [a, b]) if a == b => cp(a),
        ("PTP" | "SPTP", ["C_PTP"]) => Some(Approx::Ptp),
        ("PTP", ["C_PTP", b]) => match *b {
            "C_DIS" => Some(Approx::PtpDis),
            "C_ORI" => Some(Approx::PtpOri),
            "C_VEL" => Some(Approx::PtpVel),
            _ => None,
        },
        // KSS 8 approximates a PTP by C_DIS (its inline forms write it).
        ("PTP", ["C_DIS"]) => Some(Approx::Dis),
        ("SPTP" | "SLIN" | "SCIRC", ["C_SPL"]) => Some(Approx::Spl),
        _ => None,
    };
    match found {
        Some(a) => Ok(a),
        None if t.len() > 1 && takes(word, &t[..1]).is_ok() => Err(1),
        None => Err(0),
    }
}

/// The words `C_…` ending `tail` (a motion's approximation tags), with
/// their offsets in it; a value of a `WITH` assignment (`$X = C_Y`) is not
/// one.
fn trailing_tags(tail: &str) -> Vec<(usize, &str)> {
    let words: Vec<(usize, &str)> = tail
        .split_whitespace()
        .map(|w| (w.as_ptr() as usize - tail.as_ptr() as usize, w))
        .collect();
    let is_tag = |w: &str| {
        w.len() > 2
            && w.get(..2).is_some_and(|c| c.eq_ignore_ascii_case("C_"))
            && w.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
    };
    let n = words.iter().rev().take_while(|(_, w)| is_tag(w)).count();
    let mut start = words.len() - n;
    if start > 0 && n > 0 && words[start - 1].1.ends_with('=') {
        start += 1;
    }
    words[start..].to_vec()
}

/// `{…}, {…}` of a `CIRC` or `SCIRC`: the auxiliary point and the target.
fn circle_targets(
    word: &str,
    targets: &str,
    raw: &str,
    line: u32,
) -> Result<(KrlPos, KrlPos), ParseError> {
    let split = targets.find('}').and_then(|i| {
        let end = targets[i + 1..].trim_start().strip_prefix(',')?.trim();
        Some((&targets[..=i], end))
    });
    let Some((aux, end)) = split.filter(|(_, e)| e.starts_with('{')) else {
        return Err(ParseError::new(
            line,
            col_of(raw, targets),
            format!("{word} needs an auxiliary point and a target: {{…}}, {{…}}"),
        ));
    };
    Ok((aggregate(aux, raw, line)?, aggregate(end, raw, line)?))
}

/// A spline motion's or block's `WITH a = x, b = y` (or nothing): the path
/// speed it sets, m/s, and the options other than `$VEL.CP = v` as written.
fn with_clause(text: &str, raw: &str, line: u32) -> Result<(Option<f64>, Vec<String>), ParseError> {
    let t = text.trim();
    if t.is_empty() {
        return Ok((None, Vec::new()));
    }
    let err = |at: &str, m: String| ParseError::new(line, col_of(raw, at), m);
    // `get`: a character that is not ASCII may straddle the fourth byte.
    let body = (t.len() > 4 && t.get(..4).is_some_and(|w| w.eq_ignore_ascii_case("WITH")))
        .then(|| &t[4..])
        .filter(|b| b.starts_with(char::is_whitespace))
        .ok_or_else(|| {
            err(
                t,
                format!("{t}: only a WITH clause and an approximation are read here"),
            )
        })?;
    let (mut speed, mut kept) = (None, Vec::new());
    for part in split_top(body) {
        let part = part.trim();
        let Some((lhs, rhs)) = part.split_once('=') else {
            return Err(err(
                part,
                format!("{part:?}: an assignment `$NAME = value` was expected in WITH"),
            ));
        };
        let (l, r) = (lhs.trim().to_ascii_uppercase(), rhs.trim());
        let bad = || {
            err(
                r,
                format!("{part}: the path speed (m/s, a number from 0 up) is not read from it"),
            )
        };
        match l.as_str() {
            "$VEL.CP" => speed = Some(speed_number(r).ok_or_else(bad)?),
            "$VEL" => {
                // Without CP the speed in force stays (the option is kept).
                if let Some(v) = vel_value(r).map_err(|()| bad())? {
                    speed = Some(v);
                }
                kept.push(part.to_string());
            }
            _ => kept.push(part.to_string()),
        }
    }
    Ok((speed, kept))
}

/// A speed: a finite number from 0 up.
fn speed_number(s: &str) -> Option<f64> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v >= 0.0)
}

/// The path speed a `$VEL` value sets, m/s: the CP component of
/// `{CP 0.2, ORI1 …}` (an aggregate without one, `{ORI1 …, ORI2 …}`, sets
/// none: `Ok(None)`) or the first argument of `SVEL_CP(0.2, …)`; `Err`
/// when a CP or that argument is not a speed, or the value is neither.
fn vel_value(r: &str) -> Result<Option<f64>, ()> {
    if let Some(inner) = r.strip_prefix('{').and_then(|r| r.strip_suffix('}')) {
        let inner = inner.split_once(':').map_or(inner, |(_, r)| r);
        let mut cp = None;
        for c in inner.split(',') {
            let mut it = c.split_whitespace();
            let (Some(key), value) = (it.next(), it.next()) else {
                continue;
            };
            if key.eq_ignore_ascii_case("CP") {
                cp = Some(value.and_then(speed_number).ok_or(())?);
            }
        }
        return Ok(cp);
    }
    let up = r.to_ascii_uppercase();
    let args = up.strip_prefix("SVEL_CP").map(str::trim_start);
    let first = args.and_then(|a| a.strip_prefix('(')?.split([',', ')']).next());
    first.and_then(speed_number).map(Some).ok_or(())
}

/// `s` split at the commas outside braces and parentheses.
fn split_top(s: &str) -> Vec<&str> {
    let (mut parts, mut depth, mut start) = (Vec::new(), 0i32, 0);
    for (i, c) in s.char_indices() {
        match c {
            '{' | '(' => depth += 1,
            '}' | ')' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&s[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&s[start..]);
    parts
}

/// `{X 1, Y 2, Z 3, A 0, B 90, C 0, E1 10, S 6, T 27}` (E6POS, POS or
/// FRAME; X, Y, Z needed), a slice of the line `raw`: errors at the
/// component's column.
fn aggregate(s: &str, raw: &str, line: u32) -> Result<KrlPos, ParseError> {
    let inner = s
        .trim()
        .strip_prefix('{')
        .and_then(|r| r.strip_suffix('}'))
        .ok_or_else(|| {
            ParseError::new(
                line,
                col_of(raw, s),
                format!("{s}: an aggregate {{X …, Y …, Z …}} was expected"),
            )
        })?;
    let inner = inner.split_once(':').map_or(inner, |(_, r)| r); // `{E6POS: X …}`
    let mut xyz = [f64::NAN; 3];
    let mut p = KrlPos {
        xyz: DVec3::NAN,
        abc: [0.0; 3],
        e: [None; 6],
        s: None,
        t: None,
    };
    for part in inner.split(',') {
        component(part, raw, line, &mut xyz, &mut p)?;
    }
    if xyz.iter().any(|v| v.is_nan()) {
        return Err(ParseError::new(
            line,
            col_of(raw, s),
            "a KRL position needs X, Y and Z",
        ));
    }
    p.xyz = DVec3::from_array(xyz);
    Ok(p)
}

/// One `NAME value` of an aggregate into `xyz` or `p`.
fn component(
    part: &str,
    raw: &str,
    line: u32,
    xyz: &mut [f64; 3],
    p: &mut KrlPos,
) -> Result<(), ParseError> {
    let col = col_of(raw, part.trim_start());
    let mut it = part.split_whitespace();
    let (Some(key), Some(val), None) = (it.next(), it.next(), it.next()) else {
        return Err(ParseError::new(
            line,
            col,
            format!("{:?}: a component `NAME value` was expected", part.trim()),
        ));
    };
    let key = key.to_ascii_uppercase();
    let num = || -> Result<f64, ParseError> {
        let v = if let Some(b) = val
            .strip_prefix('\'')
            .and_then(|v| v.strip_prefix('B').or(v.strip_prefix('b')))
        {
            u32::from_str_radix(b.trim_end_matches('\''), 2)
                .map(f64::from)
                .ok()
        } else {
            val.parse::<f64>().ok()
        };
        v.filter(|v| v.is_finite())
            .ok_or_else(|| ParseError::new(line, col, format!("{key} {val}: not a number")))
    };
    match key.as_str() {
        "X" => xyz[0] = num()?,
        "Y" => xyz[1] = num()?,
        "Z" => xyz[2] = num()?,
        "A" => p.abc[0] = num()?,
        "B" => p.abc[1] = num()?,
        "C" => p.abc[2] = num()?,
        "S" => p.s = Some(num()? as u32),
        "T" => p.t = Some(num()? as u32),
        k if k.len() == 2 && k.starts_with('E') && (b'1'..=b'6').contains(&k.as_bytes()[1]) => {
            p.e[(k.as_bytes()[1] - b'1') as usize] = Some(num()?)
        }
        _ => {
            return Err(ParseError::new(
                line,
                col,
                format!("{key}: not a component of a Cartesian KRL position"),
            ))
        }
    }
    Ok(())
}

/// The statement a line of KRL is (a `$VEL.CP`, `$TOOL`, … kept by the IR
/// as text), or `None` for a line that is not one statement.
pub fn statement_of(text: &str) -> Option<Statement> {
    match parse_line(text, 1, false).ok()?? {
        Parsed1::St(s) => Some(s),
        Parsed1::Call(_, t) => Some(Statement::Verbatim(t)),
        _ => None,
    }
}

/// KUKA's orientation R = Rz(A)·Ry(B)·Rx(C), degrees.
pub fn abc_matrix(abc: [f64; 3]) -> DMat3 {
    let [a, b, c] = abc.map(f64::to_radians);
    DMat3::from_rotation_z(a) * DMat3::from_rotation_y(b) * DMat3::from_rotation_x(c)
}

/// The tool axis (tip toward the spindle) of a KRL orientation: KUKA's tool
/// points along its frame's x, so the axis is −x.
pub fn tool_axis(abc: [f64; 3]) -> DVec3 {
    -(abc_matrix(abc) * DVec3::X)
}

/// An orientation whose tool axis is `axis`: the frame of A = C = 0, B = 90°
/// (tool pointing down, axis +z) turned by the shortest rotation onto it.
pub fn abc_for_axis(axis: DVec3) -> [f64; 3] {
    let down = abc_matrix([0.0, 90.0, 0.0]);
    let r = glam::DQuat::from_rotation_arc(DVec3::Z, axis.normalize());
    let m = DMat3::from_quat(r) * down;
    let cb = m.col(0).x.hypot(m.col(0).y);
    let b = (-m.col(0).z).atan2(cb);
    let (a, c) = if cb > 1e-12 {
        (m.col(0).y.atan2(m.col(0).x), m.col(1).z.atan2(m.col(2).z))
    } else {
        ((-m.col(1).x).atan2(m.col(1).y), 0.0)
    };
    [a.to_degrees(), b.to_degrees(), c.to_degrees()]
}

impl KrlProgram {
    /// Where statement `i` was read: `NAME:LINE` of its file.
    pub fn place(&self, l: &Located) -> String {
        format!(
            "{}:{}",
            self.files.get(l.file).map_or("?", String::as_str),
            l.line
        )
    }

    /// The toolpath IR of the program, for writing it in another dialect.
    /// The first motion's `$VEL.CP` unset: `default_feed` (mm/min) and a
    /// finding. External axes E1..E6 are refused at their statement unless
    /// `lossy` (then a finding each, once per file).
    pub fn to_ir(&self, default_feed: f64, lossy: bool) -> Result<Parsed, KrlError> {
        let mut prog = Program::new(Dialect::Krl);
        prog.name = Some(self.name.clone());
        let mut op = Operation {
            tool: Some(self.tool()),
            ..Operation::default()
        };
        let mut diags = Vec::new();
        let mut warned_feed = false;
        let mut warned_e = false;
        for l in &self.statements {
            let Statement::Move {
                motion,
                vel_cp,
                with,
                ..
            } = &l.statement
            else {
                self.event(l, &mut op);
                continue;
            };
            if let Some(o) = with.iter().find(|o| moves_frame(o)) {
                let message = format!(
                    "WITH {o}: this motion's point is in a frame of its own, which the target dialect has no place for: --lossy reads it in the program's frame"
                );
                if !lossy {
                    return Err(KrlError {
                        file: self.file_name(l),
                        error: ParseError::new(l.line, 1, message),
                    });
                }
                diags.push(diag(
                    Code::LossyWord,
                    l.line,
                    format!("{}: {message}", self.place(l)),
                ));
            }
            let feed = match vel_cp {
                Some(v) => v * 60_000.0,
                None => {
                    if !warned_feed {
                        warned_feed = true;
                        diags.push(diag(Code::FeedMissing, l.line, format!(
                            "{}: no $VEL.CP before the first motion: {default_feed} mm/min assumed", self.place(l))));
                    }
                    default_feed
                }
            };
            if let Some(p) = motion.end() {
                if p.e.iter().any(Option::is_some) {
                    if !lossy {
                        return Err(KrlError { file: self.file_name(l), error: ParseError::new(l.line, 1,
                            "an external axis (E1..E6) has no place in the target dialect: --lossy drops it") });
                    }
                    if !warned_e {
                        warned_e = true;
                        diags.push(diag(
                            Code::LossyWord,
                            l.line,
                            format!("{}: external axes E1..E6 dropped", self.place(l)),
                        ));
                    }
                }
            }
            self.push_move(l, motion, feed, &mut op);
        }
        self.findings(&mut diags);
        prog.operations.push(op);
        Ok(Parsed {
            program: prog,
            diagnostics: diags,
        })
    }

    /// What was read but not modelled, and the sub-programs not read, as
    /// findings at their lines.
    fn findings(&self, diags: &mut Vec<Diagnostic>) {
        for (file, line, what) in &self.warnings {
            let name = self.files.get(*file).map_or("?", String::as_str);
            let message = format!("{name}:{line}: {what}");
            diags.push(diag(Code::UnknownWord, *line, message));
        }
        for (name, file, line) in &self.missing {
            diags.push(diag(
                Code::UnknownPosition,
                *line,
                format!(
                "{}:{line}: sub-program {name} is called but not beside the main program: not read",
                self.files.get(*file).map_or("?", String::as_str)),
            ));
        }
    }

    /// The tool of the first `$TOOL = TOOL_DATA[n]`, else an unnamed one.
    fn tool(&self) -> crate::ir::Tool {
        let first = self.statements.iter().find_map(|l| match &l.statement {
            Statement::Tool(t) => Some((l.line, t.clone())),
            _ => None,
        });
        let number = first.as_ref().and_then(|(_, t)| {
            let inner = t.split('[').nth(1)?.split(']').next()?;
            inner.trim().parse::<u32>().ok()
        });
        crate::ir::Tool {
            number,
            name: Some(
                first
                    .as_ref()
                    .map_or("robot tool ($TOOL not set)".into(), |(_, t)| t.clone()),
            ),
            cutter: None,
            line: first.map_or(0, |(l, _)| l),
        }
    }

    fn file_name(&self, l: &Located) -> Option<String> {
        if l.file == 0 {
            None
        } else {
            self.files.get(l.file).cloned()
        }
    }

    fn event(&self, l: &Located, op: &mut Operation) {
        let text = match &l.statement {
            Statement::VelCp(v) => format!("$VEL.CP = {v}"),
            Statement::Vel { text, .. } => format!("$VEL = {text}"),
            Statement::ApoCdis(v) => format!("$APO.CDIS = {v}"),
            Statement::Tool(t) => format!("$TOOL = {t}"),
            Statement::Base(b) => format!("$BASE = {b}"),
            Statement::SplineBegin(with) if with.is_empty() => "SPLINE".into(),
            Statement::SplineBegin(with) => format!("SPLINE WITH {}", with.join(", ")),
            Statement::SplineEnd(false) => "ENDSPLINE".into(),
            Statement::SplineEnd(true) => "ENDSPLINE C_SPL".into(),
            Statement::Verbatim(t) if t.starts_with(';') => {
                op.push_event(
                    l.line,
                    EventKind::Comment(t.trim_start_matches(';').trim().to_string()),
                );
                return;
            }
            Statement::Verbatim(t) => t.clone(),
            Statement::Move { .. } => return,
        };
        let word = text
            .split(|c: char| c.is_whitespace() || c == '(' || c == '=')
            .next()
            .unwrap_or("")
            .to_string();
        // Speeds, approximation and frames are the robot's; the writers of
        // other dialects keep them as comments.
        op.push_event(
            l.line,
            EventKind::Passthrough(Passthrough {
                word,
                text,
                class: PassClass::Info,
                modal: false,
                moves: false,
            }),
        );
    }

    fn push_move(&self, l: &Located, motion: &Motion, feed: f64, op: &mut Operation) {
        let (end, kind, rapid) = match motion {
            Motion::Lin(p) | Motion::Spl(p) | Motion::Slin(p) => (p, MoveKind::Linear, false),
            Motion::Ptp(p) | Motion::Sptp(p) => (p, MoveKind::Rapid, true),
            Motion::Circ { aux, end } | Motion::Scirc { aux, end } => {
                let start = op.moves.last().map_or(DVec3::NAN, |m| m.end);
                match circle(start, aux.xyz, end.xyz) {
                    Some(arc) => {
                        let id = op.push_arc(arc);
                        (end, MoveKind::Arc(id), false)
                    }
                    None => (end, MoveKind::Linear, false),
                }
            }
            Motion::PtpOther(text) | Motion::SptpOther(text) => {
                let word = if matches!(motion, Motion::PtpOther(_)) {
                    "PTP"
                } else {
                    "SPTP"
                };
                op.push_event(
                    l.line,
                    EventKind::Passthrough(Passthrough {
                        word: word.into(),
                        text: format!("{word} {text}"),
                        class: PassClass::Machine,
                        modal: false,
                        moves: true,
                    }),
                );
                return;
            }
        };
        let orient = op.intern_orient(Orient::vector(tool_axis(end.abc)));
        op.moves.push(Move {
            end: end.xyz,
            feed: if rapid { 0.0 } else { feed },
            spindle: 0.0,
            line: l.line,
            kind,
            orient: Some(orient),
            feed_mode: FeedMode::PerMinute,
        });
    }
}

fn diag(code: Code, line: u32, message: String) -> Diagnostic {
    Diagnostic {
        severity: Severity::Warning,
        code,
        line,
        col: 0,
        message,
    }
}

/// The arc from `a` through `b` to `c`, or `None` when they are in a line.
fn circle(a: DVec3, b: DVec3, c: DVec3) -> Option<crate::ir::Arc> {
    let (u, v) = (b - a, c - a);
    let n = u.cross(v);
    if !a.is_finite() || n.length_squared() < 1e-18 * u.length_squared() * v.length_squared() {
        return None;
    }
    let centre = a
        + (n.cross(u) * v.length_squared() + v.cross(n) * u.length_squared())
            / (2.0 * n.length_squared());
    crate::ir::Arc::from_points(a, c, centre, n, false)
}
