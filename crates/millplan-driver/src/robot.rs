//! `millplan robot compensate|place` and optimise's robot pass: the process
//! load along a path from the force model with the stock.
//!
//! The force run gives per move the mean force over a revolution, averaged
//! over the poses the move was loaded at (a pose in air counting zero), in
//! the tool frame of the stock simulation: x the feed normal to the axis,
//! y = z × x, z the axis toward the spindle. That is the robot's feed frame
//! ([`Load`]: along the feed, across it, along the axis), so each move's
//! mean is handed on as it is and the robot model turns it with the path
//! and the placement into its base.

use crate::check::{arg, Range};
use millplan_geom::DVec3;
use millplan_nc::write::krl::{self, KrlFiles};
use millplan_nc::Program;
use millplan_plan::force::ForceRun;
use millplan_robot::machining::{
    self, Compensated, Load, MachiningError, PathLoad, Placed, Placement,
};
use millplan_robot::{Robot, Variant};
use serde::Serialize;
use std::fmt::Write as _;

/// The loads of a force run per move of `program` (the moves of every
/// operation in order, as the strokes index them): each move's mean force;
/// a move the run did not load (a rapid, in air, not simulated) none.
pub fn move_loads(program: &Program, run: &ForceRun) -> PathLoad {
    let moves = program.operations.iter().map(|o| o.moves.len()).sum();
    let mut loads = vec![
        Load {
            feed: 0.0,
            cross: 0.0,
            axial: 0.0,
        };
        moves
    ];
    for m in run.moves.iter().filter(|m| !m.rapid && !m.air) {
        if let Some(l) = loads.get_mut(m.index as usize) {
            let [feed, cross, axial] = m.mean.mean();
            *l = Load { feed, cross, axial };
        }
    }
    PathLoad::PerMove(loads)
}

/// The force model's options of `robot compensate|place --stock` (the
/// others at `force`'s defaults; the grid fixed, as the paper's loads are
/// means over a revolution).
#[derive(Clone, Debug)]
pub struct CouplingRequest {
    pub stock: Option<String>,
    pub material: Option<String>,
    pub tool: Option<String>,
    pub flutes: usize,
    /// Helix angle, degrees.
    pub helix: f64,
    pub spindle: Option<f64>,
    pub resolution: f64,
}

impl CouplingRequest {
    /// The request of the force run.
    pub fn model(&self) -> crate::feed::ModelRequest {
        use crate::command_defaults::feed as d;
        crate::feed::ModelRequest {
            stock: self.stock.clone(),
            material: self.material.clone(),
            tool: self.tool.clone(),
            flutes: self.flutes,
            helix: self.helix,
            stickout: None,
            flute_length: None,
            modulus: d::MODULUS,
            resolution: self.resolution,
            dz: d::DZ,
            dphi: d::DPHI_DEG,
            fixed_grid: true,
            spindle: self.spindle,
        }
    }
}

/// The program of `f` and its load per move from the force model cutting
/// the stock `req` names, as `millplan force` runs it: each move's mean
/// force over a revolution, averaged along the move, zero in air.
pub fn model_load(
    f: &crate::feed::ModelFiles,
    req: &CouplingRequest,
    w: &dyn crate::feed::Watch,
) -> Result<(Program, PathLoad), crate::io::IoError> {
    let (p, run) = crate::feed::program_forces(f, &req.model(), w)?;
    let load = move_loads(&p.program, &run);
    Ok((p.program, load))
}

/// What a run's loads amount to: the moves with a load and the largest
/// mean force of a move, N.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct LoadSummary {
    pub loaded_moves: usize,
    pub max_mean_force_n: f64,
}

impl LoadSummary {
    /// The summary of per-move loads (a fixed load has none: `None`).
    pub fn of(load: &PathLoad) -> Option<LoadSummary> {
        let norm = |l: &Load| (l.feed * l.feed + l.cross * l.cross + l.axial * l.axial).sqrt();
        match load {
            PathLoad::Fixed(_) => None,
            PathLoad::PerMove(v) => Some(LoadSummary {
                loaded_moves: v.iter().filter(|l| norm(l) > 0.0).count(),
                max_mean_force_n: v.iter().map(norm).fold(0.0, f64::max),
            }),
        }
    }
}

