//! millplan's NC layer: the toolpath IR and its verifier, the front ends that read
//! APT/CL and G-code into it, and the back ends that write it out again.
//!
//! Nothing here touches the file system: readers take text (or lines), writers
//! produce text; the `millplan` binary does all I/O.

pub mod apt;
pub mod detect;
pub mod diag;
pub mod equiv;
pub mod gcode;
pub mod generate;
pub mod ir;
pub mod krl;
pub mod lines;
pub mod plausible;
pub mod readback;
pub mod stats;
pub mod text;
pub mod transform;
pub mod verify;
pub mod write;

pub use diag::{Diagnostic, ParseError, Parsed, Severity};
pub use ir::*;
pub use millplan_geom::limits::{Exceeded, Limits};

/// Reader settings shared by all front ends.
#[derive(Clone, Copy, Debug)]
pub struct ReadOptions {
    /// Force the source unit instead of reading or inferring it.
    pub units: Option<LengthUnit>,
    /// Feed (mm/min) given to cutting moves that come before any programmed feed.
    pub default_feed: f64,
    /// Chord tolerance (mm) for sampling splines into lines.
    pub chord_tol: f64,
    /// About how many moves the program holds (0: unknown). A hint: the first
    /// operation to get a move reserves room for them at once, instead of
    /// growing (copying, and touching fresh memory) step by step.
    pub expect_moves: usize,
    /// Resource limits: the sampling of a NURBS span (`expansion`), the
    /// length of a line (`line_bytes`), the nesting of an expression
    /// (`expression_depth`).
    pub limits: Limits,
    /// An F word under G93 is the block's time in seconds (Beckhoff/ISG
    /// TwinCAT CNC) rather than its inverse in minutes (RS274/NGC): a machine
    /// file's `g93_f = "seconds"`, as the writers' `g93_seconds`.
    pub g93_seconds: bool,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            units: None,
            default_feed: 1000.0,
            chord_tol: 0.002,
            expect_moves: 0,
            limits: Limits::default(),
            g93_seconds: false,
        }
    }
}

/// Reads a program of any supported format from its text, detecting the format
/// from the content. Lines end at LF, CRLF or a lone CR.
///
/// ```
/// use millplan_nc::{parse_program, ReadOptions};
///
/// let src = "G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F300\nG1 X10\nM30\n";
/// let parsed = parse_program(src, ReadOptions::default()).expect("reads");
/// assert_eq!(parsed.program.move_count(), 3);
/// let last = parsed.program.moves().last().expect("a move");
/// assert_eq!((last.end.x, last.end.z, last.line), (10.0, -1.0, 6));
/// // Bad input is an error at its line and column, never a panic.
/// let e = parse_program("G21\nG1 X1 Q@@\n", ReadOptions::default()).unwrap_err();
/// assert_eq!((e.line, e.col), (2, 8));
/// ```
pub fn parse_program(src: &str, opts: ReadOptions) -> Result<Parsed, ParseError> {
    // A move takes a line of 20 bytes or more.
    let opts = ReadOptions {
        expect_moves: if opts.expect_moves > 0 {
            opts.expect_moves
        } else {
            src.len() / 20
        },
        ..opts
    };
    let mut r = detect::Reader::new(detect::detect(src), opts);
    for (k, line) in lines::split(src).enumerate() {
        check_line_length(line.len(), k + 1, &opts.limits)?;
        r.line(line)?;
    }
    r.finish()
}

/// Refuses a line longer than `limits.line_bytes` (`line` counted from 1),
/// located just past the limit.
pub fn check_line_length(len: usize, line: usize, limits: &Limits) -> Result<(), ParseError> {
    if len as u64 <= limits.line_bytes {
        return Ok(());
    }
    let col = u32::try_from(limits.line_bytes + 1).unwrap_or(u32::MAX);
    Err(ParseError::new(
        u32::try_from(line).unwrap_or(u32::MAX),
        col,
        Exceeded::new(
            "line-bytes",
            format!("a line of {len} bytes or more"),
            limits.line_bytes as f64,
        )
        .to_string(),
    ))
}
