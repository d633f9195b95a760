//! The stock simulation's table and report.

use crate::html::{report_page, Evidence, Notes, Verdict};
use crate::svg::{self, Series};
use millplan_geom::TriMesh;
use millplan_sim::stock::remaining::Remaining;
use millplan_sim::stock::run::SimReport;
use millplan_sim::stock::sim::MoveCut;
use millplan_sim::stock::Stock;
use std::fmt::Write;

/// The verdict of a run by the one rule, as its report gives it: red when
/// a rapid, shank or holder met material or the tool cut into the part.
pub fn sim_verdict(rep: &SimReport, part: Option<&Remaining>) -> Verdict {
    Verdict::of(&sim_evidence(rep, part), sim_warnings(rep, part))
}

/// What the simulation's verdict is decided from: a rapid, shank or holder
/// in material, or a cut into the part, is a failed check.
pub fn sim_evidence(rep: &SimReport, part: Option<&Remaining>) -> Evidence {
    let mut e = Evidence::default();
    if !rep.rapid_collisions.is_empty() {
        e.failed
            .push(format!("{} rapids in material", rep.rapid_collisions.len()));
    }
    if !rep.holder_collisions.is_empty() {
        e.failed.push(format!(
            "{} moves with the shank or holder in material",
            rep.holder_collisions.len()
        ));
    }
    if let Some(r) = part {
        if r.gouged > 0 {
            e.failed.push(format!(
                "{} facets cut into the part, down to {:.3} mm",
                r.gouged, -r.min
            ));
        }
    }
    e
}

/// The warnings of a run: its collisions (the first 20), the moves it
/// could not simulate and the cuts into the part.
fn sim_warnings(rep: &SimReport, part: Option<&Remaining>) -> Vec<String> {
    let hits = rep.rapid_collisions.len() + rep.holder_collisions.len();
    let mut warnings: Vec<String> = rep
        .rapid_collisions
        .iter()
        .map(|c| {
            format!(
                "COLLISION line {}: rapid {:.3} mm into material",
                c.line, c.depth
            )
        })
        .chain(rep.holder_collisions.iter().map(|c| {
            format!(
                "COLLISION line {}: shank or holder {:.3} mm into material",
                c.line, c.depth
            )
        }))
        .take(20)
        .collect();
    if hits > 20 {
        warnings.push(format!("and {} more collisions", hits - 20));
    }
    let skipped = rep.skipped.total();
    if skipped > 0 {
        warnings.push(format!(
            "{skipped} moves not simulated ({} from or to an unknown position, {} with the axis known only as machine angles, {} without a tool{}): the stock does not show them",
            rep.skipped.unknown_position, rep.skipped.unknown_axis, rep.skipped.no_tool, rep.skipped.first()
        ));
    }
    if let Some(r) = part {
        if r.gouged > 0 {
            warnings.push(format!(
                "the program cuts into the part on {} facets, down to {:.3} mm below its surface",
                r.gouged, -r.min
            ));
        }
    }
    warnings
}

/// One row per simulated move. Lengths in mm to the µm, volumes in mm³ to
/// 0.001, rates in mm³/min to 0.1.
pub fn moves_csv(moves: &[MoveCut]) -> String {
    let mut s = String::with_capacity(64 * moves.len() + 80);
    s.push_str("index,line,removed_mm3,mrr,ap,ae,air,rapid,holder_depth,minutes\n");
    for m in moves {
        let _ = writeln!(
            s,
            "{},{},{:.3},{:.1},{:.3},{:.3},{},{},{:.3},{:.6}",
            m.index,
            m.line,
            m.removed_mm3,
            m.mrr,
            m.ap,
            m.ae,
            u8::from(m.air),
            u8::from(m.rapid),
            m.holder_depth,
            m.minutes
        );
    }
    s
}

/// At most `n` × `n` samples of the stock's top, (x, y, top).
fn top_view(stock: &Stock, n: usize) -> Vec<(f64, f64, f64)> {
    let g = stock.grid;
    let step = (g.nx.max(g.ny) / n).max(1);
    let mut pts = Vec::new();
    for j in (0..g.ny).step_by(step) {
        for i in (0..g.nx).step_by(step) {
            if let Some(t) = stock.top(i, j) {
                pts.push((g.cx(i), g.cy(j), t));
            }
        }
    }
    pts
}

