//! `millplan demo`: the whole flow on a bundled, generated example.

use crate::error::{CliError, CliResult, EXIT_OK};
use millplan_driver::demo::{make, Demo};
use std::path::PathBuf;

/// Run millplan on a bundled example: a 60 × 60 mm free-form part and a 10 mm
/// ball-end finishing raster over it, generated on the spot.
///
/// Writes into the output folder: the part (STL), the raster (APT/CL), the
/// same raster at 0°, 45° and 90° for `directions`, the machine file it runs
/// on, the program for each supported control, and the result of
/// constant-cutting-speed spindle control (vc 63 m/min, fz 0.125 mm, 2 flutes,
/// ap 0.3 mm: the paper's test conditions): the controlled program, its
/// per-point table and its report. Every input of README's tour is among them.
#[derive(clap::Args)]
pub struct Args {
    /// Folder for the demo's outputs (created if missing).
    #[arg(short, long, default_value = "millplan-demo")]
    pub output: PathBuf,
    #[command(flatten)]
    pub summary: crate::cmd::args::SummaryJson,
    /// Print one line (the folder and the report to open) instead of the
    /// summary and every file written.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(a: Args) -> CliResult<i32> {
    std::fs::create_dir_all(&a.output).map_err(|e| {
        CliError::input(format!("{}: cannot create folder: {e}", a.output.display()))
    })?;
    let demo = make().map_err(CliError::internal)?;
    let written: Vec<(PathBuf, Vec<u8>)> = (demo.files.iter())
        .map(|(name, bytes)| (a.output.join(name), bytes.clone()))
        .collect();
    crate::io::write_all(&written)?;
    print_summary(&a, &written, &demo);
    Ok(EXIT_OK)
}

/// What the demo made and where, and what spindle control did on it.
fn print_summary(a: &Args, written: &[(PathBuf, Vec<u8>)], d: &Demo) {
    let paths: Vec<(String, usize)> = written
        .iter()
        .map(|(p, b)| (p.display().to_string(), b.len()))
        .collect();
    let names: Vec<String> = paths.iter().map(|(p, _)| p.clone()).collect();
    let j = || d.json(a.output.display().to_string(), &names);
    crate::cmd::print_summary(a.summary.json, j, || d.text(&a.output, &paths, a.quiet));
}
