//! STL reading (binary and ASCII) into a welded [`TriMesh`], with a report of
//! everything suspicious the file holds.
//!
//! Binary or ASCII is decided by size arithmetic (`84 + 50·n == length`), never by
//! the word `solid`: binary files often start with it. Stored normals are not
//! trusted; facet normals come from the vertex order, and the stored ones are only
//! compared against them.

use crate::limits::{amount, Exceeded, Limits};
use crate::mesh::TriMesh;
use glam::DVec3;
use rayon::prelude::*;
use std::fmt;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StlFormat {
    Binary,
    Ascii,
}

/// What the file held besides the triangles.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StlReport {
    pub format: StlFormat,
    /// Binary: the 80-byte header (up to the first NUL); ASCII: the first solid's name.
    pub header: String,
    pub facets_in_file: usize,
    /// Facets dropped for zero area or repeated vertices.
    pub degenerate: usize,
    /// Stored normals that are all zero.
    pub zero_normals: usize,
    /// Stored normals pointing against the normal from the vertex order.
    pub flipped_normals: usize,
    /// Bytes after the last facet of a binary file.
    pub trailing_bytes: usize,
    /// Number of `solid` blocks in an ASCII file.
    pub solids: usize,
}

/// Where an STL is malformed and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub struct StlError {
    pub location: StlLocation,
    pub message: String,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StlLocation {
    /// ASCII: 1-based line and column.
    Text { line: u32, col: u32 },
    /// Binary: 0-based byte offset.
    Byte(u64),
}

impl fmt::Display for StlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.location {
            StlLocation::Text { line, col } => write!(f, "{line}:{col}: {}", self.message),
            StlLocation::Byte(b) => write!(f, "byte {b}: {}", self.message),
        }
    }
}

/// Normal comparison counters.
#[derive(Default)]
struct NormalCheck {
    zero: usize,
    flipped: usize,
}

impl NormalCheck {
    #[inline]
    fn check(&mut self, stored: DVec3, tri: &[DVec3; 3]) {
        if stored == DVec3::ZERO {
            self.zero += 1;
        } else if stored.dot((tri[1] - tri[0]).cross(tri[2] - tri[0])) < 0.0 {
            self.flipped += 1;
        }
    }
}

/// Is this an STL by its content: a binary file whose facet count matches
/// its length `len`, or ASCII starting `solid` with a `facet` or `endsolid`
/// in `head` (the file's first bytes)? Never by its name.
pub fn is_stl(len: u64, head: &[u8]) -> bool {
    if head.len() >= 84 {
        let n = u32::from_le_bytes([head[80], head[81], head[82], head[83]]) as u64;
        if 84 + 50 * n == len {
            return true;
        }
    }
    let t = String::from_utf8_lossy(&head[..head.len().min(4096)]);
    let t = t.trim_start().to_ascii_lowercase();
    t.starts_with("solid") && (t.contains("facet") || t.contains("endsolid"))
}

/// Reads an STL file's bytes (within the default [`Limits`]).
///
/// ```
/// use millplan_geom::stl::{read_stl, write_binary_stl};
/// use millplan_geom::{DVec3, TriMesh};
///
/// let (tri, _) = TriMesh::from_soup(&[[DVec3::ZERO, DVec3::X, DVec3::Y]]);
/// let mut bytes = Vec::new();
/// write_binary_stl(&tri, "one facet", &mut bytes);
/// let (mesh, report) = read_stl(&bytes).expect("reads");
/// assert_eq!((mesh.len(), report.degenerate), (1, 0));
/// assert_eq!(mesh.bounds().max, DVec3::new(1.0, 1.0, 0.0));
/// ```
pub fn read_stl(bytes: &[u8]) -> Result<(TriMesh, StlReport), StlError> {
    read_stl_limited(bytes, &Limits::default())
}

