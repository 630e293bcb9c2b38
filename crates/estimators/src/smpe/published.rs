//! The thesis's sliding-mode parameter estimator, as published (spec §1, (3.20)–(3.36),
//! (3.58)–(3.72), (3.91)–(3.99), (3.128)).

use super::{ParamSpec, ParametricModel, SlidingSurface, SmpeSample, energy_terms, weighted};
use crate::{Estimate, EstimatorError, ParametricEstimator};
use nalgebra::{SMatrix, SVector};

/// Which reading of the implicit estimator equation to use (spec §1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reading {
    /// Solve `F(θ̂) = 0` for θ̂ within the bounds at every sample (Simulink's algebraic loop).
    Implicit,
    /// Evaluate the right-hand side of (3.22)/(3.59) with the previous sample's θ̂.
    Explicit,
}

/// How the Lyapunov gain is formed with several parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GainForm {
    /// One K for all parameters, summing every parameter's term inside `|·|` (3.72), (3.128).
    Shared,
    /// `k_j = |θ̂_j (α_j⁻¹ − 1) φ_j| − η` per parameter (the `k_1`, `k_2` of (3.59)).
    PerParameter,
}

/// Configuration of [`PublishedSmpe`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmpeConfig<const N: usize, const P: usize> {
    /// One entry per parameter: name, bounds, λ_j, initial guess.
    pub params: [ParamSpec; P],
    /// η > 0 of (3.20): keeps the denominator away from zero.
    pub eta: f64,
    /// Sliding surface.
    pub surface: SlidingSurface<N>,
    /// Shared or per-parameter Lyapunov gain.
    pub gain: GainForm,
    /// Implicit or explicit reading.
    pub reading: Reading,
}

/// Counters of what the per-sample solve had to do (for reports; never hidden).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SolveStats {
    /// Samples processed.
    pub samples: u64,
    /// Implicit reading: samples where `F(θ̂) = 0` had no root inside the bounds and the
    /// least-residual point in the bounds was used.
    pub no_root: u64,
    /// Explicit reading: samples where the unclamped estimate left the bounds.
    pub clamped: u64,
    /// Explicit reading: samples where `|K·B + η| < η` and the denominator was held at `±η`.
    pub guarded: u64,
}

/// The published SMPE (thesis (3.20)–(3.22) generalised by (3.39), (3.58), (3.72)).
///
/// For each parameter `j` the estimator enforces the modified surface condition
///
/// ```text
/// F_j(θ̂) = ṡ_j(θ̂) − [k_j(θ̂)·B(θ̂) + η]·θ̂_j = 0
/// K(θ̂)   = | Σ_j θ̂_j (α_j⁻¹ − 1) φ_j | − η,    φ_j = ∂(Σ_i rate_i z_i ż_i)/∂θ_j
/// ```
///
/// with `ṡ_j` and `B` as in [`SlidingSurface`] and `α_j` from [`ParamSpec::gain_margin`].
/// Per sample the model is linearised in θ at the previous estimate,
/// `ż(θ) = ż(θ̂⁻) + S·(θ − θ̂⁻)` with `S = ∂ż/∂θ`, which is exact for models affine in θ (all
/// thesis models). Then:
/// - [`Reading::Implicit`]: for one parameter, a scan of 128 sub-intervals of the bounds
///   locates every sign change of `F` and the bracket nearest the previous estimate is refined
///   by regula falsi (Illinois); for several parameters a damped Newton iteration with
///   projection onto the bound box, started from the previous estimate (then from the initial
///   guess and the box centre), keeps the least-residual point. No root in the bounds → the
///   least-|F| point is used and counted in [`SolveStats::no_root`].
/// - [`Reading::Explicit`]: `θ̂_j = ṡ_j(θ̂⁻) / D_j` with `D_j = k_j B + η` held at `±η` when
///   `|D_j| < η` (η's stated purpose: no division by ~0), then clamped to the bounds.
///
/// WARNING: with [`GainForm::Shared`] and equal λ_j, `F_1 − F_2 = −D·(θ̂_1 − θ̂_2)`, so two
/// parameters sharing one surface are forced equal whenever `D ≠ 0` (see
/// `docs/reproduction-poc.md`).
#[derive(Debug, Clone)]
pub struct PublishedSmpe<M, const N: usize, const P: usize> {
    model: M,
    cfg: SmpeConfig<N, P>,
    inv_alpha_minus_1: [f64; P],
    estimate: Estimate<P>,
    stats: SolveStats,
}

/// One update of [`PublishedSmpe`] computed but not applied ([`PublishedSmpe::propose`]): the
/// new estimate and counters.
#[derive(Debug, Clone, Copy)]
pub struct PublishedStep<const P: usize> {
    t_s: f64,
    theta: SVector<f64, P>,
    stats: SolveStats,
}

