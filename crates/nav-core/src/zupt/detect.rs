//! Stationarity detection for ZUPT: the generalised likelihood ratio test of Skog et al.
//! (2010), "Zero-velocity detection — an algorithm evaluation" (IEEE TBME 57(11)), "SHOE".
//!
//! Over a window `Ω` of `W` samples the statistic is
//!
//! `T = (1/W)·Σ_{l∈Ω} [ ‖a_l − g·ā/‖ā‖‖²/σ_a² + ‖ω_l‖²/σ_ω² ]`
//!
//! and the unit is declared stationary when `T < γ`. Expanding the square,
//! `Σ‖a_l − g·u‖² = Σ‖a_l‖² − 2g·‖Σa_l‖ + W·g²` with `u = Σa_l/‖Σa_l‖`, so `T` needs only the
//! running sums `Σa`, `Σ‖a‖²`, `Σ‖ω‖²`: O(1) per sample with a ring buffer (recomputed from
//! the buffer once per [`DETECT_CAPACITY`] samples against rounding drift).
//!
//! Documented defaults ([`StationarityConfig::default`]): `σ_a = 0.05 m/s²`,
//! `σ_ω = 0.01 rad/s`, `W = 25` samples (0.25 s at 100 Hz), `γ = 10`. For white noise only,
//! `E[T] ≈ (2σ²_{n,a})/σ_a² + (3σ²_{n,ω} + ‖b_ω‖²)/σ_ω²` (σ_n per-sample noise, b_ω the gyro
//! bias), i.e. ≈ 2–3 for a consumer MEMS IMU at rest; motion drives `T` to 10²–10⁴. Raise
//! `σ_a`, `σ_ω` for noisier sensors (the known failure: noisy IMUs never detected as static).
// No unchecked indexing in library code; a proven index carries an `allow`.
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]
use crate::scalar::from_usize;
use crate::{NavError, Real};

/// Capacity (samples) of the detector window.
pub const DETECT_CAPACITY: usize = 256;

/// Thresholds of the GLRT detector; every field names its unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StationarityConfig<T> {
    /// Accelerometer noise scale σ_a (m/s²).
    pub sigma_accel_m_s2: T,
    /// Gyro noise scale σ_ω (rad/s).
    pub sigma_gyro_rad_s: T,
    /// Window length W (samples, 1 ≤ W ≤ [`DETECT_CAPACITY`]).
    pub window_samples: usize,
    /// Threshold γ on the statistic T (dimensionless).
    pub threshold: T,
    /// Local gravity magnitude g (m/s²).
    pub gravity_m_s2: T,
}

impl<T: Real> Default for StationarityConfig<T> {
    fn default() -> Self {
        Self {
            sigma_accel_m_s2: nalgebra::convert(0.05),
            sigma_gyro_rad_s: nalgebra::convert(0.01),
            window_samples: 25,
            threshold: nalgebra::convert(10.0),
            gravity_m_s2: nalgebra::convert(9.80665),
        }
    }
}

impl<T: Real> StationarityConfig<T> {
    /// Checks every field; names the bad one.
    pub fn validate(&self) -> Result<(), NavError> {
        for (what, v) in [
            ("sigma_accel_m_s2", self.sigma_accel_m_s2),
            ("sigma_gyro_rad_s", self.sigma_gyro_rad_s),
            ("threshold", self.threshold),
            ("gravity_m_s2", self.gravity_m_s2),
        ] {
            if !(num_traits::Float::is_finite(v) && v > T::zero()) {
                return Err(NavError::InvalidParameter {
                    what,
                    reason: "must be finite and > 0",
                });
            }
        }
        if self.window_samples == 0 || self.window_samples > DETECT_CAPACITY {
            return Err(NavError::InvalidParameter {
                what: "window_samples",
                reason: "must be in 1..=256",
            });
        }
        Ok(())
    }
}

/// Per-sample GLRT stationarity detector over a trailing window. Allocation-free.
#[derive(Debug, Clone)]
pub struct StationarityDetector<T: Real> {
    cfg: StationarityConfig<T>,
    // Per stored sample: a_x, a_y, a_z, ‖a‖², ‖ω‖².
    buf: [[T; 5]; DETECT_CAPACITY],
    head: usize,
    n: usize,
    pushes: usize,
    sums: [T; 5],
}

impl<T: Real> StationarityDetector<T> {
    /// A detector with the given thresholds.
    pub fn new(cfg: StationarityConfig<T>) -> Result<Self, NavError> {
        cfg.validate()?;
        Ok(Self {
            cfg,
            buf: [[T::zero(); 5]; DETECT_CAPACITY],
            head: 0,
            n: 0,
            pushes: 0,
            sums: [T::zero(); 5],
        })
    }

