//! `millplan force`: the loads along a program (the preparation is
//! [`crate::feed`]'s), the calibration of the edge-force coefficients from
//! measured slot forces, and the list of named materials.

use crate::check::{arg, Range};
use crate::feed::{load_warnings, meets_stock, no_contact, quantities, summary_rows, Prepared};
use millplan_models::force::coeffs::{calibrate_slot, Calibration, Line, SlotTest};
use millplan_models::force::materials::Materials;
use millplan_plan::force::{FeedLimits, ForceRun, Maxima, MoveForces, Steps};
use millplan_report::html::Verdict;
use serde::Serialize;
use std::fmt::Write as _;

/// The line of the move with the largest load of each kind.
#[derive(Serialize)]
pub struct MaxLines {
    pub fxy: u32,
    pub torque: u32,
    pub power: u32,
    pub deflection: u32,
}

/// What `force PATH --json` prints.
#[derive(Serialize)]
pub struct ForceSummary {
    pub moves: usize,
    pub cutting_moves: usize,
    pub air_moves: usize,
    pub unmodelled_moves: usize,
    pub skipped_moves: usize,
    pub evaluations: usize,
    pub time_s: f64,
    pub max: Maxima,
    pub max_lines: MaxLines,
    pub over_limit: usize,
    pub over_limit_lines: Vec<u32>,
    pub within_tolerance: usize,
    pub limit_tolerance: f64,
    pub stock: String,
    /// A cutting move meets the stock (else nothing to act on).
    pub stock_contact: bool,
    pub steps: Steps,
    /// The verdict by the one rule: red when a move is over a limit, amber
    /// on a warning (loads missing), green otherwise.
    pub verdict: Verdict,
}

impl ForceSummary {
    /// The summary of `run` over the prepared program against `limits`.
    pub fn new(p: &Prepared, run: &ForceRun, limits: &FeedLimits) -> ForceSummary {
        let over = run.over_limits(limits, &p.machine);
        let worst = |f: fn(&MoveForces) -> f64| {
            run.moves
                .iter()
                .max_by(|a, b| f(a).total_cmp(&f(b)))
                .map_or(0, |x| x.line)
        };
        let unmodelled = run.moves.iter().filter(|x| x.unmodelled).count();
        let over_lines: Vec<u32> = over.iter().take(20).map(|x| x.line).collect();
        let mut e = millplan_report::forces::force_evidence(over.len() as u64);
        let skipped = (run.skipped, run.skipped_line);
        let mut warnings = load_warnings(over.len(), &over_lines, unmodelled, skipped);
        let stock_contact = meets_stock(run);
        if !stock_contact {
            e.kept = true;
            warnings.push(no_contact(&p.stock_name));
        }
        let verdict = Verdict::of(&e, warnings);
        ForceSummary {
            moves: run.moves.len(),
            cutting_moves: run.moves.iter().filter(|x| !x.rapid).count(),
            air_moves: run.moves.iter().filter(|x| x.air).count(),
            unmodelled_moves: unmodelled,
            skipped_moves: run.skipped,
            evaluations: run.evaluated,
            time_s: run.moves.last().map_or(0.0, |x| x.t_start_s + x.seconds),
            max: run.maxima(),
            max_lines: MaxLines {
                fxy: worst(|x| x.fxy_max),
                torque: worst(|x| x.torque_max),
                power: worst(|x| x.power_w),
                deflection: worst(|x| x.deflection_mm),
            },
            over_limit: over.len(),
            over_limit_lines: over_lines,
            within_tolerance: run.within_tolerance(limits, &p.machine).len(),
            limit_tolerance: millplan_plan::force::LIMIT_TOLERANCE,
            stock: p.stock_name.clone(),
            stock_contact,
            steps: run.steps(&p.setup.grid),
            verdict,
        }
    }

    /// Whether the run found problems (exit 3): a move over a limit, or no
    /// cutting move that meets the stock.
    pub fn findings(&self) -> bool {
        self.over_limit > 0 || !self.stock_contact
    }

    /// The force report's warnings and verdict.
    pub fn notes(&self, inputs: Vec<(String, String)>) -> millplan_report::html::Notes {
        let (m, l) = (&self.max, &self.max_lines);
        millplan_report::html::Notes::of_verdict(
            inputs,
            &self.verdict,
            vec![format!(
                "Largest loads: F_xy {:.1} N (line {}), torque {:.1} N·mm (line {}), power {:.1} W (line {}), tip deflection {:.4} mm (line {}), over {:.1} s of program.",
                m.fxy, l.fxy, m.torque, l.torque, m.power, l.power, m.deflection, l.deflection, self.time_s
            )],
        )
    }

