//! `millplan simulate`: the tool bodies from the options, the strokes the
//! stock is cut by, the run (`run_command`), the stock mesh written, and
//! the summary printed.

use crate::check::{arg, tool_shape, Range};
use millplan_geom::TriMesh;
use millplan_nc::{Operation, Program};
use millplan_sim::stock::path::{strokes, PathOptions, Strokes};
use millplan_sim::stock::remaining::{remaining, Bin, Remaining};
use millplan_sim::stock::run::SimReport;
use millplan_sim::stock::spec::{StockError, StockSpec};
use millplan_sim::stock::tool::{BodyOptions, ToolBody};
use millplan_sim::stock::Stock;
use serde::Serialize;
use std::fmt::Write as _;

mod command;
pub use command::{run_command, SimCommand};

/// The options of `millplan simulate` that shape the tool and the run.
#[derive(Clone, Debug)]
pub struct SimRequest {
    /// `--tool` (`ball:D`, …): the cutter of a program that names none.
    pub tool: Option<String>,
    /// `DIAMETER:STICKOUT`, mm.
    pub holder: Option<String>,
    pub flute_length: Option<f64>,
    /// Shank diameter, mm.
    pub shank: Option<f64>,
    pub resolution: f64,
    pub tol: f64,
    pub mesh_resolution: Option<f64>,
}

/// The header rows of a simulation report: the program and the part by
/// their file names (`part` none when not given), the stock as given, the
/// dexel size and the tool (`--tool`, else the program's own).
pub fn report_inputs(
    (program, part): (&std::path::Path, Option<&std::path::Path>),
    stock: &str,
    a: &SimRequest,
) -> Vec<(String, String)> {
    vec![
        ("program".into(), crate::feed::file_name(program)),
        (
            "part".into(),
            part.map_or("none given".into(), crate::feed::file_name),
        ),
        ("stock".into(), stock.to_string()),
        ("resolution".into(), format!("{} mm", a.resolution)),
        (
            "tool".into(),
            a.tool
                .clone()
                .map_or("as each operation of the program gives it".into(), |t| {
                    format!("{t} (--tool, where the program gives no shape)")
                }),
        ),
    ]
}

/// The numbers in their ranges, before any work.
pub fn check(a: &SimRequest) -> Result<(), String> {
    arg(
        "--resolution",
        a.resolution,
        Range::from(0.005, 100.0, "mm"),
    )?;
    arg("--tol", a.tol, Range::from(0.0, 100.0, "mm"))?;
    if let Some(m) = a.mesh_resolution {
        arg("--mesh-resolution", m, Range::from(0.005, 1000.0, "mm"))?;
    }
    Ok(())
}

fn holder(s: &str) -> Result<(f64, f64), String> {
    let v: Vec<f64> = s.split(':').filter_map(|x| x.trim().parse().ok()).collect();
    match v[..] {
        [d, l] if d > 0.0 && l > 0.0 && d.is_finite() && l.is_finite() => Ok((d / 2.0, l)),
        _ => Err(format!(
            "--holder {s}: give DIAMETER:STICKOUT in mm, e.g. 32:40"
        )),
    }
}

/// The tool options of the request: cutter (or --tool), flutes, shank and
/// holder, checked.
pub fn body_options(a: &SimRequest) -> Result<BodyOptions, String> {
    let shape = a
        .tool
        .as_deref()
        .map(|s| tool_shape("--tool", s))
        .transpose()?;
    let holder = a.holder.as_deref().map(holder).transpose()?;
    for (flag, v) in [("--flute-length", a.flute_length), ("--shank", a.shank)] {
        if let Some(v) = v {
            arg(flag, v, Range::from(0.001, 10_000.0, "mm"))?;
        }
    }
    Ok(BodyOptions {
        shape,
        flute: a.flute_length,
        shank_r: a.shank.map(|d| d / 2.0),
        holder,
        no_cone: false,
    })
}

/// The tool body of an operation from the request's options
/// (`ToolBody::for_operation`).
pub fn tool_body(a: &SimRequest) -> Result<impl Fn(&Operation) -> Option<ToolBody>, String> {
    let o = body_options(a)?;
    Ok(move |op: &Operation| ToolBody::for_operation(op, &o))
}

