//! Loosely coupled GNSS/INS error-state Kalman filter for flight (thesis §4.1.4), on the same
//! mechanisation and error-state kernel as the ZUPT filter ([`crate::strapdown`]).
//!
//! # Navigation solution
//! Position is geodetic WGS-84 latitude, longitude (rad) and ellipsoidal height (m), always
//! in `f64`: latitude in `f32` radians has a step of about 0.4 m, so a 100 Hz step at 5 m/s
//! would not move it. Velocity (m/s, NED), attitude (body → NED quaternion) and the biases run
//! in the filter's scalar `T` (`f32` or `f64`). The mechanisation (Groves 2013, §5.4, first
//! order) is
//!
//! ```text
//! q  ← exp(−ω_in·Ts/2) ⊗ q ⊗ exp((ω̃ − b̂_g)·Ts/2)
//! v  ← v + (Ĉ(f̃ − b̂_a) + g(φ, h) − (2ω_ie + ω_en) × v)·Ts
//! h  ← h − v̄_D·Ts,  φ ← φ + v̄_N·Ts/(R_N + h),  λ ← λ + v̄_E·Ts/((R_E + h)·cos φ)
//! ```
//!
//! with `ω_en = [v_E/(R_E+h), −v_N/(R_N+h), −v_E·tan φ/(R_E+h)]` (transport rate) and `v̄` the
//! mean of the old and new velocity.
//!
//! # Error state and measurements
//! The 15 error states are those of [`crate::strapdown`] (`δr` in metres NED:
//! `δr_N = (R_N+h)·δφ`, `δr_E = (R_E+h)·cos φ·δλ`, `δr_D = −δh`). Every innovation is
//! *predicted − measured*, `z = H·δx + noise`, and `δx = K·z` is subtracted from the solution.
//!
//! * GNSS position and velocity (6 rows) at the antenna, `r_a = r + Ĉ·l`,
//!   `v_a = v + Ĉ(ω̂ × l)` with the lever arm `l` (m, body):
//!   `H_r = [I, 0, −[(Ĉl)×], 0, 0]`, `H_v = [0, I, −[(Ĉ(ω̂×l))×], 0, Ĉ[l×]]`; `R` from the
//!   fix's reported horizontal, vertical and speed accuracies (floored by the configuration).
//!   A fix is time-aligned to the IMU sample by its own velocity.
//! * Barometric height (1 row, `H = −e_D` on δr): `z = ĥ − (h_baro + o)`, the offset `o`
//!   between the barometric and the ellipsoidal height tracked by a first-order filter of the
//!   GNSS − baro difference (time constant `baro_offset_time_constant_s`) while GNSS is used,
//!   frozen during outages — so in an outage the vertical channel stays bounded. The barometer
//!   is used only after 1 s without a GNSS fix (while GNSS is used its height is what the
//!   offset is learnt from), with `R = σ_baro² + var(o)`. The offset is not a filter state (the
//!   filter keeps the 15 states): its error is constant over an outage, so after each baro
//!   update the height variance is floored at var(o), which averaging cannot remove.
//! * Zero velocity and zero angular rate (6 rows) whenever the static detector flags the
//!   sample (every `zupt_interval_s`): `z = [v̂, ω̂ − Ĉᵀω_ie]`, `H = [0 I 0 0 0; 0 0 0 0 −I]`.
//!   The caller decides what is static (on the ground: a hovering aircraft is not).
//! * Heading at start-up: magnetometer heading updates for the first `heading_aiding_s`
//!   seconds, `z = atan2(m_E, m_N) − D` with `m = Ĉ·m̃_b`,
//!   `H_ψ = [−m_N m_D/|m_h|², −m_E m_D/|m_h|², 1]`, the heading variance floored at
//!   `mag_heading_std_rad²` (the error is mostly a common bias); without a magnetometer the yaw is reset
//!   once to the GNSS course when the ground speed first exceeds `course_min_speed_m_s`.
//!
//! # TCZUPT in flight
//! In [`Mode::Tczupt`] the gyro input is raw and the gyro-bias estimate follows
//! `b̂_g ← b̂_g + (∂b/∂T)·(dT/dt)·Ts` (thesis eqs. 29–31) exactly as in the ZUPT filter.
//!
//! # Integrity (thesis §4.1.4.4)
//! Fault detection and exclusion acts on **whole GNSS fixes**: a loosely coupled filter sees a
//! position/velocity solution, not satellites, so it cannot exclude a single satellite. A fix
//! is excluded when its normalised innovation squared exceeds `gate_chi2` (χ², 6 degrees of
//! freedom) or when the averaged innovation of the last `window_fixes` accepted fixes plus
//! this one does (an AIME-style test, Diesel & Dunn 1996, which catches slow ramps the
//! snapshot test misses).
//!
//! Protection levels bound the position error at integrity risk set by the caller's
//! multipliers:
//!
//! ```text
//! HPL = k_H·√λ_max(P_NE) + b_H,   VPL = k_V·√P_DD + b_V
//! ```
//!
//! The fault-free term uses the covariance; the fault term `b` is the largest position error
//! an undetected fault can leave: for a fault `f` on one fix the innovation test sees
//! `fᵀS⁻¹f ≤ λ` (λ the non-centrality at which the χ² test misses with the allotted
//! probability), and the state moves by `K·f`, so `b_H = √λ·√λ_max(A_H·K·S·Kᵀ·A_Hᵀ)`; for a
//! fault sustained over the window, `W·fᵀS⁻¹f ≤ λ` and the filter may follow it fully, so
//! `b_H ≥ √(λ/W)·√λ_max(S_NE)`. The larger of the two is used; it is held between fixes and
//! through outages.
//!
//! Neither bounds a slow ramp, which the filter follows with a constant lag (constant
//! innovations, error growing as `r·t`). A solution-separation monitor against a reference
//! free of GNSS *positions* does: the filter's antenna position at the first used fix moved
//! by the integral of the GNSS velocities (see `separation.rs` for the test and the bound).
//! When the separation exceeds its threshold the fix is still used but reported as
//! [`FixStatus::SeparationAlert`]; its protection levels are folded into `b_H`, `b_V`.
//!
//! After `reset_after_exclusions` consecutive excluded fixes (default 50, 10 s at 5 Hz) the
//! filter cannot tell a long GNSS fault from its own divergence; it re-initialises position and
//! velocity on the fix and reports the reset ([`FixStatus::Reset`]).
//!
//! # Real logs
//! An IMU interval longer than five nominal sample periods is a logging gap: it is bridged with
//! the last sample before it (the sample after a gap averages over an unknown part of it).
mod filter;
mod separation;
mod stream;

