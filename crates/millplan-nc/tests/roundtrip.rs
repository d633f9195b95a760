//! Write → read round trips: APT → IR → APT → IR gives the same moves to 1e-4 mm
//! (on real files and on random programs), and every G-code dialect reads back
//! what millplan writes.

use millplan_geom::DVec3;
use millplan_nc::write::apt::write_apt;
use millplan_nc::write::gcode::write_gcode;
use millplan_nc::write::{Target, WriteOptions};
use millplan_nc::*;
use proptest::prelude::*;

mod shared_data;

fn reread(p: &Program) -> Program {
    let mut out = Vec::new();
    write_apt(p, WriteOptions::new(Target::Apt), &mut out).expect("write");
    let text = String::from_utf8(out).expect("utf8");
    let parsed =
        parse_program(&text, ReadOptions::default()).unwrap_or_else(|e| panic!("{e}\n{text}"));
    verify::verify(&parsed.program).expect("verifies");
    parsed.program
}

/// Same move kinds, end points, axes, feeds and arcs, operation by operation.
fn assert_same_moves(a: &Program, b: &Program, tol: f64) {
    let ma: Vec<_> = a
        .operations
        .iter()
        .flat_map(|o| o.moves.iter().map(move |m| (o, m)))
        .collect();
    let mb: Vec<_> = b
        .operations
        .iter()
        .flat_map(|o| o.moves.iter().map(move |m| (o, m)))
        .collect();
    assert_eq!(ma.len(), mb.len(), "move count");
    for (i, ((oa, x), (ob, y))) in ma.iter().zip(&mb).enumerate() {
        assert_eq!(x.kind.name(), y.kind.name(), "move {i} kind");
        assert!(
            (x.end - y.end).length() <= tol || x.end.is_nan() && y.end.is_nan(),
            "move {i}: {:?} vs {:?}",
            x.end,
            y.end
        );
        if x.is_cutting() {
            assert!(
                (x.feed - y.feed).abs() <= 1e-4 * x.feed.max(1.0),
                "move {i} feed {} vs {}",
                x.feed,
                y.feed
            );
        }
        // MULTAX/OFF reads as the vertical axis a move without one has.
        let vertical = |a: Option<DVec3>| a.or((oa.is_five_axis()).then_some(DVec3::Z));
        match (vertical(oa.axis(x)), vertical(ob.axis(y))) {
            (Some(u), Some(v)) => assert!((u - v).length() <= 1e-6, "move {i} axis"),
            (None, None) => {}
            (u, v) => panic!("move {i}: axis {u:?} vs {v:?}"),
        }
        if let (Some(p), Some(q)) = (oa.arc(x), ob.arc(y)) {
            assert!(
                (p.centre - q.centre).length() <= tol && (p.sweep - q.sweep).abs() < 1e-6,
                "move {i} arc"
            );
            assert!(
                (p.normal - q.normal).length() < 1e-9,
                "move {i} arc direction"
            );
        }
    }
}

#[test]
fn apt_round_trip_on_real_files() {
    for rel in [
        "swcam-apt-stl-pairs/Interface-glue.apt",
        "swcam-apt-stl-pairs/boss.apt",
        "swcam-apt-stl-pairs/RotateThin.apt",
        "nx-clsf-5axis-varcontour/ust_a.cls",
        "nx-clsf-circle-cutcom/cutcom.clsf",
        "nx-clsf-ballend-nurbs/nurbs.clsf",
        "impeller-5axis-goto-fragments/pathdata2.txt",
    ] {
        let Some(path) = shared_data::file(rel) else {
            continue;
        };
        let src = std::fs::read_to_string(path).expect("a sample reads");
        let p1 = parse_program(&src, ReadOptions::default())
            .expect("reads")
            .program;
        let p2 = reread(&p1);
        assert_same_moves(&p1, &p2, 1e-4);
        let p3 = reread(&p2);
        assert_same_moves(&p2, &p3, 1e-4);
        assert_eq!(
            p2.operations.len(),
            p3.operations.len(),
            "{rel}: operations"
        );
    }
}

