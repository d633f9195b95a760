//! The safety checks of a written program (`millplan_plan::safety`) as a
//! command reports them: each refusing finding on standard error as
//! `PATH:LINE: check NAME: message`, and the run stopped (exit 3, nothing
//! written) unless `--force`.

use crate::error::{CliError, CliResult, EXIT_FINDINGS};
use millplan_nc::equiv::Tolerance;
use millplan_nc::readback::ReadBack;
use millplan_nc::write::Target;
use millplan_nc::Program;
use millplan_plan::safety::{first_refusal, passed, Check, Finding};
use std::path::Path;

/// Refusing findings printed before "and N more".
const SHOWN: usize = 20;

fn located(path: &Path, c: &Check, f: &Finding) -> String {
    let at = match f.line {
        Some(l) => format!("{}:{l}", path.display()),
        None => path.display().to_string(),
    };
    let own = if f.in_input {
        " (the input's own fault)"
    } else {
        ""
    };
    format!("{at}: check {}: {}{own}", c.name, f.message)
}

/// Whether the checks passed. A refusal is printed (lines of `path`, the
/// program the findings' lines belong to) and, without `force`, ends the
/// run with exit 3 before anything is written; with `force` the run goes on
/// and the caller writes the program and ends with exit 3.
pub fn enforce(checks: &[Check], path: &Path, force: bool) -> CliResult<bool> {
    if passed(checks) {
        return Ok(true);
    }
    let refusing: Vec<_> = checks
        .iter()
        .flat_map(|c| c.refusing().map(move |f| (c, f)))
        .collect();
    for (c, f) in refusing.iter().take(SHOWN) {
        eprintln!("{}", located(path, c, f));
    }
    if refusing.len() > SHOWN {
        eprintln!("… and {} more", refusing.len() - SHOWN);
    }
    if force {
        eprintln!("written anyway (--force)");
        return Ok(false);
    }
    let first = match first_refusal(checks) {
        Some((c, f)) => located(path, c, f),
        None => format!("{}: a check failed", path.display()),
    };
    Err(CliError {
        code: EXIT_FINDINGS,
        message: format!("{first}; nothing written (--force writes it)"),
    })
}

/// Reads `out` (the bytes written for `target` from `p`) back: bytes that
/// do not read, or do not command what `p` does, are a writer's bug and are
/// not written (exit 1), named at `output`'s line.
pub fn read_back(out: &[u8], target: Target, p: &Program, output: &Path) -> CliResult<ReadBack> {
    let back =
        millplan_nc::readback::read_back(out, target, p, &Tolerance::default()).map_err(|e| {
            CliError::internal(format!(
                "{}: the program written does not read back ({e}); not written",
                output.display()
            ))
        })?;
    if let Err(m) = &back.equiv {
        return Err(CliError::internal(format!(
            "{}:{}: the program written would not command what was made ({m}); not written",
            output.display(),
            m.line_b
        )));
    }
    Ok(back)
}
