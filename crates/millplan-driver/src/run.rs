//! `Job::run`: the passes over the job's program, each verified and timed,
//! with the measures before and after.

use crate::job::{Job, JobError};
use crate::orient::{first_spindle, OrientRequest};
use crate::passes::{axis_vectors, missing, PassName};
use millplan_models::leadtilt::Variant;
use millplan_nc::Program;
use millplan_plan::feed::{FeedChanges, FeedParams, FeedPass};
use millplan_plan::force::{self, ForceRun};
use millplan_plan::leadtilt::{choose_with, Objective};
use millplan_plan::pipeline::{self, Context, Pass, Progress};
use millplan_plan::post::{post, PostOptions, PostReport};
use millplan_plan::reorder::{Method, ReorderParams, ReorderPass, Verdict};
use millplan_plan::speed::{deviates, FeedCoupling, SpeedParams, SpeedPass};
use serde::Serialize;
use std::time::Instant;

/// The phase [`Job::run_with`] counts the passes in.
pub const PASSES_PHASE: &str = "optimise: passes";

/// What one pass did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PassOutcome {
    pub name: &'static str,
    pub ran: bool,
    /// Why it was skipped, or what it changed.
    pub reason: String,
    pub seconds: f64,
}

/// The largest loads of a program.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Loads {
    pub fxy: f64,
    pub torque: f64,
    pub power: f64,
    pub deflection: f64,
}

/// A program's measures.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Measures {
    /// Cycle time estimated with acceleration, s.
    pub time_s: f64,
    /// Largest loads (with a stock and a material).
    pub max: Option<Loads>,
    /// Share of the ball-end cutting points whose spindle speed misses the
    /// constant-cutting-speed target by more than 5 % (with a part).
    pub vc_off_share: Option<f64>,
}

/// The optimised program and what was done to it.
pub struct Outcome {
    pub program: Program,
    pub passes: Vec<PassOutcome>,
    pub before: Measures,
    /// The input's forces (for the plots).
    pub forces_before: Option<ForceRun>,
    /// Whether a pass changed the order of the cutting points.
    pub reordered: bool,
    /// Whether the lead/tilt pass turned the tool axes (ball centres kept,
    /// tips moved).
    pub oriented: bool,
    /// After the post: the CL program it was made from and its report.
    pub posted: Option<(Program, PostReport)>,
}

/// Why `pass` is skipped after the passes before it (`None`: it runs):
/// lead and tilt after a new order would leave a program whose tips are
/// checked neither as the same points (the order) nor move by move (the
/// centres), so orient does not follow a reorder that won.
fn after_others(pass: PassName, st: &State) -> Option<String> {
    (pass == PassName::Orient && st.reordered).then(|| {
        "reorder changed the order: lead and tilt are not chosen on a new order in the same run (run `millplan orient` on the result)".to_string()
    })
}

/// What the passes leave for the checks besides the program.
#[derive(Default)]
struct State {
    reordered: bool,
    oriented: bool,
    posted: Option<(Program, PostReport)>,
}

/// Passes a second run leaves out, each with why.
struct Dropped {
    orient: Option<String>,
    reorder: Option<String>,
}

/// Lead and tilt that made the posted program slower than the input.
struct OrientLost {
    /// The posted program's time with the turned axes, s.
    with: f64,
    /// The input's, posted the same way, s.
    input: f64,
}

impl OrientLost {
    fn why(&self) -> String {
        format!(
            "dropped: with the turned axes the program posts in {:.1} s against the input's {:.1} s; without them it is faster",
            self.with, self.input
        )
    }
}

impl Job {
    /// The speed pass's settings: the job's vc, flutes and allowance; the
    /// feed follows the speed at the program's own chip load (its first
    /// cutting block's F/(S·z)), within the fz range.
    pub fn speed_params(&self) -> SpeedParams {
        let z = self.flutes as f64;
        let fz_max = self.limits.fz_range(self.diameter).fz_max;
        let fz = self
            .inputs
            .program
            .moves()
            .find(|m| m.is_cutting() && m.spindle > 0.0 && m.feed > 0.0)
            .map_or(fz_max, |m| m.feed / (m.spindle * z))
            .clamp(self.limits.fz_min, fz_max);
        let mut p = SpeedParams::new(self.vc, fz, self.flutes as u32, self.ap);
        p.feed = FeedCoupling::ChipLoad;
        p.keep_rows = false;
        // A G-code program names its tools by number only: `--tool ball:D`.
        if let Some(millplan_models::cutter::Shape::Ball { radius }) = self.body.shape {
            p.ball_d = Some(2.0 * radius);
        }
        p
    }

