//! The batch (post-flight) estimators of `aeroident run` and `aeroident montecarlo`: output
//! error (`[[estimator]] kind = "oe"`) and the filter-error method (`kind = "fem"`, output
//! error with process noise, [`aeroident_estimators::output_error::filter_error`]), fitted
//! after the flight to the air-data samples the real-time estimators saw.
//!
//! # What is fitted
//!
//! The recorded sample stream ([`super::air_data`]: the same noisy, smoothed, lag-aligned
//! samples every sample-driven estimator is fed), restricted to the **window after the last
//! change of the truth** (the damage; the whole record without one): the samples whose time
//! stamp is at least `t_change + lag`, so that the matched smoother's window (± the lag around
//! the time stamp) holds no pre-damage data. One manoeuvre, fitted by
//! [`aeroident_estimators::output_error::fit`] with the configuration of `replay --estimator
//! oe` ([`crate::replay::batch::oe_config`]: the noise covariance estimated with the
//! parameters (ML relaxation), the equation-error start) on the outputs of the structure's
//! flight model except the differentiated `ṗ q̇ ṙ` (V, α, β, p, q, r, φ, θ, ax, ay, az for
//! six-axis: the outputs of the Cramér–Rao prediction of the campaign), and the initial
//! condition of the window:
//! - `initial_states = "first-sample"` (default, as replay): fixed at the window's first
//!   sample's measurements (Jategaonkar's default);
//! - `initial_states = "estimate"`: the window's initial state is estimated with the
//!   parameters, starting from its first sample (Jategaonkar 2015 ch. 4).
//!
//! The step is Jategaonkar's relaxation ([`StepKind::Relaxation`], option `step =
//! "relaxation" | "concentrated"`) with up to [`MAX_ITERATIONS`] iterations, not the
//! replay's concentrated step with 50: the unmodelled turbulence leaves large, structured
//! residuals, so Gauss–Newton converges only linearly, and the concentrated step (whose
//! Hessian drops the per-output gradient products) overshoots and stalls with the
//! Levenberg–Marquardt damping cycling (measured in docs/uncertainty.md, "Output error in the
//! campaign"). The convergence test is the estimators crate's, unchanged. A fit that still does
//! not converge is reported, never averaged in.
//!
//! # What is reported
//!
//! The final estimate of each structure parameter is the fit's value and its σ the σ the
//! replay reports ([`crate::replay::batch::reported_sigma`]: coloured-residual where formed,
//! Cramér–Rao otherwise); both are logged at the last sample only (a batch estimate does not
//! exist before the end of the flight), so the time-history metrics (time to ±10 %, …) are
//! `null` for it: the report marks the channel `batch`. A fit that fails or does not converge is
//! the channel's failure, with the reason; its estimates stay `null`.
//!
//! **Bootstrap** (`oe` option `bootstrap_refits = N`, with `samples = "raw"`): the reported σ
//! is the parametric bootstrap's ([`crate::replay::batch::bootstrap_sigma`]: the noise levels
//! from a filter-error fit of the same window, `N` replicas flown through the fitted model and
//! refitted; replica `b` seeded `BOOTSTRAP_SEED ^ bits of the window's first α and V + b`, so
//! every run draws its own), logged as the candidate `bootstrap`. It costs one filter-error
//! fit and `N` output-error fits per run (docs/uncertainty.md, "Output error: the parametric
//! bootstrap").
//!
//! # The filter-error method (`kind = "fem"`)
//!
//! The same window, outputs and `initial_states` option as `oe`; process noise (one `F` per
//! state equation, estimated) on the translational air-data states `V, α, β` by default (the
//! Dryden gusts of the simulation are translational: their derivatives drive the air-relative
//! `V, α, β` equations, module doc of `filter_error`), option `process_noise = "V,alpha,beta"`
//! (any of `V alpha beta p q r phi theta`). Its σ is the coloured-residual σ where formed, as
//! for `oe` (the innovations of an inexact filter are autocorrelated: on the F-16 campaign the
//! Cramér–Rao σ is 0.34–0.76 of the scatter, the coloured 0.68–1.69; docs/uncertainty.md,
//! "Filter-error method: σ and bias"), and the log carries the estimated `F`.
//!
//! **Samples** (option `samples = "raw" | "smoothed"`): `fem` fits by default the **unsmoothed**
//! samples ([`super::air_data::AirDataSampler::raw`]: same time stamps, sensor noise, no matched
//! smoother), `oe` the smoothed ones the real-time estimators see. The matched smoother (0.2 s
//! window at the default 21 points) makes the measurement errors strongly correlated from one
//! 0.01 s sample to the next; output error only loses efficiency from that (its coloured σ
//! accounts for it), but the filter-error method's one-step predictor exploits it: fitted to
//! the smoothed samples its `F` grows without bound (measured on the default scenario: `F_V`
//! 3.6·10⁶ m/s/√s, the innovations of α ten times below the vane noise, no convergence), the
//! filter following the smoothed measurements. Batch methods use no differentiated channel, so
//! they do not need the smoother.

