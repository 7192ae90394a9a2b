//! The GNSS/INS filter: mechanisation step, aiding updates, integrity, and the batch runner.
use nalgebra::{Matrix2, Matrix3, SMatrix, SVector, UnitQuaternion, Vector3};

use super::separation::{self, VelocityReference};
use super::{InsConfig, Mode, WINDOW_CAPACITY};
use crate::attitude::{euler321_to_quat, quat_to_array, quat_to_dcm, quat_to_euler321};
use crate::earth;
use crate::scalar::lit;
use crate::strapdown::{self, skew, ErrorDynamics, Mat15, N_STATES};
use crate::zupt::{BiasTemperatureDerivative, HeadingSource, Levelling, SlopeEstimator};
use crate::{NavError, Real};
// f64 maths (sin, cos, sqrt, abs) without std: the trait's methods; with std the inherent
// ones are used and the import is idle.
#[allow(unused_imports)]
use num_traits::Float as _;

type Vec6<T> = SVector<T, 6>;
type Mat6<T> = SMatrix<T, 6, 6>;

/// The barometer is used only when no GNSS fix was used for this long (s): while GNSS is
/// used, the baro-to-ellipsoid offset is being learnt from it, and using both would count the
/// GNSS height twice.
const BARO_GNSS_GAP_S: f64 = 1.0;

/// An IMU interval longer than this many nominal sample periods is a logging gap.
const MAX_GAP_FACTOR: f64 = 5.0;

/// `|latitude|` beyond which the east channel is refused (cos φ → 0).
const MAX_LATITUDE_RAD: f64 = 1.56; // 89.4°

#[inline(always)]
fn to_f64<T: Real>(x: T) -> f64 {
    num_traits::ToPrimitive::to_f64(&x).unwrap_or(f64::NAN)
}

#[inline(always)]
fn finite3<T: Real>(what: &'static str, index: usize, v: &[T; 3]) -> Result<(), NavError> {
    if v.iter().all(|x| num_traits::Float::is_finite(*x)) {
        Ok(())
    } else {
        Err(NavError::NonFinite { what, index })
    }
}

/// Wraps an angle (rad) into (−π, π].
#[inline]
fn wrap_pi<T: Real>(a: T) -> T {
    num_traits::Float::atan2(num_traits::Float::sin(a), num_traits::Float::cos(a))
}

/// Largest eigenvalue of a symmetric 2×2 matrix (closed form).
#[inline(always)]
fn lambda_max2<T: Real>(m: &Matrix2<T>) -> T {
    let half_tr = (m[(0, 0)] + m[(1, 1)]) * lit::<T>(0.5);
    let d = (m[(0, 0)] - m[(1, 1)]) * lit::<T>(0.5);
    let r = num_traits::Float::sqrt(d * d + m[(0, 1)] * m[(1, 0)]);
    half_tr + r
}

/// What happened to one GNSS fix.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum FixStatus {
    /// Used in a measurement update.
    Used = 0,
    /// Excluded: its own innovation failed the χ² test.
    ExcludedSnapshot = 1,
    /// Excluded: the averaged innovation of the window failed the χ² test.
    ExcludedWindow = 2,
    /// Masked by the caller (simulated outage) or flagged unusable.
    Masked = 3,
    /// Not reached (after the last IMU sample, or before the first).
    Unused = 4,
    /// Excluded, and the filter re-initialised its position and velocity on it after too many
    /// consecutive exclusions.
    Reset = 5,
    /// Used, but the solution separation against the GNSS-velocity reference exceeds its
    /// threshold: a GNSS position fault (e.g. a slow ramp) is detected; a loosely coupled
    /// filter cannot tell which source is wrong, so this is an integrity alert.
    SeparationAlert = 6,
}

/// The GNSS/INS filter (see the module docs for the model). Never allocates.
#[derive(Debug, Clone)]
pub struct InsFilter<T: Real> {
    cfg: InsConfig<T>,
    /// The attitude quaternion whose DCM is `dcm` (a cache: a step's new DCM is the next
    /// step's old one; any other change of `q` is detected by comparing).
    dcm_q: UnitQuaternion<T>,
    dcm: Matrix3<T>,
    /// Latitude (rad), longitude (rad), ellipsoidal height (m): f64 always.
    lat: f64,
    lon: f64,
    h: f64,
    vel: Vector3<T>,
    q: UnitQuaternion<T>,
    ba: Vector3<T>,
    bg: Vector3<T>,
    p: Mat15<T>,
    /// Variance rates of the four noise groups ((unit)²/s).
    q_rate: [T; 4],
    /// Last bias-corrected angular rate (rad/s, body), for the lever arm and ZARU.
    w_hat: Vector3<T>,
    index: usize,
    // Integrity.
    win_z: [Vec6<T>; WINDOW_CAPACITY],
    win_s: [Mat6<T>; WINDOW_CAPACITY],
    win_len: usize,
    win_head: usize,
    bias_h: T,
    bias_v: T,
    last_nis: T,
    earth: EarthCache<T>,
    /// Time since the start (s), for the reference's velocity integral.
    time_s: f64,
    /// GNSS-velocity reference of the solution-separation monitor.
    sep: VelocityReference,
}

/// Earth quantities at a reference point, refreshed when the position moves by more than
/// [`EARTH_REFRESH_RAD`] in latitude or [`EARTH_REFRESH_M`] in height: over such a step the
/// radii change by < 1e-6 relative and gravity by < 3e-6 m/s² (a 60 s outage: < 6 mm).
#[derive(Debug, Clone, Copy)]
struct EarthCache<T> {
    lat: f64,
    h: f64,
    cos_lat: f64,
    tan_lat: f64,
    /// Meridian and transverse radii (m).
    rn: f64,
    re: f64,
    w_ie: Vector3<T>,
    gravity: T,
    grav_grad: T,
}

/// Latitude change (rad, ≈ 6 m) that refreshes the Earth quantities.
const EARTH_REFRESH_RAD: f64 = 1e-6;
/// Height change (m) that refreshes the Earth quantities.
const EARTH_REFRESH_M: f64 = 1.0;

impl<T: Real> EarthCache<T> {
    fn at(lat: f64, h: f64) -> Self {
        let (sl, cl) = (lat.sin(), lat.cos());
        // Radii of curvature (Groves eqs. 2.105–2.106) from one sin.
        let d = 1.0 - earth::WGS84_E2 * sl * sl;
        let re = earth::WGS84_A / d.sqrt();
        let rn = re * (1.0 - earth::WGS84_E2) / d;
        let g = earth::normal_gravity(lat, h);
        Self {
            lat,
            h,
            cos_lat: cl,
            tan_lat: sl / cl,
            rn,
            re,
            w_ie: Vector3::new(
                lit::<T>(earth::OMEGA_IE * cl),
                T::zero(),
                lit::<T>(-earth::OMEGA_IE * sl),
            ),
            gravity: lit(g),
            grav_grad: lit(2.0 * g / earth::geocentric_radius(lat)),
        }
    }
}

