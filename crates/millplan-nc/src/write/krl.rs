//! The KUKA KRL writer (process-models §5): a main `.SRC` program and, past
//! a configurable number of motions, sub-programs it calls.
//!
//! Units: mm and degrees in positions (3 decimals for mm, 4 for degrees),
//! `$VEL.CP` in m/s with 6 decimals, `$APO.CDIS` in mm. Every cutting point
//! is one `LIN` (the faithful default), approximated with `C_DIS` except
//! the last one before a rapid or the end; with [`KrlMotion::Spline`] each
//! such run is one `SPLINE` block of `SPL` segments through the same points
//! instead (a feed change inside it a segment's `WITH $VEL.CP`). Every
//! point is written inline, so no `.dat` is needed (docs/robot.md).
//! From the IR the tool axis becomes an orientation A, B, C (the tool along
//! the tool frame's x; turned about the axis as little as possible from the
//! tool pointing down, A = C = 0, B = 90°).

use crate::diag::ParseError;
use crate::ir::{Dialect, EventKind, MoveKind, PassClass, Program};
use crate::krl::{abc_for_axis, Approx, KrlPos, KrlProgram, Located, Motion, Statement};
use millplan_geom::DVec3;
use std::fmt::Write;

/// How the cutting moves of a KRL program are written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum KrlMotion {
    /// One `LIN` per point (a `CIRC` per arc), approximated with `C_DIS`:
    /// the paper's choice, and the default.
    #[default]
    Lin,
    /// Each run of approximated moves as one `SPLINE` … `ENDSPLINE` block
    /// of `SPL` segments (`SCIRC` for arcs) through the same points; a
    /// controller keeps the programmed speed on short segments better.
    Spline,
}

impl std::str::FromStr for KrlMotion {
    type Err = String;

    /// `lin` or `spline`, as the command line names them.
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "lin" => Ok(KrlMotion::Lin),
            "spline" => Ok(KrlMotion::Spline),
            _ => Err(format!(
                "{s}: lin (one LIN per point) or spline (SPLINE blocks)"
            )),
        }
    }
}

/// The most segments the writer puts in one SPLINE block of its own: the
/// controller plans a block whole before it runs and bounds its size, so a
/// longer run goes on in the next block (`ENDSPLINE C_SPL`, approximated).
pub const SPLINE_SEGMENTS_MAX: usize = 1000;

/// The largest turn, degrees, a SPLINE block of the writer's own is
/// smoothed through when the spline would swing more than
/// [`SPLINE_SWING_MM`] there. A spline passes through its points and swings
/// outside a sharp corner between long segments (under the surface at a
/// plunge or a raster's turn), where `LIN … C_DIS` cuts inside it; there the
/// block ends exactly on the corner point and the next starts at it.
pub const SPLINE_CORNER_DEG: f64 = 20.0;

/// The largest swing, mm, of a spline off the straight lines between its
/// points that a corner may cause (estimated at the segment's middle).
pub const SPLINE_SWING_MM: f64 = 0.01;

/// How a KRL program is written.
#[derive(Clone, Debug)]
pub struct KrlOptions {
    /// The main program's name (its `DEF` and file name).
    pub name: String,
    /// Motions per sub-program; 0 writes one file whatever its length.
    pub max_points: usize,
    /// `$APO.CDIS`, mm; `None`: half the median cutting step (at most 1 mm),
    /// the controller's own bound on an approximation zone.
    pub apo_cdis: Option<f64>,
    /// Path speed of the rapids, written as straight `LIN` moves, m/s.
    pub rapid_m_s: f64,
    /// Words another dialect kept that KRL cannot express become comments
    /// (else an error at their line).
    pub lossy: bool,
    /// `LIN` per point, or SPLINE blocks.
    pub motion: KrlMotion,
}

impl Default for KrlOptions {
    fn default() -> Self {
        KrlOptions {
            name: "millplan".into(),
            max_points: 5000,
            apo_cdis: None,
            rapid_m_s: 0.5,
            lossy: false,
            motion: KrlMotion::Lin,
        }
    }
}

