//! The thesis's sliding-mode estimator (published and corrected, engine in
//! `aeroident_estimators::smpe`) adapted to recorded data, on the pitch axis.
//!
//! **Nominal model and parameters.** A record comes with no aircraft model, so the nominal
//! model is the trim: the measured `Cm` of the first sample. The estimated model is the pitch
//! equation with increments about that trim (thesis (3.100)–(3.101), with Δ about the first
//! sample), sliding state `q` (thesis §3.4, ΔCm_α/ΔCm_q estimator):
//!
//! ```text
//! q̇(θ) = q̇_m − k (Cm_m − Cm_trim) + k (Cm_alpha Δα + Cm_q Δq̂ + Cm_de Δδe),   k = q̄ S c̄ / Iyy
//! ```
//!
//! so `q̇(θ) − q̇_m = k (θᵀΔφ − ΔCm_m)`: the regressors (Δα, Δq̂, Δδe) are the *measured*
//! ones (series-parallel form), and the identified parameters are the full derivatives
//! `Cm_alpha`, `Cm_q`, `Cm_de` (per rad / per unit q̂), not increments on a table. Inertial
//! coupling and thrust moment are kept in the measured `q̇_m` and cancel.
//!
//! Bounds (the thesis's prior, geometric mean of the bounds): `Cm_alpha ∈ [−5, −0.05]`,
//! `Cm_q ∈ [−80, −1]`, `Cm_de ∈ [−5, −0.05]` per rad. λ = 1/s; η = 1e-9 (published);
//! κ = 200/s, γ = 0 (corrected). No standard errors: the methods give none.
//!
//! **WARNING:** with the measured regressors this is an equation-error method; it inherits the
//! equation-error bias on real data (see `docs/real-data.md`).

use super::Prepared;
use super::online::OnlineEstimator;
use aeroident_estimators::smpe::{
    CorrectedConfig, CorrectedSmpe, GainForm, ParamSpec, ParametricModel, PublishedSmpe, Reading,
    SlidingSurface, SmpeConfig, SmpeSample,
};
use aeroident_estimators::{EstimatorError, ParametricEstimator};
use nalgebra::{SMatrix, SVector};

/// Input of the pitch increment model at one sample.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PitchInput {
    /// `k = q̄ S c̄ / Iyy`, 1/s².
    pub k_per_s2: f64,
    /// `(Δα, Δq̂, Δδe)` about the first sample, rad / – / rad.
    pub dphi: [f64; 3],
    /// `q̇_m − k (Cm_m − Cm_trim)`, rad/s².
    pub offset_rad_s2: f64,
}

/// The pitch equation with three derivative parameters (see the module doc).
#[derive(Debug, Clone, Copy, Default)]
pub struct PitchIncrementModel;

impl ParametricModel<1, 3> for PitchIncrementModel {
    type Input = PitchInput;

    fn derivatives(
        &self,
        _t_s: f64,
        _z: &SVector<f64, 1>,
        u: &PitchInput,
        theta: &SVector<f64, 3>,
    ) -> Result<SVector<f64, 1>, EstimatorError> {
        let d = u.dphi;
        Ok(SVector::<f64, 1>::new(
            u.offset_rad_s2 + u.k_per_s2 * (theta[0] * d[0] + theta[1] * d[1] + theta[2] * d[2]),
        ))
    }

    fn sensitivity(
        &self,
        _t_s: f64,
        _z: &SVector<f64, 1>,
        u: &PitchInput,
        _theta: &SVector<f64, 3>,
    ) -> Result<SMatrix<f64, 1, 3>, EstimatorError> {
        let k = u.k_per_s2;
        Ok(SMatrix::<f64, 1, 3>::new(k * u.dphi[0], k * u.dphi[1], k * u.dphi[2]))
    }
}

fn params() -> [ParamSpec; 3] {
    let spec = |name, lower: f64, upper: f64| ParamSpec {
        name,
        lower,
        upper,
        lambda: 1.0,
        initial: ParamSpec::geometric_mean(lower, upper).unwrap_or(0.5 * (lower + upper)),
    };
    [spec("Cm_alpha", -5.0, -0.05), spec("Cm_q", -80.0, -1.0), spec("Cm_de", -5.0, -0.05)]
}

enum Engine {
    Published(PublishedSmpe<PitchIncrementModel, 1, 3>),
    Corrected(CorrectedSmpe<PitchIncrementModel, 1, 3>),
}

/// Which sliding-mode estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SmpeVariant {
    /// The thesis's estimator as published (implicit reading, shared gain).
    Published,
    /// The corrected composite-adaptation estimator.
    Corrected,
}

/// A sliding-mode estimator on recorded pitch data.
pub struct SmpeReplay {
    engine: Engine,
    trim: Option<(f64, f64, f64, f64)>,
    z: f64,
    last_t_s: Option<f64>,
}

