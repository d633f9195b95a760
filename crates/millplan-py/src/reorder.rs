//! `reorder`: the reordering pass of `millplan reorder` (millplan-plan's
//! `ReorderPass`, then the speed pass unless left out), checked by the
//! driver's `reorder` module, with the GIL released.

use crate::error::{guard, option_error, Located, Place, Res};
use millplan_driver::command_defaults::{cutting, reorder as defaults};
use millplan_driver::reorder::{self as lib, ReorderRequest};
use millplan_geom::TriMesh;
use millplan_nc::Program;
use millplan_plan::machine::Machine;
use millplan_plan::pipeline::Context;
use millplan_plan::reorder::{Method, ReorderParams, Start};
use pyo3::prelude::*;

/// The options of `reorder` as Python gives them.
pub struct Options<'a> {
    pub method: Option<&'a str>,
    pub start: Option<&'a str>,
    pub start_index: Option<usize>,
    pub seed: Option<u64>,
    pub n_min: Option<usize>,
    pub tie: Option<f64>,
    pub max_step: Option<f64>,
    pub cut: millplan_driver::speed::Cutting,
}

fn bad(what: &str, m: String) -> Located {
    Located::new(Place::file(what), m)
}

/// The request of `millplan reorder` and the pass's parameters, checked as
/// the command checks them.
pub fn request(o: &Options, speed: bool) -> Res<(ReorderRequest, ReorderParams)> {
    let method = match o.method.unwrap_or("as-run") {
        "as-run" => Method::AsRun,
        "paper" => Method::Paper,
        "optimised" => Method::Optimised,
        x => return Err(bad("method", format!("{x:?}: as-run, paper or optimised"))),
    };
    let seed = o.seed.unwrap_or(defaults::SEED);
    let start = match (o.start_index, o.start.unwrap_or("lowest")) {
        (Some(i), _) => Start::Index(i),
        (None, "lowest") => Start::Lowest,
        (None, "highest") => Start::Highest,
        (None, "random") => Start::Random(seed),
        (None, x) => return Err(bad("start", format!("{x:?}: lowest, highest or random"))),
    };
    let req = ReorderRequest {
        method,
        start,
        n_min: o.n_min.unwrap_or(defaults::N_MIN),
        tie: o.tie.unwrap_or(defaults::TIE),
        max_step: o.max_step.unwrap_or(defaults::MAX_STEP),
        cut: o.cut,
        speed,
    };
    let rp = req.params().map_err(|e| option_error(&e))?;
    Ok((req, rp))
}

/// The run of `millplan reorder` (the driver's `reorder::command`) on a
/// copy of `input`; the summary (JSON).
fn run(
    input: &Program,
    mesh: &TriMesh,
    machine: Machine,
    (req, rp): (ReorderRequest, ReorderParams),
    method: &str,
) -> Res<(Program, String)> {
    guard("reorder", || {
        let err = |e: String| Located::new(Place::file("reorder"), e);
        let cx = Context::new(machine).with_part(mesh);
        let r = lib::command(&req, rp, &cx, input).map_err(|e| match e {
            lib::ReorderError::Pass(e) => err(e.to_string()),
            lib::ReorderError::NoOutcome => err("the pass left no outcome".into()),
        })?;
        let s = lib::Summary::new(
            Some(method.to_string()),
            &r.outcome,
            String::new(),
            &r.checks,
        );
        let json = serde_json::to_string(&s).map_err(|e| err(e.to_string()))?;
        Ok((r.program, json))
    })
}

/// `millplan reorder`: returns (program, summary JSON as Python).
#[pyfunction]
#[pyo3(signature = (program, part, method=None, start=None, start_index=None, seed=None,
                    n_min=None, tie=None, max_step=None, vc=None, fz=None, flutes=None, ap=None,
                    speed=true, machine=None))]
#[allow(clippy::too_many_arguments)]
pub fn reorder(
    py: Python<'_>,
    program: &Bound<'_, PyAny>,
    part: &Bound<'_, PyAny>,
    method: Option<&str>,
    start: Option<&str>,
    start_index: Option<usize>,
    seed: Option<u64>,
    n_min: Option<usize>,
    tie: Option<f64>,
    max_step: Option<f64>,
    vc: Option<f64>,
    fz: Option<f64>,
    flutes: Option<u32>,
    ap: Option<f64>,
    speed: bool,
    machine: Option<std::path::PathBuf>,
) -> PyResult<(crate::program::PyProgram, Py<PyAny>)> {
    let o = Options {
        method,
        start,
        start_index,
        seed,
        n_min,
        tie,
        max_step,
        cut: millplan_driver::speed::Cutting {
            vc: vc.unwrap_or(cutting::VC),
            fz: fz.unwrap_or(cutting::FZ),
            flutes: flutes.unwrap_or(cutting::FLUTES),
            ap: ap.unwrap_or(cutting::AP),
        },
    };
    let req = request(&o, speed)?;
    let (input, _) = crate::job::program_arg(program)?;
    let mesh = crate::job::mesh_arg(part)?;
    let m = crate::program::machine(machine.map(|m| m.display().to_string()).as_deref())?;
    let method = method.unwrap_or("as-run").to_string();
    let (prog, json) = py.detach(|| run(&input, &mesh, m, req, &method))?;
    Ok((
        crate::program::PyProgram::of(prog),
        crate::json_to_py(py, &json)?,
    ))
}
