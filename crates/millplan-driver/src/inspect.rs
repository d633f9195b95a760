//! What a file holds, as `millplan inspect --json` prints it and the Python
//! package's `inspect` returns it: typed summaries of a program (format,
//! units, tools, moves, bounds, lengths, the time estimate) and of a mesh
//! (triangles, defects, bounds, the unit guess). One place, so every front
//! gives the same keys and numbers.

use millplan_geom::stl::{StlFormat, StlReport};
use millplan_geom::{Aabb, DVec3, TriMesh};
use millplan_nc::ir::{CutterKind, LengthUnit, UnitsOrigin};
use millplan_nc::stats::{summarize, RotaryUse};
use millplan_nc::Program;
use millplan_plan::machine::Machine;
use millplan_plan::timing::{estimate_program_totals, TimeEstimate};
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// A box by its corners; `None` (JSON null) for an empty one.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Bounds {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

impl Bounds {
    pub fn of(b: &Aabb) -> Option<Bounds> {
        (!b.is_empty()).then(|| Bounds {
            min: b.min.to_array(),
            max: b.max.to_array(),
        })
    }
}

/// A tool's cutter, angles in degrees.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CutterSummary {
    pub kind: CutterKind,
    pub d: f64,
    pub r: f64,
    pub e: f64,
    pub f: f64,
    pub alpha_deg: f64,
    pub beta_deg: f64,
    pub h: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ToolSummary {
    pub number: Option<u32>,
    pub name: Option<String>,
    pub cutter: Option<CutterSummary>,
    pub line: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MoveCounts {
    pub rapid: usize,
    pub linear: usize,
    pub arc: usize,
    pub cycle: usize,
    pub total: usize,
    pub five_axis: usize,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Lengths {
    pub cutting: f64,
    pub rapid: f64,
}

/// The controller-aware time estimate: total and nominal, what the total is
/// made of, and how many feed blocks the axes hold back.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TimeSummary {
    pub model: &'static str,
    pub total_s: f64,
    pub nominal_s: f64,
    pub rapid_s: f64,
    pub feed_s: f64,
    pub dwell_s: f64,
    pub overhead: f64,
    pub velocity_limited_blocks: usize,
    pub accel_limited_blocks: usize,
    /// The planner model of the machine file's `[control] planner`.
    pub planner: &'static str,
    /// The time under each path-control mode, in the order they first occur.
    pub by_mode: Vec<millplan_plan::timing::ModeTime>,
}

impl TimeSummary {
    pub fn of(e: &TimeEstimate) -> TimeSummary {
        TimeSummary {
            model: "acceleration",
            total_s: e.total_s,
            nominal_s: e.nominal_s,
            rapid_s: e.rapid_s,
            feed_s: e.feed_s,
            dwell_s: e.dwell_s,
            overhead: e.overhead(),
            velocity_limited_blocks: e.velocity_limited_blocks,
            accel_limited_blocks: e.accel_limited_blocks,
            planner: e.planner,
            by_mode: e.by_mode.clone(),
        }
    }
}

/// What a program holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProgramSummary {
    /// `apt`, `gcode` or `krl` (a KUKA robot program).
    pub format: &'static str,
    pub dialect: &'static str,
    pub name: Option<String>,
    /// `mm` or `inch`: what the source is written in.
    pub units: &'static str,
    pub units_origin: UnitsOrigin,
    pub operations: usize,
    pub tools: Vec<ToolSummary>,
    pub moves: MoveCounts,
    pub bounds: Option<Bounds>,
    pub length_mm: Lengths,
    /// With acceleration on `machine`.
    pub time_s: f64,
    /// At programmed feeds and the rapid rate.
    pub time_nominal_s: f64,
    pub time: TimeSummary,
    pub unknown_moves: usize,
    /// The rotary axes the program moves, by letter.
    pub rotary: BTreeMap<&'static str, RotaryUse>,
    /// How many diagnostics the reader gave.
    pub diagnostics: usize,
}

