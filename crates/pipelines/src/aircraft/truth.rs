//! The reference aircraft's **true local derivatives** at a point (the trim), in the units and
//! axes of the vocabulary, as the oracle the sample-driven estimators are scored against.
//!
//! Method: central finite differences of the F-16's total aerodynamic coefficients
//! (`F16::evaluate` → `CX CY CZ CL CD Cl Cm Cn`, increments included) with respect to one
//! regressor at a time, every other held:
//!
//! | term | perturbed | step |
//! |---|---|---|
//! | `alpha`, `beta` | state α, β (still air: air-relative = state) | `1e-6` rad |
//! | `p`, `q`, `r` | body rate, by `h · 2V/b` (`2V/c̄` for q) so that p̂, q̂, r̂ move by `h` | `h = 1e-6` |
//! | `de`, `da`, `dr` | surface deflection | `1e-6` rad |
//! | `V` | airspeed, by `h · V0` (`V0` = the point's airspeed), α, β and the hat-rates held | `h = 1e-6` |
//!
//! The F-16's tables are piecewise linear (5° in α and β, 12° in δe), so inside a segment the
//! central difference is the table slope to rounding (≈ 1e-10). `alphadot` is 0 exactly: the
//! model's coefficients do not depend on α̇.
//!
//! The α products (`alpha_beta`, `alpha_p`, `alpha_q`, `alpha_r`, `alpha_de`, `alpha_da`,
//! `alpha_dr`) are the mixed second derivative `∂²C/∂α∂ξ`: the central difference, over α ±
//! [`FD_STEP_ALPHA`], of the first derivative w.r.t. `ξ`; `alpha2` is half the second
//! derivative in α. Inside a table segment these are the bilinear cross terms of the tables
//! (the α-dependence of the damping and control derivatives, Stevens & Lewis 2003 table B-4).
//! With products in a structure its first-order parameters are the derivatives at α = 0 (or
//! ξ = 0), not at the point: the true `C_ξ` of such a structure is the local derivative less
//! what the products contribute at the point, `C_ξ = ∂C/∂ξ − Σ_s C_s ∂ξ_s/∂ξ` over the
//! structure's product terms `s` ([`LocalDerivatives::truth`]), e.g. `Cl_p = ∂Cl/∂p̂ −
//! Cl_alpha_p α₀`.
//!
//! The α splines `alpha_k1…alpha_k4` (`(α − k)₊`, knots from the structure) have as truth the
//! jump of the α-slope at their knot, `∂C/∂α(k⁺) − ∂C/∂α(k⁻)`, with every other variable at the
//! point ([`LocalDerivatives::alpha_slope_jump`]). The tables are piecewise linear in α between
//! their α breakpoints (−10…45° by 5°), so the jump is zero except at a breakpoint, where it is
//! taken from one-sided slopes [`FD_STEP_ALPHA`] and twice that away, extrapolated to the
//! breakpoint (the stability-axis rotation of `CL`, `CD` curves the segments slightly). With a
//! spline in a structure, its `C_α` is the slope below every knot the point lies above:
//! `C_α = ∂C/∂α − Σ_{k < α₀} ΔC_α(k)`.
//!
//! `mach` and `mach2` are 0 exactly: the Stevens–Lewis tables are low-speed data with no Mach
//! dependence (SLJ App. A). Their regressors at the point use the vocabulary's speed of sound
//! (the standard temperature of the density altitude,
//! [`aeroident_estimators::sample::AirDataSample::mach`]).
//!
//! Units and axes (as [`aeroident_estimators::vocabulary`]): forces `CX CY CZ` body axes,
//! `CL CD` stability axes with the air-relative α; moments `Cl Cm Cn` body axes about the actual
//! CG (the model's cg transfer included); per rad, per unit p̂ = pb/2V, q̂ = qc̄/2V, r̂ = rb/2V.
//! The bias `C_0` of a structure is the intercept of the tangent plane through the point:
//! `C_0 = C(x₀) − Σ_{j ≠ 0} C_j ξ_j(x₀)` over the structure's terms of that coefficient.

use aeroident_estimators::vocabulary::{Coefficient, ModelStructure, N_TERMS, Param, Term, spline};
use aeroident_models::ModelError;
use aeroident_models::f16::{
    self, AeroCoefficients, AeroIncrements, F16, F16Controls, F16State, IncrementReference,
};
use aeroident_physics::isa;

/// Finite-difference step (rad, or per unit hat-rate / V/V0).
pub const FD_STEP: f64 = 1e-6;

/// The α step of the mixed second derivatives, rad (0.006°: inside any 5° table segment
/// unless the point is that close to a breakpoint; rounding error ≈ 1e-16/(1e-6 · 1e-4)).
pub const FD_STEP_ALPHA: f64 = 1e-4;

