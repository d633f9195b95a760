//! Regression tests of `millplan convert` for the faults of issue 16, run
//! through the real binary: each names its fault and cites the sample file
//! and line it was seen at. Outputs are read back (with `inspect --json` or
//! the library) and compared with their source, never with copied numbers.
//!
//! Tests on the samples of `../shared/data/` record a skip when the samples
//! are not there (counted by `.ci/run`, see `shared_data`); the ones on
//! programs written here always run.

use millplan_nc::equiv::{compare, Tolerance};
use millplan_nc::write::Target;
use millplan_nc::{parse_program, FeedMode, Program, ReadOptions};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[path = "../../millplan-nc/tests/shared_data/mod.rs"]
mod shared_data;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

/// A sample of `../shared/data/`, or `None` after recording the skip.
fn sample(rel: &str) -> Option<PathBuf> {
    shared_data::file(rel)
}

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("millplan runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `convert input --to target -o output [extra]`, which must succeed (with
/// `--lossy`, exit 3 says the output commands less than the source: words
/// the target cannot express became comments).
fn convert(input: &Path, target: &str, output: &Path, extra: &[&str]) -> String {
    let o = run(&[
        &["convert", s(input), "--to", target, "-o", s(output)],
        extra,
    ]
    .concat());
    let lossy = extra.contains(&"--lossy") && o.status.code() == Some(3);
    assert!(
        o.status.success() || lossy,
        "convert {} --to {target}: {}",
        input.display(),
        stderr(&o)
    );
    std::fs::read_to_string(output).expect("the output was written")
}

fn read(text: &str, units: Option<millplan_nc::LengthUnit>) -> Program {
    let o = ReadOptions {
        units,
        ..ReadOptions::default()
    };
    parse_program(text, o).expect("reads").program
}

fn inspect(path: &Path) -> serde_json::Value {
    let o = run(&["inspect", "--json", s(path)]);
    assert!(o.status.success(), "inspect: {}", stderr(&o));
    serde_json::from_slice(&o.stdout).expect("JSON")
}

/// The words of a block without its block number.
fn words(line: &str) -> Vec<&str> {
    let mut w: Vec<&str> = line.split_whitespace().collect();
    let numbered = |s: &str| {
        let d = s.strip_prefix('N').unwrap_or(s);
        !d.is_empty() && d.bytes().all(|c| c.is_ascii_digit())
    };
    if w.first().is_some_and(|s| numbered(s)) {
        w.remove(0);
    }
    w
}

fn has_axis(line: &str, letters: &[char]) -> bool {
    words(line).iter().any(|w| {
        let mut c = w.chars();
        c.next().is_some_and(|l| letters.contains(&l))
            && c.next()
                .is_some_and(|d| d.is_ascii_digit() || matches!(d, '-' | '+' | '.' | '='))
    })
}

/// Issue 16: "`convert moriseiki_nmv5000_fanuc_g43-4_mm.ptp --to fanuc`
/// copies `G91 G28 Z0 M5` verbatim but writes the source's `G43 G90 X56.184
/// Y12.405 H08` as `G43 H8` / `X56.184 Y12.405`, with no G90 anywhere after
/// it … `inspect` of the result reports bounds up to X 6077 and three times
/// the cutting length." After moriseiki…ptp:5 `G91 G28 Z0.0 M05` (and :341,
/// :348) every block that moves X, Y or Z outside a reference return is in
/// G90, and `inspect` reports the source's bounds, lengths and move counts.
#[test]
fn convert_mori_into_fanuc_keeps_g90_after_g91_g28() {
    let Some(src) = sample("nx-posted-gcode-samples/moriseiki_nmv5000_fanuc_g43-4_mm.ptp") else {
        return;
    };
    let dir = tempfile::tempdir().expect("temporary folder");
    let out = dir.path().join("mori.nc");
    let text = convert(&src, "fanuc", &out, &[]);
    // The distance mode of the output, block by block.
    let (mut absolute, mut g91_blocks, mut moves) = (true, 0, 0);
    for l in text.lines().filter(|l| !l.starts_with('(')) {
        let w = words(l);
        if w.contains(&"G91") {
            absolute = false;
            g91_blocks += 1;
        }
        if w.contains(&"G90") {
            absolute = true;
        }
        let reference = w.iter().any(|w| matches!(*w, "G28" | "G30" | "G53"));
        if has_axis(l, &['X', 'Y', 'Z']) && !reference {
            assert!(absolute, "`{l}` moves in G91\n{text}");
            moves += 1;
        }
    }
    assert!(g91_blocks >= 3, "the source's G91 blocks are in the output");
    assert!(moves > 300, "{moves} absolute blocks");
    let (a, b) = (inspect(&src), inspect(&out));
    for k in 0..3 {
        for side in ["min", "max"] {
            let (x, y) = (
                a["bounds"][side][k].as_f64().expect("bound"),
                b["bounds"][side][k].as_f64().expect("bound"),
            );
            assert!(
                (x - y).abs() < 1e-3,
                "bounds {side}[{k}]: {x} in the source, {y} written"
            );
        }
    }
    for k in ["cutting", "rapid"] {
        let (x, y) = (
            a["length_mm"][k].as_f64().expect("length"),
            b["length_mm"][k].as_f64().expect("length"),
        );
        assert!(
            (x - y).abs() <= 1e-3 * x.max(1.0),
            "{k} length: {x} in the source, {y} written"
        );
    }
    assert_eq!(a["moves"], b["moves"]);
    // And block by block, the same commanded positions.
    let p = read(&std::fs::read_to_string(&src).expect("sample"), None);
    let q = read(&text, None);
    compare(&p, &q, &Tolerance::default()).unwrap_or_else(|e| panic!("{e}"));
}

/// Issue 16: "A rotary-only `G00 B0.0 C0.0` becomes `G0 X0. Y0. Z0. B0.
/// C0.` (Heidenhain `L X+0 Y+0 Z+0 … FMAX`) in every G-code output of the
/// Sinumerik … samples." Achskreuz.mpf never names linear and rotary axes in
/// one block (:29 `N280 G0 B0.0 C0.0`); nor may any block `convert` writes
/// from it, into any G-code dialect.
#[test]
fn convert_keeps_rotary_only_blocks_rotary_only() {
    let Some(src) = sample("sinumerik-840d-spinner-u5/Achskreuz.mpf") else {
        return;
    };
    let source = std::fs::read_to_string(&src).expect("sample");
    let code = |l: &str| l.split(';').next().unwrap_or("").to_string();
    let mixed = |l: &str| {
        let c = code(l);
        has_axis(&c, &['X', 'Y', 'Z']) && has_axis(&c, &['B', 'C']) && !c.contains("SUPA")
    };
    assert!(
        !source.lines().any(mixed),
        "the sample mixes them after all"
    );
    let rotary = source
        .lines()
        .filter(|l| has_axis(&code(l), &['B', 'C']) && !code(l).contains("SUPA"))
        .count();
    assert!(rotary >= 20, "{rotary} rotary-only blocks");
    let dir = tempfile::tempdir().expect("temporary folder");
    for t in ["fanuc", "sinumerik", "heidenhain", "linuxcnc"] {
        let out = dir.path().join(format!("out.{t}"));
        // Tools called by name and Sinumerik's own words are comments in
        // other dialects (--lossy); positions are not affected.
        let text = convert(&src, t, &out, &["--lossy", "--quiet"]);
        let body: Vec<&str> = text
            .lines()
            .filter(|l| {
                !l.starts_with('(') && !words(l).first().is_some_and(|w| w.starts_with(';'))
            })
            .collect();
        if let Some(l) = body.iter().find(|l| mixed(l)) {
            panic!("{t}: `{l}` names linear and rotary axes");
        }
        let written = body.iter().filter(|l| has_axis(l, &['B', 'C'])).count();
        assert!(written >= rotary / 2, "{t}: {written} rotary blocks");
    }
}

/// Issue 16: "The CAMotics relief's `G0Z20` then `G0X0Y0` — a Z-first
/// retract from wherever the tool is — becomes one diagonal `G0 X0. Y0.
/// Z20.`" bear.nc:4-5: the first two motion blocks of every G-code output
/// are Z alone, then X and Y without Z.
#[test]
fn convert_keeps_the_z_first_retract() {
    let Some(src) = sample("camotics-ballnose-relief-gcode/bear.nc") else {
        return;
    };
    let dir = tempfile::tempdir().expect("temporary folder");
    for t in ["fanuc", "sinumerik", "heidenhain", "linuxcnc"] {
        let out = dir.path().join(format!("bear.{t}"));
        let text = convert(&src, t, &out, &[]);
        let motion: Vec<&str> = text
            .lines()
            .filter(|l| has_axis(l, &['X', 'Y', 'Z']))
            .take(2)
            .collect();
        assert_eq!(motion.len(), 2, "{t}");
        assert!(
            has_axis(motion[0], &['Z']) && !has_axis(motion[0], &['X', 'Y']),
            "{t}: `{}`",
            motion[0]
        );
        assert!(
            has_axis(motion[1], &['X'])
                && has_axis(motion[1], &['Y'])
                && !has_axis(motion[1], &['Z']),
            "{t}: `{}`",
            motion[1]
        );
    }
}

/// Issues 15 and 16: "`G93 … F50` is written under G94 as 50 mm/min; `G95
/// F0.1` becomes 0.1 mm/min." Converted into every dialect (APT too), the
/// inverse-time and per-revolution blocks read back with their mode and F.
#[test]
fn convert_keeps_g93_and_g95_blocks_in_every_dialect() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let src = dir.path().join("feeds.nc");
    std::fs::write(
        &src,
        "%\nO0010\nG21 G17 G90 G94\nT1 M6\nG43 H1\nS2000 M3\nG0 X0. Y0. Z5.\nG1 Z0. F300.\n\
         G93 G1 X10. Y5. F50.\nX20. F25.\nG95 G1 X30. F0.1\nG94 G1 X40. F400.\nM30\n%\n",
    )
    .expect("write the source");
    let p = read(&std::fs::read_to_string(&src).expect("source"), None);
    let feeds = |p: &Program| -> Vec<(FeedMode, f64)> {
        p.moves()
            .filter(|m| m.is_cutting())
            .map(|m| (m.feed_mode, m.feed))
            .collect()
    };
    let want = feeds(&p);
    assert!(
        want.contains(&(FeedMode::InverseTime, 50.0)) && want.contains(&(FeedMode::PerRev, 0.1))
    );
    for t in Target::ALL {
        let out = dir.path().join(format!("out.{}", t.extension()));
        let text = convert(&src, t.name(), &out, &[]);
        let got = feeds(&read(&text, None));
        assert_eq!(got.len(), want.len(), "{}:\n{text}", t.name());
        for (w, g) in want.iter().zip(&got) {
            assert_eq!(w.0, g.0, "{}:\n{text}", t.name());
            assert!(
                (w.1 - g.1).abs() < 1e-9,
                "{}: F{} read back as F{}",
                t.name(),
                w.1,
                g.1
            );
        }
    }
}

