//! Channel mapping files: which CSV column (or constant) feeds which standard channel, in which
//! unit, with which scale and offset.
//!
//! # TOML syntax
//! ```toml
//! description = "HFB-320, Jategaonkar 2015 test case 4"
//! nominal_dt_s = 0.1            # optional; otherwise the first sample interval
//!
//! [time]
//! column = "time_s"
//! unit = "s"
//!
//! [channels]
//! vt    = { column = "vtas_mps", unit = "m/s" }
//! alpha = { column = "alpha_deg", unit = "deg", offset = -0.1 }     # SI = (raw·scale + offset)·unit
//! thrust = { columns = ["thrust_left_N", "thrust_right_N"], unit = "N" }   # columns are summed
//! mass  = { value = 7472.0, unit = "kg" }                             # a constant
//! ```
//!
//! Each entry converts as `SI = (Σ raw · scale + offset) · factor(unit)`; `scale` defaults to 1
//! and `offset` to 0, both in the channel's own unit (so a bias correction is written in the
//! record's unit). Units are parsed by [`crate::units::Unit::parse`] and must have the
//! channel's dimension (see [`Channel::dimension`]).
//!
//! Required channels: `vt, alpha, q, ax, az, de, mass, Iyy, S, cbar` and one of `qbar`/`rho`.
//! Optional: `theta` (needed by the EKF), `qdot` (else a causal differentiator is used),
//! `thrust` (0), `thrust_moment` (else `thrust_arm·thrust`), `thrust_arm` (0),
//! `thrust_incidence` (0), `p, r` with `Ixx, Izz, Ixz` (inertial coupling, else 0), `v0` (else
//! the first sample's V), `alpha_vane_x` (distance of the α vane ahead of the CG, m, for the
//! kinematic correction `α_cg = α_vane + x q / V`; else 0).

use crate::FlightDataError;
use crate::units::{Dimension, Unit};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

/// A standard channel the replay understands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Channel {
    /// True airspeed.
    Vt,
    /// Angle of attack (at the vane; see `AlphaVaneX`).
    Alpha,
    /// Pitch attitude.
    Theta,
    /// Body pitch rate.
    Q,
    /// Body pitch acceleration.
    Qdot,
    /// Body x specific force (accelerometer at the CG).
    Ax,
    /// Body z specific force (accelerometer at the CG, ≈ −g in level flight).
    Az,
    /// Elevator deflection.
    De,
    /// Total thrust.
    Thrust,
    /// Thrust pitching moment about the CG (positive nose-up).
    ThrustMoment,
    /// Dynamic pressure.
    Qbar,
    /// Air density.
    Rho,
    /// Body roll rate.
    P,
    /// Body yaw rate.
    R,
    /// Mass.
    Mass,
    /// Roll moment of inertia.
    Ixx,
    /// Pitch moment of inertia.
    Iyy,
    /// Yaw moment of inertia.
    Izz,
    /// Product of inertia `Ixz`.
    Ixz,
    /// Wing reference area.
    S,
    /// Mean aerodynamic chord.
    Cbar,
    /// Thrust pitching-moment arm (`M_T = arm·T`, positive nose-up).
    ThrustArm,
    /// Thrust inclination to body x (positive nose-up).
    ThrustIncidence,
    /// Reference speed for `V/V0`.
    V0,
    /// Distance of the α vane ahead of the CG.
    AlphaVaneX,
}

impl Channel {
    /// Every channel, in a fixed order.
    pub const ALL: [Channel; 25] = [
        Channel::Vt,
        Channel::Alpha,
        Channel::Theta,
        Channel::Q,
        Channel::Qdot,
        Channel::Ax,
        Channel::Az,
        Channel::De,
        Channel::Thrust,
        Channel::ThrustMoment,
        Channel::Qbar,
        Channel::Rho,
        Channel::P,
        Channel::R,
        Channel::Mass,
        Channel::Ixx,
        Channel::Iyy,
        Channel::Izz,
        Channel::Ixz,
        Channel::S,
        Channel::Cbar,
        Channel::ThrustArm,
        Channel::ThrustIncidence,
        Channel::V0,
        Channel::AlphaVaneX,
    ];

