//! The physics commands under fuzzing (issue 34, item 7): `simulate`,
//! `feed`, `force`, `cut`, `lobes`, `orient` and `post` over programs,
//! stocks, materials and machine files whose numbers are mutated to hostile
//! values. Whatever the mix, the run ends with 0, 2 or 3 (never 1, 101 or a
//! signal), never panics, writes no number that is not finite anywhere (NC,
//! CSV, SVG, STL, standard output), no feed move with a feed of 0 or below,
//! and leaves every input as it was.
//!
//! CI runs a few cases with its fixed seed (`PROPTEST_RNG_SEED` in
//! `.ci/run`); `PROPTEST_CASES=20000` runs the long campaign, with
//! `MILLPLAN_FUZZ_BIN` naming a copy of the binary to test.

use millplan_geom::analytic::{tessellate, DemoSurface};
use millplan_geom::stl::write_binary_stl;
use proptest::prelude::*;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const HOSTILE: &[&str] = &[
    "nan", "inf", "-inf", "-1", "0", "1e-300", "5e-324", "1e-9", "1e308", "-1e308", "1e20", "0.01",
    "0.3", "1", "2", "10", "63", "2000",
];

/// A pass 1 mm deep in the auto stocks (their top is the highest cutting
/// tip): the approach and the retract are rapids, so `box:auto` is not a
/// slot 31 mm deep, whose force integrals alone took a minute per debug run.
const PROGRAM: &str = "UNITS/MM\nCUTTER/10,5\nFEDRAT/500\nSPINDL/6000,CLW\nRAPID\nGOTO/0,0,50\nRAPID\nGOTO/0,0,20\nGOTO/0,0,19\nGOTO/60,0,19\nGOTO/60,20,19\nGOTO/0,20,19\nRAPID\nGOTO/0,20,50\nFINI\n";
const FIVE: &str = "UNITS/MM\nCUTTER/10,5\nFEDRAT/500\nSPINDL/6000,CLW\nGOTO/0,0,50,0,0,1\nGOTO/10,0,19,0,0.5,0.866\nGOTO/20,0,19,0,0,1\nGOTO/20,0,50,0,0,1\nFINI\n";
const MATERIAL: &str = "[c45]\nmodel = \"linear\"\nkc = [2100, 800, 500]\nke = [30, 40, 0]\n[ob]\nmodel = \"oblique\"\ntau_s = 300.0\nbeta_a = [20.0, 0.3]\nrc_c0 = [1.7, 0.0]\nrc_a = [0.2, 0.0]\nke = [24.0, 43.0, 0.0]\n";
const MACHINE: &str = "[spindle]\nmin = 500\nmax = 18000\naccel = 6000\n[feed]\nmin = 1\nmax = 20000\nrapid = 15000\n[kinematics]\nkind = \"table-ac\"\nrot_point = [0, 0, 0]\n[axes.x]\nvelocity = 30000\naccel = 3000\njerk = 30000\n[axes.a]\nvelocity = 9000\naccel = 1800\n";
const STOCKS: &[&str] = &[
    "box:-10,-10,0,70,30,20",
    "box:auto",
    "box:auto:1e18",
    "box:0,0,0,1e12,1e12,1",
    "cylinder:auto",
    "box:-10,-10,0,70,30,nan",
];

/// `text` with its `k`-th number (counting from 0, wrapping) replaced by `v`.
fn mutate(text: &str, k: usize, v: &str) -> String {
    let is_num = |w: &str| !w.is_empty() && w.parse::<f64>().is_ok();
    let mut spans = Vec::new();
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let start = i;
        while i < b.len() && (b[i].is_ascii_digit() || b"+-.eE".contains(&b[i])) {
            i += 1;
        }
        if i > start
            && is_num(&text[start..i])
            && (start == 0 || !b[start - 1].is_ascii_alphabetic())
        {
            spans.push(start..i);
        }
        i = i.max(start + 1);
    }
    if spans.is_empty() {
        return text.to_string();
    }
    let s = spans[k % spans.len()].clone();
    format!("{}{v}{}", &text[..s.start], &text[s.end..])
}

/// The inputs of one case, written into `dir`.
struct Case {
    program: String,
    five: String,
    material: String,
    machine: String,
}

fn setup(dir: &Path, c: &Case) {
    let write = |n: &str, t: &[u8]| std::fs::write(dir.join(n), t).expect("write");
    write("p.apt", c.program.as_bytes());
    write("five.apt", c.five.as_bytes());
    write("m.toml", c.material.as_bytes());
    write("machine.toml", c.machine.as_bytes());
    if !dir.join("part.stl").exists() {
        let mesh = tessellate(&DemoSurface::default(), 4.0);
        let mut stl = Vec::new();
        write_binary_stl(&mesh, "part", &mut stl);
        write("part.stl", &stl);
    }
}

