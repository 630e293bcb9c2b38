//! What the experiments need of an aircraft beyond trim and linearization
//! ([`aeroident_models::aircraft::Aircraft`]): its record's channels in SI, the constants a
//! replay of that record maps, and the derivatives it flies (the truth an identification is
//! scored against). `sim` ([`crate::sim::aircraft::run`]), `run` and `montecarlo`
//! ([`crate::montecarlo::aircraft::AircraftExperiment`]) and `design`
//! ([`crate::export::design::design_for_aircraft`]) take any [`FlyableAircraft`], so adding an
//! aircraft type is one `impl Aircraft` and one `impl FlyableAircraft` (docs/architecture.md,
//! "Add an aircraft").
//!
//! # Kinematics ([`specific_force`])
//! The accelerometer's specific force follows from the rigid-body states and their
//! derivatives alone, whatever produced them: with the body velocity
//! `v = V (cosα cosβ, sinβ, sinα cosβ)` (SLJ 3rd ed. eq. 2.3-6),
//! `f = v̇ + ω × v − g_b`, `g_b = g0 (−sinθ, sinφ cosθ, cosφ cosθ)` (SLJ eq. 2.5-1 divided by
//! the mass: `m (v̇ + ω × v) = F_aero + F_thrust + m g_b`).

use super::{AirframeOutputs, AirframeState, Atmosphere};
use aeroident_estimators::AircraftConstants;
use aeroident_estimators::output_error::design::FlightCondition;
use aeroident_estimators::vocabulary::{ModelStructure, Term};
use aeroident_models::ModelError;
use aeroident_models::aircraft::{
    Aircraft, AircraftMass, AircraftTrim, ControlVector, ReferenceGeometry,
};
use aeroident_models::rigid_body as rb;
use aeroident_physics::rigid_body::{self as kernel, SinCos};
use aeroident_physics::units::G0_MPS2;
use nalgebra::SVector;

/// An aircraft the experiments fly, record and identify (module doc). States are the
/// aircraft's own ([`Aircraft::state_names`]); everything this trait returns is SI.
pub trait FlyableAircraft<const N: usize>: Aircraft<N> + Sync {
    /// The rigid-body states of `x` in SI, in [`STATE_NAMES`](super::STATE_NAMES) order.
    fn rigid_body_si(&self, x: &SVector<f64, N>) -> AirframeState;

    /// The state derivative in SI ([`STATE_NAMES`](super::STATE_NAMES) order) and the record's channels at time
    /// `t_s`, state `x` and controls `u` (surfaces as flown).
    ///
    /// # Errors
    /// A point outside the model's domain, naming the field.
    fn outputs(
        &self,
        t_s: f64,
        x: &SVector<f64, N>,
        u: &ControlVector,
    ) -> Result<AirframeOutputs, ModelError>;

    /// Mass, inertia, geometry and thrust line as the estimators' flight model and a replay's
    /// mapping take them.
    fn constants(&self) -> AircraftConstants;

    /// The vocabulary's structure of the derivatives it flies.
    fn flown_structure(&self) -> ModelStructure;

    /// The values of [`Self::flown_structure`]'s parameters (structure order) about `trim`:
    /// the derivatives it flies there (a derivative model's own values at any trim, a
    /// nonlinear aircraft's local derivatives).
    ///
    /// # Errors
    /// A trim outside the model's domain, naming the field.
    fn flown_values(&self, trim: &AircraftTrim<N>) -> Result<Vec<f64>, ModelError>;

    /// The engine command's column in a record, with its unit (`thrust_cmd_n`, `throttle`,
    /// `prop_speed_cmd_rad_s`).
    fn engine_column(&self) -> &'static str {
        "thrust_cmd_n"
    }

    /// Air density at altitude `alt_m` (m), kg/m³: the 1976 standard atmosphere
    /// ([`Atmosphere::Isa`]) unless the aircraft flies in another.
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] (`alt_m`) outside the atmosphere model.
    fn density_kgpm3(&self, alt_m: f64) -> Result<f64, ModelError> {
        Ok(Atmosphere::Isa.air(alt_m)?.0)
    }

    /// The surfaces' actuators (elevator, aileron, rudder); `None`: the surface is its
    /// command.
    fn actuators(&self) -> [Option<aeroident_io::mapping::Actuator>; 3] {
        [None; 3]
    }

    /// The surfaces (`de`, `da`, `dr`) its derivatives do not name: held at 0.
    fn held_surfaces(&self) -> Vec<&'static str> {
        held_surfaces(&self.flown_structure())
    }

    /// The flight condition a design or a Cramér–Rao bound starts from, at the trim `state`
    /// (the aircraft's units) and `controls`: airspeed, α and θ of the state, density and
    /// thrust of [`Self::outputs`] there, the trim deflections.
    ///
    /// # Errors
    /// As [`Self::outputs`].
    fn flight_condition(
        &self,
        state: &SVector<f64, N>,
        controls: &ControlVector,
    ) -> Result<FlightCondition, ModelError> {
        let x = self.rigid_body_si(state);
        let o = self.outputs(0.0, state, controls)?;
        Ok(FlightCondition {
            vt_mps: x[rb::VT],
            alpha_rad: x[rb::ALPHA],
            theta_rad: x[rb::THETA],
            rho_kgpm3: o.rho_kgpm3,
            thrust_n: o.thrust_n,
            de_rad: controls[1],
            da_rad: controls[2],
            dr_rad: controls[3],
        })
    }
}

