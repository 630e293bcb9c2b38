//! The replay as dense arrays (for the Python package's vectorised `replay` and any caller that
//! wants every sample's estimates, not the bounded [`History`](super::History)).
//!
//! [`replay_arrays`] runs exactly the pipeline of [`super::replay`] (reader → derivative stage →
//! estimator from [`crate::estimators::build`] with the same options) and records, for every
//! sample whose estimates the CLI writes as a line of `estimates.csv`, the sample time and each
//! parameter's estimate and σ. It does so by wrapping the built estimator ([`Recorder`]): the
//! replay's own loop, rejections, gaps and divergence handling are untouched, so the arrays
//! equal `estimates.csv` line for line (same `f64`s, no text round trip).
//!
//! [`replay_samples`] is the same estimator driven directly by samples the caller already has
//! (SI, at the CG): no reader, no differentiator, no gaps; each sample goes to
//! [`Estimator::update`] in order, and the same recording rule applies.
//!
//! Layout: `values[k * n + i]` is parameter `i` at recorded sample `k` (row-major, `n` =
//! number of parameters), `NaN` where the estimate (or σ) is not identified (`None` in the
//! summary), so the arrays map onto a `(samples, n)` matrix without copying.

use std::cell::RefCell;
use std::io::Read;
use std::rc::Rc;

use aeroident_estimators::{
    AirDataSample, Estimates, Estimator, EstimatorError, ModelStructure, Status,
};
use aeroident_io::{FlightDataReader, Mapping, ModelSpec};

use super::{ReplayError, ReplayOptions, ReplayOutcome, replay_with};
use crate::estimators::{BuildError, build};

/// Every recorded sample's time, estimates and σ (module doc for the layout).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EstimateArrays {
    /// Parameter names, in the structure's order (`n` of them).
    pub names: Vec<&'static str>,
    /// Sample times, s (one per recorded sample).
    pub t_s: Vec<f64>,
    /// Estimates, row-major `t_s.len() × n`; `NaN` = not identified.
    pub values: Vec<f64>,
    /// σ, row-major `t_s.len() × n`; `NaN` = none reported.
    pub sigmas: Vec<f64>,
}

impl EstimateArrays {
    fn record(&mut self, t_s: f64, e: &Estimates) {
        let n = self.names.len();
        self.t_s.push(t_s);
        self.values.extend((0..n).map(|i| e.value(i).unwrap_or(f64::NAN)));
        self.sigmas.extend((0..n).map(|i| e.sigma(i).unwrap_or(f64::NAN)));
    }
}

/// An estimator that forwards everything to `inner` and appends the estimates after each
/// accepted update (one the replay keeps: `Ok` and not diverged) to a shared
/// [`EstimateArrays`].
pub struct Recorder {
    inner: Box<dyn Estimator>,
    out: Rc<RefCell<EstimateArrays>>,
}

impl Recorder {
    /// Wraps `inner`; the recorded arrays appear in `out` (its names are set here).
    pub fn new(inner: Box<dyn Estimator>, out: Rc<RefCell<EstimateArrays>>) -> Self {
        out.borrow_mut().names = inner.structure().names().collect();
        Self { inner, out }
    }
}

impl Estimator for Recorder {
    fn method(&self) -> &'static str {
        self.inner.method()
    }
    fn structure(&self) -> &ModelStructure {
        self.inner.structure()
    }
    fn update(&mut self, sample: &AirDataSample) -> Result<&Estimates, EstimatorError> {
        self.inner.update(sample)?;
        let e = self.inner.estimates();
        if e.status != Status::Diverged {
            self.out.borrow_mut().record(sample.t_s, e);
        }
        Ok(e)
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
    fn events(&self) -> &aeroident_estimators::EventLog {
        self.inner.events()
    }
    fn new_manoeuvre(&mut self) {
        self.inner.new_manoeuvre();
    }
}

/// [`super::replay`] (no sinks) with every accepted sample's estimates recorded as arrays.
///
/// # Errors
/// As [`super::replay`].
pub fn replay_arrays<R: Read>(
    reader: FlightDataReader<R>,
    mapping: &Mapping,
    opts: &ReplayOptions,
) -> Result<(ReplayOutcome, EstimateArrays), ReplayError> {
    replay_arrays_observed(reader, mapping, opts, &mut ())
}

/// [`replay_arrays`] with `observer` told of the replay as [`super::replay_with`] tells it:
/// a caller's progress, or its way to stop a long replay (an error from the observer ends it).
///
/// # Errors
/// As [`super::replay`]; the observer's error as [`ReplayError::Output`].
pub fn replay_arrays_observed<R: Read>(
    reader: FlightDataReader<R>,
    mapping: &Mapping,
    opts: &ReplayOptions,
    observer: &mut dyn super::ReplayObserver,
) -> Result<(ReplayOutcome, EstimateArrays), ReplayError> {
    recorded(mapping, opts, |make| replay_with(reader, mapping, opts, make, observer))
}

