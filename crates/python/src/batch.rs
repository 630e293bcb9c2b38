//! `fit`: the batch output-error, filter-error and frequency-domain output-error fits of a
//! whole record, exactly as `aeroident replay DATA --map MAPPING --estimator oe|fem|fdoe`
//! (the post-flight reference fit,
//! `aeroident_pipelines::replay::fit::fit_record`), with the estimates, their σ and correlation, the
//! residuals and the model-vs-measured traces as numpy arrays.

use aeroident_io::ParameterResult;
use std::path::Path;

use aeroident_io::{Mapping, Record, RecordSource};
use aeroident_pipelines::estimators::EstimatorKind;
use aeroident_pipelines::estimators::OptionError;
use aeroident_pipelines::job::fit::{FitJob, FitJobOutcome};
use aeroident_pipelines::job::{CompatSource, InPlace, JobLog, Ran, Records};
use aeroident_pipelines::replay::batch::FitOptions;
use numpy::IntoPyArray;
use numpy::ndarray::Array2;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::record::estimator_kind;
use crate::{convert, err, to_py};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(fit_file, m)?)?;
    Ok(())
}

/// The fit's options from the keyword arguments given (`None`: not given) and any further
/// ones (`**options`, by their keys), parsed by the one parser of a batch fit's options
/// ([`FitOptions::from_pairs`]).
///
/// # Errors
/// A message naming the keyword and what it must be, or the keywords the method takes.
fn fit_options(
    kind: EstimatorKind,
    given: Vec<(&'static str, Option<toml::Value>)>,
    more: Option<&Bound<'_, PyDict>>,
) -> PyResult<FitOptions> {
    let keyword = |key: &str| {
        if key == "bootstrap_refits" { "bootstrap".to_string() } else { key.to_string() }
    };
    let mut pairs: Vec<(String, toml::Value)> =
        given.into_iter().filter_map(|(k, v)| v.map(|v| (k.to_string(), v))).collect();
    pairs.extend(crate::record::keyword_options(more)?);
    let pairs = pairs.iter().map(|(k, v)| (k.as_str(), v.clone()));
    FitOptions::from_pairs(kind, pairs).map_err(|e| match e {
        OptionError::Unknown { kind, key } => {
            let takes: Vec<String> =
                kind.fit_options().iter().map(|k| format!("`{}`", keyword(k))).collect();
            err(format!(
                "fit: estimator `{}`: unknown keyword argument `{}` (it takes {})",
                kind.name(),
                keyword(&key),
                takes.join(", ")
            ))
        }
        OptionError::Invalid { key, reason, .. } => {
            err(format!("fit: {}: {reason}", keyword(&key)))
        }
    })
}

/// The batch kind `estimator` names; a real-time kind is refused with where it belongs.
fn batch_kind(estimator: &str) -> PyResult<EstimatorKind> {
    let kind = estimator_kind(estimator)?;
    if !kind.is_batch() {
        return Err(err(format!(
            "fit: estimator `{}` is a real-time method: use `aeroident.replay(..., estimator=\"{}\")` (fit takes `oe` or `fem`)",
            kind.name(),
            kind.name()
        )));
    }
    Ok(kind)
}

/// The correlation matrix (row-major `n × n`) of a covariance whose entries may be absent
/// (fdoe's parameters not estimated): NaN in their rows and columns.
fn correlation_of(cov: &[Option<f64>], n: usize) -> Vec<f64> {
    let c = |i: usize, j: usize| cov[i * n + j].unwrap_or(f64::NAN);
    (0..n).flat_map(|i| (0..n).map(move |j| c(i, j) / (c(i, i) * c(j, j)).sqrt())).collect()
}

/// A row-major `rows × cols` vector as a 2-D array.
fn matrix(v: Vec<f64>, rows: usize, cols: usize) -> PyResult<Array2<f64>> {
    Array2::from_shape_vec((rows, cols), v).map_err(|e| err(format!("internal: array shape: {e}")))
}

/// Fits a record file by output error (`oe`), the filter-error method (`fem`) or
/// frequency-domain output error (`fdoe`, over `band_hz`) as
/// `aeroident replay DATA --map MAPPING --estimator oe|fem|fdoe [--band-hz F0:F1] [--model M] [--initial-states S]
/// [--validate-on V] [--bootstrap N] [--max-iterations N] [--process-noise S] [--window A:B …] [--and FILE …]`
/// (documentation:
/// `aeroident.fit` in python/aeroident/__init__.py).
#[pyfunction]
#[pyo3(signature = (path, mapping, estimator="oe", model=None, initial_states="first-sample", validate_with=None, bootstrap=None, max_iterations=None, process_noise=None, compat=None, windows=None, also=None, select="swr", candidates=None, band_hz=None, knots_deg=None, allow_duplicate_records=false, cross_check=None, **options))]
#[allow(clippy::too_many_arguments)]
fn fit_file<'py>(
    py: Python<'py>,
    path: &str,
    mapping: &str,
    estimator: &str,
    model: Option<&str>,
    initial_states: &str,
    validate_with: Option<&str>,
    bootstrap: Option<usize>,
    max_iterations: Option<usize>,
    process_noise: Option<&str>,
    compat: Option<&str>,
    windows: Option<Vec<(f64, f64)>>,
    also: Option<Vec<String>>,
    select: &str,
    candidates: Option<Vec<String>>,
    band_hz: Option<(f64, f64)>,
    knots_deg: Option<Vec<f64>>,
    allow_duplicate_records: bool,
    cross_check: Option<bool>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let windows = crate::record::time_windows("fit", windows)?;
    let compat = compat_source(compat);
    let kind = batch_kind(estimator)?;
    let given = vec![
        ("initial_states", Some(toml::Value::String(initial_states.to_owned()))),
        ("bootstrap_refits", bootstrap.map(|n| toml::Value::Integer(n as i64))),
        ("max_iterations", max_iterations.map(|n| toml::Value::Integer(n as i64))),
        ("process_noise", process_noise.map(|s| toml::Value::String(s.to_owned()))),
        ("band_hz", band_hz.map(|(a, b)| toml::Value::Array(vec![a.into(), b.into()]))),
    ];
    let stop = aeroident_estimators::output_error::StopFlag::default();
    let options =
        FitOptions { windows, stop: Some(stop.clone()), ..fit_options(kind, given, options)? };
    let diff_window = aeroident_pipelines::structure::DIFF_WINDOW;
    let model = crate::record::model_choice(model, select, candidates, knots_deg, diff_window);
    let (path, mapping) = (path.to_owned(), mapping.to_owned());
    let also = also.unwrap_or_default();
    let cross_check = crate::record::panel(cross_check);
    let validate_on = validate_with
        .map(|p| aeroident_pipelines::job::ValidateOn { path: p.to_owned(), windows: Vec::new() });
    let run = move || -> anyhow::Result<(FitJobOutcome, Vec<String>)> {
        let mapping = Mapping::from_path(Path::new(&mapping))?;
        let records = Records {
            data: path,
            and: also,
            format: None,
            mapping,
            live: false,
            allow_duplicates: allow_duplicate_records,
            held: None,
        };
        fit_job(&FitJob { records, model, compat, options, cross_check, validate_on })
    };
    let r = crate::interruptible(py, Some(stop), run)?;
    let (done, notes) = r.map_err(to_py)?;
    fit_dict(py, done, notes)
}

