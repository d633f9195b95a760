//! The five-axis post (spec kinematics-access-tools §1.7–1.10, process-models
//! §2.5): round trips through every kinematics kind with offsets, the DP at
//! the pole, the §1.10 worked examples, T9a, the linearisation bound by
//! brute force, unreachable orientations and the feed words as written.

use millplan_geom::DVec3;
use millplan_models::kinematics::{Joints, KinKind, Kinematics, RotaryAxis};
use millplan_nc::write::{write_program, Target};
use millplan_nc::{parse_program, FeedMode, Operation, Program, ReadOptions};
use millplan_plan::machine::{InverseTimeF, Machine};
use millplan_plan::post::feed::{
    inverse_time_f, sampled_deviation, segment_distance, tip_deviation, tip_path_length,
    tip_path_length_from, tip_samples,
};
use millplan_plan::post::ik::{changes_side, closest_to_pole, is_flip, roles, Cand};
use millplan_plan::post::{post, PostError, PostOptions, Posted};
use millplan_plan::timing::Planner;

/// One CL record: rapid or not, tip, tool axis (normalised when written).
type Rec = (bool, [f64; 3], [f64; 3]);

/// An APT CL file of `recs` at `feed` mm/min (a rapid's `RAPID` on a line of
/// its own before its `GOTO`).
fn apt(recs: &[Rec], feed: f64) -> String {
    let mut s = format!("UNITS/MM\nFEDRAT/MMPM,{feed}\n");
    for (rapid, p, k) in recs {
        let k = DVec3::from_array(*k).normalize();
        let g = format!(
            "GOTO/{:.9},{:.9},{:.9},{:.12},{:.12},{:.12}\n",
            p[0], p[1], p[2], k.x, k.y, k.z
        );
        if *rapid {
            s += &format!("RAPID\n{g}");
        } else {
            s += &g;
        }
    }
    s
}

fn program(recs: &[Rec], feed: f64) -> Program {
    parse_program(&apt(recs, feed), ReadOptions::default())
        .expect("the CL file reads")
        .program
}

fn machine(k: Kinematics) -> Machine {
    Machine {
        kinematics: Some(k),
        ..Machine::default()
    }
}

/// The joints a posted move commands (machine coordinates, degrees).
fn joints_of(kin: &Kinematics, op: &Operation, i: usize) -> Joints {
    let m = &op.moves[i];
    let o = op.orient(m).expect("a posted move has its angles");
    let (f, s) = match kin.kind {
        KinKind::TableAc => (0, 2),
        KinKind::TableAb => (0, 1),
        _ => (1, 2),
    };
    Joints {
        xyz: m.end,
        first: o.angles[f].expect("first").to_degrees(),
        second: o.angles[s].expect("second").to_degrees(),
    }
}

/// The CL tips and axes of a program (no frame, every move a point).
fn cl_of(p: &Program) -> Vec<(DVec3, DVec3)> {
    let op = &p.operations[0];
    op.moves
        .iter()
        .map(|m| (m.end, op.axis(m).expect("axis").normalize()))
        .collect()
}

/// Every CL point is reproduced, in order, by forward kinematics of some
/// posted block (tip within `tol`, axis within `ang` radians); every posted
/// block's tip lies on the CL polyline.
fn assert_round_trip(
    kin: &Kinematics,
    cl: &[(DVec3, DVec3)],
    posted: &Program,
    tol: f64,
    ang: f64,
) {
    let op = &posted.operations[0];
    let mut next = 0;
    for i in 0..op.moves.len() {
        let (tip, k) = kin.forward(&joints_of(kin, op, i));
        let on_path = (1..cl.len())
            .map(|s| segment_distance(tip, cl[s - 1].0, cl[s].0))
            .fold(f64::INFINITY, f64::min);
        assert!(
            on_path <= tol,
            "block {i}: tip {tip:?} is {on_path} mm off the CL path"
        );
        if next < cl.len() && (tip - cl[next].0).length() <= tol && (k - cl[next].1).length() <= ang
        {
            next += 1;
        }
    }
    assert_eq!(next, cl.len(), "CL point {next} is never reproduced");
}

/// A path whose tool axis tilts and turns (polar 15°…50°, azimuth over
/// 200°), with a rapid in the middle: never near a pole of any kind.
fn swinging_path() -> Vec<Rec> {
    (0..40)
        .map(|i| {
            let t = i as f64 / 39.0;
            let polar = (15.0 + 35.0 * t).to_radians();
            let az = (-60.0 + 200.0 * t).to_radians();
            let k = [polar.sin() * az.cos(), polar.sin() * az.sin(), polar.cos()];
            (
                i == 20,
                [10.0 + 30.0 * t, -5.0 + 12.0 * t, 20.0 - 8.0 * t],
                k,
            )
        })
        .collect()
}

