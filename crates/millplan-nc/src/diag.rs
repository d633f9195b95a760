//! Diagnostics (findings that do not stop reading) and located parse errors.

use std::fmt;

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Note,
    Warning,
}

/// The stable code of every finding millplan reports: one variant each, with a
/// one-line explanation (`millplan explain CODE` prints it, `millplan explain`
/// all of them). Codes are spelled in kebab case wherever they are printed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Code {
    UnknownWord,
    UnitsAssumed,
    UnitsChange,
    UnitsConflict,
    FeedMissing,
    ToolMissing,
    ArcRadius,
    ArcPlane,
    RapidCircle,
    ConstantSurfaceSpeed,
    FrameChange,
    UnknownPosition,
    BlockDelete,
    PeckDepth,
    CycleDepth,
    ZeroIncrement,
    LossyWord,
    OpenMesh,
    OffSurface,
    SpindleStopped,
    ProgramEnd,
}

impl Code {
    pub const ALL: [Code; 21] = [
        Code::UnknownWord,
        Code::UnitsAssumed,
        Code::UnitsChange,
        Code::UnitsConflict,
        Code::FeedMissing,
        Code::ToolMissing,
        Code::ArcRadius,
        Code::ArcPlane,
        Code::RapidCircle,
        Code::ConstantSurfaceSpeed,
        Code::FrameChange,
        Code::UnknownPosition,
        Code::BlockDelete,
        Code::PeckDepth,
        Code::CycleDepth,
        Code::ZeroIncrement,
        Code::LossyWord,
        Code::OpenMesh,
        Code::OffSurface,
        Code::SpindleStopped,
        Code::ProgramEnd,
    ];

    /// The code as printed: `unknown-word`.
    pub fn as_str(self) -> &'static str {
        match self {
            Code::UnknownWord => "unknown-word",
            Code::UnitsAssumed => "units-assumed",
            Code::UnitsChange => "units-change",
            Code::UnitsConflict => "units-conflict",
            Code::FeedMissing => "feed-missing",
            Code::ToolMissing => "tool-missing",
            Code::ArcRadius => "arc-radius",
            Code::ArcPlane => "arc-plane",
            Code::RapidCircle => "rapid-circle",
            Code::ConstantSurfaceSpeed => "constant-surface-speed",
            Code::FrameChange => "frame-change",
            Code::UnknownPosition => "unknown-position",
            Code::BlockDelete => "block-delete",
            Code::PeckDepth => "peck-depth",
            Code::CycleDepth => "cycle-depth",
            Code::ZeroIncrement => "zero-increment",
            Code::LossyWord => "lossy-word",
            Code::OpenMesh => "open-mesh",
            Code::OffSurface => "off-surface",
            Code::SpindleStopped => "spindle-stopped",
            Code::ProgramEnd => "program-end",
        }
    }

    /// One line on what the finding means and what to do about it.
    pub fn explain(self) -> &'static str {
        match self {
            Code::UnknownWord => "a word or record the reader does not model; it is kept verbatim and written unchanged into the same dialect, but another dialect refuses it (or, with --lossy, keeps it as a comment)",
            Code::UnitsAssumed => "nothing in the file says mm or inch; millimetres were assumed (give --units when the file is in inches)",
            Code::UnitsChange => "the program switches units in mid-program; later numbers are read in the new unit",
            Code::UnitsConflict => "a feed word or a second unit statement disagrees with the file's unit; the first declared unit is used",
            Code::FeedMissing => "a cutting move comes before any feed; the --feed value (1000 mm/min by default) is used for it",
            Code::ToolMissing => "a cutting move comes before any tool definition or tool change; its tool is unknown",
            Code::ArcRadius => "an arc's start and end lie at different distances from its centre (beyond 0.01 mm + 1e-4 r); the control may reject it",
            Code::ArcPlane => "a Heidenhain C block's plane was not named by its CC block and was inferred from where start and end lie",
            Code::RapidCircle => "RAPID stands before a CIRCLE end point; the move is made as a rapid straight line",
            Code::ConstantSurfaceSpeed => "SPINDL gives a constant surface speed (SFM/SMM); its number is kept as a spindle speed",
            Code::FrameChange => "a block changes the coordinate frame (ROT, TRANS, G52, G92, G68, G51, G10, a work offset); it is kept verbatim, and every axis is unknown after it until the program commands it again",
            Code::UnknownPosition => "a block moves the tool to a place the reader cannot know (a probing move, a macro call, an axis word given by a macro variable); it is kept verbatim, and the axes it may move are unknown after it until the program commands them again",
            Code::PeckDepth => "a pecking cycle has no peck depth, or one of zero or below: it is read as one stroke to depth, and a control may stop with an alarm instead; it is written only as the control's own cycle, as the source gave it (never as lines that drill in one stroke, nor into LinuxCNC, which refuses it)",
            Code::CycleDepth => "a canned cycle's hole bottom lies at its R plane: the hole has no depth and the cycle feeds nowhere; read as written, and a control may stop with an alarm instead",
            Code::BlockDelete => "a block-delete block (`/`) runs or not as the operator's switch says; it is kept as written, and the axes it names are unknown after it until the program commands them again",
            Code::ZeroIncrement => "an incremental (G91) move steps an axis whose position is unknown: a zero step moves nothing; another step is kept verbatim (with its G91) and the axis stays unknown",
            Code::LossyWord => "with --lossy, a word the target dialect cannot express was written as a comment: the output does less than the source",
            Code::OpenMesh => "the part mesh has open or non-manifold edges; checks against it can miss material at holes and seams",
            Code::OffSurface => "tool positions do not touch the part surface within tolerance; the part may not match the program",
            Code::ProgramEnd => "the program has no end of program (M30 or M2, M17 or M99, a closing `%`; END PGM in Heidenhain; FINI in APT): a file cut short in its transfer looks the same. Its last block is read as written: make sure it is the last block the CAM system wrote. A block after the end is never run by a control, and is refused: a second program or subprogram in the same file is not read (split the file)",
            Code::SpindleStopped => "the spindle is started at speed 0 (S0 M03, as some posts write) and the program cuts before it gets a speed: copied as written; a pass that needs the spindle speed (feed, force) refuses such a move at its line",
        }
    }

    pub fn from_name(s: &str) -> Option<Code> {
        Code::ALL.into_iter().find(|c| c.as_str() == s)
    }
}

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl serde::Serialize for Code {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

/// A finding with a stable [`Code`].
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Diagnostic {
    pub severity: Severity,
    pub code: Code,
    /// 1-based line; 0 when the finding is about the whole file.
    pub line: u32,
    /// 1-based column; 0 when not known.
    pub col: u32,
    pub message: String,
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sev = match self.severity {
            Severity::Note => "note",
            Severity::Warning => "warning",
        };
        // A finding about the whole file has no line.
        if self.line > 0 {
            write!(f, "{}:{}: ", self.line, self.col.max(1))?;
        }
        write!(f, "{sev}[{}]: {}", self.code, self.message)
    }
}

