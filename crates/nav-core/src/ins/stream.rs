//! The GNSS/INS filter stepped one message at a time, for a live telemetry stream.
//!
//! [`InsStream`] is causal: each IMU sample is processed when it arrives and the solution after
//! it is final. It runs the same mechanisation and updates as [`InsFilter::run_batch`] with
//! what a stream allows:
//!
//! * Start-up: the first `levelling_samples` IMU samples are averaged for roll and pitch (the
//!   vehicle at rest, as in the batch runner); the filter starts at the last of them, at the
//!   latest GNSS fix received within 1 s of it (else levelling starts again). No lag after that.
//! * Heading: reset once to the GNSS course when the ground speed first exceeds
//!   `course_min_speed_m_s` (no magnetometer in the stream).
//! * GNSS fixes are applied at the first IMU sample at or after their time stamp, in arrival
//!   order, with their age moved forward by their velocity; a fix that arrives after later IMU
//!   samples were processed is applied at the next one (older, as the filter handles it).
//! * Logging gaps: an interval longer than five nominal periods (the mean interval of the
//!   levelling window) is bridged with the last sample before it.
//! * IMU samples whose time does not increase are refused (counted, not processed).
//!
//! Nothing allocates: pending fixes sit in a fixed ring of [`PENDING_FIXES`].
use nalgebra::Vector3;

use super::filter::{FixStatus, InsFilter};
use super::InsConfig;
use crate::attitude::quat_to_array;
use crate::scalar::lit;
use crate::zupt::{HeadingSource, Levelling};
use crate::{NavError, Real};
// f64 maths without std: the trait's methods; with std the inherent ones are used.
#[allow(unused_imports)]
use num_traits::Float as _;

/// Capacity of the queue of received, not yet applied GNSS fixes; when full the oldest is
/// dropped (and counted).
pub const PENDING_FIXES: usize = 16;

/// An IMU interval longer than this many nominal periods is a logging gap.
const MAX_GAP_FACTOR: f64 = 5.0;

/// One GNSS fix as received.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GnssFix<T> {
    /// Fix time (s, the IMU's clock).
    pub t_s: f64,
    /// Latitude (rad), longitude (rad), ellipsoidal height (m).
    pub llh: [f64; 3],
    /// Velocity (m/s, NED).
    pub vel_m_s: [T; 3],
    /// Reported accuracies: horizontal (m), vertical (m), speed (m/s).
    pub acc: [T; 3],
}

/// The solution after one IMU sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamSolution<T> {
    /// Time of the IMU sample (s).
    pub t_s: f64,
    /// Latitude (rad), longitude (rad), ellipsoidal height (m).
    pub llh: [f64; 3],
    /// Velocity (m/s, NED).
    pub vel_m_s: [T; 3],
    /// Attitude (body → NED), scalar first.
    pub attitude: [T; 4],
    /// Horizontal and vertical protection levels (m).
    pub protection_m: [T; 2],
    /// Gyro bias estimate (rad/s, body).
    pub gyro_bias_rad_s: [T; 3],
    /// Accelerometer bias estimate (m/s², body).
    pub accel_bias_m_s2: [T; 3],
    /// Fixes used at this sample.
    pub fixes_used: u8,
    /// Fixes excluded (or reset on) at this sample.
    pub fixes_excluded: u8,
}

/// Running counts of an [`InsStream`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StreamCounts {
    /// IMU samples processed by the running filter.
    pub imu_samples: usize,
    /// IMU samples refused (time not increasing).
    pub imu_refused: usize,
    /// IMU logging gaps bridged.
    pub imu_gaps: usize,
    /// GNSS fixes used.
    pub fixes_used: usize,
    /// GNSS fixes excluded by the integrity tests.
    pub fixes_excluded: usize,
    /// Fixes dropped from a full pending queue.
    pub fixes_dropped: usize,
    /// Resets to GNSS after too many consecutive exclusions.
    pub gnss_resets: usize,
    /// Whether the heading was reset to the GNSS course.
    pub course_reset: bool,
}

/// The GNSS/INS filter fed one message at a time (see the module docs).
#[derive(Debug, Clone)]
pub struct InsStream<T: Real> {
    config: InsConfig<T>,
    levelling_samples: usize,
    lev: Levelling<T>,
    lev_t0: f64,
    filter: Option<InsFilter<T>>,
    last_t: f64,
    last_gyro: [T; 3],
    last_accel: [T; 3],
    dt_nominal_s: f64,
    heading_known: bool,
    pending: [Option<GnssFix<T>>; PENDING_FIXES],
    latest_fix: Option<GnssFix<T>>,
    consecutive_excluded: usize,
    counts: StreamCounts,
}

