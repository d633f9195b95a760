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
use crate::{check_line_length, detect, Diagnostic, ParseError, ReadOptions};

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
    let mut r = ReadBackStream::new(target, original, g93_seconds);
    r.feed(written)?;
    r.finish(tol)
}

/// The bytes an APT head is looked at for its dialect.
const HEAD: usize = 16 * 1024;

/// [`read_back_with`] of bytes handed over piece by piece, in order, as a
/// writer makes them ([`ReadBackStream::feed`], then
/// [`ReadBackStream::finish`]): the same lines read the same way, with no
/// copy of the whole text held.
pub struct ReadBackStream<'a> {
    target: Target,
    original: &'a Program,
    opts: ReadOptions,
    /// Bytes not read yet: the head until the reader is chosen, then the
    /// start of a line not ended yet (or a CR that a LF may follow).
    carry: Vec<u8>,
    reader: Option<detect::Reader>,
    /// Lines read so far.
    lines: usize,
}

impl<'a> ReadBackStream<'a> {
    /// A read-back of what a writer for `target` makes of `original`
    /// (G93 F words in seconds where `g93_seconds`).
    pub fn new(target: Target, original: &'a Program, g93_seconds: bool) -> ReadBackStream<'a> {
        let opts = ReadOptions {
            expect_moves: original.move_count(),
            g93_seconds,
            ..ReadOptions::default()
        };
        let mut r = ReadBackStream {
            target,
            original,
            opts,
            carry: Vec::new(),
            reader: None,
            lines: 0,
        };
        // Only an APT head is needed to choose the reader.
        if target != Target::Apt {
            r.reader = Some(detect::Reader::new(reader_dialect(target, ""), opts));
        }
        r
    }

    /// The next piece of the written bytes.
    pub fn feed(&mut self, bytes: &[u8]) -> Result<(), ParseError> {
        if self.reader.is_none() || !self.carry.is_empty() {
            self.carry.extend_from_slice(bytes);
            if self.reader.is_none() && self.carry.len() < HEAD + 4 {
                return Ok(());
            }
            self.choose();
            let carry = std::mem::take(&mut self.carry);
            let used = self.lines_of(&carry, false)?;
            self.carry = carry;
            self.carry.drain(..used);
        } else {
            let used = self.lines_of(bytes, false)?;
            self.carry.extend_from_slice(&bytes[used..]);
        }
        Ok(())
    }

    /// The reader of the dialect the head says, once.
    fn choose(&mut self) {
        if self.reader.is_none() {
            let head = &self.carry[..self.carry.len().min(HEAD + 4)];
            let head = String::from_utf8_lossy(head);
            let dialect = reader_dialect(self.target, &head);
            self.reader = Some(detect::Reader::new(dialect, self.opts));
        }
    }

    /// Reads the lines of `buf` that are whole (every one when `last`, the
    /// rest of `buf` then being the last line, as [`crate::lines::split`] gives
    /// it): how many bytes they took.
    fn lines_of(&mut self, buf: &[u8], last: bool) -> Result<usize, ParseError> {
        let Some(r) = self.reader.as_mut() else {
            return Ok(0);
        };
        let mut start = 0;
        while let Some(i) = memchr::memchr2(b'\n', b'\r', &buf[start..]) {
            let i = start + i;
            // A CR at the end: whether a LF follows is in the next piece.
            if buf[i] == b'\r' && i + 1 == buf.len() && !last {
                break;
            }
            let crlf = buf[i] == b'\r' && buf.get(i + 1) == Some(&b'\n');
            self.lines += 1;
            let line = String::from_utf8_lossy(&buf[start..i]);
            check_line_length(line.len(), self.lines, &self.opts.limits)?;
            r.line(&line)?;
            start = i + if crlf { 2 } else { 1 };
        }
        if last {
            self.lines += 1;
            let line = String::from_utf8_lossy(&buf[start..]);
            check_line_length(line.len(), self.lines, &self.opts.limits)?;
            r.line(&line)?;
            return Ok(buf.len());
        }
        // A line that has not ended yet is refused as soon as it is too
        // long (a CR held back for the LF that may follow is no part of it).
        let pending = &buf[start..];
        let cr = pending.last() == Some(&b'\r');
        check_line_length(
            pending.len() - cr as usize,
            self.lines + 1,
            &self.opts.limits,
        )?;
        Ok(start)
    }

    /// The last line, and the program read compared with the original
    /// within `tol`.
    pub fn finish(mut self, tol: &Tolerance) -> Result<ReadBack, ParseError> {
        self.choose();
        let carry = std::mem::take(&mut self.carry);
        self.lines_of(&carry, true)?;
        drop(carry);
        let r = match self.reader.take() {
            Some(r) => r,
            None => detect::Reader::new(reader_dialect(self.target, ""), self.opts),
        };
        let parsed = r.finish()?;
        let equiv = compare(self.original, &parsed.program, tol);
        Ok(ReadBack {
            program: parsed.program,
            diagnostics: parsed.diagnostics,
            equiv,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::write::{write_program, WriteOptions};
    use crate::{parse_program, ReadOptions};
    use proptest::prelude::*;

    /// Everything a read-back says, as text: the program, the findings and
    /// the comparison.
    fn said(r: Result<ReadBack, ParseError>) -> String {
        match r {
            Ok(b) => format!("{:?}\n{:?}\n{:?}", b.program, b.diagnostics, b.equiv),
            Err(e) => format!("error {e}"),
        }
    }

    /// The bytes in pieces cut at `cuts` (fractions of the length), fed one
    /// by one.
    fn streamed(bytes: &[u8], t: Target, p: &Program, cuts: &[f64]) -> String {
        let mut at: Vec<usize> = cuts
            .iter()
            .map(|c| (c * bytes.len() as f64) as usize)
            .collect();
        at.push(0);
        at.push(bytes.len());
        at.sort_unstable();
        let mut s = ReadBackStream::new(t, p, false);
        for w in at.windows(2) {
            if let Err(e) = s.feed(&bytes[w[0]..w[1]]) {
                return format!("error {e}");
            }
        }
        said(s.finish(&Tolerance::default()))
    }

    const SRC: &str =
        "G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F300\nG1 X10 (CUT)\nG2 X20 Y0 I5 J0\nM30\n";

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// Read in pieces, the written bytes read as they do whole: LF,
        /// CRLF and lone-CR line ends, with or without a last line end,
        /// cut anywhere (between a CR and its LF too), for every target.
        #[test]
        fn pieces_read_as_the_whole(
            cuts in proptest::collection::vec(0.0f64..1.0, 0..12),
            ends in 0usize..3,
            last in any::<bool>(),
            t in 0usize..5,
        ) {
            let p = parse_program(SRC, ReadOptions::default()).expect("reads").program;
            let t = [Target::Fanuc, Target::Sinumerik, Target::Heidenhain, Target::LinuxCnc, Target::Apt][t];
            let (out, _) = write_program(&p, WriteOptions::new(t)).expect("writes");
            let mut text = String::from_utf8(out).expect("text");
            if !last {
                text = text.trim_end().to_string();
            }
            let bytes = text.replace('\n', ["\n", "\r\n", "\r"][ends]).into_bytes();
            let whole = said(read_back_with(&bytes, t, &p, &Tolerance::default(), false));
            prop_assert_eq!(streamed(&bytes, t, &p, &cuts), whole);
        }
    }

    /// A line exactly as long as the limit allows, its CR at the end of a
    /// piece: the CR held back for its LF is no part of the line.
    #[test]
    fn a_longest_line_before_a_cr_at_a_cut_reads() {
        let limit = crate::ReadOptions::default().limits.line_bytes as usize;
        let comment = format!("({})", "A".repeat(limit - 2));
        let text = format!("G21 G90\r\n{comment}\r\nT1 M6\r\nM30\r\n");
        let p = parse_program(&text, ReadOptions::default())
            .expect("reads")
            .program;
        let bytes = text.as_bytes();
        let cut = text.find(&comment).expect("there") + comment.len() + 1;
        let whole = said(read_back_with(
            bytes,
            Target::Fanuc,
            &p,
            &Tolerance::default(),
            false,
        ));
        assert!(
            !whole.starts_with("error"),
            "{}",
            &whole[..whole.len().min(300)]
        );
        let cuts = [(cut as f64 + 0.5) / bytes.len() as f64];
        // The cut falls just after the CR.
        let at = (cuts[0] * bytes.len() as f64) as usize;
        assert_eq!(bytes[at - 1], b'\r');
        assert_eq!(streamed(bytes, Target::Fanuc, &p, &cuts), whole);
    }

    /// An APT file longer than the head the dialect is chosen from reads
    /// the same in pieces smaller than that head.
    #[test]
    fn a_long_apt_file_in_small_pieces() {
        let mut src = String::from("G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F300\n");
        for k in 0..10_000 {
            src.push_str(&format!("G1 X{} Y{}\n", k % 50, k / 50));
        }
        src.push_str("M30\n");
        let p = parse_program(&src, ReadOptions::default())
            .expect("reads")
            .program;
        let (out, _) = write_program(&p, WriteOptions::new(Target::Apt)).expect("writes");
        assert!(out.len() > 4 * HEAD, "{}", out.len());
        let whole = said(read_back_with(
            &out,
            Target::Apt,
            &p,
            &Tolerance::default(),
            false,
        ));
        assert!(
            whole.contains("Ok("),
            "{}",
            &whole[whole.len().saturating_sub(300)..]
        );
        let cuts: Vec<f64> = (1..97).map(|k| k as f64 / 97.0).collect();
        assert_eq!(streamed(&out, Target::Apt, &p, &cuts), whole);
    }
}
