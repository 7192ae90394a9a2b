//! Redundant-IMU fusion per sample: WLS, FDI (healthy and isolating a fault), Kalman step.
use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Vector3;
use nav_core::redundancy::fusion::{wls, FdiConfig, FdiFuser};
use nav_core::redundancy::geometry::{AxisKind, Polyhedron, SensorArray};
use nav_core::redundancy::kalman::{BiasKalman, BiasKalmanConfig};
use std::hint::black_box;

fn sample<const M: usize>(a: &SensorArray<f64, M>, k: usize) -> Vec<f64> {
    let w = Vector3::new(0.1, -0.2, 0.05);
    (0..a.n_axes())
        .map(|i| a.axis(i).dot(&w) + 1e-3 * ((k * 31 + i * 17) as f64).sin())
        .collect()
}

fn bench_redundancy(c: &mut Criterion) {
    let a =
        SensorArray::<f64, 18>::from_polyhedron(Polyhedron::Cube, 1, AxisKind::Triaxial).unwrap();
    let z = sample(&a, 1);
    let sigma = [1e-3; 18];
    c.bench_function("redundancy/wls_cube6_triaxial", |b| {
        b.iter(|| wls(&a, black_box(&z), &sigma, &[0.0; 18], &[true; 18]).unwrap())
    });
    let cfg = FdiConfig {
        stuck_samples: 10,
        ..FdiConfig::default()
    };
    let mut f = FdiFuser::<f64, 18, 6>::new(a, &sigma, cfg).unwrap();
    let samples: Vec<Vec<f64>> = (0..64).map(|k| sample(&a, k)).collect();
    let mut k = 0;
    c.bench_function("redundancy/fdi_cube6_healthy", |b| {
        b.iter(|| {
            k = (k + 1) % 64;
            f.step(black_box(&samples[k])).unwrap()
        })
    });
    let faulty: Vec<Vec<f64>> = samples
        .iter()
        .map(|s| {
            let mut s = s.clone();
            s[7] += 0.05;
            s
        })
        .collect();
    c.bench_function("redundancy/fdi_cube6_isolating", |b| {
        b.iter(|| {
            k = (k + 1) % 64;
            f.step(black_box(&faulty[k])).unwrap()
        })
    });
    let ico =
        SensorArray::<f64, 60>::from_polyhedron(Polyhedron::Icosahedron, 1, AxisKind::Triaxial)
            .unwrap();
    let zi = sample(&ico, 3);
    let mut fi = FdiFuser::<f64, 60, 20>::new(ico, &[1e-3; 60], FdiConfig::default()).unwrap();
    c.bench_function("redundancy/fdi_icosahedron20_healthy", |b| {
        b.iter(|| fi.step(black_box(&zi)).unwrap())
    });
    let kcfg = BiasKalmanConfig {
        rate_psd: 1.0,
        bias_psd: 1e-12,
        bias_sigma0: 0.05,
        rate_sigma0: 1.0,
    };
    let mut kf = BiasKalman::<f64, 21>::new(&a, &sigma, kcfg).unwrap();
    c.bench_function("redundancy/kalman_cube6_step", |b| {
        b.iter(|| {
            kf.predict(0.01).unwrap();
            kf.update(black_box(&z), &[true; 18]).unwrap()
        })
    });
}

criterion_group!(benches, bench_redundancy);
criterion_main!(benches);
