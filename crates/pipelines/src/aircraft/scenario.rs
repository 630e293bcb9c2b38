//! Scenario files of the aircraft experiments (`scenarios/f16/*.toml`, `scenarios/default.toml`).
//!
//! ```toml
//! kind = "run"                          # the one scenario format's kind (crate::scenario_kind)
//! name = "t4_7_case4"                  # used in reports
//! description = "Table 4.7 case 4: ΔCm_α alone, 1 Hz 0.05° sine"
//! duration_s = 10.0
//! dt_s = 0.01                           # RK4 step and sample interval (100 Hz)
//! aerodynamics = "tables"              # optional: "tables" (default) or "linear", the
//!                                       # tables' expansion at the trim (matched truth of the
//!                                       # linear six-axis structure)
//!
//! [trim]                                # wings-level trim point (thesis: 20,000 ft, 675 ft/s)
//! vt_fps = 675.0
//! alt_ft = 20000.0
//! xcg = 0.30                            # cg, fraction of c̄ (default 0.30: open-loop stable)
//!
//! [[input]]                             # pilot command added to the trim value
//! channel = "elevator"                  # elevator | aileron | rudder | throttle
//! kind = "sine"                         # any aeroident_signals::InputConfig
//! amplitude_deg = 0.05
//! frequency_hz = 1.0
//!
//! [sensors]                             # optional; default: noise-free
//! noise = true
//! seed = 1
//! scale = 1.0                           # multiplies every σ of the default sensor table
//! differentiator_window = 11            # sample-driven estimators: ṗ q̇ ṙ α̇ differentiator
//! alignment = "matched"                 # other channels: "matched" smoother | "delay"
//!
//! [[sensors.channel]]                   # optional, any number: more sensor errors on one
//! channel = "alpha_rad"                 # air-data channel of the sample-driven estimators
//! bias = 0.002                          # (vt_mps alpha_rad beta_rad p_rad_s q_rad_s r_rad_s
//! lag_tau_s = 0.02                      # phi_rad theta_rad psi_rad ax_mps2 ay_mps2 az_mps2),
//! gauss_markov_sigma = 0.001            # SI units; keys of aeroident_signals::SensorConfig
//! gauss_markov_tau_s = 30.0             # (bias, lag_tau_s, gauss_markov_sigma + _tau_s,
//! delay_s = 0.02                        # delay_s | delay_samples in whole steps, quantum);
//! quantum = 0.0001                      # white σ, rate 1/dt_s and seed stay the table's
//!
//! [increments.Cm_alpha]                 # one table per TRUE increment of the reference F-16,
//! truth = 0.0015                        # named with the vocabulary (super::increments);
//! lower = 0.001                         # per rad / per unit hat-rate about the trim point.
//! upper = 0.002                         # bounds (3.121) → prior √(lower·upper) (3.122), for
//! lambda_per_s = 1e-7                   # the two-aircraft estimators: surface gain λ and
//! eta = 1e-9                            # η of the published SMPE,
//! gradient_gain = 1e3                   # λ of the model-reference gradient law (3.3),
//! initial = 0.0014                      # optional initial estimate (default the prior)
//! step_to = 0.003                       # optional sudden damage: the increment becomes
//! step_at_s = 10.0                      # step_to at step_at_s (or: step_to_fraction = -0.3,
//!                                       # i.e. −0.3 × the F-16's own local derivative)
//! thesis_convergence_time_s = 0.4       # optional, for the report
//! thesis_note = "≈0.4 s"                # optional, verbatim claim
//!
//! [[estimator]]                         # two-aircraft (thesis Fig. 3.2) estimators, each
//! kind = "published"                    # with its own estimated F-16:
//! reading = "implicit"                  # published | corrected | mr-gradient
//! params = ["Cm_alpha"]                 # increments it estimates (1–4)
//!
//! [[estimator]]                         # sample-driven estimators (aeroident_estimators::
//! kind = "rls"                          # Estimator) fed one AirDataSample per step:
//! model = "six-axis"                    # preset name, a list of parameter names, or a model
//!                                       # file (`….toml`, relative to this file: e.g. the
//!                                       # model.toml of `replay --model auto`)
//! forgetting = 0.995                    # method options
//! ```
//! Corrected estimator keys: `lambda_per_s`, `information_per_s`, `tracking_weight`,
//! `forgetting_per_s` (see [`aeroident_estimators::smpe::CorrectedConfig`]). Optional
//! `label` on every estimator. Winds: `[[wind]]` entries ([`WindConfig`]) and
//! `estimator_wind = "unknown" | "known"` (for the two-aircraft estimators' model).
//!
//! Sample-driven kinds (built by the shared factory, `crate::estimators::build`): `rls` and
//! `ftr` (option `forgetting` ∈ (0, 1] per sample, default 1; FTR also `grid_hz = [f_min, f_max,
//! step]`, default Morelli's 0.1–1.5 Hz in 0.04 Hz), `ekf` (options `parameter_walk_per_sqrt_s`,
//! `samples = "raw" | "smoothed"`, default raw: [`SampleEstimatorSpec::raw_samples`];
//! `blocks = true`: a longitudinal and a lateral filter, `aeroident_estimators::ekf::EkfBlocks`), `smpe`,
//! `smpe-corrected`, `smpe-finite-time` (options `forgetting`, `sliding_gain_per_s`,
//! `reaching_rate_per_s`; `aeroident_estimators::finite_time`), `gradient`. Batch kind `oe` (output error fitted after the flight to the
//! recorded samples of the window after the damage) and `fem` (the filter-error method, output
//! error with process noise), with the options a recorded flight's fit takes
//! ([`aeroident_registry::estimators::EstimatorKind::fit_options`]: `initial_states`, `step`,
//! `bootstrap_refits`, `max_iterations`, `robust` for `oe`; `initial_states`,
//! `max_iterations`, `process_noise`, `gain_constraint` for `fem`) and `samples = "raw" |
//! "smoothed"`; [`super::batch`].
//!
//! The old syntax (`[params.dCm_alpha]`, `params = ["dCm_alpha"]`, `kind = "gradient"` for the
//! two-aircraft gradient law) is refused with a message saying what to write instead.

use std::collections::BTreeMap;
use std::path::Path;

use aeroident_estimators::vocabulary::{ModelStructure, Param};
use aeroident_signals::{InputConfig, WindConfig};
use serde::Deserialize;

use super::increments::{self, parse_increment};
use crate::Named;
pub use crate::estimators::SampleEstimatorSpec;
use aeroident_io::message::short;

/// The default scenario (`scenarios/default.toml`), embedded so the main job runs from any
/// directory.
pub const DEFAULT_SCENARIO: &str = include_str!("../../../../scenarios/default.toml");

