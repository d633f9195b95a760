//! G-code readers: ISO 6983 / Fanuc-style (Haas, Mori Seiki, Röders), Siemens
//! Sinumerik 840D and LinuxCNC in this module; Heidenhain plain language in
//! [`heidenhain`].
//!
//! The reader keeps the modal state (motion group, plane, G90/G91, units, feed mode,
//! feed, spindle, rotary axes, canned cycle) and turns each block into at most one
//! move plus events. Words it does not model are kept as pass-through events; those
//! it does not know at all also become diagnostics with their line and column.

pub mod expr;
pub mod heidenhain;

use crate::diag::{parse_num, Code, Diags, ParseError, Parsed};
use crate::ir::*;
use crate::ReadOptions;
use millplan_geom::DVec3;
use std::collections::BTreeMap;

/// One lexical item of a block.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    /// Address letter and value: `X-1.5`, `G43.4`, `N10`.
    Word(char, f64),
    /// `NAME=value` (Sinumerik `X=_X_HOME`, `CR=5`, `A3=.5`, `_camtolerance=.02`, `T="EM10"`).
    Assign(String, String),
    /// `NAME(args)` (Sinumerik `CYCLE832(...)`, `MSG("...")`).
    Call(String, String),
    /// A bare keyword (`TRAORI`, `SUPA`, `G64` is a Word).
    Keyword(String),
}

#[derive(Debug)]
struct Lexed {
    toks: Vec<(Tok, u32)>,
    comments: Vec<String>,
    /// The block starts with `/`: it runs or not as the operator's switch says.
    block_delete: bool,
    /// A number word directly followed by `E` and digits (`X1e5`): its
    /// column and text. G-code numbers have no exponent, so it reads as `X1`
    /// and a word `E5`, which the reader warns about.
    exponent: Option<(u32, String)>,
}

