//! Helpers shared by the snapshot and regression tests: where the real
//! samples are, how each is read, and a writer call that says what it did.
//!
//! The samples of `../shared/data/` are read where they lie and never copied
//! into the repository (several have no licence).

#![allow(dead_code)]

use millplan_nc::write::{write_program, Target, WriteOptions};
use millplan_nc::{parse_program, verify::verify, LengthUnit, Program, ReadOptions};
use std::path::{Path, PathBuf};

#[path = "../shared_data/mod.rs"]
pub mod shared_data;

/// The shared data folder, when it is there; its absence is recorded as a
/// skip of the calling test (`shared_data::skipped`).
pub fn data() -> Option<PathBuf> {
    shared_data::dir()
}

/// The text of one sample (`folder/file`), or `None` after recording why the
/// calling test skips.
pub fn sample(rel: &str) -> Option<String> {
    let p = shared_data::file(rel)?;
    match std::fs::read(&p) {
        Ok(b) => Some(String::from_utf8_lossy(&b).into_owned()),
        Err(e) => {
            shared_data::skipped(&format!("../shared/data/{rel}: {e}"));
            None
        }
    }
}

/// Every NC program under the data folder (not STL, not KRL, not notes), sorted.
pub fn programs(root: &Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    for dir in std::fs::read_dir(root).into_iter().flatten().flatten() {
        for f in std::fs::read_dir(dir.path())
            .into_iter()
            .flatten()
            .flatten()
        {
            let p = f.path();
            let ext = p
                .extension()
                .and_then(|e| e.to_str())
                .unwrap_or("")
                .to_ascii_lowercase();
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            if matches!(
                ext.as_str(),
                "apt" | "cls" | "clsf" | "ptp" | "mpf" | "nc" | "txt"
            ) && !name.contains("Tool_List")
            {
                v.push(p);
            }
        }
    }
    v.sort();
    v
}

/// Reader options a sample needs (the Haas post writes no unit word; it is inch).
pub fn options_for(name: &str) -> ReadOptions {
    let mut o = ReadOptions::default();
    if name.contains("haas_vf2tr_5axis_inch") {
        o.units = Some(LengthUnit::Inch);
    }
    o
}

/// Reads a program and runs the verifier on it; panics with `what` on failure.
pub fn read(text: &str, o: ReadOptions, what: &str) -> Program {
    let p = parse_program(text, o)
        .unwrap_or_else(|e| panic!("{what}: {e}"))
        .program;
    verify(&p).unwrap_or_else(|v| panic!("{what}: verifier: {v:?}"));
    p
}

/// Reads a sample (`folder/file`) with the options it needs, or `None` (skipped).
pub fn read_sample(rel: &str) -> Option<Program> {
    let text = sample(rel)?;
    Some(read(&text, options_for(rel), rel))
}

/// What a writer did with a program.
#[derive(Debug)]
pub enum Out {
    /// The text, with the warnings of words written as comments (`lossy`).
    Text(String, Vec<String>),
    /// The located refusal.
    Refused(millplan_nc::write::WriteError),
}

pub fn write(p: &Program, t: Target, lossy: bool) -> Out {
    let mut o = WriteOptions::new(t);
    o.lossy = lossy;
    match write_program(p, o) {
        Ok((b, w)) => Out::Text(
            String::from_utf8(b).expect("writers write UTF-8"),
            w.iter().map(|d| d.to_string()).collect(),
        ),
        Err(e) => Out::Refused(e),
    }
}

/// The text a target writes without `lossy`; panics on a refusal.
pub fn written(p: &Program, t: Target, what: &str) -> String {
    match write(p, t, false) {
        Out::Text(s, w) => {
            assert!(
                w.is_empty(),
                "{what} -> {}: warnings without lossy",
                t.name()
            );
            s
        }
        Out::Refused(e) => panic!("{what} -> {}: refused: {e}", t.name()),
    }
}

/// The G-code targets.
pub const GCODE: [Target; 4] = [
    Target::Fanuc,
    Target::Sinumerik,
    Target::Heidenhain,
    Target::LinuxCnc,
];
