//! Every entry point the Python binding calls survives hostile input —
//! empty, mismatched and non-finite — with an `Err`, never a panic, and never turns finite
//! input into a silent NaN. Property tests (proptest), kept small so `cargo test` stays fast.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use nalgebra::{Matrix3, Vector3};
use proptest::prelude::*;
use uasnav_core::allan::{self, AllanPoint, TauSpacing};
use uasnav_core::attitude::{self as att, AttitudePropagator, PropagatorConfig};
use uasnav_core::mlp::json::load_thermal_model;
use uasnav_core::noise;
use uasnav_core::redundancy::alignment;
use uasnav_core::redundancy::chi2;
use uasnav_core::redundancy::fusion::parity_residuals;
use uasnav_core::redundancy::kalman::{BiasKalman, BiasKalmanConfig};
use uasnav_core::redundancy::{AxisKind, FdiConfig, FdiFuser, Polyhedron, SensorArray};
use uasnav_core::zupt::{
    detect_static, BatchInput, BatchOutput, HeadingSource, NoDerivative, StationarityConfig,
    ZuptConfig, ZuptFilter, N_STATES,
};

const CASES: u32 = 256;

/// Finite ordinary values, the float edges, and the non-finite ones.
fn hostile() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -10.0..10.0f64,
        1 => Just(0.0),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => Just(1e308),
        1 => Just(-1e308),
        1 => Just(5e-324),
    ]
}

fn vec3s(max: usize) -> impl Strategy<Value = Vec<[f64; 3]>> {
    prop::collection::vec([hostile(), hostile(), hostile()], 0..max)
}

fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

type Arr = SensorArray<f64, 24>;

