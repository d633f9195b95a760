//! Cutter–workpiece engagement: for each axial slice of the cutter, the
//! immersion angles at which its edge is in material (process-models spec
//! §1.4), in the tool frame of the move.
//!
//! Tool frame (spec §0): origin at the tip, +z along the tool axis, +x the
//! feed direction projected normal to the axis, y = z × x. The immersion
//! angle φ is measured clockwise from +y seen from +z; the edge point of a
//! slice of radius ρ at height h is (ρ sin φ, ρ cos φ, h).

use super::tool::ToolBody;
use super::Stock;
use millplan_geom::DVec3;

/// One axial slice of the cutter.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Slice {
    /// Height of the slice's middle above the tip, mm.
    pub h: f64,
    /// Cutter radius there, mm.
    pub radius: f64,
    /// Immersion intervals [φ_start, φ_exit] in material, radians in [0, 2π].
    pub arcs: Vec<[f64; 2]>,
}

/// The engagement of one tool position.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct EngagementMap {
    /// Slice thickness, mm.
    pub dz: f64,
    /// Angular step, radians.
    pub dphi: f64,
    /// Slices from the tip up to the highest one in material (empty slices
    /// below it included, so index k is at height (k + ½)·dz).
    pub slices: Vec<Slice>,
}

impl EngagementMap {
    /// Whether any edge point is in material.
    pub fn engaged(&self) -> bool {
        self.slices.iter().any(|s| !s.arcs.is_empty())
    }

    /// The axial depth of cut: height of the top of the highest engaged slice.
    pub fn ap(&self) -> f64 {
        self.slices
            .iter()
            .rposition(|s| !s.arcs.is_empty())
            .map_or(0.0, |k| (k as f64 + 1.0) * self.dz)
    }

    /// Whether the edge point of slice `k` at immersion `phi` is in material.
    pub fn in_material(&self, k: usize, phi: f64) -> bool {
        let phi = phi.rem_euclid(std::f64::consts::TAU);
        self.slices
            .get(k)
            .is_some_and(|s| s.arcs.iter().any(|[a, b]| phi >= *a && phi <= *b))
    }
}

/// The tool frame of a move: unit x (feed), y, z (axis). A feed along the
/// axis (a plunge) takes x from the world X or Y axis.
pub fn tool_frame(axis: DVec3, feed: DVec3) -> (DVec3, DVec3, DVec3) {
    let z = axis.normalize();
    let mut x = feed - z * feed.dot(z);
    if x.length_squared() < 1e-18 {
        x = DVec3::X - z * z.x;
        if x.length_squared() < 1e-12 {
            x = DVec3::Y - z * z.y;
        }
    }
    let x = x.normalize();
    (x, z.cross(x), z)
}

/// The engagement of `tool` at `tip` with axis `axis` moving along `feed`,
/// against `stock` as it is (call it before removing the move). Slices of
/// `dz` up the flutes, angles at `dphi`.
pub fn engagement(
    stock: &Stock,
    tool: &ToolBody,
    tip: DVec3,
    axis: DVec3,
    feed: DVec3,
    dz: f64,
    dphi: f64,
) -> EngagementMap {
    let (x, y, z) = tool_frame(axis, feed);
    let nphi = ((std::f64::consts::TAU / dphi).round() as usize).max(4);
    let dphi = std::f64::consts::TAU / nphi as f64;
    let nz = ((tool.flute / dz).ceil() as usize).clamp(1, 100_000);
    let top = stock.max_top();
    let mut slices = Vec::with_capacity(nz);
    for k in 0..nz {
        let h = (k as f64 + 0.5) * dz;
        let centre = tip + z * h;
        // Above all material (for a tool not pointing down): done.
        if centre.z - tool.radius() > top && z.z > 0.0 {
            break;
        }
        let radius = tool.cutter_radius_at(h);
        let mut arcs: Vec<[f64; 2]> = Vec::new();
        if radius > 0.0 {
            let mut open: Option<f64> = None;
            for j in 0..nphi {
                let phi = (j as f64 + 0.5) * dphi;
                let (s, c) = phi.sin_cos();
                let p = centre + x * (radius * s) + y * (radius * c);
                let inside = stock.contains(p);
                match (inside, open) {
                    (true, None) => open = Some(j as f64 * dphi),
                    (false, Some(a)) => {
                        arcs.push([a, j as f64 * dphi]);
                        open = None;
                    }
                    _ => {}
                }
            }
            // An arc across φ = 0 stays two: [a, 2π] and [0, b].
            if let Some(a) = open {
                arcs.push([a, std::f64::consts::TAU]);
            }
        }
        slices.push(Slice { h, radius, arcs });
    }
    while slices.last().is_some_and(|s| s.arcs.is_empty()) {
        slices.pop();
    }
    EngagementMap { dz, dphi, slices }
}
