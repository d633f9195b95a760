//! The checks of a written program (issue 31 item 4, `millplan_plan::safety`):
//! each refuses what it exists for, at the source line of the fault, on small
//! programs built here; a clean program passes every check; a fault the
//! input already had is named as the input's.

use millplan_geom::{DVec3, TriMesh};
use millplan_models::cutter::Shape;
use millplan_models::kinematics::{KinKind, Kinematics};
use millplan_nc::equiv::Tolerance;
use millplan_nc::readback::read_back;
use millplan_nc::write::{write_program, Target, WriteOptions};
use millplan_nc::{parse_program, Operation, Orient, Program, ReadOptions};
use millplan_plan::machine::Machine;
use millplan_plan::post::{post, PostOptions};
use millplan_plan::safety::{
    check, first_refusal, passed, read_back_check, Check, Inputs, Load, LoadCheck, TipRule,
    Tolerances,
};
use millplan_sim::dropcutter::DropMesh;
use millplan_sim::stock::tool::ToolBody;
use millplan_sim::stock::Stock;

/// A slot at Z−1 through a block 0..50 × 0..50 × −10..0 with a D10 ball,
/// entering from X−10 (in air) and leaving at X60; the part a plane at
/// Z−1.5 below it. Line numbers are the text's.
const CLEAN: &str = "G21 G90 G94
T1 M6
S6000 M3
G0 X-10 Y25 Z5
G1 Z-1 F1000
G1 X60
G0 Z5
M30
";

fn read(src: &str) -> Program {
    parse_program(src, ReadOptions::default())
        .expect("the test program reads")
        .program
}

/// `CLEAN` with line `line` (1-based) replaced by `text`.
fn planted(line: usize, text: &str) -> Program {
    let mut lines: Vec<&str> = CLEAN.lines().collect();
    lines[line - 1] = text;
    read(&(lines.join("\n") + "\n"))
}

fn plane(z: f64) -> TriMesh {
    let p = |x: f64, y: f64| DVec3::new(x, y, z);
    let (a, b, c, d) = (
        p(-30.0, -30.0),
        p(80.0, -30.0),
        p(80.0, 80.0),
        p(-30.0, 80.0),
    );
    TriMesh::from_soup(&[[a, b, c], [a, c, d]]).0
}

fn ball(r: f64) -> ToolBody {
    let mut b = ToolBody::new(Shape::Ball { radius: r });
    b.flute = 1e6;
    b
}

struct World {
    part: DropMesh,
    stock: Stock,
    machine: Machine,
}

fn world() -> World {
    World {
        part: DropMesh::new(&plane(-1.5)),
        stock: Stock::block(
            DVec3::new(0.0, 0.0, -10.0),
            DVec3::new(50.0, 50.0, 0.0),
            0.5,
        ),
        machine: Machine::default(),
    }
}

fn tool_d10(_: &Operation) -> Option<ToolBody> {
    Some(ball(5.0))
}

/// Every check on `output` against `input` with the D10 ball, the block,
/// the plane and the default machine, tips kept.
fn run(w: &World, input: &Program, output: &Program) -> Vec<Check> {
    run_with(w, input, output, &tool_d10, None)
}

fn run_with(
    w: &World,
    input: &Program,
    output: &Program,
    tool: &(dyn Fn(&Operation) -> Option<ToolBody> + Sync),
    loads: Option<&dyn LoadCheck>,
) -> Vec<Check> {
    check(&Inputs {
        input,
        output,
        part: Some(&w.part),
        stock: Some(&w.stock),
        tool_body: tool,
        machine: Some(&w.machine),
        tip: TipRule::Kept,
        tol: Tolerances::default(),
        loads,
    })
}

fn named<'a>(checks: &'a [Check], name: &str) -> &'a Check {
    checks
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no check {name}"))
}

/// The check `name` refuses, and its first finding is at `line`.
fn refuses_at(checks: &[Check], name: &str, line: u32) -> bool {
    let c = named(checks, name);
    !c.ok && c.findings.first().and_then(|f| f.line) == Some(line)
}

