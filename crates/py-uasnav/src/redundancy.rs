//! Binding of `nav_core::redundancy`: configurations, k_r, and batch fusion / FDI / Kalman
//! over whole multi-sensor logs (one row per sample, one column per sensor axis).
use nalgebra::{Matrix3, Vector3};
use nav_core::redundancy::alignment;
use nav_core::redundancy::chi2;
use nav_core::redundancy::fusion::{parity_residuals, FdiConfig, FdiFuser};
use nav_core::redundancy::geometry::{AxisKind, Polyhedron, SensorArray};
use nav_core::redundancy::kalman::{BiasKalman, BiasKalmanConfig};
use nav_core::NavError;
use numpy::ndarray::{Array1, Array2};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
};
use pyo3::prelude::*;

use crate::convert::{rows, slice1};
use crate::errors::{input_error, IntoPy};
use crate::{uint_arg, uint_list_arg};

uint_list_arg!(counts_arg, "counts");
uint_list_arg!(sensor_of_arg, "sensor_of");
uint_arg!(dof_arg, "dof", usize, usize_arg);
uint_arg!(stuck_arg, "stuck_samples", u32, u32_arg);
uint_arg!(isolations_arg, "max_isolations", usize, usize_arg);

/// Axes capacity of the binding (3 triaxial sensors on each of the icosahedron's 20 faces).
const M: usize = 180;
/// Sensor capacity.
const S: usize = 60;

type Arr = SensorArray<f64, M>;
type Axes<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<i64>>);

fn export<'py>(py: Python<'py>, a: &Arr) -> Axes<'py> {
    let n = a.n_axes();
    let mut axes = Array2::zeros((n, 3));
    for (i, mut row) in axes.rows_mut().into_iter().enumerate() {
        row.iter_mut()
            .zip(a.axis(i).iter())
            .for_each(|(s, v)| *s = *v);
    }
    let sens = Array1::from_iter((0..n).map(|i| a.sensor_of(i) as i64));
    (axes.into_pyarray(py), sens.into_pyarray(py))
}

fn build(py: Python<'_>, axes: &PyReadonlyArray2<'_, f64>, sensor_of: &[usize]) -> PyResult<Arr> {
    let r = rows::<3>(py, "axes", axes)?;
    let v: Vec<Vector3<f64>> = r.iter().map(|a| Vector3::from(*a)).collect();
    Arr::from_axes(&v, sensor_of, 1e-6).py_err(py)
}

fn matrix<'py>(
    py: Python<'py>,
    a: &PyReadonlyArray2<'py, f64>,
    name: &str,
) -> PyResult<Matrix3<f64>> {
    let r = rows::<3>(py, name, a)?;
    if r.len() != 3 {
        return Err(input_error(
            py,
            format!("{name}: expected shape (3, 3), got ({}, 3)", r.len()),
        ));
    }
    Ok(Matrix3::from_row_iterator(r.iter().flatten().copied()))
}

fn check_len(py: Python<'_>, name: &str, got: usize, n: usize) -> PyResult<()> {
    if got != n {
        return Err(input_error(
            py,
            format!("{name}: expected length {n} (one per sensor axis), got {got}"),
        ));
    }
    Ok(())
}

/// A 3×3 nalgebra matrix as a (3, 3) ndarray (row-major).
fn mat3(py: Python<'_>, c: &Matrix3<f64>) -> PyResult<Array2<f64>> {
    // nalgebra stores column-major: the transpose's storage is the row-major order.
    Array2::from_shape_vec((3, 3), c.transpose().iter().copied().collect())
        .map_err(|e| input_error(py, format!("internal: 3x3 result: {e}")))
}

/// A batch call's inputs: the configuration, the (m, n) samples as one C-contiguous slice
/// with their row count m, and the per-axis sigma (n,), every shape checked against n_axes.
struct Batch<'a> {
    array: Arr,
    z: &'a [f64],
    m: usize,
    sigma: &'a [f64],
}

impl<'a> Batch<'a> {
    fn new(
        py: Python<'_>,
        axes: &PyReadonlyArray2<'_, f64>,
        sensor_of: &[usize],
        z: &'a PyReadonlyArray2<'_, f64>,
        sigma: &'a PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Self> {
        let array = build(py, axes, sensor_of)?;
        let n = array.n_axes();
        let (m, cols) = z.as_array().dim();
        if cols != n {
            return Err(input_error(
                py,
                format!(
                    "z: expected shape (m, {n}) (one column per sensor axis), got [{m}, {cols}]"
                ),
            ));
        }
        let flat = z
            .as_slice()
            .map_err(|_| input_error(py, "z: expected a C-contiguous float64 array".into()))?;
        let sg = slice1(py, "sigma", sigma)?;
        check_len(py, "sigma", sg.len(), n)?;
        Ok(Self {
            array,
            z: flat,
            m,
            sigma: sg,
        })
    }

