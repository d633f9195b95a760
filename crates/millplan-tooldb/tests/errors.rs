//! Real database failures on real files: each one is reported as what it is,
//! never taken for a missing tool, and leaves the file as it was.

use millplan_tooldb::control::{record, Kind, Measurement, Settings};
use millplan_tooldb::db::{DbError, ToolDb, ToolRecord};
use rusqlite::ErrorCode;
use std::path::Path;
use std::time::Duration;

fn library(path: &Path) -> ToolDb {
    let mut db = ToolDb::open(path).expect("open");
    let mut t = ToolRecord::new(5, "thread mill");
    t.kind = "thread-mill".into();
    t.ltol = 0.05;
    t.rtol = 0.05;
    t.lbreak = 0.2;
    t.rbreak = 0.2;
    t.sister = Some(6);
    db.put_tool(&t).expect("put");
    db.put_tool(&ToolRecord {
        number: 6,
        sister: None,
        ..t
    })
    .expect("put");
    db
}

fn raw(path: &Path, sql: &str) {
    rusqlite::Connection::open(path)
        .expect("raw")
        .execute_batch(sql)
        .expect("raw sql");
}

fn sqlite_code(e: &DbError) -> Option<ErrorCode> {
    match e {
        DbError::Sql(s) => s.sqlite_error_code(),
        _ => None,
    }
}

#[test]
fn only_a_missing_row_is_a_missing_tool() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("tools.db");
    let db = library(&path);
    assert_eq!(db.find_tool(7).expect("absent is no error"), None);
    assert!(matches!(db.tool(7), Err(DbError::UnknownTool(7))));
    // A number column holding text (REAL affinity keeps non-numeric text).
    raw(&path, "UPDATE tools SET ltol = 'abc' WHERE number = 5");
    for e in [
        db.find_tool(5).expect_err("unreadable row"),
        db.tool(5).expect_err("unreadable row"),
        db.tools().expect_err("unreadable row in the list"),
    ] {
        assert!(matches!(e, DbError::Damaged(_)), "{e:?}");
        assert!(e.to_string().starts_with("tool 5: "), "{e}");
        assert!(e.is_bad_input());
    }
    assert!(db.find_tool(6).expect("the other tool reads").is_some());
    // An ISO property that is not text.
    raw(
        &path,
        "INSERT INTO tool_props (tool, symbol, value) VALUES (6, 'IC', x'00ff')",
    );
    assert!(matches!(db.find_tool(6), Err(DbError::Damaged(_))));
}

#[test]
fn a_broken_sister_tool_is_reported_not_taken_for_none() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("tools.db");
    let mut db = library(&path);
    db.record_presetter(5, 120.0, 6.9).expect("preset");
    // The sister's row cannot be read: the duplicate search must say so instead
    // of answering "no duplicate".
    raw(&path, "UPDATE tools SET r = 'x' WHERE number = 6");
    let m = Measurement {
        tool: 5,
        kind: Kind::First,
        l: Some(120.0),
        r: Some(6.5),
        per_tooth: None,
        pz: None,
    };
    let e = record(&mut db, &m, &Settings::default()).expect_err("sister unreadable");
    assert!(e.to_string().starts_with("tool 6: "), "{e}");
    assert_eq!(db.measurement_count().expect("count"), 0, "rolled back");
    assert!(db.events(None).expect("log").is_empty());
}

#[test]
fn a_broken_duplicate_is_reported_not_taken_for_none() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("tools.db");
    let mut db = library(&path);
    db.record_presetter(5, 120.0, 6.9).expect("preset");
    let m = Measurement {
        tool: 5,
        kind: Kind::First,
        l: Some(120.0),
        r: Some(6.5),
        per_tooth: None,
        pz: None,
    };
    // No sister: the duplicate is searched by name and kind. A same-named tool
    // whose number no millplan tool can have cannot be read as a duplicate.
    let mut t = db.tool(5).expect("tool");
    t.sister = None;
    db.put_tool(&t).expect("put");
    raw(&path, "UPDATE tools SET locked = 1 WHERE number = 6");
    raw(
        &path,
        "INSERT INTO tools (number, name, kind) VALUES (5000000000, 'thread mill', 'thread-mill')",
    );
    let e = record(&mut db, &m, &Settings::default()).expect_err("duplicate unreadable");
    assert!(matches!(e, DbError::Damaged(_)), "{e:?}");
    assert!(e.to_string().starts_with("duplicates of tool 5: "), "{e}");
    assert_eq!(db.measurement_count().expect("count"), 0, "rolled back");
    // Without that row the search answers "none" and the decision is made.
    raw(&path, "DELETE FROM tools WHERE number = 5000000000");
    let o = record(&mut db, &m, &Settings::default()).expect("decided");
    assert_eq!(o.switch_to, None);
}

#[test]
fn a_log_entry_that_is_not_json_is_reported() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("tools.db");
    let db = library(&path);
    raw(
        &path,
        "INSERT INTO events (time, tool, decision, reason, inputs, outcome) \
         VALUES ('2024-01-01T00:00:00.000Z', 5, 'worn', 'r', '{not json', '{}')",
    );
    let e = db.events(None).expect_err("damaged log");
    assert!(matches!(e, DbError::Damaged(_)), "{e:?}");
    assert!(e.to_string().contains("event 1: inputs is not JSON"), "{e}");
}

