//! Path-control modes (exact stop, blending with a tolerance, look-ahead and
//! smoothing functions): each dialect's words read into the IR's
//! `EventKind::PathControl`, written back by every writer that can say them
//! (refused at their line otherwise, a comment under `--lossy`), and read
//! back the same.

use millplan_nc::write::{write_program, Target, WriteOptions};
use millplan_nc::*;

fn read(src: &str) -> Program {
    parse_program(src, ReadOptions::default())
        .unwrap_or_else(|e| panic!("{e}\n{src}"))
        .program
}

/// The path-control events of a program, in order, with the index of the
/// move each precedes.
fn modes(p: &Program) -> Vec<(usize, PathControl)> {
    p.operations
        .iter()
        .flat_map(|o| o.events.iter())
        .filter_map(|e| match e.kind {
            EventKind::PathControl(pc) => Some((e.at as usize, pc)),
            _ => None,
        })
        .collect()
}

fn write(p: &Program, t: Target, lossy: bool) -> Result<String, write::WriteError> {
    let mut o = WriteOptions::new(t);
    o.lossy = lossy;
    write_program(p, o).map(|(b, _)| String::from_utf8(b).expect("utf8"))
}

/// Writes `p` for `t` and reads it back: the same path-control events.
fn round_trip(p: &Program, t: Target) -> String {
    let text = write(p, t, false).unwrap_or_else(|e| panic!("{t:?}: {e}"));
    let back = read(&text);
    assert_eq!(modes(&back), modes(p), "{t:?}:\n{text}");
    text
}

const BLEND: PathControl = PathControl::Blend { tolerance: None };

fn blend(t: f64) -> PathControl {
    PathControl::Blend { tolerance: Some(t) }
}

#[test]
fn linuxcnc_exact_stop_and_blending_with_tolerance() {
    let p = read(
        "G21 G90\nG61\nG1 X10 F600\nG61.1\nG1 X20\nG64\nG1 Y10\nG64 P0.05\nG1 X0\nG64 P0.01 Q0.01\nG1 Y0\nM2\n",
    );
    assert_eq!(p.source, Dialect::LinuxCnc);
    assert_eq!(
        modes(&p),
        vec![
            (0, PathControl::ExactStop),
            (1, PathControl::ExactStop),
            (2, BLEND),
            (3, blend(0.05)),
            (4, blend(0.01)),
        ]
    );
    let text = round_trip(&p, Target::LinuxCnc);
    assert!(text.contains("G64 P0.05"), "{text}");
    // Sinumerik says the tolerance with G642 CTOL=, Heidenhain with cycle 32.
    let text = round_trip(&p, Target::Sinumerik);
    assert!(
        text.contains("G642 CTOL=0.05") && text.contains("G60"),
        "{text}"
    );
    // Fanuc has no programmable blend tolerance, Heidenhain no exact stop:
    // refused at the line, a comment under --lossy.
    for t in [Target::Fanuc, Target::Heidenhain, Target::Apt] {
        let e = write(&p, t, false).expect_err("refused");
        assert!(e.to_string().contains("path-control"), "{t:?}: {e}");
        let text = write(&p, t, true).expect("lossy");
        assert!(text.contains("path control"), "{t:?}:\n{text}");
    }
}

#[test]
fn inch_tolerance_reads_in_mm_and_writes_in_the_output_unit() {
    let p = read("G20 G90\nG64 P0.001\nG1 X1 F10\nM2\n");
    assert_eq!(modes(&p), vec![(0, blend(0.0254))]);
    let text = round_trip(&p, Target::LinuxCnc);
    assert!(text.contains("G64 P0.001"), "{text}");
}

#[test]
fn fanuc_exact_stop_once_and_look_ahead_functions() {
    let p = read(
        "%\nO0001\nG21 G90\nG05.1 Q1\nG08 P1\nG61\nG1 X10 F600\nG09 G1 X20\nG64\nG1 Y10\nG08 P0\nG05.1 Q0\nG1 Y0\nM30\n%\n",
    );
    assert_eq!(p.source, Dialect::Fanuc);
    let ai = |on| PathControl::Smoothing {
        kind: Smoothing::AiContour,
        on,
    };
    let la = |on| PathControl::Smoothing {
        kind: Smoothing::LookAhead,
        on,
    };
    assert_eq!(
        modes(&p),
        vec![
            (0, ai(true)),
            (0, la(true)),
            (0, PathControl::ExactStop),
            (1, PathControl::StopOnce),
            (2, BLEND),
            (3, la(false)),
            (3, ai(false)),
        ]
    );
    let text = round_trip(&p, Target::Fanuc);
    // The one-block exact stop stays in its move's block.
    assert!(
        text.lines().any(|l| l.contains("G9 ") && l.contains("X20")),
        "{text}"
    );
    // Sinumerik has G9 and G60, but no Fanuc AI contour.
    assert!(write(&p, Target::Sinumerik, false).is_err());
}

