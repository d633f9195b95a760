//! `millplan simulate` as a user runs it: a G-code program over a box, a
//! rapid through the stock and a shank in the material reported on their
//! lines with exit 3, the JSON keys, the table, the stock mesh, bad stock
//! specifications and open blanks refused with exit 2, and the real samples.

#[path = "../../millplan-nc/tests/shared_data/mod.rs"]
mod shared_data;

use std::path::Path;
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
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

/// A slot 2 mm deep, a rapid at cutting depth (line 7), then a cut 8 mm deep
/// with 5 mm of flutes (line 9: the shank rubs the wall).
const PROGRAM: &str = "%\nG21 G90 G17\nT1 M6\nS8000 M3\nG0 X0 Y0 Z5\nG1 Z-2 F500\nG1 X10\nG0 X20\nG1 Z-8\nG1 X30\nG0 Z20\nM30\n%\n";

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write");
    p.display().to_string()
}

#[test]
fn a_rapid_through_stock_and_a_shank_in_the_wall_exit_3_with_their_lines() {
    let dir = tempfile::tempdir().expect("tmp");
    let nc = write(dir.path(), "slot.nc", PROGRAM);
    let table = dir.path().join("moves.csv").display().to_string();
    let stl = dir.path().join("stock.stl").display().to_string();
    let report = dir.path().join("sim.html").display().to_string();
    let o = run(&[
        "simulate",
        &nc,
        "--tool",
        "flat:6",
        "--flute-length",
        "5",
        "--stock",
        "box:-10,-10,-20,40,10,0",
        "--resolution",
        "0.1",
        "--json",
        "--table",
        &table,
        "-o",
        &stl,
        "--report",
        &report,
    ]);
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    for k in [
        "removed_mm3",
        "moves",
        "cutting_moves",
        "air_moves",
        "rapid_collisions",
        "holder_collisions",
        "max_mrr_mm3_min",
        "resolution_mm",
    ] {
        assert!(!j[k].is_null(), "{k}: {j}");
    }
    let rapid = j["rapid_collisions"].as_array().expect("list");
    assert_eq!(rapid.len(), 1, "{j}");
    assert_eq!(rapid[0]["line"], 8, "{j}");
    assert!((rapid[0]["depth"].as_f64().expect("depth") - 2.0).abs() < 0.01);
    let holder = j["holder_collisions"].as_array().expect("list");
    assert!(holder.iter().any(|c| c["line"] == 10), "{j}");
    // Removed: the slot (10 × 6 + π·9) × 2, the rapid's slot, the deep cut.
    let slot = (10.0 * 6.0 + std::f64::consts::PI * 9.0) * 2.0;
    assert!(j["removed_mm3"].as_f64().expect("v") > 2.0 * slot);
    let csv = std::fs::read_to_string(&table).expect("table");
    assert!(
        csv.starts_with("index,line,removed_mm3,mrr,ap,ae,air"),
        "{csv}"
    );
    assert!(csv.lines().count() > 5);
    let mesh = std::fs::read(&stl).expect("stl");
    let tris = u32::from_le_bytes([mesh[80], mesh[81], mesh[82], mesh[83]]) as usize;
    assert_eq!(mesh.len(), 84 + 50 * tris);
    let html = std::fs::read_to_string(&report).expect("report");
    assert!(
        html.contains("id=\"warnings\"")
            && html.contains("COLLISION line")
            && html.contains("<svg"),
        "report"
    );
}

