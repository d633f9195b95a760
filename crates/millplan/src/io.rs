//! The binary's side of file access: the readers and outputs of
//! `millplan_driver::io` with this run's limits and a progress bar, their
//! errors as exit codes, and standard output.

use crate::error::{CliError, CliResult, EXIT_BAD_INPUT, EXIT_INTERNAL};
use millplan_driver::io::{inputs, IoError, IoErrorKind};
use millplan_geom::stl::StlReport;
use millplan_geom::TriMesh;
use millplan_nc::{Parsed, ReadOptions};
use std::io::Write;
use std::path::Path;
use std::sync::Mutex;

pub use millplan_driver::io::inputs::Input;

impl From<IoError> for CliError {
    fn from(e: IoError) -> Self {
        let code = match e.kind {
            IoErrorKind::BadInput => EXIT_BAD_INPUT,
            IoErrorKind::System => EXIT_INTERNAL,
        };
        CliError {
            code,
            message: e.message,
        }
    }
}

/// The outputs of one run: checked together before any work, written one
/// by one, renamed into place together (their errors exit codes by
/// `From<IoError>`).
pub use millplan_driver::io::outputs::Outputs;

/// Writes `files` (each checked as an output of `-o`), all of them or none.
pub fn write_all<B: AsRef<[u8]>>(files: &[(std::path::PathBuf, B)]) -> CliResult<()> {
    let named: Vec<(&str, Option<&Path>)> = files.iter().map(|(p, _)| ("-o", Some(&**p))).collect();
    let mut outputs = Outputs::plan(&[], &named, false)?;
    for (path, bytes) in files {
        outputs.write(path, bytes.as_ref())?;
    }
    Ok(outputs.commit()?)
}

/// Reads with a byte-count bar on standard error (shown for large inputs).
fn with_bar<T>(read: impl FnOnce(&mut dyn FnMut(u64, u64)) -> T) -> T {
    let mut bar = None;
    let r = read(&mut |done, total| {
        bar.get_or_insert_with(|| crate::progress::bytes(total, "reading"))
            .set_position(done)
    });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    r
}

/// Reads a program or a mesh, whichever the content says it is.
pub fn read_any(path: &Path, opts: ReadOptions) -> CliResult<Input> {
    Ok(with_bar(|p| inputs::read_any(path, opts, p))?)
}

/// Reads the part for a command that works on its surface (refused without
/// a triangle), scaled by `--stl-units`.
pub fn read_surface(
    path: &Path,
    units: Option<crate::cmd::UnitArg>,
) -> CliResult<(TriMesh, StlReport)> {
    let units = units.map(Into::into);
    Ok(inputs::read_surface(path, &crate::limits::get(), units)?)
}

/// The built-in materials plus those of `--materials`.
pub fn read_materials(path: Option<&Path>) -> CliResult<millplan_driver::Materials> {
    Ok(inputs::read_materials(path)?)
}

/// Reads an APT/CL, G-code or KUKA KRL program.
pub fn read_program(path: &Path, opts: ReadOptions) -> CliResult<Parsed> {
    Ok(with_bar(|p| inputs::read_source(path, opts, p))?.0)
}

/// On SIGINT, SIGTERM or SIGHUP: removes the outputs staged so far, says
/// what the run left and ends it with 128 + the signal's number.
pub fn remove_staged_on_signals() {
    millplan_driver::io::outputs::remove_staged_on_signals(|m| {
        eprintln!("{}", crate::error::escape_controls(m))
    });
}

// ---------------------------------------------------------------------------
// Standard output.

/// The first error writing standard output; later output is dropped.
static STDOUT_ERROR: Mutex<Option<(std::io::ErrorKind, String)>> = Mutex::new(None);

/// Whether a reader that stops early (`| head`) is the run's normal end.
static CUT_SHORT_IS_FINE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Writes to standard output, never panicking: the first failure (a closed
/// pipe, a full disk) is kept for [`stdout_failure`] and later output dropped.
pub fn out(args: std::fmt::Arguments, newline: bool) {
    let mut err = STDOUT_ERROR.lock().unwrap_or_else(|e| e.into_inner());
    if err.is_some() {
        return;
    }
    let mut o = std::io::stdout().lock();
    let r = o
        .write_fmt(args)
        .and_then(|()| if newline { o.write_all(b"\n") } else { Ok(()) });
    if let Err(e) = r {
        *err = Some((e.kind(), e.to_string()));
    }
}

/// For output a reader may take only the start of (a completion script, as
/// `millplan completions bash | head -1`): a pipe closed by the reader
/// is then no failure, as for `cat`.
pub fn reader_may_stop_early() {
    CUT_SHORT_IS_FINE.store(true, std::sync::atomic::Ordering::Relaxed);
}

/// Flushes standard output; what went wrong writing it, if anything.
pub fn stdout_failure() -> Option<String> {
    let mut err = STDOUT_ERROR.lock().unwrap_or_else(|e| e.into_inner());
    if err.is_none() {
        if let Err(e) = std::io::stdout().lock().flush() {
            *err = Some((e.kind(), e.to_string()));
        }
    }
    let fine = CUT_SHORT_IS_FINE.load(std::sync::atomic::Ordering::Relaxed);
    match &*err {
        Some((std::io::ErrorKind::BrokenPipe, _)) if fine => None,
        e => e.as_ref().map(|(_, m)| m.clone()),
    }
}