use aeroident_estimators::flight_model::{Output, StateSet};
use aeroident_estimators::output_error::filter_error::FemConfig;
use aeroident_estimators::output_error::{InitialStates, OeConfig, OeResult, StepKind};
use aeroident_estimators::sample::AirDataSample;
use serde::Serialize;

use crate::estimators::{EstimatorKind, OptionError, SampleEstimatorSpec};
use crate::replay::batch::FitOptions;
use crate::replay::batch::{
    BOOTSTRAP_SEED, MAX_ITERATIONS, bootstrap_sigma, check_bootstrap_refits, fem_reported_sigma,
    fit_fem_manoeuvres, fit_manoeuvres, initial_states_name, oe_config, process_noise_of,
    reported_sigma, termination_note,
};

/// The configuration of a batch entry: output error or the filter-error method.
#[derive(Debug, Clone, PartialEq)]
pub enum BatchConfig {
    /// `kind = "oe"`, with the parametric bootstrap's refits when asked for (option
    /// `bootstrap_refits = N`; its σ is then the reported one).
    Oe {
        /// The output-error configuration.
        config: OeConfig,
        /// Refits of the parametric bootstrap
        /// ([`crate::replay::batch::bootstrap_sigma`]), if any.
        bootstrap_refits: Option<usize>,
    },
    /// `kind = "fem"`.
    Fem(FemConfig),
}

impl BatchConfig {
    /// The output-error part (for `fem`, the base it extends).
    pub fn oe(&self) -> &OeConfig {
        match self {
            BatchConfig::Oe { config, .. } => config,
            BatchConfig::Fem(c) => &c.oe,
        }
    }

    /// The `kind` of the entry (`oe` or `fem`).
    pub fn kind(&self) -> &'static str {
        match self {
            BatchConfig::Oe { .. } => "oe",
            BatchConfig::Fem(_) => "fem",
        }
    }
}

