//! Scenario files of the aircraft experiments (`scenarios/f16/*.toml`, `scenarios/default.toml`).
//!
//! ```toml
//! name = "t4_7_case4"                  # used in reports
//! description = "Table 4.7 case 4: ΔCm_α alone, 1 Hz 0.05° sine"
//! duration_s = 10.0
//! dt_s = 0.01                           # RK4 step and sample interval (100 Hz)
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
//!
//! [params.dCm_alpha]                    # one table per increment, per radian
//! truth = 0.0015
//! lower = 0.001                         # bounds (3.121) → prior √(lower·upper) (3.122)
//! upper = 0.002
//! lambda_per_s = 1e-7                   # surface gain λ of the published SMPE
//! eta = 1e-9                            # η of the published SMPE
//! gradient_gain = 1e3                   # λ of the gradient law (3.3), if used
//! initial = 0.0014                      # optional, default the prior (3.122)
//! step_to = 0.003                       # optional sudden damage: truth becomes step_to ...
//! step_at_s = 10.0                      # ... at step_at_s
//! thesis_convergence_time_s = 0.4       # optional, for the report
//! thesis_note = "≈0.4 s"                # optional, verbatim claim
//!
//! [[estimator]]
//! kind = "published"                    # published | corrected | gradient
//! reading = "implicit"                  # published: implicit | explicit
//! params = ["dCm_alpha"]
//! ```
//! Corrected estimator keys: `lambda_per_s`, `information_per_s`, `tracking_weight`,
//! `forgetting_per_s` (see [`aeroident_estimators::smpe::CorrectedConfig`]). Optional
//! `label` on every estimator. Winds: `[[wind]]` entries ([`WindConfig`]) and
//! `estimator_wind = "unknown" | "known"`.

use std::collections::BTreeMap;
use std::path::Path;

use aeroident_signals::{InputConfig, WindConfig};
use serde::Deserialize;

use super::model::Increment;

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
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
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
}

fn one() -> f64 {
    1.0
}

impl Default for SensorSpec {
    fn default() -> Self {
        Self { noise: false, seed: 0, scale: 1.0 }
    }
}

/// One increment's truth and estimator settings (TOML `[params.<name>]`), per radian.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamEntry {
    /// True value of the reference aircraft.
    pub truth: f64,
    /// Lower bound (3.121).
    pub lower: f64,
    /// Upper bound (3.121).
    pub upper: f64,
    /// Surface gain λ of the published SMPE, 1/s.
    #[serde(default = "one")]
    pub lambda_per_s: f64,
    /// η of the published SMPE.
    #[serde(default = "default_eta")]
    pub eta: f64,
    /// Gain λ of the gradient law (3.3).
    pub gradient_gain: Option<f64>,
    /// Initial estimate (default: the prior (3.122), the geometric mean of the bounds).
    pub initial: Option<f64>,
    /// Truth after a sudden change (damage).
    pub step_to: Option<f64>,
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

impl ParamEntry {
    /// The initial estimate: `initial`, else the thesis prior (3.122) `±√(lower·upper)`, else
    /// (bounds straddling zero) the middle of the bounds.
    pub fn initial_estimate(&self) -> f64 {
        self.initial.unwrap_or_else(|| {
            aeroident_estimators::smpe::ParamSpec::geometric_mean(self.lower, self.upper)
                .unwrap_or(0.5 * (self.lower + self.upper))
        })
    }

