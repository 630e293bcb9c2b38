//! Batch output-error estimation of a whole record (`aeroident replay --estimator oe`): the
//! post-flight reference a flight-test engineer compares the real-time estimators to; and the
//! filter-error method (`--estimator fem`: output error with process noise on the air-data
//! states, [`aeroident_estimators::output_error::filter_error`]), whose reported σ is its
//! coloured-residual σ where formed, else its Cramér–Rao σ ([`fem_reported_sigma`]), and whose
//! validation simulates the model with its estimates (no filter).
//!
//! Unlike the other estimators this is not causal: it reads the whole record first (and says
//! so), splits it into manoeuvres at the reader's gap events, and runs
//! [`aeroident_estimators::output_error::fit`] (ML output error: Gauss–Newton with exact
//! sensitivities, the noise covariance estimated with the parameters, Cramér–Rao and
//! coloured-residual σ; Jategaonkar 2015 ch. 4, Klein & Morelli 2006 ch. 6).
//!
//! The model is the one given, else the richest preset whose flight model the record's first
//! sample can drive ([`FlightModel::inputs`]). The reported `std_error` is the
//! coloured-residual σ where the correction exists (real residuals are coloured and the
//! Cramér–Rao σ is then optimistic), the Cramér–Rao σ otherwise; both are in the summary.

use super::ReplayError;
use super::diagnostics::{self, Identifiability};
use super::prediction::{Recorder, ValidationReport, validate_coefficients};
use super::repeatability::{Repeatability, SoloFit};
use crate::estimators::EstimatorKind;
use crate::record::Manoeuvres;
pub use crate::results::OutputTrace;
use crate::validation::{OutputData, validate};
use crate::verdict::Evidence;
use aeroident_estimators::Term;
use aeroident_estimators::flight_model::FlightModel;
use aeroident_estimators::flight_model::{N_STATES, STATE_NAMES, state};
use aeroident_estimators::output_error::filter_error::{self, FemConfig, FemResult};
use aeroident_estimators::output_error::{InitialStates, Start, StepKind};
use aeroident_estimators::output_error::{
    OeConfig, OeError, OeResult, StopFlag, Termination, fit, fit_to_end,
};
use aeroident_estimators::{AirDataSample, ModelStructure, Param};
use aeroident_io::parameter::STATUS_NOT_CONVERGED;
use aeroident_io::warning::{Warning, WarningKind};
use aeroident_io::{
    FlightDataReader, Mapping, ModelSpec, ParameterResult, Rejection, StdErrorSource,
};
use serde::Serialize;
use std::io::Read;

/// The outcome of a batch fit.
#[derive(Debug, Clone)]
pub struct BatchOutcome {
    /// The model fitted (and whether it was the default choice).
    pub model: ModelSpec,
    /// The fit.
    pub result: OeResult,
    /// The summary document.
    pub summary: BatchSummary,
    /// Per output, the measured and the simulated time history (for the model-vs-measured
    /// figure of the report).
    pub traces: Vec<OutputTrace>,
    /// `fdoe`: the frequency-domain fit itself (`result` is then the time-domain simulation
    /// at its estimates, with its σ and iteration log); `None` for `oe`, `fem`.
    pub frequency: Option<aeroident_estimators::output_error::frequency::FdoeResult>,
    /// The options the fit ran with (its corrections, windows and screen), for the steps
    /// after it that fit the records again.
    pub options: FitOptions,
}

/// The [`OutputTrace`]s of `result` over `manoeuvres` (outputs not measured in every sample,
/// or residuals that do not match the samples, are left out).
pub(super) fn output_traces(
    result: &OeResult,
    manoeuvres: &[&[AirDataSample]],
) -> Vec<OutputTrace> {
    let ny = result.outputs.len();
    let total: usize = manoeuvres.iter().map(|m| m.len()).sum();
    if result.residuals.len() != total * ny {
        return Vec::new();
    }
    let stride = total.div_ceil(OutputTrace::MAX_POINTS).max(1);
    let mut out = Vec::new();
    'outputs: for (j, o) in result.outputs.iter().enumerate() {
        let mut tr = OutputTrace {
            name: o.name().to_string(),
            t_s: Vec::new(),
            measured: Vec::new(),
            simulated: Vec::new(),
            stride,
        };
        let mut k = 0;
        for (mi, m) in manoeuvres.iter().enumerate() {
            if mi > 0 {
                tr.t_s.push(f64::NAN);
                tr.measured.push(f64::NAN);
                tr.simulated.push(f64::NAN);
            }
            for (i, s) in m.iter().enumerate() {
                let Some(z) = o.measured(s) else { continue 'outputs };
                if i % stride == 0 {
                    tr.t_s.push(s.t_s);
                    tr.measured.push(z);
                    tr.simulated.push(z - result.residuals[k * ny + j]);
                }
                k += 1;
            }
        }
        out.push(tr);
    }
    out
}

/// One parameter of the batch summary: the common keys ([`ParameterResult`]) and the σ of
/// each source, in one `summary.json` object.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchParameter {
    /// Name; estimate (`null` for a parameter the method does not estimate — `fdoe`: those
    /// its linear model cannot see, [`aeroident_estimators::output_error::frequency`]); the
    /// reported σ (`std_error`: the bootstrap σ when asked for (`--bootstrap`), else the
    /// coloured-residual σ where available, else Cramér–Rao; the console table, `report.html`
    /// and their ±2σ status use it) and its source; the Cramér–Rao σ (`sqrt(diag M⁻¹)`,
    /// `crb_std_error`); the model file's reference; status and flags.
    #[serde(flatten)]
    pub result: ParameterResult,
    /// Coloured-residual σ (the spectral form), when the correction is positive.
    pub coloured_std_error: Option<f64>,
    /// Diagnostic: the prewhitened (vector-autoregression) coloured-residual σ
    /// ([`OeResult::sigma_coloured_prewhitened`]), when positive; a large disagreement with
    /// `coloured_std_error` says the residual spectrum is poorly estimated (docs/uncertainty.md,
    /// "Output error: the spectral coloured-residual σ").
    pub prewhitened_std_error: Option<f64>,
    /// The parametric bootstrap σ (`--bootstrap N`, `oe`), else `null`.
    pub bootstrap_std_error: Option<f64>,
    /// The parametric bootstrap's bias estimate (the refits' mean less `estimate`; its sampling
    /// error is `bootstrap_std_error/√replicas`), else `null`. Not subtracted from `estimate`.
    pub bootstrap_bias: Option<f64>,
}

impl BatchParameter {
    /// The row of a parameter the fit held out (no estimate, no σ of any source), `why` its
    /// flag.
    fn held(name: &str, why: &str) -> Self {
        Self {
            result: ParameterResult::new(name.to_string(), None, None, None, None)
                .with_flags([why.to_string()]),
            coloured_std_error: None,
            prewhitened_std_error: None,
            bootstrap_std_error: None,
            bootstrap_bias: None,
        }
    }
}

impl std::ops::Deref for BatchParameter {
    type Target = ParameterResult;

    fn deref(&self) -> &ParameterResult {
        &self.result
    }
}

/// The share of an output's innovation variance below which `fem`'s measurement-noise variance
/// has collapsed ([`BatchSummary::collapsed_noise`]). In a filter that is not degenerate the
/// noise is a sizeable part of the innovation (0.2 to 3.5 on the HFB-320 and ATTAS records);
/// a thousandth means the filter follows the output as if it were exact.
pub const COLLAPSED_NOISE_SHARE: f64 = 1e-3;

impl BatchSummary {
    /// Puts back, as `not identified` rows, the parameters `held` that the fit left out of
    /// `full` (a term reading a constant channel, [`super::constant::without_constant_terms`]):
    /// every parameter of `full` then has its row, in `full`'s order, each held one flagged with
    /// its reason (kept by [`Self::judge`]).
    pub fn insert_held(&mut self, full: &ModelStructure, held: &[(Param, String)]) {
        if held.is_empty() {
            return;
        }
        let mut fitted = std::mem::take(&mut self.parameters).into_iter();
        for p in full.params() {
            if let Some((_, why)) = held.iter().find(|(q, _)| *q == p) {
                self.parameters.push(BatchParameter::held(p.name(), why));
            } else if let Some(row) = fitted.next() {
                self.parameters.push(row);
            }
        }
        self.parameters.extend(fitted);
    }

