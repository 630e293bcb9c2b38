//! The F-16 as the two-aircraft estimators' model: increments over the vocabulary (thesis
//! (3.100)–(3.101) generalised, [`super::increments`]), an adapter implementing the generic
//! engine's [`ParametricModel`] on top of the Stevens–Lewis F-16, the analytic parameter
//! sensitivity and the inverse inertia of (3.114).

use std::cell::Cell;
use std::rc::Rc;

use aeroident_estimators::EstimatorError;
use aeroident_estimators::smpe::ParametricModel;
use aeroident_estimators::vocabulary::{Coefficient, Param, Term};
use aeroident_models::ModelError;
use aeroident_models::f16::{
    self, AeroIncrements, F16, F16Controls, F16State, IncrementReference, N_STATES,
};

use super::increments;
use nalgebra::{Matrix3, SMatrix, SVector};

/// Converts a model error into the estimator crate's error type (the estimator crate does not
/// know the model crate).
fn model_err(e: ModelError) -> EstimatorError {
    match e {
        ModelError::InvalidValue { field, value, reason } => {
            EstimatorError::InvalidConfig { field, value, reason }
        }
        ModelError::NoConvergence { what, .. } => EstimatorError::Numerical { what, t_s: f64::NAN },
    }
}

/// The F-16 seen by an estimator of `P` increments (thesis Figure 3.2: the estimated model has
/// the reference's structure and differs only in the increments).
///
/// `θ` holds the estimated increments in the order of [`F16IncrementModel::estimated`]; every
/// other cell of the increment matrix takes its value from `current` (the estimated aircraft's
/// increments, written by the other estimators of a combined run; zero when nobody estimates
/// them). The input is the F-16 control vector including the wind the estimator is told about.
#[derive(Debug, Clone)]
pub struct F16IncrementModel<const P: usize> {
    f16: F16,
    reference: IncrementReference,
    estimated: [Param; P],
    current: Rc<Cell<AeroIncrements>>,
}

impl<const P: usize> F16IncrementModel<P> {
    /// The adapter for the increments `estimated` (each expressible, see
    /// [`increments::parse_increment`]) about `reference` (the trim point).
    pub fn new(
        f16: F16,
        reference: IncrementReference,
        estimated: [Param; P],
        current: Rc<Cell<AeroIncrements>>,
    ) -> Self {
        Self { f16, reference, estimated, current }
    }

    /// The increments this model's parameters stand for.
    pub fn estimated(&self) -> &[Param; P] {
        &self.estimated
    }

    fn increments(&self, theta: &SVector<f64, P>) -> AeroIncrements {
        let mut inc = self.current.get();
        inc.reference = self.reference;
        for (j, p) in self.estimated.iter().enumerate() {
            increments::set(&mut inc, *p, theta[j]);
        }
        inc
    }
}

impl<const P: usize> ParametricModel<N_STATES, P> for F16IncrementModel<P> {
    type Input = F16Controls;

    /// SLJ §3.5 state derivatives with the estimated increments (3.100) set to `theta`.
    fn derivatives(
        &self,
        _t_s: f64,
        z: &F16State,
        u: &F16Controls,
        theta: &SVector<f64, P>,
    ) -> Result<F16State, EstimatorError> {
        self.f16.derivatives_with_increments(z, u, &self.increments(theta)).map_err(model_err)
    }

