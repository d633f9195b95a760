//! `millplan setup`: can a five-axis machine reach the whole part in one setup,
//! and how should the part be clamped?

use crate::error::{exit, CliResult};
use millplan_driver::setup::{self as lib, MachineType, SetupRequest};
use millplan_driver::watch::Watch as _;
use millplan_plan::setup::GridKind;
use std::path::PathBuf;

/// Machinability and setup orientation of a part on a five-axis machine
/// (line of sight, after Kang & Suh).
///
/// Every facet gets its visibility cone: the grid directions that leave its
/// outer side by more than --clearance degrees and see no other part of the
/// part (with --tool: along which the ball-end mill, its shank and holder
/// touch nothing but the facet). A setup needs, of the machine's rotary ranges,
/// what its most demanding facet needs along its best direction. The grid
/// seeds the search (the part as it lies and the orientation needing least
/// tilt, each spun in 15° steps); the best seeds are then refined between the
/// grid's directions, each facet's direction tested exactly, and feasibility
/// is decided by the refined setup. `required` holds the least ranges of any
/// setup, also when the machine falls short.
///
/// Ranges are MIN,MAX in degrees or `free` for an unlimited axis; for `ca`
/// range1 is the tilting A axis and range2 the C table, for `ab` range1 is the
/// A table and range2 the B cradle.
///
/// Exit code 0 when feasible, 3 when not.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub part: crate::cmd::args::Part,
    /// Machine file (see examples/machine.toml) with a `[kinematics]` table:
    /// kind = "table-ac" | "table-bc" | "table-ab" | "head-bc" |
    /// "head-b-table-c", [kinematics.first] and [kinematics.second] with min,
    /// max, sign. The older kinematics-only file reads too.
    #[arg(long, conflicts_with = "kind")]
    pub machine: Option<PathBuf>,
    /// Machine type when no --machine file is given.
    #[arg(long = "type", value_enum, id = "kind")]
    pub kind: Option<TypeArg>,
    /// First rotary range (the tilting axis): MIN,MAX or free.
    #[arg(long, default_value = "free", allow_hyphen_values = true)]
    pub range1: String,
    /// Second rotary range: MIN,MAX or free.
    #[arg(long, default_value = "free", allow_hyphen_values = true)]
    pub range2: String,
    /// Sphere grid of tool directions.
    #[arg(long, value_enum, default_value_t = GridArg::Latlon)]
    pub grid: GridArg,
    /// Approximate number of grid cells (latlon: bands × sectors × 2 with 3 sectors
    /// per 2 bands; icosphere: 20·4^k; healpix: 12·N²).
    #[arg(long, default_value_t = millplan_driver::command_defaults::setup::CELLS)]
    pub cells: usize,
    /// Tool mode: a ball-end mill `D,REACH[,HOLDER_D,HOLDER_LENGTH]` in mm (REACH
    /// from the ball centre to the holder). Without it, line of sight.
    #[arg(long, allow_hyphen_values = true)]
    pub tool: Option<String>,
    /// A direction must leave the facet's surface by more than this, degrees.
    #[arg(long, default_value_t = millplan_driver::command_defaults::setup::CLEARANCE_DEG)]
    pub clearance: f64,
    /// The part stands on its bottom face (the facets facing down at its lowest
    /// Z): leave those out and keep that face on the table (the search then only
    /// spins the part about the vertical).
    #[arg(long)]
    pub ignore_bottom: bool,
    /// Required ranges of a machine with a C axis by the exact window algorithm
    /// (every tilt interval, the smallest C window for each) instead of the fast
    /// nearest-direction method; slow on fine grids and large parts.
    #[arg(long)]
    pub exact: bool,
    /// Write an HTML report: the sphere map of directions and the part coloured by tilt.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Write the part rotated into the chosen setup (binary STL).
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum TypeArg {
    /// Tilting A table carrying a C rotary table.
    Ca,
    /// A table on a B cradle (two tilting axes).
    Ab,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum GridArg {
    /// Latitude-longitude bands and sectors, each split into two triangles.
    Latlon,
    /// Geodesic icosphere, near-uniform cells.
    Icosphere,
    /// HEALPix, equal-area cells on rings of constant latitude.
    Healpix,
}

/// The machine from --machine, or --type with --range1/--range2.
fn request(a: &Args) -> SetupRequest {
    SetupRequest {
        grid: match a.grid {
            GridArg::Latlon => GridKind::LatLon,
            GridArg::Icosphere => GridKind::Icosphere,
            GridArg::Healpix => GridKind::Healpix,
        },
        cells: a.cells,
        tool: a.tool.clone(),
        clearance: a.clearance,
        ignore_bottom: a.ignore_bottom,
        exact: a.exact,
    }
}

/// The setup search, with a bar of the share done and the time left where
/// it takes a while (hidden with -q and when standard error is no terminal).
pub fn run(a: Args) -> CliResult<i32> {
    let watch = crate::progress::Watch::new(&a.part.stl, a.notes.quiet, a.summary.json);
    let watch = watch.bars_under_json();
    let c = lib::SetupCommand {
        part: a.part.file(),
        machine: a.machine.as_deref(),
        kind: a.kind.map(|t| match t {
            TypeArg::Ca => MachineType::Ca,
            TypeArg::Ab => MachineType::Ab,
        }),
        ranges: (&a.range1, &a.range2),
        output: a.output.as_deref(),
        report: a.report.as_deref(),
        request: request(&a),
        limits: crate::limits::get(),
    };
    let r = lib::run_command(&c, &watch)?;
    let (req, plan, machine) = (&c.request, &r.plan, &r.machine);
    let s = plan.summary(&r.mesh, machine);
    let v = lib::verdict(req, &r.mesh, plan);
    let stl = a.part.stl.display().to_string();
    let text = || lib::render_text(req, &stl, (&s, &v), plan);
    let j = || lib::Report::new(req, &s, machine, (r.seconds, v.clone()));
    crate::cmd::print_summary(a.summary.json, j, text);
    watch.lap("summary printed");
    watch.print_timings(a.timings.on);
    Ok(exit(!plan.feasible))
}