    /// Sets every parameter's reference (the `model` file's, compared beside the verdict),
    /// flags, notes and status through the one judge ([`crate::verdict`]): the warnings about
    /// it, the plausibility check (the drag terms withdrawn unless `thrust_mapped`), a
    /// collapsed `fem` noise variance ([`BatchSummary::collapsed_noise`]); a value that does
    /// not repeat across manoeuvres as a note ([`super::repeatability`]); `not identified`
    /// with the reason for a parameter the method does not estimate; `not converged` for every
    /// parameter of a fit that ended at its iteration limit with its last step still above
    /// 1 σ ([`BatchSummary::still_moving`]).
    pub fn judge(&mut self, model: &ModelSpec, thrust_mapped: bool) {
        let moving = self.still_moving();
        let degenerate = self.collapsed_noise();
        if let Some(text) =
            degenerate.as_ref().filter(|t| !self.warnings.iter().any(|w| w.text == **t))
        {
            self.warnings.push(Warning::new(WarningKind::Consistency, text.clone()));
        }
        for p in &mut self.parameters {
            let r = &mut p.result;
            r.set_reference(model.reference(&r.name));
            // A row the fit held out keeps the reason it was given (Self::insert_held).
            let held = if r.estimate.is_none() { std::mem::take(&mut r.flags) } else { Vec::new() };
            r.flags = held;
            let mut doubts = self.warnings.about(&r.name);
            if r.estimate.is_none() && r.flags.is_empty() && doubts.is_empty() {
                doubts.push(format!(
                    "not estimated: {} cannot see it from the record's outputs",
                    self.estimator
                ));
            }
            let repeat = self.repeatability.as_ref().and_then(|rep| rep.failed(&r.name));
            r.combines = crate::verdict::combinations(&r.name, &self.correlations);
            let evidence = Evidence {
                doubts,
                plausibility: Some((model, thrust_mapped)),
                estimate_doubts: degenerate.iter().cloned().collect(),
                failure: moving.then_some(STATUS_NOT_CONVERGED),
                notes: repeat
                    .map(super::repeatability::Repeat::note)
                    .into_iter()
                    .chain(crate::verdict::combination_notes(&r.name, &self.correlations))
                    .collect(),
            };
            crate::verdict::judge(r, &evidence);
        }
    }

    /// `fem`: the warning of a measurement-noise variance that collapsed, below
    /// [`COLLAPSED_NOISE_SHARE`] of its output's innovation variance (the filter then takes
    /// that output as exact and follows it: its estimates and σ are those of a degenerate
    /// filter); `None` for `oe`, `fdoe` and a healthy filter.
    pub fn collapsed_noise(&self) -> Option<String> {
        let collapsed: Vec<String> = self
            .measurement_noise_var
            .iter()
            .filter_map(|(name, var)| {
                let (_, rms) = self.residual_rms.iter().find(|(n, _)| n == name)?;
                (*var < COLLAPSED_NOISE_SHARE * rms * rms)
                    .then(|| format!("{name} {var:.1e} against {:.1e}", rms * rms))
            })
            .collect();
        (!collapsed.is_empty()).then(|| {
            format!(
                "degenerate filter: the measurement-noise variance of {} collapsed below {:.0e} of the innovation variance: the filter takes that output as exact, so its estimates and σ are not a filter-error result (compare with oe)",
                collapsed.join(", "),
                COLLAPSED_NOISE_SHARE
            )
        })
    }

    /// Whether the fit ended unconverged with its last iteration still moving some estimate
    /// by more than its Cramér–Rao σ: only then are the estimates not yet the fit's (an
    /// iteration limit reached with steps below σ leaves numbers more iterations would not
    /// change beyond their σ).
    pub fn still_moving(&self) -> bool {
        self.status == "not_converged"
            && self.iterations.last().is_some_and(|it| it.max_step_sigma > 1.0)
    }
}

/// One iteration of the batch summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchIteration {
    /// Iteration (0 = start).
    pub iteration: usize,
    /// `ln det R` after it.
    pub ln_det_r: f64,
    /// Largest step in Cramér–Rao σ.
    pub max_step_sigma: f64,
}

impl From<&aeroident_estimators::output_error::OeIteration> for BatchIteration {
    fn from(it: &aeroident_estimators::output_error::OeIteration) -> Self {
        BatchIteration {
            iteration: it.iteration,
            ln_det_r: it.ln_det_r,
            max_step_sigma: it.max_step_sigma,
        }
    }
}

/// The frequency-domain part of an `fdoe` summary (`summary.json` `frequency_domain`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrequencyDomainSummary {
    /// The band asked for (`--band-hz`), Hz.
    pub band_hz: (f64, f64),
    /// The band actually fitted: the lowest and highest frequency of any manoeuvre, Hz (inside
    /// `band_hz`, and below each manoeuvre's Nyquist frequency).
    pub band_fitted_hz: (f64, f64),
    /// Frequencies fitted per manoeuvre: count, lowest and highest, Hz.
    pub frequencies: Vec<(usize, f64, f64)>,
    /// The linear model's states (sample field names).
    pub states: Vec<String>,
    /// Its measured inputs (model-input names: `de_rad`, `thrust_n`, `vt_mps` …).
    pub inputs: Vec<String>,
    /// Outputs fitted.
    pub outputs: Vec<String>,
    /// Per output, the residual spectral variance `S_jj` (output unit² · samples², the
    /// transform being the plain sum `Σ x_i z^{−i}`).
    pub residual_spectral_variance: Vec<(String, f64)>,
    /// Per manoeuvre, the linearisation's mean airspeed (m/s) and dynamic pressure (Pa).
    pub flight_conditions: Vec<(f64, f64)>,
    /// The parameters not estimated (reported `null`), held at their equation-error values.
    pub not_estimated: Vec<String>,
}

/// `summary.json` of a batch fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchSummary {
    /// The key set's version, [`aeroident_io::SCHEMA_VERSION`].
    pub schema_version: u32,
    /// `oe`, `fem` or `fdoe`.
    pub estimator: String,
    /// The model's name.
    pub model: String,
    /// The model's α knots of its spline terms, rad (absent when it has none): the JSBSim
    /// export forms the splines from them.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub alpha_knots_rad: Vec<f64>,
    /// How the fit ended: `converged` (both criteria), `converged_in_cost` (the cost stopped
    /// changing, the step did not become negligible) or `not_converged` (the last iterate).
    pub status: String,
    /// Why the fit is not `converged`: how it ended and the last iteration's measures; `null`
    /// for a converged fit.
    pub status_reason: Option<String>,
    /// Rows read.
    pub samples_read: usize,
    /// Rows rejected (listed in `rejections`).
    pub samples_rejected: usize,
    /// The rejected rows and gaps: the first [`RejectionLog::DEFAULT_LIMIT`](aeroident_io::RejectionLog::DEFAULT_LIMIT) and the last; the
    /// others are counted per kind in `warnings`.
    pub rejections: Vec<Rejection>,
    /// Manoeuvres (separate initial conditions), split at the record's gaps.
    pub manoeuvres: usize,
    /// Wall time of the fit, s.
    pub fit_wall_s: f64,
    /// Iteration log.
    pub iterations: Vec<BatchIteration>,
    /// The structure's parameters ([`BatchParameter`]).
    pub parameters: Vec<BatchParameter>,
    /// Residual RMS per fitted output (`name`, value in the output's unit).
    pub residual_rms: Vec<(String, f64)>,
    /// Identifiability: Cramér–Rao correlation matrix, data condition numbers, excitation,
    /// collinear regressors ([`Identifiability`]).
    pub identifiability: Identifiability,
    /// Per coefficient, the condition number of the Cramér–Rao correlation block.
    pub coefficients: Vec<aeroident_io::replay_output::CoefficientSummary>,
    /// Parameter pairs with Cramér–Rao `|ρ| > 0.9`.
    pub correlations: Vec<aeroident_io::replay_output::Correlation>,
    /// Sign and collinearity warnings, and the record's, each with its kind
    /// ([`aeroident_io::warning`]); `summary.json` lists their texts.
    pub warnings: aeroident_io::warning::Warnings,
    /// Validation of the simulated outputs on the fitted record.
    pub validation: ValidationReport,
    /// Validation on a second record (`--validate-on`), else `null`.
    pub validation_on: Option<ValidationReport>,
    /// What the log reader left out of each record read, as the caller that opened them
    /// reports it ([`aeroident_io::Record::open`]); empty for CSV records.
    pub reader: Vec<aeroident_io::ReaderReport>,
    /// `fem`: the estimated process noise of each state it was estimated on; empty for `oe`.
    pub process_noise: Vec<ProcessNoise>,
    /// `fem`: the measurement-noise variances `R` recovered from the innovations, per output;
    /// empty for `oe` (its `residual_rms` is the noise).
    pub measurement_noise_var: Vec<(String, f64)>,
    /// `fem`: `diag(K C)` of the final filter per integrated state (dimensionless; the gain
    /// constraint, on unless `--no-gain-constraint`, holds each at or below 1); empty for `oe`.
    pub gain_kc_diag: Vec<(String, f64)>,
    /// `first-sample` (each manoeuvre starts at its first sample's measured states) or
    /// `estimate` (`--initial-states estimate`).
    pub initial_states: String,
    /// The estimated initial states `(x0_m<k>_<state>, value, σ)` (state units: m/s, rad,
    /// rad/s; σ as the parameters'), manoeuvre `k` from 1; empty when they are not estimated.
    pub estimated_initial_states: Vec<(String, f64, f64)>,
    /// The parametric bootstrap (`--bootstrap N`), else `null`. Its σ is the reported σ of
    /// every unknown, the estimated initial states included.
    pub bootstrap: Option<BootstrapSummary>,
    /// `fdoe`: the band, frequencies, linear model and residual spectra; absent for `oe`, `fem`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency_domain: Option<FrequencyDomainSummary>,
    /// The record's other methods beside this fit (`--cross-check`,
    /// [`super::cross_check`]); absent without it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cross_check: Option<super::cross_check::CrossCheck>,
    /// Per surface and accelerometer mapped, its sign as the record's own responses decide it
    /// ([`super::sign_tests`]); empty when the record maps none.
    pub sign_tests: Vec<aeroident_io::replay_output::SignTest>,
    /// With two or more manoeuvres (`oe`, `fem`): each fitted alone and every parameter's
    /// values tested for agreement ([`super::repeatability`]); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub repeatability: Option<super::repeatability::Repeatability>,
}

