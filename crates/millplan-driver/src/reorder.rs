//! `millplan reorder`: the checks of the reordered program, the run
//! (`run_command`) and the summary the command prints.

use crate::check::{arg, Range};
use millplan_nc::{Operation, Program};
use millplan_plan::pipeline::{self, Context, Pass};
use millplan_plan::reorder::run::Tried;
use millplan_plan::reorder::{Method, ReorderParams, ReorderPass, Start};
use millplan_plan::reorder::{OrderIndicators, Outcome, ReorderStats, Verdict};
use millplan_plan::safety::{self, Check, Inputs, TipRule, Tolerances};
use millplan_plan::speed::SpeedPass;
use millplan_sim::stock::tool::ToolBody;
use serde::Serialize;
use std::fmt::Write as _;

mod command;
pub use command::{run_command, ReorderCommand, ReorderRun};

/// The reordered program against the input: the IR verifier, every
/// cutting point of the input still cut, S and F within the machine, no
/// gouge into the part the input did not have (rapids and links included).
pub fn check(input: &Program, output: &Program, cx: &Context) -> Vec<Check> {
    let body = |op: &Operation| {
        let c = op.tool.as_ref()?.cutter?;
        millplan_sim::shape_of(&c).map(ToolBody::new)
    };
    safety::check(&Inputs {
        input,
        output,
        part: cx.drop_mesh(),
        stock: None,
        tool_body: &body,
        machine: Some(&cx.machine),
        tip: TipRule::SamePoints,
        tol: Tolerances::default(),
        loads: None,
    })
}

/// The options of `millplan reorder` as given.
#[derive(Clone, Copy, Debug)]
pub struct ReorderRequest {
    pub method: Method,
    pub start: Start,
    pub n_min: usize,
    /// mm.
    pub tie: f64,
    /// mm; 0: no limit.
    pub max_step: f64,
    pub cut: crate::speed::Cutting,
    /// Run the speed pass after the new order.
    pub speed: bool,
}

impl ReorderRequest {
    /// Every number in its range, then the pass's parameters.
    pub fn params(&self) -> Result<ReorderParams, String> {
        arg("--max-step", self.max_step, Range::from(0.0, 1000.0, "mm"))?;
        arg("--tie", self.tie, Range::from(0.0, 100.0, "mm"))?;
        self.cut.check()?;
        let mut rp = ReorderParams::new(self.method);
        rp.start = self.start;
        rp.n_min = self.n_min;
        rp.tie = self.tie;
        rp.max_step = (self.max_step > 0.0).then_some(self.max_step);
        rp.ap = self.cut.ap;
        rp.vc = self.cut.vc;
        rp.speed = self.cut.params();
        Ok(rp)
    }
}

/// What a run of `millplan reorder` made: the program in its new order
/// (and speeds), the pass's outcome and the checks against the input.
pub struct Reordered {
    pub program: Program,
    pub outcome: Outcome,
    pub checks: Vec<Check>,
}

/// Why a run of `millplan reorder` stopped.
#[derive(Debug)]
pub enum ReorderError {
    /// A pass's own error (the input's, or a bug).
    Pass(pipeline::PassError),
    /// A bug: the reorder pass ran and left no outcome.
    NoOutcome,
}

/// `millplan reorder` on `input` in `cx` (the part in it): the reorder
/// pass, the speed pass unless left out, the checks of the result.
pub fn command(
    a: &ReorderRequest,
    rp: ReorderParams,
    cx: &Context,
    input: &Program,
) -> Result<Reordered, ReorderError> {
    let mut program = input.clone();
    let mut reorder = ReorderPass::new(rp);
    let mut speed = SpeedPass::new(rp.speed);
    let mut passes: Vec<&mut dyn Pass> = vec![&mut reorder];
    if a.speed {
        passes.push(&mut speed);
    }
    pipeline::run(&mut passes, &mut program, cx).map_err(ReorderError::Pass)?;
    let outcome = reorder.outcome.take().ok_or(ReorderError::NoOutcome)?;
    let checks = cx.time("checks", || check(input, &program, cx));
    Ok(Reordered {
        program,
        outcome,
        checks,
    })
}

