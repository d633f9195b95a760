//! `millplan feed`: a feed per block from the cutting forces; and what
//! `millplan force PATH` shares with it (the program, its stock, the model).

use crate::cmd::cut::load_materials;
use crate::cmd::simulate::initial_stock;
use crate::cmd::{
    arg, print_diagnostics, read_options, tool_shape, write_program_file, Range, TargetArg, UnitArg,
};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::{read_program, read_surface, Outputs};
use millplan_models::cutter::Shape;
use millplan_models::force::Grid;
use millplan_plan::feed::{machine_accel, BodyFn, FeedParams, FeedPass};
use millplan_plan::force::{simulate, FeedLimits, ForceRun, ForceSetup, MoveForces};
use millplan_plan::machine::Machine;
use millplan_plan::pipeline::{self, Context};
use millplan_sim::stock::path::{strokes, PathOptions, Strokes};
use millplan_sim::stock::spec::StockSpec;
use millplan_sim::stock::tool::{BodyOptions, ToolBody};
use millplan_sim::stock::Stock;
use serde_json::json;
use std::path::{Path, PathBuf};

/// The program's stock, material and tools (shared by `force PATH` and `feed`).
#[derive(clap::Args, Clone)]
pub struct ModelArgs {
    /// Initial stock: box:auto or box:auto:MARGIN, box:X0,Y0,Z0,X1,Y1,Z1,
    /// cylinder:auto or cylinder:auto:MARGIN, cylinder:CX,CY,Z0,Z1,D, stl:FILE or
    /// offset:MM (the --stl part grown by MM), as in `millplan simulate`.
    #[arg(long)]
    pub stock: Option<String>,
    /// Part surface (STL), for --stock offset:MM.
    #[arg(long)]
    pub stl: Option<PathBuf>,
    /// Unit of the STL files' numbers (an STL does not say): mm (default) or
    /// inch, converted to mm on reading.
    #[arg(long, value_enum)]
    pub stl_units: Option<crate::cmd::UnitArg>,
    /// Named material (`millplan force materials` lists them).
    #[arg(long)]
    pub material: Option<String>,
    /// A TOML file of further materials.
    #[arg(long)]
    pub materials: Option<PathBuf>,
    /// Machine file (TOML): feed range, rapid rate, axis accelerations, the
    /// spindle's power/torque chart (its limits at each block's speed).
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Cutter for operations whose tool has no geometry, or to override it:
    /// ball:D, flat:D or bull:D:R.
    #[arg(long)]
    pub tool: Option<String>,
    /// Flutes of every tool.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::FLUTES)]
    pub flutes: usize,
    /// Helix angle, degrees.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::HELIX_DEG, allow_hyphen_values = true)]
    pub helix: f64,
    /// Gauge length from the holder face to the tip, mm (default 3·D).
    #[arg(long)]
    pub stickout: Option<f64>,
    /// Fluted length, mm (default: the program's tool height, else the
    /// stick-out); a stepped cantilever when shorter than the stick-out.
    #[arg(long)]
    pub flute_length: Option<f64>,
    /// Young's modulus of the tool, N/mm².
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::MODULUS)]
    pub modulus: f64,
    /// Dexel size of the stock, mm; also the spacing of the poses each move
    /// is loaded at along its length.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::RESOLUTION)]
    pub resolution: f64,
    /// Axial slice height of the force model, mm (with --converge the
    /// largest used: per load sample the model halves it, up to four
    /// times, until F_xy,max and T_max are estimated within 0.4 %).
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::DZ)]
    pub dz: f64,
    /// Rotation step of the force model, degrees: the largest used, halved
    /// like --dz.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::DPHI_DEG)]
    pub dphi: f64,
    /// Refine --dz and --dphi per load sample until F_xy,max and T_max
    /// converge (within 0.4 %). The default grid can under-predict F_xy,max
    /// of a ball-end cut by 10-20 %; converging costs tens of times the
    /// force evaluations, so it is off by default. Use it to check a
    /// schedule whose loads sit close to their limits.
    #[arg(long)]
    pub converge: bool,
    /// Spindle speed, 1/min, for the moves of a program that gives none (no
    /// S word, as some CAM systems write finishing programs): the forces
    /// need one. Moves with an S word keep theirs.
    #[arg(long, value_name = "RPM")]
    pub spindle: Option<f64>,
    /// Units of a program that does not say.
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    /// One CSV row per move: loads, feed per tooth, allowed feed, binding limit.
    #[arg(long, value_name = "FILE")]
    pub table: Option<PathBuf>,
    /// HTML report: loads against time with the limits drawn.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// No progress bar or warnings.
    #[arg(long, short)]
    pub quiet: bool,
}

