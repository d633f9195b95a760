//! A job: the resolved inputs of one optimising run, each built once.

use crate::defaults::{self, Defaults};
use millplan_geom::TriMesh;
use millplan_models::cutter::Shape;
use millplan_models::force::materials::ChipLoads;
use millplan_models::force::materials::Materials;
use millplan_models::force::Grid;
use millplan_nc::{Operation, Program};
use millplan_plan::feed::machine_accel;
use millplan_plan::force::{EngagementMemo, FeedLimits, ForceRun, ForceSetup};
use millplan_plan::machine::Machine;
use millplan_sim::stock::path::{strokes, PathOptions, Strokes};
use millplan_sim::stock::spec::StockSpec;
use millplan_sim::stock::tool::{BodyOptions, ToolBody};
use millplan_sim::stock::Stock;
use serde::Serialize;

/// Limits the user gives (`--limit NAME=VALUE`): each adds a limit or
/// tightens the default one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct UserLimits {
    pub fxy: Option<f64>,
    pub torque: Option<f64>,
    pub power: Option<f64>,
    pub stress: Option<f64>,
    pub deflection: Option<f64>,
    pub fz_min: Option<f64>,
    pub fz_max: Option<f64>,
}

impl UserLimits {
    /// The limits of `--limit NAME=VALUE` (`loads`: fxy, torque, power,
    /// stress, deflection, fz_min, fz_max), each a positive number.
    pub fn parse(loads: &[(String, String)]) -> Result<UserLimits, String> {
        let mut l = UserLimits::default();
        for (name, value) in loads {
            if !crate::limits::LOAD_NAMES.contains(&name.as_str()) {
                let names = crate::limits::LOAD_NAMES.join(", ");
                return Err(format!("--limit {name}: not a load limit ({names})"));
            }
            let v: f64 = value
                .parse()
                .map_err(|_| format!("--limit {name}={value}: not a number"))?;
            let flag = format!("--limit {name}");
            let range = crate::check::Range::positive(1e9, "(N, N·mm, W, MPa or mm)");
            let v = Some(crate::check::arg(&flag, v, range)?);
            match name.as_str() {
                "fxy" => l.fxy = v,
                "torque" => l.torque = v,
                "power" => l.power = v,
                "stress" => l.stress = v,
                "fz_min" => l.fz_min = v,
                "fz_max" => l.fz_max = v,
                _ => l.deflection = v,
            }
        }
        if let (Some(lo), Some(hi)) = (l.fz_min, l.fz_max) {
            if lo > hi {
                return Err(format!(
                    "--limit fz_min={lo} is above fz_max={hi}: the feed per tooth has no range"
                ));
            }
        }
        Ok(l)
    }
}

/// What the user chose over the defaults; `None` takes the default.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Cutting speed, m/min.
    pub vc: Option<f64>,
    /// Spindle speed of cutting moves without S, 1/min.
    pub spindle: Option<f64>,
    /// Cutter of operations whose tool has no geometry, or overriding it.
    pub tool: Option<Shape>,
    pub flutes: Option<usize>,
    /// Dexel size, mm.
    pub resolution: Option<f64>,
    pub limits: UserLimits,
    /// Tolerance of the checks, mm.
    pub tol: Option<f64>,
    /// Memory the stock may take, bytes.
    pub memory: Option<u64>,
    /// Post with inverse-time feed (G93) whatever the machine file says.
    pub g93: bool,
}

/// The options of `optimise` as given, before their checks.
#[derive(Clone, Debug, Default)]
pub struct OptionsRequest {
    pub vc: Option<f64>,
    pub spindle: Option<f64>,
    /// `ball:D`, `flat:D`, `bull:D:R`.
    pub tool: Option<String>,
    pub flutes: Option<usize>,
    pub resolution: Option<f64>,
    /// `--limit NAME=VALUE` pairs.
    pub loads: Vec<(String, String)>,
    pub tol: Option<f64>,
    pub memory: Option<u64>,
    pub g93: bool,
}

