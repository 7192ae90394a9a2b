//! χ² quantiles for the FDI detection threshold, without `std` or tables.
//!
//! `dof = 1` and `dof = 2` are exact (`z²_{(1+p)/2}` and `−2·ln(1−p)`); larger `dof` use the
//! Wilson–Hilferty cube-root normal approximation (Wilson & Hilferty 1931), whose relative
//! error at the 1−10⁻³…1−10⁻⁶ quantiles used for fault detection is below 1 % for
//! `dof ≥ 3` (tested against scipy in `tests/test_redundancy.py`). The normal quantile is
//! Acklam's rational approximation (relative error < 1.2·10⁻⁹).
use crate::scalar::{from_usize, lit};
use crate::{NavError, Real};

/// Standard normal quantile `Φ⁻¹(p)` for `p ∈ (0, 1)` (Acklam's algorithm).
pub fn normal_quantile<T: Real>(p: T) -> Result<T, NavError> {
    if !(p > T::zero() && p < T::one()) {
        return Err(NavError::InvalidParameter {
            what: "probability",
            reason: "must lie strictly between 0 and 1",
        });
    }
    let a = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    let b = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    let c = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    let d = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let p_low = lit::<T>(0.02425);
    let poly = |co: &[f64], x: T| co.iter().fold(T::zero(), |acc, &k| acc * x + lit(k));
    let tail = |q: T| {
        let q = num_traits::Float::sqrt(lit::<T>(-2.0) * num_traits::Float::ln(q));
        poly(&c, q) / (poly(&d, q) * q + T::one())
    };
    Ok(if p < p_low {
        tail(p)
    } else if p > T::one() - p_low {
        -tail(T::one() - p)
    } else {
        let q = p - lit(0.5);
        let r = q * q;
        poly(&a, r) * q / (poly(&b, r) * r + T::one())
    })
}

/// Upper quantile of the χ² distribution with `dof` degrees of freedom for a false-alarm
/// probability `p_fa`: the threshold `T` with `P(χ²_dof > T) = p_fa`.
pub fn chi2_threshold<T: Real>(dof: usize, p_fa: T) -> Result<T, NavError> {
    if dof == 0 {
        return Err(NavError::InvalidParameter {
            what: "dof",
            reason: "a parity test needs at least one redundant axis",
        });
    }
    let one = T::one();
    match dof {
        1 => {
            let z = normal_quantile(one - p_fa * lit(0.5))?;
            Ok(z * z)
        }
        2 => {
            normal_quantile(p_fa)?; // validates p_fa
            Ok(lit::<T>(-2.0) * num_traits::Float::ln(p_fa))
        }
        _ => {
            let z = normal_quantile(one - p_fa)?;
            let k = from_usize::<T>(dof);
            let s = lit::<T>(2.0) / (lit::<T>(9.0) * k);
            let c = one - s + z * num_traits::Float::sqrt(s);
            Ok(k * c * c * c)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_quantiles() {
        // Reference values: scipy.stats.norm.ppf / chi2.isf.
        assert!((normal_quantile(0.975f64).unwrap() - 1.959_963_984_540_054).abs() < 1e-8);
        assert!((normal_quantile(1e-6f64).unwrap() + 4.753_424_308_822_899).abs() < 1e-7);
        assert!((chi2_threshold(1, 1e-3f64).unwrap() - 10.827_566_170_662_733).abs() < 1e-6);
        assert!((chi2_threshold(2, 1e-3f64).unwrap() - 13.815_510_557_964_274).abs() < 1e-9);
        let t15 = chi2_threshold(15, 1e-4f64).unwrap();
        assert!((t15 / 44.263_224_944_174_98 - 1.0).abs() < 0.01, "{t15}");
        assert!(chi2_threshold(0, 0.01f64).is_err());
        assert!(chi2_threshold(3, 0.0f64).is_err());
        assert!(chi2_threshold(3, f64::NAN).is_err());
    }
}
