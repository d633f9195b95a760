//! The optimised program written, re-read from its bytes and checked; the
//! verdict and the measures after.

use crate::checks;
use crate::job::{Job, JobError, Setting};
use crate::run::{Loads, Measures, Outcome, PassOutcome};
use millplan_nc::equiv::Tolerance;
use millplan_nc::readback::read_back_with;
use millplan_nc::write::{write_program, WriteOptions};
use millplan_nc::{Diagnostic, Program};
use millplan_plan::force::ForceRun;
use millplan_plan::post::post;
use millplan_plan::safety::{self, Check, Inputs, LoadCheck, TipRule, Tolerances};
use millplan_sim::dropcutter::DropMesh;
use serde::Serialize;

/// What a run concluded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Faster, or nearer the cutting speed, with neither measure worse and
    /// every check passed.
    Improved,
    /// Every check passed, the passes left the program as it was, and
    /// nothing measured better: the input is what is written.
    Kept,
    /// Every check passed and the passes' program is written, but nothing
    /// measured better, or what got better came with a measure worse (a
    /// slower program nearer the cutting speed, or feeds lowered into a
    /// limit the input exceeded): not what the user asked for, said as such.
    NotImproved,
    /// A check failed: nothing is written unless forced.
    Refused,
}

/// The verdict of a run whose checks `failed` or not, from its cycle
/// times and its shares of points off the cutting speed (before, after):
/// improved when faster or nearer the cutting speed (by more than 0.1 %)
/// with neither worse (the time by the report's threshold,
/// [`millplan_report::html::TIME_WORSE`]; the share by 0.1 %), else kept.
pub fn decide(failed: bool, time: (f64, f64), vc: (Option<f64>, Option<f64>)) -> Verdict {
    let faster = time.1 < time.0 * (1.0 - 1e-3);
    let nearer = matches!(vc, (Some(x), Some(y)) if y < x - 1e-3);
    let slower = time.1 > time.0 * (1.0 + millplan_report::html::TIME_WORSE);
    let farther = matches!(vc, (Some(x), Some(y)) if y > x + 1e-3);
    if failed {
        Verdict::Refused
    } else if (faster || nearer) && !(slower || farther) {
        Verdict::Improved
    } else {
        Verdict::Kept
    }
}

/// The run's summary, as JSON scripts read it (`--json`).
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub verdict: Verdict,
    /// The verdict's level by the one rule of every report
    /// (`millplan_report::html::Level::of`): red when a check failed, amber
    /// when the input was kept, a warning applies or a measure got worse.
    pub level: millplan_report::html::Level,
    /// What the level's warnings say (a load pass skipped on a stock no cut
    /// meets, the input's own findings), as the text summary prints them.
    pub warnings: Vec<String>,
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
    /// Whether the program written is the input as it was (no pass
    /// changed it).
    pub input_unchanged: bool,
    /// `optimise --robot`: what the compensation pass found and left
    /// (absent without it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub robot: Option<crate::robot_pass::RobotSummary>,
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
        safety::first_refusal(&self.checks).map(|(c, f)| {
            let own = if f.in_input {
                " (the input's own fault)"
            } else {
                ""
            };
            (c.name, f.line.unwrap_or(0), format!("{}{own}", f.message))
        })
    }
}

impl Job {
    /// Writes the outcome's program with `wo`, re-reads it from its bytes
    /// and runs every check that applies on what was read.
    pub fn finish(&self, o: &Outcome, wo: WriteOptions) -> Result<Written, JobError> {
        self.finish_timed(o, wo, &mut |_| {})
    }

