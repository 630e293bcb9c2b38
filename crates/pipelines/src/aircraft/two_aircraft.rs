//! The thesis's two-aircraft estimators (Figure 3.2): each channel carries an **estimated F-16**
//! flying with the current estimates of its increments, and engines of the generic SMPE
//! (`aeroident_estimators::smpe`, published and corrected) or of the model-reference gradient
//! law (`aeroident_estimators::mrac`) that compare it with the measured reference aircraft.
//!
//! In a published run the moment increments (Cl, Cm, Cn: sliding states p, q, r) form one
//! engine and each force increment (CL, CD, CY: sliding states α, V_T, β) its own; they share
//! one estimated aircraft, and within a sample each sees the other groups' estimates of the
//! previous sample. Increments are ordered moments first (Cm, Cl, Cn), then forces (CL, CD, CY),
//! term by term — for the thesis's four: ΔCm_α, ΔCm_q, ΔCL_α, ΔCD_α.

use std::cell::Cell;
use std::rc::Rc;

use aeroident_estimators::mrac::{GradientConfig, ModelReferenceGradient};
use aeroident_estimators::smpe::{
    CorrectedConfig, CorrectedSmpe, GainForm, ParamSpec, ParametricModel, PublishedSmpe, Reading,
    SlidingSurface, SmpeConfig, SmpeSample,
};
use aeroident_estimators::vocabulary::{Coefficient, Param};
use aeroident_estimators::{EstimatorError, ParametricEstimator};
use aeroident_models::f16::{
    AeroIncrements, F16, F16Controls, F16State, IncrementReference, N_STATES,
};

use super::increments::{self, is_moment, sliding_states};
use super::model::F16IncrementModel;
use super::scenario::{EstimatorSpec, ReadingSpec, Scenario};
use super::sensors::derivative_sigma;

/// The sample of the two-aircraft engines: estimated state, measured state and derivative,
/// controls.
pub type Sample = SmpeSample<N_STATES, F16Controls>;

/// Diagnostics of one published-SMPE group at one sample (after its update).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PublishedDiagnostics {
    /// Lyapunov gain K (3.128)/(3.153)/(3.159) at the new estimate.
    pub K: f64,
    /// Sliding-surface derivative ṡ of the group's first parameter, (3.106)/(3.134), at the
    /// new estimate.
    pub sdot: f64,
}

/// Ordering key of the two-aircraft increments (module doc).
pub fn thesis_order(p: &Param) -> (usize, usize) {
    let c = match p.coefficient {
        Coefficient::Cm => 0,
        Coefficient::Cl => 1,
        Coefficient::Cn => 2,
        Coefficient::CL => 3,
        Coefficient::CD => 4,
        Coefficient::CY => 5,
        Coefficient::CX => 6,
        Coefficient::CZ => 7,
    };
    (c, p.term.index())
}

/// One estimation engine over some of a channel's increments.
pub trait Engine {
    /// One update.
    ///
    /// # Errors
    /// The estimator's error.
    fn update(&mut self, s: &Sample) -> Result<(), EstimatorError>;
    /// Writes its estimates into the estimated aircraft's increments.
    fn write(&self, out: &mut AeroIncrements);
    /// Published groups: K and ṡ after the update.
    fn diagnostics(&self, _s: &Sample) -> Option<PublishedDiagnostics> {
        None
    }
    /// Solver counters, human-readable.
    fn stats(&self) -> String {
        String::new()
    }
}

struct Published<const P: usize> {
    est: PublishedSmpe<F16IncrementModel<P>, N_STATES, P>,
    model: F16IncrementModel<P>,
}

impl<const P: usize> Engine for Published<P> {
    fn update(&mut self, s: &Sample) -> Result<(), EstimatorError> {
        self.est.update(s).map(|_| ())
    }
    fn write(&self, out: &mut AeroIncrements) {
        for (j, p) in self.model.estimated().iter().enumerate() {
            increments::set(out, *p, self.est.estimate().theta[j]);
        }
    }
    fn diagnostics(&self, s: &Sample) -> Option<PublishedDiagnostics> {
        published_diagnostics(&self.model, self.est.config(), &self.est.estimate().theta, s).ok()
    }
    fn stats(&self) -> String {
        let st = self.est.stats();
        format!(
            "{:?}: samples {}, no_root {}, clamped {}, guarded {}",
            self.model.estimated().map(|p| p.name()),
            st.samples,
            st.no_root,
            st.clamped,
            st.guarded
        )
    }
}

