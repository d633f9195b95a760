//! Crash safety, concurrency and schema-version checks on a real database file.

use millplan_tooldb::control::{record, Kind, Measurement, Settings};
use millplan_tooldb::db::{DbError, ToolDb, ToolRecord};
use std::path::Path;
use std::time::Duration;

fn seed(path: &Path) {
    let mut db = ToolDb::open(path).expect("open");
    let mut t = ToolRecord::new(5, "thread mill");
    t.ltol = 0.05;
    t.rtol = 0.05;
    t.lbreak = 0.2;
    t.rbreak = 0.2;
    db.put_tool(&t).expect("put");
    db.record_presetter(5, 120.0, 6.9).expect("preset");
    record(
        &mut db,
        &Measurement {
            tool: 5,
            kind: Kind::First,
            l: Some(120.0),
            r: Some(6.9),
            per_tooth: None,
            pz: Some(0.5),
        },
        &Settings::default(),
    )
    .expect("first");
}

fn inspection(i: usize) -> Measurement {
    // Alternate ±1 µm so the tool stays within its wear tolerance.
    let d = if i.is_multiple_of(2) { 0.001 } else { -0.001 };
    Measurement {
        tool: 5,
        kind: Kind::Inspection,
        l: Some(120.0 + d),
        r: Some(6.9 + d),
        per_tooth: None,
        pz: Some(0.5),
    }
}

/// Run by `killed_writer_leaves_a_sound_database` in a child process.
#[test]
#[ignore = "child process of killed_writer_leaves_a_sound_database"]
fn child_writer_loop() {
    let Some(path) = std::env::var_os("MILLPLAN_TOOLDB_CHILD") else {
        return;
    };
    let mut db = ToolDb::open(Path::new(&path)).expect("open");
    for i in 0.. {
        record(&mut db, &inspection(i), &Settings::default()).expect("record");
    }
}

#[test]
fn killed_writer_leaves_a_sound_database() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("tools.db");
    seed(&path);
    for round in 0..3 {
        let mut child = std::process::Command::new(std::env::current_exe().expect("exe"))
            .args(["--exact", "child_writer_loop", "--ignored", "--nocapture"])
            .env("MILLPLAN_TOOLDB_CHILD", &path)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("spawn");
        std::thread::sleep(Duration::from_millis(400 + 150 * round));
        child.kill().expect("kill");
        let _ = child.wait();
        let db = ToolDb::open(&path).expect("reopens after a kill");
        assert_eq!(db.integrity().expect("check"), "ok");
        // Every committed measurement has its decision: nothing half-written.
        let m = db.measurement_count().expect("count");
        let e = db.events(None).expect("events").len() as i64;
        assert_eq!(m, e, "round {round}");
        assert!(m > 1, "the child wrote nothing in round {round}");
    }
}

#[test]
fn readers_work_while_a_writer_writes() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("tools.db");
    seed(&path);
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let readers: Vec<_> = (0..3)
        .map(|_| {
            let (path, done) = (path.clone(), done.clone());
            std::thread::spawn(move || {
                let db = ToolDb::open(&path).expect("open");
                let mut reads = 0;
                while !done.load(std::sync::atomic::Ordering::Relaxed) {
                    let t = db.tool(5).expect("read while writing");
                    assert!(t.measured);
                    db.events(Some(5)).expect("log while writing");
                    reads += 1;
                }
                reads
            })
        })
        .collect();
    let mut db = ToolDb::open(&path).expect("open");
    for i in 0..300 {
        record(&mut db, &inspection(i), &Settings::default()).expect("write while reading");
    }
    done.store(true, std::sync::atomic::Ordering::Relaxed);
    for r in readers {
        assert!(r.join().expect("reader") > 0);
    }
    assert_eq!(db.measurement_count().expect("count"), 301);
}

#[test]
fn a_database_from_a_newer_version_is_refused_and_left_alone() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("tools.db");
    seed(&path);
    {
        let c = rusqlite::Connection::open(&path).expect("raw");
        c.execute_batch("PRAGMA user_version = 99").expect("bump");
    }
    let before = std::fs::read(&path).expect("bytes");
    match ToolDb::open(&path) {
        Err(DbError::NewerSchema { found: 99, known }) => assert!(known < 99),
        Err(e) => panic!("wrong error {e}"),
        Ok(_) => panic!("opened a newer database"),
    }
    let c = rusqlite::Connection::open(&path).expect("raw");
    let v: i64 = c
        .query_row("PRAGMA user_version", [], |r| r.get(0))
        .expect("version");
    assert_eq!(v, 99);
    assert_eq!(std::fs::read(&path).expect("bytes").len(), before.len());
}
