//! The reordering report: both orders side by side.

use crate::html::simple_report;
use crate::svg::{histogram, line_plot, map, Series};
use millplan_nc::Program;
use millplan_plan::reorder::{OrderIndicators, Outcome};

/// The XY of the cutting moves of the ball-end operations, in program order.
fn cutting_xy(p: &Program) -> Vec<(f64, f64)> {
    p.operations
        .iter()
        .filter(|o| {
            o.tool
                .as_ref()
                .and_then(|t| t.cutter)
                .is_some_and(|c| c.kind == millplan_nc::CutterKind::Ball)
        })
        .flat_map(|o| o.moves.iter().filter(|m| m.is_cutting() && !m.end.is_nan()))
        .map(|m| (m.end.x, m.end.y))
        .collect()
}

/// The rows of the summary table: each indicator, original → reordered.
pub fn rows(before: &OrderIndicators, after: &OrderIndicators) -> Vec<(String, String)> {
    let row = |k: &str, f: &dyn Fn(&OrderIndicators) -> String| {
        (k.to_string(), format!("{} → {}", f(before), f(after)))
    };
    vec![
        row("off the cutting speed (> 5 %)", &|v| {
            format!("{:.2} %", 100.0 * v.as_run.vc_deviation_share)
        }),
        row("Σ|Δn| as run (1/min)", &|v| {
            format!("{:.0}", v.as_run.total_variation_n)
        }),
        row("max |Δn| as run (1/min)", &|v| {
            format!("{:.0}", v.as_run.max_delta_n)
        }),
        row("time as run, estimated with acceleration (s)", &|v| {
            format!("{:.1}", v.as_run.time_s)
        }),
        row("successive |ΔD_w| max (mm)", &|v| {
            format!("{:.3}", v.delta_d_w.max)
        }),
        row("|ΔD_w| max across jumps (mm)", &|v| {
            format!("{:.3}", v.delta_d_w.max_across_jumps)
        }),
        row("successive |Δn| max (1/min)", &|v| {
            format!("{:.0}", v.delta_n.max)
        }),
        row("Σ|Δn| of targets (1/min)", &|v| {
            format!("{:.0}", v.total_variation_n)
        }),
        row("jumps (retract or long link)", &|v| v.jumps.to_string()),
        row("cutting length (mm)", &|v| format!("{:.0}", v.cutting_mm)),
        row("rapid length (mm)", &|v| format!("{:.0}", v.link_mm)),
        row("time at programmed feeds (s)", &|v| {
            format!("{:.0}", v.time_s)
        }),
    ]
}

/// The HTML page: indicators, D_w and spindle speed along both orders, the
/// distribution of successive changes and both tours from above.
pub fn reorder_report(original: &Program, reordered: &Program, o: &Outcome, vc: f64) -> String {
    let (blue, orange) = ("#1f77b4", "#ff7f0e");
    let along = |v: &[f64], f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
        v.iter()
            .enumerate()
            .map(|(k, d)| (k as f64, f(*d)))
            .collect()
    };
    let speed = |d: f64| millplan_models::wd::spindle_speed(vc, d);
    // Successive changes between points cut one after the other.
    let steps = |v: &[f64], jump: &[bool]| -> Vec<f64> {
        (1..v.len())
            .filter(|&k| !jump.get(k).copied().unwrap_or(false))
            .map(|k| (v[k] - v[k - 1]).abs())
            .collect()
    };
    let tour = |xy: Vec<(f64, f64)>| -> Vec<(f64, f64, f64)> {
        let n = xy.len().max(1) as f64;
        xy.into_iter()
            .enumerate()
            .map(|(k, (x, y))| (x, y, k as f64 / n))
            .collect()
    };
    let figures = vec![
        (
            "Working diameter at each cutting point, in cutting order: the original order (blue) and the reordered one (orange).".to_string(),
            line_plot(
                "Working diameter along the path",
                "point in cutting order",
                "D_w (mm)",
                &[
                    Series { name: "original", color: blue, points: along(&o.dw_original, &|d| d) },
                    Series { name: "reordered", color: orange, points: along(&o.dw_reordered, &|d| d) },
                ],
            ),
        ),
        (
            format!("Spindle speed for a constant cutting speed of {vc} m/min (before machine limits), in cutting order."),
            line_plot(
                "Spindle speed along the path",
                "point in cutting order",
                "n (1/min)",
                &[
                    Series { name: "original", color: blue, points: along(&o.dw_original, &speed) },
                    Series { name: "reordered", color: orange, points: along(&o.dw_reordered, &speed) },
                ],
            ),
        ),
        (
            "Change of working diameter between points cut one after the other (steps across a retract or long link left out: the spindle has time there).".to_string(),
            histogram(
                "Successive |ΔD_w|",
                "|ΔD_w| (mm)",
                40,
                &[
                    ("original", blue, steps(&o.dw_original, &o.jump_original)),
                    ("reordered", orange, steps(&o.dw_reordered, &o.jump_reordered)),
                ],
            ),
        ),
        (
            "The original order seen from above, coloured from the first cutting point (0) to the last (1).".to_string(),
            map("Original order", "order", &tour(cutting_xy(original))),
        ),
        (
            "The reordered path seen from above, coloured from the first cutting point (0) to the last (1).".to_string(),
            map("Reordered", "order", &tour(cutting_xy(reordered))),
        ),
    ];
    simple_report(
        "Toolpath reordering",
        "Paper 000, thesis 5: cutting points reordered so the working diameter, and with it the spindle speed for a constant cutting speed, changes as little as possible between successive points. Original → reordered.",
        &rows(&o.before, &o.after),
        &figures,
    )
}