/// A machining error at its place in `path`: `path:line:1: …` where it
/// has a line.
pub fn located(path: &str, e: &MachiningError) -> String {
    match e {
        MachiningError::Unreachable { line, .. } | MachiningError::Program { line, .. } => {
            let msg = e.to_string();
            let rest = msg.split_once(": ").map_or(msg.as_str(), |(_, r)| r);
            format!("{path}:{line}:1: {rest}")
        }
        MachiningError::Empty => format!("{path}: {e}"),
    }
}

/// `x` to `digits` significant digits (deflections are small: a fixed
/// number of decimals would lose them).
pub fn sig(x: f64, digits: i32) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(digits - 1 - x.abs().log10().floor() as i32);
    (x * scale).round() / scale
}

/// `names.len()` comma-separated numbers of option `flag`, each checked
/// against `range`; `names` label them in errors (`--joints A6`).
pub fn numbers(flag: &str, text: &str, names: &[&str], range: Range) -> Result<Vec<f64>, String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != names.len() {
        return Err(format!(
            "{flag} {text}: {} numbers separated by commas were expected ({})",
            names.len(),
            names.join(",")
        ));
    }
    parts
        .iter()
        .zip(names)
        .map(|(p, n)| {
            let v: f64 = p
                .parse()
                .map_err(|_| format!("{flag} {n} {p}: not a number"))?;
            arg(&format!("{flag} {n}"), v, range)
        })
        .collect()
}

/// The workpiece frame of `--pose X,Y,Z,RZ` (mm, degrees).
pub fn pose(text: &str) -> Result<Placement, String> {
    let v = numbers(
        "--pose",
        text,
        &["X", "Y", "Z", "RZ"],
        Range::from(-1e5, 1e5, "mm or degrees"),
    )?;
    Ok(Placement {
        x: v[0],
        y: v[1],
        z: v[2],
        rz: v[3].to_radians(),
    })
}

/// The box of `--box X0,Y0,Z0,X1,Y1,Z1` (mm): lower and upper corner.
pub fn place_box(text: &str) -> Result<(DVec3, DVec3), String> {
    let names = ["X0", "Y0", "Z0", "X1", "Y1", "Z1"];
    let b = numbers("--box", text, &names, Range::from(-1e5, 1e5, "mm"))?;
    if !(b[0] < b[3] && b[1] < b[4] && b[2] < b[5]) {
        return Err(format!(
            "--box {text}: each lower corner coordinate must be below the upper"
        ));
    }
    Ok((DVec3::new(b[0], b[1], b[2]), DVec3::new(b[3], b[4], b[5])))
}

/// The fixed load of `--load FEED,CROSS,AXIAL` (N).
pub fn fixed_load(text: &str) -> Result<PathLoad, String> {
    let l = numbers(
        "--load",
        text,
        &["FEED", "CROSS", "AXIAL"],
        Range::from(-1e5, 1e5, "N"),
    )?;
    Ok(PathLoad::Fixed(Load {
        feed: l[0],
        cross: l[1],
        axial: l[2],
    }))
}

/// What `robot deflect --json` prints: the deflection at one pose under a
/// force (N) and moment (N·mm) at the TCP, in the base frame.
#[derive(Clone, Debug, Serialize)]
pub struct DeflectSummary {
    pub robot: String,
    pub joints_deg: [f64; 6],
    pub tcp_mm: [f64; 3],
    pub dp_mm: [f64; 3],
    pub dtheta_deg: [f64; 3],
    pub dp_norm_mm: f64,
}

impl DeflectSummary {
    pub fn new(
        robot: &Robot,
        joints_deg: [f64; 6],
        variant: Variant,
        (force, moment): (DVec3, DVec3),
    ) -> DeflectSummary {
        let q = joints_deg.map(f64::to_radians);
        let d = robot.deflect(&q, variant, force, moment);
        DeflectSummary {
            robot: robot.name.clone(),
            joints_deg,
            tcp_mm: robot.fk(&q).t.to_array().map(|x| sig(x, 9)),
            dp_mm: d.dp.to_array().map(|x| sig(x, 6)),
            dtheta_deg: d.dtheta.to_array().map(|x| sig(x.to_degrees(), 6)),
            dp_norm_mm: sig(d.dp.length(), 6),
        }
    }

