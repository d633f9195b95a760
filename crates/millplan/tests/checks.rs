//! The checks before writing (issue 31 item 4) end to end: a command whose
//! output fails a check exits 3 naming the line and the check, and writes
//! nothing unless --force; the checks that ran are in the JSON.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf8")
}

fn demo(dir: &Path) -> PathBuf {
    let d = dir.join("demo");
    let o = bin().args(["demo", "-o", s(&d)]).output().expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    d
}

/// `raster` over the demo part with a D10 ball, 3 mm passes, and `extra`.
fn raster(d: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    bin()
        .args([
            "raster",
            "--stl",
            s(&d.join("part.stl")),
            "--tool",
            "ball:10",
        ])
        .args(["--stepover", "3", "--step", "1", "-o", s(out)])
        .args(extra)
        .output()
        .expect("runs")
}

/// The line a `PATH:LINE: check NAME:` message names.
fn named_line(stderr: &str, path: &Path, check: &str) -> usize {
    let head = format!("{}:", path.display());
    let line = stderr
        .lines()
        .find(|l| l.contains(&format!(": check {check}:")))
        .unwrap_or_else(|| panic!("no check {check} in {stderr}"));
    let rest = line
        .strip_prefix(&head)
        .unwrap_or_else(|| panic!("{line} does not name {head}"));
    rest.split(':')
        .next()
        .expect("line")
        .parse()
        .expect("a line number")
}

