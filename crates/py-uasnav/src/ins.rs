//! Binding of `nav_core::ins`: one call runs a whole flight, or `InsStream` steps a live
//! stream one batch of messages per call (GIL released in both).
use nav_core::ins::{
    GnssFix, InsBatchInput, InsBatchOutput, InsConfig, InsFilter, InsStream, MagnetometerAiding,
    StreamSolution,
};
use nav_core::zupt::{DerivativeTable, NoDerivative};
use numpy::ndarray::Array1;
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{self, rows, slice1};
use crate::errors::{input_error, IntoPy};
use crate::zupt::to2;
use crate::{floats_arg, uint_arg};

uint_arg!(levelling_arg, "levelling_samples", usize, usize_arg);
uint_arg!(decimation_arg, "decimation", usize, usize_arg);
floats_arg!(gyro_bias0_arg, "gyro_bias0", 3);

/// `uasnav.ins.core.FilterConfig` as it crosses: nav-core's `InsConfig` fields read as
/// attributes of one object, by the same names, types checked by PyO3; `None` keeps
/// nav-core's default.
#[derive(FromPyObject)]
struct FilterConfig {
    mode: String,
    discretisation: String,
    lever_arm_m: Option<[f64; 3]>,
    window_fixes: Option<usize>,
    reset_after_exclusions: Option<usize>,
    sigma_vrw_m_s_sqrt_s: Option<f64>,
    sigma_arw_rad_sqrt_s: Option<f64>,
    sigma_abi_m_s2: Option<f64>,
    sigma_gbi_rad_s: Option<f64>,
    sigma_gbt_rad_s_sqrt_c: Option<f64>,
    init_std_tilt_rad: Option<f64>,
    init_std_heading_rad: Option<f64>,
    init_std_accel_bias_m_s2: Option<f64>,
    init_std_gyro_bias_rad_s: Option<f64>,
    gnss_min_std_position_m: Option<f64>,
    gnss_min_std_velocity_m_s: Option<f64>,
    baro_std_m: Option<f64>,
    baro_offset_time_constant_s: Option<f64>,
    zupt_std_velocity_m_s: Option<f64>,
    zaru_std_rad_s: Option<f64>,
    zupt_interval_s: Option<f64>,
    mag_heading_std_rad: Option<f64>,
    heading_aiding_s: Option<f64>,
    mag_interval_s: Option<f64>,
    declination_rad: Option<f64>,
    course_min_speed_m_s: Option<f64>,
    gate_chi2: Option<f64>,
    lambda_undetected: Option<f64>,
    k_horizontal: Option<f64>,
    k_vertical: Option<f64>,
    separation_k_h: Option<f64>,
    separation_k_v: Option<f64>,
    temp_slope_window_s: Option<f64>,
}

/// `slot ← value` unless the value is `None` (nav-core's default stays).
fn set<T>(slot: &mut T, value: Option<T>) {
    if let Some(v) = value {
        *slot = v;
    }
}

