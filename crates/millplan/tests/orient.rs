//! `millplan orient` end to end on a case whose answer is known: a D10 ball
//! raster over a flat plate cuts with the ball's centre (lead 0, the tip in
//! the cut); the force model makes a forward lean better (spec process-models
//! §1.4c, §2.4), so the chosen lead is positive, F_xy,max falls, and the
//! written CL reads back with a tool axis on every cutting point.

use std::path::Path;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_millplan"))
}

/// A 60 × 60 mm plate, top at z = 0, as an ASCII STL (two triangles on top,
/// two below).
fn plate(path: &Path) {
    let tri = |n: [f64; 3], v: [[f64; 3]; 3]| {
        let mut s = format!("facet normal {} {} {}\nouter loop\n", n[0], n[1], n[2]);
        for p in v {
            s += &format!("vertex {} {} {}\n", p[0], p[1], p[2]);
        }
        s + "endloop\nendfacet\n"
    };
    let (a, b, c, d) = ([0., 0., 0.], [60., 0., 0.], [60., 60., 0.], [0., 60., 0.]);
    let (e, f, g, h) = (
        [0., 0., -5.],
        [60., 0., -5.],
        [60., 60., -5.],
        [0., 60., -5.],
    );
    let mut s = String::from("solid plate\n");
    s += &tri([0., 0., 1.], [a, b, c]);
    s += &tri([0., 0., 1.], [a, c, d]);
    s += &tri([0., 0., -1.], [e, g, f]);
    s += &tri([0., 0., -1.], [e, h, g]);
    s += "endsolid plate\n";
    std::fs::write(path, s).expect("write");
}

#[test]
fn orient_leans_a_ball_on_a_flat_plate() {
    let dir = tempfile::tempdir().expect("tmp");
    let (stl, apt) = plate_raster(dir.path());
    let out = dir.path().join("oriented.apt");
    let s = |p: &Path| p.to_str().expect("utf8").to_string();
    let o = bin()
        .args(["orient", &apt, "--stl", &stl, "--material", "al7075"])
        .args([
            "--n",
            "8000",
            "--holder",
            "40:50",
            "--json",
            "-q",
            "-o",
            &s(&out),
        ])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let c = &j["operations"][0];
    let f = |k: &str| c[k].as_f64().unwrap_or(f64::NAN);
    assert!(f("lead_before").abs() < 0.01, "{c}");
    // The vertical ball is refused by the tip rule (lead 0, tilt 0).
    assert!(c["objective_before"].is_null(), "{c}");
    assert!(c["refused"]["tip_contact"].as_u64() > Some(0), "{c}");
    assert!(f("lead") > 1.0 && f("lead") <= 30.0, "{c}");
    // F_xy,max at the choice is below the vertical ball's (evaluated by
    // `cut` with the same tool, engagement and cut).
    let cut = bin()
        .args(["cut", "--tool", "ball:10", "--flutes", "2", "--fz", "0.1"])
        .args([
            "--ap",
            "0.5",
            "--ae",
            "0.5",
            "--material",
            "al7075",
            "--n",
            "8000",
            "--json",
        ])
        .output()
        .expect("runs");
    assert!(
        cut.status.success(),
        "{}",
        String::from_utf8_lossy(&cut.stderr)
    );
    let cj: serde_json::Value = serde_json::from_slice(&cut.stdout).expect("json");
    let vertical = cj["fxy_max"].as_f64().expect("fxy_max");
    assert!(
        f("objective_after") < vertical,
        "{} vs {vertical}",
        f("objective_after")
    );
    // Read back: every cutting point carries a tilted axis.
    let o = bin()
        .args(["inspect", "--json", "-q", &s(&out)])
        .output()
        .expect("runs");
    assert!(o.status.success());
    let back: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(
        back["moves"]["five_axis"].as_u64(),
        c["points"].as_u64(),
        "{back}"
    );
}

/// The raster of the plate test and its files.
fn plate_raster(dir: &Path) -> (String, String) {
    let (stl, apt) = (dir.join("plate.stl"), dir.join("raster.apt"));
    plate(&stl);
    let s = |p: &Path| p.to_str().expect("utf8").to_string();
    let o = bin()
        .args(["raster", "--stl", &s(&stl), "--tool", "ball:10"])
        .args(["--stepover", "5", "--step", "2", "-o", &s(&apt)])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (s(&stl), s(&apt))
}

