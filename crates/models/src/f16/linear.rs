//! First-order (linear) aerodynamics: the aircraft's coefficients as their value at a reference
//! point plus a constant gradient in the regressors of the linear stability-derivative model
//! (Klein & Morelli, *Aircraft System Identification*, 2006, eq. 5.1–5.6; Etkin & Reid,
//! *Dynamics of Flight*, 3rd ed., §4.4):
//!
//! ```text
//! C_k = C_k(ξ0) + Σ_j (∂C_k/∂ξ_j)(ξ_j − ξ0_j),   k ∈ {CY, CL, CD, Cl, Cm, Cn}
//! ξ = (α, β, p̂ = p b/2V, q̂ = q c̄/2V, r̂ = r b/2V, δe, δa, δr, V/V0)
//! ```
//!
//! with α, β, V the air-relative values (rad, rad, ft/s), p, q, r body rates (rad/s), surface
//! deflections in rad, b the span and c̄ the mean chord (ft). `CL` and `CD` are stability-axis
//! and rotated into body axes through the air-relative α (the inverse of the relation of
//! [`crate::f16::AeroCoefficients`]): `CX = CL sin α − CD cos α`, `CZ = −CL cos α − CD sin α`.
//! `CY, Cl, Cn, Cm` are body-axis, moments about the cg.
//!
//! Built from a table aircraft's local derivatives at its trim, this is the **matched truth**
//! of a linear model structure: every linear-in-parameters estimator whose structure holds
//! these terms has an exact model of it, so its scatter can be compared with the Cramér–Rao
//! bound without the model-structure error of the nonlinear tables.

/// Number of regressors `ξ` ([`LinearAero::regressors`]).
pub const N_LINEAR_REGRESSORS: usize = 9;
/// Regressor names in [`LinearAero::regressors`] order (units: rad, rad, –, –, –, rad, rad,
/// rad, –).
pub const LINEAR_REGRESSOR_NAMES: [&str; N_LINEAR_REGRESSORS] =
    ["alpha", "beta", "p_hat", "q_hat", "r_hat", "de", "da", "dr", "v_over_v0"];
/// Number of modelled coefficients.
pub const N_LINEAR_COEFFICIENTS: usize = 6;
/// Coefficient names in row order of [`LinearAero::gradient`] and [`LinearAero::value`].
pub const LINEAR_COEFFICIENT_NAMES: [&str; N_LINEAR_COEFFICIENTS] =
    ["CY", "CL", "CD", "Cl", "Cm", "Cn"];

/// Linear aerodynamics about a reference point (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearAero {
    /// Reference airspeed V0, ft/s (the `V/V0` regressor's scale); positive and finite.
    pub vt0_fps: f64,
    /// Regressors at the reference point, [`LINEAR_REGRESSOR_NAMES`] order.
    pub reference: [f64; N_LINEAR_REGRESSORS],
    /// Coefficients at the reference point, [`LINEAR_COEFFICIENT_NAMES`] order.
    pub value: [f64; N_LINEAR_COEFFICIENTS],
    /// `∂C_k/∂ξ_j`, `[coefficient][regressor]`, per rad or per unit hat-rate or per unit V/V0.
    pub gradient: [[f64; N_LINEAR_REGRESSORS]; N_LINEAR_COEFFICIENTS],
}

/// The air-relative flight state and controls the linear model reads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearAeroInputs {
    /// Air-relative true airspeed, ft/s (> 0).
    pub vt_fps: f64,
    /// Air-relative angle of attack, rad.
    pub alpha_rad: f64,
    /// Air-relative sideslip, rad.
    pub beta_rad: f64,
    /// Body rates p, q, r, rad/s.
    pub pqr_rad_s: [f64; 3],
    /// Elevator, aileron, rudder deflections, rad.
    pub surfaces_rad: [f64; 3],
}

impl LinearAero {
    /// The regressors `ξ` at `x` for span `span_ft` and mean chord `cbar_ft` (ft).
    pub fn regressors(
        &self,
        x: &LinearAeroInputs,
        span_ft: f64,
        cbar_ft: f64,
    ) -> [f64; N_LINEAR_REGRESSORS] {
        let tv = 0.5 / x.vt_fps;
        let [p, q, r] = x.pqr_rad_s;
        let [de, da, dr] = x.surfaces_rad;
        [
            x.alpha_rad,
            x.beta_rad,
            p * span_ft * tv,
            q * cbar_ft * tv,
            r * span_ft * tv,
            de,
            da,
            dr,
            x.vt_fps / self.vt0_fps,
        ]
    }

