//! The `aeroident` Python extension module (`aeroident._aeroident`; the pure-Python package in
//! `python/aeroident` re-exports it with docstrings, the Ray backend and type stubs).
//!
//! Every function here is a thin layer over the Rust library (`aeroident`, `aeroident-io`,
//! `aeroident-models`): the same code paths as the CLI, the same error messages (raised as
//! `aeroident.AeroidentError`, text = what the CLI prints after `error: `), and the GIL released
//! during long calls (record replay, simulation, trim, Monte Carlo).
//!
//! No call panics into Python: bad input is an `AeroidentError` (or a `TypeError`/`ValueError`
//! of pyo3's argument conversion), and Ctrl-C during a long call is Python's
//! `KeyboardInterrupt` (`Signals`).

use std::sync::Mutex;
use std::time::{Duration, Instant};

use pyo3::prelude::*;

mod aircraft;
mod batch;
mod convert;
mod estimator;
mod f16;
mod freqresp;
mod montecarlo;
mod record;
mod units;

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

/// Ctrl-C (any Python signal handler) during a long call.
///
/// Python's C-level handler only sets a flag; `PyErr_CheckSignals` runs the Python handler
/// (`KeyboardInterrupt` for SIGINT), on the main thread only. A long call runs with the GIL
/// released (`py.detach`), so nothing would ask until it returns, and the first Python API
/// call after it (building a numpy array) would meet the pending exception. A long call
/// therefore asks through [`Signals::interrupted`] between units of work (samples, chunks of
/// runs), stops when told, and calls [`Signals::finish`] before converting its result.
pub(crate) struct Signals {
    /// The handler's exception, once raised.
    raised: Mutex<Option<PyErr>>,
    /// When Python was last asked.
    asked: Mutex<Instant>,
}

impl Signals {
    /// At most this often the GIL is taken back to ask Python (it costs microseconds).
    const INTERVAL: Duration = Duration::from_millis(50);

    pub(crate) fn new() -> Self {
        Self { raised: Mutex::new(None), asked: Mutex::new(Instant::now()) }
    }

    /// Whether a signal handler raised (its exception kept for [`Signals::finish`]); callable
    /// with the GIL released, it attaches to ask at most every [`Signals::INTERVAL`].
    pub(crate) fn interrupted(&self) -> bool {
        let mut raised = self.raised.lock().unwrap_or_else(|p| p.into_inner());
        if raised.is_some() {
            return true;
        }
        let mut asked = self.asked.lock().unwrap_or_else(|p| p.into_inner());
        if asked.elapsed() < Self::INTERVAL {
            return false;
        }
        *asked = Instant::now();
        *raised = Python::attach(|py| py.check_signals().err());
        raised.is_some()
    }

    /// The handler's exception (`KeyboardInterrupt`) if one was raised during the call or a
    /// signal is pending now; to be called with the GIL held before the result is converted.
    ///
    /// # Errors
    /// The handler's exception.
    pub(crate) fn finish(self, py: Python<'_>) -> PyResult<()> {
        match self.raised.into_inner().unwrap_or_else(|p| p.into_inner()) {
            Some(e) => Err(e),
            None => py.check_signals(),
        }
    }
}

/// Runs `work` on a thread of its own while the caller's thread, with the GIL released, asks
/// Python for a signal every [`Signals::INTERVAL`]: a call whose library work has no unit
/// boundary to ask at (a fit's iterations, a structure selection, a spectral estimate) still
/// answers Ctrl-C within a fraction of a second. On a signal `stop` is raised (a fit ends at
/// its next iteration, its bootstrap before its next replica) and the call returns the
/// handler's exception at once; the worker finishes on its own and its result is dropped.
///
/// # Errors
/// The handler's exception (`KeyboardInterrupt`); a worker that could not be started or that
/// panicked.
pub(crate) fn interruptible<T: Send + 'static>(
    py: Python<'_>,
    stop: Option<aeroident_estimators::output_error::StopFlag>,
    work: impl FnOnce() -> T + Send + 'static,
) -> PyResult<T> {
    use std::sync::mpsc::RecvTimeoutError;
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("aeroident-call".into())
        .stack_size(aeroident_pipelines::WORKER_STACK_BYTES)
        .spawn(move || {
            let _ = tx.send(work());
        })
        .map_err(|e| err(format!("starting the call's worker thread: {e}")))?;
    let signals = std::sync::Arc::new(Signals::new());
    let asking = signals.clone();
    let out = py.detach(move || {
        loop {
            match rx.recv_timeout(Signals::INTERVAL) {
                Ok(r) => return Some(Ok(r)),
                Err(RecvTimeoutError::Disconnected) => return Some(Err(())),
                Err(RecvTimeoutError::Timeout) if asking.interrupted() => {
                    stop.iter().for_each(|s| s.raise());
                    return None;
                }
                Err(RecvTimeoutError::Timeout) => {}
            }
        }
    });
    // The worker never holds `signals`: the loop's clone is gone, so this is the last one.
    let signals = std::sync::Arc::try_unwrap(signals).unwrap_or_else(|_| Signals::new());
    signals.finish(py)?;
    match out {
        Some(Ok(r)) => Ok(r),
        Some(Err(())) => Err(err("internal: the call's worker thread ended without a result")),
        None => Err(err("interrupted")),
    }
}