/// With --stock the engagement is the simulated stock's (a block 0.5 mm
/// over the plate, cut by the raster): the summary says so per operation
/// with the samples' count and memory, the tip rule is judged on the
/// stock's material (the vertical ball's tip lies in it: refused), and the
/// choice leans forward.
#[test]
fn orient_on_the_stock_reports_its_engagement_and_samples() {
    let dir = tempfile::tempdir().expect("tmp");
    let (stl, apt) = plate_raster(dir.path());
    let out = dir.path().join("oriented.apt");
    let o = bin()
        .args(["orient", &apt, "--stl", &stl, "--material", "al7075"])
        .args(["--n", "8000", "--stock", "box:-6,-6,-5,66,66,0.5"])
        .args(["--resolution", "0.2", "--samples", "16", "--json", "-q"])
        .args(["-o", out.to_str().expect("utf8")])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(j["engagement"], "stock", "{j}");
    assert_eq!(j["stock"], "box:-6,-6,-5,66,66,0.5");
    assert_eq!(j["resolution_mm"], 0.2);
    // The first move comes from a position the program does not give.
    assert_eq!(j["unsimulated_moves"], 1);
    let c = &j["operations"][0];
    assert_eq!(c["engagement"], "stock", "{c}");
    let n = c["samples"].as_u64().expect("samples");
    assert!((1..=16).contains(&n), "{c}");
    assert!(c["sample_bytes"].as_u64() > Some(0), "{c}");
    assert!(c["objective_before"].is_null(), "{c}");
    assert!(c["refused"]["tip_contact"].as_u64() > Some(0), "{c}");
    assert!(c["lead"].as_f64() > Some(1.0), "{c}");
    assert!(out.exists());
    // The planar run says so too.
    let o = bin()
        .args(["orient", &apt, "--stl", &stl, "--material", "al7075"])
        .args(["--n", "8000", "--json", "-q", "-o"])
        .arg(dir.path().join("planar.apt"))
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(j["engagement"], "planar");
    assert_eq!(j["operations"][0]["engagement"], "planar");
    assert_eq!(j["operations"][0]["samples"], 0);
    assert!(j["stock"].is_null() && j["resolution_mm"].is_null());
}

/// Bad --stock, --resolution or --samples: exit 2 with a message naming
/// the option, nothing written.
#[test]
fn orient_stock_errors_exit_2() {
    let dir = tempfile::tempdir().expect("tmp");
    let (stl, apt) = plate_raster(dir.path());
    let out = dir.path().join("never.apt");
    for (args, needle) in [
        (vec!["--stock", "pyramid:3"], "--stock"),
        (vec!["--stock", "box:1,2,3"], "--stock"),
        (vec!["--stock", "box:auto:-1"], "--stock"),
        (vec!["--stock", "stl:/no/such/blank.stl"], "blank.stl"),
        (
            vec!["--stock", "box:auto", "--resolution", "0"],
            "--resolution",
        ),
        (vec!["--stock", "box:auto", "--samples", "0"], "--samples"),
    ] {
        let o = bin()
            .args(["orient", &apt, "--stl", &stl, "--material", "al7075"])
            .args(&args)
            .args(["-q", "-o", out.to_str().expect("utf8")])
            .output()
            .expect("runs");
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?}");
    }
}

#[path = "../../millplan-nc/tests/shared_data/mod.rs"]
mod shared_data;

/// The SolidWorks CAM glue-interface pair of `../shared/data` (a D14 ball
/// finishing operation among a drill and two flat end mills): only the ball
/// operation is re-oriented, leaning forward (its tip would cut otherwise),
/// the others are left as they were and said so, and the output reads back
/// with a tool axis on every re-oriented point.
#[test]
fn orient_the_shared_glue_interface_pair() {
    let (Some(apt), Some(stl)) = (
        shared_data::file("swcam-apt-stl-pairs/Interface-glue.apt"),
        shared_data::file("swcam-apt-stl-pairs/Interface-glue.STL"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("glue.apt");
    let s = |p: &Path| p.to_str().expect("utf8").to_string();
    let o = bin()
        .args([
            "orient",
            &s(&apt),
            "--stl",
            &s(&stl),
            "--material",
            "al7075",
        ])
        .args(["--json", "-q", "-o", &s(&out)])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let ops = j["operations"].as_array().expect("operations");
    assert_eq!(ops.len(), 1, "{j}");
    assert_eq!(ops[0]["operation"], 2);
    assert!(ops[0]["lead"].as_f64() > Some(0.0), "{j}");
    let skipped = j["skipped"].as_array().expect("skipped");
    assert_eq!(skipped.len(), 3, "{j}");
    assert!(skipped
        .iter()
        .all(|k| k["reason"].as_str().is_some_and(|r| r.contains("ball-end"))));
    let o = bin()
        .args(["inspect", "--json", "-q", &s(&out)])
        .output()
        .expect("runs");
    assert!(o.status.success());
    let back: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(
        back["moves"]["five_axis"].as_u64(),
        ops[0]["points"].as_u64()
    );
}