/// The note that says which flute length the shank and holder were
/// simulated above, when neither `--flute-length` nor the program's cutter
/// gave one.
pub fn default_flute_note(a: &SimRequest, p: &Program) -> Result<Option<String>, String> {
    let o = body_options(a)?;
    Ok(p.operations.iter().find_map(|op| o.default_flute(op)).map(|f| {
        format!(
            "no flute length given (--flute-length, or the CUTTER record's height): the shank and holder are simulated above {f:.3} mm of flutes ({}·D)",
            millplan_sim::stock::tool::DEFAULT_FLUTE_DIAMETERS
        )
    }))
}

/// The strokes of the program at `path` (its name in errors): every move
/// whose tool has a shape, at chords of a quarter cell.
pub fn program_strokes(
    a: &SimRequest,
    path: &str,
    p: &Program,
    rapid: f64,
) -> Result<Strokes, String> {
    let body = tool_body(a)?;
    let s = strokes(
        p,
        body,
        &PathOptions {
            chord: a.resolution / 4.0,
            rapid_rate: rapid,
        },
    );
    if s.skipped.no_tool > 0 && a.tool.is_none() {
        return Err(format!(
            "{path}: the program does not say the shape of its tool; give it with --tool (ball:D, flat:D, bull:D:R, cone:D:ANGLE)"
        ));
    }
    if s.strokes.is_empty() {
        return Err(format!(
            "{path}: no move could be simulated ({} from or to an unknown position, {} with the tool axis known only as machine angles)",
            s.skipped.unknown_position, s.skipped.unknown_axis
        ));
    }
    Ok(s)
}

/// The stock before the program at `program` (its name in errors) runs, as
/// `spec` names it, at cell size `res` (`StockSpec::build`; `blank` the mesh
/// of an `stl:` blank, `memory` the bytes its `copies` may take together).
pub fn build_stock(
    program: &str,
    res: f64,
    spec: &StockSpec,
    s: &Strokes,
    meshes: (Option<&TriMesh>, Option<&TriMesh>),
    memory: (u64, u32),
) -> Result<Stock, String> {
    spec.build(res, s, meshes, memory).map_err(|e| match e {
        StockError::NoCut => format!("{program}: {e}"),
        e => e.to_string(),
    })
}

/// The stock's surface as binary STL, at `mesh_resolution` (else coarse
/// enough for about a million cells).
pub fn stock_stl(stock: &Stock, mesh_resolution: Option<f64>) -> Vec<u8> {
    let step = match mesh_resolution {
        Some(m) => ((m / stock.grid.res).round() as usize).max(1),
        None => ((stock.cells() as f64 / 1e6).sqrt().ceil() as usize).max(1),
    };
    let mesh = millplan_sim::stock::stock_mesh(&stock.coarsened(step));
    let mut bytes = Vec::new();
    millplan_geom::stl::write_binary_stl(&mesh, "millplan stock", &mut bytes);
    bytes
}

/// How far along each facet's normal the material left is measured, mm.
pub const REMAINING_REACH: f64 = 10.0;

/// The material left on `part` after the run (`tol` the gouge depth).
pub fn remaining_on(stock: &Stock, part: &millplan_geom::TriMesh, tol: f64) -> Remaining {
    remaining(stock, part, REMAINING_REACH, tol)
}

/// The depth below the part's surface that counts as a cut into it: `tol`,
/// but at least half the dexel size, the grid's own error on a slope up to
/// 45° (a correct program run on 0.2 mm dexels reads up to about 0.05 mm
/// below its part).
pub fn part_tol(tol: f64, resolution: f64) -> f64 {
    tol.max(0.5 * resolution)
}

/// What `millplan simulate` runs besides its request: the program (its
/// file's name for errors), the stock as given and parsed, the part and an
/// `stl:` stock's blank (read), the machine's rapid rate and the memory the
/// stock may take.
pub struct SimInputs<'a> {
    pub name: &'a str,
    pub program: &'a Program,
    pub stock: &'a str,
    pub spec: &'a StockSpec,
    pub part: Option<&'a TriMesh>,
    pub blank: Option<&'a TriMesh>,
    pub rapid: f64,
    pub memory: u64,
}

/// What a run of `millplan simulate` made: the stock after the program,
/// the run's report, the material left on the part (with a part) and the
/// note on the flute length assumed (when neither option nor program gave
/// one).
pub struct Simulated {
    pub stock: Stock,
    pub run: SimReport,
    pub remaining: Option<Remaining>,
    pub flute_note: Option<String>,
}

impl Simulated {
    /// Whether a rapid crossed material or the holder or shank met it.
    pub fn collided(&self) -> bool {
        !(self.run.rapid_collisions.is_empty() && self.run.holder_collisions.is_empty())
    }