/// The arguments of command `k` with the stock `stock` and numbers `n`.
fn command(k: usize, stock: &str, n: [&str; 3]) -> Vec<String> {
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    let model = [
        "--stock",
        stock,
        "--material",
        "c45",
        "--materials",
        "m.toml",
        "--machine",
        "machine.toml",
    ];
    match k % 7 {
        0 => s(&[
            "simulate",
            "p.apt",
            "--stock",
            stock,
            "--machine",
            "machine.toml",
            "-o",
            "out.stl",
            "--table",
            "out.csv",
            "-q",
        ]),
        1 => [s(&["feed", "p.apt", "-o", "out.apt", "-q"]), s(&model)].concat(),
        2 => [
            s(&["force", "p.apt", "--table", "out.csv", "-q"]),
            s(&model),
        ]
        .concat(),
        3 => s(&[
            "cut",
            "--tool",
            "ball:10",
            "--fz",
            n[0],
            "--ap",
            n[1],
            "--ae",
            n[2],
            "--n",
            "6000",
            "--material",
            if n[0] == "1" { "ob" } else { "c45" },
            "--materials",
            "m.toml",
            "--csv",
            "out.csv",
            "--svg",
            "out.svg",
        ]),
        4 => s(&[
            "lobes", "--fn", n[0], "--k", "1e7", "--zeta", "0.02", "--flutes", "2", "--kt", n[1],
            "--kr", "0.3", "--slot", "-o", "out.svg",
        ]),
        5 => s(&[
            "orient",
            "p.apt",
            "--stl",
            "part.stl",
            "--material",
            "c45",
            "--materials",
            "m.toml",
            "--machine",
            "machine.toml",
            "--fz",
            "0.1",
            "--ap",
            n[1],
            "--ae",
            n[2],
            "--objective",
            if n[0] == "1" { "time" } else { "fxy" },
            "-o",
            "out.apt",
            "-q",
        ]),
        _ => s(&[
            "post",
            "five.apt",
            "--machine",
            "machine.toml",
            "-o",
            "out.nc",
        ]),
    }
}

/// A number word that is not finite (`NaN`, `inf`, `-inf`, `Xinf`), or a
/// feed of 0 or below on a feed word (`F0.`, `FEDRAT/0`).
fn bad_word(text: &str, feeds: bool) -> Option<String> {
    for w in text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '/'))
    {
        // `NaN`, `-inf`, or an address letter before it (`Xinf`, `FEDRAT/nan`).
        let lower = w.rsplit('/').next().unwrap_or(w).to_ascii_lowercase();
        let non_finite = |b: &str| {
            matches!(
                b,
                "nan" | "inf" | "-inf" | "+inf" | "infinity" | "-infinity"
            )
        };
        let lettered = lower.len() > 1 && lower.as_bytes()[0].is_ascii_alphabetic();
        if non_finite(&lower) || (lettered && non_finite(&lower[1..])) {
            return Some(w.to_string());
        }
        let feed = w
            .strip_prefix("FEDRAT/")
            .or_else(|| w.strip_prefix('F'))
            .filter(|_| feeds);
        if let Some(v) = feed.and_then(|v| v.parse::<f64>().ok()) {
            if v <= 0.0 {
                return Some(w.to_string());
            }
        }
    }
    None
}

