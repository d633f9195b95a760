//! The outputs of a run: every output is checked before any work is done
//! (a regular file or a new name in an existing folder; through a symbolic
//! link the file it names; never a device, FIFO, socket or folder; never an
//! input; never another output of the run), written to a temporary file
//! beside it (`.millplan-PID-XXXXXX.tmp`, removed on an error, on SIGINT,
//! SIGTERM and SIGHUP, and by a later run once process PID is gone) and
//! renamed into place only when every output of the run has been written,
//! keeping the mode of the file it replaces. `-` writes to standard output
//! where a command allows it. A failed run leaves nothing.

use super::{IoError, IoResult};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The temporary files of this process not yet renamed into place: removed
/// on SIGINT, SIGTERM and SIGHUP.
static STAGED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn staged() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    STAGED.lock().unwrap_or_else(|e| e.into_inner())
}

/// The outputs renamed into place by this process: what a signal's message
/// names as written.
static REPLACED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn replaced() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    REPLACED.lock().unwrap_or_else(|e| e.into_inner())
}

/// What a run stopped by a signal left: nothing, or the outputs it had
/// already renamed into place (all of one commit: [`Outputs::commit`]
/// holds the staged list while it renames, so a signal waits for it).
fn stopped_message(sig: i32) -> String {
    let done = replaced();
    if done.is_empty() {
        return format!("millplan: stopped by signal {sig}; no output written");
    }
    let names: Vec<String> = done.iter().map(|p| p.display().to_string()).collect();
    format!(
        "millplan: stopped by signal {sig} after its outputs were written: {}",
        names.join(", ")
    )
}

/// On SIGINT, SIGTERM or SIGHUP: removes the outputs staged so far, gives
/// `say` the message of what the run left, and ends the run with 128 + the
/// signal's number.
pub fn remove_staged_on_signals(say: fn(&str)) {
    #[cfg(target_os = "linux")]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        if let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) {
            std::thread::spawn(move || {
                if let Some(sig) = signals.forever().next() {
                    for p in staged().drain(..) {
                        let _ = std::fs::remove_file(p);
                    }
                    say(&stopped_message(sig));
                    std::process::exit(128 + sig);
                }
            });
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = say;
}

/// The temporary name prefix of this process's outputs.
fn tmp_prefix() -> String {
    format!(".millplan-{}-", std::process::id())
}

/// Removes the temporary files a run that no longer exists left in `dir`
/// (killed with SIGKILL, or a machine that went down): `.millplan-PID-*.tmp`
/// whose process PID is gone.
fn clean_stale(dir: &Path) {
    #[cfg(target_os = "linux")]
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let name = e.file_name();
        let Some(rest) = name.to_str().and_then(|n| n.strip_prefix(".millplan-")) else {
            continue;
        };
        let Some((pid, tail)) = rest.split_once('-') else {
            continue;
        };
        let ours = tail.ends_with(".tmp") && pid.bytes().all(|b| b.is_ascii_digit());
        if ours && !Path::new("/proc").join(pid).exists() {
            let _ = std::fs::remove_file(e.path());
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = dir;
}

/// Where an output goes.
#[derive(Clone, Debug, PartialEq)]
enum Dest {
    /// The file written (through a symbolic link, the file it names).
    File(PathBuf),
    Stdout,
}

/// One output written and waiting to be renamed into place.
struct Staged {
    file: Option<tempfile::NamedTempFile>,
    path: PathBuf,
    target: PathBuf,
}

impl Drop for Staged {
    fn drop(&mut self) {
        staged().retain(|p| *p != self.path);
    }
}

/// The outputs of one run: checked together before any work, written one by
/// one, renamed into place together.
pub struct Outputs {
    planned: Vec<(PathBuf, Dest)>,
    staged: Vec<Staged>,
}

/// Identity of an existing file (device and inode), through symbolic links.
fn identity(p: &Path) -> Option<(u64, u64)> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        std::fs::metadata(p).ok().map(|m| (m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        std::fs::canonicalize(p).ok().map(|_| (0, 0))
    }
}

/// Where a path will be written: through symbolic links, its folder
/// resolved (the file itself may not exist yet).
fn resolve(flag: &str, p: &Path) -> IoResult<PathBuf> {
    let bad = |why: &str| IoError::input(format!("{flag} {}: {why}", p.display()));
    let is_link = std::fs::symlink_metadata(p).is_ok_and(|m| m.file_type().is_symlink());
    if is_link {
        return std::fs::canonicalize(p).map_err(|_| match std::fs::metadata(p) {
            // `/proc/self/fd/1` on a pipe: there but no file.
            Ok(_) => bad("a symbolic link to something that is not a regular file; millplan writes its outputs only to regular files"),
            Err(_) => bad("a symbolic link to nothing; name a file"),
        });
    }
    if p.as_os_str().to_string_lossy().ends_with('/') || p.is_dir() {
        return Err(bad("is a folder; name a file"));
    }
    let dir = match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(bad(&format!("the folder {} does not exist", dir.display())));
    }
    let dir = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
    match p.file_name() {
        Some(f) => Ok(dir.join(f)),
        None => Err(bad("names no file")),
    }
}