    /// The true value at `t_s`.
    pub fn truth_at(&self, t_s: f64) -> f64 {
        match (self.step_to, self.step_at_s) {
            (Some(v), Some(t0)) if t_s >= t0 => v,
            _ => self.truth,
        }
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
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum EstimatorSpec {
    /// The thesis's SMPE as published (3.163)–(3.175), one engine per coefficient group.
    Published {
        /// Implicit or explicit reading.
        reading: ReadingSpec,
        /// Increments to estimate.
        params: Vec<String>,
        /// Label in outputs (default `published-<reading>`).
        label: Option<String>,
    },
    /// The corrected SMPE of the proof-of-concept work, one engine for all its increments.
    Corrected {
        /// Increments to estimate.
        params: Vec<String>,
        /// Surface gain λ, 1/s.
        #[serde(default = "default_corr_lambda")]
        lambda_per_s: f64,
        /// Information weight κ, 1/s.
        #[serde(default = "default_information")]
        information_per_s: f64,
        /// Weight of the surface term.
        #[serde(default)]
        tracking_weight: f64,
        /// Forgetting rate, 1/s.
        #[serde(default)]
        forgetting_per_s: f64,
        /// Label in outputs (default `corrected`).
        label: Option<String>,
    },
    /// The model-reference gradient law (3.3).
    Gradient {
        /// Increments to estimate.
        params: Vec<String>,
        /// Label in outputs (default `gradient`).
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
    /// The increment names it estimates.
    pub fn param_names(&self) -> &[String] {
        match self {
            EstimatorSpec::Published { params, .. }
            | EstimatorSpec::Corrected { params, .. }
            | EstimatorSpec::Gradient { params, .. } => params,
        }
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
            EstimatorSpec::Gradient { label, .. } => {
                label.clone().unwrap_or_else(|| "gradient".into())
            }
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

/// A parsed scenario. Build with [`Scenario::from_toml`] / [`Scenario::from_path`], which
/// validate it.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Name used in reports.
    pub name: String,
    /// One line on what it reproduces.
    #[serde(default)]
    pub description: String,
    /// Thesis table and case this reproduces, e.g. `"4.7"` / `1` (report grouping).
    #[serde(default)]
    pub thesis_table: Option<String>,
    /// Simulated time, s.
    pub duration_s: f64,
    /// Step and sample interval, s.
    #[serde(default = "default_dt")]
    pub dt_s: f64,
    /// Trim point.
    #[serde(default)]
    pub trim: TrimSpec,
    /// Pilot inputs.
    #[serde(default)]
    pub input: Vec<InputSpec>,
    /// Winds on the reference aircraft (body axes; `aeroident_signals::WindConfig`, e.g. the
    /// thesis's 1-cos gust (2.32) or Dryden turbulence).
    #[serde(default)]
    pub wind: Vec<WindConfig>,
    /// Whether the estimated model knows the wind.
    #[serde(default)]
    pub estimator_wind: EstimatorWind,
    /// Sensors.
    #[serde(default)]
    pub sensors: SensorSpec,
    /// Truth and settings per increment.
    pub params: BTreeMap<String, ParamEntry>,
    /// Estimators.
    pub estimator: Vec<EstimatorSpec>,
}

fn default_dt() -> f64 {
    0.01
}

impl Scenario {
    /// Parses and validates TOML text; `path` names the source in errors.
    ///
    /// # Errors
    /// [`ScenarioError::Parse`] with the line for syntax/schema errors,
    /// [`ScenarioError::Invalid`] naming the field for out-of-range values.
    pub fn from_toml(text: &str, path: &str) -> Result<Self, ScenarioError> {
        let s: Scenario = toml::from_str(text)
            .map_err(|e| ScenarioError::Parse { path: path.into(), message: e.to_string() })?;
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
    pub fn param(&self, inc: Increment) -> Option<&ParamEntry> {
        self.params.get(inc.name())
    }

    /// The true increments `[ΔCm_α, ΔCm_q, ΔCL_α, ΔCD_α]` at `t_s` (zero where not given).
    pub fn truth_at(&self, t_s: f64) -> [f64; 4] {
        Increment::ALL.map(|i| self.param(i).map_or(0.0, |p| p.truth_at(t_s)))
    }

    fn validate(&self, path: &str) -> Result<(), ScenarioError> {
        let bad = |field: &str, reason: String| ScenarioError::Invalid {
            path: path.into(),
            field: field.into(),
            reason,
        };
        let pos = |field: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(bad(field, format!("must be finite and > 0, got {v}")))
            }
        };
        pos("duration_s", self.duration_s)?;
        pos("dt_s", self.dt_s)?;
        if self.duration_s / self.dt_s > 1e7 {
            return Err(bad("duration_s", "more than 1e7 steps".into()));
        }
        pos("trim.vt_fps", self.trim.vt_fps)?;
        if !(self.trim.alt_ft.is_finite() && (0.0..=60_000.0).contains(&self.trim.alt_ft)) {
            return Err(bad(
                "trim.alt_ft",
                format!("must be in [0, 60000], got {}", self.trim.alt_ft),
            ));
        }
        if !(self.sensors.scale.is_finite() && self.sensors.scale >= 0.0) {
            return Err(bad("sensors.scale", format!("must be ≥ 0, got {}", self.sensors.scale)));
        }
        for (name, p) in &self.params {
            let f = |k: &str| format!("params.{name}.{k}");
            if Increment::from_name(name).is_none() {
                return Err(bad(
                    &format!("params.{name}"),
                    "unknown increment; use dCm_alpha, dCm_q, dCL_alpha or dCD_alpha".into(),
                ));
            }
            for (k, v) in [("truth", p.truth), ("lower", p.lower), ("upper", p.upper)] {
                if !v.is_finite() {
                    return Err(bad(&f(k), format!("must be finite, got {v}")));
                }
            }
            if p.lower >= p.upper {
                return Err(bad(&f("lower"), format!("must be below upper ({})", p.upper)));
            }
            pos(&f("lambda_per_s"), p.lambda_per_s)?;
            pos(&f("eta"), p.eta)?;
            if let Some(g) = p.gradient_gain {
                pos(&f("gradient_gain"), g)?;
            }
            let init = p.initial_estimate();
            if !(p.lower..=p.upper).contains(&init) {
                return Err(bad(&f("initial"), format!("{init} outside [lower, upper]")));
            }
            if p.step_to.is_some() != p.step_at_s.is_some() {
                return Err(bad(&f("step_to"), "step_to and step_at_s go together".into()));
            }
        }
        if self.estimator.is_empty() {
            return Err(bad("estimator", "at least one [[estimator]] is needed".into()));
        }
        for (k, e) in self.estimator.iter().enumerate() {
            let names = e.param_names();
            if names.is_empty() || names.len() > 4 {
                return Err(bad(&format!("estimator[{k}].params"), "1 to 4 increments".into()));
            }
            for n in names {
                let Some(inc) = Increment::from_name(n) else {
                    return Err(bad(&format!("estimator[{k}].params"), format!("unknown `{n}`")));
                };
                let Some(p) = self.param(inc) else {
                    return Err(bad(
                        &format!("estimator[{k}].params"),
                        format!("`{n}` has no [params.{n}] table"),
                    ));
                };
                if matches!(e, EstimatorSpec::Gradient { .. }) && p.gradient_gain.is_none() {
                    return Err(bad(
                        &format!("params.{n}.gradient_gain"),
                        "needed by the gradient estimator".into(),
                    ));
                }
                if matches!(e, EstimatorSpec::Published { .. }) && p.lower * p.upper <= 0.0 {
                    return Err(bad(
                        &format!("params.{n}.lower"),
                        "the published SMPE needs same-signed bounds (gain margin (3.124))".into(),
                    ));
                }
            }
            if names.iter().collect::<std::collections::BTreeSet<_>>().len() != names.len() {
                return Err(bad(&format!("estimator[{k}].params"), "duplicate increment".into()));
            }
        }
        let mut labels = std::collections::BTreeSet::new();
        for e in &self.estimator {
            if !labels.insert(e.label()) {
                return Err(bad("estimator.label", format!("duplicate label `{}`", e.label())));
            }
        }
        for (k, i) in self.input.iter().enumerate() {
            i.signal.build().map_err(|e| bad(&format!("input[{k}]"), e.to_string()))?;
        }
        for (k, w) in self.wind.iter().enumerate() {
            w.build().map_err(|e| bad(&format!("wind[{k}]"), e.to_string()))?;
        }
        Ok(())
    }
}
