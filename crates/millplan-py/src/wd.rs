//! The working diameter over arrays: the library's model per element, in
//! parallel with the GIL released. Broadcasting is NumPy's (the Python
//! wrapper hands over flat arrays of one length).

use crate::error::{Located, Place, Res};
use millplan_models::wd::{working_diameter, Case, Side};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use rayon::prelude::*;

/// Elements per parallel task: a few microseconds of work each.
const CHUNK: usize = 4096;

/// The inputs of one element.
struct Columns<'a> {
    d: &'a [f64],
    ap: &'a [f64],
    ae: Option<&'a [f64]>,
    alpha: &'a [f64],
    af: &'a [f64],
    right: &'a [bool],
    both: bool,
}

impl Columns<'_> {
    fn case(&self, i: usize) -> Res<Case> {
        let side = if self.right[i] {
            Side::Right
        } else {
            Side::Left
        };
        let ae = self.ae.map(|a| a[i]);
        Case::from_degrees(
            self.d[i],
            self.ap[i],
            ae,
            self.both,
            self.alpha[i],
            self.af[i],
            side,
        )
        .map_err(|e| Located::new(Place::file("working_diameter"), format!("element {i}: {e}")))
    }

    fn fill(&self, out: &mut [f64]) -> Res<()> {
        out.par_chunks_mut(CHUNK)
            .enumerate()
            .try_for_each(|(c, chunk)| {
                for (k, o) in chunk.iter_mut().enumerate() {
                    *o = working_diameter(&self.case(c * CHUNK + k)?);
                }
                Ok(())
            })
    }
}

fn slice<'a, T: numpy::Element>(a: &'a PyReadonlyArray1<'_, T>, what: &str) -> Res<&'a [T]> {
    a.as_slice()
        .map_err(|_| Located::new(Place::file(what), "must be a contiguous array"))
}

/// Working diameters of flat, equally long arrays (mm; angles in degrees;
/// `ae` None: no machined neighbour; `right`: the uncut side is right).
#[pyfunction]
#[pyo3(signature = (d, ap, ae, alpha, af, right, both=false))]
#[allow(clippy::too_many_arguments)]
pub fn _working_diameter<'py>(
    py: Python<'py>,
    d: PyReadonlyArray1<'py, f64>,
    ap: PyReadonlyArray1<'py, f64>,
    ae: Option<PyReadonlyArray1<'py, f64>>,
    alpha: PyReadonlyArray1<'py, f64>,
    af: PyReadonlyArray1<'py, f64>,
    right: PyReadonlyArray1<'py, bool>,
    both: bool,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let cols = Columns {
        d: slice(&d, "d")?,
        ap: slice(&ap, "ap")?,
        ae: ae.as_ref().map(|a| slice(a, "ae")).transpose()?,
        alpha: slice(&alpha, "alpha")?,
        af: slice(&af, "af")?,
        right: slice(&right, "side")?,
        both,
    };
    let n = cols.d.len();
    let lens = [
        cols.ap.len(),
        cols.alpha.len(),
        cols.af.len(),
        cols.right.len(),
    ];
    if lens
        .iter()
        .chain(cols.ae.map(<[f64]>::len).iter())
        .any(|&l| l != n)
    {
        return Err(Located::new(
            Place::file("working_diameter"),
            "arrays of different lengths",
        )
        .into());
    }
    let mut out = vec![0.0; n];
    py.detach(|| crate::error::guard("working_diameter", || cols.fill(&mut out)))?;
    Ok(out.into_pyarray(py))
}