#[test]
fn a_clean_program_passes_every_check_and_says_what_it_checked() {
    let w = world();
    let p = read(CLEAN);
    let loads = |out: &Program| -> Vec<Load> {
        (0..out.operations[0].moves.len())
            .map(|mv| Load {
                op: 0,
                mv,
                name: "fxy".into(),
                value: 100.0,
                limit: 300.0,
            })
            .collect()
    };
    let checks = run_with(&w, &p, &p, &tool_d10, Some(&loads));
    assert!(passed(&checks), "{checks:#?}");
    let names: Vec<_> = checks.iter().map(|c| c.name).collect();
    assert_eq!(names, ["ir", "machine", "tip", "stock", "gouge", "loads"]);
    for c in &checks {
        assert!(c.checked > 0, "{} checked nothing", c.name);
    }
    // The first rapid comes from where the tool was before the program.
    for name in ["stock", "gouge"] {
        let why = named(&checks, name).skipped.as_deref().unwrap_or("");
        assert!(why.starts_with("1 moves not"), "{name}: {why}");
        assert!(
            why.contains("1 from or to an unknown position"),
            "{name}: {why}"
        );
    }
    // 4 moves; the slot is 70 mm long, so the gouge check sampled it at 0.1 mm.
    assert_eq!(named(&checks, "tip").checked, 4);
    assert!(named(&checks, "gouge").checked > 700);
}

#[test]
fn missing_inputs_skip_their_checks_with_the_reason() {
    let p = read(CLEAN);
    let checks = check(&Inputs {
        input: &p,
        output: &p,
        part: None,
        stock: None,
        tool_body: &tool_d10,
        machine: None,
        tip: TipRule::Free,
        tol: Tolerances::default(),
        loads: None,
    });
    assert!(passed(&checks));
    for (name, why) in [
        ("machine", "no machine given"),
        ("stock", "no stock given"),
        ("gouge", "no part given"),
        ("loads", "no load model given"),
    ] {
        assert_eq!(named(&checks, name).skipped.as_deref(), Some(why));
        assert_eq!(named(&checks, name).checked, 0);
    }
}

#[test]
fn a_planted_gouge_is_refused_at_its_line() {
    let w = world();
    let out = planted(6, "G1 X60 Z-2");
    let checks = run(&w, &read(CLEAN), &out);
    assert!(refuses_at(&checks, "gouge", 6), "{checks:#?}");
    let g = &named(&checks, "gouge").findings[0];
    assert!(!g.in_input);
    // Half a millimetre below the plane at the end of the move.
    assert!(g.message.contains("0.5000 mm deep"), "{}", g.message);
    let (c, f) = first_refusal(&checks).expect("refused");
    assert_eq!((c.name, f.line), ("tip", Some(6)));
}

/// A program that cuts into the part is not safe to run because its input
/// did too (a user trial: `optimise` said "every check passed" and wrote a
/// program gouging 0.5 mm everywhere): the gouge is refused, named as the
/// input's own.
#[test]
fn a_gouge_the_input_had_is_refused_and_named_as_its_own() {
    let w = world();
    let p = planted(6, "G1 X60 Z-2");
    let checks = run(&w, &p, &p);
    let g = named(&checks, "gouge");
    assert!(!g.ok, "{g:#?}");
    assert!(!g.fails_anew(), "{g:#?}");
    assert!(refuses_at(&checks, "gouge", 6), "{checks:#?}");
    // The slot, and the rapid up from its end.
    let lines: Vec<_> = g.findings.iter().map(|f| f.line).collect();
    assert_eq!(lines, [Some(6), Some(7)]);
    assert!(g.findings.iter().all(|f| f.in_input));
    // The same gouge made deeper by the pass is new.
    let deeper = planted(6, "G1 X60 Z-2.5");
    let checks = run(&w, &p, &deeper);
    assert!(refuses_at(&checks, "gouge", 6));
    let g = named(&checks, "gouge");
    assert!(g.fails_anew(), "{g:#?}");
    assert!(!g.findings[0].in_input);
    assert!(!g.refusal().expect("refused").in_input);
    // The input's own gouge within the part's tessellation error (0.02 mm
    // here, under `input_gouge`) is reported, not refused.
    let shallow = planted(6, "G1 X60 Z-1.52");
    let checks = run(&w, &shallow, &shallow);
    let g = named(&checks, "gouge");
    assert!(g.ok, "{g:#?}");
    assert!(!g.findings.is_empty() && g.findings.iter().all(|f| f.in_input && !f.refuses));
    assert!(g.refusal().is_none());
}

