//! `raster`: a drop-cutter raster finishing path over a part, written,
//! read back and checked as `millplan raster` does it (the driver's
//! `raster` module), with the GIL released.

use crate::error::{guard, option_error, Located, Place, Res};
use millplan_driver::command_defaults::raster as defaults;
use millplan_driver::raster::{self as lib, RasterParams, RasterRequest};
use millplan_geom::TriMesh;
use millplan_nc::write::Target;
use millplan_nc::Program;
use millplan_plan::machine::Machine;
use pyo3::prelude::*;

/// The raster of `mesh`, its checks and the report (JSON), as the command
/// makes them; an error when a check fails, unless `force`.
fn run(
    mesh: &TriMesh,
    p: &RasterParams,
    machine: &Machine,
    target: Target,
    force: bool,
) -> Res<(Program, String)> {
    guard("raster", || {
        let err = |e: String| Located::new(Place::file("raster"), e);
        let limits = millplan_geom::limits::Limits::default();
        lib::check_grid(p, &mesh.bounds(), limits.moves as f64).map_err(|e| option_error(&e))?;
        let (prog, part) = lib::generate(mesh, p);
        if prog.move_count() == 0 {
            return Err(err(
                "the raster does not cross the part (check boundary)".into()
            ));
        }
        let wo = millplan_nc::write::WriteOptions {
            limits,
            ..machine.write_options(target)
        };
        let (out, _) = millplan_nc::write::write_program(&prog, wo)
            .map_err(|e| err(format!("line {}: {}", e.line, e.message)))?;
        let (checks, rep) = lib::check((&prog, &out), target, &part, machine, p).map_err(err)?;
        if !force && !millplan_plan::safety::passed(&checks) {
            let failed: Vec<&str> = checks.iter().filter(|c| !c.ok).map(|c| c.name).collect();
            return Err(err(format!(
                "refused: the checks {} failed",
                failed.join(", ")
            )));
        }
        let est = millplan_plan::timing::estimate_program(&prog, machine);
        let report = lib::Report::new(String::new(), (&prog, machine, p), (&rep, &checks), &est);
        let json = serde_json::to_string(&report).map_err(|e| err(e.to_string()))?;
        Ok((prog, json))
    })
}

/// `millplan raster`: returns (program, report JSON as Python).
#[pyfunction]
#[pyo3(signature = (part, tool, stepover, step, angle=None, oneway=false, boundary=None, tol=None,
                    clearance=None, feed=None, spindle=None, machine=None, dialect=None, force=false))]
#[allow(clippy::too_many_arguments)]
pub fn raster(
    py: Python<'_>,
    part: &Bound<'_, PyAny>,
    tool: String,
    stepover: f64,
    step: f64,
    angle: Option<f64>,
    oneway: bool,
    boundary: Option<f64>,
    tol: Option<f64>,
    clearance: Option<f64>,
    feed: Option<f64>,
    spindle: Option<f64>,
    machine: Option<std::path::PathBuf>,
    dialect: Option<&str>,
    force: bool,
) -> PyResult<(crate::program::PyProgram, Py<PyAny>)> {
    let req = RasterRequest {
        tool,
        angle: angle.unwrap_or(defaults::ANGLE_DEG),
        stepover,
        step,
        oneway,
        boundary: boundary.unwrap_or(defaults::BOUNDARY),
        tol: tol.unwrap_or(defaults::TOL),
        clearance: clearance.unwrap_or(defaults::CLEARANCE),
        feed: feed.unwrap_or(defaults::FEED),
        spindle: spindle.unwrap_or(defaults::SPINDLE),
    };
    let p = lib::params(&req).map_err(|e| option_error(&e))?;
    let mesh = crate::job::mesh_arg(part)?;
    let m = crate::program::machine(machine.map(|m| m.display().to_string()).as_deref())?;
    // The dialect the program is written in for its read-back check: the
    // one given, else the machine's, else APT (a generated program has no
    // source dialect to keep).
    let target = match dialect.map(crate::program::target).transpose()? {
        Some(t) => t,
        None => m.target().unwrap_or(Target::Apt),
    };
    let (prog, json) = py.detach(|| run(&mesh, &p, &m, target, force))?;
    Ok((
        crate::program::PyProgram::of(prog),
        crate::json_to_py(py, &json)?,
    ))
}
