//! Deflection along a path, compensation (T14) and placement (§4.5) on the
//! paper's KR 240.

use millplan_geom::DVec3;
use millplan_robot::anneal::Settings;
use millplan_robot::machining::{
    self, compensate, resample, Load, PathLoad, PathPoint, PlaceSearch, Placement,
};
use millplan_robot::{Robot, Variant};

/// A 200 mm × 100 mm zig-zag slot pattern at 0.3 mm spacing, tool vertical.
fn zigzag(step: f64) -> Vec<PathPoint> {
    let mut run = Vec::new();
    for row in 0..5 {
        let y = row as f64 * 25.0;
        let xs = [0.0, 200.0];
        let (a, b) = if row % 2 == 0 {
            (xs[0], xs[1])
        } else {
            (xs[1], xs[0])
        };
        for p in [a, b] {
            run.push(PathPoint {
                p: DVec3::new(p, y, 0.0),
                axis: DVec3::Z,
                feed: 1200.0,
                line: row + 1,
                mv: row,
                tilt: DVec3::ZERO,
            });
        }
    }
    resample(&run, step)
}

const LOAD: Load = Load {
    feed: -60.0,
    cross: 150.0,
    axial: 40.0,
};

fn place() -> Placement {
    Placement {
        x: 1300.0,
        y: -100.0,
        z: 300.0,
        rz: 0.0,
    }
}

#[test]
fn resampling_keeps_the_path_and_the_spacing() {
    let pts = zigzag(0.3);
    for w in pts.windows(2) {
        let d = (w[1].p - w[0].p).length();
        assert!(d <= 0.3 + 1e-9, "{d}");
    }
    let len: f64 = pts.windows(2).map(|w| (w[1].p - w[0].p).length()).sum();
    assert!((len - (5.0 * 200.0 + 4.0 * 25.0)).abs() < 1e-6, "{len}");
}

/// T14 (process-models §6): with p_cmd = p − Δp(p) the robot, pushed back
/// by the same load, lands on p; one fixed-point refinement
/// p_cmd ← p − Δp(p_cmd) changes p_cmd by under 1 % of |Δp|.
#[test]
fn t14_compensation_identity_and_fixed_point() {
    let robot = Robot::kr240();
    let ideal = zigzag(5.0);
    let d = robot
        .deflections(Variant::ThreeAxis, &place(), &ideal, &LOAD, None)
        .expect("reachable");
    assert!(d.mean > 0.01 && d.max < 2.0, "{} {}", d.mean, d.max);
    let cmd = compensate(&ideal, &d.dp);
    let dirs = machining::feed_dirs(&ideal);
    let at_cmd = robot
        .deflections_along(
            Variant::ThreeAxis,
            &place(),
            &cmd,
            &dirs,
            &LOAD,
            Some(d.status),
        )
        .expect("reachable");
    for i in 0..ideal.len() {
        let landed = cmd[i].p + at_cmd.dp[i];
        let refined = ideal[i].p - at_cmd.dp[i];
        let size = d.dp[i].length();
        assert!(
            (landed - ideal[i].p).length() < 0.01 * size,
            "point {i}: {} vs {}",
            landed,
            ideal[i].p
        );
        assert!((refined - cmd[i].p).length() < 0.01 * size);
    }
}

/// The paper's anisotropy (§7): the same load across the arm (y₀) deflects
/// more than along it (x₀): turning the workpiece by 90° changes the mean.
#[test]
fn deflection_depends_on_the_placement() {
    let robot = Robot::kr240();
    let path = zigzag(10.0);
    let a = robot
        .deflections(Variant::ThreeAxis, &place(), &path, &LOAD, None)
        .expect("a");
    let turned = Placement {
        rz: std::f64::consts::FRAC_PI_2,
        x: 1400.0,
        y: -100.0,
        ..place()
    };
    let b = robot
        .deflections(Variant::ThreeAxis, &turned, &path, &LOAD, None)
        .expect("b");
    assert!(
        (a.mean - b.mean).abs() > 0.01 * a.mean,
        "{} {}",
        a.mean,
        b.mean
    );
    // Out of reach: an error naming the line.
    let far = Placement {
        x: 5000.0,
        ..place()
    };
    let e = robot
        .deflections(Variant::ThreeAxis, &far, &path, &LOAD, None)
        .expect_err("far");
    assert!(e.to_string().starts_with("line 1:"), "{e}");
}

