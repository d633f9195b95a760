//! The verdict of `speed`, `feed`, `force`, `setup`, `orient` and `post` in
//! the terminal and under `--json` is the report's: one field `verdict`
//! (`level`, `summary`, `failed`, `worse`, `kept`, `warnings`) by the one
//! rule — red when a check failed; amber when the input was kept, a warning
//! applies or a measure got worse; green otherwise — and the text's last
//! line `verdict: <summary>`.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn run(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("runs")
}

/// The demo's files in a fresh folder.
fn demo() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("tmp");
    let o = run(dir.path(), &["demo", "-q", "-o", "."]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    dir
}

/// `args` run under `--json` and as text: the JSON's verdict, checked to
/// follow the one rule and to be what the text's last line and the report
/// (when `report` names one the JSON run wrote) say. Both runs exit `code`.
fn verdict(dir: &Path, args: &[&str], report: Option<&str>, code: i32) -> Value {
    let o = run(dir, &[args, &["--json", "-q"]].concat());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(code), "{args:?}: {err}");
    let j: Value = serde_json::from_slice(&o.stdout).expect("json");
    let v = j["verdict"].clone();
    let level = v["level"].as_str().expect("a level");
    let (failed, worse) = (&v["failed"], &v["worse"]);
    let nonempty = |x: &Value| x.as_array().is_some_and(|a| !a.is_empty());
    let want = if nonempty(failed) {
        "red"
    } else if v["kept"] == true || nonempty(&v["warnings"]) || nonempty(worse) {
        "amber"
    } else {
        "green"
    };
    assert_eq!(level, want, "{args:?}: {v}");
    let summary = v["summary"].as_str().expect("summary");
    let cap = format!("{}{}:", level[..1].to_uppercase(), &level[1..]);
    assert!(summary.starts_with(&cap), "{summary}");
    for w in worse.as_array().into_iter().flatten() {
        assert!(summary.contains(w.as_str().expect("words")), "{summary}");
    }
    if let Some(r) = report {
        let html = std::fs::read_to_string(dir.join(r)).expect("report");
        assert!(html.contains(&format!("data-level=\"{level}\"")), "{r}");
        assert!(
            html.contains(&format!("<p>{summary}</p>")),
            "{r}: {summary}"
        );
    }
    let text_args: Vec<&str> = args
        .iter()
        .copied()
        .filter(|a| !a.ends_with(".html") && *a != "--report")
        .collect();
    let o = run(dir, &[&text_args[..], &["-q"]].concat());
    assert_eq!(o.status.code(), Some(code), "{text_args:?}");
    let text = String::from_utf8_lossy(&o.stdout);
    let last = text.lines().last().unwrap_or("");
    assert_eq!(last, format!("verdict: {summary}"), "{text}");
    v
}

/// `speed` on the demo: the spindle control slows the cycle (the spindle's
/// acceleration holds it back) and the demo's open surface warns: amber,
/// naming the cycle time that got worse, in text, JSON and report alike.
#[test]
fn speed_says_the_reports_verdict() {
    let d = demo();
    let args = [
        "speed",
        "finish.apt",
        "--stl",
        "part.stl",
        "--vc",
        "63",
        "--fz",
        "0.1",
        "--flutes",
        "2",
        "--ap",
        "0.3",
        "-o",
        "s.apt",
        "--report",
        "s.html",
    ];
    let v = verdict(d.path(), &args, Some("s.html"), 0);
    assert_eq!(v["level"], "amber", "{v}");
    assert!(v["summary"]
        .as_str()
        .is_some_and(|s| s.contains("worse: cycle time")));
}

/// A G-code program cutting 3 mm into its stock with a D10 ball.
fn slot(dir: &Path) -> PathBuf {
    let p = dir.join("slot.nc");
    std::fs::write(
        &p,
        "%\nO0031\nG21 G90 G17 G94\nT1 M6\nS8000 M3\nG0 X-20. Y0. Z5.\nG1 Z-3. F500.\nG1 X60. F1120.\nG1 Y10.\nG1 X-20.\nG0 Z5.\nM30\n%\n",
    )
    .expect("write");
    p
}

const MODEL: [&str; 8] = [
    "--stock",
    "box:auto",
    "--tool",
    "ball:10",
    "--material",
    "al7075",
    "--resolution",
    "0.5",
];

