//! Space-time index of F3548 volumes (issue 17): index build and the encounter scan on seeded
//! synthetic intents (city 30 km, one day, 10–50 volumes each), against brute force on a
//! subsample. The 10⁵-intent figure of BENCHMARKS.md comes from `bench_python.py utm` and the
//! `phases` example; criterion runs 10⁴ intents to stay quick.
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use utm_index::{brute_force, synthetic::synthetic, Search, SpaceTimeIndex};

fn bench_utm(c: &mut Criterion) {
    let v = synthetic(10_000, 0).unwrap_or_else(|e| panic!("{e}"));
    let mut g = c.benchmark_group("utm_index");
    g.sample_size(10);
    g.bench_function("build_1e4_intents", |b| {
        b.iter(|| SpaceTimeIndex::new(black_box(&v), Search::default()))
    });
    let idx = SpaceTimeIndex::new(&v, Search::default()).unwrap_or_else(|e| panic!("{e}"));
    g.bench_function("encounters_1e4_intents", |b| {
        b.iter(|| black_box(&idx).encounters(1))
    });
    let small = synthetic(300, 0).unwrap_or_else(|e| panic!("{e}"));
    g.bench_function("index_300_intents", |b| {
        b.iter(|| {
            SpaceTimeIndex::new(black_box(&small), Search::default()).map(|i| i.encounters(1))
        })
    });
    g.bench_function("brute_force_300_intents", |b| {
        b.iter(|| brute_force(black_box(&small), &Search::default()))
    });
    g.finish();
}

criterion_group!(benches, bench_utm);
criterion_main!(benches);
