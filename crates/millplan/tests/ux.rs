//! What a CAM programmer meets: messages that keep their location, wording a
//! user understands, quiet ends of a closed pipe (issue "round two").

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[path = "../../millplan-nc/tests/shared_data/mod.rs"]
mod shared_data;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("runs")
}

/// A folder under `root` whose path is long enough that `root/…/name` is
/// `len` characters, as on a shop's file server.
fn deep_folder(root: &Path, name: &str, len: usize) -> PathBuf {
    let mut dir = root.to_path_buf();
    let mut i = 0;
    while dir.to_str().expect("utf8").len() + 1 + name.len() < len {
        let room = len - (dir.to_str().expect("utf8").len() + 1 + name.len()) - 1;
        let seg = format!("project_{i}_{}", "x".repeat(40));
        dir.push(&seg[..seg.len().min(room.max(1))]);
        i += 1;
    }
    std::fs::create_dir_all(&dir).expect("mkdir");
    dir
}

/// A malformed file: its name, bytes, the command that reads it, and the
/// line and column (or byte) of the error.
type Case<'a> = (&'a str, &'a [u8], &'a [&'a str], (Option<u64>, Option<u64>));

/// Every reader, a malformed file at a 250-character path: the text names
/// `…/file:line:col:` (only the folder's middle shortened) and the JSON error
/// gives the whole path, the line and the column.
#[test]
fn locations_are_never_cut_on_long_paths() {
    let tmp = tempfile::tempdir().expect("tmp");
    let mut binary = vec![0u8; 84 + 50];
    binary[80] = 7; // claims 7 facets, holds 1
    let cases: [Case; 6] = [
        (
            "file.apt",
            b"UNITS/MM\nFEDRAT/100,MMPM\nGOTO/1,2\n",
            &["inspect"],
            (Some(3), Some(6)),
        ),
        (
            "file.nc",
            b"G21\nG90\nT1 M6\nS1000 M3\nG0 X0 Y0\nG1 X1..5 F100\n",
            &["inspect"],
            (Some(6), Some(4)),
        ),
        (
            "file.h",
            b"0 BEGIN PGM P MM\n1 TOOL CALL 1 Z S1000\n2 L X+1..5 R0 FMAX\n3 END PGM P MM\n",
            &["inspect"],
            (Some(3), None),
        ),
        (
            "file.stl",
            b"solid p\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 zz\n",
            &["inspect"],
            (Some(5), None),
        ),
        ("binary.stl", &binary, &["inspect"], (None, Some(80))),
        (
            "machine.toml",
            b"name = \"m\"\n[spindle]\nmax_rpm = \"fast\"\n",
            &["inspect", "--machine"],
            (Some(3), None),
        ),
    ];
    let ok_apt = tmp.path().join("ok.apt");
    std::fs::write(
        &ok_apt,
        "UNITS/MM\nCUTTER/10,5\nFEDRAT/100,MMPM\nGOTO/0,0,0\nGOTO/1,0,0\n",
    )
    .expect("write");
    for (name, bytes, cmd, (line, col)) in cases {
        let dir = deep_folder(tmp.path(), name, 250);
        let file = dir.join(name);
        let path = file.to_str().expect("utf8");
        assert_eq!(path.len(), 250, "{path}");
        std::fs::write(&file, bytes).expect("write");
        let mut args: Vec<&str> = cmd.to_vec();
        args.push(path);
        if name == "machine.toml" {
            args.push(ok_apt.to_str().expect("utf8"));
        }
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{name}");
        let err = String::from_utf8_lossy(&o.stderr);
        let first = err.lines().next().unwrap_or("");
        let place = match (line, col) {
            (Some(l), Some(c)) => format!("/{name}:{l}:{c}: "),
            (Some(l), None) => format!("/{name}:{l}:"),
            (None, Some(b)) => format!("/{name}:byte {b}: "),
            (None, None) => unreachable!(),
        };
        assert!(first.contains(&place), "{name}: {first}");
        // The folder's middle is what went, its start stays.
        let start = &path[..12];
        assert!(first.starts_with(&format!("error: {start}")), "{first}");
        assert!(first.contains('…'), "{name}: {first}");
        let folder = &first[..first.find(&place).expect("place")];
        // Paths up to 160 characters print whole (an editor jumps to them);
        // this 250-character one is cut to about that.
        assert!(folder.chars().count() < 170, "{name}: {first}");
        assert!(!first.contains("bytes]"), "{name}: {first}");

        args.push("--json");
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{name}");
        let v: serde_json::Value =
            serde_json::from_str(String::from_utf8_lossy(&o.stderr).trim()).expect("json error");
        let e = &v["error"];
        assert_eq!(e["file"], path, "{name}: {v}");
        if let Some(l) = line {
            assert_eq!(e["line"].as_u64(), Some(l), "{name}: {v}");
            assert!(e["col"].as_u64().is_some(), "{name}: {v}");
        }
        if let Some(c) = col {
            assert_eq!(e["col"].as_u64(), Some(c), "{name}: {v}");
        }
    }
}

fn demo(dir: &Path) -> PathBuf {
    let d = dir.join("demo");
    let o = run(&["demo", "-q", "-o", d.to_str().expect("utf8")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    d
}

/// `inspect` on the demo's own program speaks words: no debug spelling
/// (`Mm (Declared)`, `Ball`), no "unknown 1 moves", operations counted from 1
/// as `feed` counts them.
#[test]
fn inspect_speaks_words() {
    let tmp = tempfile::tempdir().expect("tmp");
    let d = demo(tmp.path());
    let o = run(&["inspect", d.join("finish.apt").to_str().expect("utf8")]);
    assert!(o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("units       mm (as the program declares)"),
        "{out}"
    );
    assert!(
        !out.contains("Declared") && !out.contains(" Ball "),
        "{out}"
    );
    assert!(!out.contains("unknown     1 moves"), "{out}");
    assert!(
        out.contains("1 move starts where the machine stands"),
        "{out}"
    );
    let ops: Vec<&str> = out
        .lines()
        .skip_while(|l| !l.starts_with("  operations"))
        .skip(1)
        .take_while(|l| l.starts_with("    "))
        .collect();
    assert_eq!(ops.len(), 1, "{out}");
    assert!(ops[0].trim_start().starts_with("1 "), "{out}");
}

/// A file that is not what its option asks for is named for what it is.
#[test]
fn wrong_kinds_of_file_are_named() {
    let tmp = tempfile::tempdir().expect("tmp");
    let d = demo(tmp.path());
    let apt = d.join("finish.apt");
    let apt = apt.to_str().expect("utf8");
    // An APT program as the part: not "header declares 741354549 facets".
    let o = run(&["gouge", apt, "--stl", apt]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("not an STL"), "{err}");
    assert!(err.contains("APT/CL or G-code"), "{err}");
    assert!(!err.contains("facets"), "{err}");
    // An HTML page as the program: not "raise --limit line-bytes".
    let html = d.join("report.html");
    let o = run(&["inspect", html.to_str().expect("utf8")]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("report.html:1:1: an HTML or XML document"),
        "{err}"
    );
    assert!(!err.contains("--limit"), "{err}");
}

/// `--vc -5` meets the range check, which names the option and its range,
/// not the parser's "use `-- -5`".
#[test]
fn negative_numbers_meet_the_range_check() {
    let tmp = tempfile::tempdir().expect("tmp");
    let d = demo(tmp.path());
    let apt = d.join("finish.apt");
    let stl = d.join("part.stl");
    for opt in ["--vc", "--fz", "--ap"] {
        let o = run(&[
            "directions",
            apt.to_str().expect("utf8"),
            "--stl",
            stl.to_str().expect("utf8"),
            opt,
            "-5",
        ]);
        assert_eq!(o.status.code(), Some(2), "{opt}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(opt), "{opt}: {err}");
        assert!(!err.contains("-- -5"), "{opt}: {err}");
    }
}

/// Run by [`skip_file_is_rewritten_per_run`] in a process of its own: one
/// skip. Does nothing in a plain `--ignored` run.
#[test]
#[ignore]
fn one_skip_probe() {
    if std::env::var_os("MILLPLAN_SKIP_PROBE").is_some_and(|v| v == "1") {
        shared_data::skipped("a probe of the skip file");
    }
}

/// The skip file counts the last run, not every run since the target was
/// made (it grew 86 → 172 across two runs).
#[test]
fn skip_file_is_rewritten_per_run() {
    let log = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(shared_data::SKIP_DIR)
        .join("millplan-ux.txt");
    for _ in 0..2 {
        let o = Command::new(std::env::current_exe().expect("exe"))
            .args(["--ignored", "--exact", "one_skip_probe"])
            .env("MILLPLAN_SKIP_PROBE", "1")
            .env_remove("MILLPLAN_REQUIRE_DATA")
            .output()
            .expect("runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let text = std::fs::read_to_string(&log).expect("skip file");
    let _ = std::fs::remove_file(&log);
    assert_eq!(text.lines().count(), 1, "{text}");
    assert!(
        text.contains("one_skip_probe: a probe of the skip file"),
        "{text}"
    );
}

/// `speed --ap 50` on a D10 ball read D_w = 10 everywhere: the ball's model
/// needs ap ≤ R, so the option is refused naming itself and the tool.
#[test]
fn speed_refuses_ap_beyond_the_ball_radius() {
    let tmp = tempfile::tempdir().expect("tmp");
    let d = demo(tmp.path());
    let out = tmp.path().join("out.apt");
    let speed = |ap: &str| {
        run(&[
            "speed",
            d.join("finish.apt").to_str().expect("utf8"),
            "--stl",
            d.join("part.stl").to_str().expect("utf8"),
            "--vc",
            "63",
            "--fz",
            "0.1",
            "--flutes",
            "2",
            "--ap",
            ap,
            "-o",
            out.to_str().expect("utf8"),
        ])
    };
    let o = speed("50");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--ap 50 mm is more than the radius 5 mm"),
        "{err}"
    );
    assert!(err.contains("T1, D10"), "{err}");
    assert!(!out.exists());
    let o = speed("5");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `gouge` counts operations from 1, as `inspect` and `feed` do.
#[test]
fn gouge_counts_operations_from_one() {
    let tmp = tempfile::tempdir().expect("tmp");
    let d = demo(tmp.path());
    let apt = tmp.path().join("plunge.apt");
    std::fs::write(
        &apt,
        "UNITS/MM\nCUTTER/10,5\nFEDRAT/100,MMPM\nGOTO/30,30,50\nGOTO/30,30,-5\n",
    )
    .expect("write");
    let o = run(&[
        "gouge",
        apt.to_str().expect("utf8"),
        "--stl",
        d.join("part.stl").to_str().expect("utf8"),
    ]);
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("(operation 1, move"), "{out}");
    assert!(!out.contains("(operation 0,"), "{out}");
}

/// Every command that reads a program, given a malformed G-code file at a
/// 250-character path (and valid other inputs from the demo), names
/// `…/file.nc:6:4:` in its text and the whole path, line and column in its
/// JSON error; so do the part's reader (as `--stl` and as `raster`'s
/// surface) and the machine file's reader.
#[test]
fn every_reader_keeps_the_location_on_long_paths() {
    let tmp = tempfile::tempdir().expect("tmp");
    let d = demo(tmp.path());
    let file = |n: &str| d.join(n).to_str().expect("utf8").to_string();
    let (stl, apt, machine) = (file("part.stl"), file("finish.apt"), file("machine.toml"));
    let out = |ext: &str| {
        let p = tmp.path().join(format!("out.{ext}"));
        p.to_str().expect("utf8").to_string()
    };
    let bad_nc = deep_folder(&tmp.path().join("nc"), "file.nc", 250).join("file.nc");
    std::fs::write(
        &bad_nc,
        "G21\nG90\nT1 M6\nS1000 M3\nG0 X0 Y0\nG1 X1..5 F100\n",
    )
    .expect("write");
    let bad_stl = deep_folder(&tmp.path().join("stl"), "file.stl", 250).join("file.stl");
    std::fs::write(
        &bad_stl,
        "solid p\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 zz\n",
    )
    .expect("write");
    let bad_machine = deep_folder(&tmp.path().join("m"), "machine.toml", 250).join("machine.toml");
    std::fs::write(
        &bad_machine,
        "name = \"m\"\n[spindle]\nmax_rpm = \"fast\"\n",
    )
    .expect("write");
    let nc = bad_nc.to_str().expect("utf8").to_string();
    let bstl = bad_stl.to_str().expect("utf8").to_string();
    let bm = bad_machine.to_str().expect("utf8").to_string();
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<String>>();
    let o_nc = out("nc");
    let five_axis = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/machine.toml")
        .to_str()
        .expect("utf8")
        .to_string();
    let cases: Vec<(Vec<String>, &str, &str)> = vec![
        (s(&["inspect", &nc]), &nc, "6:4"),
        (s(&["convert", &nc, "-o", &o_nc]), &nc, "6:4"),
        (
            s(&[
                "speed", &nc, "--stl", &stl, "--vc", "63", "--fz", "0.1", "--flutes", "2", "--ap",
                "0.3", "-o", &o_nc,
            ]),
            &nc,
            "6:4",
        ),
        (
            s(&[
                "feed",
                &nc,
                "--stock",
                "offset:0.5",
                "--stl",
                &stl,
                "--material",
                "al7075",
                "-o",
                &o_nc,
            ]),
            &nc,
            "6:4",
        ),
        (
            s(&[
                "force",
                &nc,
                "--stock",
                "offset:0.5",
                "--stl",
                &stl,
                "--material",
                "al7075",
            ]),
            &nc,
            "6:4",
        ),
        (
            s(&["simulate", &nc, "--stock", "offset:0.5", "--stl", &stl]),
            &nc,
            "6:4",
        ),
        (s(&["gouge", &nc, "--stl", &stl]), &nc, "6:4"),
        (s(&["reorder", &nc, "--stl", &stl, "-o", &o_nc]), &nc, "6:4"),
        (
            s(&[
                "orient",
                &nc,
                "--stl",
                &stl,
                "--material",
                "al7075",
                "-o",
                &o_nc,
            ]),
            &nc,
            "6:4",
        ),
        (
            s(&["post", &nc, "--machine", &five_axis, "-o", &o_nc]),
            &nc,
            "6:4",
        ),
        (
            s(&[
                "optimise",
                &nc,
                "--stl",
                &stl,
                "--stock",
                "offset:0.5",
                "--machine",
                &machine,
                "--material",
                "al7075",
                "-o",
                &o_nc,
            ]),
            &nc,
            "6:4",
        ),
        (s(&["directions", &nc, "--stl", &stl]), &nc, "6:4"),
        (s(&["gouge", &apt, "--stl", &bstl]), &bstl, "5:"),
        (
            s(&[
                "raster",
                "--stl",
                &bstl,
                "--tool",
                "ball:10",
                "--stepover",
                "1",
                "--step",
                "0.5",
                "-o",
                &o_nc,
            ]),
            &bstl,
            "5:",
        ),
        (
            s(&[
                "reorder",
                &apt,
                "--stl",
                &stl,
                "--machine",
                &bm,
                "-o",
                &o_nc,
            ]),
            &bm,
            "3:",
        ),
    ];
    for (args, path, place) in cases {
        let name = Path::new(path)
            .file_name()
            .and_then(|n| n.to_str())
            .expect("name");
        let o = bin().args(&args).output().expect("runs");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{}: {err}", args[0]);
        let want = format!("/{name}:{place}");
        let first = err.lines().find(|l| l.starts_with("error: ")).unwrap_or("");
        assert!(first.contains(&want), "{}: {err}", args[0]);
        assert!(
            first.contains('…') && !first.contains("bytes]"),
            "{}: {first}",
            args[0]
        );
        let o = bin().args(&args).arg("--json").output().expect("runs");
        assert_eq!(o.status.code(), Some(2), "{} --json", args[0]);
        let text = String::from_utf8_lossy(&o.stderr);
        let v: serde_json::Value = serde_json::from_str(text.trim())
            .unwrap_or_else(|e| panic!("{} --json: {e}: {text}", args[0]));
        let e = &v["error"];
        assert_eq!(e["file"], *path, "{}: {v}", args[0]);
        let line: u64 = place
            .split(':')
            .next()
            .and_then(|l| l.parse().ok())
            .expect("line");
        assert_eq!(e["line"].as_u64(), Some(line), "{}: {v}", args[0]);
        assert!(e["col"].as_u64().is_some(), "{}: {v}", args[0]);
    }
}

/// The subcommands listed under `Commands:` in a help text (not `help`).
fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter(|l| !l.starts_with("   "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect()
}

/// What a user cannot look up: references to papers, theses, spec files and
/// their sections, and issue numbers. They belong in docs/.
fn unreadable_references(help: &str) -> Vec<String> {
    let mut found = Vec::new();
    let words: Vec<&str> = help.split_whitespace().collect();
    for (i, w) in words.iter().enumerate() {
        let lower = w.to_lowercase();
        let next_is_number = words.get(i + 1).is_some_and(|n| {
            n.trim_matches(|c: char| !c.is_ascii_alphanumeric())
                .parse::<u32>()
                .is_ok()
        });
        let bad = lower.contains("thesis")
            || lower.contains('§')
            || lower.contains("process-models")
            || lower.contains("working-diameter.md")
            || lower.contains("kinematics-access")
            || w.trim_start_matches('(') == "spec"
            || ((lower.trim_start_matches('(') == "paper"
                || lower.trim_start_matches('(') == "issue")
                && next_is_number);
        if bad {
            found.push(words[i..(i + 3).min(words.len())].join(" "));
        }
    }
    found
}

#[test]
fn unreadable_references_are_found() {
    assert_eq!(
        unreadable_references("as (paper 000, thesis 3) says").len(),
        2
    );
    assert_eq!(
        unreadable_references("spec process-models.md §2.3, issue 21").len(),
        4
    );
    assert!(unreadable_references("--stock SPEC --material M").is_empty());
    assert!(unreadable_references("--method paper: the published search; 3 issues").is_empty());
}

/// No `--help` of any command or subcommand cites a paper by number, a
/// thesis, a spec file or section, or an issue: help explains in words.
#[test]
fn help_texts_cite_nothing_a_user_cannot_look_up() {
    let mut todo: Vec<Vec<String>> = vec![Vec::new()];
    let mut seen = 0;
    let mut bad = Vec::new();
    while let Some(path) = todo.pop() {
        let o = bin().args(&path).arg("--help").output().expect("runs");
        assert!(o.status.success(), "{path:?}");
        let help = String::from_utf8_lossy(&o.stdout).into_owned();
        seen += 1;
        for r in unreadable_references(&help) {
            bad.push(format!("{}: {r}", path.join(" ")));
        }
        for c in subcommands(&help) {
            let mut p = path.clone();
            p.push(c);
            todo.push(p);
        }
    }
    assert!(seen > 25, "{seen} help texts");
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// `feed` (or `force`) on `program` with a box stock around its cutting
/// moves, a ball of diameter `d`, and `extra` options.
fn feed_like(cmd: &str, program: &Path, d: &str, extra: &[&str]) -> Output {
    let mut args = vec![
        cmd,
        program.to_str().expect("utf8"),
        "--stock",
        "box:auto",
        "--tool",
        d,
        "--material",
        "al7075",
        "--resolution",
        "0.5",
        "--json",
        "-q",
    ];
    args.extend_from_slice(extra);
    run(&args)
}

/// A program without S words (as NX writes its CLSF) is no silent no-op:
/// `feed` and `force` exit 2 naming the missing spindle speed and the
/// option that supplies it, and write nothing.
fn refuses_without_s(program: &Path, tool: &str) {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("out.nc");
    let o_out = ["-o", out.to_str().expect("utf8")];
    for cmd in ["feed", "force"] {
        let extra: &[&str] = if cmd == "feed" { &o_out } else { &[] };
        let o = feed_like(cmd, program, tool, extra);
        assert_eq!(o.status.code(), Some(2), "{cmd}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("spindle"), "{cmd}: {err}");
        assert!(err.contains("--spindle RPM"), "{cmd}: {err}");
        assert!(!out.exists(), "{cmd}");
    }
}

/// [`refuses_without_s`], and with `--spindle` `feed` schedules the feeds.
fn refuses_without_s_and_schedules_with_spindle(program: &Path, tool: &str) {
    refuses_without_s(program, tool);
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("out.nc");
    let o_out = ["-o", out.to_str().expect("utf8")];
    let o = feed_like(
        "feed",
        program,
        tool,
        &[&o_out[..], &["--spindle", "8000"]].concat(),
    );
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert!(j["blocks"].as_u64().is_some_and(|b| b > 0), "{j}");
    assert!(
        j["max_before"]["fxy"].as_f64().is_some_and(|f| f > 0.0),
        "{j}"
    );
    assert!(out.exists());
    let o = feed_like("force", program, tool, &["--spindle", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--spindle"));
}

#[test]
fn feed_without_s_names_the_spindle_option_on_a_small_program() {
    let dir = tempfile::tempdir().expect("tmp");
    let p = dir.path().join("no_s.nc");
    std::fs::write(
        &p,
        "%\nO0031\nG21 G90 G17 G94\nT1 M6\nM3\nG0 X-20. Y0. Z5.\nG1 Z-3. F500.\nG1 X60. F1120.\nG1 Y10.\nG1 X-20.\nG0 Z5.\nM30\n%\n",
    )
    .expect("write");
    refuses_without_s_and_schedules_with_spindle(&p, "ball:10");
}

#[test]
fn feed_without_s_names_the_spindle_option_on_nx_clsf() {
    let Some(p) = shared_data::file("nx-clsf-ballend-nurbs/nurbs.clsf") else {
        return;
    };
    // Scheduling is shown on the small program: in the box around NX's
    // whole path the D30 ball is buried up to its shank, and its 9,000
    // blocks take minutes of force integrals in a test build.
    refuses_without_s(&p, "ball:30");
}

/// `millplan completions bash | head -1` is a normal end: exit 0 and no
/// "Broken pipe" (the reader closed the pipe on purpose; it did exit 1).
#[test]
fn completions_into_a_closed_pipe_end_quietly() {
    let out = Command::new("bash")
        .arg("-c")
        .arg("\"$B\" completions bash | head -1; echo \"rc=${PIPESTATUS[0]}\"")
        .env("B", env!("CARGO_BIN_EXE_millplan"))
        .output()
        .expect("bash runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.starts_with("_millplan()"), "{text}");
    assert!(text.contains("rc=0"), "{text}");
    assert!(!String::from_utf8_lossy(&out.stderr).contains("Broken pipe"));
}

/// The demo's part is an open surface by design; the demo says so once,
/// so the open-mesh note of the later commands is expected, not a fault.
#[test]
fn demo_states_its_open_surface_once() {
    let tmp = tempfile::tempdir().expect("tmp");
    let d = tmp.path().join("demo");
    let o = run(&["demo", "-o", d.to_str().expect("utf8")]);
    assert!(o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(out.matches("open surface by design").count(), 1, "{out}");
    assert!(out.contains("note[open-mesh]"), "{out}");
}
