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
//! rho   = { expr = "isa_pressure(h_ft * 0.3048) / (287.05287 * sat_K)", unit = "kg/m3" }
//! ```
//!
//! `expr` computes a channel from columns ([`crate::expression`]: arithmetic, the standard
//! atmosphere's `isa_pressure`/`isa_temperature`/`isa_density`; mass from fuel used is
//! `expr = "17631 - fuel_used_kg"`). A top-level `inertia_reference_mass_kg = 17631.0` scales
//! the mapped inertias by each sample's mass over it ([`Mapping::inertia_reference_mass_kg`]).
//!
//! ```toml
//!
//! [columns]       # optional: names of the columns of a file without a header row
//! names = ["time_s", "elevator_rad", "qbar_Pa"]   # (.asc, a .mat matrix); default "1", "2", …
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
//! | `da` | angle | aileron, > 0 right aileron trailing edge down: negative rolling moment (Cl_da < 0) |
//! | `dr` | angle | rudder, > 0 trailing edge left (nose-left moment, Cn_dr < 0) |
//! | `thrust` | force | total thrust (absent: 0 in the equations, but the drag and axial-force terms are then drag minus thrust and are reported not identified; a glider declares `thrust = { value = 0.0, unit = "N" }`) |
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
//!
//! # Multi-rate logs (PX4 ULog, ArduPilot DataFlash)
//!
//! A log's topics are first aligned onto one time base ([`crate::align`]); columns are then
//! named `<topic>.<field>` (`sensor_combined.gyro_rad[1]`, `ATT.Roll`) and the time column is
//! `time_s` (seconds). Three tables say how ([`crate::multirate::log_table`] applies them):
//!
//! ```toml
//! [align]
//! rate_hz = 50.0            # or: clock = "sensor_combined" (that topic's timestamps)
//! method = "linear"         # or "zoh" (zero-order hold)
//!
//! [attitude]                # quaternion (w, x, y, z), body → NED: adds columns
//! quaternion = ["vehicle_attitude.q[0]", "vehicle_attitude.q[1]",      # euler.phi,
//!               "vehicle_attitude.q[2]", "vehicle_attitude.q[3]"]      # euler.theta, euler.psi (rad)
//!
//! [air_data]                # needs [attitude]: adds air.vt (m/s), air.alpha, air.beta (rad)
//! ned_velocity = ["vehicle_local_position.vx", "vehicle_local_position.vy", "vehicle_local_position.vz"]
//! wind_ne = ["wind_estimate.windspeed_north", "wind_estimate.windspeed_east"]   # optional
//! min_vt_mps = 3.0          # below it the flow angles are undefined (default 1)
//!
//! [channels]
//! phi = { column = "euler.phi", unit = "rad" }
//! de  = { column = "actuator_outputs.output[1]", calibration = [[1000, -25.0], [1500, 0.0], [2000, 25.0]], unit = "deg" }
//! ```
//!
//! `calibration` (any channel): a table of `[raw, value]` points, raw strictly increasing, at
//! least two; the weighted raw sum is mapped piecewise-linearly to a value in `unit`, then
//! `scale` and `offset` apply: `SI = (cal(Σ wᵢ rawᵢ) · scale + offset) · factor(unit)`. A raw
//! value outside the table is not extrapolated: it converts to NaN, and the row is rejected
//! as not finite (naming the column). Servo PWM → surface deflection is the intended use.

use crate::FlightDataError;
use crate::message::{exact_or_short, short};
use crate::table::Interpolation;
use crate::thrust_model::{LawInput, ThrustModel, ThrustModelFile};
use crate::units::{Dimension, Unit};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;
use toml::Spanned;

/// The output time base of [`align`](crate::align::align).
#[derive(Debug, Clone, PartialEq)]
pub enum Clock {
    /// A uniform grid at this rate, Hz, over the span every topic covers.
    RateHz(f64),
    /// The timestamps of this topic (e.g. `sensor_combined` for the IMU rate).
    Topic(String),
}

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

