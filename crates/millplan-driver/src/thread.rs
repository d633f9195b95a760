//! `millplan thread`: a measured pitch diameter against the limits of its
//! ISO 965-1 class (OK or REJECT, by how much), and the limits of size of a
//! class, each a typed outcome with its text.

use millplan_tooldb::thread::{check, class_limits, parse_designation, pitch_diameter};
use serde::Serialize;

/// What `thread check` found; `--json` prints it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CheckOutcome {
    pub ok: bool,
    pub min: f64,
    pub max: f64,
    pub d2: f64,
    pub basic_d2: f64,
}

/// Checks the measured pitch diameter `d2` of `thread` against `class`.
pub fn check_d2(thread: &str, class: &str, d2: f64) -> Result<CheckOutcome, String> {
    let c = check(thread, class, d2).map_err(|e| e.to_string())?;
    let (d, p) = parse_designation(thread).map_err(|e| e.to_string())?;
    Ok(CheckOutcome {
        ok: c.ok,
        min: c.min,
        max: c.max,
        d2,
        basic_d2: pitch_diameter(d, p),
    })
}

impl CheckOutcome {
    /// The check in one line, ending OK or REJECT and by how much.
    pub fn render_text(&self, thread: &str, class: &str) -> String {
        let verdict = if self.ok {
            "OK".to_string()
        } else if self.d2 < self.min {
            format!("REJECT: {:.3} mm under the minimum", self.min - self.d2)
        } else {
            format!("REJECT: {:.3} mm over the maximum", self.d2 - self.max)
        };
        format!(
            "{thread}-{class}: D2 {:.3} mm, limits {:.3} … {:.3} mm (basic {:.3}): {verdict}",
            self.d2, self.min, self.max, self.basic_d2
        )
    }
}

/// A range of sizes, mm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Range {
    pub min: f64,
    pub max: f64,
}

fn range(r: Option<(f64, f64)>) -> Option<Range> {
    r.map(|(min, max)| Range { min, max })
}

/// What `thread limits` prints; `--json` prints it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LimitsOutcome {
    pub thread: String,
    pub class: String,
    pub internal: bool,
    pub fundamental_deviation_um: i32,
    pub pitch_tolerance_um: u16,
    pub pitch_diameter_mm: Range,
    pub basic_d2: f64,
    pub crest_diameter_mm: Option<Range>,
    pub crest_tolerance_um: Option<u16>,
    pub crest_missing: Option<String>,
    pub major_diameter_min_mm: Option<f64>,
}

/// The limits of size of `thread` in `class`.
pub fn limits(thread: &str, class: &str) -> Result<LimitsOutcome, String> {
    let l = class_limits(thread, class).map_err(|e| e.to_string())?;
    let (d, p) = parse_designation(thread).map_err(|e| e.to_string())?;
    Ok(LimitsOutcome {
        thread: thread.to_string(),
        class: class.to_string(),
        internal: l.internal,
        fundamental_deviation_um: l.fundamental_deviation_um,
        pitch_tolerance_um: l.pitch_tolerance_um,
        pitch_diameter_mm: Range {
            min: l.pitch.0,
            max: l.pitch.1,
        },
        basic_d2: pitch_diameter(d, p),
        crest_diameter_mm: range(l.crest),
        crest_tolerance_um: l.crest_tolerance_um,
        crest_missing: l.crest_missing,
        major_diameter_min_mm: l.major_min,
    })
}

impl LimitsOutcome {
    /// The limits in words, one diameter a line.
    pub fn render_text(&self) -> String {
        let i = self.internal;
        let (pitch_name, crest_name, t2, tc) = match i {
            true => ("D2", "D1", "T_D2", "T_D1"),
            false => ("d2", "d", "T_d2", "T_d"),
        };
        let deviation = match self.fundamental_deviation_um {
            0 => "0".to_string(),
            v => format!("{v:+}"),
        };
        let (kind, dev) = if i {
            ("internal", "EI")
        } else {
            ("external", "es")
        };
        let pitch = self.pitch_diameter_mm;
        let mut text = vec![
            format!(
                "{}-{} ({kind}), ISO 965-1: {dev} {deviation} µm",
                self.thread, self.class
            ),
            format!(
                "  pitch diameter {pitch_name} {:.3} … {:.3} mm ({t2} {} µm, basic {:.3})",
                pitch.min, pitch.max, self.pitch_tolerance_um, self.basic_d2
            ),
        ];
        let crest_label = if i { "minor" } else { "major" };
        text.push(match (self.crest_diameter_mm, self.crest_tolerance_um) {
            (Some(r), Some(t)) => format!(
                "  {crest_label} diameter {crest_name} {:.3} … {:.3} mm ({tc} {t} µm)",
                r.min, r.max
            ),
            _ => format!(
                "  {crest_label} diameter {crest_name}: not given ({})",
                self.crest_missing.clone().unwrap_or_default()
            ),
        });
        if let Some(m) = self.major_diameter_min_mm {
            text.push(format!("  major diameter D ≥ {m:.3} mm"));
        }
        text.join("\n")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ISO 965-1: M10x1.5-6H has D2 9.026 … 9.206 mm (T_D2 180 µm, EI 0).
    #[test]
    fn a_class_and_a_check_in_words() {
        let l = limits("M10x1.5", "6H").expect("tolerated");
        let p = l.pitch_diameter_mm;
        assert!(
            (p.min - 9.026).abs() < 1e-9 && (p.max - 9.206).abs() < 1e-9,
            "{p:?}"
        );
        let t = l.render_text();
        assert!(
            t.starts_with("M10x1.5-6H (internal), ISO 965-1: EI 0 µm\n"),
            "{t}"
        );
        assert!(
            t.contains("pitch diameter D2 9.026 … 9.206 mm (T_D2 180 µm"),
            "{t}"
        );
        let c = check_d2("M10x1.5", "6H", 9.3).expect("checked");
        assert!(!c.ok);
        assert!(c
            .render_text("M10x1.5", "6H")
            .ends_with("REJECT: 0.094 mm over the maximum"));
        let c = check_d2("M10x1.5", "6H", 9.0).expect("checked");
        assert!(c
            .render_text("M10x1.5", "6H")
            .ends_with("REJECT: 0.026 mm under the minimum"));
        assert!(check_d2("M10x1.5", "6H", 9.1).expect("checked").ok);
        assert!(check_d2("M10x1.5", "6H", -1.0).is_err());
    }
}
