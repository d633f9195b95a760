//! `gouge`: the drop-cutter check of `millplan gouge` (the driver's `gouge`
//! module) with the GIL released; its report as `gouge --json` prints it.

use crate::error::{guard, option_error, Located, Place};
use millplan_driver::command_defaults::gouge as defaults;
use millplan_driver::gouge::{self as lib, GougeRequest};
use pyo3::prelude::*;

/// Checks every cutting move of `program` against `part`; returns the
/// report as JSON text.
#[pyfunction]
#[pyo3(signature = (program, part, tol=None, step=None, rapids=false, tools=None))]
pub fn gouge(
    py: Python<'_>,
    program: &Bound<'_, PyAny>,
    part: &Bound<'_, PyAny>,
    tol: Option<f64>,
    step: Option<f64>,
    rapids: bool,
    tools: Option<String>,
) -> PyResult<Py<PyAny>> {
    let req = GougeRequest {
        tol: tol.unwrap_or(defaults::TOL),
        step: step.unwrap_or(defaults::STEP),
        rapids,
        tool: tools,
    };
    let (g, fallback) = lib::params(&req).map_err(|e| option_error(&e))?;
    let (p, name) = crate::job::program_arg(program)?;
    let mesh = crate::job::mesh_arg(part)?;
    let json = py.detach(|| {
        guard(&name, || {
            if fallback.is_none() {
                lib::shape_is_known(&name, &p).map_err(|e| crate::error::located(&e))?;
            }
            let rep = lib::check(&p, &mesh, fallback, &g, &|_, _| {});
            if rep.moves_checked == 0 {
                let why = lib::skipped(&rep.skipped);
                return Err(Located::new(
                    Place::file(&name),
                    format!("no move could be checked ({why})"),
                ));
            }
            let report = lib::Report::new(&rep, req.tol);
            serde_json::to_string(&report)
                .map_err(|e| Located::new(Place::file(&name), e.to_string()))
        })
    })?;
    crate::json_to_py(py, &json)
}
