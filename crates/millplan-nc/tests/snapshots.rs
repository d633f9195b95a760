//! Snapshot tests of every writer (issue 15): each program is written into
//! every target (Fanuc, Sinumerik, Heidenhain, LinuxCNC, APT) and the result,
//! text or located refusal, is compared with the snapshot stored under
//! `tests/snapshots/`. A refused program is also written with `lossy`, so the
//! comments and warnings that path writes are pinned too.
//!
//! - `golden/` and `synthetic/`: our own inputs (`tests/golden/*` and the
//!   small programs below), stored as full text.
//! - `real/`: the CAM samples of `../shared/data/`, which may not be copied
//!   into the repository. Only digests are stored: line and byte counts, a
//!   64-bit FNV-1a hash of the text, a count of blocks by their first word,
//!   and a hash of every 256 lines. When one changes, the test prints the
//!   lines of the first changed range as they are written now.
//!
//! `UPDATE_SNAPSHOTS=1 cargo test -p millplan-nc --test snapshots` rewrites
//! the snapshots after a deliberate change (review the diff); without it a
//! difference fails with the first differing lines.

mod common;

use common::{data, options_for, programs, read, write, Out};
use millplan_nc::write::Target;
use millplan_nc::{Program, ReadOptions};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Lines per hashed range of a real sample's output.
const CHUNK: usize = 256;
/// Lines per part of a range: each part has a 16-bit hash beside the range's
/// own, to find the part that changed.
const PART: usize = 32;

fn snapshot_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots")
}

fn updating() -> bool {
    std::env::var_os("UPDATE_SNAPSHOTS").is_some_and(|v| v != "0" && !v.is_empty())
}

/// 64-bit FNV-1a.
fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Where `want` and `got` first differ, with a few lines of each.
fn first_difference(want: &str, got: &str) -> Option<String> {
    if want == got {
        return None;
    }
    let (w, g): (Vec<&str>, Vec<&str>) = (want.lines().collect(), got.lines().collect());
    let i = w
        .iter()
        .zip(&g)
        .position(|(a, b)| a != b)
        .unwrap_or(w.len().min(g.len()));
    let show = |v: &[&str], other: &[&str], sign: char| -> String {
        let lo = i.saturating_sub(2);
        let hi = (i + 6).min(v.len());
        let mut s = String::new();
        for (k, l) in v.iter().enumerate().take(hi).skip(lo) {
            let mark = if k >= i && other.get(k) != Some(l) {
                sign
            } else {
                ' '
            };
            s.push_str(&format!("{mark}{:5} | {l}\n", k + 1));
        }
        if hi == i {
            s.push_str(&format!("{sign}      | (ends after line {})\n", v.len()));
        }
        s
    };
    Some(format!(
        "first difference at line {} (- snapshot, + now):\n{}{}",
        i + 1,
        show(&w, &g, '-'),
        show(&g, &w, '+')
    ))
}

/// Compares `got` with the snapshot `rel`, or rewrites it when updating.
/// `explain` adds context to a difference (the changed lines of a real
/// sample, which the snapshot does not hold).
fn check(rel: &str, got: &str, explain: impl Fn(&str) -> String, failures: &mut Vec<String>) {
    let path = snapshot_dir().join(rel);
    let want = std::fs::read_to_string(&path).ok();
    if updating() {
        if want.as_deref() != Some(got) {
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir).expect("snapshot folder");
            }
            std::fs::write(&path, got).expect("write snapshot");
            eprintln!("updated {rel}");
        }
        return;
    }
    match want {
        None => failures.push(format!(
            "{rel}: no snapshot (UPDATE_SNAPSHOTS=1 writes it; review it before committing)"
        )),
        Some(want) => {
            if let Some(d) = first_difference(&want, got) {
                failures.push(format!("{rel}: {d}{}", explain(&want)));
            }
        }
    }
}

