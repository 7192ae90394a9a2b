//! # nav-ffi — the C interface of nav-core
//!
//! For avionics code in C or C++ (PX4, ArduPilot, bare-metal firmware): the ZUPT/TCZUPT filter,
//! the loosely coupled GNSS/INS filter and the thermal MLP, in **single precision** (`float`)
//! except the INS position (latitude, longitude, height: `double`, see nav-core's `ins`).
//!
//! * **Memory** is the caller's: each object (`UasnavZupt`, `UasnavIns`, `UasnavMlp`) is a
//!   fixed-size, 8-byte aligned struct that the caller places where it likes (static, stack,
//!   pool); nothing here allocates. `*_init` creates an object in it, or resets it.
//! * **Errors** are status codes ([`UasnavStatus`]), never a panic across the boundary: every
//!   pointer is checked for null and alignment, every object for the tag its `*_init` wrote,
//!   every input is screened by nav-core (non-finite values, invalid parameters, a covariance
//!   that stops being positive definite all come back as codes; the object is then unchanged
//!   or must be re-initialised, as each function says).
//! * **Conventions** as nav-core: SI units; the navigation frame is North-East-Down (NED); IMU
//!   samples are in the body frame (x forward, y right, z down); quaternions are Hamilton,
//!   scalar first `[w, x, y, z]`, rotating body → NED.
//!
//! A function may be called from any thread, but one object must not be used by two calls at
//! once (the caller's lock, as for any C struct).
// On a microcontroller (`target_os = "none"`) without std; on a host the library links std
// (nav-core itself is built without it either way: libm maths, as in the firmware).
#![cfg_attr(target_os = "none", no_std)]
#![deny(missing_docs)]

/// Required by a `no_std` static library. Nothing in this crate is meant to reach it: every
/// input is screened and every nav-core call returns a status (see the crate docs and the
/// panic-site listing of `make embedded`); if one did, the core stops here rather than
/// unwinding into C.
#[cfg(target_os = "none")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    loop {
        core::hint::spin_loop();
    }
}

use core::mem::{align_of, size_of};

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use nav_core::ins::{InsConfig, InsFilter};
use nav_core::mlp::{Activation, Affine, LayerSpec, Mlp};
use nav_core::zupt::{ProcessNoise, ZuptConfig, ZuptFilter};
use nav_core::NavError;

/// Result of every call. `UASNAV_STATUS_OK` is 0; any other value means the call did nothing
/// (or, for a filter step, see the function) and says why.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UasnavStatus {
    /// Success.
    Ok = 0,
    /// A required pointer was null.
    NullPointer = 1,
    /// A pointer was not aligned for its type.
    Misaligned = 2,
    /// The object was not initialised by its `*_init` function (or its init failed).
    NotInitialised = 3,
    /// An input was NaN or infinite, or the solution became non-finite.
    NonFinite = 4,
    /// A parameter or input is outside its valid domain.
    InvalidParameter = 5,
    /// A covariance matrix stopped being positive definite: re-initialise the filter.
    NotPositiveDefinite = 6,
    /// Array lengths are inconsistent.
    LengthMismatch = 7,
}

impl From<NavError> for UasnavStatus {
    fn from(e: NavError) -> Self {
        match e {
            NavError::NonFinite { .. } => UasnavStatus::NonFinite,
            NavError::TooShort { .. } | NavError::InvalidParameter { .. } => {
                UasnavStatus::InvalidParameter
            }
            NavError::LengthMismatch { .. } => UasnavStatus::LengthMismatch,
            NavError::NotPositiveDefinite { .. } => UasnavStatus::NotPositiveDefinite,
        }
    }
}

fn status(r: Result<(), UasnavStatus>) -> UasnavStatus {
    match r {
        Ok(()) => UasnavStatus::Ok,
        Err(s) => s,
    }
}

// ---------------------------------------------------------------------------------------------
// Caller-owned storage.

/// 64-bit words of storage in a [`UasnavZupt`].
pub const UASNAV_ZUPT_WORDS: usize = 600;
/// 64-bit words of storage in a [`UasnavIns`].
pub const UASNAV_INS_WORDS: usize = 1600;
/// 64-bit words of storage in a [`UasnavMlp`].
pub const UASNAV_MLP_WORDS: usize = 200;

/// A ZUPT or TCZUPT filter in caller-owned memory (4,808 bytes). Create or reset it with
/// [`uasnav_zupt_init`]; never copy it with `memcpy` while another call uses it.
#[repr(C)]
pub struct UasnavZupt {
    tag: u64,
    storage: [u64; UASNAV_ZUPT_WORDS],
}

/// A GNSS/INS filter in caller-owned memory (12,808 bytes). Create or reset it with
/// [`uasnav_ins_init`].
#[repr(C)]
pub struct UasnavIns {
    tag: u64,
    storage: [u64; UASNAV_INS_WORDS],
}