#[test]
fn a_planted_rapid_through_the_stock_is_refused_at_its_line() {
    let w = world();
    let out = planted(6, "G0 X60");
    let checks = run(&w, &read(CLEAN), &out);
    assert!(refuses_at(&checks, "stock", 6), "{checks:#?}");
    let f = &named(&checks, "stock").findings[0];
    assert!(
        f.message.starts_with("rapid through material"),
        "{}",
        f.message
    );
    assert!(!f.in_input);
}

#[test]
fn a_rapid_the_input_had_is_still_refused_and_named_as_the_inputs() {
    let w = world();
    let p = planted(6, "G0 X60");
    let checks = run(&w, &p, &p);
    let s = named(&checks, "stock");
    assert!(!s.ok);
    assert_eq!(s.findings.len(), 1);
    assert!(s.findings[0].in_input);
    assert_eq!(s.findings[0].line, Some(6));
}

#[test]
fn a_shank_or_holder_in_material_is_refused_at_its_line() {
    let w = world();
    // Flutes 5 mm long: a slot 8 mm deep puts the shank 3 mm into material.
    let short = |_: &Operation| {
        let mut b = ball(5.0);
        b.flute = 5.0;
        Some(b)
    };
    let deep = planted(5, "G1 Z-8 F1000");
    let checks = run_with(&w, &deep, &deep, &short, None);
    assert!(refuses_at(&checks, "stock", 6), "{checks:#?}");
    let f = &named(&checks, "stock").findings[0];
    assert!(f.message.starts_with("shank or holder"), "{}", f.message);
    // A holder of D40 at 6 mm stick-out, the whole tool cutting: the same.
    let held = |_: &Operation| {
        let mut b = ball(5.0);
        b.stickout = 6.0;
        b.holder_r = 20.0;
        Some(b)
    };
    let checks = run_with(&w, &deep, &deep, &held, None);
    assert!(refuses_at(&checks, "stock", 6), "{checks:#?}");
    // At 1 mm deep neither touches.
    let p = read(CLEAN);
    assert!(named(&run_with(&w, &p, &p, &held, None), "stock").ok);
    assert!(named(&run_with(&w, &p, &p, &short, None), "stock").ok);
}

#[test]
fn a_feed_above_the_machines_maximum_is_refused_at_its_line() {
    let w = world();
    let out = planted(6, "G1 X60 F25000");
    let checks = run(&w, &read(CLEAN), &out);
    assert!(refuses_at(&checks, "machine", 6), "{checks:#?}");
    assert!(named(&checks, "machine").findings[0]
        .message
        .contains("above the machine's maximum 20000"));
    // At the maximum exactly it passes.
    let at_max = planted(6, "G1 X60 F20000");
    assert!(named(&run(&w, &read(CLEAN), &at_max), "machine").ok);
    // Per revolution: 4 mm × 6000 1/min = 24,000 mm/min.
    let g95 = planted(6, "G95 G1 X60 F4");
    assert!(refuses_at(&run(&w, &read(CLEAN), &g95), "machine", 6));
}

#[test]
fn a_spindle_speed_outside_the_range_is_refused_at_its_line() {
    let w = world();
    let out = planted(6, "G1 X60 S30000");
    let checks = run(&w, &read(CLEAN), &out);
    assert!(refuses_at(&checks, "machine", 6), "{checks:#?}");
    assert!(named(&checks, "machine").findings[0]
        .message
        .contains("outside the machine's spindle range 500..18000"));
    let slow = planted(3, "S200 M3");
    assert!(refuses_at(&run(&w, &read(CLEAN), &slow), "machine", 4));
}

#[test]
fn a_moved_tip_is_refused_at_its_line() {
    let w = world();
    // 0.01 mm off against a tolerance of 0.001 mm.
    let out = planted(6, "G1 X60.01");
    let checks = run(&w, &read(CLEAN), &out);
    assert!(refuses_at(&checks, "tip", 6), "{checks:#?}");
    // A move more is named too.
    let extra = read(&CLEAN.replace("G0 Z5\nM30", "G0 Z5\nG0 Z6\nM30"));
    let checks = run(&w, &read(CLEAN), &extra);
    let t = named(&checks, "tip");
    assert!(
        !t.ok
            && t.findings[0]
                .message
                .contains("goes on to (60.0000, 25.0000, 6.0000)"),
        "{t:#?}"
    );
}