/// A program ready for force simulation.
pub struct Prepared {
    pub program: millplan_nc::Program,
    pub strokes: Strokes,
    pub stock: Stock,
    pub setup: ForceSetup,
    pub machine: Machine,
    pub stock_name: String,
}

fn need<'a>(v: &'a Option<String>, flag: &str) -> CliResult<&'a str> {
    v.as_deref()
        .ok_or_else(|| CliError::input(format!("give {flag}")))
}

/// The force model's setup from the options, every number checked.
pub fn force_setup(m: &ModelArgs) -> CliResult<ForceSetup> {
    let materials = load_materials(m.materials.as_deref())?;
    let law = materials
        .get(need(&m.material, "--material")?)
        .map_err(|e| CliError::input(format!("--material: {e}")))?
        .law;
    if !(1..=64).contains(&m.flutes) {
        return Err(CliError::input(format!(
            "--flutes {}: must be from 1 to 64",
            m.flutes
        )));
    }
    arg("--helix", m.helix, Range::from(-70.0, 70.0, "degrees"))?;
    arg("--dz", m.dz, Range::from(0.001, 1.0, "mm"))?;
    arg("--dphi", m.dphi, Range::from(0.01, 10.0, "degrees"))?;
    let (lo, hi) = millplan_models::force::deflect::MODULUS_RANGE;
    arg("--modulus", m.modulus, Range::from(lo, hi, "N/mm²"))?;
    arg(
        "--resolution",
        m.resolution,
        Range::from(0.005, 100.0, "mm"),
    )?;
    for (flag, v) in [
        ("--stickout", m.stickout),
        ("--flute-length", m.flute_length),
    ] {
        if let Some(v) = v {
            arg(flag, v, Range::positive(10_000.0, "mm"))?;
        }
    }
    let mut s = ForceSetup::new(law, m.flutes);
    s.helix = m.helix.to_radians();
    s.grid = Grid {
        dz: m.dz,
        dphi: m.dphi.to_radians(),
    };
    if m.converge {
        s.refine = Some(millplan_models::force::converge::Refine::default());
    }
    s.stickout = m.stickout;
    s.flute_length = m.flute_length;
    s.modulus = m.modulus;
    Ok(s)
}

/// The tool body of an operation: its cutter or --tool, flutes from
/// --flute-length or the program's tool height.
pub fn body_fn(m: &ModelArgs) -> CliResult<BodyFn> {
    let fallback = match &m.tool {
        Some(s) => Some(tool_shape("--tool", s)?),
        None => None,
    };
    if matches!(fallback, Some(Shape::Cone { .. })) {
        return Err(CliError::input("--tool: use ball:D, flat:D or bull:D:R"));
    }
    let o = BodyOptions {
        shape: fallback,
        flute: m.flute_length,
        no_cone: true,
        ..BodyOptions::default()
    };
    Ok(Box::new(move |op: &millplan_nc::Operation| {
        ToolBody::for_operation(op, &o)
    }))
}

/// Reads the program and builds its strokes and stock.
pub fn prepare(path: &Path, m: &ModelArgs) -> CliResult<Prepared> {
    let setup = force_setup(m)?;
    let stock_name = need(&m.stock, "--stock")?.to_string();
    let spec =
        StockSpec::parse(&stock_name).map_err(|e| CliError::input(format!("--stock {e}")))?;
    let machine = crate::cmd::load_machine(m.machine.as_deref())?;
    let mut parsed = read_program(path, read_options(m.units, None)?)?;
    print_diagnostics(path, &parsed.diagnostics, m.quiet || m.json);
    if let Some(n) = m.spindle {
        arg("--spindle", n, Range::positive(1.0e6, "1/min"))?;
        millplan_plan::force::supply_spindle(&mut parsed.program, n);
    }
    let body = body_fn(m)?;
    let s = strokes(
        &parsed.program,
        &body,
        &PathOptions {
            chord: m.resolution / 4.0,
            rapid_rate: machine.rapid,
        },
    );
    if s.strokes.iter().all(|x| x.rapid) {
        return Err(CliError::input(format!(
            "{}: no cutting move can be simulated (give the tool's shape with --tool ball:D, flat:D or bull:D:R; {} moves from or to an unknown position)",
            path.display(),
            s.skipped.unknown_position
        )));
    }
    let part = match &m.stl {
        Some(p) => Some(read_surface(p, m.stl_units)?.0),
        None => None,
    };
    let stock = initial_stock(path, m.resolution, &spec, &s, part.as_ref(), m.stl_units)?;
    Ok(Prepared {
        program: parsed.program,
        strokes: s,
        stock,
        setup,
        machine,
        stock_name,
    })
}