impl Channel {
    /// The channel that fills a field of `aeroident_estimators::AirDataSample` or
    /// `AircraftConstants` (the names estimators use in their errors: `r_rad_s` → `r`,
    /// `Iyy_kgm2` → `Iyy`, `rho_kgpm3` → `rho`); `None` for other names.
    pub fn of_sample_field(field: &str) -> Option<Channel> {
        use Channel as C;
        Some(match field {
            "vt_mps" => C::Vt,
            "alpha_rad" => C::Alpha,
            "beta_rad" => C::Beta,
            "p_rad_s" => C::P,
            "q_rad_s" => C::Q,
            "r_rad_s" => C::R,
            "pdot_rad_s2" => C::Pdot,
            "qdot_rad_s2" => C::Qdot,
            "rdot_rad_s2" => C::Rdot,
            "alphadot_rad_s" => C::Alphadot,
            "phi_rad" => C::Phi,
            "theta_rad" => C::Theta,
            "psi_rad" => C::Psi,
            "ax_mps2" => C::Ax,
            "ay_mps2" => C::Ay,
            "az_mps2" => C::Az,
            "de_rad" => C::De,
            "da_rad" => C::Da,
            "dr_rad" => C::Dr,
            "thrust_n" => C::Thrust,
            "throttle" => C::Throttle,
            "thrust_moment_nm" => C::ThrustMoment,
            "qbar_pa" => C::Qbar,
            "rho_kgpm3" => C::Rho,
            "mass_kg" => C::Mass,
            "Ixx_kgm2" => C::Ixx,
            "Iyy_kgm2" => C::Iyy,
            "Izz_kgm2" => C::Izz,
            "Ixz_kgm2" => C::Ixz,
            "S_m2" => C::S,
            "cbar_m" => C::Cbar,
            "b_m" => C::B,
            "thrust_arm_m" => C::ThrustArm,
            "thrust_incidence_rad" => C::ThrustIncidence,
            "v0_mps" => C::V0,
            _ => return None,
        })
    }
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
    /// Aileron (positive: right aileron trailing edge down, a negative rolling moment).
    Da = "da": Angle,
    /// Rudder (trailing edge left positive).
    Dr = "dr": Angle,
    /// Total thrust.
    Thrust = "thrust": Force,
    /// Throttle position, 0–1.
    Throttle = "throttle": Dimensionless,
    /// Propeller shaft speed (the `propeller` law of `[thrust_model]`).
    PropSpeed = "prop_speed": AngularRate,
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

/// The physical range of each aircraft constant, SI (lowest, highest, unit): a value outside
/// it is a slip (a unit, an exponent), never an aircraft. Wide enough for a 1 g micro air
/// vehicle (mass 10⁻³ kg, wing 1 cm², chord and span of a centimetre, inertias about
/// 10⁻⁷ kg·m²) and for the largest aircraft with margin (A380: 575 t, 845 m², span 80 m, mean
/// chord 12 m, inertias of order 10⁸ kg·m²; An-225 640 t). The upper ends stay within the
/// estimators' own plausibility limits (`aeroident_estimators::sample::PLAUSIBILITY`), so a
/// mapping that passes here yields samples they accept. A constant outside its range is a
/// mapping error; a value read from a column outside it rejects its row.
pub const CONSTANT_RANGES: [(Channel, f64, f64, &str); 8] = [
    (Channel::Mass, 1e-3, 1e7, "kg"),
    (Channel::S, 1e-4, 1e4, "m²"),
    (Channel::Cbar, 1e-3, 1e2, "m"),
    (Channel::B, 1e-2, 1e3, "m"),
    (Channel::Ixx, 1e-9, 1e10, "kg·m²"),
    (Channel::Iyy, 1e-9, 1e10, "kg·m²"),
    (Channel::Izz, 1e-9, 1e10, "kg·m²"),
    (Channel::Ixz, -1e10, 1e10, "kg·m²"),
];

/// `ch`'s physical range ([`CONSTANT_RANGES`]): `Err` with the reason when `v_si` is outside.
pub(crate) fn check_constant_range(ch: Channel, v_si: f64) -> Result<(), String> {
    let Some(&(_, lo, hi, unit)) = CONSTANT_RANGES.iter().find(|r| r.0 == ch) else {
        return Ok(());
    };
    if (lo..=hi).contains(&v_si) {
        return Ok(());
    }
    Err(format!(
        "{} {unit} is outside the physical range {lo:e} … {hi:e} {unit} (a 1 g micro air vehicle to beyond the largest aircraft): check the unit and the exponent",
        exponent_form(v_si)
    ))
}

/// `x` in exponent form to 4 significant digits, without trailing zeros (`1.858e5`, `1e-300`).
fn exponent_form(x: f64) -> String {
    let text = format!("{x:.3e}");
    match text.split_once('e') {
        Some((mantissa, exp)) if mantissa.contains('.') => {
            format!("{}e{exp}", mantissa.trim_end_matches('0').trim_end_matches('.'))
        }
        _ => text,
    }
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
    /// An expression over columns whose value is in `unit` ([`crate::expression`]), e.g.
    /// `"17631 - fuel_used_kg"`.
    pub expr: Option<String>,
    /// Unit string, e.g. `"deg/s"`.
    pub unit: String,
    /// Multiplier applied to the raw value before `offset` (default 1).
    #[serde(default = "one")]
    pub scale: f64,
    /// Added after `scale`, in the channel's unit (default 0), e.g. a bias correction.
    #[serde(default)]
    pub offset: f64,
    /// Piecewise-linear calibration `[[raw, value], …]` (raw strictly increasing, ≥ 2 points),
    /// applied to the weighted raw sum before `scale` and `offset` (e.g. servo PWM → degrees).
    pub calibration: Option<Vec<[f64; 2]>>,
    /// Free-text provenance note (ignored by the reader).
    pub note: Option<String>,
    /// A surface (`de`, `da`, `dr`) whose column is the *command*: the actuator between it and
    /// the surface ([`Actuator`]); the record stage passes the command through it.
    pub actuator: Option<ActuatorSpec>,
    /// A surface (`de`, `da`, `dr`) recorded early or late against the response it causes:
    /// the record stage reads it this many seconds later (> 0: the value used at time `t` is
    /// the logged one at `t − shift_s`; < 0: at `t + |shift_s|`), interpolated linearly.
    /// Checked: finite, within ±[`MAX_INPUT_SHIFT_S`] ([`Mapping::input_shifts`]).
    pub shift_s: Option<f64>,
}

/// The largest input time shift, s, a mapping's `shift_s` may declare either way: the
/// compatibility stage's bound on any time shift it undoes (a lag or a lead beyond it is a
/// mislabelled column or time base, not a timing error to interpolate away).
pub const MAX_INPUT_SHIFT_S: f64 = 0.5;

fn one() -> f64 {
    1.0
}

/// `actuator = { tau_s = …, rate_limit_rad_s = …, position_limits_rad = [min, max] }` of a
/// commanded surface, as written.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActuatorSpec {
    /// First-order time constant, s.
    pub tau_s: f64,
    /// Rate limit, rad/s (none: unlimited).
    pub rate_limit_rad_s: Option<f64>,
    /// Position limits `[min, max]`, rad (none: unlimited).
    pub position_limits_rad: Option<[f64; 2]>,
}

/// The actuator of a commanded surface: a first-order lag `τ δ̇ = u − δ` with its rate and
/// position limits (the model of Stevens & Lewis 2nd ed. §3.4 and NASA TP-1538 for the F-16:
/// τ 0.0495 s, 60°/s, ±25° on the elevator), checked: τ in (0, 1] s, the limits positive and
/// ordered, all finite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Actuator {
    /// Time constant, s.
    pub tau_s: f64,
    /// Rate limit, rad/s (`f64::INFINITY`: unlimited).
    pub rate_limit_rad_s: f64,
    /// Position limits, rad (`(−∞, ∞)`: unlimited).
    pub position_limits_rad: (f64, f64),
}

impl Actuator {
    /// The spec checked (module doc of [`Actuator`]); `Err` with the reason.
    fn from_spec(a: &ActuatorSpec) -> Result<Self, String> {
        if !(a.tau_s > 0.0 && a.tau_s <= 1.0) {
            return Err(format!(
                "actuator `tau_s = {}`: a time constant must be in (0, 1] s",
                exact_or_short(a.tau_s)
            ));
        }
        let rate = a.rate_limit_rad_s.unwrap_or(f64::INFINITY);
        let usable = rate > 0.0 && (rate.is_finite() || a.rate_limit_rad_s.is_none());
        if !usable {
            return Err(format!(
                "actuator `rate_limit_rad_s = {}`: must be positive and finite",
                exact_or_short(rate)
            ));
        }
        let (lo, hi) = match a.position_limits_rad {
            Some([lo, hi]) if lo.is_finite() && hi.is_finite() && lo < hi => (lo, hi),
            Some([lo, hi]) => {
                return Err(format!(
                    "actuator `position_limits_rad = [{}, {}]`: must be finite with min < max",
                    exact_or_short(lo),
                    exact_or_short(hi)
                ));
            }
            None => (f64::NEG_INFINITY, f64::INFINITY),
        };
        Ok(Self { tau_s: a.tau_s, rate_limit_rad_s: rate, position_limits_rad: (lo, hi) })
    }

    /// The surface one step `dt_s` after `surface` under the command `command` held over the
    /// step (zero-order hold): the exact discrete lag, then the rate and position limits.
    pub fn step(&self, surface: f64, command: f64, dt_s: f64) -> f64 {
        self.step_limited(surface, command, dt_s).0
    }

