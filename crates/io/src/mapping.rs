//! Channel mapping files: which CSV column (or constant) feeds which channel of an
//! [`AirDataSample`](aeroident_estimators::AirDataSample), in which unit, with which scale and
//! offset. The full channel reference (unit dimension and sign convention of every channel) is
//! `docs/mapping.md`; it is summarised here.
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
//! da    = { columns = ["ail_left_deg", "ail_right_deg"], weights = [0.5, -0.5], unit = "deg" }
//! Ixz   = { column = "ixz", unit = "slug*ft2", scale = -1.0 }      # JSBSim logs −Jxz
//! mass  = { value = 7472.0, unit = "kg" }                             # a constant
//! ```
//!
//! Each entry converts as `SI = ((Σ wᵢ rawᵢ) · scale + offset) · factor(unit)`; `weights`
//! (one per column of `columns`) default to 1, `scale` to 1 and `offset` to 0, all in the
//! channel's own unit (so a bias correction is written in the record's unit). Units are parsed
//! by [`crate::units::Unit::parse`] and must have the channel's dimension
//! ([`Channel::dimension`]). Every key is checked: an unknown key is an error naming the file,
//! the line and the key.
//!
//! # Channels (SI after conversion; axes and signs of Stevens & Lewis 3rd ed. §1.4, §2.5)
//!
//! Body axes x forward, y right, z down; flow angles and accelerations at the CG.
//!
//! | key | dimension | meaning and sign |
//! |---|---|---|
//! | `vt` | speed | true airspeed V (> 0) — **required** |
//! | `alpha` | angle | angle of attack, at the vane (corrected by `alpha_vane_x`) — **required** |
//! | `beta` | angle | sideslip, > 0 wind from the right; at the vane (`beta_vane_x/z`) |
//! | `p`, `q`, `r` | angular rate | body roll, pitch, yaw rate (> 0 right wing down, nose up, nose right) |
//! | `pdot`, `qdot`, `rdot` | angular acceleration | their time derivatives |
//! | `alphadot` | angular rate | α̇ |
//! | `phi`, `theta`, `psi` | angle | Euler bank, pitch, heading |
//! | `ax`, `ay`, `az` | acceleration | body specific force at the CG (accelerometer, `az ≈ −g` level) |
//! | `de` | angle | elevator, > 0 trailing edge down (nose-down moment) |
//! | `da` | angle | aileron, > 0 rolls right wing down (Cl_da > 0) |
//! | `dr` | angle | rudder, > 0 trailing edge left (nose-left moment, Cn_dr < 0) |
//! | `thrust` | force | total thrust (absent: 0, a glider or thrust-in-trim record) |
//! | `throttle` | dimensionless | throttle position, 0–1 |
//! | `thrust_moment` | moment | thrust pitching moment about the CG, > 0 nose up |
//! | `qbar`, `rho` | pressure, density | dynamic pressure, air density — **one required**; the other is formed from V |
//! | `mass` | mass | — **required** (> 0) |
//! | `S` | area | wing reference area — **required** (> 0) |
//! | `cbar`, `b` | length | mean aerodynamic chord, wing span (full span) |
//! | `Ixx`, `Iyy`, `Izz` | moment of inertia | `Jx`, `Jy`, `Jz` (> 0) |
//! | `Ixz` | moment of inertia | Stevens & Lewis `Jxz` (tensor `[[Jx,0,−Jxz],[0,Jy,0],[−Jxz,0,Jz]]`); JSBSim's `ixz` is the tensor element `−Jxz`, map it with `scale = -1` |
//! | `thrust_arm` | length | `M_T = arm · T`, > 0 nose up |
//! | `thrust_incidence` | angle | thrust line to body x, > 0 nose up |
//! | `v0` | speed | reference speed of the `V/V0` terms |
//! | `alpha_vane_x` | length | α vane position ahead of the CG (body x) |
//! | `beta_vane_x`, `beta_vane_z` | length | β vane position ahead of / below the CG (body x, z) |
//!
//! Vane corrections (first order in the rates; see [`crate::flight_data`]):
//! `α_cg = α_vane + x_α q / V`, `β_cg = β_vane − x_β r / V + z_β p / V`.
//!
//! A channel that is not mapped is absent (`None`) in every sample — never 0.

use crate::FlightDataError;
use crate::units::{Dimension, Unit};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;
use toml::Spanned;