/// Splits a block into tokens and comments. `(..)` comments may nest (some posts
/// write `(#508= (NAME))`); `;` comments run to the end of the line.
fn lex(line: &str, ln: u32) -> Result<Lexed, ParseError> {
    let b = line.as_bytes();
    let mut i = 0;
    let mut toks = Vec::with_capacity(8);
    let mut comments = Vec::new();
    let mut block_delete = false;
    let mut exponent = None;
    while i < b.len() {
        let c = b[i];
        let col = (i + 1) as u32;
        if c.is_ascii_whitespace() || c == b',' {
            // Commas separate names in `DEF REAL _A, _B`.
            i += 1;
            continue;
        }
        match c {
            b'(' => {
                let mut depth = 0;
                let s = i;
                while i < b.len() {
                    match b[i] {
                        b'(' => depth += 1,
                        b')' => {
                            depth -= 1;
                            if depth == 0 {
                                i += 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                    i += 1;
                }
                let inner = line[s..i]
                    .trim_start_matches('(')
                    .trim_end_matches(')')
                    .trim();
                comments.push(inner.to_string());
                continue;
            }
            b')' => {
                // A stray closing parenthesis after a nested comment.
                i += 1;
                continue;
            }
            b';' => {
                comments.push(line[i + 1..].trim().to_string());
                break;
            }
            b'%' => {
                i += 1;
                continue;
            }
            b'/' if toks.is_empty() => {
                // Block delete (`/`, `/1`..`/9`): the block runs unless the
                // operator switches it off.
                block_delete = true;
                i += 1;
                while i < b.len() && b[i].is_ascii_digit() {
                    i += 1;
                }
                continue;
            }
            _ => {}
        }
        if c.is_ascii_alphabetic() || c == b'_' || c == b'#' || c == b'$' {
            // Address letter followed directly by a number?
            let next = b.get(i + 1).copied().unwrap_or(b' ');
            if c.is_ascii_alphabetic()
                && (next.is_ascii_digit() || matches!(next, b'-' | b'+' | b'.'))
            {
                let s = i + 1;
                let mut j = s;
                if j < b.len() && matches!(b[j], b'-' | b'+') {
                    j += 1;
                }
                while j < b.len() && (b[j].is_ascii_digit() || b[j] == b'.') {
                    j += 1;
                }
                // `A3=..`, `R1=..`: an identifier being assigned, not a word.
                let mut k = j;
                while k < b.len() && b[k] == b' ' {
                    k += 1;
                }
                if k < b.len() && b[k] == b'=' && !(j < b.len() && b[j].is_ascii_alphabetic()) {
                    let name = line[i..j].to_ascii_uppercase();
                    let (val, end) = assign_value(line, k + 1);
                    toks.push((Tok::Assign(name, val), col));
                    i = end;
                    continue;
                }
                let num = &line[s..j];
                let mut e = j + 1;
                if e < b.len() && matches!(b[e], b'-' | b'+') {
                    e += 1;
                }
                if exponent.is_none()
                    && matches!(b.get(j), Some(b'e' | b'E'))
                    && b.get(e).is_some_and(|d| d.is_ascii_digit())
                {
                    let end = (e..b.len())
                        .find(|&k| !b[k].is_ascii_digit())
                        .unwrap_or(b.len());
                    exponent = Some((col, line[i..end].to_string()));
                }
                match parse_num(num) {
                    Some(v) => toks.push((Tok::Word(c.to_ascii_uppercase() as char, v), col)),
                    None => {
                        return Err(ParseError::new(
                            ln,
                            col,
                            format!("`{}` is not a number after `{}`", num, c as char),
                        ))
                    }
                }
                i = j;
                continue;
            }
            let s = i;
            let mut j = i + 1;
            while j < b.len() && (b[j].is_ascii_alphanumeric() || b[j] == b'_' || b[j] == b'.') {
                j += 1;
            }
            let name = line[s..j].to_ascii_uppercase();
            let mut k = j;
            while k < b.len() && b[k] == b' ' {
                k += 1;
            }
            if k < b.len() && b[k] == b'=' {
                let (val, end) = assign_value(line, k + 1);
                toks.push((Tok::Assign(name, val), col));
                i = end;
            } else if k < b.len() && b[k] == b'(' {
                let mut depth = 0;
                let mut e = k;
                let mut in_str = false;
                while e < b.len() {
                    match b[e] {
                        b'"' => in_str = !in_str,
                        b'(' if !in_str => depth += 1,
                        b')' if !in_str => {
                            depth -= 1;
                            if depth == 0 {
                                break;
                            }
                        }
                        _ => {}
                    }
                    e += 1;
                }
                if e >= b.len() {
                    return Err(ParseError::new(
                        ln,
                        col,
                        format!("`{name}(` has no closing parenthesis"),
                    ));
                }
                toks.push((Tok::Call(name, line[k + 1..e].to_string()), col));
                i = e + 1;
            } else {
                toks.push((Tok::Keyword(name), col));
                i = j;
            }
            continue;
        }
        if c == b'[' {
            return Err(ParseError::new(
                ln,
                col,
                "bracketed macro expressions are not supported",
            ));
        }
        let mut e = i;
        while e < b.len() && !b[e].is_ascii_whitespace() {
            e += 1;
        }
        return Err(ParseError::new(
            ln,
            col,
            format!("unexpected `{}`", &line[i..e]),
        ));
    }
    Ok(Lexed {
        toks,
        comments,
        block_delete,
        exponent,
    })
}

/// The value text of an assignment: a quoted string or everything up to white space.
fn assign_value(line: &str, from: usize) -> (String, usize) {
    let b = line.as_bytes();
    let mut i = from;
    while i < b.len() && b[i] == b' ' {
        i += 1;
    }
    if i < b.len() && b[i] == b'"' {
        let s = i + 1;
        let mut e = s;
        while e < b.len() && b[e] != b'"' {
            e += 1;
        }
        return (line[s..e].to_string(), (e + 1).min(b.len()));
    }
    let s = i;
    let mut depth = 0i32;
    while i < b.len() {
        match b[i] {
            b'(' => depth += 1,
            b')' => depth -= 1,
            b' ' | b'\t' | b';' if depth <= 0 => break,
            _ => {}
        }
        i += 1;
    }
    (line[s..i].to_string(), i)
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Motion {
    Rapid,
    Linear,
    Cw,
    Ccw,
    /// A canned cycle (G73, G81–G89) is active: positions are hole positions.
    Cycle,
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Plane {
    Xy,
    Zx,
    Yz,
}

impl Plane {
    fn normal(self) -> DVec3 {
        match self {
            Plane::Xy => DVec3::Z,
            Plane::Zx => DVec3::Y,
            Plane::Yz => DVec3::X,
        }
    }
}

struct CycleState {
    name: String,
    r: f64,
    z: f64,
    q: Option<f64>,
    p: Option<f64>,
    initial_z: f64,
    return_initial: bool,
    index: Option<CycleId>,
}

/// Incremental G-code reader (Fanuc, Sinumerik, LinuxCNC).
pub struct GcodeReader {
    opts: ReadOptions,
    dialect: Dialect,
    program: Program,
    ops: Vec<Operation>,
    op: Operation,
    diags: Diags,
    vars: BTreeMap<String, f64>,
    line_no: u32,
    saw_content: bool,
    /// The line of the program's end (M2, M30 or a closing `%`): a control
    /// runs nothing after it.
    ended: Option<u32>,
    /// An M17 or M99 (a subprogram's end) was read: a program end for the
    /// warning of a program without one.
    returned: bool,
    /// The line of the last block read.
    last_block: u32,
    /// The program began as a whole one: a tape's opening %, a program
    /// number or a tool change.
    framed: bool,
    /// mm per program unit right now.
    scale: f64,
    unit: Option<(LengthUnit, UnitsOrigin)>,
    motion: Motion,
    plane: Plane,
    absolute: bool,
    feed_mode: FeedMode,
    feed: f64,
    feed_seen: bool,
    feed_missing_reported: bool,
    spindle: f64,
    spindle_dir: SpindleDir,
    /// Tool-tip position; NaN on an axis the program has not commanded since
    /// the start, a tool change, a machine move, or a change of work offset,
    /// tool length or TCP (each puts the tool at other program numbers).
    pos: DVec3,
    rotary: [Option<f64>; 3],
    vector: Option<DVec3>,
    /// The work offset last selected (`None`: none yet).
    offset: Option<WorkOffset>,
    /// The tool-length compensation last selected (`None`: none yet).
    length: Option<ToolLength>,
    /// A frame change (G52, G68, ...) was read: its cancel reframes positions.
    frame_changed: bool,
    /// A G98 canned cycle from an unknown height is active (kept verbatim).
    blind_cycle: bool,
    tcp: bool,
    tcp_vectors: bool,
    selected_tool: Option<(Option<u32>, Option<String>, u32)>,
    /// A tool-select event not yet followed by a move: an M6 right after it
    /// takes it in (event index, moves of the operation then).
    pending_select: Option<(usize, usize)>,
    cycle: Option<CycleState>,
    return_initial: bool,
    /// G90.1: arc centres I, J, K are absolute coordinates (LinuxCNC);
    /// G91.1 (the default): offsets from the arc's start.
    arc_centre_absolute: bool,
    pub blocks: usize,
    pub motion_blocks: usize,
}

/// Words every reader understands without comment; the rest of the G and M codes
/// are kept verbatim.
const KNOWN_KEYWORDS: &[&str] = &[
    "TRAORI",
    "TRAFOOF",
    "SUPA",
    "MCALL",
    "ROT",
    "TRANS",
    "AROT",
    "ATRANS",
    "SCALE",
    "ASCALE",
    "MIRROR",
    "AMIRROR",
    "COMPOF",
    "COMPON",
    "COMPCAD",
    "COMPCURV",
    "FNORM",
    "FFWON",
    "FFWOF",
    "SOFT",
    "BRISK",
    "G64",
    "G60",
    "G601",
    "G602",
    "CFC",
    "CFTCP",
    "CFIN",
    "ORIWKS",
    "ORIMKS",
    "ORIAXES",
    "ORIVECT",
    "ORICONO",
    "UPATH",
    "SPATH",
    "M17",
    "RET",
    "STOPRE",
    "ENDPROGRAM",
    "ORIRESET",
    "CUT2D",
    "CUT3DC",
    "CUT3DF",
    "CUT3DFF",
    "DIAMOF",
    "DIAMON",
    "BSPLINE",
    "POLY",
    "TRANSMIT",
    "TRACYL",
    "ASPLINE",
    "CSPLINE",
    "DEF",
    "REAL",
    "INT",
    "STRING",
    "BOOL",
    "AXIS",
    "FRAME",
    "CHAR",
    "G40",
    "G500",
    "IF",
    "ELSE",
    "ENDIF",
    "GOTOF",
    "GOTOB",
    "LOOP",
    "ENDLOOP",
];

/// G codes (×10) that change the modal state a writer keeps: motion, plane,
/// units, distance and feed mode, canned cycles.
fn is_modal_g(code: i64) -> bool {
    matches!(
        code,
        0 | 10 | 20 | 30 | 170 | 180 | 190 | 200 | 210 | 700 | 710 | 7000 | 7100 | 800
            ..=890 | 730 | 740 | 760 | 900 | 910 | 930 | 940 | 950
    )
}

/// G codes (×10) whose blocks the reader keeps whole, because their axis words
/// are not a move to be read: data setting (G10), frame changes (G52, G92,
/// G68, G51, G50.1/G51.1 mirror, G68.2 tilted plane), probing (G31) and macro
/// calls (G65, G66). Every axis is unknown after them, except after G31, which
/// leaves unknown only the axes it names.
const SPECIAL_G: &[i64] = &[
    100, 310, 311, 312, 313, 314, 510, 511, 520, 531, 650, 660, 661, 680, 681, 682, 683, 684, 920,
];

/// G codes (×10) that cancel a frame change (G50 scaling, G50.1 mirror, G69
/// rotation, G92.1–G92.3 offsets): no-ops in a program header, but after a
/// frame change every axis is unknown again.
const CANCEL_G: &[i64] = &[500, 501, 690, 921, 922, 923];

/// Of [`SPECIAL_G`], those whose other words are arguments, not state.
const ARGUMENT_G: &[i64] = &[100, 650, 660, 661];

/// The words of one block, gathered before they are interpreted.
#[derive(Default)]
struct Words {
    /// G codes ×10 with their value and column.
    g: Vec<(i64, f64, u32)>,
    /// The S word and its column: the spindle speed, or on Sinumerik in a
    /// G4 block the dwell in spindle revolutions.
    s: Option<(f64, u32)>,
    xyz: [Option<f64>; 3],
    /// Columns of the Z, R and Q words (0: not in the block), where a
    /// canned cycle's depth and peck findings point.
    z_col: u32,
    r_col: u32,
    q_col: u32,
    ijk: [Option<f64>; 3],
    vec3: [Option<f64>; 3],
    rot: [Option<f64>; 3],
    cr: Option<f64>,
    r: Option<f64>,
    q: Option<f64>,
    p: Option<f64>,
    h: Option<f64>,
    d: Option<f64>,
    l: Option<f64>,
    u: Option<f64>,
    /// The F word with its column: read after the block's G codes (its
    /// unit depends on G93/G94/G95; in a Sinumerik G4 block it is the dwell).
    f: Option<(f64, u32)>,
    m: Vec<f64>,
    /// Words nobody models, as written.
    keep: Vec<String>,
    keep_modal: bool,
    /// A kept word acts on the machine (not only a variable assignment).
    keep_machine: bool,
    /// Sinumerik `ADIS=` and `CTOL=` (rounding distance, contour
    /// tolerance) with their text, for a G641/G642 of the same block.
    adis: Option<(f64, String)>,
    ctol: Option<(f64, String)>,
}

impl GcodeReader {
    pub fn new(dialect: Dialect, opts: ReadOptions) -> GcodeReader {
        let unit = opts.units.map(|u| (u, UnitsOrigin::Override));
        GcodeReader {
            opts,
            dialect,
            program: Program::new(dialect),
            ops: Vec::new(),
            op: Operation::default(),
            diags: Diags::default(),
            vars: BTreeMap::new(),
            line_no: 0,
            saw_content: false,
            ended: None,
            returned: false,
            last_block: 0,
            framed: false,
            scale: unit.map(|(u, _)| u.mm()).unwrap_or(1.0),
            unit,
            motion: Motion::Rapid,
            plane: Plane::Xy,
            absolute: true,
            feed_mode: FeedMode::PerMinute,
            feed: 0.0,
            feed_seen: false,
            feed_missing_reported: false,
            spindle: 0.0,
            spindle_dir: SpindleDir::Off,
            pos: UNKNOWN,
            rotary: [None; 3],
            vector: None,
            offset: None,
            length: None,
            frame_changed: false,
            blind_cycle: false,
            tcp: false,
            tcp_vectors: false,
            selected_tool: None,
            pending_select: None,
            cycle: None,
            return_initial: true,
            arc_centre_absolute: false,
            blocks: 0,
            motion_blocks: 0,
        }
    }

    fn sinumerik(&self) -> bool {
        self.dialect == Dialect::Sinumerik
    }

    fn set_unit(&mut self, u: LengthUnit, ln: u32) {
        match self.unit {
            Some((_, UnitsOrigin::Override)) => {}
            Some((have, _)) if have != u && self.op.moves.len() + self.ops.len() > 0 => {
                self.diags.warn(
                    Code::UnitsChange,
                    ln,
                    1,
                    format!("unit changes to {u:?} in mid-program"),
                );
                self.unit = Some((u, UnitsOrigin::Declared));
                self.scale = u.mm();
            }
            _ => {
                self.unit = Some((u, UnitsOrigin::Declared));
                self.scale = u.mm();
            }
        }
    }

    fn value(&self, text: &str, ln: u32, col: u32) -> Result<f64, ParseError> {
        expr::eval_within(text, &self.vars, self.opts.limits.expression_depth)
            .map_err(|e| ParseError::new(ln, col, format!("`{text}`: {e}")))
    }

    /// Feeds one physical line.
    pub fn line(&mut self, raw: &str) -> Result<(), ParseError> {
        self.line_no += 1;
        let ln = self.line_no;
        let raw = raw.strip_suffix('\r').unwrap_or(raw);
        if raw.trim().is_empty() {
            return Ok(());
        }
        let t = raw.trim_start();
        // The tape's marks: the `%` before the program starts it, the one
        // after it ends it.
        if t.trim_end() == "%" {
            if self.blocks > 0 {
                self.ended.get_or_insert(ln);
            }
            self.framed = true;
            return Ok(());
        }
        if let Some(end) = self.ended {
            return self.after_end(raw, ln, end);
        }
        // Fanuc program number line `O0001` or Haas' `O ENTER ...` prompt.
        if (t.starts_with('O') || t.starts_with('o'))
            && t.as_bytes()
                .get(1)
                .map(|c| c.is_ascii_digit() || *c == b' ')
                .unwrap_or(true)
            && self.op.moves.is_empty()
            && self.ops.is_empty()
        {
            let name = t[1..].trim();
            self.framed = true;
            if self.program.name.is_none() && !name.is_empty() {
                self.program.name = Some(name.to_string());
            }
            self.saw_content = true;
            return Ok(());
        }
        let lexed = lex(raw, ln)?;
        self.saw_content = true;
        if let Some((col, w)) = &lexed.exponent {
            let (word, exp) = w.split_at(w.find(['e', 'E']).unwrap_or(w.len()));
            self.diags.warn(
                Code::UnknownWord,
                ln,
                *col,
                format!(
                    "`{w}` reads as `{word}` and a word `{exp}`: G-code numbers have no exponent (write the number out if {} was meant)",
                    &w[1..]
                ),
            );
        }
        for c in lexed.comments {
            if !c.is_empty() {
                self.op.push_event(ln, EventKind::Comment(c));
            }
        }
        if lexed.toks.is_empty() {
            return Ok(());
        }
        self.blocks += 1;
        self.last_block = ln;
        if lexed.block_delete {
            return self.optional_block(&lexed.toks, ln);
        }
        self.block(raw, &lexed.toks, ln)
    }

    /// A line after the program's end (at line `end`): comments are let
    /// be; a block is refused, as a control never runs it and a program or
    /// subprogram after it is not read.
    fn after_end(&mut self, raw: &str, ln: u32, end: u32) -> Result<(), ParseError> {
        // Comments only, perhaps numbered (`N110 (END)`), or a Ctrl-Z; not
        // lexed: one call site keeps `lex` inlined into `line`, some 0.5 %
        // of a read.
        let t = raw.trim_start();
        let t = match t.strip_prefix(['N', 'n']) {
            Some(r) if r.starts_with(|c: char| c.is_ascii_digit()) => {
                r.trim_start_matches(|c: char| c.is_ascii_digit())
            }
            _ => t,
        };
        let mut depth = 0u32;
        let mut words = false;
        for c in t.chars() {
            match c {
                '(' => depth += 1,
                ')' => depth = depth.saturating_sub(1),
                ';' if depth == 0 => break,
                c if depth == 0 && !c.is_whitespace() && c != '%' && c != '\x1a' => {
                    words = true;
                    break;
                }
                _ => {}
            }
        }
        if !words {
            return Ok(());
        }
        let col = (raw.len() - raw.trim_start().len() + 1) as u32;
        Err(ParseError::new(
            ln,
            col,
            format!("a block after the end of the program (line {end}): a control never runs it, and a second program or a subprogram in the same file (M98, Haas M97) is not read: split the file, or remove what follows the end"),
        ))
    }

    /// A block-delete block: it may run or not, so it is kept as written and
    /// every axis it names is unknown afterwards. A block whose modal state
    /// would differ between the two cases cannot be read either way.
    fn optional_block(&mut self, toks: &[(Tok, u32)], ln: u32) -> Result<(), ParseError> {
        for (t, col) in toks {
            let modal = match t {
                Tok::Word('G', v) => {
                    // Allowed: what the program is in already, dwells and
                    // machine-coordinate moves.
                    let same = match (v * 10.0).round() as i64 {
                        0 => self.motion == Motion::Rapid,
                        10 => self.motion == Motion::Linear,
                        20 => self.motion == Motion::Cw,
                        30 => self.motion == Motion::Ccw,
                        900 => self.absolute,
                        910 => !self.absolute,
                        40 | 530 | 280 | 300 => true,
                        _ => false,
                    };
                    !same
                }
                Tok::Word('M', v) => *v == 6.0,
                Tok::Word('T', _) | Tok::Word('F', _) | Tok::Word('S', _) => true,
                Tok::Assign(..) | Tok::Call(..) => true,
                _ => false,
            };
            if modal {
                return Err(ParseError::new(
                    ln,
                    *col,
                    format!(
                        "`{}` in a block-delete block: the program's state after it depends on the operator's switch",
                        tok_text(t)
                    ),
                ));
            }
        }
        for (t, _) in toks {
            match t {
                Tok::Word(c @ ('X' | 'Y' | 'Z'), _) => self.pos[axis_index(*c)] = f64::NAN,
                Tok::Word(c @ ('A' | 'B' | 'C'), _) => {
                    self.rotary[(*c as u8 - b'A') as usize] = None
                }
                _ => {}
            }
        }
        let text = format!("/{}", block_text(toks));
        self.diags.note(
            Code::BlockDelete,
            ln,
            1,
            "block-delete block kept as written; the axes it names are unknown after it",
        );
        self.passthrough("/", &text, PassClass::Machine, false, true, ln);
        Ok(())
    }

    fn passthrough(
        &mut self,
        word: &str,
        text: &str,
        class: PassClass,
        modal: bool,
        moves: bool,
        ln: u32,
    ) {
        self.op.push_event(
            ln,
            EventKind::Passthrough(Passthrough {
                word: word.to_string(),
                text: text.to_string(),
                class,
                modal,
                moves,
            }),
        );
    }

    /// Blocks that are frame changes or declarations as a whole.
    fn whole_block(&mut self, raw: &str, toks: &[(Tok, u32)], ln: u32) -> Option<()> {
        let Some((Tok::Keyword(k), _)) = toks.iter().find(|(t, _)| matches!(t, Tok::Keyword(_)))
        else {
            return None;
        };
        if matches!(
            k.as_str(),
            "ROT" | "AROT" | "TRANS" | "ATRANS" | "SCALE" | "ASCALE" | "MIRROR" | "AMIRROR"
        ) {
            // Frame-changing blocks carry angles and offsets in their X/Y/Z words.
            let has_values = toks.len() > 1;
            let reframes = has_values && k != "TRANS"
                || toks
                    .iter()
                    .any(|(t, _)| matches!(t, Tok::Word(_, v) if *v != 0.0));
            if reframes {
                self.diags.warn(
                    Code::FrameChange,
                    ln,
                    1,
                    format!("`{k}` changes the programmable frame; it is kept verbatim and every axis is unknown after it"),
                );
            }
            // A frame (or the reset of one after a change) moves every position.
            let moves = reframes || std::mem::take(&mut self.frame_changed);
            if moves {
                self.pos = UNKNOWN;
                self.rotary = [None; 3];
                self.frame_changed = reframes;
            }
            let k = k.clone();
            self.passthrough(&k, &block_text(toks), PassClass::Machine, false, moves, ln);
            return Some(());
        }
        if k == "DEF" {
            for (t, _) in toks {
                if let Tok::Assign(n, v) = t {
                    if let Ok(x) =
                        expr::eval_within(v, &self.vars, self.opts.limits.expression_depth)
                    {
                        self.vars.insert(n.clone(), x);
                    }
                } else if let Tok::Keyword(n) = t {
                    if !matches!(
                        n.as_str(),
                        "DEF" | "REAL" | "INT" | "BOOL" | "STRING" | "CHAR" | "AXIS" | "FRAME"
                    ) {
                        self.vars
                            .entry(n.trim_end_matches(',').to_string())
                            .or_insert(0.0);
                    }
                }
            }
            // As written (`DEF REAL _A, _B=2`), without its block number and comment.
            let code = raw.split(';').next().unwrap_or(raw).trim();
            let code = match code.strip_prefix(['N', 'n']) {
                Some(r) if r.starts_with(|c: char| c.is_ascii_digit()) => r
                    .trim_start_matches(|c: char| c.is_ascii_digit())
                    .trim_start(),
                _ => code,
            };
            self.passthrough("DEF", code, PassClass::Info, false, false, ln);
            return Some(());
        }
        None
    }

    /// Sorts the tokens of a block into words; assignments and calls are
    /// evaluated or kept here.
    fn gather(&mut self, toks: &[(Tok, u32)], ln: u32, w: &mut Words) -> Result<(), ParseError> {
        for (k, (tok, col)) in toks.iter().enumerate() {
            let col = *col;
            // An address letter alone (`G2 X20 I5 F`): no control reads it,
            // and kept verbatim it would be written into the output as is.
            // A letter before a variable or an expression (`F#1`) is kept.
            if let Tok::Keyword(name) = tok {
                let value_follows = toks.get(k + 1).is_some_and(
                    |(t, _)| matches!(t, Tok::Keyword(v) if v.starts_with(['#', '['])),
                );
                if name.len() == 1 && name.as_bytes()[0].is_ascii_alphabetic() && !value_follows {
                    return Err(ParseError::new(
                        ln,
                        col,
                        format!("`{name}` without a number: an address letter needs its value"),
                    ));
                }
            }
            match tok {
                Tok::Word(letter, v) => {
                    let v = *v;
                    match letter {
                        'N' => {}
                        'G' => w.g.push(((v * 10.0).round() as i64, v, col)),
                        'X' | 'Y' | 'Z' => {
                            if *letter == 'Z' {
                                w.z_col = col;
                            }
                            w.xyz[axis_index(*letter)] = Some(v)
                        }
                        'I' | 'J' | 'K' => w.ijk[axis_index(*letter)] = Some(v),
                        'A' | 'B' | 'C' => w.rot[(*letter as u8 - b'A') as usize] = Some(v),
                        'F' => w.f = Some((v, col)),
                        'S' => {
                            if v < 0.0 {
                                return Err(ParseError::new(ln, col, "negative spindle speed"));
                            }
                            w.s = Some((v, col));
                        }
                        'T' => {
                            if v < 0.0 || v.fract() != 0.0 || v > f64::from(u32::MAX) {
                                // `T9.` pre-selects tool 9; `T1.5` is not a tool number.
                                return Err(ParseError::new(
                                    ln,
                                    col,
                                    format!(
                                        "tool number T{} is not a whole number up to {}",
                                        fmt_num(v),
                                        u32::MAX
                                    ),
                                ));
                            }
                            self.selected_tool = Some((Some(v as u32), None, ln));
                            self.select_event(EventKind::ToolSelect(v as u32), ln);
                        }
                        'M' => w.m.push(v),
                        'R' => {
                            // An arc's radius or a cycle's height: refused
                            // here, at its column, rather than when the
                            // reader finishes (at the line's start).
                            let limit = millplan_geom::limits::NC_EXTENT;
                            if v.abs() > limit {
                                return Err(ParseError::new(
                                    ln,
                                    col,
                                    format!("R{v:e} is beyond the plausibility limit of {limit:e} mm (an arc radius or a cycle height): no machine moves there"),
                                ));
                            }
                            w.r = Some(v);
                            w.r_col = col;
                        }
                        'Q' => {
                            w.q = Some(v);
                            w.q_col = col;
                        }
                        'P' => w.p = Some(v),
                        'H' => w.h = Some(v),
                        'D' => w.d = Some(v),
                        'L' => w.l = Some(v),
                        'U' => w.u = Some(v),
                        'V' | 'W' | 'E' | 'O' => {
                            w.keep.push(fmt_word(*letter, v));
                            w.keep_machine = true;
                        }
                        _ => {
                            self.diags.warn(
                                Code::UnknownWord,
                                ln,
                                col,
                                format!("word `{}` kept verbatim", fmt_word(*letter, v)),
                            );
                            w.keep.push(fmt_word(*letter, v));
                            w.keep_machine = true;
                        }
                    }
                }
                Tok::Assign(name, val) => match name.as_str() {
                    "X" | "Y" | "Z" => {
                        w.xyz[axis_index(name.chars().next().unwrap_or('X'))] =
                            Some(self.value(val, ln, col)?)
                    }
                    "I" | "J" | "K" => {
                        w.ijk[axis_index(name.chars().next().unwrap_or('I'))] =
                            Some(self.value(val, ln, col)?)
                    }
                    "A" | "B" | "C" => {
                        w.rot[(name.as_bytes()[0] - b'A') as usize] =
                            Some(self.value(val, ln, col)?);
                    }
                    "A3" | "B3" | "C3" => {
                        w.vec3[(name.as_bytes()[0] - b'A') as usize] =
                            Some(self.value(val, ln, col)?)
                    }
                    "CR" => w.cr = Some(self.value(val, ln, col)?),
                    "F" => w.f = Some((self.value(val, ln, col)?, col)),
                    "S" => {
                        let v = self.value(val, ln, col)?;
                        if v < 0.0 {
                            return Err(ParseError::new(ln, col, "negative spindle speed"));
                        }
                        w.s = Some((v, col));
                    }
                    "ADIS" | "CTOL" if self.sinumerik() => {
                        let v = self.value(val, ln, col)?;
                        let slot = if name == "ADIS" {
                            &mut w.adis
                        } else {
                            &mut w.ctol
                        };
                        *slot = Some((v, format!("{name}={val}")));
                    }
                    "T" => {
                        self.selected_tool =
                            Some((val.trim().parse::<u32>().ok(), Some(val.clone()), ln));
                        let e = match val.trim().parse::<u32>() {
                            Ok(n) => EventKind::ToolSelect(n),
                            Err(_) => EventKind::Passthrough(Passthrough {
                                word: "T".into(),
                                text: format!("T=\"{val}\""),
                                class: PassClass::Machine,
                                modal: false,
                                moves: false,
                            }),
                        };
                        self.select_event(e, ln);
                    }
                    _ => {
                        // Variable assignment (`_camtolerance=.02`, `R1=5`): the
                        // reader substitutes its value where it is used.
                        match expr::eval_within(val, &self.vars, self.opts.limits.expression_depth)
                        {
                            Ok(x) => {
                                self.vars.insert(name.clone(), x);
                            }
                            Err(_) => {
                                self.diags.note(
                                    Code::UnknownWord,
                                    ln,
                                    col,
                                    format!("assignment `{name}={val}` kept verbatim"),
                                );
                                w.keep_machine = true;
                            }
                        }
                        w.keep.push(format!("{name}={val}"));
                    }
                },
                Tok::Call(name, args) => {
                    if name == "CYCLE832" && self.high_speed(args, ln, col) {
                        // Read as a path-control event.
                    } else if name == "MSG" {
                        let text = args.trim().trim_matches('"').to_string();
                        self.op.push_event(ln, EventKind::Comment(text));
                    } else {
                        if !matches!(
                            name.as_str(),
                            "CYCLE800" | "CYCLE832" | "CYCLE832_" | "G642" | "G645"
                        ) {
                            self.diags.warn(
                                Code::UnknownWord,
                                ln,
                                col,
                                format!(
                                    "call `{name}(...)` kept verbatim; its motion is not simulated"
                                ),
                            );
                        }
                        w.keep.push(format!("{name}({args})"));
                        w.keep_machine = true;
                    }
                }
                Tok::Keyword(k) => match k.as_str() {
                    "TRAORI" => self.tcp_event(true, ln),
                    "TRAFOOF" => self.tcp_event(false, ln),
                    "SOFT" | "BRISK" if self.sinumerik() => self
                        .op
                        .push_event(ln, EventKind::PathControl(PathControl::Soft(k == "SOFT"))),
                    // A Sinumerik subprogram's end (kept as written).
                    "RET" | "M17" => {
                        self.returned = true;
                        w.keep.push(k.clone());
                        w.keep_machine = true;
                    }
                    _ => {
                        if !KNOWN_KEYWORDS.contains(&k.as_str()) {
                            self.diags.warn(
                                Code::UnknownWord,
                                ln,
                                col,
                                format!("`{k}` kept verbatim"),
                            );
                        }
                        w.keep.push(k.clone());
                        w.keep_machine = true;
                    }
                },
            }
        }
        Ok(())
    }

    /// The path-control mode a G code (×10) of this dialect sets, given the
    /// block's words: exact stop, blending (with its tolerance), a
    /// look-ahead function; `None` when it is no such code here.
    fn path_code(&self, code: i64, w: &Words) -> Option<PathControl> {
        let d = self.dialect;
        let sin = self.sinumerik();
        let switch = |v: Option<f64>| match v {
            Some(x) if x == 0.0 || x == 1.0 => Some(x == 1.0),
            _ => None,
        };
        Some(match code {
            610 | 611 if d == Dialect::LinuxCnc => PathControl::ExactStop,
            610 if d == Dialect::Fanuc => PathControl::ExactStop,
            600 if sin => PathControl::ExactStop,
            90 if sin || d == Dialect::Fanuc => PathControl::StopOnce,
            640 if d == Dialect::LinuxCnc => PathControl::Blend {
                tolerance: w.p.filter(|p| *p > 0.0).map(|p| p * self.scale),
            },
            640 => PathControl::Blend { tolerance: None },
            6410 if sin => PathControl::Blend {
                tolerance: w.adis.as_ref().map(|a| a.0 * self.scale),
            },
            6420 if sin => PathControl::Blend {
                tolerance: w.ctol.as_ref().map(|a| a.0 * self.scale),
            },
            51 if d == Dialect::Fanuc => PathControl::Smoothing {
                kind: Smoothing::AiContour,
                on: switch(w.q)?,
            },
            80 if d == Dialect::Fanuc => PathControl::Smoothing {
                kind: Smoothing::LookAhead,
                on: switch(w.p)?,
            },
            _ => return None,
        })
    }

    /// Takes the words [`Self::path_code`] read for `code` out of the block.
    fn path_take(&mut self, code: i64, w: &mut Words, ln: u32, col: u32) {
        match code {
            640 if self.dialect == Dialect::LinuxCnc => {
                w.p = None;
                if w.q.take().is_some() {
                    self.diags.note(
                        Code::UnknownWord,
                        ln,
                        col,
                        "G64 Q (the naive-CAM tolerance) is not kept: it follows P when the program is written",
                    );
                }
            }
            6410 => w.adis = None,
            6420 => w.ctol = None,
            51 => w.q = None,
            80 => w.p = None,
            _ => {}
        }
    }

    /// Sinumerik `CYCLE832(tolerance, mode, …)`: the high-speed settings on
    /// (mode not 0, `_OFF`) with their contour tolerance, or off. False when
    /// its tolerance is no number the reader knows (kept verbatim then).
    fn high_speed(&mut self, args: &str, ln: u32, col: u32) -> bool {
        let mut a = args.split(',').map(str::trim);
        let Some(Ok(tol)) = a.next().map(|t| self.value(t, ln, col)) else {
            return false;
        };
        let on = match a.next() {
            Some("_OFF") => false,
            Some(m) => !self.value(m, ln, col).is_ok_and(|v| v == 0.0),
            None => tol > 0.0,
        };
        let tolerance = if on { tol.max(0.0) * self.scale } else { 0.0 };
        self.op.push_event(
            ln,
            EventKind::PathControl(PathControl::Smoothing {
                kind: Smoothing::HighSpeed { tolerance },
                on,
            }),
        );
        true
    }

    fn dwell_p(&self, p: f64) -> f64 {
        dwell_p(self.dialect, p)
    }

    fn feed_word(&mut self, v: f64, ln: u32, col: u32) -> Result<(), ParseError> {
        if !(v > 0.0) {
            return Err(ParseError::new(
                ln,
                col,
                format!("feed F{} is not positive", fmt_num(v)),
            ));
        }
        self.feed = match self.feed_mode {
            // The IR's inverse time is per minute; a block time in seconds
            // is 60 / F of it.
            FeedMode::InverseTime if self.opts.g93_seconds => 60.0 / v,
            FeedMode::InverseTime => v,
            _ => v * self.scale,
        };
        self.feed_seen = true;
        Ok(())
    }

    /// A tool selection; an M6 before the next move takes it in.
    fn select_event(&mut self, e: EventKind, ln: u32) {
        self.op.push_event(ln, e);
        self.pending_select = Some((self.op.events.len() - 1, self.op.moves.len()));
    }

    fn tcp_event(&mut self, on: bool, ln: u32) {
        let vector_tilted = self.vector.is_some_and(|v| v.x != 0.0 || v.y != 0.0);
        if self.tcp != on && (tilted(&self.rotary) || vector_tilted) {
            // Tip or pivot: with a rotary axis turned, X, Y and Z name
            // another point; the program must command them.
            self.pos = UNKNOWN;
        }
        self.tcp = on;
        self.op.push_event(ln, EventKind::Tcp(on));
    }

    /// A tool-length event. After a change of length the program Z of the
    /// tool is another (LinuxCNC leaves the tool standing; some Fanuc-style
    /// controls move Z by the offset; Sinumerik applies it with Z's next
    /// move): Z is unknown until the program commands it, as after a change
    /// of work offset.
    fn length_event(&mut self, t: ToolLength, ln: u32) {
        if self.length != Some(t) {
            self.length = Some(t);
            self.pos.z = f64::NAN;
        }
        self.op.push_event(ln, EventKind::ToolLength(t));
    }

    fn block(&mut self, raw: &str, toks: &[(Tok, u32)], ln: u32) -> Result<(), ParseError> {
        if self.whole_block(raw, toks, ln).is_some() {
            return Ok(());
        }
        if let Some(code) = toks.iter().find_map(|(t, _)| match t {
            Tok::Word('G', v) => {
                let c = (v * 10.0).round() as i64;
                SPECIAL_G.contains(&c).then_some(c)
            }
            _ => None,
        }) {
            return self.kept_block(toks, ln, Some(code));
        }
        // `X#100`, `Z[#5-2.]`: an axis given by a macro variable, whose value
        // is known only when the control runs.
        if toks.windows(2).any(|p| {
            matches!(&p[0].0, Tok::Keyword(k) if k.len() == 1 && "XYZABCIJKUVWR".contains(k.as_str()))
                && matches!(&p[1].0, Tok::Keyword(v) if v.starts_with('#'))
        }) {
            return self.kept_block(toks, ln, None);
        }
        if self.blind_cycle_block(toks, ln)? {
            return Ok(());
        }
        let ev_start = self.op.events.len();
        let mut w = Words::default();
        self.gather(toks, ln, &mut w)?;
        let mut motion_word = false;
        let mut new_cycle: Option<String> = None;
        let mut dwell = false;
        // SUPA: this block in machine coordinates.
        let mut machine: Option<u32> = toks
            .iter()
            .find(|(t, _)| matches!(t, Tok::Keyword(k) if k == "SUPA"))
            .map(|(_, c)| *c);
        let mut cutcom = None;
        let mut tlc: Option<(i64, u32)> = None;
        // A length change the reader does not model (G43.1, G43.2, an H
        // without G43): kept verbatim, and Z unknown after it.
        let mut length_kept = false;
        let mut offset: Option<WorkOffset> = None;
        let mut path: Vec<PathControl> = Vec::new();
        for &(code, v, col) in &w.g.clone() {
            match code {
                0 => {
                    self.motion = Motion::Rapid;
                    motion_word = true;
                }
                10 => {
                    self.motion = Motion::Linear;
                    motion_word = true;
                }
                20 => {
                    self.motion = Motion::Cw;
                    motion_word = true;
                }
                30 => {
                    self.motion = Motion::Ccw;
                    motion_word = true;
                }
                40 => dwell = true,
                170 => self.plane = Plane::Xy,
                180 => self.plane = Plane::Zx,
                190 => self.plane = Plane::Yz,
                200 | 700 | 7000 => self.set_unit(LengthUnit::Inch, ln),
                210 | 710 | 7100 => self.set_unit(LengthUnit::Mm, ln),
                900 => self.absolute = true,
                910 => self.absolute = false,
                930 => self.feed_mode = FeedMode::InverseTime,
                940 => self.feed_mode = FeedMode::PerMinute,
                950 => self.feed_mode = FeedMode::PerRev,
                400 => cutcom = Some(CutCom::Off),
                410 => cutcom = Some(CutCom::Left),
                420 => cutcom = Some(CutCom::Right),
                430 | 434 | 435 | 490 => tlc = Some((code, col)),
                431 | 432 if w.xyz.iter().any(Option::is_some) => {
                    return Err(ParseError::new(
                        ln,
                        col,
                        format!("G{} sets a tool-length offset from its axis words, which are not a position: not read (write the offset into the tool table)", fmt_num(v)),
                    ));
                }
                440 => {
                    return Err(ParseError::new(
                        ln,
                        col,
                        "G44 (tool length subtracted) is not read: under it a Z word names the tool tip only if the tool table holds negative lengths, which the program does not say",
                    ));
                }
                431 | 432 => {
                    length_kept = true;
                    w.keep.push(fmt_word('G', v));
                    w.keep_modal = true;
                    w.keep_machine = true;
                }
                800 => {
                    self.cycle = None;
                    if self.motion == Motion::Cycle {
                        self.motion = Motion::Rapid;
                    }
                }
                730 | 740 | 760 | 810 | 820 | 830 | 840 | 850 | 860 | 870 | 880 | 890 => {
                    new_cycle = Some(format!("G{}", code / 10));
                    motion_word = true;
                }
                901 => self.arc_centre_absolute = true,
                911 => self.arc_centre_absolute = false,
                980 => self.return_initial = true,
                990 => self.return_initial = false,
                530 | 280 | 300 => machine = Some(col),
                c if self.path_code(c, &w).is_some() => {
                    if let Some(pc) = self.path_code(c, &w) {
                        path.push(pc);
                    }
                    self.path_take(c, &mut w, ln, col);
                }
                540..=590 if code % 10 == 0 && !(self.sinumerik() && code > 570) => {
                    offset = Some(WorkOffset((code / 10 - 53) as u16))
                }
                541 if w.p.is_some_and(|p| p >= 1.0 && p.fract() == 0.0) => {
                    offset = Some(WorkOffset(6 + w.p.take().unwrap_or(1.0) as u16));
                }
                5000 if self.sinumerik() => offset = Some(WorkOffset(0)),
                5050..=5990 if self.sinumerik() && code % 10 == 0 => {
                    offset = Some(WorkOffset((code / 10 - 500) as u16))
                }
                591..=593 if self.dialect == Dialect::LinuxCnc => {
                    offset = Some(WorkOffset((code - 584) as u16))
                }
                c if CANCEL_G.contains(&c) => {
                    if std::mem::take(&mut self.frame_changed) {
                        self.pos = UNKNOWN;
                        self.rotary = [None; 3];
                    }
                    w.keep.push(fmt_word('G', v));
                    w.keep_machine = true;
                }
                _ => {
                    // Modal codes every control has (offsets, path modes, planes
                    // for TCP); kept verbatim without a note.
                    const KNOWN: &[i64] = &[
                        50, 51, 90, 150, 160, 531, 541, 610, 611, 640, 641, 642, 680, 682, 690,
                        600, 6010, 6020, 6420, 6450, 1530, 5000, 1000, 580, 590,
                    ];
                    if !(KNOWN.contains(&code) || (5050..=5990).contains(&code)) {
                        self.diags.note(
                            Code::UnknownWord,
                            ln,
                            col,
                            format!("G{} kept verbatim", fmt_num(v)),
                        );
                    }
                    w.keep.push(fmt_word('G', v));
                    w.keep_modal |= is_modal_g(code);
                    w.keep_machine = true;
                }
            }
        }
        // Sinumerik `G4 S10` dwells ten revolutions of the spindle, which
        // keeps its speed; elsewhere S is the speed.
        let mut dwell_s = None;
        if let Some((v, col)) = w.s.take() {
            if dwell && self.sinumerik() {
                if !(self.spindle > 0.0) || self.spindle_dir == SpindleDir::Off {
                    return Err(ParseError::new(
                        ln,
                        col,
                        "a dwell in spindle revolutions (G4 S) with the spindle stopped or its speed not set",
                    ));
                }
                dwell_s = Some(v * 60.0 / self.spindle);
            } else {
                self.spindle = v;
            }
        }
        // F after the block's feed mode; Sinumerik `G4 F1.5` is a dwell of
        // 1.5 s for that block, not a feed.
        let mut dwell_f = None;
        if let Some((v, col)) = w.f.take() {
            if dwell && self.sinumerik() {
                dwell_f = Some(v);
            } else {
                self.feed_word(v, ln, col)?;
            }
        }
        if let Some(m) = machine {
            return self.machine_block(toks, &w, ln, m);
        }
        // Tool length: G43 Hn, G43.4/G43.5 Hn (with TCP), G49; Sinumerik D.
        if let Some((code, col)) = tlc {
            let register = match w.h.take() {
                Some(h) if h >= 0.0 && h.fract() == 0.0 && h <= f64::from(u32::MAX) => {
                    Some(h as u32)
                }
                Some(h) => {
                    return Err(ParseError::new(
                        ln,
                        col,
                        format!("H{} is not a register number", fmt_num(h)),
                    ))
                }
                None => None,
            };
            match code {
                490 => {
                    if self.tcp {
                        self.tcp_event(false, ln);
                    }
                    self.length_event(ToolLength::Off, ln);
                    self.tcp_vectors = false;
                }
                _ => {
                    if code != 430 && !self.tcp {
                        self.tcp_event(true, ln);
                    }
                    if code == 430 && self.tcp {
                        self.tcp_event(false, ln);
                    }
                    self.tcp_vectors = code == 435;
                    self.length_event(ToolLength::On { register }, ln);
                }
            }
        }
        let d_register =
            |d: f64| (d >= 0.0 && d.fract() == 0.0 && d <= f64::from(u32::MAX)).then_some(d as u32);
        if self.sinumerik() {
            if let Some(d) = w.d.take() {
                let t = match d_register(d) {
                    Some(0) => ToolLength::Off,
                    Some(n) => ToolLength::On { register: Some(n) },
                    None => {
                        return Err(ParseError::new(
                            ln,
                            1,
                            format!("D{} is not a register", fmt_num(d)),
                        ))
                    }
                };
                self.length_event(t, ln);
            }
        }
        if let Some(side) = cutcom {
            let register = match side {
                CutCom::Off => None,
                _ => w.d.take().and_then(d_register),
            };
            self.op.push_event(ln, EventKind::CutCom { side, register });
        }
        for pc in path {
            self.op.push_event(ln, EventKind::PathControl(pc));
        }
        for (v, text) in [w.adis.take(), w.ctol.take()].into_iter().flatten() {
            // Set for a later block: kept as written.
            let _ = v;
            w.keep.push(text);
        }
        if let Some(o) = offset {
            self.op.push_event(ln, EventKind::WorkOffset(o));
            if self.offset != Some(o) {
                // Positions in the new frame: the program must command them.
                self.offset = Some(o);
                self.pos = UNKNOWN;
                self.rotary = [None; 3];
            }
        }
        let mut tool_change = false;
        for &v in &w.m {
            // M99 (kept as written) returns from a subprogram.
            self.returned |= v == 99.0;
            let e = match (v as i64, v.fract() == 0.0) {
                (3, true) => {
                    self.spindle_dir = SpindleDir::Cw;
                    Some(EventKind::Spindle(SpindleDir::Cw))
                }
                (4, true) => {
                    self.spindle_dir = SpindleDir::Ccw;
                    Some(EventKind::Spindle(SpindleDir::Ccw))
                }
                (5, true) => {
                    self.spindle_dir = SpindleDir::Off;
                    Some(EventKind::Spindle(SpindleDir::Off))
                }
                (6, true) => {
                    tool_change = true;
                    None
                }
                (7, true) => Some(EventKind::Coolant(Coolant::Mist)),
                (8, true) => Some(EventKind::Coolant(Coolant::Flood)),
                (9, true) => Some(EventKind::Coolant(Coolant::Off)),
                (0, true) => Some(EventKind::Stop { optional: false }),
                (1, true) => Some(EventKind::Stop { optional: true }),
                // Program ends: the writer ends its own program.
                (2, true) | (30, true) => {
                    self.ended.get_or_insert(ln);
                    None
                }
                (17, true) => {
                    self.returned = true;
                    None
                }
                _ => {
                    w.keep.push(fmt_word('M', v));
                    w.keep_machine = true;
                    None
                }
            };
            if let Some(e) = e {
                self.op.push_event(ln, e);
            }
        }
        if tool_change {
            self.tool_change(ln, ev_start);
        }
        if dwell {
            // Fanuc P is whole milliseconds (a P with decimals, as Haas
            // writes it, seconds), LinuxCNC P seconds; X/U seconds; Sinumerik F
            // seconds.
            let secs = dwell_f
                .or(dwell_s)
                .or(w.p.take().map(|p| self.dwell_p(p)))
                .or(w.xyz[0].take())
                .or(w.u.take())
                .unwrap_or(0.0);
            self.op.push_event(ln, EventKind::Dwell(secs));
        }
        if let Some(name) = new_cycle {
            // The initial level is where the series of cycles began: a
            // G98 G83 after a G99 G82 (no G80 between) returns to it, not
            // to the R the tool stands at (Fanuc, LinuxCNC's `old_z`).
            let initial_z = match (&self.cycle, self.motion) {
                (Some(cs), Motion::Cycle) => cs.initial_z,
                _ => self.pos.z,
            };
            self.motion = Motion::Cycle;
            self.cycle = Some(CycleState {
                name,
                r: f64::NAN,
                z: f64::NAN,
                q: None,
                p: None,
                initial_z,
                return_initial: self.return_initial,
                index: None,
            });
        }
        let in_cycle = self.motion == Motion::Cycle && !dwell;
        let arc = matches!(self.motion, Motion::Cw | Motion::Ccw) && !dwell;
        if in_cycle {
            if let Some(cs) = &mut self.cycle {
                let s = self.scale;
                // G98/G99 alone switch the level the next holes return to.
                if cs.return_initial != self.return_initial {
                    cs.return_initial = self.return_initial;
                    cs.index = None;
                }
                if let Some(r) = w.r.take() {
                    cs.r = r * s;
                    cs.index = None;
                }
                if let Some(z) = w.xyz[2] {
                    cs.z = z * s;
                    cs.index = None;
                }
                if let Some(qv) = w.q.take() {
                    cs.q = Some(qv * s);
                    cs.index = None;
                }
                if let Some(pv) = w.p.take() {
                    cs.p = Some(dwell_p(self.dialect, pv));
                    cs.index = None;
                }
            }
            if w.ijk[2].is_some() || w.l.is_some() {
                return Err(ParseError::new(
                    ln,
                    1,
                    "canned-cycle repeat counts (K, L) are not supported",
                ));
            }
        }
        // An H left over changes the length register in use.
        length_kept |= w.h.is_some();
        // Whatever no model took is kept verbatim.
        for (letter, v) in [
            ('R', w.r),
            ('Q', w.q),
            ('P', w.p),
            ('H', w.h),
            ('D', w.d),
            ('L', w.l),
            ('U', w.u),
        ] {
            if let Some(v) = v {
                if !(letter == 'R' && arc) {
                    w.keep.push(fmt_word(letter, v));
                    w.keep_machine = true;
                }
            }
        }
        if !w.keep.is_empty() {
            let text = w.keep.join(" ");
            let word = w.keep[0].clone();
            let modal = w.keep_modal;
            let class = if w.keep_machine {
                PassClass::Machine
            } else {
                PassClass::Info
            };
            self.passthrough(&word, &text, class, modal, length_kept, ln);
        }
        if length_kept {
            self.diags.warn(
                Code::UnknownPosition,
                ln,
                1,
                "a tool-length change the reader does not model (G43.1, G43.2, or an H without G43): kept verbatim, and Z is unknown after it until the program commands it",
            );
            self.length = None;
            self.pos.z = f64::NAN;
        }
        if dwell {
            return Ok(());
        }
        let has_xyz = w.xyz.iter().any(Option::is_some);
        if in_cycle {
            if !has_xyz && !motion_word {
                return Ok(());
            }
            // A depth error points at this block's Z, else its R; a peck
            // finding at its Q, else there.
            let depth = [w.z_col, w.r_col].into_iter().find(|c| *c > 0).unwrap_or(1);
            let peck = if w.q_col > 0 { w.q_col } else { depth };
            return self.cycle_point(w.xyz, (depth, peck), ln);
        }
        let has_rot = w.rot.iter().any(Option::is_some);
        let has_vec = w.vec3.iter().any(Option::is_some);
        if !(has_xyz || has_rot || has_vec) {
            if motion_word && (w.ijk.iter().any(Option::is_some) || w.cr.is_some() || w.r.is_some())
            {
                return Err(ParseError::new(ln, 1, "arc without an end point"));
            }
            return Ok(());
        }
        self.motion_words(w, ln)
    }

    /// A canned cycle that returns to its initial level (G98) from a height the
    /// program has not set: its blocks up to the cycle's end are kept verbatim
    /// and not simulated. Returns whether `toks` was such a block.
    fn blind_cycle_block(&mut self, toks: &[(Tok, u32)], ln: u32) -> Result<bool, ParseError> {
        let codes: Vec<i64> = toks
            .iter()
            .filter_map(|(t, _)| match t {
                Tok::Word('G', v) => Some((v * 10.0).round() as i64),
                _ => None,
            })
            .collect();
        let starts = codes.iter().any(|c| {
            matches!(
                c,
                730 | 740 | 760 | 810 | 820 | 830 | 840 | 850 | 860 | 870 | 880 | 890
            )
        });
        let ends = codes.iter().any(|c| matches!(c, 0 | 10 | 20 | 30 | 800));
        let initial = if codes.contains(&980) {
            true
        } else if codes.contains(&990) {
            false
        } else {
            self.return_initial
        };
        let hole = toks.iter().any(|(t, _)| {
            matches!(
                t,
                Tok::Word('X' | 'Y' | 'Z' | 'R' | 'Q' | 'P' | 'A' | 'B' | 'C', _)
            )
        });
        let blind = if starts {
            // A length change on the block puts Z at another number first.
            let reframed = length_code(toks).is_some_and(|t| self.length != Some(t));
            initial && (self.pos.z.is_nan() || reframed)
        } else {
            self.blind_cycle && !ends && hole
        };
        if !blind {
            if ends && std::mem::take(&mut self.blind_cycle) {
                // The control's cycle ends here: say so, as the reader has
                // no cycle of its own that a writer would end.
                self.passthrough("G80", "G80", PassClass::Machine, true, false, ln);
            }
            return Ok(false);
        }
        self.return_initial = initial;
        if starts {
            self.blind_cycle = true;
            self.cycle = None;
            self.motion = Motion::Rapid;
            self.diags.warn(
                Code::UnknownPosition,
                ln,
                1,
                "canned cycle returning (G98) to an initial height the program has not set: its blocks are kept verbatim and not simulated",
            );
        }
        for (t, col) in toks {
            match t {
                Tok::Word('F', v) => self.feed_word(*v, ln, *col)?,
                Tok::Word(c @ ('X' | 'Y'), _) => self.pos[axis_index(*c)] = f64::NAN,
                _ => {}
            }
        }
        let text = block_text(toks);
        self.passthrough("G98", &text, PassClass::Machine, true, true, ln);
        Ok(true)
    }

    /// A block kept whole and not simulated: a special G code's (`code`) or one
    /// with a macro-variable axis word (`None`). Its modal words still set the
    /// reader's state; the axes it may move or reframe are unknown after it.
    fn kept_block(
        &mut self,
        toks: &[(Tok, u32)],
        ln: u32,
        code: Option<i64>,
    ) -> Result<(), ParseError> {
        let arguments = code.is_some_and(|c| ARGUMENT_G.contains(&c));
        let mut modal = false;
        if !arguments {
            for (t, col) in toks {
                match t {
                    Tok::Word('G', v) => {
                        let c = (v * 10.0).round() as i64;
                        modal |= is_modal_g(c);
                        match c {
                            0 => self.motion = Motion::Rapid,
                            10 => self.motion = Motion::Linear,
                            20 => self.motion = Motion::Cw,
                            30 => self.motion = Motion::Ccw,
                            170 => self.plane = Plane::Xy,
                            180 => self.plane = Plane::Zx,
                            190 => self.plane = Plane::Yz,
                            200 | 700 => self.set_unit(LengthUnit::Inch, ln),
                            210 | 710 => self.set_unit(LengthUnit::Mm, ln),
                            900 => self.absolute = true,
                            910 => self.absolute = false,
                            930 => self.feed_mode = FeedMode::InverseTime,
                            940 => self.feed_mode = FeedMode::PerMinute,
                            950 => self.feed_mode = FeedMode::PerRev,
                            800 => {
                                self.cycle = None;
                                if self.motion == Motion::Cycle {
                                    self.motion = Motion::Rapid;
                                }
                            }
                            _ => {}
                        }
                    }
                    Tok::Word('F', v) => self.feed_word(*v, ln, *col)?,
                    _ => {}
                }
            }
        }
        let probe = code.is_some_and(|c| (310..=314).contains(&c));
        let (what, diag) = match code {
            None => (
                "an axis word given by a macro variable",
                Code::UnknownPosition,
            ),
            Some(c) if probe || c == 650 || c == 660 || c == 661 => {
                ("a move the reader does not simulate", Code::UnknownPosition)
            }
            Some(_) => ("a frame or offset change", Code::FrameChange),
        };
        if code.is_none() || probe {
            // Only the axes the block names may move.
            for (t, _) in toks {
                let letter = match t {
                    Tok::Word(c, _) => Some(*c),
                    Tok::Keyword(k) if k.len() == 1 => k.chars().next(),
                    _ => None,
                };
                match letter {
                    Some(c @ ('X' | 'Y' | 'Z')) => self.pos[axis_index(c)] = f64::NAN,
                    Some(c @ ('A' | 'B' | 'C')) => self.rotary[(c as u8 - b'A') as usize] = None,
                    _ => {}
                }
            }
        } else {
            self.pos = UNKNOWN;
            self.rotary = [None; 3];
            self.frame_changed = true;
        }
        let word = match code {
            Some(c) => fmt_word('G', c as f64 / 10.0),
            None => "#".to_string(),
        };
        let text = block_text(toks);
        self.diags.warn(
            diag,
            ln,
            1,
            format!("`{text}`: {what}, kept verbatim; the axes it affects are unknown after it"),
        );
        self.passthrough(&word, &text, PassClass::Machine, modal, true, ln);
        Ok(())
    }

    /// A block in machine coordinates or to a reference point (G28, G30, G53,
    /// SUPA): kept verbatim; the axes it names are unknown afterwards.
    fn machine_block(
        &mut self,
        toks: &[(Tok, u32)],
        w: &Words,
        ln: u32,
        _col: u32,
    ) -> Result<(), ParseError> {
        // A length code kept in the block (`G49 G53 Z0`): the length in
        // force is no longer known.
        if length_code(toks).is_some() {
            self.length = None;
        }
        // Its spindle, coolant and tool words are events of the same block.
        for &v in &w.m {
            let e = match v as i64 {
                3 => Some(EventKind::Spindle(SpindleDir::Cw)),
                4 => Some(EventKind::Spindle(SpindleDir::Ccw)),
                5 => Some(EventKind::Spindle(SpindleDir::Off)),
                8 => Some(EventKind::Coolant(Coolant::Flood)),
                9 => Some(EventKind::Coolant(Coolant::Off)),
                _ => None,
            };
            if let Some(EventKind::Spindle(d)) = e {
                self.spindle_dir = d;
            }
            if let Some(e) = e {
                self.op.push_event(ln, e);
            }
        }
        if self.sinumerik() {
            if let Some(d) = w.d {
                let t = if d == 0.0 {
                    ToolLength::Off
                } else {
                    ToolLength::On {
                        register: Some(d as u32),
                    }
                };
                self.length_event(t, ln);
            }
        }
        let text: Vec<String> = toks
            .iter()
            .filter(|(t, _)| match t {
                Tok::Word(c, v) => {
                    let event = matches!(c, 'N' | 'S' | 'T' | 'F')
                        || *c == 'M' && matches!(*v as i64, 3 | 4 | 5 | 8 | 9)
                        || *c == 'D' && self.sinumerik();
                    !event
                }
                Tok::Assign(n, _) => !matches!(n.as_str(), "S" | "T" | "F"),
                _ => true,
            })
            .map(|(t, _)| tok_text(t))
            .collect();
        for (k, v) in w.xyz.iter().enumerate() {
            if v.is_some() {
                self.pos[k] = f64::NAN;
            }
        }
        for (k, v) in w.rot.iter().enumerate() {
            if v.is_some() {
                self.rotary[k] = None;
            }
        }
        let word = if toks
            .iter()
            .any(|(t, _)| matches!(t, Tok::Keyword(k) if k == "SUPA"))
        {
            "SUPA".to_string()
        } else {
            w.g.iter()
                .find(|g| matches!(g.0, 280 | 300 | 530))
                .map(|g| fmt_word('G', g.1))
                .unwrap_or_default()
        };
        let modal = w.g.iter().any(|g| is_modal_g(g.0));
        self.passthrough(&word, &text.join(" "), PassClass::Machine, modal, true, ln);
        Ok(())
    }

    /// The move of a block with axis words.
    fn motion_words(&mut self, w: Words, ln: u32) -> Result<(), ParseError> {
        // An incremental step from an axis the program has not set cannot be
        // an absolute position: the block is kept as written (with its G91),
        // and its axes stay unknown.
        if !self.absolute {
            let blind = (0..3).any(|k| w.xyz[k].is_some_and(|v| v != 0.0) && self.pos[k].is_nan())
                || (0..3).any(|k| w.rot[k].is_some_and(|v| v != 0.0) && self.rotary[k].is_none());
            if blind {
                return self.blind_increment(&w, ln);
            }
        }
        self.motion_blocks += 1;
        let start = self.pos;
        let mut end = self.pos;
        let mut moved = false;
        for k in 0..3 {
            if let Some(v) = w.xyz[k] {
                let v = v * self.scale;
                if self.absolute {
                    end[k] = v;
                    moved = true;
                } else if !end[k].is_nan() {
                    end[k] += v;
                    moved = true;
                } else {
                    self.zero_increment(["X", "Y", "Z"][k], ln);
                }
            }
        }
        let mut rotary = self.rotary;
        for (k, r) in w.rot.iter().enumerate() {
            if let Some(v) = r {
                let v = v.to_radians();
                if self.absolute {
                    rotary[k] = Some(v);
                    moved = true;
                } else if let Some(old) = rotary[k] {
                    rotary[k] = Some(old + v);
                    moved = true;
                } else {
                    self.zero_increment(["A", "B", "C"][k], ln);
                }
            }
        }
        let mut ijk = w.ijk;
        let mut vec3 = w.vec3;
        if self.tcp_vectors
            && matches!(self.motion, Motion::Rapid | Motion::Linear)
            && ijk.iter().any(Option::is_some)
        {
            vec3 = ijk;
            ijk = [None; 3];
        }
        if vec3.iter().any(Option::is_some) {
            let old = self.vector.unwrap_or(DVec3::Z);
            let v = DVec3::new(
                vec3[0].unwrap_or(old.x),
                vec3[1].unwrap_or(old.y),
                vec3[2].unwrap_or(old.z),
            );
            let v = v
                .try_normalize()
                .ok_or_else(|| ParseError::new(ln, 1, "tool vector has zero length"))?;
            self.vector = Some(v);
            moved = true;
        }
        if !moved {
            // Only zero increments on unknown axes: nothing moves.
            return Ok(());
        }
        self.rotary = rotary;
        let orient = self.current_orient();
        let mut m = Move {
            end,
            feed: self.feed,
            spindle: if self.spindle_dir == SpindleDir::Off {
                0.0
            } else {
                self.spindle
            },
            line: ln,
            orient,
            kind: MoveKind::Linear,
            feed_mode: self.feed_mode,
        };
        match self.motion {
            Motion::Rapid => {
                m.kind = MoveKind::Rapid;
                m.feed = 0.0;
            }
            Motion::Linear => {}
            Motion::Cw | Motion::Ccw => {
                let (Some(s), Some(e)) = (known(start), known(end)) else {
                    return Err(ParseError::new(
                        ln,
                        1,
                        "arc from or to a position the program has not set (an axis is unknown)",
                    ));
                };
                let arc = self.arc(s, e, ijk, w.cr.or(w.r), ln)?;
                m.kind = MoveKind::Arc(self.op.push_arc(arc));
            }
            Motion::Cycle => unreachable!("handled by the caller"),
        }
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

    fn zero_increment(&mut self, axis: &str, ln: u32) {
        self.diags.note(
            Code::ZeroIncrement,
            ln,
            1,
            format!("incremental {axis}0 from an unknown {axis} position: no motion"),
        );
    }

    /// A G91 block that steps an axis whose position is unknown: kept verbatim
    /// with its distance mode; the axes it steps stay unknown.
    fn blind_increment(&mut self, w: &Words, ln: u32) -> Result<(), ParseError> {
        let g = match self.motion {
            Motion::Rapid => "G0",
            Motion::Linear => "G1",
            _ => {
                return Err(ParseError::new(
                    ln,
                    1,
                    "incremental arc from a position the program has not set",
                ))
            }
        };
        let mut text = vec!["G91".to_string(), g.to_string()];
        for (k, v) in w.xyz.iter().enumerate() {
            if let Some(v) = v {
                text.push(fmt_word(['X', 'Y', 'Z'][k], *v));
                self.pos[k] += v * self.scale;
            }
        }
        for (k, v) in w.rot.iter().enumerate() {
            if let Some(v) = v {
                text.push(fmt_word(['A', 'B', 'C'][k], *v));
                self.rotary[k] = self.rotary[k].map(|a| a + v.to_radians());
            }
        }
        if g == "G1" {
            let f = match self.feed_mode {
                FeedMode::InverseTime => self.feed,
                _ => self.feed / self.scale,
            };
            text.push(fmt_word('F', f));
        }
        self.diags.note(
            Code::ZeroIncrement,
            ln,
            1,
            "incremental step from an axis position the program has not set: kept verbatim, the axis stays unknown",
        );
        self.passthrough(g, &text.join(" "), PassClass::Machine, true, true, ln);
        Ok(())
    }

    fn arc(
        &mut self,
        start: DVec3,
        end: DVec3,
        ijk: [Option<f64>; 3],
        r: Option<f64>,
        ln: u32,
    ) -> Result<Arc, ParseError> {
        let n = self.plane.normal();
        let normal = if self.motion == Motion::Ccw { n } else { -n };
        let centre = if ijk.iter().any(Option::is_some) {
            let c = if self.arc_centre_absolute {
                // A coordinate left out is the start's.
                let s = self.scale;
                DVec3::new(
                    ijk[0].map_or(start.x, |v| v * s),
                    ijk[1].map_or(start.y, |v| v * s),
                    ijk[2].map_or(start.z, |v| v * s),
                )
            } else {
                let off = DVec3::new(
                    ijk[0].unwrap_or(0.0),
                    ijk[1].unwrap_or(0.0),
                    ijk[2].unwrap_or(0.0),
                ) * self.scale;
                start + off
            };
            // Keep the centre in the plane of the start point.
            c - n * (c - start).dot(n)
        } else if let Some(r) = r {
            let r = r * self.scale;
            let a = start - n * start.dot(n);
            let b = end - n * start.dot(n) - n * (end - start).dot(n);
            let chord = b - a;
            let half = chord.length() / 2.0;
            if half < 1e-9 {
                return Err(ParseError::new(
                    ln,
                    1,
                    "a radius arc cannot be a full circle; use I/J/K",
                ));
            }
            if half > r.abs() + 1e-6 {
                return Err(ParseError::new(
                    ln,
                    1,
                    format!(
                        "arc radius {:.4} is shorter than half the chord {:.4}",
                        r.abs(),
                        half
                    ),
                ));
            }
            let h = (r * r - half * half).max(0.0).sqrt();
            // Back into the plane of the start point.
            let mid = a + chord * 0.5 + n * start.dot(n);
            let perp = normal.cross(chord).normalize();
            // Positive R: the short way (≤ 180°); negative: the long way.
            if r > 0.0 {
                mid + perp * h
            } else {
                mid - perp * h
            }
        } else {
            return Err(ParseError::new(ln, 1, "arc needs I/J/K or R"));
        };
        let full = (start - end).length() < 1e-9;
        let arc = Arc::from_points(start, end, centre, normal, full)
            .ok_or_else(|| ParseError::new(ln, 1, "arc start lies on its centre"))?;
        let r_end = {
            let d = end - centre;
            (d - n * d.dot(n)).length()
        };
        if (r_end - arc.radius).abs() > crate::verify::ARC_TOL + 1e-4 * arc.radius {
            self.diags.warn(
                Code::ArcRadius,
                ln,
                1,
                format!(
                    "arc end is {:.4} mm from the centre, its start {:.4} mm",
                    r_end, arc.radius
                ),
            );
        }
        Ok(arc)
    }

    /// A hole of the active cycle at `xyz`; `col` is where an error in the
    /// cycle's depth points (the block's Z or R word), `peck_col` a finding
    /// on its peck (its Q word, else `col`).
    fn cycle_point(
        &mut self,
        xyz: [Option<f64>; 3],
        (col, peck_col): (u32, u32),
        ln: u32,
    ) -> Result<(), ParseError> {
        let Some(cs) = &mut self.cycle else {
            return Err(ParseError::new(
                ln,
                1,
                "hole position without an active cycle",
            ));
        };
        if !self.absolute {
            return Err(ParseError::new(
                ln,
                1,
                "canned cycles in incremental mode (G91) are not supported",
            ));
        }
        if cs.r.is_nan() || cs.z.is_nan() {
            return Err(ParseError::new(ln, 1, format!("{} needs R and Z", cs.name)));
        }
        let s = self.scale;
        let x = xyz[0].map(|v| v * s).unwrap_or(self.pos.x);
        let y = xyz[1].map(|v| v * s).unwrap_or(self.pos.y);
        if x.is_nan() || y.is_nan() {
            return Err(ParseError::new(
                ln,
                1,
                "hole position with an X or Y the program has not set",
            ));
        }
        if cs.return_initial && cs.initial_z.is_nan() {
            return Err(ParseError::new(
                ln,
                1,
                format!(
                    "{} returns to its initial Z (G98), which the program has not set",
                    cs.name
                ),
            ));
        }
        if cs.z > cs.r && cs.name != "G87" {
            // LinuxCNC stops on it ("R less than Z in cycle"): a drilling or
            // boring cycle feeds down from R to Z. Back boring (G87) is read
            // either way: it cuts from R toward Z along the tool axis, and
            // an NX post writes it with R above Z for a tool turned upside
            // down (B-180, haas_vf2tr_5axis_inch.ptp).
            return Err(ParseError::new(
                ln,
                col,
                format!(
                    "{} with its hole bottom Z{} above its R plane R{}: the cycle feeds down from R to Z",
                    cs.name,
                    fmt_num(cs.z / self.scale),
                    fmt_num(cs.r / self.scale)
                ),
            ));
        }
        let idx = match cs.index {
            Some(i) => i,
            None => {
                let retract = if cs.return_initial {
                    cs.initial_z - cs.r
                } else {
                    0.0
                };
                let feed = if self.feed_seen {
                    self.feed
                } else {
                    self.opts.default_feed
                };
                if cs.z == cs.r {
                    self.diags.warn(
                        Code::CycleDepth,
                        ln,
                        col,
                        format!(
                            "{} with its hole bottom Z{} at its R plane: a hole of no depth, read as such (a control may stop with an alarm)",
                            cs.name,
                            fmt_num(cs.z / self.scale)
                        ),
                    );
                }
                let pecking = matches!(cs.name.as_str(), "G73" | "G83");
                match cs.q {
                    Some(q) if pecking && q <= 0.0 => self.diags.warn(
                        Code::PeckDepth,
                        ln,
                        peck_col,
                        format!(
                            "{} with peck depth Q{}: read as one stroke to depth (a control may stop with an alarm)",
                            cs.name,
                            fmt_num(q / self.scale)
                        ),
                    ),
                    None if pecking => self.diags.warn(
                        Code::PeckDepth,
                        ln,
                        peck_col,
                        format!("{} without a peck depth Q: read as one stroke to depth", cs.name),
                    ),
                    _ => {}
                }
                let Some(cs) = &mut self.cycle else {
                    return Ok(());
                };
                let cy = Cycle {
                    name: cs.name.clone(),
                    bottom: cs.z - cs.r,
                    clearance: 0.0,
                    retract: retract.max(0.0),
                    feed,
                    peck: cs.q,
                    peck_next: None,
                    dwell: cs.p,
                    line: ln,
                };
                let i = self.op.push_cycle(cy);
                if let Some(cs) = &mut self.cycle {
                    cs.index = Some(i);
                }
                i
            }
        };
        let Some(cs) = &self.cycle else {
            return Ok(());
        };
        let end = DVec3::new(x, y, cs.r);
        let top = if cs.return_initial {
            cs.initial_z
        } else {
            cs.r
        };
        self.motion_blocks += 1;
        let orient = self.current_orient();
        let m = Move {
            end,
            feed: 0.0,
            spindle: if self.spindle_dir == SpindleDir::Off {
                0.0
            } else {
                self.spindle
            },
            line: ln,
            orient,
            kind: MoveKind::Cycle(idx),
            feed_mode: FeedMode::PerMinute,
        };
        self.push_move(m, ln);
        // After the hole the tool stands at the return plane.
        self.pos = DVec3::new(x, y, top);
        Ok(())
    }

    fn push_move(&mut self, mut m: Move, ln: u32) {
        if m.is_cutting() && !self.feed_seen {
            m.feed = self.opts.default_feed;
            m.feed_mode = FeedMode::PerMinute;
            if !self.feed_missing_reported {
                self.feed_missing_reported = true;
                self.diags.warn(
                    Code::FeedMissing,
                    ln,
                    1,
                    format!(
                        "cutting move before any F word: read at {} mm/min, the readers' default (a F word before it gives the feed; `millplan convert --feed` another default)",
                        self.opts.default_feed
                    ),
                );
            }
        }
        if m.is_cutting() && self.op.tool.is_none() {
            let (number, name, tl) = self.selected_tool.clone().unwrap_or((None, None, ln));
            self.op.tool = Some(Tool {
                number,
                name,
                cutter: None,
                line: tl,
            });
            self.diags.warn(
                Code::ToolMissing,
                ln,
                1,
                "cutting move before any tool change (M6): tool unknown",
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
        self.pending_select = None;
    }

    /// An M6 in a block whose first event is `ev_start` of the operation.
    fn tool_change(&mut self, ln: u32, mut ev_start: usize) {
        self.framed = true;
        // A selection right before the change is the tool it takes in.
        if let Some((ev, moves)) = self.pending_select.take() {
            if moves == self.op.moves.len() && ev < self.op.events.len() {
                self.op.events.remove(ev);
                if ev < ev_start {
                    ev_start -= 1;
                }
            }
        }
        let (number, name, tl) = self.selected_tool.clone().unwrap_or((None, None, ln));
        // `G43` without H takes the tool in the spindle: another length.
        self.length = None;
        if !self.op.moves.is_empty() {
            let prev = std::mem::take(&mut self.op);
            self.ops.push(prev);
            self.cycle = None;
        } else if ev_start > 0 && self.op.tool.is_some() {
            // Two changes without a move between: the first tool's events
            // stay with it.
            let rest = self.op.events.split_off(ev_start);
            let prev = std::mem::take(&mut self.op);
            self.ops.push(prev);
            self.op.events = rest;
            self.cycle = None;
        }
        // The change may move every linear axis.
        self.pos = UNKNOWN;
        self.op.start = UNKNOWN;
        self.op.tool = Some(Tool {
            number,
            name: name.clone(),
            cutter: None,
            line: tl,
        });
        if let Some(n) = name {
            self.op.name.get_or_insert(n);
        }
    }

    pub fn finish(mut self) -> Result<Parsed, ParseError> {
        if !self.saw_content {
            return Err(ParseError::new(1, 1, "empty file: no G-code blocks"));
        }
        if self.ended.is_none() && !self.returned && self.last_block > 0 {
            let last = self.last_block;
            self.diags.warn(
                Code::ProgramEnd,
                last,
                1,
                format!("the program has no end (M30 or M2, M17 or M99, or a closing %): a file cut short ends like this; its last block, line {last}, is read as written"),
            );
            // A program that began as one (a tape's %, a program number, a
            // tool change) was cut short; bare blocks are a fragment by
            // nature (warned of only).
            if self.framed {
                self.program.unterminated = Some(last);
            }
        }
        self.ops.push(std::mem::take(&mut self.op));
        self.ops
            .retain(|o| !(o.moves.is_empty() && o.events.is_empty() && o.tool.is_none()));
        let (u, origin) = match self.unit {
            Some(x) => x,
            None => {
                self.diags.warn(Code::UnitsAssumed, 0, 0, "no unit word (G20/G21, G70/G71, G700/G710): millimetres assumed (override with --units)");
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

/// The tool length a block's G43/G43.4/G43.5/G44 (with its H) or G49
/// selects, if it has one.
fn length_code(toks: &[(Tok, u32)]) -> Option<ToolLength> {
    let code = toks.iter().find_map(|(t, _)| match t {
        Tok::Word('G', v) => {
            let c = (v * 10.0).round() as i64;
            matches!(c, 430 | 434 | 435 | 440 | 490).then_some(c)
        }
        _ => None,
    })?;
    if code == 490 {
        return Some(ToolLength::Off);
    }
    let register = toks.iter().find_map(|(t, _)| match t {
        Tok::Word('H', h) if *h >= 0.0 && h.fract() == 0.0 && *h <= f64::from(u32::MAX) => {
            Some(*h as u32)
        }
        _ => None,
    });
    Some(ToolLength::On { register })
}

/// Whether a rotary axis is known to stand away from 0: TCP on or off then
/// changes what X, Y and Z mean.
pub(crate) fn tilted(rotary: &[Option<f64>; 3]) -> bool {
    rotary.iter().any(|r| r.is_some_and(|a| a != 0.0))
}

fn axis_index(c: char) -> usize {
    match c {
        'X' | 'I' => 0,
        'Y' | 'J' => 1,
        _ => 2,
    }
}

pub(crate) fn fmt_num(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        let s = format!("{v:.6}");
        s.trim_end_matches('0').to_string()
    }
}

/// Seconds of a dwell `P` word (G4, G82, G89): LinuxCNC counts seconds,
/// Fanuc whole milliseconds; a P with decimals in a Fanuc-style program is
/// seconds (Haas writes `P.05`).
fn dwell_p(dialect: Dialect, p: f64) -> f64 {
    if dialect == Dialect::LinuxCnc || p.fract() != 0.0 {
        p
    } else {
        p / 1000.0
    }
}

/// A word as a block kept verbatim spells it. Axis words keep a decimal
/// point on whole numbers (`C45.`): on a Fanuc without decimal-point input
/// `C45` is 0.045°. Codes, registers and counts (G, M, H, P, Q…) do not.
fn fmt_word(c: char, v: f64) -> String {
    let n = fmt_num(v);
    if matches!(c, 'X' | 'Y' | 'Z' | 'A' | 'B' | 'C' | 'U' | 'V' | 'W') && !n.contains('.') {
        format!("{c}{n}.")
    } else {
        format!("{c}{n}")
    }
}

fn tok_text(t: &Tok) -> String {
    match t {
        Tok::Word(c, v) => fmt_word(*c, *v),
        Tok::Assign(n, v) => format!("{n}={v}"),
        Tok::Call(n, a) => format!("{n}({a})"),
        Tok::Keyword(k) => k.clone(),
    }
}

fn block_text(toks: &[(Tok, u32)]) -> String {
    let mut s = String::new();
    let mut letter = false;
    for (t, _) in toks.iter().filter(|(t, _)| !matches!(t, Tok::Word('N', _))) {
        let text = tok_text(t);
        // `X#100`: an address letter and the variable that gives its value.
        if !(s.is_empty() || letter && text.starts_with('#')) {
            s.push(' ');
        }
        letter = matches!(t, Tok::Keyword(k) if k.len() == 1);
        s.push_str(&text);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lexes_packed_fanuc_sinumerik_and_comments() {
        let l = lex("G0X0.000Y0.000S15000M3", 1).expect("lex");
        assert_eq!(l.toks.len(), 5);
        let l = lex(
            "N330 G0 X-75. Y34.99 Z=_Z_HOME T=\"PLAN_D50\" CYCLE832(_camtolerance,1,1) ; note",
            1,
        )
        .expect("lex");
        assert_eq!(l.comments, vec!["note".to_string()]);
        assert!(l
            .toks
            .iter()
            .any(|(t, _)| *t == Tok::Assign("Z".into(), "_Z_HOME".into())));
        assert!(l
            .toks
            .iter()
            .any(|(t, _)| *t == Tok::Assign("T".into(), "PLAN_D50".into())));
        assert!(l
            .toks
            .iter()
            .any(|(t, _)| matches!(t, Tok::Call(n, _) if n == "CYCLE832")));
        let l = lex("(#508= (MILL_.25_PROFILE         ))", 1).expect("lex");
        assert_eq!(l.toks.len(), 0);
        assert_eq!(l.comments.len(), 1);
        let l = lex("N10 A3=0.5 B3=0 C3=.866", 1).expect("lex");
        assert_eq!(l.toks[1].0, Tok::Assign("A3".into(), "0.5".into()));
    }

    #[test]
    fn letters_in_numbers_are_located() {
        let e = lex("G1 X1.2.5 Y3", 7).expect_err("bad number");
        assert_eq!((e.line, e.col), (7, 4));
    }
}
