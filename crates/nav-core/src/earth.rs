//! WGS-84 Earth model for local-level (NED) navigation: normal gravity, Earth rotation rate
//! resolved in NED, and the radii of curvature.
//!
//! Same contract as the Python `uasnav.earth` (tests compare both): gravity is the Somigliana
//! normal gravity on the ellipsoid with the second-order free-air height correction of
//! Groves (2013), *Principles of GNSS, Inertial, and Multisensor Integrated Navigation*,
//! eqs. (2.134) and (2.139); the centrifugal part is included (it is "gravity", not
//! "gravitation"), so a static accelerometer reads `−g` along the local down axis.
// No unchecked indexing in library code; a proven index carries an `allow`.
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]
use nalgebra::Vector3;

use crate::scalar::lit;
use crate::Real;

/// Earth rotation rate `ω_ie` (rad/s), WGS-84.
pub const OMEGA_IE: f64 = 7.292_115e-5;
/// Semi-major (equatorial) axis `a` (m), WGS-84.
pub const WGS84_A: f64 = 6_378_137.0;
/// Flattening `f`, WGS-84.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// First eccentricity squared `e²`, WGS-84.
pub const WGS84_E2: f64 = 6.694_379_990_14e-3;
/// Polar radius `b` (m), WGS-84.
pub const WGS84_B: f64 = 6_356_752.314_25;
/// Earth gravitational constant `μ` (m³/s²), WGS-84.
pub const WGS84_MU: f64 = 3.986_004_418e14;
/// Normal gravity at the equator `γ_e` (m/s²), WGS-84.
pub const GAMMA_EQUATOR: f64 = 9.780_325_335_9;
/// Somigliana constant `k = b·γ_p/(a·γ_e) − 1`, WGS-84.
pub const SOMIGLIANA_K: f64 = 1.931_852_652_41e-3;
/// Largest |height| (m) the second-order free-air correction is used for: 100 km, the top of
/// the atmosphere; far above, the series returns a number that only looks like gravity.
pub const MAX_HEIGHT_M: f64 = 100_000.0;

/// WGS-84 normal gravity magnitude (m/s²) at geodetic latitude `latitude_rad` (rad) and height
/// `height_m` (m above the ellipsoid).
///
/// Somigliana on the ellipsoid, `γ₀ = γ_e (1 + k sin²φ)/√(1 − e² sin²φ)` (Groves eq. 2.134),
/// times the free-air factor `1 − 2h/a·(1 + f·(1 − 2 sin²φ) + ω²a²b/μ) + 3h²/a²` (Groves
/// eq. 2.139).
pub fn normal_gravity<T: Real>(latitude_rad: T, height_m: T) -> T {
    let s2 = num_traits::Float::powi(num_traits::Float::sin(latitude_rad), 2);
    let g0 = lit::<T>(GAMMA_EQUATOR) * (T::one() + lit::<T>(SOMIGLIANA_K) * s2)
        / num_traits::Float::sqrt(T::one() - lit::<T>(WGS84_E2) * s2);
    let m = OMEGA_IE * OMEGA_IE * WGS84_A * WGS84_A * WGS84_B / WGS84_MU;
    let a = lit::<T>(WGS84_A);
    let h = height_m;
    let f = lit::<T>(WGS84_F);
    let k = T::one() + f * (T::one() - lit::<T>(2.0) * s2) + lit::<T>(m);
    g0 * (T::one() - lit::<T>(2.0) / a * k * h + lit::<T>(3.0) * h * h / (a * a))
}

/// Gravity vector in NED (m/s²): `[0, 0, g]` (down positive), `g` from [`normal_gravity`]
/// (the deflection of the vertical is neglected, as in the normal-gravity model).
pub fn gravity_ned<T: Real>(latitude_rad: T, height_m: T) -> Vector3<T> {
    Vector3::new(T::zero(), T::zero(), normal_gravity(latitude_rad, height_m))
}

/// Earth rotation `ω_ie^n` resolved in NED (rad/s): `ω_ie·[cos φ, 0, −sin φ]`.
pub fn earth_rate_ned<T: Real>(latitude_rad: T) -> Vector3<T> {
    let w = lit::<T>(OMEGA_IE);
    Vector3::new(
        w * num_traits::Float::cos(latitude_rad),
        T::zero(),
        -w * num_traits::Float::sin(latitude_rad),
    )
}

