//! The model-reference gradient estimator of thesis §3.1.1, (3.2)–(3.3)
//! (`spec/thesis-method.md` §4), the comparison method of thesis §4.2.5.
//!
//! The cost is the energy error of the sliding states between the estimated model (state `z`,
//! running with the current estimate) and the reference (measured `z_m`):
//!
//! ```text
//! J(θ̂)        = ½ Σ_i w_i (z_i² − z_m,i²)                                        (3.2)
//! dθ̂_j/dt     = −λ_j Σ_i w_ji (z_i ż_i(θ̂) − z_m,i ż_m,i)                          (3.3)
//! ```
//!
//! For ΔCm_q the thesis uses `p, q, r` as the states; "by the same rule" ΔCm_α uses `p, q, r`
//! and ΔCL_α, ΔCD_α use `α, V_T, β` (the sliding states of their SMPE estimators, §3).
//! The law is integrated with an explicit Euler step over the time between samples and the
//! estimate is clamped to the bounds of its [`ParamSpec`] (the thesis's law has no bounds; the
//! clamp only keeps a diverging run finite and is counted in [`GradientStats::clamped`]).
//!
//! WARNING: (3.3) is not a gradient of a positive-definite cost: `J` changes sign, and
//! `dJ/dt ≈ Σ z_i (∂ż_i/∂θ) θ̃` has the sign of `z_i ∂ż_i/∂θ`, so whether the estimate moves
//! towards or away from the truth depends on the sign of the states and of the sensitivity,
//! not only on λ.
//!
//! [`ParamSpec`]: crate::smpe::ParamSpec
//! [`GradientStats::clamped`]: crate::mrac::GradientStats::clamped

use crate::smpe::{ParamSpec, ParametricModel, SmpeSample, sample_interval_s};
use crate::{Estimate, EstimatorError, ParametricEstimator};
use nalgebra::SVector;

/// Configuration of [`ModelReferenceGradient`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GradientConfig<const N: usize, const P: usize> {
    /// One entry per parameter: name, bounds (clamp), `lambda` = gradient gain λ_j
    /// (parameter units · s / (state units)²·s⁻¹ — i.e. whatever makes (3.3) consistent), and
    /// initial guess.
    pub params: [ParamSpec; P],
    /// Weights `w_ji` (usually 0 or 1) of the sliding states of parameter `j` in (3.2)–(3.3).
    pub states: [[f64; N]; P],
}

/// Counters of the gradient law (for reports; never hidden).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct GradientStats {
    /// Samples processed.
    pub samples: u64,
    /// Parameter updates that left the bounds and were clamped.
    pub clamped: u64,
}

/// One update of [`ModelReferenceGradient`] computed but not applied
/// ([`ModelReferenceGradient::propose`]): the new estimate and how many parameters were clamped.
#[derive(Debug, Clone, Copy)]
pub struct GradientStep<const P: usize> {
    t_s: f64,
    theta: SVector<f64, P>,
    clamped: u64,
}

impl<const P: usize> GradientStep<P> {
    /// The estimate θ̂ once the step is committed.
    pub fn theta(&self) -> &SVector<f64, P> {
        &self.theta
    }
}

/// The model-reference gradient estimator (3.3). `N` model states, `P` parameters.
///
/// Sample: [`SmpeSample`] with `z` the estimated model's state, `z_m`, `ż_m` the measured
/// reference states and derivatives, `u` the common input. The estimated model's derivative
/// `ż(θ̂)` is evaluated with the estimator's [`ParametricModel`] at `z`.
#[derive(Debug, Clone)]
pub struct ModelReferenceGradient<M, const N: usize, const P: usize> {
    model: M,
    cfg: GradientConfig<N, P>,
    last_t_s: Option<f64>,
    estimate: Estimate<P>,
    stats: GradientStats,
}

