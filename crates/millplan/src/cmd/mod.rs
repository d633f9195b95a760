//! One file per subcommand.

pub mod convert;
pub mod demo;
pub mod directions;
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

impl From<TargetArg> for millplan_nc::Dialect {
    fn from(t: TargetArg) -> Self {
        use millplan_nc::Dialect;
        match t {
            TargetArg::Fanuc => Dialect::Fanuc,
            TargetArg::Sinumerik => Dialect::Sinumerik,
            TargetArg::Heidenhain => Dialect::Heidenhain,
            TargetArg::Linuxcnc => Dialect::LinuxCnc,
            TargetArg::Apt => Dialect::AptIso,
        }
    }
}

/// Writes a program in a dialect (APT or G-code).
pub fn write_program(
    p: &millplan_nc::Program,
    dialect: millplan_nc::Dialect,
    o: millplan_nc::write::gcode::GcodeOptions,
) -> Result<Vec<u8>, millplan_nc::write::WriteError> {
    // Room for a typical block per move up front: growing an 80 MB text by
    // doubling copies it and faults in fresh pages each time.
    let moves: usize = p.operations.iter().map(|o| o.moves.len()).sum();
    let mut out = Vec::with_capacity(moves * 96 + 4096);
    write_program_to(p, dialect, o, &mut out, None)?;
    Ok(out)
}

fn write_program_to(
    p: &millplan_nc::Program,
    dialect: millplan_nc::Dialect,
    o: millplan_nc::write::gcode::GcodeOptions,
    out: &mut Vec<u8>,
    sink: Option<millplan_nc::write::Sink>,
) -> Result<(), millplan_nc::write::WriteError> {
    if dialect.is_apt() {
        millplan_nc::write::apt::write_apt_to(p, out, sink)
    } else {
        let o = millplan_nc::write::gcode::GcodeOptions { dialect, ..o };
        millplan_nc::write::gcode::write_gcode_to(p, o, out, sink)
    }
}

/// Writes a program in a dialect straight into the file `path` (atomically,
/// never over one of `inputs`), a few megabytes at a time: a large program is
/// never held whole as text.
pub fn write_program_file(
    p: &millplan_nc::Program,
    dialect: millplan_nc::Dialect,
    o: millplan_nc::write::gcode::GcodeOptions,
    path: &std::path::Path,
    inputs: &[&std::path::Path],
) -> crate::error::CliResult<()> {
    use millplan_nc::write::WriteError;
    use std::io::Write;
    let mut failed: Option<WriteError> = None;
    let written = crate::io::write_atomic_with(path, inputs, |f| {
        let mut buf = Vec::new();
        let mut io_error = None;
        let r = {
            let mut sink = |b: &[u8]| {
                f.write_all(b).map_err(|e| {
                    let message = e.to_string();
                    io_error = Some(e);
                    WriteError { message }
                })
            };
            write_program_to(p, dialect, o, &mut buf, Some(&mut sink))
        };
        match (r, io_error) {
            (Ok(()), _) => f.write_all(&buf),
            (Err(_), Some(e)) => Err(e),
            (Err(e), None) => {
                failed = Some(e);
                Err(std::io::Error::other("the program cannot be written"))
            }
        }
    });
    match failed {
        // Something the target cannot express: the user's input, not the disk.
        Some(e) => Err(crate::error::CliError::input(e.to_string())),
        None => written,
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
        eprintln!("{}:{d}", path.display());
    }
}

/// The machine from `--machine FILE`, or the built-in default.
pub fn load_machine(
    path: Option<&std::path::Path>,
) -> crate::error::CliResult<millplan_plan::machine::Machine> {
    use crate::error::CliError;
    match path {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .map_err(|e| CliError::input(format!("{}: cannot read: {e}", p.display())))?;
            millplan_plan::machine::Machine::from_toml(&text)
                .map_err(|e| CliError::input(format!("{}: {e}", p.display())))
        }
        None => Ok(millplan_plan::machine::Machine::default()),
    }
}
