//! The job's checks refuse what each exists for (issue 31, done-when 3),
//! planted in the optimised program before it is written: a feed above the
//! machine's maximum, a moved tip, a gouge, a load over its limit; each at
//! the right line. And the defaults a run without options must have.

use millplan_driver::{Inputs, Job, Options, PassName, UserLimits, Verdict};
use millplan_geom::{DVec3, TriMesh};
use millplan_models::cutter::Shape;
use millplan_models::force::materials::Materials;
use millplan_nc::write::{Target, WriteOptions};
use millplan_nc::{parse_program, Program, ReadOptions};
use millplan_plan::machine::Machine;
use millplan_sim::stock::spec::StockSpec;

/// A ball D10 running along X over the plate z = 0 at z 0 (tip on the
/// plate), lines 6 to 9; the stock 0.3 mm above it.
const PROGRAM: &str = "G21 G90 G17\nT1 M6\nS8000 M3\nG0 X-10 Y10 Z5\nG0 Z0.5\nG1 Z0 F800\nG1 X20\nG1 X40\nG1 X60\nG0 Z5\nM30\n";

fn plate() -> TriMesh {
    let c = |x: f64, y: f64| DVec3::new(x, y, 0.0);
    let soup = [
        [c(-20.0, -20.0), c(80.0, -20.0), c(80.0, 40.0)],
        [c(-20.0, -20.0), c(80.0, 40.0), c(-20.0, 40.0)],
    ];
    TriMesh::from_soup(&soup).0
}

fn job(limits: UserLimits) -> Job {
    job_of(PROGRAM, limits)
}

fn job_of(src: &str, limits: UserLimits) -> Job {
    let program = parse_program(src, ReadOptions::default())
        .expect("reads")
        .program;
    Job::new(Inputs {
        program,
        part: Some(plate()),
        stock: Some(StockSpec::Box {
            min: DVec3::new(-20.0, -20.0, -5.0),
            max: DVec3::new(80.0, 40.0, 0.3),
        }),
        blank: None,
        machine: Machine::default(),
        machine_given: false,
        materials: Materials::builtin(),
        material: Some("al7075".into()),
        options: Options {
            tool: Some(Shape::Ball { radius: 5.0 }),
            limits,
            ..Options::default()
        },
        library: Vec::new(),
    })
    .expect("a job")
}

/// The job's input with `plant` applied, written and checked: the failed
/// check's name and line.
fn refused(j: &Job, plant: impl FnOnce(&mut Program)) -> (&'static str, u32) {
    let mut o = j.run(&[]).expect("runs");
    plant(&mut o.program);
    let w = j
        .finish(&o, WriteOptions::new(Target::Fanuc))
        .expect("written");
    assert_eq!(w.summary.verdict, Verdict::Refused);
    let (name, line, _) = w.summary.refusal().expect("a refusal");
    (name, line)
}

fn move_at(p: &mut Program, line: u32) -> &mut millplan_nc::Move {
    p.operations
        .iter_mut()
        .flat_map(|op| op.moves.iter_mut())
        .find(|m| m.line == line)
        .expect("the move")
}

#[test]
fn the_input_as_it_is_passes_every_check() {
    let j = job(UserLimits::default());
    let o = j.run(&[]).expect("runs");
    let w = j
        .finish(&o, WriteOptions::new(Target::Fanuc))
        .expect("written");
    for c in &w.summary.checks {
        assert!(c.ok, "{c:?}");
    }
    assert_eq!(
        w.summary.verdict,
        Verdict::Kept,
        "nothing ran, nothing gained"
    );
}

#[test]
fn a_feed_above_the_machines_maximum_is_refused_at_its_line() {
    let j = job(UserLimits::default());
    let max = j.inputs.machine.feed_max;
    assert_eq!(
        refused(&j, |p| move_at(p, 8).feed = 2.0 * max),
        ("machine", 8)
    );
}

#[test]
fn a_moved_tip_is_refused_at_its_line() {
    let j = job(UserLimits::default());
    assert_eq!(refused(&j, |p| move_at(p, 7).end.y += 0.5), ("tip", 7));
}

#[test]
fn a_planted_gouge_is_found_at_its_line() {
    let j = job(UserLimits::default());
    let mut o = j.run(&[]).expect("runs");
    move_at(&mut o.program, 8).end.z = -1.0;
    let w = j
        .finish(&o, WriteOptions::new(Target::Fanuc))
        .expect("written");
    let g = w
        .summary
        .checks
        .iter()
        .find(|c| c.name == "gouge")
        .expect("gouge check");
    assert!(!g.ok);
    assert!(
        g.findings.iter().any(|f| f.line == Some(8) && !f.in_input),
        "{g:?}"
    );
}

#[test]
fn a_load_over_its_limit_is_refused_at_its_line() {
    let j = job(UserLimits {
        fxy: Some(1.0),
        ..UserLimits::default()
    });
    let (name, line) = refused(&j, |_| {});
    assert_eq!(name, "loads");
    assert!((6..=9).contains(&line), "{line}");
}

