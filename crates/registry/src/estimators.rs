//! The one place an aircraft estimator is built: [`build`] turns an [`EstimatorKind`], a model
//! structure, its priors and the options into a `Box<dyn Estimator>`; the replay pipeline (and
//! anything else that drives estimators over recorded or simulated samples) uses only that box.
//!
//! The registry of every kind a scenario, the command line or Python names: the online and
//! batch [`EstimatorKind`]s (with their options, default feed and [`build`]) and the
//! closed-loop experiment's [`TwoAircraftKind`]s.
//!
//! Adding an estimator: implement [`aeroident_estimators::Estimator`] in the core, add a
//! variant to [`EstimatorKind`] and an arm to [`build`].

use aeroident_estimators::ekf::{Ekf, EkfBlocks, EkfConfig};
use aeroident_estimators::finite_time::{FiniteTimeConfig, FiniteTimeSmpe};
use aeroident_estimators::flight_model::StateSet;
use aeroident_estimators::ftr::{Ftr, FtrConfig};
use aeroident_estimators::iv::{DEFAULT_INSTRUMENT_DELAY, IvConfig, MAX_INSTRUMENT_DELAY, RlsIv};
use aeroident_estimators::model_reference::{
    CorrectedSmpeEstimator, GradientEstimator, ModelReferenceConfig, PublishedSmpeEstimator,
};
use aeroident_estimators::rls::{Rls, RlsConfig};
use aeroident_estimators::{ChangeConfig, Estimator, EstimatorError, ModelStructure, Priors};

use crate::Named;

/// The aircraft estimators, by command-line name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EstimatorKind {
    /// Recursive least squares (equation error) on every modelled coefficient.
    Rls,
    /// Recursive instrumental variables: equation error whose estimates noise on the measured
    /// regressors does not pull towards zero (`aeroident_estimators::iv`).
    RlsIv,
    /// Real-time Fourier-transform regression (equation error in the frequency domain,
    /// Morelli 2000): biases drop out.
    Ftr,
    /// Extended Kalman filter (states and parameters; recursive output error).
    Ekf,
    /// The thesis's sliding-mode parameter estimator.
    Smpe,
    /// The corrected sliding-mode parameter estimator.
    SmpeCorrected,
    /// The finite-time sliding-mode estimator on the forgotten information memory, with the
    /// memory's σ (`aeroident_estimators::finite_time`, `docs/smpe-finite-time.md`).
    SmpeFiniteTime,
    /// The model-reference gradient estimator.
    Gradient,
    /// Batch maximum-likelihood output error (not real time: `replay` reads the whole record
    /// and fits it; `aeroident_pipelines::replay::batch`).
    Oe,
    /// Batch filter-error method: maximum likelihood with process noise (turbulence), a
    /// steady-state Kalman filter in the cost (Jategaonkar 2015 ch. 5; not real time, as `oe`).
    Fem,
    /// Batch frequency-domain output error: the derivatives of the structure's linearised model
    /// from the Fourier transforms of the record over a band (Klein & Morelli 2006 ch. 7,
    /// SIDPAC `fdoe`; `aeroident_pipelines::replay::frequency`). `replay` only.
    Fdoe,
}

impl crate::Named for EstimatorKind {
    const ALL: &'static [Self] = &[
        EstimatorKind::Rls,
        EstimatorKind::RlsIv,
        EstimatorKind::Ftr,
        EstimatorKind::Ekf,
        EstimatorKind::Smpe,
        EstimatorKind::SmpeCorrected,
        EstimatorKind::SmpeFiniteTime,
        EstimatorKind::Gradient,
        EstimatorKind::Oe,
        EstimatorKind::Fem,
        EstimatorKind::Fdoe,
    ];

    fn name(self) -> &'static str {
        EstimatorKind::name(self)
    }
}

