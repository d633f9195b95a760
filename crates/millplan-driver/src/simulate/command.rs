//! `millplan simulate`'s run: the options and the stock checked, the
//! program, the part and an `stl:` stock's blank read, the simulation, the
//! stock mesh, the table and the report renamed into place.

use super::*;
use crate::io::inputs::PartFile;
use crate::io::outputs::Outputs;
use crate::watch::{Stop, Watch};
use std::path::Path;

/// A `simulate` run as its caller asks for it.
pub struct SimCommand<'a> {
    pub input: &'a Path,
    pub request: SimRequest,
    /// The stock as given (`--stock`).
    pub stock: &'a str,
    /// The part (`--stl`) and the unit of the STL files read (`--stl-units`).
    pub part: Option<&'a Path>,
    pub stl_units: Option<millplan_nc::LengthUnit>,
    pub machine: Option<&'a Path>,
    /// The stock's mesh (`-o`), the per-move table and the report.
    pub output: Option<&'a Path>,
    pub table: Option<&'a Path>,
    pub report: Option<&'a Path>,
    /// How the program is read (its limits bound the stock's memory too).
    pub read: millplan_nc::ReadOptions,
}

/// Runs `c`, `w` hearing the laps, the strokes simulated (as the phase
/// `simulating`, on a long run only) and the note on the flute length.
pub fn run_command(c: &SimCommand, w: &dyn Watch) -> Result<Simulated, Stop> {
    // Checked before any work, not after the simulation.
    check(&c.request).map_err(Stop::input)?;
    let spec = StockSpec::parse(c.stock).map_err(|e| Stop::input(format!("--stock {e}")))?;
    let machine = crate::io::inputs::read_machine(c.machine)?;
    let blank = match &spec {
        StockSpec::Stl(p) => Some(p.as_path()),
        _ => None,
    };
    let inputs = [Some(c.input), c.part, c.machine, blank];
    let outs = [("-o", c.output), ("--table", c.table)];
    let outs = [&outs[..], &[("--report", c.report)]].concat();
    let mut outputs = crate::io::outputs::plan(&inputs, &outs, false)?;
    w.lap("arguments, machine file and outputs checked");
    let parsed = crate::watch::read_program(c.input, c.read, w)?;
    w.lap("program read");
    let limits = &c.read.limits;
    let units = c.stl_units;
    let part = c.part.map(|path| PartFile { path, units }.read(limits));
    let part = part.transpose()?;
    let blank = crate::io::inputs::read_blank(&spec, limits, units)?;
    w.lap("part read");
    let name = c.input.display().to_string();
    let g = SimInputs {
        name: &name,
        program: &parsed.program,
        stock: c.stock,
        spec: &spec,
        part: part.as_ref(),
        blank: blank.as_ref(),
        rapid: machine.rapid,
        memory: limits.memory,
    };
    // Shown on a long run only.
    let progress = |done: usize, total: usize| {
        if total > crate::command_defaults::progress::LONG_SIMULATION_STROKES {
            w.phase("simulating", done, total)
        }
    };
    let run = command(&c.request, &g, &mut |l| w.lap(l), &progress);
    w.phases_done();
    let sim = run.map_err(|e| Stop::input(e.to_string()))?;
    if let Some(note) = &sim.flute_note {
        w.note(&format!("note: {note}"));
    }
    write_outputs(c, &mut outputs, &sim, part.as_ref())?;
    outputs.commit()?;
    w.lap("outputs written, synced and renamed into place");
    Ok(sim)
}

/// Writes the stock's mesh, the table and the report asked for.
fn write_outputs(
    c: &SimCommand,
    outputs: &mut Outputs,
    sim: &Simulated,
    part: Option<&TriMesh>,
) -> Result<(), Stop> {
    if let Some(p) = c.output {
        outputs.write(p, &stock_stl(&sim.stock, c.request.mesh_resolution))?;
    }
    if let Some(p) = c.table {
        outputs.write(p, sim.table_csv().as_bytes())?;
    }
    if let Some(p) = c.report {
        let files = (c.input, c.part);
        let html = sim.report_html(&c.request, files, c.stock, part);
        outputs.write(p, html.as_bytes())?;
    }
    Ok(())
}
