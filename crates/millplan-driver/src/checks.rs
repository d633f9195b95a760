//! The checks of a written program, run on the program re-read from its own
//! bytes before it is renamed into place. Each says what it checked and what
//! it found; a finding the input already had is marked `in_input` and
//! refuses the output only where the check says so (a rapid through
//! material, a holder or shank collision: always).

use crate::defaults::Defaults;
use millplan_geom::TriMesh;
use millplan_nc::equiv::{compare, Tolerance};
use millplan_nc::{FeedMode, Program};
use millplan_plan::force::{FeedLimits, ForceRun};
use millplan_plan::machine::Machine;
use millplan_sim::dropcutter::DropMesh;
use millplan_sim::gouge::{check as gouge_check, GougeParams, GougeReport};
use millplan_sim::stock::path::Strokes;
use millplan_sim::stock::run::{run as run_sim, Collision};
use millplan_sim::stock::Stock;
use serde::Serialize;

/// One finding of a check.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Finding {
    /// Source line of the written program (0: none).
    pub line: u32,
    pub message: String,
    /// The input had it already.
    pub in_input: bool,
}

/// One check: whether it passed, what it covered, what it found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Check {
    pub name: &'static str,
    pub ok: bool,
    /// What it checked (or why it could not).
    pub checked: String,
    pub findings: Vec<Finding>,
}

impl Check {
    fn new(name: &'static str, checked: String, findings: Vec<Finding>, ok: bool) -> Check {
        Check {
            name,
            ok,
            checked,
            findings,
        }
    }

    /// The first finding that refuses the output: its line and words.
    pub fn first_refusal(&self) -> Option<&Finding> {
        (!self.ok).then(|| {
            self.findings
                .iter()
                .find(|f| !f.in_input)
                .or(self.findings.first())
        })?
    }
}

/// The written bytes read back: they must parse and command what the
/// optimised program does (`equiv::compare`), and pass the IR verifier.
pub fn read_back(out: &Program, bytes: &[u8]) -> (Option<Program>, Check) {
    let text = String::from_utf8_lossy(bytes);
    let parsed = match millplan_nc::parse_program(&text, millplan_nc::ReadOptions::default()) {
        Ok(p) => p,
        Err(e) => {
            let f = vec![finding(
                e.line as u32,
                format!("does not read back: {e}"),
                false,
            )];
            return (
                None,
                Check::new("read-back", "the written bytes".into(), f, false),
            );
        }
    };
    let mut f: Vec<Finding> = millplan_nc::verify::verify(&parsed.program)
        .err()
        .unwrap_or_default()
        .iter()
        .map(|v| finding(0, format!("IR verifier: {v}"), false))
        .collect();
    if let Err(m) = compare(out, &parsed.program, &Tolerance::default()) {
        f.push(finding(
            m.line_b,
            format!("does not command what the optimised program does: {m}"),
            false,
        ));
    }
    let checked = format!("{} moves re-read and compared", parsed.program.move_count());
    let ok = f.is_empty();
    let mut back = parsed.program;
    same_tools(&mut back, out);
    (Some(back), Check::new("read-back", checked, f, ok))
}

/// A dialect that names tools by number only (G-code) loses their shape:
/// the re-read program's operations take the shapes of the program written,
/// so every later check runs with the same tools; and where its moves are
/// those written one for one, their source lines, so findings name the
/// input's lines.
fn same_tools(back: &mut Program, out: &Program) {
    if back.operations.len() != out.operations.len() {
        return;
    }
    for (b, o) in back.operations.iter_mut().zip(&out.operations) {
        if b.moves.len() == o.moves.len() {
            for (x, y) in b.moves.iter_mut().zip(&o.moves) {
                x.line = y.line;
            }
        }
        let Some(ot) = &o.tool else { continue };
        match &mut b.tool {
            Some(bt) if bt.cutter.is_none() => bt.cutter = ot.cutter,
            None => b.tool = Some(ot.clone()),
            _ => {}
        }
    }
}

fn finding(line: u32, message: String, in_input: bool) -> Finding {
    Finding {
        line,
        message,
        in_input,
    }
}

/// The program and its input on the stock: a rapid through material or a
/// shank or holder in material refuses the output, the input's own marked.
pub fn collisions(stock: &Stock, input: &Strokes, output: &Strokes, tol: f64) -> Check {
    let hits = |s: &Strokes| {
        let rep = run_sim(&mut stock.clone(), s, tol, &|_| {});
        (rep.simulated, rep.rapid_collisions, rep.holder_collisions)
    };
    let (_, ri, hi) = hits(input);
    let (n, ro, ho) = hits(output);
    let had = |v: &[Collision], c: &Collision| v.iter().any(|x| x.line == c.line);
    let mut f = Vec::new();
    for c in &ro {
        let m = format!("rapid into material, {:.3} mm deep", c.depth);
        f.push(finding(c.line, m, had(&ri, c)));
    }
    for c in &ho {
        let m = format!("shank or holder in material, {:.3} mm deep", c.depth);
        f.push(finding(c.line, m, had(&hi, c)));
    }
    let ok = f.is_empty();
    Check::new(
        "rapids-and-holder",
        format!("{n} moves simulated on the stock"),
        f,
        ok,
    )
}

