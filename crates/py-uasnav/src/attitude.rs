//! Binding of `nav_core::attitude`: batch calls over (n, 3) / (n, 4) arrays.
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use nav_core::attitude::{self as att, AttitudePropagator, PropagatorConfig};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2,
    PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use crate::convert::{rows, slice1};
use crate::errors::{input_error, IntoPy};

fn quats(py: Python<'_>, q: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<UnitQuaternion<f64>>> {
    rows::<4>(py, "q", q)?
        .iter()
        .enumerate()
        .map(|(i, a)| att::quat_from_array(*a).map_err(|e| input_error(py, format!("q[{i}]: {e}"))))
        .collect()
}

/// Propagates q0 through body rates (n, 3) rad/s at dt_s; returns (n, 4) quaternions after
/// each step (scalar first, body → NED).
#[pyfunction]
#[pyo3(signature = (q0, rates, dt_s, coning=false))]
fn attitude_propagate<'py>(
    py: Python<'py>,
    q0: [f64; 4],
    rates: PyReadonlyArray2<'py, f64>,
    dt_s: f64,
    coning: bool,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let r = rows::<3>(py, "rates", &rates)?;
    let q0 = att::quat_from_array(q0).py_err(py)?;
    let out = py.detach(|| -> Result<Array2<f64>, nav_core::NavError> {
        let mut out = Array2::zeros((r.len(), 4));
        let mut p = AttitudePropagator::new(q0, PropagatorConfig { coning });
        for (k, w) in r.iter().enumerate() {
            p.step(&Vector3::from(*w), dt_s).map_err(|e| match e {
                nav_core::NavError::NonFinite { what, .. } => {
                    nav_core::NavError::NonFinite { what, index: k }
                }
                other => other,
            })?;
            let a = att::quat_to_array(p.attitude());
            for (j, v) in a.iter().enumerate() {
                out[(k, j)] = *v;
            }
        }
        Ok(out)
    });
    Ok(out.py_err(py)?.into_pyarray(py))
}

/// Rotation angle θ (rad) of the drift accumulated by integrating rates (n, 3) rad/s.
#[pyfunction]
#[pyo3(signature = (rates, dt_s, coning=false))]
fn attitude_drift_angles<'py>(
    py: Python<'py>,
    rates: PyReadonlyArray2<'py, f64>,
    dt_s: f64,
    coning: bool,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let r = rows::<3>(py, "rates", &rates)?;
    let out = py.detach(|| {
        let mut theta = vec![0.0; r.len()];
        att::drift_angles(r, dt_s, PropagatorConfig { coning }, &mut theta).map(|_| theta)
    });
    Ok(out.py_err(py)?.into_pyarray(py))
}

/// First crossing time (s) of each threshold (rad) by θ sampled at dt_s; None if never.
#[pyfunction]
fn attitude_first_crossing_times(
    py: Python<'_>,
    theta: PyReadonlyArray1<'_, f64>,
    dt_s: f64,
    thresholds: Vec<f64>,
) -> PyResult<Vec<Option<f64>>> {
    let th = slice1(py, "theta", &theta)?;
    Ok(thresholds
        .iter()
        .map(|&x| att::first_crossing_time(th, dt_s, x))
        .collect())
}

/// Rotation angle θ = 2·acos(|q_s|) (rad) of each quaternion (n, 4).
#[pyfunction]
fn attitude_rotation_angle<'py>(
    py: Python<'py>,
    q: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let qs = quats(py, &q)?;
    Ok(Array1::from_iter(qs.iter().map(att::rotation_angle)).into_pyarray(py))
}

/// Quaternions (n, 4) from 3-2-1 Euler angles (n, 3) [roll, pitch, yaw] rad.
#[pyfunction]
fn attitude_euler_to_quat<'py>(
    py: Python<'py>,
    euler: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let e = rows::<3>(py, "euler", &euler)?;
    if let Some(i) = e.iter().position(|r| r.iter().any(|v| !v.is_finite())) {
        return Err(input_error(
            py,
            format!("euler: non-finite value at row {i}"),
        ));
    }
    let out = Array2::from_shape_fn((e.len(), 4), |(i, j)| {
        att::quat_to_array(&att::euler321_to_quat(e[i][0], e[i][1], e[i][2]))[j]
    });
    Ok(out.into_pyarray(py))
}

/// 3-2-1 Euler angles (n, 3) [roll, pitch, yaw] rad of quaternions (n, 4).
#[pyfunction]
fn attitude_quat_to_euler<'py>(
    py: Python<'py>,
    q: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let qs = quats(py, &q)?;
    let out = Array2::from_shape_fn((qs.len(), 3), |(i, j)| {
        let (r, p, y) = att::quat_to_euler321(&qs[i]);
        [r, p, y][j]
    });
    Ok(out.into_pyarray(py))
}

/// DCMs C_b^n (n, 3, 3) of quaternions (n, 4).
#[pyfunction]
fn attitude_quat_to_dcm<'py>(
    py: Python<'py>,
    q: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let qs = quats(py, &q)?;
    let out = Array3::from_shape_fn((qs.len(), 3, 3), |(i, r, c)| {
        att::quat_to_dcm(&qs[i])[(r, c)]
    });
    Ok(out.into_pyarray(py))
}

/// Quaternions (n, 4) of DCMs C_b^n (n, 3, 3); each must be a rotation to within tol.
#[pyfunction]
#[pyo3(signature = (dcm, tol=1e-6))]
fn attitude_dcm_to_quat<'py>(
    py: Python<'py>,
    dcm: PyReadonlyArray3<'py, f64>,
    tol: f64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let shape = dcm.shape();
    if shape[1] != 3 || shape[2] != 3 {
        return Err(input_error(
            py,
            format!("dcm: expected shape (n, 3, 3), got {shape:?}"),
        ));
    }
    let v = dcm.as_array();
    let mut out = Array2::zeros((shape[0], 4));
    for i in 0..shape[0] {
        let m = Matrix3::from_fn(|r, c| v[(i, r, c)]);
        let q = att::dcm_to_quat(&m, tol).map_err(|e| input_error(py, format!("dcm[{i}]: {e}")))?;
        for (j, x) in att::quat_to_array(&q).iter().enumerate() {
            out[(i, j)] = *x;
        }
    }
    Ok(out.into_pyarray(py))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(attitude_propagate, m)?)?;
    m.add_function(wrap_pyfunction!(attitude_drift_angles, m)?)?;
    m.add_function(wrap_pyfunction!(attitude_first_crossing_times, m)?)?;
    m.add_function(wrap_pyfunction!(attitude_rotation_angle, m)?)?;
    m.add_function(wrap_pyfunction!(attitude_euler_to_quat, m)?)?;
    m.add_function(wrap_pyfunction!(attitude_quat_to_euler, m)?)?;
    m.add_function(wrap_pyfunction!(attitude_quat_to_dcm, m)?)?;
    m.add_function(wrap_pyfunction!(attitude_dcm_to_quat, m)?)?;
    Ok(())
}
