//! KUKA KRL spline motions (KSS 8.x `SPLINE` … `ENDSPLINE` blocks of `SPL`,
//! `SLIN`, `SCIRC` segments): the reader, the writer's `--krl-motion
//! spline`, the round trips LIN and SPLINE, sub-programs that no block
//! straddles, and located errors.

use millplan_geom::DVec3;
use millplan_nc::krl::{self, Approx, KrlPos, Motion, Statement};
use millplan_nc::write::krl::{check, from_ir, split, write, KrlMotion, KrlOptions};
use millplan_nc::*;

mod shared_data;

fn no_subs(_: &str) -> Option<String> {
    None
}

/// The motions of a program: (motion, approximation, speed, WITH options).
fn moves(p: &krl::KrlProgram) -> Vec<(Motion, Approx, Option<f64>, Vec<String>)> {
    p.statements
        .iter()
        .filter_map(|l| match &l.statement {
            Statement::Move {
                motion,
                approx,
                vel_cp,
                with,
            } => Some((motion.clone(), *approx, *vel_cp, with.clone())),
            _ => None,
        })
        .collect()
}

fn end(m: &Motion) -> KrlPos {
    *m.end().expect("a known end")
}

/// A zigzag of `rows` rows of `per_row` cutting points 0.3 mm apart, a
/// rapid between rows, two feeds: one `PTP`, then `LIN`s.
fn zigzag(rows: usize, per_row: usize) -> Program {
    let mut apt = String::from("CUTTER/10\nGOTO/0,0,5,0,0,1\n");
    for r in 0..rows {
        let y = r as f64 * 2.0;
        apt.push_str(&format!(
            "RAPID\nGOTO/0,{y:.1},5,0,0,1\nGOTO/0,{y:.1},-1,0,0,1\n"
        ));
        apt.push_str(if r % 2 == 0 {
            "FEDRAT/1120\n"
        } else {
            "FEDRAT/900\n"
        });
        for i in 1..=per_row {
            let z = -1.0 + 0.01 * (i % 7) as f64;
            apt.push_str(&format!("GOTO/{:.1},{y:.1},{z:.2},0,0,1\n", i as f64 * 0.3));
        }
    }
    parse_program(&apt, ReadOptions::default())
        .expect("apt")
        .program
}

fn spline(max_points: usize) -> KrlOptions {
    KrlOptions {
        name: "zz".into(),
        max_points,
        motion: KrlMotion::Spline,
        ..KrlOptions::default()
    }
}

fn read_files(files: &[(String, String)]) -> krl::KrlProgram {
    let mut resolve = |n: &str| {
        files
            .iter()
            .find(|f| f.0.eq_ignore_ascii_case(n))
            .map(|f| f.1.clone())
    };
    krl::read(&files[0].1, &mut resolve).expect("reads back")
}

/// LIN and SPLINE written from the same toolpath read back to the same
/// poses and speeds, the LINs as `SPL` segments; a run of approximated
/// moves is one block, the rapids and the approach stay `LIN`/`PTP`.
#[test]
fn lin_and_spline_round_trips_keep_poses_and_speeds() {
    let prog = zigzag(3, 20);
    let k = from_ir(&prog, &KrlOptions::default()).expect("krl");
    let lin = &write(&k, &KrlOptions::default())[0].1;
    let files = write(&k, &spline(0));
    assert_eq!(files.len(), 1);
    let text = &files[0].1;
    check(&k, &files).expect("read back within the digits written");
    // Two blocks a row: the plunge ends exactly where the row turns off
    // it (a spline would swing below the row there), then the row.
    assert_eq!(text.matches("\nSPLINE\n").count(), 6, "{text}");
    assert_eq!(text.matches("\nENDSPLINE\n").count(), 6, "{text}");
    // Each row's plunge and its 20 points.
    assert_eq!(text.lines().filter(|l| l.starts_with("SPL ")).count(), 63);
    assert!(!text.contains("C_DIS"), "{text}");
    let (a, b) = (
        moves(&krl::read(lin, &mut no_subs).expect("LIN reads")),
        moves(&krl::read(text, &mut no_subs).expect("SPLINE reads")),
    );
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(end(&x.0), end(&y.0));
        assert_eq!(x.2, y.2, "speed of {:?}", y.0);
        match (&x.0, &y.0) {
            // Approximated LINs and the exact one ending their run.
            (Motion::Lin(_), Motion::Spl(_)) => assert_eq!(y.1, Approx::Exact),
            // The rapids and the approach.
            (Motion::Lin(_), Motion::Lin(_)) | (Motion::Ptp(_), Motion::Ptp(_)) => {
                assert_eq!((x.1, y.1), (Approx::Exact, Approx::Exact))
            }
            (p, q) => panic!("{p:?} written as {q:?}"),
        }
    }
    // Into the IR both are the same toolpath.
    let ir = |t: &str| {
        krl::read(t, &mut no_subs)
            .expect("reads")
            .to_ir(1.0, false)
            .expect("ir")
            .program
    };
    let (p, q) = (ir(lin), ir(text));
    let (p, q) = (&p.operations[0].moves, &q.operations[0].moves);
    assert_eq!(p.len(), q.len());
    for (m, n) in p.iter().zip(q) {
        assert_eq!((m.end, m.kind, m.feed), (n.end, n.kind, n.feed));
    }
}

