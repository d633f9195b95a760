//! The working-diameter model's own throughput on 1,000,000 cases, one
//! thread and all of rayon's, to compare with the Python package's
//! vectorised `working_diameter` on the same cases
//! (`crates/millplan-py/bench/bench.py wd` builds them with the same formulas).
//!
//! `cargo run --release -p millplan-bench --example wd_rate [N]`

use millplan_models::wd::{working_diameter, Case, Side};
use rayon::prelude::*;
use std::time::Instant;

/// Case `i` of the benchmark: a ball of 10 mm, ap 0.3 mm, every tenth case
/// without a neighbour, angles spread by irrational steps.
fn case(i: usize) -> Case {
    let f = i as f64;
    let ae = (!i.is_multiple_of(10)).then(|| 0.25 + (f * 0.569_840_290_998_053).fract());
    let alpha = 80.0 * (f * 0.618_033_988_749_895).fract();
    let af = -180.0 + 360.0 * (f * 0.754_877_666_246_693).fract();
    let side = if i.is_multiple_of(2) {
        Side::Left
    } else {
        Side::Right
    };
    Case::from_degrees(10.0, 0.3, ae, false, alpha, af, side).unwrap_or_else(|e| panic!("{e}"))
}

fn best_of(reps: usize, f: impl Fn() -> f64) -> (f64, f64) {
    let mut best = f64::INFINITY;
    let mut sum = 0.0;
    for _ in 0..reps {
        let t = Instant::now();
        sum = std::hint::black_box(f());
        best = best.min(t.elapsed().as_secs_f64());
    }
    (best, sum)
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let cases: Vec<Case> = (0..n).map(case).collect();
    let (t1, s1) = best_of(5, || cases.iter().map(working_diameter).sum());
    let (tp, sp) = best_of(5, || cases.par_iter().map(working_diameter).sum());
    println!(
        "{n} cases: 1 thread {t1:.4} s ({:.2} M/s, sum {s1:.6}); {} threads {tp:.4} s ({:.2} M/s, sum {sp:.6})",
        n as f64 / t1 / 1e6,
        rayon::current_num_threads(),
        n as f64 / tp / 1e6
    );
}
