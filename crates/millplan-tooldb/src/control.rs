//! Thread-mill active control (paper 002; spec §4.6): what to do after a laser
//! measurement, decided and logged in one transaction.
//!
//! - First measurement: compare with the presetter (Δset). Beyond the setup
//!   tolerance the tool is wrongly assembled or its data is wrong: lock it, write
//!   no offsets, and name a duplicate if one is available. Otherwise the measured
//!   L and R become the table values and DL, DR start at 0.
//! - Inspection: Δ = measured − (value + delta) for length and radius (the worst
//!   tooth when teeth are measured one by one).
//!   - |Δ| ≤ LTOL/RTOL: wear compensation, DL/DR take the deviation.
//!   - beyond the tolerance, up to LBREAK/RBREAK: worn. Lock the tool; switch to
//!     its sister tool when that one is free and has the same effective radius
//!     R + DR, otherwise stop the pallet.
//!   - beyond LBREAK/RBREAK: broken. Lock the tool and the pallet (the thread
//!     just cut is suspect) and switch to the sister tool if possible.

use crate::db::{
    damaged_or_sql, get_tool, latest_presetter, log_event, put_tool_tx, DbError, ToolDb, ToolRecord,
};
use rusqlite::{params, OptionalExtension};
use serde_json::json;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// First measurement on the machine (Q340 = 0).
    First,
    /// Inspection after a job (Q340 = 1).
    Inspection,
}

/// A laser measurement.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Measurement {
    pub tool: u32,
    pub kind: Kind,
    /// Measured length, mm.
    pub l: Option<f64>,
    /// Measured radius, mm.
    pub r: Option<f64>,
    /// Radii of the individual teeth, mm.
    pub per_tooth: Option<Vec<f64>>,
    /// Axial measuring point used (PZ), mm.
    pub pz: Option<f64>,
}

#[derive(Clone, Debug)]
pub struct Settings {
    /// Setup tolerance Δset between presetter and first laser measurement, mm.
    pub dset: f64,
    /// Pallet the tool is working on (locked when a tool breaks).
    pub pallet: Option<String>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            dset: 0.02,
            pallet: None,
        }
    }
}

/// What millplan decided after a measurement.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Decision {
    /// First measurement within Δset of the presetter: measured values written.
    FirstAccepted,
    /// First measurement beyond Δset: tool locked, offsets not written.
    SetupMismatch,
    /// Inspection within the wear tolerance: DL/DR updated.
    WearCompensated,
    /// Inspection beyond the wear tolerance: tool locked.
    Worn,
    /// Inspection beyond the breakage limit: tool (and pallet) locked.
    Broken,
}

impl Decision {
    /// The name as logged and printed (`first-accepted`, `setup-mismatch`,
    /// `wear-compensated`, `worn`, `broken`).
    pub fn as_str(self) -> &'static str {
        match self {
            Decision::FirstAccepted => "first-accepted",
            Decision::SetupMismatch => "setup-mismatch",
            Decision::WearCompensated => "wear-compensated",
            Decision::Worn => "worn",
            Decision::Broken => "broken",
        }
    }

    /// The check found a problem: the tool was locked and may not cut on.
    pub fn is_problem(self) -> bool {
        match self {
            Decision::FirstAccepted | Decision::WearCompensated => false,
            Decision::SetupMismatch | Decision::Worn | Decision::Broken => true,
        }
    }
}

