//! Additive aerodynamic increments about a reference (trim) point: thesis eq. (3.100)–(3.101),
//! `spec/thesis-method.md` §3, generalised to every coefficient and every regressor.
//!
//! ```text
//! ΔC_k = Σ_j D[k][j] · ξ_j ,   ξ = [1, Δα, Δβ, (b/2V)Δp, (c̄/2V)Δq, (b/2V)Δr, Δδe, Δδa, Δδr]
//! ```
//! with Δ(·) = (·) − (·)_ref, angles and deflections in **radians**, rates in rad/s and `V` the
//! air-relative true airspeed. So every derivative is **per radian** (or per unit nondimensional
//! rate), e.g. the thesis's
//! `Cm = Cm_T + ΔCm_α·Δα + ΔCm_q·(c̄/2V_T)·Δq`, `CL = CL_T + ΔCL_α·Δα`, `CD = CD_T + ΔCD_α·Δα`.
//!
//! **Where they enter** (our decision; the thesis does not say): after the textbook build-up,
//! including its cg transfer, i.e. about the actual cg. ΔCL and ΔCD are stability-axis
//! increments; they are rotated into the body axes with the air-relative α:
//! `ΔCX = ΔCL·sinα − ΔCD·cosα`, `ΔCZ = −ΔCL·cosα − ΔCD·sinα` (stability axes, β ignored, as in
//! SLJ §2.3's stability-axis definition of CL and CD). ΔCY, ΔCl, ΔCm, ΔCn are body-axis.

use nalgebra::SMatrix;

/// Aerodynamic coefficients an increment can act on (row index of [`AeroIncrements::D`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AeroCoefficient {
    /// Lift coefficient CL (stability axes).
    CL = 0,
    /// Drag coefficient CD (stability axes).
    CD = 1,
    /// Side-force coefficient CY (body axes).
    CY = 2,
    /// Rolling-moment coefficient Cl (body axes).
    Cl = 3,
    /// Pitching-moment coefficient Cm (body axes, about the actual cg).
    Cm = 4,
    /// Yawing-moment coefficient Cn (body axes, about the actual cg).
    Cn = 5,
}

/// Regressors an increment multiplies (column index of [`AeroIncrements::D`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IncrementRegressor {
    /// 1: a constant offset ΔC_0.
    Bias = 0,
    /// Δα, rad.
    Alpha = 1,
    /// Δβ, rad.
    Beta = 2,
    /// (b / 2V)·Δp, dimensionless.
    PHat = 3,
    /// (c̄ / 2V)·Δq, dimensionless.
    QHat = 4,
    /// (b / 2V)·Δr, dimensionless.
    RHat = 5,
    /// Δδe, rad.
    Elevator = 6,
    /// Δδa, rad.
    Aileron = 7,
    /// Δδr, rad.
    Rudder = 8,
}

/// Number of coefficients (rows of the increment matrix).
pub const N_COEFFICIENTS: usize = 6;
/// Number of regressors (columns of the increment matrix).
pub const N_REGRESSORS: usize = 9;

/// The reference point Δ(·) is taken about, normally the trim. Radians and rad/s.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct IncrementReference {
    /// α_ref, rad.
    pub alpha_rad: f64,
    /// β_ref, rad.
    pub beta_rad: f64,
    /// p_ref, rad/s.
    pub p_rad_s: f64,
    /// q_ref, rad/s.
    pub q_rad_s: f64,
    /// r_ref, rad/s.
    pub r_rad_s: f64,
    /// δe_ref, rad.
    pub elevator_rad: f64,
    /// δa_ref, rad.
    pub aileron_rad: f64,
    /// δr_ref, rad.
    pub rudder_rad: f64,
}

/// The air-relative flight condition the increments are evaluated at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IncrementInputs {
    /// Air-relative true airspeed, ft/s (> 0).
    pub vt_fps: f64,
    /// Air-relative α, rad.
    pub alpha_rad: f64,
    /// Air-relative β, rad.
    pub beta_rad: f64,
    /// Body roll rate, rad/s.
    pub p_rad_s: f64,
    /// Body pitch rate, rad/s.
    pub q_rad_s: f64,
    /// Body yaw rate, rad/s.
    pub r_rad_s: f64,
    /// Elevator, rad.
    pub elevator_rad: f64,
    /// Aileron, rad.
    pub aileron_rad: f64,
    /// Rudder, rad.
    pub rudder_rad: f64,
}

/// Additive increments `D` (6 coefficients × 9 regressors, per radian) about a `reference`.
/// Zero by default (the nominal textbook aircraft).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AeroIncrements {
    /// The point Δ(·) is measured from.
    pub reference: IncrementReference,
    /// `D[(coefficient, regressor)]`; rows [`AeroCoefficient`], columns [`IncrementRegressor`].
    pub D: SMatrix<f64, N_COEFFICIENTS, N_REGRESSORS>,
}

impl Default for AeroIncrements {
    fn default() -> Self {
        Self::zero()
    }
}

impl AeroIncrements {
    /// No increments (the nominal aircraft).
    pub fn zero() -> Self {
        Self { reference: IncrementReference::default(), D: SMatrix::zeros() }
    }

