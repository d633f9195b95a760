//! `millplan simulate`: the program run over its stock.

use crate::cmd::{print_diagnostics, read_options, UnitArg};
use crate::error::{CliError, CliResult, EXIT_FINDINGS, EXIT_OK};
use crate::io::{read_program, read_surface, Outputs};
use crate::timings::Table as _;
use millplan_driver::simulate::{self as lib, SimRequest};
use millplan_driver::StockSpec;
use millplan_geom::TriMesh;
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
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

fn request(a: &Args) -> SimRequest {
    SimRequest {
        tool: a.tool.clone(),
        holder: a.holder.clone(),
        flute_length: a.flute_length,
        shank: a.shank,
        resolution: a.resolution,
        tol: a.tol,
        mesh_resolution: a.mesh_resolution,
    }
}

pub fn run(a: Args) -> CliResult<i32> {
    let mut clock = crate::timings::Clock::start();
    let code = run_timed(&a, &mut clock)?;
    clock.lap("summary printed");
    clock.print(a.timings.on);
    Ok(code)
}

fn run_timed(a: &Args, clock: &mut crate::timings::Clock) -> CliResult<i32> {
    let req = request(a);
    // Checked before any work, not after the simulation.
    lib::check(&req).map_err(CliError::input)?;
    let spec = StockSpec::parse(&a.stock).map_err(|e| CliError::input(format!("--stock {e}")))?;
    let machine = crate::cmd::load_machine(a.machine.as_deref())?;
    let mut outputs = plan_outputs(a, &spec)?;
    clock.lap("arguments, machine file and outputs checked");
    let parsed = read_program(&a.path, read_options(a.units, None)?)?;
    print_diagnostics(&a.path, &parsed.diagnostics, a.quiet || a.json);
    clock.lap("program read");
    let part = match &a.stl {
        Some(p) => Some(read_surface(p, a.stl_units)?.0),
        None => None,
    };
    let blank = crate::io::read_blank(&spec, a.stl_units)?;
    clock.lap("part read");
    let path = a.path.display().to_string();
    let g = lib::SimInputs {
        name: &path,
        program: &parsed.program,
        stock: &a.stock,
        spec: &spec,
        part: part.as_ref(),
        blank: blank.as_ref(),
        rapid: machine.rapid,
        memory: crate::limits::get().memory,
    };
    // A bar on a long program only.
    let bar = crate::progress::Phases::new(!a.quiet && !a.json);
    let progress = |done: usize, total: usize| {
        if total > millplan_driver::command_defaults::progress::LONG_SIMULATION_STROKES {
            bar.report("simulating", done, total)
        }
    };
    let run = lib::command(&req, &g, &mut |l| clock.lap(l), &progress);
    bar.finish();
    let sim = run.map_err(|e| CliError::input(e.to_string()))?;
    if let (Some(note), false) = (&sim.flute_note, a.quiet || a.json) {
        eprintln!("note: {note}");
    }
    write_outputs(a, &mut outputs, &sim, part.as_ref())?;
    outputs.commit()?;
    clock.lap("outputs written, synced and renamed into place");
    let report = sim.report(&a.stock);
    if a.json {
        crate::cmd::print_json(serde_json::to_value(&report).unwrap_or_default());
    } else {
        out!("{}", report.render_text(&path, a.tol));
    }
    Ok(if sim.collided() {
        EXIT_FINDINGS
    } else {
        EXIT_OK
    })
}

/// The outputs of the run, checked against every file it reads.
fn plan_outputs(a: &Args, spec: &StockSpec) -> CliResult<Outputs> {
    let mut inputs: Vec<&Path> = vec![&a.path];
    inputs.extend(a.stl.as_deref());
    inputs.extend(a.machine.as_deref());
    if let StockSpec::Stl(p) = spec {
        inputs.push(p);
    }
    Ok(Outputs::plan(
        &inputs,
        &[
            ("-o", a.output.as_deref()),
            ("--table", a.table.as_deref()),
            ("--report", a.report.as_deref()),
        ],
        false,
    )?)
}

fn write_outputs(
    a: &Args,
    outputs: &mut Outputs,
    sim: &lib::Simulated,
    part: Option<&TriMesh>,
) -> CliResult<()> {
    if let Some(p) = &a.output {
        outputs.write(p, &lib::stock_stl(&sim.stock, a.mesh_resolution))?;
    }
    if let Some(p) = &a.table {
        outputs.write(p, sim.table_csv().as_bytes())?;
    }
    if let Some(p) = &a.report {
        let files = (a.path.as_path(), a.stl.as_deref());
        let html = sim.report_html(&request(a), files, &a.stock, part);
        outputs.write(p, html.as_bytes())?;
    }
    Ok(())
}