/// Summarises program `p` (read with `diagnostics` diagnostics) timed on `machine`.
pub fn program(p: &Program, diagnostics: usize, machine: &Machine) -> ProgramSummary {
    // Independent walks of the program, side by side.
    let (s, est) = std::thread::scope(|sc| {
        let est = sc.spawn(|| estimate_program_totals(p, machine));
        let s = summarize(p, machine.rapid);
        let est = est.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
        (s, est)
    });
    let tools = p
        .operations
        .iter()
        .filter_map(|o| o.tool.as_ref())
        .map(|t| ToolSummary {
            number: t.number,
            name: t.name.clone(),
            cutter: t.cutter.map(|c| CutterSummary {
                kind: c.kind,
                d: c.d,
                r: c.r,
                e: c.e,
                f: c.f,
                alpha_deg: c.alpha.to_degrees(),
                beta_deg: c.beta.to_degrees(),
                h: c.h,
            }),
            line: t.line,
        })
        .collect();
    let rotary = ["A", "B", "C"]
        .into_iter()
        .zip(s.rotary)
        .filter_map(|(n, u)| u.map(|u| (n, u)))
        .collect();
    ProgramSummary {
        format: match p.source {
            d if d.is_apt() => "apt",
            millplan_nc::Dialect::Krl => "krl",
            _ => "gcode",
        },
        dialect: p.source.name(),
        name: p.name.clone(),
        units: match p.units.source {
            LengthUnit::Mm => "mm",
            LengthUnit::Inch => "inch",
        },
        units_origin: p.units.origin,
        operations: p.operations.len(),
        tools,
        moves: MoveCounts {
            rapid: s.moves.rapid,
            linear: s.moves.linear,
            arc: s.moves.arc,
            cycle: s.moves.cycle,
            total: p.move_count(),
            five_axis: s.five_axis_moves,
        },
        bounds: Bounds::of(&s.bounds),
        length_mm: Lengths {
            cutting: s.cutting_mm,
            rapid: s.rapid_mm,
        },
        time_s: est.total_s,
        time_nominal_s: s.time_s,
        time: TimeSummary::of(&est),
        unknown_moves: s.unknown_moves,
        rotary,
        diagnostics,
    }
}

/// What an STL holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeshSummary {
    pub format: &'static str,
    /// `binary` or `ascii`.
    pub encoding: &'static str,
    pub header: String,
    pub triangles: usize,
    pub facets_in_file: usize,
    pub vertices: usize,
    pub degenerate: usize,
    pub open_edges: usize,
    pub non_manifold_edges: usize,
    pub zero_normals: usize,
    pub flipped_normals: usize,
    pub trailing_bytes: usize,
    pub bounds: Option<Bounds>,
    /// The unit the caller gave the numbers in (`mm` or `inch`), if any.
    pub stl_units: Option<&'static str>,
    /// Without a given unit, the unit the part's size suggests:
    /// `mm`, `inch` or `unknown`.
    pub units_guess: Option<&'static str>,
}

/// Summarises `mesh` (in mm, converted from `given` if that was inch) as read with report `r`.
pub fn mesh(mesh: &TriMesh, r: &StlReport, given: Option<LengthUnit>) -> MeshSummary {
    let b = mesh.bounds();
    let given = given.map(|u| match u {
        LengthUnit::Mm => "mm",
        LengthUnit::Inch => "inch",
    });
    let edges = mesh.edge_report();
    MeshSummary {
        format: "stl",
        encoding: match r.format {
            StlFormat::Binary => "binary",
            _ => "ascii",
        },
        header: r.header.clone(),
        triangles: mesh.len(),
        facets_in_file: r.facets_in_file,
        vertices: mesh.vertices.len(),
        degenerate: r.degenerate,
        open_edges: edges.open,
        non_manifold_edges: edges.non_manifold,
        zero_normals: r.zero_normals,
        flipped_normals: r.flipped_normals,
        trailing_bytes: r.trailing_bytes,
        bounds: Bounds::of(&b),
        stl_units: given,
        units_guess: if given.is_some() {
            None
        } else {
            Some(units_guess(b.size()))
        },
    }
}

/// A part's size says little about its unit: under 8 units across, inches
/// are the likelier (a part of a few mm is rare); from 8 to 30 both are
/// common (beet_mm.stl is 28 mm across, a 20-inch plate 20 units), so the
/// guess says it cannot tell; above, mm.
pub fn units_guess(size: DVec3) -> &'static str {
    match size.max_element() {
        s if s < 8.0 => "inch",
        s if s < 30.0 => "unknown",
        _ => "mm",
    }
}

/// `writeln!` into a `String`, which cannot fail.
macro_rules! w {
    ($o:expr, $($t:tt)*) => {
        let _ = writeln!($o, $($t)*);
    };
}

/// Seconds as `123 s (0:02:03)`, both forms of the same whole second.
pub fn hms(t: f64) -> String {
    let s = t.max(0.0).round() as u64;
    format!("{s} s ({}:{:02}:{:02})", s / 3600, (s / 60) % 60, s % 60)
}

#[cfg(test)]
mod hms_tests {
    /// A user trial: `4 s (0:00:03)`, `149 s (0:02:28)`: the seconds were
    /// rounded and the clock cut.
    #[test]
    fn both_forms_say_the_same_second() {
        assert_eq!(super::hms(3.6), "4 s (0:00:04)");
        assert_eq!(super::hms(148.5), "149 s (0:02:29)");
        assert_eq!(super::hms(3599.7), "3600 s (1:00:00)");
        assert_eq!(super::hms(-1.0), "0 s (0:00:00)");
    }
}

