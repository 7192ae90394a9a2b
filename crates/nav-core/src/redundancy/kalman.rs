//! Kalman fusion with one bias state per sensor axis: the partial self-calibration that
//! redundancy allows (the thesis' second future development, §4.3.6).
//!
//! State `[ω (3, IMU frame); b_1 … b_n (axis biases)]`, all random walks:
//! `ω` with a large spectral density (it follows the motion), `b_i` with the sensors' bias
//! random-walk density. Measurement `z_i = h_iᵀω + b_i + v_i`. Only the component of `b` in
//! the parity space (orthogonal to the range of `H`) is observable from the redundant
//! measurements alone; the rest stays at its prior unless an external rate reference is
//! applied with [`BiasKalman::update_rate`] (a zero-rate update while static, or the Earth
//! rate), which makes every bias observable.
//!
//! `S` is the compile-time state size (`3 + n_axes` at most); unused states stay inert.
use nalgebra::{SMatrix, SVector, Vector3};

use super::geometry::SensorArray;
use crate::{NavError, Real};

/// Noise settings of [`BiasKalman`] (rad/s units for a gyro array; m/s² for accelerometers).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasKalmanConfig<T: Real> {
    /// Random-walk spectral density of the true rate (unit²/s): how fast it may change.
    pub rate_psd: T,
    /// Random-walk spectral density of each axis bias (unit²/s).
    pub bias_psd: T,
    /// Prior standard deviation of each axis bias (unit), e.g. the turn-on bias spec.
    pub bias_sigma0: T,
    /// Prior standard deviation of the rate (unit).
    pub rate_sigma0: T,
}

/// Kalman filter over the rate and per-axis biases of a redundant array.
#[derive(Debug, Clone)]
pub struct BiasKalman<T: Real, const S: usize> {
    x: SVector<T, S>,
    p: SMatrix<T, S, S>,
    h: [Vector3<T>; S],
    r: [T; S],
    n: usize,
    cfg: BiasKalmanConfig<T>,
}

impl<T: Real, const S: usize> BiasKalman<T, S> {
    /// New filter for the axes of `array` with per-axis white noise σ per sample (`sigma`).
    pub fn new<const M: usize>(
        array: &SensorArray<T, M>,
        sigma: &[T],
        cfg: BiasKalmanConfig<T>,
    ) -> Result<Self, NavError> {
        let n = array.n_axes();
        if n + 3 > S {
            return Err(NavError::InvalidParameter {
                what: "sensor axes",
                reason: "3 + number of axes exceeds the filter's compile-time state size S",
            });
        }
        if sigma.len() != n {
            return Err(NavError::LengthMismatch {
                what: "sigma",
                expected: n,
                got: sigma.len(),
            });
        }
        for v in [cfg.rate_psd, cfg.bias_psd, cfg.bias_sigma0, cfg.rate_sigma0]
            .iter()
            .chain(sigma.iter())
        {
            // The σ are squared into P and R: their squares must be finite too (1e308² = inf).
            if !num_traits::Float::is_finite(*v * *v) || *v < T::zero() {
                return Err(NavError::InvalidParameter {
                    what: "kalman noise",
                    reason:
                        "every noise parameter must be finite (its square too) and non-negative",
                });
            }
        }
        // A zero measurement σ makes R singular: every other consumer of the per-axis σ
        // (WLS fusion, FDI, parity residuals) requires σ > 0; so does the filter.
        if sigma.iter().any(|s| !(*s > T::zero())) {
            return Err(NavError::InvalidParameter {
                what: "sigma",
                reason: "every measurement sigma must be > 0",
            });
        }
        let mut h = [Vector3::zeros(); S];
        let mut r = [T::one(); S];
        let mut p = SMatrix::<T, S, S>::zeros();
        for j in 0..3 {
            p[(j, j)] = cfg.rate_sigma0 * cfg.rate_sigma0;
        }
        for i in 0..n {
            h[i] = array.axis(i);
            r[i] = sigma[i] * sigma[i];
            p[(3 + i, 3 + i)] = cfg.bias_sigma0 * cfg.bias_sigma0;
        }
        Ok(Self {
            x: SVector::zeros(),
            p,
            h,
            r,
            n,
            cfg,
        })
    }

