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

/// What a spindle-control report was made from, shown in its header.
#[derive(Clone, Debug, Default)]
pub struct SpeedInputs {
    /// The program's file name.
    pub program: String,
    /// The part's file name.
    pub part: String,
    /// The tool, as the program names it (`T1 BALL D10`).
    pub tool: String,
    /// The machine's name.
    pub machine: String,
    /// Spindle range (min, max), 1/min.
    pub spindle: (f64, f64),
    /// Spindle acceleration, 1/min per second.
    pub spindle_accel: f64,
    /// Largest feed, mm/min.
    pub feed_max: f64,
    /// Cutting speed asked for, m/min.
    pub vc: f64,
    /// Feed per tooth, mm.
    pub fz: f64,
    pub flutes: u32,
    /// Stock along the normal, mm.
    pub ap: f64,
    /// Time of the program before and after spindle control (feeds at
    /// F = n·z·fz unless kept), s.
    pub time_before_s: Option<f64>,
    pub time_after_s: Option<f64>,
    /// Findings about the inputs (off-surface points, mesh defects), shown
    /// in the warning box at the top.
    pub warnings: Vec<String>,
    /// The checks of the written program that failed (it is written only
    /// under `--force`), each in words ([`failed_checks`]).
    pub failed: Vec<String>,
}

/// A time that grew by more than this share counts as worse in a verdict
/// (below it: the estimate's rounding).
pub const TIME_WORSE: f64 = 0.005;

/// `before → after unit (±x %)` of a measure that got worse, for a verdict.
pub fn worse_words(name: &str, before: f64, after: f64, decimals: usize, unit: &str) -> String {
    let pct = if before.abs() > 1e-12 {
        format!(" ({:+.1} %)", 100.0 * (after - before) / before)
    } else {
        String::new()
    };
    format!("{name} {before:.decimals$} → {after:.decimals$} {unit}{pct}")
}

/// What the spindle-control verdict is decided from: the pass kept the
/// input when it found no ball-end point to act on; worse when more points
/// miss the cutting speed than at the program's constant speed, or the time
/// grew.
pub fn speed_evidence(s: &Summary, failed: &[String], times: [Option<f64>; 2]) -> Evidence {
    let mut e = Evidence {
        failed: failed.to_vec(),
        kept: s.points == 0,
        ..Evidence::default()
    };
    let before = 100.0 * s.vc_constant_deviation_share;
    let after = 100.0 * s.vc_deviation_share;
    if after > before {
        e.worse.push(worse_words(
            "points off the cutting speed",
            before,
            after,
            1,
            "%",
        ));
    }
    if let [Some(b), Some(a)] = times {
        if a > b * (1.0 + TIME_WORSE) {
            e.worse.push(worse_words("cycle time", b, a, 1, "s"));
        }
    }
    e
}