/// A thermal MLP in caller-owned memory (1,608 bytes). Create it with [`uasnav_mlp_init`].
#[repr(C)]
pub struct UasnavMlp {
    tag: u64,
    storage: [u64; UASNAV_MLP_WORDS],
}

// The storage must hold the Rust object with its alignment (u64 storage: 8 bytes).
const _: () = assert!(size_of::<ZuptFilter<f32>>() <= 8 * UASNAV_ZUPT_WORDS);
const _: () = assert!(align_of::<ZuptFilter<f32>>() <= align_of::<u64>());
const _: () = assert!(size_of::<InsFilter<f32>>() <= 8 * UASNAV_INS_WORDS);
const _: () = assert!(align_of::<InsFilter<f32>>() <= align_of::<u64>());
const _: () = assert!(size_of::<Mlp<f32>>() <= 8 * UASNAV_MLP_WORDS);
const _: () = assert!(align_of::<Mlp<f32>>() <= align_of::<u64>());

const TAG_ZUPT: u64 = 0x7561_736e_7a75_7074; // "uasnzupt"
const TAG_INS: u64 = 0x7561_736e_696e_7331; // "uasnins1"
const TAG_MLP: u64 = 0x7561_736e_6d6c_7031; // "uasnmlp1"

/// The storage of one kind of object: its tag and the Rust type it holds.
trait Slot {
    type Inner;
    const TAG: u64;
    fn tag(&mut self) -> &mut u64;
    fn storage(&mut self) -> *mut Self::Inner;
}

macro_rules! slot {
    ($outer:ty, $inner:ty, $tag:expr) => {
        impl Slot for $outer {
            type Inner = $inner;
            const TAG: u64 = $tag;
            fn tag(&mut self) -> &mut u64 {
                &mut self.tag
            }
            fn storage(&mut self) -> *mut $inner {
                self.storage.as_mut_ptr().cast()
            }
        }
    };
}
slot!(UasnavZupt, ZuptFilter<f32>, TAG_ZUPT);
slot!(UasnavIns, InsFilter<f32>, TAG_INS);
slot!(UasnavMlp, Mlp<f32>, TAG_MLP);

/// Checks that `p` is non-null and aligned for `T`.
fn check_ptr<T>(p: *const T) -> Result<(), UasnavStatus> {
    if p.is_null() {
        Err(UasnavStatus::NullPointer)
    } else if !p.is_aligned() {
        Err(UasnavStatus::Misaligned)
    } else {
        Ok(())
    }
}

/// Writes `value` into the object at `obj` (created or reset) and tags it.
fn store<S: Slot>(obj: *mut S, value: S::Inner) -> Result<(), UasnavStatus> {
    check_ptr(obj)?;
    // SAFETY: `obj` is non-null and aligned (checked); the caller passes a pointer to a `S`
    // it owns (the documented contract of every `*_init`), not used by another call now. Its
    // bytes may be uninitialised: `S` is plain words, and we only write through a raw pointer
    // before reading anything.
    let slot = unsafe { &mut *obj };
    let was = core::mem::replace(slot.tag(), 0);
    if was == S::TAG {
        // SAFETY: the tag says `storage` holds a live `S::Inner` written by an earlier init;
        // dropping it in place before overwriting (the nav-core types own no resources, so
        // this only keeps Rust's ownership rules honest).
        unsafe { core::ptr::drop_in_place(slot.storage()) };
    }
    // SAFETY: `storage` is large and aligned enough for `S::Inner` (compile-time asserts above)
    // and holds no live value now (dropped above or never written).
    unsafe { slot.storage().write(value) };
    *slot.tag() = S::TAG;
    Ok(())
}

/// The live object at `obj`, if `obj` is a valid pointer to an initialised object.
fn live<'a, S: Slot>(obj: *mut S) -> Result<&'a mut S::Inner, UasnavStatus> {
    check_ptr(obj)?;
    // SAFETY: non-null and aligned (checked); points to a caller-owned `S` not used by another
    // call now (the contract). Reading the tag word is defined for any bit pattern of a u64.
    let slot = unsafe { &mut *obj };
    if *slot.tag() != S::TAG {
        return Err(UasnavStatus::NotInitialised);
    }
    // SAFETY: the tag is only set by `store` after writing a valid `S::Inner` into `storage`
    // (aligned and large enough, see the asserts), and cleared while re-initialising.
    Ok(unsafe { &mut *slot.storage() })
}

/// `N` values read from a caller's array.
fn read<T: Copy, const N: usize>(p: *const T) -> Result<[T; N], UasnavStatus> {
    check_ptr(p)?;
    // SAFETY: non-null and aligned (checked); the contract of each function is that the
    // pointer designates at least `N` readable elements (stated in the header for every
    // array parameter). `[T; N]` has the alignment of `T`.
    Ok(unsafe { p.cast::<[T; N]>().read() })
}

/// Like [`read`], a null pointer meaning `default`.
fn read_or<T: Copy, const N: usize>(p: *const T, default: [T; N]) -> Result<[T; N], UasnavStatus> {
    if p.is_null() {
        Ok(default)
    } else {
        read(p)
    }
}

