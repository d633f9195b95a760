//! `millplan convert` and `inspect` with KUKA KRL (process-models §5): a
//! `.SRC` read with the sub-programs beside it, written as KRL (poses,
//! external axes and speeds kept), into APT only when the external axes may
//! be dropped, and back.

#[path = "../../millplan-nc/tests/shared_data/mod.rs"]
mod shared_data;

use millplan_nc::krl::{self, Motion, Statement};
use std::path::Path;

fn run(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args(args)
        .output()
        .expect("runs")
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

const SMALL: &str = "&ACCESS RVP
&REL 1
DEF small()
$TOOL = TOOL_DATA[2]
$BASE = BASE_DATA[1]
PTP {X 10.0, Y 0.0, Z 50.0, A 0.0, B 90.0, C 0.0}
$VEL.CP = 0.018667
$APO.CDIS = 0.15
LIN {X 10.0, Y 0.0, Z 5.0, A 0.0, B 90.0, C 0.0, E1 12.5} C_DIS
SetRPM(8000)
LIN {X 10.3, Y 0.0, Z 5.0, A 10.0, B 80.0, C 5.0, E1 13.0} C_DIS
LIN {X 10.6, Y 0.0, Z 5.0, A 10.0, B 80.0, C 5.0, E1 13.5}
END
";

/// The motions of a KRL file: (X, Y, Z, A, B, C, E1, `$VEL.CP`).
fn motions(text: &str) -> Vec<[f64; 8]> {
    let p = krl::read(text, &mut |_| None).expect("reads");
    p.statements
        .iter()
        .filter_map(|l| match &l.statement {
            Statement::Move {
                motion: Motion::Lin(x) | Motion::Ptp(x),
                vel_cp,
                ..
            } => Some([
                x.xyz.x,
                x.xyz.y,
                x.xyz.z,
                x.abc[0],
                x.abc[1],
                x.abc[2],
                x.e[0].unwrap_or(f64::NAN),
                vel_cp.unwrap_or(f64::NAN),
            ]),
            _ => None,
        })
        .collect()
}

fn same(a: &[[f64; 8]], b: &[[f64; 8]], tol: f64) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        for k in 0..8 {
            let ok = (x[k].is_nan() && y[k].is_nan()) || (x[k] - y[k]).abs() <= tol;
            assert!(ok, "{x:?} vs {y:?}");
        }
    }
}

