//! Self-contained HTML report of the spindle-speed pass: SVG plots of D_w and n
//! along the path and against position (as the paper's figures 2-7 to 2-10), a
//! histogram of the cutting speed with and without control, a top-view map coloured
//! by D_w, and the summary table. No scripts, no network.

use crate::svg::{histogram, line_plot, map, scatter, Series};
use millplan_plan::speed::{PointRow, Summary};
use std::fmt::Write;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The report page.
pub fn speed_report(title: &str, s: &Summary, rows: &[PointRow], vc: f64) -> String {
    let pi = std::f64::consts::PI;
    let idx = |f: &dyn Fn(&PointRow) -> f64| {
        rows.iter()
            .enumerate()
            .map(|(i, r)| (i as f64, f(r)))
            .collect::<Vec<_>>()
    };
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title><style>\
         body{{font-family:sans-serif;margin:24px;max-width:1100px;color:#222}}\
         table{{border-collapse:collapse;margin:8px 0 20px}}td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}\
         th{{background:#f4f4f4}}td:first-child{{text-align:left}}figure{{margin:10px 0 24px}}</style></head><body>\
         <h1>{t}</h1><p>Constant cutting speed vc = {vc} m/min by per-point spindle speed n = 1000·vc/(π·D<sub>w</sub>).</p>",
        t = esc(title)
    );
    let row = |h: &mut String, name: &str, v: String| {
        let _ = write!(h, "<tr><td>{}</td><td>{v}</td></tr>", esc(name));
    };
    h.push_str("<h2>Summary</h2><table>");
    row(&mut h, "cutting points analysed", s.points.to_string());
    row(&mut h, "ball-end operations", s.operations.to_string());
    row(&mut h, "CL point convention", format!("{:?}", s.convention));
    row(
        &mut h,
        "working diameter D_w min / mean / max (mm)",
        format!(
            "{:.3} / {:.3} / {:.3} (σ {:.3})",
            s.d_w.min, s.d_w.mean, s.d_w.max, s.d_w.std
        ),
    );
    row(
        &mut h,
        "spindle speed min / mean / max (1/min)",
        format!(
            "{:.0} / {:.0} / {:.0}",
            s.spindle.min, s.spindle.mean, s.spindle.max
        ),
    );
    row(
        &mut h,
        "cutting speed without control (m/min)",
        format!(
            "{:.1} … {:.1} (σ {:.2}) at n = {:.0}",
            s.vc_constant.min, s.vc_constant.max, s.vc_constant.std, s.constant_spindle
        ),
    );
    row(
        &mut h,
        "cutting speed with control (m/min)",
        format!(
            "{:.1} … {:.1} (σ {:.2})",
            s.vc_controlled.min, s.vc_controlled.max, s.vc_controlled.std
        ),
    );
    row(
        &mut h,
        "points clamped to the spindle range",
        s.clamped.to_string(),
    );
    row(
        &mut h,
        "points rate-limited by spindle acceleration",
        s.rate_limited.to_string(),
    );
    row(
        &mut h,
        "points held below the S threshold",
        s.held.to_string(),
    );
    row(
        &mut h,
        "feeds clamped to the feed range",
        s.feed_clamped.to_string(),
    );
    row(
        &mut h,
        "points off the surface (gap flagged)",
        s.gap_flagged.to_string(),
    );
    row(
        &mut h,
        "total variation Σ|Δn| (1/min)",
        format!(
            "{:.0} (targets {:.0})",
            s.indicators.total_variation, s.indicators_target.total_variation
        ),
    );
    row(
        &mut h,
        "max |Δn| between points (1/min)",
        format!(
            "{:.0} (targets {:.0})",
            s.indicators.max_step, s.indicators_target.max_step
        ),
    );
    row(
        &mut h,
        "spindle acceleration demand max / mean (1/min/s)",
        format!(
            "{:.0} / {:.0}",
            s.indicators.max_accel, s.indicators.mean_accel
        ),
    );
    row(
        &mut h,
        "∫ n ds ((1/min)·mm)",
        format!("{:.4e}", s.indicators.speed_integral),
    );
    h.push_str("</table>");
    let fig = |h: &mut String, svg: String, cap: &str| {
        let _ = write!(
            h,
            "<figure>{svg}<figcaption>{}</figcaption></figure>",
            esc(cap)
        );
    };
    fig(
        &mut h,
        line_plot(
            "Working diameter along the path",
            "cutting point",
            "mm",
            &[
                Series {
                    name: "D_w",
                    color: "#1f77b4",
                    points: idx(&|r| r.r.dw),
                },
                Series {
                    name: "D_cc = D·sin α",
                    color: "#aaa",
                    points: idx(&|r| r.r.dw.min(r.d * r.r.inclination.sin())),
                },
            ],
        ),
        "D_w at every cutting point, in cutting order (paper figure 2-7 style).",
    );
    fig(
        &mut h,
        line_plot(
            "Spindle speed along the path",
            "cutting point",
            "1/min",
            &[
                Series {
                    name: "target 1000·vc/(π·D_w)",
                    color: "#ff7f0e",
                    points: idx(&|r| r.n_target),
                },
                Series {
                    name: "written (range, rate, threshold)",
                    color: "#2ca02c",
                    points: idx(&|r| r.n),
                },
            ],
        ),
        "Spindle speed per point: target and what the program commands.",
    );
    fig(
        &mut h,
        scatter(
            "Working diameter against X",
            "X (mm)",
            "D_w (mm)",
            "#1f77b4",
            &rows
                .iter()
                .map(|r| (r.r.contact.x, r.r.dw))
                .collect::<Vec<_>>(),
        ),
        "D_w against position (paper figures 2-8 to 2-10 style).",
    );
    fig(
        &mut h,
        histogram(
            "Cutting speed at the highest engaged point",
            "vc (m/min)",
            40,
            &[
                (
                    "constant spindle speed",
                    "#d62728",
                    rows.iter()
                        .map(|r| pi * r.r.dw * s.constant_spindle / 1000.0)
                        .collect(),
                ),
                (
                    "with spindle control",
                    "#2ca02c",
                    rows.iter().map(|r| pi * r.r.dw * r.n / 1000.0).collect(),
                ),
            ],
        ),
        "How evenly the surface is cut: without control the cutting speed follows D_w.",
    );
    fig(
        &mut h,
        map(
            "Top view coloured by D_w",
            "D_w mm",
            &rows
                .iter()
                .map(|r| (r.r.contact.x, r.r.contact.y, r.r.dw))
                .collect::<Vec<_>>(),
        ),
        "Contact points seen from above, coloured by working diameter.",
    );
    let _ = write!(
        h,
        "<h2>Run data</h2><pre>{}</pre></body></html>",
        esc(&serde_json::to_string_pretty(s).unwrap_or_default())
    );
    h
}

/// A plain report page: a title, an introduction, a summary table and figures
/// (SVG with captions). No scripts, no network.
pub fn simple_report(
    title: &str,
    intro: &str,
    rows: &[(String, String)],
    figures: &[(String, String)],
) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title><style>\
         body{{font-family:sans-serif;margin:24px;max-width:1100px;color:#222}}\
         table{{border-collapse:collapse;margin:8px 0 20px}}td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}\
         td:first-child{{text-align:left}}figure{{margin:10px 0 24px}}</style></head><body><h1>{t}</h1><p>{i}</p><h2>Summary</h2><table>",
        t = esc(title),
        i = esc(intro)
    );
    for (k, v) in rows {
        let _ = write!(h, "<tr><td>{}</td><td>{}</td></tr>", esc(k), esc(v));
    }
    h.push_str("</table>");
    for (caption, svg) in figures {
        let _ = write!(
            h,
            "<figure>{svg}<figcaption>{}</figcaption></figure>",
            esc(caption)
        );
    }
    h.push_str("</body></html>");
    h
}