/// A feed change inside a run is the segment's own `WITH $VEL.CP`, and the
/// program's `$VEL.CP` after the block is the one it had set.
#[test]
fn a_feed_change_inside_a_run_is_a_segment_speed() {
    let src = "DEF f()\nPTP {X 0, Y 0, Z 0, A 0, B 90, C 0}\n$VEL.CP = 0.02\n\
LIN {X 1, Y 0, Z 0, A 0, B 90, C 0} C_DIS\n$VEL.CP = 0.01\n\
LIN {X 2, Y 0, Z 0, A 0, B 90, C 0} C_DIS\nLIN {X 3, Y 0, Z 0, A 0, B 90, C 0}\n\
LIN {X 3, Y 0, Z 5, A 0, B 90, C 0}\nEND\n";
    let k = krl::read(src, &mut no_subs).expect("reads");
    let files = write(&k, &spline(0));
    check(&k, &files).expect("same motions");
    let t = &files[0].1;
    assert!(t.contains("SPL {X 2.000, Y 0.000, Z 0.000, A 0.0000, B 90.0000, C 0.0000} WITH $VEL.CP = 0.010000\n"), "{t}");
    assert!(
        t.contains("ENDSPLINE\n$VEL.CP = 0.010000\nLIN {X 3.000, Y 0.000, Z 5.000"),
        "{t}"
    );
    let speeds: Vec<Option<f64>> = moves(&read_files(&files)).iter().map(|m| m.2).collect();
    assert_eq!(
        speeds,
        [None, Some(0.02), Some(0.01), Some(0.01), Some(0.01)]
    );
}

/// Sub-programs hold as many motions as with LIN; no SPLINE block
/// straddles two files: one cut by a file's end closes with `C_SPL` there
/// and opens again in the next; read back through the main, the poses and
/// speeds are those written.
#[test]
fn sub_programs_split_as_lin_and_no_block_straddles() {
    let prog = zigzag(4, 25);
    let k = from_ir(&prog, &KrlOptions::default()).expect("krl");
    let lin = write(
        &k,
        &KrlOptions {
            max_points: 17,
            ..spline(17)
        }
        .with_lin(),
    );
    let spl = write(&k, &spline(17));
    assert!(spl.len() > 3);
    let count = |t: &str| {
        t.lines()
            .filter(|l| {
                ["LIN ", "PTP ", "SPL ", "SCIRC "]
                    .iter()
                    .any(|w| l.starts_with(w))
            })
            .count()
    };
    let names = |f: &[(String, String)]| f.iter().map(|x| x.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&lin), names(&spl));
    for ((_, a), (name, b)) in lin.iter().zip(&spl) {
        assert_eq!(count(a), count(b), "{name}");
        let opened = b.lines().filter(|l| *l == "SPLINE").count();
        let closed = b.lines().filter(|l| l.starts_with("ENDSPLINE")).count();
        assert_eq!(opened, closed, "{name}: {b}");
    }
    assert!(spl.iter().any(|f| f.1.contains("ENDSPLINE C_SPL\nEND\n")));
    check(&k, &spl).expect("read back");
    let back = moves(&read_files(&spl));
    assert_eq!(back.len(), moves(&k).len());
    for (x, y) in moves(&k).iter().zip(&back) {
        assert!((end(&x.0).xyz - end(&y.0).xyz).abs().max_element() <= 5e-4);
        assert!((x.2.unwrap_or(0.0) - y.2.unwrap_or(0.0)).abs() <= 5e-7);
    }
    // A program read with its own blocks, split through one of them.
    let text = &write(&k, &spline(0))[0].1;
    let files = split(
        text,
        &KrlOptions {
            motion: KrlMotion::Lin,
            ..spline(10)
        },
    )
    .expect("splits");
    for (name, t) in &files {
        let opened = t.lines().filter(|l| *l == "SPLINE").count();
        let closed = t.lines().filter(|l| l.starts_with("ENDSPLINE")).count();
        assert_eq!(opened, closed, "{name}: {t}");
        assert!(
            !t.contains("SPLINE\nENDSPLINE"),
            "an empty block in {name}: {t}"
        );
    }
}

trait WithLin {
    fn with_lin(self) -> Self;
}

