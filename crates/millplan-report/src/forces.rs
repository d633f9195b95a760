//! The per-move force table and the report of `millplan force` and
//! `millplan feed`: loads against time with the limits drawn.

use crate::html::{report_page, Notes};
use crate::svg::{line_plot, Series};
use millplan_plan::force::MoveForces;
use std::fmt::Write;

/// One CSV row per simulated move.
pub fn moves_csv(moves: &[MoveForces]) -> String {
    let mut s = String::from(
        "index,line,t_s,rapid,air,unmodelled,rpm,feed,fz,lead_deg,cells,removed_mm3,fxy_max,fx_min,fx_max,fy_min,fy_max,fz_min,fz_max,torque_max,torque_mean,power_w,stress_mpa,deflection_mm,fz_allowed,binding\n",
    );
    for m in moves {
        let _ = writeln!(
            s,
            "{},{},{:.4},{},{},{},{:.1},{:.2},{:.5},{:.2},{},{:.5},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.6},{},{}",
            m.index, m.line, m.t_start_s, m.rapid, m.air, m.unmodelled, m.rpm, m.feed, m.fz,
            m.lead_deg, m.cells, m.removed_mm3, m.fxy_max, m.fx[0], m.fx[1], m.fy[0], m.fy[1],
            m.fz_force[0], m.fz_force[1], m.torque_max, m.torque_mean, m.power_w, m.stress_mpa,
            m.deflection_mm,
            m.fz_allowed.map(|f| format!("{f:.5}")).unwrap_or_default(),
            m.binding.unwrap_or("")
        );
    }
    s
}

/// A quantity's limit at one move.
pub type LimitFn<'a> = Box<dyn Fn(&MoveForces) -> Option<f64> + 'a>;

/// One quantity to plot: its name, unit, value per move and its limit per
/// move (`None`: not limited there).
pub struct Quantity<'a> {
    pub name: &'a str,
    pub unit: &'a str,
    pub value: fn(&MoveForces) -> f64,
    pub limit: LimitFn<'a>,
}

/// The report: a summary table and, per quantity, its value over time for
/// each run (`runs`: name and moves, e.g. before and after) with its limit.
pub fn report(
    title: &str,
    intro: &str,
    notes: &Notes,
    rows: &[(String, String)],
    runs: &[(&str, &[MoveForces])],
    quantities: &[Quantity],
) -> String {
    const COLORS: [&str; 3] = ["#1f77b4", "#d62728", "#2ca02c"];
    let figures: Vec<(String, String)> = quantities
        .iter()
        .map(|q| {
            let mut series: Vec<Series> = runs
                .iter()
                .zip(COLORS)
                .map(|((name, moves), color)| Series {
                    name,
                    color,
                    points: moves
                        .iter()
                        .filter(|m| !m.rapid)
                        .map(|m| (m.t_start_s, (q.value)(m)))
                        .collect(),
                })
                .collect();
            if let Some((_, moves)) = runs.first() {
                let lim: Vec<(f64, f64)> = moves
                    .iter()
                    .filter(|m| !m.rapid)
                    .filter_map(|m| (q.limit)(m).map(|l| (m.t_start_s, l)))
                    .collect();
                if !lim.is_empty() {
                    series.push(Series {
                        name: "limit",
                        color: "#000000",
                        points: lim,
                    });
                }
            }
            let ylabel = format!("{} [{}]", q.name, q.unit);
            (
                format!("{} along the program", q.name),
                line_plot(
                    &format!("{} per move", q.name),
                    "time [s]",
                    &ylabel,
                    &series,
                ),
            )
        })
        .collect();
    report_page(title, intro, notes, rows, &figures)
}
