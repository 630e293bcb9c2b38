//! Increments over the vocabulary: a scenario names each true (or estimated) increment with a
//! parameter name of `aeroident_estimators::vocabulary` (`Cm_alpha`, `Cl_p`, `Cn_beta`,
//! `CL_alpha` …) and it acts on the F-16 through the model's increment matrix
//! ([`AeroIncrements`], 6 coefficients × 9 regressors about the trim point).
//!
//! Mapping: coefficient `CL, CD, CY, Cl, Cm, Cn` → the matrix row of the same name; term
//! `0, alpha, beta, p, q, r, de, da, dr` → regressor `1, Δα, Δβ, (b/2V)Δp, (c̄/2V)Δq, (b/2V)Δr,
//! Δδe, Δδa, Δδr`. So an increment `ΔC_k_j` adds `ΔC_k_j · Δξ_j` to `C_k`, Δ about the trim:
//! the local derivative `∂C_k/∂ξ_j` of the aircraft changes by exactly `ΔC_k_j` and the trim
//! point does not move (except for a bias `_0`). Anything else (`CX`, `CZ`, `alphadot`, `V`,
//! `alpha2`, `alpha_de`, `alpha_beta`) has no row or column in the matrix and is rejected with
//! [`IncrementError`].

use aeroident_estimators::vocabulary::{Coefficient, Param, Term};
use aeroident_models::f16::{
    self, AeroCoefficient, AeroIncrements, IncrementReference, IncrementRegressor,
};

/// Why a parameter name cannot be an F-16 increment.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum IncrementError {
    /// The old thesis name (`dCm_alpha` …).
    #[error(
        "`{old}` is the old thesis name; increments are named with the vocabulary: write `{new}`"
    )]
    OldName {
        /// The name given.
        old: String,
        /// The vocabulary name to write instead.
        new: String,
    },
    /// Not `<coefficient>_<term>` of the vocabulary.
    #[error(
        "`{0}` is not a parameter name of the vocabulary (`<coefficient>_<term>`: coefficient CX CY CZ CL CD Cl Cm Cn, term 0 alpha beta p q r alphadot de da dr V alpha2 alpha_de alpha_beta)"
    )]
    Unknown(String),
    /// A vocabulary parameter the F-16 increment matrix cannot express.
    #[error(
        "`{name}`: the F-16 increment matrix has no {what}; increments can act on CL CD CY Cl Cm Cn through the terms 0 alpha beta p q r de da dr"
    )]
    NotExpressible {
        /// The parameter.
        name: &'static str,
        /// What the matrix lacks (e.g. "row for CX", "alphadot regressor").
        what: String,
    },
}

/// The thesis's old increment names and their vocabulary names.
const OLD_NAMES: [(&str, &str); 4] = [
    ("dCm_alpha", "Cm_alpha"),
    ("dCm_q", "Cm_q"),
    ("dCL_alpha", "CL_alpha"),
    ("dCD_alpha", "CD_alpha"),
];

/// Parses an increment name: a vocabulary [`Param`] the increment matrix can express.
///
/// # Errors
/// [`IncrementError`] naming the problem (old name, unknown name, not expressible).
pub fn parse_increment(name: &str) -> Result<Param, IncrementError> {
    if let Some((_, new)) = OLD_NAMES.iter().find(|(o, _)| *o == name) {
        return Err(IncrementError::OldName { old: name.into(), new: (*new).into() });
    }
    if let Some(rest) = name.strip_prefix('d')
        && Param::from_name(rest).is_some()
    {
        return Err(IncrementError::OldName { old: name.into(), new: rest.into() });
    }
    let p = Param::from_name(name).ok_or_else(|| IncrementError::Unknown(name.into()))?;
    slot(p)?;
    Ok(p)
}

/// The increment-matrix cell `(row, column)` of parameter `p`.
///
/// # Errors
/// [`IncrementError::NotExpressible`] for a coefficient or term the matrix lacks.
pub fn slot(p: Param) -> Result<(AeroCoefficient, IncrementRegressor), IncrementError> {
    let row = match p.coefficient {
        Coefficient::CL => AeroCoefficient::CL,
        Coefficient::CD => AeroCoefficient::CD,
        Coefficient::CY => AeroCoefficient::CY,
        Coefficient::Cl => AeroCoefficient::Cl,
        Coefficient::Cm => AeroCoefficient::Cm,
        Coefficient::Cn => AeroCoefficient::Cn,
        Coefficient::CX | Coefficient::CZ => {
            return Err(IncrementError::NotExpressible {
                name: p.name(),
                what: format!("row for {} (use CL/CD, stability axes)", p.coefficient.name()),
            });
        }
    };
    let col = match p.term {
        Term::Bias => IncrementRegressor::Bias,
        Term::Alpha => IncrementRegressor::Alpha,
        Term::Beta => IncrementRegressor::Beta,
        Term::P => IncrementRegressor::PHat,
        Term::Q => IncrementRegressor::QHat,
        Term::R => IncrementRegressor::RHat,
        Term::De => IncrementRegressor::Elevator,
        Term::Da => IncrementRegressor::Aileron,
        Term::Dr => IncrementRegressor::Rudder,
        Term::Alphadot
        | Term::Q0
        | Term::V
        | Term::Alpha2
        | Term::AlphaDe
        | Term::AlphaBeta
        | Term::AlphaP
        | Term::AlphaQ
        | Term::AlphaR
        | Term::AlphaDa
        | Term::AlphaDr
        | Term::AlphaK1
        | Term::AlphaK2
        | Term::AlphaK3
        | Term::AlphaK4
        | Term::Mach
        | Term::Mach2 => {
            return Err(IncrementError::NotExpressible {
                name: p.name(),
                what: format!("`{}` regressor", p.term.name()),
            });
        }
    };
    Ok((row, col))
}

