//! Format and dialect detection from the content (the file name only where
//! the content has no dialect's words: [`detect_named`]), and one reader
//! front that dispatches to the right front end.

use crate::apt::AptReader;
use crate::diag::{ParseError, Parsed};
use crate::gcode::heidenhain::HeidenhainReader;
use crate::gcode::GcodeReader;
use crate::ir::Dialect;
use crate::ReadOptions;

/// The line (from 1) that shows a KUKA KRL robot program (`.SRC`), `None`
/// for anything else. KRL opens with `&ACCESS`/`&REL`/`&PARAM` header lines
/// or `DEF name(`/`DEFDAT name` (Sinumerik's `DEF REAL X` has no
/// parenthesis), after `;` comments.
pub fn krl_line(head: &str) -> Option<u32> {
    for (k, line) in crate::lines::split(head).enumerate().take(50) {
        let t = line.trim();
        if t.is_empty() || t.starts_with(';') {
            continue;
        }
        let up = t.to_ascii_uppercase();
        let def_call = up
            .strip_prefix("GLOBAL ")
            .unwrap_or(&up)
            .strip_prefix("DEF ")
            .and_then(|r| r.trim_start().split_once('('))
            .is_some_and(|(name, _)| {
                !name.is_empty() && name.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
            });
        let header = ["&ACCESS", "&REL", "&PARAM", "&COMMENT"]
            .iter()
            .any(|h| up.starts_with(h));
        if header || def_call || up.starts_with("DEFDAT ") {
            return Some(u32::try_from(k + 1).unwrap_or(u32::MAX));
        }
        return None;
    }
    None
}

/// Guesses the dialect from the first part of a file (a few kB are plenty).
pub fn detect(head: &str) -> Dialect {
    if krl_line(head).is_some() {
        return Dialect::Krl;
    }
    let mut apt = 0i32;
    let mut gcode = 0i32;
    let mut heidenhain = 0i32;
    let (mut nx, mut catia, mut sw) = (0, 0, 0);
    let (mut sinumerik, mut linuxcnc) = (0, 0);
    for line in crate::lines::split(head).take(400) {
        let t = line.trim();
        if t.is_empty() {
            continue;
        }
        let up = t.to_ascii_uppercase();
        if up.starts_with("$$*CATIA") || up.contains("CATIA") && up.starts_with("$$") {
            catia += 3;
        }
        if up.starts_with("$$") {
            apt += 1;
            continue;
        }
        let body = up
            .trim_start_matches(|c: char| c.is_ascii_digit())
            .trim_start();
        if up.as_bytes()[0].is_ascii_digit()
            && (body.starts_with("BEGIN PGM")
                || body.starts_with("L ")
                || body.starts_with("TOOL CALL")
                || body.starts_with("CC ")
                || body.starts_with("CYCL DEF")
                || body.starts_with("BLK FORM"))
        {
            heidenhain += 3;
            continue;
        }
        let major = up.split('/').next().unwrap_or("").trim();
        let has_slash = up.contains('/');
        match major {
            "GOTO" | "FEDRAT" | "CUTTER" | "SPINDL" | "LOADTL" | "CIRCLE" | "COOLNT" | "FROM"
            | "GODLTA" | "TLAXIS" | "UNITS" | "CUTCOM" | "CYCLE" | "SELECT" | "LOAD" | "INDIRV"
            | "TOOLNO"
                if has_slash =>
            {
                apt += 3
            }
            "TOOL PATH" | "TLDATA" | "MSYS" | "PAINT" | "KNOT" | "CNTRL" | "NURBS" if has_slash => {
                apt += 3;
                nx += 2;
            }
            "CSYS" | "TRNTYP" | "UNIT" | "INSERT" if has_slash => {
                apt += 3;
                sw += 2;
            }
            m if m.starts_with("CSI_") => {
                apt += 3;
                sw += 2;
            }
            "RAPID" | "MULTAX" | "FINI" | "END-OF-PATH" => apt += 1,
            _ => {}
        }
        if up.starts_with("PARTNO") || up.starts_with("PPRINT") || up.starts_with("MULTAX") {
            apt += 2;
        }
        let g = up
            .trim_start_matches('N')
            .trim_start_matches(|c: char| c.is_ascii_digit())
            .trim_start();
        if g.starts_with('G')
            || g.starts_with('X')
            || g.starts_with('Y')
            || g.starts_with('Z')
            || g.starts_with('M')
            || g.starts_with('T')
            || g.starts_with('S')
            || g.starts_with('(')
            || g.starts_with('%')
        {
            gcode += 1;
        }
        // Words in comments say nothing about the dialect.
        let code = strip_comments(&up);
        for m in [
            "G710", "G700", "G70 ", "G71 ", "TRAORI", "TRAFOOF", "CYCLE8", "SUPA", "T=\"", "MSG(",
            "DEF REAL", "G642", "COMPCAD", "COMPOF", "SOFT", "FNORM",
        ] {
            if code.contains(m) {
                sinumerik += 2;
            }
        }
        if up.starts_with(';') {
            sinumerik += 1;
            linuxcnc += 1;
        }
        // LinuxCNC's own comment directives are its words.
        for m in ["(MSG,", "(DEBUG,"] {
            if up.contains(m) {
                linuxcnc += 2;
            }
        }
        for m in ["#<", " SUB", "ENDSUB", "G64 P", "G61.1", "G90.1", "G91.1"] {
            if code.contains(m) {
                linuxcnc += 2;
            }
        }
        if code.starts_with('O') && code.contains("SUB") {
            linuxcnc += 2;
        }
    }
    if heidenhain > apt && heidenhain >= gcode {
        return Dialect::Heidenhain;
    }
    if apt > 0 && apt >= gcode {
        return if nx > 0 && nx >= sw {
            Dialect::AptNx
        } else if catia > 0 {
            Dialect::AptCatia
        } else if sw > 0 {
            Dialect::AptSolidworks
        } else {
            Dialect::AptIso
        };
    }
    if sinumerik > 2 && sinumerik > linuxcnc {
        Dialect::Sinumerik
    } else if linuxcnc >= 2 {
        Dialect::LinuxCnc
    } else {
        Dialect::Fanuc
    }
}

