//! Quaternion propagation: one step, and a 1000-step loop (ahrs-rs style).
use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{UnitQuaternion, Vector3};
use nav_core::attitude::{AttitudePropagator, PropagatorConfig};
use std::hint::black_box;

fn bench_propagation(c: &mut Criterion) {
    let w = Vector3::new(1e-3, -2e-3, 5e-4);
    for (name, coning) in [("plain", false), ("coning", true)] {
        let cfg = PropagatorConfig { coning };
        let mut p = AttitudePropagator::new(UnitQuaternion::<f64>::identity(), cfg);
        c.bench_function(&format!("attitude/step_f64_{name}"), |b| {
            b.iter(|| p.step(black_box(&w), black_box(0.01)).unwrap())
        });
    }
    let mut p32 = AttitudePropagator::new(
        UnitQuaternion::<f32>::identity(),
        PropagatorConfig::default(),
    );
    let w32 = Vector3::new(1e-3_f32, -2e-3, 5e-4);
    c.bench_function("attitude/step_f32_plain", |b| {
        b.iter(|| p32.step(black_box(&w32), black_box(0.01)).unwrap())
    });
    c.bench_function("attitude/1000_steps_f64", |b| {
        b.iter(|| {
            let mut p = AttitudePropagator::new(
                UnitQuaternion::<f64>::identity(),
                PropagatorConfig::default(),
            );
            for _ in 0..1000 {
                p.step(black_box(&w), 0.01).unwrap();
            }
            *p.attitude()
        })
    });
}

criterion_group!(benches, bench_propagation);
criterion_main!(benches);
