//! The one mapping from nav-core errors to Python exceptions (classes live in
//! `uasnav.errors`, so Python and Rust raise the same hierarchy).
use nav_core::NavError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyType;

static INPUT_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static NUMERICAL_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();

fn class<'py>(
    py: Python<'py>,
    cell: &PyOnceLock<Py<PyType>>,
    name: &str,
) -> PyResult<Bound<'py, PyType>> {
    cell.import(py, "uasnav.errors", name).cloned()
}

/// Converts a [`NavError`] into `uasnav.errors.InputError` (bad input; also a `ValueError`)
/// or `uasnav.errors.NumericalError`, keeping nav-core's message intact.
pub fn to_py(py: Python<'_>, err: NavError) -> PyErr {
    let (cell, name) = match err {
        NavError::NotPositiveDefinite { .. } => (&NUMERICAL_ERROR, "NumericalError"),
        _ => (&INPUT_ERROR, "InputError"),
    };
    match class(py, cell, name) {
        Ok(cls) => PyErr::from_type(cls, err.to_string()),
        Err(e) => e,
    }
}

/// Raises `uasnav.errors.InputError` with `msg`.
pub fn input_error(py: Python<'_>, msg: String) -> PyErr {
    match class(py, &INPUT_ERROR, "InputError") {
        Ok(cls) => PyErr::from_type(cls, msg),
        Err(e) => e,
    }
}

/// `Result<T, NavError>` → `PyResult<T>`.
pub trait IntoPy<T> {
    /// Maps the error with [`to_py`].
    fn py_err(self, py: Python<'_>) -> PyResult<T>;
}

impl<T> IntoPy<T> for Result<T, NavError> {
    fn py_err(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| to_py(py, e))
    }
}
