//! Relative alignment of redundant sensors (thesis §4.3.5, eqs. 41–45) and misalignment
//! compensation.
//!
//! Each sensor's `C_b^n` comes from an initialisation (levelling gives roll and pitch from
//! the mean specific force; heading needs a ZUPT/magnetic initialisation). Eq. (45) gives the
//! rotation from the reference sensor to sensor `i`: `C_br^bi = (C_bi^n)ᵀ·C_br^n`.
//! Levelling alone leaves the relative heading unobserved, so [`wahba`] also estimates the
//! full relative rotation from vectors both sensors measured at the same instants (the mean
//! specific force in two or more static attitudes, or rate vectors during motion).
use nalgebra::{Matrix3, Vector3};

use crate::scalar::lit;
use crate::{NavError, Real};

/// Roll and pitch (rad) of a static sensor from its mean specific force `f_b` (m/s², body
/// frame; NED convention, so a level sensor reads `[0, 0, −g]`).
pub fn level<T: Real>(f_b: &Vector3<T>) -> Result<(T, T), NavError> {
    if f_b.iter().any(|v| !num_traits::Float::is_finite(*v)) || f_b.norm() <= T::zero() {
        return Err(NavError::InvalidParameter {
            what: "specific force",
            reason: "must be finite and non-zero to level",
        });
    }
    let roll = num_traits::Float::atan2(-f_b.y, -f_b.z);
    let pitch = num_traits::Float::atan2(
        f_b.x,
        num_traits::Float::sqrt(f_b.y * f_b.y + f_b.z * f_b.z),
    );
    Ok((roll, pitch))
}

/// Eq. (45): rotation from the reference sensor frame to sensor `i`'s frame,
/// `C_br^bi = (C_bi^n)ᵀ · C_br^n`, with eq. (44) `C_n^b = (C_b^n)ᵀ`.
pub fn relative_rotation<T: Real>(c_bi_n: &Matrix3<T>, c_br_n: &Matrix3<T>) -> Matrix3<T> {
    c_bi_n.transpose() * c_br_n
}

/// Least-squares rotation `C` (reference → sensor) with `v_sensor,k ≈ C·v_ref,k` for paired
/// observations (Wahba's problem, solved by SVD with the determinant fixed to +1).
///
/// Needs at least two non-parallel pairs; weights are per pair (non-negative).
pub fn wahba<T: Real>(
    v_ref: &[Vector3<T>],
    v_sensor: &[Vector3<T>],
    weights: &[T],
) -> Result<Matrix3<T>, NavError> {
    if v_ref.len() != v_sensor.len() || weights.len() != v_ref.len() {
        return Err(NavError::LengthMismatch {
            what: "wahba pairs",
            expected: v_ref.len(),
            got: v_sensor.len().min(weights.len()),
        });
    }
    // The solution does not depend on the weights' scale: normalise them by the largest so
    // that weights near f64::MAX do not overflow B (or the SVD's internal squares).
    let w_max = weights
        .iter()
        .fold(T::zero(), |m, w| num_traits::Float::max(m, *w));
    let w_scale = if w_max > T::zero() && num_traits::Float::is_finite(w_max) {
        T::one() / w_max
    } else {
        T::one()
    };
    let mut b = Matrix3::zeros();
    for (k, ((r, s), w)) in v_ref.iter().zip(v_sensor).zip(weights).enumerate() {
        if r.iter()
            .chain(s.iter())
            .any(|v| !num_traits::Float::is_finite(*v))
            || !num_traits::Float::is_finite(*w)
            || *w < T::zero()
        {
            return Err(NavError::NonFinite {
                what: "wahba pair",
                index: k,
            });
        }
        b += s * r.transpose() * (*w * w_scale);
    }
    if !b.iter().all(|v| num_traits::Float::is_finite(*v)) {
        return Err(NavError::NonFinite {
            what: "wahba attitude profile matrix (vectors too large)",
            index: 0,
        });
    }
    let svd = b.svd(true, true);
    let (u, vt) = match (svd.u, svd.v_t) {
        (Some(u), Some(vt)) => (u, vt),
        _ => {
            return Err(NavError::NotPositiveDefinite {
                what: "wahba attitude profile matrix",
            })
        }
    };
    let sv = svd.singular_values;
    let hi = num_traits::Float::max(sv[0], num_traits::Float::max(sv[1], sv[2]));
    let lo = num_traits::Float::min(sv[0], num_traits::Float::min(sv[1], sv[2]));
    let mid = sv[0] + sv[1] + sv[2] - hi - lo;
    // `!(mid > …)` also refuses NaN singular values (max/min would hide them in hi/lo).
    if !(hi > T::zero()) || !(mid > hi * lit(1e-6)) || !num_traits::Float::is_finite(mid) {
        return Err(NavError::InvalidParameter {
            what: "wahba pairs",
            reason: "need at least two non-parallel vector pairs",
        });
    }
    let d = (u * vt).determinant();
    let m = Matrix3::from_diagonal(&Vector3::new(T::one(), T::one(), d));
    let c = u * m * vt;
    if !c.iter().all(|v| num_traits::Float::is_finite(*v)) {
        return Err(NavError::NotPositiveDefinite {
            what: "wahba attitude profile matrix",
        });
    }
    Ok(c)
}

