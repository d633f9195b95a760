//! Oracles T10a–T10f of spec `process-models.md` §6 for the zero-order
//! stability lobes (§3), on the Insperger & Stépán benchmark.

use millplan_models::lobes::{a_lim_at, directional, immersion, minimum, Mode, Setup};
use std::f64::consts::PI;

const KR: f64 = 1.0 / 3.0;

fn bench_mode() -> Mode {
    // m = 0.03993 kg, fn = 922 Hz → k = m·ωn².
    let k = 0.03993 * (2.0 * PI * 922.0f64).powi(2);
    assert!((k - 1.34005e6).abs() < 0.00001e6 * 5.0, "k = {k}");
    Mode {
        fn_hz: 922.0,
        k,
        zeta: 0.011,
    }
}

fn assert_factors(got: [f64; 4], want: [f64; 4], what: &str) {
    for (g, w) in got.iter().zip(want) {
        assert!(
            (g - w).abs() <= 1e-5 * w.abs().max(1.0),
            "{what}: {got:?} vs {want:?}"
        );
    }
}

#[test]
fn t10a_t10c_directional_factors() {
    assert_factors(
        directional(KR, 0.0, PI),
        [-PI / 3.0, -PI, PI, -PI / 3.0], // (−1.0472, −π, π, −1.0472)
        "T10a slot",
    );
    assert_factors(
        directional(KR, 0.0, PI / 2.0),
        [-1.5236, -1.90413, 1.23746, 0.4764],
        "T10b half up",
    );
    assert_factors(
        directional(KR, PI / 2.0, PI),
        [0.4764, -1.23746, 1.90413, -1.5236],
        "T10c half down",
    );
    // Radial depth → immersion.
    assert_eq!(immersion(10.0, 10.0, true), (0.0, PI));
    let (st, ex) = immersion(5.0, 10.0, false);
    assert!(st == 0.0 && (ex - PI / 2.0).abs() < 1e-12);
}

#[test]
fn t10d_sdof_frf_minimum() {
    let m = bench_mode();
    let want = -1.0 / (4.0 * m.k * m.zeta * (1.0 + m.zeta));
    assert!((want - -1.67755e-5).abs() <= 1e-4 * 1.67755e-5);
    let wn = 2.0 * PI * m.fn_hz;
    let got = (0..200_000)
        .map(|i| m.frf(wn * (0.9 + 0.2 * i as f64 / 200_000.0)).0)
        .fold(f64::INFINITY, f64::min);
    assert!((got - want).abs() <= 1e-4 * want.abs(), "Re G min {got}");
}

fn slot(x: Option<Mode>, y: Option<Mode>) -> Setup {
    Setup {
        x,
        y,
        flutes: 2,
        kt: 6e8,
        kr: KR,
        st: 0.0,
        ex: PI,
    }
}

#[test]
fn t10e_flexible_in_x_only() {
    let m = bench_mode();
    let s = slot(Some(m), None);
    s.validate().expect("valid");
    let lobes = s.lobes(900.0, 1000.0, 100_001, 3);
    let min = minimum(&lobes).expect("lobes");
    let want = 8.0 * m.k * m.zeta * (1.0 + m.zeta) / (2.0 * 2e8) * 1000.0;
    assert!((want - 0.29805).abs() < 0.0001);
    assert!(
        (min.a_lim_mm - want).abs() <= 0.005 * want,
        "a_lim,min {}",
        min.a_lim_mm
    );
}

#[test]
fn t10f_symmetric_slot() {
    let m = bench_mode();
    let s = slot(Some(m), Some(m));
    let lobes = s.lobes(900.0, 1100.0, 200_001, 4);
    let min = minimum(&lobes).expect("lobes");
    assert!(
        (min.a_lim_mm - 0.0479).abs() <= 0.005 * 0.0479,
        "a_lim,min {}",
        min.a_lim_mm
    );
    assert!(
        (min.fc_hz - 923.6).abs() <= 0.01 * 923.6,
        "f_c {}",
        min.fc_hz
    );
    // Lobe k = 0 of the lower branch: its minimum sits at about 50 100 1/min.
    let k0 = lobes
        .iter()
        .find(|l| l.k == 0 && l.branch == 0)
        .expect("lobe 0");
    let p0 = k0
        .points
        .iter()
        .min_by(|a, b| a.a_lim_mm.total_cmp(&b.a_lim_mm))
        .expect("points");
    assert!(
        (p0.rpm - 50_100.0).abs() <= 0.01 * 50_100.0,
        "lobe 0 at {}",
        p0.rpm
    );
    // The second eigenvalue branch has its minimum at 1.94 mm.
    let b1 = lobes
        .iter()
        .filter(|l| l.branch == 1)
        .flat_map(|l| l.points.iter())
        .map(|p| p.a_lim_mm)
        .fold(f64::INFINITY, f64::min);
    assert!(
        (b1 - 1.94).abs() <= 0.005 * 1.94 + 0.005,
        "second branch {b1}"
    );
    // The envelope at the lobe's best speed is the minimum itself, and it
    // rises away from the resonance.
    let at = a_lim_at(&lobes, p0.rpm).expect("covered");
    assert!((at - p0.a_lim_mm).abs() < 1e-3);
    // Closed form of §6 T10f: a_lim(ω) = −2/(N(Kn·Re G ± Kt·Im G)).
    let w = 2.0 * PI * min.fc_hz;
    let (re, im) = m.frf(w);
    let cf = [-1.0, 1.0]
        .iter()
        .map(|sg| -2.0 / (2.0 * (2e8 * re + sg * 6e8 * im)) * 1000.0)
        .filter(|a| *a > 0.0)
        .fold(f64::INFINITY, f64::min);
    assert!((cf - min.a_lim_mm).abs() <= 0.005 * cf, "closed form {cf}");
}

#[test]
fn invalid_setups_are_refused() {
    let m = bench_mode();
    assert!(slot(None, None).validate().is_err());
    assert!(slot(Some(Mode { zeta: 0.0, ..m }), None)
        .validate()
        .is_err());
    assert!(Setup {
        flutes: 0,
        ..slot(Some(m), None)
    }
    .validate()
    .is_err());
}
