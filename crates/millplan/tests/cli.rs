//! The CLI through the real binary: exit codes, JSON keys, atomic outputs.

use std::path::PathBuf;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

#[path = "../../millplan-nc/tests/shared_data/mod.rs"]
mod shared_data;

fn golden(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../millplan-nc/tests/golden")
        .join(name)
}

fn json(args: &[&str]) -> serde_json::Value {
    let out = bin().args(args).output().expect("runs");
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("json")
}

/// `feed` on a real program: SOLIDWORKS CAM's Interface-glue (a 14 mm flat
/// end mill clearing, a 14 mm ball on 40 Z levels, the flat end mill again)
/// over its 135 × 135 × 30 mm stock in al7075, with a 1500 N F_xy and
/// 0.1 mm deflection limit. The written program re-reads, its feeds stay in
/// the machine's range, its own prediction stays within the limits, and
/// the operations whose feed was conservative (the flat end mill's, loaded
/// to about half the limit) run faster, while the ball's, which exceeds it,
/// is slowed. The program drives a rapid into the stock at line 36 (as
/// `optimise` finds it too): refused without `--force`, written with it
/// (exit 3), the stock check failing on the input's own faults only.
#[test]
fn feed_on_a_real_program_meets_its_limits_and_speeds_up_the_conservative_operations() {
    let Some(apt) = shared_data::file("swcam-apt-stl-pairs/Interface-glue.apt") else {
        return;
    };
    let machine = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/machine.toml");
    let d = tempfile::tempdir().expect("tmp");
    let out = d.path().join("feed.apt");
    let args = [
        "feed",
        apt.to_str().expect("utf-8"),
        "--stock",
        "box:0,0,-30,135,135,0",
        "--material",
        "al7075",
        "--machine",
        machine.to_str().expect("utf-8"),
        "--to",
        "apt",
        "--limit",
        "fxy=1500,deflection=0.1",
        "--flutes",
        "2",
        "--resolution",
        "0.5",
        "--dz",
        "0.25",
        "--dphi",
        "4",
        "-o",
        out.to_str().expect("utf-8"),
        "--json",
        "-q",
    ];
    let refused = bin().args(args).output().expect("runs");
    let err = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(3), "{err}");
    assert!(err.contains("Interface-glue.apt:36: check stock"), "{err}");
    assert!(!out.exists(), "nothing written without --force");
    let o = bin().args(args).arg("--force").output().expect("runs");
    assert_eq!(o.status.code(), Some(3));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    for c in j["checks"].as_array().expect("checks") {
        let own = c["findings"].as_array().expect("findings").iter();
        let own = own.clone().all(|f| f["in_input"] == true);
        assert!(c["ok"] == true || (c["name"] == "stock" && own), "{c}");
    }
    let f = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    assert_eq!(j["over_limit_after"], 0, "{j}");
    // Within the tolerance the command states for its exit code (a load
    // that far over its limit is within the model's resolution, and
    // counted as `within_tolerance_after`).
    let within = 1.0 + f(&j["limit_tolerance"]);
    assert!(within > 1.0 && within <= 1.01, "{j}");
    assert!(f(&j["max_after"]["fxy"]) <= 1500.0 * within, "{j}");
    assert!(f(&j["max_after"]["deflection"]) <= 0.1 * within, "{j}");
    assert!(
        f(&j["max_before"]["fxy"]) > 1500.0,
        "the input exceeds the limit somewhere: {j}"
    );
    let ops = j["operations"].as_array().expect("operations");
    assert_eq!(ops.len(), 3, "three milling operations are simulated: {j}");
    let mut faster = 0;
    let mut slowed = 0;
    for o in ops {
        let (t0, t1) = (
            f(&o["time_nominal_before_s"]),
            f(&o["time_nominal_after_s"]),
        );
        if f(&o["fxy_max_before"]) < 0.6 * 1500.0 {
            assert!(t1 < 0.8 * t0, "a conservative operation gains: {o}");
            faster += 1;
        } else if f(&o["fxy_max_before"]) > 1500.0 {
            assert!(t1 > t0, "an overloaded operation is slowed: {o}");
            slowed += 1;
        }
    }
    assert!(faster >= 1 && slowed >= 1, "{j}");
    // Feeds within the machine's range (1–20000 mm/min in examples/machine.toml).
    let text = std::fs::read_to_string(&out).expect("written");
    let feeds: Vec<f64> = text
        .lines()
        .filter_map(|l| l.strip_prefix("FEDRAT/"))
        .map(|f| {
            f.split(',')
                .next()
                .unwrap_or("")
                .trim()
                .parse()
                .expect("a feed")
        })
        .collect();
    // FEDRAT is written where the feed changes (air blocks share one feed).
    assert!(feeds.len() > 50, "{} feeds written", feeds.len());
    assert!(
        feeds.iter().all(|v| (1.0..=20000.0).contains(v)),
        "{feeds:?}"
    );
    // It re-reads, with every move of the input.
    let (a, b) = (
        json(&["inspect", "--json", apt.to_str().expect("utf-8")]),
        json(&["inspect", "--json", out.to_str().expect("utf-8")]),
    );
    assert_eq!(a["moves"], b["moves"], "{a}\n{b}");
}

