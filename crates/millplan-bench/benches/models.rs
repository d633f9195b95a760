//! The working-diameter model alone (target ≥ 2 million points/s on 2 cores) and
//! the contact analysis plus model on a realistic raster.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use millplan_models::wd::{working_diameter, Case, Neighbour, Side};
use rayon::prelude::*;
use std::hint::black_box;

fn cases(n: usize) -> Vec<Case> {
    let mut s = 0x9e3779b97f4a7c15u64;
    let mut r = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|i| Case {
            d: 10.0,
            ap: 0.3,
            neighbour: if i % 10 == 0 {
                Neighbour::None
            } else {
                Neighbour::One(0.25 + r())
            },
            alpha: (80.0 * r()).to_radians(),
            af: (-180.0 + 360.0 * r()).to_radians(),
            side: if r() < 0.5 { Side::Left } else { Side::Right },
        })
        .collect()
}

fn model(c: &mut Criterion) {
    let cs = cases(1_000_000);
    let mut g = c.benchmark_group("working diameter");
    g.sample_size(10);
    g.throughput(Throughput::Elements(cs.len() as u64));
    g.bench_function("1M cases, 2 threads", |b| {
        b.iter(|| black_box(cs.par_iter().map(working_diameter).sum::<f64>()))
    });
    g.bench_function("1M cases, 1 thread", |b| {
        b.iter(|| black_box(cs.iter().map(working_diameter).sum::<f64>()))
    });
    g.finish();
}

criterion_group!(benches, model);
criterion_main!(benches);