fn kinds_with_offsets() -> Vec<Kinematics> {
    [
        KinKind::TableAc,
        KinKind::TableBc,
        KinKind::TableAb,
        KinKind::HeadBc,
        KinKind::HeadBTableC,
    ]
    .into_iter()
    .map(|kind| Kinematics {
        rot_point: [10.0, -5.0, 2.0],
        offset: match kind {
            KinKind::TableAc => [0.0, 3.0, 20.0],
            _ => [-4.0, 0.0, 20.0],
        },
        tool_offset: 100.0,
        pivot: 250.0,
        ..Kinematics::new(kind)
    })
    .collect()
}

/// Spec §1 (round trips, §5 "any FK→IK→FK identity"): every kinematics
/// kind with axis offsets, machine coordinates and TCP.
#[test]
fn posted_axes_reproduce_every_cl_tip_and_axis_for_every_kind() {
    let recs = swinging_path();
    let p = program(&recs, 1000.0);
    let cl = cl_of(&p);
    for kin in kinds_with_offsets() {
        for tcp in [false, true] {
            let o = PostOptions {
                tcp,
                ..PostOptions::default()
            };
            let posted = post(&p, &machine(kin.clone()), &o).expect("posts");
            assert!(posted.report.max_tip_error_mm < 1e-9, "{:?}", kin.kind);
            assert!(posted.report.flips.is_empty(), "{:?}", kin.kind);
            if tcp {
                // The tips themselves, and the angles give the axes.
                let op = &posted.program.operations[0];
                assert_eq!(op.moves.len(), cl.len());
                for (i, (tip, k)) in cl.iter().enumerate() {
                    let j = joints_of(&kin, op, i);
                    assert!((op.moves[i].end - *tip).length() < 1e-12);
                    assert!((kin.tool_axis(j.first, j.second) - *k).length() < 1e-9);
                }
            } else {
                assert_round_trip(&kin, &cl, &posted.program, 1e-9, 1e-9);
            }
        }
    }
}

/// The same through the written G-code and the reader (four decimals of
/// position and angle): within 2 µm of the rounding, for every kind and
/// every dialect.
#[test]
fn written_programs_read_back_to_the_cl_tips() {
    let recs = swinging_path();
    let p = program(&recs, 1000.0);
    let cl = cl_of(&p);
    for kin in kinds_with_offsets() {
        let m = machine(kin.clone());
        let posted = post(&p, &m, &PostOptions::default()).expect("posts");
        for target in [
            Target::Fanuc,
            Target::Sinumerik,
            Target::Heidenhain,
            Target::LinuxCnc,
        ] {
            let mut wo = m.write_options(target);
            wo.auto_tcp = false;
            let (text, _) = write_program(&posted.program, wo).expect("writes");
            let text = String::from_utf8(text).expect("utf-8");
            let back = parse_program(&text, ReadOptions::default())
                .expect("reads back")
                .program;
            assert_eq!(back.move_count(), posted.program.move_count(), "{target:?}");
            // Four decimals of a degree at up to ~300 mm from the pivot.
            assert_round_trip(&kin, &cl, &back, 2e-3, 1e-5);
        }
    }
}

/// Spec §1.7 rule 3 and §1.8: a cut that passes 0.3° from the pole is
/// posted without a branch change and with the turning axis held inside the
/// pole cone (3° here), the tilt passing through zero and the pole blocks
/// reported; without the cone the exact IK swings the turning axis by about
/// 180° across the same cut.
#[test]
fn the_dp_never_flips_a_branch_in_a_cut_across_the_pole() {
    let recs: Vec<Rec> = (0..=40)
        .map(|i| {
            let t = (20.0 - i as f64).to_radians();
            let off = 0.3f64.to_radians();
            (
                (i == 0),
                [i as f64, 0.0, 0.0],
                [t.sin(), off.sin(), t.cos()],
            )
        })
        .collect();
    let p = program(&recs, 800.0);
    for kin in kinds_with_offsets()
        .into_iter()
        .filter(|k| k.kind != KinKind::TableAb)
    {
        let ro = roles(kin.kind);
        let travel = |cone: f64| -> (f64, Posted) {
            let o = PostOptions {
                pole_cone: cone,
                pole_tol: 3.0,
                ..PostOptions::default()
            };
            let posted = post(&p, &machine(kin.clone()), &o).expect("posts");
            let op = &posted.program.operations[0];
            let mut c_travel = 0.0;
            let mut tilt_signs = (false, false);
            for i in 1..op.moves.len() {
                let (a, b) = (joints_of(&kin, op, i - 1), joints_of(&kin, op, i));
                let ca = Cand {
                    first: a.first,
                    second: a.second,
                    dev: 0.0,
                };
                let cb = Cand {
                    first: b.first,
                    second: b.second,
                    dev: 0.0,
                };
                assert!(op.moves[i].is_cutting());
                assert!(
                    !is_flip(ro, &ca, &cb),
                    "{:?}: flip in the cut at move {i}",
                    kin.kind
                );
                c_travel += (b.second - a.second).abs();
                tilt_signs.0 |= b.first > 1.0;
                tilt_signs.1 |= b.first < -1.0;
            }
            // Held, the tilt passes through zero; exact, it stays on one side.
            assert_eq!(tilt_signs.0 && tilt_signs.1, cone > 0.0, "{:?}", kin.kind);
            (c_travel, posted)
        };
        let (held, posted) = travel(3.0);
        let r = &posted.report;
        assert!(r.flips.is_empty(), "{:?}", kin.kind);
        assert!(r.pole_blocks >= 5, "{:?}: {}", kin.kind, r.pole_blocks);
        assert!(
            r.max_orientation_deviation_deg > 0.0 && r.max_orientation_deviation_deg <= 3.0 + 1e-9
        );
        assert!(r.pole_flagged.is_empty());
        assert!(held < 30.0, "{:?}: C travels {held}°", kin.kind);
        let (exact, _) = travel(0.0);
        assert!(
            exact > 90.0,
            "{:?}: C travels {exact}° without the cone",
            kin.kind
        );
    }
}