#[test]
fn inspect_json_on_every_shared_file() {
    let Some(root) = shared_data::dir() else {
        return;
    };
    let dirs = std::fs::read_dir(root).expect("../shared/data lists");
    let mut n = 0;
    for d in dirs.flatten() {
        for f in std::fs::read_dir(d.path()).expect("dir").flatten() {
            let p = f.path();
            let name = p
                .file_name()
                .and_then(|s| s.to_str())
                .unwrap_or("")
                .to_string();
            // Documentation, the CAMotics project file, tool lists and KRL robot
            // programs (read by the robot issue) are not NC programs or meshes.
            if name == "PROVENANCE.md"
                || name.ends_with(".camotics")
                || name.ends_with(".csv")
                || name.ends_with(".txt") && name.contains("Tool_List")
                || name.ends_with(".SRC")
            {
                continue;
            }
            let j = json(&["inspect", "--json", p.to_str().expect("utf8")]);
            n += 1;
            if j["format"] == "stl" {
                for k in ["triangles", "degenerate", "open_edges", "bounds"] {
                    assert!(!j[k].is_null(), "{name}: {k}");
                }
            } else {
                for k in [
                    "format",
                    "units",
                    "tools",
                    "moves",
                    "bounds",
                    "length_mm",
                    "time_s",
                ] {
                    assert!(!j[k].is_null(), "{name}: {k}");
                }
                for k in ["rapid", "linear", "arc"] {
                    assert!(j["moves"][k].is_u64(), "{name}: moves.{k}");
                }
                assert!(
                    j["length_mm"]["cutting"].is_number() && j["length_mm"]["rapid"].is_number()
                );
                // The estimate with acceleration never undercuts the time at
                // programmed feeds (rapids at the rapid rate).
                let (t, t0) = (
                    j["time_s"].as_f64().expect("time_s"),
                    j["time_nominal_s"].as_f64().expect("time_nominal_s"),
                );
                assert!(
                    t.is_finite() && t >= t0 * (1.0 - 1e-9),
                    "{name}: {t} < {t0}"
                );
                assert_eq!(j["time"]["model"], "acceleration", "{name}");
            }
        }
    }
    assert!(n >= 25, "{n} files inspected");
}

#[test]
fn inspect_counts_the_interface_glue_pair() {
    let (Some(apt), Some(stl)) = (
        shared_data::file("swcam-apt-stl-pairs/Interface-glue.apt"),
        shared_data::file("swcam-apt-stl-pairs/Interface-glue.STL"),
    ) else {
        return;
    };
    let j = json(&["inspect", "--json", apt.to_str().expect("utf8")]);
    let m = &j["moves"];
    let total = m["rapid"].as_u64().unwrap_or(0)
        + m["linear"].as_u64().unwrap_or(0)
        + m["arc"].as_u64().unwrap_or(0)
        + m["cycle"].as_u64().unwrap_or(0);
    assert_eq!(total, 6311);
    assert_eq!(m["arc"], 50);
    let j = json(&["inspect", "--json", stl.to_str().expect("utf8")]);
    assert_eq!(
        (j["encoding"].as_str(), j["triangles"].as_u64()),
        (Some("binary"), Some(1652))
    );
    // formats.md: bbox [10,10,-30]..[125,125,-1] (single-precision file).
    let want = [[10.0, 10.0, -30.0], [125.0, 125.0, -1.0]];
    for (k, w) in ["min", "max"].iter().zip(want) {
        for (a, b) in j["bounds"][k].as_array().expect("bounds").iter().zip(w) {
            assert!(
                (a.as_f64().unwrap_or(f64::NAN) - b).abs() < 1e-4,
                "{k}: {a} vs {b}"
            );
        }
    }
}