impl EstimatorKind {
    /// The name used on the command line and in `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            EstimatorKind::Rls => "rls",
            EstimatorKind::RlsIv => "rls-iv",
            EstimatorKind::Ftr => "ftr",
            EstimatorKind::Ekf => "ekf",
            EstimatorKind::Smpe => "smpe",
            EstimatorKind::SmpeCorrected => "smpe-corrected",
            EstimatorKind::SmpeFiniteTime => "smpe-finite-time",
            EstimatorKind::Gradient => "gradient",
            EstimatorKind::Oe => "oe",
            EstimatorKind::Fem => "fem",
            EstimatorKind::Fdoe => "fdoe",
        }
    }

    /// Whether the estimator regresses on the measured coefficients
    /// ([`AirDataSample::measured_coefficients`](aeroident_estimators::AirDataSample::measured_coefficients)),
    /// and so needs the angular accelerations `ṗ, q̇, ṙ` of the moment coefficients (the
    /// replay differentiates the rates when the record lacks them). Estimators that integrate
    /// their own model (Kalman filters) do not: a differentiated rate is not an independent
    /// measurement, so they are not given one.
    pub fn uses_measured_coefficients(self) -> bool {
        !matches!(
            self,
            EstimatorKind::Ekf | EstimatorKind::Oe | EstimatorKind::Fem | EstimatorKind::Fdoe
        )
    }

    /// The options an `[[estimator]]` entry of this kind takes besides `kind`, `model` and
    /// `label` ([`EstimatorOptions::set`]; the batch kinds' in `aircraft::batch::config`).
    pub fn options(self) -> &'static [&'static str] {
        match self {
            EstimatorKind::Rls => &["forgetting", "change_false_alarm_interval_s"],
            EstimatorKind::RlsIv => &["forgetting", "instrument_delay"],
            EstimatorKind::Ftr => &["forgetting", "grid_hz", "spread_sigma"],
            EstimatorKind::Ekf => {
                &["parameter_walk_per_sqrt_s", "samples", "blocks", "update_every"]
            }
            EstimatorKind::SmpeFiniteTime => &[
                "forgetting",
                "sliding_gain_per_s",
                "reaching_rate_per_s",
                "change_false_alarm_interval_s",
            ],
            // The fit's options ([`EstimatorKind::fit_options`]) and which samples the
            // experiment records for it.
            EstimatorKind::Oe => &[
                "initial_states",
                "step",
                "bootstrap_refits",
                "max_iterations",
                "robust",
                "samples",
            ],
            EstimatorKind::Fem => {
                &["initial_states", "max_iterations", "process_noise", "gain_constraint", "samples"]
            }
            // A recorded flight's fit only (`replay --band-hz`): the closed-loop experiment
            // refuses the kind (`aircraft::batch::config`).
            EstimatorKind::Fdoe => &[],
            EstimatorKind::Smpe | EstimatorKind::SmpeCorrected | EstimatorKind::Gradient => &[],
        }
    }

    /// The options of a batch fit of this kind, of a recorded flight and of the closed-loop
    /// experiment alike (`aeroident_pipelines::replay::fit::FitOptions::from_pairs` parses
    /// them); none for a real-time estimator. The faces derive from it which of their flags
    /// suit which method.
    pub fn fit_options(self) -> &'static [&'static str] {
        match self {
            EstimatorKind::Oe => {
                &["initial_states", "step", "bootstrap_refits", "max_iterations", "robust"]
            }
            EstimatorKind::Fem => {
                &["initial_states", "max_iterations", "process_noise", "gain_constraint"]
            }
            EstimatorKind::Fdoe => &["band_hz", "max_iterations"],
            _ => &[],
        }
    }

    /// Whether the estimator is a batch fit of a whole record (`oe`, `fem`, `fdoe`).
    pub fn is_batch(self) -> bool {
        matches!(self, EstimatorKind::Oe | EstimatorKind::Fem | EstimatorKind::Fdoe)
    }

    /// The samples the closed-loop experiment feeds it unless its entry says otherwise
    /// (`samples = "raw" | "smoothed"`, [`SampleEstimatorSpec::raw_samples`]): the raw ones for
    /// the estimators whose noise model assumes white, independent measurement errors (`ekf`,
    /// `fem`), the matched-smoother ones for the equation-error estimators and `oe`.
    pub fn default_feed(self) -> Feed {
        match self {
            EstimatorKind::Ekf | EstimatorKind::Fem => Feed::Raw,
            _ => Feed::Smoothed,
        }
    }
}

/// Which samples of the conditioning stage (`aeroident_pipelines::condition`) an estimator consumes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feed {
    /// The conditioned samples (matched smoother or delay, with the differentiated `ṗ q̇ ṙ α̇`).
    Smoothed,
    /// The unsmoothed samples behind them (`aeroident_pipelines::condition::Conditioner::raw`).
    Raw,
}

/// The two-aircraft estimators of the closed-loop experiment (`run`): each flies an estimated
/// F-16 beside the reference and estimates increments of its aerodynamics (TOML
/// `[[estimator]] kind`, with `params = [...]` instead of a model structure).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TwoAircraftKind {
    /// The thesis's sliding-mode parameter estimator as published, (3.163)–(3.175).
    Published,
    /// The corrected sliding-mode parameter estimator (`docs/smpe-corrected.md`).
    Corrected,
    /// The thesis's model-reference gradient law (3.3).
    MrGradient,
}

impl crate::Named for TwoAircraftKind {
    const ALL: &'static [Self] =
        &[TwoAircraftKind::Published, TwoAircraftKind::Corrected, TwoAircraftKind::MrGradient];

    fn name(self) -> &'static str {
        match self {
            TwoAircraftKind::Published => "published",
            TwoAircraftKind::Corrected => "corrected",
            TwoAircraftKind::MrGradient => "mr-gradient",
        }
    }
}

impl TwoAircraftKind {
    /// The options an `[[estimator]]` entry of this kind takes besides `kind`, `params` and
    /// `label` (parsed with the entry by `aeroident_pipelines::aircraft::scenario`).
    pub fn options(self) -> &'static [&'static str] {
        match self {
            TwoAircraftKind::Published => &["reading"],
            TwoAircraftKind::Corrected => {
                &["lambda_per_s", "information_per_s", "tracking_weight", "forgetting_per_s"]
            }
            TwoAircraftKind::MrGradient => &[],
        }
    }
}

/// The message for an `[[estimator]] kind` that is none of the registry's, listing them all.
pub fn unknown_kind(kind: &str) -> String {
    let two: Vec<&str> = TwoAircraftKind::ALL.iter().map(|k| k.name()).collect();
    format!(
        "unknown kind `{kind}`: two-aircraft estimators {}, sample-driven {}, batch (post-flight) {}",
        two.join(" | "),
        online_kinds().join(" | "),
        batch_kinds().join(" | ")
    )
}

/// The instrument delay of an `rls-iv` replay, samples: `given` (the option), else the
/// differentiator window `diff_window` = `N`, samples (twice the half-span `(N−1)/2` over which
/// a differentiated rate's noise is correlated with the rate's), capped at
/// [`MAX_INSTRUMENT_DELAY`]. Measured on a noisy F-16 record (docs/real-data.md, "Instrumental
/// variables"): with `N = 5` a delay of 1 or 2 samples leaves `Cm_q` 60–130 % off, 3 and more
/// agree with the noise-free fit.
pub fn instrument_delay(given: Option<usize>, diff_window: usize) -> usize {
    given.unwrap_or(diff_window.min(MAX_INSTRUMENT_DELAY))
}

