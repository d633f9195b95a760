//! `millplan thread`: ISO metric thread checks.

use crate::cmd::tool::print;
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use clap::Subcommand;
use millplan_tooldb::thread::{check, parse_designation, pitch_diameter};
use serde_json::json;

/// ISO metric threads: is a measured pitch diameter within its tolerance class
/// (ISO 965-1 tabulated limits)?
///
/// Exit codes: 0 within the class (OK); 2 bad arguments (a thread or class not
/// in the table, a D2 that is not a positive number); 3 out of the class
/// (REJECT).
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    pub command: ThreadCommand,
}

#[derive(Subcommand)]
pub enum ThreadCommand {
    /// Check a measured pitch diameter D2 against the class limits.
    ///
    /// Prints OK or REJECT (under the minimum / over the maximum, by how much);
    /// with --json the key `ok`. Exit 0 for OK, 3 for REJECT.
    Check {
        /// Thread, e.g. M20x1.
        thread: String,
        /// Tolerance class, e.g. 6H (internal) or 6g (external).
        #[arg(long)]
        class: String,
        /// Measured pitch diameter, mm.
        #[arg(long)]
        d2: f64,
        /// Print the result as JSON on standard output (the key `ok`).
        #[arg(long)]
        json: bool,
    },
}

pub fn run(a: Args) -> CliResult<i32> {
    match a.command {
        ThreadCommand::Check {
            thread,
            class,
            d2,
            json,
        } => {
            let c = check(&thread, &class, d2).map_err(|e| CliError::input(e.to_string()))?;
            let (d, p) = parse_designation(&thread).map_err(|e| CliError::input(e.to_string()))?;
            let verdict = if c.ok {
                "OK".to_string()
            } else if d2 < c.min {
                format!("REJECT: {:.3} mm under the minimum", c.min - d2)
            } else {
                format!("REJECT: {:.3} mm over the maximum", d2 - c.max)
            };
            print(
                json,
                json!({ "ok": c.ok, "min": c.min, "max": c.max, "d2": d2, "basic_d2": pitch_diameter(d, p) }),
                format!(
                    "{thread}-{class}: D2 {d2:.3} mm, limits {:.3} … {:.3} mm (basic {:.3}): {verdict}",
                    c.min,
                    c.max,
                    pitch_diameter(d, p)
                ),
            )?;
            Ok(if c.ok { EXIT_OK } else { EXIT_FINDINGS })
        }
    }
}