/// Issue 15: "a 7-line `G83 … Q0.00001` became 3.6 M lines, 89 MB." Every
/// target refuses it: exit 2, the message names the file and the cycle's
/// line (7), and no output is left behind.
#[test]
fn convert_refuses_an_absurd_peck_at_its_line() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let src = dir.path().join("peck.nc");
    std::fs::write(
        &src,
        "%\nO0020\nG21 G17 G90 G94\nT2 M6\nG43 H2 S1500 M3\nG0 X10. Y10. Z5.\n\
         G98 G83 X10. Y10. Z-20. R2. Q0.00001 F100.\nX30.\nG80\nM30\n%\n",
    )
    .expect("write the source");
    for t in Target::ALL {
        let out = dir.path().join(format!("out.{}", t.extension()));
        let o = run(&["convert", s(&src), "--to", t.name(), "-o", s(&out)]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{}: {e}", t.name());
        assert!(
            e.contains(&format!("{}:7:1:", src.display())) && e.contains("peck"),
            "{}: {e}",
            t.name()
        );
        assert!(!out.exists(), "{}: an output was left", t.name());
    }
}

/// Issue 16: "G-code → APT drops the rotary axes of five-axis moves (a
/// PPRINT instead …)." Without --lossy the conversion stops at the first
/// move with machine angles (exit 2, its line); with --lossy it writes and
/// warns at that line.
#[test]
fn convert_of_rotary_gcode_into_apt_refuses_at_the_line() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let src = dir.path().join("rotary.nc");
    std::fs::write(
        &src,
        "%\nO0003\nG21 G90 G17 G94\nT1 M6\nG43 H1 S2000 M3\nG0 X0. Y0. Z50.\nG1 Z5. F500.\n\
         X10. B-30. C45.\nX20. B-35.\nG0 Z50.\nM30\n%\n",
    )
    .expect("write the source");
    let out = dir.path().join("rotary.apt");
    let o = run(&["convert", s(&src), "--to", "apt", "-o", s(&out)]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains(&format!("{}:8:1:", src.display())) && e.contains("rotary"),
        "{e}"
    );
    assert!(!out.exists());
    // With --lossy it is written, and exit 3 says it commands less.
    let o = run(&["convert", s(&src), "--to", "apt", "-o", s(&out), "--lossy"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(3), "{e}");
    assert!(out.is_file());
    for line in [8, 9, 10] {
        assert!(
            e.contains(&format!("{}:{line}:1:", src.display())),
            "no warning at {line}: {e}"
        );
    }
}