/// The constants of an airframe of `mass` and `geometry` whose thrust acts along a line
/// inclined `thrust_incidence_rad` (rad, nose-up) to body x with pitching-moment arm
/// `thrust_arm_m` (m), and whose `V/V0` terms, if any, are relative to `v0_mps` (m/s).
pub fn airframe_constants(
    mass: &AircraftMass,
    geometry: &ReferenceGeometry,
    (thrust_arm_m, thrust_incidence_rad): (f64, f64),
    v0_mps: Option<f64>,
) -> AircraftConstants {
    AircraftConstants {
        mass_kg: mass.mass_kg,
        S_m2: geometry.wing_area_m2,
        cbar_m: Some(geometry.chord_m),
        b_m: Some(geometry.span_m),
        Ixx_kgm2: Some(mass.jx_kgm2),
        Iyy_kgm2: Some(mass.jy_kgm2),
        Izz_kgm2: Some(mass.jz_kgm2),
        Ixz_kgm2: Some(mass.jxz_kgm2),
        thrust_arm_m,
        thrust_incidence_rad,
        v0_mps,
    }
}

/// The surfaces (`de`, `da`, `dr`) `structure` has no term of, alone or in a product.
pub fn held_surfaces(structure: &ModelStructure) -> Vec<&'static str> {
    let has = |t: Term| {
        let uses = |p: Term| p == t || p.factors().is_some_and(|(f, g)| f == t || g == t);
        structure.params().any(|p| uses(p.term))
    };
    [("de", Term::De), ("da", Term::Da), ("dr", Term::Dr)]
        .into_iter()
        .filter(|(_, t)| !has(*t))
        .map(|(n, _)| n)
        .collect()
}

/// The specific force at the CG in body axes, m/s² (module doc), from the SI rigid-body state
/// `x` and its derivative `xdot` ([`STATE_NAMES`](super::STATE_NAMES) order): the body acceleration of
/// `(V̇, α̇, β̇)` less the kernel's force equations without a specific force
/// ([`kernel::body_acceleration`]).
pub fn specific_force(x: &AirframeState, xdot: &AirframeState) -> [f64; 3] {
    let (v, alpha, beta) = (x[rb::VT], SinCos::of(x[rb::ALPHA]), SinCos::of(x[rb::BETA]));
    let (vd, ad, bd) = (xdot[rb::VT], xdot[rb::ALPHA], xdot[rb::BETA]);
    let (sa, ca, sb, cb) = (alpha.sin, alpha.cos, beta.sin, beta.cos);
    // d/dt of v·(cosα cosβ, sinβ, sinα cosβ) through V, α and β.
    let v_dot = [
        vd * ca * cb - v * ad * sa * cb - v * bd * ca * sb,
        vd * sb + v * bd * cb,
        vd * sa * cb + v * ad * ca * cb - v * bd * sa * sb,
    ];
    let gravity = kernel::gravity_body(G0_MPS2, SinCos::of(x[rb::PHI]), SinCos::of(x[rb::THETA]));
    let omega = [x[rb::P], x[rb::Q], x[rb::R]];
    let free =
        kernel::body_acceleration(kernel::body_velocity(v, alpha, beta), omega, gravity, [0.0; 3]);
    core::array::from_fn(|k| v_dot[k] - free[k])
}

/// The record's channels of an aircraft whose equations give the SI state derivative `xdot`
/// at the SI state `x`, flying in the standard atmosphere with thrust `thrust_n`: the
/// specific force by [`specific_force`], density and speed of sound of the 1976 standard
/// atmosphere at the altitude ([`Atmosphere::air`]).
///
/// # Errors
/// [`ModelError::InvalidValue`] (`alt_m`) outside the standard atmosphere.
pub fn isa_outputs(
    x: &AirframeState,
    xdot: AirframeState,
    thrust_n: f64,
) -> Result<AirframeOutputs, ModelError> {
    let (rho, a) = Atmosphere::Isa.air(x[rb::ALT])?;
    let vt = x[rb::VT];
    Ok(AirframeOutputs {
        xdot,
        accel_mps2: specific_force(x, &xdot),
        thrust_n,
        qbar_pa: 0.5 * rho * vt * vt,
        rho_kgpm3: rho,
        mach: vt / a,
    })
}