/// Options of the estimators (each uses the ones that apply to it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimatorOptions {
    /// Forgetting factor `λ ∈ (0, 1]` per sample of RLS (and RLS-IV) and of FTR's recursive
    /// transform (1 = none).
    pub forgetting: f64,
    /// RLS-IV: delay of the state regressors' instruments, samples
    /// ([`IvConfig::delay_samples`]); `None`: [`DEFAULT_INSTRUMENT_DELAY`].
    pub instrument_delay: Option<usize>,
    /// EKF parameter random walk, as a fraction of each parameter's prior σ per √s (0 =
    /// constant parameters): lets the filter follow a sudden change (damage) instead of gating
    /// it out. With 0.01 the σ of a parameter can grow by 1 % of its prior σ in 1 s.
    pub parameter_walk_per_sqrt_s: f64,
    /// Nominal sample interval of the data, s, when known (the record's `nominal_dt_s`).
    pub sample_interval_s: Option<f64>,
    /// FTR frequency grid `(f_min, f_max, step)`, Hz; `None` = Morelli's rigid-body grid
    /// ([`FtrConfig::default`], 0.1–1.5 Hz in 0.04 Hz). A scenario whose excitation reaches
    /// beyond 1.5 Hz must extend it: a harmonic outside the grid is seen only through the
    /// window's leakage (docs/uncertainty.md, "Equation-error coverage, continued").
    pub ftr_grid_hz: Option<(f64, f64, f64)>,
    /// `ftr`: compute each solve's σ over the updates of the solve interval
    /// ([`FtrConfig::spread_sigma`]): a bounded update for a flight computer, each solution
    /// published up to one interval after its solve. Default off.
    pub ftr_spread_sigma: bool,
    /// `ekf` over a structure with both axes: a longitudinal and a lateral filter instead of
    /// one coupled filter ([`EkfBlocks`]; about 0.7 of the coupled filter's cost on the six-axis
    /// preset). Default off.
    pub ekf_blocks: bool,
    /// `ekf`: step the filter on every `n`-th sample ([`EkfConfig::update_every`]); 1 (the
    /// default): every sample.
    pub ekf_update_every: u32,
    /// `smpe-finite-time`: sliding gain `γ`, standard errors per second
    /// ([`FiniteTimeConfig::sliding_gain_per_s`]).
    pub sliding_gain_per_s: f64,
    /// `smpe-finite-time`: exponential reaching rate `q`, 1/s
    /// ([`FiniteTimeConfig::reaching_rate_per_s`]).
    pub reaching_rate_per_s: f64,
    /// `rls`, `smpe-finite-time`: mean time between false alarms of the change test over all
    /// equations, s ([`ChangeConfig::false_alarm_interval_s`]); 0 disables the test
    /// (`aeroident_estimators::change`, docs/change-detection.md).
    pub change_false_alarm_interval_s: f64,
}

/// Default of [`EstimatorOptions::change_false_alarm_interval_s`], s.
pub const DEFAULT_CHANGE_FALSE_ALARM_INTERVAL_S: f64 = 0.0;

impl Default for EstimatorOptions {
    fn default() -> Self {
        Self {
            forgetting: 1.0,
            instrument_delay: None,
            parameter_walk_per_sqrt_s: 0.0,
            sample_interval_s: None,
            ftr_grid_hz: None,
            ftr_spread_sigma: false,
            ekf_blocks: false,
            ekf_update_every: 1,
            sliding_gain_per_s: FiniteTimeConfig::default().sliding_gain_per_s,
            reaching_rate_per_s: FiniteTimeConfig::default().reaching_rate_per_s,
            change_false_alarm_interval_s: DEFAULT_CHANGE_FALSE_ALARM_INTERVAL_S,
        }
    }
}

/// Why an estimator could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// A batch method has no per-sample estimator.
    #[error(
        "estimator `{0}` is a batch method (it reads the whole record): run it with `aeroident replay --estimator {0}`"
    )]
    Batch(&'static str),
    /// A prior outside the limits every estimator can start from
    /// ([`aeroident_estimators::prior::ParamPrior::check`]).
    #[error(
        "estimator `{estimator}`: the prior of `{name}` (value {value}, sigma {sigma}, from the model file or the generic priors): {reason}"
    )]
    Prior {
        /// Estimator name.
        estimator: &'static str,
        /// Parameter name.
        name: &'static str,
        /// Prior value.
        value: f64,
        /// Prior σ.
        sigma: f64,
        /// Which limit it breaks.
        reason: String,
    },
    /// The estimator rejected its configuration.
    #[error("estimator `{estimator}`: {source}")]
    Config {
        /// Estimator name.
        estimator: &'static str,
        /// Why.
        source: EstimatorError,
    },
}

/// Refuses a prior outside [`aeroident_estimators::prior::ParamPrior::check`]'s limits,
/// naming the parameter, its value and σ, before any estimator starts from it.
///
/// # Errors
/// [`BuildError::Prior`] for the first such prior.
pub fn check_priors(
    kind: EstimatorKind,
    structure: &ModelStructure,
    priors: &Priors,
) -> Result<(), BuildError> {
    for (i, p) in structure.params().enumerate() {
        let Some(prior) = priors.prior.get(i).filter(|_| i < priors.n) else { break };
        prior.check().map_err(|reason| BuildError::Prior {
            estimator: kind.name(),
            name: p.name(),
            value: prior.value,
            sigma: prior.sigma,
            reason,
        })?;
    }
    Ok(())
}

