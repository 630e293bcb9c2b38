//! Identifiability diagnostics of an estimator's final state, from its parameter covariance
//! ([`Estimator::covariance`]): per-coefficient condition numbers and the strongly correlated
//! parameter pairs (Klein & Morelli 2006 §5.4 and ch. 12: pairwise correlations above 0.9 and
//! large condition numbers flag terms the data cannot separate, e.g. `Cm_q` and `Cm_alphadot`
//! in a plain short-period manoeuvre, where α̇ ≈ q).
//!
//! [`identifiability`] adds what the record itself says, independent of the estimator (so it
//! exists for every method): per coefficient the condition number of the scaled information
//! matrix `XᵀX` of its regressors, per parameter an excitation measure (the regressor's
//! standard deviation and its share of the coefficient's variation), the pairs of regressors
//! that are collinear (`|r| > 0.9`), the full correlation matrix of the estimates and the
//! parameters not identified (reported `null`). Summary key `identifiability`.

use super::prediction::Recorder;
use aeroident_estimators::{Coefficient, Estimator, ModelStructure, Term};
use aeroident_io::replay_output::{CoefficientSummary, Correlation};
use aeroident_io::warning::{Warning, WarningKind};
use nalgebra::{DMatrix, SymmetricEigen};
use serde::Serialize;

/// Pairs with `|ρ|` above this are listed.
pub const CORRELATION_THRESHOLD: f64 = 0.9;

/// 2-norm condition number of the correlation matrix of covariance `c` (the covariance scaled
/// to unit diagonal): `λ_max / λ_min`. `None` when a variance is not positive or the matrix is
/// not positive definite.
pub fn scaled_condition_number(c: &DMatrix<f64>) -> Option<f64> {
    let n = c.nrows();
    if n == 0 || (0..n).any(|i| c[(i, i)].is_nan() || c[(i, i)] <= 0.0) {
        return None;
    }
    let r = DMatrix::from_fn(n, n, |i, j| c[(i, j)] / (c[(i, i)] * c[(j, j)]).sqrt());
    let eig = SymmetricEigen::new(r).eigenvalues;
    let lo = eig.min();
    let hi = eig.max();
    (lo > 0.0 && hi.is_finite()).then(|| hi / lo)
}

/// The covariance block of parameters `idx`, if the estimator gives every entry.
fn covariance_block(
    cov: &dyn Fn(usize, usize) -> Option<f64>,
    idx: &[usize],
) -> Option<DMatrix<f64>> {
    let n = idx.len();
    let mut m = DMatrix::zeros(n, n);
    for (a, &i) in idx.iter().enumerate() {
        for (b, &j) in idx.iter().enumerate() {
            m[(a, b)] = cov(i, j)?;
        }
    }
    Some(m)
}

/// Per modelled coefficient, the condition number of its parameters' correlation matrix
/// (`null` when the estimator gives no covariance or a parameter is not identified).
pub fn coefficient_conditions(est: &dyn Estimator) -> Vec<CoefficientSummary> {
    let e = est.estimates();
    let values: Vec<Option<f64>> = (0..e.n).map(|i| e.value(i)).collect();
    conditions_from(est.structure(), &values, &|i, j| est.covariance(i, j))
}

/// [`coefficient_conditions`] from estimates `values` and covariance `cov(i, j)`.
pub fn conditions_from(
    st: &ModelStructure,
    values: &[Option<f64>],
    cov: &dyn Fn(usize, usize) -> Option<f64>,
) -> Vec<CoefficientSummary> {
    st.coefficients()
        .map(|c: Coefficient| {
            let first = st.first_index(c);
            let idx: Vec<usize> = (first..first + st.n_terms(c)).collect();
            let condition_number = if idx.iter().all(|i| values[*i].is_some()) {
                covariance_block(cov, &idx).and_then(|m| scaled_condition_number(&m))
            } else {
                None
            };
            CoefficientSummary { name: c.name().to_string(), condition_number }
        })
        .collect()
}