/// [`program`] as JSON, for the text rendering and `--json`.
pub fn program_json(p: &Program, diagnostics: usize, machine: &Machine) -> serde_json::Value {
    serde_json::to_value(program(p, diagnostics, machine)).unwrap_or_default()
}

/// [`mesh`] as JSON, for the text rendering and `--json`.
pub fn mesh_json(m: &TriMesh, r: &StlReport, given: Option<LengthUnit>) -> serde_json::Value {
    serde_json::to_value(mesh(m, r, given)).unwrap_or_default()
}

/// Scales a mesh read from an STL to mm: `--stl-units inch` multiplies every
/// coordinate by 25.4; mm (the default: an STL does not say) leaves it.
pub fn to_mm(m: &mut TriMesh, given: Option<LengthUnit>) {
    if given == Some(LengthUnit::Inch) {
        m.map_vertices(|v| v * 25.4);
    }
}

pub fn render_mesh(path: &str, j: &Value) -> String {
    let mut o = String::new();
    w!(
        o,
        "{}: STL ({}), header {}",
        path,
        j["encoding"].as_str().unwrap_or(""),
        j["header"]
    );
    w!(
        o,
        "  triangles      {} ({} in file, {} degenerate dropped)",
        j["triangles"],
        j["facets_in_file"],
        j["degenerate"]
    );
    w!(o, "  vertices       {} after welding", j["vertices"]);
    w!(
        o,
        "  open edges     {}   non-manifold edges {}",
        j["open_edges"],
        j["non_manifold_edges"]
    );
    w!(
        o,
        "  stored normals {} zero, {} against the vertex order",
        j["zero_normals"],
        j["flipped_normals"]
    );
    if j["trailing_bytes"].as_u64().unwrap_or(0) > 0 {
        w!(
            o,
            "  trailing bytes {} after the last facet",
            j["trailing_bytes"]
        );
    }
    if let Some(b) = j["bounds"].as_object() {
        let v = |k: &str, i: usize| b[k][i].as_f64().unwrap_or(0.0);
        w!(
            o,
            "  bounds         [{:.3}, {:.3}, {:.3}] .. [{:.3}, {:.3}, {:.3}]",
            v("min", 0),
            v("min", 1),
            v("min", 2),
            v("max", 0),
            v("max", 1),
            v("max", 2)
        );
        w!(
            o,
            "  size           {:.3} x {:.3} x {:.3}",
            v("max", 0) - v("min", 0),
            v("max", 1) - v("min", 1),
            v("max", 2) - v("min", 2)
        );
    }
    if let Some(u) = j["stl_units"].as_str() {
        w!(o, "  units          {u} (--stl-units), bounds in mm");
        return o;
    }
    match j["units_guess"].as_str() {
        Some("inch") => {
            w!(
                o,
                "  units          inch (guess: the part is under 8 units across; --stl-units says)"
            );
        }
        Some("unknown") => {
            w!(o, "  units          mm or inch: 8 to 30 units across fits both (commands take mm unless --stl-units inch)");
        }
        _ => {
            w!(o, "  units          mm");
        }
    }
    o
}

/// The unit of a program and how it is known, in words.
fn units_text(u: millplan_nc::ir::Units) -> String {
    use millplan_nc::ir::{LengthUnit, UnitsOrigin};
    let unit = match u.source {
        LengthUnit::Mm => "mm",
        LengthUnit::Inch => "inch",
    };
    let how = match u.origin {
        UnitsOrigin::Declared => "as the program declares",
        UnitsOrigin::InferredFromFeed => "from the program's feed words",
        UnitsOrigin::Assumed => "assumed: the program does not say; --units sets it",
        UnitsOrigin::Override => "given by --units",
    };
    format!("{unit} ({how})")
}

