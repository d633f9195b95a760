//! Hostile inputs to the readers (issue 17): line endings of every kind in
//! every dialect, and the limits on what a few bytes may ask for — a NURBS
//! span sampled into millions of moves, an expression nested thousands
//! deep, a line without end. Each is the smallest repro, with the located
//! error it must give.

mod common;

use millplan_nc::detect::detect;
use millplan_nc::{parse_program, text, Limits, ReadOptions};
use std::path::Path;

fn golden(name: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(name);
    std::fs::read_to_string(p).expect("golden input")
}

/// `src` with every line ending replaced by `nl`.
fn with_endings(src: &str, nl: &str) -> String {
    millplan_nc::lines::split(src).collect::<Vec<_>>().join(nl)
}

/// The IR of `src` read with LF, CRLF and lone-CR line endings is the same
/// program, line numbers and all, in the same dialect.
fn same_under_every_ending(name: &str, src: &str, opts: ReadOptions) {
    let lf = with_endings(src, "\n");
    let want = parse_program(&lf, opts).unwrap_or_else(|e| panic!("{name}: {e}"));
    let want_ir = text::print(&want.program);
    assert!(want.program.move_count() > 0, "{name}");
    for nl in ["\r\n", "\r"] {
        let other = with_endings(src, nl);
        assert_eq!(detect(&other), detect(&lf), "{name} {nl:?}");
        let got = parse_program(&other, opts).unwrap_or_else(|e| panic!("{name} {nl:?}: {e}"));
        assert_eq!(
            got.program.move_count(),
            want.program.move_count(),
            "{name} {nl:?}"
        );
        assert!(
            text::print(&got.program) == want_ir,
            "{name} {nl:?}: the IR differs"
        );
        assert_eq!(got.diagnostics, want.diagnostics, "{name} {nl:?}");
    }
}

/// Issue 17: "CR-only line endings read silently as one line: a five-block
/// program becomes one move". Every dialect's golden input reads the same
/// with LF, CRLF and CR only.
#[test]
fn every_dialect_reads_every_line_ending() {
    for name in [
        "fanuc.nc",
        "linuxcnc.ngc",
        "sinumerik.mpf",
        "heidenhain.h",
        "catia.apt",
        "inch_iso.apt",
        "nx.cls",
        "solidworks.apt",
    ] {
        same_under_every_ending(name, &golden(name), ReadOptions::default());
    }
    // The five-block program of the issue: five moves, not one.
    let five = "G21 G90\rT1 M6\rG0 X0 Y0 Z5\rG1 Z0 F100\rG1 X10\rG1 Y10\rG1 X0\rM30\r";
    let p = parse_program(five, ReadOptions::default()).expect("reads");
    assert_eq!(p.program.move_count(), 5);
    assert_eq!(p.program.moves().last().map(|m| m.line), Some(7));
}

/// The real samples (when `../shared/data` is here) read the same with
/// their line endings turned into CRLF and into CR only.
#[test]
fn every_sample_reads_every_line_ending() {
    let Some(root) = common::data() else {
        return;
    };
    for path in common::programs(&root) {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let src = String::from_utf8_lossy(&std::fs::read(&path).expect("read")).into_owned();
        if parse_program(&src, common::options_for(name)).is_err() {
            continue;
        }
        same_under_every_ending(name, &src, common::options_for(name));
    }
}

/// Issue 17: "A 133-byte NURBS with 1e12 control points subdivides to 16.8
/// M moves (2 GB, 13 s)". The span is refused at the NURBS record, naming the
/// limit, after at most the limit's worth of sampling; raised, it reads.
#[test]
fn a_nurbs_span_is_sampled_within_the_expansion_limit() {
    let src = "CUTTER/10\nFEDRAT/100\nGOTO/0,0,0\nNURBS/\nKNOT/0.5,1\nCNTRL/1e12,0,0\nCNTRL/0,1e12,0\nCNTRL/1e12,1e12,0\nCNTRL/0,0,1e12\nFINI\n";
    assert!(src.len() < 133);
    let t = std::time::Instant::now();
    let e = parse_program(src, ReadOptions::default()).expect_err("refused");
    assert_eq!((e.line, e.col), (4, 1), "{e}");
    assert!(
        e.message.contains("span 1 needs more than 10000 moves"),
        "{e}"
    );
    assert!(e.message.contains("--limit expansion=N"), "{e}");
    assert!(t.elapsed().as_secs() < 5);
    // A sane spline (the published samples' shape) is well within.
    let sane = src.replace("1e12", "10");
    let p = parse_program(&sane, ReadOptions::default()).expect("reads");
    assert!(p.program.move_count() < 1000);
    let mut o = ReadOptions::default();
    o.limits.expansion = 20;
    assert!(parse_program(&sane, o).is_err());
}

