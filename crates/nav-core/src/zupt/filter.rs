//! The filter kernel: strapdown mechanisation, block-structured covariance propagation, the
//! nine-measurement ZUPT update in Joseph form, feedback and reset; and the batch runner.
use nalgebra::{SMatrix, SVector, UnitQuaternion, Vector3};

use super::slope::SlopeEstimator;
use super::{
    BiasTemperatureDerivative, HeadingSource, Levelling, Mode, ZuptConfig, N_MEAS, N_STATES,
};
use crate::attitude::{quat_from_rotation_vector, quat_to_array, quat_to_dcm};
use crate::earth;
use crate::scalar::lit;
use crate::strapdown::{self, ErrorDynamics};
use crate::{NavError, Real};

type Mat15<T> = SMatrix<T, N_STATES, N_STATES>;
type Vec9<T> = SVector<T, N_MEAS>;

#[inline(always)]
fn finite3<T: Real>(what: &'static str, index: usize, v: &[T; 3]) -> Result<(), NavError> {
    if v.iter().all(|x| num_traits::Float::is_finite(*x)) {
        Ok(())
    } else {
        Err(NavError::NonFinite { what, index })
    }
}

/// The ZUPT / TCZUPT filter (see the module docs for the model). Never allocates; `Clone`
/// but not `Copy` (it holds a 15×15 covariance and the 512-sample temperature window).
#[derive(Debug, Clone)]
pub struct ZuptFilter<T: Real> {
    cfg: ZuptConfig<T>,
    dt: T,
    // Navigation solution.
    pos: Vector3<T>,
    vel: Vector3<T>,
    q: UnitQuaternion<T>,
    ba: Vector3<T>,
    bg: Vector3<T>,
    // Frozen references of the ZUPT measurement.
    q0: UnitQuaternion<T>,
    /// Frozen position (m, NED displacement from the start).
    pos0: Vector3<T>,
    /// Whether the previous sample was flagged stationary (re-freeze on a new rest period).
    was_stationary: bool,
    // Error covariance P (15×15).
    p: Mat15<T>,
    // Earth model at the frozen position.
    w_ie: Vector3<T>,
    /// Rotation of the NED frame over one sample, `exp(−ω_ie·Ts/2)`.
    q_earth: UnitQuaternion<T>,
    g0: T,
    grav_grad: T,
    // Γ diagonal per group (variance added per step).
    gamma: [T; 4],
    r_diag: Vec9<T>,
    // Scheduling.
    steps_per_update: usize,
    since_update: usize,
    slope: SlopeEstimator<T>,
    index: usize,
    n_updates: usize,
    last_dtemp_dt: T,
    last_nis: T,
}

impl<T: Real> ZuptFilter<T> {
    /// A filter at rest at the frozen attitude `q0` (body → NED), with initial bias estimates
    /// `accel_bias_m_s2` (m/s², body) and `gyro_bias_rad_s` (rad/s, body), for samples every
    /// `dt_s` seconds.
    pub fn new(
        config: ZuptConfig<T>,
        q0: UnitQuaternion<T>,
        accel_bias_m_s2: Vector3<T>,
        gyro_bias_rad_s: Vector3<T>,
        dt_s: T,
    ) -> Result<Self, NavError> {
        config.validate()?;
        if !(num_traits::Float::is_finite(dt_s) && dt_s > T::zero()) {
            return Err(NavError::InvalidParameter {
                what: "dt_s",
                reason: "must be finite and > 0",
            });
        }
        crate::error::check_finite("q0", q0.coords.as_slice())?;
        crate::error::check_finite("accel_bias_m_s2", accel_bias_m_s2.as_slice())?;
        crate::error::check_finite("gyro_bias_rad_s", gyro_bias_rad_s.as_slice())?;
        let per = num_traits::Float::round(config.update_interval_s / dt_s);
        let steps_per_update = num_traits::ToPrimitive::to_usize(&per)
            .unwrap_or(usize::MAX)
            .max(1);
        let sq = |x: T| x * x;
        let mut p = Mat15::zeros();
        let init = [
            config.init_std_position_m,
            config.init_std_velocity_m_s,
            config.init_std_attitude_rad,
            config.init_std_accel_bias_m_s2,
            config.init_std_gyro_bias_rad_s,
        ];
        for (b, s) in init.iter().enumerate() {
            for i in 0..3 {
                p[(3 * b + i, 3 * b + i)] = sq(*s);
            }
        }
        let n = config.noise;
        let gamma = [
            sq(n.sigma_vrw_m_s_sqrt_s) * dt_s,
            sq(n.sigma_arw_rad_sqrt_s) * dt_s,
            sq(n.sigma_abi_m_s2) * dt_s,
            sq(n.sigma_gbi_rad_s) * dt_s,
        ];
        let r = [
            sq(config.meas_std_position_m),
            sq(config.meas_std_velocity_m_s),
            sq(config.meas_std_attitude_rad),
        ];
        let r_diag = Vec9::from_fn(|i, _| r[i / 3]);
        let g0 = earth::normal_gravity(config.latitude_rad, config.height_m);
        Ok(Self {
            dt: dt_s,
            pos: Vector3::zeros(),
            vel: Vector3::zeros(),
            q: q0,
            ba: accel_bias_m_s2,
            bg: gyro_bias_rad_s,
            q0,
            pos0: Vector3::zeros(),
            was_stationary: true,
            p,
            w_ie: earth::earth_rate_ned(config.latitude_rad),
            q_earth: quat_from_rotation_vector(
                &(-earth::earth_rate_ned(config.latitude_rad) * dt_s),
            ),
            g0,
            grav_grad: lit::<T>(2.0) * g0 / earth::geocentric_radius(config.latitude_rad),
            gamma,
            r_diag,
            steps_per_update,
            since_update: 0,
            slope: SlopeEstimator::new(config.temp_slope_window_s, dt_s),
            index: 0,
            n_updates: 0,
            last_dtemp_dt: T::zero(),
            last_nis: T::zero(),
            cfg: config,
        })
    }