impl Options {
    /// Every option given in its range (the error names the option), the
    /// tool parsed and the load limits read.
    pub fn checked(r: &OptionsRequest) -> Result<Options, String> {
        use crate::check::{arg, tool_shape, Range, MAX_VC};
        let within =
            |flag: &str, v: Option<f64>, range: Range| v.map(|v| arg(flag, v, range)).transpose();
        let tool = r
            .tool
            .as_deref()
            .map(|s| tool_shape("--tool", s))
            .transpose()?;
        let flutes = r.flutes.map(|f| f as f64);
        within("--flutes", flutes, Range::from(1.0, 64.0, ""))?;
        Ok(Options {
            vc: within("--vc", r.vc, Range::positive(MAX_VC, "m/min"))?,
            spindle: within("--spindle", r.spindle, crate::check::SPINDLE)?,
            tool,
            flutes: r.flutes,
            resolution: within(
                "--resolution",
                r.resolution,
                Range::from(0.005, 100.0, "mm"),
            )?,
            limits: UserLimits::parse(&r.loads)?,
            tol: within("--tol", r.tol, Range::from(0.0, 100.0, "mm"))?,
            memory: r.memory,
            g93: r.g93,
        })
    }
}

/// The inputs as read (the caller does all file access).
pub struct Inputs {
    pub program: Program,
    pub part: Option<TriMesh>,
    pub stock: Option<StockSpec>,
    /// The mesh of an `stl:` stock.
    pub blank: Option<TriMesh>,
    pub machine: Machine,
    /// Whether the machine came from a file (else millplan's default).
    pub machine_given: bool,
    pub materials: Materials,
    pub material: Option<String>,
    pub options: Options,
    /// What the tool library gave each operation (`tools::apply` on the
    /// program, before the job); empty without a library.
    pub library: Vec<Option<crate::tools::LibraryTool>>,
}

/// One resolved setting and where its value came from.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Setting {
    pub name: &'static str,
    pub value: String,
    /// `option`, `program`, `machine`, `material table`, `default`, …
    pub from: String,
}

/// Why a job cannot be built or run.
#[derive(Debug, PartialEq)]
pub struct JobError {
    pub message: String,
    /// The inputs are sound but the program cannot run on the machine (an
    /// axis out of its travel): a finding (exit 3), not bad input.
    pub refused: bool,
    /// What the run had to say before it stopped (the passes it skipped,
    /// and why), to be said before the error.
    pub notes: Vec<String>,
}

impl JobError {
    /// A finding that stops the run (exit 3).
    pub fn refused(message: String) -> JobError {
        JobError {
            message,
            refused: true,
            notes: Vec::new(),
        }
    }

    /// The message after the program's name `path`: `path:line:col: …`
    /// where it starts at its line, else `path: …`.
    pub fn located(&self, path: &str) -> String {
        if self.message.starts_with(|c: char| c.is_ascii_digit()) {
            format!("{path}:{}", self.message)
        } else {
            format!("{path}: {}", self.message)
        }
    }
}

/// Bad input (exit 2).
impl From<String> for JobError {
    fn from(message: String) -> JobError {
        JobError {
            message,
            refused: false,
            notes: Vec::new(),
        }
    }
}