impl<T: Real> InsFilter<T> {
    /// A filter at latitude `lat_rad`, longitude `lon_rad` (rad), ellipsoidal height
    /// `height_m` (m), velocity `vel_ned_m_s` (m/s, NED) and attitude `q` (body → NED), with
    /// initial position σ `std_position_m` (m, N/E/D) and velocity σ `std_velocity_m_s`
    /// (m/s); the other initial σ come from the configuration.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        config: InsConfig<T>,
        lat_rad: f64,
        lon_rad: f64,
        height_m: f64,
        vel_ned_m_s: Vector3<T>,
        q: UnitQuaternion<T>,
        std_position_m: [T; 3],
        std_velocity_m_s: [T; 3],
    ) -> Result<Self, NavError> {
        config.validate()?;
        if !(lat_rad.is_finite() && lat_rad.abs() <= MAX_LATITUDE_RAD) {
            return Err(NavError::InvalidParameter {
                what: "latitude",
                reason:
                    "must be finite and within ±89.4° (the east channel is singular at the poles)",
            });
        }
        if !(lon_rad.is_finite() && height_m.abs() <= earth::MAX_HEIGHT_M) {
            return Err(NavError::InvalidParameter {
                what: "longitude/height",
                reason: "must be finite, height within ±100 km",
            });
        }
        crate::error::check_finite("velocity", vel_ned_m_s.as_slice())?;
        crate::error::check_finite("attitude", q.coords.as_slice())?;
        crate::error::check_finite("std_position_m", &std_position_m)?;
        crate::error::check_finite("std_velocity_m_s", &std_velocity_m_s)?;
        let sq = |x: T| x * x;
        let mut p = Mat15::zeros();
        for i in 0..3 {
            p[(i, i)] = sq(std_position_m[i]);
            p[(3 + i, 3 + i)] = sq(std_velocity_m_s[i]);
            p[(9 + i, 9 + i)] = sq(config.init_std_accel_bias_m_s2);
            p[(12 + i, 12 + i)] = sq(config.init_std_gyro_bias_rad_s);
        }
        p[(6, 6)] = sq(config.init_std_tilt_rad);
        p[(7, 7)] = sq(config.init_std_tilt_rad);
        p[(8, 8)] = sq(config.init_std_heading_rad);
        let n = config.noise;
        Ok(Self {
            lat: lat_rad,
            lon: lon_rad,
            h: height_m,
            vel: vel_ned_m_s,
            q,
            ba: Vector3::zeros(),
            bg: Vector3::zeros(),
            p,
            q_rate: [
                sq(n.sigma_vrw_m_s_sqrt_s),
                sq(n.sigma_arw_rad_sqrt_s),
                sq(n.sigma_abi_m_s2),
                sq(n.sigma_gbi_rad_s),
            ],
            w_hat: Vector3::zeros(),
            index: 0,
            win_z: [Vec6::zeros(); WINDOW_CAPACITY],
            win_s: [Mat6::zeros(); WINDOW_CAPACITY],
            win_len: 0,
            win_head: 0,
            bias_h: T::zero(),
            bias_v: T::zero(),
            last_nis: T::zero(),
            earth: EarthCache::at(lat_rad, height_m),
            time_s: 0.0,
            sep: VelocityReference {
                first_t: f64::NAN,
                ..VelocityReference::default()
            },
            cfg: config,
            dcm_q: q,
            dcm: quat_to_dcm(&q),
        })
    }

    /// Sets the bias estimates (m/s² and rad/s, body), e.g. a turn-on gyro bias from zeroing.
    pub fn set_biases(&mut self, accel_m_s2: Vector3<T>, gyro_rad_s: Vector3<T>) {
        self.ba = accel_m_s2;
        self.bg = gyro_rad_s;
    }

    /// Latitude (rad), longitude (rad), ellipsoidal height (m).
    #[inline]
    pub fn position(&self) -> [f64; 3] {
        [self.lat, self.lon, self.h]
    }

    /// Velocity (m/s, NED).
    #[inline]
    pub fn velocity_m_s(&self) -> Vector3<T> {
        self.vel
    }

    /// Attitude (body → NED).
    #[inline]
    pub fn attitude(&self) -> &UnitQuaternion<T> {
        &self.q
    }

    /// Gyro bias estimate (rad/s, body).
    #[inline]
    pub fn gyro_bias_rad_s(&self) -> Vector3<T> {
        self.bg
    }

    /// Accelerometer bias estimate (m/s², body).
    #[inline]
    pub fn accel_bias_m_s2(&self) -> Vector3<T> {
        self.ba
    }

    /// Error covariance (order δr, δv, ψ, δb_a, δb_g; SI).
    #[inline]
    pub fn covariance(&self) -> &Mat15<T> {
        &self.p
    }

    /// NIS of the latest GNSS fix tested (χ² with 6 degrees of freedom when consistent).
    #[inline]
    pub fn last_nis(&self) -> T {
        self.last_nis
    }

    /// Horizontal and vertical protection levels (m), see the module docs.
    pub fn protection_levels(&self) -> (T, T) {
        let phh = self.p.fixed_view::<2, 2>(0, 0).into_owned();
        let sh = num_traits::Float::sqrt(num_traits::Float::max(lambda_max2(&phh), T::zero()));
        let sv = num_traits::Float::sqrt(self.p[(2, 2)]);
        (
            self.cfg.k_horizontal * sh + self.bias_h,
            self.cfg.k_vertical * sv + self.bias_v,
        )
    }

    /// One mechanisation and covariance step over `dt_s` (s) with gyro `gyro_rad_s` (rad/s,
    /// body) and specific force `accel_m_s2` (m/s², body) held over the step, and the
    /// deterministic gyro-bias rate `dbias_dt_rad_s2` (rad/s², eq. 31; zero for the classic
    /// filter). Errors on non-finite input (state unchanged) and on a non-finite solution.
    pub fn predict(
        &mut self,
        gyro_rad_s: &[T; 3],
        accel_m_s2: &[T; 3],
        dt_s: T,
        dbias_dt_rad_s2: &Vector3<T>,
    ) -> Result<(), NavError> {
        finite3("gyro_rad_s", self.index, gyro_rad_s)?;
        finite3("accel_m_s2", self.index, accel_m_s2)?;
        if !(num_traits::Float::is_finite(dt_s) && dt_s > T::zero()) {
            return Err(NavError::InvalidParameter {
                what: "dt_s",
                reason: "IMU time must be strictly increasing",
            });
        }
        let dt = dt_s;
        self.refresh_earth();
        let e = self.earth;
        let (rn_h, re_h) = (e.rn + self.h, e.re + self.h);
        let w_ie = e.w_ie;
        let w_en = Vector3::new(
            self.vel.y / lit::<T>(re_h),
            -self.vel.x / lit::<T>(rn_h),
            -self.vel.y * lit::<T>(e.tan_lat / re_h),
        );
        let w_in = w_ie + w_en;
        let w_hat = Vector3::from(*gyro_rad_s) - self.bg;
        let f_hat = Vector3::from(*accel_m_s2) - self.ba;
        let c = if self.dcm_q == self.q {
            self.dcm
        } else {
            quat_to_dcm(&self.q)
        };
        let q_nav = strapdown::small_rotation(&(w_in * (-dt)));
        self.q = strapdown::attitude_step(&self.q, &w_hat, dt, &q_nav);
        self.dcm_q = self.q;
        self.dcm = quat_to_dcm(&self.q);
        // Specific force resolved with the mean of the old and new attitude (Groves eq. 5.84):
        // with the old one alone a turn leaves a systematic velocity error of |f|·|ω|·Ts/2.
        let c_mid = (c + self.dcm) * lit::<T>(0.5);
        let f_n = c_mid * f_hat;
        let g = e.gravity;
        let w_v = w_ie * lit::<T>(2.0) + w_en;
        let acc = f_n + Vector3::new(T::zero(), T::zero(), g) - w_v.cross(&self.vel);
        let v_old = self.vel;
        self.vel += acc * dt;
        let v_bar = (v_old + self.vel) * lit::<T>(0.5);
        let dt64 = to_f64(dt);
        self.h -= to_f64(v_bar.z) * dt64;
        self.lat += to_f64(v_bar.x) * dt64 / rn_h;
        self.lon += to_f64(v_bar.y) * dt64 / (re_h * e.cos_lat);
        self.bg += dbias_dt_rad_s2 * dt;
        self.w_hat = w_hat;
        self.time_s += dt64;
        let e = ErrorDynamics {
            dt,
            c,
            f_n,
            w_v,
            w_psi: w_in,
            grav_grad: e.grav_grad,
        };
        let gamma = [
            self.q_rate[0] * dt,
            self.q_rate[1] * dt,
            self.q_rate[2] * dt,
            self.q_rate[3] * dt,
        ];
        strapdown::propagate_covariance(&mut self.p, &e, self.cfg.discretisation, &gamma);
        // Wraps rather than panicking (release keeps overflow checks): a 32-bit flight
        // controller stepping at 1 kHz reaches usize::MAX after 49.7 days.
        self.index = self.index.wrapping_add(1);
        self.check_health()
    }

    #[inline(always)]
    fn refresh_earth(&mut self) {
        if (self.lat - self.earth.lat).abs() > EARTH_REFRESH_RAD
            || (self.h - self.earth.h).abs() > EARTH_REFRESH_M
        {
            self.earth = EarthCache::at(self.lat, self.h);
        }
    }

    #[inline(always)]
    fn check_health(&self) -> Result<(), NavError> {
        let sol = self.vel.sum() + self.q.coords.sum() + self.bg.sum() + self.ba.sum();
        if !(num_traits::Float::is_finite(sol) && (self.lat + self.lon + self.h).is_finite()) {
            return Err(NavError::NonFinite {
                what: "navigation solution",
                index: self.index,
            });
        }
        if self.lat.abs() > MAX_LATITUDE_RAD || self.h.abs() > earth::MAX_HEIGHT_M {
            return Err(NavError::InvalidParameter {
                what: "navigation solution",
                reason: "left the valid domain (|latitude| > 89.4° or |height| > 100 km): diverged",
            });
        }
        if !strapdown::covariance_healthy(&self.p) {
            return Err(NavError::NotPositiveDefinite {
                what: "state covariance P",
            });
        }
        Ok(())
    }

    /// Feeds an estimated error state back into the solution (and resets it to zero).
    fn feedback(&mut self, dx: &SVector<T, N_STATES>) {
        let (sl, cl) = (self.lat.sin(), self.lat.cos());
        let d = 1.0 - earth::WGS84_E2 * sl * sl;
        let re = earth::WGS84_A / d.sqrt();
        let rn = re * (1.0 - earth::WGS84_E2) / d;
        self.lat -= to_f64(dx[0]) / (rn + self.h);
        self.lon -= to_f64(dx[1]) / ((re + self.h) * cl);
        self.h += to_f64(dx[2]);
        self.vel -= dx.fixed_rows::<3>(3);
        let psi: Vector3<T> = dx.fixed_rows::<3>(6).into_owned();
        self.q = strapdown::correct_attitude(&self.q, &psi);
        self.ba -= dx.fixed_rows::<3>(9);
        self.bg -= dx.fixed_rows::<3>(12);
    }

    /// GNSS position/velocity fix: latitude, longitude (rad), ellipsoidal height (m) of the
    /// antenna, its velocity (m/s, NED), reported σ (horizontal m, vertical m, speed m/s), all
    /// valid `age_s` seconds before the current IMU time (≥ 0; the measured position is moved
    /// forward by the measured velocity). Runs the integrity tests and returns what was done.
    pub fn update_gnss(
        &mut self,
        llh: &[f64; 3],
        vel_ned_m_s: &[T; 3],
        acc: &[T; 3],
        age_s: f64,
    ) -> Result<FixStatus, NavError> {
        let (ant_pre, p_pre) = self.antenna();
        let st = self.update_gnss_innovation(llh, vel_ned_m_s, acc, age_s)?;
        if st != FixStatus::Used {
            self.sep.chain = false;
            return Ok(st);
        }
        let cfg = self.cfg;
        let ss = to_f64(num_traits::Float::max(
            acc[2],
            cfg.gnss_min_std_velocity_m_s,
        ));
        let v = Vector3::new(
            to_f64(vel_ned_m_s[0]),
            to_f64(vel_ned_m_s[1]),
            to_f64(vel_ned_m_s[2]),
        );
        let radii = self.radii();
        let (ant, p) = self.antenna();
        if !self.sep.active {
            // Anchor at the last trusted epoch: once the filter has converged on GNSS.
            if !self.sep.first_t.is_finite() {
                self.sep.first_t = self.time_s;
            }
            let sh = to_f64(num_traits::Float::max(acc[0], cfg.gnss_min_std_position_m));
            let sv = to_f64(num_traits::Float::max(acc[1], cfg.gnss_min_std_position_m));
            let f = separation::ANCHOR_VARIANCE_FRACTION;
            let converged = p[0].max(p[1]) <= f * sh * sh && p[2] <= f * sv * sv;
            if !(converged || self.time_s - self.sep.first_t >= separation::ANCHOR_MAX_WAIT_S) {
                return Ok(FixStatus::Used);
            }
            self.sep.anchor(self.time_s, &v, ss * ss, &ant, &p);
        } else {
            self.sep
                .advance(self.time_s, &v, ss * ss, &ant_pre, &p_pre, radii);
        }
        self.sep.last_ant = ant;
        self.sep.last_p = p;
        // Separation and its protection levels (see `separation`).
        let vr = self.sep.variance();
        let r = &self.sep.llh;
        let d = [
            (ant[0] - r[0]) * radii.0,
            (ant[1] - r[1]) * radii.1,
            -(ant[2] - r[2]),
        ];
        let vs = [vr[0] + p[0], vr[1] + p[1], vr[2] + p[2]];
        let (kh, kv) = (to_f64(cfg.separation_k_h), to_f64(cfg.separation_k_v));
        let alert =
            d[0] * d[0] / vs[0] + d[1] * d[1] / vs[1] > kh * kh || d[2].abs() > kv * vs[2].sqrt();
        let hpl_ss =
            kh * vs[0].max(vs[1]).sqrt() + to_f64(cfg.k_horizontal) * vr[0].max(vr[1]).sqrt();
        let vpl_ss = kv * vs[2].sqrt() + to_f64(cfg.k_vertical) * vr[2].sqrt();
        let phh = self.p.fixed_view::<2, 2>(0, 0).into_owned();
        let ff_h = to_f64(cfg.k_horizontal)
            * to_f64(num_traits::Float::max(lambda_max2(&phh), T::zero())).sqrt();
        let ff_v = to_f64(cfg.k_vertical) * p[2].sqrt();
        self.bias_h = num_traits::Float::max(self.bias_h, lit(hpl_ss - ff_h));
        self.bias_v = num_traits::Float::max(self.bias_v, lit(vpl_ss - ff_v));
        Ok(if alert {
            FixStatus::SeparationAlert
        } else {
            FixStatus::Used
        })
    }

    /// (R_N + h, (R_E + h)·cos φ) (m) at the current position.
    fn radii(&self) -> (f64, f64) {
        let (sl, cl) = (self.lat.sin(), self.lat.cos());
        let d = 1.0 - earth::WGS84_E2 * sl * sl;
        let re = earth::WGS84_A / d.sqrt();
        let rn = re * (1.0 - earth::WGS84_E2) / d;
        (rn + self.h, (re + self.h) * cl)
    }

    /// Antenna latitude, longitude (rad), height (m) and the position variances (m², N/E/D).
    fn antenna(&self) -> ([f64; 3], [f64; 3]) {
        let cl_b = quat_to_dcm(&self.q) * Vector3::from(self.cfg.lever_arm_m);
        let (rn_h, re_h_cos) = self.radii();
        (
            [
                self.lat + to_f64(cl_b.x) / rn_h,
                self.lon + to_f64(cl_b.y) / re_h_cos,
                self.h - to_f64(cl_b.z),
            ],
            [
                to_f64(self.p[(0, 0)]),
                to_f64(self.p[(1, 1)]),
                to_f64(self.p[(2, 2)]),
            ],
        )
    }

    /// The innovation tests and the measurement update of [`Self::update_gnss`].
    fn update_gnss_innovation(
        &mut self,
        llh: &[f64; 3],
        vel_ned_m_s: &[T; 3],
        acc: &[T; 3],
        age_s: f64,
    ) -> Result<FixStatus, NavError> {
        if !llh.iter().all(|x| x.is_finite()) {
            return Err(NavError::NonFinite {
                what: "gnss position",
                index: self.index,
            });
        }
        finite3("gnss velocity", self.index, vel_ned_m_s)?;
        finite3("gnss accuracy", self.index, acc)?;
        let (sl, cl) = (self.lat.sin(), self.lat.cos());
        let d = 1.0 - earth::WGS84_E2 * sl * sl;
        let re = earth::WGS84_A / d.sqrt();
        let rn = re * (1.0 - earth::WGS84_E2) / d;
        let c = quat_to_dcm(&self.q);
        let l = Vector3::from(self.cfg.lever_arm_m);
        let cl_b = c * l;
        let v_meas = Vector3::from(*vel_ned_m_s);
        let age = age_s.max(0.0);
        // Predicted − measured, in metres NED (the measured position moved by v·age).
        let dn = (self.lat - llh[0]) * (rn + self.h) - to_f64(v_meas.x) * age;
        let de = (self.lon - llh[1]) * (re + self.h) * cl - to_f64(v_meas.y) * age;
        let dd = -(self.h - llh[2]) - to_f64(v_meas.z) * age;
        let w_l = self.w_hat.cross(&l);
        let c_wl = c * w_l;
        let mut z = Vec6::zeros();
        z[0] = lit::<T>(dn) + cl_b.x;
        z[1] = lit::<T>(de) + cl_b.y;
        z[2] = lit::<T>(dd) + cl_b.z;
        let v_ant = self.vel + c_wl;
        for i in 0..3 {
            z[3 + i] = v_ant[i] - v_meas[i];
        }
        let cfg = self.cfg;
        let sh = num_traits::Float::max(acc[0], cfg.gnss_min_std_position_m);
        let sv = num_traits::Float::max(acc[1], cfg.gnss_min_std_position_m);
        let ss = num_traits::Float::max(acc[2], cfg.gnss_min_std_velocity_m_s);
        let r = Vec6::from([sh * sh, sh * sh, sv * sv, ss * ss, ss * ss, ss * ss]);
        // H = [I 0 −[Ĉl×] 0 0; 0 I −[Ĉ(ω̂×l)×] 0 Ĉ[l×]]: H·P and S = H·P·Hᵀ + R from its
        // identity and lever-arm blocks (the lever-arm terms vanish without a lever arm).
        let lever = l != Vector3::zeros();
        let g = gnss_gain(
            &self.p,
            lever.then(|| (-skew(&cl_b), -skew(&c_wl), c * skew(&l))),
            &r,
        )?;
        let nis = z.dot(&strapdown::chol_solve(&g.chol, &z));
        self.last_nis = nis;
        let passes = nis <= cfg.gate_chi2; // false for NaN too
        if !passes {
            return Ok(FixStatus::ExcludedSnapshot);
        }
        // Averaged innovation over the window (the stored fixes and this one).
        let s = g.s;
        let (mut zs, mut ss_sum) = (z, s);
        for k in 0..self.win_len {
            zs += self.win_z[k];
            ss_sum += self.win_s[k];
        }
        if self.win_len > 0 {
            // mean z = zs/n, cov(mean) = Σs/n²: the statistic is zsᵀ·Σs⁻¹·zs.
            if let Some(ch) = ss_sum.cholesky() {
                let t = zs.dot(&strapdown::chol_solve(&ch, &zs));
                let passes = t <= cfg.gate_chi2;
                if !passes {
                    return Ok(FixStatus::ExcludedWindow);
                }
            }
        }
        let dx = strapdown::joseph_update(&mut self.p, &z, &g)?;
        self.feedback(&dx);
        // Window bookkeeping (ring buffer of the accepted fixes).
        let w = cfg.window_fixes.saturating_sub(1);
        if w > 0 {
            self.win_z[self.win_head] = z;
            self.win_s[self.win_head] = s;
            self.win_head = (self.win_head + 1) % w;
            self.win_len = (self.win_len + 1).min(w);
        }
        // Fault terms of the protection levels.
        let pos_cols = g.hp.fixed_columns::<3>(0).into_owned(); // (H·P)[:, δr] = (P·Hᵀ)ᵀ rows
        let x = pos_cols.transpose() * strapdown::chol_solve(&g.chol, &pos_cols); // A·K·S·Kᵀ·Aᵀ (3×3)
        let xh = x.fixed_view::<2, 2>(0, 0).into_owned();
        let lam = cfg.lambda_undetected;
        let snap_h =
            num_traits::Float::sqrt(lam * num_traits::Float::max(lambda_max2(&xh), T::zero()));
        let snap_v = num_traits::Float::sqrt(lam * num_traits::Float::max(x[(2, 2)], T::zero()));
        let nw: T = lit(cfg.window_fixes as f64);
        let sh2 = s.fixed_view::<2, 2>(0, 0).into_owned();
        let sus_h = num_traits::Float::sqrt(lam / nw * lambda_max2(&sh2));
        let sus_v = num_traits::Float::sqrt(lam / nw * s[(2, 2)]);
        self.bias_h = num_traits::Float::max(snap_h, sus_h);
        self.bias_v = num_traits::Float::max(snap_v, sus_v);
        self.check_health()?;
        Ok(FixStatus::Used)
    }

    /// Barometric height update: the ellipsoidal height `height_m` (m) the barometer implies
    /// (baro altitude plus the tracked offset), with `offset_var_m2` (m²), the variance of that
    /// offset, added to the barometer's own `baro_std_m²`.
    pub fn update_height(&mut self, height_m: f64, offset_var_m2: T) -> Result<(), NavError> {
        if !height_m.is_finite() {
            return Err(NavError::NonFinite {
                what: "baro height",
                index: self.index,
            });
        }
        let mut hm = SMatrix::<T, 1, N_STATES>::zeros();
        hm[(0, 2)] = -T::one();
        let z = SVector::<T, 1>::new(lit(self.h - height_m));
        let r = SVector::<T, 1>::new(
            self.cfg.baro_std_m * self.cfg.baro_std_m
                + num_traits::Float::max(offset_var_m2, T::zero()),
        );
        let g = strapdown::gain(&self.p, &hm, &r, "baro innovation covariance")?;
        let dx = strapdown::joseph_update(&mut self.p, &z, &g)?;
        self.feedback(&dx);
        // The offset error is common to every baro sample, so averaging them cannot take the
        // vertical σ below it: floor the height variance there (conservative, keeps P ≥ 0).
        if self.p[(2, 2)] < offset_var_m2 {
            self.p[(2, 2)] = offset_var_m2;
        }
        self.check_health()
    }

    /// Zero-velocity and zero-angular-rate update (the caller found the vehicle static).
    pub fn update_static(&mut self) -> Result<(), NavError> {
        let c = quat_to_dcm(&self.q);
        let w_ie = earth::earth_rate_ned::<T>(lit(self.lat));
        let w_err = self.w_hat - c.transpose() * w_ie;
        let mut z = Vec6::zeros();
        let mut hm = SMatrix::<T, 6, N_STATES>::zeros();
        for i in 0..3 {
            z[i] = self.vel[i];
            z[3 + i] = w_err[i];
            hm[(i, 3 + i)] = T::one();
            hm[(3 + i, 12 + i)] = -T::one();
        }
        let (sv, sw) = (self.cfg.zupt_std_velocity_m_s, self.cfg.zaru_std_rad_s);
        let r = Vec6::from([sv * sv, sv * sv, sv * sv, sw * sw, sw * sw, sw * sw]);
        let g = strapdown::gain(&self.p, &hm, &r, "ZUPT innovation covariance")?;
        let dx = strapdown::joseph_update(&mut self.p, &z, &g)?;
        self.feedback(&dx);
        self.check_health()
    }

    /// Magnetometer heading update from the field `mag_body` (any unit, body).
    pub fn update_mag_heading(&mut self, mag_body: &[T; 3]) -> Result<(), NavError> {
        finite3("mag", self.index, mag_body)?;
        let m = quat_to_dcm(&self.q) * Vector3::from(*mag_body);
        let mh2 = m.x * m.x + m.y * m.y;
        let horizontal = mh2 > T::default_epsilon();
        if !horizontal {
            return Ok(()); // no horizontal field: nothing to learn
        }
        let z = SVector::<T, 1>::new(wrap_pi(
            num_traits::Float::atan2(m.y, m.x) - self.cfg.declination_rad,
        ));
        let mut hm = SMatrix::<T, 1, N_STATES>::zeros();
        hm[(0, 6)] = -m.x * m.z / mh2;
        hm[(0, 7)] = -m.y * m.z / mh2;
        hm[(0, 8)] = T::one();
        let s = self.cfg.mag_heading_std_rad;
        let r = SVector::<T, 1>::new(s * s);
        let g = strapdown::gain(&self.p, &hm, &r, "heading innovation covariance")?;
        let dx = strapdown::joseph_update(&mut self.p, &z, &g)?;
        self.feedback(&dx);
        // A magnetic heading error is mostly a bias (declination, iron), common to every
        // sample: averaging cannot take the heading σ below the single-sample σ.
        if self.p[(8, 8)] < r[0] {
            self.p[(8, 8)] = r[0];
        }
        self.check_health()
    }

    /// Re-initialises position and velocity on a GNSS fix (antenna position and velocity,
    /// lever arm removed), with the fix's accuracies as their σ and their cross-covariances
    /// cleared; the attitude and biases are kept.
    pub fn reset_to_gnss(
        &mut self,
        llh: &[f64; 3],
        vel_ned_m_s: &[T; 3],
        acc: &[T; 3],
    ) -> Result<(), NavError> {
        if !llh.iter().all(|x| x.is_finite()) {
            return Err(NavError::NonFinite {
                what: "gnss position",
                index: self.index,
            });
        }
        finite3("gnss velocity", self.index, vel_ned_m_s)?;
        if self.sep.active {
            let (a, p) = self.antenna();
            self.sep.accumulate_bridge(&a, &p);
        }
        let c = quat_to_dcm(&self.q);
        let cl_b = c * Vector3::from(self.cfg.lever_arm_m);
        let (sl, cl) = (
            num_traits::Float::sin(llh[0]),
            num_traits::Float::cos(llh[0]),
        );
        let d = 1.0 - earth::WGS84_E2 * sl * sl;
        let re = earth::WGS84_A / d.sqrt();
        let rn = re * (1.0 - earth::WGS84_E2) / d;
        self.lat = llh[0] - to_f64(cl_b.x) / (rn + llh[2]);
        self.lon = llh[1] - to_f64(cl_b.y) / ((re + llh[2]) * cl);
        self.h = llh[2] + to_f64(cl_b.z);
        self.vel = Vector3::from(*vel_ned_m_s);
        let sh = num_traits::Float::max(acc[0], self.cfg.gnss_min_std_position_m);
        let sv = num_traits::Float::max(acc[1], self.cfg.gnss_min_std_position_m);
        let ss = num_traits::Float::max(acc[2], self.cfg.gnss_min_std_velocity_m_s);
        for i in 0..6 {
            for j in 0..N_STATES {
                self.p[(i, j)] = T::zero();
                self.p[(j, i)] = T::zero();
            }
        }
        let var = [sh * sh, sh * sh, sv * sv, ss * ss, ss * ss, ss * ss];
        for (i, v) in var.iter().enumerate() {
            self.p[(i, i)] = *v;
        }
        self.win_len = 0;
        self.win_head = 0;
        // The reference bridges the jump: it follows the dead-reckoned displacement up to the
        // reset and the filter's displacement from here on (never the jump itself).
        let (a, p) = self.antenna();
        self.sep.last_ant = a;
        self.sep.last_p = p;
        self.sep.chain = false;
        self.check_health()
    }

    /// Resets the yaw to the GNSS course `course_rad` (rad) with σ `std_rad`, keeping roll
    /// and pitch; the heading error is decorrelated from the other states.
    pub fn reset_heading(&mut self, course_rad: T, std_rad: T) -> Result<(), NavError> {
        crate::error::check_finite("course", &[course_rad, std_rad])?;
        let (roll, pitch, _) = quat_to_euler321(&self.q);
        self.q = euler321_to_quat(roll, pitch, course_rad);
        for i in 0..N_STATES {
            self.p[(8, i)] = T::zero();
            self.p[(i, 8)] = T::zero();
        }
        self.p[(8, 8)] = std_rad * std_rad;
        Ok(())
    }
}

