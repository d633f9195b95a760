//! One-dimensional maximisation, shared by the models and the simulation.

/// Maximum of a unimodal function on [lo, hi] by golden-section search, to an
/// interval of `tol` or `max_iter` steps: (best x, f(best x)).
pub fn golden_max(
    f: &impl Fn(f64) -> f64,
    mut lo: f64,
    mut hi: f64,
    tol: f64,
    max_iter: usize,
) -> (f64, f64) {
    const K: f64 = 0.618_033_988_749_894_9;
    if hi <= lo {
        return (lo, f(lo));
    }
    let mut x1 = hi - K * (hi - lo);
    let mut x2 = lo + K * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..max_iter {
        if hi - lo < tol {
            break;
        }
        if f1 < f2 {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + K * (hi - lo);
            f2 = f(x2);
        } else {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - K * (hi - lo);
            f1 = f(x1);
        }
    }
    if f1 >= f2 {
        (x1, f1)
    } else {
        (x2, f2)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn finds_the_peak_of_a_concave_function() {
        let (x, v) = super::golden_max(&|x: f64| -(x - 0.3).powi(2) + 2.0, -1.0, 4.0, 1e-12, 200);
        assert!((x - 0.3).abs() < 1e-6 && (v - 2.0).abs() < 1e-12);
        let (x, _) = super::golden_max(&|x: f64| x, 0.0, 1.0, 1e-12, 200);
        assert!(x > 1.0 - 1e-9, "monotone: the end");
    }
}