/// The verdict in words: what changed, what it buys, what to look at.
pub fn speed_verdict(i: &SpeedInputs, s: &Summary) -> Vec<String> {
    let pct = |n: usize| {
        if s.points == 0 {
            0.0
        } else {
            100.0 * n as f64 / s.points as f64
        }
    };
    let mut v = Vec::new();
    let before = 100.0 * s.vc_constant_deviation_share;
    let after = 100.0 * s.vc_deviation_share;
    v.push(format!(
        "Spindle control keeps the cutting speed within 5 % of {} m/min at {:.1} % of the {} points, against {:.1} % at the program's constant {:.0} 1/min (cutting speed {:.1}–{:.1} m/min there).",
        i.vc,
        100.0 - after,
        s.points,
        100.0 - before,
        s.constant_spindle,
        s.vc_constant.min,
        s.vc_constant.max
    ));
    if s.rate_limited > 0 || s.clamped > 0 {
        v.push(format!(
            "The machine limits it: {} points ({:.1} %) wait for the spindle's acceleration of {:.0} 1/min/s and {} ({:.1} %) are clamped to its range {:.0}–{:.0} 1/min; that is why the cutting speed still spans {:.1}–{:.1} m/min with control.",
            s.rate_limited,
            pct(s.rate_limited),
            i.spindle_accel,
            s.clamped,
            pct(s.clamped),
            i.spindle.0,
            i.spindle.1,
            s.vc_controlled.min,
            s.vc_controlled.max
        ));
    }
    if let (Some(b), Some(a)) = (i.time_before_s, i.time_after_s) {
        let d = a - b;
        v.push(format!(
            "Cycle time {:.0} s → {:.0} s ({}{:.0} s, {:+.1} %) at the feeds written, estimated with acceleration.",
            b,
            a,
            if d >= 0.0 { "+" } else { "−" },
            d.abs(),
            if b > 0.0 { 100.0 * d / b } else { 0.0 }
        ));
    }
    if !i.warnings.is_empty() {
        v.push("Look at the warnings above before using the program.".to_string());
    } else if s.rate_limited > 0 {
        v.push("Look at the spindle-speed plot where the written speed leaves its target: there a higher spindle acceleration, or an order that changes D_w less (millplan reorder), would help.".to_string());
    }
    v
}

/// The header rows of a run with spindle control: the files, the tool, the
/// machine's limits and the cutting data.
pub fn speed_inputs_rows(i: &SpeedInputs) -> Vec<(String, String)> {
    vec![
        ("program".into(), i.program.clone()),
        ("part".into(), i.part.clone()),
        ("tool".into(), i.tool.clone()),
        (
            "machine".into(),
            format!(
                "{}: spindle {:.0}–{:.0} 1/min, acceleration {:.0} 1/min/s, feed up to {:.0} mm/min",
                i.machine, i.spindle.0, i.spindle.1, i.spindle_accel, i.feed_max
            ),
        ),
        (
            "cutting data".into(),
            format!(
                "vc {} m/min, fz {} mm, {} flutes, ap {} mm",
                i.vc, i.fz, i.flutes, i.ap
            ),
        ),
    ]
}

/// The table of a report's inputs (left out when there are none).
fn inputs_table(h: &mut String, rows: &[(String, String)]) {
    if rows.is_empty() {
        return;
    }
    h.push_str("<table class=\"inputs\" id=\"inputs\">");
    for (k, v) in rows {
        let _ = write!(h, "<tr><th>{}</th><td>{}</td></tr>", esc(k), esc(v));
    }
    h.push_str("</table>");
}

/// The report page: a header with its inputs, the warnings in a box, the
/// verdict in words, the summary table and the plots with the machine's
/// limits drawn.
pub fn speed_report(title: &str, i: &SpeedInputs, s: &Summary, rows: &[PointRow]) -> String {
    let vc = i.vc;
    let pi = std::f64::consts::PI;
    let idx = |f: &dyn Fn(&PointRow) -> f64| {
        rows.iter()
            .enumerate()
            .map(|(i, r)| (i as f64, f(r)))
            .collect::<Vec<_>>()
    };
    let mut h = page_start(title);
    let _ = write!(
        h,
        "<p>Constant cutting speed vc = {vc} m/min by per-point spindle speed n = 1000·vc/(π·D<sub>w</sub>).</p>"
    );
    notes(
        &mut h,
        &Notes::judged(
            speed_inputs_rows(i),
            i.warnings.clone(),
            &speed_evidence(s, &i.failed, [i.time_before_s, i.time_after_s]),
            speed_verdict(i, s),
        ),
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
        "points off the cutting speed by more than 5 % (%)",
        format!(
            "{:.1} with control, {:.1} at the constant speed",
            100.0 * s.vc_deviation_share,
            100.0 * s.vc_constant_deviation_share
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
                Series {
                    name: "spindle maximum",
                    color: "#c62828",
                    points: limit_line(rows.len(), i.spindle.1),
                },
                Series {
                    name: "spindle minimum",
                    color: "#8e24aa",
                    points: limit_line(rows.len(), i.spindle.0),
                },
            ],
        ),
        "Spindle speed per point: target, what the program commands, and the machine's range.",
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
    h.push_str("</body></html>");
    h
}