/// Snapshot files under `sub` that no input produced any more.
fn stale(sub: &str, produced: &[String], failures: &mut Vec<String>) {
    let dir = snapshot_dir().join(sub);
    for f in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
        let rel = format!("{sub}/{}", f.file_name().to_string_lossy());
        if !produced.contains(&rel) {
            if updating() {
                std::fs::remove_file(f.path()).expect("remove stale snapshot");
                eprintln!("removed {rel}");
            } else {
                failures.push(format!(
                    "{rel}: no input writes this snapshot any more (UPDATE_SNAPSHOTS=1 removes it)"
                ));
            }
        }
    }
}

fn report(failures: Vec<String>) {
    assert!(
        failures.is_empty(),
        "{} snapshot(s) differ:\n\n{}",
        failures.len(),
        failures.join("\n\n")
    );
}

/// The full snapshot of one program in one target: the text, or the
/// refusal followed by what `lossy` writes.
fn full_snapshot(p: &Program, t: Target) -> String {
    match write(p, t, false) {
        Out::Text(text, warnings) => {
            assert!(warnings.is_empty(), "warnings without lossy: {warnings:?}");
            text
        }
        Out::Refused(e) => {
            let mut s = format!("refused: {e}\n");
            match write(p, t, true) {
                Out::Text(text, warnings) => {
                    s.push_str(&format!("--- with lossy: {} warning(s)\n", warnings.len()));
                    for w in warnings {
                        s.push_str(&format!("warning: {w}\n"));
                    }
                    s.push_str("---\n");
                    s.push_str(&text);
                }
                Out::Refused(e) => s.push_str(&format!("refused with lossy too: {e}\n")),
            }
            s
        }
    }
}

/// Writes `p` into every target and checks the full-text snapshots
/// `sub/<name>.<target>.txt`.
fn check_full(sub: &str, name: &str, p: &Program, produced: &mut Vec<String>) -> Vec<String> {
    let mut failures = Vec::new();
    for t in Target::ALL {
        let rel = format!("{sub}/{name}.{}.txt", t.name());
        check(&rel, &full_snapshot(p, t), |_| String::new(), &mut failures);
        produced.push(rel);
    }
    failures
}

#[test]
fn writers_on_the_golden_inputs() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let mut inputs: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("golden folder")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e != "ir"))
        .collect();
    inputs.sort();
    assert!(inputs.len() >= 8, "golden inputs missing");
    let (mut failures, mut produced) = (Vec::new(), Vec::new());
    for path in &inputs {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .expect("file name");
        let src = std::fs::read_to_string(path).expect("golden input");
        let p = read(&src, ReadOptions::default(), name);
        failures.extend(check_full("golden", name, &p, &mut produced));
    }
    stale("golden", &produced, &mut failures);
    report(failures);
}