impl std::fmt::Display for JobError {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for JobError {}

/// A job: the inputs, every default resolved, the tool bodies' rule, the
/// stock and the force model built once.
pub struct Job {
    pub inputs: Inputs,
    /// Every setting with its source, for the report.
    pub settings: Vec<Setting>,
    pub vc: f64,
    pub flutes: usize,
    pub resolution: f64,
    pub tol: f64,
    /// Finishing allowance of the speed pass, mm.
    pub ap: f64,
    pub body: BodyOptions,
    /// The stock before the program (with `--stock`).
    pub stock: Option<Stock>,
    /// The force model (with `--material`).
    pub setup: Option<ForceSetup>,
    pub limits: FeedLimits,
    pub feed_accel: f64,
    /// Diameter of the first cutting operation's tool, mm.
    pub diameter: f64,
    /// The forces of the input on the stock (with a stock and a material).
    pub forces_before: Option<ForceRun>,
    /// No cutting move of the input meets the stock: the loads say nothing
    /// of it, and the passes that act on them (feed, orient) do not run.
    pub stock_missed: bool,
    /// The engaged cells the input's force run found on the stock, which
    /// the later runs over the same path use (the feed pass, the check of
    /// the program written).
    pub(crate) kept: Option<std::sync::Arc<EngagementMemo>>,
    /// The input with the default spindle speed on the cutting moves that
    /// have none (`None`: every one has its own), for the analyses and the
    /// passes that need a speed; the program written keeps the input's own
    /// words unless such a pass ran.
    spindled: Option<Program>,
}

fn set(v: &mut Vec<Setting>, name: &'static str, value: String, from: &str) {
    v.push(Setting {
        name,
        value,
        from: from.to_string(),
    });
}

/// The cutting speed, the flutes and the helix: the options', else the
/// tool library's, else the cutting table's and the defaults; recorded.
fn cutting_data(
    inputs: &Inputs,
    lib: Option<crate::tools::LibraryTool>,
    s: &mut Vec<Setting>,
) -> (f64, usize, f64) {
    let o = &inputs.options;
    let material = inputs.material.as_deref().map(str::to_ascii_lowercase);
    let (cut, fallback) = defaults::cutting(material.as_deref().unwrap_or("default"));
    let table = if fallback {
        "cutting table [default]"
    } else {
        "cutting table"
    };
    let vc = pick(s, "vc", o.vc, None, (cut.vc, table), " m/min");
    let lib_flutes = lib
        .and_then(|t| t.flutes)
        .map(|z| (z as f64, "tool library"));
    let flutes = o.flutes.map(|z| z as f64);
    let flutes = pick(
        s,
        "flutes",
        flutes,
        lib_flutes,
        (Defaults::FLUTES as f64, "default"),
        "",
    ) as usize;
    let lib_helix = lib.and_then(|t| t.helix_deg).map(|h| (h, "tool library"));
    let helix = pick(
        s,
        "helix",
        None,
        lib_helix,
        (Defaults::HELIX_DEG, "default"),
        "°",
    );
    (vc, flutes, helix)
}

/// The value `given` (from `option`), else `alt` with its source, else the
/// default with its; recorded in `s` with `unit`.
fn pick(
    s: &mut Vec<Setting>,
    name: &'static str,
    given: Option<f64>,
    alt: Option<(f64, &str)>,
    default: (f64, &str),
    unit: &str,
) -> f64 {
    let (v, from) = match (given, alt) {
        (Some(v), _) => (v, "option"),
        (None, Some(a)) => a,
        (None, None) => default,
    };
    set(s, name, format!("{v}{unit}"), from);
    v
}

/// The tool library's tool of the job, recorded.
fn library_setting(lib: Option<crate::tools::LibraryTool>, s: &mut Vec<Setting>) {
    let Some(t) = lib else { return };
    let holder = t.holder.map_or("none given".into(), |(r, l)| {
        format!("D {} mm from {l} mm above the tip", 2.0 * r)
    });
    let v = format!("T{}: holder {holder}", t.number);
    set(s, "tool", v, "tool library");
}

/// The finishing allowance of the speed pass: the `offset:` stock's, else
/// the default; at most the tool's radius.
fn allowance(i: &Inputs, d: f64, s: &mut Vec<Setting>) -> f64 {
    let (ap, from) = match &i.stock {
        Some(StockSpec::Offset(mm)) if *mm > 0.0 => ((*mm).min(d / 2.0), "stock offset"),
        _ => (Defaults::AP.min(d / 2.0), "default"),
    };
    set(s, "ap", format!("{ap} mm"), from);
    ap
}

/// What the library gave the first cutting operation's tool (the job's
/// flutes, helix and holder are one tool's, as its diameter is).
fn first_library_tool(i: &Inputs) -> Option<crate::tools::LibraryTool> {
    let op = i
        .program
        .operations
        .iter()
        .position(|op| op.moves.iter().any(|m| m.is_cutting()))?;
    i.library.get(op).copied().flatten()
}

/// The first cutting operation's tool diameter, mm.
fn first_diameter(p: &Program, body: &BodyOptions) -> Option<f64> {
    p.operations
        .iter()
        .filter(|op| op.moves.iter().any(|m| m.is_cutting()))
        .find_map(|op| ToolBody::for_operation(op, body))
        .map(|b| 2.0 * b.radius())
}

impl Job {
    /// Resolves every default and builds the stock and the force model.
    pub fn new(inputs: Inputs) -> Result<Job, JobError> {
        Job::new_timed(inputs, &mut |_| {})
    }