    /// The moves over a limit at their lines of `path` (the first 20), then
    /// the counts and the largest loads.
    pub fn render_text(&self, path: &str, over: &[&MoveForces]) -> String {
        let mut o = String::new();
        for x in over.iter().take(20) {
            let _ = writeln!(
                o,
                "{path}:{}: over a limit: F_xy {:.1} N, T {:.1} N·mm, P {:.1} W, δ {:.4} mm",
                x.line, x.fxy_max, x.torque_max, x.power_w, x.deflection_mm
            );
        }
        let _ = writeln!(
            o,
            "{} moves ({} cutting, {} in air, {} not modelled), {:.1} s",
            self.moves, self.cutting_moves, self.air_moves, self.unmodelled_moves, self.time_s
        );
        let (m, l) = (&self.max, &self.max_lines);
        let _ = writeln!(
            o,
            "F_xy,max {:.1} N (line {}), T_max {:.1} N·mm (line {}), power {:.1} W (line {})",
            m.fxy, l.fxy, m.torque, l.torque, m.power, l.power
        );
        let _ = writeln!(
            o,
            "stress {:.1} MPa, deflection {:.4} mm (line {})",
            m.stress, m.deflection, l.deflection
        );
        if !over.is_empty() {
            let _ = writeln!(o, "{} moves over a limit", over.len());
        }
        o.push_str(&self.verdict.text());
        o
    }
}

/// The force report of the program at `path`: its loads against time, the
/// limits drawn.
pub fn report(
    path: &str,
    inputs: Vec<(String, String)>,
    summary: &ForceSummary,
    run: &ForceRun,
    limits: &FeedLimits,
    p: &Prepared,
) -> String {
    millplan_report::forces::report(
        &format!("millplan force: {path}"),
        "Per move, the largest load of its strokes against the time the move starts; the black line is the limit at the move's spindle speed.",
        &summary.notes(inputs),
        &summary_rows(summary),
        &[("program", &run.moves)],
        &quantities(limits, &p.machine),
    )
}

/// The slot tests of a CSV (`name` the file in errors): a header naming the
/// columns feed, fx, fy and fz, then numbers; `#` starts a comment line.
pub fn parse_tests(text: &str, name: &str) -> Result<Vec<SlotTest>, String> {
    let at = |line: usize, why: &str| format!("{name}:{line}: {why}");
    let mut cols: Option<[usize; 4]> = None;
    let mut tests = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = line.split([',', ';', '\t']).map(str::trim).collect();
        let Some(c) = cols else {
            let find = |n: &str| cells.iter().position(|x| x.eq_ignore_ascii_case(n));
            let (Some(f), Some(x), Some(y), Some(z)) =
                (find("feed"), find("fx"), find("fy"), find("fz"))
            else {
                return Err(at(
                    i + 1,
                    "the header must name the columns feed, fx, fy and fz",
                ));
            };
            cols = Some([f, x, y, z]);
            continue;
        };
        let num = |k: usize| -> Result<f64, String> {
            let s = cells.get(c[k]).copied().unwrap_or("");
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| at(i + 1, &format!("`{s}` is not a number")))
        };
        let t = SlotTest {
            c: num(0)?,
            fx: num(1)?,
            fy: num(2)?,
            fz: num(3)?,
        };
        if !(t.c > 0.0 && t.c < 10.0) {
            return Err(at(
                i + 1,
                "the feed per tooth must be above 0 and under 10 mm",
            ));
        }
        tests.push(t);
    }
    Ok(tests)
}

/// The options of `force calibrate` in their ranges.
pub fn check_calibration(flutes: usize, ap: f64) -> Result<(), String> {
    if !(1..=64).contains(&flutes) {
        return Err(format!("--flutes {flutes}: must be from 1 to 64"));
    }
    arg("--ap", ap, Range::positive(1000.0, "mm"))?;
    Ok(())
}

/// One fitted line of a calibration.
#[derive(Serialize)]
pub struct LineJson {
    pub slope: f64,
    pub intercept: f64,
    pub r2: f64,
}

impl From<&Line> for LineJson {
    fn from(l: &Line) -> Self {
        LineJson {
            slope: l.slope,
            intercept: l.intercept,
            r2: l.r2,
        }
    }
}

