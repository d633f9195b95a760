//! Programs: reading, the IR's moves as NumPy arrays, writing, `inspect`.

use crate::error::{read_bytes, write_bytes, Located, Place, Res};
use millplan_nc::write::{write_program as write_nc, Target};
use millplan_nc::{Diagnostic, LengthUnit, MoveKind, Program, ReadOptions};
use millplan_plan::machine::Machine;
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::Path;
use std::sync::Arc;

/// A program in millplan's IR (tool-tip positions in mm, feeds in mm/min,
/// spindle speeds in 1/min, whatever the source was written in).
#[pyclass(module = "millplan", name = "Program", frozen)]
pub struct PyProgram {
    pub program: Arc<Program>,
    pub diagnostics: Vec<Diagnostic>,
    pub path: Option<String>,
}

/// The unit argument: `None`, `"mm"` or `"inch"`.
pub fn unit(u: Option<&str>) -> Res<Option<LengthUnit>> {
    match u {
        None => Ok(None),
        Some("mm") => Ok(Some(LengthUnit::Mm)),
        Some("inch") => Ok(Some(LengthUnit::Inch)),
        Some(o) => Err(Located::new(
            Place::file("units"),
            format!("{o:?}: must be \"mm\" or \"inch\""),
        )),
    }
}

/// Reads and parses a program file.
pub fn read(path: &str, units: Option<LengthUnit>) -> Res<PyProgram> {
    let bytes = read_bytes(path)?;
    let text = String::from_utf8_lossy(&bytes);
    if bytes.iter().take(4096).any(|&b| b == 0) {
        return Err(Located::new(
            Place::at(path, 1, 1),
            "binary data: not an APT/CL or G-code program",
        ));
    }
    let opts = ReadOptions {
        units,
        ..ReadOptions::default()
    };
    let parsed = millplan_nc::parse_program(&text, opts)
        .map_err(|e| Located::new(Place::at(path, e.line, e.col), e.message))?;
    Ok(PyProgram {
        program: Arc::new(parsed.program),
        diagnostics: parsed.diagnostics,
        path: Some(path.to_string()),
    })
}

/// A machine file, or millplan's built-in three-axis machine.
pub fn machine(path: Option<&str>) -> Res<Machine> {
    let Some(path) = path else {
        return Ok(Machine::default());
    };
    let text = String::from_utf8_lossy(&read_bytes(path)?).into_owned();
    Machine::from_toml(&text).map_err(|e| {
        let place = match e.at {
            Some((l, c)) => Place::at(path, l as u32, c as u32),
            None => Place::file(path),
        };
        let msg = match &e.field {
            Some(f) => format!("{f}: {}", e.message),
            None => e.message.clone(),
        };
        Located::new(place, msg)
    })
}

/// The summary of a program or STL file as JSON text.
pub fn inspect_json(
    path: &str,
    machine_path: Option<&str>,
    units: Option<LengthUnit>,
) -> Res<String> {
    let m = machine(machine_path)?;
    let bytes = read_bytes(path)?;
    let head = &bytes[..bytes.len().min(64 * 1024)];
    let json = if millplan_geom::stl::is_stl(bytes.len() as u64, head) {
        let (mut mesh, report) = crate::mesh::parse_stl(path, &bytes)?;
        if units == Some(LengthUnit::Inch) {
            mesh.map_vertices(|v| v * 25.4);
        }
        serde_json::to_string(&millplan_driver::inspect::mesh(&mesh, &report, units))
    } else {
        let p = read(path, units)?;
        let s = millplan_driver::inspect::program(&p.program, p.diagnostics.len(), &m);
        serde_json::to_string(&s)
    };
    json.map_err(|e| Located::new(Place::file(path), e.to_string()))
}

/// Target dialect by name.
pub fn target(name: &str) -> Res<Target> {
    Target::from_name(name).ok_or_else(|| {
        let all: Vec<&str> = Target::ALL.iter().map(|t| t.name()).collect();
        Located::new(
            Place::file("dialect"),
            format!("{name:?}: must be one of {}", all.join(", ")),
        )
    })
}

/// Writes `p` to `path` in `dialect` (else the one the file name says, else
/// the source's); returns the dialect written.
pub fn write(p: &Program, path: &str, dialect: Option<&str>, m: Option<&Machine>) -> Res<Target> {
    let to = dialect.map(target).transpose()?;
    let t = millplan_driver::target::output_target(to, Path::new(path), m, p.source)
        .map_err(|e| Located::new(Place::file(path), e))?;
    let wo = m.cloned().unwrap_or_default().write_options(t);
    let (bytes, _) =
        write_nc(p, wo).map_err(|e| Located::new(Place::at(path, e.line, 1), e.message))?;
    write_bytes(path, &bytes)?;
    Ok(t)
}

/// The moves' kinds as small integers (see `Program.KINDS`).
fn kind_code(k: MoveKind) -> u8 {
    match k {
        MoveKind::Rapid => 0,
        MoveKind::Linear => 1,
        MoveKind::Arc(_) => 2,
        MoveKind::Cycle(_) => 3,
    }
}

impl PyProgram {
    /// A program made by millplan (no file, no reader's notes).
    pub fn of(program: Program) -> PyProgram {
        PyProgram {
            program: Arc::new(program),
            diagnostics: Vec::new(),
            path: None,
        }
    }

    fn n(&self) -> usize {
        self.program.move_count()
    }