/// Small programs of our own, one per thing a writer must carry over.
const SYNTHETIC: &[(&str, &str)] = &[
    (
        // Feed per minute, inverse time and per revolution, switched back and forth.
        "feed_modes.nc",
        "%\nO0010\nG21 G17 G90 G94\nT1 M6\nG43 H1\nS2000 M3\nG0 X0. Y0. Z5.\nG1 Z0. F300.\n\
         G93 G1 X10. Y5. F50.\nX20. F25.\nG95 G1 X30. F0.1\nY10.\nG94 G1 X40. F400.\nM30\n%\n",
    ),
    (
        // Canned cycles: plain, with a dwell, with pecks, feed out.
        "cycles.nc",
        "%\nO0020\nG21 G17 G90 G94\nT2 M6\nG43 H2 S1500 M3\nG0 X10. Y10. Z25.\n\
         G98 G81 X10. Y10. Z-5. R2. F120.\nX20.\nG80\nG99 G82 X30. Y10. Z-4. R2. P500 F120.\n\
         G80\nG98 G83 X40. Y10. Z-20. R2. Q5. F100.\nY20.\nG80\nG85 X50. Y10. Z-8. R1. F80.\n\
         G80\nG0 Z50.\nM30\n%\n",
    ),
    (
        // Five axes by machine angles under G43.4; a reference return in
        // incremental mode; a rotary-only rapid; AI contour control on and off.
        "five_axis_angles.nc",
        "%\nO0030\nG40 G17 G49 G90 G80 G21\nG91 G28 Z0.0 M05\nG28 X0.0 Y0.0 B0.0\nT9 M6\n\
         G05.1 Q1\nG90 G00 B0.0 C0.0\nG43.4 G90 X10. Y10. Z50. H09 S3000 M3\nG1 Z5. F500.\n\
         X20. B-30. C45. F800.\nX30. Y15. B-35.5 C60.25\nG0 Z50.\nG49\nG05.1 Q0\nM30\n%\n",
    ),
    (
        // Nothing commanded before the first move: a Z-first retract, then X
        // and Y; a block in machine coordinates forgets them again.
        "unknown_start.ngc",
        "G21 G17 G90 G94\nT1 M6\nG0 Z20\nG0 X0 Y0 S10000 M3\nG1 Z-1 F500\nX10 Y5\n\
         G53 G0 Z0\nG0 X5 Y5\nZ2\nG1 Z-1\nM30\n",
    ),
    (
        // Tool vectors with arcs in and out of the principal planes, and a drill cycle.
        "five_axis_vectors.apt",
        "PARTNO VECTORS\nUNITS/MM\nCUTTER/10,5,0,5,0,0,60\nLOADTL/4\nSPINDL/8000,RPM,CLW\n\
         RAPID\nGOTO/0,0,50,0,0,1\nFEDRAT/1000,MMPM\nMULTAX/ON\nGOTO/0,0,0,0,0,1\n\
         GOTO/10,0,0,0.6,0,0.8\nGOTO/20,0,-2,0.6,0,0.8\nCIRCLE/20,10,-2,0,0,1,10\nGOTO/30,10,-2,0.6,0,0.8\n\
         CIRCLE/25,10,-2,0,0.6,0.8,5\nGOTO/25,14,-5,0.6,0,0.8\nGOTO/25,14,30,0,0,1\n\
         MULTAX/OFF\nCYCLE/DRILL,FEDTO,12,RAPTO,2,RTRCTO,5,MMPM,150\nGOTO/50,50,0\nGOTO/60,50,0\n\
         CYCLE/OFF\nFINI\n",
    ),
    (
        // Compensation, work offsets, coolant, stops, dwell, messages.
        "events.mpf",
        "; events\nG17 G710 G90 G94\nT=\"END_MILL_D8\"\nM6\nD1\nG55\nMSG(\"ROUGH\")\n\
         G0 X0 Y0 Z10 S4000 M3 M8\nG1 Z-2 F300\nG41 X10 Y0\nY20\nG40 X20 Y20\nM1\nG4 F1.5\n\
         G0 Z10 M9\nM0\nG56\nG0 X50 Y50\nM5\nM30\n",
    ),
    (
        // An inch program with an arc and a speed that is not whole.
        "inch.nc",
        "%\nO0040\nG20 G17 G90 G94\nT3 M6\nG43 H3 S4200.6 M3\nG0 X0. Y0. Z1.\nG1 Z-.05 F20.\n\
         G2 X1. Y0. I.5 J0.\nG1 Y.5 S5100.\nG0 Z1.\nM30\n%\n",
    ),
];

#[test]
fn writers_on_synthetic_programs() {
    let (mut failures, mut produced) = (Vec::new(), Vec::new());
    for (name, src) in SYNTHETIC {
        let p = read(src, ReadOptions::default(), name);
        failures.extend(check_full("synthetic", name, &p, &mut produced));
    }
    stale("synthetic", &produced, &mut failures);
    report(failures);
}

/// The class of a written line by its first word: a G or M code as written,
/// otherwise the word's letters (`X`, `L`, `CC`, `GOTO`, `T=`), or `comment`.
fn block_class(line: &str) -> String {
    let mut words = line.split_whitespace();
    let mut w = words.next().unwrap_or("");
    // Heidenhain block numbers and `N` numbers say nothing of the block.
    let numbered = |w: &str| {
        let d = w.strip_prefix('N').unwrap_or(w);
        !d.is_empty() && d.bytes().all(|c| c.is_ascii_digit())
    };
    if numbered(w) {
        w = words.next().unwrap_or("");
    }
    if w.is_empty() {
        return "empty".into();
    }
    if w.starts_with('(') || w.starts_with(';') {
        return "comment".into();
    }
    let letters: String = w
        .chars()
        .take_while(|c| c.is_ascii_alphabetic() || *c == '_' || *c == '=')
        .collect();
    match letters.as_str() {
        "G" | "M" => w
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '.')
            .collect(),
        "" => w.chars().take(1).collect(),
        l => l.to_string(),
    }
}

