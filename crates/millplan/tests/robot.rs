//! `millplan robot`: the compliant-joint robot model through the binary.

mod common;
use common::bin;

fn run(args: &[&str]) -> std::process::Output {
    bin().args(args).output().expect("runs")
}

fn json(args: &[&str]) -> serde_json::Value {
    let o = run(args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("json")
}

fn vec3(v: &serde_json::Value) -> [f64; 3] {
    let a = v.as_array().expect("array");
    [0, 1, 2].map(|i| a[i].as_f64().expect("number"))
}

/// T12's units and Equation 2 at the KR 240's home pose with the wrist
/// bent down: the deflection of the command is the library's C·w, in the
/// base frame, to at least four significant digits; a moment adds.
#[test]
fn deflect_prints_the_model_deflection() {
    let j = json(&[
        "robot",
        "deflect",
        "--robot",
        "kr240",
        "--joints",
        "0,-90,90,0,30,0",
        "--force",
        "0,1000,0",
        "--json",
    ]);
    let robot = millplan_robot::Robot::kr240();
    let q = [0.0, -90.0, 90.0, 0.0, 30.0, 0.0].map(f64::to_radians);
    let want = robot.deflect(
        &q,
        millplan_robot::Variant::ThreeAxis,
        millplan_geom::DVec3::new(0.0, 1000.0, 0.0),
        millplan_geom::DVec3::ZERO,
    );
    let dp = vec3(&j["dp_mm"]);
    let dth = vec3(&j["dtheta_deg"]);
    for i in 0..3 {
        let w = want.dp[i];
        assert!(
            (dp[i] - w).abs() <= 1e-4 * w.abs().max(1e-6),
            "{dp:?} vs {}",
            want.dp
        );
        let w = want.dtheta[i].to_degrees();
        assert!((dth[i] - w).abs() <= 1e-4 * w.abs().max(1e-9), "{dth:?}");
    }
    assert!(
        dp[1] > 0.1,
        "a lateral load moves the tool sideways: {dp:?}"
    );
    // A moment of 100 N·m about z adds a rotation about z.
    let m = json(&[
        "robot",
        "deflect",
        "--joints",
        "0,-90,90,0,30,0",
        "--force",
        "0,1000,0",
        "--moment",
        "0,0,100",
        "--json",
    ]);
    assert!(vec3(&m["dtheta_deg"])[2] > dth[2]);
    // One axis per joint is stiffer than three.
    let one = json(&[
        "robot",
        "deflect",
        "--joints",
        "0,-90,90,0,30,0",
        "--force",
        "0,1000,0",
        "--axes",
        "one",
        "--json",
    ]);
    assert!(vec3(&one["dp_mm"])[1] < dp[1]);
}

#[test]
fn deflect_refuses_bad_input_with_exit_2() {
    let o = run(&[
        "robot",
        "deflect",
        "--joints",
        "0,-90,90,0,30,nan",
        "--force",
        "0,0,1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--joints A6"));
    let dir = tempfile::tempdir().expect("tmp");
    let file = dir.path().join("arm.toml");
    std::fs::write(&file, "name = 3\n").expect("write");
    let o = run(&[
        "robot",
        "deflect",
        "--robot",
        file.to_str().expect("utf8"),
        "--joints",
        "0,-90,90,0,30,0",
        "--force",
        "0,0,1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("arm.toml:1:8:"), "{err}");
}
