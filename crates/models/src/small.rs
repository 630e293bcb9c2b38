//! The thesis's four proof-of-concept systems (Gurbacki 2010 §2.1, (2.1)–(2.4); signs as
//! reconstructed in `spec/thesis-method.md` §2). Time in s; states and input dimensionless.
//!
//! Each implements [`Dynamics`] (the truth model) and [`Parameterized`](crate::parametric::Parameterized) (so the same equations
//! serve as the estimated model with θ̂). The input is the scalar command `u` held over a step.

use crate::parametric::Parameterized;
use crate::{Dynamics, ModelError};
use nalgebra::SVector;

fn check_finite<const N: usize>(x: &SVector<f64, N>, u: f64) -> Result<(), ModelError> {
    if let Some(v) = x.iter().find(|v| !v.is_finite()) {
        return Err(ModelError::InvalidValue { field: "state", value: *v, reason: "not finite" });
    }
    if !u.is_finite() {
        return Err(ModelError::InvalidValue { field: "u", value: u, reason: "not finite" });
    }
    Ok(())
}

/// First-order linear system (2.1): `ẋ = −a x + u`. State `[x]`, parameter `[a]` (1/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstOrder {
    /// Parameter a, 1/s (a > 0 stable).
    pub a: f64,
}

impl Dynamics<1> for FirstOrder {
    type Input = f64;
    /// # Errors
    /// [`ModelError::InvalidValue`] for a non-finite state or input.
    fn derivatives(
        &self,
        _t_s: f64,
        x: &SVector<f64, 1>,
        u: &f64,
    ) -> Result<SVector<f64, 1>, ModelError> {
        check_finite(x, *u)?;
        Ok(SVector::<f64, 1>::new(-self.a * x[0] + u))
    }
}

impl Parameterized<1> for FirstOrder {
    fn param_names(&self) -> [&'static str; 1] {
        ["a"]
    }
    fn params(&self) -> SVector<f64, 1> {
        SVector::<f64, 1>::new(self.a)
    }
    fn with_params(&self, theta: &SVector<f64, 1>) -> Self {
        Self { a: theta[0] }
    }
}

/// First-order nonlinear system (2.2):
/// `ẋ = −a sin(y) x + B u`, `ẏ = −C y x + sin(ω t)`. State `[x, y]`, parameter `[a]`.
/// Thesis constants (§4.1.2): C = 4, B = 1.4, ω = 0.7 rad/s ([`FirstOrderNonlinear::thesis`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstOrderNonlinear {
    /// Parameter a.
    pub a: f64,
    /// Input gain B.
    pub B: f64,
    /// Coupling C.
    pub C: f64,
    /// Forcing frequency ω, rad/s.
    pub omega_rad_s: f64,
}

impl FirstOrderNonlinear {
    /// The thesis's constants (C = 4, B = 1.4, ω = 0.7 rad/s) with parameter `a`.
    pub fn thesis(a: f64) -> Self {
        Self { a, B: 1.4, C: 4.0, omega_rad_s: 0.7 }
    }
}

impl Dynamics<2> for FirstOrderNonlinear {
    type Input = f64;
    /// # Errors
    /// [`ModelError::InvalidValue`] for a non-finite state or input.
    fn derivatives(
        &self,
        t_s: f64,
        z: &SVector<f64, 2>,
        u: &f64,
    ) -> Result<SVector<f64, 2>, ModelError> {
        check_finite(z, *u)?;
        let (x, y) = (z[0], z[1]);
        Ok(SVector::<f64, 2>::new(
            -self.a * y.sin() * x + self.B * u,
            -self.C * y * x + (self.omega_rad_s * t_s).sin(),
        ))
    }
}

impl Parameterized<1> for FirstOrderNonlinear {
    fn param_names(&self) -> [&'static str; 1] {
        ["a"]
    }
    fn params(&self) -> SVector<f64, 1> {
        SVector::<f64, 1>::new(self.a)
    }
    fn with_params(&self, theta: &SVector<f64, 1>) -> Self {
        Self { a: theta[0], ..*self }
    }
}

/// Second-order linear system (2.3): `ẍ = −a₂ ẋ − a₁ x + u`. State `[x, ẋ]`, parameters
/// `[a1, a2]` (1/s², 1/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SecondOrder {
    /// Stiffness a₁, 1/s².
    pub a1: f64,
    /// Damping a₂, 1/s.
    pub a2: f64,
}

impl Dynamics<2> for SecondOrder {
    type Input = f64;
    /// # Errors
    /// [`ModelError::InvalidValue`] for a non-finite state or input.
    fn derivatives(
        &self,
        _t_s: f64,
        z: &SVector<f64, 2>,
        u: &f64,
    ) -> Result<SVector<f64, 2>, ModelError> {
        check_finite(z, *u)?;
        Ok(SVector::<f64, 2>::new(z[1], -self.a2 * z[1] - self.a1 * z[0] + u))
    }
}

