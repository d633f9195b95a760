//! `millplan convert`: read a program in any supported format, write it in another.

use crate::cmd::{print_diagnostics, read_options, target_for, write_program, TargetArg, UnitArg};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::Outputs;
use millplan_nc::equiv::Tolerance;
use millplan_nc::readback::read_back;
use millplan_nc::write::krl::{KrlFiles, KrlMotion};
use millplan_nc::write::{self, Target};
use millplan_nc::LengthUnit;
use millplan_plan::orient::ResolveOrientation;
use millplan_plan::pipeline::{self, Context};
use std::path::PathBuf;

/// Convert an NC program (APT/CL, G-code or KUKA KRL) to another dialect.
///
/// Every block of the output means what its source block meant: moves, arcs,
/// feeds and feed modes (G93/G94/G95), spindle, coolant, tool-length and
/// cutter compensation, work offsets and comments are carried over; an axis
/// the source never set is never written; words the source dialect keeps
/// verbatim are copied into the same dialect, and a word another dialect
/// cannot express stops the conversion at its line (--lossy: a comment and a
/// warning instead, exit 3 when the output commands less than the source). Arcs outside the XY/ZX/YZ planes and canned cycles are
/// written as straight lines. A KRL program (.src) is read with the
/// sub-programs its main calls from beside it (a missing one named with its
/// calling line); KRL to KRL keeps the poses, external axes and speeds as
/// read, in one file; into another dialect the orientation A, B, C becomes
/// a tool axis and an external axis (E1..E6) stops the conversion at its
/// line (--lossy: dropped with a warning). The output is written to a temporary file and
/// renamed, so a failed run leaves nothing behind.
#[derive(clap::Args)]
pub struct Args {
    /// Input program.
    pub input: PathBuf,
    /// Output file (`-`: standard output).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Target dialect; default: from the output's extension (.nc Fanuc, .mpf
    /// Sinumerik, .h Heidenhain, .ngc LinuxCNC, .apt/.cls APT, .src KRL),
    /// else the input's own.
    #[arg(long, value_enum)]
    pub to: Option<TargetArg>,
    /// Unit of the source when the file does not say.
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    /// Unit of the output program (default: the unit of the source, so that
    /// words copied as written keep their meaning).
    #[arg(long, value_enum)]
    pub out_units: Option<UnitArg>,
    /// Feed (mm/min) for cutting moves programmed before any feed.
    #[arg(long)]
    pub feed: Option<f64>,
    /// Write block numbers (always on for Heidenhain).
    #[arg(long)]
    pub line_numbers: bool,
    /// Write words the target cannot express as comments (a warning each)
    /// instead of refusing the conversion; exit 3 when the output then
    /// commands less than the source.
    #[arg(long)]
    pub lossy: bool,
    /// Machine file (examples/machine.toml): its control's dialect is the
    /// default target and its S-word decimals are used; with a `[kinematics]`
    /// table, rotary angles become tool axes (so five-axis G-code can be
    /// written as APT).
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// With a KRL output: at most this many motions a file. A longer
    /// program becomes a main program (at -o) calling sub-programs of N
    /// motions each, written beside it as NAME_001.src, NAME_002.src, …
    /// (NAME from the output's file name), as a controller loads them. 0:
    /// one file, as without the option.
    #[arg(long, value_name = "N")]
    pub max_points: Option<usize>,
    /// With a KRL output: each point one LIN as read or written, or each run of approximated LINs one SPLINE block of SPL points.
    #[arg(long, default_value = "lin", value_name = "lin|spline")]
    pub krl_motion: KrlMotion,
    /// Do not print reader diagnostics.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print a machine-readable summary (JSON) on standard output (not with -o -); errors too,
    /// as JSON on standard error.
    #[arg(long)]
    pub json: bool,
}

/// Reads the output back and runs it and its source through the same
/// interpreter: a program that would command something else is not written
/// (with --lossy, where words were dropped on purpose, it is, with a warning,
/// and the run ends with exit 3). Returns whether the output is equivalent.
fn check_output(p: &millplan_nc::Program, out: &[u8], target: Target, a: &Args) -> CliResult<bool> {
    let back = read_back(out, target, p, &Tolerance::default()).map_err(|e| {
        CliError::internal(format!(
            "{}: the program written does not read back ({e}); not written",
            a.output.display()
        ))
    })?;
    match back.equiv {
        Ok(_) => Ok(true),
        Err(m) if a.lossy => {
            // Said even with --quiet: the exit code alone does not say why.
            eprintln!(
                "{}: warning: written with --lossy, the output does not command what the source does ({m})",
                a.output.display()
            );
            Ok(false)
        }
        Err(m) => Err(CliError::internal(format!(
            "{}:{}: the output would not command what the source does ({m}); not written",
            a.input.display(),
            m.line_a
        ))),
    }
}