impl WithLin for KrlOptions {
    fn with_lin(self) -> Self {
        KrlOptions {
            motion: KrlMotion::Lin,
            ..self
        }
    }
}

/// A SPLINE program as written by hand on a KSS 8 controller: FOLDs,
/// comments, lower case, `WITH $VEL = SVEL_CP(…)`, a block's `WITH
/// $VEL.CP`, an option not modelled (kept and named), `E6POS:`, `SCIRC`,
/// `TRIGGER`, a lone `SLIN … C_SPL`.
const HAND: &str = "&ACCESS RVP\r
&REL 3\r
DEF hand( )\r
;FOLD INI;%{PE}\r
  BAS (#INITMOV,0 )\r
;ENDFOLD (INI)\r
$TOOL = TOOL_DATA[1]\r
$BASE = BASE_DATA[2]\r
PTP {A1 0, A2 -90, A3 90, A4 0, A5 0, A6 0}\r
$VEL.CP = 0.05\r
SLIN {X 100, Y 0, Z 50, A 0, B 90, C 0} C_SPL\r
SPLINE WITH $VEL.CP = 0.2 ; the block's speed\r
  ;FOLD SPL P1\r
  spl {E6POS: X 100, Y 10, Z 50, A 0, B 90, C 0, E1 5.5}\r
  ;ENDFOLD\r
  TRIGGER WHEN DISTANCE=0 DELAY=0 DO $OUT[3]=TRUE\r
  SPL {X 110, Y 20, Z 50, A 0, B 90, C 0} WITH $VEL = SVEL_CP(0.3, , LCPDAT1)\r
  SLIN {X 120, Y 20, Z 50, A 0, B 90, C 0} WITH $ACC = {CP 2.0, ORI1 200, ORI2 200}, $VEL.CP=0.1\r
  SCIRC {X 130, Y 30, Z 50, A 0, B 90, C 0}, {X 140, Y 20, Z 50, A 0, B 90, C 0}\r
ENDSPLINE C_SPL\r
SLIN {POS: X 140, Y 0, Z 80, A 0, B 90, C 0}\r
END\r
";

#[test]
fn a_hand_written_spline_program_reads() {
    let p = krl::read(HAND, &mut no_subs).expect("reads");
    let m = moves(&p);
    assert_eq!(m.len(), 7);
    assert!(matches!(m[1].0, Motion::Slin(_)) && m[1].1 == Approx::Spl);
    assert_eq!(m[1].2, Some(0.05));
    let Motion::Spl(p1) = &m[2].0 else {
        panic!("{:?}", m[2])
    };
    assert_eq!(
        (p1.xyz, p1.e[0]),
        (DVec3::new(100.0, 10.0, 50.0), Some(5.5))
    );
    let speeds: Vec<Option<f64>> = m.iter().map(|x| x.2).collect();
    // The block's 0.2 but where a segment has its own; after it, 0.05 again.
    assert_eq!(
        speeds,
        [
            None,
            Some(0.05),
            Some(0.2),
            Some(0.3),
            Some(0.1),
            Some(0.2),
            Some(0.05)
        ]
    );
    assert_eq!(m[3].3, ["$VEL = SVEL_CP(0.3, , LCPDAT1)"]);
    assert_eq!(m[4].3, ["$ACC = {CP 2.0, ORI1 200, ORI2 200}"]);
    assert!(matches!(m[5].0, Motion::Scirc { .. }));
    // The option not modelled is named, at its line; SVEL_CP is read.
    assert_eq!(p.warnings.len(), 1, "{:?}", p.warnings);
    assert_eq!(
        (p.warnings[0].1, p.warnings[0].2.contains("$ACC")),
        (18, true)
    );
    assert!(p
        .statements
        .iter()
        .any(|l| matches!(&l.statement, Statement::Verbatim(t) if t.starts_with("TRIGGER"))));
    assert!(p
        .statements
        .iter()
        .any(|l| l.statement == Statement::SplineEnd(true)));
    // Into the IR: straight moves to the segments' points, an arc, the
    // speeds as feeds, the warning a finding.
    let parsed = p.to_ir(1000.0, true).expect("ir");
    verify::verify(&parsed.program).expect("verifies");
    let op = &parsed.program.operations[0];
    assert_eq!(op.moves.len(), 6);
    assert!(matches!(op.moves[4].kind, MoveKind::Arc(_)));
    assert!((op.moves[2].feed - 0.3 * 60_000.0).abs() < 1e-9);
    assert!(parsed
        .diagnostics
        .iter()
        .any(|d| d.message.contains("hand:18") && d.message.contains("$ACC")));
    // KRL → KRL keeps the blocks, options and speeds as read.
    let files = write(
        &p,
        &KrlOptions {
            name: "hand".into(),
            ..KrlOptions::default()
        },
    );
    check(&p, &files).expect("same motions");
    let again = krl::read(&files[0].1, &mut no_subs).expect("re-reads");
    assert_eq!(moves(&again), m);
    assert!(files[0].1.contains("SPLINE\n"), "{}", files[0].1);
    assert!(files[0].1.contains("ENDSPLINE C_SPL\n"), "{}", files[0].1);
    assert!(
        files[0].1.contains("TRIGGER WHEN DISTANCE=0"),
        "{}",
        files[0].1
    );
}

/// Malformed spline lines: errors at their line and column.
#[test]
fn malformed_spline_lines_are_located() {
    let at = |body: &str| {
        let src = format!("DEF bad()\n{body}\nEND\n");
        let e = krl::read(&src, &mut no_subs).expect_err(body);
        (e.error.line, e.error.col, e.error.message)
    };
    let block = |seg: &str| format!("SPLINE\n{seg}\nENDSPLINE");
    let (l, c, m) = at("  SPL {X 1, Y 2, Z 3}");
    assert_eq!((l, c), (2, 3), "{m}");
    assert!(m.contains("outside a SPLINE block"), "{m}");
    let (l, c, m) = at(&block("SPL {X 1, Y two, Z 3}"));
    assert_eq!((l, c), (3, 11), "{m}");
    let (l, c, m) = at(&block("SPL {X 1, Y 2, Z 3} WITH $VEL.CP = fast"));
    assert_eq!((l, c), (3, 36), "{m}");
    let (l, c, m) = at(&block("SPL {X 1, Y 2, Z 3} C_FOO"));
    assert_eq!((l, c), (3, 21), "{m}");
    let (l, c, m) = at(&block("SPL {X 1, Y 2, Z 3} WITH $ACC"));
    assert_eq!((l, c), (3, 26), "{m}");
    let (l, c, m) = at(&block("SCIRC {X 1, Y 2, Z 3}"));
    assert_eq!((l, c), (3, 7), "{m}");
    let (l, c, m) = at(&block("  LIN {X 1, Y 2, Z 3}"));
    assert_eq!((l, c), (3, 3), "{m}");
    assert!(m.contains("opened at line 2"), "{m}");
    let (l, _, m) = at(&block("$VEL.CP = 0.1"));
    assert_eq!(l, 3, "{m}");
    let (l, _, m) = at(&block("SPLINE"));
    assert_eq!(l, 3, "{m}");
    let (l, c, m) = at("SPLINE\nSPL {X 1, Y 2, Z 3}\nENDSPLINE C_DIS");
    assert_eq!((l, c), (4, 11), "{m}");
    let (l, _, m) = at("ENDSPLINE");
    assert_eq!(l, 2, "{m}");
    let (l, _, m) = at("SPLINE\nSPL {X 1, Y 2, Z 3}");
    assert_eq!(l, 2, "{m}");
    assert!(m.contains("not closed"), "{m}");
    let (l, c, m) = at(&block("SPL XP1"));
    assert_eq!((l, c), (3, 5), "{m}");
}

/// The PowerMILL sample's sub-program (6000 LINs with E1) written as
/// SPLINE blocks reads back to the same poses and E1.
#[test]
fn powermill_sub_program_as_spline() {
    let Some(path) = shared_data::file("kuka-krl-powermill-ballnose/f1_Kuka_APT202T02S02.SRC")
    else {
        return;
    };
    let src = std::fs::read_to_string(path).expect("reads");
    let k = krl::read(&src, &mut no_subs).expect("reads");
    let files = write(
        &k,
        &KrlOptions {
            name: "s02".into(),
            ..spline(2500)
        },
    );
    check(&k, &files).expect("same motions");
    let back = moves(&read_files(&files));
    let orig = moves(&k);
    assert_eq!(back.len(), orig.len());
    let mut spl = 0;
    for (x, y) in orig.iter().zip(&back) {
        if let Motion::PtpOther(t) = &x.0 {
            assert_eq!(y.0, Motion::PtpOther(t.clone()));
            continue;
        }
        assert_eq!((end(&x.0).xyz, end(&x.0).e), (end(&y.0).xyz, end(&y.0).e));
        spl += usize::from(matches!(y.0, Motion::Spl(_)));
    }
    assert!(spl > 5900, "{spl} SPL segments");
    // Blocks of at most SPLINE_SEGMENTS_MAX segments, a long run going on
    // in the next (approximated).
    let mut longest = 0;
    for (_, t) in &files {
        let mut n = 0;
        for l in t.lines() {
            n = if l == "SPLINE" {
                0
            } else {
                n + usize::from(l.starts_with("SPL "))
            };
            longest = longest.max(n);
        }
    }
    // PowerMILL's passes end in turns a spline would swing through: each
    // ends its block exactly, well before the cap.
    assert!(longest > 20 && longest <= millplan_nc::write::krl::SPLINE_SEGMENTS_MAX);
}

/// A run longer than [`SPLINE_SEGMENTS_MAX`] segments goes on, approximated,
/// in the next block.
#[test]
fn a_long_run_is_cut_into_blocks_of_the_cap() {
    let k = from_ir(&zigzag(1, 2500), &KrlOptions::default()).expect("krl");
    let files = write(&k, &spline(0));
    check(&k, &files).expect("the same motions");
    let t = &files[0].1;
    let mut sizes = Vec::new();
    let mut n = 0;
    for l in t.lines() {
        if l == "SPLINE" {
            n = 0;
        } else if l.starts_with("SPL ") {
            n += 1;
        } else if l.starts_with("ENDSPLINE") {
            sizes.push((n, l.to_string()));
        }
    }
    let cap = millplan_nc::write::krl::SPLINE_SEGMENTS_MAX;
    // The plunge, then the row of 2,500 points in blocks of the cap.
    assert_eq!(
        sizes,
        [
            (1, "ENDSPLINE".to_string()),
            (cap, "ENDSPLINE C_SPL".to_string()),
            (cap, "ENDSPLINE C_SPL".to_string()),
            (2500 - 2 * cap, "ENDSPLINE".to_string())
        ],
        "{t}"
    );
}

/// Programs of random motions (approximated or exact LINs and CIRCs, PTPs,
/// named PTPs), speed changes, comments and calls, written as SPLINE in
/// one file and in sub-programs of random sizes: every file reads back
/// (the reader refuses a block holding anything but segments, `TRIGGER`
/// and comments, a nested, unclosed or empty-ended one), the motions are
/// those written, the files hold the motions LIN output holds, and each
/// file's blocks open and close in it.
#[test]
fn random_programs_split_into_valid_spline_files() {
    let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = |n: u64| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed % n
    };
    let (mut cut_blocks, mut scirc) = (0, 0);
    for case in 0..300 {
        let mut src = String::from("DEF r()\nPTP {X 0, Y 0, Z 5, A 0, B 90, C 0}\n");
        let len = 1 + next(40);
        for i in 0..len {
            let x = i as f64 + 1.0;
            let tag = if next(3) == 0 { "" } else { " C_DIS" };
            let line = match next(12) {
                0 => format!("$VEL.CP = 0.0{}\n", 1 + next(9)),
                1 => "; a comment\n".to_string(),
                2 => "SetRPM(8000)\n".to_string(),
                3 => format!("PTP {{X {x}, Y 9, Z 5, A 0, B 90, C 0}}\n"),
                4 => "PTP XHOME\n".to_string(),
                5 => format!(
                    "CIRC {{X {x}, Y 1, Z 0, A 0, B 90, C 0}}, {{X {}, Y 0, Z 0, A 0, B 90, C 0}}{tag}\n",
                    x + 0.5
                ),
                _ => format!("LIN {{X {x}, Y 0, Z 0, A 0, B 90, C 0, E1 {}}}{tag}\n", next(360)),
            };
            src.push_str(&line);
        }
        src.push_str("END\n");
        let k = krl::read(&src, &mut no_subs).expect("the source reads");
        let max_points = [0, 1, 2, 3, 5, 8][next(6) as usize];
        let o = KrlOptions {
            name: "r".into(),
            ..spline(max_points)
        };
        let files = write(&k, &o);
        check(&k, &files).unwrap_or_else(|e| panic!("case {case}: {e}\n{src}\n{files:#?}"));
        let lin = write(&k, &o.clone().with_lin());
        assert_eq!(lin.len(), files.len(), "case {case}");
        let count = |t: &str| {
            let words = ["LIN ", "PTP ", "CIRC ", "SPL ", "SCIRC "];
            t.lines()
                .filter(|l| words.iter().any(|w| l.starts_with(w)))
                .count()
        };
        for ((_, a), (name, b)) in lin.iter().zip(&files) {
            assert_eq!(count(a), count(b), "case {case}, {name}");
            krl::read(b, &mut no_subs)
                .unwrap_or_else(|e| panic!("case {case}, {name}: {e:?}\n{b}"));
            assert!(
                !b.contains("SPLINE\nENDSPLINE"),
                "case {case}, {name}: an empty block\n{b}"
            );
            cut_blocks += usize::from(b.ends_with("ENDSPLINE C_SPL\nEND\n"));
            scirc += b.matches("\nSCIRC ").count();
        }
    }
    // The cases reached what they are for: blocks cut at a file's end, arcs.
    assert!(
        cut_blocks > 50 && scirc > 50,
        "{cut_blocks} blocks cut, {scirc} SCIRC"
    );
}