    /// The m samples in order (one value per axis each). A configuration has at least three
    /// axes (checked when it was built); `max(1)` only keeps `chunks_exact` total.
    fn samples(&self) -> std::slice::ChunksExact<'a, f64> {
        self.z.chunks_exact(self.array.n_axes().max(1))
    }
}

/// Axes (n, 3) and sensor index (n,) of counts[f] sensors on face f of a Platonic solid.
#[pyfunction]
fn redundancy_face_config<'py>(
    py: Python<'py>,
    shape: &str,
    #[pyo3(from_py_with = counts_arg)] counts: Vec<usize>,
    triaxial: bool,
) -> PyResult<Axes<'py>> {
    let p = Polyhedron::from_name(shape).py_err(py)?;
    let kind = if triaxial {
        AxisKind::Triaxial
    } else {
        AxisKind::Single
    };
    let a = Arr::from_face_counts(p, &counts, kind).py_err(py)?;
    Ok(export(py, &a))
}

/// Axes and sensor index of triaxial sensors with mountings (s, 3, 3) (IMU → sensor).
#[pyfunction]
#[pyo3(signature = (mountings, tol=1e-6))]
fn redundancy_mountings_config<'py>(
    py: Python<'py>,
    mountings: PyReadonlyArray3<'py, f64>,
    tol: f64,
) -> PyResult<Axes<'py>> {
    let v = mountings.as_array();
    let (ns, r, c) = v.dim();
    if r != 3 || c != 3 {
        return Err(input_error(
            py,
            format!("mountings: expected shape (s, 3, 3), got [{ns}, {r}, {c}]"),
        ));
    }
    // Row-major (3, 3) blocks: fill the matrix row by row.
    let ms: Vec<Matrix3<f64>> = v
        .outer_iter()
        .map(|m| Matrix3::from_row_iterator(m.iter().copied()))
        .collect();
    let mut a = Arr::empty();
    for (s, c) in ms.iter().enumerate() {
        a.push_triaxial(c, tol)
            .map_err(|e| input_error(py, format!("mountings[{s}]: {e}")))?;
    }
    a.check_observable().py_err(py)?;
    Ok(export(py, &a))
}

/// Face normals (F, 3) of a Platonic solid.
#[pyfunction]
fn redundancy_face_normals<'py>(
    py: Python<'py>,
    shape: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let p = Polyhedron::from_name(shape).py_err(py)?;
    let mut out = Array2::zeros((p.faces(), 3));
    for (f, mut row) in out.rows_mut().into_iter().enumerate() {
        let n: Vector3<f64> = p.face_normal(f).py_err(py)?;
        row.iter_mut().zip(n.iter()).for_each(|(s, v)| *s = *v);
    }
    Ok(out.into_pyarray(py))
}

/// Improvement factor k_r per IMU axis (eq. 40) of a configuration.
#[pyfunction]
fn redundancy_kr(
    py: Python<'_>,
    axes: PyReadonlyArray2<'_, f64>,
    #[pyo3(from_py_with = sensor_of_arg)] sensor_of: Vec<usize>,
) -> PyResult<[f64; 3]> {
    let a = build(py, &axes, &sensor_of)?;
    let k = a.k_r().py_err(py)?;
    Ok([k.x, k.y, k.z])
}

/// Least-squares covariance (HᵀWH)⁻¹ (3, 3) for per-axis noise sigma (n,).
#[pyfunction]
fn redundancy_ls_covariance<'py>(
    py: Python<'py>,
    axes: PyReadonlyArray2<'py, f64>,
    #[pyo3(from_py_with = sensor_of_arg)] sensor_of: Vec<usize>,
    sigma: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = build(py, &axes, &sensor_of)?;
    let s = slice1(py, "sigma", &sigma)?;
    check_len(py, "sigma", s.len(), a.n_axes())?;
    let c = a.ls_covariance(s).py_err(py)?;
    Ok(mat3(py, &c)?.into_pyarray(py))
}