/// Refuses a run with a move that cut with the spindle stopped, at its line.
pub fn stopped_spindle(path: &Path, run: &ForceRun) -> CliResult<()> {
    match run.stopped_spindle() {
        Some(line) => Err(CliError::input(format!(
            "{}:{line}:1: {}, {}",
            path.display(),
            millplan_plan::force::STOPPED_SPINDLE,
            millplan_plan::force::SPINDLE_OPTION
        ))),
        None => Ok(()),
    }
}

/// Forces of the prepared program, with a progress bar.
pub fn run_forces(
    p: &Prepared,
    program: &millplan_nc::Program,
    s: &Strokes,
    quiet: bool,
) -> CliResult<ForceRun> {
    let bar = crate::progress::count(s.strokes.len() as u64, "forces", "strokes", !quiet);
    let r = simulate(program, s, p.stock.clone(), &p.setup, None, &|d| {
        bar.set_position(d as u64)
    });
    bar.finish_and_clear();
    r.map_err(CliError::input)
}

/// The load limits of `--limit NAME=VALUE` with the feed-per-tooth range
/// (`fz_max` None: each tool's from the material's chip loads).
pub fn load_limits(
    fos: f64,
    fz_min: f64,
    fz_max: Option<f64>,
    chip_loads: Option<millplan_models::force::materials::ChipLoads>,
) -> CliResult<FeedLimits> {
    let mut l = FeedLimits {
        fxy: None,
        torque: None,
        power: None,
        stress: None,
        deflection: None,
        fos,
        fz_min,
        fz_max,
        chip_loads,
    };
    for (name, value) in crate::limits::loads() {
        let v: f64 = value
            .parse()
            .map_err(|_| CliError::input(format!("--limit {name}={value}: not a number")))?;
        let flag = format!("--limit {name}");
        let x = arg(&flag, v, Range::positive(1e9, "(N, N·mm, W, MPa or mm)"))?;
        let v = Some(x);
        match name.as_str() {
            "fxy" => l.fxy = v,
            "torque" => l.torque = v,
            "power" => l.power = v,
            "stress" => l.stress = v,
            "fz_min" => l.fz_min = x,
            "fz_max" => l.fz_max = v,
            _ => l.deflection = v,
        }
    }
    Ok(l)
}

/// A feed per block from the cutting forces (the feed iteration of
/// docs/forces.md).
///
/// The program runs stroke by stroke through its stock; each cutting stroke
/// gets the feed per tooth at which the tightest limit is met: --limit
/// fxy=N,torque=N·mm,power=W,stress=MPa,deflection=mm and the machine's
/// spindle chart (power and torque at the block's speed), power, torque and
/// stress divided by --fos. A block takes the smallest of its strokes'. Blocks
/// whose edge meets no material run at the machine file's `[feed] air`, else
/// at the tool's --fz-max times its flutes and speed. Every cutting move is
/// loaded all along it (every dexel of --resolution), not only where it
/// ends. Feeds stay within --fz-min..--fz-max and the machine's feed range;
/// changes between
/// blocks are brought within the feed acceleration by lowering feeds only.
/// Positions, spindle speeds and feed modes are kept; canned cycles keep
/// their feeds. The written program is simulated again: its own prediction.
///
/// Exit codes: 0 done (moves over a limit by at most 0.5 %, within the
/// model's resolution, are reported as such); 2 bad input; 3 the written
/// program still exceeds a limit by more than 0.5 % somewhere (even
/// --fz-min is too much there; the program is written).
#[derive(clap::Args)]
pub struct Args {
    /// Program (APT/CL or G-code).
    pub path: PathBuf,
    #[command(flatten)]
    pub model: ModelArgs,
    /// Output program.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output dialect (default: the machine's, else the file name's, else the input's).
    #[arg(long, value_enum)]
    pub to: Option<TargetArg>,
    /// Smallest feed per tooth, mm (at most a tool's largest).
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::FZ_MIN)]
    pub fz_min: f64,
    /// Largest feed per tooth, mm, for every tool (the tool maker's chip
    /// load); default: per tool, the material's chip load at its diameter
    /// (`fz_max` of the materials table), else 0.02·D.
    #[arg(long)]
    pub fz_max: Option<f64>,
    /// Factor of safety on power, torque and stress.
    #[arg(long, default_value_t = millplan_driver::command_defaults::feed::FOS)]
    pub fos: f64,
    /// Feed acceleration, mm/s² (default: the machine's smallest linear-axis
    /// acceleration, else 1000).
    #[arg(long)]
    pub feed_accel: Option<f64>,
}