/// `compat=`: `"auto"` (checked on the records, as `--compat auto`), else a `compat.json`,
/// read and checked against the records by the job's first step, before any record is read.
fn compat_source(compat: Option<&str>) -> Option<CompatSource> {
    compat.map(CompatSource::from_arg)
}

/// The reader notes a job's steps give (its second record's), collected for Python.
#[derive(Default)]
struct Notes(Vec<String>);

impl JobLog for Notes {
    fn reader_note(&mut self, text: &str) {
        self.0.push(text.to_string());
    }
}

/// Runs `job` in place: its records opened (their readers' notes collected), fitted, and
/// validated on the second record when asked.
fn fit_job(job: &FitJob) -> anyhow::Result<(FitJobOutcome, Vec<String>)> {
    let Ran::Done(prepared) = job.prepare(&mut InPlace, &mut ())? else {
        anyhow::bail!("internal: a step run in place was abandoned");
    };
    let (mut readers, mut notes, mut reports) = (Vec::new(), Notes::default(), Vec::new());
    for file in job.records.files() {
        let source = RecordSource::Path(file.clone());
        let Record { reader, report, .. } = Record::open(source, None, &job.records.mapping)?;
        readers.push(reader);
        notes.0.extend(report.notes());
        reports.push(report);
    }
    let (outcome, selection) = job.fit(prepared, readers, reports)?;
    let done = job.finish(outcome, selection, &mut InPlace, &mut notes, String::new)?;
    Ok((done, notes.0))
}