    /// Whether a check failed (exit 3): a collision, or with the part the
    /// tool cut into it (the report's verdict is then red).
    pub fn failed(&self) -> bool {
        self.collided() || self.remaining.as_ref().is_some_and(|r| r.gouged > 0)
    }

    /// What `simulate --json` prints.
    pub fn report<'a>(&'a self, stock: &'a str) -> Report<'a> {
        Report::new(&self.run, stock, self.remaining.as_ref())
    }

    /// The per-move table (`--table`), CSV.
    pub fn table_csv(&self) -> String {
        millplan_report::sim::moves_csv(&self.run.per_move)
    }

    /// The HTML report (`--report`) of the run of the program at `files.0`
    /// (over the part at `files.1`, `part` its mesh) on the stock as given.
    pub fn report_html(
        &self,
        a: &SimRequest,
        files: (&std::path::Path, Option<&std::path::Path>),
        stock: &str,
        part: Option<&TriMesh>,
    ) -> String {
        let title = format!("Stock simulation of {}", files.0.display());
        let inputs = report_inputs(files, stock, a);
        let rem = self.remaining.as_ref().zip(part);
        millplan_report::sim::report(&title, inputs, stock, &self.stock, &self.run, rem)
    }
}

/// Why a run of `millplan simulate` stopped: the program's moves (none
/// simulable, no tool shape) or the stock (it cannot be built from them or
/// the part, or the memory does not hold it); the message says which file.
#[derive(Debug)]
pub enum SimError {
    Program(String),
    Stock(String),
}

impl std::fmt::Display for SimError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SimError::Program(m) | SimError::Stock(m) => f.write_str(m),
        }
    }
}

/// `millplan simulate`: the strokes, the stock built, the material removed
/// stroke by stroke (`progress` hears the strokes done and their number),
/// the material left on the part; `lap` hears each phase's end.
pub fn command(
    a: &SimRequest,
    g: &SimInputs,
    lap: &mut dyn FnMut(&str),
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Simulated, SimError> {
    let strokes = program_strokes(a, g.name, g.program, g.rapid).map_err(SimError::Program)?;
    let flute_note = default_flute_note(a, g.program).map_err(SimError::Program)?;
    lap("strokes (tool bodies, moves in chords)");
    let parts = (g.part, g.blank);
    let mut stock = build_stock(g.name, a.resolution, g.spec, &strokes, parts, (g.memory, 1))
        .map_err(SimError::Stock)?;
    lap("stock built");
    let total = strokes.strokes.len();
    let run = crate::simulate_stock(&mut stock, &strokes, a.tol, &|d| progress(d, total));
    lap("material removal");
    let part_tol = part_tol(a.tol, a.resolution);
    let remaining = g.part.map(|p| remaining_on(&stock, p, part_tol));
    lap("material left on the part");
    Ok(Simulated {
        stock,
        run,
        remaining,
        flute_note,
    })
}

/// The material left on the part.
#[derive(Serialize)]
pub struct RemainingJson<'a> {
    min: f64,
    max: f64,
    mean: f64,
    facets: usize,
    gouged: usize,
    histogram: &'a [Bin],
}

/// What `simulate --json` prints.
#[derive(Serialize)]
pub struct Report<'a> {
    #[serde(flatten)]
    pub run: &'a SimReport,
    pub stock: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub remaining: Option<RemainingJson<'a>>,
    /// The report's verdict: red when a rapid, shank or holder met
    /// material or the tool cut into the part.
    pub verdict: millplan_report::html::Verdict,
}

impl<'a> Report<'a> {
    pub fn new(run: &'a SimReport, stock: &'a str, rem: Option<&'a Remaining>) -> Self {
        Report {
            run,
            stock,
            verdict: millplan_report::sim::sim_verdict(run, rem),
            remaining: rem.map(|r| RemainingJson {
                min: r.min,
                max: r.max,
                mean: r.mean,
                facets: r.facets,
                gouged: r.gouged,
                histogram: &r.histogram,
            }),
        }
    }