    /// Time update over `dt_s` seconds (random walks: `P += Q·dt`); `dt_s` must be finite
    /// and > 0 (a zero step is a duplicated timestamp, refused as everywhere in nav-core).
    pub fn predict(&mut self, dt_s: T) -> Result<(), NavError> {
        if !(num_traits::Float::is_finite(dt_s) && dt_s > T::zero()) {
            return Err(NavError::InvalidParameter {
                what: "dt_s",
                reason: "must be finite and > 0",
            });
        }
        for j in 0..3 {
            self.p[(j, j)] += self.cfg.rate_psd * dt_s;
        }
        for i in 0..self.n {
            self.p[(3 + i, 3 + i)] += self.cfg.bias_psd * dt_s;
        }
        Ok(())
    }

    // One scalar update with measurement row `H = [g (rate part), e_bias]`.
    fn scalar_update(
        &mut self,
        g: &Vector3<T>,
        bias: Option<usize>,
        z: T,
        r: T,
    ) -> Result<(), NavError> {
        let mut ph = SVector::<T, S>::zeros();
        for k in 0..S {
            let mut v = self.p[(k, 0)] * g.x + self.p[(k, 1)] * g.y + self.p[(k, 2)] * g.z;
            if let Some(b) = bias {
                v += self.p[(k, 3 + b)];
            }
            ph[k] = v;
        }
        let mut s = ph[0] * g.x + ph[1] * g.y + ph[2] * g.z + r;
        let mut pred = self.x[0] * g.x + self.x[1] * g.y + self.x[2] * g.z;
        if let Some(b) = bias {
            s += ph[3 + b];
            pred += self.x[3 + b];
        }
        if !(s > T::zero()) || !num_traits::Float::is_finite(s) {
            return Err(NavError::NotPositiveDefinite {
                what: "innovation variance",
            });
        }
        let k = ph / s;
        self.x += k * (z - pred);
        // P ← P − K·(PH)ᵀ = P − K·S·Kᵀ as an in-place rank-1 update; the caller
        // symmetrises once per batch of scalar updates.
        self.p.ger(-T::one(), &k, &ph, T::one());
        Ok(())
    }

    fn symmetrise(&mut self) {
        for i in 0..S {
            for j in (i + 1)..S {
                let v = (self.p[(i, j)] + self.p[(j, i)]) * crate::scalar::lit::<T>(0.5);
                self.p[(i, j)] = v;
                self.p[(j, i)] = v;
            }
        }
    }

    /// Measurement update with one sample (one value per axis); axes with `use_axis[i]`
    /// false (excluded by FDI) are skipped. Non-finite used samples are an error.
    pub fn update(&mut self, z: &[T], use_axis: &[bool]) -> Result<(), NavError> {
        if z.len() != self.n || use_axis.len() != self.n {
            return Err(NavError::LengthMismatch {
                what: "z / use_axis",
                expected: self.n,
                got: z.len().min(use_axis.len()),
            });
        }
        for i in 0..self.n {
            if !use_axis[i] {
                continue;
            }
            if !num_traits::Float::is_finite(z[i]) {
                return Err(NavError::NonFinite {
                    what: "sensor sample",
                    index: i,
                });
            }
            let g = self.h[i];
            self.scalar_update(&g, Some(i), z[i], self.r[i])?;
        }
        self.symmetrise();
        Ok(())
    }

    /// External rate reference (e.g. zero while static, or the Earth rate in the IMU frame)
    /// with standard deviation `sigma` per axis.
    pub fn update_rate(&mut self, rate: &Vector3<T>, sigma: T) -> Result<(), NavError> {
        if rate.iter().any(|v| !num_traits::Float::is_finite(*v)) || !(sigma > T::zero()) {
            return Err(NavError::InvalidParameter {
                what: "rate reference",
                reason: "must be finite with a positive sigma",
            });
        }
        for j in 0..3 {
            let g = Vector3::ith(j, T::one());
            self.scalar_update(&g, None, rate[j], sigma * sigma)?;
        }
        self.symmetrise();
        Ok(())
    }

