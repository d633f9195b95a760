//! The boundary method against the brute-force sampler on random cases, and the
//! properties of spec `working-diameter.md` §2.2 and the bounds O6.

use millplan_models::wd::*;
use proptest::prelude::*;

fn side(b: bool) -> Side {
    if b {
        Side::Left
    } else {
        Side::Right
    }
}

/// A small deterministic generator (no dependency needed for 1000 cases).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn boundary_method_agrees_with_brute_force_on_1000_cases() {
    let mut g = Lcg(7);
    let mut worst: f64 = 0.0;
    for i in 0..1000 {
        let d = 6.0 + 6.0 * g.next();
        let ap = 0.05 + 0.95 * g.next();
        let neighbour = match i % 5 {
            0 => Neighbour::None,
            4 => Neighbour::Both(0.05 + 2.0 * g.next()),
            _ => Neighbour::One(0.05 + 3.0 * g.next()),
        };
        let c = Case {
            d,
            ap,
            neighbour,
            alpha: (85.0 * g.next()).to_radians(),
            af: (-180.0 + 360.0 * g.next()).to_radians(),
            side: side(g.next() < 0.5),
        };
        let exact = working_diameter(&c);
        let reference = brute_force(&c, 150, 600);
        // The sampler can only miss the maximum, so it lies at or below.
        assert!(
            reference <= exact + 1e-9,
            "{c:?}: brute {reference} > boundary {exact}"
        );
        worst = worst.max(exact - reference);
        assert!(
            exact - reference < 2e-3,
            "{c:?}: boundary {exact} brute {reference}"
        );
    }
    eprintln!("worst boundary − brute-force difference: {worst:.2e} mm");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn bounds_symmetry_and_monotonicity(
        d in 6.0..12.0f64, ap in 0.05..1.0f64, ae in 0.05..4.0f64,
        alpha in 0.0..85.0f64, af in -180.0..180.0f64, left in any::<bool>(), k in 1.01..3.0f64,
    ) {
        let c = Case { d, ap, neighbour: Neighbour::One(ae), alpha: alpha.to_radians(), af: af.to_radians(), side: side(left) };
        let dw = working_diameter(&c);
        let upper = working_diameter(&Case { neighbour: Neighbour::None, ..c });
        // O6: D sin α ≤ D_w ≤ the no-neighbour value.
        prop_assert!(dw >= contact_diameter(d, c.alpha) - 1e-9);
        prop_assert!(dw <= upper + 1e-9);
        // Mirror symmetry: (α, A_f, left) = (α, −A_f, right).
        let m = working_diameter(&Case { af: -c.af, side: side(!left), ..c });
        prop_assert!((dw - m).abs() < 1e-9);
        // Non-decreasing in ap and in ae.
        let more_ap = working_diameter(&Case { ap: (ap * k).min(d / 2.0), ..c });
        let more_ae = working_diameter(&Case { neighbour: Neighbour::One(ae * k), ..c });
        prop_assert!(more_ap >= dw - 1e-9);
        prop_assert!(more_ae >= dw - 1e-9);
        // Scale: D_w depends on ap/D and ae/D only, times D.
        let s = working_diameter(&Case { d: d * k, ap: ap * k, neighbour: Neighbour::One(ae * k), ..c });
        prop_assert!((s - k * dw).abs() < 1e-7 * d * k);
        // Both neighbours machined can only shrink the region.
        let both = working_diameter(&Case { neighbour: Neighbour::Both(ae), ..c });
        prop_assert!(both <= dw + 1e-9);
    }

    #[test]
    fn uphill_and_downhill_do_not_depend_on_the_side(
        ap in 0.05..1.0f64, ae in 0.05..4.0f64, alpha in 0.0..85.0f64, down in any::<bool>(),
    ) {
        let af = if down { 180.0f64 } else { 0.0 };
        let c = Case { d: 10.0, ap, neighbour: Neighbour::One(ae), alpha: alpha.to_radians(), af: af.to_radians(), side: Side::Left };
        let l = working_diameter(&c);
        let r = working_diameter(&Case { side: Side::Right, ..c });
        prop_assert!((l - r).abs() < 1e-9);
    }
}