/// Writes `value` into the caller's `out`.
fn write<T>(out: *mut T, value: T) -> Result<(), UasnavStatus> {
    check_ptr(out)?;
    // SAFETY: non-null and aligned (checked); `out` designates a writable `T` (the contract).
    // `T` is a plain `repr(C)` struct or scalar without drop glue, so overwriting whatever was
    // there is fine.
    unsafe { out.write(value) };
    Ok(())
}

fn quat(q: [f32; 4]) -> Result<UnitQuaternion<f32>, UasnavStatus> {
    if !q.iter().all(|x| x.is_finite()) {
        return Err(UasnavStatus::NonFinite);
    }
    let n2 = q.iter().map(|x| x * x).sum::<f32>();
    if !(n2 > 0.25 && n2 < 4.0) {
        return Err(UasnavStatus::InvalidParameter);
    }
    let q = Quaternion::new(q[0], q[1], q[2], q[3]);
    // A quaternion that is unit to rounding is taken as it is (so that a state read out and
    // fed back is bit-identical); anything else is normalised.
    Ok(if (n2 - 1.0).abs() <= 8.0 * f32::EPSILON {
        UnitQuaternion::new_unchecked(q)
    } else {
        UnitQuaternion::from_quaternion(q)
    })
}

fn quat_out(q: &UnitQuaternion<f32>) -> [f32; 4] {
    [q.w, q.i, q.j, q.k]
}

fn diag15(p: &nalgebra::SMatrix<f32, 15, 15>) -> [f32; 15] {
    core::array::from_fn(|i| p[(i, i)])
}

/// The quaternion `q[4]` (body → NED, scalar first) of roll, pitch, yaw (rad, 3-2-1 order:
/// yaw about down, then pitch, then roll).
///
/// # Safety
/// `q` a writable array of 4 floats.
#[no_mangle]
pub unsafe extern "C" fn uasnav_quat_from_euler321(
    roll_rad: f32,
    pitch_rad: f32,
    yaw_rad: f32,
    q: *mut [f32; 4],
) -> UasnavStatus {
    if !(roll_rad.is_finite() && pitch_rad.is_finite() && yaw_rad.is_finite()) {
        return UasnavStatus::NonFinite;
    }
    let u = nav_core::attitude::euler321_to_quat(roll_rad, pitch_rad, yaw_rad);
    status(write(q, quat_out(&u)))
}

// ---------------------------------------------------------------------------------------------
// ZUPT / TCZUPT.

/// Configuration of the ZUPT/TCZUPT filter (see nav-core `zupt::ZuptConfig`); fill it with
/// [`uasnav_zupt_config_default`] and change what you need.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UasnavZuptConfig {
    /// false: ZUPT (the gyro input is thermally calibrated); true: TCZUPT (raw gyro, the bias
    /// follows the MLP's ∂b/∂T times dT/dt, see [`uasnav_zupt_step`]).
    pub tczupt: bool,
    /// Velocity random walk σ_VRW (m/s/√s).
    pub sigma_vrw_m_s_sqrt_s: f32,
    /// Angle random walk σ_ARW (rad/√s).
    pub sigma_arw_rad_sqrt_s: f32,
    /// Accelerometer bias instability σ_ABI (m/s²).
    pub sigma_abi_m_s2: f32,
    /// Gyro bias instability σ_GBI (rad/s).
    pub sigma_gbi_rad_s: f32,
    /// σ of the frozen-position measurement (m).
    pub meas_std_position_m: f32,
    /// σ of the zero-velocity measurement (m/s).
    pub meas_std_velocity_m_s: f32,
    /// σ of the frozen-attitude measurement (rad).
    pub meas_std_attitude_rad: f32,
    /// Time between ZUPT updates in [`uasnav_zupt_step`] (s).
    pub update_interval_s: f32,
    /// Initial σ of the position error (m).
    pub init_std_position_m: f32,
    /// Initial σ of the velocity error (m/s).
    pub init_std_velocity_m_s: f32,
    /// Initial σ of the attitude error (rad).
    pub init_std_attitude_rad: f32,
    /// Initial σ of the accelerometer bias (m/s²).
    pub init_std_accel_bias_m_s2: f32,
    /// Initial σ of the gyro bias (rad/s).
    pub init_std_gyro_bias_rad_s: f32,
    /// Geodetic latitude of the site (rad).
    pub latitude_rad: f32,
    /// Height of the site above the WGS-84 ellipsoid (m).
    pub height_m: f32,
    /// Window of the least-squares dT/dt estimate (s, TCZUPT).
    pub temp_slope_window_s: f32,
}

