//! `setup`: can a five-axis machine reach the whole part in one setup, and
//! how should it be clamped (the driver's `setup` module, as `millplan
//! setup` searches), with the GIL released.

use crate::error::{guard, option_error, Located, Place, Res};
use crate::mesh::PyMesh;
use millplan_driver::command_defaults::setup as defaults;
use millplan_driver::setup::{self as lib, Kinematics, MachineType, SetupRequest};
use millplan_geom::TriMesh;
use millplan_plan::setup::{self as plan, GridKind};
use pyo3::prelude::*;

/// The sphere grid by name.
fn grid(name: Option<&str>) -> Res<GridKind> {
    match name.unwrap_or("latlon") {
        "latlon" => Ok(GridKind::LatLon),
        "icosphere" => Ok(GridKind::Icosphere),
        "healpix" => Ok(GridKind::Healpix),
        o => Err(Located::new(
            Place::file("grid"),
            format!("{o:?}: must be latlon, icosphere or healpix"),
        )),
    }
}

/// The machine: a machine file's kinematics, or a type with its ranges.
fn machine(file: Option<&str>, kind: Option<&str>, ranges: [&str; 2]) -> Res<Kinematics> {
    match (file, kind) {
        (Some(_), Some(_)) => Err(Located::new(
            Place::file("kind"),
            "give a machine file or a machine type, not both",
        )),
        (Some(f), None) => crate::program::machine(Some(f))?
            .kinematics()
            .cloned()
            .ok_or_else(|| {
                let m = "the machine file has no [kinematics] table: setup needs the rotary axes";
                Located::new(Place::file(f), m)
            }),
        (None, Some(k)) => {
            let t = match k {
                "ca" => MachineType::Ca,
                "ab" => MachineType::Ab,
                o => {
                    let m = format!("{o:?}: must be ca or ab");
                    return Err(Located::new(Place::file("kind"), m));
                }
            };
            lib::machine_of_type(t, ranges[0], ranges[1]).map_err(|e| option_error(&e))
        }
        (None, None) => Err(Located::new(
            Place::file("machine"),
            "give a machine file or a machine type (kind=\"ca\" or \"ab\")",
        )),
    }
}

/// The search as `millplan setup` runs it: the report (JSON) and the part
/// turned into the chosen setup.
fn run(
    req: &SetupRequest,
    name: &str,
    mut mesh: TriMesh,
    k: &Kinematics,
) -> Res<(String, TriMesh)> {
    guard(name, || {
        lib::check(req).map_err(|e| option_error(&e))?;
        let p = lib::params(req).map_err(|e| option_error(&e))?;
        let t0 = std::time::Instant::now();
        let found = plan::plan(&mut mesh, k, &p).map_err(|e| match e {
            plan::SetupError::NoTriangles => Located::new(Place::file(name), e.to_string()),
            e => Located::new(Place::default(), e.to_string()),
        })?;
        let secs = t0.elapsed().as_secs_f64();
        let s = found.summary(&mesh, k);
        let verdict = lib::verdict(req, &mesh, &found);
        let report = lib::Report::new(req, &s, k, (secs, verdict));
        let json = serde_json::to_string(&report)
            .map_err(|e| Located::new(Place::file(name), e.to_string()))?;
        let r = found.best.setup;
        mesh.map_vertices(|v| r * v);
        Ok((json, mesh))
    })
}

/// `millplan setup`: returns (report as `setup --json` prints it, the part
/// rotated into the setup found).
#[pyfunction]
#[pyo3(signature = (part, machine=None, kind=None, range1=None, range2=None, grid=None,
                    cells=None, tool=None, clearance=None, ignore_bottom=false, exact=false))]
#[allow(clippy::too_many_arguments)]
pub fn setup(
    py: Python<'_>,
    part: &Bound<'_, PyAny>,
    machine: Option<std::path::PathBuf>,
    kind: Option<&str>,
    range1: Option<&str>,
    range2: Option<&str>,
    grid: Option<&str>,
    cells: Option<usize>,
    tool: Option<String>,
    clearance: Option<f64>,
    ignore_bottom: bool,
    exact: bool,
) -> PyResult<(Py<PyAny>, PyMesh)> {
    let file = machine.map(|m| m.display().to_string());
    let ranges = [range1.unwrap_or("free"), range2.unwrap_or("free")];
    let k = self::machine(file.as_deref(), kind, ranges)?;
    let req = SetupRequest {
        grid: self::grid(grid)?,
        cells: cells.unwrap_or(defaults::CELLS),
        tool,
        clearance: clearance.unwrap_or(defaults::CLEARANCE_DEG),
        ignore_bottom,
        exact,
    };
    let name = match part.cast::<PyMesh>() {
        Ok(m) => m.get().path.clone().unwrap_or_else(|| "<mesh>".into()),
        Err(_) => part.extract::<std::path::PathBuf>()?.display().to_string(),
    };
    let mesh = crate::job::mesh_arg(part)?;
    let (json, rotated) = py.detach(|| run(&req, &name, mesh, &k))?;
    let report = crate::json_to_py(py, &json)?;
    Ok((report, PyMesh::new(rotated, None)))
}
