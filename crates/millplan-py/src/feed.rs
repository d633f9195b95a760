//! `feed`: a feed per block from the cutting forces, as `millplan feed`
//! schedules it (the driver's `feed` module: the model, the stock, the
//! feed pass, the written program's loads, the summary), with the GIL
//! released.

use crate::error::{guard, option_error, write_bytes, Located, Place, Res};
use millplan_driver::command_defaults::feed as defaults;
use millplan_driver::feed::{self as lib, FeedRequest, ModelRequest, Prepared, ScheduleError};
use millplan_driver::StockSpec;
use millplan_geom::TriMesh;
use millplan_nc::write::Target;
use millplan_nc::Program;
use millplan_plan::force::ForceRun;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::Path;

/// What one run is given besides the options.
pub struct Given {
    pub name: String,
    pub program: Program,
    pub part: Option<TriMesh>,
    pub machine: Option<String>,
    pub dialect: Option<String>,
    pub output: Option<String>,
    /// `--limit NAME=VALUE` pairs.
    pub loads: Vec<(String, String)>,
}

/// What a run gives back.
struct Ran {
    program: Program,
    text: String,
    before: ForceRun,
    summary_json: String,
}

/// The program's strokes and stock with the model, as `millplan feed`
/// prepares them.
fn prepare(m: &ModelRequest, g: &Given) -> Res<Prepared> {
    let materials = millplan_driver::cut::materials(None).map_err(|e| option_error(&e))?;
    let setup = lib::force_setup(m, &materials).map_err(|e| option_error(&e))?;
    let spec = lib::stock_spec(m).map_err(|e| option_error(&e))?;
    let machine = crate::program::machine(g.machine.as_deref())?;
    let mut program = g.program.clone();
    lib::supply_spindle(m, &mut program).map_err(|e| option_error(&e))?;
    let s = lib::input_strokes(m, &g.name, &program, machine.rapid)
        .map_err(|e| crate::error::located_in(&g.name, &e))?;
    let blank = match &spec {
        StockSpec::Stl(p) => Some(crate::mesh::read(&p.display().to_string(), false)?.mesh),
        _ => None,
    };
    let memory = millplan_geom::limits::Limits::default().memory;
    let parts = (g.part.as_ref(), blank.as_deref());
    let stock = millplan_driver::simulate::build_stock(
        &g.name,
        m.resolution,
        &spec,
        &s,
        parts,
        (memory, 2),
    )
    .map_err(|e| crate::error::located_in("stock", &e))?;
    Prepared::new(m, &materials, (program, s, stock), setup, machine).map_err(|e| option_error(&e))
}

/// The output's dialect: `dialect`, else the machine file's control, else
/// the output's extension, else the input's.
fn target(g: &Given, p: &Prepared) -> Res<Target> {
    let to = g
        .dialect
        .as_deref()
        .map(crate::program::target)
        .transpose()?;
    let out = g.output.as_deref().unwrap_or("");
    let machine = g.machine.is_some().then_some(&p.machine);
    millplan_driver::target::output_target(to, Path::new(out), machine, p.program.source)
        .map_err(|e| crate::error::dialect_error(out, &e))
}

/// The run of `millplan feed`: prepared, scheduled, the written program's
/// loads and checks, written to `output` when given and no check refuses it.
fn run(m: &ModelRequest, f: &FeedRequest, g: &Given) -> Res<Ran> {
    guard(&g.name, || {
        let p = prepare(m, g)?;
        let params = lib::feed_params(f, m, &p, &g.loads).map_err(|e| option_error(&e))?;
        let target = target(g, &p)?;
        let s = lib::schedule(&p, params, m, &|_, _, _| {}).map_err(|e| match e {
            ScheduleError::Pass(e) => Located::new(Place::file(&g.name), e.to_string()),
            ScheduleError::Missing => {
                Located::new(Place::file(&g.name), "the feed pass left no result")
            }
        })?;
        lib::stopped_spindle(&g.name, &s.before).map_err(|e| crate::error::located(&e))?;
        let s2 =
            lib::program_strokes(m, &s.program, p.machine.rapid).map_err(|e| option_error(&e))?;
        let after = lib::forces_after(&p, &s, &s2, &|_| {})
            .map_err(|e| crate::error::located_in(&g.name, &e))?;
        let wo = millplan_nc::write::WriteOptions {
            limits: millplan_geom::limits::Limits::default(),
            ..p.machine.write_options(target)
        };
        let (bytes, _) = millplan_nc::write::write_program(&s.program, wo)
            .map_err(|e| Located::new(Place::at(&g.name, e.line, 1), e.message))?;
        // The command's checks; a refused program is not written (the
        // summary's `checks` and red verdict say why).
        let checks = lib::checks(&p, &s.program, m).map_err(|e| option_error(&e))?;
        if let (Some(o), true) = (&g.output, millplan_plan::safety::passed(&checks)) {
            write_bytes(o, &bytes)?;
        }
        let output = g.output.clone().unwrap_or_default();
        let summary = lib::FeedSummary::new(&p, &s, (&after, checks), &output, target.name());
        let summary_json = serde_json::to_string(&summary)
            .map_err(|e| Located::new(Place::file(&g.name), e.to_string()))?;
        Ok(Ran {
            text: String::from_utf8_lossy(&bytes).into_owned(),
            program: s.program,
            before: s.before,
            summary_json,
        })
    })
}

