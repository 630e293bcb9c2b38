//! `read` (a record as numpy arrays) and `replay` (a record or arrays through an estimator, all
//! samples in Rust, the estimates as a time × parameter matrix).

use std::path::Path;
use std::sync::Arc;

use aeroident_estimators::AirDataSample;
use aeroident_io::{Mapping, ModelSpec, Record, RecordEvent, RecordSource};
use aeroident_pipelines::estimators::{EstimatorKind, EstimatorOptions, build};
use aeroident_pipelines::job::replay::ReplayJob;
use aeroident_pipelines::job::{CompatSource, InPlace, ModelChoice, Ran, Records};
use aeroident_pipelines::record::cache::ScreenedRecord;
use aeroident_pipelines::record::unsupported;
use aeroident_pipelines::replay::arrays::{
    EstimateArrays, check_array_size, replay_arrays_cached, replay_arrays_observed, replay_samples,
};
use aeroident_pipelines::replay::{DerivativeSource, ReplayObserver, ReplayOptions};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{self, CONSTANTS, OPTIONAL, REQUIRED, Source};
use crate::{Signals, err, to_py};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(replay_file, m)?)?;
    m.add_function(wrap_pyfunction!(replay_arrays_py, m)?)?;
    m.add_function(wrap_pyfunction!(sample_keys, m)?)?;
    Ok(())
}

/// The `windows=[(start_s, end_s), …]` argument of `replay` and `fit` as checked time windows.
///
/// # Errors
/// A window that is not finite with start < end, or windows that overlap, naming `func`.
pub fn time_windows(
    func: &str,
    windows: Option<Vec<(f64, f64)>>,
) -> PyResult<Vec<aeroident_pipelines::window::TimeWindow>> {
    let windows: Vec<_> = windows
        .unwrap_or_default()
        .into_iter()
        .map(|(a, b)| aeroident_pipelines::window::TimeWindow::parse(&format!("{a}:{b}")))
        .collect::<Result<_, _>>()
        .map_err(|e| err(format!("{func}: windows: {e}")))?;
    aeroident_pipelines::window::check_windows(&windows)
        .map_err(|e| err(format!("{func}: windows: {e}")))?;
    Ok(windows)
}

/// The estimator by its CLI name (`rls`, `rls-iv`, `ftr`, `ekf`, `smpe`, `smpe-corrected`,
/// `gradient`, `oe`, `fem`).
pub fn estimator_kind(name: &str) -> PyResult<EstimatorKind> {
    use aeroident_pipelines::Named as _;
    let found = EstimatorKind::ALL.iter().find(|k| k.name().eq_ignore_ascii_case(name));
    found.copied().ok_or_else(|| {
        err(format!("unknown estimator `{name}` (one of: {})", EstimatorKind::names().join(", ")))
    })
}

/// The estimator options among the keyword arguments, each with the registry's key
/// ([`EstimatorKind::options`]) and the keyword's name.
const OPTION_KEYWORDS: [(&str, &str); 5] = [
    ("forgetting", "forgetting"),
    ("parameter_walk_per_sqrt_s", "parameter_walk_per_sqrt_s"),
    ("grid_hz", "ftr_grid_hz"),
    ("sliding_gain_per_s", "sliding_gain_per_s"),
    ("reaching_rate_per_s", "reaching_rate_per_s"),
];

/// The keyword argument of the registry's option `key`.
fn keyword(key: &str) -> &str {
    OPTION_KEYWORDS.iter().find(|o| o.0 == key).map_or(key, |o| o.1)
}