/// Upper χ² quantile for dof and false-alarm probability p_fa.
#[pyfunction]
fn redundancy_chi2_threshold(
    py: Python<'_>,
    #[pyo3(from_py_with = dof_arg)] dof: usize,
    p_fa: f64,
) -> PyResult<f64> {
    chi2::chi2_threshold(dof, p_fa).py_err(py)
}

type FuseOut<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyArray2<u8>>,
);

/// Batch fusion of z (m, n): (fused (m, 3), variance (m, 3), chi2 (m,), valid (m,),
/// alarm (m,), health (m, n_sensors) bit flags). Without fdi, only non-finite samples are
/// screened out and the parity statistic is reported but not acted on.
#[pyfunction]
#[pyo3(signature = (axes, sensor_of, z, sigma, bias, fdi, p_fa=1e-6, saturation=f64::INFINITY, stuck_samples=0, max_isolations=2))]
#[allow(clippy::too_many_arguments)]
fn redundancy_fuse<'py>(
    py: Python<'py>,
    axes: PyReadonlyArray2<'py, f64>,
    #[pyo3(from_py_with = sensor_of_arg)] sensor_of: Vec<usize>,
    z: PyReadonlyArray2<'py, f64>,
    sigma: PyReadonlyArray1<'py, f64>,
    bias: PyReadonlyArray1<'py, f64>,
    fdi: bool,
    p_fa: f64,
    saturation: f64,
    #[pyo3(from_py_with = stuck_arg)] stuck_samples: u32,
    #[pyo3(from_py_with = isolations_arg)] max_isolations: usize,
) -> PyResult<FuseOut<'py>> {
    let b = Batch::new(py, &axes, &sensor_of, &z, &sigma)?;
    let (n, ns, m) = (b.array.n_axes(), b.array.n_sensors(), b.m);
    if ns > S {
        return Err(input_error(
            py,
            format!("sensor_of: at most {S} sensors, got {ns}"),
        ));
    }
    let bs = slice1(py, "bias", &bias)?;
    check_len(py, "bias", bs.len(), n)?;
    let cfg = FdiConfig {
        p_fa,
        saturation,
        stuck_samples,
        max_isolations,
    };
    let mut fuser = FdiFuser::<f64, M, S>::new(b.array, b.sigma, cfg).py_err(py)?;
    fuser.set_axis_bias(bs).py_err(py)?;
    let res = py.detach(|| -> Result<_, NavError> {
        let mut fused = Array2::from_elem((m, 3), f64::NAN);
        let mut var = Array2::from_elem((m, 3), f64::NAN);
        let mut chi = Array1::from_elem(m, f64::NAN);
        let mut valid = Array1::from_elem(m, false);
        let mut alarm = Array1::from_elem(m, false);
        let mut health = Array2::<u8>::zeros((m, ns));
        let slots = fused
            .rows_mut()
            .into_iter()
            .zip(var.rows_mut())
            .zip(chi.iter_mut())
            .zip(valid.iter_mut())
            .zip(alarm.iter_mut())
            .zip(health.rows_mut());
        for (zk, (((((mut fk, mut vk), ck), vd), al), mut hk)) in b.samples().zip(slots) {
            let out = if fdi {
                fuser.step(zk)?
            } else {
                fuser.fuse_finite(zk)?
            };
            *vd = out.valid;
            *al = out.alarm;
            hk.iter_mut()
                .zip(out.health.iter())
                .for_each(|(s, h)| *s = h.0);
            if out.valid {
                let diag = out.fused.covariance.diagonal();
                fk.iter_mut()
                    .zip(out.fused.value.iter())
                    .for_each(|(s, v)| *s = *v);
                vk.iter_mut().zip(diag.iter()).for_each(|(s, v)| *s = *v);
                *ck = out.fused.chi2;
            }
        }
        Ok((fused, var, chi, valid, alarm, health))
    });
    let (fused, var, chi, valid, alarm, health) = res.py_err(py)?;
    Ok((
        fused.into_pyarray(py),
        var.into_pyarray(py),
        chi.into_pyarray(py),
        valid.into_pyarray(py),
        alarm.into_pyarray(py),
        health.into_pyarray(py),
    ))
}

