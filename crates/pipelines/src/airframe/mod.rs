//! An aircraft built from identified derivatives: a model file's structure (`models/*.toml`,
//! [`aeroident_io::model_file::ModelSpec`]) with parameter values (a replay summary's estimates
//! or the model file's `[reference.<param>]` values) and a mapping's constants (mass, inertia,
//! S, b, c̄, thrust line; a `[thrust_model]` law), flown by the same trim, linearization and
//! simulation as the F-16 ([`aeroident_models::aircraft::Aircraft`]).
//!
//! # Equations
//! The flat-earth 6-DOF rigid body of the shared kernel ([`aeroident_physics::rigid_body`];
//! Stevens, Lewis & Johnson 3rd ed. §2.5, §3.5) as the output-error flight model evaluates it
//! ([`aeroident_estimators::flight_model::FlightModel::eval`], coupled state set): the
//! coefficients are the vocabulary's `C_k = Σ θ_kj ξ_j` ([`aeroident_estimators::vocabulary`],
//! `Term::value` conventions: p̂ = pb/2V, q̂ = qc̄/2V, r̂ = rb/2V, δ rad, SLJ signs), stability-axis
//! `CL`, `CD` rotated into body axes through α, forces `q̄S C`, moments `q̄Sb Cl`, `q̄Sc̄ Cm`,
//! `q̄Sb Cn` about the CG, an α̇ term solved exactly, thrust along the thrust line (incidence
//! `σT`) with pitching moment `arm · T`, gravity `g0` = 9.80665 m/s². This module adds the
//! heading and navigation equations (`ψ̇ = (q sinφ + r cosφ)/cosθ`, `[ṅ, ė, −ḣ] = Cᵀ v_body`,
//! SLJ §1.3, §2.5), the atmosphere ([`Atmosphere`](crate::airframe::Atmosphere)) and the engine ([`Propulsion`](crate::airframe::Propulsion)).
//!
//! # States and controls (SI)
//! [`STATE_NAMES`](crate::airframe::STATE_NAMES): the rigid-body layout of [`aeroident_models::rigid_body`] in metres:
//! `vt_mps, alpha_rad, beta_rad, phi_rad, theta_rad, psi_rad, p_rad_s, q_rad_s, r_rad_s,
//! north_m, east_m, alt_m` (altitude up). Controls
//! [`aeroident_models::aircraft::CONTROL_NAMES`]: engine command (per [`Propulsion`](crate::airframe::Propulsion)),
//! elevator, aileron, rudder, rad. Still air; no rotor momentum, no engine lag.

pub mod f16;
mod files;
pub mod flyable;
pub(crate) mod handle;
pub mod modes;
#[cfg(test)]
pub(crate) mod tests;
#[cfg(test)]
mod third_aircraft;
mod trim;

pub use files::{airframe_from_mapping, load, parameter_values};
pub use flyable::FlyableAircraft;
pub use handle::{ACTUATOR_NOTE, ActuatorState, AnyAircraft, Linear, Trim};
pub use trim::{MAX_TRIM_ANGLE_RAD, trim_wings_level};

use aeroident_estimators::flight_model::{self as fm, FlightModel, ModelInputs, StateSet};
use aeroident_estimators::vocabulary::ModelStructure;
use aeroident_io::thrust_model::{LawInput, ThrustModel};
use aeroident_models::aircraft::{
    Aircraft, AircraftMass, AircraftTrim, ControlVector, ReferenceGeometry,
};
use aeroident_models::f16::data::AtmosphereConstants;
use aeroident_models::rigid_body::{self as rb, body_from_ned};
use aeroident_models::{Dynamics, ModelError, atmosphere};
use aeroident_physics::isa;
use aeroident_physics::units::{FT_PER_M, KGPM3_PER_SLUGPFT3};
use nalgebra::{SVector, Vector3};

/// Number of states.
pub const N_STATES: usize = rb::N_STATES;

