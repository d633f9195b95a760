//! All file access of millplan: reading programs and meshes with located errors,
//! and writing outputs through a temporary file that is renamed into place, so a
//! failed run leaves nothing half-written and never touches its inputs.

use crate::error::{CliError, CliResult};
use millplan_geom::stl::{read_stl_from, StlReport};
use millplan_geom::TriMesh;
use millplan_nc::detect::{detect, Reader};
use millplan_nc::{Parsed, ReadOptions};
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;

/// What a file holds, decided from its content.
pub enum Input {
    Program(Parsed),
    Mesh(TriMesh, StlReport),
}

fn open(path: &Path) -> CliResult<File> {
    File::open(path).map_err(|e| CliError::input(format!("{}: cannot open: {e}", path.display())))
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

/// Is this an STL (binary by size arithmetic, or ASCII `solid … facet`)?
fn is_stl(path: &Path, head: &[u8]) -> bool {
    if let Ok(meta) = std::fs::metadata(path) {
        if head.len() >= 84 {
            let n = u32::from_le_bytes([head[80], head[81], head[82], head[83]]) as u64;
            if 84 + 50 * n == meta.len() {
                return true;
            }
        }
    }
    let t = String::from_utf8_lossy(&head[..head.len().min(4096)]);
    let t = t.trim_start().to_ascii_lowercase();
    if t.starts_with("solid") && (t.contains("facet") || t.contains("endsolid")) {
        return true;
    }
    // A binary STL with a broken count still has an 80-byte header and no text.
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    ext.as_deref() == Some("stl")
}

/// Reads a program or a mesh, whichever the content says it is.
pub fn read_any(path: &Path, opts: ReadOptions) -> CliResult<Input> {
    let mut f = open(path)?;
    let mut head = vec![0u8; 64 * 1024];
    let n = read_up_to(&mut f, &mut head)
        .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
    head.truncate(n);
    if is_stl(path, &head) {
        let (m, r) = read_mesh(path)?;
        return Ok(Input::Mesh(m, r));
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

/// Reads an STL mesh.
pub fn read_mesh(path: &Path) -> CliResult<(TriMesh, StlReport)> {
    let cannot =
        |e: std::io::Error| CliError::input(format!("{}: cannot read: {e}", path.display()));
    let mut f = File::open(path).map_err(cannot)?;
    prefetch(&f);
    let len = f.metadata().map_err(cannot)?.len();
    read_stl_from(&mut f, len).map_err(|e| CliError::input(format!("{}:{e}", path.display())))
}

/// Reads the part for a command that works on its surface: an STL without a
/// triangle (after degenerate ones are dropped) is refused, rather than every
/// point coming out without contact.
pub fn read_surface(path: &Path) -> CliResult<(TriMesh, StlReport)> {
    let (mesh, report) = read_mesh(path)?;
    if mesh.is_empty() {
        return Err(CliError::input(format!(
            "{}: no triangles: there is no part surface to work on",
            path.display()
        )));
    }
    Ok((mesh, report))
}

/// Reads an APT/CL or G-code program line by line (the file is never held whole).
pub fn read_program(path: &Path, opts: ReadOptions) -> CliResult<Parsed> {
    let f = open(path)?;
    prefetch(&f);
    let size = f.metadata().map(|m| m.len()).unwrap_or(0);
    let mut r = BufReader::with_capacity(1 << 16, f);
    let head = r
        .fill_buf()
        .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
    if head.is_empty() {
        return Err(CliError::input(format!(
            "{}:1:1: empty file",
            path.display()
        )));
    }
    if head.iter().take(4096).any(|&b| b == 0) {
        return Err(CliError::input(format!(
            "{}:1:1: binary data: not an APT/CL or G-code program",
            path.display()
        )));
    }
    let dialect = detect(&String::from_utf8_lossy(head));
    // A move takes a line of 20 bytes or more.
    let opts = ReadOptions {
        expect_moves: (size / 20) as usize,
        ..opts
    };
    let mut reader = Reader::new(dialect, opts);
    let bar = crate::progress::bytes(size, "reading");
    let mut buf = Vec::with_capacity(256);
    let mut line_no: u32 = 0;
    let mut done: u64 = 0;
    loop {
        buf.clear();
        let n = r
            .read_until(b'\n', &mut buf)
            .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
        if n == 0 {
            break;
        }
        line_no += 1;
        done += n as u64;
        if line_no.is_multiple_of(65536) {
            bar.set_position(done);
        }
        if buf.last() == Some(&b'\n') {
            buf.pop();
        }
        let text = match std::str::from_utf8(&buf) {
            Ok(t) => std::borrow::Cow::Borrowed(t),
            // Old posts write Latin-1 comments; keep them readable rather than fail.
            Err(_) => std::borrow::Cow::Owned(buf.iter().map(|&b| b as char).collect::<String>()),
        };
        reader
            .line(&text)
            .map_err(|e| CliError::input(format!("{}:{e}", path.display())))?;
    }
    bar.finish_and_clear();
    reader
        .finish()
        .map_err(|e| CliError::input(format!("{}:{e}", path.display())))
}

/// Writes `bytes` to `path` atomically: a temporary file in the same folder,
/// flushed, then renamed over the target. Refuses to overwrite any of `inputs`.
pub fn write_atomic(path: &Path, bytes: &[u8], inputs: &[&Path]) -> CliResult<()> {
    write_atomic_with(path, inputs, |f| f.write_all(bytes))
}

/// [`write_atomic`] with the bytes written by `fill` (for outputs too large
/// to build in memory first); the file is renamed into place only when `fill`
/// succeeds.
pub fn write_atomic_with(
    path: &Path,
    inputs: &[&Path],
    fill: impl FnOnce(&mut File) -> std::io::Result<()>,
) -> CliResult<()> {
    for i in inputs {
        if same_file(path, i) {
            return Err(CliError::input(format!(
                "{}: refusing to overwrite an input file; choose another -o",
                path.display()
            )));
        }
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".millplan-")
        .tempfile_in(&dir)
        .map_err(|e| {
            CliError::input(format!(
                "{}: cannot create a file there: {e}",
                dir.display()
            ))
        })?;
    // Temporary files are created private; an output is an ordinary file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let _ = tmp
            .as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644));
    }
    fill(tmp.as_file_mut())
        .and_then(|_| tmp.as_file().sync_all())
        .map_err(|e| CliError::internal(format!("{}: write failed: {e}", path.display())))?;
    tmp.persist(path).map_err(|e| {
        CliError::internal(format!(
            "{}: cannot rename into place: {}",
            path.display(),
            e.error
        ))
    })?;
    Ok(())
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// Where a path will be: its folder resolved (the file itself may not exist yet).
fn resolved(p: &Path) -> std::path::PathBuf {
    let dir = match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let dir = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
    match p.file_name() {
        Some(f) => dir.join(f),
        None => dir,
    }
}

/// Refuses a run whose outputs would overwrite one another (`-o out.nc
/// --report out.nc`), before anything is written.
pub fn distinct_outputs(outputs: &[Option<&Path>]) -> CliResult<()> {
    let given: Vec<&Path> = outputs.iter().flatten().copied().collect();
    for (i, a) in given.iter().enumerate() {
        for b in &given[i + 1..] {
            if resolved(a) == resolved(b) || same_file(a, b) {
                return Err(CliError::input(format!(
                    "{}: two outputs would be written to this one file; give each its own name",
                    a.display()
                )));
            }
        }
    }
    Ok(())
}