/// The configuration of a batch entry (`kind = "oe"` or `"fem"`): [`oe_config`] of its
/// structure with the entry's options as a recorded flight's fit takes them
/// ([`FitOptions::from_pairs`], the one parser; [`EstimatorKind::fit_options`] lists each
/// method's), over the experiment's own defaults: Jategaonkar's relaxation step
/// ([`StepKind::Relaxation`]; `step = "concentrated"` for the other) and at most
/// [`MAX_ITERATIONS`] iterations. The outputs are the structure's flight model's without the
/// differentiated `ṗ q̇ ṙ` (they are computed from the gyros already fitted, not independent
/// measurements: fitting both would count the gyro noise twice under the diagonal `R`).
/// `samples = "raw" | "smoothed"` is the experiment's own option (which samples it records);
/// a bootstrap needs the raw ones.
///
/// # Errors
/// A message naming an unknown option or value, an option the method does not have; `fdoe`,
/// which fits recorded flights only.
pub fn config(spec: &SampleEstimatorSpec) -> Result<BatchConfig, String> {
    let name = spec.kind.as_str();
    let kind = match <EstimatorKind as crate::Named>::from_name(name) {
        Some(k @ (EstimatorKind::Oe | EstimatorKind::Fem)) => k,
        Some(EstimatorKind::Fdoe) => {
            return Err("fdoe: frequency-domain output error fits a recorded flight (`aeroident replay --estimator fdoe`); the closed-loop experiment's batch fits are `oe` and `fem`".into());
        }
        _ => return Err(format!("{name}: not a batch fit (`oe` or `fem`)")),
    };
    let mut options = entry_options(kind, &spec.options)?;
    options.step.get_or_insert(StepKind::Relaxation);
    options.max_iterations.get_or_insert(MAX_ITERATIONS);
    let mut c = oe_config(spec.model);
    c.initial_states = InitialStates::FirstSample;
    let set = StateSet::of(&spec.model).map_err(|e| format!("{name}: {e}"))?;
    c.outputs = Some(
        set.outputs()
            .iter()
            .copied()
            .filter(|o| !matches!(o, Output::Pdot | Output::Qdot | Output::Rdot))
            .collect(),
    );
    if kind == EstimatorKind::Fem {
        let mut f = FemConfig::new(spec.model);
        f.oe = c;
        options.apply_to_fem(&mut f);
        return Ok(BatchConfig::Fem(f));
    }
    options.apply_to_oe(&mut c);
    if options.bootstrap_refits.is_some() && !spec.raw_samples() {
        return Err("oe: `bootstrap_refits` needs `samples = \"raw\"`: the bootstrap's noise levels come from a filter-error fit, which needs measurement errors white from sample to sample (module doc)".into());
    }
    Ok(BatchConfig::Oe { config: c, bootstrap_refits: options.bootstrap_refits })
}

/// The fit options of an `[[estimator]]` entry of batch `kind` (every key but `samples`,
/// which is checked here), parsed and checked as a recorded flight's.
///
/// # Errors
/// A message naming the entry's kind, the option and what it must be.
fn entry_options(kind: EstimatorKind, table: &toml::Table) -> Result<FitOptions, String> {
    let name = kind.name();
    if let Some(v) = table.get("samples")
        && !matches!(v.as_str(), Some("raw" | "smoothed"))
    {
        return Err(format!("{name}: `samples` must be \"raw\" or \"smoothed\", got {v}"));
    }
    let pairs = table.iter().filter(|(k, _)| *k != "samples").map(|(k, v)| (k.as_str(), v.clone()));
    let options = FitOptions::from_pairs(kind, pairs).map_err(|e| match e {
        OptionError::Unknown { key, .. } => crate::estimators::unknown_option(kind, &key),
        OptionError::Invalid { key, reason, .. } => format!("{name}: `{key}`: {reason}"),
    })?;
    if let Some((key, reason)) = options.refusal() {
        return Err(format!("{}: {reason}", crate::estimators::unknown_option(kind, key)));
    }
    if let Some(n) = options.bootstrap_refits {
        check_bootstrap_refits(n).map_err(|e| format!("{name}: `bootstrap_refits`: {e}"))?;
    }
    Ok(options)
}

