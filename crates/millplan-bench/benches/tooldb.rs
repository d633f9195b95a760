//! Recording 10,000 laser measurements with their decisions in a library file
//! (each one transaction: measurement, tool update, decision log). Target ≤ 2 s.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use millplan_tooldb::control::{record, Kind, Measurement, Settings};
use millplan_tooldb::db::{ToolDb, ToolRecord};

fn setup() -> (tempfile::TempDir, ToolDb) {
    let dir = tempfile::tempdir().expect("tmp");
    let mut db = ToolDb::open(&dir.path().join("tools.db")).expect("open");
    for n in 1..=20 {
        let mut t = ToolRecord::new(n, "thread mill");
        t.ltol = 0.05;
        t.rtol = 0.05;
        t.lbreak = 0.2;
        t.rbreak = 0.2;
        db.put_tool(&t).expect("put");
        db.record_presetter(n, 120.0, 6.9).expect("preset");
    }
    (dir, db)
}

fn measurements(c: &mut Criterion) {
    let mut g = c.benchmark_group("tool library");
    g.sample_size(10);
    g.bench_function("10,000 measurements with decisions", |b| {
        b.iter_batched(
            setup,
            |(_dir, mut db)| {
                for i in 0..10_000u32 {
                    let tool = 1 + i % 20;
                    let kind = if i < 20 {
                        Kind::First
                    } else {
                        Kind::Inspection
                    };
                    let d = if i.is_multiple_of(2) { 0.001 } else { -0.001 };
                    let m = Measurement {
                        tool,
                        kind,
                        l: Some(120.0 + d),
                        r: Some(6.9 + d),
                        per_tooth: None,
                        pz: Some(0.5),
                    };
                    record(&mut db, &m, &Settings::default()).expect("record");
                }
            },
            BatchSize::PerIteration,
        )
    });
    g.finish();
}

criterion_group!(benches, measurements);
criterion_main!(benches);