/// Magnetometer input of the batch runner.
#[derive(Debug, Clone, Copy)]
pub struct MagnetometerAiding<'a, T> {
    /// Sample times (s, same clock as the IMU), strictly increasing.
    pub t_s: &'a [f64],
    /// Field (any unit, body frame).
    pub field: &'a [[T; 3]],
}

/// A whole flight for [`InsFilter::run_batch`]; times in seconds on one clock.
#[derive(Debug, Clone, Copy)]
pub struct InsBatchInput<'a, T> {
    /// IMU sample times (s), strictly increasing.
    pub imu_t_s: &'a [f64],
    /// Gyro output (rad/s, body).
    pub gyro_rad_s: &'a [[T; 3]],
    /// Accelerometer output (m/s², body).
    pub accel_m_s2: &'a [[T; 3]],
    /// Die temperature (°C); required for TCZUPT.
    pub temp_c: Option<&'a [T]>,
    /// Per-IMU-sample static flag (ZUPT/ZARU where true).
    pub stationary: Option<&'a [bool]>,
    /// GNSS fix times (s), strictly increasing.
    pub gnss_t_s: &'a [f64],
    /// GNSS latitude (rad), longitude (rad), ellipsoidal height (m).
    pub gnss_llh: &'a [[f64; 3]],
    /// GNSS velocity (m/s, NED).
    pub gnss_vel_m_s: &'a [[T; 3]],
    /// Reported accuracies: horizontal (m), vertical (m), speed (m/s).
    pub gnss_acc: &'a [[T; 3]],
    /// Per-fix use flag (false = masked outage); `None` = all used.
    pub gnss_use: Option<&'a [bool]>,
    /// Barometer sample times (s) and altitudes (m, any datum: the offset is tracked).
    pub baro: Option<(&'a [f64], &'a [T])>,
    /// Magnetometer for the start-up heading.
    pub mag: Option<MagnetometerAiding<'a, T>>,
    /// Initial attitude (body → NED, scalar first); `None` = levelling over
    /// `levelling_samples` with the magnetic heading (or 0 without a magnetometer, to be reset
    /// by the GNSS course).
    pub initial_attitude: Option<[T; 4]>,
    /// Samples averaged for levelling.
    pub levelling_samples: usize,
    /// Initial gyro bias (rad/s, body).
    pub gyro_bias0_rad_s: [T; 3],
}