    /// [`Self::step`], and whether the rate limit cut the step short.
    pub fn step_limited(&self, surface: f64, command: f64, dt_s: f64) -> (f64, bool) {
        let lag = (command - surface) * (1.0 - (-dt_s / self.tau_s).exp());
        let max_move = self.rate_limit_rad_s * dt_s;
        let (lo, hi) = self.position_limits_rad;
        ((surface + lag.clamp(-max_move, max_move)).clamp(lo, hi), lag.abs() > max_move)
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct MappingFile {
    description: Option<String>,
    nominal_dt_s: Option<f64>,
    inertia_reference_mass_kg: Option<f64>,
    time: ChannelSpec,
    channels: BTreeMap<Spanned<String>, ChannelSpec>,
    columns: Option<ColumnsSpec>,
    align: Option<AlignFile>,
    attitude: Option<AttitudeFile>,
    air_data: Option<AirDataFile>,
    thrust_model: Option<ThrustModelFile>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct AlignFile {
    rate_hz: Option<f64>,
    clock: Option<String>,
    method: String,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct AttitudeFile {
    quaternion: Vec<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct AirDataFile {
    ned_velocity: Vec<String>,
    wind_ne: Option<Vec<String>>,
    min_vt_mps: Option<f64>,
}

/// Derived column: bank angle φ from `[attitude]`, rad.
pub const EULER_PHI: &str = "euler.phi";
/// Derived column: pitch attitude θ from `[attitude]`, rad.
pub const EULER_THETA: &str = "euler.theta";
/// Derived column: heading ψ from `[attitude]`, rad.
pub const EULER_PSI: &str = "euler.psi";
/// Derived column: true airspeed from `[air_data]`, m/s.
pub const AIR_VT: &str = "air.vt";
/// Derived column: angle of attack from `[air_data]`, rad.
pub const AIR_ALPHA: &str = "air.alpha";
/// Derived column: sideslip from `[air_data]`, rad.
pub const AIR_BETA: &str = "air.beta";

/// `[align]`: the time base a multi-rate log is aligned to and the interpolation.
#[derive(Debug, Clone, PartialEq)]
pub struct AlignSpec {
    /// Rate grid or clock topic.
    pub clock: Clock,
    /// Zero-order hold or linear.
    pub method: Interpolation,
}

/// `[air_data]`: flow angles and airspeed from the inertial velocity, the wind and the
/// attitude (see [`crate::multirate`]).
#[derive(Debug, Clone, PartialEq)]
pub struct AirDataSpec {
    /// North, east, down velocity columns, m/s.
    pub ned_velocity: [String; 3],
    /// North, east wind columns, m/s (absent: no wind).
    pub wind_ne: Option<[String; 2]>,
    /// Airspeed below which α, β are undefined (NaN), m/s.
    pub min_vt_mps: f64,
}

/// The `[columns]` table: names for the columns of a file without a header row.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ColumnsSpec {
    names: Vec<String>,
}

/// Where a resolved channel's value comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// Weighted sum of these CSV columns: `(name, weight)`; for a channel with an
    /// [`ChannelMap::expression`], the columns it reads (weights 1, not used).
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
    /// Piecewise-linear calibration `(raw, value)`, raw strictly increasing.
    pub calibration: Option<Vec<(f64, f64)>>,
    /// How the columns of [`Source::Columns`] combine into the raw value when not by their
    /// weighted sum: an expression over them (`expr = …`), its columns in the order of
    /// [`crate::expression::Expression::columns`].
    pub expression: Option<crate::expression::Expression>,
}

/// Piecewise-linear interpolation in `table` (`(raw, value)`, raw strictly increasing);
/// NaN outside `[raw_first, raw_last]`.
pub fn calibrate(table: &[(f64, f64)], raw: f64) -> f64 {
    let i = table.partition_point(|(r, _)| *r < raw);
    match (i, table.get(i)) {
        (_, Some(&(r1, v1))) if r1 == raw => v1,
        (0, _) | (_, None) => f64::NAN,
        (i, Some(&(r1, v1))) => {
            let (r0, v0) = table[i - 1];
            v0 + (v1 - v0) * (raw - r0) / (r1 - r0)
        }
    }
}

impl ChannelMap {
    /// Converts a raw value (weighted sum of the columns) to SI, through the calibration
    /// table if there is one (NaN outside it).
    pub fn to_si(&self, raw: f64) -> f64 {
        let x = match &self.calibration {
            Some(table) => calibrate(table, raw),
            None => raw,
        };
        (x * self.scale + self.offset) * self.to_si
    }

    /// The constant's SI value, if the channel is a constant.
    /// (A calibration does not apply to constants: `value` is already in `unit`.)
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
    /// `inertia_reference_mass_kg`: the mass, kg, at which the mapped `Ixx`, `Iyy`, `Izz`,
    /// `Ixz` hold; each sample's inertias are scaled by its mass over it (constant radii of
    /// gyration: the usual first approximation of fuel burn when no loading data are given).
    /// `None`: the inertias as mapped.
    pub inertia_reference_mass_kg: Option<f64>,
    /// The time channel.
    pub time: ChannelMap,
    /// The mapped channels.
    pub channels: BTreeMap<Channel, ChannelMap>,
    /// `[align]` (multi-rate logs only).
    pub align: Option<AlignSpec>,
    /// `[attitude] quaternion` columns (w, x, y, z), body → NED.
    pub quaternion: Option<[String; 4]>,
    /// `[air_data]`.
    pub air_data: Option<AirDataSpec>,
    /// `[columns] names`: the name of each column, in order, of a file without a header row
    /// (a whitespace `.asc`, a `.mat` matrix); `None` names them `"1"`, `"2"`, … (see
    /// [`crate::log`]). A CSV has its own header and ignores this list.
    pub column_names: Option<Vec<String>>,
    /// The actuators of the surfaces mapped as commands (`actuator = { … }` on `de`, `da`,
    /// `dr`): the record stage passes each command through its actuator.
    pub actuators: BTreeMap<Channel, Actuator>,
    /// `[thrust_model]`: thrust from a law of the throttle or the propeller speed, for a
    /// record without a `thrust` channel ([`crate::thrust_model`]).
    pub thrust_model: Option<ThrustModel>,
    /// The surfaces' time shifts (`shift_s` on `de`, `da`, `dr`), s, checked
    /// ([`Mapping::input_shifts`]).
    shifts: BTreeMap<Channel, f64>,
}

/// The channel thrust law `law` reads besides ρ and V.
pub fn law_input(law: &ThrustModel) -> Channel {
    match law.input() {
        LawInput::PropSpeed => Channel::PropSpeed,
        LawInput::Throttle => Channel::Throttle,
    }
}

/// `[thrust_model]` resolved and checked against the channels: refused beside a `thrust`
/// channel (two sources of one force), without the channel its law reads, or with a
/// constant no propeller has (the reason names the key).
fn thrust_model_of(
    file: &str,
    spec: Option<&ThrustModelFile>,
    channels: &BTreeMap<Channel, ChannelMap>,
) -> Result<Option<ThrustModel>, FlightDataError> {
    let Some(spec) = spec else { return Ok(None) };
    let bad = |reason: String| FlightDataError::MappingSyntax {
        file: file.to_string(),
        message: format!("[thrust_model]: {reason}"),
    };
    let model = spec.resolve().map_err(bad)?;
    if channels.contains_key(&Channel::Thrust) {
        return Err(bad(
            "the mapping also has a `thrust` channel: give one source of thrust".into()
        ));
    }
    let input = law_input(&model);
    if !channels.contains_key(&input) {
        let key = input.key();
        return Err(bad(format!("its law reads channel `{key}`, which is not mapped")));
    }
    Ok(Some(model))
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
        let time = time_map(file, &raw.time)?;
        let mut channels = BTreeMap::new();
        let (mut actuators, mut shifts) = (BTreeMap::new(), BTreeMap::new());
        for (key, spec) in &raw.channels {
            let (ch, m) = channel_map(text, file, key, spec)?;
            if let Some(a) = actuator_of(text, file, key, spec, ch, &m)? {
                actuators.insert(ch, a);
            }
            if let Some(t) = shift_of(text, file, key, spec, ch, &m)? {
                shifts.insert(ch, t);
            }
            channels.insert(ch, m);
        }
        check_channel_set(file, &channels)?;
        check_file_settings(file, &raw, &channels)?;
        let (align, quaternion, air_data) = resolve_log_tables(file, &raw, &channels)?;
        let thrust_model = thrust_model_of(file, raw.thrust_model.as_ref(), &channels)?;
        let column_names = raw.columns.map(|c| c.names);
        if let Some(names) = &column_names {
            check_column_names(file, names)?;
        }
        Ok(Self {
            file: file.to_string(),
            description: raw.description.unwrap_or_default(),
            nominal_dt_s: raw.nominal_dt_s,
            inertia_reference_mass_kg: raw.inertia_reference_mass_kg,
            time,
            channels,
            align,
            quaternion,
            air_data,
            column_names,
            actuators,
            thrust_model,
            shifts,
        })
    }

    /// The surfaces' time shifts the mapping declares (`shift_s` on `de`, `da`, `dr`), in
    /// seconds, each non-zero: the record stage reads surface `ch` `shift_s` later, so that
    /// the value used at time `t` is the logged one at `t − shift_s` (a PX4 log's commands,
    /// one 50-Hz sample late against the servos, take `shift_s = -0.02`). Applied by the jobs
    /// with any compatibility corrections, before the estimators see the record
    /// (`docs/mapping.md`, "Surfaces recorded early or late").
    pub fn input_shifts(&self) -> Vec<(Channel, f64)> {
        self.shifts.iter().map(|(c, t)| (*c, *t)).filter(|(_, t)| *t != 0.0).collect()
    }

    /// Whether channel `ch` is mapped (to a column or a constant).
    pub fn has(&self, ch: Channel) -> bool {
        self.channels.contains_key(&ch)
    }

    /// A sample field an estimator names in an error (`r_rad_s`, `Iyy_kgm2`, …; the
    /// `AirDataSample` / `AircraftConstants` field) in the user's terms: the mapping channel,
    /// and where this mapping takes it from, e.g. ``channel `r` (column `R_dps` of FILE)``,
    /// ``channel `Iyy` (a constant in FILE)`` or ``channel `r` (not mapped in FILE)``. `None` for
    /// a name that is no sample field (the estimator's own configuration).
    pub fn describe_field(&self, field: &str) -> Option<String> {
        let ch = Channel::of_sample_field(field)?;
        let file = &self.file;
        let key = ch.key();
        let expression = self.channels.get(&ch).and_then(|m| m.expression.as_ref());
        Some(match self.channels.get(&ch).map(|m| &m.source) {
            Some(Source::Columns(_)) if let Some(e) = expression => {
                format!("channel `{key}` (expression `{}` of {file})", e.text())
            }
            Some(Source::Columns(cols)) => {
                let names: Vec<String> = cols.iter().map(|(c, _)| format!("`{c}`")).collect();
                let what = if names.len() == 1 { "column" } else { "columns" };
                format!("channel `{key}` ({what} {} of {file})", names.join(", "))
            }
            Some(Source::Constant(_)) => format!("channel `{key}` (a constant in {file})"),
            None if ch == Channel::Rho => {
                format!("channel `rho` (not mapped in {file}; derived from qbar and vt)")
            }
            None => format!("channel `{key}` (not mapped in {file})"),
        })
    }
}

impl Mapping {
    /// A sample field (`de_rad`, `thrust_n`, …) as a row's message names it: the mapping
    /// channel and where it comes from, without the mapping file, e.g. ``channel `de` (column
    /// `elevator_rad`, the mapping's offset 3 applied)`` or ``channel `qdot` (derived, not a
    /// column)``. A name that is no sample field is given as it is, in backticks.
    pub fn field_label(&self, field: &str) -> String {
        match Channel::of_sample_field(field) {
            Some(ch) => self.channel_label(ch),
            None => format!("`{field}`"),
        }
    }

    /// Channel `ch` as a message names it: ``channel `de` (column `elevator_rad`, …)``, or
    /// ``channel `qdot` (derived, not a column)`` when the mapping has no source for it.
    pub fn channel_label(&self, ch: Channel) -> String {
        let key = ch.key();
        let Some(m) = self.channels.get(&ch) else {
            return format!("channel `{key}` (derived, not a column)");
        };
        let source = match (&m.source, &m.expression) {
            (Source::Columns(_), Some(e)) => format!("expression `{}`", e.text()),
            (Source::Columns(cols), None) => {
                let names: Vec<String> = cols.iter().map(|(c, _)| format!("`{c}`")).collect();
                let what = if names.len() == 1 { "column" } else { "columns" };
                format!("{what} {}", names.join(", "))
            }
            (Source::Constant(_), _) => "a constant".into(),
        };
        format!("channel `{key}` ({source}{})", Self::adjustment(m))
    }

    /// What the mapping does to a channel's raw value besides the unit, for a message: its
    /// scale, offset or calibration table (empty when none).
    fn adjustment(m: &ChannelMap) -> String {
        let mut parts = Vec::new();
        if m.scale != 1.0 {
            parts.push(format!("scale {}", aeroident_physics::text::Short(m.scale)));
        }
        if m.offset != 0.0 {
            parts.push(format!("offset {}", aeroident_physics::text::Short(m.offset)));
        }
        if m.calibration.is_some() {
            parts.push("calibration table".to_string());
        }
        if parts.is_empty() {
            return String::new();
        }
        format!(", the mapping's {} applied", parts.join(" and "))
    }
}

type LogTables = (Option<AlignSpec>, Option<[String; 4]>, Option<AirDataSpec>);

/// The `[time]` table resolved to seconds: a non-zero scale (else every row would have the
/// same time) and a column, never a constant.
fn time_map(file: &str, spec: &ChannelSpec) -> Result<ChannelMap, FlightDataError> {
    if spec.scale == 0.0 {
        return Err(FlightDataError::BadSpec {
            file: file.to_string(),
            channel: "time".into(),
            reason:
                "[time]: `scale = 0`: scale must be non-zero (every row would have the same time)"
                    .into(),
        });
    }
    check_time_spec(file, spec)?;
    let time = resolve(file, "time", spec, Dimension::Time)?;
    if matches!(time.source, Source::Constant(_)) {
        return Err(FlightDataError::BadSpec {
            file: file.to_string(),
            channel: "time".into(),
            reason: "time must come from a column".into(),
        });
    }
    Ok(time)
}

/// The checked actuator of channel `ch` when its spec declares one: only a surface read from
/// columns can be commanded. Errors name the file, the channel and the line.
fn actuator_of(
    text: &str,
    file: &str,
    key: &Spanned<String>,
    spec: &ChannelSpec,
    ch: Channel,
    m: &ChannelMap,
) -> Result<Option<Actuator>, FlightDataError> {
    let Some(a) = &spec.actuator else { return Ok(None) };
    let bad = |reason: String| FlightDataError::BadSpec {
        file: file.to_string(),
        channel: ch.key().into(),
        reason: format!("line {}: {reason}", line_of(text, key.span().start)),
    };
    if let Some(why) = not_a_logged_surface("actuator", ch, m) {
        return Err(bad(why));
    }
    Actuator::from_spec(a).map(Some).map_err(bad)
}

/// Why the surface key `key` (`actuator`, `shift_s`) does not apply to channel `ch` read
/// through `m`, `None` if it does: only a surface (`de`, `da`, `dr`) read from columns has a
/// logged command to lag or a timing to shift.
fn not_a_logged_surface(key: &str, ch: Channel, m: &ChannelMap) -> Option<String> {
    if !matches!(ch, Channel::De | Channel::Da | Channel::Dr) {
        return Some(format!("`{key}` applies to the surfaces `de`, `da`, `dr` only"));
    }
    matches!(m.source, Source::Constant(_)).then(|| {
        format!(
            "`{key}` applies to a surface read from columns, not to a `value` (a constant surface)"
        )
    })
}

/// The checked `shift_s` of channel `ch` when its spec declares one: only a surface read from
/// columns, finite and within ±[`MAX_INPUT_SHIFT_S`]. Errors name the file, the channel, the
/// line and the key.
fn shift_of(
    text: &str,
    file: &str,
    key: &Spanned<String>,
    spec: &ChannelSpec,
    ch: Channel,
    m: &ChannelMap,
) -> Result<Option<f64>, FlightDataError> {
    let Some(t) = spec.shift_s else { return Ok(None) };
    let bad = |reason: String| FlightDataError::BadSpec {
        file: file.to_string(),
        channel: ch.key().into(),
        reason: format!("line {}: `shift_s = {}`: {reason}", line_of(text, key.span().start), t),
    };
    if let Some(why) = not_a_logged_surface("shift_s", ch, m) {
        return Err(bad(why));
    }
    if !t.is_finite() || t.abs() > MAX_INPUT_SHIFT_S {
        return Err(bad(format!(
            "must be finite and within ±{MAX_INPUT_SHIFT_S} s (a larger offset is a wrong column or time base, not a timing error)"
        )));
    }
    Ok(Some(t))
}

/// One `[channels]` entry `key` resolved to SI: a known channel with a non-zero scale, and a
/// constant within the channel's physical range (positive where it must be). Errors carry
/// the TOML line of `key` in `text`.
fn channel_map(
    text: &str,
    file: &str,
    key: &Spanned<String>,
    spec: &ChannelSpec,
) -> Result<(Channel, ChannelMap), FlightDataError> {
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
        // on it is 0 and the parameters it feeds are never identified.
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
            reason: format!("must be > 0, got {}", exact_or_short(v)),
        });
    }
    if let Some(v) = m.constant()
        && let Err(reason) = check_constant_range(ch, v)
    {
        return Err(FlightDataError::BadSpec {
            file: file.to_string(),
            channel: ch.key().into(),
            reason: format!(
                "line {}: `value = {:?}` {}: {reason}",
                line_of(text, key.span().start),
                spec.value.unwrap_or(v),
                spec.unit
            ),
        });
    }
    Ok((ch, m))
}