/// Every pair of identified parameters whose estimates correlate with `|ρ| >`
/// [`CORRELATION_THRESHOLD`], in parameter order.
pub fn strong_correlations(est: &dyn Estimator) -> Vec<Correlation> {
    let e = est.estimates();
    let values: Vec<Option<f64>> = (0..e.n).map(|i| e.value(i)).collect();
    correlations_from(est.structure(), &values, &|i, j| est.covariance(i, j))
}

/// [`strong_correlations`] from estimates `values` and covariance `cov(i, j)`.
pub fn correlations_from(
    st: &ModelStructure,
    values: &[Option<f64>],
    cov: &dyn Fn(usize, usize) -> Option<f64>,
) -> Vec<Correlation> {
    let st = *st;
    let n = st.n_params();
    let mut out = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            if values[i].is_none() || values[j].is_none() {
                continue;
            }
            let (Some(cij), Some(cii), Some(cjj)) = (cov(i, j), cov(i, i), cov(j, j)) else {
                continue;
            };
            if !(cii > 0.0 && cjj > 0.0) {
                continue;
            }
            let rho = cij / (cii * cjj).sqrt();
            if rho.abs() > CORRELATION_THRESHOLD {
                let name = |k: usize| st.param(k).map_or_else(String::new, |p| p.name().into());
                out.push(Correlation { a: name(i), b: name(j), rho });
            }
        }
    }
    out
}

/// The correlation matrix of the estimates (`rho[i][j]`, `null` where a parameter is not
/// identified or the estimator gives no covariance).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CorrelationMatrix {
    /// Parameter names (rows and columns).
    pub names: Vec<String>,
    /// `cov(i,j) / (σ_i σ_j)`.
    pub rho: Vec<Vec<Option<f64>>>,
}

/// What the record says about one coefficient's regressors.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DataCondition {
    /// Coefficient.
    pub name: String,
    /// Samples with the coefficient and all its regressors.
    pub samples: usize,
    /// 2-norm condition number of `XᵀX` scaled to unit diagonal (`null`: singular, e.g. a
    /// regressor that is identically zero); > 10³ flags terms the data cannot separate.
    pub data_condition_number: Option<f64>,
}

/// Excitation of one parameter's regressor over the record.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Excitation {
    /// Parameter name.
    pub parameter: String,
    /// Standard deviation of the regressor `ξ_j` (its unit: rad, nondimensional rate …;
    /// 0 for a bias).
    pub regressor_std: f64,
    /// `|θ_j| std(ξ_j) / std(C)`: the part of the measured coefficient's variation this term
    /// explains at the final estimate (`null` if not identified or `C` constant). Terms
    /// below ≈ 0.05 are barely excited: their estimates rest on little information.
    pub contribution: Option<f64>,
}

/// Identifiability of the model on the record (module doc).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Identifiability {
    /// Per coefficient, the data condition number.
    pub coefficients: Vec<DataCondition>,
    /// Per parameter, the excitation.
    pub excitation: Vec<Excitation>,
    /// Regressor pairs of the same coefficient with sample correlation `|r| > 0.9` (mean
    /// removed; biases excluded): terms the data cannot separate whatever the method.
    pub collinear_regressors: Vec<Correlation>,
    /// The estimates' correlation matrix.
    pub correlation_matrix: CorrelationMatrix,
    /// Parameters not identified at the end (reported `null`).
    pub not_identified: Vec<String>,
}

/// The correlation matrix of estimates `values` (structure order, `None` = not identified)
/// with covariance `cov(i, j)`.
pub fn correlation_matrix(
    st: &ModelStructure,
    values: &[Option<f64>],
    cov: &dyn Fn(usize, usize) -> Option<f64>,
) -> CorrelationMatrix {
    let n = st.n_params();
    let rho = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    if values[i].is_none() || values[j].is_none() {
                        return None;
                    }
                    let (cij, cii, cjj) = (cov(i, j)?, cov(i, i)?, cov(j, j)?);
                    let r = cij / (cii * cjj).sqrt();
                    (cii > 0.0 && cjj > 0.0 && r.is_finite()).then_some(r)
                })
                .collect()
        })
        .collect();
    CorrelationMatrix { names: st.names().map(String::from).collect(), rho }
}

