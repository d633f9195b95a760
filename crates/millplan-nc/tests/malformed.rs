//! Bad input gives a located error, never a panic; unknown words are diagnostics.
//! The arbitrary-input properties stand in for a fuzzer and run in CI.

use millplan_geom::stl::read_stl;
use millplan_nc::{parse_program, ReadOptions};
use proptest::prelude::*;

fn err(src: &str) -> (u32, u32, String) {
    let e = parse_program(src, ReadOptions::default()).expect_err("must fail");
    (e.line, e.col, e.message)
}

#[test]
fn located_errors() {
    // Truncated GOTO.
    let (l, c, m) = err("UNITS/MM\nFEDRAT/100,MMPM\nGOTO/1.0,2.0\n");
    assert_eq!((l, c), (3, 6), "{m}");
    // Letters in a number.
    let (l, c, m) = err("UNITS/MM\nGOTO/1.0,2x.5,3\n");
    assert_eq!((l, c), (2, 10), "{m}");
    // G-code: malformed number, radius too short.
    let (l, _, _) = err("G21 G90\nT1 M6\nG1 X1..5 F100\n");
    assert_eq!(l, 3);
    let (l, _, m) = err("G21 G90\nT1 M6\nG0 X0 Y0\nG2 X10 Y0 R2 F100\n");
    assert_eq!(l, 4, "{m}");
    // Empty and blank files.
    assert!(parse_program("", ReadOptions::default()).is_err());
    assert!(parse_program("\n\n  \n", ReadOptions::default()).is_err());
    // Unfinished continuation, CIRCLE without end point, zero tool axis.
    assert_eq!(err("UNITS/MM\nGOTO/1,2,$\n").0, 2);
    assert_eq!(err("UNITS/MM\nGOTO/0,0,0\nCIRCLE/1,0,0,0,0,1,1\n").0, 3);
    assert_eq!(err("UNITS/MM\nGOTO/0,0,0,0,0,0\n").0, 2);
    // Heidenhain: arc without DR.
    assert_eq!(
        err("0 BEGIN PGM X MM\n1 L X+0 Y+0 Z+0 FMAX\n2 CC X+5 Y+0\n3 C X+10 Y+0\n").0,
        4
    );
}

#[test]
fn unknown_words_are_kept_and_reported() {
    let p = parse_program(
        "UNITS/MM\nFROBNICATE/1,2\nFEDRAT/100,MMPM\nGOTO/1,2,3\n",
        ReadOptions::default(),
    )
    .expect("reads");
    assert!(p
        .diagnostics
        .iter()
        .any(|d| d.code == millplan_nc::diag::Code::UnknownWord && d.line == 2));
    assert!(p.program.operations[0].events.iter().any(
        |e| matches!(&e.kind, millplan_nc::EventKind::Passthrough(p) if p.word == "FROBNICATE")
    ));
    let g =
        parse_program("G21\nT1 M6\nG1 X1 F100 FOOBAR\n", ReadOptions::default()).expect("reads");
    assert!(
        g.diagnostics
            .iter()
            .any(|d| d.code == millplan_nc::diag::Code::UnknownWord && d.line == 3 && d.col == 12),
        "{:?}",
        g.diagnostics
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn readers_never_panic_on_arbitrary_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let text = String::from_utf8_lossy(&bytes);
        let _ = parse_program(&text, ReadOptions::default());
        let _ = read_stl(&bytes);
    }

    #[test]
    fn readers_never_panic_on_nc_like_text(lines in proptest::collection::vec(
        "(GOTO/|CIRCLE/|FEDRAT/|G[0-3] |G1[7-9] |X|Y|Z|I|J|R|L |CC |C |NURBS/|KNOT/|CNTRL/|\\$\\$|;|\\(|F|S|M6|T|DR\\+|~|\\$)[-0-9.,A-Z ]{0,24}", 0..30)) {
        let text = lines.join("\n");
        let _ = parse_program(&text, ReadOptions::default());
        let _ = parse_program(&format!("0 BEGIN PGM X MM\n{text}"), ReadOptions::default());
        let _ = parse_program(&format!("G21\n{text}"), ReadOptions::default());
        let _ = parse_program(&format!("UNITS/MM\n{text}"), ReadOptions::default());
    }
}
