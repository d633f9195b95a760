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

/// The commanded poses of a KRL file: X, Y, Z and A, B, C.
fn krl_poses(path: &std::path::Path) -> Vec<([f64; 3], [f64; 3])> {
    let text = std::fs::read_to_string(path).expect("written");
    let k = millplan_nc::krl::read(&text, &mut |_| None).expect("KRL reads back");
    k.statements
        .iter()
        .filter_map(|l| match &l.statement {
            millplan_nc::krl::Statement::Move {
                motion: millplan_nc::krl::Motion::Lin(p) | millplan_nc::krl::Motion::Ptp(p),
                ..
            } => Some((p.xyz.to_array(), p.abc)),
            _ => None,
        })
        .collect()
}

/// `robot compensate --orientation`: the same positions, the tool turned
/// back; the deflected tool then stays within a thousandth of the load's
/// turn of the nominal orientation (without: off by the whole turn, a
/// hundredth of a degree here), and the tip within a thousandth of the
/// largest deflection of the path.
#[test]
fn compensate_corrects_the_orientation_on_request() {
    let dir = tempfile::tempdir().expect("tmp");
    let apt = zigzag_apt(dir.path());
    let go = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec![
            "robot",
            "compensate",
            apt.to_str().expect("utf8"),
            "--pose",
            "1300,-100,300,0",
            "--load",
            "-60,150,40",
            "--max-points",
            "0",
            "-o",
            out.to_str().expect("utf8"),
            "--json",
        ];
        args.extend_from_slice(extra);
        (json(&args), krl_poses(&out))
    };
    let (plain, plain_krl) = go("plain.src", &[]);
    let (posed, posed_krl) = go("posed.src", &["--orientation"]);
    let f = |j: &serde_json::Value, k: &str| j[k].as_f64().expect(k);
    let turn = f(&plain, "max_rotation_deg");
    assert!(turn > 1e-3 && turn < 1.0, "{plain}");
    assert_eq!(turn, f(&posed, "max_rotation_deg"));
    assert_eq!(plain["orientation"], false);
    assert_eq!(posed["orientation"], true);
    let plain_off = f(&plain, "residual_rotation_max_deg");
    assert!((plain_off - turn).abs() < 0.01 * turn, "{plain}");
    assert!(
        f(&posed, "residual_rotation_max_deg") < 1e-3 * turn,
        "{posed}"
    );
    let max = f(&plain, "max_deflection_mm");
    for j in [&plain, &posed] {
        assert!(f(j, "residual_max_mm") < 1e-3 * max, "{j}");
    }
    assert_eq!(plain_krl.len(), posed_krl.len());
    let mut turned = 0;
    for ((p, a), (q, b)) in plain_krl.iter().zip(&posed_krl) {
        assert_eq!(p, q, "the positions do not change");
        turned += usize::from(a.iter().zip(b).any(|(x, y)| (x - y).abs() > 1e-4));
    }
    assert!(
        turned > plain_krl.len() / 2,
        "{turned} of {}",
        plain_krl.len()
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

/// A slot in G-code (the paper's cut: 12 mm, three flutes, a_p 6 at
/// f_z 0.08 and 5310 1/min), entered and left through air, at `z` under
/// the stock's top at z 0.
fn slot_nc(dir: &std::path::Path, z: f64) -> std::path::PathBuf {
    let s = format!(
        "G21 G90 G17\nT1 M6\nS5310 M3\nG0 X-20 Y0 Z5\nG1 Z{z} F1274.4\nG1 X10\nG1 X90\nG1 X130\nG0 Z5\nM30\n"
    );
    let p = dir.join("slot.nc");
    std::fs::write(&p, s).expect("write");
    p
}

fn coupled(path: &std::path::Path, out: &std::path::Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "robot",
        "compensate",
        path.to_str().expect("utf8"),
        "--pose",
        "1300,-100,300,0",
        "--stock",
        "box:0,-20,-20,120,20,0",
        "--material",
        "en-aw-2007",
        "--tool",
        "flat:12",
        "--flutes",
        "3",
        "--helix",
        "0",
        "--resolution",
        "0.25",
        "-o",
        out.to_str().expect("utf8"),
        "--json",
    ];
    args.extend_from_slice(extra);
    json(&args)
}

