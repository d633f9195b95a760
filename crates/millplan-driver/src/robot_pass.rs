//! `optimise --robot ROBOT --pose X,Y,Z,RZ`: the last pass, offline
//! compensation of the optimised program for a compliant robot (paper 001,
//! process-models §4.4), written as KUKA KRL. It moves the tool tip on
//! purpose (p_cmd = p − Δp), so it runs after the checks of the optimised
//! program, on the program as written and re-read, with the loads the force
//! model found on it ([`crate::robot::move_loads`]). Its own check re-reads
//! the KRL it wrote and runs the deflection again at the commanded points
//! read: the deflected tip must land on the nominal path within the
//! tolerance.

use crate::robot::{move_loads, LoadSummary};
use millplan_nc::krl::Statement;
use millplan_nc::write::krl::{self, KrlFiles, KrlMotion, KrlOptions};
use millplan_nc::Program;
use millplan_plan::force::ForceRun;
use millplan_robot::machining::{self, Compensated, PathLoad, PathPoint, Placement};
use millplan_robot::{Robot, Variant};
use serde::Serialize;

/// The robot, where the workpiece sits and how the KRL is written.
pub struct RobotSetup {
    pub robot: Robot,
    pub variant: Variant,
    pub place: Placement,
    /// Distance between commanded points, mm.
    pub spacing: f64,
    /// Motions per sub-program (0: one file).
    pub max_points: usize,
    /// `LIN` per point or SPLINE blocks.
    pub motion: KrlMotion,
    /// How far the deflected tip may land from the nominal path, mm.
    pub tol: f64,
    /// Correct the tool's orientation too (`--orientation`).
    pub orientation: bool,
}

impl RobotSetup {
    /// The setup of `--robot` (the robot read) and `--pose X,Y,Z,RZ`: three
    /// compliant axes per frame, the paper's spacing.
    pub fn new(
        robot: Robot,
        pose: &str,
        max_points: usize,
        tol: f64,
    ) -> Result<RobotSetup, String> {
        Ok(RobotSetup {
            robot,
            variant: Variant::ThreeAxis,
            place: crate::robot::pose(pose)?,
            spacing: crate::command_defaults::robot::SPACING_MM,
            max_points,
            motion: KrlMotion::Lin,
            tol,
            orientation: false,
        })
    }
}

/// `optimise`'s KRL options without `--robot` (`robot`: whether it is
/// given): refused with the reason, for only the robot pass writes KRL.
/// `motion` is `--krl-motion` as given (`None`: not given).
pub fn krl_options(robot: bool, motion: Option<KrlMotion>) -> Result<(), String> {
    match (robot, motion) {
        (false, Some(_)) => Err("--krl-motion: optimise writes a KRL program, whose motions are LIN or SPLINE, only with --robot (the program compensated for a robot); without it the output is a program for a machine tool".into()),
        _ => Ok(()),
    }
}

/// The dialect the optimised program is written, re-read and checked in
/// before the pass when the output is KRL: KRL has no spindle speed and
/// no tool for the force model and the checks to work with, so the
/// source's own dialect (APT for a KRL source).
pub fn check_target(source: millplan_nc::ir::Dialect) -> millplan_nc::write::Target {
    use millplan_nc::write::Target;
    Target::of(source)
        .filter(|t| *t != Target::Krl)
        .unwrap_or(Target::Apt)
}

/// What the pass did, in the units of `robot compensate`: the deflection
/// |Δp| of the tool tip under the process load before compensation, and
/// after it the largest distance of the deflected tip from the path.
#[derive(Clone, Debug, Serialize)]
pub struct RobotSummary {
    /// Mean |Δp| over the points, mm (before compensation).
    pub mean_deflection_mm: f64,
    /// Largest |Δp|, mm (before compensation).
    pub max_deflection_mm: f64,
    /// The largest distance of the deflected tip from the path, commanded
    /// to the points read back from the KRL written, mm.
    pub residual_max_mm: f64,
    pub tolerance_mm: f64,
    pub points: usize,
    pub loads: Option<LoadSummary>,
    /// The tool's turn |Δθ| under the load before compensation, degrees:
    /// the largest.
    pub max_rotation_deg: f64,
    /// The largest angle between the deflected tool at the commanded
    /// points and the nominal tool, degrees: the turn itself unless
    /// `orientation`.
    pub residual_rotation_max_deg: f64,
    /// Whether the orientation was corrected (`--orientation`).
    pub orientation: bool,
}

impl RobotSummary {
    /// The rows of the report's robot section: (what, value).
    pub fn rows(&self) -> Vec<(&'static str, String)> {
        use crate::robot::sig;
        let mm = |v: f64, d: i32| format!("{} mm", sig(v, d));
        let mut rows = vec![
            ("commanded points", self.points.to_string()),
            (
                "deflection before compensation, mean |Δp|",
                mm(self.mean_deflection_mm, 4),
            ),
            (
                "deflection before compensation, max |Δp|",
                mm(self.max_deflection_mm, 4),
            ),
            (
                "after compensation (the KRL read back), max distance of the tip from the path",
                mm(self.residual_max_mm, 3),
            ),
            ("tolerance", format!("{} mm", self.tolerance_mm)),
        ];
        let deg = |v: f64| format!("{}°", sig(v, 3));
        rows.push((
            "tool turned by the load, max |Δθ|",
            deg(self.max_rotation_deg),
        ));
        let after = if self.orientation {
            "after compensation, orientation corrected: max angle to the nominal tool"
        } else {
            "after compensation, orientation not corrected: max angle to the nominal tool"
        };
        rows.push((after, deg(self.residual_rotation_max_deg)));
        if let Some(l) = &self.loads {
            rows.push(("moves under load", l.loaded_moves.to_string()));
            rows.push((
                "largest mean force of a move",
                format!("{} N", sig(l.max_mean_force_n, 4)),
            ));
        }
        rows
    }