/// State names with units, in state order (module doc): the rigid body's
/// ([`aeroident_models::rigid_body::STATE_NAMES`]) in metres, a test holding the two to one
/// layout.
pub const STATE_NAMES: [&str; N_STATES] = [
    "vt_mps",
    "alpha_rad",
    "beta_rad",
    "phi_rad",
    "theta_rad",
    "psi_rad",
    "p_rad_s",
    "q_rad_s",
    "r_rad_s",
    "north_m",
    "east_m",
    "alt_m",
];

/// The state vector, in the order of [`STATE_NAMES`].
pub type AirframeState = SVector<f64, N_STATES>;

/// What the engine command (control 0) is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Propulsion {
    /// The command is the thrust itself, N (a mapping with a `thrust` channel or none: trim
    /// solves for the thrust level flight needs).
    Commanded,
    /// The command is the law's input (throttle 0–1, or propeller speed rad/s), thrust from
    /// [`ThrustModel::thrust_n`] at the local density and airspeed.
    Law(ThrustModel),
}

impl Propulsion {
    /// What the command is, with its unit.
    pub fn command(&self) -> &'static str {
        match self {
            Propulsion::Commanded => "thrust_n",
            Propulsion::Law(law) => match law.input() {
                LawInput::Throttle => "throttle (0-1)",
                LawInput::PropSpeed => "prop_speed_rad_s",
            },
        }
    }
}

/// The atmosphere the aircraft flies in: density and speed of sound by altitude.
#[derive(Debug, Clone, PartialEq)]
pub enum Atmosphere {
    /// The 1976 standard atmosphere ([`aeroident_physics::isa`]).
    Isa,
    /// The textbook air-data computer of the Stevens–Lewis F-16 (SLJ §3.5 ADC,
    /// [`aeroident_models::atmosphere`]): to compare with the F-16 in the same air.
    Textbook(AtmosphereConstants),
}

impl Atmosphere {
    /// Density (kg/m³) and the Mach terms' speed of sound (m/s; the standard temperature of
    /// the density altitude, as [`aeroident_estimators::sample::AirDataSample::mach`] forms it
    /// from a record) at altitude `alt_m` (m).
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] (`alt_m`) outside the atmosphere model.
    pub fn air(&self, alt_m: f64) -> Result<(f64, f64), ModelError> {
        let outside = ModelError::InvalidValue {
            field: "alt_m",
            value: alt_m,
            reason: "outside the atmosphere model",
        };
        let rho = match self {
            Atmosphere::Isa => {
                let t = isa::temperature_k(alt_m).ok_or(outside.clone())?;
                isa::density_kgpm3(isa::pressure_pa(alt_m).ok_or(outside.clone())?, t)
            }
            Atmosphere::Textbook(c) => {
                atmosphere::air_data(c, 1.0, alt_m * FT_PER_M)?.rho_slug_ft3 * KGPM3_PER_SLUGPFT3
            }
        };
        let t = isa::temperature_of_density_k(rho).ok_or(outside)?;
        Ok((rho, isa::speed_of_sound_mps(t)))
    }
}

/// The constants of the airframe, SI (from a mapping, [`airframe_from_mapping`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Airframe {
    /// Mass and inertia.
    pub mass: AircraftMass,
    /// Reference geometry of the coefficients.
    pub geometry: ReferenceGeometry,
    /// Thrust pitching-moment arm, m (`M_T = arm · T`, positive nose-up).
    pub thrust_arm_m: f64,
    /// Thrust-line inclination to body x, rad, positive nose-up.
    pub thrust_incidence_rad: f64,
    /// Reference speed of the `V/V0` and `q0` terms, m/s.
    pub v0_mps: Option<f64>,
    /// The engine.
    pub propulsion: Propulsion,
    /// The surfaces' actuators (elevator, aileron, rudder), from the mapping's commanded
    /// surfaces: the surface follows its command through it in `sim` ([`crate::sim::aircraft`])
    /// and in the exports that hold one; `None` = the surface is the command.
    pub actuators: [Option<aeroident_io::mapping::Actuator>; 3],
}

