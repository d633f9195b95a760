//! `millplan demo`: the whole flow on a bundled, generated example.

use crate::error::{CliError, CliResult, EXIT_OK};
use crate::io::Outputs;
use millplan_driver::command_defaults::cutting;
use millplan_geom::analytic::{tessellate, DemoSurface};
use millplan_nc::generate::{raster, Raster};
use millplan_nc::write::{write_program, Target, WriteOptions};
use millplan_plan::machine::Machine;
use millplan_plan::speed::{apply, SpeedParams};
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
    /// Print a machine-readable summary (JSON) on standard output; errors too,
    /// as JSON on standard error.
    #[arg(long)]
    pub json: bool,
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

/// The demo's machine: a three-axis high-speed machining centre with a Fanuc
/// control, the machine file every `--machine` of README's tour reads.
pub const MACHINE_TOML: &str = r#"# The machine of millplan's demo (examples/machine.toml documents every field).
name = "demo HSC centre, three axes"

[control]
dialect = "fanuc"

[spindle]
min = 500       # 1/min
max = 18000     # 1/min
accel = 6000    # 1/min per second

[feed]
max = 20000     # mm/min
rapid = 15000   # mm/min
"#;

/// The demo raster at 0°, 45° and 90° as APT/CL, each with its file name.
fn direction_rasters(surface: &DemoSurface) -> CliResult<Vec<(String, Vec<u8>)>> {
    let mut files = Vec::new();
    for angle in [0, 45, 90] {
        let r = Raster {
            angle_deg: angle as f64,
            ..Raster::default()
        };
        let (program, _) = raster(surface, &r);
        let mut apt = Vec::new();
        millplan_nc::write::apt::write_apt(&program, WriteOptions::new(Target::Apt), &mut apt)
            .map_err(|e| CliError::internal(e.to_string()))?;
        files.push((format!("raster_{angle}.apt"), apt));
    }
    Ok(files)
}

pub fn run(a: Args) -> CliResult<i32> {
    std::fs::create_dir_all(&a.output).map_err(|e| {
        CliError::input(format!("{}: cannot create folder: {e}", a.output.display()))
    })?;
    let surface = DemoSurface::default();
    let mesh = tessellate(&surface, 0.5);
    let mut stl = Vec::new();
    millplan_geom::stl::write_binary_stl(&mesh, "millplan demo free-form part", &mut stl);
    let (program, _) = raster(&surface, &Raster::default());
    let mut written = vec![(a.output.join("part.stl"), stl)];
    let mut apt = Vec::new();
    millplan_nc::write::apt::write_apt(&program, WriteOptions::new(Target::Apt), &mut apt)
        .map_err(|e| CliError::internal(e.to_string()))?;
    written.push((a.output.join("finish.apt"), apt));
    for (t, name) in [
        (Target::Fanuc, "finish_fanuc.nc"),
        (Target::Sinumerik, "finish_sinumerik.mpf"),
        (Target::Heidenhain, "finish_heidenhain.h"),
        (Target::LinuxCnc, "finish_linuxcnc.ngc"),
    ] {
        let (out, _) = write_program(&program, WriteOptions::new(t))
            .map_err(|e| CliError::internal(e.to_string()))?;
        written.push((a.output.join(name), out));
    }
    for (name, bytes) in direction_rasters(&surface)? {
        written.push((a.output.join(name), bytes));
    }
    let machine =
        Machine::from_toml(MACHINE_TOML).map_err(|e| CliError::internal(e.to_string()))?;
    written.push((
        a.output.join("machine.toml"),
        MACHINE_TOML.as_bytes().to_vec(),
    ));
    // Spindle control on the same part and path.
    let params = SpeedParams::new(cutting::VC, cutting::FZ, cutting::FLUTES, cutting::AP);
    let res =
        apply(&program, &mesh, &machine, &params).map_err(|e| CliError::internal(e.to_string()))?;
    let (controlled, _) = write_program(&res.program, WriteOptions::new(Target::Fanuc))
        .map_err(|e| CliError::internal(e.to_string()))?;
    written.push((a.output.join("finish_constant_vc_fanuc.nc"), controlled));
    written.push((
        a.output.join("points.csv"),
        millplan_report::table::points_csv(&res.rows).into_bytes(),
    ));
    written.push((
        a.output.join("report.html"),
        report(&program, &mesh, &machine, &res),
    ));
    write_all(&written)?;
    print_summary(&a, &written, mesh.len(), &program, &res.summary);
    Ok(EXIT_OK)
}