/// The options of estimator `kind` from the keyword arguments given (`None`: not given), as
/// (registry key, value) pairs: parsed by the estimator registry
/// ([`aeroident_pipelines::estimators::parse_options`]), which refuses an option the kind does
/// not take instead of ignoring it.
///
/// # Errors
/// A message naming the kind, the keyword argument and the keyword arguments the kind takes,
/// or what the value must be.
pub fn estimator_options(
    kind: EstimatorKind,
    given: Vec<(&'static str, Option<toml::Value>)>,
    more: Option<&Bound<'_, PyDict>>,
) -> PyResult<EstimatorOptions> {
    use aeroident_pipelines::estimators::{OptionError, parse_options};
    let mut pairs: Vec<(String, toml::Value)> =
        given.into_iter().filter_map(|(key, v)| v.map(|v| (key.to_string(), v))).collect();
    pairs.extend(keyword_options(more)?);
    let pairs = pairs.iter().map(|(k, v)| (k.as_str(), v.clone()));
    parse_options(kind, pairs).map_err(|e| {
        err(match e {
            OptionError::Unknown { kind, key } => {
                // `samples` is the closed-loop experiment's choice of feed, not an estimator's.
                let takes: Vec<String> = kind
                    .options()
                    .iter()
                    .filter(|o| **o != "samples")
                    .map(|o| format!("`{}`", keyword(o)))
                    .collect();
                let takes = if takes.is_empty() { "none".to_string() } else { takes.join(", ") };
                format!(
                    "estimator `{}`: unknown keyword argument `{}` (it takes {takes})",
                    kind.name(),
                    keyword(&key)
                )
            }
            OptionError::Invalid { kind, key, reason } => {
                format!("estimator `{}`: `{}` {reason}", kind.name(), keyword(&key))
            }
        })
    })
}

/// The estimator options given as further keyword arguments (`**options`: any option the
/// estimator registry knows, by its key, e.g. `instrument_delay=8`), as (registry key, value)
/// pairs.
///
/// # Errors
/// A value that is not a number, a string, a boolean or a list of them.
pub fn keyword_options(more: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, toml::Value)>> {
    let Some(more) = more else { return Ok(Vec::new()) };
    let mut out = Vec::new();
    for (k, v) in more.iter() {
        let k: String = k.extract()?;
        let key = OPTION_KEYWORDS.iter().find(|o| o.1 == k).map_or(k.clone(), |o| o.0.to_string());
        out.push((key, toml_value(&v).map_err(|e| err(format!("`{k}`: {e}")))?));
    }
    Ok(out)
}

/// A Python value as an option value: a bool, an int, a float, a string, or a list or tuple
/// of them.
fn toml_value(v: &Bound<'_, PyAny>) -> Result<toml::Value, String> {
    use pyo3::types::{PyBool, PyFloat, PyInt, PyList, PyString, PyTuple};
    if v.is_instance_of::<PyBool>() {
        return v.extract::<bool>().map(toml::Value::Boolean).map_err(|e| e.to_string());
    }
    if v.is_instance_of::<PyInt>() {
        return v.extract::<i64>().map(toml::Value::Integer).map_err(|e| e.to_string());
    }
    if v.is_instance_of::<PyFloat>() {
        return v.extract::<f64>().map(toml::Value::Float).map_err(|e| e.to_string());
    }
    if v.is_instance_of::<PyString>() {
        return v.extract::<String>().map(toml::Value::String).map_err(|e| e.to_string());
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> = v
            .try_iter()
            .map_err(|e| e.to_string())?
            .collect::<PyResult<_>>()
            .map_err(|e| e.to_string())?;
        return items.iter().map(toml_value).collect::<Result<_, _>>().map(toml::Value::Array);
    }
    Err(format!("expected a number, a string, a boolean or a list of them, got {}", v.get_type()))
}

/// A number keyword argument as an option value.
pub fn number(v: Option<f64>) -> Option<toml::Value> {
    v.map(toml::Value::Float)
}

/// A model argument as the CLI's `--model`: a preset name or a model file path.
pub fn model_spec(model: &str) -> PyResult<ModelSpec> {
    ModelSpec::from_arg(model).map_err(to_py)
}

/// The keys a sample dict may hold (channels and constants).
#[pyfunction]
fn sample_keys() -> Vec<&'static str> {
    convert::all_keys()
}

