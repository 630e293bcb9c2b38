//! The `aeroident` Python extension module (`aeroident._aeroident`; the pure-Python package in
//! `python/aeroident` re-exports it with docstrings, the Ray backend and type stubs).
//!
//! Every function here is a thin layer over the Rust library (`aeroident`, `aeroident-io`,
//! `aeroident-models`): the same code paths as the CLI, the same error messages (raised as
//! `aeroident.AeroidentError`, text = what the CLI prints after `error: `), and the GIL released
//! during long calls (record replay, simulation, trim, Monte Carlo).

use pyo3::prelude::*;

mod batch;
mod convert;
mod estimator;
mod f16;
mod montecarlo;
mod record;

pyo3::create_exception!(
    _aeroident,
    AeroidentError,
    pyo3::exceptions::PyException,
    "An aeroident error: bad input (file, row, field named) or a failed computation; the \
     message is the one the CLI prints."
);

/// An error as a Python `AeroidentError` with the CLI's message.
pub(crate) fn to_py(e: impl Into<anyhow::Error>) -> PyErr {
    AeroidentError::new_err(aeroident_pipelines::error::chain_message(e.into().chain()))
}

/// A message as a Python `AeroidentError`.
pub(crate) fn err(msg: impl Into<String>) -> PyErr {
    AeroidentError::new_err(msg.into())
}

#[pymodule]
fn _aeroident(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("AeroidentError", m.py().get_type::<AeroidentError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    record::register(m)?;
    batch::register(m)?;
    estimator::register(m)?;
    f16::register(m)?;
    montecarlo::register(m)?;
    Ok(())
}
