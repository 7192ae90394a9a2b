//! Binding of `utm_index`: encounters (conflicts and near misses) of 4D volumes given as
//! arrays, the brute-force reference, and the earliest conflict-free departure delays.
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use utm_index::{brute_force, Encounter, IndexError, Search, SpaceTimeIndex, Volumes};

use crate::convert::rows;
use crate::errors::input_error;

type Out<'py> = (
    Bound<'py, PyArray2<u32>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
);

fn err(py: Python<'_>, e: IndexError) -> PyErr {
    input_error(py, e.to_string())
}

/// The volumes as borrowed views of the numpy arrays (zero-copy; only the offsets are
/// converted to `usize`).
#[allow(clippy::too_many_arguments)]
fn volumes<'a>(
    py: Python<'_>,
    intent: &'a PyReadonlyArray1<'_, u32>,
    alt: &'a PyReadonlyArray2<'_, f64>,
    time: &'a PyReadonlyArray2<'_, f64>,
    offsets: &PyReadonlyArray1<'_, u64>,
    vertices: &'a PyReadonlyArray2<'_, f64>,
    circle: &'a PyReadonlyArray2<'_, f64>,
) -> PyResult<Volumes<'a>> {
    let intent = intent
        .as_slice()
        .map_err(|_| input_error(py, "intent: expected a C-contiguous uint32 array".into()))?;
    let offsets: Vec<usize> = offsets
        .as_slice()
        .map_err(|_| input_error(py, "offsets: expected a C-contiguous uint64 array".into()))?
        .iter()
        .map(|&o| usize::try_from(o).unwrap_or(usize::MAX))
        .collect();
    Volumes::new(
        intent,
        rows::<2>(py, "alt", alt)?,
        rows::<2>(py, "time", time)?,
        offsets,
        rows::<2>(py, "vertices", vertices)?,
        rows::<3>(py, "circle", circle)?,
    )
    .map_err(|e| err(py, e))
}

fn export<'py>(py: Python<'py>, enc: &[Encounter]) -> PyResult<Out<'py>> {
    let k = enc.len();
    let shape_err = |_| input_error(py, "internal: encounter array shape".into());
    let pair = Array2::from_shape_vec((k, 2), enc.iter().flat_map(|e| [e.a, e.b]).collect())
        .map_err(shape_err)?;
    let time = Array2::from_shape_vec(
        (k, 2),
        enc.iter().flat_map(|e| [e.t_start, e.t_end]).collect(),
    )
    .map_err(shape_err)?;
    let dist = Array2::from_shape_vec(
        (k, 2),
        enc.iter()
            .flat_map(|e| [e.horizontal_m, e.vertical_m])
            .collect(),
    )
    .map_err(shape_err)?;
    Ok((
        pair.into_pyarray(py),
        time.into_pyarray(py),
        dist.into_pyarray(py),
    ))
}

/// Encounters of volumes of different intents: (pairs (k, 2) volume indices, overlap
/// (k, 2) s, distances (k, 2) horizontal/vertical m). `brute` selects the O(n²) reference.
#[pyfunction]
#[pyo3(signature = (intent, alt, time, offsets, vertices, circle, horizontal_m=0.0, vertical_m=0.0, threads=1, brute=false))]
#[allow(clippy::too_many_arguments)]
fn utm_encounters<'py>(
    py: Python<'py>,
    intent: PyReadonlyArray1<'py, u32>,
    alt: PyReadonlyArray2<'py, f64>,
    time: PyReadonlyArray2<'py, f64>,
    offsets: PyReadonlyArray1<'py, u64>,
    vertices: PyReadonlyArray2<'py, f64>,
    circle: PyReadonlyArray2<'py, f64>,
    horizontal_m: f64,
    vertical_m: f64,
    threads: usize,
    brute: bool,
) -> PyResult<Out<'py>> {
    let v = volumes(py, &intent, &alt, &time, &offsets, &vertices, &circle)?;
    let s = Search {
        horizontal_m,
        vertical_m,
    };
    let enc = py
        .detach(|| {
            if brute {
                brute_force(&v, &s)
            } else {
                SpaceTimeIndex::with_threads(&v, s, threads).map(|idx| idx.encounters(threads))
            }
        })
        .map_err(|e| err(py, e))?;
    export(py, &enc)
}

/// Smallest departure delay (s) of each intent in `which` that leaves it free of conflict
/// with every other intent, NaN where none within `max_delay_s`.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn utm_earliest_delays<'py>(
    py: Python<'py>,
    intent: PyReadonlyArray1<'py, u32>,
    alt: PyReadonlyArray2<'py, f64>,
    time: PyReadonlyArray2<'py, f64>,
    offsets: PyReadonlyArray1<'py, u64>,
    vertices: PyReadonlyArray2<'py, f64>,
    circle: PyReadonlyArray2<'py, f64>,
    which: PyReadonlyArray1<'py, u32>,
    max_delay_s: f64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let v = volumes(py, &intent, &alt, &time, &offsets, &vertices, &circle)?;
    let which = which
        .as_slice()
        .map_err(|_| input_error(py, "which: expected a C-contiguous uint32 array".into()))?
        .to_vec();
    let out = py
        .detach(|| -> Result<Vec<f64>, IndexError> {
            let idx = SpaceTimeIndex::new(&v, Search::default())?;
            which
                .iter()
                .map(|&i| {
                    idx.earliest_delay(i, max_delay_s)
                        .map(|d| d.unwrap_or(f64::NAN))
                })
                .collect()
        })
        .map_err(|e| err(py, e))?;
    Ok(out.into_pyarray(py))
}

/// Registers the UTM functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(utm_encounters, m)?)?;
    m.add_function(wrap_pyfunction!(utm_earliest_delays, m)?)?;
    Ok(())
}