/// The library's check of a count against its limit, for a Python int of any size (one past
/// 64 bits is checked as `u64::MAX` and shown as given).
fn check_count<T: TryFrom<u64> + Copy + std::fmt::Display>(
    count: &Bound<'_, pyo3::types::PyInt>,
    option: &str,
    most: T,
    check: impl Fn(T) -> Result<(), String>,
) -> PyResult<()> {
    let given = count.to_string();
    let n = match count.extract::<u64>() {
        Ok(n) => T::try_from(n).unwrap_or(most),
        Err(_) if count.as_any().lt(0)? => {
            return Err(err(format!("{option} = {given}: a count cannot be negative")));
        }
        Err(_) => most,
    };
    check(n).map_err(|e| err(e.replacen(&n.to_string(), &given, 1)))
}

/// `runs` of a Monte Carlo campaign checked as the library checks it
/// ([`aeroident_pipelines::montecarlo::check_runs`]), before any run or task.
#[pyfunction]
fn check_runs(runs: &Bound<'_, pyo3::types::PyInt>) -> PyResult<()> {
    use aeroident_pipelines::montecarlo::{MAX_RUNS, check_runs};
    check_count(runs, "runs", MAX_RUNS + 1, |n| check_runs(n, "runs"))
}

/// `bootstrap` of a fit checked as the library checks it
/// ([`aeroident_pipelines::replay::batch::check_bootstrap_refits`]), before the record is read.
#[pyfunction]
fn check_bootstrap_refits(refits: &Bound<'_, pyo3::types::PyInt>) -> PyResult<()> {
    use aeroident_pipelines::replay::batch::{MAX_BOOTSTRAP_REFITS, check_bootstrap_refits};
    check_count(refits, "option `bootstrap`", MAX_BOOTSTRAP_REFITS + 1, |n| {
        check_bootstrap_refits(n).map_err(|e| format!("option `bootstrap`: {e}"))
    })
}

/// The `aeroident` command line on `argv` (the first element the program's name), the
/// installed console script's body (`aeroident._cli:main`): the same program as the Rust
/// binary ([`aeroident::run_main`]), with the GIL released while it runs. Returns the exit
/// code.
#[pyfunction]
fn cli_main(py: Python<'_>, argv: Vec<String>) -> u8 {
    py.detach(move || aeroident::run_main(argv))
}

#[pymodule]
fn _aeroident(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("AeroidentError", m.py().get_type::<AeroidentError>())?;
    aeroident_pipelines::install_worker_stacks();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // numpy's C API and the numpy crate's shared borrow checking are looked up on the first
    // array built or borrowed; a failure there (e.g. a pending KeyboardInterrupt raised while
    // they import numpy's modules) is a panic in the numpy crate, so both are looked up here,
    // where a failure is an ImportError.
    let py = m.py();
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        use numpy::PyArrayMethods as _;
        let _ = numpy::PyArray1::<f64>::zeros(py, 0, false).readonly();
    }))
    .map_err(|_| {
        pyo3::exceptions::PyImportError::new_err(
            "aeroident: numpy's C API could not be loaded (is numpy installed and importable?)",
        )
    })?;
    m.add("MAX_RUNS", aeroident_pipelines::montecarlo::MAX_RUNS)?;
    m.add("MAX_BOOTSTRAP_REFITS", aeroident_pipelines::replay::batch::MAX_BOOTSTRAP_REFITS)?;
    m.add_function(wrap_pyfunction!(check_runs, m)?)?;
    m.add_function(wrap_pyfunction!(check_bootstrap_refits, m)?)?;
    m.add_function(wrap_pyfunction!(cli_main, m)?)?;
    record::register(m)?;
    batch::register(m)?;
    estimator::register(m)?;
    f16::register(m)?;
    aircraft::register(m)?;
    montecarlo::register(m)?;
    freqresp::register(m)?;
    Ok(())
}
