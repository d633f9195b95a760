//! `millplan simulate`: the program run over its stock.

use crate::cmd::{print_diagnostics, read_options, Range, UnitArg};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::{read_mesh, read_program, read_surface, Outputs};
use millplan_geom::TriMesh;
use millplan_sim::stock::path::{strokes, PathOptions, Strokes};
use millplan_sim::stock::remaining::{remaining, Remaining};
use millplan_sim::stock::run::{run as run_sim, SimReport};
use millplan_sim::stock::spec::{StockError, StockSpec};
use millplan_sim::stock::tool::{BodyOptions, ToolBody};
use millplan_sim::stock::Stock;
use std::path::{Path, PathBuf};

/// Run the program over its stock: material removal, engagement per move,
/// collisions, and the result against the part.
///
/// The stock is a grid of vertical material columns (dexels) of side
/// --resolution; each move's tool body (cutter, shank, holder) is swept
/// through it in program order. Reported per move: removed volume, removal
/// rate, axial depth, radial engagement, air cuts. A rapid that removes
/// material is a crash; the shank (above --flute-length) or the holder
/// (--holder) meeting material is a collision. Both are reported with their
/// line and make the exit code 3.
///
/// With --stl, the material left on the part (or cut into it) at every facet.
///
/// Stocks: box:auto or box:auto:MARGIN (the cutting moves' bounds widened by the tool
/// radius and MARGIN mm, default 1; top at the highest cutting tip),
/// box:X0,Y0,Z0,X1,Y1,Z1, cylinder:auto or cylinder:auto:MARGIN, cylinder:CX,CY,Z0,Z1,D,
/// stl:FILE (a closed mesh, e.g. a casting), offset:MM (the --stl part grown
/// by MM, down to its bottom: what a finishing program meets after roughing).
///
/// Exit codes: 0 done; 2 bad input; 3 a rapid, shank or holder hit material.
#[derive(clap::Args)]
pub struct Args {
    /// Program (APT/CL or G-code).
    pub path: PathBuf,
    /// Initial stock (see above).
    #[arg(long)]
    pub stock: String,
    /// Cutter for operations whose tool has no geometry, or to override it:
    /// ball:D, flat:D, bull:D:R, cone:D:ANGLE.
    #[arg(long)]
    pub tool: Option<String>,
    /// Cutting length from the tip, mm. Above it the shank does not cut and
    /// material there is a collision. Default: the program's tool height
    /// when it gives one, else the whole tool cuts (shank not checked).
    #[arg(long, value_name = "MM")]
    pub flute_length: Option<f64>,
    /// Shank diameter above the flutes, mm (default: the cutter's).
    #[arg(long, value_name = "D")]
    pub shank: Option<f64>,
    /// Holder as DIAMETER:STICKOUT (mm; stick-out from the tip to the
    /// holder's face). Default: no holder.
    #[arg(long, value_name = "D:L")]
    pub holder: Option<String>,
    /// Part surface (STL): report the material left on it.
    #[arg(long)]
    pub stl: Option<PathBuf>,
    /// Unit of the STL files' numbers (the part and an stl: blank; an STL
    /// does not say): mm (default) or inch, converted to mm on reading.
    #[arg(long, value_enum)]
    pub stl_units: Option<UnitArg>,
    /// Dexel size, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::simulate::RESOLUTION, value_name = "MM")]
    pub resolution: f64,
    /// Material deeper than this (mm) met by a rapid, shank or holder is a
    /// collision; on the part, cut deeper than this is a gouge.
    #[arg(long, default_value_t = millplan_driver::command_defaults::simulate::TOL, value_name = "MM")]
    pub tol: f64,
    /// Machine file (TOML) for the rapid rate.
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Write the final stock as binary STL.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Cell size of the written stock mesh, mm (default: --resolution, or
    /// coarser so the mesh has at most about a million cells).
    #[arg(long, value_name = "MM")]
    pub mesh_resolution: Option<f64>,
    /// Write one CSV row per move: index,line,removed_mm3,mrr,ap,ae,air,...
    #[arg(long, value_name = "FILE")]
    pub table: Option<PathBuf>,
    /// Write an HTML report: the stock coloured by height or by the material
    /// left on the part, the removal rate along the program.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Units of a program that does not say (G20/G21, UNITS/).
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// No progress bar or warnings.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(a: Args) -> CliResult<i32> {
    crate::cmd::arg(
        "--resolution",
        a.resolution,
        Range::from(0.005, 100.0, "mm"),
    )?;
    crate::cmd::arg("--tol", a.tol, Range::from(0.0, 100.0, "mm"))?;
    // Checked before any work, not after the simulation.
    if let Some(m) = a.mesh_resolution {
        crate::cmd::arg("--mesh-resolution", m, Range::from(0.005, 1000.0, "mm"))?;
    }
    let spec = StockSpec::parse(&a.stock).map_err(|e| CliError::input(format!("--stock {e}")))?;
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    let mut inputs: Vec<&Path> = vec![&a.path];
    inputs.extend(a.stl.as_deref());
    if let StockSpec::Stl(p) = &spec {
        inputs.push(p);
    }
    let mut outputs = Outputs::plan(
        &inputs,
        &[
            ("-o", a.output.as_deref()),
            ("--table", a.table.as_deref()),
            ("--report", a.report.as_deref()),
        ],
        false,
    )?;
    let parsed = read_program(&a.path, read_options(a.units, None)?)?;
    print_diagnostics(&a.path, &parsed.diagnostics, a.quiet || a.json);
    let strokes = program_strokes(&a, &parsed.program, machine.rapid)?;
    let part = match &a.stl {
        Some(p) => Some(read_surface(p, a.stl_units)?.0),
        None => None,
    };
    let mut stock = initial_stock(
        &a.path,
        a.resolution,
        &spec,
        &strokes,
        part.as_ref(),
        a.stl_units,
    )?;
    let bar = crate::progress::count(
        strokes.strokes.len() as u64,
        "simulating",
        "strokes",
        !a.quiet && !a.json && strokes.strokes.len() > 50_000,
    );
    let rep = run_sim(&mut stock, &strokes, a.tol, &|d| bar.set_position(d as u64));
    bar.finish_and_clear();
    let rem = part.as_ref().map(|p| remaining(&stock, p, 10.0, a.tol));
    write_outputs(&a, &mut outputs, &stock, &rep, rem.as_ref(), part.as_ref())?;
    outputs.commit()?;
    print_summary(&a, &rep, rem.as_ref());
    Ok(
        if rep.rapid_collisions.is_empty() && rep.holder_collisions.is_empty() {
            EXIT_OK
        } else {
            EXIT_FINDINGS
        },
    )
}

/// The tool body of an operation: its cutter (or --tool), flutes, shank and
/// holder from the options (`ToolBody::for_operation`).
fn tool_body(a: &Args) -> CliResult<impl Fn(&millplan_nc::Operation) -> Option<ToolBody>> {
    let shape = match &a.tool {
        Some(s) => Some(crate::cmd::tool_shape("--tool", s)?),
        None => None,
    };
    let holder = match &a.holder {
        None => None,
        Some(s) => {
            let v: Vec<f64> = s.split(':').filter_map(|x| x.trim().parse().ok()).collect();
            match v[..] {
                [d, l] if d > 0.0 && l > 0.0 && d.is_finite() && l.is_finite() => {
                    Some((d / 2.0, l))
                }
                _ => {
                    return Err(CliError::input(format!(
                        "--holder {s}: give DIAMETER:STICKOUT in mm, e.g. 32:40"
                    )))
                }
            }
        }
    };
    for (flag, v) in [("--flute-length", a.flute_length), ("--shank", a.shank)] {
        if let Some(v) = v {
            crate::cmd::arg(flag, v, Range::from(0.001, 10_000.0, "mm"))?;
        }
    }
    let o = BodyOptions {
        shape,
        flute: a.flute_length,
        shank_r: a.shank.map(|d| d / 2.0),
        holder,
        no_cone: false,
    };
    Ok(move |op: &millplan_nc::Operation| ToolBody::for_operation(op, &o))
}

fn program_strokes(a: &Args, p: &millplan_nc::Program, rapid: f64) -> CliResult<Strokes> {
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
        return Err(CliError::input(format!(
            "{}: the program does not say the shape of its tool; give it with --tool (ball:D, flat:D, bull:D:R, cone:D:ANGLE)",
            a.path.display()
        )));
    }
    if s.strokes.is_empty() {
        return Err(CliError::input(format!(
            "{}: no move could be simulated ({} from or to an unknown position, {} with the tool axis known only as machine angles)",
            a.path.display(),
            s.skipped.unknown_position,
            s.skipped.unknown_axis
        )));
    }
    Ok(s)
}