    /// [`Job::new`] naming its phases to `lap` as each ends (for a
    /// `--timings` table): the defaults, the stock, the input's loads.
    pub fn new_timed(inputs: Inputs, lap: &mut dyn FnMut(&str)) -> Result<Job, JobError> {
        Job::for_passes(inputs, None, lap)
    }

    /// [`Job::new_timed`] for the passes the user named (`--passes`): one
    /// that a missing input keeps from running is refused
    /// ([`crate::passes::check_named`]) before the stock is built and the
    /// input's loads are measured.
    pub fn for_passes(
        inputs: Inputs,
        named: Option<&[crate::passes::PassName]>,
        lap: &mut dyn FnMut(&str),
    ) -> Result<Job, JobError> {
        let o = inputs.options.clone();
        let mut s = Vec::new();
        let lib = first_library_tool(&inputs);
        let body = BodyOptions {
            shape: o.tool,
            holder: lib.and_then(|t| t.holder),
            ..BodyOptions::default()
        };
        let d = first_diameter(&inputs.program, &body).ok_or_else(|| {
            let cuts = (inputs.program.operations.iter())
                .any(|op| op.moves.iter().any(|m| m.is_cutting()));
            JobError::from(if cuts {
                "the program has no cutting move with a tool of known shape: give --tool ball:D, flat:D or bull:D:R"
            } else {
                "the program has no cutting move (only rapids and canned cycles): no pass of optimise changes it (gouge, simulate and convert check and write it)"
            }.to_string())
        })?;
        let (vc, flutes, helix) = cutting_data(&inputs, lib, &mut s);
        library_setting(lib, &mut s);
        let dflt = |v: f64| (v, "default");
        let resolution = pick(
            &mut s,
            "resolution",
            o.resolution,
            None,
            dflt(Defaults::RESOLUTION),
            " mm",
        );
        let tol = pick(&mut s, "tol", o.tol, None, dflt(Defaults::TOL), " mm");
        let ap = allowance(&inputs, d, &mut s);
        let limits = limits(&o.limits, chip_loads(&inputs)?, d, &mut s);
        let accel = machine_accel(&inputs.machine).map(|a| (a, "machine"));
        let feed_accel = pick(
            &mut s,
            "feed_accel",
            None,
            accel,
            dflt(Defaults::FEED_ACCEL),
            " mm/s²",
        );
        let setup = force_setup(&inputs, flutes, helix)?;
        let mut job = Job {
            inputs,
            settings: s,
            vc,
            flutes,
            resolution,
            tol,
            ap,
            body,
            stock: None,
            setup,
            limits,
            feed_accel,
            diameter: d,
            forces_before: None,
            stock_missed: false,
            kept: None,
            spindled: None,
        };
        job.default_spindle();
        lap("defaults resolved, materials and tools looked up");
        if let Some(order) = named {
            crate::passes::check_named(&job, order).map_err(JobError::from)?;
        }
        job.stock = job.build_stock()?;
        lap("stock built");
        if let Some((run, kept)) = job.forces_kept(job.analysed())? {
            job.forces_before = Some(run);
            job.kept = Some(std::sync::Arc::new(kept));
        }
        job.stock_missed =
            (job.forces_before.as_ref()).is_some_and(|r| !crate::feed::meets_stock(r));
        job.learn_limits();
        lap("the input's loads on the stock (limits learned)");
        if let Some(order) = named {
            crate::passes::check_named(&job, order).map_err(JobError::from)?;
        }
        Ok(job)
    }