/// Extracts the `config` argument; a missing attribute or a wrong type is an `InputError`
/// naming the field (the one mapping of extraction errors).
fn config_arg(obj: &Bound<'_, PyAny>) -> PyResult<InsConfig<f64>> {
    let py = obj.py();
    let a: FilterConfig = obj.extract().map_err(|e: PyErr| {
        let why = match e.cause(py) {
            Some(c) => format!(": {}", c.value(py)),
            None => String::new(),
        };
        input_error(py, format!("config: {}{why}", e.value(py)))
    })?;
    let mut c = InsConfig::<f64> {
        mode: convert::mode(py, &a.mode)?,
        discretisation: convert::discretisation(py, &a.discretisation)?,
        ..InsConfig::default()
    };
    set(&mut c.lever_arm_m, a.lever_arm_m);
    set(&mut c.window_fixes, a.window_fixes);
    set(&mut c.reset_after_exclusions, a.reset_after_exclusions);
    set(&mut c.noise.sigma_vrw_m_s_sqrt_s, a.sigma_vrw_m_s_sqrt_s);
    set(&mut c.noise.sigma_arw_rad_sqrt_s, a.sigma_arw_rad_sqrt_s);
    set(&mut c.noise.sigma_abi_m_s2, a.sigma_abi_m_s2);
    set(&mut c.noise.sigma_gbi_rad_s, a.sigma_gbi_rad_s);
    set(&mut c.sigma_gbt_rad_s_sqrt_c, a.sigma_gbt_rad_s_sqrt_c);
    set(&mut c.init_std_tilt_rad, a.init_std_tilt_rad);
    set(&mut c.init_std_heading_rad, a.init_std_heading_rad);
    set(&mut c.init_std_accel_bias_m_s2, a.init_std_accel_bias_m_s2);
    set(&mut c.init_std_gyro_bias_rad_s, a.init_std_gyro_bias_rad_s);
    set(&mut c.gnss_min_std_position_m, a.gnss_min_std_position_m);
    set(
        &mut c.gnss_min_std_velocity_m_s,
        a.gnss_min_std_velocity_m_s,
    );
    set(&mut c.baro_std_m, a.baro_std_m);
    set(
        &mut c.baro_offset_time_constant_s,
        a.baro_offset_time_constant_s,
    );
    set(&mut c.zupt_std_velocity_m_s, a.zupt_std_velocity_m_s);
    set(&mut c.zaru_std_rad_s, a.zaru_std_rad_s);
    set(&mut c.zupt_interval_s, a.zupt_interval_s);
    set(&mut c.mag_heading_std_rad, a.mag_heading_std_rad);
    set(&mut c.heading_aiding_s, a.heading_aiding_s);
    set(&mut c.mag_interval_s, a.mag_interval_s);
    set(&mut c.declination_rad, a.declination_rad);
    set(&mut c.course_min_speed_m_s, a.course_min_speed_m_s);
    set(&mut c.gate_chi2, a.gate_chi2);
    set(&mut c.lambda_undetected, a.lambda_undetected);
    set(&mut c.k_horizontal, a.k_horizontal);
    set(&mut c.k_vertical, a.k_vertical);
    set(&mut c.separation_k_h, a.separation_k_h);
    set(&mut c.separation_k_v, a.separation_k_v);
    set(&mut c.temp_slope_window_s, a.temp_slope_window_s);
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

/// The IMU and GNSS arrays both entry points take, viewed as slices and rows.
struct Samples<'a> {
    imu_t: &'a [f64],
    gyro: &'a [[f64; 3]],
    accel: &'a [[f64; 3]],
    gnss_t: &'a [f64],
    gnss_llh: &'a [[f64; 3]],
    gnss_vel: &'a [[f64; 3]],
    gnss_acc: &'a [[f64; 3]],
}