/// The richest preset the flight model can integrate from the record's first sample.
pub(super) fn default_model(
    first: &AirDataSample,
    mapping: &Mapping,
) -> Result<ModelSpec, ReplayError> {
    let supports = |spec: &ModelSpec| {
        FlightModel::new(spec.structure)
            .and_then(|m| m.inputs(first).map(|_| ()))
            .map_err(|e| as_mapped(&e, mapping))
    };
    crate::record::needs::richest_preset(supports).map_err(|why| {
        ReplayError::Model(format!(
            "no preset model can be fitted by output error from the channels of {} ({why})",
            mapping.file
        ))
    })
}

/// Checks that the flight model of `model` can take the record's first sample, its error
/// naming what the user wrote in `mapping` ([`as_mapped`]) rather than the sample's field.
fn check_model_inputs(
    model: &ModelSpec,
    first: &AirDataSample,
    mapping: &Mapping,
) -> Result<(), ReplayError> {
    FlightModel::new(model.structure).and_then(|m| m.inputs(first).map(|_| ())).map_err(|e| {
        ReplayError::Model(format!("model `{}`: {}", model.name, as_mapped(&e, mapping)))
    })
}

/// `e` in the mapping's words: an error about a sample field or constant (a configuration
/// value, a non-finite input) names the mapping's channel as the user wrote it (its column,
/// expression or constant, [`Mapping::field_label`]), or says the mapping lacks it; any other
/// error as it is.
fn as_mapped(e: &aeroident_estimators::EstimatorError, mapping: &Mapping) -> String {
    use aeroident_estimators::EstimatorError as E;
    let (field, what) = match e {
        E::InvalidConfig { field, value, reason } => (*field, format!("= {value}: {reason}")),
        E::NonFiniteInput { field, value, t_s } => {
            (*field, format!("= {value} at t = {t_s} s is not finite"))
        }
        _ => return e.to_string(),
    };
    match aeroident_io::Channel::of_sample_field(field) {
        Some(ch) if mapping.channels.contains_key(&ch) => {
            format!("{} {what}", mapping.field_label(field))
        }
        Some(ch) => {
            format!(
                "`{}` is not in the mapping {}: the flight model needs it",
                ch.key(),
                mapping.file
            )
        }
        None => e.to_string(),
    }
}

/// The output-error configuration of a post-flight fit of `structure` (`replay --estimator
/// oe`, and the base of the `oe` estimator of `aeroident run`): [`OeConfig::new`]'s defaults,
/// i.e. every output of the structure's flight model that the data have, no output biases,
/// each manoeuvre's initial state at its first sample, and the equation-error start (least
/// squares on the measured coefficients, the generic priors where that fails), never a
/// reference result.
pub fn oe_config(structure: ModelStructure) -> OeConfig {
    OeConfig::new(structure)
}

/// Fits `manoeuvres` by output error with `config` and times the fit: `(result, wall s)`. A fit
/// that does not converge is its last iterate, [`OeResult::termination`] saying why
/// ([`termination_note`] words it).
///
/// # Errors
/// A fit that fails (a model that cannot be simulated, unknowns that are not identifiable …).
pub fn fit_manoeuvres(
    manoeuvres: &[&[AirDataSample]],
    config: &OeConfig,
) -> Result<(OeResult, f64), String> {
    let t0 = std::time::Instant::now();
    let result = fit_to_end(manoeuvres, config).map_err(|e| fit_error("output error", e))?;
    Ok((result, t0.elapsed().as_secs_f64()))
}

/// Fits `manoeuvres` by the filter-error method with `config` and times the fit; a fit that
/// does not converge is its last iterate, as [`fit_manoeuvres`].
///
/// # Errors
/// As [`fit_manoeuvres`].
pub fn fit_fem_manoeuvres(
    manoeuvres: &[&[AirDataSample]],
    config: &FemConfig,
) -> Result<(FemResult, f64), String> {
    let t0 = std::time::Instant::now();
    let result =
        filter_error::fit_to_end(manoeuvres, config).map_err(|e| fit_error("filter error", e))?;
    Ok((result, t0.elapsed().as_secs_f64()))
}

fn fit_error(method: &str, e: OeError) -> String {
    match e {
        // `fit_to_end` returns the last iterate instead.
        OeError::NotConverged { reason, .. } => format!("{method}: {}", reason.describe()),
        OeError::Estimator(e) => format!("{method}: {e}"),
    }
}

/// What a fit that did not meet both convergence criteria must say (`None` for one that did):
/// how it ended, after how many iterations, and the last iteration's convergence measures
/// (relative change of det R, largest step in Cramér–Rao σ), so a creeping fit can be told
/// from a stalled one.
pub fn termination_note(result: &OeResult) -> Option<String> {
    termination_note_of(result.termination, &result.iterations)
}

/// [`termination_note`] of a fit that ended as `termination` with iteration log `iterations`
/// (`ln_det_r` the log-determinant of its noise covariance).
pub fn termination_note_of(
    termination: Termination,
    iterations: &[aeroident_estimators::output_error::OeIteration],
) -> Option<String> {
    if termination == Termination::Converged {
        return None;
    }
    let last = match iterations {
        [.., a, b] => format!(
            " (last iteration: relative change of det R {:.1e}, largest step {:.1e} σ)",
            (b.ln_det_r - a.ln_det_r).exp_m1().abs(),
            b.max_step_sigma
        ),
        _ => String::new(),
    };
    Some(format!(
        "{} after {} iterations{last}",
        termination.describe(),
        iterations.len().saturating_sub(1)
    ))
}

/// The words for a fit started twice ([`OeResult::restart`]): how the fit from the
/// equation-error start ended, how the one from the generic priors did, and which is
/// reported; `None` for a fit started once.
pub fn restart_note(result: &OeResult) -> Option<String> {
    let r = result.restart.as_ref()?;
    let ending = |(t, ln): (Termination, f64)| format!("{}, ln det R {ln:.3}", t.status());
    let second = match &r.second {
        Ok(second) => *second,
        Err(e) => {
            return Some(format!(
                "started twice: the fit from the equation-error start ended {}; the fit from \
                 the generic priors could not run ({e}), so the first is reported",
                ending(r.first)
            ));
        }
    };
    let kept = if r.kept_second { "the second" } else { "the first" };
    Some(format!(
        "started twice: the fit from the equation-error start ended {}, the fit from the \
         generic priors {}; reported: {kept} ({}). Two starts reaching different answers mean \
         the cost has more than one valley: check the excitation and any unmeasured state",
        ending(r.first),
        ending(second),
        if r.first.0.is_converged() == second.0.is_converged() {
            "the lower det R"
        } else {
            "the converged one"
        }
    ))
}

/// The model's simulated outputs over `manoeuvres` with parameters `theta` (no fit: output
/// error's simulation at the given values, initial states at each manoeuvre's first sample),
/// as a result whose residuals are `z − y` (for the validation of a filter-error fit, whose
/// own residuals are one-step innovations).
pub(super) fn simulate_at(
    manoeuvres: &[&[AirDataSample]],
    structure: ModelStructure,
    outputs: &[aeroident_estimators::Output],
    theta: &[f64],
) -> Result<OeResult, aeroident_estimators::EstimatorError> {
    let mut config = OeConfig::new(structure);
    config.outputs = Some(outputs.to_vec());
    config.start = Start::Given(theta.to_vec());
    config.max_iterations = 0;
    match fit(manoeuvres, &config) {
        Ok(res) => Ok(res),
        Err(OeError::NotConverged { result, .. }) => Ok(*result),
        Err(OeError::Estimator(e)) => Err(e),
    }
}

/// The σ a batch fit reports for every unknown (order of [`OeResult::names`]: the structure's
/// parameters first, then output biases and free initial states): the coloured-residual σ
/// where the correction was formed (real residuals are coloured and the Cramér–Rao σ is then
/// optimistic; Morelli & Klein 1997), the Cramér–Rao σ otherwise.
pub fn reported_sigma(result: &OeResult) -> Vec<f64> {
    result.sigma_coloured.clone().unwrap_or_else(|| result.sigma.clone())
}

/// The σ a filter-error fit reports for every unknown (order of [`OeResult::names`], the
/// structure's parameters first) and whether it is the coloured-residual one: the
/// coloured-residual sandwich where it was formed ([`OeResult::sigma_coloured`], else
/// [`FemResult::sigma_coloured_theta`], NaN for a process-noise `F` whose entry was not
/// positive), else the Cramér–Rao σ. On the F-16 campaign the Cramér–Rao σ is 1.3–3× short of
/// the scatter and the coloured one 0.6–1.9× it (docs/uncertainty.md, "Where the targets
/// stand").
pub fn fem_reported_sigma(fem: &FemResult) -> (Vec<f64>, bool) {
    let r = &fem.result;
    match r.sigma_coloured.as_ref().or(fem.sigma_coloured_theta.as_ref()) {
        Some(c) => (c.clone(), true),
        None => (r.sigma.clone(), false),
    }
}