    /// The pipeline's context: the machine, the part, the verifier after
    /// every pass (release builds too).
    pub fn context(&self) -> Context<'_> {
        let cx = Context::new(self.inputs.machine.clone()).verifying();
        match &self.inputs.part {
            Some(m) => cx.with_part(m),
            None => cx,
        }
    }

    /// The largest loads of `p` on the job's stock, `None` without a stock
    /// or a material: converged where they may be the program's largest
    /// ([`force::simulate_largest`]), each move's own on the coarsest grid
    /// elsewhere.
    pub fn forces(&self, p: &Program) -> Result<Option<ForceRun>, JobError> {
        Ok(self.forces_kept(p)?.map(|r| r.0))
    }

    /// [`Job::forces`], and the engaged cells its run found
    /// ([`force::EngagementMemo`]), for later runs over the same path.
    pub fn forces_kept(
        &self,
        p: &Program,
    ) -> Result<Option<(ForceRun, force::EngagementMemo)>, JobError> {
        let (Some(stock), Some(setup)) = (&self.stock, &self.setup) else {
            return Ok(None);
        };
        let s = self.strokes(p, true);
        let budget = crate::limits::memo_budget(self.memory(), stock);
        force::simulate_largest_within(p, &s, stock, setup, &|_| {}, budget)
            .map(Some)
            .map_err(JobError::from)
    }

    /// The loads of every move of `p` on the job's stock, each converged
    /// as `millplan force` gives them; `None` without a stock or a
    /// material.
    pub fn forces_of_every_move(&self, p: &Program) -> Result<Option<ForceRun>, JobError> {
        self.forces_using(p, force::LimitUse::None)
    }

    /// The loads of a program the job wrote, as its limits are checked: a
    /// load sample below every limit by more than its error is not refined
    /// further ([`force::LimitUse::Check`]).
    pub fn forces_checked(&self, p: &Program) -> Result<Option<ForceRun>, JobError> {
        self.forces_using(
            p,
            force::LimitUse::Check(&self.limits, &self.inputs.machine),
        )
    }

    fn forces_using(&self, p: &Program, u: force::LimitUse) -> Result<Option<ForceRun>, JobError> {
        let (Some(stock), Some(setup)) = (&self.stock, &self.setup) else {
            return Ok(None);
        };
        let s = self.strokes(p, true);
        force::simulate_with(p, &s, stock.clone(), setup, u, &|_| {}, self.memo())
            .map(Some)
            .map_err(JobError::from)
    }

    /// The share of ball-end cutting points of `p` off the cutting speed.
    pub fn vc_off_share(&self, p: &Program, cx: &Context) -> Option<f64> {
        let surface = cx.surface()?;
        let mut q = p.clone();
        let mut params = self.speed_params();
        params.keep_rows = true;
        let (rows, _, _) =
            millplan_plan::speed::apply_in_place(&mut q, surface, &cx.machine, &params).ok()?;
        let off = rows
            .iter()
            .filter(|r| deviates(p.operations[r.op].moves[r.mv].spindle, r.n_target))
            .count();
        (!rows.is_empty()).then(|| off as f64 / rows.len() as f64)
    }

    /// The measures of `p` (its forces when already known).
    pub fn measure(&self, p: &Program, forces: Option<&ForceRun>, cx: &Context) -> Measures {
        let max = forces.map(|f| {
            let m = f.maxima();
            Loads {
                fxy: m.fxy,
                torque: m.torque,
                power: m.power,
                deflection: m.deflection,
            }
        });
        Measures {
            time_s: millplan_plan::timing::estimate_program(p, &self.inputs.machine).total_s,
            max,
            vc_off_share: self.vc_off_share(p, cx),
        }
    }

    /// Runs `passes` in their order over the job's program: a pass whose
    /// inputs are missing is skipped with its reason.
    pub fn run(&self, passes: &[PassName]) -> Result<Outcome, JobError> {
        self.run_with(passes, None)
    }

    /// [`Job::run`] reporting to `progress` (a bar, say): the phase
    /// `passes` counts the passes done, and each pass reports its own
    /// phases between them.
    pub fn run_with(
        &self,
        passes: &[PassName],
        progress: Option<&Progress>,
    ) -> Result<Outcome, JobError> {
        self.run_dropping(passes, progress, None)
    }

    /// [`Job::run_with`] and the program written and checked
    /// ([`Job::finish_timed`]), `lap` hearing each phase as it ends (`None`)
    /// and, before the passes' phase, each pass that ran with its seconds.
    /// Where the checks
    /// refuse a program whose order reorder changed (a retract link that
    /// plunges beside a wall, say), the passes run again without reorder
    /// and that program is kept if fewer checks refuse it, reorder saying
    /// why it was dropped.
    pub fn run_and_finish(
        &self,
        passes: &[PassName],
        progress: Option<&Progress>,
        wo: millplan_nc::write::WriteOptions,
        lap: &mut dyn FnMut(&str, Option<f64>),
    ) -> Result<(Outcome, crate::Written), JobError> {
        let ran = |o: &Outcome, phase: &str, lap: &mut dyn FnMut(&str, Option<f64>)| {
            for p in o.passes.iter().filter(|p| p.ran) {
                lap(&format!("pass {}", p.name), Some(p.seconds));
            }
            lap(phase, None);
        };
        let checking = || {
            if let Some(f) = progress {
                f("optimise: checks of the written program", 0, 1);
            }
        };
        let outcome = self.run_with(passes, progress)?;
        ran(&outcome, "the input measured, the passes run", lap);
        checking();
        // The skipped passes are said before an error that stops the checks.
        let noted = |mut e: JobError, o: &Outcome| {
            e.notes = crate::report::skipped_notes(o);
            e
        };
        let w = (self.finish_timed(&outcome, wo, &mut |n| lap(n, None)))
            .map_err(|e| noted(e, &outcome))?;
        // Only a fault of the passes' own can be the new order's.
        if !outcome.reordered || !w.summary.checks.iter().any(|c| c.fails_anew()) {
            return Ok((outcome, w));
        }
        let dropped = "dropped: the checks refused the program in the new order".to_string();
        let mut again = self.run_dropping(passes, progress, Some(dropped))?;
        ran(&again, "the passes run again without reorder", lap);
        checking();
        let mut w2 =
            (self.finish_timed(&again, wo, &mut |n| lap(n, None))).map_err(|e| noted(e, &again))?;
        // Kept when the checks that refuse it for faults of the passes' own
        // are some of those that refused the new order so, not all (a fault
        // of the input's own refuses both); reorder then names what refused
        // only its order.
        let failed = |w: &crate::Written| -> Vec<&'static str> {
            w.summary
                .checks
                .iter()
                .filter(|c| c.fails_anew())
                .map(|c| c.name)
                .collect()
        };
        let (before, after) = (failed(&w), failed(&w2));
        if after.len() >= before.len() || !after.iter().all(|c| before.contains(c)) {
            return Ok((outcome, w));
        }
        let passed =
            |name: &str| (w2.summary.checks.iter()).any(|c| c.name == name && !c.fails_anew());
        let only: Vec<String> = (w.summary.checks.iter())
            .filter(|c| c.fails_anew() && passed(c.name))
            .map(|c| match c.refusing().find(|f| !f.in_input) {
                Some(f) => format!("{} at line {}: {}", c.name, f.line.unwrap_or(0), f.message),
                None => c.name.to_string(),
            })
            .collect();
        let why = format!(
            "dropped: the checks refused the program in the new order (check {}); in the old order {} passed",
            only.join("; check "),
            if only.len() == 1 { "it" } else { "they" }
        );
        for p in again.passes.iter_mut().chain(w2.summary.passes.iter_mut()) {
            if p.name == PassName::Reorder.name() {
                p.reason = why.clone();
            }
        }
        Ok((again, w2))
    }

    /// [`Job::run_with`], reorder left out with the reason `no_reorder`
    /// where given.
    fn run_dropping(
        &self,
        passes: &[PassName],
        progress: Option<&Progress>,
        no_reorder: Option<String>,
    ) -> Result<Outcome, JobError> {
        let mut dropped = Dropped {
            orient: None,
            reorder: no_reorder,
        };
        let cx = match progress {
            Some(f) => self.context().with_progress(f),
            None => self.context(),
        };
        let input = self.analysed();
        let forces_before = self.forces_before.clone();
        let before = self.measure(input, forces_before.as_ref(), &cx);
        let (mut program, mut out, mut st) = self.run_passes(passes, &cx, &dropped)?;
        // Lead and tilt are kept only where they win once posted: a program
        // the turned axes make slower than the input on the machine (their
        // rotary motion, the points a post inserts) is run again without
        // them, and the faster of the two is kept.
        if let Some(slower) = self.orient_lost(&st) {
            dropped.orient = Some(slower.why());
            let (p2, out2, st2) = self.run_passes(passes, &cx, &dropped)?;
            if st2
                .posted
                .as_ref()
                .is_some_and(|(_, r)| r.time_s < slower.with)
            {
                (program, out, st) = (p2, out2, st2);
            }
        }
        Ok(Outcome {
            program,
            passes: out,
            before,
            forces_before,
            reordered: st.reordered,
            oriented: st.oriented,
            posted: st.posted,
        })
    }

    /// The pass list run on the input, the passes `dropped` left out.
    fn run_passes(
        &self,
        passes: &[PassName],
        cx: &Context,
        dropped: &Dropped,
    ) -> Result<(Program, Vec<PassOutcome>, State), JobError> {
        let input = self.analysed();
        // The default spindle speed is written only where a pass that needs
        // a speed runs (the speeds, the feeds, lead and tilt on the forces).
        let speeds = passes.iter().any(|&p| {
            matches!(p, PassName::Speed | PassName::Feed | PassName::Orient)
                && missing(self, p).is_none()
        });
        let mut p = if speeds { input } else { &self.inputs.program }.clone();
        let mut out = Vec::new();
        let mut st = State::default();
        for (k, &pass) in passes.iter().enumerate() {
            cx.progress(PASSES_PHASE, k, passes.len());
            let t = Instant::now();
            let dropped = match pass {
                PassName::Orient => dropped.orient.clone(),
                PassName::Reorder => dropped.reorder.clone(),
                _ => None,
            };
            let (ran, reason) = match dropped
                .or_else(|| missing(self, pass))
                .or_else(|| after_others(pass, &st))
            {
                Some(why) => (false, why),
                None => (true, self.run_pass(pass, &mut p, cx, passes, &mut st)?),
            };
            out.push(PassOutcome {
                name: pass.name(),
                ran,
                reason,
                seconds: t.elapsed().as_secs_f64(),
            });
        }
        cx.progress(PASSES_PHASE, passes.len(), passes.len());
        Ok((p, out, st))
    }

    /// Where lead and tilt turned the axes and the program they ended in
    /// posts slower than the input by more than the report's threshold
    /// ([`millplan_report::html::TIME_WORSE`]): the two times.
    fn orient_lost(&self, st: &State) -> Option<OrientLost> {
        let (_, r) = st.posted.as_ref().filter(|_| st.oriented)?;
        let input = post(
            &self.inputs.program,
            &self.inputs.machine,
            &self.post_options(),
        )
        .ok()?;
        let t0 = input.report.time_s;
        (r.time_s > t0 * (1.0 + millplan_report::html::TIME_WORSE)).then_some(OrientLost {
            with: r.time_s,
            input: t0,
        })
    }

    fn run_pass(
        &self,
        pass: PassName,
        p: &mut Program,
        cx: &Context,
        all: &[PassName],
        st: &mut State,
    ) -> Result<String, JobError> {
        match pass {
            PassName::Speed => self.speed(p, cx),
            PassName::Reorder => {
                let (said, changed) = self.reorder(p, cx)?;
                st.reordered |= changed;
                // A new order needs its speeds again (as `millplan reorder` does).
                if changed && all.contains(&PassName::Speed) {
                    return Ok(format!("{said}; {}", self.speed(p, cx)?));
                }
                Ok(said)
            }
            PassName::Feed => self.feed(p, cx),
            PassName::Post => {
                let (said, cl, report) = self.post(p)?;
                st.posted = Some((cl, report));
                Ok(said)
            }
            PassName::Orient => {
                let (said, changed) = self.orient(p)?;
                st.oriented |= changed;
                // Turned axes change the working diameters: the speeds
                // follow them (as after a new order).
                if changed && all.contains(&PassName::Speed) {
                    return Ok(format!("{said}; {}", self.speed(p, cx)?));
                }
                Ok(said)
            }
        }
    }

    fn pipeline(&self, pass: &mut dyn Pass, p: &mut Program, cx: &Context) -> Result<(), JobError> {
        pipeline::run(&mut [pass], p, cx).map_err(|e| JobError::from(e.to_string()))
    }

    fn speed(&self, p: &mut Program, cx: &Context) -> Result<String, JobError> {
        let mut pass = SpeedPass::new(self.speed_params());
        self.pipeline(&mut pass, p, cx)?;
        let s = pass
            .summary
            .ok_or_else(|| JobError::from("speed: no summary".to_string()))?;
        Ok(format!(
            "spindle {:.0}–{:.0} 1/min on {} points ({:.1} % off vc: clamped or rate-limited)",
            s.spindle.min,
            s.spindle.max,
            s.points,
            100.0 * s.vc_deviation_share
        ))
    }

    fn reorder(&self, p: &mut Program, cx: &Context) -> Result<(String, bool), JobError> {
        let mut rp = ReorderParams::new(Method::AsRun);
        // No slower than the verdict of the whole run allows: an order a
        // little slower but nearer the cutting speed would be a measure
        // worse there (`millplan reorder` keeps its own 3 %).
        rp.time_slack = millplan_report::html::TIME_WORSE;
        rp.ap = self.ap;
        rp.vc = self.vc;
        rp.speed = self.speed_params();
        let mut pass = ReorderPass::new(rp);
        self.pipeline(&mut pass, p, cx)?;
        let o = pass
            .outcome
            .ok_or_else(|| JobError::from("reorder: no outcome".to_string()))?;
        Ok(match o.verdict {
            Some(Verdict::Improved) => (
                format!(
                    "new order: {:.1} s → {:.1} s as run, {} direct links, {} retracts",
                    o.before.as_run.time_s,
                    o.after.as_run.time_s,
                    o.stats.direct_links,
                    o.stats.retracts
                ),
                true,
            ),
            _ => ("no order wins: the original order kept".into(), false),
        })
    }

    /// The lead/tilt pass's request: `millplan orient`'s defaults (lead
    /// 0–30°, tilt ±30°, F_xy,max at fz 0.1 mm, ae 0.5 mm, reach 30 mm, 48
    /// samples, no holder) with the job's material, flutes, helix,
    /// allowance (ap), resolution and the program's first cutting speed, as
    /// `millplan orient --stock` with those options runs it.
    pub fn orient_request(&self, p: &Program) -> Result<OrientRequest, JobError> {
        use crate::command_defaults::orient as d;
        let helix = self.setup.map_or(d::HELIX_DEG, |s| s.helix.to_degrees());
        Ok(OrientRequest {
            lead_range: d::LEAD_RANGE.into(),
            tilt_range: d::TILT_RANGE.into(),
            variant: Variant::TiltThenLead,
            objective: Objective::Fxy,
            fz: d::FZ,
            n: Some(first_spindle(p).ok_or_else(|| {
                JobError::from(
                    "orient: the program sets no spindle speed for its cutting moves".to_string(),
                )
            })?),
            flutes: self.flutes,
            helix,
            ap: self.ap,
            ae: d::AE,
            reach: d::REACH,
            holder: None,
            material: self.inputs.material.clone().unwrap_or_default(),
            stock: None,
            resolution: self.resolution,
            samples: d::SAMPLES,
        })
    }

    /// Lead and tilt per five-axis ball-end operation (tool axis vectors
    /// on every cutting move, [`axis_vectors`]) from the forces on the
    /// job's stock: `p` becomes the re-oriented program (ball centres
    /// kept; every other operation as it was). Returns what it did and
    /// whether any operation was re-oriented.
    fn orient(&self, p: &mut Program) -> Result<(String, bool), JobError> {
        let (Some(mesh), Some(stock)) = (&self.inputs.part, &self.stock) else {
            return Err(JobError::from("orient: no part or stock".to_string()));
        };
        let req = self.orient_request(p)?;
        let params = crate::orient::params(&req, &self.inputs.materials).map_err(JobError::from)?;
        let st = self.strokes(p, false);
        let input = crate::orient::stock_input(stock.clone(), &st, req.samples);
        let o = choose_with(
            p,
            mesh,
            &self.inputs.machine,
            &params,
            Some(input),
            &|_, _, _| {},
        )
        .map_err(|e| JobError::from(format!("orient: {e}")))?;
        let five: Vec<bool> = p.operations.iter().map(axis_vectors).collect();
        if o.program.operations.len() != five.len() {
            return Err(JobError::from(
                "orient: the operations changed in number".to_string(),
            ));
        }
        let mut out = o.program;
        for ((new, old), five) in out.operations.iter_mut().zip(&p.operations).zip(&five) {
            if !five {
                *new = old.clone();
            }
        }
        let chosen: Vec<_> = o.chosen.iter().filter(|c| five[c.operation]).collect();
        let said = if chosen.is_empty() {
            "no operation re-oriented (no five-axis ball-end operation touches the part)"
                .to_string()
        } else {
            let ops: Vec<String> = chosen
                .iter()
                .map(|c| {
                    let before = c.objective_before.map_or(
                        "the orientation read is refused by the constraints".to_string(),
                        |v| format!("{v:.1} N as read"),
                    );
                    format!(
                        "operation {}: lead {:.1}°, tilt {:.1}° (F_xy,max {:.1} N; {before})",
                        c.operation + 1,
                        c.lead,
                        c.tilt,
                        c.objective_after
                    )
                })
                .collect();
            ops.join("; ")
        };
        let changed = !chosen.is_empty();
        *p = out;
        Ok((said, changed))
    }

    /// Whether the post writes inverse-time feed: `--g93`, else the machine
    /// file's `[post] inverse_time`.
    pub fn g93(&self) -> bool {
        self.inputs.options.g93 || self.inputs.machine.post.inverse_time
    }

    /// The post's settings: the job's tolerance, G93 as [`Job::g93`], the
    /// machine file's pole cone, pole tolerance and clearance; joint
    /// positions (no TCP).
    pub fn post_options(&self) -> PostOptions {
        let m = &self.inputs.machine.post;
        PostOptions {
            tol: self.tol,
            tcp: false,
            g93: self.g93(),
            pole_cone: m.pole_cone,
            pole_tol: m.pole_tol,
            clearance: m.clearance,
        }
    }

    /// Five-axis CL through the machine's kinematics: `p` becomes the
    /// posted program; the CL program and the post's report are returned.
    fn post(&self, p: &mut Program) -> Result<(String, Program, PostReport), JobError> {
        let posted = post(p, &self.inputs.machine, &self.post_options()).map_err(|e| {
            let m = if e.line() == 0 {
                format!("post: {e}")
            } else {
                format!("{e}")
            };
            // The machine cannot run the program (an axis out of its
            // travel): a finding, as `millplan post` exits on it.
            if e.is_check() {
                JobError::refused(format!("{m}; nothing written"))
            } else {
                JobError::from(m)
            }
        })?;
        let r = posted.report;
        let said = format!(
            "{} blocks in {}, {} flips, {} points inserted, tip within {:.4} mm by the kinematics; {:.1} s as posted",
            r.blocks,
            if self.g93() { "G93 (inverse time)" } else { "G94" },
            r.flips.len(),
            r.inserted_points,
            r.max_tip_error_mm,
            r.time_s
        );
        let cl = std::mem::replace(p, posted.program);
        Ok((said, cl, r))
    }

    /// The feed pass's settings.
    pub fn feed_params(&self) -> Option<FeedParams> {
        Some(FeedParams {
            setup: self.setup?,
            limits: self.limits,
            accel: self.feed_accel,
            chord: self.resolution / 4.0,
            learned: Vec::new(),
        })
    }

    fn feed(&self, p: &mut Program, cx: &Context) -> Result<String, JobError> {
        let (Some(params), Some(stock)) = (self.feed_params(), &self.stock) else {
            return Err(JobError::from("feed: no stock or material".to_string()));
        };
        let mut pass = FeedPass::new(params, stock.clone(), self.body_fn());
        pass.memo = self.kept.clone();
        self.pipeline(&mut pass, p, cx)?;
        let c: FeedChanges = pass.changes.unwrap_or_default();
        let binding: Vec<String> = c.binding.iter().map(|(k, v)| format!("{k} {v}")).collect();
        Ok(format!(
            "{} blocks from the forces, {} in air, {} kept; F {:.0}–{:.0} mm/min; deciding: {}",
            c.blocks,
            c.air_blocks,
            c.kept_blocks,
            c.feed_min,
            c.feed_max,
            binding.join(", ")
        ))
    }
}