/// A random program: one or two operations of rapids, lines, XY arcs, with or without axes.
fn program_strategy() -> impl Strategy<Value = Program> {
    let coord = -500.0..500.0f64;
    let step = (
        coord.clone(),
        coord.clone(),
        coord.clone(),
        0..4u8,
        0.1..1.0f64,
        10.0..5000.0f64,
    );
    (
        proptest::collection::vec(step, 1..40),
        any::<bool>(),
        1.0..20.0f64,
    )
        .prop_map(|(steps, five, d)| {
            let mut op = Operation {
                tool: Some(Tool {
                    number: Some(3),
                    name: None,
                    cutter: Some(Cutter::ball(d)),
                    line: 0,
                }),
                start: DVec3::new(0.0, 0.0, 100.0),
                ..Operation::default()
            };
            let mut pos = DVec3::new(0.0, 0.0, 100.0);
            for (i, (x, y, z, kind, t, feed)) in steps.into_iter().enumerate() {
                // G-code has no FROM: a program starts by positioning the tool.
                let kind = if i == 0 { 0 } else { kind };
                let end = DVec3::new(x, y, z);
                let mut m = match kind {
                    0 => Move::rapid(end),
                    _ => Move::linear(end, feed.round()),
                };
                if kind == 3 {
                    // An XY arc from pos to a point on the same circle, centre given.
                    let c = DVec3::new(pos.x + 10.0 * t + 1.0, pos.y, pos.z);
                    let r = (pos - c).length();
                    let ang = std::f64::consts::PI * t;
                    let e = c + DVec3::new(-r * ang.cos(), r * ang.sin(), 0.0);
                    if let Some(a) = Arc::from_points(
                        pos,
                        e,
                        c,
                        DVec3::Z * if t > 0.5 { 1.0 } else { -1.0 },
                        false,
                    ) {
                        m.end = e;
                        m.kind = MoveKind::Arc(op.push_arc(a));
                    }
                }
                if five && m.arc().is_none() {
                    let v = DVec3::new(t - 0.5, 0.3, 1.0).normalize();
                    m.orient = Some(op.intern_orient(Orient::vector(v)));
                }
                pos = m.end;
                op.moves.push(m);
            }
            let mut p = Program::new(Dialect::AptIso);
            p.operations.push(op);
            p
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn apt_write_read_gives_the_same_moves(p in program_strategy()) {
        verify::verify(&p).expect("generated program verifies");
        let q = reread(&p);
        assert_same_moves(&p, &q, 1e-4);
    }

    #[test]
    fn gcode_dialects_read_back_their_output(p in program_strategy()) {
        for d in [Target::Fanuc, Target::Sinumerik, Target::LinuxCnc, Target::Heidenhain] {
            let mut out = Vec::new();
            match write_gcode(&p, WriteOptions::new(d), &mut out) {
                Ok(_) => {}
                Err(e) => {
                    // Only LinuxCNC refuses, and only for tool vectors.
                    prop_assert!(d == Target::LinuxCnc, "{}: {e}", d.name());
                    continue;
                }
            }
            let text = String::from_utf8(out).expect("utf8");
            let parsed = parse_program(&text, ReadOptions::default()).map_err(|e| TestCaseError::fail(format!("{}: {e}\n{text}", d.name())))?;
            verify::verify(&parsed.program).map_err(|v| TestCaseError::fail(format!("{v:?}")))?;
            let a: Vec<_> = p.moves().collect();
            let b: Vec<_> = parsed.program.moves().collect();
            prop_assert_eq!(a.len(), b.len(), "{} move count\n{}", d.name(), text);
            for (x, y) in a.iter().zip(&b) {
                prop_assert_eq!(x.kind.name(), y.kind.name());
                prop_assert!((x.end - y.end).length() < 2e-4, "{}: {:?} vs {:?}", d.name(), x.end, y.end);
                if x.is_cutting() {
                    prop_assert!((x.feed - y.feed).abs() < 1e-3, "{} feed", d.name());
                }
            }
        }
    }
}
