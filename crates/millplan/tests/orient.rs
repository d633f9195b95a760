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
    let (stl, apt, out) = (
        dir.path().join("plate.stl"),
        dir.path().join("raster.apt"),
        dir.path().join("oriented.apt"),
    );
    plate(&stl);
    let s = |p: &Path| p.to_str().expect("utf8").to_string();
    let o = bin()
        .args(["raster", "--stl", &s(&stl), "--tool", "ball:10"])
        .args(["--stepover", "5", "--step", "2", "-o", &s(&apt)])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = bin()
        .args([
            "orient",
            &s(&apt),
            "--stl",
            &s(&stl),
            "--material",
            "al7075",
        ])
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