/// An aircraft flying identified derivatives (module doc).
#[derive(Debug, Clone)]
pub struct ModelFileAircraft {
    name: String,
    /// What the values' sources left out and how it was filled ([`files::parameter_values`]).
    notes: Vec<String>,
    model: FlightModel,
    theta: Vec<f64>,
    airframe: Airframe,
    atmosphere: Atmosphere,
}

/// An evaluation error of the flight model as a model error: once [`ModelFileAircraft::new`]
/// has validated the structure, the only one is the singular α̇ equation (module doc of
/// [`aeroident_estimators::flight_model`]), named by its `what`.
fn model_error(e: aeroident_estimators::EstimatorError) -> ModelError {
    let reason = match e {
        aeroident_estimators::EstimatorError::Numerical { what, .. } => what,
        _ => "flight model evaluation failed",
    };
    ModelError::InvalidValue { field: "alphadot", value: f64::NAN, reason }
}

impl ModelFileAircraft {
    /// An aircraft named `name` flying `structure` with parameter values `theta` (structure
    /// order, [`ModelStructure::params`]) on `airframe`, in the standard atmosphere.
    ///
    /// # Errors
    /// The structure does not declare both axes (a force pair `CL`+`CD` or `CX`+`CZ`, `Cm`,
    /// `CY`, `Cl`, `Cn`), `theta` has the wrong length or a non-finite value, a `V`/`q0` term
    /// lacks `v0`, or a constant is not finite and positive (inertia: `Jx Jz > Jxz²`); each
    /// naming the parameter or constant.
    pub fn new(
        name: &str,
        structure: ModelStructure,
        theta: Vec<f64>,
        airframe: Airframe,
    ) -> crate::error::Result<Self> {
        let model = FlightModel::new(structure)
            .map_err(|e| crate::err!("model `{name}`: cannot be flown: {e}"))?;
        if model.state_set() != StateSet::Coupled {
            crate::bail!(
                "model `{name}` declares only the {} axis: flying needs CL+CD (or CX+CZ), Cm, CY, Cl and Cn",
                if model.state_set().lon() { "longitudinal" } else { "lateral" }
            );
        }
        if theta.len() != structure.n_params() {
            crate::bail!(
                "model `{name}`: {} parameter values for {} parameters",
                theta.len(),
                structure.n_params()
            );
        }
        for (p, v) in structure.names().zip(&theta) {
            if !v.is_finite() {
                crate::bail!("model `{name}`: parameter `{p}` = {v} is not finite");
            }
        }
        check_airframe(&airframe, &structure)?;
        let atmosphere = Atmosphere::Isa;
        Ok(Self { name: name.to_string(), notes: Vec::new(), model, theta, airframe, atmosphere })
    }

    /// The same aircraft in `atmosphere`.
    pub fn with_atmosphere(mut self, atmosphere: Atmosphere) -> Self {
        self.atmosphere = atmosphere;
        self
    }

    /// The same aircraft with `notes` on how its values were filled (each printed by the
    /// faces beside the held surfaces, [`Self::held_surfaces_note`]).
    pub fn with_notes(mut self, notes: Vec<String>) -> Self {
        self.notes = notes;
        self
    }