/// Reads an STL file's bytes; more facets than `limits.stl_triangles` or a
/// vertex beyond ±`limits.stl_extent` is an error at its place.
pub fn read_stl_limited(bytes: &[u8], limits: &Limits) -> Result<(TriMesh, StlReport), StlError> {
    if bytes.is_empty() {
        return Err(StlError {
            location: StlLocation::Byte(0),
            message: "empty file".into(),
        });
    }
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        if 84 + 50 * n == bytes.len() as u64 {
            return read_binary(bytes, n as usize, 0, limits);
        }
    }
    if looks_ascii(bytes) {
        return read_ascii(bytes, limits);
    }
    if let Some(e) = text_not_stl(bytes) {
        return Err(e);
    }
    if bytes.len() < 84 {
        return Err(StlError {
            location: StlLocation::Byte(bytes.len() as u64),
            message: format!(
                "file ends after {} bytes: too short for a binary STL (84-byte header) and not ASCII STL",
                bytes.len()
            ),
        });
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    let need = 84 + 50 * n;
    let have = bytes.len() as u64;
    if have > need {
        // Tolerated: extra bytes after the declared facets (seen from some exporters).
        return read_binary(bytes, n as usize, (have - need) as usize, limits);
    }
    Err(StlError {
        location: StlLocation::Byte(80),
        message: format!(
            "binary STL header declares {n} facets ({need} bytes) but the file has {have} bytes: \
             truncated file or wrong facet count"
        ),
    })
}

/// A text file that is not ASCII STL (it does not start with `solid`): an
/// APT/CL or G-code program or a document given as a mesh. Its binary
/// "header" would be read as a nonsense facet count; say what it is instead.
fn text_not_stl(bytes: &[u8]) -> Option<StlError> {
    let head = &bytes[..bytes.len().min(4096)];
    let text = head
        .iter()
        .all(|&b| b.is_ascii_graphic() || b.is_ascii_whitespace() || b >= 0x80);
    if !text {
        return None;
    }
    let first = String::from_utf8_lossy(head);
    let first = first.trim_start().lines().next().unwrap_or("").trim();
    let what = if first.starts_with('<') {
        "an HTML or XML document"
    } else {
        "text that looks like an APT/CL or G-code program"
    };
    let shown: String = first.chars().take(40).collect();
    Some(StlError {
        location: StlLocation::Text { line: 1, col: 1 },
        message: format!(
            "not an STL: the file is {what} (it starts `{shown}`); an STL is binary or starts with `solid`"
        ),
    })
}

fn looks_ascii(bytes: &[u8]) -> bool {
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    let head = &bytes[start..];
    head.len() >= 5
        && head[..5].eq_ignore_ascii_case(b"solid")
        && !bytes[..bytes.len().min(4096)].contains(&0)
}

fn header_text(h: &[u8]) -> String {
    let end = h.iter().position(|&b| b == 0).unwrap_or(h.len());
    String::from_utf8_lossy(&h[..end]).trim().to_string()
}

/// Refuses a facet count over the limit before anything is allocated for it.
fn check_count(n: u64, limits: &Limits) -> Result<(), StlError> {
    if n <= limits.stl_triangles {
        return Ok(());
    }
    Err(StlError {
        location: StlLocation::Byte(80),
        message: Exceeded::new(
            "stl-triangles",
            format!("the binary STL header declares {n} facets"),
            limits.stl_triangles as f64,
        )
        .to_string(),
    })
}

fn read_binary(
    bytes: &[u8],
    n: usize,
    trailing: usize,
    limits: &Limits,
) -> Result<(TriMesh, StlReport), StlError> {
    check_count(n as u64, limits)?;
    let mut corners: Vec<[u32; 3]> = vec![[0; 3]; 3 * n];
    let normals = parse_records(&bytes[84..84 + 50 * n], 0, &mut corners, limits)?;
    finish_binary(&bytes[..80], n, trailing, corners, normals)
}

