//! Cutter–workpiece engagement (spec `process-models.md` §1.4): the question
//! "is this edge point, in the tool frame, in material?" and the analytic
//! planar raster pass used for single engagements.

use super::edge::Tool;
use super::{mul, r_wt, Mat3};
use crate::cutter::Shape;

/// Where the material is, seen from the tool. Points are in the tool frame
/// (origin at the tip, +z toward the shank). The model asks only about edge
/// points whose chip thickness is positive (the front half is carried by h).
pub trait Engagement {
    /// Heights above the tip between which the edge can touch material; the
    /// model slices only this band.
    fn z_range(&self, tool: &Tool) -> (f64, f64);
    /// Whether the edge point `p` is in material.
    fn contains(&self, p: [f64; 3]) -> bool;
    /// Where on the circle of radius `r` around the axis at height `z` (the
    /// edge of one slice over a revolution) material can be, by sector
    /// (none: the model skips the slice): bit s stands for
    /// the tool-frame angles θ ∈ [s, s + 1)·2π/[`SECTORS`] of the points
    /// (r sin θ, r cos θ, z). A clear bit must be certain: the model then
    /// asks no point of that sector. By default every sector is asked.
    fn sectors(&self, _z: f64, _r: f64) -> u64 {
        u64::MAX
    }
}

/// An engagement lent: what it lends.
impl<T: Engagement + ?Sized> Engagement for &T {
    fn z_range(&self, tool: &Tool) -> (f64, f64) {
        (**self).z_range(tool)
    }
    #[inline]
    fn contains(&self, p: [f64; 3]) -> bool {
        (**self).contains(p)
    }
    fn sectors(&self, z: f64, r: f64) -> u64 {
        (**self).sectors(z, r)
    }
}

/// Sectors of the full turn in [`Engagement::sectors`] (one bit each).
pub const SECTORS: usize = 64;

/// ⌊v⌋ for |v| < 2⁶³ without the C library's `floor` (not inlined on
/// x86-64 without SSE4.1): truncation, one down below zero.
#[inline]
pub fn floor_i64(v: f64) -> i64 {
    let t = v as i64;
    if (t as f64) > v {
        t - 1
    } else {
        t
    }
}

/// An engagement given by a closure, with the band of heights to slice.
pub struct FnEngagement<F: Fn([f64; 3]) -> bool> {
    pub z_lo: f64,
    pub z_hi: f64,
    pub f: F,
}

impl<F: Fn([f64; 3]) -> bool> Engagement for FnEngagement<F> {
    fn z_range(&self, _tool: &Tool) -> (f64, f64) {
        (self.z_lo, self.z_hi)
    }
    fn contains(&self, p: [f64; 3]) -> bool {
        (self.f)(p)
    }
}

/// The planar raster pass of §1.4(a): the cutter finishes the plane z_w = 0
/// at depth `ap` below the stock top; without `ae` it cuts a slot (or first
/// pass), with `ae` every earlier pass k = 1, 2, … ran at y_w = −k·ae and left
/// its scallop. The ball centre is at (0, 0, R0) in the feed frame.
///
/// The earlier passes are taken as cut by the same profile; for a ball the
/// scallop does not depend on the orientation, so lead and tilt are exact.
/// Flat and bull end mills are only accepted without lead and tilt. Unlike
/// the reference script of the spec (passes k = 1…5) every earlier pass
/// counts; the two agree whenever 5·ae covers the tool's width.
#[derive(Clone, Copy, Debug)]
pub struct PlanarRaster {
    pub ap: f64,
    pub ae: Option<f64>,
    shape: Shape,
    rot: Mat3,
    offset: [f64; 3],
    z_hi: f64,
}

impl PlanarRaster {
    pub fn new(
        tool: &Tool,
        ap: f64,
        ae: Option<f64>,
        lead: f64,
        tilt: f64,
    ) -> Result<PlanarRaster, String> {
        let r0 = tool.shape.radius();
        if !(ap > 0.0 && ap.is_finite()) {
            return Err(format!("depth of cut {ap}: must be a positive number"));
        }
        if let Some(e) = ae {
            if !(e > 0.0 && e.is_finite()) {
                return Err(format!("stepover {e}: must be a positive number"));
            }
        }
        let ball = matches!(tool.shape, Shape::Ball { .. });
        if !ball && (lead != 0.0 || tilt != 0.0) {
            return Err("lead and tilt need a ball-end mill in the planar raster".into());
        }
        if !(lead.abs() < 1.5 && tilt.abs() < 1.5) {
            return Err("lead and tilt must be under 85 degrees".into());
        }
        let rot = r_wt(lead, tilt);
        let c = mul(&rot, [0.0, 0.0, r0]);
        let offset = [-c[0], -c[1], r0 - c[2]];
        // Highest tool-frame height with a point at z_w ≤ ap: the lowest point
        // of the circle at height z is R0 + (z − R0)·cos γ − R(z)·sin γ above
        // the plane, γ the angle between the tool axis and the normal.
        let cg = rot[2][2];
        let sg = (rot[2][0].powi(2) + rot[2][1].powi(2)).sqrt();
        let low = |z: f64| {
            let r = tool.edge(z.max(1e-9)).r;
            if ball {
                r0 + (z - r0) * cg - r * sg
            } else {
                z
            }
        };
        let steps = 400;
        let top = tool.flute_length;
        let mut z_hi = 0.0;
        for i in 0..=steps {
            let z = top * i as f64 / steps as f64;
            if low(z) <= ap {
                z_hi = z;
            }
        }
        let z_hi = (z_hi + top / steps as f64).min(top);
        Ok(PlanarRaster {
            ap,
            ae,
            shape: tool.shape,
            rot,
            offset,
            z_hi,
        })
    }

    /// The point in the feed frame.
    #[inline]
    pub fn to_work(&self, p: [f64; 3]) -> [f64; 3] {
        let q = mul(&self.rot, p);
        [
            q[0] + self.offset[0],
            q[1] + self.offset[1],
            q[2] + self.offset[2],
        ]
    }
}

impl Engagement for PlanarRaster {
    fn z_range(&self, _tool: &Tool) -> (f64, f64) {
        (0.0, self.z_hi)
    }

    #[inline]
    fn contains(&self, p: [f64; 3]) -> bool {
        let r = &self.rot;
        let z = r[2][0] * p[0] + r[2][1] * p[1] + r[2][2] * p[2] + self.offset[2];
        if z > self.ap {
            return false;
        }
        let Some(ae) = self.ae else {
            return true;
        };
        let y = r[1][0] * p[0] + r[1][1] * p[1] + r[1][2] * p[2] + self.offset[1];
        // The nearest earlier pass leaves the lowest scallop (the profile
        // rises with the distance from its axis).
        let k = (-y / ae).round().max(1.0);
        let d = (y + k * ae).abs();
        d >= self.shape.radius() || z <= self.shape.height(d)
    }
}