/// How a batch fit went (`summary.json` `batch_fits`, and the Monte Carlo per-run results).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchFit {
    /// Estimator label.
    pub estimator: String,
    /// First sample time of the fitted window, s (sample time stamps).
    pub from_s: f64,
    /// Last sample time of the fitted window, s.
    pub to_s: f64,
    /// Samples fitted.
    pub samples: usize,
    /// Outputs fitted.
    pub outputs: Vec<String>,
    /// `estimate` or `first-sample`.
    pub initial_states: &'static str,
    /// Gauss–Newton iterations (`null`: the fit failed before iterating).
    pub iterations: Option<usize>,
    /// How the fit ended: `converged`, `converged_in_cost` or `not_converged` (the last
    /// iterate; [`aeroident_estimators::output_error::Termination::status`]).
    pub status: &'static str,
    /// Why it is not `converged` ([`termination_note`]); `None` when it is.
    pub status_reason: Option<String>,
    /// Wall time of the fit, s.
    pub wall_s: f64,
    /// Residual RMS per output (unit of the output).
    pub residual_rms: Vec<f64>,
    /// Whether the σ are the coloured-residual ones (else Cramér–Rao).
    pub coloured_sigma: bool,
    /// Lag (samples) at which the prewhitened form's sum over the whitened residuals was
    /// truncated (diagnostic `coloured_prewhitened`).
    pub coloured_lag: usize,
    /// Order of the residuals' vector autoregression in the prewhitened form (0: white).
    pub coloured_ar_order: usize,
    /// `fem`: the estimated process noise of each state; empty for `oe`.
    pub process_noise: Vec<crate::replay::batch::ProcessNoise>,
    /// The candidate σ of the structure parameters (structure order), by kind: `cramer_rao`
    /// (`sqrt(diag M⁻¹)`, diagonal weighting), `coloured` (the spectral, multitaper coloured-residual
    /// sandwich, the reported one), `coloured_prewhitened` (the sandwich with a vector
    /// autoregression of the residuals), `coloured_truncated` (the lag-truncated sandwich of sample
    /// autocovariances), and for `fem` `lag0` (sandwich with the full lag-0 innovation covariance) and
    /// `full_b` (Cramér–Rao with the full innovation covariance); a kind that could not be
    /// formed is absent. For measuring which σ is honest (docs/uncertainty.md).
    pub sigma_candidates: Vec<(String, Vec<f64>)>,
    /// `oe` with `bootstrap_refits`: the replicas that failed and are not in the bootstrap σ
    /// (a run fails when more than half do); `null` without the bootstrap.
    pub bootstrap_failed: Option<usize>,
    /// `oe` with `bootstrap_refits`: the bootstrap's bias estimate of the structure parameters
    /// (structure order; the refits' mean less the estimate, not subtracted from it); `null`
    /// without the bootstrap.
    pub bootstrap_bias: Option<Vec<f64>>,
}

/// The outcome of [`fit_window`]: per structure parameter `(estimate, σ)`, and the log.
pub type WindowFit = (Vec<(f64, f64)>, BatchFit);

/// Fits `samples` from `window_from_s` (sample time stamps; the first sample at or after it)
/// by output error with `config`.
///
/// A fit that does not converge on both criteria gives its last iterate, [`BatchFit::status`]
/// and [`BatchFit::status_reason`] saying how it ended; the bootstrap runs only on a converged
/// fit.
///
/// # Errors
/// A message: too few samples in the window, or the fit failed (the reason).
pub fn fit_window(
    label: &str,
    samples: &[AirDataSample],
    window_from_s: f64,
    config: &BatchConfig,
) -> Result<WindowFit, String> {
    let k0 = samples.partition_point(|s| s.t_s < window_from_s);
    let window = &samples[k0..];
    if window.len() < 2 {
        return Err(format!(
            "{}: {} samples after t = {window_from_s:.3} s, at least 2 needed",
            config.kind(),
            window.len()
        ));
    }
    match config {
        BatchConfig::Oe { config: c, bootstrap_refits } => {
            let (result, wall_s) = fit_manoeuvres(&[window], c)?;
            let mut sigma = reported_sigma(&result);
            let mut extra = Vec::new();
            let mut failed = None;
            let mut bias = None;
            if let Some(n) = bootstrap_refits.filter(|_| result.termination.is_converged()) {
                // Each run's own draws: the seed mixes in the window's first measurements (a
                // common seed would correlate the runs' σ through shared replica noise).
                let first = &window[0];
                let seed = BOOTSTRAP_SEED
                    ^ first.alpha_rad.to_bits()
                    ^ first.vt_mps.to_bits().rotate_left(29);
                let (b, summary) = bootstrap_sigma(&[window], c, &result, n, seed, None)
                    .map_err(|e| format!("oe: {e}"))?;
                failed = Some(summary.failed);
                sigma.copy_from_slice(&b.sigma);
                let np = result.n_params;
                extra.push(("bootstrap".to_string(), b.sigma[..np].to_vec()));
                bias = Some(b.bias[..np].to_vec());
            }
            let values = result.values[..result.n_params].iter().copied().zip(sigma).collect();
            let mut log = log_of(label, window, c, &result, wall_s, Vec::new(), extra);
            log.bootstrap_failed = failed;
            log.bootstrap_bias = bias;
            Ok((values, log))
        }
        BatchConfig::Fem(c) => {
            let (fem, wall_s) = fit_fem_manoeuvres(&[window], c)?;
            let r = &fem.result;
            // Coloured-residual σ where formed, as output error (fem_reported_sigma).
            let (sigma, coloured) = fem_reported_sigma(&fem);
            let values = (0..r.n_params).map(|i| (r.values[i], sigma[i])).collect();
            let np = r.n_params;
            let extra = [
                ("lag0", &fem.sigma_lag0),
                ("full_b", &fem.sigma_full_b),
                ("coloured_theta", &fem.sigma_coloured_theta),
            ]
            .into_iter()
            .filter_map(|(k, v)| v.as_ref().map(|v| (k.to_string(), v[..np].to_vec())))
            .collect();
            let mut log = log_of(label, window, &c.oe, r, wall_s, process_noise_of(&fem), extra);
            log.coloured_sigma = coloured;
            Ok((values, log))
        }
    }
}