/// §4.5: the annealing placement is reproducible for a seed and no worse
/// than a hand-picked feasible placement inside its box.
#[test]
fn placement_search_is_seeded_and_improves() {
    let robot = Robot::kr240();
    let path = zigzag(10.0);
    let search = PlaceSearch {
        lo: DVec3::new(800.0, -800.0, 0.0),
        hi: DVec3::new(1800.0, 800.0, 800.0),
        settings: Settings {
            seed: 7,
            restarts: 2,
            ..Settings::default()
        },
    };
    let a = machining::place(
        &robot,
        Variant::ThreeAxis,
        &path,
        &machining::PathLoad::Fixed(LOAD),
        &search,
    )
    .expect("placed");
    let b = machining::place(
        &robot,
        Variant::ThreeAxis,
        &path,
        &machining::PathLoad::Fixed(LOAD),
        &search,
    )
    .expect("placed");
    assert_eq!(a.place, b.place);
    let hand = robot
        .deflections(Variant::ThreeAxis, &place(), &path, &LOAD, None)
        .expect("hand");
    eprintln!(
        "hand {:.4} mean / {:.4} max; placed {:?}: {:.4} / {:.4} after {} evaluations",
        hand.mean, hand.max, a.place, a.mean, a.max, a.evaluations
    );
    assert!(a.mean <= hand.mean, "{} > {}", a.mean, hand.mean);
    assert!(a.evaluations > 100);
}

/// The compensated program in KRL: one LIN per point, the first a PTP, the
/// speed in m/s; it reads back to the compensated points.
#[test]
fn compensated_program_is_krl() {
    let robot = Robot::kr240();
    let ideal = zigzag(0.3);
    let d = robot
        .deflections(Variant::ThreeAxis, &place(), &ideal, &LOAD, None)
        .expect("reachable");
    let cmd = compensate(&ideal, &d.dp);
    let k = machining::krl_program("slot", std::slice::from_ref(&cmd), &place(), 0.15);
    let files = millplan_nc::write::krl::write(
        &k,
        &millplan_nc::write::krl::KrlOptions {
            max_points: 0,
            ..Default::default()
        },
    );
    let text = &files[0].1;
    assert!(text.contains("$VEL.CP = 0.020000"));
    assert_eq!(
        text.lines().filter(|l| l.starts_with("LIN ")).count(),
        cmd.len() - 1
    );
    let back = millplan_nc::krl::read(text, &mut |_| None).expect("reads");
    let pts: Vec<DVec3> = back
        .statements
        .iter()
        .filter_map(|l| match &l.statement {
            millplan_nc::krl::Statement::Move {
                motion: millplan_nc::krl::Motion::Lin(p) | millplan_nc::krl::Motion::Ptp(p),
                ..
            } => Some(p.xyz),
            _ => None,
        })
        .collect();
    for (a, b) in pts.iter().zip(&cmd) {
        assert!((*a - b.p).length() < 1e-3);
    }
}

/// The path's deflections (one thread's frames and tool rotation kept from
/// point to point, in parallel) equal, point by point, the slow route of
/// Equation 2: every IK solution of the pose, the one of the path's Status,
/// the full 6×6 C = J K⁻¹ Jᵀ built and applied to the wrench, to 1e-9 mm.
#[test]
fn path_deflection_equals_the_compliance_matrix_pose_by_pose() {
    let mut run = resample(&zigzag(0.3), 5.0);
    // The axis tilts along the path (the kept rotation must follow it).
    for (i, p) in run.iter_mut().enumerate() {
        let t = (i as f64 * 0.05).sin() * 0.02;
        p.axis = DVec3::new(t.sin(), 0.0, t.cos());
        if i % 7 < 3 {
            p.axis = DVec3::Z;
        }
    }
    let place = place();
    let load = Load {
        feed: -95.0,
        cross: 305.0,
        axial: 68.0,
    };
    let robot = Robot::kr240();
    let pose = place.pose();
    let dirs = machining::feed_dirs(&run);
    for variant in [Variant::ThreeAxis, Variant::OneAxis] {
        let d = robot
            .deflections(variant, &place, &run, &load, None)
            .expect("reachable");
        for (i, pt) in run.iter().enumerate() {
            let tcp = machining::tcp_pose(&pose, pt.p, pt.axis);
            let q = robot
                .ik_all(&tcp, 0.0)
                .into_iter()
                .find(|q| robot.config(q).status == d.status && robot.feasible_winding(q).is_some())
                .expect("a solution of the path's Status");
            let f = dirs[i];
            let force =
                pose.r * (f * load.feed + pt.axis.cross(f) * load.cross + pt.axis * load.axial);
            let c = robot.compliance(&q, variant).apply(force, DVec3::ZERO);
            let want = pose.r.transpose() * c.dp;
            assert!(
                (want - d.dp[i]).length() <= 1e-9,
                "{variant:?} point {i}: {} vs {want}",
                d.dp[i]
            );
        }
    }
}

