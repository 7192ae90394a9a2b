//! The firmware tests of nav-core: every case runs one algorithm over the fixed inputs of
//! [`inputs`] (generated on the host from the uasnav simulator) and reports its outputs and
//! the cost of each call through a [`Probe`].
//!
//! The same code runs on the target (QEMU, semihosting) and on the host (the reference): the
//! host build uses nav-core without `std`, so both use libm's maths and the same sequence of
//! IEEE-754 operations — the outputs must match bit for bit at equal precision. Each case runs
//! in `f32` and `f64`; the `f32` outputs are compared with the `f64` ones within the bounds
//! derived in `check.py`.
//!
//! Output protocol (one line each, printed by the probe's owner):
//! `case <name>`, then `v <hex of the f64 bits>` per output value, then `end`.
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod inputs;

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use nav_core::attitude::{euler321_to_quat, AttitudePropagator, PropagatorConfig};
use nav_core::ins::{InsConfig, InsFilter};
use nav_core::mlp::{Activation, Affine, LayerSpec, Mlp};
use nav_core::redundancy::{FdiConfig, FdiFuser, SensorArray};
use nav_core::zupt::{StationarityConfig, StationarityDetector, ZuptConfig, ZuptFilter};
use nav_core::{NavError, Real};

/// Samples per case (100 Hz).
pub const N: usize = inputs::STATIC_GYRO.len();
/// Outputs are recorded every this many samples.
pub const EVERY: usize = 30;
/// ZUPT updates every this many samples (10 Hz) in the ZUPT case.
pub const ZUPT_UPDATE_EVERY: usize = 10;
/// Sample period (s).
pub const DT_S: f64 = 0.01;

/// Where a case reports to: output values, and the start/stop of each timed call.
pub trait Probe {
    /// A case starts.
    fn begin(&mut self, case: &str);
    /// One output value (f32 outputs are widened exactly).
    fn value(&mut self, x: f64);
    /// The timed call starts now.
    fn tic(&mut self);
    /// The timed call named `step` ended now.
    fn toc(&mut self, step: &'static str);
    /// The case ended.
    fn end(&mut self);
}

/// Runs `f` as one timed call of `step`.
#[inline(always)]
fn timed<P: Probe, R>(p: &mut P, step: &'static str, f: impl FnOnce() -> R) -> R {
    p.tic();
    let r = core::hint::black_box(f());
    p.toc(step);
    r
}

#[inline(always)]
fn c<T: Real>(x: f64) -> T {
    nalgebra::convert(x)
}

#[inline(always)]
fn f<T: Real>(x: T) -> f64 {
    num_traits::ToPrimitive::to_f64(&x).unwrap_or(f64::NAN)
}

fn v3<T: Real>(a: &[f64; 3]) -> [T; 3] {
    [c(a[0]), c(a[1]), c(a[2])]
}

fn out_vec<T: Real, P: Probe>(p: &mut P, v: &Vector3<T>) {
    for x in v.iter() {
        p.value(f(*x));
    }
}

fn out_quat<T: Real, P: Probe>(p: &mut P, q: &UnitQuaternion<T>) {
    // Scalar first; the sign is fixed by the algorithm, not normalised here.
    for x in [q.w, q.i, q.j, q.k] {
        p.value(f(x));
    }
}

/// Precision suffix of case names.
pub fn precision<T: Real>() -> &'static str {
    if core::mem::size_of::<T>() == 4 {
        "f32"
    } else {
        "f64"
    }
}

/// Runs every case in `T`; the first error aborts and is returned with the case name.
pub fn run_all<T: Real, P: Probe>(p: &mut P) -> Result<(), (&'static str, NavError)> {
    attitude::<T, P>(p).map_err(|e| ("attitude", e))?;
    zupt::<T, P>(p).map_err(|e| ("zupt", e))?;
    tczupt::<T, P>(p).map_err(|e| ("tczupt", e))?;
    ins::<T, P>(p).map_err(|e| ("ins", e))?;
    detector::<T, P>(p).map_err(|e| ("detector", e))?;
    fdi::<T, P>(p).map_err(|e| ("fdi", e))?;
    position::<T, P>(p);
    Ok(())
}