/// The files of a written program: (name, text), the main first.
pub type KrlFiles = Vec<(String, String)>;

/// KRL names: letters, digits and `_`, starting with a letter, at most 24.
pub fn krl_name(s: &str) -> String {
    let mut n: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .take(20)
        .collect();
    if !n.starts_with(|c: char| c.is_ascii_alphabetic()) {
        n.insert(0, 'P');
    }
    n
}

/// Writes `p`: one file, or a main calling sub-programs of `max_points`
/// motions each. A SPLINE block never straddles two files: one open at a
/// file's end is closed there with `C_SPL` (the path goes on, approximated)
/// and opened again in the next file.
pub fn write(p: &KrlProgram, o: &KrlOptions) -> KrlFiles {
    let name = krl_name(&o.name);
    let is_move = |l: &Located| matches!(l.statement, Statement::Move { .. });
    let motions = p.statements.iter().filter(|l| is_move(l)).count();
    let mut missing: Vec<String> = Vec::new();
    for (m, _, _) in &p.missing {
        if !missing.contains(m) {
            missing.push(m.clone());
        }
    }
    let mut r = Render::new(&p.statements, o.motion);
    let n = p.statements.len();
    if o.max_points == 0 || motions <= o.max_points {
        return vec![(name.clone(), file(&name, &missing, &[], &mut r, 0..n))];
    }
    // Everything before the first motion stays in the main; the rest is cut
    // into chunks of `max_points` motions.
    let first = p.statements.iter().position(is_move).unwrap_or(0);
    let mut cuts = vec![first];
    let mut count = 0;
    for (i, l) in p.statements.iter().enumerate().skip(first) {
        if is_move(l) {
            if count == o.max_points {
                cuts.push(i);
                count = 0;
            }
            count += 1;
        }
    }
    cuts.push(n);
    let subs: Vec<String> = (1..cuts.len()).map(|i| format!("{name}_{i:03}")).collect();
    let main = file(&name, &missing, &subs, &mut r, 0..first);
    let mut out = vec![(name.clone(), main)];
    for (s, w) in subs.iter().zip(cuts.windows(2)) {
        out.push((s.clone(), file(s, &missing, &[], &mut r, w[0]..w[1])));
    }
    out
}

/// The program name a KRL output at `output` takes: its file stem.
pub fn stem(output: &std::path::Path) -> String {
    let s = output.file_stem().and_then(|s| s.to_str());
    s.unwrap_or("millplan").into()
}

/// The paths of written files: the main program at `output`, each
/// sub-program beside it as `NAME.src`.
pub fn file_paths(output: &std::path::Path, files: &KrlFiles) -> Vec<std::path::PathBuf> {
    files
        .iter()
        .enumerate()
        .map(|(i, (name, _))| {
            if i == 0 {
                output.to_path_buf()
            } else {
                output.with_file_name(format!("{name}.src"))
            }
        })
        .collect()
}

/// The motions of a program, in order.
fn motions(p: &KrlProgram) -> Vec<&Statement> {
    p.statements
        .iter()
        .map(|l| &l.statement)
        .filter(|s| matches!(s, Statement::Move { .. }))
        .collect()
}

/// Whether `b`, read back, commands what `a` does within the precision
/// written (mm to 3 decimals, degrees to 4, m/s to 6): the same targets,
/// speed and options; a `LIN` may have become an `SPL`, a `CIRC` an `SCIRC`
/// (their approximation then the spline's own).
fn same_motion(a: &Statement, b: &Statement) -> bool {
    use Motion::*;
    let (
        Statement::Move {
            motion: ma,
            approx: aa,
            vel_cp: va,
            with: wa,
        },
        Statement::Move {
            motion: mb,
            approx: ab,
            vel_cp: vb,
            with: wb,
        },
    ) = (a, b)
    else {
        return a == b;
    };
    let same = aa == ab;
    let splined = *ab == Approx::Exact;
    let targets = match (ma, mb) {
        (Lin(x), Lin(y))
        | (Ptp(x), Ptp(y))
        | (Spl(x), Spl(y))
        | (Slin(x), Slin(y))
        | (Sptp(x), Sptp(y)) => same && near(x, y),
        (Lin(x), Spl(y)) => splined && near(x, y),
        (Circ { aux, end }, Circ { aux: x, end: y })
        | (Scirc { aux, end }, Scirc { aux: x, end: y }) => same && near(aux, x) && near(end, y),
        (Circ { aux, end }, Scirc { aux: x, end: y }) => splined && near(aux, x) && near(end, y),
        (PtpOther(x), PtpOther(y)) | (SptpOther(x), SptpOther(y)) => same && x == y,
        _ => false,
    };
    let vel = match (va, vb) {
        (Some(x), Some(y)) => (x - y).abs() <= 5e-7 * (1.0 + 1e-9),
        (x, y) => x == y,
    };
    targets && vel && wa == wb
}

