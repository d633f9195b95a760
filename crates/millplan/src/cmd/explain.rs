//! `millplan explain`: what a finding's code means.

use crate::error::{CliError, CliResult, EXIT_OK};
use millplan_driver::explain as lib;

/// Explain the code of a finding (`warning[unknown-word]`): what it means and
/// what to do about it. Without a code, every code.
#[derive(clap::Args)]
pub struct Args {
    /// A code as printed: `unknown-word`, or the whole `warning[unknown-word]`.
    pub code: Option<String>,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
}

pub fn run(a: Args) -> CliResult<i32> {
    let codes = lib::codes(a.code.as_deref()).map_err(CliError::input)?;
    crate::cmd::print_summary(a.summary.json, || lib::json(&codes), || lib::text(&codes));
    Ok(EXIT_OK)
}
