//! `millplan demo`: the whole flow on a bundled, generated example. A
//! 60 × 60 mm free-form part and a 10 mm ball-end finishing raster over it;
//! the raster at 0°, 45° and 90° for `directions`; the machine file; the
//! program for each supported control; and constant-cutting-speed spindle
//! control at the paper's test conditions (`command_defaults::cutting`):
//! the controlled program, its per-point table and its report.

use crate::command_defaults::cutting;
use millplan_geom::analytic::{tessellate, DemoSurface};
use millplan_nc::generate::{raster, Raster};
use millplan_nc::write::{write_program, Target, WriteOptions};
use millplan_nc::Program;
use millplan_plan::machine::Machine;
use millplan_plan::speed::{apply, SpeedParams, SpeedResult, Summary};
use serde::Serialize;
use std::fmt::Write as _;

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

/// The demo's files (name in the folder, bytes) and what they show.
pub struct Demo {
    pub files: Vec<(String, Vec<u8>)>,
    pub triangles: usize,
    /// The finishing raster.
    pub program: Program,
    /// What spindle control did on it.
    pub summary: Summary,
    /// Cutting length, mm.
    pub cutting_mm: f64,
    /// The time estimate with acceleration on the default machine, s.
    pub time_s: f64,
    /// The time at programmed feeds, s.
    pub time_nominal_s: f64,
}

/// An internal failure (the generated example did not write or control).
fn internal(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// A program as APT/CL.
fn apt(program: &Program) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    millplan_nc::write::apt::write_apt(program, WriteOptions::new(Target::Apt), &mut out)
        .map_err(internal)?;
    Ok(out)
}

/// Makes every file of the demo, in memory.
pub fn make() -> Result<Demo, String> {
    let surface = DemoSurface::default();
    let mesh = tessellate(&surface, 0.5);
    let mut stl = Vec::new();
    millplan_geom::stl::write_binary_stl(&mesh, "millplan demo free-form part", &mut stl);
    let (program, _) = raster(&surface, &Raster::default());
    let mut files = vec![("part.stl".to_string(), stl)];
    files.push(("finish.apt".into(), apt(&program)?));
    for (t, name) in [
        (Target::Fanuc, "finish_fanuc.nc"),
        (Target::Sinumerik, "finish_sinumerik.mpf"),
        (Target::Heidenhain, "finish_heidenhain.h"),
        (Target::LinuxCnc, "finish_linuxcnc.ngc"),
    ] {
        let (out, _) = write_program(&program, WriteOptions::new(t)).map_err(internal)?;
        files.push((name.into(), out));
    }
    for angle in [0, 45, 90] {
        let r = Raster {
            angle_deg: angle as f64,
            ..Raster::default()
        };
        files.push((format!("raster_{angle}.apt"), apt(&raster(&surface, &r).0)?));
    }
    let machine = Machine::from_toml(MACHINE_TOML).map_err(internal)?;
    files.push(("machine.toml".into(), MACHINE_TOML.as_bytes().to_vec()));
    // Spindle control on the same part and path.
    let params = SpeedParams::new(cutting::VC, cutting::FZ, cutting::FLUTES, cutting::AP);
    let res = apply(&program, &mesh, &machine, &params).map_err(internal)?;
    let (controlled, _) =
        write_program(&res.program, WriteOptions::new(Target::Fanuc)).map_err(internal)?;
    files.push(("finish_constant_vc_fanuc.nc".into(), controlled));
    let csv = millplan_report::table::points_csv(&res.rows);
    files.push(("points.csv".into(), csv.into_bytes()));
    files.push((
        "report.html".into(),
        report(&program, &mesh, &machine, &res),
    ));
    let default = Machine::default();
    let s = millplan_nc::stats::summarize(&program, default.rapid);
    let time_s = millplan_plan::timing::estimate_program(&program, &default).total_s;
    Ok(Demo {
        files,
        triangles: mesh.len(),
        summary: res.summary,
        cutting_mm: s.cutting_mm,
        time_s,
        time_nominal_s: s.time_s,
        program,
    })
}