/// Whether `p` is a moment increment (Cl, Cm, Cn: it acts on ṗ, q̇, ṙ) rather than a force
/// increment (CL, CD, CY: it acts on V̇, α̇, β̇).
pub fn is_moment(p: Param) -> bool {
    matches!(p.coefficient, Coefficient::Cl | Coefficient::Cm | Coefficient::Cn)
}

/// The thesis's sliding states of an increment's estimator, as F-16 state indices: `p, q, r`
/// for a moment increment (3.105), `α, V_T, β` for a force increment (3.133).
pub fn sliding_states(p: Param) -> [usize; 3] {
    if is_moment(p) { [f16::P, f16::Q, f16::R] } else { [f16::ALPHA, f16::VT, f16::BETA] }
}

/// The increment matrix about `reference` with `values` set (cells not named are zero).
/// Parameters that cannot be expressed are skipped (callers validate with [`parse_increment`]).
pub fn increment_matrix(reference: IncrementReference, values: &[(Param, f64)]) -> AeroIncrements {
    let mut inc = AeroIncrements { reference, ..AeroIncrements::zero() };
    for &(p, v) in values {
        set(&mut inc, p, v);
    }
    inc
}

/// Sets increment `p` of `inc` to `value` (no effect if `p` is not expressible).
pub fn set(inc: &mut AeroIncrements, p: Param, value: f64) {
    if let Ok((c, r)) = slot(p) {
        inc.set(c, r, value);
    }
}

/// Increment `p` of `inc` (0 if not expressible).
pub fn get(inc: &AeroIncrements, p: Param) -> f64 {
    slot(p).map_or(0.0, |(c, r)| inc.get(c, r))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_old_unknown_and_inexpressible_are_clear_errors() {
        assert_eq!(parse_increment("Cl_p").unwrap().name(), "Cl_p");
        let e = parse_increment("dCm_alpha").unwrap_err().to_string();
        assert!(e.contains("write `Cm_alpha`"), "{e}");
        let e = parse_increment("dCn_beta").unwrap_err().to_string();
        assert!(e.contains("write `Cn_beta`"), "{e}");
        let e = parse_increment("Cm_alphadot").unwrap_err().to_string();
        assert!(e.contains("alphadot") && e.contains("no"), "{e}");
        let e = parse_increment("CX_alpha").unwrap_err().to_string();
        assert!(e.contains("row for CX"), "{e}");
        assert!(matches!(parse_increment("Cm_foo"), Err(IncrementError::Unknown(_))));
    }

    #[test]
    fn matrix_cells_match_the_thesis_constructor() {
        let reference = IncrementReference { alpha_rad: 0.04, ..Default::default() };
        let p = |n| Param::from_name(n).unwrap();
        let ours = increment_matrix(
            reference,
            &[
                (p("Cm_alpha"), 0.0015),
                (p("Cm_q"), 0.01),
                (p("CL_alpha"), 0.01),
                (p("CD_alpha"), 0.001),
            ],
        );
        assert_eq!(ours, AeroIncrements::thesis(reference, 0.0015, 0.01, 0.01, 0.001));
        assert_eq!(get(&ours, p("Cm_q")), 0.01);
    }

    /// At the F-16 level: a ΔCl_p increment changes Cl by exactly ΔCl_p · (b/2V)(p − p_ref)
    /// with the air-relative V, and nothing else; likewise ΔCn_beta, ΔCY_dr and ΔCL_de.
    #[test]
    fn analytic_increments_act_on_the_f16_coefficients_exactly() {
        use aeroident_models::f16::{F16, F16Controls, F16State};
        let f = F16::new(0.30).unwrap();
        let mut x = F16State::zeros();
        x[f16::VT] = 600.0;
        x[f16::ALPHA] = 0.06;
        x[f16::BETA] = 0.02;
        x[f16::P] = 0.3;
        x[f16::Q] = 0.05;
        x[f16::R] = -0.04;
        x[f16::ALT] = 15_000.0;
        x[f16::POW] = 30.0;
        let u = F16Controls::new(0.3, -0.02, 0.01, -0.015);
        let reference = IncrementReference {
            alpha_rad: 0.05,
            beta_rad: 0.0,
            elevator_rad: -0.03,
            rudder_rad: 0.005,
            ..Default::default()
        };
        let p = |n| Param::from_name(n).unwrap();
        let base = f.evaluate(&x, &u, &AeroIncrements::zero()).unwrap().1.coefficients;
        let b = f.data().geometry.span_ft;
        let cases: [(&str, f64, f64); 4] = [
            ("Cl_p", -0.1, b / (2.0 * 600.0) * 0.3),
            ("Cn_beta", 0.04, 0.02),
            ("CY_dr", 0.2, -0.015 - 0.005),
            ("CL_de", 0.5, -0.02 + 0.03),
        ];
        for (name, d, xi) in cases {
            let inc = increment_matrix(reference, &[(p(name), d)]);
            let c = f.evaluate(&x, &u, &inc).unwrap().1.coefficients;
            let diffs = [
                ("CL", c.CL - base.CL),
                ("CY", c.CY - base.CY),
                ("Cl", c.Cl - base.Cl),
                ("Cm", c.Cm - base.Cm),
                ("Cn", c.Cn - base.Cn),
            ];
            for (coef, diff) in diffs {
                // Increments act about the actual cg, after the model's cg transfer: a ΔCY
                // does not move Cn.
                let want = if name.starts_with(&format!("{coef}_")) { d * xi } else { 0.0 };
                assert!((diff - want).abs() < 1e-14, "{name} on {coef}: {diff} vs {want}");
            }
        }
    }
}