#[test]
fn a_feed_above_the_machine_is_refused_at_its_line_and_nothing_written() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = demo(dir.path());
    let out = dir.path().join("r.apt");
    // The default machine's maximum feed is 20,000 mm/min.
    let o = raster(&d, &out, &["--feed", "30000"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(!out.exists(), "nothing is written");
    assert!(
        err.contains("above the machine's maximum 20000 mm/min"),
        "{err}"
    );
    assert!(err.contains("nothing written (--force writes it)"), "{err}");
    let line = named_line(&err, &out, "machine");
    // --force writes the same program: the line named is a cutting move.
    let o = raster(&d, &out, &["--feed", "30000", "--force"]);
    assert_eq!(o.status.code(), Some(3));
    let text = std::fs::read_to_string(&out).expect("written with --force");
    let at = text.lines().nth(line - 1).expect("the line exists");
    assert!(at.starts_with("GOTO/"), "line {line}: {at}");
    let before = text.lines().take(line).collect::<Vec<_>>().join("\n");
    assert!(before.contains("FEDRAT/30000"), "{before}");
}

#[test]
fn a_spindle_speed_outside_the_machine_is_refused() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = demo(dir.path());
    let out = dir.path().join("r.nc");
    let o = raster(&d, &out, &["--spindle", "30000", "--json"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(!out.exists());
    assert!(
        err.contains("check machine: S30000 outside the machine's spindle range 500..18000"),
        "{err}"
    );
    // A clean raster says what it checked.
    let o = raster(&d, &out, &["--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let names: Vec<_> = j["checks"]
        .as_array()
        .expect("checks")
        .iter()
        .map(|c| {
            (
                c["name"].as_str().unwrap_or("").to_string(),
                c["ok"].as_bool(),
            )
        })
        .collect();
    let want = [
        "read-back",
        "ir",
        "machine",
        "tip",
        "stock",
        "gouge",
        "loads",
    ];
    assert_eq!(names.len(), want.len(), "{names:?}");
    for ((n, ok), w) in names.iter().zip(want) {
        assert_eq!((n.as_str(), *ok), (w, Some(true)));
    }
    assert!(
        j["checks"][5]["checked"].as_u64().unwrap_or(0) > 1000,
        "{}",
        j["checks"][5]
    );
}

#[test]
fn speed_checks_machine_and_positions_and_says_why_it_simulates_nothing() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = demo(dir.path());
    let o = bin()
        .args([
            "speed",
            s(&d.join("finish.apt")),
            "--stl",
            s(&d.join("part.stl")),
        ])
        .args(["--vc", "63", "--fz", "0.1", "--ap", "0.3", "--json", "-q"])
        .args(["--machine", s(&d.join("machine.toml"))])
        .args(["-o", s(&dir.path().join("vc.nc"))])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let checks = j["checks"].as_array().expect("checks");
    let by = |n: &str| {
        checks
            .iter()
            .find(|c| c["name"] == n)
            .unwrap_or_else(|| panic!("no {n}"))
    };
    for n in ["ir", "machine", "tip"] {
        assert_eq!(by(n)["ok"], true, "{}", by(n));
        assert!(by(n)["checked"].as_u64().unwrap_or(0) > 6000, "{}", by(n));
    }
    for n in ["stock", "gouge"] {
        let why = by(n)["skipped"].as_str().unwrap_or("");
        assert!(why.starts_with("positions kept"), "{n}: {why}");
    }
}

/// A rapid planted into the demo's finishing pass (the stock 0.5 mm over
/// the part): `orient --stock` refuses it at its line and names it as the
/// input's own fault.
#[test]
fn orient_refuses_a_rapid_through_the_stock_that_the_input_had() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = demo(dir.path());
    let src = std::fs::read_to_string(d.join("finish.apt")).expect("demo");
    let mut lines: Vec<&str> = src.lines().collect();
    // Line 25 is a cutting GOTO in the middle of the first pass.
    assert!(lines[24].starts_with("GOTO/"), "{}", lines[24]);
    lines.insert(24, "RAPID");
    let planted = dir.path().join("planted.apt");
    std::fs::write(&planted, lines.join("\n") + "\n").expect("write");
    let out = dir.path().join("or.apt");
    let o = bin()
        .args(["orient", s(&planted), "--stl", s(&d.join("part.stl"))])
        .args([
            "--material",
            "al7075",
            "--stock",
            "offset:0.5",
            "--samples",
            "8",
            "-q",
        ])
        .args(["-o", s(&out)])
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(!out.exists());
    // The GOTO after the RAPID is line 26.
    assert_eq!(named_line(&err, &planted, "stock"), 26, "{err}");
    assert!(err.contains("rapid through material"), "{err}");
    assert!(err.contains("(the input's own fault)"), "{err}");
}

/// `feed` keeps every position, so a rapid the input drives into the stock
/// is in its output too: refused at its line before any force is computed
/// (exit 3, nothing written), and written with exit 3 under --force, the
/// check failed in the JSON.
#[test]
fn feed_refuses_a_rapid_into_the_stock_at_its_line() {
    let dir = tempfile::tempdir().expect("tmp");
    let apt = dir.path().join("in.apt");
    // Line 8: a rapid from 50 down to 15, 5 mm into the 20 mm box.
    let program = "UNITS/MM\nCUTTER/10,5\nFEDRAT/500\nSPINDL/6000,CLW\nRAPID\nGOTO/0,0,50\nRAPID\nGOTO/0,0,15\nGOTO/0,0,14\nGOTO/5,0,14\nRAPID\nGOTO/5,0,50\nFINI\n";
    std::fs::write(&apt, program).expect("write");
    let out = dir.path().join("out.apt");
    let run = |extra: &[&str]| {
        bin()
            .args(["feed", s(&apt), "-o", s(&out), "--material", "al7075"])
            .args(["--stock", "box:-10,-10,0,40,10,20", "--resolution", "1"])
            .args(extra)
            .output()
            .expect("runs")
    };
    let o = run(&["-q"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(!out.exists(), "nothing written");
    assert_eq!(named_line(&err, &apt, "stock"), 8, "{err}");
    assert!(err.contains("rapid through material"), "{err}");
    assert!(err.contains("(the input's own fault)"), "{err}");
    let o = run(&["-q", "--force", "--json"]);
    assert_eq!(o.status.code(), Some(3));
    assert!(out.exists(), "written under --force");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let stock = v["checks"]
        .as_array()
        .expect("checks")
        .iter()
        .find(|c| c["name"] == "stock")
        .expect("the stock check");
    assert_eq!(stock["ok"], false, "{stock}");
    assert_eq!(v["verdict"]["level"], "red", "{}", v["verdict"]);
}

/// A user trial: `gouge` on a program whose only cuts are canned-cycle
/// holes, its tool without a shape, said "no move could be checked" with
/// every count at zero. Holes are cuts: the tool's shape is asked for at
/// its line, and with `--tool` every hole is checked along its axis.
#[test]
fn gouge_asks_for_the_shape_of_a_tool_that_only_drills() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = demo(dir.path());
    let nc = dir.path().join("holes.nc");
    std::fs::write(
        &nc,
        "G21 G90 G17\nT1 M6\nS1000 M3\nG0 X0 Y0 Z10\nG81 X10 Y10 Z-5 R2 F100\nX20\nG80\nM30\n",
    )
    .expect("write");
    let gouge = |extra: &[&str]| {
        bin()
            .args(["gouge", s(&nc), "--stl", s(&d.join("part.stl")), "-q"])
            .args(extra)
            .output()
            .expect("runs")
    };
    let o = gouge(&[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("holes.nc:2:1: the program does not say the shape of its tool"),
        "{err}"
    );
    let o = gouge(&["--tool", "ball:6", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(v["moves_checked"], 2, "{v}");
    assert_eq!(v["moves_skipped"], 0, "{v}");
    // A review: the samples counted against the memory limit before any
    // work left the holes out, so a hole 500 m deep at a step of 1 µm
    // tried to take 40 GB. It is refused first.
    let deep = dir.path().join("deep.nc");
    std::fs::write(
        &deep,
        "G21 G90 G17\nT1 M6\nS1000 M3\nG0 X0 Y0 Z10\nG81 X10 Y10 Z-500000 R2 F100\nG80\nM30\n",
    )
    .expect("write");
    let o = bin()
        .args(["gouge", s(&deep), "--stl", s(&d.join("part.stl")), "-q"])
        .args([
            "--tool",
            "flat:6",
            "--step",
            "0.001",
            "--limit",
            "memory=500",
        ])
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("over the memory limit"), "{err}");
}
