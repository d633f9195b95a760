//! `millplan wd-sweep`: the working diameter over a grid of cases (thesis 1).

use crate::error::{CliError, CliResult, EXIT_OK};
use crate::timings::{Clock, Table as _};
use millplan_driver::sweep::{self as lib, Design};
use std::path::PathBuf;

/// Tabulate and plot the working diameter over tool diameter, depth of cut,
/// stepover, feed direction, inclination and up/down milling — the published
/// study design (D 6-8-10 mm, ap 0.1–1.0 mm, ae 1 mm, A_f 0–180°).
///
/// Writes OUT/wd_sweep.csv (one row per case) and OUT/wd_sweep.html with one SVG
/// plot per tool diameter and milling side; with --fit also reports how well the
/// regression surrogate (a fitted formula for the working diameter) matches the geometric model.
#[derive(clap::Args)]
pub struct Args {
    /// Output folder.
    #[arg(short, long, default_value = "wd-sweep")]
    pub output: PathBuf,
    /// Tool diameters, mm.
    #[arg(long, value_delimiter = ',', default_value = millplan_driver::command_defaults::sweep::D)]
    pub d: Vec<f64>,
    /// Depths of cut, mm.
    #[arg(long, value_delimiter = ',', default_value = millplan_driver::command_defaults::sweep::AP)]
    pub ap: Vec<f64>,
    /// Stepover to the machined neighbour, mm (0 = no neighbour).
    #[arg(long, value_delimiter = ',', default_value = millplan_driver::command_defaults::sweep::AE)]
    pub ae: Vec<f64>,
    /// Inclinations, degrees.
    #[arg(long, value_delimiter = ',', default_value = millplan_driver::command_defaults::sweep::ALPHA)]
    pub alpha: Vec<f64>,
    /// Feed-direction step over 0–180°, degrees.
    #[arg(long, default_value_t = millplan_driver::command_defaults::sweep::AF_STEP)]
    pub af_step: f64,
    /// Also fit the regression surrogate and print R², RMSE and MAPE.
    #[arg(long)]
    pub fit: bool,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    #[command(flatten)]
    pub timings: crate::cmd::args::Timings,
}

pub fn run(a: Args) -> CliResult<i32> {
    let mut clock = Clock::start();
    let design = Design {
        d: a.d,
        ap: a.ap,
        ae: a.ae,
        alpha: a.alpha,
        af_step: a.af_step,
    };
    lib::check(&design).map_err(CliError::input)?;
    std::fs::create_dir_all(&a.output)
        .map_err(|e| CliError::input(format!("{}: {e}", a.output.display())))?;
    clock.lap("design checked, output folder made");
    let fit = a.fit.then(lib::fit);
    if let (Some(f), false) = (&fit, a.summary.json) {
        outln!("{}", lib::SweepSummary::fit_text(f));
    }
    if a.fit {
        clock.lap("surrogate fitted and compared with the model");
    }
    let (csv, html) = lib::files(&design, fit.as_ref());
    clock.lap("working diameter over the design, table and plots");
    let (c, h) = (
        a.output.join("wd_sweep.csv"),
        a.output.join("wd_sweep.html"),
    );
    crate::io::write_all(&[(c.clone(), csv), (h.clone(), html)])?;
    clock.lap("files written and renamed into place");
    let names = (c.display().to_string(), h.display().to_string());
    let summary = lib::SweepSummary::new(names.0, names.1, fit.as_ref());
    a.summary.print(&summary, |s| s.text());
    clock.end(a.timings.on);
    Ok(EXIT_OK)
}
