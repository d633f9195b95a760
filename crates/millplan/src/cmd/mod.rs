//! One file per subcommand.

pub mod convert;
pub mod demo;
pub mod directions;
pub mod inspect;
pub mod speed;
pub mod sweep;
pub mod wd;

use clap::ValueEnum;
use millplan_nc::{LengthUnit, ReadOptions};

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
