//! `speed`: the constant-cutting-speed pass of `millplan speed` (the
//! driver's `speed` module), its per-point rows as NumPy columns and its
//! report as `speed --json` gives it, run with the GIL released.

use crate::error::{guard, Located, Place, Res};
use millplan_driver::speed::{self as lib, Convention, Cutting, NormalMode, SpeedRequest, Surface};
use millplan_geom::TriMesh;
use millplan_nc::Program;
use millplan_plan::machine::Machine;
use millplan_plan::pipeline::Context;
use millplan_plan::speed::{side_name, PointRow};
use numpy::ndarray::Array1;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The uncut side's names, indexed by the `uncut_side` codes.
pub const SIDES: [&str; 4] = ["none", "both", "left", "right"];

/// The options of `speed` as strings and numbers from Python.
pub struct Options<'a> {
    pub cut: Cutting,
    pub ball_d: Option<f64>,
    pub s_threshold: Option<f64>,
    pub keep_feed: bool,
    pub convention: Option<&'a str>,
    pub normals: Option<&'a str>,
}

fn place(what: &str, e: impl Into<String>) -> Located {
    Located::new(Place::file(what), e)
}

/// The request of `millplan speed`, checked as the command checks it.
pub fn request(o: &Options) -> Res<SpeedRequest> {
    let convention = match o.convention {
        None | Some("auto") => None,
        Some("tip") => Some(Convention::Tip),
        Some("centre") => Some(Convention::Centre),
        Some(x) => return Err(place("convention", format!("{x:?}: auto, tip or centre"))),
    };
    let normals = match o.normals {
        None | Some("smooth") => NormalMode::Smooth,
        Some("facet") => NormalMode::Facet,
        Some("ball") => NormalMode::Ball,
        Some(x) => return Err(place("normals", format!("{x:?}: smooth, facet or ball"))),
    };
    let req = SpeedRequest {
        cut: o.cut,
        ball_d: o.ball_d,
        s_threshold: o
            .s_threshold
            .unwrap_or(millplan_driver::command_defaults::speed::S_THRESHOLD),
        keep_feed: o.keep_feed,
        convention,
        normals,
        nearest_incentre: false,
        keep_rows: true,
    };
    lib::check(&req).map_err(|e| crate::error::option_error(&e))?;
    Ok(req)
}

/// What a run gives back: the new program, the rows and the report (JSON).
pub struct Ran {
    pub program: Program,
    pub rows: Vec<PointRow>,
    pub report_json: String,
}

/// `millplan speed`'s run (the driver's `speed::command`: the pass, its
/// checks, the part's findings) on `input` over `mesh`, with the times
/// before and after.
pub fn run(req: &SpeedRequest, input: &Program, mesh: &TriMesh, machine: Machine) -> Res<Ran> {
    guard("speed", || {
        let time_before = lib::cycle_time(input, &machine);
        let mut cx = Context::new(machine).with_surface(Surface::new(mesh));
        let out = lib::command(req, &mut cx, mesh, input.clone()).map_err(|e| match e {
            lib::SpeedError::Pass(e) => place("speed", e.to_string()),
            lib::SpeedError::NoSummary => place("speed", "the pass left no summary"),
        })?;
        let time_after = lib::cycle_time(&out.program, &cx.machine);
        let target = millplan_driver::target::output_target(
            None,
            std::path::Path::new(""),
            None,
            input.source,
        )
        .map_err(|e| place("speed", e))?;
        let times = [time_before, time_after];
        let report = out.report((String::new(), target), &cx.machine, times);
        let report_json =
            serde_json::to_string(&report).map_err(|e| place("speed", e.to_string()))?;
        Ok(Ran {
            program: out.program,
            rows: out.rows,
            report_json,
        })
    })
}

/// One column of the rows.
fn col<T: Copy>(rows: &[PointRow], f: impl Fn(&PointRow) -> T) -> Array1<T> {
    rows.iter().map(f).collect()
}

