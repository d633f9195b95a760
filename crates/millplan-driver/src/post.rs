//! `millplan post`: the post's options from the command line and the machine
//! file, the output dialect, the written program read back, the checks of
//! the posted tips, and the typed summary with its text.

use crate::check::{arg, Range};
use millplan_nc::equiv::Tolerance;
use millplan_nc::readback::read_back_with;
use millplan_nc::write::Target;
use millplan_nc::Program;
use millplan_plan::machine::Machine;
use millplan_plan::post::{AxisRange, Flip, PostError, PostOptions, PostReport};
use millplan_plan::safety::{self, Check, Inputs, TipRule, Tolerances};
use millplan_report::html::Verdict;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

mod command;
pub use command::{command, PostCommand, PostRun};

/// The options of `millplan post` that shape the post.
#[derive(Clone, Copy, Debug)]
pub struct PostRequest {
    /// Tolerance of the tip off the CL segment and of arcs' chords, mm.
    pub tol: f64,
    pub tcp: bool,
    pub g93: bool,
    /// Degrees; None: the machine file's `[post] pole_cone`.
    pub pole_cone: Option<f64>,
    /// Degrees; None: the machine file's `[post] pole_tol`.
    pub pole_tol: Option<f64>,
    /// mm; None: the machine file's `[post] clearance`.
    pub clearance: Option<f64>,
}

/// The post's options: the command line's, else the machine file's `[post]`.
pub fn options(r: &PostRequest, m: &Machine) -> Result<PostOptions, String> {
    Ok(PostOptions {
        tol: arg("--tol", r.tol, Range::positive(10.0, "mm"))?,
        tcp: r.tcp,
        g93: r.g93,
        pole_cone: arg(
            "--pole-cone",
            r.pole_cone.unwrap_or(m.post.pole_cone),
            Range::from(0.0, 30.0, "degrees"),
        )?,
        pole_tol: arg(
            "--pole-tol",
            r.pole_tol.unwrap_or(m.post.pole_tol),
            Range::from(0.0, 180.0, "degrees"),
        )?,
        clearance: arg(
            "--clearance",
            r.clearance.unwrap_or(m.post.clearance),
            Range::positive(10_000.0, "mm"),
        )?,
    })
}

/// The dialect of a posted program: `to`, else the machine file's control,
/// else `output`'s extension; G-code only. The machine (its file at
/// `machine_path`) must have kinematics.
pub fn target(
    to: Option<Target>,
    output: &Path,
    machine: &Machine,
    machine_path: &Path,
) -> Result<Target, String> {
    if machine.kinematics().is_none() {
        return Err(format!(
            "{}: no [kinematics] table: a five-axis post needs the machine's rotary axes",
            machine_path.display()
        ));
    }
    let target = match to.or(machine.target()) {
        Some(t) => t,
        None => crate::target::output_target(None, output, None, millplan_nc::Dialect::Generated)?,
    };
    if !target.is_gcode() {
        return Err("--to apt: a posted program is G-code".into());
    }
    Ok(target)
}

/// A post error located in the CL file at `path`: whether it is a check's
/// finding (else the input's fault), and its message.
pub fn error(path: &str, e: &PostError) -> (bool, String) {
    let message = if e.line() == 0 {
        format!("{path}: {e}")
    } else {
        format!("{path}:{e}")
    };
    if e.is_check() {
        (true, format!("{message}; nothing written"))
    } else {
        (false, message)
    }
}

/// Reads the written program `out` back as it was written (`wo`: its
/// dialect, and G93 F as seconds where the machine's control reads them so):
/// it must command what the posted IR does (`tol` the post's tolerance;
/// `output` and `input` the files' names in the message). An error here is
/// a bug, not the user's.
pub fn read_back_check(
    posted: &Program,
    out: &[u8],
    wo: &millplan_nc::write::WriteOptions,
    tol: f64,
    (output, input): (&str, &str),
) -> Result<(), String> {
    let tol = read_back_tolerance(tol);
    let back = read_back_with(out, wo.target, posted, &tol, wo.g93_seconds);
    read_back_verdict(back, (output, input))
}