    /// The notes of [`Self::with_notes`].
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The surfaces (`de`, `da`, `dr`) the model has no derivative of: trimmed and flown held
    /// at 0 (a partial test card, e.g. an elevator-and-aileron UAV).
    pub fn held_surfaces(&self) -> Vec<&'static str> {
        flyable::held_surfaces(&self.structure())
    }

    /// A note naming [`Self::held_surfaces`], `None` when the model has every surface.
    pub fn held_surfaces_note(&self) -> Option<String> {
        let held = self.held_surfaces();
        (!held.is_empty()).then(|| {
            format!(
                "model `{}` has no `{}` derivative: that surface is held at 0 (trim, flight and the linear model's input column)",
                self.name,
                held.join("`, `")
            )
        })
    }

    /// The airframe constants.
    pub fn airframe(&self) -> &Airframe {
        &self.airframe
    }

    /// The model structure it flies.
    pub fn structure(&self) -> ModelStructure {
        *self.model.structure()
    }

    /// The parameter values it flies, in the order of [`Self::structure`]'s parameters.
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// The airframe as the estimators' flight model takes it (SI).
    pub fn constants(&self) -> aeroident_estimators::AircraftConstants {
        let a = &self.airframe;
        let thrust_line = (a.thrust_arm_m, a.thrust_incidence_rad);
        flyable::airframe_constants(&a.mass, &a.geometry, thrust_line, a.v0_mps)
    }

    /// Density (kg/m³) and the Mach terms' speed of sound (m/s; the standard temperature of
    /// the density altitude, as [`aeroident_estimators::sample::AirDataSample::mach`] forms it
    /// from a record) at altitude `alt_m`.
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] (`alt_m`) outside the atmosphere model.
    pub fn air(&self, alt_m: f64) -> Result<(f64, f64), ModelError> {
        self.atmosphere.air(alt_m)
    }

    /// Thrust, N, at density `rho_kgpm3`, airspeed `vt_mps` and engine command `command`.
    pub fn thrust_n(&self, rho_kgpm3: f64, vt_mps: f64, command: f64) -> f64 {
        match &self.airframe.propulsion {
            Propulsion::Commanded => command,
            Propulsion::Law(law) => law.thrust_n(rho_kgpm3, vt_mps, command),
        }
    }

    /// The flight model's inputs at state `x` and controls `u` (the states it integrates are
    /// taken from `x` by [`FlightModel::eval`], so `x_meas` is not read).
    fn inputs(
        &self,
        t_s: f64,
        x: &AirframeState,
        u: &ControlVector,
    ) -> Result<ModelInputs, ModelError> {
        let (rho, a) = self.air(x[rb::ALT])?;
        let thrust_n = self.thrust_n(rho, x[rb::VT], u[0]);
        let (af, m, g) = (&self.airframe, &self.airframe.mass, &self.airframe.geometry);
        Ok(ModelInputs {
            t_s,
            de_rad: u[1],
            da_rad: u[2],
            dr_rad: u[3],
            thrust_n,
            thrust_moment_nm: af.thrust_arm_m * thrust_n,
            rho_kgpm3: rho,
            a_mps: a,
            mass_kg: m.mass_kg,
            S_m2: g.wing_area_m2,
            cbar_m: g.chord_m,
            b_m: g.span_m,
            inertia: [m.jx_kgm2, m.jy_kgm2, m.jz_kgm2, m.jxz_kgm2],
            v0_mps: af.v0_mps.unwrap_or(0.0),
            thrust_incidence_rad: af.thrust_incidence_rad,
            ..ModelInputs::default()
        })
    }
}

/// Checks the airframe's constants (see [`ModelFileAircraft::new`]).
fn check_airframe(a: &Airframe, structure: &ModelStructure) -> crate::error::Result<()> {
    let (m, g) = (&a.mass, &a.geometry);
    let positive = [
        ("mass", m.mass_kg),
        ("Ixx", m.jx_kgm2),
        ("Iyy", m.jy_kgm2),
        ("Izz", m.jz_kgm2),
        ("S", g.wing_area_m2),
        ("b", g.span_m),
        ("cbar", g.chord_m),
    ];
    for (name, v) in positive {
        if !(v.is_finite() && v > 0.0) {
            crate::bail!("constant `{name}` = {v} must be finite and > 0 to fly the aircraft");
        }
    }
    for (name, v) in [
        ("Ixz", m.jxz_kgm2),
        ("thrust_arm", a.thrust_arm_m),
        ("thrust_incidence", a.thrust_incidence_rad),
    ] {
        if !v.is_finite() {
            crate::bail!("constant `{name}` = {v} is not finite");
        }
    }
    if m.jx_kgm2 * m.jz_kgm2 <= m.jxz_kgm2 * m.jxz_kgm2 {
        crate::bail!("constant `Ixz` = {}: Ixx·Izz − Ixz² must be > 0", m.jxz_kgm2);
    }
    let needs_v0 = structure.params().any(|p| {
        use aeroident_estimators::vocabulary::Term;
        matches!(p.term, Term::V | Term::Q0)
    });
    match a.v0_mps {
        Some(v) if !(v.is_finite() && v > 0.0) => crate::bail!("constant `v0` = {v} must be > 0"),
        None if needs_v0 => crate::bail!("the model has V/V0 or q0 terms: give the constant `v0`"),
        _ => Ok(()),
    }
}

