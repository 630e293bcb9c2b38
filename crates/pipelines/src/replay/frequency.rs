//! Frequency-domain output error of a whole record (`aeroident replay --estimator fdoe`):
//! [`aeroident_estimators::output_error::frequency`] on the record's manoeuvres, reported in
//! the batch fits' `summary.json` shape ([`BatchSummary`]) so the report, the results table
//! and the cross-check read it as they read `oe`.
//!
//! The parameters the linear model does not see (drag, zero-order, `V` and product terms) are
//! reported with a `null` estimate and σ. The validation and the model-vs-measured figure
//! simulate the nonlinear flight model over each manoeuvre with the fdoe estimates and the
//! unseen parameters at their equation-error values (the time-domain fit's own start), as the
//! filter-error method's are simulated; a model that cannot be simulated open loop is said so
//! in the warnings and leaves the figure out.

use super::ReplayError;
use super::batch::{
    BatchIteration, BatchOutcome, BatchParameter, BatchSummary, FitOptions, FrequencyDomainSummary,
    default_model, output_traces, simulate_at, simulated_validation,
};
use super::cross_check::ParameterEstimate;
use super::diagnostics;
use super::prediction::Recorder;
use super::repeatability::{CONVERGED, SoloFit};
use crate::record::Manoeuvres;
use aeroident_estimators::AirDataSample;
use aeroident_estimators::flight_model::STATE_NAMES;
use aeroident_estimators::output_error::OeResult;
use aeroident_estimators::output_error::frequency::{
    FdoeConfig, FdoeResult, MAX_INTERVAL_DEVIATION, fit,
};
use aeroident_io::message::short;
use aeroident_io::{Mapping, ModelSpec, ParameterResult, StdErrorSource};

/// Fits the record `rec` (read and split by the caller) by frequency-domain output error over
/// `band_hz` with `model` (else the default preset) and reports it as a batch fit.
///
/// # Errors
/// No supported model; the fit fails ([`ReplayError::Model`] with the reason: a band without
/// frequencies, non-uniform sampling, nothing identifiable …).
pub(super) fn fit_fdoe(
    rec: Manoeuvres,
    file: &str,
    mapping: &Mapping,
    model: Option<ModelSpec>,
    band_hz: (f64, f64),
    options: &FitOptions,
) -> Result<BatchOutcome, ReplayError> {
    let model = match model {
        Some(m) => m,
        None => default_model(&rec.manoeuvres[0][0], mapping)?,
    };
    let (model, level_note) = super::sideslip_level(model, &rec.manoeuvres[0][0]);
    let slices: Vec<&[AirDataSample]> = rec.manoeuvres.iter().map(Vec::as_slice).collect();
    crate::structure::check_knots_in_range(&model.structure, &slices, &model.name)
        .map_err(ReplayError::Model)?;
    let mut config = FdoeConfig { band_hz, ..FdoeConfig::new(model.structure) };
    if let Some(n) = options.max_iterations {
        config.max_iterations = n;
    }
    config.stop.clone_from(&options.stop);
    let t0 = std::time::Instant::now();
    let (bridged, bridge_note) = bridged(&slices);
    let uniform: Vec<&[AirDataSample]> = match &bridged {
        Some(b) => b.iter().map(Vec::as_slice).collect(),
        None => slices.clone(),
    };
    let fd = fit(&uniform, &config).map_err(|e| ReplayError::Model(e.to_string()))?;
    let wall = t0.elapsed().as_secs_f64();
    let mut warnings: Vec<String> =
        band_clipped(band_hz, &uniform, fitted_band(&fd)).into_iter().collect();
    warnings.extend(bridge_note);
    let simulated = match simulate_at(&slices, model.structure, &fd.outputs, &fd.values) {
        Ok(r) => Some(r),
        Err(e) => {
            warnings.push(format!(
                    "fdoe: the nonlinear model at the estimates cannot be simulated open loop ({e}); no time-domain validation or figure"
                ));
            None
        }
    };
    let validation = match &simulated {
        Some(r) => simulated_validation(r, &slices, file, None),
        None => super::prediction::ValidationReport {
            data: file.to_string(),
            used_for_fit: true,
            prediction: "none: the model could not be simulated".into(),
            samples: slices.iter().map(|m| m.len()).sum(),
            outputs: Vec::new(),
            notes: Vec::new(),
        },
    };
    let traces = simulated.as_ref().map_or_else(Vec::new, |r| output_traces(r, &slices));
    let (rejections, unlisted) = rec.rejections.finish();
    let mut summary = summarise(&model, &fd, &slices, wall, validation);
    if uniform.len() > 1 {
        super::batch::apply_repeatability(solo_fits(&uniform, &config), &mut summary);
    }
    summary.samples_read = rec.read;
    summary.samples_rejected = rec.rejected;
    summary.rejections = rejections;
    summary.warnings.extend(unlisted);
    summary.warnings.extend(warnings);
    summary.warnings.extend(level_note);
    summary.warnings.extend(rec.notes.iter().cloned());
    if !options.estimates_only {
        let (sign_tests, sign_warnings) = super::sign_tests::checked(&slices, mapping);
        summary.sign_tests = sign_tests;
        summary.warnings.extend(sign_warnings);
    }
    if let Some(c) = &options.compat {
        summary.warnings.extend(c.warnings());
    }
    let result = simulated.map_or_else(|| bare_result(&fd), |r| with_estimates(r, &fd));
    let options = options.clone();
    Ok(BatchOutcome { model, result, summary, traces, frequency: Some(fd), options })
}