/// The tolerance the posted program is read back within, for the post's
/// `tol`.
pub fn read_back_tolerance(tol: f64) -> Tolerance {
    Tolerance {
        position: tol.max(Tolerance::default().position),
        ..Tolerance::default()
    }
}

/// What reading the posted program back gave, as the post stops on it.
pub fn read_back_verdict(
    back: Result<millplan_nc::readback::ReadBack, millplan_nc::ParseError>,
    (output, input): (&str, &str),
) -> Result<(), String> {
    let back = back.map_err(|e| {
        format!("{output}: the posted program does not read back ({e}); not written")
    })?;
    back.equiv.map_err(|m| {
        format!(
            "{input}:{}: the posted program would not command what the post made ({m}); not written",
            m.line_a
        )
    })?;
    Ok(())
}

/// The posted program against the CL file: the IR verifier, S and F within
/// the machine, and every posted tip (through the machine's forward
/// kinematics, or as written under TCP) on the CL path within `tol`.
pub fn check_posted(cl: &Program, posted: &Program, machine: &Machine, tol: f64) -> Vec<Check> {
    let Some(kin) = machine.kinematics() else {
        return Vec::new();
    };
    safety::check(&Inputs {
        input: cl,
        output: posted,
        part: None,
        stock: None,
        tool_body: &|_| None,
        machine: Some(machine),
        tip: TipRule::MovedBy(kin),
        tol: Tolerances {
            tip: tol,
            ..Tolerances::default()
        },
        loads: None,
    })
}

/// What `post --json` prints.
#[derive(Serialize)]
pub struct PostSummary<'a> {
    pub input: String,
    pub output: String,
    pub machine: &'a str,
    pub target: &'static str,
    pub mode: &'static str,
    pub feed_mode: &'static str,
    pub tol_mm: f64,
    pub pole_cone_deg: f64,
    pub blocks: usize,
    pub flips: usize,
    pub flip_list: &'a [Flip],
    pub pole_blocks: usize,
    pub pole_flagged: &'a [u32],
    pub max_orientation_deviation_deg: f64,
    pub inserted_points: usize,
    pub arc_points: usize,
    pub flip_moves: usize,
    pub slowed_blocks: usize,
    pub null_moves: usize,
    pub g93_blocks: usize,
    pub max_tip_error_mm: f64,
    pub time_s: f64,
    pub nominal_s: f64,
    pub time_g93_s: f64,
    pub time_g94_s: f64,
    pub nominal_g93_s: f64,
    pub nominal_g94_s: f64,
    pub rotary: &'a [AxisRange],
    pub checks: &'a [Check],
    /// The verdict by the one rule: red when a check of the posted program
    /// failed (written only under `--force`), amber when blocks near the
    /// pole deviate beyond the pole tolerance, green otherwise.
    pub verdict: Verdict,
    #[serde(skip)]
    report: &'a PostReport,
}

/// The verdict of a post: its checks, and the pole blocks whose
/// orientation deviates beyond `pole_tol` degrees as a warning.
pub fn verdict(r: &PostReport, checks: &[Check], pole_tol: f64) -> Verdict {
    let mut warnings = Vec::new();
    if let Some(first) = r.pole_flagged.first() {
        warnings.push(format!(
            "{} blocks near the pole deviate in orientation by more than {pole_tol}° (the first at line {first}; largest {:.3}°)",
            r.pole_flagged.len(),
            r.max_orientation_deviation_deg
        ));
    }
    let e = millplan_report::html::Evidence {
        failed: millplan_report::html::failed_checks(checks),
        ..Default::default()
    };
    Verdict::of(&e, warnings)
}

