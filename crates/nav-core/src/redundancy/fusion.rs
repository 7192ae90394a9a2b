//! Weighted least-squares fusion of redundant sensor axes and parity-space fault detection
//! and isolation (FDI).
//!
//! Model per sample: `z = H·x + b + v`, `v ~ N(0, diag σ²)`, with `x` the IMU-frame rate
//! (rad/s) or specific force (m/s²). The WLS estimate is `x̂ = (HᵀWH)⁻¹HᵀW(z − b)` with
//! `W = diag(1/σ²)` (σ from each sensor's Allan white noise), covariance `(HᵀWH)⁻¹`.
//! The parity statistic `χ² = Σ (z_i − b_i − h_iᵀx̂)²/σ_i²` is χ²-distributed with
//! `n − 3` degrees of freedom when no axis is faulty, so the detection threshold for a
//! false-alarm probability `p_fa` per sample is the χ² upper quantile ([`super::chi2`]).
//! Isolation removes, one sensor at a time, the sensor whose exclusion leaves the smallest
//! normalised statistic `χ²'/T(dof')`, and re-fuses without it (graceful degradation).
//!
//! Before the parity test, axes are screened: non-finite samples (dropouts), samples at or
//! beyond the saturation limit and outputs stuck at one value for `stuck_samples` samples
//! exclude their sensor and set its [`SensorHealth`] flag.
use nalgebra::{Matrix3, Vector3};

use super::chi2::chi2_threshold;
use super::geometry::{check_info, SensorArray};
use crate::scalar::lit;
use crate::{NavError, Real};

/// Result of fusing one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fused<T: Real> {
    /// Fused IMU-frame vector (unit of the measurement: rad/s or m/s²).
    pub value: Vector3<T>,
    /// Its covariance `(HᵀWH)⁻¹` (unit²).
    pub covariance: Matrix3<T>,
    /// Parity statistic `Σ r_i²/σ_i²` (dimensionless).
    pub chi2: T,
    /// Degrees of freedom `n_used − 3`.
    pub dof: usize,
    /// Number of axes used.
    pub n_used: usize,
}

/// Weighted least-squares fusion of one sample `z` (per axis, length ≥ `n_axes`) with
/// per-axis noise `sigma` and bias corrections `bias` (subtracted), using the axes with
/// `use_axis[i]`. Non-finite used samples are an error (screen them first).
pub fn wls<T: Real, const M: usize>(
    array: &SensorArray<T, M>,
    z: &[T],
    sigma: &[T],
    bias: &[T],
    use_axis: &[bool],
) -> Result<Fused<T>, NavError> {
    let n = array.n_axes();
    for (what, len) in [
        ("z", z.len()),
        ("sigma", sigma.len()),
        ("bias", bias.len()),
        ("use_axis", use_axis.len()),
    ] {
        if len < n {
            return Err(NavError::LengthMismatch {
                what,
                expected: n,
                got: len,
            });
        }
    }
    let mut a = Matrix3::zeros();
    let mut rhs = Vector3::zeros();
    let mut n_used = 0;
    for i in 0..n {
        if !use_axis[i] {
            continue;
        }
        let zi = z[i] - bias[i];
        if !num_traits::Float::is_finite(zi) {
            return Err(NavError::NonFinite {
                what: "sensor sample",
                index: i,
            });
        }
        let h = array.axis(i);
        let w = T::one() / (sigma[i] * sigma[i]);
        a += h * h.transpose() * w;
        rhs += h * (zi * w);
        n_used += 1;
    }
    check_info(&a)?;
    let cov = a.try_inverse().ok_or(NavError::NotPositiveDefinite {
        what: "information matrix HᵀWH",
    })?;
    let x = cov * rhs;
    let mut chi2 = T::zero();
    for i in 0..n {
        if use_axis[i] {
            let r = (z[i] - bias[i] - array.axis(i).dot(&x)) / sigma[i];
            chi2 += r * r;
        }
    }
    Ok(Fused {
        value: x,
        covariance: cov,
        chi2,
        dof: n_used - 3,
        n_used,
    })
}

