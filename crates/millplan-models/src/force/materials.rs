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
    fz_max: Option<Vec<[f64; 2]>>,
    #[serde(default)]
    fz_note: String,
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub note: String,
    pub law: Law,
    /// The largest feed per tooth by tool diameter (`fz_max`), if the table
    /// gives one.
    pub chip_loads: Option<ChipLoads>,
    /// Where the chip loads come from (`fz_note`).
    pub fz_note: String,
}

/// Rows a chip-load table may have.
pub const CHIP_LOAD_ROWS: usize = 24;

/// The share of the tool diameter taken as the largest feed per tooth where
/// the material gives no chip loads: 0.02·D, a tool maker's rule of thumb for
/// aluminium with small radial engagement, high for harder materials.
pub const FALLBACK_FZ_SHARE: f64 = 0.02;

/// A material's largest feed per tooth by tool diameter (the `fz_max`
/// column: rows `[D mm, fz mm]`, diameters strictly increasing). Between rows
/// the value is interpolated linearly in D; below the first row it falls in
/// proportion to D (a chip load scales with the edge's size); above the last
/// it stays at the last row's (no extrapolation beyond what the source
/// gives). Fixed-size so that the limits holding it stay `Copy`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChipLoads {
    rows: [[f64; 2]; CHIP_LOAD_ROWS],
    len: usize,
}

impl ChipLoads {
    /// The table from its rows, checked: 1 to [`CHIP_LOAD_ROWS`] rows,
    /// diameters finite, positive and strictly increasing, feeds per tooth
    /// finite, positive and at most 5 mm.
    pub fn new(rows: &[[f64; 2]]) -> Result<ChipLoads, String> {
        if rows.is_empty() || rows.len() > CHIP_LOAD_ROWS {
            return Err(format!(
                "`fz_max` needs 1 to {CHIP_LOAD_ROWS} rows [D mm, fz mm], got {}",
                rows.len()
            ));
        }
        let mut out = ChipLoads {
            rows: [[0.0; 2]; CHIP_LOAD_ROWS],
            len: rows.len(),
        };
        for (k, &[d, fz]) in rows.iter().enumerate() {
            if !(d.is_finite() && d > 0.0 && d <= 1000.0) {
                return Err(format!(
                    "`fz_max` row {}: diameter {d} must be above 0 and at most 1000 mm",
                    k + 1
                ));
            }
            if k > 0 && d <= rows[k - 1][0] {
                return Err(format!(
                    "`fz_max` row {}: diameters must increase ({d} after {})",
                    k + 1,
                    rows[k - 1][0]
                ));
            }
            if !(fz.is_finite() && fz > 0.0 && fz <= 5.0) {
                return Err(format!(
                    "`fz_max` row {}: feed per tooth {fz} must be above 0 and at most 5 mm",
                    k + 1
                ));
            }
            out.rows[k] = [d, fz];
        }
        Ok(out)
    }

    /// The rows `[D, fz]`.
    pub fn rows(&self) -> &[[f64; 2]] {
        &self.rows[..self.len]
    }

    /// The largest feed per tooth of a tool of diameter `d`, mm.
    pub fn at(&self, d: f64) -> f64 {
        let r = self.rows();
        let [d0, f0] = r[0];
        if d <= d0 {
            return f0 * (d / d0).max(0.0);
        }
        for w in r.windows(2) {
            let ([da, fa], [db, fb]) = (w[0], w[1]);
            if d <= db {
                return fa + (fb - fa) * (d - da) / (db - da);
            }
        }
        r[r.len() - 1][1]
    }
}

/// Where a largest feed per tooth came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FzSource {
    /// Given by the user.
    Given,
    /// The material's chip-load table at the tool's diameter.
    Material,
    /// No table: [`FALLBACK_FZ_SHARE`]·D.
    Diameter,
}