/// [`replay_arrays_observed`] of a record held in memory
/// ([`crate::record::cache::ScreenedRecord`], read with `opts`' spike screen): the same
/// arrays and outcome as from its file.
///
/// # Errors
/// As [`super::replay_cached`]; the observer's error as [`ReplayError::Output`].
pub fn replay_arrays_cached(
    record: &crate::record::cache::ScreenedRecord,
    mapping: &Mapping,
    opts: &ReplayOptions,
    observer: &mut dyn super::ReplayObserver,
) -> Result<(ReplayOutcome, EstimateArrays), ReplayError> {
    recorded(mapping, opts, |make| super::replay_cached_with(record, mapping, opts, make, observer))
}

/// The outcome of `run` given an estimator maker whose estimators record every estimate
/// ([`Recorder`]), with the arrays they recorded.
fn recorded(
    mapping: &Mapping,
    opts: &ReplayOptions,
    run: impl FnOnce(
        &dyn Fn(&ModelSpec) -> Result<Box<dyn Estimator>, BuildError>,
    ) -> Result<ReplayOutcome, ReplayError>,
) -> Result<(ReplayOutcome, EstimateArrays), ReplayError> {
    let out = Rc::new(RefCell::new(EstimateArrays::default()));
    let eo = opts.built_estimator_options(mapping);
    let make = |model: &ModelSpec| -> Result<Box<dyn Estimator>, BuildError> {
        let inner = build(opts.estimator, model.structure, model.priors, &eo)?;
        Ok(Box::new(Recorder::new(inner, Rc::clone(&out))))
    };
    let outcome = run(&make)?;
    let arrays = std::mem::take(&mut *out.borrow_mut());
    Ok((outcome, arrays))
}

/// Most memory, bytes, the dense arrays of a replay of samples may be estimated to need
/// ([`estimated_array_bytes`]): 2 GiB, the limit of a batch fit
/// (`aeroident_estimators::output_error::MAX_FIT_BYTES`), checked before the samples are made.
pub const MAX_ARRAY_BYTES: f64 = 2.0 * (1u64 << 30) as f64;

/// The memory, bytes, of replaying `samples` samples of a structure of `params` parameters into
/// dense arrays: the samples themselves (an [`AirDataSample`] each), the recorded time, estimate
/// and σ of every parameter ([`EstimateArrays`]), and the copy of those the caller makes to hand
/// them on (a numpy matrix).
pub fn estimated_array_bytes(samples: usize, params: usize) -> f64 {
    let sample = std::mem::size_of::<AirDataSample>() as f64;
    let row = 8.0 * (1.0 + 2.0 * params as f64);
    samples as f64 * (sample + 2.0 * row)
}

/// Refuses a replay of `samples` samples into dense arrays of `params` parameters whose
/// estimated memory ([`estimated_array_bytes`]) is over [`MAX_ARRAY_BYTES`], with the estimate:
/// such a replay would abort the process (and a Python interpreter with it) on the allocation.
///
/// # Errors
/// The message, with the sample count, the estimate and the limit.
pub fn check_array_size(samples: usize, params: usize) -> Result<(), String> {
    let bytes = estimated_array_bytes(samples, params);
    if bytes <= MAX_ARRAY_BYTES {
        return Ok(());
    }
    Err(format!(
        "{} samples × {params} parameters: the replay would need about {} MB for the samples and their estimates, more than the limit of {} MB; replay slices of the arrays (each its own call) or the record file with windows",
        aeroident_io::message::short_count(samples),
        (bytes / 1e6).round(),
        (MAX_ARRAY_BYTES / 1e6).round()
    ))
}

