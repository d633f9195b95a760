//! `millplan inspect`: what a file holds.

use crate::cmd::{print_diagnostics, read_options, UnitArg};
use crate::error::{CliResult, EXIT_OK};
use crate::io::{read_any, Input};
use millplan_geom::Aabb;
use millplan_nc::stats::summarize;
use millplan_nc::{Dialect, Program};
use serde_json::{json, Value};
use std::path::PathBuf;

/// Print what a file holds: format and dialect, units, tools, moves, bounds,
/// path lengths and estimated time (programs); triangles, defects and bounds (STL).
///
/// The time is an estimate with acceleration: the machine file's axis
/// velocities, accelerations and jerks (conservative defaults where it has
/// none), with look-ahead across blocks; the time at programmed feeds is
/// printed beside it.
///
/// The format is detected from the content, not the file name.
#[derive(clap::Args)]
pub struct Args {
    /// APT/CL, G-code (Fanuc, Sinumerik, LinuxCNC, Heidenhain) or STL file.
    pub file: PathBuf,
    /// Print a machine-readable JSON summary on standard output.
    #[arg(long)]
    pub json: bool,
    /// Print the program's IR, one line per move and event.
    #[arg(long)]
    pub ir: bool,
    /// Unit of the source when the file does not say (or says wrongly).
    #[arg(long, value_enum)]
    pub units: Option<UnitArg>,
    /// Rapid traverse rate for the time estimate, mm/min (default: the
    /// machine file's, else 15000).
    #[arg(long)]
    pub rapid_rate: Option<f64>,
    /// Machine file (examples/machine.toml): its rapid rate, axis limits and
    /// kinematics time the program (default: a built-in three-axis machine).
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Do not print reader diagnostics.
    #[arg(long, short)]
    pub quiet: bool,
    /// Unit of an STL's numbers (an STL does not say): mm or inch, converted
    /// to mm; without it the unit is guessed from the part's size.
    #[arg(long, value_enum)]
    pub stl_units: Option<UnitArg>,
    /// Print the wall time of each phase on standard error (they add up to
    /// the whole run).
    #[arg(long)]
    pub timings: bool,
}

fn bounds_json(b: &Aabb) -> Value {
    if b.is_empty() {
        return Value::Null;
    }
    json!({ "min": [b.min.x, b.min.y, b.min.z], "max": [b.max.x, b.max.y, b.max.z] })
}

/// The rotary axes the program moves, by letter.
fn rotary_json(r: &[Option<millplan_nc::stats::RotaryUse>; 3]) -> Value {
    let mut m = serde_json::Map::new();
    for (name, u) in ["A", "B", "C"].iter().zip(r) {
        if let Some(u) = u {
            m.insert(name.to_string(), json!(u));
        }
    }
    Value::Object(m)
}

fn format_name(d: Dialect) -> &'static str {
    if d.is_apt() {
        "apt"
    } else {
        "gcode"
    }
}

fn program_json(p: &Program, diags: usize, machine: &millplan_plan::machine::Machine) -> Value {
    let s = summarize(p, machine.rapid);
    let est = millplan_plan::timing::estimate_program(p, machine);
    let tools: Vec<Value> = p
        .operations
        .iter()
        .filter_map(|o| o.tool.as_ref())
        .map(|t| {
            json!({
                "number": t.number,
                "name": t.name,
                "cutter": t.cutter.map(|c| json!({
                    "kind": c.kind, "d": c.d, "r": c.r, "e": c.e, "f": c.f,
                    "alpha_deg": c.alpha.to_degrees(), "beta_deg": c.beta.to_degrees(), "h": c.h
                })),
                "line": t.line,
            })
        })
        .collect();
    json!({
        "format": format_name(p.source),
        "dialect": p.source.name(),
        "name": p.name,
        "units": match p.units.source { millplan_nc::LengthUnit::Mm => "mm", millplan_nc::LengthUnit::Inch => "inch" },
        "units_origin": p.units.origin,
        "operations": p.operations.len(),
        "tools": tools,
        "moves": { "rapid": s.moves.rapid, "linear": s.moves.linear, "arc": s.moves.arc, "cycle": s.moves.cycle,
                   "total": p.move_count(), "five_axis": s.five_axis_moves },
        "bounds": bounds_json(&s.bounds),
        "length_mm": { "cutting": s.cutting_mm, "rapid": s.rapid_mm },
        "time_s": est.total_s,
        "time_nominal_s": s.time_s,
        "time": crate::cmd::time_json(&est),
        "unknown_moves": s.unknown_moves,
        "rotary": rotary_json(&s.rotary),
        "diagnostics": diags,
    })
}