/// Strapdown attitude propagation with coning correction over the flight's gyro samples.
pub fn attitude<T: Real, P: Probe>(p: &mut P) -> Result<(), NavError> {
    p.begin("attitude");
    let [r, pi, y] = inputs::FLIGHT_EULER0;
    let q0 = euler321_to_quat(c::<T>(r), c(pi), c(y));
    let mut prop = AttitudePropagator::new(q0, PropagatorConfig { coning: true });
    let dt = c::<T>(DT_S);
    for (k, w) in inputs::FLIGHT_GYRO.iter().enumerate() {
        let w = Vector3::from(v3::<T>(w));
        timed(p, "attitude.step", || prop.step(&w, dt))?;
        if (k + 1) % EVERY == 0 {
            p.value(k as f64);
            out_quat(p, prop.attitude());
        }
    }
    p.end();
    Ok(())
}

fn zupt_outputs<T: Real, P: Probe>(p: &mut P, z: &ZuptFilter<T>) {
    out_vec(p, &z.position_m());
    out_vec(p, &z.velocity_m_s());
    out_quat(p, z.attitude());
    out_vec(p, &z.accel_bias_m_s2());
    out_vec(p, &z.gyro_bias_rad_s());
    for i in 0..nav_core::zupt::N_STATES {
        p.value(f(z.covariance()[(i, i)]));
    }
}

fn static_q0<T: Real>() -> UnitQuaternion<T> {
    // The simulator's attitude of the static log (roll, pitch, yaw in rad).
    euler321_to_quat(c(0.02), c(-0.01), c(0.5))
}

/// ZUPT filter on the static log: predict every sample, the ZUPT update at 10 Hz.
pub fn zupt<T: Real, P: Probe>(p: &mut P) -> Result<(), NavError> {
    p.begin("zupt");
    let cfg = ZuptConfig::<T>::default();
    let dt = c::<T>(DT_S);
    let mut z = ZuptFilter::new(cfg, static_q0(), Vector3::zeros(), Vector3::zeros(), dt)?;
    let zero = Vector3::zeros();
    for k in 0..N {
        let g = v3::<T>(&inputs::STATIC_GYRO[k]);
        let a = v3::<T>(&inputs::STATIC_ACCEL[k]);
        timed(p, "zupt.predict", || z.predict(&g, &a, &zero))?;
        if (k + 1) % ZUPT_UPDATE_EVERY == 0 {
            timed(p, "zupt.update", || z.update())?;
        }
        if (k + 1) % EVERY == 0 {
            p.value(k as f64);
            zupt_outputs(p, &z);
            p.value(f(z.last_nis()));
        }
    }
    p.end();
    Ok(())
}

/// The thermal MLP of the inputs (1-6-6-1, tanh, linear output).
pub fn thermal_mlp<T: Real>() -> Result<Mlp<T>, NavError> {
    let conv = |a: &[f64], out: &mut [T]| {
        for (o, x) in out.iter_mut().zip(a) {
            *o = c(*x);
        }
    };
    let (mut w1, mut b1, mut w2, mut b2, mut w3) = (
        [T::zero(); 6],
        [T::zero(); 6],
        [T::zero(); 36],
        [T::zero(); 6],
        [T::zero(); 6],
    );
    conv(&inputs::MLP_W1, &mut w1);
    conv(&inputs::MLP_B1, &mut b1);
    conv(&inputs::MLP_W2, &mut w2);
    conv(&inputs::MLP_B2, &mut b2);
    conv(&inputs::MLP_W3, &mut w3);
    let [b3, in_off, in_gain, out_off, out_scale] = inputs::MLP_NORM;
    let b3 = [c::<T>(b3)];
    let layers = [
        LayerSpec {
            weights: &w1,
            biases: &b1,
            activation: Activation::Tanh,
        },
        LayerSpec {
            weights: &w2,
            biases: &b2,
            activation: Activation::Tanh,
        },
        LayerSpec {
            weights: &w3,
            biases: &b3,
            activation: Activation::Linear,
        },
    ];
    Mlp::new(
        &layers,
        Affine {
            offset: c(in_off),
            scale: c(in_gain),
        },
        Affine {
            offset: c(out_off),
            scale: c(out_scale),
        },
        (c(-40.0), c(85.0)),
    )
}

/// Per-axis scale of the MLP's ∂b/∂T (one network models the three axes' common shape).
const AXIS_SCALE: [f64; 3] = [1.0, -0.6, 0.8];