/// Builds estimator `kind` over `structure` with `priors` (one per parameter, parameter
/// order; used by the estimators that start from a prior) and `options`. Every estimator is
/// `Send`, so a caller may move it to another thread (the Python class, usable from any
/// thread).
///
/// # Errors
/// [`BuildError::Batch`] for the batch output-error method; [`BuildError::Prior`] for a prior
/// outside the limits ([`check_priors`]); [`BuildError::Config`] when the
/// estimator rejects the structure or an option (e.g. a
/// forgetting factor outside (0, 1], or a structure the EKF's flight model cannot integrate).
pub fn build(
    kind: EstimatorKind,
    structure: ModelStructure,
    priors: Priors,
    options: &EstimatorOptions,
) -> Result<Box<dyn Estimator + Send>, BuildError> {
    check_priors(kind, &structure, &priors)?;
    let config = |source| BuildError::Config { estimator: kind.name(), source };
    match kind {
        // RLS and FTR start without a prior (exact initialisation / frequency-domain solve).
        EstimatorKind::Rls => {
            let cfg = RlsConfig { forgetting: options.forgetting, init_samples: 0 };
            let change = change_config(options);
            boxed(|| {
                let mut rls = Rls::new(structure, cfg)?;
                if let Some(c) = change {
                    rls.enable_change_detection(c)?;
                }
                Ok(rls)
            })
        }
        EstimatorKind::RlsIv => {
            let cfg = IvConfig {
                forgetting: options.forgetting,
                init_samples: 0,
                delay_samples: options.instrument_delay.unwrap_or(DEFAULT_INSTRUMENT_DELAY),
            };
            boxed(|| RlsIv::new(structure, cfg))
        }
        EstimatorKind::Ftr => {
            let mut cfg = FtrConfig {
                forgetting: options.forgetting,
                spread_sigma: options.ftr_spread_sigma,
                ..FtrConfig::default()
            };
            if let Some((f_min_hz, f_max_hz, f_step_hz)) = options.ftr_grid_hz {
                cfg = FtrConfig { f_min_hz, f_max_hz, f_step_hz, ..cfg };
            }
            boxed(|| Ftr::new(structure, cfg))
        }
        EstimatorKind::Ekf => {
            let cfg = ekf_config(structure, &priors, options.parameter_walk_per_sqrt_s)
                .map_err(config)?;
            let cfg = EkfConfig { update_every: options.ekf_update_every, ..cfg };
            if options.ekf_blocks && StateSet::of(&structure).ok() == Some(StateSet::Coupled) {
                boxed(|| EkfBlocks::new(cfg))
            } else {
                boxed(|| Ekf::new(cfg))
            }
        }
        EstimatorKind::Smpe => boxed(|| {
            PublishedSmpeEstimator::new(structure, &priors, ModelReferenceConfig::default())
        }),
        EstimatorKind::SmpeCorrected => boxed(|| {
            CorrectedSmpeEstimator::new(structure, &priors, ModelReferenceConfig::default())
        }),
        // Starts without a prior, as RLS (the memory's exact initialisation).
        EstimatorKind::SmpeFiniteTime => {
            let cfg = FiniteTimeConfig {
                forgetting: options.forgetting,
                init_samples: 0,
                sliding_gain_per_s: options.sliding_gain_per_s,
                reaching_rate_per_s: options.reaching_rate_per_s,
            };
            let change = change_config(options);
            boxed(|| {
                let mut est = FiniteTimeSmpe::new(structure, cfg)?;
                if let Some(c) = change {
                    est.enable_change_detection(c)?;
                }
                Ok(est)
            })
        }
        EstimatorKind::Gradient => {
            boxed(|| GradientEstimator::new(structure, &priors, ModelReferenceConfig::default()))
        }
        EstimatorKind::Oe | EstimatorKind::Fem | EstimatorKind::Fdoe => {
            return Err(BuildError::Batch(kind.name()));
        }
    }
    .map_err(config)
}

/// Runs `make` and moves the estimator it builds to the heap, in a stack frame of its own.
///
/// The estimators are fixed-capacity and allocation-free (the core is `no_std`), so each is
/// built by value on the stack before it is boxed: over the vocabulary an `Rls` is 0.2 MB, an
/// `RlsIv` 0.4 MB. Built inline in [`build`]'s `match`, the arms' temporaries added up to one
/// 2 MB frame (a copy of every estimator, some twice), and a six-axis run needed 2.3–2.7 MiB
/// of stack, past the 2 MiB default of a spawned thread. Here only the chosen estimator is on
/// the stack, once.
#[inline(never)]
/// The change test of [`EstimatorOptions::change_false_alarm_interval_s`], `None` when it is 0
/// (a negative or non-finite interval reaches the estimator, which refuses it by name).
fn change_config(options: &EstimatorOptions) -> Option<ChangeConfig> {
    let t = options.change_false_alarm_interval_s;
    (t != 0.0).then(|| ChangeConfig { false_alarm_interval_s: t, ..ChangeConfig::default() })
}

fn boxed<E: Estimator + Send + 'static>(
    make: impl FnOnce() -> Result<E, EstimatorError>,
) -> Result<Box<dyn Estimator + Send>, EstimatorError> {
    // Allocated first, so that the estimator goes from `make`'s return slot to the heap
    // without another copy on this frame.
    let slot = Box::<E>::new_uninit();
    let estimator: Box<E> = Box::write(slot, make()?);
    Ok(estimator)
}

/// The EKF's configuration over `structure`: `priors`, and a parameter random walk of
/// `walk_per_sqrt_s` × each prior σ per √s ([`EstimatorOptions::parameter_walk_per_sqrt_s`]).
///
/// # Errors
/// [`EstimatorError::InvalidConfig`] when `walk_per_sqrt_s` is negative or not finite.
fn ekf_config(
    structure: ModelStructure,
    priors: &Priors,
    walk_per_sqrt_s: f64,
) -> Result<EkfConfig, EstimatorError> {
    if !(walk_per_sqrt_s >= 0.0 && walk_per_sqrt_s.is_finite()) {
        return Err(EstimatorError::InvalidConfig {
            field: "parameter_walk_per_sqrt_s",
            value: walk_per_sqrt_s,
            reason: "must be finite and >= 0",
        });
    }
    let mut cfg = EkfConfig { priors: *priors, ..EkfConfig::new(structure) };
    for i in 0..priors.n {
        cfg.param_process_noise[i] = walk_per_sqrt_s * priors.prior[i].sigma;
    }
    Ok(cfg)
}

