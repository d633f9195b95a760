//! The extension module `millplan._millplan`: thin wrappers over millplan's
//! library crates. Every decision and default lives in those crates; here
//! arguments become library values, results become NumPy arrays or dicts,
//! errors become `MillplanError` with their file, line and column, and the
//! long computations run with the GIL released. The Python package
//! (`python/millplan`) re-exports these with docstrings and type stubs.

mod cut;
mod error;
mod feed;
mod force;
mod gouge;
mod job;
mod mesh;
mod post;
mod program;
mod raster;
mod reorder;
mod setup;
mod simulate;
mod speed;
mod tools;
mod wd;

use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A named column of a table of rows `R`: its name and the value of a row.
pub(crate) type Column<R, T> = (&'static str, fn(&R) -> T);

/// JSON text (a library summary serialised by serde) as Python objects.
pub(crate) fn json_to_py(py: Python<'_>, json: &str) -> PyResult<Py<PyAny>> {
    Ok(py.import("json")?.call_method1("loads", (json,))?.unbind())
}

/// What a file holds, as `millplan inspect --json` prints it.
#[pyfunction]
#[pyo3(signature = (path, machine=None, units=None))]
fn inspect(
    py: Python<'_>,
    path: std::path::PathBuf,
    machine: Option<std::path::PathBuf>,
    units: Option<&str>,
) -> PyResult<Py<PyAny>> {
    let path = path.display().to_string();
    let machine = machine.map(|m| m.display().to_string());
    let units = program::unit(units)?;
    let json = py.detach(|| {
        error::guard(&path, || {
            program::inspect_json(&path, machine.as_deref(), units)
        })
    })?;
    json_to_py(py, &json)
}

/// Reads an APT/CL or G-code program (format detected from the content).
#[pyfunction]
#[pyo3(signature = (path, units=None))]
fn read_program(
    py: Python<'_>,
    path: std::path::PathBuf,
    units: Option<&str>,
) -> PyResult<program::PyProgram> {
    let path = path.display().to_string();
    let units = program::unit(units)?;
    Ok(py.detach(|| error::guard(&path, || program::read(&path, units)))?)
}

/// Writes a program; returns the dialect written.
#[pyfunction]
#[pyo3(signature = (program, path, dialect=None, machine=None))]
fn write_program(
    py: Python<'_>,
    program: &program::PyProgram,
    path: std::path::PathBuf,
    dialect: Option<&str>,
    machine: Option<std::path::PathBuf>,
) -> PyResult<&'static str> {
    let path = path.display().to_string();
    let m = machine
        .map(|m| program::machine(Some(&m.display().to_string())))
        .transpose()?;
    let p = program.program.clone();
    let t = py.detach(|| error::guard(&path, || program::write(&p, &path, dialect, m.as_ref())))?;
    Ok(t.name())
}

/// Reads an STL part.
#[pyfunction]
#[pyo3(signature = (path, units=None))]
fn read_stl(
    py: Python<'_>,
    path: std::path::PathBuf,
    units: Option<&str>,
) -> PyResult<mesh::PyMesh> {
    let path = path.display().to_string();
    let inch = program::unit(units)? == Some(millplan_nc::LengthUnit::Inch);
    Ok(py.detach(|| error::guard(&path, || mesh::read(&path, inch)))?)
}

/// The load limits dict as `--limit NAME=VALUE` pairs (fxy N, torque N·mm,
/// power W, stress MPa, deflection mm, fz_min and fz_max mm), checked by
/// the driver as the command line's are.
pub(crate) fn loads(d: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, String)>> {
    let Some(d) = d else { return Ok(Vec::new()) };
    d.iter()
        .map(|(k, v)| Ok((k.extract::<String>()?, v.extract::<f64>()?.to_string())))
        .collect()
}

/// The job of `millplan optimise`; returns (program, text, summary JSON, refused).
#[pyfunction]
#[pyo3(signature = (program, part=None, stock=None, machine=None, material=None, tools=None,
                    flutes=None, vc=None, resolution=None, passes=None, limits=None, dialect=None, output=None,
                    library=None))]
#[allow(clippy::too_many_arguments)]
fn optimise(
    py: Python<'_>,
    program: &Bound<'_, PyAny>,
    part: Option<&Bound<'_, PyAny>>,
    stock: Option<String>,
    machine: Option<std::path::PathBuf>,
    material: Option<String>,
    tools: Option<String>,
    flutes: Option<usize>,
    vc: Option<f64>,
    resolution: Option<f64>,
    passes: Option<String>,
    limits: Option<&Bound<'_, PyDict>>,
    dialect: Option<String>,
    output: Option<std::path::PathBuf>,
    library: Option<&Bound<'_, PyAny>>,
) -> PyResult<(program::PyProgram, String, Py<PyAny>, bool)> {
    let (p, name) = job::program_arg(program)?;
    let req = job::Request {
        program: p,
        name: name.clone(),
        part: job::part_arg(part)?,
        stock,
        machine: machine.map(|m| m.display().to_string()),
        material,
        tool: tools,
        flutes,
        vc,
        resolution,
        passes,
        loads: self::loads(limits)?,
        dialect,
        output: output.map(|o| o.display().to_string()),
        library: tools::library_arg(library)?,
    };
    let done = py.detach(|| job::run(req))?;
    let summary = json_to_py(py, &done.summary_json)?;
    let prog = program::PyProgram::of(done.program);
    Ok((prog, done.text, summary, done.refused))
}

/// The usual file extension of a dialect's programs (`fanuc` → `nc`).
#[pyfunction]
fn dialect_extension(dialect: &str) -> PyResult<&'static str> {
    Ok(program::target(dialect)?.extension())
}

#[pymodule]
fn _millplan(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("MillplanError", m.py().get_type::<error::MillplanError>())?;
    m.add_class::<program::PyProgram>()?;
    m.add_class::<mesh::PyMesh>()?;
    m.add_class::<tools::PyToolLibrary>()?;
    m.add_function(wrap_pyfunction!(inspect, m)?)?;
    m.add_function(wrap_pyfunction!(read_program, m)?)?;
    m.add_function(wrap_pyfunction!(write_program, m)?)?;
    m.add_function(wrap_pyfunction!(read_stl, m)?)?;
    m.add_function(wrap_pyfunction!(wd::_working_diameter, m)?)?;
    m.add_function(wrap_pyfunction!(optimise, m)?)?;
    m.add_function(wrap_pyfunction!(dialect_extension, m)?)?;
    m.add_function(wrap_pyfunction!(speed::speed, m)?)?;
    m.add("SIDES", speed::SIDES.to_vec())?;
    m.add_function(wrap_pyfunction!(gouge::gouge, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(force::force, m)?)?;
    m.add_function(wrap_pyfunction!(cut::cut, m)?)?;
    m.add_function(wrap_pyfunction!(raster::raster, m)?)?;
    m.add_function(wrap_pyfunction!(reorder::reorder, m)?)?;
    m.add_function(wrap_pyfunction!(feed::feed, m)?)?;
    m.add_function(wrap_pyfunction!(setup::setup, m)?)?;
    m.add_function(wrap_pyfunction!(post::post, m)?)?;
    Ok(())
}
