//! `millplan orient`'s run: the materials, the request and the outputs
//! checked, the machine file, the program, the part and an `stl:` stock's
//! blank read, the choice and its checks, the program written only when an
//! operation was re-oriented and the checks pass or `--force`.

use super::*;
use crate::io::inputs::PartFile;
use crate::watch::{enforce, Stop, Watch};
use millplan_nc::write::Target;
use std::path::Path;

/// An `orient` run as its caller asks for it.
pub struct OrientCommand<'a> {
    pub input: &'a Path,
    pub part: PartFile<'a>,
    pub machine: Option<&'a Path>,
    /// The materials file (`--materials`) beside the built-in ones.
    pub materials: Option<&'a Path>,
    pub output: &'a Path,
    /// The output's dialect when given (`--to`).
    pub to: Option<Target>,
    pub request: OrientRequest,
    /// How the program is read (its limits bound the stock and the writing).
    pub read: millplan_nc::ReadOptions,
    /// Whether a program the checks refuse is written anyway.
    pub force: bool,
}

/// What an `orient` run chose and wrote.
pub struct OrientRun {
    /// With the checks when an operation was re-oriented.
    pub summary: Summary,
    /// Whether the run ends with exit 3: no operation re-oriented (nothing
    /// written), or written only by `--force`.
    pub findings: bool,
}

/// Runs `c`, `w` hearing the laps, the stock's phases, the operations
/// chosen, the note on moves the stock did not see and the checks' refusal.
pub fn run_command(c: &OrientCommand, w: &dyn Watch) -> Result<OrientRun, Stop> {
    let materials = crate::io::inputs::read_materials(c.materials)?;
    let p = params(&c.request, &materials).map_err(Stop::input)?;
    let spec = stock_spec(&c.request).map_err(Stop::input)?;
    let blank = c.request.stock.as_deref().and_then(StockSpec::file_of);
    let inputs = [Some(c.input), Some(c.part.path), c.machine, c.materials];
    let inputs = [&inputs[..], &[blank.as_deref()]].concat();
    let mut outputs = crate::io::outputs::plan(&inputs, &[("-o", Some(c.output))], false)?;
    let machine = crate::io::inputs::read_machine(c.machine)?;
    w.lap("arguments, materials, machine file and outputs checked");
    let parsed = crate::watch::read_program(c.input, c.read, w)?;
    let source = parsed.program.source;
    let target = crate::target::output_target(c.to, c.output, Some(&machine), source)
        .map_err(Stop::input)?;
    w.lap("program read");
    let limits = &c.read.limits;
    let mesh = c.part.read(limits)?;
    let blank = match &spec {
        Some(s) => crate::io::inputs::read_blank(s, limits, c.part.units)?,
        None => None,
    };
    w.lap("part and stock files read");
    let (name, output) = (
        c.input.display().to_string(),
        c.output.display().to_string(),
    );
    let g = OrientInputs {
        name: &name,
        output: &output,
        program: &parsed.program,
        mesh: &mesh,
        machine: &machine,
        blank: blank.as_ref(),
        memory: limits.memory,
    };
    let o = choose(&c.request, p, &g, w)?;
    w.lap("lead and tilt chosen, the result checked");
    if !o.chosen {
        outputs.commit()?;
        let summary = o.summary;
        return Ok(OrientRun {
            summary,
            findings: true,
        });
    }
    let checked = enforce(&o.checks, c.input, c.force, w)?;
    let summary = o.summary.with_checks(o.checks);
    let mut wo = machine.write_options(target);
    wo.limits = c.read.limits;
    let warnings = outputs.write_program(c.output, &o.program, wo, c.input)?;
    w.diagnostics_written(&warnings);
    outputs.commit()?;
    w.lap("output written, read back and renamed into place");
    let findings = !checked;
    Ok(OrientRun { summary, findings })
}

/// The choice over the inputs `g`, `w` hearing the stock's phases and the
/// operations done, then the note on moves the stock did not see.
fn choose(
    req: &OrientRequest,
    p: Params,
    g: &OrientInputs,
    w: &dyn Watch,
) -> Result<Outcome, Stop> {
    let total = g.program.operations.len();
    let o = command(req, p, g, &|stage, done, all| match stage {
        Stage::Stock => w.phase("stock", done, all),
        Stage::Operations => {
            w.phases_done();
            w.count("lead/tilt", Some("operations"), done, total)
        }
    })
    .map_err(Stop::input)?;
    w.phases_done();
    w.counted();
    if let Some(n) = o.unsimulated_note(g.name) {
        w.note(&n);
    }
    Ok(o)
}
