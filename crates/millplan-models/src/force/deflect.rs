//! The tool as a cantilever (spec `process-models.md` §2.2): bending stress at
//! the clamping point and tip deflection under the transversal force, for a
//! uniform or a stepped (shank + flutes) tool.

use std::f64::consts::PI;

/// Young's modulus of carbide, the default [N/mm²].
pub const E_CARBIDE: f64 = 600_000.0;

/// The plausible range of a tool's Young's modulus [N/mm²]: from 10,000
/// (below any metal a tool is made of; aluminium is 70,000) to 2,000,000
/// (above diamond's 1,200,000). A modulus of 1e-308 would bend the tool by
/// an infinite amount.
pub const MODULUS_RANGE: (f64, f64) = (1e4, 2e6);

/// Equivalent diameter of the fluted part over the nominal one (Kops & Vo).
pub const DE_RATIO: f64 = 0.8;

/// Second moment of area of a round section of diameter d \[mm⁴\].
pub fn inertia(d: f64) -> f64 {
    PI * d.powi(4) / 64.0
}

/// A tool clamped at the holder face, loaded at the tip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cantilever {
    /// Gauge length from the holder face to the force point \[mm\].
    pub length: f64,
    /// Shank diameter \[mm\].
    pub shank_d: f64,
    /// Equivalent diameter of the fluted part \[mm\] (≈ 0.8·D).
    pub flute_d: f64,
    /// Length of the fluted part at the tip \[mm\]; `None` treats the whole
    /// length as fluted (the Tunc–Budak form).
    pub flute_length: Option<f64>,
    /// Young's modulus [N/mm²].
    pub e: f64,
}

/// Stresses and deflection under one force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bending {
    /// Largest bending stress \[MPa\] (holder face or flute root).
    pub stress: f64,
    /// Stress at the holder face and at the flute root \[MPa\].
    pub stress_holder: f64,
    pub stress_flute_root: f64,
    /// Tip deflection \[mm\].
    pub deflection: f64,
}

impl Cantilever {
    /// A uniform tool of nominal diameter d with the equivalent diameter
    /// 0.8·d over the gauge length, carbide.
    pub fn uniform(d: f64, length: f64) -> Cantilever {
        Cantilever {
            length,
            shank_d: d,
            flute_d: DE_RATIO * d,
            flute_length: None,
            e: E_CARBIDE,
        }
    }

    pub fn validate(&self) -> Result<(), String> {
        let ok = |v: f64| v > 0.0 && v.is_finite();
        if !(ok(self.length) && ok(self.shank_d) && ok(self.flute_d) && ok(self.e)) {
            return Err("the cantilever needs positive length, diameters and modulus".into());
        }
        if let Some(lf) = self.flute_length {
            if !(ok(lf) && lf <= self.length) {
                return Err("the flute length must be positive and at most the stick-out".into());
            }
        }
        Ok(())
    }

    /// Stress σ = 32·F·L/(π·D³) and deflection δ = F·L³/(3EI), or for the
    /// stepped tool δ = F/(3E)·[(L³ − Lf³)/I_s + Lf³/I_f].
    pub fn bend(&self, force: f64) -> Bending {
        let (l, e) = (self.length, self.e);
        let sigma = |d: f64, arm: f64| 32.0 * force * arm / (PI * d.powi(3));
        match self.flute_length {
            None => {
                let s = sigma(self.flute_d, l);
                Bending {
                    stress: s,
                    stress_holder: s,
                    stress_flute_root: s,
                    deflection: force * l.powi(3) / (3.0 * e * inertia(self.flute_d)),
                }
            }
            Some(lf) => {
                let sh = sigma(self.shank_d, l);
                let sf = sigma(self.flute_d, lf);
                let d = force / (3.0 * e)
                    * ((l.powi(3) - lf.powi(3)) / inertia(self.shank_d)
                        + lf.powi(3) / inertia(self.flute_d));
                Bending {
                    stress: sh.max(sf),
                    stress_holder: sh,
                    stress_flute_root: sf,
                    deflection: d,
                }
            }
        }
    }
}