/// `force`: a move over a limit is a failed check, red (exit 3); without
/// limits the loads alone are no verdict against the program.
#[test]
fn force_says_the_reports_verdict() {
    let d = tempfile::tempdir().expect("tmp");
    slot(d.path());
    let args = [&["force", "slot.nc"][..], &MODEL, &["--report", "f.html"]].concat();
    let v = verdict(d.path(), &args, Some("f.html"), 0);
    assert_ne!(v["level"], "red", "{v}");
    let over = [&args[..], &["--limit", "fxy=1"]].concat();
    let v = verdict(d.path(), &over, Some("f.html"), 3);
    assert_eq!(v["level"], "red", "{v}");
    assert!(v["failed"][0]
        .as_str()
        .is_some_and(|f| f.ends_with("moves over a load limit")));
}

/// `feed`: text, JSON and report agree; a limit no feed can meet leaves
/// moves over it: red (exit 3).
#[test]
fn feed_says_the_reports_verdict() {
    let d = tempfile::tempdir().expect("tmp");
    slot(d.path());
    let base = [&["feed", "slot.nc"][..], &MODEL, &["-o", "fed.nc"]].concat();
    let args = [&base[..], &["--report", "fe.html"]].concat();
    let v = verdict(d.path(), &args, Some("fe.html"), 0);
    assert_ne!(v["level"], "red", "{v}");
    let html = std::fs::read_to_string(d.path().join("fe.html")).expect("report");
    assert!(html.contains("<th>tools</th><td>T1"), "the inputs box");
    let over = [&args[..], &["--limit", "fxy=0.001"]].concat();
    let v = verdict(d.path(), &over, Some("fe.html"), 3);
    assert_eq!(v["level"], "red", "{v}");
}

/// A closed cube of side 20 as ASCII STL.
fn cube(dir: &Path) {
    let v = |i: usize| {
        [
            20.0 * (i & 1) as f64,
            20.0 * (i >> 1 & 1) as f64,
            20.0 * (i >> 2 & 1) as f64,
        ]
    };
    // Each face by its corners, counter-clockwise seen from outside.
    let faces = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut s = String::from("solid cube\n");
    for f in faces {
        for t in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
            s += "facet normal 0 0 0\nouter loop\n";
            for i in t {
                let p = v(i);
                s += &format!("vertex {} {} {}\n", p[0], p[1], p[2]);
            }
            s += "endloop\nendfacet\n";
        }
    }
    s += "endsolid cube\n";
    std::fs::write(dir.join("cube.stl"), s).expect("write");
}

/// `setup`: a cube whose walls a table tilting to 95° reaches is green; to
/// 60° it is not feasible in one setup, a failed check: red (exit 3).
#[test]
fn setup_says_the_reports_verdict() {
    let d = tempfile::tempdir().expect("tmp");
    cube(d.path());
    let common = [
        "setup",
        "--stl",
        "cube.stl",
        "--clearance",
        "80",
        "--ignore-bottom",
        "--type",
        "ca",
        "--range2",
        "free",
        "--report",
        "su.html",
    ];
    let v = verdict(
        d.path(),
        &[&common[..], &["--range1", "0,95"]].concat(),
        Some("su.html"),
        0,
    );
    assert_eq!(v["level"], "green", "{v}");
    let v = verdict(
        d.path(),
        &[&common[..], &["--range1", "0,60"]].concat(),
        Some("su.html"),
        3,
    );
    assert_eq!(v["level"], "red", "{v}");
}

/// `orient` on the demo's ball-end finish re-orients it: green; a program
/// with a flat end mill only has nothing to act on: amber, the input kept,
/// exit 3.
#[test]
fn orient_says_its_verdict() {
    let d = demo();
    let args = [
        "orient",
        "finish.apt",
        "--stl",
        "part.stl",
        "--material",
        "al7075",
        "-o",
        "o.apt",
    ];
    let v = verdict(d.path(), &args, None, 0);
    assert_eq!(v["level"], "green", "{v}");
    // Operations count from 1 in the text, as in `inspect`, `gouge`, `feed`.
    let text = String::from_utf8_lossy(&run(d.path(), &args).stdout).to_string();
    assert!(text.starts_with("operation 1: lead"), "{text}");
    std::fs::write(
        d.path().join("flat.apt"),
        "UNITS/MM\nCUTTER/10\nSPINDL/8000,RPM,CLW\nFEDRAT/500,MMPM\nGOTO/0,0,5\nGOTO/0,0,-1\nGOTO/40,0,-1\n",
    )
    .expect("write");
    let flat = [
        "orient",
        "flat.apt",
        "--stl",
        "part.stl",
        "--material",
        "al7075",
        "-o",
        "f.apt",
    ];
    let v = verdict(d.path(), &flat, None, 3);
    assert_eq!(
        (v["level"].as_str(), v["kept"].as_bool()),
        (Some("amber"), Some(true)),
        "{v}"
    );
}

