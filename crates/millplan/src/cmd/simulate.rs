//! `millplan simulate`: the program run over its stock.

use crate::error::{exit, CliError, CliResult};
use crate::io::Outputs;
use crate::timings::Table as _;
use millplan_driver::simulate::{self as lib, SimRequest};
use millplan_driver::StockSpec;
use millplan_geom::TriMesh;
use std::path::PathBuf;

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
    #[command(flatten)]
    pub part: crate::cmd::args::OptionalPart,
    /// Dexel size, mm.
    #[arg(long, default_value_t = millplan_driver::command_defaults::simulate::RESOLUTION, value_name = "MM")]
    pub resolution: f64,
    /// Material deeper than this (mm) met by a rapid, shank or holder is a
    /// collision; on the part, cut deeper than this is a gouge.
    #[arg(long, default_value_t = millplan_driver::command_defaults::simulate::TOL, value_name = "MM")]
    pub tol: f64,
    #[command(flatten)]
    pub machine: crate::cmd::args::MachineFile,
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
    #[command(flatten)]
    pub units: crate::cmd::args::ProgramUnits,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
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
    clock.end(a.timings.on);
    Ok(code)
}

fn run_timed(a: &Args, clock: &mut crate::timings::Clock) -> CliResult<i32> {
    let req = request(a);
    // Checked before any work, not after the simulation.
    lib::check(&req).map_err(CliError::input)?;
    let spec = StockSpec::parse(&a.stock).map_err(|e| CliError::input(format!("--stock {e}")))?;
    let machine = a.machine.load()?;
    let mut outputs = plan_outputs(a, &spec)?;
    clock.lap("arguments, machine file and outputs checked");
    let quiet = a.notes.quiet || a.summary.json;
    let parsed = a.units.read(&a.path, quiet)?;
    clock.lap("program read");
    let part = a.part.read()?;
    let blank = a.part.units.blank(&spec)?;
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
    let bar = crate::progress::Phases::new(!quiet);
    let progress = |done: usize, total: usize| {
        if total > millplan_driver::command_defaults::progress::LONG_SIMULATION_STROKES {
            bar.report("simulating", done, total)
        }
    };
    let run = lib::command(&req, &g, &mut |l| clock.lap(l), &progress);
    bar.finish();
    let sim = run.map_err(|e| CliError::input(e.to_string()))?;
    if let (Some(note), false) = (&sim.flute_note, quiet) {
        eprintln!("note: {note}");
    }
    write_outputs(a, &mut outputs, &sim, part.as_ref())?;
    outputs.commit()?;
    clock.lap("outputs written, synced and renamed into place");
    let report = sim.report(&a.stock);
    a.summary.print(&report, |r| r.render_text(&path, a.tol));
    Ok(exit(sim.collided()))
}

/// The outputs of the run, checked against every file it reads.
fn plan_outputs(a: &Args, spec: &StockSpec) -> CliResult<Outputs> {
    let blank = match spec {
        StockSpec::Stl(p) => Some(p.as_path()),
        _ => None,
    };
    let inputs = [
        Some(&*a.path),
        a.part.stl.as_deref(),
        a.machine.machine.as_deref(),
        blank,
    ];
    let (table, report) = (a.table.as_deref(), a.report.as_deref());
    let outs = [
        ("-o", a.output.as_deref()),
        ("--table", table),
        ("--report", report),
    ];
    crate::io::plan(&inputs, &outs, false)
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
        let files = (a.path.as_path(), a.part.stl.as_deref());
        let html = sim.report_html(&request(a), files, &a.stock, part);
        outputs.write(p, html.as_bytes())?;
    }
    Ok(())
}
