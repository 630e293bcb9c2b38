//! `aeroident.Estimator` (and the per-method subclasses in the Python package): one online
//! estimator from the factory (`crates/pipelines/src/estimators.rs`), fed one sample dict at a
//! time.

use aeroident_estimators::{AircraftConstants, Status};
use aeroident_pipelines::estimators::{EstimatorKind, EstimatorOptions, build};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{self, DictSource};
use crate::err;
use crate::record::{estimator_kind, model_spec};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Estimator>()?;
    Ok(())
}

/// An online estimator (see the Python package's `Estimator` docstring).
#[pyclass(unsendable, subclass, module = "aeroident", name = "EstimatorBase")]
pub struct Estimator {
    est: Box<dyn aeroident_estimators::Estimator>,
    kind: EstimatorKind,
    model: String,
    constants: AircraftConstants,
    samples: usize,
}

#[pymethods]
impl Estimator {
    #[new]
    #[pyo3(signature = (kind, model="longitudinal", constants=None, forgetting=1.0, sample_interval_s=None, parameter_walk_per_sqrt_s=0.0, ftr_grid_hz=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        kind: &str,
        model: &str,
        constants: Option<&Bound<'_, PyDict>>,
        forgetting: f64,
        sample_interval_s: Option<f64>,
        parameter_walk_per_sqrt_s: f64,
        ftr_grid_hz: Option<(f64, f64, f64)>,
    ) -> PyResult<Self> {
        let k = estimator_kind(kind)?;
        let spec = model_spec(model)?;
        let constants = convert::constants_from(constants)?;
        let opts = EstimatorOptions {
            forgetting,
            instrument_delay: None,
            sample_interval_s,
            parameter_walk_per_sqrt_s,
            ftr_grid_hz,
        };
        let est = build(k, spec.structure, spec.priors, &opts).map_err(|e| err(e.to_string()))?;
        Ok(Self { est, kind: k, model: spec.name, constants, samples: 0 })
    }

    /// The method's name (`rls`, `rls-iv`, `ftr`, `ekf` …).
    #[getter]
    fn method(&self) -> &'static str {
        self.kind.name()
    }

    /// The model's name (preset or file path).
    #[getter]
    fn model(&self) -> &str {
        &self.model
    }

    /// Parameter names, in order.
    #[getter]
    fn names(&self) -> Vec<&'static str> {
        self.est.structure().names().collect()
    }

    /// Samples accepted so far.
    #[getter]
    fn samples(&self) -> usize {
        self.samples
    }

    /// Consumes one sample (a dict of SI channels; see `sample_keys()`).
    fn update(&mut self, sample: &Bound<'_, PyDict>) -> PyResult<()> {
        let n = self.samples;
        let s =
            convert::sample_from(&DictSource(sample), &self.constants, &|| format!("sample {n}"))?;
        let r = self.est.update(&s).map(|_| ());
        match r {
            Ok(_) => {
                self.samples += 1;
                Ok(())
            }
            Err(e) if self.est.estimates().status == Status::Diverged => Err(err(format!(
                "estimator `{}` diverged at t = {} s ({e})",
                self.kind.name(),
                s.t_s
            ))),
            Err(e) => Err(err(format!("estimator refused sample: {e}"))),
        }
    }

    /// The current estimates: dict with `names`, `values` (None = not identified), `sigma`
    /// (None = none reported) and `status`.
    fn estimates<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let e = self.est.estimates();
        let n = self.est.structure().n_params();
        let d = PyDict::new(py);
        d.set_item("names", self.names())?;
        d.set_item("values", (0..n).map(|i| e.value(i)).collect::<Vec<_>>())?;
        d.set_item("sigma", (0..n).map(|i| e.sigma(i)).collect::<Vec<_>>())?;
        d.set_item("status", e.status.name())?;
        Ok(d)
    }

    /// Covariance of parameters `i` and `j` (None where the method gives none).
    fn covariance(&self, i: usize, j: usize) -> Option<f64> {
        self.est.covariance(i, j)
    }

    /// Mean normalised innovation squared (None for methods without innovations).
    fn nis(&self) -> Option<f64> {
        self.est.nis()
    }

    /// What the estimator did to itself so far: dict with `listed` (`[{t_s, kind, subject}]`,
    /// kind `restart`, `reanchor` or `change_detected`), `counts` (per kind) and `not_listed`,
    /// as in the replay summary's `events`.
    fn events<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let s = aeroident_io::replay_output::EventsSummary::from_log(self.est.events());
        let v = serde_json::to_value(&s).map_err(|e| err(e.to_string()))?;
        crate::convert::json_to_py(py, &v)
    }

    /// A new manoeuvre starts with the next sample (model states re-initialised).
    fn new_manoeuvre(&mut self) {
        self.est.new_manoeuvre();
    }

    fn __repr__(&self) -> String {
        format!(
            "<aeroident estimator {} on {} ({} parameters), {} samples>",
            self.kind.name(),
            self.model,
            self.est.structure().n_params(),
            self.samples
        )
    }
}
