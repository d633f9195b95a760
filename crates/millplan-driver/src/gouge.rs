//! `millplan gouge`: the checked options, the cutter per operation, the
//! sample count before any work, the check, the run (`run_command`) and
//! the typed summary.

use crate::check::{arg, tool_shape, Range};
use millplan_models::cutter::Shape;
use millplan_nc::{MoveKind, Operation, Program};
use millplan_sim::dropcutter::DropMesh;
use millplan_sim::gouge::{check_with_progress, samples, Skipped};
pub use millplan_sim::gouge::{GougeParams, GougeReport, BYTES_PER_SAMPLE};
use millplan_sim::stock::tool::{ToolBody, UNKNOWN_FLUTE};
use serde::Serialize;
use std::fmt::Write as _;

mod command;
pub use command::{nothing_checked, run_command, GougeCommand};

/// The options of `millplan gouge`.
#[derive(Clone, Debug)]
pub struct GougeRequest {
    pub tol: f64,
    pub step: f64,
    pub rapids: bool,
    /// The cutter of operations that name none.
    pub tool: Option<String>,
}

/// The options checked: the check's parameters and the fallback cutter.
pub fn params(a: &GougeRequest) -> Result<(GougeParams, Option<Shape>), String> {
    arg("--tol", a.tol, Range::from(0.0, 100.0, "mm"))?;
    arg("--step", a.step, Range::from(0.001, 1000.0, "mm"))?;
    let fallback = a
        .tool
        .as_deref()
        .map(|s| tool_shape("--tool", s))
        .transpose()?;
    let g = GougeParams {
        step: a.step,
        tol: a.tol,
        rapids: a.rapids,
    };
    Ok((g, fallback))
}

/// Without a fallback cutter, an operation that cuts must name its own:
/// else an error at the tool's line in `path`.
pub fn shape_is_known(path: &str, program: &Program) -> Result<(), String> {
    if let Some(op) = program.operations.iter().find(|op| {
        let cuts = |m: &millplan_nc::Move| m.is_cutting() || matches!(m.kind, MoveKind::Cycle(_));
        op.moves.iter().any(cuts) && op.tool.as_ref().and_then(|t| t.cutter).is_none()
    }) {
        let line = op.tool.as_ref().map_or(0, |t| t.line);
        return Err(format!(
            "{path}:{line}:1: the program does not say the shape of its tool; give it with --tool (ball:D, flat:D, bull:D:R, cone:D:ANGLE)"
        ));
    }
    Ok(())
}

/// The tool of an operation: its own cutter, else the fallback; fluted up
/// to the CUTTER record's height where it gives one, else all along (as
/// the drop-cutter takes a vertical tool).
fn body(fallback: Option<Shape>) -> impl Fn(&Operation) -> Option<ToolBody> {
    move |op: &Operation| {
        let cutter = op.tool.as_ref().and_then(|t| t.cutter);
        let shape = match cutter {
            Some(c) => millplan_sim::shape_of(&c),
            None => fallback,
        }?;
        let mut b = ToolBody::new(shape);
        b.flute = cutter
            .map(|c| c.h)
            .filter(|h| *h > 0.0)
            .unwrap_or(UNKNOWN_FLUTE);
        Some(b)
    }
}

/// Points from which the check shows its progress (some 300,000 points a
/// second: a second's worth).
pub const SHOWN_SAMPLES: f64 = 3e5;

/// What `n` samples at `step` are, for the memory limit's message.
pub fn samples_needed(step: f64, n: f64) -> String {
    format!(
        "--step {step} over this program samples {} points, which",
        millplan_geom::limits::amount(n)
    )
}

/// The points the check will sample (counted before it runs).
pub fn sample_count(p: &Program, fallback: Option<Shape>, g: &GougeParams) -> f64 {
    samples(p, body(fallback), g)
}

/// The check of `p` against `part`, reporting the points done.
pub fn check(
    p: &Program,
    part: &millplan_geom::TriMesh,
    fallback: Option<Shape>,
    g: &GougeParams,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> GougeReport {
    let part = DropMesh::new(part);
    check_with_progress(p, &part, body(fallback), g, progress)
}

/// The moves skipped, by reason.
pub fn skipped(s: &Skipped) -> String {
    format!(
        "{} without a tool shape, {} with a tilted or unknown tool axis, {} canned-cycle holes, {} from or to an unknown position{}",
        s.no_tool, s.tilted, s.cycles, s.unknown_position, s.first()
    )
}

/// What `gouge --json` prints.
#[derive(Serialize)]
pub struct Report<'a> {
    #[serde(flatten)]
    pub check: &'a GougeReport,
    pub clean: bool,
    pub tol: f64,
}

fn mostly_off_part(rep: &GougeReport) -> bool {
    rep.mostly_off_part()
}

/// The finding on the program when most of its cutting moves stood away
/// from the part.
pub fn off_part_finding(rep: &GougeReport) -> Option<millplan_nc::Diagnostic> {
    mostly_off_part(rep).then(|| millplan_nc::Diagnostic {
        severity: millplan_nc::Severity::Warning,
        code: millplan_nc::diag::Code::OffSurface,
        line: 0,
        col: 0,
        message: format!(
            "{}, and the check proves nothing where it is not",
            rep.off_part_words()
        ),
    })
}

impl<'a> Report<'a> {
    /// `clean` when the check looked at some move, found no gouge, and
    /// had the tool by the part in most of the cutting moves.
    pub fn new(check: &'a GougeReport, tol: f64) -> Self {
        Report {
            check,
            clean: check.gouges.is_empty() && check.moves_checked > 0 && !mostly_off_part(check),
            tol,
        }
    }

    /// Whether the run found a problem: a gouge, or a part away from most
    /// of the path.
    pub fn found(&self) -> bool {
        !self.check.gouges.is_empty() || mostly_off_part(self.check)
    }

    /// Each gouge at its line in `path`, then the counts.
    pub fn render_text(&self, path: &str) -> String {
        let rep = self.check;
        let mut o = String::new();
        for gg in &rep.gouges {
            let _ = writeln!(
                o,
                "{path}:{}: gouge {:.3} mm deep at X{:.3} Y{:.3} Z{:.3} (operation {}, move {})",
                gg.line,
                gg.depth,
                gg.at[0],
                gg.at[1],
                gg.at[2],
                gg.operation + 1,
                gg.mv
            );
        }
        let verdict = if rep.moves_checked == 0 {
            "nothing checked".to_string()
        } else if rep.gouges.is_empty() && mostly_off_part(rep) {
            format!(
                "no gouge, but the tool stands by the part in only {} of {} cutting moves: not checked against the part the program was made for",
                rep.cutting_moves - rep.off_part_moves,
                rep.cutting_moves
            )
        } else if rep.gouges.is_empty() {
            "clean".to_string()
        } else {
            format!(
                "{} gouging moves, deepest {:.3} mm",
                rep.gouges.len(),
                rep.max_depth
            )
        };
        let _ = writeln!(
            o,
            "{} moves checked at {} points: {verdict}",
            rep.moves_checked, rep.points_checked
        );
        if rep.moves_skipped > 0 {
            let _ = writeln!(
                o,
                "{} moves not checked: {}",
                rep.moves_skipped,
                skipped(&rep.skipped)
            );
        }
        o
    }
}
