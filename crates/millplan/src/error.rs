//! Exit codes and the error type every command returns.
//!
//! | code | meaning |
//! |---|---|
//! | 0 | success |
//! | 1 | internal failure (a bug, or the system refused: disk full, permission) |
//! | 2 | bad input or bad arguments: the message says file, line and column |
//! | 3 | the check ran and found problems (gouges, limits) |
//!
//! A failure to write standard output (a closed pipe, a full disk) turns a
//! success into 1 and leaves 3 as it is: what the check found stands.

use std::fmt;

pub const EXIT_OK: i32 = 0;
pub const EXIT_INTERNAL: i32 = 1;
pub const EXIT_BAD_INPUT: i32 = 2;
pub const EXIT_FINDINGS: i32 = 3;

/// A failure with the exit code it maps to.
#[derive(Debug)]
pub struct CliError {
    pub code: i32,
    pub message: String,
}

impl CliError {
    pub fn input(message: impl Into<String>) -> CliError {
        CliError {
            code: EXIT_BAD_INPUT,
            message: message.into(),
        }
    }

    /// What a check or the input's own content found (exit 3).
    pub fn findings(message: impl Into<String>) -> CliError {
        CliError {
            code: EXIT_FINDINGS,
            message: message.into(),
        }
    }

    pub fn internal(message: impl Into<String>) -> CliError {
        CliError {
            code: EXIT_INTERNAL,
            message: message.into(),
        }
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl From<anyhow::Error> for CliError {
    fn from(e: anyhow::Error) -> Self {
        CliError::internal(format!("{e:#}"))
    }
}

impl From<millplan_driver::watch::Stop> for CliError {
    fn from(e: millplan_driver::watch::Stop) -> Self {
        use millplan_driver::watch::Stop;
        match e {
            Stop::Io(e) => e.into(),
            Stop::Internal(m) => CliError::internal(m),
            Stop::Refused(m) => CliError::findings(m),
        }
    }
}

pub type CliResult<T> = Result<T, CliError>;

/// The exit code of a run that went to its end: 3 when it `found` problems,
/// else 0.
pub fn exit(found: bool) -> i32 {
    if found {
        EXIT_FINDINGS
    } else {
        EXIT_OK
    }
}

pub use millplan_driver::message::{escape_controls, text};

/// The stable name of an exit code in a JSON error: `usage` (arguments
/// clap refused), `bad-input`, `findings` (a check failed, or nothing to
/// act on), `internal`.
pub fn code_name(exit: i32, usage: bool) -> &'static str {
    match (exit, usage) {
        (_, true) => "usage",
        (EXIT_BAD_INPUT, _) => "bad-input",
        (EXIT_FINDINGS, _) => "findings",
        _ => "internal",
    }
}

/// An error as one line of JSON for standard error under `--json`
/// (`millplan_driver::message::json`, the code named by [`code_name`]).
pub fn json(message: &str, exit: i32, usage: bool) -> String {
    millplan_driver::message::json(message, exit, code_name(exit, usage))
}