/// How [`DEFAULT_SCENARIO`] is named in messages.
pub const DEFAULT_ORIGIN: &str = "<embedded scenarios/default.toml>";

/// Errors reading or validating a scenario. Each names the file and the field.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("cannot read scenario `{path}`: {source}")]
    Io {
        /// File path.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// TOML syntax or schema error (the message carries line and column).
    #[error("scenario `{path}`: {message}")]
    Parse {
        /// File path (or `<embedded default>`).
        path: String,
        /// Parser message with the line.
        message: String,
    },
    /// A value is out of range.
    #[error("scenario `{path}`: `{field}`: {reason}")]
    Invalid {
        /// File path.
        path: String,
        /// Offending field.
        field: String,
        /// Why.
        reason: String,
    },
    /// The file's `kind` is missing or names another command's scenario.
    #[error(transparent)]
    Kind(#[from] crate::scenario_kind::KindError),
}

/// Control channel a pilot input acts on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Channel {
    /// Elevator, rad (input added to the trim deflection).
    Elevator,
    /// Aileron, rad.
    Aileron,
    /// Rudder, rad.
    Rudder,
    /// Throttle, 0–1.
    Throttle,
}

/// One pilot input (TOML `[[input]]`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct InputSpec {
    /// The control it acts on.
    pub channel: Channel,
    /// The signal (kind and parameters, degrees converted in `aeroident_signals::config`).
    #[serde(flatten)]
    pub signal: InputConfig,
}

/// The trim point (TOML `[trim]`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrimSpec {
    /// True airspeed, ft/s (thesis: 675).
    #[serde(default = "default_vt")]
    pub vt_fps: f64,
    /// Altitude, ft (thesis: 20,000).
    #[serde(default = "default_alt")]
    pub alt_ft: f64,
    /// cg position, fraction of c̄. Default 0.30: the open-loop F-16 is statically unstable
    /// at the nominal 0.35 at this flight condition (q diverges within ~10 s; data README §7).
    #[serde(default = "default_xcg")]
    pub xcg: f64,
}

fn default_vt() -> f64 {
    675.0
}
fn default_alt() -> f64 {
    20_000.0
}
fn default_xcg() -> f64 {
    0.30
}

impl Default for TrimSpec {
    fn default() -> Self {
        Self { vt_fps: default_vt(), alt_ft: default_alt(), xcg: default_xcg() }
    }
}

/// Sensor model switch (TOML `[sensors]`); levels in [`super::sensors`].
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    /// Add noise to the measured states and derivatives.
    #[serde(default)]
    pub noise: bool,
    /// Seed of the noise generators.
    #[serde(default)]
    pub seed: u64,
    /// Factor on every σ of the default table (1 = the cited levels).
    #[serde(default = "one")]
    pub scale: f64,
    /// Sample-driven estimators: window of the causal differentiator that forms ṗ q̇ ṙ α̇
    /// from the noisy gyros and vane, samples (odd, ≥ 3; default 11).
    #[serde(default = "default_window")]
    pub differentiator_window: usize,
    /// Sample-driven estimators: how the other channels are aligned with the differentiated
    /// ones ([`super::air_data`]).
    #[serde(default)]
    pub alignment: Alignment,
    /// Sample-driven estimators: sensor errors beyond the white noise on some of the twelve
    /// air-data channels (TOML `[[sensors.channel]]`).
    #[serde(default)]
    pub channel: Vec<ChannelSensorSpec>,
}

/// One `[[sensors.channel]]` entry: bias, lag, Gauss–Markov drift, transport delay and
/// quantisation on one of the air-data channels of the sample-driven estimators
/// ([`super::sensors::sensed_channels`]), in that channel's SI units (rad, m/s, m/s²) and
/// seconds; the keys and their meaning are those of [`aeroident_signals::SensorConfig`]. The
/// white noise, sample rate (`1/dt_s`) and seed stay the experiment's, so the white draws are
/// the same with or without the entry. The two-aircraft estimators' sensors do not read it.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelSensorSpec {
    /// The channel, e.g. `alpha_rad`.
    pub channel: String,
    /// Constant bias (channel units).
    #[serde(default)]
    pub bias: f64,
    /// Scale factor on the truth (default 1; `aeroident_signals::SensorParameters::scale`).
    #[serde(default = "unit_scale")]
    pub scale: f64,
    /// Gauss–Markov stationary σ (channel units), with `gauss_markov_tau_s`.
    pub gauss_markov_sigma: Option<f64>,
    /// Gauss–Markov correlation time (s), with `gauss_markov_sigma`.
    pub gauss_markov_tau_s: Option<f64>,
    /// First-order lag time constant (s).
    pub lag_tau_s: Option<f64>,
    /// Transport delay (s), a whole number of steps.
    pub delay_s: Option<f64>,
    /// Transport delay (steps).
    pub delay_samples: Option<usize>,
    /// Quantisation LSB (channel units).
    pub quantum: Option<f64>,
}

/// The default [`ChannelSensorSpec::scale`]: a sensor that reads the truth's size.
fn unit_scale() -> f64 {
    1.0
}

impl ChannelSensorSpec {
    /// The channel's sensor: these errors on white noise of σ `white_sigma` (channel units),
    /// sampled every `dt_s` (s), keyed with `seed`.
    ///
    /// # Errors
    /// [`aeroident_signals::SignalError`] naming the bad key (e.g. a `delay_s` that is not a
    /// whole number of steps, a lone `gauss_markov_sigma`, a non-positive `lag_tau_s`).
    pub fn build(
        &self,
        white_sigma: f64,
        dt_s: f64,
        seed: u64,
    ) -> Result<aeroident_signals::SensorModel, aeroident_signals::SignalError> {
        let config = aeroident_signals::SensorConfig {
            channel: self.channel.clone(),
            white_sigma,
            bias: self.bias,
            scale: self.scale,
            gauss_markov_sigma: self.gauss_markov_sigma,
            gauss_markov_tau_s: self.gauss_markov_tau_s,
            sample_rate_hz: 1.0 / dt_s,
            delay_s: self.delay_s,
            delay_samples: self.delay_samples,
            quantum: self.quantum,
            lag_tau_s: self.lag_tau_s,
            seed: Some(seed),
        };
        config.build(0)
    }
}

pub use crate::condition::Alignment;

fn one() -> f64 {
    1.0
}

fn default_window() -> usize {
    super::sensors::DIFFERENTIATOR_WINDOW
}

impl Default for SensorSpec {
    fn default() -> Self {
        Self {
            noise: false,
            seed: 0,
            scale: 1.0,
            differentiator_window: default_window(),
            alignment: Alignment::Matched,
            channel: Vec::new(),
        }
    }
}

