//! `millplan thread`: ISO metric thread checks.

use crate::cmd::tool::print;
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use clap::Subcommand;
use millplan_tooldb::thread::{check, class_limits, parse_designation, pitch_diameter};
use serde_json::json;

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
        } => run_check(&thread, &class, d2, json),
        ThreadCommand::Limits {
            thread,
            class,
            json,
        } => run_limits(&thread, &class, json),
    }
}

/// `thread check`: OK (exit 0) or REJECT (exit 3).
fn run_check(thread: &str, class: &str, d2: f64, json: bool) -> CliResult<i32> {
    let c = check(thread, class, d2).map_err(|e| CliError::input(e.to_string()))?;
    let (d, p) = parse_designation(thread).map_err(|e| CliError::input(e.to_string()))?;
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

/// `thread limits`: the limits of size of a class.
fn run_limits(thread: &str, class: &str, json: bool) -> CliResult<i32> {
    let l = class_limits(thread, class).map_err(|e| CliError::input(e.to_string()))?;
    let (d, p) = parse_designation(thread).map_err(|e| CliError::input(e.to_string()))?;
    let (pitch_name, crest_name, t2, tc) = if l.internal {
        ("D2", "D1", "T_D2", "T_D1")
    } else {
        ("d2", "d", "T_d2", "T_d")
    };
    let range = |r: Option<(f64, f64)>| r.map(|(min, max)| json!({ "min": min, "max": max }));
    let mut text = vec![
        format!(
            "{thread}-{class} ({}), ISO 965-1: {} {} µm",
            if l.internal { "internal" } else { "external" },
            if l.internal { "EI" } else { "es" },
            match l.fundamental_deviation_um {
                0 => "0".to_string(),
                v => format!("{v:+}"),
            }
        ),
        format!(
            "  pitch diameter {pitch_name} {:.3} … {:.3} mm ({t2} {} µm, basic {:.3})",
            l.pitch.0,
            l.pitch.1,
            l.pitch_tolerance_um,
            pitch_diameter(d, p)
        ),
    ];
    let crest_label = if l.internal { "minor" } else { "major" };
    text.push(match (l.crest, l.crest_tolerance_um) {
        (Some((lo, hi)), Some(t)) => {
            format!("  {crest_label} diameter {crest_name} {lo:.3} … {hi:.3} mm ({tc} {t} µm)")
        }
        _ => format!(
            "  {crest_label} diameter {crest_name}: not given ({})",
            l.crest_missing.clone().unwrap_or_default()
        ),
    });
    if let Some(m) = l.major_min {
        text.push(format!("  major diameter D ≥ {m:.3} mm"));
    }
    print(
        json,
        json!({
            "thread": thread,
            "class": class,
            "internal": l.internal,
            "fundamental_deviation_um": l.fundamental_deviation_um,
            "pitch_tolerance_um": l.pitch_tolerance_um,
            "pitch_diameter_mm": range(Some(l.pitch)),
            "basic_d2": pitch_diameter(d, p),
            "crest_diameter_mm": range(l.crest),
            "crest_tolerance_um": l.crest_tolerance_um,
            "crest_missing": l.crest_missing,
            "major_diameter_min_mm": l.major_min,
        }),
        text.join("\n"),
    )?;
    Ok(EXIT_OK)
}