fn run_checked(dir: &Path, args: &[String]) -> Result<i32, TestCaseError> {
    for f in ["out.apt", "out.nc", "out.csv", "out.svg", "out.stl"] {
        let _ = std::fs::remove_file(dir.join(f));
    }
    let inputs = ["p.apt", "five.apt", "m.toml", "machine.toml", "part.stl"];
    let before: Vec<Vec<u8>> = inputs
        .iter()
        .map(|f| std::fs::read(dir.join(f)).expect("in"))
        .collect();
    let mut child = Command::new(binary())
        .current_dir(dir)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let t = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break Some(s);
        }
        if cpu_seconds(child.id()).unwrap_or(t.elapsed().as_secs_f64()) > LIMIT_S
            || t.elapsed() > Duration::from_secs(30 * 60)
        {
            let _ = child.kill();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let o = child.wait_with_output().expect("output");
    let err = String::from_utf8_lossy(&o.stderr);
    let Some(status) = status else {
        return Err(TestCaseError::fail(format!(
            "{args:?} ran over {LIMIT_S} s of CPU"
        )));
    };
    let code = status.code().unwrap_or(-1);
    prop_assert!(matches!(code, 0 | 2 | 3), "{args:?}: {status:?} {err}");
    prop_assert!(!err.contains("panicked"), "{args:?}: {err}");
    let out = String::from_utf8_lossy(&o.stdout);
    if let Some(w) = bad_word(&out, false) {
        prop_assert!(false, "{args:?} printed `{w}`: {out}");
    }
    for f in ["out.apt", "out.nc", "out.csv", "out.svg"] {
        if let Ok(text) = std::fs::read_to_string(dir.join(f)) {
            let text: String = text
                .lines()
                .map(|l| l.split(['(', ';']).next().unwrap_or(""))
                .collect::<Vec<_>>()
                .join("\n");
            if let Some(w) = bad_word(&text, f.starts_with("out.apt") || f == "out.nc") {
                prop_assert!(false, "{args:?} wrote `{w}` into {f}");
            }
        }
    }
    if let Ok(stl) = std::fs::read(dir.join("out.stl")) {
        let floats = stl
            .get(84..)
            .unwrap_or(&[])
            .chunks_exact(50)
            .flat_map(|t| t[..48].chunks_exact(4));
        for f in floats {
            let v = f32::from_le_bytes([f[0], f[1], f[2], f[3]]);
            prop_assert!(v.is_finite(), "{args:?} wrote {v} into out.stl");
        }
    }
    for (f, b) in inputs.iter().zip(&before) {
        prop_assert!(
            std::fs::read(dir.join(f)).expect("in") == *b,
            "{args:?} changed {f}"
        );
    }
    for e in std::fs::read_dir(dir).expect("dir").flatten() {
        let n = e.file_name().to_string_lossy().into_owned();
        prop_assert!(!n.starts_with(".millplan-"), "{args:?} left {n}");
    }
    Ok(code)
}

/// CPU seconds a command may take (user and system, all its threads).
const LIMIT_S: f64 = 120.0;

/// The CPU time of process `pid` so far, s, where `/proc` tells it: the
/// limit counts the command's own work, not the time a loaded or niced
/// machine leaves it waiting (a fuzz campaign runs beside other work). The
/// wall clock stands in elsewhere.
fn cpu_seconds(pid: u32) -> Option<f64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // Fields after the command name in parentheses: state is the 3rd field
    // of the file, utime and stime the 14th and 15th.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    // USER_HZ is 100 on every Linux architecture the toolchain targets.
    Some(ticks / 100.0)
}

/// The binary under test: `MILLPLAN_FUZZ_BIN` names a copy for a long
/// campaign, so that builds made while it runs do not change what it tests.
fn binary() -> std::ffi::OsString {
    std::env::var_os("MILLPLAN_FUZZ_BIN").unwrap_or_else(|| env!("CARGO_BIN_EXE_millplan").into())
}

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(21)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    #[test]
    fn physics_commands_hold_their_promises(
        k in 0usize..7,
        which in 0usize..5,
        at in 0usize..40,
        v in prop::sample::select(HOSTILE),
        stock in prop::sample::select(STOCKS),
        n in prop::array::uniform3(prop::sample::select(HOSTILE)),
    ) {
        let dir = tempfile::tempdir().expect("tmp");
        let pick = |i: usize, t: &str| if which == i { mutate(t, at, v) } else { t.to_string() };
        let c = Case {
            program: pick(0, PROGRAM),
            five: pick(1, FIVE),
            material: pick(2, MATERIAL),
            machine: pick(3, MACHINE),
        };
        setup(dir.path(), &c);
        let t = Instant::now();
        let code = run_checked(dir.path(), &command(k, stock, n))?;
        if let Ok(p) = std::env::var("MILLPLAN_FUZZ_LOG") {
            use std::io::Write;
            let mut f = std::fs::OpenOptions::new().create(true).append(true).open(p).expect("log");
            let _ = writeln!(f, "{} {code} {:.3}", k % 7, t.elapsed().as_secs_f64());
        }
    }
}

#[test]
fn mutation_replaces_one_number() {
    assert_eq!(mutate("GOTO/1,2.5,-3\n", 1, "nan"), "GOTO/1,nan,-3\n");
    assert_eq!(mutate("GOTO/1,2.5,-3\n", 5, "inf"), "GOTO/1,2.5,inf\n");
    assert_eq!(bad_word("G1 X1 F0.", true), Some("F0.".into()));
    assert_eq!(bad_word("FEDRAT/0,MMPM", true), Some("FEDRAT/0".into()));
    assert_eq!(bad_word("G1 Xinf", false), Some("Xinf".into()));
    assert_eq!(bad_word("G1 X1 F100. (info)", true), None);
    assert_eq!(bad_word("fill=\"#F00\"", false), None);
}