    /// [`Job::finish`] naming its phases to `lap` as each ends: writing
    /// and reading back, the output's loads, the checks, the measures.
    pub fn finish_timed(
        &self,
        o: &Outcome,
        wo: WriteOptions,
        lap: &mut dyn FnMut(&str),
    ) -> Result<Written, JobError> {
        let (program, wo) = self.for_writing(o, wo)?;
        let program = program.as_ref().unwrap_or(&o.program);
        let (bytes, warnings) = write_program(program, wo)
            .map_err(|e| JobError::from(format!("{}: {}", e.line, e.message)))?;
        let tol = Tolerance {
            position: self.tol.max(Tolerance::default().position),
            ..Tolerance::default()
        };
        let back = match read_back_with(&bytes, wo.target, program, &tol, wo.g93_seconds) {
            Ok(b) => b,
            // A failed check like any other: refused, written with --force.
            Err(e) => {
                let check = Check {
                    name: "read-back",
                    ok: false,
                    checked: 0,
                    unit: "steps",
                    skipped: None,
                    findings: vec![safety::Finding {
                        line: None,
                        message: format!("the program written does not read back at its line {e}"),
                        in_input: false,
                        refuses: true,
                    }],
                };
                let after = self.measure(program, None, &self.context());
                let summary = self.summary(o, &after, vec![check], wo);
                return Ok(Written {
                    bytes,
                    warnings,
                    summary,
                    forces_after: None,
                    program: program.clone(),
                });
            }
        };
        let mut list = vec![safety::read_back_check(&back)];
        let mut read = back.program;
        checks::same_tools(&mut read, program);
        lap("program written in memory and read back");
        // A posted program is in machine coordinates: the loads, the stock
        // and the part are checked on the CL program it was posted from,
        // its tips through the kinematics against the input.
        let cl = o.posted.as_ref().map_or(&read, |(cl, _)| cl);
        // Loads and measures at the speed the input's were taken at, where
        // the program written has no S of its own.
        let analysed = self.analysed_copy(cl);
        // The loads of the feeds and speeds read back, on the path the
        // passes computed on where the written one pairs with it within the
        // tolerance (the tip check holds it to that).
        let paired = match o.posted {
            Some(_) => None,
            None => checks::loads_program(&read, program, self.tol),
        };
        let forces_after = match &paired {
            Some(p) => self.forces_checked(&self.analysed_copy(p))?,
            None => self.forces_checked(&analysed)?,
        };
        lap("the output's loads on the stock");
        list.extend(self.checks(o, cl, (&analysed, forces_after.as_ref())));
        if let Some((cl, _)) = &o.posted {
            self.posted_checks(cl, &read, o.oriented, &mut list);
        }
        lap("the output checked (IR, machine, tips, stock, part)");
        let cx = self.context();
        let mut after = self.measure(&analysed, forces_after.as_ref(), &cx);
        if let Some((_, r)) = &o.posted {
            // What the machine runs: the posted blocks with the rotary
            // axes' motion, not the CL program's tip path.
            after.time_s = r.time_s;
        }
        let summary = self.summary(o, &after, list, wo);
        lap("the output measured (time, constant-vc share)");
        Ok(Written {
            bytes,
            warnings,
            summary,
            forces_after,
            program: read,
        })
    }

    /// A posted program as the target writes it (the TCP words its control
    /// knows, TCP stated by the post itself), `None` when nothing was posted.
    fn for_writing(
        &self,
        o: &Outcome,
        mut wo: WriteOptions,
    ) -> Result<(Option<Program>, WriteOptions), JobError> {
        if o.posted.is_none() {
            return Ok((None, wo));
        }
        if !wo.target.is_gcode() {
            return Err(JobError::from(
                "a posted program is G-code: give --to with a G-code dialect".to_string(),
            ));
        }
        let mut p = o.program.clone();
        millplan_plan::post::for_target(&mut p, wo.target)
            .map_err(|e| JobError::from(format!("{}: {e}", e.line())))?;
        wo.auto_tcp = false;
        Ok((Some(p), wo))
    }

    /// The posted program as read back against the CL program it was
    /// posted from (`cl`, the input unless a pass before the post turned
    /// its axes): the IR verifier, S and F within the machine (G93 words
    /// included), and every posted tip through the machine's forward
    /// kinematics on the CL path within the tolerance; these replace the CL
    /// program's checks of the same names. When the axes were turned
    /// (`oriented`) the CL program's own tip check (ball centres where the
    /// input put them) stands beside the posted one, the two as one `tip`
    /// check.
    fn posted_checks(&self, cl: &Program, read: &Program, oriented: bool, list: &mut Vec<Check>) {
        let Some(kin) = self.inputs.machine.kinematics() else {
            return;
        };
        let input = if oriented { cl } else { &self.inputs.program };
        let posted = safety::check(&Inputs {
            input,
            output: read,
            part: None,
            stock: None,
            tool_body: &|_| None,
            machine: Some(&self.inputs.machine),
            tip: TipRule::MovedBy(kin),
            tol: Tolerances {
                tip: self.tol,
                ..Tolerances::default()
            },
            loads: None,
        });
        let replaced = ["ir", "machine", "tip"];
        let centres = list
            .iter()
            .position(|c| oriented && c.name == "tip")
            .map(|k| list.remove(k));
        list.retain(|c| !replaced.contains(&c.name));
        for mut c in posted.into_iter().filter(|c| replaced.contains(&c.name)) {
            if let Some(centres) = centres.as_ref().filter(|_| c.name == "tip") {
                c.ok &= centres.ok;
                c.findings.extend(centres.findings.iter().cloned());
                if let Some(b) = &centres.skipped {
                    let a = c.skipped.take().map_or(String::new(), |a| format!("{a}; "));
                    c.skipped = Some(format!("{a}ball centres: {b}"));
                }
            }
            list.push(c);
        }
    }

