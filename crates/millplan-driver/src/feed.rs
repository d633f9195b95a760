//! `millplan feed` and what `millplan force PATH` shares with it: the force
//! model's setup and the tool bodies from the options, the program's strokes
//! and stock, the load limits, the feed pass run over the program, and the
//! typed summary with its text and report.

use crate::check::{arg, tool_shape, Range};
use millplan_models::cutter::Shape;
use millplan_models::force::materials::{ChipLoads, Materials};
use millplan_models::force::Grid;
use millplan_nc::{Operation, Program};
pub use millplan_plan::feed::FeedParams;
use millplan_plan::feed::{machine_accel, BodyFn, FeedChanges, FeedPass};
/// The load limits of a run.
pub use millplan_plan::force::FeedLimits;
use millplan_plan::force::{
    simulate, simulate_largest_within, ForceSetup, FzRange, LimitUse, MoveForces,
};
use millplan_plan::force::{Maxima, Steps};
use millplan_plan::machine::Machine;
use millplan_plan::pipeline::{self, Context, PassError, Progress};
use millplan_plan::safety::{self, Check, TipRule, Tolerances};
use millplan_report::html::Verdict;
use millplan_sim::stock::path::{strokes, PathOptions, Strokes};
use millplan_sim::stock::spec::StockSpec;
use millplan_sim::stock::tool::{BodyOptions, ToolBody};
use millplan_sim::stock::Stock;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// The loads of a program's run, per move.
pub use millplan_plan::force::ForceRun;

/// The options of `force PATH` and `feed` that shape the model, the tool
/// and the stock.
#[derive(Clone, Debug)]
pub struct ModelRequest {
    /// `--stock` as the user wrote it.
    pub stock: Option<String>,
    pub material: Option<String>,
    /// `--tool` (`ball:D`, `flat:D`, `bull:D:R`).
    pub tool: Option<String>,
    pub flutes: usize,
    /// Helix angle, degrees.
    pub helix: f64,
    pub stickout: Option<f64>,
    pub flute_length: Option<f64>,
    /// Young's modulus, N/mm².
    pub modulus: f64,
    pub resolution: f64,
    pub dz: f64,
    /// Rotation step, degrees.
    pub dphi: f64,
    /// Use the grid as given instead of refining it per load sample.
    pub fixed_grid: bool,
    /// `--spindle`, 1/min: the speed of the moves that have none.
    pub spindle: Option<f64>,
}

/// The options of `feed` beyond the model's.
#[derive(Clone, Copy, Debug)]
pub struct FeedRequest {
    pub fz_min: f64,
    pub fz_max: Option<f64>,
    pub fos: f64,
    pub feed_accel: Option<f64>,
}

fn need<'a>(v: &'a Option<String>, flag: &str) -> Result<&'a str, String> {
    v.as_deref().ok_or_else(|| format!("give {flag}"))
}

/// The chip loads of the request's material (`--material`, required).
fn chip_loads(m: &ModelRequest, materials: &Materials) -> Result<Option<ChipLoads>, String> {
    Ok(materials
        .get(need(&m.material, "--material")?)
        .map_err(|e| format!("--material: {e}"))?
        .chip_loads)
}

