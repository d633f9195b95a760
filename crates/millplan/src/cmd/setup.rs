//! `millplan setup`: can a five-axis machine reach the whole part in one setup,
//! and how should the part be clamped?

use crate::error::{exit, CliError, CliResult};
use crate::timings::Table as _;
use millplan_driver::setup::{self as lib, Kinematics, MachineType, SetupRequest};
use millplan_plan::setup::{self, GridKind};
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
fn machine(a: &Args) -> CliResult<Kinematics> {
    let file = a
        .machine
        .as_deref()
        .map(|p| crate::cmd::load_machine(Some(p)));
    let file = file.transpose()?;
    let path = a.machine.as_deref().map(|p| p.display().to_string());
    let file = file.as_ref().zip(path.as_deref());
    let kind = a.kind.map(|t| match t {
        TypeArg::Ca => MachineType::Ca,
        TypeArg::Ab => MachineType::Ab,
    });
    lib::kinematics(file, kind, (&a.range1, &a.range2)).map_err(CliError::input)
}

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
fn plan_shown(
    a: &Args,
    mesh: &mut millplan_geom::TriMesh,
    machine: &Kinematics,
    p: &setup::SetupParams,
) -> CliResult<setup::SetupPlan> {
    let show = lib::shows_progress(mesh, p) && !a.notes.quiet;
    let bar = crate::progress::fraction("cones of access", show);
    let progress = |done: usize, total: usize| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    };
    let plan = setup::plan_with_progress(mesh, machine, p, &progress).map_err(|e| match e {
        setup::SetupError::NoTriangles => CliError::input(format!("{}: {e}", a.part.stl.display())),
        e => CliError::input(e.to_string()),
    });
    bar.finish_and_clear();
    plan
}

pub fn run(a: Args) -> CliResult<i32> {
    let mut clock = crate::timings::Clock::start();
    let inputs = [Some(&*a.part.stl), a.machine.as_deref()];
    let outs = [
        ("-o", a.output.as_deref()),
        ("--report", a.report.as_deref()),
    ];
    let mut outputs = crate::io::plan(&inputs, &outs, false)?;
    let req = request(&a);
    lib::check(&req).map_err(CliError::input)?;
    let machine = machine(&a)?;
    let p = lib::params(&req).map_err(CliError::input)?;
    clock.lap("arguments, machine file and outputs checked");
    let mut mesh = a.part.read()?;
    clock.lap("part read");
    let t0 = std::time::Instant::now();
    let plan = plan_shown(&a, &mut mesh, &machine, &p)?;
    let secs = t0.elapsed().as_secs_f64();
    clock.lap("cones of access and setups searched");
    let stl = a.part.stl.display().to_string();
    match lib::flipped_note(&plan, &stl) {
        Some(n) if !a.notes.quiet && !a.summary.json => eprintln!("{n}"),
        _ => {}
    }
    if let Some(out) = &a.output {
        outputs.write(out, &lib::rotated_stl(&mesh, &plan))?;
    }
    if let Some(path) = &a.report {
        let html = lib::report(&req, stl.clone(), &mesh, &plan, &machine);
        outputs.write(path, html.as_bytes())?;
    }
    outputs.commit()?;
    clock.lap("outputs written and renamed into place");
    let s = plan.summary(&mesh, &machine);
    let v = lib::verdict(&req, &mesh, &plan);
    let text = || lib::render_text(&req, &stl, (&s, &v), &plan);
    let j = || lib::Report::new(&req, &s, &machine, (secs, v.clone()));
    crate::cmd::print_summary(a.summary.json, j, text);
    clock.end(a.timings.on);
    Ok(exit(!plan.feasible))
}