/// A knot this close to a table breakpoint, rad, is at it: the model's breakpoints are
/// degrees over the textbook's 57.29578 (≈ 1e-9 rad from `k.to_radians()`).
pub const KNOT_AT_BREAKPOINT_RAD: f64 = 1e-6;

/// The jump of every coefficient's α-slope at one α breakpoint of the model's tables.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlphaKink {
    /// The breakpoint, rad.
    pub alpha_rad: f64,
    /// `∂C/∂α(k⁺) − ∂C/∂α(k⁻)` per rad, vocabulary order `CX CY CZ CL CD Cl Cm Cn`.
    pub jump: [f64; 8],
}

/// The product terms of the vocabulary with their two factors ([`Term::factors`]).
fn products() -> impl Iterator<Item = (Term, Term, Term)> {
    Term::ALL.into_iter().filter_map(|t| t.factors().map(|(a, b)| (t, a, b)))
}

/// The total coefficients of one evaluation in vocabulary order `CX CY CZ CL CD Cl Cm Cn`.
pub fn coefficient_vector(c: &AeroCoefficients) -> [f64; 8] {
    [c.CX, c.CY, c.CZ, c.CL, c.CD, c.Cl, c.Cm, c.Cn]
}

/// Local derivatives of every coefficient w.r.t. every first-order term at one point.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalDerivatives {
    /// Coefficients at the point, vocabulary order.
    pub value: [f64; 8],
    /// Regressor values `ξ_j` at the point (vocabulary units: α, β rad; hats; δ rad; V/V0 = 1;
    /// Mach); `None` for the α splines, whose knots belong to a structure.
    pub regressor: [Option<f64>; N_TERMS],
    /// `∂C_k/∂ξ_j`, `[coefficient][term]`; `None` for the bias and the α splines.
    pub d: [[Option<f64>; N_TERMS]; 8],
    /// The α-slope jumps at the tables' α breakpoints, ascending (module doc).
    pub alpha_kinks: Vec<AlphaKink>,
}

impl LocalDerivatives {
    /// `∂C/∂ξ` of parameter `p` at the point, `½∂²C/∂α²` for `alpha2`, `∂²C/∂α∂ξ` for the other
    /// α products (module doc); `None` for the bias.
    pub fn derivative(&self, p: Param) -> Option<f64> {
        self.d[p.coefficient.index()][p.term.index()]
    }

    /// The true value of parameter `p` within `structure`: the derivative less what the
    /// structure's product terms contribute to it at the point, or for the bias the intercept
    /// of the model through the point over the structure's other terms of that coefficient
    /// (module doc). `None` where no single true value exists.
    pub fn truth(&self, structure: &ModelStructure, p: Param) -> Option<f64> {
        let c = p.coefficient;
        if let Some(i) = p.term.knot() {
            return Some(self.alpha_slope_jump(c, structure.knots().get(i)?));
        }
        if p.term != Term::Bias {
            let mut v = self.derivative(p)?;
            if p.term == Term::Alpha {
                v -= self.spline_slope_at_point(structure, c)?;
            }
            for (s, a, b) in products() {
                if structure.contains(Param::new(c, s)) && (a == p.term || b == p.term) {
                    // ∂(ξa ξb)/∂ξt at the point: the other factor (2 α for α²).
                    let other = if a == p.term { b } else { a };
                    let slope = if a == b { 2.0 } else { 1.0 } * self.regressor[other.index()]?;
                    v -= self.d[c.index()][s.index()]? * slope;
                }
            }
            return Some(v);
        }
        let mut v = self.value[c.index()];
        for t in structure.terms_of(c).filter(|t| *t != Term::Bias) {
            v -= self.truth(structure, Param::new(c, t))? * self.regressor_in(structure, t)?;
        }
        Some(v)
    }

    /// `∂C/∂α(k⁺) − ∂C/∂α(k⁻)` of coefficient `c` at the knot `knot_rad` (module doc): the jump
    /// at a table breakpoint within [`KNOT_AT_BREAKPOINT_RAD`], zero elsewhere.
    pub fn alpha_slope_jump(&self, c: Coefficient, knot_rad: f64) -> f64 {
        self.alpha_kinks
            .iter()
            .find(|k| (k.alpha_rad - knot_rad).abs() <= KNOT_AT_BREAKPOINT_RAD)
            .map_or(0.0, |k| k.jump[c.index()])
    }

    /// What the structure's α splines of `c` add to its α-slope at the point: the jumps at the
    /// knots below the point's α.
    fn spline_slope_at_point(&self, structure: &ModelStructure, c: Coefficient) -> Option<f64> {
        let alpha = self.regressor[Term::Alpha.index()]?;
        let mut v = 0.0;
        for t in structure.terms_of(c) {
            if let Some(i) = t.knot() {
                let k = structure.knots().get(i)?;
                if alpha > k {
                    v += self.alpha_slope_jump(c, k);
                }
            }
        }
        Some(v)
    }

