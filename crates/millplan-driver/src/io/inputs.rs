//! Reading a run's inputs: what a file is decided from its content (an STL
//! binary or ASCII whatever its name, a program's dialect from its first
//! bytes), programs read line by line within the limits (LF, CRLF or a lone
//! CR), a KUKA KRL program read whole with the sub-programs beside it, and
//! every error located at `file:line:col`.

use super::{IoError, IoResult};
use millplan_geom::limits::Limits;
use millplan_geom::stl::{read_stl_from_limited, StlError, StlLocation, StlReport};
use millplan_geom::TriMesh;
use millplan_nc::detect::{detect_named, Reader};
use millplan_nc::krl::{KrlError, KrlProgram};
use millplan_nc::{LengthUnit, ParseError, Parsed, ReadOptions};
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// What a file holds, decided from its content.
pub enum Input {
    Program(Parsed),
    Mesh(TriMesh, StlReport),
}

/// `path: what`, bad input in that file.
fn in_file(path: &Path, what: impl std::fmt::Display) -> IoError {
    IoError::in_file(path, None, None, format!("{}: {what}", path.display()))
}

/// A reader's located error, `path:line:col: what`.
fn parse_error(path: &Path, e: &ParseError) -> IoError {
    let (line, col) = (Some(e.line.into()), Some(e.col.into()));
    IoError::in_file(path, line, col, format!("{}:{e}", path.display()))
}

/// An STL reader's error, at its line and column or (binary) its byte.
fn stl_error(path: &Path, e: &StlError) -> IoError {
    let (line, col) = match e.location {
        StlLocation::Text { line, col } => (Some(line.into()), Some(col.into())),
        StlLocation::Byte(b) => (None, Some(b)),
    };
    IoError::in_file(path, line, col, format!("{}:{e}", path.display()))
}