/// One column per sample field (`NaN` = absent), the constants per sample, the row numbers.
struct Columns {
    rows: Vec<u64>,
    cols: Vec<(&'static str, Vec<f64>)>,
    rejected_rows: Vec<u64>,
    rejected_reasons: Vec<String>,
    gap_rows: Vec<u64>,
    notes: Vec<String>,
}

/// Reads `path` with the CLI's reader for its extension ([`Record::open`]: CSV,
/// `.asc`, `.mat`, ULog, DataFlash), stopping early when `signals` reports Ctrl-C.
fn read_columns(path: &str, mapping: &str, signals: &Signals) -> anyhow::Result<Columns> {
    let mapping = Mapping::from_path(Path::new(mapping))?;
    let record = Record::open(RecordSource::Path(path.to_string()), None, &mapping)?;
    let (notes, reader) = (record.notes(), record.reader);
    let keys = convert::all_keys();
    let mut c = Columns {
        rows: Vec::new(),
        cols: keys.iter().map(|k| (*k, Vec::new())).collect(),
        rejected_rows: Vec::new(),
        rejected_reasons: Vec::new(),
        gap_rows: Vec::new(),
        notes,
    };
    for ev in reader {
        if signals.interrupted() {
            break; // the caller raises the handler's exception
        }
        match ev? {
            RecordEvent::Sample { row, sample: s } => {
                c.rows.push(row);
                let mut k = 0;
                let mut push = |v: Option<f64>| {
                    c.cols[k].1.push(v.unwrap_or(f64::NAN));
                    k += 1;
                };
                for v in [s.t_s, s.vt_mps, s.alpha_rad, s.qbar_pa] {
                    push(Some(v));
                }
                for f in OPTIONAL {
                    push((f.1)(&s));
                }
                for f in CONSTANTS {
                    push((f.1)(&s.constants));
                }
            }
            RecordEvent::Rejected { row, problem } => {
                c.rejected_rows.push(row);
                c.rejected_reasons.push(problem.to_string());
            }
            RecordEvent::Gap { row, .. } => c.gap_rows.push(row),
        }
    }
    Ok(c)
}

/// See `aeroident.read` (python/aeroident/__init__.py) for the documentation.
#[pyfunction]
#[pyo3(signature = (path, mapping))]
fn read<'py>(py: Python<'py>, path: &str, mapping: &str) -> PyResult<Bound<'py, PyDict>> {
    let (p, m) = (path.to_owned(), mapping.to_owned());
    let signals = Signals::new();
    let c = py.detach(|| read_columns(&p, &m, &signals));
    signals.finish(py)?;
    let c = c.map_err(to_py)?;
    let d = PyDict::new(py);
    for (k, v) in c.cols {
        d.set_item(k, v.into_pyarray(py))?;
    }
    d.set_item("row", c.rows.into_pyarray(py))?;
    d.set_item("rejected_rows", c.rejected_rows.into_pyarray(py))?;
    d.set_item("rejected_reasons", c.rejected_reasons)?;
    d.set_item("gap_rows", c.gap_rows.into_pyarray(py))?;
    d.set_item("notes", c.notes)?;
    Ok(d)
}

/// A replay observer that ends the replay at Ctrl-C (its error stops the replay loop; the
/// caller raises the handler's exception instead of that error).
struct Interruptible<'a>(&'a Signals);

impl ReplayObserver for Interruptible<'_> {
    fn estimate(
        &mut self,
        _t_s: f64,
        _v: &[Option<f64>],
        _s: &[Option<f64>],
    ) -> std::io::Result<()> {
        if self.0.interrupted() {
            return Err(std::io::Error::other("interrupted"));
        }
        Ok(())
    }
}

/// The result dict of a replay: names, t_s, estimates and std_error (time × parameter).
fn arrays_dict<'py>(py: Python<'py>, a: EstimateArrays) -> PyResult<Bound<'py, PyDict>> {
    let n = a.names.len();
    let k = a.t_s.len();
    let d = PyDict::new(py);
    let shape = |v: Vec<f64>| {
        Array2::from_shape_vec((k, n), v).map_err(|e| err(format!("internal: array shape: {e}")))
    };
    d.set_item("names", a.names.iter().map(|s| s.to_string()).collect::<Vec<_>>())?;
    d.set_item("t_s", a.t_s.into_pyarray(py))?;
    d.set_item("estimates", shape(a.values)?.into_pyarray(py))?;
    d.set_item("std_error", shape(a.sigmas)?.into_pyarray(py))?;
    Ok(d)
}

fn derivative_source(s: &str) -> PyResult<DerivativeSource> {
    use aeroident_pipelines::Named as _;
    DerivativeSource::from_name(s).ok_or_else(|| {
        err(format!("derivatives: `{s}` is not one of {}", DerivativeSource::names().join(", ")))
    })
}

