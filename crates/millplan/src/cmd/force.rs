//! `millplan force …`: the force model's data: calibration of coefficients
//! from measured slot forces, and the named materials.

use crate::cmd::cut::load_materials;
use crate::cmd::{arg, Range};
use crate::error::{CliError, CliResult, EXIT_OK};
use millplan_models::force::coeffs::{calibrate_slot, Calibration, Line, SlotTest};
use millplan_models::force::materials::Materials;
use serde_json::json;
use std::path::{Path, PathBuf};

/// Cutting-force model data: calibrate coefficients, list materials.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    pub command: Sub,
}

#[derive(clap::Subcommand)]
pub enum Sub {
    Calibrate(CalibrateArgs),
    Materials(MaterialsArgs),
}

/// Mechanistic calibration (spec process-models.md §1.5b): fits the six
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
    match a.command {
        Sub::Calibrate(c) => calibrate(c),
        Sub::Materials(m) => list(&load_materials(m.materials.as_deref())?, m.json),
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
        outln!(
            "{}",
            serde_json::to_string_pretty(&cal_json(&cal, tests.len())).unwrap_or_default()
        );
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
            .map(|x| json!({"name": x.name, "note": x.note}))
            .collect();
        outln!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
    } else {
        for x in m.by_name.values() {
            outln!("{:<12} {}", x.name, x.note);
        }
    }
    Ok(EXIT_OK)
}
