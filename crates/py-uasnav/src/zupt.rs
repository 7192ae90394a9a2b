//! Binding of `nav_core::zupt`: one call runs a whole log (GIL released).
use nav_core::zupt::{
    detect_static, BatchInput, BatchOutput, DerivativeTable, HeadingSource, NoDerivative,
    StationarityConfig, ZuptConfig, ZuptFilter, N_STATES,
};
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{self, rows, slice1};
use crate::errors::{input_error, IntoPy};
use crate::{floats_arg, uint_arg};

uint_arg!(levelling_arg, "levelling_samples", usize, usize_arg);
uint_arg!(decimation_arg, "decimation", usize, usize_arg);
uint_arg!(window_arg, "window_samples", usize, usize_arg);
floats_arg!(accel_bias0_arg, "accel_bias0", 3);
floats_arg!(gyro_bias0_arg, "gyro_bias0", 3);

/// `uasnav.zupt.FilterConfig` as it crosses: nav-core's `ZuptConfig` fields read as attributes
/// of one object, by the same names and units (SI, units in the names), types checked by PyO3;
/// `None` keeps nav-core's default.
#[derive(FromPyObject)]
struct FilterConfig {
    mode: String,
    discretisation: String,
    sigma_vrw_m_s_sqrt_s: Option<f64>,
    sigma_arw_rad_sqrt_s: Option<f64>,
    sigma_abi_m_s2: Option<f64>,
    sigma_gbi_rad_s: Option<f64>,
    meas_std_position_m: Option<f64>,
    meas_std_velocity_m_s: Option<f64>,
    meas_std_attitude_rad: Option<f64>,
    update_interval_s: Option<f64>,
    init_std_position_m: Option<f64>,
    init_std_velocity_m_s: Option<f64>,
    init_std_attitude_rad: Option<f64>,
    init_std_accel_bias_m_s2: Option<f64>,
    init_std_gyro_bias_rad_s: Option<f64>,
    latitude_rad: Option<f64>,
    height_m: Option<f64>,
    temp_slope_window_s: Option<f64>,
}

/// `slot ← value` unless the value is `None` (nav-core's default stays).
fn set<T>(slot: &mut T, value: Option<T>) {
    if let Some(v) = value {
        *slot = v;
    }
}

/// The `config` argument as nav-core's `ZuptConfig` (None: the classic filter with nav-core's
/// defaults), validated.
fn config_arg(py: Python<'_>, obj: Option<&Bound<'_, PyAny>>) -> PyResult<ZuptConfig<f64>> {
    let Some(obj) = obj else {
        let c = ZuptConfig::<f64>::default();
        c.validate().py_err(py)?;
        return Ok(c);
    };
    let a: FilterConfig = obj.extract().map_err(|e| convert::config_error(py, e))?;
    let mut c = ZuptConfig::<f64> {
        mode: convert::mode(py, &a.mode)?,
        discretisation: convert::discretisation(py, &a.discretisation)?,
        ..ZuptConfig::default()
    };
    set(&mut c.noise.sigma_vrw_m_s_sqrt_s, a.sigma_vrw_m_s_sqrt_s);
    set(&mut c.noise.sigma_arw_rad_sqrt_s, a.sigma_arw_rad_sqrt_s);
    set(&mut c.noise.sigma_abi_m_s2, a.sigma_abi_m_s2);
    set(&mut c.noise.sigma_gbi_rad_s, a.sigma_gbi_rad_s);
    set(&mut c.meas_std_position_m, a.meas_std_position_m);
    set(&mut c.meas_std_velocity_m_s, a.meas_std_velocity_m_s);
    set(&mut c.meas_std_attitude_rad, a.meas_std_attitude_rad);
    set(&mut c.update_interval_s, a.update_interval_s);
    set(&mut c.init_std_position_m, a.init_std_position_m);
    set(&mut c.init_std_velocity_m_s, a.init_std_velocity_m_s);
    set(&mut c.init_std_attitude_rad, a.init_std_attitude_rad);
    set(&mut c.init_std_accel_bias_m_s2, a.init_std_accel_bias_m_s2);
    set(&mut c.init_std_gyro_bias_rad_s, a.init_std_gyro_bias_rad_s);
    set(&mut c.latitude_rad, a.latitude_rad);
    set(&mut c.height_m, a.height_m);
    set(&mut c.temp_slope_window_s, a.temp_slope_window_s);
    c.validate().py_err(py)?;
    Ok(c)
}

