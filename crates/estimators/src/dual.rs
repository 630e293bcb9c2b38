//! Forward-mode dual numbers with a fixed number of derivative directions, implementing the
//! [`Scalar`] trait (of `aeroident-physics`, which implements it for `f64`) so that one generic
//! function gives values (`f64`) and exact first derivatives ([`Dual`]).
//!
//! A dual number `a + Σ_k a_k ε_k` with `ε_j ε_k = 0` carries a value and its derivatives along
//! `N` directions; arithmetic and the elementary functions apply the chain rule exactly, so a
//! function evaluated on duals seeded with unit directions returns its Jacobian columns to
//! rounding (no step size, unlike finite differences). Source: Griewank & Walther, *Evaluating
//! Derivatives*, 2nd ed., SIAM 2008, ch. 3 (forward mode, tangent propagation).
//!
//! `no_std`, no allocation: a `Dual<N>` is `N + 1` floats on the stack.

use core::ops::{Add, Div, Mul, Neg, Sub};

pub use aeroident_physics::Scalar;

/// A dual number with `N` derivative directions: value `re` and partials `eps[k] = ∂/∂s_k`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dual<const N: usize> {
    /// Value.
    pub re: f64,
    /// Derivatives along the `N` seeded directions.
    pub eps: [f64; N],
}

impl<const N: usize> Dual<N> {
    /// A constant (all derivatives 0).
    #[inline]
    pub fn constant(re: f64) -> Self {
        Self { re, eps: [0.0; N] }
    }

    /// The independent variable of direction `k` (derivative 1 along `k`, 0 elsewhere) with
    /// value `re`. `k ≥ N` gives a constant.
    #[inline]
    pub fn variable(re: f64, k: usize) -> Self {
        let mut eps = [0.0; N];
        if k < N {
            eps[k] = 1.0;
        }
        Self { re, eps }
    }

    /// `f(re)` with derivative `df` (chain rule: `eps · df`).
    #[inline]
    fn chain(self, value: f64, df: f64) -> Self {
        let mut eps = self.eps;
        for e in eps.iter_mut() {
            *e *= df;
        }
        Self { re: value, eps }
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self.re += o.re;
        for (a, b) in self.eps.iter_mut().zip(o.eps.iter()) {
            *a += b;
        }
        self
    }
}

impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self.re -= o.re;
        for (a, b) in self.eps.iter_mut().zip(o.eps.iter()) {
            *a -= b;
        }
        self
    }
}

impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut eps = [0.0; N];
        for (k, e) in eps.iter_mut().enumerate() {
            *e = self.eps[k] * o.re + self.re * o.eps[k];
        }
        Self { re: self.re * o.re, eps }
    }
}

impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let inv = 1.0 / o.re;
        let q = self.re * inv;
        let mut eps = [0.0; N];
        for (k, e) in eps.iter_mut().enumerate() {
            *e = (self.eps[k] - q * o.eps[k]) * inv;
        }
        Self { re: q, eps }
    }
}

impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    #[inline]
    fn neg(mut self) -> Self {
        self.re = -self.re;
        for e in self.eps.iter_mut() {
            *e = -*e;
        }
        self
    }
}

impl<const N: usize> Add<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: f64) -> Self {
        self.re += o;
        self
    }
}

impl<const N: usize> Sub<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: f64) -> Self {
        self.re -= o;
        self
    }
}

impl<const N: usize> Mul<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(mut self, o: f64) -> Self {
        self.re *= o;
        for e in self.eps.iter_mut() {
            *e *= o;
        }
        self
    }
}

impl<const N: usize> Div<f64> for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: f64) -> Self {
        self * (1.0 / o)
    }
}

impl<const N: usize> Scalar for Dual<N> {
    #[inline]
    fn cst(v: f64) -> Self {
        Self::constant(v)
    }
    #[inline]
    fn re(self) -> f64 {
        self.re
    }
    #[inline]
    fn sin(self) -> Self {
        self.chain(libm::sin(self.re), libm::cos(self.re))
    }
    #[inline]
    fn cos(self) -> Self {
        self.chain(libm::cos(self.re), -libm::sin(self.re))
    }
    #[inline]
    fn tan(self) -> Self {
        let t = libm::tan(self.re);
        self.chain(t, 1.0 + t * t)
    }
    #[inline]
    fn sqrt(self) -> Self {
        let s = libm::sqrt(self.re);
        self.chain(s, 0.5 / s)
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        // d atan2(y, x) = (x dy − y dx) / (x² + y²).
        let (y0, x0) = (self.re, x.re);
        let r2 = x0 * x0 + y0 * y0;
        let mut eps = [0.0; N];
        for (k, e) in eps.iter_mut().enumerate() {
            *e = (x0 * self.eps[k] - y0 * x.eps[k]) / r2;
        }
        Self { re: libm::atan2(y0, x0), eps }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type D2 = Dual<2>;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-13 * (1.0 + b.abs())
    }

