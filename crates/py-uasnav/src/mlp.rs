//! Binding of `nav_core::mlp`: a thermal-model file's networks evaluated over a whole
//! temperature series in one call.
use nav_core::mlp::json::load_thermal_model;
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyType;

use crate::convert::slice1;
use crate::errors::{input_error, IntoPy};

static DATA_FORMAT_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// A model file the Rust loader refused: `uasnav.errors.DataFormatError` (an `InputError`),
/// the class Python's own loader raises, so `uasnav.thermal.load_model` (whose load-time probe
/// evaluates through this binding) reports it as a malformed file, naming the file.
fn model_file_error(py: Python<'_>, msg: String) -> PyErr {
    match DATA_FORMAT_ERROR.import(py, "uasnav.errors", "DataFormatError") {
        Ok(cls) => PyErr::from_type(cls.clone(), msg),
        Err(e) => e,
    }
}

type MlpBatch<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<bool>>,
);

/// Evaluates the networks of a neural thermal-model file (its JSON text) at temperatures
/// (n,) °C: returns (value (n, k), d value/dT (n, k), clipped (n,)). With `clip` the input is
/// held inside the calibrated range (derivative 0 outside, flagged); `derivative_networks`
/// evaluates the file's networks trained on ∂b/∂T instead of the bias networks. A file the
/// loader refuses (validated fully, `nav_core::mlp::json`) raises `DataFormatError`.
#[pyfunction]
#[pyo3(signature = (model_json, temp_c, clip=true, derivative_networks=false))]
fn mlp_evaluate_model<'py>(
    py: Python<'py>,
    model_json: &str,
    temp_c: PyReadonlyArray1<'py, f64>,
    clip: bool,
    derivative_networks: bool,
) -> PyResult<MlpBatch<'py>> {
    let x = slice1(py, "temp_c", &temp_c)?;
    let nets = load_thermal_model(model_json).map_err(|e| model_file_error(py, e.to_string()))?;
    let list = if derivative_networks {
        nets.derivative
            .ok_or_else(|| input_error(py, "model file has no derivative_models".into()))?
    } else {
        nets.bias
    };
    let out = py.detach(|| -> Result<_, nav_core::NavError> {
        let k = list.len();
        let mut value = Array2::zeros((x.len(), k));
        let mut deriv = Array2::zeros((x.len(), k));
        let mut clipped = Array1::from_elem(x.len(), false);
        let (mut v, mut d) = (vec![0.0; x.len()], vec![0.0; x.len()]);
        for ((net, mut vcol), mut dcol) in list
            .iter()
            .zip(value.columns_mut())
            .zip(deriv.columns_mut())
        {
            net.eval_batch(x, &mut v, &mut d, clip)?;
            vcol.iter_mut().zip(&v).for_each(|(slot, y)| *slot = *y);
            dcol.iter_mut().zip(&d).for_each(|(slot, y)| *slot = *y);
        }
        if clip {
            let (lo, hi) = nets.range_c;
            for (c, &t) in clipped.iter_mut().zip(x) {
                *c = t < lo || t > hi;
            }
        }
        Ok((value, deriv, clipped))
    });
    let (v, d, c) = out.py_err(py)?;
    Ok((v.into_pyarray(py), d.into_pyarray(py), c.into_pyarray(py)))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(mlp_evaluate_model, m)?)?;
    Ok(())
}
