//! `millplan raster`'s run: the request and the outputs checked, the
//! machine file and the part read, the raster's size against the limits,
//! the raster generated, written in memory, read back and checked, renamed
//! into place, its time estimated.

use super::*;
use crate::io::inputs::PartFile;
use crate::watch::{enforce, Stop, Watch};
use std::path::Path;

/// A `raster` run as its caller asks for it.
pub struct RasterCommand<'a> {
    pub part: PartFile<'a>,
    pub machine: Option<&'a Path>,
    pub output: &'a Path,
    /// The output's dialect when given (`--to`).
    pub to: Option<Target>,
    pub request: RasterRequest,
    /// The limits of the run (the raster's moves and memory, the writing).
    pub limits: millplan_geom::limits::Limits,
    /// Whether a raster the checks refuse is written anyway.
    pub force: bool,
}

/// What a `raster` run wrote and found.
pub struct RasterRun {
    pub program: Program,
    pub machine: Machine,
    pub params: RasterParams,
    pub gouges: GougeReport,
    pub checks: Vec<Check>,
    pub estimate: TimeEstimate,
}

impl RasterRun {
    /// The summary of the run of `c`.
    pub fn report(&self, c: &RasterCommand) -> Report<'_> {
        let output = c.output.display().to_string();
        let on = (&self.program, &self.machine, &self.params);
        Report::new(output, on, (&self.gouges, &self.checks), &self.estimate)
    }

    /// Whether a check failed (the raster written by `--force`).
    pub fn findings(&self) -> bool {
        !safety::passed(&self.checks)
    }
}

/// Runs `c`, `w` hearing the laps, the part's findings, the writer's
/// warnings and the checks' refusal (located in the output).
pub fn run_command(c: &RasterCommand, w: &dyn Watch) -> Result<RasterRun, Stop> {
    let p = params(&c.request).map_err(Stop::input)?;
    let (stl, output) = (c.part.path, c.output);
    let inputs = [Some(stl), c.machine];
    let mut outputs = crate::io::outputs::plan(&inputs, &[("-o", Some(output))], false)?;
    let machine = crate::io::inputs::read_machine(c.machine)?;
    w.lap("arguments, machine file and outputs checked");
    let mesh = c.part.read(&c.limits)?;
    w.lap("part read");
    let (points, bytes) =
        check_grid(&p, &mesh.bounds(), c.limits.moves as f64).map_err(Stop::input)?;
    let what = format!("a raster of {} points", amount(points.ceil()));
    crate::limits::check_memory(&c.limits, &what, bytes).map_err(Stop::input)?;
    let found: Vec<_> = millplan_plan::checks::mesh(&mesh).into_iter().collect();
    w.findings(stl, &found);
    let (program, part) = generate(&mesh, &p);
    w.lap("raster generated (drop-cutter)");
    if program.move_count() == 0 {
        return Err(Stop::input(format!(
            "{}: the raster does not cross the part (check --boundary)",
            stl.display()
        )));
    }
    let target = crate::target::output_target(c.to, output, Some(&machine), Dialect::Generated)
        .map_err(Stop::input)?;
    let mut wo = machine.write_options(target);
    wo.limits = c.limits;
    let out = crate::watch::write_program(&program, wo, stl, w)?;
    w.lap("program written");
    let (checks, gouges) = check((&program, &out), target, &part, &machine, &p)
        .map_err(|e| Stop::Internal(format!("{}: {e}", output.display())))?;
    enforce(&checks, output, c.force, w)?;
    w.lap("written program read back and checked");
    outputs.write(output, &out)?;
    outputs.commit()?;
    w.lap("output synced and renamed into place");
    let estimate = millplan_plan::timing::estimate_program(&program, &machine);
    Ok(RasterRun {
        program,
        machine,
        params: p,
        gouges,
        checks,
        estimate,
    })
}