/// A force of its own at every point (the force model's, in the workpiece
/// frame): the fixed feed-frame load given point by point deflects exactly
/// as the fixed load; Equation 2 is linear, so a point's force doubled
/// doubles its Δp and leaves the others; one force a point is required.
#[test]
fn deflection_under_a_force_per_point() {
    let run = resample(&zigzag(0.3), 10.0);
    let (robot, place) = (Robot::kr240(), place());
    let load = Load {
        feed: -95.0,
        cross: 305.0,
        axial: 68.0,
    };
    let dirs = machining::feed_dirs(&run);
    let forces: Vec<DVec3> = run
        .iter()
        .zip(&dirs)
        .map(|(p, f)| *f * load.feed + p.axis.cross(*f) * load.cross + p.axis * load.axial)
        .collect();
    let fixed = robot
        .deflections(Variant::ThreeAxis, &place, &run, &load, None)
        .expect("reachable");
    let each = robot
        .deflections_under(Variant::ThreeAxis, &place, &run, &forces, None)
        .expect("reachable");
    assert_eq!(each.dp, fixed.dp);
    assert_eq!((each.mean, each.max), (fixed.mean, fixed.max));
    let mut doubled = forces.clone();
    doubled[3] *= 2.0;
    let d = robot
        .deflections_under(Variant::ThreeAxis, &place, &run, &doubled, None)
        .expect("reachable");
    assert!((d.dp[3] - fixed.dp[3] * 2.0).length() < 1e-12);
    assert_eq!(d.dp[4], fixed.dp[4]);
    assert!(d.max >= fixed.max);
    let e = robot
        .deflections_under(Variant::ThreeAxis, &place, &run, &forces[1..], None)
        .expect_err("one short");
    assert!(e.to_string().contains("one force a point"), "{e}");
}

/// A load per move (`PathLoad::PerMove`, what the force model with the
/// stock gives): the same load for every move deflects exactly as the
/// fixed load; a move with no load (in air) does not deflect, the others
/// as before; a move past the list has none.
#[test]
fn deflection_under_a_load_per_move() {
    let run = zigzag(0.3);
    let (robot, place) = (Robot::kr240(), place());
    let dirs = machining::feed_dirs(&run);
    let moves = run.iter().map(|p| p.mv).max().expect("points") as usize + 1;
    let fixed = robot
        .deflections_loaded(
            Variant::ThreeAxis,
            &place,
            &run,
            &dirs,
            &PathLoad::Fixed(LOAD),
            None,
        )
        .expect("reachable");
    let same = PathLoad::PerMove(vec![LOAD; moves]);
    let each = robot
        .deflections_loaded(Variant::ThreeAxis, &place, &run, &dirs, &same, None)
        .expect("reachable");
    assert_eq!(each.dp, fixed.dp);
    let mut air = vec![LOAD; moves];
    air[2] = Load {
        feed: 0.0,
        cross: 0.0,
        axial: 0.0,
    };
    let d = robot
        .deflections_loaded(
            Variant::ThreeAxis,
            &place,
            &run,
            &dirs,
            &PathLoad::PerMove(air),
            None,
        )
        .expect("reachable");
    for (i, p) in run.iter().enumerate() {
        if p.mv == 2 {
            assert_eq!(d.dp[i], DVec3::ZERO, "point {i}");
        } else {
            assert_eq!(d.dp[i], fixed.dp[i], "point {i}");
        }
    }
    let none = PathLoad::PerMove(Vec::new());
    let d = robot
        .deflections_loaded(Variant::ThreeAxis, &place, &run, &dirs, &none, None)
        .expect("reachable");
    assert_eq!((d.mean, d.max), (0.0, 0.0));
}

/// The angle of a rotation (rad), precise for small ones (from the
/// quaternion's vector part, not its scalar).
fn angle(r: &millplan_geom::DMat3) -> f64 {
    let q = glam::DQuat::from_mat3(r);
    2.0 * q.xyz().length().atan2(q.w.abs())
}