macro_rules! channels {
    ($($(#[$doc:meta])* $v:ident = $key:literal : $dim:ident,)*) => {
        /// A channel of the mapping format (table in the module doc).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub enum Channel {
            $($(#[$doc])* $v,)*
        }

        impl Channel {
            /// Every channel, in a fixed order.
            pub const ALL: &'static [Channel] = &[$(Channel::$v,)*];

            /// The key in the `[channels]` table.
            pub fn key(self) -> &'static str {
                match self {
                    $(Channel::$v => $key,)*
                }
            }

            /// The dimension the channel's unit must have.
            pub fn dimension(self) -> Dimension {
                match self {
                    $(Channel::$v => Dimension::$dim,)*
                }
            }
        }
    };
}

channels! {
    /// True airspeed.
    Vt = "vt": Speed,
    /// Angle of attack (at the vane; see `AlphaVaneX`).
    Alpha = "alpha": Angle,
    /// Sideslip (at the vane; see `BetaVaneX`, `BetaVaneZ`).
    Beta = "beta": Angle,
    /// Body roll rate.
    P = "p": AngularRate,
    /// Body pitch rate.
    Q = "q": AngularRate,
    /// Body yaw rate.
    R = "r": AngularRate,
    /// Body roll acceleration.
    Pdot = "pdot": AngularAcceleration,
    /// Body pitch acceleration.
    Qdot = "qdot": AngularAcceleration,
    /// Body yaw acceleration.
    Rdot = "rdot": AngularAcceleration,
    /// Angle-of-attack rate.
    Alphadot = "alphadot": AngularRate,
    /// Bank angle.
    Phi = "phi": Angle,
    /// Pitch attitude.
    Theta = "theta": Angle,
    /// Heading.
    Psi = "psi": Angle,
    /// Body x specific force at the CG.
    Ax = "ax": Acceleration,
    /// Body y specific force at the CG.
    Ay = "ay": Acceleration,
    /// Body z specific force at the CG (≈ −g in level flight).
    Az = "az": Acceleration,
    /// Elevator (trailing edge down positive).
    De = "de": Angle,
    /// Aileron (right wing down positive).
    Da = "da": Angle,
    /// Rudder (trailing edge left positive).
    Dr = "dr": Angle,
    /// Total thrust.
    Thrust = "thrust": Force,
    /// Throttle position, 0–1.
    Throttle = "throttle": Dimensionless,
    /// Thrust pitching moment about the CG (positive nose-up).
    ThrustMoment = "thrust_moment": Moment,
    /// Dynamic pressure.
    Qbar = "qbar": Pressure,
    /// Air density.
    Rho = "rho": Density,
    /// Mass.
    Mass = "mass": Mass,
    /// Roll moment of inertia `Jx`.
    Ixx = "Ixx": Inertia,
    /// Pitch moment of inertia `Jy`.
    Iyy = "Iyy": Inertia,
    /// Yaw moment of inertia `Jz`.
    Izz = "Izz": Inertia,
    /// Product of inertia `Jxz` (Stevens & Lewis sign).
    Ixz = "Ixz": Inertia,
    /// Wing reference area.
    S = "S": Area,
    /// Mean aerodynamic chord.
    Cbar = "cbar": Length,
    /// Wing span.
    B = "b": Length,
    /// Thrust pitching-moment arm (`M_T = arm·T`, positive nose-up).
    ThrustArm = "thrust_arm": Length,
    /// Thrust inclination to body x (positive nose-up).
    ThrustIncidence = "thrust_incidence": Angle,
    /// Reference speed for `V/V0`.
    V0 = "v0": Speed,
    /// Distance of the α vane ahead of the CG (body x).
    AlphaVaneX = "alpha_vane_x": Length,
    /// Distance of the β vane ahead of the CG (body x).
    BetaVaneX = "beta_vane_x": Length,
    /// Distance of the β vane below the CG (body z).
    BetaVaneZ = "beta_vane_z": Length,
}

impl Channel {
    fn from_key(k: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|c| c.key() == k)
    }

    /// Channels every mapping must provide (plus one of `qbar`, `rho`): the required fields
    /// of an [`AirDataSample`](aeroident_estimators::AirDataSample) and its constants.
    pub const REQUIRED: [Channel; 4] = [Channel::Vt, Channel::Alpha, Channel::Mass, Channel::S];

    /// Channels whose value must be > 0 when mapped.
    pub const POSITIVE: [Channel; 11] = [
        Channel::Vt,
        Channel::Mass,
        Channel::S,
        Channel::Cbar,
        Channel::B,
        Channel::Ixx,
        Channel::Iyy,
        Channel::Izz,
        Channel::Qbar,
        Channel::Rho,
        Channel::V0,
    ];
}

/// One `[channels]` entry as written in TOML.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelSpec {
    /// A single CSV column name.
    pub column: Option<String>,
    /// Several CSV columns whose (weighted) values are summed (e.g. two engines' thrust).
    pub columns: Option<Vec<String>>,
    /// Weights of `columns`, one per column (default 1 each), e.g. `[0.5, -0.5]` for a
    /// half-difference of two surfaces.
    pub weights: Option<Vec<f64>>,
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

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct MappingFile {
    description: Option<String>,
    nominal_dt_s: Option<f64>,
    time: ChannelSpec,
    channels: BTreeMap<Spanned<String>, ChannelSpec>,
}

/// Where a resolved channel's value comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// Weighted sum of these CSV columns: `(name, weight)`.
    Columns(Vec<(String, f64)>),
    /// A constant, already in SI.
    Constant(f64),
}