/// Two targets the same within the digits written.
fn near(a: &KrlPos, b: &KrlPos) -> bool {
    let mm = 5e-4 * (1.0 + 1e-9) + 1e-12 * a.xyz.abs().max_element();
    let deg = 5e-5 * (1.0 + 1e-9);
    let e_same = a.e.iter().zip(&b.e).all(|(x, y)| match (x, y) {
        (Some(x), Some(y)) => (x - y).abs() <= mm,
        (x, y) => x == y,
    });
    (a.xyz - b.xyz).abs().max_element() <= mm
        && a.abc.iter().zip(&b.abc).all(|(x, y)| (x - y).abs() <= deg)
        && e_same
        && a.s == b.s
        && a.t == b.t
}

/// A one-file KRL text split by [`write()`] with `o` (a main program calling
/// sub-programs of `o.max_points` motions, its cutting moves as SPLINE
/// blocks under [`KrlMotion::Spline`]), checked: the files read back, the
/// main finding its sub-programs among them, command the motions of `text`
/// (poses, external axes, approximation, `$VEL.CP`) in the same order.
pub fn split(text: &str, o: &KrlOptions) -> Result<KrlFiles, String> {
    let k = crate::krl::read(text, &mut |_| None)
        .map_err(|e| format!("the program written does not read back: {e:?}"))?;
    let files = write(&k, o);
    check(&k, &files)?;
    Ok(files)
}

/// Reads `files` back (the main finding its sub-programs among them) and
/// compares their motions with those of `k`, the program they were
/// written from.
pub fn check(k: &KrlProgram, files: &KrlFiles) -> Result<(), String> {
    let back = crate::krl::read(&files[0].1, &mut |n| {
        files
            .iter()
            .find(|(f, _)| f.eq_ignore_ascii_case(n))
            .map(|(_, t)| t.clone())
    })
    .map_err(|e| format!("the files written do not read back: {e:?}"))?;
    let (a, b) = (motions(k), motions(&back));
    if a.len() != b.len() {
        return Err(format!(
            "the files read back hold {} motions, the program {}",
            b.len(),
            a.len()
        ));
    }
    if let Some(i) = a.iter().zip(&b).position(|(x, y)| !same_motion(x, y)) {
        return Err(format!(
            "motion {} reads back as {:?}, written {:?}",
            i + 1,
            b[i],
            a[i]
        ));
    }
    Ok(())
}

/// One file: `ext` the sub-programs its statements call that were not read
/// (declared again, so that the calls kept stay calls), `calls` those it
/// calls at its end, `range` its statements.
fn file(
    name: &str,
    ext: &[String],
    calls: &[String],
    r: &mut Render,
    range: std::ops::Range<usize>,
) -> String {
    let mut s = String::with_capacity(1 << 16);
    let _ = writeln!(s, "&ACCESS RVP\n&REL 1\nDEF {name}()");
    for c in ext.iter().chain(calls) {
        let _ = writeln!(s, "EXT {c}()");
    }
    for i in range {
        r.put(&mut s, i);
    }
    r.finish(&mut s);
    for c in calls {
        let _ = writeln!(s, "{c}()");
    }
    s.push_str("END\n");
    s
}

