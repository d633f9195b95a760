//! The cutting edge of a helical end mill discretised into axial slices
//! (spec `process-models.md` §1.1), precomputed once per tool and grid.
//!
//! Every slice is described at the absolute angle θ = 0 (the edge point at
//! (0, R, z) in the tool frame); an edge point at θ is the same slice rotated
//! about the tool axis, so the per-slice data serve every flute and every
//! spindle angle.

use crate::cutter::Shape;

/// A cutter with helical flutes, lengths in mm, angles in rad.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tool {
    /// Ball, flat or bull (torus) profile; cone tips have no helical edge model.
    pub shape: Shape,
    /// Number of equally spaced flutes (any count from 1).
    pub flutes: usize,
    /// Nominal helix angle i0 (constant lead: lag ψ(z) = z·tan(i0)/R0).
    pub helix: f64,
    /// Height of the fluted part above the tip; the edge ends there.
    pub flute_length: f64,
}

impl Tool {
    /// Checks that the tool can be discretised.
    pub fn validate(&self) -> Result<(), String> {
        let r = self.shape.radius();
        if !(r > 0.0 && r.is_finite()) {
            return Err("the tool radius must be a positive number".into());
        }
        if matches!(self.shape, Shape::Cone { .. }) {
            return Err(
                "the force model covers ball, flat and bull end mills, not cone tips".into(),
            );
        }
        if self.flutes == 0 || self.flutes > 64 {
            return Err(format!("{} flutes: must be from 1 to 64", self.flutes));
        }
        if !(self.helix.abs() < 80f64.to_radians()) {
            return Err("the helix angle must be under 80 degrees".into());
        }
        if !(self.flute_length > 0.0 && self.flute_length.is_finite()) {
            return Err("the flute length must be a positive number".into());
        }
        Ok(())
    }
}

/// Local geometry of the edge at height z (§1.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgePoint {
    /// Radius R(z) of the edge.
    pub r: f64,
    /// Axial immersion angle κ: 0 at a ball tip, π/2 on the cylinder.
    pub kappa: f64,
    /// dR/dz (cot κ on a round part, 0 on the cylinder).
    pub dr_dz: f64,
    /// Lag angle ψ(z).
    pub psi: f64,
    /// tan of the local helix angle, R(z)·tan(i0)/R0.
    pub tan_i: f64,
}

impl Tool {
    /// The edge at height z ≥ 0 above the tip (z > 0 on round profiles: the
    /// tip itself is singular, §1.1).
    pub fn edge(&self, z: f64) -> EdgePoint {
        let r0 = self.shape.radius();
        let (r, kappa, dr_dz) = match self.shape {
            Shape::Ball { radius } if z < radius => {
                let r = (z * (2.0 * radius - z)).max(0.0).sqrt();
                let ck = ((radius - z) / radius).clamp(-1.0, 1.0);
                (r, ck.acos(), (radius - z) / r.max(1e-12))
            }
            Shape::Bull { radius, corner } if z < corner => {
                let u = (z * (2.0 * corner - z)).max(0.0).sqrt();
                let ck = ((corner - z) / corner).clamp(-1.0, 1.0);
                (radius - corner + u, ck.acos(), (corner - z) / u.max(1e-12))
            }
            _ => (r0, std::f64::consts::FRAC_PI_2, 0.0),
        };
        let t = self.helix.tan();
        EdgePoint {
            r,
            kappa,
            dr_dz,
            psi: z * t / r0,
            tan_i: r * t / r0,
        }
    }
}

/// One slice of the edge, cell-centred at meridian length `u` (height `z`)
/// with length `dz` along the meridian (the height on the cylinder).
#[derive(Clone, Copy, Debug)]
pub struct Slice {
    pub z: f64,
    /// Meridian length from the tip to the centre, mm ([`meridian`]).
    pub u: f64,
    /// Length along the meridian, mm.
    pub dz: f64,
    pub edge: EdgePoint,
    pub sin_k: f64,
    pub cos_k: f64,
    /// Chip width db: the meridian's arc over the slice (dz / sin κ in
    /// heights).
    pub db: f64,
    /// Edge arc length dS = dh·sqrt(1 + (dR/dz)² + (R tan i0/R0)²) over the
    /// slice's height dh.
    pub ds: f64,
    /// Unit vectors at θ = 0 in the tool frame: outward surface normal n,
    /// edge tangent t (toward the shank), cutting velocity v.
    pub normal: [f64; 3],
    pub tangent: [f64; 3],
}

/// Cell-centred slices covering heights [z_lo, z_hi] with cells of about
/// `dz` along the meridian: equal lengths of the profile, so a ball's tip is
/// sliced as finely in κ as its side (equal heights would give the slice at
/// the tip an arc of sqrt(2·R·dz), where the chip's direction turns fastest).
/// Never evaluates at the tip itself.
pub fn slices(tool: &Tool, z_lo: f64, z_hi: f64, dz: f64) -> Vec<Slice> {
    let z_lo = z_lo.max(0.0);
    let z_hi = z_hi.min(tool.flute_length);
    if !(z_hi > z_lo) || !(dz > 0.0) {
        return Vec::new();
    }
    let (u_lo, u_hi) = (meridian(&tool.shape, z_lo), meridian(&tool.shape, z_hi));
    let n = ((u_hi - u_lo) / dz).ceil().max(1.0) as usize;
    let h = (u_hi - u_lo) / n as f64;
    let ti = tool.helix.tan() / tool.shape.radius();
    (0..n)
        .map(|i| {
            let u = u_lo + (i as f64 + 0.5) * h;
            let z = height(&tool.shape, u);
            let e = tool.edge(z);
            let (sin_k, cos_k) = e.kappa.sin_cos();
            let sin_k = sin_k.max(1e-9);
            // Edge r(z) = (R sin(θ0 − ψ), R cos(θ0 − ψ), z); at θ = 0 its
            // derivative is (−R ψ', R', 1).
            let d = [-e.r * ti, e.dr_dz, 1.0];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            Slice {
                z,
                u,
                dz: h,
                edge: e,
                sin_k,
                cos_k,
                db: h,
                ds: h * sin_k * len,
                normal: [0.0, sin_k, -cos_k],
                tangent: [d[0] / len, d[1] / len, d[2] / len],
            }
        })
        .collect()
}

/// Length of the edge's meridian (the profile in the plane through the
/// axis) from the tip up to height z, mm: ρ·κ(z) on a round part of radius
/// ρ, then the straight side.
pub fn meridian(shape: &Shape, z: f64) -> f64 {
    let z = z.max(0.0);
    match *shape {
        Shape::Ball { radius: rho } | Shape::Bull { corner: rho, .. } if rho > 0.0 => {
            if z < rho {
                rho * ((rho - z) / rho).clamp(-1.0, 1.0).acos()
            } else {
                rho * std::f64::consts::FRAC_PI_2 + (z - rho)
            }
        }
        _ => z,
    }
}

/// The height above the tip at meridian length `u` ([`meridian`]'s inverse).
pub fn height(shape: &Shape, u: f64) -> f64 {
    let u = u.max(0.0);
    match *shape {
        Shape::Ball { radius: rho } | Shape::Bull { corner: rho, .. } if rho > 0.0 => {
            let quarter = rho * std::f64::consts::FRAC_PI_2;
            if u < quarter {
                rho * (1.0 - (u / rho).cos())
            } else {
                rho + (u - quarter)
            }
        }
        _ => u,
    }
}