impl<T: Real> InsStream<T> {
    /// A stream filter with `config`, levelling over `levelling_samples` (≥ 2) samples.
    pub fn new(config: InsConfig<T>, levelling_samples: usize) -> Result<Self, NavError> {
        config.validate()?;
        if levelling_samples < 2 {
            return Err(NavError::InvalidParameter {
                what: "levelling_samples",
                reason: "must be ≥ 2",
            });
        }
        Ok(Self {
            config,
            levelling_samples,
            lev: Levelling::new(),
            lev_t0: f64::NAN,
            filter: None,
            last_t: f64::NEG_INFINITY,
            last_gyro: [T::zero(); 3],
            last_accel: [T::zero(); 3],
            dt_nominal_s: f64::NAN,
            heading_known: false,
            pending: [None; PENDING_FIXES],
            latest_fix: None,
            consecutive_excluded: 0,
            counts: StreamCounts::default(),
        })
    }

    /// Whether the filter runs (levelling done, initialised on a fix).
    pub fn is_running(&self) -> bool {
        self.filter.is_some()
    }

    /// Running counts.
    pub fn counts(&self) -> StreamCounts {
        self.counts
    }

    /// Queues a GNSS fix received now; applied at the first IMU sample at or after `fix.t_s`.
    pub fn push_gnss(&mut self, fix: GnssFix<T>) -> Result<(), NavError> {
        if !(fix.t_s.is_finite() && fix.llh.iter().all(|x| x.is_finite())) {
            return Err(NavError::NonFinite {
                what: "GNSS fix",
                index: 0,
            });
        }
        crate::error::check_finite("GNSS velocity", &fix.vel_m_s)?;
        crate::error::check_finite("GNSS accuracy", &fix.acc)?;
        self.latest_fix = Some(fix);
        if self.filter.is_none() {
            return Ok(());
        }
        if let Some(slot) = self.pending.iter_mut().find(|s| s.is_none()) {
            *slot = Some(fix);
            return Ok(());
        }
        // Full: drop the oldest (smallest time) fix.
        let mut oldest = 0;
        for (i, s) in self.pending.iter().enumerate() {
            if let (Some(a), Some(Some(b))) = (s, self.pending.get(oldest)) {
                if a.t_s < b.t_s {
                    oldest = i;
                }
            }
        }
        if let Some(slot) = self.pending.get_mut(oldest) {
            *slot = Some(fix);
        }
        self.counts.fixes_dropped += 1;
        Ok(())
    }

    /// Processes one IMU sample: time `t_s` (s), gyro (rad/s, body), accelerometer (m/s², body).
    /// Returns the solution once the filter runs, `None` while levelling or for a refused sample.
    pub fn push_imu(
        &mut self,
        t_s: f64,
        gyro_rad_s: [T; 3],
        accel_m_s2: [T; 3],
    ) -> Result<Option<StreamSolution<T>>, NavError> {
        if !t_s.is_finite() || t_s <= self.last_t {
            self.counts.imu_refused += 1;
            return Ok(None);
        }
        crate::error::check_finite("gyro_rad_s", &gyro_rad_s)?;
        crate::error::check_finite("accel_m_s2", &accel_m_s2)?;
        let dt_s = t_s - self.last_t;
        self.last_t = t_s;
        let (prev_gyro, prev_accel) = (self.last_gyro, self.last_accel);
        self.last_gyro = gyro_rad_s;
        self.last_accel = accel_m_s2;
        let Some(f) = self.filter.as_mut() else {
            self.level(t_s, &accel_m_s2)?;
            return Ok(None);
        };
        let gap = dt_s > MAX_GAP_FACTOR * self.dt_nominal_s;
        let (g, a) = if gap {
            (prev_gyro, prev_accel)
        } else {
            (gyro_rad_s, accel_m_s2)
        };
        self.counts.imu_gaps += usize::from(gap);
        f.predict(&g, &a, lit(dt_s), &Vector3::zeros())?;
        self.counts.imu_samples += 1;
        let mut used = 0u8;
        let mut excluded = 0u8;
        // Due fixes in time order (equal times in arrival order: the slots are filled in order
        // and a stable scan picks the first smallest).
        loop {
            let mut next: Option<usize> = None;
            for (i, s) in self.pending.iter().enumerate() {
                if let Some(fx) = s {
                    if fx.t_s <= t_s
                        && next
                            .and_then(|j| self.pending.get(j).copied().flatten())
                            .is_none_or(|b| fx.t_s < b.t_s)
                    {
                        next = Some(i);
                    }
                }
            }
            let Some(i) = next else { break };
            let Some(fx) = self.pending.get_mut(i).and_then(Option::take) else {
                break;
            };
            let f = self.filter.as_mut().ok_or(NavError::InvalidParameter {
                what: "stream",
                reason: "filter not running",
            })?;
            let floor_v = self.config.gnss_min_std_velocity_m_s;
            if !self.heading_known {
                let v = fx.vel_m_s;
                let speed = num_traits::Float::sqrt(v[0] * v[0] + v[1] * v[1]);
                if speed > self.config.course_min_speed_m_s {
                    let course = num_traits::Float::atan2(v[1], v[0]);
                    let sd = lit::<T>(5.0_f64.to_radians())
                        + num_traits::Float::max(fx.acc[2], floor_v) / speed;
                    f.reset_heading(course, sd)?;
                    self.heading_known = true;
                    self.counts.course_reset = true;
                }
            }
            let st = f.update_gnss(&fx.llh, &fx.vel_m_s, &fx.acc, t_s - fx.t_s)?;
            if matches!(st, FixStatus::Used | FixStatus::SeparationAlert) {
                self.consecutive_excluded = 0;
                self.counts.fixes_used += 1;
                used = used.saturating_add(1);
            } else {
                self.counts.fixes_excluded += 1;
                excluded = excluded.saturating_add(1);
                self.consecutive_excluded += 1;
                if self.config.reset_after_exclusions > 0
                    && self.consecutive_excluded >= self.config.reset_after_exclusions
                {
                    f.reset_to_gnss(&fx.llh, &fx.vel_m_s, &fx.acc)?;
                    self.counts.gnss_resets += 1;
                    self.consecutive_excluded = 0;
                }
            }
        }
        let f = self.filter.as_ref().ok_or(NavError::InvalidParameter {
            what: "stream",
            reason: "filter not running",
        })?;
        let (hpl, vpl) = f.protection_levels();
        let v = f.velocity_m_s();
        let bg = f.gyro_bias_rad_s();
        let ba = f.accel_bias_m_s2();
        Ok(Some(StreamSolution {
            t_s,
            llh: f.position(),
            vel_m_s: [v[0], v[1], v[2]],
            attitude: quat_to_array(f.attitude()),
            protection_m: [hpl, vpl],
            gyro_bias_rad_s: [bg[0], bg[1], bg[2]],
            accel_bias_m_s2: [ba[0], ba[1], ba[2]],
            fixes_used: used,
            fixes_excluded: excluded,
        }))
    }

