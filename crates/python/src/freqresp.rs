//! `freqresp`: frequency responses of a record and transfer-function fits, exactly as
//! `aeroident freqresp DATA --map MAPPING --input … --output …`
//! ([`aeroident_pipelines::freqresp::freqresp`]), each pair's arrays as numpy arrays.

use std::path::Path;

use aeroident_io::{Mapping, Record, RecordSource};
use aeroident_pipelines::freqresp::{FreqRespOptions, FreqRespOutcome, freqresp};
use aeroident_signals::spectral::{PairResponse, SpectralOptions};
use aeroident_signals::tf_fit::{FitOptions, TfSpec};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::{convert, err, to_py};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(freqresp_file, m)?)?;
    Ok(())
}

/// Frequency responses of a record file as `aeroident freqresp` computes them (documentation:
/// `aeroident.freqresp` in python/aeroident/__init__.py).
#[pyfunction]
#[pyo3(signature = (path, mapping, inputs, outputs, windows=None, windows_s=None, overlap=0.8, f_min_hz=None, f_max_hz=None, points_per_decade=40, fits=None, min_coherence=0.6))]
#[allow(clippy::too_many_arguments)]
fn freqresp_file<'py>(
    py: Python<'py>,
    path: &str,
    mapping: &str,
    inputs: Vec<String>,
    outputs: Vec<String>,
    windows: Option<Vec<(f64, f64)>>,
    windows_s: Option<Vec<f64>>,
    overlap: f64,
    f_min_hz: Option<f64>,
    f_max_hz: Option<f64>,
    points_per_decade: usize,
    fits: Option<Vec<String>>,
    min_coherence: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let windows = crate::record::time_windows("freqresp", windows)?;
    let fits = fits
        .unwrap_or_default()
        .iter()
        .map(|f| TfSpec::parse(f))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| err(format!("freqresp: fits: {e}")))?;
    let opts = FreqRespOptions {
        inputs,
        outputs,
        windows,
        spectral: SpectralOptions {
            window_lengths_s: windows_s.unwrap_or_default(),
            overlap,
            f_min_hz,
            f_max_hz,
            points_per_decade,
        },
        fits,
        fit: FitOptions { min_coherence, ..FitOptions::default() },
        excitation: None,
    };
    let (path, mapping) = (path.to_owned(), mapping.to_owned());
    let run = move || -> anyhow::Result<_> {
        let mapping = Mapping::from_path(Path::new(&mapping))?;
        let reader = Record::open(RecordSource::Path(path), None, &mapping)?.reader;
        Ok(freqresp(reader, &opts)?)
    };
    let r = crate::interruptible(py, None, run)?;
    outcome_dict(py, r.map_err(to_py)?)
}

/// The outcome as the dict `aeroident.freqresp` documents: `freqresp.json`'s keys, each pair's
/// arrays as numpy arrays (the sweeps left out).
fn outcome_dict(py: Python<'_>, o: FreqRespOutcome) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("file", &o.file)?;
    d.set_item("samples", o.samples)?;
    d.set_item("stretches", o.stretches)?;
    d.set_item("dt_s", o.dt_s)?;
    d.set_item("window_lengths_s", o.window_lengths_s.clone().into_pyarray(py))?;
    d.set_item("overlap", o.overlap)?;
    let pairs = PyList::empty(py);
    for p in o.pairs {
        pairs.append(pair_dict(py, p)?)?;
    }
    d.set_item("pairs", pairs)?;
    let fits = serde_json::to_value(&o.fits).map_err(|e| err(format!("freqresp: {e}")))?;
    d.set_item("fits", convert::json_to_py(py, &fits)?)?;
    d.set_item("warnings", o.warnings)?;
    Ok(d)
}

/// One pair's response: `input`, `output` and its arrays (numpy).
fn pair_dict(py: Python<'_>, p: PairResponse) -> PyResult<Bound<'_, PyDict>> {
    let e = PyDict::new(py);
    e.set_item("input", &p.input)?;
    e.set_item("output", &p.output)?;
    for (k, v) in [
        ("frequency_hz", p.frequency_hz),
        ("magnitude_db", p.magnitude_db),
        ("phase_deg", p.phase_deg),
        ("coherence", p.coherence),
        ("multiple_coherence", p.multiple_coherence),
        ("random_error", p.random_error),
        ("magnitude_error_db", p.magnitude_error_db),
        ("phase_error_deg", p.phase_error_deg),
    ] {
        e.set_item(k, v.into_pyarray(py))?;
    }
    Ok(e)
}
