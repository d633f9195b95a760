//! Errors as Python exceptions: `millplan.MillplanError` (a `ValueError`)
//! carrying the file, line and column where the input is wrong, and no Rust
//! panic ever reaching Python.

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};

create_exception!(
    _millplan,
    MillplanError,
    PyValueError,
    "Bad input to millplan, located: `file`, `line` and `col` (1-based; None where \
     the error has no place in a file) and `message` (the words without the place)."
);

/// Where an error is: a file (or an argument's name) and a line and column in it.
#[derive(Clone, Debug, Default)]
pub struct Place {
    pub file: Option<String>,
    pub line: Option<u32>,
    pub col: Option<u32>,
}

impl Place {
    pub fn file(file: &str) -> Place {
        Place {
            file: Some(file.to_string()),
            ..Place::default()
        }
    }

    pub fn at(file: &str, line: u32, col: u32) -> Place {
        Place {
            file: Some(file.to_string()),
            line: Some(line),
            col: Some(col),
        }
    }
}

/// A located error, not yet a Python exception (so it can be made without
/// the interpreter, in the parts that run with the GIL released).
#[derive(Clone, Debug)]
pub struct Located {
    pub place: Place,
    pub message: String,
}

impl Located {
    pub fn new(place: Place, message: impl Into<String>) -> Located {
        Located {
            place,
            message: message.into(),
        }
    }

    /// `file:line:col: message`, as the command line prints it.
    pub fn text(&self) -> String {
        let p = &self.place;
        match (&p.file, p.line, p.col) {
            (Some(f), Some(l), Some(c)) => format!("{f}:{l}:{c}: {}", self.message),
            (Some(f), Some(l), None) => format!("{f}:{l}: {}", self.message),
            (Some(f), None, _) => format!("{f}: {}", self.message),
            (None, _, _) => self.message.clone(),
        }
    }
}

impl From<Located> for PyErr {
    fn from(e: Located) -> PyErr {
        Python::attach(|py| {
            let err = MillplanError::new_err(e.text());
            let v = err.value(py);
            // Setting attributes on a fresh exception instance cannot fail
            // short of memory; the message is there either way.
            let _ = v.setattr("file", e.place.file.clone());
            let _ = v.setattr("line", e.place.line);
            let _ = v.setattr("col", e.place.col);
            let _ = v.setattr("message", e.message.clone());
            err
        })
    }
}

pub type Res<T> = Result<T, Located>;

/// Runs `f`, turning a panic into a located error: a fault of millplan's,
/// reported as an exception rather than unwinding into the interpreter.
pub fn guard<T>(what: &str, f: impl FnOnce() -> Res<T>) -> Res<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(p) => {
            let why = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "unknown".into());
            Err(Located::new(
                Place::file(what),
                format!("internal error (please report it): {why}"),
            ))
        }
    }
}

/// Reads a file's bytes, an error naming it when it cannot be read.
pub fn read_bytes(path: &str) -> Res<Vec<u8>> {
    std::fs::read(path).map_err(|e| Located::new(Place::file(path), format!("cannot read: {e}")))
}

/// Writes a file's bytes, an error naming it when it cannot be written.
pub fn write_bytes(path: &str, bytes: &[u8]) -> Res<()> {
    std::fs::write(path, bytes)
        .map_err(|e| Located::new(Place::file(path), format!("cannot write: {e}")))
}

/// A command-line option's error (`--tol 500: …`) as the keyword
/// argument's (`tol 500: …`), placed at that argument; a message naming
/// no single option first has no place.
pub fn option_error(e: &str) -> Located {
    let Some(e) = e.strip_prefix("--") else {
        // A message about several options: their names without dashes.
        return Located::new(Place::default(), e.replace("--", ""));
    };
    let (flag, rest) = e.split_at(e.find([' ', ':']).unwrap_or(e.len()));
    let name = flag.replace('-', "_");
    Located::new(Place::file(&name), format!("{name}{rest}"))
}

/// A library's `file:line:col: message` text as a located error (the
/// place parsed back out; the whole text as the message when it has none).
pub fn located(e: &str) -> Located {
    let mut parts = e.splitn(4, ':');
    let (f, l, c, m) = (parts.next(), parts.next(), parts.next(), parts.next());
    if let (Some(f), Some(Ok(l)), Some(Ok(c)), Some(m)) =
        (f, l.map(str::parse::<u32>), c.map(str::parse::<u32>), m)
    {
        return Located::new(Place::at(f, l, c), m.trim_start());
    }
    Located::new(Place::default(), e)
}

/// A library's message about the file `file`: located as `file:line:col:`
/// when it says so, else at `file` (its own `file: ` prefix taken off).
pub fn located_in(file: &str, e: &str) -> Located {
    let l = located(e);
    if l.place.file.is_some() {
        return l;
    }
    let rest = e
        .strip_prefix(file)
        .and_then(|r| r.strip_prefix(": "))
        .unwrap_or(e);
    Located::new(Place::file(file), rest)
}

/// The driver's error choosing the output's dialect (worded for `--to` and
/// the output file `out`, which may be none) as the `dialect` keyword's.
pub fn dialect_error(out: &str, e: &str) -> Located {
    let e = e.replace("--to", "dialect");
    match e.strip_prefix(": ") {
        Some(rest) => Located::new(Place::file("dialect"), rest),
        None if out.is_empty() => Located::new(Place::file("dialect"), e),
        None => located_in(out, &e),
    }
}