/// A horizontal line at `y` across `n` points, for a machine limit.
pub(crate) fn limit_line(n: usize, y: f64) -> Vec<(f64, f64)> {
    vec![(0.0, y), (n.saturating_sub(1) as f64, y)]
}

/// How a verdict reads at a glance; one rule ([`Level::of`]) for every
/// report and text summary.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Level {
    /// Every check passed and the result is better by the measures its
    /// pass exists for, with no warning.
    #[default]
    Green,
    /// The input was kept (nothing measured better, or nothing to act on),
    /// a warning applies, or a measure got worse.
    Amber,
    /// A check failed.
    Red,
}

/// What a verdict is decided from.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Evidence {
    /// The checks that failed, each in words (what and how much).
    pub failed: Vec<String>,
    /// The result is the input as it was, or there was nothing to act on.
    pub kept: bool,
    /// The measures a pass exists for that got worse, each in words
    /// (`cycle time 10.0 → 10.2 s`).
    pub worse: Vec<String>,
    /// The program written differs from the input, yet no measure got
    /// better (and none worse): the figures in words.
    pub not_better: Option<String>,
}

impl Level {
    /// The one rule: red when a check failed; amber when the input was kept,
    /// a warning applies or a measure got worse; green otherwise.
    pub fn of(e: &Evidence, warnings: usize) -> Level {
        if !e.failed.is_empty() {
            Level::Red
        } else if e.kept || warnings > 0 || !e.worse.is_empty() || e.not_better.is_some() {
            Level::Amber
        } else {
            Level::Green
        }
    }

    /// The level's name as text and JSON print it.
    pub fn name(self) -> &'static str {
        match self {
            Level::Green => "green",
            Level::Amber => "amber",
            Level::Red => "red",
        }
    }

    /// (border, background) colours of the verdict box.
    fn colours(self) -> (&'static str, &'static str) {
        match self {
            Level::Green => ("#2e7d32", "#f1f8e9"),
            Level::Amber => ("#ef8f00", "#fff8e1"),
            Level::Red => ("#c62828", "#fdecea"),
        }
    }
}

/// The verdict's first sentence: its level and why, naming what failed and
/// what got worse.
pub fn headline(e: &Evidence, warnings: usize) -> String {
    let level = Level::of(e, warnings);
    let mut why = Vec::new();
    if !e.failed.is_empty() {
        why.push(format!("failed: {}", e.failed.join("; ")));
    }
    if !e.worse.is_empty() {
        why.push(format!("worse: {}", e.worse.join("; ")));
    }
    if let Some(n) = &e.not_better {
        why.push(format!("changed, but {n}"));
    }
    if e.kept {
        why.push("the input is kept as it was".to_string());
    }
    match warnings {
        0 => {}
        1 => why.push("a warning applies".to_string()),
        n => why.push(format!("{n} warnings apply")),
    }
    if why.is_empty() {
        why.push("every check passed and the result is better by its measures".to_string());
    }
    let name = level.name();
    let mut first = name.chars();
    let cap: String = first
        .next()
        .map(|c| c.to_ascii_uppercase())
        .into_iter()
        .chain(first)
        .collect();
    format!("{cap}: {}.", why.join("; "))
}

/// A verdict as the terminal and `--json` print it, by the same rule and in
/// the same words as a report's verdict box: the level, the headline
/// ([`headline`]), what failed, what got worse and the warnings.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Verdict {
    pub level: Level,
    /// The headline: level and why (`Amber: worse: cycle time …`).
    pub summary: String,
    pub failed: Vec<String>,
    pub worse: Vec<String>,
    /// The input was kept, or there was nothing to act on.
    pub kept: bool,
    pub warnings: Vec<String>,
}