impl<const P: usize> PublishedStep<P> {
    /// The estimate θ̂ once the step is committed.
    pub fn theta(&self) -> &SVector<f64, P> {
        &self.theta
    }
}

/// The per-sample residual, affine-in-θ pieces precomputed.
struct Residual<const N: usize, const P: usize> {
    cfg: SmpeConfig<N, P>,
    c: [f64; P],
    theta0: SVector<f64, P>,
    r0: f64,
    r_lin: SVector<f64, P>,
    l0: f64,
    l_lin: SVector<f64, P>,
    b0: f64,
    b_lin: SVector<f64, P>,
}

impl<const N: usize, const P: usize> Residual<N, P> {
    fn parts(&self, theta: &SVector<f64, P>) -> (f64, f64, f64) {
        let d = theta - self.theta0;
        (self.r0 + self.r_lin.dot(&d), self.l0 + self.l_lin.dot(&d), self.b0 + self.b_lin.dot(&d))
    }

    /// Gains k_j (3.36)/(3.72).
    fn gains(&self, theta: &SVector<f64, P>) -> [f64; P] {
        let eta = self.cfg.eta;
        let g: [f64; P] = core::array::from_fn(|j| theta[j] * self.c[j] * self.r_lin[j]);
        match self.cfg.gain {
            GainForm::Shared => [libm::fabs(g.iter().sum::<f64>()) - eta; P],
            GainForm::PerParameter => g.map(|x| libm::fabs(x) - eta),
        }
    }

    fn eval(&self, theta: &SVector<f64, P>) -> SVector<f64, P> {
        let (r, l, b) = self.parts(theta);
        let k = self.gains(theta);
        SVector::<f64, P>::from_fn(|j, _| {
            r + self.cfg.params[j].lambda * l - (k[j] * b + self.cfg.eta) * theta[j]
        })
    }
}

fn project<const P: usize>(theta: &mut SVector<f64, P>, params: &[ParamSpec; P]) {
    for j in 0..P {
        theta[j] = theta[j].clamp(params[j].lower, params[j].upper);
    }
}

