//! The one strapdown mechanisation and error-state kernel shared by the ZUPT filter
//! ([`crate::zupt`]) and the GNSS/INS filter ([`crate::ins`]).
//!
//! Both filters carry the same 15 error states (Groves 2013, §14.2.4, local-navigation frame)
//!
//! `δx = [δr (m, NED), δv (m/s, NED), ψ (rad, NED), δb_a (m/s², body), δb_g (rad/s, body)]`,
//!
//! every component *estimate − truth*, `Ĉ_b^n = (I + [ψ×])·C_b^n`, and the same continuous
//! error model
//!
//! ```text
//! δṙ  = δv
//! δv̇  = (2g/r_eS)·δr_D·e_D − [ω_v×]·δv − [(Ĉf̂)×]·ψ − Ĉ·δb_a
//! ψ̇   = −[ω_ψ×]·ψ − Ĉ·δb_g
//! δḃ_a = η_ba,   δḃ_g = η_bg
//! ```
//!
//! with `ω_v = 2ω_ie + ω_en` (Coriolis and transport rate) and `ω_ψ = ω_in = ω_ie + ω_en`. The
//! ZUPT filter, at rest, has `ω_en = 0`; the GNSS/INS filter passes the transport rate of its
//! current velocity. Terms of order `|v|/R` (≈ 3e-6 s⁻¹ at 20 m/s) on δr and ψ are dropped:
//! over a 60 s outage they change the error by well under 1 %.
//!
//! The attitude update is `q ← exp(−ω_ψ·Ts/2) ⊗ q ⊗ exp(ω̂_b·Ts/2)` (body rotation on the
//! right, rotation of the navigation frame on the left), renormalised with one Newton step.
//!
//! `Φ = I + F·Ts` is applied block-wise (≈ 960 multiply-adds instead of two dense 15×15
//! products, 6750); the second-order `Φ = I + F·Ts + (F·Ts)²/2` is the dense reference path.
//! The measurement update is the Joseph form for any `M×15` measurement matrix, with a
//! Cholesky factorisation of the innovation covariance (failure → `NotPositiveDefinite`).
// No unchecked indexing in library code (issue #20); a proven index carries an `allow`.
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]
use nalgebra::{Matrix3, Quaternion, SMatrix, SVector, UnitQuaternion, Vector3};

use crate::attitude::quat_from_rotation_vector;
use crate::scalar::lit;
use crate::{NavError, Real};

/// Number of error states.
pub const N_STATES: usize = 15;

/// 15×15 error covariance.
pub type Mat15<T> = SMatrix<T, N_STATES, N_STATES>;

/// Discretisation of the transition matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Discretisation {
    /// `Φ = I + F·Ts` (eq. 16), propagated with block-sparse products (fast path).
    #[default]
    FirstOrder,
    /// `Φ = I + F·Ts + (F·Ts)²/2`, propagated with dense 15×15 products (reference path).
    SecondOrder,
}

/// `[v×]`, the cross-product matrix.
#[inline(always)]
pub fn skew<T: Real>(v: &Vector3<T>) -> Matrix3<T> {
    Matrix3::new(
        T::zero(),
        -v.z,
        v.y,
        v.z,
        T::zero(),
        -v.x,
        -v.y,
        v.x,
        T::zero(),
    )
}

/// `exp(φ/2)` for a small rotation vector `φ` (rad), not normalised: 4th-order series below
/// 1e-4 rad (truncation |φ|⁶/46080 < 3e-29, below f64 resolution), exact above.
#[inline(always)]
pub(crate) fn small_rotation<T: Real>(phi: &Vector3<T>) -> Quaternion<T> {
    let n2 = phi.norm_squared();
    if n2 < lit(1e-8) {
        let k = lit::<T>(0.5) - n2 / lit(48.0);
        Quaternion::new(
            T::one() - n2 / lit(8.0) + n2 * n2 / lit(384.0),
            phi.x * k,
            phi.y * k,
            phi.z * k,
        )
    } else {
        quat_from_rotation_vector(phi).into_inner()
    }
}

/// One attitude step: `q ← q_nav ⊗ q ⊗ exp(ω̂_b·Ts/2)` with `q_nav = exp(−ω_ψ·Ts/2)` the
/// rotation of the navigation frame over the step, and one Newton step towards `|q| = 1`
/// (`|q|² − 1` is O(1e-16) here: no sqrt, no division).
#[inline(always)]
pub(crate) fn attitude_step<T: Real>(
    q: &UnitQuaternion<T>,
    body_rate_rad_s: &Vector3<T>,
    dt_s: T,
    q_nav: &Quaternion<T>,
) -> UnitQuaternion<T> {
    let q_body = small_rotation(&(body_rate_rad_s * dt_s));
    let q = q_nav * q.into_inner() * q_body;
    let s = (lit::<T>(3.0) - q.norm_squared()) * lit::<T>(0.5);
    UnitQuaternion::new_unchecked(q * s)
}