impl Verdict {
    /// The verdict of `e` with `warnings`, by [`Level::of`].
    pub fn of(e: &Evidence, warnings: Vec<String>) -> Verdict {
        Verdict {
            level: Level::of(e, warnings.len()),
            summary: headline(e, warnings.len()),
            failed: e.failed.clone(),
            worse: e.worse.clone(),
            kept: e.kept,
            warnings,
        }
    }

    /// The verdict's lines in a text summary: each warning, then
    /// `verdict: LEVEL: why.`
    pub fn text(&self) -> String {
        let mut o = String::new();
        for w in &self.warnings {
            let _ = writeln!(o, "warning: {w}");
        }
        let _ = writeln!(o, "verdict: {}", self.summary);
        o
    }
}

/// The failed checks of a written program in words, for a verdict: the
/// check's name and its first finding that is not the input's own, at its
/// line; of a check that failed only for the input's own faults, the first
/// of those, marked so.
pub fn failed_checks(checks: &[millplan_plan::safety::Check]) -> Vec<String> {
    checks
        .iter()
        .filter(|c| !c.ok)
        .map(|c| {
            let new = c.refusing().find(|f| !f.in_input);
            let (f, own) = match new {
                Some(f) => (Some(f), ""),
                None => (c.refusing().next(), " (the input's own fault)"),
            };
            match f {
                Some(f) => match f.line {
                    Some(line) => {
                        format!("check {} at line {line}: {}{own}", c.name, f.message)
                    }
                    None => format!("check {}: {}{own}", c.name, f.message),
                },
                None => format!("check {}", c.name),
            }
        })
        .collect()
}

/// What a report says before its tables: the inputs it was made from (a
/// header table), warnings (shown in a red box: what to look at before using
/// the result) and a verdict: its level by the one rule, then in words (what
/// changed and what it buys). Any may be empty.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Notes {
    /// Header rows: name, value (files, tool, machine limits, cutting data).
    pub inputs: Vec<(String, String)>,
    pub warnings: Vec<String>,
    /// The verdict's level, from [`Level::of`] (see [`Notes::judged`]).
    pub level: Level,
    pub verdict: Vec<String>,
}

impl Notes {
    /// Notes whose verdict is decided from `evidence` and the warnings: the
    /// level, then [`headline`], then the words of `verdict`.
    pub fn judged(
        inputs: Vec<(String, String)>,
        warnings: Vec<String>,
        evidence: &Evidence,
        verdict: Vec<String>,
    ) -> Notes {
        Notes::of_verdict(inputs, &Verdict::of(evidence, warnings), verdict)
    }

    /// Notes showing `v` (its warnings, level and headline), then the words
    /// of `verdict`.
    pub fn of_verdict(inputs: Vec<(String, String)>, v: &Verdict, verdict: Vec<String>) -> Notes {
        let mut lines = vec![v.summary.clone()];
        lines.extend(verdict);
        Notes {
            inputs,
            warnings: v.warnings.clone(),
            level: v.level,
            verdict: lines,
        }
    }
}

