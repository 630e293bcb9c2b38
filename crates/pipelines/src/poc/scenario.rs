//! Scenario files of the proof-of-concept cases (`scenarios/poc/*.toml`).
//!
//! # TOML shape
//! ```toml
//! kind = "poc"                   # the one scenario format's kind (crate::scenario_kind)
//!
//! [case]
//! name = "table_4_1_case_1"      # also the output sub-directory name
//! thesis_table = "4.1"           # groups the rows of report.md
//! thesis_case = 1
//! description = "step, a = 3"
//!
//! [system]                       # the reference system (truth); kind picks (2.1)–(2.4)
//! kind = "first_order"           # first_order | first_order_nonlinear | second_order |
//! a = 3.0                        # second_order_nonlinear; a (first order) or a1, a2
//! # B = 1.4, C = 4.0, omega_rad_s = 0.7   (first_order_nonlinear only; thesis defaults)
//! # initial_state = [0.0]        (default: zeros; the estimated model starts there too)
//!
//! [input]                        # any aeroident_signals::InputConfig
//! kind = "step"
//! amplitude = 1.0
//!
//! [[parameters]]                 # one per parameter, in the order a | a1, a2
//! name = "a"
//! lower = 1.0                    # θ_low (3.29)
//! upper = 5.0                    # θ_upp
//! lambda = 5.0                   # λ_j (3.19)/(3.57), 1/s
//! # initial = 2.0                (default: the geometric mean (3.30))
//! thesis_convergence_time_s = 0.5
//!
//! [estimator]
//! eta = 0.01                     # η (3.20)
//! # gain = "shared"              shared (3.72, default) | per_parameter (k_j of (3.59))
//! # corrected_information_per_s = 1e4, corrected_tracking_weight = 1.0,
//! # corrected_forgetting_per_s = 0.0   (corrected estimator; see docs/smpe-corrected.md)
//!
//! [simulation]
//! duration_s = 5.0
//! # dt_s = 0.001                 (default 1 ms, RK4)
//! # max_abs_state = 1e9         (stop when the reference system leaves this range)
//!
//! # [noise]                      (table 4.6) band-limited white noise on every measured
//! # noise_power = 3.2e-7         state and state derivative; sample time default dt_s;
//! # seed = 1                     channel k uses seed + k.
//! # apply_to = "states_and_derivatives"   (default) | "states" (ż_m exact)
//! ```
//! Unknown keys are errors. Parse errors name the file, line and column (from the `toml`
//! crate's spans); semantic errors name the file, the key path and the reason.

use aeroident_signals::InputConfig;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Errors reading a scenario file.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("{path}: cannot read")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// TOML syntax or schema error (unknown key, wrong type, missing key).
    #[error("{path}:{line}:{column}: {message}")]
    Parse {
        /// File.
        path: PathBuf,
        /// 1-based line of the offending span.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The parser's message (names the key).
        message: String,
    },
    /// A value parsed but is not valid.
    #[error("{path}: key `{key}`: {reason}")]
    Invalid {
        /// File.
        path: PathBuf,
        /// Key path, e.g. `parameters[1].lower`.
        key: String,
        /// Why it is invalid.
        reason: String,
    },
    /// The file's `kind` is missing or names another command's scenario.
    #[error(transparent)]
    Kind(#[from] crate::scenario_kind::KindError),
}

/// The whole scenario file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PocScenario {
    /// `kind = "poc"`, checked by [`crate::scenario_kind::check`] before this is parsed.
    #[serde(rename = "kind")]
    _kind: crate::scenario_kind::ScenarioKind,
    /// Identification of the case.
    pub case: CaseInfo,
    /// Reference system.
    pub system: SystemConfig,
    /// Input `u` applied to both systems.
    pub input: InputConfig,
    /// Parameter settings, in model order.
    pub parameters: Vec<ParamConfig>,
    /// Estimator settings.
    pub estimator: EstimatorSettings,
    /// Simulation settings.
    pub simulation: SimulationConfig,
    /// Measurement noise (table 4.6 cases only).
    pub noise: Option<NoiseConfig>,
}