impl UasnavZuptConfig {
    fn to_core(self) -> ZuptConfig<f32> {
        let d = ZuptConfig::<f32>::default();
        ZuptConfig {
            mode: if self.tczupt {
                nav_core::zupt::Mode::Tczupt
            } else {
                d.mode
            },
            noise: ProcessNoise {
                sigma_vrw_m_s_sqrt_s: self.sigma_vrw_m_s_sqrt_s,
                sigma_arw_rad_sqrt_s: self.sigma_arw_rad_sqrt_s,
                sigma_abi_m_s2: self.sigma_abi_m_s2,
                sigma_gbi_rad_s: self.sigma_gbi_rad_s,
            },
            meas_std_position_m: self.meas_std_position_m,
            meas_std_velocity_m_s: self.meas_std_velocity_m_s,
            meas_std_attitude_rad: self.meas_std_attitude_rad,
            update_interval_s: self.update_interval_s,
            init_std_position_m: self.init_std_position_m,
            init_std_velocity_m_s: self.init_std_velocity_m_s,
            init_std_attitude_rad: self.init_std_attitude_rad,
            init_std_accel_bias_m_s2: self.init_std_accel_bias_m_s2,
            init_std_gyro_bias_rad_s: self.init_std_gyro_bias_rad_s,
            latitude_rad: self.latitude_rad,
            height_m: self.height_m,
            temp_slope_window_s: self.temp_slope_window_s,
            ..d
        }
    }
}

/// Read-out of the ZUPT/TCZUPT filter.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UasnavZuptState {
    /// Position: NED displacement from the start (m).
    pub position_m: [f32; 3],
    /// Velocity (m/s, NED).
    pub velocity_m_s: [f32; 3],
    /// Attitude quaternion body → NED, scalar first.
    pub attitude: [f32; 4],
    /// Accelerometer bias estimate (m/s², body).
    pub accel_bias_m_s2: [f32; 3],
    /// Gyro bias estimate (rad/s, body).
    pub gyro_bias_rad_s: [f32; 3],
    /// Diagonal of the error covariance (order δr, δv, ψ, δb_a, δb_g; SI units squared).
    pub covariance_diag: [f32; 15],
    /// Normalised innovation squared of the latest update (χ², 9 degrees of freedom).
    pub last_nis: f32,
    /// Latest dT/dt estimate (°C/s, TCZUPT).
    pub temp_rate_c_s: f32,
    /// Number of updates applied.
    pub updates: u32,
}

/// Fills `out` with the default ZUPT configuration, or with TCZUPT and the thesis' TCZUPT
/// process noise when `tczupt`.
///
/// # Safety
/// `out` must point to a writable `UasnavZuptConfig` (or be null: error).
#[no_mangle]
pub unsafe extern "C" fn uasnav_zupt_config_default(
    out: *mut UasnavZuptConfig,
    tczupt: bool,
) -> UasnavStatus {
    let d = ZuptConfig::<f32>::default();
    let n = if tczupt {
        ProcessNoise::<f32>::thesis_tczupt()
    } else {
        d.noise
    };
    status(write(
        out,
        UasnavZuptConfig {
            tczupt,
            sigma_vrw_m_s_sqrt_s: n.sigma_vrw_m_s_sqrt_s,
            sigma_arw_rad_sqrt_s: n.sigma_arw_rad_sqrt_s,
            sigma_abi_m_s2: n.sigma_abi_m_s2,
            sigma_gbi_rad_s: n.sigma_gbi_rad_s,
            meas_std_position_m: d.meas_std_position_m,
            meas_std_velocity_m_s: d.meas_std_velocity_m_s,
            meas_std_attitude_rad: d.meas_std_attitude_rad,
            update_interval_s: d.update_interval_s,
            init_std_position_m: d.init_std_position_m,
            init_std_velocity_m_s: d.init_std_velocity_m_s,
            init_std_attitude_rad: d.init_std_attitude_rad,
            init_std_accel_bias_m_s2: d.init_std_accel_bias_m_s2,
            init_std_gyro_bias_rad_s: d.init_std_gyro_bias_rad_s,
            latitude_rad: d.latitude_rad,
            height_m: d.height_m,
            temp_slope_window_s: d.temp_slope_window_s,
        },
    ))
}

/// Creates (or resets) a ZUPT/TCZUPT filter at rest in `filter`: attitude `q0[4]` (body →
/// NED, scalar first, normalised here), initial biases `accel_bias_m_s2[3]` (m/s², body) and
/// `gyro_bias_rad_s[3]` (rad/s, body; both may be null for zero), sample period `dt_s` (s).
/// On error the object is left uninitialised.
///
/// # Safety
/// `filter` must point to caller-owned memory of `sizeof(UasnavZupt)`; the array pointers
/// to as many floats as stated.
#[no_mangle]
pub unsafe extern "C" fn uasnav_zupt_init(
    filter: *mut UasnavZupt,
    config: *const UasnavZuptConfig,
    q0: *const f32,
    accel_bias_m_s2: *const f32,
    gyro_bias_rad_s: *const f32,
    dt_s: f32,
) -> UasnavStatus {
    status((|| {
        check_ptr(filter)?;
        // SAFETY: non-null, aligned (checked) and a caller-owned `UasnavZupt` (the contract):
        // clearing the tag first leaves the object uninitialised if anything below fails.
        unsafe { (*filter).tag = 0 };
        let cfg = read::<UasnavZuptConfig, 1>(config)?[0].to_core();
        let q = quat(read(q0)?)?;
        let ba = read_or(accel_bias_m_s2, [0.0; 3])?;
        let bg = read_or(gyro_bias_rad_s, [0.0; 3])?;
        let f = ZuptFilter::new(cfg, q, Vector3::from(ba), Vector3::from(bg), dt_s)?;
        store(filter, f)
    })())
}