pub use filter::{
    FixStatus, InsBatchInput, InsBatchOutput, InsBatchSummary, InsFilter, MagnetometerAiding,
};
pub use stream::{GnssFix, InsStream, StreamCounts, StreamSolution, PENDING_FIXES};

use crate::scalar::lit;
pub use crate::strapdown::Discretisation;
pub use crate::zupt::{Mode, ProcessNoise};
use crate::{NavError, Real};

/// Capacity (fixes) of the averaged-innovation window.
pub const WINDOW_CAPACITY: usize = 32;

/// Configuration of [`InsFilter`]; every field names its unit. `Copy`, so variants are built
/// with struct-update syntax.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InsConfig<T> {
    /// Classic (calibrated gyro, random-walk bias) or thermally compensated
    /// (`Tczupt`: raw gyro, bias follows ∂b/∂T·dT/dt).
    pub mode: Mode,
    /// IMU process noise (σ_VRW, σ_ARW, σ_ABI, σ_GBI; eqs. 22–25).
    pub noise: ProcessNoise<T>,
    /// Transition-matrix discretisation.
    pub discretisation: Discretisation,
    /// Initial σ of roll and pitch (rad).
    pub init_std_tilt_rad: T,
    /// Initial σ of the heading (rad).
    pub init_std_heading_rad: T,
    /// Initial σ of the accelerometer bias (m/s²).
    pub init_std_accel_bias_m_s2: T,
    /// Initial σ of the gyro bias (rad/s).
    pub init_std_gyro_bias_rad_s: T,
    /// GNSS antenna position relative to the IMU (m, body frame).
    pub lever_arm_m: [T; 3],
    /// Floor on the reported horizontal/vertical position accuracy (m).
    pub gnss_min_std_position_m: T,
    /// Floor on the reported speed accuracy (m/s).
    pub gnss_min_std_velocity_m_s: T,
    /// σ of the barometric height (m).
    pub baro_std_m: T,
    /// Time constant (s) of the baro-to-ellipsoid offset filter.
    pub baro_offset_time_constant_s: T,
    /// σ of the zero-velocity pseudo-measurement (m/s).
    pub zupt_std_velocity_m_s: T,
    /// σ of the zero-angular-rate pseudo-measurement (rad/s).
    pub zaru_std_rad_s: T,
    /// Time between ZUPT/ZARU updates while static (s).
    pub zupt_interval_s: T,
    /// σ of the magnetometer heading (rad).
    pub mag_heading_std_rad: T,
    /// Magnetometer heading aiding lasts this long after the start (s).
    pub heading_aiding_s: T,
    /// Time between magnetometer heading updates (s).
    pub mag_interval_s: T,
    /// Magnetic declination (rad, east positive).
    pub declination_rad: T,
    /// Ground speed above which the GNSS course may initialise the heading (m/s).
    pub course_min_speed_m_s: T,
    /// χ² threshold (6 degrees of freedom) of the per-fix and the window tests.
    pub gate_chi2: T,
    /// Non-centrality λ of the χ² test at the allotted missed-detection probability.
    pub lambda_undetected: T,
    /// Fixes in the averaged-innovation window (1..=[`WINDOW_CAPACITY`]).
    pub window_fixes: usize,
    /// Horizontal fault-free multiplier `k_H` (on the major-axis σ).
    pub k_horizontal: T,
    /// Vertical fault-free multiplier `k_V` (on σ_D).
    pub k_vertical: T,
    /// Window (s) of the least-squares dT/dt slope (TCZUPT, and the classic filter's
    /// thermal bias wander).
    pub temp_slope_window_s: T,
    /// Classic filter only: the gyro bias's thermal wander, modelled as a random walk *in
    /// temperature* (rad/s/√°C): with the die temperature given, each step adds
    /// σ²·|dT/dt|·Δt to the gyro-bias variance (nothing while the temperature is constant).
    /// Without it an uncompensated bias following a warming die (≈ 2·10⁻⁴ rad/s/°C for a
    /// consumer MEMS gyro) outruns the σ_GBI random walk, the heading error grows beyond its
    /// σ and sound GNSS fixes are excluded at the next acceleration. 0 = off.
    pub sigma_gbt_rad_s_sqrt_c: T,
    /// Consecutive excluded fixes after which the filter re-initialises on GNSS (0 = never).
    pub reset_after_exclusions: usize,
    /// Horizontal false-alert multiplier of the solution-separation test (χ²₂ threshold
    /// `k²`, on the normalised N/E separation): `√(−2 ln P_FA)`.
    pub separation_k_h: T,
    /// Vertical false-alert multiplier of the solution-separation test (on σ_D).
    pub separation_k_v: T,
}