/// A validated channel: source and conversion `SI = (Σwᵢ·rawᵢ·scale + offset)·to_si`.
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
    /// Converts a raw value (weighted sum of the columns) to SI.
    pub fn to_si(&self, raw: f64) -> f64 {
        (raw * self.scale + self.offset) * self.to_si
    }

    /// The constant's SI value, if the channel is a constant.
    pub fn constant(&self) -> Option<f64> {
        match self.source {
            Source::Constant(v) => Some(v),
            Source::Columns(_) => None,
        }
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
}

/// 1-based line of byte offset `at` in `text`.
pub(crate) fn line_of(text: &str, at: usize) -> usize {
    text.as_bytes()[..at.min(text.len())].iter().filter(|b| **b == b'\n').count() + 1
}

impl Mapping {
    /// Reads and validates a mapping file.
    ///
    /// # Errors
    /// [`FlightDataError`] naming the file (and TOML line, channel, unit) for I/O, syntax,
    /// unknown keys or units, wrong dimensions, missing required channels, or a vane
    /// correction without the rate it needs.
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
        if raw.time.scale == 0.0 {
            return Err(FlightDataError::BadSpec {
                file: file.to_string(),
                channel: "time".into(),
                reason: "[time]: `scale = 0`: scale must be non-zero (every row would have the same time)".into(),
            });
        }
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
            let Some(ch) = Channel::from_key(key.get_ref()) else {
                return Err(FlightDataError::UnknownChannel {
                    file: file.to_string(),
                    line: line_of(text, key.span().start),
                    channel: key.get_ref().clone(),
                    valid: Channel::ALL.iter().map(|c| c.key()).collect::<Vec<_>>().join(", "),
                });
            };
            if spec.scale == 0.0 {
                // A zero scale makes the channel identically its offset: every regressor built
                // on it is 0 and the parameters it feeds are never identified (issue 10 #10).
                return Err(FlightDataError::BadSpec {
                    file: file.to_string(),
                    channel: ch.key().into(),
                    reason: format!(
                        "line {}: `scale = 0`: scale must be non-zero (it would make the channel the constant {} {}; map a constant with `value`)",
                        line_of(text, key.span().start),
                        spec.offset,
                        spec.unit
                    ),
                });
            }
            let m = resolve(file, ch.key(), spec, ch.dimension())?;
            if Channel::POSITIVE.contains(&ch)
                && let Some(v) = m.constant()
                && (v.is_nan() || v <= 0.0)
            {
                return Err(FlightDataError::BadSpec {
                    file: file.to_string(),
                    channel: ch.key().into(),
                    reason: format!("must be > 0, got {v}"),
                });
            }
            channels.insert(ch, m);
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
        // A vane correction needs the flow angle and the rate it is corrected with.
        for (vane, needs) in [
            (Channel::AlphaVaneX, [Channel::Q, Channel::Alpha]),
            (Channel::BetaVaneX, [Channel::R, Channel::Beta]),
            (Channel::BetaVaneZ, [Channel::P, Channel::Beta]),
        ] {
            if channels.contains_key(&vane) {
                for n in needs {
                    if !channels.contains_key(&n) {
                        return Err(FlightDataError::BadSpec {
                            file: file.to_string(),
                            channel: vane.key().into(),
                            reason: format!("the vane correction needs channel `{}`", n.key()),
                        });
                    }
                }
            }
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
        })
    }

    /// Whether channel `ch` is mapped (to a column or a constant).
    pub fn has(&self, ch: Channel) -> bool {
        self.channels.contains_key(&ch)
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
    if spec.weights.is_some() && spec.columns.is_none() {
        return Err(bad("`weights` needs `columns`".into()));
    }
    let source = match (&spec.column, &spec.columns, spec.value) {
        (Some(c), None, None) => Source::Columns(vec![(c.clone(), 1.0)]),
        (None, Some(cs), None) if !cs.is_empty() => {
            let weights = spec.weights.clone().unwrap_or_else(|| vec![1.0; cs.len()]);
            if weights.len() != cs.len() {
                return Err(bad(format!(
                    "{} weights for {} columns: give one weight per column",
                    weights.len(),
                    cs.len()
                )));
            }
            if let Some(w) = weights.iter().find(|w| !w.is_finite()) {
                return Err(bad(format!("weight {w} is not finite")));
            }
            Source::Columns(cs.iter().cloned().zip(weights).collect())
        }
        (None, None, Some(v)) => {
            let si = (v * spec.scale + spec.offset) * unit.to_si;
            if !si.is_finite() {
                return Err(bad(format!("value {v} is not finite in SI ({si})")));
            }
            Source::Constant(si)
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nmass = { value = 1.0, unit = \"kg\" }\nS = { value = 1.0, unit = \"m2\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\n";

    /// Issue 10 #10: a channel with `scale = 0` is identically its offset, so the parameters it
    /// feeds could never be identified; the mapping is refused, naming file, line and key.
    #[test]
    fn errors_zero_scale_names_file_line_and_key() {
        let text = format!("{HEAD}q = {{ column = \"q\", unit = \"deg/s\", scale = 0.0 }}\n");
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.starts_with("m.toml: channel `q`: line 10: `scale = 0`"), "{e}");
        assert!(e.contains("scale must be non-zero"), "{e}");
        let text = HEAD.replace("unit = \"s\"", "unit = \"s\"\nscale = -0.0");
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.contains("m.toml: channel `time`") && e.contains("non-zero"), "{e}");
        // Any non-zero scale (a sign flip) is still accepted.
        let text = format!("{HEAD}q = {{ column = \"q\", unit = \"deg/s\", scale = -1e-300 }}\n");
        assert!(Mapping::from_toml_str(&text, "m.toml").is_ok());
    }

    #[test]
    fn errors_unknown_channel_names_file_line_and_key() {
        let text = format!("{HEAD}bank = {{ column = \"phi\", unit = \"deg\" }}\n");
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.starts_with("m.toml: line 10: unknown channel `bank`"), "{e}");
        assert!(e.contains("phi") && e.contains("beta_vane_z"), "lists the valid keys: {e}");
    }

    #[test]
    fn errors_ekf_table_is_no_longer_part_of_the_format() {
        let text = format!("{HEAD}[ekf]\nsigma_vt_mps = 0.5\n");
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.contains("m.toml") && e.contains("ekf") && e.contains("line 10"), "{e}");
    }

    #[test]
    fn errors_vane_correction_without_its_rate() {
        let text = format!(
            "{HEAD}beta = {{ column = \"b\", unit = \"deg\" }}\nbeta_vane_x = {{ value = 13.0, unit = \"m\" }}\n"
        );
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.contains("`beta_vane_x`: the vane correction needs channel `r`"), "{e}");
    }

    #[test]
    fn errors_weights_must_match_columns_and_constants_be_positive() {
        let text =
            format!("{HEAD}da = {{ columns = [\"l\", \"r\"], weights = [0.5], unit = \"deg\" }}\n");
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.contains("`da`: 1 weights for 2 columns"), "{e}");
        let text = format!("{HEAD}b = {{ value = 0.0, unit = \"m\" }}\n");
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.contains("`b`: must be > 0"), "{e}");
    }

    #[test]
    fn analytic_weighted_columns_and_constants_convert_to_si() {
        let text = format!(
            "{HEAD}da = {{ columns = [\"l\", \"r\"], weights = [0.5, -0.5], unit = \"deg\", offset = 1.0 }}\nIxz = {{ value = 1060.0, unit = \"slug*ft2\", scale = -1.0 }}\n"
        );
        let m = Mapping::from_toml_str(&text, "m.toml").unwrap();
        let da = &m.channels[&Channel::Da];
        assert_eq!(da.source, Source::Columns(vec![("l".into(), 0.5), ("r".into(), -0.5)]));
        assert!((da.to_si(2.0) - 3.0f64.to_radians()).abs() < 1e-15);
        let ixz = m.channels[&Channel::Ixz].constant().unwrap();
        assert!((ixz + 1060.0 * 1.355_817_948_331_400_4).abs() < 1e-9, "{ixz}");
    }
}