/// Least-squares residuals `r_i = z_i − h_iᵀx̂` of one sample fused from every axis with
/// weights `1/σ²` and no bias correction, written to `out[..n_axes]`. Their mean over a
/// window is the observable (parity-space) part of the axis biases.
pub fn parity_residuals<T: Real, const M: usize>(
    array: &SensorArray<T, M>,
    z: &[T],
    sigma: &[T],
    out: &mut [T],
) -> Result<(), NavError> {
    let n = array.n_axes();
    if out.len() < n {
        return Err(NavError::LengthMismatch {
            what: "out",
            expected: n,
            got: out.len(),
        });
    }
    // `wls` squares sigma, so a negative or infinite one would pass silently as |σ| or as
    // weight 0: the same check as `FdiFuser::new`.
    if sigma
        .iter()
        .take(n)
        .any(|s| !num_traits::Float::is_finite(*s) || *s <= T::zero())
    {
        return Err(NavError::InvalidParameter {
            what: "sigma",
            reason: "every axis noise must be finite and positive",
        });
    }
    let zero = [T::zero(); M];
    let all = [true; M];
    let f = wls(array, z, sigma, &zero[..n], &all[..n])?;
    for (i, r) in out.iter_mut().enumerate().take(n) {
        *r = z[i] - array.axis(i).dot(&f.value);
        // Finite samples near the float range can still overflow the residual.
        if !num_traits::Float::is_finite(*r) {
            return Err(NavError::NonFinite {
                what: "parity residual (samples too large)",
                index: i,
            });
        }
    }
    Ok(())
}

/// Per-sensor health flags of one sample (bit set; 0 = healthy).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SensorHealth(pub u8);

impl SensorHealth {
    /// Healthy.
    pub const OK: u8 = 0;
    /// A sample was NaN or infinite (dropout).
    pub const NON_FINITE: u8 = 1;
    /// A sample reached the saturation limit.
    pub const SATURATED: u8 = 2;
    /// An output repeated the same value for `stuck_samples` samples.
    pub const STUCK: u8 = 4;
    /// Isolated by the parity test.
    pub const PARITY: u8 = 8;

    /// True when no flag is set.
    pub fn is_ok(self) -> bool {
        self.0 == 0
    }
}

/// FDI settings (units of the measurement: rad/s for gyros, m/s² for accelerometers).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FdiConfig<T: Real> {
    /// False-alarm probability of the parity test per sample (0 < p < 1).
    pub p_fa: T,
    /// Absolute output at or beyond which a sample counts as saturated (∞ = off).
    pub saturation: T,
    /// Consecutive identical samples that flag an output as stuck (0 = off).
    pub stuck_samples: u32,
    /// Maximum number of sensors isolated by the parity test per sample.
    pub max_isolations: usize,
}

impl<T: Real> Default for FdiConfig<T> {
    fn default() -> Self {
        Self {
            p_fa: lit(1e-6),
            saturation: T::infinity(),
            stuck_samples: 0,
            max_isolations: 2,
        }
    }
}

/// Output of [`FdiFuser::step`] for up to `S` sensors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FdiOutput<T: Real, const S: usize> {
    /// The fused sample from the axes that passed (meaningful only if `valid`).
    pub fused: Fused<T>,
    /// True when the remaining axes observe three axes and pass the parity test (or no
    /// redundancy is left to test them).
    pub valid: bool,
    /// True when the parity test fired on this sample (before isolation).
    pub alarm: bool,
    /// Health of each sensor on this sample.
    pub health: [SensorHealth; S],
}

/// Stateful fuser with fault detection, isolation and re-fusion; `M` axes and `S` sensors
/// at most (compile time), no allocation per sample.
#[derive(Debug, Clone)]
pub struct FdiFuser<T: Real, const M: usize, const S: usize> {
    array: SensorArray<T, M>,
    sigma: [T; M],
    bias: [T; M],
    config: FdiConfig<T>,
    threshold: [T; M],
    last: [T; M],
    repeats: [u32; M],
}

