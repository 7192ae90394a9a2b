//! Binding of `nav_core::ins`: one call runs a whole flight (GIL released).
use nav_core::ins::{
    Discretisation, InsBatchInput, InsBatchOutput, InsConfig, InsFilter, MagnetometerAiding, Mode,
};
use nav_core::zupt::{DerivativeTable, NoDerivative};
use numpy::ndarray::Array1;
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{float_items, rows, slice1};
use crate::errors::{input_error, IntoPy};
use crate::zupt::to2;
use crate::{floats_arg, uint_arg};

uint_arg!(levelling_arg, "levelling_samples", usize, usize_arg);
uint_arg!(decimation_arg, "decimation", usize, usize_arg);
uint_arg!(window_arg, "window_fixes", usize, usize_arg);
uint_arg!(reset_arg, "reset_after_exclusions", usize, usize_arg);
floats_arg!(lever_arm_arg, "lever_arm", 3);
floats_arg!(gyro_bias0_arg, "gyro_bias0", 3);

/// Builds an `InsConfig` from `mode`, `discretisation` and a dict of SI floats named exactly
/// as the nav-core fields; an unknown key is an error.
fn config(
    py: Python<'_>,
    mode: &str,
    discretisation: &str,
    values: Option<&Bound<'_, PyDict>>,
    lever_arm: [f64; 3],
    window_fixes: usize,
) -> PyResult<InsConfig<f64>> {
    let mut c = InsConfig::<f64> {
        mode: match mode {
            "classic" => Mode::Zupt,
            "tczupt" => Mode::Tczupt,
            _ => {
                return Err(input_error(
                    py,
                    format!("mode: expected 'classic' or 'tczupt', got {mode:?}"),
                ))
            }
        },
        discretisation: match discretisation {
            "first_order" => Discretisation::FirstOrder,
            "second_order" => Discretisation::SecondOrder,
            _ => {
                return Err(input_error(
                    py,
                    format!(
                        "discretisation: expected 'first_order' or 'second_order', got {discretisation:?}"
                    ),
                ))
            }
        },
        lever_arm_m: lever_arm,
        window_fixes,
        ..InsConfig::default()
    };
    if let Some(d) = values {
        for (key, x) in float_items(py, d)? {
            let slot = match key.as_str() {
                "sigma_vrw_m_s_sqrt_s" => &mut c.noise.sigma_vrw_m_s_sqrt_s,
                "sigma_arw_rad_sqrt_s" => &mut c.noise.sigma_arw_rad_sqrt_s,
                "sigma_abi_m_s2" => &mut c.noise.sigma_abi_m_s2,
                "sigma_gbi_rad_s" => &mut c.noise.sigma_gbi_rad_s,
                "sigma_gbt_rad_s_sqrt_c" => &mut c.sigma_gbt_rad_s_sqrt_c,
                "init_std_tilt_rad" => &mut c.init_std_tilt_rad,
                "init_std_heading_rad" => &mut c.init_std_heading_rad,
                "init_std_accel_bias_m_s2" => &mut c.init_std_accel_bias_m_s2,
                "init_std_gyro_bias_rad_s" => &mut c.init_std_gyro_bias_rad_s,
                "gnss_min_std_position_m" => &mut c.gnss_min_std_position_m,
                "gnss_min_std_velocity_m_s" => &mut c.gnss_min_std_velocity_m_s,
                "baro_std_m" => &mut c.baro_std_m,
                "baro_offset_time_constant_s" => &mut c.baro_offset_time_constant_s,
                "zupt_std_velocity_m_s" => &mut c.zupt_std_velocity_m_s,
                "zaru_std_rad_s" => &mut c.zaru_std_rad_s,
                "zupt_interval_s" => &mut c.zupt_interval_s,
                "mag_heading_std_rad" => &mut c.mag_heading_std_rad,
                "heading_aiding_s" => &mut c.heading_aiding_s,
                "mag_interval_s" => &mut c.mag_interval_s,
                "declination_rad" => &mut c.declination_rad,
                "course_min_speed_m_s" => &mut c.course_min_speed_m_s,
                "gate_chi2" => &mut c.gate_chi2,
                "lambda_undetected" => &mut c.lambda_undetected,
                "k_horizontal" => &mut c.k_horizontal,
                "k_vertical" => &mut c.k_vertical,
                "separation_k_h" => &mut c.separation_k_h,
                "separation_k_v" => &mut c.separation_k_v,
                "temp_slope_window_s" => &mut c.temp_slope_window_s,
                _ => return Err(input_error(py, format!("config: unknown key {key:?}"))),
            };
            *slot = x;
        }
    }
    c.validate().py_err(py)?;
    Ok(c)
}

