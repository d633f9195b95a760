//! KUKA KRL: the reader, the writer and the round trips (process-models §5,
//! T17), and the PowerMILL sample of `../shared/data`.

use millplan_geom::DVec3;
use millplan_nc::krl::{self, Approx, Motion, Statement};
use millplan_nc::write::apt::write_apt;
use millplan_nc::write::krl::{from_ir, write, KrlOptions};
use millplan_nc::write::{Target, WriteOptions};
use millplan_nc::*;

mod shared_data;

const SMALL: &str = "&ACCESS RVP\r
&REL 1\r
DEF small()\r
;FOLD INI\r
  BAS (#INITMOV,0 )\r
;ENDFOLD (INI)\r
$TOOL = TOOL_DATA[2]\r
$BASE = BASE_DATA[1]\r
PTP {A1 0, A2 -90, A3 90, A4 0, A5 0, A6 0}\r
$VEL.CP = 0.018667 ; 1120 mm/min\r
$APO.CDIS = 0.15\r
LIN {X 10.0, Y 0.0, Z 5.0, A 0.0, B 90.0, C 0.0, E1 12.5} C_DIS\r
SetRPM(8000)\r
LIN {X 10.3, Y 0.0, Z 5.0, A 0.0, B 90.0, C 0.0, E1 13.0}\r
CIRC {X 15.3, Y 5.0, Z 5.0, A 0, B 90, C 0}, {X 20.3, Y 0.0, Z 5.0, A 0, B 90, C 0} C_DIS\r
END\r
";

fn no_subs(_: &str) -> Option<String> {
    None
}

fn moves(p: &krl::KrlProgram) -> Vec<(Motion, Approx, Option<f64>)> {
    p.statements
        .iter()
        .filter_map(|l| match &l.statement {
            Statement::Move {
                motion,
                approx,
                vel_cp,
                ..
            } => Some((motion.clone(), *approx, *vel_cp)),
            _ => None,
        })
        .collect()
}

#[test]
fn reads_motions_speeds_and_verbatim_calls() {
    let p = krl::read(SMALL, &mut no_subs).expect("reads");
    assert_eq!(p.name, "small");
    let m = moves(&p);
    assert_eq!(m.len(), 4);
    assert!(matches!(&m[0].0, Motion::PtpOther(t) if t.contains("A2 -90")));
    let Motion::Lin(first) = &m[1].0 else {
        panic!("{:?}", m[1])
    };
    assert_eq!(first.xyz, DVec3::new(10.0, 0.0, 5.0));
    assert_eq!(first.e[0], Some(12.5));
    assert_eq!((m[1].1, m[1].2), (Approx::Dis, Some(0.018667)));
    assert_eq!(m[2].1, Approx::Exact);
    assert!(matches!(m[3].0, Motion::Circ { .. }));
    let verbatim: Vec<&str> = p
        .statements
        .iter()
        .filter_map(|l| match &l.statement {
            Statement::Verbatim(t) => Some(t.as_str()),
            _ => None,
        })
        .collect();
    assert!(verbatim.contains(&"SetRPM(8000)"), "{verbatim:?}");
    assert!(verbatim.contains(&";FOLD INI"), "{verbatim:?}");
    assert!(p
        .statements
        .iter()
        .any(|l| l.statement == Statement::Tool("TOOL_DATA[2]".into())));
    assert!(p
        .statements
        .iter()
        .any(|l| l.statement == Statement::ApoCdis(0.15)));
}

#[test]
fn bad_krl_is_a_located_error() {
    let e = krl::read("DEF a()\nLIN {X 1, Y 2}\nEND\n", &mut no_subs).expect_err("no Z");
    assert_eq!((e.file, e.error.line), (None, 2));
    let e = krl::read("DEF a()\n$VEL.CP = fast\nEND\n", &mut no_subs).expect_err("speed");
    assert_eq!(e.error.line, 2);
    assert!(e.error.message.contains("$VEL.CP"), "{}", e.error);
}

/// KRL → KRL: poses, E1, approximation and speeds come back as read.
#[test]
fn krl_round_trip_keeps_poses_e1_and_speeds() {
    let p = krl::read(SMALL, &mut no_subs).expect("reads");
    let files = write(
        &p,
        &KrlOptions {
            name: "small".into(),
            ..KrlOptions::default()
        },
    );
    assert_eq!(files.len(), 1);
    let back = krl::read(&files[0].1, &mut no_subs).expect("re-reads");
    assert_eq!(moves(&back), moves(&p));
    assert!(files[0].1.contains("$VEL.CP = 0.018667"));
    assert!(files[0].1.contains("SetRPM(8000)"));
}

/// A long program is cut into sub-programs a main calls; read back through
/// the resolver it is the same program.
#[test]
fn sub_programs_split_and_read_back() {
    let p = krl::read(SMALL, &mut no_subs).expect("reads");
    let o = KrlOptions {
        name: "small".into(),
        max_points: 2,
        ..KrlOptions::default()
    };
    let files = write(&p, &o);
    assert_eq!(
        files.iter().map(|f| f.0.as_str()).collect::<Vec<_>>(),
        ["small", "small_001", "small_002"]
    );
    assert!(files[0].1.contains("EXT small_001()") && files[0].1.contains("\nsmall_002()\n"));
    let mut resolve = |name: &str| {
        files
            .iter()
            .find(|f| f.0.eq_ignore_ascii_case(name))
            .map(|f| f.1.clone())
    };
    let back = krl::read(&files[0].1, &mut resolve).expect("re-reads");
    assert_eq!(moves(&back), moves(&p));
    assert_eq!(back.files, ["small", "small_001", "small_002"]);
    // Without the second sub-program: what is there, and the missing one named with its calling line.
    let mut partial = |name: &str| {
        if name == "small_002" {
            None
        } else {
            resolve(name)
        }
    };
    let back = krl::read(&files[0].1, &mut partial).expect("reads what is there");
    assert_eq!(back.missing.len(), 1);
    let (name, file, line) = &back.missing[0];
    assert_eq!((name.as_str(), *file), ("small_002", 0));
    assert_eq!(
        files[0].1.lines().nth(*line as usize - 1),
        Some("small_002()")
    );
}

/// Into the IR: A, B, C become the tool axis (B = 90°: tool pointing down,
/// axis +z), $VEL.CP a feed in mm/min; E1 is refused at its line unless lossy.
#[test]
fn to_ir_turns_orientation_into_axis_and_refuses_e1() {
    let p = krl::read(SMALL, &mut no_subs).expect("reads");
    let e = p.to_ir(1000.0, false).expect_err("E1");
    assert_eq!(e.error.line, 12);
    assert!(e.error.message.contains("E1"), "{}", e.error);
    let parsed = p.to_ir(1000.0, true).expect("lossy");
    assert!(parsed
        .diagnostics
        .iter()
        .any(|d| d.code == diag::Code::LossyWord));
    verify::verify(&parsed.program).expect("verifies");
    let op = &parsed.program.operations[0];
    assert_eq!(op.moves.len(), 3);
    let axis = op.axis(&op.moves[0]).expect("axis");
    assert!((axis - DVec3::Z).length() < 1e-12, "{axis}");
    assert!((op.moves[0].feed - 1120.02).abs() < 1e-9);
    assert!(matches!(op.moves[2].kind, MoveKind::Arc(_)));
}

/// T17 (process-models §6): 1120 mm/min → `$VEL.CP = 0.018667`; points
/// 0.3 mm apart → `$APO.CDIS` ≤ 0.15; one LIN per CL point after the approach.
#[test]
fn t17_units_from_a_cl_program() {
    let mut apt = String::from("CUTTER/10\nGOTO/0,0,5,0,0,1\nFEDRAT/1120\n");
    for i in 0..=100 {
        apt.push_str(&format!("GOTO/{:.1},0,-1,0,0,1\n", i as f64 * 0.3));
    }
    let prog = parse_program(&apt, ReadOptions::default())
        .expect("apt")
        .program;
    let k = from_ir(&prog, &KrlOptions::default()).expect("krl");
    let text = &write(&k, &KrlOptions::default())[0].1;
    assert!(text.contains("$VEL.CP = 0.018667\n"), "{text}");
    let cdis: f64 = text
        .lines()
        .find_map(|l| l.strip_prefix("$APO.CDIS = "))
        .expect("cdis")
        .parse()
        .expect("number");
    assert!(cdis <= 0.15 && cdis > 0.1, "{cdis}");
    assert_eq!(text.lines().filter(|l| l.starts_with("LIN ")).count(), 101);
    assert_eq!(text.lines().filter(|l| l.starts_with("PTP ")).count(), 1);
    assert!(
        text.contains("LIN {X 0.300, Y 0.000, Z -1.000, A 0.0000, B 90.0000, C 0.0000} C_DIS"),
        "{text}"
    );
    // Read back into the IR: the same points, axes and feed.
    let back = krl::read(text, &mut no_subs)
        .expect("re-reads")
        .to_ir(1.0, false)
        .expect("ir")
        .program;
    let (a, b) = (&prog.operations[0], &back.operations[0]);
    assert_eq!(a.moves.len(), b.moves.len());
    for (m, n) in a.moves.iter().zip(&b.moves) {
        assert!((m.end - n.end).length() < 1e-3);
        assert!((a.axis(m).unwrap_or(DVec3::Z) - b.axis(n).expect("axis")).length() < 1e-6);
    }
    assert!((b.moves[5].feed - 1120.0).abs() < 0.03);
}

/// The PowerMILL sample: the main and the two sub-programs present read (the
/// other 30 named with their calling lines), E1 kept; KRL → KRL keeps poses
/// and E1; KRL → APT → KRL keeps the positions and tool axes.
#[test]
fn powermill_sample_reads_and_converts() {
    let Some(main) = shared_data::file("kuka-krl-powermill-ballnose/f1_Kuka_APT2_Main.SRC") else {
        return;
    };
    let dir = main.parent().expect("dir").to_path_buf();
    let mut resolve = |name: &str| std::fs::read_to_string(dir.join(format!("{name}.SRC"))).ok();
    let src = std::fs::read_to_string(&main).expect("main");
    let p = krl::read(&src, &mut resolve).expect("reads");
    assert_eq!(p.files.len(), 3);
    assert_eq!(p.missing.len(), 30);
    let (name, _, line) = &p.missing[0];
    assert_eq!(name, "f1_Kuka_APT203T02S03");
    assert_eq!(
        src.lines().nth(*line as usize - 1).map(str::trim),
        Some("f1_Kuka_APT203T02S03()")
    );
    let lins = moves(&p)
        .iter()
        .filter(|m| matches!(m.0, Motion::Lin(_)))
        .count();
    assert_eq!(lins, 5996 + 6000);
    let e1: Vec<f64> = moves(&p)
        .iter()
        .filter_map(|m| match &m.0 {
            Motion::Lin(x) => x.e[0],
            _ => None,
        })
        .collect();
    assert_eq!(e1.len(), lins);
    // KRL → KRL, split as the controller wants it.
    let files = write(
        &p,
        &KrlOptions {
            name: "f1".into(),
            max_points: 6000,
            ..KrlOptions::default()
        },
    );
    let mut again = |name: &str| files.iter().find(|f| f.0 == name).map(|f| f.1.clone());
    let back = krl::read(&files[0].1, &mut again).expect("re-reads");
    assert_eq!(moves(&back), moves(&p));
    // KRL → APT (E1 dropped, said so) → KRL.
    let ir = p.to_ir(30000.0, true).expect("lossy").program;
    let mut apt = Vec::new();
    let mut o = WriteOptions::new(Target::Apt);
    o.lossy = true; // `PTP XHOME`: a named position APT has no word for
    write_apt(&ir, o, &mut apt).expect("apt");
    let apt = parse_program(
        std::str::from_utf8(&apt).expect("utf8"),
        ReadOptions::default(),
    )
    .expect("apt reads")
    .program;
    let k = from_ir(&apt, &KrlOptions::default()).expect("krl");
    let text = write(
        &k,
        &KrlOptions {
            max_points: 0,
            ..KrlOptions::default()
        },
    );
    let round = krl::read(&text[0].1, &mut no_subs)
        .expect("reads")
        .to_ir(1.0, false)
        .expect("ir")
        .program;
    let (a, b) = (&ir.operations[0], &round.operations[0]);
    assert_eq!(a.moves.len(), b.moves.len());
    for (m, n) in a.moves.iter().zip(&b.moves) {
        assert!((m.end - n.end).length() < 2e-3, "{} vs {}", m.end, n.end);
        assert!((a.axis(m).expect("axis") - b.axis(n).expect("axis")).length() < 1e-5);
    }
}

/// The approximation tags each motion takes (KSS 8.x; KUKA's
/// mxAutomation manual lists C_PTP alone or with C_DIS, C_ORI, C_VEL for
/// PTP and C_DIS, C_ORI, C_VEL for LIN and CIRC; KSS 8's inline forms write
/// `PTP … C_DIS` and `LIN … C_DIS C_DIS`; C_SPL is the spline motions'):
/// each is read and written back as read.
#[test]
fn approximation_tags_read_per_motion() {
    let p = "{X 1, Y 2, Z 3, A 0, B 90, C 0}";
    let q = "{X 2, Y 2, Z 3, A 0, B 90, C 0}";
    let cases: &[(&str, Approx)] = &[
        (&format!("LIN {p} C_DIS"), Approx::Dis),
        (&format!("LIN {p} c_vel"), Approx::Vel),
        (&format!("LIN {p} C_ORI"), Approx::Ori),
        (&format!("LIN {p} C_DIS C_DIS"), Approx::Dis),
        (&format!("CIRC {p}, {q} C_VEL"), Approx::Vel),
        (&format!("PTP {p} C_PTP"), Approx::Ptp),
        (&format!("PTP {p} C_PTP C_DIS"), Approx::PtpDis),
        (&format!("PTP {p} C_PTP C_ORI"), Approx::PtpOri),
        (&format!("PTP {p} C_PTP C_VEL"), Approx::PtpVel),
        (&format!("PTP {p} C_DIS"), Approx::Dis),
        (&format!("SPTP {p} C_SPL"), Approx::Spl),
        (&format!("SPTP {p} C_PTP"), Approx::Ptp),
        (&format!("SLIN {p} C_SPL"), Approx::Spl),
        (&format!("SLIN {p} WITH $VEL.CP = 0.1 C_SPL"), Approx::Spl),
        (&format!("SCIRC {p}, {q} C_SPL"), Approx::Spl),
        (&format!("LIN {p}"), Approx::Exact),
    ];
    for (line, want) in cases {
        let src = format!("DEF t()\n{line}\nEND\n");
        let k = krl::read(&src, &mut no_subs).unwrap_or_else(|e| panic!("{line}: {e:?}"));
        let m = moves(&k);
        assert_eq!(m.len(), 1, "{line}");
        assert_eq!(m[0].1, *want, "{line}");
        let files = write(&k, &KrlOptions::default());
        let back = krl::read(&files[0].1, &mut no_subs).expect("re-reads");
        assert_eq!(moves(&back), m, "{line}\n{}", files[0].1);
    }
}

/// A tag a motion does not take is an error at its line and column, named
/// with what the motion takes.
#[test]
fn approximation_tags_that_do_not_belong_are_located() {
    let p = "{X 1, Y 2, Z 3, A 0, B 90, C 0}";
    let at = |body: &str| {
        let src = format!("DEF bad()\nPTP {p}\n{body}\nEND\n");
        let e = krl::read(&src, &mut no_subs).expect_err(body);
        (e.error.line, e.error.col, e.error.message)
    };
    // `LIN {…}` is 35 characters: the tag at 37.
    let cases: &[(String, u32, &str)] = &[
        (format!("LIN {p} C_PTP"), 37, "LIN and CIRC take"),
        (format!("LIN {p} C_SPL"), 37, "LIN and CIRC take"),
        (format!("LIN {p} C_DIS C_VEL"), 43, "after LIN C_DIS"),
        (format!("LIN {p} C_FOO"), 37, "LIN and CIRC take"),
        (format!("PTP {p} C_VEL"), 37, "PTP takes C_PTP"),
        (format!("PTP {p} C_SPL"), 37, "PTP takes C_PTP"),
        (format!("PTP {p} C_PTP C_SPL"), 43, "after PTP C_PTP"),
        (format!("PTP {p} C_DIS C_PTP"), 43, "after PTP C_DIS"),
        (format!("SPTP {p} C_DIS"), 38, "SPTP takes C_SPL or C_PTP"),
        (
            format!("SLIN {p} C_DIS"),
            38,
            "outside a SPLINE block take C_SPL",
        ),
        (
            format!("SLIN {p} C_PTP"),
            38,
            "outside a SPLINE block take C_SPL",
        ),
        (
            format!("SPLINE\nSPL {p} C_SPL\nENDSPLINE"),
            37,
            "ENDSPLINE C_SPL approximates",
        ),
        (
            format!("SPLINE\nSLIN {p} C_SPL\nENDSPLINE"),
            38,
            "ENDSPLINE C_SPL approximates",
        ),
    ];
    for (body, col, says) in cases {
        let line = if body.starts_with("SPLINE") { 4 } else { 3 };
        let (l, c, m) = at(body);
        assert_eq!((l, c), (line, *col), "{body}: {m}");
        assert!(m.contains(says), "{body}: {m}");
    }
}