/// Views the IMU and GNSS arguments both entry points take (zero-copy) and checks that the
/// IMU rows match `imu_t` and the GNSS rows `gnss_t`; a wrong shape or layout names the
/// argument.
#[allow(clippy::too_many_arguments)]
fn samples<'a>(
    py: Python<'_>,
    imu_t: &'a PyReadonlyArray1<'_, f64>,
    gyro: &'a PyReadonlyArray2<'_, f64>,
    accel: &'a PyReadonlyArray2<'_, f64>,
    gnss_t: &'a PyReadonlyArray1<'_, f64>,
    gnss_llh: &'a PyReadonlyArray2<'_, f64>,
    gnss_vel: &'a PyReadonlyArray2<'_, f64>,
    gnss_acc: &'a PyReadonlyArray2<'_, f64>,
) -> PyResult<Samples<'a>> {
    let s = Samples {
        imu_t: slice1(py, "imu_t", imu_t)?,
        gyro: rows::<3>(py, "gyro", gyro)?,
        accel: rows::<3>(py, "accel", accel)?,
        gnss_t: slice1(py, "gnss_t", gnss_t)?,
        gnss_llh: rows::<3>(py, "gnss_llh", gnss_llh)?,
        gnss_vel: rows::<3>(py, "gnss_vel", gnss_vel)?,
        gnss_acc: rows::<3>(py, "gnss_acc", gnss_acc)?,
    };
    let n = s.imu_t.len();
    if s.gyro.len() != n || s.accel.len() != n {
        return Err(input_error(
            py,
            format!(
                "gyro/accel: expected {n} rows like imu_t, got {} and {}",
                s.gyro.len(),
                s.accel.len()
            ),
        ));
    }
    let m = s.gnss_t.len();
    if s.gnss_llh.len() != m || s.gnss_vel.len() != m || s.gnss_acc.len() != m {
        return Err(input_error(
            py,
            format!("gnss_llh/gnss_vel/gnss_acc: expected {m} rows like gnss_t"),
        ));
    }
    Ok(s)
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
    gyro_bias0=[0.0; 3], config, decimation=1))]
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
    #[pyo3(from_py_with = config_arg)] config: InsConfig<f64>,
    #[pyo3(from_py_with = decimation_arg)] decimation: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let cfg = config;
    let arrays = samples(
        py, &imu_t, &gyro, &accel, &gnss_t, &gnss_llh, &gnss_vel, &gnss_acc,
    )?;
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
        if d.len() != arrays.gyro.len() {
            return Err(input_error(
                py,
                format!(
                    "dbias_dtemp: expected {} rows, got {}",
                    arrays.gyro.len(),
                    d.len()
                ),
            ));
        }
    }
    if decimation == 0 {
        return Err(input_error(py, "decimation: must be >= 1".into()));
    }
    let baro = pair(py, "baro_t/baro_h", bt, bh)?;
    let magp = pair(py, "mag_t/mag", mt, mf)?.map(|(t_s, field)| MagnetometerAiding { t_s, field });
    let input = InsBatchInput {
        imu_t_s: arrays.imu_t,
        gyro_rad_s: arrays.gyro,
        accel_m_s2: arrays.accel,
        temp_c: t,
        stationary: st,
        gnss_t_s: arrays.gnss_t,
        gnss_llh: arrays.gnss_llh,
        gnss_vel_m_s: arrays.gnss_vel,
        gnss_acc: arrays.gnss_acc,
        gnss_use: gu,
        baro,
        mag: magp,
        initial_attitude: q0,
        levelling_samples,
        gyro_bias0_rad_s: gyro_bias0,
    };
    let n = arrays.gyro.len();
    let m = arrays.gnss_t.len();
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

/// `nav_core::ins::InsStream`: the filter stepped one batch of received messages per call.
#[pyclass(name = "InsStream", module = "uasnav._core")]
struct PyInsStream {
    inner: InsStream<f64>,
}

#[pymethods]
impl PyInsStream {
    #[new]
    #[pyo3(signature = (*, config, levelling_samples=100))]
    fn new(
        py: Python<'_>,
        #[pyo3(from_py_with = config_arg)] config: InsConfig<f64>,
        #[pyo3(from_py_with = levelling_arg)] levelling_samples: usize,
    ) -> PyResult<Self> {
        let inner = InsStream::new(config, levelling_samples).py_err(py)?;
        Ok(Self { inner })
    }