/// Per statement: a motion where the path turns by more than
/// [`SPLINE_CORNER_DEG`] and a spline through it (tangents from the
/// neighbouring points, as a Catmull-Rom spline takes them) would swing
/// more than [`SPLINE_SWING_MM`] off the straight line to the point before
/// or after it. Finely sampled curves turn by much at short segments and
/// swing little: they stay in one block.
fn sharp_corners(st: &[Located]) -> Vec<bool> {
    let at: Vec<(usize, DVec3)> = st
        .iter()
        .enumerate()
        .filter_map(|(i, l)| match &l.statement {
            Statement::Move { motion, .. } => motion.end().map(|p| (i, p.xyz)),
            _ => None,
        })
        .collect();
    let p = |k: isize| at[k.clamp(0, at.len() as isize - 1) as usize].1;
    let tangent = |k: isize| (p(k + 1) - p(k - 1)) * 0.5;
    // The midpoint of the Hermite cubic from k to k + 1 lies (T_k − T_k+1)/8
    // from the chord's; its part across the chord is the swing.
    let swing = |k: isize| {
        let chord = p(k + 1) - p(k);
        let d = (tangent(k) - tangent(k + 1)) / 8.0;
        let l2 = chord.length_squared();
        if l2 > 0.0 {
            (d - chord * (d.dot(chord) / l2)).length()
        } else {
            0.0
        }
    };
    let cos_max = SPLINE_CORNER_DEG.to_radians().cos();
    let mut out = vec![false; st.len()];
    for k in 1..at.len().saturating_sub(1) {
        let k = k as isize;
        let (u, v) = (p(k) - p(k - 1), p(k + 1) - p(k));
        let (lu, lv) = (u.length(), v.length());
        let turns = lu > 0.0 && lv > 0.0 && u.dot(v) < cos_max * lu * lv;
        out[at[k as usize].0] = turns && swing(k - 1).max(swing(k)) > SPLINE_SWING_MM;
    }
    out
}

/// The statements of a program written in the order the controller runs
/// them, file after file: the path speed written so far and the one in
/// force, the SPLINE blocks open.
struct Render<'a> {
    st: &'a [Located],
    /// Per statement: a `LIN` or `CIRC` written as a segment of a SPLINE
    /// block of the writer's own ([`KrlMotion::Spline`]): an approximated
    /// one, or the one ending a run of them.
    seg: Vec<bool>,
    /// Per segment: approximated, and the next motion a segment too (the
    /// path goes on without a stop).
    cont: Vec<bool>,
    /// `$VEL.CP` as the files written so far set it, and as the program has it.
    written_vel: Option<f64>,
    vel: Option<f64>,
    /// A block of the writer's own is open, with this many segments.
    ours: bool,
    segments: usize,
    /// A block read with the program: its `SPLINE` line, and whether that
    /// line is written yet (it waits for the block's first statement, so
    /// that no file holds an empty block).
    theirs: Option<(&'a Statement, bool)>,
    /// Comments read after that `SPLINE` line while it waits: written
    /// after it when it is, in the order read.
    held: Vec<&'a Statement>,
}

