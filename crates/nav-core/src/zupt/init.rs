//! Initial alignment of a stationary unit: coarse levelling from averaged accelerometers and
//! heading from an input or from a levelled magnetometer with declination (thesis eq. 3).
// No unchecked indexing in library code; a proven index carries an `allow`.
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]
use nalgebra::{UnitQuaternion, Vector3};

use crate::attitude::euler321_to_quat;
use crate::error::check_finite;
use crate::scalar::from_usize;
use crate::{NavError, Real};

/// Where the initial heading comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HeadingSource<T> {
    /// True heading (yaw, rad, 3-2-1 convention) given by an external reference.
    Given(T),
    /// Heading from the averaged magnetometer, levelled with the coarse roll and pitch, plus
    /// the magnetic declination (rad, east positive): thesis eq. (3).
    Magnetic {
        /// Declination `D` (rad, positive east): true = magnetic + D.
        declination_rad: T,
    },
}

/// Accumulates the averaging ("zeroing") window of a stationary start (thesis: 60 s) and
/// produces the coarse-levelled attitude. Allocation-free; one `push` per sample.
#[derive(Debug, Clone, Copy)]
pub struct Levelling<T: Real> {
    sum_f: Vector3<T>,
    sum_m: Vector3<T>,
    n: usize,
    n_mag: usize,
}

impl<T: Real> Default for Levelling<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real> Levelling<T> {
    /// An empty accumulator.
    pub fn new() -> Self {
        Self {
            sum_f: Vector3::zeros(),
            sum_m: Vector3::zeros(),
            n: 0,
            n_mag: 0,
        }
    }

    /// Adds one accelerometer sample (specific force, m/s², body frame) and optionally one
    /// magnetometer sample (any unit, body frame). Non-finite input is an error.
    pub fn push(&mut self, accel_m_s2: &[T; 3], mag: Option<&[T; 3]>) -> Result<(), NavError> {
        check_finite("levelling accel", accel_m_s2)?;
        self.sum_f += Vector3::from(*accel_m_s2);
        self.n += 1;
        if let Some(m) = mag {
            check_finite("levelling mag", m)?;
            self.sum_m += Vector3::from(*m);
            self.n_mag += 1;
        }
        Ok(())
    }

    /// Number of accelerometer samples accumulated.
    pub fn len(&self) -> usize {
        self.n
    }

    /// True if no sample was accumulated.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Coarse-levelled attitude (body → NED). Roll and pitch from the mean specific force
    /// `f̄ = C_nᵇ·[0, 0, −g]` of a static unit: `φ = atan2(−f̄_y, −f̄_z)`,
    /// `θ = atan2(f̄_x, √(f̄_y² + f̄_z²))`; heading from `heading`.
    ///
    /// For [`HeadingSource::Magnetic`] the mean field `m̄` is levelled,
    /// `h_x = m_x cosθ + (m_y sinφ + m_z cosφ) sinθ`, `h_y = m_y cosφ − m_z sinφ`, and
    /// `ψ = atan2(−h_y, h_x) + D` (eq. 3 written for the NED/body-x-forward convention, where a
    /// unit heading east sees the horizontal field on its −y axis).
    pub fn attitude(&self, heading: HeadingSource<T>) -> Result<UnitQuaternion<T>, NavError> {
        if self.n == 0 {
            return Err(NavError::TooShort {
                what: "levelling window",
                len: 0,
                min: 1,
            });
        }
        let f = self.sum_f / from_usize::<T>(self.n);
        let horiz = num_traits::Float::sqrt(f.y * f.y + f.z * f.z);
        if f.norm() <= T::default_epsilon() {
            return Err(NavError::InvalidParameter {
                what: "levelling accel",
                reason: "mean specific force is zero (free fall?)",
            });
        }
        let roll = num_traits::Float::atan2(-f.y, -f.z);
        let pitch = num_traits::Float::atan2(f.x, horiz);
        let yaw = match heading {
            HeadingSource::Given(y) => {
                check_finite("heading", &[y])?;
                y
            }
            HeadingSource::Magnetic { declination_rad } => {
                check_finite("declination", &[declination_rad])?;
                if self.n_mag == 0 {
                    return Err(NavError::InvalidParameter {
                        what: "heading",
                        reason: "magnetic heading requested but no magnetometer samples",
                    });
                }
                let m = self.sum_m / from_usize::<T>(self.n_mag);
                let (sr, cr) = (num_traits::Float::sin(roll), num_traits::Float::cos(roll));
                let (sp, cp) = (num_traits::Float::sin(pitch), num_traits::Float::cos(pitch));
                let hx = m.x * cp + (m.y * sr + m.z * cr) * sp;
                let hy = m.y * cr - m.z * sr;
                num_traits::Float::atan2(-hy, hx) + declination_rad
            }
        };
        Ok(euler321_to_quat(roll, pitch, yaw))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::{quat_to_dcm, quat_to_euler321};

    #[test]
    fn levelling_recovers_roll_pitch_and_magnetic_heading() {
        let (roll, pitch, yaw) = (0.1_f64, -0.2, 2.5);
        let q = euler321_to_quat(roll, pitch, yaw);
        let c_nb = quat_to_dcm(&q).transpose();
        let f_b = c_nb * Vector3::new(0.0, 0.0, -9.81);
        // Field with 60° dip pointing to magnetic north, declination 0.05 rad east: magnetic
        // north is true north rotated by +D, so the field in NED is rotated by D about down.
        let d = 0.05_f64;
        let h_mag_north = Vector3::new(20.0, 0.0, 34.6);
        let rz = nalgebra::Rotation3::from_euler_angles(0.0, 0.0, d);
        let m_b = c_nb * (rz * h_mag_north);
        let mut lev = Levelling::new();
        for _ in 0..10 {
            lev.push(&f_b.into(), Some(&m_b.into())).unwrap();
        }
        let (r, p, y) = quat_to_euler321(
            &lev.attitude(HeadingSource::Magnetic { declination_rad: d })
                .unwrap(),
        );
        assert!((r - roll).abs() < 1e-12 && (p - pitch).abs() < 1e-12);
        assert!((y - yaw).abs() < 1e-12, "{y}");
        let (_, _, y2) = quat_to_euler321(&lev.attitude(HeadingSource::Given(-1.0)).unwrap());
        assert!((y2 + 1.0).abs() < 1e-12);
        assert!(Levelling::<f64>::new()
            .attitude(HeadingSource::Given(0.0))
            .is_err());
        assert!(lev.push(&[f64::NAN, 0.0, 0.0], None).is_err());
    }
}