/// The load from the force model with the stock: a path through air above
/// the stock gets no load and no deflection; a slot's largest move load is
/// the closed-form mean force of the paper's slot (|(−95.15, 304.95, 68.0)|
/// = 326.6 N, process-models §6 T1a with §1.5e's coefficients), and its
/// deflection is that of the fixed --load of the same force where the slot
/// is cut in full, less where the tool enters and leaves; compensation
/// leaves a residual far below the deflection.
#[test]
fn compensate_takes_the_load_from_the_force_model() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("c.src");
    let air = coupled(&slot_nc(dir.path(), 2.0), &out, &[]);
    assert_eq!(air["loads"]["loaded_moves"], 0, "{air}");
    assert_eq!(air["mean_deflection_mm"].as_f64(), Some(0.0), "{air}");
    assert_eq!(air["max_deflection_mm"].as_f64(), Some(0.0), "{air}");
    let slot = coupled(&slot_nc(dir.path(), -6.0), &out, &[]);
    assert_eq!(slot["loads"]["loaded_moves"], 3, "{slot}");
    let f = slot["loads"]["max_mean_force_n"].as_f64().expect("force");
    assert!((f - 326.6).abs() < 0.02 * 326.6, "{slot}");
    let fixed = json(&[
        "robot",
        "compensate",
        slot_nc(dir.path(), -6.0).to_str().expect("utf8"),
        "--pose",
        "1300,-100,300,0",
        "--load",
        "-95.15,304.95,68.0",
        "-o",
        out.to_str().expect("utf8"),
        "--json",
    ]);
    let (cm, cx) = (
        slot["mean_deflection_mm"].as_f64().expect("mean"),
        slot["max_deflection_mm"].as_f64().expect("max"),
    );
    let (fm, fx) = (
        fixed["mean_deflection_mm"].as_f64().expect("mean"),
        fixed["max_deflection_mm"].as_f64().expect("max"),
    );
    assert!(cm > 0.3 * fm && cm < fm, "coupled {slot}, fixed {fixed}");
    // The fixed load also loads the plunge and the entry and exit: the
    // largest deflection is at most theirs, close to it.
    assert!(
        cx > 0.9 * fx && cx < 1.01 * fx,
        "coupled {slot}, fixed {fixed}"
    );
    let r = slot["residual_max_mm"].as_f64().expect("residual");
    assert!(r < 0.01 * cx, "{slot}");
    // --load and --stock exclude each other; one of them is needed.
    let o = run(&[
        "robot",
        "place",
        "x.nc",
        "--load",
        "0,0,0",
        "--stock",
        "box:auto",
        "--material",
        "en-aw-2007",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(&["robot", "place", "x.nc"]);
    assert_eq!(o.status.code(), Some(2));
}

/// `robot place` with the coupled load runs, feasible and seeded.
#[test]
fn place_takes_the_load_from_the_force_model() {
    let dir = tempfile::tempdir().expect("tmp");
    let nc = slot_nc(dir.path(), -6.0);
    let args = [
        "robot",
        "place",
        nc.to_str().expect("utf8"),
        "--stock",
        "box:0,-20,-20,120,20,0",
        "--material",
        "en-aw-2007",
        "--tool",
        "flat:12",
        "--flutes",
        "3",
        "--resolution",
        "0.25",
        "--seed",
        "2",
        "--restarts",
        "1",
        "--json",
    ];
    let a = json(&args);
    assert_eq!(a["feasible"], true, "{a}");
    let mean = a["mean_deflection_mm"].as_f64().expect("mean");
    assert!(mean > 0.0 && mean <= a["max_deflection_mm"].as_f64().expect("max"));
    assert_eq!(json(&args), a);
}

/// `optimise --robot`: the optimised slot ends compensated and written as
/// KRL, a main program calling sub-programs of --max-points motions beside
/// it, which read back (the pass re-runs the deflection on what it read
/// and holds the tip within --tol); without the stock the load is
/// missing and the run says so (exit 2).
#[test]
fn optimise_ends_with_the_compensation_pass() {
    let dir = tempfile::tempdir().expect("tmp");
    let nc = slot_nc(dir.path(), -6.0);
    let out = dir.path().join("opt.src");
    let mut args = vec![
        "optimise",
        nc.to_str().expect("utf8"),
        "--material",
        "en-aw-2007",
        "--tool",
        "flat:12",
        "--flutes",
        "3",
        "--resolution",
        "0.25",
        "--robot",
        "kr240",
        "--pose",
        "1300,-100,300,0",
        "--max-points",
        "200",
        "-o",
        out.to_str().expect("utf8"),
    ];
    let o = run(&args);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("--stock"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    args.extend_from_slice(&["--stock", "box:0,-20,-20,120,20,0"]);
    let o = run(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("robot: deflection mean"), "{err}");
    let main = std::fs::read_to_string(&out).expect("main");
    assert!(main.contains("opt_001()"), "{main}");
    let k = millplan_nc::krl::read(&main, &mut |n| {
        std::fs::read_to_string(dir.path().join(format!("{n}.src"))).ok()
    })
    .expect("reads with its sub-programs");
    assert!(k.missing.is_empty(), "{:?}", k.missing);
    let motions = k
        .statements
        .iter()
        .filter(|l| matches!(l.statement, millplan_nc::krl::Statement::Move { .. }))
        .count();
    // 140 mm of cutting and the plunge at 0.3 mm, in files of 200.
    assert!(motions > 480, "{motions}");
    assert!(dir.path().join("opt_003.src").is_file());
    // The same points as SPLINE blocks: checked by the pass as LIN is.
    let spl = dir.path().join("spl.src");
    let n = args.len();
    args[n - 3] = spl.to_str().expect("utf8");
    args.extend_from_slice(&["--krl-motion", "spline"]);
    let o = run(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let k = millplan_nc::krl::read(&std::fs::read_to_string(&spl).expect("main"), &mut |n| {
        std::fs::read_to_string(dir.path().join(format!("{n}.src"))).ok()
    })
    .expect("reads with its sub-programs");
    let segments = k
        .statements
        .iter()
        .filter(|l| matches!(&l.statement, millplan_nc::krl::Statement::Move { motion, .. } if motion.is_spline()))
        .count();
    assert!(
        segments > 480 && segments < motions,
        "{segments} of {motions}"
    );
    let sub = std::fs::read_to_string(dir.path().join("spl_002.src")).expect("sub");
    assert!(
        sub.starts_with("&ACCESS RVP\n&REL 1\nDEF spl_002()\nSPLINE\n"),
        "{sub}"
    );
}

/// `convert --to krl --max-points N`: a main program calling sub-programs
/// of N motions beside it (the writer of `robot compensate`), which read
/// back to the poses of the one-file conversion; refused for another
/// dialect or standard output.
#[test]
fn convert_splits_krl_into_sub_programs() {
    let dir = tempfile::tempdir().expect("tmp");
    let apt = zigzag_apt(dir.path());
    let one = dir.path().join("one.src");
    let split = dir.path().join("zz.src");
    let conv = |out: &std::path::Path, extra: &[&str]| {
        let mut args = vec![
            "convert",
            apt.to_str().expect("utf8"),
            "-o",
            out.to_str().expect("utf8"),
            "--to",
            "krl",
        ];
        args.extend_from_slice(extra);
        run(&args)
    };
    // The approach GOTO is a feed move the KRL writes as PTP: --lossy.
    let o = conv(&one, &["--lossy"]);
    assert!(o.status.code().is_some_and(|c| c == 0 || c == 3), "{o:?}");
    let o = conv(&split, &["--max-points", "2", "--lossy"]);
    assert!(o.status.code().is_some_and(|c| c == 0 || c == 3), "{o:?}");
    let read = |p: &std::path::Path| {
        let text = std::fs::read_to_string(p).expect("written");
        millplan_nc::krl::read(&text, &mut |n| {
            std::fs::read_to_string(dir.path().join(format!("{n}.src"))).ok()
        })
        .expect("reads")
    };
    let poses = |k: &millplan_nc::krl::KrlProgram| -> Vec<millplan_nc::krl::Statement> {
        k.statements
            .iter()
            .filter(|l| matches!(l.statement, millplan_nc::krl::Statement::Move { .. }))
            .map(|l| l.statement.clone())
            .collect()
    };
    let (a, b) = (read(&one), read(&split));
    assert!(b.missing.is_empty(), "{:?}", b.missing);
    assert_eq!(poses(&a), poses(&b));
    let n = poses(&a).len();
    assert!(n > 4, "{n}");
    let subs = n.div_ceil(2);
    assert_eq!(b.files.len(), 1 + subs, "{:?}", b.files);
    assert!(dir.path().join(format!("zz_{subs:03}.src")).is_file());
    let main = std::fs::read_to_string(&split).expect("main");
    assert!(
        main.contains("zz_001()") && !main.contains("LIN "),
        "{main}"
    );
    let x = dir.path().join("x.apt");
    let o = run(&[
        "convert",
        apt.to_str().expect("utf8"),
        "-o",
        x.to_str().expect("utf8"),
        "--max-points",
        "2",
        "--lossy",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("--max-points"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = run(&[
        "convert",
        apt.to_str().expect("utf8"),
        "-o",
        "-",
        "--to",
        "krl",
        "--max-points",
        "2",
        "--lossy",
    ]);
    assert_eq!(o.status.code(), Some(2));
}

/// `robot compensate --krl-motion spline`: the same commanded points as
/// with LIN, each run a SPLINE block of SPL segments, in sub-programs of as
/// many motions as LIN's, no block straddling two files.
#[test]
fn compensate_writes_spline_blocks_on_request() {
    let dir = tempfile::tempdir().expect("tmp");
    let apt = zigzag_apt(dir.path());
    let write = |name: &str, motion: &str| {
        let out = dir.path().join(name);
        let o = run(&[
            "robot",
            "compensate",
            apt.to_str().expect("utf8"),
            "--pose",
            "1300,-100,300,0",
            "--load",
            "-60,150,40",
            "--max-points",
            "300",
            "--krl-motion",
            motion,
            "-o",
            out.to_str().expect("utf8"),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(&out).expect("written");
        let k = millplan_nc::krl::read(&text, &mut |n| {
            std::fs::read_to_string(dir.path().join(format!("{n}.src"))).ok()
        })
        .expect("reads back");
        assert!(k.missing.is_empty(), "{:?}", k.missing);
        let ends: Vec<[f64; 6]> = k
            .statements
            .iter()
            .filter_map(|l| match &l.statement {
                millplan_nc::krl::Statement::Move { motion, .. } => motion.end().map(|p| {
                    let [x, y, z] = p.xyz.to_array();
                    [x, y, z, p.abc[0], p.abc[1], p.abc[2]]
                }),
                _ => None,
            })
            .collect();
        (k.files.len(), ends)
    };
    let (lin_files, lin) = write("lin.src", "lin");
    let (spl_files, spl) = write("spl.src", "spline");
    assert_eq!(lin_files, spl_files);
    assert!(spl_files > 2, "{spl_files} files");
    assert_eq!(lin, spl);
    for i in 1..spl_files {
        let t = std::fs::read_to_string(dir.path().join(format!("spl_{i:03}.src"))).expect("sub");
        let open = t.lines().filter(|l| *l == "SPLINE").count();
        let close = t.lines().filter(|l| l.starts_with("ENDSPLINE")).count();
        assert!(open >= 1 && open == close, "spl_{i:03}: {t}");
        assert!(!t.contains("\nLIN "), "spl_{i:03}: {t}");
    }
}

/// `--krl-motion` where no KRL program is written is refused (exit 2,
/// the reason named, nothing written), not ignored: `optimise` without
/// `--robot` writes G-code, `convert --to fanuc` writes G-code; given with
/// a KRL output it is taken.
#[test]
fn krl_motion_without_a_krl_output_is_refused() {
    let dir = tempfile::tempdir().expect("tmp");
    let nc = slot_nc(dir.path(), -6.0);
    let out = dir.path().join("opt.nc");
    let o = run(&[
        "optimise",
        nc.to_str().expect("utf8"),
        "--krl-motion",
        "spline",
        "-o",
        out.to_str().expect("utf8"),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--krl-motion") && err.contains("--robot"),
        "{err}"
    );
    assert!(!out.exists());
    let o = run(&[
        "optimise",
        nc.to_str().expect("utf8"),
        "--max-points",
        "10",
        "-o",
        out.to_str().expect("utf8"),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--robot"), "{err}");
    assert!(!out.exists());
    for motion in ["lin", "spline"] {
        let o = run(&[
            "convert",
            nc.to_str().expect("utf8"),
            "--to",
            "fanuc",
            "-o",
            out.to_str().expect("utf8"),
            "--krl-motion",
            motion,
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{motion}: {err}");
        assert!(
            err.contains("--krl-motion") && err.contains("only a KRL program"),
            "{err}"
        );
        assert!(!out.exists());
    }
    let src = dir.path().join("slot.src");
    let o = run(&[
        "convert",
        nc.to_str().expect("utf8"),
        "-o",
        src.to_str().expect("utf8"),
        "--krl-motion",
        "lin",
        "--lossy",
    ]);
    // Taken: written (exit 3 only for what --lossy drops, the tool call).
    assert_ne!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(std::fs::read_to_string(&src).expect("src").contains("LIN "));
}

/// The options of `optimise --robot` on the slot of [`slot_nc`]: EN AW-2007,
/// a 3-flute D12 flat end mill, the KR 240 at 1300,-100,300,0, one KRL file.
const SLOT_ON_THE_ROBOT: [&str; 16] = [
    "--material",
    "en-aw-2007",
    "--tool",
    "flat:12",
    "--flutes",
    "3",
    "--resolution",
    "0.25",
    "--stock",
    "box:0,-20,-20,120,20,0",
    "--robot",
    "kr240",
    "--pose",
    "1300,-100,300,0",
    "--max-points",
    "0",
];

/// `optimise --robot --json --report`: the robot pass's figures (the
/// deflection before compensation, mean and max |Δp|, and the largest
/// distance of the tip from the path that the KRL read back leaves) are
/// keys of the typed summary and one section of the report, the same
/// numbers as standard error prints without --json.
#[test]
fn optimise_robot_figures_in_json_and_report() {
    let dir = tempfile::tempdir().expect("tmp");
    let nc = slot_nc(dir.path(), -6.0);
    let out = dir.path().join("opt.src");
    let report = dir.path().join("opt.html");
    let mut args = vec!["optimise", nc.to_str().expect("utf8")];
    args.extend(SLOT_ON_THE_ROBOT);
    args.extend([
        "-o",
        out.to_str().expect("utf8"),
        "--report",
        report.to_str().expect("utf8"),
    ]);
    let text = run(&args);
    let err = String::from_utf8_lossy(&text.stderr).to_string();
    assert!(text.status.success(), "{err}");
    args.push("--json");
    let j = json(&args);
    let r = &j["robot"];
    let num = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k}: {j}"));
    let (mean, max, residual) = (
        num("mean_deflection_mm"),
        num("max_deflection_mm"),
        num("residual_max_mm"),
    );
    assert!(mean > 0.01 && mean <= max, "{r}");
    assert!(
        residual <= num("tolerance_mm") && residual < 0.1 * max,
        "{r}"
    );
    assert!(r["points"].as_u64().expect("points") > 480, "{r}");
    assert!(
        r["loads"]["max_mean_force_n"].as_f64().expect("force") > 100.0,
        "{r}"
    );
    // Standard error prints the same figures (--json rounds lengths to the
    // micrometre): mean and max to 4 significant digits, the residual to 3.
    let line = err
        .lines()
        .find(|l| l.starts_with("robot: deflection mean "))
        .unwrap_or_else(|| panic!("{err}"));
    let word_after = |w: &str| -> String {
        let rest = line
            .split_once(w)
            .unwrap_or_else(|| panic!("{w} in {line}"))
            .1;
        rest.split_whitespace().next().unwrap_or("").to_string()
    };
    let printed = [
        (word_after("deflection mean "), mean),
        (word_after(", max "), max),
        (word_after("leaves at most "), residual),
    ];
    let html = std::fs::read_to_string(&report).expect("report");
    let section = html
        .split_once("<section id=\"robot\">")
        .map(|(_, s)| s.split("</section>").next().unwrap_or(""))
        .expect("a robot section");
    for (text, json) in &printed {
        let v: f64 = text.parse().unwrap_or_else(|_| panic!("{text} in {line}"));
        assert!((v - json).abs() <= 5e-4, "{line}\n{r}");
        let cell = format!("<td>{text} mm</td>");
        assert!(section.contains(&cell), "{cell} in {section}");
    }
    assert_eq!(html.matches("<section id=\"robot\">").count(), 1);
    assert!(html.ends_with("</body></html>"));
}

/// `optimise --robot --orientation`: the orientation corrected as `robot
/// compensate --orientation` does it (process-models §4.4, optional): the
/// tool's turn under the load is left at the commanded points without it
/// and (nearly) gone with it, the position held within --tol either way;
/// the KRL differs in A, B, C only. Without --robot the option is refused.
#[test]
fn optimise_robot_corrects_the_orientation_on_request() {
    let dir = tempfile::tempdir().expect("tmp");
    let nc = slot_nc(dir.path(), -6.0);
    let run_with = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["optimise", nc.to_str().expect("utf8")];
        args.extend(SLOT_ON_THE_ROBOT);
        args.extend(["--json", "-o", out.to_str().expect("utf8")]);
        args.extend_from_slice(extra);
        let j = json(&args);
        (j["robot"].clone(), krl_poses(&out))
    };
    let (plain, pos_plain) = run_with("plain.src", &[]);
    let (turned, pos_turned) = run_with("turned.src", &["--orientation"]);
    let f = |r: &serde_json::Value, k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k}: {r}"));
    assert_eq!(
        (
            plain["orientation"].as_bool(),
            turned["orientation"].as_bool()
        ),
        (Some(false), Some(true))
    );
    let rot = f(&plain, "max_rotation_deg");
    assert!(rot > 0.002, "{plain}");
    assert!(
        f(&plain, "residual_rotation_max_deg") >= 0.5 * rot,
        "{plain}"
    );
    assert!(
        f(&turned, "residual_rotation_max_deg") <= 0.05 * rot,
        "{turned}"
    );
    assert!(
        f(&turned, "residual_max_mm") <= f(&turned, "tolerance_mm"),
        "{turned}"
    );
    assert_eq!(pos_plain.len(), pos_turned.len());
    let (mut moved, mut turned_abc) = (0.0f64, 0.0f64);
    for ((p0, a0), (p1, a1)) in pos_plain.iter().zip(&pos_turned) {
        moved = moved.max((0..3).map(|i| (p0[i] - p1[i]).abs()).fold(0.0, f64::max));
        turned_abc = turned_abc.max((0..3).map(|i| (a0[i] - a1[i]).abs()).fold(0.0, f64::max));
    }
    assert!(turned_abc > 1e-3, "{turned_abc}");
    assert!(moved < 0.01, "{moved}");
    let o = run(&[
        "optimise",
        nc.to_str().expect("utf8"),
        "--orientation",
        "-o",
        dir.path().join("x.nc").to_str().expect("utf8"),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--robot"), "{err}");
}
