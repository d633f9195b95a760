//! `millplan speed` (and the spindle-control reports of `reorder`): the
//! request checked into the pass's parameters, the pass on a copy of the
//! input, the checks of its output, the run (`run_command`), the report's
//! header and the summary.

use crate::check::{arg, Range, MAX_TOOL_D, MAX_VC};
pub use millplan_models::contact::{Convention, NormalMode, Surface};
use millplan_nc::write::Target;
use millplan_nc::{Diagnostic, Program};
use millplan_plan::machine::Machine;
use millplan_plan::pipeline::{self, Context, PassError};
use millplan_plan::safety::{self, Check, Inputs, TipRule, Tolerances};
use millplan_plan::speed::{FeedCoupling, SpeedParams, SpeedPass, Summary};
pub use millplan_report::html::failed_checks;
use millplan_report::html::Verdict;
use serde::Serialize;
use std::fmt::Write as _;

mod command;
pub use command::{run_command, SpeedCommand, SpeedRun};

/// The cutting data of a spindle-control run, as given.
#[derive(Clone, Copy, Debug)]
pub struct Cutting {
    /// m/min.
    pub vc: f64,
    /// mm.
    pub fz: f64,
    pub flutes: u32,
    /// Stock thickness along the surface normal, mm.
    pub ap: f64,
}

impl Cutting {
    /// Every value in its physical range, naming the option.
    pub fn check(&self) -> Result<(), String> {
        arg("--vc", self.vc, Range::positive(MAX_VC, "m/min"))?;
        arg("--fz", self.fz, Range::positive(10.0, "mm"))?;
        arg("--flutes", self.flutes as f64, Range::from(1.0, 1000.0, ""))?;
        arg("--ap", self.ap, Range::positive(MAX_TOOL_D / 2.0, "mm"))?;
        Ok(())
    }

    /// Spindle-control settings for the commands that read only the
    /// summary and the program (no per-point rows).
    pub fn params(&self) -> SpeedParams {
        let mut p = SpeedParams::new(self.vc, self.fz, self.flutes, self.ap);
        p.keep_rows = false;
        p
    }
}

/// The options of `millplan speed` as given.
#[derive(Clone, Copy, Debug)]
pub struct SpeedRequest {
    pub cut: Cutting,
    pub ball_d: Option<f64>,
    pub s_threshold: f64,
    pub keep_feed: bool,
    /// `None`: decided from the part.
    pub convention: Option<Convention>,
    pub normals: NormalMode,
    pub nearest_incentre: bool,
    /// Keep the per-point rows (for a table or a report).
    pub keep_rows: bool,
}

/// Every number in its physical range, naming the option.
pub fn check(a: &SpeedRequest) -> Result<(), String> {
    arg("--vc", a.cut.vc, Range::positive(MAX_VC, "m/min"))?;
    arg("--fz", a.cut.fz, Range::positive(10.0, "mm"))?;
    arg(
        "--flutes",
        a.cut.flutes as f64,
        Range::from(1.0, 1000.0, ""),
    )?;
    let d = match a.ball_d {
        Some(d) => arg("--ball-d", d, Range::positive(MAX_TOOL_D, "mm"))?,
        None => MAX_TOOL_D,
    };
    // The ball model's domain: the stock no thicker than the ball's radius.
    arg(
        "--ap",
        a.cut.ap,
        Range::positive(d / 2.0, "mm (at most D/2)"),
    )?;
    arg(
        "--s-threshold",
        a.s_threshold,
        Range::from(0.0, 1e5, "1/min"),
    )?;
    Ok(())
}

/// The pass's parameters.
pub fn params(a: &SpeedRequest) -> SpeedParams {
    let c = a.cut;
    let mut p = SpeedParams::new(c.vc, c.fz, c.flutes, c.ap);
    p.feed = if a.keep_feed {
        FeedCoupling::Programmed
    } else {
        FeedCoupling::ChipLoad
    };
    p.s_threshold = a.s_threshold.max(0.0);
    p.convention = a.convention;
    p.normals = a.normals;
    p.nearest_incentre = a.nearest_incentre;
    p.ball_d = a.ball_d;
    p.keep_rows = a.keep_rows;
    p
}

