//! Control-surface actuators: first-order lags with rate and position limits, and the F-16
//! airframe with its three surface actuators as one 16-state model.
//!
//! ```text
//! δ̇ = clamp( ω·(clamp(δ_cmd, −δ_max, δ_max) − δ), −δ̇_max, δ̇_max )
//! ```
//! A position that starts inside the limits stays inside (the lag drives it toward a clamped
//! command). Throttle has no actuator here: it acts through the engine power lag of the model.
//!
//! Values ([`crate::actuator::SurfaceActuators::f16`]): lag 20.2 rad/s (time constant 0.0495 s) on all three
//! surfaces; elevator ±25°, 60°/s; aileron ±21.5°, 80°/s; rudder ±30°, 120°/s. These are the
//! F-16 actuator values of NASA TP-1538 (Nguyen et al. 1979) as tabulated by L. Sonneveldt,
//! *Nonlinear F-16 Model Description*, TU Delft, 2010, and used by SLJ's later chapters; the
//! position limits equal the `[ranges]` of the textbook data. The 13-state textbook model itself
//! has no actuators (data README §8).

use crate::f16::{F16, F16Controls, N_STATES};
use crate::{Dynamics, ModelError};
use nalgebra::SVector;

/// One first-order, rate- and position-limited actuator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstOrderActuator {
    /// Lag bandwidth ω (1/time constant), rad/s.
    pub bandwidth_rad_s: f64,
    /// Rate limit, rad/s (> 0).
    pub rate_limit_rad_s: f64,
    /// Symmetric position limit, rad (> 0).
    pub position_limit_rad: f64,
}

impl FirstOrderActuator {
    /// Surface rate, rad/s, at position `position_rad` for command `command_rad`.
    #[inline]
    pub fn rate(&self, position_rad: f64, command_rad: f64) -> f64 {
        let target = command_rad.clamp(-self.position_limit_rad, self.position_limit_rad);
        (self.bandwidth_rad_s * (target - position_rad))
            .clamp(-self.rate_limit_rad_s, self.rate_limit_rad_s)
    }
}

/// Elevator, aileron and rudder actuators.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceActuators {
    /// Elevator.
    pub elevator: FirstOrderActuator,
    /// Aileron.
    pub aileron: FirstOrderActuator,
    /// Rudder.
    pub rudder: FirstOrderActuator,
}

impl SurfaceActuators {
    /// The F-16 values (module doc: NASA TP-1538 via Sonneveldt 2010).
    pub fn f16() -> Self {
        let a = |limit_deg: f64, rate_deg_s: f64| FirstOrderActuator {
            bandwidth_rad_s: 20.2,
            rate_limit_rad_s: rate_deg_s.to_radians(),
            position_limit_rad: limit_deg.to_radians(),
        };
        Self { elevator: a(25.0, 60.0), aileron: a(21.5, 80.0), rudder: a(30.0, 120.0) }
    }
}

/// Number of states of [`F16WithActuators`]: the 13 airframe states, then elevator, aileron and
/// rudder positions (rad) at indices 13, 14, 15.
pub const N_STATES_WITH_ACTUATORS: usize = N_STATES + 3;
/// Index of the elevator position state, rad.
pub const ELEVATOR_POS: usize = 13;
/// Index of the aileron position state, rad.
pub const AILERON_POS: usize = 14;
/// Index of the rudder position state, rad.
pub const RUDDER_POS: usize = 15;

/// The F-16 airframe driven through its surface actuators. Input: the pilot's **commands**
/// ([`F16Controls`]; throttle and wind pass straight through).
#[derive(Debug, Clone)]
pub struct F16WithActuators {
    /// The airframe.
    pub airframe: F16,
    /// The actuators.
    pub actuators: SurfaceActuators,
}