/// One true increment of the reference aircraft and the two-aircraft estimators' settings for
/// it (TOML `[increments.<name>]`), per rad / per unit hat-rate, about the trim point.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IncrementEntry {
    /// True value of the reference aircraft's increment (default 0: the nominal F-16).
    #[serde(default)]
    pub truth: f64,
    /// Lower bound (3.121); needed when a two-aircraft estimator estimates it.
    pub lower: Option<f64>,
    /// Upper bound (3.121).
    pub upper: Option<f64>,
    /// Surface gain λ of the published SMPE, 1/s.
    #[serde(default = "one")]
    pub lambda_per_s: f64,
    /// η of the published SMPE.
    #[serde(default = "default_eta")]
    pub eta: f64,
    /// Gain λ of the model-reference gradient law (3.3).
    pub gradient_gain: Option<f64>,
    /// Initial estimate (default: the prior (3.122), the geometric mean of the bounds).
    pub initial: Option<f64>,
    /// Increment after a sudden change (damage).
    pub step_to: Option<f64>,
    /// Increment after the change as a fraction of the nominal F-16's own local derivative of
    /// this parameter at the trim point (e.g. `-0.3` on `Cm_alpha`: 30 % of the pitch
    /// stiffness lost). Alternative to `step_to`.
    pub step_to_fraction: Option<f64>,
    /// Time of the change, s.
    pub step_at_s: Option<f64>,
    /// The thesis's reported convergence time, s (report only).
    pub thesis_convergence_time_s: Option<f64>,
    /// The thesis's claim verbatim, e.g. `">20 s"` (report only).
    pub thesis_note: Option<String>,
}

fn default_eta() -> f64 {
    1e-9
}

impl IncrementEntry {
    /// `(lower, upper)` when both are given.
    pub fn bounds(&self) -> Option<(f64, f64)> {
        self.lower.zip(self.upper)
    }

    /// The initial estimate: `initial`, else the thesis prior (3.122) `±√(lower·upper)`, else
    /// (bounds straddling zero) the middle of the bounds; 0 without bounds.
    pub fn initial_estimate(&self) -> f64 {
        self.initial.unwrap_or_else(|| match self.bounds() {
            Some((lo, up)) => aeroident_estimators::smpe::ParamSpec::geometric_mean(lo, up)
                .unwrap_or(0.5 * (lo + up)),
            None => 0.0,
        })
    }
}

/// Reading of the published estimator's implicit equation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ReadingSpec {
    /// Solve the equation for θ̂ at each sample.
    Implicit,
    /// Previous θ̂ on the right-hand side.
    Explicit,
}

/// One estimator (TOML `[[estimator]]`).
#[derive(Debug, Clone, PartialEq)]
pub enum EstimatorSpec {
    /// The thesis's SMPE as published (3.163)–(3.175): one engine for the moment increments
    /// (sliding states p, q, r) and one per force increment (α, V_T, β).
    Published {
        /// Implicit or explicit reading.
        reading: ReadingSpec,
        /// Increments to estimate.
        params: Vec<Param>,
        /// Label in outputs (default `published-<reading>`).
        label: Option<String>,
    },
    /// The corrected SMPE of the proof-of-concept work, one engine for all its increments.
    Corrected {
        /// Increments to estimate.
        params: Vec<Param>,
        /// Surface gain λ, 1/s.
        lambda_per_s: f64,
        /// Information weight κ, 1/s.
        information_per_s: f64,
        /// Weight of the surface term.
        tracking_weight: f64,
        /// Forgetting rate, 1/s.
        forgetting_per_s: f64,
        /// Label in outputs (default `corrected`).
        label: Option<String>,
    },
    /// The thesis's model-reference gradient law (3.3), TOML `kind = "mr-gradient"`.
    MrGradient {
        /// Increments to estimate.
        params: Vec<Param>,
        /// Label in outputs (default `mr-gradient`).
        label: Option<String>,
    },
    /// A sample-driven estimator.
    Sample(SampleEstimatorSpec),
}

/// The TOML shape of the two-aircraft estimators (names as written).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
enum RawTwoAircraft {
    Published {
        reading: ReadingSpec,
        params: Vec<String>,
        label: Option<String>,
    },
    Corrected {
        params: Vec<String>,
        #[serde(default = "default_corr_lambda")]
        lambda_per_s: f64,
        #[serde(default = "default_information")]
        information_per_s: f64,
        #[serde(default)]
        tracking_weight: f64,
        #[serde(default)]
        forgetting_per_s: f64,
        label: Option<String>,
    },
    MrGradient {
        params: Vec<String>,
        label: Option<String>,
    },
}

fn default_corr_lambda() -> f64 {
    5.0
}
fn default_information() -> f64 {
    100.0
}

impl EstimatorSpec {
    /// The increments a two-aircraft estimator estimates (empty for a sample-driven one).
    pub fn param_names(&self) -> &[Param] {
        match self {
            EstimatorSpec::Published { params, .. }
            | EstimatorSpec::Corrected { params, .. }
            | EstimatorSpec::MrGradient { params, .. } => params,
            EstimatorSpec::Sample(_) => &[],
        }
    }

    /// Whether it is a two-aircraft (estimated-F-16) estimator.
    pub fn is_two_aircraft(&self) -> bool {
        !matches!(self, EstimatorSpec::Sample(_))
    }

    /// Output label.
    pub fn label(&self) -> String {
        match self {
            EstimatorSpec::Published { label, reading, .. } => label.clone().unwrap_or_else(|| {
                match reading {
                    ReadingSpec::Implicit => "published-implicit",
                    ReadingSpec::Explicit => "published-explicit",
                }
                .into()
            }),
            EstimatorSpec::Corrected { label, .. } => {
                label.clone().unwrap_or_else(|| "corrected".into())
            }
            EstimatorSpec::MrGradient { label, .. } => {
                label.clone().unwrap_or_else(|| "mr-gradient".into())
            }
            EstimatorSpec::Sample(s) => s.label.clone().unwrap_or_else(|| s.kind.clone()),
        }
    }
}

/// Whether the estimators and the estimated aircraft are told the wind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EstimatorWind {
    /// Still air in the estimated model (a real aircraft without a wind estimate).
    #[default]
    Unknown,
    /// The reference aircraft's wind is passed to the estimated model (a perfect wind estimate).
    Known,
}