const HEAD_B_TABLE_C: &str = "name = \"head B, table C\"
[control]
dialect = \"sinumerik\"
[spindle]
min = 500.0
max = 18000.0
accel = 6000.0
[feed]
max = 20000.0
[kinematics]
kind = \"head-b-table-c\"
pivot = 250.0
[kinematics.first]
min = -110.0
max = 110.0
[kinematics.second]
min = -720.0
max = 720.0
";

/// `post` of the demo's finish: green; on a machine whose spindle stops at
/// 5,000 1/min (the program runs at 6,000) the machine check fails and the
/// program is written under `--force` only: red (exit 3).
#[test]
fn post_says_its_verdict() {
    let d = demo();
    std::fs::write(d.path().join("m.toml"), HEAD_B_TABLE_C).expect("write");
    let slow = HEAD_B_TABLE_C.replace("max = 18000.0", "max = 5000.0");
    std::fs::write(d.path().join("slow.toml"), slow).expect("write");
    let args = ["post", "finish.apt", "--machine", "m.toml", "-o", "p.mpf"];
    let v = verdict(d.path(), &args, None, 0);
    assert_eq!(v["level"], "green", "{v}");
    let forced = [
        "post",
        "finish.apt",
        "--machine",
        "slow.toml",
        "-o",
        "p.mpf",
        "--force",
    ];
    let v = verdict(d.path(), &forced, None, 3);
    assert_eq!(v["level"], "red", "{v}");
    assert!(v["failed"][0]
        .as_str()
        .is_some_and(|f| f.contains("check machine") && f.contains("spindle")));
}

/// Nothing to act on is no silent success: `force` and `feed` whose stock
/// no cutting move meets say so, amber with the input kept, exit 3; `speed`
/// on a program whose only cutter is a flat end mill says there is no
/// ball-end operation, exit 3, nothing written.
#[test]
fn nothing_to_act_on_says_so_and_exits_3() {
    let d = demo();
    slot(d.path());
    let far = [
        "--stock",
        "box:-30,-30,-50,70,70,-40",
        "--tool",
        "ball:10",
        "--material",
        "al7075",
        "--resolution",
        "0.5",
    ];
    for cmd in ["force", "feed"] {
        let mut args = vec![cmd, "slot.nc"];
        args.extend(far);
        if cmd == "feed" {
            args.extend(["-o", "air.nc"]);
        }
        let v = verdict(d.path(), &args, None, 3);
        assert_eq!(v["kept"], true, "{cmd}: {v}");
        assert!(
            v["warnings"].as_array().into_iter().flatten().any(|w| w
                .as_str()
                .is_some_and(|w| w.starts_with("no cutting move meets the stock"))),
            "{cmd}: {v}"
        );
    }
    std::fs::write(
        d.path().join("flat.apt"),
        "UNITS/MM\nCUTTER/10\nSPINDL/8000,RPM,CLW\nFEDRAT/500,MMPM\nGOTO/0,0,5\nGOTO/0,0,-1\nGOTO/40,0,-1\n",
    )
    .expect("write");
    let o = run(
        d.path(),
        &[
            "speed", "flat.apt", "--stl", "part.stl", "--vc", "63", "--fz", "0.1", "--ap", "0.3",
            "-o", "s.apt",
        ],
    );
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(
            "flat.apt: the program has no ball-end operation (its cutters: D10.000 R0.000)"
        ),
        "{err}"
    );
    assert!(
        err.contains("nothing for spindle control to act on"),
        "{err}"
    );
    assert!(!d.path().join("s.apt").exists());
}

/// `speed --help` names the machine file's reference, not the keys of the
/// single-purpose file it replaced (`spindle_min`, `feed_max`, …).
#[test]
fn speed_help_documents_the_machine_file_of_today() {
    let o = run(Path::new("."), &["speed", "--help"]);
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(help.contains("examples/machine.toml"), "{help}");
    for old in [
        "spindle_min",
        "spindle_max",
        "spindle_accel",
        "feed_min",
        "feed_max",
    ] {
        assert!(!help.contains(old), "{old}: {help}");
    }
}