impl F16WithActuators {
    /// The surface deflections held in state `x` combined with the throttle and wind of `cmd`.
    pub fn surface_controls(
        x: &SVector<f64, N_STATES_WITH_ACTUATORS>,
        cmd: &F16Controls,
    ) -> F16Controls {
        F16Controls {
            elevator_rad: x[ELEVATOR_POS],
            aileron_rad: x[AILERON_POS],
            rudder_rad: x[RUDDER_POS],
            ..*cmd
        }
    }

    /// A 16-state vector from an airframe state and surface positions (e.g. a trim).
    pub fn state(
        x: &SVector<f64, N_STATES>,
        surfaces: &F16Controls,
    ) -> SVector<f64, N_STATES_WITH_ACTUATORS> {
        let mut s = SVector::<f64, N_STATES_WITH_ACTUATORS>::zeros();
        s.fixed_rows_mut::<N_STATES>(0).copy_from(x);
        s[ELEVATOR_POS] = surfaces.elevator_rad;
        s[AILERON_POS] = surfaces.aileron_rad;
        s[RUDDER_POS] = surfaces.rudder_rad;
        s
    }
}

impl Dynamics<N_STATES_WITH_ACTUATORS> for F16WithActuators {
    type Input = F16Controls;
    /// Airframe derivatives at the actual surface positions, then the actuator rates.
    fn derivatives(
        &self,
        t_s: f64,
        x: &SVector<f64, N_STATES_WITH_ACTUATORS>,
        cmd: &F16Controls,
    ) -> Result<SVector<f64, N_STATES_WITH_ACTUATORS>, ModelError> {
        let airframe_x: SVector<f64, N_STATES> = x.fixed_rows::<N_STATES>(0).into_owned();
        let xd = self.airframe.derivatives(t_s, &airframe_x, &Self::surface_controls(x, cmd))?;
        let mut out = SVector::<f64, N_STATES_WITH_ACTUATORS>::zeros();
        out.fixed_rows_mut::<N_STATES>(0).copy_from(&xd);
        out[ELEVATOR_POS] = self.actuators.elevator.rate(x[ELEVATOR_POS], cmd.elevator_rad);
        out[AILERON_POS] = self.actuators.aileron.rate(x[AILERON_POS], cmd.aileron_rad);
        out[RUDDER_POS] = self.actuators.rudder.rate(x[RUDDER_POS], cmd.rudder_rad);
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_small_step_is_a_first_order_lag() {
        // Small step (below the rate limit): δ(t) = c (1 − e^{−ωt}); rate at t = 0 is ω c.
        let a = SurfaceActuators::f16().elevator;
        let c = 0.01;
        assert!((a.rate(0.0, c) - 20.2 * c).abs() < 1e-15);
        // Integrate with small steps and compare at t = 0.1 s.
        let (mut d, dt) = (0.0, 1e-5);
        for _ in 0..10_000 {
            d += a.rate(d, c) * dt;
        }
        let exact = c * (1.0 - (-20.2f64 * 0.1).exp());
        assert!((d - exact).abs() < 1e-6, "{d} vs {exact}");
    }

    #[test]
    fn analytic_large_step_is_rate_then_position_limited() {
        let a = SurfaceActuators::f16().elevator;
        // 40° command: rate-limited at 60°/s, target clamped at 25°.
        assert!((a.rate(0.0, 40f64.to_radians()) - 60f64.to_radians()).abs() < 1e-15);
        let (mut d, dt) = (0.0, 1e-4);
        for _ in 0..20_000 {
            d += a.rate(d, 40f64.to_radians()) * dt;
        }
        assert!((d.to_degrees() - 25.0).abs() < 1e-6 && d.to_degrees() <= 25.0);
        // Ramp phase: after 0.1 s at most 6°.
        let mut d = 0.0;
        for _ in 0..1000 {
            d += a.rate(d, 40f64.to_radians()) * dt;
        }
        assert!((d.to_degrees() - 6.0).abs() < 1e-9);
    }
}