/// K and ṡ of a published-SMPE group at `theta` for sample `s`, computed from the engine's
/// definitions (3.36)/(3.128) and (3.106): `φ_j = Σ_i rate_i z_i ∂ż_i/∂θ_j`,
/// `K = |Σ_j θ_j (μ_j⁻¹ − 1) φ_j| − η`, `ṡ = Σ_i rate_i (z_i ż_i − z_m,i ż_m,i) + λ_0 Σ_i
/// ½ w_i (z_i² − z_m,i²)` (first-order surface).
///
/// # Errors
/// The model's errors.
pub fn published_diagnostics<M: ParametricModel<N_STATES, P>, const P: usize>(
    model: &M,
    cfg: &SmpeConfig<N_STATES, P>,
    theta: &nalgebra::SVector<f64, P>,
    s: &SmpeSample<N_STATES, M::Input>,
) -> Result<PublishedDiagnostics, EstimatorError> {
    let zdot = model.derivatives(s.t_s, &s.z, &s.u, theta)?;
    let sens = model.sensitivity(s.t_s, &s.z, &s.u, theta)?;
    let sf = &cfg.surface;
    let mut k_sum = 0.0;
    for j in 0..P {
        let phi: f64 = (0..N_STATES).map(|i| sf.rate[i] * s.z[i] * sens[(i, j)]).sum();
        let mu = cfg.params[j].gain_margin().unwrap_or(1.0);
        k_sum += theta[j] * (1.0 / mu - 1.0) * phi;
    }
    let mut sdot = 0.0;
    for i in 0..N_STATES {
        let e_dot = s.z[i] * zdot[i] - s.z_m[i] * s.zdot_m[i];
        let e = 0.5 * (s.z[i] * s.z[i] - s.z_m[i] * s.z_m[i]);
        sdot += sf.rate[i] * e_dot
            + cfg.params[0].lambda * (sf.lambda_energy[i] * e_dot + sf.lambda_integral[i] * e);
    }
    Ok(PublishedDiagnostics { K: k_sum.abs() - cfg.eta, sdot })
}

struct Generic<E, const P: usize> {
    est: E,
    params: [Param; P],
}

impl<E: ParametricEstimator<P, Sample = Sample>, const P: usize> Engine for Generic<E, P> {
    fn update(&mut self, s: &Sample) -> Result<(), EstimatorError> {
        self.est.update(s).map(|_| ())
    }
    fn write(&self, out: &mut AeroIncrements) {
        for (j, p) in self.params.iter().enumerate() {
            increments::set(out, *p, self.est.estimate().theta[j]);
        }
    }
}

fn setup_err(what: &str, e: impl std::fmt::Display) -> String {
    format!("setting up `{what}`: {e}")
}

struct Ctx<'a> {
    sc: &'a Scenario,
    f16: F16,
    reference: IncrementReference,
    current: Rc<Cell<AeroIncrements>>,
}

impl Ctx<'_> {
    fn spec(&self, p: Param) -> ParamSpec {
        // Validated: every estimated increment has an [increments] table with bounds.
        let e = self.sc.increment(p);
        let (lower, upper) = e.and_then(|e| e.bounds()).unwrap_or((-1.0, 1.0));
        ParamSpec {
            name: p.name(),
            lower,
            upper,
            lambda: e.map_or(1.0, |e| e.lambda_per_s),
            initial: e.map_or(0.0, |e| e.initial_estimate()),
        }
    }

    fn model<const P: usize>(&self, params: [Param; P]) -> F16IncrementModel<P> {
        F16IncrementModel::new(self.f16.clone(), self.reference, params, self.current.clone())
    }

    fn published<const P: usize>(
        &self,
        params: [Param; P],
        reading: Reading,
    ) -> Result<Box<dyn Engine>, String> {
        let surface = SlidingSurface::first_order(&sliding_states(params[0]))
            .map_err(|e| setup_err("published surface", e))?;
        let eta = params
            .iter()
            .filter_map(|p| self.sc.increment(*p).map(|e| e.eta))
            .fold(f64::INFINITY, f64::min);
        let cfg = SmpeConfig {
            params: params.map(|p| self.spec(p)),
            eta,
            surface,
            gain: GainForm::Shared,
            reading,
        };
        let model = self.model(params);
        let est = PublishedSmpe::new(model.clone(), cfg)
            .map_err(|e| setup_err(&format!("published SMPE {:?}", params.map(|p| p.name())), e))?;
        Ok(Box::new(Published { est, model }))
    }

    fn corrected<const P: usize>(
        &self,
        params: [Param; P],
        spec: &EstimatorSpec,
    ) -> Result<Box<dyn Engine>, String> {
        let EstimatorSpec::Corrected {
            lambda_per_s,
            information_per_s,
            tracking_weight,
            forgetting_per_s,
            ..
        } = *spec
        else {
            return Err(setup_err("corrected", "not a corrected spec"));
        };
        // Rows weighted by 1/σ² of the nominal derivative noise (unit-free information).
        let sig = derivative_sigma(self.sc.dt_s);
        let mut sliding = [0.0; N_STATES];
        for p in params {
            for i in sliding_states(p) {
                sliding[i] = 1.0 / (sig[i] * sig[i]);
            }
        }
        let cfg = CorrectedConfig {
            params: params.map(|p| self.spec(p)),
            sliding,
            lambda_per_s,
            information_per_s,
            tracking_weight,
            forgetting_per_s,
        };
        let est = CorrectedSmpe::new(self.model(params), cfg)
            .map_err(|e| setup_err("corrected SMPE", e))?;
        Ok(Box::new(Generic { est, params }))
    }

    fn gradient<const P: usize>(&self, params: [Param; P]) -> Result<Box<dyn Engine>, String> {
        let mut specs = params.map(|p| self.spec(p));
        for (s, p) in specs.iter_mut().zip(params) {
            s.lambda = self.sc.increment(p).and_then(|e| e.gradient_gain).unwrap_or(1.0);
        }
        let states = params.map(|p| {
            let mut w = [0.0; N_STATES];
            for i in sliding_states(p) {
                w[i] = 1.0;
            }
            w
        });
        let est = ModelReferenceGradient::new(
            self.model(params),
            GradientConfig { params: specs, states },
        )
        .map_err(|e| setup_err("model-reference gradient estimator", e))?;
        Ok(Box::new(Generic { est, params }))
    }
}

