//! `millplan reorder`: the checks of the reordered program and the summary
//! the command prints.

use millplan_nc::{Operation, Program};
use millplan_plan::pipeline::Context;
use millplan_plan::reorder::run::Tried;
use millplan_plan::reorder::{OrderIndicators, Outcome, ReorderStats, Verdict};
use millplan_plan::safety::{self, Check, Inputs, TipRule, Tolerances};
use millplan_sim::stock::tool::ToolBody;
use serde::Serialize;
use std::fmt::Write as _;

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
