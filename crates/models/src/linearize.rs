//! Linearization by central differences, eigenvalues and F-16 mode identification
//! (SLJ 3rd ed. §3.7–3.8: longitudinal modes short period / phugoid, lateral-directional modes
//! roll / spiral / Dutch roll).
//!
//! `A = ∂f/∂x`, `B = ∂f/∂u` at `(x0, u0)`, column `k` from `(f(x0 + h e_k) − f(x0 − h e_k)) / 2h`
//! with `h = rel_step · max(|x0_k|, 1)`; truncation error O(h²).

use crate::f16::{ALPHA, BETA, F16, F16Controls, N_CONTROLS, N_STATES, P, PHI, Q, R, THETA, VT};
use crate::{Dynamics, ModelError};
use nalgebra::{Complex, DMatrix, SMatrix, SVector};

/// A linear model `δẋ = A δx + B δu` about a point.
#[derive(Debug, Clone, PartialEq)]
pub struct Linearization<const N: usize, const M: usize> {
    /// State matrix A (N × N).
    pub a: SMatrix<f64, N, N>,
    /// Input matrix B (N × M).
    pub b: SMatrix<f64, N, M>,
}

/// Default relative finite-difference step of [`linearize`].
pub const DEFAULT_REL_STEP: f64 = 1e-6;

/// Central-difference Jacobians of any model at `(t_s, x0, u0)`. `to_input` maps the input vector
/// (M numbers) to the model's input type, so the same routine serves every model.
///
/// # Errors
/// Any error of the model's derivatives at the perturbed points.
pub fn linearize<const N: usize, const M: usize, D: Dynamics<N>>(
    model: &D,
    t_s: f64,
    x0: &SVector<f64, N>,
    u0: &SVector<f64, M>,
    to_input: impl Fn(&SVector<f64, M>) -> D::Input,
    rel_step: f64,
) -> Result<Linearization<N, M>, ModelError> {
    let u_nom = to_input(u0);
    let mut a = SMatrix::<f64, N, N>::zeros();
    for k in 0..N {
        let h = rel_step * x0[k].abs().max(1.0);
        let mut xp = *x0;
        let mut xm = *x0;
        xp[k] += h;
        xm[k] -= h;
        let col = (model.derivatives(t_s, &xp, &u_nom)? - model.derivatives(t_s, &xm, &u_nom)?)
            / (2.0 * h);
        a.set_column(k, &col);
    }
    let mut b = SMatrix::<f64, N, M>::zeros();
    for k in 0..M {
        let h = rel_step * u0[k].abs().max(1.0);
        let mut up = *u0;
        let mut um = *u0;
        up[k] += h;
        um[k] -= h;
        let col = (model.derivatives(t_s, x0, &to_input(&up))?
            - model.derivatives(t_s, x0, &to_input(&um))?)
            / (2.0 * h);
        b.set_column(k, &col);
    }
    Ok(Linearization { a, b })
}

/// The F-16's A (13 × 13) and B (13 × 4, columns throttle, elevator, aileron, rudder in rad)
/// about `(x0, u0)` (the wind of `u0` is held).
///
/// # Errors
/// As [`linearize`].
pub fn linearize_f16(
    model: &F16,
    x0: &SVector<f64, N_STATES>,
    u0: &F16Controls,
) -> Result<Linearization<N_STATES, N_CONTROLS>, ModelError> {
    linearize(model, 0.0, x0, &u0.to_vector(), |v| u0.with_vector(v), DEFAULT_REL_STEP)
}

/// Names of the F-16's dynamic modes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModeName {
    /// Longitudinal short-period oscillation (complex pair).
    ShortPeriod,
    /// A real root of a short period that has split (relaxed static stability, e.g. xcg 0.35).
    ShortPeriodReal,
    /// Longitudinal phugoid (complex pair).
    Phugoid,
    /// A real root of a split phugoid.
    PhugoidReal,
    /// Lateral roll subsidence (real).
    Roll,
    /// Lateral spiral (real, slow).
    Spiral,
    /// Lateral Dutch roll (complex pair).
    DutchRoll,
    /// A coupled roll–spiral oscillation (when roll and spiral merge into a complex pair).
    RollSpiral,
}