/// Most Gauss–Newton iterations of the campaign's fits (the estimators crate's default is 50).
/// On turbulent flights the residuals are large and structured, so Gauss–Newton converges
/// only linearly (Dennis & Schnabel 1983 ch. 10: the neglected second-order term of the
/// Hessian is not small): over 200 runs of `scenarios/montecarlo/with-oe.toml` (seed 1) the
/// fits took 16 iterations on average and at most 192 to meet the unchanged convergence test
/// (docs/uncertainty.md, "Output error in the campaign").
pub const MAX_ITERATIONS: usize = 250;

/// One state's process noise, as a filter-error fit estimates it or a bootstrap flies it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProcessNoise {
    /// The state ([`STATE_NAMES`]: `vt_mps`, `alpha_rad` …).
    pub state: String,
    /// Its process-noise intensity `F`, the state's unit per √s.
    pub f: f64,
    /// The σ of `F` (Cramér–Rao); `null` where none is formed (the bootstrap's).
    pub std_error: Option<f64>,
}

/// The process noise of each process-noise state of a filter-error fit, with its σ.
pub fn process_noise_of(fem: &FemResult) -> Vec<ProcessNoise> {
    let row = |i: usize| {
        let (f, s) = fem.process_noise(i)?;
        Some(ProcessNoise { state: STATE_NAMES[i].to_string(), f, std_error: Some(s) })
    };
    fem.process_noise_states.iter().filter_map(|&i| row(i)).collect()
}

/// The seed of the first bootstrap replica (replica `b` is seeded `seed + b`): fixed, so that
/// a bootstrap σ is reproducible run to run.
pub const BOOTSTRAP_SEED: u64 = 1;

/// The most replicas a parametric bootstrap ([`bootstrap_sigma`]) refits.
///
/// Each replica is a whole output-error fit of the record (as long as the fit itself), and the
/// σ of `B` replicas has a relative sampling error of about `1/√(2(B − 1))`: 0.7 % at the
/// limit, 5 % at the 200 replicas Efron & Tibshirani (1993, §6.4) find enough for a standard
/// error. More replicas cost hours and memory and buy nothing measurable.
pub const MAX_BOOTSTRAP_REFITS: usize = 10_000;

/// Checks a bootstrap's number of replicas, before anything is fitted or allocated: 2 (a
/// spread needs two) to [`MAX_BOOTSTRAP_REFITS`].
///
/// # Errors
/// Why the count is refused (the caller names its option: `--bootstrap`, `bootstrap_refits`).
pub fn check_bootstrap_refits(refits: usize) -> Result<(), String> {
    if refits < 2 {
        return Err(format!("{refits} refits: at least 2 are needed for a spread"));
    }
    if refits > MAX_BOOTSTRAP_REFITS {
        return Err(format!(
            "{refits} refits is more than the {MAX_BOOTSTRAP_REFITS} a bootstrap takes (each is a whole fit of the record; the σ of {MAX_BOOTSTRAP_REFITS} replicas is already within 0.7 %)"
        ));
    }
    Ok(())
}

/// How the parametric bootstrap of an output-error fit went (`summary.json` `bootstrap`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BootstrapSummary {
    /// Replicas flown and refitted: all those asked for unless a stop came first.
    pub refits: usize,
    /// Replicas asked for (`--bootstrap N`); more than [`BootstrapSummary::refits`] when a stop
    /// ([`OeConfig::stop`]) ended the bootstrap early.
    pub requested: usize,
    /// Replicas that failed (the replica left the physical domain, or its refit failed or did
    /// not converge); the σ is the spread of the others.
    pub failed: usize,
    /// Seed of replica 0 (replica `b`: `seed + b`; PCG64, standard normal draws).
    pub seed: u64,
    /// The process noise the replicas were flown with, the filter-error method's estimate on
    /// the same data (no σ).
    pub process_noise: Vec<ProcessNoise>,
    /// The measurement-noise variances `(output, R)` of the replicas (the filter-error
    /// method's), the output's unit squared.
    pub measurement_noise_var: Vec<(String, f64)>,
    /// Wall time of the filter-error fit and the refits, s.
    pub wall_s: f64,
}

/// What the parametric bootstrap gives per unknown (order of [`OeResult::names`]: the
/// structure parameters, the output biases, the free initial states; the unknown's unit).
#[derive(Debug, Clone, PartialEq)]
pub struct BootstrapSpread {
    /// The sample standard deviation of the refits: the σ.
    pub sigma: Vec<f64>,
    /// The refits' mean less the estimate: the bootstrap's estimate of the fit's bias (its own
    /// sampling error is `sigma/√(refits − failed)`). Reported, never subtracted.
    pub bias: Vec<f64>,
}

/// Below this fraction of an unknown's coloured-residual σ, a bootstrap σ is flagged
/// ([`bootstrap_shrink_warnings`]). Where the bootstrap is right and the coloured σ is not, the
/// coloured σ was measured at most 1.9× the scatter (the synthetic process-noise test of
/// `output_error::bootstrap`, one record; its mean over 24 records 1.46×), so a ratio below 1/4
/// is not that: it is residual colour the replicas' process noise does not produce.
pub const BOOTSTRAP_BELOW_COLOURED: f64 = 0.25;

/// Warnings for the unknowns (`names`, order of [`OeResult::names`]) whose bootstrap σ
/// (`bootstrap`) is below [`BOOTSTRAP_BELOW_COLOURED`] × their coloured-residual σ
/// (`coloured`, `None` where not formed: no warning). Measured on ATTAS AilRud1, the initial
/// bank angles' bootstrap σ is 0.04–0.06× the coloured one: the replicas carry process noise
/// on `β` only, and the bank-angle residual's colour is model error, which the bootstrap does
/// not see (docs/real-data.md, "Output error's bootstrap σ on the repeats").
pub fn bootstrap_shrink_warnings(
    names: &[String],
    coloured: &[Option<f64>],
    bootstrap: &[f64],
) -> Vec<String> {
    names
        .iter()
        .zip(coloured)
        .zip(bootstrap)
        .filter_map(|((name, c), b)| {
            let c = (*c)?;
            (*b < BOOTSTRAP_BELOW_COLOURED * c).then(|| {
                format!(
                    "bootstrap: the σ of {name} is {:.2}× its coloured-residual σ ({b:.3e} against {c:.3e}): the replicas' process noise does not produce that residual colour (model error?), which the bootstrap does not see; the coloured σ is the cautious one",
                    b / c
                )
            })
        })
        .collect()
}

/// The parametric bootstrap σ of the output-error fit `fitted` of `manoeuvres` with `config`
/// ([`aeroident_estimators::output_error::bootstrap`]): the noise levels from a filter-error
/// fit of the same data ([`FemConfig::new`] with `config` as its output-error part, at most
/// [`MAX_ITERATIONS`] iterations), then `refits` replicas flown at the
/// fitted unknowns and refitted, in parallel (rayon); replica `b` draws from PCG64 seeded
/// `seed + b`. Returns the σ and the bias estimate of every unknown ([`BootstrapSpread`]) and
/// the summary.
///
/// A stop raised on `config` ([`OeConfig::stop`]) starts no further replica and drops the
/// refits it interrupts: the σ is then the spread of the replicas done
/// ([`BootstrapSummary::refits`] of [`BootstrapSummary::requested`]). `counter`, when given,
/// counts each replica as it ends.
///
/// # Errors
/// A message when `refits` is outside 2 to [`MAX_BOOTSTRAP_REFITS`] (before any fit), the
/// filter-error fit fails or does not converge, more than half of the replicas done fail (the
/// first reason given), or fewer than 2 are usable.
pub fn bootstrap_sigma(
    manoeuvres: &[&[AirDataSample]],
    config: &OeConfig,
    fitted: &OeResult,
    refits: usize,
    seed: u64,
    counter: Option<&ReplicaCounter>,
) -> Result<(BootstrapSpread, BootstrapSummary), String> {
    use aeroident_estimators::output_error::bootstrap::{self, BootstrapNoise};
    check_bootstrap_refits(refits).map_err(|e| format!("bootstrap: {e}"))?;
    let t0 = std::time::Instant::now();
    let mut fem_config = FemConfig::new(config.structure);
    fem_config.oe = config.clone();
    fem_config.oe.max_iterations = MAX_ITERATIONS;
    let noise_source = "bootstrap: the noise levels come from a filter-error fit";
    let (fem, _) =
        fit_fem_manoeuvres(manoeuvres, &fem_config).map_err(|e| format!("{noise_source}: {e}"))?;
    if !fem.result.termination.is_converged() {
        let why = termination_note(&fem.result).unwrap_or_default();
        return Err(format!("{noise_source}, which did not converge: {why}"));
    }
    let noise = BootstrapNoise::from_fem(&fem);
    let draws = replicas(manoeuvres, config, fitted, &noise, (refits, seed), counter);
    let done = draws.len();
    let failed = draws.iter().filter(|d| d.is_err()).count();
    if 2 * failed > done {
        let first = draws.iter().find_map(|d| d.as_ref().err()).cloned().unwrap_or_default();
        return Err(format!("bootstrap: {failed} of {done} replicas failed (first: {first})"));
    }
    let ok: Vec<Vec<f64>> = draws.into_iter().filter_map(Result::ok).collect();
    let too_few =
        || format!("bootstrap: {} usable refits of {done} done, at least 2 needed", ok.len());
    let sigma = bootstrap::spread(&ok).ok_or_else(too_few)?;
    let bias = bootstrap::bias(&ok, &fitted.values).ok_or_else(too_few)?;
    let names = |i: usize| STATE_NAMES[i].to_string();
    let summary = BootstrapSummary {
        refits: done,
        requested: refits,
        failed,
        seed,
        process_noise: noise
            .process_noise
            .iter()
            .map(|(i, f)| ProcessNoise { state: names(*i), f: *f, std_error: None })
            .collect(),
        measurement_noise_var: fem
            .result
            .outputs
            .iter()
            .zip(&noise.measurement_var)
            .map(|(o, r)| (o.name().to_string(), *r))
            .collect(),
        wall_s: t0.elapsed().as_secs_f64(),
    };
    Ok((BootstrapSpread { sigma, bias }, summary))
}

