//! `reorder`: the reordering pass of `millplan reorder` (millplan-plan's
//! `ReorderPass`, then the speed pass unless left out), checked by the
//! driver's `reorder` module, with the GIL released.

use crate::error::{guard, option_error, Located, Place, Res};
use millplan_driver::command_defaults::{cutting, reorder as defaults};
use millplan_geom::TriMesh;
use millplan_nc::Program;
use millplan_plan::machine::Machine;
use millplan_plan::pipeline::{self, Context, Pass};
use millplan_plan::reorder::{Method, ReorderParams, ReorderPass, Start};
use millplan_plan::speed::{SpeedParams, SpeedPass};
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

/// The pass's parameters, as the command builds them from its options.
pub fn params(o: &Options) -> Res<ReorderParams> {
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
    let req = millplan_driver::speed::SpeedRequest {
        cut: o.cut,
        ball_d: None,
        s_threshold: millplan_driver::command_defaults::speed::S_THRESHOLD,
        keep_feed: false,
        convention: None,
        normals: millplan_driver::speed::NormalMode::Smooth,
        nearest_incentre: false,
        keep_rows: false,
    };
    millplan_driver::speed::check(&req).map_err(|e| option_error(&e))?;
    let max_step = o.max_step.unwrap_or(defaults::MAX_STEP);
    let tie = o.tie.unwrap_or(defaults::TIE);
    millplan_driver::check::arg(
        "--max-step",
        max_step,
        millplan_driver::check::Range::from(0.0, 1000.0, "mm"),
    )
    .map_err(|e| option_error(&e))?;
    millplan_driver::check::arg(
        "--tie",
        tie,
        millplan_driver::check::Range::from(0.0, 100.0, "mm"),
    )
    .map_err(|e| option_error(&e))?;
    let mut rp = ReorderParams::new(method);
    rp.start = start;
    rp.n_min = o.n_min.unwrap_or(defaults::N_MIN);
    rp.tie = tie;
    rp.max_step = (max_step > 0.0).then_some(max_step);
    rp.ap = o.cut.ap;
    rp.vc = o.cut.vc;
    rp.speed = speed_params(o.cut);
    Ok(rp)
}

fn speed_params(c: millplan_driver::speed::Cutting) -> SpeedParams {
    let mut p = SpeedParams::new(c.vc, c.fz, c.flutes, c.ap);
    p.keep_rows = false;
    p
}

/// The passes over a copy of `input`, the checks, the summary (JSON).
fn run(
    input: &Program,
    mesh: &TriMesh,
    machine: Machine,
    rp: ReorderParams,
    speed: bool,
    method: &str,
) -> Res<(Program, String)> {
    guard("reorder", || {
        let err = |e: String| Located::new(Place::file("reorder"), e);
        let mut program = input.clone();
        let cx = Context::new(machine).with_part(mesh);
        let mut reorder = ReorderPass::new(rp);
        let mut sp = SpeedPass::new(rp.speed);
        let mut passes: Vec<&mut dyn Pass> = vec![&mut reorder];
        if speed {
            passes.push(&mut sp);
        }
        pipeline::run(&mut passes, &mut program, &cx).map_err(|e| err(e.to_string()))?;
        let o = reorder
            .outcome
            .take()
            .ok_or_else(|| err("the pass left no outcome".into()))?;
        let checks = millplan_driver::reorder::check(input, &program, &cx);
        let s = millplan_driver::reorder::Summary::new(
            Some(method.to_string()),
            &o,
            String::new(),
            &checks,
        );
        let json = serde_json::to_string(&s).map_err(|e| err(e.to_string()))?;
        Ok((program, json))
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
    let rp = params(&o)?;
    let (input, _) = crate::job::program_arg(program)?;
    let mesh = crate::job::mesh_arg(part)?;
    let m = crate::program::machine(machine.map(|m| m.display().to_string()).as_deref())?;
    let method = method.unwrap_or("as-run").to_string();
    let (prog, json) = py.detach(|| run(&input, &mesh, m, rp, speed, &method))?;
    Ok((
        crate::program::PyProgram::of(prog),
        crate::json_to_py(py, &json)?,
    ))
}