/// `[case]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseInfo {
    /// Case name; output sub-directory.
    pub name: String,
    /// Thesis table, e.g. `"4.1"`.
    pub thesis_table: String,
    /// Case number within the table.
    pub thesis_case: u32,
    /// One-line description.
    #[serde(default)]
    pub description: String,
}

/// `[system]`: which reference system, with its true parameters.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SystemConfig {
    /// (2.1) `ẋ = −a x + u`.
    FirstOrder {
        /// True a.
        a: f64,
        /// Initial `[x]`.
        initial_state: Option<[f64; 1]>,
    },
    /// (2.2) `ẋ = −a sin(y) x + B u`, `ẏ = −C y x + sin(ω t)`.
    FirstOrderNonlinear {
        /// True a.
        a: f64,
        /// B (thesis 1.4).
        #[serde(rename = "B", default = "default_b")]
        B: f64,
        /// C (thesis 4).
        #[serde(rename = "C", default = "default_c")]
        C: f64,
        /// ω, rad/s (thesis 0.7).
        #[serde(default = "default_omega")]
        omega_rad_s: f64,
        /// Initial `[x, y]`.
        initial_state: Option<[f64; 2]>,
    },
    /// (2.3) `ẍ = −a₂ ẋ − a₁ x + u`.
    SecondOrder {
        /// True a₁.
        a1: f64,
        /// True a₂.
        a2: f64,
        /// Initial `[x, ẋ]`.
        initial_state: Option<[f64; 2]>,
    },
    /// (2.4) `ẍ = −a₂ ẋ − a₁ x² + u`.
    SecondOrderNonlinear {
        /// True a₁.
        a1: f64,
        /// True a₂.
        a2: f64,
        /// Initial `[x, ẋ]`.
        initial_state: Option<[f64; 2]>,
    },
}

fn default_b() -> f64 {
    1.4
}
fn default_c() -> f64 {
    4.0
}
fn default_omega() -> f64 {
    0.7
}

impl SystemConfig {
    /// Parameter names in model order.
    pub fn param_names(&self) -> &'static [&'static str] {
        match self {
            Self::FirstOrder { .. } | Self::FirstOrderNonlinear { .. } => &["a"],
            _ => &["a1", "a2"],
        }
    }
}

/// `[[parameters]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamConfig {
    /// Parameter name (must match the model order: `a`, or `a1` then `a2`).
    pub name: String,
    /// Lower bound θ_low.
    pub lower: f64,
    /// Upper bound θ_upp.
    pub upper: f64,
    /// λ_j, 1/s.
    pub lambda: f64,
    /// Initial estimate (default: the geometric mean (3.30)).
    pub initial: Option<f64>,
    /// Convergence time the thesis reports, s.
    pub thesis_convergence_time_s: Option<f64>,
}

/// Lyapunov-gain form of the published estimator in TOML.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum GainConfig {
    /// One K for all parameters (3.72).
    #[default]
    Shared,
    /// k_j per parameter (3.59).
    PerParameter,
}

/// `[estimator]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimatorSettings {
    /// η of (3.20).
    pub eta: f64,
    /// Gain form of the published estimator.
    #[serde(default)]
    pub gain: GainConfig,
    /// κ of the corrected estimator, 1/s.
    #[serde(default = "default_information")]
    pub corrected_information_per_s: f64,
    /// γ of the corrected estimator.
    #[serde(default = "default_tracking")]
    pub corrected_tracking_weight: f64,
    /// ρ of the corrected estimator, 1/s.
    #[serde(default)]
    pub corrected_forgetting_per_s: f64,
}

fn default_information() -> f64 {
    1e4
}
fn default_tracking() -> f64 {
    1.0
}

/// `[simulation]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationConfig {
    /// Simulated time, s.
    pub duration_s: f64,
    /// RK4 step, s.
    #[serde(default = "default_dt")]
    pub dt_s: f64,
    /// The run stops early when any reference state exceeds this magnitude.
    #[serde(default = "default_max_state")]
    pub max_abs_state: f64,
}

fn default_dt() -> f64 {
    1e-3
}
fn default_max_state() -> f64 {
    1e9
}

/// `[noise]`: band-limited white noise on the measured states and derivatives.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseConfig {
    /// Two-sided PSD height (Simulink "noise power"), units²·s.
    pub noise_power: f64,
    /// Noise sample time, s (default: the simulation step).
    pub sample_time_s: Option<f64>,
    /// Seed of the first channel.
    pub seed: u64,
    /// Which measurements are noisy (default: states and their derivatives).
    #[serde(default)]
    pub apply_to: NoiseTarget,
}

