//! The KUKA KRL writer (process-models §5): a main `.SRC` program and, past
//! a configurable number of motions, sub-programs it calls.
//!
//! Units: mm and degrees in positions (3 decimals for mm, 4 for degrees),
//! `$VEL.CP` in m/s with 6 decimals, `$APO.CDIS` in mm. Every cutting point
//! is one `LIN` (the faithful default; `SPLINE` blocks are not written),
//! approximated with `C_DIS` except the last one before a rapid or the end.
//! From the IR the tool axis becomes an orientation A, B, C (the tool along
//! the tool frame's x; turned about the axis as little as possible from the
//! tool pointing down, A = C = 0, B = 90°).

use crate::diag::ParseError;
use crate::ir::{Dialect, EventKind, MoveKind, PassClass, Program};
use crate::krl::{abc_for_axis, Approx, KrlPos, KrlProgram, Located, Motion, Statement};
use millplan_geom::DVec3;
use std::fmt::Write;

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
}

impl Default for KrlOptions {
    fn default() -> Self {
        KrlOptions {
            name: "millplan".into(),
            max_points: 5000,
            apo_cdis: None,
            rapid_m_s: 0.5,
            lossy: false,
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
/// motions each.
pub fn write(p: &KrlProgram, o: &KrlOptions) -> KrlFiles {
    let name = krl_name(&o.name);
    let motions = p
        .statements
        .iter()
        .filter(|l| matches!(l.statement, Statement::Move { .. }))
        .count();
    let mut missing: Vec<String> = Vec::new();
    for (m, _, _) in &p.missing {
        if !missing.contains(m) {
            missing.push(m.clone());
        }
    }
    if o.max_points == 0 || motions <= o.max_points {
        return vec![(
            name.clone(),
            file(&name, &missing, &[], p.statements.iter()),
        )];
    }
    // Everything before the first motion stays in the main; the rest is cut
    // into chunks of `max_points` motions.
    let first = p
        .statements
        .iter()
        .position(|l| matches!(l.statement, Statement::Move { .. }))
        .unwrap_or(0);
    let mut chunks: Vec<Vec<&Located>> = vec![Vec::new()];
    let mut count = 0;
    for l in &p.statements[first..] {
        if matches!(l.statement, Statement::Move { .. }) {
            if count == o.max_points {
                chunks.push(Vec::new());
                count = 0;
            }
            count += 1;
        }
        chunks.last_mut().expect("one chunk").push(l);
    }
    let subs: Vec<String> = (1..=chunks.len())
        .map(|i| format!("{name}_{i:03}"))
        .collect();
    let mut out = vec![(
        name.clone(),
        file(&name, &missing, &subs, p.statements[..first].iter()),
    )];
    for (s, chunk) in subs.iter().zip(chunks) {
        out.push((s.clone(), file(s, &missing, &[], chunk.into_iter())));
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

/// A one-file KRL text split by [`write()`] with `o` (a main program calling
/// sub-programs of `o.max_points` motions), checked: the files read back,
/// the main finding its sub-programs among them, command the motions of
/// `text` (poses, approximation, `$VEL.CP`) in the same order.
pub fn split(text: &str, o: &KrlOptions) -> Result<KrlFiles, String> {
    let k = crate::krl::read(text, &mut |_| None)
        .map_err(|e| format!("the program written does not read back: {e:?}"))?;
    let files = write(&k, o);
    let back = crate::krl::read(&files[0].1, &mut |n| {
        files
            .iter()
            .find(|(f, _)| f.eq_ignore_ascii_case(n))
            .map(|(_, t)| t.clone())
    })
    .map_err(|e| format!("the sub-programs written do not read back: {e:?}"))?;
    let (a, b) = (motions(&k), motions(&back));
    if a.len() != b.len() {
        return Err(format!(
            "the sub-programs read back hold {} motions, the program {}",
            b.len(),
            a.len()
        ));
    }
    if let Some(i) = a.iter().zip(&b).position(|(x, y)| x != y) {
        return Err(format!(
            "motion {} reads back as {:?}, written {:?}",
            i + 1,
            b[i],
            a[i]
        ));
    }
    Ok(files)
}

/// One file: `ext` the sub-programs its statements call that were not read
/// (declared again, so that the calls kept stay calls), `calls` those it
/// calls at its end.
fn file<'a>(
    name: &str,
    ext: &[String],
    calls: &[String],
    body: impl Iterator<Item = &'a Located>,
) -> String {
    let mut s = String::with_capacity(1 << 16);
    let _ = writeln!(s, "&ACCESS RVP\n&REL 1\nDEF {name}()");
    for c in ext.iter().chain(calls) {
        let _ = writeln!(s, "EXT {c}()");
    }
    for l in body {
        statement(&mut s, &l.statement);
    }
    for c in calls {
        let _ = writeln!(s, "{c}()");
    }
    s.push_str("END\n");
    s
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
            match motion {
                Motion::Lin(p) => {
                    s.push_str("LIN ");
                    pos(s, p);
                }
                Motion::Ptp(p) => {
                    s.push_str("PTP ");
                    pos(s, p);
                }
                Motion::Circ { aux, end } => {
                    s.push_str("CIRC ");
                    pos(s, aux);
                    s.push_str(", ");
                    pos(s, end);
                }
                Motion::PtpOther(t) => {
                    let _ = write!(s, "PTP {t}");
                }
            }
            s.push_str(match approx {
                Approx::Exact => "\n",
                Approx::Dis => " C_DIS\n",
                Approx::Vel => " C_VEL\n",
                Approx::Ori => " C_ORI\n",
            });
        }
        Statement::VelCp(v) => {
            let _ = writeln!(s, "$VEL.CP = {v:.6}");
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