/// A sample-driven estimator (TOML `[[estimator]]` with a sample-driven `kind`): an
/// [`aeroident_estimators::Estimator`] over a model structure of the vocabulary, fed one
/// air-data sample per step.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleEstimatorSpec {
    /// Method: an [`EstimatorKind`] name ([`online_kinds`] or [`batch_kinds`]).
    pub kind: String,
    /// The model structure (preset or list).
    pub model: ModelStructure,
    /// How the structure was given (preset name, or `custom`).
    pub model_name: String,
    /// Label in outputs (default: the kind).
    pub label: Option<String>,
    /// Method options (every other key of the entry), checked by the estimator factory.
    pub options: toml::Table,
}

impl SampleEstimatorSpec {
    /// Whether the entry is fed the **unsmoothed** samples (`aeroident_pipelines::aircraft::air_data::AirDataSampler::raw`: white sensor
    /// noise, the same time stamps) instead of the matched-smoother ones the equation-error
    /// estimators need: option `samples = "raw" | "smoothed"` of `ekf`, `oe` and `fem` (the
    /// value is checked by the estimator factory or `aeroident_pipelines::aircraft::batch::config`); default raw for
    /// `ekf` and `fem`, smoothed for `oe`.
    /// - `oe`, `fem`: the samples the post-flight fit records (`aeroident_pipelines::aircraft::batch` module doc).
    /// - `ekf`: raw means the raw samples **without** the differentiated `ṗ q̇ ṙ`. The filter
    ///   assumes white measurement noise and independent outputs; the smoothed samples are
    ///   correlated over the smoother's 0.2 s and the raw accelerations are differences of the
    ///   raw gyros around them, so this is the feed its noise model describes (the moments are
    ///   then learned from the gyros through the dynamics). Measured on the matched truth in
    ///   calm air (docs/uncertainty.md, "Efficiency on the matched truth"): scatter 0.7–4.0 ×
    ///   the Cramér–Rao bound raw, 0.9–10 × smoothed; on the default scenario's 1,000 × 60 s
    ///   campaign mean NIS 0.99 against 0.79, scatter ≤ 2× the bound on 4 of 11 primary
    ///   derivatives against 2 ("EKF: the raw feed by default"). `samples = "smoothed"` gives
    ///   it the matched-smoother samples with the differentiated accelerations.
    pub fn raw_samples(&self) -> bool {
        match self.options.get("samples").and_then(|v| v.as_str()) {
            Some(v) => v == "raw",
            None => {
                EstimatorKind::from_name(&self.kind).is_some_and(|k| k.default_feed() == Feed::Raw)
            }
        }
    }
}

/// The sample-driven (online) estimator kinds of `[[estimator]]`: every [`EstimatorKind`]
/// that is not a batch fit, in [`Named::ALL`]'s order.
pub fn online_kinds() -> Vec<&'static str> {
    EstimatorKind::ALL.iter().filter(|k| !k.is_batch()).map(|k| k.name()).collect()
}

/// Whether `kind` (an `[[estimator]] kind`) is a batch (post-flight) estimator: the CLI's
/// [`EstimatorKind::is_batch`] kinds.
pub fn is_batch_kind(kind: &str) -> bool {
    EstimatorKind::from_name(kind).is_some_and(|k| k.is_batch())
}

/// The batch estimator kinds of `[[estimator]]` (`oe`, `fem`), for messages.
pub fn batch_kinds() -> Vec<&'static str> {
    let kinds = EstimatorKind::ALL;
    kinds.iter().filter(|k| k.is_batch()).map(|k| k.name()).collect()
}

/// The options estimator `kind` takes ([`EstimatorKind::options`]) for a message
/// ([`quoted_list`]).
pub fn option_list(kind: EstimatorKind) -> String {
    quoted_list(kind.options())
}

/// Option names for a message: "none", "`forgetting`", "`forgetting` and `grid_hz`",
/// "`a`, `b` and `c`".
pub fn quoted_list(items: &[&str]) -> String {
    match items {
        [] => "none".to_string(),
        [one] => format!("`{one}`"),
        [init @ .., last] => {
            let init: Vec<String> = init.iter().map(|o| format!("`{o}`")).collect();
            format!("{} and `{last}`", init.join(", "))
        }
    }
}

/// The message for option `key` that estimator `kind` does not take, listing those it takes
/// ([`option_list`]).
pub fn unknown_option(kind: EstimatorKind, key: &str) -> String {
    format!("{}: unknown option `{key}` (it takes {})", kind.name(), option_list(kind))
}

/// An estimator option the registry refuses ([`parse_options`], [`EstimatorOptions::set`]).
/// It carries the kind and the key, so a face can name the option as it spells it (the CLI's
/// `--forgetting`, a Python keyword argument); its text names them as a scenario does.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OptionError {
    /// `kind` does not take option `key`: the text is [`unknown_option`]'s, listing the
    /// options it takes.
    #[error("{}", unknown_option(*kind, key))]
    Unknown {
        /// The estimator.
        kind: EstimatorKind,
        /// The option, as the registry names it ([`EstimatorKind::options`]).
        key: String,
    },
    /// `kind` takes option `key`, but not the value given.
    #[error("{}: `{key}` {reason}", kind.name())]
    Invalid {
        /// The estimator.
        kind: EstimatorKind,
        /// The option, as the registry names it.
        key: String,
        /// What the value must be and the value given ("must be a number, got \"x\"").
        reason: String,
    },
}

