//! Non-rational B-splines from NX `NURBS/KNOT/CNTRL` records, sampled to a chord tolerance.
//!
//! NX writes a cubic, clamped spline whose first control point is the preceding
//! GOTO; the `KNOT/` values omit the leading zeros and the last three ones. So with
//! n `CNTRL/` points (n + 1 control points in all) NX writes n − 2 knots: the
//! interior knots followed by a single 1. Every spline in `nx-clsf-ballend-nurbs`
//! follows that rule; a full knot vector (n + 1 + 4 values) is accepted as well.

use millplan_geom::DVec3;

pub const DEGREE: usize = 3;

/// A clamped B-spline of degree 3.
#[derive(Clone, Debug)]
pub struct BSpline {
    pub knots: Vec<f64>,
    pub ctrl: Vec<DVec3>,
}

impl BSpline {
    /// Builds the spline from what the file wrote; `Err` says why it is inconsistent.
    pub fn from_nx(
        start: DVec3,
        written_knots: &[f64],
        cntrl: &[DVec3],
    ) -> Result<BSpline, String> {
        let mut ctrl = Vec::with_capacity(cntrl.len() + 1);
        ctrl.push(start);
        ctrl.extend_from_slice(cntrl);
        let n = ctrl.len();
        if n < DEGREE + 1 {
            return Err(format!(
                "a cubic spline needs at least 4 control points, found {n}"
            ));
        }
        let knots = if written_knots.len() == n + DEGREE + 1 {
            written_knots.to_vec()
        } else if written_knots.len() + 2 * DEGREE + 1 == n + DEGREE + 1 {
            let mut k = vec![0.0; DEGREE + 1];
            k.extend_from_slice(written_knots);
            let last = *written_knots.last().unwrap_or(&1.0);
            k.extend(std::iter::repeat_n(last, DEGREE));
            k
        } else {
            return Err(format!(
                "{} knots do not fit {} control points of a cubic spline (expected {} or {})",
                written_knots.len(),
                n,
                n - DEGREE,
                n + DEGREE + 1
            ));
        };
        if knots.windows(2).any(|w| w[1] < w[0]) || knots.iter().any(|k| !k.is_finite()) {
            return Err("knot vector is not non-decreasing".into());
        }
        if knots[DEGREE] >= knots[n] {
            return Err("knot vector has an empty parameter range".into());
        }
        Ok(BSpline { knots, ctrl })
    }

    pub fn range(&self) -> (f64, f64) {
        (self.knots[DEGREE], self.knots[self.ctrl.len()])
    }

    /// Point at parameter `u` (de Boor).
    pub fn eval(&self, u: f64) -> DVec3 {
        let n = self.ctrl.len();
        let (lo, hi) = self.range();
        let u = u.clamp(lo, hi);
        // Knot span: largest k in [p, n-1] with knots[k] <= u.
        let mut k = DEGREE;
        while k + 1 < n && self.knots[k + 1] <= u {
            k += 1;
        }
        let mut d = [DVec3::ZERO; DEGREE + 1];
        for (j, dj) in d.iter_mut().enumerate() {
            *dj = self.ctrl[j + k - DEGREE];
        }
        for r in 1..=DEGREE {
            for j in (r..=DEGREE).rev() {
                let i = j + k - DEGREE;
                let den = self.knots[i + DEGREE + 1 - r] - self.knots[i];
                let a = if den > 0.0 {
                    (u - self.knots[i]) / den
                } else {
                    0.0
                };
                d[j] = d[j - 1] * (1.0 - a) + d[j] * a;
            }
        }
        d[DEGREE]
    }

    /// Points after the start, so that every chord stays within `tol` of the curve
    /// (checked at the chord's quarter points), ending exactly at the curve's end.
    pub fn sample(&self, tol: f64) -> Vec<DVec3> {
        self.sample_within(tol, u64::MAX).unwrap_or_default()
    }