/// A/C table, C travel [−150°, 40°]: turning the azimuth from 0° to 60° at a
/// 30° tilt needs the other branch past 40°. Inside a cut that is refused
/// at the line that needs it; across a rapid it is made there, with a
/// retract, rotation and approach, and reported.
#[test]
fn a_forced_branch_change_happens_only_across_a_rapid() {
    let kin = Kinematics {
        second: RotaryAxis {
            min: Some(-150.0),
            max: Some(40.0),
            sign: 1.0,
        },
        ..Kinematics::new(KinKind::TableAc)
    };
    let recs = |rapid_at: Option<usize>| -> Vec<Rec> {
        (0..=12)
            .map(|i| {
                let az = (5.0 * i as f64).to_radians();
                let t = 30f64.to_radians();
                (
                    Some(i) == rapid_at || i == 0,
                    [i as f64, 0.0, 0.0],
                    [t.sin() * az.sin(), t.sin() * az.cos(), t.cos()],
                )
            })
            .collect()
    };
    let e = post(
        &program(&recs(None), 500.0),
        &machine(kin.clone()),
        &PostOptions::default(),
    )
    .expect_err("refused");
    match e {
        PostError::FlipInCut { line } => assert!((4..=15).contains(&line), "{line}"),
        other => panic!("{other:?}"),
    }
    let posted = post(
        &program(&recs(Some(7)), 500.0),
        &machine(kin.clone()),
        &PostOptions::default(),
    )
    .expect("posts");
    let r = &posted.report;
    assert_eq!(r.flips.len(), 1);
    // Record k ≥ 1 is on line 4 + k, a rapid's GOTO one further.
    assert_eq!(r.flips[0].line, 7 + 5, "the rapid's line");
    assert_eq!(r.flip_moves, 3);
    // The retract leaves along the old axis by the clearance.
    let op = &posted.program.operations[0];
    let i = op
        .moves
        .iter()
        .position(|m| m.line == 12)
        .expect("flip moves");
    let (up, _) = kin.forward(&joints_of(&kin, op, i));
    let (before, k) = kin.forward(&joints_of(&kin, op, i - 1));
    assert!((up - (before + k * 50.0)).length() < 1e-9);
}

/// Spec §1.10 worked examples and §5 "G93" oracles (xyzac, no offsets,
/// joints linearly interpolated), tolerance 1e-4.
#[test]
fn inverse_time_worked_examples() {
    let kin = Kinematics::new(KinKind::TableAc);
    let j = |x: f64, y: f64, z: f64, a: f64, c: f64| Joints {
        xyz: DVec3::new(x, y, z),
        first: a,
        second: c,
    };
    let l = tip_path_length(
        &kin,
        &j(50.0, 0.0, 0.0, 0.0, 0.0),
        &j(50.0, 0.0, 0.0, 0.0, 90.0),
    );
    assert!((l - 78.539816).abs() < 1e-4, "{l}");
    assert!((l - 25.0 * std::f64::consts::PI).abs() < 1e-4);
    assert!((inverse_time_f(l, 1000.0) - 12.732395).abs() < 1e-4);
    // The chord, wrong for a non-TCP machine.
    let chord =
        (kin.forward(&j(50.0, 0.0, 0.0, 0.0, 90.0)).0 - DVec3::new(50.0, 0.0, 0.0)).length();
    assert!((chord - 70.710678).abs() < 1e-6);
    assert!((inverse_time_f(chord, 1000.0) - 14.142136).abs() < 1e-6);
    let (a, b) = (
        j(20.0, 10.0, 30.0, 0.0, 0.0),
        j(25.0, 10.0, 28.0, 30.0, 45.0),
    );
    let l = tip_path_length(&kin, &a, &b);
    assert!((l - 21.892250).abs() < 1e-4, "{l}");
    assert!((inverse_time_f(l, 800.0) - 36.542611).abs() < 1e-4);
    // End to end: the CL move the second example stands for, posted in G93
    // without linearisation, gets that F word.
    let (p0, _) = kin.forward(&a);
    let (p1, k1) = kin.forward(&b);
    let p = program(
        &[
            (true, p0.to_array(), [0.0, 0.0, 1.0]),
            (false, p1.to_array(), k1.to_array()),
        ],
        800.0,
    );
    let o = PostOptions {
        g93: true,
        tol: 10.0,
        ..PostOptions::default()
    };
    let posted = post(&p, &machine(kin.clone()), &o).expect("posts");
    let m = posted.program.operations[0].moves[1];
    assert_eq!(m.feed_mode, FeedMode::InverseTime);
    assert!((m.feed - 36.542611).abs() < 1e-4, "{}", m.feed);
}