impl SmpeReplay {
    /// A new estimator of the given variant.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] from the engine.
    pub fn new(variant: SmpeVariant) -> Result<Self, EstimatorError> {
        let engine = match variant {
            SmpeVariant::Published => Engine::Published(PublishedSmpe::new(
                PitchIncrementModel,
                SmpeConfig {
                    params: params(),
                    eta: 1e-9,
                    surface: SlidingSurface::first_order(&[0])?,
                    gain: GainForm::Shared,
                    reading: Reading::Implicit,
                },
            )?),
            SmpeVariant::Corrected => Engine::Corrected(CorrectedSmpe::new(
                PitchIncrementModel,
                CorrectedConfig {
                    params: params(),
                    sliding: [1.0],
                    lambda_per_s: 1.0,
                    information_per_s: 200.0,
                    tracking_weight: 0.0,
                    forgetting_per_s: 0.0,
                },
            )?),
        };
        Ok(Self { engine, trim: None, z: 0.0, last_t_s: None })
    }

    fn theta(&self) -> SVector<f64, 3> {
        match &self.engine {
            Engine::Published(e) => e.estimate().theta,
            Engine::Corrected(e) => e.estimate().theta,
        }
    }
}

impl OnlineEstimator for SmpeReplay {
    fn names(&self) -> Vec<&'static str> {
        vec!["Cm_alpha", "Cm_q", "Cm_de"]
    }
    fn needs_coefficients(&self) -> bool {
        true
    }
    fn update(&mut self, s: &Prepared) -> Result<(), EstimatorError> {
        let f = &s.flight;
        let (Some(c), Some(qdot)) = (s.coefficients, s.qdot_rad_s2) else {
            return Err(EstimatorError::NonFiniteInput {
                field: "qdot_rad_s2",
                value: f64::NAN,
                t_s: f.t_s,
            });
        };
        let qbar = super::coefficients::qbar_pa(f).unwrap_or(f64::NAN);
        let k = qbar * f.S_m2 * f.cbar_m / f.Iyy_kgm2;
        let (a0, q0, d0, cm0) = *self.trim.get_or_insert((c.alpha_rad, c.qhat, c.de_rad, c.Cm));
        let u = PitchInput {
            k_per_s2: k,
            dphi: [c.alpha_rad - a0, c.qhat - q0, c.de_rad - d0],
            offset_rad_s2: qdot - k * (c.Cm - cm0),
        };
        if self.last_t_s.is_none() {
            self.z = f.q_rad_s;
        }
        let sample = SmpeSample {
            t_s: f.t_s,
            z: SVector::<f64, 1>::new(self.z),
            z_m: SVector::<f64, 1>::new(f.q_rad_s),
            zdot_m: SVector::<f64, 1>::new(qdot),
            u,
        };
        match &mut self.engine {
            Engine::Published(e) => e.update(&sample).map(|_| ())?,
            Engine::Corrected(e) => e.update(&sample).map(|_| ())?,
        }
        // Integrate the estimated model to the next sample (explicit Euler, current estimate).
        let zdot = PitchIncrementModel.derivatives(f.t_s, &sample.z, &u, &self.theta())?[0];
        if let Some(prev) = self.last_t_s {
            let dt = f.t_s - prev;
            self.z += zdot * dt;
        }
        self.last_t_s = Some(f.t_s);
        Ok(())
    }
    fn current(&self, values: &mut [f64], sigmas: &mut [Option<f64>]) {
        let th = self.theta();
        for i in 0..3 {
            values[i] = th[i];
            sigmas[i] = None;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::regressors::CoefficientSample;
    use aeroident_io::FlightSample;

    /// Noise-free pitch data generated from known derivatives: the corrected SMPE recovers them.
    #[test]
    fn analytic_corrected_smpe_recovers_known_pitch_derivatives() {
        let truth = [-1.0, -27.0, -1.4];
        let mut est = SmpeReplay::new(SmpeVariant::Corrected).unwrap();
        let (qbar, s, cbar, iyy) = (4000.0, 30.0, 2.4, 9.0e4);
        let k = qbar * s * cbar / iyy;
        for i in 0..3000 {
            let t = i as f64 * 0.02;
            let alpha = 0.1 + 0.02 * (1.3 * t).sin() + 0.01 * (4.1 * t).sin();
            let qhat = 1e-3 * (2.3 * t).cos() + 4e-4 * (0.7 * t).sin();
            let de = -0.01 + 0.01 * (0.9 * t).sin() + 0.004 * (3.3 * t).cos();
            let cm = 0.05 + truth[0] * alpha + truth[1] * qhat + truth[2] * de;
            let flight = FlightSample {
                t_s: t,
                vt_mps: 100.0,
                alpha_rad: alpha,
                q_rad_s: qhat * 2.0 * 100.0 / cbar,
                qbar_pa: Some(qbar),
                mass_kg: 7000.0,
                Iyy_kgm2: iyy,
                S_m2: s,
                cbar_m: cbar,
                ..Default::default()
            };
            let c = CoefficientSample {
                t_s: t,
                alpha_rad: alpha,
                qhat,
                de_rad: de,
                v_ratio: 1.0,
                Cm: cm,
                CL: 0.0,
                CD: 0.0,
            };
            let p = Prepared {
                flight,
                row: i as u64 + 2,
                qdot_rad_s2: Some(k * cm),
                rho_kgpm3: 0.8,
                alpha_cg_rad: alpha,
                coefficients: Some(c),
            };
            est.update(&p).unwrap();
        }
        let th = est.theta();
        for j in 0..3 {
            assert!(
                (th[j] - truth[j]).abs() < 0.02 * truth[j].abs(),
                "param {j}: {} vs {}",
                th[j],
                truth[j]
            );
        }
    }
}