    /// The key in the `[channels]` table.
    pub fn key(self) -> &'static str {
        match self {
            Channel::Vt => "vt",
            Channel::Alpha => "alpha",
            Channel::Theta => "theta",
            Channel::Q => "q",
            Channel::Qdot => "qdot",
            Channel::Ax => "ax",
            Channel::Az => "az",
            Channel::De => "de",
            Channel::Thrust => "thrust",
            Channel::ThrustMoment => "thrust_moment",
            Channel::Qbar => "qbar",
            Channel::Rho => "rho",
            Channel::P => "p",
            Channel::R => "r",
            Channel::Mass => "mass",
            Channel::Ixx => "Ixx",
            Channel::Iyy => "Iyy",
            Channel::Izz => "Izz",
            Channel::Ixz => "Ixz",
            Channel::S => "S",
            Channel::Cbar => "cbar",
            Channel::ThrustArm => "thrust_arm",
            Channel::ThrustIncidence => "thrust_incidence",
            Channel::V0 => "v0",
            Channel::AlphaVaneX => "alpha_vane_x",
        }
    }

    /// The dimension the channel's unit must have.
    pub fn dimension(self) -> Dimension {
        use Dimension as D;
        match self {
            Channel::Vt | Channel::V0 => D::Speed,
            Channel::Alpha | Channel::Theta | Channel::De | Channel::ThrustIncidence => D::Angle,
            Channel::Q | Channel::P | Channel::R => D::AngularRate,
            Channel::Qdot => D::AngularAcceleration,
            Channel::Ax | Channel::Az => D::Acceleration,
            Channel::Thrust => D::Force,
            Channel::ThrustMoment => D::Moment,
            Channel::Qbar => D::Pressure,
            Channel::Rho => D::Density,
            Channel::Mass => D::Mass,
            Channel::Ixx | Channel::Iyy | Channel::Izz | Channel::Ixz => D::Inertia,
            Channel::S => D::Area,
            Channel::Cbar | Channel::ThrustArm | Channel::AlphaVaneX => D::Length,
        }
    }

    fn from_key(k: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|c| c.key() == k)
    }

    /// Channels every mapping must provide.
    pub const REQUIRED: [Channel; 10] = [
        Channel::Vt,
        Channel::Alpha,
        Channel::Q,
        Channel::Ax,
        Channel::Az,
        Channel::De,
        Channel::Mass,
        Channel::Iyy,
        Channel::S,
        Channel::Cbar,
    ];
}

/// One `[channels]` entry as written in TOML.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelSpec {
    /// A single CSV column name.
    pub column: Option<String>,
    /// Several CSV columns whose values are summed (e.g. two engines' thrust).
    pub columns: Option<Vec<String>>,
    /// A constant value (in `unit`).
    pub value: Option<f64>,
    /// Unit string, e.g. `"deg/s"`.
    pub unit: String,
    /// Multiplier applied to the raw value before `offset` (default 1).
    #[serde(default = "one")]
    pub scale: f64,
    /// Added after `scale`, in the channel's unit (default 0), e.g. a bias correction.
    #[serde(default)]
    pub offset: f64,
    /// Free-text provenance note (ignored by the reader).
    pub note: Option<String>,
}

fn one() -> f64 {
    1.0
}

/// Optional EKF measurement-noise standard deviations (SI) for this record.
#[derive(Debug, Clone, Copy, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EkfNoise {
    /// σ of V, m/s.
    pub sigma_vt_mps: Option<f64>,
    /// σ of α, rad.
    pub sigma_alpha_rad: Option<f64>,
    /// σ of θ, rad.
    pub sigma_theta_rad: Option<f64>,
    /// σ of q, rad/s.
    pub sigma_q_rad_s: Option<f64>,
    /// σ of q̇, rad/s².
    pub sigma_qdot_rad_s2: Option<f64>,
    /// σ of ax, m/s².
    pub sigma_ax_mps2: Option<f64>,
    /// σ of az, m/s².
    pub sigma_az_mps2: Option<f64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct MappingFile {
    description: Option<String>,
    nominal_dt_s: Option<f64>,
    time: ChannelSpec,
    channels: BTreeMap<String, ChannelSpec>,
    ekf: Option<EkfNoise>,
}

/// Where a resolved channel's value comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// Sum of these CSV column names.
    Columns(Vec<String>),
    /// A constant, already in SI.
    Constant(f64),
}

/// A validated channel: source and conversion `SI = (Σraw·scale + offset)·to_si`.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelMap {
    /// Where the value comes from.
    pub source: Source,
    /// Unit conversion factor to SI.
    pub to_si: f64,
    /// Raw-unit scale.
    pub scale: f64,
    /// Raw-unit offset.
    pub offset: f64,
    /// The unit string as written.
    pub unit: String,
}

impl ChannelMap {
    /// Converts a raw value (sum of the columns) to SI.
    pub fn to_si(&self, raw: f64) -> f64 {
        (raw * self.scale + self.offset) * self.to_si
    }
}