/// The error dynamics of one step, from which `Φ` is built (see the module docs).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ErrorDynamics<T> {
    /// Step length Ts (s).
    pub dt: T,
    /// Body → NED DCM `Ĉ` at the start of the step.
    pub c: Matrix3<T>,
    /// Specific force resolved in NED, `Ĉf̂` (m/s²).
    pub f_n: Vector3<T>,
    /// `ω_v` (rad/s, NED): the rate whose skew matrix couples δv into δv̇.
    pub w_v: Vector3<T>,
    /// `ω_ψ` (rad/s, NED): the rate whose skew matrix couples ψ into ψ̇.
    pub w_psi: Vector3<T>,
    /// Vertical gravity gradient `2g/r_eS` (s⁻²).
    pub grav_grad: T,
}

/// The non-identity block rows of `Φ = I + F·Ts` (δv and ψ rows; δr rows are `I, Ts·I`),
/// stored column-major as nalgebra converts them (`[column][row]`).
struct PhiBlocks<T> {
    dt: T,
    /// `(2g/r)·Ts` on the δv_D ← δr_D entry.
    dd: T,
    vv: [[T; 3]; 3],
    vp: [[T; 3]; 3],
    vb: [[T; 3]; 3],
    pp: [[T; 3]; 3],
}

impl<T: Real> PhiBlocks<T> {
    /// `(Φ·S)[0..9, :]` for a 15×L matrix `S` given by its rows `src[k]` (the bias rows of
    /// `Φ·S` equal those of `S`). Each output row is a few AXPYs over contiguous length-L
    /// rows, which the compiler vectorises.
    // Fixed-size arrays indexed by constants below 15: the bounds are proven at compile time.
    #[allow(clippy::indexing_slicing)]
    #[inline(always)]
    fn rows<const L: usize>(&self, src: &[[T; L]; N_STATES]) -> [[T; L]; 9] {
        let mut out = [[T::zero(); L]; 9];
        for i in 0..3 {
            for l in 0..L {
                out[i][l] = src[i][l] + self.dt * src[3 + i][l];
            }
            let mut v = src[3 + i];
            let mut p = src[6 + i];
            for k in 0..3 {
                // [k][i] is row i, column k of the block (column-major storage).
                let c = self.vb[k][i];
                for l in 0..L {
                    v[l] += c * src[9 + k][l];
                    p[l] += c * src[12 + k][l];
                }
                // vv, vp and pp are skew-symmetric: their diagonal is zero.
                if k != i {
                    let (a, b, d) = (self.vv[k][i], self.vp[k][i], self.pp[k][i]);
                    for l in 0..L {
                        v[l] += a * src[3 + k][l] + b * src[6 + k][l];
                        p[l] += d * src[6 + k][l];
                    }
                }
            }
            out[3 + i] = v;
            out[6 + i] = p;
        }
        for l in 0..L {
            out[5][l] += self.dd * src[2][l];
        }
        out
    }
}