/// [`detect`], with the file's extension (without its dot) as a hint where
/// the text has none of a dialect's own words: such a G-code program reads
/// as Fanuc-style, unless its name ends `.ngc`, LinuxCNC's own extension
/// (there `G4 P2` dwells two seconds, where a Fanuc dwells two
/// milliseconds), or `.mpf` or `.spf`, Sinumerik's main and sub programs
/// (there `G4 S10` dwells ten spindle revolutions). Words in the text still
/// decide over the name.
pub fn detect_named(head: &str, extension: Option<&str>) -> Dialect {
    let d = detect(head);
    let is = |x: &str| extension.is_some_and(|e| e.eq_ignore_ascii_case(x));
    match d {
        Dialect::Fanuc if is("ngc") => Dialect::LinuxCnc,
        // `;` comments count for both Sinumerik and LinuxCNC: the name
        // breaks that tie too.
        Dialect::Fanuc | Dialect::LinuxCnc if is("mpf") || is("spf") => Dialect::Sinumerik,
        d => d,
    }
}

/// A G-code line without its `( )` and `;` comments.
fn strip_comments(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut depth = 0usize;
    for c in line.chars() {
        match c {
            '(' => depth += 1,
            ')' if depth > 0 => depth -= 1,
            ';' if depth == 0 => break,
            c if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out
}

/// A reader for any format: feed lines, then finish.
pub enum Reader {
    Apt(Box<AptReader>),
    Gcode(Box<GcodeReader>),
    Heidenhain(Box<HeidenhainReader>),
    /// KRL is read whole (a program is statements, not blocks): the lines
    /// gathered, read at the end without its sub-programs (those a main
    /// calls are named as not read).
    Krl(String, ReadOptions),
}

impl Reader {
    pub fn new(dialect: Dialect, opts: ReadOptions) -> Reader {
        match dialect {
            d if d.is_apt() => Reader::Apt(Box::new(AptReader::new(d, opts))),
            Dialect::Heidenhain => Reader::Heidenhain(Box::new(HeidenhainReader::new(opts))),
            Dialect::Krl => Reader::Krl(String::new(), opts),
            d => Reader::Gcode(Box::new(GcodeReader::new(d, opts))),
        }
    }

    pub fn line(&mut self, line: &str) -> Result<(), ParseError> {
        match self {
            Reader::Apt(r) => r.line(line),
            Reader::Gcode(r) => r.line(line),
            Reader::Heidenhain(r) => r.line(line),
            Reader::Krl(text, _) => {
                text.push_str(line);
                text.push('\n');
                Ok(())
            }
        }
    }

    /// The program read, with every number within the plausibility limits
    /// of [`crate::plausible`].
    pub fn finish(self) -> Result<Parsed, ParseError> {
        let parsed = match self {
            Reader::Apt(r) => r.finish(),
            Reader::Gcode(r) => r.finish(),
            Reader::Heidenhain(r) => r.finish(),
            Reader::Krl(text, opts) => read_krl(&text, &opts),
        }?;
        crate::plausible::check(&parsed.program)?;
        let mut parsed = parsed;
        let warnings = crate::plausible::warnings(&parsed.program);
        parsed.diagnostics.extend(warnings);
        Ok(parsed)
    }
}

/// A KRL program into the IR (external axes dropped with a finding: a
/// writer of another dialect is asked through [`crate::write::krl::from_krl`]
/// whether they may be).
fn read_krl(text: &str, opts: &ReadOptions) -> Result<Parsed, ParseError> {
    crate::krl::read(text, &mut |_| None)
        .and_then(|k| k.to_ir(opts.default_feed, true))
        .map_err(|e| e.error)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_in_comments_do_not_decide_the_dialect() {
        let fanuc = "%\nO0001\n(POST FOR TRAORI AND SUPA MACHINES, G710)\nG21 G90\nG0 X1 Y2 ; CYCLE832 here\nG1 Z-1 F100\nM30\n";
        assert_eq!(detect(fanuc), Dialect::Fanuc);
        let sinumerik = "N10 G710 G90\nN20 TRAORI\nN30 G0 X1\n";
        assert_eq!(detect(sinumerik), Dialect::Sinumerik);
    }

    /// Issue 18: a KUKA `.SRC` got "1:1: unexpected `&ACCESS`".
    #[test]
    fn an_ngc_file_without_a_dialect_s_words_is_linuxcnc() {
        let plain = "G21 G90\nG0 X0 Y0 Z5\nG4 P2\nM30\n";
        assert_eq!(detect_named(plain, None), Dialect::Fanuc);
        assert_eq!(detect_named(plain, Some("nc")), Dialect::Fanuc);
        assert_eq!(detect_named(plain, Some("NGC")), Dialect::LinuxCnc);
        assert_eq!(detect_named(plain, Some("MPF")), Dialect::Sinumerik);
        assert_eq!(detect_named(plain, Some("spf")), Dialect::Sinumerik);
        let commented = "; part A\n; op 1\nG90 G0 X0 Y0 Z5\nG4 S10\nM30\n";
        assert_eq!(detect_named(commented, None), Dialect::LinuxCnc);
        assert_eq!(detect_named(commented, Some("mpf")), Dialect::Sinumerik);
        // The text's own words decide over the name.
        let siemens = "G710\nTRAORI\nG0 X0 Y0 Z5\nM30\n";
        assert_eq!(detect_named(siemens, Some("ngc")), Dialect::Sinumerik);
        let apt = "PARTNO P\nGOTO/0,0,5\nFINI\n";
        assert_eq!(detect_named(apt, Some("ngc")), Dialect::AptIso);
    }

    #[test]
    fn krl_is_told_by_its_head() {
        let krl = "&ACCESS RVP\n&REL 2\nDEF f1_Kuka()\nPTP $AXIS_ACT\nEND\n";
        assert_eq!(krl_line(krl), Some(1));
        assert_eq!(detect(krl), Dialect::Krl);
        let bare = "; generated\nDEF main( )\n  LIN {X 1}\nEND\n";
        assert_eq!(krl_line(bare), Some(2));
        // Read by the KRL reader: its error at the statement's line.
        let e = crate::parse_program(bare, ReadOptions::default()).expect_err("no Y, Z");
        assert_eq!(e.line, 3, "{e}");
        assert!(e.message.contains("X, Y and Z"), "{e}");
        let p = crate::parse_program(krl, ReadOptions::default()).expect("reads");
        assert_eq!(p.program.source, Dialect::Krl);
        for not_krl in [
            "N10 DEF REAL DEPTH=2\nN20 G0 X1\n",
            "G21 G90\nG1 X1 F100\n",
            "TOOL PATH/ROUGH\nGOTO/1,2,3\n",
            "0 BEGIN PGM X MM\n",
        ] {
            assert!(krl_line(not_krl).is_none(), "{not_krl}");
        }
    }
}