/// `SPTP` is a motion: to a Cartesian target a positioning move of the
/// toolpath (not a line kept aside, after which the next move would start
/// from the wrong place); to joint angles a motion whose end is not known.
/// KRL → KRL writes both back as `SPTP`.
#[test]
fn sptp_is_a_positioning_move() {
    let src = "DEF s()\nSPTP {X 10, Y 20, Z 50, A 0, B 90, C 0} C_SPL\n$VEL.CP = 0.1\nLIN {X 10, Y 20, Z 5, A 0, B 90, C 0}\nSPTP {A1 0, A2 -90, A3 90, A4 0, A5 0, A6 0}\nEND\n";
    let p = krl::read(src, &mut no_subs).expect("reads");
    let m = moves(&p);
    assert!(matches!(&m[0].0, Motion::Sptp(x) if x.xyz == DVec3::new(10.0, 20.0, 50.0)));
    assert_eq!(m[0].1, Approx::Spl);
    assert!(matches!(&m[2].0, Motion::SptpOther(t) if t.contains("A2 -90")));
    assert!(p.warnings.is_empty(), "{:?}", p.warnings);
    let ir = p.to_ir(1000.0, true).expect("ir").program;
    let mv: Vec<&Move> = ir.moves().collect();
    assert_eq!(mv.len(), 2, "{mv:?}");
    assert!(mv[0].is_rapid() && mv[0].end == DVec3::new(10.0, 20.0, 50.0));
    assert!(mv[1].is_cutting() && mv[1].end == DVec3::new(10.0, 20.0, 5.0));
    let files = write(&p, &KrlOptions::default());
    assert!(files[0].1.contains("SPTP {X 10"), "{}", files[0].1);
    assert!(files[0].1.contains("SPTP {A1 0, A2 -90"), "{}", files[0].1);
    check(&p, &files).expect("the same motions");
}

