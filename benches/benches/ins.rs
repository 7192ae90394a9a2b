//! GNSS/INS filter: one predict (the goal: within 2× of the ZUPT filter's predict,
//! `zupt/predict_f64_first_order`), one GNSS update, and a 1000-step loop.
use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use nalgebra::{UnitQuaternion, Vector3};
use nav_core::ins::{InsConfig, InsFilter};
use std::hint::black_box;

fn filter<T: nav_core::Real>() -> InsFilter<T> {
    let q = UnitQuaternion::from_euler_angles(
        nalgebra::convert(0.01),
        nalgebra::convert(-0.02),
        nalgebra::convert(0.5),
    );
    InsFilter::new(
        InsConfig::default(),
        0.8,
        0.1,
        300.0,
        Vector3::new(
            nalgebra::convert(12.0),
            nalgebra::convert(3.0),
            nalgebra::convert(-0.5),
        ),
        q,
        [nalgebra::convert(1.0); 3],
        [nalgebra::convert(0.1); 3],
    )
    .unwrap()
}

fn bench_ins(c: &mut Criterion) {
    let g = [1e-2, -2e-2, 3e-2];
    let a = [0.3, -0.2, -9.8];
    let zero = Vector3::zeros();
    // A fresh copy per call (untimed): unaided, constant inputs would eventually drive the
    // solution out of its domain (the vertical channel is unstable).
    let f = filter::<f64>();
    c.bench_function("ins/predict_f64", |b| {
        b.iter_batched_ref(
            || f.clone(),
            |f| {
                f.predict(black_box(&g), black_box(&a), 0.01, &zero)
                    .unwrap()
            },
            BatchSize::SmallInput,
        )
    });
    let f32f = filter::<f32>();
    let (g32, a32) = ([1e-2_f32, -2e-2, 3e-2], [0.3_f32, -0.2, -9.8]);
    c.bench_function("ins/predict_f32", |b| {
        b.iter_batched_ref(
            || f32f.clone(),
            |f| {
                f.predict(black_box(&g32), black_box(&a32), 0.01, &Vector3::zeros())
                    .unwrap()
            },
            BatchSize::SmallInput,
        )
    });
    let llh = f.position();
    c.bench_function("ins/gnss_update_f64", |b| {
        b.iter_batched_ref(
            || f.clone(),
            |f| {
                f.update_gnss(black_box(&llh), &[12.0, 3.0, -0.5], &[1.5, 2.5, 0.15], 0.0)
                    .unwrap()
            },
            BatchSize::SmallInput,
        )
    });
    c.bench_function("ins/loop_1000_predict_f64", |b| {
        b.iter(|| {
            let mut f = filter::<f64>();
            for _ in 0..1000 {
                f.predict(black_box(&g), black_box(&a), 0.01, &zero)
                    .unwrap();
            }
            f.position()
        })
    });
}

criterion_group!(benches, bench_ins);
criterion_main!(benches);