    /// [`BSpline::sample`], giving up as soon as one polynomial piece (span)
    /// needs more than `per_span` points: `Err(span)` with the span's number
    /// (from 1). The work done is bounded by the limit, whatever the control
    /// points (a spline with points at 1e12 would otherwise become millions
    /// of moves).
    pub fn sample_within(&self, tol: f64, per_span: u64) -> Result<Vec<DVec3>, usize> {
        // Seed with the distinct knots so each polynomial piece is subdivided on its own.
        let mut params: Vec<f64> = self.knots[DEGREE..=self.ctrl.len()].to_vec();
        params.dedup();
        let mut out = Vec::new();
        for (k, w) in params.windows(2).enumerate() {
            let before = out.len();
            // One point over the limit is enough to know.
            let mut budget = per_span.saturating_add(1);
            self.refine(
                (w[0], self.eval(w[0])),
                (w[1], self.eval(w[1])),
                tol,
                0,
                &mut budget,
                &mut out,
            );
            if (out.len() - before) as u64 > per_span {
                return Err(k + 1);
            }
        }
        Ok(out)
    }

    /// Subdivides (u0, p0)–(u1, p1) until its chords are within `tol`, one
    /// point from `budget` each; stops when the budget runs out.
    fn refine(
        &self,
        (u0, p0): (f64, DVec3),
        (u1, p1): (f64, DVec3),
        tol: f64,
        depth: u32,
        budget: &mut u64,
        out: &mut Vec<DVec3>,
    ) {
        if *budget == 0 {
            return;
        }
        let um = 0.5 * (u0 + u1);
        let pm = self.eval(um);
        let dev = |q: DVec3| dist_to_segment(q, p0, p1);
        let worst = dev(pm)
            .max(dev(self.eval(0.5 * (u0 + um))))
            .max(dev(self.eval(0.5 * (um + u1))));
        if worst > tol && depth < 24 {
            self.refine((u0, p0), (um, pm), tol, depth + 1, budget, out);
            self.refine((um, pm), (u1, p1), tol, depth + 1, budget, out);
        } else {
            *budget -= 1;
            out.push(p1);
        }
    }
}

fn dist_to_segment(q: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    if l2 == 0.0 {
        return (q - a).length();
    }
    let t = ((q - a).dot(ab) / l2).clamp(0.0, 1.0);
    (q - (a + ab * t)).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamped_spline_interpolates_ends_and_reproduces_a_line() {
        // Control points on a straight line: the curve is that line.
        let start = DVec3::ZERO;
        let cntrl: Vec<DVec3> = (1..=6)
            .map(|i| DVec3::new(i as f64, 2.0 * i as f64, 0.0))
            .collect();
        let s = BSpline::from_nx(start, &[0.25, 0.5, 0.75, 1.0], &cntrl).expect("valid");
        millplan_geom::assert_near!(s.eval(0.0), start, 1e-12);
        millplan_geom::assert_near!(s.eval(1.0), cntrl[5], 1e-12);
        let pts = s.sample(1e-3);
        for p in &pts {
            assert!((p.y - 2.0 * p.x).abs() < 1e-9);
        }
        assert_eq!(*pts.last().expect("points"), cntrl[5]);
    }

    #[test]
    fn chord_tolerance_holds_on_a_curved_spline() {
        let cntrl = [
            DVec3::new(10., 0., 0.),
            DVec3::new(10., 10., 0.),
            DVec3::new(0., 10., 5.),
            DVec3::new(-5., 3., 0.),
        ];
        let s = BSpline::from_nx(DVec3::ZERO, &[0.4, 1.0], &cntrl).expect("valid");
        let tol = 0.01;
        let pts = s.sample(tol);
        let mut prev = s.eval(0.0);
        let mut seg = Vec::new();
        for p in &pts {
            seg.push((prev, *p));
            prev = *p;
        }
        for k in 0..=2000 {
            let q = s.eval(k as f64 / 2000.0);
            let d = seg
                .iter()
                .map(|(a, b)| dist_to_segment(q, *a, *b))
                .fold(f64::INFINITY, f64::min);
            assert!(d <= tol * 1.01, "deviation {d} at {k}");
        }
    }

    #[test]
    fn inconsistent_knots_are_rejected() {
        let cntrl = [DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE];
        assert!(BSpline::from_nx(DVec3::ZERO, &[0.1, 0.2, 0.3, 1.0], &cntrl).is_err());
        assert!(BSpline::from_nx(DVec3::ZERO, &[0.5, 0.2], &cntrl).is_err());
    }
}
