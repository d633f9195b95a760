//! File access of a run: reading programs and meshes with located errors
//! and within the resource limits (`inputs`), and writing the outputs of a
//! run together or not at all (`outputs`). The binary prints; this module
//! decides what a file is, what may be written where, and what went wrong.

pub mod inputs;
pub mod outputs;

use std::path::{Path, PathBuf};

/// Whether an error is the input's fault (bad input, exit 2) or the
/// system's (a write that failed, a disk full, exit 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IoErrorKind {
    BadInput,
    System,
}

/// An error reading an input or writing an output: its kind, the file,
/// line and column where known, and the whole message as printed
/// (`file:line:col: what`, `file: what` or `--flag file: what`).
#[derive(Clone, Debug, PartialEq)]
pub struct IoError {
    pub kind: IoErrorKind,
    pub file: Option<PathBuf>,
    pub line: Option<u64>,
    /// The column; for a binary STL, the byte offset.
    pub col: Option<u64>,
    pub message: String,
}

impl IoError {
    /// Bad input, not located further than its message says.
    pub fn input(message: impl Into<String>) -> IoError {
        IoError {
            kind: IoErrorKind::BadInput,
            file: None,
            line: None,
            col: None,
            message: message.into(),
        }
    }

    /// The system refused (or a broken promise of this crate).
    pub fn system(message: impl Into<String>) -> IoError {
        IoError {
            kind: IoErrorKind::System,
            ..IoError::input(message)
        }
    }

    /// Bad input in `file`, at `line` and `col` where given; the message
    /// is `file:line:col: what`, `file:line:what` (a located error of a
    /// reader, whose text starts with its place) or `file: what`.
    pub(crate) fn in_file(
        file: &Path,
        line: Option<u64>,
        col: Option<u64>,
        text: String,
    ) -> IoError {
        IoError {
            file: Some(file.to_path_buf()),
            line,
            col,
            ..IoError::input(text)
        }
    }
}

impl std::fmt::Display for IoError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for IoError {}

pub type IoResult<T> = Result<T, IoError>;