/// The largest feed per tooth of a tool of diameter `d` in a material with
/// chip loads `chip` (None: the [`FALLBACK_FZ_SHARE`]·D rule), and its source.
pub fn fz_max_for(chip: Option<&ChipLoads>, d: f64) -> (f64, FzSource) {
    match chip {
        Some(c) => (c.at(d), FzSource::Material),
        None => (FALLBACK_FZ_SHARE * d, FzSource::Diameter),
    }
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

    /// The built-in table with the materials of `extra` (a TOML text and
    /// the name of where it came from) added or replacing those of the same
    /// name: every command's materials.
    pub fn load(extra: Option<(&str, &str)>) -> Result<Materials, String> {
        let mut m = Materials::builtin();
        if let Some((text, origin)) = extra {
            m.add_toml(text, origin)?;
        }
        Ok(m)
    }

    /// Adds (or replaces) the materials of a TOML text; `origin` names it in
    /// errors.
    pub fn add_toml(&mut self, text: &str, origin: &str) -> Result<(), String> {
        let table: BTreeMap<String, Entry> =
            toml::from_str(text).map_err(|e| format!("{origin}: {}", e.message()))?;
        for (name, e) in table {
            let at = |m: String| {
                let at = line_of(text, &name, &m).map_or(String::new(), |l| format!(":{l}"));
                format!("{origin}{at}: material `{name}`: {m}")
            };
            let law = law(&e).map_err(at)?;
            let chip_loads = e
                .fz_max
                .as_deref()
                .map(ChipLoads::new)
                .transpose()
                .map_err(at)?;
            let name = name.to_ascii_lowercase();
            self.by_name.insert(
                name.clone(),
                Material {
                    name,
                    note: e.note,
                    law,
                    chip_loads,
                    fz_note: e.fz_note,
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
                Some(toml::Value::Float(h)) if *h > 0.0 && *h <= 2.0 => ChipRule::Fixed(*h),
                Some(_) => return Err(
                    "`chip` must be \"per-element\" or a chip thickness above 0 and at most 2 mm"
                        .into(),
                ),
            };
            let beta = match e.beta.as_deref() {
                None | Some("converted") => BetaRule::Converted,
                Some("same") => BetaRule::Same,
                Some(x) => return Err(format!("`beta = \"{x}\"`: use \"converted\" or \"same\"")),
            };
            let h_min = match chip {
                ChipRule::PerElement { h_min } => h_min,
                ChipRule::Fixed(h) => h,
            };
            db.check(rake_deg, h_min, beta)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chip_loads_read_interpolate_and_refuse_bad_rows() {
        let mut m = Materials::default();
        let base = "[x]\nmodel = \"linear\"\nkc = [1.0, 1.0, 0.0]\nke = [0.0, 0.0, 0.0]\n";
        m.add_toml(
            &format!("{base}fz_max = [[4.0, 0.02], [8.0, 0.06]]\nfz_note = \"shop\"\n"),
            "f",
        )
        .expect("valid");
        let x = m.get("x").expect("added");
        let c = x.chip_loads.expect("chip loads");
        assert_eq!(x.fz_note, "shop");
        assert_eq!(c.rows(), &[[4.0, 0.02], [8.0, 0.06]]);
        for (d, want) in [
            (2.0, 0.01),
            (4.0, 0.02),
            (6.0, 0.04),
            (8.0, 0.06),
            (20.0, 0.06),
        ] {
            assert!((c.at(d) - want).abs() < 1e-12, "D{d}: {}", c.at(d));
        }
        assert_eq!(fz_max_for(Some(&c), 6.0).1, FzSource::Material);
        assert!((fz_max_for(None, 10.0).0 - 0.2).abs() < 1e-12);
        for (rows, needle) in [
            ("[]", "1 to 24 rows"),
            ("[[4.0, 0.02], [4.0, 0.03]]", "must increase"),
            ("[[0.0, 0.02]]", "diameter"),
            ("[[4.0, -0.02]]", "feed per tooth"),
            ("[[4.0, nan]]", "feed per tooth"),
        ] {
            let e = Materials::default()
                .add_toml(&format!("{base}fz_max = {rows}\n"), "f")
                .expect_err(rows);
            assert!(
                e.contains("material `x`") && e.contains(needle),
                "{rows}: {e}"
            );
        }
        // Every built-in table reads, its rows as documented.
        let b = Materials::builtin();
        let ti = b
            .get("ti6al4v")
            .expect("built in")
            .chip_loads
            .expect("rows");
        assert_eq!(ti.at(16.0), 0.06);
        assert!(b.get("al7075-hss").expect("built in").chip_loads.is_none());
    }
}