fn fails_with_2(args: &[&str], needle: &str) {
    let out = bin().args(args).output().expect("runs");
    assert_eq!(out.status.code(), Some(2), "{args:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(needle), "{args:?}: {err}");
}

#[test]
fn bad_inputs_exit_2_with_location_and_leave_no_output() {
    let dir = tempfile::tempdir().expect("tmp");
    let w = |name: &str, bytes: &[u8]| {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).expect("write");
        p
    };
    let truncated = w("t.apt", b"UNITS/MM\nFEDRAT/100,MMPM\nGOTO/1,2\n");
    let letters = w("l.nc", b"G21\nT1 M6\nG1 X1..2 F100\n");
    let empty = w("e.apt", b"");
    let mut stl = vec![0u8; 84 + 50];
    stl[80] = 7; // claims 7 facets, holds 1
    let stl = w("bad.stl", &stl);
    let mut no_facets = vec![0u8; 84];
    no_facets[..5].copy_from_slice(b"solid");
    let no_facets = w("none.stl", &no_facets);
    let out = dir.path().join("out.nc");
    let o = out.to_str().expect("utf8");
    fails_with_2(
        &[
            "convert",
            truncated.to_str().expect("utf8"),
            "--to",
            "fanuc",
            "-o",
            o,
        ],
        "t.apt:3:6:",
    );
    fails_with_2(
        &[
            "convert",
            letters.to_str().expect("utf8"),
            "--to",
            "fanuc",
            "-o",
            o,
        ],
        "l.nc:3:",
    );
    fails_with_2(&["inspect", empty.to_str().expect("utf8")], "e.apt:1:1:");
    fails_with_2(
        &["inspect", stl.to_str().expect("utf8")],
        "bad.stl:byte 80:",
    );
    fails_with_2(
        &[
            "inspect",
            dir.path().join("missing.apt").to_str().expect("utf8"),
        ],
        "cannot open",
    );
    fails_with_2(&["convert", "--bogus"], "");
    fails_with_2(
        &[
            "reorder",
            truncated.to_str().expect("utf8"),
            "--stl",
            stl.to_str().expect("utf8"),
            "--max-step=-1",
            "-o",
            o,
        ],
        "--max-step",
    );
    // An STL without a triangle has no surface to control the spindle on.
    let apt = w(
        "ok.apt",
        b"UNITS/MM\nCUTTER/10,5\nFEDRAT/100,MMPM\nGOTO/0,0,0\nGOTO/1,0,0\n",
    );
    for cmd in ["speed", "reorder", "directions"] {
        let mut args = vec![
            cmd,
            "--stl",
            no_facets.to_str().expect("utf8"),
            apt.to_str().expect("utf8"),
        ];
        if cmd == "speed" {
            args.extend(["--vc", "63", "--fz", "0.1", "--flutes", "2", "--ap", "0.3"]);
        }
        if cmd == "reorder" {
            args.extend(["--ap", "0.3"]);
        }
        if cmd == "directions" {
            args.extend(["--vc", "63", "--fz", "0.1", "--flutes", "2", "--ap", "0.3"]);
        }
        if cmd != "directions" {
            args.extend(["-o", o]);
        }
        fails_with_2(&args, "none.stl: no triangles");
    }
    assert!(!out.exists(), "a failed run left an output");
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(".millplan"))
        .collect();
    assert!(leftovers.is_empty());
}