    /// Estimated gyro bias (rad/s, body).
    #[inline]
    pub fn gyro_bias_rad_s(&self) -> Vector3<T> {
        self.bg
    }

    /// Estimated accelerometer bias (m/s², body).
    #[inline]
    pub fn accel_bias_m_s2(&self) -> Vector3<T> {
        self.ba
    }

    /// Current attitude estimate (body → NED).
    #[inline]
    pub fn attitude(&self) -> &UnitQuaternion<T> {
        &self.q
    }

    /// Velocity estimate (m/s, NED).
    #[inline]
    pub fn velocity_m_s(&self) -> Vector3<T> {
        self.vel
    }

    /// Position estimate: NED displacement from the frozen initial point (m).
    #[inline]
    pub fn position_m(&self) -> Vector3<T> {
        self.pos
    }

    /// Error covariance P (15×15; order δr, δv, ψ, δb_a, δb_g; SI units).
    #[inline]
    pub fn covariance(&self) -> &SMatrix<T, N_STATES, N_STATES> {
        &self.p
    }

    /// Number of ZUPT updates applied so far.
    #[inline]
    pub fn updates(&self) -> usize {
        self.n_updates
    }

    /// Latest dT/dt estimate (°C/s) used by TCZUPT.
    #[inline]
    pub fn temp_rate_c_s(&self) -> T {
        self.last_dtemp_dt
    }

    /// Normalised innovation squared `zᵀS⁻¹z` of the latest update (χ² with 9 degrees of
    /// freedom for a consistent filter).
    #[inline]
    pub fn last_nis(&self) -> T {
        self.last_nis
    }

    /// One time-propagation step (eqs. 15–18) with gyro `gyro_rad_s` (rad/s, body; calibrated
    /// for ZUPT, raw for TCZUPT) and specific force `accel_m_s2` (m/s², body) held over the
    /// sample period; `dbias_dt_rad_s2` is the deterministic gyro-bias rate (rad/s²) of eq. 31
    /// (zero for standard ZUPT). Errors on non-finite input (state unchanged) and when the
    /// covariance stops being finite and non-negative on the diagonal.
    pub fn predict(
        &mut self,
        gyro_rad_s: &[T; 3],
        accel_m_s2: &[T; 3],
        dbias_dt_rad_s2: &Vector3<T>,
    ) -> Result<(), NavError> {
        finite3("gyro_rad_s", self.index, gyro_rad_s)?;
        finite3("accel_m_s2", self.index, accel_m_s2)?;
        finite3("dbias_dt_rad_s2", self.index, &(*dbias_dt_rad_s2).into())?;
        let dt = self.dt;
        let w_hat = Vector3::from(*gyro_rad_s) - self.bg;
        let f_hat = Vector3::from(*accel_m_s2) - self.ba;
        let c = quat_to_dcm(&self.q);
        // Attitude: body rotation on the right, Earth rotation of the NED frame on the left.
        self.q = strapdown::attitude_step(&self.q, &w_hat, dt, self.q_earth.quaternion());
        let f_n = c * f_hat;
        let g = self.g0 + self.grav_grad * self.pos.z;
        let acc = f_n + Vector3::new(T::zero(), T::zero(), g)
            - self.w_ie.cross(&self.vel) * lit::<T>(2.0);
        let v_old = self.vel;
        self.vel += acc * dt;
        self.pos += (v_old + self.vel) * (dt * lit::<T>(0.5));
        // Eq. 31 (F_g = 0): deterministic thermal drift of the bias.
        self.bg += dbias_dt_rad_s2 * dt;

        let dynamics = ErrorDynamics {
            dt,
            c,
            f_n,
            // At rest: no transport rate, so ω_v = 2ω_ie and ω_ψ = ω_ie.
            w_v: self.w_ie * lit::<T>(2.0),
            w_psi: self.w_ie,
            grav_grad: self.grav_grad,
        };
        strapdown::propagate_covariance(
            &mut self.p,
            &dynamics,
            self.cfg.discretisation,
            &self.gamma,
        );
        // Wraps rather than panicking (release keeps overflow checks): a 32-bit flight
        // controller stepping at 1 kHz reaches usize::MAX after 49.7 days.
        self.index = self.index.wrapping_add(1);
        self.check_health()
    }

