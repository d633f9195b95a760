//! `millplan thread`: ISO metric thread checks.

use crate::error::{exit, CliError, CliResult, EXIT_OK};
use clap::Subcommand;
use millplan_driver::thread as lib;

/// ISO metric threads: limits of size of a tolerance class and whether a
/// measured pitch diameter is within it (ISO 965-1 tables).
///
/// Classes: G, H (internal) and g, h (external), grades 4 to 8 where the
/// tables have a value confirmed by two public sources; a two-grade class
/// such as 4H5H or 5g6g names the pitch-diameter tolerance first and the
/// crest-diameter tolerance second.
///
/// Exit codes: 0 within the class (OK); 2 bad arguments (a thread or class the
/// tables cannot tolerance, with the reason; a D2 that is not a positive
/// number); 3 out of the class (REJECT).
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
        /// Tolerance class, e.g. 6H, 5H, 6G, 4H5H (internal) or 6g, 4h, 4g6g
        /// (external).
        #[arg(long)]
        class: String,
        /// Measured pitch diameter, mm.
        #[arg(long)]
        d2: f64,
        /// Print the result as JSON on standard output (the key `ok`).
        #[arg(long)]
        json: bool,
    },
    /// Print the limits of size of a thread in a class: pitch diameter, minor
    /// (internal) or major (external) diameter, the fundamental deviation and
    /// the tolerances used.
    Limits {
        /// Thread, e.g. M10x1.5.
        thread: String,
        /// Tolerance class, e.g. 6H, 5H, 6G, 4H5H (internal) or 6g, 4h, 4g6g
        /// (external).
        #[arg(long)]
        class: String,
        /// Print the limits as JSON on standard output.
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
            let c = lib::check_d2(&thread, &class, d2).map_err(CliError::input)?;
            let text = || format!("{}\n", c.render_text(&thread, &class));
            crate::cmd::print_summary(json, || &c, text);
            Ok(exit(!c.ok))
        }
        ThreadCommand::Limits {
            thread,
            class,
            json,
        } => {
            let l = lib::limits(&thread, &class).map_err(CliError::input)?;
            crate::cmd::print_summary(json, || &l, || format!("{}\n", l.render_text()));
            Ok(EXIT_OK)
        }
    }
}