/// Process-models T9a: s = 0.5 mm at v_f = fpt·N·n = 0.16·4·1750 = 1120
/// mm/min takes 4.4643e-4 min, F = 2240 (1/min) — here on a tilted tool
/// with the feed given per revolution (0.64 mm at 1750 1/min).
#[test]
fn t9a_g93_word() {
    let kin = Kinematics::new(KinKind::TableAc);
    let k = kin.tool_axis(30.0, 45.0).to_array();
    let src = format!(
        "UNITS/MM\nSPINDL/RPM,1750,CLW\nRAPID\nGOTO/1,2,3,{},{},{}\nFEDRAT/MMPR,0.64\nGOTO/1.5,2,3,{},{},{}\n",
        k[0], k[1], k[2], k[0], k[1], k[2]
    );
    let p = parse_program(&src, ReadOptions::default())
        .expect("reads")
        .program;
    let o = PostOptions {
        g93: true,
        ..PostOptions::default()
    };
    let m = machine(kin);
    let posted = post(&p, &m, &o).expect("posts");
    let mv = posted.program.operations[0].moves[1];
    assert!((mv.feed - 2240.0).abs() < 1e-9, "{}", mv.feed);
    // The block's time as the report sums it (the rapid before it has no
    // known start, so no time).
    let nominal_min = posted.report.nominal_s / 60.0;
    assert!((nominal_min - 4.4643e-4).abs() < 1e-8, "{nominal_min}");
    let (text, _) = write_program(&posted.program, m.write_options(Target::Fanuc)).expect("writes");
    let text = String::from_utf8(text).expect("utf-8");
    assert!(text.contains("G93") && text.contains("F2240."), "{text}");
    // The control is left in G94.
    assert!(
        text.trim_end()
            .lines()
            .rev()
            .take(3)
            .any(|l| l.contains("G94")),
        "{text}"
    );
}

/// §1.10 controller variance: a control that reads G93 F as seconds gets
/// 60/2240 s; one that refuses G0 under G93 gets G94 before each rapid.
#[test]
fn g93_semantics_follow_the_machine_file() {
    let kin = Kinematics::new(KinKind::TableAc);
    let k = kin.tool_axis(30.0, 45.0).to_array();
    let recs: Vec<Rec> = vec![
        (true, [1.0, 2.0, 3.0], k),
        (false, [1.56, 2.0, 3.0], k),
        (true, [1.56, 2.0, 30.0], k),
        (false, [1.56, 2.0, 3.0], k),
    ];
    let p = program(&recs, 1120.0);
    let mut m = machine(kin);
    m.control.g93_f = InverseTimeF::Seconds;
    m.control.g93_rapids = false;
    let o = PostOptions {
        g93: true,
        ..PostOptions::default()
    };
    let posted = post(&p, &m, &o).expect("posts");
    let (text, _) = write_program(&posted.program, m.write_options(Target::Fanuc)).expect("writes");
    let text = String::from_utf8(text).expect("utf-8");
    // 0.56 mm at 1120 mm/min: 0.03 s.
    assert!(text.contains("F0.03"), "{text}");
    let after = &text[text.find("G93").expect("G93")..];
    let rapid = after.lines().find(|l| l.contains("G0")).expect("the rapid");
    assert!(rapid.contains("G94") && rapid.contains("G0"), "{rapid}");
}

/// §1.7.5 linearisation, checked by brute force: 2000 samples of the tip
/// path of every posted cutting block (joints moving linearly) stay within
/// the tolerance of the CL segment; without linearisation they would not.
#[test]
fn linearised_tip_path_stays_within_tolerance() {
    let recs = swinging_path();
    let p = program(&recs, 1000.0);
    for kin in kinds_with_offsets() {
        let m = machine(kin.clone());
        let check = |posted: &Posted| -> f64 {
            let op = &posted.program.operations[0];
            let mut worst: f64 = 0.0;
            for i in 1..op.moves.len() {
                if !op.moves[i].is_cutting() {
                    continue;
                }
                let (a, b) = (joints_of(&kin, op, i - 1), joints_of(&kin, op, i));
                let (pa, pb) = (kin.forward(&a).0, kin.forward(&b).0);
                for s in 1..2000 {
                    let s = s as f64 / 2000.0;
                    let j = millplan_plan::post::feed::lerp(&a, &b, s);
                    worst = worst.max(segment_distance(kin.forward(&j).0, pa, pb));
                }
            }
            worst
        };
        let tol = 0.005;
        let posted = post(
            &p,
            &m,
            &PostOptions {
                tol,
                ..PostOptions::default()
            },
        )
        .expect("posts");
        assert!(posted.report.inserted_points > 0, "{:?}", kin.kind);
        let worst = check(&posted);
        assert!(worst <= tol, "{:?}: {worst} mm", kin.kind);
        let loose = post(
            &p,
            &m,
            &PostOptions {
                tol: 10.0,
                ..PostOptions::default()
            },
        )
        .expect("posts");
        assert!(
            check(&loose) > tol,
            "{:?}: the test path needs linearisation",
            kin.kind
        );
    }
}