/// Loads of the written program under every limit, within
/// [`Defaults::LOAD_SLACK`].
pub fn loads(after: &ForceRun, before: &ForceRun, l: &FeedLimits, m: &Machine) -> Check {
    let slack = 1.0 + Defaults::LOAD_SLACK;
    let loose = FeedLimits {
        fxy: l.fxy.map(|v| v * slack),
        torque: l.torque.map(|v| v * slack),
        power: l.power.map(|v| v * slack),
        stress: l.stress.map(|v| v * slack),
        deflection: l.deflection.map(|v| v * slack),
        fos: l.fos / slack,
        ..*l
    };
    let was: std::collections::BTreeSet<u32> = before
        .over_limits(&loose, m)
        .iter()
        .map(|x| x.line)
        .collect();
    let f: Vec<Finding> = after
        .over_limits(&loose, m)
        .iter()
        .map(|x| {
            finding(
                x.line,
                format!(
                    "over a load limit (F_xy {:.1} N, torque {:.1} N·mm, power {:.1} W)",
                    x.fxy_max, x.torque_max, x.power_w
                ),
                was.contains(&x.line),
            )
        })
        .collect();
    let ok = f.is_empty();
    let checked = format!(
        "{} moves' loads against the limits (+{} % model resolution)",
        after.moves.len(),
        Defaults::LOAD_SLACK * 100.0
    );
    Check::new("loads", checked, f, ok)
}

/// Every spindle speed in the machine's range and every per-minute cutting
/// feed in its feed range.
pub fn machine(p: &Program, m: &Machine) -> Check {
    let mut f = Vec::new();
    let mut n = 0;
    for mv in p.moves().filter(|x| x.is_cutting()) {
        n += 1;
        if mv.spindle > 0.0
            && !(mv.spindle >= m.spindle_min * 0.999 && mv.spindle <= m.spindle_max * 1.001)
        {
            f.push(finding(
                mv.line,
                format!(
                    "S{} outside the spindle's {}–{} 1/min",
                    mv.spindle, m.spindle_min, m.spindle_max
                ),
                false,
            ));
        }
        if mv.feed_mode == FeedMode::PerMinute && !(mv.feed > 0.0 && mv.feed <= m.feed_max * 1.001)
        {
            f.push(finding(
                mv.line,
                format!(
                    "F{} outside the machine's feed range (max {} mm/min)",
                    mv.feed, m.feed_max
                ),
                false,
            ));
        }
    }
    let ok = f.is_empty();
    Check::new("machine", format!("{n} cutting moves' S and F"), f, ok)
}

/// The tool tip where the input put it: move by move when no pass moved or
/// reordered points; else every cutting point of the input still cut.
pub fn tips(input: &Program, out: &Program, reordered: bool, tol: f64) -> Check {
    let mut f = Vec::new();
    if !reordered {
        let a: Vec<_> = input.moves().collect();
        let b: Vec<_> = out.moves().collect();
        if a.len() != b.len() {
            f.push(finding(
                0,
                format!("{} moves became {}", a.len(), b.len()),
                false,
            ));
        }
        for (x, y) in a.iter().zip(&b) {
            let d = (x.end - y.end).length();
            if d > tol && !(x.end.is_nan() && y.end.is_nan()) && !d.is_nan() {
                f.push(finding(
                    y.line,
                    format!("tip moved {d:.4} mm from the input's line {}", x.line),
                    false,
                ));
            }
        }
        let ok = f.is_empty();
        return Check::new("tip", format!("{} moves' positions", a.len()), f, ok);
    }
    let key = |v: millplan_geom::DVec3| {
        (
            (v.x / tol).round() as i64,
            (v.y / tol).round() as i64,
            (v.z / tol).round() as i64,
        )
    };
    let cut: std::collections::BTreeSet<_> = out
        .moves()
        .filter(|m| m.is_cutting() && !m.end.is_nan())
        .map(|m| key(m.end))
        .collect();
    let mut n = 0;
    for m in input.moves().filter(|m| m.is_cutting() && !m.end.is_nan()) {
        n += 1;
        if !cut.contains(&key(m.end)) {
            f.push(finding(
                m.line,
                "a cutting point of the input is not cut".into(),
                false,
            ));
        }
    }
    let ok = f.is_empty();
    Check::new(
        "tip",
        format!("{n} cutting points of the input (reordered)"),
        f,
        ok,
    )
}

/// Gouges of the output the input did not have (by place, within `tol`).
pub fn gouges(
    part: &TriMesh,
    input: &Program,
    out: &Program,
    shape: &dyn Fn(&millplan_nc::Operation) -> Option<millplan_models::cutter::Shape>,
    tol: f64,
) -> Check {
    let dm = DropMesh::new(part);
    let g = GougeParams {
        tol: tol.max(GougeParams::default().tol),
        ..GougeParams::default()
    };
    let a: GougeReport = gouge_check(input, &dm, shape, &g);
    let b: GougeReport = gouge_check(out, &dm, shape, &g);
    let near = |p: [f64; 3]| {
        a.gouges.iter().any(|x| {
            let d: f64 = x.at.iter().zip(p).map(|(u, v)| (u - v) * (u - v)).sum();
            d.sqrt() <= 2.0 * g.step
        })
    };
    let f: Vec<Finding> = b
        .gouges
        .iter()
        .map(|x| finding(x.line, format!("gouge {:.3} mm deep", x.depth), near(x.at)))
        .collect();
    let ok = f.iter().all(|x| x.in_input);
    Check::new(
        "gouge",
        format!(
            "{} points of {} moves against the part",
            b.points_checked, b.moves_checked
        ),
        f,
        ok,
    )
}