impl Outputs {
    /// Checks the outputs of a run (`(flag, path)`, `None` for one not asked
    /// for) against each other and against its inputs, before any work.
    /// `stdout`: whether `-` may stand for standard output.
    pub fn plan(
        inputs: &[&Path],
        outputs: &[(&str, Option<&Path>)],
        stdout: bool,
    ) -> IoResult<Outputs> {
        let mut planned: Vec<(PathBuf, Dest)> = Vec::new();
        for (flag, p) in outputs {
            let Some(p) = p else { continue };
            let dest = if p.as_os_str() == "-" {
                if !stdout {
                    return Err(IoError::input(format!(
                        "{flag} -: standard output carries this command's summary; name a file"
                    )));
                }
                Dest::Stdout
            } else {
                Dest::File(check_target(flag, p, inputs)?)
            };
            if let Some((q, _)) = planned.iter().find(|(_, d)| *d == dest) {
                return Err(IoError::input(format!(
                    "{flag} {}: {} is already an output of this run; give each its own name",
                    p.display(),
                    q.display()
                )));
            }
            planned.push((p.to_path_buf(), dest));
        }
        Ok(Outputs {
            planned,
            staged: Vec::new(),
        })
    }

    fn dest(&self, path: &Path) -> IoResult<Dest> {
        self.planned
            .iter()
            .find(|(p, _)| p == path)
            .map(|(_, d)| d.clone())
            .ok_or_else(|| IoError::system(format!("{}: not a planned output", path.display())))
    }

    /// Writes `bytes` as the output `path` (one of those planned).
    pub fn write(&mut self, path: &Path, bytes: &[u8]) -> IoResult<()> {
        self.write_with(path, |w| w.write_all(bytes))
    }

    /// Writes the output `path` with `fill` (for outputs too large to build
    /// in memory first). A file is staged until [`Outputs::commit`];
    /// standard output is written at once.
    pub fn write_with(
        &mut self,
        path: &Path,
        fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> IoResult<()> {
        let target = match self.dest(path)? {
            Dest::Stdout => {
                if stdout_was_closed() {
                    return Err(IoError::system(
                        "standard output is closed: nothing written (name a file with -o)",
                    ));
                }
                let mut out = std::io::stdout().lock();
                return fill(&mut out)
                    .and_then(|()| out.flush())
                    .map_err(|e| IoError::system(format!("standard output: {e}")));
            }
            Dest::File(t) => t,
        };
        let dir = target.parent().unwrap_or(Path::new(".")).to_path_buf();
        clean_stale(&dir);
        let file = tempfile::Builder::new()
            .prefix(&tmp_prefix())
            .suffix(".tmp")
            .tempfile_in(&dir)
            .map_err(|e| {
                IoError::input(format!(
                    "{}: cannot create a file there: {e}",
                    dir.display()
                ))
            })?;
        let mut s = Staged {
            path: file.path().to_path_buf(),
            file: Some(file),
            target,
        };
        staged().push(s.path.clone());
        let f = s.file.as_mut().map(|f| f.as_file_mut());
        let Some(f) = f else {
            return Err(IoError::system("staged output lost"));
        };
        keep_mode(f, &s.target);
        let written = {
            let mut w = std::io::BufWriter::with_capacity(1 << 20, &mut *f);
            fill(&mut w).and_then(|()| w.flush())
        };
        written
            .and_then(|()| f.sync_all())
            .map_err(|e| IoError::system(format!("{}: write failed: {e}", path.display())))?;
        self.staged.push(s);
        Ok(())
    }

    /// Renames every staged output into place (after all were written),
    /// holding the staged list: a signal arriving meanwhile waits until
    /// every rename is done, and then says what was written. A rename that
    /// fails says which outputs it had already replaced.
    pub fn commit(mut self) -> IoResult<()> {
        // What became a special file or a folder while the run worked is
        // still not replaced: all are checked before the first rename.
        for s in &self.staged {
            if std::fs::metadata(&s.target).is_ok_and(|m| !m.is_file()) {
                return Err(IoError::input(format!(
                    "{}: no longer a regular file; nothing written",
                    s.target.display()
                )));
            }
        }
        let mut all = std::mem::take(&mut self.staged);
        let mut guard = staged();
        for s in &mut all {
            let Some(f) = s.file.take() else { continue };
            if let Err(e) = f.persist(&s.target) {
                let done = replaced().clone();
                let done: Vec<String> = done.iter().map(|p| p.display().to_string()).collect();
                return Err(IoError::system(format!(
                    "{}: cannot rename into place: {}; {}",
                    s.target.display(),
                    e.error,
                    match done.len() {
                        0 => "no output replaced".to_string(),
                        _ => format!("already replaced: {}", done.join(", ")),
                    }
                )));
            }
            guard.retain(|p| *p != s.path);
            replaced().push(s.target.clone());
        }
        drop(guard);
        Ok(())
    }
}

impl Outputs {
    /// Writes program `p` in `o.target` as the output `path`, a few
    /// megabytes at a time: a large program is never held whole as text.
    /// What the target cannot express is the input's fault, located at its
    /// line in `source`; returns the words written as comments under
    /// `--lossy`, as warnings.
    pub fn write_program(
        &mut self,
        path: &Path,
        p: &millplan_nc::Program,
        o: millplan_nc::write::WriteOptions,
        source: &Path,
    ) -> IoResult<Vec<millplan_nc::Diagnostic>> {
        self.write_program_tee(path, p, o, source, &mut |_| {})
    }