/// Each (bridged) manoeuvre fitted alone over the same band with the same model, for the
/// repeatability test ([`super::repeatability`]): the estimated parameters and their
/// Cramér–Rao σ (the ones fdoe reports) of a converged fit.
fn solo_fits(uniform: &[&[AirDataSample]], config: &FdoeConfig) -> Vec<SoloFit> {
    use rayon::prelude::*;
    uniform
        .par_iter()
        .enumerate()
        .map(|(k, m)| {
            let mut solo = SoloFit::of(k, m);
            match fit(&[m], config) {
                Err(e) => solo.status = format!("failed: {e}"),
                Ok(fd) if !fd.termination.is_converged() => solo.status = "not converged".into(),
                Ok(fd) => {
                    solo.estimates = (0..fd.values.len())
                        .filter_map(|i| {
                            let s = fd.sigma[i].filter(|s| s.is_finite() && *s > 0.0)?;
                            Some(ParameterEstimate::new(&fd.names[i], fd.values[i], s))
                        })
                        .collect();
                    solo.status = CONVERGED.into();
                }
            }
            solo
        })
        .collect()
}

/// The time-domain simulation's result at the fdoe estimates, carrying the fdoe σ and
/// termination (σ 0 for the parameters not estimated: the CLI's table and Python read the
/// summary's `null` instead).
fn with_estimates(mut r: OeResult, fd: &FdoeResult) -> OeResult {
    let np = fd.values.len();
    r.values[..np].copy_from_slice(&fd.values);
    for (s, f) in r.sigma.iter_mut().zip(&fd.sigma) {
        *s = f.unwrap_or(0.0);
    }
    r.sigma_coloured = None;
    r.sigma_coloured_prewhitened = None;
    r.sigma_coloured_truncated = None;
    r.iterations.clone_from(&fd.iterations);
    r.termination = fd.termination;
    r.start.clone_from(&fd.start);
    r
}

/// A result without a time-domain simulation (the model could not be simulated).
fn bare_result(fd: &FdoeResult) -> OeResult {
    let np = fd.values.len();
    OeResult {
        structure: fd.structure,
        names: fd.names.clone(),
        n_params: np,
        values: fd.values.clone(),
        sigma: fd.sigma.iter().map(|s| s.unwrap_or(0.0)).collect(),
        sigma_coloured: None,
        sigma_coloured_prewhitened: None,
        coloured_lag: 0,
        coloured_ar_order: 0,
        sigma_coloured_truncated: None,
        covariance: fd.covariance.iter().map(|c| c.unwrap_or(0.0)).collect(),
        correlation: vec![0.0; np * np],
        outputs: fd.outputs.clone(),
        r: Vec::new(),
        residual_rms: Vec::new(),
        residual_mean: Vec::new(),
        residuals: Vec::new(),
        manoeuvre_lengths: Vec::new(),
        iterations: fd.iterations.clone(),
        start: fd.start.clone(),
        restart: None,
        termination: fd.termination,
        unmeasured_states: Vec::new(),
        dominance: None,
    }
}