    pub fn render_text(&self) -> String {
        let ([tx, ty, tz], [x, y, z], [a, b, c]) = (self.tcp_mm, self.dp_mm, self.dtheta_deg);
        format!(
            "robot  {}\nTCP    {tx:.3} {ty:.3} {tz:.3} mm (base frame)\ndp     {x} {y} {z} mm  (|dp| {} mm)\ndtheta {a} {b} {c} degrees\n",
            self.robot, self.dp_norm_mm
        )
    }
}

/// What `robot compensate --json` prints.
#[derive(Clone, Debug, Serialize)]
pub struct CompensateSummary {
    pub mean_deflection_mm: f64,
    pub max_deflection_mm: f64,
    pub residual_mean_mm: f64,
    pub residual_max_mm: f64,
    /// The tool's turn under the load before compensation, degrees.
    pub mean_rotation_deg: f64,
    pub max_rotation_deg: f64,
    /// The angle between the deflected tool at the commanded points and
    /// the nominal tool, degrees: the turn itself unless `orientation`.
    pub residual_rotation_mean_deg: f64,
    pub residual_rotation_max_deg: f64,
    /// Whether the orientation was corrected (`--orientation`).
    pub orientation: bool,
    pub points: usize,
    pub files: Vec<String>,
    /// With --stock: the moves the force model loaded and the largest mean
    /// force of a move.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub loads: Option<LoadSummary>,
}

impl CompensateSummary {
    pub fn new(c: &Compensated, load: &PathLoad, files: Vec<String>) -> CompensateSummary {
        CompensateSummary {
            mean_deflection_mm: sig(c.mean, 6),
            max_deflection_mm: sig(c.max, 6),
            residual_mean_mm: sig(c.residual_mean, 6),
            residual_max_mm: sig(c.residual_max, 6),
            mean_rotation_deg: sig(c.rot_mean_deg, 6),
            max_rotation_deg: sig(c.rot_max_deg, 6),
            residual_rotation_mean_deg: sig(c.residual_rot_mean_deg, 6),
            residual_rotation_max_deg: sig(c.residual_rot_max_deg, 6),
            orientation: c.orientation,
            points: c.points,
            files,
            loads: LoadSummary::of(load),
        }
    }

    pub fn render_text(&self) -> String {
        let mut o = String::new();
        if let Some(l) = &self.loads {
            let _ = writeln!(
                o,
                "load from the force model: {} moves loaded, largest mean force {:.1} N",
                l.loaded_moves, l.max_mean_force_n
            );
        }
        let _ = writeln!(
            o,
            "deflection before compensation: mean {} mm, max {} mm over {} points",
            self.mean_deflection_mm, self.max_deflection_mm, self.points
        );
        let _ = writeln!(
            o,
            "after compensation (the model against itself): mean {} mm, max {} mm",
            self.residual_mean_mm, self.residual_max_mm
        );
        let _ = writeln!(
            o,
            "tool turned by the load: mean {}°, max {}°; after compensation ({}): mean {}°, max {}°",
            self.mean_rotation_deg,
            self.max_rotation_deg,
            if self.orientation {
                "orientation corrected"
            } else {
                "orientation not corrected"
            },
            self.residual_rotation_mean_deg,
            self.residual_rotation_max_deg
        );
        let _ = writeln!(o, "wrote {}", self.files.join(", "));
        o
    }
}

/// A placement as `robot place --json` prints it (mm, degrees).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct PoseJson {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub rz: f64,
}

/// What `robot place --json` prints.
#[derive(Clone, Debug, Default, Serialize)]
pub struct PlaceSummary {
    pub pose: PoseJson,
    pub mean_deflection_mm: f64,
    pub max_deflection_mm: f64,
    pub feasible: bool,
    pub evaluations: usize,
}