/// What `force calibrate --json` prints.
#[derive(Serialize)]
pub struct CalibrationJson {
    pub ktc: f64,
    pub krc: f64,
    pub kac: f64,
    pub kte: f64,
    pub kre: f64,
    pub kae: f64,
    pub fit_x: LineJson,
    pub fit_y: LineJson,
    pub fit_z: LineJson,
    pub tests: usize,
}

/// The calibration of `tests` (slot tests of a cutter with `flutes` at axial
/// depth `ap`), `name` the measurements' file in errors.
pub fn calibrate(
    tests: &[SlotTest],
    flutes: usize,
    ap: f64,
    name: &str,
) -> Result<Calibration, String> {
    calibrate_slot(tests, flutes, ap).map_err(|e| format!("{name}: {e}"))
}

impl CalibrationJson {
    pub fn new(c: &Calibration, tests: usize) -> Self {
        let [ktc, krc, kac] = c.coeffs.kc;
        let [kte, kre, kae] = c.coeffs.ke;
        CalibrationJson {
            ktc,
            krc,
            kac,
            kte,
            kre,
            kae,
            fit_x: (&c.fit_x).into(),
            fit_y: (&c.fit_y).into(),
            fit_z: (&c.fit_z).into(),
            tests,
        }
    }
}

/// The calibration in words, ending with the entry for a materials file
/// named `name`; `n` the number of slot tests.
pub fn calibration_text(c: &Calibration, name: &str, n: usize) -> String {
    let [ktc, krc, kac] = c.coeffs.kc;
    let [kte, kre, kae] = c.coeffs.ke;
    let mut o = String::new();
    let _ = writeln!(o, "{n} slot tests");
    let _ = writeln!(
        o,
        "Ktc {ktc:10.2} N/mm²   Kte {kte:8.3} N/mm   (from Fy, R² {:.5})",
        c.fit_y.r2
    );
    let _ = writeln!(
        o,
        "Krc {krc:10.2} N/mm²   Kre {kre:8.3} N/mm   (from Fx, R² {:.5})",
        c.fit_x.r2
    );
    let _ = writeln!(
        o,
        "Kac {kac:10.2} N/mm²   Kae {kae:8.3} N/mm   (from Fz, R² {:.5})",
        c.fit_z.r2
    );
    let _ = writeln!(o);
    let _ = writeln!(o, "# for a materials file (--materials):");
    let _ = writeln!(
        o,
        "[{name}]\nmodel = \"linear\"\nnote = \"calibrated from {n} slot tests\""
    );
    let _ = writeln!(
        o,
        "kc = [{ktc:.3}, {krc:.3}, {kac:.3}]\nke = [{kte:.4}, {kre:.4}, {kae:.4}]"
    );
    o
}

/// One named material as `force materials --json` lists it.
#[derive(Serialize)]
pub struct MaterialJson<'a> {
    pub name: &'a str,
    pub note: &'a str,
    pub fz_max: Option<&'a [[f64; 2]]>,
    pub fz_note: &'a str,
}

/// The named materials, in name order.
pub fn material_list(m: &Materials) -> Vec<MaterialJson<'_>> {
    m.by_name
        .values()
        .map(|x| MaterialJson {
            name: &x.name,
            note: &x.note,
            fz_max: x.chip_loads.as_ref().map(|c| c.rows()),
            fz_note: &x.fz_note,
        })
        .collect()
}

/// The named materials in words, one a line.
pub fn material_text(m: &Materials) -> String {
    let mut o = String::new();
    for x in m.by_name.values() {
        let _ = writeln!(o, "{:<12} {}", x.name, x.note);
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slot_tests_read_by_their_header_and_refused_at_their_line() {
        let text = "# slot tests\nnote;FZ;Fy;feed;fx\nx;-1;2;0.1;-3\n\nx;-4;5;0.2;-6\n";
        let t = parse_tests(text, "s.csv").expect("reads");
        assert_eq!(t.len(), 2);
        assert_eq!((t[1].c, t[1].fx, t[1].fy, t[1].fz), (0.2, -6.0, 5.0, -4.0));
        let bad = parse_tests("feed,fx,fy,fz\n0.1,1,2,3\n0.1,1,x,3\n", "s.csv");
        assert_eq!(bad.err().as_deref(), Some("s.csv:3: `x` is not a number"));
        let no_header = parse_tests("feed,fx,fy\n", "s.csv");
        assert!(no_header.is_err_and(|e| e.starts_with("s.csv:1: the header")));
        let fz = parse_tests("feed,fx,fy,fz\n12,1,2,3\n", "s.csv");
        assert!(fz.is_err_and(|e| e.starts_with("s.csv:2: the feed per tooth")));
    }
}
