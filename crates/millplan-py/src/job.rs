//! `optimise`: the job API of `millplan optimise` (millplan-driver), the
//! inputs given as objects or file names, run with the GIL released.

use crate::error::{guard, Located, Place, Res};
use crate::mesh::PyMesh;
use crate::program::PyProgram;
use millplan_driver::given::{Given, GivenError};
use millplan_driver::passes::{self, ORDER};
use millplan_driver::{Inputs, Job, OptionsRequest, Verdict};
use millplan_geom::TriMesh;
use millplan_models::force::materials::Materials;
use millplan_nc::Program;
use std::path::Path;

/// What `optimise` was given, before any file is read.
pub struct Request {
    pub program: Program,
    pub name: String,
    pub part: Option<TriMesh>,
    pub stock: Option<String>,
    pub machine: Option<String>,
    pub material: Option<String>,
    pub tool: Option<String>,
    pub flutes: Option<usize>,
    pub vc: Option<f64>,
    pub resolution: Option<f64>,
    pub passes: Option<String>,
    /// The load limits as `--limit NAME=VALUE` pairs.
    pub loads: Vec<(String, String)>,
    pub dialect: Option<String>,
    pub output: Option<String>,
    /// A tool library: each tool the program calls takes its geometry.
    pub library: Option<millplan_driver::tools::Library>,
}

impl Request {
    /// A request for `program` with every option at its default.
    pub fn new(program: Program, name: String) -> Request {
        Request {
            program,
            name,
            part: None,
            stock: None,
            machine: None,
            material: None,
            tool: None,
            flutes: None,
            vc: None,
            resolution: None,
            passes: None,
            loads: Vec::new(),
            dialect: None,
            output: None,
            library: None,
        }
    }
}

/// The written program, its text and the summary (as JSON).
pub struct Done {
    pub program: Program,
    pub text: String,
    pub summary_json: String,
    pub refused: bool,
}

fn err(place: &str, e: impl std::fmt::Display) -> Located {
    Located::new(Place::file(place), e.to_string())
}

/// The inputs of the job, checked as `millplan optimise` checks its
/// options (`Inputs::given`: the same ranges and messages).
pub fn inputs(r: &Request) -> Res<Inputs> {
    let given = Given {
        program: r.program.clone(),
        part: r.part.clone(),
        stock: r.stock.as_deref(),
        stl_units: None,
        limits: millplan_geom::limits::Limits::default(),
        machine: r
            .machine
            .as_deref()
            .map(|m| crate::program::machine(Some(m)))
            .transpose()?,
        materials: Materials::load(None).map_err(|e| err("material", e))?,
        material: r.material.clone(),
        library: r.library.as_ref(),
        options: OptionsRequest {
            vc: r.vc,
            spindle: None,
            tool: r.tool.clone(),
            flutes: r.flutes,
            resolution: r.resolution,
            loads: r.loads.clone(),
            tol: None,
            memory: None,
            g93: false,
        },
    };
    Inputs::given(given).map_err(|e| match e {
        GivenError::Option(m) => crate::error::option_error(&m),
        GivenError::Tool(e) => Located::new(Place::at(&r.name, e.line, 1), e.message),
        GivenError::Io(e) => Located::new(Place::default(), e.message),
    })
}

/// Runs the job as `millplan optimise` does: the passes, the written
/// program re-read and checked; written to `output` unless refused.
pub fn run(r: Request) -> Res<Done> {
    guard(&r.name.clone(), || {
        let order = match &r.passes {
            Some(s) => passes::parse_list(s).map_err(|e| err("passes", e))?,
            None => ORDER.to_vec(),
        };
        // Passes named by the caller are refused when an input is missing.
        let named = r.passes.is_some().then_some(&order[..]);
        let job = Job::for_passes(inputs(&r)?, named, &mut |_| {}).map_err(|e| err(&r.name, e))?;
        let machine = job.inputs.machine_given.then_some(&job.inputs.machine);
        let to = r
            .dialect
            .as_deref()
            .map(crate::program::target)
            .transpose()?;
        // Without an output file, no file name says a dialect.
        let out = r.output.as_deref().unwrap_or("");
        let target = millplan_driver::target::output_target(
            to,
            Path::new(out),
            machine,
            job.inputs.program.source,
        )
        .map_err(|e| err(&r.name, e.trim_start_matches(": ")))?;
        let outcome = job.run(&order).map_err(|e| err(&r.name, e))?;
        let w = job
            .finish(&outcome, job.inputs.machine.write_options(target))
            .map_err(|e| err(&r.name, e))?;
        let refused = w.summary.verdict == Verdict::Refused;
        if let (Some(o), false) = (&r.output, refused) {
            crate::error::write_bytes(o, &w.bytes)?;
        }
        Ok(Done {
            summary_json: serde_json::to_string(&w.summary).map_err(|e| err(&r.name, e))?,
            text: String::from_utf8_lossy(&w.bytes).into_owned(),
            program: w.program,
            refused,
        })
    })
}

/// A program argument: a `Program` or a file name.
pub fn program_arg(p: &pyo3::Bound<'_, pyo3::PyAny>) -> pyo3::PyResult<(Program, String)> {
    use pyo3::prelude::*;
    if let Ok(p) = p.cast::<PyProgram>() {
        let p = p.get();
        return Ok((
            (*p.program).clone(),
            p.path.clone().unwrap_or_else(|| "<program>".into()),
        ));
    }
    let path = p.extract::<std::path::PathBuf>()?.display().to_string();
    let r = crate::program::read(&path, None)?;
    Ok(((*r.program).clone(), path))
}

/// A part argument: a `Mesh`, a file name or None.
pub fn part_arg(p: Option<&pyo3::Bound<'_, pyo3::PyAny>>) -> pyo3::PyResult<Option<TriMesh>> {
    use pyo3::prelude::*;
    let Some(p) = p.filter(|p| !p.is_none()) else {
        return Ok(None);
    };
    if let Ok(m) = p.cast::<PyMesh>() {
        return Ok(Some((*m.get().mesh).clone()));
    }
    let path = p.extract::<std::path::PathBuf>()?.display().to_string();
    Ok(Some((*crate::mesh::read(&path, false)?.mesh).clone()))
}

/// A part that must be given: a `Mesh` or a file name.
pub fn mesh_arg(p: &pyo3::Bound<'_, pyo3::PyAny>) -> pyo3::PyResult<TriMesh> {
    part_arg(Some(p))?
        .ok_or_else(|| Located::new(Place::file("part"), "a Mesh or an STL file is needed").into())
}
