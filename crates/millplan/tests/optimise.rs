//! `millplan optimise` end to end: the demo part, a planted fault, the
//! passes one by one with the existing commands, and the real CAM samples
//! of `../shared/data` (skipped, and said so, when they are not there).

#[path = "../../millplan-nc/tests/shared_data/mod.rs"]
mod shared_data;

#[path = "support/plate.rs"]
mod support;
use support::plate;

use millplan_nc::equiv::{compare, Tolerance};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf8")
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("runs")
}

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
        panic!(
            "{e}: {}\n{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        )
    })
}

/// `millplan demo` into `dir/demo`: its part, finishing raster and machine.
fn demo(dir: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let d = dir.join("demo");
    assert!(run(&["demo", "-o", s(&d), "-q"]).status.success());
    (
        d.join("part.stl"),
        d.join("finish.apt"),
        d.join("machine.toml"),
    )
}

fn read(p: &Path) -> millplan_nc::Program {
    let text = std::fs::read_to_string(p).expect("written");
    millplan_nc::parse_program(&text, millplan_nc::ReadOptions::default())
        .expect("reads")
        .program
}

fn setting(j: &serde_json::Value, name: &str) -> String {
    let v = j["settings"]
        .as_array()
        .expect("settings")
        .iter()
        .find(|x| x["name"] == name)
        .unwrap_or_else(|| panic!("setting {name}"));
    v["value"]
        .as_str()
        .expect("value")
        .split(' ')
        .next()
        .expect("number")
        .to_string()
}

fn pass<'a>(j: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    j["passes"]
        .as_array()
        .expect("passes")
        .iter()
        .find(|p| p["name"] == name)
        .unwrap_or_else(|| panic!("pass {name}"))
}

