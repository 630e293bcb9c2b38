//! The open-loop simulation scenario file (`aeroident f16 sim <scenario.toml>`).
//!
//! ```toml
//! kind = "sim"                # the one scenario format's kind (crate::scenario_kind)
//!
//! [aircraft]                  # the F-16's; leave it out for `aeroident sim --aircraft MODEL.toml`
//! xcg = 0.30                  # fraction of cbar; 0.30 is open-loop stable (data README §7)
//! actuators = "f16"           # "f16" (20.2 rad/s lags, rate/position limits) | "ideal"
//! aerodynamics = "tables"     # optional: "tables" (default) | "linear", the tables' first-
//!                             # order expansion at the trim (the linear structure's truth)
//!
//! [trim]                      # steady wings-level trim the run starts from
//! alt_ft = 20000.0            # or alt_m
//! vt_fps = 675.0              # or vt_mps
//! gamma_deg = 0.0             # optional
//!
//! [run]
//! duration_s = 20.0
//! dt_s = 0.01                 # RK4 step; inputs and wind are held over a step (ZOH)
//! seed = 1                    # sensor seeds derive from it unless a sensor gives its own
//!
//! [[input]]                   # any number; inputs on the same channel superpose (add)
//! channel = "elevator"        # throttle | elevator | aileron | rudder
//! kind = "doublet"            # every kind of aeroident_signals::InputConfig
//! amplitude_deg = 1.0
//! start_s = 1.0
//! pulse_width_s = 0.5
//!
//! [[wind]]                    # aeroident_signals::WindConfig: one_minus_cosine | dryden
//! kind = "one_minus_cosine"
//! axis = "z"
//! amplitude_fps = 20.0
//! rise_time_s = 6.0
//! delay_s = 2.0
//!
//! [[sensor]]                  # aeroident_signals::SensorConfig on any output channel
//! channel = "alpha_rad"
//! white_sigma = 0.001
//! sample_rate_hz = 100.0
//!
//! [increments]                # optional: thesis (3.100–3.101) increments about the trim, per rad
//! dCm_alpha = -0.1
//! onset_s = 5.0               # optional step time (sudden damage); default: from t = 0
//! ```
//! Throttle inputs use the plain `amplitude` key (throttle is 0–1); surface inputs may use
//! `amplitude_deg` (converted once to radians by the signals crate).

use aeroident_signals::{InputConfig, SensorConfig, WindConfig};
use serde::Deserialize;

/// A scenario file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimScenario {
    /// `kind = "sim"`, checked by [`crate::scenario_kind::check`] before this is parsed.
    #[serde(rename = "kind")]
    _kind: crate::scenario_kind::ScenarioKind,
    /// The F-16's settings; absent for a model-file aircraft, which comes from the command
    /// line (`aeroident sim --aircraft MODEL.toml`) and has no cg, actuator or table choice.
    pub aircraft: Option<AircraftConfig>,
    /// The trim the run starts from.
    pub trim: TrimConfig,
    /// Run length and step.
    pub run: RunConfig,
    /// Pilot inputs.
    #[serde(default)]
    pub input: Vec<ChannelInput>,
    /// Disturbances (superposed).
    #[serde(default)]
    pub wind: Vec<WindConfig>,
    /// Sensors.
    #[serde(default)]
    pub sensor: Vec<SensorConfig>,
    /// Optional aerodynamic increments.
    pub increments: Option<IncrementsConfig>,
}

/// `[aircraft]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AircraftConfig {
    /// Centre of gravity, fraction of c̄.
    pub xcg: f64,
    /// Surface actuator model.
    #[serde(default)]
    pub actuators: ActuatorChoice,
    /// The tables, or their first-order expansion at the trim: a record whose every
    /// derivative is the trim's along the whole flight, so what an estimator misses on it is
    /// the data's fault, not the linear model structure's.
    #[serde(default)]
    pub aerodynamics: crate::aircraft::scenario::AerodynamicsSpec,
}

/// Which surface actuators to fly with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ActuatorChoice {
    /// The F-16 actuators of `aeroident_models::actuator::SurfaceActuators::f16`.
    #[default]
    F16,
    /// Surfaces follow the commands instantly (the textbook 13-state model).
    Ideal,
}

/// `[trim]`: the altitude as `alt_ft` or `alt_m`, the airspeed as `vt_fps` or `vt_mps` (one
/// of each pair).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrimConfig {
    /// Altitude, ft.
    pub alt_ft: Option<f64>,
    /// Altitude, m.
    pub alt_m: Option<f64>,
    /// True airspeed, ft/s.
    pub vt_fps: Option<f64>,
    /// True airspeed, m/s.
    pub vt_mps: Option<f64>,
    /// Flight-path angle, deg.
    #[serde(default)]
    pub gamma_deg: f64,
}

impl TrimConfig {
    /// The trim's airspeed and altitude in SI: `(vt_mps, alt_m)`.
    ///
    /// # Errors
    /// Neither or both of a pair given, naming the keys.
    pub fn si(&self) -> crate::error::Result<(f64, f64)> {
        let one = |si: Option<f64>, ft: Option<f64>, keys: &str| match (si, ft) {
            (Some(v), None) => Ok(v),
            (None, Some(v)) => Ok(v * aeroident_physics::units::M_PER_FT),
            (None, None) => Err(crate::err!("[trim]: give {keys}")),
            (Some(_), Some(_)) => Err(crate::err!("[trim]: give one of {keys}, not both")),
        };
        Ok((
            one(self.vt_mps, self.vt_fps, "vt_mps or vt_fps")?,
            one(self.alt_m, self.alt_ft, "alt_m or alt_ft")?,
        ))
    }

    /// The trim's airspeed and altitude in the F-16's units: `(vt_fps, alt_ft)`.
    ///
    /// # Errors
    /// As [`Self::si`].
    pub fn english(&self) -> crate::error::Result<(f64, f64)> {
        let (vt, alt) = self.si()?;
        let f = aeroident_physics::units::FT_PER_M;
        Ok((self.vt_fps.unwrap_or(vt * f), self.alt_ft.unwrap_or(alt * f)))
    }
}

/// `[run]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunConfig {
    /// Length, s.
    pub duration_s: f64,
    /// Integration step, s.
    pub dt_s: f64,
    /// Run seed (sensor seeds derive from it).
    #[serde(default)]
    pub seed: u64,
}

/// A control channel a pilot input acts on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Channel {
    /// Throttle (0–1).
    Throttle,
    /// Elevator (rad).
    Elevator,
    /// Aileron (rad).
    Aileron,
    /// Rudder (rad).
    Rudder,
}

/// `[[input]]`: a channel and an input signal.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct ChannelInput {
    /// Control channel.
    pub channel: Channel,
    /// The signal (flattened `kind = ...` table).
    #[serde(flatten)]
    pub input: InputConfig,
}

/// `[increments]`: the thesis's four increments (per rad / per unit (c̄/2V)Δq) about the trim.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IncrementsConfig {
    /// ΔCm_α, 1/rad.
    #[serde(default)]
    pub dCm_alpha: f64,
    /// ΔCm_q, per unit (c̄/2V)Δq.
    #[serde(default)]
    pub dCm_q: f64,
    /// ΔCL_α, 1/rad.
    #[serde(default)]
    pub dCL_alpha: f64,
    /// ΔCD_α, 1/rad.
    #[serde(default)]
    pub dCD_alpha: f64,
    /// Onset time, s (absent: active from the start).
    pub onset_s: Option<f64>,
}