/// Output buffers of [`InsFilter::run_batch`]: row `j` holds the state after IMU sample
/// `j·decimation`; per-fix arrays have one entry per GNSS fix.
#[derive(Debug)]
pub struct InsBatchOutput<'a, T> {
    /// Store one row every `decimation` samples (≥ 1).
    pub decimation: usize,
    /// Latitude, longitude (rad), height (m).
    pub llh: &'a mut [[f64; 3]],
    /// Velocity (m/s, NED).
    pub vel_m_s: &'a mut [[T; 3]],
    /// Attitude (body → NED), scalar first.
    pub attitude: &'a mut [[T; 4]],
    /// Gyro bias (rad/s, body).
    pub gyro_bias_rad_s: &'a mut [[T; 3]],
    /// Accelerometer bias (m/s², body).
    pub accel_bias_m_s2: &'a mut [[T; 3]],
    /// Diagonal of P (SI units).
    pub cov_diag: &'a mut [[T; N_STATES]],
    /// Horizontal and vertical protection levels (m).
    pub protection_m: &'a mut [[T; 2]],
    /// Whether a GNSS fix was used since the previous row.
    pub gnss_used: &'a mut [bool],
    /// Per fix: [`FixStatus`] as `u8`.
    pub fix_status: &'a mut [u8],
    /// Per fix: NIS (0 when not tested).
    pub fix_nis: &'a mut [T],
}

