//! Binding of `nav_core::earth` (scalar helpers; the Python `uasnav.earth` is the public API,
//! these exist so that tests can compare the Rust model the filter uses with it).
use nav_core::earth;
use pyo3::prelude::*;

use crate::errors::input_error;

fn finite(py: Python<'_>, what: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(input_error(
            py,
            format!("{what}: must be finite, got {v:?}"),
        ))
    }
}

/// A geodetic latitude: finite and within ±π/2 (anything else is not a place on Earth and
/// would return a number that looks valid).
fn latitude(py: Python<'_>, v: f64) -> PyResult<f64> {
    let lat = finite(py, "latitude_rad", v)?;
    if lat.abs() > std::f64::consts::FRAC_PI_2 {
        return Err(input_error(
            py,
            format!("latitude_rad: must be within ±π/2 rad, got {lat:?}"),
        ));
    }
    Ok(lat)
}

/// A result that overflowed (e.g. a height of 1e300 m) is an error, not `inf`.
fn finite_out(py: Python<'_>, what: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(input_error(
            py,
            format!("{what}: the result is not finite ({v}); check the inputs' magnitude"),
        ))
    }
}

/// WGS-84 normal gravity (m/s²) at geodetic latitude (rad) and ellipsoidal height (m).
#[pyfunction]
fn earth_normal_gravity(py: Python<'_>, latitude_rad: f64, height_m: f64) -> PyResult<f64> {
    let h = finite(py, "height_m", height_m)?;
    if h.abs() > earth::MAX_HEIGHT_M {
        return Err(input_error(
            py,
            format!(
                "height_m: must be within ±{} m of the ellipsoid, got {h:?}",
                earth::MAX_HEIGHT_M
            ),
        ));
    }
    let g = earth::normal_gravity(latitude(py, latitude_rad)?, h);
    finite_out(py, "normal gravity", g)
}

/// Earth rotation rate resolved in NED (rad/s) at geodetic latitude (rad).
#[pyfunction]
fn earth_rate_ned(py: Python<'_>, latitude_rad: f64) -> PyResult<[f64; 3]> {
    Ok(earth::earth_rate_ned(latitude(py, latitude_rad)?).into())
}

/// Meridian and transverse radii of curvature (m) at geodetic latitude (rad).
#[pyfunction]
fn earth_radii(py: Python<'_>, latitude_rad: f64) -> PyResult<(f64, f64)> {
    let lat = latitude(py, latitude_rad)?;
    Ok((earth::meridian_radius(lat), earth::transverse_radius(lat)))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(earth_normal_gravity, m)?)?;
    m.add_function(wrap_pyfunction!(earth_rate_ned, m)?)?;
    m.add_function(wrap_pyfunction!(earth_radii, m)?)?;
    Ok(())
}