impl Diagnostic {
    /// `file:line:col: severity[code]: message`, or `file: …` for the whole file.
    pub fn located(&self, file: &str) -> String {
        if self.line > 0 {
            format!("{file}:{self}")
        } else {
            format!("{file}: {self}")
        }
    }
}

/// Bad input that stops reading, with its position.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{line}:{col}: {message}")]
pub struct ParseError {
    pub line: u32,
    pub col: u32,
    pub message: String,
}

impl ParseError {
    pub fn new(line: u32, col: u32, message: impl Into<String>) -> ParseError {
        ParseError {
            line,
            col: col.max(1),
            message: message.into(),
        }
    }
}

/// A program read from a file, with what the reader noticed on the way.
#[derive(Clone, Debug)]
pub struct Parsed {
    pub program: crate::ir::Program,
    pub diagnostics: Vec<Diagnostic>,
}

/// Collects diagnostics; identical codes beyond `per_code_limit` are only counted,
/// so a file with 20 000 unknown records does not produce 20 000 messages.
#[derive(Debug, Default)]
pub struct Diags {
    pub list: Vec<Diagnostic>,
    counts: Vec<(Code, usize)>,
}

const PER_CODE_LIMIT: usize = 50;

impl Diags {
    pub fn push(
        &mut self,
        severity: Severity,
        code: Code,
        line: u32,
        col: u32,
        message: impl Into<String>,
    ) {
        let n = match self.counts.iter_mut().find(|(c, _)| *c == code) {
            Some((_, n)) => {
                *n += 1;
                *n
            }
            None => {
                self.counts.push((code, 1));
                1
            }
        };
        if n <= PER_CODE_LIMIT {
            self.list.push(Diagnostic {
                severity,
                code,
                line,
                col,
                message: message.into(),
            });
        }
    }

    pub fn warn(&mut self, code: Code, line: u32, col: u32, message: impl Into<String>) {
        self.push(Severity::Warning, code, line, col, message)
    }

    pub fn note(&mut self, code: Code, line: u32, col: u32, message: impl Into<String>) {
        self.push(Severity::Note, code, line, col, message)
    }

    /// The diagnostics, followed by one summary line per code whose count was capped.
    pub fn finish(mut self) -> Vec<Diagnostic> {
        for (code, n) in self.counts {
            if n > PER_CODE_LIMIT {
                self.list.push(Diagnostic {
                    severity: Severity::Note,
                    code,
                    line: 0,
                    col: 0,
                    message: format!(
                        "{} more `{code}` findings not listed ({n} in all)",
                        n - PER_CODE_LIMIT
                    ),
                });
            }
        }
        self.list
    }
}

