//! Blocks a reader cannot simulate, and what the writers make of them: frame
//! and offset changes, probing, macro calls and variables, block delete, cycles
//! from unknown heights, Heidenhain cycle and tool-call details, and the words
//! a writer must neither add nor drop. Each program is the smallest that
//! showed the fault; outputs are read back and compared with their source.

mod common;

use common::{read, write, Out};
use millplan_geom::DVec3;
use millplan_nc::diag::Code;
use millplan_nc::equiv::{compare, Tolerance};
use millplan_nc::write::Target;
use millplan_nc::{parse_program, EventKind, MoveKind, Program, ReadOptions};

fn parse(text: &str) -> Program {
    read(text, ReadOptions::default(), "program")
}

fn codes(text: &str) -> Vec<Code> {
    parse_program(text, ReadOptions::default())
        .expect("reads")
        .diagnostics
        .iter()
        .map(|d| d.code)
        .collect()
}

/// The text `t` writes; panics when refused.
fn out(p: &Program, t: Target) -> String {
    match write(p, t, false) {
        Out::Text(s, _) => s,
        Out::Refused(e) => panic!("{} refused: {e}", t.name()),
    }
}

/// Written into `t`, read back, and compared with the source.
fn equivalent(p: &Program, t: Target) -> String {
    let text = out(p, t);
    let q = parse(&text);
    if let Err(e) = compare(p, &q, &Tolerance::default()) {
        panic!("{} output differs: {e}\n{text}", t.name());
    }
    text
}

/// The lines of `text` after the first that contains `after`.
fn lines_after<'a>(text: &'a str, after: &str) -> Vec<&'a str> {
    text.lines()
        .skip_while(|l| !l.contains(after))
        .skip(1)
        .collect()
}

const G_TARGETS: [Target; 2] = [Target::Fanuc, Target::LinuxCnc];

#[test]
fn a_work_offset_change_restates_every_position() {
    let p = parse(
        "G21 G90 G17\nT1 M6\nG54\nG0 X10. Y10. C45.\nZ5.\nG1 Z-1. F100.\nG0 Z50.\nG55\nG0 X10. Y10. C45.\nZ5.\nM30\n",
    );
    // Both moves after G55 are moves: the numbers are the same, the place is not.
    let after: Vec<_> = p.operations[0]
        .moves
        .iter()
        .filter(|m| m.line >= 9)
        .collect();
    assert_eq!(after.len(), 2, "{after:?}");
    for t in G_TARGETS {
        let text = equivalent(&p, t);
        let rest = lines_after(&text, "G55");
        assert!(
            rest.first()
                .is_some_and(|l| l.contains("X10") && l.contains("Y10") && l.contains("C45")),
            "{}: {rest:?}",
            t.name()
        );
    }
}

#[test]
fn reselecting_the_active_work_offset_changes_nothing() {
    let p = parse("G21 G90\nT1 M6\nG54\nG0 X1. Y1. Z5.\nG54\nG0 Z10.\nM30\n");
    let m = &p.operations[0].moves[1];
    assert_eq!((m.end.x, m.end.y, m.end.z), (1.0, 1.0, 10.0));
}

#[test]
fn data_frame_probe_and_macro_blocks_are_kept_whole() {
    // The kept block, and whether every axis (not only the named ones) is unknown after it.
    let cases = [
        ("G10 L2 P1 X100. Y50. Z-200.", Code::FrameChange),
        ("G52 X10. Y10.", Code::FrameChange),
        ("G92 X0. Y0. Z0.", Code::FrameChange),
        ("G68 X0. Y0. R45", Code::FrameChange),
        ("G51 X0. Y0. P2", Code::FrameChange),
        ("G65 P9810 X50. Y50. Z-20. F1000", Code::UnknownPosition),
        ("G31 X50. Y1. Z30. F100", Code::UnknownPosition),
    ];
    for (block, code) in cases {
        let src = format!("G21 G90 G17 G94\nT1 M6\nG0 X1. Y1. Z30.\n{block}\nG0 X1. Y1. Z30.\nG1 Z-1. F200.\nM30\n");
        let p = parse(&src);
        assert!(codes(&src).contains(&code), "{block}: {:?}", codes(&src));
        // The move after it to the same numbers is a move, not dropped.
        let moves = &p.operations[0].moves;
        assert_eq!(moves.len(), 3, "{block}: {moves:?}");
        assert!(
            !p.operations[0].events.iter().any(|e| matches!(&e.kind,
                EventKind::Passthrough(x) if x.text != block)
                && e.line == 4),
            "{block}: split into several events"
        );
        // Copied as written into the dialect it came from; others refuse it.
        {
            let t = Target::Fanuc;
            let text = equivalent(&p, t);
            let rest = lines_after(&text, block);
            assert!(
                !rest.is_empty(),
                "{}: `{block}` not copied whole:\n{text}",
                t.name()
            );
            assert!(
                rest[0].contains("X1.") && rest[0].contains("Y1.") && rest[0].contains("Z30."),
                "{}: {block} then {:?}",
                t.name(),
                rest[0]
            );
        }
    }
}

