//! `millplan gouge`: does the program cut into the part?

use crate::cmd::{print_diagnostics, read_options, UnitArg};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::{read_program, read_surface};
use millplan_plan::checks;
use millplan_sim::dropcutter::DropMesh;
use millplan_sim::gouge::{
    check_with_progress, samples, GougeParams, GougeReport, Skipped, BYTES_PER_SAMPLE,
};
use std::path::PathBuf;

/// Check a program for gouges: every cutting move (and with --rapids every
/// rapid) is sampled at --step and the tool tip compared with the height at which
/// the cutter would touch the part there (drop-cutter, exact for flat, ball,
/// bull and cone cutters). Deeper than --tol is a gouge.
///
/// Exit code 0 when clean, 3 when gouges were found, 2 when the program does
/// not say its tool's shape (give --tool) or no move could be checked. Moves
/// whose tool axis is not +Z (5-axis), canned cycles and moves from a position
/// the program has not set are counted as not checked, each kind apart.
#[derive(clap::Args)]
pub struct Args {
    /// Program (APT/CL or G-code).
    pub path: PathBuf,
    /// Part surface (STL).
    #[arg(long)]
    pub stl: PathBuf,
    /// Unit of the STL's numbers (an STL does not say): mm (default) or inch,
    /// converted to mm on reading.
    #[arg(long, value_enum)]
    pub stl_units: Option<UnitArg>,
    /// Depth that counts as a gouge, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::gouge::TOL)]
    pub tol: f64,
    /// Sampling step along the moves, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::gouge::STEP)]
    pub step: f64,
    /// Check rapid moves too.
    #[arg(long)]
    pub rapids: bool,
    /// Cutter for operations whose tool has no geometry: ball:D, flat:D, bull:D:R, cone:D:ANGLE.
    #[arg(long)]
    pub tool: Option<String>,
    /// Unit of a program that does not say (NX's Haas posts, bare GOTO files): mm or
    /// inch.
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    /// Print a machine-readable summary (JSON) on standard output; errors too, as JSON
    /// on standard error.
    #[arg(long)]
    pub json: bool,
    /// Print no warnings or notes about the inputs (errors still print).
    #[arg(long, short)]
    pub quiet: bool,
}

/// A check without the cutter's shape checks nothing: a program with a
/// cutting operation whose tool has no shape is refused rather than called
/// clean.
fn shape_is_known(path: &std::path::Path, program: &millplan_nc::Program) -> CliResult<()> {
    if let Some(op) = program.operations.iter().find(|op| {
        op.moves.iter().any(|m| m.is_cutting()) && op.tool.as_ref().and_then(|t| t.cutter).is_none()
    }) {
        let line = op.tool.as_ref().map_or(0, |t| t.line);
        return Err(CliError::input(format!(
            "{}:{line}:1: the program does not say the shape of its tool; give it with --tool (ball:D, flat:D, bull:D:R, cone:D:ANGLE)",
            path.display()
        )));
    }
    Ok(())
}

pub fn run(a: Args) -> CliResult<i32> {
    crate::cmd::arg("--tol", a.tol, crate::cmd::Range::from(0.0, 100.0, "mm"))?;
    crate::cmd::arg(
        "--step",
        a.step,
        crate::cmd::Range::from(0.001, 1000.0, "mm"),
    )?;
    let fallback = match &a.tool {
        Some(s) => Some(crate::cmd::tool_shape("--tool", s)?),
        None => None,
    };
    let parsed = read_program(&a.path, read_options(a.units, None)?)?;
    print_diagnostics(&a.path, &parsed.diagnostics, a.quiet || a.json);
    if fallback.is_none() {
        shape_is_known(&a.path, &parsed.program)?;
    }
    let (mesh, _) = read_surface(&a.stl, a.stl_units)?;
    print_diagnostics(
        &a.stl,
        &checks::mesh(&mesh).into_iter().collect::<Vec<_>>(),
        a.quiet || a.json,
    );
    let part = DropMesh::new(&mesh);
    let g = GougeParams {
        step: a.step,
        tol: a.tol,
        rapids: a.rapids,
    };
    let shape = |op: &millplan_nc::Operation| match op.tool.as_ref().and_then(|t| t.cutter) {
        Some(c) => millplan_sim::shape_of(&c),
        None => fallback,
    };
    // Counted first: a step of 1e-9 on a long program is refused, not run.
    let n = samples(&parsed.program, shape, &g);
    crate::limits::check_memory(
        &format!(
            "--step {} over this program samples {} points, which",
            a.step,
            millplan_geom::limits::amount(n)
        ),
        n * BYTES_PER_SAMPLE,
    )?;
    // Some 300,000 points a second: a bar from a second's worth on.
    let bar = crate::progress::count(n as u64, "gouge check", "points", !a.quiet && n >= 3e5);
    let rep = check_with_progress(&parsed.program, &part, shape, &g, &|done, _| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    if a.json {
        let mut j = serde_json::to_value(&rep).unwrap_or_default();
        j["clean"] = serde_json::json!(rep.gouges.is_empty() && rep.moves_checked > 0);
        j["tol"] = serde_json::json!(a.tol);
        crate::cmd::print_json(j);
    } else {
        print_report(&a, &rep);
    }
    if rep.moves_checked == 0 {
        return Err(CliError::input(format!(
            "{}: no move could be checked ({})",
            a.path.display(),
            skipped(&rep.skipped)
        )));
    }
    Ok(if rep.gouges.is_empty() {
        EXIT_OK
    } else {
        EXIT_FINDINGS
    })
}

fn skipped(s: &Skipped) -> String {
    format!(
        "{} without a tool shape, {} with a tilted or unknown tool axis, {} canned-cycle holes, {} from or to an unknown position",
        s.no_tool, s.tilted, s.cycles, s.unknown_position
    )
}

fn print_report(a: &Args, rep: &GougeReport) {
    for gg in &rep.gouges {
        outln!(
            "{}:{}: gouge {:.3} mm deep at X{:.3} Y{:.3} Z{:.3} (operation {}, move {})",
            a.path.display(),
            gg.line,
            gg.depth,
            gg.at[0],
            gg.at[1],
            gg.at[2],
            gg.operation + 1,
            gg.mv
        );
    }
    outln!(
        "{} moves checked at {} points: {}",
        rep.moves_checked,
        rep.points_checked,
        if rep.moves_checked == 0 {
            "nothing checked".to_string()
        } else if rep.gouges.is_empty() {
            "clean".to_string()
        } else {
            format!(
                "{} gouging moves, deepest {:.3} mm",
                rep.gouges.len(),
                rep.max_depth
            )
        }
    );
    if rep.moves_skipped > 0 {
        outln!(
            "{} moves not checked: {}",
            rep.moves_skipped,
            skipped(&rep.skipped)
        );
    }
}