/// The force model's setup from the options, every number checked.
pub fn force_setup(m: &ModelRequest, materials: &Materials) -> Result<ForceSetup, String> {
    let law = materials
        .get(need(&m.material, "--material")?)
        .map_err(|e| format!("--material: {e}"))?
        .law;
    if !(1..=64).contains(&m.flutes) {
        return Err(format!("--flutes {}: must be from 1 to 64", m.flutes));
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
    if m.fixed_grid {
        s.refine = None;
    }
    s.stickout = m.stickout;
    s.flute_length = m.flute_length;
    s.modulus = m.modulus;
    Ok(s)
}

/// The stock the request names (`--stock`, required).
pub fn stock_spec(m: &ModelRequest) -> Result<StockSpec, String> {
    StockSpec::parse(need(&m.stock, "--stock")?).map_err(|e| format!("--stock {e}"))
}

/// The tool body of an operation: its cutter or --tool, flutes from
/// --flute-length or the program's tool height.
pub fn body_fn(m: &ModelRequest) -> Result<BodyFn, String> {
    let fallback = match &m.tool {
        Some(s) => Some(tool_shape("--tool", s)?),
        None => None,
    };
    if matches!(fallback, Some(Shape::Cone { .. })) {
        return Err("--tool: use ball:D, flat:D or bull:D:R".into());
    }
    let o = BodyOptions {
        shape: fallback,
        flute: m.flute_length,
        no_cone: true,
        ..BodyOptions::default()
    };
    Ok(Box::new(move |op: &Operation| {
        ToolBody::for_operation(op, &o)
    }))
}

/// The strokes of `program` with the request's tool bodies, at chords of a
/// quarter cell.
pub fn program_strokes(m: &ModelRequest, program: &Program, rapid: f64) -> Result<Strokes, String> {
    Ok(strokes(
        program,
        body_fn(m)?,
        &PathOptions {
            chord: m.resolution / 4.0,
            rapid_rate: rapid,
        },
    ))
}

/// The strokes of the input program at `path` (its name in errors):
/// refused when no cutting move can be simulated.
pub fn input_strokes(
    m: &ModelRequest,
    path: &str,
    program: &Program,
    rapid: f64,
) -> Result<Strokes, String> {
    let s = program_strokes(m, program, rapid)?;
    if s.strokes.iter().all(|x| x.rapid) {
        return Err(format!(
            "{path}: no cutting move can be simulated (give the tool's shape with --tool ball:D, flat:D or bull:D:R; {} moves from or to an unknown position)",
            s.skipped.unknown_position
        ));
    }
    Ok(s)
}

/// A program ready for force simulation.
pub struct Prepared {
    pub program: Program,
    pub strokes: Strokes,
    pub stock: Stock,
    pub setup: ForceSetup,
    pub machine: Machine,
    pub stock_name: String,
    /// The material's chip loads (the feed per tooth by tool diameter).
    pub chip_loads: Option<ChipLoads>,
    /// The `memory` limit of the run, bytes (what is left of it once the
    /// stock is counted bounds the force runs' engagement memo).
    pub memory: u64,
}

impl Prepared {
    /// The prepared run: `setup` from [`force_setup`], `stock` built by
    /// [`crate::simulate::build_stock`] over `strokes`.
    pub fn new(
        m: &ModelRequest,
        materials: &Materials,
        (program, strokes, stock): (Program, Strokes, Stock),
        setup: ForceSetup,
        machine: Machine,
    ) -> Result<Prepared, String> {
        Ok(Prepared {
            program,
            strokes,
            stock,
            setup,
            machine,
            stock_name: need(&m.stock, "--stock")?.to_string(),
            chip_loads: chip_loads(m, materials)?,
            memory: millplan_geom::limits::Limits::default().memory,
        })
    }
}

/// The files of a `force PATH`, `feed` or `robot --stock` run besides the
/// options, and how they are read.
pub struct ModelFiles<'a> {
    pub program: &'a std::path::Path,
    /// The part (`--stl`), for an `offset:` stock.
    pub stl: Option<&'a std::path::Path>,
    /// The unit of the STL files' numbers (the part and an `stl:` blank).
    pub stl_units: Option<millplan_nc::LengthUnit>,
    /// Further materials (`--materials`).
    pub materials: Option<&'a std::path::Path>,
    pub machine: Option<&'a std::path::Path>,
    /// How the program is read; its limits bound the meshes read and the
    /// stock's memory too.
    pub read: millplan_nc::ReadOptions,
}

pub use crate::watch::Watch;

mod command;
pub use command::{command, FeedCommand};

/// Reads the program and the files `f` names and builds its strokes and
/// stock as `req` asks: the run every force command starts from.
pub fn prepare(
    f: &ModelFiles,
    req: &ModelRequest,
    w: &dyn Watch,
) -> Result<Prepared, crate::io::IoError> {
    use crate::io::{inputs, IoError};
    let materials = inputs::read_materials(f.materials)?;
    let setup = force_setup(req, &materials).map_err(IoError::input)?;
    let spec = stock_spec(req).map_err(IoError::input)?;
    let machine = inputs::read_machine(f.machine)?;
    w.lap("materials and machine file read");
    let mut reading = |done, total| w.reading(done, total);
    let (mut parsed, _) = inputs::read_source(f.program, f.read, &mut reading)?;
    w.diagnostics(&parsed.diagnostics);
    supply_spindle(req, &mut parsed.program).map_err(IoError::input)?;
    w.lap("program read");
    let name = f.program.display().to_string();
    let s = input_strokes(req, &name, &parsed.program, machine.rapid).map_err(IoError::input)?;
    w.lap("strokes (tool bodies, moves in chords)");
    let limits = &f.read.limits;
    let part = match f.stl {
        Some(p) => Some(inputs::read_surface(p, limits, f.stl_units)?.0),
        None => None,
    };
    let blank = inputs::read_blank(&spec, limits, f.stl_units)?;
    w.lap("part and stock files read");
    let meshes = (part.as_ref(), blank.as_ref());
    // The prepared stock stays while each run cuts a copy of it.
    let memory = (limits.memory, 2);
    let stock = crate::simulate::build_stock(&name, req.resolution, &spec, &s, meshes, memory)
        .map_err(IoError::input)?;
    let p = Prepared::new(req, &materials, (parsed.program, s, stock), setup, machine)
        .map(|p| Prepared {
            memory: limits.memory,
            ..p
        })
        .map_err(IoError::input);
    w.lap("stock built");
    p
}