/// Least-squares residuals r = z − H·x̂ (m, n) with weights 1/sigma²; rows with a non-finite
/// sample are NaN (and excluded from learning by the caller).
#[pyfunction]
fn redundancy_parity_residuals<'py>(
    py: Python<'py>,
    axes: PyReadonlyArray2<'py, f64>,
    #[pyo3(from_py_with = sensor_of_arg)] sensor_of: Vec<usize>,
    z: PyReadonlyArray2<'py, f64>,
    sigma: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let b = Batch::new(py, &axes, &sensor_of, &z, &sigma)?;
    let n = b.array.n_axes();
    let res = py.detach(|| -> Result<_, NavError> {
        let mut out = Array2::from_elem((b.m, n), f64::NAN);
        let mut r = vec![0.0; n];
        for (zk, mut row) in b.samples().zip(out.rows_mut()) {
            if zk.iter().all(|v| v.is_finite()) {
                parity_residuals(&b.array, zk, b.sigma, &mut r)?;
                row.assign(&numpy::ndarray::ArrayView1::from(r.as_slice()));
            }
        }
        Ok(out)
    });
    Ok(res.py_err(py)?.into_pyarray(py))
}

type KfOut<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
);

/// Rate, rate σ, axis biases, bias σ.
type KfArrays = (Array2<f64>, Array2<f64>, Array2<f64>, Array2<f64>);

fn kalman_run<const K: usize>(
    b: &Batch<'_>,
    dt_s: f64,
    cfg: BiasKalmanConfig<f64>,
    zero_rate: Option<&[bool]>,
    zero_rate_sigma: f64,
) -> Result<KfArrays, NavError> {
    let (n, m) = (b.array.n_axes(), b.m);
    let mut kf = BiasKalman::<f64, K>::new(&b.array, b.sigma, cfg)?;
    let mut rate = Array2::zeros((m, 3));
    let mut rate_sd = Array2::zeros((m, 3));
    let mut bias = Array2::zeros((m, n));
    let mut bias_sd = Array2::zeros((m, n));
    let mut use_axis = vec![true; n];
    let slots = rate
        .rows_mut()
        .into_iter()
        .zip(rate_sd.rows_mut())
        .zip(bias.rows_mut())
        .zip(bias_sd.rows_mut());
    for (k, (zk, (((mut rk, mut rsk), mut bk), mut bsk))) in b.samples().zip(slots).enumerate() {
        use_axis
            .iter_mut()
            .zip(zk)
            .for_each(|(u, v)| *u = v.is_finite());
        if k > 0 {
            kf.predict(dt_s)?;
        }
        kf.update(zk, &use_axis)?;
        if zero_rate.is_some_and(|z| z.get(k).copied().unwrap_or(false)) {
            kf.update_rate(&Vector3::zeros(), zero_rate_sigma)?;
        }
        rk.iter_mut()
            .zip(kf.rate().iter())
            .for_each(|(s, v)| *s = *v);
        rsk.iter_mut()
            .zip(kf.rate_sigma().iter())
            .for_each(|(s, v)| *s = *v);
        for (i, (bs, bss)) in bk.iter_mut().zip(bsk.iter_mut()).enumerate() {
            *bs = kf.axis_bias(i);
            *bss = kf.axis_bias_sigma(i);
        }
    }
    Ok((rate, rate_sd, bias, bias_sd))
}

/// Kalman fusion with per-axis bias states over z (m, n) sampled every dt_s: (rate (m, 3),
/// rate σ (m, 3), axis biases (m, n), bias σ (m, n)). zero_rate (m,) marks samples where the
/// true rate is known to be zero (static), applied with zero_rate_sigma.
#[pyfunction]
#[pyo3(signature = (axes, sensor_of, z, sigma, dt_s, rate_psd, bias_psd, bias_sigma0, rate_sigma0, zero_rate=None, zero_rate_sigma=1e-3))]
#[allow(clippy::too_many_arguments)]
fn redundancy_kalman<'py>(
    py: Python<'py>,
    axes: PyReadonlyArray2<'py, f64>,
    #[pyo3(from_py_with = sensor_of_arg)] sensor_of: Vec<usize>,
    z: PyReadonlyArray2<'py, f64>,
    sigma: PyReadonlyArray1<'py, f64>,
    dt_s: f64,
    rate_psd: f64,
    bias_psd: f64,
    bias_sigma0: f64,
    rate_sigma0: f64,
    zero_rate: Option<Vec<bool>>,
    zero_rate_sigma: f64,
) -> PyResult<KfOut<'py>> {
    let b = Batch::new(py, &axes, &sensor_of, &z, &sigma)?;
    let (n, m) = (b.array.n_axes(), b.m);
    if let Some(zr) = &zero_rate {
        if zr.len() != m {
            return Err(input_error(
                py,
                format!("zero_rate: expected length {m}, got {}", zr.len()),
            ));
        }
    }
    let cfg = BiasKalmanConfig {
        rate_psd,
        bias_psd,
        bias_sigma0,
        rate_sigma0,
    };
    let zr = zero_rate.as_deref();
    let res = py.detach(|| {
        if n + 3 <= 21 {
            kalman_run::<21>(&b, dt_s, cfg, zr, zero_rate_sigma)
        } else if n + 3 <= 63 {
            kalman_run::<63>(&b, dt_s, cfg, zr, zero_rate_sigma)
        } else {
            Err(NavError::InvalidParameter {
                what: "sensor axes",
                reason: "the Kalman binding supports at most 60 axes",
            })
        }
    });
    let (r, rs, b, bsd) = res.py_err(py)?;
    Ok((
        r.into_pyarray(py),
        rs.into_pyarray(py),
        b.into_pyarray(py),
        bsd.into_pyarray(py),
    ))
}