/// Small-angle misalignment (rad, rotation vector) of an estimated relative rotation with
/// respect to the nominal one: `C_est = exp([φ×])·C_nominal`.
pub fn misalignment<T: Real>(c_est: &Matrix3<T>, c_nominal: &Matrix3<T>) -> Vector3<T> {
    let e = c_est * c_nominal.transpose();
    // Skew part of exp([φ×]) ≈ I + [φ×].
    Vector3::new(
        (e[(2, 1)] - e[(1, 2)]) * lit(0.5),
        (e[(0, 2)] - e[(2, 0)]) * lit(0.5),
        (e[(1, 0)] - e[(0, 1)]) * lit(0.5),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::{euler321_to_quat, quat_to_dcm};

    fn dcm(r: f64, p: f64, y: f64) -> Matrix3<f64> {
        quat_to_dcm(&euler321_to_quat(r, p, y))
    }

    #[test]
    fn level_recovers_roll_pitch() {
        let c_bn = dcm(0.2, -0.3, 1.0);
        let f_b = c_bn.transpose() * Vector3::new(0.0, 0.0, -9.81);
        let (r, p) = level(&f_b).unwrap();
        assert!((r - 0.2).abs() < 1e-12 && (p + 0.3).abs() < 1e-12);
        assert!(level(&Vector3::<f64>::zeros()).is_err());
    }

    #[test]
    fn eq45_and_wahba_recover_known_mounting_errors() {
        // Reference sensor and sensor i with a known relative rotation (a cube face change
        // plus a 1° class mounting error).
        let c_rel = dcm(0.012, -0.008, 0.015) * dcm(core::f64::consts::FRAC_PI_2, 0.0, 0.0);
        let c_br_n = dcm(0.1, 0.05, 0.7);
        let c_bi_n = c_br_n * c_rel.transpose();
        let est = relative_rotation(&c_bi_n, &c_br_n);
        assert!((est - c_rel).amax() < 1e-12);
        // Gravity seen in three static attitudes by both sensors.
        let mut vr = [Vector3::zeros(); 3];
        let mut vs = [Vector3::zeros(); 3];
        for (k, (r, p)) in [(0.0, 0.0), (1.2, 0.0), (0.0, -1.0)].iter().enumerate() {
            let c = dcm(*r, *p, 0.3);
            vr[k] = c.transpose() * Vector3::new(0.0, 0.0, -9.81);
            vs[k] = c_rel * vr[k];
        }
        let w = wahba(&vr, &vs, &[1.0; 3]).unwrap();
        assert!((w - c_rel).amax() < 1e-12);
        let nominal = dcm(core::f64::consts::FRAC_PI_2, 0.0, 0.0);
        let phi = misalignment(&w, &nominal);
        let truth = misalignment(&c_rel, &nominal);
        assert!((phi - truth).amax() < 1e-12 && truth.norm() > 0.01);
        assert!(wahba(&vr[..1], &vs[..1], &[1.0]).is_err());
    }
}