/// An orientation outside the rotary travel stops the post at its CL line,
/// naming the axis.
#[test]
fn unreachable_orientation_names_the_line_and_the_axis() {
    let kin = Kinematics {
        first: RotaryAxis {
            min: Some(-30.0),
            max: Some(30.0),
            sign: 1.0,
        },
        ..Kinematics::new(KinKind::TableAc)
    };
    let t = 60f64.to_radians();
    let recs: Vec<Rec> = vec![
        (true, [0.0, 0.0, 10.0], [0.0, 0.0, 1.0]),
        (false, [1.0, 0.0, 10.0], [0.0, 0.1, 1.0]),
        (false, [2.0, 0.0, 10.0], [0.0, t.sin(), t.cos()]),
    ];
    let e = post(
        &program(&recs, 500.0),
        &machine(kin),
        &PostOptions::default(),
    )
    .expect_err("refused");
    match &e {
        PostError::Unreachable { line, axis, .. } => assert_eq!((*line, *axis), (6, 'A'), "{e}"),
        other => panic!("{other:?}"),
    }
    assert!(e.is_check());
    assert!(
        e.to_string().starts_with("6:1: axis A runs out of range"),
        "{e}"
    );
}

/// G94 in machine coordinates: the control applies F to the joints' XYZ
/// distance, so F = that distance / (tip path / tip feed).
#[test]
fn g94_feed_is_converted_to_the_joint_distance() {
    let recs = swinging_path();
    let p = program(&recs, 1000.0);
    let kin = kinds_with_offsets().remove(0);
    let posted = post(&p, &machine(kin.clone()), &PostOptions::default()).expect("posts");
    let op = &posted.program.operations[0];
    let mut checked = 0;
    for i in 1..op.moves.len() {
        let m = &op.moves[i];
        if !m.is_cutting() || op.moves[i - 1].is_rapid() && i == 1 {
            continue;
        }
        let (a, b) = (joints_of(&kin, op, i - 1), joints_of(&kin, op, i));
        let minutes = tip_path_length(&kin, &a, &b) / 1000.0;
        let want = (b.xyz - a.xyz).length() / minutes;
        assert!(
            (m.feed - want).abs() <= 1e-9 * want,
            "move {i}: {} vs {want}",
            m.feed
        );
        assert_eq!(m.feed_mode, FeedMode::PerMinute);
        checked += 1;
    }
    assert!(checked > 30);
}

/// A G94 block that turns the table 90° while X, Y and Z move a few µm
/// would need an F below the machine's lowest feed: it is written in G93
/// (§1.10.4: its time from the rotary axis's top speed) and counted.
#[test]
fn a_g94_block_below_the_lowest_feed_is_written_in_g93() {
    let kin = Kinematics::new(KinKind::TableAc);
    let (k0, k1) = (kin.tool_axis(30.0, 0.0), kin.tool_axis(30.0, 90.0));
    let recs: Vec<Rec> = vec![
        (true, [0.001, 0.0, 0.0], k0.to_array()),
        (false, [0.001, 0.0, 0.0], k1.to_array()),
    ];
    let mut m = machine(kin);
    m.axes.second.velocity = Some(18000.0);
    let posted = post(&program(&recs, 1000.0), &m, &PostOptions::default()).expect("posts");
    let mv = posted.program.operations[0].moves[1];
    assert_eq!(posted.report.g93_blocks, 1);
    assert_eq!(mv.feed_mode, FeedMode::InverseTime);
    // 90° at 18000 °/min: 0.005 min, F = 200.
    assert!((mv.feed - 200.0).abs() < 1e-6, "{}", mv.feed);
}