/// A character that is not ASCII where `WITH` is looked for is a located
/// error, not a panic (a Latin-1 file read with replacement characters).
#[test]
fn a_wide_character_after_a_target_is_located() {
    let src = "DEF s()\nSPLINE\nSPL {X 1, Y 2, Z 3, A 0, B 90, C 0} ab\u{fc}c\nENDSPLINE\nEND\n";
    let e = krl::read(src, &mut no_subs).expect_err("refused");
    assert_eq!(e.error.line, 3, "{e:?}");
}

/// Written as SPLINE, a path that turns sharply (a raster's end, here a
/// right angle) ends its block exactly on the corner point, where a spline
/// through it would swing outside; gentle turns stay in one block.
#[test]
fn a_sharp_corner_ends_the_spline_block_exactly() {
    let mut apt = String::from("CUTTER/10\nGOTO/0,0,5,0,0,1\nGOTO/0,0,-1,0,0,1\nFEDRAT/1000\n");
    for i in 1..=10 {
        apt.push_str(&format!("GOTO/{:.1},0,-1,0,0,1\n", i as f64));
    }
    for i in 1..=10 {
        // a 5° bend halfway up the second leg
        let x = 10.0
            + if i > 5 {
                (i - 5) as f64 * 5f64.to_radians().tan()
            } else {
                0.0
            };
        apt.push_str(&format!("GOTO/{x:.4},{i}.0,-1,0,0,1\n"));
    }
    let p = parse_program(&apt, ReadOptions::default())
        .expect("apt")
        .program;
    let k = from_ir(&p, &KrlOptions::default()).expect("krl");
    let files = write(&k, &spline(0));
    check(&k, &files).expect("the same motions");
    let text = &files[0].1;
    let lines: Vec<&str> = text.lines().collect();
    let corner = lines
        .iter()
        .position(|l| l.starts_with("SPL {X 10") && l.contains("Y 0"))
        .unwrap_or_else(|| panic!("{text}"));
    assert_eq!(lines[corner + 1], "ENDSPLINE", "{text}");
    // The plunge, then one block for each leg: the 5° bend ends none.
    assert_eq!(text.matches("ENDSPLINE").count(), 3, "{text}");
}

