//! `force`: the loads of every move of a program through its stock (the
//! driver's job, `Job::forces_of_every_move`, as `millplan force PATH` computes them), as
//! NumPy columns, with the GIL released.

use crate::error::{guard, Located, Place, Res};
use crate::job::Request;
use millplan_driver::Job;
use millplan_plan::force::{ForceRun, MoveForces};
use numpy::ndarray::Array1;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The run of the job's stock and material over its program; the summary
/// as JSON (the counts and maxima of `millplan force --json`).
fn run(r: &Request) -> Res<(ForceRun, String)> {
    guard(&r.name, || {
        let err = |e: &dyn std::fmt::Display| Located::new(Place::file(&r.name), e.to_string());
        let job = Job::new(crate::job::inputs(r)?).map_err(|e| err(&e))?;
        let run = job
            .forces_of_every_move(job.analysed())
            .map_err(|e| err(&e))?
            .ok_or_else(|| err(&"give a stock and a material"))?;
        if let Some(line) = run.stopped_spindle() {
            let why = millplan_plan::force::STOPPED_SPINDLE;
            return Err(Located::new(Place::at(&r.name, line, 1), why));
        }
        let summary = serde_json::json!({
            "moves": run.moves.len(),
            "cutting_moves": run.moves.iter().filter(|x| !x.rapid).count(),
            "air_moves": run.moves.iter().filter(|x| x.air).count(),
            "unmodelled_moves": run.moves.iter().filter(|x| x.unmodelled).count(),
            "skipped_moves": run.skipped,
            "evaluations": run.evaluated,
            "time_s": run.moves.last().map_or(0.0, |x| x.t_start_s + x.seconds),
            "max": run.maxima(),
        });
        Ok((run, summary.to_string()))
    })
}

/// One column of the rows.
fn col<T: Copy>(rows: &[MoveForces], f: impl Fn(&MoveForces) -> T) -> Array1<T> {
    rows.iter().map(f).collect()
}

/// The moves' loads as NumPy columns, named as `force --table` names them.
pub(crate) fn columns<'py>(py: Python<'py>, rows: &[MoveForces]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("index", col(rows, |m| m.index).into_pyarray(py))?;
    d.set_item("line", col(rows, |m| m.line).into_pyarray(py))?;
    d.set_item("cells", col(rows, |m| m.cells as u64).into_pyarray(py))?;
    let f64s: [crate::Column<MoveForces, f64>; 22] = [
        ("t_s", |m| m.t_start_s),
        ("seconds", |m| m.seconds),
        ("rpm", |m| m.rpm),
        ("feed", |m| m.feed),
        ("fz", |m| m.fz),
        ("lead_deg", |m| m.lead_deg),
        ("dz_mm", |m| m.dz_mm),
        ("dphi_deg", |m| m.dphi_deg),
        ("removed_mm3", |m| m.removed_mm3),
        ("fxy_max", |m| m.fxy_max),
        ("fx_min", |m| m.fx[0]),
        ("fx_max", |m| m.fx[1]),
        ("fy_min", |m| m.fy[0]),
        ("fy_max", |m| m.fy[1]),
        ("fz_min", |m| m.fz_force[0]),
        ("fz_max", |m| m.fz_force[1]),
        ("torque_max", |m| m.torque_max),
        ("torque_mean", |m| m.torque_mean),
        ("power_w", |m| m.power_w),
        ("stress_mpa", |m| m.stress_mpa),
        ("deflection_mm", |m| m.deflection_mm),
        ("fz_allowed", |m| m.fz_allowed.unwrap_or(f64::NAN)),
    ];
    for (name, f) in f64s {
        d.set_item(name, col(rows, f).into_pyarray(py))?;
    }
    let bools: [crate::Column<MoveForces, bool>; 3] = [
        ("rapid", |m| m.rapid),
        ("air", |m| m.air),
        ("unmodelled", |m| m.unmodelled),
    ];
    for (name, f) in bools {
        d.set_item(name, col(rows, f).into_pyarray(py))?;
    }
    Ok(d)
}

/// `millplan force PATH`: returns (columns per move, summary).
#[pyfunction]
#[pyo3(signature = (program, stock, material, part=None, machine=None, tools=None,
                    flutes=None, resolution=None))]
#[allow(clippy::too_many_arguments)]
pub fn force<'py>(
    py: Python<'py>,
    program: &Bound<'py, PyAny>,
    stock: String,
    material: String,
    part: Option<&Bound<'py, PyAny>>,
    machine: Option<std::path::PathBuf>,
    tools: Option<String>,
    flutes: Option<usize>,
    resolution: Option<f64>,
) -> PyResult<(Bound<'py, PyDict>, Py<PyAny>)> {
    let (p, name) = crate::job::program_arg(program)?;
    let mut req = Request::new(p, name);
    req.part = crate::job::part_arg(part)?;
    req.stock = Some(stock);
    req.machine = machine.map(|m| m.display().to_string());
    req.material = Some(material);
    req.tool = tools;
    req.flutes = flutes;
    req.resolution = resolution;
    let (ran, summary) = py.detach(|| run(&req))?;
    let summary = crate::json_to_py(py, &summary)?;
    Ok((columns(py, &ran.moves)?, summary))
}
