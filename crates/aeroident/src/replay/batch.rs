//! Batch output-error estimation of a whole record (`aeroident replay --estimator oe`): the
//! post-flight reference a flight-test engineer compares the real-time estimators to.
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
use aeroident_estimators::flight_model::FlightModel;
use aeroident_estimators::output_error::{OeConfig, OeError, OeResult, fit};
use aeroident_estimators::{AirDataSample, ModelStructure};
use aeroident_io::{FlightDataReader, Mapping, ModelSpec, RecordEvent, Rejection};
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
}

/// One parameter of the batch summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchParameter {
    /// Name (`Cm_alpha` …).
    pub name: String,
    /// Estimate.
    pub estimate: f64,
    /// Reported σ: coloured-residual σ where available, else Cramér–Rao.
    pub std_error: f64,
    /// Cramér–Rao σ (`sqrt(diag M⁻¹)`).
    pub crb_sigma: f64,
    /// Coloured-residual σ, when the correction is positive.
    pub coloured_sigma: Option<f64>,
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

/// `summary.json` of a batch fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchSummary {
    /// `oe`.
    pub estimator: String,
    /// The model's name.
    pub model: String,
    /// `converged`.
    pub status: String,
    /// Rows read.
    pub samples_read: usize,
    /// Rows rejected (listed in `rejections`).
    pub samples_rejected: usize,
    /// Every rejected row and gap.
    pub rejections: Vec<Rejection>,
    /// Manoeuvres (separate initial conditions), split at the record's gaps.
    pub manoeuvres: usize,
    /// Wall time of the fit, s.
    pub fit_wall_s: f64,
    /// Iteration log.
    pub iterations: Vec<BatchIteration>,
    /// The structure's parameters.
    pub parameters: Vec<BatchParameter>,
    /// Residual RMS per fitted output (`name`, value in the output's unit).
    pub residual_rms: Vec<(String, f64)>,
}

/// The richest preset the flight model can integrate from the record's first sample.
fn default_model(first: &AirDataSample, mapping: &Mapping) -> Result<ModelSpec, ReplayError> {
    let mut why = Vec::new();
    for name in ModelStructure::PRESETS {
        let Some(spec) = ModelSpec::preset(name) else { continue };
        match FlightModel::new(spec.structure).and_then(|m| m.inputs(first).map(|_| ())) {
            Ok(()) => return Ok(spec),
            Err(e) => why.push(format!("`{name}`: {e}")),
        }
    }
    Err(ReplayError::Model(format!(
        "no preset model can be fitted by output error from the channels of {} ({})",
        mapping.file,
        why.join(" | ")
    )))
}

/// Reads the whole record, splits it at gaps and fits it by output error.
///
/// # Errors
/// Fatal data errors, no usable samples, no supported model, and a fit that fails or does not
/// converge ([`ReplayError::Model`] with the reason and the iteration count).
pub fn fit_record<R: Read>(
    reader: FlightDataReader<R>,
    mapping: &Mapping,
    model: Option<ModelSpec>,
) -> Result<BatchOutcome, ReplayError> {
    let file = reader.file().to_string();
    let mut manoeuvres: Vec<Vec<AirDataSample>> = vec![Vec::new()];
    let mut rejections = Vec::new();
    let (mut read, mut rejected) = (0usize, 0usize);
    for event in reader {
        match event? {
            RecordEvent::Sample { sample, .. } => {
                read += 1;
                if let Some(m) = manoeuvres.last_mut() {
                    m.push(sample);
                }
            }
            RecordEvent::Rejected { row, problem } => {
                read += 1;
                rejected += 1;
                rejections.push(Rejection { row, reason: problem.to_string() });
            }
            RecordEvent::Gap { row, dt_s, nominal_dt_s } => {
                rejections.push(Rejection {
                    row,
                    reason: format!(
                        "gap: {dt_s} s before this row (nominal {nominal_dt_s} s); a new manoeuvre with its own initial state"
                    ),
                });
                if manoeuvres.last().is_some_and(|m| !m.is_empty()) {
                    manoeuvres.push(Vec::new());
                }
            }
        }
    }
    manoeuvres.retain(|m| !m.is_empty());
    let Some(first) = manoeuvres.first().and_then(|m| m.first()).copied() else {
        return Err(aeroident_io::FlightDataError::NoSamples {
            file,
            rejected,
            first: rejections.iter().take(3).map(|r| (r.row, r.reason.clone())).collect(),
        }
        .into());
    };
    let model = match model {
        Some(m) => m,
        None => default_model(&first, mapping)?,
    };
    // The default start: equation-error least squares on the measured coefficients (the
    // generic priors where that fails), never a reference result.
    let config = OeConfig::new(model.structure);
    let slices: Vec<&[AirDataSample]> = manoeuvres.iter().map(Vec::as_slice).collect();
    let t0 = std::time::Instant::now();
    let result = fit(&slices, &config).map_err(|e| match e {
        OeError::NotConverged { reason, result } => ReplayError::Model(format!(
            "output error did not converge ({reason:?}) after {} iterations: no result",
            result.iterations.len()
        )),
        OeError::Estimator(e) => ReplayError::Model(format!("output error: {e}")),
    })?;
    let fit_wall_s = t0.elapsed().as_secs_f64();
    let parameters = (0..result.n_params)
        .map(|i| {
            let coloured = result.sigma_coloured.as_ref().map(|s| s[i]);
            BatchParameter {
                name: result.names[i].clone(),
                estimate: result.values[i],
                std_error: coloured.unwrap_or(result.sigma[i]),
                crb_sigma: result.sigma[i],
                coloured_sigma: coloured,
            }
        })
        .collect();
    let summary = BatchSummary {
        estimator: "oe".into(),
        model: model.name.clone(),
        status: "converged".into(),
        samples_read: read,
        samples_rejected: rejected,
        rejections,
        manoeuvres: slices.len(),
        fit_wall_s,
        iterations: result
            .iterations
            .iter()
            .map(|it| BatchIteration {
                iteration: it.iteration,
                ln_det_r: it.ln_det_r,
                max_step_sigma: it.max_step_sigma,
            })
            .collect(),
        parameters,
        residual_rms: result
            .outputs
            .iter()
            .zip(&result.residual_rms)
            .map(|(o, r)| (o.name().to_string(), *r))
            .collect(),
    };
    Ok(BatchOutcome { model, result, summary })
}