/// The mapped channels are enough to build samples: every required channel, `qbar` or `rho`
/// (the dynamic pressure or what it is computed from), and for a vane correction the flow
/// angle and the rate it is corrected with.
fn check_channel_set(
    file: &str,
    channels: &BTreeMap<Channel, ChannelMap>,
) -> Result<(), FlightDataError> {
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
    Ok(())
}

/// The file-level settings: a finite positive `nominal_dt_s`, and an
/// `inertia_reference_mass_kg` that is finite, positive and has an inertia to scale.
fn check_file_settings(
    file: &str,
    raw: &MappingFile,
    channels: &BTreeMap<Channel, ChannelMap>,
) -> Result<(), FlightDataError> {
    if let Some(dt) = raw.nominal_dt_s
        && !(dt.is_finite() && dt > 0.0)
    {
        return Err(FlightDataError::BadSpec {
            file: file.to_string(),
            channel: "nominal_dt_s".into(),
            reason: format!("must be finite and > 0, got {}", exact_or_short(dt)),
        });
    }
    if let Some(m0) = raw.inertia_reference_mass_kg {
        if !(m0.is_finite() && m0 > 0.0) {
            return Err(FlightDataError::BadSpec {
                file: file.to_string(),
                channel: "inertia_reference_mass_kg".into(),
                reason: format!("must be finite and > 0, got {}", exact_or_short(m0)),
            });
        }
        if ![Channel::Ixx, Channel::Iyy, Channel::Izz].iter().any(|c| channels.contains_key(c)) {
            return Err(FlightDataError::BadSpec {
                file: file.to_string(),
                channel: "inertia_reference_mass_kg".into(),
                reason: "no inertia (Ixx, Iyy, Izz) is mapped to scale".into(),
            });
        }
        let mass = channels.get(&Channel::Mass).and_then(ChannelMap::constant);
        if let Some(mass) =
            mass.filter(|m| !(m / m0 <= MAX_LOADING_RATIO && m0 / m <= MAX_LOADING_RATIO))
        {
            return Err(FlightDataError::BadSpec {
                file: file.to_string(),
                channel: "inertia_reference_mass_kg".into(),
                reason: format!(
                    "{} kg beside the constant mass {} kg would scale the inertias by {}: no loading changes them that much (at most ×{MAX_LOADING_RATIO} either way); is it the same aircraft and unit?",
                    exact_or_short(m0),
                    exact_or_short(mass),
                    short(mass / m0)
                ),
            });
        }
    }
    check_inertia_tensor(file, channels)
}

