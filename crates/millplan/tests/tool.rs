//! `millplan tool` and `millplan thread` through the binary.

use std::path::Path;
use std::process::Command;

fn run(db: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
        .arg("tool")
        .args(["--db", db.to_str().expect("utf8")])
        .args(args)
        .output()
        .expect("runs")
}

fn ok_json(db: &Path, args: &[&str]) -> serde_json::Value {
    let mut a = args.to_vec();
    a.push("--json");
    let o = run(db, &a);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("json")
}

#[test]
fn pz_and_thread_check_keys() {
    let o = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args(["tool", "pz", "--insl", "12.1", "--tp", "1.5", "--json"])
        .output()
        .expect("runs");
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert!(
        (j["pz"].as_f64().expect("pz") - 0.80).abs() < 1e-12,
        "paper 002 table 2"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args(["tool", "pz", "--insl", "14", "--tp=-1"])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2), "negative pitch");
    let o = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args([
            "thread", "check", "M20x1", "--class", "6H", "--d2", "19.30", "--json",
        ])
        .output()
        .expect("runs");
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(
        (j["ok"].as_bool(), j["min"].as_f64(), j["max"].as_f64()),
        (Some(false), Some(19.35), Some(19.51))
    );
    let o = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args(["thread", "check", "M99x7", "--class", "6H", "--d2", "1"])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn a_tool_room_session() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = dir.path().join("lib").join("tools.db");
    for n in ["5", "6"] {
        ok_json(
            &db,
            &[
                "add",
                n,
                "--name",
                "thread mill",
                "--kind",
                "thread-mill",
                "--insl",
                "14",
                "--tp",
                "1",
                "--rtol",
                "0.01",
                "--rbreak",
                "0.05",
                "--ltol",
                "0.02",
                "--lbreak",
                "0.1",
            ],
        );
        ok_json(&db, &["preset", n, "--l", "120", "--r", "6.9"]);
    }
    ok_json(&db, &["add", "5", "--sister", "6"]);
    let j = ok_json(
        &db,
        &["measure", "5", "--first", "--l", "120.01", "--r", "6.95"],
    );
    assert_eq!(j["decision"], "setup-mismatch");
    assert_eq!(j["switch_to"], 6);
    let j = ok_json(
        &db,
        &["measure", "6", "--first", "--l", "120.003", "--r", "6.899"],
    );
    assert_eq!(j["decision"], "first-accepted");
    let j = ok_json(
        &db,
        &["measure", "6", "--teeth", "6.898,6.897", "--pallet", "P2"],
    );
    assert_eq!(j["decision"], "wear-compensated");
    let log = ok_json(&db, &["log"]);
    assert_eq!(log.as_array().expect("log").len(), 3);
    // Export / import round trip through CSV and the TOOL.T table.
    let csv = dir.path().join("tools.csv");
    ok_json(
        &db,
        &[
            "export",
            "--format",
            "csv",
            "-o",
            csv.to_str().expect("utf8"),
        ],
    );
    let db2 = dir.path().join("copy.db");
    ok_json(&db2, &["import", csv.to_str().expect("utf8")]);
    assert_eq!(ok_json(&db2, &["show"]), ok_json(&db, &["show"]));
    let tt = dir.path().join("TOOL.T");
    ok_json(
        &db,
        &[
            "export",
            "--format",
            "tool-t",
            "-o",
            tt.to_str().expect("utf8"),
        ],
    );
    assert!(std::fs::read_to_string(&tt)
        .expect("tool.t")
        .starts_with("BEGIN TOOL"));
    let h = dir.path().join("measure.h");
    let j = ok_json(&db, &["cycle", "6", "-o", h.to_str().expect("utf8")]);
    assert_eq!(j["pz"], 0.5);
    assert!(std::fs::read_to_string(&h)
        .expect("cycle")
        .contains("TCH PROBE 483"));
}

#[test]
fn bad_inputs_change_nothing() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = dir.path().join("tools.db");
    ok_json(&db, &["add", "1", "--name", "keep"]);
    let before = ok_json(&db, &["show"]);
    let o = run(&db, &["measure", "99", "--l", "1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no tool 99"));
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "number,name,r\n2,ok,3\n3,bad,x\n").expect("write");
    let o = run(&db, &["import", bad.to_str().expect("utf8")]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("bad.csv:3:3:"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = run(&db, &["measure", "1", "--r", "1"]);
    assert_eq!(o.status.code(), Some(2), "no tolerances set");
    assert_eq!(ok_json(&db, &["show"]), before);
    assert!(ok_json(&db, &["log"]).as_array().expect("log").is_empty());
    // A library written by a newer millplan is refused.
    let newer = dir.path().join("newer.db");
    ok_json(&newer, &["show"]);
    rusqlite::Connection::open(&newer)
        .expect("raw")
        .execute_batch("PRAGMA user_version = 42")
        .expect("bump");
    let o = run(&newer, &["show"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("newer millplan"));
}