/// Other moves along the same path are the same tips: a repeated point the
/// writer leaves out, a line written in two pieces, with other feeds; a
/// step off the path is not.
#[test]
fn the_same_path_in_other_moves_keeps_the_tips() {
    let w = world();
    let repeated = read(&CLEAN.replace("G1 X60\n", "G1 X60\nG1 X60\n"));
    let checks = run(&w, &repeated, &read(CLEAN));
    assert!(named(&checks, "tip").ok, "{checks:#?}");
    let halves = read(&CLEAN.replace("G1 X60\n", "G1 X25 F1500\nG1 X60\n"));
    let checks = run(&w, &read(CLEAN), &halves);
    let t = named(&checks, "tip");
    assert!(t.ok && t.checked == 4, "{t:#?}");
    let bent = read(&CLEAN.replace("G1 X60\n", "G1 X25 Y25.01\nG1 X60\n"));
    let checks = run(&w, &read(CLEAN), &bent);
    assert!(refuses_at(&checks, "tip", 6), "{checks:#?}");
}

#[test]
fn loads_over_their_limit_are_refused_beyond_the_stated_tolerance() {
    let w = world();
    let p = read(CLEAN);
    // The slot (move 2, line 6) at `fxy`; the tolerance is 0.5 %.
    let loads = |fxy: f64| {
        move |out: &Program| -> Vec<Load> {
            vec![Load {
                op: 0,
                mv: 2,
                name: "fxy".into(),
                value: fxy,
                limit: 300.0,
            }]
            .into_iter()
            .filter(|l| l.mv < out.operations[0].moves.len())
            .collect()
        }
    };
    // 301.4 / 300 is 0.47 % over: within the model's resolution.
    let over = loads(301.4);
    assert!(named(&run_with(&w, &p, &p, &tool_d10, Some(&over)), "loads").ok);
    // 301.6 / 300 is 0.53 % over.
    let over = loads(301.6);
    let checks = run_with(&w, &p, &p, &tool_d10, Some(&over));
    assert!(refuses_at(&checks, "loads", 6), "{checks:#?}");
}

#[test]
fn the_ir_verifier_refuses_a_broken_output() {
    let w = world();
    let mut out = read(CLEAN);
    out.operations[0].moves[2].feed = 0.0;
    let checks = run(&w, &read(CLEAN), &out);
    assert!(refuses_at(&checks, "ir", 6), "{checks:#?}");
}

#[test]
fn the_ball_centre_may_stay_while_the_axis_turns() {
    let w = world();
    let input = read(CLEAN);
    // The slot's end re-oriented 10° about Y, the tip moved so the centre stays.
    let a = 10f64.to_radians();
    let k = DVec3::new(a.sin(), 0.0, a.cos());
    let centre = |mut p: Program, keep_centre: bool| {
        let op = &mut p.operations[0];
        let id = op.intern_orient(Orient::vector(k));
        let m = &mut op.moves[2];
        m.orient = Some(id);
        if keep_centre {
            m.end = m.end + DVec3::Z * 5.0 - k * 5.0;
        }
        p
    };
    let tip = |out: &Program| {
        millplan_plan::safety::tip(&Inputs {
            input: &input,
            output: out,
            part: Some(&w.part),
            stock: None,
            tool_body: &tool_d10,
            machine: None,
            tip: TipRule::CentreKept,
            tol: Tolerances::default(),
            loads: None,
        })
    };
    let kept = centre(read(CLEAN), true);
    assert!(tip(&kept).ok, "{:#?}", tip(&kept));
    let moved = centre(read(CLEAN), false);
    let t = tip(&moved);
    assert!(!t.ok && t.findings[0].line == Some(6), "{t:#?}");
    // Under `Kept` the turned axis is a finding even where the tip stays.
    let checks = run(&w, &input, &centre(read(CLEAN), false));
    assert!(refuses_at(&checks, "tip", 6));
}

