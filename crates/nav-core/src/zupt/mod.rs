//! The 15-state zero-velocity-update (ZUPT) filter and the thermally compensated TCZUPT
//! filter of the thesis (§4.2.2.2, eqs. 8–25; §4.2.3.2, eqs. 29–31).
//!
//! # Model
//! The mechanisation and the error-state kernel are shared with the GNSS/INS filter
//! ([`crate::strapdown`]); here the unit is at rest, so the transport rate is zero.
//!
//! An error-state (closed-loop) Kalman filter runs beside a strapdown navigation solution in
//! the local-level NED frame (Earth rate and WGS-84 normal gravity, [`crate::earth`]). The
//! error state (eq. 8) is
//!
//! `δx = [δr (m, NED), δv (m/s, NED), ψ (rad, NED), δb_a (m/s², body), δb_g (rad/s, body)]`,
//!
//! every component defined as *estimate − truth*, with the attitude error `ψ` defined by
//! `Ĉ_b^n = (I + [ψ×])·C_b^n`. Position is the NED displacement (m) from the frozen initial
//! point: for a unit at rest this is Groves' curvilinear position error scaled by the radii
//! of curvature. The continuous error model (eq. 13; Groves 2013, §14.2.4, local-navigation
//! frame, transport rate dropped because the unit is at rest) is
//!
//! ```text
//! δṙ  = δv
//! δv̇  = (2g/r_eS)·δr_D·e_D − 2[ω_ie×]·δv − [(Ĉf̂)×]·ψ − Ĉ·δb_a  − Ĉ·η_a
//! ψ̇   = −[ω_ie×]·ψ − Ĉ·δb_g − Ĉ·η_g
//! δḃ_a = η_ba,   δḃ_g = η_bg                                      (eqs. 10, 12)
//! ```
//!
//! discretised as `Φ ≈ I + F·Ts` (eq. 16, or with the second-order term `(F·Ts)²/2`,
//! [`Discretisation`]) and `Γ = G·Q·Gᵀ·Ts` (eq. 18) with `Q = diag(σ_VRW², σ_ARW², σ_ABI²,
//! σ_GBI²)` (eqs. 22–25). Because `Q` is isotropic within each group, `Ĉ·σ²I·Ĉᵀ = σ²I` and
//! `Γ` is diagonal. `Φ·P·Φᵀ` is evaluated block-wise: only the δr, δv and ψ block rows of
//! `Φ` differ from the identity, so `P⁻` needs `(Φ·x)[0..9]` of the 15 columns of `P` and of
//! the 9 rows of `(Φ·P)[0..9, :]` (≈ 960 multiply-adds, skipping the zero diagonals of the
//! skew blocks) instead of two dense 15×15 products (6750).
//!
//! Note on σ_GBI: the thesis (eq. 25) puts the bias instability (rad/s) straight on the
//! diagonal of Q, so the bias random walk has the numerical PSD σ_GBI² (read as
//! (rad/s)²/s). We keep that convention so that the thesis' Tables 3–6 plug in unchanged.
//!
//! # Measurement (eqs. 19–21)
//! Every `update_interval_s` (thesis: 1 s) of stationary data, the nine measurements
//! `z = [r̂ − r₀, v̂ − 0, ψ(q̂ ⊗ q₀*)]` compare the solution with the frozen initial position,
//! zero velocity and frozen initial attitude; `H = [I₉ 0]`. The gain uses a Cholesky
//! factorisation of `S = H·P·Hᵀ + R` (failure → [`NavError::NotPositiveDefinite`]); with
//! `H = [I₉ 0]`, `H·P` and `S` are read off `P` without products. The covariance update is the
//! Joseph form of the shared kernel `strapdown::joseph_update` (the GNSS/INS filter's), expanded
//! as `P − K·HP − (K·HP)ᵀ + K·S·Kᵀ` and written exactly symmetric: ≈ 4.3k multiply-adds for
//! M = 9 instead of three 15×9×15 products (≈ 6.1k). The estimated errors are fed back into the
//! solution and the bias estimates, and the error state is reset to zero.
//!
//! # TCZUPT (eqs. 29–31)
//! In [`Mode::Tczupt`] the gyro input is raw (not thermally calibrated) and the gyro-bias
//! estimate is propagated with `b̂_g ← b̂_g + (∂b/∂T)·(dT/dt)·Ts` (eq. 31 with `F_g = 0`),
//! `∂b/∂T` from a [`BiasTemperatureDerivative`] (e.g. the MLP engine's analytic derivative)
//! and `dT/dt` from the sliding-window least-squares slope of the die temperature
//! ([`SlopeEstimator`]); σ'_GBI is configured smaller than the raw bias instability (Table 5).
//!
//! # Stationarity
//! Updates are applied only on samples flagged stationary; [`StationarityDetector`] is the
//! generalised likelihood ratio test (SHOE) with documented default thresholds. When a new
//! rest period starts after motion, the position and attitude references are re-frozen at
//! the current solution (the unit may have been moved); zero velocity stays absolute.
mod detect;
mod filter;
mod init;
mod slope;

