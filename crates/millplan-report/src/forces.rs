//! The per-move force table and the report of `millplan force` and
//! `millplan feed`: loads against time with the limits drawn.

use crate::html::{report_page, worse_words, Evidence, Notes, TIME_WORSE};
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

/// A number rounded to what it means: four significant digits, no more
/// than three decimals above 1, thousands grouped by a thin space.
pub fn round(v: f64) -> String {
    if !v.is_finite() {
        return "–".to_string();
    }
    if v == v.trunc() && v.abs() < 1e12 {
        return group(&format!("{v:.0}"));
    }
    let mag = v.abs().log10().floor() as i32;
    let decimals = (3 - mag).clamp(0, if v.abs() >= 1.0 { 3 } else { 6 }) as usize;
    group(&format!("{v:.decimals$}"))
}

/// `12345.6` → `12 345.6`.
fn group(s: &str) -> String {
    let (sign, rest) = s.strip_prefix('-').map_or(("", s), |r| ("−", r));
    let (int, frac) = rest
        .split_once('.')
        .map_or((rest, None), |(i, f)| (i, Some(f)));
    if int.len() <= 4 {
        return format!("{sign}{rest}");
    }
    let mut out = String::new();
    for (k, c) in int.chars().enumerate() {
        if k > 0 && (int.len() - k) % 3 == 0 {
            out.push('\u{2009}');
        }
        out.push(c);
    }
    match frac {
        Some(f) => format!("{sign}{out}.{f}"),
        None => format!("{sign}{out}"),
    }
}

/// Label and unit of a summary entry of `force` or `feed`, by its key
/// (`None`: left out of the table, shown elsewhere or internal).
fn label(key: &str) -> Option<(&'static str, &'static str)> {
    Some(match key {
        "moves" => ("moves simulated", ""),
        "cutting_moves" => ("cutting moves", ""),
        "air_moves" => ("moves in air", ""),
        "unmodelled_moves" => ("moves in material without a load model", ""),
        "skipped_moves" => ("moves not simulated", ""),
        "evaluations" => ("force evaluations", ""),
        "time_s" => ("time of the program", "s"),
        "time_before_s" => ("cycle time before, with acceleration", "s"),
        "time_after_s" => ("cycle time after, with acceleration", "s"),
        "time_nominal_before_s" => ("time before at the programmed feeds", "s"),
        "time_nominal_after_s" => ("time after at the programmed feeds", "s"),
        "max" => ("largest loads", ""),
        "max_before" => ("largest loads before", ""),
        "max_after" => ("largest loads after", ""),
        "max_lines" => ("lines of the largest loads", ""),
        "over_limit" => ("moves over a limit", ""),
        "over_limit_after" => ("moves over a limit after", ""),
        "over_limit_lines" => ("lines over a limit", ""),
        "within_tolerance" => ("moves within the limit's tolerance", ""),
        "limit_tolerance" => ("tolerance on a limit", "share"),
        "stock" => ("stock", ""),
        "stock_contact" => ("a cutting move meets the stock", ""),
        "steps" => ("force integration steps", ""),
        "binding" => ("what limits the feed, blocks", ""),
        "blocks" => ("blocks", ""),
        "air_blocks" => ("blocks in air", ""),
        "kept_blocks" => ("blocks kept", ""),
        "feed_range_written" => ("feeds written", "mm/min"),
        "feed_accel" => ("feed acceleration", "mm/s²"),
        "fz_range" => ("feed per tooth", "mm"),
        "limits" => ("limits", ""),
        "output" => ("output", ""),
        "dialect" => ("dialect", ""),
        _ => return None,
    })
}

/// The unit of a field inside a summary's object (loads, limits, steps).
fn field_unit(key: &str) -> &'static str {
    match key {
        "fxy" => "N",
        "torque" => "N·mm",
        "power" => "W",
        "stress" => "MPa",
        "deflection" | "dz_mm" => "mm",
        "dphi_deg" => "°",
        _ => "",
    }
}

