//! Oracles T10a–T10f of spec `process-models.md` §6 for the zero-order
//! stability lobes (§3), on the Insperger & Stépán benchmark; the complete
//! envelope (issue 30 item 3) against an independent brute-force solver
//! written here from §3.

use millplan_models::lobes::{
    directional, immersion, LobesError, Mode, Setup, Stability, CEILING_MM, MAX_LOBES,
};
use std::f64::consts::PI;

#[path = "lobes_brute/mod.rs"]
mod brute;
use brute::Brute;

const KR: f64 = 1.0 / 3.0;

/// Agreement of the envelope with the brute force, relative (measured: at
/// most 0.012 % on the random sweep).
const TOL: f64 = 0.001;

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

fn brute(s: &Setup) -> Brute {
    let m = |m: Mode| brute::Sdof {
        fn_hz: m.fn_hz,
        k: m.k,
        zeta: m.zeta,
    };
    Brute {
        x: s.x.map(m),
        y: s.y.map(m),
        flutes: s.flutes as f64,
        kt: s.kt,
        kr: s.kr,
        st: s.st,
        ex: s.ex,
    }
}

/// The brute force's frequency step for a setup: 1/50 of the narrowest
/// ζ·fn and 1/100 of the tooth-passing frequency at `n` (the step only
/// has to separate a root's crossings of the real axis, each then found by
/// bisection; at 1/20 and 1/40 it misses some).
fn brute_step(s: &Setup, n: f64) -> f64 {
    let narrow =
        s.x.iter()
            .chain(s.y.iter())
            .map(|m| m.zeta * m.fn_hz)
            .fold(f64::INFINITY, f64::min);
    (narrow / 50.0).min(s.flutes as f64 * n / 60.0 / 100.0)
}

#[test]
fn t10e_flexible_in_x_only() {
    let m = bench_mode();
    let s = slot(Some(m), None);
    s.validate().expect("valid");
    let min = s.minimum().expect("a minimum");
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
    let min = s.minimum().expect("a minimum");
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
    // Lobe k = 0: its bottom sits at about 50 100 1/min.
    let n0 = s.lobe_speed(&min, 0);
    assert!((n0 - 50_100.0).abs() <= 0.01 * 50_100.0, "lobe 0 at {n0}");
    // The second eigenvalue branch (the higher root) has its minimum at
    // 1.94 mm.
    let b1 = (0..200_001)
        .filter_map(|i| {
            let w = 2.0 * PI * (900.0 + 200.0 * i as f64 / 200_000.0);
            let r: Vec<f64> = s.limits_at(w).into_iter().flatten().map(|x| x.0).collect();
            (r.len() == 2).then(|| r[0].max(r[1]))
        })
        .fold(f64::INFINITY, f64::min);
    assert!(
        (b1 - 1.94).abs() <= 0.005 * 1.94 + 0.005,
        "second branch {b1}"
    );
    // The envelope at the bottom of lobe 0 is the minimum itself, set by
    // lobe 0 at the minimum's chatter frequency.
    let st = s.stability(0.95 * n0, 1.05 * n0).expect("envelope");
    let at = st
        .envelope
        .iter()
        .min_by(|a, b| (a.rpm - n0).abs().total_cmp(&(b.rpm - n0).abs()))
        .expect("points");
    assert!((at.a_lim_mm - min.a_lim_mm).abs() <= 1e-3 * min.a_lim_mm);
    let c = at.chatter.expect("a lobe sets it");
    assert_eq!(c.lobe, 0);
    assert!((c.fc_hz - min.fc_hz).abs() < 1.0);
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
    for bad in [
        Mode { zeta: 0.0, ..m },
        Mode { fn_hz: 1e-18, ..m },
        Mode { fn_hz: 2e5, ..m },
        Mode { k: 1e-300, ..m },
        Mode {
            zeta: f64::NAN,
            ..m
        },
    ] {
        assert!(slot(Some(bad), None).validate().is_err(), "{bad:?}");
        assert!(slot(Some(bad), None).stability(1000.0, 2000.0).is_err());
    }
    assert!(Setup {
        flutes: 0,
        ..slot(Some(m), None)
    }
    .validate()
    .is_err());
    assert!(Setup {
        kt: 1e-308,
        ..slot(Some(m), None)
    }
    .validate()
    .is_err());
    let s = slot(Some(m), Some(m));
    for (lo, hi) in [(3000.0, 2000.0), (0.0, 2000.0), (1000.0, f64::INFINITY)] {
        assert!(matches!(s.stability(lo, hi), Err(LobesError::Invalid(_))));
    }
}

/// The benchmark of §3 in a slot, flexible in x and y.
fn benchmark() -> Setup {
    let m = Mode {
        fn_hz: 922.0,
        k: 1.34005e6,
        zeta: 0.011,
    };
    slot(Some(m), Some(m))
}