#[cfg(test)]
use crate::strapdown::skew as filter_test_skew;
pub use detect::{detect_static, StationarityConfig, StationarityDetector, DETECT_CAPACITY};
pub use filter::{BatchInput, BatchOutput, BatchSummary, ZuptFilter};
pub use init::{HeadingSource, Levelling};
pub use slope::{SlopeEstimator, SLOPE_CAPACITY};

use crate::scalar::lit;
use crate::{NavError, Real};
use nalgebra::Vector3;

/// Number of error states (eq. 8).
pub const N_STATES: usize = crate::strapdown::N_STATES;
/// Number of ZUPT measurements (position, velocity, attitude).
pub const N_MEAS: usize = 9;

/// Which filter of the thesis runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Classic: the gyro input is already thermally calibrated; the bias is a random walk
    /// (eq. 12). The thesis calls this filter "standard ZUPT"; Python accepts `"zupt"` for it
    /// beside the canonical `"classic"`.
    #[default]
    Classic,
    /// TCZUPT: raw gyro input; the bias also follows the temperature model (eqs. 29–31).
    Tczupt,
}

pub use crate::strapdown::Discretisation;

/// The four process-noise parameters of eqs. (22)–(25), SI units in the field names (same
/// fields as the Python `uasnav.noise.FilterNoise`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProcessNoise<T> {
    /// Velocity random walk σ_VRW (m/s/√s): accelerometer white noise, Q(1..3).
    pub sigma_vrw_m_s_sqrt_s: T,
    /// Angle random walk σ_ARW (rad/√s): gyro white noise, Q(4..6).
    pub sigma_arw_rad_sqrt_s: T,
    /// Accelerometer bias instability σ_ABI (m/s²), Q(7..9).
    pub sigma_abi_m_s2: T,
    /// Gyro bias instability σ_GBI (rad/s), Q(10..12); σ'_GBI for TCZUPT.
    pub sigma_gbi_rad_s: T,
}

impl<T: Real> ProcessNoise<T> {
    /// The thesis' standard-ZUPT values, Tables 3–4 (CRS05-02 gyros, MS8010 accelerometers):
    /// σ_ARW = 3.18 deg/√h, σ_GBI = 1.5e-4 deg/s, σ_VRW = 0.05 m/s/√h, σ_ABI = 2 m/s/h.
    pub fn thesis_zupt() -> Self {
        let deg = core::f64::consts::PI / 180.0;
        Self {
            sigma_vrw_m_s_sqrt_s: lit(0.05 / 60.0),
            sigma_arw_rad_sqrt_s: lit(3.18 * deg / 60.0),
            sigma_abi_m_s2: lit(2.0 / 3600.0),
            sigma_gbi_rad_s: lit(1.5e-4 * deg),
        }
    }

    /// The thesis' TCZUPT values, Tables 5–6: as [`Self::thesis_zupt`] but σ'_GBI = 5e-4 deg/s.
    pub fn thesis_tczupt() -> Self {
        Self {
            sigma_gbi_rad_s: lit(5e-4 * core::f64::consts::PI / 180.0),
            ..Self::thesis_zupt()
        }
    }
}

/// Configuration of [`ZuptFilter`]; every field names its unit. `Copy`, so Python and tests
/// can build variants with struct-update syntax.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZuptConfig<T> {
    /// ZUPT or TCZUPT.
    pub mode: Mode,
    /// Process noise (eqs. 22–25).
    pub noise: ProcessNoise<T>,
    /// Measurement noise σ of the frozen-position measurement (m), R(1..3).
    pub meas_std_position_m: T,
    /// Measurement noise σ of the zero-velocity measurement (m/s), R(4..6).
    pub meas_std_velocity_m_s: T,
    /// Measurement noise σ of the frozen-attitude measurement (rad), R(7..9).
    pub meas_std_attitude_rad: T,
    /// Time between ZUPT updates (s); the thesis uses 1 s.
    pub update_interval_s: T,
    /// Initial σ of the position error (m).
    pub init_std_position_m: T,
    /// Initial σ of the velocity error (m/s).
    pub init_std_velocity_m_s: T,
    /// Initial σ of the attitude error (rad).
    pub init_std_attitude_rad: T,
    /// Initial σ of the accelerometer bias (m/s²).
    pub init_std_accel_bias_m_s2: T,
    /// Initial σ of the gyro bias (rad/s).
    pub init_std_gyro_bias_rad_s: T,
    /// Geodetic latitude (rad) of the (frozen) position.
    pub latitude_rad: T,
    /// Height above the WGS-84 ellipsoid (m).
    pub height_m: T,
    /// Transition-matrix discretisation.
    pub discretisation: Discretisation,
    /// Window (s) of the least-squares dT/dt slope (TCZUPT).
    pub temp_slope_window_s: T,
}

