//! `millplan convert`: the dialect written, the program resolved through a
//! machine's kinematics, the written bytes read back and compared with the
//! program, KRL split into sub-programs, and the typed summary.

use millplan_nc::diag::Severity;
use millplan_nc::write::krl::{self, KrlFiles};
use millplan_nc::write::{Target, WriteOptions};
use millplan_nc::{Diagnostic, Dialect, LengthUnit, Program};
use millplan_plan::machine::Machine;
use millplan_plan::orient::ResolveOrientation;
use millplan_plan::pipeline::{self, Context, PassError};
use serde::Serialize;
use std::path::Path;

mod command;
pub use command::{command, ConvertCommand, Converted};

/// The options of `convert` that shape what is written.
#[derive(Clone, Copy, Debug)]
pub struct ConvertRequest {
    /// `--to`.
    pub to: Option<Target>,
    /// `--out-units`.
    pub unit: Option<LengthUnit>,
    pub line_numbers: bool,
    pub lossy: bool,
    /// `--max-points`: motions per KRL sub-program (0 or none: one file).
    pub max_points: Option<usize>,
    /// `--krl-motion`: each point one LIN, or runs as SPLINE blocks (none
    /// given: LIN).
    pub motion: Option<krl::KrlMotion>,
}

/// The dialect to write: `--to`, else the machine file's control, else the
/// output's name, else the source's own dialect.
pub fn target(
    r: &ConvertRequest,
    machine: &Machine,
    output: &Path,
    source: Dialect,
) -> Result<Target, String> {
    match r.to.or(machine.target()) {
        Some(t) => Ok(t),
        None => crate::target::output_target(None, output, None, source),
    }
}

/// The program's rotary angles resolved to tool axes through the machine's
/// kinematics (nothing without kinematics).
pub fn resolve(p: &mut Program, machine: &Machine) -> Result<(), PassError> {
    if let Some(k) = machine.kinematics() {
        let cx = Context::new(machine.clone());
        let mut pass = ResolveOrientation::new(k.clone());
        pipeline::run(&mut [&mut pass], p, &cx)?;
    }
    Ok(())
}

/// The writer's options: the machine's for `target`, with the request's
/// unit, line numbers and `--lossy`.
pub fn write_options(r: &ConvertRequest, machine: &Machine, target: Target) -> WriteOptions {
    let mut o = machine.write_options(target);
    o.unit = r.unit;
    o.line_numbers = r.line_numbers;
    o.lossy = r.lossy;
    o
}

/// Whether the bytes `out` written for `target` from `p` command what `p`
/// does. Bytes that do not read back, or (without `--lossy`) do not
/// command the same, are an error (a writer's bug: nothing is written);
/// under `--lossy` a difference is the warning returned. `input` and
/// `output` name the files in the messages.
pub fn check_output(
    p: &Program,
    out: &[u8],
    target: Target,
    lossy: bool,
    (input, output): (&str, &str),
) -> Result<Option<String>, String> {
    let tol = millplan_nc::equiv::Tolerance::default();
    let back = millplan_nc::readback::read_back(out, target, p, &tol).map_err(|e| {
        format!("{output}: the program written does not read back ({e}); not written")
    })?;
    match back.equiv {
        Ok(_) => Ok(None),
        Err(m) if lossy => Ok(Some(format!(
            "{output}: warning: written with --lossy, the output does not command what the source does ({m})"
        ))),
        Err(m) => Err(format!(
            "{input}:{}: the output would not command what the source does ({m}); not written",
            m.line_a
        )),
    }
}

/// Why KRL sub-programs cannot be made.
#[derive(Debug)]
pub enum SplitError {
    /// `--max-points` with an output that cannot take them.
    Option(String),
    /// The written program does not split (a writer's bug).
    Split(String),
}

/// The KRL output `out` (written for `output`) split into a main program
/// and sub-programs of `--max-points` motions, SPLINE blocks with
/// `--krl-motion spline` (checked: they read back to its motions), when
/// asked for; `None` to write `out` as it is.
pub fn krl_files(
    r: &ConvertRequest,
    target: Target,
    output: &Path,
    out: &[u8],
) -> Result<Option<KrlFiles>, SplitError> {
    if target != Target::Krl {
        return match krl_only_given(r) {
            Some(opt) => Err(SplitError::Option(format!(
                "{opt}: only a KRL program has sub-programs and LIN or SPLINE motions, and the output is {} (give --to krl or an output named .src, or leave {opt} out)",
                target.name()
            ))),
            None => Ok(None),
        };
    }
    let n = r.max_points.unwrap_or_default();
    let motion = r.motion.unwrap_or_default();
    if n == 0 && motion == krl::KrlMotion::Lin {
        return Ok(None);
    }
    if output.as_os_str() == "-" {
        return Err(SplitError::Option(
            "--max-points, --krl-motion: KRL files are staged beside the main program; name the output file".into(),
        ));
    }
    let o = krl::KrlOptions {
        name: krl::stem(output),
        max_points: n,
        motion,
        ..Default::default()
    };
    krl::split(&String::from_utf8_lossy(out), &o)
        .map(Some)
        .map_err(|e| SplitError::Split(format!("{}: {e}; not written", output.display())))
}

/// The KRL-only options given (`--max-points`, `--krl-motion`), named as
/// the command line spells them; `None` when neither is.
fn krl_only_given(r: &ConvertRequest) -> Option<&'static str> {
    match (r.max_points.is_some(), r.motion.is_some()) {
        (true, true) => Some("--max-points, --krl-motion"),
        (true, false) => Some("--max-points"),
        (false, true) => Some("--krl-motion"),
        (false, false) => None,
    }
}

/// What `convert --json` prints.
#[derive(Debug, Serialize)]
pub struct ConvertSummary {
    /// Whether the output commands what the source does.
    pub equivalent: bool,
    pub input: String,
    pub moves: usize,
    pub output: String,
    /// The dialect written.
    pub target: &'static str,
    /// The reader's warnings on the source, located.
    pub warnings: Vec<String>,
}

impl ConvertSummary {
    /// The summary of `p` read from `input` (with the reader's findings
    /// `found`) and written to `output` for `target`.
    pub fn new(
        (input, found): (&str, &[Diagnostic]),
        p: &Program,
        (output, target): (&str, Target),
        equivalent: bool,
    ) -> ConvertSummary {
        ConvertSummary {
            equivalent,
            input: input.to_string(),
            moves: p.move_count(),
            output: output.to_string(),
            target: target.name(),
            warnings: found
                .iter()
                .filter(|d| d.severity == Severity::Warning)
                .map(|d| d.located(input))
                .collect(),
        }
    }

    /// The line on standard error without `--json`.
    pub fn text(&self) -> String {
        format!(
            "wrote {} ({} moves, {})",
            self.output, self.moves, self.target
        )
    }
}