#[test]
fn every_input_point_must_be_cut_in_any_order() {
    let w = world();
    let input =
        read("G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F500\nG1 X10\nG1 Y10\nG1 X0\nM30\n");
    let reversed =
        read("G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y10 Z5\nG1 Z-1 F500\nG1 X10\nG1 Y0\nG1 X0\nM30\n");
    let missing = read("G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F500\nG1 X10\nG1 X0\nM30\n");
    let tip = |out: &Program| {
        millplan_plan::safety::tip(&Inputs {
            input: &input,
            output: out,
            part: None,
            stock: Some(&w.stock),
            tool_body: &tool_d10,
            machine: None,
            tip: TipRule::SamePoints,
            tol: Tolerances::default(),
            loads: None,
        })
    };
    assert!(tip(&reversed).ok, "{:#?}", tip(&reversed));
    let t = tip(&missing);
    assert!(!t.ok);
    // (10, 10) and (0, 10) are never cut.
    assert_eq!(t.findings.len(), 2);
    assert!(
        t.findings[0]
            .message
            .contains("line 7 (10.0000, 10.0000, -1.0000)"),
        "{}",
        t.findings[0].message
    );
    assert!(
        t.findings[1]
            .message
            .contains("line 8 (0.0000, 10.0000, -1.0000)"),
        "{}",
        t.findings[1].message
    );
}

/// A five-axis CL on a table A/C machine, posted; its tips through forward
/// kinematics are the CL's, and a posted point moved by 0.05 mm is refused.
#[test]
fn posted_tips_are_checked_through_forward_kinematics() {
    let mut kin = Kinematics::new(KinKind::TableAc);
    kin.rot_point = [10.0, 20.0, 30.0];
    kin.offset = [0.0, 5.0, -3.0];
    let machine = Machine {
        kinematics: Some(kin.clone()),
        ..Machine::default()
    };
    let mut cl = String::from("UNITS/MM\nFEDRAT/MMPM,1000\nRAPID\nGOTO/0,0,20,0,0,1\n");
    for i in 0..=10 {
        let t = i as f64 / 10.0;
        let k = DVec3::new(0.4 * t, -0.3 * t, 1.0).normalize();
        cl += &format!(
            "GOTO/{:.6},{:.6},{:.6},{:.12},{:.12},{:.12}\n",
            40.0 * t,
            10.0 * t * t,
            -1.0 - t,
            k.x,
            k.y,
            k.z
        );
    }
    let input = read(&cl);
    let posted = post(&input, &machine, &PostOptions::default()).expect("posts");
    let tip = |out: &Program| {
        millplan_plan::safety::tip(&Inputs {
            input: &input,
            output: out,
            part: None,
            stock: None,
            tool_body: &tool_d10,
            machine: Some(&machine),
            tip: TipRule::MovedBy(&kin),
            tol: Tolerances {
                tip: 0.01,
                ..Tolerances::default()
            },
            loads: None,
        })
    };
    let t = tip(&posted.program);
    assert!(t.ok, "{t:#?}");
    // Every cutting CL point and the points inserted between them.
    assert!(t.checked >= 11, "{t:#?}");
    let mut moved = posted.program.clone();
    let op = &mut moved.operations[0];
    let i = op.moves.len() - 3;
    op.moves[i].end.x += 0.05;
    let line = op.moves[i].line;
    let t = tip(&moved);
    assert!(!t.ok);
    assert_eq!(t.findings[0].line, Some(line));
    // A block that changes branch inside the cut: the same tip at its end
    // (A and C of the other solution, X, Y and Z solved for the tip), the
    // rotaries swinging the tip far off the path in between. Both ends
    // pass; the tip inside the block does not.
    let mut flipped = posted.program.clone();
    let op = &mut flipped.operations[0];
    let i = op.moves.len() - 5;
    let (m, angles) = (op.moves[i], op.orient(&op.moves[i]).expect("angles").angles);
    let (a, c) = (angles[0].expect("A"), angles[2].expect("C"));
    let joints = |xyz: DVec3, a: f64, c: f64| millplan_models::kinematics::Joints {
        xyz,
        first: a.to_degrees(),
        second: c.to_degrees(),
    };
    let want = kin.tip(&joints(m.end, a, c));
    let (a2, c2) = (-a, c + std::f64::consts::PI);
    // The tip is affine in X, Y and Z at fixed angles: one linear solve.
    let at = |xyz: DVec3| kin.tip(&joints(xyz, a2, c2));
    let base = at(m.end);
    let jac = millplan_geom::DMat3::from_cols(
        at(m.end + DVec3::X) - base,
        at(m.end + DVec3::Y) - base,
        at(m.end + DVec3::Z) - base,
    );
    let end = m.end + jac.inverse() * (want - base);
    assert!((at(end) - want).length() < 1e-9);
    let id = op.intern_orient(Orient {
        axis: None,
        angles: [Some(a2), None, Some(c2)],
    });
    op.moves[i].end = end;
    op.moves[i].orient = Some(id);
    let t = tip(&flipped);
    assert!(!t.ok, "{t:#?}");
    assert_eq!(t.findings[0].line, Some(op_line(&flipped, i)), "{t:#?}");
    assert!(
        t.findings[0].message.contains("inside the block"),
        "{}",
        t.findings[0].message
    );
    // Under TCP the tips are written as they are.
    let tcp = post(
        &input,
        &machine,
        &PostOptions {
            tcp: true,
            ..PostOptions::default()
        },
    )
    .expect("posts under TCP");
    assert!(tip(&tcp.program).ok);
}