/// The bootstrap's replicas ([`bootstrap_sigma`]), in parallel, in replica order: each
/// replica's refitted unknowns or why it failed. Once `config`'s stop is raised no replica
/// starts and a refit it interrupts is left out, so only the replicas done are returned.
fn replicas(
    manoeuvres: &[&[AirDataSample]],
    config: &OeConfig,
    fitted: &OeResult,
    noise: &aeroident_estimators::output_error::bootstrap::BootstrapNoise,
    (refits, seed): (usize, u64),
    counter: Option<&ReplicaCounter>,
) -> Vec<Result<Vec<f64>, String>> {
    use aeroident_estimators::output_error::{NotConverged, bootstrap};
    use rand::{Rng, SeedableRng};
    use rayon::prelude::*;
    let stopped = || config.stop.as_ref().is_some_and(StopFlag::raised);
    let draws: Vec<Option<Result<Vec<f64>, String>>> = (0..refits)
        .into_par_iter()
        .map(|b| {
            if stopped() {
                return None;
            }
            let mut rng = rand_pcg::Pcg64::seed_from_u64(seed.wrapping_add(b as u64));
            let mut normal = || rng.sample::<f64, _>(rand_distr::StandardNormal);
            let refit = bootstrap::refit(manoeuvres, config, fitted, noise, &mut normal);
            counter.inspect(|c| c.add_one());
            match refit {
                Err(OeError::NotConverged { reason: NotConverged::Stopped, .. }) => None,
                r => Some(r.map_err(|e| fit_error(&format!("bootstrap replica {b}"), e))),
            }
        })
        .collect();
    draws.into_iter().flatten().collect()
}

/// The name of an initial-state setting as the CLI (`--initial-states`) and the run scenario
/// (`initial_states`) write it: `first-sample` or `estimate`.
pub fn initial_states_name(setting: InitialStates) -> &'static str {
    match setting {
        InitialStates::FirstSample => "first-sample",
        InitialStates::Estimate(_) => "estimate",
    }
}

/// The states of a comma-separated list (`V` or `vt`, `alpha`, `beta`, `p`, `q`, `r`, `phi`,
/// `theta`) as a full-state mask: the states the filter-error method gives process noise.
///
/// # Errors
/// A message naming an unknown state.
pub fn parse_process_noise_states(list: &str) -> Result<[bool; N_STATES], String> {
    let mut mask = [false; N_STATES];
    for name in list.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        let i = match name {
            "V" | "vt" => state::V,
            "alpha" => state::ALPHA,
            "beta" => state::BETA,
            "p" => state::P,
            "q" => state::Q,
            "r" => state::R,
            "phi" => state::PHI,
            "theta" => state::THETA,
            other => {
                return Err(format!(
                    "fem: `process_noise` state `{other}` unknown (V alpha beta p q r phi theta)"
                ));
            }
        };
        mask[i] = true;
    }
    if !mask.contains(&true) {
        return Err(format!("fem: `process_noise` names no state (`{list}`)"));
    }
    Ok(mask)
}

/// Which batch fit of a record (`replay --estimator oe | fem | fdoe`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BatchMethod {
    /// Time-domain maximum-likelihood output error.
    Oe,
    /// The filter-error method (output error with process noise).
    Fem,
    /// Frequency-domain output error ([`super::frequency`]) over the band `band_hz`
    /// `(f_min, f_max)`, Hz.
    Fdoe {
        /// The band fitted, Hz.
        band_hz: (f64, f64),
    },
}

impl BatchMethod {
    /// The estimator kind of the method (`oe`, `fem`, `fdoe`).
    pub fn kind(&self) -> EstimatorKind {
        match self {
            BatchMethod::Oe => EstimatorKind::Oe,
            BatchMethod::Fem => EstimatorKind::Fem,
            BatchMethod::Fdoe { .. } => EstimatorKind::Fdoe,
        }
    }
}

/// The bootstrap replicas done so far, shared with a face that shows them (a progress bar):
/// [`bootstrap_sigma`] adds one as each replica ends. Clones share the count.
#[derive(Debug, Clone, Default)]
pub struct ReplicaCounter(std::sync::Arc<std::sync::atomic::AtomicUsize>);

impl ReplicaCounter {
    /// Replicas done (refitted, failed or abandoned by a stop).
    pub fn done(&self) -> usize {
        self.0.load(std::sync::atomic::Ordering::Relaxed)
    }

    fn add_one(&self) {
        self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }
}

impl PartialEq for ReplicaCounter {
    /// Equal when shared: the same count.
    fn eq(&self, other: &Self) -> bool {
        std::sync::Arc::ptr_eq(&self.0, &other.0)
    }
}

/// What a batch fit of a record fits and how (`replay --estimator oe|fem
/// [--initial-states …] [--bootstrap N]`).
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// The method: output error, the filter-error method or frequency-domain output error.
    pub method: BatchMethod,
    /// Each manoeuvre's initial state: at its first sample, or estimated.
    pub initial_states: InitialStates,
    /// `oe` only: the parametric bootstrap with this many refits ([`bootstrap_sigma`], seed
    /// [`BOOTSTRAP_SEED`]); its σ is then the reported one.
    pub bootstrap_refits: Option<usize>,
    /// Counts the bootstrap's replicas as they end, for a face's progress; `None`: uncounted.
    pub bootstrap_done: Option<ReplicaCounter>,
    /// `oe` only: how the Gauss–Newton step treats the noise covariance ([`StepKind`]);
    /// `None`: [`OeConfig::new`]'s.
    pub step: Option<StepKind>,
    /// Most Gauss–Newton iterations; `None`: [`OeConfig::new`]'s 50 for output error,
    /// [`MAX_ITERATIONS`] for the filter-error method. A fit stopped by it reports its last
    /// iterate ([`termination_note`]).
    pub max_iterations: Option<usize>,
    /// `fem` only: the states with process noise (full-state mask,
    /// [`parse_process_noise_states`]); `None`: [`FemConfig::new`]'s (`V`, `α`, `β`).
    pub process_noise: Option<[bool; N_STATES]>,
    /// `fem` only: hold `diag(K C) ≤ 1` ([`FemConfig::gain_limit`], Jategaonkar 2015 ch. 5);
    /// default on.
    pub gain_constraint: bool,
    /// A compatibility check's corrections, applied to every sample before the fit
    /// ([`crate::compat::Corrected`]); the summary's warnings list them.
    pub compat: Option<crate::record::Corrections>,
    /// The time windows of the record fitted, each its own manoeuvre ([`crate::window`]);
    /// empty: the whole record.
    pub windows: Vec<crate::window::TimeWindow>,
    /// The spike screen before the fit ([`crate::record::outliers`]); `None`: off. Default on.
    pub spike_screen: Option<crate::record::outliers::SpikeScreen>,
    /// `oe` only: Huber's robust weights on the normalised residuals
    /// ([`OeConfig::robust`]); `None`: the Gaussian maximum-likelihood fit. Default off.
    pub robust: Option<aeroident_estimators::output_error::Huber>,
    /// A request to stop ([`OeConfig::stop`]): the fit ends at its next iteration with its
    /// last iterate, the bootstrap before its next replica with the replicas done. `None`
    /// (default): it runs to its end.
    pub stop: Option<StopFlag>,
    /// Only the estimates and their σ (a refit that reads nothing else: the panel's batch
    /// methods, the timing tests' refits): no sign tests, whose surface-lead search over a
    /// long record costs more than the fit. Default off.
    pub estimates_only: bool,
}

impl Default for FitOptions {
    /// Output error, initial states at the first sample, no bootstrap, the default limit
    /// (`fem`: the gain constraint on).
    fn default() -> Self {
        Self {
            method: BatchMethod::Oe,
            initial_states: InitialStates::FirstSample,
            bootstrap_refits: None,
            bootstrap_done: None,
            step: None,
            max_iterations: None,
            process_noise: None,
            gain_constraint: true,
            compat: None,
            windows: Vec::new(),
            spike_screen: Some(crate::record::outliers::SpikeScreen::default()),
            robust: None,
            stop: None,
            estimates_only: false,
        }
    }
}