    /// Analytic `∂ż/∂θ` (the model is affine in the increments, so this is exact), with `ξ`
    /// the increment's regressor at `z` ([`AeroIncrements`]: Δα, (c̄/2V)Δq, … air-relative):
    /// - moments (SLJ §3.5 moment equations): `∂q̇/∂ΔCm = c₇ q̄ S c̄ ξ`; `∂ṗ/∂ΔCl = c₃ q̄ S b ξ`,
    ///   `∂ṙ/∂ΔCl = c₄ q̄ S b ξ`; `∂ṗ/∂ΔCn = c₄ q̄ S b ξ`, `∂ṙ/∂ΔCn = c₉ q̄ S b ξ`. Because
    ///   `I_xy = I_yz = 0`, C_m does not reach `ṗ, ṙ` nor Cl, Cn `q̇` (so `C_p = C_r = 0` in
    ///   (3.117)).
    /// - forces: the stability-axis ΔCL, ΔCD rotated into `ΔC_X, ΔC_Z` (as the model does), ΔCY
    ///   along body y; `Δu̇ = q̄S ΔC_X/m`, `Δv̇ = q̄S ΔC_Y/m`, `Δẇ = q̄S ΔC_Z/m`, then
    ///   `V̇ = (u u̇ + v v̇ + w ẇ)/V`, `α̇ = (u ẇ − w u̇)/(u² + w²)`,
    ///   `β̇ = (V v̇ − v V̇) cos β/(u² + w²)` differentiated.
    fn sensitivity(
        &self,
        _t_s: f64,
        z: &F16State,
        u: &F16Controls,
        theta: &SVector<f64, P>,
    ) -> Result<SMatrix<f64, N_STATES, P>, EstimatorError> {
        let (_, out) = self.f16.evaluate(z, u, &self.increments(theta)).map_err(model_err)?;
        let d = self.f16.data();
        let g = &d.geometry;
        let r = &self.reference;
        let qs = out.qbar_psf * g.wing_area_ft2;
        let qsb = qs * g.span_ft;
        let b2v = g.span_ft * (0.5 / out.vt_air_fps);
        let (sa, ca) = out.alpha_air_rad.sin_cos();
        let (vt, alpha, beta) = (z[f16::VT], z[f16::ALPHA], z[f16::BETA]);
        let cb = beta.cos();
        let (ub, vb, wb) = (vt * alpha.cos() * cb, vt * beta.sin(), vt * alpha.sin() * cb);
        let dum = ub * ub + wb * wb;
        let rmqs = d.mass.inverse_mass_per_slug * qs;
        let mc = &d.moment;
        let mut s = SMatrix::<f64, N_STATES, P>::zeros();
        for (j, p) in self.estimated.iter().enumerate() {
            let xi = match p.term {
                Term::Bias => 1.0,
                Term::Alpha => out.alpha_air_rad - r.alpha_rad,
                Term::Beta => out.beta_air_rad - r.beta_rad,
                Term::P => b2v * (z[f16::P] - r.p_rad_s),
                Term::Q => g.cbar_ft * 0.5 / out.vt_air_fps * (z[f16::Q] - r.q_rad_s),
                Term::R => b2v * (z[f16::R] - r.r_rad_s),
                Term::De => u.elevator_rad - r.elevator_rad,
                Term::Da => u.aileron_rad - r.aileron_rad,
                Term::Dr => u.rudder_rad - r.rudder_rad,
                // Not expressible (rejected when the scenario is read): no effect on ż.
                _ => continue,
            };
            let (dcx, dcy, dcz) = match p.coefficient {
                Coefficient::Cm => {
                    s[(f16::Q, j)] = mc.c7 * qs * g.cbar_ft * xi;
                    continue;
                }
                Coefficient::Cl => {
                    s[(f16::P, j)] = mc.c3 * qsb * xi;
                    s[(f16::R, j)] = mc.c4 * qsb * xi;
                    continue;
                }
                Coefficient::Cn => {
                    s[(f16::P, j)] = mc.c4 * qsb * xi;
                    s[(f16::R, j)] = mc.c9 * qsb * xi;
                    continue;
                }
                Coefficient::CL => (sa * xi, 0.0, -ca * xi),
                Coefficient::CD => (-ca * xi, 0.0, -sa * xi),
                Coefficient::CY => (0.0, xi, 0.0),
                Coefficient::CX | Coefficient::CZ => continue,
            };
            let (dud, dvd, dwd) = (rmqs * dcx, rmqs * dcy, rmqs * dcz);
            let dvt = (ub * dud + vb * dvd + wb * dwd) / vt;
            s[(f16::VT, j)] = dvt;
            s[(f16::ALPHA, j)] = (ub * dwd - wb * dud) / dum;
            s[(f16::BETA, j)] = (vt * dvd - vb * dvt) * cb / dum;
        }
        Ok(s)
    }
}

/// Inverse of the F-16 inertia tensor, `[a_ij]` of (3.114), computed from `I_xx, I_yy, I_zz,
/// J_xz` of the data (SLJ §3.5 mass properties; tensor element (1,3) = −J_xz, `I_xy = I_yz =
/// 0`), slug⁻¹·ft⁻². Independent of the model's moment constants `c₁…c₉`.
pub fn inverse_inertia(f16: &F16) -> Matrix3<f64> {
    let m = &f16.data().mass;
    let i = Matrix3::new(
        m.ixx_slug_ft2,
        0.0,
        -m.ixz_slug_ft2,
        0.0,
        m.iyy_slug_ft2,
        0.0,
        -m.ixz_slug_ft2,
        0.0,
        m.izz_slug_ft2,
    );
    // The inertia tensor of a real aircraft is positive definite, so the inverse exists.
    i.try_inverse().unwrap_or_else(Matrix3::zeros)
}
