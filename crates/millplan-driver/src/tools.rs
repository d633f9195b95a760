//! Tool data from the tool library (`millplan tool`, `millplan_tooldb`):
//! each tool number the program calls takes its geometry from the library's
//! row, corrected by the measured deltas (R + DR, L + DL), and what the row
//! lacks from its ISO 13399 properties (the `tool_props` table, one symbol
//! per row):
//!
//! | symbol | meaning | used as |
//! |---|---|---|
//! | `RE` | corner radius, mm | a bull-nose cutter (a `ball` kind or RE = R: a ball) |
//! | `APMX` | usable flute length, mm | the flute length of the tool body |
//! | `ZEFP` | number of flutes (peripheral effective cutting edges) | flutes of the force model |
//! | `FHA` | flute helix angle, degrees | helix of the force model |
//! | `LPR` | protruding length (stick-out from the holder), mm | where the holder starts |
//! | `HOLDER_D` | holder diameter at the tool, mm (millplan's symbol) | the holder's radius |
//!
//! A tool the program calls that the library lacks, and a tool the library
//! has locked (its own decision after a measurement: setup mismatch, worn,
//! broken) or whose tool life is used up, are errors at the line of the
//! tool call, before any work.

use millplan_nc::{Cutter, Program};
use millplan_tooldb::db::ToolRecord;
use std::collections::BTreeMap;

/// The library as read: every tool by number, with the library's last
/// decision about it (`worn`, `broken`, …) where it logged one.
#[derive(Clone, Debug, Default)]
pub struct Library {
    pub tools: BTreeMap<u32, ToolRecord>,
    pub last_decision: BTreeMap<u32, String>,
}

impl Library {
    /// The library file of `--tools`, read whole (it must exist); the error
    /// names the option and the file, the file's fault or the system's.
    pub fn open(p: &std::path::Path) -> Result<Library, crate::tool::ToolError> {
        if !p.is_file() {
            let m = format!("--tools {}: no such tool library", p.display());
            return Err(crate::tool::ToolError::input(m));
        }
        let err = |e: millplan_tooldb::db::DbError| crate::tool::ToolError {
            bad_input: e.is_bad_input(),
            message: format!("--tools {}: {e}", p.display()),
        };
        let db = millplan_tooldb::db::ToolDb::open(p).map_err(err)?;
        Library::read(&db).map_err(err)
    }

    /// Every tool of an open library and the last decision logged for each.
    pub fn read(db: &millplan_tooldb::db::ToolDb) -> Result<Library, millplan_tooldb::db::DbError> {
        let mut lib = Library::default();
        for t in db.tools()? {
            lib.tools.insert(t.number, t);
        }
        for e in db.events(None)? {
            if let Some(n) = e.tool {
                lib.last_decision.insert(n, e.decision);
            }
        }
        Ok(lib)
    }
}

/// What one library tool gives a job beyond its cutter.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LibraryTool {
    pub number: u32,
    pub flutes: Option<usize>,
    pub helix_deg: Option<f64>,
    /// Holder radius and stick-out, mm.
    pub holder: Option<(f64, f64)>,
}

/// A tool call the library cannot serve, at its line.
#[derive(Clone, Debug, PartialEq)]
pub struct ToolError {
    pub line: u32,
    pub message: String,
}

fn prop(t: &ToolRecord, symbol: &str) -> Option<f64> {
    t.iso
        .get(symbol)
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v > 0.0)
}

/// The cutter of a library row: radius R + DR, corner radius from the kind
/// (`ball`) or `RE`, flute length `APMX`; `None` for a kind millplan
/// cannot shape (thread mills, drills) or a row without a radius.
pub fn cutter_of(t: &ToolRecord) -> Option<Cutter> {
    let r = t.effective_r();
    let kind = t.kind.to_ascii_lowercase();
    if !(r > 0.0)
        || !(kind.contains("mill") || kind == "ball" || kind == "bull" || kind == "flat")
        || kind.contains("thread")
    {
        return None;
    }
    let re = if kind.contains("ball") {
        r
    } else {
        prop(t, "RE").unwrap_or(0.0).min(r)
    };
    let h = prop(t, "APMX").unwrap_or(0.0);
    Some(Cutter::from_iso(2.0 * r, re, r - re, re, 0.0, 0.0, h))
}

/// Why the library refuses tool `t` before any work, if it does.
fn refused(t: &ToolRecord, lib: &Library) -> Option<String> {
    if t.locked {
        let why = lib
            .last_decision
            .get(&t.number)
            .map_or(String::new(), |d| format!(" (its last decision: {d})"));
        return Some(format!(
            "tool {} is locked in the tool library{why}: it may not cut",
            t.number
        ));
    }
    match t.life_min {
        Some(life) if t.used_min >= life => Some(format!(
            "tool {} is worn out: {:.1} of its {:.1} minutes of life used",
            t.number, t.used_min, life
        )),
        _ => None,
    }
}

