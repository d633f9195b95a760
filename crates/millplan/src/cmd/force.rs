//! `millplan force …`: the force model's data: calibration of coefficients
//! from measured slot forces, and the named materials.

use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::read_materials as load_materials;
use millplan_driver::force as lib;
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
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
}

/// Lists the named materials (built in, plus those of --materials).
#[derive(clap::Args)]
pub struct MaterialsArgs {
    /// A TOML file of further materials (same form as the built-in table).
    #[arg(long)]
    pub materials: Option<PathBuf>,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
}

pub fn run(a: Args) -> CliResult<i32> {
    match (a.command, a.path) {
        (Some(Sub::Calibrate(c)), _) => calibrate(c),
        (Some(Sub::Materials(m)), _) => list(&load_materials(m.materials.as_deref())?, m.summary.json),
        (None, Some(path)) => program_forces(&path, &a.model),
        (None, None) => Err(CliError::input(
            "give a program (millplan force PATH --stock SPEC --material M) or a subcommand (calibrate, materials)",
        )),
    }
}

/// `millplan force PATH`: the loads of every move.
fn program_forces(path: &Path, m: &crate::cmd::feed::ModelArgs) -> CliResult<i32> {
    use millplan_driver::feed::Watch as _;
    let watch = crate::progress::Watch::new(path, m.notes.quiet, m.summary.json);
    let mut outputs = m.plan(path, &[])?;
    let limits =
        millplan_driver::feed::force_limits(&crate::limits::loads()).map_err(CliError::input)?;
    watch.lap("arguments, limits and outputs checked");
    let (p, run) = millplan_driver::feed::program_forces(&m.files(path)?, &m.request(), &watch)?;
    let name = path.display().to_string();
    let over = run.over_limits(&limits, &p.machine);
    let summary = lib::ForceSummary::new(&p, &run, &limits);
    if let Some(t) = &m.table {
        outputs.write(t, millplan_driver::feed::loads_csv(&run).as_bytes())?;
    }
    if let Some(r) = &m.report {
        let inputs = m.report_inputs(path, &p, &limits);
        let html = lib::report(&name, inputs, &summary, &run, &limits, &p);
        outputs.write(r, html.as_bytes())?;
    }
    outputs.commit()?;
    watch.lap("outputs written and renamed into place");
    m.summary.print(&summary, |s| s.render_text(&name, &over));
    watch.lap("summary printed");
    watch.print_timings(m.timings.on);
    Ok(crate::error::exit(summary.findings()))
}

fn calibrate(a: CalibrateArgs) -> CliResult<i32> {
    lib::check_calibration(a.flutes, a.ap).map_err(CliError::input)?;
    let name = a.measurements.display().to_string();
    let text = std::fs::read_to_string(&a.measurements)
        .map_err(|e| CliError::input(format!("{name}: cannot read: {e}")))?;
    let tests = lib::parse_tests(&text, &name).map_err(CliError::input)?;
    let cal = lib::calibrate(&tests, a.flutes, a.ap, &name).map_err(CliError::input)?;
    let j = || lib::CalibrationJson::new(&cal, tests.len());
    let text = || lib::calibration_text(&cal, &a.name, tests.len());
    crate::cmd::print_summary(a.summary.json, j, text);
    Ok(EXIT_OK)
}

fn list(m: &millplan_driver::Materials, json: bool) -> CliResult<i32> {
    crate::cmd::print_summary(json, || lib::material_list(m), || lib::material_text(m));
    Ok(EXIT_OK)
}
