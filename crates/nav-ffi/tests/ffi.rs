//! The C interface against nav-core itself (bit for bit), and hostile calls: every one comes
//! back as a status code. A panic inside an `extern "C"` function aborts the test process, so
//! these tests also show that none of the inputs reach a panic.
use std::mem::MaybeUninit;

use nalgebra::Vector3;
use nav_core::ins::{InsConfig, InsFilter};
use nav_core::zupt::{ZuptConfig, ZuptFilter};
use nav_ffi::*;
use proptest::prelude::*;

fn zupt_obj() -> Box<MaybeUninit<UasnavZupt>> {
    Box::new(MaybeUninit::uninit())
}

fn ins_obj() -> Box<MaybeUninit<UasnavIns>> {
    Box::new(MaybeUninit::uninit())
}

/// A deterministic "IMU at rest" sample with a little motion.
fn sample(k: usize) -> ([f32; 3], [f32; 3]) {
    let t = k as f32 * 0.01;
    (
        [1e-3 * t.sin(), -2e-3 * (0.5 * t).cos(), 5e-4],
        [0.05 * t.cos(), -0.02, -9.8],
    )
}

fn zupt_init(obj: &mut MaybeUninit<UasnavZupt>, q0: &[f32; 4], tczupt: bool) -> UasnavStatus {
    let mut cfg = MaybeUninit::<UasnavZuptConfig>::uninit();
    // SAFETY: `cfg` is a writable UasnavZuptConfig; `obj` caller-owned storage of the right
    // type; `q0` 4 floats; null biases are allowed.
    unsafe {
        assert_eq!(
            uasnav_zupt_config_default(cfg.as_mut_ptr(), tczupt),
            UasnavStatus::Ok
        );
        uasnav_zupt_init(
            obj.as_mut_ptr(),
            cfg.as_ptr(),
            q0.as_ptr(),
            std::ptr::null(),
            std::ptr::null(),
            0.01,
        )
    }
}

#[test]
fn zupt_through_the_c_interface_equals_nav_core() {
    let q = nav_core::attitude::euler321_to_quat(0.02f32, -0.01, 0.5);
    let q0 = [q.w, q.i, q.j, q.k];
    let mut obj = zupt_obj();
    assert_eq!(zupt_init(&mut obj, &q0, false), UasnavStatus::Ok);
    let mut core = ZuptFilter::new(
        ZuptConfig::<f32>::default(),
        q,
        Vector3::zeros(),
        Vector3::zeros(),
        0.01,
    )
    .unwrap();
    for k in 0..200 {
        let (g, a) = sample(k);
        // SAFETY: `obj` initialised above; `g`, `a` 3 floats each; null bias rate allowed.
        let s = unsafe {
            uasnav_zupt_predict(obj.as_mut_ptr(), g.as_ptr(), a.as_ptr(), std::ptr::null())
        };
        assert_eq!(s, UasnavStatus::Ok);
        core.predict(&g, &a, &Vector3::zeros()).unwrap();
        if k % 10 == 9 {
            // SAFETY: initialised object.
            let s = unsafe { uasnav_zupt_update(obj.as_mut_ptr()) };
            assert_eq!(s, UasnavStatus::Ok);
            core.update().unwrap();
        }
    }
    let mut st = MaybeUninit::<UasnavZuptState>::uninit();
    // SAFETY: initialised object, writable state.
    let s = unsafe { uasnav_zupt_state(obj.as_mut_ptr(), st.as_mut_ptr()) };
    assert_eq!(s, UasnavStatus::Ok);
    // SAFETY: written by the successful call above.
    let st = unsafe { st.assume_init() };
    let cq = core.attitude();
    assert_eq!(st.attitude, [cq.w, cq.i, cq.j, cq.k]);
    assert_eq!(st.position_m, <[f32; 3]>::from(core.position_m()));
    assert_eq!(st.velocity_m_s, <[f32; 3]>::from(core.velocity_m_s()));
    assert_eq!(st.gyro_bias_rad_s, <[f32; 3]>::from(core.gyro_bias_rad_s()));
    assert_eq!(st.accel_bias_m_s2, <[f32; 3]>::from(core.accel_bias_m_s2()));
    for i in 0..15 {
        assert_eq!(st.covariance_diag[i], core.covariance()[(i, i)]);
    }
    assert_eq!(st.updates, 20);
    assert_eq!(st.last_nis, core.last_nis());
}