/// Parses binary facet records (the first is facet `first`) into their
/// corners' f32 bit patterns, in parallel blocks. A coordinate that is not
/// finite or lies beyond the extent limit is an error at its facet.
fn parse_records(
    body: &[u8],
    first: usize,
    corners: &mut [[u32; 3]],
    limits: &Limits,
) -> Result<NormalCheck, StlError> {
    let extent = limits.stl_extent;
    const BLOCK: usize = 1 << 14;
    #[inline]
    fn f(b: &[u8], at: usize) -> f32 {
        f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
    }
    let blocks: Vec<(NormalCheck, Option<(usize, f32)>)> = body
        .par_chunks(50 * BLOCK)
        .zip(corners.par_chunks_mut(3 * BLOCK))
        .enumerate()
        .map(|(b, (recs, out))| {
            let mut normals = NormalCheck::default();
            for (i, (rec, out)) in recs
                .chunks_exact(50)
                .zip(out.chunks_exact_mut(3))
                .enumerate()
            {
                let v = |k: usize| [f(rec, 12 * k), f(rec, 12 * k + 4), f(rec, 12 * k + 8)];
                let tri = [v(1), v(2), v(3)];
                if let Some(c) = tri.iter().flatten().find(|c| !(c.abs() as f64 <= extent)) {
                    return (normals, Some((first + b * BLOCK + i, *c)));
                }
                let d = |p: [f32; 3]| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                normals.check(d(v(0)), &[d(tri[0]), d(tri[1]), d(tri[2])]);
                // -0.0 and +0.0 are one coordinate.
                for (o, p) in out.iter_mut().zip(&tri) {
                    *o = p.map(|c| (c + 0.0).to_bits());
                }
            }
            (normals, None)
        })
        .collect();
    if let Some((i, c)) = blocks.iter().find_map(|b| b.1) {
        return Err(StlError {
            location: StlLocation::Byte((84 + 50 * i) as u64),
            message: if c.is_finite() {
                out_of_extent(&format!("facet {}", i + 1), c as f64, limits)
            } else {
                format!("facet {} has a non-finite coordinate", i + 1)
            },
        });
    }
    Ok(blocks
        .iter()
        .fold(NormalCheck::default(), |a, b| NormalCheck {
            zero: a.zero + b.0.zero,
            flipped: a.flipped + b.0.flipped,
        }))
}

fn finish_binary(
    header: &[u8],
    n: usize,
    trailing: usize,
    corners: Vec<[u32; 3]>,
    normals: NormalCheck,
) -> Result<(TriMesh, StlReport), StlError> {
    let (mesh, weld) = TriMesh::from_f32_corners(corners);
    let report = StlReport {
        format: StlFormat::Binary,
        header: header_text(header),
        facets_in_file: n,
        degenerate: weld.degenerate,
        zero_normals: normals.zero,
        flipped_normals: normals.flipped,
        trailing_bytes: trailing,
        solids: 1,
    };
    Ok((mesh, report))
}

/// The message for a vertex coordinate beyond the extent limit.
fn out_of_extent(what: &str, c: f64, limits: &Limits) -> String {
    Exceeded::new(
        "stl-extent",
        format!("{what} has a vertex at {} mm", amount(c)),
        limits.stl_extent,
    )
    .to_string()
}

/// Reads an STL of `len` bytes from `r` (within the default [`Limits`]).
pub fn read_stl_from(
    r: &mut impl std::io::Read,
    len: u64,
) -> Result<(TriMesh, StlReport), StlError> {
    read_stl_from_limited(r, len, &Limits::default())
}

