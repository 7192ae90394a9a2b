//! Filter tests on static data simulated here (truth known exactly): convergence, NEES
//! consistency against χ² bounds, the block-sparse propagation against the dense product,
//! TCZUPT with a known thermal model, error handling, and covariance invariants (proptest).
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use proptest::prelude::*;

use super::*;
use crate::attitude::{euler321_to_quat, quat_to_dcm};
use crate::earth;

/// Small deterministic normal generator (xorshift64* + Box–Muller): tests need no RNG crate.
struct Gauss(u64, Option<f64>);

impl Gauss {
    fn new(seed: u64) -> Self {
        Gauss(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1, None)
    }
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn next(&mut self) -> f64 {
        if let Some(x) = self.1.take() {
            return x;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let r = (-2.0 * u1.ln()).sqrt();
        let a = 2.0 * core::f64::consts::PI * u2;
        self.1 = Some(r * a.sin());
        r * a.cos()
    }
    fn vec3(&mut self, s: f64) -> Vector3<f64> {
        Vector3::new(self.next() * s, self.next() * s, self.next() * s)
    }
}

/// A static unit at attitude `q` with noise and bias random walks exactly as the filter models
/// them (eqs. 22–25). Returns (gyro, accel, true gyro bias) per sample.
struct StaticSim {
    q: UnitQuaternion<f64>,
    dt: f64,
    noise: ProcessNoise<f64>,
    lat: f64,
}

type Series = (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<Vector3<f64>>);

impl StaticSim {
    fn run(&self, n: usize, bg0: Vector3<f64>, ba0: Vector3<f64>, rng: &mut Gauss) -> Series {
        let c_nb: Matrix3<f64> = quat_to_dcm(&self.q).transpose();
        let w_b = c_nb * earth::earth_rate_ned(self.lat);
        let f_b = c_nb * Vector3::new(0.0, 0.0, -earth::normal_gravity(self.lat, 0.0));
        let (mut bg, mut ba) = (bg0, ba0);
        let nz = self.noise;
        let sd = self.dt.sqrt();
        let (mut gy, mut ac, mut tb) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..n {
            gy.push((w_b + bg + rng.vec3(nz.sigma_arw_rad_sqrt_s / sd)).into());
            ac.push((f_b + ba + rng.vec3(nz.sigma_vrw_m_s_sqrt_s / sd)).into());
            tb.push(bg);
            bg += rng.vec3(nz.sigma_gbi_rad_s * sd);
            ba += rng.vec3(nz.sigma_abi_m_s2 * sd);
        }
        (gy, ac, tb)
    }
}

fn sim() -> StaticSim {
    StaticSim {
        q: euler321_to_quat(0.02, -0.03, 1.0),
        dt: 0.01,
        noise: ProcessNoise::thesis_zupt(),
        lat: 45f64.to_radians(),
    }
}

#[test]
fn gyro_bias_converges_and_nees_stays_inside_chi2_bounds() {
    let s = sim();
    let cfg = ZuptConfig::<f64>::default();
    let runs = 24;
    let n = 30_000; // 300 s at 100 Hz
    let checkpoints = [3_000usize, 10_000, 20_000, 29_999];
    let mut nees = [0.0; 4];
    let mut last_err = 0.0_f64;
    for run in 0..runs {
        let mut rng = Gauss::new(100 + run);
        let bg0 = rng.vec3(cfg.init_std_gyro_bias_rad_s);
        let ba0 = rng.vec3(cfg.init_std_accel_bias_m_s2 * 0.1);
        let (gy, ac, tb) = s.run(n, bg0, ba0, &mut rng);
        let mut f = ZuptFilter::new(cfg, s.q, Vector3::zeros(), Vector3::zeros(), s.dt).unwrap();
        for k in 0..n {
            f.step(&gy[k], &ac[k], None, true, &mut NoDerivative)
                .unwrap();
            if let Some(c) = checkpoints.iter().position(|&x| x == k) {
                let e = f.gyro_bias_rad_s() - tb[k];
                let pb = f.covariance().fixed_view::<3, 3>(12, 12).into_owned();
                nees[c] += e.dot(&(pb.try_inverse().unwrap() * e));
                if c == 3 {
                    last_err = last_err.max(e.amax());
                }
            }
        }
    }
    // Sum of `runs` NEES values of 3 dof is χ²(3·runs): 99 % two-sided bounds for 72 dof.
    let (lo, hi) = (46.9, 106.6);
    for (c, v) in nees.iter().enumerate() {
        assert!(
            *v > lo && *v < hi,
            "checkpoint {c}: NEES sum {v} outside [{lo}, {hi}]"
        );
    }
    // σ_ARW/√T after 300 s ≈ 5.3e-5 rad/s; worst of 72 axis errors stays well inside 4σ.
    assert!(last_err < 2.5e-4, "{last_err}");
    assert!(last_err > 1e-6, "suspiciously exact: {last_err}");
}

#[test]
fn block_propagation_equals_dense_first_order_product() {
    let s = sim();
    let cfg = ZuptConfig::<f64>::default();
    let mut rng = Gauss::new(7);
    let (gy, ac, _) = s.run(300, rng.vec3(1e-4), Vector3::zeros(), &mut rng);
    let mut f = ZuptFilter::new(cfg, s.q, Vector3::zeros(), Vector3::zeros(), s.dt).unwrap();
    for k in 0..250 {
        f.step(&gy[k], &ac[k], None, true, &mut NoDerivative)
            .unwrap();
    }
    // Dense reference Φ = I + F·Ts from the same linearisation point.
    let p0 = *f.covariance();
    let c = quat_to_dcm(f.attitude());
    let f_n = c * (Vector3::from(ac[250]) - f.accel_bias_m_s2());
    let w = super::filter_test_skew(&earth::earth_rate_ned(cfg.latitude_rad));
    let mut fm = nalgebra::SMatrix::<f64, 15, 15>::zeros();
    fm.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&Matrix3::identity());
    let g = earth::normal_gravity(cfg.latitude_rad, 0.0);
    fm[(5, 2)] = 2.0 * g / earth::geocentric_radius(cfg.latitude_rad);
    fm.fixed_view_mut::<3, 3>(3, 3).copy_from(&(w * -2.0));
    fm.fixed_view_mut::<3, 3>(3, 6)
        .copy_from(&(-super::filter_test_skew(&f_n)));
    fm.fixed_view_mut::<3, 3>(3, 9).copy_from(&(-c));
    fm.fixed_view_mut::<3, 3>(6, 6).copy_from(&(-w));
    fm.fixed_view_mut::<3, 3>(6, 12).copy_from(&(-c));
    let phi = nalgebra::SMatrix::<f64, 15, 15>::identity() + fm * s.dt;
    let mut want = phi * p0 * phi.transpose();
    let n = cfg.noise;
    let gam = [
        n.sigma_vrw_m_s_sqrt_s,
        n.sigma_arw_rad_sqrt_s,
        n.sigma_abi_m_s2,
        n.sigma_gbi_rad_s,
    ];
    for (grp, sg) in gam.iter().enumerate() {
        for i in 0..3 {
            want[(3 + 3 * grp + i, 3 + 3 * grp + i)] += sg * sg * s.dt;
        }
    }
    f.predict(&gy[250], &ac[250], &Vector3::zeros()).unwrap();
    let got = *f.covariance();
    let scale = want.amax();
    assert!(
        (got - want).amax() < 1e-12 * scale,
        "{}",
        (got - want).amax()
    );
    assert!(got.iter().all(|x| x.is_finite()));