/// The reference aircraft's aerodynamics (TOML `aerodynamics`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AerodynamicsSpec {
    /// The Stevens–Lewis tables (SLJ App. A): nonlinear in α, β and the surfaces.
    #[default]
    Tables,
    /// The tables' first-order expansion at the trim ([`super::truth::linearised`]): the
    /// matched truth of the linear six-axis structure, whose local derivatives are the trim's
    /// everywhere. For separating estimator defects from model-structure error.
    Linear,
}

/// The TOML shape (names as written); [`Scenario::from_toml`] turns it into a [`Scenario`].
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScenario {
    /// `kind = "run"`, checked by [`crate::scenario_kind::check`] before this is parsed.
    #[serde(rename = "kind")]
    _kind: crate::scenario_kind::ScenarioKind,
    name: String,
    #[serde(default)]
    description: String,
    #[serde(default)]
    thesis_table: Option<String>,
    duration_s: f64,
    #[serde(default = "default_dt")]
    dt_s: f64,
    #[serde(default)]
    trim: TrimSpec,
    #[serde(default)]
    aerodynamics: AerodynamicsSpec,
    #[serde(default)]
    input: Vec<InputSpec>,
    #[serde(default)]
    wind: Vec<WindConfig>,
    #[serde(default)]
    estimator_wind: EstimatorWind,
    #[serde(default)]
    sensors: SensorSpec,
    /// The old `[params.<dName>]` tables: refused with a message.
    #[serde(default)]
    params: Option<toml::Table>,
    #[serde(default)]
    increments: BTreeMap<String, IncrementEntry>,
    #[serde(default)]
    estimator: Vec<toml::Table>,
}

/// A parsed, validated scenario. Build with [`Scenario::from_toml`] / [`Scenario::from_path`].
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// Name used in reports.
    pub name: String,
    /// One line on what it reproduces.
    pub description: String,
    /// Thesis table and case this reproduces, e.g. `"4.7"` / `1` (report grouping).
    pub thesis_table: Option<String>,
    /// Simulated time, s.
    pub duration_s: f64,
    /// Step and sample interval, s.
    pub dt_s: f64,
    /// Trim point.
    pub trim: TrimSpec,
    /// The reference aircraft's aerodynamics (default the tables).
    pub aerodynamics: AerodynamicsSpec,
    /// Pilot inputs.
    pub input: Vec<InputSpec>,
    /// Winds on the reference aircraft (body axes; `aeroident_signals::WindConfig`, e.g. the
    /// thesis's 1-cos gust (2.32) or Dryden turbulence).
    pub wind: Vec<WindConfig>,
    /// Whether the two-aircraft estimators' model knows the wind.
    pub estimator_wind: EstimatorWind,
    /// Sensors.
    pub sensors: SensorSpec,
    /// True increments of the reference aircraft and their estimator settings, by parameter.
    pub increments: BTreeMap<Param, IncrementEntry>,
    /// Estimators.
    pub estimator: Vec<EstimatorSpec>,
}

fn default_dt() -> f64 {
    0.01
}

/// Parses a list of increment names of `estimator[k].params`.
fn parse_params(names: &[String], field: &str) -> Result<Vec<Param>, (String, String)> {
    names
        .iter()
        .map(|n| parse_increment(n).map_err(|e| (field.to_string(), e.to_string())))
        .collect()
}

/// The structure of a model file (`models/*.toml`, or the `model.toml` that `replay --model
/// auto` writes), its path taken relative to `base_dir` (the scenario file's directory) unless
/// absolute; the file's name names the model. Its priors and references are not used: each
/// estimator of a scenario takes its own priors.
fn model_file(name: &str, base_dir: &Path) -> Result<(ModelStructure, String), String> {
    let path = base_dir.join(name);
    let spec = aeroident_io::ModelSpec::from_path(&path).map_err(|e| e.to_string())?;
    Ok((spec.structure, name.to_string()))
}

/// Parses one `[[estimator]]` table; model files are read relative to `base_dir`.
fn parse_estimator(
    k: usize,
    t: &toml::Table,
    base_dir: &Path,
) -> Result<EstimatorSpec, (String, String)> {
    let field = format!("estimator[{k}]");
    let kind = t
        .get("kind")
        .and_then(toml::Value::as_str)
        .ok_or_else(|| (format!("{field}.kind"), "missing or not a string".to_string()))?;
    if crate::estimators::TwoAircraftKind::from_name(kind).is_some() {
        let raw: RawTwoAircraft = toml::Value::Table(t.clone())
            .try_into()
            .map_err(|e: toml::de::Error| (field.clone(), e.message().to_string()))?;
        let pf = format!("{field}.params");
        return Ok(match raw {
            RawTwoAircraft::Published { reading, params, label } => {
                EstimatorSpec::Published { reading, params: parse_params(&params, &pf)?, label }
            }
            RawTwoAircraft::Corrected {
                params,
                lambda_per_s,
                information_per_s,
                tracking_weight,
                forgetting_per_s,
                label,
            } => EstimatorSpec::Corrected {
                params: parse_params(&params, &pf)?,
                lambda_per_s,
                information_per_s,
                tracking_weight,
                forgetting_per_s,
                label,
            },
            RawTwoAircraft::MrGradient { params, label } => {
                EstimatorSpec::MrGradient { params: parse_params(&params, &pf)?, label }
            }
        });
    }
    if crate::estimators::EstimatorKind::from_name(kind).is_none() {
        return Err((format!("{field}.kind"), crate::estimators::unknown_kind(kind)));
    }
    if t.contains_key("params") {
        let hint = if kind == "gradient" {
            "the thesis's two-aircraft gradient law (3.3) is now `kind = \"mr-gradient\"`; `kind = \"gradient\"` is the sample-driven gradient estimator, which takes `model = ...`"
        } else {
            "a sample-driven estimator takes `model = \"<preset>\"` or `model = [\"Cm_alpha\", ...]`, not `params`"
        };
        return Err((format!("{field}.params"), hint.into()));
    }
    let (model, model_name) = match t.get("model") {
        Some(toml::Value::String(name)) if name.ends_with(".toml") => {
            model_file(name, base_dir).map_err(|e| (format!("{field}.model"), e))?
        }
        Some(toml::Value::String(name)) => (
            ModelStructure::preset(name).ok_or_else(|| {
                (
                    format!("{field}.model"),
                    format!(
                        "unknown preset `{name}` (presets: {}; a model file `….toml`; or a list of parameter names)",
                        ModelStructure::PRESETS.join(", ")
                    ),
                )
            })?,
            name.clone(),
        ),
        Some(toml::Value::Array(list)) => {
            let mut st = ModelStructure::empty();
            for v in list {
                let name = v.as_str().ok_or_else(|| {
                    (format!("{field}.model"), format!("`{v}` is not a parameter name"))
                })?;
                let p = Param::from_name(name).ok_or_else(|| {
                    (
                        format!("{field}.model"),
                        format!("`{name}` is not a parameter name (`<coefficient>_<term>`)"),
                    )
                })?;
                st.insert(p);
            }
            (st, "custom".into())
        }
        Some(_) => {
            return Err((
                format!("{field}.model"),
                "a preset name or a list of parameter names".into(),
            ));
        }
        None => {
            return Err((format!("{field}.model"), "missing (e.g. `model = \"six-axis\"`)".into()));
        }
    };
    let model = model.validated().map_err(|e| (format!("{field}.model"), e.to_string()))?;
    let label = match t.get("label") {
        None => None,
        Some(toml::Value::String(s)) => Some(s.clone()),
        Some(_) => return Err((format!("{field}.label"), "must be a string".into())),
    };
    let mut options = t.clone();
    for key in ["kind", "model", "label"] {
        options.remove(key);
    }
    Ok(EstimatorSpec::Sample(SampleEstimatorSpec {
        kind: kind.into(),
        model,
        model_name,
        label,
        options,
    }))
}

