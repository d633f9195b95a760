//! The reordering report: its inputs, the warnings, the verdict in words and
//! both orders side by side.

use crate::html::{
    limit_line, report_page, speed_inputs_rows, worse_words, Evidence, Notes, SpeedInputs,
    TIME_WORSE,
};
use crate::svg::{histogram, line_plot, map, Series};
use millplan_nc::Program;
use millplan_plan::reorder::{OrderIndicators, Outcome, Verdict};

/// What a reordering report was made from: the files, tool, machine and
/// cutting data of its spindle control (`run`; its `warnings` the findings
/// about the inputs, a mesh's defects say) and the method's name.
#[derive(Clone, Debug, Default)]
pub struct ReorderInputs {
    pub run: SpeedInputs,
    pub method: String,
}

/// Above this share of rate-limited points the report warns: there the
/// spindle cannot follow the speeds the order asks for.
pub const RATE_LIMITED_WARNING: f64 = 0.05;

fn share(n: usize, of: usize) -> f64 {
    if of == 0 {
        0.0
    } else {
        n as f64 / of as f64
    }
}

/// `a → b` with the relative change, in the unit given.
fn change(a: f64, b: f64, decimals: usize, unit: &str) -> String {
    let pct = if a.abs() > 1e-12 {
        format!(" ({:+.1} %)", 100.0 * (b - a) / a)
    } else {
        String::new()
    };
    format!("{a:.decimals$} → {b:.decimals$}{unit}{pct}")
}

/// The report's warnings and verdict in words: whether the order was improved
/// or kept and by how much (time, Σ|Δn|, the share off the cutting speed, all
/// as the machine will run it), and what to look at.
pub fn reorder_notes(o: &Outcome, i: &ReorderInputs) -> Notes {
    let (b, a) = (&o.before.as_run, &o.after.as_run);
    let mut warnings = i.run.warnings.clone();
    if let Some(d) =
        millplan_plan::checks::off_surface_points(b.off_surface, b.no_contact, b.points)
    {
        warnings.push(d.message);
    }
    let limited = share(a.rate_limited, a.points);
    if limited > RATE_LIMITED_WARNING {
        warnings.push(format!(
            "{} of {} points ({:.1} %) wait for the spindle's acceleration of {:.0} 1/min/s in the written order: the cutting speed misses its target there",
            a.rate_limited,
            a.points,
            100.0 * limited,
            i.run.spindle_accel
        ));
    }
    let measures = format!(
        "points off the cutting speed by more than 5 % {:.1} % → {:.1} %, Σ|Δn| {}, time {}, estimated with acceleration as the machine will run it with spindle control",
        100.0 * b.vc_deviation_share,
        100.0 * a.vc_deviation_share,
        change(b.total_variation_n, a.total_variation_n, 0, " 1/min"),
        change(b.time_s, a.time_s, 1, " s")
    );
    let tried = o.tried.len().saturating_sub(1);
    let mut verdict = vec![match o.verdict {
        Some(Verdict::Improved) => format!(
            "Improved: of {tried} candidate orders measured, the one written is worse than the original on no measure and better on at least one: {measures}."
        ),
        Some(Verdict::Kept) => format!(
            "Kept: none of the {tried} candidate orders measured runs better without running worse on another measure, so the original order is written as it was: {:.1} % of the points off the cutting speed by more than 5 %, Σ|Δn| {:.0} 1/min, {:.1} s as the machine will run it.",
            100.0 * b.vc_deviation_share,
            b.total_variation_n,
            b.time_s
        ),
        None => format!("Reordered by the {} method: {measures}.", i.method),
    }];
    if o.verdict != Some(Verdict::Kept) {
        verdict.push(format!(
            "{} links are direct (proven gouge-free by the drop-cutter), {} retract, rapid and plunge.",
            o.stats.direct_links, o.stats.retracts
        ));
    }
    let evidence = reorder_evidence(o);
    if !evidence.worse.is_empty() && o.verdict.is_none() {
        verdict.push(
            "Compare with the default method (as-run) before using it: it never writes an order worse on any of these measures."
                .to_string(),
        );
    }
    if !warnings.is_empty() {
        verdict.push("Look at the warnings above before using the program.".to_string());
    } else if a.rate_limited > 0 {
        verdict.push(format!(
            "Look at the spindle-speed plot where the targets change fastest or leave the range {:.0}–{:.0} 1/min: there the machine limits the speed ({:.1} % of the points wait for its acceleration).",
            i.run.spindle.0,
            i.run.spindle.1,
            100.0 * limited
        ));
    }
    let mut inputs = speed_inputs_rows(&i.run);
    inputs.push(("method".into(), i.method.clone()));
    Notes::judged(inputs, warnings, &evidence, verdict)
}

/// What the reordering verdict is decided from: kept when the original
/// order is written; worse on each of the measures the pass exists for
/// (the share off the cutting speed, Σ|Δn|, the time as the machine runs
/// it) that grew.
pub fn reorder_evidence(o: &Outcome) -> Evidence {
    let (b, a) = (&o.before.as_run, &o.after.as_run);
    let mut e = Evidence {
        kept: o.verdict == Some(Verdict::Kept),
        ..Evidence::default()
    };
    if a.vc_deviation_points > b.vc_deviation_points {
        e.worse.push(worse_words(
            "points off the cutting speed",
            100.0 * b.vc_deviation_share,
            100.0 * a.vc_deviation_share,
            1,
            "%",
        ));
    }
    if a.total_variation_n > b.total_variation_n * (1.0 + 1e-9) {
        e.worse.push(worse_words(
            "Σ|Δn|",
            b.total_variation_n,
            a.total_variation_n,
            0,
            "1/min",
        ));
    }
    if a.max_delta_n > b.max_delta_n * (1.0 + 1e-9) {
        e.worse.push(worse_words(
            "max |Δn|",
            b.max_delta_n,
            a.max_delta_n,
            0,
            "1/min",
        ));
    }
    if a.time_s > b.time_s * (1.0 + TIME_WORSE) {
        e.worse
            .push(worse_words("time", b.time_s, a.time_s, 1, "s"));
    }
    e
}

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
pub fn reorder_report(
    original: &Program,
    reordered: &Program,
    o: &Outcome,
    i: &ReorderInputs,
) -> String {
    let vc = i.run.vc;
    let longest = o.dw_original.len().max(o.dw_reordered.len());
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
            format!("Spindle speed for a constant cutting speed of {vc} m/min (before machine limits), in cutting order, with the machine's spindle range."),
            line_plot(
                "Spindle speed along the path",
                "point in cutting order",
                "n (1/min)",
                &[
                    Series { name: "original", color: blue, points: along(&o.dw_original, &speed) },
                    Series { name: "reordered", color: orange, points: along(&o.dw_reordered, &speed) },
                    Series { name: "spindle maximum", color: "#c62828", points: limit_line(longest, i.run.spindle.1) },
                    Series { name: "spindle minimum", color: "#8e24aa", points: limit_line(longest, i.run.spindle.0) },
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
    report_page(
        "Toolpath reordering",
        "Paper 000, thesis 5: cutting points reordered so the working diameter, and with it the spindle speed for a constant cutting speed, changes as little as possible between successive points. Original → reordered.",
        &reorder_notes(o, i),
        &rows(&o.before, &o.after),
        &figures,
    )
}
