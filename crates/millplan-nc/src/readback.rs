//! The written-program read-back: the bytes a writer produced are read again
//! with the reader of the dialect they were written for, and the program read
//! is run through the same interpreter as the program that was written
//! ([`crate::equiv`]). A writer that drops a word, rounds a position too far
//! or writes something its own reader takes differently is caught here,
//! before the file is renamed into place.
//!
//! Every command that writes a program (`convert`, `post`, and the checks of
//! `millplan_plan::safety`) goes through [`read_back`].

use crate::equiv::{compare, Mismatch, Tolerance, Walked};
use crate::ir::{Dialect, Program};
use crate::write::Target;
use crate::{check_line_length, detect, lines, Diagnostic, ParseError, ReadOptions};

/// What reading the written bytes back gave.
#[derive(Clone, Debug)]
pub struct ReadBack {
    /// The program as its reader sees the written bytes (its lines are the
    /// written file's lines).
    pub program: Program,
    /// What the reader said about the written text (a writer should leave
    /// none of severity error).
    pub diagnostics: Vec<Diagnostic>,
    /// Whether the program read back commands what the written program did:
    /// the steps walked, or where the two part.
    pub equiv: Result<Walked, Mismatch>,
}

impl ReadBack {
    /// Whether the written bytes mean what the written program meant.
    pub fn is_equivalent(&self) -> bool {
        self.equiv.is_ok()
    }
}

/// The dialect whose reader reads what a writer for `target` wrote. An APT
/// file says in its head which APT it is (the writer states it), so for
/// [`Target::Apt`] the head decides among the APT dialects.
pub fn reader_dialect(target: Target, written: &str) -> Dialect {
    match target {
        Target::Fanuc => Dialect::Fanuc,
        Target::Sinumerik => Dialect::Sinumerik,
        Target::Heidenhain => Dialect::Heidenhain,
        Target::LinuxCnc => Dialect::LinuxCnc,
        Target::Krl => Dialect::Krl,
        Target::Apt => {
            let head = &written[..floor_char_boundary(written, 16 * 1024)];
            match detect::detect(head) {
                d if d.is_apt() => d,
                _ => Dialect::AptIso,
            }
        }
    }
}

fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    if i >= s.len() {
        return s.len();
    }
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// Reads `written` (the bytes a writer made for `target` from `original`)
/// back with `target`'s reader and compares it with `original` within
/// `tol`. `Err` only when the bytes do not read at all (a line and column
/// of the written text); a program that reads but commands something else
/// is `Ok` with [`ReadBack::equiv`] naming where the two part.
///
/// ```
/// use millplan_nc::{parse_program, ReadOptions};
/// use millplan_nc::equiv::Tolerance;
/// use millplan_nc::readback::read_back;
/// use millplan_nc::write::{write_program, Target, WriteOptions};
///
/// let src = "G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F300\nG1 X10\nM30\n";
/// let p = parse_program(src, ReadOptions::default()).expect("reads").program;
/// let (out, _) = write_program(&p, WriteOptions::new(Target::Sinumerik)).expect("writes");
/// let back = read_back(&out, Target::Sinumerik, &p, &Tolerance::default())
///     .expect("reads back");
/// assert!(back.is_equivalent());
/// ```
pub fn read_back(
    written: &[u8],
    target: Target,
    original: &Program,
    tol: &Tolerance,
) -> Result<ReadBack, ParseError> {
    read_back_with(written, target, original, tol, false)
}

/// [`read_back`] of bytes whose G93 F words are block times in seconds
/// where `g93_seconds` (as the writers' [`crate::write::WriteOptions`] say).
pub fn read_back_with(
    written: &[u8],
    target: Target,
    original: &Program,
    tol: &Tolerance,
    g93_seconds: bool,
) -> Result<ReadBack, ParseError> {
    let text = String::from_utf8_lossy(written);
    let opts = ReadOptions {
        expect_moves: original.move_count(),
        g93_seconds,
        ..ReadOptions::default()
    };
    let mut r = detect::Reader::new(reader_dialect(target, &text), opts);
    for (k, line) in lines::split(&text).enumerate() {
        check_line_length(line.len(), k + 1, &opts.limits)?;
        r.line(line)?;
    }
    let parsed = r.finish()?;
    let equiv = compare(original, &parsed.program, tol);
    Ok(ReadBack {
        program: parsed.program,
        diagnostics: parsed.diagnostics,
        equiv,
    })
}