/// The speed pass on a copy of the input: computed on the input, which it
/// does not change, then written into the copy, made once the analysis and
/// the part's surface (which nothing after it needs) have let their memory
/// go, so that the three are not held at once.
pub fn run(
    a: &SpeedRequest,
    cx: &mut Context,
    input: &Program,
) -> Result<(Program, SpeedPass), PassError> {
    let mut pass = SpeedPass::new(params(a));
    cx.time("speed computed on the input", || pass.plan(input, cx))?;
    let t = std::time::Instant::now();
    cx.release_surface();
    cx.record("surface freed", t.elapsed().as_secs_f64());
    let mut program = cx.time("copy of the input for the checks", || input.clone());
    pipeline::run(&mut [&mut pass], &mut program, cx)?;
    Ok((program, pass))
}

/// The checks of a program whose speeds and feeds are all that changed:
/// the IR verifier, S and F within the machine, every position kept.
pub fn checks(cx: &Context, input: &Program, output: &Program) -> Vec<Check> {
    cx.time("checks (IR, machine, positions)", || {
        safety::check_feeds_only(&Inputs {
            input,
            output,
            part: None,
            stock: None,
            tool_body: &|_| None,
            machine: Some(&cx.machine),
            tip: TipRule::Kept,
            tol: Tolerances::default(),
            loads: None,
        })
    })
}

/// The estimated cycle time of `p` on `machine`, with acceleration, s.
pub fn cycle_time(p: &Program, machine: &Machine) -> f64 {
    millplan_plan::timing::estimate_program(p, machine).total_s
}

/// The program as read on a thread of its own, with the cycle time
/// estimated there after the read, and the wall time of each.
pub struct ReadBeside {
    pub parsed: millplan_nc::Parsed,
    pub read_s: f64,
    pub time_before: f64,
    pub estimate_s: f64,
}

/// Runs `write` while the cycle time of `program` on `machine` is
/// estimated on another thread: what `write` gave, the estimate, and the
/// wall times of the writing and of the estimate.
pub fn write_beside<T>(
    program: &Program,
    machine: &Machine,
    write: impl FnOnce() -> T,
) -> (T, f64, [f64; 2]) {
    std::thread::scope(|s| {
        let estimate = s.spawn(|| {
            let t = std::time::Instant::now();
            (cycle_time(program, machine), t.elapsed().as_secs_f64())
        });
        let t = std::time::Instant::now();
        let written = write();
        let write_s = t.elapsed().as_secs_f64();
        let (total, estimate_s) = estimate
            .join()
            .unwrap_or_else(|e| std::panic::resume_unwind(e));
        (written, total, [write_s, estimate_s])
    })
}

/// What `millplan speed` makes of a program: the new program, the pass's
/// summary and per-point rows, the checks of the output and the part's
/// own findings (open edges, points off the part).
pub struct Outcome {
    pub program: Program,
    pub summary: Summary,
    pub rows: Vec<millplan_plan::speed::PointRow>,
    pub checks: Vec<Check>,
    pub findings: Vec<Diagnostic>,
}

/// Why a run of `millplan speed` stopped.
#[derive(Debug)]
pub enum SpeedError {
    /// The pass's own error (the input's, or a bug).
    Pass(PassError),
    /// A bug: the pass ran and left no summary.
    NoSummary,
}

/// `millplan speed` on `input` over `mesh` (its surface in `cx`): the pass
/// on a copy of the input, the checks of its output against the input,
/// the part's findings; each phase timed in `cx`.
pub fn command(
    a: &SpeedRequest,
    cx: &mut Context,
    mesh: &millplan_geom::TriMesh,
    input: Program,
) -> Result<Outcome, SpeedError> {
    let (program, mut pass) = run(a, cx, &input).map_err(SpeedError::Pass)?;
    let checks = checks(cx, &input, &program);
    cx.time("input freed", || drop(input));
    let summary = pass.summary.take().ok_or(SpeedError::NoSummary)?;
    // A part that does not match its path makes every speed meaningless.
    let findings = cx.time("part checks (open edges, points off the part)", || {
        [
            millplan_plan::checks::mesh(mesh),
            millplan_plan::checks::off_surface(&summary),
        ]
        .into_iter()
        .flatten()
        .collect()
    });
    Ok(Outcome {
        program,
        summary,
        rows: std::mem::take(&mut pass.rows),
        checks,
        findings,
    })
}

impl Outcome {
    /// Too many points off the part for the speeds to mean anything.
    pub fn untrusted(&self) -> bool {
        millplan_plan::checks::untrusted(&self.summary)
    }