#[test]
fn a_run_without_options_has_every_default_and_says_where_from() {
    let j = job(UserLimits::default());
    let from = |n: &str| {
        let s = j
            .settings
            .iter()
            .find(|s| s.name == n)
            .unwrap_or_else(|| panic!("{n}"));
        s.from.clone()
    };
    assert_eq!(from("vc"), "cutting table");
    assert_eq!(j.vc, 300.0, "al7075 in data/cutting.toml");
    // materials.toml, al7075: the ATA chip load of a D10 end mill, 0.08 mm.
    assert!(from("fz_max").contains("chip load"), "{}", from("fz_max"));
    assert_eq!(j.limits.fz_max, None, "per tool, not one for all");
    assert!((j.limits.fz_range(10.0).fz_max - 0.08).abs() < 1e-12);
    assert_eq!((from("fz_min"), j.limits.fz_min), ("default".into(), 0.01));
    // The machine has no spindle chart: F_xy, torque and power are the
    // input's own largest on the stock.
    let max = j.forces_before.as_ref().expect("forces").maxima();
    assert!(max.fxy > 0.0);
    assert_eq!(j.limits.fxy, Some(max.fxy));
    assert_eq!(j.limits.torque, Some(max.torque));
    assert!(from("fxy").contains("input"), "{}", from("fxy"));
    assert_eq!(from("spindle"), "program");
    assert_eq!(from("flutes"), "default");
    // The feed pass runs, the others say why not.
    let o = j
        .run(&[PassName::Speed, PassName::Feed, PassName::Post])
        .expect("runs");
    let ran: Vec<bool> = o.passes.iter().map(|p| p.ran).collect();
    assert_eq!(ran, [true, true, false]);
    assert!(o.passes[2].reason.contains("three-axis"));
}

/// Without a limit of its own, the feed pass raises the feeds where the
/// input cuts lightly (here 0.1 mm deep after 0.3 mm, lines 8–9), but no
/// move is loaded more than the input's hardest (within the model's
/// resolution), and the written program passes the load check against that
/// learned limit.
#[test]
fn feeds_rise_but_no_load_above_the_inputs_largest() {
    let src = PROGRAM.replace("G1 X40\n", "G1 Z0.2\nG1 X40\n");
    let j = job_of(&src, UserLimits::default());
    let before = j.forces_before.as_ref().expect("forces").maxima();
    let o = j.run(&[PassName::Feed]).expect("runs");
    let w = j
        .finish(&o, WriteOptions::new(Target::Fanuc))
        .expect("written");
    let after = w.forces_after.as_ref().expect("forces").maxima();
    assert!(
        after.fxy <= before.fxy * 1.005,
        "{} > {}",
        after.fxy,
        before.fxy
    );
    let loads = w.summary.checks.iter().find(|c| c.name == "loads");
    let loads = loads.expect("load check");
    assert!(loads.ok && loads.checked > 0, "{loads:?}");
    assert!(w.summary.time_after_s < w.summary.time_before_s);
}

/// `--limit fz_max=` sets the top of every tool's range and says so.
#[test]
fn a_given_fz_max_replaces_the_chip_load() {
    let j = job(UserLimits {
        fz_max: Some(0.03),
        fz_min: Some(0.005),
        ..UserLimits::default()
    });
    assert_eq!(j.limits.fz_range(10.0).fz_max, 0.03);
    assert_eq!(j.limits.fz_min, 0.005);
    let from: Vec<_> = j
        .settings
        .iter()
        .filter(|s| s.name.starts_with("fz_"))
        .collect();
    assert!(from.iter().all(|s| s.from == "option"), "{from:?}");
}

#[test]
fn a_program_without_s_gets_the_speed_of_vc() {
    let src = PROGRAM.replace("S8000 M3\n", "M3\n");
    let program = parse_program(&src, ReadOptions::default())
        .expect("reads")
        .program;
    let j = Job::new(Inputs {
        program,
        part: None,
        stock: None,
        blank: None,
        machine: Machine::default(),
        machine_given: false,
        materials: Materials::builtin(),
        material: Some("al7075".into()),
        options: Options {
            tool: Some(Shape::Ball { radius: 5.0 }),
            ..Options::default()
        },
        library: Vec::new(),
    })
    .expect("a job");
    let n = 1000.0 * 300.0 / (std::f64::consts::PI * 10.0);
    let want = n.clamp(j.inputs.machine.spindle_min, j.inputs.machine.spindle_max);
    for m in j.analysed().moves().filter(|m| m.is_cutting()) {
        assert!((m.spindle - want).abs() < 1e-9, "{}", m.spindle);
    }
    // The input itself keeps its words: the speed is written only by a pass
    // that needs one.
    assert!(j.inputs.program.moves().all(|m| !(m.spindle > 0.0)));
}

/// `Job::run_with` tells its hook how far the passes have come (the bar of
/// `millplan optimise`): the pass count from 0 to the number of passes, and
/// between them the phases the passes report themselves (the feed pass's
/// forces); `Job::run` gives the same program without a hook.
#[test]
fn the_progress_hook_hears_the_passes_and_their_phases() {
    let j = job(UserLimits::default());
    let heard = std::sync::Mutex::new(Vec::<(String, usize, usize)>::new());
    let hook = |phase: &str, done: usize, total: usize| {
        heard
            .lock()
            .expect("not poisoned")
            .push((phase.to_string(), done, total));
    };
    let order = [PassName::Speed, PassName::Feed];
    let with = j.run_with(&order, Some(&hook)).expect("runs");
    let heard = heard.into_inner().expect("not poisoned");
    let passes: Vec<(usize, usize)> = heard
        .iter()
        .filter(|h| h.0 == millplan_driver::run::PASSES_PHASE)
        .map(|h| (h.1, h.2))
        .collect();
    assert_eq!(passes, [(0, 2), (1, 2), (2, 2)], "{heard:?}");
    assert!(
        heard.iter().any(|h| h.0 == "feed: forces"),
        "the feed pass's own phase: {heard:?}"
    );
    let without = j.run(&order).expect("runs");
    assert_eq!(with.program, without.program);
}