/// Issue 16: "Fanuc output carries decimal S words (`S4200.6`)." Converted
/// into Fanuc, S words are whole numbers within half a revolution per minute.
#[test]
fn convert_writes_whole_s_words_for_fanuc() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let src = dir.path().join("speeds.mpf");
    std::fs::write(
        &src,
        "; speeds\nG17 G710 G90 G94\nT1\nM6\nD1\nG0 X0 Y0 Z5 S4200.6 M3\nG1 Z0 F300\nX10 S5100.4\n\
         Y10 S5099.5\nM30\n",
    )
    .expect("write the source");
    let out = dir.path().join("speeds.nc");
    let text = convert(&src, "fanuc", &out, &[]);
    let mut n = 0;
    for w in text.lines().flat_map(words) {
        if let Some(v) = w.strip_prefix('S') {
            assert!(v.bytes().all(|c| c.is_ascii_digit()), "`{w}`\n{text}");
            n += 1;
        }
    }
    assert!(n >= 3, "{text}");
    let (p, q) = (
        read(&std::fs::read_to_string(&src).expect("source"), None),
        read(&text, None),
    );
    for (a, b) in p.moves().zip(q.moves()) {
        assert!(
            (a.spindle - b.spindle).abs() <= 0.5,
            "S{} written as S{}",
            a.spindle,
            b.spindle
        );
    }
}