/// Opens an input. A device (`/dev/zero`, `/dev/urandom`) or socket is
/// refused: it has no end, and a program or mesh is a file (a pipe, such as
/// `<(zcat part.stl.gz)`, is read).
fn open(path: &Path) -> IoResult<File> {
    let f = File::open(path).map_err(|e| in_file(path, format!("cannot open: {e}")))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = f.metadata().map(|m| m.file_type());
        if t.is_ok_and(|t| t.is_char_device() || t.is_block_device() || t.is_socket()) {
            return Err(in_file(
                path,
                "a device or socket, not a file: millplan reads programs and meshes from files (or pipes)",
            ));
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

/// Binary data: a NUL byte in the first 4 KB (no NC program has one).
fn is_binary(head: &[u8]) -> bool {
    head.iter().take(4096).any(|&b| b == 0)
}

/// Reads a program or a mesh, whichever the content says it is (an STL by
/// size arithmetic or `solid … facet`, never by its name).
pub fn read_any(
    path: &Path,
    opts: ReadOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> IoResult<Input> {
    let mut f = open(path)?;
    let len = f.metadata().map(|m| m.len()).unwrap_or(0);
    let mut head = vec![0u8; 64 * 1024];
    let n = read_up_to(&mut f, &mut head).map_err(|e| in_file(path, e))?;
    head.truncate(n);
    if millplan_geom::stl::is_stl(len, &head) {
        let (m, r) = read_mesh(path, &opts.limits)?;
        return Ok(Input::Mesh(m, r));
    }
    if is_binary(&head) {
        // A binary STL with a wrong count (a truncated file) is binary data
        // like any other: say what it is not, whatever its name.
        return match read_mesh(path, &opts.limits) {
            Ok((m, r)) => Ok(Input::Mesh(m, r)),
            Err(e) => Err(IoError {
                message: format!(
                    "{} (binary data: not an APT/CL or G-code program, and not a readable STL)",
                    e.message
                ),
                ..e
            }),
        };
    }
    Ok(Input::Program(read_source(path, opts, progress)?.0))
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

/// Reads an STL mesh within `limits`.
pub fn read_mesh(path: &Path, limits: &Limits) -> IoResult<(TriMesh, StlReport)> {
    let cannot = |e: std::io::Error| in_file(path, format!("cannot read: {e}"));
    let mut f = File::open(path).map_err(cannot)?;
    prefetch(&f);
    let len = f.metadata().map_err(cannot)?.len();
    read_stl_from_limited(&mut f, len, limits).map_err(|e| stl_error(path, &e))
}

/// Reads the part for a command that works on its surface, in mm (an inch
/// STL scaled by 25.4; an STL does not say, mm is the default): an STL
/// without a triangle (after degenerate ones are dropped) is refused, rather
/// than every point coming out without contact.
pub fn read_surface(
    path: &Path,
    limits: &Limits,
    units: Option<LengthUnit>,
) -> IoResult<(TriMesh, StlReport)> {
    let (mut mesh, report) = read_mesh(path, limits)?;
    if units == Some(LengthUnit::Inch) {
        mesh.map_vertices(|v| v * 25.4);
    }
    if mesh.is_empty() {
        return Err(in_file(
            path,
            "no triangles: there is no part surface to work on",
        ));
    }
    Ok((mesh, report))
}

/// A part's STL file and the unit of its numbers (`--stl-units`).
#[derive(Clone, Copy)]
pub struct PartFile<'a> {
    pub path: &'a Path,
    pub units: Option<LengthUnit>,
}

impl PartFile<'_> {
    /// The part (refused without a triangle), in mm ([`read_surface`]).
    pub fn read(&self, limits: &Limits) -> IoResult<TriMesh> {
        Ok(read_surface(self.path, limits, self.units)?.0)
    }
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

/// The dialect of a program from its first bytes (and its name's extension,
/// where they have no dialect's words); an empty file, binary data and an
/// HTML or XML page are refused at 1:1.
fn dialect_of(path: &Path, head: &[u8]) -> IoResult<millplan_nc::Dialect> {
    let refuse = |what: &str| {
        let at = format!("{}:1:1: {what}", path.display());
        Err(IoError::in_file(path, Some(1), Some(1), at))
    };
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
    let extension = path.extension().and_then(|e| e.to_str());
    Ok(detect_named(&head, extension))
}

/// Reads an APT/CL or G-code program line by line (the file is never held
/// whole; lines end at LF, CRLF or a lone CR), within the limits of `opts`;
/// `progress(bytes done, bytes in all)` hears how far it got now and then.
/// A KUKA KRL program is read whole, with its sub-programs, and also
/// returned as KRL (poses, external axes and statements as written, which
/// the IR does not hold).
pub fn read_source(
    path: &Path,
    opts: ReadOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> IoResult<(Parsed, Option<KrlProgram>)> {
    let f = open(path)?;
    prefetch(&f);
    let size = f.metadata().map(|m| m.len()).unwrap_or(0);
    let mut r = BufReader::with_capacity(1 << 16, f);
    let head = r.fill_buf().map_err(|e| in_file(path, e))?;
    let dialect = dialect_of(path, head)?;
    if dialect == millplan_nc::Dialect::Krl {
        return read_krl(path, &opts).map(|(p, k)| (p, Some(k)));
    }
    // A move takes a line of 20 bytes or more.
    let opts = ReadOptions {
        expect_moves: (size / 20) as usize,
        ..opts
    };
    let mut reader = Reader::new(dialect, opts);
    read_lines(path, &mut r, &mut reader, &opts.limits, &mut |done| {
        progress(done, size)
    })?;
    let parsed = reader.finish().map_err(|e| parse_error(path, &e))?;
    // A number that became infinite (an inch `GOTO/1e308`, 25.4 times over
    // the largest number) is no position.
    millplan_nc::write::preflight::finite(&parsed.program).map_err(|e| {
        let line = e.line.max(1);
        let what = e
            .message
            .replace("no target can write it", "out of range once in mm");
        let at = format!("{}:{line}:1: {what}", path.display());
        IoError::in_file(path, Some(line as u64), Some(1), at)
    })?;
    Ok((parsed, None))
}

/// Feeds every line of `r` to `reader`, each within the line length limit.
fn read_lines(
    path: &Path,
    r: &mut impl BufRead,
    reader: &mut Reader,
    limits: &Limits,
    progress: &mut dyn FnMut(u64),
) -> IoResult<()> {
    let max = usize::try_from(limits.line_bytes).unwrap_or(usize::MAX);
    let mut buf = Vec::with_capacity(256);
    let mut line_no: usize = 0;
    let mut done: u64 = 0;
    let mut feed = |line: &[u8], line_no: usize| -> IoResult<()> {
        let located = |e: ParseError| parse_error(path, &e);
        millplan_nc::check_line_length(line.len(), line_no, limits).map_err(located)?;
        let text = match std::str::from_utf8(line) {
            Ok(t) => std::borrow::Cow::Borrowed(t),
            // Old posts write Latin-1 comments; keep them readable rather than fail.
            Err(_) => std::borrow::Cow::Owned(line.iter().map(|&b| b as char).collect::<String>()),
        };
        reader.line(&text).map_err(located)
    };
    loop {
        // A line whole in the buffer is read where it lies: most are, and
        // copying each out cost more than finding its end.
        let avail = r.fill_buf().map_err(|e| in_file(path, e))?;
        let whole = memchr::memchr2(b'\n', b'\r', avail)
            .filter(|&i| i <= max && (avail[i] == b'\n' || i + 1 < avail.len()));
        let n = match whole {
            Some(i) => {
                let crlf = avail[i] == b'\r' && avail[i + 1] == b'\n';
                line_no += 1;
                feed(&avail[..i], line_no)?;
                let used = i + 1 + usize::from(crlf);
                r.consume(used);
                used as u64
            }
            // Across the buffer's end, too long, a CR last in the buffer,
            // or the end of the file.
            None => match read_line(r, &mut buf, max).map_err(|e| in_file(path, e))? {
                Some(n) => {
                    line_no += 1;
                    feed(&buf, line_no)?;
                    n
                }
                None => break,
            },
        };
        done += n;
        if line_no.is_multiple_of(65536) {
            progress(done);
        }
    }
    Ok(())
}

/// A KRL program and the sub-programs its main calls, each read from the
/// `.src` file of its name beside it (in any case); a missing one is a
/// finding at its calling line. External axes are dropped from the IR with
/// a finding (`read_source` keeps them in the KRL program).
fn read_krl(path: &Path, opts: &ReadOptions) -> IoResult<(Parsed, KrlProgram)> {
    let text = read_krl_file(path, opts)?;
    let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut failed: Option<IoError> = None;
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
pub fn krl_error(main: &Path, e: KrlError) -> IoError {
    let dir = main.parent().unwrap_or(Path::new("."));
    let file = (e.file.as_deref())
        .and_then(|n| sibling_src(dir, n))
        .unwrap_or_else(|| main.to_path_buf());
    parse_error(&file, &e.error)
}

/// One KRL file as text, its lines within the limits.
fn read_krl_file(path: &Path, opts: &ReadOptions) -> IoResult<String> {
    let mut bytes = Vec::new();
    open(path)?
        .take(opts.limits.memory)
        .read_to_end(&mut bytes)
        .map_err(|e| in_file(path, e))?;
    let text = String::from_utf8(bytes)
        .unwrap_or_else(|e| e.into_bytes().iter().map(|&b| b as char).collect());
    for (k, line) in millplan_nc::lines::split(&text).enumerate() {
        millplan_nc::check_line_length(line.len(), k + 1, &opts.limits)
            .map_err(|e| parse_error(path, &e))?;
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

/// The machine of `--machine FILE` (the machine file, or either of the two
/// older single-purpose files; a field's error at `file:line:col`), or the
/// built-in default.
pub fn read_machine(path: Option<&Path>) -> IoResult<millplan_plan::machine::Machine> {
    let Some(p) = path else {
        return Ok(millplan_plan::machine::Machine::default());
    };
    let text = std::fs::read_to_string(p)
        .map_err(|e| IoError::input(format!("{}: cannot read: {e}", p.display())))?;
    millplan_plan::machine::Machine::from_toml(&text).map_err(|e| {
        // `file:line:col: field: message` when the error has a place.
        let sep = if e.at.is_some() { ":" } else { ": " };
        IoError::input(format!("{}{sep}{e}", p.display()))
    })
}

/// The robot of `--robot NAME`: `kr240`, the bundled KUKA KR 240 R2500, or
/// a robot file in its TOML form (a TOML error at `file:line:col`).
pub fn read_robot(name: &str) -> IoResult<millplan_robot::Robot> {
    if name == "kr240" {
        return Ok(millplan_robot::Robot::kr240());
    }
    let p = Path::new(name);
    let text = std::fs::read_to_string(p)
        .map_err(|e| IoError::input(format!("{}: cannot read: {e}", p.display())))?;
    millplan_robot::Robot::from_toml(&text).map_err(|e| match e {
        millplan_robot::RobotError::Toml { .. } => IoError::input(format!("{}:{e}", p.display())),
        _ => IoError::input(format!("{}: {e}", p.display())),
    })
}

/// The built-in materials plus those of the TOML file `path`
/// (`--materials`; an error of the file at its place).
pub fn read_materials(
    path: Option<&Path>,
) -> IoResult<millplan_models::force::materials::Materials> {
    let text = match path {
        Some(p) => Some(
            std::fs::read_to_string(p)
                .map_err(|e| IoError::input(format!("{}: cannot read: {e}", p.display())))?,
        ),
        None => None,
    };
    let origin = path.map(|p| p.display().to_string()).unwrap_or_default();
    crate::cut::materials(text.as_deref().map(|t| (t, origin.as_str()))).map_err(IoError::input)
}

/// The blank of an `stl:` stock (`--stock stl:FILE`) within `limits`, in
/// mm (an inch STL scaled by 25.4); `None` for a stock of another kind.
pub fn read_blank(
    spec: &millplan_sim::stock::spec::StockSpec,
    limits: &Limits,
    units: Option<LengthUnit>,
) -> IoResult<Option<TriMesh>> {
    let millplan_sim::stock::spec::StockSpec::Stl(p) = spec else {
        return Ok(None);
    };
    let (mut mesh, _) = read_mesh(p, limits)?;
    if units == Some(LengthUnit::Inch) {
        mesh.map_vertices(|v| v * 25.4);
    }
    Ok(Some(mesh))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A G-code program without a dialect's own words is LinuxCNC's when
    /// its name ends `.ngc`: its `G4 P2` dwells two seconds, where the same
    /// text in a `.nc` (Fanuc-style) dwells two milliseconds.
    #[test]
    fn an_ngc_name_makes_a_plain_program_linuxcnc() {
        let dir = tempfile::tempdir().expect("tmp");
        for (name, dialect, seconds) in [
            ("p.ngc", millplan_nc::Dialect::LinuxCnc, 2.0),
            ("p.nc", millplan_nc::Dialect::Fanuc, 0.002),
        ] {
            let path = dir.path().join(name);
            std::fs::write(&path, "G21 G90\nG0 X0 Y0 Z5\nG4 P2\nM30\n").expect("writes");
            let (parsed, _) =
                read_source(&path, ReadOptions::default(), &mut |_, _| {}).expect("reads");
            assert_eq!(parsed.program.source, dialect, "{name}");
            let dwell: Vec<f64> = parsed.program.operations[0]
                .events
                .iter()
                .filter_map(|e| match e.kind {
                    millplan_nc::ir::EventKind::Dwell(s) => Some(s),
                    _ => None,
                })
                .collect();
            assert_eq!(dwell, [seconds], "{name}");
        }
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

    /// Lines read where they lie in the buffer and lines copied out across
    /// its end make the same program, whatever the buffer's size and the
    /// sizes of the reads behind it; an error is at the same line.
    #[test]
    fn a_program_reads_the_same_through_any_buffer() {
        struct Chunks<'a>(&'a [u8], usize);
        impl Read for Chunks<'_> {
            fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
                let n = self.0.len().min(self.1).min(buf.len());
                buf[..n].copy_from_slice(&self.0[..n]);
                self.0 = &self.0[n..];
                Ok(n)
            }
        }
        let mut src = b"G21 G90\r\nG0 X0 Y0 Z5\rG1 X1.5 F100 (caf\xe9)\n\r\n".to_vec();
        for k in 0..40 {
            src.extend_from_slice(format!("G1 X{k}.25 Y-{k}\r\n").as_bytes());
        }
        src.extend_from_slice(b"M30");
        let run = |src: &[u8], cap: usize, chunk: usize| {
            let mut r = BufReader::with_capacity(cap, Chunks(src, chunk));
            let mut reader = Reader::new(millplan_nc::Dialect::Fanuc, ReadOptions::default());
            let path = Path::new("p.nc");
            let limits = Limits::default();
            read_lines(path, &mut r, &mut reader, &limits, &mut |_| {})
                .map(|()| millplan_nc::text::print(&reader.finish().expect("ends").program))
                .map_err(|e| e.message)
        };
        let want = run(&src, 1 << 16, usize::MAX).expect("reads");
        assert!(want.contains("1.5") && want.contains("39.25"), "{want}");
        let mut bad = src.clone();
        bad.extend_from_slice(b"\nG1 X1..5\n");
        let err = run(&bad, 1 << 16, usize::MAX).expect_err("bad number");
        assert!(err.starts_with("p.nc:46:"), "{err}");
        for cap in [1, 2, 3, 5, 8, 13, 64] {
            for chunk in [1, 2, 7, usize::MAX] {
                assert_eq!(run(&src, cap, chunk).as_ref(), Ok(&want), "{cap} {chunk}");
                assert_eq!(run(&bad, cap, chunk), Err(err.clone()), "{cap} {chunk}");
            }
        }
    }

    /// The errors carry their place: a program's at its line and column,
    /// an empty file at 1:1, a missing file by its name alone.
    #[test]
    fn errors_are_located() {
        let dir = std::env::temp_dir().join(format!("millplan-inputs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let (empty, bad) = (dir.join("empty.nc"), dir.join("bad.nc"));
        std::fs::write(&empty, "").expect("write");
        std::fs::write(&bad, "G0 X0 Y0 Z5\nG1 X1..5 F100\n").expect("write");
        let none = &mut |_: u64, _: u64| {};
        let e = read_source(&empty, ReadOptions::default(), none).expect_err("empty");
        assert_eq!((e.line, e.col), (Some(1), Some(1)));
        assert_eq!(e.message, format!("{}:1:1: empty file", empty.display()));
        let e = read_source(&bad, ReadOptions::default(), none).expect_err("bad");
        assert_eq!((e.file.as_deref(), e.line), (Some(bad.as_path()), Some(2)));
        assert!(
            e.message.starts_with(&format!("{}:2:", bad.display())),
            "{e}"
        );
        let gone = dir.join("gone.nc");
        let e = read_source(&gone, ReadOptions::default(), none).expect_err("gone");
        assert_eq!(
            (e.line, e.col, e.kind),
            (None, None, super::super::IoErrorKind::BadInput)
        );
        assert!(
            e.message
                .starts_with(&format!("{}: cannot open", gone.display())),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).expect("clean");
    }

    /// A machine file's field error is located at its line and column and
    /// named; a file that cannot be read says so; none given is the
    /// built-in machine.
    #[test]
    fn a_machine_file_is_read_or_located() {
        let dir = tempfile::tempdir().expect("tmp");
        let bad = dir.path().join("m.toml");
        let text = "[spindle]\nmin = 500\nmax = nan\naccel = 6000\n[feed]\nmax = 20000\n";
        std::fs::write(&bad, text).expect("write");
        let Err(e) = read_machine(Some(&bad)) else {
            panic!("a NaN spindle maximum is refused")
        };
        let want = format!(
            "{}:3:7: spindle.max: must be from 1 to 1000000 1/min, got NaN",
            bad.display()
        );
        assert_eq!(e.message, want);
        let gone = dir.path().join("gone.toml");
        let Err(e) = read_machine(Some(&gone)) else {
            panic!("a missing file is refused")
        };
        assert!(e
            .message
            .starts_with(&format!("{}: cannot read", gone.display())));
        let d = read_machine(None).expect("default");
        assert_eq!(d.name, millplan_plan::machine::Machine::default().name);
    }
}
