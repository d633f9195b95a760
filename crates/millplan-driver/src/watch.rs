//! What a command's run tells its caller while it works (`Watch`: the
//! bytes read, the findings on a program, the phases and strokes done, the
//! laps of `--timings`, the checks' refusal) and why it stopped (`Stop`):
//! the binary draws and prints them, the driver decides.

use crate::io::IoError;
use millplan_plan::pipeline::PassError;
use millplan_plan::safety::Check;
use std::path::Path;

/// What a run tells its caller while it works (a command draws it as bars
/// and prints the findings).
pub trait Watch: Sync {
    /// `done` bytes of the program read of `total`.
    fn reading(&self, done: u64, total: u64);
    /// The reader's findings on the program, once it is read.
    fn diagnostics(&self, found: &[millplan_nc::Diagnostic]);
    /// The words a writer kept as comments (`--lossy`), located in the
    /// input: said unless `-q` (under `--json` too, unlike the reader's).
    fn diagnostics_written(&self, found: &[millplan_nc::Diagnostic]) {
        self.diagnostics(found)
    }
    /// `done` strokes of the force run of `total` (first with 0).
    fn strokes(&self, done: usize, total: usize);
    /// The force run has ended.
    fn forces_done(&self);
    /// The phase `name` has ended (for a `--timings` table; each phase is
    /// the work since the previous one).
    fn lap(&self, _name: &str) {}
    /// `done` of the `total` steps of the pass phase `phase`
    /// (`Context::progress`).
    fn phase(&self, _phase: &str, _done: usize, _total: usize) {}
    /// The passes that reported phases have ended.
    fn phases_done(&self) {}
    /// Work without a count has started (`Some`, what it is) or ended.
    fn busy(&self, _what: Option<&str>) {}
    /// A warning said whatever `-q` says (the exit code alone does not
    /// say why).
    fn warning(&self, _text: &str) {}
    /// The checks refused the output: the `lines` of its findings (and
    /// whether it is written anyway, `--force`).
    fn refused(&self, _lines: &[String], _forced: bool) {}
    /// Findings on a file other than the program, located in `path` (the
    /// part's mesh defects, its points off the path).
    fn findings(&self, _path: &Path, _found: &[millplan_nc::Diagnostic]) {}
    /// A note on the run: said unless `-q` or `--json`.
    fn note(&self, _text: &str) {}
    /// `done` of the `total` steps of `what`, counted in `unit` (`None`:
    /// shown as a share).
    fn count(&self, _what: &str, _unit: Option<&str>, _done: usize, _total: usize) {}
    /// The work [`Watch::count`] counted has ended.
    fn counted(&self) {}
}

/// Why a command's run stopped before its end.
#[derive(Debug)]
pub enum Stop {
    /// An input's fault or a file's, as [`IoError`] tells (exit 2, or 1
    /// when the system refused).
    Io(IoError),
    /// A bug: a pass that left nothing, bytes that do not read back (exit 1).
    Internal(String),
    /// The checks refused the output and nothing was written (exit 3).
    Refused(String),
}

impl From<IoError> for Stop {
    fn from(e: IoError) -> Stop {
        Stop::Io(e)
    }
}

impl Stop {
    /// Bad input (exit 2).
    pub fn input(message: impl Into<String>) -> Stop {
        Stop::Io(IoError::input(message))
    }

    /// A pass's failure on the program at `path`: the input's fault or a bug.
    pub fn pass(path: &Path, e: PassError) -> Stop {
        let message = format!("{}: {e}", path.display());
        if e.is_input() {
            Stop::input(message)
        } else {
            Stop::Internal(message)
        }
    }
}

/// Whether the checks passed. A refusal is told to `w` (its findings at
/// the lines of `path`, the program they belong to) and, without `force`,
/// stops the run before anything is written; with `force` the run goes on,
/// writes and ends with exit 3.
pub fn enforce(checks: &[Check], path: &Path, force: bool, w: &dyn Watch) -> Result<bool, Stop> {
    let Some((lines, first)) = crate::checks::refusal(checks, &path.display().to_string()) else {
        return Ok(true);
    };
    w.refused(&lines, force);
    if force {
        return Ok(false);
    }
    Err(Stop::Refused(format!(
        "{first}; nothing written (--force writes it)"
    )))
}

/// Reads the program at `path` (APT/CL, G-code or KUKA KRL) as `opts`
/// say, `w` hearing the bytes read and then the reader's findings.
pub fn read_program(
    path: &Path,
    opts: millplan_nc::ReadOptions,
    w: &dyn Watch,
) -> Result<millplan_nc::Parsed, IoError> {
    let mut reading = |done, total| w.reading(done, total);
    let (parsed, _) = crate::io::inputs::read_source(path, opts, &mut reading)?;
    w.diagnostics(&parsed.diagnostics);
    Ok(parsed)
}

/// Writes `p` into memory as `o` says, the words a writer kept as comments
/// told to `w` (located in `source`).
pub fn write_program(
    p: &millplan_nc::Program,
    o: millplan_nc::write::WriteOptions,
    source: &Path,
    w: &dyn Watch,
) -> Result<Vec<u8>, IoError> {
    let (out, warnings) = millplan_nc::write::write_program(p, o)
        .map_err(|e| crate::io::outputs::write_error(source, &e))?;
    w.diagnostics_written(&warnings);
    Ok(out)
}
