//! `uasnav._core`: the Python binding of nav-core.
//!
//! This crate only extracts, checks, converts, releases the GIL and maps errors; every
//! number is computed in nav-core. One file per nav-core concept, registered below.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]
mod allan;
mod attitude;
mod convert;
mod csv;
mod earth;
mod errors;
mod ins;
mod mlp;
mod redundancy;
mod utm;
mod zupt;

use pyo3::prelude::*;

/// The compiled core of uasnav (private: import `uasnav.allan`, `uasnav.attitude`, …).
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    allan::register(m)?;
    attitude::register(m)?;
    mlp::register(m)?;
    earth::register(m)?;
    zupt::register(m)?;
    redundancy::register(m)?;
    utm::register(m)?;
    ins::register(m)?;
    csv::register(m)?;
    Ok(())
}
