//! Argument groups that several commands share, declared once and
//! flattened into each (`#[command(flatten)]`): the same option in the same
//! words everywhere, and what the binary does with it in one place.

use crate::cmd::UnitArg;
use crate::error::CliResult;
use std::path::Path;

/// The unit of the part's STL.
#[derive(clap::Args, Clone, Copy)]
pub struct PartUnits {
    /// Unit of the STL's numbers (an STL does not say): mm (default) or inch,
    /// converted to mm on reading.
    #[arg(long, value_enum)]
    pub stl_units: Option<UnitArg>,
}

impl PartUnits {
    /// Reads the part at `stl` (refused without a triangle), in mm.
    pub fn read(&self, stl: &Path) -> CliResult<millplan_geom::TriMesh> {
        Ok(crate::io::read_surface(stl, self.stl_units)?.0)
    }
}

/// `--json` of the commands with a machine-readable summary.
#[derive(clap::Args, Clone, Copy)]
pub struct SummaryJson {
    /// Print a machine-readable summary (JSON) on standard output; errors too,
    /// as JSON on standard error.
    #[arg(long)]
    pub json: bool,
}

impl SummaryJson {
    /// Prints `v` as JSON (numbers rounded to what they mean), else its text.
    pub fn print<T: serde::Serialize>(&self, v: &T, text: impl FnOnce(&T) -> String) {
        crate::cmd::print_summary(self.json, || v, || text(v));
    }
}

/// `-q` of the commands that warn about their inputs.
#[derive(clap::Args, Clone, Copy)]
pub struct Quiet {
    /// Print no warnings or notes about the inputs (errors still print).
    #[arg(long, short)]
    pub quiet: bool,
}

/// `--timings` of the commands that name their phases.
#[derive(clap::Args, Clone, Copy)]
pub struct Timings {
    /// Print the wall time of each phase on standard error (they add up to
    /// the whole run).
    #[arg(long = "timings")]
    pub on: bool,
}