    /// Estimated IMU-frame rate (unit of the measurement).
    pub fn rate(&self) -> Vector3<T> {
        Vector3::new(self.x[0], self.x[1], self.x[2])
    }

    /// Estimated bias of axis `i` (unit of the measurement; 0 beyond the axes).
    pub fn axis_bias(&self, i: usize) -> T {
        if i < self.n {
            self.x[3 + i]
        } else {
            T::zero()
        }
    }

    /// Standard deviation of the bias estimate of axis `i`.
    pub fn axis_bias_sigma(&self, i: usize) -> T {
        if i < self.n {
            num_traits::Float::sqrt(self.p[(3 + i, 3 + i)])
        } else {
            T::zero()
        }
    }

    /// Standard deviation of the rate estimate per IMU axis.
    pub fn rate_sigma(&self) -> Vector3<T> {
        Vector3::new(
            num_traits::Float::sqrt(self.p[(0, 0)]),
            num_traits::Float::sqrt(self.p[(1, 1)]),
            num_traits::Float::sqrt(self.p[(2, 2)]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::fusion::wls;
    use super::super::geometry::{AxisKind, Polyhedron};
    use super::*;

    #[test]
    fn learns_parity_bias_and_full_bias_with_zero_rate_updates() {
        let a = SensorArray::<f64, 18>::from_polyhedron(Polyhedron::Cube, 1, AxisKind::Triaxial)
            .unwrap();
        let mut b = [0.0; 18];
        for (i, bi) in b.iter_mut().enumerate() {
            *bi = 0.05 * ((i as f64) * 1.7).sin();
        }
        let cfg = BiasKalmanConfig {
            rate_psd: 1.0,
            bias_psd: 1e-12,
            bias_sigma0: 0.05,
            rate_sigma0: 1.0,
        };
        let mut kf = BiasKalman::<f64, 21>::new(&a, &[1e-3; 18], cfg).unwrap();
        let mut kz = kf.clone();
        for k in 0..500 {
            let w = Vector3::new((0.01 * k as f64).sin(), 0.2, -0.1);
            let z: [f64; 18] = core::array::from_fn(|i| a.axis(i).dot(&w) + b[i]);
            kf.predict(0.01).unwrap();
            kf.update(&z, &[true; 18]).unwrap();
            let zs: [f64; 18] = core::array::from_fn(|i| b[i]);
            kz.predict(0.01).unwrap();
            kz.update(&zs, &[true; 18]).unwrap();
            kz.update_rate(&Vector3::zeros(), 1e-4).unwrap();
        }
        // Parity part of b: b − H·(H⁺b); the filter's bias estimate matches it (its
        // range-space part stays at the prior mean, zero).
        let fb = wls(&a, &b, &[1.0; 18], &[0.0; 18], &[true; 18]).unwrap();
        for i in 0..18 {
            let parity = b[i] - a.axis(i).dot(&fb.value);
            assert!((kf.axis_bias(i) - parity).abs() < 2e-4, "{i}");
            // With the zero-rate reference every bias is observable.
            assert!((kz.axis_bias(i) - b[i]).abs() < 2e-4, "{i}");
        }
        assert!(kz.axis_bias_sigma(0) < kf.axis_bias_sigma(0));
    }

    #[test]
    fn rejects_bad_input() {
        let a = SensorArray::<f64, 18>::from_polyhedron(Polyhedron::Cube, 1, AxisKind::Triaxial)
            .unwrap();
        let cfg = BiasKalmanConfig {
            rate_psd: 1.0,
            bias_psd: 0.0,
            bias_sigma0: 0.05,
            rate_sigma0: 1.0,
        };
        assert!(BiasKalman::<f64, 20>::new(&a, &[1e-3; 18], cfg).is_err());
        let mut kf = BiasKalman::<f64, 21>::new(&a, &[1e-3; 18], cfg).unwrap();
        let mut z = [0.0; 18];
        z[3] = f64::NAN;
        assert!(matches!(
            kf.update(&z, &[true; 18]),
            Err(NavError::NonFinite { index: 3, .. })
        ));
        assert!(kf.predict(f64::NAN).is_err());
    }
}