/// Under TCP, LinuxCNC gets a comment (its TCP is the loaded kinematics)
/// and Fanuc, whose G43.4 needs a tool number, refuses an operation
/// without one; Sinumerik and Heidenhain write TRAORI and M128.
#[test]
fn tcp_words_per_control() {
    let kin = Kinematics::new(KinKind::TableAc);
    let k = kin.tool_axis(20.0, 10.0).to_array();
    let p = program(
        &[(true, [0.0, 0.0, 5.0], k), (false, [5.0, 0.0, 5.0], k)],
        500.0,
    );
    let m = machine(kin);
    let o = PostOptions {
        tcp: true,
        ..PostOptions::default()
    };
    let posted = post(&p, &m, &o).expect("posts");
    for (target, word) in [
        (Target::Sinumerik, "TRAORI"),
        (Target::Heidenhain, "M128"),
        (Target::LinuxCnc, "TCP KINEMATICS"),
    ] {
        let mut q = posted.program.clone();
        millplan_plan::post::for_target(&mut q, target).expect("fits");
        let mut wo = m.write_options(target);
        wo.auto_tcp = false;
        let (text, _) = write_program(&q, wo).expect("writes");
        let text = String::from_utf8(text).expect("utf-8");
        assert!(text.contains(word), "{target:?}: {text}");
    }
    let mut q = posted.program.clone();
    let e = millplan_plan::post::for_target(&mut q, Target::Fanuc).expect_err("no tool number");
    assert!(e.to_string().contains("G43.4"), "{e}");
}

/// `[post]` in the machine file: read, defaulted, and checked against its
/// ranges with the field named.
#[test]
fn machine_file_post_settings() {
    let base = "[spindle]\nmin = 100.0\nmax = 20000.0\naccel = 5000.0\n[feed]\nmax = 20000.0\n[kinematics]\nkind = \"table-ac\"\n";
    let m = Machine::from_toml(base).expect("reads");
    assert_eq!(m.post, millplan_plan::machine::PostSettings::default());
    assert_eq!(
        (m.post.pole_cone, m.post.pole_tol, m.post.clearance),
        (1.0, 1.0, 50.0)
    );
    let m = Machine::from_toml(&format!(
        "{base}[post]\npole_cone = 2.5\nclearance = 20.0\n"
    ))
    .expect("reads");
    assert_eq!(
        (m.post.pole_cone, m.post.pole_tol, m.post.clearance),
        (2.5, 1.0, 20.0)
    );
    let e = Machine::from_toml(&format!("{base}[post]\npole_cone = 45.0\n")).expect_err("refused");
    assert_eq!(e.field.as_deref(), Some("post.pole_cone"), "{e}");
    assert!(e.at.is_some(), "located: {e}");
    let e = Machine::from_toml(&format!("{base}[post]\nclearence = 5.0\n")).expect_err("typo");
    assert!(e.to_string().contains("clearence"), "{e}");
}

/// §1.9: a block whose rotary travel the axis cannot make in the time the
/// tip feed gives is slowed to the axis's top speed, and counted.
#[test]
fn a_block_too_fast_for_a_rotary_axis_is_slowed() {
    let kin = Kinematics::new(KinKind::TableAc);
    // A tilts from 10° to 40° while the tip moves 1 mm at 6000 mm/min
    // (0.01 min): 3000 °/min, where A makes 900 °/min.
    let (k0, k1) = (kin.tool_axis(10.0, 0.0), kin.tool_axis(40.0, 0.0));
    let recs: Vec<Rec> = vec![
        (true, [0.0, 0.0, 0.0], k0.to_array()),
        (false, [1.0, 0.0, 0.0], k1.to_array()),
    ];
    let mut m = machine(kin);
    m.axes.first.velocity = Some(900.0);
    let o = PostOptions {
        g93: true,
        tol: 10.0,
        ..PostOptions::default()
    };
    let posted = post(&program(&recs, 6000.0), &m, &o).expect("posts");
    assert_eq!(posted.report.slowed_blocks, 1);
    let mv = posted.program.operations[0].moves[1];
    // 30° at 900 °/min: 1/30 min, F = 30.
    assert!((mv.feed - 30.0).abs() < 1e-9, "{}", mv.feed);
    // Without the limit, the tip feed decides.
    m.axes.first.velocity = None;
    let posted = post(&program(&recs, 6000.0), &m, &o).expect("posts");
    assert_eq!(posted.report.slowed_blocks, 0);
    assert!(posted.program.operations[0].moves[1].feed > 30.0);
}

/// The linearisation's samples of a block give its tip path length and
/// deviation to the bit, whatever the rotary turn (none, one step of 2°,
/// 2, 4 or many steps): the post measures an unsplit block once.
#[test]
fn sampled_tip_length_is_the_tip_length_to_the_bit() {
    let mut kin = Kinematics::new(KinKind::TableAc);
    kin.rot_point = [3.0, -7.0, -100.0];
    let p0 = DVec3::new(1.0, 2.0, 3.0);
    let p1 = DVec3::new(1.3, 2.1, 2.9);
    for turn in [0.0, 1e-13, 0.37, 1.9, 2.0, 3.5, 4.0, 6.2, 8.0, 9.0, 47.0] {
        let a = Joints {
            xyz: DVec3::new(10.0, -4.0, 25.0),
            first: -12.5,
            second: 33.0,
        };
        let b = Joints {
            xyz: DVec3::new(10.05, -3.97, 25.02),
            first: -12.5 + turn * 0.4,
            second: 33.0 - turn,
        };
        let s = tip_samples(&kin, &a, &b);
        assert_eq!(s.is_none(), turn < 1e-12, "{turn}");
        assert_eq!(
            tip_path_length_from(&kin, &a, &b, s.as_ref()).to_bits(),
            tip_path_length(&kin, &a, &b).to_bits(),
            "{turn}"
        );
        assert_eq!(
            sampled_deviation(s.as_ref(), p0, p1).to_bits(),
            tip_deviation(&kin, &a, &b, p0, p1).to_bits(),
            "{turn}"
        );
    }
}