/// The time-domain batch fits (output error, filter error) of the record `rec`, read and split
/// by the caller ([`super::fit::fit_records`], which has checked `options`): the model given,
/// else the richest preset the first sample can drive; `file` names the record(s).
///
/// # Errors
/// No supported model, a fit that fails ([`ReplayError::Model`] with the reason), a bootstrap
/// that fails ([`bootstrap_sigma`]).
pub(crate) fn fit_time_domain(
    rec: Manoeuvres,
    file: &str,
    mapping: &Mapping,
    model: Option<ModelSpec>,
    options: &FitOptions,
) -> Result<BatchOutcome, ReplayError> {
    let model = match model {
        Some(m) => m,
        None => default_model(&rec.manoeuvres[0][0], mapping)?,
    };
    check_model_inputs(&model, &rec.manoeuvres[0][0], mapping)?;
    let (model, level_note) = super::sideslip_level(model, &rec.manoeuvres[0][0]);
    let slices: Vec<&[AirDataSample]> = rec.manoeuvres.iter().map(Vec::as_slice).collect();
    crate::structure::check_knots_in_range(&model.structure, &slices, &model.name)
        .map_err(ReplayError::Model)?;
    let fitted = fit_slices(&slices, model.structure, options)?;
    let sigmas =
        sigma_stage(&slices, &fitted, options.bootstrap_refits, options.bootstrap_done.as_ref())?;
    let st = model.structure;
    let result = &fitted.result;
    // A filter-error fit is validated (and drawn) by simulating the model at its estimates;
    // a model whose simulation leaves the physical domain open loop (an unstable mode the
    // filter held) is shown by its one-step predictions instead, and says so.
    let mut simulation_note = None;
    let simulated = match &fitted.fem {
        Some(_) => {
            match simulate_at(&slices, st, &result.outputs, &result.values[..result.n_params]) {
                Ok(r) => r,
                Err(e) => {
                    simulation_note = Some(format!(
                        "filter error: the model at the estimates cannot be simulated open loop ({e}); the validation and the figure show the filter's one-step predictions"
                    ));
                    result.clone()
                }
            }
        }
        None => result.clone(),
    };
    let validation = simulated_validation(&simulated, &slices, file, None);
    let traces = output_traces(&simulated, &slices);
    let (rejections, unlisted) = rec.rejections.finish();
    let mut summary =
        summarise(&model, &fitted, &sigmas, &rec.manoeuvres, options.initial_states, validation);
    summary.samples_read = rec.read;
    summary.samples_rejected = rec.rejected;
    summary.rejections = rejections;
    summary.warnings.extend(unlisted);
    summary.warnings.extend(simulation_note);
    summary.warnings.extend(level_note);
    summary.warnings.extend(rec.notes.iter().cloned());
    summary.warnings.extend(dominance_warnings(&fitted.result, &slices, mapping));
    summary
        .warnings
        .extend(crate::kinematics::Kinematics::of_manoeuvres(&slices).warnings(mapping));
    if !options.estimates_only {
        let (sign_tests, sign_warnings) = super::sign_tests::checked(&slices, mapping);
        summary.sign_tests = sign_tests;
        summary.warnings.extend(sign_warnings);
    }
    if let Some(c) = &options.compat {
        summary.warnings.extend(c.warnings());
    }
    repeat_stage(&slices, st, options, &mut summary);
    let options = options.clone();
    Ok(BatchOutcome { model, result: fitted.result, summary, traces, frequency: None, options })
}

/// The repeatability stage ([`super::repeatability`]): with two or more manoeuvres, each fitted
/// alone by the same method (no bootstrap), its estimates tested for agreement; a parameter
/// that does not repeat gets a warning naming it (the judge's note) and the σ of its
/// manoeuvres' spread where that is the larger (source `repeatability`).
fn repeat_stage(
    slices: &[&[AirDataSample]],
    structure: ModelStructure,
    options: &FitOptions,
    summary: &mut BatchSummary,
) {
    use rayon::prelude::*;
    if slices.len() < 2 {
        return;
    }
    let solo = FitOptions { bootstrap_refits: None, bootstrap_done: None, ..options.clone() };
    let fits: Vec<SoloFit> =
        slices.par_iter().enumerate().map(|(k, m)| solo_fit(k, m, structure, &solo)).collect();
    apply_repeatability(fits, summary);
}

/// The manoeuvres' solo `fits` tested for agreement ([`Repeatability::assess`]) and written
/// into `summary`: the notes of the parameters that do not repeat, their σ raised to the
/// manoeuvres' spread where that is the larger (source `repeatability`), and the test itself.
pub(super) fn apply_repeatability(fits: Vec<SoloFit>, summary: &mut BatchSummary) {
    let names: Vec<String> = summary.parameters.iter().map(|p| p.name.clone()).collect();
    let rep = Repeatability::assess(fits, &names);
    summary.warnings.extend(rep.warnings());
    for p in &mut summary.parameters {
        rep.widen(&mut p.result);
    }
    summary.repeatability = Some(rep);
}

/// Manoeuvre `k` fitted alone: its estimates and σ (the reported ones) when the fit converged.
fn solo_fit(
    k: usize,
    m: &[AirDataSample],
    structure: ModelStructure,
    options: &FitOptions,
) -> SoloFit {
    let mut fit = SoloFit::of(k, m);
    let fitted = match fit_slices(&[m], structure, options) {
        Ok(f) => f,
        Err(e) => {
            fit.status = format!("failed: {e}");
            return fit;
        }
    };
    if !fitted.result.termination.is_converged() {
        fit.status = "not converged".into();
        return fit;
    }
    let sigma = match &fitted.fem {
        Some(f) => fem_reported_sigma(f).0,
        None => reported_sigma(&fitted.result),
    };
    let r = &fitted.result;
    fit.estimates = (0..r.n_params)
        .filter(|&i| sigma[i].is_finite() && sigma[i] > 0.0)
        .map(|i| super::cross_check::ParameterEstimate::new(&r.names[i], r.values[i], sigma[i]))
        .collect();
    fit.status = super::repeatability::CONVERGED.into();
    fit
}

/// The summary's warnings when one sample dominates the fit
/// ([`aeroident_estimators::output_error::Dominance`]): the sample's time and the output (the
/// share of the cost, named by `mapping`'s channel and column) or its Cook's distance, against
/// the stated limits.
pub fn dominance_warnings(
    result: &OeResult,
    manoeuvres: &[&[AirDataSample]],
    mapping: &Mapping,
) -> Vec<String> {
    use aeroident_estimators::output_error::Dominance;
    let Some(d) = result.dominance else { return Vec::new() };
    let t_s = |i: usize| manoeuvres.iter().flat_map(|m| m.iter()).nth(i).map(|s| s.t_s);
    let at =
        |i: usize| t_s(i).map_or(format!("sample {i}"), |t| format!("the sample at t = {t} s"));
    let mut out = Vec::new();
    if d.share_dominates(result.outputs.len()) {
        out.push(format!(
            "one sample dominates the fit: {} holds {:.1} % of the weighted cost Σ eᵀR⁻¹e (limit {} %; χ² {:.0}, mostly output {}); check it for a spike, or fit with the robust option",
            at(d.share_sample),
            100.0 * d.share,
            100.0 * Dominance::SHARE_LIMIT,
            d.chi2,
            mapping.field_label(d.share_output.name())
        ));
    }
    if d.cook_dominates() {
        out.push(format!(
            "one sample dominates the fit: {} has Cook's distance {:.3} (limit {}): without it the estimate would move beyond its confidence region; check it for a spike, or fit with the robust option",
            at(d.cook_sample),
            d.cook,
            Dominance::COOK_LIMIT
        ));
    }
    out
}

/// A batch fit of the record's manoeuvres, timed.
struct FittedRecord {
    /// The output-error result (of the filter-error fit for `fem`).
    result: OeResult,
    fit_wall_s: f64,
    /// `fem`: its full result.
    fem: Option<FemResult>,
    /// `oe`: the configuration fitted (the bootstrap refits with it).
    oe: Option<OeConfig>,
}

/// The fit stage: output error or the filter-error method on `slices`, as `options` say.
fn fit_slices(
    slices: &[&[AirDataSample]],
    structure: ModelStructure,
    options: &FitOptions,
) -> Result<FittedRecord, ReplayError> {
    if options.method == BatchMethod::Fem {
        let mut config = FemConfig::new(structure);
        options.apply_to_fem(&mut config);
        config.oe.stop.clone_from(&options.stop);
        let (f, wall) = fit_fem_manoeuvres(slices, &config).map_err(ReplayError::Model)?;
        Ok(FittedRecord { result: f.result.clone(), fit_wall_s: wall, fem: Some(f), oe: None })
    } else {
        let mut config = oe_config(structure);
        options.apply_to_oe(&mut config);
        config.stop.clone_from(&options.stop);
        let (r, wall) = fit_manoeuvres(slices, &config).map_err(ReplayError::Model)?;
        Ok(FittedRecord { result: r, fit_wall_s: wall, fem: None, oe: Some(config) })
    }
}