    /// `safety::check` on the program read back, with the job's tools,
    /// stock, part, machine and limits.
    /// `analysed` is `read` as the loads were taken (its default spindle
    /// speed, [`Job::analysed_copy`]), `after` its forces.
    fn checks(
        &self,
        o: &Outcome,
        read: &Program,
        (analysed, after): (&Program, Option<&ForceRun>),
    ) -> Vec<Check> {
        let drop = self.inputs.part.as_ref().map(DropMesh::new);
        let body = |op: &millplan_nc::Operation| self.body_of(op);
        let loads = after.map(|run| {
            let v = checks::loads_of(analysed, run, &self.limits, &self.inputs.machine);
            move |_: &Program| v.clone()
        });
        // The input's own gouges are allowed up to `--tol` where it is wider
        // than the default (a part exported with a coarse chord).
        let tol = Tolerances {
            collision: self.tol,
            gouge: self.tol.min(Tolerances::default().gouge),
            input_gouge: self.tol.max(Tolerances::default().input_gouge),
            ..Tolerances::default()
        };
        safety::check(&Inputs {
            input: &self.inputs.program,
            output: read,
            part: drop.as_ref(),
            stock: self.stock.as_ref(),
            tool_body: &body,
            machine: Some(&self.inputs.machine),
            // Orient does not run after a reorder that won (`after_others`),
            // so at most one of the two applies.
            tip: match (o.reordered, o.oriented) {
                (true, _) => TipRule::SamePoints,
                (false, true) => TipRule::CentreKept,
                (false, false) => TipRule::Kept,
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
        // A posted program against the input as the same post runs it (the
        // input's CL estimate knows nothing of the rotary axes), when the
        // input posts.
        let before_time = match &o.posted {
            Some(_) => post(
                &self.inputs.program,
                &self.inputs.machine,
                &self.post_options(),
            )
            .map_or(b.time_s, |p| p.report.time_s),
            None => b.time_s,
        };
        let verdict = decide(
            checks.iter().any(|c| !c.ok),
            (before_time, after.time_s),
            (b.vc_off_share, after.vc_off_share),
        );
        let input_unchanged = o.program == self.inputs.program;
        let verdict = match verdict {
            Verdict::Kept if !input_unchanged => Verdict::NotImproved,
            v => v,
        };
        let mut s = Summary {
            verdict,
            level: millplan_report::html::Level::Green,
            warnings: Vec::new(),
            passes: o.passes.clone(),
            time_before_s: before_time,
            time_after_s: after.time_s,
            max_before: b.max,
            max_after: after.max,
            vc_off_before: b.vc_off_share,
            vc_off_after: after.vc_off_share,
            checks,
            settings: self.settings.clone(),
            dialect: wo.target.name().to_string(),
            moves: o.program.move_count(),
            input_unchanged,
            robot: None,
        };
        s.level = crate::report::level(&s);
        s.warnings = crate::report::warnings(&s);
        s
    }
}

impl crate::job::Inputs {
    /// How a job's program is written to `output`: the dialect by the one
    /// rule of [`crate::target::output_target`] (`to`, else the machine
    /// file, else the file name, else the source), the machine's options,
    /// and the run's resource `limits`. KRL is refused without a robot
    /// cell (`robot`: `--robot` given), before any work on the inputs.
    pub fn write_options(
        &self,
        to: Option<millplan_nc::write::Target>,
        output: &std::path::Path,
        limits: millplan_nc::Limits,
        robot: bool,
    ) -> Result<WriteOptions, String> {
        let i = self;
        let machine = i.machine_given.then_some(&i.machine);
        let target = crate::target::output_target(to, output, machine, i.program.source)?;
        if target == millplan_nc::write::Target::Krl && !robot {
            // Its frames, tool and speeds are the robot cell's: refused
            // before any pass rather than by the checks of what it wrote.
            return Err(format!(
                "{}: a KRL program is written for a robot cell: give it with --robot and --pose, or name a machine tool's dialect with --to",
                output.display()
            ));
        }
        Ok(WriteOptions {
            limits,
            ..i.machine.write_options(target)
        })
    }
}
