//! `millplan explain`: the finding codes a user asks about, their
//! explanations as text and as JSON.

use millplan_nc::diag::Code;
use serde::Serialize;
use std::fmt::Write as _;

/// The code inside a finding as printed (`warning[unknown-word]`), or the
/// text as it is.
fn bare(c: &str) -> &str {
    let c = c.trim();
    match (c.find('['), c.rfind(']')) {
        (Some(a), Some(b)) if a < b => &c[a + 1..b],
        _ => c,
    }
}

/// The codes asked for: the one `code` names, else every code.
pub fn codes(code: Option<&str>) -> Result<Vec<Code>, String> {
    match code {
        Some(c) => Code::from_name(bare(c)).map(|k| vec![k]).ok_or_else(|| {
            format!("`{c}` is not a millplan code; `millplan explain` lists them all")
        }),
        None => Ok(Code::ALL.to_vec()),
    }
}

/// One code as `--json` prints it.
#[derive(Debug, Serialize)]
pub struct Explained {
    pub code: &'static str,
    pub explanation: &'static str,
}

/// The codes as `--json` prints them.
pub fn json(codes: &[Code]) -> Vec<Explained> {
    codes
        .iter()
        .map(|c| Explained {
            code: c.as_str(),
            explanation: c.explain(),
        })
        .collect()
}

/// The codes as text, one a line: the code, then what it means.
pub fn text(codes: &[Code]) -> String {
    let mut t = String::new();
    for c in codes {
        let _ = writeln!(t, "{:<24} {}", c.as_str(), c.explain());
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_code_is_found_bare_or_as_printed() {
        let one = codes(Some("unknown-word")).expect("code");
        assert_eq!(one.len(), 1);
        let printed = codes(Some(" warning[unknown-word] ")).expect("code");
        assert_eq!(printed[0].as_str(), one[0].as_str());
        assert!(codes(Some("no-such-code")).is_err());
        assert_eq!(codes(None).expect("all").len(), Code::ALL.len());
    }
}