    /// Partials of a two-variable expression against the hand-derived analytic ones.
    #[test]
    fn analytic_partials_of_arithmetic_and_elementary_functions() {
        let (x0, y0) = (0.7, -1.3);
        let x = D2::variable(x0, 0);
        let y = D2::variable(y0, 1);
        // f = x y + x / y − y + 3  →  fx = y + 1/y,  fy = x − x/y² − 1
        let f = x * y + x / y - y + 3.0;
        assert!(close(f.re, x0 * y0 + x0 / y0 - y0 + 3.0));
        assert!(close(f.eps[0], y0 + 1.0 / y0));
        assert!(close(f.eps[1], x0 - x0 / (y0 * y0) - 1.0));
        // g = sin(x) cos(y) + tan(x y)
        let g = x.sin() * y.cos() + (x * y).tan();
        let sec2 = 1.0 / libm::cos(x0 * y0).powi(2);
        assert!(close(g.eps[0], x0.cos() * y0.cos() + y0 * sec2));
        assert!(close(g.eps[1], -x0.sin() * y0.sin() + x0 * sec2));
        // h = sqrt(x² + y²), atan2(y, x)
        let h = (x * x + y * y).sqrt();
        let r = (x0 * x0 + y0 * y0).sqrt();
        assert!(close(h.eps[0], x0 / r) && close(h.eps[1], y0 / r));
        let a = y.atan2(x);
        assert!(close(a.re, y0.atan2(x0)));
        assert!(close(a.eps[0], -y0 / (r * r)) && close(a.eps[1], x0 / (r * r)));
        // Negation, f64 operands, division by f64.
        let n = -(x * 2.0 - 1.0) / 4.0;
        assert!(close(n.re, -(2.0 * x0 - 1.0) / 4.0) && close(n.eps[0], -0.5));
        assert_eq!(n.eps[1], 0.0);
    }

    /// The shared rigid-body kernel instantiated with duals (as the flight model runs it):
    /// every partial of the chain body velocity → force equations → wind-axes rates, Euler
    /// rates, Euler's equations and their inverse equals a central difference of the `f64`
    /// instantiation, and the values agree.
    #[test]
    fn rigid_body_kernel_dual_partials_match_central_differences_of_f64() {
        use aeroident_physics::rigid_body::{self as rb, Inertia, InertiaConstants, SinCos};
        const N: usize = 14;
        const I: Inertia = Inertia { jx: 1.7e4, jy: 7.7e4, jz: 9.1e4, jxz: 1.4e3 };
        fn kernel<T: Scalar>(x: [T; N]) -> [T; 12] {
            let [vt, al, be, p, q, r, ph, th, ax, ay, az, l, m, n] = x;
            let omega = [p, q, r];
            let (beta, phi, theta) = (SinCos::of(be), SinCos::of(ph), SinCos::of(th));
            let v = rb::body_velocity(vt, SinCos::of(al), beta);
            let vd =
                rb::body_acceleration(v, omega, rb::gravity_body(9.8, phi, theta), [ax, ay, az]);
            let [vtd, alphad, betad] = rb::wind_axes_rates(v, vd, vt, beta.cos);
            let [phid, thetad, psid] = rb::euler_rates(omega, phi, theta);
            let c = InertiaConstants::of(&I);
            let [pd, qd, rd] = rb::angular_acceleration(&c, omega, [l, m, n], 160.0);
            // The inverse at independent angular accelerations (the forward ones would give
            // back the inputs, a trivial derivative).
            let [li, ni] = rb::roll_yaw_moments(&I, omega, ax * 0.1, az * 0.1, 160.0);
            let mi = rb::pitch_moment(&I, p, r, ay * 0.1, 160.0);
            [vtd, alphad, betad, phid, thetad, psid, pd, qd, rd, li, mi, ni]
        }
        let x0 = [120.0, 0.12, -0.07, 0.4, -0.2, 0.3, 0.5, 0.25, 1.2, -0.8, -10.5, 4e4, -6e4, 2e4];
        let duals = kernel::<Dual<N>>(core::array::from_fn(|k| Dual::variable(x0[k], k)));
        let values = kernel(x0);
        for (j, d) in duals.iter().enumerate() {
            assert!((d.re - values[j]).abs() <= 1e-14 * values[j].abs(), "value {j}");
            for k in 0..N {
                let h = 1e-6 * x0[k].abs().max(1.0);
                let (mut up, mut down) = (x0, x0);
                up[k] += h;
                down[k] -= h;
                let fd = (kernel(up)[j] - kernel(down)[j]) / (2.0 * h);
                let tol = 1e-6 * (fd.abs() + values[j].abs() / x0[k].abs().max(1.0)) + 1e-12;
                assert!((d.eps[k] - fd).abs() <= tol, "d out{j}/d x{k}: {} vs {fd}", d.eps[k]);
            }
        }
    }

    /// The same generic function gives the same value in f64 and in duals, and its dual
    /// derivative matches a central difference.
    #[test]
    fn generic_function_value_and_derivative_agree_with_f64() {
        fn f<T: Scalar>(x: T) -> T {
            (x * x + 1.0).sqrt() * x.sin() / (x.cos() + 2.0)
        }
        let x0 = 0.4;
        let d = f(Dual::<1>::variable(x0, 0));
        assert_eq!(d.re, f(x0));
        let h = 1e-6;
        let fd = (f(x0 + h) - f(x0 - h)) / (2.0 * h);
        assert!((d.eps[0] - fd).abs() < 1e-9, "{} vs {fd}", d.eps[0]);
        assert_eq!(Dual::<3>::variable(1.0, 5).eps, [0.0; 3]);
    }
}
