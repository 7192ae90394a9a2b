//! Solution separation against a GNSS-velocity reference trajectory (slow-ramp integrity).
//!
//! An innovation test cannot bound a slow ramp: the filter follows a ramp of rate `r` with a
//! constant lag, so its innovations stay constant while the error grows as `r·t`; below the
//! rate the test detects, the error is unbounded. The reference is a second, GNSS-position-free
//! solution: the antenna position of the filter at the first used fix (the last trusted
//! epoch), moved by the trapezoidal integral of the **GNSS velocities** of the used fixes, and
//! across GNSS gaps, exclusions and resets by the filter's own (dead-reckoned) displacement.
//! A fault in the GNSS *position* (a pseudorange ramp: Doppler velocity is unaffected) leaves
//! the reference untouched while the filter follows it, so their separation `d` grows with
//! the fault. With `V_ref` the reference variance (anchor covariance + Σ wᵢ²·σ_v,ᵢ² of the
//! trapezoid weights + the filter's covariance growth over the bridged spans) and
//! `V_sep = V_ref + P_rr` (filter position covariance):
//!
//! ```text
//! alert   when d_Nᵀ/V_N·d_N + d_E²/V_E > k_sep,H²   or   |d_D| > k_sep,V·√V_D
//! HPL_ss = k_sep,H·√max(V_sep,N, V_sep,E) + k_H·√max(V_ref,N, V_ref,E)
//! VPL_ss = k_sep,V·√V_sep,D + k_V·√V_ref,D
//! ```
//!
//! (no alert ⇒ `|d| ≤ T`, and the reference error is within `k·σ_ref` at the integrity risk,
//! so the filter error `d + e_ref` is within the PL). The bound holds for any GNSS position
//! fault beginning after the anchor, as long as the GNSS velocity is fault-free and its errors
//! are white with the reported σ; `V_ref` grows as `σ_v²·Δt·t`, so the PL grows as √t over a
//! flight. A fault that corrupts position *and* velocity consistently (spoofing, or a receiver
//! that differentiates positions) is not covered.
use nalgebra::Vector3;

/// Largest interval (s) between consecutive used fixes integrated by the trapezoid rule;
/// longer spans are bridged by the filter's displacement and covariance growth.
pub(super) const REF_MAX_GAP_S: f64 = 1.0;

/// The reference is anchored once the filter has converged: its position variance at most
/// this fraction of the fix's (≥ 16 fixes' worth of averaging), or [`ANCHOR_MAX_WAIT_S`] after
/// the first used fix. GNSS is assumed fault-free before the anchor.
pub(super) const ANCHOR_VARIANCE_FRACTION: f64 = 0.0625;
/// Longest wait (s) for convergence before anchoring anyway.
pub(super) const ANCHOR_MAX_WAIT_S: f64 = 30.0;

/// The reference trajectory and its variance; plain data, never allocates.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct VelocityReference {
    /// True once anchored on a used fix.
    pub active: bool,
    /// Time (s) of the first used fix (NaN before it).
    pub first_t: f64,
    /// Reference antenna latitude, longitude (rad), ellipsoidal height (m).
    pub llh: [f64; 3],
    /// Variance (m², N/E/D) of the closed part of the reference.
    pub var: [f64; 3],
    /// Weight (s) already accumulated for the latest point and its velocity variance
    /// ((m/s)²): the point's trapezoid weight closes when the next span is added.
    pub pend_w: f64,
    pub pend_var: f64,
    /// Measured antenna velocity (m/s, NED) at the latest point and its time (s).
    pub prev_v: [f64; 3],
    pub prev_t: f64,
    /// The last GNSS call used its fix and no reset followed (the trapezoid may continue).
    pub chain: bool,
    /// Filter antenna position and position variance at the last bridging origin.
    pub last_ant: [f64; 3],
    pub last_p: [f64; 3],
    /// Displacement (Δlat, Δlon rad, Δh m) and variance (m²) bridged so far (resets).
    pub bridge_d: [f64; 3],
    pub bridge_var: [f64; 3],
}

impl VelocityReference {
    /// Current variance of the reference (m², N/E/D).
    pub fn variance(&self) -> [f64; 3] {
        let p = self.pend_w * self.pend_w * self.pend_var;
        [self.var[0] + p, self.var[1] + p, self.var[2] + p]
    }

    /// Adds the filter's displacement from the last bridging origin to `ant` (llh) with its
    /// covariance growth `p` − `last_p` (m², ≥ 0) to the bridged span.
    pub fn accumulate_bridge(&mut self, ant: &[f64; 3], p: &[f64; 3]) {
        for i in 0..3 {
            self.bridge_d[i] += ant[i] - self.last_ant[i];
            self.bridge_var[i] += (p[i] - self.last_p[i]).max(0.0);
        }
    }

    /// Starts a trapezoid chain at a used fix: measured velocity `v` (m/s NED, σ² `var_v`)
    /// at time `t` (s).
    fn start_point(&mut self, t: f64, v: &Vector3<f64>, var_v: f64) {
        self.pend_w = 0.0;
        self.pend_var = var_v;
        self.prev_v = [v.x, v.y, v.z];
        self.prev_t = t;
        self.chain = true;
    }