impl<T: Real> Default for ZuptConfig<T> {
    fn default() -> Self {
        Self {
            mode: Mode::Classic,
            noise: ProcessNoise::thesis_zupt(),
            meas_std_position_m: lit(1e-3),
            meas_std_velocity_m_s: lit(1e-3),
            meas_std_attitude_rad: lit(1e-4),
            update_interval_s: T::one(),
            init_std_position_m: lit(1e-3),
            init_std_velocity_m_s: lit(1e-3),
            init_std_attitude_rad: lit(1e-4),
            init_std_accel_bias_m_s2: lit(0.05),
            init_std_gyro_bias_rad_s: lit(1e-3),
            latitude_rad: lit(45.0_f64.to_radians()),
            height_m: T::zero(),
            discretisation: Discretisation::FirstOrder,
            temp_slope_window_s: lit(30.0),
        }
    }
}

impl<T: Real> ZuptConfig<T> {
    /// Checks every field (finite, positive where a σ or an interval); names the bad one.
    pub fn validate(&self) -> Result<(), NavError> {
        let pos: [(&'static str, T); 14] = [
            ("sigma_vrw_m_s_sqrt_s", self.noise.sigma_vrw_m_s_sqrt_s),
            ("sigma_arw_rad_sqrt_s", self.noise.sigma_arw_rad_sqrt_s),
            ("sigma_abi_m_s2", self.noise.sigma_abi_m_s2),
            ("sigma_gbi_rad_s", self.noise.sigma_gbi_rad_s),
            ("meas_std_position_m", self.meas_std_position_m),
            ("meas_std_velocity_m_s", self.meas_std_velocity_m_s),
            ("meas_std_attitude_rad", self.meas_std_attitude_rad),
            ("update_interval_s", self.update_interval_s),
            ("init_std_position_m", self.init_std_position_m),
            ("init_std_velocity_m_s", self.init_std_velocity_m_s),
            ("init_std_attitude_rad", self.init_std_attitude_rad),
            ("init_std_accel_bias_m_s2", self.init_std_accel_bias_m_s2),
            ("init_std_gyro_bias_rad_s", self.init_std_gyro_bias_rad_s),
            ("temp_slope_window_s", self.temp_slope_window_s),
        ];
        for (what, v) in pos {
            if !(num_traits::Float::is_finite(v) && v > T::zero()) {
                return Err(NavError::InvalidParameter {
                    what,
                    reason: "must be finite and > 0",
                });
            }
        }
        if !num_traits::Float::is_finite(self.latitude_rad)
            || num_traits::Float::abs(self.latitude_rad) > lit(core::f64::consts::FRAC_PI_2)
        {
            return Err(NavError::InvalidParameter {
                what: "latitude_rad",
                reason: "must be finite and within ±π/2",
            });
        }
        // "Within the bound" is false for NaN too.
        let height_ok = num_traits::Float::abs(self.height_m) <= lit(crate::earth::MAX_HEIGHT_M);
        if !height_ok {
            return Err(NavError::InvalidParameter {
                what: "height_m",
                reason: "must be finite and within ±100 km of the ellipsoid",
            });
        }
        Ok(())
    }
}

/// Source of the gyro-bias temperature derivative `∂b/∂T` (rad/s/°C, body axes) for TCZUPT.
///
/// Implemented for closures `FnMut(usize, T) -> Vector3<T>` (sample index, die temperature
/// °C), for a per-sample table ([`DerivativeTable`]) and for [`NoDerivative`]; the MLP engine
/// implements it by evaluating its analytic input derivative.
pub trait BiasTemperatureDerivative<T: Real> {
    /// `∂b/∂T` (rad/s/°C) at sample `index` and die temperature `temp_c` (°C).
    fn dbias_dtemp(&mut self, index: usize, temp_c: T) -> Vector3<T>;
}

impl<T: Real, F: FnMut(usize, T) -> Vector3<T>> BiasTemperatureDerivative<T> for F {
    #[inline]
    fn dbias_dtemp(&mut self, index: usize, temp_c: T) -> Vector3<T> {
        self(index, temp_c)
    }
}

/// No thermal model (`∂b/∂T = 0`): TCZUPT degenerates to ZUPT with σ'_GBI.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoDerivative;

impl<T: Real> BiasTemperatureDerivative<T> for NoDerivative {
    #[inline]
    fn dbias_dtemp(&mut self, _index: usize, _temp_c: T) -> Vector3<T> {
        Vector3::zeros()
    }
}

/// `∂b/∂T` precomputed per sample (rad/s/°C), e.g. by a Python thermal model evaluated on the
/// whole temperature series; indices past the end give zero.
#[derive(Debug, Clone, Copy)]
pub struct DerivativeTable<'a, T>(pub &'a [[T; 3]]);

impl<T: Real> BiasTemperatureDerivative<T> for DerivativeTable<'_, T> {
    #[inline]
    fn dbias_dtemp(&mut self, index: usize, _temp_c: T) -> Vector3<T> {
        self.0
            .get(index)
            .map_or_else(Vector3::zeros, |d| Vector3::from(*d))
    }
}

#[cfg(test)]
mod tests;