fn mean_std(x: &[f64]) -> (f64, f64) {
    let n = x.len().max(1) as f64;
    let m = x.iter().sum::<f64>() / n;
    (m, (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / n).sqrt())
}

/// The record-based measures and the estimates' correlation matrix (module doc). `values`:
/// the final estimates, structure order; `cov(i, j)` their covariance.
pub fn identifiability(
    st: &ModelStructure,
    cov: &dyn Fn(usize, usize) -> Option<f64>,
    rec: &Recorder,
    values: &[Option<f64>],
) -> Identifiability {
    let st: ModelStructure = *st;
    let mut coefficients = Vec::new();
    let mut excitation = Vec::new();
    let mut collinear_regressors = Vec::new();
    for c in st.coefficients() {
        let first = st.first_index(c);
        let terms: Vec<Term> = st.terms_of(c).collect();
        let rows = rec.rows_for(&st, c);
        let x: Vec<Vec<f64>> = terms.iter().map(|t| rec.term_series(*t, &rows)).collect();
        let y = rec.coef_series(c, &rows);
        let p = terms.len();
        let info = DMatrix::from_fn(p, p, |a, b| x[a].iter().zip(&x[b]).map(|(u, v)| u * v).sum());
        let data_condition_number = if rows.len() > p {
            let inv = info.clone().try_inverse();
            inv.and_then(|m| scaled_condition_number(&m))
        } else {
            None
        };
        coefficients.push(DataCondition {
            name: c.name().into(),
            samples: rows.len(),
            data_condition_number,
        });
        let (_, y_std) = mean_std(&y);
        let stats: Vec<(f64, f64)> = x.iter().map(|v| mean_std(v)).collect();
        for (j, t) in terms.iter().enumerate() {
            let name = st.param(first + j).map_or(String::new(), |q| q.name().to_string());
            let contribution = values[first + j]
                .filter(|_| y_std > 0.0 && !rows.is_empty())
                .map(|v| v.abs() * stats[j].1 / y_std);
            excitation.push(Excitation {
                parameter: name.clone(),
                regressor_std: if rows.is_empty() { 0.0 } else { stats[j].1 },
                contribution,
            });
            for k in j + 1..p {
                if *t == Term::Bias || terms[k] == Term::Bias {
                    continue;
                }
                let (sj, sk) = (stats[j].1, stats[k].1);
                if !(sj > 0.0 && sk > 0.0) {
                    continue;
                }
                let cov = x[j]
                    .iter()
                    .zip(&x[k])
                    .map(|(a, b)| (a - stats[j].0) * (b - stats[k].0))
                    .sum::<f64>()
                    / rows.len() as f64;
                let r = cov / (sj * sk);
                if r.abs() > CORRELATION_THRESHOLD {
                    let other = st.param(first + k).map_or(String::new(), |q| q.name().into());
                    collinear_regressors.push(Correlation { a: name.clone(), b: other, rho: r });
                }
            }
        }
    }
    let not_identified = (0..st.n_params())
        .filter(|i| values[*i].is_none())
        .filter_map(|i| st.param(i).map(|p| p.name().to_string()))
        .collect();
    Identifiability {
        coefficients,
        excitation,
        collinear_regressors,
        correlation_matrix: correlation_matrix(&st, values, cov),
        not_identified,
    }
}

/// The primary control derivatives whose sign the mapping's surface conventions fix for a
/// conventional (tail-aft) aircraft (docs/mapping.md, Channels): `de` > 0 trailing edge down
/// gives `Cm_de` < 0, `da` > 0 right aileron trailing edge down gives `Cl_da` < 0, `dr` > 0
/// trailing edge left gives `Cn_dr` < 0: each positive deflection a negative moment (Stevens &
/// Lewis, Jategaonkar). (parameter, expected sign, surface key, its convention).
pub(crate) const CONTROL_SIGNS: [(&str, f64, &str, &str); 3] = [
    ("Cm_de", -1.0, "de", "> 0 trailing edge down"),
    ("Cl_da", -1.0, "da", "> 0 right aileron trailing edge down, rolling left"),
    ("Cn_dr", -1.0, "dr", "> 0 trailing edge left"),
];

