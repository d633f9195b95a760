//! `simulate`: the stock simulation of `millplan simulate` (the driver's
//! `simulate` module): removed volume and engagement per move as NumPy
//! columns, the report as `simulate --json` prints it, with the GIL
//! released.

use crate::error::{guard, option_error, read_bytes, write_bytes, Located, Place, Res};
use millplan_driver::command_defaults::simulate as defaults;
use millplan_driver::simulate::{self as lib, SimRequest};
use millplan_driver::StockSpec;
use millplan_geom::TriMesh;
use millplan_nc::Program;
use millplan_sim::stock::sim::MoveCut;
use numpy::ndarray::Array1;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// What a run gives back: the per-move rows and the report (JSON).
struct Ran {
    moves: Vec<MoveCut>,
    report_json: String,
}

/// The inputs of one run besides the request.
struct Given<'a> {
    name: &'a str,
    program: &'a Program,
    stock: &'a str,
    part: Option<&'a TriMesh>,
    rapid: f64,
    output: Option<&'a str>,
}

/// The blank of an `stl:` stock, read.
fn blank(spec: &StockSpec) -> Res<Option<TriMesh>> {
    let StockSpec::Stl(p) = spec else {
        return Ok(None);
    };
    let p = p.display().to_string();
    Ok(Some(crate::mesh::parse_stl(&p, &read_bytes(&p)?)?.0))
}

/// The run of `millplan simulate` (the driver's `simulate::command`: the
/// strokes, the stock built, the simulation, what is left on the part), the
/// stock's STL written.
fn run(req: &SimRequest, g: &Given) -> Res<Ran> {
    guard(g.name, || {
        let spec = StockSpec::parse(g.stock)
            .map_err(|e| Located::new(Place::file("stock"), e.to_string()))?;
        let blank = blank(&spec)?;
        let inputs = lib::SimInputs {
            name: g.name,
            program: g.program,
            stock: g.stock,
            spec: &spec,
            part: g.part,
            blank: blank.as_ref(),
            rapid: g.rapid,
            memory: millplan_geom::limits::Limits::default().memory,
        };
        let sim = lib::command(req, &inputs, &mut |_| {}, &|_, _| {}).map_err(|e| match e {
            lib::SimError::Program(e) => crate::error::located(&e),
            lib::SimError::Stock(e) => match e.strip_prefix(&format!("{}: ", g.name)) {
                Some(m) => Located::new(Place::file(g.name), m),
                None => Located::new(Place::file("stock"), e),
            },
        })?;
        if let Some(o) = g.output {
            write_bytes(o, &lib::stock_stl(&sim.stock, req.mesh_resolution))?;
        }
        let report_json = serde_json::to_string(&sim.report(g.stock))
            .map_err(|e| Located::new(Place::file(g.name), e.to_string()))?;
        Ok(Ran {
            moves: sim.run.per_move,
            report_json,
        })
    })
}

/// One column of the rows.
fn col<T: Copy>(rows: &[MoveCut], f: impl Fn(&MoveCut) -> T) -> Array1<T> {
    rows.iter().map(f).collect()
}

/// The per-move rows as NumPy columns, named as `simulate --table` names them.
fn columns<'py>(py: Python<'py>, rows: &[MoveCut]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("index", col(rows, |m| m.index).into_pyarray(py))?;
    d.set_item("line", col(rows, |m| m.line).into_pyarray(py))?;
    let f64s: [crate::Column<MoveCut, f64>; 7] = [
        ("removed_mm3", |m| m.removed_mm3),
        ("mrr", |m| m.mrr),
        ("ap", |m| m.ap),
        ("ae", |m| m.ae),
        ("holder_depth", |m| m.holder_depth),
        ("depth", |m| m.depth),
        ("minutes", |m| m.minutes),
    ];
    for (name, f) in f64s {
        d.set_item(name, col(rows, f).into_pyarray(py))?;
    }
    d.set_item("air", col(rows, |m| m.air).into_pyarray(py))?;
    d.set_item("rapid", col(rows, |m| m.rapid).into_pyarray(py))?;
    Ok(d)
}

/// `millplan simulate`: returns (columns per move, report JSON as Python).
#[pyfunction]
#[pyo3(signature = (program, stock, part=None, machine=None, tools=None, holder=None,
                    flute_length=None, shank=None, resolution=None, tol=None,
                    mesh_resolution=None, output=None))]
#[allow(clippy::too_many_arguments)]
pub fn simulate<'py>(
    py: Python<'py>,
    program: &Bound<'py, PyAny>,
    stock: String,
    part: Option<&Bound<'py, PyAny>>,
    machine: Option<std::path::PathBuf>,
    tools: Option<String>,
    holder: Option<String>,
    flute_length: Option<f64>,
    shank: Option<f64>,
    resolution: Option<f64>,
    tol: Option<f64>,
    mesh_resolution: Option<f64>,
    output: Option<std::path::PathBuf>,
) -> PyResult<(Bound<'py, PyDict>, Py<PyAny>)> {
    let req = SimRequest {
        tool: tools,
        holder,
        flute_length,
        shank,
        resolution: resolution.unwrap_or(defaults::RESOLUTION),
        tol: tol.unwrap_or(defaults::TOL),
        mesh_resolution,
    };
    lib::check(&req).map_err(|e| option_error(&e))?;
    lib::body_options(&req).map_err(|e| option_error(&e))?;
    let (p, name) = crate::job::program_arg(program)?;
    let part = crate::job::part_arg(part)?;
    let m = crate::program::machine(machine.map(|m| m.display().to_string()).as_deref())?;
    let output = output.map(|o| o.display().to_string());
    let given = Given {
        name: &name,
        program: &p,
        stock: &stock,
        part: part.as_ref(),
        rapid: m.rapid,
        output: output.as_deref(),
    };
    let ran = py.detach(|| run(&req, &given))?;
    let report = crate::json_to_py(py, &ran.report_json)?;
    Ok((columns(py, &ran.moves)?, report))
}