fn bools<'a>(
    py: Python<'_>,
    name: &str,
    a: &'a PyReadonlyArray1<'_, bool>,
) -> PyResult<&'a [bool]> {
    a.as_slice()
        .map_err(|_| input_error(py, format!("{name}: expected a contiguous bool array")))
}

fn pair<A, B>(py: Python<'_>, what: &str, a: Option<A>, b: Option<B>) -> PyResult<Option<(A, B)>> {
    match (a, b) {
        (Some(a), Some(b)) => Ok(Some((a, b))),
        (None, None) => Ok(None),
        _ => Err(input_error(
            py,
            format!("{what}: give both the times and the values, or neither"),
        )),
    }
}

type Hist = (
    Vec<[f64; 3]>,
    Vec<[f64; 3]>,
    Vec<[f64; 4]>,
    Vec<[f64; 3]>,
    Vec<[f64; 3]>,
    Vec<[f64; 15]>,
    Vec<[f64; 2]>,
    Vec<bool>,
    Vec<u8>,
    Vec<f64>,
);

/// Runs the GNSS/INS filter over a whole flight; returns a dict of decimated histories,
/// per-fix status and a summary (see `_core.pyi`).
#[pyfunction]
#[pyo3(signature = (imu_t, gyro, accel, gnss_t, gnss_llh, gnss_vel, gnss_acc, *,
    gnss_use=None, baro_t=None, baro_h=None, mag_t=None, mag=None, temp=None,
    dbias_dtemp=None, stationary=None, initial_attitude=None, levelling_samples=100,
    gyro_bias0=[0.0; 3], mode="classic", discretisation="first_order", config=None,
    lever_arm=[0.0; 3], window_fixes=10, reset_after_exclusions=50, decimation=1))]
