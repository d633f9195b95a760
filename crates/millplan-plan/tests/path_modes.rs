//! Issue 37, "the estimate changes when the mode changes, by the amount the
//! planner model says", per dialect: the same right-angle corner (two
//! 50 mm blocks at 50 mm/s on axes of 1000 mm/s², no jerk) read from each
//! dialect's words for exact stop, blending and blending within a
//! tolerance, timed by `estimate_program` with the generic planner, against
//! the closed forms of docs/time.md ("Path-control modes and planner
//! models"):
//! - exact stop: two rest-to-rest trapezoids, 2·(L/v + v/a) = 2.1 s;
//! - blending over `blend_mm` (0.2 mm): the corner at v_c = √(a·0.2/|Δe|)
//!   (|Δe| = 1 on either axis), t = 2L/v + v/a + (v − v_c)²/(a·v);
//! - blending within T: the rounding arc's length ℓ = tanθ·d·(π − 2θ),
//!   d = cosθ·T/(1 − sinθ), θ = 45°, in place of 0.2 mm.

use millplan_nc::{parse_program, ReadOptions};
use millplan_plan::machine::Machine;
use millplan_plan::timing::estimate_program;

const MACHINE: &str = "[control]\nplanner = \"generic\"\n[spindle]\nmin = 0.0\nmax = 24000.0\naccel = 10000.0\n[feed]\nmax = 12000.0\nrapid = 12000.0\n[axes.x]\nvelocity = 12000.0\naccel = 1000.0\n[axes.y]\nvelocity = 12000.0\naccel = 1000.0\n[axes.z]\nvelocity = 12000.0\naccel = 1000.0\n";

const A: f64 = 1000.0;
const V: f64 = 50.0;
const L: f64 = 50.0;

fn time(src: &str) -> f64 {
    let m = Machine::from_toml(MACHINE).expect("machine");
    let p = parse_program(src, ReadOptions::default())
        .unwrap_or_else(|e| panic!("{e}\n{src}"))
        .program;
    estimate_program(&p, &m).total_s
}

fn exact_stop() -> f64 {
    2.0 * (L / V + V / A)
}

/// The corner passed at the speed a blend over `ell` mm allows.
fn blended(ell: f64) -> f64 {
    let vc = (A * ell).sqrt().min(V);
    2.0 * L / V + V / A + (V - vc).powi(2) / (A * V)
}

fn rounding(t: f64) -> f64 {
    let th = std::f64::consts::FRAC_PI_4;
    let d = th.cos() * t / (1.0 - th.sin());
    th.tan() * d * (std::f64::consts::PI - 2.0 * th)
}

fn close(got: f64, want: f64, what: &str) {
    assert!((got - want).abs() < 1e-9, "{what}: {got} s, want {want} s");
}

/// The corner in G-code after `head` (the mode's words), `X0 Y0` to
/// `X50 Y0` to `X50 Y50`.
fn gcode(pre: &str, head: &str, post: &str) -> String {
    format!("{pre}G0 X0 Y0 Z0\n{head}\nG1 X50 F3000\nG1 Y50\n{post}")
}

#[test]
fn linuxcnc_modes_time_as_the_planner_says() {
    let lc = |head: &str| time(&gcode("G21 G90 G17\n", head, "M2\n"));
    close(lc("G61"), exact_stop(), "G61");
    close(lc("G61.1"), exact_stop(), "G61.1");
    close(lc("G64"), blended(0.2), "G64");
    close(lc("G64 P0.01"), blended(rounding(0.01)), "G64 P0.01");
    assert!(lc("G64 P0.01") > lc("G64") && lc("G64") < lc("G61"));
}

#[test]
fn fanuc_modes_time_as_the_planner_says() {
    let fanuc = |head: &str| time(&gcode("%\nO0001\nG21 G90 G17\n", head, "M30\n%\n"));
    close(fanuc("G61"), exact_stop(), "G61");
    close(fanuc("G64"), blended(0.2), "G64");
    // G09 on the first block alone stops at the corner.
    let once = time("%\nO0001\nG21 G90 G17\nG64\nG0 X0 Y0 Z0\nG09 G1 X50 F3000\nG1 Y50\nM30\n%\n");
    close(once, exact_stop(), "G09");
}

#[test]
fn sinumerik_modes_time_as_the_planner_says() {
    // SOFT says the dialect (the axes have no jerk limit: the same
    // trapezoids); G60 is exact stop only to a Sinumerik.
    let sin = |head: &str| time(&gcode("G71 G90 G17\nSOFT\n", head, "M30\n"));
    close(sin("G60"), exact_stop(), "G60");
    close(sin("G64"), blended(0.2), "G64");
    close(sin("G641 ADIS=0.01"), blended(rounding(0.01)), "G641 ADIS");
    close(sin("CTOL=0.01 G642"), blended(rounding(0.01)), "G642 CTOL");
    let once = time("G71 G90 G17\nSOFT\nG64\nG0 X0 Y0 Z0\nG1 X50 F3000 G9\nG1 Y50\nM30\n");
    close(once, exact_stop(), "G9");
}

#[test]
fn heidenhain_tolerance_cycle_times_as_the_planner_says() {
    let plain =
        "0 BEGIN PGM T MM\n1 L X+0 Y+0 Z+0 FMAX\n2 L X+50 F3000\n3 L Y+50\n4 END PGM T MM\n";
    close(time(plain), blended(0.2), "no cycle 32");
    let cycle = "0 BEGIN PGM T MM\n1 CYCL DEF 32.0 TOLERANCE\n2 CYCL DEF 32.1 T0.01\n3 L X+0 Y+0 Z+0 FMAX\n4 L X+50 F3000\n5 L Y+50\n6 END PGM T MM\n";
    close(time(cycle), blended(rounding(0.01)), "CYCL DEF 32.1 T0.01");
}