#[test]
fn convert_refuses_to_overwrite_its_input_and_round_trips() {
    let dir = tempfile::tempdir().expect("tmp");
    let src = dir.path().join("in.apt");
    std::fs::copy(golden("solidworks.apt"), &src).expect("copy");
    let before = std::fs::read(&src).expect("read");
    let s = src.to_str().expect("utf8");
    fails_with_2(
        &["convert", s, "--to", "apt", "-o", s],
        "refusing to overwrite",
    );
    assert_eq!(
        std::fs::read(&src).expect("read"),
        before,
        "input untouched"
    );
    for (to, ext) in [
        ("fanuc", "nc"),
        ("sinumerik", "mpf"),
        ("heidenhain", "h"),
        ("linuxcnc", "ngc"),
        ("apt", "apt"),
    ] {
        let out = dir.path().join(format!("out.{ext}"));
        let st = bin()
            .args(["convert", s, "--to", to, "-o", out.to_str().expect("utf8")])
            .status()
            .expect("runs");
        assert!(st.success(), "{to}");
        let j = json(&["inspect", "--json", out.to_str().expect("utf8")]);
        assert_eq!(j["units"], "mm", "{to}");
        assert!(j["moves"]["linear"].as_u64().unwrap_or(0) >= 1, "{to}");
    }
}

#[test]
fn demo_runs_and_its_outputs_read() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("demo");
    let st = bin()
        .args(["demo", "-o", out.to_str().expect("utf8")])
        .status()
        .expect("runs");
    assert!(st.success());
    let stl = json(&[
        "inspect",
        "--json",
        out.join("part.stl").to_str().expect("utf8"),
    ]);
    assert_eq!(stl["triangles"], 28800);
    let apt = json(&[
        "inspect",
        "--json",
        out.join("finish.apt").to_str().expect("utf8"),
    ]);
    for f in [
        "finish_fanuc.nc",
        "finish_sinumerik.mpf",
        "finish_heidenhain.h",
        "finish_linuxcnc.ngc",
    ] {
        let g = json(&["inspect", "--json", out.join(f).to_str().expect("utf8")]);
        assert_eq!(g["moves"]["linear"], apt["moves"]["linear"], "{f}");
    }
}

/// `-q` as on every other command: the same files, one line printed.
#[test]
fn quiet_demo_writes_the_same_files_and_one_line() {
    let dir = tempfile::tempdir().expect("tmp");
    let listing = |quiet: bool| {
        let out = dir.path().join(if quiet { "q" } else { "loud" });
        let mut cmd = bin();
        cmd.args(["demo", "-o", out.to_str().expect("utf8")]);
        if quiet {
            cmd.arg("-q");
        }
        let o = cmd.output().expect("runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(&out)
            .expect("folder")
            .map(|e| {
                let e = e.expect("entry");
                let name = e.file_name().to_string_lossy().into_owned();
                (name, std::fs::read(e.path()).expect("reads"))
            })
            .collect();
        files.sort();
        (String::from_utf8(o.stdout).expect("utf8"), files)
    };
    let (loud, all) = listing(false);
    let (quiet, same) = listing(true);
    assert!(loud.lines().count() > all.len(), "{loud}");
    assert_eq!(quiet.lines().count(), 1, "{quiet}");
    assert!(quiet.contains("report.html"), "{quiet}");
    let names = |f: &[(String, Vec<u8>)]| f.iter().map(|x| x.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&all), names(&same));
    // The report names its folder; every other file is the same byte for byte.
    for ((name, a), (_, b)) in all.iter().zip(&same) {
        if name != "report.html" {
            assert!(a == b, "{name}");
        }
    }
}

#[test]
fn help_explains_every_command() {
    for c in [
        "inspect",
        "convert",
        "demo",
        "wd",
        "wd-sweep",
        "speed",
        "directions",
        "setup",
    ] {
        let out = bin().args([c, "--help"]).output().expect("runs");
        assert!(out.status.success());
        assert!(String::from_utf8_lossy(&out.stdout).len() > 200, "{c}");
    }
}