impl std::fmt::Display for Decision {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The decision, as logged and printed.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Outcome {
    pub event_id: i64,
    pub decision: Decision,
    pub reason: String,
    pub tool_locked: bool,
    /// Tool to continue with (the sister or a duplicate), if any.
    pub switch_to: Option<u32>,
    pub pallet_locked: bool,
    pub dl: f64,
    pub dr: f64,
}

fn check_value(name: &str, v: Option<f64>) -> Result<(), DbError> {
    match v {
        Some(x) if !(x.is_finite() && x >= 0.0) => Err(DbError::Invalid(format!(
            "{name} must be a non-negative number, got {x}"
        ))),
        _ => Ok(()),
    }
}

/// Records a measurement and applies the decision logic; everything in one
/// transaction, the decision appended to the event log.
pub fn record(db: &mut ToolDb, m: &Measurement, s: &Settings) -> Result<Outcome, DbError> {
    check_value("measured L", m.l)?;
    check_value("measured R", m.r)?;
    check_value("PZ", m.pz)?;
    if let Some(teeth) = &m.per_tooth {
        if teeth.is_empty() || teeth.iter().any(|t| !(t.is_finite() && *t >= 0.0)) {
            return Err(DbError::Invalid(
                "per-tooth radii must be non-negative numbers".into(),
            ));
        }
    }
    if m.l.is_none() && m.r.is_none() && m.per_tooth.is_none() {
        return Err(DbError::Invalid(
            "a measurement needs L, R or per-tooth radii".into(),
        ));
    }
    if !(s.dset >= 0.0) {
        return Err(DbError::Invalid(
            "the setup tolerance Δset must not be negative".into(),
        ));
    }
    let per_tooth = match &m.per_tooth {
        Some(teeth) => Some(
            serde_json::to_string(teeth)
                .map_err(|e| DbError::Invalid(format!("per-tooth radii: {e}")))?,
        ),
        None => None,
    };
    // The write lock first: what is read below cannot change before the commit.
    let tx = db.transaction()?;
    let presetter = latest_presetter(&tx, m.tool)?;
    let mut t = get_tool(&tx, m.tool)?.ok_or(DbError::UnknownTool(m.tool))?;
    // The radius that matters is the worst (smallest) tooth.
    let r_meas = match (&m.per_tooth, m.r) {
        (Some(teeth), _) => Some(teeth.iter().copied().fold(f64::INFINITY, f64::min)),
        (None, r) => r,
    };
    tx.execute(
        "INSERT INTO measurements (tool, time, kind, l, r, per_tooth, pz) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
        params![
            m.tool,
            crate::db::now(),
            match m.kind {
                Kind::First => "first",
                Kind::Inspection => "inspection",
            },
            m.l,
            r_meas,
            per_tooth,
            m.pz
        ],
    )?;
    let inputs = json!({ "measurement": m, "tool_before": t, "presetter": presetter.map(|(l, r)| json!({"l": l, "r": r})), "dset": s.dset, "pallet": s.pallet });
    let mut out = Outcome {
        event_id: 0,
        decision: Decision::FirstAccepted,
        reason: String::new(),
        tool_locked: t.locked,
        switch_to: None,
        pallet_locked: false,
        dl: t.dl,
        dr: t.dr,
    };
    match m.kind {
        Kind::First => {
            let (lref, rref) = presetter.unwrap_or((t.l, t.r));
            let dl = m.l.map(|l| l - lref).unwrap_or(0.0);
            let dr = r_meas.map(|r| r - rref).unwrap_or(0.0);
            if dl.abs() > s.dset || dr.abs() > s.dset {
                t.locked = true;
                let dup = duplicate(&tx, &t)?;
                out.decision = Decision::SetupMismatch;
                out.reason = format!(
                    "first laser measurement differs from the presetter by ΔL {dl:+.4} / ΔR {dr:+.4} mm, beyond Δset {:.4} mm: \
                     tool locked for checking outside the machine, offsets not written{}",
                    s.dset,
                    match dup {
                        Some(d) => format!("; duplicate tool T{d} available"),
                        None => "; no duplicate tool in the library".into(),
                    }
                );
                out.switch_to = dup;
            } else {
                if let Some(l) = m.l {
                    t.l = l;
                    t.dl = 0.0;
                }
                if let Some(r) = r_meas {
                    t.r = r;
                    t.dr = 0.0;
                }
                t.measured = true;
                out.decision = Decision::FirstAccepted;
                out.reason = format!(
                    "first laser measurement within Δset {:.4} mm of the presetter (ΔL {dl:+.4}, ΔR {dr:+.4}): measured values written, DL and DR reset",
                    s.dset
                );
            }
        }
        Kind::Inspection => {
            if m.l.is_some() && (t.ltol <= 0.0 || t.lbreak <= 0.0)
                || r_meas.is_some() && (t.rtol <= 0.0 || t.rbreak <= 0.0)
            {
                return Err(DbError::Invalid(format!(
                    "tool {} has no wear and breakage tolerances (LTOL/LBREAK, RTOL/RBREAK): set them before inspections",
                    t.number
                )));
            }
            let dl = m.l.map(|l| l - (t.l + t.dl));
            let dr = r_meas.map(|r| r - (t.r + t.dr));
            let level = |d: Option<f64>, tol: f64, brk: f64| match d {
                Some(d) if d.abs() > brk => 2,
                Some(d) if d.abs() > tol => 1,
                _ => 0,
            };
            let status = level(dl, t.ltol, t.lbreak).max(level(dr, t.rtol, t.rbreak));
            let fmt = |d: Option<f64>| d.map(|v| format!("{v:+.4}")).unwrap_or("-".into());
            match status {
                0 => {
                    if let Some(d) = dl {
                        t.dl += d;
                    }
                    if let Some(d) = dr {
                        t.dr += d;
                    }
                    out.decision = Decision::WearCompensated;
                    out.reason = format!(
                        "deviation ΔL {} / ΔR {} mm within LTOL {:.4} / RTOL {:.4}: DL = {:+.4}, DR = {:+.4}",
                        fmt(dl),
                        fmt(dr),
                        t.ltol,
                        t.rtol,
                        t.dl,
                        t.dr
                    );
                }
                1 => {
                    t.locked = true;
                    let sister = free_sister(&tx, &t)?;
                    out.switch_to = sister;
                    out.decision = Decision::Worn;
                    match (sister, &s.pallet) {
                        (Some(n), _) => {
                            out.reason = format!(
                                "deviation ΔL {} / ΔR {} mm beyond the wear tolerance: tool locked, continue with sister tool T{n} (same R + DR)",
                                fmt(dl),
                                fmt(dr)
                            );
                        }
                        (None, pallet) => {
                            if let Some(p) = pallet {
                                lock_pallet(&tx, p)?;
                                out.pallet_locked = true;
                            }
                            out.reason = format!(
                                "deviation ΔL {} / ΔR {} mm beyond the wear tolerance: tool locked; no free sister tool with the same R + DR, \
                                 pallet {} stopped",
                                fmt(dl),
                                fmt(dr),
                                pallet.as_deref().unwrap_or("(not given)")
                            );
                        }
                    }
                }
                _ => {
                    t.locked = true;
                    let sister = free_sister(&tx, &t)?;
                    out.switch_to = sister;
                    if let Some(p) = &s.pallet {
                        lock_pallet(&tx, p)?;
                        out.pallet_locked = true;
                    }
                    out.decision = Decision::Broken;
                    out.reason = format!(
                        "deviation ΔL {} / ΔR {} mm beyond the breakage limit (LBREAK {:.4} / RBREAK {:.4}): tool locked, pallet {} locked \
                         for inspection of the last thread{}",
                        fmt(dl),
                        fmt(dr),
                        t.lbreak,
                        t.rbreak,
                        s.pallet.as_deref().unwrap_or("(not given)"),
                        sister.map(|n| format!(", continue with sister tool T{n}")).unwrap_or_else(|| ", no free sister tool".into())
                    );
                }
            }
        }
    }
    put_tool_tx(&tx, &t)?;
    out.tool_locked = t.locked;
    out.dl = t.dl;
    out.dr = t.dr;
    let outcome = json!({
        "decision": out.decision, "tool_locked": out.tool_locked, "switch_to": out.switch_to,
        "pallet_locked": out.pallet_locked, "dl": out.dl, "dr": out.dr, "l": t.l, "r": t.r
    });
    out.event_id = log_event(
        &tx,
        Some(m.tool),
        out.decision.as_str(),
        &out.reason,
        &inputs,
        &outcome,
    )?;
    tx.commit()?;
    Ok(out)
}

/// The sister tool RT when it is free and has the same effective radius (the
/// control refuses a swap otherwise).
fn free_sister(tx: &rusqlite::Connection, t: &ToolRecord) -> Result<Option<u32>, DbError> {
    let Some(n) = t.sister else { return Ok(None) };
    // A sister tool missing from the library is no sister; one that cannot be
    // read is an error.
    Ok(get_tool(tx, n)?
        .filter(|s| !s.locked && (s.effective_r() - t.effective_r()).abs() <= 0.001)
        .map(|s| s.number))
}

/// A replacement for a wrongly set-up tool: its sister if free, else a free tool
/// of the same name and kind.
fn duplicate(tx: &rusqlite::Connection, t: &ToolRecord) -> Result<Option<u32>, DbError> {
    if let Some(n) = t.sister {
        if let Some(s) = get_tool(tx, n)?.filter(|s| !s.locked) {
            return Ok(Some(s.number));
        }
    }
    let mut st = tx.prepare("SELECT number FROM tools WHERE name = ?1 AND kind = ?2 AND number != ?3 AND locked = 0 ORDER BY number LIMIT 1")?;
    // No row: no duplicate. Any other failure is reported.
    st.query_row(params![t.name, t.kind, t.number], |r| r.get(0))
        .optional()
        .map_err(|e| damaged_or_sql(format!("duplicates of tool {}", t.number), e))
}

fn lock_pallet(tx: &rusqlite::Connection, id: &str) -> Result<(), DbError> {
    tx.execute(
        "INSERT INTO pallets (id, locked) VALUES (?1, 1) ON CONFLICT(id) DO UPDATE SET locked = 1",
        [id],
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lib() -> ToolDb {
        let mut db = ToolDb::memory().expect("db");
        let mut t = ToolRecord::new(5, "thread mill");
        t.kind = "thread-mill".into();
        t.ltol = 0.01;
        t.rtol = 0.01;
        t.lbreak = 0.1;
        t.rbreak = 0.05;
        t.sister = Some(6);
        db.put_tool(&t).expect("put");
        let mut s = t.clone();
        s.number = 6;
        s.sister = None;
        db.put_tool(&s).expect("put");
        db.record_presetter(5, 120.0, 6.9).expect("preset");
        db.record_presetter(6, 120.0, 6.9).expect("preset");
        db
    }

    fn meas(kind: Kind, l: f64, r: f64) -> Measurement {
        Measurement {
            tool: 5,
            kind,
            l: Some(l),
            r: Some(r),
            per_tooth: None,
            pz: Some(0.5),
        }
    }

    #[test]
    fn first_measurement_within_and_beyond_dset() {
        let mut db = lib();
        let o = record(
            &mut db,
            &meas(Kind::First, 120.005, 6.895),
            &Settings::default(),
        )
        .expect("record");
        assert_eq!(o.decision, Decision::FirstAccepted);
        let t = db.tool(5).expect("tool");
        assert_eq!(
            (t.l, t.r, t.dl, t.dr, t.measured, t.locked),
            (120.005, 6.895, 0.0, 0.0, true, false)
        );
        let mut db = lib();
        let o = record(
            &mut db,
            &meas(Kind::First, 120.0, 6.85),
            &Settings::default(),
        )
        .expect("record");
        assert_eq!(
            (o.decision, o.tool_locked, o.switch_to),
            (Decision::SetupMismatch, true, Some(6))
        );
        // Offsets not written.
        assert_eq!(db.tool(5).expect("tool").r, 6.9);
    }

    #[test]
    fn inspection_wear_worn_broken() {
        let mut db = lib();
        record(
            &mut db,
            &meas(Kind::First, 120.0, 6.9),
            &Settings::default(),
        )
        .expect("first");
        let o = record(
            &mut db,
            &meas(Kind::Inspection, 119.996, 6.893),
            &Settings::default(),
        )
        .expect("inspect");
        assert_eq!(o.decision, Decision::WearCompensated);
        assert!((o.dr + 0.007).abs() < 1e-12 && (o.dl + 0.004).abs() < 1e-12);
        // Worn: 0.02 below the compensated radius; the sister has R + DR 6.9 ≠ 6.893: no switch.
        let s = Settings {
            pallet: Some("P7".into()),
            ..Settings::default()
        };
        let o = record(&mut db, &meas(Kind::Inspection, 119.996, 6.873), &s).expect("inspect");
        assert_eq!(
            (o.decision, o.tool_locked, o.switch_to, o.pallet_locked),
            (Decision::Worn, true, None, true)
        );
        // Broken tooth: per-tooth radii, the worst one counts.
        let mut db = lib();
        record(
            &mut db,
            &meas(Kind::First, 120.0, 6.9),
            &Settings::default(),
        )
        .expect("first");
        let m = Measurement {
            per_tooth: Some(vec![6.9, 6.899, 6.7]),
            ..meas(Kind::Inspection, 120.0, 6.9)
        };
        let o = record(
            &mut db,
            &m,
            &Settings {
                pallet: Some("P1".into()),
                ..Settings::default()
            },
        )
        .expect("inspect");
        assert_eq!(
            (o.decision, o.switch_to, o.pallet_locked),
            (Decision::Broken, Some(6), true)
        );
        assert!(db.pallet_locked("P1").expect("pallet"));
        let log = db.events(Some(5)).expect("log");
        assert_eq!(log.len(), 2);
        assert_eq!(log[1].decision, "broken");
        assert_eq!(log[1].inputs["measurement"]["per_tooth"][2], 6.7);
    }

    #[test]
    fn decisions_keep_their_names_and_say_which_are_problems() {
        use Decision::*;
        for (d, name, problem) in [
            (FirstAccepted, "first-accepted", false),
            (SetupMismatch, "setup-mismatch", true),
            (WearCompensated, "wear-compensated", false),
            (Worn, "worn", true),
            (Broken, "broken", true),
        ] {
            assert_eq!(serde_json::to_value(d).expect("json"), json!(name));
            assert_eq!((d.as_str(), d.to_string().as_str()), (name, name));
            assert_eq!(d.is_problem(), problem, "{name}");
        }
    }

    #[test]
    fn bad_measurements_change_nothing() {
        let mut db = lib();
        assert!(matches!(
            record(
                &mut db,
                &Measurement {
                    tool: 99,
                    ..meas(Kind::First, 1.0, 1.0)
                },
                &Settings::default()
            ),
            Err(DbError::UnknownTool(99))
        ));
        assert!(record(&mut db, &meas(Kind::First, -1.0, 1.0), &Settings::default()).is_err());
        let mut t = db.tool(5).expect("tool");
        t.rtol = 0.0;
        db.put_tool(&t).expect("put");
        assert!(record(
            &mut db,
            &meas(Kind::Inspection, 120.0, 6.9),
            &Settings::default()
        )
        .is_err());
        assert_eq!(db.measurement_count().expect("count"), 0);
        assert!(db.events(None).expect("log").is_empty());
    }
}
