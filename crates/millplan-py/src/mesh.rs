//! Parts: an STL's triangles as arrays, closest points and drop-cutter over
//! many points at once, with the GIL released.

use crate::error::{guard, read_bytes, Located, Place, Res};
use millplan_geom::bvh::Bvh;
use millplan_geom::stl::{read_stl_limited, StlLocation, StlReport};
use millplan_geom::{DVec2, DVec3, Limits, TriMesh};
use millplan_models::cutter::Shape;
use millplan_sim::dropcutter::DropMesh;
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use std::sync::{Arc, OnceLock};

/// Parses STL bytes, errors at their line and column (ASCII) or byte (binary).
pub fn parse_stl(path: &str, bytes: &[u8]) -> Res<(TriMesh, StlReport)> {
    read_stl_limited(bytes, &Limits::default()).map_err(|e| {
        let place = match e.location {
            StlLocation::Text { line, col } => Place::at(path, line, col),
            StlLocation::Byte(_) => Place::file(path),
        };
        let msg = match e.location {
            StlLocation::Byte(b) => format!("byte {b}: {}", e.message),
            StlLocation::Text { .. } => e.message,
        };
        Located::new(place, msg)
    })
}

/// A triangle mesh (a part), in mm.
#[pyclass(module = "millplan", name = "Mesh", frozen)]
pub struct PyMesh {
    pub mesh: Arc<TriMesh>,
    pub path: Option<String>,
    bvh: OnceLock<Bvh>,
    drop: OnceLock<DropMesh>,
}

impl PyMesh {
    pub fn new(mesh: TriMesh, path: Option<String>) -> PyMesh {
        PyMesh {
            mesh: Arc::new(mesh),
            path,
            bvh: OnceLock::new(),
            drop: OnceLock::new(),
        }
    }

    fn name(&self) -> &str {
        self.path.as_deref().unwrap_or("<mesh>")
    }
}

/// Reads an STL file (binary or ASCII); `units="inch"` scales it to mm.
pub fn read(path: &str, inch: bool) -> Res<PyMesh> {
    let bytes = read_bytes(path)?;
    let (mut mesh, _) = parse_stl(path, &bytes)?;
    if inch {
        mesh.map_vertices(|v| v * 25.4);
    }
    Ok(PyMesh::new(mesh, Some(path.to_string())))
}

/// Any array-like of numbers as a float64 2-D array (NumPy converts it).
fn as_f64_2d<'py>(x: &Bound<'py, PyAny>) -> PyResult<PyReadonlyArray2<'py, f64>> {
    if let Ok(a) = x.extract::<PyReadonlyArray2<'py, f64>>() {
        return Ok(a);
    }
    let np = x.py().import("numpy")?;
    let a = np.call_method1("asarray", (x, "float64"))?;
    a.extract::<PyReadonlyArray2<'py, f64>>()
        .map_err(|_| Located::new(Place::file("points"), "must be a 2-D array of numbers").into())
}

/// Rows of an (n, k) array as points, or an error naming the argument.
fn rows<const K: usize>(a: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; K]>> {
    let a = as_f64_2d(a)?;
    let v = a.as_array();
    if v.ncols() != K {
        return Err(Located::new(
            Place::file(what),
            format!("must have shape (n, {K}), not {:?}", v.shape()),
        )
        .into());
    }
    Ok(v.rows()
        .into_iter()
        .map(|r| std::array::from_fn(|i| r[i]))
        .collect())
}

#[pymethods]
impl PyMesh {
    /// Vertex positions, mm, shape (n, 3) (welded: shared corners once).
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let v = &self.mesh.vertices;
        Array2::from_shape_fn((v.len(), 3), |(i, k)| v[i][k]).into_pyarray(py)
    }

    /// Triangles as vertex indices, shape (m, 3), counter-clockwise seen
    /// from outside.
    #[getter]
    fn faces<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<u32>> {
        let t = &self.mesh.triangles;
        Array2::from_shape_fn((t.len(), 3), |(i, k)| t[i][k]).into_pyarray(py)
    }

    /// The closest point of the surface to each of `points` (shape (n, 3),
    /// mm), searched within `max_distance`. Returns `(closest, distance,
    /// triangle)`: shape (n, 3), (n,), (n,); where nothing lies within
    /// `max_distance`, NaN, inf and -1. Runs in parallel with the GIL
    /// released; the search tree is built on the first call.
    #[pyo3(signature = (points, max_distance=f64::INFINITY))]
    #[allow(clippy::type_complexity)]
    fn closest_points<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
        max_distance: f64,
    ) -> PyResult<(
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<i64>>,
    )> {
        if !(max_distance > 0.0) {
            return Err(Located::new(Place::file("max_distance"), "must be positive").into());
        }
        let pts: Vec<DVec3> = rows::<3>(points, "points")?
            .into_iter()
            .map(DVec3::from_array)
            .collect();
        let (p, d, t) = py.detach(|| {
            guard(self.name(), || {
                let bvh = self.bvh.get_or_init(|| Bvh::build(&self.mesh));
                let hits = bvh.closest_many(&self.mesh, &pts, max_distance);
                let mut p = Array2::from_elem((hits.len(), 3), f64::NAN);
                let mut d = Array1::from_elem(hits.len(), f64::INFINITY);
                let mut t = Array1::from_elem(hits.len(), -1i64);
                for (i, h) in hits.iter().enumerate() {
                    if let Some(h) = h {
                        for k in 0..3 {
                            p[[i, k]] = h.point[k];
                        }
                        d[i] = h.distance;
                        t[i] = i64::from(h.triangle);
                    }
                }
                Ok((p, d, t))
            })
        })?;
        Ok((p.into_pyarray(py), d.into_pyarray(py), t.into_pyarray(py)))
    }

    /// Drops `cutter` (`ball:D`, `flat:D`, `bull:D:R`, mm) onto the surface
    /// along -z at each of `xy` (shape (n, 2)): the tool-tip height where it
    /// first touches, shape (n,), NaN where it touches nothing. Exact for
    /// the cutter's profile; in parallel with the GIL released.
    fn drop_cutter<'py>(
        &self,
        py: Python<'py>,
        cutter: &str,
        xy: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let shape = Shape::parse(cutter).map_err(|e| Located::new(Place::file("cutter"), e))?;
        let pts: Vec<DVec2> = rows::<2>(xy, "xy")?
            .into_iter()
            .map(DVec2::from_array)
            .collect();
        let z = py.detach(|| {
            guard(self.name(), || {
                let dm = self.drop.get_or_init(|| DropMesh::new(&self.mesh));
                let drops = dm.drop_many(&shape, &pts);
                Ok(drops
                    .iter()
                    .map(|d| d.map_or(f64::NAN, |d| d.z))
                    .collect::<Array1<f64>>())
            })
        })?;
        Ok(z.into_pyarray(py))
    }

    /// Triangle count.
    fn __len__(&self) -> usize {
        self.mesh.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "<millplan.Mesh {}, {} triangles, {} vertices>",
            self.name(),
            self.mesh.len(),
            self.mesh.vertices.len()
        )
    }
}