    /// Adds one sample (specific force m/s², angular rate rad/s, body frame) and returns the
    /// statistic `T` over the trailing window (partial at the start) and the decision `T < γ`.
    // Ring-buffer indices are taken modulo `window_samples ≤ DETECT_CAPACITY = buf.len()`
    // (checked by `validate` in `new`): every index is in range.
    #[allow(clippy::indexing_slicing)]
    pub fn push(
        &mut self,
        accel_m_s2: &[T; 3],
        gyro_rad_s: &[T; 3],
    ) -> Result<(T, bool), NavError> {
        if !accel_m_s2
            .iter()
            .chain(gyro_rad_s.iter())
            .all(|x| num_traits::Float::is_finite(*x))
        {
            return Err(NavError::NonFinite {
                what: "stationarity input",
                index: self.pushes,
            });
        }
        let [ax, ay, az] = *accel_m_s2;
        let [wx, wy, wz] = *gyro_rad_s;
        let rec = [
            ax,
            ay,
            az,
            ax * ax + ay * ay + az * az,
            wx * wx + wy * wy + wz * wz,
        ];
        // Finite samples whose squared norms (or their window sums) overflow are refused like
        // non-finite ones (|a| ≈ 1e154 m/s² is no measurement), before the state changes.
        let sums_finite = self
            .sums
            .iter()
            .zip(rec.iter())
            .all(|(s, r)| num_traits::Float::is_finite(*s + *r));
        if !sums_finite {
            return Err(NavError::NonFinite {
                what: "stationarity input (squared norm overflows)",
                index: self.pushes,
            });
        }
        let w = self.cfg.window_samples;
        if self.n == w {
            let old = self.buf[self.head];
            for (s, o) in self.sums.iter_mut().zip(old.iter()) {
                *s -= *o;
            }
            self.head = (self.head + 1) % w;
            self.n -= 1;
        }
        self.buf[(self.head + self.n) % w] = rec;
        for (s, r) in self.sums.iter_mut().zip(rec.iter()) {
            *s += *r;
        }
        self.n += 1;
        self.pushes += 1;
        if self.pushes.is_multiple_of(DETECT_CAPACITY) {
            self.sums = [T::zero(); 5];
            for i in 0..self.n {
                let r = self.buf[(self.head + i) % w];
                for (s, v) in self.sums.iter_mut().zip(r.iter()) {
                    *s += *v;
                }
            }
        }
        let t = self.statistic();
        Ok((t, t < self.cfg.threshold))
    }

    fn statistic(&self) -> T {
        let [sx, sy, sz, saa, sww] = self.sums;
        let n = from_usize::<T>(self.n);
        let g = self.cfg.gravity_m_s2;
        let norm = num_traits::Float::sqrt(sx * sx + sy * sy + sz * sz);
        // Σ‖a − g·u‖² ≥ 0 mathematically; clamp the rounding residue.
        let acc = num_traits::Float::max(saa - (g + g) * norm + n * g * g, T::zero());
        let sa2 = self.cfg.sigma_accel_m_s2 * self.cfg.sigma_accel_m_s2;
        let sw2 = self.cfg.sigma_gyro_rad_s * self.cfg.sigma_gyro_rad_s;
        (acc / sa2 + sww / sw2) / n
    }
}