impl<T: Real, const M: usize, const S: usize> FdiFuser<T, M, S> {
    /// New fuser for `array` with per-axis white-noise σ per sample (`sigma`, unit of the
    /// measurement, all finite and positive).
    pub fn new(
        array: SensorArray<T, M>,
        sigma: &[T],
        config: FdiConfig<T>,
    ) -> Result<Self, NavError> {
        let n = array.n_axes();
        if array.n_sensors() > S {
            return Err(NavError::InvalidParameter {
                what: "sensors",
                reason: "more sensors than the compile-time capacity S",
            });
        }
        if sigma.len() != n {
            return Err(NavError::LengthMismatch {
                what: "sigma",
                expected: n,
                got: sigma.len(),
            });
        }
        if sigma
            .iter()
            .any(|s| !num_traits::Float::is_finite(*s) || *s <= T::zero())
        {
            return Err(NavError::InvalidParameter {
                what: "sigma",
                reason: "every axis noise must be finite and positive",
            });
        }
        if !(config.saturation > T::zero()) {
            return Err(NavError::InvalidParameter {
                what: "saturation",
                reason: "must be positive (infinity disables the check)",
            });
        }
        if config.stuck_samples == 1 {
            return Err(NavError::InvalidParameter {
                what: "stuck_samples",
                reason: "must be 0 (off) or at least 2 identical samples",
            });
        }
        let mut threshold = [T::infinity(); M];
        for (d, t) in threshold.iter_mut().enumerate().skip(1) {
            *t = chi2_threshold(d, config.p_fa)?;
        }
        let mut s = [T::one(); M];
        s[..n].copy_from_slice(sigma);
        Ok(Self {
            array,
            sigma: s,
            bias: [T::zero(); M],
            config,
            threshold,
            last: [T::nan(); M],
            repeats: [0; M],
        })
    }

    /// Sets per-axis bias corrections (subtracted before fusion), e.g. the parity-space bias
    /// learned during an initial static window or a Kalman filter's bias estimates.
    pub fn set_axis_bias(&mut self, bias: &[T]) -> Result<(), NavError> {
        let n = self.array.n_axes();
        if bias.len() != n {
            return Err(NavError::LengthMismatch {
                what: "bias",
                expected: n,
                got: bias.len(),
            });
        }
        crate::error::check_finite("bias", bias)?;
        self.bias[..n].copy_from_slice(bias);
        Ok(())
    }

    /// The detection threshold (χ² upper quantile) for `dof` degrees of freedom.
    pub fn threshold(&self, dof: usize) -> T {
        self.threshold[dof.min(M - 1)]
    }

    /// Fuses one sample (`z`: one value per axis, array order) with screening, parity
    /// detection, isolation and re-fusion.
    pub fn step(&mut self, z: &[T]) -> Result<FdiOutput<T, S>, NavError> {
        let n = self.sample_len(z)?;
        let mut health = [SensorHealth::default(); S];
        for i in 0..n {
            let s = self.array.sensor_of(i);
            let v = z[i];
            if !num_traits::Float::is_finite(v) {
                health[s].0 |= SensorHealth::NON_FINITE;
            } else if num_traits::Float::abs(v) >= self.config.saturation {
                health[s].0 |= SensorHealth::SATURATED;
            }
            if v == self.last[i] {
                self.repeats[i] = self.repeats[i].saturating_add(1);
            } else {
                self.repeats[i] = 0;
            }
            self.last[i] = v;
            if self.config.stuck_samples > 0 && self.repeats[i] + 1 >= self.config.stuck_samples {
                health[s].0 |= SensorHealth::STUCK;
            }
        }
        let mut use_axis = self.healthy_axes(&health);
        let mut alarm = false;
        let mut isolations = 0;
        loop {
            let fused = match wls(&self.array, z, &self.sigma, &self.bias, &use_axis) {
                Ok(f) => f,
                Err(NavError::InvalidParameter { .. }) => {
                    return Ok(self.invalid(alarm, health));
                }
                Err(e) => return Err(e),
            };
            if fused.dof == 0 || fused.chi2 <= self.threshold[fused.dof] {
                return Ok(FdiOutput {
                    fused,
                    valid: true,
                    alarm,
                    health,
                });
            }
            alarm = true;
            if isolations >= self.config.max_isolations {
                return Ok(FdiOutput {
                    fused,
                    valid: false,
                    alarm,
                    health,
                });
            }
            // Try every remaining sensor; keep the exclusion with the smallest normalised χ².
            let mut best: Option<(usize, T)> = None;
            for s in 0..self.array.n_sensors() {
                if !health[s].is_ok() {
                    continue;
                }
                let mut trial = use_axis;
                for (i, t) in trial.iter_mut().enumerate().take(n) {
                    if self.array.sensor_of(i) == s {
                        *t = false;
                    }
                }
                if let Ok(f) = wls(&self.array, z, &self.sigma, &self.bias, &trial) {
                    if f.dof >= 1 {
                        let ratio = f.chi2 / self.threshold[f.dof];
                        if best.is_none_or(|(_, r)| ratio < r) {
                            best = Some((s, ratio));
                        }
                    }
                }
            }
            match best {
                Some((s, _)) => {
                    health[s].0 |= SensorHealth::PARITY;
                    for (i, u) in use_axis.iter_mut().enumerate().take(n) {
                        if self.array.sensor_of(i) == s {
                            *u = false;
                        }
                    }
                    isolations += 1;
                }
                None => {
                    return Ok(FdiOutput {
                        fused,
                        valid: false,
                        alarm,
                        health,
                    })
                }
            }
        }
    }

