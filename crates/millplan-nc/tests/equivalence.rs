//! Every program millplan writes means what its source meant: each real
//! sample of `../shared/data/` is written into every dialect, read back and
//! run through the same interpreter as its source ([`millplan_nc::equiv`]):
//! the same positions, axis by axis, step by step, with the same feeds, feed
//! modes, spindle speeds and tool orientations. A dialect that cannot express
//! something must refuse with the source line, never write something else.
//! Round trips (A → B → A) and three-step chains (A → B → C) too.
//!
//! Skipped (and said so) when `../shared/data` is not there.

use millplan_nc::equiv::{compare, Tolerance};
use millplan_nc::write::{write_program, Target, WriteOptions};
use millplan_nc::{parse_program, verify::verify, Program, ReadOptions};
use std::path::{Path, PathBuf};

mod shared_data;

fn data() -> Option<PathBuf> {
    shared_data::dir()
}

/// Every program file under the data folder (not STL, not KRL, not notes).
fn programs(root: &Path) -> Vec<PathBuf> {
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
            let program = matches!(
                ext.as_str(),
                "apt" | "cls" | "clsf" | "ptp" | "mpf" | "nc" | "txt"
            ) && !name.contains("Tool_List");
            if program {
                v.push(p);
            }
        }
    }
    v.sort();
    v
}

/// Units as the sample needs them (the Haas post writes none; it is inch).
fn options(path: &Path) -> ReadOptions {
    let mut o = ReadOptions::default();
    if path.to_string_lossy().contains("haas_vf2tr_5axis_inch") {
        o.units = Some(millplan_nc::LengthUnit::Inch);
    }
    o
}

fn read(text: &str, o: ReadOptions) -> Result<Program, String> {
    let p = parse_program(text, o).map_err(|e| e.to_string())?;
    verify(&p.program).map_err(|v| format!("{v:?}"))?;
    Ok(p.program)
}

enum Outcome {
    Read(Program),
    /// The target refuses, saying what (and where, when a line says it).
    Refused(String),
    Failed(String),
}

/// Writes `p` for `t` and reads the text back.
fn through(p: &Program, t: Target) -> Outcome {
    match write_program(p, WriteOptions::new(t)) {
        Ok((bytes, warnings)) => {
            assert!(warnings.is_empty(), "warnings without --lossy");
            let Ok(text) = String::from_utf8(bytes) else {
                return Outcome::Failed("not UTF-8".into());
            };
            match read(&text, ReadOptions::default()) {
                Ok(q) => Outcome::Read(q),
                Err(e) => Outcome::Failed(format!("re-read: {e}")),
            }
        }
        Err(e) if e.message.is_empty() => Outcome::Failed("an empty refusal".into()),
        Err(e) => Outcome::Refused(e.to_string()),
    }
}

#[test]
fn every_sample_in_every_dialect_means_what_its_source_meant() {
    let Some(root) = data() else {
        return;
    };
    let files = programs(&root);
    assert!(files.len() >= 20, "only {} samples", files.len());
    let tol = Tolerance::default();
    let (mut written, mut refused, mut chains, mut chains3) = (0, 0, 0, 0);
    let mut failures = Vec::new();
    for f in &files {
        let name = f
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("?")
            .to_string();
        let src = std::fs::read_to_string(f).expect("readable");
        let a = read(&src, options(f)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let own = Target::of(a.source);
        let mut outputs = Vec::new();
        for t in Target::ALL {
            match through(&a, t) {
                Outcome::Read(b) => {
                    written += 1;
                    if let Err(m) = compare(&a, &b, &tol) {
                        failures.push(format!("{name} -> {}: {m}", t.name()));
                    } else {
                        outputs.push((t, b));
                    }
                }
                Outcome::Refused(e) => {
                    refused += 1;
                    // A program can always be written into its own dialect.
                    if Some(t) == own {
                        failures.push(format!(
                            "{name} -> its own dialect {} refused: {e}",
                            t.name()
                        ));
                    }
                }
                Outcome::Failed(e) => failures.push(format!("{name} -> {}: {e}", t.name())),
            }
        }
        // Round trips and chains: A -> B -> C and A -> B -> C -> D against A.
        for (t1, b) in &outputs {
            for t2 in Target::ALL {
                let Outcome::Read(c) = through(b, t2) else {
                    continue;
                };
                chains += 1;
                if let Err(m) = compare(&a, &c, &tol) {
                    failures.push(format!("{name} -> {} -> {}: {m}", t1.name(), t2.name()));
                    continue;
                }
                for t3 in Target::ALL {
                    if let Outcome::Read(d) = through(&c, t3) {
                        chains3 += 1;
                        if let Err(m) = compare(&a, &d, &tol) {
                            failures.push(format!(
                                "{name} -> {} -> {} -> {}: {m}",
                                t1.name(),
                                t2.name(),
                                t3.name()
                            ));
                        }
                    }
                }
            }
        }
    }
    eprintln!(
        "{} samples: {written} conversions equivalent, {refused} refused with a located error, {chains} two-step and {chains3} three-step chains",
        files.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(written > 50 && chains > 100 && chains3 > 500);
}