    // The second-order option agrees closely (the F² term is O(Ts²)).
    let cfg2 = ZuptConfig {
        discretisation: Discretisation::SecondOrder,
        ..cfg
    };
    let mut f1 = ZuptFilter::new(cfg, s.q, Vector3::zeros(), Vector3::zeros(), s.dt).unwrap();
    let mut f2 = ZuptFilter::new(cfg2, s.q, Vector3::zeros(), Vector3::zeros(), s.dt).unwrap();
    for k in 0..300 {
        f1.step(&gy[k], &ac[k], None, true, &mut NoDerivative)
            .unwrap();
        f2.step(&gy[k], &ac[k], None, true, &mut NoDerivative)
            .unwrap();
    }
    // Compare as correlation-normalised differences: the F² term adds the O(Ts) direct
    // gyro-bias → velocity coupling that the first-order Φ only builds over two steps.
    let (p1, p2) = (f1.covariance(), f2.covariance());
    let mut d = 0.0_f64;
    for i in 0..15 {
        for j in 0..15 {
            let s = (p1[(i, i)] * p1[(j, j)]).sqrt();
            d = d.max((p1[(i, j)] - p2[(i, j)]).abs() / s);
        }
    }
    assert!(d < 0.05, "{d}");
    assert!((f1.gyro_bias_rad_s() - f2.gyro_bias_rad_s()).amax() < 1e-7);
}