/// Reads an STL of `len` bytes from `r`. A binary file whose size matches its
/// facet count is parsed as it streams in (its bytes are never held whole);
/// anything else is read whole and given to [`read_stl_limited`].
pub fn read_stl_from_limited(
    r: &mut impl std::io::Read,
    len: u64,
    limits: &Limits,
) -> Result<(TriMesh, StlReport), StlError> {
    let io = |e: std::io::Error, at: u64| StlError {
        location: StlLocation::Byte(at),
        message: format!("read failed: {e}"),
    };
    let mut head = vec![0u8; len.min(84) as usize];
    r.read_exact(&mut head).map_err(|e| io(e, 0))?;
    if head.len() == 84 {
        let n = u32::from_le_bytes([head[80], head[81], head[82], head[83]]) as u64;
        if n > 0 && 84 + 50 * n == len {
            check_count(n, limits)?;
            const CHUNK: usize = 1 << 16;
            let n = n as usize;
            let mut corners: Vec<[u32; 3]> = vec![[0; 3]; 3 * n];
            let mut buf = vec![0u8; 50 * CHUNK.min(n)];
            let mut normals = NormalCheck::default();
            for (c, out) in corners.chunks_mut(3 * CHUNK).enumerate() {
                let recs = out.len() / 3;
                let body = &mut buf[..50 * recs];
                r.read_exact(body)
                    .map_err(|e| io(e, 84 + 50 * (c * CHUNK) as u64))?;
                let got = parse_records(body, c * CHUNK, out, limits)?;
                normals.zero += got.zero;
                normals.flipped += got.flipped;
            }
            return finish_binary(&head[..80], n, 0, corners, normals);
        }
    }
    let mut bytes = head;
    r.read_to_end(&mut bytes).map_err(|e| io(e, 0))?;
    read_stl_limited(&bytes, limits)
}

/// Whitespace tokenizer over ASCII STL that tracks line and column.
#[derive(Clone)]
struct Tokens<'a> {
    b: &'a [u8],
    pos: usize,
    line: u32,
    line_start: usize,
}

impl<'a> Tokens<'a> {
    /// Next token with its (line, col), or `None` at end of input.
    fn next(&mut self) -> Option<(&'a [u8], u32, u32)> {
        while self.pos < self.b.len() && self.b[self.pos].is_ascii_whitespace() {
            // A line ends at LF, CRLF or a lone CR.
            let c = self.b[self.pos];
            if c == b'\n' || (c == b'\r' && self.b.get(self.pos + 1) != Some(&b'\n')) {
                self.line += 1;
                self.line_start = self.pos + 1;
            }
            self.pos += 1;
        }
        if self.pos >= self.b.len() {
            return None;
        }
        let s = self.pos;
        while self.pos < self.b.len() && !self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Some((
            &self.b[s..self.pos],
            self.line,
            (s - self.line_start + 1) as u32,
        ))
    }

    /// The rest of the current line (solid names may contain spaces).
    fn rest_of_line(&mut self) -> &'a [u8] {
        let s = self.pos;
        while self.pos < self.b.len() && !matches!(self.b[self.pos], b'\n' | b'\r') {
            self.pos += 1;
        }
        &self.b[s..self.pos]
    }

    fn here(&self) -> StlLocation {
        StlLocation::Text {
            line: self.line,
            col: (self.pos - self.line_start + 1) as u32,
        }
    }
}