/// Issue 17: "a 12 KB Sinumerik expression of nested unary minus overflows
/// the reader thread's stack (exit 134)". Read on a thread with a small
/// stack, it is a located error naming the limit.
#[test]
fn a_deep_expression_is_a_located_error() {
    let src = format!(
        "N10 G710 G90\nN20 TRAORI\nN30 DEF REAL _Z\nN40 T=\"BALL\" D1\nN50 G1 X1 Y1 Z={}5 F100\nN60 M30\n",
        "-".repeat(12_000)
    );
    assert!(src.len() > 12_000);
    let e = std::thread::Builder::new()
        .stack_size(256 * 1024)
        .spawn(move || parse_program(&src, ReadOptions::default()))
        .expect("spawn")
        .join()
        .expect("the reader does not overflow its stack")
        .expect_err("refused");
    assert_eq!((e.line, e.col), (5, 14), "{e}");
    assert!(e.message.contains("expression-depth limit of 64"), "{e}");
    // LinuxCNC's expressions go through the same evaluator.
    let ngc = format!(
        "G21\nT1 M6\n#<a>={}1\nG1 X#<a> F100\nM30\n",
        "-".repeat(5000)
    );
    if let Err(e) = parse_program(&ngc, ReadOptions::default()) {
        assert!(!e.message.is_empty());
    }
}

/// A line longer than the line-bytes limit is refused where the limit ends.
#[test]
fn a_line_without_end_is_a_located_error() {
    let long = format!("G21\nT1 M6\nG1 X1 F100 ({})\nM30\n", "x".repeat(70_000));
    let e = parse_program(&long, ReadOptions::default()).expect_err("refused");
    assert_eq!((e.line, e.col), (3, 65_537), "{e}");
    assert!(e.message.contains("line-bytes limit of 65536"), "{e}");
    let o = ReadOptions {
        limits: Limits {
            line_bytes: 100_000,
            ..Limits::default()
        },
        ..ReadOptions::default()
    };
    assert!(parse_program(&long, o).is_ok());
}

/// Issue 17: pecks of `Q0.000001` in G83, APT `CYCLE/DEEP` and Heidenhain
/// cycles 200 and 1 are never expanded: every reader refuses them at the
/// cycle's line (`MAX_PECKS`), and every writer refuses such a cycle made
/// by other means (a pass, a generator).
#[test]
fn tiny_pecks_are_refused_in_every_dialect() {
    let cases = [
        ("G21 G17 G90 G94\nT2 M6\nG43 H2 S1500 M3\nG0 X10. Y10. Z5.\nG98 G83 X10. Y10. Z-20. R2. Q0.000001 F100.\nX30.\nG80\nM30\n", 5),
        ("UNITS/MM\nCUTTER/10\nFEDRAT/100\nGOTO/0,0,10\nCYCLE/DEEP,FEDTO,20,STEP,0.000001,RAPTO,2,MMPM,100\nGOTO/10,10,0\nCYCLE/OFF\nFINI\n", 5),
        ("0 BEGIN PGM P MM\n1 TOOL CALL 1 Z S1000\n2 L Z+50 R0 FMAX\n3 CYCL DEF 200 DRILLING ~\n  Q200=2 ;SET-UP CLEARANCE ~\n  Q201=-20 ;DEPTH ~\n  Q206=150 ;FEED RATE ~\n  Q202=0.000001 ;PLUNGING DEPTH ~\n  Q210=0 ;DWELL TIME AT TOP ~\n  Q203=+0 ;SURFACE COORDINATE ~\n  Q204=50 ;2ND SET-UP CLEARANCE ~\n  Q211=0 ;DWELL TIME AT BOTTOM\n4 L X+10 Y+10 R0 FMAX M99\n5 END PGM P MM\n", 4),
        ("0 BEGIN PGM P MM\n1 TOOL CALL 1 Z S1000\n2 L Z+50 R0 FMAX\n3 CYCL DEF 1.0 PECKING\n4 CYCL DEF 1.1 SET UP 2\n5 CYCL DEF 1.2 DEPTH -20\n6 CYCL DEF 1.3 PECKG 0.000001\n7 CYCL DEF 1.4 DWELL 0\n8 CYCL DEF 1.5 F150\n9 L X+10 Y+10 R0 FMAX M99\n10 END PGM P MM\n", 4),
    ];
    for (src, line) in cases {
        let e = parse_program(src, ReadOptions::default()).expect_err("refused");
        assert_eq!(e.line, line, "{e}");
        assert!(e.message.contains("at most 1000 are accepted"), "{e}");
        // The same cycle with a sane peck reads; made absurd afterwards,
        // every target refuses it. The G-code targets at its line, for its
        // pecks (APT may stop earlier, at a move from a position not yet
        // known).
        let sane = src.replace("0.000001", "2");
        let mut p = parse_program(&sane, ReadOptions::default()).expect("reads");
        let c = p
            .program
            .operations
            .iter_mut()
            .flat_map(|o| o.cycles.iter_mut())
            .next();
        c.expect("a cycle").peck = Some(0.000001);
        for t in millplan_nc::write::Target::ALL {
            let o = millplan_nc::write::WriteOptions::new(t);
            let e = millplan_nc::write::write_program(&p.program, o).expect_err("refused");
            if t.is_gcode() {
                assert_eq!(e.line, line, "{}: {e}", t.name());
                assert!(e.message.contains("at most 1000 are accepted"), "{e}");
            }
        }
    }
}