/// TCZUPT on the static log with the MLP's ∂b/∂T, through `step` (slope of the die
/// temperature, MLP derivative, predict, and the 1 Hz update when due).
pub fn tczupt<T: Real, P: Probe>(p: &mut P) -> Result<(), NavError> {
    p.begin("mlp");
    let mlp = thermal_mlp::<T>()?;
    for k in (0..N).step_by(EVERY) {
        let o = timed(p, "mlp.eval", || mlp.eval(c(inputs::STATIC_TEMP[k])));
        p.value(k as f64);
        p.value(f(o.value));
        p.value(f(o.derivative));
    }
    p.end();
    p.begin("tczupt");
    let cfg = ZuptConfig::<T> {
        mode: nav_core::zupt::Mode::Tczupt,
        noise: nav_core::zupt::ProcessNoise::thesis_tczupt(),
        // A window the 3 s log fills (the default 30 s would leave dT/dt at zero).
        temp_slope_window_s: c(1.0),
        ..ZuptConfig::default()
    };
    let dt = c::<T>(DT_S);
    let mut z = ZuptFilter::new(cfg, static_q0(), Vector3::zeros(), Vector3::zeros(), dt)?;
    let s: [T; 3] = v3(&AXIS_SCALE);
    let mut deriv = |_k: usize, temp: T| {
        let d = mlp.eval(temp).derivative;
        Vector3::new(d * s[0], d * s[1], d * s[2])
    };
    for k in 0..N {
        let g = v3::<T>(&inputs::STATIC_GYRO[k]);
        let a = v3::<T>(&inputs::STATIC_ACCEL[k]);
        let temp = Some(c::<T>(inputs::STATIC_TEMP[k]));
        p.tic();
        let updated = z.step(&g, &a, temp, true, &mut deriv)?;
        p.toc(if updated {
            "tczupt.step+update"
        } else {
            "tczupt.step"
        });
        if (k + 1) % EVERY == 0 {
            p.value(k as f64);
            zupt_outputs(p, &z);
            p.value(f(z.temp_rate_c_s()));
        }
    }
    p.end();
    Ok(())
}

fn ins_outputs<T: Real, P: Probe>(p: &mut P, ins: &InsFilter<T>) {
    for x in ins.position() {
        p.value(x);
    }
    out_vec(p, &ins.velocity_m_s());
    out_quat(p, ins.attitude());
    out_vec(p, &ins.accel_bias_m_s2());
    out_vec(p, &ins.gyro_bias_rad_s());
    for i in 0..nav_core::strapdown::N_STATES {
        p.value(f(ins.covariance()[(i, i)]));
    }
}

/// GNSS/INS on the flight: predict every IMU sample, a GNSS update at each 5 Hz fix.
pub fn ins<T: Real, P: Probe>(p: &mut P) -> Result<(), NavError> {
    p.begin("ins");
    let [r, pi, y] = inputs::FLIGHT_EULER0;
    let q0 = euler321_to_quat(c::<T>(r), c(pi), c(y));
    let [lat, lon, h] = inputs::FLIGHT_LLH0;
    let mut ins = InsFilter::new(
        InsConfig::<T>::default(),
        lat,
        lon,
        h,
        Vector3::from(v3::<T>(&inputs::FLIGHT_VEL0)),
        q0,
        [c(1.5), c(1.5), c(2.5)],
        [c(0.15); 3],
    )?;
    let dt = c::<T>(DT_S);
    let zero = Vector3::zeros();
    let mut fixes = inputs::GNSS_FIXES.iter().peekable();
    for k in 0..N {
        let g = v3::<T>(&inputs::FLIGHT_GYRO[k]);
        let a = v3::<T>(&inputs::FLIGHT_ACCEL[k]);
        timed(p, "ins.predict", || ins.predict(&g, &a, dt, &zero))?;
        while let Some(fix) = fixes.next_if(|fix| fix[0] as usize <= k) {
            let llh = [fix[1], fix[2], fix[3]];
            let vel = v3::<T>(&[fix[4], fix[5], fix[6]]);
            let acc = v3::<T>(&[fix[7], fix[8], fix[9]]);
            let st = timed(p, "ins.update_gnss", || {
                ins.update_gnss(&llh, &vel, &acc, 0.0)
            })?;
            p.value(k as f64);
            p.value(f64::from(st as u8));
            ins_outputs(p, &ins);
        }
        if (k + 1) % EVERY == 0 {
            p.value(k as f64);
            // Not a fix: status −1.
            p.value(-1.0);
            ins_outputs(p, &ins);
        }
    }
    p.end();
    Ok(())
}

/// GLRT static detector over the flight (static, then take-off): statistic and decision.
pub fn detector<T: Real, P: Probe>(p: &mut P) -> Result<(), NavError> {
    p.begin("detector");
    let mut d = StationarityDetector::new(StationarityConfig::<T>::default())?;
    for k in 0..N {
        let a = v3::<T>(&inputs::FLIGHT_ACCEL[k]);
        let g = v3::<T>(&inputs::FLIGHT_GYRO[k]);
        let (stat, still) = timed(p, "detector.push", || d.push(&a, &g))?;
        if k % 5 == 0 {
            p.value(k as f64);
            p.value(f(stat));
            p.value(f64::from(u8::from(still)));
        }
    }
    p.end();
    Ok(())
}