#[test]
fn sinumerik_modes_with_their_tolerances() {
    let p = read(
        "G71 G90\nSOFT\nG60\nG1 X10 F600\nG9 X20\nG64\nG1 Y10\nG641 ADIS=0.2\nG1 X0\nCTOL=0.03 G642\nG1 Y0\nCYCLE832(0.01,1,1)\nG1 X5\nCYCLE832(0,0,1)\nBRISK\nG1 X6\nM30\n",
    );
    assert_eq!(p.source, Dialect::Sinumerik);
    assert_eq!(
        modes(&p),
        vec![
            (0, PathControl::Soft(true)),
            (0, PathControl::ExactStop),
            (1, PathControl::StopOnce),
            (2, BLEND),
            (3, blend(0.2)),
            (4, blend(0.03)),
            (
                5,
                PathControl::Smoothing {
                    kind: Smoothing::HighSpeed { tolerance: 0.01 },
                    on: true
                }
            ),
            (
                6,
                PathControl::Smoothing {
                    kind: Smoothing::HighSpeed { tolerance: 0.0 },
                    on: false
                }
            ),
            (6, PathControl::Soft(false)),
        ]
    );
    let text = round_trip(&p, Target::Sinumerik);
    assert!(
        text.contains("CYCLE832(0.01,1,1)") && text.contains("SOFT"),
        "{text}"
    );
    // LinuxCNC has exact stop and blending, not SOFT, G9 or CYCLE832.
    assert!(write(&p, Target::LinuxCnc, false).is_err());
    let lossy = write(&p, Target::LinuxCnc, true).expect("lossy");
    let back = read(&lossy);
    let kept: Vec<PathControl> = modes(&back).into_iter().map(|m| m.1).collect();
    assert_eq!(
        kept,
        vec![PathControl::ExactStop, BLEND, blend(0.2), blend(0.03)],
        "{lossy}"
    );
}

#[test]
fn heidenhain_tolerance_cycle() {
    let p = read(
        "0 BEGIN PGM T MM\n1 CYCL DEF 32.0 TOLERANCE\n2 CYCL DEF 32.1 T0.02\n3 L X+10 Y+0 F600\n4 CYCL DEF 32.0 TOLERANCE\n5 CYCL DEF 32.1\n6 L X+20\n7 END PGM T MM\n",
    );
    assert_eq!(p.source, Dialect::Heidenhain);
    assert_eq!(modes(&p), vec![(0, blend(0.02)), (1, BLEND)]);
    let text = round_trip(&p, Target::Heidenhain);
    assert!(text.contains("CYCL DEF 32.1 T0.02"), "{text}");
    round_trip(&p, Target::LinuxCnc);
    round_trip(&p, Target::Sinumerik);
    // A tolerance cycle without a number is refused at its line.
    let e = parse_program(
        "0 BEGIN PGM T MM\n1 CYCL DEF 32.1 Tx\n2 END PGM T MM\n",
        ReadOptions::default(),
    )
    .expect_err("bad tolerance");
    assert_eq!(e.line, 2, "{e}");
}

#[test]
fn text_form_keeps_every_mode() {
    let src = "G21 G90\nG61\nG1 X10 F600\nG64 P0.05\nG1 X0\nM2\n";
    let p = read(src);
    let t = text::print(&p);
    assert!(
        t.contains("path exact-stop") && t.contains("path blend tol=0.05"),
        "{t}"
    );
    let back = text::parse(&t).expect("parses");
    assert_eq!(modes(&back), modes(&p));
    for pc in [
        PathControl::StopOnce,
        PathControl::Soft(true),
        PathControl::Smoothing {
            kind: Smoothing::HighSpeed { tolerance: 0.01 },
            on: true,
        },
        PathControl::Smoothing {
            kind: Smoothing::AiContour,
            on: false,
        },
    ] {
        let mut q = p.clone();
        q.operations[0].events.insert(
            0,
            Event {
                at: 0,
                line: 1,
                kind: EventKind::PathControl(pc),
            },
        );
        let back = text::parse(&text::print(&q)).expect("parses");
        assert_eq!(modes(&back), modes(&q));
    }
}