fn read_ascii(bytes: &[u8], limits: &Limits) -> Result<(TriMesh, StlReport), StlError> {
    let mut t = Tokens {
        b: bytes,
        pos: 0,
        line: 1,
        line_start: 0,
    };
    let err = |line: u32, col: u32, message: String| StlError {
        location: StlLocation::Text { line, col },
        message,
    };
    let expect = |t: &mut Tokens, word: &str| -> Result<(), StlError> {
        match t.next() {
            Some((tok, _, _)) if tok.eq_ignore_ascii_case(word.as_bytes()) => Ok(()),
            Some((tok, l, c)) => Err(err(
                l,
                c,
                format!(
                    "expected `{word}`, found `{}`",
                    String::from_utf8_lossy(tok)
                ),
            )),
            None => Err(StlError {
                location: t.here(),
                message: format!("file ends where `{word}` was expected"),
            }),
        }
    };
    let number = |t: &mut Tokens| -> Result<f64, StlError> {
        match t.next() {
            Some((tok, l, c)) => match fast_float2::parse::<f64, _>(tok) {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(err(
                    l,
                    c,
                    format!(
                        "expected a number, found `{}`",
                        String::from_utf8_lossy(tok)
                    ),
                )),
            },
            None => Err(StlError {
                location: t.here(),
                message: "file ends where a number was expected".into(),
            }),
        }
    };
    let mut soup: Vec<[DVec3; 3]> = Vec::new();
    let mut normals = NormalCheck::default();
    let mut header = String::new();
    let mut solids = 0;
    loop {
        match t.next() {
            None => break,
            Some((tok, _, _)) if tok.eq_ignore_ascii_case(b"solid") => {
                let name = String::from_utf8_lossy(t.rest_of_line()).trim().to_string();
                if solids == 0 {
                    header = name;
                }
                solids += 1;
            }
            Some((tok, l, c)) => {
                return Err(err(
                    l,
                    c,
                    format!("expected `solid`, found `{}`", String::from_utf8_lossy(tok)),
                ))
            }
        }
        loop {
            match t.next() {
                Some((tok, _, _)) if tok.eq_ignore_ascii_case(b"endsolid") => {
                    t.rest_of_line();
                    break;
                }
                Some((tok, fl, fc)) if tok.eq_ignore_ascii_case(b"facet") => {
                    expect(&mut t, "normal")?;
                    let n = DVec3::new(number(&mut t)?, number(&mut t)?, number(&mut t)?);
                    expect(&mut t, "outer")?;
                    expect(&mut t, "loop")?;
                    if soup.len() as u64 >= limits.stl_triangles {
                        return Err(err(
                            fl,
                            fc,
                            Exceeded::new(
                                "stl-triangles",
                                format!("facet {} is one too many", soup.len() + 1),
                                limits.stl_triangles as f64,
                            )
                            .to_string(),
                        ));
                    }
                    let mut tri = [DVec3::ZERO; 3];
                    let facet = format!("facet {}", soup.len() + 1);
                    // A vertex coordinate, within the extent limit.
                    let coord = |t: &mut Tokens| -> Result<f64, StlError> {
                        let at = t.clone();
                        let v = number(t)?;
                        if v.abs() <= limits.stl_extent {
                            return Ok(v);
                        }
                        let mut at = at;
                        let (_, l, c) = at.next().unwrap_or((b"", t.line, 1));
                        Err(err(l, c, out_of_extent(&facet, v, limits)))
                    };
                    for p in &mut tri {
                        expect(&mut t, "vertex")?;
                        *p = DVec3::new(coord(&mut t)?, coord(&mut t)?, coord(&mut t)?);
                    }
                    expect(&mut t, "endloop")?;
                    expect(&mut t, "endfacet")?;
                    normals.check(n, &tri);
                    soup.push(tri);
                }
                Some((tok, l, c)) => {
                    return Err(err(
                        l,
                        c,
                        format!(
                            "expected `facet` or `endsolid`, found `{}`",
                            String::from_utf8_lossy(tok)
                        ),
                    ))
                }
                None => {
                    return Err(StlError {
                        location: t.here(),
                        message: "file ends inside a solid (no `endsolid`)".into(),
                    })
                }
            }
        }
    }
    let facets = soup.len();
    let (mesh, weld) = TriMesh::from_soup(&soup);
    drop(soup);
    Ok((
        mesh,
        StlReport {
            format: StlFormat::Ascii,
            header,
            facets_in_file: facets,
            degenerate: weld.degenerate,
            zero_normals: normals.zero,
            flipped_normals: normals.flipped,
            trailing_bytes: 0,
            solids,
        },
    ))
}