/// `$VEL_EXTAX` is not the path speed: named as not modelled, and a
/// segment's own `$VEL.CP` beside it is kept when written again.
#[test]
fn vel_extax_is_not_the_path_speed() {
    let src = "DEF s()\n$VEL.CP = 0.1\nSPLINE\nSPL {X 1, Y 2, Z 3, A 0, B 90, C 0} WITH $VEL.CP = 0.3, $VEL_EXTAX[1] = 50\nSPL {X 2, Y 2, Z 3, A 0, B 90, C 0}\nENDSPLINE\nEND\n";
    let p = krl::read(src, &mut no_subs).expect("reads");
    assert!(
        p.warnings.iter().any(|w| w.2.contains("$VEL_EXTAX")),
        "{:?}",
        p.warnings
    );
    let files = write(&p, &KrlOptions::default());
    let back = krl::read(&files[0].1, &mut no_subs).expect("reads back");
    assert_eq!(moves(&back)[0].2, Some(0.3), "{}", files[0].1);
    check(&p, &files).expect("the same motions");
}

/// A segment whose `WITH` moves its frame (`$BASE`, `$TOOL`, `$IPO_MODE`)
/// is refused at its line into another dialect (its point is not in the
/// program's frame); `--lossy` reads it with a finding; KRL → KRL keeps it.
#[test]
fn a_segment_in_a_frame_of_its_own_is_refused_into_the_ir() {
    let src = "DEF s()\n$VEL.CP = 0.1\nSPLINE\nSPL {X 1, Y 2, Z 3, A 0, B 90, C 0}\nSPL {X 2, Y 2, Z 3, A 0, B 90, C 0} WITH $BASE = BASE_DATA[4]\nENDSPLINE\nEND\n";
    let p = krl::read(src, &mut no_subs).expect("reads");
    let e = p.to_ir(1000.0, false).expect_err("refused");
    assert_eq!(e.error.line, 5, "{e:?}");
    assert!(e.error.message.contains("$BASE"), "{e:?}");
    let lossy = p.to_ir(1000.0, true).expect("lossy reads");
    assert!(
        lossy
            .diagnostics
            .iter()
            .any(|d| d.message.contains("$BASE")),
        "{:?}",
        lossy.diagnostics
    );
    let files = write(&p, &KrlOptions::default());
    assert!(
        files[0].1.contains("WITH $BASE = BASE_DATA[4]"),
        "{}",
        files[0].1
    );
    check(&p, &files).expect("the same motions");
}