    /// The collisions at their lines in `path`, then the removal and what is
    /// left on the part (`tol` the gouge depth).
    pub fn render_text(&self, path: &str, tol: f64) -> String {
        let rep = self.run;
        let part_tol = part_tol(tol, rep.resolution_mm);
        let mut o = String::new();
        for c in &rep.rapid_collisions {
            let _ = writeln!(
                o,
                "{path}:{}: rapid into material, {:.3} mm deep ({:.3} mm³)",
                c.line, c.depth, c.volume_mm3
            );
        }
        for c in &rep.holder_collisions {
            let _ = writeln!(
                o,
                "{path}:{}: shank or holder in material, {:.3} mm deep ({:.3} mm³)",
                c.line, c.depth, c.volume_mm3
            );
        }
        let _ = writeln!(
            o,
            "{} of {} moves simulated at {} mm: removed {:.1} mm³ of {:.1} ({} cutting, {} in air), highest rate {:.0} mm³/min at line {}",
            rep.simulated, rep.moves, rep.resolution_mm, rep.removed_mm3, rep.stock_before_mm3,
            rep.cutting_moves, rep.air_moves, rep.max_mrr_mm3_min, rep.max_mrr_line
        );
        if rep.skipped.total() > 0 {
            let _ = writeln!(
                o,
                "not simulated: {} moves from or to an unknown position, {} with the axis known only as machine angles{}",
                rep.skipped.unknown_position, rep.skipped.unknown_axis, rep.skipped.first()
            );
        }
        if let Some(r) = &self.remaining {
            let _ = writeln!(
                o,
                "on the part ({} facets): material left {:.3} to {:.3} mm, mean {:.3}; {} facets cut into by more than {part_tol} mm",
                r.facets, r.min, r.max, r.mean, r.gouged
            );
        }
        let hits = rep.rapid_collisions.len() + rep.holder_collisions.len();
        if hits == 0 {
            o.push_str("no collisions\n");
        } else {
            let _ = writeln!(o, "{hits} collisions");
        }
        // What the verdict weighs, so an amber run says why; the verdict
        // last, as every command's.
        for w in &self.verdict.warnings {
            let _ = writeln!(o, "warning: {w}");
        }
        let _ = writeln!(o, "verdict: {}", self.verdict.summary);
        o
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(tool: Option<&str>) -> SimRequest {
        SimRequest {
            tool: tool.map(Into::into),
            holder: None,
            flute_length: None,
            shank: None,
            resolution: 0.25,
            tol: crate::command_defaults::simulate::TOL,
            mesh_resolution: None,
        }
    }

    fn program(src: &str) -> Program {
        millplan_nc::parse_program(src, millplan_nc::ReadOptions::default())
            .expect("reads")
            .program
    }

    /// A 10 mm flat end mill slots 2 mm deep straight through a 50 mm box
    /// (its round ends outside): 50 · 10 · 2 = 1000 mm³ removed, to the
    /// dexels' resolution; every phase heard, no collision. A rapid through
    /// the box is one; a tool without a shape is the program's error.
    #[test]
    fn a_slot_removes_its_volume_and_a_rapid_through_the_stock_collides() {
        let slot = "G21 G90\nT1 M6\nS1000 M3\nG0 X-10 Y0 Z5\nG1 Z-2 F500\nG1 X60\nG0 Z5\nM30\n";
        let p = program(slot);
        let stock = "box:0,-20,-10,50,20,0";
        let spec = StockSpec::parse(stock).expect("stock");
        let g = SimInputs {
            name: "slot.nc",
            program: &p,
            stock,
            spec: &spec,
            part: None,
            blank: None,
            rapid: 10_000.0,
            memory: 1 << 30,
        };
        let mut laps = Vec::new();
        let Ok(sim) = command(
            &request(Some("flat:10")),
            &g,
            &mut |l| laps.push(l.to_string()),
            &|_, _| {},
        ) else {
            panic!("simulates")
        };
        assert!(
            (sim.run.removed_mm3 - 1000.0).abs() < 0.02 * 1000.0,
            "{}",
            sim.run.removed_mm3
        );
        assert!(!sim.collided());
        assert_eq!(laps.len(), 4, "{laps:?}");
        assert!(sim.table_csv().lines().count() > sim.run.per_move.len());
        let rapid = program("G21 G90\nT1 M6\nS1000 M3\nG0 X-10 Y0 Z-2\nG0 X60\nM30\n");
        let g = SimInputs {
            program: &rapid,
            ..g
        };
        let Ok(crash) = command(&request(Some("flat:10")), &g, &mut |_| {}, &|_, _| {}) else {
            panic!("simulates")
        };
        assert!(crash.collided());
        let Err(SimError::Program(e)) = command(&request(None), &g, &mut |_| {}, &|_, _| {}) else {
            panic!("no tool shape")
        };
        assert!(e.starts_with("slot.nc: ") && e.contains("--tool"), "{e}");
    }
}