fn array<const P: usize>(v: &[Param]) -> [Param; P] {
    core::array::from_fn(|j| v[j])
}

/// One two-aircraft channel: its engines and its estimated aircraft.
pub struct TwoAircraft {
    /// The increments estimated, in [`thesis_order`].
    pub params: Vec<Param>,
    /// `published`, `corrected` or `mr-gradient`.
    pub kind: &'static str,
    /// The engines.
    pub engines: Vec<Box<dyn Engine>>,
    /// The estimated aircraft's increments (shared with the engines' models).
    pub current: Rc<Cell<AeroIncrements>>,
    /// The estimated aircraft's state.
    pub x: F16State,
    /// The estimated aircraft.
    pub f16: F16,
}

/// Builds the channel of a two-aircraft `spec` from the trim state `x0`.
///
/// # Errors
/// A message naming the engine that could not be built.
pub fn build(
    sc: &Scenario,
    spec: &EstimatorSpec,
    f16: &F16,
    reference: IncrementReference,
    x0: &F16State,
) -> Result<TwoAircraft, String> {
    let mut params = spec.param_names().to_vec();
    params.sort_by_key(thesis_order);
    let current = Rc::new(Cell::new(AeroIncrements { reference, ..AeroIncrements::zero() }));
    let ctx = Ctx { sc, f16: f16.clone(), reference, current: current.clone() };
    let mut init = current.get();
    for p in &params {
        increments::set(&mut init, *p, ctx.spec(*p).initial);
    }
    current.set(init);
    let mut engines: Vec<Box<dyn Engine>> = Vec::new();
    let kind = match spec {
        EstimatorSpec::Published { reading, .. } => {
            let reading = match reading {
                ReadingSpec::Implicit => Reading::Implicit,
                ReadingSpec::Explicit => Reading::Explicit,
            };
            let moments: Vec<Param> = params.iter().copied().filter(|p| is_moment(*p)).collect();
            match moments.len() {
                0 => {}
                1 => engines.push(ctx.published::<1>(array(&moments), reading)?),
                2 => engines.push(ctx.published::<2>(array(&moments), reading)?),
                3 => engines.push(ctx.published::<3>(array(&moments), reading)?),
                _ => engines.push(ctx.published::<4>(array(&moments), reading)?),
            }
            for p in params.iter().filter(|p| !is_moment(**p)) {
                engines.push(ctx.published::<1>([*p], reading)?);
            }
            "published"
        }
        EstimatorSpec::Corrected { .. } => {
            engines.push(match params.len() {
                1 => ctx.corrected::<1>(array(&params), spec)?,
                2 => ctx.corrected::<2>(array(&params), spec)?,
                3 => ctx.corrected::<3>(array(&params), spec)?,
                _ => ctx.corrected::<4>(array(&params), spec)?,
            });
            "corrected"
        }
        EstimatorSpec::MrGradient { .. } => {
            engines.push(match params.len() {
                1 => ctx.gradient::<1>(array(&params))?,
                2 => ctx.gradient::<2>(array(&params))?,
                3 => ctx.gradient::<3>(array(&params))?,
                _ => ctx.gradient::<4>(array(&params))?,
            });
            "mr-gradient"
        }
        EstimatorSpec::Sample(_) => return Err("not a two-aircraft estimator".into()),
    };
    Ok(TwoAircraft { params, kind, engines, current, x: *x0, f16: f16.clone() })
}
