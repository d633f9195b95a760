//! Numbers rounded to what they mean before they are printed (every
//! command's `--json`): positions and
//! lengths to the micrometre (3 decimals of mm), angles to 0.001°, spindle
//! speeds to 0.1 1/min; anything else to 6 significant digits, so that no
//! output carries the noise of binary floating point (`-57.533539999999995`).
//! Rotation matrices and unit vectors are left whole. Inside, nothing is
//! rounded.

use serde_json::Value;

/// How a number is rounded, chosen by the name of its JSON key.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Rule {
    /// Decimals after the point.
    Decimals(i32),
    /// Significant digits.
    Significant(i32),
    /// Not rounded.
    Exact,
}

/// The rule for a key: angles (`…deg…`), spindle speeds (`…rpm…`,
/// `spindle…`, `n`, `…delta_n…`), lengths (`…_mm`, coordinates, bounds,
/// diameters), else `inherited` (the enclosing key's rule).
fn rule_for(key: &str, inherited: Rule) -> Rule {
    let k = key.to_ascii_lowercase();
    // Rotations and unit vectors are used, not read: kept whole, so that a
    // rotation stays a rotation to the last bit.
    if ["setup", "rotation", "matrix", "normal", "axis"]
        .iter()
        .any(|w| k.contains(w))
    {
        return Rule::Exact;
    }
    if k.contains("deg") || k.contains("angle") || k.contains("tilt") {
        return Rule::Decimals(3);
    }
    if k.contains("rpm")
        || k.starts_with("spindle")
        || k == "n"
        || k.contains("delta_n")
        || k.starts_with("n_")
    {
        return Rule::Decimals(1);
    }
    // Words that name a part of something (`spindle.min`, `bounds.max`)
    // keep the rule of what they are part of; at the top they are lengths.
    let parts = ["min", "max", "x", "y", "z", "mean", "first", "last"];
    if parts.contains(&k.as_str()) {
        return match inherited {
            Rule::Significant(_) => Rule::Decimals(3),
            r => r,
        };
    }
    let lengths = [
        "bounds",
        "size",
        "d_w",
        "d_cc",
        "d_mean_area",
        "d_mean_chip",
        "gap",
        "ae",
        "ap",
        "d",
        "r",
        "l",
        "d2",
        "basic_d2",
        "depth",
        "max_depth",
        "tol",
        "insl",
        "tp",
        "pz",
        "clearance",
    ];
    if k.ends_with("_mm") || lengths.contains(&k.as_str()) {
        return Rule::Decimals(3);
    }
    inherited
}

fn round(v: f64, rule: Rule) -> f64 {
    let decimals = match rule {
        Rule::Exact => return v,
        Rule::Decimals(d) => d,
        Rule::Significant(s) => {
            if v == 0.0 || !v.is_finite() {
                return v;
            }
            s - 1 - v.abs().log10().floor() as i32
        }
    };
    if !(-20..=20).contains(&decimals) {
        return v;
    }
    let f = 10f64.powi(decimals);
    let r = (v * f).round() / f;
    // -0.0 reads as "-0": a coordinate of zero is zero.
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

fn walk(v: &mut Value, rule: Rule) {
    match v {
        Value::Number(n) if n.is_f64() => {
            if let Some(x) = n.as_f64() {
                if let Some(r) = serde_json::Number::from_f64(round(x, rule)) {
                    *n = r;
                }
            }
        }
        Value::Array(items) => items.iter_mut().for_each(|i| walk(i, rule)),
        Value::Object(map) => {
            for (k, item) in map.iter_mut() {
                walk(item, rule_for(k, rule));
            }
        }
        _ => {}
    }
}

/// `v` with every float rounded to what it means.
pub fn json(mut v: Value) -> Value {
    walk(&mut v, Rule::Significant(6));
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json as j;

    #[test]
    fn numbers_are_rounded_to_their_meaning() {
        let v = json(j!({
            "bounds": {"min": [-57.533539999999995, 0.1 + 0.2, -0.0000001]},
            "inclination_deg": 12.345678,
            "spindle": {"min": 4200.649, "max": 8448.0},
            "n": 4855.55,
            "length_mm": {"cutting": 3300.1234567},
            "r2": 0.969112345,
            "share": 0.14823456789,
            "moves": 6384,
            "setup": [[0.1 + 0.2, 1.0]],
        }));
        assert_eq!(v["setup"][0][0], 0.1 + 0.2);
        assert_eq!(v["bounds"]["min"][0], -57.534);
        assert_eq!(v["bounds"]["min"][1], 0.3);
        assert_eq!(v["bounds"]["min"][2].to_string(), "0.0");
        assert_eq!(v["inclination_deg"], 12.346);
        assert_eq!(v["spindle"]["min"], 4200.6);
        assert_eq!(v["n"], 4855.6);
        assert_eq!(v["length_mm"]["cutting"], 3300.123);
        assert_eq!(v["r2"], 0.969112);
        assert_eq!(v["share"], 0.148235);
        assert_eq!(v["moves"], 6384);
    }
}