/// What [`InsFilter::run_batch`] returns besides the histories.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InsBatchSummary<T> {
    /// Initial attitude (body → NED), scalar first.
    pub initial_attitude: [T; 4],
    /// GNSS fixes used.
    pub fixes_used: usize,
    /// GNSS fixes excluded by the integrity tests.
    pub fixes_excluded: usize,
    /// Used fixes at which the solution-separation monitor raised an alert.
    pub separation_alerts: usize,
    /// ZUPT/ZARU updates.
    pub static_updates: usize,
    /// Barometric updates.
    pub baro_updates: usize,
    /// Magnetometer heading updates.
    pub mag_updates: usize,
    /// Whether the heading was reset to the GNSS course.
    pub course_reset: bool,
    /// IMU logging gaps bridged (intervals longer than 5 nominal periods).
    pub imu_gaps: usize,
    /// Resets to GNSS after `reset_after_exclusions` consecutive excluded fixes.
    pub gnss_resets: usize,
}

fn check_increasing(what: &'static str, t: &[f64]) -> Result<(), NavError> {
    if let Some(index) = t.iter().position(|x| !x.is_finite()) {
        return Err(NavError::NonFinite { what, index });
    }
    if t.windows(2).any(|w| matches!(w, [a, b] if b <= a)) {
        return Err(NavError::InvalidParameter {
            what,
            reason: "times must be strictly increasing",
        });
    }
    Ok(())
}

fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), NavError> {
    if expected == got {
        Ok(())
    } else {
        Err(NavError::LengthMismatch {
            what,
            expected,
            got,
        })
    }
}

impl<T: Real> InsFilter<T> {
    /// Runs a whole flight: initialises at the first usable GNSS fix (which must lie within
    /// 1 s of the first IMU sample), then predicts at every IMU sample and applies, in time
    /// order, the barometer, magnetometer (start-up), static and GNSS updates that fall
    /// before it. No allocation.
    // The indices below are bounded by the length checks at the top.
    #[allow(clippy::indexing_slicing)]
    pub fn run_batch<D: BiasTemperatureDerivative<T>>(
        config: InsConfig<T>,
        input: &InsBatchInput<'_, T>,
        deriv: &mut D,
        out: &mut InsBatchOutput<'_, T>,
    ) -> Result<InsBatchSummary<T>, NavError> {
        config.validate()?;
        let n = input.imu_t_s.len();
        if n < 2 {
            return Err(NavError::TooShort {
                what: "IMU samples",
                len: n,
                min: 2,
            });
        }
        check_len("gyro_rad_s", n, input.gyro_rad_s.len())?;
        check_len("accel_m_s2", n, input.accel_m_s2.len())?;
        check_increasing("IMU time", input.imu_t_s)?;
        if let Some(t) = input.temp_c {
            check_len("temp_c", n, t.len())?;
        } else if config.mode == Mode::Tczupt {
            return Err(NavError::InvalidParameter {
                what: "temp_c",
                reason: "TCZUPT needs the die temperature",
            });
        }
        if let Some(s) = input.stationary {
            check_len("stationary", n, s.len())?;
        }
        let m = input.gnss_t_s.len();
        if m == 0 {
            return Err(NavError::TooShort {
                what: "GNSS fixes",
                len: 0,
                min: 1,
            });
        }
        check_len("gnss_llh", m, input.gnss_llh.len())?;
        check_len("gnss_vel_m_s", m, input.gnss_vel_m_s.len())?;
        check_len("gnss_acc", m, input.gnss_acc.len())?;
        check_increasing("GNSS time", input.gnss_t_s)?;
        if let Some(u) = input.gnss_use {
            check_len("gnss_use", m, u.len())?;
        }
        if let Some((t, h)) = input.baro {
            check_len("baro height", t.len(), h.len())?;
            check_increasing("baro time", t)?;
        }
        if let Some(mg) = input.mag {
            check_len("mag field", mg.t_s.len(), mg.field.len())?;
            check_increasing("mag time", mg.t_s)?;
        }
        if out.decimation == 0 {
            return Err(NavError::InvalidParameter {
                what: "decimation",
                reason: "must be ≥ 1",
            });
        }
        let rows = n.div_ceil(out.decimation);
        check_len("out.llh", rows, out.llh.len())?;
        check_len("out.vel_m_s", rows, out.vel_m_s.len())?;
        check_len("out.attitude", rows, out.attitude.len())?;
        check_len("out.gyro_bias_rad_s", rows, out.gyro_bias_rad_s.len())?;
        check_len("out.accel_bias_m_s2", rows, out.accel_bias_m_s2.len())?;
        check_len("out.cov_diag", rows, out.cov_diag.len())?;
        check_len("out.protection_m", rows, out.protection_m.len())?;
        check_len("out.gnss_used", rows, out.gnss_used.len())?;
        check_len("out.fix_status", m, out.fix_status.len())?;
        check_len("out.fix_nis", m, out.fix_nis.len())?;

        let usable = |j: usize| input.gnss_use.is_none_or(|u| u[j]);
        let t0 = input.imu_t_s[0];
        // Initial fix: the last usable fix at or before t0, else the first after it.
        let mut first = None;
        for j in 0..m {
            if usable(j) {
                if input.gnss_t_s[j] <= t0 || first.is_none() {
                    first = Some(j);
                }
                if input.gnss_t_s[j] > t0 {
                    break;
                }
            }
        }
        let j0 = first.ok_or(NavError::InvalidParameter {
            what: "GNSS",
            reason: "no usable fix to initialise the position",
        })?;
        if (input.gnss_t_s[j0] - t0).abs() > 1.0 {
            return Err(NavError::InvalidParameter {
                what: "GNSS",
                reason: "the first usable fix is more than 1 s from the first IMU sample",
            });
        }
        // Initial attitude.
        let q0 = match input.initial_attitude {
            Some(a) => crate::attitude::quat_from_array(a)?,
            None => {
                let mut lev = Levelling::new();
                let k_lev = input.levelling_samples.clamp(1, n);
                let mut n_mag = 0usize;
                for k in 0..k_lev {
                    let tk = input.imu_t_s[k];
                    let mag = input.mag.and_then(|mg| {
                        // The magnetometer sample nearest in time (levelling is static).
                        let idx = mg.t_s.partition_point(|&t| t <= tk);
                        idx.checked_sub(1).and_then(|i| mg.field.get(i))
                    });
                    n_mag += usize::from(mag.is_some());
                    lev.push(&input.accel_m_s2[k], mag)?;
                }
                let heading = if n_mag > 0 {
                    HeadingSource::Magnetic {
                        declination_rad: config.declination_rad,
                    }
                } else {
                    HeadingSource::Given(T::zero())
                };
                lev.attitude(heading)?
            }
        };
        let acc0 = input.gnss_acc[j0];
        let floor_p = config.gnss_min_std_position_m;
        let floor_v = config.gnss_min_std_velocity_m_s;
        let sp = num_traits::Float::max(acc0[0], floor_p);
        let mut f = Self::new(
            config,
            input.gnss_llh[j0][0],
            input.gnss_llh[j0][1],
            input.gnss_llh[j0][2],
            Vector3::from(input.gnss_vel_m_s[j0]),
            q0,
            [sp, sp, num_traits::Float::max(acc0[1], floor_p)],
            [num_traits::Float::max(acc0[2], floor_v); 3],
        )?;
        f.bg = Vector3::from(input.gyro_bias0_rad_s);
        crate::error::check_finite("gyro_bias0_rad_s", f.bg.as_slice())?;
        let have_mag = input.mag.is_some_and(|mg| !mg.t_s.is_empty());
        let mut heading_known = have_mag || input.initial_attitude.is_some();
        let span = input.imu_t_s[n - 1] - t0;
        let dt_nominal_s = span / (n - 1) as f64;
        let dt_nominal: T = lit(dt_nominal_s);
        let mut slope = SlopeEstimator::new(config.temp_slope_window_s, dt_nominal);
        let thermal_wander =
            config.mode == Mode::Classic && config.sigma_gbt_rad_s_sqrt_c > T::zero();
        let zupt_every = to_f64(config.zupt_interval_s);
        let mag_every = to_f64(config.mag_interval_s);
        let mag_until = t0 + to_f64(config.heading_aiding_s);
        let tau = to_f64(config.baro_offset_time_constant_s);

        for s in out.fix_status.iter_mut() {
            *s = FixStatus::Unused as u8;
        }
        for v in out.fix_nis.iter_mut() {
            *v = T::zero();
        }
        out.fix_status[j0] = FixStatus::Used as u8;
        let mut summary = InsBatchSummary {
            initial_attitude: quat_to_array(&q0),
            fixes_used: 1,
            fixes_excluded: 0,
            separation_alerts: 0,
            static_updates: 0,
            baro_updates: 0,
            mag_updates: 0,
            course_reset: false,
            imu_gaps: 0,
            gnss_resets: 0,
        };
        let mut consecutive_excluded = 0usize;
        // Cursors into the aiding streams (everything up to t0 is consumed).
        let mut jg = j0 + 1;
        while jg < m && input.gnss_t_s[jg] <= t0 {
            jg += 1;
        }
        let mut jb = 0usize;
        let mut baro_offset: Option<f64> = None;
        // Variance (m²) of the offset estimate: a first-order filter of independent
        // differences, var ← (1−a)²·var + a²·(σ_v² + σ_baro²).
        let mut baro_offset_var = 0.0_f64;
        let baro_var = to_f64(config.baro_std_m * config.baro_std_m);
        let mut last_fix_llh = input.gnss_llh[j0];
        let mut jm = 0usize;
        let mut last_mag = f64::NEG_INFINITY;
        let mut last_static = f64::NEG_INFINITY;
        let mut used_since_row = true;
        let mut gnss_t_last_used = input.gnss_t_s[j0];

        for k in 0..n {
            let tk = input.imu_t_s[k];
            if k > 0 {
                let dt: T = lit(tk - input.imu_t_s[k - 1]);
                let mut rate = Vector3::zeros();
                let mut thermal_var = T::zero();
                if config.mode == Mode::Tczupt || thermal_wander {
                    if let Some(temps) = input.temp_c {
                        let temp = temps[k];
                        if !num_traits::Float::is_finite(temp) {
                            return Err(NavError::NonFinite {
                                what: "temp_c",
                                index: k,
                            });
                        }
                        let dtdt = slope.push(temp);
                        if config.mode == Mode::Tczupt {
                            rate = deriv.dbias_dtemp(k, temp) * dtdt;
                        } else {
                            let s = config.sigma_gbt_rad_s_sqrt_c;
                            thermal_var = s * s * num_traits::Float::abs(dtdt) * dt;
                        }
                    }
                }
                // A logging gap: the sample after it averages over an unknown part of the gap
                // (a 2 s gap of a 50 Hz log once read −4.7 m/s² for gravity), so the gap is
                // bridged with the last sample before it, as a dead-reckoning outage.
                let gap = tk - input.imu_t_s[k - 1] > MAX_GAP_FACTOR * dt_nominal_s;
                let j = if gap { k - 1 } else { k };
                summary.imu_gaps += usize::from(gap);
                f.predict(&input.gyro_rad_s[j], &input.accel_m_s2[j], dt, &rate)
                    .map_err(|e| reindex(e, k))?;
                if thermal_var > T::zero() {
                    for i in 12..15 {
                        f.p[(i, i)] += thermal_var;
                    }
                }
            } else if config.mode == Mode::Tczupt || thermal_wander {
                if let Some(temps) = input.temp_c {
                    slope.push(temps[0]);
                }
            }
            // Barometer.
            if let Some((bt, bh)) = input.baro {
                while jb < bt.len() && bt[jb] <= tk {
                    let hb = to_f64(bh[jb]);
                    if !hb.is_finite() {
                        return Err(NavError::NonFinite {
                            what: "baro height",
                            index: jb,
                        });
                    }
                    if baro_offset.is_none() {
                        baro_offset = Some(last_fix_llh[2] - hb);
                        let s = num_traits::Float::max(acc0[1], floor_p);
                        baro_offset_var = to_f64(s * s);
                    }
                    if let Some(o) = baro_offset {
                        if bt[jb] >= t0 && tk - gnss_t_last_used > BARO_GNSS_GAP_S {
                            f.update_height(hb + o, lit(baro_offset_var))?;
                            summary.baro_updates += 1;
                        }
                    }
                    jb += 1;
                }
            }
            // Magnetometer heading at start-up.
            if let Some(mg) = input.mag {
                while jm < mg.t_s.len() && mg.t_s[jm] <= tk {
                    if mg.t_s[jm] >= t0
                        && mg.t_s[jm] <= mag_until
                        && mg.t_s[jm] - last_mag >= mag_every
                    {
                        f.update_mag_heading(&mg.field[jm])?;
                        summary.mag_updates += 1;
                        last_mag = mg.t_s[jm];
                    }
                    jm += 1;
                }
            }
            // Static pseudo-measurements.
            if input.stationary.is_some_and(|s| s[k]) && tk - last_static >= zupt_every {
                f.update_static()?;
                summary.static_updates += 1;
                last_static = tk;
            }
            // GNSS.
            while jg < m && input.gnss_t_s[jg] <= tk {
                if usable(jg) {
                    let vel = input.gnss_vel_m_s[jg];
                    if !heading_known {
                        let speed = num_traits::Float::sqrt(vel[0] * vel[0] + vel[1] * vel[1]);
                        if speed > config.course_min_speed_m_s {
                            let course = num_traits::Float::atan2(vel[1], vel[0]);
                            // Crab/sideslip and speed noise: 5° plus s_acc/speed.
                            let sd = lit::<T>(5.0_f64.to_radians())
                                + num_traits::Float::max(input.gnss_acc[jg][2], floor_v) / speed;
                            f.reset_heading(course, sd)?;
                            heading_known = true;
                            summary.course_reset = true;
                        }
                    }
                    let age = tk - input.gnss_t_s[jg];
                    let st = f.update_gnss(&input.gnss_llh[jg], &vel, &input.gnss_acc[jg], age)?;
                    out.fix_status[jg] = st as u8;
                    out.fix_nis[jg] = f.last_nis;
                    if matches!(st, FixStatus::Used | FixStatus::SeparationAlert) {
                        summary.separation_alerts += usize::from(st == FixStatus::SeparationAlert);
                        consecutive_excluded = 0;
                        summary.fixes_used += 1;
                        used_since_row = true;
                        last_fix_llh = input.gnss_llh[jg];
                        // Baro offset: first-order filter of (GNSS − baro) while GNSS is used.
                        if let (Some(o), Some((bt, bh))) = (baro_offset.as_mut(), input.baro) {
                            if jb > 0 {
                                let hb = to_f64(bh[jb - 1]);
                                let a = ((input.gnss_t_s[jg] - gnss_t_last_used) / tau).min(1.0);
                                *o += a * (input.gnss_llh[jg][2] - hb - *o);
                                let sv =
                                    to_f64(num_traits::Float::max(input.gnss_acc[jg][1], floor_p));
                                baro_offset_var = (1.0 - a) * (1.0 - a) * baro_offset_var
                                    + a * a * (sv * sv + baro_var);
                                let _ = bt;
                            }
                        }
                        gnss_t_last_used = input.gnss_t_s[jg];
                    } else {
                        summary.fixes_excluded += 1;
                        consecutive_excluded += 1;
                        if config.reset_after_exclusions > 0
                            && consecutive_excluded >= config.reset_after_exclusions
                        {
                            // Persistent disagreement: either GNSS has been faulty for that long
                            // or the filter has diverged. Without a second position source the
                            // filter cannot tell which; it re-initialises on GNSS and reports it.
                            f.reset_to_gnss(&input.gnss_llh[jg], &vel, &input.gnss_acc[jg])?;
                            out.fix_status[jg] = FixStatus::Reset as u8;
                            summary.gnss_resets += 1;
                            consecutive_excluded = 0;
                        }
                    }
                } else {
                    out.fix_status[jg] = FixStatus::Masked as u8;
                }
                jg += 1;
            }
            if k % out.decimation == 0 {
                let j = k / out.decimation;
                out.llh[j] = f.position();
                out.vel_m_s[j] = f.vel.into();
                out.attitude[j] = quat_to_array(&f.q);
                out.gyro_bias_rad_s[j] = f.bg.into();
                out.accel_bias_m_s2[j] = f.ba.into();
                for i in 0..N_STATES {
                    out.cov_diag[j][i] = f.p[(i, i)];
                }
                let (hpl, vpl) = f.protection_levels();
                out.protection_m[j] = [hpl, vpl];
                out.gnss_used[j] = used_since_row;
                used_since_row = false;
            }
        }
        Ok(summary)
    }
}