/// A summary value in words: numbers rounded, lists joined, objects as
/// `name value unit` pairs.
fn words(v: &serde_json::Value, unit: &str) -> String {
    use serde_json::Value;
    let with_unit = |s: String| {
        if unit.is_empty() {
            s
        } else {
            format!("{s} {unit}")
        }
    };
    match v {
        Value::Number(n) => with_unit(n.as_f64().map_or_else(|| n.to_string(), round)),
        Value::String(s) => s.clone(),
        Value::Bool(b) => if *b { "yes" } else { "no" }.to_string(),
        Value::Null => "–".to_string(),
        Value::Array(a) => {
            let sep = if a.len() == 2 && !unit.is_empty() {
                " … "
            } else {
                ", "
            };
            with_unit(a.iter().map(|x| words(x, "")).collect::<Vec<_>>().join(sep))
        }
        Value::Object(o) => o
            .iter()
            .filter(|(_, x)| !x.is_null())
            .map(|(k, x)| format!("{} {}", k.replace('_', " "), words(x, field_unit(k))))
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// The summary table of a `force` or `feed` run: each entry under its name
/// in words with its unit, numbers rounded (the JSON output keeps full
/// precision); per-operation and per-tool lists are left to the verdict and
/// the JSON.
pub fn summary_table(summary: &serde_json::Value) -> Vec<(String, String)> {
    let Some(o) = summary.as_object() else {
        return Vec::new();
    };
    o.iter()
        .filter_map(|(k, v)| {
            let (name, unit) = label(k)?;
            Some((name.to_string(), words(v, unit)))
        })
        .collect()
}

/// What the verdict of `force` is decided from: a move over a limit is a
/// failed check.
pub fn force_evidence(over_limit: u64) -> Evidence {
    Evidence {
        failed: if over_limit > 0 {
            vec![format!("{over_limit} moves over a load limit")]
        } else {
            Vec::new()
        },
        ..Evidence::default()
    }
}

/// What the verdict of `feed` is decided from: a move over a limit after
/// is a failed check; the input is kept when no block's feed changed;
/// the cycle time that grew is worse.
pub fn feed_evidence(over_limit_after: u64, changed_blocks: u64, time_s: [f64; 2]) -> Evidence {
    let mut e = force_evidence(over_limit_after);
    e.kept = changed_blocks == 0;
    if time_s[1] > time_s[0] * (1.0 + TIME_WORSE) {
        e.worse
            .push(worse_words("cycle time", time_s[0], time_s[1], 1, "s"));
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_rounded_to_four_digits() {
        assert_eq!(round(123.456789), "123.5");
        assert_eq!(round(0.0123456), "0.01235");
        assert_eq!(round(12345.678), "12\u{2009}346");
        assert_eq!(round(-2.5), "−2.500");
        assert_eq!(round(3.0), "3");
        assert_eq!(round(f64::NAN), "–");
    }

    #[test]
    fn the_summary_table_names_units_and_rounds() {
        let v = serde_json::json!({
            "time_before_s": 12.345678901234,
            "max_after": {"fxy": 101.23456789, "deflection": 0.00123456},
            "feed_range_written": [500.0, 2345.6789],
            "fz_by_tool": [{"tool": 1}],
            "stock": "offset:0.5",
        });
        let t = summary_table(&v);
        let get = |k: &str| t.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
        assert_eq!(
            get("cycle time before, with acceleration").as_deref(),
            Some("12.35 s")
        );
        assert_eq!(
            get("largest loads after").as_deref(),
            Some("deflection 0.001235 mm, fxy 101.2 N")
        );
        assert_eq!(get("feeds written").as_deref(), Some("500 … 2346 mm/min"));
        assert_eq!(get("stock").as_deref(), Some("offset:0.5"));
        assert_eq!(t.len(), 4, "{t:?}");
        assert!(t.iter().all(|(_, v)| v.len() < 120), "{t:?}");
    }

    #[test]
    fn feed_verdicts_follow_the_one_rule() {
        use crate::html::Level;
        let l = |e: &Evidence| Level::of(e, 0);
        assert_eq!(l(&feed_evidence(0, 10, [10.0, 8.0])), Level::Green);
        assert_eq!(l(&feed_evidence(0, 0, [10.0, 10.0])), Level::Amber);
        assert_eq!(l(&feed_evidence(0, 10, [10.0, 11.0])), Level::Amber);
        assert_eq!(l(&feed_evidence(3, 10, [10.0, 8.0])), Level::Red);
        assert_eq!(Level::of(&force_evidence(0), 1), Level::Amber);
        let h = crate::html::headline(&feed_evidence(0, 10, [10.0, 11.0]), 0);
        assert!(
            h.starts_with("Amber: worse: cycle time 10.0 → 11.0 s (+10.0 %)"),
            "{h}"
        );
    }
}