/// The digest stored for a real sample's output: counts, hashes, no text.
fn digest(text: &str) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let mut s = format!(
        "lines {} bytes {} fnv1a64 {:016x}\n",
        lines.len(),
        text.len(),
        fnv1a64(text.as_bytes())
    );
    let mut classes: BTreeMap<String, usize> = BTreeMap::new();
    for l in &lines {
        *classes.entry(block_class(l)).or_default() += 1;
    }
    s.push_str("blocks");
    for (c, n) in &classes {
        s.push_str(&format!(" {c}={n}"));
    }
    s.push('\n');
    for (k, chunk) in lines.chunks(CHUNK).enumerate() {
        let lo = k * CHUNK + 1;
        s.push_str(&format!(
            "lines {lo}-{} fnv1a64 {:016x} parts",
            lo + chunk.len() - 1,
            fnv1a64(chunk.join("\n").as_bytes())
        ));
        for part in chunk.chunks(PART) {
            s.push_str(&format!(
                " {:04x}",
                fnv1a64(part.join("\n").as_bytes()) & 0xffff
            ));
        }
        s.push('\n');
    }
    s
}

/// The digest snapshot of one sample in every target (and with `lossy`
/// where a target refuses), with the outputs it was made from.
fn real_snapshot(p: &Program, summary: &str) -> (String, BTreeMap<String, String>) {
    let mut s = format!(
        "# Writer digests: the sample is not ours to copy, so no text of it or of\n\
         # what is written from it is stored.\n{summary}\n"
    );
    let mut texts = BTreeMap::new();
    for t in Target::ALL {
        match write(p, t, false) {
            Out::Text(text, warnings) => {
                assert!(warnings.is_empty(), "warnings without lossy");
                s.push_str(&format!("== {}\n{}", t.name(), digest(&text)));
                texts.insert(t.name().to_string(), text);
            }
            Out::Refused(e) => {
                s.push_str(&format!("== {}\nrefused: {e}\n", t.name()));
                let key = format!("{} lossy", t.name());
                match write(p, t, true) {
                    Out::Text(text, warnings) => {
                        s.push_str(&format!(
                            "== {key}\nwarnings {} fnv1a64 {:016x}\n{}",
                            warnings.len(),
                            fnv1a64(warnings.join("\n").as_bytes()),
                            digest(&text)
                        ));
                        texts.insert(key, text);
                    }
                    Out::Refused(e) => s.push_str(&format!("== {key}\nrefused: {e}\n")),
                }
            }
        }
    }
    (s, texts)
}

/// For a changed real digest: the lines, as written now, of the first part
/// of the first range whose hash changed (shown, never stored).
fn changed_lines(want: &str, got: &str, texts: &BTreeMap<String, String>) -> String {
    // `lines 257-512 fnv1a64 … parts a1b2 …`: the range and its part hashes.
    let range = |l: &str| {
        let mut w = l.strip_prefix("lines ")?.split_whitespace();
        let (a, b) = w.next()?.split_once('-')?;
        let parts: Vec<String> = w.skip(3).map(str::to_string).collect();
        Some((a.parse::<usize>().ok()?, b.parse::<usize>().ok()?, parts))
    };
    let mut section = String::new();
    let mut first: Option<(String, usize, usize)> = None;
    for (w, g) in want.lines().zip(got.lines()) {
        if let Some(name) = g.strip_prefix("== ") {
            section = name.to_string();
        }
        if w == g {
            continue;
        }
        match (range(w), range(g)) {
            (Some((_, _, old)), Some((lo, hi, new))) => {
                let k = old
                    .iter()
                    .zip(&new)
                    .position(|(a, b)| a != b)
                    .unwrap_or(old.len().min(new.len()));
                let from = (lo + k * PART).min(hi);
                first = Some((section.clone(), from, (from + PART - 1).min(hi)));
                break;
            }
            _ if first.is_none() => first = Some((section.clone(), 1, PART)),
            _ => {}
        }
    }
    let Some((section, lo, hi)) = first else {
        return String::new();
    };
    let Some(text) = texts.get(&section) else {
        return String::new();
    };
    let mut s =
        format!("\n{section}: lines {lo}-{hi}, the first part that changed, as written now:\n");
    for (k, l) in text.lines().enumerate().take(hi).skip(lo - 1) {
        s.push_str(&format!("{:6} | {l}\n", k + 1));
    }
    s
}

