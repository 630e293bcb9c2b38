//! Identifiability diagnostics of an estimator's final state, from its parameter covariance
//! ([`Estimator::covariance`]): per-coefficient condition numbers and the strongly correlated
//! parameter pairs (Klein & Morelli 2006 §5.4 and ch. 12: pairwise correlations above 0.9 and
//! large condition numbers flag terms the data cannot separate, e.g. `Cm_q` and `Cm_alphadot`
//! in a plain short-period manoeuvre, where α̇ ≈ q).

use aeroident_estimators::{Coefficient, Estimator};
use aeroident_io::replay_output::{CoefficientSummary, Correlation};
use nalgebra::{DMatrix, SymmetricEigen};

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
fn covariance_block(est: &dyn Estimator, idx: &[usize]) -> Option<DMatrix<f64>> {
    let n = idx.len();
    let mut m = DMatrix::zeros(n, n);
    for (a, &i) in idx.iter().enumerate() {
        for (b, &j) in idx.iter().enumerate() {
            m[(a, b)] = est.covariance(i, j)?;
        }
    }
    Some(m)
}

/// Per modelled coefficient, the condition number of its parameters' correlation matrix
/// (`null` when the estimator gives no covariance or a parameter is not identified).
pub fn coefficient_conditions(est: &dyn Estimator) -> Vec<CoefficientSummary> {
    let st = *est.structure();
    let e = est.estimates();
    st.coefficients()
        .map(|c: Coefficient| {
            let first = st.first_index(c);
            let idx: Vec<usize> = (first..first + st.n_terms(c)).collect();
            let condition_number = if idx.iter().all(|i| e.is_identified(*i)) {
                covariance_block(est, &idx).and_then(|m| scaled_condition_number(&m))
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
    let st = *est.structure();
    let e = est.estimates();
    let n = st.n_params();
    let mut out = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            if !(e.is_identified(i) && e.is_identified(j)) {
                continue;
            }
            let (Some(cij), Some(cii), Some(cjj)) =
                (est.covariance(i, j), est.covariance(i, i), est.covariance(j, j))
            else {
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

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::rls::{Rls, RlsConfig};
    use aeroident_estimators::{AirDataSample, AircraftConstants, ModelStructure, Term};

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
        }
        let ours = coefficient_conditions(&rls)[0].condition_number.unwrap();
        let theirs = rls.condition_number(Coefficient::Cm).unwrap();
        assert!((ours - theirs).abs() < 1e-6 * theirs, "{ours} vs {theirs}");
        assert!(ours > 100.0, "{ours}");
        let pairs = strong_correlations(&rls);
        assert!(pairs.iter().any(|c| c.a == "Cm_q" && c.b == "Cm_alphadot" && c.rho < -0.9));
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