    /// The coefficients `[CY, CL, CD, Cl, Cm, Cn]` at `x` (module doc).
    pub fn stability_coefficients(
        &self,
        x: &LinearAeroInputs,
        span_ft: f64,
        cbar_ft: f64,
    ) -> [f64; N_LINEAR_COEFFICIENTS] {
        let xi = self.regressors(x, span_ft, cbar_ft);
        let mut c = self.value;
        for (ck, row) in c.iter_mut().zip(&self.gradient) {
            for ((g, xi), x0) in row.iter().zip(&xi).zip(&self.reference) {
                *ck += g * (xi - x0);
            }
        }
        c
    }

    /// The body-axis coefficients `(CX, CY, CZ, Cl, Cm, Cn)` at `x`: the stability-axis lift
    /// and drag rotated through the air-relative α (module doc).
    pub fn body_coefficients(&self, x: &LinearAeroInputs, span_ft: f64, cbar_ft: f64) -> [f64; 6] {
        let [cy, cl_lift, cd, cl_roll, cm, cn] = self.stability_coefficients(x, span_ft, cbar_ft);
        let (s, c) = x.alpha_rad.sin_cos();
        [cl_lift * s - cd * c, cy, -cl_lift * c - cd * s, cl_roll, cm, cn]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> LinearAero {
        let mut gradient = [[0.0; N_LINEAR_REGRESSORS]; N_LINEAR_COEFFICIENTS];
        for (k, row) in gradient.iter_mut().enumerate() {
            for (j, g) in row.iter_mut().enumerate() {
                *g = 0.1 * (k as f64 + 1.0) - 0.03 * j as f64;
            }
        }
        LinearAero {
            vt0_fps: 600.0,
            reference: [0.04, 0.0, 0.0, 0.0, 0.0, -0.03, 0.0, 0.0, 1.0],
            value: [0.0, 0.4, 0.03, 0.0, 0.0, 0.0],
            gradient,
        }
    }

    /// At the reference point the model returns its reference values; one regressor moved
    /// by h changes each coefficient by gradient × h (hand-computed: p̂ = p b/2V).
    #[test]
    fn value_at_reference_and_gradient_along_one_regressor() {
        let m = model();
        let (b, c) = (30.0, 11.32);
        let at = LinearAeroInputs {
            vt_fps: 600.0,
            alpha_rad: 0.04,
            beta_rad: 0.0,
            pqr_rad_s: [0.0; 3],
            surfaces_rad: [-0.03, 0.0, 0.0],
        };
        assert_eq!(m.stability_coefficients(&at, b, c), m.value);
        let p = 0.2;
        let moved = LinearAeroInputs { pqr_rad_s: [p, 0.0, 0.0], ..at };
        let p_hat = p * b / (2.0 * 600.0);
        let got = m.stability_coefficients(&moved, b, c);
        for (k, g) in got.iter().enumerate() {
            let want = m.value[k] + m.gradient[k][2] * p_hat;
            assert!((g - want).abs() < 1e-15, "coefficient {k}: {g} vs {want}");
        }
    }

    /// Body-axis rotation: `CL = CX sin α − CZ cos α`, `CD = −CX cos α − CZ sin α` recover the
    /// stability-axis values at any α.
    #[test]
    fn body_axes_invert_to_lift_and_drag() {
        let m = model();
        let x = LinearAeroInputs {
            vt_fps: 640.0,
            alpha_rad: 0.12,
            beta_rad: 0.03,
            pqr_rad_s: [0.1, -0.05, 0.02],
            surfaces_rad: [0.01, -0.02, 0.015],
        };
        let st = m.stability_coefficients(&x, 30.0, 11.32);
        let [cx, cy, cz, cl, cm, cn] = m.body_coefficients(&x, 30.0, 11.32);
        let (s, c) = x.alpha_rad.sin_cos();
        assert!((cx * s - cz * c - st[1]).abs() < 1e-15);
        assert!((-cx * c - cz * s - st[2]).abs() < 1e-15);
        assert_eq!([cy, cl, cm, cn], [st[0], st[3], st[4], st[5]]);
    }
}