#[test]
fn the_cancel_of_a_frame_change_restates_positions_but_a_header_cancel_does_not() {
    let p = parse("G21 G90 G69\nT1 M6\nG0 X1. Y1. Z5.\nG69\nG0 X1. Y1. Z6.\nM30\n");
    let m = &p.operations[0].moves[1];
    assert_eq!((m.end.x, m.end.y), (1.0, 1.0));
    let p = parse("G21 G90\nT1 M6\nG0 X1. Y1. Z5.\nG68 X0 Y0 R30.\nG0 X1. Y1. Z5.\nG69\nG0 X1. Y1. Z5.\nM30\n");
    assert_eq!(p.operations[0].moves.len(), 3);
}

#[test]
fn an_axis_from_a_macro_variable_is_kept_and_unknown_after() {
    let src = "G21 G90 G17 G94\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F100\n#100=50.\nG1 X#100\nG0 Z50.\nG0 X0 Y0\nM30\n";
    let p = parse(src);
    assert!(codes(src).contains(&Code::UnknownPosition));
    {
        let t = Target::Fanuc;
        let text = equivalent(&p, t);
        let rest = lines_after(&text, "X#100");
        assert!(
            rest.iter().any(|l| l.contains("X0.")),
            "{}: the move back to X0 is dropped:\n{text}",
            t.name()
        );
    }
}

#[test]
fn a_block_delete_block_is_kept_with_its_slash() {
    let src = "G21 G90 G17 G94\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F100\n/G1 X50.\nG0 Z50.\nX0 Y0\nM30\n";
    let p = parse(src);
    assert!(codes(src).contains(&Code::BlockDelete));
    {
        let t = Target::Fanuc;
        let text = equivalent(&p, t);
        let rest = lines_after(&text, "/G1 X50.");
        assert!(
            rest.iter().any(|l| l.contains("X0.")),
            "{}: X0 after the optional block dropped:\n{text}",
            t.name()
        );
    }
    // A block whose state would differ with the switch cannot be read either way.
    let e = parse_program(
        "G21 G90\nT1 M6\nG0 X0 Y0 Z5\n/G91 G0 X5.\nM30\n",
        ReadOptions::default(),
    )
    .expect_err("refused");
    assert_eq!((e.line, e.col), (4, 2), "{e}");
}

#[test]
fn what_comes_before_a_tool_change_stays_before_it() {
    let p = parse(
        "%\nO0100\nG21 G17 G90 G94 G40 G49 G80\nG91 G28 Z0.\nG90\n(FIRST TOOL)\nT5\nM6\nS2000 M3\nG0 X10. Y10.\nG43 H5 Z20.\nG1 Z-1. F200\nM30\n%\n",
    );
    for t in G_TARGETS {
        let text = equivalent(&p, t);
        let at = |s: &str| text.find(s).unwrap_or_else(|| panic!("{s} in\n{text}"));
        assert!(at("G28 Z0.") < at("M6"), "{}:\n{text}", t.name());
        assert!(at("(FIRST TOOL)") < at("M6"), "{}:\n{text}", t.name());
    }
}

#[test]
fn a_g98_cycle_from_an_unknown_height_is_kept_until_its_end() {
    let src = "G21 G90 G17\nT1 M6\nG54\nG55\nG98 G82 X25. Y21. Z-7. R3. F250. P5\nX30.\nG80\nG0 Z50.\nM30\n";
    let p = parse(src);
    assert!(codes(src).contains(&Code::UnknownPosition));
    let text = out(&p, Target::Fanuc);
    let rest = lines_after(&text, "G98 G82");
    assert!(rest[0].contains("X30."), "{text}");
    assert_eq!(
        rest[1], "G80",
        "the cycle must end where the source ends it:\n{text}"
    );
}

