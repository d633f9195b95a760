//! The optimised program written, re-read from its bytes and checked; the
//! verdict and the measures after.

use crate::checks::{self, Check};
use crate::job::{Job, JobError, Setting};
use crate::run::{Loads, Measures, Outcome, PassOutcome};
use millplan_nc::write::{write_program, WriteOptions};
use millplan_nc::{Diagnostic, Program};
use millplan_plan::force::ForceRun;
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
        self.checks.iter().find_map(|c| {
            c.first_refusal()
                .map(|f| (c.name, f.line, f.message.clone()))
        })
    }
}

impl Job {
    /// Writes the outcome's program with `wo`, re-reads it from its bytes
    /// and runs every check that applies on what was read.
    pub fn finish(&self, o: &Outcome, wo: WriteOptions) -> Result<Written, JobError> {
        let (bytes, warnings) = write_program(&o.program, wo)
            .map_err(|e| JobError(format!("{}: {}", e.line, e.message)))?;
        let (back, rb) = checks::read_back(&o.program, &bytes);
        let read = back.unwrap_or_else(|| o.program.clone());
        let forces_after = self.forces(&read)?;
        let mut list = vec![rb];
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

    fn checks(&self, o: &Outcome, read: &Program, after: Option<&ForceRun>) -> Vec<Check> {
        let input = &self.inputs.program;
        let mut v = vec![
            checks::machine(read, &self.inputs.machine),
            checks::tips(input, read, o.reordered, self.tol.max(1e-3)),
        ];
        if let Some(stock) = &self.stock {
            v.push(checks::collisions(
                stock,
                &self.strokes(input),
                &self.strokes(read),
                self.tol,
            ));
        }
        if let (Some(a), Some(b)) = (after, &o.forces_before) {
            v.push(checks::loads(a, b, &self.limits, &self.inputs.machine));
        }
        if let Some(part) = &self.inputs.part {
            let body = self.body;
            let shape = move |op: &millplan_nc::Operation| {
                millplan_sim::stock::tool::ToolBody::for_operation(op, &body).map(|b| b.shape)
            };
            v.push(checks::gouges(part, input, read, &shape, self.tol));
        }
        v
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