/// Offline compensation with the orientation corrected too (process-models
/// §4.4, "optionally the orientation"): the tool commanded to p − Δp and
/// turned by −Δθ, then pushed by the same load, lands within 1e-3 of |Δp|
/// of the nominal point and within 1e-3 of |Δθ| of the nominal orientation
/// (here under 0.1 µm and 1e-7 rad, against |Δp| up to 0.2 mm and |Δθ| up
/// to 2.4e-4 rad); without the correction the orientation is off by
/// the |Δθ| at the commanded point, within 1 % of that at the nominal one.
/// The position is the same with and without: the tilt moves no point.
#[test]
fn orientation_compensation_leaves_position_and_orientation_on_the_path() {
    let robot = Robot::kr240();
    let ideal = zigzag(5.0);
    let v = Variant::ThreeAxis;
    let d = robot
        .deflections(v, &place(), &ideal, &LOAD, None)
        .expect("reachable");
    let dirs = machining::feed_dirs(&ideal);
    let plain = compensate(&ideal, &d.dp);
    let posed = machining::compensate_pose(&ideal, &d);
    let at = |cmd: &[PathPoint]| {
        robot
            .deflections_along(v, &place(), cmd, &dirs, &LOAD, Some(d.status))
            .expect("reachable")
    };
    let (at_plain, at_posed) = (at(&plain), at(&posed));
    let mut worst = (0.0f64, 0.0f64);
    for i in 0..ideal.len() {
        assert_eq!(plain[i].p, posed[i].p);
        assert_eq!(posed[i].tilt, -d.dtheta[i]);
        let (dp, dth) = (d.dp[i].length(), d.dtheta[i].length());
        assert!(dth > 1e-5, "point {i}: the load turns the tool ({dth} rad)");
        // Landed position and orientation of the corrected command.
        let landed = posed[i].p + at_posed.dp[i];
        let r = machining::rotation(at_posed.dtheta[i]) * posed[i].orientation();
        let off = angle(&(r * ideal[i].orientation().transpose()));
        assert!((landed - ideal[i].p).length() < 1e-3 * dp, "point {i}");
        assert!(off < 1e-3 * dth, "point {i}: {off} vs {dth}");
        worst = (
            worst.0.max((landed - ideal[i].p).length()),
            worst.1.max(off),
        );
        // Without: the orientation is off by the whole turn.
        let r = machining::rotation(at_plain.dtheta[i]) * plain[i].orientation();
        let off = angle(&(r * ideal[i].orientation().transpose()));
        assert!((off - at_plain.dtheta[i].length()).abs() < 1e-12);
        assert!((off - dth).abs() < 0.01 * dth, "point {i}");
    }
    assert!(worst.0 < 1e-4 && worst.1 < 1e-7, "{worst:?}");
}

/// The corrected orientation in KRL: A, B, C are KUKA's Z-Y-X angles of
/// the turned tool (they read back to the same rotation); a point without
/// tilt is written with the A, B, C of its axis, unchanged.
#[test]
fn orientation_compensation_is_written_as_abc() {
    let robot = Robot::kr240();
    let ideal = zigzag(5.0);
    let d = robot
        .deflections(Variant::ThreeAxis, &place(), &ideal, &LOAD, None)
        .expect("reachable");
    let posed = machining::compensate_pose(&ideal, &d);
    let k = machining::krl_program("slot", std::slice::from_ref(&posed), &place(), 0.15);
    let abc: Vec<[f64; 3]> = k
        .statements
        .iter()
        .filter_map(|l| match &l.statement {
            millplan_nc::krl::Statement::Move {
                motion: millplan_nc::krl::Motion::Lin(p) | millplan_nc::krl::Motion::Ptp(p),
                ..
            } => Some(p.abc),
            _ => None,
        })
        .collect();
    assert_eq!(abc.len(), posed.len());
    let axis_abc = millplan_nc::krl::abc_for_axis(DVec3::Z);
    for (a, p) in abc.iter().zip(&posed) {
        let r = millplan_robot::pose::abc_to_matrix(*a);
        assert!((r - p.orientation())
            .to_cols_array()
            .iter()
            .all(|e| e.abs() < 1e-12));
        assert!(a.iter().zip(axis_abc).any(|(x, y)| (x - y).abs() > 1e-6));
    }
    assert_eq!(ideal[0].abc(), axis_abc);
}