    /// Fuses one sample without fault detection: only non-finite samples are screened out
    /// (their whole sensor is dropped and flagged [`SensorHealth::NON_FINITE`]); the parity
    /// statistic is reported but never acted on, `alarm` stays false, and the stuck-output
    /// history is left untouched. Invalid only when the remaining axes cannot observe three
    /// axes (never a value fused from non-finite samples).
    pub fn fuse_finite(&self, z: &[T]) -> Result<FdiOutput<T, S>, NavError> {
        self.sample_len(z)?;
        let mut health = [SensorHealth::default(); S];
        for (i, v) in z.iter().enumerate() {
            if !num_traits::Float::is_finite(*v) {
                health[self.array.sensor_of(i)].0 |= SensorHealth::NON_FINITE;
            }
        }
        let use_axis = self.healthy_axes(&health);
        match wls(&self.array, z, &self.sigma, &self.bias, &use_axis) {
            Ok(fused) => Ok(FdiOutput {
                fused,
                valid: true,
                alarm: false,
                health,
            }),
            Err(NavError::InvalidParameter { .. }) => Ok(self.invalid(false, health)),
            Err(e) => Err(e),
        }
    }

    /// Number of axes, checking that `z` holds one sample per axis.
    fn sample_len(&self, z: &[T]) -> Result<usize, NavError> {
        let n = self.array.n_axes();
        if z.len() != n {
            return Err(NavError::LengthMismatch {
                what: "z",
                expected: n,
                got: z.len(),
            });
        }
        Ok(n)
    }

    /// Axes whose sensor is healthy (a sensor with one bad axis is dropped as a whole).
    fn healthy_axes(&self, health: &[SensorHealth; S]) -> [bool; M] {
        let mut use_axis = [false; M];
        for (i, u) in use_axis.iter_mut().enumerate().take(self.array.n_axes()) {
            *u = health[self.array.sensor_of(i)].is_ok();
        }
        use_axis
    }