/// How far a sample's mass may lie from `inertia_reference_mass_kg`, either way: an empty
/// aircraft weighs about half of its maximum take-off mass, so ×3 is ample for fuel burn and
/// loading, and a larger ratio is a wrong unit or another aircraft.
const MAX_LOADING_RATIO: f64 = 3.0;

/// Checks constant inertias describe a body: each moment at most the sum of the other two
/// (the triangle inequality every rigid body's moments satisfy, about any axes), and with a
/// constant `Ixz`, `Ixx·Izz > Ixz²` (the tensor positive definite). A mapping that breaks it
/// would make the moment equations of a body that cannot exist.
fn check_inertia_tensor(
    file: &str,
    channels: &BTreeMap<Channel, ChannelMap>,
) -> Result<(), FlightDataError> {
    let constant = |c: Channel| channels.get(&c).and_then(ChannelMap::constant);
    let bad = |channel: &str, reason: String| FlightDataError::BadSpec {
        file: file.to_string(),
        channel: channel.into(),
        reason,
    };
    let (Some(ixx), Some(iyy), Some(izz)) =
        (constant(Channel::Ixx), constant(Channel::Iyy), constant(Channel::Izz))
    else {
        return Ok(());
    };
    // A relative margin for moments rounded in the source (a flat plate has Izz = Ixx + Iyy).
    let over = |a: f64, b: f64, c: f64| a > (b + c) * (1.0 + 1e-6);
    for (name, a, b, c, others) in [
        ("Ixx", ixx, iyy, izz, "Iyy + Izz"),
        ("Iyy", iyy, ixx, izz, "Ixx + Izz"),
        ("Izz", izz, ixx, iyy, "Ixx + Iyy"),
    ] {
        if over(a, b, c) {
            return Err(bad(
                name,
                format!(
                    "{name} = {} kg·m² exceeds {others} = {} kg·m²: no rigid body has such moments of inertia (a channel swapped, or a unit?)",
                    exact_or_short(a),
                    exact_or_short(b + c)
                ),
            ));
        }
    }
    match constant(Channel::Ixz) {
        Some(ixz) if ixz * ixz >= ixx * izz => Err(bad(
            "Ixz",
            format!(
                "Ixz = {} kg·m² with Ixx = {} and Izz = {}: Ixz² must be below Ixx·Izz for a body's inertia tensor",
                exact_or_short(ixz),
                exact_or_short(ixx),
                exact_or_short(izz)
            ),
        )),
        _ => Ok(()),
    }
}