    /// The report's header, warnings, cycle times and failed checks; the
    /// program and the part by their file names.
    pub fn report_inputs(
        &self,
        (program, part): (String, String),
        machine: &Machine,
        cut: Cutting,
        times: [f64; 2],
    ) -> millplan_report::html::SpeedInputs {
        let on = (program, &self.program);
        let mut i = report_inputs(on, part, machine, cut, &self.findings, times);
        i.failed = failed_checks(&self.checks);
        i
    }

    /// The HTML report (`--report`) of the run on the program `names.0`
    /// over the part `names.1`.
    pub fn report_html(
        &self,
        names: (String, String),
        machine: &Machine,
        cut: Cutting,
        times: [f64; 2],
    ) -> String {
        let title = format!("millplan speed: {}", names.0);
        let inputs = self.report_inputs(names, machine, cut, times);
        millplan_report::html::speed_report(&title, &inputs, &self.summary, &self.rows)
    }

    /// The per-point table (`--table`), CSV.
    pub fn table_csv(&self) -> String {
        millplan_report::table::points_csv(&self.rows)
    }

    /// What `speed --json` prints for the program written to `output`.
    pub fn report<'a>(
        &'a self,
        written: (String, Target),
        machine: &'a Machine,
        times: [f64; 2],
    ) -> Report<'a> {
        let on = (&self.summary, self.checks.as_slice());
        Report::new(on, written, machine, &self.findings, times)
    }
}

/// Why spindle control has nothing to act on in `p`, when so: no cutting
/// move, or every cutting operation's cutter is known and none is a ball.
/// A tool the program gives no shape is no such finding: `--ball-d` names
/// its ball, and without it the pass asks for the option (the input's lack).
pub fn nothing_to_control(p: &Program) -> Option<String> {
    let cutters: Vec<Option<millplan_nc::Cutter>> = p
        .operations
        .iter()
        .filter(|op| op.moves.iter().any(|m| m.is_cutting()))
        .map(|op| op.tool.as_ref().and_then(|t| t.cutter))
        .collect();
    if cutters.is_empty() {
        return Some("the program has no cutting move: nothing for spindle control to act on; nothing written".into());
    }
    let ball = cutters.iter().any(|c| match c {
        Some(c) => c.kind == millplan_nc::CutterKind::Ball,
        None => true,
    });
    (!ball).then(|| {
        format!(
            "the program has no ball-end operation (its cutters: {}): nothing for spindle control to act on; nothing written",
            cutting_tools(p)
        )
    })
}

/// The tools of the program's cutting operations, in their order.
fn cutting_op_tools(p: &Program) -> Vec<&millplan_nc::Tool> {
    p.operations
        .iter()
        .filter(|op| op.moves.iter().any(|m| m.is_cutting()))
        .filter_map(|op| op.tool.as_ref())
        .collect()
}

/// `tools` in words, each once, joined by `; ` (a tool the program gives
/// neither number, name nor shape is not shown).
fn distinct_words(tools: &[&millplan_nc::Tool]) -> String {
    let mut shown: Vec<String> = Vec::new();
    for t in tools {
        let words = tool_words(t);
        if !words.is_empty() && !shown.contains(&words) {
            shown.push(words);
        }
    }
    if shown.is_empty() {
        return "not named by the program".to_string();
    }
    shown.join("; ")
}

/// The tools spindle control works with, as the program names them: those
/// of its cutting ball-end operations (a multi-tool program's drill and flat
/// mill are not the tool of the report), each once; the first cutting
/// operation's tool when none is a ball.
pub fn tool_name(p: &Program) -> String {
    let cutting = cutting_op_tools(p);
    let balls: Vec<&millplan_nc::Tool> = cutting
        .iter()
        .copied()
        .filter(|t| {
            t.cutter
                .is_some_and(|c| c.kind == millplan_nc::CutterKind::Ball)
        })
        .collect();
    if balls.is_empty() {
        distinct_words(&cutting[..cutting.len().min(1)])
    } else {
        distinct_words(&balls)
    }
}

/// Every tool the program cuts with, as it names them, each once, in the
/// order the operations use them (`force` and `feed` load them all).
pub fn cutting_tools(p: &Program) -> String {
    distinct_words(&cutting_op_tools(p))
}