/// Gives every operation of `p` its tool from `lib`: the cutter replaced by
/// the library's; returns what each tool gives beyond its cutter, by
/// operation. A tool missing, locked or worn out is an error at its call.
pub fn apply(p: &mut Program, lib: &Library) -> Result<Vec<Option<LibraryTool>>, ToolError> {
    let mut out = Vec::with_capacity(p.operations.len());
    for op in &mut p.operations {
        let cuts = op.moves.iter().any(|m| m.is_cutting());
        let Some(tool) = op.tool.as_mut().filter(|_| cuts) else {
            out.push(None);
            continue;
        };
        // The tool's own line (its call or definition), else the first move's.
        let first = op.moves.first().map_or(0, |m| m.line);
        let line = if tool.line > 0 { tool.line } else { first };
        let Some(n) = tool.number else {
            return Err(ToolError {
                line,
                message: "the tool has no number to look up in the tool library".into(),
            });
        };
        let t = lib.tools.get(&n).ok_or_else(|| ToolError {
            line,
            message: format!("tool {n} is not in the tool library"),
        })?;
        if let Some(message) = refused(t, lib) {
            return Err(ToolError { line, message });
        }
        if let Some(c) = cutter_of(t) {
            tool.cutter = Some(c);
        }
        let holder = match (prop(t, "HOLDER_D"), prop(t, "LPR")) {
            (Some(d), Some(l)) => Some((d / 2.0, l)),
            _ => None,
        };
        out.push(Some(LibraryTool {
            number: n,
            flutes: prop(t, "ZEFP")
                .map(|z| z.round() as usize)
                .filter(|z| *z > 0),
            helix_deg: prop(t, "FHA"),
            holder,
        }));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use millplan_nc::{parse_program, ReadOptions};

    const SRC: &str = "G21 G90\nT3 M6\nS8000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F300\nG1 X10\nM30\n";

    fn lib(t: ToolRecord) -> Library {
        Library {
            tools: [(t.number, t)].into_iter().collect(),
            ..Library::default()
        }
    }

    fn ball(n: u32) -> ToolRecord {
        let mut t = ToolRecord::new(n, "ball D10");
        t.kind = "ball".into();
        t.r = 5.0;
        t.dr = -0.01;
        t.l = 80.0;
        t.iso.insert("ZEFP".into(), "4".into());
        t.iso.insert("FHA".into(), "35".into());
        t.iso.insert("LPR".into(), "40".into());
        t.iso.insert("HOLDER_D".into(), "32".into());
        t
    }

    fn program() -> Program {
        parse_program(SRC, ReadOptions::default())
            .expect("reads")
            .program
    }

    #[test]
    fn the_library_gives_geometry_corrected_by_its_deltas_and_props() {
        let mut p = program();
        let got = apply(&mut p, &lib(ball(3))).expect("served");
        let op = p
            .operations
            .iter()
            .position(|o| o.moves.iter().any(|m| m.is_cutting()))
            .expect("a cutting operation");
        let c = p.operations[op].tool.as_ref().and_then(|t| t.cutter);
        let c = c.expect("cutter");
        assert!((c.d - 9.98).abs() < 1e-12, "R + DR: {}", c.d);
        assert!((c.r - 4.99).abs() < 1e-12, "a ball: corner radius R");
        let t = got[op].expect("library tool");
        assert_eq!((t.flutes, t.helix_deg), (Some(4), Some(35.0)));
        assert_eq!(t.holder, Some((16.0, 40.0)));
    }

    #[test]
    fn a_tool_the_library_lacks_is_an_error_at_its_call() {
        let mut p = program();
        let e = apply(&mut p, &lib(ball(4))).expect_err("T3 missing");
        assert_eq!(e.line, 2, "the T3 M6 line");
        assert!(e.message.contains("tool 3"), "{}", e.message);
    }

    #[test]
    fn a_locked_or_worn_out_tool_is_refused_before_any_work() {
        let mut t = ball(3);
        t.locked = true;
        let mut l = lib(t);
        l.last_decision.insert(3, "worn".into());
        let e = apply(&mut program(), &l).expect_err("locked");
        assert!(
            e.message.contains("locked") && e.message.contains("worn"),
            "{}",
            e.message
        );
        let mut t = ball(3);
        t.life_min = Some(30.0);
        t.used_min = 31.0;
        let e = apply(&mut program(), &lib(t)).expect_err("worn out");
        assert!(e.message.contains("worn out"), "{}", e.message);
    }
}
