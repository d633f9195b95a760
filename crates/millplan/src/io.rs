//! All file access of millplan: reading programs and meshes with located
//! errors and within the resource limits, writing the outputs of a run, and
//! standard output.
//!
//! Outputs: every output of a run is checked before any work is done (a
//! regular file or a new name in an existing folder; through a symbolic link
//! the file it names; never a device, FIFO, socket or folder; never an input;
//! never another output of the run), written to a temporary file beside it
//! (`.millplan-PID-XXXXXX.tmp`, removed on an error, on SIGINT, SIGTERM and
//! SIGHUP, and by a later run once process PID is gone) and renamed into
//! place only when every output of the run has been written. `-` writes to
//! standard output where a command allows it. A failed run leaves nothing.

use crate::error::{CliError, CliResult};
use millplan_geom::stl::{read_stl_from_limited, StlReport};
use millplan_geom::TriMesh;
use millplan_nc::detect::{detect, Reader};
use millplan_nc::{Parsed, ReadOptions};
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// What a file holds, decided from its content.
pub enum Input {
    Program(Parsed),
    Mesh(TriMesh, StlReport),
}

/// Opens an input. A device (`/dev/zero`, `/dev/urandom`) or socket is
/// refused: it has no end, and a program or mesh is a file (a pipe, such as
/// `<(zcat part.stl.gz)`, is read).
fn open(path: &Path) -> CliResult<File> {
    let f = File::open(path)
        .map_err(|e| CliError::input(format!("{}: cannot open: {e}", path.display())))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = f.metadata().map(|m| m.file_type());
        if t.is_ok_and(|t| t.is_char_device() || t.is_block_device() || t.is_socket()) {
            return Err(CliError::input(format!(
                "{}: a device or socket, not a file: millplan reads programs and meshes from files (or pipes)",
                path.display()
            )));
        }
    }
    Ok(f)
}

/// Asks the kernel to start reading all of `f` now, in large requests, ahead
/// of the parse. A file not read for a while may have left the page cache
/// (some VMs hand idle page cache back to the host after a minute); read
/// on demand it then arrives a readahead window at a time, and the parse waits
/// on every one. An advice only: a refusal changes nothing.
fn prefetch(f: &File) {
    #[cfg(target_os = "linux")]
    {
        let _ = rustix::fs::fadvise(f, 0, None, rustix::fs::Advice::WillNeed);
    }
    #[cfg(not(target_os = "linux"))]
    let _ = f;
}

/// Is this an STL by its content (binary by size arithmetic, or ASCII
/// `solid … facet`)? Never by its name.
fn is_stl(len: u64, head: &[u8]) -> bool {
    millplan_geom::stl::is_stl(len, head)
}

/// Binary data: a NUL byte in the first 4 KB (no NC program has one).
fn is_binary(head: &[u8]) -> bool {
    head.iter().take(4096).any(|&b| b == 0)
}

/// Reads a program or a mesh, whichever the content says it is.
pub fn read_any(path: &Path, opts: ReadOptions) -> CliResult<Input> {
    let mut f = open(path)?;
    let len = f.metadata().map(|m| m.len()).unwrap_or(0);
    let mut head = vec![0u8; 64 * 1024];
    let n = read_up_to(&mut f, &mut head)
        .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
    head.truncate(n);
    if is_stl(len, &head) {
        let (m, r) = read_mesh(path)?;
        return Ok(Input::Mesh(m, r));
    }
    if is_binary(&head) {
        // A binary STL with a wrong count (a truncated file) is binary data
        // like any other: say what it is not, whatever its name.
        return match read_mesh(path) {
            Ok((m, r)) => Ok(Input::Mesh(m, r)),
            Err(e) => Err(CliError::input(format!(
                "{} (binary data: not an APT/CL or G-code program, and not a readable STL)",
                e.message
            ))),
        };
    }
    Ok(Input::Program(read_program(path, opts)?))
}

fn read_up_to(f: &mut File, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match f.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}

/// Reads an STL mesh within the limits of this run.
pub fn read_mesh(path: &Path) -> CliResult<(TriMesh, StlReport)> {
    let cannot =
        |e: std::io::Error| CliError::input(format!("{}: cannot read: {e}", path.display()));
    let mut f = File::open(path).map_err(cannot)?;
    prefetch(&f);
    let len = f.metadata().map_err(cannot)?.len();
    read_stl_from_limited(&mut f, len, &crate::limits::get())
        .map_err(|e| CliError::input(format!("{}:{e}", path.display())))
}