#[test]
fn tczupt_tracks_a_thermal_ramp_that_zupt_lags() {
    // Bias follows b(T) = k·(T − 30) with T ramping at 2 °C/min (the thesis' ramp test);
    // the exact ∂b/∂T = k is handed to TCZUPT.
    let s = sim();
    let k = Vector3::new(2e-5, -3e-5, 1.5e-5); // rad/s/°C
    let n = 60_000;
    let mut rng = Gauss::new(11);
    let temps: Vec<f64> = (0..n)
        .map(|i| 27.0 + 2.0 / 60.0 * i as f64 * s.dt)
        .collect();
    let quiet = StaticSim {
        noise: ProcessNoise {
            sigma_gbi_rad_s: 0.0,
            ..s.noise
        },
        ..sim()
    };
    let (mut gy, ac, _) = quiet.run(n, Vector3::zeros(), Vector3::zeros(), &mut rng);
    let truth: Vec<Vector3<f64>> = temps.iter().map(|t| k * (t - 30.0)).collect();
    for (g, b) in gy.iter_mut().zip(&truth) {
        for i in 0..3 {
            g[i] += b[i];
        }
    }
    let b0 = truth[0];
    let run = |mode: Mode| {
        let cfg = ZuptConfig {
            mode,
            noise: if mode == Mode::Tczupt {
                ProcessNoise::thesis_tczupt()
            } else {
                ProcessNoise::thesis_zupt()
            },
            ..ZuptConfig::default()
        };
        let mut f = ZuptFilter::new(cfg, s.q, Vector3::zeros(), b0, s.dt).unwrap();
        let mut deriv = |_i: usize, _t: f64| k;
        let mut se = 0.0;
        for i in 0..n {
            f.step(&gy[i], &ac[i], Some(temps[i]), true, &mut deriv)
                .unwrap();
            if i >= n / 2 {
                se += (f.gyro_bias_rad_s() - truth[i]).norm_squared();
            }
        }
        ((se / (n / 2) as f64 / 3.0).sqrt(), f.temp_rate_c_s())
    };
    let (rms_z, _) = run(Mode::Classic);
    let (rms_t, rate) = run(Mode::Tczupt);
    assert!((rate - 2.0 / 60.0).abs() < 1e-9, "{rate}");
    assert!(rms_t < 0.7 * rms_z, "TCZUPT {rms_t} vs ZUPT {rms_z}");
}