/// `P ← Φ·P·Φᵀ + diag(Γ)`, `gamma` the variance added per step to the δv, ψ, δb_a and δb_g
/// groups (`σ²·Ts` each, eq. 18: `Q` is isotropic per group, so `Ĉ·σ²I·Ĉᵀ = σ²I`).
// Index loops mirror the block algebra (row i, column j) and unroll fully; every index is a
// constant below 15.
#[allow(clippy::needless_range_loop, clippy::indexing_slicing)]
#[inline(always)]
pub(crate) fn propagate_covariance<T: Real>(
    p: &mut Mat15<T>,
    e: &ErrorDynamics<T>,
    disc: Discretisation,
    gamma: &[T; 4],
) {
    let dt = e.dt;
    let a_vv = skew(&e.w_v) * (-dt);
    let a_vp = skew(&e.f_n) * (-dt);
    let a_vb = e.c * (-dt);
    let a_pp = skew(&e.w_psi) * (-dt);
    let a_dd = e.grav_grad * dt;
    match disc {
        Discretisation::FirstOrder => {
            // Only the δr, δv and ψ block rows of Φ differ from I, so P⁻ = Φ·P·Φᵀ needs
            // only (Φ·x)[0..9] of 15-vectors x: first for the 15 columns of P (giving
            // M = (Φ·P)[0..9, :]), then for the 9 rows of M (giving P⁻[0..9, 0..9]); the
            // bias blocks are P⁻[0..9, 9..] = M[:, 9..] and P⁻[9.., 9..] = P[9.., 9..].
            let blocks = PhiBlocks {
                dt,
                dd: a_dd,
                vv: a_vv.into(),
                vp: a_vp.into(),
                vb: a_vb.into(),
                pp: a_pp.into(),
            };
            // P is symmetric, so its column-major columns are also its rows.
            let m = blocks.rows(&p.data.0); // M = (Φ·P)[0..9, :], row-major
            let mut mt = [[T::zero(); 9]; N_STATES]; // Mᵀ
            for (i, row) in m.iter().enumerate() {
                for (j, v) in row.iter().enumerate() {
                    mt[j][i] = *v;
                }
            }
            // (Φ·Mᵀ)[0..9, :] = (M·Φᵀ)ᵀ[0..9, 0..9] = P⁻[0..9, 0..9] (symmetric).
            let n = blocks.rows(&mt);
            let cols = &mut p.data.0;
            for (a, row) in n.iter().enumerate() {
                cols[a][..9].copy_from_slice(row);
            }
            for j in 9..N_STATES {
                cols[j][..9].copy_from_slice(&mt[j]);
                for i in 0..9 {
                    cols[i][j] = mt[j][i];
                }
            }
        }
        Discretisation::SecondOrder => {
            let mut f = Mat15::<T>::zeros();
            let eye3 = Matrix3::<T>::identity();
            f.fixed_view_mut::<3, 3>(0, 3).copy_from(&eye3);
            f[(5, 2)] = e.grav_grad;
            f.fixed_view_mut::<3, 3>(3, 3).copy_from(&(-skew(&e.w_v)));
            f.fixed_view_mut::<3, 3>(3, 6).copy_from(&(-skew(&e.f_n)));
            f.fixed_view_mut::<3, 3>(3, 9).copy_from(&(-e.c));
            f.fixed_view_mut::<3, 3>(6, 6).copy_from(&(-skew(&e.w_psi)));
            f.fixed_view_mut::<3, 3>(6, 12).copy_from(&(-e.c));
            let ft = f * dt;
            let phi = Mat15::<T>::identity() + ft + ft * ft * lit::<T>(0.5);
            *p = phi * *p * phi.transpose();
        }
    }
    for (grp, var) in gamma.iter().enumerate() {
        for i in 0..3 {
            let k = 3 * (grp + 1) + i;
            p[(k, k)] += *var;
        }
    }
}

/// Whether the diagonal of `P` is finite and non-negative (the per-step health check).
#[inline(always)]
pub(crate) fn covariance_healthy<T: Real>(p: &Mat15<T>) -> bool {
    let (mut trace, mut negative) = (T::zero(), false);
    for i in 0..N_STATES {
        let d = p[(i, i)];
        trace += d;
        negative |= d < T::zero();
    }
    !negative && num_traits::Float::is_finite(trace)
}

/// Cholesky factor of the innovation covariance `S = H·P·Hᵀ + R` and `P·Hᵀ`.
pub(crate) struct Gain<T: Real, const M: usize> {
    /// Cholesky factorisation of `S`.
    pub chol: nalgebra::Cholesky<T, nalgebra::Const<M>>,
    /// `H·P` (M×15).
    pub hp: SMatrix<T, M, N_STATES>,
    /// `S = H·P·Hᵀ + diag(r)`, kept so that the update and the integrity tests need not
    /// recompute it (an M×M×15 product each).
    pub s: SMatrix<T, M, M>,
}

/// Factorises `S = H·P·Hᵀ + diag(r)` (no state change).
// Indices below M and N_STATES, the matrices' compile-time sizes.
#[allow(clippy::indexing_slicing)]
#[inline]
pub(crate) fn gain<T: Real, const M: usize>(
    p: &Mat15<T>,
    h: &SMatrix<T, M, N_STATES>,
    r_diag: &SVector<T, M>,
    what: &'static str,
) -> Result<Gain<T, M>, NavError> {
    let hp = h * p;
    let mut s = hp * h.transpose();
    for i in 0..M {
        s[(i, i)] += r_diag[i];
    }
    let chol = s.cholesky().ok_or(NavError::NotPositiveDefinite { what })?;
    Ok(Gain { chol, hp, s })
}