impl Parameterized<2> for SecondOrder {
    fn param_names(&self) -> [&'static str; 2] {
        ["a1", "a2"]
    }
    fn params(&self) -> SVector<f64, 2> {
        SVector::<f64, 2>::new(self.a1, self.a2)
    }
    fn with_params(&self, theta: &SVector<f64, 2>) -> Self {
        Self { a1: theta[0], a2: theta[1] }
    }
}

/// Second-order nonlinear system (2.4): `ẍ = −a₂ ẋ − a₁ x² + u`. State `[x, ẋ]`, parameters
/// `[a1, a2]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SecondOrderNonlinear {
    /// Coefficient a₁ of x².
    pub a1: f64,
    /// Damping a₂, 1/s.
    pub a2: f64,
}

impl Dynamics<2> for SecondOrderNonlinear {
    type Input = f64;
    /// # Errors
    /// [`ModelError::InvalidValue`] for a non-finite state or input.
    fn derivatives(
        &self,
        _t_s: f64,
        z: &SVector<f64, 2>,
        u: &f64,
    ) -> Result<SVector<f64, 2>, ModelError> {
        check_finite(z, *u)?;
        Ok(SVector::<f64, 2>::new(z[1], -self.a2 * z[1] - self.a1 * z[0] * z[0] + u))
    }
}

impl Parameterized<2> for SecondOrderNonlinear {
    fn param_names(&self) -> [&'static str; 2] {
        ["a1", "a2"]
    }
    fn params(&self) -> SVector<f64, 2> {
        SVector::<f64, 2>::new(self.a1, self.a2)
    }
    fn with_params(&self, theta: &SVector<f64, 2>) -> Self {
        Self { a1: theta[0], a2: theta[1] }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::rk4_step;

    /// Analytic step response of (2.1): x(t) = (u/a)(1 − e^{−a t}).
    #[test]
    fn analytic_first_order_step_response() {
        let m = FirstOrder { a: 3.0 };
        let dt = 1e-3;
        let mut x = SVector::<f64, 1>::zeros();
        for k in 0..1000 {
            x = rk4_step(&m, k as f64 * dt, &x, &2.0, dt).unwrap();
        }
        let exact = 2.0 / 3.0 * (1.0 - (-3.0f64).exp());
        assert!((x[0] - exact).abs() < 1e-12);
    }

    /// Analytic step response of (2.3) with a₁ = 8, a₂ = 6 (roots −2, −4):
    /// x(t) = u/8 · (1 − 2e^{−2t} + e^{−4t}).
    #[test]
    fn analytic_second_order_step_response() {
        let m = SecondOrder { a1: 8.0, a2: 6.0 };
        let dt = 1e-3;
        let mut z = SVector::<f64, 2>::zeros();
        for k in 0..1500 {
            z = rk4_step(&m, k as f64 * dt, &z, &4.0, dt).unwrap();
        }
        let t: f64 = 1.5;
        let exact = 0.5 * (1.0 - 2.0 * (-2.0 * t).exp() + (-4.0 * t).exp());
        assert!((z[0] - exact).abs() < 1e-11, "{} vs {exact}", z[0]);
    }

    /// Hand-evaluated right-hand sides of (2.2) and (2.4).
    #[test]
    fn analytic_nonlinear_right_hand_sides() {
        let m = FirstOrderNonlinear::thesis(7.0);
        let d = m.derivatives(2.0, &SVector::<f64, 2>::new(0.5, 0.3), &3.0).unwrap();
        assert!((d[0] - (-7.0 * 0.3f64.sin() * 0.5 + 1.4 * 3.0)).abs() < 1e-15);
        assert!((d[1] - (-4.0 * 0.3 * 0.5 + 1.4f64.sin())).abs() < 1e-15);
        let m = SecondOrderNonlinear { a1: 12.0, a2: 8.0 };
        let d = m.derivatives(0.0, &SVector::<f64, 2>::new(0.5, -1.0), &5.0).unwrap();
        assert_eq!(d[0], -1.0);
        assert!((d[1] - (8.0 - 12.0 * 0.25 + 5.0)).abs() < 1e-15);
        assert!(m.derivatives(0.0, &SVector::<f64, 2>::new(f64::NAN, 0.0), &0.0).is_err());
    }

    #[test]
    fn with_params_round_trip() {
        let m = SecondOrder { a1: 1.0, a2: 2.0 };
        let n = m.with_params(&SVector::<f64, 2>::new(8.0, 6.0));
        assert_eq!(n.params(), SVector::<f64, 2>::new(8.0, 6.0));
        assert_eq!(n.param_names(), ["a1", "a2"]);
    }
}