impl Reordered {
    /// The HTML report: the inputs (the program and the part by their
    /// file names in `names`), warnings (the part's mesh defects, points
    /// off the part, a spindle that cannot follow), the verdict and both
    /// orders.
    pub fn report_html(
        &self,
        (input, mesh): (&Program, &millplan_geom::TriMesh),
        names: (String, String),
        (machine, cut): (&millplan_plan::machine::Machine, crate::speed::Cutting),
        method: String,
    ) -> String {
        let findings: Vec<_> = millplan_plan::checks::mesh(mesh).into_iter().collect();
        let o = &self.outcome;
        let times = [o.before.as_run.time_s, o.after.as_run.time_s];
        let run =
            crate::speed::report_inputs((names.0, input), names.1, machine, cut, &findings, times);
        let i = millplan_report::reorder::ReorderInputs { run, method };
        millplan_report::reorder::reorder_report(input, &self.program, o, &i)
    }
}

/// What `reorder` reports (`--json`).
#[derive(Serialize)]
pub struct Summary<'a> {
    pub method: Option<String>,
    pub verdict: Option<Verdict>,
    pub original: &'a OrderIndicators,
    pub reordered: &'a OrderIndicators,
    pub stats: &'a ReorderStats,
    pub tried: &'a [Tried],
    pub output: String,
    pub checks: &'a [Check],
}

impl<'a> Summary<'a> {
    pub fn new(
        method: Option<String>,
        o: &'a Outcome,
        output: String,
        checks: &'a [Check],
    ) -> Self {
        Summary {
            method,
            verdict: o.verdict,
            original: &o.before,
            reordered: &o.after,
            stats: &o.stats,
            tried: &o.tried,
            output,
            checks,
        }
    }

    /// Both orders side by side, then what was written.
    pub fn render_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "  {:<28} {:>16} {:>16}", "", "original", "reordered");
        for (k, v) in millplan_report::reorder::rows(self.original, self.reordered) {
            let (b, r) = v.split_once(" → ").unwrap_or((&v, ""));
            let _ = writeln!(s, "  {k:<28} {b:>16} {r:>16}");
        }
        let _ = match self.verdict {
            Some(Verdict::Kept) => writeln!(
                s,
                "  no order found that runs better and worse on nothing: the original order kept; wrote {}",
                self.output
            ),
            _ => writeln!(
                s,
                "  {} direct links, {} retracts; wrote {}",
                self.stats.direct_links, self.stats.retracts, self.output
            ),
        };
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::command_defaults::{cutting as c, reorder as d};
    use millplan_geom::analytic::{tessellate, DemoSurface};
    use millplan_nc::generate::{raster, Raster};

    fn request(speed: bool) -> ReorderRequest {
        ReorderRequest {
            method: Method::AsRun,
            start: Start::Lowest,
            n_min: d::N_MIN,
            tie: d::TIE,
            max_step: d::MAX_STEP,
            cut: crate::speed::Cutting {
                vc: c::VC,
                fz: c::FZ,
                flutes: c::FLUTES,
                ap: c::AP,
            },
            speed,
        }
    }

    /// On the demo part's raster the default method keeps or improves the
    /// order (never worse on its measures: the as-run rule), every cutting
    /// point of the input still cut and nothing gouged (its checks pass);
    /// left without the speed pass, no spindle speed changes. A tie beyond
    /// its range is refused naming the option.
    #[test]
    fn the_command_never_orders_worse_and_keeps_every_point() {
        let s = DemoSurface::default();
        let mesh = tessellate(&s, 1.5);
        let rows = Raster {
            stepover: 3.0,
            step: 1.0,
            ..Raster::default()
        };
        let (input, _) = raster(&s, &rows);
        let cx = Context::new(millplan_plan::machine::Machine::default()).with_part(&mesh);
        for speed in [true, false] {
            let req = request(speed);
            let rp = req.params().expect("params");
            let Ok(r) = command(&req, rp, &cx, &input) else {
                panic!("reorders")
            };
            assert!(safety::passed(&r.checks), "{:?}", r.checks);
            let o = &r.outcome;
            assert!(
                o.after.time_s <= o.before.time_s + 1e-9,
                "{} {}",
                o.after.time_s,
                o.before.time_s
            );
            assert_eq!(o.after.points, o.before.points);
            if !speed {
                let s_in: Vec<f64> = input.moves().map(|m| m.spindle).collect();
                assert!(r.program.moves().all(|m| s_in.contains(&m.spindle)));
            }
        }
        let bad = ReorderRequest {
            tie: 200.0,
            ..request(true)
        };
        assert!(bad.params().expect_err("tie").starts_with("--tie"));
    }
}