impl ModeName {
    /// snake_case name used in CLI/JSON output.
    pub fn as_str(self) -> &'static str {
        match self {
            ModeName::ShortPeriod => "short_period",
            ModeName::ShortPeriodReal => "short_period_real",
            ModeName::Phugoid => "phugoid",
            ModeName::PhugoidReal => "phugoid_real",
            ModeName::Roll => "roll",
            ModeName::Spiral => "spiral",
            ModeName::DutchRoll => "dutch_roll",
            ModeName::RollSpiral => "roll_spiral",
        }
    }
}

/// One identified mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mode {
    /// Which mode.
    pub name: ModeName,
    /// Eigenvalue (1/s); for a pair, the one with positive imaginary part.
    pub eigenvalue: Complex<f64>,
    /// Natural frequency |λ|, rad/s.
    pub wn_rad_s: f64,
    /// Damping ratio −Re λ / |λ| (±1 for a real root; negative = unstable).
    pub zeta: f64,
}

impl Mode {
    fn new(name: ModeName, l: Complex<f64>) -> Self {
        let wn = l.norm();
        Self {
            name,
            eigenvalue: Complex::new(l.re, l.im.abs()),
            wn_rad_s: wn,
            zeta: if wn > 0.0 { -l.re / wn } else { 0.0 },
        }
    }
}

/// Eigenvalues of a square matrix (real Schur form, nalgebra), sorted by real part then
/// imaginary part.
pub fn eigenvalues<const N: usize>(a: &SMatrix<f64, N, N>) -> Vec<Complex<f64>> {
    eigenvalues_dyn(DMatrix::from_iterator(N, N, a.iter().copied()))
}

/// [`eigenvalues`] of a square matrix whose size is known at run time only (a linear model
/// grown by actuator states).
///
/// # Panics
/// `a` not square (nalgebra's own check).
pub fn eigenvalues_dyn(a: DMatrix<f64>) -> Vec<Complex<f64>> {
    let mut v: Vec<Complex<f64>> = a.complex_eigenvalues().iter().copied().collect();
    v.sort_by(|x, y| x.re.total_cmp(&y.re).then(x.im.total_cmp(&y.im)));
    v
}

/// Splits 4 eigenvalues into complex pairs (positive-imaginary member) and real roots.
fn pairs_and_reals(ev: &[Complex<f64>]) -> (Vec<Complex<f64>>, Vec<Complex<f64>>) {
    let scale = ev.iter().fold(1e-12f64, |m, l| m.max(l.norm()));
    let mut pairs = vec![];
    let mut reals = vec![];
    for l in ev {
        if l.im.abs() <= 1e-9 * scale {
            reals.push(Complex::new(l.re, 0.0));
        } else if l.im > 0.0 {
            pairs.push(*l);
        }
    }
    (pairs, reals)
}

/// The F-16's modes from a 13-state A matrix about a **wings-level** trim, where the
/// longitudinal states (vt, α, θ, q) and the lateral states (β, φ, p, r) decouple (SLJ §3.7–3.8
/// use the same 4-state blocks). Rules (by magnitude, documented heuristics):
/// * longitudinal: two complex pairs → larger ωn short period, smaller phugoid; one pair and
///   two real roots → the pair is the short period when its ωn exceeds every real root,
///   otherwise it is the phugoid and the real roots are a split short period; four real roots →
///   the two largest |λ| are short-period roots.
/// * lateral: one complex pair (Dutch roll) and two real roots (larger |λ| roll, smaller spiral);
///   two pairs → larger ωn Dutch roll, the other a roll–spiral oscillation.
pub fn f16_modes(a: &SMatrix<f64, N_STATES, N_STATES>) -> Vec<Mode> {
    rigid_body_modes(a)
}

