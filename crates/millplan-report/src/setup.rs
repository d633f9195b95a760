//! The setup report: its inputs, the warnings, the verdict in words, the
//! sphere map of tool directions with the machine's rotary limits and the part
//! coloured by the tilt its facets need.

use crate::html::{report_page, Evidence, Notes, Verdict};
use crate::svg::{map, sphere_map, DirClass};
use millplan_geom::{DVec3, TriMesh};
use millplan_models::kinematics::{Kinematics, RotaryAxis};
use millplan_plan::setup::SetupPlan;

/// What a setup report was made from.
#[derive(Clone, Debug, Default)]
pub struct SetupInputs {
    /// The part's file.
    pub part: String,
    /// Line of sight, or the tool (`tool 10,40`).
    pub mode: String,
    pub clearance_deg: f64,
    /// Findings about the inputs (a mesh's defects, facets turned outward),
    /// shown in the warning box.
    pub warnings: Vec<String>,
}

/// An angle to 0.001°, without the sign of a value that rounds to zero.
fn deg(v: f64) -> String {
    let t = format!("{v:.3}");
    match t.strip_prefix('-') {
        Some(u) if u.chars().all(|c| c == '0' || c == '.') => u.to_string(),
        _ => t,
    }
}

/// A rotary range in words.
fn range(ax: &RotaryAxis) -> String {
    match (ax.min, ax.max) {
        (None, None) => "free".to_string(),
        (lo, hi) => format!(
            "{} … {}",
            lo.map_or("−∞".into(), |v| format!("{v}°")),
            hi.map_or("∞".into(), |v| format!("{v}°"))
        ),
    }
}

/// The ends of a range for drawing: a free or open end is a whole turn.
fn span(ax: &RotaryAxis) -> (f64, f64) {
    (ax.min.unwrap_or(-180.0), ax.max.unwrap_or(180.0))
}

/// Whether the machine misses some direction within 0.1° of `d`: `d` lies on
/// the edge of what its ranges reach (or outside).
fn on_edge(machine: &Kinematics, d: DVec3) -> bool {
    let u = d.any_orthonormal_vector();
    let v = d.cross(u);
    let e = 0.1f64.to_radians().tan();
    (0..8).any(|k| {
        let t = std::f64::consts::TAU * k as f64 / 8.0;
        !machine.reaches((d + e * (t.cos() * u + t.sin() * v)).normalize())
    })
}

/// The edges of what the machine's rotary ranges reach, as curves of tool
/// directions in the table frame: each limited end of one axis with the
/// other swept over its range, kept where it is the edge (a limit that lies
/// inside what the other branch of the axes reaches is left out).
pub fn limit_curves(machine: &Kinematics) -> Vec<Vec<[f64; 3]>> {
    const STEPS: usize = 180;
    let (f, s) = (span(&machine.first), span(&machine.second));
    let mut out: Vec<Vec<[f64; 3]>> = Vec::new();
    let mut sweep = |(lo, hi): (f64, f64), at: &dyn Fn(f64) -> DVec3| {
        let mut piece = Vec::new();
        for k in 0..=STEPS {
            let d = at(lo + (hi - lo) * k as f64 / STEPS as f64);
            if on_edge(machine, d) {
                piece.push(d.to_array());
            } else if piece.len() > 1 {
                out.push(std::mem::take(&mut piece));
            } else {
                piece.clear();
            }
        }
        if piece.len() > 1 {
            out.push(piece);
        }
    };
    for end in [machine.first.min, machine.first.max].into_iter().flatten() {
        sweep(s, &|v| machine.tool_axis(end, v));
    }
    for end in [machine.second.min, machine.second.max]
        .into_iter()
        .flatten()
    {
        sweep(f, &|v| machine.tool_axis(v, end));
    }
    out
}

/// The verdict of a setup search by the one rule: red when no setup
/// reaches every facet that needs cutting; amber on a warning (the mesh's
/// defects, facets out of reach or reached by no direction); green
/// otherwise. Text, JSON and report print it alike.
pub fn setup_verdict(i: &SetupInputs, mesh: &TriMesh, plan: &SetupPlan) -> Verdict {
    let best = &plan.best;
    let total = mesh.area().max(1e-300);
    let mut warnings = i.warnings.clone();
    if !best.unreachable.is_empty() {
        warnings.push(format!(
            "{} facets ({:.2} mm², {:.2} % of the part's area) are out of the machine's reach in the setup chosen",
            best.unreachable.len(),
            best.unreachable_area,
            100.0 * best.unreachable_area / total
        ));
    }
    if !plan.inaccessible.is_empty() {
        warnings.push(format!(
            "{} facets no tool direction reaches at all (undercuts, or closed in by the part): no setup and no rotary range machines them",
            plan.inaccessible.len()
        ));
    }
    let evidence = Evidence {
        failed: if plan.feasible {
            Vec::new()
        } else {
            vec![format!(
                "one setup reaches every facet ({} facets out of reach)",
                best.unreachable.len()
            )]
        },
        ..Evidence::default()
    };
    Verdict::of(&evidence, warnings)
}