#[test]
fn a_clean_program_exits_0_and_says_so() {
    let dir = tempfile::tempdir().expect("tmp");
    let clean = PROGRAM
        .replace("G0 X20\n", "G0 Z5\nG0 X20\nG1 Z-2\n")
        .replace("G1 Z-8\n", "");
    let nc = write(dir.path(), "clean.nc", &clean);
    let o = run(&[
        "simulate",
        &nc,
        "--tool",
        "flat:6",
        "--stock",
        "box:-10,-10,-20,40,10,0",
        "--resolution",
        "0.2",
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{text}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(text.contains("no collisions"), "{text}");
}

#[test]
fn bad_stocks_and_open_blanks_are_refused_with_exit_2() {
    let dir = tempfile::tempdir().expect("tmp");
    let nc = write(dir.path(), "slot.nc", PROGRAM);
    for (stock, says) in [
        ("box:1,2,3", "6 finite numbers"),
        ("box:0,0,0,-1,1,1", "must exceed"),
        ("sphere:3", "a stock is"),
        ("offset:0.5", "needs the part"),
        ("box:auto:x", "margin"),
    ] {
        let o = run(&["simulate", &nc, "--tool", "flat:6", "--stock", stock]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{stock}: {err}");
        assert!(err.contains(says), "{stock}: {err}");
    }
    // A single triangle is no blank.
    let mut stl = vec![0u8; 80];
    stl.extend(1u32.to_le_bytes());
    for v in [[0f32, 0., 0.], [0., 0., 1.], [1., 0., 0.], [0., 1., 0.]] {
        for c in v {
            stl.extend(c.to_le_bytes());
        }
    }
    stl.extend([0, 0]);
    let open = dir.path().join("open.stl");
    std::fs::write(&open, stl).expect("write");
    let o = run(&[
        "simulate",
        &nc,
        "--tool",
        "flat:6",
        "--stock",
        &format!("stl:{}", open.display()),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("closed mesh"), "{err}");
    // Without a tool shape, G-code says nothing: refused, not guessed.
    let o = run(&["simulate", &nc, "--stock", "box:auto"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--tool"));
}

#[test]
fn the_demo_finish_over_its_part_with_an_allowance_leaves_no_more_than_the_allowance() {
    let dir = tempfile::tempdir().expect("tmp");
    let demo = dir.path().join("demo");
    assert!(run(&["demo", "-o", demo.to_str().expect("utf8")])
        .status
        .success());
    let p = |n: &str| demo.join(n).display().to_string();
    let o = run(&[
        "simulate",
        &p("finish.apt"),
        "--stock",
        "offset:0.5",
        "--stl",
        &p("part.stl"),
        // Dexels of 0.2 mm read a slope up to 0.1 mm off: no gouge is
        // counted above half their size.
        "--resolution",
        "0.2",
        "--json",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    let r = &j["remaining"];
    // The finishing pass takes the allowance off where it reaches; nothing
    // is left thicker than the allowance, and nothing is cut into by more
    // than the dexel error.
    assert!(r["max"].as_f64().expect("max") <= 0.5 + 0.05, "{r}");
    assert!(r["mean"].as_f64().expect("mean") < 0.25, "{r}");
    assert!(r["min"].as_f64().expect("min") > -0.1, "{r}");
    assert!(j["removed_mm3"].as_f64().expect("v") > 100.0);
    assert_ne!(j["verdict"]["level"], "red", "{}", j["verdict"]);
    // A user trial: a hole drilled 10 mm into the part made the report red
    // and exited 0, the text and JSON without a verdict. Exit 3, and the
    // verdict said in both.
    let drill = write(
        dir.path(),
        "drill.nc",
        "G21 G90 G17\nT1 M6\nS2000 M3\nG0 X30 Y30 Z30\nG98 G81 X30 Y30 Z-10 R10 F100\nG80\nG0 Z50\nM30\n",
    );
    let args = [
        "simulate",
        &drill,
        "--tool",
        "flat:10",
        "--stock",
        "offset:0.5",
    ];
    let o = run(&[&args[..], &["--stl", &p("part.stl"), "--json"]].concat());
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v = &json(&o)["verdict"];
    assert_eq!(v["level"], "red", "{v}");
    assert!(
        v["failed"][0]
            .as_str()
            .unwrap_or("")
            .contains("cut into the part"),
        "{v}"
    );
    let o = run(&[&args[..], &["--stl", &p("part.stl")]].concat());
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stdout).contains("verdict: Red"));
}

/// The CAMotics bear relief (its project file: stock 80 × 80 × 20 mm, a
/// 1/8" ball): the removed volume converges as the dexels shrink.
#[test]
fn the_camotics_relief_removes_a_converging_volume() {
    let Some(nc) = shared_data::file("camotics-ballnose-relief-gcode/bear.nc") else {
        return;
    };
    let v: Vec<f64> = ["0.4", "0.2"]
        .iter()
        .map(|res| {
            let o = run(&[
                "simulate",
                nc.to_str().expect("utf8"),
                "--tool",
                "ball:3.175",
                "--stock",
                "box:0,0,-20,80,80,0",
                "--resolution",
                res,
                "--json",
                "-q",
            ]);
            assert_eq!(
                o.status.code(),
                Some(0),
                "{}",
                String::from_utf8_lossy(&o.stderr)
            );
            json(&o)["removed_mm3"].as_f64().expect("v")
        })
        .collect();
    // 88,263 mm³ at 0.05 and 0.025 mm (release runs); coarser cells are
    // within 0.05 % of it.
    for x in &v {
        assert!((x - 88_263.0).abs() < 0.0005 * 88_263.0, "{v:?}");
    }
}

/// The five-axis samples run through: NX variable contour (bull D32 R5 with a
/// box around its cuts, which its approach rapids cross) and the impeller
/// fragments (no tool in the file: a ball given).
#[test]
fn the_five_axis_samples_simulate() {
    let Some(nx) = shared_data::file("nx-clsf-5axis-varcontour/ust_a.cls") else {
        return;
    };
    let o = run(&[
        "simulate",
        nx.to_str().expect("utf8"),
        "--stock",
        "box:auto",
        "--resolution",
        "4",
        "--json",
        "-q",
    ]);
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let j = json(&o);
    assert!(j["simulated"].as_u64().expect("n") > 500, "{j}");
    assert!(j["removed_mm3"].as_f64().expect("v") > 0.0);
    for f in ["pathdata2.txt", "toolpathdata3.txt", "yelun.txt"] {
        let Some(p) = shared_data::file(&format!("impeller-5axis-goto-fragments/{f}")) else {
            return;
        };
        let o = run(&[
            "simulate",
            p.to_str().expect("utf8"),
            "--tool",
            "ball:6",
            "--stock",
            "box:auto",
            "--resolution",
            "0.5",
            "--json",
            "-q",
        ]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{f}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(json(&o)["cutting_moves"].as_u64().expect("n") > 10, "{f}");
    }
}

/// A drilling cycle returns the tool to its retract level (`RTRCTO`, 20 mm
/// above the holes here, whose points lie 2 mm under the stock's top); the
/// next operation's first rapid starts there, not at the last hole's point,
/// and so crosses no material.
#[test]
fn the_move_after_a_drilling_cycle_starts_at_the_cycles_return_level() {
    let dir = tempfile::tempdir().expect("tmp");
    let apt = write(
        dir.path(),
        "drill.apt",
        "PARTNO/1\nUNIT/MM\nCUTTER/6.,0,3.,0,0,0,60.\nLOAD/TOOL,1\nSPINDL/3000,RPM,CLW\n\
         RAPID/\nGOTO/10,10,25.\nCYCLE/DRILL,FEDTO,5.,MMPM,200.,RAPTO,2.,RTRCTO,20.\n\
         GOTO/10,10,3.\nGOTO/30,10,3.\nCYCLE/OFF\n\
         CUTTER/10.,0,5.,0,0,0,60.\nLOAD/TOOL,2\nSPINDL/6000,RPM,CLW\n\
         RAPID/\nGOTO/50,30,25.\nGOTO/50,30,6.\nFEDRAT/500,MMPM\nGOTO/50,30,4.\nGOTO/60,30,4.\n\
         RAPID/\nGOTO/60,30,25.\nFINI\n",
    );
    let o = run(&[
        "simulate",
        &apt,
        "--stock",
        "box:0,0,0,70,40,5",
        "--resolution",
        "0.25",
        "--json",
    ]);
    let j = json(&o);
    assert_eq!(
        j["rapid_collisions"].as_array().map(Vec::len),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert_eq!(o.status.code(), Some(0));
    assert!(
        j["removed_mm3"].as_f64().unwrap_or(0.0) > 100.0,
        "the holes and the slot cut"
    );
}

/// A user trial: `verdict: Amber: a warning applies.` without the warning.
/// The text names each warning the verdict weighs, before the verdict line
/// (still the last line, as every command's).
#[test]
fn an_amber_verdict_names_its_warnings() {
    let dir = tempfile::tempdir().expect("tmp");
    let o = run(&["demo", "-q", "-o", dir.path().to_str().expect("utf-8")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d = dir.path();
    let (apt, stl) = (d.join("finish.apt"), d.join("part.stl"));
    let o = run(&[
        "simulate",
        apt.to_str().expect("utf-8"),
        "--stl",
        stl.to_str().expect("utf-8"),
        "--stock",
        "offset:0.3",
        "-q",
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    let lines: Vec<&str> = text.lines().collect();
    let last = lines.last().copied().unwrap_or("");
    assert!(last.starts_with("verdict: Amber"), "{text}");
    let before = lines[lines.len() - 2];
    assert!(
        before.starts_with("warning: ") && before.contains("not simulated"),
        "{text}"
    );
}
