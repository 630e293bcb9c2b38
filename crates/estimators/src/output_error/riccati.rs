//! The steady-state Kalman filter of a discrete linear system: the discrete algebraic Riccati
//! equation (DARE) of the one-step prediction covariance, solved by the structure-preserving
//! doubling algorithm, and the gain.
//!
//! For `x_{k+1} = Φ x_k + w_k`, `z_k = C x_k + v_k`, `cov w = Q`, `cov v = R`, the a-priori
//! (predicted) covariance `P` of the steady-state filter solves
//!
//! ```text
//! P = Φ P Φᵀ − Φ P Cᵀ (C P Cᵀ + R)⁻¹ C P Φᵀ + Q
//! ```
//!
//! (Jategaonkar 2015 ch. 5 writes the continuous-time form for the filter-error method;
//! Simon, *Optimal State Estimation*, Wiley 2006, ch. 7, the discrete one). The innovation
//! covariance is `S = C P Cᵀ + R` and the gain `K = P Cᵀ S⁻¹` (correction `x̂ = x̃ + K ν`).
//!
//! # Solver
//!
//! The structure-preserving doubling algorithm (Chu, Fan & Lin, "A structure-preserving
//! doubling algorithm for continuous-time algebraic Riccati equations", Linear Algebra Appl.
//! 396, 2005; the discrete form, e.g. Lin & Xu, SIAM J. Matrix Anal. Appl. 28(1), 2006) for
//! `X = Aᵀ X (I + G X)⁻¹ A + H` with `A = Φᵀ`, `G = Cᵀ R⁻¹ C`, `H = Q` (the matrix inversion
//! lemma turns this into the equation above):
//!
//! ```text
//! W = I + G_k H_k,  A_{k+1} = A_k W⁻¹ A_k,  G_{k+1} = G_k + A_k W⁻¹ G_k A_kᵀ,
//! H_{k+1} = H_k + A_kᵀ H_k W⁻¹ A_k,   H_k → P
//! ```
//!
//! `H_k` is the Riccati recursion after `2^k` steps from `P = Q`, so it converges
//! quadratically for a stabilisable, detectable pair and still doubles the horizon per
//! iteration where a noise-free mode lies on the unit circle. Stopped when the relative change
//! of `H` is below 10⁻¹³ (at most [`MAX_DOUBLINGS`] iterations).

use crate::EstimatorError;
use nalgebra::DMatrix;

/// Most doubling iterations (a horizon of `2^60` steps).
pub const MAX_DOUBLINGS: usize = 60;

/// The steady-state filter: a-priori covariance `P` (`nx × nx`), innovation covariance
/// `S = C P Cᵀ + R` (`ny × ny`) and gain `K = P Cᵀ S⁻¹` (`nx × ny`).
#[derive(Debug, Clone, PartialEq)]
pub struct SteadyState {
    /// A-priori (one-step prediction) state covariance.
    pub p: DMatrix<f64>,
    /// Innovation covariance.
    pub s: DMatrix<f64>,
    /// Kalman gain.
    pub k: DMatrix<f64>,
}

fn numerical(what: &'static str) -> EstimatorError {
    EstimatorError::Numerical { what, t_s: 0.0 }
}