pub fn run(a: Args) -> CliResult<i32> {
    let mut clock = crate::timings::Clock::start();
    let mut machine = crate::cmd::load_machine(a.machine.as_deref())?;
    machine.rapid = crate::cmd::arg(
        "--rapid-rate",
        a.rapid_rate.unwrap_or(machine.rapid),
        crate::cmd::Range::positive(1e7, "mm/min"),
    )?;
    clock.lap("arguments and machine file");
    let input = read_any(&a.file, read_options(a.units, None)?)?;
    clock.lap("file read");
    match input {
        Input::Program(parsed) => {
            print_diagnostics(&a.file, &parsed.diagnostics, a.quiet || a.json);
            let p = &parsed.program;
            if a.ir {
                out!("{}", millplan_nc::text::print(p));
                clock.lap("IR printed");
                clock.print(a.timings);
                return Ok(EXIT_OK);
            }
            let j = program_json(p, parsed.diagnostics.len(), &machine);
            clock.lap("summary and time estimate");
            if a.json {
                crate::cmd::print_json(j);
            } else {
                print_program(&a.file, p, &j);
            }
            drop(parsed);
        }
        Input::Mesh(mut mesh, r) => {
            crate::cmd::stl_to_mm(&mut mesh, a.stl_units);
            let j = mesh_json(&mesh, &r, a.stl_units);
            clock.lap("summary (edges, bounds)");
            if a.json {
                crate::cmd::print_json(j);
            } else {
                print_mesh(&a.file, &j);
            }
        }
    }
    clock.lap("printed");
    clock.print(a.timings);
    Ok(EXIT_OK)
}

/// A part's size says little about its unit: under 8 units across, inches
/// are the likelier (a part of a few mm is rare); from 8 to 30 both are
/// common (beet_mm.stl is 28 mm across, a 20-inch plate 20 units), so the
/// guess says it cannot tell; above, mm.
fn units_guess(size: millplan_geom::DVec3) -> &'static str {
    match size.max_element() {
        s if s < 8.0 => "inch",
        s if s < 30.0 => "unknown",
        _ => "mm",
    }
}

fn mesh_json(
    mesh: &millplan_geom::TriMesh,
    r: &millplan_geom::stl::StlReport,
    given: Option<UnitArg>,
) -> Value {
    let b = mesh.bounds();
    let given = given.map(|u| match u {
        UnitArg::Mm => "mm",
        UnitArg::Inch => "inch",
    });
    let edges = mesh.edge_report();
    json!({
        "format": "stl",
        "encoding": match r.format { millplan_geom::stl::StlFormat::Binary => "binary", _ => "ascii" },
        "header": r.header,
        "triangles": mesh.len(),
        "facets_in_file": r.facets_in_file,
        "vertices": mesh.vertices.len(),
        "degenerate": r.degenerate,
        "open_edges": edges.open,
        "non_manifold_edges": edges.non_manifold,
        "zero_normals": r.zero_normals,
        "flipped_normals": r.flipped_normals,
        "trailing_bytes": r.trailing_bytes,
        "bounds": bounds_json(&b),
        "stl_units": given,
        "units_guess": if given.is_some() { None } else { Some(units_guess(b.size())) },
    })
}