/// Checks every state and control is finite, `vt > 0` and `cos θ ≠ 0`; errors name the state.
fn check_point(x: &AirframeState, u: &ControlVector) -> Result<(), ModelError> {
    let bad = |field, value, reason| Err(ModelError::InvalidValue { field, value, reason });
    for (k, v) in x.iter().enumerate() {
        if !v.is_finite() {
            return bad(STATE_NAMES[k], *v, "not finite");
        }
    }
    for (k, v) in u.iter().enumerate() {
        if !v.is_finite() {
            return bad(aeroident_models::aircraft::CONTROL_NAMES[k], *v, "not finite");
        }
    }
    if x[rb::VT] <= 0.0 {
        return bad(STATE_NAMES[rb::VT], x[rb::VT], "must be > 0");
    }
    if x[rb::THETA].cos() == 0.0 || x[rb::ALPHA].cos() * x[rb::BETA].cos() == 0.0 {
        return bad(STATE_NAMES[rb::THETA], x[rb::THETA], "|theta| or |beta| = 90 deg");
    }
    Ok(())
}

/// What the equations give at one point: the state derivative and the channels a record of
/// the flight holds (SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirframeOutputs {
    /// `ẋ`, state units per second ([`STATE_NAMES`]).
    pub xdot: AirframeState,
    /// Specific force at the CG in body axes `(ax, ay, az)`, m/s² (an accelerometer's reading:
    /// `az ≈ −g` in level flight).
    pub accel_mps2: [f64; 3],
    /// Thrust, N.
    pub thrust_n: f64,
    /// Dynamic pressure `½ρV²`, Pa.
    pub qbar_pa: f64,
    /// Density, kg/m³.
    pub rho_kgpm3: f64,
    /// Mach number (the speed of sound of [`ModelFileAircraft::air`]).
    pub mach: f64,
}

impl ModelFileAircraft {
    /// The module doc's equations at `x` (SI) with controls `u`: the state derivative and the
    /// record's channels.
    ///
    /// # Errors
    /// A state or control that is not finite, `vt ≤ 0`, |θ| or |β| at 90°, an altitude outside
    /// the atmosphere, or a flight-model evaluation error; each naming the field.
    pub fn outputs(
        &self,
        t_s: f64,
        x: &AirframeState,
        u: &ControlVector,
    ) -> Result<AirframeOutputs, ModelError> {
        check_point(x, u)?;
        let inputs = self.inputs(t_s, x, u)?;
        use fm::state as s;
        let mut x8 = [0.0; fm::N_STATES];
        let pairs = [
            (s::V, rb::VT),
            (s::ALPHA, rb::ALPHA),
            (s::BETA, rb::BETA),
            (s::P, rb::P),
            (s::Q, rb::Q),
            (s::R, rb::R),
            (s::PHI, rb::PHI),
            (s::THETA, rb::THETA),
        ];
        for (i8, i12) in pairs {
            x8[i8] = x[i12];
        }
        let d = self.model.eval(&self.theta, &inputs, &x8, &[0.0; 8], &[0.0; 8], None);
        let d = d.map_err(model_error)?;
        let mut xd = AirframeState::zeros();
        for (i8, i12) in pairs {
            xd[i12] = d.xdot[i8];
        }
        navigation(x, &mut xd);
        let (rho, vt) = (inputs.rho_kgpm3, x[rb::VT]);
        Ok(AirframeOutputs {
            xdot: xd,
            accel_mps2: d.accel,
            thrust_n: inputs.thrust_n,
            qbar_pa: 0.5 * rho * vt * vt,
            rho_kgpm3: rho,
            mach: vt / inputs.a_mps,
        })
    }
}