impl FitOptions {
    /// Sets what the options say of an output-error fit's configuration (initial states,
    /// step, iteration limit, Huber's weights), leaving the rest of `config` as it is: the
    /// one translation of the options, for a record's fit and the closed-loop experiment's
    /// (`crate::aircraft::batch::config`).
    pub fn apply_to_oe(&self, config: &mut OeConfig) {
        config.initial_states = self.initial_states;
        config.robust = self.robust;
        if let Some(step) = self.step {
            config.step = step;
        }
        if let Some(n) = self.max_iterations {
            config.max_iterations = n;
        }
    }

    /// [`FitOptions::apply_to_oe`] for the filter-error method: its output-error part (the
    /// iteration limit [`MAX_ITERATIONS`] unless given: convergence on turbulent or
    /// model-error records is slow, module doc of `filter_error`), the states with process
    /// noise and the gain constraint.
    pub fn apply_to_fem(&self, config: &mut FemConfig) {
        self.apply_to_oe(&mut config.oe);
        config.oe.max_iterations = self.max_iterations.unwrap_or(MAX_ITERATIONS);
        if let Some(mask) = self.process_noise {
            config.process_noise = mask;
        }
        if !self.gain_constraint {
            config.gain_limit = None;
        }
    }
}

/// The σ of every unknown (order of [`OeResult::names`]) and where it comes from.
struct Sigmas {
    /// The reported σ: bootstrap, else coloured-residual where formed, else Cramér–Rao.
    reported: Vec<f64>,
    /// The coloured-residual σ, where formed.
    coloured: Vec<Option<f64>>,
    bootstrap: Option<BootstrapSummary>,
    spread: Option<BootstrapSpread>,
    /// Why the bootstrap was not run, when asked for.
    bootstrap_skipped: Option<String>,
}

/// The σ stage: coloured-residual σ where formed, for both methods (fem:
/// [`fem_reported_sigma`]); the bootstrap σ, when asked for on a converged output-error fit,
/// replaces the reported σ of every unknown (initial states included).
fn sigma_stage(
    slices: &[&[AirDataSample]],
    fitted: &FittedRecord,
    refits: Option<usize>,
    counter: Option<&ReplicaCounter>,
) -> Result<Sigmas, ReplayError> {
    let result = &fitted.result;
    let (mut reported, coloured) = match &fitted.fem {
        Some(f) => fem_reported_sigma(f),
        None => (reported_sigma(result), result.sigma_coloured.is_some()),
    };
    let coloured = reported.iter().map(|s| coloured.then_some(*s)).collect();
    let mut out = Sigmas {
        reported: Vec::new(),
        coloured,
        bootstrap: None,
        spread: None,
        bootstrap_skipped: None,
    };
    if let (Some(n), Some(config)) = (refits, &fitted.oe) {
        let stopped = || config.stop.as_ref().is_some_and(StopFlag::raised);
        if stopped() {
            out.bootstrap_skipped = Some(
                "bootstrap not run: a stop was asked for during the fit (the reported σ is the fit's own)".into(),
            );
        } else if result.termination.is_converged() {
            match bootstrap_sigma(slices, config, result, n, BOOTSTRAP_SEED, counter) {
                Ok((spread, summary)) => {
                    reported.copy_from_slice(&spread.sigma);
                    out.bootstrap = Some(summary);
                    out.spread = Some(spread);
                }
                // Stopped before it had a σ: the fit's own σ stand, and the summary says why.
                Err(e) if stopped() => {
                    out.bootstrap_skipped = Some(format!(
                        "bootstrap stopped on request before it had a σ ({e}); the reported σ is the fit's own"
                    ));
                }
                Err(e) => return Err(ReplayError::Model(e)),
            }
        } else {
            out.bootstrap_skipped =
                Some("bootstrap not run: the fit did not converge (its σ would describe the last iterate, not the estimator)".into());
        }
    }
    out.reported = reported;
    Ok(out)
}

/// The summary document of a fit (the record's row counts are the caller's).
fn summarise(
    model: &ModelSpec,
    fitted: &FittedRecord,
    sigmas: &Sigmas,
    manoeuvres: &[Vec<AirDataSample>],
    initial_states: InitialStates,
    validation: ValidationReport,
) -> BatchSummary {
    let result = &fitted.result;
    let st = model.structure;
    let reported = &sigmas.reported;
    let spread = sigmas.spread.as_ref();
    // The free initial states follow the parameters and the output biases (OeResult::names).
    let estimated_initial_states = result
        .names
        .iter()
        .enumerate()
        .filter(|(_, n)| n.starts_with("x0_m"))
        .map(|(i, n)| (n.clone(), result.values[i], reported[i]))
        .collect();
    let parameters = (0..result.n_params)
        .map(|i| {
            let source = match (spread, sigmas.coloured[i]) {
                (Some(_), _) => StdErrorSource::Bootstrap,
                (None, Some(_)) => StdErrorSource::Coloured,
                (None, None) => StdErrorSource::CramerRao,
            };
            let name = result.names[i].clone();
            BatchParameter {
                result: ParameterResult::new(
                    name,
                    Some(result.values[i]),
                    Some(reported[i]),
                    None,
                    None,
                )
                .with_source(source)
                .with_crb_std_error(Some(result.sigma[i])),
                coloured_std_error: sigmas.coloured[i],
                bootstrap_std_error: spread.map(|b| b.sigma[i]),
                bootstrap_bias: spread.map(|b| b.bias[i]),
                prewhitened_std_error: result.sigma_coloured_prewhitened.as_ref().map(|c| c[i]),
            }
        })
        .collect();
    let np = result.n_params;
    let n = result.n();
    let values: Vec<Option<f64>> = result.values[..np].iter().map(|v| Some(*v)).collect();
    let cov = |i: usize, j: usize| Some(result.covariance[i * n + j]);
    let mut recorder = Recorder::for_structure(&st);
    for m in manoeuvres {
        recorder.new_segment();
        m.iter().for_each(|s| recorder.push(s));
    }
    let identifiability = diagnostics::identifiability(&st, &cov, &recorder, &values);
    let warnings = fit_warnings(result, sigmas, &identifiability, &values);
    BatchSummary {
        schema_version: aeroident_io::SCHEMA_VERSION,
        estimator: if fitted.fem.is_some() { "fem" } else { "oe" }.into(),
        model: model.name.clone(),
        alpha_knots_rad: model.structure.knots().as_slice().to_vec(),
        status: result.termination.status().into(),
        status_reason: termination_note(result),
        samples_read: 0,
        samples_rejected: 0,
        rejections: Vec::new(),
        manoeuvres: manoeuvres.len(),
        fit_wall_s: fitted.fit_wall_s,
        iterations: result.iterations.iter().map(BatchIteration::from).collect(),
        parameters,
        residual_rms: result
            .outputs
            .iter()
            .zip(&result.residual_rms)
            .map(|(o, r)| (o.name().to_string(), *r))
            .collect(),
        coefficients: diagnostics::conditions_from(&st, &values, &cov),
        correlations: diagnostics::correlations_from(&st, &values, &cov),
        identifiability,
        warnings,
        validation,
        validation_on: None,
        reader: Vec::new(),
        process_noise: fitted.fem.as_ref().map_or_else(Vec::new, process_noise_of),
        measurement_noise_var: match &fitted.fem {
            Some(f) => f
                .result
                .outputs
                .iter()
                .zip(&f.result.r)
                .map(|(o, r)| (o.name().to_string(), *r))
                .collect(),
            None => Vec::new(),
        },
        gain_kc_diag: fitted.fem.as_ref().map_or_else(Vec::new, |f| {
            f.kc_states.iter().map(|&i| STATE_NAMES[i].to_string()).zip(f.kc_diag.clone()).collect()
        }),
        initial_states: initial_states_name(initial_states).into(),
        estimated_initial_states,
        bootstrap: sigmas.bootstrap.clone(),
        frequency_domain: None,
        cross_check: None,
        sign_tests: Vec::new(),
        repeatability: None,
    }
}

/// The summary's warnings: how the fit ended when it did not converge on both criteria, the
/// sign checks (against the reported σ), the bootstrap's failed replicas and shrunk σ, and the
/// collinear regressors.
fn fit_warnings(
    result: &OeResult,
    sigmas: &Sigmas,
    identifiability: &Identifiability,
    values: &[Option<f64>],
) -> aeroident_io::warning::Warnings {
    let mut warnings: aeroident_io::warning::Warnings =
        termination_note(result).into_iter().chain(restart_note(result)).collect();
    let reported: Vec<Option<f64>> = sigmas.reported.iter().map(|s| Some(*s)).collect();
    warnings.extend(diagnostics::sign_warnings(&result.structure, values, &reported));
    warnings.extend(sigmas.bootstrap_skipped.clone());
    if let Some(b) = sigmas.bootstrap.as_ref().filter(|b| b.refits < b.requested) {
        warnings.push(format!(
            "bootstrap stopped on request after {} of {} replicas: its σ is the spread of those {}",
            b.refits, b.requested, b.refits
        ));
    }
    if let Some(b) = sigmas.bootstrap.as_ref().filter(|b| b.failed > 0) {
        warnings.push(format!(
            "bootstrap: {} of {} replicas failed and are not in the σ (the spread of the other {})",
            b.failed,
            b.refits,
            b.refits - b.failed
        ));
    }
    if let Some(b) = &sigmas.spread {
        warnings.extend(bootstrap_shrink_warnings(&result.names, &sigmas.coloured, &b.sigma));
    }
    for c in &identifiability.collinear_regressors {
        warnings.push(diagnostics::collinear_warning(c));
    }
    warnings
}