/// The program as [`prepare`]d from `f` and the forces of every move
/// along it (`w` hears the strokes done); a cutting move without a spindle
/// speed is an error at its line.
pub fn program_forces(
    f: &ModelFiles,
    req: &ModelRequest,
    w: &dyn Watch,
) -> Result<(Prepared, ForceRun), crate::io::IoError> {
    use crate::io::IoError;
    let p = prepare(f, req, w)?;
    let total = p.strokes.strokes.len();
    w.strokes(0, total);
    let run = forces(&p, &p.program, &p.strokes, &|d| w.strokes(d, total));
    w.forces_done();
    w.lap("forces along every move");
    let run = run.map_err(IoError::input)?;
    stopped_spindle(&f.program.display().to_string(), &run).map_err(IoError::input)?;
    Ok((p, run))
}

/// The files a `force` or `feed` run read, by the names a report shows
/// (file names, not folders).
pub struct InputNames {
    pub program: String,
    /// The part (`--stl`), when given.
    pub part: Option<String>,
}

impl InputNames {
    /// The names of the program at `program` and the part at `part`.
    pub fn of(program: &std::path::Path, part: Option<&std::path::Path>) -> InputNames {
        InputNames {
            program: file_name(program),
            part: part.map(file_name),
        }
    }
}