pub fn render_program(path: &str, p: &Program, j: &Value) -> String {
    let mut o = String::new();
    w!(
        o,
        "{}: {} ({})",
        path,
        j["format"].as_str().unwrap_or(""),
        p.source.name()
    );
    w!(o, "  units       {}", units_text(p.units));
    w!(o, "  operations  {}", p.operations.len());
    for (i, op) in (1..).zip(&p.operations) {
        let t = op.tool.as_ref();
        let tool = match t {
            Some(t) => {
                let mut s = format!("T{}", t.number.map(|n| n.to_string()).unwrap_or("?".into()));
                if let Some(n) = &t.name {
                    s += &format!(" {n}");
                }
                if let Some(c) = &t.cutter {
                    let kind = format!("{:?}", c.kind).to_lowercase();
                    s += &format!(" ({kind} D{:.3} R{:.3})", c.d, c.r);
                }
                s
            }
            None => "no tool".into(),
        };
        w!(
            o,
            "    {i:>3} {:<24} {:>8} moves  {tool}",
            op.name.as_deref().unwrap_or("-"),
            op.moves.len()
        );
    }
    let m = &j["moves"];
    w!(
        o,
        "  moves       {} rapid, {} linear, {} arc, {} cycle ({} five-axis)",
        m["rapid"],
        m["linear"],
        m["arc"],
        m["cycle"],
        m["five_axis"]
    );
    if let Some(r) = j["rotary"].as_object() {
        for (name, u) in r {
            let f = |k: &str| u[k].as_f64().unwrap_or(f64::NAN);
            w!(
                o,
                "  rotary {name}    {:.3} .. {:.3} deg, {:.3} deg travelled",
                f("min_deg"),
                f("max_deg"),
                f("travel_deg")
            );
        }
    }
    if let Some(b) = j["bounds"].as_object() {
        // mm, to the thousandth as the lengths are (the JSON keeps them whole).
        let xyz = |v: &serde_json::Value| {
            let c = v.as_array().map_or(&[][..], |a| &a[..]).iter();
            let c: Vec<String> = c
                .map(|x| x.as_f64().map_or("?".into(), |f| format!("{f:.3}")))
                .collect();
            c.join(", ")
        };
        w!(
            o,
            "  bounds      [{}] .. [{}] mm",
            xyz(&b["min"]),
            xyz(&b["max"])
        );
    }
    w!(
        o,
        "  length      {:.1} mm cutting, {:.1} mm rapid",
        j["length_mm"]["cutting"].as_f64().unwrap_or(0.0),
        j["length_mm"]["rapid"].as_f64().unwrap_or(0.0)
    );
    let unknown = j["unknown_moves"].as_u64().unwrap_or(0);
    if unknown > 0 {
        let what = match unknown {
            1 => "1 move starts".to_string(),
            n => format!("{n} moves start or end"),
        };
        w!(o,
            "  unset start {what} where the machine stands before the program, a position the program never sets: left out of lengths, bounds and time"
        );
    }
    let t = j["time_s"].as_f64().unwrap_or(0.0);
    let t0 = j["time_nominal_s"].as_f64().unwrap_or(0.0);
    w!(
        o,
        "  time        {} estimated with acceleration ({} at programmed feeds)",
        hms(t),
        hms(t0),
    );
    w!(
        o,
        "  planner     {}",
        j["time"]["planner"].as_str().unwrap_or("generic")
    );
    for m in j["time"]["by_mode"].as_array().into_iter().flatten() {
        w!(
            o,
            "    {:<18}{:>10.1} s  {} blocks",
            m["mode"].as_str().unwrap_or(""),
            m["time_s"].as_f64().unwrap_or(0.0),
            m["blocks"].as_u64().unwrap_or(0)
        );
    }
    o
}

/// Fastest rapid rate `--rapid-rate` takes, mm/min.
pub const MAX_RAPID: f64 = 1e7;

/// The machine's rapid rate, or `--rapid-rate` in its range.
pub fn rapid_rate(machine: &Machine, given: Option<f64>) -> Result<f64, String> {
    crate::check::arg(
        "--rapid-rate",
        given.unwrap_or(machine.rapid),
        crate::check::Range::positive(MAX_RAPID, "mm/min"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 18: beet_mm.stl (28 mm across) was guessed as inch.
    #[test]
    fn mid_sized_parts_are_not_guessed_as_inch() {
        assert_eq!(units_guess(DVec3::new(22.2, 28.4, 7.2)), "unknown");
        assert_eq!(units_guess(DVec3::new(3.0, 2.0, 1.0)), "inch");
        assert_eq!(units_guess(DVec3::new(60.0, 60.0, 9.6)), "mm");
    }

    #[test]
    fn a_program_is_summarised_with_its_tools_moves_and_time() {
        let src = "G21 G90\nT1 M6\nS6000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F300\nG1 X10\nM30\n";
        let parsed =
            millplan_nc::parse_program(src, millplan_nc::ReadOptions::default()).expect("reads");
        let s = program(&parsed.program, 0, &Machine::default());
        assert_eq!(s.format, "gcode");
        assert_eq!(s.units, "mm");
        assert_eq!(s.moves.total, 3);
        assert_eq!((s.moves.rapid, s.moves.linear), (1, 2));
        assert!((s.length_mm.cutting - 16.0).abs() < 1e-9, "{s:?}");
        assert!(s.time_s >= s.time_nominal_s && s.time_s > 0.0, "{s:?}");
        assert_eq!(s.tools.len(), 1);
        assert_eq!(s.tools[0].number, Some(1));
    }
}