fn feed_params(a: &Args, p: &Prepared) -> CliResult<FeedParams> {
    arg("--fz-min", a.fz_min, Range::positive(5.0, "mm"))?;
    if let Some(f) = a.fz_max {
        arg(
            "--fz-max",
            f,
            Range::from(a.fz_min, 5.0, "mm (from --fz-min)"),
        )?;
    }
    let material = need(&a.model.material, "--material")?;
    let chip_loads = load_materials(a.model.materials.as_deref())?
        .get(material)
        .map_err(|e| CliError::input(format!("--material: {e}")))?
        .chip_loads;
    arg("--fos", a.fos, Range::from(1.0, 100.0, ""))?;
    let accel = a
        .feed_accel
        .or_else(|| machine_accel(&p.machine))
        .unwrap_or(millplan_driver::defaults::Defaults::FEED_ACCEL);
    arg("--feed-accel", accel, Range::positive(1e6, "mm/s²"))?;
    let limits = load_limits(a.fos, a.fz_min, a.fz_max, chip_loads)?;
    Ok(FeedParams {
        setup: p.setup,
        limits,
        accel,
        chord: a.model.resolution / 4.0,
    })
}

pub fn run(a: Args) -> CliResult<i32> {
    let m = &a.model;
    let mut inputs: Vec<&Path> = vec![&a.path];
    inputs.extend(m.stl.as_deref());
    inputs.extend(m.machine.as_deref());
    inputs.extend(m.materials.as_deref());
    let blank = m.stock.as_deref().and_then(StockSpec::file_of);
    inputs.extend(blank.as_deref());
    let mut outputs = Outputs::plan(
        &inputs,
        &[
            ("-o", Some(&a.output)),
            ("--table", m.table.as_deref()),
            ("--report", m.report.as_deref()),
        ],
        false,
    )?;
    let p = prepare(&a.path, m)?;
    let params = feed_params(&a, &p)?;
    let limits = params.limits;
    let target = crate::cmd::target_with_machine(a.to, &a.output, &p.machine, p.program.source)?;
    let mut out = p.program.clone();
    let mut pass = FeedPass::new(params, p.stock.clone(), body_fn(m)?);
    let bar = crate::progress::Phases::new(!(m.quiet || m.json));
    let hook = |phase: &str, done: usize, total: usize| bar.report(phase, done, total);
    let cx = Context::new(p.machine.clone()).with_progress(&hook);
    let ran = pipeline::run(&mut [&mut pass], &mut out, &cx);
    bar.finish();
    ran.map_err(|e| crate::cmd::pass_error(&a.path, e))?;
    let (Some(before), Some(changes)) = (pass.before.take(), pass.changes.take()) else {
        return Err(CliError::internal("the feed pass left no result"));
    };
    stopped_spindle(&a.path, &before)?;
    let s2 = strokes(
        &out,
        body_fn(m)?,
        &PathOptions {
            chord: m.resolution / 4.0,
            rapid_rate: p.machine.rapid,
        },
    );
    let after = run_forces(&p, &out, &s2, m.quiet || m.json)?;
    write_program_file(
        &out,
        cx.machine.write_options(target),
        &mut outputs,
        &a.output,
        &a.path,
        m.quiet,
    )?;
    let over = after.over_limits(&limits, &p.machine);
    let near = after.within_tolerance(&limits, &p.machine).len();
    let runs = [&before, &after];
    let mut summary = feed_summary(&a, &p, &out, runs, &changes, &pass.params, target, &over);
    summary["within_tolerance_after"] = near.into();
    write_extras(
        m,
        &mut outputs,
        &summary,
        &before,
        &after,
        &limits,
        &p.machine,
    )?;
    outputs.commit()?;
    print_feed(&a, &summary);
    Ok(if over.is_empty() {
        EXIT_OK
    } else {
        EXIT_FINDINGS
    })
}