    /// Levelling: average the accelerometer, then start on the latest fix within 1 s.
    fn level(&mut self, t_s: f64, accel_m_s2: &[T; 3]) -> Result<(), NavError> {
        if self.lev.is_empty() {
            self.lev_t0 = t_s;
        }
        self.lev.push(accel_m_s2, None)?;
        if self.lev.len() < self.levelling_samples {
            return Ok(());
        }
        let fix = match self.latest_fix {
            Some(fx) if (fx.t_s - t_s).abs() <= 1.0 => fx,
            _ => {
                // No fix near the end of the window: level again on newer samples.
                self.lev = Levelling::new();
                return Ok(());
            }
        };
        let q0 = self.lev.attitude(HeadingSource::Given(T::zero()))?;
        let floor_p = self.config.gnss_min_std_position_m;
        let floor_v = self.config.gnss_min_std_velocity_m_s;
        let sp = num_traits::Float::max(fix.acc[0], floor_p);
        let f = InsFilter::new(
            self.config,
            fix.llh[0],
            fix.llh[1],
            fix.llh[2],
            Vector3::from(fix.vel_m_s),
            q0,
            [sp, sp, num_traits::Float::max(fix.acc[1], floor_p)],
            [num_traits::Float::max(fix.acc[2], floor_v); 3],
        )?;
        self.dt_nominal_s = (t_s - self.lev_t0) / (self.lev.len() - 1) as f64;
        self.filter = Some(f);
        self.counts.fixes_used += 1;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fix(t: f64) -> GnssFix<f64> {
        GnssFix {
            t_s: t,
            llh: [0.8, 0.1, 100.0],
            vel_m_s: [0.0; 3],
            acc: [2.0, 3.0, 0.2],
        }
    }

    #[test]
    fn levels_then_runs_and_refuses_old_samples() {
        let mut s = InsStream::<f64>::new(InsConfig::default(), 10).unwrap();
        s.push_gnss(fix(0.0)).unwrap();
        let g = [0.0; 3];
        let a = [0.0, 0.0, -9.81];
        for k in 0..10 {
            assert!(s.push_imu(k as f64 * 0.02, g, a).unwrap().is_none());
        }
        assert!(s.is_running());
        s.push_gnss(fix(0.25)).unwrap();
        let mut used = 0;
        for k in 10..20 {
            let sol = s.push_imu(k as f64 * 0.02, g, a).unwrap().unwrap();
            used += sol.fixes_used;
            assert!(sol.llh.iter().all(|x| x.is_finite()));
        }
        assert_eq!(used, 1);
        assert!(s.push_imu(0.1, g, a).unwrap().is_none());
        assert_eq!(s.counts().imu_refused, 1);
    }

    #[test]
    fn without_a_fix_levelling_starts_again() {
        let mut s = InsStream::<f64>::new(InsConfig::default(), 5).unwrap();
        for k in 0..12 {
            s.push_imu(k as f64 * 0.02, [0.0; 3], [0.0, 0.0, -9.81])
                .unwrap();
        }
        assert!(!s.is_running());
        assert!(InsStream::<f64>::new(InsConfig::default(), 1).is_err());
    }
}