/// Runs the ZUPT/TCZUPT filter over a whole log; returns a dict of decimated histories and
/// a summary (see `_core.pyi`).
#[pyfunction]
#[pyo3(signature = (gyro, accel, dt_s, *, config=None, temp=None, dbias_dtemp=None, mag=None, stationary=None,
    levelling_samples=6000, heading_rad=None, declination_rad=None,
    accel_bias0=[0.0; 3], gyro_bias0=[0.0; 3], zero_gyro_bias=true, decimation=1))]
#[allow(clippy::too_many_arguments)]
fn zupt_run<'py>(
    py: Python<'py>,
    gyro: PyReadonlyArray2<'py, f64>,
    accel: PyReadonlyArray2<'py, f64>,
    dt_s: f64,
    config: Option<Bound<'py, PyAny>>,
    temp: Option<PyReadonlyArray1<'py, f64>>,
    dbias_dtemp: Option<PyReadonlyArray2<'py, f64>>,
    mag: Option<PyReadonlyArray2<'py, f64>>,
    stationary: Option<PyReadonlyArray1<'py, bool>>,
    #[pyo3(from_py_with = levelling_arg)] levelling_samples: usize,
    heading_rad: Option<f64>,
    declination_rad: Option<f64>,
    #[pyo3(from_py_with = accel_bias0_arg)] accel_bias0: [f64; 3],
    #[pyo3(from_py_with = gyro_bias0_arg)] gyro_bias0: [f64; 3],
    zero_gyro_bias: bool,
    #[pyo3(from_py_with = decimation_arg)] decimation: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let cfg = config_arg(py, config.as_ref())?;
    let g = rows::<3>(py, "gyro", &gyro)?;
    let a = rows::<3>(py, "accel", &accel)?;
    let t = temp.as_ref().map(|x| slice1(py, "temp", x)).transpose()?;
    let d = dbias_dtemp
        .as_ref()
        .map(|x| rows::<3>(py, "dbias_dtemp", x))
        .transpose()?;
    let m = mag.as_ref().map(|x| rows::<3>(py, "mag", x)).transpose()?;
    let s = stationary
        .as_ref()
        .map(|x| {
            x.as_slice()
                .map_err(|_| input_error(py, "stationary: expected a contiguous bool array".into()))
        })
        .transpose()?;
    if let Some(d) = d {
        if d.len() != g.len() {
            return Err(input_error(
                py,
                format!("dbias_dtemp: expected {} rows, got {}", g.len(), d.len()),
            ));
        }
    }
    let heading = match (heading_rad, declination_rad) {
        (Some(h), None) => HeadingSource::Given(h),
        (None, Some(dec)) => HeadingSource::Magnetic {
            declination_rad: dec,
        },
        (None, None) => HeadingSource::Given(0.0),
        (Some(_), Some(_)) => {
            return Err(input_error(
                py,
                "heading_rad and declination_rad: give one (heading input or magnetic heading)"
                    .into(),
            ))
        }
    };
    if decimation == 0 {
        return Err(input_error(py, "decimation: must be >= 1".into()));
    }
    let n = g.len();
    let nrows = n.div_ceil(decimation);
    let input = BatchInput {
        dt_s,
        gyro_rad_s: g,
        accel_m_s2: a,
        temp_c: t,
        mag: m,
        stationary: s,
        levelling_samples,
        heading,
        accel_bias0_m_s2: accel_bias0,
        gyro_bias0_rad_s: gyro_bias0,
        zero_gyro_bias,
    };
    type Hist = (
        Vec<[f64; 3]>,
        Vec<[f64; 3]>,
        Vec<[f64; 4]>,
        Vec<[f64; N_STATES]>,
        Vec<f64>,
    );
    let result = py.detach(|| {
        let mut h: Hist = (
            vec![[0.0; 3]; nrows],
            vec![[0.0; 3]; nrows],
            vec![[0.0; 4]; nrows],
            vec![[0.0; N_STATES]; nrows],
            vec![0.0; nrows],
        );
        let mut out = BatchOutput {
            decimation,
            gyro_bias_rad_s: &mut h.0,
            accel_bias_m_s2: &mut h.1,
            attitude: &mut h.2,
            cov_diag: &mut h.3,
            temp_rate_c_s: &mut h.4,
        };
        let summary = match d {
            Some(table) => {
                ZuptFilter::run_batch(cfg, &input, &mut DerivativeTable(table), &mut out)
            }
            None => ZuptFilter::run_batch(cfg, &input, &mut NoDerivative, &mut out),
        }?;
        Ok::<_, nav_core::NavError>((h, summary))
    });
    let ((gb, ab, att, cov, tr), summary) = result.py_err(py)?;
    let dict = PyDict::new(py);
    dict.set_item("gyro_bias", to2(&gb).into_pyarray(py))?;
    dict.set_item("accel_bias", to2(&ab).into_pyarray(py))?;
    dict.set_item("attitude", to2(&att).into_pyarray(py))?;
    dict.set_item("cov_diag", to2(&cov).into_pyarray(py))?;
    dict.set_item("temp_rate", Array1::from_vec(tr).into_pyarray(py))?;
    dict.set_item("initial_attitude", summary.initial_attitude.to_vec())?;
    dict.set_item("updates", summary.updates)?;
    dict.set_item("mean_nis", summary.mean_nis)?;
    Ok(dict)
}