/// The stock before the program at `program` runs, as `spec` names it, at
/// cell size `res` (`StockSpec::build`; an `stl:` blank read here).
pub fn initial_stock(
    program: &Path,
    res: f64,
    spec: &StockSpec,
    s: &Strokes,
    part: Option<&TriMesh>,
    stl_units: Option<UnitArg>,
) -> CliResult<Stock> {
    let blank = match spec {
        StockSpec::Stl(p) => {
            let (mut mesh, _) = read_mesh(p)?;
            crate::cmd::stl_to_mm(&mut mesh, stl_units);
            Some(mesh)
        }
        _ => None,
    };
    let memory = crate::limits::get().memory;
    spec.build(res, s, part, blank.as_ref(), memory)
        .map_err(|e| match e {
            StockError::NoCut => CliError::input(format!("{}: {e}", program.display())),
            e => CliError::input(e.to_string()),
        })
}

fn write_outputs(
    a: &Args,
    outputs: &mut Outputs,
    stock: &Stock,
    rep: &SimReport,
    rem: Option<&Remaining>,
    part: Option<&TriMesh>,
) -> CliResult<()> {
    if let Some(p) = &a.output {
        let step = match a.mesh_resolution {
            Some(m) => ((m / stock.grid.res).round() as usize).max(1),
            None => ((stock.cells() as f64 / 1e6).sqrt().ceil() as usize).max(1),
        };
        let mesh = millplan_sim::stock::stock_mesh(&stock.coarsened(step));
        let mut bytes = Vec::new();
        millplan_geom::stl::write_binary_stl(&mesh, "millplan stock", &mut bytes);
        outputs.write(p, &bytes)?;
    }
    if let Some(p) = &a.table {
        outputs.write(p, millplan_report::sim::moves_csv(&rep.per_move).as_bytes())?;
    }
    if let Some(p) = &a.report {
        let title = format!("Stock simulation of {}", a.path.display());
        let html = millplan_report::sim::report(&title, &a.stock, stock, rep, rem.zip(part));
        outputs.write(p, html.as_bytes())?;
    }
    Ok(())
}