impl<T: Real> Default for InsConfig<T> {
    /// A consumer MEMS IMU (σ_ARW 0.3 deg/√h, σ_VRW 0.1 m/s/√h, bias instabilities 10 deg/h
    /// and 1 mg·s^-½ as random-walk PSDs) and integrity at P_FA = 1e-5, P_MD = 1e-3 (χ²₆
    /// threshold 33.1 → λ = 71.2; k_H = 6.0 and k_V = 5.33 for a 1e-7 fault-free risk).
    fn default() -> Self {
        let deg = core::f64::consts::PI / 180.0;
        Self {
            mode: Mode::Classic,
            noise: ProcessNoise {
                sigma_vrw_m_s_sqrt_s: lit(0.1 / 60.0),
                sigma_arw_rad_sqrt_s: lit(0.3 * deg / 60.0),
                sigma_abi_m_s2: lit(1e-4),
                sigma_gbi_rad_s: lit(1e-5),
            },
            discretisation: Discretisation::FirstOrder,
            init_std_tilt_rad: lit(2.0 * deg),
            init_std_heading_rad: lit(10.0 * deg),
            init_std_accel_bias_m_s2: lit(0.1),
            init_std_gyro_bias_rad_s: lit(0.2 * deg),
            lever_arm_m: [T::zero(); 3],
            gnss_min_std_position_m: lit(0.5),
            gnss_min_std_velocity_m_s: lit(0.05),
            baro_std_m: lit(1.0),
            baro_offset_time_constant_s: lit(100.0),
            zupt_std_velocity_m_s: lit(0.02),
            zaru_std_rad_s: lit(1e-3),
            zupt_interval_s: lit(0.2),
            mag_heading_std_rad: lit(5.0 * deg),
            heading_aiding_s: lit(30.0),
            mag_interval_s: lit(0.2),
            declination_rad: T::zero(),
            course_min_speed_m_s: lit(5.0),
            gate_chi2: lit(33.1),
            lambda_undetected: lit(71.2),
            window_fixes: 10,
            k_horizontal: lit(6.0),
            k_vertical: lit(5.33),
            temp_slope_window_s: lit(30.0),
            sigma_gbt_rad_s_sqrt_c: T::zero(),
            reset_after_exclusions: 50,
            separation_k_h: lit(4.80),
            separation_k_v: lit(4.42),
        }
    }
}

