//! `millplan tool`: where the library lives by default, a tool and an event
//! in words, the measurement and the laser cycle from the options, and the
//! JSON of what a subcommand did.

use crate::check::{arg, Range};
use millplan_tooldb::control::{Kind, Measurement, Outcome};
use millplan_tooldb::cycles::{CycleOptions, Measure};
use millplan_tooldb::db::{EventRecord, ToolRecord};
use millplan_tooldb::thread::pz;
use serde::Serialize;
use std::ffi::OsString;
use std::path::PathBuf;

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