/// One propagation step with gyro `gyro_rad_s[3]` (rad/s, body) and specific force
/// `accel_m_s2[3]` (m/s², body) held over the sample period, and the deterministic gyro-bias
/// rate `dbias_dt_rad_s2[3]` (rad/s², null for zero). A non-finite input leaves the filter
/// unchanged; `UASNAV_STATUS_NOT_POSITIVE_DEFINITE` or a non-finite solution means
/// re-initialise.
///
/// # Safety
/// `filter` must have been created by [`uasnav_zupt_init`]; the arrays hold 3 floats.
#[no_mangle]
pub unsafe extern "C" fn uasnav_zupt_predict(
    filter: *mut UasnavZupt,
    gyro_rad_s: *const f32,
    accel_m_s2: *const f32,
    dbias_dt_rad_s2: *const f32,
) -> UasnavStatus {
    status((|| {
        let f = live(filter)?;
        let g = read(gyro_rad_s)?;
        let a = read(accel_m_s2)?;
        let d = read_or(dbias_dt_rad_s2, [0.0; 3])?;
        Ok(f.predict(&g, &a, &Vector3::from(d))?)
    })())
}

/// The ZUPT measurement update (frozen position, zero velocity, frozen attitude) now; call it
/// only while the unit is stationary.
///
/// # Safety
/// `filter` must have been created by [`uasnav_zupt_init`].
#[no_mangle]
pub unsafe extern "C" fn uasnav_zupt_update(filter: *mut UasnavZupt) -> UasnavStatus {
    status((|| Ok(live(filter)?.update()?))())
}

/// One sample with the filter's own scheduling: dT/dt from `temp_c` (°C, TCZUPT), the gyro
/// bias rate `∂b/∂T · dT/dt` with `∂b_i/∂T = dbias_scale[i] · mlp'(temp_c)` (rad/s/°C; `mlp`
/// null or `dbias_scale` null: zero), the propagation, and the update when `stationary` and
/// one is due (every `update_interval_s`). `*updated` (may be null) tells whether it was.
///
/// # Safety
/// `filter` created by [`uasnav_zupt_init`], `mlp` (if not null) by [`uasnav_mlp_init`];
/// arrays of 3 floats.
#[no_mangle]
pub unsafe extern "C" fn uasnav_zupt_step(
    filter: *mut UasnavZupt,
    gyro_rad_s: *const f32,
    accel_m_s2: *const f32,
    temp_c: f32,
    stationary: bool,
    mlp: *mut UasnavMlp,
    dbias_scale: *const f32,
    updated: *mut bool,
) -> UasnavStatus {
    status((|| {
        let f = live(filter)?;
        let g = read(gyro_rad_s)?;
        let a = read(accel_m_s2)?;
        let net = if mlp.is_null() || dbias_scale.is_null() {
            None
        } else {
            Some((&*live(mlp)?, read::<f32, 3>(dbias_scale)?))
        };
        let mut deriv = |_k: usize, t: f32| match net {
            Some((m, s)) => {
                let d = m.eval(t).derivative;
                Vector3::new(d * s[0], d * s[1], d * s[2])
            }
            None => Vector3::zeros(),
        };
        let did = f.step(&g, &a, Some(temp_c), stationary, &mut deriv)?;
        if !updated.is_null() {
            write(updated, did)?;
        }
        Ok(())
    })())
}

/// Copies the filter's solution, biases and covariance diagonal into `out`.
///
/// # Safety
/// `filter` created by [`uasnav_zupt_init`]; `out` a writable `UasnavZuptState`.
#[no_mangle]
pub unsafe extern "C" fn uasnav_zupt_state(
    filter: *mut UasnavZupt,
    out: *mut UasnavZuptState,
) -> UasnavStatus {
    status((|| {
        let f = live(filter)?;
        write(
            out,
            UasnavZuptState {
                position_m: f.position_m().into(),
                velocity_m_s: f.velocity_m_s().into(),
                attitude: quat_out(f.attitude()),
                accel_bias_m_s2: f.accel_bias_m_s2().into(),
                gyro_bias_rad_s: f.gyro_bias_rad_s().into(),
                covariance_diag: diag15(f.covariance()),
                last_nis: f.last_nis(),
                temp_rate_c_s: f.temp_rate_c_s(),
                updates: u32::try_from(f.updates()).unwrap_or(u32::MAX),
            },
        )
    })())
}