/// The page's head (style, title) up to the heading.
fn page_start(title: &str) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title><style>\
         body{{font-family:sans-serif;margin:24px;max-width:1100px;color:#222}}\
         table{{border-collapse:collapse;margin:8px 0 20px}}td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}\
         th{{background:#f4f4f4}}td:first-child{{text-align:left}}figure{{margin:10px 0 24px}}\
         table.inputs th{{text-align:left}}table.inputs td{{text-align:left}}\
         .warnings{{border:2px solid #c62828;background:#fdecea;padding:8px 14px;margin:12px 0}}\
         .verdict{{border-left:4px solid #2e7d32;background:#f1f8e9;padding:8px 14px;margin:12px 0}}</style></head><body>\
         <h1>{t}</h1>",
        t = esc(title)
    );
    h
}

/// The inputs, the warnings box and the verdict (each left out when empty).
fn notes(h: &mut String, n: &Notes) {
    inputs_table(h, &n.inputs);
    if !n.warnings.is_empty() {
        h.push_str(
            "<div class=\"warnings\" id=\"warnings\" role=\"alert\"><strong>Warnings</strong><ul>",
        );
        for w in &n.warnings {
            let _ = write!(h, "<li>{}</li>", esc(w));
        }
        h.push_str("</ul></div>");
    }
    if !n.verdict.is_empty() {
        let (border, background) = n.level.colours();
        let _ = write!(
            h,
            "<div class=\"verdict {name}\" id=\"verdict\" data-level=\"{name}\" style=\"border-left-color:{border};background:{background}\"><strong>Verdict: {name}</strong>",
            name = n.level.name()
        );
        for p in &n.verdict {
            let _ = write!(h, "<p>{}</p>", esc(p));
        }
        h.push_str("</div>");
    }
}

/// A plain report page: a title, an introduction, a summary table and figures
/// (SVG with captions). No scripts, no network.
pub fn simple_report(
    title: &str,
    intro: &str,
    rows: &[(String, String)],
    figures: &[(String, String)],
) -> String {
    report_page(title, intro, &Notes::default(), rows, figures)
}

/// A report page with warnings and a verdict above its summary table and
/// figures.
pub fn report_page(
    title: &str,
    intro: &str,
    n: &Notes,
    rows: &[(String, String)],
    figures: &[(String, String)],
) -> String {
    let mut h = page_start(title);
    let _ = write!(h, "<p>{}</p>", esc(intro));
    notes(&mut h, n);
    h.push_str("<h2>Summary</h2><table>");
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

#[cfg(test)]
mod verdict_tests {
    use super::*;

    /// The one rule: red on a failed check whatever else holds; amber on a
    /// kept input, a warning or a worse measure; green only without any.
    #[test]
    fn the_level_follows_the_one_rule() {
        let e = |failed: bool, kept: bool, worse: bool| Evidence {
            failed: if failed {
                vec!["check gouge".into()]
            } else {
                vec![]
            },
            kept,
            worse: if worse {
                vec!["time 1 → 2 s".into()]
            } else {
                vec![]
            },
            not_better: None,
        };
        assert_eq!(Level::of(&e(false, false, false), 0), Level::Green);
        assert_eq!(Level::of(&e(false, true, false), 0), Level::Amber);
        assert_eq!(Level::of(&e(false, false, true), 0), Level::Amber);
        assert_eq!(Level::of(&e(false, false, false), 1), Level::Amber);
        assert_eq!(Level::of(&e(true, false, false), 0), Level::Red);
        assert_eq!(Level::of(&e(true, true, true), 3), Level::Red);
        let h = headline(&e(true, false, true), 2);
        assert_eq!(
            h,
            "Red: failed: check gouge; worse: time 1 → 2 s; 2 warnings apply."
        );
        assert!(headline(&e(false, false, false), 0).starts_with("Green: every check passed"));
        // Changed but no better: amber, and not called worse.
        let same = Evidence {
            not_better: Some("nothing measured better (time 1 → 1 s)".into()),
            ..e(false, false, false)
        };
        assert_eq!(Level::of(&same, 0), Level::Amber);
        assert_eq!(
            headline(&same, 0),
            "Amber: changed, but nothing measured better (time 1 → 1 s)."
        );
    }

    /// The page names the level and colours the verdict box by it.
    #[test]
    fn the_page_shows_the_level_in_colour() {
        let n = Notes::judged(
            Vec::new(),
            vec!["a warning".into()],
            &Evidence::default(),
            vec!["words".into()],
        );
        assert_eq!(n.level, Level::Amber);
        let page = report_page("t", "i", &n, &[], &[]);
        assert!(page.contains("data-level=\"amber\""), "{page}");
        assert!(page.contains("border-left-color:#ef8f00"), "{page}");
        assert!(
            page.contains("<p>Amber: a warning applies.</p><p>words</p>"),
            "{page}"
        );
    }
}