/// A tool in words: `T8 BALL D14.000 R7.000 (ball)`.
fn tool_words(t: &millplan_nc::Tool) -> String {
    let mut words = Vec::new();
    if let Some(n) = t.number {
        words.push(format!("T{n}"));
    }
    if let Some(n) = &t.name {
        words.push(n.clone());
    }
    if let Some(c) = &t.cutter {
        let kind = match c.kind {
            millplan_nc::CutterKind::Ball => " (ball)",
            _ => "",
        };
        words.push(format!("D{:.3} R{:.3}{kind}", c.d, c.r));
    }
    words.join(" ")
}

/// The header, warnings and cycle times of a spindle-control report; the
/// program and the part by their file names. No check failed: a caller
/// with the written program's checks sets `failed` ([`failed_checks`]).
pub fn report_inputs(
    (program_name, program): (String, &Program),
    part: String,
    machine: &Machine,
    cut: Cutting,
    findings: &[Diagnostic],
    [time_before_s, time_after_s]: [f64; 2],
) -> millplan_report::html::SpeedInputs {
    millplan_report::html::SpeedInputs {
        program: program_name,
        part,
        tool: tool_name(program),
        machine: machine.name.clone(),
        spindle: (machine.spindle_min, machine.spindle_max),
        spindle_accel: machine.spindle_accel,
        feed_max: machine.feed_max,
        vc: cut.vc,
        fz: cut.fz,
        flutes: cut.flutes,
        ap: cut.ap,
        time_before_s: Some(time_before_s),
        time_after_s: Some(time_after_s),
        warnings: verdict_warnings(findings),
        failed: Vec::new(),
    }
}

/// The part's findings as the verdict's warnings, each with its code (as
/// the other commands name it: `open-mesh`, `off-surface`).
fn verdict_warnings(findings: &[Diagnostic]) -> Vec<String> {
    findings
        .iter()
        .map(|d| format!("{} [{}]", d.message, d.code))
        .collect()
}

/// What `speed --json` prints: the pass's summary and the run around it.
#[derive(Serialize)]
pub struct Report<'a> {
    #[serde(flatten)]
    pub summary: &'a Summary,
    pub output: String,
    pub dialect: &'static str,
    pub machine: &'a Machine,
    pub findings: &'a [Diagnostic],
    pub trusted: bool,
    pub checks: &'a [Check],
    pub time_before_s: f64,
    pub time_after_s: f64,
    pub time_model: &'static str,
    /// The verdict by the one rule, as the report's: red when a check of
    /// the written program failed; amber when no ball-end point was found,
    /// a warning applies, more points miss the cutting speed than at the
    /// constant speed or the cycle time grew; green otherwise.
    pub verdict: Verdict,
}

impl<'a> Report<'a> {
    pub fn new(
        (summary, checks): (&'a Summary, &'a [Check]),
        (output, target): (String, Target),
        machine: &'a Machine,
        findings: &'a [Diagnostic],
        [time_before_s, time_after_s]: [f64; 2],
    ) -> Self {
        let verdict = Verdict::of(
            &millplan_report::html::speed_evidence(
                summary,
                &millplan_report::html::failed_checks(checks),
                [Some(time_before_s), Some(time_after_s)],
            ),
            verdict_warnings(findings),
        );
        Report {
            summary,
            output,
            dialect: target.name(),
            machine,
            findings,
            trusted: !millplan_plan::checks::untrusted(summary),
            checks,
            time_before_s,
            time_after_s,
            time_model: "acceleration",
            verdict,
        }
    }

    /// The text summary.
    pub fn render_text(&self) -> String {
        let s = self.summary;
        let mut o = String::new();
        let _ = writeln!(
            o,
            "{} cutting points in {} ball-end operation(s), CL points read as {:?}",
            s.points, s.operations, s.convention
        );
        let _ = writeln!(
            o,
            "  D_w        {:.3} … {:.3} mm (mean {:.3})",
            s.d_w.min, s.d_w.max, s.d_w.mean
        );
        let _ = writeln!(
            o,
            "  spindle    {:.0} … {:.0} 1/min",
            s.spindle.min, s.spindle.max
        );
        let _ = writeln!(
            o,
            "  vc         {:.1} … {:.1} m/min with control; {:.1} … {:.1} at constant {:.0} 1/min",
            s.vc_controlled.min,
            s.vc_controlled.max,
            s.vc_constant.min,
            s.vc_constant.max,
            s.constant_spindle
        );
        let _ = writeln!(
            o,
            "  limits     {} clamped, {} rate-limited, {} held under the S threshold, {} feeds clamped",
            s.clamped, s.rate_limited, s.held, s.feed_clamped
        );
        if s.gap_flagged > 0 {
            let _ = writeln!(o, "  warning    {} points are not R from the surface (gouge, wrong convention or a different part)", s.gap_flagged);
        }
        let _ = writeln!(o, "  wrote      {} ({})", self.output, self.dialect);
        let _ = writeln!(
            o,
            "  time       {:.1} s → {:.1} s, estimated with acceleration on {}",
            self.time_before_s, self.time_after_s, self.machine.name
        );
        o.push_str(&self.verdict.text());
        o
    }
}

