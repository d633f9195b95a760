//! `millplan force …`: the force model's data: calibration of coefficients
//! from measured slot forces, and the named materials.

use crate::cmd::cut::load_materials;
use crate::cmd::{arg, Range};
use crate::error::{CliError, CliResult, EXIT_OK};
use millplan_models::force::coeffs::{calibrate_slot, Calibration, Line, SlotTest};
use millplan_models::force::materials::Materials;
use serde_json::json;
use std::path::{Path, PathBuf};

/// Cutting forces along a program, and the force model's data.
///
/// `millplan force PATH --stock SPEC --material M`: the program runs stroke
/// by stroke through its stock and every cutting stroke's engagement (the
/// tool at the stroke's end against the material left before it) gives the
/// forces, torque, power, bending stress and tip deflection over a
/// revolution; per move the largest of its strokes. Cutting data from the
/// program: spindle speed, feed, feed per tooth = feed/(n·--flutes). With
/// --limit fxy=…,power=… the moves over a limit are listed (exit 3); the
/// machine's spindle chart limits power and torque at each block's speed.
/// The tool's orientation is the program's tool axis; each stroke's lead
/// (`lead_deg` of the table) is the feed's angle out of the plane normal to
/// the axis, positive when the shank leans toward the feed, the sign of
/// `cut --lead` and `orient` (docs/leadtilt.md). The chip depends on that
/// lead alone, so no tilt is taken.
///
/// `millplan force calibrate` and `millplan force materials` are the model's
/// data; a program file named `calibrate` or `materials` is given as
/// `./calibrate`.
#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct Args {
    #[command(subcommand)]
    pub command: Option<Sub>,
    /// Program (APT/CL or G-code) to simulate.
    pub path: Option<PathBuf>,
    #[command(flatten)]
    pub model: crate::cmd::feed::ModelArgs,
}

#[derive(clap::Subcommand)]
pub enum Sub {
    Calibrate(CalibrateArgs),
    Materials(MaterialsArgs),
}