    /// One f64 per move.
    fn per_move(
        &self,
        f: impl Fn(&millplan_nc::Operation, &millplan_nc::Move) -> f64,
    ) -> Array1<f64> {
        self.program
            .operations
            .iter()
            .flat_map(|o| o.moves.iter().map(move |m| (o, m)))
            .map(|(o, m)| f(o, m))
            .collect()
    }

    /// Three f64 per move.
    fn per_move3(
        &self,
        f: impl Fn(&millplan_nc::Operation, &millplan_nc::Move) -> [f64; 3],
    ) -> Array2<f64> {
        let mut a = Array2::<f64>::zeros((self.n(), 3));
        let f = &f;
        let rows = self
            .program
            .operations
            .iter()
            .flat_map(|o| o.moves.iter().map(move |m| f(o, m)));
        for (mut row, v) in a.rows_mut().into_iter().zip(rows) {
            row[0] = v[0];
            row[1] = v[1];
            row[2] = v[2];
        }
        a
    }
}

#[pymethods]
impl PyProgram {
    /// Move kind codes: 0 rapid, 1 linear, 2 arc, 3 canned-cycle hole.
    #[classattr]
    const KINDS: (&'static str, &'static str, &'static str, &'static str) =
        ("rapid", "linear", "arc", "cycle");

    /// Tool-tip position at the end of each move, mm, shape (n, 3); NaN on
    /// an axis the program has not set yet.
    #[getter]
    fn xyz<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.per_move3(|_, m| m.end.to_array()).into_pyarray(py)
    }

    /// Unit tool axis of each move (tip up the spindle), shape (n, 3); NaN
    /// where the program does not give one (a three-axis move: the
    /// operation's fixed axis).
    #[getter]
    fn axis<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.per_move3(|o, m| o.axis(m).map_or([f64::NAN; 3], |a| a.to_array()))
            .into_pyarray(py)
    }

    /// Feed of each move in its feed mode's unit (mm/min for most), 0 on rapids.
    #[getter]
    fn feed<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.per_move(|_, m| m.feed).into_pyarray(py)
    }

    /// Spindle speed while each move runs, 1/min (0: stopped).
    #[getter]
    fn spindle<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.per_move(|_, m| m.spindle).into_pyarray(py)
    }

    /// Kind code of each move (see `KINDS`).
    #[getter]
    fn kind<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u8>> {
        let v: Array1<u8> = self.program.moves().map(|m| kind_code(m.kind)).collect();
        v.into_pyarray(py)
    }

    /// 1-based source line of each move (0: generated).
    #[getter]
    fn line<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        let v: Array1<u32> = self.program.moves().map(|m| m.line).collect();
        v.into_pyarray(py)
    }

    /// Index of the operation each move belongs to.
    #[getter]
    fn operation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        let v: Array1<u32> = (0u32..)
            .zip(&self.program.operations)
            .flat_map(|(i, o)| std::iter::repeat_n(i, o.moves.len()))
            .collect();
        v.into_pyarray(py)
    }

    /// The operations: name, tool (number, name, cutter) and move count each.
    #[getter]
    fn operations<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.program
            .operations
            .iter()
            .map(|o| {
                let d = PyDict::new(py);
                d.set_item("name", o.name.clone())?;
                d.set_item("moves", o.moves.len())?;
                d.set_item("tool", o.tool.as_ref().and_then(|t| t.number))?;
                Ok(d)
            })
            .collect()
    }

    /// The tools of the operations, as `inspect` lists them.
    #[getter]
    fn tools(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let s = millplan_driver::inspect::program(&self.program, 0, &Machine::default());
        crate::json_to_py(py, &serde_json::to_string(&s.tools).unwrap_or_default())
    }

    /// The file the program was read from, if any.
    #[getter]
    fn path(&self) -> Option<String> {
        self.path.clone()
    }

    /// The reader's notes (words it kept but does not model), as
    /// `file:line:col: message` strings.
    #[getter]
    fn diagnostics(&self) -> Vec<String> {
        let f = self.path.clone().unwrap_or_else(|| "<program>".into());
        self.diagnostics
            .iter()
            .map(|d| format!("{f}:{}:{}: {}", d.line, d.col, d.message))
            .collect()
    }

    /// The source dialect (`fanuc`, `apt`, …).
    #[getter]
    fn dialect(&self) -> &'static str {
        self.program.source.name()
    }

    /// The IR as text, one line per move and event (`millplan inspect --ir`).
    fn ir(&self) -> String {
        millplan_nc::text::print(&self.program)
    }

    /// The summary `millplan.inspect` gives for this program, timed on the
    /// built-in machine or `machine` (a machine file).
    #[pyo3(signature = (machine=None))]
    fn summary(&self, py: Python<'_>, machine: Option<&str>) -> PyResult<Py<PyAny>> {
        let m = crate::program::machine(machine)?;
        let s = millplan_driver::inspect::program(&self.program, self.diagnostics.len(), &m);
        crate::json_to_py(py, &serde_json::to_string(&s).unwrap_or_default())
    }

    fn __len__(&self) -> usize {
        self.n()
    }

    fn __repr__(&self) -> String {
        format!(
            "<millplan.Program {} ({}), {} operations, {} moves>",
            self.path.as_deref().unwrap_or("-"),
            self.program.source.name(),
            self.program.operations.len(),
            self.n()
        )
    }
}