#[test]
fn non_finite_input_and_bad_config_are_errors() {
    let s = sim();
    let cfg = ZuptConfig::<f64>::default();
    let mut f = ZuptFilter::new(cfg, s.q, Vector3::zeros(), Vector3::zeros(), s.dt).unwrap();
    let before = f.gyro_bias_rad_s();
    let e = f
        .step(
            &[f64::NAN, 0.0, 0.0],
            &[0.0, 0.0, -9.8],
            None,
            true,
            &mut NoDerivative,
        )
        .unwrap_err();
    assert!(matches!(
        e,
        NavError::NonFinite {
            what: "gyro_rad_s",
            ..
        }
    ));
    assert!(f
        .step(
            &[0.0; 3],
            &[f64::INFINITY, 0.0, 0.0],
            None,
            true,
            &mut NoDerivative
        )
        .is_err());
    assert_eq!(f.gyro_bias_rad_s(), before);
    let tc = ZuptConfig {
        mode: Mode::Tczupt,
        ..cfg
    };
    let mut f = ZuptFilter::new(tc, s.q, Vector3::zeros(), Vector3::zeros(), s.dt).unwrap();
    assert!(f
        .step(&[0.0; 3], &[0.0, 0.0, -9.8], None, true, &mut NoDerivative)
        .is_err());
    assert!(f
        .step(
            &[0.0; 3],
            &[0.0, 0.0, -9.8],
            Some(f64::NAN),
            true,
            &mut NoDerivative
        )
        .is_err());
    let bad = ZuptConfig {
        meas_std_velocity_m_s: 0.0,
        ..cfg
    };
    assert!(matches!(
        ZuptFilter::new(bad, s.q, Vector3::zeros(), Vector3::zeros(), s.dt),
        Err(NavError::InvalidParameter {
            what: "meas_std_velocity_m_s",
            ..
        })
    ));
    assert!(ZuptFilter::new(cfg, s.q, Vector3::zeros(), Vector3::zeros(), -1.0).is_err());
}