impl<M, const N: usize, const P: usize> PublishedSmpe<M, N, P>
where
    M: ParametricModel<N, P>,
{
    /// A new estimator starting from each parameter's `initial` guess at `t = 0`.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] when η is not finite and positive, a surface weight is
    /// not finite or no state slides, or a parameter's bounds are not finite, ordered and of
    /// one sign (needed by the gain margin (3.32)), λ ≤ 0, or the initial guess is outside.
    pub fn new(model: M, cfg: SmpeConfig<N, P>) -> Result<Self, EstimatorError> {
        if !(cfg.eta.is_finite() && cfg.eta > 0.0) {
            return Err(EstimatorError::InvalidConfig {
                field: "eta",
                value: cfg.eta,
                reason: "must be finite and > 0",
            });
        }
        cfg.surface.validate()?;
        let mut c = [0.0; P];
        for (cj, p) in c.iter_mut().zip(&cfg.params) {
            p.validate(true)?;
            // validate(true) guarantees same-signed bounds, so the margin exists.
            let alpha = p.gain_margin().unwrap_or(1.0);
            *cj = 1.0 / alpha - 1.0;
        }
        let theta = SVector::<f64, P>::from_fn(|j, _| cfg.params[j].initial);
        Ok(Self {
            model,
            cfg,
            inv_alpha_minus_1: c,
            estimate: Estimate::new(0.0, theta),
            stats: SolveStats::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SmpeConfig<N, P> {
        &self.cfg
    }

    /// Counters of the per-sample solve.
    pub fn stats(&self) -> SolveStats {
        self.stats
    }

    /// One update computed from the current state without changing it, counters included,
    /// so that a caller updating several estimators can apply all of them or none
    /// ([`ParametricEstimator::update`] is this and [`PublishedSmpe::commit`]).
    ///
    /// # Errors
    /// As [`ParametricEstimator::update`].
    pub fn propose(
        &self,
        sample: &SmpeSample<N, M::Input>,
    ) -> Result<PublishedStep<P>, EstimatorError> {
        sample.check_finite()?;
        let res = self.residual(sample)?;
        let mut stats = self.stats;
        let theta = match (self.cfg.reading, P) {
            (Reading::Explicit, _) => self.solve_explicit(&res, &mut stats),
            (Reading::Implicit, 1) => self.solve_scalar(&res, &mut stats),
            (Reading::Implicit, _) => self.solve_newton(&res, &mut stats),
        };
        if theta.iter().any(|x| !x.is_finite()) {
            return Err(EstimatorError::Numerical { what: "SMPE estimate", t_s: sample.t_s });
        }
        stats.samples += 1;
        Ok(PublishedStep { t_s: sample.t_s, theta, stats })
    }

    /// Applies a step proposed from the current state ([`PublishedSmpe::propose`]; a step
    /// proposed before another update changed the state must be dropped, not committed).
    pub fn commit(&mut self, step: PublishedStep<P>) {
        self.stats = step.stats;
        self.estimate = Estimate::new(step.t_s, step.theta);
    }

    fn residual(&self, s: &SmpeSample<N, M::Input>) -> Result<Residual<N, P>, EstimatorError> {
        let theta0 = self.estimate.theta;
        let zdot0 = self.model.derivatives(s.t_s, &s.z, &s.u, &theta0)?;
        let sens: SMatrix<f64, N, P> = self.model.sensitivity(s.t_s, &s.z, &s.u, &theta0)?;
        let (e_dot, e) = energy_terms(&s.z, &zdot0, &s.z_m, &s.zdot_m);
        // ∂Ė_i/∂θ_j = z_i S_ij
        let lin = |w: &[f64; N]| {
            SVector::<f64, P>::from_fn(|j, _| (0..N).map(|i| w[i] * s.z[i] * sens[(i, j)]).sum())
        };
        let sf = &self.cfg.surface;
        Ok(Residual {
            cfg: self.cfg,
            c: self.inv_alpha_minus_1,
            theta0,
            r0: weighted(&sf.rate, &e_dot),
            r_lin: lin(&sf.rate),
            l0: weighted(&sf.lambda_energy, &e_dot) + weighted(&sf.lambda_integral, &e),
            l_lin: lin(&sf.lambda_energy),
            b0: weighted(&sf.bracket, &e_dot),
            b_lin: lin(&sf.bracket),
        })
    }

    fn solve_explicit(&self, res: &Residual<N, P>, stats: &mut SolveStats) -> SVector<f64, P> {
        let theta0 = res.theta0;
        let (r, l, b) = res.parts(&theta0);
        let k = res.gains(&theta0);
        let eta = self.cfg.eta;
        let mut out = theta0;
        for j in 0..P {
            let mut d = k[j] * b + eta;
            if libm::fabs(d) < eta || d.is_nan() {
                d = if d < 0.0 { -eta } else { eta };
                stats.guarded += 1;
            }
            let p = &self.cfg.params[j];
            let raw = (r + p.lambda * l) / d;
            let v = if raw.is_finite() { raw } else { theta0[j] };
            if v < p.lower || v > p.upper {
                stats.clamped += 1;
            }
            out[j] = v.clamp(p.lower, p.upper);
        }
        out
    }

    fn solve_scalar(&self, res: &Residual<N, P>, stats: &mut SolveStats) -> SVector<f64, P> {
        const GRID: usize = 128;
        let p = &self.cfg.params[0];
        let (lo, hi) = (p.lower, p.upper);
        let prev = res.theta0[0].clamp(lo, hi);
        let f = |x: f64| res.eval(&SVector::<f64, P>::from_element(x))[0];
        let mut best = (f64::INFINITY, prev);
        let mut bracket: Option<(f64, f64, f64, f64, f64)> = None; // (a, fa, b, fb, distance)
        let mut xa = lo;
        let mut fa = f(xa);
        for k in 1..=GRID {
            let xb = lo + (hi - lo) * (k as f64) / (GRID as f64);
            let fb = f(xb);
            if libm::fabs(fa) < best.0 {
                best = (libm::fabs(fa), xa);
            }
            if fa == 0.0 || fa * fb < 0.0 || (fb == 0.0 && k == GRID) {
                let mid = 0.5 * (xa + xb);
                let dist = libm::fabs(mid - prev);
                if bracket.is_none_or(|b| dist < b.4) {
                    bracket = Some((xa, fa, xb, fb, dist));
                }
            }
            xa = xb;
            fa = fb;
        }
        if libm::fabs(fa) < best.0 {
            best = (libm::fabs(fa), xa);
        }
        let root = match bracket {
            Some((mut a, mut fa, mut b, mut fb, _)) => {
                if fa == 0.0 {
                    a
                } else if fb == 0.0 {
                    b
                } else {
                    // Illinois regula falsi.
                    let mut side = 0i8;
                    let mut x = 0.5 * (a + b);
                    for _ in 0..100 {
                        x = (a * fb - b * fa) / (fb - fa);
                        if !x.is_finite() || x <= a.min(b) || x >= a.max(b) {
                            x = 0.5 * (a + b);
                        }
                        let fx = f(x);
                        if fx == 0.0 || libm::fabs(b - a) < 1e-14 * (hi - lo) {
                            break;
                        }
                        if fx * fb < 0.0 {
                            a = b;
                            fa = fb;
                            if side == -1 {
                                fa *= 0.5;
                            }
                            side = -1;
                        } else {
                            if side == 1 {
                                fa *= 0.5;
                            }
                            side = 1;
                        }
                        b = x;
                        fb = fx;
                    }
                    x
                }
            }
            None => {
                stats.no_root += 1;
                best.1
            }
        };
        SVector::<f64, P>::from_element(root.clamp(lo, hi))
    }

    fn solve_newton(&self, res: &Residual<N, P>, stats: &mut SolveStats) -> SVector<f64, P> {
        let params = &self.cfg.params;
        let scale = 1.0 + libm::fabs(res.r0) + libm::fabs(res.l0) + libm::fabs(res.b0);
        let tol = 1e-10 * scale;
        let norm = |t: &SVector<f64, P>| res.eval(t).norm();
        let mut starts = [res.theta0, res.theta0, res.theta0];
        starts[1] = SVector::<f64, P>::from_fn(|j, _| params[j].initial);
        starts[2] = SVector::<f64, P>::from_fn(|j, _| 0.5 * (params[j].lower + params[j].upper));
        let mut best = (f64::INFINITY, res.theta0);
        for start in starts {
            let mut theta = start;
            project(&mut theta, params);
            let mut fnorm = norm(&theta);
            for _ in 0..40 {
                if fnorm < tol {
                    break;
                }
                let f = res.eval(&theta);
                let mut jac = SMatrix::<f64, P, P>::zeros();
                for k in 0..P {
                    let h = 1e-7 * (params[k].upper - params[k].lower);
                    let mut tp = theta;
                    tp[k] += h;
                    jac.set_column(k, &((res.eval(&tp) - f) / h));
                }
                let step = match solve_linear(jac, -f) {
                    Some(s) if s.iter().all(|x| x.is_finite()) => s,
                    _ => -(jac.transpose() * f) * 1e-3,
                };
                let mut t = 1.0;
                let mut improved = false;
                while t > 1e-6 {
                    let mut cand = theta + step * t;
                    project(&mut cand, params);
                    let cn = norm(&cand);
                    if cn < fnorm {
                        theta = cand;
                        fnorm = cn;
                        improved = true;
                        break;
                    }
                    t *= 0.5;
                }
                if !improved {
                    break;
                }
            }
            if fnorm < best.0 {
                best = (fnorm, theta);
            }
            if best.0 < tol {
                break;
            }
        }
        if best.0.is_nan() || best.0 >= tol {
            stats.no_root += 1;
        }
        best.1
    }
}

impl<M, const N: usize, const P: usize> ParametricEstimator<P> for PublishedSmpe<M, N, P>
where
    M: ParametricModel<N, P>,
{
    type Sample = SmpeSample<N, M::Input>;

    fn param_names(&self) -> [&'static str; P] {
        self.cfg.params.map(|p| p.name)
    }

    fn update(&mut self, sample: &Self::Sample) -> Result<&Estimate<P>, EstimatorError> {
        let step = self.propose(sample)?;
        self.commit(step);
        Ok(&self.estimate)
    }

    fn estimate(&self) -> &Estimate<P> {
        &self.estimate
    }
}

/// Solves `A x = b` by Gaussian elimination with partial pivoting (no allocation, any `P`).
/// `None` when a pivot is below `1e-300` (singular) or the result is not finite.
fn solve_linear<const P: usize>(
    mut a: SMatrix<f64, P, P>,
    mut b: SVector<f64, P>,
) -> Option<SVector<f64, P>> {
    for col in 0..P {
        let piv = (col..P)
            .max_by(|&i, &j| libm::fabs(a[(i, col)]).total_cmp(&libm::fabs(a[(j, col)])))?;
        if libm::fabs(a[(piv, col)]) <= 1e-300 || a[(piv, col)].is_nan() {
            return None;
        }
        a.swap_rows(piv, col);
        b.swap_rows(piv, col);
        for row in col + 1..P {
            let m = a[(row, col)] / a[(col, col)];
            for k in col..P {
                a[(row, k)] -= m * a[(col, k)];
            }
            b[row] -= m * b[col];
        }
    }
    let mut x = SVector::<f64, P>::zeros();
    for row in (0..P).rev() {
        let mut acc = b[row];
        for k in row + 1..P {
            acc -= a[(row, k)] * x[k];
        }
        x[row] = acc / a[(row, row)];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}
