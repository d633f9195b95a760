//! `millplan tool`: where the library lives by default, a tool and an event
//! in words, the measurement and the laser cycle from the options, and the
//! JSON of what a subcommand did.

use crate::check::{arg, Range};
use millplan_tooldb::control::{record, Kind, Measurement, Outcome, Settings};
use millplan_tooldb::cycles::{self, CycleOptions, Measure};
use millplan_tooldb::db::{DbError, EventRecord, ToolDb, ToolEdit, ToolRecord};
use millplan_tooldb::thread::pz;
use serde::Serialize;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// A failure of a library operation, its message naming the library (or
/// the imported file, at its line and column): the arguments' or the
/// file's fault (`bad_input`, exit 2), or the system's (locked for too
/// long, read-only, an I/O error: exit 1).
#[derive(Debug)]
pub struct ToolError {
    pub bad_input: bool,
    pub message: String,
}

impl ToolError {
    /// The arguments' fault.
    pub fn input(message: impl Into<String>) -> ToolError {
        ToolError {
            bad_input: true,
            message: message.into(),
        }
    }

    /// The program's fault.
    pub fn internal(message: impl Into<String>) -> ToolError {
        ToolError {
            bad_input: false,
            message: message.into(),
        }
    }
}

impl std::fmt::Display for ToolError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for ToolError {}

/// The library file: `--db` as given, else [`default_db`] from the
/// environment with its folder created (a `--db` folder never is).
pub fn library_path(
    db: Option<PathBuf>,
    millplan_db: Option<OsString>,
    xdg_data_home: Option<OsString>,
    home: Option<OsString>,
) -> Result<PathBuf, ToolError> {
    if let Some(p) = db {
        return Ok(p);
    }
    let p = default_db(millplan_db, xdg_data_home, home).map_err(ToolError::input)?;
    if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| ToolError::input(format!("{}: cannot create: {e}", dir.display())))?;
    }
    Ok(p)
}

/// The formats `tool export` writes.
#[derive(Clone, Copy, Debug)]
pub enum ExportFormat {
    Csv,
    Json,
    /// Heidenhain TOOL.T-style table.
    ToolT,
}

/// The controls `tool cycle` writes a measuring program for.
#[derive(Clone, Copy, Debug)]
pub enum CycleControl {
    Heidenhain,
    Fanuc,
}

/// The options of `tool cycle`.
#[derive(Clone, Copy, Debug)]
pub struct CycleRequest {
    pub number: u32,
    pub control: CycleControl,
    pub first: bool,
    pub measured: Measured,
    pub clearance: f64,
    pub per_tooth: bool,
}

/// An open tool library and where it is: each subcommand's decisions.
pub struct Library {
    pub path: PathBuf,
    db: ToolDb,
}

impl Library {
    /// Opens (or creates) the library at `path`; a file that is not one is
    /// an error, never taken for an empty library.
    pub fn open(path: PathBuf) -> Result<Library, ToolError> {
        let db = ToolDb::open(&path).map_err(|e| db_error(&path, e))?;
        Ok(Library { path, db })
    }

    fn err(&self, e: DbError) -> ToolError {
        db_error(&self.path, e)
    }

    /// Registers tool `number`, or changes it (values not given stay). Only
    /// a tool the library does not have is new; a row that cannot be read
    /// is an error, never overwritten by a fresh record.
    pub fn add(&mut self, number: u32, edit: ToolEdit) -> Result<ToolRecord, ToolError> {
        let found = self.db.find_tool(number).map_err(|e| self.err(e))?;
        let mut t = found.unwrap_or_else(|| ToolRecord::new(number, ""));
        t.apply(edit)
            .map_err(|e| ToolError::input(format!("insert data: {e}")))?;
        self.db.put_tool(&t).map_err(|e| self.err(e))?;
        Ok(t)
    }

    /// Records the insert on a thread mill; its PZ.
    pub fn insert(
        &mut self,
        number: u32,
        designation: &str,
        insl: f64,
        tp: f64,
    ) -> Result<f64, ToolError> {
        let r = self.db.add_insert(number, designation, insl, tp);
        r.map_err(|e| self.err(e))
    }

    /// Records the presetter's values; the tool as it now is.
    pub fn preset(&mut self, number: u32, l: f64, r: f64) -> Result<ToolRecord, ToolError> {
        self.db
            .record_presetter(number, l, r)
            .map_err(|e| self.err(e))?;
        self.db.tool(number).map_err(|e| self.err(e))
    }

