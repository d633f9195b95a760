//! `millplan demo`: the whole flow on a bundled, generated example.

use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::Outputs;
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

/// Writes every file, all of them or none.
fn write_all(written: &[(PathBuf, Vec<u8>)]) -> CliResult<()> {
    let named: Vec<(&str, Option<&std::path::Path>)> = written
        .iter()
        .map(|(p, _)| ("-o", Some(p.as_path())))
        .collect();
    let mut outputs = Outputs::plan(&[], &named, false)?;
    for (path, bytes) in written {
        outputs.write(path, bytes)?;
    }
    outputs.commit()
}

pub fn run(a: Args) -> CliResult<i32> {
    std::fs::create_dir_all(&a.output).map_err(|e| {
        CliError::input(format!("{}: cannot create folder: {e}", a.output.display()))
    })?;
    let demo = make().map_err(CliError::internal)?;
    let written: Vec<(PathBuf, Vec<u8>)> = (demo.files.iter())
        .map(|(name, bytes)| (a.output.join(name), bytes.clone()))
        .collect();
    write_all(&written)?;
    print_summary(&a, &written, &demo);
    Ok(EXIT_OK)
}

/// What the demo made and where, and what spindle control did on it.
fn print_summary(a: &Args, written: &[(PathBuf, Vec<u8>)], d: &Demo) {
    if a.summary.json {
        let paths: Vec<String> = written
            .iter()
            .map(|(p, _)| p.display().to_string())
            .collect();
        let j = d.json(a.output.display().to_string(), &paths);
        crate::cmd::print_json(serde_json::to_value(&j).unwrap_or_default());
        return;
    }
    if a.quiet {
        outln!(
            "millplan demo: {} files in {}; open {} for the plots",
            written.len(),
            a.output.display(),
            a.output.join("report.html").display()
        );
        return;
    }
    outln!(
        "millplan demo: free-form part {} triangles, ball D10 raster {} points",
        d.triangles,
        d.program.move_count()
    );
    outln!(
        "  cutting length {:.0} mm, time {:.0} s estimated with acceleration ({:.0} s at programmed feeds)",
        d.cutting_mm,
        d.time_s,
        d.time_nominal_s
    );
    for (path, bytes) in written {
        outln!("  wrote {} ({} bytes)", path.display(), bytes.len());
    }
    outln!(
        "  part.stl is an open surface by design (the part's top, no sides or bottom): the other commands note its open border as note[open-mesh]; expected here"
    );
    let r = &d.summary;
    outln!(
        "spindle control: D_w {:.2}…{:.2} mm, n {:.0}…{:.0} 1/min; vc {:.1}…{:.1} m/min with control vs {:.1}…{:.1} at a constant {:.0} 1/min",
        r.d_w.min, r.d_w.max, r.spindle.min, r.spindle.max, r.vc_controlled.min, r.vc_controlled.max, r.vc_constant.min, r.vc_constant.max, r.constant_spindle
    );
    outln!(
        "open {} in a browser for the plots",
        a.output.join("report.html").display()
    );
}
