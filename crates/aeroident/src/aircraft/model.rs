//! The F-16 as the estimators' model: the four thesis increments (3.100)–(3.101), an adapter
//! implementing the generic engine's [`ParametricModel`] on top of the Stevens–Lewis F-16, the
//! analytic parameter sensitivity and the inverse inertia of (3.114).

use std::cell::Cell;
use std::rc::Rc;

use aeroident_estimators::EstimatorError;
use aeroident_estimators::smpe::ParametricModel;
use aeroident_models::ModelError;
use aeroident_models::f16::{
    self, AeroIncrements, F16, F16Controls, F16State, IncrementReference, N_STATES,
};
use nalgebra::{Matrix3, SMatrix, SVector};

/// The thesis's four unknown increments (3.100), all **per radian**: ΔCm_α per rad of Δα,
/// ΔCm_q per unit of `(c̄/2V_T)Δq`, ΔCL_α and ΔCD_α per rad of Δα.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Increment {
    /// ΔCm_α, pitching moment per rad of Δα.
    CmAlpha,
    /// ΔCm_q, pitching moment per unit `(c̄/2V_T)·Δq`.
    CmQ,
    /// ΔCL_α, lift per rad of Δα.
    CLAlpha,
    /// ΔCD_α, drag per rad of Δα.
    CDAlpha,
}

impl Increment {
    /// All four, in the order of the thesis and of [`Increment::index`].
    pub const ALL: [Increment; 4] =
        [Increment::CmAlpha, Increment::CmQ, Increment::CLAlpha, Increment::CDAlpha];

    /// Name used in scenario files, CSV headers and `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            Increment::CmAlpha => "dCm_alpha",
            Increment::CmQ => "dCm_q",
            Increment::CLAlpha => "dCL_alpha",
            Increment::CDAlpha => "dCD_alpha",
        }
    }

    /// Position in [`Increment::ALL`] and in the `[f64; 4]` increment vectors.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Parses a [`Increment::name`].
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|i| i.name() == s)
    }

    /// The thesis's sliding states of this increment's estimator: `p, q, r` for the pitching
    /// moment (3.105), `α, V_T, β` for lift and drag (3.133), as F-16 state indices.
    pub fn sliding_states(self) -> [usize; 3] {
        match self {
            Increment::CmAlpha | Increment::CmQ => [f16::P, f16::Q, f16::R],
            Increment::CLAlpha | Increment::CDAlpha => [f16::ALPHA, f16::VT, f16::BETA],
        }
    }
}

/// The four increments `[ΔCm_α, ΔCm_q, ΔCL_α, ΔCD_α]` about `reference` as the F-16 model's
/// increment matrix.
pub fn thesis_increments(reference: IncrementReference, values: &[f64; 4]) -> AeroIncrements {
    AeroIncrements::thesis(reference, values[0], values[1], values[2], values[3])
}

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

/// The F-16 seen by an estimator of `P` of the four increments (thesis Figure 3.2: the
/// estimated model has the reference's structure and differs only in the increments).
///
/// `θ` holds the estimated increments in the order of [`F16IncrementModel::estimated`]; the
/// others take the values shared in `current` (the estimated aircraft's increments, written by
/// the other estimators of a combined run; zero when nobody estimates them). The input is the
/// F-16 control vector including the wind the estimator is told about.
#[derive(Debug, Clone)]
pub struct F16IncrementModel<const P: usize> {
    f16: F16,
    reference: IncrementReference,
    estimated: [Increment; P],
    current: Rc<Cell<[f64; 4]>>,
}

impl<const P: usize> F16IncrementModel<P> {
    /// The adapter for the increments `estimated` about `reference` (the trim point).
    pub fn new(
        f16: F16,
        reference: IncrementReference,
        estimated: [Increment; P],
        current: Rc<Cell<[f64; 4]>>,
    ) -> Self {
        Self { f16, reference, estimated, current }
    }

    /// The increments this model's parameters stand for.
    pub fn estimated(&self) -> &[Increment; P] {
        &self.estimated
    }

    fn increments(&self, theta: &SVector<f64, P>) -> AeroIncrements {
        let mut v = self.current.get();
        for (j, inc) in self.estimated.iter().enumerate() {
            v[inc.index()] = theta[j];
        }
        thesis_increments(self.reference, &v)
    }
}

impl<const P: usize> ParametricModel<N_STATES, P> for F16IncrementModel<P> {
    type Input = F16Controls;

    /// SLJ §3.5 state derivatives with the increments (3.100) set to `theta`.
    fn derivatives(
        &self,
        _t_s: f64,
        z: &F16State,
        u: &F16Controls,
        theta: &SVector<f64, P>,
    ) -> Result<F16State, EstimatorError> {
        self.f16.derivatives_with_increments(z, u, &self.increments(theta)).map_err(model_err)
    }

    /// Analytic `∂ż/∂θ` (the model is affine in the increments, so this is exact):
    /// - ΔCm_α, ΔCm_q: `∂q̇/∂ΔCm = c₇ q̄ S c̄ · ξ` (SLJ §3.5 moment equations, `c₇ = 1/I_yy`),
    ///   `ξ = Δα` or `(c̄/2V)Δq`; `ṗ`, `ṙ` do not depend on C_m because `I_xy = I_yz = 0`
    ///   (so `C_p = C_r = 0` in (3.117)).
    /// - ΔCL_α, ΔCD_α: the stability-axis increment rotated into `ΔC_X, ΔC_Z` (as the model
    ///   does), `Δu̇ = q̄S ΔC_X/m`, `Δẇ = q̄S ΔC_Z/m`, then `V̇ = (u u̇ + v v̇ + w ẇ)/V`,
    ///   `α̇ = (u ẇ − w u̇)/(u² + w²)`, `β̇ = (V v̇ − v V̇) cos β/(u² + w²)` differentiated.
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
        let qs = out.qbar_psf * g.wing_area_ft2;
        let d_alpha = out.alpha_air_rad - self.reference.alpha_rad;
        let q_hat = g.cbar_ft * 0.5 / out.vt_air_fps * (z[f16::Q] - self.reference.q_rad_s);
        let (sa, ca) = out.alpha_air_rad.sin_cos();
        let (vt, alpha, beta) = (z[f16::VT], z[f16::ALPHA], z[f16::BETA]);
        let cb = beta.cos();
        let (ub, vb, wb) = (vt * alpha.cos() * cb, vt * beta.sin(), vt * alpha.sin() * cb);
        let dum = ub * ub + wb * wb;
        let rmqs = d.mass.inverse_mass_per_slug * qs;
        let mut s = SMatrix::<f64, N_STATES, P>::zeros();
        for (j, inc) in self.estimated.iter().enumerate() {
            let (dcx, dcz) = match inc {
                Increment::CmAlpha | Increment::CmQ => {
                    let xi = if *inc == Increment::CmAlpha { d_alpha } else { q_hat };
                    s[(f16::Q, j)] = d.moment.c7 * qs * g.cbar_ft * xi;
                    continue;
                }
                Increment::CLAlpha => (sa * d_alpha, -ca * d_alpha),
                Increment::CDAlpha => (-ca * d_alpha, -sa * d_alpha),
            };
            let (dud, dwd) = (rmqs * dcx, rmqs * dcz);
            let dvt = (ub * dud + wb * dwd) / vt;
            s[(f16::VT, j)] = dvt;
            s[(f16::ALPHA, j)] = (ub * dwd - wb * dud) / dum;
            s[(f16::BETA, j)] = -vb * dvt * cb / dum;
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