    /// Processes one batch in arrival order: fix `j` arrived after `gnss_before[j]` of the
    /// batch's IMU samples. Returns the solutions after each processed IMU sample.
    #[pyo3(signature = (imu_t, gyro, accel, gnss_t, gnss_llh, gnss_vel, gnss_acc, gnss_before))]
    #[allow(clippy::too_many_arguments)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        imu_t: PyReadonlyArray1<'py, f64>,
        gyro: PyReadonlyArray2<'py, f64>,
        accel: PyReadonlyArray2<'py, f64>,
        gnss_t: PyReadonlyArray1<'py, f64>,
        gnss_llh: PyReadonlyArray2<'py, f64>,
        gnss_vel: PyReadonlyArray2<'py, f64>,
        gnss_acc: PyReadonlyArray2<'py, f64>,
        gnss_before: PyReadonlyArray1<'py, u64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let s = samples(
            py, &imu_t, &gyro, &accel, &gnss_t, &gnss_llh, &gnss_vel, &gnss_acc,
        )?;
        let gb = gnss_before.as_slice().map_err(|_| {
            input_error(py, "gnss_before: expected a contiguous uint64 array".into())
        })?;
        let (n, m) = (s.imu_t.len(), s.gnss_t.len());
        if gb.len() != m {
            return Err(input_error(
                py,
                format!("gnss_before: expected {m} rows like gnss_t"),
            ));
        }
        if gb.windows(2).any(|w| matches!(w, [x, y] if y < x)) || gb.iter().any(|&b| b as usize > n)
        {
            return Err(input_error(
                py,
                format!("gnss_before: expected non-decreasing counts within 0..={n}"),
            ));
        }
        let inner = &mut self.inner;
        let out = py.detach(|| -> Result<Vec<StreamSolution<f64>>, nav_core::NavError> {
            let mut out = Vec::with_capacity(n);
            let mut fixes = (s.gnss_t.iter().zip(s.gnss_llh).zip(s.gnss_vel))
                .zip(s.gnss_acc)
                .zip(gb)
                .peekable();
            let mut imu = s.imu_t.iter().zip(s.gyro).zip(s.accel);
            for k in 0..=n {
                while let Some(((((t, l), v), acc), _)) =
                    fixes.next_if(|(_, b)| usize::try_from(**b).is_ok_and(|b| b == k))
                {
                    inner.push_gnss(GnssFix {
                        t_s: *t,
                        llh: *l,
                        vel_m_s: *v,
                        acc: *acc,
                    })?;
                }
                if let Some(((t, gy), ac)) = imu.next() {
                    if let Some(sol) = inner.push_imu(*t, *gy, *ac)? {
                        out.push(sol);
                    }
                }
            }
            Ok(out)
        });
        let sols = out.py_err(py)?;
        let dict = PyDict::new(py);
        let col =
            |f: &dyn Fn(&StreamSolution<f64>) -> f64| sols.iter().map(f).collect::<Vec<f64>>();
        dict.set_item("t", Array1::from_vec(col(&|s| s.t_s)).into_pyarray(py))?;
        let llh: Vec<[f64; 3]> = sols.iter().map(|s| s.llh).collect();
        let vel: Vec<[f64; 3]> = sols.iter().map(|s| s.vel_m_s).collect();
        let att: Vec<[f64; 4]> = sols.iter().map(|s| s.attitude).collect();
        let pl: Vec<[f64; 2]> = sols.iter().map(|s| s.protection_m).collect();
        let bg: Vec<[f64; 3]> = sols.iter().map(|s| s.gyro_bias_rad_s).collect();
        let ba: Vec<[f64; 3]> = sols.iter().map(|s| s.accel_bias_m_s2).collect();
        dict.set_item("gyro_bias", to2(&bg).into_pyarray(py))?;
        dict.set_item("accel_bias", to2(&ba).into_pyarray(py))?;
        dict.set_item("llh", to2(&llh).into_pyarray(py))?;
        dict.set_item("vel", to2(&vel).into_pyarray(py))?;
        dict.set_item("attitude", to2(&att).into_pyarray(py))?;
        dict.set_item("protection", to2(&pl).into_pyarray(py))?;
        let used: Vec<u8> = sols.iter().map(|s| s.fixes_used).collect();
        let excl: Vec<u8> = sols.iter().map(|s| s.fixes_excluded).collect();
        dict.set_item("fixes_used", Array1::from_vec(used).into_pyarray(py))?;
        dict.set_item("fixes_excluded", Array1::from_vec(excl).into_pyarray(py))?;
        Ok(dict)
    }

    /// Whether the filter runs (levelling done and initialised on a fix).
    #[getter]
    fn running(&self) -> bool {
        self.inner.is_running()
    }

    /// Running counts as a dict.
    fn counts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = self.inner.counts();
        let d = PyDict::new(py);
        d.set_item("imu_samples", c.imu_samples)?;
        d.set_item("imu_refused", c.imu_refused)?;
        d.set_item("imu_gaps", c.imu_gaps)?;
        d.set_item("fixes_used", c.fixes_used)?;
        d.set_item("fixes_excluded", c.fixes_excluded)?;
        d.set_item("fixes_dropped", c.fixes_dropped)?;
        d.set_item("gnss_resets", c.gnss_resets)?;
        d.set_item("course_reset", c.course_reset)?;
        Ok(d)
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ins_run, m)?)?;
    m.add_class::<PyInsStream>()?;
    Ok(())
}