fn log_of(
    label: &str,
    window: &[AirDataSample],
    config: &OeConfig,
    r: &OeResult,
    wall_s: f64,
    process_noise: Vec<crate::replay::batch::ProcessNoise>,
    extra_sigmas: Vec<(String, Vec<f64>)>,
) -> BatchFit {
    let np = r.n_params;
    let mut sigma_candidates = vec![("cramer_rao".to_string(), r.sigma[..np].to_vec())];
    if let Some(c) = &r.sigma_coloured {
        sigma_candidates.push(("coloured".to_string(), c[..np].to_vec()));
    }
    if let Some(c) = &r.sigma_coloured_prewhitened {
        sigma_candidates.push(("coloured_prewhitened".to_string(), c[..np].to_vec()));
    }
    if let Some(c) = &r.sigma_coloured_truncated {
        sigma_candidates.push(("coloured_truncated".to_string(), c[..np].to_vec()));
    }
    sigma_candidates.extend(extra_sigmas);
    BatchFit {
        estimator: label.into(),
        from_s: window[0].t_s,
        to_s: window[window.len() - 1].t_s,
        samples: window.len(),
        outputs: r.outputs.iter().map(|o| o.name().to_string()).collect(),
        initial_states: initial_states_name(config.initial_states),
        iterations: Some(r.n_iterations()),
        status: r.termination.status(),
        status_reason: termination_note(r),
        wall_s,
        residual_rms: r.residual_rms.clone(),
        coloured_sigma: r.sigma_coloured.is_some(),
        coloured_lag: r.coloured_lag,
        coloured_ar_order: r.coloured_ar_order,
        process_noise,
        sigma_candidates,
        bootstrap_failed: None,
        bootstrap_bias: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::ModelStructure;
    use aeroident_estimators::flight_model::{N_STATES, state};

    fn spec(kind: &str, options: &str) -> SampleEstimatorSpec {
        SampleEstimatorSpec {
            kind: kind.into(),
            model: ModelStructure::longitudinal(),
            model_name: "longitudinal".into(),
            label: None,
            options: toml::from_str(options).unwrap(),
        }
    }

    /// `max_iterations` sets the limit of both batch kinds; 0, a float or a string is refused
    /// with the key named; `process_noise` names the states of `fem`.
    #[test]
    fn the_iteration_limit_and_the_process_noise_states_are_options() {
        for kind in ["oe", "fem"] {
            let c = config(&spec(kind, "max_iterations = 7")).unwrap();
            assert_eq!(c.oe().max_iterations, 7, "{kind}");
            assert_eq!(config(&spec(kind, "")).unwrap().oe().max_iterations, MAX_ITERATIONS);
            for bad in ["max_iterations = 0", "max_iterations = 2.5", "max_iterations = \"x\""] {
                let e = config(&spec(kind, bad)).unwrap_err();
                assert!(e.contains("`max_iterations`: must be an integer of at least 1"), "{e}");
            }
        }
        let BatchConfig::Fem(f) =
            config(&spec("fem", "process_noise = \"V, alpha,theta,q\"")).unwrap()
        else {
            panic!("fem expected")
        };
        let mut want = [state::V, state::ALPHA, state::THETA, state::Q];
        want.sort_unstable();
        let on: Vec<usize> = (0..N_STATES).filter(|&k| f.process_noise[k]).collect();
        assert_eq!(on, want);
        let e = config(&spec("fem", "process_noise = \"V,gamma\"")).unwrap_err();
        assert!(e.contains("`gamma` unknown"), "{e}");
        let e = config(&spec("fem", "process_noise = \" , \"")).unwrap_err();
        assert!(e.contains("names no state"), "{e}");
    }

    /// `bootstrap_refits` is held to 2 to [`MAX_BOOTSTRAP_REFITS`] when the scenario is read,
    /// with the key named; a count past `usize` or negative is refused too.
    #[test]
    fn the_bootstrap_refit_count_is_limited() {
        use crate::replay::batch::MAX_BOOTSTRAP_REFITS;
        let ok = format!("samples = \"raw\"\nbootstrap_refits = {MAX_BOOTSTRAP_REFITS}");
        assert!(config(&spec("oe", &ok)).is_ok());
        for n in [MAX_BOOTSTRAP_REFITS as i64 + 1, 4_294_967_295, i64::MAX] {
            let e = config(&spec("oe", &format!("samples = \"raw\"\nbootstrap_refits = {n}")))
                .unwrap_err();
            assert!(e.starts_with("oe: `bootstrap_refits`: ") && e.contains("more than"), "{e}");
        }
        let e = config(&spec("oe", "samples = \"raw\"\nbootstrap_refits = -3")).unwrap_err();
        assert!(e.contains("at least 2"), "{e}");
    }

    /// A scenario's batch entry takes a recorded flight's options through the same parser:
    /// Huber's weights and the concentrated step of output error, the filter-error method
    /// without its gain constraint, over the experiment's defaults (relaxation, the longer
    /// iteration limit); an option of the other method is refused naming whose it is.
    #[test]
    fn errors_an_entry_takes_the_options_a_record_fit_takes() {
        let BatchConfig::Oe { config: c, .. } = config(&spec("oe", "")).unwrap() else {
            panic!("oe expected")
        };
        assert_eq!(
            (c.step, c.max_iterations, c.robust),
            (StepKind::Relaxation, MAX_ITERATIONS, None)
        );
        let given = "robust = true\nstep = \"concentrated\"\ninitial_states = \"estimate\"";
        let BatchConfig::Oe { config: c, .. } = config(&spec("oe", given)).unwrap() else {
            panic!("oe expected")
        };
        assert_eq!(c.step, StepKind::Concentrated);
        assert!(
            c.robust.is_some()
                && c.initial_states
                    == InitialStates::Estimate(
                        [true; aeroident_estimators::flight_model::N_STATES]
                    )
        );
        let BatchConfig::Fem(f) = config(&spec("fem", "gain_constraint = false")).unwrap() else {
            panic!("fem expected")
        };
        assert!(f.gain_limit.is_none() && f.oe.step == StepKind::Relaxation);
        for (kind, option, owner) in [
            ("fem", "robust = true", "output error"),
            ("fem", "step = \"concentrated\"", "output error"),
            ("oe", "gain_constraint = false", "filter-error method"),
            ("oe", "band_hz = [0.1, 2.0]", "frequency-domain output error"),
        ] {
            let e = config(&spec(kind, option)).unwrap_err();
            assert!(e.starts_with(&format!("{kind}: ")) && e.contains(owner), "{option}: {e}");
        }
    }
}
