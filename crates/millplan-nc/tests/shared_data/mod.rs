//! The real CAM samples of `../shared/data/` (beside the repository, never
//! copied into it) and a skip that is never silent.
//!
//! A test that cannot run for want of a sample calls [`skipped`]: it prints
//! `SKIPPED:` and appends a line to this test binary's file in
//! `shared-data-skipped/` of the target's `tmp` folder, which `.ci/run`
//! counts into its closing line. Each run of a test binary starts its file
//! afresh (on its first use of this module), so the count is the last run's. With
//! `MILLPLAN_REQUIRE_DATA=1` (`.ci/run` sets it when the folder is there) a
//! skip fails the test instead: a sample that went missing is an error, not a
//! pass. Shared by the test crates of `millplan-nc`, `millplan-sim` and
//! `millplan` (`#[path]`).

#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};

/// The folder `.ci/run` counts the skips in: one file per test binary.
pub const SKIP_DIR: &str = "shared-data-skipped";

/// This test binary's skip file, emptied the first time a run asks for it.
fn skip_log() -> PathBuf {
    static FRESH: std::sync::Once = std::sync::Once::new();
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(SKIP_DIR);
    let log = dir.join(format!(
        "{}-{}.txt",
        env!("CARGO_PKG_NAME"),
        env!("CARGO_CRATE_NAME")
    ));
    FRESH.call_once(|| {
        let _ = std::fs::create_dir_all(&dir);
        let _ = std::fs::remove_file(&log);
    });
    log
}

/// `../shared/data`, when it is there.
pub fn dir() -> Option<PathBuf> {
    skip_log();
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    if d.is_dir() {
        Some(d)
    } else {
        skipped("../shared/data is not here");
        None
    }
}

/// The sample at `rel` under `../shared/data`, when it is there.
pub fn file(rel: &str) -> Option<PathBuf> {
    skip_log();
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(rel);
    if p.is_file() {
        Some(p)
    } else {
        skipped(&format!("../shared/data/{rel} is not here"));
        None
    }
}

/// Records that the calling test checked less than it would with the data:
/// printed, and counted by `.ci/run`; a failure under `MILLPLAN_REQUIRE_DATA=1`.
pub fn skipped(why: &str) {
    let test = std::thread::current()
        .name()
        .unwrap_or("a test")
        .to_string();
    if std::env::var_os("MILLPLAN_REQUIRE_DATA").is_some_and(|v| v == "1") {
        panic!("{test}: {why} (MILLPLAN_REQUIRE_DATA=1 requires the shared data)");
    }
    eprintln!("SKIPPED: {test}: {why}");
    let log = skip_log();
    let line = format!("{} {test}: {why}\n", env!("CARGO_PKG_NAME"));
    if let Ok(mut f) = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&log)
    {
        // One write per line: appends of a short line do not interleave.
        let _ = f.write_all(line.as_bytes());
    }
}
