//! `ToolLibrary`: a tool library (millplan-tooldb's SQLite file, as
//! `millplan tool` keeps it) read for Python, and given to `optimise` so
//! each tool the program calls takes the library's geometry (the driver's
//! `tools` module).

use crate::error::{Located, Place, Res};
use millplan_driver::tools::{cutter_of, Library};
use millplan_tooldb::db::{DbError, ToolDb};
use pyo3::exceptions::PyKeyError;
use pyo3::prelude::*;

/// A tool library file, read when opened.
#[pyclass(module = "millplan", name = "ToolLibrary", frozen)]
pub struct PyToolLibrary {
    pub library: Library,
    pub path: String,
}

fn db_error(path: &str, e: DbError) -> Located {
    Located::new(Place::file(path), e.to_string())
}

/// Opens the library at `path` (which must exist: a missing file is never
/// taken for an empty library) and reads its tools and decisions.
pub fn open(path: &str) -> Res<(ToolDb, Library)> {
    if !std::path::Path::new(path).is_file() {
        return Err(Located::new(Place::file(path), "no such tool library"));
    }
    let db = ToolDb::open(std::path::Path::new(path)).map_err(|e| db_error(path, e))?;
    let lib = Library::read(&db).map_err(|e| db_error(path, e))?;
    Ok((db, lib))
}

fn to_py<T: serde::Serialize>(py: Python<'_>, v: &T) -> PyResult<Py<PyAny>> {
    let json = serde_json::to_string(v)
        .map_err(|e| Located::new(Place::file("tool library"), e.to_string()))?;
    crate::json_to_py(py, &json)
}

#[pymethods]
impl PyToolLibrary {
    #[new]
    fn new(py: Python<'_>, path: std::path::PathBuf) -> PyResult<PyToolLibrary> {
        let path = path.display().to_string();
        let (_, library) = py.detach(|| crate::error::guard(&path, || open(&path)))?;
        Ok(PyToolLibrary { library, path })
    }

    /// Every tool, as `millplan tool show --json` lists them.
    #[getter]
    fn tools(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let all: Vec<_> = self.library.tools.values().collect();
        to_py(py, &all)
    }

    /// The tool numbers, ascending.
    #[getter]
    fn numbers(&self) -> Vec<u32> {
        self.library.tools.keys().copied().collect()
    }

    /// The file it was read from.
    #[getter]
    fn path(&self) -> String {
        self.path.clone()
    }

    /// The cutter the library gives tool `number` (radius R + DR, corner
    /// radius from its kind or RE, flute length APMX): a dict of `d`, `r`
    /// (corner radius) and `flute_length` (mm, None if unknown), or None
    /// for a kind millplan cannot shape.
    fn cutter(&self, py: Python<'_>, number: u32) -> PyResult<Option<Py<PyAny>>> {
        let t = self.record(number)?;
        cutter_of(t)
            .map(|c| {
                let v = serde_json::json!({"d": c.d, "r": c.r, "flute_length": (c.h > 0.0).then_some(c.h)});
                to_py(py, &v)
            })
            .transpose()
    }

    /// The library's last decision about tool `number` (`worn`, `broken`,
    /// …), None if it logged none.
    fn decision(&self, number: u32) -> PyResult<Option<String>> {
        self.record(number)?;
        Ok(self.library.last_decision.get(&number).cloned())
    }

    /// The decision log (of one tool, or all), as `millplan tool log --json`.
    #[pyo3(signature = (number=None))]
    fn log(&self, py: Python<'_>, number: Option<u32>) -> PyResult<Py<PyAny>> {
        let path = self.path.clone();
        let ev = py.detach(|| {
            crate::error::guard(&path, || {
                let (db, _) = open(&path)?;
                db.events(number).map_err(|e| db_error(&path, e))
            })
        })?;
        to_py(py, &ev)
    }

    fn __getitem__(&self, py: Python<'_>, number: u32) -> PyResult<Py<PyAny>> {
        to_py(py, self.record(number)?)
    }

    fn __contains__(&self, number: u32) -> bool {
        self.library.tools.contains_key(&number)
    }

    fn __len__(&self) -> usize {
        self.library.tools.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "<millplan.ToolLibrary {}, {} tools>",
            self.path,
            self.library.tools.len()
        )
    }
}

impl PyToolLibrary {
    fn record(&self, number: u32) -> PyResult<&millplan_tooldb::db::ToolRecord> {
        self.library
            .tools
            .get(&number)
            .ok_or_else(|| PyKeyError::new_err(format!("T{number}: not in {}", self.path)))
    }
}

/// A library argument: a `ToolLibrary`, a file name or None.
pub fn library_arg(l: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Library>> {
    let Some(l) = l.filter(|l| !l.is_none()) else {
        return Ok(None);
    };
    if let Ok(t) = l.cast::<PyToolLibrary>() {
        return Ok(Some(t.get().library.clone()));
    }
    let path = l.extract::<std::path::PathBuf>()?.display().to_string();
    Ok(Some(open(&path)?.1))
}