    /// Health check after each step: a non-finite solution (e.g. from absurd but finite input)
    /// or a covariance diagonal that is not finite and non-negative is reported, never carried.
    fn check_health(&self) -> Result<(), NavError> {
        // Sums propagate NaN and inf, so one finiteness test per group suffices (a sum can
        // only overflow when some value is already beyond 1e307: absurd either way).
        let sol =
            self.pos.sum() + self.vel.sum() + self.q.coords.sum() + self.bg.sum() + self.ba.sum();
        if !num_traits::Float::is_finite(sol) {
            return Err(NavError::NonFinite {
                what: "navigation solution",
                index: self.index,
            });
        }
        if !strapdown::covariance_healthy(&self.p) {
            return Err(NavError::NotPositiveDefinite {
                what: "state covariance P",
            });
        }
        Ok(())
    }

    /// The ZUPT measurement update (eqs. 19–21): frozen position, zero velocity, frozen
    /// attitude; Joseph form (the shared `strapdown::joseph_update`); feedback into the
    /// solution and reset.
    pub fn update(&mut self) -> Result<(), NavError> {
        // Attitude measurement: q̂ ⊗ q₀* = exp(ψ/2) for Ĉ = (I + [ψ×])·C₀.
        let dq = self.q.into_inner() * self.q0.conjugate().into_inner();
        let s = if dq.w < T::zero() {
            -T::one()
        } else {
            T::one()
        };
        let psi = Vector3::new(dq.i, dq.j, dq.k) * (lit::<T>(2.0) * s);
        let mut z = Vec9::<T>::zeros();
        z.fixed_rows_mut::<3>(0).copy_from(&(self.pos - self.pos0));
        z.fixed_rows_mut::<3>(3).copy_from(&self.vel);
        z.fixed_rows_mut::<3>(6).copy_from(&psi);

        // H = [I₉ 0]: the shared Joseph-form kernel with H·P and S read off P.
        let g =
            strapdown::gain_leading(&self.p, &self.r_diag, "innovation covariance S = HPHᵀ + R")?;
        self.last_nis = z.dot(&g.chol.solve(&z));
        let dx = strapdown::joseph_update(&mut self.p, &z, &g)?;
        // Feedback (δx = estimate − truth) and reset.
        self.pos -= dx.fixed_rows::<3>(0);
        self.vel -= dx.fixed_rows::<3>(3);
        let dpsi: Vector3<T> = dx.fixed_rows::<3>(6).into_owned();
        self.q = strapdown::correct_attitude(&self.q, &dpsi);
        self.ba -= dx.fixed_rows::<3>(9);
        self.bg -= dx.fixed_rows::<3>(12);
        self.n_updates = self.n_updates.saturating_add(1);
        self.check_health()
    }

