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

pub type CliResult<T> = Result<T, CliError>;

/// Longest word of a message printed whole; a longer one (a 1 MB token the
/// input held) is cut to its start and its length.
const LONGEST_WORD: usize = 80;

/// `message` with every word (a run without whitespace) longer than
/// [`LONGEST_WORD`] bytes shortened to its first 40 characters, `…` and its
/// length in bytes.
pub fn shorten(message: &str) -> std::borrow::Cow<'_, str> {
    let long = |w: &str| w.len() > LONGEST_WORD;
    if !message.split_whitespace().any(long) {
        return std::borrow::Cow::Borrowed(message);
    }
    let mut out = String::with_capacity(256);
    let mut rest = message;
    while !rest.is_empty() {
        let ws = rest
            .find(|c: char| !c.is_whitespace())
            .unwrap_or(rest.len());
        out.push_str(&rest[..ws]);
        rest = &rest[ws..];
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        let word = &rest[..end];
        if long(word) {
            let head: String = word.chars().take(40).collect();
            out.push_str(&format!("{head}…[{} bytes]", word.len()));
        } else {
            out.push_str(word);
        }
        rest = &rest[end..];
    }
    std::borrow::Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 17: "error messages echo a whole 1 MB token".
    #[test]
    fn long_words_are_cut() {
        let token = "9".repeat(1_000_000);
        let m = format!("f.nc:4:4: `{token}` is not a number after `X`");
        let s = shorten(&m);
        assert!(s.len() < 200, "{s}");
        assert!(s.starts_with("f.nc:4:4: `9999"), "{s}");
        assert!(
            s.ends_with("…[1000002 bytes] is not a number after `X`"),
            "{s}"
        );
        assert_eq!(shorten("short words stay"), "short words stay");
        assert_eq!(
            shorten(&"é".repeat(100))
                .chars()
                .filter(|c| *c == 'é')
                .count(),
            40
        );
    }
}