    /// Anchors the reference on the filter antenna position `ant` (llh) with variance `p`
    /// (m², N/E/D), at a used fix at `t` (s) with measured velocity `v` (m/s NED, σ² `var_v`).
    pub fn anchor(&mut self, t: f64, v: &Vector3<f64>, var_v: f64, ant: &[f64; 3], p: &[f64; 3]) {
        self.active = true;
        self.llh = *ant;
        self.var = *p;
        self.bridge_d = [0.0; 3];
        self.bridge_var = [0.0; 3];
        self.start_point(t, v, var_v);
    }

    /// Advances the anchored reference to a used fix at time `t` (s) with measured antenna
    /// velocity `v` (m/s NED, variance `var_v` (m/s)²); `ant_pre`, `p_pre`: filter antenna
    /// position (llh) and position variance (m², N/E/D) before this fix's update; `radii`:
    /// (R_N + h, (R_E + h)·cos φ) (m).
    pub fn advance(
        &mut self,
        t: f64,
        v: &Vector3<f64>,
        var_v: f64,
        ant_pre: &[f64; 3],
        p_pre: &[f64; 3],
        radii: (f64, f64),
    ) {
        let dt = t - self.prev_t;
        if self.chain && dt <= REF_MAX_GAP_S {
            let m = [
                0.5 * (self.prev_v[0] + v.x) * dt,
                0.5 * (self.prev_v[1] + v.y) * dt,
                0.5 * (self.prev_v[2] + v.z) * dt,
            ];
            self.llh[0] += m[0] / radii.0;
            self.llh[1] += m[1] / radii.1;
            self.llh[2] -= m[2];
            let w = self.pend_w + 0.5 * dt;
            let add = w * w * self.pend_var;
            for x in &mut self.var {
                *x += add;
            }
            self.pend_w = 0.5 * dt;
            self.pend_var = var_v;
            self.prev_v = [v.x, v.y, v.z];
            self.prev_t = t;
        } else {
            // Bridge: close the pending point, move by what the filter dead-reckoned.
            let add = self.pend_w * self.pend_w * self.pend_var;
            self.accumulate_bridge(ant_pre, p_pre);
            for i in 0..3 {
                self.llh[i] += self.bridge_d[i];
                self.var[i] += add + self.bridge_var[i];
            }
            self.start_point(t, v, var_v);
        }
        self.bridge_d = [0.0; 3];
        self.bridge_var = [0.0; 3];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Constant velocity at a steady rate: the trapezoid integral is exact and the variance
    /// is the anchor's plus σ_v²·Σwᵢ² with interior weights Δt and end weights Δt/2.
    #[test]
    fn trapezoid_integral_and_variance_closed_form() {
        let (dt, n, var_v) = (0.2, 51, 0.15_f64 * 0.15);
        let radii = (6.4e6, 5.0e6);
        let v = Vector3::new(3.0, -4.0, 0.5);
        let mut r = VelocityReference::default();
        r.anchor(0.0, &v, var_v, &[0.5, 0.1, 100.0], &[0.04, 0.05, 0.09]);
        for k in 1..n {
            let p = [0.0; 3];
            r.advance(k as f64 * dt, &v, var_v, &r.llh.clone(), &p, radii);
        }
        let t = (n - 1) as f64 * dt;
        assert!((((r.llh[0] - 0.5) * radii.0) - 3.0 * t).abs() < 1e-6);
        assert!((((r.llh[1] - 0.1) * radii.1) + 4.0 * t).abs() < 1e-6);
        assert!(((100.0 - r.llh[2]) - 0.5 * t).abs() < 1e-9);
        let sum_w2 = (n - 2) as f64 * dt * dt + 2.0 * (dt / 2.0) * (dt / 2.0);
        let var = r.variance();
        for (i, a) in [0.04, 0.05, 0.09].iter().enumerate() {
            assert!((var[i] - a - var_v * sum_w2).abs() < 1e-12, "{i}: {}", var[i]);
        }
    }

    /// A span longer than [`REF_MAX_GAP_S`] is bridged by the filter's displacement and
    /// covariance growth, never by the end velocities.
    #[test]
    fn long_gap_is_bridged_by_the_filter_displacement() {
        let radii = (6.4e6, 5.0e6);
        let v = Vector3::new(10.0, 0.0, 0.0);
        let mut r = VelocityReference::default();
        r.anchor(0.0, &v, 0.01, &[0.5, 0.1, 100.0], &[0.04, 0.04, 0.09]);
        r.last_ant = [0.5, 0.1, 100.0];
        r.last_p = [0.04, 0.04, 0.09];
        // 5 s later the filter dead-reckoned 45 m north (not 50) with variance 2.0 m².
        let ant = [0.5 + 45.0 / radii.0, 0.1, 100.0];
        r.advance(5.0, &v, 0.01, &ant, &[2.04, 2.04, 0.59], radii);
        assert!(((r.llh[0] - 0.5) * radii.0 - 45.0).abs() < 1e-6);
        let var = r.variance();
        assert!((var[0] - 2.04).abs() < 1e-12 && (var[2] - 0.59).abs() < 1e-12);
    }
}
