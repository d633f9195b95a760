//! The feed pass on a generated ball-end finishing case: a raster over the
//! demo surface with a finishing allowance, cut at a conservative feed.

use millplan_geom::analytic::{tessellate, DemoSurface};
use millplan_models::cutter::Shape;
use millplan_models::force::materials::Materials;
use millplan_nc::generate::{raster, Raster};
use millplan_nc::Program;
use millplan_plan::feed::{FeedParams, FeedPass};
use millplan_plan::force::{
    simulate, simulate_in_parts, simulate_largest, simulate_largest_kept, simulate_largest_within,
    simulate_with, FeedLimits, ForceRun, ForceSetup, LimitUse, LIMIT_TOLERANCE,
};
use millplan_plan::machine::Machine;
use millplan_plan::pipeline::{self, Context};
use millplan_sim::stock::path::{strokes, PathOptions};
use millplan_sim::stock::spec::offset_stock;
use millplan_sim::stock::tool::ToolBody;
use millplan_sim::stock::Stock;

fn case() -> (Program, Stock) {
    let surface = DemoSurface { size: 24.0 };
    let mesh = tessellate(&surface, 0.5);
    let (program, _) = raster(
        &surface,
        &Raster {
            stepover: 0.8,
            step: 0.4,
            feed: 1000.0,
            spindle: 10000.0,
            ..Raster::default()
        },
    );
    (program, offset_stock(&mesh, 0.4, 0.1))
}

fn body(_: &millplan_nc::Operation) -> Option<ToolBody> {
    Some(ToolBody::new(Shape::Ball { radius: 5.0 }))
}

fn setup() -> ForceSetup {
    ForceSetup::new(Materials::builtin().get("al7075").expect("built in").law, 2)
}

fn limits() -> FeedLimits {
    FeedLimits {
        fxy: Some(160.0),
        torque: None,
        power: Some(400.0),
        stress: None,
        deflection: Some(0.05),
        fos: 1.0,
        fz_min: 0.01,
        fz_max: Some(0.25),
        chip_loads: None,
    }
}

/// The case's strokes: the ball at a chord of 0.025 mm.
fn strokes_of(p: &Program, m: &Machine) -> millplan_sim::stock::path::Strokes {
    strokes(
        p,
        body,
        &PathOptions {
            chord: 0.025,
            rapid_rate: m.rapid,
        },
    )
}

fn forces(p: &Program, stock: Stock, m: &Machine) -> ForceRun {
    let s = strokes_of(p, m);
    simulate(p, &s, stock, &setup(), LimitUse::None, &|_| {}).expect("simulates")
}

fn time_s(p: &Program, m: &Machine) -> f64 {
    millplan_nc::stats::summarize(p, m.rapid).time_s
}

#[test]
fn forces_do_not_depend_on_how_the_run_is_split_over_threads() {
    // Parts run on other threads from copies of the simulator: every stroke
    // must still meet the stock one sequential run gives it.
    let (p, stock) = case();
    let m = Machine::default();
    let s = strokes_of(&p, &m);
    let limits = limits();
    let run = |threads: usize, min_part: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool")
            .install(|| {
                simulate_in_parts(
                    &p,
                    &s,
                    stock.clone(),
                    &setup(),
                    LimitUse::Schedule(&limits, &m),
                    &|_| {},
                    min_part,
                )
            })
            .expect("simulates")
    };
    let one = run(1, 100);
    assert!(s.strokes.len() > 1000, "{} strokes", s.strokes.len());
    for (threads, min_part) in [(2, 100), (3, 37), (4, 1000)] {
        assert_eq!(
            run(threads, min_part),
            one,
            "{threads} threads, parts of {min_part}"
        );
    }
}