fn cube() -> Arr {
    Arr::from_face_counts(
        Polyhedron::from_name("cube").unwrap(),
        &[1; 6],
        AxisKind::Single,
    )
    .unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    #[test]
    fn allan_entry_points(
        rate in prop::collection::vec(hostile(), 0..24),
        tau0 in hostile(),
        m in 0usize..40,
        short_buffer in any::<bool>(),
        n in any::<usize>(),
    ) {
        let mut phase = vec![0.0; rate.len() + usize::from(!short_buffer)];
        let r = allan::phase_from_rate(&rate, tau0, &mut phase);
        if !(all_finite(&rate) && tau0.is_finite() && tau0 > 0.0) || short_buffer {
            prop_assert!(r.is_err());
        }
        let _ = allan::oavar_from_phase(&phase, tau0, m);
        let _ = allan::cluster_size_for_tau(tau0, 0.01);
        let _ = allan::cluster_size_for_tau(0.5, tau0);
        let mut out = [0usize; 8];
        for sp in [TauSpacing::Octave, TauSpacing::Decade, TauSpacing::All] {
            prop_assert!(allan::cluster_sizes(n, sp, &mut out) <= out.len());
            prop_assert!(allan::cluster_sizes(n, sp, &mut []) == 0);
        }
    }

    #[test]
    fn noise_fit_and_readings(
        pts in prop::collection::vec((hostile(), hostile(), hostile()), 0..12),
    ) {
        let curve: Vec<AllanPoint<f64>> = pts
            .iter()
            .map(|&(t, v, e)| AllanPoint { tau_s: t, m: 1, avar: v, adev: v.abs().sqrt(), n_terms: 1, rel_error: e })
            .collect();
        let bad = curve.iter().any(|p| !(p.tau_s.is_finite() && p.avar.is_finite()));
        let fit = noise::fit_ieee952(&curve);
        let read = noise::read_points(&curve);
        if bad || curve.is_empty() {
            prop_assert!(fit.is_err());
            prop_assert!(read.is_err());
        }
    }

    #[test]
    fn attitude_entry_points(
        q in [hostile(), hostile(), hostile(), hostile()],
        c in prop::collection::vec(hostile(), 9),
        tol in hostile(),
        rates in vec3s(12),
        dt in hostile(),
        extra in 0usize..2,
        threshold in hostile(),
    ) {
        let r = att::quat_from_array(q);
        if !all_finite(&q) {
            prop_assert!(r.is_err());
        }
        if let Ok(u) = r {
            prop_assert!(all_finite(&att::quat_to_array(&u)));
        }
        let m = Matrix3::from_row_slice(&c);
        let d = att::dcm_to_quat(&m, tol);
        if !(all_finite(&c) && tol.is_finite() && tol >= 0.0) {
            prop_assert!(d.is_err());
        }
        let mut theta = vec![0.0; rates.len() + extra];
        let dr = att::drift_angles(&rates, dt, PropagatorConfig { coning: true }, &mut theta);
        if extra > 0 {
            prop_assert!(dr.is_err());
        } else if dr.is_ok() {
            prop_assert!(all_finite(&theta), "finite rates gave a NaN angle: {theta:?}");
        }
        let mut p = AttitudePropagator::new(nalgebra::UnitQuaternion::identity(), PropagatorConfig { coning: true });
        for w in &rates {
            if p.step(&Vector3::from(*w), dt).is_ok() {
                prop_assert!(all_finite(&att::quat_to_array(p.attitude())));
            }
        }
        let _ = att::first_crossing_time(&theta, dt, threshold);
    }

    #[test]
    fn stationarity_detector(
        a in vec3s(16),
        g in vec3s(16),
        sigma in hostile(),
        window in 0usize..300,
    ) {
        let cfg = StationarityConfig { sigma_accel_m_s2: sigma, window_samples: window, ..StationarityConfig::default() };
        let mut stat = vec![0.0; a.len()];
        let mut mask = vec![false; a.len()];
        let r = detect_static(&a, &g, cfg, &mut stat, &mut mask);
        if a.len() != g.len() || !(sigma.is_finite() && sigma > 0.0) {
            prop_assert!(r.is_err());
        }
        if r.is_ok() {
            prop_assert!(all_finite(&stat));
        }
    }

    #[test]
    fn zupt_batch(
        g in vec3s(24),
        extra_accel in 0usize..2,
        dt in hostile(),
        levelling in 0usize..40,
        decimation in 0usize..4,
        heading in hostile(),
        bias in hostile(),
    ) {
        // Accelerometer near gravity so that levelling itself usually succeeds.
        let a: Vec<[f64; 3]> = g.iter().map(|w| [w[0] * 1e-3, 0.0, -9.8]).chain(
            core::iter::repeat_n([0.0, 0.0, -9.8], extra_accel)).collect();
        let input = BatchInput {
            dt_s: dt,
            gyro_rad_s: &g,
            accel_m_s2: &a,
            temp_c: None,
            mag: None,
            stationary: None,
            levelling_samples: levelling,
            heading: HeadingSource::Given(heading),
            accel_bias0_m_s2: [bias; 3],
            gyro_bias0_rad_s: [0.0; 3],
            zero_gyro_bias: true,
        };
        let rows = g.len().div_ceil(decimation.max(1));
        let mut h = (vec![[0.0; 3]; rows], vec![[0.0; 3]; rows], vec![[0.0; 4]; rows], vec![[0.0; N_STATES]; rows], vec![0.0; rows]);
        let mut out = BatchOutput {
            decimation,
            gyro_bias_rad_s: &mut h.0,
            accel_bias_m_s2: &mut h.1,
            attitude: &mut h.2,
            cov_diag: &mut h.3,
            temp_rate_c_s: &mut h.4,
        };
        let r = ZuptFilter::run_batch(ZuptConfig::default(), &input, &mut NoDerivative, &mut out);
        if g.len() < 2 || extra_accel > 0 || decimation == 0 || !(dt.is_finite() && dt > 0.0)
            || !heading.is_finite() || !bias.is_finite() || g.iter().flatten().any(|v| !v.is_finite())
        {
            prop_assert!(r.is_err());
        }
        if let Ok(s) = r {
            prop_assert!(all_finite(&s.initial_attitude));
            prop_assert!(h.2.iter().flatten().all(|v| v.is_finite()));
            prop_assert!(h.0.iter().flatten().all(|v| v.is_finite()));
        }
    }

    #[test]
    fn redundancy_entry_points(
        axes in vec3s(8),
        sensor_of in prop::collection::vec(0usize..10, 0..8),
        tol in hostile(),
        sigma in prop::collection::vec(hostile(), 5..8),
        z in prop::collection::vec(hostile(), 5..8),
        dof in 0usize..2000,
        p in hostile(),
        dt in hostile(),
    ) {
        let v: Vec<Vector3<f64>> = axes.iter().map(|a| Vector3::from(*a)).collect();
        let r = Arr::from_axes(&v, &sensor_of, tol);
        if axes.len() != sensor_of.len() || !(tol.is_finite() && tol >= 0.0) {
            prop_assert!(r.is_err());
        }
        if let Ok(c) = chi2::chi2_threshold(dof, p) {
            prop_assert!(c.is_finite());
        }
        let cube = cube();
        let fdi = FdiConfig { p_fa: 1e-6, saturation: f64::INFINITY, stuck_samples: 3, max_isolations: 2 };
        let f = FdiFuser::<f64, 24, 8>::new(cube, &sigma, fdi);
        if sigma.len() != 6 || !sigma.iter().all(|s| s.is_finite() && *s > 0.0) {
            prop_assert!(f.is_err());
        }
        if let Ok(mut f) = f {
            prop_assert!(f.set_axis_bias(&z).is_err() == (z.len() != 6) || !all_finite(&z));
            let out = f.step(&z);
            if z.len() != 6 {
                prop_assert!(out.is_err());
            }
            if let Ok(o) = out {
                if o.valid {
                    prop_assert!(o.fused.value.iter().all(|v| v.is_finite()));
                }
            }
            let _ = f.fuse_finite(&z);
        }
        let mut res = vec![0.0; 6];
        let pr = parity_residuals(&cube, &z, &sigma, &mut res);
        // z and sigma need at least one entry per axis (longer ones are read up to n).
        let bad_sigma = sigma.iter().take(6).any(|s| !(s.is_finite() && *s > 0.0));
        if z.len() < 6 || sigma.len() < 6 || bad_sigma || !all_finite(&z[..6.min(z.len())]) {
            prop_assert!(pr.is_err());
        }
        if pr.is_ok() {
            prop_assert!(all_finite(&res));
        }
        let kcfg = BiasKalmanConfig { rate_psd: 1e-6, bias_psd: 1e-12, bias_sigma0: 1e-3, rate_sigma0: 1.0 };
        if let Ok(mut kf) = BiasKalman::<f64, 9>::new(&cube, &sigma, kcfg) {
            let pr = kf.predict(dt);
            if !(dt.is_finite() && dt > 0.0) {
                prop_assert!(pr.is_err());
            }
            let use_axis: Vec<bool> = z.iter().map(|v| v.is_finite()).collect();
            let _ = kf.update(&z, &use_axis);
            prop_assert!(kf.rate().iter().all(|v| v.is_finite()));
        }
        if let Some(f0) = axes.first() {
            if let Ok((roll, pitch)) = alignment::level(&Vector3::from(*f0)) {
                prop_assert!(roll.is_finite() && pitch.is_finite());
            }
        }
        let w: Vec<f64> = z.iter().take(v.len()).copied().collect();
        if let Ok(c) = alignment::wahba(&v, &v, &w) {
            prop_assert!(c.iter().all(|x| x.is_finite()));
        }
    }

    #[test]
    fn thermal_model_file_never_panics(text in "\\PC{0,64}", x in prop::collection::vec(hostile(), 0..6)) {
        let _ = load_thermal_model(&text);
        let prefix = format!("{{\"version\": 1, \"kind\": \"neural\", \"range_c\": [{}, {}]", x.first().copied().unwrap_or(0.0), x.last().copied().unwrap_or(1.0));
        let _ = load_thermal_model(&prefix);
        let _ = load_thermal_model(&(prefix + &text));
    }
}