#[test]
fn writers_on_the_real_samples() {
    let Some(root) = data() else {
        return;
    };
    let files = programs(&root);
    assert!(files.len() >= 20, "only {} samples", files.len());
    let (mut failures, mut produced) = (Vec::new(), Vec::new());
    for f in &files {
        let name = f
            .file_name()
            .and_then(|n| n.to_str())
            .expect("file name")
            .to_string();
        let src = std::fs::read_to_string(f).expect("readable sample");
        let p = read(&src, options_for(&name), &name);
        let rel_src = f.strip_prefix(&root).unwrap_or(f).display().to_string();
        let summary = format!(
            "# Source: ../shared/data/{rel_src}, read as {} ({:?}), {} operations, {} moves.",
            p.source.name(),
            p.units.source,
            p.operations.len(),
            p.move_count()
        );
        let (got, texts) = real_snapshot(&p, &summary);
        let rel = format!("real/{name}.snap");
        check(
            &rel,
            &got,
            |want| changed_lines(want, &got, &texts),
            &mut failures,
        );
        produced.push(rel);
    }
    stale("real", &produced, &mut failures);
    report(failures);
}

#[test]
fn the_harness_hashes_and_points_at_the_first_difference() {
    // Published FNV-1a 64 test vectors.
    assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
    assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
    assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    assert_eq!(first_difference("a\nb\n", "a\nb\n"), None);
    let d = first_difference("G0 X1\nG1 X2\nG1 X3\n", "G0 X1\nG1 X2.5\nG1 X3\n").expect("differs");
    assert!(d.starts_with("first difference at line 2"), "{d}");
    assert!(
        d.contains("-    2 | G1 X2\n") && d.contains("+    2 | G1 X2.5\n"),
        "{d}"
    );
    // A text that only grows differs after its last common line.
    let d = first_difference("a\n", "a\nb\n").expect("differs");
    assert!(d.starts_with("first difference at line 2"), "{d}");
    // Digests change with one character and name the range it is in.
    let text: String = (0..600).map(|i| format!("G1 X{i}\n")).collect();
    let changed = text.replacen("G1 X300\n", "G1 X300.\n", 1);
    let (a, b) = (digest(&text), digest(&changed));
    let first = a
        .lines()
        .zip(b.lines())
        .find(|(x, y)| x != y)
        .map(|(x, _)| x.to_string());
    assert!(
        first
            .as_deref()
            .is_some_and(|l| l.starts_with(&format!("lines 600 bytes {} ", text.len()))),
        "{first:?}"
    );
    let range = a
        .lines()
        .zip(b.lines())
        .filter(|(x, y)| x != y)
        .map(|(x, _)| x.to_string())
        .collect::<Vec<_>>();
    assert_eq!(range.len(), 2, "the total and the range 257-512: {range:?}");
    assert!(range[1].starts_with("lines 257-512 "), "{range:?}");
    assert_eq!(block_class("12 L X+1 FMAX"), "L");
    assert_eq!(block_class("N20 G1 X1"), "G1");
    assert_eq!(block_class("G43.4 H9"), "G43.4");
    assert_eq!(block_class("(comment)"), "comment");
    assert_eq!(block_class("T=\"MILL\""), "T=");
    assert_eq!(block_class("GOTO/1,2,3"), "GOTO");
}