    /// The regressor of term `t` at the point, the α splines with `structure`'s knots.
    fn regressor_in(&self, structure: &ModelStructure, t: Term) -> Option<f64> {
        match t.knot() {
            Some(i) => {
                Some(spline(self.regressor[Term::Alpha.index()]?, structure.knots().get(i)?))
            }
            None => self.regressor[t.index()],
        }
    }
}

/// The true local derivatives of `f16` with increments `inc` at state `x` and controls `u`
/// (module doc), in still air.
///
/// # Errors
/// The model's errors at the point or a perturbed point.
pub fn local_derivatives(
    f16: &F16,
    x: &F16State,
    u: &F16Controls,
    inc: &AeroIncrements,
) -> Result<LocalDerivatives, ModelError> {
    let u = F16Controls { wind_ned_fps: [0.0; 3], wind_body_fps: [0.0; 3], ..*u };
    let g = &f16.data().geometry;
    let value = coefficient_vector(&f16.evaluate(x, &u, inc)?.1.coefficients);
    let mut d = first_order(f16, x, &u, inc)?;
    let alpha_shifted = |sign: f64| {
        let mut xs = *x;
        xs[f16::ALPHA] += sign * FD_STEP_ALPHA;
        first_order(f16, &xs, &u, inc)
    };
    let (dp, dm) = (alpha_shifted(1.0)?, alpha_shifted(-1.0)?);
    for (s, a, b) in products() {
        let half = if a == b { 0.5 } else { 1.0 };
        for (k, row) in d.iter_mut().enumerate() {
            let slope = |d: &[[Option<f64>; N_TERMS]; 8]| d[k][b.index()];
            row[s.index()] =
                slope(&dp).zip(slope(&dm)).map(|(p, m)| half * (p - m) / (2.0 * FD_STEP_ALPHA));
        }
    }
    let vt = x[f16::VT];
    let two_v = 2.0 * vt;
    let mut regressor = [None; N_TERMS];
    regressor[Term::Bias.index()] = Some(1.0);
    regressor[Term::Alpha.index()] = Some(x[f16::ALPHA]);
    regressor[Term::Beta.index()] = Some(x[f16::BETA]);
    regressor[Term::P.index()] = Some(x[f16::P] * g.span_ft / two_v);
    regressor[Term::Q.index()] = Some(x[f16::Q] * g.cbar_ft / two_v);
    regressor[Term::R.index()] = Some(x[f16::R] * g.span_ft / two_v);
    regressor[Term::Alphadot.index()] = Some(0.0);
    regressor[Term::De.index()] = Some(u.elevator_rad);
    regressor[Term::Da.index()] = Some(u.aileron_rad);
    regressor[Term::Dr.index()] = Some(u.rudder_rad);
    regressor[Term::V.index()] = Some(1.0);
    let mach = mach_at(f16, x, &u)?;
    regressor[Term::Mach.index()] = mach;
    regressor[Term::Mach2.index()] = mach.map(|m| m * m);
    for (s, a, b) in products() {
        regressor[s.index()] = regressor[a.index()].zip(regressor[b.index()]).map(|(a, b)| a * b);
    }
    let alpha_kinks = alpha_kinks(f16, x, &u, inc)?;
    Ok(LocalDerivatives { value, regressor, d, alpha_kinks })
}

/// The Mach number at the point as the vocabulary forms it
/// ([`aeroident_estimators::sample::AirDataSample::mach`]): the
/// speed of sound at the standard temperature of the density altitude, `ρ = 2 q̄ / V²`; `None`
/// outside the standard atmosphere's range.
fn mach_at(f16: &F16, x: &F16State, u: &F16Controls) -> Result<Option<f64>, ModelError> {
    use aeroident_physics::units::{M_PER_FT, PA_PER_PSF};
    let o = f16.outputs(0.0, x, u)?;
    let vt = x[f16::VT] * M_PER_FT;
    let rho = 2.0 * o.qbar_psf * PA_PER_PSF / (vt * vt);
    let a = isa::temperature_of_density_k(rho).map(isa::speed_of_sound_mps);
    Ok(a.map(|a| vt / a))
}

/// The α breakpoints of every table of the model's data, rad, ascending, each once.
fn alpha_breakpoints_rad(f16: &F16) -> Vec<f64> {
    let d = f16.data();
    let mut deg: Vec<f64> = [&d.cx.r, &d.cm.r].into_iter().flatten().copied().collect();
    for t in [&d.cl, &d.cn, &d.dlda, &d.dldr, &d.dnda, &d.dndr] {
        deg.extend(t.r);
    }
    deg.extend(d.cz.table.x);
    for t in &d.damping {
        deg.extend(t.x);
    }
    deg.sort_by(f64::total_cmp);
    deg.dedup();
    deg.into_iter().map(|a| a / d.rad_to_deg).collect()
}