// ---------------------------------------------------------------------------------------------
// MLP.

/// Creates a thermal MLP in `mlp`: `n1` tanh neurons in the first hidden layer, `n2` in the
/// second (0: one hidden layer), a linear output neuron; `w1[n1]`, `b1[n1]`, `w2[n2·n1]`
/// (row-major, `w2[j·n1 + i]` from neuron i to j; null when `n2` is 0), `b2[n2]`,
/// `w3[n2 or n1]`, output bias `b3`; `norm[4]` = input offset (°C), input gain (1/°C), output
/// offset and output scale (output unit, e.g. rad/s); `range[2]` the calibrated input range
/// (°C). At most 16 neurons per layer.
///
/// # Safety
/// `mlp` caller-owned memory of `sizeof(UasnavMlp)`; arrays of the stated lengths.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn uasnav_mlp_init(
    mlp: *mut UasnavMlp,
    n1: usize,
    n2: usize,
    w1: *const f32,
    b1: *const f32,
    w2: *const f32,
    b2: *const f32,
    w3: *const f32,
    b3: f32,
    norm: *const f32,
    range: *const f32,
) -> UasnavStatus {
    const M: usize = nav_core::mlp::MAX_NEURONS;
    status((|| {
        check_ptr(mlp)?;
        // SAFETY: non-null, aligned, caller-owned (the contract): the object is uninitialised
        // until `store` succeeds.
        unsafe { (*mlp).tag = 0 };
        if n1 == 0 || n1 > M || n2 > M {
            return Err(UasnavStatus::InvalidParameter);
        }
        let n_out = if n2 == 0 { n1 } else { n2 };
        let w1: [f32; M] = read_n(w1, n1)?;
        let b1: [f32; M] = read_n(b1, n1)?;
        let w3: [f32; M] = read_n(w3, n_out)?;
        let mut w2s = [0.0f32; M * M];
        let mut b2s = [0.0f32; M];
        if n2 > 0 {
            // Row by row: at most 16 × 16 values.
            for j in 0..n2 {
                // `wrapping_add` is plain address arithmetic; `read_n` checks the result.
                let row: [f32; M] = read_n(w2.wrapping_add(j * n1), n1)?;
                w2s[j * n1..(j + 1) * n1].copy_from_slice(&row[..n1]);
            }
            b2s = read_n(b2, n2)?;
        }
        let [in_off, in_gain, out_off, out_scale] = read(norm)?;
        let [lo, hi] = read(range)?;
        let b3 = [b3];
        let hidden1 = LayerSpec {
            weights: &w1[..n1],
            biases: &b1[..n1],
            activation: Activation::Tanh,
        };
        let output = LayerSpec {
            weights: &w3[..n_out],
            biases: &b3,
            activation: Activation::Linear,
        };
        let input = Affine {
            offset: in_off,
            scale: in_gain,
        };
        let out = Affine {
            offset: out_off,
            scale: out_scale,
        };
        let net = if n2 == 0 {
            Mlp::new(&[hidden1, output], input, out, (lo, hi))?
        } else {
            let hidden2 = LayerSpec {
                weights: &w2s[..n1 * n2],
                biases: &b2s[..n2],
                activation: Activation::Tanh,
            };
            Mlp::new(&[hidden1, hidden2, output], input, out, (lo, hi))?
        };
        store(mlp, net)
    })())
}

/// Reads `n ≤ 16` floats from `p` into the front of a 16-float array.
fn read_n(p: *const f32, n: usize) -> Result<[f32; nav_core::mlp::MAX_NEURONS], UasnavStatus> {
    let mut out = [0.0f32; nav_core::mlp::MAX_NEURONS];
    if n > out.len() {
        return Err(UasnavStatus::InvalidParameter);
    }
    check_ptr(p)?;
    // SAFETY: non-null and aligned (checked); `n` ≤ 16 (checked) and the caller's array holds
    // at least `n` floats (the contract of `uasnav_mlp_init`).
    let src = unsafe { core::slice::from_raw_parts(p, n) };
    out[..n].copy_from_slice(src);
    Ok(out)
}

/// The network's output `*value` (output unit) and derivative `*derivative` (output unit per
/// °C) at `x` (°C); with `clip` the input is held to the calibrated range (derivative 0
/// outside it). Either output pointer may be null.
///
/// # Safety
/// `mlp` created by [`uasnav_mlp_init`].
#[no_mangle]
pub unsafe extern "C" fn uasnav_mlp_eval(
    mlp: *mut UasnavMlp,
    x: f32,
    clip: bool,
    value: *mut f32,
    derivative: *mut f32,
) -> UasnavStatus {
    status((|| {
        let m = live(mlp)?;
        let o = if clip {
            m.eval_clipped(x)?
        } else if x.is_finite() {
            m.eval(x)
        } else {
            return Err(UasnavStatus::NonFinite);
        };
        if !value.is_null() {
            write(value, o.value)?;
        }
        if !derivative.is_null() {
            write(derivative, o.derivative)?;
        }
        Ok(())
    })())
}