/// Solves the filter DARE (module doc) for `P`.
///
/// Shapes: `phi` `nx × nx`, `c` `ny × nx`, `q` `nx × nx` symmetric positive semi-definite,
/// `r` `ny × ny` symmetric positive definite.
///
/// # Errors
/// [`EstimatorError::Numerical`] when `R` is not positive definite, a doubling step is
/// singular, or the iteration does not converge (an undetectable unstable mode) or produces
/// non-finite values.
pub fn dare(
    phi: &DMatrix<f64>,
    c: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Result<DMatrix<f64>, EstimatorError> {
    let nx = phi.nrows();
    let rinv = r
        .clone()
        .cholesky()
        .ok_or_else(|| {
            numerical("Riccati equation: measurement-noise covariance R not positive definite")
        })?
        .inverse();
    let mut a = phi.transpose();
    let mut g = c.transpose() * rinv * c;
    let mut h = q.clone();
    let eye = DMatrix::<f64>::identity(nx, nx);
    for _ in 0..MAX_DOUBLINGS {
        let w = &eye + &g * &h;
        let lu = w.lu();
        let wa =
            lu.solve(&a).ok_or_else(|| numerical("Riccati equation: doubling step singular"))?;
        let wg =
            lu.solve(&g).ok_or_else(|| numerical("Riccati equation: doubling step singular"))?;
        let h_next = &h + a.transpose() * &h * &wa;
        let g_next = &g + &a * wg * a.transpose();
        let a_next = &a * wa;
        let change = (&h_next - &h).norm();
        let scale = h_next.norm();
        // Keep the iterates symmetric against rounding.
        h = (&h_next + h_next.transpose()) * 0.5;
        g = (&g_next + g_next.transpose()) * 0.5;
        a = a_next;
        if !(h.iter().all(|v| v.is_finite()) && a.iter().all(|v| v.is_finite())) {
            return Err(numerical("Riccati equation: the doubling iteration diverged"));
        }
        if change <= 1e-13 * scale || scale == 0.0 {
            return Ok(h);
        }
    }
    Err(numerical(
        "Riccati equation: no convergence (an unstable mode the outputs do not observe?)",
    ))
}

/// The steady-state filter ([`SteadyState`]) of `(Φ, C, Q, R)`: [`dare`], then `S` and `K`.
///
/// # Errors
/// As [`dare`]; [`EstimatorError::Numerical`] when `S` is not positive definite.
pub fn steady_state(
    phi: &DMatrix<f64>,
    c: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Result<SteadyState, EstimatorError> {
    let p = dare(phi, c, q, r)?;
    let pct = &p * c.transpose();
    let s = c * &pct + r;
    let s = (&s + s.transpose()) * 0.5;
    let chol = s
        .clone()
        .cholesky()
        .ok_or_else(|| numerical("Kalman filter: innovation covariance not positive definite"))?;
    // K = P Cᵀ S⁻¹ = (S⁻¹ C P)ᵀ.
    let k = chol.solve(&pct.transpose()).transpose();
    Ok(SteadyState { p, s, k })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Scalar closed form: `c² p² + (r(1 − φ²) − q c²) p − q r = 0`, positive root.
    #[test]
    fn scalar_matches_closed_form() {
        for &(phi, c, q, r) in &[
            (0.95, 1.0, 0.01, 0.1),
            (1.0, 1.0, 1e-4, 1e-2),
            (1.2, 0.5, 0.3, 2.0),
            (0.2, 3.0, 5.0, 1e-3),
        ] {
            let m = |v: f64| DMatrix::from_element(1, 1, v);
            let p = dare(&m(phi), &m(c), &m(q), &m(r)).unwrap()[(0, 0)];
            let b = r * (1.0 - phi * phi) - q * c * c;
            let exact = (-b + (b * b + 4.0 * c * c * q * r).sqrt()) / (2.0 * c * c);
            assert!((p - exact).abs() <= 1e-10 * exact, "φ {phi}: {p} vs closed form {exact}");
            let ss = steady_state(&m(phi), &m(c), &m(q), &m(r)).unwrap();
            let k = exact * c / (c * c * exact + r);
            assert!((ss.k[(0, 0)] - k).abs() <= 1e-10 * k.abs());
            assert!((ss.s[(0, 0)] - (c * c * exact + r)).abs() <= 1e-10 * ss.s[(0, 0)]);
        }
    }

    /// A 2×2 system with an integrator, an unstable mode, noise on one state only and one
    /// output: the solution satisfies the Riccati equation to rounding, is symmetric positive
    /// definite, and the filter `Φ (I − K C)` is stable.
    #[test]
    fn two_states_satisfy_the_riccati_equation() {
        let phi = DMatrix::from_row_slice(2, 2, &[1.0, 0.1, 0.0, 1.02]);
        let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let q = DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, 0.04]);
        let r = DMatrix::from_element(1, 1, 0.25);
        let p = dare(&phi, &c, &q, &r).unwrap();
        let s = &c * &p * c.transpose() + &r;
        let sinv = s.clone().try_inverse().unwrap();
        let rhs = &phi * &p * phi.transpose()
            - &phi * &p * c.transpose() * sinv * &c * &p * phi.transpose()
            + &q;
        let residual = (&rhs - &p).norm();
        assert!(residual <= 1e-10 * p.norm(), "Riccati residual {residual:e}, |P| {}", p.norm());
        assert!((p[(0, 1)] - p[(1, 0)]).abs() <= 1e-12 * p.norm());
        assert!(p.clone().cholesky().is_some(), "P not positive definite: {p}");
        let ss = steady_state(&phi, &c, &q, &r).unwrap();
        let closed = &phi * (DMatrix::identity(2, 2) - &ss.k * &c);
        let eig = closed.complex_eigenvalues();
        assert!(eig.iter().all(|l| l.norm() < 1.0), "filter not stable: {eig}");
    }

    #[test]
    fn refuses_a_non_positive_r() {
        let m = |v: f64| DMatrix::from_element(1, 1, v);
        assert!(dare(&m(0.9), &m(1.0), &m(0.1), &m(0.0)).is_err());
    }
}