/// The spindle-control report of the demo, with its inputs, findings and
/// cycle times.
fn report(
    program: &Program,
    mesh: &millplan_geom::TriMesh,
    machine: &Machine,
    res: &SpeedResult,
) -> Vec<u8> {
    let findings: Vec<_> = [
        millplan_plan::checks::mesh(mesh),
        millplan_plan::checks::off_surface(&res.summary),
    ]
    .into_iter()
    .flatten()
    .collect();
    let cut = crate::speed::Cutting {
        vc: cutting::VC,
        fz: cutting::FZ,
        flutes: cutting::FLUTES,
        ap: cutting::AP,
    };
    let inputs = crate::speed::report_inputs(
        ("finish.apt".into(), &res.program),
        "part.stl".into(),
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

/// One file written, for `--json`.
#[derive(Serialize)]
pub struct FileJson {
    pub path: String,
    pub bytes: usize,
}

/// What spindle control did, for `--json`: each range as `[min, max]`.
#[derive(Serialize)]
pub struct SpindleControlJson {
    pub d_w_mm: [f64; 2],
    pub spindle_rpm: [f64; 2],
    pub vc_controlled_m_min: [f64; 2],
    pub vc_constant_m_min: [f64; 2],
    pub constant_spindle_rpm: f64,
}

/// What `millplan demo --json` prints.
#[derive(Serialize)]
pub struct DemoJson {
    pub folder: String,
    pub triangles: usize,
    pub points: usize,
    pub cutting_mm: f64,
    pub time_s: f64,
    pub time_nominal_s: f64,
    pub files: Vec<FileJson>,
    pub spindle_control: SpindleControlJson,
}

impl Demo {
    /// What `millplan demo` prints without `--json`: the files `written`
    /// (path and size) into `folder` and what ran, or with `quiet` one line.
    pub fn text(
        &self,
        folder: &std::path::Path,
        written: &[(String, usize)],
        quiet: bool,
    ) -> String {
        let report = folder.join("report.html").display().to_string();
        if quiet {
            return format!(
                "millplan demo: {} files in {}; open {report} for the plots\n",
                written.len(),
                folder.display(),
            );
        }
        let mut t = format!(
            "millplan demo: free-form part {} triangles, ball D10 raster {} points\n",
            self.triangles,
            self.program.move_count()
        );
        let _ = writeln!(
                t,
                "  cutting length {:.0} mm, time {:.0} s estimated with acceleration ({:.0} s at programmed feeds)",
                self.cutting_mm, self.time_s, self.time_nominal_s
            );
        for (path, bytes) in written {
            let _ = writeln!(t, "  wrote {path} ({bytes} bytes)");
        }
        t.push_str("  part.stl is an open surface by design (the part's top, no sides or bottom): the other commands note its open border as note[open-mesh]; expected here\n");
        let r = &self.summary;
        let _ = writeln!(
                t,
                "spindle control: D_w {:.2}…{:.2} mm, n {:.0}…{:.0} 1/min; vc {:.1}…{:.1} m/min with control vs {:.1}…{:.1} at a constant {:.0} 1/min",
                r.d_w.min, r.d_w.max, r.spindle.min, r.spindle.max, r.vc_controlled.min, r.vc_controlled.max, r.vc_constant.min, r.vc_constant.max, r.constant_spindle
            );
        let _ = writeln!(t, "open {report} in a browser for the plots");
        t
    }

    /// The summary for `--json`, the files as written into `folder`
    /// (`paths`, in the order of [`Demo::files`]).
    pub fn json(&self, folder: String, paths: &[String]) -> DemoJson {
        let r = &self.summary;
        let files = paths.iter().zip(&self.files);
        DemoJson {
            folder,
            triangles: self.triangles,
            points: self.program.move_count(),
            cutting_mm: self.cutting_mm,
            time_s: self.time_s,
            time_nominal_s: self.time_nominal_s,
            files: files
                .map(|(p, (_, b))| FileJson {
                    path: p.clone(),
                    bytes: b.len(),
                })
                .collect(),
            spindle_control: SpindleControlJson {
                d_w_mm: [r.d_w.min, r.d_w.max],
                spindle_rpm: [r.spindle.min, r.spindle.max],
                vc_controlled_m_min: [r.vc_controlled.min, r.vc_controlled.max],
                vc_constant_m_min: [r.vc_constant.min, r.vc_constant.max],
                constant_spindle_rpm: r.constant_spindle,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every file of README's tour is made, each readable as what it is,
    /// and spindle control kept the cutting speed nearer its target than
    /// the constant spindle speed did.
    #[test]
    fn the_demo_makes_every_file() {
        let d = make().expect("demo");
        let names: Vec<&str> = d.files.iter().map(|(n, _)| n.as_str()).collect();
        for n in [
            "part.stl",
            "finish.apt",
            "raster_45.apt",
            "machine.toml",
            "report.html",
        ] {
            assert!(names.contains(&n), "{n} in {names:?}");
        }
        assert_eq!(d.files.len(), 13);
        let stl = &d.files[0].1;
        assert!(millplan_geom::stl::is_stl(stl.len() as u64, stl));
        assert_eq!(d.triangles, (stl.len() - 84) / 50);
        assert!(d.time_s >= d.time_nominal_s && d.cutting_mm > 0.0);
        let r = &d.summary;
        let spread = |s: &millplan_plan::speed::Stats| s.max - s.min;
        assert!(spread(&r.vc_controlled) < spread(&r.vc_constant), "{r:?}");
        let j = d.json("out".into(), &["out/part.stl".into()]);
        assert_eq!(j.files.len(), 1);
        assert_eq!(j.files[0].bytes, stl.len());
    }
}
