//! # aeroident-models
//!
//! Continuous-time simulation models `ẋ = f(t, x, u)` and the tools that act on them: a fixed-step
//! RK4 integrator, trim and linearization. A model has one job: give state derivatives.
//!
//! Sources: Stevens, Lewis & Johnson, *Aircraft Control and Simulation*, 3rd ed., Wiley 2015
//! (SLJ) §3.5–3.8 for the F-16; Gurbacki 2010 thesis §2.1 for the proof-of-concept systems.

use nalgebra::SVector;

/// Rate- and position-limited first-order surface actuators; the F-16 with actuators (16 states).
pub mod actuator;
/// One abstract aircraft (mass, geometry, controls, wings-level trim) over the shared rigid
/// body; the F-16 is one implementation.
pub mod aircraft;
/// The textbook air-data computer of the F-16 model (SLJ §3.5, ADC).
pub mod atmosphere;
/// The Stevens–Lewis nonlinear F-16 (SLJ §3.5, App. A; NASA TP-1538).
pub mod f16;
pub mod integrate;
/// Central-difference linearization, eigenvalues and F-16 mode identification (SLJ §3.7–3.8).
pub mod linearize;
/// Flat-earth 6-DOF rigid-body equations shared by the aircraft models (SLJ §2.5, §3.5): one
/// rotation matrix, one wind convention.
pub mod rigid_body;
/// Trim of the F-16: wings-level, coordinated turn, pull-up (SLJ §3.6; thesis index 2.31).
pub mod trim;

/// Errors a model evaluation can return.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A state or input was not finite, or left the model's domain (e.g. vt ≤ 0).
    #[error("invalid `{field}` = {}: {reason}", aeroident_physics::text::ExactOrShort(*.value))]
    InvalidValue {
        /// Name of the state or input.
        field: &'static str,
        /// The value received.
        value: f64,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// An iterative procedure (trim, implicit solve) did not converge.
    #[error("{what} did not converge: {detail}")]
    NoConvergence {
        /// What did not converge.
        what: &'static str,
        /// Residual or other detail.
        detail: String,
    },
}

/// An inertia the rigid-body kernel refuses is an invalid value of the model's input.
impl From<rigid_body::InertiaError> for ModelError {
    fn from(e: rigid_body::InertiaError) -> Self {
        ModelError::InvalidValue { field: e.field, value: e.value, reason: e.reason }
    }
}

/// A continuous-time model `ẋ = f(t, x, u)` with `N` states.
///
/// One job: give the state derivative. No integration and no I/O.
pub trait Dynamics<const N: usize> {
    /// The input held over an integration step (zero-order hold), e.g. control deflections.
    type Input;
    /// The state derivative at time `t_s` (s) for state `x` and input `u`.
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] when `x` or `u` is outside the model's domain.
    fn derivatives(
        &self,
        t_s: f64,
        x: &SVector<f64, N>,
        u: &Self::Input,
    ) -> Result<SVector<f64, N>, ModelError>;
}
/// Models whose parameters can be replaced (truth and estimated model share equations).
pub mod parametric;
/// The thesis's four proof-of-concept systems (2.1)–(2.4).
pub mod small;