/// Validates `[align]`, `[attitude]` and `[air_data]`, and that derived columns used by
/// channels have the table that makes them.
fn resolve_log_tables(
    file: &str,
    raw: &MappingFile,
    channels: &BTreeMap<Channel, ChannelMap>,
) -> Result<LogTables, FlightDataError> {
    let bad = |channel: &str, reason: String| FlightDataError::BadSpec {
        file: file.to_string(),
        channel: channel.to_string(),
        reason,
    };
    let align = match &raw.align {
        None => None,
        Some(a) => {
            let method = match a.method.as_str() {
                "linear" => Interpolation::Linear,
                "zoh" | "zero-order-hold" => Interpolation::ZeroOrderHold,
                m => {
                    return Err(bad(
                        "align.method",
                        format!("`{m}` is not a method (use \"linear\" or \"zoh\")"),
                    ));
                }
            };
            let clock = match (a.rate_hz, &a.clock) {
                (Some(r), None) if r.is_finite() && r > 0.0 => Clock::RateHz(r),
                (Some(r), None) => {
                    return Err(bad(
                        "align.rate_hz",
                        format!("must be finite and > 0, got {}", exact_or_short(r)),
                    ));
                }
                (None, Some(c)) if !c.is_empty() => Clock::Topic(c.clone()),
                _ => {
                    return Err(bad(
                        "align",
                        "give exactly one of `rate_hz` or `clock` (a topic name)".into(),
                    ));
                }
            };
            Some(AlignSpec { clock, method })
        }
    };
    let quaternion = match &raw.attitude {
        None => None,
        Some(a) => Some(<[String; 4]>::try_from(a.quaternion.clone()).map_err(|q| {
            bad("attitude.quaternion", format!("give 4 columns (w, x, y, z), got {}", q.len()))
        })?),
    };
    if let Some(q) = &quaternion {
        distinct_components(q).map_err(|r| bad("attitude.quaternion", r))?;
    }
    let air_data = match &raw.air_data {
        None => None,
        Some(a) => {
            if quaternion.is_none() {
                return Err(bad(
                    "air_data",
                    "needs [attitude] quaternion to rotate the velocity into body axes".into(),
                ));
            }
            let ned_velocity = <[String; 3]>::try_from(a.ned_velocity.clone()).map_err(|v| {
                bad("air_data.ned_velocity", format!("give 3 columns (N, E, D), got {}", v.len()))
            })?;
            distinct_components(&ned_velocity).map_err(|r| bad("air_data.ned_velocity", r))?;
            let wind_ne = match &a.wind_ne {
                None => None,
                Some(w) => Some(<[String; 2]>::try_from(w.clone()).map_err(|w| {
                    bad("air_data.wind_ne", format!("give 2 columns (N, E), got {}", w.len()))
                })?),
            };
            if let Some(w) = &wind_ne {
                distinct_components(w).map_err(|r| bad("air_data.wind_ne", r))?;
            }
            let min_vt_mps = a.min_vt_mps.unwrap_or(1.0);
            if !(min_vt_mps.is_finite() && min_vt_mps > 0.0) {
                return Err(bad(
                    "air_data.min_vt_mps",
                    format!("must be finite and > 0, got {}", exact_or_short(min_vt_mps)),
                ));
            }
            Some(AirDataSpec { ned_velocity, wind_ne, min_vt_mps })
        }
    };
    for (ch, m) in channels {
        let Source::Columns(cols) = &m.source else { continue };
        for (c, _) in cols {
            let euler = [EULER_PHI, EULER_THETA, EULER_PSI].contains(&c.as_str());
            let air = [AIR_VT, AIR_ALPHA, AIR_BETA].contains(&c.as_str());
            if euler && quaternion.is_none() {
                return Err(bad(ch.key(), format!("column `{c}` needs an [attitude] table")));
            }
            if air && air_data.is_none() {
                return Err(bad(ch.key(), format!("column `{c}` needs an [air_data] table")));
            }
        }
    }
    Ok((align, quaternion, air_data))
}

/// The components of a vector (quaternion, velocity, wind) must be different, non-empty
/// columns: one column as two components makes an absurd vector (a quaternion of one component
/// four times is the fixed attitude φ = 90°, θ = 0, ψ = 90°, whatever the aircraft does).
fn distinct_components(columns: &[String]) -> Result<(), String> {
    for (i, c) in columns.iter().enumerate() {
        if c.is_empty() {
            return Err(format!("component {} is an empty column name", i + 1));
        }
        if let Some(j) = columns[..i].iter().position(|d| d == c) {
            return Err(format!(
                "`{c}` is given twice (components {} and {}): each component needs its own column",
                j + 1,
                i + 1
            ));
        }
    }
    Ok(())
}

/// `[columns] names` must be non-empty, unique, and free of line breaks and surrounding
/// spaces (a header field is trimmed, so such a name could never match).
fn check_column_names(file: &str, names: &[String]) -> Result<(), FlightDataError> {
    let bad = |reason: String| FlightDataError::BadSpec {
        file: file.to_string(),
        channel: "columns.names".into(),
        reason,
    };
    if names.is_empty() {
        return Err(bad("the list is empty".into()));
    }
    for (i, n) in names.iter().enumerate() {
        if n.is_empty() || n.trim() != n || n.contains(['\n', '\r']) {
            return Err(bad(format!(
                "name {} `{n}` is empty, has surrounding spaces or a line break",
                i + 1
            )));
        }
        if let Some(j) = names[..i].iter().position(|m| m == n) {
            return Err(bad(format!("`{n}` is given twice (columns {} and {})", j + 1, i + 1)));
        }
    }
    Ok(())
}

/// The time channel must grow with its column: a negative scale would reverse every interval
/// (each row then "goes backwards"), and a calibration table has no meaning for a clock.
fn check_time_spec(file: &str, spec: &ChannelSpec) -> Result<(), FlightDataError> {
    let bad = |reason: String| FlightDataError::BadSpec {
        file: file.to_string(),
        channel: "time".into(),
        reason,
    };
    if spec.scale < 0.0 {
        return Err(bad(format!(
            "`scale = {}`: a negative scale reverses time (every row would go backwards)",
            spec.scale
        )));
    }
    if spec.calibration.is_some() {
        return Err(bad("`calibration` does not apply to the time channel".into()));
    }
    if spec.shift_s.is_some() {
        return Err(bad("`shift_s` applies to the surfaces `de`, `da`, `dr` only".into()));
    }
    Ok(())
}

/// The columns of one channel: named, and each once. A column given twice is summed twice
/// (the channel would be double its value), a zero weight drops its column (all zero: a
/// constant channel).
fn check_columns(cols: &[(String, f64)]) -> Result<(), String> {
    for (i, (c, w)) in cols.iter().enumerate() {
        if c.is_empty() {
            return Err("a column name is empty".into());
        }
        if let Some(j) = cols[..i].iter().position(|(d, _)| d == c) {
            return Err(format!(
                "column `{c}` is given twice (entries {} and {}): its values would be summed twice; give it once, with a weight if a multiple is meant",
                j + 1,
                i + 1
            ));
        }
        if *w == 0.0 {
            return Err(format!(
                "weight {} (column `{c}`) is 0: the column would not count; remove it",
                i + 1
            ));
        }
    }
    Ok(())
}

