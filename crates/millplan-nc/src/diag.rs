//! Diagnostics (findings that do not stop reading) and located parse errors.

use std::fmt;

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Note,
    Warning,
}

/// A finding with a stable code, e.g. `unknown-word`, `units-assumed`.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Diagnostic {
    pub severity: Severity,
    pub code: &'static str,
    /// 1-based line; 0 when the finding is about the whole file.
    pub line: u32,
    /// 1-based column; 0 when not known.
    pub col: u32,
    pub message: String,
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sev = match self.severity {
            Severity::Note => "note",
            Severity::Warning => "warning",
        };
        write!(
            f,
            "{}:{}: {sev}[{}]: {}",
            self.line,
            self.col.max(1),
            self.code,
            self.message
        )
    }
}

/// Bad input that stops reading, with its position.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{line}:{col}: {message}")]
pub struct ParseError {
    pub line: u32,
    pub col: u32,
    pub message: String,
}

impl ParseError {
    pub fn new(line: u32, col: u32, message: impl Into<String>) -> ParseError {
        ParseError {
            line,
            col: col.max(1),
            message: message.into(),
        }
    }
}

/// A program read from a file, with what the reader noticed on the way.
#[derive(Clone, Debug)]
pub struct Parsed {
    pub program: crate::ir::Program,
    pub diagnostics: Vec<Diagnostic>,
}

/// Collects diagnostics; identical codes beyond `per_code_limit` are only counted,
/// so a file with 20 000 unknown records does not produce 20 000 messages.
#[derive(Debug, Default)]
pub struct Diags {
    pub list: Vec<Diagnostic>,
    counts: Vec<(&'static str, usize)>,
}

const PER_CODE_LIMIT: usize = 50;

impl Diags {
    pub fn push(
        &mut self,
        severity: Severity,
        code: &'static str,
        line: u32,
        col: u32,
        message: impl Into<String>,
    ) {
        let n = match self.counts.iter_mut().find(|(c, _)| *c == code) {
            Some((_, n)) => {
                *n += 1;
                *n
            }
            None => {
                self.counts.push((code, 1));
                1
            }
        };
        if n <= PER_CODE_LIMIT {
            self.list.push(Diagnostic {
                severity,
                code,
                line,
                col,
                message: message.into(),
            });
        }
    }

    pub fn warn(&mut self, code: &'static str, line: u32, col: u32, message: impl Into<String>) {
        self.push(Severity::Warning, code, line, col, message)
    }

    pub fn note(&mut self, code: &'static str, line: u32, col: u32, message: impl Into<String>) {
        self.push(Severity::Note, code, line, col, message)
    }

    /// The diagnostics, followed by one summary line per code whose count was capped.
    pub fn finish(mut self) -> Vec<Diagnostic> {
        for (code, n) in self.counts {
            if n > PER_CODE_LIMIT {
                self.list.push(Diagnostic {
                    severity: Severity::Note,
                    code,
                    line: 0,
                    col: 0,
                    message: format!(
                        "{} more `{code}` findings not listed ({n} in all)",
                        n - PER_CODE_LIMIT
                    ),
                });
            }
        }
        self.list
    }
}

/// Parses a number the way NC files write them (`.5`, `103.`, `-0`, `+2.7`, `1e-3`).
#[inline]
pub fn parse_num(s: &str) -> Option<f64> {
    let s = s.strip_prefix('+').unwrap_or(s);
    if s.is_empty() {
        return None;
    }
    match fast_float2::parse::<f64, _>(s) {
        Ok(v) if v.is_finite() => Some(v),
        _ => None,
    }
}