#[test]
fn the_largest_loads_come_out_as_when_every_move_is_converged() {
    // Learning limits needs only the program's largest loads: converging
    // only the moves that may reach them must find the same maxima, and
    // every move it evaluates again must carry the loads a run that
    // converges every move gives it; the others their coarsest-grid loads,
    // which cannot reach the maxima.
    let (p, stock) = case();
    let m = Machine::default();
    let s = strokes_of(&p, &m);
    let all = simulate(&p, &s, stock.clone(), &setup(), LimitUse::None, &|_| {}).expect("runs");
    let largest = simulate_largest(&p, &s, &stock, &setup(), &|_| {}).expect("runs");
    let stock2 = stock.clone();
    let coarse = simulate(&p, &s, stock, &setup(), LimitUse::Coarse, &|_| {}).expect("runs");
    let (a, b) = (all.maxima(), largest.maxima());
    assert_eq!(
        (a.fxy, a.torque, a.power, a.stress, a.deflection),
        (b.fxy, b.torque, b.power, b.stress, b.deflection)
    );
    let floor = coarse.floor();
    assert!(
        floor.fxy > 0.5 * a.fxy && floor.fxy <= a.fxy,
        "{floor:?} {a:?}"
    );
    assert!(floor.torque <= a.torque && floor.power <= a.power);
    assert_eq!(all.moves.len(), largest.moves.len());
    let (mut again, mut kept) = (0, 0);
    for ((x, y), c) in all.moves.iter().zip(&largest.moves).zip(&coarse.moves) {
        if y == c && x != y {
            kept += 1;
            assert!(
                y.fxy_max < a.fxy && y.torque_max < a.torque,
                "line {}",
                y.line
            );
        } else {
            // Converged where a sample may decide the program's largest
            // loads, else on the coarsest grid: within its error.
            again += usize::from(!x.rapid);
            let near = |u: f64, v: f64| (u - v).abs() <= 0.05 * v + 1e-9;
            assert!(
                near(y.fxy_max, x.fxy_max) && near(y.torque_max, x.torque_max),
                "line {}: {} {} against {} {}",
                y.line,
                y.fxy_max,
                y.torque_max,
                x.fxy_max,
                x.torque_max
            );
        }
    }
    assert!(kept > again, "{kept} moves kept coarse, {again} converged");
    assert!(largest.evaluated < coarse.evaluated + all.evaluated / 2);
    // Nor does it depend on the threads the parts run on.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool")
        .install(|| simulate_largest(&p, &s, &stock2, &setup(), &|_| {}))
        .expect("runs");
    assert_eq!(one, largest);
}

#[test]
fn engaged_cells_kept_from_the_inputs_run_give_every_later_run_bit_for_bit() {
    // The feed pass and the check of what it wrote run over the path the
    // input's run walked: with the cells that run kept, each gives exactly
    // what a run that finds them on the stock gives, at other feeds and
    // speeds too, and with whatever limits it uses.
    let (p, stock) = case();
    let m = Machine::default();
    let s = strokes_of(&p, &m);
    let (largest, memo) = simulate_largest_kept(&p, &s, &stock, &setup(), &|_| {}).expect("runs");
    assert_eq!(
        largest,
        simulate_largest(&p, &s, &stock, &setup(), &|_| {}).expect("runs")
    );
    assert!(memo.fits(&s, &stock, &setup()));
    assert!(memo.memory_bytes() > 0);
    // Under a memory limit the memo holds less (nothing at 0, part of it
    // at a quarter), and the loads are the same.
    for budget in [0, memo.memory_bytes() / 4] {
        let (run, small) =
            simulate_largest_within(&p, &s, &stock, &setup(), &|_| {}, budget).expect("runs");
        assert_eq!(run, largest, "memo of {budget} bytes");
        assert!(
            small.memory_bytes() < memo.memory_bytes(),
            "{budget}: {} of {}",
            small.memory_bytes(),
            memo.memory_bytes()
        );
    }
    // The run with the memo and the run without, on `stock`.
    let same = |prog: &Program, setup: &ForceSetup, u: LimitUse<'_>| {
        let strokes = strokes_of(prog, &m);
        let run = |memo| {
            simulate_with(prog, &strokes, stock.clone(), setup, u, &|_| {}, memo).expect("runs")
        };
        assert_eq!(run(Some(&memo)), run(None), "{u:?}");
    };
    let mut faster = p.clone();
    for op in &mut faster.operations {
        for mv in &mut op.moves {
            mv.feed *= 1.7;
            mv.spindle *= 0.9;
        }
    }
    let s2 = strokes_of(&faster, &m);
    assert!(
        memo.fits(&s2, &stock, &setup()),
        "feeds and speeds are not the path"
    );
    let limits = limits();
    for prog in [&p, &faster] {
        for u in [
            LimitUse::None,
            LimitUse::Check(&limits, &m),
            LimitUse::Schedule(&limits, &m),
        ] {
            same(prog, &setup(), u);
        }
    }
    // Without a memo `simulate_with` is `simulate`.
    assert_eq!(
        simulate(&p, &s, stock.clone(), &setup(), LimitUse::None, &|_| {}).expect("runs"),
        simulate_with(
            &p,
            &s,
            stock.clone(),
            &setup(),
            LimitUse::None,
            &|_| {},
            None
        )
        .expect("runs")
    );
    // Another path or another stock: the memo does not fit and is not used.
    let mut moved = p.clone();
    if let Some(mv) = moved.operations[0].moves.iter_mut().find(|m| m.feed > 0.0) {
        mv.end.z -= 0.2;
    }
    assert!(!memo.fits(&strokes_of(&moved, &m), &stock, &setup()));
    same(&moved, &setup(), LimitUse::None);
    // A model cut to another flute length has other slices.
    let mut short = setup();
    short.stickout = Some(7.3);
    short.flute_length = Some(3.7);
    assert!(!memo.fits(&s, &stock, &short));
    same(&p, &short, LimitUse::None);
    let mut sim = millplan_sim::stock::sim::Simulator::new(stock.clone());
    let removed: f64 = s
        .strokes
        .iter()
        .map(|k| sim.step(k, &s.tools[0]).removed)
        .sum();
    assert!(removed > 0.0);
    assert!(!memo.fits(&s, &sim.stock, &setup()));
}