/// The gain from a raw column value to SI, `weight · scale · unit factor`, must be a normal
/// number: one that underflows to 0 (or a subnormal) makes the channel constant, one that
/// overflows makes every row non-finite.
fn check_gain(spec: &ChannelSpec, unit: &Unit, source: &Source) -> Result<(), String> {
    let Source::Columns(cols) = source else { return Ok(()) };
    let weights: Vec<f64> =
        if spec.expr.is_some() { vec![1.0] } else { cols.iter().map(|(_, w)| *w).collect() };
    for w in weights {
        let gain = w * spec.scale * unit.to_si;
        if !gain.is_normal() {
            let weight = if w == 1.0 { String::new() } else { format!("weight {w:e} × ") };
            return Err(format!(
                "{weight}scale {:e} × unit `{}` ({:e} SI) gives the gain {gain:e}: the channel would be {}",
                spec.scale,
                spec.unit,
                unit.to_si,
                if gain.is_finite() {
                    "constant (underflow to 0)"
                } else {
                    "non-finite (overflow)"
                }
            ));
        }
    }
    Ok(())
}

/// A calibration table `[raw, value]`: at least 2 finite points, raw values increasing
/// strictly, values running one way ([`check_calibration_values`]).
fn check_calibration(t: &[(f64, f64)]) -> Result<(), String> {
    if t.len() < 2 {
        return Err(format!("calibration needs at least 2 points, got {}", t.len()));
    }
    if let Some((r, v)) = t.iter().find(|(r, v)| !(r.is_finite() && v.is_finite())) {
        return Err(format!(
            "calibration point [{}, {}] is not finite",
            exact_or_short(*r),
            exact_or_short(*v)
        ));
    }
    if let Some(w) = t.windows(2).find(|w| w[1].0 <= w[0].0) {
        return Err(format!(
            "calibration raw values must increase strictly: {} then {}",
            exact_or_short(w[0].0),
            exact_or_short(w[1].0)
        ));
    }
    check_calibration_values(t)
}

/// A calibration's values must not all be equal (a constant channel) and must run one way
/// (non-decreasing or non-increasing; flat stretches are dead bands): a table that rises and
/// falls maps two raw values to one deflection.
fn check_calibration_values(table: &[(f64, f64)]) -> Result<(), String> {
    let first = table[0].1;
    if table.iter().all(|(_, v)| *v == first) {
        return Err(format!(
            "calibration values are all {}: the channel would be constant",
            exact_or_short(first)
        ));
    }
    let rises = table.windows(2).any(|w| w[1].1 > w[0].1);
    let falls = table.windows(2).any(|w| w[1].1 < w[0].1);
    if rises && falls {
        let values: Vec<String> = table.iter().map(|(_, v)| exact_or_short(*v)).collect();
        return Err(format!(
            "calibration values rise and fall ({}): two raw values would give the same value; the values must run one way",
            crate::message::list(&values, 12)
        ));
    }
    Ok(())
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
        return Err(bad(not_finite(spec.scale, spec.offset)));
    }
    if spec.weights.is_some() && spec.columns.is_none() {
        return Err(bad("`weights` needs `columns`".into()));
    }
    let mut expression = None;
    let source = match (&spec.column, &spec.columns, spec.value) {
        (None, None, None) if spec.expr.is_some() => {
            let text = spec.expr.as_deref().unwrap_or_default();
            let e = crate::expression::Expression::parse(text)
                .map_err(|m| bad(format!("expr `{text}`: {m}")))?;
            if e.columns().is_empty() {
                return Err(bad(format!(
                    "expr `{text}` reads no column: map a constant with `value`"
                )));
            }
            let cols = e.columns().iter().map(|c| (c.clone(), 1.0)).collect();
            expression = Some(e);
            Source::Columns(cols)
        }
        _ if spec.expr.is_some() => {
            return Err(bad(
                "give exactly one of `column`, `columns` (non-empty), `value` or `expr`".into(),
            ));
        }
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
                return Err(bad(format!("weight {} is not finite", exact_or_short(*w))));
            }
            Source::Columns(cs.iter().cloned().zip(weights).collect())
        }
        (None, None, Some(v)) => {
            let si = (v * spec.scale + spec.offset) * unit.to_si;
            if !si.is_finite() {
                return Err(bad(format!("value {} is not finite in SI ({si})", exact_or_short(v))));
            }
            Source::Constant(si)
        }
        _ => {
            return Err(bad(
                "give exactly one of `column`, `columns` (non-empty), `value` or `expr`".into(),
            ));
        }
    };
    if let Source::Columns(cols) = &source
        && expression.is_none()
    {
        check_columns(cols).map_err(bad)?;
    }
    check_gain(spec, &unit, &source).map_err(bad)?;
    let calibration = match &spec.calibration {
        None => None,
        Some(_) if matches!(source, Source::Constant(_)) => {
            return Err(bad("`calibration` applies to columns, not to a `value`".into()));
        }
        Some(points) => {
            let t: Vec<(f64, f64)> = points.iter().map(|[r, v]| (*r, *v)).collect();
            check_calibration(&t).map_err(bad)?;
            Some(t)
        }
    };
    Ok(ChannelMap {
        source,
        to_si: unit.to_si,
        scale: spec.scale,
        offset: spec.offset,
        unit: spec.unit.clone(),
        calibration,
        expression,
    })
}

