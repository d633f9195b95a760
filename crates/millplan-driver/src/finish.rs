//! The optimised program written, re-read from its bytes and checked; the
//! verdict and the measures after.

use crate::checks;
use crate::job::{Job, JobError, Setting};
use crate::run::{Loads, Measures, Outcome, PassOutcome};
use millplan_nc::equiv::Tolerance;
use millplan_nc::readback::read_back;
use millplan_nc::write::{write_program, WriteOptions};
use millplan_nc::{Diagnostic, Program};
use millplan_plan::force::ForceRun;
use millplan_plan::safety::{self, Check, Inputs, LoadCheck, TipRule, Tolerances};
use millplan_sim::dropcutter::DropMesh;
use serde::Serialize;

/// What a run concluded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Faster, or nearer the cutting speed, with every check passed.
    Improved,
    /// Every check passed but nothing measured better.
    Kept,
    /// A check failed: nothing is written unless forced.
    Refused,
}

/// The run's summary, as JSON scripts read it (`--json`).
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub verdict: Verdict,
    pub passes: Vec<PassOutcome>,
    pub time_before_s: f64,
    pub time_after_s: f64,
    pub max_before: Option<Loads>,
    pub max_after: Option<Loads>,
    /// Share of ball-end points off the cutting speed.
    pub vc_off_before: Option<f64>,
    pub vc_off_after: Option<f64>,
    pub checks: Vec<Check>,
    /// Every setting with where its value came from.
    pub settings: Vec<Setting>,
    pub dialect: String,
    pub moves: usize,
}

/// The written program with its checks.
pub struct Written {
    pub bytes: Vec<u8>,
    /// Words written as comments (the writer's warnings).
    pub warnings: Vec<Diagnostic>,
    pub summary: Summary,
    /// The forces of the written program (for the plots).
    pub forces_after: Option<ForceRun>,
    /// The written program as re-read.
    pub program: Program,
}

impl Summary {
    /// The first check that refuses the output: its name, line and words.
    pub fn refusal(&self) -> Option<(&'static str, u32, String)> {
        safety::first_refusal(&self.checks)
            .map(|(c, f)| (c.name, f.line.unwrap_or(0), f.message.clone()))
    }
}

impl Job {
    /// Writes the outcome's program with `wo`, re-reads it from its bytes
    /// and runs every check that applies on what was read.
    pub fn finish(&self, o: &Outcome, wo: WriteOptions) -> Result<Written, JobError> {
        let (bytes, warnings) = write_program(&o.program, wo)
            .map_err(|e| JobError(format!("{}: {}", e.line, e.message)))?;
        let back = read_back(&bytes, wo.target, &o.program, &Tolerance::default())
            .map_err(|e| JobError(format!("the program written does not read back: {e}")))?;
        let mut list = vec![safety::read_back_check(&back)];
        let mut read = back.program;
        checks::same_tools(&mut read, &o.program);
        let forces_after = self.forces(&read)?;
        list.extend(self.checks(o, &read, forces_after.as_ref()));
        let cx = self.context();
        let after = self.measure(&read, forces_after.as_ref(), &cx);
        let summary = self.summary(o, &after, list, wo);
        Ok(Written {
            bytes,
            warnings,
            summary,
            forces_after,
            program: read,
        })
    }

    /// `safety::check` on the program read back, with the job's tools,
    /// stock, part, machine and limits.
    fn checks(&self, o: &Outcome, read: &Program, after: Option<&ForceRun>) -> Vec<Check> {
        let drop = self.inputs.part.as_ref().map(DropMesh::new);
        let body = |op: &millplan_nc::Operation| self.body_of(op);
        let loads = after.map(|run| {
            let v = checks::loads_of(read, run, &self.limits, &self.inputs.machine);
            move |_: &Program| v.clone()
        });
        let tol = Tolerances {
            collision: self.tol,
            gouge: self.tol.min(Tolerances::default().gouge),
            ..Tolerances::default()
        };
        safety::check(&Inputs {
            input: &self.inputs.program,
            output: read,
            part: drop.as_ref(),
            stock: self.stock.as_ref(),
            tool_body: &body,
            machine: Some(&self.inputs.machine),
            tip: if o.reordered {
                TipRule::SamePoints
            } else {
                TipRule::Kept
            },
            tol,
            loads: loads.as_ref().map(|l| l as &dyn LoadCheck),
        })
    }

    fn summary(
        &self,
        o: &Outcome,
        after: &Measures,
        checks: Vec<Check>,
        wo: WriteOptions,
    ) -> Summary {
        let b = &o.before;
        let faster = after.time_s < b.time_s * (1.0 - 1e-3);
        let nearer =
            matches!((b.vc_off_share, after.vc_off_share), (Some(x), Some(y)) if y < x - 1e-3);
        let verdict = if checks.iter().any(|c| !c.ok) {
            Verdict::Refused
        } else if faster || nearer {
            Verdict::Improved
        } else {
            Verdict::Kept
        };
        Summary {
            verdict,
            passes: o.passes.clone(),
            time_before_s: b.time_s,
            time_after_s: after.time_s,
            max_before: b.max,
            max_after: after.max,
            vc_off_before: b.vc_off_share,
            vc_off_after: after.vc_off_share,
            checks,
            settings: self.settings.clone(),
            dialect: wo.target.name().to_string(),
            moves: o.program.move_count(),
        }
    }
}