/// The model choice of `replay`'s and `fit`'s keywords (`model`, `select`, `candidates`,
/// `knots_deg`), the selection differentiating with `diff_window`.
pub fn model_choice(
    model: Option<&str>,
    select: &str,
    candidates: Option<Vec<String>>,
    knots_deg: Option<Vec<f64>>,
    diff_window: usize,
) -> ModelChoice {
    ModelChoice {
        model: model.map(str::to_owned),
        select: select.to_owned(),
        candidates: candidates.unwrap_or_default(),
        knots_deg: knots_deg.unwrap_or_default(),
        diff_window,
    }
}

/// The panel of the Python `cross_check` argument: `None` the default panel, `True` the whole
/// panel (`--cross-check`), `False` none (`--no-cross-check`).
pub(crate) fn panel(cross_check: Option<bool>) -> aeroident_pipelines::job::cross_check::Panel {
    use aeroident_pipelines::job::cross_check::Panel;
    Panel::from_flags(cross_check == Some(true), cross_check == Some(false))
}

/// Replays a record file exactly as `aeroident replay DATA --map MAPPING` (module doc of the
/// Python package).
#[pyfunction]
#[pyo3(signature = (path, mapping, estimator="rls", model=None, forgetting=None, derivatives="auto", diff_window=5, compat=None, windows=None, cross_check=None, select="swr", candidates=None, knots_deg=None, **options))]
#[allow(clippy::too_many_arguments)]
fn replay_file<'py>(
    py: Python<'py>,
    path: &str,
    mapping: &str,
    estimator: &str,
    model: Option<&str>,
    forgetting: Option<f64>,
    derivatives: &str,
    diff_window: usize,
    compat: Option<&str>,
    windows: Option<Vec<(f64, f64)>>,
    cross_check: Option<bool>,
    select: &str,
    candidates: Option<Vec<String>>,
    knots_deg: Option<Vec<f64>>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = estimator_kind(estimator)?;
    let windows = time_windows("replay", windows)?;
    let estimator_options = (!kind.is_batch())
        .then(|| estimator_options(kind, vec![("forgetting", number(forgetting))], options))
        .transpose()?
        .unwrap_or_default();
    let derivatives = derivative_source(derivatives)?;
    let choice = model_choice(model, select, candidates, knots_deg, diff_window);
    let (path, mapping) = (path.to_owned(), mapping.to_owned());
    let compat = compat.map(CompatSource::from_arg);
    let signals = Signals::new();
    let cross_check = panel(cross_check);
    let run = || -> anyhow::Result<_> {
        let mapping = Mapping::from_path(Path::new(&mapping))?;
        if kind.is_batch() {
            anyhow::bail!(
                "estimator `{0}` is a batch method with no per-sample estimates: use `aeroident.fit(path, mapping, estimator=\"{0}\")` (CLI: `aeroident replay --estimator {0}`)",
                kind.name()
            );
        }
        let options = ReplayOptions {
            estimator: kind,
            estimator_options,
            derivatives,
            diff_window,
            windows,
            ..ReplayOptions::default()
        };
        let records = Records::one(path, mapping);
        let job =
            ReplayJob { records, model: choice, compat, options, cross_check, validate_on: None };
        replay_job(&job, &signals)
    };
    let r = py.detach(run);
    signals.finish(py)?;
    let (model, summary, arrays, notes, toml) = r.map_err(to_py)?;
    let d = arrays_dict(py, arrays)?;
    d.set_item("model", model)?;
    d.set_item("selected_model", toml)?;
    d.set_item("summary", convert::json_to_py(py, &summary)?)?;
    d.set_item("notes", notes)?;
    Ok(d)
}

/// What [`replay_job`] gives Python: the model's name, `summary.json`, the estimate arrays,
/// the reader's notes and the selected model's file text (`--model auto`).
type ReplayResult = (String, serde_json::Value, EstimateArrays, Vec<String>, Option<String>);