/// The report: what was simulated, collisions first, the stock seen from
/// above (coloured by the material left on the part when it is given, else
/// by height) and the removal rate along the program.
pub fn report(
    title: &str,
    inputs: Vec<(String, String)>,
    stock_spec: &str,
    stock: &Stock,
    rep: &SimReport,
    part: Option<(&Remaining, &TriMesh)>,
) -> String {
    let hits = rep.rapid_collisions.len() + rep.holder_collisions.len();
    let intro = format!(
        "The program run over the stock {stock_spec} at {} mm: what every move removed, where anything but the cutting edge met material, and the stock left.",
        rep.resolution_mm
    );
    let warnings = sim_warnings(rep, part.map(|p| p.0));
    let mut verdict = vec![format!(
        "{} {:.1} mm³ removed of {:.1} mm³ ({:.1} %) in {:.2} min; the highest removal rate {:.0} mm³/min at line {}; {} of {} cutting moves cut only air.",
        if hits == 0 {
            "No rapid, shank or holder met material."
        } else {
            "Collisions: see the warnings."
        },
        rep.removed_mm3,
        rep.stock_before_mm3,
        100.0 * rep.removed_mm3 / rep.stock_before_mm3.max(1e-12),
        rep.minutes,
        rep.max_mrr_mm3_min,
        rep.max_mrr_line,
        rep.air_moves,
        rep.cutting_moves + rep.air_moves
    )];
    if let Some((r, _)) = part {
        verdict.push(format!(
            "Material left on the part: {:.3} to {:.3} mm, mean {:.3} mm.",
            r.min, r.max, r.mean
        ));
    }
    let mut rows: Vec<(String, String)> = vec![
        ("Stock".into(), stock_spec.into()),
        (
            "Resolution".into(),
            format!(
                "{} mm ({} × {} dexels)",
                rep.resolution_mm, stock.grid.nx, stock.grid.ny
            ),
        ),
        (
            "Moves simulated".into(),
            format!("{} of {}", rep.simulated, rep.moves),
        ),
        (
            "Cutting moves / in air".into(),
            format!("{} / {}", rep.cutting_moves, rep.air_moves),
        ),
        (
            "Removed".into(),
            format!(
                "{:.1} mm³ of {:.1} mm³",
                rep.removed_mm3, rep.stock_before_mm3
            ),
        ),
        (
            "Highest removal rate".into(),
            format!(
                "{:.0} mm³/min (line {})",
                rep.max_mrr_mm3_min, rep.max_mrr_line
            ),
        ),
        ("Estimated time".into(), format!("{:.2} min", rep.minutes)),
        (
            "Rapid collisions".into(),
            rep.rapid_collisions.len().to_string(),
        ),
        (
            "Shank or holder collisions".into(),
            rep.holder_collisions.len().to_string(),
        ),
    ];
    let mut figures = Vec::new();
    if let Some(field) = crate::view3d::height_field(stock, part.map(|(_, m)| m)) {
        figures.push((
            format!(
                "The stock after the program in 3-D, coloured by {}.",
                field.scale.quantity
            ),
            crate::view3d::fragment("stock3d", &field),
        ));
    }
    if let Some((r, mesh)) = part {
        rows.push((
            "Material left on the part".into(),
            format!(
                "{:.3} to {:.3} mm, mean {:.3} ({} facets, {} cut into)",
                r.min, r.max, r.mean, r.facets, r.gouged
            ),
        ));
        let step = (mesh.len() / 20_000).max(1);
        let pts: Vec<(f64, f64, f64)> = (0..mesh.len())
            .step_by(step)
            .filter(|t| r.per_facet[*t].is_finite())
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                let q = (a + b + c) / 3.0;
                (q.x, q.y, r.per_facet[t])
            })
            .collect();
        figures.push((
            "The part from above, coloured by the material left on it (mm; negative: cut into)."
                .to_string(),
            svg::map("Material left on the part", "mm", &pts),
        ));
        let vals: Vec<f64> = r
            .per_facet
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        figures.push((
            "How much material is left, over the part's facets.".to_string(),
            svg::histogram("Material left", "mm", 30, &[("facets", "#1f77b4", vals)]),
        ));
    } else {
        figures.push((
            "The stock after the program, from above, coloured by height (mm).".to_string(),
            svg::map("Stock after the program", "z (mm)", &top_view(stock, 150)),
        ));
    }
    let mut t = 0.0;
    let mrr: Vec<(f64, f64)> = rep
        .per_move
        .iter()
        .map(|m| {
            t += m.minutes;
            (t, m.mrr)
        })
        .collect();
    figures.push((
        "Material removal rate along the program (rapids at 0).".to_string(),
        svg::line_plot(
            "Removal rate",
            "time (min)",
            "mm³/min",
            &[Series {
                name: "MRR",
                color: "#d62728",
                points: mrr,
            }],
        ),
    ));
    report_page(
        title,
        &intro,
        &Notes::judged(
            inputs,
            warnings,
            &sim_evidence(rep, part.map(|p| p.0)),
            verdict,
        ),
        &rows,
        &figures,
    )
}