fn print_mesh(path: &std::path::Path, j: &Value) {
    outln!(
        "{}: STL ({}), header {}",
        path.display(),
        j["encoding"].as_str().unwrap_or(""),
        j["header"]
    );
    outln!(
        "  triangles      {} ({} in file, {} degenerate dropped)",
        j["triangles"],
        j["facets_in_file"],
        j["degenerate"]
    );
    outln!("  vertices       {} after welding", j["vertices"]);
    outln!(
        "  open edges     {}   non-manifold edges {}",
        j["open_edges"],
        j["non_manifold_edges"]
    );
    outln!(
        "  stored normals {} zero, {} against the vertex order",
        j["zero_normals"],
        j["flipped_normals"]
    );
    if j["trailing_bytes"].as_u64().unwrap_or(0) > 0 {
        outln!(
            "  trailing bytes {} after the last facet",
            j["trailing_bytes"]
        );
    }
    if let Some(b) = j["bounds"].as_object() {
        let v = |k: &str, i: usize| b[k][i].as_f64().unwrap_or(0.0);
        outln!(
            "  bounds         [{:.3}, {:.3}, {:.3}] .. [{:.3}, {:.3}, {:.3}]",
            v("min", 0),
            v("min", 1),
            v("min", 2),
            v("max", 0),
            v("max", 1),
            v("max", 2)
        );
        outln!(
            "  size           {:.3} x {:.3} x {:.3}",
            v("max", 0) - v("min", 0),
            v("max", 1) - v("min", 1),
            v("max", 2) - v("min", 2)
        );
    }
    if let Some(u) = j["stl_units"].as_str() {
        outln!("  units          {u} (--stl-units), bounds in mm");
        return;
    }
    match j["units_guess"].as_str() {
        Some("inch") => {
            outln!("  units          inch (guess: the part is under 8 units across; --stl-units says)")
        }
        Some("unknown") => outln!(
            "  units          mm or inch: 8 to 30 units across fits both (commands take mm unless --stl-units inch)"
        ),
        _ => outln!("  units          mm"),
    }
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

fn print_program(path: &std::path::Path, p: &Program, j: &Value) {
    outln!(
        "{}: {} ({})",
        path.display(),
        j["format"].as_str().unwrap_or(""),
        p.source.name()
    );
    outln!("  units       {}", units_text(p.units));
    outln!("  operations  {}", p.operations.len());
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
        outln!(
            "    {i:>3} {:<24} {:>8} moves  {tool}",
            op.name.as_deref().unwrap_or("-"),
            op.moves.len()
        );
    }
    let m = &j["moves"];
    outln!(
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
            outln!(
                "  rotary {name}    {:.3} .. {:.3} deg, {:.3} deg travelled",
                f("min_deg"),
                f("max_deg"),
                f("travel_deg")
            );
        }
    }
    if let Some(b) = j["bounds"].as_object() {
        outln!("  bounds      {} .. {}", b["min"], b["max"]);
    }
    outln!(
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
        outln!(
            "  unset start {what} where the machine stands before the program, a position the program never sets: left out of lengths, bounds and time"
        );
    }
    let t = j["time_s"].as_f64().unwrap_or(0.0);
    let t0 = j["time_nominal_s"].as_f64().unwrap_or(0.0);
    outln!(
        "  time        {} estimated with acceleration ({} at programmed feeds)",
        crate::cmd::hms(t),
        crate::cmd::hms(t0),
    );
}

#[cfg(test)]
mod tests {
    use millplan_geom::DVec3;

    /// Issue 18: beet_mm.stl (28 mm across) was guessed as inch.
    #[test]
    fn mid_sized_parts_are_not_guessed_as_inch() {
        assert_eq!(super::units_guess(DVec3::new(22.2, 28.4, 7.2)), "unknown");
        assert_eq!(super::units_guess(DVec3::new(3.0, 2.0, 1.0)), "inch");
        assert_eq!(super::units_guess(DVec3::new(60.0, 60.0, 9.6)), "mm");
    }
}