impl<'a> Render<'a> {
    fn new(st: &'a [Located], motion: KrlMotion) -> Render<'a> {
        let n = st.len();
        let (mut seg, mut cont) = (vec![false; n], vec![false; n]);
        if motion == KrlMotion::Spline {
            let mut prev_dis = false;
            for (i, l) in st.iter().enumerate() {
                if let Statement::Move { motion, approx, .. } = &l.statement {
                    let lin = matches!(motion, Motion::Lin(_) | Motion::Circ { .. });
                    seg[i] = lin && (*approx == Approx::Dis || prev_dis);
                    prev_dis = seg[i] && *approx == Approx::Dis;
                }
            }
            let corner = sharp_corners(st);
            let mut next_seg = false;
            for (i, l) in st.iter().enumerate().rev() {
                if let Statement::Move { approx, .. } = &l.statement {
                    cont[i] = seg[i] && *approx == Approx::Dis && next_seg && !corner[i];
                    next_seg = seg[i];
                }
            }
        }
        Render {
            st,
            seg,
            cont,
            written_vel: None,
            vel: None,
            ours: false,
            segments: 0,
            theirs: None,
            held: Vec::new(),
        }
    }

    /// Writes statement `i`.
    fn put(&mut self, s: &mut String, i: usize) {
        let l = &self.st[i];
        if self.seg[i] {
            if self.ours && self.segments == SPLINE_SEGMENTS_MAX {
                self.close(s, true);
            }
            if !self.ours {
                s.push_str("SPLINE\n");
                (self.ours, self.segments) = (true, 0);
            }
            self.segment(s, &l.statement, true);
            self.segments += 1;
            if !self.cont[i] {
                self.close(s, false);
            }
            return;
        }
        let comment = matches!(&l.statement, Statement::Verbatim(t) if t.starts_with(';'));
        if self.ours {
            match &l.statement {
                Statement::VelCp(v) => return self.vel = Some(*v),
                _ if comment => return statement(s, &l.statement),
                _ => self.close(s, true),
            }
        }
        match &l.statement {
            Statement::SplineBegin(_) => return self.theirs = Some((&l.statement, false)),
            Statement::SplineEnd(_) => self.open_theirs(s),
            _ if comment => {
                if let Some((_, false)) = self.theirs {
                    return self.held.push(&l.statement);
                }
            }
            _ => self.open_theirs(s),
        }
        match &l.statement {
            Statement::SplineEnd(_) => self.theirs = None,
            Statement::VelCp(v) | Statement::Vel { cp: Some(v), .. } => {
                self.vel = Some(*v);
                self.written_vel = Some(*v);
            }
            Statement::Move { motion, .. } if motion.is_spline() => {
                return self.segment(s, &l.statement, false)
            }
            _ => {}
        }
        statement(s, &l.statement);
    }

    /// Writes the `SPLINE` line of a block read, if it waits, and the
    /// comments held after it.
    fn open_theirs(&mut self, s: &mut String) {
        if let Some((b, false)) = self.theirs {
            statement(s, b);
            self.theirs = Some((b, true));
            for c in self.held.drain(..) {
                statement(s, c);
            }
        }
    }

    /// Closes the writer's block, approximated or not; then the path speed
    /// the program has, where the block's segments carried it alone.
    fn close(&mut self, s: &mut String, approx: bool) {
        s.push_str(if approx {
            "ENDSPLINE C_SPL\n"
        } else {
            "ENDSPLINE\n"
        });
        self.ours = false;
        if self.vel != self.written_vel {
            if let Some(v) = self.vel {
                let _ = writeln!(s, "$VEL.CP = {v:.6}");
            }
            self.written_vel = self.vel;
        }
    }

    /// The end of a file: a block open is closed, approximated, to be
    /// opened again by the next file's first statement in it.
    fn finish(&mut self, s: &mut String) {
        if self.ours {
            self.close(s, true);
        }
        if let Some((b, true)) = self.theirs {
            s.push_str("ENDSPLINE C_SPL\n");
            self.theirs = Some((b, false));
        }
    }

    /// A spline segment: `SPL`/`SCIRC` for a `LIN`/`CIRC` of the writer's
    /// block (`ours`), else as read; its own `WITH $VEL.CP` where its speed
    /// is not the one written, and the options read.
    fn segment(&self, s: &mut String, st: &Statement, ours: bool) {
        let Statement::Move {
            motion,
            approx,
            vel_cp,
            with,
        } = st
        else {
            return;
        };
        match motion {
            Motion::Lin(p) if ours => motion_text(s, &Motion::Spl(*p)),
            Motion::Circ { aux, end } if ours => motion_text(
                s,
                &Motion::Scirc {
                    aux: *aux,
                    end: *end,
                },
            ),
            _ => motion_text(s, motion),
        }
        let own_vel = with.iter().any(|w| crate::krl::sets_path_speed(w));
        let mut opts: Vec<String> = Vec::new();
        if let (Some(v), false) = (vel_cp, own_vel) {
            if Some(*v) != self.written_vel {
                opts.push(format!("$VEL.CP = {v:.6}"));
            }
        }
        opts.extend(with.iter().cloned());
        if !opts.is_empty() {
            let _ = write!(s, " WITH {}", opts.join(", "));
        }
        s.push_str(if ours { "\n" } else { approx_tag(*approx) });
    }
}

fn approx_tag(a: Approx) -> &'static str {
    match a {
        Approx::Exact => "\n",
        Approx::Dis => " C_DIS\n",
        Approx::Vel => " C_VEL\n",
        Approx::Ori => " C_ORI\n",
        Approx::Spl => " C_SPL\n",
        Approx::Ptp => " C_PTP\n",
        Approx::PtpDis => " C_PTP C_DIS\n",
        Approx::PtpOri => " C_PTP C_ORI\n",
        Approx::PtpVel => " C_PTP C_VEL\n",
    }
}