/// A warning for each identified parameter whose sign a conventional stable aircraft does not
/// have ([`aeroident_estimators::prior::expected_sign`]: positive `Cm_q`, `Cl_p`, `Cn_r`,
/// `Cm_alpha` … ; Klein & Morelli 2006 ch. 3), and for each primary control derivative whose
/// sign contradicts the mapping's surface convention (`CONTROL_SIGNS`: most often a surface
/// mapped with the wrong sign; a canard or other unconventional layout can explain it) by more
/// than 2σ (`sigmas`, one per value; an unexcited surface's derivative near 0 is not a sign).
pub fn sign_warnings(
    st: &ModelStructure,
    values: &[Option<f64>],
    sigmas: &[Option<f64>],
) -> Vec<Warning> {
    let mut out = Vec::new();
    for (i, v) in values.iter().enumerate() {
        let (Some(v), Some(param)) = (*v, st.param(i)) else { continue };
        let significant = sigmas.get(i).copied().flatten().is_none_or(|s| v.abs() > 2.0 * s);
        if let Some((_, sign, key, convention)) =
            CONTROL_SIGNS.iter().find(|(name, ..)| *name == param.name())
            && v * sign < 0.0
            && significant
        {
            let text = format!(
                "{} = {v:+.4} has the sign a conventional aircraft does not have under the mapping's convention for `{key}` ({convention}; expected {}): check the sign (`scale = -1`) of `{key}` in the mapping (docs/mapping.md)",
                param.name(),
                if *sign > 0.0 { "> 0" } else { "< 0" }
            );
            out.push(Warning::new(WarningKind::Sign, text).about(param.name()));
        }
        if let Some(sign) = aeroident_estimators::prior::expected_sign(param)
            && v * sign < 0.0
        {
            let text = format!(
                "{} = {v:+.4} has the sign a conventional stable aircraft does not have (expected {}): check the record's sign conventions, the excitation and the correlations",
                param.name(),
                if sign > 0.0 { "> 0" } else { "< 0" }
            );
            out.push(Warning::new(WarningKind::Sign, text).about(param.name()));
        }
    }
    out
}

/// The warning of two regressors the record cannot separate (the identifiability's
/// collinear pair `c`).
pub fn collinear_warning(c: &Correlation) -> Warning {
    let text = format!(
        "collinear regressors {} and {} (sample correlation {:+.3}): the record cannot separate these terms whatever the method",
        c.a, c.b, c.rho
    );
    Warning::new(WarningKind::Collinear, text)
}

#[cfg(test)]
mod tests {
    use super::*;

    use aeroident_estimators::rls::{Rls, RlsConfig};
    use aeroident_estimators::{AirDataSample, AircraftConstants, ModelStructure, Term};