/// The α-slope jump of every coefficient at each α breakpoint, every other variable at the
/// point: one-sided slopes at `h` and `2h` from the breakpoint (`h` = [`FD_STEP_ALPHA`])
/// extrapolated to it, `2 s(h) − s(2h)`, so the segments' own curvature cancels.
fn alpha_kinks(
    f16: &F16,
    x: &F16State,
    u: &F16Controls,
    inc: &AeroIncrements,
) -> Result<Vec<AlphaKink>, ModelError> {
    let slope_at = |alpha: f64| -> Result<[f64; 8], ModelError> {
        let (mut xp, mut xm) = (*x, *x);
        xp[f16::ALPHA] = alpha + FD_STEP;
        xm[f16::ALPHA] = alpha - FD_STEP;
        let c = |x: &F16State| {
            f16.evaluate(x, u, inc).map(|(_, o)| coefficient_vector(&o.coefficients))
        };
        let (p, m) = (c(&xp)?, c(&xm)?);
        Ok(core::array::from_fn(|k| (p[k] - m[k]) / (2.0 * FD_STEP)))
    };
    let h = FD_STEP_ALPHA;
    let side = |k: f64, sign: f64| -> Result<[f64; 8], ModelError> {
        let (s1, s2) = (slope_at(k + sign * h)?, slope_at(k + sign * 2.0 * h)?);
        Ok(core::array::from_fn(|i| 2.0 * s1[i] - s2[i]))
    };
    alpha_breakpoints_rad(f16)
        .into_iter()
        .map(|k| {
            let (above, below) = (side(k, 1.0)?, side(k, -1.0)?);
            Ok(AlphaKink { alpha_rad: k, jump: core::array::from_fn(|i| above[i] - below[i]) })
        })
        .collect()
}

/// `∂C_k/∂ξ_j` of the first-order terms at (`x`, `u`), still air (`u` already without wind);
/// the bias and the products `None`.
fn first_order(
    f16: &F16,
    x: &F16State,
    u: &F16Controls,
    inc: &AeroIncrements,
) -> Result<[[Option<f64>; N_TERMS]; 8], ModelError> {
    let g = &f16.data().geometry;
    let coeffs = |x: &F16State, u: &F16Controls| -> Result<[f64; 8], ModelError> {
        f16.evaluate(x, u, inc).map(|(_, o)| coefficient_vector(&o.coefficients))
    };
    let vt = x[f16::VT];
    let h = FD_STEP;
    let mut d = [[None; N_TERMS]; 8];
    let mut put = |term: Term, plus: [f64; 8], minus: [f64; 8], step: f64| {
        for k in 0..8 {
            d[k][term.index()] = Some((plus[k] - minus[k]) / (2.0 * step));
        }
    };
    // State perturbations: (term, state index, state step per unit regressor step).
    let state_terms = [
        (Term::Alpha, f16::ALPHA, 1.0),
        (Term::Beta, f16::BETA, 1.0),
        (Term::P, f16::P, 2.0 * vt / g.span_ft),
        (Term::Q, f16::Q, 2.0 * vt / g.cbar_ft),
        (Term::R, f16::R, 2.0 * vt / g.span_ft),
    ];
    for (term, i, scale) in state_terms {
        let (mut xp, mut xm) = (*x, *x);
        xp[i] += h * scale;
        xm[i] -= h * scale;
        put(term, coeffs(&xp, u)?, coeffs(&xm, u)?, h);
    }
    // Airspeed with the hat-rates held: the body rates scale with V.
    {
        let (mut xp, mut xm) = (*x, *x);
        for (xs, f) in [(&mut xp, 1.0 + h), (&mut xm, 1.0 - h)] {
            xs[f16::VT] = vt * f;
            for i in [f16::P, f16::Q, f16::R] {
                xs[i] = x[i] * f;
            }
        }
        put(Term::V, coeffs(&xp, u)?, coeffs(&xm, u)?, h);
    }
    type Field = fn(&mut F16Controls) -> &mut f64;
    let surfaces: [(Term, Field); 3] = [
        (Term::De, |c| &mut c.elevator_rad),
        (Term::Da, |c| &mut c.aileron_rad),
        (Term::Dr, |c| &mut c.rudder_rad),
    ];
    for (term, field) in surfaces {
        let (mut up, mut um) = (*u, *u);
        *field(&mut up) += h;
        *field(&mut um) -= h;
        put(term, coeffs(x, &up)?, coeffs(x, &um)?, h);
    }
    // The tables depend on neither α̇ nor Mach (low-speed data, SLJ App. A).
    for row in &mut d {
        for t in [Term::Alphadot, Term::Mach, Term::Mach2] {
            row[t.index()] = Some(0.0);
        }
    }
    Ok(d)
}