/// Parses a number the way NC files write them (`.5`, `103.`, `-0`, `+2.7`, `1e-3`).
#[inline]
pub fn parse_num(s: &str) -> Option<f64> {
    let s = s.strip_prefix('+').unwrap_or(s);
    if let Some((v, n)) = plain_decimal(s.as_bytes()) {
        if n == s.len() {
            return Some(v);
        }
    }
    if s.is_empty() {
        return None;
    }
    match fast_float2::parse::<f64, _>(s) {
        Ok(v) if v.is_finite() => Some(v),
        _ => None,
    }
}

/// Powers of ten that a double holds exactly (10^0 ..= 10^15).
const POW10: [f64; 16] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
];

/// The number at the start of `b` up to a comma or the end, when it is
/// written as NC files mostly write them (`-12.345`: an optional minus, at
/// most 15 digits, at most one point), with the bytes it takes; `None` for
/// anything else, which [`parse_num`]'s general parser then reads.
///
/// Both the digits as an integer (under 10^15 < 2^53) and the power of ten
/// are exact doubles, so their one IEEE division is the correctly rounded
/// value: the same bits as the general parser gives (Clinger's fast path).
/// A third of the time of reading a million GOTOs went to the general
/// parser's set-up on such short numbers.
#[inline]
pub(crate) fn plain_decimal(b: &[u8]) -> Option<(f64, usize)> {
    let neg = b.first() == Some(&b'-');
    let start = usize::from(neg);
    let mut m: u64 = 0;
    let mut point: Option<usize> = None;
    let mut i = start;
    while let Some(&c) = b.get(i) {
        let d = c.wrapping_sub(b'0');
        if d < 10 {
            m = m * 10 + u64::from(d);
        } else if c == b'.' && point.is_none() {
            point = Some(i);
        } else if c == b',' {
            break;
        } else {
            return None;
        }
        i += 1;
        // 16 bytes hold at most 16 digits: `m` cannot overflow.
        if i - start > 16 {
            return None;
        }
    }
    let digits = i - start - usize::from(point.is_some());
    if digits == 0 || digits > 15 {
        return None;
    }
    let v = m as f64 / POW10[point.map_or(0, |p| i - p - 1)];
    Some((if neg { -v } else { v }, i))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The general parser alone, as `parse_num` was before its fast path.
    fn general(s: &str) -> Option<f64> {
        let s = s.strip_prefix('+').unwrap_or(s);
        if s.is_empty() {
            return None;
        }
        match fast_float2::parse::<f64, _>(s) {
            Ok(v) if v.is_finite() => Some(v),
            _ => None,
        }
    }

    fn same(s: &str) {
        let (a, b) = (parse_num(s), general(s));
        assert_eq!(
            a.map(f64::to_bits),
            b.map(f64::to_bits),
            "{s:?}: {a:?} against {b:?}"
        );
    }

    #[test]
    fn short_decimals_parse_to_the_bits_of_the_general_parser() {
        for s in [
            "0",
            "-0",
            "-0.0",
            "+0.",
            ".5",
            "-.5",
            "5.",
            "-5.",
            ".",
            "-",
            "-.",
            "+",
            "",
            "0.1",
            "0.3",
            "-2.675",
            "103.",
            "0000.0300",
            "999999999999999",
            "9999999999999999",
            "0.000000000000001",
            "123456789.012345",
            "1234567890.123456",
            "1.2.3",
            "1e-3",
            "--5",
            "+-5",
            "-+5",
            "5-",
            "1,5",
            " 5",
            "0x10",
            "inf",
            "NaN",
            "1_0",
        ] {
            same(s);
        }
    }

    proptest::proptest! {
        #[test]
        fn any_digits_and_point_parse_to_the_same_bits(
            s in "[-+]?[0-9]{0,17}(\\.[0-9]{0,17})?"
        ) {
            same(&s);
        }

        #[test]
        fn any_short_string_parses_to_the_same_bits(s in "[-+.0-9eE]{0,12}") {
            same(&s);
        }
    }

    #[test]
    fn every_code_has_a_name_and_an_explanation() {
        let mut names: Vec<&str> = Code::ALL.iter().map(|c| c.as_str()).collect();
        for c in Code::ALL {
            assert_eq!(Code::from_name(c.as_str()), Some(c));
            assert!(c.explain().len() > 20, "{c}");
        }
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), Code::ALL.len(), "names are unique");
        assert_eq!(Code::from_name("no-such-code"), None);
    }
}
