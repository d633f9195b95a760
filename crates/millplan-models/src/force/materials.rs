//! Named coefficient sets: a built-in TOML table (`data/materials.toml`) that a
//! user file of the same form extends or overrides by name.
//!
//! EN AW-2007 (Schnoes & Zaeh, table 3) is kept as published, on the paper's
//! own directions: t along the flute, d outward, n along the cutting velocity
//! (paper 001, eq. 4–7). The spec (§1.5e, §8 item 2) suspected a 10× slip in
//! k_tc = 57.5 N/mm² because it read t as the cutting direction. In the paper
//! the cutting direction is n, whose k_nc = −672 N/mm² is the usual size of an
//! aluminium cutting coefficient (negative: the force on the tool opposes the
//! cutting velocity), k_dc = −76.5 N/mm² pushes the tool inward like a radial
//! coefficient, and k_tc acts along the flute like an axial one, where
//! 57.5 N/mm² is plausible. The units N/mm² and N/mm are therefore taken as
//! printed, with no rescaling, and the set is evaluated with the flute-segment
//! law it was fitted for.

use super::coeffs::{BetaRule, ChipRule, Coeffs, Law, Oblique, Orthogonal};
use serde::Deserialize;
use std::collections::BTreeMap;

const BUILTIN: &str = include_str!("../../data/materials.toml");

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    model: String,
    #[serde(default)]
    note: String,
    kc: Option<[f64; 3]>,
    ke: Option<[f64; 3]>,
    tau_s: Option<f64>,
    beta_a: Option<[f64; 2]>,
    rc_c0: Option<[f64; 2]>,
    rc_a: Option<[f64; 2]>,
    rake: Option<f64>,
    chip: Option<toml::Value>,
    h_min: Option<f64>,
    beta: Option<String>,
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub note: String,
    pub law: Law,
}

/// The materials known by name.
#[derive(Clone, Debug, Default)]
pub struct Materials {
    pub by_name: BTreeMap<String, Material>,
}

impl Materials {
    /// The built-in table.
    pub fn builtin() -> Materials {
        let mut m = Materials::default();
        // The built-in file is part of the build and tested; it always parses.
        if let Err(e) = m.add_toml(BUILTIN, "built-in materials") {
            debug_assert!(false, "{e}");
        }
        m
    }

    /// Adds (or replaces) the materials of a TOML text; `origin` names it in
    /// errors.
    pub fn add_toml(&mut self, text: &str, origin: &str) -> Result<(), String> {
        let table: BTreeMap<String, Entry> =
            toml::from_str(text).map_err(|e| format!("{origin}: {}", e.message()))?;
        for (name, e) in table {
            let law = law(&e).map_err(|m| {
                let at = line_of(text, &name, &m).map_or(String::new(), |l| format!(":{l}"));
                format!("{origin}{at}: material `{name}`: {m}")
            })?;
            let name = name.to_ascii_lowercase();
            self.by_name.insert(
                name.clone(),
                Material {
                    name,
                    note: e.note,
                    law,
                },
            );
        }
        Ok(())
    }

    pub fn get(&self, name: &str) -> Result<&Material, String> {
        self.by_name.get(&name.to_ascii_lowercase()).ok_or_else(|| {
            let known: Vec<&str> = self.by_name.keys().map(|s| s.as_str()).collect();
            format!("unknown material `{name}` (known: {})", known.join(", "))
        })
    }
}

fn finite<const N: usize>(v: Option<[f64; N]>, what: &str) -> Result<[f64; N], String> {
    let v = v.ok_or_else(|| format!("`{what}` is missing"))?;
    if v.iter().any(|x| !x.is_finite() || x.abs() > 1e6) {
        return Err(format!(
            "`{what}` must hold finite numbers of sensible size"
        ));
    }
    Ok(v)
}

/// The tangential and radial coefficients (the first two of `v`) must not
/// be negative: they would give negative power and torque. The axial one
/// may legitimately be either sign.
fn not_negative(v: &[f64; 3], what: &str, names: &str) -> Result<(), String> {
    if v[0] < 0.0 || v[1] < 0.0 {
        return Err(format!(
            "`{what}` = [{}, {}, {}]: the tangential and radial coefficients ({names}) must not be negative (only the axial one may be)",
            v[0], v[1], v[2]
        ));
    }
    Ok(())
}

/// The 1-based line of the key a validation message names (its first
/// `quoted` word) inside the table `[name]` of `text`, or of the table's
/// header when the key is not written there.
fn line_of(text: &str, name: &str, msg: &str) -> Option<usize> {
    let key = msg.split('`').nth(1).unwrap_or("");
    let header = |l: &str| {
        let t = l.trim();
        t.starts_with('[') && t.trim_matches(['[', ']', ' ', '"']) == name
    };
    let start = text.lines().position(header)?;
    let key_line = text
        .lines()
        .enumerate()
        .skip(start + 1)
        .take_while(|(_, l)| !l.trim_start().starts_with('['))
        .find(|(_, l)| {
            let t = l.trim_start();
            !key.is_empty() && t.starts_with(key) && t[key.len()..].trim_start().starts_with('=')
        })
        .map(|(i, _)| i);
    Some(key_line.unwrap_or(start) + 1)
}

fn law(e: &Entry) -> Result<Law, String> {
    match e.model.as_str() {
        "linear" => {
            let (kc, ke) = (finite(e.kc, "kc")?, finite(e.ke, "ke")?);
            not_negative(&kc, "kc", "Ktc, Krc")?;
            not_negative(&ke, "ke", "Kte, Kre")?;
            Ok(Law::Rta(Coeffs { kc, ke }))
        }
        "flute-segment" => Ok(Law::FluteSegment(Coeffs {
            kc: finite(e.kc, "kc")?,
            ke: finite(e.ke, "ke")?,
        })),
        "oblique" => {
            let tau_s = finite(e.tau_s.map(|x| [x]), "tau_s")?[0];
            if !(tau_s > 0.0) {
                return Err("`tau_s` must be positive".into());
            }
            let db = Orthogonal {
                tau_s,
                beta_a: finite(e.beta_a, "beta_a")?,
                rc_c0: finite(e.rc_c0, "rc_c0")?,
                rc_a: finite(e.rc_a, "rc_a")?,
                ke: finite(e.ke, "ke")?,
            };
            not_negative(&db.ke, "ke", "Kte, Kre")?;
            let rake_deg = e.rake.unwrap_or(0.0);
            if !(rake_deg.abs() < 45.0) {
                return Err("`rake` must be within ±45 degrees".into());
            }
            let chip = match &e.chip {
                None => ChipRule::PerElement { h_min: 0.005 },
                Some(toml::Value::String(s)) if s == "per-element" => ChipRule::PerElement {
                    h_min: e.h_min.unwrap_or(0.005).max(1e-4),
                },
                Some(toml::Value::Float(h)) if *h > 0.0 => ChipRule::Fixed(*h),
                Some(_) => {
                    return Err("`chip` must be \"per-element\" or a chip thickness in mm".into())
                }
            };
            let beta = match e.beta.as_deref() {
                None | Some("converted") => BetaRule::Converted,
                Some("same") => BetaRule::Same,
                Some(x) => return Err(format!("`beta = \"{x}\"`: use \"converted\" or \"same\"")),
            };
            Ok(Law::Oblique(Oblique {
                db,
                rake_deg,
                beta,
                chip,
            }))
        }
        m => Err(format!(
            "model `{m}`: use \"linear\", \"oblique\" or \"flute-segment\""
        )),
    }
}
