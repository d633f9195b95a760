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
use millplan_plan::timing::{estimate_program, TimeEstimate};
use serde::Serialize;
use std::collections::BTreeMap;

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
        }
    }
}

/// What a program holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProgramSummary {
    /// `apt` or `gcode`.
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
    let s = summarize(p, machine.rapid);
    let est = estimate_program(p, machine);
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
        format: if p.source.is_apt() { "apt" } else { "gcode" },
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
