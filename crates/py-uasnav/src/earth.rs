//! Binding of `nav_core::earth` (scalar helpers; the Python `uasnav.earth` is the public API,
//! these exist so that tests can compare the Rust model the filter uses with it).
use nav_core::earth;
use pyo3::prelude::*;

use crate::errors::input_error;

fn finite(py: Python<'_>, what: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(input_error(py, format!("{what}: must be finite, got {v}")))
    }
}

/// WGS-84 normal gravity (m/s²) at geodetic latitude (rad) and ellipsoidal height (m).
#[pyfunction]
fn earth_normal_gravity(py: Python<'_>, latitude_rad: f64, height_m: f64) -> PyResult<f64> {
    Ok(earth::normal_gravity(
        finite(py, "latitude_rad", latitude_rad)?,
        finite(py, "height_m", height_m)?,
    ))
}

/// Earth rotation rate resolved in NED (rad/s) at geodetic latitude (rad).
#[pyfunction]
fn earth_rate_ned(py: Python<'_>, latitude_rad: f64) -> PyResult<[f64; 3]> {
    Ok(earth::earth_rate_ned(finite(py, "latitude_rad", latitude_rad)?).into())
}

/// Meridian and transverse radii of curvature (m) at geodetic latitude (rad).
#[pyfunction]
fn earth_radii(py: Python<'_>, latitude_rad: f64) -> PyResult<(f64, f64)> {
    let lat = finite(py, "latitude_rad", latitude_rad)?;
    Ok((earth::meridian_radius(lat), earth::transverse_radius(lat)))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(earth_normal_gravity, m)?)?;
    m.add_function(wrap_pyfunction!(earth_rate_ned, m)?)?;
    m.add_function(wrap_pyfunction!(earth_radii, m)?)?;
    Ok(())
}
