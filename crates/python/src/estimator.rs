//! `aeroident.Estimator` (and the per-method subclasses in the Python package): one online
//! estimator from the factory (`crates/registry/src/estimators.rs`), fed one sample dict at a
//! time.
//!
//! The object may be used from any Python thread (a thread pool, a callback thread): its state
//! is behind a mutex, each method holding it only for its own call, so updates from several
//! threads are applied one at a time, whole, in the order they take it.

use std::sync::{Mutex, MutexGuard};

use aeroident_estimators::{AircraftConstants, Status};
use aeroident_pipelines::estimators::{EstimatorKind, EstimatorOptions, build};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{self, DictSource};
use crate::err;
use crate::record::{estimator_kind, estimator_options, model_spec, number};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Estimator>()?;
    Ok(())
}

/// An online estimator (see the Python package's `Estimator` docstring).
#[pyclass(subclass, module = "aeroident", name = "EstimatorBase")]
pub struct Estimator {
    state: Mutex<State>,
    kind: EstimatorKind,
    model: String,
    constants: AircraftConstants,
}

/// What an update changes: the estimator and its count of accepted samples.
struct State {
    est: Box<dyn aeroident_estimators::Estimator + Send>,
    samples: usize,
}

impl Estimator {
    /// Why parameter's estimate (`value`) or σ (`sigma`) is absent, `None` when neither is.
    fn reason(
        &self,
        value: Option<f64>,
        sigma: Option<f64>,
        status: Status,
        samples: usize,
    ) -> Option<String> {
        match (value, sigma) {
            (Some(_), Some(_)) => None,
            (None, _) if status == Status::Diverged => {
                Some("not identified: the estimator diverged".into())
            }
            (None, _) => Some(format!(
                "not identified: the samples so far ({samples}) do not determine it (estimator {})",
                status.name()
            )),
            (Some(_), None) => {
                Some(format!("no standard error: `{}` reports none for it", self.kind.name()))
            }
        }
    }

    /// The state, for one method call. A panic while it was held (a bug) leaves it poisoned:
    /// the estimator is then refused rather than used half-updated.
    fn state(&self) -> PyResult<MutexGuard<'_, State>> {
        self.state.lock().map_err(|_| {
            err(format!(
                "estimator `{}`: an earlier call failed inside the library; make a new estimator",
                self.kind.name()
            ))
        })
    }
}