#[test]
fn ins_through_the_c_interface_equals_nav_core() {
    let q = nav_core::attitude::euler321_to_quat(0.0f32, 0.0, 1.0);
    let q0 = [q.w, q.i, q.j, q.k];
    let llh = [0.785_f64, 0.122, 300.0];
    let v0 = [5.0f32, 0.0, 0.0];
    let (sp, sv) = ([1.5f32, 1.5, 2.5], [0.15f32; 3]);
    let mut cfg = MaybeUninit::<UasnavInsConfig>::uninit();
    let mut obj = ins_obj();
    // SAFETY: writable config; caller-owned object; arrays of the stated lengths.
    unsafe {
        assert_eq!(
            uasnav_ins_config_default(cfg.as_mut_ptr()),
            UasnavStatus::Ok
        );
        let s = uasnav_ins_init(
            obj.as_mut_ptr(),
            cfg.as_ptr(),
            llh.as_ptr(),
            v0.as_ptr(),
            q0.as_ptr(),
            sp.as_ptr(),
            sv.as_ptr(),
        );
        assert_eq!(s, UasnavStatus::Ok);
    }
    let mut core = InsFilter::new(
        InsConfig::<f32>::default(),
        llh[0],
        llh[1],
        llh[2],
        Vector3::from(v0),
        q,
        sp,
        sv,
    )
    .unwrap();
    let mut status = 255u8;
    for k in 0..100 {
        let (g, a) = sample(k);
        // SAFETY: initialised object; 3-float arrays.
        let s = unsafe {
            uasnav_ins_predict(
                obj.as_mut_ptr(),
                g.as_ptr(),
                a.as_ptr(),
                0.01,
                std::ptr::null(),
            )
        };
        assert_eq!(s, UasnavStatus::Ok);
        core.predict(&g, &a, 0.01, &Vector3::zeros()).unwrap();
        if k % 20 == 19 {
            let p = core.position();
            let fix = [p[0] + 1e-7, p[1], p[2] + 0.5];
            let (vel, acc) = ([5.0f32, 0.1, 0.0], [1.5f32, 2.5, 0.15]);
            // SAFETY: initialised object; arrays of 3; writable status byte.
            let s = unsafe {
                uasnav_ins_update_gnss(
                    obj.as_mut_ptr(),
                    fix.as_ptr(),
                    vel.as_ptr(),
                    acc.as_ptr(),
                    0.0,
                    &mut status,
                )
            };
            assert_eq!(s, UasnavStatus::Ok);
            let st = core.update_gnss(&fix, &vel, &acc, 0.0).unwrap();
            assert_eq!(status, st as u8);
        }
    }
    let mut out = MaybeUninit::<UasnavInsState>::uninit();
    // SAFETY: initialised object, writable state.
    let s = unsafe { uasnav_ins_state(obj.as_mut_ptr(), out.as_mut_ptr()) };
    assert_eq!(s, UasnavStatus::Ok);
    // SAFETY: written by the call above.
    let out = unsafe { out.assume_init() };
    assert_eq!(out.llh, core.position());
    assert_eq!(out.velocity_m_s, <[f32; 3]>::from(core.velocity_m_s()));
    let cq = core.attitude();
    assert_eq!(out.attitude, [cq.w, cq.i, cq.j, cq.k]);
    let (h, v) = core.protection_levels();
    assert_eq!(out.protection_level_m, [h, v]);
}