/// ARCHITECTURE.md's dependency rule, read from `cargo metadata`: each
/// library crate depends only on the crates below it
/// (geom ← nc; geom ← models; nc + models ← sim ← plan ← report ← driver;
/// tooldb alone, below driver; geom + nc ← robot), and no library on the command-line, terminal or temporary-file
/// crates that only the binary uses (but the driver's `io`, which stages a
/// run's outputs in temporary files).
#[test]
fn crate_dependencies_point_one_way() {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let m: serde_json::Value = serde_json::from_slice(&out.stdout).expect("metadata json");
    let allowed: &[(&str, &[&str])] = &[
        ("millplan-geom", &[]),
        ("millplan-nc", &["millplan-geom"]),
        ("millplan-models", &["millplan-geom"]),
        (
            "millplan-sim",
            &["millplan-geom", "millplan-nc", "millplan-models"],
        ),
        (
            "millplan-plan",
            &[
                "millplan-geom",
                "millplan-nc",
                "millplan-models",
                "millplan-sim",
            ],
        ),
        (
            "millplan-report",
            &[
                "millplan-geom",
                "millplan-nc",
                "millplan-models",
                "millplan-sim",
                "millplan-plan",
            ],
        ),
        ("millplan-tooldb", &[]),
        ("millplan-robot", &["millplan-geom", "millplan-nc"]),
        (
            "millplan-driver",
            &[
                "millplan-geom",
                "millplan-nc",
                "millplan-models",
                "millplan-sim",
                "millplan-plan",
                "millplan-report",
                "millplan-tooldb",
                "millplan-robot",
            ],
        ),
    ];
    let binary_only = [
        "clap",
        "clap_complete",
        "clap_mangen",
        "indicatif",
        "tempfile",
        "anyhow",
        "mimalloc",
    ];
    let packages = m["packages"].as_array().expect("packages");
    let mut seen = 0;
    for p in packages {
        let name = p["name"].as_str().unwrap_or("");
        let Some((_, ok)) = allowed.iter().find(|(n, _)| *n == name) else {
            continue;
        };
        seen += 1;
        for d in p["dependencies"].as_array().expect("dependencies") {
            if !d["kind"].is_null() {
                continue; // dev- and build-dependencies
            }
            let dep = d["name"].as_str().unwrap_or("");
            if dep.starts_with("millplan") {
                assert!(ok.contains(&dep), "{name} must not depend on {dep}");
            }
            let staging = name == "millplan-driver" && dep == "tempfile";
            assert!(
                staging || !binary_only.contains(&dep),
                "{name} must not depend on {dep}: only the binary does I/O and argument parsing"
            );
        }
    }
    assert_eq!(seen, allowed.len(), "every library crate checked");
}

#[test]
fn wd_prints_the_oracle_value() {
    // working-diameter.md §2.3: D 10, ap 0.3, ae 0.25, α 20°, A_f 45°, left → 4.1301 mm.
    let j = json(&[
        "wd", "--d", "10", "--ap", "0.3", "--ae", "0.25", "--alpha", "20", "--af", "45", "--side",
        "left", "--json",
    ]);
    assert!((j["d_w"].as_f64().expect("d_w") - 4.1301).abs() < 1e-4);
    // No --ae: no neighbouring pass (O2 row: 6.4210 mm).
    let j = json(&[
        "wd", "--d", "10", "--ap", "0.3", "--alpha", "20", "--af", "0", "--json",
    ]);
    assert!((j["d_w"].as_f64().expect("d_w") - 6.4210).abs() < 1e-4);
    fails_with_2(
        &["wd", "--d", "10", "--ap=-1", "--alpha", "20", "--af", "0"],
        "--ap -1: must be a number above 0 and at most 5 mm",
    );
}