    /// The thesis's four increments (3.100–3.101) about `reference`, all per radian:
    /// `ΔCm_α` (per rad of Δα), `ΔCm_q` (per unit (c̄/2V)Δq), `ΔCL_α`, `ΔCD_α` (per rad of Δα).
    pub fn thesis(
        reference: IncrementReference,
        dCm_alpha: f64,
        dCm_q: f64,
        dCL_alpha: f64,
        dCD_alpha: f64,
    ) -> Self {
        let mut s = Self { reference, D: SMatrix::zeros() };
        s.set(AeroCoefficient::Cm, IncrementRegressor::Alpha, dCm_alpha);
        s.set(AeroCoefficient::Cm, IncrementRegressor::QHat, dCm_q);
        s.set(AeroCoefficient::CL, IncrementRegressor::Alpha, dCL_alpha);
        s.set(AeroCoefficient::CD, IncrementRegressor::Alpha, dCD_alpha);
        s
    }

    /// Sets one derivative increment (per radian / per unit nondimensional rate).
    pub fn set(&mut self, c: AeroCoefficient, r: IncrementRegressor, value: f64) {
        self.D[(c as usize, r as usize)] = value;
    }

    /// One derivative increment.
    pub fn get(&self, c: AeroCoefficient, r: IncrementRegressor) -> f64 {
        self.D[(c as usize, r as usize)]
    }

    /// True when every increment is zero (the build-up can skip them).
    pub fn is_zero(&self) -> bool {
        self.D.iter().all(|&v| v == 0.0)
    }

    /// The regressor vector ξ at `x` (module doc), dimensionless or rad.
    pub fn regressors(
        &self,
        x: &IncrementInputs,
        span_ft: f64,
        cbar_ft: f64,
    ) -> [f64; N_REGRESSORS] {
        let r = &self.reference;
        let inv2v = 0.5 / x.vt_fps;
        [
            1.0,
            x.alpha_rad - r.alpha_rad,
            x.beta_rad - r.beta_rad,
            span_ft * inv2v * (x.p_rad_s - r.p_rad_s),
            cbar_ft * inv2v * (x.q_rad_s - r.q_rad_s),
            span_ft * inv2v * (x.r_rad_s - r.r_rad_s),
            x.elevator_rad - r.elevator_rad,
            x.aileron_rad - r.aileron_rad,
            x.rudder_rad - r.rudder_rad,
        ]
    }

    /// The coefficient increments `[ΔCL, ΔCD, ΔCY, ΔCl, ΔCm, ΔCn]` at `x`.
    pub fn deltas(&self, x: &IncrementInputs, span_ft: f64, cbar_ft: f64) -> [f64; N_COEFFICIENTS] {
        let xi = self.regressors(x, span_ft, cbar_ft);
        let mut out = [0.0; N_COEFFICIENTS];
        for (k, o) in out.iter_mut().enumerate() {
            *o = (0..N_REGRESSORS).map(|j| self.D[(k, j)] * xi[j]).sum();
        }
        out
    }
}

/// When the increments act: always, or from a time on (a step at `t0_s` models sudden damage).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum IncrementSchedule {
    /// Active at every time.
    #[default]
    Always,
    /// Zero for `t_s < t0_s`, active for `t_s ≥ t0_s`.
    StepAt {
        /// Onset time, s.
        t0_s: f64,
    },
}

impl IncrementSchedule {
    /// Whether the increments act at time `t_s`.
    #[inline]
    pub fn active(&self, t_s: f64) -> bool {
        match *self {
            IncrementSchedule::Always => true,
            IncrementSchedule::StepAt { t0_s } => t_s >= t0_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_thesis_increments_formula() {
        let reference = IncrementReference { alpha_rad: 0.05, q_rad_s: 0.0, ..Default::default() };
        let inc = AeroIncrements::thesis(reference, -0.2, -3.0, 0.5, 0.1);
        let x = IncrementInputs {
            vt_fps: 500.0,
            alpha_rad: 0.07,
            beta_rad: 0.0,
            p_rad_s: 0.0,
            q_rad_s: 0.1,
            r_rad_s: 0.0,
            elevator_rad: 0.0,
            aileron_rad: 0.0,
            rudder_rad: 0.0,
        };
        let d = inc.deltas(&x, 30.0, 11.32);
        let da = 0.02;
        let qhat = 11.32 / 1000.0 * 0.1;
        assert!((d[AeroCoefficient::Cm as usize] - (-0.2 * da - 3.0 * qhat)).abs() < 1e-15);
        assert!((d[AeroCoefficient::CL as usize] - 0.5 * da).abs() < 1e-15);
        assert!((d[AeroCoefficient::CD as usize] - 0.1 * da).abs() < 1e-15);
        assert_eq!(d[AeroCoefficient::CY as usize], 0.0);
        assert!(IncrementSchedule::StepAt { t0_s: 2.0 }.active(2.0));
        assert!(!IncrementSchedule::StepAt { t0_s: 2.0 }.active(1.999));
    }
}
