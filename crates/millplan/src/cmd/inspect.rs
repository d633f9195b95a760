//! `millplan inspect`: what a file holds.

use crate::cmd::{print_diagnostics, UnitArg};
use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::{read_any, Input};
use crate::timings::Table as _;
use millplan_driver::inspect as lib;
use std::path::PathBuf;

/// Print what a file holds: format and dialect, units, tools, moves, bounds,
/// path lengths and estimated time (programs); triangles, defects and bounds (STL).
///
/// The time is an estimate with acceleration: the machine file's axis
/// velocities, accelerations and jerks (conservative defaults where it has
/// none), with look-ahead across blocks; the time at programmed feeds is
/// printed beside it. The estimate follows the control's planner (the
/// machine file's `[control] planner`) and honours the program's
/// path-control mode (exact stop, blending within a tolerance) at every
/// block; the time under each mode is printed below it.
///
/// The format is detected from the content, not the file name.
#[derive(clap::Args)]
pub struct Args {
    /// APT/CL, G-code (Fanuc, Sinumerik, LinuxCNC, Heidenhain) or STL file.
    pub file: PathBuf,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    /// Print the program's IR, one line per move and event.
    #[arg(long)]
    pub ir: bool,
    #[command(flatten)]
    pub units: crate::cmd::args::ProgramUnits,
    /// Rapid traverse rate for the time estimate, mm/min (default: the
    /// machine file's, else 15000).
    #[arg(long)]
    pub rapid_rate: Option<f64>,
    #[command(flatten)]
    pub machine: crate::cmd::args::MachineFile,
    #[command(flatten)]
    pub notes: crate::cmd::args::Quiet,
    /// Unit of an STL's numbers (an STL does not say): mm or inch, converted
    /// to mm; without it the unit is guessed from the part's size.
    #[arg(long, value_enum)]
    pub stl_units: Option<UnitArg>,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

pub fn run(a: Args) -> CliResult<i32> {
    // A summary holds the program's moves and little else: in 2 MiB pages
    // the allocator's small objects kept about 6 MB more resident (82 MB
    // against 76 MB on 1,000,000 GOTOs, docs/benchmarks.md), at no gain.
    crate::small_pages_only();
    let mut clock = crate::timings::Clock::start();
    let mut machine = a.machine.load()?;
    machine.rapid = lib::rapid_rate(&machine, a.rapid_rate).map_err(CliError::input)?;
    clock.lap("arguments and machine file");
    let input = read_any(&a.file, a.units.options()?)?;
    clock.lap("file read");
    let name = a.file.display().to_string();
    match input {
        Input::Program(parsed) => {
            let p = &parsed.program;
            print_diagnostics(
                &a.file,
                &parsed.diagnostics,
                a.notes.quiet || a.summary.json,
            );
            if a.ir {
                out!("{}", millplan_nc::text::print(p));
                clock.lap("IR printed");
                clock.print(a.timings.on);
                return Ok(EXIT_OK);
            }
            let j = lib::program_json(p, parsed.diagnostics.len(), &machine);
            clock.lap("summary and time estimate");
            a.summary.print(&j, |j| lib::render_program(&name, p, j));
        }
        Input::Mesh(mut mesh, r) => {
            let given = a.stl_units.map(Into::into);
            lib::to_mm(&mut mesh, given);
            let j = lib::mesh_json(&mesh, &r, given);
            clock.lap("summary (edges, bounds)");
            a.summary.print(&j, |j| lib::render_mesh(&name, j));
        }
    }
    clock.lap("printed");
    clock.print(a.timings.on);
    Ok(EXIT_OK)
}
