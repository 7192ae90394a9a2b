//! Binding of `nav_core::allan` and `nav_core::noise`.
use nav_core::allan::{self, TauSpacing};
use nav_core::noise;
use nav_core::NavError;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use crate::convert::slice1;
use crate::errors::{input_error, IntoPy};
use crate::{uint_arg, uint_list_arg};

uint_arg!(n_arg, "n", usize, usize_arg);
uint_list_arg!(ms_arg, "ms");

/// Most cluster sizes the "all" spacing may return (8 MB; each size is one O(N) pass, so a
/// longer list is hours of work, not an analysis anyone runs).
const MAX_ALL_SIZES: usize = 1 << 20;

fn spacing(py: Python<'_>, s: &str) -> PyResult<TauSpacing> {
    match s {
        "octave" => Ok(TauSpacing::Octave),
        "decade" => Ok(TauSpacing::Decade),
        "all" => Ok(TauSpacing::All),
        _ => Err(input_error(
            py,
            format!("taus: unknown spacing {s:?} (expected 'octave', 'decade' or 'all')"),
        )),
    }
}

/// Cluster sizes m of a spacing for n samples.
#[pyfunction]
fn allan_cluster_sizes(
    py: Python<'_>,
    #[pyo3(from_py_with = n_arg)] n: usize,
    spacing_name: &str,
) -> PyResult<Vec<usize>> {
    let sp = spacing(py, spacing_name)?;
    let cap = match sp {
        TauSpacing::All => allan::max_cluster_size(n),
        _ => 192,
    };
    if cap > MAX_ALL_SIZES {
        return Err(input_error(
            py,
            format!(
                "taus: 'all' spacing for {n} samples is {cap} cluster sizes (at most {MAX_ALL_SIZES}); \
                 use 'octave' or 'decade'"
            ),
        ));
    }
    let mut out = vec![0usize; cap];
    let k = allan::cluster_sizes(n, sp, &mut out);
    out.truncate(k);
    Ok(out)
}

/// Cluster size for a cluster time (s) at sample period tau0_s (s).
#[pyfunction]
fn allan_cluster_size_for_tau(py: Python<'_>, tau_s: f64, tau0_s: f64) -> PyResult<usize> {
    allan::cluster_size_for_tau(tau_s, tau0_s).py_err(py)
}

type OadevArrays<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<u64>>,
    Bound<'py, PyArray1<f64>>,
);

/// Overlapping Allan variance of each column of `data` (n, k) at cluster sizes `ms`.
/// Returns (taus (len(ms),), avar (len(ms), k), n_terms (len(ms),), rel_error (len(ms),)).
#[pyfunction]
fn allan_oavar<'py>(
    py: Python<'py>,
    data: PyReadonlyArray2<'py, f64>,
    tau0_s: f64,
    #[pyo3(from_py_with = ms_arg)] ms: Vec<usize>,
) -> PyResult<OadevArrays<'py>> {
    let view = data.as_array();
    let k = view.ncols();
    if ms.is_empty() {
        return Err(input_error(py, "ms: no cluster sizes".into()));
    }
    if k == 0 {
        return Err(input_error(
            py,
            format!(
                "data: no columns (shape ({}, 0)); expected one column per axis",
                view.nrows()
            ),
        ));
    }
    let result = py.detach(
        || -> Result<Vec<Vec<allan::AllanPoint<f64>>>, (usize, NavError)> {
            // One angle buffer, reused for every column; the strided column is read in place.
            let mut phase = vec![0.0; view.nrows() + 1];
            let mut per_axis = Vec::with_capacity(k);
            for j in 0..k {
                allan::phase_from_iter(view.column(j).iter().copied(), tau0_s, &mut phase)
                    .map_err(|e| (j, e))?;
                per_axis.push(oavar_parallel(&phase, tau0_s, &ms).map_err(|e| (j, e))?);
            }
            Ok(per_axis)
        },
    );
    let per_axis = result.map_err(|(col, e)| match e {
        NavError::NonFinite { what, index } => input_error(
            py,
            format!("{what}: non-finite value (NaN or inf) at row {index}, column {col}"),
        ),
        other => crate::errors::to_py(py, other),
    })?;
    // Every column has one point per cluster size (k ≥ 1 was checked above).
    let first = per_axis
        .first()
        .ok_or_else(|| input_error(py, "data: no columns".into()))?;
    let taus: Vec<f64> = first.iter().map(|p| p.tau_s).collect();
    let n_terms: Vec<u64> = first.iter().map(|p| p.n_terms as u64).collect();
    let rel: Vec<f64> = first.iter().map(|p| p.rel_error).collect();
    let mut avar = Array2::zeros((ms.len(), k));
    for (mut col, points) in avar.columns_mut().into_iter().zip(&per_axis) {
        for (slot, p) in col.iter_mut().zip(points) {
            *slot = p.avar;
        }
    }
    // Finite data can still overflow f64 (values near 1e308, or a sample period so short
    // that 1/τ² overflows): an infinite or NaN variance is an error, never a silent answer.
    if let Some(((i, j), v)) = avar.indexed_iter().find(|(_, v)| !v.is_finite()) {
        let tau = taus.get(i).copied().unwrap_or(f64::NAN);
        return Err(input_error(
            py,
            format!(
                "data: the Allan variance of column {j} at tau = {tau:e} s is {v} (overflow: \
                 values or sample rate too large for float64); rescale the data"
            ),
        ));
    }
    Ok((
        taus.into_pyarray(py),
        avar.into_pyarray(py),
        n_terms.into_pyarray(py),
        rel.into_pyarray(py),
    ))
}