/// A validated mapping file.
#[derive(Debug, Clone)]
pub struct Mapping {
    /// Path or name of the mapping file (for messages).
    pub file: String,
    /// Free-text description.
    pub description: String,
    /// Nominal sample interval, s, if given.
    pub nominal_dt_s: Option<f64>,
    /// The time channel.
    pub time: ChannelMap,
    /// The mapped channels.
    pub channels: BTreeMap<Channel, ChannelMap>,
    /// EKF noise settings, if given.
    pub ekf: EkfNoise,
}

impl Mapping {
    /// Reads and validates a mapping file.
    ///
    /// # Errors
    /// [`FlightDataError`] naming the file (and TOML line, channel, unit) for I/O, syntax,
    /// unknown channels or units, wrong dimensions, or missing required channels.
    pub fn from_path(path: &Path) -> Result<Self, FlightDataError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|source| FlightDataError::Io { file: file.clone(), source })?;
        Self::from_toml_str(&text, &file)
    }

    /// Parses and validates mapping TOML text; `file` names it in errors.
    ///
    /// # Errors
    /// As [`Mapping::from_path`].
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, FlightDataError> {
        let raw: MappingFile = toml::from_str(text).map_err(|e| {
            FlightDataError::MappingSyntax { file: file.to_string(), message: e.to_string() }
        })?;
        let time = resolve(file, "time", &raw.time, Dimension::Time)?;
        if matches!(time.source, Source::Constant(_)) {
            return Err(FlightDataError::BadSpec {
                file: file.to_string(),
                channel: "time".into(),
                reason: "time must come from a column".into(),
            });
        }
        let mut channels = BTreeMap::new();
        for (key, spec) in &raw.channels {
            let Some(ch) = Channel::from_key(key) else {
                return Err(FlightDataError::UnknownChannel {
                    file: file.to_string(),
                    channel: key.clone(),
                    valid: Channel::ALL.iter().map(|c| c.key()).collect::<Vec<_>>().join(", "),
                });
            };
            channels.insert(ch, resolve(file, key, spec, ch.dimension())?);
        }
        for ch in Channel::REQUIRED {
            if !channels.contains_key(&ch) {
                return Err(FlightDataError::MissingChannel {
                    file: file.to_string(),
                    channel: ch.key().into(),
                });
            }
        }
        if !channels.contains_key(&Channel::Qbar) && !channels.contains_key(&Channel::Rho) {
            return Err(FlightDataError::MissingChannel {
                file: file.to_string(),
                channel: "qbar or rho".into(),
            });
        }
        if let Some(dt) = raw.nominal_dt_s
            && !(dt.is_finite() && dt > 0.0)
        {
            return Err(FlightDataError::BadSpec {
                file: file.to_string(),
                channel: "nominal_dt_s".into(),
                reason: format!("must be finite and > 0, got {dt}"),
            });
        }
        Ok(Self {
            file: file.to_string(),
            description: raw.description.unwrap_or_default(),
            nominal_dt_s: raw.nominal_dt_s,
            time,
            channels,
            ekf: raw.ekf.unwrap_or_default(),
        })
    }
}

fn resolve(
    file: &str,
    key: &str,
    spec: &ChannelSpec,
    dim: Dimension,
) -> Result<ChannelMap, FlightDataError> {
    let bad = |reason: String| FlightDataError::BadSpec {
        file: file.to_string(),
        channel: key.to_string(),
        reason,
    };
    let unit = Unit::parse(&spec.unit).map_err(|e| FlightDataError::Unit {
        file: file.to_string(),
        channel: key.to_string(),
        message: e.to_string(),
    })?;
    if unit.dimension != dim {
        return Err(FlightDataError::WrongDimension {
            file: file.to_string(),
            channel: key.to_string(),
            unit: spec.unit.clone(),
            expected: dim.to_string(),
        });
    }
    if !spec.scale.is_finite() || !spec.offset.is_finite() {
        return Err(bad(format!("scale {} and offset {} must be finite", spec.scale, spec.offset)));
    }
    let source = match (&spec.column, &spec.columns, spec.value) {
        (Some(c), None, None) => Source::Columns(vec![c.clone()]),
        (None, Some(cs), None) if !cs.is_empty() => Source::Columns(cs.clone()),
        (None, None, Some(v)) if v.is_finite() => {
            Source::Constant((v * spec.scale + spec.offset) * unit.to_si)
        }
        (None, None, Some(v)) => return Err(bad(format!("value {v} is not finite"))),
        _ => {
            return Err(bad(
                "give exactly one of `column`, `columns` (non-empty) or `value`".into()
            ));
        }
    };
    Ok(ChannelMap {
        source,
        to_si: unit.to_si,
        scale: spec.scale,
        offset: spec.offset,
        unit: spec.unit.clone(),
    })
}