/// The message of a scale or offset that is not finite, both shown short.
fn not_finite(scale: f64, offset: f64) -> String {
    use aeroident_physics::text::Short;
    format!("scale {} and offset {} must be finite", Short(scale), Short(offset))
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nmass = { value = 1.0, unit = \"kg\" }\nS = { value = 1.0, unit = \"m2\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\n";

    /// A commanded surface's actuator is read with its units; one on a channel that is not a
    /// surface, on a constant, with a time constant of 0 or limits out of order is refused,
    /// naming file, channel and line.
    #[test]
    fn actuator_of_a_commanded_surface_is_checked() {
        let act = "actuator = { tau_s = 0.05, rate_limit_rad_s = 1.0, position_limits_rad = [-0.4, 0.4] }";
        let text = format!("{HEAD}de = {{ column = \"cmd\", unit = \"rad\", {act} }}\n");
        let m = Mapping::from_toml_str(&text, "m.toml").unwrap();
        let a = m.actuators[&Channel::De];
        assert_eq!((a.tau_s, a.rate_limit_rad_s, a.position_limits_rad), (0.05, 1.0, (-0.4, 0.4)));
        let plain = format!(
            "{HEAD}de = {{ column = \"cmd\", unit = \"rad\", actuator = {{ tau_s = 0.05 }} }}\n"
        );
        let a = Mapping::from_toml_str(&plain, "m.toml").unwrap().actuators[&Channel::De];
        assert!(a.rate_limit_rad_s.is_infinite() && a.position_limits_rad.0.is_infinite());
        for (line, want) in [
            (format!("q = {{ column = \"q\", unit = \"rad/s\", {act} }}"), "surfaces `de`, `da`, `dr` only"),
            (format!("de = {{ value = 0.0, unit = \"rad\", {act} }}"), "not to a `value`"),
            ("de = { column = \"c\", unit = \"rad\", actuator = { tau_s = 0.0 } }".into(), "(0, 1] s"),
            (
                "de = { column = \"c\", unit = \"rad\", actuator = { tau_s = 0.05, position_limits_rad = [0.4, -0.4] } }".into(),
                "min < max",
            ),
            (
                "de = { column = \"c\", unit = \"rad\", actuator = { tau_s = 0.05, rate_limit_rad_s = -1.0 } }".into(),
                "positive and finite",
            ),
        ] {
            let e = Mapping::from_toml_str(&format!("{HEAD}{line}\n"), "m.toml").unwrap_err().to_string();
            assert!(e.starts_with("m.toml: channel `") && e.contains("line 10") && e.contains(want), "{e}");
        }
    }

    /// A surface's `shift_s` is kept as declared; one on a channel that is not a surface (`q`),
    /// on a constant, not finite, beyond ±0.5 s, or on the time channel is refused, naming
    /// file, channel, line and key.
    #[test]
    fn shift_of_a_surface_is_checked() {
        let text = format!(
            "{HEAD}de = {{ column = \"c\", unit = \"rad\", shift_s = -0.02 }}\nda = {{ column = \"a\", unit = \"rad\", shift_s = 0.0 }}\n"
        );
        let m = Mapping::from_toml_str(&text, "m.toml").unwrap();
        assert_eq!(m.input_shifts(), [(Channel::De, -0.02)]);
        for (line, want) in [
            (
                "q = { column = \"q\", unit = \"rad/s\", shift_s = 0.02 }",
                "surfaces `de`, `da`, `dr` only",
            ),
            ("de = { value = 0.0, unit = \"rad\", shift_s = 0.02 }", "constant surface"),
            ("de = { column = \"c\", unit = \"rad\", shift_s = nan }", "finite and within ±0.5 s"),
            ("dr = { column = \"c\", unit = \"rad\", shift_s = -inf }", "finite and within ±0.5 s"),
            ("da = { column = \"c\", unit = \"rad\", shift_s = 0.6 }", "finite and within ±0.5 s"),
        ] {
            let e = Mapping::from_toml_str(&format!("{HEAD}{line}\n"), "m.toml")
                .unwrap_err()
                .to_string();
            let channel = &line[..2];
            assert!(e.starts_with(&format!("m.toml: channel `{}", channel.trim())), "{e}");
            assert!(e.contains("line 10") && e.contains("`shift_s = ") && e.contains(want), "{e}");
        }
        let time = HEAD.replace("unit = \"s\"\n", "unit = \"s\"\nshift_s = 0.1\n");
        let e = Mapping::from_toml_str(&time, "m.toml").unwrap_err().to_string();
        assert!(e.starts_with("m.toml: channel `time`") && e.contains("`shift_s`"), "{e}");
    }

    /// A channel with `scale = 0` is identically its offset, so the parameters it
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

    /// A channel's scale and offset are shown short where a message describes the channel
    /// (a scale of 1e300 was written out in its 301 digits).
    #[test]
    fn a_channel_is_described_with_its_scale_short() {
        let text = format!(
            "{HEAD}q = {{ column = \"q\", unit = \"rad/s\", scale = 1e300, offset = -2.5e-7 }}\n"
        );
        let m = Mapping::from_toml_str(&text, "m.toml").unwrap();
        let d = m.field_label("q_rad_s");
        assert!(d.contains("scale 1.000e300") && d.contains("offset -2.500e-7"), "{d}");
        assert!(d.len() < 120, "{d}");
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
    fn analytic_calibration_is_piecewise_linear_and_nan_outside() {
        let text = format!(
            "{HEAD}de = {{ column = \"pwm\", calibration = [[1000, -20.0], [1500, 0.0], [2000, 30.0]], unit = \"deg\", offset = 1.0 }}\n"
        );
        let m = Mapping::from_toml_str(&text, "m.toml").unwrap();
        let de = &m.channels[&Channel::De];
        let deg = |d: f64| d.to_radians();
        assert!((de.to_si(1000.0) - deg(-19.0)).abs() < 1e-15);
        assert!((de.to_si(1250.0) - deg(-9.0)).abs() < 1e-15);
        assert!((de.to_si(1500.0) - deg(1.0)).abs() < 1e-15);
        assert!((de.to_si(1900.0) - deg(25.0)).abs() < 1e-14);
        assert!((de.to_si(2000.0) - deg(31.0)).abs() < 1e-15);
        assert!(de.to_si(999.9).is_nan() && de.to_si(2000.1).is_nan());
        for (cal, want) in [
            ("[[1000, 0.0]]", "at least 2 points"),
            ("[[1000, 0.0], [1000, 1.0]]", "must increase strictly: 1000 then 1000"),
            ("[[1000, 0.0], [900, 1.0]]", "must increase strictly"),
        ] {
            let text =
                format!("{HEAD}de = {{ column = \"pwm\", calibration = {cal}, unit = \"deg\" }}\n");
            let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
            assert!(e.contains("`de`") && e.contains(want), "{e}");
        }
    }

    #[test]
    fn log_tables_parse_and_derived_columns_need_their_table() {
        let text = format!(
            "{HEAD}phi = {{ column = \"euler.phi\", unit = \"rad\" }}\n[align]\nclock = \"imu\"\nmethod = \"zoh\"\n[attitude]\nquaternion = [\"a.q[0]\", \"a.q[1]\", \"a.q[2]\", \"a.q[3]\"]\n"
        );
        let m = Mapping::from_toml_str(&text, "m.toml").unwrap();
        assert_eq!(
            m.align,
            Some(AlignSpec {
                clock: Clock::Topic("imu".into()),
                method: Interpolation::ZeroOrderHold
            })
        );
        assert_eq!(m.quaternion.as_ref().unwrap()[3], "a.q[3]");
        let text = format!("{HEAD}phi = {{ column = \"euler.phi\", unit = \"rad\" }}\n");
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.contains("`phi`: column `euler.phi` needs an [attitude] table"), "{e}");
        let text = format!("{HEAD}[align]\nrate_hz = 50.0\nclock = \"x\"\nmethod = \"linear\"\n");
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.contains("exactly one of `rate_hz` or `clock`"), "{e}");
        let text = format!("{HEAD}[align]\nrate_hz = 50.0\nmethod = \"cubic\"\n");
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.contains("`cubic` is not a method"), "{e}");
        let text = format!("{HEAD}[air_data]\nned_velocity = [\"p.vx\", \"p.vy\", \"p.vz\"]\n");
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.contains("needs [attitude] quaternion"), "{e}");
    }

    #[test]
    fn column_names_for_headerless_files_are_checked() {
        let text = format!("{HEAD}[columns]\nnames = [\"t\", \"V\", \"a\"]\n");
        let m = Mapping::from_toml_str(&text, "m.toml").unwrap();
        assert_eq!(m.column_names, Some(vec!["t".into(), "V".into(), "a".into()]));
        assert_eq!(Mapping::from_toml_str(HEAD, "m.toml").unwrap().column_names, None);
        let text = format!("{HEAD}[columns]\nnames = [\"t\", \"V\", \"t\"]\n");
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.contains("`columns.names`: `t` is given twice (columns 1 and 3)"), "{e}");
        let text = format!("{HEAD}[columns]\nnames = [\"t\", \" V\"]\n");
        let e = Mapping::from_toml_str(&text, "m.toml").unwrap_err().to_string();
        assert!(e.contains("name 2 ` V`"), "{e}");
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