/// Roll and pitch (k, 2) rad from mean specific forces (k, 3) m/s².
#[pyfunction]
fn redundancy_level<'py>(
    py: Python<'py>,
    f: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let r = rows::<3>(py, "f", &f)?;
    let mut out = Array2::zeros((r.len(), 2));
    for (k, (v, mut row)) in r.iter().zip(out.rows_mut()).enumerate() {
        let (roll, pitch) = alignment::level(&Vector3::from(*v))
            .map_err(|e| input_error(py, format!("f[{k}]: {e}")))?;
        row.assign(&numpy::ndarray::ArrayView1::from(&[roll, pitch]));
    }
    Ok(out.into_pyarray(py))
}

/// Eq. (45): C_br^bi (3, 3) = (C_bi^n)ᵀ · C_br^n.
#[pyfunction]
fn redundancy_relative_rotation<'py>(
    py: Python<'py>,
    c_bi_n: PyReadonlyArray2<'py, f64>,
    c_br_n: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = matrix(py, &c_bi_n, "c_bi_n")?;
    let b = matrix(py, &c_br_n, "c_br_n")?;
    for (name, m) in [("c_bi_n", &a), ("c_br_n", &b)] {
        // NaN in, NaN out would be a silent wrong answer; a DCM must at least be finite.
        if let Some(i) = m.transpose().iter().position(|v| !v.is_finite()) {
            return Err(input_error(
                py,
                format!(
                    "{name}: non-finite value at row {}, column {}",
                    i / 3,
                    i % 3
                ),
            ));
        }
    }
    let c = alignment::relative_rotation(&a, &b);
    Ok(mat3(py, &c)?.into_pyarray(py))
}

/// Rotation C (3, 3), reference → sensor, with v_sensor ≈ C·v_ref (Wahba, SVD).
#[pyfunction]
fn redundancy_wahba<'py>(
    py: Python<'py>,
    v_ref: PyReadonlyArray2<'py, f64>,
    v_sensor: PyReadonlyArray2<'py, f64>,
    weights: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let r: Vec<Vector3<f64>> = rows::<3>(py, "v_ref", &v_ref)?
        .iter()
        .map(|a| Vector3::from(*a))
        .collect();
    let s: Vec<Vector3<f64>> = rows::<3>(py, "v_sensor", &v_sensor)?
        .iter()
        .map(|a| Vector3::from(*a))
        .collect();
    let w = slice1(py, "weights", &weights)?;
    let c = alignment::wahba(&r, &s, w).py_err(py)?;
    Ok(mat3(py, &c)?.into_pyarray(py))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(redundancy_face_config, m)?)?;
    m.add_function(wrap_pyfunction!(redundancy_mountings_config, m)?)?;
    m.add_function(wrap_pyfunction!(redundancy_face_normals, m)?)?;
    m.add_function(wrap_pyfunction!(redundancy_kr, m)?)?;
    m.add_function(wrap_pyfunction!(redundancy_ls_covariance, m)?)?;
    m.add_function(wrap_pyfunction!(redundancy_chi2_threshold, m)?)?;
    m.add_function(wrap_pyfunction!(redundancy_fuse, m)?)?;
    m.add_function(wrap_pyfunction!(redundancy_parity_residuals, m)?)?;
    m.add_function(wrap_pyfunction!(redundancy_kalman, m)?)?;
    m.add_function(wrap_pyfunction!(redundancy_level, m)?)?;
    m.add_function(wrap_pyfunction!(redundancy_relative_rotation, m)?)?;
    m.add_function(wrap_pyfunction!(redundancy_wahba, m)?)?;
    Ok(())
}
