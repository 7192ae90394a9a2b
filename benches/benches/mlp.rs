//! MLP inference: one 1-2-2-1 evaluation with derivative (exact tanh, f64 and f32), the
//! largest supported 1-16-16-1 network, and a 1000-sample batch.
use criterion::{criterion_group, criterion_main, Criterion};
use nav_core::mlp::{Activation, Affine, LayerSpec, Mlp};
use std::hint::black_box;

fn net(n: usize) -> Mlp<f64> {
    let w1: Vec<f64> = (0..n).map(|i| 0.3 + 0.1 * i as f64).collect();
    let b1: Vec<f64> = (0..n).map(|i| -0.2 + 0.05 * i as f64).collect();
    let w2: Vec<f64> = (0..n * n)
        .map(|i| ((i * 7 % 11) as f64 - 5.0) / 7.0)
        .collect();
    let b2: Vec<f64> = (0..n).map(|i| 0.01 * i as f64).collect();
    let w3: Vec<f64> = (0..n).map(|i| 1.0 - 0.1 * i as f64).collect();
    let tanh = Activation::Tanh;
    Mlp::new(
        &[
            LayerSpec {
                weights: &w1,
                biases: &b1,
                activation: tanh,
            },
            LayerSpec {
                weights: &w2,
                biases: &b2,
                activation: tanh,
            },
            LayerSpec {
                weights: &w3,
                biases: &[0.02],
                activation: Activation::Linear,
            },
        ],
        Affine {
            offset: 8.0,
            scale: 0.035,
        },
        Affine {
            offset: 1e-3,
            scale: 2e-4,
        },
        (-20.5, 37.3),
    )
    .unwrap()
}

fn bench_mlp(c: &mut Criterion) {
    let m = net(2);
    c.bench_function("mlp/eval_1-2-2-1_f64", |b| {
        b.iter(|| m.eval(black_box(25.3)))
    });
    c.bench_function("mlp/eval_clipped_1-2-2-1_f64", |b| {
        b.iter(|| m.eval_clipped(black_box(25.3)).unwrap())
    });
    let fast = net(2).with_fast_tanh();
    c.bench_function("mlp/eval_1-2-2-1_f64_fast_tanh", |b| {
        b.iter(|| fast.eval(black_box(25.3)))
    });
    let m32 = Mlp::<f32>::new(
        &[
            LayerSpec {
                weights: &[0.3, 0.4],
                biases: &[-0.2, -0.15],
                activation: Activation::Tanh,
            },
            LayerSpec {
                weights: &[0.1, -0.3, 0.5, 0.2],
                biases: &[0.0, 0.01],
                activation: Activation::Tanh,
            },
            LayerSpec {
                weights: &[1.0, 0.9],
                biases: &[0.02],
                activation: Activation::Linear,
            },
        ],
        Affine {
            offset: 8.0,
            scale: 0.035,
        },
        Affine {
            offset: 1e-3,
            scale: 2e-4,
        },
        (-20.5, 37.3),
    )
    .unwrap();
    c.bench_function("mlp/eval_1-2-2-1_f32", |b| {
        b.iter(|| m32.eval(black_box(25.3f32)))
    });
    let big = net(16);
    c.bench_function("mlp/eval_1-16-16-1_f64", |b| {
        b.iter(|| big.eval(black_box(25.3)))
    });
    let x: Vec<f64> = (0..1000).map(|i| -20.0 + 0.057 * i as f64).collect();
    let (mut v, mut d) = (vec![0.0; 1000], vec![0.0; 1000]);
    c.bench_function("mlp/batch_1000_1-2-2-1_f64", |b| {
        b.iter(|| m.eval_batch(black_box(&x), &mut v, &mut d, true).unwrap())
    });
}

criterion_group!(benches, bench_mlp);
criterion_main!(benches);