impl PlaceSummary {
    /// The placement found; `None`: nothing in the box is feasible.
    pub fn new(found: Option<&Placed>) -> PlaceSummary {
        let Some(p) = found else {
            return PlaceSummary::default();
        };
        PlaceSummary {
            pose: PoseJson {
                x: sig(p.place.x, 7),
                y: sig(p.place.y, 7),
                z: sig(p.place.z, 7),
                rz: sig(p.place.rz.to_degrees(), 6),
            },
            mean_deflection_mm: sig(p.mean, 6),
            max_deflection_mm: sig(p.max, 6),
            feasible: true,
            evaluations: p.evaluations,
        }
    }

    pub fn render_text(&self) -> String {
        if !self.feasible {
            return "no feasible placement in the box: the robot cannot machine the path anywhere in it\n".into();
        }
        let p = &self.pose;
        format!(
            "placement: X {} Y {} Z {} mm, RZ {} degrees\ndeflection: mean {} mm, max {} mm ({} evaluations)\n",
            p.x, p.y, p.z, p.rz, self.mean_deflection_mm, self.max_deflection_mm, self.evaluations
        )
    }
}

fn vec3(flag: &str, text: &str, names: [&str; 3], range: Range) -> Result<DVec3, String> {
    let v = numbers(flag, text, &names, range)?;
    Ok(DVec3::new(v[0], v[1], v[2]))
}

/// The options of `robot deflect` as given.
#[derive(Clone, Debug)]
pub struct DeflectRequest {
    /// `A1,A2,A3,A4,A5,A6`, degrees.
    pub joints: String,
    /// `FX,FY,FZ`, N, in the base frame.
    pub force: String,
    /// `MX,MY,MZ`, N·m, in the base frame.
    pub moment: Option<String>,
    pub variant: Variant,
}

/// `robot deflect`: every number checked, the deflection at the pose.
pub fn deflect(robot: &Robot, r: &DeflectRequest) -> Result<DeflectSummary, String> {
    let deg = numbers(
        "--joints",
        &r.joints,
        &["A1", "A2", "A3", "A4", "A5", "A6"],
        Range::from(-360.0, 360.0, "degrees"),
    )?;
    let force = vec3(
        "--force",
        &r.force,
        ["FX", "FY", "FZ"],
        Range::from(-1e6, 1e6, "N"),
    )?;
    let moment = match &r.moment {
        Some(m) => {
            vec3(
                "--moment",
                m,
                ["MX", "MY", "MZ"],
                Range::from(-1e5, 1e5, "N·m"),
            )? * 1e3
        }
        None => DVec3::ZERO,
    };
    let joints = [deg[0], deg[1], deg[2], deg[3], deg[4], deg[5]];
    Ok(DeflectSummary::new(
        robot,
        joints,
        r.variant,
        (force, moment),
    ))
}

/// A path on a robot under its load: what `compensate` and `place` work on.
pub struct Process<'a> {
    pub robot: &'a Robot,
    pub variant: Variant,
    pub program: &'a Program,
    pub load: &'a PathLoad,
    /// The program's file, for located errors.
    pub path: &'a str,
}

/// The options of `robot compensate` as given.
#[derive(Clone, Debug)]
pub struct CompensateRequest {
    /// `X,Y,Z,RZ`: the workpiece frame in the robot base (mm, degrees).
    pub pose: String,
    /// Distance between the commanded points, mm.
    pub spacing: f64,
    /// Motions per KRL sub-program; 0: one file.
    pub max_points: usize,
    /// `LIN` per point or SPLINE blocks.
    pub motion: krl::KrlMotion,
    /// Correct the tool's orientation too.
    pub orientation: bool,
}

impl CompensateRequest {
    /// The workpiece frame, the spacing checked: before any work.
    pub fn check(&self) -> Result<Placement, String> {
        let place = pose(&self.pose)?;
        arg("--spacing", self.spacing, Range::from(0.01, 100.0, "mm"))?;
        Ok(place)
    }
}

/// What `robot compensate` writes and prints: the KRL files (the main
/// program first), where each goes (the main at the output, its
/// sub-programs beside it) and the summary.
pub struct Compensation {
    pub files: KrlFiles,
    pub paths: Vec<std::path::PathBuf>,
    pub summary: CompensateSummary,
}