fn reindex(e: NavError, k: usize) -> NavError {
    match e {
        NavError::NonFinite { what, .. } => NavError::NonFinite { what, index: k },
        other => other,
    }
}

/// [`strapdown::gain`] for the GNSS rows, with `H` given by its blocks: `H·P` is P's δr and δv
/// rows plus, with a lever arm, `A·P[ψ]`, `B·P[ψ] + D·P[δb_g]` (`lever` = (A, B, D)); `S` is
/// built the same way from the columns of `H·P`. Without a lever arm `H = [I₆ 0]` and the
/// result is exactly the dense product's (the skipped terms are exact zeros).
fn gnss_gain<T: Real>(
    p: &Mat15<T>,
    lever: Option<(Matrix3<T>, Matrix3<T>, Matrix3<T>)>,
    r_diag: &Vec6<T>,
) -> Result<strapdown::Gain<T, 6>, NavError> {
    let mut hp: SMatrix<T, 6, N_STATES> = p.fixed_rows::<6>(0).into_owned();
    let mut s: Mat6<T> = hp.fixed_columns::<6>(0).into_owned();
    if let Some((a, b, d)) = lever {
        let p_psi = p.fixed_rows::<3>(6);
        let top = a * p_psi;
        let bot = b * p_psi + d * p.fixed_rows::<3>(12);
        let mut hp_top = hp.fixed_rows_mut::<3>(0);
        hp_top += top;
        let mut hp_bot = hp.fixed_rows_mut::<3>(3);
        hp_bot += bot;
        let hp_psi = hp.fixed_columns::<3>(6);
        let s_pos = hp.fixed_columns::<3>(0) + hp_psi * a.transpose();
        let s_vel = hp.fixed_columns::<3>(3)
            + hp_psi * b.transpose()
            + hp.fixed_columns::<3>(12) * d.transpose();
        s.fixed_columns_mut::<3>(0).copy_from(&s_pos);
        s.fixed_columns_mut::<3>(3).copy_from(&s_vel);
    }
    for i in 0..6 {
        s[(i, i)] += r_diag[i];
    }
    let chol = s.cholesky().ok_or(NavError::NotPositiveDefinite {
        what: "GNSS innovation covariance S",
    })?;
    Ok(strapdown::Gain { chol, hp, s })
}

