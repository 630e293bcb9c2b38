//! Small causal filters for fixed-rate use (sensor lag, smoothing, band-limiting noise), each
//! discretised EXACTLY for a zero-order-held input (ZOH equivalent), so they are stable and have
//! the continuous filter's step response at the sample instants for any sample time.
//! Allocation-free per sample.

use nalgebra::{Matrix2, Vector2};

use crate::error::{SignalError, finite, positive};

/// First-order low-pass `H(s) = 1 / (τ s + 1)`, ZOH-exact:
/// `y_{k+1} = y_k + (1 − e^{−Ts/τ})·(u_k − y_k)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstOrderLowPass {
    alpha: f64,
    y: f64,
}

impl FirstOrderLowPass {
    /// Filter with time constant `tau_s` (s, > 0) for sample time `dt_s` (s, > 0), initial
    /// output `y0`.
    ///
    /// # Errors
    /// [`SignalError::InvalidParameter`] naming `tau_s`, `dt_s` or `y0`.
    pub fn new(tau_s: f64, dt_s: f64, y0: f64) -> Result<Self, SignalError> {
        let tau = positive("tau_s", tau_s)?;
        let dt = positive("dt_s", dt_s)?;
        Ok(Self { alpha: -(-dt / tau).exp_m1(), y: finite("y0", y0)? })
    }

    /// Feeds input `u` (held over the coming sample) and returns the output at the NEXT sample
    /// instant.
    pub fn step(&mut self, u: f64) -> f64 {
        self.y += self.alpha * (u - self.y);
        self.y
    }

    /// Current output.
    pub fn output(&self) -> f64 {
        self.y
    }

    /// Sets the output (state) to `y`, e.g. to start in steady state.
    pub fn reset(&mut self, y: f64) {
        self.y = y;
    }
}

/// Second-order low-pass `H(s) = ω_n² / (s² + 2ζω_n s + ω_n²)` (unit DC gain), ZOH-exact via
/// the matrix exponential of its state-space form (states: y, ẏ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SecondOrderLowPass {
    phi: Matrix2<f64>,
    gamma: Vector2<f64>,
    x: Vector2<f64>,
}

impl SecondOrderLowPass {
    /// Filter with natural frequency `omega_n_rad_s` (rad/s, > 0), damping ratio `zeta` (> 0)
    /// and sample time `dt_s` (s, > 0), starting at rest at output `y0`.
    ///
    /// # Errors
    /// [`SignalError::InvalidParameter`] naming the bad argument.
    pub fn new(omega_n_rad_s: f64, zeta: f64, dt_s: f64, y0: f64) -> Result<Self, SignalError> {
        let wn = positive("omega_n_rad_s", omega_n_rad_s)?;
        let z = positive("zeta", zeta)?;
        let dt = positive("dt_s", dt_s)?;
        let y0 = finite("y0", y0)?;
        // ẋ = A x + B u, A = [[0, 1], [−ωn², −2ζωn]], B = [0, ωn²]. ZOH: Φ = e^{A dt},
        // Γ = ∫₀^dt e^{Aτ} dτ B, from the exponential of [[A, B], [0, 0]]·dt.
        let mut m = nalgebra::Matrix3::<f64>::zeros();
        m[(0, 1)] = dt;
        m[(1, 0)] = -wn * wn * dt;
        m[(1, 1)] = -2.0 * z * wn * dt;
        m[(1, 2)] = wn * wn * dt;
        let e = m.exp();
        Ok(Self {
            phi: Matrix2::new(e[(0, 0)], e[(0, 1)], e[(1, 0)], e[(1, 1)]),
            gamma: Vector2::new(e[(0, 2)], e[(1, 2)]),
            x: Vector2::new(y0, 0.0),
        })
    }

    /// Feeds input `u` (held over the coming sample) and returns the output at the next sample.
    pub fn step(&mut self, u: f64) -> f64 {
        self.x = self.phi * self.x + self.gamma * u;
        self.x[0]
    }

    /// Current output.
    pub fn output(&self) -> f64 {
        self.x[0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_first_order_step_response() {
        // y(t) = 1 - e^{-t/tau} at the sample instants, exactly (ZOH of a step is the step).
        let (tau, dt) = (0.3, 0.01);
        let mut f = FirstOrderLowPass::new(tau, dt, 0.0).unwrap();
        for k in 1..=200 {
            let y = f.step(1.0);
            let t = k as f64 * dt;
            assert!((y - (1.0 - (-t / tau).exp())).abs() < 1e-13, "k = {k}");
        }
        assert!(FirstOrderLowPass::new(0.0, dt, 0.0).is_err());
    }

    #[test]
    fn analytic_second_order_step_response() {
        // Underdamped step response:
        // y = 1 - e^{-z wn t} (cos(wd t) + z/sqrt(1-z^2) sin(wd t)), wd = wn sqrt(1 - z^2).
        let (wn, z, dt) = (8.0, 0.3, 0.005);
        let wd = wn * (1.0f64 - z * z).sqrt();
        let mut f = SecondOrderLowPass::new(wn, z, dt, 0.0).unwrap();
        for k in 1..=400 {
            let y = f.step(1.0);
            let t = k as f64 * dt;
            let e = 1.0
                - (-z * wn * t).exp()
                    * ((wd * t).cos() + z / (1.0 - z * z).sqrt() * (wd * t).sin());
            assert!((y - e).abs() < 1e-12, "k = {k}: {y} vs {e}");
        }
        assert!(SecondOrderLowPass::new(8.0, -0.1, dt, 0.0).is_err());
    }
}