/// The binary's sources: every `.rs` file under `src`, with its text.
fn binary_sources() -> Vec<(PathBuf, String)> {
    fn files(dir: &std::path::Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).expect("src").flatten() {
            let p = e.path();
            if p.is_dir() {
                files(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    let mut v = Vec::new();
    files(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src"),
        &mut v,
    );
    v.sort();
    v.into_iter()
        .map(|f| {
            let text = std::fs::read_to_string(&f).expect("read");
            (f, text)
        })
        .collect()
}

/// The functions of `text` longer than `max` lines, counted brace to brace,
/// as (first line, lines).
fn long_functions(text: &str, max: usize) -> Vec<(usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut long = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let t = lines[i].trim_start();
        let is_fn =
            (t.starts_with("fn ") || t.starts_with("pub fn ") || t.starts_with("pub(crate) fn "))
                && !t.ends_with(';');
        if !is_fn {
            i += 1;
            continue;
        }
        let indent = lines[i].len() - t.len();
        let mut j = i + 1;
        while j < lines.len()
            && !(lines[j].len() > indent
                && lines[j][..indent].trim().is_empty()
                && lines[j][indent..].starts_with('}'))
        {
            j += 1;
        }
        if j - i + 1 > max {
            long.push((i + 1, j - i + 1));
        }
        i = j + 1;
    }
    long
}

#[test]
fn long_functions_are_found_brace_to_brace() {
    let short = "fn a() {\n    x();\n}\n";
    assert!(long_functions(short, 3).is_empty());
    assert_eq!(long_functions(short, 2), vec![(1, 3)]);
    let nested = "impl A {\n    pub fn b() {\n        y();\n        z();\n    }\n}\n";
    assert_eq!(long_functions(nested, 3), vec![(2, 4)]);
}

/// ARCHITECTURE.md: the binary parses arguments, calls the libraries and
/// prints; decisions live in the library crates. Every function of the
/// binary is at most 60 lines, counted brace to brace.
#[test]
fn no_function_of_the_binary_is_over_60_lines() {
    let mut long = Vec::new();
    for (f, text) in binary_sources() {
        for (at, n) in long_functions(&text, 60) {
            long.push(format!("{}:{at} ({n} lines)", f.display()));
        }
    }
    assert!(long.is_empty(), "functions over 60 lines: {long:?}");
}

/// The bound of [`the_binary_stays_small`]: 7,610 lines after `feed`,
/// `force`, `post` and `tool` moved into `millplan-driver`, 7,766 once the
/// KRL reading of `convert`, `--spindle`, `simulate --timings` and the
/// progress bar of `optimise` came in beside that move; 6,409 after file
/// access (`io`), the tool library's decisions, the run's limits, the
/// rounding of JSON numbers, the timing clock, the demo's files and the
/// thread checks' outcomes moved into the driver; 6,324 once `robot`'s
/// and `speed`'s runs moved (one driver function per command); 6,345 with
/// the argument groups several commands share declared once (`cmd/args.rs`:
/// no fewer lines, one definition); 6,060 once `simulate`, `orient`,
/// `reorder`, `tool`, `optimise`'s text and `speed`'s threads moved;
/// 6,048 with the machine file read by the driver's `io`; 6,026 with
/// `optimise`'s option checks in the driver (`Options::checked`); 5,447
/// once `robot --stock` went through the driver; 5,563 with `--timings` on
/// `feed`, `force`, `orient`, `reorder`, `gouge`, `raster` and `setup` (the
/// laps where the binary's own steps end, one `Timings` group for all);
/// 5,577 with `feed`'s checks before writing and its `--force`; 5,607 with
/// `optimise --robot --orientation` and the KRL-only options refused
/// without a KRL output; 5,571 with one helper printing the commands'
/// summaries as JSON or text; 5,615 with `--timings` on `directions`, `lobes`,
/// `wd-sweep` and `robot place` and `compensate` (5,617 with a lap only
/// for the phases that ran); 5,616 with `optimise`'s orient pass in the
/// driver and its help reflowed; 5,433 with the options several commands
/// repeated declared once as groups in `cmd/args.rs` (the part, the
/// program's units, the machine file, the output and its dialect,
/// `--force`, the force model's tool and steps; the force model's inputs
/// shared by `feed`, `force` and `robot`), the repeated planning of outputs,
/// bars and sets of files as one helper each, and setup's choice of
/// kinematics and inspect's inch STL in the driver; 5,287 once the runs of
/// `feed`, `post` and `convert` moved into the driver (`feed::command`,
/// `post::command`, `convert::command`, telling the binary through
/// `watch::Watch`); 5,288 with a line of `post --help`; 4,767 once the
/// runs of `reorder`, `simulate`, `speed`, `orient`, `raster`, `gouge`,
/// `setup` and `directions` moved there too (`run_command` in each
/// module), with the helpers only they used (`verdict.rs`, the in-memory
/// and file writers, `pass_error`, the output plan); 4,775 with `optimise`
/// refusing a named pass whose input is missing (its help says so); 4,785
/// with a job's finding (an axis out of travel) mapped to exit 3.
const MAX_BINARY_LINES: usize = 4785;

/// The binary's size, all files under `src` counted. Issue 31 sets 5,000
/// lines as the goal; the bound is lowered as commands move into
/// `millplan-driver`.
#[test]
fn the_binary_stays_small() {
    const MAX_LINES: usize = MAX_BINARY_LINES;
    let total: usize = binary_sources()
        .iter()
        .map(|(_, t)| t.lines().count())
        .sum();
    assert!(
        total <= MAX_LINES,
        "the binary has {total} lines, more than {MAX_LINES}: move the decisions into a library crate"
    );
}

/// A numeric literal where `text` (one line) gives a default: a clap
/// `default_value = "<number…>"` or `default_value_t = <number>`, or an
/// `unwrap_or(<number>)`. Defaults are named in `millplan_driver`
/// (`command_defaults`, `defaults`) so that each is chosen in one place.
fn numeric_default(text: &str) -> Option<&str> {
    let numeric = |rest: &str| {
        let rest = rest.strip_prefix('"').unwrap_or(rest);
        let rest = rest.strip_prefix('-').unwrap_or(rest);
        let rest = rest.strip_prefix('.').unwrap_or(rest);
        rest.starts_with(|c: char| c.is_ascii_digit())
    };
    ["default_value = ", "default_value_t = ", "unwrap_or("]
        .into_iter()
        .find(|pat| {
            text.match_indices(pat)
                .any(|(i, _)| numeric(&text[i + pat.len()..]))
        })
}

#[test]
fn numeric_defaults_are_recognised() {
    assert!(numeric_default(r#"#[arg(long, default_value = "0:30")]"#).is_some());
    assert!(numeric_default("#[arg(long, default_value_t = -1.5)]").is_some());
    assert!(numeric_default("let x = a.or(b).unwrap_or(1000.0);").is_some());
    assert!(numeric_default(r#"#[arg(long, default_value = "fxy")]"#).is_none());
    assert!(numeric_default("#[arg(long, default_value_t = command_defaults::cut::DZ)]").is_none());
    assert!(numeric_default("let x = a.unwrap_or(f64::NAN);").is_none());
    assert!(numeric_default(r#"t.map(|t| t.to_string()).unwrap_or("-".into())"#).is_none());
    assert!(numeric_default("let x = a.unwrap_or(.5);").is_some());
}

#[test]
fn the_commands_hold_no_numeric_default() {
    let mut found = Vec::new();
    for (f, text) in binary_sources() {
        if !f.components().any(|c| c.as_os_str() == "cmd") {
            continue;
        }
        for (i, line) in text.lines().enumerate() {
            if let Some(what) = numeric_default(line) {
                found.push(format!("{}:{}: {what}", f.display(), i + 1));
            }
        }
    }
    assert!(found.is_empty(), "numeric defaults in cmd/: {found:?}");
}

/// The commands name no internals of the model and simulation crates: what
/// they need of `millplan-models` and `millplan-sim` reaches them through
/// the types `millplan_driver` re-exports one by one at its root or in its
/// command modules (never a whole crate or a glob), and through the plan
/// and report crates' own APIs. Every file of `cmd/` is held to it.
#[test]
fn the_commands_name_no_model_or_simulation_internals() {
    let mut found = Vec::new();
    for (f, text) in binary_sources() {
        let in_cmd = f.components().any(|c| c.as_os_str() == "cmd");
        if !in_cmd {
            continue;
        }
        for (i, line) in text.lines().enumerate() {
            if line.contains("millplan_sim") || line.contains("millplan_models") {
                found.push(format!("{}:{}: {}", f.display(), i + 1, line.trim()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "cmd/ names model or simulation internals: {found:?}"
    );
    let driver = std::fs::read_to_string(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../millplan-driver/src/lib.rs"),
    )
    .expect("driver's lib.rs");
    for line in driver
        .lines()
        .filter(|l| l.starts_with("pub use millplan_"))
    {
        assert!(
            !line.ends_with("::*;") && line.matches("::").count() >= 2,
            "the driver re-exports a whole module or crate: {line}"
        );
    }
}

#[test]
fn explain_takes_a_code_as_it_is_printed() {
    for arg in [
        "unknown-word",
        "warning[unknown-word]",
        "note[block-delete]",
    ] {
        let out = bin().args(["explain", arg]).output().expect("runs");
        assert!(out.status.success(), "{arg}");
        assert!(!out.stdout.is_empty(), "{arg}");
    }
    let out = bin().args(["explain", "no-such"]).output().expect("runs");
    assert_eq!(out.status.code(), Some(2));
}

/// Issue 18, then issue 35: a KUKA robot program is read as KRL, its
/// errors at their line, not a parse error at `&ACCESS` (the PowerMILL
/// sample's `inspect` is in tests/convert_krl.rs).
#[test]
fn krl_programs_are_read_as_krl() {
    let dir = tempfile::tempdir().expect("tmp");
    let src = dir.path().join("ROBOT.SRC");
    std::fs::write(
        &src,
        "&ACCESS RVP\r\n&REL 2\r\nDEF robot()\r\nLIN {X 1}\r\nEND\r\n",
    )
    .expect("write");
    fails_with_2(
        &["inspect", src.to_str().expect("utf8")],
        "ROBOT.SRC:4:5: a KRL position needs X, Y and Z",
    );
}

/// `millplan feed` on a generated ball-end finishing case: the program it
/// writes re-reads, stays in the machine's feed range and its limits, and
/// is faster than the conservative input; `force PATH` reports the loads.
#[test]
fn feed_schedules_a_generated_finishing_raster() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = dir.path();
    let s = |p: &str| d.join(p).display().to_string();
    let out = bin()
        .args(["demo", "-o", &s("demo")])
        .output()
        .expect("runs");
    assert!(out.status.success());
    let raster = bin()
        .args([
            "raster",
            "--stl",
            &s("demo/part.stl"),
            "--tool",
            "ball:10",
            "--stepover",
            "2",
            "--step",
            "1",
            "-o",
            &s("r.apt"),
            "-q",
        ])
        .output()
        .expect("runs");
    assert!(
        raster.status.success(),
        "{}",
        String::from_utf8_lossy(&raster.stderr)
    );
    let common = [
        "--stock",
        "offset:0.3",
        "--stl",
        &s("demo/part.stl"),
        "--material",
        "al7075",
    ];
    let f = json(&[&["force", &s("r.apt")][..], &common, &["--json", "-q"]].concat());
    assert!(f["max"]["fxy"].as_f64().expect("fxy") > 0.0, "{f}");
    let j = json(
        &[
            &["feed", &s("r.apt")][..],
            &common,
            &[
                "--limit",
                "fxy=150,deflection=0.05",
                // A finishing pass: the tool maker's chip load, above the
                // material table's roughing value (0.08 mm at D10).
                "--fz-max",
                "0.2",
                "-o",
                &s("out.apt"),
                "--json",
                "-q",
            ],
        ]
        .concat(),
    );
    for k in [
        "time_before_s",
        "time_after_s",
        "max_before",
        "max_after",
        "binding",
        "blocks",
    ] {
        assert!(!j[k].is_null(), "{k}: {j}");
    }
    assert!(
        j["max_after"]["fxy"].as_f64().expect("fxy") <= 150.0 * (1.0 + 1e-9),
        "{j}"
    );
    assert!(
        j["time_after_s"].as_f64() < j["time_before_s"].as_f64(),
        "{j}"
    );
    let back = json(&["inspect", "--json", &s("out.apt")]);
    assert!(!back.is_null());
    let text = std::fs::read_to_string(d.join("out.apt")).expect("written");
    for f in text.lines().filter_map(|l| l.strip_prefix("FEDRAT/")) {
        let v: f64 = f
            .split(',')
            .next()
            .unwrap_or("")
            .trim()
            .parse()
            .expect("a feed");
        assert!((1.0..=20000.0).contains(&v), "feed {v}");
    }
}

/// `inspect` prints the bounds in mm to the thousandth, as its lengths: an
/// inch program's came out as 60.959999999999994.
#[test]
fn inspect_rounds_the_bounds_of_an_inch_program() {
    let dir = tempfile::tempdir().expect("tmp");
    let nc = dir.path().join("inch.nc");
    std::fs::write(
        &nc,
        "%\nO2000\nG17 G20 G90 G94\nT1 M6\nS5000 M3\nG0 X0.5 Y0.5 Z1.\nG1 Z-0.04 F10.\nX2.4 Y2.4\nG0 Z1.\nM30\n%\n",
    )
    .expect("write");
    let o = bin()
        .args(["inspect", nc.to_str().expect("utf8")])
        .output()
        .expect("runs");
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("bounds      [12.700, 12.700, -1.016] .. [60.960, 60.960, 25.400] mm"),
        "{text}"
    );
}
