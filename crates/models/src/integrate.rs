//! Fixed-step integrators: [`rk4_step`] holds the input constant over the step (zero-order
//! hold); [`rk4_step_varying`] evaluates a continuous input at the stage times.

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
    rk4_stages(model, t_s, x, [u, u, u], dt_s)
}

/// One classical fourth-order Runge–Kutta step of `dt_s` seconds from `(t_s, x)` with a
/// **continuous** input: `input(t)` is evaluated at the stage times `t_s`, `t_s + dt/2` (shared
/// by the two middle stages) and `t_s + dt`, so a smooth input is integrated to the scheme's
/// order (local error O(dt⁵)). [`rk4_step`] instead holds the input of `t_s` over the step: a
/// staircase, which for a smooth input is the input delayed by `dt/2` on average (an O(dt)
/// error: a phase lag `ω dt/2` at frequency `ω`).
///
/// This is how the aircraft experiments fly their pilot inputs: a real control surface moves
/// continuously, and a recorded surface sample is the position at the sample instant, so an
/// estimator that interpolates between samples (output error, Jategaonkar 2015 ch. 4
/// `ruku4.m`) sees the input the aircraft flew.
///
/// # Errors
/// Whatever the model's [`Dynamics::derivatives`] returns at any of the four stages.
pub fn rk4_step_varying<const N: usize, D: Dynamics<N>>(
    model: &D,
    t_s: f64,
    x: &SVector<f64, N>,
    input: impl Fn(f64) -> D::Input,
    dt_s: f64,
) -> Result<SVector<f64, N>, ModelError> {
    let (u0, u_half, u1) = (input(t_s), input(t_s + 0.5 * dt_s), input(t_s + dt_s));
    rk4_stages(model, t_s, x, [&u0, &u_half, &u1], dt_s)
}

/// The four stages of the classical RK4 step with the inputs `[u(t), u(t + h/2), u(t + h)]`
/// (the two middle stages share the half-step input).
fn rk4_stages<const N: usize, D: Dynamics<N>>(
    model: &D,
    t_s: f64,
    x: &SVector<f64, N>,
    [u0, u_half, u1]: [&D::Input; 3],
    h: f64,
) -> Result<SVector<f64, N>, ModelError> {
    let k1 = model.derivatives(t_s, x, u0)?;
    let k2 = model.derivatives(t_s + 0.5 * h, &(x + k1 * (0.5 * h)), u_half)?;
    let k3 = model.derivatives(t_s + 0.5 * h, &(x + k2 * (0.5 * h)), u_half)?;
    let k4 = model.derivatives(t_s + h, &(x + k3 * h), u1)?;
    Ok(x + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::small::FirstOrder;

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

    /// Response of ẋ = −a x + sin(ω(t − d)) from x(0) = 0 (closed form, through the responses
    /// to sin ωt and cos ωt).
    fn forced_exact(a: f64, w: f64, d: f64, t: f64) -> f64 {
        let den = a * a + w * w;
        let s = (a * (w * t).sin() - w * (w * t).cos() + w * (-a * t).exp()) / den;
        let c = (w * (w * t).sin() + a * (w * t).cos() - a * (-a * t).exp()) / den;
        s * (w * d).cos() - c * (w * d).sin()
    }

    /// Largest |x(t_k) − x_exact(t_k)| over 1 s of ẋ = −2x + sin 6t, x(0) = 0, stepping with
    /// `dt`, the input continuous (`varying`) or held at each step's start (`rk4_step`), against
    /// the exact response to the input delayed by `delay`.
    fn forced_error(dt: f64, varying: bool, delay: f64) -> f64 {
        let (a, w) = (2.0, 6.0);
        let m = FirstOrder { a };
        let u = |t: f64| (w * t).sin();
        let mut x = SVector::<f64, 1>::zeros();
        let mut worst = 0.0_f64;
        for i in 0..(1.0 / dt).round() as usize {
            let t = i as f64 * dt;
            x = if varying {
                rk4_step_varying(&m, t, &x, u, dt).unwrap()
            } else {
                rk4_step(&m, t, &x, &u(t), dt).unwrap()
            };
            worst = worst.max((x[0] - forced_exact(a, w, delay, t + dt)).abs());
        }
        worst
    }

    /// A continuous input evaluated at the stage times keeps RK4's fourth order; the held
    /// input (the staircase) is first order, and its error is that of the input delayed by
    /// dt/2: against the response to the delayed input it is 100× smaller.
    #[test]
    fn analytic_rk4_varying_input_orders() {
        let order = (forced_error(0.02, true, 0.0) / forced_error(0.01, true, 0.0)).log2();
        assert!((order - 4.0).abs() < 0.1, "varying: observed order {order}");
        let held = (forced_error(0.02, false, 0.0) / forced_error(0.01, false, 0.0)).log2();
        assert!((held - 1.0).abs() < 0.05, "held: observed order {held}");
        let (to_exact, to_delayed) =
            (forced_error(0.01, false, 0.0), forced_error(0.01, false, 0.005));
        assert!(
            to_delayed < 0.01 * to_exact,
            "held: {to_exact} to the input, {to_delayed} to the delayed input"
        );
    }
}
