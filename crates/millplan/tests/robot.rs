//! `millplan robot`: the compliant-joint robot model through the binary.

fn bin() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_millplan"))
}

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

/// A 100 mm × 50 mm zig-zag at z 0, tool vertical, as APT.
fn zigzag_apt(dir: &std::path::Path) -> std::path::PathBuf {
    let mut s = String::from("CUTTER/12\nGOTO/0,0,10,0,0,1\nFEDRAT/1200\n");
    for row in 0..3 {
        let y = row as f64 * 25.0;
        let (a, b) = if row % 2 == 0 {
            (0.0, 100.0)
        } else {
            (100.0, 0.0)
        };
        s.push_str(&format!("GOTO/{a},{y},0,0,0,1\nGOTO/{b},{y},0,0,0,1\n"));
    }
    let p = dir.join("zigzag.apt");
    std::fs::write(&p, s).expect("write");
    p
}

/// `robot compensate`: the JSON keys of the issue, and the KRL it writes
/// reads back with one commanded point per 0.3 mm, moved by less than the
/// largest deflection.
#[test]
fn compensate_writes_krl_and_reports() {
    let dir = tempfile::tempdir().expect("tmp");
    let apt = zigzag_apt(dir.path());
    let out = dir.path().join("slot.src");
    let j = json(&[
        "robot",
        "compensate",
        apt.to_str().expect("utf8"),
        "--pose",
        "1300,-100,300,0",
        "--load",
        "-60,150,40",
        "-o",
        out.to_str().expect("utf8"),
        "--json",
    ]);
    let (mean, max) = (
        j["mean_deflection_mm"].as_f64().expect("mean"),
        j["max_deflection_mm"].as_f64().expect("max"),
    );
    assert!(mean > 0.0 && max >= mean && max < 2.0, "{j}");
    let points = j["points"].as_u64().expect("points") as usize;
    // 250 mm of cutting (plus the plunge) at 0.3 mm.
    assert!(points > 250.0_f64.div_euclid(0.3) as usize, "{points}");
    let text = std::fs::read_to_string(&out).expect("written");
    let k = millplan_nc::krl::read(&text, &mut |_| None).expect("KRL reads back");
    assert_eq!(
        k.statements
            .iter()
            .filter(|l| matches!(l.statement, millplan_nc::krl::Statement::Move { .. }))
            .count(),
        points
    );
    assert!(text.contains("$VEL.CP = 0.020000"), "1200 mm/min in m/s");
    // Out of reach: located at the first line it cannot machine, exit 2.
    let o = run(&[
        "robot",
        "compensate",
        apt.to_str().expect("utf8"),
        "--pose",
        "5000,0,0,0",
        "--load",
        "0,100,0",
        "-o",
        out.to_str().expect("utf8"),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("zigzag.apt:"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// `robot place`: the JSON keys of the issue, feasible, reproducible for a seed.
#[test]
fn place_is_seeded() {
    let dir = tempfile::tempdir().expect("tmp");
    let apt = zigzag_apt(dir.path());
    let args = [
        "robot",
        "place",
        apt.to_str().expect("utf8"),
        "--load",
        "-60,150,40",
        "--seed",
        "3",
        "--restarts",
        "1",
        "--json",
    ];
    let a = json(&args);
    assert_eq!(a["feasible"], true);
    for k in ["x", "y", "z", "rz"] {
        assert!(a["pose"][k].is_number(), "{a}");
    }
    assert!(a["evaluations"].as_u64().expect("evaluations") > 100);
    assert!(
        a["mean_deflection_mm"].as_f64().expect("mean")
            <= a["max_deflection_mm"].as_f64().expect("max")
    );
    assert_eq!(json(&args), a);
}