/// The KRL output `out` split into a main program and sub-programs of
/// `--max-points` motions, SPLINE blocks with `--krl-motion spline`
/// (checked: they read back to its motions), when asked for; `None` to
/// write `out` as it is.
fn krl_files(a: &Args, target: Target, out: &[u8]) -> CliResult<Option<KrlFiles>> {
    let n = a.max_points.unwrap_or_default();
    if n == 0 && a.krl_motion == KrlMotion::Lin {
        return Ok(None);
    }
    if target != Target::Krl {
        return Err(CliError::input(
            "--max-points, --krl-motion: sub-programs and SPLINE blocks are KRL's; give --to krl or an output named .src",
        ));
    }
    if a.output.as_os_str() == "-" {
        return Err(CliError::input(
            "--max-points, --krl-motion: KRL files are staged beside the main program; name the output file",
        ));
    }
    let o = write::krl::KrlOptions {
        name: write::krl::stem(&a.output),
        max_points: n,
        motion: a.krl_motion,
        ..Default::default()
    };
    let text = String::from_utf8_lossy(out);
    write::krl::split(&text, &o)
        .map(Some)
        .map_err(|e| CliError::internal(format!("{}: {e}; not written", a.output.display())))
}

/// Writes `out` at -o, or with --max-points its KRL split (a main program
/// and sub-programs beside it).
fn write_out(
    a: &Args,
    inputs: &[&std::path::Path],
    mut outputs: Outputs,
    target: Target,
    out: &[u8],
) -> CliResult<()> {
    match krl_files(a, target, out)? {
        Some(files) => crate::cmd::robot::stage_krl(inputs, &a.output, &files, 0)?
            .0
            .commit(),
        None => {
            outputs.write(&a.output, out)?;
            outputs.commit()
        }
    }
}

/// The reader's warnings (an `S0` before a cut, words not understood), each
/// at its place, for `--json`.
fn json_warnings(input: &std::path::Path, d: &[millplan_nc::Diagnostic]) -> Vec<String> {
    let file = input.display().to_string();
    d.iter()
        .filter(|d| d.severity == millplan_nc::diag::Severity::Warning)
        .map(|d| d.located(&file))
        .collect()
}

pub fn run(a: Args) -> CliResult<i32> {
    if a.json && a.output.as_os_str() == "-" {
        return Err(CliError::input(
            "--json: not with -o - (the program itself goes to standard output)",
        ));
    }
    let inputs: Vec<&std::path::Path> = [Some(a.input.as_path()), a.machine.as_deref()]
        .into_iter()
        .flatten()
        .collect();
    let outputs = Outputs::plan(&inputs, &[("-o", Some(&a.output))], true)?;
    let (parsed, krl) = crate::io::read_source(&a.input, read_options(a.units, a.feed)?)?;
    print_diagnostics(&a.input, &parsed.diagnostics, a.quiet);
    let warnings = json_warnings(&a.input, &parsed.diagnostics);
    let mut p = parsed.program;
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    let to = a.to.map(Into::into).or(machine.target());
    let target = match to {
        Some(t) => t,
        None => target_for(None, &a.output, p.source)?,
    };
    if let Some(k) = machine.kinematics() {
        let cx = Context::new(machine.clone());
        let mut pass = ResolveOrientation::new(k.clone());
        pipeline::run(&mut [&mut pass], &mut p, &cx)
            .map_err(|e| crate::cmd::pass_error(&a.input, e))?;
    }
    let mut o = machine.write_options(target);
    o.unit = a.out_units.map(LengthUnit::from);
    o.line_numbers = a.line_numbers;
    o.lossy = a.lossy;
    let out = match krl
        .as_ref()
        .map(|k| write::krl::from_krl(k, target, a.lossy))
    {
        Some(Ok(Some(text))) => text.into_bytes(),
        Some(Err(e)) => return Err(crate::io::krl_error(&a.input, e)),
        _ => write_program(&p, o, &a.input, a.quiet)?,
    };
    let equivalent = check_output(&p, &out, target, &a)?;
    write_out(&a, &inputs, outputs, target, &out)?;
    if a.json {
        outln!(
            "{}",
            serde_json::json!({
                "input": a.input.display().to_string(),
                "output": a.output.display().to_string(),
                "target": target.name(),
                "moves": p.move_count(),
                "equivalent": equivalent,
                "warnings": warnings,
            })
        );
    } else {
        let (path, moves) = (a.output.display(), p.move_count());
        eprintln!("wrote {path} ({moves} moves, {})", target.name());
    }
    Ok(if equivalent { EXIT_OK } else { EXIT_FINDINGS })
}