#[test]
fn batch_matches_stepwise_filter_and_recovers_turn_on_bias() {
    let s = sim();
    let cfg = ZuptConfig::<f64>::default();
    let mut rng = Gauss::new(5);
    let bg0 = Vector3::new(3e-3, -2e-3, 1e-3);
    let (gy, ac, tb) = s.run(20_000, bg0, Vector3::zeros(), &mut rng);
    let rows = 20_000usize.div_ceil(100);
    let (mut gb, mut ab, mut att, mut cov, mut tr) = (
        vec![[0.0; 3]; rows],
        vec![[0.0; 3]; rows],
        vec![[0.0; 4]; rows],
        vec![[0.0; 15]; rows],
        vec![0.0; rows],
    );
    let (_, _, yaw) = crate::attitude::quat_to_euler321(&s.q);
    let input = BatchInput {
        dt_s: s.dt,
        gyro_rad_s: &gy,
        accel_m_s2: &ac,
        temp_c: None,
        mag: None,
        stationary: None,
        levelling_samples: 6000,
        heading: HeadingSource::Given(yaw),
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
    let sum = ZuptFilter::run_batch(cfg, &input, &mut NoDerivative, &mut out).unwrap();
    assert_eq!(sum.updates, 200);
    // Mean NIS of a consistent filter ≈ 9 (χ²₉); the levelled (not true) attitude biases it a
    // little, so accept a generous band.
    assert!(
        sum.mean_nis > 4.0 && sum.mean_nis < 20.0,
        "{}",
        sum.mean_nis
    );
    let e = Vector3::from(out.gyro_bias_rad_s[rows - 1]) - tb[19_900];
    assert!(e.amax() < 2e-4, "{e}");
    // Bias σ shrinks monotonically-ish from the prior.
    assert!(out.cov_diag[rows - 1][14] < 0.01 * out.cov_diag[0][14]);
    // Initial zeroing starts the estimate at the 60 s mean minus Earth rate: within a few
    // σ_ARW/√60 ≈ 1.2e-4 rad/s of the truth instead of 3e-3 away.
    let zeroed = BatchInput {
        zero_gyro_bias: true,
        ..input
    };
    ZuptFilter::run_batch(cfg, &zeroed, &mut NoDerivative, &mut out).unwrap();
    let e0 = Vector3::from(out.gyro_bias_rad_s[0]) - tb[0];
    assert!(e0.amax() < 5e-4, "{e0}");
    // Wrong buffer sizes are errors, not panics.
    let mut short = vec![[0.0; 3]; rows - 1];
    let mut out2 = BatchOutput {
        decimation: 100,
        gyro_bias_rad_s: &mut short,
        accel_bias_m_s2: &mut ab,
        attitude: &mut att,
        cov_diag: &mut cov,
        temp_rate_c_s: &mut tr,
    };
    assert!(matches!(
        ZuptFilter::run_batch(cfg, &input, &mut NoDerivative, &mut out2),
        Err(NavError::LengthMismatch { .. })
    ));
}

fn is_psd(p: &nalgebra::SMatrix<f64, 15, 15>) -> bool {
    // Symmetric and its eigenvalues ≥ −1e-12·max.
    let sym = (p - p.transpose()).amax() <= 1e-12 * p.amax();
    let ev = p.symmetric_eigenvalues();
    sym && ev.iter().all(|&e| e > -1e-9 * p.amax())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn covariance_stays_symmetric_psd_and_finite(
        seed in 0u64..1_000_000,
        roll in -1.0f64..1.0, pitch in -1.0f64..1.0, yaw in -3.0f64..3.0,
        scale in -3.0f64..3.0,
        moving in 0.0f64..1.0,
        second in any::<bool>(),
    ) {
        // Random attitudes, noise levels scaled by 10^scale, random non-stationary spans and
        // gross input (large rates): the filter must never produce a non-finite or indefinite P.
        let q = euler321_to_quat(roll, pitch, yaw);
        let k = 10f64.powf(scale);
        let cfg = ZuptConfig {
            noise: ProcessNoise {
                sigma_vrw_m_s_sqrt_s: 1e-3 * k,
                sigma_arw_rad_sqrt_s: 1e-3 * k,
                sigma_abi_m_s2: 1e-4 * k,
                sigma_gbi_rad_s: 1e-5 * k,
            },
            discretisation: if second { Discretisation::SecondOrder } else { Discretisation::FirstOrder },
            ..ZuptConfig::default()
        };
        let mut rng = Gauss::new(seed);
        let mut f = ZuptFilter::new(cfg, q, Vector3::zeros(), Vector3::zeros(), 0.01).unwrap();
        for i in 0..1500 {
            let still = (i as f64 / 1500.0) > moving * 0.5;
            let g = rng.vec3(if still { 1e-2 } else { 1.0 });
            let a = Vector3::new(0.0, 0.0, -9.8) + rng.vec3(if still { 0.05 } else { 3.0 });
            f.step(&g.into(), &a.into(), None, still, &mut NoDerivative).unwrap();
        }
        let p = f.covariance();
        prop_assert!(p.iter().all(|x| x.is_finite()));
        prop_assert!(is_psd(p));
        prop_assert!(f.gyro_bias_rad_s().iter().all(|x| x.is_finite()));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn any_finite_input_gives_ok_or_err_never_a_panic_or_silent_nan(
        seed in 0u64..1_000_000,
        mag in -300.0f64..300.0,
        tc in any::<bool>(),
    ) {
        // Finite input of any magnitude (up to 1e300): every step returns Ok with a finite
        // state or an Err; nothing panics and no NaN is carried forward silently.
        let cfg = ZuptConfig {
            mode: if tc { Mode::Tczupt } else { Mode::Classic },
            ..ZuptConfig::default()
        };
        let mut f = ZuptFilter::new(cfg, UnitQuaternion::identity(), Vector3::zeros(), Vector3::zeros(), 0.01)
            .unwrap();
        let mut rng = Gauss::new(seed);
        let scale = 10f64.powf(mag);
        let mut deriv = |_i: usize, t: f64| Vector3::new(t, -t, 1e-5);
        for _ in 0..250 {
            let g = rng.vec3(scale);
            let a = rng.vec3(scale);
            let temp = rng.next() * scale;
            match f.step(&g.into(), &a.into(), Some(temp), true, &mut deriv) {
                Ok(_) => {
                    prop_assert!(f.gyro_bias_rad_s().iter().all(|x| x.is_finite()));
                    prop_assert!(f.covariance().iter().all(|x| x.is_finite()));
                }
                Err(_) => break,
            }
        }
    }
}