/// Issue 30 item 3: lobes beyond a fixed count were dropped, so the
/// deepest stable cut in 2000…3000 1/min was read from a gap between
/// lobes 0…9 (127.29 mm at 2,677 1/min). The zero-order limit there is
/// 0.17 mm at about 2,770 1/min.
#[test]
fn the_deepest_cut_takes_every_lobe_in_the_range() {
    let s = benchmark();
    let st = s.stability(2000.0, 3000.0).expect("envelope");
    let d = st.deepest;
    assert!(d.a_lim_mm <= 0.2, "deepest {d:?}");
    assert!((2700.0..=2800.0).contains(&d.rpm), "deepest {d:?}");
    for p in st
        .envelope
        .iter()
        .filter(|p| (2700.0..=2800.0).contains(&p.rpm))
    {
        assert!(p.a_lim_mm <= 0.2, "{p:?}");
    }
    // Every point is set by a lobe, and the lobes there run well past 9.
    assert!(st.envelope.iter().all(|p| p.chatter.is_some()));
    let (lo, hi) = st.lobes().expect("lobes");
    assert!(lo >= 9 && hi >= 13, "lobes {lo}…{hi}");
    assert!(d.a_lim_mm <= st.exact_below_mm);
    // The independent solver agrees at the deepest point, and nowhere in
    // the range finds a deeper stable cut.
    let b = brute(&s);
    let df = brute_step(&s, 2000.0);
    let at = b.a_lim(d.rpm, 6.0 * 922.0, df);
    assert!((at - d.a_lim_mm).abs() <= TOL * at, "brute {at} vs {d:?}");
    for i in 0..=200 {
        let n = 2000.0 + 5.0 * i as f64;
        let a = b.a_lim(n, 6.0 * 922.0, df);
        assert!(
            a <= d.a_lim_mm * (1.0 + TOL),
            "{n} 1/min: brute {a} above {d:?}"
        );
    }
}

/// Issue 30: the old default range started at 2,735.16 1/min (0.9 times
/// the lowest bottom of lobes 0…9), where lobes 10 and up reach: its first
/// envelope point was 0.41 mm, the zero-order limit there is 0.11 mm. The
/// default range now starts at 0.9 times the bottom of lobe 9 of the lowest
/// root; its first point takes every lobe there as well.
#[test]
fn the_default_range_starts_with_every_lobe() {
    let s = benchmark();
    let b = brute(&s);
    let old = s.stability(2735.16, 3000.0).expect("envelope").envelope[0];
    let want = b.a_lim(2735.16, 6.0 * 922.0, brute_step(&s, 2735.16));
    assert!((want - 0.11).abs() < 0.01, "brute {want}");
    assert!(
        (old.a_lim_mm - want).abs() <= TOL * want,
        "{old:?} vs {want}"
    );
    let min = s.minimum().expect("minimum");
    let (lo, hi) = s.default_range(&min);
    assert!((lo - 0.9 * s.lobe_speed(&min, 9)).abs() < 1e-9 * lo);
    assert!((hi - 1.3 * s.lobe_speed(&min, 0)).abs() < 1e-9 * hi);
    let first = s.stability(lo, hi).expect("envelope").envelope[0];
    assert_eq!(first.rpm, lo);
    let want = b.a_lim(lo, 6.0 * 922.0, brute_step(&s, lo));
    assert!(
        (first.a_lim_mm - want).abs() <= TOL * want,
        "{first:?} vs {want}"
    );
    assert!(first.chatter.expect("a lobe").lobe >= 10);
}

/// A fixed pseudo-random sequence (64-bit LCG), so the sweep is the same
/// on every run.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn log(&mut self, lo: f64, hi: f64) -> f64 {
        lo * (hi / lo).powf(self.next())
    }
    fn pick<T: Copy>(&mut self, v: &[T]) -> T {
        v[((self.next() * v.len() as f64) as usize).min(v.len() - 1)]
    }
}

fn random_mode(r: &mut Lcg) -> Mode {
    Mode {
        fn_hz: r.log(200.0, 3000.0),
        k: r.log(1e6, 1e8),
        zeta: r.log(0.005, 0.05),
    }
}