/// The JSON summary of a feed run.
#[allow(clippy::too_many_arguments)]
fn feed_summary(
    a: &Args,
    p: &Prepared,
    out: &millplan_nc::Program,
    [before, after]: [&ForceRun; 2],
    changes: &millplan_plan::feed::FeedChanges,
    params: &FeedParams,
    target: millplan_nc::write::Target,
    over: &[&MoveForces],
) -> serde_json::Value {
    let limits = params.limits;
    let fz = millplan_plan::feed::fz_ranges(&limits, &p.strokes.tools);
    let t = |q: &millplan_nc::Program| millplan_plan::timing::estimate_program(q, &p.machine);
    let (t0, t1) = (t(&p.program), t(out));
    json!({
        "time_before_s": t0.total_s, "time_after_s": t1.total_s,
        "time_nominal_before_s": t0.nominal_s, "time_nominal_after_s": t1.nominal_s,
        "time_model": "acceleration",
        "max_before": before.maxima(), "max_after": after.maxima(),
        "binding": changes.binding, "blocks": changes.blocks, "air_blocks": changes.air_blocks,
        "kept_blocks": changes.kept_blocks, "feed_range_written": [changes.feed_min, changes.feed_max],
        "feed_accel": params.accel, "fz_range": fz_range(&fz), "fz_by_tool": fz,
        "limit_tolerance": millplan_plan::force::LIMIT_TOLERANCE,
        "limits": {"fxy": limits.fxy, "torque": limits.torque, "power": limits.power, "stress": limits.stress, "deflection": limits.deflection, "fos": limits.fos},
        "over_limit_after": over.len(), "over_limit_lines": over.iter().take(20).map(|x| x.line).collect::<Vec<_>>(),
        "stock": p.stock_name, "output": a.output.display().to_string(), "dialect": target.name(),
        "operations": per_operation(out, before, after),
        "steps": before.steps(&p.setup.grid),
    })
}

/// The smallest and largest feed per tooth over the tools.
fn fz_range(fz: &[millplan_plan::force::FzRange]) -> [f64; 2] {
    let lo = fz.iter().map(|r| r.fz_min).fold(f64::INFINITY, f64::min);
    let hi = fz.iter().map(|r| r.fz_max).fold(0.0, f64::max);
    [lo.min(hi), hi]
}

/// Per operation with simulated moves: its time at the programmed feeds
/// (the simulation's strokes; the whole program's estimate with
/// acceleration is `time_before_s`/`time_after_s`) and largest F_xy before
/// and after, so a user sees which operation gained and which was
/// slowed to respect a limit.
fn per_operation(
    p: &millplan_nc::Program,
    before: &ForceRun,
    after: &ForceRun,
) -> Vec<serde_json::Value> {
    let mut starts = Vec::with_capacity(p.operations.len());
    let mut k = 0u32;
    for op in &p.operations {
        starts.push(k);
        k += op.moves.len() as u32;
    }
    let op_of = |i: u32| starts.partition_point(|s| *s <= i).saturating_sub(1);
    #[derive(Clone, Copy, Default)]
    struct Acc {
        moves: usize,
        t: [f64; 2],
        fxy: [f64; 2],
    }
    let mut acc = vec![Acc::default(); p.operations.len()];
    for (side, run) in [before, after].into_iter().enumerate() {
        for m in &run.moves {
            let a = &mut acc[op_of(m.index)];
            a.moves += usize::from(side == 0);
            a.t[side] += m.seconds;
            a.fxy[side] = a.fxy[side].max(m.fxy_max);
        }
    }
    p.operations
        .iter()
        .zip(&acc)
        .enumerate()
        .filter(|(_, (_, a))| a.moves > 0)
        .map(|(i, (op, a))| {
            json!({
                "operation": i + 1,
                "name": op.name,
                "tool": op.tool.as_ref().and_then(|t| t.number),
                "tool_name": op.tool.as_ref().and_then(|t| t.name.clone()),
                "line": op.moves.first().map(|m| m.line),
                "moves": a.moves,
                "time_nominal_before_s": a.t[0], "time_nominal_after_s": a.t[1],
                "fxy_max_before": a.fxy[0], "fxy_max_after": a.fxy[1],
            })
        })
        .collect()
}