// ---------------------------------------------------------------------------------------------
// GNSS/INS.

/// The main settings of the GNSS/INS filter (the others keep nav-core's defaults); fill it
/// with [`uasnav_ins_config_default`].
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UasnavInsConfig {
    /// Velocity random walk σ_VRW (m/s/√s).
    pub sigma_vrw_m_s_sqrt_s: f32,
    /// Angle random walk σ_ARW (rad/√s).
    pub sigma_arw_rad_sqrt_s: f32,
    /// Accelerometer bias random walk σ_ABI (m/s² per √s).
    pub sigma_abi_m_s2: f32,
    /// Gyro bias random walk σ_GBI (rad/s per √s).
    pub sigma_gbi_rad_s: f32,
    /// Initial σ of roll and pitch (rad).
    pub init_std_tilt_rad: f32,
    /// Initial σ of the heading (rad).
    pub init_std_heading_rad: f32,
    /// Initial σ of the accelerometer bias (m/s²).
    pub init_std_accel_bias_m_s2: f32,
    /// Initial σ of the gyro bias (rad/s).
    pub init_std_gyro_bias_rad_s: f32,
    /// GNSS antenna position relative to the IMU (m, body).
    pub lever_arm_m: [f32; 3],
    /// Floor on the reported position accuracy (m).
    pub gnss_min_std_position_m: f32,
    /// Floor on the reported speed accuracy (m/s).
    pub gnss_min_std_velocity_m_s: f32,
    /// χ² threshold (6 degrees of freedom) of the fix and window tests.
    pub gate_chi2: f32,
}

/// Read-out of the GNSS/INS filter.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UasnavInsState {
    /// Latitude (rad), longitude (rad), height above the WGS-84 ellipsoid (m).
    pub llh: [f64; 3],
    /// Velocity (m/s, NED).
    pub velocity_m_s: [f32; 3],
    /// Attitude quaternion body → NED, scalar first.
    pub attitude: [f32; 4],
    /// Accelerometer bias estimate (m/s², body).
    pub accel_bias_m_s2: [f32; 3],
    /// Gyro bias estimate (rad/s, body).
    pub gyro_bias_rad_s: [f32; 3],
    /// Diagonal of the error covariance (order δr N/E/D in m, δv, ψ, δb_a, δb_g; SI squared).
    pub covariance_diag: [f32; 15],
    /// Normalised innovation squared of the latest fix tested.
    pub last_nis: f32,
    /// Horizontal and vertical protection levels (m).
    pub protection_level_m: [f32; 2],
}

/// Fills `out` with nav-core's default GNSS/INS settings (a consumer MEMS IMU).
///
/// # Safety
/// `out` a writable `UasnavInsConfig`.
#[no_mangle]
pub unsafe extern "C" fn uasnav_ins_config_default(out: *mut UasnavInsConfig) -> UasnavStatus {
    let d = InsConfig::<f32>::default();
    status(write(
        out,
        UasnavInsConfig {
            sigma_vrw_m_s_sqrt_s: d.noise.sigma_vrw_m_s_sqrt_s,
            sigma_arw_rad_sqrt_s: d.noise.sigma_arw_rad_sqrt_s,
            sigma_abi_m_s2: d.noise.sigma_abi_m_s2,
            sigma_gbi_rad_s: d.noise.sigma_gbi_rad_s,
            init_std_tilt_rad: d.init_std_tilt_rad,
            init_std_heading_rad: d.init_std_heading_rad,
            init_std_accel_bias_m_s2: d.init_std_accel_bias_m_s2,
            init_std_gyro_bias_rad_s: d.init_std_gyro_bias_rad_s,
            lever_arm_m: d.lever_arm_m,
            gnss_min_std_position_m: d.gnss_min_std_position_m,
            gnss_min_std_velocity_m_s: d.gnss_min_std_velocity_m_s,
            gate_chi2: d.gate_chi2,
        },
    ))
}

