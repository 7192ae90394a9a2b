//! numpy ↔ Rust conversions with shape checks that name the argument.
use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::errors::input_error;

/// Borrows a 1-D float64 array as a contiguous slice (zero-copy) or explains why not.
pub fn slice1<'a>(
    py: Python<'_>,
    name: &str,
    a: &'a PyReadonlyArray1<'_, f64>,
) -> PyResult<&'a [f64]> {
    a.as_slice()
        .map_err(|_| input_error(py, format!("{name}: expected a C-contiguous float64 array")))
}

/// Borrows an `(n, k)` float64 array with `k == cols` as rows of `[f64; K]` (zero-copy).
pub fn rows<'a, const K: usize>(
    py: Python<'_>,
    name: &str,
    a: &'a PyReadonlyArray2<'_, f64>,
) -> PyResult<&'a [[f64; K]]> {
    let shape = a.shape();
    if shape[1] != K {
        return Err(input_error(
            py,
            format!("{name}: expected shape (n, {K}), got {shape:?}"),
        ));
    }
    let flat = a
        .as_slice()
        .map_err(|_| input_error(py, format!("{name}: expected a C-contiguous float64 array")))?;
    // `as_chunks` is exact because the length is n·K.
    let (chunks, rest) = flat.as_chunks::<K>();
    debug_assert!(rest.is_empty());
    Ok(chunks)
}
