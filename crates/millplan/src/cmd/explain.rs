//! `millplan explain`: what a finding's code means.

use crate::error::{CliError, CliResult, EXIT_OK};
use millplan_nc::diag::Code;

/// Explain the code of a finding (`warning[unknown-word]`): what it means and
/// what to do about it. Without a code, every code.
#[derive(clap::Args)]
pub struct Args {
    /// A code as printed: `unknown-word`, or the whole `warning[unknown-word]`.
    pub code: Option<String>,
    /// Print the codes and their explanations as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `warning[unknown-word]` → `unknown-word`.
fn bare(c: &str) -> &str {
    let c = c.trim();
    match (c.find('['), c.rfind(']')) {
        (Some(a), Some(b)) if a < b => &c[a + 1..b],
        _ => c,
    }
}

pub fn run(a: Args) -> CliResult<i32> {
    let codes: Vec<Code> = match &a.code {
        Some(c) => vec![Code::from_name(bare(c)).ok_or_else(|| {
            CliError::input(format!(
                "`{c}` is not a millplan code; `millplan explain` lists them all"
            ))
        })?],
        None => Code::ALL.to_vec(),
    };
    if a.json {
        let v: Vec<_> = codes
            .iter()
            .map(|c| serde_json::json!({ "code": c.as_str(), "explanation": c.explain() }))
            .collect();
        outln!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
    } else {
        for c in codes {
            outln!("{:<24} {}", c.as_str(), c.explain());
        }
    }
    Ok(EXIT_OK)
}