/// Drives estimator `est` with `samples` in order (module doc) and records its estimates.
/// Refused samples (input errors) are skipped and counted; a divergence stops the run.
///
/// Returns the arrays, the number of refused samples, the divergence message if any, and the
/// estimator's events ([`Estimator::events`]: restarts, re-anchorings, detected changes).
pub fn replay_samples(
    est: Box<dyn Estimator>,
    samples: impl IntoIterator<Item = AirDataSample>,
) -> (EstimateArrays, usize, Option<String>, aeroident_io::replay_output::EventsSummary) {
    let out = Rc::new(RefCell::new(EstimateArrays::default()));
    let mut rec = Recorder::new(est, Rc::clone(&out));
    let mut refused = 0;
    let mut diverged = None;
    for s in samples {
        let r = rec.update(&s).map(|_| ()).map_err(|e| e.to_string());
        if rec.estimates().status == Status::Diverged {
            let why = r.err().map_or(String::new(), |e| format!(" ({e})"));
            diverged =
                Some(format!("estimator `{}` diverged at t = {} s{why}", rec.method(), s.t_s));
            break;
        }
        if r.is_err() {
            refused += 1;
        }
    }
    let events = aeroident_io::replay_output::EventsSummary::from_log(rec.events());
    drop(rec);
    let arrays = std::mem::take(&mut *out.borrow_mut());
    (arrays, refused, diverged, events)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ten million samples of a 15-parameter structure are refused with the estimate (at least
    /// the bytes of the estimate and σ matrices alone, 2.4 GB) and the limit; a short record
    /// is not.
    #[test]
    fn arrays_past_the_memory_limit_are_refused_with_the_estimate() {
        let matrices = |n: f64, p: f64| n * 2.0 * 8.0 * p;
        assert!(estimated_array_bytes(10_000_000, 15) >= matrices(1e7, 15.0));
        let e = check_array_size(10_000_000, 15).unwrap_err();
        let mb = (estimated_array_bytes(10_000_000, 15) / 1e6).round();
        assert!(
            e.contains("1.000e7 samples")
                && e.contains(&format!("{mb} MB"))
                && e.contains("2147 MB"),
            "{e}"
        );
        assert!(mb > 2400.0, "{mb}");
        assert!(check_array_size(400, 15).is_ok());
        assert!(check_array_size(0, 15).is_ok());
    }
    use crate::estimators::EstimatorKind;
    use aeroident_estimators::AircraftConstants;

    /// A pitch record generated from known derivatives: `Cm = Cm0 + Cm_alpha α + Cm_q q c/2V +
    /// Cm_de δe` exactly (no noise), so least squares recovers them; the dense arrays must end
    /// at the true values and every recorded row must match the bounded history's last point.
    fn samples() -> Vec<AirDataSample> {
        let c = AircraftConstants {
            mass_kg: 7000.0,
            S_m2: 30.0,
            cbar_m: Some(3.0),
            b_m: Some(10.0),
            Ixx_kgm2: Some(1.0e4),
            Iyy_kgm2: Some(5.0e4),
            Izz_kgm2: Some(6.0e4),
            Ixz_kgm2: Some(0.0),
            ..AircraftConstants::default()
        };
        (0..400)
            .map(|k| {
                let t = 0.02 * k as f64;
                let alpha = 0.05 + 0.02 * (1.3 * t).sin();
                let q = 0.03 * (2.1 * t).cos();
                let de = -0.02 + 0.01 * (3.7 * t).sin();
                let vt = 100.0;
                let qbar = 0.5 * 1.0 * vt * vt;
                let cm = 0.02 - 0.6 * alpha - 12.0 * q * 3.0 / (2.0 * vt) - 1.1 * de;
                let qdot = cm * qbar * 30.0 * 3.0 / 5.0e4;
                let cl = 0.1 + 5.0 * alpha;
                let cd = 0.03 + 0.4 * alpha;
                // Body-axis specific force from CL, CD (no thrust): X = -CD cos α + CL sin α …
                let (sa, ca) = alpha.sin_cos();
                let ax = qbar * 30.0 * (-cd * ca + cl * sa) / 7000.0;
                let az = qbar * 30.0 * (-cd * sa - cl * ca) / 7000.0;
                AirDataSample {
                    t_s: t,
                    vt_mps: vt,
                    alpha_rad: alpha,
                    qbar_pa: qbar,
                    q_rad_s: Some(q),
                    qdot_rad_s2: Some(qdot),
                    ax_mps2: Some(ax),
                    az_mps2: Some(az),
                    de_rad: Some(de),
                    constants: c,
                    ..AirDataSample::default()
                }
            })
            .collect()
    }

    #[test]
    fn replay_samples_records_every_accepted_sample_and_recovers_the_truth() {
        let spec = ModelSpec::preset("longitudinal").expect("preset");
        let est = build(
            EstimatorKind::Rls,
            spec.structure,
            spec.priors,
            &crate::estimators::EstimatorOptions::default(),
        )
        .expect("rls");
        let (a, refused, diverged, _) = replay_samples(est, samples());
        assert_eq!((refused, diverged), (0, None));
        let n = a.names.len();
        assert_eq!(a.t_s.len(), 400);
        assert_eq!(a.values.len(), 400 * n);
        let last = &a.values[399 * n..];
        let get = |name: &str| last[a.names.iter().position(|x| *x == name).expect(name)];
        assert!((get("Cm_alpha") + 0.6).abs() < 1e-8, "Cm_alpha {}", get("Cm_alpha"));
        assert!((get("Cm_de") + 1.1).abs() < 1e-8, "Cm_de {}", get("Cm_de"));
        assert!((get("CL_alpha") - 5.0).abs() < 1e-8, "CL_alpha {}", get("CL_alpha"));
    }
}