    /// Load limits nothing else gives (no `--limit`; torque and power not
    /// from the spindle chart either) take the input's own largest load on
    /// the stock: the program as its CAM system wrote it is the one the shop
    /// has proven, so the feeds may rise where it cuts lightly but no cut
    /// may load the tool more than its hardest one did (VERICUT's "learn
    /// mode" takes its limits from the program in the same way). Without a
    /// stock or a material there are no loads to learn.
    fn learn_limits(&mut self) {
        let Some(run) = &self.forces_before else {
            return;
        };
        let max = run.maxima();
        let chart = self.inputs.machine.spindle_curve.is_some();
        let from = "the input's largest (no --limit, no spindle chart)";
        let learned = crate::feed::learn(&mut self.limits, &max, chart);
        for (name, v) in learned {
            let value = match name {
                "fxy" => format!("{v:.1} N"),
                "torque" => format!("{v:.1} N·mm"),
                _ => format!("{v:.1} W"),
            };
            let from = if name == "fxy" {
                "the input's largest (no --limit fxy)"
            } else {
                from
            };
            set(&mut self.settings, name, value, from);
        }
        if chart {
            let v = "at each block's speed".to_string();
            set(
                &mut self.settings,
                "torque, power",
                v,
                "the machine's spindle chart",
            );
        }
    }

    /// The tool body of an operation (holder included when one is given).
    pub fn body_of(&self, op: &Operation) -> Option<ToolBody> {
        ToolBody::for_operation(op, &self.body)
    }

    /// The tool bodies the force model can load (no cones: drills are left
    /// out), as the feed pass takes them.
    pub fn body_fn(&self) -> millplan_plan::feed::BodyFn {
        let o = BodyOptions {
            no_cone: true,
            ..self.body
        };
        Box::new(move |op: &Operation| ToolBody::for_operation(op, &o))
    }

    /// The engaged cells the input's force run found, where it ran.
    pub fn memo(&self) -> Option<&EngagementMemo> {
        self.kept.as_deref()
    }

    /// The strokes of `p` through the stock at this job's resolution, of
    /// every tool (`forces`: only those the force model can load).
    pub fn strokes(&self, p: &Program, forces: bool) -> Strokes {
        let o = BodyOptions {
            no_cone: forces,
            ..self.body
        };
        strokes(
            p,
            |op: &Operation| ToolBody::for_operation(op, &o),
            &PathOptions {
                chord: self.resolution / 4.0,
                rapid_rate: self.inputs.machine.rapid,
            },
        )
    }

    /// The `memory` limit the job runs under, bytes.
    pub(crate) fn memory(&self) -> u64 {
        self.inputs
            .options
            .memory
            .unwrap_or(millplan_geom::limits::Limits::default().memory)
    }

    fn build_stock(&self) -> Result<Option<Stock>, JobError> {
        let Some(spec) = &self.inputs.stock else {
            return Ok(None);
        };
        let s = self.strokes(&self.inputs.program, false);
        let memory = self.memory();
        // The job keeps its stock while each run cuts a copy of it.
        let meshes = (self.inputs.part.as_ref(), self.inputs.blank.as_ref());
        spec.build(self.resolution, &s, meshes, (memory, 2))
            .map(Some)
            .map_err(|e| JobError::from(format!("--stock: {e}")))
    }

    /// The input as the analyses see it: with the default spindle speed on
    /// the cutting moves that have none (`--spindle`, else the speed of vc on the tool's diameter).
    pub fn analysed(&self) -> &Program {
        self.spindled.as_ref().unwrap_or(&self.inputs.program)
    }