    /// [`Outputs::write_program`], `tee` handed every piece of the text as
    /// it is written (to read it back beside, say), in order.
    pub fn write_program_tee(
        &mut self,
        path: &Path,
        p: &millplan_nc::Program,
        o: millplan_nc::write::WriteOptions,
        source: &Path,
        tee: &mut dyn FnMut(&[u8]),
    ) -> IoResult<Vec<millplan_nc::Diagnostic>> {
        use millplan_nc::write::WriteError;
        let mut failed: Option<WriteError> = None;
        let mut warnings = Vec::new();
        let written = self.write_with(path, |f| {
            let mut buf = Vec::new();
            let mut io_error = None;
            let r = {
                let mut sink = |b: &[u8]| {
                    tee(b);
                    f.write_all(b).map_err(|e| {
                        let message = e.to_string();
                        io_error = Some(e);
                        WriteError::new(0, message)
                    })
                };
                millplan_nc::write::write_program_to(p, o, &mut buf, Some(&mut sink))
            };
            match (r, io_error) {
                (Ok(w), _) => {
                    warnings = w;
                    tee(&buf);
                    f.write_all(&buf)
                }
                (Err(_), Some(e)) => Err(e),
                (Err(e), None) => {
                    failed = Some(e);
                    Err(std::io::Error::other("the program cannot be written"))
                }
            }
        });
        match failed {
            // Something the target cannot express: the user's input, not the disk.
            Some(e) => Err(write_error(source, &e)),
            None => written.map(|()| warnings),
        }
    }
}

impl Outputs {
    /// The KRL files from the `first` (0: the main program, at `output`;
    /// its sub-programs beside it) planned against `inputs` and staged.
    pub fn stage_krl(
        inputs: &[&Path],
        output: &Path,
        files: &millplan_nc::write::krl::KrlFiles,
        first: usize,
    ) -> IoResult<Outputs> {
        let paths = millplan_nc::write::krl::file_paths(output, files);
        let planned: Vec<(&str, Option<&Path>)> = paths[first..]
            .iter()
            .map(|p| ("-o", Some(p.as_path())))
            .collect();
        let mut outputs = Outputs::plan(inputs, &planned, false)?;
        for (p, (_, text)) in paths.iter().zip(files).skip(first) {
            outputs.write(p, text.as_bytes())?;
        }
        Ok(outputs)
    }
}

/// The outputs `(flag, path)` of a run, checked before any work against each
/// other and the files it reads (`None`: an optional file not given);
/// `stdout` when `-` may name standard output ([`Outputs::plan`]).
pub fn plan(
    inputs: &[Option<&Path>],
    outputs: &[(&str, Option<&Path>)],
    stdout: bool,
) -> IoResult<Outputs> {
    let inputs: Vec<&Path> = inputs.iter().flatten().copied().collect();
    Outputs::plan(&inputs, outputs, stdout)
}

/// A writer's error at its source line (`file:line:1: message`), or in the
/// source as a whole: bad input.
pub fn write_error(source: &Path, e: &millplan_nc::write::WriteError) -> IoError {
    let (line, text) = if e.line > 0 {
        let at = format!("{}:{}:1: {}", source.display(), e.line, e.message);
        (Some(e.line as u64), at)
    } else {
        (None, format!("{}: {}", source.display(), e.message))
    };
    IoError::in_file(source, line, line.map(|_| 1), text)
}

/// Whether standard output was closed when millplan started (`>&-`): Rust's
/// runtime puts `/dev/null`, opened for reading and writing, in its place,
/// and the program would be written to nothing while the run said it wrote
/// it. A shell's `> /dev/null` opens it for writing only.
fn stdout_was_closed() -> bool {
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{fcntl_getfl, fstat, major, minor, FileType, OFlags};
        let out = std::io::stdout();
        let Ok(st) = fstat(&out) else {
            return true;
        };
        let null = FileType::from_raw_mode(st.st_mode) == FileType::CharacterDevice
            && (major(st.st_rdev), minor(st.st_rdev)) == (1, 3);
        null && fcntl_getfl(&out).is_ok_and(|f| f & OFlags::RWMODE == OFlags::RDWR)
    }
    #[cfg(not(target_os = "linux"))]
    false
}