/// A random setup: modes, flutes, coefficients, immersion; the y mode the
/// same as x, its own, or rigid.
fn random_setup(r: &mut Lcg) -> Setup {
    let x = random_mode(r);
    let y = match r.pick(&[0, 1, 2]) {
        0 => Some(x),
        1 => Some(Mode {
            fn_hz: x.fn_hz * r.log(0.7, 1.4),
            ..random_mode(r)
        }),
        _ => None,
    };
    let (st, ex) = r.pick(&[
        (0.0, PI),
        (0.0, PI / 2.0),
        (PI / 2.0, PI),
        immersion(3.0, 10.0, true),
    ]);
    Setup {
        x: Some(x),
        y,
        flutes: r.pick(&[2, 3, 4, 6]),
        kt: r.log(500.0, 2500.0) * 1e6,
        kr: 0.1 + 0.5 * r.next(),
        st,
        ex,
    }
}

/// Compares an envelope with the brute force at `samples` of its speeds
/// and at its deepest point, and checks that the brute force finds no
/// deeper stable cut at those speeds: the largest relative deviation.
fn against_brute(s: &Setup, st: &Stability, samples: usize, f_top: f64) -> f64 {
    let b = brute(s);
    let df = brute_step(s, st.envelope[0].rpm);
    let mut worst: f64 = 0.0;
    let mut check = |p: &millplan_models::lobes::EnvPoint| {
        let want = b.a_lim(p.rpm, f_top, df);
        if p.chatter.is_some() {
            worst = worst.max((p.a_lim_mm - want).abs() / want);
        } else {
            // Only a bound: the true limit lies at or above it.
            assert!(
                want >= p.a_lim_mm * (1.0 - TOL),
                "{s:?}: {p:?} vs brute {want}"
            );
        }
        assert!(
            want <= st.deepest.a_lim_mm * (1.0 + TOL),
            "{s:?}: brute {want} at {} above the deepest {:?}",
            p.rpm,
            st.deepest
        );
    };
    let step = (st.envelope.len() / samples).max(1);
    st.envelope.iter().step_by(step).for_each(&mut check);
    check(&st.deepest);
    worst
}

/// Issue 30 item 3 (b): speed ranges well below the first lobe (lobes 3 to
/// 40 around the natural frequency), on 30 random setups, against the
/// independent solver: every compared point within `TOL`.
#[test]
fn envelopes_below_the_first_lobe_match_the_brute_force() {
    let mut r = Lcg(0x5eed_1ab5);
    let mut worst: f64 = 0.0;
    for _ in 0..30 {
        let s = random_setup(&mut r);
        s.validate().expect("valid");
        let k = r.log(3.0, 40.0);
        let n = 60.0 * s.x.expect("x").fn_hz / (s.flutes as f64 * k);
        let st = s.stability(n / r.log(1.05, 1.5), n).expect("envelope");
        let f_top = 6.0 * s.max_fn();
        worst = worst.max(against_brute(&s, &st, 20, f_top));
    }
    eprintln!(
        "largest deviation from the brute force: {:.3} %",
        100.0 * worst
    );
    assert!(worst <= TOL, "largest deviation {worst}");
}

/// Above lobe 0 the chatter frequency follows the tooth frequency far past
/// the natural frequency: the band must grow until nothing above it can
/// come lower, and the envelope must still match the brute force (here
/// scanning up to 40 times the natural frequency).
#[test]
fn the_band_grows_above_lobe_0() {
    let s = benchmark();
    let min = s.minimum().expect("minimum");
    let n0 = s.lobe_speed(&min, 0);
    let st = s.stability(0.5 * n0, 20.0 * n0).expect("envelope");
    assert!(st.envelope.iter().all(|p| p.chatter.is_some()));
    assert!(st.deepest.a_lim_mm <= st.exact_below_mm);
    let worst = against_brute(&s, &st, 40, 40.0 * 922.0);
    assert!(worst <= TOL, "largest deviation {worst}");
    // Rising to the end: the deepest cut is at the top speed.
    assert!((st.deepest.rpm - 20.0 * n0).abs() < 1e-6 * n0);
}

/// Issue 34: a range spanning more lobes than resolved is refused with the
/// lowest start that is accepted, and that start is accepted; memory stays
/// bounded (at most 32 speeds per lobe).
#[test]
fn too_many_lobes_are_refused_with_the_start_that_works() {
    let s = benchmark();
    let Err(LobesError::TooManyLobes { lobes, n_min }) = s.stability(1.0, 3000.0) else {
        panic!("1…3000 1/min spans tens of thousands of lobes");
    };
    assert!(lobes > 10_000.0 && n_min > 1.0 && n_min < 3000.0);
    let st = s.stability(n_min * 1.0001, 3000.0).expect("accepted");
    // 32 speeds per lobe and the top of each pocket.
    assert!(st.envelope.len() as f64 <= 34.0 * MAX_LOBES);
    let (lo, hi) = st.lobes().expect("lobes");
    assert!(hi - lo > 300, "lobes {lo}…{hi}");
    assert!(st.exact_below_mm <= CEILING_MM || st.envelope.iter().all(|p| p.chatter.is_some()));
}