#[test]
fn bad_pointers_and_uninitialised_objects_are_status_codes() {
    let g = [0.0f32; 3];
    let mut obj = zupt_obj();
    // SAFETY: every pointer is null, valid or points to storage of the right type; the
    // functions must refuse the null and uninitialised ones without touching them.
    unsafe {
        // Zeroed storage: never initialised.
        std::ptr::write_bytes(obj.as_mut_ptr(), 0, 1);
        assert_eq!(
            uasnav_zupt_update(obj.as_mut_ptr()),
            UasnavStatus::NotInitialised
        );
        assert_eq!(
            uasnav_zupt_update(std::ptr::null_mut()),
            UasnavStatus::NullPointer
        );
        assert_eq!(
            uasnav_zupt_predict(obj.as_mut_ptr(), g.as_ptr(), g.as_ptr(), std::ptr::null()),
            UasnavStatus::NotInitialised
        );
        // Misaligned object pointer.
        let p = (obj.as_mut_ptr() as *mut u8).wrapping_add(1) as *mut UasnavZupt;
        assert_eq!(uasnav_zupt_update(p), UasnavStatus::Misaligned);
        // A failed init leaves the object uninitialised, also after a good one.
        assert_eq!(
            zupt_init(&mut obj, &[1.0, 0.0, 0.0, 0.0], false),
            UasnavStatus::Ok
        );
        assert_eq!(
            zupt_init(&mut obj, &[0.0, 0.0, 0.0, 0.0], false),
            UasnavStatus::InvalidParameter
        );
        assert_eq!(
            uasnav_zupt_update(obj.as_mut_ptr()),
            UasnavStatus::NotInitialised
        );
        let mut st = MaybeUninit::<UasnavZuptState>::uninit();
        assert_eq!(
            uasnav_zupt_state(obj.as_mut_ptr(), st.as_mut_ptr()),
            UasnavStatus::NotInitialised
        );
        let mut m = Box::new(MaybeUninit::<UasnavMlp>::zeroed());
        let mut y = 0.0f32;
        assert_eq!(
            uasnav_mlp_eval(m.as_mut_ptr(), 20.0, false, &mut y, std::ptr::null_mut()),
            UasnavStatus::NotInitialised
        );
        let w = [1.0f32; 16];
        let norm = [25.0f32, 0.05, 0.0, 1e-3];
        let range = [-40.0f32, 85.0];
        // 17 neurons: refused; 0 neurons: refused; reversed range: refused.
        for (n1, r) in [(17usize, range), (0, range), (4, [85.0, -40.0])] {
            let s = uasnav_mlp_init(
                m.as_mut_ptr(),
                n1,
                0,
                w.as_ptr(),
                w.as_ptr(),
                std::ptr::null(),
                std::ptr::null(),
                w.as_ptr(),
                0.0,
                norm.as_ptr(),
                r.as_ptr(),
            );
            assert_ne!(s, UasnavStatus::Ok);
        }
        let s = uasnav_mlp_init(
            m.as_mut_ptr(),
            4,
            3,
            w.as_ptr(),
            w.as_ptr(),
            std::ptr::null(),
            w.as_ptr(),
            w.as_ptr(),
            0.0,
            norm.as_ptr(),
            range.as_ptr(),
        );
        assert_eq!(s, UasnavStatus::NullPointer);
        let s = uasnav_mlp_init(
            m.as_mut_ptr(),
            4,
            3,
            w.as_ptr(),
            w.as_ptr(),
            w.as_ptr(),
            w.as_ptr(),
            w.as_ptr(),
            0.0,
            norm.as_ptr(),
            range.as_ptr(),
        );
        assert_eq!(s, UasnavStatus::Ok);
        assert_eq!(
            uasnav_mlp_eval(m.as_mut_ptr(), f32::NAN, true, &mut y, std::ptr::null_mut()),
            UasnavStatus::NonFinite
        );
        assert_eq!(
            uasnav_mlp_eval(m.as_mut_ptr(), 100.0, true, &mut y, std::ptr::null_mut()),
            UasnavStatus::Ok
        );
    }
}

