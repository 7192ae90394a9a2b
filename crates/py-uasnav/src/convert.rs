//! numpy ↔ Rust conversions with shape checks that name the argument, and integer arguments
//! whose out-of-range values raise `InputError` (pyo3's default is `OverflowError`).
use nav_core::zupt::{Discretisation, Mode};
use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyOverflowError;
use pyo3::prelude::*;
use pyo3::types::PyString;

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
    if shape.get(1) != Some(&K) {
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

/// Extracts an integer in `0..=max`; a negative or too large Python int is an `InputError`
/// naming the argument (other extraction failures, e.g. a str, stay `TypeError`).
fn uint_in(name: &str, obj: &Bound<'_, PyAny>, max: u64) -> PyResult<u64> {
    let py = obj.py();
    let range = || {
        input_error(
            py,
            format!(
                "{name}: expected an integer in 0..={max}, got {}",
                repr(obj)
            ),
        )
    };
    match obj.extract::<u64>() {
        Ok(v) if v <= max => Ok(v),
        Ok(_) => Err(range()),
        Err(e) if e.is_instance_of::<PyOverflowError>(py) => Err(range()),
        Err(e) => Err(e),
    }
}

/// A `usize` argument (see [`uint_in`]).
pub fn usize_arg(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    let v = uint_in(name, obj, u64::try_from(usize::MAX).unwrap_or(u64::MAX))?;
    usize::try_from(v).map_err(|_| input_error(obj.py(), format!("{name}: {v} is too large")))
}

/// A `u32` argument (see [`uint_in`]).
pub fn u32_arg(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<u32> {
    let v = uint_in(name, obj, u64::from(u32::MAX))?;
    u32::try_from(v).map_err(|_| input_error(obj.py(), format!("{name}: {v} is too large")))
}

/// Iterates a sequence or array argument (a str is refused: it is iterable, but never meant).
fn items<'py>(name: &str, what: &str, obj: &Bound<'py, PyAny>) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let py = obj.py();
    let refuse = || {
        input_error(
            py,
            format!("{name}: expected a sequence of {what}, got {}", repr(obj)),
        )
    };
    if obj.is_instance_of::<PyString>() {
        return Err(refuse());
    }
    obj.try_iter()
        .map_err(|_| refuse())?
        .collect::<PyResult<Vec<_>>>()
}

/// Extracts a sequence (list, tuple, 1-D array) of unsigned integers (see [`uint_in`]),
/// naming the bad element.
pub fn uint_list(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<usize>> {
    items(name, "integers", obj)?
        .iter()
        .enumerate()
        .map(|(i, x)| usize_arg(&format!("{name}[{i}]"), x))
        .collect()
}

/// Extracts a fixed-length float vector (e.g. a quaternion), as an `InputError` when the
/// length differs or an element is not a number.
pub fn floats<const N: usize>(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<[f64; N]> {
    let py = obj.py();
    let v = items(name, "floats", obj)?
        .iter()
        .enumerate()
        .map(|(i, x)| {
            x.extract::<f64>().map_err(|_| {
                input_error(
                    py,
                    format!("{name}[{i}]: expected a float, got {}", repr(x)),
                )
            })
        })
        .collect::<PyResult<Vec<f64>>>()?;
    <[f64; N]>::try_from(v.as_slice())
        .map_err(|_| input_error(py, format!("{name}: expected {N} values, got {}", v.len())))
}

/// The one mapping of a typed config object's extraction error (a missing attribute, a wrong
/// type) to an `InputError` naming the field: `config: failed to extract field … : <cause>`.
pub fn config_error(py: Python<'_>, e: PyErr) -> PyErr {
    let why = match e.cause(py) {
        Some(c) => format!(": {}", c.value(py)),
        None => String::new(),
    };
    input_error(py, format!("config: {}{why}", e.value(py)))
}

/// A filter mode by its Python name: `"classic"` (also `"zupt"`, the thesis' name of the
/// ZUPT filter's classic mode) or `"tczupt"`.
pub fn mode(py: Python<'_>, name: &str) -> PyResult<Mode> {
    match name {
        "classic" | "zupt" => Ok(Mode::Classic),
        "tczupt" => Ok(Mode::Tczupt),
        _ => Err(input_error(
            py,
            format!("mode: expected 'classic', 'zupt' or 'tczupt', got {name:?}"),
        )),
    }
}

/// A transition-matrix discretisation by its Python name.
pub fn discretisation(py: Python<'_>, name: &str) -> PyResult<Discretisation> {
    match name {
        "first_order" => Ok(Discretisation::FirstOrder),
        "second_order" => Ok(Discretisation::SecondOrder),
        _ => Err(input_error(
            py,
            format!("discretisation: expected 'first_order' or 'second_order', got {name:?}"),
        )),
    }
}

/// `repr(obj)`, shortened, for messages ("got -1", not a Rust debug dump).
pub fn repr(obj: &Bound<'_, PyAny>) -> String {
    let s = obj
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "<unprintable>".into());
    if s.chars().count() > 60 {
        format!("{}…", s.chars().take(60).collect::<String>())
    } else {
        s
    }
}

/// Defines `fn $fn(obj) -> PyResult<$t>` for `#[pyo3(from_py_with = $fn)]` on the integer
/// argument `$name` (`$conv` is [`usize_arg`] or [`u32_arg`]).
#[macro_export]
macro_rules! uint_arg {
    ($fn:ident, $name:literal, $t:ty, $conv:ident) => {
        fn $fn(obj: &pyo3::Bound<'_, pyo3::PyAny>) -> pyo3::PyResult<$t> {
            $crate::convert::$conv($name, obj)
        }
    };
}

/// Defines `fn $fn(obj) -> PyResult<Vec<usize>>` for a list-of-indices argument `$name`.
#[macro_export]
macro_rules! uint_list_arg {
    ($fn:ident, $name:literal) => {
        fn $fn(obj: &pyo3::Bound<'_, pyo3::PyAny>) -> pyo3::PyResult<Vec<usize>> {
            $crate::convert::uint_list($name, obj)
        }
    };
}

/// Defines `fn $fn(obj) -> PyResult<[f64; $n]>` for a fixed-length float argument `$name`.
#[macro_export]
macro_rules! floats_arg {
    ($fn:ident, $name:literal, $n:literal) => {
        fn $fn(obj: &pyo3::Bound<'_, pyo3::PyAny>) -> pyo3::PyResult<[f64; $n]> {
            $crate::convert::floats::<$n>($name, obj)
        }
    };
}