/// What stands after a LIN, PTP or CIRC target besides its approximation is
/// located, not read past: `CA 90` would have the arc end at its target
/// whatever angle it asks for.
#[test]
fn words_after_a_target_are_located() {
    for (src, col, needle) in [
        ("DEF s()\nLIN {X 0, Y 0, Z 0, A 0, B 90, C 0}\nCIRC {X 1, Y 1, Z 0, A 0, B 90, C 0}, {X 2, Y 0, Z 0, A 0, B 90, C 0}, CA 90 C_DIS\nEND\n", 70, "CA"),
        ("DEF s()\nLIN {X 0, Y 0, Z 0, A 0, B 90, C 0} C_DIS junk\nEND\n", 37, "approximation"),
    ] {
        let e = krl::read(src, &mut no_subs).expect_err("refused");
        assert!(e.error.message.contains(needle), "{e:?}");
        assert_eq!(e.error.col, col, "{e:?}");
    }
}

/// KRL → KRL: the comments right after a block's `SPLINE` line (a FOLD
/// line, as KSS writes it) are written after it again, in the order read,
/// in one file and where sub-programs cut the block (the line then opens
/// the file that holds the block's first segment, the comments after it).
#[test]
fn comments_after_the_spline_line_stay_after_it() {
    let src = "DEF c()\nPTP {X 0, Y 0, Z 9, A 0, B 90, C 0}\nSPLINE\n; first\n;FOLD SPL P1\nSPL {X 1, Y 0, Z 9, A 0, B 90, C 0}\n;ENDFOLD\nSPL {X 2, Y 0, Z 9, A 0, B 90, C 0}\nENDSPLINE\nEND\n";
    let p = krl::read(src, &mut no_subs).expect("reads");
    let after_spline = |t: &str| -> Vec<String> {
        let lines: Vec<&str> = t.lines().collect();
        let i = lines.iter().position(|l| *l == "SPLINE").expect("SPLINE");
        lines[i..].iter().take(4).map(|l| l.to_string()).collect()
    };
    let one = write(
        &p,
        &KrlOptions {
            name: "c".into(),
            ..KrlOptions::default()
        },
    );
    check(&p, &one).expect("same motions");
    assert_eq!(one.len(), 1);
    assert_eq!(
        after_spline(&one[0].1)[..3],
        ["SPLINE", "; first", ";FOLD SPL P1"],
        "{}",
        one[0].1
    );
    assert!(!one[0].1.contains("; first\nSPLINE"), "{}", one[0].1);
    let subs = write(
        &p,
        &KrlOptions {
            name: "c".into(),
            max_points: 1,
            ..KrlOptions::default()
        },
    );
    check(&p, &subs).expect("same motions");
    assert_eq!(subs.len(), 4, "{subs:?}");
    assert!(!subs[1].1.contains("SPLINE"), "{}", subs[1].1);
    assert_eq!(
        after_spline(&subs[2].1),
        [
            "SPLINE",
            "; first",
            ";FOLD SPL P1",
            "SPL {X 1.000, Y 0.000, Z 9.000, A 0.0000, B 90.0000, C 0.0000}"
        ],
        "{}",
        subs[2].1
    );
    assert!(
        subs[2].1.contains(";ENDFOLD\nENDSPLINE C_SPL\n"),
        "{}",
        subs[2].1
    );
    assert_eq!(
        after_spline(&subs[3].1)[..2],
        [
            "SPLINE",
            "SPL {X 2.000, Y 0.000, Z 9.000, A 0.0000, B 90.0000, C 0.0000}"
        ],
        "{}",
        subs[3].1
    );
}