/// The model's options, the defaults of `millplan feed` where none is given:
/// (stock, material, tool), flutes, [helix, modulus, resolution, dz, dphi],
/// (stickout, flute length, spindle), fixed grid (the steps as given, not
/// refined until the peaks converge).
fn model(
    (stock, material, tool): (String, String, Option<String>),
    flutes: Option<usize>,
    [helix, modulus, resolution, dz, dphi]: [Option<f64>; 5],
    (stickout, flute_length, spindle): (Option<f64>, Option<f64>, Option<f64>),
    fixed_grid: bool,
) -> ModelRequest {
    ModelRequest {
        stock: Some(stock),
        material: Some(material),
        tool,
        flutes: flutes.unwrap_or(defaults::FLUTES),
        helix: helix.unwrap_or(defaults::HELIX_DEG),
        stickout,
        flute_length,
        modulus: modulus.unwrap_or(defaults::MODULUS),
        resolution: resolution.unwrap_or(defaults::RESOLUTION),
        dz: dz.unwrap_or(defaults::DZ),
        dphi: dphi.unwrap_or(defaults::DPHI_DEG),
        fixed_grid,
        spindle,
    }
}

/// `millplan feed`: returns (program, text written, summary, loads per move
/// of the input with the feeds allowed).
#[pyfunction]
#[pyo3(signature = (program, stock, material, part=None, machine=None, tools=None, flutes=None,
                    helix=None, stickout=None, flute_length=None, modulus=None, resolution=None,
                    dz=None, dphi=None, fixed_grid=false, spindle=None, fz_min=None, fz_max=None,
                    fos=None, feed_accel=None, limits=None, dialect=None, output=None))]
#[allow(clippy::too_many_arguments)]
pub fn feed<'py>(
    py: Python<'py>,
    program: &Bound<'py, PyAny>,
    stock: String,
    material: String,
    part: Option<&Bound<'py, PyAny>>,
    machine: Option<std::path::PathBuf>,
    tools: Option<String>,
    flutes: Option<usize>,
    helix: Option<f64>,
    stickout: Option<f64>,
    flute_length: Option<f64>,
    modulus: Option<f64>,
    resolution: Option<f64>,
    dz: Option<f64>,
    dphi: Option<f64>,
    fixed_grid: bool,
    spindle: Option<f64>,
    fz_min: Option<f64>,
    fz_max: Option<f64>,
    fos: Option<f64>,
    feed_accel: Option<f64>,
    limits: Option<&Bound<'py, PyDict>>,
    dialect: Option<String>,
    output: Option<std::path::PathBuf>,
) -> PyResult<(
    crate::program::PyProgram,
    String,
    Py<PyAny>,
    Bound<'py, PyDict>,
)> {
    let m = model(
        (stock, material, tools),
        flutes,
        [helix, modulus, resolution, dz, dphi],
        (stickout, flute_length, spindle),
        fixed_grid,
    );
    let f = FeedRequest {
        fz_min: fz_min.unwrap_or(defaults::FZ_MIN),
        fz_max,
        fos: fos.unwrap_or(defaults::FOS),
        feed_accel,
    };
    let (p, name) = crate::job::program_arg(program)?;
    let g = Given {
        name,
        program: p,
        part: crate::job::part_arg(part)?,
        machine: machine.map(|m| m.display().to_string()),
        dialect,
        output: output.map(|o| o.display().to_string()),
        loads: crate::loads(limits)?,
    };
    let ran = py.detach(|| run(&m, &f, &g))?;
    let summary = crate::json_to_py(py, &ran.summary_json)?;
    let moves = crate::force::columns(py, &ran.before.moves)?;
    let prog = crate::program::PyProgram::of(ran.program);
    Ok((prog, ran.text, summary, moves))
}