    /// `p` as the analyses take it: with the default spindle speed where
    /// its cutting moves have none, as [`Job::analysed`] is the input (the
    /// program written keeps no S but where a pass wrote one, and its loads
    /// and measures are taken at the speed the input's were).
    pub fn analysed_copy<'a>(&self, p: &'a Program) -> std::borrow::Cow<'a, Program> {
        if p.moves().any(|m| m.is_cutting() && !(m.spindle > 0.0)) {
            std::borrow::Cow::Owned(self.fill_spindle(p.clone()))
        } else {
            std::borrow::Cow::Borrowed(p)
        }
    }

    /// `p` with `--spindle`, else the speed of the cutting speed on the
    /// tool's diameter, on its cutting moves without a spindle speed.
    fn fill_spindle(&self, mut p: Program) -> Program {
        let (o, vc, body) = (self.inputs.options.spindle, self.vc, self.body);
        for op in &mut p.operations {
            let dia =
                ToolBody::for_operation(op, &body).map_or(self.diameter, |b| 2.0 * b.radius());
            let n = o.unwrap_or_else(|| defaults::spindle_for(vc, dia));
            for m in op
                .moves
                .iter_mut()
                .filter(|m| m.is_cutting() && !(m.spindle > 0.0))
            {
                m.spindle = n.clamp(
                    self.inputs.machine.spindle_min,
                    self.inputs.machine.spindle_max,
                );
            }
        }
        p
    }

    /// Cutting moves without a spindle speed get `--spindle`, else the
    /// speed of the cutting speed on their tool's diameter, in the copy of
    /// the input the analyses take ([`Job::analysed`]).
    fn default_spindle(&mut self) {
        let missing = self
            .inputs
            .program
            .moves()
            .any(|m| m.is_cutting() && !(m.spindle > 0.0));
        if !missing {
            set(
                &mut self.settings,
                "spindle",
                "as programmed".into(),
                "program",
            );
            return;
        }
        self.spindled = Some(self.fill_spindle(self.inputs.program.clone()));
        let (value, from) = match self.inputs.options.spindle {
            Some(n) => (format!("{n} 1/min where the program has no S"), "option"),
            None => (
                "1000·vc/(π·D) where the program has no S".to_string(),
                "default",
            ),
        };
        set(&mut self.settings, "spindle", value, from);
    }
}

/// The force model of the material, `None` without one.
fn force_setup(
    inputs: &Inputs,
    flutes: usize,
    helix_deg: f64,
) -> Result<Option<ForceSetup>, JobError> {
    let Some(name) = &inputs.material else {
        return Ok(None);
    };
    let law = inputs
        .materials
        .get(name)
        .map_err(|e| JobError::from(format!("--material: {e}")))?
        .law;
    let mut s = ForceSetup::new(law, flutes);
    s.helix = helix_deg.to_radians();
    // The default grid as the coarsest, refined per load sample until the
    // peaks converge (`ForceSetup::new`).
    s.grid = Grid::default();
    Ok(Some(s))
}

/// The material's chip loads by tool diameter (`fz_max` of its row in the
/// materials table), `None` without a material or a row.
fn chip_loads(inputs: &Inputs) -> Result<Option<ChipLoads>, JobError> {
    let Some(name) = &inputs.material else {
        return Ok(None);
    };
    let m = inputs
        .materials
        .get(name)
        .map_err(|e| JobError::from(format!("--material: {e}")))?;
    Ok(m.chip_loads)
}