    fn invalid(&self, alarm: bool, health: [SensorHealth; S]) -> FdiOutput<T, S> {
        FdiOutput {
            fused: Fused {
                value: Vector3::repeat(T::nan()),
                covariance: Matrix3::repeat(T::nan()),
                chi2: T::nan(),
                dof: 0,
                n_used: 0,
            },
            valid: false,
            alarm,
            health,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::geometry::{AxisKind, Polyhedron};
    use super::*;

    type Arr = SensorArray<f64, 18>;

    fn cube6() -> Arr {
        Arr::from_polyhedron(Polyhedron::Cube, 1, AxisKind::Triaxial).unwrap()
    }

    // Deterministic pseudo-normal noise (sum of 12 uniforms from an LCG) for no-dependency
    // tests.
    struct Rng(u64);
    impl Rng {
        fn normal(&mut self) -> f64 {
            let mut s = 0.0;
            for _ in 0..12 {
                self.0 = self
                    .0
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                s += (self.0 >> 11) as f64 / (1u64 << 53) as f64;
            }
            s - 6.0
        }
    }

    fn sample(a: &Arr, w: &Vector3<f64>, sigma: f64, rng: &mut Rng) -> [f64; 18] {
        let mut z = [0.0; 18];
        for (i, zi) in z.iter_mut().enumerate() {
            *zi = a.axis(i).dot(w) + sigma * rng.normal();
        }
        z
    }

    #[test]
    fn wls_is_exact_without_noise_and_matches_mean_for_cube() {
        let a = cube6();
        let w = Vector3::new(0.1, -0.2, 0.3);
        let mut rng = Rng(1);
        let z = sample(&a, &w, 0.0, &mut rng);
        let f = wls(&a, &z, &[1.0; 18], &[0.0; 18], &[true; 18]).unwrap();
        assert!((f.value - w).amax() < 1e-14);
        assert!(f.chi2 < 1e-20);
        assert_eq!(f.dof, 15);
        // Covariance = σ²/6 per axis (k_r² = 1/6).
        assert!((f.covariance[(0, 0)] - 1.0 / 6.0).abs() < 1e-12);
    }

    #[test]
    fn parity_bias_does_not_move_the_estimate() {
        // A bias in the parity space (orthogonal to range(H)) leaves x̂ unchanged: this is
        // why the parity-space bias can be learned and removed without touching the output.
        let a = cube6();
        let mut z = sample(&a, &Vector3::new(0.01, 0.02, 0.03), 0.0, &mut Rng(2));
        let f0 = wls(&a, &z, &[1.0; 18], &[0.0; 18], &[true; 18]).unwrap();
        let mut b = [0.0; 18];
        for (i, bi) in b.iter_mut().enumerate() {
            *bi = (i as f64 * 0.37).sin();
        }
        let mut r = [0.0; 18];
        let fb = wls(&a, &b, &[1.0; 18], &[0.0; 18], &[true; 18]).unwrap();
        for i in 0..18 {
            r[i] = b[i] - a.axis(i).dot(&fb.value);
            z[i] += r[i];
        }
        let f1 = wls(&a, &z, &[1.0; 18], &[0.0; 18], &[true; 18]).unwrap();
        assert!((f1.value - f0.value).amax() < 1e-12);
        let f2 = wls(&a, &z, &[1.0; 18], &r, &[true; 18]).unwrap();
        assert!(f2.chi2 < 1e-20);
    }

    #[test]
    fn chi2_statistic_has_its_false_alarm_rate() {
        let a = cube6();
        let sigma = 0.01;
        let cfg = FdiConfig {
            p_fa: 0.05,
            ..FdiConfig::default()
        };
        let mut f = FdiFuser::<f64, 18, 6>::new(a, &[sigma; 18], cfg).unwrap();
        let mut rng = Rng(3);
        let mut alarms = 0;
        let n = 4000;
        for _ in 0..n {
            let z = sample(&a, &Vector3::new(0.1, 0.0, -0.1), sigma, &mut rng);
            if f.step(&z).unwrap().alarm {
                alarms += 1;
            }
        }
        let rate = alarms as f64 / n as f64;
        assert!((rate - 0.05).abs() < 0.015, "{rate}");
    }

    fn run_fault(kind: u8) -> (f64, f64) {
        // Returns (max error with FDI, max error of plain WLS) over the fault interval.
        let a = cube6();
        let sigma = 0.005;
        let cfg = FdiConfig {
            p_fa: 1e-6,
            saturation: 4.0,
            stuck_samples: 5,
            max_isolations: 2,
        };
        let mut f = FdiFuser::<f64, 18, 6>::new(a, &[sigma; 18], cfg).unwrap();
        let mut rng = Rng(4);
        let (mut e_fdi, mut e_plain) = (0.0f64, 0.0f64);
        let mut stuck_val = [0.0; 3];
        for k in 0..400 {
            let t = k as f64 * 0.01;
            let w = Vector3::new((2.0 * t).sin(), 0.5 * (3.0 * t).cos(), 0.2);
            let mut z = sample(&a, &w, sigma, &mut rng);
            if k == 199 {
                stuck_val.copy_from_slice(&z[6..9]);
            }
            if k >= 200 {
                // Sensor 2 (axes 6..9) fails.
                match kind {
                    0 => z[7] += 0.5,                         // bias step
                    1 => z[6..9].copy_from_slice(&stuck_val), // stuck output
                    2 => z[8] += 0.5 * rng.normal(),          // noise burst
                    3 => z[6] = 4.0,                          // saturation
                    _ => z[6] = f64::NAN,                     // dropout
                }
            }
            let out = f.step(&z).unwrap();
            if k >= 205 {
                assert!(out.valid, "kind {kind} k {k}");
                // A noise burst is only flagged on the samples where it is large.
                assert!(kind == 2 || !out.health[2].is_ok(), "kind {kind} k {k}");
                for s in [0, 1, 3, 4, 5] {
                    assert!(out.health[s].is_ok(), "kind {kind} k {k} s {s}");
                }
                e_fdi = e_fdi.max((out.fused.value - w).amax());
                let plain = wls(&a, &z, &[sigma; 18], &[0.0; 18], &[true; 18]);
                e_plain = e_plain.max(match plain {
                    Ok(p) => (p.value - w).amax(),
                    Err(_) => f64::INFINITY,
                });
            }
        }
        (e_fdi, e_plain)
    }

    #[test]
    fn faults_are_isolated_and_refused() {
        // No-fault envelope: 5σ of the fused estimate (σ·k_r with 5 sensors left).
        let envelope = 5.0 * 0.005 / 5f64.sqrt();
        for kind in 0..5 {
            let (e_fdi, e_plain) = run_fault(kind);
            assert!(e_fdi < envelope, "kind {kind}: {e_fdi}");
            assert!(e_plain > envelope, "kind {kind}: plain {e_plain}");
        }
    }

    #[test]
    fn unobservable_after_exclusion_is_invalid_not_garbage() {
        let a = Arr::from_polyhedron(Polyhedron::Cube, 1, AxisKind::Single).unwrap();
        let mut f = FdiFuser::<f64, 18, 6>::new(a, &[0.01; 6], FdiConfig::default()).unwrap();
        // Both x-axis gyros drop out: x is unobservable.
        let z = [f64::NAN, 0.0, 0.0, f64::NAN, 0.0, 0.0];
        let out = f.step(&z).unwrap();
        assert!(!out.valid);
        assert!(out.fused.value.iter().all(|v| v.is_nan()));
        assert_eq!(out.health[0].0, SensorHealth::NON_FINITE);
        assert!(f.step(&[0.0; 5]).is_err());
        let one = FdiConfig {
            stuck_samples: 1,
            ..FdiConfig::default()
        };
        assert!(FdiFuser::<f64, 18, 6>::new(a, &[0.01; 6], one).is_err());
    }

    #[test]
    fn fuse_finite_drops_only_non_finite_sensors_and_never_isolates() {
        let a = cube6();
        let w = Vector3::new(0.1, -0.2, 0.3);
        let mut z: [f64; 18] = core::array::from_fn(|i| a.axis(i).dot(&w));
        z[7] += 1.0; // a gross bias on sensor 2: FDI would isolate it, fuse_finite must not
        let f = FdiFuser::<f64, 18, 6>::new(a, &[0.01; 18], FdiConfig::default()).unwrap();
        let out = f.fuse_finite(&z).unwrap();
        let all = wls(&a, &z, &[0.01; 18], &[0.0; 18], &[true; 18]).unwrap();
        assert!(out.valid && !out.alarm);
        assert_eq!(out.fused, all);
        assert!(out.health.iter().all(|h| h.is_ok()));
        // chi² of a 1.0 residual spread over 18 axes is far beyond any threshold but ignored
        assert!(out.fused.chi2 > f.threshold(out.fused.dof));
        // A NaN on sensor 4 drops its three axes, exactly like excluding them by hand.
        z[13] = f64::NAN;
        let out = f.fuse_finite(&z).unwrap();
        let mut use_axis = [true; 18];
        use_axis[12..15].copy_from_slice(&[false; 3]);
        let ref_ = wls(&a, &z, &[0.01; 18], &[0.0; 18], &use_axis).unwrap();
        assert!(out.valid);
        assert_eq!(out.fused, ref_);
        assert_eq!(out.health[4].0, SensorHealth::NON_FINITE);
        assert!(f.fuse_finite(&z[..17]).is_err());
        // Both x gyros of a single-axis cube out: invalid, NaN, not garbage.
        let s = Arr::from_polyhedron(Polyhedron::Cube, 1, AxisKind::Single).unwrap();
        let fs = FdiFuser::<f64, 18, 6>::new(s, &[0.01; 6], FdiConfig::default()).unwrap();
        let out = fs
            .fuse_finite(&[f64::NAN, 0.0, 0.0, f64::NAN, 0.0, 0.0])
            .unwrap();
        assert!(!out.valid && out.fused.value.iter().all(|v| v.is_nan()));
    }

    #[test]
    fn parity_residuals_are_orthogonal_to_the_columns_of_h() {
        // r = (I − H(HᵀWH)⁻¹HᵀW) z: a rotation-like bias (H·x) leaves no residual, and with
        // equal weights Hᵀr = 0 for any z.
        let a = cube6();
        let mut rng = Rng(7);
        let z: [f64; 18] = core::array::from_fn(|_| rng.normal());
        let mut r = [0.0; 18];
        parity_residuals(&a, &z, &[0.5; 18], &mut r).unwrap();
        let mut htr = Vector3::zeros();
        for (i, ri) in r.iter().enumerate() {
            htr += a.axis(i) * *ri;
        }
        assert!(htr.amax() < 1e-12);
        let x = Vector3::new(1.0, 2.0, -3.0);
        let zx: [f64; 18] = core::array::from_fn(|i| a.axis(i).dot(&x));
        parity_residuals(&a, &zx, &[0.5; 18], &mut r).unwrap();
        assert!(r.iter().all(|v| v.abs() < 1e-12));
        assert!(parity_residuals(&a, &z, &[0.5; 18], &mut r[..17]).is_err());
    }

    proptest::proptest! {
        #[test]
        fn wls_recovers_any_rate_for_any_rotated_array(
            r in -3.0f64..3.0, p in -1.5f64..1.5, y in -3.0f64..3.0,
            wx in -5.0f64..5.0, wy in -5.0f64..5.0, wz in -5.0f64..5.0,
        ) {
            // Rotating the whole array (all mountings by one rotation) keeps k_r = 1/√6 and the
            // noise-free WLS estimate exact: an invariant independent of the face layout.
            let rot = crate::attitude::quat_to_dcm(&crate::attitude::euler321_to_quat(r, p, y));
            let mut ms = [Matrix3::zeros(); 6];
            for (f, m) in ms.iter_mut().enumerate() {
                *m = Polyhedron::Cube.face_frame::<f64>(f).unwrap() * rot;
            }
            let a = Arr::from_mountings(&ms, 1e-9).unwrap();
            let k = a.k_r().unwrap();
            proptest::prop_assert!((k - Vector3::repeat(1.0 / 6f64.sqrt())).amax() < 1e-12);
            let w = Vector3::new(wx, wy, wz);
            let z: [f64; 18] = core::array::from_fn(|i| a.axis(i).dot(&w));
            let f = wls(&a, &z, &[1.0; 18], &[0.0; 18], &[true; 18]).unwrap();
            proptest::prop_assert!((f.value - w).amax() < 1e-12);
        }
    }

    #[test]
    fn f32_fusion_works() {
        let a = SensorArray::<f32, 18>::from_polyhedron(Polyhedron::Cube, 1, AxisKind::Triaxial)
            .unwrap();
        let w = Vector3::new(0.1f32, -0.2, 0.3);
        let z: [f32; 18] = core::array::from_fn(|i| a.axis(i).dot(&w));
        let mut f = FdiFuser::<f32, 18, 6>::new(a, &[1e-3; 18], FdiConfig::default()).unwrap();
        let out = f.step(&z).unwrap();
        assert!(out.valid && (out.fused.value - w).amax() < 1e-5);
    }
}