/// Writes a mesh as binary STL (normals from the vertex order).
pub fn write_binary_stl(mesh: &TriMesh, header: &str, out: &mut Vec<u8>) {
    let mut h = [0u8; 80];
    let hb = header.as_bytes();
    let n = hb.len().min(80);
    h[..n].copy_from_slice(&hb[..n]);
    out.reserve(84 + 50 * mesh.len());
    out.extend_from_slice(&h);
    out.extend_from_slice(&(mesh.len() as u32).to_le_bytes());
    for t in 0..mesh.len() {
        let nrm = mesh.facet_normal(t);
        for v in std::iter::once(nrm).chain(mesh.corners(t)) {
            for c in [v.x, v.y, v.z] {
                out.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> TriMesh {
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        TriMesh {
            vertices: v,
            triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        }
    }

    #[test]
    fn binary_with_solid_header_is_binary() {
        let mut b = Vec::new();
        write_binary_stl(&tetra(), "solid SLUMOLD", &mut b);
        let (m, r) = read_stl(&b).expect("reads");
        assert_eq!(r.format, StlFormat::Binary);
        assert_eq!(r.header, "solid SLUMOLD");
        assert_eq!(m.len(), 4);
        assert_eq!(m.edge_report().open, 0);
        assert_eq!(r.flipped_normals, 0);
    }

    #[test]
    fn streamed_binary_reads_like_the_whole_file() {
        // Over 65,536 facets: the stream is parsed in more than one chunk.
        let m = crate::analytic::tessellate(&crate::analytic::DemoSurface::default(), 0.3);
        assert!(m.len() > 1 << 16);
        let mut b = Vec::new();
        write_binary_stl(&m, "solid streamed", &mut b);
        let whole = read_stl(&b).expect("reads");
        let streamed = read_stl_from(&mut &b[..], b.len() as u64).expect("reads");
        assert_eq!(streamed.0.vertices, whole.0.vertices);
        assert_eq!(streamed.0.triangles, whole.0.triangles);
        assert_eq!(streamed.1, whole.1);
        // A bad coordinate in the second chunk is found at the same byte.
        let at = 84 + 50 * 70_000 + 12 + 4;
        b[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        let e1 = read_stl(&b).expect_err("NaN");
        let e2 = read_stl_from(&mut &b[..], b.len() as u64).expect_err("NaN");
        assert_eq!(e1, e2);
        assert_eq!(e2.location, StlLocation::Byte(84 + 50 * 70_000));
        // A stream shorter than its length says fails with a location.
        let e3 = read_stl_from(&mut &b[..b.len() - 10], b.len() as u64).expect_err("short");
        assert!(matches!(e3.location, StlLocation::Byte(_)), "{e3:?}");
        // ASCII goes the whole-file way.
        let a = b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        assert_eq!(
            read_stl_from(&mut &a[..], a.len() as u64)
                .expect("ascii")
                .0
                .len(),
            1
        );
    }

    #[test]
    fn wrong_count_is_located_error() {
        let mut b = Vec::new();
        write_binary_stl(&tetra(), "x", &mut b);
        b[80] = 9;
        let e = read_stl(&b).expect_err("must fail");
        assert_eq!(e.location, StlLocation::Byte(80));
        assert!(e.message.contains("declares 9 facets"), "{e}");
    }

    #[test]
    fn trailing_bytes_tolerated_and_reported() {
        let mut b = Vec::new();
        write_binary_stl(&tetra(), "x", &mut b);
        b.extend_from_slice(&[0; 7]);
        let (_, r) = read_stl(&b).expect("reads");
        assert_eq!(r.trailing_bytes, 7);
    }

    #[test]
    fn ascii_zero_normals_two_solids_and_errors() {
        let src = "solid a b\r\n facet normal 0 0 0\n outer loop\n vertex 0 0 0\n vertex 1 0 0\n vertex 0 1 0\n endloop\n endfacet\nendsolid other\n\
                   solid c\nfacet normal 0 0 -1e0 outer loop vertex 0 0 0 vertex 0 1 0 vertex 1 0 0 endloop endfacet endsolid\n";
        let (m, r) = read_stl(src.as_bytes()).expect("reads");
        assert_eq!(
            (r.format, r.solids, r.zero_normals, r.flipped_normals),
            (StlFormat::Ascii, 2, 1, 0)
        );
        assert_eq!(r.header, "a b");
        assert_eq!(m.len(), 2);
        let bad =
            "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1x 0\n";
        let e = read_stl(bad.as_bytes()).expect_err("fails");
        assert_eq!(e.location, StlLocation::Text { line: 6, col: 10 });
        let e = read_stl(b"solid x\nfacet normal 0 0 1\n").expect_err("fails");
        assert!(e.message.contains("file ends"), "{e}");
    }

    /// Issue 17: "a 123-byte STL facet at ±1e30 makes `raster` take 8–24
    /// GB". A vertex beyond the extent limit is refused at its facet (binary:
    /// the facet's byte; ASCII: the number's line and column), and a facet
    /// count over the limit before anything is allocated for it.
    #[test]
    fn limits_are_located_errors() {
        let mut b = Vec::new();
        write_binary_stl(&tetra(), "x", &mut b);
        let at = 84 + 50 * 2 + 12 + 4;
        b[at..at + 4].copy_from_slice(&1e30f32.to_le_bytes());
        for e in [
            read_stl(&b).expect_err("far"),
            read_stl_from(&mut &b[..], b.len() as u64).expect_err("far"),
        ] {
            assert_eq!(e.location, StlLocation::Byte(84 + 100), "{e}");
            assert!(
                e.message.contains("facet 3 has a vertex at 1.000e30 mm"),
                "{e}"
            );
            assert!(e.message.contains("--limit stl-extent=N"), "{e}");
        }
        let wide = Limits {
            stl_extent: 1e31,
            ..Limits::default()
        };
        assert!(read_stl_limited(&b, &wide).is_ok());
        let few = Limits {
            stl_triangles: 3,
            ..Limits::default()
        };
        write_binary_stl(&tetra(), "x", &mut b);
        let e = read_stl_limited(&b[b.len() / 2..], &few).expect_err("count");
        assert_eq!(e.location, StlLocation::Byte(80));
        assert!(e.message.contains("declares 4 facets"), "{e}");
        let e = read_stl_from_limited(&mut &b[b.len() / 2..], b.len() as u64 / 2, &few)
            .expect_err("count");
        assert!(e.message.contains("stl-triangles limit of 3"), "{e}");
        let ascii = "solid x\rfacet normal 0 0 1\router loop\rvertex 0 0 0\rvertex 1 0 0\rvertex 0 -1e30 0\r";
        let e = read_stl(ascii.as_bytes()).expect_err("far");
        assert_eq!(e.location, StlLocation::Text { line: 6, col: 10 }, "{e}");
        let facets = "facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0 0 vertex 0 1 0 endloop endfacet\n";
        let many = format!("solid x\n{}endsolid\n", facets.repeat(4));
        let e = read_stl_limited(many.as_bytes(), &few).expect_err("count");
        assert_eq!(e.location, StlLocation::Text { line: 5, col: 1 }, "{e}");
    }

    /// Lines of an ASCII STL end at LF, CRLF or a lone CR.
    #[test]
    fn ascii_lines_end_at_any_line_ending() {
        for nl in ["\n", "\r\n", "\r"] {
            let src = [
                "solid named part",
                "facet normal 0 0 1",
                "outer loop",
                "vertex 0 0 0",
                "vertex 1 0 0",
                "vertex 0 1 0",
                "endloop",
                "endfacet",
                "endsolid",
            ]
            .join(nl);
            let (m, r) = read_stl(src.as_bytes()).expect("reads");
            assert_eq!((m.len(), r.header.as_str()), (1, "named part"), "{nl:?}");
            let bad = src.replace("vertex 0 1 0", "vertex 0 1 q");
            let e = read_stl(bad.as_bytes()).expect_err("bad");
            assert_eq!(e.location, StlLocation::Text { line: 6, col: 12 }, "{nl:?}");
        }
    }

    #[test]
    fn garbage_and_empty() {
        assert!(read_stl(b"").is_err());
        assert!(read_stl(b"hello").is_err());
    }
}
