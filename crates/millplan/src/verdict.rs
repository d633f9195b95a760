//! The safety checks of a written program (`millplan_plan::safety`) as a
//! command reports them: each refusing finding on standard error as
//! `PATH:LINE: check NAME: message` (`millplan_driver::checks::refusal`),
//! and the run stopped (exit 3, nothing written) unless `--force`.

use crate::error::{CliError, CliResult, EXIT_FINDINGS};
use millplan_driver::checks;
use millplan_plan::safety::Check;
use std::path::Path;

/// Whether the checks passed. A refusal is printed (lines of `path`, the
/// program the findings' lines belong to) and, without `force`, ends the
/// run with exit 3 before anything is written; with `force` the run goes on
/// and the caller writes the program and ends with exit 3.
pub fn enforce(checks: &[Check], path: &Path, force: bool) -> CliResult<bool> {
    let Some((lines, first)) = checks::refusal(checks, &path.display().to_string()) else {
        return Ok(true);
    };
    for l in lines {
        eprintln!("{l}");
    }
    if force {
        eprintln!("written anyway (--force)");
        return Ok(false);
    }
    Err(CliError {
        code: EXIT_FINDINGS,
        message: format!("{first}; nothing written (--force writes it)"),
    })
}