#[allow(clippy::too_many_arguments)]
fn ins_run<'py>(
    py: Python<'py>,
    imu_t: PyReadonlyArray1<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    accel: PyReadonlyArray2<'py, f64>,
    gnss_t: PyReadonlyArray1<'py, f64>,
    gnss_llh: PyReadonlyArray2<'py, f64>,
    gnss_vel: PyReadonlyArray2<'py, f64>,
    gnss_acc: PyReadonlyArray2<'py, f64>,
    gnss_use: Option<PyReadonlyArray1<'py, bool>>,
    baro_t: Option<PyReadonlyArray1<'py, f64>>,
    baro_h: Option<PyReadonlyArray1<'py, f64>>,
    mag_t: Option<PyReadonlyArray1<'py, f64>>,
    mag: Option<PyReadonlyArray2<'py, f64>>,
    temp: Option<PyReadonlyArray1<'py, f64>>,
    dbias_dtemp: Option<PyReadonlyArray2<'py, f64>>,
    stationary: Option<PyReadonlyArray1<'py, bool>>,
    initial_attitude: Option<Bound<'py, PyAny>>,
    #[pyo3(from_py_with = levelling_arg)] levelling_samples: usize,
    #[pyo3(from_py_with = gyro_bias0_arg)] gyro_bias0: [f64; 3],
    mode: &str,
    discretisation: &str,
    config: Option<Bound<'py, PyDict>>,
    #[pyo3(from_py_with = lever_arm_arg)] lever_arm: [f64; 3],
    #[pyo3(from_py_with = window_arg)] window_fixes: usize,
    #[pyo3(from_py_with = reset_arg)] reset_after_exclusions: usize,
    #[pyo3(from_py_with = decimation_arg)] decimation: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let cfg = self::config(
        py,
        mode,
        discretisation,
        config.as_ref(),
        lever_arm,
        window_fixes,
    )?;
    let cfg = InsConfig {
        reset_after_exclusions,
        ..cfg
    };
    let it = slice1(py, "imu_t", &imu_t)?;
    let g = rows::<3>(py, "gyro", &gyro)?;
    let a = rows::<3>(py, "accel", &accel)?;
    let gt = slice1(py, "gnss_t", &gnss_t)?;
    let gl = rows::<3>(py, "gnss_llh", &gnss_llh)?;
    let gv = rows::<3>(py, "gnss_vel", &gnss_vel)?;
    let ga = rows::<3>(py, "gnss_acc", &gnss_acc)?;
    let gu = gnss_use
        .as_ref()
        .map(|x| bools(py, "gnss_use", x))
        .transpose()?;
    let bt = baro_t
        .as_ref()
        .map(|x| slice1(py, "baro_t", x))
        .transpose()?;
    let bh = baro_h
        .as_ref()
        .map(|x| slice1(py, "baro_h", x))
        .transpose()?;
    let mt = mag_t.as_ref().map(|x| slice1(py, "mag_t", x)).transpose()?;
    let mf = mag.as_ref().map(|x| rows::<3>(py, "mag", x)).transpose()?;
    let t = temp.as_ref().map(|x| slice1(py, "temp", x)).transpose()?;
    let d = dbias_dtemp
        .as_ref()
        .map(|x| rows::<3>(py, "dbias_dtemp", x))
        .transpose()?;
    let st = stationary
        .as_ref()
        .map(|x| bools(py, "stationary", x))
        .transpose()?;
    let q0 = initial_attitude
        .as_ref()
        .map(|x| crate::convert::floats::<4>("initial_attitude", x))
        .transpose()?;
    if let Some(d) = d {
        if d.len() != g.len() {
            return Err(input_error(
                py,
                format!("dbias_dtemp: expected {} rows, got {}", g.len(), d.len()),
            ));
        }
    }
    if decimation == 0 {
        return Err(input_error(py, "decimation: must be >= 1".into()));
    }
    let baro = pair(py, "baro_t/baro_h", bt, bh)?;
    let magp = pair(py, "mag_t/mag", mt, mf)?.map(|(t_s, field)| MagnetometerAiding { t_s, field });
    let input = InsBatchInput {
        imu_t_s: it,
        gyro_rad_s: g,
        accel_m_s2: a,
        temp_c: t,
        stationary: st,
        gnss_t_s: gt,
        gnss_llh: gl,
        gnss_vel_m_s: gv,
        gnss_acc: ga,
        gnss_use: gu,
        baro,
        mag: magp,
        initial_attitude: q0,
        levelling_samples,
        gyro_bias0_rad_s: gyro_bias0,
    };
    let n = g.len();
    let m = gt.len();
    let nrows = n.div_ceil(decimation);
    let result = py.detach(|| {
        let mut h: Hist = (
            vec![[0.0; 3]; nrows],
            vec![[0.0; 3]; nrows],
            vec![[0.0; 4]; nrows],
            vec![[0.0; 3]; nrows],
            vec![[0.0; 3]; nrows],
            vec![[0.0; 15]; nrows],
            vec![[0.0; 2]; nrows],
            vec![false; nrows],
            vec![0u8; m],
            vec![0.0; m],
        );
        let mut out = InsBatchOutput {
            decimation,
            llh: &mut h.0,
            vel_m_s: &mut h.1,
            attitude: &mut h.2,
            gyro_bias_rad_s: &mut h.3,
            accel_bias_m_s2: &mut h.4,
            cov_diag: &mut h.5,
            protection_m: &mut h.6,
            gnss_used: &mut h.7,
            fix_status: &mut h.8,
            fix_nis: &mut h.9,
        };
        let summary = match d {
            Some(table) => InsFilter::run_batch(cfg, &input, &mut DerivativeTable(table), &mut out),
            None => InsFilter::run_batch(cfg, &input, &mut NoDerivative, &mut out),
        }?;
        Ok::<_, nav_core::NavError>((h, summary))
    });
    let (h, s) = result.py_err(py)?;
    let dict = PyDict::new(py);
    dict.set_item("llh", to2(&h.0).into_pyarray(py))?;
    dict.set_item("vel", to2(&h.1).into_pyarray(py))?;
    dict.set_item("attitude", to2(&h.2).into_pyarray(py))?;
    dict.set_item("gyro_bias", to2(&h.3).into_pyarray(py))?;
    dict.set_item("accel_bias", to2(&h.4).into_pyarray(py))?;
    dict.set_item("cov_diag", to2(&h.5).into_pyarray(py))?;
    dict.set_item("protection", to2(&h.6).into_pyarray(py))?;
    dict.set_item("gnss_used", Array1::from_vec(h.7).into_pyarray(py))?;
    dict.set_item("fix_status", Array1::from_vec(h.8).into_pyarray(py))?;
    dict.set_item("fix_nis", Array1::from_vec(h.9).into_pyarray(py))?;
    dict.set_item("initial_attitude", s.initial_attitude.to_vec())?;
    dict.set_item("fixes_used", s.fixes_used)?;
    dict.set_item("fixes_excluded", s.fixes_excluded)?;
    dict.set_item("static_updates", s.static_updates)?;
    dict.set_item("baro_updates", s.baro_updates)?;
    dict.set_item("mag_updates", s.mag_updates)?;
    dict.set_item("course_reset", s.course_reset)?;
    dict.set_item("imu_gaps", s.imu_gaps)?;
    dict.set_item("gnss_resets", s.gnss_resets)?;
    dict.set_item("separation_alerts", s.separation_alerts)?;
    Ok(dict)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ins_run, m)?)?;
    Ok(())
}