#[pymethods]
impl Estimator {
    // The estimator options (`forgetting` … `reaching_rate_per_s`) default to `None`, "not
    // given": the given ones are parsed by the estimator registry, which refuses one the kind
    // does not take, and the others keep the estimator's defaults.
    #[new]
    #[pyo3(signature = (kind, model="longitudinal", constants=None, forgetting=None, sample_interval_s=None, parameter_walk_per_sqrt_s=None, ftr_grid_hz=None, sliding_gain_per_s=None, reaching_rate_per_s=None, **options))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        kind: &str,
        model: &str,
        constants: Option<&Bound<'_, PyDict>>,
        forgetting: Option<f64>,
        sample_interval_s: Option<f64>,
        parameter_walk_per_sqrt_s: Option<f64>,
        ftr_grid_hz: Option<(f64, f64, f64)>,
        sliding_gain_per_s: Option<f64>,
        reaching_rate_per_s: Option<f64>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let k = estimator_kind(kind)?;
        let grid =
            ftr_grid_hz.map(|(a, b, c)| toml::Value::Array(vec![a.into(), b.into(), c.into()]));
        let given = vec![
            ("forgetting", number(forgetting)),
            ("parameter_walk_per_sqrt_s", number(parameter_walk_per_sqrt_s)),
            ("grid_hz", grid),
            ("sliding_gain_per_s", number(sliding_gain_per_s)),
            ("reaching_rate_per_s", number(reaching_rate_per_s)),
        ];
        let options = estimator_options(k, given, options)?;
        let spec = model_spec(model)?;
        let constants = convert::constants_from(constants)?;
        let opts = EstimatorOptions { sample_interval_s, ..options };
        let est = build(k, spec.structure, spec.priors, &opts).map_err(|e| err(e.to_string()))?;
        Ok(Self {
            state: Mutex::new(State { est, samples: 0 }),
            kind: k,
            model: spec.name,
            constants,
        })
    }

    /// The method's name (str: ``rls``, ``rls-iv``, ``ftr``, ``ekf`` …).
    #[getter]
    fn method(&self) -> &'static str {
        self.kind.name()
    }

    /// The model's name (str: a preset or a model file's path).
    #[getter]
    fn model(&self) -> &str {
        &self.model
    }

    /// The ``n`` parameter names (list of str), the order of every estimate array.
    #[getter]
    fn names(&self) -> PyResult<Vec<&'static str>> {
        Ok(self.state()?.est.structure().names().collect())
    }

    /// The samples accepted so far (int).
    #[getter]
    fn samples(&self) -> PyResult<usize> {
        Ok(self.state()?.samples)
    }

    /// ``update(sample)``: consumes one sample, a dict of SI channels and constants by the
    /// keys of ``sample_keys()`` (a number each; ``None`` or NaN: absent).
    ///
    /// Raises ``AeroidentError`` naming a missing required channel or constant, a value that
    /// is not a number, a constant out of its physical range, a sample the estimator refuses
    /// (its state is then unchanged) or a divergence.
    fn update(&self, sample: &Bound<'_, PyDict>) -> PyResult<()> {
        // The sample is converted first (it may run Python code: a number's `__float__`), and
        // the state taken after, so no Python code runs while it is held.
        let n = self.state()?.samples;
        let what = || format!("sample {n}");
        let s = convert::sample_from(&DictSource(sample), &self.constants, &what)?;
        let mut st = self.state()?;
        let r = st.est.update(&s).map(|_| ());
        match r {
            Ok(_) => {
                st.samples += 1;
                Ok(())
            }
            Err(e) if st.est.estimates().status == Status::Diverged => Err(err(format!(
                "estimator `{}` diverged at t = {} s ({e})",
                self.kind.name(),
                s.t_s
            ))),
            Err(e) => Err(err(format!("estimator refused sample: {e}"))),
        }
    }

    /// ``estimates()``: the current estimates as a dict: ``names`` (list of ``n`` str),
    /// ``estimate`` ``(n,)`` float64 (NaN: not identified), ``std_error`` ``(n,)`` float64
    /// (NaN: none reported), ``reasons`` (dict: for each parameter with a NaN, why),
    /// ``estimator_status`` (``initialising``, ``running``, ``diverged``) and ``samples`` (int).
    /// The keys are those of ``summary.json``. Units: each parameter's own (per rad, or per
    /// unit non-dimensional rate; dimensionless coefficients).
    fn estimates<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (names, values, sigma, status, samples) = {
            let st = self.state()?;
            let (e, structure) = (st.est.estimates(), st.est.structure());
            let n = structure.n_params();
            let names: Vec<&'static str> = structure.names().collect();
            let values: Vec<Option<f64>> = (0..n).map(|i| e.value(i)).collect();
            let sigma: Vec<Option<f64>> = (0..n).map(|i| e.sigma(i)).collect();
            (names, values, sigma, e.status, st.samples)
        };
        let reasons = PyDict::new(py);
        for (i, name) in names.iter().enumerate() {
            if let Some(why) = self.reason(values[i], sigma[i], status, samples) {
                reasons.set_item(*name, why)?;
            }
        }
        let nan =
            |v: &[Option<f64>]| -> Vec<f64> { v.iter().map(|x| x.unwrap_or(f64::NAN)).collect() };
        let d = PyDict::new(py);
        d.set_item("names", names)?;
        d.set_item("estimate", nan(&values).into_pyarray(py))?;
        d.set_item("std_error", nan(&sigma).into_pyarray(py))?;
        d.set_item("reasons", reasons)?;
        d.set_item("estimator_status", status.name())?;
        d.set_item("samples", samples)?;
        Ok(d)
    }

    /// ``covariance(i, j)``: the covariance of parameters ``i`` and ``j`` (float, the
    /// parameters' units multiplied), ``None`` where the method gives none.
    ///
    /// Raises ``IndexError`` for an index past the parameters.
    fn covariance(&self, i: usize, j: usize) -> PyResult<Option<f64>> {
        let st = self.state()?;
        let n = st.est.structure().n_params();
        if i >= n || j >= n {
            return Err(pyo3::exceptions::PyIndexError::new_err(format!(
                "covariance({i}, {j}): the model has {n} parameters (indices 0 to {})",
                n.saturating_sub(1)
            )));
        }
        Ok(st.est.covariance(i, j))
    }

    /// ``covariance_matrix()``: the parameters' covariance, ``(n, n)`` float64 in ``names``
    /// order; NaN where the method gives none (a sliding-mode estimator, a parameter not yet
    /// identified).
    fn covariance_matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let st = self.state()?;
        let n = st.est.structure().n_params();
        let c = |i: usize, j: usize| st.est.covariance(i, j).unwrap_or(f64::NAN);
        Ok(Array2::from_shape_fn((n, n), |(i, j)| c(i, j)).into_pyarray(py))
    }

    /// ``nis()``: the mean normalised innovation squared (float, dimensionless), ``None`` for
    /// a method without innovations.
    fn nis(&self) -> PyResult<Option<f64>> {
        Ok(self.state()?.est.nis())
    }

    /// ``events()``: what the estimator did to itself so far: dict with `listed` (`[{t_s, kind, subject}]`,
    /// kind `restart`, `reanchor` or `change_detected`), `counts` (per kind) and `not_listed`,
    /// as in the replay summary's `events`.
    fn events<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let s = aeroident_io::replay_output::EventsSummary::from_log(self.state()?.est.events());
        let v = serde_json::to_value(&s).map_err(|e| err(e.to_string()))?;
        crate::convert::json_to_py(py, &v)
    }

    /// ``new_manoeuvre()``: a new manoeuvre starts with the next sample (the model's states
    /// are re-initialised from it; the estimates are kept).
    fn new_manoeuvre(&self) -> PyResult<()> {
        self.state()?.est.new_manoeuvre();
        Ok(())
    }

    fn __repr__(&self) -> PyResult<String> {
        let st = self.state()?;
        Ok(format!(
            "<aeroident estimator {} on {} ({} parameters), {} samples>",
            self.kind.name(),
            self.model,
            st.est.structure().n_params(),
            st.samples
        ))
    }
}