/// `(n, K)` array from rows (shared with `ins`).
pub(crate) fn to2<const K: usize>(v: &[[f64; K]]) -> Array2<f64> {
    let mut out = Array2::zeros((v.len(), K));
    for (mut row, r) in out.rows_mut().into_iter().zip(v) {
        row.iter_mut().zip(r).for_each(|(s, x)| *s = *x);
    }
    out
}

type StaticArrays<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<bool>>);

/// GLRT (SHOE) stationarity statistic and mask (n,) of a log with a centred window.
#[pyfunction]
#[pyo3(signature = (accel, gyro, *, sigma_accel_m_s2=0.05, sigma_gyro_rad_s=0.01,
    window_samples=25, threshold=10.0, gravity_m_s2=9.80665))]
#[allow(clippy::too_many_arguments)]
fn zupt_detect_static<'py>(
    py: Python<'py>,
    accel: PyReadonlyArray2<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    sigma_accel_m_s2: f64,
    sigma_gyro_rad_s: f64,
    #[pyo3(from_py_with = window_arg)] window_samples: usize,
    threshold: f64,
    gravity_m_s2: f64,
) -> PyResult<StaticArrays<'py>> {
    let a = rows::<3>(py, "accel", &accel)?;
    let g = rows::<3>(py, "gyro", &gyro)?;
    let cfg = StationarityConfig {
        sigma_accel_m_s2,
        sigma_gyro_rad_s,
        window_samples,
        threshold,
        gravity_m_s2,
    };
    let (stat, mask) = py
        .detach(|| {
            let mut stat = vec![0.0; a.len()];
            let mut mask = vec![false; a.len()];
            detect_static(a, g, cfg, &mut stat, &mut mask).map(|_| (stat, mask))
        })
        .py_err(py)?;
    Ok((stat.into_pyarray(py), mask.into_pyarray(py)))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(zupt_run, m)?)?;
    m.add_function(wrap_pyfunction!(zupt_detect_static, m)?)?;
    Ok(())
}
