//! `millplan tool` and `millplan thread` through the binary.

use std::path::{Path, PathBuf};
use std::process::Command;

fn run(db: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
        .arg("tool")
        .args(["--db", db.to_str().expect("utf8")])
        .args(args)
        .output()
        .expect("runs")
}

/// Runs with --json, checks the exit code, returns the JSON it printed.
fn json_exit(db: &Path, args: &[&str], code: i32) -> serde_json::Value {
    let mut a = args.to_vec();
    a.push("--json");
    let o = run(db, &a);
    assert_eq!(
        o.status.code(),
        Some(code),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("json")
}

fn ok_json(db: &Path, args: &[&str]) -> serde_json::Value {
    json_exit(db, args, 0)
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A failed command: its exit code, the library named in its message, nothing
/// on standard output, no panic.
fn fails(db: &Path, args: &[&str], code: i32, says: &str) -> String {
    let o = run(db, args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(code), "{args:?}: {err}");
    if args.contains(&"--json") {
        // Under --json the error is JSON naming the library as its file.
        let e: serde_json::Value = serde_json::from_str(&err).expect("a JSON error");
        assert_eq!(
            e["error"]["file"],
            db.display().to_string(),
            "{args:?}: {err}"
        );
    } else {
        assert!(
            err.starts_with(&format!("error: {}: ", db.display())),
            "{args:?}: {err}"
        );
    }
    assert!(err.contains(says), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(o.stdout.is_empty(), "{args:?}");
    err
}

/// Every row of the library's tools table as text, read behind millplan's back.
fn raw_tools(db: &Path) -> Vec<String> {
    let c = rusqlite::Connection::open(db).expect("raw");
    let mut st = c
        .prepare("SELECT quote(number), quote(name), quote(kind), quote(l), quote(r), quote(ltol), quote(rtol), quote(lbreak), quote(rbreak), quote(locked), quote(sister) FROM tools ORDER BY number")
        .expect("prepare");
    let rows = st
        .query_map([], |r| {
            (0..11)
                .map(|i| r.get::<_, String>(i))
                .collect::<Result<Vec<_>, _>>()
        })
        .expect("query");
    rows.map(|r| r.expect("row").join("|")).collect()
}

fn a_thread_mill(db: &Path, n: &str) {
    ok_json(
        db,
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
    ok_json(db, &["preset", n, "--l", "120", "--r", "6.9"]);
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
}

fn thread_check(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args(["thread", "check"])
        .args(args)
        .output()
        .expect("runs")
}

#[test]
fn thread_check_exits_3_on_reject() {
    // Spec §5: M20×1-6H gauge decisions (19.515 is out by the standard).
    for (d2, ok, code, verdict) in [
        ("19.30", false, 3, "REJECT: 0.050 mm under the minimum"),
        ("19.40", true, 0, ": OK"),
        ("19.515", false, 3, "REJECT: 0.005 mm over the maximum"),
    ] {
        let o = thread_check(&["M20x1", "--class", "6H", "--d2", d2, "--json"]);
        assert_eq!(o.status.code(), Some(code), "{d2}: {}", stderr(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
        assert_eq!(
            (j["ok"].as_bool(), j["min"].as_f64(), j["max"].as_f64()),
            (Some(ok), Some(19.35), Some(19.51)),
            "{d2}"
        );
        let o = thread_check(&["M20x1", "--class", "6H", "--d2", d2]);
        assert_eq!(o.status.code(), Some(code), "{d2}");
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.trim_end().ends_with(verdict), "{d2}: {text}");
    }
    for bad in [
        &["M99x7", "--class", "6H", "--d2", "1"][..],
        &["M20x1", "--class", "6H", "--d2", "NaN"],
        &["M20x1", "--class", "6H", "--d2=-19.4"],
    ] {
        let o = thread_check(bad);
        assert_eq!(o.status.code(), Some(2), "{bad:?}: {}", stderr(&o));
        assert!(o.stdout.is_empty() && stderr(&o).starts_with("error: "));
    }
    let help = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args(["thread", "check", "--help"])
        .output()
        .expect("runs");
    assert!(String::from_utf8_lossy(&help.stdout).contains("Exit 0 for OK, 3 for REJECT"));
}

#[test]
fn thread_limits_and_checks_of_more_classes() {
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_millplan"))
            .arg("thread")
            .args(args)
            .output()
            .expect("runs")
    };
    // Spec §4.7: M10×1.5-6H pitch 9.026–9.206, D1 8.376–8.676, D ≥ 10.000.
    let o = run(&["limits", "M10x1.5", "--class", "6H", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(
        (
            j["pitch_diameter_mm"]["min"].as_f64(),
            j["pitch_diameter_mm"]["max"].as_f64(),
            j["crest_diameter_mm"]["min"].as_f64(),
            j["crest_diameter_mm"]["max"].as_f64(),
            j["major_diameter_min_mm"].as_f64(),
            j["pitch_tolerance_um"].as_u64(),
        ),
        (
            Some(9.026),
            Some(9.206),
            Some(8.376),
            Some(8.676),
            Some(10.0),
            Some(180)
        )
    );
    // Yamawa's 5H M6×1: T_D2 = 118 µm; ASME B1.13M 4g6g M10×1.5: d2 8.909–8.994.
    let text =
        String::from_utf8_lossy(&run(&["limits", "M6x1", "--class", "5H"]).stdout).to_string();
    assert!(text.contains("D2 5.350 … 5.468 mm (T_D2 118 µm"), "{text}");
    let o = run(&[
        "check", "M10x1.5", "--class", "4g6g", "--d2", "8.9", "--json",
    ]);
    assert_eq!(o.status.code(), Some(3), "8.9 < 8.909: {}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(
        (j["min"].as_f64(), j["max"].as_f64()),
        (Some(8.909), Some(8.994))
    );
    // A crest tolerance only one source gives: the limits say so, the
    // pitch diameter is still given.
    let text =
        String::from_utf8_lossy(&run(&["limits", "M10x1.5", "--class", "4h"]).stdout).to_string();
    assert!(
        text.contains("major diameter d: not given (no confirmed T_d for grade 4"),
        "{text}"
    );
    // Classes the tables cannot tolerance: exit 2 with the reason, as JSON too.
    for class in ["7H", "6e"] {
        let o = run(&["limits", "M10x1.5", "--class", class, "--json"]);
        assert_eq!(o.status.code(), Some(2), "{class}");
        let e: serde_json::Value = serde_json::from_slice(&o.stderr).expect("json error");
        let msg = e["error"]["message"]
            .as_str()
            .unwrap_or_default()
            .to_string();
        assert!(msg.contains("M10x1.5-") && msg.contains(class), "{msg}");
    }
}

#[test]
fn a_tool_room_session() {
    let dir = tempfile::tempdir().expect("tmp");
    // `--db` never creates its folder (issue 34): the shop makes it.
    std::fs::create_dir(dir.path().join("lib")).expect("mkdir");
    let db = dir.path().join("lib").join("tools.db");
    for n in ["5", "6"] {
        a_thread_mill(&db, n);
    }
    ok_json(&db, &["add", "5", "--sister", "6"]);
    // A setup mismatch locks the tool: a problem found, exit 3, JSON as ever.
    let j = json_exit(
        &db,
        &["measure", "5", "--first", "--l", "120.01", "--r", "6.95"],
        3,
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
}

#[test]
fn measure_exits_3_when_the_tool_is_locked() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = dir.path().join("tools.db");
    for n in ["5", "6"] {
        a_thread_mill(&db, n);
    }
    for n in ["5", "6"] {
        let j = ok_json(&db, &["measure", n, "--first", "--l", "120", "--r", "6.9"]);
        assert_eq!(j["decision"], "first-accepted");
    }
    let j = ok_json(&db, &["measure", "5", "--r", "6.895"]);
    assert_eq!(j["decision"], "wear-compensated");
    // 0.02 under the compensated radius: beyond RTOL 0.01, within RBREAK 0.05.
    let o = run(&db, &["measure", "5", "--r", "6.875"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.starts_with("WORN: "), "{text}");
    // A tooth 0.1 short: broken, the pallet locked too.
    let j = json_exit(
        &db,
        &["measure", "6", "--teeth", "6.9,6.8", "--pallet", "P1"],
        3,
    );
    assert_eq!(
        (&j["decision"], &j["tool_locked"], &j["pallet_locked"]),
        (&"broken".into(), &true.into(), &true.into())
    );
    let o = run(&db, &["measure", "6", "--r", "6.9"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // Every decision logged, whatever the exit code.
    let log = ok_json(&db, &["log"]);
    let decisions: Vec<_> = log
        .as_array()
        .expect("log")
        .iter()
        .map(|e| e["decision"].as_str().expect("decision").to_string())
        .collect();
    assert_eq!(
        decisions,
        [
            "first-accepted",
            "first-accepted",
            "wear-compensated",
            "worn",
            "broken",
            "wear-compensated"
        ]
    );
    let help = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args(["tool", "measure", "--help"])
        .output()
        .expect("runs");
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains("setup-mismatch, worn and broken (exit 3"),
        "{help}"
    );
}

/// Issue 15: a tool row that cannot be read was taken for "new tool" and
/// overwritten by `add` with only the values given.
#[test]
fn add_never_overwrites_a_tool_it_cannot_read() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = dir.path().join("tools.db");
    a_thread_mill(&db, "5");
    rusqlite::Connection::open(&db)
        .expect("raw")
        .execute_batch("UPDATE tools SET ltol = 'abc' WHERE number = 5")
        .expect("damage");
    let before = raw_tools(&db);
    let out = dir.path().join("out");
    for args in [
        &["add", "5", "--rtol", "0.02"][..],
        &["add", "5", "--rtol", "0.02", "--json"],
        &["show", "5"],
        &["show"],
        &["measure", "5", "--r", "6.9"],
        &["preset", "5", "--l", "120", "--r", "6.9"],
        &["cycle", "5", "-o", out.to_str().expect("utf8")],
        &["export", "-o", out.to_str().expect("utf8")],
    ] {
        let err = fails(&db, args, 2, "tool 5: ");
        assert!(err.contains("cannot read"), "{err}");
        assert!(!err.contains("no tool"), "{err}");
    }
    assert_eq!(raw_tools(&db), before);
    assert!(!out.exists());
    // A tool the library does not have is still new.
    ok_json(&db, &["add", "7", "--name", "new"]);
}

#[test]
fn a_file_that_is_not_a_library_is_refused_and_left_alone() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = dir.path().join("tools.db");
    let text = b"number,name\n5,thread mill\n".repeat(40);
    std::fs::write(&db, &text).expect("write");
    let csv = dir.path().join("in.csv");
    std::fs::write(&csv, "number,name\n1,a\n").expect("write");
    for args in [
        &["show"][..],
        &["show", "--json"],
        &["add", "1", "--name", "x"],
        &["log"],
        &["import", csv.to_str().expect("utf8")],
    ] {
        fails(&db, args, 2, "file is not a database");
    }
    assert_eq!(std::fs::read(&db).expect("read"), text);
    let mut names: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    names.sort();
    assert_eq!(names, ["in.csv", "tools.db"]);
}

#[test]
fn a_library_from_a_newer_millplan_is_refused_and_left_alone() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = dir.path().join("tools.db");
    a_thread_mill(&db, "5");
    rusqlite::Connection::open(&db)
        .expect("raw")
        .execute_batch("PRAGMA journal_mode = DELETE; PRAGMA user_version = 42")
        .expect("bump");
    let before = std::fs::read(&db).expect("read");
    for args in [&["show"][..], &["add", "5", "--name", "x"]] {
        fails(&db, args, 2, "newer millplan");
    }
    assert_eq!(std::fs::read(&db).expect("read"), before);
}

/// Makes a file unwritable even for root: read-only permissions, then the
/// immutable attribute (undone on drop).
struct Unwritable(PathBuf);

impl Unwritable {
    fn new(path: &Path) -> Option<Unwritable> {
        let writable = || std::fs::OpenOptions::new().append(true).open(path).is_ok();
        let mut p = std::fs::metadata(path).expect("meta").permissions();
        p.set_readonly(true);
        std::fs::set_permissions(path, p).expect("chmod");
        let guard = Unwritable(path.to_path_buf());
        if !writable() {
            return Some(guard);
        }
        let _ = Command::new("chattr").arg("+i").arg(path).status();
        (!writable()).then_some(guard)
    }
}

impl Drop for Unwritable {
    fn drop(&mut self) {
        let _ = Command::new("chattr")
            .arg("-i")
            .arg(&self.0)
            .stderr(std::process::Stdio::null())
            .status();
        if let Ok(m) = std::fs::metadata(&self.0) {
            let mut p = m.permissions();
            #[allow(clippy::permissions_set_readonly_false)]
            p.set_readonly(false);
            let _ = std::fs::set_permissions(&self.0, p);
        }
    }
}

#[test]
fn a_read_only_library_is_read_but_not_written() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = dir.path().join("tools.db");
    a_thread_mill(&db, "5");
    let before = raw_tools(&db);
    let csv = dir.path().join("in.csv");
    std::fs::write(&csv, "number,name\n1,a\n").expect("write");
    {
        let Some(_ro) = Unwritable::new(&db) else {
            eprintln!("skipped: this system cannot make a file unwritable");
            return;
        };
        let j = ok_json(&db, &["show", "5"]);
        assert_eq!(j[0]["name"], "thread mill");
        fails(
            &db,
            &["add", "5", "--name", "other"],
            1,
            "readonly database",
        );
        fails(
            &db,
            &["measure", "5", "--first", "--r", "6.9"],
            1,
            "readonly",
        );
        // The library is at fault, not the file being imported.
        fails(
            &db,
            &["import", csv.to_str().expect("utf8")],
            1,
            "not writable",
        );
    }
    assert_eq!(raw_tools(&db), before);
}

#[test]
fn a_locked_library_is_waited_for_then_reported() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = dir.path().join("tools.db");
    a_thread_mill(&db, "5");
    let before = raw_tools(&db);
    // Another program holds the write lock with a change not yet committed.
    let other = rusqlite::Connection::open(&db).expect("raw");
    other
        .execute_batch("BEGIN IMMEDIATE; UPDATE tools SET name = 'held' WHERE number = 5;")
        .expect("lock");
    let j = ok_json(&db, &["show", "5"]);
    assert_eq!(j[0]["name"], "thread mill", "readers are not blocked");
    let t0 = std::time::Instant::now();
    fails(
        &db,
        &["add", "5", "--name", "other"],
        1,
        "database is locked",
    );
    assert!(t0.elapsed().as_secs_f64() > 5.0, "waited for the lock");
    other.execute_batch("ROLLBACK").expect("unlock");
    assert_eq!(raw_tools(&db), before);
    ok_json(&db, &["add", "5", "--name", "other"]);
}

#[test]
fn a_library_that_cannot_be_opened_is_a_system_failure() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = dir.path().join("tools.db");
    a_thread_mill(&db, "5");
    let before = std::fs::read(&db).expect("read");
    // The write-ahead log cannot be a file: SQLite cannot open the library.
    std::fs::create_dir(dir.path().join("tools.db-wal")).expect("mkdir");
    fails(&db, &["show"], 1, "unable to open database file");
    assert_eq!(std::fs::read(&db).expect("read"), before);
}

#[test]
fn library_paths_are_files_or_refused() {
    let dir = tempfile::tempdir().expect("tmp");
    fails(dir.path(), &["show"], 2, "is a folder");
    let o = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args(["tool", "show"])
        .env("MILLPLAN_DB", "")
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("MILLPLAN_DB is set but empty"));
    // SQLite's special names are plain file names here: what is saved stays saved.
    for name in [":memory:", "file:lib.db?mode=memory"] {
        let tool = |args: &[&str]| {
            Command::new(env!("CARGO_BIN_EXE_millplan"))
                .current_dir(dir.path())
                .args(["tool", "--db", name, "--json"])
                .args(args)
                .output()
                .expect("runs")
        };
        assert!(tool(&["add", "1", "--name", "kept"]).status.success());
        assert!(dir.path().join(name).is_file(), "{name}");
        let j: serde_json::Value =
            serde_json::from_slice(&tool(&["show", "1"]).stdout).expect("json");
        assert_eq!(j[0]["name"], "kept", "{name}");
    }
}

/// Issue 17: a closed standard output ends the run with a message and exit
/// 1 (the output is cut short), never a panic.
#[test]
fn closed_stdout_ends_with_a_message() {
    let dir = tempfile::tempdir().expect("tmp");
    let db = dir.path().join("tools.db");
    let csv = dir.path().join("many.csv");
    let mut text = String::from("number,name\n");
    for n in 0..3000 {
        text.push_str(&format!("{n},tool number {n} with a long enough name\n"));
    }
    std::fs::write(&csv, text).expect("write");
    ok_json(&db, &["import", csv.to_str().expect("utf8")]);
    // Far more than a pipe holds: the writer meets the closed pipe for sure.
    let mut child = Command::new(env!("CARGO_BIN_EXE_millplan"))
        .args(["tool", "--db", db.to_str().expect("utf8"), "show", "--json"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    drop(child.stdout.take());
    let o = child.wait_with_output().expect("wait");
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    // Under --json the message is JSON.
    assert!(
        stderr(&o).contains("\"message\":\"standard output: Broken pipe"),
        "{}",
        stderr(&o)
    );
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
}
