//! # uasnav-core — embeddable navigation numerics for small unmanned aircraft
//!
//! Conventions, stated once and tested (`attitude::tests`):
//!
//! * **Units**: SI everywhere (s, m, m/s, m/s², rad, rad/s) unless a name says otherwise
//!   (`_deg_h`, `_deg_sqrt_h`, …).
//! * **Frames**: the navigation frame is the local-level North-East-Down (NED) frame; sensor
//!   samples are resolved in the body frame (x forward, y right, z down).
//! * **Quaternions**: Hamilton algebra, scalar first in every array we read or write
//!   (`[q_s, q_x, q_y, q_z]`), and they rotate **body → NED**: `v_n = q ⊗ v_b ⊗ q*`, i.e.
//!   `C_b^n = R(q)`.
//!
//! The crate builds without `std` (`default-features = false`); the `std` feature only adds
//! heap-backed conveniences. Per-sample code never allocates and never panics on sensor data:
//! fallible functions return [`NavError`].
#![cfg_attr(not(feature = "std"), no_std)]
#![deny(missing_docs)]
#![forbid(unsafe_code)]
// Library code never unwraps (fallible paths return `NavError`); tests may.
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

#[cfg(feature = "std")]
extern crate std;

pub mod allan;
pub mod attitude;
pub mod earth;
pub mod error;
pub mod ins;
pub mod mlp;
pub mod noise;
pub mod redundancy;
pub(crate) mod scalar;
pub mod strapdown;
pub mod zupt;

pub use error::NavError;
pub use scalar::Real;

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