    /// Records a laser measurement and decides (wear, worn, broken).
    pub fn measure(
        &mut self,
        req: MeasureRequest,
        pallet: Option<String>,
    ) -> Result<Outcome, ToolError> {
        check_measure(&req).map_err(ToolError::input)?;
        let tool = self.db.tool(req.number).map_err(|e| self.err(e))?;
        let settings = Settings {
            dset: req.dset,
            pallet,
        };
        let m = measurement(req, &tool);
        record(&mut self.db, &m, &settings).map_err(|e| self.err(e))
    }

    /// One tool, or all.
    pub fn show(&self, number: Option<u32>) -> Result<Vec<ToolRecord>, ToolError> {
        match number {
            Some(n) => self.db.tool(n).map(|t| vec![t]),
            None => self.db.tools(),
        }
        .map_err(|e| self.err(e))
    }

    /// The decision log (one tool's, or all).
    pub fn log(&self, number: Option<u32>) -> Result<Vec<EventRecord>, ToolError> {
        self.db.events(number).map_err(|e| self.err(e))
    }

    /// Imports the tools of `file` (JSON when it starts `[`, else CSV), all
    /// or nothing; how many. Errors in the file are located in it.
    pub fn import(&mut self, file: &Path) -> Result<usize, ToolError> {
        let text = std::fs::read_to_string(file)
            .map_err(|e| ToolError::input(format!("{}: {e}", file.display())))?;
        let n = if text.trim_start().starts_with('[') {
            self.db.import_json(&text)
        } else {
            self.db.import_csv(&text)
        };
        n.map_err(|e| match e {
            // Located in the imported file (line:column).
            DbError::Invalid(_) => ToolError::input(format!("{}:{e}", file.display())),
            e => self.err(e),
        })
    }

    /// The library as CSV, JSON or a TOOL.T table.
    pub fn export(&self, format: ExportFormat) -> Result<String, ToolError> {
        match format {
            ExportFormat::Csv => self.db.export_csv(),
            ExportFormat::Json => self.db.export_json(),
            ExportFormat::ToolT => self.db.export_tool_t(),
        }
        .map_err(|e| self.err(e))
    }

    /// The measuring program for the laser, and the insert's PZ it uses.
    pub fn cycle(&self, x: CycleRequest) -> Result<(String, Option<f64>), ToolError> {
        check_clearance(x.clearance).map_err(ToolError::input)?;
        let tool = self.db.tool(x.number).map_err(|e| self.err(e))?;
        let o = cycle_options(&tool, x.first, x.measured, x.clearance, x.per_tooth);
        let text = match x.control {
            CycleControl::Heidenhain => cycles::heidenhain(&tool, &o),
            CycleControl::Fanuc => cycles::fanuc(&tool, &o),
        };
        Ok((text, o.pz))
    }
}

/// A library error with the library's path: bad input when the arguments
/// or the file are at fault, else the system's.
fn db_error(path: &Path, e: DbError) -> ToolError {
    ToolError {
        bad_input: e.is_bad_input(),
        message: format!("{}: {e}", path.display()),
    }
}

/// The library's default location from `$MILLPLAN_DB`, `$XDG_DATA_HOME` and
/// `$HOME` (as given): the first, else `millplan/tools.db` under the second
/// or `~/.local/share`. An empty `$MILLPLAN_DB` is an error, not a
/// temporary library.
pub fn default_db(
    millplan_db: Option<OsString>,
    xdg_data_home: Option<OsString>,
    home: Option<OsString>,
) -> Result<PathBuf, String> {
    if let Some(p) = millplan_db {
        if p.is_empty() {
            return Err(
                "MILLPLAN_DB is set but empty: name the tool library file, or unset it".into(),
            );
        }
        return Ok(PathBuf::from(p));
    }
    let base = xdg_data_home
        .map(PathBuf::from)
        .or_else(|| home.map(|h| PathBuf::from(h).join(".local/share")))
        .unwrap_or_else(|| PathBuf::from("."));
    Ok(base.join("millplan").join("tools.db"))
}

/// The PZ of a tool's insert from its ISO data (`INSL`, `TP`), if it has one.
pub fn insert_pz(t: &ToolRecord) -> Option<f64> {
    let g = |k: &str| t.iso.get(k).and_then(|v| v.parse::<f64>().ok());
    pz(g("INSL")?, g("TP")?).ok()
}