    pub fn render_text(&self) -> String {
        use crate::robot::sig;
        format!(
            "robot: deflection mean {} mm, max {} mm over {} points; compensated, the KRL read back leaves at most {} mm (tolerance {} mm)",
            sig(self.mean_deflection_mm, 4),
            sig(self.max_deflection_mm, 4),
            self.points,
            sig(self.residual_max_mm, 3),
            self.tolerance_mm
        )
    }
}

/// The KRL files (main first) and the summary.
pub struct RobotWritten {
    pub files: KrlFiles,
    pub summary: RobotSummary,
}

/// Compensates `program` (written and re-read) under the loads of its force
/// run, writes KRL named `name`, and checks it.
/// `posted`: the program was posted to a machine's joints (refused).
pub fn run(
    s: &RobotSetup,
    (program, posted): (&Program, bool),
    forces: Option<&ForceRun>,
    name: &str,
) -> Result<RobotWritten, String> {
    if posted {
        return Err("the program was posted to a machine's joints; leave out the post pass (--passes) for a robot".into());
    }
    let forces = forces.ok_or(
        "the robot pass needs the process load along the path: give --stock and --material",
    )?;
    let load = move_loads(program, forces);
    let err = |e: machining::MachiningError| e.to_string();
    let c = machining::compensate_program_with(
        &s.robot,
        s.variant,
        program,
        &s.place,
        &load,
        s.spacing,
        s.orientation,
    )
    .map_err(err)?;
    let k = machining::krl_program(name, &c.runs, &s.place, s.spacing / 2.0);
    let o = KrlOptions {
        name: name.into(),
        max_points: s.max_points,
        motion: s.motion,
        ..KrlOptions::default()
    };
    let files = krl::write(&k, &o);
    krl::check(&k, &files)?;
    let residual = verify(s, &c, &files, &load)?;
    if !(residual <= s.tol) {
        return Err(format!(
            "the KRL written, run on the robot model, leaves the tip {residual:.4} mm from the path: over the tolerance of {} mm",
            s.tol
        ));
    }
    let summary = RobotSummary {
        mean_deflection_mm: c.mean,
        max_deflection_mm: c.max,
        residual_max_mm: residual,
        tolerance_mm: s.tol,
        points: c.points,
        loads: LoadSummary::of(&load),
        // Six digits, as `robot compensate` prints them (the JSON's
        // rounding keeps keys that name a rotation whole).
        max_rotation_deg: crate::robot::sig(c.rot_max_deg, 6),
        residual_rotation_max_deg: crate::robot::sig(c.residual_rot_max_deg, 6),
        orientation: c.orientation,
    };
    Ok(RobotWritten { files, summary })
}

/// The robot pass at the end of `optimise`, on what `Job::finish` wrote as
/// `w`: when the output is KRL the program is first written, re-read and
/// checked again in the dialect of [`check_target`] (within `limits`); then
/// compensated and written as KRL named after `output`. `w` is left with
/// the main KRL program as its bytes; the files (main first) are returned,
/// the sub-programs to be written beside `output`.
pub fn after_optimise(
    s: &RobotSetup,
    (job, outcome): (&crate::Job, &crate::Outcome),
    w: &mut crate::Written,
    output: &std::path::Path,
    limits: millplan_geom::limits::Limits,
) -> Result<RobotWritten, String> {
    let krl_name = millplan_nc::write::Target::Krl.name();
    if w.summary.dialect == krl_name {
        let t = check_target(job.inputs.program.source);
        let wo = millplan_nc::write::WriteOptions {
            limits,
            ..job.inputs.machine.write_options(t)
        };
        *w = job.finish(outcome, wo).map_err(|e| e.to_string())?;
        w.summary.dialect = krl_name.into();
    }
    let stem = krl::stem(output);
    let posted = outcome.posted.is_some();
    let done = run(s, (&w.program, posted), w.forces_after.as_ref(), &stem)
        .map_err(|e| format!("--robot: {e}"))?;
    w.bytes = done.files[0].1.clone().into_bytes();
    w.summary.robot = Some(done.summary.clone());
    Ok(done)
}

/// Reads the files back (the main finding its sub-programs among them),
/// puts every commanded point read in place of the one computed, and runs
/// the deflection again: the largest distance of the tip from the path.
fn verify(
    s: &RobotSetup,
    c: &Compensated,
    files: &KrlFiles,
    load: &PathLoad,
) -> Result<f64, String> {
    let back = millplan_nc::krl::read(&files[0].1, &mut |n| {
        files
            .iter()
            .find(|(f, _)| f.eq_ignore_ascii_case(n))
            .map(|(_, t)| t.clone())
    })
    .map_err(|e| format!("the KRL written does not read back: {e:?}"))?;
    let mut read = back.statements.iter().filter_map(|l| match &l.statement {
        Statement::Move { motion, .. } => motion.end().map(|p| p.xyz),
        _ => None,
    });
    let mut cmd: Vec<Vec<PathPoint>> = Vec::with_capacity(c.runs.len());
    for run in &c.runs {
        let mut r = Vec::with_capacity(run.len());
        for pt in run {
            let p = read
                .next()
                .ok_or("the KRL written holds fewer motions than the compensated path")?;
            r.push(PathPoint { p, ..*pt });
        }
        cmd.push(r);
    }
    if read.next().is_some() {
        return Err("the KRL written holds more motions than the compensated path".into());
    }
    machining::residual_max(&s.robot, s.variant, &s.place, c, &cmd, load).map_err(|e| e.to_string())
}