#[test]
fn a_file_that_is_not_a_database_is_refused_and_left_alone() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("tools.db");
    let text = b"number,name\n5,not a database\n".repeat(20);
    std::fs::write(&path, &text).expect("write");
    let e = ToolDb::open(&path).err().expect("refused");
    assert_eq!(sqlite_code(&e), Some(ErrorCode::NotADatabase), "{e:?}");
    assert!(e.is_bad_input());
    assert!(e.to_string().contains("not a millplan tool library"), "{e}");
    assert_eq!(std::fs::read(&path).expect("read"), text);
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("tools.db")]);
}

#[test]
fn a_damaged_database_is_reported_as_damaged() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("tools.db");
    {
        let mut db = library(&path);
        for n in 10..60 {
            db.put_tool(&ToolRecord::new(n, &"long name ".repeat(20)))
                .expect("put");
        }
    }
    raw(&path, "PRAGMA wal_checkpoint(TRUNCATE)");
    let mut bytes = std::fs::read(&path).expect("read");
    let page = u16::from_be_bytes([bytes[16], bytes[17]]) as usize;
    assert!(bytes.len() >= 4 * page, "several pages");
    // Every page after the schema page overwritten.
    for b in &mut bytes[page..] {
        *b = 0xA5;
    }
    std::fs::write(&path, &bytes).expect("write");
    let e = match ToolDb::open(&path) {
        Err(e) => e,
        Ok(db) => db.tools().expect_err("damaged pages"),
    };
    assert_eq!(sqlite_code(&e), Some(ErrorCode::DatabaseCorrupt), "{e:?}");
    assert!(e.is_bad_input());
    assert_eq!(std::fs::read(&path).expect("read"), bytes, "left alone");
}

#[test]
fn a_newer_library_in_rollback_mode_is_refused_before_any_write() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("tools.db");
    drop(library(&path));
    // What a newer millplan might leave: another journal mode, a higher version.
    raw(
        &path,
        "PRAGMA journal_mode = DELETE; PRAGMA user_version = 7",
    );
    let before = std::fs::read(&path).expect("read");
    let e = ToolDb::open(&path).err().expect("refused");
    assert!(
        matches!(e, DbError::NewerSchema { found: 7, known: 1 }),
        "{e:?}"
    );
    assert!(e.is_bad_input());
    assert_eq!(
        std::fs::read(&path).expect("read"),
        before,
        "not switched to WAL"
    );
}

#[test]
fn a_locked_library_is_a_system_failure_not_a_missing_tool() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("tools.db");
    drop(library(&path));
    // Another program holds the write lock with a change not yet committed.
    let other = rusqlite::Connection::open(&path).expect("raw");
    other
        .execute_batch("BEGIN IMMEDIATE; UPDATE tools SET name = 'held' WHERE number = 5;")
        .expect("lock");
    let mut db = ToolDb::open_with_timeout(&path, Duration::from_millis(200)).expect("open");
    // WAL: reading still works and sees the committed state.
    assert_eq!(db.tool(5).expect("read").name, "thread mill");
    let e = db
        .put_tool(&ToolRecord::new(5, "mine"))
        .expect_err("locked");
    assert_eq!(sqlite_code(&e), Some(ErrorCode::DatabaseBusy), "{e:?}");
    assert!(!e.is_bad_input());
    assert!(e.to_string().contains("another program is writing"), "{e}");
    let e = db.record_presetter(5, 120.0, 6.9).expect_err("locked");
    assert!(!e.is_bad_input(), "{e:?}");
    other.execute_batch("ROLLBACK").expect("unlock");
    assert_eq!(db.tool(5).expect("read").name, "thread mill");
    db.put_tool(&ToolRecord::new(5, "mine"))
        .expect("free again");
}

/// Two programs changing the library at once wait for each other; a deferred
/// transaction that read first would fail at once with "database is locked".
#[test]
fn concurrent_writers_wait_instead_of_failing() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("tools.db");
    drop(library(&path));
    let writers: Vec<_> = [5u32, 6]
        .into_iter()
        .map(|n| {
            let path = path.clone();
            std::thread::spawn(move || {
                let mut db = ToolDb::open(&path).expect("open");
                for i in 0..150 {
                    db.record_presetter(n, 120.0 + i as f64 * 1e-3, 6.9)
                        .map_err(|e| format!("T{n} write {i}: {e}"))?;
                }
                Ok::<_, String>(())
            })
        })
        .collect();
    for w in writers {
        w.join()
            .expect("thread")
            .expect("every write waits its turn");
    }
}

#[test]
fn paths_that_are_no_library_file_are_refused() {
    let dir = tempfile::tempdir().expect("tmp");
    for p in [Path::new(""), dir.path()] {
        let e = ToolDb::open(p).err().expect("refused");
        assert!(matches!(e, DbError::Invalid(_)), "{p:?}: {e:?}");
    }
    // A library inside a file that is no folder: the folder is never
    // created, so this is the user's path to correct, named in the message.
    let file = dir.path().join("plain");
    std::fs::write(&file, "x").expect("write");
    let e = ToolDb::open(&file.join("tools.db")).err().expect("refused");
    assert!(matches!(e, DbError::Invalid(_)), "{e:?}");
    assert!(e.is_bad_input());
    assert!(e.to_string().contains("plain"), "{e}");
}
