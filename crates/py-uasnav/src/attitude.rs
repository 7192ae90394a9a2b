//! Binding of `nav_core::attitude`: batch calls over (n, 3) / (n, 4) arrays.
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use nav_core::attitude::{self as att, AttitudePropagator, PropagatorConfig};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
};
use pyo3::prelude::*;

use crate::convert::{rows, slice1};
use crate::errors::{input_error, IntoPy};
use crate::floats_arg;

floats_arg!(q0_arg, "q0", 4);

/// Every (n, k) row of `out` filled from `vals` (same length by construction).
fn fill_rows<const K: usize>(out: &mut Array2<f64>, vals: impl Iterator<Item = [f64; K]>) {
    for (mut row, v) in out.rows_mut().into_iter().zip(vals) {
        for (slot, x) in row.iter_mut().zip(v) {
            *slot = x;
        }
    }
}

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
    #[pyo3(from_py_with = q0_arg)] q0: [f64; 4],
    rates: PyReadonlyArray2<'py, f64>,
    dt_s: f64,
    coning: bool,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let r = rows::<3>(py, "rates", &rates)?;
    let q0 = att::quat_from_array(q0).py_err(py)?;
    let out = py.detach(|| -> Result<Array2<f64>, nav_core::NavError> {
        let mut out = Array2::zeros((r.len(), 4));
        let mut p = AttitudePropagator::new(q0, PropagatorConfig { coning });
        for (k, (w, mut row)) in r.iter().zip(out.rows_mut()).enumerate() {
            p.step(&Vector3::from(*w), dt_s).map_err(|e| match e {
                nav_core::NavError::NonFinite { what, .. } => {
                    nav_core::NavError::NonFinite { what, index: k }
                }
                other => other,
            })?;
            for (slot, v) in row.iter_mut().zip(att::quat_to_array(p.attitude())) {
                *slot = v;
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
    // A NaN never compares ≥, so unchecked it would read as "never crossed" (None).
    if !(dt_s.is_finite() && dt_s > 0.0) {
        return Err(input_error(
            py,
            format!("dt_s: must be finite and > 0, got {dt_s:?}"),
        ));
    }
    if let Some(i) = th.iter().position(|v| !v.is_finite()) {
        return Err(input_error(
            py,
            format!("theta: non-finite value at index {i}"),
        ));
    }
    if let Some(x) = thresholds.iter().find(|v| !v.is_finite()) {
        return Err(input_error(
            py,
            format!("thresholds: must be finite, got {x:?}"),
        ));
    }
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
    let mut out = Array2::zeros((e.len(), 4));
    fill_rows(
        &mut out,
        e.iter()
            .map(|&[r, p, y]| att::quat_to_array(&att::euler321_to_quat(r, p, y))),
    );
    Ok(out.into_pyarray(py))
}

/// 3-2-1 Euler angles (n, 3) [roll, pitch, yaw] rad of quaternions (n, 4).
#[pyfunction]
fn attitude_quat_to_euler<'py>(
    py: Python<'py>,
    q: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let qs = quats(py, &q)?;
    let mut out = Array2::zeros((qs.len(), 3));
    fill_rows(
        &mut out,
        qs.iter().map(|q| {
            let (r, p, y) = att::quat_to_euler321(q);
            [r, p, y]
        }),
    );
    Ok(out.into_pyarray(py))
}

/// DCMs C_b^n (n, 3, 3) of quaternions (n, 4).
#[pyfunction]
fn attitude_quat_to_dcm<'py>(
    py: Python<'py>,
    q: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let qs = quats(py, &q)?;
    let mut out = Array3::zeros((qs.len(), 3, 3));
    for (mut m, q) in out.outer_iter_mut().zip(&qs) {
        let c = att::quat_to_dcm(q);
        for ((r, col), slot) in m.indexed_iter_mut() {
            *slot = c.get((r, col)).copied().unwrap_or(f64::NAN);
        }
    }
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
    let v = dcm.as_array();
    let (n, r, c) = v.dim();
    if r != 3 || c != 3 {
        return Err(input_error(
            py,
            format!("dcm: expected shape (n, 3, 3), got [{n}, {r}, {c}]"),
        ));
    }
    let mut out = Array2::zeros((n, 4));
    for (i, (m, mut row)) in v.outer_iter().zip(out.rows_mut()).enumerate() {
        let mut mat = Matrix3::zeros();
        for ((r, c), x) in m.indexed_iter() {
            if let Some(slot) = mat.get_mut((r, c)) {
                *slot = *x;
            }
        }
        let q =
            att::dcm_to_quat(&mat, tol).map_err(|e| input_error(py, format!("dcm[{i}]: {e}")))?;
        for (slot, x) in row.iter_mut().zip(att::quat_to_array(&q)) {
            *slot = x;
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