// ---------------------------------------------------------------------------
// Issue 34, "Hostile inputs, round two".

use millplan_nc::write::{write_program, Target, WriteOptions};

/// Issue 34: "`convert nan_num.nc --to fanuc` and `feed` copy `XNAN YINF` /
/// `ZINF` verbatim into the output (docs/usage.md: no writer writes a non-finite
/// number)". A block the reader keeps verbatim is refused by every writer at
/// the source's line.
#[test]
fn verbatim_non_finite_words_are_refused_by_every_writer() {
    let src = "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z0 F100\nG28 XNAN YINF\nG1 X10\nM30\n";
    let p = parse_program(src, ReadOptions::default()).expect("reads");
    for t in Target::ALL {
        let e = write_program(&p.program, WriteOptions::new(t)).expect_err(t.name());
        assert_eq!(e.line, 5, "{}: {e}", t.name());
        assert!(e.message.contains("`XNAN`"), "{}: {e}", t.name());
    }
    assert_eq!(
        millplan_nc::write::preflight::non_finite_word("G28 X-inf (NAN in a comment)"),
        Some("X-inf")
    );
    for fine in ["G28 X0 Y0", "(XNAN)", "M INFO", "G0 X1 ; YINF", "MINFEED=3"] {
        assert_eq!(
            millplan_nc::write::preflight::non_finite_word(fine),
            None,
            "{fine}"
        );
    }
}

/// Issue 34: "`feed` on an APT with one GOTO at z = −1e308 writes
/// `FEDRAT/0`; a Heidenhain `FU1e308` block becomes `G95 F0.`" and "`feed`
/// on a Heidenhain program with `A+1e308` writes `Ainf`". A coordinate,
/// rotary position or feed that is finite but absurd is refused at its line
/// under the plausibility limits (1e6 mm, degrees, per minute).
#[test]
fn absurd_finite_numbers_are_refused_at_their_line() {
    let cases: [(&str, &str, u32); 5] = [
        ("fanuc", "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-2000000 F100\nM30\n", 4),
        ("fanuc", "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 X10 F1000001\nM30\n", 4),
        (
            "apt",
            "UNITS/MM\nCUTTER/10,5\nFEDRAT/500\nGOTO/10,10,50\nGOTO/10,10,-1e308\nFINI\n",
            5,
        ),
        (
            "heidenhain FU",
            "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S1000\n2 L X+0 Y+0 Z+5 FMAX M3\n3 L Z+0 FU1e308\n4 END PGM T MM\n",
            4,
        ),
        (
            "heidenhain A",
            "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S1000\n2 L X+0 Y+0 Z+5 FMAX M3\n3 L A+1e308 F100\n4 END PGM T MM\n",
            4,
        ),
    ];
    for (what, src, line) in cases {
        let e = parse_program(src, ReadOptions::default()).expect_err(what);
        assert_eq!(e.line, line, "{what}: {e}");
        assert!(e.message.contains("plausibility limit"), "{what}: {e}");
    }
    // Rotary words may exceed 360°, coordinates may be zero or negative.
    let ok = "G21 G90\nT1 M6\nG0 X0 Y0 Z5 A0\nG1 X-999999 A7200 F100\nM30\n";
    parse_program(ok, ReadOptions::default()).expect("plausible");
}

/// Issue 34: "`X1e5` in G-code reads as `X1` and a word `E5`, with no
/// warning". It still reads so (G-code has no exponent), with a warning at
/// the word.
#[test]
fn an_exponent_in_a_gcode_word_is_warned_about() {
    let src = "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 X1e5 F100\nM30\n";
    let p = parse_program(src, ReadOptions::default()).expect("reads");
    let d = p
        .diagnostics
        .iter()
        .find(|d| d.message.contains("no exponent"))
        .unwrap_or_else(|| panic!("no warning: {:?}", p.diagnostics));
    assert_eq!((d.line, d.col), (4, 4), "{d:?}");
    assert!(d.message.contains("`X1e5` reads as `X1`"), "{d:?}");
    let plain = "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 X1 E5 F100\nM30\n";
    let p = parse_program(plain, ReadOptions::default()).expect("reads");
    assert!(!p.diagnostics.iter().any(|d| d.message.contains("exponent")));
}

/// Issue 34: "`orient … --ap 0.01` writes `FEDRAT/0,MMPM`". No writer writes
/// a feed move with a feed of 0 or below; it is refused at the move's line.
#[test]
fn no_writer_writes_a_zero_feed_on_a_feed_move() {
    let src = "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z0 F100\nG1 X10\nM30\n";
    let mut p = parse_program(src, ReadOptions::default())
        .expect("reads")
        .program;
    let m = p.operations[0]
        .moves
        .iter_mut()
        .find(|m| m.line == 5)
        .expect("move of line 5");
    m.feed = 0.0;
    for t in Target::ALL {
        let e = write_program(&p, WriteOptions::new(t)).expect_err(t.name());
        assert_eq!(e.line, 5, "{}: {e}", t.name());
        assert!(e.message.contains("not above 0"), "{}: {e}", t.name());
    }
}
