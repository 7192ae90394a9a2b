//! Binding of `csv_chunk`: whole lines of a numeric CSV file (bytes) into an (m, k) float64
//! array, parsed on every core with the GIL released, or `None` for the row-by-row reader.
use csv_chunk::{cores, line_breaks, parse, Layout};
use numpy::ndarray::{Array2, ShapeBuilder};
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::errors::input_error;
use crate::{uint_arg, uint_list_arg};

uint_arg!(width_arg, "width", usize, usize_arg);
uint_arg!(threads_arg, "threads", usize, usize_arg);
uint_list_arg!(columns_arg, "columns");

fn end_arg(obj: &Bound<'_, PyAny>) -> PyResult<Option<usize>> {
    if obj.is_none() {
        return Ok(None);
    }
    crate::convert::usize_arg("end", obj).map(Some)
}

/// The rows of `chunk[:end]` (bytes of whole lines below the header row) as an
/// (m, len(columns)) Fortran-order float64 array of the cells at `columns`, or None when some
/// line needs the row-by-row reader (see the `csv_chunk` crate). `threads` 0: one per core.
#[pyfunction]
#[pyo3(signature = (chunk, width, columns, exact_width, nan_ok=false, threads=0, end=None))]
#[allow(clippy::too_many_arguments)] // the Python signature
fn csv_parse_chunk<'py>(
    py: Python<'py>,
    chunk: &Bound<'py, PyBytes>,
    #[pyo3(from_py_with = width_arg)] width: usize,
    #[pyo3(from_py_with = columns_arg)] columns: Vec<usize>,
    exact_width: bool,
    nan_ok: bool,
    #[pyo3(from_py_with = threads_arg)] threads: usize,
    #[pyo3(from_py_with = end_arg)] end: Option<usize>,
) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
    if let Some(j) = columns.iter().find(|&&j| j >= width) {
        return Err(input_error(
            py,
            format!("columns: {j} is not below width {width}"),
        ));
    }
    let layout = Layout {
        width,
        columns: &columns,
        exact_width,
        nan_ok,
    };
    let parts = if threads == 0 { cores() } else { threads };
    // bytes objects are immutable: the text is read in place while other threads run
    let text = prefix(py, chunk.as_bytes(), end)?;
    let Some(table) = py.detach(|| parse(text, &layout, parts)) else {
        return Ok(None);
    };
    let shape = (table.rows, columns.len()).f();
    let array = Array2::from_shape_vec(shape, table.values)
        .map_err(|e| input_error(py, format!("chunk: {e}")))?;
    Ok(Some(array.into_pyarray(py)))
}

/// Line breaks (`\n`, `\r\n`, `\r`) in `chunk[:end]`, counted with the GIL released.
#[pyfunction]
#[pyo3(signature = (chunk, end=None))]
fn csv_line_breaks(
    py: Python<'_>,
    chunk: &Bound<'_, PyBytes>,
    #[pyo3(from_py_with = end_arg)] end: Option<usize>,
) -> PyResult<usize> {
    let text = prefix(py, chunk.as_bytes(), end)?;
    Ok(py.detach(|| line_breaks(text)))
}

/// `all[..end]` (all of it for None), or an `InputError` naming `end`.
fn prefix<'a>(py: Python<'_>, all: &'a [u8], end: Option<usize>) -> PyResult<&'a [u8]> {
    match end {
        None => Ok(all),
        Some(end) => all.get(..end).ok_or_else(|| {
            input_error(
                py,
                format!("end: {end} is beyond the chunk's {} bytes", all.len()),
            )
        }),
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(csv_parse_chunk, m)?)?;
    m.add_function(wrap_pyfunction!(csv_line_breaks, m)?)?;
    Ok(())
}