impl<'a> PostSummary<'a> {
    /// The summary of a post of `input` to `output` (`o` its options, `r`
    /// its report, `checks` those of what it wrote).
    pub fn new(
        (input, output): (&Path, &Path),
        o: &PostOptions,
        machine: &'a Machine,
        target: Target,
        r: &'a PostReport,
        checks: &'a [Check],
    ) -> Self {
        PostSummary {
            input: input.display().to_string(),
            output: output.display().to_string(),
            machine: &machine.name,
            target: target.name(),
            mode: if o.tcp { "tcp" } else { "machine" },
            feed_mode: if o.g93 { "g93" } else { "g94" },
            tol_mm: o.tol,
            pole_cone_deg: o.pole_cone,
            blocks: r.blocks,
            flips: r.flips.len(),
            flip_list: &r.flips,
            pole_blocks: r.pole_blocks,
            pole_flagged: &r.pole_flagged,
            max_orientation_deviation_deg: r.max_orientation_deviation_deg,
            inserted_points: r.inserted_points,
            arc_points: r.arc_points,
            flip_moves: r.flip_moves,
            slowed_blocks: r.slowed_blocks,
            null_moves: r.null_moves,
            g93_blocks: r.g93_blocks,
            max_tip_error_mm: r.max_tip_error_mm,
            time_s: r.time_s,
            nominal_s: r.nominal_s,
            time_g93_s: r.time_g93_s,
            time_g94_s: r.time_g94_s,
            nominal_g93_s: r.nominal_g93_s,
            nominal_g94_s: r.nominal_g94_s,
            rotary: &r.rotary,
            checks,
            verdict: verdict(r, checks, o.pole_tol),
            report: r,
        }
    }

    /// The line on standard error that says what was written.
    pub fn wrote(&self) -> String {
        format!(
            "wrote {} ({} blocks, {}, {}, {})",
            self.output, self.blocks, self.target, self.mode, self.feed_mode
        )
    }

    /// The rotary axes' use, flips, pole blocks, inserted points and times.
    pub fn render_text(&self) -> String {
        let r = self.report;
        let lim = |v: Option<f64>| v.map_or("unlimited".to_string(), |v| format!("{v:.1}"));
        let rows: Vec<String> = r
            .rotary
            .iter()
            .map(|ax| match (ax.min, ax.max) {
                (Some(lo), Some(hi)) => format!(
                    "  {}  used {lo:.3} .. {hi:.3} deg   travel {} .. {}",
                    ax.axis,
                    lim(ax.limit_min),
                    lim(ax.limit_max)
                ),
                _ => format!("  {}  not moved", ax.axis),
            })
            .collect();
        let mut o = String::new();
        let _ = writeln!(o, "rotary axes:\n{}", rows.join("\n"));
        let _ = writeln!(
            o,
            "branch flips {} (across rapids), pole blocks {} ({} beyond --pole-tol), max orientation deviation {:.4} deg",
            r.flips.len(),
            r.pole_blocks,
            r.pole_flagged.len(),
            r.max_orientation_deviation_deg
        );
        let _ = writeln!(
            o,
            "points inserted {} (linearisation), {} from arcs; blocks slowed {}",
            r.inserted_points, r.arc_points, r.slowed_blocks
        );
        let _ = writeln!(
            o,
            "time {:.1} s estimated ({:.1} s nominal); at the CL tip feed (G93) {:.1} s, a plain G94 post {:.1} s",
            r.time_s, r.nominal_s, r.time_g93_s, r.time_g94_s
        );
        o.push_str(&self.verdict.text());
        o
    }
}

/// The writer's options for a posted program: the machine's for `target`,
/// TCP switched only by the post's own events (it states TCP itself, per
/// operation, when asked for it).
pub fn write_options(
    machine: &millplan_plan::machine::Machine,
    target: millplan_nc::write::Target,
) -> millplan_nc::write::WriteOptions {
    millplan_nc::write::WriteOptions {
        auto_tcp: false,
        ..machine.write_options(target)
    }
}
