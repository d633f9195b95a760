//! One file per subcommand.

pub mod args;
pub mod completions;
pub mod convert;
pub mod cut;
pub mod demo;
pub mod directions;
pub mod explain;
pub mod feed;
pub mod force;
pub mod gouge;
pub mod inspect;
pub mod lobes;
pub mod optimise;
pub mod orient;
pub mod post;
pub mod raster;
pub mod reorder;
pub mod robot;
pub mod setup;
pub mod simulate;
pub mod speed;
pub mod sweep;
pub mod thread;
pub mod tool;
pub mod wd;

use crate::error::{CliError, CliResult};
use clap::ValueEnum;
use millplan_nc::write::Target;
use millplan_nc::{LengthUnit, ReadOptions};

pub use millplan_driver::check::{Range, FEED};

/// Checks a numeric argument: finite and in its range, else an error naming
/// the option, the value and the range (exit 2).
pub fn arg(flag: &str, v: f64, r: Range) -> CliResult<f64> {
    millplan_driver::check::arg(flag, v, r).map_err(CliError::input)
}

/// Cutting data for the commands that evaluate spindle control along the way;
/// the defaults are the paper's test conditions. A negative number is taken
/// as a value so that the range check, not the parser, answers it.
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct CuttingData {
    /// Cutting speed, m/min.
    #[arg(long, default_value_t = millplan_driver::command_defaults::cutting::VC, allow_negative_numbers = true)]
    pub vc: f64,
    /// Feed per tooth, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::cutting::FZ, allow_negative_numbers = true)]
    pub fz: f64,
    /// Number of flutes.
    #[arg(long, default_value_t = millplan_driver::command_defaults::cutting::FLUTES)]
    pub flutes: u32,
    /// Stock thickness along the surface normal (finishing allowance), mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::cutting::AP, allow_negative_numbers = true)]
    pub ap: f64,
}

impl CuttingData {
    /// The values, as the library takes them.
    pub fn cutting(&self) -> millplan_driver::speed::Cutting {
        millplan_driver::speed::Cutting {
            vc: self.vc,
            fz: self.fz,
            flutes: self.flutes,
            ap: self.ap,
        }
    }
}

/// Prints a JSON summary on standard output, every number rounded to what
/// it means (`round::json`).
pub fn print_json(v: serde_json::Value) {
    let v = millplan_driver::round::json(v);
    outln!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
}

/// Prints a command's summary: `json()` as [`print_json`] does when `json`,
/// else `text()`.
pub fn print_summary<T: serde::Serialize>(
    json: bool,
    j: impl FnOnce() -> T,
    text: impl FnOnce() -> String,
) {
    if json {
        print_json(serde_json::to_value(j()).unwrap_or_default());
    } else {
        out!("{}", text());
    }
}

/// Refuses `--json` with `-o -`: the program itself goes to standard output.
pub fn json_not_on_stdout(json: bool, output: &std::path::Path) -> CliResult<()> {
    if json && output.as_os_str() == "-" {
        return Err(CliError::input(
            "--json: not with -o - (the program itself goes to standard output)",
        ));
    }
    Ok(())
}

/// Output dialect, shared by the writing commands.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum TargetArg {
    Fanuc,
    Sinumerik,
    Heidenhain,
    Linuxcnc,
    Apt,
    /// KUKA KRL, a robot program (.src): one LIN per point after a PTP approach.
    Krl,
}

impl From<TargetArg> for Target {
    fn from(t: TargetArg) -> Self {
        match t {
            TargetArg::Fanuc => Target::Fanuc,
            TargetArg::Sinumerik => Target::Sinumerik,
            TargetArg::Heidenhain => Target::Heidenhain,
            TargetArg::Linuxcnc => Target::LinuxCnc,
            TargetArg::Apt => Target::Apt,
            TargetArg::Krl => Target::Krl,
        }
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

/// Reader options from the common flags, with the limits of this run.
pub fn read_options(units: Option<UnitArg>, feed: Option<f64>) -> CliResult<ReadOptions> {
    let d = ReadOptions::default();
    Ok(ReadOptions {
        units: units.map(Into::into),
        default_feed: match feed {
            Some(f) => arg("--feed", f, FEED)?,
            None => d.default_feed,
        },
        limits: crate::limits::get(),
        ..d
    })
}

/// Prints a program's diagnostics to standard error, prefixed with the file name.
pub fn print_diagnostics(path: &std::path::Path, diags: &[millplan_nc::Diagnostic], quiet: bool) {
    if quiet {
        return;
    }
    for d in diags {
        eprintln!(
            "{}",
            crate::error::text(&d.located(&path.display().to_string()))
        );
    }
}

/// The machine from `--machine FILE` (the machine file, or either of the two
/// older single-purpose files), or the built-in default.
pub fn load_machine(
    path: Option<&std::path::Path>,
) -> crate::error::CliResult<millplan_plan::machine::Machine> {
    Ok(millplan_driver::io::inputs::read_machine(path)?)
}