/// The modes of any aircraft whose first 12 states follow the rigid-body layout of
/// [`crate::rigid_body::STATE_NAMES`] (the F-16's 13 states, the 12 of a model-file aircraft):
/// the rules of [`f16_modes`] on the longitudinal block (vt, α, θ, q) and the lateral block
/// (β, φ, p, r) of the `N × N` matrix `a` about a wings-level trim. The length unit of `vt`
/// (ft/s or m/s) does not change the eigenvalues (1/s).
/// `N < 12` (no rigid-body layout) does not compile.
pub fn rigid_body_modes<const N: usize>(a: &SMatrix<f64, N, N>) -> Vec<Mode> {
    const { assert!(N >= crate::rigid_body::N_STATES, "the rigid-body layout has 12 states") };
    let block = |idx: [usize; 4]| {
        let mut m = SMatrix::<f64, 4, 4>::zeros();
        for i in 0..4 {
            for j in 0..4 {
                m[(i, j)] = a[(idx[i], idx[j])];
            }
        }
        eigenvalues(&m)
    };
    let mut modes = vec![];
    let by_norm_desc = |v: &mut Vec<Complex<f64>>| v.sort_by(|x, y| y.norm().total_cmp(&x.norm()));

    let (mut pairs, mut reals) = pairs_and_reals(&block([VT, ALPHA, THETA, Q]));
    by_norm_desc(&mut pairs);
    by_norm_desc(&mut reals);
    match (pairs.len(), reals.len()) {
        (2, _) => {
            modes.push(Mode::new(ModeName::ShortPeriod, pairs[0]));
            modes.push(Mode::new(ModeName::Phugoid, pairs[1]));
        }
        (1, _) => {
            let max_real = reals.iter().fold(0.0f64, |m, l| m.max(l.norm()));
            if pairs[0].norm() > max_real {
                modes.push(Mode::new(ModeName::ShortPeriod, pairs[0]));
                modes.extend(reals.iter().map(|l| Mode::new(ModeName::PhugoidReal, *l)));
            } else {
                modes.extend(reals.iter().map(|l| Mode::new(ModeName::ShortPeriodReal, *l)));
                modes.push(Mode::new(ModeName::Phugoid, pairs[0]));
            }
        }
        _ => {
            for (k, l) in reals.iter().enumerate() {
                modes.push(Mode::new(
                    if k < 2 { ModeName::ShortPeriodReal } else { ModeName::PhugoidReal },
                    *l,
                ));
            }
        }
    }

    let (mut pairs, mut reals) = pairs_and_reals(&block([BETA, PHI, P, R]));
    by_norm_desc(&mut pairs);
    by_norm_desc(&mut reals);
    match pairs.len() {
        2 => {
            modes.push(Mode::new(ModeName::DutchRoll, pairs[0]));
            modes.push(Mode::new(ModeName::RollSpiral, pairs[1]));
        }
        1 => {
            modes.push(Mode::new(ModeName::DutchRoll, pairs[0]));
            if let Some(l) = reals.first() {
                modes.push(Mode::new(ModeName::Roll, *l));
            }
            if let Some(l) = reals.get(1) {
                modes.push(Mode::new(ModeName::Spiral, *l));
            }
        }
        _ => {
            let n = reals.len();
            for (k, l) in reals.iter().enumerate() {
                let name = if k == 0 {
                    ModeName::Roll
                } else if k + 1 == n {
                    ModeName::Spiral
                } else {
                    ModeName::DutchRoll
                };
                modes.push(Mode::new(name, *l));
            }
        }
    }
    modes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ẋ = A x + B u with known A, B: central differences are exact for a linear model.
    struct Lin;
    impl Dynamics<2> for Lin {
        type Input = SVector<f64, 1>;
        fn derivatives(
            &self,
            _t: f64,
            x: &SVector<f64, 2>,
            u: &SVector<f64, 1>,
        ) -> Result<SVector<f64, 2>, ModelError> {
            Ok(SVector::<f64, 2>::new(x[1], -4.0 * x[0] - 0.4 * x[1] + 2.0 * u[0]))
        }
    }

    #[test]
    fn analytic_linear_model_jacobians_and_damped_oscillator_eigenvalues() {
        let l = linearize(
            &Lin,
            0.0,
            &SVector::<f64, 2>::new(0.3, -1.0),
            &SVector::<f64, 1>::new(0.5),
            |v| *v,
            1e-6,
        )
        .unwrap();
        let a = SMatrix::<f64, 2, 2>::new(0.0, 1.0, -4.0, -0.4);
        assert!((l.a - a).amax() < 1e-8);
        assert!((l.b[(1, 0)] - 2.0).abs() < 1e-8);
        // ωn = 2, ζ = 0.1: λ = −0.2 ± j·2·√(1 − 0.01).
        let ev = eigenvalues(&l.a);
        assert!((ev[1].re + 0.2).abs() < 1e-7 && (ev[1].im - 2.0 * 0.99f64.sqrt()).abs() < 1e-7);
    }
}
