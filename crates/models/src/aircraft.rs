//! One abstract aircraft, several implementations: what trim, linearization and mode analysis
//! need from an aircraft, so that the same tools fly the Stevens–Lewis F-16 and an aircraft
//! built from identified derivatives (the model-file aircraft of the pipelines crate).
//!
//! The design follows the layering of flight-mechanics simulators (e.g. FlightMechanicsSimulator.jl:
//! an aircraft is mass and inertia, reference geometry, aerodynamics and an engine on top of a
//! shared rigid body; SLJ 3rd ed. §2.5, §3.5). Here an aircraft is a [`Dynamics`](crate::Dynamics) model whose
//! first 12 states follow the rigid-body layout of [`crate::rigid_body::STATE_NAMES`]
//! (`vt, α, β, φ, θ, ψ, p, q, r, north, east, alt`; further states such as the F-16's engine
//! power follow), with four controls ([`CONTROL_NAMES`](crate::aircraft::CONTROL_NAMES): engine command, elevator, aileron,
//! rudder, rad), and the [`Aircraft`](crate::aircraft::Aircraft) trait adds its mass, geometry and a wings-level trim.
//!
//! # Units
//! Everything this module's API takes and returns is SI and radians. The state vectors are the
//! aircraft's own: the F-16 keeps its English units (ft, ft/s: [`Aircraft::length_unit_m`](crate::aircraft::Aircraft::length_unit_m)
//! converts), a model-file aircraft is SI. Eigenvalues (1/s) do not depend on the unit.

use crate::f16::{self, F16, F16Controls};
use crate::linearize::rigid_body_modes;
use crate::linearize::{DEFAULT_REL_STEP, Linearization, Mode, eigenvalues, linearize};
use crate::trim::{TrimCondition, trim};
use crate::{Dynamics, ModelError};
use aeroident_physics::units::{FT_PER_M, KG_PER_SLUG, KGM2_PER_SLUGFT2, M_PER_FT, M2_PER_FT2};
use nalgebra::{Complex, SVector};

/// Number of controls of every aircraft.
pub const N_CONTROLS: usize = 4;

/// The controls, in order: the engine command (its meaning is the aircraft's,
/// [`Aircraft::engine_command`]), elevator, aileron and rudder deflections, rad (SLJ signs:
/// positive deflection gives a negative moment).
pub const CONTROL_NAMES: [&str; N_CONTROLS] =
    ["engine", "elevator_rad", "aileron_rad", "rudder_rad"];

/// A control vector in the order of [`CONTROL_NAMES`].
pub type ControlVector = SVector<f64, N_CONTROLS>;

/// Mass and inertia, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AircraftMass {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Roll inertia `Jx`, kg·m².
    pub jx_kgm2: f64,
    /// Pitch inertia `Jy`, kg·m².
    pub jy_kgm2: f64,
    /// Yaw inertia `Jz`, kg·m².
    pub jz_kgm2: f64,
    /// Product of inertia `Jxz`, kg·m², SLJ sign (tensor `[[Jx,0,−Jxz],[0,Jy,0],[−Jxz,0,Jz]]`).
    pub jxz_kgm2: f64,
}

/// Reference geometry of the aerodynamic coefficients, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceGeometry {
    /// Wing reference area S, m².
    pub wing_area_m2: f64,
    /// Span b, m.
    pub span_m: f64,
    /// Mean aerodynamic chord c̄, m.
    pub chord_m: f64,
}

/// A trimmed flight condition of an `N`-state aircraft.
#[derive(Debug, Clone, PartialEq)]
pub struct AircraftTrim<const N: usize> {
    /// Trimmed state, in the aircraft's own units (north = east = ψ = 0).
    pub state: SVector<f64, N>,
    /// Trimmed controls ([`CONTROL_NAMES`]).
    pub controls: ControlVector,
    /// Largest absolute `[V̇, α̇, β̇, ṗ, q̇, ṙ]` at the solution, in the state's units per second.
    pub max_abs_residual: f64,
}

/// An aircraft: a [`Dynamics`] model with the rigid-body state layout (module doc), its mass,
/// geometry and engine command, and a wings-level trim.
pub trait Aircraft<const N: usize>: Dynamics<N> {
    /// A short name for reports (`"F-16 (Stevens & Lewis), xcg 0.35"`, a model file's name).
    fn name(&self) -> String;
    /// Mass and inertia, SI.
    fn mass(&self) -> AircraftMass;
    /// Reference geometry, SI.
    fn geometry(&self) -> ReferenceGeometry;
    /// What control 0 is, with its unit (`"throttle (0-1)"`, `"thrust_n"`, …).
    fn engine_command(&self) -> &'static str;
    /// Metres per length unit of the states `vt` (per second), `north`, `east`, `alt`.
    fn length_unit_m(&self) -> f64;
    /// The states' names with their units, in state order (`vt_fps` or `vt_mps`, `alpha_rad`, …).
    fn state_names(&self) -> &'static [&'static str; N];
    /// The model's input for the control vector `u` (still air).
    fn input(&self, u: &ControlVector) -> Self::Input;
    /// Steady wings-level, level flight at true airspeed `vt_mps` (m/s) and altitude `alt_m` (m).
    ///
    /// # Errors
    /// [`ModelError`] when the condition is invalid or the trim does not converge.
    fn trim_level(&self, vt_mps: f64, alt_m: f64) -> Result<AircraftTrim<N>, ModelError>;
}