/// Which measured signals get the noise of `[noise]`.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum NoiseTarget {
    /// `z_m` and `ż_m` (every signal the estimators read from the reference system).
    #[default]
    StatesAndDerivatives,
    /// `z_m` only; `ż_m` exact.
    States,
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

impl PocScenario {
    /// Reads and validates a scenario file.
    ///
    /// # Errors
    /// [`ScenarioError`] naming the file and the line (parse) or key (validation).
    pub fn from_path(path: &Path) -> Result<Self, ScenarioError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| ScenarioError::Io { path: path.to_path_buf(), source })?;
        Self::from_str_at(&text, path)
    }

    /// Parses and validates scenario text; `path` is only used in messages.
    ///
    /// # Errors
    /// As [`PocScenario::from_path`].
    pub fn from_str_at(text: &str, path: &Path) -> Result<Self, ScenarioError> {
        let file = path.display().to_string();
        crate::scenario_kind::check(text, &file, crate::scenario_kind::ScenarioKind::Poc)?;
        let sc: Self = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map_or((0, 0), |s| line_col(text, s.start));
            ScenarioError::Parse {
                path: path.to_path_buf(),
                line,
                column,
                message: e.message().to_string(),
            }
        })?;
        sc.validate(path)?;
        Ok(sc)
    }

    fn validate(&self, path: &Path) -> Result<(), ScenarioError> {
        let bad = |key: String, reason: String| {
            Err(ScenarioError::Invalid { path: path.to_path_buf(), key, reason })
        };
        let names = self.system.param_names();
        if self.parameters.len() != names.len() {
            return bad(
                "parameters".into(),
                format!(
                    "system `{}` has {} parameter(s) {:?}, found {}",
                    self.case.name,
                    names.len(),
                    names,
                    self.parameters.len()
                ),
            );
        }
        for (i, (p, want)) in self.parameters.iter().zip(names).enumerate() {
            let key = |k: &str| format!("parameters[{i}].{k}");
            if p.name != *want {
                return bad(
                    key("name"),
                    format!("expected `{want}` (model order), found `{}`", p.name),
                );
            }
            for (k, v) in [("lower", p.lower), ("upper", p.upper), ("lambda", p.lambda)] {
                if !v.is_finite() {
                    return bad(key(k), format!("must be finite, found {v}"));
                }
            }
            if p.lower >= p.upper {
                return bad(key("lower"), format!("{} must be below upper = {}", p.lower, p.upper));
            }
            if p.lower * p.upper <= 0.0 {
                return bad(
                    key("lower"),
                    "bounds must have one sign (the gain margin (3.32) is √(upper/lower))".into(),
                );
            }
            if p.lambda <= 0.0 {
                return bad(key("lambda"), format!("must be > 0, found {}", p.lambda));
            }
            if let Some(x) = p.initial
                && !(x.is_finite() && x >= p.lower && x <= p.upper)
            {
                return bad(key("initial"), format!("{x} is not within [lower, upper]"));
            }
            if let Some(t) = p.thesis_convergence_time_s
                && !(t.is_finite() && t >= 0.0)
            {
                return bad(key("thesis_convergence_time_s"), format!("must be ≥ 0, found {t}"));
            }
        }
        let e = &self.estimator;
        if !(e.eta.is_finite() && e.eta > 0.0) {
            return bad("estimator.eta".into(), format!("must be finite and > 0, found {}", e.eta));
        }
        if !(e.corrected_information_per_s.is_finite() && e.corrected_information_per_s > 0.0) {
            return bad("estimator.corrected_information_per_s".into(), "must be > 0".into());
        }
        if !(e.corrected_tracking_weight.is_finite() && e.corrected_tracking_weight >= 0.0) {
            return bad("estimator.corrected_tracking_weight".into(), "must be ≥ 0".into());
        }
        if !(e.corrected_forgetting_per_s.is_finite() && e.corrected_forgetting_per_s >= 0.0) {
            return bad("estimator.corrected_forgetting_per_s".into(), "must be ≥ 0".into());
        }
        let s = &self.simulation;
        if !(s.dt_s.is_finite() && s.dt_s > 0.0) {
            return bad("simulation.dt_s".into(), format!("must be > 0, found {}", s.dt_s));
        }
        if !(s.duration_s.is_finite() && s.duration_s >= s.dt_s) {
            return bad(
                "simulation.duration_s".into(),
                format!("must be ≥ dt_s, found {}", s.duration_s),
            );
        }
        if s.duration_s / s.dt_s > 1e8 {
            return bad("simulation.duration_s".into(), "more than 1e8 steps".into());
        }
        if !(s.max_abs_state.is_finite() && s.max_abs_state > 0.0) {
            return bad("simulation.max_abs_state".into(), "must be > 0".into());
        }
        if let Some(n) = &self.noise {
            if !(n.noise_power.is_finite() && n.noise_power >= 0.0) {
                return bad(
                    "noise.noise_power".into(),
                    format!("must be ≥ 0, found {}", n.noise_power),
                );
            }
            if let Some(ts) = n.sample_time_s
                && !(ts.is_finite() && ts > 0.0)
            {
                return bad("noise.sample_time_s".into(), format!("must be > 0, found {ts}"));
            }
        }
        let finite_state = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let ok = match &self.system {
            SystemConfig::FirstOrder { a, initial_state } => {
                a.is_finite() && initial_state.is_none_or(|s| finite_state(&s))
            }
            SystemConfig::FirstOrderNonlinear { a, B, C, omega_rad_s, initial_state } => {
                [a, B, C, omega_rad_s].iter().all(|x| x.is_finite())
                    && initial_state.is_none_or(|s| finite_state(&s))
            }
            SystemConfig::SecondOrder { a1, a2, initial_state }
            | SystemConfig::SecondOrderNonlinear { a1, a2, initial_state } => {
                a1.is_finite() && a2.is_finite() && initial_state.is_none_or(|s| finite_state(&s))
            }
        };
        if !ok {
            return bad("system".into(), "parameters and initial_state must be finite".into());
        }
        self.input.build().map_err(|e| ScenarioError::Invalid {
            path: path.to_path_buf(),
            key: "input".into(),
            reason: e.to_string(),
        })?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
kind = "poc"
[case]
name = "t"
thesis_table = "4.1"
thesis_case = 1
[system]
kind = "first_order"
a = 3.0
[input]
kind = "step"
amplitude = 1.0
[[parameters]]
name = "a"
lower = 1.0
upper = 5.0
lambda = 5.0
[estimator]
eta = 0.01
[simulation]
duration_s = 1.0
"#;

    #[test]
    fn parses_minimal_file() {
        let s = PocScenario::from_str_at(GOOD, Path::new("x.toml")).unwrap();
        assert_eq!(s.simulation.dt_s, 1e-3);
        assert_eq!(s.estimator.gain, GainConfig::Shared);
    }

    #[test]
    fn unknown_key_names_file_line_and_key() {
        let text = GOOD.replace("lambda = 5.0", "lambda = 5.0\nlamda = 3.0");
        let err = PocScenario::from_str_at(&text, Path::new("bad.toml")).unwrap_err().to_string();
        let line = text.lines().position(|l| l.starts_with("lamda")).unwrap() + 1;
        assert!(err.starts_with(&format!("bad.toml:{line}:")), "{err}");
        assert!(err.contains("lamda"), "{err}");
    }

    #[test]
    fn semantic_error_names_key() {
        let text = GOOD.replace("lower = 1.0", "lower = -1.0");
        let err = PocScenario::from_str_at(&text, Path::new("b.toml")).unwrap_err().to_string();
        assert!(err.contains("b.toml") && err.contains("parameters[0].lower"), "{err}");
        let text = GOOD.replace("name = \"a\"", "name = \"b\"");
        let err = PocScenario::from_str_at(&text, Path::new("b.toml")).unwrap_err().to_string();
        assert!(err.contains("parameters[0].name"), "{err}");
        let text = GOOD.replace("eta = 0.01", "eta = 0.0");
        let err = PocScenario::from_str_at(&text, Path::new("b.toml")).unwrap_err().to_string();
        assert!(err.contains("estimator.eta"), "{err}");
    }
}