/// The batch summary of an fdoe fit (the record's row counts are the caller's).
fn summarise(
    model: &ModelSpec,
    fd: &FdoeResult,
    slices: &[&[AirDataSample]],
    fit_wall_s: f64,
    validation: super::prediction::ValidationReport,
) -> BatchSummary {
    let st = model.structure;
    let np = fd.values.len();
    let values: Vec<Option<f64>> =
        (0..np).map(|i| fd.estimated[i].then_some(fd.values[i])).collect();
    let parameters = (0..np)
        .map(|i| BatchParameter {
            result: ParameterResult::new(fd.names[i].clone(), values[i], fd.sigma[i], None, None)
                .with_source(StdErrorSource::CramerRao)
                .with_crb_std_error(fd.sigma[i]),
            coloured_std_error: None,
            prewhitened_std_error: None,
            bootstrap_std_error: None,
            bootstrap_bias: None,
        })
        .collect();
    let cov = |i: usize, j: usize| fd.covariance[i * np + j];
    let mut recorder = Recorder::for_structure(&model.structure);
    for m in slices {
        recorder.new_segment();
        m.iter().for_each(|s| recorder.push(s));
    }
    let identifiability = diagnostics::identifiability(&st, &cov, &recorder, &values);
    let mut warnings: aeroident_io::warning::Warnings =
        super::batch::termination_note_of(fd.termination, &fd.iterations).into_iter().collect();
    warnings.extend(diagnostics::sign_warnings(&st, &values, &fd.sigma));
    let not_estimated: Vec<String> =
        (0..np).filter(|&i| !fd.estimated[i]).map(|i| fd.names[i].clone()).collect();
    BatchSummary {
        schema_version: aeroident_io::SCHEMA_VERSION,
        estimator: "fdoe".into(),
        model: model.name.clone(),
        alpha_knots_rad: model.structure.knots().as_slice().to_vec(),
        status: fd.termination.status().into(),
        status_reason: super::batch::termination_note_of(fd.termination, &fd.iterations),
        samples_read: 0,
        samples_rejected: 0,
        rejections: Vec::new(),
        manoeuvres: slices.len(),
        fit_wall_s,
        iterations: fd.iterations.iter().map(BatchIteration::from).collect(),
        parameters,
        residual_rms: Vec::new(),
        coefficients: diagnostics::conditions_from(&st, &values, &cov),
        correlations: diagnostics::correlations_from(&st, &values, &cov),
        identifiability,
        warnings,
        validation,
        validation_on: None,
        reader: Vec::new(),
        process_noise: Vec::new(),
        measurement_noise_var: Vec::new(),
        gain_kc_diag: Vec::new(),
        initial_states: "transient terms (x_Δ per manoeuvre)".into(),
        estimated_initial_states: Vec::new(),
        bootstrap: None,
        cross_check: None,
        sign_tests: Vec::new(),
        repeatability: None,
        frequency_domain: Some(FrequencyDomainSummary {
            band_hz: fd.band_hz,
            band_fitted_hz: fitted_band(fd),
            frequencies: fd
                .frequencies_hz
                .iter()
                .map(|f| (f.len(), f[0], f[f.len() - 1]))
                .collect(),
            states: fd.states.iter().map(|&i| STATE_NAMES[i].to_string()).collect(),
            inputs: fd.inputs.iter().map(|s| s.to_string()).collect(),
            outputs: fd.outputs.iter().map(|o| o.name().to_string()).collect(),
            residual_spectral_variance: fd
                .outputs
                .iter()
                .zip(&fd.s_vv)
                .map(|(o, s)| (o.name().to_string(), *s))
                .collect(),
            flight_conditions: fd.flight_conditions.clone(),
            not_estimated,
        }),
    }
}

/// The band fitted: the lowest and highest frequency any manoeuvre contributed, Hz.
fn fitted_band(fd: &FdoeResult) -> (f64, f64) {
    let lo =
        fd.frequencies_hz.iter().filter_map(|f| f.first()).fold(f64::INFINITY, |a, b| a.min(*b));
    let hi = fd.frequencies_hz.iter().filter_map(|f| f.last()).fold(0.0, |a: f64, b| a.max(*b));
    (lo, hi)
}

/// Most samples in a row [`bridged`] puts back: two or three adjacent wild points the spike
/// screen removed. The reader splits a record at a longer interval between its rows (a gap,
/// [`aeroident_io::flight_data::ONE_SAMPLE_HOLE_MAX`]), so a longer hole inside a manoeuvre
/// is the screen's: that many wild points in a row is a fault, not noise, and stays a hole
/// for the fit to refuse.
const MAX_BRIDGED_SAMPLES: usize = 3;

/// The manoeuvres with each hole of at most [`MAX_BRIDGED_SAMPLES`] missing samples bridged
/// by linear interpolation ([`AirDataSample::between`]), and a warning that counts them and
/// names the first; `(None, None)` when no manoeuvre has one. A hole is an interval of `n ≥ 2`
/// times the manoeuvre's median interval, to the tolerance the transform allows
/// ([`MAX_INTERVAL_DEVIATION`] per interval); its `n − 1` samples go back on the grid. The
/// discrete Fourier transform needs uniform sampling, and the spike screen (on by default)
/// and the reader remove a wild point or a bad row instead of replacing it; interpolation
/// reconstructs missing or bad points (Klein & Morelli 2006, §11.3), here for the transform
/// only.
fn bridged(slices: &[&[AirDataSample]]) -> (Option<Vec<Vec<AirDataSample>>>, Option<String>) {
    let mut filled: Vec<Vec<AirDataSample>> = Vec::with_capacity(slices.len());
    let (mut count, mut first) = (0usize, None::<f64>);
    for m in slices {
        let dt = median_interval(m);
        let mut out = Vec::with_capacity(m.len());
        for (k, s) in m.iter().enumerate() {
            let prev = k.checked_sub(1).map(|j| &m[j]);
            if let Some((n, prev)) =
                dt.zip(prev).and_then(|(dt, p)| Some((hole(s.t_s - p.t_s, dt)?, p)))
            {
                let at = |i: usize| AirDataSample::between(prev, s, i as f64 / n as f64);
                out.extend((1..n).map(at));
                count += n - 1;
                first.get_or_insert(at(1).t_s);
            }
            out.push(*s);
        }
        filled.push(out);
    }
    let Some(t) = first else { return (None, None) };
    let note = format!(
        "fdoe: {count} sample(s) missing from the record's uniform sampling (a row rejected or a spike the screen removed; the first at t = {} s) bridged by linear interpolation for the Fourier transform; the validation and the figure use the samples as read",
        short(t)
    );
    (Some(filled), Some(note))
}