    /// One sample: predict, and update when `stationary` and an update is due (cadence
    /// `update_interval_s`). `temp_c` (°C) and `deriv` are used in TCZUPT mode only (`temp_c`
    /// required there). Returns whether an update was applied.
    pub fn step<D: BiasTemperatureDerivative<T>>(
        &mut self,
        gyro_rad_s: &[T; 3],
        accel_m_s2: &[T; 3],
        temp_c: Option<T>,
        stationary: bool,
        deriv: &mut D,
    ) -> Result<bool, NavError> {
        let mut rate = Vector3::zeros();
        if self.cfg.mode == Mode::Tczupt {
            let temp = temp_c.ok_or(NavError::InvalidParameter {
                what: "temp_c",
                reason: "TCZUPT needs the die temperature",
            })?;
            if !num_traits::Float::is_finite(temp) {
                return Err(NavError::NonFinite {
                    what: "temp_c",
                    index: self.index,
                });
            }
            let dtdt = self.slope.push(temp);
            self.last_dtemp_dt = dtdt;
            rate = deriv.dbias_dtemp(self.index, temp) * dtdt;
        }
        self.predict(gyro_rad_s, accel_m_s2, &rate)?;
        if stationary && !self.was_stationary {
            // A new rest period after motion: the unit may have moved and turned, so the
            // position and attitude references are re-frozen at the current solution (only
            // the zero-velocity measurement stays absolute).
            self.q0 = self.q;
            self.pos0 = self.pos;
        }
        self.was_stationary = stationary;
        self.since_update += 1;
        if self.since_update >= self.steps_per_update {
            self.since_update = 0;
            if stationary {
                self.update()?;
                return Ok(true);
            }
        }
        Ok(false)
    }
}

/// A whole log for [`ZuptFilter::run_batch`]: slices of equal length `n`, sampled every
/// `dt_s`.
#[derive(Debug, Clone, Copy)]
pub struct BatchInput<'a, T> {
    /// Sample period (s).
    pub dt_s: T,
    /// Gyro output (rad/s, body), one `[x, y, z]` per sample.
    pub gyro_rad_s: &'a [[T; 3]],
    /// Accelerometer output (m/s², body).
    pub accel_m_s2: &'a [[T; 3]],
    /// Die temperature (°C); required for TCZUPT.
    pub temp_c: Option<&'a [T]>,
    /// Magnetometer (any unit, body) for a magnetic initial heading.
    pub mag: Option<&'a [[T; 3]]>,
    /// Per-sample stationarity (updates only where true); `None` = stationary throughout.
    pub stationary: Option<&'a [bool]>,
    /// Samples averaged for coarse levelling (thesis: 60 s of data).
    pub levelling_samples: usize,
    /// Initial heading.
    pub heading: HeadingSource<T>,
    /// Initial accelerometer bias estimate (m/s², body).
    pub accel_bias0_m_s2: [T; 3],
    /// Initial gyro bias estimate (rad/s, body), e.g. a residual 15 deg/h scenario. With
    /// `zero_gyro_bias` it is added to the zeroing estimate.
    pub gyro_bias0_rad_s: [T; 3],
    /// Initial zeroing (thesis §4.2.6.2): start the gyro-bias estimate from the mean gyro
    /// output over the levelling window minus the Earth rate resolved in the levelled body
    /// frame.
    pub zero_gyro_bias: bool,
}

/// Output buffers of [`ZuptFilter::run_batch`]: row `j` holds the state after sample
/// `j·decimation` (so each has `ceil(n / decimation)` rows).
#[derive(Debug)]
pub struct BatchOutput<'a, T> {
    /// Store one row every `decimation` samples (≥ 1).
    pub decimation: usize,
    /// Gyro bias estimate (rad/s, body).
    pub gyro_bias_rad_s: &'a mut [[T; 3]],
    /// Accelerometer bias estimate (m/s², body).
    pub accel_bias_m_s2: &'a mut [[T; 3]],
    /// Attitude (body → NED), scalar first.
    pub attitude: &'a mut [[T; 4]],
    /// Diagonal of P (SI units; δr, δv, ψ, δb_a, δb_g).
    pub cov_diag: &'a mut [[T; N_STATES]],
    /// dT/dt (°C/s) used by TCZUPT (0 for ZUPT).
    pub temp_rate_c_s: &'a mut [T],
}

/// What [`ZuptFilter::run_batch`] returns besides the histories.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BatchSummary<T> {
    /// Levelled initial attitude (body → NED), scalar first.
    pub initial_attitude: [T; 4],
    /// Number of ZUPT updates applied.
    pub updates: usize,
    /// Mean normalised innovation squared over the updates (≈ 9 when consistent).
    pub mean_nis: T,
}