/// The rows as NumPy columns, named as the command's `--table` CSV names them.
pub fn columns<'py>(py: Python<'py>, rows: &[PointRow]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let f64s: [crate::Column<PointRow, f64>; 18] = [
        ("x", |r| r.cl.x),
        ("y", |r| r.cl.y),
        ("z", |r| r.cl.z),
        ("cx", |r| r.r.contact.x),
        ("cy", |r| r.r.contact.y),
        ("cz", |r| r.r.contact.z),
        ("nx", |r| r.r.normal.x),
        ("ny", |r| r.r.normal.y),
        ("nz", |r| r.r.normal.z),
        ("inclination_deg", |r| r.r.inclination.to_degrees()),
        ("feed_angle_deg", |r| r.r.feed_angle.to_degrees()),
        ("ae", |r| r.r.ae().unwrap_or(f64::NAN)),
        ("d_w", |r| r.r.dw),
        ("n", |r| r.n),
        ("feed", |r| r.feed),
        ("n_target", |r| r.n_target),
        ("gap", |r| {
            if r.r.gap.is_finite() {
                r.r.gap
            } else {
                f64::NAN
            }
        }),
        ("d", |r| r.d),
    ];
    d.set_item("line", col(rows, |r| r.line).into_pyarray(py))?;
    d.set_item("operation", col(rows, |r| r.op as u32).into_pyarray(py))?;
    d.set_item("move", col(rows, |r| r.mv as u64).into_pyarray(py))?;
    for (name, f) in f64s {
        d.set_item(name, col(rows, f).into_pyarray(py))?;
    }
    let side = |r: &PointRow| {
        SIDES
            .iter()
            .position(|s| *s == side_name(&r.r))
            .unwrap_or(0) as u8
    };
    d.set_item("uncut_side", col(rows, side).into_pyarray(py))?;
    let bools: [crate::Column<PointRow, bool>; 5] = [
        ("clamped", |r| r.clamped),
        ("rate_limited", |r| r.rate_limited),
        ("held", |r| r.held),
        ("gap_flag", |r| r.gap_flag),
        ("corner", |r| r.r.corner),
    ];
    for (name, f) in bools {
        d.set_item(name, col(rows, f).into_pyarray(py))?;
    }
    Ok(d)
}

/// `millplan speed` on a program and a part; returns (program, columns,
/// report JSON).
#[pyfunction]
#[pyo3(signature = (program, part, vc, fz, ap, flutes=None, machine=None, ball_d=None,
                    keep_feed=false, s_threshold=None, convention=None, normals=None))]
#[allow(clippy::too_many_arguments)]
pub fn speed<'py>(
    py: Python<'py>,
    program: &Bound<'py, PyAny>,
    part: &Bound<'py, PyAny>,
    vc: f64,
    fz: f64,
    ap: f64,
    flutes: Option<u32>,
    machine: Option<std::path::PathBuf>,
    ball_d: Option<f64>,
    keep_feed: bool,
    s_threshold: Option<f64>,
    convention: Option<&str>,
    normals: Option<&str>,
) -> PyResult<(crate::program::PyProgram, Bound<'py, PyDict>, Py<PyAny>)> {
    let req = request(&Options {
        cut: Cutting {
            vc,
            fz,
            flutes: flutes.unwrap_or(millplan_driver::command_defaults::cutting::FLUTES),
            ap,
        },
        ball_d,
        s_threshold,
        keep_feed,
        convention,
        normals,
    })?;
    let (input, _) = crate::job::program_arg(program)?;
    let mesh = crate::job::mesh_arg(part)?;
    let m = crate::program::machine(machine.map(|m| m.display().to_string()).as_deref())?;
    let ran = py.detach(|| run(&req, &input, &mesh, m))?;
    let cols = columns(py, &ran.rows)?;
    let report = crate::json_to_py(py, &ran.report_json)?;
    Ok((crate::program::PyProgram::of(ran.program), cols, report))
}