/// Review of issue 16: `--lossy` turned a failed equivalence check into a
/// warning with exit 0. A five-axis G-code block written into APT without the
/// machine's kinematics loses its rotary axes: written (the user asked for
/// that), said even with `--quiet`, and exit 3.
#[test]
fn convert_lossy_that_commands_less_exits_3() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let src = dir.path().join("rot.nc");
    std::fs::write(
        &src,
        "G21 G90 G17 G94\nT1 M6\nG0 X0 Y0 Z50.\nG0 B30. C10.\nG1 X10. F100.\nM30\n",
    )
    .expect("write");
    let out = dir.path().join("rot.apt");
    let o = run(&[
        "convert",
        s(&src),
        "--to",
        "apt",
        "-o",
        s(&out),
        "--lossy",
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("does not command what the source does"),
        "{}",
        stderr(&o)
    );
    assert!(out.is_file());
    // Without --lossy nothing is written, exit 2 at the line.
    std::fs::remove_file(&out).expect("remove");
    let o = run(&["convert", s(&src), "--to", "apt", "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("rot.nc:4:"), "{}", stderr(&o));
    assert!(!out.exists());
}

/// A user trial: `convert --lossy --json` said `"equivalent": true` with no
/// warnings where the text run listed the words written as comments: only
/// the reader's findings reached the JSON. A word written as a comment is
/// one the output does not command: exit 3, `equivalent: false`, and the
/// writer's warnings in the list.
#[test]
fn a_lossy_conversion_says_so_in_json() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let src = dir.path().join("s.mpf");
    std::fs::write(
        &src,
        "; S\nG71 G90 G17\nT1\nM6\nD1\nFNORM\nS8000 M3\nG0 X0 Y0 Z50\nG1 Z-1 F500\nM30\n",
    )
    .expect("writes");
    let out = dir.path().join("o.nc");
    let o = run(&[
        "convert",
        s(&src),
        "--to",
        "fanuc",
        "--lossy",
        "--json",
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(j["equivalent"], false, "{j}");
    let warnings = j["warnings"].as_array().expect("a list");
    assert!(
        warnings.iter().any(|w| w
            .as_str()
            .is_some_and(|w| w.contains("lossy-word") && w.contains("FNORM"))),
        "{j}"
    );
}