/// The A/C trunnion of examples/machine.toml: pivot 120 mm below the
/// table, A from −120° to 30°.
fn example_trunnion() -> Kinematics {
    Kinematics {
        rot_point: [0.0, 0.0, -120.0],
        first: RotaryAxis {
            min: Some(-120.0),
            max: Some(30.0),
            sign: 1.0,
        },
        ..Kinematics::new(KinKind::TableAc)
    }
}

/// A leaned ball-end raster (`millplan orient` on the demo part) turns its
/// near-vertical tool axis by 110° about the pole from one row to the next,
/// 2.2° from it at the closest, outside the 0.5° pole cone. Taking the tilt
/// to its other side there (A from +7° to −3°, C by 70° instead of 110°) is
/// the other IK branch: the axis would pass through the pole, which the CL
/// never does, and the linearisation halving toward it left blocks a few µm
/// long whose tip swept tens of mm off the path. The cut keeps its side,
/// and every block's tip stays on the CL line.
#[test]
fn a_cut_passing_near_the_pole_keeps_its_branch() {
    let recs: Vec<Rec> = vec![
        (
            false,
            [0.673849, 7.23676, 0.149427],
            [-0.134769718, 0.152648082, 0.979048357],
        ),
        (
            false,
            [0.639085, 8.235919, 0.1414],
            [-0.127816923, 0.152816228, 0.979954098],
        ),
        (
            false,
            [-0.190404, 9.940641, 0.041731],
            [0.03808071, 0.011871814, 0.999204143],
        ),
        (
            false,
            [0.805991, 9.901635, 0.155743],
            [0.038801793, 0.019673088, 0.999053247],
        ),
    ];
    let p = program(&recs, 2000.0);
    let kin = example_trunnion();
    let ro = roles(KinKind::TableAc);
    let near = closest_to_pole(
        ro,
        DVec3::from_array(recs[1].2).normalize(),
        DVec3::from_array(recs[2].2).normalize(),
    );
    assert!(
        near > 1.0 && near < 3.0,
        "the CL passes {near}° from the pole"
    );
    let o = PostOptions {
        pole_cone: 0.5,
        pole_tol: 0.5,
        ..PostOptions::default()
    };
    let posted = post(&p, &machine(kin.clone()), &o).expect("posts");
    let op = &posted.program.operations[0];
    let cand = |j: &Joints| Cand {
        first: j.first,
        second: j.second,
        dev: 0.0,
    };
    for i in 1..op.moves.len() {
        let (a, b) = (joints_of(&kin, op, i - 1), joints_of(&kin, op, i));
        assert!(
            !changes_side(ro, &cand(&a), &cand(&b)),
            "block {i}: A {} -> {} changes side in the cut",
            a.first,
            b.first
        );
        let (ta, tb) = (kin.forward(&a).0, kin.forward(&b).0);
        let dev = tip_deviation(&kin, &a, &b, ta, tb);
        assert!(dev <= o.tol, "block {i}: the tip strays {dev} mm inside it");
    }
    assert_round_trip(&kin, &cl_of(&p), &posted.program, 1e-6, 1e-6);
}

/// A block can take no less than the control's block cycle: a cut of a few
/// µm (as the linearisation leaves where it halves toward the pole cone's
/// edge) at 2000 mm/min would ask G93 for F 4·10⁵ (a 0.15 ms block) where
/// the control needs 1 ms; the post writes what the control will do,
/// F = 1/(1 ms) = 60 000 1/min, and counts the block as slowed.
#[test]
fn no_block_is_posted_shorter_than_the_block_cycle() {
    let recs: Vec<Rec> = vec![
        (false, [0.0, 0.0, 0.0], [0.1, 0.0, 1.0]),
        (false, [10.0, 0.0, 0.0], [0.1, 0.0, 1.0]),
        (false, [10.005, 0.0, 0.0], [0.1, 0.0, 1.0]),
        (false, [20.0, 0.0, 0.0], [0.1, 0.0, 1.0]),
    ];
    let p = program(&recs, 2000.0);
    let o = PostOptions {
        g93: true,
        ..PostOptions::default()
    };
    let f_of = |block_time_s: f64| {
        let mut m = machine(Kinematics::new(KinKind::TableAc));
        m.control.planner = Planner {
            block_time_s,
            ..Planner::default()
        };
        let posted = post(&p, &m, &o).expect("posts");
        let op = &posted.program.operations[0];
        let short = op.moves.iter().map(|m| m.feed).fold(0.0f64, f64::max);
        (short, posted.report.slowed_blocks)
    };
    let (free, slowed_free) = f_of(0.0);
    assert!((free - 2000.0 / 0.005).abs() < 1e-6 * free, "{free}");
    let (capped, slowed) = f_of(0.001);
    assert!((capped - 60_000.0).abs() < 1e-6, "{capped}");
    assert_eq!(slowed, slowed_free + 1);
}