fn print_summary(a: &Args, rep: &SimReport, rem: Option<&Remaining>) {
    if a.json {
        let mut j = serde_json::to_value(rep).unwrap_or_default();
        j["stock"] = serde_json::json!(a.stock);
        if let Some(r) = rem {
            j["remaining"] = serde_json::json!({
                "min": r.min, "max": r.max, "mean": r.mean,
                "facets": r.facets, "gouged": r.gouged, "histogram": r.histogram,
            });
        }
        crate::cmd::print_json(j);
        return;
    }
    for c in &rep.rapid_collisions {
        outln!(
            "{}:{}: rapid into material, {:.3} mm deep ({:.3} mm³)",
            a.path.display(),
            c.line,
            c.depth,
            c.volume_mm3
        );
    }
    for c in &rep.holder_collisions {
        outln!(
            "{}:{}: shank or holder in material, {:.3} mm deep ({:.3} mm³)",
            a.path.display(),
            c.line,
            c.depth,
            c.volume_mm3
        );
    }
    outln!(
        "{} of {} moves simulated at {} mm: removed {:.1} mm³ of {:.1} ({} cutting, {} in air), highest rate {:.0} mm³/min at line {}",
        rep.simulated, rep.moves, rep.resolution_mm, rep.removed_mm3, rep.stock_before_mm3,
        rep.cutting_moves, rep.air_moves, rep.max_mrr_mm3_min, rep.max_mrr_line
    );
    if rep.skipped.total() > 0 {
        outln!(
            "not simulated: {} moves from or to an unknown position, {} with the axis known only as machine angles",
            rep.skipped.unknown_position, rep.skipped.unknown_axis
        );
    }
    if let Some(r) = rem {
        outln!(
            "on the part ({} facets): material left {:.3} to {:.3} mm, mean {:.3}; {} facets cut into by more than {} mm",
            r.facets, r.min, r.max, r.mean, r.gouged, a.tol
        );
    }
    let hits = rep.rapid_collisions.len() + rep.holder_collisions.len();
    outln!(
        "{}",
        if hits == 0 {
            "no collisions".to_string()
        } else {
            format!("{hits} collisions")
        }
    );
}