/// The intervals `n` (2 to [`MAX_BRIDGED_SAMPLES`] + 1) that an interval of `d` s spans on a
/// grid of `dt` s, when it is a whole number of them within the transform's tolerance.
fn hole(d: f64, dt: f64) -> Option<usize> {
    let n = (d / dt).round();
    let whole = (d - n * dt).abs() <= n * MAX_INTERVAL_DEVIATION * dt;
    (whole && n >= 2.0 && n <= (MAX_BRIDGED_SAMPLES + 1) as f64).then_some(n as usize)
}

/// The median interval between a manoeuvre's samples, s; `None` for fewer than two samples
/// or a median that is not positive.
fn median_interval(m: &[AirDataSample]) -> Option<f64> {
    let mut dts: Vec<f64> = m.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
    dts.sort_by(f64::total_cmp);
    dts.get(dts.len() / 2).copied().filter(|d| *d > 0.0)
}

/// The warning of a band asked above the record's Nyquist frequency (the highest of its
/// manoeuvres'), where the fit could only stop short of it; `None` when it was not.
fn band_clipped(
    asked: (f64, f64),
    slices: &[&[AirDataSample]],
    fitted: (f64, f64),
) -> Option<String> {
    let nyquist = slices
        .iter()
        .filter(|m| m.len() > 1)
        .map(|m| 0.5 * (m.len() - 1) as f64 / (m[m.len() - 1].t_s - m[0].t_s))
        .fold(0.0, f64::max);
    (asked.1 >= nyquist).then(|| {
        format!(
            "--band-hz {}:{} reaches above the record's Nyquist frequency {} Hz: the fit stopped at {} Hz (band_fitted_hz in summary.json); lower the band's upper edge",
            short(asked.0),
            short(asked.1),
            short(nyquist),
            short(fitted.1)
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A manoeuvre at 0.01 s with the rows at 0.05 s (one), 0.10–0.12 s (three) and
    /// 0.20–0.23 s (four) missing: the first two holes are bridged (four samples, each where a
    /// uniform record has it, the lone one halfway between its neighbours), the run of four is
    /// left for the fit to refuse; a manoeuvre with none missing is not copied.
    #[test]
    fn short_holes_are_bridged_and_longer_ones_left() {
        let missing = |k: usize| k == 5 || (10..=12).contains(&k) || (20..=23).contains(&k);
        let at = |k: usize| AirDataSample {
            t_s: 0.01 * k as f64,
            vt_mps: 100.0 + k as f64,
            de_rad: Some(0.001 * k as f64),
            ..Default::default()
        };
        let m: Vec<AirDataSample> = (0..30).filter(|&k| !missing(k)).map(at).collect();
        let (filled, note) = bridged(&[&m]);
        let filled = filled.expect("bridged");
        let t: Vec<f64> = filled[0].iter().map(|s| s.t_s).collect();
        let expected: Vec<f64> =
            (0..30).filter(|k| !(20..=23).contains(k)).map(|k| 0.01 * k as f64).collect();
        assert_eq!(t.len(), expected.len());
        assert!(t.iter().zip(&expected).all(|(a, b)| (a - b).abs() < 1e-12), "{t:?}");
        let hole = filled[0].iter().find(|s| (s.t_s - 0.05).abs() < 1e-12).unwrap();
        assert!((hole.vt_mps - 105.0).abs() < 1e-9 && (hole.de_rad.unwrap() - 0.005).abs() < 1e-12);
        let note = note.unwrap();
        assert!(
            note.starts_with("fdoe: 4 sample(s) missing") && note.contains("t = 0.05 s"),
            "{note}"
        );
        let whole: Vec<AirDataSample> = (0..30).map(at).collect();
        assert_eq!(bridged(&[&whole]), (None, None));
    }
}
