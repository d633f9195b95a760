//! Every default of a job, in one place. A run without options takes these;
//! each is printed in the report beside the value used.
//!
//! | name | value | used when |
//! |---|---|---|
//! | `vc` | per material, [`cutting`] (`data/cutting.toml`) | no `--vc` |
//! | `spindle` | 1000·vc/(π·D) of each operation's tool | a cutting move has no S and no `--spindle` |
//! | `fz_min` | [`Defaults::FZ_MIN`] mm (as `millplan feed`), at most a tool's `fz_max` | no `--limit fz_min=` |
//! | `fz_max` | per tool, the material's chip load at its diameter (`fz_max` of the materials table, `millplan_models::force::materials`), else 0.02·D | no `--limit fz_max=` (which sets it for every tool) |
//! | torque, power | the machine file's spindle chart at each block's speed | the machine file has a chart (`--limit` tightens) |
//! | F_xy; torque and power without a chart | the input program's own largest load on the stock (`Job::learn_limits`) | no `--limit` for it, a stock and a material given |
//! | `flutes` | [`Defaults::FLUTES`] | the program and `--flutes` say nothing |
//! | `helix` | [`Defaults::HELIX_DEG`] | always (force model) |
//! | `resolution` | [`Defaults::RESOLUTION`] mm | no `--resolution` |
//! | `ap` (speed pass) | the allowance of `--stock offset:MM`, else [`Defaults::AP`] | constant cutting speed |
//! | `feed_accel` | the machine's smallest linear-axis acceleration, else [`Defaults::FEED_ACCEL`] | feed pass |
//! | `tol` | [`Defaults::TOL`] mm | checks: collisions deeper, tips farther, are findings |
//! | `load_slack` | [`Defaults::LOAD_SLACK`] | a load this far over its limit is within the model's resolution |

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The fixed defaults (see the module's table).
pub struct Defaults;

impl Defaults {
    /// Smallest feed per tooth, mm (`millplan feed --fz-min`'s default).
    pub const FZ_MIN: f64 = 0.01;
    /// Flutes of a tool nobody describes.
    pub const FLUTES: usize = 2;
    /// Helix angle of the force model, degrees.
    pub const HELIX_DEG: f64 = 30.0;
    /// Dexel size of the stock, mm.
    pub const RESOLUTION: f64 = 0.1;
    /// Finishing allowance of the constant-cutting-speed pass without an
    /// `offset:` stock, mm (the thesis's ap, spec working-diameter.md).
    pub const AP: f64 = 0.3;
    /// Feed acceleration of a machine file that gives no axis acceleration,
    /// mm/s².
    pub const FEED_ACCEL: f64 = 1000.0;
    /// Collision depth, tip distance and gouge depth below which the checks
    /// find nothing, mm.
    pub const TOL: f64 = 0.01;
    /// A load at most this fraction over its limit passes the load check
    /// (the force model's resolution; reported as such).
    pub const LOAD_SLACK: f64 = 0.005;
}

/// Cutting data of one material for solid carbide (see `data/cutting.toml`;
/// the feed per tooth comes from the materials table's chip loads).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cutting {
    /// Cutting speed, m/min.
    pub vc: f64,
}

const CUTTING: &str = include_str!("../data/cutting.toml");

/// The cutting data of `material` (lower case), and whether it is the
/// table's `[default]` standing in for a material without a row.
pub fn cutting(material: &str) -> (Cutting, bool) {
    let table: BTreeMap<String, Cutting> = toml::from_str(CUTTING).unwrap_or_default();
    match table.get(&material.to_ascii_lowercase()) {
        Some(c) => (*c, false),
        None => (
            table
                .get("default")
                .copied()
                .unwrap_or(Cutting { vc: 100.0 }),
            true,
        ),
    }
}

/// The spindle speed at cutting speed `vc` (m/min) on diameter `d` (mm),
/// 1/min.
pub fn spindle_for(vc: f64, d: f64) -> f64 {
    1000.0 * vc / (std::f64::consts::PI * d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_parses_and_names_known_materials() {
        let table: BTreeMap<String, Cutting> = toml::from_str(CUTTING).expect("cutting.toml");
        let known = millplan_models::force::materials::Materials::builtin();
        for (name, c) in &table {
            assert!(name == "default" || known.get(name).is_ok(), "{name}");
            assert!(c.vc > 0.0, "{name}");
        }
        for name in known.by_name.keys() {
            assert!(!cutting(name).1, "{name} has no cutting data");
        }
    }

    #[test]
    fn spindle_from_vc_is_the_thesis_formula() {
        // working-diameter.md: n = 1000·vc/(π·D); vc 63 on D 10 → 2005.3.
        assert!((spindle_for(63.0, 10.0) - 2005.352).abs() < 1e-3);
    }

    #[test]
    fn unknown_material_takes_the_default_row() {
        let (c, fallback) = cutting("unobtainium");
        assert!(fallback);
        assert_eq!(c.vc, 100.0);
        assert_eq!(cutting("AL7075").0.vc, 300.0);
    }
}
