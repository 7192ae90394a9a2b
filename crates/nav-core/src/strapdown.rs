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
//! `Φ = I + F·Ts` is applied block-wise and to one triangle of the symmetric result (≈ 790
//! multiply-adds instead of two dense 15×15 products, 6750); the second-order `Φ = I + F·Ts + (F·Ts)²/2` is the dense reference path.
//! The measurement update is the Joseph form for any `M×15` measurement matrix, with a
//! Cholesky factorisation of the innovation covariance (failure → `NotPositiveDefinite`).
// No unchecked indexing in library code; a proven index carries an `allow`.
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
    /// `P⁻ = Φ·P·Φᵀ` for `Φ = I + F·Ts`, in place, from the 3×3 block structure of `Φ`
    /// (identity, zero, skew-symmetric and `−Ĉ·Ts` blocks) and the symmetry of `P`:
    ///
    /// 1. `M = (Φ·P)[0..9, :]`, one column of `P` at a time (`P` is symmetric, so its
    ///    column-major columns are contiguous); the ψ rows only for columns 6.. (their columns
    ///    0..6 would only feed the lower triangle);
    /// 2. `P⁻[a, b] = Φ[b, :]·M[a, :]` for `b ≥ a` only, mirrored, so `P⁻` is exactly symmetric;
    /// 3. `P⁻[0..9, 9..] = M[:, 9..]` (the bias columns of `Φ` are the identity); `P⁻[9.., 9..]`
    ///    is unchanged.
    ///
    /// ≈ 790 multiply-adds (the full first-order block product: ≈ 960; dense: 6750), written as
    /// short scalar dot products over one column/row held in registers: on the SSE2 baseline
    /// this ran 1.5× faster than AXPYs over whole 15-element rows, which spilled registers.
    // Fixed-size arrays indexed by constants below 15: the bounds are proven at compile time.
    #[allow(clippy::indexing_slicing, clippy::needless_range_loop)]
    #[inline(always)]
    fn propagate(&self, p: &mut Mat15<T>) {
        let src = &p.data.0; // src[k] = column k of P = row k (P is symmetric)
        let dt = self.dt;
        // Step 1, one column x = P[:, j] at a time: mt[j] = (Φ·x)[0..9] = M[0..9, j].
        // [k][i] of a block array is row i, column k of the block (column-major).
        let mut mt = [[T::zero(); 9]; N_STATES];
        for j in 0..N_STATES {
            let x = &src[j];
            let y = &mut mt[j];
            for i in 0..3 {
                y[i] = x[i] + dt * x[3 + i];
            }
            for i in 0..3 {
                let mut v = x[3 + i];
                for k in 0..3 {
                    v += self.vb[k][i] * x[9 + k];
                    if k != i {
                        v += self.vv[k][i] * x[3 + k] + self.vp[k][i] * x[6 + k];
                    }
                }
                y[3 + i] = v;
            }
            y[5] += self.dd * x[2];
            if j >= 6 {
                for i in 0..3 {
                    let mut q = x[6 + i];
                    for k in 0..3 {
                        q += self.vb[k][i] * x[12 + k];
                        if k != i {
                            q += self.pp[k][i] * x[6 + k];
                        }
                    }
                    y[6 + i] = q;
                }
            }
        }
        // Step 2, one row x = M[a, :] at a time: P⁻[a, b] = Φ[b, :]·x for b ≥ a only (the
        // upper triangle), mirrored so that P⁻ is exactly symmetric (cols[j][i] = P[i, j]).
        let cols = &mut p.data.0;
        for a in 0..9 {
            let x = |c: usize| mt[c][a];
            for i in 0..3 {
                if i >= a {
                    let y = x(i) + dt * x(3 + i);
                    cols[i][a] = y;
                    cols[a][i] = y;
                }
            }
            for i in 0..3 {
                if 3 + i >= a {
                    let mut v = x(3 + i);
                    for k in 0..3 {
                        v += self.vb[k][i] * x(9 + k);
                        if k != i {
                            v += self.vv[k][i] * x(3 + k) + self.vp[k][i] * x(6 + k);
                        }
                    }
                    if i == 2 {
                        v += self.dd * x(2);
                    }
                    cols[3 + i][a] = v;
                    cols[a][3 + i] = v;
                }
            }
            for i in 0..3 {
                if 6 + i >= a {
                    let mut q = x(6 + i);
                    for k in 0..3 {
                        q += self.vb[k][i] * x(12 + k);
                        if k != i {
                            q += self.pp[k][i] * x(6 + k);
                        }
                    }
                    cols[6 + i][a] = q;
                    cols[a][6 + i] = q;
                }
            }
        }
        // Step 3: the bias columns, P⁻[0..9, 9..] = M[:, 9..] (and mirrored).
        for j in 9..N_STATES {
            for a in 0..9 {
                let y = mt[j][a];
                cols[j][a] = y;
                cols[a][j] = y;
            }
        }
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
            let blocks = PhiBlocks {
                dt,
                dd: a_dd,
                vv: a_vv.into(),
                vp: a_vp.into(),
                vb: a_vb.into(),
                pp: a_pp.into(),
            };
            blocks.propagate(p);
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

/// `S⁻¹·B` from the Cholesky factorisation of `S` (M×M) for an M×C right-hand side: forward
/// then backward substitution on the fixed-size factor, fully unrolled. It performs exactly
/// nalgebra's `Cholesky::solve` operations in the same order (the forward step's AXPY
/// `b_j ← b_j − c·L_ji`, the backward step's dot product accumulated from zero in increasing
/// index order), so its result is bit-identical (tested) — nalgebra's generic column loops over
/// dynamic views cost ≈ 10 % of a GNSS/INS run.
// Indices below M, the matrices' compile-time sizes.
#[allow(clippy::indexing_slicing)]
#[inline]
pub(crate) fn chol_solve<T: Real, const M: usize, const C: usize>(
    chol: &nalgebra::Cholesky<T, nalgebra::Const<M>>,
    b: &SMatrix<T, M, C>,
) -> SMatrix<T, M, C> {
    let l = chol.l_dirty(); // lower triangle and diagonal are the factor L (S = L·Lᵀ)
    let mut x = *b;
    for c in 0..C {
        // L·y = b
        for i in 0..M {
            let coeff = x[(i, c)] / l[(i, i)];
            x[(i, c)] = coeff;
            for j in i + 1..M {
                x[(j, c)] = -coeff * l[(j, i)] + x[(j, c)];
            }
        }
        // Lᵀ·x = y
        for i in (0..M).rev() {
            let mut dot = T::zero();
            for k in i + 1..M {
                dot += l[(k, i)] * x[(k, c)];
            }
            x[(i, c)] = (x[(i, c)] - dot) / l[(i, i)];
        }
    }
    x
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

/// [`gain`] for `H = [I_M 0]` (the first `M` error states measured directly, as the ZUPT's
/// position, velocity and attitude): `H·P` is the first `M` rows of `P` and `S` their leading
/// `M×M` block plus `diag(r)`, read off instead of multiplied (no state change).
// Indices below M, the matrices' compile-time size.
#[allow(clippy::indexing_slicing)]
#[inline]
pub(crate) fn gain_leading<T: Real, const M: usize>(
    p: &Mat15<T>,
    r_diag: &SVector<T, M>,
    what: &'static str,
) -> Result<Gain<T, M>, NavError> {
    let hp: SMatrix<T, M, N_STATES> = p.fixed_rows::<M>(0).into_owned();
    let mut s: SMatrix<T, M, M> = hp.fixed_columns::<M>(0).into_owned();
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
    let kt = chol_solve(&g.chol, &g.hp); // Kᵀ = S⁻¹·H·P
    let k = kt.transpose();
    let dx = k * z;
    // The Joseph form expanded, (I−KH)P(I−KH)ᵀ + KRKᵀ = P − K·HP − (K·HP)ᵀ + K·S·Kᵀ with
    // S = HPHᵀ + R — exact for any K, so it keeps the Joseph form's tolerance of an inexact gain,
    // but costs M-row products (≈ 3.8k multiply-adds for M = 6) instead of two dense 15×15
    // products (≈ 9.5k).
    // K·S·Kᵀ is symmetric: only its upper triangle is formed, and the result is written
    // mirrored (exactly symmetric, as the old explicit symmetrisation made it).
    let khp = k * g.hp;
    let ks = k * g.s;
    let mut p_new = *p;
    for j in 0..N_STATES {
        for i in 0..=j {
            let mut ksk = T::zero();
            for m in 0..M {
                ksk += ks[(i, m)] * kt[(m, j)];
            }
            let x = (p[(i, j)] + p[(j, i)]) * lit::<T>(0.5) - khp[(i, j)] - khp[(j, i)] + ksk;
            p_new[(i, j)] = x;
            p_new[(j, i)] = x;
        }
    }
    for i in 0..N_STATES {
        let d = p_new[(i, i)];
        if !(num_traits::Float::is_finite(d) && d > T::zero()) {
            return Err(NavError::NotPositiveDefinite {
                what: "state covariance P",
            });
        }
    }
    *p = p_new;
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

    /// A small deterministic generator (xorshift64*) for the randomised tests.
    struct Rng(u64);
    impl Rng {
        fn uniform(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
        }
        fn sym(&mut self, scale: f64) -> f64 {
            (2.0 * self.uniform() - 1.0) * scale
        }
        fn vec3(&mut self, scale: f64) -> Vector3<f64> {
            Vector3::new(self.sym(scale), self.sym(scale), self.sym(scale))
        }
    }

    fn dense_phi(e: &ErrorDynamics<f64>) -> Mat15<f64> {
        let mut f = Mat15::<f64>::zeros();
        f.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&Matrix3::identity());
        f[(5, 2)] = e.grav_grad;
        f.fixed_view_mut::<3, 3>(3, 3).copy_from(&(-skew(&e.w_v)));
        f.fixed_view_mut::<3, 3>(3, 6).copy_from(&(-skew(&e.f_n)));
        f.fixed_view_mut::<3, 3>(3, 9).copy_from(&(-e.c));
        f.fixed_view_mut::<3, 3>(6, 6).copy_from(&(-skew(&e.w_psi)));
        f.fixed_view_mut::<3, 3>(6, 12).copy_from(&(-e.c));
        Mat15::identity() + f * e.dt
    }

    #[test]
    fn block_triangle_kernel_equals_dense_product_on_random_spd_p() {
        // 500 random SPD P (entries spanning 8 decades between the state groups) and random Φ
        // of the filter's structure (random attitude, specific force, rates, step), f64 and
        // f32. Tolerance: every element within 64·ε·(|Φ|·|P|·|Φ|ᵀ)ᵢⱼ — a few times the
        // rounding bound of a 15-term product, taken twice — of the dense Φ·P·Φᵀ + Γ; and the
        // result exactly symmetric.
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for trial in 0..500 {
            let scale: [f64; N_STATES] = core::array::from_fn(|_| 10f64.powf(rng.sym(4.0)));
            let a = Mat15::<f64>::from_fn(|i, _| rng.sym(1.0) * scale[i]);
            let p = a * a.transpose() + Mat15::from_diagonal(&SVector::from(scale)) * 1e-3;
            let big = trial % 2 == 0; // alternately realistic and exaggerated rates
            let e = ErrorDynamics {
                dt: 10f64.powf(-3.0 + 2.0 * rng.uniform()),
                c: *UnitQuaternion::from_euler_angles(rng.sym(3.1), rng.sym(1.5), rng.sym(3.1))
                    .to_rotation_matrix()
                    .matrix(),
                f_n: rng.vec3(20.0),
                w_v: rng.vec3(if big { 1.0 } else { 3e-4 }),
                w_psi: rng.vec3(if big { 1.0 } else { 3e-4 }),
                grav_grad: rng.uniform() * 4e-6,
            };
            let gamma = [rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()];
            let phi = dense_phi(&e);
            let mut dense = phi * p * phi.transpose();
            for (grp, var) in gamma.iter().enumerate() {
                for i in 0..3 {
                    dense[(3 * (grp + 1) + i, 3 * (grp + 1) + i)] += *var;
                }
            }
            let bound = phi.abs() * p.abs() * phi.abs().transpose();
            let mut fast = p;
            propagate_covariance(&mut fast, &e, Discretisation::FirstOrder, &gamma);
            assert_eq!(
                fast,
                fast.transpose(),
                "trial {trial}: not exactly symmetric"
            );
            let tol = bound * (64.0 * f64::EPSILON);
            for i in 0..N_STATES {
                for j in 0..N_STATES {
                    let g = if i == j && i >= 3 {
                        gamma[i / 3 - 1]
                    } else {
                        0.0
                    };
                    let err = (fast[(i, j)] - dense[(i, j)]).abs();
                    assert!(
                        err <= tol[(i, j)] + 64.0 * f64::EPSILON * g,
                        "trial {trial} ({i},{j}): {err:e} > {:e}",
                        tol[(i, j)]
                    );
                }
            }
            // f32: the same inputs rounded, against the f64 dense product.
            let p32: Mat15<f32> = p.cast();
            let e32 = ErrorDynamics {
                dt: e.dt as f32,
                c: e.c.cast(),
                f_n: e.f_n.cast(),
                w_v: e.w_v.cast(),
                w_psi: e.w_psi.cast(),
                grav_grad: e.grav_grad as f32,
            };
            let mut fast32 = p32;
            propagate_covariance(&mut fast32, &e32, Discretisation::FirstOrder, &[0.0; 4]);
            let dense0 = phi * p32.cast::<f64>() * phi.transpose();
            for i in 0..N_STATES {
                for j in 0..N_STATES {
                    let err = (f64::from(fast32[(i, j)]) - dense0[(i, j)]).abs();
                    let tol = 64.0 * f64::from(f32::EPSILON) * bound[(i, j)];
                    assert!(err <= tol, "f32 trial {trial} ({i},{j}): {err:e} > {tol:e}");
                }
            }
        }
    }

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

    /// `chol_solve` is nalgebra's `Cholesky::solve`, bit for bit (same operations, same order),
    /// for the sizes the filters use, on random SPD matrices spanning several decades.
    fn check_chol_solve<const M: usize, const C: usize>(rng: &mut Rng) {
        for _ in 0..200 {
            let a = SMatrix::<f64, M, M>::from_fn(|_, _| rng.sym(1.0));
            let d = SVector::<f64, M>::from_fn(|_, _| 10f64.powf(rng.sym(4.0)));
            let s = a * a.transpose() + SMatrix::<f64, M, M>::from_diagonal(&d);
            let b = SMatrix::<f64, M, C>::from_fn(|_, _| {
                let e = rng.sym(3.0);
                rng.sym(10f64.powf(e))
            });
            let ch = s.cholesky().unwrap();
            let (got, want) = (chol_solve(&ch, &b), ch.solve(&b));
            for (g, w) in got.iter().zip(want.iter()) {
                assert_eq!(g.to_bits(), w.to_bits(), "M={M} C={C}");
            }
        }
    }

    #[test]
    fn chol_solve_is_nalgebras_solve_bit_for_bit() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        check_chol_solve::<6, 15>(&mut rng);
        check_chol_solve::<6, 1>(&mut rng);
        check_chol_solve::<6, 3>(&mut rng);
        check_chol_solve::<3, 15>(&mut rng);
        check_chol_solve::<2, 15>(&mut rng);
        check_chol_solve::<1, 15>(&mut rng);
    }

    #[test]
    fn gain_leading_is_gain_with_a_leading_identity_bit_for_bit() {
        let mut rng = Rng(0x2545_f491_4f6c_dd1d);
        let scale: [f64; N_STATES] = core::array::from_fn(|_| 10f64.powf(rng.sym(4.0)));
        let a = Mat15::<f64>::from_fn(|i, _| rng.sym(1.0) * scale[i]);
        let p = a * a.transpose() + Mat15::from_diagonal(&SVector::from(scale)) * 1e-3;
        let r = SVector::<f64, 9>::from_fn(|i, _| 1e-4 * (i as f64 + 1.0));
        let h = SMatrix::<f64, 9, N_STATES>::from_fn(|i, j| if i == j { 1.0 } else { 0.0 });
        let dense = gain(&p, &h, &r, "S").unwrap();
        let ours = gain_leading(&p, &r, "S").unwrap();
        assert_eq!(dense.hp, ours.hp);
        assert_eq!(dense.s, ours.s);
        assert_eq!(dense.chol.l(), ours.chol.l());
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