/// Checks one output file: a regular file or a new name in an existing
/// folder, not an input. Returns the file to write.
fn check_target(flag: &str, p: &Path, inputs: &[&Path]) -> IoResult<PathBuf> {
    let target = resolve(flag, p)?;
    if let Ok(m) = std::fs::metadata(&target) {
        if !m.is_file() {
            return Err(IoError::input(format!(
                "{flag} {}: not a regular file (a device, a FIFO or a socket): millplan writes its outputs only to regular files",
                p.display()
            )));
        }
    }
    let id = identity(&target);
    for i in inputs {
        let same = id.is_some() && id == identity(i)
            || std::fs::canonicalize(i).is_ok_and(|c| c == target);
        if same {
            return Err(IoError::input(format!(
                "{}: refusing to overwrite an input file ({}); choose another {flag}",
                p.display(),
                i.display()
            )));
        }
    }
    Ok(target)
}

/// An output that replaces a file keeps that file's permissions; a new one
/// is an ordinary file (temporary files are created private).
fn keep_mode(f: &File, target: &Path) {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(target).map_or(0o644, |m| m.permissions().mode() & 0o7777);
        let _ = f.set_permissions(std::fs::Permissions::from_mode(mode));
    }
    #[cfg(not(unix))]
    let _ = (f, target);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 17: "with several outputs (`-o`, `--table`, `--report`), a
    /// failure in a later one leaves the earlier ones written". Nothing is
    /// in place until every output is written; a failure leaves neither the
    /// outputs nor their temporary files.
    #[test]
    fn outputs_land_together_or_not_at_all() {
        let dir = tempfile::tempdir().expect("tmp");
        let (a, b) = (dir.path().join("a.nc"), dir.path().join("b.csv"));
        std::fs::write(&b, "old").expect("write");
        let mut o =
            Outputs::plan(&[], &[("-o", Some(&a)), ("--table", Some(&b))], false).expect("plan");
        o.write(&a, b"program").expect("stage a");
        assert!(!a.exists(), "staged, not yet in place");
        let e = o
            .write_with(&b, |w| {
                w.write_all(b"half")?;
                Err(std::io::Error::other("disk full"))
            })
            .expect_err("fails");
        assert!(e.message.contains("disk full"), "{e}");
        drop(o);
        assert!(!a.exists());
        assert_eq!(std::fs::read_to_string(&b).expect("b"), "old");
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .expect("dir")
            .flatten()
            .collect();
        assert_eq!(left.len(), 1, "{left:?}");
        // Other tests of this binary stage their own outputs meanwhile.
        assert!(!staged().iter().any(|p| p.starts_with(dir.path())));
        // All written: all in place, the replaced file keeps its mode.
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(&b, std::fs::Permissions::from_mode(0o600)).expect("chmod");
        }
        let mut o =
            Outputs::plan(&[], &[("-o", Some(&a)), ("--table", Some(&b))], false).expect("plan");
        o.write(&a, b"program").expect("a");
        o.write(&b, b"table").expect("b");
        o.commit().expect("commit");
        assert_eq!(std::fs::read_to_string(&a).expect("a"), "program");
        assert_eq!(std::fs::read_to_string(&b).expect("b"), "table");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&b).expect("b").permissions().mode() & 0o777;
            assert_eq!(mode, 0o600);
        }
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 2);
    }

    /// A target that turned into a folder (or a FIFO) while the run worked
    /// is not replaced either.
    #[test]
    fn a_target_changed_meanwhile_is_not_replaced() {
        let dir = tempfile::tempdir().expect("tmp");
        let (a, b) = (dir.path().join("a.nc"), dir.path().join("b.nc"));
        let mut o =
            Outputs::plan(&[], &[("-o", Some(&a)), ("--report", Some(&b))], false).expect("plan");
        o.write(&a, b"a").expect("a");
        o.write(&b, b"b").expect("b");
        std::fs::create_dir(&b).expect("dir");
        let e = o.commit().expect_err("refused");
        assert!(e.message.contains("no longer a regular file"), "{e}");
        assert!(!a.exists() && b.is_dir());
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 1);
    }
}
