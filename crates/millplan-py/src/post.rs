//! `post`: a five-axis CL program posted through a machine's kinematics,
//! written, read back and checked as `millplan post` does it (the driver's
//! `post` module), with the GIL released.

use crate::error::{guard, option_error, write_bytes, Located, Place, Res};
use millplan_driver::command_defaults::post as defaults;
use millplan_driver::post::{self as lib, PostRequest, PostSummary};
use millplan_nc::write::{Target, WriteOptions};
use millplan_nc::Program;
use millplan_plan::machine::Machine;
use millplan_plan::post::{for_target, post as post_cl, Posted};
use pyo3::prelude::*;
use std::path::Path;

/// What one run is given besides the options.
struct Given<'a> {
    name: &'a str,
    cl: &'a Program,
    machine: &'a Machine,
    machine_path: &'a str,
    dialect: Option<&'a str>,
    output: Option<&'a str>,
    force: bool,
}

/// A post error located in the CL program.
fn post_error(name: &str, e: &millplan_plan::post::PostError) -> Located {
    crate::error::located_in(name, &lib::error(name, e).1)
}

/// Refuses the run when a check of the posted program failed (unless
/// `force`), at the first refusing finding's line of the CL program.
fn enforce(name: &str, checks: &[millplan_driver::Check], force: bool) -> Res<()> {
    if force || millplan_plan::safety::passed(checks) {
        return Ok(());
    }
    let Some((c, f)) = millplan_plan::safety::first_refusal(checks) else {
        return Err(Located::new(
            Place::file(name),
            "a check failed; nothing written",
        ));
    };
    let place = match f.line {
        Some(l) => Place::at(name, l, 1),
        None => Place::file(name),
    };
    let m = format!(
        "check {}: {}; nothing written (force=True writes it)",
        c.name, f.message
    );
    Err(Located::new(place, m))
}

/// The post as `millplan post` runs it: the program posted and written for
/// its dialect, read back, checked; written to `output` unless refused.
/// Returns the posted program, its text and the summary (JSON).
fn run(r: &PostRequest, g: &Given) -> Res<(Program, String, String)> {
    guard(g.name, || {
        let o = lib::options(r, g.machine).map_err(|e| option_error(&e))?;
        let to = g.dialect.map(crate::program::target).transpose()?;
        let out = g.output.unwrap_or("");
        let target: Target = lib::target(to, Path::new(out), g.machine, Path::new(g.machine_path))
            .map_err(|e| match e.strip_prefix(&format!("{}: ", g.machine_path)) {
                Some(rest) => Located::new(Place::file(g.machine_path), rest),
                None => crate::error::dialect_error(out, &e),
            })?;
        let Posted {
            mut program,
            report,
            ..
        } = post_cl(g.cl, g.machine, &o).map_err(|e| post_error(g.name, &e))?;
        for_target(&mut program, target).map_err(|e| post_error(g.name, &e))?;
        let mut wo = WriteOptions {
            limits: millplan_geom::limits::Limits::default(),
            ..g.machine.write_options(target)
        };
        // The post states TCP itself, per operation, when asked for it.
        wo.auto_tcp = false;
        let (bytes, _) = millplan_nc::write::write_program(&program, wo)
            .map_err(|e| Located::new(Place::at(g.name, e.line, 1), e.message))?;
        lib::read_back_check(&program, &bytes, &wo, r.tol, (out, g.name))
            .map_err(|e| crate::error::located(&e))?;
        let checks = lib::check_posted(g.cl, &program, g.machine, o.tol);
        enforce(g.name, &checks, g.force)?;
        if let Some(o) = g.output {
            write_bytes(o, &bytes)?;
        }
        let names = (Path::new(g.name), Path::new(out));
        let s = PostSummary::new(names, &o, g.machine, target, &report, &checks);
        let json = serde_json::to_string(&s)
            .map_err(|e| Located::new(Place::file(g.name), e.to_string()))?;
        Ok((program, String::from_utf8_lossy(&bytes).into_owned(), json))
    })
}

/// `millplan post`: returns (posted program, text written, summary).
#[pyfunction]
#[pyo3(signature = (program, machine, output=None, dialect=None, tcp=false, g93=false, tol=None,
                    pole_cone=None, pole_tol=None, clearance=None, force=false))]
#[allow(clippy::too_many_arguments)]
pub fn post(
    py: Python<'_>,
    program: &Bound<'_, PyAny>,
    machine: std::path::PathBuf,
    output: Option<std::path::PathBuf>,
    dialect: Option<String>,
    tcp: bool,
    g93: bool,
    tol: Option<f64>,
    pole_cone: Option<f64>,
    pole_tol: Option<f64>,
    clearance: Option<f64>,
    force: bool,
) -> PyResult<(crate::program::PyProgram, String, Py<PyAny>)> {
    let r = PostRequest {
        tol: tol.unwrap_or(defaults::TOL),
        tcp,
        g93,
        pole_cone,
        pole_tol,
        clearance,
    };
    let (cl, name) = crate::job::program_arg(program)?;
    let machine_path = machine.display().to_string();
    let m = crate::program::machine(Some(&machine_path))?;
    let output = output.map(|o| o.display().to_string());
    let g = Given {
        name: &name,
        cl: &cl,
        machine: &m,
        machine_path: &machine_path,
        dialect: dialect.as_deref(),
        output: output.as_deref(),
        force,
    };
    let (p, text, json) = py.detach(|| run(&r, &g))?;
    let summary = crate::json_to_py(py, &json)?;
    Ok((crate::program::PyProgram::of(p), text, summary))
}
