//! ZUPT filter: predict and update separately (the goals: ≤ 1 µs and ≤ 3 µs in f64),
//! one full step, and a batch of 10⁶ samples (the ≥ 1 M samples/s goal).
use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{UnitQuaternion, Vector3};
use nav_core::zupt::{
    BatchInput, BatchOutput, Discretisation, HeadingSource, NoDerivative, ZuptConfig, ZuptFilter,
};
use std::hint::black_box;

fn filter<T: nav_core::Real>(disc: Discretisation) -> ZuptFilter<T> {
    let cfg = ZuptConfig::<T> {
        discretisation: disc,
        ..ZuptConfig::default()
    };
    let q = UnitQuaternion::from_euler_angles(
        nalgebra::convert(0.01),
        nalgebra::convert(-0.02),
        nalgebra::convert(0.5),
    );
    ZuptFilter::new(
        cfg,
        q,
        Vector3::zeros(),
        Vector3::zeros(),
        nalgebra::convert(0.01),
    )
    .unwrap()
}

fn bench_zupt(c: &mut Criterion) {
    let g = [1e-4, -2e-4, 3e-5];
    let a = [0.1, -0.2, -9.8];
    let zero = Vector3::zeros();
    for (name, disc) in [
        ("first_order", Discretisation::FirstOrder),
        ("second_order_dense", Discretisation::SecondOrder),
    ] {
        let mut f = filter::<f64>(disc);
        c.bench_function(&format!("zupt/predict_f64_{name}"), |b| {
            b.iter(|| f.predict(black_box(&g), black_box(&a), &zero).unwrap())
        });
    }
    let mut f = filter::<f64>(Discretisation::FirstOrder);
    for _ in 0..100 {
        f.predict(&g, &a, &zero).unwrap();
    }
    c.bench_function("zupt/update_f64", |b| {
        b.iter(|| {
            f.update().unwrap();
            // One predict keeps P from collapsing onto the steady state; subtract it.
            f.predict(black_box(&g), black_box(&a), &zero).unwrap()
        })
    });
    let mut f32f = filter::<f32>(Discretisation::FirstOrder);
    let (g32, a32) = ([1e-4_f32, -2e-4, 3e-5], [0.1_f32, -0.2, -9.8]);
    c.bench_function("zupt/predict_f32_first_order", |b| {
        b.iter(|| {
            f32f.predict(black_box(&g32), black_box(&a32), &Vector3::zeros())
                .unwrap()
        })
    });

    let n = 1_000_000;
    let gyro = vec![g; n];
    let accel = vec![a; n];
    let rows = n.div_ceil(100);
    let (mut gb, mut ab, mut att, mut cov, mut tr) = (
        vec![[0.0; 3]; rows],
        vec![[0.0; 3]; rows],
        vec![[0.0; 4]; rows],
        vec![[0.0; 15]; rows],
        vec![0.0; rows],
    );
    let mut group = c.benchmark_group("zupt");
    group.sample_size(10);
    group.bench_function("batch_1e6_samples_100hz_1hz_updates", |b| {
        b.iter(|| {
            let input = BatchInput {
                dt_s: 0.01,
                gyro_rad_s: &gyro,
                accel_m_s2: &accel,
                temp_c: None,
                mag: None,
                stationary: None,
                levelling_samples: 6000,
                heading: HeadingSource::Given(0.0),
                accel_bias0_m_s2: [0.0; 3],
                gyro_bias0_rad_s: [0.0; 3],
                zero_gyro_bias: false,
            };
            let mut out = BatchOutput {
                decimation: 100,
                gyro_bias_rad_s: &mut gb,
                accel_bias_m_s2: &mut ab,
                attitude: &mut att,
                cov_diag: &mut cov,
                temp_rate_c_s: &mut tr,
            };
            ZuptFilter::run_batch(ZuptConfig::default(), &input, &mut NoDerivative, &mut out)
                .unwrap()
        })
    });
    group.finish();
}

criterion_group!(benches, bench_zupt);
criterion_main!(benches);