/// The heading and navigation rows of `xd` at `x` (module doc).
fn navigation(x: &AirframeState, xd: &mut AirframeState) {
    let (sphi, cphi) = x[rb::PHI].sin_cos();
    xd[rb::PSI] = (x[rb::Q] * sphi + x[rb::R] * cphi) / x[rb::THETA].cos();
    let v_body =
        rb::VelocityAngles { vt_fps: x[rb::VT], alpha_rad: x[rb::ALPHA], beta_rad: x[rb::BETA] }
            .to_body();
    let ned: Vector3<f64> =
        body_from_ned(x[rb::PHI], x[rb::THETA], x[rb::PSI]).transpose() * v_body;
    xd[rb::NORTH] = ned[0];
    xd[rb::EAST] = ned[1];
    xd[rb::ALT] = -ned[2];
}

impl Dynamics<N_STATES> for ModelFileAircraft {
    type Input = ControlVector;

    /// The module doc's equations at `x` (SI) with controls `u` ([`ModelFileAircraft::outputs`]).
    fn derivatives(
        &self,
        t_s: f64,
        x: &AirframeState,
        u: &ControlVector,
    ) -> Result<AirframeState, ModelError> {
        Ok(self.outputs(t_s, x, u)?.xdot)
    }
}

impl Aircraft<N_STATES> for ModelFileAircraft {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn mass(&self) -> AircraftMass {
        self.airframe.mass
    }

    fn geometry(&self) -> ReferenceGeometry {
        self.airframe.geometry
    }

    fn engine_command(&self) -> &'static str {
        self.airframe.propulsion.command()
    }

    fn length_unit_m(&self) -> f64 {
        1.0
    }

    fn state_names(&self) -> &'static [&'static str; N_STATES] {
        &STATE_NAMES
    }

    fn input(&self, u: &ControlVector) -> ControlVector {
        *u
    }

    fn trim_level(&self, vt_mps: f64, alt_m: f64) -> Result<AircraftTrim<N_STATES>, ModelError> {
        trim_wings_level(self, vt_mps, alt_m)
    }
}

/// The model-file aircraft flies its own structure and values, records its command as the
/// propulsion's column ([`Propulsion`]) and drives its surfaces through the mapping's
/// actuators.
impl FlyableAircraft<N_STATES> for ModelFileAircraft {
    fn rigid_body_si(&self, x: &AirframeState) -> AirframeState {
        *x
    }

    fn outputs(
        &self,
        t_s: f64,
        x: &AirframeState,
        u: &ControlVector,
    ) -> Result<AirframeOutputs, ModelError> {
        ModelFileAircraft::outputs(self, t_s, x, u)
    }

    fn constants(&self) -> aeroident_estimators::AircraftConstants {
        ModelFileAircraft::constants(self)
    }

    fn flown_structure(&self) -> ModelStructure {
        self.structure()
    }

    fn flown_values(&self, _trim: &AircraftTrim<N_STATES>) -> Result<Vec<f64>, ModelError> {
        Ok(self.theta.clone())
    }

    fn engine_column(&self) -> &'static str {
        match &self.airframe.propulsion {
            Propulsion::Commanded => "thrust_cmd_n",
            Propulsion::Law(law) => match law.input() {
                LawInput::Throttle => "throttle",
                LawInput::PropSpeed => "prop_speed_cmd_rad_s",
            },
        }
    }

    fn actuators(&self) -> [Option<aeroident_io::mapping::Actuator>; 3] {
        self.airframe.actuators
    }

    fn density_kgpm3(&self, alt_m: f64) -> Result<f64, ModelError> {
        Ok(self.air(alt_m)?.0)
    }
}