/// The table (the input's loads with the allowed feeds) and the report.
fn write_extras(
    m: &ModelArgs,
    outputs: &mut Outputs,
    summary: &serde_json::Value,
    before: &ForceRun,
    after: &ForceRun,
    limits: &FeedLimits,
    machine: &Machine,
) -> CliResult<()> {
    if let Some(t) = &m.table {
        outputs.write(
            t,
            millplan_report::forces::moves_csv(&before.moves).as_bytes(),
        )?;
    }
    if let Some(r) = &m.report {
        let rows = summary_rows(summary);
        let html = millplan_report::forces::report(
            "millplan feed: loads before and after",
            "Per move, the largest load of its strokes against the time the move starts; the black line is the limit at the move's spindle speed.",
            &feed_notes(summary),
            &rows,
            &[("input", &before.moves), ("output", &after.moves)],
            &quantities(limits, machine),
        );
        outputs.write(r, html.as_bytes())?;
    }
    Ok(())
}

/// Warnings shared by `force` and `feed`: moves over a limit, moves whose
/// loads are missing, moves not simulated.
fn load_warnings(v: &serde_json::Value, over: &str, lines: &str) -> Vec<String> {
    let n = |k: &str| v[k].as_u64().unwrap_or(0);
    let mut w = Vec::new();
    if n(over) > 0 {
        w.push(format!(
            "{} moves exceed a limit (lines {}{})",
            n(over),
            v[lines]
                .as_array()
                .map(|a| a
                    .iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join(", "))
                .unwrap_or_default(),
            if n(over) > 20 { ", …" } else { "" }
        ));
    }
    if n("unmodelled_moves") > 0 {
        w.push(format!(
            "{} moves removed material the model could not load (spindle stopped, or no edge ahead of the feed in material): their loads are missing",
            n("unmodelled_moves")
        ));
    }
    if n("skipped_moves") > 0 {
        w.push(format!(
            "{} moves not simulated (unknown position or axis, no tool): their loads are missing",
            n("skipped_moves")
        ));
    }
    w
}

/// The force report's warnings and verdict.
pub fn force_notes(v: &serde_json::Value) -> millplan_report::html::Notes {
    let f = |a: &str, b: &str| v[a][b].as_f64().unwrap_or(0.0);
    millplan_report::html::Notes::judged(
        Vec::new(),
        load_warnings(v, "over_limit", "over_limit_lines"),
        &millplan_report::forces::force_evidence(v["over_limit"].as_u64().unwrap_or(0)),
        vec![format!(
            "Largest loads: F_xy {:.1} N (line {}), torque {:.1} N·mm (line {}), power {:.1} W (line {}), tip deflection {:.4} mm (line {}), over {:.1} s of program.",
            f("max", "fxy"),
            v["max_lines"]["fxy"],
            f("max", "torque"),
            v["max_lines"]["torque"],
            f("max", "power"),
            v["max_lines"]["power"],
            f("max", "deflection"),
            v["max_lines"]["deflection"],
            v["time_s"].as_f64().unwrap_or(0.0)
        )],
    )
}

/// One entry of the summary's `operations` in words.
fn operation_line(o: &serde_json::Value) -> String {
    let g = |k: &str| o[k].as_f64().unwrap_or(0.0);
    format!(
        "Operation {} (line {}, tool {}): {:.1} s → {:.1} s at the programmed feeds, F_xy max {:.1} → {:.1} N",
        o["operation"],
        o["line"],
        o["tool"],
        g("time_nominal_before_s"),
        g("time_nominal_after_s"),
        g("fxy_max_before"),
        g("fxy_max_after")
    )
}