#[test]
fn forces_follow_the_engagement_along_the_program() {
    let (p, stock) = case();
    let m = Machine::default();
    let run = forces(&p, stock, &m);
    let cutting: Vec<_> = run.moves.iter().filter(|x| !x.rapid && !x.air).collect();
    assert!(
        cutting.len() > 500,
        "the raster cuts: {} moves",
        cutting.len()
    );
    assert!(cutting.iter().all(|x| x.fxy_max > 0.0 || x.unmodelled));
    // Power is T_mean·ω: every loaded move's follows from its torque.
    for x in &cutting {
        let w = x.rpm * std::f64::consts::TAU / 60.0;
        assert!((x.power_w - x.torque_mean * w / 1000.0).abs() <= 1e-6 * x.power_w.max(1.0));
    }
    // Material goes as it is cut: running the program a second time over its
    // own result meets air everywhere.
    let (p2, mut stock2) = case();
    let s = strokes(
        &p2,
        body,
        &PathOptions {
            chord: 0.025,
            rapid_rate: m.rapid,
        },
    );
    let _ = millplan_sim::stock::run::run(&mut stock2, &s, 0.01, &|_| {});
    let again = simulate(&p2, &s, stock2, &setup(), LimitUse::None, &|_| {}).expect("simulates");
    let median = |r: &ForceRun| {
        let mut v: Vec<f64> = r
            .moves
            .iter()
            .filter(|x| !x.rapid)
            .map(|x| x.fxy_max)
            .collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (first, second) = (median(&run), median(&again));
    assert!(
        second < 0.1 * first,
        "F_xy median {second:.1} N over the finished part, {first:.1} N cutting it"
    );
}

#[test]
fn scheduled_feeds_meet_the_limits_within_the_machine_and_save_time() {
    let (mut p, stock) = case();
    let input = p.clone();
    let m = Machine::default();
    let params = FeedParams {
        setup: setup(),
        limits: limits(),
        accel: 2000.0,
        chord: 0.025,
        learned: Vec::new(),
    };
    let mut pass = FeedPass::new(params, stock.clone(), Box::new(body));
    let cx = Context::new(m.clone()).verifying();
    pipeline::run(&mut [&mut pass], &mut p, &cx).expect("the pass runs");
    let ch = pass.changes.expect("changes");
    let held = held_at_fz_min(pass.before.as_ref().expect("loads"), &limits());
    assert!(ch.blocks > 500, "{ch:?}");
    // Every feed block within the machine's range, spindle speeds kept.
    for (a, b) in input.moves().zip(p.moves()) {
        assert_eq!(a.spindle, b.spindle);
        if b.is_cutting() {
            assert!(
                b.feed >= m.feed_min && b.feed <= m.feed_max,
                "feed {}",
                b.feed
            );
        }
    }
    // The output's own prediction stays within every limit (within the
    // tolerance the exit codes state), but at moves the pass had to hold
    // at the smallest feed per tooth, which it reports as still over.
    let after = forces(&p, stock, &m);
    let l = limits();
    let within = 1.0 + LIMIT_TOLERANCE;
    for x in after
        .moves
        .iter()
        .filter(|x| !x.unmodelled && !held.contains(&x.index))
    {
        assert!(
            x.fxy_max <= l.fxy.unwrap_or(f64::INFINITY) * within,
            "move {} fxy {}",
            x.index,
            x.fxy_max
        );
        assert!(x.power_w <= l.power.unwrap_or(f64::INFINITY) * within);
        assert!(x.deflection_mm <= l.deflection.unwrap_or(f64::INFINITY) * within);
        if x.fz > 0.0 && x.fxy_max > 0.0 {
            assert!(x.fz <= 0.25 * (1.0 + 1e-9), "fz {}", x.fz);
        }
    }
    // 1000 mm/min at 10000 1/min is 0.05 mm per tooth: conservative here.
    let (t0, t1) = (time_s(&input, &m), time_s(&p, &m));
    assert!(t1 < 0.8 * t0, "time {t0:.1} s became {t1:.1} s");
    // Some limit binds on most blocks; smoothing shows where it acted.
    let limited: usize = ["fxy", "power", "deflection", "feed-range", "accel"]
        .iter()
        .map(|k| ch.binding.get(k).copied().unwrap_or(0))
        .sum();
    assert!(limited * 2 > ch.blocks, "{:?}", ch.binding);
}

/// A straight ball-end pass through a box, next to an earlier pass, against
/// the analytic planar raster of §1.4(a) with the same depth and stepover.
#[test]
fn a_pass_through_the_stock_loads_the_tool_as_the_planar_raster_does() {
    use millplan_models::force::converge::ConvergedModel;
    use millplan_models::force::engage::PlanarRaster;
    use millplan_models::force::Cut;
    use millplan_nc::{Move, Operation};
    let (ap, ae, fz, n) = (0.5, 0.8, 0.05, 10000.0);
    let mut op = Operation {
        name: None,
        tool: None,
        frame: None,
        start: millplan_geom::DVec3::new(-10.0, -ae, 10.0),
        moves: Vec::new(),
        arcs: Vec::new(),
        cycles: Vec::new(),
        orients: Vec::new(),
        events: Vec::new(),
    };
    let feed = fz * 2.0 * n;
    let mut push = |m: Move| op.moves.push(Move { spindle: n, ..m });
    for y in [-ae, 0.0] {
        push(Move::rapid(millplan_geom::DVec3::new(-10.0, y, 10.0)));
        push(Move::linear(millplan_geom::DVec3::new(-10.0, y, -ap), feed));
        for k in 1..=60 {
            push(Move::linear(
                millplan_geom::DVec3::new(-10.0 + k as f64 * 0.5, y, -ap),
                feed,
            ));
        }
        push(Move::rapid(millplan_geom::DVec3::new(20.0, y, 10.0)));
    }
    let mut p = Program::new(millplan_nc::Dialect::AptIso);
    p.operations.push(op);
    let stock = Stock::block(
        millplan_geom::DVec3::new(-2.0, -10.0, -10.0),
        millplan_geom::DVec3::new(30.0, 10.0, 0.0),
        0.1,
    );
    let run = forces(&p, stock, &Machine::default());
    // The middle of the second pass.
    let got: Vec<f64> = run.moves[100..115].iter().map(|x| x.fxy_max).collect();
    let sim = got.iter().sum::<f64>() / got.len() as f64;
    let s = setup();
    let edge = millplan_models::force::edge::Tool {
        shape: Shape::Ball { radius: 5.0 },
        flutes: 2,
        helix: s.helix,
        flute_length: 30.0,
    };
    // Both on the setup's steps. The stock counts an edge point as material
    // only LIFT_SHARE of a dexel below a column's top (force.rs): with the
    // steps converged per engagement the analytic pass to compare with is
    // that much shallower; on the fixed 0.05 mm slices, centred 0.025 mm
    // below the top, the 0.02 mm does not show.
    let lift = millplan_plan::force::LIFT_SHARE * 0.1;
    let (refine, depth) = match s.refine {
        Some(r) => (r, ap - lift),
        None => (
            millplan_models::force::converge::Refine {
                halvings: 0,
                ..Default::default()
            },
            ap,
        ),
    };
    let model = ConvergedModel::new(edge, s.law, s.grid, refine).expect("model");
    let raster = PlanarRaster::new(&edge, depth, Some(ae), 0.0, 0.0).expect("raster");
    let want = model
        .evaluate(
            &Cut {
                fz,
                rpm: n,
                lead: 0.0,
                tilt: 0.0,
            },
            &raster,
        )
        .summary()
        .fxy_max;
    assert!(
        (sim - want).abs() < 0.02 * want,
        "F_xy,max {sim:.1} N in the stock, {want:.1} N analytic"
    );
}

/// The full slot of issue 30, fault 1: a D10 flat end mill enters a box at
/// X −10 and leaves it at X 50 in one move, `G1 X60 F1120`. The move ends in
/// air, so a load taken only at its end is zero and the move keeps its
/// feed; loaded along the move, its F_xy is the analytic slot's (§1.4(a)
/// without a stepover), and the scheduled feed keeps it under the limit when
/// the written program is simulated again.
fn slot_case() -> (Program, Stock) {
    use millplan_geom::DVec3;
    use millplan_nc::{Move, Operation};
    let mut op = Operation {
        tool: Some(millplan_nc::Tool {
            number: Some(1),
            name: Some("FLAT D10".into()),
            cutter: None,
            line: 0,
        }),
        start: DVec3::new(-20.0, 0.0, 5.0),
        ..Operation::default()
    };
    for m in [
        Move::rapid(DVec3::new(-20.0, 0.0, 5.0)),
        Move::linear(DVec3::new(-20.0, 0.0, -SLOT_AP), 500.0),
        Move::linear(DVec3::new(60.0, 0.0, -SLOT_AP), 1120.0),
        Move::rapid(DVec3::new(60.0, 0.0, 5.0)),
    ] {
        op.moves.push(Move {
            spindle: SLOT_RPM,
            ..m
        });
    }
    let mut p = Program::new(millplan_nc::Dialect::AptIso);
    p.operations.push(op);
    let stock = Stock::block(
        DVec3::new(-10.0, -20.0, -10.0),
        DVec3::new(50.0, 20.0, 0.0),
        0.1,
    );
    (p, stock)
}

const SLOT_AP: f64 = 3.0;
const SLOT_RPM: f64 = 8000.0;

fn flat(_: &millplan_nc::Operation) -> Option<ToolBody> {
    Some(ToolBody::new(Shape::Flat { radius: 5.0 }))
}

fn slot_forces(p: &Program, stock: Stock) -> ForceRun {
    let s = strokes(
        p,
        flat,
        &PathOptions {
            chord: 0.025,
            rapid_rate: 15000.0,
        },
    );
    simulate(p, &s, stock, &setup(), LimitUse::None, &|_| {}).expect("simulates")
}

/// F_xy,max of the analytic full slot at feed `f` (mm/min).
fn analytic_slot_fxy(f: f64) -> f64 {
    use millplan_models::force::engage::PlanarRaster;
    use millplan_models::force::{Cut, ForceModel};
    let s = setup();
    let edge = millplan_models::force::edge::Tool {
        shape: Shape::Flat { radius: 5.0 },
        flutes: 2,
        helix: s.helix,
        flute_length: 30.0,
    };
    let model = ForceModel::new(edge, s.law, s.grid).expect("model");
    let slot = PlanarRaster::new(&edge, SLOT_AP, None, 0.0, 0.0).expect("slot");
    let cut = Cut {
        fz: f / (2.0 * SLOT_RPM),
        rpm: SLOT_RPM,
        lead: 0.0,
        tilt: 0.0,
    };
    model.evaluate(&cut, &slot).summary().fxy_max
}

#[test]
fn a_slot_that_ends_in_air_is_loaded_along_its_move() {
    let (p, stock) = slot_case();
    let run = slot_forces(&p, stock);
    let slot = run.moves.iter().find(|m| m.index == 2).expect("the slot");
    let want = analytic_slot_fxy(1120.0);
    assert!(!slot.air && !slot.unmodelled, "{slot:?}");
    assert!(
        (slot.fxy_max - want).abs() < 0.03 * want,
        "F_xy,max {:.1} N along the slot, {want:.1} N analytic",
        slot.fxy_max
    );
    // The plunge beside the box cuts nothing.
    assert!(run
        .moves
        .iter()
        .find(|m| m.index == 1)
        .is_some_and(|m| m.air));
}

#[test]
fn a_slot_that_ends_in_air_is_scheduled_under_the_limit() {
    let (mut p, stock) = slot_case();
    let m = Machine::default();
    let limit = 0.7 * analytic_slot_fxy(1120.0);
    let params = FeedParams {
        setup: setup(),
        limits: FeedLimits {
            fxy: Some(limit),
            power: None,
            deflection: None,
            fz_max: Some(0.2),
            ..limits()
        },
        accel: 2000.0,
        chord: 0.025,
        learned: Vec::new(),
    };
    let mut pass = FeedPass::new(params, stock.clone(), Box::new(flat));
    let cx = Context::new(m.clone()).verifying();
    pipeline::run(&mut [&mut pass], &mut p, &cx).expect("the pass runs");
    let ch = pass.changes.expect("changes");
    assert_eq!(ch.binding.get("fxy"), Some(&1), "{ch:?}");
    assert_eq!(ch.kept_blocks, 0, "{ch:?}");
    let feed = p.operations[0].moves[2].feed;
    assert!(feed < 1120.0, "the slot's feed {feed} was not lowered");
    // The written program simulated again: loaded, at the limit, not over.
    let after = slot_forces(&p, stock);
    let slot = after.moves.iter().find(|m| m.index == 2).expect("the slot");
    assert!(
        slot.fxy_max <= limit * (1.0 + 1e-9) && slot.fxy_max > 0.97 * limit,
        "F_xy,max {:.1} N against a limit of {limit:.1} N",
        slot.fxy_max
    );
}

/// Issue 30, "done when": a program scheduled under `fxy=100` (the demo's
/// ball D10 finishing raster over the demo surface, al7075) and re-checked
/// with the force grid's slice length and rotation step each four times
/// finer than the default, fixed, stays within 2 % of its limit. The
/// default grid used to under-predict F_xy,max by up to 22 %, and such a
/// schedule had 2,446 of 6,384 blocks over its limit at the finer grid.
#[test]
fn a_schedule_rechecked_on_a_four_times_finer_grid_stays_within_two_percent() {
    let (mut p, stock) = case();
    let m = Machine::default();
    let limits = FeedLimits {
        fxy: Some(100.0),
        torque: None,
        power: None,
        stress: None,
        deflection: None,
        ..limits()
    };
    let params = FeedParams {
        setup: setup(),
        limits,
        accel: 2000.0,
        chord: 0.025,
        learned: Vec::new(),
    };
    let mut pass = FeedPass::new(params, stock.clone(), Box::new(body));
    let cx = Context::new(m.clone());
    pipeline::run(&mut [&mut pass], &mut p, &cx).expect("the pass runs");
    let ch = pass.changes.expect("changes");
    let held = held_at_fz_min(pass.before.as_ref().expect("loads"), &pass.params.limits);
    assert!(
        ch.binding.get("fxy").copied().unwrap_or(0) > 100,
        "the limit must bind: {:?}",
        ch.binding
    );
    let mut fine = setup();
    fine.grid.dz /= 4.0;
    fine.grid.dphi /= 4.0;
    fine.refine = None;
    let s = strokes_of(&p, &m);
    let after = simulate(&p, &s, stock, &fine, LimitUse::None, &|_| {}).expect("simulates");
    let worst = after
        .moves
        .iter()
        .filter(|x| !x.unmodelled && !held.contains(&x.index))
        .map(|x| x.fxy_max)
        .fold(0.0, f64::max);
    assert!(worst > 90.0, "the limit is reached: {worst} N");
    assert!(worst <= 102.0, "F_xy,max {worst} N at the finer grid");
    // The moves held at the smallest feed per tooth are at or over the
    // limit on the finer grid too (within the same 2 %): the default grid
    // did not invent them.
    for x in after.moves.iter().filter(|x| held.contains(&x.index)) {
        assert!(x.fxy_max > 98.0, "move {} at {} N", x.index, x.fxy_max);
    }
}

/// The moves a schedule (`run`, the pass's loads of its input) held at the
/// smallest feed per tooth because a limit could not be met even there:
/// `feed` reports them as still over the limit and exits 3.
fn held_at_fz_min(run: &ForceRun, limits: &FeedLimits) -> std::collections::HashSet<u32> {
    run.moves
        .iter()
        .filter(|x| x.binding == Some("feed-range"))
        .filter(|x| {
            x.fz_allowed
                .is_some_and(|a| a <= limits.fz_min * (1.0 + 1e-9))
        })
        .map(|x| x.index)
        .collect()
}
