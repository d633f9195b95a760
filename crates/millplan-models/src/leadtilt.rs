//! Lead and tilt: the local feed / cross-feed / normal frame at a cutter
//! contact point, both conversions between (lead, tilt) and a tool axis, and
//! the lead/tilt search (spec kinematics-access-tools §2.1–§2.2,
//! process-models §0 and §2.4).
//!
//! **The one convention** (process-models §0; paper 003: lead a rotation
//! about the cross-feed axis C, tilt one about the feed axis F), used by
//! `cut`, `orient` and the force model alike: in the FCN frame (f the feed,
//! n the outward normal, c = n × f) lead is a right-handed rotation about c
//! and tilt a right-handed rotation about f. A positive lead leans the shank
//! towards +f (ahead of the tip, which trails and does not cut); a positive
//! tilt leans it towards −c = f × n (to the right of the feed, seen from
//! the shank). The default composition is §0's R_wt = Rx(tilt)·Ry(lead),
//! the tool axis (sin L, −cos L·sin T, cos L·cos T) in FCN
//! ([`Variant::TiltThenLead`]). Kinematics-access-tools §2.1 writes the
//! tilt towards +c instead; process-models §0 is followed here, so that
//! spec's worked example holds with the tilt's sign turned.
//!
//! Pure geometry and a generic search: it knows no IR and no part, so the
//! force model, the planner's `orient` command and tests share it. Angles
//! are in degrees at the API, as users bound them.

use crate::force::Cut;
use millplan_geom::{DMat3, DVec3};

/// The FCN frame at a cutter-contact point (§2.1): f the feed direction in
/// the tangent plane, c = n × f the cross-feed, n the outward surface normal.
/// Right-handed and orthonormal: f × c = n.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fcn {
    pub f: DVec3,
    pub c: DVec3,
    pub n: DVec3,
}

impl Fcn {
    /// The frame from the surface normal `n` and the path step `dp`
    /// (p_{i+1} − p_i, or a central difference); `None` when the step has no
    /// component in the tangent plane or the normal is zero.
    pub fn new(n: DVec3, dp: DVec3) -> Option<Fcn> {
        let n = n.try_normalize()?;
        let f = (dp - n * dp.dot(n)).try_normalize()?;
        Some(Fcn {
            f,
            c: n.cross(f),
            n,
        })
    }

    /// World-from-FCN rotation M = [f c n] (columns).
    pub fn matrix(&self) -> DMat3 {
        DMat3::from_cols(self.f, self.c, self.n)
    }

    /// A vector given in FCN coordinates, in the world: M·t.
    pub fn to_world(&self, t: DVec3) -> DVec3 {
        self.f * t.x + self.c * t.y + self.n * t.z
    }

    /// A world vector in FCN coordinates: Mᵀ·t.
    pub fn from_world(&self, t: DVec3) -> DVec3 {
        DVec3::new(t.dot(self.f), t.dot(self.c), t.dot(self.n))
    }

    /// The tool axis (world) for `lead`, `tilt` (degrees).
    pub fn axis(&self, lead: f64, tilt: f64, v: Variant) -> DVec3 {
        self.to_world(v.axis(lead, tilt))
    }

    /// (lead, tilt) in degrees of a world tool axis.
    pub fn angles(&self, axis: DVec3, v: Variant) -> (f64, f64) {
        v.angles(self.from_world(axis.normalize()))
    }
}

/// The composition order of the two rotations (§2.2); they do not commute.
/// Both keep the signs of the convention above (lead about +c, tilt about
/// +f, right-handed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Variant {
    /// Variant 1 of kinematics-access-tools §2.2: R = Ry(lead)·Rx(tilt)
    /// (tilt about f, then lead about c, fixed axes; or lead first, then
    /// tilt about the moved feed axis, the axis swinging on a great circle):
    /// t = (sinL·cosT, −sinT, cosL·cosT). FeatureCAM's "lead first, then
    /// lean"; arcsin on the tilt.
    LeadThenTilt,
    /// Variant 2 of §2.2 and process-models §0, the default and the force
    /// model's own: R_wt = Rx(tilt)·Ry(lead) (lead about c, then tilt about
    /// f, fixed axes; or tilt first, then lead about the moved cross-feed
    /// axis): t = (sinL, −cosL·sinT, cosL·cosT).
    #[default]
    TiltThenLead,
}