/// A file's name without its folder, as a report's header shows it.
pub fn file_name(f: &std::path::Path) -> String {
    f.file_name().map_or_else(
        || f.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The header rows of a `force` or `feed` report: program, part, stock,
/// the tools the program cuts with, material, machine, the model's options
/// and the load limits.
pub fn model_inputs(
    names: &InputNames,
    m: &ModelRequest,
    p: &Prepared,
    limits: &FeedLimits,
) -> Vec<(String, String)> {
    let mut tools = crate::speed::cutting_tools(&p.program);
    if let Some(t) = &m.tool {
        tools.push_str(&format!(" (--tool {t} where the program gives no shape)"));
    }
    let mc = &p.machine;
    let mut options = format!(
        "{} flutes, helix {}°, resolution {} mm, force grid dz {} mm × dφ {}°",
        m.flutes, m.helix, m.resolution, m.dz, m.dphi
    );
    if let Some(n) = m.spindle {
        options.push_str(&format!(", spindle {n} 1/min where the program gives none"));
    }
    vec![
        ("program".into(), names.program.clone()),
        (
            "part".into(),
            names.part.clone().unwrap_or_else(|| "none given".into()),
        ),
        ("stock".into(), p.stock_name.clone()),
        ("tools".into(), tools),
        (
            "material".into(),
            m.material.clone().unwrap_or_else(|| "–".into()),
        ),
        (
            "machine".into(),
            format!(
                "{}: spindle {:.0}–{:.0} 1/min, feed up to {:.0} mm/min",
                mc.name, mc.spindle_min, mc.spindle_max, mc.feed_max
            ),
        ),
        ("options".into(), options),
        ("load limits".into(), limits_words(limits)),
    ]
}

/// The load limits in words: each given limit with its unit, the factor of
/// safety and the feed per tooth's range.
pub fn limits_words(l: &FeedLimits) -> String {
    let named = [
        ("F_xy", l.fxy, "N"),
        ("torque", l.torque, "N·mm"),
        ("power", l.power, "W"),
        ("stress", l.stress, "MPa"),
        ("deflection", l.deflection, "mm"),
    ];
    let mut w: Vec<String> = named
        .iter()
        .filter_map(|(k, v, u)| v.map(|v| format!("{k} {} {u}", millplan_report::forces::round(v))))
        .collect();
    if w.is_empty() {
        w.push("none given (the machine's spindle chart only)".into());
    }
    w.push(format!(
        "factor of safety {}",
        millplan_report::forces::round(l.fos)
    ));
    let fz_max = match l.fz_max {
        Some(f) if f.is_finite() => format!("{} mm", millplan_report::forces::round(f)),
        Some(_) => "unbounded".into(),
        None => "per tool from the material's chip loads".into(),
    };
    w.push(format!(
        "feed per tooth from {} mm to {fz_max}",
        millplan_report::forces::round(l.fz_min)
    ));
    w.join(", ")
}

/// Gives the moves of `program` without a spindle speed the request's
/// `--spindle` (checked first); without the option nothing changes.
pub fn supply_spindle(m: &ModelRequest, program: &mut Program) -> Result<(), String> {
    if let Some(n) = m.spindle {
        crate::check::arg(
            "--spindle",
            n,
            crate::check::Range::positive(1.0e6, "1/min"),
        )?;
        millplan_plan::force::supply_spindle(program, n);
    }
    Ok(())
}

/// Refuses a run with a move that cut with the spindle stopped, at its line
/// of `path`, naming the option that supplies the speed.
pub fn stopped_spindle(path: &str, run: &ForceRun) -> Result<(), String> {
    match run.stopped_spindle() {
        Some(line) => Err(format!(
            "{path}:{line}:1: {}, {}",
            millplan_plan::force::STOPPED_SPINDLE,
            millplan_plan::force::SPINDLE_OPTION
        )),
        None => Ok(()),
    }
}

/// The forces of `program` cut into `s` over the prepared stock, every
/// load converged; `done` hears the strokes done.
pub fn forces(
    p: &Prepared,
    program: &Program,
    s: &Strokes,
    done: &(dyn Fn(usize) + Sync),
) -> Result<ForceRun, String> {
    simulate(program, s, p.stock.clone(), &p.setup, LimitUse::None, done)
}

/// The forces of the program a feed run wrote (`s`), as its limits are
/// checked: a load sample below every limit by more than its error is not
/// refined further ([`LimitUse::Check`]); `done` hears the strokes done.
pub fn forces_after(
    p: &Prepared,
    s: &Scheduled,
    strokes: &Strokes,
    done: &(dyn Fn(usize) + Sync),
) -> Result<ForceRun, String> {
    let check = LimitUse::Check(&s.params.limits, &p.machine);
    simulate(&s.program, strokes, p.stock.clone(), &p.setup, check, done)
}

/// The checks of `output`, the program a feed run made of the prepared
/// input ([`millplan_plan::safety::check`] with the request's tool bodies):
/// the IR, S and F within the machine, every tip where the input put it,
/// and no rapid, shank or holder in the initial stock. The loads are the
/// feed summary's own (a move still over a limit is written and reported).
pub fn checks(p: &Prepared, output: &Program, m: &ModelRequest) -> Result<Vec<Check>, String> {
    let body = body_fn(m)?;
    Ok(safety::check(&safety::Inputs {
        input: &p.program,
        output,
        part: None,
        stock: Some(&p.stock),
        tool_body: &*body,
        machine: Some(&p.machine),
        tip: TipRule::Kept,
        tol: Tolerances::default(),
        loads: None,
    }))
}

/// The stock check of the input itself, before any force is computed: a
/// feed run keeps every position, so a rapid, shank or holder the input
/// drives through the stock is in its output too, and is refused as it
/// would be there (all its findings are the input's own).
pub fn input_collisions(p: &Prepared, m: &ModelRequest) -> Result<Check, String> {
    let body = body_fn(m)?;
    let i = safety::Inputs {
        input: &p.program,
        output: &p.program,
        part: None,
        stock: Some(&p.stock),
        tool_body: &*body,
        machine: None,
        tip: TipRule::Kept,
        tol: Tolerances::default(),
        loads: None,
    };
    Ok(safety::stock(&i, &p.stock))
}

/// The load limits of `--limit NAME=VALUE` (`loads`) with the feed-per-tooth
/// range (`fz_max` None: each tool's from the material's chip loads).
pub fn load_limits(
    fos: f64,
    fz_min: f64,
    fz_max: Option<f64>,
    chip_loads: Option<ChipLoads>,
    loads: &[(String, String)],
) -> Result<FeedLimits, String> {
    let u = crate::job::UserLimits::parse(loads)?;
    Ok(FeedLimits {
        fxy: u.fxy,
        torque: u.torque,
        power: u.power,
        stress: u.stress,
        deflection: u.deflection,
        fos,
        fz_min: u.fz_min.unwrap_or(fz_min),
        fz_max: u.fz_max.or(fz_max),
        chip_loads,
    })
}

/// The limits `force PATH` checks: only those of `--limit` (`loads`).
pub fn force_limits(loads: &[(String, String)]) -> Result<FeedLimits, String> {
    load_limits(1.0, 0.0, Some(f64::INFINITY), None, loads)
}

/// The feed pass's parameters: the feed-per-tooth range, the factor of
/// safety and the feed acceleration (the machine's smallest linear-axis
/// acceleration, else [`crate::defaults::Defaults::FEED_ACCEL`]).
pub fn feed_params(
    r: &FeedRequest,
    m: &ModelRequest,
    p: &Prepared,
    loads: &[(String, String)],
) -> Result<FeedParams, String> {
    arg("--fz-min", r.fz_min, Range::positive(5.0, "mm"))?;
    if let Some(f) = r.fz_max {
        arg(
            "--fz-max",
            f,
            Range::from(r.fz_min, 5.0, "mm (from --fz-min)"),
        )?;
    }
    arg("--fos", r.fos, Range::from(1.0, 100.0, ""))?;
    let accel = r
        .feed_accel
        .or_else(|| machine_accel(&p.machine))
        .unwrap_or(crate::defaults::Defaults::FEED_ACCEL);
    arg("--feed-accel", accel, Range::positive(1e6, "mm/s²"))?;
    let mut limits = load_limits(r.fos, r.fz_min, r.fz_max, p.chip_loads, loads)?;
    let chart = p.machine.spindle_curve.is_some();
    let learned = if limits.fxy.is_none()
        && limits.torque.is_none()
        && limits.power.is_none()
        && limits.stress.is_none()
        && limits.deflection.is_none()
    {
        let budget = crate::limits::memo_budget(p.memory, &p.stock);
        let (program, strokes) = (&p.program, &p.strokes);
        let run = simulate_largest_within(program, strokes, &p.stock, &p.setup, &|_| {}, budget)?.0;
        learn(&mut limits, &run.maxima(), chart)
            .into_iter()
            .map(|(name, _)| name)
            .collect()
    } else {
        Vec::new()
    };
    Ok(FeedParams {
        setup: p.setup,
        limits,
        accel,
        chord: m.resolution / 4.0,
        learned,
    })
}

/// Load limits nothing gives take the input's own largest loads: F_xy
/// always, torque and power unless the machine's spindle chart gives them
/// at each block's speed. The program as its CAM system wrote it is the one
/// the shop has proven, so the feeds may rise where it cuts lightly but no
/// cut may load the tool more than its hardest one did (VERICUT's "learn
/// mode" takes its limits from the program in the same way). Without any
/// load limit the feed per tooth alone would bound a cut, and the material
/// table's chip load is meant for a moderate engagement: a deep full slot
/// raised to it loads the tool several times over. Returns each limit
/// learned with its value.
pub fn learn(l: &mut FeedLimits, max: &Maxima, chart: bool) -> Vec<(&'static str, f64)> {
    let mut learned = Vec::new();
    if l.fxy.is_none() && max.fxy > 0.0 {
        l.fxy = Some(max.fxy);
        learned.push(("fxy", max.fxy));
    }
    if !chart && l.torque.is_none() && max.torque > 0.0 {
        l.torque = Some(max.torque);
        learned.push(("torque", max.torque));
    }
    if !chart && l.power.is_none() && max.power > 0.0 {
        l.power = Some(max.power);
        learned.push(("power", max.power));
    }
    learned
}

/// What the feed pass made of the program.
pub struct Scheduled {
    pub program: Program,
    /// The input's loads with the feeds allowed.
    pub before: ForceRun,
    pub changes: FeedChanges,
    pub params: FeedParams,
}

/// Why the feed pass gave no program.
pub enum ScheduleError {
    /// The pass refused (the input's fault or a bug: [`PassError::is_input`]).
    Pass(PassError),
    /// The pass ran but left no result: a bug.
    Missing,
}

/// The feed pass over the prepared program, its phases told to `progress`.
pub fn schedule(
    p: &Prepared,
    params: FeedParams,
    m: &ModelRequest,
    progress: &Progress<'_>,
) -> Result<Scheduled, ScheduleError> {
    let body = body_fn(m).map_err(|_| ScheduleError::Missing)?;
    let mut out = p.program.clone();
    let mut pass = FeedPass::new(params, p.stock.clone(), body);
    let cx = Context::new(p.machine.clone()).with_progress(progress);
    pipeline::run(&mut [&mut pass], &mut out, &cx).map_err(ScheduleError::Pass)?;
    let (Some(before), Some(changes)) = (pass.before.take(), pass.changes.take()) else {
        return Err(ScheduleError::Missing);
    };
    Ok(Scheduled {
        program: out,
        before,
        changes,
        params: pass.params,
    })
}

/// The limits of a feed run as its summary names them.
#[derive(Serialize)]
pub struct LimitsJson {
    pub fxy: Option<f64>,
    pub torque: Option<f64>,
    pub power: Option<f64>,
    pub stress: Option<f64>,
    pub deflection: Option<f64>,
    pub fos: f64,
    /// The limits taken from the input's own largest loads, no load limit
    /// being given ([`learn`]).
    pub learned: Vec<&'static str>,
}

/// One operation with simulated moves: its time at the programmed feeds
/// (the simulation's strokes) and largest F_xy before and after.
#[derive(Serialize)]
pub struct OperationJson {
    pub operation: usize,
    pub name: Option<String>,
    pub tool: Option<u32>,
    pub tool_name: Option<String>,
    pub line: Option<u32>,
    pub moves: usize,
    pub time_nominal_before_s: f64,
    pub time_nominal_after_s: f64,
    pub fxy_max_before: f64,
    pub fxy_max_after: f64,
}

impl OperationJson {
    /// The operation in words.
    pub fn text(&self) -> String {
        format!(
            "Operation {} (line {}, tool {}): {:.1} s → {:.1} s at the programmed feeds, F_xy max {:.1} → {:.1} N",
            self.operation,
            json_text(&self.line),
            json_text(&self.tool),
            self.time_nominal_before_s,
            self.time_nominal_after_s,
            self.fxy_max_before,
            self.fxy_max_after
        )
    }
}

/// A value as JSON prints it (`null` for none).
fn json_text<T: Serialize>(v: &T) -> String {
    serde_json::to_string(v).unwrap_or_default()
}

/// What `feed --json` prints.
#[derive(Serialize)]
pub struct FeedSummary {
    pub time_before_s: f64,
    pub time_after_s: f64,
    pub time_nominal_before_s: f64,
    pub time_nominal_after_s: f64,
    pub time_model: &'static str,
    pub max_before: Maxima,
    pub max_after: Maxima,
    pub binding: BTreeMap<&'static str, usize>,
    pub blocks: usize,
    pub air_blocks: usize,
    pub kept_blocks: usize,
    pub feed_range_written: [f64; 2],
    pub feed_accel: f64,
    pub fz_range: [f64; 2],
    pub fz_by_tool: Vec<FzRange>,
    pub limit_tolerance: f64,
    pub limits: LimitsJson,
    pub over_limit_after: usize,
    pub over_limit_lines: Vec<u32>,
    pub within_tolerance_after: usize,
    pub stock: String,
    /// A cutting move of the input meets the stock (else nothing to act on).
    pub stock_contact: bool,
    pub output: String,
    pub dialect: &'static str,
    pub operations: Vec<OperationJson>,
    pub steps: Steps,
    /// The checks of the written program ([`checks`]).
    pub checks: Vec<Check>,
    /// The verdict by the one rule: red when a move is still over a limit
    /// or a check failed (written under `--force`), amber when no block's
    /// feed changed, a warning applies or the cycle time grew, green
    /// otherwise.
    pub verdict: Verdict,
}

/// The lines of the first 20 moves of `over`.
fn first_lines(over: &[&MoveForces]) -> Vec<u32> {
    over.iter().take(20).map(|x| x.line).collect()
}

impl FeedSummary {
    /// The summary of a feed run: `s` the pass's result, `after` the written
    /// program's loads and `checks` its checks, `output` its name, `dialect`
    /// the target's.
    pub fn new(
        p: &Prepared,
        s: &Scheduled,
        (after, checks): (&ForceRun, Vec<Check>),
        output: &str,
        dialect: &'static str,
    ) -> Self {
        let limits = s.params.limits;
        let fz = millplan_plan::feed::fz_ranges(&limits, &p.strokes.tools);
        let t = |q: &Program| millplan_plan::timing::estimate_program(q, &p.machine);
        let (t0, t1) = (t(&p.program), t(&s.program));
        let over = after.over_limits(&limits, &p.machine);
        let c = &s.changes;
        let over_lines = first_lines(&over);
        let mut e = millplan_report::forces::feed_evidence(
            over.len() as u64,
            (c.blocks + c.air_blocks) as u64,
            [t0.total_s, t1.total_s],
        );
        e.failed
            .extend(millplan_report::html::failed_checks(&checks));
        let mut warnings = load_warnings(over.len(), &over_lines, 0, (0, None));
        let stock_contact = meets_stock(&s.before);
        if !stock_contact {
            e.kept = true;
            warnings.push(no_contact(&p.stock_name));
        }
        let verdict = Verdict::of(&e, warnings);
        FeedSummary {
            time_before_s: t0.total_s,
            time_after_s: t1.total_s,
            time_nominal_before_s: t0.nominal_s,
            time_nominal_after_s: t1.nominal_s,
            time_model: "acceleration",
            max_before: s.before.maxima(),
            max_after: after.maxima(),
            binding: c.binding.clone(),
            blocks: c.blocks,
            air_blocks: c.air_blocks,
            kept_blocks: c.kept_blocks,
            feed_range_written: [c.feed_min, c.feed_max],
            feed_accel: s.params.accel,
            fz_range: fz_range(&fz),
            fz_by_tool: fz,
            limit_tolerance: millplan_plan::force::LIMIT_TOLERANCE,
            limits: LimitsJson {
                fxy: limits.fxy,
                torque: limits.torque,
                power: limits.power,
                stress: limits.stress,
                deflection: limits.deflection,
                fos: limits.fos,
                learned: s.params.learned.clone(),
            },
            over_limit_after: over.len(),
            over_limit_lines: over_lines,
            within_tolerance_after: after.within_tolerance(&limits, &p.machine).len(),
            stock: p.stock_name.clone(),
            stock_contact,
            output: output.to_string(),
            dialect,
            operations: per_operation(&s.program, &s.before, after),
            steps: s.before.steps(&p.setup.grid),
            checks,
            verdict,
        }
    }

    /// Whether the run found problems (exit 3): moves still over a limit,
    /// no cutting move that meets the stock, or a check that failed (the
    /// program written under `--force`).
    pub fn findings(&self) -> bool {
        self.over_limit_after > 0 || !self.stock_contact || !safety::passed(&self.checks)
    }

    /// The summary in words, as `feed` prints it.
    pub fn render_text(&self) -> String {
        let mut o = String::new();
        let (t0, t1) = (self.time_before_s, self.time_after_s);
        let _ = writeln!(
            o,
            "time {t0:.1} s → {t1:.1} s ({:+.1} %), estimated with acceleration ({:.1} s → {:.1} s at programmed feeds)",
            100.0 * (t1 / t0.max(1e-9) - 1.0),
            self.time_nominal_before_s,
            self.time_nominal_after_s,
        );
        let pairs = [
            ("fxy", self.max_before.fxy, self.max_after.fxy),
            ("torque", self.max_before.torque, self.max_after.torque),
            ("power", self.max_before.power, self.max_after.power),
            ("stress", self.max_before.stress, self.max_after.stress),
            (
                "deflection",
                self.max_before.deflection,
                self.max_after.deflection,
            ),
        ];
        for (k, b, a) in pairs {
            let _ = writeln!(o, "  {k:<11} max {b:>10.3} → {a:>10.3}");
        }
        if !self.limits.learned.is_empty() {
            let _ = writeln!(
                o,
                "  no load limit given: {} held to the input's largest (give --limit to raise them)",
                self.limits.learned.join(", ")
            );
        }
        if self.operations.len() > 1 {
            for op in &self.operations {
                let _ = writeln!(o, "  {}", op.text());
            }
        }
        self.render_tail(&mut o);
        o
    }

    /// The blocks, what is still over a limit and the file written.
    fn render_tail(&self, o: &mut String) {
        let _ = writeln!(
            o,
            "{} blocks from the forces, {} in air, {} kept; binding: {}",
            self.blocks,
            self.air_blocks,
            self.kept_blocks,
            json_text(&self.binding)
        );
        if self.over_limit_after > 0 {
            let _ = writeln!(
                o,
                "{} moves still over a limit at the smallest feed (lines {})",
                self.over_limit_after,
                json_text(&self.over_limit_lines)
            );
        }
        if self.within_tolerance_after > 0 {
            let _ = writeln!(
                o,
                "{} moves over a limit by at most {} %, within the model's resolution",
                self.within_tolerance_after,
                100.0 * self.limit_tolerance
            );
        }
        let _ = writeln!(o, "wrote {} ({})", self.output, self.dialect);
        o.push_str(&self.verdict.text());
    }

    /// The feed report's warnings and verdict.
    pub fn notes(&self, inputs: Vec<(String, String)>) -> millplan_report::html::Notes {
        let (t0, t1) = (self.time_before_s, self.time_after_s);
        let mut verdict = vec![format!(
            "Time {t0:.1} s → {t1:.1} s ({:+.1} %); F_xy max {:.1} → {:.1} N, tip deflection {:.4} → {:.4} mm; deciding per block: {}.",
            100.0 * (t1 / t0.max(1e-9) - 1.0),
            self.max_before.fxy,
            self.max_after.fxy,
            self.max_before.deflection,
            self.max_after.deflection,
            json_text(&self.binding)
        )];
        for op in &self.operations {
            verdict.push(format!("{}.", op.text()));
        }
        millplan_report::html::Notes::of_verdict(inputs, &self.verdict, verdict)
    }
}

/// The smallest and largest feed per tooth over the tools.
fn fz_range(fz: &[FzRange]) -> [f64; 2] {
    let lo = fz.iter().map(|r| r.fz_min).fold(f64::INFINITY, f64::min);
    let hi = fz.iter().map(|r| r.fz_max).fold(0.0, f64::max);
    [lo.min(hi), hi]
}

/// Per operation with simulated moves: its time at the programmed feeds
/// (the simulation's strokes; the whole program's estimate with
/// acceleration is `time_before_s`/`time_after_s`) and largest F_xy before
/// and after, so a user sees which operation gained and which was
/// slowed to respect a limit.
fn per_operation(p: &Program, before: &ForceRun, after: &ForceRun) -> Vec<OperationJson> {
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
        .map(|(i, (op, a))| OperationJson {
            operation: i + 1,
            name: op.name.clone(),
            tool: op.tool.as_ref().and_then(|t| t.number),
            tool_name: op.tool.as_ref().and_then(|t| t.name.clone()),
            line: op.moves.first().map(|m| m.line),
            moves: a.moves,
            time_nominal_before_s: a.t[0],
            time_nominal_after_s: a.t[1],
            fxy_max_before: a.fxy[0],
            fxy_max_after: a.fxy[1],
        })
        .collect()
}

/// Whether a cutting move of `run` meets the stock.
pub fn meets_stock(run: &ForceRun) -> bool {
    run.moves.iter().any(|m| !m.rapid && !m.air)
}

/// The warning of a run whose cutting moves all pass through air: nothing
/// to load, the stock (`stock`, as given) is likely not the one cut.
pub fn no_contact(stock: &str) -> String {
    format!("no cutting move meets the stock (--stock {stock}): there is no load to act on; is it the stock this program cuts?")
}

/// Warnings shared by `force` and `feed`: moves over a limit (`over` of
/// them, the first at `lines`), moves whose loads are missing, moves not
/// simulated.
pub fn load_warnings(
    over: usize,
    lines: &[u32],
    unmodelled: usize,
    (skipped, first): (usize, Option<u32>),
) -> Vec<String> {
    let mut w = Vec::new();
    if over > 0 {
        w.push(format!(
            "{over} moves exceed a limit (lines {}{})",
            lines
                .iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(", "),
            if over > 20 { ", …" } else { "" }
        ));
    }
    if unmodelled > 0 {
        w.push(format!(
            "{unmodelled} moves removed material the model could not load (spindle stopped, or no edge ahead of the feed in material): their loads are missing"
        ));
    }
    if skipped > 0 {
        w.push(format!(
            "{skipped} moves not simulated (unknown position or axis, no tool{}): their loads are missing",
            millplan_sim::stock::path::first_line_note(first)
        ));
    }
    w
}

/// A summary's entries as table rows: each under its name in words with its
/// unit, numbers rounded (the JSON keeps full precision).
pub fn summary_rows<T: Serialize>(summary: &T) -> Vec<(String, String)> {
    serde_json::to_value(summary)
        .map(|v| millplan_report::forces::summary_table(&v))
        .unwrap_or_default()
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

/// The CSV table of a run's loads (the input's, with the feeds allowed).
pub fn loads_csv(run: &ForceRun) -> String {
    millplan_report::forces::moves_csv(&run.moves)
}

/// The feed report: loads before and after against time, the limits drawn.
pub fn feed_report(
    inputs: Vec<(String, String)>,
    summary: &FeedSummary,
    before: &ForceRun,
    after: &ForceRun,
    limits: &FeedLimits,
    machine: &Machine,
) -> String {
    millplan_report::forces::report(
        "millplan feed: loads before and after",
        "Per move, the largest load of its strokes against the time the move starts; the black line is the limit at the move's spindle speed.",
        &summary.notes(inputs),
        &summary_rows(summary),
        &[("input", &before.moves), ("output", &after.moves)],
        &quantities(limits, machine),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn loads(v: &[(&str, &str)]) -> Vec<(String, String)> {
        v.iter()
            .map(|(k, x)| (k.to_string(), x.to_string()))
            .collect()
    }

    #[test]
    fn limits_take_each_named_load_and_refuse_what_is_no_number() {
        let l = load_limits(
            1.5,
            0.01,
            None,
            None,
            &loads(&[("fxy", "300"), ("power", "2000"), ("fz_max", "0.1")]),
        )
        .expect("limits");
        assert_eq!(
            (l.fxy, l.power, l.torque),
            (Some(300.0), Some(2000.0), None)
        );
        assert_eq!((l.fos, l.fz_min, l.fz_max), (1.5, 0.01, Some(0.1)));
        let e = force_limits(&loads(&[("fxy", "abc")])).err();
        assert_eq!(e.as_deref(), Some("--limit fxy=abc: not a number"));
        assert!(force_limits(&loads(&[("torque", "-1")])).is_err());
        let f = force_limits(&[]).expect("none");
        assert_eq!((f.fz_min, f.fz_max), (0.0, Some(f64::INFINITY)));
    }

    #[test]
    fn json_text_prints_what_the_summary_prints() {
        assert_eq!(json_text(&None::<u32>), "null");
        assert_eq!(json_text(&vec![3u32, 5]), "[3,5]");
        let b: BTreeMap<&str, usize> = [("fxy", 2), ("air", 1)].into_iter().collect();
        assert_eq!(json_text(&b), r#"{"air":1,"fxy":2}"#);
    }
}
