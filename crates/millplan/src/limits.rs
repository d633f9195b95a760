//! The resource limits of this run, settled once from `$MILLPLAN_LIMITS`
//! and `--limit` by `millplan_driver::limits` and held for every command.

use crate::error::{CliError, CliResult};
use millplan_driver::limits::{self as lib, RunLimits};
use millplan_geom::limits::Limits;
use std::sync::OnceLock;

static RUN: OnceLock<RunLimits> = OnceLock::new();

/// The load limits of the command line (`--limit fxy=300,torque=2000`), as
/// given, in order.
pub fn loads() -> Vec<(String, String)> {
    RUN.get().map(|r| r.loads.clone()).unwrap_or_default()
}

/// The limits in force (the defaults until [`init`] ran).
pub fn get() -> Limits {
    RUN.get().map_or_else(lib::defaults, |r| r.resources)
}

/// Settles the limits from the environment and the `--limit` arguments.
pub fn init(args: &[String]) -> CliResult<()> {
    let env = std::env::var_os("MILLPLAN_LIMITS").map(|e| e.to_string_lossy().into_owned());
    let run = lib::resolve(lib::defaults(), env.as_deref(), args).map_err(CliError::input)?;
    let _ = RUN.set(run);
    Ok(())
}