/// A tool in one line.
pub fn describe(t: &ToolRecord) -> String {
    format!(
        "T{:<5} {:<28} {:<12} L {:>9.4} R {:>8.4} DL {:+.4} DR {:+.4} tol L {:.3}/{:.3} R {:.3}/{:.3}{}{}",
        t.number,
        t.name,
        t.kind,
        t.l,
        t.r,
        t.dl,
        t.dr,
        t.ltol,
        t.lbreak,
        t.rtol,
        t.rbreak,
        t.sister.map(|s| format!(" sister T{s}")).unwrap_or_default(),
        if t.locked { "  LOCKED" } else { "" }
    )
}

/// The tools in words, one a line; `library` names an empty library.
pub fn tools_text(tools: &[ToolRecord], library: &str) -> String {
    if tools.is_empty() {
        format!("{library}: no tools yet")
    } else {
        tools.iter().map(describe).collect::<Vec<_>>().join("\n")
    }
}

/// The events of the log in words, one a line.
pub fn events_text(events: &[EventRecord]) -> String {
    events
        .iter()
        .map(|e| {
            format!(
                "{} T{} {}: {}",
                e.time,
                e.tool.map(|t| t.to_string()).unwrap_or("-".into()),
                e.decision,
                e.reason
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The options of `tool measure` beyond the tool's record.
#[derive(Clone, Debug)]
pub struct MeasureRequest {
    pub number: u32,
    pub first: bool,
    pub l: Option<f64>,
    pub r: Option<f64>,
    pub teeth: Option<Vec<f64>>,
    pub pz: Option<f64>,
    /// Setup tolerance, mm.
    pub dset: f64,
}

/// The options in their ranges, before the library is read.
pub fn check_measure(x: &MeasureRequest) -> Result<(), String> {
    arg("--dset", x.dset, Range::from(0.0, 10.0, "mm"))?;
    if let Some(pz) = x.pz {
        arg("--pz", pz, Range::from(0.0, 1000.0, "mm"))?;
    }
    Ok(())
}

/// The measurement of tool `t` (its insert's PZ unless `--pz` gives one).
pub fn measurement(x: MeasureRequest, t: &ToolRecord) -> Measurement {
    Measurement {
        tool: x.number,
        kind: if x.first {
            Kind::First
        } else {
            Kind::Inspection
        },
        l: x.l,
        r: x.r,
        per_tooth: x.teeth,
        pz: x.pz.or_else(|| insert_pz(t)),
    }
}

/// The decision of a measurement in words.
pub fn outcome_text(o: &Outcome) -> String {
    format!(
        "{}: {}{}",
        o.decision.as_str().to_uppercase(),
        o.reason,
        o.switch_to
            .map(|n| format!("\nnext: use T{n}"))
            .unwrap_or_default()
    )
}

/// What the laser of `tool cycle` measures.
#[derive(Clone, Copy, Debug)]
pub enum Measured {
    Length,
    Radius,
    Both,
}

/// The laser cycle's clearance in its range, before the library is read.
pub fn check_clearance(clearance: f64) -> Result<(), String> {
    arg("--clearance", clearance, Range::positive(10_000.0, "mm"))?;
    Ok(())
}

/// The laser cycle's options for tool `t`.
pub fn cycle_options(
    t: &ToolRecord,
    first: bool,
    measured: Measured,
    clearance: f64,
    per_tooth: bool,
) -> CycleOptions {
    CycleOptions {
        kind: if first { Kind::First } else { Kind::Inspection },
        measure: match measured {
            Measured::Length => Measure::Length,
            Measured::Radius => Measure::Radius,
            Measured::Both => Measure::Both,
        },
        clearance,
        per_tooth,
        pz: insert_pz(t),
    }
}

/// What `tool pz --json` prints.
#[derive(Serialize)]
pub struct PzJson {
    pub pz: f64,
    pub insl: f64,
    pub tp: f64,
}

/// What `tool insert --json` prints.
#[derive(Serialize)]
pub struct InsertJson<'a> {
    pub tool: u32,
    pub designation: &'a str,
    pub insl: f64,
    pub tp: f64,
    pub pz: f64,
}

/// What `tool export` and `tool cycle` print with `--json`: the file
/// written and, for a cycle, the insert's PZ.
#[derive(Serialize)]
pub struct WrittenJson {
    pub output: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pz: Option<Option<f64>>,
}

/// What `tool import --json` prints.
#[derive(Serialize)]
pub struct ImportedJson {
    pub imported: usize,
}

/// One subcommand of `millplan tool` on the library, as given.
pub enum ToolRequest {
    Add(u32, ToolEdit),
    /// Tool, designation, INSL and TP (mm).
    Insert(u32, String, (f64, f64)),
    /// Tool, L and R (mm) from the presetter.
    Preset(u32, (f64, f64)),
    Measure(MeasureRequest, Option<String>),
    Show(Option<u32>),
    Log(Option<u32>),
    Import(PathBuf),
    Export(ExportFormat),
    Cycle(CycleRequest),
}

/// What a subcommand made: its JSON and text (when it writes a file, what
/// to write and the PZ it used: `tool export` none, `tool cycle` the
/// insert's if it has one), and whether a measurement found a problem.
#[derive(Debug)]
pub struct ToolOutcome {
    pub json: serde_json::Value,
    pub text: String,
    pub file: Option<(String, Option<Option<f64>>)>,
    pub problem: bool,
}

impl ToolOutcome {
    fn said<T: Serialize>(v: &T, text: String) -> Result<ToolOutcome, ToolError> {
        let json = serde_json::to_value(v)
            .map_err(|e| ToolError::internal(format!("JSON output: {e}")))?;
        Ok(ToolOutcome {
            json,
            text,
            file: None,
            problem: false,
        })
    }

    fn file(text: String, pz: Option<Option<f64>>) -> ToolOutcome {
        ToolOutcome {
            json: serde_json::Value::Null,
            text: String::new(),
            file: Some((text, pz)),
            problem: false,
        }
    }

    /// What a subcommand that wrote `output` says (its JSON, its text).
    pub fn written(output: &Path, pz: Option<Option<f64>>) -> Result<ToolOutcome, ToolError> {
        let text = format!("wrote {}", output.display());
        let output = output.display().to_string();
        ToolOutcome::said(&WrittenJson { output, pz }, text)
    }
}

/// `millplan tool pz`: the PZ of an insert (no library needed).
pub fn pz_command(insl: f64, tp: f64) -> Result<ToolOutcome, ToolError> {
    let v = pz(insl, tp).map_err(|e| ToolError::input(e.to_string()))?;
    let text = format!("PZ = {v:.3} mm (INSL {insl}, TP {tp})");
    ToolOutcome::said(&PzJson { pz: v, insl, tp }, text)
}

/// `millplan tool SUBCOMMAND` on the library.
pub fn command(lib: &mut Library, r: ToolRequest) -> Result<ToolOutcome, ToolError> {
    match r {
        ToolRequest::Add(number, edit) => {
            let t = lib.add(number, edit)?;
            ToolOutcome::said(&t, format!("saved {}", describe(&t)))
        }
        ToolRequest::Insert(tool, designation, (insl, tp)) => {
            let pz = lib.insert(tool, &designation, insl, tp)?;
            let text = format!("T{tool}: insert {designation}, PZ {pz:.3} mm");
            let designation = designation.as_str();
            ToolOutcome::said(
                &InsertJson {
                    tool,
                    designation,
                    insl,
                    tp,
                    pz,
                },
                text,
            )
        }
        ToolRequest::Preset(number, (l, r)) => {
            let t = lib.preset(number, l, r)?;
            let text = format!("presetter values recorded: {}", describe(&t));
            ToolOutcome::said(&t, text)
        }
        ToolRequest::Measure(req, pallet) => {
            let o = lib.measure(req, pallet)?;
            let problem = o.decision.is_problem();
            let out = ToolOutcome::said(&o, outcome_text(&o))?;
            Ok(ToolOutcome { problem, ..out })
        }
        ToolRequest::Show(number) => {
            let tools = lib.show(number)?;
            let text = tools_text(&tools, &lib.path.display().to_string());
            ToolOutcome::said(&tools, text)
        }
        ToolRequest::Log(number) => {
            let ev = lib.log(number)?;
            ToolOutcome::said(&ev, events_text(&ev))
        }
        ToolRequest::Import(file) => {
            let n = lib.import(&file)?;
            let text = format!("imported {n} tools into {}", lib.path.display());
            ToolOutcome::said(&ImportedJson { imported: n }, text)
        }
        ToolRequest::Export(format) => Ok(ToolOutcome::file(lib.export(format)?, None)),
        ToolRequest::Cycle(c) => {
            let (text, pz) = lib.cycle(c)?;
            Ok(ToolOutcome::file(text, Some(pz)))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tool added is shown, exported and measured for; the failures say
    /// whose fault they are and where.
    #[test]
    fn library_operations_decide_and_locate_their_errors() {
        let dir = tempfile::tempdir().expect("tmp");
        let path = dir.path().join("tools.db");
        let mut lib = Library::open(path.clone()).expect("created");
        let edit = ToolEdit {
            name: Some("ball 10".into()),
            kind: Some("ball".into()),
            l: Some(80.0),
            r: Some(5.0),
            ..ToolEdit::default()
        };
        let t = lib.add(7, edit).expect("added");
        assert_eq!((t.number, t.r), (7, 5.0));
        assert_eq!(lib.show(None).expect("all").len(), 1);
        assert!(lib
            .export(ExportFormat::Csv)
            .expect("csv")
            .contains("ball 10"));
        let e = lib.show(Some(8)).expect_err("unknown");
        assert!(
            e.bad_input && e.message.starts_with(&path.display().to_string()),
            "{e}"
        );
        // An import's error is located in the imported file.
        let csv = dir.path().join("bad.csv");
        std::fs::write(&csv, "name\nx\n").expect("write");
        let e = lib.import(&csv).expect_err("no number column");
        assert!(
            e.message.starts_with(&format!("{}:1:1: ", csv.display())),
            "{e}"
        );
        let x = CycleRequest {
            number: 7,
            control: CycleControl::Heidenhain,
            first: true,
            measured: Measured::Both,
            clearance: -1.0,
            per_tooth: false,
        };
        assert!(lib.cycle(x).expect_err("clearance").bad_input);
        let (text, pz) = lib
            .cycle(CycleRequest {
                clearance: 20.0,
                ..x
            })
            .expect("cycle");
        assert!(!text.is_empty() && pz.is_none());
        // A file that is no library is refused, never taken for an empty one.
        let junk = dir.path().join("junk.db");
        std::fs::write(&junk, vec![b'x'; 4096]).expect("write");
        assert!(Library::open(junk).is_err());
        // `--db` is taken as given; an empty $MILLPLAN_DB is refused.
        let given = library_path(Some(path.clone()), None, None, None).expect("given");
        assert_eq!(given, path);
        assert!(
            library_path(None, Some("".into()), None, None)
                .expect_err("empty")
                .bad_input
        );
    }

    /// The subcommands through the one function: a tool added and shown,
    /// an insert's PZ by paper 002's formula 2 (INSL 12.1, TP 1.5:
    /// (12.1 − 7·1.5)/2 = 0.8 mm; INSL 14, TP 1: 0.5 mm, an exact multiple),
    /// the export as a file to write, a bad pitch the arguments' fault.
    #[test]
    fn the_commands_route_through_one_function() {
        let dir = tempfile::tempdir().expect("tmp");
        let mut lib = Library::open(dir.path().join("tools.db")).expect("opens");
        let edit = ToolEdit {
            name: Some("thread mill".into()),
            l: Some(80.0),
            r: Some(5.0),
            ..ToolEdit::default()
        };
        let added = command(&mut lib, ToolRequest::Add(7, edit)).expect("adds");
        assert!(added.text.starts_with("saved") && !added.problem);
        let shown = command(&mut lib, ToolRequest::Show(Some(7))).expect("shows");
        assert_eq!(shown.json[0]["number"], 7, "{}", shown.json);
        let ins = ToolRequest::Insert(7, "12IR1.5ISO".into(), (12.1, 1.5));
        let ins = command(&mut lib, ins).expect("insert");
        assert!(
            (ins.json["pz"].as_f64().expect("pz") - 0.8).abs() < 1e-9,
            "{}",
            ins.json
        );
        let pz = pz_command(14.0, 1.0).expect("pz");
        assert!((pz.json["pz"].as_f64().expect("pz") - 0.5).abs() < 1e-9);
        assert!(!pz_command(14.0, -1.0)
            .expect_err("pitch")
            .message
            .is_empty());
        let export = command(&mut lib, ToolRequest::Export(ExportFormat::Csv)).expect("export");
        let (text, pz) = export.file.expect("a file to write");
        assert!(text.lines().count() >= 2 && pz.is_none(), "{text}");
        let w = ToolOutcome::written(Path::new("out.csv"), None).expect("said");
        assert_eq!(
            (w.json["output"].as_str(), w.text.as_str()),
            (Some("out.csv"), "wrote out.csv")
        );
    }
}