/// Axes of the redundant array (six triaxial gyros).
pub const ARRAY_AXES: usize = 18;

/// Redundant-IMU fusion with fault detection and isolation on the cube array; a stuck-high
/// fault on one axis of sensor 2 from sample 150 on.
pub fn fdi<T: Real, P: Probe>(p: &mut P) -> Result<(), NavError> {
    p.begin("fdi");
    let mut mounts = [Matrix3::<T>::identity(); 6];
    for (s, m) in mounts.iter_mut().enumerate() {
        for i in 0..3 {
            for j in 0..3 {
                m[(i, j)] = c(inputs::ARRAY_MOUNTINGS[3 * s + i][j]);
            }
        }
    }
    let array = SensorArray::<T, ARRAY_AXES>::from_mountings(&mounts, c(1e-6))?;
    let sigma = [c::<T>(2e-3); ARRAY_AXES];
    let mut fuser = FdiFuser::<T, ARRAY_AXES, 6>::new(array, &sigma, FdiConfig::default())?;
    let mut z = [T::zero(); ARRAY_AXES];
    for k in 0..N {
        for (o, x) in z.iter_mut().zip(inputs::ARRAY_GYRO[k].iter()) {
            *o = c(*x);
        }
        if k >= N / 2 {
            z[7] += c(0.05);
        }
        let o = timed(p, "fdi.step", || fuser.step(&z))?;
        if k % 5 == 0 {
            p.value(k as f64);
            out_vec(p, &o.fused.value);
            p.value(f(o.fused.chi2));
            p.value(f64::from(u8::from(o.valid)));
            p.value(f64::from(u8::from(o.alarm)));
            for h in o.health {
                p.value(f64::from(h.0));
            }
        }
    }
    p.end();
    Ok(())
}

/// Earth radii and gravity at a reference point, as the INS caches them (f64).
struct Earth {
    lat: f64,
    h: f64,
    cos_lat: f64,
    rn: f64,
    re: f64,
    gravity: f64,
    grav_grad: f64,
}

impl Earth {
    fn at(lat: f64, h: f64) -> Self {
        use num_traits::Float;
        let (sl, cl) = (lat.sin(), lat.cos());
        let d = 1.0 - nav_core::earth::WGS84_E2 * sl * sl;
        let re = nav_core::earth::WGS84_A / d.sqrt();
        let g = nav_core::earth::normal_gravity(lat, h);
        Earth {
            lat,
            h,
            cos_lat: cl,
            rn: re * (1.0 - nav_core::earth::WGS84_E2) / d,
            re,
            gravity: g,
            grav_grad: 2.0 * g / nav_core::earth::geocentric_radius(lat),
        }
    }
}

/// The price of the f64 geodetic position on each core: the position part of the INS
/// mechanisation done as nav-core's INS does it (latitude, longitude, height in f64, the Earth
/// radii and gravity recomputed in f64 after 1e-6 rad or 1 m of motion), and as PX4's EKF2 does
/// it (a `T` NED position from a local origin, radii fixed at the origin). A constant velocity
/// of (10, 5, −1) m/s NED, 300 steps of 10 ms.
pub fn position<T: Real, P: Probe>(p: &mut P) {
    p.begin("position");
    let [lat0, lon0, h0] = inputs::FLIGHT_LLH0;
    let (mut lat, mut lon, mut h) = (lat0, lon0, h0);
    let mut e = Earth::at(lat, h);
    let v64 = [10.0f64, 5.0, -1.0];
    let v: Vector3<T> = Vector3::from(v3::<T>(&v64));
    let dt = c::<T>(DT_S);
    let mut ned = Vector3::<T>::zeros();
    for k in 0..N {
        timed(p, "position.geodetic_f64", || {
            let (rn_h, re_h) = (e.rn + h, e.re + h);
            h -= v64[2] * DT_S;
            lat += v64[0] * DT_S / rn_h;
            lon += v64[1] * DT_S / (re_h * e.cos_lat);
            if num_traits::Float::abs(lat - e.lat) > 1e-6 || num_traits::Float::abs(h - e.h) > 1.0 {
                e = Earth::at(lat, h);
            }
        });
        timed(p, "position.local", || ned += v * dt);
        if (k + 1) % EVERY == 0 {
            p.value(k as f64);
            for x in [lat, lon, h, e.gravity, e.grav_grad] {
                p.value(x);
            }
            out_vec(p, &ned);
        }
    }
    p.end();
}