/// Mechanistic calibration (docs/forces.md): fits the six
/// coefficients of the linear edge-force model to mean slot forces of a flat
/// end mill measured at several feeds, and reports R² of each fit.
///
/// The CSV has a header naming the columns feed (feed per tooth, mm) and fx,
/// fy, fz (mean forces on the tool, N: x along the feed, y as the spindle
/// turns, z toward the shank); other columns are ignored. Lines starting with
/// # are comments.
#[derive(clap::Args)]
pub struct CalibrateArgs {
    /// The measurements (CSV).
    pub measurements: PathBuf,
    /// Number of flutes of the test cutter.
    #[arg(long)]
    pub flutes: usize,
    /// Axial depth of the slot tests, mm.
    #[arg(long)]
    pub ap: f64,
    /// Name for the materials-file entry printed at the end.
    #[arg(long, default_value = "calibrated")]
    pub name: String,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Lists the named materials (built in, plus those of --materials).
#[derive(clap::Args)]
pub struct MaterialsArgs {
    /// A TOML file of further materials.
    #[arg(long)]
    pub materials: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: Args) -> CliResult<i32> {
    match (a.command, a.path) {
        (Some(Sub::Calibrate(c)), _) => calibrate(c),
        (Some(Sub::Materials(m)), _) => list(&load_materials(m.materials.as_deref())?, m.json),
        (None, Some(path)) => program_forces(&path, &a.model),
        (None, None) => Err(CliError::input(
            "give a program (millplan force PATH --stock SPEC --material M) or a subcommand (calibrate, materials)",
        )),
    }
}

/// `millplan force PATH`: the loads of every move.
fn program_forces(path: &Path, m: &crate::cmd::feed::ModelArgs) -> CliResult<i32> {
    use crate::cmd::feed::{
        force_notes, load_limits, prepare, quantities, run_forces, summary_rows,
    };
    let mut inputs: Vec<&Path> = vec![path];
    inputs.extend(m.stl.as_deref());
    inputs.extend(m.machine.as_deref());
    inputs.extend(m.materials.as_deref());
    let blank = m
        .stock
        .as_deref()
        .and_then(millplan_sim::stock::spec::StockSpec::file_of);
    inputs.extend(blank.as_deref());
    let mut outputs = crate::io::Outputs::plan(
        &inputs,
        &[
            ("--table", m.table.as_deref()),
            ("--report", m.report.as_deref()),
        ],
        false,
    )?;
    let limits = load_limits(1.0, 0.0, Some(f64::INFINITY), None)?;
    let p = prepare(path, m)?;
    let run = run_forces(&p, &p.program, &p.strokes, m.quiet || m.json)?;
    crate::cmd::feed::stopped_spindle(path, &run)?;
    let over = run.over_limits(&limits, &p.machine);
    let cutting = run.moves.iter().filter(|x| !x.rapid).count();
    let last = run.moves.last().map_or(0.0, |x| x.t_start_s + x.seconds);
    let worst = |f: fn(&millplan_plan::force::MoveForces) -> f64| {
        run.moves
            .iter()
            .max_by(|a, b| f(a).total_cmp(&f(b)))
            .map_or(0, |x| x.line)
    };
    let summary = json!({
        "moves": run.moves.len(), "cutting_moves": cutting,
        "air_moves": run.moves.iter().filter(|x| x.air).count(),
        "unmodelled_moves": run.moves.iter().filter(|x| x.unmodelled).count(),
        "skipped_moves": run.skipped, "evaluations": run.evaluated, "time_s": last,
        "max": run.maxima(),
        "max_lines": {"fxy": worst(|x| x.fxy_max), "torque": worst(|x| x.torque_max), "power": worst(|x| x.power_w), "deflection": worst(|x| x.deflection_mm)},
        "over_limit": over.len(), "over_limit_lines": over.iter().take(20).map(|x| x.line).collect::<Vec<_>>(),
        "within_tolerance": run.within_tolerance(&limits, &p.machine).len(),
        "limit_tolerance": millplan_plan::force::LIMIT_TOLERANCE,
        "stock": p.stock_name,
        "steps": run.steps(&p.setup.grid),
    });
    if let Some(t) = &m.table {
        outputs.write(t, millplan_report::forces::moves_csv(&run.moves).as_bytes())?;
    }
    if let Some(r) = &m.report {
        let html = millplan_report::forces::report(
            &format!("millplan force: {}", path.display()),
            "Per move, the largest load of its strokes against the time the move starts; the black line is the limit at the move's spindle speed.",
            &force_notes(&summary),
            &summary_rows(&summary),
            &[("program", &run.moves)],
            &quantities(&limits, &p.machine),
        );
        outputs.write(r, html.as_bytes())?;
    }
    outputs.commit()?;
    print_forces(path, m.json, &summary, &over);
    Ok(if over.is_empty() {
        EXIT_OK
    } else {
        crate::error::EXIT_FINDINGS
    })
}

fn print_forces(
    path: &Path,
    json: bool,
    s: &serde_json::Value,
    over: &[&millplan_plan::force::MoveForces],
) {
    if json {
        crate::cmd::print_json(s.clone());
        return;
    }
    for x in over.iter().take(20) {
        outln!(
            "{}:{}: over a limit: F_xy {:.1} N, T {:.1} N·mm, P {:.1} W, δ {:.4} mm",
            path.display(),
            x.line,
            x.fxy_max,
            x.torque_max,
            x.power_w,
            x.deflection_mm
        );
    }
    outln!(
        "{} moves ({} cutting, {} in air, {} not modelled), {:.1} s",
        s["moves"],
        s["cutting_moves"],
        s["air_moves"],
        s["unmodelled_moves"],
        s["time_s"].as_f64().unwrap_or(0.0)
    );
    let mx = &s["max"];
    let l = &s["max_lines"];
    outln!(
        "F_xy,max {:.1} N (line {}), T_max {:.1} N·mm (line {}), power {:.1} W (line {})",
        mx["fxy"].as_f64().unwrap_or(0.0),
        l["fxy"],
        mx["torque"].as_f64().unwrap_or(0.0),
        l["torque"],
        mx["power"].as_f64().unwrap_or(0.0),
        l["power"]
    );
    outln!(
        "stress {:.1} MPa, deflection {:.4} mm (line {})",
        mx["stress"].as_f64().unwrap_or(0.0),
        mx["deflection"].as_f64().unwrap_or(0.0),
        l["deflection"]
    );
    if !over.is_empty() {
        outln!("{} moves over a limit", over.len());
    }
}

fn calibrate(a: CalibrateArgs) -> CliResult<i32> {
    if !(1..=64).contains(&a.flutes) {
        return Err(CliError::input(format!(
            "--flutes {}: must be from 1 to 64",
            a.flutes
        )));
    }
    arg("--ap", a.ap, Range::positive(1000.0, "mm"))?;
    let tests = read_tests(&a.measurements)?;
    let cal = calibrate_slot(&tests, a.flutes, a.ap)
        .map_err(|e| CliError::input(format!("{}: {e}", a.measurements.display())))?;
    if a.json {
        crate::cmd::print_json(cal_json(&cal, tests.len()));
    } else {
        print_cal(&cal, &a.name, tests.len());
    }
    Ok(EXIT_OK)
}

/// Reads the slot tests: a header with feed, fx, fy, fz, then numbers.
pub fn read_tests(path: &Path) -> CliResult<Vec<SlotTest>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::input(format!("{}: cannot read: {e}", path.display())))?;
    let at = |line: usize, why: &str| CliError::input(format!("{}:{line}: {why}", path.display()));
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
        let num = |k: usize| -> CliResult<f64> {
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

fn line_json(l: &Line) -> serde_json::Value {
    json!({"slope": l.slope, "intercept": l.intercept, "r2": l.r2})
}

fn cal_json(c: &Calibration, n: usize) -> serde_json::Value {
    let [ktc, krc, kac] = c.coeffs.kc;
    let [kte, kre, kae] = c.coeffs.ke;
    json!({
        "ktc": ktc, "krc": krc, "kac": kac, "kte": kte, "kre": kre, "kae": kae,
        "fit_x": line_json(&c.fit_x), "fit_y": line_json(&c.fit_y), "fit_z": line_json(&c.fit_z),
        "tests": n,
    })
}

fn print_cal(c: &Calibration, name: &str, n: usize) {
    let [ktc, krc, kac] = c.coeffs.kc;
    let [kte, kre, kae] = c.coeffs.ke;
    outln!("{n} slot tests");
    outln!(
        "Ktc {ktc:10.2} N/mm²   Kte {kte:8.3} N/mm   (from Fy, R² {:.5})",
        c.fit_y.r2
    );
    outln!(
        "Krc {krc:10.2} N/mm²   Kre {kre:8.3} N/mm   (from Fx, R² {:.5})",
        c.fit_x.r2
    );
    outln!(
        "Kac {kac:10.2} N/mm²   Kae {kae:8.3} N/mm   (from Fz, R² {:.5})",
        c.fit_z.r2
    );
    outln!();
    outln!("# for a materials file (--materials):");
    outln!("[{name}]\nmodel = \"linear\"\nnote = \"calibrated from {n} slot tests\"");
    outln!("kc = [{ktc:.3}, {krc:.3}, {kac:.3}]\nke = [{kte:.4}, {kre:.4}, {kae:.4}]");
}
fn list(m: &Materials, json: bool) -> CliResult<i32> {
    if json {
        let v: Vec<_> = m
            .by_name
            .values()
            .map(|x| {
                json!({"name": x.name, "note": x.note,
                    "fz_max": x.chip_loads.as_ref().map(|c| c.rows()), "fz_note": x.fz_note})
            })
            .collect();
        crate::cmd::print_json(serde_json::Value::from(v));
    } else {
        for x in m.by_name.values() {
            outln!("{:<12} {}", x.name, x.note);
        }
    }
    Ok(EXIT_OK)
}