#[cfg(test)]
mod gain_tests {
    use super::*;

    #[test]
    fn structured_gnss_gain_equals_the_dense_product() {
        // A full SPD P (A·Aᵀ + I) and a lever arm with attitude and rate terms.
        let a = Mat15::<f64>::from_fn(|i, j| ((i * 7 + j * 3) % 11) as f64 * 0.1 - 0.4);
        let p = a * a.transpose() + Mat15::identity();
        let c = quat_to_dcm(&euler321_to_quat(0.1, -0.2, 2.0));
        let l = Vector3::new(0.3, -0.1, -0.2);
        let w = Vector3::new(0.2, 0.1, -0.5);
        let (cl, cwl) = (c * l, c * w.cross(&l));
        let mut h = SMatrix::<f64, 6, N_STATES>::zeros();
        h.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&Matrix3::identity());
        h.fixed_view_mut::<3, 3>(0, 6).copy_from(&(-skew(&cl)));
        h.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&Matrix3::identity());
        h.fixed_view_mut::<3, 3>(3, 6).copy_from(&(-skew(&cwl)));
        h.fixed_view_mut::<3, 3>(3, 12).copy_from(&(c * skew(&l)));
        let r = Vec6::from([2.0, 2.0, 6.0, 0.02, 0.02, 0.02]);
        let dense = strapdown::gain(&p, &h, &r, "S").unwrap();
        let blocks = (-skew(&cl), -skew(&cwl), c * skew(&l));
        let ours = gnss_gain(&p, Some(blocks), &r).unwrap();
        assert!((ours.hp - dense.hp).abs().max() < 1e-12);
        assert!((ours.s - dense.s).abs().max() < 1e-12);
        // Without a lever arm: exactly the dense product with H = [I₆ 0].
        let mut h0 = SMatrix::<f64, 6, N_STATES>::zeros();
        h0.fixed_view_mut::<6, 6>(0, 0).fill_with_identity();
        let dense0 = strapdown::gain(&p, &h0, &r, "S").unwrap();
        let ours0 = gnss_gain(&p, None, &r).unwrap();
        assert_eq!(ours0.hp, dense0.hp);
        assert_eq!(ours0.s, dense0.s);
    }
}
