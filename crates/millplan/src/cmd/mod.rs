//! One file per subcommand.

pub mod convert;
pub mod demo;
pub mod directions;
pub mod explain;
pub mod gouge;
pub mod inspect;
pub mod raster;
pub mod reorder;
pub mod setup;
pub mod speed;
pub mod sweep;
pub mod thread;
pub mod tool;
pub mod wd;

use clap::ValueEnum;
use millplan_nc::write::{Target, WriteOptions};
use millplan_nc::{LengthUnit, ReadOptions};

/// Cutting data for the commands that evaluate spindle control along the way;
/// the defaults are the paper's test conditions.
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct CuttingData {
    /// Cutting speed, m/min.
    #[arg(long, default_value_t = 63.0)]
    pub vc: f64,
    /// Feed per tooth, mm.
    #[arg(long, default_value_t = 0.125)]
    pub fz: f64,
    /// Number of flutes.
    #[arg(long, default_value_t = 2)]
    pub flutes: u32,
    /// Stock thickness along the surface normal (finishing allowance), mm.
    #[arg(long, default_value_t = 0.3)]
    pub ap: f64,
}

impl CuttingData {
    /// Spindle-control settings for commands that read only the summary and
    /// the program (no per-point rows).
    pub fn params(&self) -> millplan_plan::speed::SpeedParams {
        let mut p = millplan_plan::speed::SpeedParams::new(self.vc, self.fz, self.flutes, self.ap);
        p.keep_rows = false;
        p
    }
}

/// Output dialect, shared by the writing commands.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum TargetArg {
    Fanuc,
    Sinumerik,
    Heidenhain,
    Linuxcnc,
    Apt,
}

impl From<TargetArg> for Target {
    fn from(t: TargetArg) -> Self {
        match t {
            TargetArg::Fanuc => Target::Fanuc,
            TargetArg::Sinumerik => Target::Sinumerik,
            TargetArg::Heidenhain => Target::Heidenhain,
            TargetArg::Linuxcnc => Target::LinuxCnc,
            TargetArg::Apt => Target::Apt,
        }
    }
}

/// The dialect an output is written in: `--to`, else the output file's
/// extension, else the source's own dialect. Never a silent default: a
/// program whose target none of these names is refused.
pub fn target_for(
    to: Option<TargetArg>,
    output: &std::path::Path,
    source: millplan_nc::Dialect,
) -> crate::error::CliResult<Target> {
    if let Some(t) = to {
        return Ok(t.into());
    }
    if let Some(t) = output
        .extension()
        .and_then(|e| e.to_str())
        .and_then(Target::from_extension)
    {
        return Ok(t);
    }
    Target::of(source).ok_or_else(|| {
        crate::error::CliError::input(format!(
            "{}: say which dialect to write with --to (the file name's extension names none)",
            output.display()
        ))
    })
}

/// Writes a program for `o.target` straight into the file `path` (atomically,
/// never over one of `inputs`), a few megabytes at a time: a large program is
/// never held whole as text. Words written as comments under `--lossy` are
/// printed as warnings located in `source`.
pub fn write_program_file(
    p: &millplan_nc::Program,
    o: WriteOptions,
    path: &std::path::Path,
    source: &std::path::Path,
    inputs: &[&std::path::Path],
    quiet: bool,
) -> crate::error::CliResult<()> {
    use millplan_nc::write::WriteError;
    use std::io::Write;
    let mut failed: Option<WriteError> = None;
    let mut warnings = Vec::new();
    let written = crate::io::write_atomic_with(path, inputs, |f| {
        let mut buf = Vec::new();
        let mut io_error = None;
        let r = {
            let mut sink = |b: &[u8]| {
                f.write_all(b).map_err(|e| {
                    let message = e.to_string();
                    io_error = Some(e);
                    WriteError::new(0, message)
                })
            };
            millplan_nc::write::write_program_to(p, o, &mut buf, Some(&mut sink))
        };
        match (r, io_error) {
            (Ok(w), _) => {
                warnings = w;
                f.write_all(&buf)
            }
            (Err(_), Some(e)) => Err(e),
            (Err(e), None) => {
                failed = Some(e);
                Err(std::io::Error::other("the program cannot be written"))
            }
        }
    });
    match failed {
        // Something the target cannot express: the user's input, not the disk.
        Some(e) => Err(crate::error::CliError::input(located(source, &e))),
        None => {
            print_diagnostics(source, &warnings, quiet);
            written
        }
    }
}

/// `file:line:col: message` for a writer's error at a source line.
fn located(source: &std::path::Path, e: &millplan_nc::write::WriteError) -> String {
    if e.line > 0 {
        format!("{}:{}:1: {}", source.display(), e.line, e.message)
    } else {
        format!("{}: {}", source.display(), e.message)
    }
}

/// Writes a program for `o.target` into memory; words written as comments
/// under `--lossy` are printed as warnings located in `source`.
pub fn write_program(
    p: &millplan_nc::Program,
    o: WriteOptions,
    source: &std::path::Path,
    quiet: bool,
) -> crate::error::CliResult<Vec<u8>> {
    let (out, warnings) = millplan_nc::write::write_program(p, o)
        .map_err(|e| crate::error::CliError::input(located(source, &e)))?;
    print_diagnostics(source, &warnings, quiet);
    Ok(out)
}

/// A pass's failure as the command reports it: the input's fault (exit 2,
/// naming the program) or a bug (exit 1).
pub fn pass_error(
    path: &std::path::Path,
    e: millplan_plan::pipeline::PassError,
) -> crate::error::CliError {
    if e.is_input() {
        crate::error::CliError::input(format!("{}: {e}", path.display()))
    } else {
        crate::error::CliError::internal(format!("{}: {e}", path.display()))
    }
}

/// Source unit override shared by the reading commands.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum UnitArg {
    Mm,
    Inch,
}

impl From<UnitArg> for LengthUnit {
    fn from(u: UnitArg) -> Self {
        match u {
            UnitArg::Mm => LengthUnit::Mm,
            UnitArg::Inch => LengthUnit::Inch,
        }
    }
}

/// Reader options from the common flags.
pub fn read_options(units: Option<UnitArg>, feed: Option<f64>) -> ReadOptions {
    let d = ReadOptions::default();
    ReadOptions {
        units: units.map(Into::into),
        default_feed: feed.unwrap_or(d.default_feed),
        ..d
    }
}

/// Prints a program's diagnostics to standard error, prefixed with the file name.
pub fn print_diagnostics(path: &std::path::Path, diags: &[millplan_nc::Diagnostic], quiet: bool) {
    if quiet {
        return;
    }
    for d in diags {
        eprintln!("{}", d.located(&path.display().to_string()));
    }
}

/// The machine from `--machine FILE` (the machine file, or either of the two
/// older single-purpose files), or the built-in default.
pub fn load_machine(
    path: Option<&std::path::Path>,
) -> crate::error::CliResult<millplan_plan::machine::Machine> {
    use crate::error::CliError;
    match path {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .map_err(|e| CliError::input(format!("{}: cannot read: {e}", p.display())))?;
            millplan_plan::machine::Machine::from_toml(&text).map_err(|e| {
                // `file:line:col: field: message` when the error has a place.
                let sep = if e.at.is_some() { ":" } else { ": " };
                CliError::input(format!("{}{sep}{e}", p.display()))
            })
        }
        None => Ok(millplan_plan::machine::Machine::default()),
    }
}