/// `robot compensate`: the path resampled and compensated at `place`,
/// written as KRL named after `output`.
pub fn compensate(
    p: &Process,
    r: &CompensateRequest,
    place: &Placement,
    output: &std::path::Path,
) -> Result<Compensation, String> {
    let c = machining::compensate_program_with(
        p.robot,
        p.variant,
        p.program,
        place,
        p.load,
        r.spacing,
        r.orientation,
    )
    .map_err(|e| located(p.path, &e))?;
    let stem = krl::stem(output);
    let k = machining::krl_program(&stem, &c.runs, place, r.spacing / 2.0);
    let o = krl::KrlOptions {
        name: stem,
        max_points: r.max_points,
        motion: r.motion,
        ..Default::default()
    };
    let files = krl::write(&k, &o);
    krl::check(&k, &files).map_err(|e| format!("{}: {e}; not written", output.display()))?;
    let paths = krl::file_paths(output, &files);
    let names = paths.iter().map(|p| p.display().to_string()).collect();
    let summary = CompensateSummary::new(&c, p.load, names);
    Ok(Compensation {
        files,
        paths,
        summary,
    })
}

/// The options of `robot place` as given.
#[derive(Clone, Debug)]
pub struct PlaceRequest {
    /// `X0,Y0,Z0,X1,Y1,Z1`: the box the workpiece origin may be placed in.
    pub bounds: String,
    pub seed: u64,
    pub restarts: usize,
}

impl PlaceRequest {
    /// The search, its box and restarts checked: before any work.
    pub fn check(&self) -> Result<machining::PlaceSearch, String> {
        let (lo, hi) = place_box(&self.bounds)?;
        arg(
            "--restarts",
            self.restarts as f64,
            Range::from(1.0, 100.0, ""),
        )?;
        Ok(machining::PlaceSearch {
            lo,
            hi,
            settings: millplan_robot::anneal::Settings {
                seed: self.seed,
                restarts: self.restarts,
                ..Default::default()
            },
        })
    }
}

