//! The crate's single error type.
// No unchecked indexing in library code; a proven index carries an `allow`.
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]
use core::fmt;

/// Everything that can go wrong in nav-core. Small and `Copy` so that it can be returned from
/// per-sample code on a microcontroller; the `&'static str` fields name what was wrong.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NavError {
    /// A value that must be finite was NaN or infinite.
    NonFinite {
        /// Which input held the value.
        what: &'static str,
        /// Index of the first offending sample (0 for scalars).
        index: usize,
    },
    /// A series was shorter than the algorithm needs.
    TooShort {
        /// Which input was too short.
        what: &'static str,
        /// Its length.
        len: usize,
        /// The minimum length required.
        min: usize,
    },
    /// Two inputs (or an input and an output buffer) have incompatible lengths.
    LengthMismatch {
        /// Which input or buffer.
        what: &'static str,
        /// The length required.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// A parameter is out of its valid domain.
    InvalidParameter {
        /// Which parameter.
        what: &'static str,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// A covariance (or normal-equation) matrix stopped being positive definite.
    NotPositiveDefinite {
        /// Which matrix.
        what: &'static str,
    },
}

impl fmt::Display for NavError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            NavError::NonFinite { what, index } => {
                write!(f, "{what}: non-finite value (NaN or inf) at index {index}")
            }
            NavError::TooShort { what, len, min } => {
                write!(f, "{what}: too short ({len} samples, need at least {min})")
            }
            NavError::LengthMismatch {
                what,
                expected,
                got,
            } => write!(f, "{what}: expected length {expected}, got {got}"),
            NavError::InvalidParameter { what, reason } => write!(f, "{what}: {reason}"),
            NavError::NotPositiveDefinite { what } => {
                write!(f, "{what}: matrix is not positive definite")
            }
        }
    }
}

impl core::error::Error for NavError {}

/// Returns `Err(NonFinite)` naming the first non-finite element of `xs`.
pub(crate) fn check_finite<T: crate::Real>(what: &'static str, xs: &[T]) -> Result<(), NavError> {
    match xs.iter().position(|x| !num_traits::Float::is_finite(*x)) {
        Some(index) => Err(NavError::NonFinite { what, index }),
        None => Ok(()),
    }
}