/// The result dict of `fit` (module doc of the Python package).
fn fit_dict(
    py: Python<'_>,
    done: FitJobOutcome,
    notes: Vec<String>,
) -> PyResult<Bound<'_, PyDict>> {
    let summary = done.document().map_err(|e| err(e.to_string()))?;
    let (outcome, selection) = (done.outcome, done.selection);
    let r = &outcome.result;
    let (n, np, ny) = (r.n(), r.n_params, r.outputs.len());
    let s = &outcome.summary;
    let d = PyDict::new(py);
    d.set_item("names", r.names[..np].to_vec())?;
    // The summary's numbers, NaN where it has `null` (a parameter fdoe's linear model cannot
    // see); for `oe` and `fem` they are the fit's own.
    let nan = |v: Option<f64>| v.unwrap_or(f64::NAN);
    // The keys are the summary's per-parameter keys (aeroident_io::parameter).
    let column = |f: fn(&ParameterResult) -> Option<f64>| -> Vec<f64> {
        s.parameters.iter().map(|p| nan(f(p))).collect()
    };
    d.set_item("estimate", column(|p| p.estimate).into_pyarray(py))?;
    d.set_item("std_error", column(|p| p.std_error).into_pyarray(py))?;
    d.set_item("crb_std_error", column(|p| p.crb_std_error).into_pyarray(py))?;
    d.set_item("timing_std_error", column(|p| p.timing_std_error).into_pyarray(py))?;
    d.set_item("unmodelled_std_error", column(|p| p.unmodelled_std_error).into_pyarray(py))?;
    d.set_item("reference", column(|p| p.reference).into_pyarray(py))?;
    d.set_item("status", s.parameters.iter().map(|p| p.status.clone()).collect::<Vec<_>>())?;
    d.set_item("flags", s.parameters.iter().map(|p| p.flags.clone()).collect::<Vec<_>>())?;
    d.set_item(
        "parameter_notes",
        s.parameters.iter().map(|p| p.notes.clone()).collect::<Vec<_>>(),
    )?;
    let corr: Vec<f64> = match &outcome.frequency {
        Some(fd) => correlation_of(&fd.covariance, np),
        None => (0..np).flat_map(|i| (0..np).map(move |j| r.correlation[i * n + j])).collect(),
    };
    d.set_item("correlation", matrix(corr, np, np)?.into_pyarray(py))?;
    d.set_item("outputs", r.outputs.iter().map(|o| o.name()).collect::<Vec<_>>())?;
    d.set_item(
        "residuals",
        matrix(r.residuals.clone(), r.residuals.len() / ny.max(1), ny)?.into_pyarray(py),
    )?;
    let traces = PyDict::new(py);
    for t in &outcome.traces {
        let tr = PyDict::new(py);
        tr.set_item("t_s", t.t_s.clone().into_pyarray(py))?;
        tr.set_item("measured", t.measured.clone().into_pyarray(py))?;
        tr.set_item("simulated", t.simulated.clone().into_pyarray(py))?;
        traces.set_item(&t.name, tr)?;
    }
    d.set_item("traces", traces)?;
    d.set_item("model", outcome.model.name.clone())?;
    d.set_item("notes", notes)?;
    d.set_item("summary", convert::json_to_py(py, &summary)?)?;
    d.set_item("selected_model", selection.map(|s| s.model.to_toml()))?;
    Ok(d)
}
