//! The per-sample ZUPT step (predict + update, ZUPT and TCZUPT, both discretisations) and the
//! batch runner, and the GNSS/INS filter's predict, updates and batch runner, never touch the heap: counted with an instrumented global allocator.
use nalgebra::{UnitQuaternion, Vector3};
use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use std::alloc::System;
use uasnav_core::zupt::{
    BatchInput, BatchOutput, Discretisation, HeadingSource, Mode, NoDerivative, ZuptConfig,
    ZuptFilter,
};

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

fn main() {
    per_sample_step_and_batch_do_not_allocate();
    ins_step_updates_and_batch_do_not_allocate();
    println!("zupt_no_alloc: ok (ZUPT and GNSS/INS per-sample steps and batches allocate nothing)");
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
    for mode in [Mode::Classic, Mode::Tczupt] {
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

fn ins_step_updates_and_batch_do_not_allocate() {
    use uasnav_core::ins::{
        InsBatchInput, InsBatchOutput, InsConfig, InsFilter, MagnetometerAiding,
    };
    let q = UnitQuaternion::from_euler_angles(0.01, -0.02, 0.5);
    let acc: [f64; 3] = (q.inverse() * Vector3::new(0.0, 0.0, -9.806)).into();
    let n = 2_000;
    let imu_t: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
    let gyro = vec![[1e-4, -2e-4, 3e-5]; n];
    let accel = vec![acc; n];
    let temp: Vec<f64> = (0..n).map(|i| 25.0 + 1e-3 * i as f64).collect();
    let stationary: Vec<bool> = (0..n).map(|i| i < 500).collect();
    let m = 100;
    let gnss_t: Vec<f64> = (0..m).map(|i| i as f64 * 0.2).collect();
    let llh = vec![[0.8, 0.1, 300.0]; m];
    let gvel = vec![[0.0; 3]; m];
    let gacc = vec![[1.0, 1.5, 0.1]; m];
    let use_fix: Vec<bool> = (0..m).map(|i| !(40..60).contains(&i)).collect();
    let baro_t: Vec<f64> = (0..200).map(|i| i as f64 * 0.1).collect();
    let baro_h = vec![120.0; 200];
    let mag_t = baro_t.clone();
    let mag = vec![[0.2, 0.0, 0.4]; 200];
    let rows = n.div_ceil(10);
    let mut o = (
        vec![[0.0; 3]; rows],
        vec![[0.0; 3]; rows],
        vec![[0.0; 4]; rows],
        vec![[0.0; 3]; rows],
        vec![[0.0; 3]; rows],
        vec![[0.0; 15]; rows],
        vec![[0.0; 2]; rows],
        vec![false; rows],
        vec![0u8; m],
        vec![0.0; m],
    );
    for mode in [Mode::Classic, Mode::Tczupt] {
        for disc in [Discretisation::FirstOrder, Discretisation::SecondOrder] {
            let cfg = InsConfig {
                mode,
                discretisation: disc,
                ..InsConfig::default()
            };
            let mut f = InsFilter::new(
                cfg,
                0.8,
                0.1,
                300.0,
                Vector3::zeros(),
                q,
                [1.0; 3],
                [0.1; 3],
            )
            .unwrap();
            let region = Region::new(GLOBAL);
            for (k, g) in gyro.iter().take(200).enumerate() {
                f.predict(g, &acc, 0.01, &Vector3::zeros()).unwrap();
                if k % 20 == 0 {
                    f.update_gnss(&llh[0], &[0.0; 3], &gacc[0], 0.005).unwrap();
                    f.update_height(300.0, 0.5).unwrap();
                    f.update_static().unwrap();
                    f.update_mag_heading(&mag[0]).unwrap();
                }
            }
            let _ = f.protection_levels();
            let s = region.change();
            assert_eq!(
                s.allocations + s.reallocations,
                0,
                "ins {mode:?} {disc:?}: {s:?}"
            );

            let input = InsBatchInput {
                imu_t_s: &imu_t,
                gyro_rad_s: &gyro,
                accel_m_s2: &accel,
                temp_c: Some(&temp),
                stationary: Some(&stationary),
                gnss_t_s: &gnss_t,
                gnss_llh: &llh,
                gnss_vel_m_s: &gvel,
                gnss_acc: &gacc,
                gnss_use: Some(&use_fix),
                baro: Some((&baro_t, &baro_h)),
                mag: Some(MagnetometerAiding {
                    t_s: &mag_t,
                    field: &mag,
                }),
                initial_attitude: None,
                levelling_samples: 100,
                gyro_bias0_rad_s: [0.0; 3],
            };
            let mut out = InsBatchOutput {
                decimation: 10,
                llh: &mut o.0,
                vel_m_s: &mut o.1,
                attitude: &mut o.2,
                gyro_bias_rad_s: &mut o.3,
                accel_bias_m_s2: &mut o.4,
                cov_diag: &mut o.5,
                protection_m: &mut o.6,
                gnss_used: &mut o.7,
                fix_status: &mut o.8,
                fix_nis: &mut o.9,
            };
            let mut deriv = |_i: usize, _t: f64| Vector3::new(1e-5, 2e-5, -1e-5);
            let region = Region::new(GLOBAL);
            let summary = InsFilter::run_batch(cfg, &input, &mut deriv, &mut out).unwrap();
            let s = region.change();
            assert_eq!(
                s.allocations + s.reallocations,
                0,
                "ins batch {mode:?}: {s:?}"
            );
            assert!(summary.fixes_used > 50 && summary.static_updates > 0);
        }
    }
}