impl<T: Real> ZuptFilter<T> {
    /// Runs a whole log: coarse levelling over the first `levelling_samples`, then the filter
    /// over every sample, writing decimated histories into `out`. No allocation.
    pub fn run_batch<D: BiasTemperatureDerivative<T>>(
        config: ZuptConfig<T>,
        input: &BatchInput<'_, T>,
        deriv: &mut D,
        out: &mut BatchOutput<'_, T>,
    ) -> Result<BatchSummary<T>, NavError> {
        let n = input.gyro_rad_s.len();
        if n < 2 {
            return Err(NavError::TooShort {
                what: "gyro_rad_s",
                len: n,
                min: 2,
            });
        }
        let check_len = |what: &'static str, got: usize| {
            if got == n {
                Ok(())
            } else {
                Err(NavError::LengthMismatch {
                    what,
                    expected: n,
                    got,
                })
            }
        };
        check_len("accel_m_s2", input.accel_m_s2.len())?;
        if let Some(t) = input.temp_c {
            check_len("temp_c", t.len())?;
        } else if config.mode == Mode::Tczupt {
            return Err(NavError::InvalidParameter {
                what: "temp_c",
                reason: "TCZUPT needs the die temperature",
            });
        }
        if let Some(m) = input.mag {
            check_len("mag", m.len())?;
        }
        if let Some(s) = input.stationary {
            check_len("stationary", s.len())?;
        }
        if out.decimation == 0 {
            return Err(NavError::InvalidParameter {
                what: "decimation",
                reason: "must be ≥ 1",
            });
        }
        let rows = n.div_ceil(out.decimation);
        check_len_rows(rows, out)?;

        let mut lev = Levelling::new();
        let m = input.levelling_samples.clamp(1, n);
        let mut sum_w = Vector3::zeros();
        for k in 0..m {
            let mag = input.mag.map(|v| &v[k]);
            lev.push(&input.accel_m_s2[k], mag)
                .map_err(|e| reindex(e, k))?;
            finite3("gyro_rad_s", k, &input.gyro_rad_s[k])?;
            sum_w += Vector3::from(input.gyro_rad_s[k]);
        }
        let q0 = lev.attitude(input.heading)?;
        let mut bg0 = Vector3::from(input.gyro_bias0_rad_s);
        if input.zero_gyro_bias {
            let w_b = quat_to_dcm(&q0).transpose() * earth::earth_rate_ned(config.latitude_rad);
            bg0 += sum_w / crate::scalar::from_usize::<T>(m) - w_b;
        }
        let mut f = Self::new(
            config,
            q0,
            Vector3::from(input.accel_bias0_m_s2),
            bg0,
            input.dt_s,
        )?;
        let mut nis_sum = T::zero();
        for k in 0..n {
            let temp = input.temp_c.map(|t| t[k]);
            let stat = input.stationary.is_none_or(|s| s[k]);
            if f.step(
                &input.gyro_rad_s[k],
                &input.accel_m_s2[k],
                temp,
                stat,
                deriv,
            )? {
                nis_sum += f.last_nis;
            }
            if k % out.decimation == 0 {
                let j = k / out.decimation;
                out.gyro_bias_rad_s[j] = f.bg.into();
                out.accel_bias_m_s2[j] = f.ba.into();
                out.attitude[j] = quat_to_array(&f.q);
                for i in 0..N_STATES {
                    out.cov_diag[j][i] = f.p[(i, i)];
                }
                out.temp_rate_c_s[j] = f.last_dtemp_dt;
            }
        }
        let mean_nis = if f.n_updates > 0 {
            nis_sum / crate::scalar::from_usize(f.n_updates)
        } else {
            T::zero()
        };
        Ok(BatchSummary {
            initial_attitude: quat_to_array(&q0),
            updates: f.n_updates,
            mean_nis,
        })
    }
}

fn reindex(e: NavError, k: usize) -> NavError {
    match e {
        NavError::NonFinite { what, .. } => NavError::NonFinite { what, index: k },
        other => other,
    }
}

fn check_len_rows<T>(rows: usize, out: &BatchOutput<'_, T>) -> Result<(), NavError> {
    let lens: [(&'static str, usize); 5] = [
        ("out.gyro_bias_rad_s", out.gyro_bias_rad_s.len()),
        ("out.accel_bias_m_s2", out.accel_bias_m_s2.len()),
        ("out.attitude", out.attitude.len()),
        ("out.cov_diag", out.cov_diag.len()),
        ("out.temp_rate_c_s", out.temp_rate_c_s.len()),
    ];
    for (what, got) in lens {
        if got != rows {
            return Err(NavError::LengthMismatch {
                what,
                expected: rows,
                got,
            });
        }
    }
    Ok(())
}
