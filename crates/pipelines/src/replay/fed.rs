//! The samples a replay feeds its estimator, in order, with the manoeuvre each belongs to:
//! what the record stage and the conditioning stage make of a log's rows (mapping and units,
//! the spike screen, the compatibility corrections, the causal differentiator's `ṗ q̇ ṙ α̇` and
//! the delay of the other channels to match, `V0`). A caller that feeds an estimator itself (the
//! C library's, `examples/c/replay_samples.c`) takes these to be fed exactly what
//! `aeroident replay` feeds.

use super::{ReplayError, ReplayOptions, ReplayOutcome, replay_with};
use crate::estimators::build;
use aeroident_estimators::{
    AirDataSample, Estimates, Estimator, EstimatorError, EventLog, ModelStructure,
};
use aeroident_io::Mapping;
use std::cell::RefCell;
use std::rc::Rc;

/// One sample an estimator was given, and the manoeuvre it belongs to (numbered from 0; the
/// replay starts a new one at each gap in the record, [`Estimator::new_manoeuvre`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FedSample {
    /// Manoeuvre number.
    pub manoeuvre: u32,
    /// The sample, as the estimator's `update` received it.
    pub sample: AirDataSample,
}

/// Passes every call to the estimator the replay built and records what it is fed.
struct Recorder {
    inner: Box<dyn Estimator + Send>,
    log: Rc<RefCell<Vec<FedSample>>>,
    manoeuvre: u32,
}

impl Estimator for Recorder {
    fn method(&self) -> &'static str {
        self.inner.method()
    }

    fn structure(&self) -> &ModelStructure {
        self.inner.structure()
    }

    fn update(&mut self, sample: &AirDataSample) -> Result<&Estimates, EstimatorError> {
        self.log.borrow_mut().push(FedSample { manoeuvre: self.manoeuvre, sample: *sample });
        self.inner.update(sample)
    }

    fn estimates(&self) -> &Estimates {
        self.inner.estimates()
    }

    fn covariance(&self, i: usize, j: usize) -> Option<f64> {
        self.inner.covariance(i, j)
    }

    fn nis(&self) -> Option<f64> {
        self.inner.nis()
    }

    fn events(&self) -> &EventLog {
        self.inner.events()
    }

    fn new_manoeuvre(&mut self) {
        self.manoeuvre += 1;
        self.inner.new_manoeuvre();
    }
}

/// Replays `reader` through `mapping` with `opts`, as [`super::replay`] (what `aeroident
/// replay` runs: the same stages, the same estimator built by the same registry with the same
/// options), and returns the samples its estimator was given, in order, with the replay's
/// outcome.
///
/// # Errors
/// As [`super::replay`].
pub fn fed_samples<R: std::io::Read>(
    reader: aeroident_io::FlightDataReader<R>,
    mapping: &Mapping,
    opts: &ReplayOptions,
) -> Result<(Vec<FedSample>, ReplayOutcome), ReplayError> {
    let log = Rc::new(RefCell::new(Vec::new()));
    let built = opts.built_estimator_options(mapping);
    let make = |model: &aeroident_io::ModelSpec| {
        let inner = build(opts.estimator, model.structure, model.priors, &built)?;
        Ok(Box::new(Recorder { inner, log: Rc::clone(&log), manoeuvre: 0 }) as Box<dyn Estimator>)
    };
    let outcome = replay_with(reader, mapping, opts, make, &mut ())?;
    let samples = log.borrow().clone();
    Ok((samples, outcome))
}
