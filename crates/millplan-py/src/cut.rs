//! `cut`: one engagement's forces, torque, power and tool bending (the
//! driver's `cut` module, as `millplan cut` evaluates it), the figures as
//! `cut --json` prints them and the curves over a revolution as NumPy
//! columns.

use crate::error::{guard, option_error, Located, Place};
use millplan_driver::command_defaults::cut as defaults;
use millplan_driver::cut::{self as lib, CutRequest, Variant};
use millplan_driver::Materials;
use numpy::ndarray::Array1;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

fn variant(v: Option<&str>) -> PyResult<Variant> {
    match v {
        None => Ok(Variant::default()),
        Some(s) => serde_json::from_value(serde_json::Value::String(s.to_string())).map_err(|_| {
            let m = format!("{s:?}: tilt-then-lead or lead-then-tilt");
            Located::new(Place::file("variant"), m).into()
        }),
    }
}

/// The curves over one revolution: angle, forces in the tool and the
/// workpiece frame, torque.
fn curves<'py>(py: Python<'py>, r: &lib::CutOutcome) -> PyResult<Bound<'py, PyDict>> {
    let rev = r.result.evaluation.revolution();
    let d = PyDict::new(py);
    let cols: [crate::Column<millplan_models::force::Sample, f64>; 8] = [
        ("phi_deg", |p| p.phi.to_degrees()),
        ("fx", |p| p.tool[0]),
        ("fy", |p| p.tool[1]),
        ("fz", |p| p.tool[2]),
        ("fx_w", |p| p.work[0]),
        ("fy_w", |p| p.work[1]),
        ("fz_w", |p| p.work[2]),
        ("torque", |p| p.torque),
    ];
    for (name, f) in cols {
        let a: Array1<f64> = rev.iter().map(f).collect();
        d.set_item(name, a.into_pyarray(py))?;
    }
    Ok(d)
}

/// `millplan cut`: returns (the figures of `cut --json`, the curves).
#[pyfunction]
#[pyo3(signature = (tool, fz, ap, n, ae=None, material=None, coeffs=None, flutes=None,
                    helix=None, lead=None, tilt=None, variant=None, stickout=None,
                    flute_length=None, modulus=None, dz=None, dphi=None, fixed_grid=false))]
#[allow(clippy::too_many_arguments)]
pub fn cut<'py>(
    py: Python<'py>,
    tool: String,
    fz: f64,
    ap: f64,
    n: f64,
    ae: Option<f64>,
    material: Option<String>,
    coeffs: Option<String>,
    flutes: Option<usize>,
    helix: Option<f64>,
    lead: Option<f64>,
    tilt: Option<f64>,
    variant: Option<&str>,
    stickout: Option<f64>,
    flute_length: Option<f64>,
    modulus: Option<f64>,
    dz: Option<f64>,
    dphi: Option<f64>,
    fixed_grid: bool,
) -> PyResult<(Py<PyAny>, Bound<'py, PyDict>)> {
    let req = CutRequest {
        tool,
        flutes: flutes.unwrap_or(defaults::FLUTES),
        helix: helix.unwrap_or(defaults::HELIX_DEG),
        fz,
        ap,
        ae,
        slot: ae.is_none(),
        lead: lead.unwrap_or(defaults::LEAD_DEG),
        tilt: tilt.unwrap_or(defaults::TILT_DEG),
        variant: self::variant(variant)?,
        stickout,
        flute_length,
        modulus: modulus.unwrap_or(defaults::MODULUS),
        material,
        coeffs,
        n,
        dz: dz.unwrap_or(defaults::DZ),
        dphi: dphi.unwrap_or(defaults::DPHI_DEG),
        fixed_grid,
    };
    let (json, out) = py.detach(|| {
        guard("cut", || {
            let materials = Materials::load(None).map_err(|e| option_error(&e))?;
            let out = lib::run(&req, &materials).map_err(|e| option_error(&e))?;
            let json = serde_json::to_string(&out.json())
                .map_err(|e| Located::new(Place::file("cut"), e.to_string()))?;
            Ok((json, out))
        })
    })?;
    Ok((crate::json_to_py(py, &json)?, curves(py, &out)?))
}