#[test]
fn writers_add_no_unit_word_to_a_unit_less_program() {
    let p = parse("T1 M6\nG0 X1. Y1. Z5.\nG1 Z0 F100.\nM30\n");
    for t in G_TARGETS {
        let text = equivalent(&p, t);
        assert!(
            !text.contains("G21") && !text.contains("G20"),
            "{}:\n{text}",
            t.name()
        );
    }
    let text = equivalent(&p, Target::Sinumerik);
    assert!(!text.contains("G71") && !text.contains("G64"), "{text}");
}

#[test]
fn a_fanuc_program_keeps_its_number() {
    let p = parse("%\nO1000\nG21 G90\nT1 M6\nG0 X1. Y1. Z5.\nM30\n%\n");
    let text = out(&p, Target::Fanuc);
    assert!(text.lines().any(|l| l == "O1000"), "{text}");
    // With its title beside it (it was written as `O0001 (1000CYCLETEST)`,
    // which stores the program under another number on the control).
    let p = parse("%\nO1000 (CYCLE TEST)\nG21 G90\nT1 M6\nG0 X1. Y1. Z5.\nM30\n%\n");
    let text = out(&p, Target::Fanuc);
    assert!(text.lines().any(|l| l == "O1000 (CYCLE TEST)"), "{text}");
    // A name that only starts with a digit is no program number.
    let p = parse("PARTNO 3D PART\nUNITS/MM\nLOADTL/1\nRAPID\nGOTO/1,1,5\nFINI\n");
    let text = out(&p, Target::Fanuc);
    assert!(text.lines().any(|l| l == "O0001 (3DPART)"), "{text}");
}

#[test]
fn g41_without_d_gets_no_invented_register() {
    let p = parse("G21 G90 G17 G94\nT5 M6\nG0 X-10 Y-10 Z5\nG1 Z-1 F100\nG41 G1 X0 Y0\nX50.\nG40 G1 X60. Y-10.\nM30\n");
    let text = equivalent(&p, Target::Fanuc);
    let g41 = text.lines().find(|l| l.contains("G41")).expect("G41");
    assert!(!g41.contains('D'), "{g41}");
    let p = parse(
        "G21 G90 G17 G94\nT5 M6\nG0 X-10 Y-10 Z5\nG1 Z-1 F100\nG41 D25 G1 X0 Y0\nX50.\nM30\n",
    );
    let text = equivalent(&p, Target::Fanuc);
    assert!(text.contains("G41 D25"), "{text}");
}

#[test]
fn a_leading_trafoof_is_written() {
    let p = parse("G71 G90\nT=\"EM10\"\nM6\nTRAFOOF\nG0 X1. Y1. Z5.\nM30\n");
    let text = out(&p, Target::Sinumerik);
    assert!(text.contains("TRAFOOF"), "{text}");
}

const HH_CYCLE: &str = "0 BEGIN PGM T MM
1 TOOL CALL 5 Z S3000 DL+0.1 DR-0.05
2 L Z+100 R0 FMAX M3
3 L X+0 Y+0 R0 FMAX
4 CYCL DEF 200 DRILLING ~
  Q200=+2 ;SET-UP CLEARANCE ~
  Q201=-10 ;DEPTH ~
  Q206=+150 ;FEED RATE FOR PLNGNG ~
  Q202=+10 ;PLUNGING DEPTH ~
  Q210=+0 ;DWELL TIME AT TOP ~
  Q203=+0 ;SURFACE COORDINATE ~
  Q204=+50 ;2ND SET-UP CLEARANCE ~
  Q211=+0 ;DWELL TIME AT DEPTH
5 L Z+2 FMAX
6 L X+0 Y+0 FMAX M89
7 L X+10 FMAX
8 L X+20 FMAX M99
9 L X+30 FMAX
10 M140 MB MAX F99999
11 L Z+100 FMAX M5
12 END PGM T MM
";

#[test]
fn heidenhain_cycles_keep_their_lines_and_end_at_the_second_set_up_clearance() {
    let p = parse(HH_CYCLE);
    let op = &p.operations[0];
    // M89 calls the cycle after every positioning block up to the M99.
    let holes: Vec<_> = op
        .moves
        .iter()
        .filter(|m| matches!(m.kind, MoveKind::Cycle(_)))
        .map(|m| m.end.x)
        .collect();
    assert_eq!(holes, [0.0, 10.0, 20.0]);
    // After a hole the tool stands at Q203 + Q204, so the move to X+10
    // runs at Z 50.
    let i = op
        .moves
        .iter()
        .position(|m| m.is_rapid() && m.end.x == 10.0)
        .expect("the move to X+10");
    assert_eq!(op.moves[i].end.z, 50.0);
    let text = equivalent(&p, Target::Heidenhain);
    for l in HH_CYCLE.lines().filter(|l| l.starts_with("  Q")) {
        assert!(text.lines().any(|w| w == l), "`{l}` lost:\n{text}");
    }
    assert!(
        text.contains("TOOL CALL 5 Z S3000 DL+0.1 DR-0.05"),
        "{text}"
    );
    assert!(text.contains("M140 MB MAX F99999"), "{text}");
    // The deltas and M140 have no G-code equivalent.
    assert!(matches!(write(&p, Target::Fanuc, false), Out::Refused(_)));
}