/// Runs `job` in place, its estimates collected as arrays and its replay stopped by a
/// signal Python received ([`Interruptible`]); a diverged estimator is an error.
fn replay_job(job: &ReplayJob, signals: &Signals) -> anyhow::Result<ReplayResult> {
    job.check()?;
    let Ran::Done(prepared) = job.prepare(&mut InPlace, &mut ())? else {
        anyhow::bail!("internal: a step run in place was abandoned");
    };
    let (mapping, opts) = (&job.records.mapping, &prepared.options);
    let open = || Record::open(RecordSource::Path(job.records.data.clone()), None, mapping);
    let Record { reader, report, .. } = open()?;
    let notes = report.notes();
    // The steps after the feed read the record again: held in memory, it is read once.
    let screen = opts.spike_screen;
    let (held, reader) = match job.records.holds(screen) {
        true => (ScreenedRecord::read(reader, screen).map(Arc::new), None),
        false => (None, Some(reader)),
    };
    let observer = &mut Interruptible(signals);
    let (mut outcome, arrays) = match (&held, reader) {
        (Some(h), _) => replay_arrays_cached(h, mapping, opts, observer)?,
        (None, Some(r)) => replay_arrays_observed(r, mapping, opts, observer)?,
        // Too long to hold, or unreadable (the replay then says why): from the file.
        (None, None) => replay_arrays_observed(open()?.reader, mapping, opts, observer)?,
    };
    outcome.reader.push(report);
    if let Some(e) = outcome.diverged_error(job.options.estimator.name()) {
        anyhow::bail!(e);
    }
    let prepared = aeroident_pipelines::job::replay::Prepared { held, ..prepared };
    let done = job.finish(prepared, outcome, &mut InPlace, &mut (), String::new)?;
    let toml = done.selection.as_ref().map(|s| s.model.to_toml());
    Ok((done.outcome.model.name.clone(), done.document()?, arrays, notes, toml))
}

/// Column arrays (read-only float64 views) as a per-row [`Source`].
struct RowSource<'a> {
    cols: &'a [(String, &'a [f64])],
    k: usize,
}

impl Source for RowSource<'_> {
    fn get(&self, key: &str) -> PyResult<Option<f64>> {
        Ok(self.cols.iter().find(|c| c.0 == key).map(|c| c.1[self.k]).filter(|v| !v.is_nan()))
    }
}

/// The richest preset (`six-axis`, `longitudinal`, `lateral`) the first sample supports, as the
/// CLI chooses one (no derivative is differentiated for arrays).
fn default_model(first: &AirDataSample, uses_measured: bool) -> PyResult<ModelSpec> {
    let supports = |spec: &ModelSpec| {
        let missing = unsupported(&spec.structure, first, uses_measured, &[]);
        if missing.is_empty() { Ok(()) } else { Err(missing.join("; ")) }
    };
    aeroident_pipelines::record::needs::richest_preset(supports).map_err(|why| {
        err(format!(
            "no preset model is supported by the arrays' channels ({why}); give the missing channels or model="
        ))
    })
}

