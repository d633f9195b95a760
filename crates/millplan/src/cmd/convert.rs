//! `millplan convert`: read a program in any supported format, write it in another.

use crate::cmd::{print_diagnostics, read_options, write_program, TargetArg, UnitArg};
use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::{read_program, write_atomic};
use millplan_nc::write::gcode::GcodeOptions;
use millplan_nc::{Dialect, LengthUnit};
use std::path::PathBuf;

/// Convert an NC program (APT/CL or G-code) to another dialect.
///
/// Moves, arcs, feeds, spindle speeds, coolant and comments are carried over;
/// post words the target does not share become comments. Arcs outside the XY/ZX/YZ
/// planes and canned cycles are written as straight lines. The output is written
/// to a temporary file and renamed, so a failed run leaves nothing behind.
#[derive(clap::Args)]
pub struct Args {
    /// Input program.
    pub input: PathBuf,
    /// Output file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Target dialect.
    #[arg(long, value_enum)]
    pub to: TargetArg,
    /// Unit of the source when the file does not say.
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    /// Unit of the output program.
    #[arg(long, value_enum, default_value = "mm")]
    pub out_units: UnitArg,
    /// Feed (mm/min) for cutting moves programmed before any feed.
    #[arg(long)]
    pub feed: Option<f64>,
    /// Write block numbers (always on for Heidenhain).
    #[arg(long)]
    pub line_numbers: bool,
    /// Do not print reader diagnostics.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(a: Args) -> CliResult<i32> {
    let parsed = read_program(&a.input, read_options(a.units, a.feed))?;
    print_diagnostics(&a.input, &parsed.diagnostics, a.quiet);
    let p = parsed.program;
    let dialect: Dialect = a.to.into();
    let mut o = GcodeOptions::new(dialect);
    o.unit = LengthUnit::from(a.out_units);
    o.line_numbers = a.line_numbers;
    let out = write_program(&p, dialect, o)
        .map_err(|e| CliError::input(format!("{}: {e}", a.input.display())))?;
    write_atomic(&a.output, &out, &[&a.input])?;
    eprintln!(
        "wrote {} ({} moves, {})",
        a.output.display(),
        p.move_count(),
        dialect.name()
    );
    Ok(EXIT_OK)
}
