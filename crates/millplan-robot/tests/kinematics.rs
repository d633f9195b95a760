//! The KR 240 chain of Schnoes & Zaeh (Table 1) against process-models §4.1:
//! the home pose, the inverse kinematics, Status and Turn.

use millplan_geom::{DMat3, DVec3};
use millplan_robot::{Config, Joints, Pose, Robot};
use proptest::prelude::*;

const HOME: Joints = [0.0, -90.0, 90.0, 0.0, 0.0, 0.0];

fn rad(q: Joints) -> Joints {
    q.map(f64::to_radians)
}

/// §4.1 check 1: at KUKA's home pose (A2 −90°, A3 +90°) the flange lands in
/// front of the robot, x 1.5–1.6 m, z about 1.8 m. Equation 1's matrix is
/// T = Rx(α)·Trans(x, y, z)·Rz(θ) and lands it at (1550, 0, 1784) mm; the
/// literal "rotations first" reading Rz(θ)·Rx(α)·Trans(x, y, z) puts it at
/// (0, 2125, 59) mm, beside the robot near the floor.
#[test]
fn home_pose_lands_in_front_at_shoulder_height() {
    let robot = Robot::kr240();
    let mut frames = Vec::new();
    robot.frames(&rad(HOME), &mut frames);
    let flange = frames[7].t;
    assert!(
        (flange - DVec3::new(1550.0, 0.0, 1784.0)).length() < 1e-9,
        "{flange}"
    );
    assert!((1500.0..=1600.0).contains(&flange.x));
    assert!((1750.0..=1900.0).contains(&flange.z));
    // The flange faces forward (A5 = 0: along the forearm), the lower arm upright.
    assert!((frames[7].r.col(2) - DVec3::X).length() < 1e-12);
    assert!((frames[3].t - DVec3::new(350.0, 0.0, 1825.0)).length() < 1e-9);
    // A5 = +30° tips the flange down, as KUKA's A5 does.
    let mut q = HOME;
    q[4] = 30.0;
    robot.frames(&rad(q), &mut frames);
    assert!(frames[7].r.col(2).z < -0.49, "{}", frames[7].r.col(2));
    // The other reading of the table, for the record of why it was not taken.
    let other = rotations_first(&rad(HOME));
    assert!(
        (other - DVec3::new(0.0, 2125.0, 59.0)).length() < 1e-6,
        "{other}"
    );
}

/// The flange of Table 1 read as Rz(θ)·Rx(α)·Trans(x, y, z), θ = −q.
fn rotations_first(q: &Joints) -> DVec3 {
    let rows: [(usize, f64, [f64; 3]); 8] = [
        (1, 0.0, [0.0, 0.0, 225.0]),
        (2, 90.0, [350.0, 450.0, 0.0]),
        (0, 0.0, [575.0, 0.0, 0.0]),
        (3, 0.0, [575.0, 0.0, 0.0]),
        (0, 0.0, [41.0, 340.0, 0.0]),
        (4, -90.0, [0.0, 0.0, 340.0]),
        (5, 90.0, [0.0, 320.0, 0.0]),
        (6, -90.0, [0.0, 0.0, 200.0]),
    ];
    let mut r = DMat3::IDENTITY;
    let mut t = DVec3::ZERO;
    for (axis, alpha, xyz) in rows {
        let theta = if axis == 0 { 0.0 } else { -q[axis - 1] };
        let m = DMat3::from_rotation_z(theta) * DMat3::from_rotation_x(f64::to_radians(alpha));
        t += r * (m * DVec3::from_array(xyz));
        r *= m;
    }
    t
}

#[test]
fn home_pose_status_is_kukas_usual_one() {
    let robot = Robot::kr240();
    let mut q = HOME;
    q[4] = 30.0;
    // Basic area, A3 beyond the stretched arm, A5 > 0: Status 'B010'; A2 < 0: Turn 'B000010'.
    assert_eq!(robot.config(&rad(q)), Config { status: 2, turn: 2 });
}

fn assert_pose_near(a: &Pose, b: &Pose, tol: f64) {
    assert!((a.t - b.t).length() < tol, "{} vs {}", a.t, b.t);
    let d = (a.r - b.r).abs().to_cols_array();
    assert!(d.iter().all(|x| *x < tol), "{:?} vs {:?}", a.r, b.r);
}