/// The reading phases' times of `millplan speed` in the context's timings:
/// arguments checked, the STL and its surface, the toolpath read on its own
/// thread and its time estimate, all reading together.
pub fn record_reading(
    cx: &Context,
    [t_setup, t_mesh, t_surface, t_inputs]: [f64; 4],
    [read_s, estimate_s]: [f64; 2],
) {
    cx.record("arguments, machine file and outputs checked", t_setup);
    cx.record("  read STL", t_mesh);
    cx.record("  surface (BVH, vertex normals)", t_surface);
    cx.record("  read toolpath (its own thread)", read_s);
    cx.record(
        "  time estimate of the input (after it, same thread)",
        estimate_s,
    );
    cx.record("read STL, surface and toolpath", t_inputs);
}

#[cfg(test)]
mod tests {
    use super::*;
    use millplan_geom::analytic::{tessellate, DemoSurface};
    use millplan_nc::generate::{raster, Raster};

    pub(super) fn request() -> SpeedRequest {
        SpeedRequest {
            cut: Cutting {
                vc: 63.0,
                fz: 0.125,
                flutes: 2,
                ap: 0.3,
            },
            ball_d: None,
            s_threshold: crate::command_defaults::speed::S_THRESHOLD,
            keep_feed: false,
            convention: None,
            normals: NormalMode::Smooth,
            nearest_incentre: false,
            keep_rows: true,
        }
    }

    /// The command's run is the spindle-control model applied on its own
    /// (`speed::apply`, no pipeline): the same program and summary; its
    /// checks pass (only S and F changed); on a part moved away every point
    /// is off the part and the run is not to be trusted.
    #[test]
    fn the_command_is_the_model_and_says_when_the_part_is_elsewhere() {
        let s = DemoSurface::default();
        let mesh = tessellate(&s, 1.0);
        let stepped = Raster {
            stepover: 3.0,
            step: 1.0,
            ..Raster::default()
        };
        let (prog, _) = raster(&s, &stepped);
        let req = request();
        let machine = Machine::default();
        let want =
            millplan_plan::speed::apply(&prog, &mesh, &machine, &params(&req)).expect("applies");
        let mut cx = Context::new(machine.clone()).with_surface(Surface::new(&mesh));
        let Ok(out) = command(&req, &mut cx, &mesh, prog.clone()) else {
            panic!("the command runs")
        };
        assert_eq!(out.program, want.program);
        assert_eq!(out.summary, want.summary);
        assert_eq!(out.rows.len(), out.summary.points);
        assert!(safety::passed(&out.checks), "{:?}", out.checks);
        assert!(!out.untrusted());
        let times = [
            cycle_time(&prog, &machine),
            cycle_time(&out.program, &machine),
        ];
        let json =
            serde_json::to_value(out.report(("o.nc".into(), Target::Fanuc), &machine, times))
                .expect("json");
        assert_eq!(json["points"], out.summary.points);
        assert_eq!(json["trusted"], true);
        assert!(out.table_csv().lines().count() == out.rows.len() + 1);
        let mut far = mesh.clone();
        far.map_vertices(|v| v + millplan_geom::DVec3::new(0.0, 0.0, -50.0));
        let mut cx = Context::new(machine).with_surface(Surface::new(&far));
        let Ok(off) = command(&req, &mut cx, &far, prog) else {
            panic!("the command runs off the part")
        };
        assert!(off.untrusted());
        assert!(!off.findings.is_empty());
    }

    /// Writing beside the estimate gives what the writer gave and the
    /// estimate `cycle_time` gives.
    #[test]
    fn writing_beside_the_estimate() {
        let (prog, _) = raster(&DemoSurface::default(), &Raster::default());
        let machine = Machine::default();
        let want = cycle_time(&prog, &machine);
        assert!(want > 0.0);
        let (written, after, [w, e]) = write_beside(&prog, &machine, || 7);
        assert_eq!((written, after), (7, want));
        assert!(w >= 0.0 && e >= 0.0);
    }
}
