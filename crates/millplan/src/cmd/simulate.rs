//! `millplan simulate`: the program run over its stock.

use crate::error::{exit, CliResult};
use millplan_driver::simulate::{self as lib, SimRequest};
use millplan_driver::watch::Watch as _;
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
/// Exit codes: 0 done; 2 bad input; 3 a rapid, shank or holder hit material, or the tool cut into the --stl part.
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
    /// collision; on the part, cut deeper than this (and than half the
    /// dexel size, the grid's own error) is a gouge.
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
    let watch = crate::progress::Watch::new(&a.path, a.notes.quiet, a.summary.json);
    let c = lib::SimCommand {
        input: &a.path,
        request: request(&a),
        stock: &a.stock,
        part: a.part.stl.as_deref(),
        stl_units: a.part.units.stl_units.map(Into::into),
        machine: a.machine.machine.as_deref(),
        output: a.output.as_deref(),
        table: a.table.as_deref(),
        report: a.report.as_deref(),
        read: a.units.options()?,
    };
    let sim = lib::run_command(&c, &watch)?;
    let path = a.path.display().to_string();
    a.summary
        .print(&sim.report(&a.stock), |r| r.render_text(&path, a.tol));
    watch.lap("summary printed");
    watch.print_timings(a.timings.on);
    Ok(exit(sim.failed()))
}
