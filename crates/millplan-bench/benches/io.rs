//! Reading and writing at the sizes the issue names: a 1,000,000-GOTO APT file,
//! a 2,000,000-triangle binary STL, 1,000,000 G-code blocks.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use millplan_nc::apt::AptReader;
use millplan_nc::write::gcode::write_gcode;
use millplan_nc::write::{Target, WriteOptions};
use millplan_nc::{Dialect, ReadOptions};
use std::hint::black_box;

fn read_apt(c: &mut Criterion) {
    let src = millplan_bench::big_apt(1_000_000);
    let mut g = c.benchmark_group("apt");
    g.sample_size(10);
    g.throughput(Throughput::Bytes(src.len() as u64));
    g.bench_function("read 1M GOTO", |b| {
        b.iter(|| {
            let mut r = AptReader::new(Dialect::AptIso, ReadOptions::default());
            for line in src.split('\n') {
                r.line(line).expect("valid");
            }
            black_box(r.finish().expect("valid").program.move_count())
        })
    });
    g.finish();
}

fn read_stl(c: &mut Criterion) {
    let bytes = millplan_bench::big_stl(2_000_000);
    let mut g = c.benchmark_group("stl");
    g.sample_size(10);
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("read 2M triangles", |b| {
        b.iter(|| black_box(millplan_geom::stl::read_stl(&bytes).expect("valid").0.len()))
    });
    let (mesh, _) = millplan_geom::stl::read_stl(&bytes).expect("valid");
    g.bench_function("edge topology of 2M triangles", |b| {
        b.iter(|| black_box(mesh.edge_report()))
    });
    g.finish();
}

fn write(c: &mut Criterion) {
    let p = millplan_bench::big_program(1_000_000);
    let mut g = c.benchmark_group("gcode");
    g.sample_size(10);
    g.throughput(Throughput::Elements(1_000_000));
    g.bench_function("write 1M blocks fanuc", |b| {
        b.iter(|| {
            let mut out = Vec::new();
            write_gcode(&p, WriteOptions::new(Target::Fanuc), &mut out).expect("writes");
            black_box(out.len())
        })
    });
    g.finish();
}

criterion_group!(benches, read_apt, read_stl, write);
criterion_main!(benches);