/// A cluster-size index and its result, as returned by a worker thread.
type Indexed = (usize, Result<allan::AllanPoint<f64>, NavError>);

/// Evaluates the cluster sizes on all available cores (each is an independent O(N) pass
/// over the shared, read-only angle series).
fn oavar_parallel(
    phase: &[f64],
    tau0_s: f64,
    ms: &[usize],
) -> Result<Vec<allan::AllanPoint<f64>>, NavError> {
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .min(ms.len());
    if threads <= 1 || phase.len() < 100_000 {
        return ms
            .iter()
            .map(|&m| allan::oavar_from_phase(phase, tau0_s, m))
            .collect();
    }
    // Interleave the sizes so each thread gets a similar mix of work.
    let results: Vec<Vec<Indexed>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                s.spawn(move || {
                    (t..ms.len())
                        .step_by(threads)
                        .zip(ms.iter().skip(t).step_by(threads))
                        .map(|(i, &m)| (i, allan::oavar_from_phase(phase, tau0_s, m)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_default())
            .collect()
    });
    let mut out: Vec<Option<allan::AllanPoint<f64>>> = vec![None; ms.len()];
    for (i, r) in results.into_iter().flatten() {
        if let Some(slot) = out.get_mut(i) {
            *slot = Some(r?);
        }
    }
    out.into_iter()
        .map(|p| {
            p.ok_or(NavError::InvalidParameter {
                what: "allan worker",
                reason: "a worker thread failed",
            })
        })
        .collect()
}

fn curve(taus: &[f64], avar: &[f64], rel_error: &[f64]) -> Vec<allan::AllanPoint<f64>> {
    taus.iter()
        .zip(avar)
        .zip(rel_error)
        .map(|((&t, &v), &e)| allan::AllanPoint {
            tau_s: t,
            m: 0,
            avar: v,
            adev: v.sqrt(),
            n_terms: 0,
            rel_error: e,
        })
        .collect()
}

fn curve_args<'a>(
    py: Python<'_>,
    taus: &'a PyReadonlyArray1<'_, f64>,
    avar: &'a PyReadonlyArray1<'_, f64>,
    rel_error: &'a PyReadonlyArray1<'_, f64>,
) -> PyResult<Vec<allan::AllanPoint<f64>>> {
    let (t, v, e) = (
        slice1(py, "taus", taus)?,
        slice1(py, "avar", avar)?,
        slice1(py, "rel_error", rel_error)?,
    );
    if t.len() != v.len() || t.len() != e.len() {
        return Err(input_error(
            py,
            format!(
                "taus, avar and rel_error differ in length ({}, {}, {})",
                t.len(),
                v.len(),
                e.len()
            ),
        ));
    }
    Ok(curve(t, v, e))
}

/// Five-term IEEE 952 fit: returns ([Q, N, B, K, R], [active ×5], rms relative residual).
#[pyfunction]
fn noise_fit_ieee952(
    py: Python<'_>,
    taus: PyReadonlyArray1<'_, f64>,
    avar: PyReadonlyArray1<'_, f64>,
    rel_error: PyReadonlyArray1<'_, f64>,
) -> PyResult<([f64; 5], [bool; 5], f64)> {
    let pts = curve_args(py, &taus, &avar, &rel_error)?;
    let fit = noise::fit_ieee952(&pts).py_err(py)?;
    let c = fit.coefficients;
    Ok((
        [
            c.quantization,
            c.random_walk,
            c.bias_instability,
            c.rate_random_walk,
            c.rate_ramp,
        ],
        fit.active,
        fit.rms_rel_residual,
    ))
}

/// Point readings: for Q, N, B, K, R either None or (value, segment index, slope).
#[pyfunction]
fn noise_read_points(
    py: Python<'_>,
    taus: PyReadonlyArray1<'_, f64>,
    avar: PyReadonlyArray1<'_, f64>,
    rel_error: PyReadonlyArray1<'_, f64>,
) -> PyResult<Vec<Option<(f64, usize, f64)>>> {
    let pts = curve_args(py, &taus, &avar, &rel_error)?;
    let r = noise::read_points(&pts).py_err(py)?;
    Ok([
        r.quantization,
        r.random_walk,
        r.bias_instability,
        r.rate_random_walk,
        r.rate_ramp,
    ]
    .iter()
    .map(|o| o.map(|s| (s.value, s.segment, s.slope)))
    .collect())
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(allan_cluster_sizes, m)?)?;
    m.add_function(wrap_pyfunction!(allan_cluster_size_for_tau, m)?)?;
    m.add_function(wrap_pyfunction!(allan_oavar, m)?)?;
    m.add_function(wrap_pyfunction!(noise_fit_ieee952, m)?)?;
    m.add_function(wrap_pyfunction!(noise_read_points, m)?)?;
    Ok(())
}