/// At its Q word (a user trial saw column 1), and a missing Q at the
/// block's Z.
#[test]
fn a_peck_of_zero_is_reported() {
    let src = "G21 G90 G17\nT1 M6\nG0 X0 Y0 Z10.\nG99 G83 X0 Y0 Z-3. R3. Q0 F250.\nG80\nM30\n";
    assert!(codes(src).contains(&Code::PeckDepth), "{:?}", codes(src));
    let at = |src: &str| {
        let d = parse_program(src, ReadOptions::default()).expect("reads");
        let p = d
            .diagnostics
            .iter()
            .find(|d| d.code == Code::PeckDepth)
            .expect("peck");
        (p.line, p.col)
    };
    assert_eq!(at(src), (4, 24));
    assert_eq!(at(&src.replace(" Q0", "")), (4, 15));
}

#[test]
fn apt_multax_off_turns_the_tool_vertical() {
    let p = parse(
        "PARTNO T\nUNITS/MM\nLOADTL/3\nFEDRAT/500,MMPM\nGOTO/0,0,10\nMULTAX/ON\nGOTO/3,3,0,0.1,0,0.995\nMULTAX/OFF\nGOTO/3,4,0\nFINI\n",
    );
    let op = &p.operations[0];
    let last = op.moves.last().expect("moves");
    let axis = op.axis(last).expect("an axis");
    assert!((axis - DVec3::Z).length() < 1e-12, "{axis:?}");
    let text = equivalent(&p, Target::Heidenhain);
    assert!(text.contains("TZ+1"), "{text}");
}

#[test]
fn sinumerik_definitions_lead_the_program_and_keep_their_commas() {
    let p = parse("N10 DEF REAL _A, _B=2 ; two\nN20 G71 G90\nN30 T=\"EM10\"\nN40 M6\nN50 G0 X=_B Y1 Z5\nN60 DEF INT _C\nM30\n");
    let text = equivalent(&p, Target::Sinumerik);
    let first_code = text
        .lines()
        .position(|l| !l.starts_with(';') && !l.starts_with("DEF"))
        .expect("code");
    let defs: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.starts_with("DEF"))
        .map(|(i, _)| i)
        .collect();
    assert_eq!(defs.len(), 2, "{text}");
    assert!(defs.iter().all(|i| *i < first_code), "{text}");
    assert!(text.contains("DEF REAL _A, _B=2"), "{text}");
}

#[test]
fn a_restated_apt_frame_neither_splits_the_operation_nor_ends_its_cycle() {
    let p = parse(
        "PARTNO T\nUNITS/MM\nLOAD/TOOL,15\nSPINDL/1000,RPM,CLW\nCSYS/1.,0,0,0,0,1.,0,0,0,0,1.,0\nRAPID/\nGOTO/10,10,100.\n\
         CYCLE/DRILL,FEDTO,7.65,MMPM,125.,RAPTO,3.,RTRCTO,100.\nGOTO/10,10,0\nGOTO/20,10,0\n\
         CSYS/1.,0,0,0,0,1.,0,0,0,0,1.,0\nGOTO/30,10,0\nFINI\n",
    );
    assert_eq!(p.operations.len(), 1);
    let holes = p.operations[0]
        .moves
        .iter()
        .filter(|m| matches!(m.kind, MoveKind::Cycle(_)))
        .count();
    assert_eq!(holes, 3);
}

/// Written in inches from millimetres, read back and compared.
fn in_inches(p: &Program, t: Target) -> String {
    let mut o = millplan_nc::write::WriteOptions::new(t);
    o.unit = Some(millplan_nc::LengthUnit::Inch);
    let (b, _) = millplan_nc::write::write_program(p, o).expect("written");
    let text = String::from_utf8(b).expect("UTF-8");
    let q = parse(&text);
    if let Err(e) = compare(p, &q, &Tolerance::default()) {
        panic!("{} in inches differs: {e}\n{text}", t.name());
    }
    text
}