/// `v` must be finite and positive; the error is `field` and why.
fn positive(field: &str, v: f64) -> Result<(), (String, String)> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err((field.into(), format!("must be finite and > 0, got {v}")))
    }
}

impl IncrementEntry {
    /// The `[increments.NAME]` table `name` is consistent: finite values within a prior's
    /// range, bounds in pairs around the initial estimate, positive rates and gains, and a
    /// sudden change either fully given (time and target) or not at all. The error is the key
    /// and why.
    fn validate(&self, name: &str) -> Result<(), (String, String)> {
        let f = |k: &str| format!("increments.{name}.{k}");
        self.validate_values(name)?;
        positive(&f("lambda_per_s"), self.lambda_per_s)?;
        positive(&f("eta"), self.eta)?;
        if let Some(g) = self.gradient_gain {
            positive(&f("gradient_gain"), g)?;
        }
        if let Some((lo, up)) = self.bounds() {
            let init = self.initial_estimate();
            if !(lo..=up).contains(&init) {
                return Err((f("initial"), format!("{init} outside [lower, upper]")));
            }
        }
        if self.step_to.is_some() && self.step_to_fraction.is_some() {
            return Err((f("step_to"), "give step_to or step_to_fraction, not both".into()));
        }
        if (self.step_to.is_some() || self.step_to_fraction.is_some()) != self.step_at_s.is_some() {
            return Err((f("step_at_s"), "step_at_s goes with step_to or step_to_fraction".into()));
        }
        if let Some(t0) = self.step_at_s
            && !(t0.is_finite() && t0 >= 0.0)
        {
            return Err((f("step_at_s"), format!("must be finite and ≥ 0, got {t0}")));
        }
        Ok(())
    }

    /// The increment's values and bounds are finite and within a prior's limit, and `lower`
    /// and `upper` come together with `lower < upper`. The increment of an aerodynamic
    /// derivative and its bounds: beyond a prior's limit no parameter is that large (a typo),
    /// and the flight would not stay finite.
    fn validate_values(&self, name: &str) -> Result<(), (String, String)> {
        let f = |k: &str| format!("increments.{name}.{k}");
        let mut finite = vec![("truth", self.truth)];
        finite.extend(self.lower.map(|v| ("lower", v)));
        finite.extend(self.upper.map(|v| ("upper", v)));
        finite.extend(self.step_to.map(|v| ("step_to", v)));
        finite.extend(self.step_to_fraction.map(|v| ("step_to_fraction", v)));
        finite.extend(self.initial.map(|v| ("initial", v)));
        let max = aeroident_estimators::ParamPrior::MAX_ABS_VALUE;
        for (k, v) in finite {
            if !(v.is_finite() && v.abs() <= max) {
                return Err((
                    f(k),
                    format!(
                        "must be finite and within ±{max:e} (no aerodynamic parameter is that large), got {v}"
                    ),
                ));
            }
        }
        match (self.lower, self.upper) {
            (Some(lo), Some(up)) if lo >= up => {
                Err((f("lower"), format!("must be below upper ({up})")))
            }
            (Some(_), None) | (None, Some(_)) => {
                Err((f("lower"), "lower and upper go together".into()))
            }
            _ => Ok(()),
        }
    }
}