/// Issue 31, done-when 1: on the demo part `optimise` writes a program that
/// passes its own verification, runs faster than the input and meets every
/// limit; the JSON keys scripts rely on are there.
#[test]
fn demo_is_optimised_verified_and_faster() {
    let dir = tempfile::tempdir().expect("tmp");
    let (stl, apt, machine) = demo(dir.path());
    let out = dir.path().join("opt.nc");
    let report = dir.path().join("opt.html");
    let o = run(&[
        "optimise",
        s(&apt),
        "--stl",
        s(&stl),
        "--stock",
        "offset:0.3",
        "--machine",
        s(&machine),
        "--material",
        "al7075",
        "-o",
        s(&out),
        "--report",
        s(&report),
        "--json",
        "--limit",
        "fxy=120",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    assert_eq!(j["verdict"], "improved");
    let (t0, t1) = (
        j["time_before_s"].as_f64().expect("t0"),
        j["time_after_s"].as_f64().expect("t1"),
    );
    assert!(t1 < t0, "{t0} → {t1}");
    for c in j["checks"].as_array().expect("checks") {
        assert_eq!(c["ok"], true, "{c}");
    }
    let names: Vec<&str> = j["checks"]
        .as_array()
        .expect("c")
        .iter()
        .map(|c| c["name"].as_str().expect("n"))
        .collect();
    for n in [
        "read-back",
        "machine",
        "tip",
        "ir",
        "stock",
        "loads",
        "gouge",
    ] {
        assert!(names.contains(&n), "{n} in {names:?}");
    }
    assert_eq!(pass(&j, "speed")["ran"], true);
    assert_eq!(pass(&j, "feed")["ran"], true);
    assert_eq!(pass(&j, "post")["ran"], false);
    assert!(pass(&j, "post")["reason"]
        .as_str()
        .expect("r")
        .contains("three-axis"));
    // The limit given binds: F_xy 170 N at the input's feeds, at most 120 N after.
    assert!(j["max_before"]["fxy"].as_f64().expect("fxy") > 120.0);
    assert!(j["max_after"]["fxy"].as_f64().expect("fxy") <= 120.0 * 1.005);
    for k in ["fxy", "torque", "power", "deflection"] {
        assert!(
            j["max_before"][k].is_number() && j["max_after"][k].is_number(),
            "{k}"
        );
    }
    assert!(j["vc_off_after"].as_f64().expect("vc") < j["vc_off_before"].as_f64().expect("vc"));
    let html = std::fs::read_to_string(&report).expect("report");
    assert!(
        html.contains("Improved: cycle time") && html.contains("<svg"),
        "report"
    );
    assert!(read(&out).move_count() > 1000);
}

/// The demo's constant-cutting-speed program (written at S ≈ 4200) with
/// `speed` raising its plunge to S ≈ 16900: at the smallest feed per tooth
/// the plunge still drew 244.6 W against the 206.4 W learned from the
/// input (the edge forces do not shrink with the chip; power grows with the
/// speed), and the check refused line 12. The feed pass now lowers that
/// block's spindle speed by the share that meets the limit: every check
/// passes, the power stays under what the input drew, and the run is faster.
#[test]
fn demo_constant_vc_program_meets_the_power_learned_from_the_input() {
    let dir = tempfile::tempdir().expect("tmp");
    let (stl, _, machine) = demo(dir.path());
    let nc = dir.path().join("demo").join("finish_constant_vc_fanuc.nc");
    let out = dir.path().join("opt.nc");
    let o = run(&[
        "optimise",
        s(&nc),
        "--stl",
        s(&stl),
        "--stock",
        "offset:0.5",
        "--material",
        "al7075",
        "--tool",
        "ball:10",
        "--passes",
        "speed,feed",
        "--resolution",
        "0.5",
        "--machine",
        s(&machine),
        "-o",
        s(&out),
        "--json",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    assert_eq!(j["verdict"], "improved", "{j}");
    for c in j["checks"].as_array().expect("checks") {
        assert_eq!(c["ok"], true, "{c}");
    }
    let power = |k: &str| j[k]["power"].as_f64().expect("power");
    assert!(
        power("max_after") <= power("max_before") * 1.005,
        "{} W after, {} W learned",
        power("max_after"),
        power("max_before")
    );
    assert!(j["time_after_s"].as_f64() < j["time_before_s"].as_f64());
    let feed = pass(&j, "feed")["reason"]
        .as_str()
        .expect("reason")
        .to_string();
    assert!(feed.contains("power-speed"), "{feed}");
    // The plunge (line 12) runs slower than the speed pass set it, and
    // still at the smallest feed per tooth (0.01 mm, 2 flutes).
    let p = read(&out);
    let plunge = p.moves().find(|m| m.is_cutting()).expect("a cut");
    let next = p.moves().filter(|m| m.is_cutting()).nth(1).expect("cuts");
    assert!(
        plunge.spindle < next.spindle * 0.95,
        "{} {}",
        plunge.spindle,
        next.spindle
    );
    let fz = plunge.feed / (plunge.spindle * 2.0);
    assert!((fz - 0.01).abs() < 1e-4, "fz {fz}");
}

/// A pass whose input is missing says why and the run goes on.
/// The default list skips a pass whose input is missing and says why; a
/// pass the user named in --passes is refused instead (exit 2, before any
/// work, nothing written), unless the program has nothing for it.
#[test]
fn a_pass_without_its_input_prints_the_reason() {
    let dir = tempfile::tempdir().expect("tmp");
    let (_, apt, machine) = demo(dir.path());
    let out = dir.path().join("o.nc");
    let o = run(&["optimise", s(&apt), "--machine", s(&machine), "-o", s(&out)]);
    let (err, text) = (
        String::from_utf8_lossy(&o.stderr),
        String::from_utf8_lossy(&o.stdout),
    );
    assert_eq!(o.status.code(), Some(0), "{err}");
    // Said once, in the table of passes (a user trial saw each twice, as
    // a note on standard error as well).
    for said in [
        "speed    skipped  no part (--stl)",
        "feed     skipped  no stock (--stock)",
    ] {
        assert_eq!(text.matches(said).count(), 1, "{text}");
    }
    assert!(!err.contains("skipped"), "{err}");
    assert!(out.exists());
    std::fs::remove_file(&out).expect("rm");
    let named = |list: &str| {
        let args = [
            "optimise",
            s(&apt),
            "--machine",
            s(&machine),
            "--passes",
            list,
        ];
        run(&[&args[..], &["-o", s(&out)]].concat())
    };
    let o = named("post,feed");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--passes names feed, which cannot run: no stock (--stock)"),
        "{err}"
    );
    assert!(!out.exists(), "nothing is written");
    // Post has nothing to do on a three-axis program: skipped, not refused.
    let o = named("post");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("post     skipped  a three-axis program"),
        "{text}"
    );
    let o = run(&["optimise", s(&apt), "--passes", "speed,warp", "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown pass `warp`"));
    let o = run(&["optimise", "--list-passes"]);
    let t = String::from_utf8_lossy(&o.stdout);
    for p in ["speed", "reorder", "orient", "feed", "post"] {
        assert!(t.contains(p), "{t}");
    }
}

/// When the written program cannot be made at all (an error, not a check's
/// refusal), the passes skipped are still said, before the error.
#[test]
fn skipped_passes_are_said_before_an_error_in_writing() {
    let dir = tempfile::tempdir().expect("tmp");
    let src = dir.path().join("r.nc");
    let text = "G21 G90 G94\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z0 F300\nG1 X10 A10.\nM30\n";
    std::fs::write(&src, text).expect("writes");
    let out = dir.path().join("o.apt");
    let o = run(&["optimise", s(&src), "--tool", "ball:10", "-o", s(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let (note, error) = (err.find("pass speed skipped"), err.find("r.nc:6:"));
    assert!(note.is_some() && note < error, "{err}");
    assert!(!out.exists(), "nothing is written");
}

/// A user trial: with a stock no cutting move meets (given in the wrong
/// place), every block read as air and `optimise` raised the feeds to the
/// air feed, exit 0 and Green, where `feed` warned. The load passes now do
/// not run on such a stock: skipped with the reason in the default list
/// (the feeds written are the input's), refused when named (exit 2,
/// nothing written).
#[test]
fn a_stock_no_cut_meets_keeps_the_feeds() {
    let dir = tempfile::tempdir().expect("tmp");
    let (stl, apt, machine) = demo(dir.path());
    let out = dir.path().join("o.nc");
    let far = "box:500,500,0,600,600,50";
    let common = [
        "optimise",
        s(&apt),
        "--stl",
        s(&stl),
        "--machine",
        s(&machine),
        "--stock",
        far,
        "--material",
        "al7075",
    ];
    let o = run(&[&common[..], &["-o", s(&out), "--passes", "feed,speed"]].concat());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(
            "--passes names feed, which cannot run: no cutting move of the program meets the stock"
        ),
        "{err}"
    );
    assert!(!out.exists(), "nothing is written");
    let written = |more: &[&str]| {
        let o = run(&[&common[..], &["-o", s(&out)], more].concat());
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(0), "{err}");
        o
    };
    written(&["--passes", "speed,reorder"]);
    let speed_only = read(&out);
    let j = json(&written(&["--json"]));
    assert_eq!(j["level"], "amber", "{j}");
    let warned = j["warnings"].as_array().expect("warnings");
    assert!(
        warned.iter().any(|w| w
            .as_str()
            .is_some_and(|w| w.starts_with("pass feed skipped: no cutting move"))),
        "{j}"
    );
    let feed = pass(&j, "feed");
    assert!(
        feed.to_string()
            .contains("no cutting move of the program meets the stock"),
        "{feed}"
    );
    // No feed but the speed pass's own: the default list wrote what speed
    // and reorder alone do, move for move.
    let all = read(&out);
    let feeds = |p: &millplan_nc::Program| -> Vec<u64> {
        p.moves()
            .filter(|m| m.is_cutting())
            .map(|m| m.feed.to_bits())
            .collect()
    };
    assert_eq!(feeds(&all), feeds(&speed_only));
}

/// A user trial: the default passes on a G-code program, its ball given
/// with `--tool ball:10`, stopped at reorder (exit 2: "no 3-axis ball-end
/// operation to reorder") though the list says a pass the program has
/// nothing for is skipped. reorder now takes the ball `--tool` gives, and a
/// program of arcs, which it leaves alone, skips it with the reason.
#[test]
fn reorder_takes_the_ball_of_tool_and_skips_arcs() {
    let dir = tempfile::tempdir().expect("tmp");
    let (stl, _, _) = demo(dir.path());
    let fanuc = dir.path().join("demo").join("finish_fanuc.nc");
    let out = dir.path().join("o.nc");
    let opt = |nc: &Path| {
        let args = [
            "optimise",
            s(nc),
            "--stl",
            s(&stl),
            "--tool",
            "ball:10",
            "--json",
        ];
        let o = run(&[&args[..], &["-o", s(&out)]].concat());
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        json(&o)
    };
    let j = opt(&fanuc);
    assert_eq!(pass(&j, "reorder")["ran"], true, "{}", pass(&j, "reorder"));
    let arcs = dir.path().join("arcs.nc");
    let text = "%\nO0001\nG21 G17 G90 G94\nT1 M6\nS6000 M3\nG0 X10. Y10. Z60.\n\
                G1 Z40. F600.\nG2 X30. Y10. I10. J0.\nG3 X50. Y10. I10. J0.\nG0 Z60.\nM30\n%\n";
    std::fs::write(&arcs, text).expect("written");
    let j = opt(&arcs);
    let reorder = pass(&j, "reorder");
    assert_eq!(reorder["ran"], false, "{reorder}");
    assert!(
        reorder["reason"]
            .as_str()
            .is_some_and(|r| r.contains("straight moves")),
        "{reorder}"
    );
}

/// A rapid through the stock is refused whether or not the input had it:
/// exit 3 naming the check and the line, nothing written; --force writes.
#[test]
fn a_rapid_through_the_stock_is_refused() {
    let dir = tempfile::tempdir().expect("tmp");
    let nc = dir.path().join("p.nc");
    std::fs::write(
        &nc,
        "%\nO1\nG21 G90 G17\nT1 M6\nS8000 M3\nG0 X-20 Y10 Z5\nG1 Z-1 F500\nG1 X50 F1000\nG0 X120\nG0 Z5\nM30\n%\n",
    )
    .expect("write");
    let out = dir.path().join("o.nc");
    let args = [
        "optimise",
        s(&nc),
        "--tool",
        "flat:10",
        "--stock",
        "box:0,0,-10,100,20,0",
        "--material",
        "al7075",
        "-o",
        s(&out),
    ];
    let o = run(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains(":9: check stock failed: rapid through material"),
        "{err}"
    );
    assert!(!out.exists(), "nothing written");
    let o = bin().args(args).arg("--force").output().expect("runs");
    assert_eq!(o.status.code(), Some(3));
    assert!(out.exists(), "written with --force");
}

/// Issue 31: running the passes one by one with the existing commands
/// (`speed`, then `feed`) gives the same program as `optimise`: positions,
/// S and F to the written precision.
#[test]
fn passes_one_by_one_give_the_same_program() {
    let dir = tempfile::tempdir().expect("tmp");
    let (stl, apt, machine) = demo(dir.path());
    let opt = dir.path().join("opt.nc");
    // The same limits for both runs: without them optimise would learn its
    // own from the input's loads, which feed alone does not. The stock at
    // 0.25 mm: the test is about the two routes agreeing, not the loads,
    // and fewer samples along the moves and a sixth of the stock's columns.
    let common = [
        "--stl",
        s(&stl),
        "--machine",
        s(&machine),
        "--limit",
        "fxy=150,torque=1500,power=2000",
    ];
    let o = bin()
        .args([
            "optimise",
            s(&apt),
            "--stock",
            "offset:0.3",
            "--resolution",
            "0.25",
            "--material",
            "al7075",
            "--passes",
            "speed,feed",
            "-o",
            s(&opt),
            "--json",
        ])
        .args(common)
        .output()
        .expect("runs");
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    let (vc, ap, flutes) = (setting(&j, "vc"), setting(&j, "ap"), setting(&j, "flutes"));
    let (fz_min, fz_max) = (setting(&j, "fz_min"), setting(&j, "fz_max"));
    let sp = dir.path().join("speed.nc");
    let first = read(&apt);
    let m = first
        .moves()
        .find(|m| m.is_cutting() && m.spindle > 0.0)
        .expect("cut");
    let fz =
        (m.feed / (m.spindle * 2.0)).clamp(fz_min.parse().expect("f"), fz_max.parse().expect("f"));
    let o = bin()
        .args([
            "speed",
            s(&apt),
            "--vc",
            &vc,
            "--fz",
            &fz.to_string(),
            "--flutes",
            &flutes,
            "--ap",
            &ap,
            "-o",
            s(&sp),
            "-q",
        ])
        .args(common)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let fd = dir.path().join("feed.nc");
    let o = bin()
        .args([
            "feed",
            s(&sp),
            "--stock",
            "offset:0.3",
            "--resolution",
            "0.25",
            "--material",
            "al7075",
            "--fz-min",
            &fz_min,
            "--fz-max",
            &fz_max,
            "--tool",
            "ball:10",
            "-o",
            s(&fd),
            "-q",
        ])
        .args(common)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let tol = Tolerance {
        feed: 2e-3,
        spindle: 1.0,
        ..Tolerance::default()
    };
    if let Err(m) = compare(&read(&opt), &read(&fd), &tol) {
        panic!("optimise and speed → feed differ: {m}");
    }
}

/// The SOLIDWORKS CAM pair on its 135 × 135 × 30 stock (PROVENANCE.md).
/// Simulated on that box, the input's own drill cycle rapids between its
/// holes 3 mm above a hole point 6.8 mm under the stock's top (lines
/// 18–23), and its path runs inside this STL (another revision of the
/// part): the stock check refuses the output (a rapid through material is
/// refused even when the input has it) and names those findings as the
/// input's; the gouges are all the input's. With --force the faster program
/// is written and the exit code stays 3.
#[test]
fn swcam_interface_glue_is_faster_and_its_own_faults_are_named() {
    let (Some(apt), Some(stl)) = (
        shared_data::file("swcam-apt-stl-pairs/Interface-glue.apt"),
        shared_data::file("swcam-apt-stl-pairs/Interface-glue.STL"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("glue.apt");
    let glue = |passes: &str| {
        run(&[
            "optimise",
            s(&apt),
            "--stl",
            s(&stl),
            "--stock",
            "box:0,0,-30,135,135,0",
            "--resolution",
            "0.5",
            "--material",
            "al7075",
            "--passes",
            passes,
            "-o",
            s(&out),
            "--json",
            "--force",
        ])
    };
    let o = glue("speed,feed");
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    eprintln!("{}", serde_json::to_string(&j).unwrap_or_default());
    assert_eq!(j["verdict"], "refused");
    let checks = j["checks"].as_array().expect("checks");
    for c in checks {
        let own = c["findings"]
            .as_array()
            .expect("f")
            .iter()
            .all(|f| f["in_input"] == true);
        let named = c["name"] == "stock" || c["name"] == "gouge";
        assert!(c["ok"] == true || (named && own), "{c}");
    }
    assert!(j["time_after_s"].as_f64() < j["time_before_s"].as_f64());
    assert!(out.exists(), "written with --force");
    // A user trial: with reorder in the list its retract links plunged
    // beside a wall, and the run was refused for gouges the input does not
    // have. The order is now dropped where the checks refuse more of it,
    // reorder naming the check; what is left is the input's own fault.
    let j = json(&glue("speed,reorder,feed"));
    let reorder = pass(&j, "reorder");
    let why = reorder["reason"].as_str().expect("reason");
    assert_eq!(reorder["ran"], false, "{why}");
    // Each check that refused a fault of the new order's own is named: its
    // links gouge, and one rapids through the stock where the input did not.
    assert!(
        why.starts_with("dropped: the checks refused the program in the new order (check ")
            && why.contains("check gouge at line "),
        "{why}"
    );
    for c in j["checks"].as_array().expect("checks") {
        let f = c["findings"].as_array().expect("findings");
        let own = f.iter().all(|f| f["in_input"] == true);
        assert!(
            c["ok"] == true || c["name"] == "stock" || (c["name"] == "gouge" && own),
            "{c}"
        );
    }
}

/// The NX ball-end NURBS program (no STL exists for it): its part is the
/// surface the program itself leaves on a box (`simulate -o`), its stock that
/// part grown by 0.3 mm. A 1 mm grid is 30 cells across its D30 ball.
#[test]
fn nx_nurbs_is_optimised_on_its_own_surface() {
    let Some(clsf) = shared_data::file("nx-clsf-ballend-nurbs/nurbs.clsf") else {
        return;
    };
    let dir = tempfile::tempdir().expect("tmp");
    let part = dir.path().join("part.stl");
    let o = run(&[
        "simulate",
        s(&clsf),
        "--stock",
        "box:auto:2",
        "--resolution",
        "1",
        "-o",
        s(&part),
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.path().join("nx.apt");
    let o = run(&[
        "optimise",
        s(&clsf),
        "--stl",
        s(&part),
        "--stock",
        "offset:0.3",
        "--resolution",
        "1",
        "--material",
        "al7075",
        "-o",
        s(&out),
        "--json",
        "--force",
    ]);
    // The simulated part keeps the box's material where the program's own
    // rapids pass (a rapid removes nothing): its moves gouge that part,
    // refused as the input's own (written with --force). Every other check
    // passes, and the program is faster.
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    eprintln!("{}", serde_json::to_string(&j).unwrap_or_default());
    assert_eq!(j["verdict"], "refused");
    for c in j["checks"].as_array().expect("checks") {
        let f = c["findings"].as_array().expect("findings");
        let own = !f.is_empty() && f.iter().all(|f| f["in_input"] == true);
        assert!(c["ok"] == true || (c["name"] == "gouge" && own), "{c}");
    }
    let t = |k: &str| j[k].as_f64().unwrap_or(f64::NAN);
    assert!(t("time_after_s") < 0.5 * t("time_before_s"), "{j}");
    assert!(out.exists(), "written with --force");
}

/// A table-table A/C machine whose `[post]` asks for inverse-time feed.
const TABLE_AC_G93: &str = r#"name = "table A/C, inverse time"
[control]
dialect = "fanuc"
[spindle]
min = 500.0
max = 18000.0
accel = 6000.0
[feed]
max = 20000.0
rapid = 30000.0
[kinematics]
kind = "table-ac"
rot_point = [0.0, 0.0, -100.0]
offset = [0.0, 5.0, 20.0]
[kinematics.first]
min = -120.0
max = 120.0
[axes.a]
velocity = 9000.0
[axes.c]
velocity = 18000.0
[post]
inverse_time = true
"#;

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(
    p: millplan_geom::DVec3,
    a: millplan_geom::DVec3,
    b: millplan_geom::DVec3,
) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - p).length()
}

/// Issue 31, done-when 2: the NX variable-contour sample optimised for a
/// table A/C machine whose machine file asks for inverse time is posted in
/// G93, passes its own checks, and the forward kinematics of every posted
/// cutting block (computed here from the written A, C and X Y Z words)
/// lies on the CL path within --tol (plus the written precision).
#[test]
fn nx_variable_contour_is_posted_in_g93_and_its_tips_are_the_cl_path() {
    let Some(cls) = shared_data::file("nx-clsf-5axis-varcontour/ust_a.cls") else {
        return;
    };
    let dir = tempfile::tempdir().expect("tmp");
    let m = dir.path().join("ac.toml");
    std::fs::write(&m, TABLE_AC_G93).expect("write");
    let out = dir.path().join("ust_a.nc");
    let o = run(&[
        "optimise",
        s(&cls),
        "--machine",
        s(&m),
        "--tol",
        "0.01",
        "-o",
        s(&out),
        "--json",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    assert_eq!(pass(&j, "post")["ran"], true, "{j}");
    // Only the post ran: before and after are the same blocks as the
    // machine runs them (not the CL program's tip path before), so the
    // cycle time is unchanged and nothing is claimed better.
    let (t0, t1) = (
        j["time_before_s"].as_f64().expect("t0"),
        j["time_after_s"].as_f64().expect("t1"),
    );
    assert!((t0 - t1).abs() <= 1e-9 * t0, "{t0} -> {t1}");
    // The posted program is written: not the input kept, not improved.
    assert_eq!(j["verdict"], "not_improved", "{j}");
    let tip = j["checks"]
        .as_array()
        .expect("checks")
        .iter()
        .find(|c| c["name"] == "tip")
        .expect("tip check");
    assert_eq!(tip["ok"], true, "{tip}");
    let text = std::fs::read_to_string(&out).expect("written");
    assert!(text.lines().any(|l| l.contains("G93")), "no G93 block");
    // The CL path in the part frame.
    let cl = read(&cls);
    let mut segs = Vec::new();
    for op in &cl.operations {
        let at = |v: millplan_geom::DVec3| op.frame.map_or(v, |f| f.to_parent(v));
        let mut prev: Option<millplan_geom::DVec3> = None;
        for mv in &op.moves {
            let e = at(mv.end);
            if let Some(p) = prev.filter(|_| mv.is_cutting()) {
                segs.push((p, e));
            }
            prev = e.is_finite().then_some(e);
        }
    }
    assert!(segs.len() > 100);
    let kin = millplan_plan::machine::Machine::from_toml(TABLE_AC_G93)
        .expect("machine")
        .kinematics()
        .cloned()
        .expect("kinematics");
    let posted = read(&out);
    let (mut n, mut worst) = (0, 0.0f64);
    for op in &posted.operations {
        for mv in op.moves.iter().filter(|m| m.is_cutting()) {
            let a = op.orient(mv).expect("angles").angles;
            let j = millplan_models::kinematics::Joints {
                xyz: mv.end,
                first: a[0].expect("A").to_degrees(),
                second: a[2].expect("C").to_degrees(),
            };
            let t = kin.forward(&j).0;
            let d = segs
                .iter()
                .map(|&(p, q)| segment_distance(t, p, q))
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(d);
            n += 1;
        }
    }
    assert!(n > 100, "{n} posted cutting blocks");
    assert!(
        worst <= 0.01 + 2e-3,
        "a posted tip {worst} mm off the CL path"
    );
}

/// `--tools`: the demo's tool 1 served from a library (`millplan tool add`,
/// flutes and helix as ISO 13399 properties) gives the run its flutes and
/// helix, said to come from the library; a library without tool 1 stops the
/// run at the tool's record (the demo's `CUTTER/` before `LOADTL/1`, line 4)
/// with exit 2 and nothing written.
#[test]
fn the_tool_library_serves_the_tools_and_a_missing_one_is_located() {
    let dir = tempfile::tempdir().expect("tmp");
    let (part, apt, machine) = demo(dir.path());
    let db = dir.path().join("tools.db");
    let add = |n: &str| {
        let o = run(&[
            "tool",
            "add",
            n,
            "--db",
            s(&db),
            "--kind",
            "ball",
            "--r",
            "5",
            "--l",
            "80",
            "--iso",
            "ZEFP=3",
            "--iso",
            "FHA=40",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    add("1");
    let out = dir.path().join("opt.nc");
    let args = |out: &Path| {
        vec![
            "optimise".to_string(),
            s(&apt).into(),
            "--stl".into(),
            s(&part).into(),
            "--machine".into(),
            s(&machine).into(),
            "--tools".into(),
            s(&db).into(),
            "--passes".into(),
            "speed".into(),
            "-o".into(),
            s(out).into(),
            "--json".into(),
        ]
    };
    let o = bin().args(args(&out)).output().expect("runs");
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    assert_eq!(setting(&j, "flutes"), "3");
    let from = |n: &str| {
        j["settings"]
            .as_array()
            .expect("settings")
            .iter()
            .find(|x| x["name"] == n)
            .map(|x| x["from"].clone())
    };
    assert_eq!(from("flutes"), Some("tool library".into()));
    assert_eq!(from("helix"), Some("tool library".into()));
    let other = dir.path().join("other.db");
    let o = run(&[
        "tool",
        "add",
        "7",
        "--db",
        s(&other),
        "--kind",
        "ball",
        "--r",
        "5",
    ]);
    assert!(o.status.success());
    let out2 = dir.path().join("opt2.nc");
    let mut a = args(&out2);
    a[7] = s(&other).into();
    let o = bin().args(&a).output().expect("runs");
    assert_eq!(o.status.code(), Some(2));
    let e: serde_json::Value = serde_json::from_slice(&o.stderr).expect("a JSON error");
    let e = &e["error"];
    assert!(
        e["file"]
            .as_str()
            .is_some_and(|f| f.ends_with("finish.apt")),
        "{e}"
    );
    assert_eq!(e["line"], 4, "{e}");
    assert!(
        e["message"].as_str().is_some_and(|m| m.contains("tool 1")),
        "{e}"
    );
    assert!(!out2.exists());
}

/// Issue 31, the default pass list: lead and tilt for five-axis CL on the
/// stock. A D10 ball raster over a flat plate, written as five-axis CL with
/// a vertical axis on every point, cuts with the ball's tip (refused by
/// the lead/tilt pass's tip rule), so `optimise` leans it; the ball centres
/// stay where the input put them (the tip check), the feeds follow on the
/// re-oriented program, and the orient pass alone writes what `millplan
/// orient --stock` with the job's allowance writes.
#[test]
fn a_five_axis_ball_program_is_leaned_on_the_stock_with_its_centres_kept() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = dir.path();
    let (stl, raster, apt) = (d.join("plate.stl"), d.join("r.apt"), d.join("r5.apt"));
    plate(&stl);
    let o = run(&[
        "raster",
        "--stl",
        s(&stl),
        "--tool",
        "ball:10",
        "--stepover",
        "10",
        "--step",
        "2",
        "-o",
        s(&raster),
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Every point with its (vertical) tool axis: five-axis CL.
    let text = std::fs::read_to_string(&raster).expect("written");
    let five: String = text
        .lines()
        .map(|l| {
            if l.starts_with("GOTO/") && l.matches(',').count() == 2 {
                format!("{l},0,0,1\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    std::fs::write(&apt, five).expect("write");
    let stock = "box:-6,-6,-5,66,66,0.5";
    let common = ["--stl", s(&stl), "--stock", stock, "--material", "al7075"];
    let out = d.join("o.apt");
    let mut args = vec!["optimise", s(&apt)];
    args.extend(common);
    args.extend(["--resolution", "0.2", "-o", s(&out), "--json", "-q"]);
    let o = run(&args);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    let orient = pass(&j, "orient");
    assert_eq!(orient["ran"], true, "{j}");
    let said = orient["reason"].as_str().expect("said");
    // The speeds follow the turned axes.
    assert!(
        said.contains("lead") && said.contains("spindle"),
        "{orient}"
    );
    assert_eq!(pass(&j, "feed")["ran"], true, "{j}");
    assert_eq!(j["verdict"], "improved", "{j}");
    for c in j["checks"].as_array().expect("checks") {
        assert_eq!(c["ok"], true, "{c}");
    }
    // Leaned: the written axes are no longer vertical, the centres kept.
    let (input, output) = (read(&apt), read(&out));
    let cutting = |p: &millplan_nc::Program| {
        p.operations
            .iter()
            .flat_map(|op| {
                op.moves
                    .iter()
                    .filter(|m| m.is_cutting())
                    .map(|m| (m.end, op.orient(m).and_then(|o| o.axis)))
            })
            .collect::<Vec<_>>()
    };
    let (a, b) = (cutting(&input), cutting(&output));
    assert_eq!(a.len(), b.len());
    let leaned = b
        .iter()
        .filter(|(_, ax)| ax.is_some_and(|v| v.z < 0.999_999))
        .count();
    assert!(leaned > b.len() / 2, "{leaned} of {} leaned", b.len());
    for ((p, u), (q, v)) in a.iter().zip(&b) {
        let (u, v) = (u.expect("axis"), v.expect("axis"));
        let (c0, c1) = (*p + u * 5.0, *q + v * 5.0);
        assert!(c0.distance(c1) < 0.01, "centre {c0} → {c1}");
    }
    // The orient pass alone (written whatever its loads say) is `millplan
    // orient --stock` with the job's allowance and resolution.
    let (alone, cmd) = (d.join("alone.apt"), d.join("cmd.apt"));
    orient_alone(&apt, &common, &alone);
    let mut args = vec!["orient", s(&apt)];
    args.extend(common);
    args.extend(["--resolution", "0.2", "--ap", "0.3", "-q", "-o", s(&cmd)]);
    let o = run(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let gotos = |p: &Path| {
        std::fs::read_to_string(p)
            .expect("written")
            .lines()
            .filter(|l| l.starts_with("GOTO/"))
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    assert_eq!(gotos(&alone), gotos(&cmd));
    // Leaned, then posted for a table A/C machine: the posted tips are
    // checked through the kinematics against the re-oriented CL, the ball
    // centres against the input, the two as one `tip` check.
    let (m, posted) = (d.join("ac.toml"), d.join("posted.nc"));
    std::fs::write(&m, TABLE_AC_G93).expect("write");
    let mut args = vec!["optimise", s(&apt)];
    args.extend(common);
    args.extend(["--resolution", "0.2", "--machine", s(&m), "--json", "-q"]);
    args.extend(["-o", s(&posted)]);
    let o = run(&args);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    assert_eq!(pass(&j, "orient")["ran"], true, "{j}");
    assert_eq!(pass(&j, "post")["ran"], true, "{j}");
    let checks = j["checks"].as_array().expect("checks");
    let tips: Vec<_> = checks.iter().filter(|c| c["name"] == "tip").collect();
    assert_eq!(tips.len(), 1, "{j}");
    assert_eq!(tips[0]["ok"], true, "{j}");
    // A program of a three-axis and a five-axis operation (the CL reader
    // keeps a tool axis from one operation to the next, so the three-axis
    // one comes first; the five-axis one runs between its passes, 5 mm
    // over in y): only the five-axis one is leaned, the other written as
    // it was.
    let mixed = d.join("mixed.apt");
    let body = |t: &str| {
        t.lines()
            .filter(|l| !l.starts_with("FINI"))
            .map(|l| format!("{l}\n"))
            .collect::<String>()
    };
    let five: String = std::fs::read_to_string(&apt)
        .expect("written")
        .lines()
        .map(|l| match l.strip_prefix("GOTO/") {
            Some(r) => {
                let mut v: Vec<String> = r.split(',').map(str::to_string).collect();
                let y: f64 = v[1].parse().expect("y");
                v[1] = format!("{}", y + 5.0);
                format!("GOTO/{}\n", v.join(","))
            }
            None => format!("{l}\n"),
        })
        .collect();
    std::fs::write(&mixed, body(&text) + &body(&five) + "FINI\n").expect("write");
    let out = d.join("mixed_out.apt");
    orient_alone(&mixed, &common, &out);
    let (input, output) = (read(&mixed), read(&out));
    assert_eq!(input.operations.len(), 2, "two operations");
    let axes = |op: &millplan_nc::Operation| {
        op.moves
            .iter()
            .filter(|m| m.is_cutting())
            .map(|m| op.orient(m).and_then(|o| o.axis))
            .collect::<Vec<_>>()
    };
    assert!(axes(&input.operations[0]).iter().all(Option::is_none));
    assert!(axes(&output.operations[0]).iter().all(Option::is_none));
    assert_eq!(
        gotos_of(&input.operations[0]),
        gotos_of(&output.operations[0])
    );
    assert!(axes(&output.operations[1])
        .iter()
        .any(|a| a.is_some_and(|v| v.z < 0.999_999)));
}

/// Lead and tilt are kept only where they win once posted. A D10 ball
/// raster over the demo part, written as five-axis CL with its axis tilted
/// 15° about y (the ball centres where the vertical raster put them), is
/// leaned by the orient pass to a tilt whose rotary motion, posted for a
/// table A/C machine, runs more than twice as long as the input; the run is
/// made again without it, and the faster program written, said as such.
#[test]
fn lead_and_tilt_that_post_slower_than_the_input_are_dropped() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = dir.path();
    let (stl, _, _) = demo(d);
    let (raster, apt, m) = (d.join("r.apt"), d.join("r5.apt"), d.join("ac.toml"));
    let o = run(&[
        "raster",
        "--stl",
        s(&stl),
        "--tool",
        "ball:10",
        "--stepover",
        "4",
        "--step",
        "0.5",
        "-o",
        s(&raster),
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (sa, ca) = 15f64.to_radians().sin_cos();
    let text = std::fs::read_to_string(&raster).expect("written");
    let five: String = text
        .lines()
        .map(|l| match l.strip_prefix("GOTO/") {
            Some(r) if l.matches(',').count() == 2 => {
                let v: Vec<f64> = r.split(',').map(|x| x.parse().expect("number")).collect();
                // The same centre: tip = centre − R·axis.
                let (x, z) = (v[0] - 5.0 * sa, v[2] + 5.0 * (1.0 - ca));
                format!("GOTO/{x:.6},{:.6},{z:.6},{sa:.7},0,{ca:.7}\n", v[1])
            }
            _ => format!("{l}\n"),
        })
        .collect();
    std::fs::write(&apt, five).expect("write");
    std::fs::write(&m, TABLE_AC_G93).expect("write");
    let out = d.join("o.nc");
    let o = run(&[
        "optimise",
        s(&apt),
        "--stl",
        s(&stl),
        "--stock",
        "offset:0.5",
        "--machine",
        s(&m),
        "--material",
        "al7075",
        "--resolution",
        "0.5",
        "-o",
        s(&out),
        "--json",
        "-q",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    let orient = pass(&j, "orient");
    assert_eq!(orient["ran"], false, "{j}");
    assert!(
        orient["reason"]
            .as_str()
            .is_some_and(|r| r.starts_with("dropped: with the turned axes")),
        "{orient}"
    );
    assert_eq!(pass(&j, "post")["ran"], true, "{j}");
    assert_eq!(pass(&j, "feed")["ran"], true, "{j}");
    assert_eq!(j["verdict"], "improved", "{j}");
    let (before, after) = (
        j["time_before_s"].as_f64().expect("t"),
        j["time_after_s"].as_f64().expect("t"),
    );
    assert!(after < before, "{before} → {after}");
    // The axes written are the input's (no lean), posted.
    for c in j["checks"].as_array().expect("checks") {
        assert_eq!(c["ok"], true, "{c}");
    }
}

/// `optimise --passes orient` of `apt` into `out`, written whatever its
/// checks say (`--force`), with the options `common` at 0.2 mm.
fn orient_alone(apt: &Path, common: &[&str], out: &Path) {
    let mut args = vec!["optimise", s(apt)];
    args.extend(common);
    args.extend(["--resolution", "0.2", "--passes", "orient", "--force"]);
    args.extend(["-q", "-o", s(out)]);
    let o = run(&args);
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The cutting positions of an operation.
fn gotos_of(op: &millplan_nc::Operation) -> Vec<millplan_geom::DVec3> {
    op.moves
        .iter()
        .filter(|m| m.is_cutting())
        .map(|m| m.end)
        .collect()
}

/// A program without S is analysed at the default spindle speed, but that
/// speed is written only where a pass that needs one ran (here the feeds):
/// a run whose passes change nothing writes the input's words, no S added.
#[test]
fn a_default_spindle_speed_is_written_only_where_a_pass_needs_it() {
    let dir = tempfile::tempdir().expect("tmp");
    let (_, _, machine) = demo(dir.path());
    let apt = dir.path().join("nos.apt");
    std::fs::write(
        &apt,
        "PARTNO NOS\nUNITS/MM\nCUTTER/10,5\nLOADTL/1\nRAPID\nGOTO/0,0,20\nFEDRAT/800,MMPM\n\
         GOTO/0,0,-1\nGOTO/50,0,-1\nGOTO/50,30,-1\nRAPID\nGOTO/50,30,20\nFINI\n",
    )
    .expect("write");
    let spindles = |out: &Path| read(out).moves().filter(|m| m.spindle > 0.0).count();
    let common = ["--machine", s(&machine), "--resolution", "0.5"];
    let kept = dir.path().join("kept.nc");
    let o = run(&[&["optimise", s(&apt)], &common[..], &["-o", s(&kept)]].concat());
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(spindles(&kept), 0, "no pass ran: no S is invented");
    let fed = dir.path().join("fed.nc");
    let stock = ["--stock", "box:-10,-10,-5,60,40,0", "--material", "al7075"];
    let o = run(&[
        &["optimise", s(&apt)],
        &common[..],
        &stock[..],
        &["-o", s(&fed)],
    ]
    .concat());
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        spindles(&fed) > 0,
        "the feeds are written for the speed they assume"
    );
    // With a stock and a material but no pass that needs a speed, the
    // program written has no S, and its loads are still checked at the
    // speed the input's were taken at.
    let plain = dir.path().join("plain.nc");
    let args = [&["optimise", s(&apt)], &common[..], &stock[..]].concat();
    let o = run(&[&args[..], &["--passes", "post", "-o", s(&plain), "--json"]].concat());
    let j = json(&o);
    assert_eq!(o.status.code(), Some(0), "{j}");
    assert_eq!(spindles(&plain), 0);
    let checks = j["checks"].as_array().expect("checks");
    let loads = checks.iter().find(|c| c["name"] == "loads").expect("loads");
    assert!(loads["checked"].as_u64() > Some(0), "{loads}");
}

/// A tool axis the machine's rotary axes cannot reach stops `optimise` as it
/// stops `millplan post`: exit 3 at the CL line (`file:line:col` in the
/// text, `line` and `col` in the JSON), nothing written; it exited 2 as bad
/// input, its location after a space where no tool reads it.
#[test]
fn an_axis_out_of_its_travel_is_a_finding_at_its_line() {
    let dir = tempfile::tempdir().expect("tmp");
    let example = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/machine.toml");
    let text = std::fs::read_to_string(example).expect("example machine");
    // Linear travel wide enough that only the A axis (−120 .. 30) is short.
    let wide = text
        .replace("min = -300.0\nmax = 300.0", "min = -3000.0\nmax = 3000.0")
        .replace("min = -250.0\nmax = 250.0", "min = -3000.0\nmax = 3000.0")
        .replace("min = -400.0\nmax = 0.0", "min = -3000.0\nmax = 3000.0");
    assert_ne!(wide, text, "the example's travel was widened");
    let machine = dir.path().join("m.toml");
    std::fs::write(&machine, wide).expect("write");
    let apt = dir.path().join("a.apt");
    std::fs::write(
        &apt,
        "PARTNO BADAXIS\nUNITS/MM\nCUTTER/10,5,0,5,0,0,50\nLOADTL/1\nSPINDL/6000,RPM,CLW\nRAPID\n\
         GOTO/0,0,50,0,0,1\nFEDRAT/1000,MMPM\nGOTO/0,0,10,0,0,1\nGOTO/10,0,10,0,0.5,0.8660254\n\
         GOTO/20,0,10,0,0.8660254,-0.5\nGOTO/30,0,10,0,0,1\nRAPID\nGOTO/30,0,50,0,0,1\nFINI\n",
    )
    .expect("write");
    let out = dir.path().join("o.nc");
    let args = ["optimise", s(&apt), "--machine", s(&machine), "-o", s(&out)];
    let o = run(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains(&format!("{}:11:1: axis A runs out of range", s(&apt))),
        "{err}"
    );
    assert!(!out.exists());
    let o = run(&[&args[..], &["--json"]].concat());
    let e: serde_json::Value = serde_json::from_slice(&o.stderr).expect("one JSON error");
    assert_eq!(e["error"]["code"], "findings", "{e}");
    assert_eq!(
        (e["error"]["line"].as_u64(), e["error"]["col"].as_u64()),
        (Some(11), Some(1))
    );
}

/// A flat end mill plunging into the stock cuts with its end teeth, which
/// the force model does not load: the feed pass keeps the plunge's feed
/// (it raised F300 to the fz range's top, F1280 here) and names why.
#[test]
fn a_flat_end_plunge_into_the_stock_is_never_fed_faster() {
    let dir = tempfile::tempdir().expect("tmp");
    let (_, _, machine) = demo(dir.path());
    let nc = dir.path().join("plunge.nc");
    std::fs::write(
        &nc,
        "%\nO1000\nG17 G21 G90 G94\nT1 M6\nG43 H1\nS8000 M3\nG0 X10. Y10. Z20.\nZ5.\n\
         G1 Z-1. F300.\nX50. F800.\nY50.\nG0 Z20.\nM30\n%\n",
    )
    .expect("write");
    let out = dir.path().join("o.nc");
    let o = run(&[
        "optimise",
        s(&nc),
        "--tool",
        "flat:10",
        "--stock",
        "box:0,0,-10,70,70,0",
        "--material",
        "al7075",
        "--machine",
        s(&machine),
        "--resolution",
        "0.5",
        "--passes",
        "feed",
        "-o",
        s(&out),
        "--json",
    ]);
    let j = json(&o);
    assert_eq!(o.status.code(), Some(0), "{j}");
    let p = read(&out);
    // The first cutting move is the plunge to Z-1.
    let plunge = p.moves().find(|m| m.is_cutting()).expect("the plunge");
    assert_eq!((plunge.end.x, plunge.end.z), (10.0, -1.0));
    assert!(plunge.feed <= 300.0, "plunge at F{}", plunge.feed);
}

/// The holes of a canned cycle are gouge-checked along their axis, and a
/// cycle spelled out as lines in G-code drills where the input's cycle
/// drilled: a hole the part (another revision, here a plain plate) does not
/// have is the input's gouge, in G-code as in APT, not a new one refused;
/// and a new order (the tip then checked point by point) finds the
/// input's holes cut where the lines cut them (a ball-end pass in air follows, for the tool shape
/// `optimise` asks for) (SOLIDWORKS CAM's Interface-glue written to G-code was
/// refused for its own drill's holes).
#[test]
fn a_canned_cycle_written_as_lines_gouges_only_where_the_input_drilled() {
    let dir = tempfile::tempdir().expect("tmp");
    let d = dir.path();
    let (stl, apt) = (d.join("plate.stl"), d.join("drill.apt"));
    plate(&stl);
    std::fs::write(
        &apt,
        "PARTNO/HOLES\nUNITS/MM\nCUTTER/6.5,0,3.25,1.952797,31.,0,105.\nLOAD/TOOL,16\n\
         SPINDL/3000,RPM,CLW\nRAPID\nGOTO/20,20,25.\nCYCLE/INIT\n\
         CYCLE/DEEP2,FEDTO,4.,1STPECK,1.5,SUBPECK,1.,MMPM,200.,RAPTO,2.,RTRCTO,25.\n\
         GOTO/20,20,0.\nGOTO/40,20,0.\nCYCLE/OFF\n\
         CUTTER/10,5,0,5,0,0,0\nLOAD/TOOL,1\nSPINDL/6000,RPM,CLW\nRAPID\nGOTO/10,50,5\n\
         FEDRAT/1000,MMPM\nGOTO/10,50,1\nGOTO/50,50,1\nFINI\n",
    )
    .expect("write");
    let (nc, back) = (d.join("o.nc"), d.join("o.apt"));
    // Runs `optimise` on `src` into both outputs with `more` options: the
    // exit code wanted, and the check `name` must be `ok` as given with
    // findings, every one the input's.
    let both = |src: &Path, more: &[&str], code: i32, name: &str, ok: bool| {
        for out in [&nc, &back] {
            let mut args = vec!["optimise", s(src), "--stl", s(&stl)];
            args.extend(more);
            args.extend(["-o", s(out), "--json", "-q"]);
            let o = run(&args);
            let j = json(&o);
            assert_eq!(o.status.code(), Some(code), "{}: {j}", out.display());
            let c = j["checks"]
                .as_array()
                .expect("checks")
                .iter()
                .find(|c| c["name"] == name)
                .expect("the check")
                .clone();
            assert_eq!(c["ok"], ok, "{c}");
            let f = c["findings"].as_array().expect("findings");
            assert!(
                !f.is_empty() && f.iter().all(|x| x["in_input"] == true),
                "{}: {c}",
                out.display()
            );
        }
    };
    // The plate has no holes: the input's own drill gouges it, which is
    // refused as the input's (written with --force).
    both(
        &apt,
        &["--passes", "speed,reorder", "--force"],
        3,
        "gouge",
        false,
    );
    let text = std::fs::read_to_string(&nc).expect("written");
    assert!(text.contains("written as lines"), "{text}");
    // Holes whose feed plane lies 1 mm inside the stock: the cycle's rapid
    // down to it goes through material, refused whatever the dialect, and
    // named the input's own in G-code lines as in the cycle itself.
    let deep = d.join("deep.apt");
    let src = std::fs::read_to_string(&apt).expect("written");
    std::fs::write(
        &deep,
        src.replace(
            "GOTO/20,20,0.\nGOTO/40,20,0.",
            "GOTO/20,20,-3.\nGOTO/40,20,-3.",
        ),
    )
    .expect("write");
    let stock = ["--stock", "box:0,0,-5,60,60,0", "--passes", "speed"];
    both(&deep, &stock, 3, "stock", false);
    // Canned cycles alone: nothing for the passes, said as such (not
    // "give --tool", which the drill's CUTTER record already does).
    let holes = d.join("holes.apt");
    let only = src.split("CUTTER/10,5").next().expect("the drill's part");
    std::fs::write(&holes, format!("{only}FINI\n")).expect("write");
    let o = run(&[
        "optimise",
        s(&holes),
        "--stl",
        s(&stl),
        "--tool",
        "flat:8",
        "-o",
        s(&nc),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("only rapids and canned cycles"), "{err}");
}
