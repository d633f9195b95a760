//! `--json` on every command: a run that succeeds prints one JSON document on
//! standard output, and one that fails prints `{"error": {"file", "line",
//! "col", "code", "exit", "message"}}` on standard error, for every command
//! `millplan --help` lists.

use std::path::Path;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

/// The commands `millplan --help` lists.
fn listed_commands() -> Vec<String> {
    let o = bin().arg("--help").output().expect("runs");
    let help = String::from_utf8_lossy(&o.stdout).to_string();
    let section = help
        .split("Commands:")
        .nth(1)
        .and_then(|s| s.split("\n\n").next())
        .expect("a Commands section")
        .to_string();
    section
        .lines()
        .filter(|l| l.starts_with("  ") && !l.starts_with("    "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|c| c != "help")
        .collect()
}

/// A five-axis machine file (A/C table) in `tmp`, its path.
fn machine5(tmp: &Path) -> String {
    let m = tmp.join("five.toml");
    std::fs::write(
        &m,
        "[spindle]\nmin = 100.0\nmax = 20000.0\naccel = 5000.0\n[feed]\nmax = 20000.0\n[kinematics]\nkind = \"table-ac\"\n",
    )
    .expect("write");
    m.display().to_string()
}

/// A successful run and a failing one of a command, both with --json.
struct Case {
    command: &'static str,
    ok: Vec<String>,
    fails: Vec<String>,
}

fn cases(d: &Path, tmp: &Path) -> Vec<Case> {
    let p = |n: &str| d.join(n).display().to_string();
    let t = |n: &str| tmp.join(n).display().to_string();
    let v = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    let (stl, apt, missing) = (p("part.stl"), p("finish.apt"), t("missing.apt"));
    let db = t("tools.db");
    vec![
        Case {
            command: "inspect",
            ok: v(&["inspect", "--json", &apt]),
            fails: v(&["inspect", "--json", &missing]),
        },
        Case {
            command: "convert",
            ok: v(&["convert", "--json", &apt, "--to", "fanuc", "-o", &t("c.nc")]),
            fails: v(&["convert", "--json", &apt, "-o", "-"]),
        },
        Case {
            command: "demo",
            ok: v(&["demo", "--json", "-o", &t("demo2")]),
            fails: v(&["demo", "--json", "-o", &stl]),
        },
        Case {
            command: "wd",
            ok: v(&[
                "wd", "--json", "--d", "10", "--ap", "0.3", "--ae", "0.25", "--alpha", "20",
                "--af", "45", "--side", "left", "--vc", "63",
            ]),
            fails: v(&[
                "wd", "--json", "--d", "-1", "--ap", "0.3", "--ae", "0.25", "--alpha", "20",
                "--af", "45", "--side", "left",
            ]),
        },
        Case {
            command: "wd-sweep",
            ok: v(&[
                "wd-sweep",
                "--json",
                "--d",
                "10",
                "--ap",
                "0.3",
                "--alpha",
                "0",
                "--af-step",
                "90",
                "-o",
                &t("sweep"),
            ]),
            fails: v(&["wd-sweep", "--json", "--af-step", "0", "-o", &t("sweep2")]),
        },
        Case {
            command: "speed",
            ok: v(&[
                "speed",
                "--json",
                "--vc",
                "63",
                "--fz",
                "0.1",
                "--ap",
                "0.3",
                "--stl",
                &stl,
                &apt,
                "-o",
                &t("vc.nc"),
            ]),
            fails: v(&[
                "speed",
                "--json",
                "--stl",
                &stl,
                &missing,
                "-o",
                &t("vc2.nc"),
            ]),
        },
        Case {
            command: "directions",
            ok: v(&[
                "directions",
                "--json",
                "--stl",
                &stl,
                &p("raster_0.apt"),
                &p("raster_90.apt"),
            ]),
            fails: v(&["directions", "--json", "--stl", &stl, &missing]),
        },
        Case {
            command: "gouge",
            ok: v(&["gouge", "--json", "--stl", &stl, &apt]),
            fails: v(&["gouge", "--json", "--stl", &missing, &apt]),
        },
        Case {
            command: "raster",
            ok: v(&[
                "raster",
                "--json",
                "--stl",
                &stl,
                "--tool",
                "ball:10",
                "--stepover",
                "3",
                "--step",
                "1",
                "-o",
                &t("r.apt"),
            ]),
            fails: v(&[
                "raster",
                "--json",
                "--stl",
                &stl,
                "--tool",
                "ball:10",
                "--stepover",
                "3",
                "--step",
                "1e-9",
                "-o",
                &t("r2.apt"),
            ]),
        },
        Case {
            command: "orient",
            ok: v(&[
                "orient",
                "--json",
                "--stl",
                &stl,
                &apt,
                "--material",
                "al7075",
                "--stock",
                "offset:0.5",
                "--samples",
                "8",
                "-o",
                &t("or.apt"),
            ]),
            fails: v(&[
                "orient",
                "--json",
                "--stl",
                &stl,
                &apt,
                "--material",
                "al7075",
                "--stock",
                "box:1,2,3",
                "-o",
                &t("or2.apt"),
            ]),
        },
        Case {
            command: "reorder",
            ok: v(&[
                "reorder",
                "--json",
                "--method",
                "paper",
                "--stl",
                &stl,
                &apt,
                "-o",
                &t("re.apt"),
            ]),
            fails: v(&[
                "reorder",
                "--json",
                "--stl",
                &stl,
                &missing,
                "-o",
                &t("re2.apt"),
            ]),
        },
        Case {
            command: "setup",
            ok: v(&["setup", "--json", "--type", "ca", "--stl", &stl]),
            fails: v(&["setup", "--json", "--stl", &stl]),
        },
        Case {
            command: "tool",
            ok: v(&[
                "tool", "--json", "--db", &db, "pz", "--insl", "14", "--tp", "1",
            ]),
            fails: v(&["tool", "--json", "--db", &db, "show", "99"]),
        },
        Case {
            command: "thread",
            ok: v(&[
                "thread", "check", "M20x1", "--class", "6H", "--d2", "19.43", "--json",
            ]),
            fails: v(&[
                "thread", "check", "M20x1", "--class", "9Z", "--d2", "19.43", "--json",
            ]),
        },
        Case {
            command: "completions",
            ok: v(&["completions", "--json", "fish"]),
            fails: v(&["completions", "--json", "powershell"]),
        },
        Case {
            command: "man",
            ok: v(&["man", "--json", "-o", &t("man")]),
            fails: v(&["man", "--json", "-o", &stl]),
        },
        Case {
            command: "simulate",
            ok: v(&[
                "simulate",
                "--json",
                &apt,
                "--stock",
                "box:auto",
                "--resolution",
                "0.5",
            ]),
            fails: v(&["simulate", "--json", &apt, "--stock", "box:1,2,3"]),
        },
        Case {
            command: "cut",
            ok: v(&[
                "cut",
                "--json",
                "--tool",
                "ball:10",
                "--fz",
                "0.1",
                "--ap",
                "1",
                "--ae",
                "1",
                "--n",
                "6000",
                "--material",
                "al7075",
            ]),
            fails: v(&[
                "cut",
                "--json",
                "--tool",
                "ball:10",
                "--fz",
                "-0.1",
                "--ap",
                "1",
                "--slot",
                "--n",
                "6000",
                "--material",
                "al7075",
            ]),
        },
        Case {
            command: "lobes",
            ok: v(&[
                "lobes", "--json", "--fn", "922", "--k", "1.34e6", "--zeta", "0.011", "--flutes",
                "2", "--kt", "600", "--kr", "0.3", "--slot",
            ]),
            fails: v(&[
                "lobes", "--json", "--fn", "922", "--k", "1e6", "--zeta", "0", "--flutes", "2",
                "--kt", "600", "--kr", "0.3", "--slot",
            ]),
        },
        Case {
            command: "force",
            ok: v(&["force", "materials", "--json"]),
            fails: v(&[
                "force",
                "--json",
                &missing,
                "--stock",
                "box:auto",
                "--material",
                "al7075",
            ]),
        },
        Case {
            command: "feed",
            ok: v(&[
                "feed",
                "--json",
                &apt,
                "--stock",
                "offset:0.3",
                "--stl",
                &stl,
                "--material",
                "al7075",
                "--resolution",
                "0.5",
                "-o",
                &t("fed.apt"),
            ]),
            fails: v(&[
                "feed",
                "--json",
                &apt,
                "--stock",
                "offset:0.3",
                "--material",
                "al7075",
                "-o",
                &t("fed2.apt"),
            ]),
        },
        Case {
            command: "optimise",
            ok: v(&[
                "optimise",
                "--json",
                &apt,
                "--stl",
                &stl,
                "--stock",
                "offset:0.3",
                "--material",
                "al7075",
                "--passes",
                "feed",
                "--resolution",
                "0.5",
                "--limit",
                "fxy=120",
                "-o",
                &t("opt.apt"),
            ]),
            fails: v(&[
                "optimise",
                "--json",
                &t("no-such-program.apt"),
                "-o",
                &t("opt2.apt"),
            ]),
        },
        Case {
            command: "post",
            ok: v(&[
                "post",
                "--json",
                &apt,
                "--machine",
                &machine5(tmp),
                "--to",
                "fanuc",
                "-o",
                &t("posted.nc"),
            ]),
            fails: v(&[
                "post",
                "--json",
                &apt,
                "--machine",
                &machine5(tmp),
                "-o",
                "-",
            ]),
        },
        Case {
            command: "robot",
            ok: v(&[
                "robot",
                "deflect",
                "--joints",
                "0,-90,90,0,30,0",
                "--force",
                "0,1000,0",
                "--json",
            ]),
            fails: v(&[
                "robot",
                "deflect",
                "--joints",
                "0,-90,90,0,30",
                "--force",
                "0,1000,0",
                "--json",
            ]),
        },
        Case {
            command: "explain",
            ok: v(&["explain", "--json"]),
            fails: v(&["explain", "--json", "no-such-code"]),
        },
    ]
}

#[test]
fn every_command_prints_json_and_json_errors() {
    let tmp = tempfile::tempdir().expect("tmp");
    let demo = tmp.path().join("demo");
    let o = bin()
        .args(["demo", "-o"])
        .arg(&demo)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cases = cases(&demo, tmp.path());
    let mut listed = listed_commands();
    listed.sort();
    let mut covered: Vec<String> = cases.iter().map(|c| c.command.to_string()).collect();
    covered.sort();
    assert_eq!(listed, covered, "every listed command has a JSON case");
    for c in &cases {
        let o = bin().args(&c.ok).output().expect("runs");
        assert!(
            o.status.success(),
            "{:?}: {}",
            c.ok,
            String::from_utf8_lossy(&o.stderr)
        );
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap_or_else(|e| {
            panic!(
                "{:?}: stdout is not JSON ({e}): {}",
                c.ok,
                String::from_utf8_lossy(&o.stdout)
            )
        });
        let o = bin().args(&c.fails).output().expect("runs");
        assert_eq!(o.status.code(), Some(2), "{:?}", c.fails);
        let e: serde_json::Value = serde_json::from_slice(&o.stderr).unwrap_or_else(|e| {
            panic!(
                "{:?}: stderr is not JSON ({e}): {}",
                c.fails,
                String::from_utf8_lossy(&o.stderr)
            )
        });
        let err = &e["error"];
        for k in ["file", "line", "col", "code", "exit", "message"] {
            assert!(err.get(k).is_some(), "{:?}: no `{k}` in {e}", c.fails);
        }
        assert!(
            err["message"].as_str().is_some_and(|m| !m.is_empty()),
            "{e}"
        );
        assert_eq!(err["exit"], 2, "{e}");
    }
}

/// An argument clap refuses is a JSON error too, coded `usage`; a program's
/// syntax error names its file, line and column.
#[test]
fn usage_and_syntax_errors_are_json() {
    let o = bin()
        .args(["raster", "--json", "--stl", "x.stl"])
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    let e: serde_json::Value = serde_json::from_slice(&o.stderr).expect("json");
    assert_eq!(e["error"]["code"], "usage", "{e}");
    assert!(
        e["error"]["message"]
            .as_str()
            .is_some_and(|m| m.contains("--tool")),
        "{e}"
    );
    let tmp = tempfile::tempdir().expect("tmp");
    let bad = tmp.path().join("bad.nc");
    std::fs::write(&bad, "G21 G90\nG1 X1 Q@@\n").expect("write");
    let o = bin()
        .args(["inspect", "--json"])
        .arg(&bad)
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    let e: serde_json::Value = serde_json::from_slice(&o.stderr).expect("json");
    assert_eq!(e["error"]["file"], bad.display().to_string(), "{e}");
    assert_eq!(
        (e["error"]["line"].as_u64(), e["error"]["col"].as_u64()),
        (Some(2), Some(8)),
        "{e}"
    );
    assert_eq!(e["error"]["code"], "bad-input");
    // Without --json the message stays text.
    let o = bin().arg("inspect").arg(&bad).output().expect("runs");
    assert!(String::from_utf8_lossy(&o.stderr).starts_with("error: "));
}
