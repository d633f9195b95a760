//! Axially symmetric cutters described by one profile: the height h(r) of the
//! cutter surface above its tip at radial distance r, for 0 ≤ r ≤ R. Flat, ball,
//! bull-nose (torus) and cone/drill tips are convex, so h is convex and
//! non-decreasing, which is what makes one drop-cutter algorithm exact for all.

/// A cutter shape, lengths in mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    Flat {
        radius: f64,
    },
    Ball {
        radius: f64,
    },
    /// Torus: corner radius `corner` on a flat of radius `radius − corner`.
    Bull {
        radius: f64,
        corner: f64,
    },
    /// Cone tip rising at `alpha` (radians) above the horizontal (drill: 90° − half
    /// the point angle).
    Cone {
        radius: f64,
        alpha: f64,
    },
}

impl Shape {
    /// From the ISO `CUTTER/` values (d, r, e, f, α): flat, ball, bull or cone.
    pub fn from_iso(d: f64, r: f64, alpha: f64) -> Option<Shape> {
        let radius = d / 2.0;
        let ball = millplan_geom::tol::is_ball(d, r);
        if !(radius > 0.0) || r < 0.0 || (r > radius + 1e-9 && !ball) {
            return None;
        }
        Some(if alpha > 1e-9 && r <= 1e-9 {
            Shape::Cone { radius, alpha }
        } else if r <= 1e-9 {
            Shape::Flat { radius }
        } else if ball {
            Shape::Ball { radius }
        } else {
            Shape::Bull { radius, corner: r }
        })
    }

    /// Parses `ball:10`, `flat:12`, `bull:10:2` (diameter, corner radius) and
    /// `cone:6:118` (diameter, included point angle in degrees).
    pub fn parse(s: &str) -> Result<Shape, String> {
        let parts: Vec<&str> = s.split(':').collect();
        let num = |i: usize| -> Result<f64, String> {
            parts
                .get(i)
                .ok_or_else(|| format!("`{s}`: missing value"))?
                .trim()
                .parse::<f64>()
                .map_err(|_| format!("`{s}`: `{}` is not a number", parts[i]))
        };
        let d = num(1)?;
        let (d_min, d_max) = millplan_geom::limits::TOOL_DIAMETER;
        if !(d > 0.0 && d.is_finite()) {
            return Err(format!("`{s}`: the diameter must be a positive number"));
        }
        if !(d_min..=d_max).contains(&d) {
            return Err(format!(
                "`{s}`: a diameter of {d} mm is no tool's (between {d_min} and {d_max} mm)"
            ));
        }
        let kind = parts[0].to_ascii_lowercase();
        let fields = match kind.as_str() {
            "ball" | "flat" | "end" => 2,
            _ => 3,
        };
        if parts.len() > fields {
            return Err(format!(
                "`{s}`: {kind} takes {} value{} ({}); `{}` is one too many",
                fields - 1,
                if fields > 2 { "s" } else { "" },
                if fields > 2 { "D:R or D:ANGLE" } else { "D" },
                parts[fields..].join(":")
            ));
        }
        let shape = match kind.as_str() {
            "ball" => Shape::Ball { radius: d / 2.0 },
            "flat" | "end" => Shape::Flat { radius: d / 2.0 },
            "bull" | "torus" => {
                let c = num(2)?;
                if !(c > 0.0 && c < d / 2.0) {
                    return Err(format!(
                        "`{s}`: the corner radius must be between 0 and d/2"
                    ));
                }
                Shape::Bull {
                    radius: d / 2.0,
                    corner: c,
                }
            }
            "cone" | "drill" => {
                let angle = num(2)?;
                if !(angle > 0.0 && angle < 180.0) {
                    return Err(format!(
                        "`{s}`: the point angle must be between 0 and 180 degrees"
                    ));
                }
                Shape::Cone {
                    radius: d / 2.0,
                    alpha: (90.0 - angle / 2.0).to_radians(),
                }
            }
            other => {
                return Err(format!(
                    "unknown cutter `{other}` (ball:D, flat:D, bull:D:R, cone:D:ANGLE)"
                ))
            }
        };
        Ok(shape)
    }

    /// The cutter shrunk inward by `t` (every point at least `t` inside the
    /// original, or a shape a little larger where the exact inset is not one
    /// of these shapes), and how far its tip rises: the tool that must still
    /// meet the part for a contact to be more than `t` deep in any direction.
    pub fn inset(&self, t: f64) -> (Shape, f64) {
        let t = t.max(0.0).min(self.radius());
        match *self {
            Shape::Flat { radius } => (Shape::Flat { radius: radius - t }, t),
            Shape::Ball { radius } => (Shape::Ball { radius: radius - t }, t),
            Shape::Bull { radius, corner } if corner > t => (
                Shape::Bull {
                    radius: radius - t,
                    corner: corner - t,
                },
                t,
            ),
            Shape::Bull { radius, .. } => (Shape::Flat { radius: radius - t }, t),
            // The flank moves in by t; the tip rises by t / cos(alpha).
            Shape::Cone { radius, alpha } => (
                Shape::Cone {
                    radius: radius - t,
                    alpha,
                },
                t / alpha.cos().max(1e-6),
            ),
        }
    }

    pub fn radius(&self) -> f64 {
        match *self {
            Shape::Flat { radius }
            | Shape::Ball { radius }
            | Shape::Bull { radius, .. }
            | Shape::Cone { radius, .. } => radius,
        }
    }