    /// A flipped elevator gives `Cm_de` > 0: the warning names the surface key and the fix; a
    /// correct `Cm_de`, an unidentified one and one within 2σ of 0 give none.
    #[test]
    fn control_derivative_against_the_mapping_convention_is_warned() {
        let st = ModelStructure::empty().with(Coefficient::Cm, &[Term::Alpha, Term::De]);
        let w = sign_warnings(&st, &[Some(-1.0), Some(1.5)], &[None, Some(0.1)]);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with("Cm_de = +1.5000")
                && w[0].contains("`de`")
                && w[0].contains("scale = -1")
        );
        assert!(sign_warnings(&st, &[Some(-1.0), Some(-1.5)], &[None, None]).is_empty());
        assert!(sign_warnings(&st, &[Some(-1.0), None], &[None, None]).is_empty());
        // Within 2σ of 0 (an unexcited elevator): no warning.
        assert!(sign_warnings(&st, &[Some(-1.0), Some(0.02)], &[None, Some(0.05)]).is_empty());
    }

    /// The condition number from the estimator's covariance (nalgebra eigenvalues) equals the
    /// RLS's own (Jacobi iteration on its P), and a nearly collinear pair is listed: two
    /// independent computations.
    #[test]
    fn analytic_rls_condition_number_and_collinear_pair() {
        let st = ModelStructure::empty()
            .with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::Q, Term::Alphadot, Term::De]);
        let k = AircraftConstants {
            mass_kg: 1000.0,
            S_m2: 10.0,
            cbar_m: Some(2.0),
            Iyy_kgm2: Some(2000.0),
            ..Default::default()
        };
        let mut rls = Rls::new(st, RlsConfig::default()).unwrap();
        let mut rec = Recorder::default();
        for i in 0..400 {
            let t = i as f64 * 0.02;
            let q = 0.1 * (2.1 * t).sin();
            // α̇ follows q closely (a short period), with a small independent part.
            let alphadot = 0.95 * q + 0.004 * (5.3 * t).cos();
            let s = AirDataSample {
                t_s: t,
                vt_mps: 50.0,
                alpha_rad: 0.05 + 0.02 * (1.3 * t).sin(),
                qbar_pa: 1500.0,
                q_rad_s: Some(q),
                qdot_rad_s2: Some(0.3 * (0.9 * t).sin() + 0.01 * (7.7 * t).sin()),
                alphadot_rad_s: Some(alphadot),
                de_rad: Some(0.02 * (0.7 * t + 0.4).sin()),
                constants: k,
                ..Default::default()
            };
            rls.update(&s).unwrap();
            rec.push(&s);
        }
        let ours = coefficient_conditions(&rls)[0].condition_number.unwrap();
        let theirs = rls.condition_number(Coefficient::Cm).unwrap();
        assert!((ours - theirs).abs() < 1e-6 * theirs, "{ours} vs {theirs}");
        assert!(ours > 100.0, "{ours}");
        let pairs = strong_correlations(&rls);
        assert!(pairs.iter().any(|c| c.a == "Cm_q" && c.b == "Cm_alphadot" && c.rho < -0.9));
        // The record's own measures: the information matrix XᵀX of the same samples gives
        // the same condition number as the RLS covariance (its prior is negligible), and the
        // regressors q̂ and α̇̂ are collinear (r ≈ +0.99); the matrix's ρ equals the pair's.
        let e = rls.estimates();
        let values: Vec<Option<f64>> = (0..e.n).map(|i| e.value(i)).collect();
        let id = identifiability(&st, &|i, j| rls.covariance(i, j), &rec, &values);
        let data = id.coefficients[0].data_condition_number.unwrap();
        assert!((data - theirs).abs() < 0.02 * theirs, "{data} vs {theirs}");
        assert!(
            id.collinear_regressors
                .iter()
                .any(|c| c.a == "Cm_q" && c.b == "Cm_alphadot" && c.rho > 0.9),
            "{:?}",
            id.collinear_regressors
        );
        let rho = id.correlation_matrix.rho[2][3].unwrap();
        let pair = pairs.iter().find(|c| c.a == "Cm_q" && c.b == "Cm_alphadot").unwrap();
        assert!((rho - pair.rho).abs() < 1e-12);
        assert!(id.not_identified.is_empty());
        assert_eq!(id.excitation[0].regressor_std, 0.0, "the bias regressor is constant");
    }

    #[test]
    fn analytic_condition_number_of_a_2x2_covariance() {
        // Correlation matrix [[1, ρ], [ρ, 1]] has eigenvalues 1 ± ρ, whatever the variances.
        let rho: f64 = 0.8;
        let (s1, s2) = (3.0, 0.01);
        let c = DMatrix::from_row_slice(2, 2, &[s1 * s1, rho * s1 * s2, rho * s1 * s2, s2 * s2]);
        let k = scaled_condition_number(&c).unwrap();
        assert!((k - (1.0 + rho) / (1.0 - rho)).abs() < 1e-12, "{k}");
        let singular = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        assert!(scaled_condition_number(&singular).is_none_or(|k| k > 1e12));
        assert!(scaled_condition_number(&DMatrix::from_row_slice(1, 1, &[0.0])).is_none());
    }
}