#[test]
fn millimetres_written_in_inches_keep_small_steps_and_feeds_per_revolution() {
    // -0.1127 and -0.112 mm are the same to 4 places of an inch, not to the 5
    // written: the step in X was dropped.
    let p = parse(
        "G21 G90 G17 G94\nT1 M6\nG0 X-.1127 Y.048 Z1.7224\nG1 Y.0478 F10.\nX-.112 Y.0212\nX-.1123 Y.0089\n\
         G95 G1 X40. F0.1\nM30\n",
    );
    for t in [Target::Fanuc, Target::LinuxCnc, Target::Sinumerik] {
        let text = in_inches(&p, t);
        assert!(
            text.contains("0.003937"),
            "{}: F0.1 mm/rev:\n{text}",
            t.name()
        );
    }
    // The cycle definition is copied only in its own unit: in inches the
    // writer spells the holes out.
    let hh = HH_CYCLE
        .replace(" DL+0.1 DR-0.05", "")
        .replace("10 M140 MB MAX F99999", "10 L Z+80 FMAX");
    in_inches(&parse(&hh), Target::Heidenhain);
}

#[test]
fn cycle_lengths_agree_between_a_g98_source_and_every_output() {
    let p = parse(
        "%\nO2000\nG21 G17 G90 G94 G40 G49 G80\nT1 M6\nS1000 M3\nG54\nG0 X0. Y0.\nG43 H1 Z50.\n\
         G98 G81 X10. Y10. Z-5. R2. F100.\nX30. Y10.\nG80\nG0 Z50.\nM30\n%\n",
    );
    // Across at 50, down to R2, drill to -5, back to 50 (G98), twice:
    // √200 + 48 + 55 + 20 + 48 + 55 mm at rapid.
    let want = 200f64.sqrt() + 48.0 + 55.0 + 20.0 + 48.0 + 55.0;
    let rapid = |q: &Program| millplan_nc::stats::summarize(q, 10_000.0).rapid_mm;
    assert!((rapid(&p) - want).abs() < 1e-9, "{}", rapid(&p));
    for t in [
        Target::Fanuc,
        Target::LinuxCnc,
        Target::Sinumerik,
        Target::Heidenhain,
    ] {
        let q = parse(&equivalent(&p, t));
        assert!(
            (rapid(&q) - want).abs() < 1e-6,
            "{}: {}",
            t.name(),
            rapid(&q)
        );
    }
}

#[test]
fn block_numbers_stay_within_five_digits() {
    let mut src = String::from("G21 G90 G17 G94\nT1 M6\nG0 X0 Y0 Z5.\nG1 Z0 F100.\n");
    for i in 1..=10_500 {
        src.push_str(&format!("X{}.\n", i % 2));
    }
    src.push_str("M30\n");
    let p = parse(&src);
    for t in [Target::Fanuc, Target::LinuxCnc] {
        let mut o = millplan_nc::write::WriteOptions::new(t);
        o.line_numbers = true;
        let (b, _) = millplan_nc::write::write_program(&p, o).expect("written");
        let text = String::from_utf8(b).expect("UTF-8");
        let longest = text
            .lines()
            .filter_map(|l| l.strip_prefix('N'))
            .map(|l| l.bytes().take_while(u8::is_ascii_digit).count())
            .max();
        assert_eq!(longest, Some(5), "{}", t.name());
        let q = parse(&text);
        compare(&p, &q, &Tolerance::default()).expect("the same program");
    }
}

#[test]
fn heidenhain_cycle_values_that_are_not_numbers_are_located() {
    for (src, line) in [
        ("0 BEGIN PGM T MM\n1 TOOL CALL 5 Z S3000\n2 CYCL DEF 1.0 PECKING\n3 CYCL DEF 1.5 F-inf\n4 END PGM T MM\n", 4),
        ("0 BEGIN PGM T MM\n1 TOOL CALL 5 Z S3000\n2 CYCL DEF 200 DRILLING ~\n-inf\n3 END PGM T MM\n", 3),
    ] {
        let e = parse_program(src, ReadOptions::default()).expect_err("refused");
        assert_eq!(e.line, line, "{e}");
    }
    // No value at all, or a word, is still read.
    parse("0 BEGIN PGM T MM\n1 TOOL CALL 5 Z S3000\n2 CYCL DEF 1.0 PECKING\n3 CYCL DEF 1.4 DWELL\n4 CYCL DEF 200 DRILLING ~\n  Q206=FAUTO ;FEED ~\n  Q201=-5\n5 END PGM T MM\n");
}