/// The feed report's warnings and verdict.
fn feed_notes(v: &serde_json::Value) -> millplan_report::html::Notes {
    let g = |k: &str| v[k].as_f64().unwrap_or(0.0);
    let f = |a: &str, b: &str| v[a][b].as_f64().unwrap_or(0.0);
    let (t0, t1) = (g("time_before_s"), g("time_after_s"));
    let mut verdict = vec![format!(
        "Time {t0:.1} s → {t1:.1} s ({:+.1} %); F_xy max {:.1} → {:.1} N, tip deflection {:.4} → {:.4} mm; deciding per block: {}.",
        100.0 * (t1 / t0.max(1e-9) - 1.0),
        f("max_before", "fxy"),
        f("max_after", "fxy"),
        f("max_before", "deflection"),
        f("max_after", "deflection"),
        v["binding"]
    )];
    for o in v["operations"].as_array().into_iter().flatten() {
        verdict.push(format!("{}.", operation_line(o)));
    }
    let n = |k: &str| v[k].as_u64().unwrap_or(0);
    let e = millplan_report::forces::feed_evidence(
        n("over_limit_after"),
        n("blocks") + n("air_blocks"),
        [t0, t1],
    );
    let warnings = load_warnings(v, "over_limit_after", "over_limit_lines");
    millplan_report::html::Notes::judged(Vec::new(), warnings, &e, verdict)
}

/// The summary's scalar entries as table rows.
pub fn summary_rows(v: &serde_json::Value) -> Vec<(String, String)> {
    millplan_report::forces::summary_table(v)
}

/// The plotted quantities with their limits (user and spindle chart).
pub fn quantities<'a>(
    l: &'a FeedLimits,
    m: &'a Machine,
) -> Vec<millplan_report::forces::Quantity<'a>> {
    use millplan_report::forces::Quantity;
    let fos = l.fos;
    vec![
        Quantity {
            name: "F_xy,max",
            unit: "N",
            value: |x: &MoveForces| x.fxy_max,
            limit: Box::new(move |_| l.fxy),
        },
        Quantity {
            name: "torque T_max",
            unit: "N·mm",
            value: |x: &MoveForces| x.torque_max,
            limit: Box::new(move |x| l.at(x.rpm, 1.0, m).torque.map(|t| t / fos)),
        },
        Quantity {
            name: "power",
            unit: "W",
            value: |x: &MoveForces| x.power_w,
            limit: Box::new(move |x| l.at(x.rpm, 1.0, m).power.map(|p| p / fos)),
        },
        Quantity {
            name: "bending stress",
            unit: "MPa",
            value: |x: &MoveForces| x.stress_mpa,
            limit: Box::new(move |_| l.stress.map(|s| s / fos)),
        },
        Quantity {
            name: "tip deflection",
            unit: "mm",
            value: |x: &MoveForces| x.deflection_mm,
            limit: Box::new(move |_| l.deflection),
        },
    ]
}

fn print_feed(a: &Args, s: &serde_json::Value) {
    if a.model.json {
        crate::cmd::print_json(s.clone());
        return;
    }
    let f = |k: &str| s[k].as_f64().unwrap_or(0.0);
    outln!(
        "time {:.1} s → {:.1} s ({:+.1} %), estimated with acceleration ({:.1} s → {:.1} s at programmed feeds)",
        f("time_before_s"),
        f("time_after_s"),
        100.0 * (f("time_after_s") / f("time_before_s").max(1e-9) - 1.0),
        f("time_nominal_before_s"),
        f("time_nominal_after_s"),
    );
    for k in ["fxy", "torque", "power", "stress", "deflection"] {
        outln!(
            "  {k:<11} max {:>10.3} → {:>10.3}",
            s["max_before"][k].as_f64().unwrap_or(0.0),
            s["max_after"][k].as_f64().unwrap_or(0.0)
        );
    }
    if let Some(ops) = s["operations"].as_array().filter(|o| o.len() > 1) {
        for o in ops {
            outln!("  {}", operation_line(o));
        }
    }
    outln!(
        "{} blocks from the forces, {} in air, {} kept; binding: {}",
        s["blocks"],
        s["air_blocks"],
        s["kept_blocks"],
        s["binding"]
    );
    if f("over_limit_after") > 0.0 {
        outln!(
            "{} moves still over a limit at the smallest feed (lines {})",
            s["over_limit_after"],
            s["over_limit_lines"]
        );
    }
    if f("within_tolerance_after") > 0.0 {
        outln!(
            "{} moves over a limit by at most {} %, within the model's resolution",
            s["within_tolerance_after"],
            100.0 * f("limit_tolerance")
        );
    }
    outln!(
        "wrote {} ({})",
        a.output.display(),
        s["dialect"].as_str().unwrap_or("")
    );
}