/// Reads the part for a command that works on its surface: an STL without a
/// triangle (after degenerate ones are dropped) is refused, rather than every
/// point coming out without contact.
pub fn read_surface(
    path: &Path,
    units: Option<crate::cmd::UnitArg>,
) -> CliResult<(TriMesh, StlReport)> {
    let (mut mesh, report) = read_mesh(path)?;
    crate::cmd::stl_to_mm(&mut mesh, units);
    if mesh.is_empty() {
        return Err(CliError::input(format!(
            "{}: no triangles: there is no part surface to work on",
            path.display()
        )));
    }
    Ok((mesh, report))
}

/// Reads one line into `buf` without its terminator (LF, CRLF or a lone CR,
/// also when the CR and LF arrive in different reads); `None` at the end.
/// Stops as soon as the line is longer than `max` bytes: `buf` then holds
/// `max + 1` of them. Returns the bytes consumed.
fn read_line(r: &mut impl BufRead, buf: &mut Vec<u8>, max: usize) -> std::io::Result<Option<u64>> {
    buf.clear();
    let mut consumed = 0u64;
    loop {
        let avail = r.fill_buf()?;
        if avail.is_empty() {
            return Ok((consumed > 0).then_some(consumed));
        }
        let end = memchr::memchr2(b'\n', b'\r', avail);
        let take = end.unwrap_or(avail.len());
        let room = (max + 1).saturating_sub(buf.len());
        buf.extend_from_slice(&avail[..take.min(room)]);
        let cr = end.is_some_and(|i| avail[i] == b'\r');
        let used = end.map_or(take, |i| i + 1);
        r.consume(used);
        consumed += used as u64;
        if buf.len() > max {
            return Ok(Some(consumed));
        }
        if end.is_some() {
            if cr && r.fill_buf()?.first() == Some(&b'\n') {
                r.consume(1);
                consumed += 1;
            }
            return Ok(Some(consumed));
        }
    }
}

/// The dialect of a program from its first bytes; an empty file, binary
/// data, an HTML or XML page and a KUKA robot program are refused at 1:1.
fn dialect_of(path: &Path, head: &[u8]) -> CliResult<millplan_nc::Dialect> {
    let refuse = |what: &str| Err(CliError::input(format!("{}:1:1: {what}", path.display())));
    if head.is_empty() {
        return refuse("empty file");
    }
    if is_binary(head) {
        return refuse("binary data: not an APT/CL or G-code program");
    }
    let head = String::from_utf8_lossy(head);
    if head.trim_start().starts_with('<') {
        return refuse("an HTML or XML document (it starts `<`), not an APT/CL or G-code program");
    }
    Ok(detect(&head))
}

/// Reads an APT/CL, G-code or KUKA KRL program (see [`read_source`]).
pub fn read_program(path: &Path, opts: ReadOptions) -> CliResult<Parsed> {
    read_source(path, opts).map(|(p, _)| p)
}

/// Reads an APT/CL or G-code program line by line (the file is never held
/// whole; lines end at LF, CRLF or a lone CR), within the limits of `opts`.
/// A KUKA KRL program is read whole, with its sub-programs, and also
/// returned as KRL (poses, external axes and statements as written, which
/// the IR does not hold).
pub fn read_source(
    path: &Path,
    opts: ReadOptions,
) -> CliResult<(Parsed, Option<millplan_nc::krl::KrlProgram>)> {
    let located = |e: millplan_nc::ParseError| CliError::input(format!("{}:{e}", path.display()));
    let f = open(path)?;
    prefetch(&f);
    let size = f.metadata().map(|m| m.len()).unwrap_or(0);
    let mut r = BufReader::with_capacity(1 << 16, f);
    let head = r
        .fill_buf()
        .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
    let dialect = dialect_of(path, head)?;
    if dialect == millplan_nc::Dialect::Krl {
        return read_krl(path, &opts).map(|(p, k)| (p, Some(k)));
    }
    // A move takes a line of 20 bytes or more.
    let opts = ReadOptions {
        expect_moves: (size / 20) as usize,
        ..opts
    };
    let max = usize::try_from(opts.limits.line_bytes).unwrap_or(usize::MAX);
    let mut reader = Reader::new(dialect, opts);
    let bar = crate::progress::bytes(size, "reading");
    let mut buf = Vec::with_capacity(256);
    let mut line_no: usize = 0;
    let mut done: u64 = 0;
    while let Some(n) = read_line(&mut r, &mut buf, max)
        .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?
    {
        line_no += 1;
        done += n;
        if line_no.is_multiple_of(65536) {
            bar.set_position(done);
        }
        millplan_nc::check_line_length(buf.len(), line_no, &opts.limits).map_err(located)?;
        let text = match std::str::from_utf8(&buf) {
            Ok(t) => std::borrow::Cow::Borrowed(t),
            // Old posts write Latin-1 comments; keep them readable rather than fail.
            Err(_) => std::borrow::Cow::Owned(buf.iter().map(|&b| b as char).collect::<String>()),
        };
        reader.line(&text).map_err(located)?;
    }
    bar.finish_and_clear();
    let parsed = reader.finish().map_err(located)?;
    // A number that became infinite (an inch `GOTO/1e308`, 25.4 times over
    // the largest number) is no position.
    millplan_nc::write::preflight::finite(&parsed.program).map_err(|e| {
        CliError::input(format!(
            "{}:{}:1: {}",
            path.display(),
            e.line.max(1),
            e.message
                .replace("no target can write it", "out of range once in mm")
        ))
    })?;
    Ok((parsed, None))
}