fn pos(s: &mut String, p: &KrlPos) {
    let [a, b, c] = p.abc.map(|v| if v.abs() < 5e-5 { 0.0 } else { v });
    let _ = write!(
        s,
        "{{X {:.3}, Y {:.3}, Z {:.3}, A {a:.4}, B {b:.4}, C {c:.4}",
        p.xyz.x, p.xyz.y, p.xyz.z
    );
    for (i, e) in p.e.iter().enumerate() {
        if let Some(e) = e {
            let _ = write!(s, ", E{} {e:.3}", i + 1);
        }
    }
    if let Some(v) = p.s {
        let _ = write!(s, ", S {v}");
    }
    if let Some(v) = p.t {
        let _ = write!(s, ", T {v}");
    }
    s.push('}');
}

fn statement(s: &mut String, st: &Statement) {
    match st {
        Statement::Move { motion, approx, .. } => {
            motion_text(s, motion);
            s.push_str(approx_tag(*approx));
        }
        Statement::SplineBegin(with) if with.is_empty() => s.push_str("SPLINE\n"),
        Statement::SplineBegin(with) => {
            let _ = writeln!(s, "SPLINE WITH {}", with.join(", "));
        }
        Statement::SplineEnd(true) => s.push_str("ENDSPLINE C_SPL\n"),
        Statement::SplineEnd(false) => s.push_str("ENDSPLINE\n"),
        Statement::VelCp(v) => {
            let _ = writeln!(s, "$VEL.CP = {v:.6}");
        }
        Statement::Vel { text, .. } => {
            let _ = writeln!(s, "$VEL = {text}");
        }
        Statement::ApoCdis(v) => {
            let _ = writeln!(s, "$APO.CDIS = {v:.3}");
        }
        Statement::Tool(t) => {
            let _ = writeln!(s, "$TOOL = {t}");
        }
        Statement::Base(b) => {
            let _ = writeln!(s, "$BASE = {b}");
        }
        Statement::Verbatim(t) => {
            let _ = writeln!(s, "{t}");
        }
    }
}

/// A motion's keyword and targets, as read.
fn motion_text(s: &mut String, motion: &Motion) {
    let (word, aux, end) = match motion {
        Motion::PtpOther(t) => {
            let _ = write!(s, "PTP {t}");
            return;
        }
        Motion::SptpOther(t) => {
            let _ = write!(s, "SPTP {t}");
            return;
        }
        Motion::Sptp(p) => ("SPTP", None, p),
        Motion::Lin(p) => ("LIN", None, p),
        Motion::Ptp(p) => ("PTP", None, p),
        Motion::Spl(p) => ("SPL", None, p),
        Motion::Slin(p) => ("SLIN", None, p),
        Motion::Circ { aux, end } => ("CIRC", Some(aux), end),
        Motion::Scirc { aux, end } => ("SCIRC", Some(aux), end),
    };
    s.push_str(word);
    s.push(' ');
    if let Some(a) = aux {
        pos(s, a);
        s.push_str(", ");
    }
    pos(s, end);
}

/// `$VEL.CP` for a feed in mm/min: m/s (T17: 1120 mm/min → 0.018667).
pub fn vel_cp(feed_mm_min: f64) -> f64 {
    feed_mm_min / 60_000.0
}