/// `robot place`: the placement in the box with the smallest mean
/// deflection along the path (not feasible: none in the box).
pub fn place(p: &Process, search: &machining::PlaceSearch) -> Result<PlaceSummary, String> {
    let samples = machining::placement_samples(p.program).map_err(|e| located(p.path, &e))?;
    let found = machining::place(p.robot, p.variant, &samples, p.load, search);
    Ok(PlaceSummary::new(found.as_ref()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::feed::{self, ModelRequest};
    use millplan_models::force::materials::Materials;

    /// A slot through a box of EN AW-2007 (the paper's: 12 mm flat end
    /// mill, three straight flutes, a_p 6, f_z 0.08 at 5310 1/min): entered
    /// from air, cut in full from x 10 to 90, left into air.
    const SLOT: &str = "G21 G90 G17\nT1 M6\nS5310 M3\nG0 X-20 Y0 Z5\nG1 Z-6 F1274.4\nG1 X10\nG1 X90\nG1 X130\nG0 Z5\nM30\n";

    fn loads_of(src: &str) -> (Program, ForceRun, PathLoad) {
        let req = ModelRequest {
            stock: Some("box:0,-20,-20,120,20,0".into()),
            material: Some("en-aw-2007".into()),
            tool: Some("flat:12".into()),
            flutes: 3,
            helix: 0.0,
            stickout: None,
            flute_length: None,
            modulus: crate::command_defaults::feed::MODULUS,
            resolution: 0.25,
            dz: crate::command_defaults::feed::DZ,
            dphi: crate::command_defaults::feed::DPHI_DEG,
            fixed_grid: true,
            spindle: None,
        };
        let materials = Materials::builtin();
        let setup = feed::force_setup(&req, &materials).expect("setup");
        let spec = feed::stock_spec(&req).expect("stock");
        let program = millplan_nc::parse_program(src, millplan_nc::ReadOptions::default())
            .expect("reads")
            .program;
        let s = feed::input_strokes(&req, "slot", &program, 10_000.0).expect("strokes");
        let stock =
            crate::simulate::build_stock("slot", 0.25, &spec, &s, (None, None), (1 << 30, 2))
                .expect("stock");
        let machine = millplan_plan::machine::Machine::default();
        let p = feed::Prepared::new(&req, &materials, (program, s, stock), setup, machine)
            .expect("prepared");
        let run = feed::forces(&p, &p.program, &p.strokes, &|_| {}).expect("forces");
        let load = move_loads(&p.program, &run);
        (p.program, run, load)
    }

    /// The load of the move at `line` of the program (the run's moves
    /// index the same list).
    fn at_line(program: &Program, run: &ForceRun, load: &PathLoad, line: u32) -> Load {
        let moves: Vec<_> = program.operations.iter().flat_map(|o| &o.moves).collect();
        let index = moves.iter().position(|m| m.line == line).expect("move");
        if let Some(m) = run.moves.iter().find(|m| m.index as usize == index) {
            assert_eq!(m.line, line);
        }
        let PathLoad::PerMove(v) = load else {
            panic!("per move")
        };
        assert_eq!(v.len(), moves.len());
        v[index]
    }

    /// The full slot's load is the mean force over a revolution of the
    /// closed form (process-models §6 T1a with the EN AW-2007 flute-segment
    /// coefficients of §1.5e: (−95.15, 304.95, 68.00) N along the feed,
    /// across it, along the axis); the plunge through air and the rapids
    /// carry none; entering and leaving the slot carry less.
    #[test]
    fn a_slot_gets_the_closed_form_mean_force_and_air_none() {
        let (program, run, load) = loads_of(SLOT);
        let slot = at_line(&program, &run, &load, 7);
        for (got, want) in [slot.feed, slot.cross, slot.axial]
            .iter()
            .zip([-95.15, 304.95, 68.0])
        {
            assert!((got - want).abs() <= 0.02 * want.abs(), "{slot:?}");
        }
        for line in [4, 5, 9] {
            assert_eq!(
                at_line(&program, &run, &load, line),
                Load {
                    feed: 0.0,
                    cross: 0.0,
                    axial: 0.0
                },
                "line {line}"
            );
        }
        for line in [6, 8] {
            let l = at_line(&program, &run, &load, line);
            assert!(l.cross > 0.0 && l.cross < slot.cross, "line {line}: {l:?}");
        }
        let s = LoadSummary::of(&load).expect("per move");
        assert_eq!(s.loaded_moves, 3);
        assert!((s.max_mean_force_n - 326.6).abs() < 0.02 * 326.6, "{s:?}");
        assert_eq!(LoadSummary::of(&PathLoad::Fixed(slot)), None);
    }

    /// A 100 mm × 50 mm zig-zag at z 0, tool vertical, as APT.
    fn zigzag() -> Program {
        let mut s = String::from("CUTTER/12\nGOTO/0,0,10,0,0,1\nFEDRAT/1200\n");
        for row in 0..3 {
            let y = row as f64 * 25.0;
            let (a, b) = if row % 2 == 0 { (0, 100) } else { (100, 0) };
            s.push_str(&format!("GOTO/{a},{y},0,0,0,1\nGOTO/{b},{y},0,0,0,1\n"));
        }
        millplan_nc::parse_program(&s, millplan_nc::ReadOptions::default())
            .expect("reads")
            .program
    }

    /// `robot deflect` is the model's deflection (Schnoes & Zaeh, Eq. 2)
    /// with the moment in N·m turned into N·mm; a wrong count of numbers
    /// names the option and what it wants.
    #[test]
    fn deflect_checks_its_numbers_and_is_the_model() {
        let robot = Robot::kr240();
        let req = DeflectRequest {
            joints: "0,-90,90,0,30,0".into(),
            force: "0,1000,0".into(),
            moment: Some("0,0,50".into()),
            variant: Variant::ThreeAxis,
        };
        let got = deflect(&robot, &req).expect("deflects");
        let q = [0.0, -90.0, 90.0, 0.0, 30.0, 0.0].map(f64::to_radians);
        let want = robot.deflect(
            &q,
            Variant::ThreeAxis,
            DVec3::new(0.0, 1000.0, 0.0),
            DVec3::new(0.0, 0.0, 50e3),
        );
        for i in 0..3 {
            assert!((got.dp_mm[i] - want.dp[i]).abs() <= 1e-5 * want.dp.length());
        }
        let bad = DeflectRequest {
            joints: "0,-90,90,0,30".into(),
            ..req.clone()
        };
        let e = deflect(&robot, &bad).expect_err("five joints");
        assert!(e.starts_with("--joints") && e.contains("6 numbers"), "{e}");
        let bad = DeflectRequest {
            force: "0,1e7,0".into(),
            ..req
        };
        let e = deflect(&robot, &bad).expect_err("out of range");
        assert!(e.starts_with("--force FY"), "{e}");
    }

    /// `robot compensate`: the main program goes to the output, its
    /// sub-programs beside it, one commanded point per --spacing; the
    /// summary names the files; out of reach is located in the program.
    #[test]
    fn compensate_names_its_files_and_locates_the_unreachable() {
        let (robot, program) = (Robot::kr240(), zigzag());
        let load = fixed_load("-60,150,40").expect("load");
        let p = Process {
            robot: &robot,
            variant: Variant::ThreeAxis,
            program: &program,
            load: &load,
            path: "zz.apt",
        };
        let req = CompensateRequest {
            pose: "1300,-100,300,0".into(),
            spacing: 0.3,
            max_points: 300,
            motion: krl::KrlMotion::Lin,
            orientation: false,
        };
        let place = req.check().expect("pose");
        let out = std::path::Path::new("/tmp/zz.src");
        let c = compensate(&p, &req, &place, out).expect("compensates");
        assert_eq!(c.paths[0], out);
        assert!(c.files.len() > 2, "{} files", c.files.len());
        assert_eq!(c.paths.len(), c.files.len());
        let named: Vec<String> = c.paths.iter().map(|p| p.display().to_string()).collect();
        assert_eq!(c.summary.files, named);
        let back = millplan_nc::krl::read(&c.files[0].1, &mut |n| {
            c.files
                .iter()
                .find(|(f, _)| f.eq_ignore_ascii_case(n))
                .map(|(_, t)| t.clone())
        })
        .expect("reads back");
        let motions = back
            .statements
            .iter()
            .filter(|l| matches!(l.statement, millplan_nc::krl::Statement::Move { .. }))
            .count();
        assert_eq!(motions, c.summary.points);
        assert!(c.summary.points > (250.0_f64 / 0.3) as usize);
        assert!(c.summary.residual_max_mm < c.summary.max_deflection_mm);
        let far = CompensateRequest {
            pose: "5000,0,0,0".into(),
            ..req
        };
        let Err(e) = compensate(&p, &far, &far.check().expect("pose"), out) else {
            panic!("out of reach at X 5000")
        };
        assert!(e.starts_with("zz.apt:"), "{e}");
        let bad = CompensateRequest {
            spacing: 0.0,
            ..far
        };
        assert!(bad.check().expect_err("spacing").starts_with("--spacing"));
    }

    /// `robot place`: seeded, so the same search finds the same
    /// placement; an empty box and no restarts are refused before any work.
    #[test]
    fn place_is_seeded_and_checks_its_box() {
        let (robot, program) = (Robot::kr240(), zigzag());
        let load = fixed_load("-60,150,40").expect("load");
        let p = Process {
            robot: &robot,
            variant: Variant::ThreeAxis,
            program: &program,
            load: &load,
            path: "zz.apt",
        };
        let req = PlaceRequest {
            bounds: crate::command_defaults::robot::PLACE_BOX.into(),
            seed: 7,
            restarts: 1,
        };
        let a = place(&p, &req.check().expect("box")).expect("places");
        let b = place(&p, &req.check().expect("box")).expect("places");
        assert!(a.feasible && a.evaluations > 0);
        assert_eq!(
            (a.pose.x, a.pose.y, a.pose.z),
            (b.pose.x, b.pose.y, b.pose.z)
        );
        let empty = PlaceRequest {
            bounds: "900,0,0,800,1,1".into(),
            ..req.clone()
        };
        assert!(empty.check().expect_err("box").starts_with("--box"));
        let none = PlaceRequest { restarts: 0, ..req };
        assert!(none
            .check()
            .expect_err("restarts")
            .starts_with("--restarts"));
    }
}