/// A KRL program and the sub-programs its main calls, each read from the
/// `.src` file of its name beside it (in any case); a missing one is a
/// finding at its calling line. External axes are dropped from the IR with
/// a finding (`read_source` keeps them in the KRL program).
fn read_krl(path: &Path, opts: &ReadOptions) -> CliResult<(Parsed, millplan_nc::krl::KrlProgram)> {
    let text = read_krl_file(path, opts)?;
    let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut failed: Option<CliError> = None;
    let mut resolve = |name: &str| {
        let p = sibling_src(&dir, name)?;
        read_krl_file(&p, opts).map_err(|e| failed = Some(e)).ok()
    };
    let k = millplan_nc::krl::read(&text, &mut resolve);
    if let Some(e) = failed {
        return Err(e);
    }
    let at = |e| krl_error(path, e);
    let k = k.map_err(at)?;
    let parsed = k.to_ir(opts.default_feed, true).map_err(at)?;
    Ok((parsed, k))
}

/// An error of the KRL program whose main is `main`, at `file:line:col` of
/// the file it is in (a sub-program's beside the main).
pub fn krl_error(main: &Path, e: millplan_nc::krl::KrlError) -> CliError {
    let dir = main.parent().unwrap_or(Path::new("."));
    let file = (e.file.as_deref())
        .and_then(|n| sibling_src(dir, n))
        .unwrap_or_else(|| main.to_path_buf());
    CliError::input(format!("{}:{}", file.display(), e.error))
}

/// One KRL file as text, its lines within the limits.
fn read_krl_file(path: &Path, opts: &ReadOptions) -> CliResult<String> {
    let mut bytes = Vec::new();
    open(path)?
        .take(opts.limits.memory)
        .read_to_end(&mut bytes)
        .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
    let text = String::from_utf8(bytes)
        .unwrap_or_else(|e| e.into_bytes().iter().map(|&b| b as char).collect());
    for (k, line) in millplan_nc::lines::split(&text).enumerate() {
        millplan_nc::check_line_length(line.len(), k + 1, &opts.limits)
            .map_err(|e| CliError::input(format!("{}:{e}", path.display())))?;
    }
    Ok(text)
}

/// The file `NAME.src` in `dir`, name and extension in any case.
fn sibling_src(dir: &Path, name: &str) -> Option<PathBuf> {
    std::fs::read_dir(dir).ok()?.flatten().find_map(|e| {
        let p = e.path();
        let stem = p.file_stem()?.to_str()?;
        let ext = p.extension()?.to_str()?;
        (stem.eq_ignore_ascii_case(name) && ext.eq_ignore_ascii_case("src")).then_some(p)
    })
}

// ---------------------------------------------------------------------------
// Outputs.

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
    crate::error::escape_controls(&format!(
        "millplan: stopped by signal {sig} after its outputs were written: {}",
        names.join(", ")
    ))
}

