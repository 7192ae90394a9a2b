//! Overlapping Allan deviation, octave cluster sizes, on 10⁶ and 10⁷ samples.
use criterion::{criterion_group, criterion_main, Criterion};
use nav_core::allan::{oadev, TauSpacing};
use std::hint::black_box;

fn series(n: usize) -> Vec<f64> {
    let mut s = 0x9e37_79b9_7f4a_7c15_u64;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.02 + 0.007
        })
        .collect()
}

fn bench_allan(c: &mut Criterion) {
    let mut g = c.benchmark_group("allan");
    g.sample_size(10);
    for n in [1_000_000usize, 10_000_000] {
        let y = series(n);
        g.bench_function(format!("oadev_octave_{n}"), |b| {
            b.iter(|| oadev(black_box(&y), 0.01, TauSpacing::Octave).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench_allan);
criterion_main!(benches);