/// Batch detection over a log with a *centred* window: `stat_out[k]`, `mask_out[k]` use the
/// `W` samples around `k` (the first and last `W/2` samples reuse the nearest full window).
// Every slice was checked to have length n above; k < n and k − lag ≥ 0 (k + 1 ≥ w > lag),
// head ≤ tail < n: every index is in range.
#[allow(clippy::indexing_slicing)]
pub fn detect_static<T: Real>(
    accel_m_s2: &[[T; 3]],
    gyro_rad_s: &[[T; 3]],
    cfg: StationarityConfig<T>,
    stat_out: &mut [T],
    mask_out: &mut [bool],
) -> Result<(), NavError> {
    let n = accel_m_s2.len();
    for (what, got) in [
        ("gyro_rad_s", gyro_rad_s.len()),
        ("stat_out", stat_out.len()),
        ("mask_out", mask_out.len()),
    ] {
        if got != n {
            return Err(NavError::LengthMismatch {
                what,
                expected: n,
                got,
            });
        }
    }
    let mut det = StationarityDetector::new(cfg)?;
    if n == 0 {
        return Ok(());
    }
    let w = cfg.window_samples.min(n);
    let lag = (w - 1) / 2;
    for k in 0..n {
        let (t, _) = det
            .push(&accel_m_s2[k], &gyro_rad_s[k])
            .map_err(|_| NavError::NonFinite {
                what: "stationarity input",
                index: k,
            })?;
        if k + 1 >= w {
            stat_out[k - lag] = t;
        }
    }
    // Full windows filled stat_out[w - 1 - lag ..= n - 1 - lag]; for an even W that range is
    // not symmetric (it starts at lag + 1), so the ends are filled from its own first and last
    // entries, not from index `lag`.
    let head = w - 1 - lag;
    let tail = n - 1 - lag;
    let first = stat_out[head];
    let last = stat_out[tail];
    for v in stat_out.iter_mut().take(head) {
        *v = first;
    }
    for v in stat_out.iter_mut().skip(tail + 1) {
        *v = last;
    }
    for (m, t) in mask_out.iter_mut().zip(stat_out.iter()) {
        *m = *t < cfg.threshold;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statistic_matches_the_direct_glrt_formula_and_separates_motion() {
        let cfg = StationarityConfig::<f64> {
            window_samples: 7,
            ..StationarityConfig::default()
        };
        // Deterministic pseudo-noise; motion between samples 300 and 500.
        let n = 800;
        let noise = |k: usize, j: usize| ((k * 7 + j * 13) as f64 * 0.7).sin();
        let accel: std::vec::Vec<[f64; 3]> = (0..n)
            .map(|k| {
                let m = if (300..500).contains(&k) { 2.0 } else { 0.0 };
                [
                    0.02 * noise(k, 0) + m * (k as f64 * 0.3).sin(),
                    0.02 * noise(k, 1),
                    -9.80665 + 0.02 * noise(k, 2),
                ]
            })
            .collect();
        let gyro: std::vec::Vec<[f64; 3]> = (0..n)
            .map(|k| {
                let m = if (300..500).contains(&k) { 0.5 } else { 0.0 };
                [
                    0.005 * noise(k, 3) + m,
                    0.005 * noise(k, 4),
                    0.005 * noise(k, 5),
                ]
            })
            .collect();
        let mut det = StationarityDetector::new(cfg).unwrap();
        for k in 0..n {
            let (t, _) = det.push(&accel[k], &gyro[k]).unwrap();
            // Direct formula over the trailing window.
            let lo = (k + 1).saturating_sub(7);
            let win = &accel[lo..=k];
            let wn = win.len() as f64;
            let mean: [f64; 3] =
                core::array::from_fn(|j| win.iter().map(|a| a[j]).sum::<f64>() / wn);
            let nm = (mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]).sqrt();
            let mut want = 0.0;
            for l in lo..=k {
                let a = accel[l];
                let e: f64 = (0..3)
                    .map(|j| (a[j] - 9.80665 * mean[j] / nm).powi(2))
                    .sum();
                let w2: f64 = gyro[l].iter().map(|x| x * x).sum();
                want += e / 0.05f64.powi(2) + w2 / 0.01f64.powi(2);
            }
            want /= wn;
            assert!(
                (t - want).abs() < 1e-9 * want.max(1.0),
                "k={k}: {t} vs {want}"
            );
        }
        let mut stat = std::vec![0.0; n];
        let mut mask = std::vec![false; n];
        detect_static(&accel, &gyro, cfg, &mut stat, &mut mask).unwrap();
        assert!(mask[..290].iter().all(|&m| m) && mask[510..].iter().all(|&m| m));
        assert!(mask[310..490].iter().all(|&m| !m));
        assert!(detect_static(&accel, &gyro[..5], cfg, &mut stat, &mut mask).is_err());
        let bad = StationarityConfig {
            window_samples: 0,
            ..cfg
        };
        assert!(StationarityDetector::new(bad).is_err());
        assert!(det.push(&[f64::NAN, 0.0, 0.0], &[0.0; 3]).is_err());
    }

    #[test]
    fn ends_of_the_log_take_the_nearest_full_window_for_odd_and_even_windows() {
        // A moving unit (rate 1 rad/s, never static) with a rate that grows along the log:
        // every centred statistic is large and differs from its neighbours, so an end sample
        // left at 0 (static) or filled from the wrong window shows.
        let n = 40;
        let accel: std::vec::Vec<[f64; 3]> = (0..n).map(|_| [0.0, 0.0, -9.80665]).collect();
        let gyro: std::vec::Vec<[f64; 3]> =
            (0..n).map(|k| [1.0 + 0.01 * k as f64, 0.0, 0.0]).collect();
        for w in [4usize, 5, 6, 7, 20] {
            let cfg = StationarityConfig::<f64> {
                window_samples: w,
                ..StationarityConfig::default()
            };
            let mut stat = std::vec![0.0; n];
            let mut mask = std::vec![true; n];
            detect_static(&accel, &gyro, cfg, &mut stat, &mut mask).unwrap();
            assert!(
                mask.iter().all(|&m| !m),
                "W={w}: a moving sample declared static"
            );
            // Direct statistic of the full window ending at sample e (centre e − lag).
            let lag = (w - 1) / 2;
            let full = |e: usize| -> f64 {
                let mut s = 0.0;
                for g in &gyro[e + 1 - w..=e] {
                    s += g.iter().map(|x| x * x).sum::<f64>() / 0.01f64.powi(2);
                }
                s / w as f64
            };
            for (k, &got) in stat.iter().enumerate() {
                let e = (k + lag).clamp(w - 1, n - 1);
                let want = full(e);
                assert!(
                    (got - want).abs() < 1e-9 * want,
                    "W={w} k={k}: {got} vs {want}"
                );
            }
        }
    }
}