    /// Height of the cutter surface above the tip at radial distance r (r ≤ R).
    #[inline]
    pub fn height(&self, r: f64) -> f64 {
        match *self {
            Shape::Flat { .. } => 0.0,
            Shape::Ball { radius } => radius - (radius * radius - r * r).max(0.0).sqrt(),
            Shape::Bull { radius, corner } => {
                let e = radius - corner;
                if r <= e {
                    0.0
                } else {
                    let u = r - e;
                    corner - (corner * corner - u * u).max(0.0).sqrt()
                }
            }
            Shape::Cone { alpha, .. } => r * alpha.tan(),
        }
    }

    /// Slope h'(r) of the profile (r < R; for the cone's tip, 0 is a valid
    /// subgradient at r = 0).
    #[inline]
    pub fn slope(&self, r: f64) -> f64 {
        match *self {
            Shape::Flat { .. } => 0.0,
            Shape::Ball { radius } => r / (radius * radius - r * r).max(1e-300).sqrt(),
            Shape::Bull { radius, corner } => {
                let u = r - (radius - corner);
                if u <= 0.0 {
                    0.0
                } else {
                    u / (corner * corner - u * u).max(1e-300).sqrt()
                }
            }
            Shape::Cone { alpha, .. } => {
                if r > 0.0 {
                    alpha.tan()
                } else {
                    0.0
                }
            }
        }
    }

    /// The radius r* ∈ [0, R] maximising r·s − h(r): where a plane rising with
    /// slope s touches the cutter (the profile's slope equals s, or the rim).
    #[inline]
    pub fn contact_radius(&self, s: f64) -> f64 {
        if s <= 0.0 {
            return 0.0;
        }
        match *self {
            Shape::Flat { radius } => radius,
            Shape::Ball { radius } => radius * s / (1.0 + s * s).sqrt(),
            Shape::Bull { radius, corner } => (radius - corner) + corner * s / (1.0 + s * s).sqrt(),
            Shape::Cone { radius, alpha } => {
                if s > alpha.tan() {
                    radius
                } else {
                    0.0
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The corner radius of a ball end written in inches to six decimals,
    /// read in millimetres, is within rounding of half the diameter, on
    /// either side: a ball, not a bull-nose nor nothing.
    #[test]
    fn a_ball_within_rounding_of_its_radius_is_a_ball() {
        let ball = |d: f64, r: f64| matches!(Shape::from_iso(d, r, 0.0), Some(Shape::Ball { .. }));
        assert!(ball(0.393701 * 25.4, 0.19685 * 25.4));
        assert!(ball(10.0, 5.000_01));
        assert!(ball(10.0, 4.999_99));
        assert!(matches!(
            Shape::from_iso(10.0, 4.99, 0.0),
            Some(Shape::Bull { .. })
        ));
        assert_eq!(Shape::from_iso(10.0, 5.01, 0.0), None);
    }

    #[test]
    fn profiles_and_contact_radii() {
        let b = Shape::Ball { radius: 5.0 };
        assert_eq!(b.height(0.0), 0.0);
        assert!((b.height(5.0) - 5.0).abs() < 1e-12);
        // A 30° slope touches a ball at R·sin 30°.
        let s = 30f64.to_radians().tan();
        assert!((b.contact_radius(s) - 2.5).abs() < 1e-12);
        let t = Shape::Bull {
            radius: 5.0,
            corner: 1.0,
        };
        assert_eq!(t.height(4.0), 0.0);
        assert!((t.height(5.0) - 1.0).abs() < 1e-12);
        assert!((t.contact_radius(s) - 4.5).abs() < 1e-12);
        let c = Shape::parse("cone:6:90").expect("cone");
        assert!((c.height(3.0) - 3.0).abs() < 1e-12);
        assert_eq!(c.contact_radius(0.5), 0.0);
        assert_eq!(c.contact_radius(2.0), 3.0);
        // The contact radius maximises r·s − h(r) (checked by sampling).
        for sh in [b, t, c, Shape::Flat { radius: 5.0 }] {
            for s in [0.1, 0.5, 1.0, 3.0] {
                let r = sh.contact_radius(s);
                let best = (0..=10000)
                    .map(|i| sh.radius() * i as f64 / 10000.0)
                    .map(|x| x * s - sh.height(x))
                    .fold(f64::NEG_INFINITY, f64::max);
                assert!(r * s - sh.height(r) >= best - 1e-9, "{sh:?} s {s}");
            }
        }
        // The slope is the profile's derivative.
        for sh in [b, t, c, Shape::Flat { radius: 5.0 }] {
            for r in [0.5, 2.0, 4.2, 4.9] {
                let e = 1e-6;
                let fd = (sh.height(r + e) - sh.height(r - e)) / (2.0 * e);
                assert!((sh.slope(r) - fd).abs() < 1e-5, "{sh:?} r {r}");
            }
        }
        assert_eq!(
            Shape::from_iso(10.0, 5.0, 0.0),
            Some(Shape::Ball { radius: 5.0 })
        );
        assert_eq!(
            Shape::from_iso(16.0, 0.0, 31f64.to_radians()),
            Some(Shape::Cone {
                radius: 8.0,
                alpha: 31f64.to_radians()
            })
        );
        assert!(
            Shape::parse("bull:10:6").is_err()
                && Shape::parse("spoon:3").is_err()
                && Shape::parse("ball:-1").is_err()
        );
    }

    /// A diameter no writer can give back (the fuzz run's `ball:1e-300`,
    /// written as `d=0` and refused when read back) is refused where it is
    /// given; a micrometre tool is still one.
    #[test]
    fn diameters_outside_the_plausible_range_are_refused() {
        assert!(Shape::parse("ball:1e-300").is_err());
        assert!(Shape::parse("flat:1e7").is_err());
        assert_eq!(
            Shape::parse("ball:0.001"),
            Ok(Shape::Ball { radius: 0.0005 })
        );
    }
}