/// The load limits: the user's; the feed-per-tooth range, its top per tool
/// from the material's chip loads at the tool's diameter (`d` the first
/// tool's, for the report) unless `--limit fz_max=` gives one for every
/// tool; the spindle chart applied per block by [`FeedLimits::at`]. The
/// input's own loads are added by [`Job::learn_limits`].
fn limits(u: &UserLimits, chip: Option<ChipLoads>, d: f64, s: &mut Vec<Setting>) -> FeedLimits {
    let mut l = FeedLimits {
        fxy: u.fxy,
        torque: u.torque,
        power: u.power,
        stress: u.stress,
        deflection: u.deflection,
        fos: 1.0,
        fz_min: u.fz_min.unwrap_or(Defaults::FZ_MIN),
        fz_max: u.fz_max,
        chip_loads: chip,
    };
    let r = l.fz_range(d);
    let lowered = l.fz_min > r.fz_max;
    l.fz_min = l.fz_min.min(r.fz_max);
    let from = |x: Option<f64>, default: &str| {
        let given = if x.is_some() { "option" } else { default };
        if lowered {
            format!("{given}, lowered to the largest feed per tooth of a D {d} mm tool")
        } else {
            given.to_string()
        }
    };
    set(
        s,
        "fz_min",
        format!("{:.4} mm", l.fz_min),
        &from(u.fz_min, "default"),
    );
    let top = match (u.fz_max, r.source) {
        (Some(_), _) => "option".to_string(),
        (None, millplan_models::force::materials::FzSource::Diameter) => {
            format!(
                "{}·D (the material has no chip loads)",
                millplan_models::force::materials::FALLBACK_FZ_SHARE
            )
        }
        (None, _) => "materials table: the chip load at each tool's diameter".into(),
    };
    set(s, "fz_max", format!("{:.4} mm at D {d} mm", r.fz_max), &top);
    for (name, v) in [
        ("fxy", u.fxy),
        ("torque", u.torque),
        ("power", u.power),
        ("stress", u.stress),
        ("deflection", u.deflection),
    ] {
        if let Some(v) = v {
            set(s, name, v.to_string(), "option");
        }
    }
    l
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every load name is read into its own limit, and a name that is not
    /// one is refused (never taken as another limit).
    #[test]
    fn load_limits_are_read_by_name_and_an_unknown_one_is_refused() {
        let pairs: Vec<(String, String)> = crate::limits::LOAD_NAMES
            .iter()
            .enumerate()
            .map(|(k, n)| (n.to_string(), format!("{}", k + 1)))
            .collect();
        let l = UserLimits::parse(&pairs).expect("every name");
        let got = [
            l.fxy,
            l.torque,
            l.power,
            l.stress,
            l.deflection,
            l.fz_min,
            l.fz_max,
        ];
        assert_eq!(got, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0].map(Some));
        for v in ["0.01", "-1"] {
            let e = UserLimits::parse(&[("flexion".into(), v.into())]).expect_err("unknown");
            assert!(e.starts_with("--limit flexion: not a load limit"), "{e}");
        }
        // A feed-per-tooth range upside down is refused; a bottom above a
        // tool's top is lowered to it, and the setting says so.
        let pair = |n: &str, v: &str| (n.to_string(), v.to_string());
        let e = UserLimits::parse(&[pair("fz_min", "0.2"), pair("fz_max", "0.1")])
            .expect_err("no range");
        assert!(e.contains("fz_min=0.2 is above fz_max=0.1"), "{e}");
        let u = UserLimits::parse(&[pair("fz_min", "0.5")]).expect("read");
        let mut s = Vec::new();
        let l = limits(&u, None, 10.0, &mut s);
        assert!(l.fz_min <= l.fz_range(10.0).fz_max);
        let fz_min = s.iter().find(|x| x.name == "fz_min").expect("said");
        assert!(fz_min.from.contains("lowered"), "{fz_min:?}");
    }

    /// `optimise`'s options: none given is no choice made; each given is
    /// checked against its range, naming the option; the tool parsed; a
    /// load limit read.
    #[test]
    fn options_are_checked_naming_the_option() {
        let none = Options::checked(&OptionsRequest::default()).expect("none given");
        assert!(none.vc.is_none() && none.tool.is_none() && none.resolution.is_none());
        let given = OptionsRequest {
            tool: Some("ball:10".into()),
            flutes: Some(2),
            resolution: Some(0.1),
            loads: vec![("fxy".into(), "300".into())],
            ..OptionsRequest::default()
        };
        let o = Options::checked(&given).expect("in range");
        assert_eq!(o.tool.map(|t| t.radius()), Some(5.0));
        assert_eq!(o.resolution, Some(0.1));
        let bad = |r: OptionsRequest, flag: &str| {
            let e = Options::checked(&r).err().unwrap_or_default();
            assert!(e.starts_with(flag), "{flag}: {e}");
        };
        bad(
            OptionsRequest {
                flutes: Some(0),
                ..given.clone()
            },
            "--flutes",
        );
        bad(
            OptionsRequest {
                resolution: Some(0.001),
                ..given.clone()
            },
            "--resolution",
        );
        bad(
            OptionsRequest {
                vc: Some(-1.0),
                ..given.clone()
            },
            "--vc",
        );
        bad(
            OptionsRequest {
                tol: Some(f64::NAN),
                ..given.clone()
            },
            "--tol",
        );
        bad(
            OptionsRequest {
                tool: Some("ball:1e9".into()),
                ..given
            },
            "--tool",
        );
    }
}