/// The spindle-control report of the demo, with its inputs, findings and
/// cycle times.
fn report(
    program: &millplan_nc::Program,
    mesh: &millplan_geom::TriMesh,
    machine: &Machine,
    res: &millplan_plan::speed::SpeedResult,
) -> Vec<u8> {
    let findings: Vec<_> = [
        millplan_plan::checks::mesh(mesh),
        millplan_plan::checks::off_surface(&res.summary),
    ]
    .into_iter()
    .flatten()
    .collect();
    let cut = millplan_driver::speed::Cutting {
        vc: cutting::VC,
        fz: cutting::FZ,
        flutes: cutting::FLUTES,
        ap: cutting::AP,
    };
    let inputs = crate::cmd::speed::report_inputs(
        (std::path::Path::new("finish.apt"), &res.program),
        std::path::Path::new("part.stl"),
        machine,
        cut,
        &findings,
        [
            millplan_plan::timing::estimate_program(program, machine).total_s,
            millplan_plan::timing::estimate_program(&res.program, machine).total_s,
        ],
    );
    millplan_report::html::speed_report(
        "millplan demo: constant cutting speed",
        &inputs,
        &res.summary,
        &res.rows,
    )
    .into_bytes()
}

/// The demo's summary as JSON; `times` the estimate with acceleration and
/// the time at programmed feeds.
fn summary_json(
    a: &Args,
    written: &[(PathBuf, Vec<u8>)],
    (triangles, program): (usize, &millplan_nc::Program),
    cutting_mm: f64,
    (time_s, time_nominal_s): (f64, f64),
    r: &millplan_plan::speed::Summary,
) -> serde_json::Value {
    let files: Vec<_> = written
        .iter()
        .map(|(p, b)| serde_json::json!({"path": p.display().to_string(), "bytes": b.len()}))
        .collect();
    serde_json::json!({
        "folder": a.output.display().to_string(),
        "triangles": triangles,
        "points": program.move_count(),
        "cutting_mm": cutting_mm,
        "time_s": time_s,
        "time_nominal_s": time_nominal_s,
        "files": files,
        "spindle_control": {
            "d_w_mm": [r.d_w.min, r.d_w.max],
            "spindle_rpm": [r.spindle.min, r.spindle.max],
            "vc_controlled_m_min": [r.vc_controlled.min, r.vc_controlled.max],
            "vc_constant_m_min": [r.vc_constant.min, r.vc_constant.max],
            "constant_spindle_rpm": r.constant_spindle,
        },
    })
}

/// What the demo made and where, and what spindle control did on it.
fn print_summary(
    a: &Args,
    written: &[(PathBuf, Vec<u8>)],
    triangles: usize,
    program: &millplan_nc::Program,
    r: &millplan_plan::speed::Summary,
) {
    let s =
        millplan_nc::stats::summarize(program, millplan_plan::machine::Machine::default().rapid);
    let est = millplan_plan::timing::estimate_program(
        program,
        &millplan_plan::machine::Machine::default(),
    );
    if a.json {
        let times = (est.total_s, s.time_s);
        crate::cmd::print_json(summary_json(
            a,
            written,
            (triangles, program),
            s.cutting_mm,
            times,
            r,
        ));
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
        triangles,
        program.move_count()
    );
    outln!(
        "  cutting length {:.0} mm, time {:.0} s estimated with acceleration ({:.0} s at programmed feeds)",
        s.cutting_mm,
        est.total_s,
        s.time_s
    );
    for (path, bytes) in written {
        outln!("  wrote {} ({} bytes)", path.display(), bytes.len());
    }
    outln!(
        "  part.stl is an open surface by design (the part's top, no sides or bottom): the other commands note its open border as note[open-mesh]; expected here"
    );
    outln!(
        "spindle control: D_w {:.2}…{:.2} mm, n {:.0}…{:.0} 1/min; vc {:.1}…{:.1} m/min with control vs {:.1}…{:.1} at a constant {:.0} 1/min",
        r.d_w.min, r.d_w.max, r.spindle.min, r.spindle.max, r.vc_controlled.min, r.vc_controlled.max, r.vc_constant.min, r.vc_constant.max, r.constant_spindle
    );
    outln!(
        "open {} in a browser for the plots",
        a.output.join("report.html").display()
    );
}