/// Meridian radius of curvature `R_N = a(1 − e²)/(1 − e² sin²φ)^{3/2}` (m), Groves eq. 2.105.
pub fn meridian_radius<T: Real>(latitude_rad: T) -> T {
    let s2 = num_traits::Float::powi(num_traits::Float::sin(latitude_rad), 2);
    let d = T::one() - lit::<T>(WGS84_E2) * s2;
    lit::<T>(WGS84_A * (1.0 - WGS84_E2)) / (d * num_traits::Float::sqrt(d))
}

/// Transverse (prime-vertical) radius of curvature `R_E = a/√(1 − e² sin²φ)` (m), Groves
/// eq. 2.106.
pub fn transverse_radius<T: Real>(latitude_rad: T) -> T {
    let s2 = num_traits::Float::powi(num_traits::Float::sin(latitude_rad), 2);
    lit::<T>(WGS84_A) / num_traits::Float::sqrt(T::one() - lit::<T>(WGS84_E2) * s2)
}

/// Geocentric radius of the ellipsoid surface `r_eS` (m) at geodetic latitude (Groves
/// eq. 2.137), used for the vertical gravity gradient `2g/r_eS`.
pub fn geocentric_radius<T: Real>(latitude_rad: T) -> T {
    let (s, c) = (
        num_traits::Float::sin(latitude_rad),
        num_traits::Float::cos(latitude_rad),
    );
    let re = transverse_radius(latitude_rad);
    let e2 = lit::<T>(WGS84_E2);
    let one_m = T::one() - e2;
    re * num_traits::Float::sqrt(c * c + one_m * one_m * s * s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gravity_matches_published_wgs84_values() {
        // WGS-84 normal gravity at the equator and the pole (NIMA TR8350.2 Table 3.4).
        assert!((normal_gravity(0.0_f64, 0.0) - 9.780_325_335_9).abs() < 1e-9);
        let gp = normal_gravity(core::f64::consts::FRAC_PI_2, 0.0);
        assert!((gp - 9.832_184_937_8).abs() < 1e-6, "{gp}");
        // 45°: the 1980 series formula 9.780327(1 + 0.0053024 sin²φ − 0.0000058 sin²2φ) gives
        // 9.8061999; it approximates Somigliana to ~2e-6 m/s².
        let g45 = normal_gravity(45.0_f64.to_radians(), 0.0);
        assert!((g45 - 9.806_199_877).abs() < 3e-6, "{g45}");
        // Free-air gradient ≈ −3.086e-6 (m/s²)/m (textbook mean value) near the surface.
        let dg = normal_gravity(45.0_f64.to_radians(), 100.0) - g45;
        assert!((dg / 100.0 + 3.086e-6).abs() < 2e-8, "{dg}");
    }

    #[test]
    fn earth_rate_and_radii() {
        let lat = 0.7_f64;
        let w = earth_rate_ned(lat);
        assert!((w.norm() - OMEGA_IE).abs() < 1e-18);
        assert!((w.z + OMEGA_IE * lat.sin()).abs() < 1e-18);
        assert_eq!(w.y, 0.0);
        // At the equator R_N = a(1 − e²), R_E = a; at the pole both are a²/b.
        assert!((meridian_radius(0.0_f64) - WGS84_A * (1.0 - WGS84_E2)).abs() < 1e-6);
        assert!((transverse_radius(0.0_f64) - WGS84_A).abs() < 1e-9);
        let pole = core::f64::consts::FRAC_PI_2;
        let ab = WGS84_A * WGS84_A / WGS84_B;
        assert!((meridian_radius(pole) - ab).abs() < 1e-3);
        assert!((transverse_radius(pole) - ab).abs() < 1e-3);
        assert!((geocentric_radius(0.0_f64) - WGS84_A).abs() < 1e-6);
        assert!((geocentric_radius(pole) - WGS84_B).abs() < 1e-3);
        // f32 agrees to single precision.
        assert!((normal_gravity(0.7_f32, 10.0) as f64 - normal_gravity(0.7, 10.0)).abs() < 1e-5);
    }
}