impl<M, const N: usize, const P: usize> ModelReferenceGradient<M, N, P>
where
    M: ParametricModel<N, P>,
{
    /// A new estimator at each parameter's initial guess.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] when a bound, gain or initial guess is not finite, the
    /// bounds are not ordered, the initial guess is outside them, a gain is not positive, a
    /// state weight is not finite, or a parameter has no sliding state.
    pub fn new(model: M, cfg: GradientConfig<N, P>) -> Result<Self, EstimatorError> {
        for (p, w) in cfg.params.iter().zip(&cfg.states) {
            p.validate(false)?;
            if let Some(x) = w.iter().find(|x| !x.is_finite()) {
                return Err(EstimatorError::InvalidConfig {
                    field: "states",
                    value: *x,
                    reason: "weights must be finite",
                });
            }
            if w.iter().all(|&x| x == 0.0) {
                return Err(EstimatorError::InvalidConfig {
                    field: "states",
                    value: 0.0,
                    reason: "every parameter needs at least one state",
                });
            }
        }
        let theta = SVector::<f64, P>::from_fn(|j, _| cfg.params[j].initial);
        Ok(Self {
            model,
            cfg,
            last_t_s: None,
            estimate: Estimate::new(0.0, theta),
            stats: GradientStats::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &GradientConfig<N, P> {
        &self.cfg
    }

    /// Counters.
    pub fn stats(&self) -> GradientStats {
        self.stats
    }

    /// A new manoeuvre starts with the next sample (a gap in the record): the next sample is
    /// treated as a first one (no time step); θ̂ is kept.
    pub fn new_manoeuvre(&mut self) {
        self.last_t_s = None;
    }

    /// One update computed from the current state without changing it, counters included,
    /// so that a caller updating several estimators can apply all of them or none
    /// ([`ParametricEstimator::update`] is this and [`ModelReferenceGradient::commit`]).
    ///
    /// # Errors
    /// As [`ParametricEstimator::update`].
    pub fn propose(&self, s: &SmpeSample<N, M::Input>) -> Result<GradientStep<P>, EstimatorError> {
        s.check_finite()?;
        let dt = sample_interval_s(self.last_t_s, s.t_s)?;
        let rate = self.cost_rate(s)?;
        let mut theta = self.estimate.theta;
        let mut clamped = 0;
        for j in 0..P {
            let p = &self.cfg.params[j];
            let v = theta[j] - p.lambda * rate[j] * dt;
            if !v.is_finite() {
                return Err(EstimatorError::Numerical { what: "gradient update", t_s: s.t_s });
            }
            if v < p.lower || v > p.upper {
                clamped += 1;
            }
            theta[j] = v.clamp(p.lower, p.upper);
        }
        Ok(GradientStep { t_s: s.t_s, theta, clamped })
    }

    /// Applies a step proposed from the current state ([`ModelReferenceGradient::propose`]; a
    /// step proposed before another update changed the state must be dropped, not committed).
    pub fn commit(&mut self, step: GradientStep<P>) {
        self.stats.samples += 1;
        self.stats.clamped += step.clamped;
        self.last_t_s = Some(step.t_s);
        self.estimate = Estimate::new(step.t_s, step.theta);
    }

    /// The bracket of (3.3) for each parameter, `Σ_i w_ji (z_i ż_i(θ̂) − z_m,i ż_m,i)`, at
    /// the current estimate (`dJ/dt` of (3.2) restricted to the parameter's states).
    ///
    /// # Errors
    /// As the model's [`ParametricModel::derivatives`].
    pub fn cost_rate(
        &self,
        s: &SmpeSample<N, M::Input>,
    ) -> Result<SVector<f64, P>, EstimatorError> {
        let zdot = self.model.derivatives(s.t_s, &s.z, &s.u, &self.estimate.theta)?;
        Ok(SVector::<f64, P>::from_fn(|j, _| {
            (0..N)
                .map(|i| self.cfg.states[j][i] * (s.z[i] * zdot[i] - s.z_m[i] * s.zdot_m[i]))
                .sum()
        }))
    }
}

impl<M, const N: usize, const P: usize> ParametricEstimator<P> for ModelReferenceGradient<M, N, P>
where
    M: ParametricModel<N, P>,
{
    type Sample = SmpeSample<N, M::Input>;

    fn param_names(&self) -> [&'static str; P] {
        self.cfg.params.map(|p| p.name)
    }

    fn update(&mut self, s: &Self::Sample) -> Result<&Estimate<P>, EstimatorError> {
        let step = self.propose(s)?;
        self.commit(step);
        Ok(&self.estimate)
    }

    fn estimate(&self) -> &Estimate<P> {
        &self.estimate
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SMatrix;

    /// ẋ = −a x + u (thesis (2.1)), the estimated model of a first-order system.
    struct FirstOrder;
    impl ParametricModel<1, 1> for FirstOrder {
        type Input = f64;
        fn derivatives(
            &self,
            _t: f64,
            z: &SVector<f64, 1>,
            u: &f64,
            th: &SVector<f64, 1>,
        ) -> Result<SVector<f64, 1>, EstimatorError> {
            Ok(SVector::<f64, 1>::new(-th[0] * z[0] + u))
        }
        fn sensitivity(
            &self,
            _t: f64,
            z: &SVector<f64, 1>,
            _u: &f64,
            _th: &SVector<f64, 1>,
        ) -> Result<SMatrix<f64, 1, 1>, EstimatorError> {
            Ok(SMatrix::<f64, 1, 1>::new(-z[0]))
        }
    }

    fn cfg(lambda: f64, initial: f64) -> GradientConfig<1, 1> {
        GradientConfig {
            params: [ParamSpec { name: "a", lower: -100.0, upper: 100.0, lambda, initial }],
            states: [[1.0]],
        }
    }

    #[test]
    fn analytic_one_euler_step_of_3_3() {
        // Hand computation of (3.3): z = 2, ż(θ̂ = 1) = −1·2 + 0.5 = −1.5; z_m = 1.5, ż_m = 0.3.
        // bracket = 2·(−1.5) − 1.5·0.3 = −3.45; θ̂ ← 1 − λ·dt·(−3.45) = 1 + 0.1·0.01·3.45.
        let mut g = ModelReferenceGradient::new(FirstOrder, cfg(0.1, 1.0)).unwrap();
        let s = |t_s| SmpeSample {
            t_s,
            z: SVector::<f64, 1>::new(2.0),
            z_m: SVector::<f64, 1>::new(1.5),
            zdot_m: SVector::<f64, 1>::new(0.3),
            u: 0.5,
        };
        g.update(&s(0.0)).unwrap();
        assert_eq!(g.estimate().theta[0], 1.0, "first sample: dt = 0, no step");
        let th = g.update(&s(0.01)).unwrap().theta[0];
        assert!((th - (1.0 + 0.1 * 0.01 * 3.45)).abs() < 1e-15, "{th}");
    }

    #[test]
    fn analytic_identical_systems_hold_the_estimate() {
        // Same state and derivative in both systems: the bracket is zero, θ̂ does not move.
        let mut g = ModelReferenceGradient::new(FirstOrder, cfg(1e3, 3.0)).unwrap();
        for k in 0..100 {
            let z = SVector::<f64, 1>::new(0.7);
            let zd = SVector::<f64, 1>::new(-3.0 * 0.7 + 1.0);
            let s = SmpeSample { t_s: k as f64 * 0.01, z, z_m: z, zdot_m: zd, u: 1.0 };
            assert_eq!(g.update(&s).unwrap().theta[0], 3.0);
        }
    }

    /// ẋ = −x + b u with unknown input gain b: `∂ẋ/∂b = u`.
    struct InputGain;
    impl ParametricModel<1, 1> for InputGain {
        type Input = f64;
        fn derivatives(
            &self,
            _t: f64,
            z: &SVector<f64, 1>,
            u: &f64,
            th: &SVector<f64, 1>,
        ) -> Result<SVector<f64, 1>, EstimatorError> {
            Ok(SVector::<f64, 1>::new(-z[0] + th[0] * u))
        }
    }

    /// Runs (3.3) against a truth of the same model with parameter `truth`, input u = 1 from
    /// x = 0 for 20 s; returns the final estimate.
    fn closed_loop<M: ParametricModel<1, 1, Input = f64>>(model: M, truth: f64, start: f64) -> f64 {
        let mut c = cfg(50.0, start);
        c.params[0].lower = 0.5; // keeps the open-loop pole stable if the law runs away
        let mut g = ModelReferenceGradient::new(model, c).unwrap();
        let (mut x, mut xm, dt) = (0.0f64, 0.0f64, 1e-3);
        for k in 0..20_000 {
            let t = k as f64 * dt;
            let th = g.estimate().theta;
            let xmd = g
                .model
                .derivatives(t, &SVector::<f64, 1>::new(xm), &1.0, &SVector::<f64, 1>::new(truth))
                .unwrap()[0];
            let s = SmpeSample {
                t_s: t,
                z: SVector::<f64, 1>::new(x),
                z_m: SVector::<f64, 1>::new(xm),
                zdot_m: SVector::<f64, 1>::new(xmd),
                u: 1.0,
            };
            let xd = g.model.derivatives(t, &s.z, &1.0, &th).unwrap()[0];
            g.update(&s).unwrap();
            x += dt * xd;
            xm += dt * xmd;
        }
        g.estimate().theta[0]
    }

    #[test]
    fn analytic_sign_condition_of_3_3() {
        // Bracket ≈ x·(∂ẋ/∂θ)·θ̃. Input gain: ∂ẋ/∂b = u = 1 and x > 0, so θ̃ decays.
        let b = closed_loop(InputGain, 3.0, 1.0);
        assert!((b - 3.0).abs() < 0.03, "b̂ = {b}");
        // Pole: ∂ẋ/∂a = −x, so x·∂ẋ/∂a = −x² < 0 and (3.3) drives â AWAY from a = 3 (to the
        // lower clamp here): the law is not a descent direction for this system.
        let a = closed_loop(FirstOrder, 3.0, 1.0);
        assert!(a < 1.0, "â = {a} should have moved away from 3");
        assert_eq!(a, 0.5, "runs into the lower clamp");
    }

    #[test]
    fn bad_config_and_samples_are_errors() {
        let mut c = cfg(1.0, 0.0);
        c.states = [[0.0]];
        assert!(ModelReferenceGradient::new(FirstOrder, c).is_err());
        let mut g = ModelReferenceGradient::new(FirstOrder, cfg(1.0, 0.0)).unwrap();
        let z = SVector::<f64, 1>::new(f64::NAN);
        let s = SmpeSample { t_s: 0.0, z, z_m: z, zdot_m: z, u: 0.0 };
        assert!(matches!(g.update(&s), Err(EstimatorError::NonFiniteInput { .. })));
    }
}