/// Away from the singularities (wrist A5 = 0, wrist centre on A1, arm
/// stretched) the eight solutions are distinct and well conditioned.
fn regular(robot: &Robot, q: &Joints) -> bool {
    if q[4].abs() < 2f64.to_radians() {
        return false;
    }
    let mut frames = Vec::new();
    robot.frames(q, &mut frames);
    let wc = frames[6].t;
    let elbow = frames[3].t;
    let shoulder = frames[1].t;
    let (a, b) = (elbow - shoulder, wc - elbow);
    let sin_elbow = a.cross(b).length() / (a.length() * b.length());
    wc.truncate().length() > 100.0 && sin_elbow > 0.03
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// FK → IK with the configuration's Status and Turn → the same angles;
    /// over the whole workspace within the limits.
    #[test]
    fn ik_inverts_fk(u in proptest::array::uniform6(0.0f64..1.0)) {
        let robot = Robot::kr240();
        let mut q = [0.0; 6];
        for i in 0..6 {
            let [lo, hi] = robot.limits[i];
            q[i] = lo + (hi - lo) * u[i];
        }
        prop_assume!(regular(&robot, &q));
        let pose = robot.fk(&q);
        let cfg = robot.config(&q);
        let back = robot.ik(&pose, cfg).expect("solvable");
        for i in 0..6 {
            prop_assert!((back[i] - q[i]).abs() < 1e-7, "A{}: {} vs {} ({:?})", i + 1, back[i], q[i], q);
        }
        // Every other solution reaches the same pose too.
        for other in robot.ik_all(&pose, 0.0) {
            assert_pose_near(&robot.fk(&other), &pose, 1e-6);
        }
    }
}

#[test]
fn eight_configurations_of_one_pose() {
    let robot = Robot::kr240();
    let q = rad([10.0, -70.0, 100.0, 20.0, 40.0, -30.0]);
    let pose = robot.fk(&q);
    let all = robot.ik_all(&pose, 0.0);
    let statuses: std::collections::BTreeSet<u8> =
        all.iter().map(|q| robot.config(q).status).collect();
    assert!(statuses.len() >= 2, "{statuses:?} {all:?}");
    // Following a path: the nearest solution to the one before is the one before.
    let near = robot.ik_near(&pose, &q).expect("near");
    assert!(near.iter().zip(&q).all(|(a, b)| (a - b).abs() < 1e-9));
}

#[test]
fn feasibility_keeps_the_margins() {
    let robot = Robot::kr240();
    assert!(robot.feasible(&rad([0.0, -90.0, 90.0, 0.0, 30.0, 0.0])));
    assert!(
        !robot.feasible(&rad([0.0, -90.0, 90.0, 0.0, 3.0, 0.0])),
        "wrist singularity"
    );
    assert!(
        !robot.feasible(&rad([182.0, -90.0, 90.0, 0.0, 30.0, 0.0])),
        "A1 margin"
    );
    assert!(robot
        .ik(
            &Pose::new(DMat3::IDENTITY, DVec3::new(5000.0, 0.0, 0.0)),
            Config { status: 2, turn: 0 }
        )
        .is_err());
}

#[test]
fn robot_files_are_checked() {
    let bad = millplan_robot::robot::KR240_TOML.replacen("\nsign = -1", "\nsign = 2", 1);
    let e = Robot::from_toml(&bad).expect_err("sign");
    assert!(e.to_string().contains("sign must be 1 or -1"), "{e}");
    // The last row's α (A6): the wrist no longer meets in one point.
    let text = millplan_robot::robot::KR240_TOML;
    let at = text.rfind("alpha_deg = -90.0").expect("A6 row");
    let bad = format!("{}alpha_deg = -80.0{}", &text[..at], &text[at + 17..]);
    let e = Robot::from_toml(&bad).expect_err("wrist");
    assert!(e.to_string().contains("wrist"), "{e}");
    let bad = millplan_robot::robot::KR240_TOML.replacen("axis = 1", "axis = \"one\"", 1);
    let e = Robot::from_toml(&bad).expect_err("type");
    assert!(e.to_string().starts_with("19:8:"), "{e}");
}