/// `$VEL = {…}` without CP (only the orientation speeds ORI1, ORI2), in a
/// segment's `WITH` or as a statement before a block: KRL assigns only the
/// components an aggregate names, so the path speed stays the one in force
/// (the block's, else `$VEL.CP`), and the aggregate is kept as written
/// (a `WITH` option named in a warning) and written back. A `$VEL = {CP v,
/// …}` statement sets the path speed as `$VEL.CP = v` does; a CP that is
/// not a speed is an error at its line.
#[test]
fn vel_without_cp_keeps_the_path_speed() {
    let src = "DEF v()\n$VEL.CP = 0.05\nPTP {X 0, Y 0, Z 9, A 0, B 90, C 0}\n$VEL = {ORI1 100, ORI2 100}\nSPLINE WITH $VEL.CP = 0.2\nSPL {X 1, Y 0, Z 9, A 0, B 90, C 0} WITH $VEL = {ORI1 200, ORI2 200}\nSPL {X 2, Y 0, Z 9, A 0, B 90, C 0}\nENDSPLINE\nSPLINE\nSPL {X 3, Y 0, Z 9, A 0, B 90, C 0} WITH $VEL = {ORI1 50}\nENDSPLINE\n$VEL = {CP 0.1, ORI1 300, ORI2 300}\nSPLINE\nSPL {X 4, Y 0, Z 9, A 0, B 90, C 0}\nENDSPLINE\nEND\n";
    let p = krl::read(src, &mut no_subs).expect("reads");
    let m = moves(&p);
    let speeds: Vec<Option<f64>> = m.iter().map(|x| x.2).collect();
    assert_eq!(
        speeds,
        [Some(0.05), Some(0.2), Some(0.2), Some(0.05), Some(0.1)]
    );
    assert_eq!(m[1].3, ["$VEL = {ORI1 200, ORI2 200}"]);
    assert_eq!(m[3].3, ["$VEL = {ORI1 50}"]);
    let named: Vec<u32> = p
        .warnings
        .iter()
        .filter(|w| w.2.contains("no CP") && w.2.contains("path speed stays"))
        .map(|w| w.1)
        .collect();
    assert_eq!(named, [6, 10], "{:?}", p.warnings);
    assert!(p.statements.iter().any(|l| l.statement
        == Statement::Vel {
            cp: Some(0.1),
            text: "{CP 0.1, ORI1 300, ORI2 300}".into()
        }));
    // KRL → KRL: the speeds, the options and the statements as read.
    let files = write(
        &p,
        &KrlOptions {
            name: "v".into(),
            ..KrlOptions::default()
        },
    );
    check(&p, &files).expect("same motions");
    let t = &files[0].1;
    assert!(t.contains("\n$VEL = {ORI1 100, ORI2 100}\n"), "{t}");
    assert!(t.contains("\n$VEL = {CP 0.1, ORI1 300, ORI2 300}\n"), "{t}");
    assert!(
        t.contains("WITH $VEL.CP = 0.200000, $VEL = {ORI1 200, ORI2 200}\n"),
        "{t}"
    );
    assert_eq!(moves(&krl::read(t, &mut no_subs).expect("re-reads")), m);
    // Into the IR: the speeds as feeds.
    let ir = p.to_ir(1000.0, true).expect("ir");
    let feeds: Vec<f64> = ir.program.moves().map(|x| x.feed).collect();
    assert!((feeds[4] - 0.1 * 60_000.0).abs() < 1e-9, "{feeds:?}");
    assert!((feeds[3] - 0.05 * 60_000.0).abs() < 1e-9, "{feeds:?}");
    // A CP that is not a speed: at its line.
    for (body, line) in [
        ("$VEL = {CP fast, ORI1 100}", 2),
        (
            "SPLINE\nSPL {X 1, Y 0, Z 9} WITH $VEL = {CP fast}\nENDSPLINE",
            3,
        ),
    ] {
        let e = krl::read(&format!("DEF b()\n{body}\nEND\n"), &mut no_subs).expect_err(body);
        assert_eq!(e.error.line, line, "{body}: {}", e.error.message);
        assert!(
            e.error.message.contains("path speed"),
            "{}",
            e.error.message
        );
    }
}
