//! The float trait every algorithm is generic over (f32 for Cortex-M class targets, f64 by
//! default) and small numeric helpers shared by the modules.
// No unchecked indexing in library code; a proven index carries an `allow`.
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]
use nalgebra::RealField;

/// A real scalar usable by every nav-core algorithm: `f32` or `f64`.
pub trait Real: RealField + Copy + num_traits::Float {}
impl<T: RealField + Copy + num_traits::Float> Real for T {}

/// Converts an `f64` literal to `T` (exact for f64, rounded for f32).
#[inline(always)]
pub(crate) fn lit<T: Real>(x: f64) -> T {
    nalgebra::convert(x)
}

/// Converts a count to `T`.
#[inline(always)]
pub(crate) fn from_usize<T: Real>(n: usize) -> T {
    nalgebra::convert(n as f64)
}
