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

use super::{AirframeOutputs, AirframeState, STATE_NAMES};
use aeroident_estimators::AircraftConstants;
use aeroident_estimators::output_error::design::FlightCondition;
use aeroident_estimators::vocabulary::{ModelStructure, Term};
use aeroident_models::ModelError;
use aeroident_models::aircraft::{
    Aircraft, AircraftMass, AircraftTrim, ControlVector, ReferenceGeometry,
};
use aeroident_models::rigid_body as rb;
use aeroident_physics::isa;
use nalgebra::{SVector, Vector3};

/// Standard gravity, m/s² (the flight model's `g0`).
pub const G0_MPS2: f64 = 9.806_65;

/// An aircraft the experiments fly, record and identify (module doc). States are the
/// aircraft's own ([`Aircraft::state_names`]); everything this trait returns is SI.
pub trait FlyableAircraft<const N: usize>: Aircraft<N> + Sync {
    /// The rigid-body states of `x` in SI, in [`STATE_NAMES`] order.
    fn rigid_body_si(&self, x: &SVector<f64, N>) -> AirframeState;

    /// The state derivative in SI ([`STATE_NAMES`] order) and the record's channels at time
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
    /// ([`aeroident_physics::isa`]) unless the aircraft flies in another.
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] (`alt_m`) outside the atmosphere model.
    fn density_kgpm3(&self, alt_m: f64) -> Result<f64, ModelError> {
        Ok(isa_air(alt_m)?.0)
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
/// `x` and its derivative `xdot` ([`STATE_NAMES`] order).
pub fn specific_force(x: &AirframeState, xdot: &AirframeState) -> [f64; 3] {
    let (v, alpha, beta) = (x[rb::VT], x[rb::ALPHA], x[rb::BETA]);
    let (sa, ca) = alpha.sin_cos();
    let (sb, cb) = beta.sin_cos();
    let (vd, ad, bd) = (xdot[rb::VT], xdot[rb::ALPHA], xdot[rb::BETA]);
    let vel = Vector3::new(ca * cb, sb, sa * cb) * v;
    let vel_dot = Vector3::new(ca * cb, sb, sa * cb) * vd
        + Vector3::new(-sa * cb, 0.0, ca * cb) * (v * ad)
        + Vector3::new(-ca * sb, cb, -sa * sb) * (v * bd);
    let omega = Vector3::new(x[rb::P], x[rb::Q], x[rb::R]);
    let (sphi, cphi) = x[rb::PHI].sin_cos();
    let (sth, cth) = x[rb::THETA].sin_cos();
    let g = Vector3::new(-sth, sphi * cth, cphi * cth) * G0_MPS2;
    let f = vel_dot + omega.cross(&vel) - g;
    [f[0], f[1], f[2]]
}

/// The record's channels of an aircraft whose equations give the SI state derivative `xdot`
/// at the SI state `x`, flying in the standard atmosphere with thrust `thrust_n`: the
/// specific force by [`specific_force`], density and speed of sound of the 1976 standard
/// atmosphere ([`aeroident_physics::isa`]) at the altitude.
///
/// # Errors
/// [`ModelError::InvalidValue`] (`alt_m`) outside the standard atmosphere.
pub fn isa_outputs(
    x: &AirframeState,
    xdot: AirframeState,
    thrust_n: f64,
) -> Result<AirframeOutputs, ModelError> {
    let (rho, a) = isa_air(x[rb::ALT])?;
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

/// Density (kg/m³) and speed of sound (m/s) of the 1976 standard atmosphere at `alt_m` (m).
///
/// # Errors
/// [`ModelError::InvalidValue`] (`alt_m`) outside the standard atmosphere.
fn isa_air(alt_m: f64) -> Result<(f64, f64), ModelError> {
    let outside = ModelError::InvalidValue {
        field: STATE_NAMES[rb::ALT],
        value: alt_m,
        reason: "outside the standard atmosphere",
    };
    let t = isa::temperature_k(alt_m).ok_or(outside.clone())?;
    let p = isa::pressure_pa(alt_m).ok_or(outside)?;
    Ok((isa::density_kgpm3(p, t), isa::speed_of_sound_mps(t)))
}