/// A KRL program for a toolpath: the first move a `PTP` (the approach),
/// every cutting point one `LIN` (arcs `CIRC` through their midpoint), the
/// rapids straight `LIN`s at `rapid_m_s`. Cycles, unknown positions and
/// operation frames are refused at their line.
pub fn from_ir(prog: &Program, o: &KrlOptions) -> Result<KrlProgram, ParseError> {
    let mut p = KrlProgram {
        name: krl_name(&o.name),
        files: vec![krl_name(&o.name)],
        ..KrlProgram::default()
    };
    let cdis = o.apo_cdis.unwrap_or_else(|| auto_cdis(prog));
    push(&mut p, 0, Statement::Verbatim("BAS(#INITMOV, 0)".into()));
    push(&mut p, 0, Statement::Verbatim("$ADVANCE = 3".into()));
    push(&mut p, 0, Statement::ApoCdis(cdis));
    let mut vel: Option<f64> = None;
    let mut first = true;
    for op in &prog.operations {
        if op.frame.is_some() {
            let line = op.moves.first().map_or(1, |m| m.line.max(1));
            return Err(ParseError::new(
                line,
                1,
                "an operation in a frame of its own: KRL is written in the base's coordinates only",
            ));
        }
        let mut ev = op.events.iter().peekable();
        for (i, m) in op.moves.iter().enumerate() {
            while let Some(e) = ev.next_if(|e| e.at as usize <= i) {
                event(&mut p, prog.source, e, o.lossy)?;
            }
            if !m.end.is_finite() {
                return Err(ParseError::new(
                    m.line.max(1),
                    1,
                    "a position not known here (after a machine move): KRL needs every coordinate",
                ));
            }
            let axis = op.axis(m).unwrap_or(DVec3::Z);
            let target = KrlPos {
                xyz: m.end,
                abc: abc_for_axis(axis),
                e: [None; 6],
                s: None,
                t: None,
            };
            let rapid = m.kind == MoveKind::Rapid;
            let speed = if rapid { o.rapid_m_s } else { vel_cp(m.feed) };
            if !first && vel != Some(speed) {
                push(&mut p, m.line, Statement::VelCp(speed));
                vel = Some(speed);
            }
            let next_rapid = op
                .moves
                .get(i + 1)
                .is_none_or(|n| n.kind == MoveKind::Rapid);
            let approx = if rapid || next_rapid || first {
                Approx::Exact
            } else {
                Approx::Dis
            };
            let motion = match m.kind {
                _ if first => Motion::Ptp(target),
                MoveKind::Cycle(_) => return Err(ParseError::new(
                    m.line.max(1),
                    1,
                    "a canned cycle: KRL has none; write the program with the cycle spelled out",
                )),
                MoveKind::Arc(id) => {
                    let arc = &op.arcs[id.index()];
                    let start = p_last(&p).unwrap_or(m.end);
                    let mid = arc_mid(arc, start, m.end);
                    Motion::Circ {
                        aux: KrlPos { xyz: mid, ..target },
                        end: target,
                    }
                }
                _ => Motion::Lin(target),
            };
            first = false;
            push_move(&mut p, m.line, motion, approx, vel);
        }
        for e in ev {
            event(&mut p, prog.source, e, o.lossy)?;
        }
    }
    Ok(p)
}

fn push(p: &mut KrlProgram, line: u32, statement: Statement) {
    p.statements.push(Located {
        file: 0,
        line,
        statement,
    });
}

fn push_move(p: &mut KrlProgram, line: u32, motion: Motion, approx: Approx, vel: Option<f64>) {
    push(
        p,
        line,
        Statement::Move {
            motion,
            approx,
            vel_cp: vel,
            with: Vec::new(),
        },
    );
}

fn p_last(p: &KrlProgram) -> Option<DVec3> {
    p.statements.iter().rev().find_map(|l| match &l.statement {
        Statement::Move {
            motion: Motion::Lin(x) | Motion::Ptp(x),
            ..
        } => Some(x.xyz),
        Statement::Move {
            motion: Motion::Circ { end, .. },
            ..
        } => Some(end.xyz),
        _ => None,
    })
}