impl OptionError {
    /// The estimator whose option was refused.
    pub fn kind(&self) -> EstimatorKind {
        match self {
            OptionError::Unknown { kind, .. } | OptionError::Invalid { kind, .. } => *kind,
        }
    }

    /// The refused option, as the registry names it ([`EstimatorKind::options`]).
    pub fn key(&self) -> &str {
        match self {
            OptionError::Unknown { key, .. } | OptionError::Invalid { key, .. } => key,
        }
    }
}

/// The options of estimator `kind` from key/value pairs, each parsed and checked by
/// [`EstimatorOptions::set`] over the defaults: the one place that knows which kind takes which
/// option. A scenario's `[[estimator]]` entry, the CLI's flags and Python's keyword arguments
/// all become such pairs (keys as [`EstimatorKind::options`] names them). A later pair of the
/// same key replaces an earlier one. [`EstimatorOptions::sample_interval_s`] is not an option
/// (it is the record's) and stays `None`.
///
/// # Errors
/// [`OptionError::Unknown`] for the first key `kind` does not take (naming those it takes),
/// [`OptionError::Invalid`] for the first value of the wrong type or out of the option's domain.
pub fn parse_options<'a>(
    kind: EstimatorKind,
    pairs: impl IntoIterator<Item = (&'a str, toml::Value)>,
) -> Result<EstimatorOptions, OptionError> {
    let mut options = EstimatorOptions::default();
    for (key, v) in pairs {
        options.set(kind, key, &v)?;
    }
    Ok(options)
}

impl EstimatorOptions {
    /// Sets the scenario option `key` (one of [`EstimatorKind::options`] of `kind`) from its
    /// TOML value. `samples` is read by the experiment ([`SampleEstimatorSpec::raw_samples`])
    /// and only checked here. [`parse_options`] sets a whole list.
    ///
    /// # Errors
    /// [`OptionError::Invalid`] naming the option and what it must be, or
    /// [`OptionError::Unknown`] for an option `kind` does not take.
    pub fn set(
        &mut self,
        kind: EstimatorKind,
        key: &str,
        v: &toml::Value,
    ) -> Result<(), OptionError> {
        let invalid = |reason: String| OptionError::Invalid { kind, key: key.into(), reason };
        let number = || {
            v.as_float()
                .or_else(|| v.as_integer().map(|i| i as f64))
                .ok_or_else(|| invalid(format!("must be a number, got {v}")))
        };
        match (key, kind) {
            (
                "forgetting",
                EstimatorKind::Rls
                | EstimatorKind::RlsIv
                | EstimatorKind::Ftr
                | EstimatorKind::SmpeFiniteTime,
            ) => {
                self.forgetting = number()?;
            }
            ("sliding_gain_per_s", EstimatorKind::SmpeFiniteTime) => {
                self.sliding_gain_per_s = number()?;
            }
            ("reaching_rate_per_s", EstimatorKind::SmpeFiniteTime) => {
                self.reaching_rate_per_s = number()?;
            }
            (
                "change_false_alarm_interval_s",
                EstimatorKind::Rls | EstimatorKind::SmpeFiniteTime,
            ) => {
                let t = number()?;
                if !(t >= 0.0 && t.is_finite()) {
                    return Err(invalid(format!(
                        "must be a finite number of seconds ≥ 0 (0: no change test), got {v}"
                    )));
                }
                self.change_false_alarm_interval_s = t;
            }
            ("instrument_delay", EstimatorKind::RlsIv) => {
                let d = v.as_integer().filter(|d| *d >= 1).ok_or_else(|| {
                    invalid(format!("must be a whole number of samples ≥ 1, got {v}"))
                })?;
                self.instrument_delay = Some(d as usize);
            }
            ("grid_hz", EstimatorKind::Ftr) => {
                let bad = || {
                    invalid(format!("must be [f_min, f_max, step] in Hz (three numbers), got {v}"))
                };
                let a = v.as_array().filter(|a| a.len() == 3).ok_or_else(bad)?;
                let num = |x: &toml::Value| {
                    x.as_float().or_else(|| x.as_integer().map(|i| i as f64)).ok_or_else(bad)
                };
                self.ftr_grid_hz = Some((num(&a[0])?, num(&a[1])?, num(&a[2])?));
            }
            ("spread_sigma", EstimatorKind::Ftr) => {
                self.ftr_spread_sigma = v
                    .as_bool()
                    .ok_or_else(|| invalid(format!("must be true or false, got {v}")))?;
            }
            ("parameter_walk_per_sqrt_s", EstimatorKind::Ekf) => {
                self.parameter_walk_per_sqrt_s = number()?;
            }
            ("blocks", EstimatorKind::Ekf) => {
                self.ekf_blocks = v
                    .as_bool()
                    .ok_or_else(|| invalid(format!("must be true or false, got {v}")))?;
            }
            ("update_every", EstimatorKind::Ekf) => {
                let n = v.as_integer().filter(|n| (1..=1000).contains(n)).ok_or_else(|| {
                    invalid(format!("must be a whole number of samples from 1 to 1000, got {v}"))
                })?;
                self.ekf_update_every = n as u32;
            }
            ("samples", EstimatorKind::Ekf) => {
                if !matches!(v.as_str(), Some("raw" | "smoothed")) {
                    return Err(invalid(format!("must be \"raw\" or \"smoothed\", got {v}")));
                }
            }
            (other, _) => return Err(OptionError::Unknown { kind, key: other.into() }),
        }
        Ok(())
    }
}

