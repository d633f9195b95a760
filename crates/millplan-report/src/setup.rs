//! The setup report: the sphere map of tool directions and the part coloured
//! by the tilt its facets need.

use crate::html::simple_report;
use crate::svg::{map, sphere_map, DirClass};
use millplan_geom::TriMesh;
use millplan_models::kinematics::{Kinematics, RotaryAxis};
use millplan_plan::setup::SetupPlan;

/// `part`: how to name the part (its file); `mode`: line of sight or the tool.
pub fn setup_report(
    part: &str,
    mode: &str,
    clearance_deg: f64,
    mesh: &TriMesh,
    plan: &SetupPlan,
    machine: &Kinematics,
) -> String {
    let best = &plan.best;
    let grid = plan.grid.as_ref();
    let s = best.setup;
    let mut class: Vec<DirClass> = (0..grid.len())
        .map(|c| {
            if best.mask[c / 64] >> (c % 64) & 1 == 1 {
                DirClass::Reach
            } else {
                DirClass::Out
            }
        })
        .collect();
    for &t in &best.unreachable {
        for c in plan.vis.cells_of(t) {
            class[c] = DirClass::Missing;
        }
    }
    for c in best.chosen.iter().flatten() {
        class[*c] = DirClass::Used;
    }
    let cells: Vec<([f64; 3], DirClass)> = (0..grid.len())
        .map(|c| ((s * grid.direction(c)).to_array(), class[c]))
        .collect();
    let tilts: Vec<(f64, f64, f64)> = plan
        .live
        .iter()
        .zip(&best.dirs)
        .filter_map(|(&t, d)| {
            let [p, q, r] = mesh.corners(t);
            let m = s * ((p + q + r) / 3.0);
            d.map(|d| (m.x, m.y, (s * d).z.clamp(-1.0, 1.0).acos().to_degrees()))
        })
        .collect();
    let range = |ax: &RotaryAxis| match (ax.min, ax.max) {
        (None, None) => "free".to_string(),
        (lo, hi) => format!(
            "{} … {}",
            lo.map_or("−∞".into(), |v| format!("{v}°")),
            hi.map_or("∞".into(), |v| format!("{v}°"))
        ),
    };
    let yes = |b: bool| if b { "yes" } else { "no" }.to_string();
    let mut rows = vec![
        ("part".to_string(), part.to_string()),
        ("facets".to_string(), mesh.len().to_string()),
        (
            "machine".to_string(),
            format!(
                "{:?}: first axis {}, second axis {}",
                machine.kind,
                range(&machine.first),
                range(&machine.second)
            ),
        ),
        ("mode".to_string(), mode.to_string()),
        (
            "grid".to_string(),
            format!(
                "{} ({} cells), clearance {}°",
                grid.name(),
                grid.len(),
                clearance_deg
            ),
        ),
        ("feasible in one setup".to_string(), yes(plan.feasible)),
        ("largest tilt".to_string(), format!("{:.2}°", best.tilt)),
        (
            "facets out of reach".to_string(),
            format!(
                "{} ({:.2} mm²)",
                best.unreachable.len(),
                best.unreachable_area
            ),
        ),
        (
            "facets no direction sees (no range reaches)".to_string(),
            plan.inaccessible.len().to_string(),
        ),
        (
            "share of the machine's ranges needed".to_string(),
            format!("{:.1} %", 100.0 * best.usage),
        ),
    ];
    if let Some(r) = best.required {
        rows.push((
            "required ranges (the least of any setup)".to_string(),
            format!(
                "first {:.2}° … {:.2}°, second {:.2}° … {:.2}°",
                r[0].0, r[0].1, r[1].0, r[1].1
            ),
        ));
    }
    let m = |i: usize| format!("[{:.6} {:.6} {:.6}]", s.row(i).x, s.row(i).y, s.row(i).z);
    rows.push((
        "setup rotation (part → table)".to_string(),
        format!("{} {} {}", m(0), m(1), m(2)),
    ));
    simple_report(
        "Setup and machinability",
        "Tool directions each facet can be reached from, the directions the machine reaches with the part clamped in the chosen setup, and the tilt every facet needs.",
        &rows,
        &[
            ("Tool directions in the table frame (equal-area projection). Dark blue: the direction each facet is cut from; red: directions facets need but the machine cannot reach.".to_string(), sphere_map("Directions", &cells)),
            ("The part in the chosen setup seen from above, coloured by the tilt its facets need (degrees).".to_string(), map("Required tilt", "tilt °", &tilts)),
        ],
    )
}