/// A G94 F is the feed of the joints, which the control holds to its
/// maximum cutting feed: where the table turns, the joints move much
/// further than the tip (17 mm for a 1 mm cut turning A by 10° about a
/// pivot 100 mm below), and a block at the CL's 1000 mm/min would need
/// F17000 on a machine whose top feed is 5000. It is written at most 5000
/// and counted as slowed.
#[test]
fn no_g94_block_asks_more_than_the_machines_top_feed() {
    let tilt = |deg: f64| {
        let a = deg.to_radians();
        [0.0, a.sin(), a.cos()]
    };
    let recs: Vec<Rec> = vec![
        (false, [0.0, 0.0, 0.0], tilt(0.0)),
        (false, [1.0, 0.0, 0.0], tilt(10.0)),
        (false, [2.0, 0.0, 0.0], tilt(10.0)),
    ];
    let p = program(&recs, 1000.0);
    let kin = Kinematics {
        rot_point: [0.0, 0.0, -100.0],
        ..Kinematics::new(KinKind::TableAc)
    };
    let top = |feed_max: f64| {
        let mut m = machine(kin.clone());
        m.feed_max = feed_max;
        let posted = post(&p, &m, &PostOptions::default()).expect("posts");
        let f = posted.program.operations[0]
            .moves
            .iter()
            .filter(|m| m.feed_mode == FeedMode::PerMinute && m.is_cutting())
            .map(|m| m.feed)
            .fold(0.0f64, f64::max);
        (f, posted.report.slowed_blocks)
    };
    let (free, slowed_free) = top(1e6);
    assert!(free > 10_000.0, "{free}");
    let (capped, slowed) = top(5000.0);
    assert!((capped - 5000.0).abs() < 1e-6, "{capped}");
    assert!(slowed > slowed_free);
}

/// A cut whose tool axis passes 0.49° from the pole, inside the 0.5° cone,
/// 59.6 mm from the C axis of a table (a pass-end link of a leaned raster):
/// the tilt crosses zero while C sweeps about 160° with the tip all but
/// still. Where the linearisation inserted a point inside the cone it held
/// C at the mean of the block's ends, leaving an 11° jump of C at the cone's
/// edge that no halving removed: blocks whose tip swept 0.28 mm off a
/// 0.02 mm cut. A point entering or leaving the cone now holds its outside
/// end's C, and every block's tip stays within the tolerance.
#[test]
fn a_cut_through_the_pole_cone_keeps_its_tip_on_the_path() {
    let recs: Vec<Rec> = vec![
        (
            false,
            [59.360414, 0.042968, -0.08217],
            [-0.072082812, -0.008593625, 0.997361628],
        ),
        (
            false,
            [59.585272, 0.042971, -0.044769],
            [-0.067054571, -0.008594141, 0.997712296],
        ),
        (
            false,
            [59.583525, 0.042976, -0.023818],
            [-0.01670506, -0.008595093, 0.999823517],
        ),
        (
            false,
            [59.582837, 0.042977, -0.002911],
            [0.033432707, -0.008595528, 0.999404008],
        ),
        (
            false,
            [59.957674, -0.416155, 0.017892],
            [0.008465259, 0.083230959, 0.996494329],
        ),
    ];
    let p = program(&recs, 1500.0);
    let kin = example_trunnion();
    let ro = roles(KinKind::TableAc);
    let k = |i: usize| DVec3::from_array(recs[i].2).normalize();
    let near = closest_to_pole(ro, k(2), k(3));
    assert!(near > 0.45 && near < 0.5, "{near}");
    let o = PostOptions {
        pole_cone: 0.5,
        pole_tol: 0.5,
        ..PostOptions::default()
    };
    let posted = post(&p, &machine(kin.clone()), &o).expect("posts");
    assert!(posted.report.pole_blocks > 0);
    let op = &posted.program.operations[0];
    let mut worst: f64 = 0.0;
    for i in 1..op.moves.len() {
        let (a, b) = (joints_of(&kin, op, i - 1), joints_of(&kin, op, i));
        let (ta, tb) = (kin.forward(&a).0, kin.forward(&b).0);
        worst = worst.max(tip_deviation(&kin, &a, &b, ta, tb));
    }
    assert!(worst <= o.tol, "a block's tip strays {worst} mm");
    assert_round_trip(
        &kin,
        &cl_of(&p),
        &posted.program,
        1e-6,
        o.pole_cone.to_radians(),
    );
}
