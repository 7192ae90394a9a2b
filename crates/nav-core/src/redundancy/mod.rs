//! Redundant inertial sensors on regular polyhedra (thesis §4.3, eqs. 38–46).
//!
//! * [`geometry`] — face normals of the five Platonic solids, per-face sensor frames, user
//!   mounting matrices, the improvement factor `k_r` (eq. 40) and the least-squares
//!   covariance `(HᵀWH)⁻¹`.
//! * [`fusion`] — allocation-free weighted least-squares fusion of all sensor axes and
//!   fault detection and isolation (FDI) in the parity space with a χ² threshold.
//! * [`chi2`] — the χ² quantile used for the FDI threshold (no_std).
//! * [`kalman`] — Kalman fusion with one bias state per sensor axis (partial
//!   self-calibration through redundancy).
//! * [`alignment`] — levelling, the relative rotations of eq. (45) and Wahba alignment of
//!   one sensor to a reference for misalignment compensation.
//!
//! Frames: the *IMU frame* is the polyhedron's frame (x, y, z along the cube's face normals
//! for the cube). A sensor's *mounting* `C` maps IMU-frame vectors into its own frame,
//! `ω_s = C·ω_imu`, so the rows of `C` are the sensor's axes resolved in the IMU frame
//! (the same convention as `log.meta["mounting"]` of `uasnav.sim.simulate_array`).
// `!(x > 0)` is deliberate throughout: it also rejects NaN. Index loops walk several
// parallel fixed-size arrays (axes, sigma, bias, masks) at once.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

pub mod alignment;
pub mod chi2;
pub mod fusion;
pub mod geometry;
pub mod kalman;

pub use fusion::{FdiConfig, FdiFuser, FdiOutput, Fused, SensorHealth};
pub use geometry::{AxisKind, Polyhedron, SensorArray};