/// The warnings and the verdict in words: feasible or not, the ranges the
/// part needs, the setup chosen, the share out of reach, what to look at.
pub fn setup_notes(
    i: &SetupInputs,
    mesh: &TriMesh,
    plan: &SetupPlan,
    machine: &Kinematics,
) -> Notes {
    let best = &plan.best;
    let s = plan.summary(mesh, machine);
    let [n0, n1] = s.axes.map(str::to_uppercase);
    let total = mesh.area().max(1e-300);
    let v = setup_verdict(i, mesh, plan);
    let e = s.euler_zyx_deg.map(deg);
    let chosen = format!(
        "the part turned by Euler Z-Y-X {}°, {}°, {}°",
        e[0], e[1], e[2]
    );
    let needs = |r: Option<[(f64, f64); 2]>| {
        r.map_or("no range that reaches every facet".to_string(), |r| {
            format!(
                "{n0} {}° … {}° and {n1} {}° … {}°",
                deg(r[0].0),
                deg(r[0].1),
                deg(r[1].0),
                deg(r[1].1)
            )
        })
    };
    let mut verdict = vec![if plan.feasible {
        format!(
            "Feasible in one setup: with {chosen} the machine reaches every facet that needs cutting ({} facets), using {:.0} % of its ranges; largest tilt {:.2}°.",
            plan.live.len(),
            100.0 * s.usage,
            s.max_tilt_deg
        )
    } else {
        format!(
            "Not feasible in one setup: with {chosen}, the best setup found, {} facets ({:.2} % of the part's area) stay out of reach.",
            best.unreachable.len(),
            100.0 * best.unreachable_area / total
        )
    }];
    verdict.push(format!(
        "The part needs {} (the least of any setup), against the machine's {n0} {} and {n1} {}.",
        needs(s.required),
        range(&machine.first),
        range(&machine.second)
    ));
    if let Some(r) = s.would_do {
        verdict.push(format!(
            "As it lies in the file it would need {}.",
            needs(Some(r))
        ));
    }
    if !plan.feasible {
        verdict.push("Look at the red directions on the map (needed, out of reach) and the facets of largest tilt: they need a second setup, or a machine with larger ranges.".to_string());
    } else if !v.warnings.is_empty() {
        verdict.push("Look at the warnings above before clamping the part.".to_string());
    }
    Notes::of_verdict(
        vec![
            ("part".into(), format!("{} ({} facets)", i.part, mesh.len())),
            (
                "machine".into(),
                format!(
                    "{:?}: {n0} {}, {n1} {}",
                    machine.kind,
                    range(&machine.first),
                    range(&machine.second)
                ),
            ),
            ("mode".into(), i.mode.clone()),
            (
                "sphere grid".into(),
                format!(
                    "{} ({} cells), clearance {}°",
                    plan.grid.name(),
                    plan.grid.len(),
                    i.clearance_deg
                ),
            ),
        ],
        &v,
        verdict,
    )
}

/// The report page.
pub fn setup_report(
    i: &SetupInputs,
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
    let yes = |b: bool| if b { "yes" } else { "no" }.to_string();
    let mut rows = vec![
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
    report_page(
        "Setup and machinability",
        "Tool directions each facet can be reached from, the directions the machine reaches with the part clamped in the chosen setup, and the tilt every facet needs.",
        &setup_notes(i, mesh, plan, machine),
        &rows,
        &[
            ("Tool directions in the table frame (equal-area projection). Dark blue: the direction each facet is cut from; red: directions facets need but the machine cannot reach; black lines: the edges of what the machine's rotary ranges reach.".to_string(), sphere_map("Directions", &cells, &limit_curves(machine))),
            ("The part in the chosen setup seen from above, coloured by the tilt its facets need (degrees).".to_string(), map("Required tilt", "tilt °", &tilts)),
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use millplan_models::kinematics::KinKind;

    /// The tilt of a direction from the table's Z, degrees.
    fn tilt(d: &[f64; 3]) -> f64 {
        d[2].clamp(-1.0, 1.0).acos().to_degrees()
    }

    /// On an A/C table the tool's tilt from Z is |A| (the tool axis is
    /// Rz(C)ᵀ·Rx(A)ᵀ·Z), so what A ≤ 30° reaches ends on the 30° circle. The
    /// C limits of ±90° lie inside it (negative A covers the other half) and
    /// A = 0 is a single direction inside: neither is drawn.
    #[test]
    fn limit_curves_of_an_ac_table_are_its_tilt_circle() {
        for c in [None, Some((-90.0, 90.0))] {
            let mut k = Kinematics::new(KinKind::TableAc);
            k.first = RotaryAxis {
                min: Some(if c.is_some() { -30.0 } else { 0.0 }),
                max: Some(30.0),
                sign: 1.0,
            };
            if let Some((lo, hi)) = c {
                k.second = RotaryAxis {
                    min: Some(lo),
                    max: Some(hi),
                    sign: 1.0,
                };
            }
            let curves = limit_curves(&k);
            let points: Vec<&[f64; 3]> = curves.iter().flatten().collect();
            assert!(points.len() > 100, "{c:?}: {}", points.len());
            for d in points {
                assert!((tilt(d) - 30.0).abs() < 1e-9, "{c:?}: {d:?}");
            }
        }
    }

    #[test]
    fn angles_that_round_to_zero_have_no_sign() {
        assert_eq!(deg(-0.0), "0.000");
        assert_eq!(deg(-0.0004), "0.000");
        assert_eq!(deg(-0.0006), "-0.001");
        assert_eq!(deg(35.26439), "35.264");
    }
}