impl Scenario {
    /// Parses and validates TOML text; `path` names the source in errors.
    ///
    /// # Errors
    /// [`ScenarioError::Parse`] with the line for syntax/schema errors,
    /// [`ScenarioError::Invalid`] naming the field for out-of-range values, old names and
    /// unavailable estimators.
    pub fn from_toml(text: &str, path: &str) -> Result<Self, ScenarioError> {
        crate::scenario_kind::check(text, path, crate::scenario_kind::ScenarioKind::Run)?;
        let raw: RawScenario = toml::from_str(text)
            .map_err(|e| ScenarioError::Parse { path: path.into(), message: e.to_string() })?;
        let bad = |field: String, reason: String| ScenarioError::Invalid {
            path: path.into(),
            field,
            reason,
        };
        if let Some(old) = &raw.params {
            let first = old.keys().next().cloned().unwrap_or_default();
            let new = parse_increment(&first)
                .map(|p| p.name().to_string())
                .or_else(|e| match e {
                    increments::IncrementError::OldName { new, .. } => Ok(new),
                    e => Err(e),
                })
                .unwrap_or_else(|_| "<vocabulary name>".into());
            return Err(bad(
                format!("params.{first}"),
                format!(
                    "`[params.*]` is the old syntax: write `[increments.{new}]` (increments are named with the vocabulary: dCm_alpha → Cm_alpha, dCm_q → Cm_q, dCL_alpha → CL_alpha, dCD_alpha → CD_alpha)"
                ),
            ));
        }
        let mut incs = BTreeMap::new();
        for (name, e) in raw.increments {
            let p = parse_increment(&name)
                .map_err(|e| bad(format!("increments.{name}"), e.to_string()))?;
            incs.insert(p, e);
        }
        let estimator = raw
            .estimator
            .iter()
            .enumerate()
            .map(|(k, t)| parse_estimator(k, t, Path::new(path).parent().unwrap_or(Path::new(""))))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|(f, r)| bad(f, r))?;
        let s = Scenario {
            name: raw.name,
            description: raw.description,
            thesis_table: raw.thesis_table,
            duration_s: raw.duration_s,
            dt_s: raw.dt_s,
            trim: raw.trim,
            aerodynamics: raw.aerodynamics,
            input: raw.input,
            wind: raw.wind,
            estimator_wind: raw.estimator_wind,
            sensors: raw.sensors,
            increments: incs,
            estimator,
        };
        s.validate(path)?;
        Ok(s)
    }

    /// Reads, parses and validates a scenario file.
    ///
    /// # Errors
    /// [`ScenarioError::Io`] and those of [`Scenario::from_toml`].
    pub fn from_path(path: &Path) -> Result<Self, ScenarioError> {
        let p = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|source| ScenarioError::Io { path: p.clone(), source })?;
        Self::from_toml(&text, &p)
    }

    /// The settings of an increment.
    pub fn increment(&self, p: Param) -> Option<&IncrementEntry> {
        self.increments.get(&p)
    }

    /// The earliest sudden change of any increment, s (the damage time), if any.
    pub fn damage_at_s(&self) -> Option<f64> {
        self.increments.values().filter_map(|e| e.step_at_s).reduce(f64::min)
    }

    /// Each `[[sensors.channel]]` names a distinct air-data channel and builds; the error is
    /// the key (`sensors.channel[k]` or its `.channel`) and why.
    fn validate_channel_sensors(&self) -> Result<(), (String, String)> {
        let known = super::sensors::sensed_channels().map(|(name, _)| name);
        for (k, c) in self.sensors.channel.iter().enumerate() {
            let key = format!("sensors.channel[{k}]");
            if !known.contains(&c.channel.as_str()) {
                let why = format!("unknown channel `{}`; known: {}", c.channel, known.join(", "));
                return Err((format!("{key}.channel"), why));
            }
            if self.sensors.channel[..k].iter().any(|o| o.channel == c.channel) {
                return Err((format!("{key}.channel"), format!("`{}` given twice", c.channel)));
            }
            c.build(0.0, self.dt_s, 0).map_err(|e| (key, e.to_string()))?;
        }
        Ok(())
    }

    /// Every setting of the parsed file is usable, checked in file order (run, sensors,
    /// increments, estimators, inputs, wind) so the first error is the first a reader meets;
    /// [`ScenarioError::Invalid`] names the key of `path` and why.
    fn validate(&self, path: &str) -> Result<(), ScenarioError> {
        let bad = |(field, reason): (String, String)| ScenarioError::Invalid {
            path: path.into(),
            field,
            reason,
        };
        self.validate_run().map_err(bad)?;
        self.validate_channel_sensors().map_err(bad)?;
        for (p, e) in &self.increments {
            e.validate(p.name()).map_err(bad)?;
        }
        self.validate_estimators().map_err(bad)?;
        for (k, i) in self.input.iter().enumerate() {
            i.signal.build().map_err(|e| bad((format!("input[{k}]"), e.to_string())))?;
            i.signal.check_sampled_every(self.dt_s).map_err(|r| bad((format!("input[{k}]"), r)))?;
        }
        self.validate_orthogonal_sets().map_err(|(k, r)| bad((format!("input[{k}]"), r)))?;
        for (k, w) in self.wind.iter().enumerate() {
            w.build().map_err(|e| bad((format!("wind[{k}]"), e.to_string())))?;
        }
        Ok(())
    }

    /// The run's own settings: positive duration and step (at most 1e7 steps, a run that
    /// would not end otherwise; a step no longer than the run), a cg in the F-16 model's range
    /// (the trim fails outside it, once per Monte Carlo run), a positive trim airspeed at an altitude of the F-16 data
    /// (0–60 000 ft), a non-negative sensor noise scale and an odd differentiator window of at
    /// least 3 (a whole-sample lag). The error is the key and why.
    fn validate_run(&self) -> Result<(), (String, String)> {
        positive("duration_s", self.duration_s)?;
        positive("dt_s", self.dt_s)?;
        if self.duration_s / self.dt_s > 1e7 {
            return Err(("duration_s".into(), "more than 1e7 steps".into()));
        }
        if self.dt_s > self.duration_s {
            return Err((
                "dt_s".into(),
                format!(
                    "{} s is longer than duration_s {} s: the run would hold no step",
                    short(self.dt_s),
                    short(self.duration_s)
                ),
            ));
        }
        positive("trim.vt_fps", self.trim.vt_fps)?;
        let (lo, hi) = (aeroident_models::f16::XCG_MIN, aeroident_models::f16::XCG_MAX);
        if !(lo..=hi).contains(&self.trim.xcg) {
            return Err((
                "trim.xcg".into(),
                format!(
                    "{} is outside the F-16 model's cg range {lo}–{hi} (fraction of c̄)",
                    short(self.trim.xcg)
                ),
            ));
        }
        if !(self.trim.alt_ft.is_finite() && (0.0..=60_000.0).contains(&self.trim.alt_ft)) {
            return Err((
                "trim.alt_ft".into(),
                format!("must be in [0, 60000], got {}", self.trim.alt_ft),
            ));
        }
        if !(self.sensors.scale.is_finite() && self.sensors.scale >= 0.0) {
            return Err((
                "sensors.scale".into(),
                format!("must be ≥ 0, got {}", self.sensors.scale),
            ));
        }
        let w = self.sensors.differentiator_window;
        if w < 3 || w.is_multiple_of(2) {
            return Err((
                "sensors.differentiator_window".into(),
                format!("must be odd and ≥ 3 (a whole-sample lag), got {w}"),
            ));
        }
        Ok(())
    }

    /// At least one `[[estimator]]`, each one that builds, with distinct labels; a
    /// two-aircraft estimator's increments as [`Self::validate_estimator_params`] requires.
    /// The error is the key and why.
    fn validate_estimators(&self) -> Result<(), (String, String)> {
        if self.estimator.is_empty() {
            return Err(("estimator".into(), "at least one [[estimator]] is needed".into()));
        }
        for (k, e) in self.estimator.iter().enumerate() {
            if let EstimatorSpec::Sample(s) = e {
                if crate::estimators::is_batch_kind(&s.kind) {
                    super::batch::config(s).map_err(|r| (format!("estimator[{k}]"), r))?;
                } else {
                    crate::estimators::build_sample_estimator(s)
                        .map_err(|r| (format!("estimator[{k}]"), r))?;
                }
                continue;
            }
            self.validate_estimator_params(k, e)?;
        }
        let mut labels = std::collections::BTreeSet::new();
        for e in &self.estimator {
            if !labels.insert(e.label()) {
                return Err(("estimator.label".into(), format!("duplicate label `{}`", e.label())));
            }
        }
        Ok(())
    }

    /// The increments of the two-aircraft estimator `e` (`estimator[k]`): 1 to 4 distinct ones,
    /// each with an `[increments.NAME]` table and bounds, a gradient gain for the
    /// model-reference gradient estimator, and same-signed bounds for the published SMPE
    /// (its gain margin, (3.124)). The error is the key and why.
    fn validate_estimator_params(
        &self,
        k: usize,
        e: &EstimatorSpec,
    ) -> Result<(), (String, String)> {
        let names = e.param_names();
        if names.is_empty() || names.len() > 4 {
            return Err((format!("estimator[{k}].params"), "1 to 4 increments".into()));
        }
        for p in names {
            let n = p.name();
            let Some(entry) = self.increment(*p) else {
                return Err((
                    format!("estimator[{k}].params"),
                    format!("`{n}` has no [increments.{n}] table"),
                ));
            };
            let Some((lo, up)) = entry.bounds() else {
                return Err((
                    format!("increments.{n}.lower"),
                    "a two-aircraft estimator needs the bounds lower and upper".into(),
                ));
            };
            if matches!(e, EstimatorSpec::MrGradient { .. }) && entry.gradient_gain.is_none() {
                return Err((
                    format!("increments.{n}.gradient_gain"),
                    "needed by the model-reference gradient estimator".into(),
                ));
            }
            if matches!(e, EstimatorSpec::Published { .. }) && lo * up <= 0.0 {
                return Err((
                    format!("increments.{n}.lower"),
                    "the published SMPE needs same-signed bounds (gain margin (3.124))".into(),
                ));
            }
        }
        if names.iter().collect::<std::collections::BTreeSet<_>>().len() != names.len() {
            return Err((format!("estimator[{k}].params"), "duplicate increment".into()));
        }
        Ok(())
    }

    /// Members of one orthogonal multisine set must share period, pool, size and start, and
    /// take distinct indices (otherwise they are not orthogonal).
    fn validate_orthogonal_sets(&self) -> Result<(), (usize, String)> {
        let mut first: Option<(f64, &Vec<u32>, usize, f64)> = None;
        let mut seen = std::collections::BTreeSet::new();
        for (k, i) in self.input.iter().enumerate() {
            if let InputConfig::OrthogonalMultisine {
                base_period_s,
                harmonics,
                inputs,
                index,
                start_s,
                ..
            } = &i.signal
            {
                let this = (*base_period_s, harmonics, *inputs, *start_s);
                match first {
                    None => first = Some(this),
                    Some(f) if f != this => {
                        return Err((
                            k,
                            "members of an orthogonal multisine set must share base_period_s, harmonics, inputs and start_s".into(),
                        ));
                    }
                    Some(_) => {}
                }
                if !seen.insert(*index) {
                    return Err((k, format!("orthogonal multisine index {index} used twice")));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimators::{TwoAircraftKind, unknown_kind};

    /// `[[sensors.channel]]` entries parse into their keys, and a bad entry is refused naming
    /// the key: an unknown channel, a channel given twice, a delay that is not whole steps, a
    /// lone Gauss–Markov σ, an unknown key.
    #[test]
    fn channel_sensor_entries_parse_and_bad_ones_name_the_key() {
        let head = "kind = \"run\"\nname = \"t\"\nduration_s = 1.0\ndt_s = 0.01\n";
        let rls = "[[estimator]]\nkind = \"rls\"\nmodel = \"six-axis\"\n";
        let with = |entries: &str| Scenario::from_toml(&format!("{head}{entries}{rls}"), "t.toml");
        let ok = with(
            "[[sensors.channel]]\nchannel = \"q_rad_s\"\nbias = 0.001\ndelay_s = 0.03\n\
             [[sensors.channel]]\nchannel = \"az_mps2\"\nquantum = 0.01\nlag_tau_s = 0.05\n",
        )
        .unwrap();
        let c = &ok.sensors.channel;
        assert_eq!((c.len(), c[0].channel.as_str(), c[0].bias), (2, "q_rad_s", 0.001));
        assert_eq!(
            (c[0].delay_s, c[1].quantum, c[1].lag_tau_s),
            (Some(0.03), Some(0.01), Some(0.05))
        );
        let err = |entries: &str| with(entries).unwrap_err().to_string();
        let e = err("[[sensors.channel]]\nchannel = \"alpha_deg\"\n");
        assert!(e.contains("`sensors.channel[0].channel`") && e.contains("alpha_deg"), "{e}");
        let e = err(
            "[[sensors.channel]]\nchannel = \"p_rad_s\"\n[[sensors.channel]]\nchannel = \"p_rad_s\"\n",
        );
        assert!(e.contains("`sensors.channel[1].channel`") && e.contains("twice"), "{e}");
        let e = err("[[sensors.channel]]\nchannel = \"p_rad_s\"\ndelay_s = 0.015\n");
        assert!(e.contains("`sensors.channel[0]`") && e.contains("delay_s"), "{e}");
        let e = err("[[sensors.channel]]\nchannel = \"p_rad_s\"\ngauss_markov_sigma = 0.1\n");
        assert!(e.contains("gauss_markov"), "{e}");
        let e = err("[[sensors.channel]]\nchannel = \"p_rad_s\"\nwhite_sigma = 0.1\n");
        assert!(e.contains("white_sigma"), "{e}");
    }

    /// A true increment (or its bounds, start, step) no aerodynamic parameter can take is
    /// refused naming its key and value, as a prior beyond ±1e4 is; ±1e4 itself is accepted.
    #[test]
    fn absurd_true_increments_are_refused_naming_the_key() {
        let head = "kind = \"run\"\nname = \"t\"\nduration_s = 1.0\ndt_s = 0.01\n";
        let rls = "[[estimator]]\nkind = \"rls\"\nmodel = \"six-axis\"\n";
        let with = |inc: &str| Scenario::from_toml(&format!("{head}{inc}{rls}"), "t.toml");
        for (inc, key) in [
            ("truth = 1e308", "increments.Cm_alpha.truth"),
            ("truth = -2e4", "increments.Cm_alpha.truth"),
            ("lower = -1e300\nupper = 1.0", "increments.Cm_alpha.lower"),
            ("truth = 0.1\ninitial = 1e305", "increments.Cm_alpha.initial"),
        ] {
            let e = with(&format!("[increments.Cm_alpha]\n{inc}\n")).unwrap_err().to_string();
            assert!(e.contains(key) && e.contains("within ±1e4"), "{inc}: {e}");
        }
        let s = with("[increments.Cm_alpha]\ntruth = -1e4\n").unwrap();
        assert_eq!(s.increments.values().next().map(|e| e.truth), Some(-1e4));
    }

    /// A harmonic number past the highest a multisine takes is refused when the scenario is
    /// parsed, naming the input and the limit, before an orthogonal set's peak grid (64 points
    /// per period of the highest harmonic) is sized by it; the limit itself is accepted.
    #[test]
    fn harmonics_beyond_the_limit_are_refused_at_parse() {
        let huge = DEFAULT_SCENARIO.replacen(
            "harmonics = [5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31]",
            "harmonics = [5, 7, 4000000000, 11]",
            1,
        );
        assert_ne!(huge, DEFAULT_SCENARIO, "the default scenario's harmonics changed");
        let e = Scenario::from_toml(&huge, "d.toml").unwrap_err().to_string();
        assert!(e.contains("input[0]") && e.contains("4.000e9") && e.contains("10000"), "{e}");
        let plain = "kind = \"multisine\"\namplitude_deg = 1.0\nbase_period_s = 10.0\n";
        for (k, ok) in [(10_001u64, false), (1_000_000_000, false), (10_000, true)] {
            let text = format!("{plain}harmonics = [1, {k}]\n");
            let c: aeroident_signals::InputConfig = toml::from_str(&text).unwrap();
            let r = c.build();
            assert_eq!(r.is_ok(), ok, "{k}: {:?}", r.err());
        }
    }

    /// A step longer than the run, and a cg outside the F-16 model's range (where its trim
    /// fails, once for every Monte Carlo run), are refused when the scenario is parsed naming
    /// the key; the range's ends are accepted.
    #[test]
    fn a_step_longer_than_the_run_and_a_cg_out_of_range_are_refused_at_parse() {
        let set = |from: &str, to: &str| {
            assert!(DEFAULT_SCENARIO.contains(from), "the default scenario has no `{from}`");
            Scenario::from_toml(&DEFAULT_SCENARIO.replacen(from, to, 1), "d.toml")
        };
        let e = set("dt_s = 0.01", "dt_s = 1000.0").unwrap_err().to_string();
        assert!(e.contains("`dt_s`") && e.contains("longer than duration_s"), "{e}");
        for (xcg, ok) in [("5.0", false), ("0.05", false), ("0.1", true), ("0.5", true)] {
            let r = set("xcg = 0.30", &format!("xcg = {xcg}"));
            assert_eq!(r.is_ok(), ok, "xcg {xcg}: {:?}", r.as_ref().err().map(ToString::to_string));
            if let Err(e) = r {
                assert!(
                    e.to_string().contains("`trim.xcg`") && e.to_string().contains("0.1–0.5"),
                    "{e}"
                );
            }
        }
    }

    /// An input reaching the Nyquist frequency of the step is refused naming the input and both
    /// frequencies: the default's highest harmonic, 31 over its base period, against dt_s = 0.5 s
    /// (Nyquist 1 Hz); a sine given in rad/s is converted before the comparison.
    #[test]
    fn an_input_above_the_nyquist_frequency_is_refused_at_parse() {
        let coarse = DEFAULT_SCENARIO.replacen("dt_s = 0.01", "dt_s = 0.5", 1);
        let e = Scenario::from_toml(&coarse, "d.toml").unwrap_err().to_string();
        assert!(e.contains("input[0]") && e.contains("Nyquist frequency 1 Hz"), "{e}");
        let sine = |w: f64| -> aeroident_signals::InputConfig {
            toml::from_str(&format!("kind = \"sine\"\namplitude = 1.0\nfrequency_rad_s = {w}\n"))
                .unwrap()
        };
        let f = sine(2.0 * core::f64::consts::PI * 3.0).highest_frequency_hz().unwrap();
        assert!((f - 3.0).abs() < 1e-12, "{f}");
    }

    /// `model = "….toml"` reads a model file relative to the scenario's directory (the
    /// `model.toml` `replay --model auto` writes), and a missing or bad one is refused naming
    /// the estimator's key and the file.
    #[test]
    fn estimator_model_from_a_model_file_next_to_the_scenario() {
        let dir =
            std::env::temp_dir().join(format!("aeroident-scenario-model-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let model = "[coefficients]\nCm = [\"0\", \"alpha\", \"q\", \"de\"]\nCL = [\"0\", \"alpha\"]\nCD = [\"0\", \"alpha2\", \"alpha_q\"]\n";
        std::fs::write(dir.join("chosen.toml"), model).unwrap();
        let head = "kind = \"run\"\nname = \"t\"\nduration_s = 1.0\ndt_s = 0.01\n";
        let scenario_path = dir.join("s.toml").display().to_string();
        let with = |m: &str| {
            let text = format!("{head}[[estimator]]\nkind = \"rls\"\nmodel = \"{m}\"\n");
            Scenario::from_toml(&text, &scenario_path)
        };
        let s = with("chosen.toml").unwrap();
        let EstimatorSpec::Sample(e) = &s.estimator[0] else { panic!("a sample estimator") };
        let names: Vec<&str> = e.model.names().collect();
        assert_eq!(
            names,
            [
                "CL_0",
                "CL_alpha",
                "CD_0",
                "CD_alpha2",
                "CD_alpha_q",
                "Cm_0",
                "Cm_alpha",
                "Cm_q",
                "Cm_de"
            ]
        );
        assert_eq!(e.model_name, "chosen.toml");
        let e = with("missing.toml").unwrap_err().to_string();
        assert!(e.contains("estimator[0].model") && e.contains("missing.toml"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Every option a two-aircraft kind declares is one its entry parses (with a valid value),
    /// and any other key is refused naming it: the registry and the parser cannot drift apart.
    #[test]
    fn declared_two_aircraft_options_are_the_parsed_ones() {
        for &kind in TwoAircraftKind::ALL {
            let mut t = toml::Table::new();
            t.insert("kind".into(), kind.name().into());
            t.insert("params".into(), toml::Value::Array(vec!["Cm_alpha".into()]));
            for &o in kind.options() {
                let v: toml::Value = if o == "reading" { "implicit".into() } else { 1.0.into() };
                t.insert(o.into(), v);
            }
            let e = parse_estimator(0, &t, Path::new(""))
                .unwrap_or_else(|e| panic!("{}: {e:?}", kind.name()));
            assert_eq!(e.param_names().len(), 1);
            t.insert("no_such_option".into(), 1.0.into());
            let (field, why) = parse_estimator(0, &t, Path::new("")).unwrap_err();
            assert_eq!(field, "estimator[0]");
            assert!(why.contains("no_such_option"), "{}: {why}", kind.name());
        }
        let mut t = toml::Table::new();
        t.insert("kind".into(), "nope".into());
        let (field, why) = parse_estimator(3, &t, Path::new("")).unwrap_err();
        assert_eq!(
            (field.as_str(), why.as_str()),
            ("estimator[3].kind", unknown_kind("nope").as_str())
        );
        assert!(
            why.contains("published | corrected | mr-gradient") && why.contains("rls"),
            "{why}"
        );
    }
}