/// A linear model about a wings-level trim with its eigenvalues and modes.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelLinearization<const N: usize> {
    /// The trim it is taken about.
    pub trim: AircraftTrim<N>,
    /// `A` (N × N) and `B` (N × 4) in the aircraft's state units, controls [`CONTROL_NAMES`].
    pub linear: Linearization<N, N_CONTROLS>,
    /// Eigenvalues of `A`, 1/s, sorted by real then imaginary part.
    pub eigenvalues: Vec<Complex<f64>>,
    /// The modes of the longitudinal and lateral blocks ([`rigid_body_modes`]).
    pub modes: Vec<Mode>,
}

/// Trims `aircraft` wings-level at `vt_mps` (m/s), `alt_m` (m), and linearizes it there by
/// central differences ([`linearize`], step [`DEFAULT_REL_STEP`]; SLJ §3.7–3.8).
///
/// # Errors
/// The trim's errors, or a model error at a perturbed point.
pub fn linearize_level<const N: usize, A: Aircraft<N>>(
    aircraft: &A,
    vt_mps: f64,
    alt_m: f64,
) -> Result<LevelLinearization<N>, ModelError> {
    let trim = aircraft.trim_level(vt_mps, alt_m)?;
    let linear = linearize(
        aircraft,
        0.0,
        &trim.state,
        &trim.controls,
        |u| aircraft.input(u),
        DEFAULT_REL_STEP,
    )?;
    let eigenvalues = eigenvalues(&linear.a);
    let modes = rigid_body_modes(&linear.a);
    Ok(LevelLinearization { trim, linear, eigenvalues, modes })
}

/// The F-16 as one [`Aircraft`]: its own equations, units (ft) and trim, unchanged.
impl Aircraft<{ f16::N_STATES }> for F16 {
    fn name(&self) -> String {
        format!("F-16 (Stevens & Lewis), xcg {}", self.xcg)
    }

    fn mass(&self) -> AircraftMass {
        let m = &self.data().mass;
        AircraftMass {
            mass_kg: m.mass_slug() * KG_PER_SLUG,
            jx_kgm2: m.ixx_slug_ft2 * KGM2_PER_SLUGFT2,
            jy_kgm2: m.iyy_slug_ft2 * KGM2_PER_SLUGFT2,
            jz_kgm2: m.izz_slug_ft2 * KGM2_PER_SLUGFT2,
            jxz_kgm2: m.ixz_slug_ft2 * KGM2_PER_SLUGFT2,
        }
    }

    fn geometry(&self) -> ReferenceGeometry {
        let g = &self.data().geometry;
        ReferenceGeometry {
            wing_area_m2: g.wing_area_ft2 * M2_PER_FT2,
            span_m: g.span_ft * M_PER_FT,
            chord_m: g.cbar_ft * M_PER_FT,
        }
    }

    fn engine_command(&self) -> &'static str {
        "throttle (0-1; engine power lag, SLJ §3.5)"
    }

    fn length_unit_m(&self) -> f64 {
        M_PER_FT
    }

    fn state_names(&self) -> &'static [&'static str; f16::N_STATES] {
        &f16::STATE_NAMES
    }

    fn input(&self, u: &ControlVector) -> F16Controls {
        F16Controls::new(u[0], u[1], u[2], u[3])
    }

    fn trim_level(
        &self,
        vt_mps: f64,
        alt_m: f64,
    ) -> Result<AircraftTrim<{ f16::N_STATES }>, ModelError> {
        let t = trim(self, &TrimCondition::level(alt_m * FT_PER_M, vt_mps * FT_PER_M))?;
        Ok(AircraftTrim {
            state: t.state,
            controls: t.controls.to_vector(),
            max_abs_residual: t.max_abs_residual(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linearize::{f16_modes, linearize_f16};

    /// Through the trait the F-16 gives the numbers of its own trim and linearization.
    #[test]
    fn f16_through_the_trait_matches_its_own_trim_and_linearization() {
        let f = F16::new(0.35).unwrap();
        let l = linearize_level(&f, 502.0 * M_PER_FT, 0.0).unwrap();
        let t = trim(&f, &TrimCondition::level(0.0, 502.0)).unwrap();
        // 502 ft/s through m/s and back differs in the last bit, so the trims agree to the
        // solver's tolerance; the linearization is compared at the trait's own trim.
        assert!((l.trim.state - t.state).amax() < 1e-6, "{}", (l.trim.state - t.state).amax());
        let own = linearize_f16(&f, &l.trim.state, &f.input(&l.trim.controls)).unwrap();
        assert!((l.linear.a - own.a).amax() < 1e-9 && (l.linear.b - own.b).amax() < 1e-9);
        assert_eq!(l.modes, f16_modes(&own.a));
        assert!((f.mass().mass_kg - 9295.44).abs() < 1.0, "{}", f.mass().mass_kg);
    }
}