/// The samples of `arrays` (one float64 array per key of `sample_keys()`, other keys ignored)
/// with the aircraft constants `consts`, row by row, and what `first` makes of their count and
/// first sample before the others are made (the model, once the memory they would take is
/// known to fit: [`arrays_model`]).
///
/// # Errors
/// A required channel missing, an array that is not a contiguous 1-D float64 array, arrays of
/// different lengths or empty, a row the sample refuses (naming the row), `first`'s error.
fn samples_of_arrays<'py, T>(
    arrays: &Bound<'py, PyDict>,
    consts: &aeroident_estimators::AircraftConstants,
    first: impl FnOnce(usize, &AirDataSample) -> PyResult<T>,
) -> PyResult<(Vec<AirDataSample>, T)> {
    let keys = convert::all_keys();
    let mut views: Vec<(String, PyReadonlyArray1<'py, f64>)> = Vec::new();
    for (k, v) in arrays.iter() {
        let k: String = k.extract()?;
        if !keys.contains(&k.as_str()) {
            continue; // row numbers, rejections and the like
        }
        let a: PyReadonlyArray1<'py, f64> = v
            .extract()
            .map_err(|_| err(format!("arrays[`{k}`]: expected a 1-D float64 numpy array")))?;
        views.push((k, a));
    }
    if let Some(r) = REQUIRED.iter().find(|r| !views.iter().any(|v| v.0 == **r)) {
        return Err(err(format!("arrays: required channel `{r}` is missing")));
    }
    let slices: Vec<(String, &[f64])> = views
        .iter()
        .map(|(k, a)| a.as_slice().map(|s| (k.clone(), s)))
        .collect::<Result<_, _>>()
        .map_err(|e| err(format!("arrays: not contiguous: {e}")))?;
    let n = slices[0].1.len();
    if let Some(bad) = slices.iter().find(|s| s.1.len() != n) {
        return Err(err(format!(
            "arrays: `{}` has {} values, `{}` has {n}",
            bad.0,
            bad.1.len(),
            slices[0].0
        )));
    }
    if n == 0 {
        return Err(err("arrays: no samples"));
    }
    let row = |k: usize| {
        let src = RowSource { cols: &slices, k };
        convert::sample_from(&src, consts, &|| format!("arrays row {k}"))
    };
    let made = first(n, &row(0)?)?;
    Ok(((0..n).map(row).collect::<PyResult<_>>()?, made))
}

/// The model of `replay(arrays, model=…)` for `n` samples: the one named, else the richest
/// preset the first sample supports; refused when the arrays cannot form it, or when the
/// samples and their estimates would not fit in memory (the estimate in the message).
fn arrays_model(
    model: Option<&str>,
    kind: EstimatorKind,
    n: usize,
    first: &AirDataSample,
) -> PyResult<ModelSpec> {
    let spec = match model {
        Some(m) => model_spec(m)?,
        None => default_model(first, kind.uses_measured_coefficients())?,
    };
    let missing = unsupported(&spec.structure, first, kind.uses_measured_coefficients(), &[]);
    if !missing.is_empty() {
        return Err(err(format!(
            "model `{}` is not supported by the arrays: {}",
            spec.name,
            missing.join("; ")
        )));
    }
    check_array_size(n, spec.structure.n_params()).map_err(|e| err(format!("arrays: {e}")))?;
    Ok(spec)
}

/// Replays samples given as arrays (one float64 array per key of `sample_keys()`).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(name = "replay_arrays", signature = (arrays, estimator="rls", model=None, constants=None, forgetting=None, sample_interval_s=None, **options))]
fn replay_arrays_py<'py>(
    py: Python<'py>,
    arrays: &Bound<'py, PyDict>,
    estimator: &str,
    model: Option<&str>,
    constants: Option<&Bound<'py, PyDict>>,
    forgetting: Option<f64>,
    sample_interval_s: Option<f64>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = estimator_kind(estimator)?;
    let consts = convert::constants_from(constants)?;
    let (samples, spec) =
        samples_of_arrays(arrays, &consts, |n, first| arrays_model(model, kind, n, first))?;
    let n = samples.len();
    let options = estimator_options(kind, vec![("forgetting", number(forgetting))], options)?;
    let opts = EstimatorOptions { sample_interval_s, ..options };
    let first = samples[0];
    let (spec_structure, spec_priors) = (spec.structure, spec.priors);
    let signals = Signals::new();
    let (result, model_name) = py.detach(|| {
        // Ctrl-C ends the feed; the handler's exception is raised below.
        let feed = samples.into_iter().take_while(|_| !signals.interrupted());
        let r = build(kind, spec.structure, spec.priors, &opts)
            .map(|est| replay_samples(est, feed))
            .map_err(|e| e.to_string());
        (r, spec.name)
    });
    signals.finish(py)?;
    let (arrays, refused, diverged, events) = result.map_err(err)?;
    if let Some(msg) = diverged {
        return Err(err(format!("{msg}; its estimates are not a result")));
    }
    if arrays.t_s.is_empty() {
        // Every sample refused: empty arrays would pass for a result. The first refusal's
        // reason, from a fresh estimator given the first sample.
        let why = build(kind, spec_structure, spec_priors, &opts)
            .ok()
            .and_then(|mut est| est.update(&first).err())
            .map_or_else(String::new, |e| format!(" (the first: {e})"));
        return Err(err(format!(
            "arrays: the estimator accepted none of the {n} samples, {refused} refused{why}"
        )));
    }
    let d = arrays_dict(py, arrays)?;
    d.set_item("model", model_name)?;
    d.set_item("samples_refused", refused)?;
    let events = serde_json::to_value(&events).map_err(|e| err(e.to_string()))?;
    d.set_item("events", crate::convert::json_to_py(py, &events)?)?;
    Ok(d)
}