/// The simulated-output validation of an output-error result on `manoeuvres` (its residuals
/// `z − y` are the result's own; the prediction is `ŷ = z − e`; no prediction variance from
/// the parameters is formed, so the interval has the residual variance only).
///
/// `fit_r`: on a second record, the fitted record's noise variances `R` (per output, order of
/// `result.outputs`), the residual variance of the prediction interval.
pub(super) fn simulated_validation(
    result: &OeResult,
    manoeuvres: &[&[AirDataSample]],
    data: &str,
    fit_r: Option<&[f64]>,
) -> ValidationReport {
    let used_for_fit = fit_r.is_none();
    let ny = result.outputs.len();
    let samples: Vec<&AirDataSample> = manoeuvres.iter().flat_map(|m| m.iter()).collect();
    let st = result.structure;
    let controls = [(Term::De, "de"), (Term::Da, "da"), (Term::Dr, "dr")];
    let inputs: Vec<(&str, Vec<f64>)> = controls
        .iter()
        .filter(|(t, _)| st.params().any(|p| p.term == *t))
        .filter_map(|(t, name)| {
            let u: Option<Vec<f64>> = samples
                .iter()
                .map(|s| match t {
                    Term::De => s.de_rad,
                    Term::Da => s.da_rad,
                    _ => s.dr_rad,
                })
                .collect();
            u.map(|u| (*name, u))
        })
        .collect();
    let input_refs: Vec<(&str, &[f64])> = inputs.iter().map(|(n, u)| (*n, u.as_slice())).collect();
    let mut outputs = Vec::new();
    let mut notes = Vec::new();
    for (j, o) in result.outputs.iter().enumerate() {
        let z: Option<Vec<f64>> = samples.iter().map(|s| o.measured(s)).collect();
        let Some(z) = z else {
            notes.push(format!("{}: not validated: not measured in every sample", o.name()));
            continue;
        };
        if result.residuals.len() != z.len() * ny {
            notes.push(format!("{}: not validated: residuals do not match the samples", o.name()));
            continue;
        }
        let y_hat: Vec<f64> =
            z.iter().enumerate().map(|(k, z)| z - result.residuals[k * ny + j]).collect();
        let d = OutputData {
            name: o.name(),
            prediction: "simulated",
            y: &z,
            y_hat: &y_hat,
            y_hat_var: None,
            residual_var: fit_r.and_then(|r| r.get(j).copied()),
            segments: &result.manoeuvre_lengths,
            inputs: &input_refs,
        };
        match validate(&d) {
            Ok(v) => outputs.push(v),
            Err(e) => notes.push(format!("{}: not validated: {e}", o.name())),
        }
    }
    ValidationReport {
        data: data.to_string(),
        used_for_fit,
        prediction: "simulated: the output-error model integrated over each manoeuvre from its first sample's measured state with the estimated parameters; prediction interval from the residual variance only".into(),
        samples: samples.len(),
        outputs,
        notes,
    }
}

/// Applies a batch fit's parameters to a second record, or held-out `windows` of one (empty:
/// the whole record), with the prediction interval of the fit's noise variances `R`
/// (`--validate-on`, `--validate-window`): its manoeuvres are
/// simulated with the parameters fixed (initial states from each manoeuvre's first sample, no
/// re-estimation; the same outputs), and the simulated outputs validated. If the model cannot
/// be simulated on that record, the measured coefficients are predicted by equation error
/// instead (with the Cramér–Rao covariance), and the report says so.
///
/// # Errors
/// Fatal data errors and no usable sample of the second record.
pub fn validate_on<R: Read>(
    reader: FlightDataReader<R>,
    fitted: &BatchOutcome,
    windows: &[crate::window::TimeWindow],
) -> Result<ValidationReport, ReplayError> {
    let file = reader.file().to_string();
    let rec = crate::record::read_manoeuvres(reader, None, windows)?;
    let slices: Vec<&[AirDataSample]> = rec.manoeuvres.iter().map(Vec::as_slice).collect();
    let r = &fitted.result;
    let np = r.n_params;
    let simulated = simulate_at(&slices, r.structure, &r.outputs, &r.values[..np]);
    match simulated {
        Ok(res) => Ok(simulated_validation(&res, &slices, &file, Some(&r.r))),
        Err(e) => {
            let mut recorder = Recorder::for_structure(&r.structure);
            for m in &slices {
                recorder.new_segment();
                m.iter().for_each(|s| recorder.push(s));
            }
            let values: Vec<Option<f64>> = r.values[..np].iter().map(|v| Some(*v)).collect();
            let n = r.n();
            let cov = |i: usize, j: usize| Some(r.covariance[i * n + j]);
            let mut v = validate_coefficients(&recorder, &r.structure, &values, &cov, &file, None);
            v.used_for_fit = false;
            v.notes.insert(
                0,
                format!("the output-error model could not be simulated on this record ({e}); equation-error prediction of the measured coefficients instead"),
            );
            Ok(v)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record whose mapping lacks the constants the flight model needs (here the chord and
    /// the pitch inertia): the error names them as the mapping would (`cbar`, `Iyy`), not by
    /// the sample's internal field with a NaN (`Iyy_kgm2` = NaN), for the default model and
    /// for a model given.
    #[test]
    fn a_missing_constant_is_named_as_the_mapping_names_it() {
        let map = "[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nq = { column = \"q\", unit = \"rad/s\" }\ntheta = { column = \"th\", unit = \"rad\" }\nde = { column = \"de\", unit = \"rad\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\n";
        let mapping = Mapping::from_toml_str(map, "m.toml").unwrap();
        let mut csv = String::from("t,V,a,q,th,de\n");
        for k in 0..50 {
            let x = 0.01 * (k as f64 * 0.3).sin();
            csv.push_str(&format!("{},100,{},{x},{},{x}\n", k as f64 * 0.1, 0.05 + x, 0.05 + x));
        }
        for model in [None, ModelSpec::from_arg("longitudinal").ok()] {
            let reader = FlightDataReader::new(csv.as_bytes(), "r.csv", &mapping).unwrap();
            let Err(e) = crate::replay::fit::fit_records(
                vec![reader],
                &mapping,
                model,
                FitOptions::default(),
            ) else {
                panic!("fitted without the chord and the inertia");
            };
            let text = e.to_string();
            assert!(text.contains("is not in the mapping m.toml"), "{text}");
            assert!(text.contains("`Iyy`") || text.contains("`cbar`"), "{text}");
            assert!(
                !text.contains("NaN") && !text.contains("_kgm2") && !text.contains("cbar_m"),
                "{text}"
            );
        }
    }

    /// A bootstrap's replica count is refused outside 2 to [`MAX_BOOTSTRAP_REFITS`] by a fit
    /// before any record is read or replica allocated (4294967295 replicas once allocated
    /// 137 GB and aborted): the fit here has no record at all, so only the check can answer.
    #[test]
    fn bootstrap_refit_counts_are_limited_before_reading() {
        assert_eq!(check_bootstrap_refits(2), Ok(()));
        assert_eq!(check_bootstrap_refits(MAX_BOOTSTRAP_REFITS), Ok(()));
        for n in [0, 1, MAX_BOOTSTRAP_REFITS + 1, u32::MAX as usize, usize::MAX] {
            let options = FitOptions { bootstrap_refits: Some(n), ..FitOptions::default() };
            let map = "[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\n";
            let mapping = Mapping::from_toml_str(map, "m.toml").unwrap();
            let readers: Vec<FlightDataReader<&[u8]>> = Vec::new();
            let Err(e) = crate::replay::fit::fit_records(readers, &mapping, None, options) else {
                panic!("{n} refits accepted");
            };
            let ReplayError::Option { option: "bootstrap", reason } = &e else {
                panic!("expected the bootstrap option named, got {e}");
            };
            assert!(reason.starts_with(&format!("{n} refits")), "{reason}");
            let limit = format!("more than the {MAX_BOOTSTRAP_REFITS}");
            assert_eq!(reason.contains(&limit), n > MAX_BOOTSTRAP_REFITS, "{reason}");
        }
    }

    /// Flagged below 1/4 of the coloured σ, not at or above it, and never without a coloured
    /// σ; the warning names the unknown and the ratio.
    #[test]
    fn a_bootstrap_sigma_far_below_the_coloured_one_is_flagged() {
        let names: Vec<String> = ["Cm_alpha", "x0_m1_q_rad_s", "x0_m1_phi_rad", "Cl_p"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let coloured = [Some(1.0), Some(2.0), Some(0.015), None];
        let bootstrap = [0.3, 0.5, 0.00066, 1e-9];
        let w = bootstrap_shrink_warnings(&names, &coloured, &bootstrap);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("x0_m1_phi_rad") && w[0].contains("0.04×"), "{}", w[0]);
    }
}
