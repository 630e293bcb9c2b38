//! Fixed-step integrators. The input is held constant over a step (zero-order hold).

use crate::{Dynamics, ModelError};
use nalgebra::SVector;

/// One classical fourth-order Runge–Kutta step of `dt_s` seconds from `(t_s, x)`, with the input
/// `u` held constant over the step. Local error O(dt⁵), global error O(dt⁴).
///
/// # Errors
/// Whatever the model's [`Dynamics::derivatives`] returns at any of the four stages.
pub fn rk4_step<const N: usize, D: Dynamics<N>>(
    model: &D,
    t_s: f64,
    x: &SVector<f64, N>,
    u: &D::Input,
    dt_s: f64,
) -> Result<SVector<f64, N>, ModelError> {
    let h = dt_s;
    let k1 = model.derivatives(t_s, x, u)?;
    let k2 = model.derivatives(t_s + 0.5 * h, &(x + k1 * (0.5 * h)), u)?;
    let k3 = model.derivatives(t_s + 0.5 * h, &(x + k2 * (0.5 * h)), u)?;
    let k4 = model.derivatives(t_s + h, &(x + k3 * h), u)?;
    Ok(x + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ẋ = −a x + b, closed form x(t) = b/a + (x0 − b/a) e^{−a t}.
    struct Decay {
        a: f64,
        b: f64,
    }
    impl Dynamics<1> for Decay {
        type Input = ();
        fn derivatives(
            &self,
            _t: f64,
            x: &SVector<f64, 1>,
            _u: &(),
        ) -> Result<SVector<f64, 1>, ModelError> {
            Ok(SVector::<f64, 1>::new(-self.a * x[0] + self.b))
        }
    }

    fn final_error(dt: f64) -> f64 {
        let m = Decay { a: 2.0, b: 1.0 };
        let mut x = SVector::<f64, 1>::new(3.0);
        let n = (1.0 / dt).round() as usize;
        for i in 0..n {
            x = rk4_step(&m, i as f64 * dt, &x, &(), dt).unwrap();
        }
        let exact = 0.5 + (3.0 - 0.5) * (-2.0f64).exp();
        (x[0] - exact).abs()
    }

    #[test]
    fn analytic_rk4_fourth_order_convergence() {
        let e1 = final_error(0.1);
        let e2 = final_error(0.05);
        let order = (e1 / e2).log2();
        assert!((order - 4.0).abs() < 0.15, "observed order {order}");
        assert!(final_error(0.001) < 1e-12);
    }
}