impl Variant {
    /// The unit tool axis in FCN coordinates for `lead`, `tilt` (degrees).
    pub fn axis(self, lead: f64, tilt: f64) -> DVec3 {
        let (sl, cl) = lead.to_radians().sin_cos();
        let (st, ct) = tilt.to_radians().sin_cos();
        match self {
            Variant::LeadThenTilt => DVec3::new(sl * ct, -st, cl * ct),
            Variant::TiltThenLead => DVec3::new(sl, -cl * st, cl * ct),
        }
    }

    /// (lead, tilt) in degrees of a unit tool axis in FCN coordinates.
    pub fn angles(self, t: DVec3) -> (f64, f64) {
        let (l, tt) = match self {
            Variant::LeadThenTilt => (t.x.atan2(t.z), (-t.y).clamp(-1.0, 1.0).asin()),
            Variant::TiltThenLead => (t.x.clamp(-1.0, 1.0).asin(), (-t.y).atan2(t.z)),
        };
        (l.to_degrees(), tt.to_degrees())
    }

    /// The force model's lead and tilt, radians, of the tool at (`lead`,
    /// `tilt`) degrees of this variant: the (L, T) whose R_wt(L, T)·ẑ
    /// (process-models §0) is [`Variant::axis`]. The same angles for
    /// [`Variant::TiltThenLead`]; for [`Variant::LeadThenTilt`] the same
    /// axis, the tool turned about it (which changes no load: F_xy, torque
    /// and power do not depend on where the spindle angle is counted from).
    pub fn force_angles(self, lead: f64, tilt: f64) -> (f64, f64) {
        match self {
            Variant::TiltThenLead => (lead.to_radians(), tilt.to_radians()),
            Variant::LeadThenTilt => {
                let a = self.axis(lead, tilt);
                (a.x.clamp(-1.0, 1.0).asin(), (-a.y).atan2(a.z))
            }
        }
    }

    /// The force model's cutting conditions for the tool at (`lead`,
    /// `tilt`) degrees of this variant, at feed per tooth `fz` and spindle
    /// speed `rpm`: what `cut` and `orient` both evaluate.
    pub fn cut(self, fz: f64, rpm: f64, lead: f64, tilt: f64) -> Cut {
        let (lead, tilt) = self.force_angles(lead, tilt);
        Cut {
            fz,
            rpm,
            lead,
            tilt,
        }
    }
}

/// Settings of the search of process-models §2.4.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchOptions {
    /// Lead range, degrees (inclusive).
    pub lead: (f64, f64),
    /// Tilt range, degrees (inclusive).
    pub tilt: (f64, f64),
    /// Grid step, degrees (§2.4: 5°).
    pub grid: f64,
    /// Central-difference step h, degrees (§2.4: about 0.5°).
    pub h: f64,
    /// First descent step γ, degrees (§2.4: 2°).
    pub gamma: f64,
    /// The descent stops when γ falls below this, degrees (§2.4: 0.05°).
    pub gamma_min: f64,
}

impl Default for SearchOptions {
    /// The spec's values: lead 0–30°, tilt ±30°, 5° grid, h 0.5°, γ 2° down
    /// to 0.05°.
    fn default() -> Self {
        SearchOptions {
            lead: (0.0, 30.0),
            tilt: (-30.0, 30.0),
            grid: 5.0,
            h: 0.5,
            gamma: 2.0,
            gamma_min: 0.05,
        }
    }
}