/// The point halfway along `arc` from `start` to `end` (a helix rises half way).
fn arc_mid(arc: &crate::ir::Arc, start: DVec3, end: DVec3) -> DVec3 {
    let rot = millplan_geom::DMat3::from_axis_angle(arc.normal, arc.sweep / 2.0);
    arc.centre + rot * (start - arc.centre) + arc.normal * ((end - start).dot(arc.normal) / 2.0)
}

fn event(
    p: &mut KrlProgram,
    source: Dialect,
    e: &crate::ir::Event,
    lossy: bool,
) -> Result<(), ParseError> {
    let st = match &e.kind {
        EventKind::Comment(c) => Statement::Verbatim(format!("; {c}")),
        EventKind::Passthrough(t) if source == Dialect::Krl => {
            match crate::krl::statement_of(&t.text) {
                // The blocks of a source read: its moves come back as
                // `LIN`s, which a SPLINE block cannot hold; the writer's
                // `motion` makes blocks of its own.
                Some(Statement::SplineBegin(_) | Statement::SplineEnd(_)) => return Ok(()),
                Some(s) => s,
                None => Statement::Verbatim(t.text.clone()),
            }
        }
        EventKind::Passthrough(t) if t.class == PassClass::Machine && !lossy => {
            return Err(ParseError::new(
                e.line.max(1),
                1,
                format!(
                    "{}: KRL cannot express it (--lossy keeps it as a comment)",
                    t.text
                ),
            ));
        }
        EventKind::Passthrough(t) => Statement::Verbatim(format!("; {}", t.text)),
        other => Statement::Verbatim(format!("; {other:?}")),
    };
    push(p, e.line, st);
    Ok(())
}

/// Half the median cutting step, at most 1 mm (T17: 0.3 mm → 0.15).
fn auto_cdis(prog: &Program) -> f64 {
    let mut steps = Vec::new();
    for op in &prog.operations {
        for w in op.moves.windows(2) {
            if w[1].kind != MoveKind::Rapid {
                let d = (w[1].end - w[0].end).length();
                if d.is_finite() && d > 0.0 {
                    steps.push(d);
                }
            }
        }
    }
    if steps.is_empty() {
        return 0.1;
    }
    let mid = steps.len() / 2;
    let (_, m, _) = steps.select_nth_unstable_by(mid, f64::total_cmp);
    ((*m / 2.0).min(1.0) * 1000.0).floor() / 1000.0
}

/// The writer of [`super::write_program_to`] for [`super::Target::Krl`]: a
/// toolpath as one KRL file (no sub-programs: one output, one file), named
/// after the program.
pub(crate) fn write_ir_to(
    prog: &Program,
    o: &super::WriteOptions,
    out: &mut Vec<u8>,
    sink: Option<super::Sink>,
) -> Result<super::Written, super::WriteError> {
    let ko = KrlOptions {
        name: prog.name.clone().unwrap_or_else(|| "millplan".into()),
        max_points: 0,
        lossy: o.lossy,
        ..KrlOptions::default()
    };
    let k = from_ir(prog, &ko).map_err(|e| super::WriteError::new(e.line, e.message))?;
    let (_, text) = write(&k, &ko).swap_remove(0);
    out.extend_from_slice(text.as_bytes());
    if let Some(s) = sink {
        s(out)?;
        out.clear();
    }
    Ok(Vec::new())
}

/// A program read as KRL, written for `target`. KRL itself: from the program
/// as read, one file (`Some`): poses A, B, C, external axes, Status and
/// Turn, speeds and verbatim lines kept, the sub-programs read inline and
/// those missing still called. Another dialect is written from the IR
/// (`None`), an external axis being refused at its line unless `lossy`.
pub fn from_krl(
    k: &KrlProgram,
    target: super::Target,
    lossy: bool,
) -> Result<Option<String>, crate::krl::KrlError> {
    if target == super::Target::Krl {
        let o = KrlOptions {
            name: k.name.clone(),
            max_points: 0,
            ..KrlOptions::default()
        };
        return Ok(Some(write(k, &o).swap_remove(0).1));
    }
    if !lossy {
        k.to_ir(1.0, false)?;
    }
    Ok(None)
}