/// The source line of move `i` of the first operation.
fn op_line(p: &Program, i: usize) -> u32 {
    p.operations[0].moves[i].line
}

#[test]
fn bytes_that_do_not_mean_what_was_written_fail_the_read_back() {
    let p = read(CLEAN);
    let (out, _) = write_program(&p, WriteOptions::new(Target::Fanuc)).expect("writes");
    let back = read_back(&out, Target::Fanuc, &p, &Tolerance::default()).expect("reads");
    let c = read_back_check(&back);
    assert!(c.ok && c.checked >= 4, "{c:#?}");
    let text = String::from_utf8(out)
        .expect("text")
        .replace("X60.", "X61.");
    let back = read_back(text.as_bytes(), Target::Fanuc, &p, &Tolerance::default()).expect("reads");
    let c = read_back_check(&back);
    assert!(!c.ok);
    let line = c.findings[0].line.expect("a line of the written file");
    assert!(text
        .lines()
        .nth(line as usize - 1)
        .expect("line")
        .contains("X61"));
    // Bytes that do not read are an error at their line.
    let e = read_back(
        b"G21\nG1 X1 Q@@\n",
        Target::Fanuc,
        &p,
        &Tolerance::default(),
    )
    .expect_err("does not read");
    assert_eq!(e.line, 2);
}

/// After the lead/tilt pass a ball end is leaned with its centre kept: its
/// gouges are found by its distance to the part (not skipped as a tilted
/// tool), and a gouge of the ball where the input's vertical ball had its
/// centre is the input's; the leaned ball lowered further is new.
#[test]
fn a_leaned_ball_is_gouge_checked_and_its_own_gouge_matched_by_its_centre() {
    let w = world();
    // The input gouges 0.5 mm along its slot at Z−2.
    let input = planted(6, "G1 X60 Z-2");
    let a = 10f64.to_radians();
    let k = DVec3::new(a.sin(), 0.0, a.cos());
    let leaned = |lower: f64| {
        let mut p = planted(6, "G1 X60 Z-2");
        let op = &mut p.operations[0];
        let id = op.intern_orient(Orient::vector(k));
        for i in 1..=2 {
            let m = &mut op.moves[i];
            m.orient = Some(id);
            m.end = m.end + DVec3::Z * 5.0 - k * 5.0 - DVec3::Z * lower;
        }
        p
    };
    let gouge = |out: &Program| named(&run(&w, &input, out), "gouge").clone();
    let same = gouge(&leaned(0.0));
    let skipped = same.skipped.as_deref().unwrap_or("");
    assert!(skipped.contains("0 with a tilted tool"), "{same:#?}");
    assert!(!same.ok && !same.fails_anew(), "{same:#?}");
    let slot = same
        .findings
        .iter()
        .find(|f| f.line == Some(6))
        .expect("the slot's gouge");
    assert!(
        slot.in_input && slot.message.contains("0.5000 mm deep"),
        "{slot:#?}"
    );
    let deeper = gouge(&leaned(0.3));
    assert!(deeper.fails_anew(), "{deeper:#?}");
    let slot = deeper
        .findings
        .iter()
        .find(|f| f.line == Some(6))
        .expect("the slot's gouge");
    assert!(
        !slot.in_input && slot.message.contains("0.8000 mm deep"),
        "{slot:#?}"
    );
}