proptest! {
    /// Arbitrary floats (NaN, ±inf, huge, subnormal) into every step: a status, never a panic
    /// (which would abort the process), and a non-finite input leaves the filter unchanged.
    #[test]
    fn hostile_samples_give_status_codes(
        g in prop::array::uniform3(prop::num::f32::ANY),
        a in prop::array::uniform3(prop::num::f32::ANY),
        d in prop::array::uniform3(prop::num::f32::ANY),
        temp in prop::num::f32::ANY,
        dt in prop::num::f32::ANY,
        llh in prop::array::uniform3(prop::num::f64::ANY),
        acc in prop::array::uniform3(prop::num::f32::ANY),
        still in any::<bool>(),
    ) {
        let mut z = zupt_obj();
        prop_assert_eq!(zupt_init(&mut z, &[1.0, 0.0, 0.0, 0.0], true), UasnavStatus::Ok);
        let mut before = MaybeUninit::<UasnavZuptState>::uninit();
        let mut after = MaybeUninit::<UasnavZuptState>::uninit();
        let mut i = ins_obj();
        let mut cfg = MaybeUninit::<UasnavInsConfig>::uninit();
        let q0 = [1.0f32, 0.0, 0.0, 0.0];
        // SAFETY: initialised objects or caller-owned storage of the right type; arrays of the
        // stated lengths; writable outputs.
        unsafe {
            prop_assert_eq!(uasnav_zupt_state(z.as_mut_ptr(), before.as_mut_ptr()), UasnavStatus::Ok);
            let s = uasnav_zupt_predict(z.as_mut_ptr(), g.as_ptr(), a.as_ptr(), d.as_ptr());
            prop_assert_eq!(uasnav_zupt_state(z.as_mut_ptr(), after.as_mut_ptr()), UasnavStatus::Ok);
            if s == UasnavStatus::NonFinite && !(g.iter().chain(&a).chain(&d).all(|x| x.is_finite())) {
                prop_assert_eq!(before.assume_init(), after.assume_init());
            }
            let mut upd = false;
            let _ = uasnav_zupt_step(z.as_mut_ptr(), g.as_ptr(), a.as_ptr(), temp, still, std::ptr::null_mut(), std::ptr::null(), &mut upd);
            let _ = uasnav_zupt_update(z.as_mut_ptr());
            prop_assert_eq!(uasnav_ins_config_default(cfg.as_mut_ptr()), UasnavStatus::Ok);
            let start = [0.785f64, 0.122, 300.0];
            let v0 = [0.0f32; 3];
            let sp = [1.0f32; 3];
            let _ = uasnav_ins_init(i.as_mut_ptr(), cfg.as_ptr(), llh.as_ptr(), v0.as_ptr(), q0.as_ptr(), sp.as_ptr(), sp.as_ptr());
            prop_assert_eq!(uasnav_ins_init(i.as_mut_ptr(), cfg.as_ptr(), start.as_ptr(), v0.as_ptr(), q0.as_ptr(), sp.as_ptr(), sp.as_ptr()), UasnavStatus::Ok);
            let _ = uasnav_ins_predict(i.as_mut_ptr(), g.as_ptr(), a.as_ptr(), dt, d.as_ptr());
            let mut st = 0u8;
            let _ = uasnav_ins_update_gnss(i.as_mut_ptr(), llh.as_ptr(), g.as_ptr(), acc.as_ptr(), f64::from(dt), &mut st);
            let mut out = MaybeUninit::<UasnavInsState>::uninit();
            prop_assert_eq!(uasnav_ins_state(i.as_mut_ptr(), out.as_mut_ptr()), UasnavStatus::Ok);
        }
    }
}