/// The first-order aerodynamics of the point (`x`, `u`) that `ld` was taken at, as the F-16's
/// linear aerodynamics ([`aeroident_models::f16::Aerodynamics::Linear`]): an increment matrix
/// about that point ([`super::increments::increment_matrix`]) whose bias column holds the
/// point's `CL CD CY Cl Cm Cn` and whose `alpha beta p q r de da dr` columns hold their local
/// derivatives. An aircraft flying it has, everywhere, the local derivatives `ld` has at the
/// point: the matched truth of the linear six-axis structure, exact along the whole flight.
/// The airspeed derivative (`Term::V`) is not carried: the F-16's tables depend on the
/// airspeed only through the hat rates, so it is zero (checked in the tests).
pub fn linearised(ld: &LocalDerivatives, x: &F16State, u: &F16Controls) -> AeroIncrements {
    const COEFFICIENTS: [Coefficient; 6] = [
        Coefficient::CL,
        Coefficient::CD,
        Coefficient::CY,
        Coefficient::Cl,
        Coefficient::Cm,
        Coefficient::Cn,
    ];
    const TERMS: [Term; 8] =
        [Term::Alpha, Term::Beta, Term::P, Term::Q, Term::R, Term::De, Term::Da, Term::Dr];
    let reference = IncrementReference {
        alpha_rad: x[f16::ALPHA],
        beta_rad: x[f16::BETA],
        p_rad_s: x[f16::P],
        q_rad_s: x[f16::Q],
        r_rad_s: x[f16::R],
        elevator_rad: u.elevator_rad,
        aileron_rad: u.aileron_rad,
        rudder_rad: u.rudder_rad,
    };
    let mut values = Vec::with_capacity(COEFFICIENTS.len() * (TERMS.len() + 1));
    for c in COEFFICIENTS {
        values.push((Param::new(c, Term::Bias), ld.value[c.index()]));
        for t in TERMS {
            let p = Param::new(c, t);
            values.push((p, ld.derivative(p).expect("first-order terms have a local value")));
        }
    }
    super::increments::increment_matrix(reference, &values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aircraft::increments::increment_matrix;
    use aeroident_estimators::vocabulary::Coefficient;
    use aeroident_models::f16::IncrementReference;
    use aeroident_models::linearize::linearize_f16;
    use aeroident_models::trim::{TrimCondition, trim};

    fn p(n: &str) -> Param {
        Param::from_name(n).unwrap()
    }

    fn thesis_trim() -> (F16, aeroident_models::trim::F16Trim) {
        let f = F16::new(0.30).unwrap();
        let t = trim(&f, &TrimCondition::level(20_000.0, 675.0)).unwrap();
        (f, t)
    }

    /// Against the F-16's linearisation (an independent central difference of the state
    /// derivatives, `aeroident_models::linearize`): at wings-level trim (p = r = 0) the pitch
    /// equation gives `∂q̇/∂α = c₇ q̄ S c̄ Cm_α`, `∂q̇/∂q = c₇ q̄ S c̄ (c̄/2V) Cm_q`,
    /// `∂q̇/∂δe = c₇ q̄ S c̄ Cm_δe`, and the roll/yaw pair gives Cl and Cn through c₃ c₄ c₉:
    /// `∂ṗ/∂β = q̄Sb (c₃ Cl_β + c₄ Cn_β)`, `∂ṙ/∂β = q̄Sb (c₄ Cl_β + c₉ Cn_β)`.
    #[test]
    fn val_truth_derivatives_match_the_linearisation() {
        let (f, t) = thesis_trim();
        let ld = local_derivatives(&f, &t.state, &t.controls, &AeroIncrements::zero()).unwrap();
        let lin = linearize_f16(&f, &t.state, &t.controls).unwrap();
        let d = f.data();
        let (g, m) = (&d.geometry, &d.moment);
        let o = f.outputs(0.0, &t.state, &t.controls).unwrap();
        let qs = o.qbar_psf * g.wing_area_ft2;
        let (qsc, qsb) = (qs * g.cbar_ft, qs * g.span_ft);
        let vt = t.state[f16::VT];
        let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
        let cm_a = lin.a[(f16::Q, f16::ALPHA)] / (m.c7 * qsc);
        let cm_q = lin.a[(f16::Q, f16::Q)] / (m.c7 * qsc * g.cbar_ft / (2.0 * vt));
        let cm_de = lin.b[(f16::Q, 1)] / (m.c7 * qsc);
        assert!(rel(ld.derivative(p("Cm_alpha")).unwrap(), cm_a) < 1e-5, "{cm_a}");
        assert!(rel(ld.derivative(p("Cm_q")).unwrap(), cm_q) < 1e-5, "{cm_q}");
        assert!(rel(ld.derivative(p("Cm_de")).unwrap(), cm_de) < 1e-5, "{cm_de}");
        // Roll/yaw: solve the 2×2 system of the linearisation for Cl_β, Cn_β (and the p̂, δa, δr
        // columns). ṗ also carries (c₂ p + c₁ r + c₄ h) q terms, zero at q = 0.
        let det = m.c3 * m.c9 - m.c4 * m.c4;
        for (col_p, col_r, scale, cl, cn) in [
            (lin.a[(f16::P, f16::BETA)], lin.a[(f16::R, f16::BETA)], 1.0, "Cl_beta", "Cn_beta"),
            (
                lin.a[(f16::P, f16::P)],
                lin.a[(f16::R, f16::P)],
                g.span_ft / (2.0 * vt),
                "Cl_p",
                "Cn_p",
            ),
            (
                lin.a[(f16::P, f16::R)],
                lin.a[(f16::R, f16::R)],
                g.span_ft / (2.0 * vt),
                "Cl_r",
                "Cn_r",
            ),
            (lin.b[(f16::P, 2)], lin.b[(f16::R, 2)], 1.0, "Cl_da", "Cn_da"),
            (lin.b[(f16::P, 3)], lin.b[(f16::R, 3)], 1.0, "Cl_dr", "Cn_dr"),
        ] {
            let (a, b) = (col_p / (qsb * scale), col_r / (qsb * scale));
            let want_cl = (m.c9 * a - m.c4 * b) / det;
            let want_cn = (m.c3 * b - m.c4 * a) / det;
            let got_cl = ld.derivative(p(cl)).unwrap();
            let got_cn = ld.derivative(p(cn)).unwrap();
            assert!(
                (got_cl - want_cl).abs() < 1e-5 * want_cl.abs().max(1e-3),
                "{cl}: {got_cl} vs {want_cl}"
            );
            assert!(
                (got_cn - want_cn).abs() < 1e-5 * want_cn.abs().max(1e-3),
                "{cn}: {got_cn} vs {want_cn}"
            );
        }
        // Sign sanity (a statically stable, roll-damped, weathercock-stable aircraft).
        assert!(ld.derivative(p("Cm_alpha")).unwrap() < 0.0);
        assert!(ld.derivative(p("Cl_p")).unwrap() < 0.0);
        assert!(ld.derivative(p("Cn_beta")).unwrap() > 0.0);
        assert!(ld.derivative(p("Cn_r")).unwrap() < 0.0);
    }

    /// Against hand-computed table values: CY_β = −0.02/deg (SLJ's CY formula, no α
    /// dependence); Cl_p = the damping table `Clp(α)` interpolated at the trim α by hand; the
    /// increments add exactly their value to the matching derivative.
    #[test]
    fn analytic_table_slopes_and_increments() {
        let (f, t) = thesis_trim();
        let ld = local_derivatives(&f, &t.state, &t.controls, &AeroIncrements::zero()).unwrap();
        let cy_b = ld.derivative(p("CY_beta")).unwrap();
        assert!((cy_b - (-0.02 * 180.0 / core::f64::consts::PI)).abs() < 1e-8, "{cy_b}");
        // Clp row (index 5) of the damping table, α breakpoints −10, −5, 0, 5 … deg.
        let clp = &f.data().damping[5];
        let a_deg = t.state[f16::ALPHA].to_degrees();
        let i = clp.x.iter().rposition(|&x| x <= a_deg).unwrap();
        let w = (a_deg - clp.x[i]) / (clp.x[i + 1] - clp.x[i]);
        let hand = clp.y[i] + w * (clp.y[i + 1] - clp.y[i]);
        assert!((ld.derivative(p("Cl_p")).unwrap() - hand).abs() < 1e-8, "Cl_p vs {hand}");
        // Increments: ΔCl_p = −0.1, ΔCm_alpha = +0.04 change exactly those derivatives.
        let reference = IncrementReference {
            alpha_rad: t.state[f16::ALPHA],
            elevator_rad: t.controls.elevator_rad,
            ..Default::default()
        };
        let inc = increment_matrix(reference, &[(p("Cl_p"), -0.1), (p("Cm_alpha"), 0.04)]);
        let ld2 = local_derivatives(&f, &t.state, &t.controls, &inc).unwrap();
        for name in ["Cl_p", "Cm_alpha", "Cn_r", "CL_alpha"] {
            let want = match name {
                "Cl_p" => -0.1,
                "Cm_alpha" => 0.04,
                _ => 0.0,
            };
            let diff = ld2.derivative(p(name)).unwrap() - ld.derivative(p(name)).unwrap();
            assert!((diff - want).abs() < 1e-8, "{name}: Δ = {diff}");
        }
        // The bias is the intercept: at the point, Σ truth·ξ over a structure reproduces C.
        let st = ModelStructure::longitudinal();
        for c in [Coefficient::CL, Coefficient::Cm] {
            let v: f64 = st
                .terms_of(c)
                .map(|t| {
                    ld.truth(&st, Param::new(c, t)).unwrap() * ld.regressor[t.index()].unwrap()
                })
                .sum();
            assert!((v - ld.value[c.index()]).abs() < 1e-12, "{c:?}");
        }
    }

    /// The α products against the damping table by hand: inside the 0–5° segment the slope
    /// of the `Clp` and `Clr` rows per rad is `Cl_alpha_p` and `Cl_alpha_r`. In a structure
    /// with those products, `Cl_p` is the damping extrapolated to α = 0 (the row's value at 0°
    /// on a linear segment), and the model through the truths reproduces the local derivative
    /// and the coefficient at the point.
    #[test]
    fn alpha_products_are_the_table_cross_slopes() {
        let (f, t) = thesis_trim();
        let ld = local_derivatives(&f, &t.state, &t.controls, &AeroIncrements::zero()).unwrap();
        let a0 = t.state[f16::ALPHA];
        assert!((0.0..5f64.to_radians()).contains(&a0));
        let damping = &f.data().damping;
        let per_rad = |row: usize| (damping[row].y[3] - damping[row].y[2]) / 5f64.to_radians();
        for (name, row) in [("Cl_alpha_p", 5), ("Cl_alpha_r", 4)] {
            let got = ld.derivative(p(name)).unwrap();
            assert!((got - per_rad(row)).abs() < 1e-5, "{name}: {got} vs {}", per_rad(row));
        }
        let st = ModelStructure::lateral()
            .with(Coefficient::Cl, &[Term::AlphaP, Term::AlphaR, Term::AlphaBeta]);
        let cl_p = ld.truth(&st, p("Cl_p")).unwrap();
        assert!((cl_p - damping[5].y[2]).abs() < 1e-5, "Cl_p at α = 0: {cl_p}");
        let local = cl_p + ld.truth(&st, p("Cl_alpha_p")).unwrap() * a0;
        assert!((local - ld.derivative(p("Cl_p")).unwrap()).abs() < 1e-9);
        let v: f64 = st
            .terms_of(Coefficient::Cl)
            .map(|t| {
                let xi = ld.regressor[t.index()].unwrap();
                ld.truth(&st, Param::new(Coefficient::Cl, t)).unwrap() * xi
            })
            .sum();
        assert!((v - ld.value[Coefficient::Cl.index()]).abs() < 1e-12);
        // The linear (matched-truth) aircraft has no cross terms in its moments.
        let lin = f.clone().with_linear_aero(linearised(&ld, &t.state, &t.controls));
        let ll = local_derivatives(&lin, &t.state, &t.controls, &AeroIncrements::zero()).unwrap();
        for n in ["Cl_alpha_p", "Cl_alpha_r", "Cm_alpha_q", "Cn_alpha_dr", "Cl_alpha_beta"] {
            let v = ll.derivative(p(n)).unwrap();
            assert!(v.abs() < 1e-5, "linear aircraft {n} = {v}");
        }
    }

    /// The α splines against the tables themselves: with knots on the 0° and 5° breakpoints,
    /// the body-axis `CX`, `CZ` and `Cm` are linear in α on each 5° segment at the trim's other
    /// variables, so the structure `1, α, (α−0°)₊, (α−5°)₊` through the truths reproduces the
    /// model's own values from −4° to 9°, on both sides of both knots. The stability-axis `CL`
    /// jump is the rotation of the body-axis ones (`−ΔCZ_α cos k + ΔCX_α sin k`); a knot between
    /// breakpoints has no jump; the tables have no Mach term, and the point's Mach is the
    /// standard atmosphere's (675 ft/s at 20,000 ft: 675/1036.9, ICAO table).
    #[test]
    fn alpha_splines_are_the_tables_slope_jumps() {
        use aeroident_estimators::vocabulary::AlphaKnots;
        let (f, t) = thesis_trim();
        let ld = local_derivatives(&f, &t.state, &t.controls, &AeroIncrements::zero()).unwrap();
        let knots = AlphaKnots::new(&[0.0, 5f64.to_radians()]).unwrap();
        let terms = [Term::Alpha, Term::AlphaK1, Term::AlphaK2];
        let mut st = ModelStructure::default().with_knots(knots);
        for c in [Coefficient::CX, Coefficient::CZ, Coefficient::Cm, Coefficient::CL] {
            st = st.with(c, &terms);
        }
        let u = F16Controls { wind_ned_fps: [0.0; 3], wind_body_fps: [0.0; 3], ..t.controls };
        for c in [Coefficient::CX, Coefficient::CZ, Coefficient::Cm] {
            let th = |t: Term| ld.truth(&st, Param::new(c, t)).unwrap();
            assert!(th(Term::AlphaK2).abs() > 1e-3, "{c:?}: the 5° breakpoint has a kink");
            for a_deg in [-4.0, -1.0, 3.0, 7.0, 9.0] {
                let a = f64::to_radians(a_deg);
                let mut x = t.state;
                x[f16::ALPHA] = a;
                let model = coefficient_vector(
                    &f.evaluate(&x, &u, &AeroIncrements::zero()).unwrap().1.coefficients,
                );
                let fit = th(Term::Bias)
                    + th(Term::Alpha) * a
                    + th(Term::AlphaK1) * spline(a, 0.0)
                    + th(Term::AlphaK2) * spline(a, 5f64.to_radians());
                let want = model[c.index()];
                assert!((fit - want).abs() < 1e-7, "{c:?} at {a_deg}°: {fit} vs {want}");
            }
        }
        let k = 5f64.to_radians();
        let jump = |c: Coefficient| ld.alpha_slope_jump(c, k);
        let rotated = -jump(Coefficient::CZ) * k.cos() + jump(Coefficient::CX) * k.sin();
        assert!(
            (jump(Coefficient::CL) - rotated).abs() < 1e-6,
            "CL jump {}",
            jump(Coefficient::CL)
        );
        assert_eq!(ld.alpha_slope_jump(Coefficient::Cm, 7f64.to_radians()), 0.0);
        let with_mach =
            ModelStructure::longitudinal().with(Coefficient::Cm, &[Term::Mach, Term::Mach2]);
        assert_eq!(ld.truth(&with_mach, p("Cm_mach")), Some(0.0));
        assert_eq!(ld.truth(&with_mach, p("Cm_mach2")), Some(0.0));
        let mach = ld.regressor[Term::Mach.index()].unwrap();
        assert!((mach - 675.0 / 1036.9).abs() < 0.003, "Mach {mach}");
    }

    /// The linearised F-16 (matched truth): at trim it has the tables' values and local
    /// derivatives, so the trim holds (ẋ of the trim ≈ 0); 3° of α and 2° of β away its local
    /// derivatives are still the trim's (the model is linear), while the tables' have moved
    /// (Cl_β and Cl_r depend on α: the independent check that the point is off-trim).
    #[test]
    fn linearised_aircraft_keeps_the_trim_derivatives_everywhere() {
        let (f, t) = thesis_trim();
        let zero = AeroIncrements::zero();
        let ld = local_derivatives(&f, &t.state, &t.controls, &zero).unwrap();
        let lin = f.clone().with_linear_aero(linearised(&ld, &t.state, &t.controls));
        for n in ["CL_V", "CD_V", "CY_V", "Cl_V", "Cm_V", "Cn_V"] {
            let v = ld.derivative(p(n)).unwrap();
            assert!(v.abs() < 1e-8, "the tables' {n} = {v}: the linear model would drop it");
        }
        let at_trim = local_derivatives(&lin, &t.state, &t.controls, &zero).unwrap();
        for k in 0..8 {
            assert!((at_trim.value[k] - ld.value[k]).abs() < 1e-12, "value {k}");
        }
        let xd = aeroident_models::Dynamics::derivatives(&lin, 0.0, &t.state, &t.controls).unwrap();
        for i in [f16::VT, f16::ALPHA, f16::BETA, f16::P, f16::Q, f16::R] {
            assert!(xd[i].abs() < 1e-6, "state {i}: {}", xd[i]);
        }
        let mut off = t.state;
        off[f16::ALPHA] += 3f64.to_radians();
        off[f16::BETA] += 2f64.to_radians();
        off[f16::P] += 0.1;
        let far = local_derivatives(&lin, &off, &t.controls, &zero).unwrap();
        let tables_far = local_derivatives(&f, &off, &t.controls, &zero).unwrap();
        let names = ["CY_beta", "CL_alpha", "CD_alpha", "Cl_beta", "Cl_p", "Cl_r", "Cl_da"];
        for n in names.iter().chain(&["Cm_alpha", "Cm_q", "Cm_de", "Cn_beta", "Cn_r", "Cn_dr"]) {
            let (a, b) = (far.derivative(p(n)).unwrap(), ld.derivative(p(n)).unwrap());
            assert!((a - b).abs() < 1e-6 * b.abs().max(1e-2), "{n}: {a} vs trim {b}");
        }
        for n in ["Cl_beta", "Cl_r"] {
            let (a, b) = (tables_far.derivative(p(n)).unwrap(), ld.derivative(p(n)).unwrap());
            assert!((a - b).abs() > 0.05 * b.abs(), "tables' {n} should move off trim: {a} vs {b}");
        }
    }
}