impl<T: Real> InsConfig<T> {
    /// Checks every field (finite, positive where a σ, an interval or a threshold); names
    /// the bad one.
    pub fn validate(&self) -> Result<(), NavError> {
        let pos: [(&'static str, T); 24] = [
            ("sigma_vrw_m_s_sqrt_s", self.noise.sigma_vrw_m_s_sqrt_s),
            ("sigma_arw_rad_sqrt_s", self.noise.sigma_arw_rad_sqrt_s),
            ("sigma_abi_m_s2", self.noise.sigma_abi_m_s2),
            ("sigma_gbi_rad_s", self.noise.sigma_gbi_rad_s),
            ("init_std_tilt_rad", self.init_std_tilt_rad),
            ("init_std_heading_rad", self.init_std_heading_rad),
            ("init_std_accel_bias_m_s2", self.init_std_accel_bias_m_s2),
            ("init_std_gyro_bias_rad_s", self.init_std_gyro_bias_rad_s),
            ("gnss_min_std_position_m", self.gnss_min_std_position_m),
            ("gnss_min_std_velocity_m_s", self.gnss_min_std_velocity_m_s),
            ("baro_std_m", self.baro_std_m),
            (
                "baro_offset_time_constant_s",
                self.baro_offset_time_constant_s,
            ),
            ("zupt_std_velocity_m_s", self.zupt_std_velocity_m_s),
            ("zaru_std_rad_s", self.zaru_std_rad_s),
            ("zupt_interval_s", self.zupt_interval_s),
            ("mag_heading_std_rad", self.mag_heading_std_rad),
            ("mag_interval_s", self.mag_interval_s),
            ("course_min_speed_m_s", self.course_min_speed_m_s),
            ("gate_chi2", self.gate_chi2),
            ("lambda_undetected", self.lambda_undetected),
            ("k_horizontal", self.k_horizontal),
            ("k_vertical", self.k_vertical),
            ("separation_k_h", self.separation_k_h),
            ("separation_k_v", self.separation_k_v),
        ];
        for (what, v) in pos {
            if !(num_traits::Float::is_finite(v) && v > T::zero()) {
                return Err(NavError::InvalidParameter {
                    what,
                    reason: "must be finite and > 0",
                });
            }
        }
        let nonneg: [(&'static str, T); 3] = [
            ("heading_aiding_s", self.heading_aiding_s),
            ("temp_slope_window_s", self.temp_slope_window_s),
            ("sigma_gbt_rad_s_sqrt_c", self.sigma_gbt_rad_s_sqrt_c),
        ];
        for (what, v) in nonneg {
            if !(num_traits::Float::is_finite(v) && v >= T::zero()) {
                return Err(NavError::InvalidParameter {
                    what,
                    reason: "must be finite and >= 0",
                });
            }
        }
        crate::error::check_finite("lever_arm_m", &self.lever_arm_m)?;
        crate::error::check_finite("declination_rad", &[self.declination_rad])?;
        if !(1..=WINDOW_CAPACITY).contains(&self.window_fixes) {
            return Err(NavError::InvalidParameter {
                what: "window_fixes",
                reason: "must be in 1..=32",
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