/// Creates (or resets) a GNSS/INS filter in `filter` at `llh[3]` (latitude, longitude in rad,
/// ellipsoidal height in m), velocity `vel_ned_m_s[3]` (m/s, NED), attitude `q[4]` (body →
/// NED, scalar first), initial σ `std_position_m[3]` (m, N/E/D) and `std_velocity_m_s[3]`
/// (m/s). On error the object is left uninitialised.
///
/// # Safety
/// `filter` caller-owned memory of `sizeof(UasnavIns)`; arrays of the stated lengths.
#[no_mangle]
pub unsafe extern "C" fn uasnav_ins_init(
    filter: *mut UasnavIns,
    config: *const UasnavInsConfig,
    llh: *const f64,
    vel_ned_m_s: *const f32,
    q: *const f32,
    std_position_m: *const f32,
    std_velocity_m_s: *const f32,
) -> UasnavStatus {
    status((|| {
        check_ptr(filter)?;
        // SAFETY: non-null, aligned, caller-owned (the contract): uninitialised until `store`.
        unsafe { (*filter).tag = 0 };
        let c = read::<UasnavInsConfig, 1>(config)?[0];
        let d = InsConfig::<f32>::default();
        let cfg = InsConfig {
            noise: ProcessNoise {
                sigma_vrw_m_s_sqrt_s: c.sigma_vrw_m_s_sqrt_s,
                sigma_arw_rad_sqrt_s: c.sigma_arw_rad_sqrt_s,
                sigma_abi_m_s2: c.sigma_abi_m_s2,
                sigma_gbi_rad_s: c.sigma_gbi_rad_s,
            },
            init_std_tilt_rad: c.init_std_tilt_rad,
            init_std_heading_rad: c.init_std_heading_rad,
            init_std_accel_bias_m_s2: c.init_std_accel_bias_m_s2,
            init_std_gyro_bias_rad_s: c.init_std_gyro_bias_rad_s,
            lever_arm_m: c.lever_arm_m,
            gnss_min_std_position_m: c.gnss_min_std_position_m,
            gnss_min_std_velocity_m_s: c.gnss_min_std_velocity_m_s,
            gate_chi2: c.gate_chi2,
            ..d
        };
        let [lat, lon, h] = read(llh)?;
        let v = read(vel_ned_m_s)?;
        let q = quat(read(q)?)?;
        let f = InsFilter::new(
            cfg,
            lat,
            lon,
            h,
            Vector3::from(v),
            q,
            read(std_position_m)?,
            read(std_velocity_m_s)?,
        )?;
        store(filter, f)
    })())
}

/// One mechanisation and covariance step over `dt_s` (s) with gyro `gyro_rad_s[3]` (rad/s,
/// body), specific force `accel_m_s2[3]` (m/s², body) and gyro-bias rate `dbias_dt_rad_s2[3]`
/// (rad/s², null for zero). A non-finite input leaves the filter unchanged.
///
/// # Safety
/// `filter` created by [`uasnav_ins_init`]; arrays of 3 floats.
#[no_mangle]
pub unsafe extern "C" fn uasnav_ins_predict(
    filter: *mut UasnavIns,
    gyro_rad_s: *const f32,
    accel_m_s2: *const f32,
    dt_s: f32,
    dbias_dt_rad_s2: *const f32,
) -> UasnavStatus {
    status((|| {
        let f = live(filter)?;
        let g = read(gyro_rad_s)?;
        let a = read(accel_m_s2)?;
        let d = read_or(dbias_dt_rad_s2, [0.0; 3])?;
        Ok(f.predict(&g, &a, dt_s, &Vector3::from(d))?)
    })())
}

/// A GNSS fix: antenna `llh[3]` (rad, rad, m ellipsoidal), velocity `vel_ned_m_s[3]` (m/s,
/// NED), reported σ `accuracy[3]` (horizontal m, vertical m, speed m/s), valid `age_s` (s ≥ 0)
/// before the current IMU time. `*fix_status` (may be null) receives what was done: 0 used,
/// 1 excluded by its own χ² test, 2 excluded by the window test, 3 masked, 4 unused,
/// 5 excluded and the filter re-initialised on it, 6 used with a solution-separation alert.
///
/// # Safety
/// `filter` created by [`uasnav_ins_init`]; arrays of the stated lengths.
#[no_mangle]
pub unsafe extern "C" fn uasnav_ins_update_gnss(
    filter: *mut UasnavIns,
    llh: *const f64,
    vel_ned_m_s: *const f32,
    accuracy: *const f32,
    age_s: f64,
    fix_status: *mut u8,
) -> UasnavStatus {
    status((|| {
        let f = live(filter)?;
        let p = read(llh)?;
        let v = read(vel_ned_m_s)?;
        let acc = read(accuracy)?;
        let st = f.update_gnss(&p, &v, &acc, age_s)?;
        if !fix_status.is_null() {
            write(fix_status, st as u8)?;
        }
        Ok(())
    })())
}

/// Copies the filter's solution, biases, covariance diagonal and protection levels into `out`.
///
/// # Safety
/// `filter` created by [`uasnav_ins_init`]; `out` a writable `UasnavInsState`.
#[no_mangle]
pub unsafe extern "C" fn uasnav_ins_state(
    filter: *mut UasnavIns,
    out: *mut UasnavInsState,
) -> UasnavStatus {
    status((|| {
        let f = live(filter)?;
        let (hpl, vpl) = f.protection_levels();
        write(
            out,
            UasnavInsState {
                llh: f.position(),
                velocity_m_s: f.velocity_m_s().into(),
                attitude: quat_out(f.attitude()),
                accel_bias_m_s2: f.accel_bias_m_s2().into(),
                gyro_bias_rad_s: f.gyro_bias_rad_s().into(),
                covariance_diag: diag15(f.covariance()),
                last_nis: f.last_nis(),
                protection_level_m: [hpl, vpl],
            },
        )
    })())
}
