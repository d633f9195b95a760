//! Drop-cutter of a 10 mm ball: a 60 × 60 mm surface with 0.5 mm facets (28,800
//! triangles, target ≥ 200,000 points/s) and a 2,000,000-triangle surface (target
//! ≥ 100,000 points/s), on a 0.1 mm grid of points, 2 cores.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use millplan_geom::analytic::{tessellate, DemoSurface};
use millplan_geom::DVec2;
use millplan_models::cutter::Shape;
use millplan_sim::dropcutter::DropMesh;
use std::hint::black_box;

fn points(n: usize) -> Vec<DVec2> {
    let side = (n as f64).sqrt().ceil() as usize;
    (0..n)
        .map(|i| {
            DVec2::new(
                2.0 + 56.0 * (i % side) as f64 / side as f64,
                2.0 + 56.0 * (i / side) as f64 / side as f64,
            )
        })
        .collect()
}

fn drop(c: &mut Criterion) {
    let ball = Shape::Ball { radius: 5.0 };
    let pts = points(100_000);
    let mut g = c.benchmark_group("drop-cutter D10 ball");
    g.sample_size(10);
    g.throughput(Throughput::Elements(pts.len() as u64));
    let small = tessellate(&DemoSurface::default(), 0.5);
    let dm = DropMesh::new(&small);
    g.bench_function("28,800 triangles, 100k points", |b| {
        b.iter(|| black_box(dm.drop_many(&ball, &pts).len()))
    });
    let big = tessellate(&DemoSurface::default(), 60.0 / 1000.0);
    let dm = DropMesh::new(&big);
    g.bench_function("2,000,000 triangles, 100k points", |b| {
        b.iter(|| black_box(dm.drop_many(&ball, &pts).len()))
    });
    g.finish();
}

criterion_group!(benches, drop);
criterion_main!(benches);