/// The sample-driven estimator of `spec`, built by the shared factory ([`build`]) with the
/// generic priors and the entry's options ([`parse_options`]).
///
/// An `rls-iv` entry must give `instrument_delay`: the closed-loop samples pass the matched
/// smoother, which correlates the sensor noise over the whole differentiator window `N`
/// (`[sensors] differentiator_window`), so the instruments must lie at least `N` samples back;
/// no default can know `N` here. Measured on `scenarios/default.toml`'s flight without the
/// damage (N = 21): with a delay of 5 the reported σ shrink 2–4 × below least squares'
/// (Cn_r 0.0041 against 0.0143) and a target is missed; with 21 or 30 the estimates agree
/// with least squares' within its σ.
///
/// # Errors
/// A message naming the kind, the unknown, bad or missing option, or the configuration error.
pub fn build_sample_estimator(
    spec: &SampleEstimatorSpec,
) -> Result<Box<dyn Estimator + Send>, String> {
    let kind = EstimatorKind::from_name(&spec.kind).ok_or_else(|| {
        format!("unknown sample-driven estimator `{}` ({})", spec.kind, online_kinds().join(" | "))
    })?;
    let pairs = spec.options.iter().map(|(key, v)| (key.as_str(), v.clone()));
    let options = parse_options(kind, pairs).map_err(|e| e.to_string())?;
    if kind == EstimatorKind::RlsIv && options.instrument_delay.is_none() {
        return Err("rls-iv: give `instrument_delay` (samples), at least `[sensors] differentiator_window`: the matched smoother correlates the noise over the whole window".into());
    }
    build(kind, spec.model, aeroident_estimators::Priors::generic(&spec.model), &options)
        .map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every option a kind declares is one its parser takes (with a valid value), and any
    /// other key is refused with the declared list: the declaration and the parser cannot
    /// drift apart.
    #[test]
    fn declared_options_are_the_parsed_ones() {
        let valid = |key: &str| -> toml::Value {
            match key {
                "forgetting" => toml::Value::Float(0.99),
                "instrument_delay" | "update_every" => toml::Value::Integer(8),
                "grid_hz" => toml::Value::Array(vec![0.1.into(), 1.5.into(), 0.04.into()]),
                "parameter_walk_per_sqrt_s" => toml::Value::Float(0.01),
                "samples" => "raw".into(),
                "sliding_gain_per_s" | "reaching_rate_per_s" => toml::Value::Float(5.0),
                "change_false_alarm_interval_s" => toml::Value::Float(3600.0),
                "spread_sigma" | "blocks" => toml::Value::Boolean(true),
                other => panic!("no valid value for `{other}`"),
            }
        };
        for &k in EstimatorKind::ALL.iter().filter(|k| !k.is_batch()) {
            let mut o = EstimatorOptions::default();
            for key in k.options() {
                o.set(k, key, &valid(key)).unwrap_or_else(|e| panic!("{}: {e}", k.name()));
            }
            let e = o.set(k, "no_such_option", &toml::Value::Float(1.0)).unwrap_err();
            assert_eq!(e.to_string(), unknown_option(k, "no_such_option"));
        }
        assert_eq!(
            unknown_option(EstimatorKind::Ftr, "x"),
            "ftr: unknown option `x` (it takes `forgetting`, `grid_hz` and `spread_sigma`)"
        );
        assert_eq!(
            unknown_option(EstimatorKind::Oe, "x"),
            "oe: unknown option `x` (it takes `initial_states`, `step`, `bootstrap_refits`, `max_iterations`, `robust` and `samples`)"
        );
        assert_eq!(
            unknown_option(EstimatorKind::Smpe, "x"),
            "smpe: unknown option `x` (it takes none)"
        );
        assert_eq!(
            unknown_option(EstimatorKind::Rls, "x"),
            "rls: unknown option `x` (it takes `forgetting` and `change_false_alarm_interval_s`)"
        );
    }

    /// `ekf`'s `blocks`: a boolean, refused otherwise; on a structure with both axes it builds
    /// the blocks (their estimates are the two axis filters', not the coupled filter's), on a
    /// one-axis structure the one filter.
    #[test]
    fn ekf_blocks_option_builds_the_blocks_on_two_axes_only() {
        let on = parse_options(EstimatorKind::Ekf, [("blocks", toml::Value::Boolean(true))]);
        let on = on.unwrap();
        assert!(on.ekf_blocks);
        let bad = parse_options(EstimatorKind::Ekf, [("blocks", toml::Value::Integer(1))]);
        assert!(bad.unwrap_err().to_string().contains("must be true or false"));
        let six = ModelStructure::six_axis();
        let off = EstimatorOptions::default();
        // Across the axes the coupled filter has a covariance, the blocks none.
        let at = |name: &str| six.params().position(|p| p.name() == name).unwrap();
        let (cl, cy) = (at("CL_alpha"), at("CY_beta"));
        let coupled = build(EstimatorKind::Ekf, six, Priors::generic(&six), &off).unwrap();
        let blocks = build(EstimatorKind::Ekf, six, Priors::generic(&six), &on).unwrap();
        assert!(coupled.covariance(cl, cy).is_some());
        assert_eq!(blocks.covariance(cl, cy), None);
        assert!(blocks.covariance(cl, cl).is_some());
        let lon = ModelStructure::longitudinal();
        let one = build(EstimatorKind::Ekf, lon, Priors::generic(&lon), &on).unwrap();
        assert!(one.covariance(0, lon.n_params() - 1).is_some(), "one axis: the one filter");
    }

    /// `ekf`'s `update_every`: a whole number from 1 to 1000 (both ends taken), refused
    /// otherwise with the range.
    #[test]
    fn ekf_update_every_is_a_whole_number_of_samples() {
        let n = |v: toml::Value| parse_options(EstimatorKind::Ekf, [("update_every", v)]);
        for ok in [1, 3, 1000] {
            assert_eq!(n(toml::Value::Integer(ok)).unwrap().ekf_update_every, ok as u32);
        }
        assert_eq!(EstimatorOptions::default().ekf_update_every, 1);
        for bad in [toml::Value::Integer(0), toml::Value::Float(2.0), toml::Value::Integer(1001)] {
            let e = n(bad).unwrap_err().to_string();
            assert!(e.contains("from 1 to 1000"), "{e}");
        }
    }

    /// The registry refuses an option the kind does not take, naming the kind and the options
    /// it takes (`ekf` has no forgetting factor: it was silently ignored from Python), and
    /// gives every kind the options it does take (`smpe-finite-time` forgets: the CLI refused
    /// it).
    #[test]
    fn errors_parse_options_refuses_what_the_kind_does_not_take() {
        let e = parse_options(EstimatorKind::Ekf, [("forgetting", toml::Value::Float(0.9))])
            .unwrap_err();
        assert_eq!(e, OptionError::Unknown { kind: EstimatorKind::Ekf, key: "forgetting".into() });
        let msg = e.to_string();
        assert!(msg.starts_with("ekf: unknown option `forgetting`"), "{msg}");
        assert!(msg.contains("parameter_walk_per_sqrt_s"), "{msg}");
        let o =
            parse_options(EstimatorKind::SmpeFiniteTime, [("forgetting", 0.99.into())]).unwrap();
        assert_eq!(o.forgetting, 0.99);
        assert_eq!(o, EstimatorOptions { forgetting: 0.99, ..Default::default() });
        // A value of the wrong type names the option and carries its key.
        let e = parse_options(EstimatorKind::SmpeFiniteTime, [("forgetting", "high".into())])
            .unwrap_err();
        assert_eq!((e.kind(), e.key()), (EstimatorKind::SmpeFiniteTime, "forgetting"));
        assert_eq!(e.to_string(), "smpe-finite-time: `forgetting` must be a number, got \"high\"");
    }

    /// A scenario's `rls-iv` entry without `instrument_delay` is refused with what to give; with
    /// it, it builds.
    #[test]
    fn errors_scenario_rls_iv_needs_its_instrument_delay() {
        let mut spec = SampleEstimatorSpec {
            kind: "rls-iv".into(),
            model: ModelStructure::longitudinal(),
            model_name: "longitudinal".into(),
            label: None,
            options: toml::Table::new(),
        };
        let e = build_sample_estimator(&spec).err().unwrap();
        assert!(e.contains("instrument_delay") && e.contains("differentiator_window"), "{e}");
        spec.options.insert("instrument_delay".into(), toml::Value::Integer(21));
        assert_eq!(build_sample_estimator(&spec).unwrap().method(), "rls-iv");
        spec.options.insert("instrument_delay".into(), toml::Value::Integer(0));
        assert!(build_sample_estimator(&spec).err().unwrap().contains("≥ 1"));
    }

    /// A scenario's batch entry takes the fit's options and the experiment's `samples`, no
    /// other (fdoe none: the experiment refuses it); a real-time estimator has no fit options.
    #[test]
    fn a_batch_entry_takes_the_fit_options_and_its_samples() {
        for k in EstimatorKind::ALL {
            let entry: Vec<&str> =
                k.options().iter().copied().filter(|o| *o != "samples").collect();
            match k {
                EstimatorKind::Oe | EstimatorKind::Fem => {
                    assert_eq!(entry, k.fit_options(), "{}", k.name());
                    assert!(k.options().contains(&"samples"), "{}", k.name());
                }
                EstimatorKind::Fdoe => assert!(k.options().is_empty()),
                _ => assert!(k.fit_options().is_empty(), "{}", k.name()),
            }
        }
    }

    #[test]
    fn builds_every_estimator_over_the_same_structure() {
        let st = ModelStructure::longitudinal();
        let pr = Priors::generic(&st);
        let online: Vec<EstimatorKind> =
            EstimatorKind::ALL.iter().copied().filter(|k| !k.is_batch()).collect();
        assert_eq!(online.len(), 8, "{online:?}");
        for k in online {
            let e = build(k, st, pr, &EstimatorOptions::default()).unwrap();
            assert_eq!(e.method(), k.name());
            assert_eq!(e.structure().n_params(), 12);
            assert!(e.estimates().value(0).is_none(), "{}: identified before data", k.name());
        }
        let bad = EstimatorOptions { forgetting: 1.5, ..Default::default() };
        let err = build(EstimatorKind::Rls, st, pr, &bad).err().unwrap().to_string();
        assert!(err.starts_with("estimator `rls`: invalid configuration `forgetting`"), "{err}");
        // The FTR grid option reaches the estimator: 0.1–3.0 Hz in 0.04 Hz is 73 frequencies,
        // over the 64 of `ftr::MAX_FREQUENCIES`; 0.1–1.7 Hz (41) builds.
        let wide = EstimatorOptions { ftr_grid_hz: Some((0.1, 3.0, 0.04)), ..Default::default() };
        let err = build(EstimatorKind::Ftr, st, pr, &wide).err().unwrap().to_string();
        assert!(err.starts_with("estimator `ftr`: invalid configuration `f_step_hz`"), "{err}");
        let grid = EstimatorOptions { ftr_grid_hz: Some((0.1, 1.7, 0.04)), ..Default::default() };
        assert!(build(EstimatorKind::Ftr, st, pr, &grid).is_ok());
        // The EKF's flight model needs a state set: Cm alone does not determine one.
        let cm = ModelStructure::empty()
            .with(aeroident_estimators::Coefficient::Cm, &[aeroident_estimators::Term::Alpha]);
        let err = build(EstimatorKind::Ekf, cm, Priors::generic(&cm), &EstimatorOptions::default())
            .err()
            .unwrap()
            .to_string();
        assert!(err.starts_with("estimator `ekf`:"), "{err}");
    }
}