/// Where the search ended.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SearchResult {
    pub lead: f64,
    pub tilt: f64,
    pub value: f64,
    /// The best grid node the descent started from.
    pub grid_lead: f64,
    pub grid_tilt: f64,
    pub grid_value: f64,
    /// Objective evaluations (grid, gradients and steps).
    pub evaluations: usize,
    /// Grid nodes the objective refused (a constraint failed).
    pub infeasible_nodes: usize,
}

/// Minimises `f(lead, tilt)` over the ranges (§2.4): a coarse grid, then
/// steepest descent from its best node with central-difference gradients,
/// steps of γ along −g/|g|, γ halved whenever a step does not improve, until
/// γ < `gamma_min`. Where the full step does not improve (or is refused),
/// a step of γ along one angle alone is tried before γ is halved, so the
/// descent slides along a constraint instead of stalling at it. `f` returns `None` where a constraint fails: such a point
/// never becomes the answer, and a gradient that needs it is taken one-sided.
/// `None` when no grid node is feasible.
pub fn search(
    mut f: impl FnMut(f64, f64) -> Option<f64>,
    o: &SearchOptions,
) -> Option<SearchResult> {
    let mut evaluations = 0usize;
    let mut eval = |l: f64, t: f64| {
        evaluations += 1;
        f(l, t).filter(|v| v.is_finite())
    };
    let nodes = |(lo, hi): (f64, f64)| {
        let n = ((hi - lo) / o.grid).floor().max(0.0) as usize;
        let mut v: Vec<f64> = (0..=n).map(|k| lo + k as f64 * o.grid).collect();
        if hi - v.last().copied().unwrap_or(lo) > 1e-9 {
            v.push(hi);
        }
        v
    };
    let mut best: Option<(f64, f64, f64)> = None;
    let mut infeasible_nodes = 0;
    for &l in &nodes(o.lead) {
        for &t in &nodes(o.tilt) {
            match eval(l, t) {
                Some(v) if best.is_none_or(|b| v < b.2) => best = Some((l, t, v)),
                Some(_) => {}
                None => infeasible_nodes += 1,
            }
        }
    }
    let (gl, gt, gv) = best?;
    let clamp = |l: f64, t: f64| (l.clamp(o.lead.0, o.lead.1), t.clamp(o.tilt.0, o.tilt.1));
    let (mut l, mut t, mut v) = (gl, gt, gv);
    let mut gamma = o.gamma;
    while gamma >= o.gamma_min {
        // Central differences, one-sided where a neighbour is refused or
        // outside the ranges.
        let diff = |eval: &mut dyn FnMut(f64, f64) -> Option<f64>, dl: f64, dt: f64| {
            let (pl, pt) = clamp(l + dl, t + dt);
            let (ml, mt) = clamp(l - dl, t - dt);
            let span = (pl - ml).abs().max((pt - mt).abs());
            let (p, m) = (eval(pl, pt), eval(ml, mt));
            match (p, m) {
                (Some(p), Some(m)) if span > 0.0 => (p - m) / span,
                (Some(p), None) if span > 0.0 => {
                    (p - v) / ((pl - l).abs().max((pt - t).abs())).max(1e-12)
                }
                (None, Some(m)) if span > 0.0 => {
                    (v - m) / ((l - ml).abs().max((t - mt).abs())).max(1e-12)
                }
                _ => 0.0,
            }
        };
        let gl = diff(&mut eval, o.h, 0.0);
        let gt = diff(&mut eval, 0.0, o.h);
        let norm = gl.hypot(gt);
        if norm == 0.0 {
            break;
        }
        let (nl, nt) = clamp(l - gamma * gl / norm, t - gamma * gt / norm);
        if let Some(nv) = eval(nl, nt).filter(|nv| *nv < v) {
            (l, t, v) = (nl, nt, nv);
            continue;
        }
        // Against a constraint the full step is refused: a step along one
        // angle alone may still improve (sliding along the boundary).
        let mut moved = false;
        for (dl, dt) in [(gamma * gl.signum(), 0.0), (0.0, gamma * gt.signum())] {
            if dl == 0.0 && dt == 0.0 {
                continue;
            }
            let (nl, nt) = clamp(l - dl, t - dt);
            if let Some(nv) = eval(nl, nt).filter(|nv| *nv < v) {
                (l, t, v) = (nl, nt, nv);
                moved = true;
                break;
            }
        }
        if !moved {
            gamma *= 0.5;
        }
    }
    Some(SearchResult {
        lead: l,
        tilt: t,
        value: v,
        grid_lead: gl,
        grid_tilt: gt,
        grid_value: gv,
        evaluations,
        infeasible_nodes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn near(a: DVec3, b: [f64; 3], tol: f64) {
        assert!((a - DVec3::from_array(b)).length() < tol, "{a:?} vs {b:?}");
    }

    /// Spec kinematics-access-tools §2.1: f × c = n, orthonormal; f is the
    /// step projected into the tangent plane.
    #[test]
    fn fcn_frame_is_right_handed() {
        let fr =
            Fcn::new(DVec3::new(0.0, -0.5, 0.866025), DVec3::new(2.0, 0.3, 0.4)).expect("frame");
        assert!((fr.f.cross(fr.c) - fr.n).length() < 1e-12);
        assert!(fr.f.dot(fr.n).abs() < 1e-12 && fr.c.dot(fr.n).abs() < 1e-12);
        assert!(fr.f.x > 0.9, "{fr:?}");
        assert!(Fcn::new(DVec3::Z, DVec3::Z).is_none());
    }

    /// Spec kinematics-access-tools §2.2, worked example: n = (0, −0.5,
    /// 0.866025), f = (1, 0, 0), c = (0, 0.866025, 0.5); variant 1 (lead
    /// first, then tilt about the moved feed axis) with L = 10°, T = 5°
    /// gives t_W = (0.172987, −0.415051, 0.893201), and back (10°, 5°).
    /// That spec leans a positive tilt towards +c; the convention here is
    /// process-models §0's (towards −c), so the same axis is (10°, −5°).
    #[test]
    fn spec_worked_example() {
        let fr = Fcn::new(DVec3::new(0.0, -0.5, 0.866025), DVec3::X).expect("frame");
        near(fr.c, [0.0, 0.866025, 0.5], 1e-6);
        let t = fr.axis(10.0, -5.0, Variant::LeadThenTilt);
        near(t, [0.172987, -0.415051, 0.893201], 2e-6);
        let (l, tt) = fr.angles(t, Variant::LeadThenTilt);
        assert!(
            (l - 10.0).abs() < 1e-9 && (tt + 5.0).abs() < 1e-9,
            "{l} {tt}"
        );
    }

    /// The signs of process-models §0 ("a positive lead leans the shank
    /// toward +x_w: the tip trails and does not cut"; R_wt = Rx(tilt)·
    /// Ry(lead), so a positive tilt turns the axis about +x_w, towards
    /// −y_w = −c) and paper 003 (lead about C, tilt about F), in both
    /// variants; and the default is §0's matrix itself.
    #[test]
    fn positive_lead_leans_towards_the_feed_positive_tilt_away_from_c() {
        for v in [Variant::LeadThenTilt, Variant::TiltThenLead] {
            let a = v.axis(10.0, 0.0);
            near(
                a,
                [10f64.to_radians().sin(), 0.0, 10f64.to_radians().cos()],
                1e-15,
            );
            let a = v.axis(0.0, 10.0);
            near(
                a,
                [0.0, -10f64.to_radians().sin(), 10f64.to_radians().cos()],
                1e-15,
            );
            // Both together: the shank ahead (+f) and on the −c side.
            let a = v.axis(20.0, 15.0);
            assert!(a.x > 0.0 && a.y < 0.0, "{v:?}: {a}");
        }
        assert_eq!(Variant::default(), Variant::TiltThenLead);
        for (l, t) in [(10.0, -10.0), (25.0, 26.4), (-5.0, 30.0)] {
            let m = crate::force::r_wt(f64::to_radians(l), f64::to_radians(t));
            let z = DVec3::new(m[0][2], m[1][2], m[2][2]);
            assert!(
                (z - Variant::default().axis(l, t)).length() < 1e-15,
                "({l}, {t})"
            );
        }
    }

    /// Process-models §1.4c, the tip-contact test §0 asks the convention to
    /// be asserted with: on the planar raster a positive lead keeps every
    /// engaged element off the tip (κ well above 0: h = −fz·sin L < 0
    /// there) at any tilt. A negative lead cuts with the tip where the tip
    /// lies in material: upright, and at a positive tilt, which leans the
    /// shank toward −c and so moves the tip toward +c, the uncut side (the
    /// earlier passes lie on −c, §1.4a); a negative tilt moves it onto the
    /// earlier passes' side, 1.7 mm out, below their scallops' reach.
    #[test]
    fn a_positive_lead_keeps_the_tip_out_of_the_cut() {
        use crate::force::coeffs::{Coeffs, Law};
        use crate::force::edge::Tool;
        use crate::force::engage::PlanarRaster;
        use crate::force::{ForceModel, Grid};
        let tool = Tool {
            shape: crate::cutter::Shape::Ball { radius: 5.0 },
            flutes: 2,
            helix: 30f64.to_radians(),
            flute_length: 30.0,
        };
        let law = Law::Rta(Coeffs::rta(1750.0, 550.0, 640.0, 0.0, 0.0, 0.0));
        let m = ForceModel::new(tool, law, Grid::default()).expect("model");
        let kappa = |l: f64, t: f64| {
            let cut = Variant::default().cut(0.1, 8000.0, l, t);
            let e = PlanarRaster::new(&tool, 0.5, Some(0.5), cut.lead, cut.tilt).expect("raster");
            m.evaluate(&cut, &e)
                .kappa_min
                .expect("engaged")
                .to_degrees()
        };
        // The lowest slice's centre (z = dz/2 = 0.025 mm) is at κ = 5.73°
        // (no higher on a finer grid); with a lead L the chip needs
        // tan κ·sin φ > tan L, so κ > L.
        let lowest = (1.0 - Grid::default().dz / 2.0 / 5.0).acos().to_degrees();
        for t in [-20.0, 0.0, 20.0] {
            assert!(
                kappa(10.0, t) > 10.0,
                "lead 10, tilt {t}: {}",
                kappa(10.0, t)
            );
        }
        for t in [0.0, 20.0] {
            let k = kappa(-10.0, t);
            assert!(k <= lowest + 1e-9, "lead −10, tilt {t}: {k}");
        }
        assert!(
            kappa(-10.0, -20.0) > 2.0 * lowest,
            "{}",
            kappa(-10.0, -20.0)
        );
    }

    /// Spec §2.2: the variants differ only when both angles are non-zero,
    /// by 0.085° at (10°, 5°) and 1.40° at (30°, −10°).
    #[test]
    fn variants_differ_as_the_spec_says() {
        let apart = |l: f64, t: f64| {
            let a = Variant::LeadThenTilt.axis(l, t);
            let b = Variant::TiltThenLead.axis(l, t);
            a.dot(b).clamp(-1.0, 1.0).acos().to_degrees()
        };
        assert!(
            (apart(10.0, 5.0) - 0.085).abs() < 0.0015,
            "{}",
            apart(10.0, 5.0)
        );
        assert!(
            (apart(30.0, -10.0) - 1.40).abs() < 0.005,
            "{}",
            apart(30.0, -10.0)
        );
        assert!(apart(20.0, 0.0) < 1e-12 && apart(0.0, -20.0) < 1e-12);
    }

    proptest! {
        /// Spec §2.2 [verified round-trips]: (L, T) → t → (L, T) for both
        /// variants, in any frame, over the ranges users give (|L|, |T| < 90°).
        #[test]
        fn round_trips(l in -89.0f64..89.0, t in -89.0f64..89.0,
                       nx in -1.0f64..1.0, ny in -1.0f64..1.0, dx in -1.0f64..1.0, dy in -1.0f64..1.0) {
            let n = DVec3::new(nx, ny, 1.5);
            let Some(fr) = Fcn::new(n, DVec3::new(dx, dy, 0.1)) else { return Ok(()); };
            for v in [Variant::LeadThenTilt, Variant::TiltThenLead] {
                let axis = fr.axis(l, t, v);
                prop_assert!((axis.length() - 1.0).abs() < 1e-12);
                let (l2, t2) = fr.angles(axis, v);
                prop_assert!((l2 - l).abs() < 1e-7 && (t2 - t).abs() < 1e-7, "{v:?}: {l2} {t2}");
            }
        }

        /// The two code paths build one tool axis: the axis `orient` writes
        /// and `post` turns into machine angles (`Fcn::axis`) is the one the
        /// force model of `cut` evaluates (R_wt of `Variant::cut`'s angles,
        /// process-models §0, taken into the world through the same frame),
        /// for any lead, tilt, feed direction and normal, in both variants;
        /// and the feed the force model sees is the frame's feed direction.
        #[test]
        fn orient_and_cut_build_the_same_axis(l in -80.0f64..80.0, t in -80.0f64..80.0,
                       nx in -1.0f64..1.0, ny in -1.0f64..1.0, dx in -1.0f64..1.0, dy in -1.0f64..1.0) {
            let Some(fr) = Fcn::new(DVec3::new(nx, ny, 1.5), DVec3::new(dx, dy, 0.1)) else { return Ok(()); };
            for v in [Variant::LeadThenTilt, Variant::TiltThenLead] {
                let cut = v.cut(0.1, 6000.0, l, t);
                let m = crate::force::r_wt(cut.lead, cut.tilt);
                let col = |k: usize| DVec3::new(m[0][k], m[1][k], m[2][k]);
                let written = fr.axis(l, t, v);
                prop_assert!((fr.to_world(col(2)) - written).length() < 1e-12, "{v:?}");
                // fz·R_wtᵀ·x̂ (§1.2) is the world feed fz·f in the tool frame.
                let fv = DVec3::from_array(cut.feed_vector());
                let tool_in_world = [col(0), col(1), col(2)].map(|c| fr.to_world(c));
                let feed = tool_in_world[0] * fv.x + tool_in_world[1] * fv.y + tool_in_world[2] * fv.z;
                prop_assert!((feed - fr.f * 0.1).length() < 1e-12, "{v:?}: {feed}");
            }
        }
    }

    /// Spec process-models §2.4, T19: f = (L − 12)² + 2(T + 7)² on the 5°
    /// grid converges to (12, −7) within 0.1°.
    #[test]
    fn t19_descent_converges() {
        let r = search(
            |l, t| Some((l - 12.0).powi(2) + 2.0 * (t + 7.0).powi(2)),
            &SearchOptions::default(),
        )
        .expect("feasible");
        assert_eq!((r.grid_lead, r.grid_tilt), (10.0, -5.0));
        assert!(
            (r.lead - 12.0).abs() < 0.1 && (r.tilt + 7.0).abs() < 0.1,
            "{r:?}"
        );
    }

    /// A constraint the optimum lies beyond: the answer stays feasible, on
    /// the boundary (here lead ≤ 8°), and refused nodes are counted.
    #[test]
    fn constrained_descent_stays_feasible() {
        let r = search(
            |l, t| (l <= 8.0).then(|| (l - 12.0).powi(2) + 2.0 * (t + 7.0).powi(2)),
            &SearchOptions::default(),
        )
        .expect("feasible");
        assert!(r.lead <= 8.0 && r.lead > 7.5, "{r:?}");
        assert!((r.tilt + 7.0).abs() < 0.3, "{r:?}");
        assert!(r.infeasible_nodes > 0);
        assert!(search(|_, _| None, &SearchOptions::default()).is_none());
    }
}