/// On SIGINT, SIGTERM or SIGHUP: removes the outputs staged so far and ends
/// the run with 128 + the signal's number.
pub fn remove_staged_on_signals() {
    #[cfg(target_os = "linux")]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        if let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) {
            std::thread::spawn(move || {
                if let Some(sig) = signals.forever().next() {
                    for p in staged().drain(..) {
                        let _ = std::fs::remove_file(p);
                    }
                    eprintln!("{}", stopped_message(sig));
                    std::process::exit(128 + sig);
                }
            });
        }
    }
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
fn resolve(flag: &str, p: &Path) -> CliResult<PathBuf> {
    let bad = |why: &str| CliError::input(format!("{flag} {}: {why}", p.display()));
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
    ) -> CliResult<Outputs> {
        let mut planned: Vec<(PathBuf, Dest)> = Vec::new();
        for (flag, p) in outputs {
            let Some(p) = p else { continue };
            let dest = if p.as_os_str() == "-" {
                if !stdout {
                    return Err(CliError::input(format!(
                        "{flag} -: standard output carries this command's summary; name a file"
                    )));
                }
                Dest::Stdout
            } else {
                Dest::File(check_target(flag, p, inputs)?)
            };
            if let Some((q, _)) = planned.iter().find(|(_, d)| *d == dest) {
                return Err(CliError::input(format!(
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

    fn dest(&self, path: &Path) -> CliResult<Dest> {
        self.planned
            .iter()
            .find(|(p, _)| p == path)
            .map(|(_, d)| d.clone())
            .ok_or_else(|| CliError::internal(format!("{}: not a planned output", path.display())))
    }

    /// Writes `bytes` as the output `path` (one of those planned).
    pub fn write(&mut self, path: &Path, bytes: &[u8]) -> CliResult<()> {
        self.write_with(path, |w| w.write_all(bytes))
    }

    /// Writes the output `path` with `fill` (for outputs too large to build
    /// in memory first). A file is staged until [`Outputs::commit`];
    /// standard output is written at once.
    pub fn write_with(
        &mut self,
        path: &Path,
        fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> CliResult<()> {
        let target = match self.dest(path)? {
            Dest::Stdout => {
                if stdout_was_closed() {
                    return Err(CliError::internal(
                        "standard output is closed: nothing written (name a file with -o)",
                    ));
                }
                let mut out = std::io::stdout().lock();
                return fill(&mut out)
                    .and_then(|()| out.flush())
                    .map_err(|e| CliError::internal(format!("standard output: {e}")));
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
                CliError::input(format!(
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
            return Err(CliError::internal("staged output lost"));
        };
        keep_mode(f, &s.target);
        let written = {
            let mut w = std::io::BufWriter::with_capacity(1 << 20, &mut *f);
            fill(&mut w).and_then(|()| w.flush())
        };
        written
            .and_then(|()| f.sync_all())
            .map_err(|e| CliError::internal(format!("{}: write failed: {e}", path.display())))?;
        self.staged.push(s);
        Ok(())
    }

    /// Renames every staged output into place (after all were written),
    /// holding the staged list: a signal arriving meanwhile waits until
    /// every rename is done, and then says what was written. A rename that
    /// fails says which outputs it had already replaced.
    pub fn commit(mut self) -> CliResult<()> {
        // What became a special file or a folder while the run worked is
        // still not replaced: all are checked before the first rename.
        for s in &self.staged {
            if std::fs::metadata(&s.target).is_ok_and(|m| !m.is_file()) {
                return Err(CliError::input(format!(
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
                return Err(CliError::internal(format!(
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
fn check_target(flag: &str, p: &Path, inputs: &[&Path]) -> CliResult<PathBuf> {
    let target = resolve(flag, p)?;
    if let Ok(m) = std::fs::metadata(&target) {
        if !m.is_file() {
            return Err(CliError::input(format!(
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
            return Err(CliError::input(format!(
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

    #[test]
    fn lines_end_at_lf_crlf_and_cr_across_reads() {
        // A reader of 1-byte reads puts every CR and LF in a read of its own.
        struct Slow<'a>(&'a [u8]);
        impl Read for Slow<'_> {
            fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
                let n = self.0.len().min(1).min(buf.len());
                buf[..n].copy_from_slice(&self.0[..n]);
                self.0 = &self.0[n..];
                Ok(n)
            }
        }
        let src = b"G0 X1\r\nG1 Y2\rG1 Z3\n\r\nM30";
        for cap in [1, 2, 3, 64] {
            let mut r = BufReader::with_capacity(cap, Slow(src));
            let mut buf = Vec::new();
            let mut lines = Vec::new();
            let mut total = 0;
            while let Some(n) = read_line(&mut r, &mut buf, 100).expect("reads") {
                lines.push(String::from_utf8_lossy(&buf).into_owned());
                total += n;
            }
            assert_eq!(lines, ["G0 X1", "G1 Y2", "G1 Z3", "", "M30"], "{cap}");
            assert_eq!(total, src.len() as u64);
        }
        // A line without end stops at the limit.
        let long = vec![b'x'; 10_000];
        let mut r = BufReader::with_capacity(64, &long[..]);
        let mut buf = Vec::new();
        assert!(read_line(&mut r, &mut buf, 100).expect("reads").is_some());
        assert_eq!(buf.len(), 101);
    }
}