/// KRL → KRL keeps every pose, E1 and the speed; KRL → APT refuses E1 at
/// its line (exit 2) unless --lossy, and the orientation becomes the tool
/// axis; APT → KRL is one LIN per CL point after the PTP approach, the
/// speed in m/s with six decimals.
#[test]
fn krl_round_trips_and_refuses_e1_for_apt() {
    let dir = tempfile::tempdir().expect("tmp");
    let src = dir.path().join("small.src");
    std::fs::write(&src, SMALL).expect("write");
    let out = dir.path().join("out.src");
    let o = run(&["convert", s(&src), "-o", s(&out)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let written = std::fs::read_to_string(&out).expect("out");
    same(&motions(&written), &motions(SMALL), 5e-4);
    assert!(written.contains("SetRPM(8000)"), "{written}");

    let apt = dir.path().join("out.apt");
    let o = run(&["convert", s(&src), "-o", s(&apt)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("small.src:9:1:") && err.contains("E1"),
        "{err}"
    );
    assert!(!apt.exists());

    let o = run(&["convert", s(&src), "-o", s(&apt), "--lossy"]);
    assert!(o.status.code().is_some_and(|c| c == 0 || c == 3), "{o:?}");
    let text = std::fs::read_to_string(&apt).expect("apt");
    let prog = millplan_nc::parse_program(&text, millplan_nc::ReadOptions::default())
        .expect("apt reads")
        .program;
    let op = &prog.operations[0];
    let src = motions(SMALL);
    assert_eq!(op.moves.len(), src.len());
    for (m, x) in op.moves.iter().zip(&src) {
        let want = krl::tool_axis([x[3], x[4], x[5]]);
        let axis = op.axis(m).expect("a tool axis");
        assert!((axis - want).length() < 1e-5, "{axis} vs {want}");
    }
    // B 90: the tool points down, the tool axis is +z.
    assert!((op.axis(&op.moves[0]).expect("axis") - millplan_geom::DVec3::Z).length() < 1e-9);

    let back = dir.path().join("back.src");
    let o = run(&["convert", s(&apt), "-o", s(&back), "--lossy"]);
    assert!(
        o.status.code().is_some_and(|c| c == 0 || c == 3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = std::fs::read_to_string(&back).expect("back");
    assert!(text.contains("$VEL.CP = 0.018667"), "{text}");
    let (a, b) = (motions(SMALL), motions(&text));
    assert_eq!(b.len(), a.len());
    assert_eq!(text.lines().filter(|l| l.starts_with("PTP ")).count(), 1);
    for (x, y) in a.iter().zip(&b) {
        for k in 0..3 {
            assert!((x[k] - y[k]).abs() < 1e-3, "{x:?} vs {y:?}");
        }
        let (u, v) = (
            krl::tool_axis([x[3], x[4], x[5]]),
            krl::tool_axis([y[3], y[4], y[5]]),
        );
        assert!((u - v).length() < 1e-5, "{u} vs {v}");
    }
}

/// The PowerMILL sample: the main calls 32 sub-programs, two are beside
/// it; convert reads what is there, names each missing one with its calling
/// line, and writes KRL with every pose and E1 of the two; inspect reads it.
#[test]
fn powermill_main_with_missing_sub_programs() {
    let Some(main) = shared_data::file("kuka-krl-powermill-ballnose/f1_Kuka_APT2_Main.SRC") else {
        return;
    };
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("f1.src");
    let o = run(&["convert", s(&main), "-o", s(&out)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    let src = std::fs::read_to_string(&main).expect("main");
    let missing: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("is called but not beside the main program"))
        .collect();
    assert_eq!(missing.len(), 30, "{err}");
    let line = src
        .lines()
        .position(|l| l.trim() == "f1_Kuka_APT203T02S03()")
        .expect("call")
        + 1;
    assert!(
        missing[0].contains(&format!(":{line}: sub-program f1_Kuka_APT203T02S03")),
        "{}",
        missing[0]
    );
    let written = std::fs::read_to_string(&out).expect("out");
    let mut from_sample = Vec::new();
    for sub in ["f1_Kuka_APT201T02S01.SRC", "f1_Kuka_APT202T02S02.SRC"] {
        let text = std::fs::read_to_string(main.with_file_name(sub)).expect("sub");
        from_sample.extend(motions(&text));
    }
    let got = motions(&written);
    assert_eq!(got.len(), 5996 + 6000);
    same(&got, &from_sample, 5e-4);
    assert!(written.contains("EXT f1_Kuka_APT203T02S03()"));

    let o = run(&["inspect", s(&main), "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert!(j.to_string().contains(r#""format":"krl""#), "{j}");

    // Into APT the external axis E1 stops the conversion at its line in
    // the sub-program that holds it.
    let apt = dir.path().join("f1.apt");
    let o = run(&["convert", s(&main), "-o", s(&apt)]);
    assert_eq!(o.status.code(), Some(2));
    let e1 = std::fs::read_to_string(main.with_file_name("f1_Kuka_APT201T02S01.SRC"))
        .expect("sub")
        .lines()
        .position(|l| l.contains("E1 "))
        .expect("E1")
        + 1;
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!("f1_Kuka_APT201T02S01.SRC:{e1}:1:")),
        "{err}"
    );
}

/// The end poses of every motion a KRL program commands, its sub-programs
/// read from `dir` (those missing left out): (X, Y, Z, A, B, C, E1,
/// `$VEL.CP`), spline segments too.
fn all_motions(text: &str, dir: &Path) -> Vec<[f64; 8]> {
    let p = krl::read(text, &mut |n| {
        std::fs::read_to_string(dir.join(format!("{n}.src"))).ok()
    })
    .expect("reads");
    p.statements
        .iter()
        .filter_map(|l| match &l.statement {
            Statement::Move { motion, vel_cp, .. } => motion.end().map(|x| {
                [
                    x.xyz.x,
                    x.xyz.y,
                    x.xyz.z,
                    x.abc[0],
                    x.abc[1],
                    x.abc[2],
                    x.e[0].unwrap_or(f64::NAN),
                    vel_cp.unwrap_or(f64::NAN),
                ]
            }),
            _ => None,
        })
        .collect()
}

/// `convert --krl-motion spline`: the approximated LIN runs become SPLINE
/// blocks of SPL segments through the same poses, E1 and speeds, in one
/// file or, with --max-points, in sub-programs of as many motions as LIN
/// output has, no block straddling two; refused for another dialect.
#[test]
fn krl_motion_spline_writes_blocks_that_read_back() {
    let dir = tempfile::tempdir().expect("tmp");
    let src = dir.path().join("small.src");
    std::fs::write(&src, SMALL).expect("write");
    let out = dir.path().join("spl.src");
    let o = run(&["convert", s(&src), "-o", s(&out), "--krl-motion", "spline"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let written = std::fs::read_to_string(&out).expect("out");
    // The plunge's end turns a right angle into the cut: its block ends
    // exactly there (a spline would swing under it), before the call.
    assert!(written.contains("\nSPLINE\nSPL {X 10.000, Y 0.000, Z 5.000, A 0.0000, B 90.0000, C 0.0000, E1 12.500}\nENDSPLINE\nSetRPM(8000)\nSPLINE\n"), "{written}");
    assert!(!written.contains("LIN "), "{written}");
    same(&all_motions(&written, dir.path()), &motions(SMALL), 5e-4);

    let main = dir.path().join("parts.src");
    let o = run(&[
        "convert",
        s(&src),
        "-o",
        s(&main),
        "--krl-motion",
        "spline",
        "--max-points",
        "2",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&main).expect("main");
    same(&all_motions(&text, dir.path()), &motions(SMALL), 5e-4);
    for sub in ["parts_001.src", "parts_002.src"] {
        let t = std::fs::read_to_string(dir.path().join(sub)).expect("sub");
        let open = t.lines().filter(|l| *l == "SPLINE").count();
        let close = t.lines().filter(|l| l.starts_with("ENDSPLINE")).count();
        assert_eq!(open, close, "{sub}: {t}");
    }

    let apt = dir.path().join("x.apt");
    let o = run(&[
        "convert",
        s(&src),
        "-o",
        s(&apt),
        "--lossy",
        "--krl-motion",
        "spline",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--krl-motion"));
    assert!(!apt.exists());
}

/// A SPLINE program with a malformed segment: exit 2 at its file, line and
/// column, nothing written.
#[test]
fn a_malformed_spline_segment_is_located() {
    let dir = tempfile::tempdir().expect("tmp");
    let src = dir.path().join("bad.src");
    std::fs::write(
        &src,
        "DEF bad()\nSPLINE\n  SPL {X 1, Y 2, Z 3}\n  SPL {X 1, Y 2, Z 3} WITH $VEL.CP = fast\nENDSPLINE\nEND\n",
    )
    .expect("write");
    let out = dir.path().join("out.src");
    let o = run(&["convert", s(&src), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.src:4:38:"), "{err}");
    assert!(!out.exists());
}

/// The PowerMILL main and its two sub-programs converted with
/// `--krl-motion spline`: every pose and E1 of the sample back.
#[test]
fn powermill_as_spline() {
    let Some(main) = shared_data::file("kuka-krl-powermill-ballnose/f1_Kuka_APT2_Main.SRC") else {
        return;
    };
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("f1.src");
    let o = run(&[
        "convert",
        s(&main),
        "-o",
        s(&out),
        "--krl-motion",
        "spline",
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let written = std::fs::read_to_string(&out).expect("out");
    let mut from_sample = Vec::new();
    for sub in ["f1_Kuka_APT201T02S01.SRC", "f1_Kuka_APT202T02S02.SRC"] {
        let text = std::fs::read_to_string(main.with_file_name(sub)).expect("sub");
        from_sample.extend(motions(&text));
    }
    same(&all_motions(&written, dir.path()), &from_sample, 5e-4);
    // Every LIN of the sample is approximated or ends a run of them.
    let spl = written.lines().filter(|l| l.starts_with("SPL {")).count();
    assert_eq!(spl, from_sample.len());
    assert!(!written.contains("\nLIN "));
}

/// An approximation tag the motion does not take (C_PTP after a LIN):
/// exit 2 at its file, line and column, nothing written.
#[test]
fn an_approximation_the_motion_does_not_take_is_located() {
    let dir = tempfile::tempdir().expect("tmp");
    let src = dir.path().join("bad.src");
    std::fs::write(
        &src,
        "DEF bad()\nPTP {X 0, Y 0, Z 9, A 0, B 90, C 0} C_PTP\nLIN {X 1, Y 0, Z 9, A 0, B 90, C 0} C_PTP\nEND\n",
    )
    .expect("write");
    let out = dir.path().join("out.src");
    let o = run(&["convert", s(&src), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.src:3:37:") && err.contains("C_PTP after LIN"),
        "{err}"
    );
    assert!(!out.exists());
}
