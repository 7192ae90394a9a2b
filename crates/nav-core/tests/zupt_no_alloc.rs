//! The per-sample ZUPT step (predict + update, ZUPT and TCZUPT, both discretisations) and the
//! batch runner never touch the heap: counted with an instrumented global allocator.
use nalgebra::{UnitQuaternion, Vector3};
use nav_core::zupt::{
    BatchInput, BatchOutput, Discretisation, HeadingSource, Mode, NoDerivative, ZuptConfig,
    ZuptFilter,
};
use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use std::alloc::System;

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

fn main() {
    per_sample_step_and_batch_do_not_allocate();
    println!("zupt_no_alloc: ok (per-sample step and batch allocate nothing)");
}

fn per_sample_step_and_batch_do_not_allocate() {
    let q = UnitQuaternion::from_euler_angles(0.01, -0.02, 0.5);
    let f_b = q.inverse() * Vector3::new(0.0, 0.0, -9.806);
    let acc: [f64; 3] = f_b.into();
    let n = 2_000;
    let gyro = vec![[1e-4, -2e-4, 3e-5]; n];
    let accel = vec![acc; n];
    let temp: Vec<f64> = (0..n).map(|i| 25.0 + 1e-3 * i as f64).collect();
    let rows = n.div_ceil(10);
    let (mut gb, mut ab, mut att, mut cov, mut tr) = (
        vec![[0.0; 3]; rows],
        vec![[0.0; 3]; rows],
        vec![[0.0; 4]; rows],
        vec![[0.0; 15]; rows],
        vec![0.0; rows],
    );
    // Control: the counter does see a heap allocation.
    let region = Region::new(GLOBAL);
    let v = std::hint::black_box(vec![1u8; 16]);
    assert!(region.change().allocations >= 1);
    drop(v);
    for mode in [Mode::Zupt, Mode::Tczupt] {
        for disc in [Discretisation::FirstOrder, Discretisation::SecondOrder] {
            let cfg = ZuptConfig {
                mode,
                discretisation: disc,
                ..ZuptConfig::default()
            };
            let mut f = ZuptFilter::new(cfg, q, Vector3::zeros(), Vector3::zeros(), 0.01).unwrap();
            let mut deriv = |_i: usize, _t: f64| Vector3::new(1e-5, 2e-5, -1e-5);
            let region = Region::new(GLOBAL);
            for (k, g) in gyro.iter().enumerate() {
                f.step(g, &acc, Some(temp[k]), true, &mut deriv).unwrap();
            }
            let s = region.change();
            assert_eq!(
                s.allocations + s.reallocations,
                0,
                "{mode:?} {disc:?}: {s:?}"
            );
            assert_eq!(f.updates(), 20);

            let input = BatchInput {
                dt_s: 0.01,
                gyro_rad_s: &gyro,
                accel_m_s2: &accel,
                temp_c: Some(&temp),
                mag: None,
                stationary: None,
                levelling_samples: 500,
                heading: HeadingSource::Given(0.5),
                accel_bias0_m_s2: [0.0; 3],
                gyro_bias0_rad_s: [0.0; 3],
                zero_gyro_bias: false,
            };
            let mut out = BatchOutput {
                decimation: 10,
                gyro_bias_rad_s: &mut gb,
                accel_bias_m_s2: &mut ab,
                attitude: &mut att,
                cov_diag: &mut cov,
                temp_rate_c_s: &mut tr,
            };
            let region = Region::new(GLOBAL);
            ZuptFilter::run_batch(cfg, &input, &mut NoDerivative, &mut out).unwrap();
            let s = region.change();
            assert_eq!(s.allocations + s.reallocations, 0, "batch {mode:?}: {s:?}");
        }
    }
}