/// The Joseph-form update `P ← (I−KH)P(I−KH)ᵀ + K·R·Kᵀ` (symmetrised; `H·P` and `S` from
/// [`gain`]) for the innovation
/// `z = h(x̂) − y` (predicted minus measured); returns `δx = K·z`. `P` is left
/// unchanged on error.
// Indices below M and N_STATES, the matrices' compile-time sizes.
#[allow(clippy::indexing_slicing)]
#[inline]
pub(crate) fn joseph_update<T: Real, const M: usize>(
    p: &mut Mat15<T>,
    z: &SVector<T, M>,
    g: &Gain<T, M>,
) -> Result<SVector<T, N_STATES>, NavError> {
    let kt = g.chol.solve(&g.hp); // Kᵀ = S⁻¹·H·P
    let k = kt.transpose();
    let dx = k * z;
    // The Joseph form expanded, (I−KH)P(I−KH)ᵀ + KRKᵀ = P − K·HP − (K·HP)ᵀ + K·S·Kᵀ with
    // S = HPHᵀ + R — exact for any K, so it keeps the Joseph form's tolerance of an inexact gain,
    // but costs M-row products (≈ 3.8k multiply-adds for M = 6) instead of two dense 15×15
    // products (≈ 9.5k).
    let khp = k * g.hp;
    let p_new = *p - khp - khp.transpose() + (k * g.s) * kt;
    let p_sym = (p_new + p_new.transpose()) * lit::<T>(0.5);
    for i in 0..N_STATES {
        let d = p_sym[(i, i)];
        if !(num_traits::Float::is_finite(d) && d > T::zero()) {
            return Err(NavError::NotPositiveDefinite {
                what: "state covariance P",
            });
        }
    }
    *p = p_sym;
    Ok(dx)
}

/// Feeds the attitude part `ψ` of an estimated error state back: `q ← exp(−ψ/2) ⊗ q`.
#[inline]
pub(crate) fn correct_attitude<T: Real>(
    q: &UnitQuaternion<T>,
    psi: &Vector3<T>,
) -> UnitQuaternion<T> {
    UnitQuaternion::new_normalize(quat_from_rotation_vector(&(-psi)).into_inner() * q.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_order_blocks_equal_dense_first_order_product() {
        // The block-sparse Φ·P·Φᵀ must equal the dense product with Φ = I + F·Ts, for a
        // transport-rate ω_v ≠ 2ω_ψ (the GNSS/INS case) as well as the ZUPT one.
        let mut p = Mat15::<f64>::from_fn(|i, j| ((i * 7 + j * 3) % 11) as f64 * 0.01);
        p = p * p.transpose() + Mat15::identity();
        let e = ErrorDynamics {
            dt: 0.01,
            c: *UnitQuaternion::from_euler_angles(0.1, -0.2, 0.7)
                .to_rotation_matrix()
                .matrix(),
            f_n: Vector3::new(0.3, -0.2, -9.8),
            w_v: Vector3::new(1e-4, -3e-5, -2e-4),
            w_psi: Vector3::new(6e-5, -1e-5, -7e-5),
            grav_grad: 3.1e-6,
        };
        let mut fast = p;
        propagate_covariance(&mut fast, &e, Discretisation::FirstOrder, &[0.0; 4]);
        let mut f = Mat15::<f64>::zeros();
        f.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&Matrix3::identity());
        f[(5, 2)] = e.grav_grad;
        f.fixed_view_mut::<3, 3>(3, 3).copy_from(&(-skew(&e.w_v)));
        f.fixed_view_mut::<3, 3>(3, 6).copy_from(&(-skew(&e.f_n)));
        f.fixed_view_mut::<3, 3>(3, 9).copy_from(&(-e.c));
        f.fixed_view_mut::<3, 3>(6, 6).copy_from(&(-skew(&e.w_psi)));
        f.fixed_view_mut::<3, 3>(6, 12).copy_from(&(-e.c));
        let phi = Mat15::identity() + f * e.dt;
        let dense = phi * p * phi.transpose();
        assert!(
            (fast - dense).abs().max() < 1e-12,
            "{}",
            (fast - dense).abs().max()
        );
    }

    #[test]
    fn joseph_update_matches_optimal_gain_form() {
        // With the optimal gain, Joseph = (I − KH)P (textbook identity).
        let mut p = Mat15::<f64>::from_fn(|i, j| ((i * 5 + j * 2) % 7) as f64 * 0.02);
        p = p * p.transpose() + Mat15::identity() * 0.5;
        let mut h = SMatrix::<f64, 2, N_STATES>::zeros();
        h[(0, 0)] = 1.0;
        h[(1, 4)] = 1.0;
        h[(1, 7)] = -0.3;
        let r = SVector::<f64, 2>::new(0.4, 0.1);
        let z = SVector::<f64, 2>::new(0.5, -0.2);
        let g = gain(&p, &h, &r, "S").unwrap();
        let mut pj = p;
        let dx = joseph_update(&mut pj, &z, &g).unwrap();
        let s = h * p * h.transpose() + SMatrix::<f64, 2, 2>::from_diagonal(&r);
        let k = p * h.transpose() * s.try_inverse().unwrap();
        let po = (Mat15::identity() - k * h) * p;
        assert!((pj - po).abs().max() < 1e-12);
        assert!((dx - k * z).abs().max() < 1e-12);
    }
}
