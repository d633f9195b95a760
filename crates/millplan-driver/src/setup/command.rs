//! `millplan setup`'s run: the outputs and the request checked, the
//! machine, the part read, the cones of access and the setups searched,
//! the part turned and the report renamed into place.

use super::*;
use crate::io::inputs::PartFile;
use crate::watch::{Stop, Watch};
use std::path::Path;

/// A `setup` run as its caller asks for it.
pub struct SetupCommand<'a> {
    pub part: PartFile<'a>,
    /// The machine file (`--machine`), else the machine of `--type` with
    /// the rotary ranges `ranges`.
    pub machine: Option<&'a Path>,
    pub kind: Option<MachineType>,
    pub ranges: (&'a str, &'a str),
    /// The part turned into the setup found (`-o`), and the report.
    pub output: Option<&'a Path>,
    pub report: Option<&'a Path>,
    pub request: SetupRequest,
    pub limits: millplan_geom::limits::Limits,
}

/// What a `setup` run found: the part (facets turned outward), the plan,
/// the machine and the search's wall time, s.
pub struct SetupRun {
    pub mesh: TriMesh,
    pub plan: SetupPlan,
    pub machine: Kinematics,
    pub seconds: f64,
}

/// Runs `c`, `w` hearing the laps, the search's share done (on a long
/// search) and the note on facets wound inward.
pub fn run_command(c: &SetupCommand, w: &dyn Watch) -> Result<SetupRun, Stop> {
    let inputs = [Some(c.part.path), c.machine];
    let outs = [("-o", c.output), ("--report", c.report)];
    let mut outputs = crate::io::outputs::plan(&inputs, &outs, false)?;
    check(&c.request).map_err(Stop::input)?;
    let file = c.machine.map(|p| crate::io::inputs::read_machine(Some(p)));
    let file = file.transpose()?;
    let path = c.machine.map(|p| p.display().to_string());
    let file = file.as_ref().zip(path.as_deref());
    let machine = kinematics(file, c.kind, c.ranges).map_err(Stop::input)?;
    let p = params(&c.request).map_err(Stop::input)?;
    w.lap("arguments, machine file and outputs checked");
    let mut mesh = c.part.read(&c.limits)?;
    w.lap("part read");
    let t0 = std::time::Instant::now();
    let shown = shows_progress(&mesh, &p);
    let progress = |done: usize, total: usize| {
        if shown {
            w.count("cones of access", None, done, total)
        }
    };
    let plan = millplan_plan::setup::plan_with_progress(&mut mesh, &machine, &p, &progress);
    w.counted();
    let plan = plan.map_err(|e| match e {
        SetupError::NoTriangles => Stop::input(format!("{}: {e}", c.part.path.display())),
        e => Stop::input(e.to_string()),
    })?;
    let seconds = t0.elapsed().as_secs_f64();
    w.lap("cones of access and setups searched");
    let stl = c.part.path.display().to_string();
    if let Some(n) = flipped_note(&plan, &stl) {
        w.note(&n);
    }
    if let Some(out) = c.output {
        outputs.write(out, &rotated_stl(&mesh, &plan))?;
    }
    if let Some(path) = c.report {
        let html = report(&c.request, stl, &mesh, &plan, &machine);
        outputs.write(path, html.as_bytes())?;
    }
    outputs.commit()?;
    w.lap("outputs written and renamed into place");
    Ok(SetupRun {
        mesh,
        plan,
        machine,
        seconds,
    })
}
