//! Small dense linear algebra on fixed-capacity arrays with a run-time active size `n ≤ C`:
//! Cholesky factorisation, solve and inverse of symmetric positive-definite matrices. No
//! allocation; the estimators use it so one compiled estimator serves any model structure.
//!
//! Source: Golub & Van Loan, *Matrix Computations*, 4th ed., Algorithm 4.2.1 (Cholesky,
//! gaxpy form).

// Index loops follow the textbook algorithms line by line, and `!(x > 0.0)` is meant to be
// true for NaN as well.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

/// A `C × C` array of which the leading `n × n` block is used.
pub type Square<const C: usize> = [[f64; C]; C];

/// Lower Cholesky factor `L` (`A = L Lᵀ`) of the leading `n × n` block of `a`, written into
/// `l` (upper part zeroed). Returns `false` if `A` is not positive definite or not finite.
pub fn cholesky<const C: usize>(a: &Square<C>, n: usize, l: &mut Square<C>) -> bool {
    for row in l.iter_mut().take(n) {
        row[..n].fill(0.0);
    }
    for j in 0..n {
        let mut d = a[j][j];
        for k in 0..j {
            d -= l[j][k] * l[j][k];
        }
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let djj = libm::sqrt(d);
        l[j][j] = djj;
        for i in j + 1..n {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            l[i][j] = s / djj;
        }
    }
    true
}

/// Solves `L Lᵀ x = b` for the leading `n` entries (in place in `b`).
pub fn cholesky_solve<const C: usize>(l: &Square<C>, n: usize, b: &mut [f64; C]) {
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i][k] * b[k];
        }
        b[i] = s / l[i][i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[k][i] * b[k];
        }
        b[i] = s / l[i][i];
    }
}

/// `(L Lᵀ)⁻¹` of the leading block into `inv`.
pub fn cholesky_inverse<const C: usize>(l: &Square<C>, n: usize, inv: &mut Square<C>) {
    for j in 0..n {
        let mut e = [0.0; C];
        e[j] = 1.0;
        cholesky_solve(l, n, &mut e);
        for i in 0..n {
            inv[i][j] = e[i];
        }
    }
}

/// Smallest admissible squared pivot of a unit-diagonal-scaled information matrix in
/// [`well_conditioned`]: every regressor must carry at least this fraction of its energy
/// independently of the others.
pub const MIN_SCALED_PIVOT: f64 = 1e-8;

/// Smallest root-mean-square value a regressor must have (in its own unit: rad, or the
/// non-dimensional rates) before it can identify anything: `1e-6`, far below any sensor's noise
/// but far above rounding, so a simulated record whose β or p̂ sit at 1e-10 before the input
/// starts is not taken as "excited" (the scaled test alone is blind to size).
pub const MIN_REGRESSOR_RMS: f64 = 1e-6;

/// Whether the leading `n × n` block of a symmetric positive semi-definite information matrix
/// `A = Σ w φφᵀ` (total weight `weight`, e.g. the effective sample count) is well conditioned:
/// every regressor's mean square `A_ii / weight` is at least [`MIN_REGRESSOR_RMS`]², and,
/// scaled to unit diagonal (the regressors' correlation matrix), its Cholesky factor exists
/// with every squared pivot at least `min_pivot`, i.e. every regressor carries at least that
/// fraction of its energy independently of the others (persistent excitation over the samples
/// so far). `false` if a diagonal entry is not positive and finite.
pub fn well_conditioned<const C: usize>(
    a: &Square<C>,
    n: usize,
    weight: f64,
    min_pivot: f64,
) -> bool {
    let floor = weight * MIN_REGRESSOR_RMS * MIN_REGRESSOR_RMS;
    for i in 0..n {
        if !(a[i][i] >= floor) {
            return false;
        }
    }
    let mut scaled = [[0.0; C]; C];
    for i in 0..n {
        let d = a[i][i];
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
    }
    for i in 0..n {
        for j in 0..n {
            scaled[i][j] = a[i][j] / libm::sqrt(a[i][i] * a[j][j]);
        }
    }
    let mut l = [[0.0; C]; C];
    cholesky(&scaled, n, &mut l) && (0..n).all(|i| l[i][i] * l[i][i] >= min_pivot)
}

/// 2-norm condition number of the leading `n × n` block of a symmetric positive semi-definite
/// matrix scaled to unit diagonal (i.e. of the correlation matrix), by Jacobi eigenvalue
/// iteration; `None` if a diagonal entry is not positive or the matrix is singular.
pub fn scaled_condition_number<const C: usize>(a: &Square<C>, n: usize) -> Option<f64> {
    let mut m = [[0.0; C]; C];
    for i in 0..n {
        if a[i][i].is_nan() || a[i][i] <= 0.0 {
            return None;
        }
    }
    for i in 0..n {
        for j in 0..n {
            m[i][j] = a[i][j] / libm::sqrt(a[i][i] * a[j][j]);
        }
    }
    // Cyclic Jacobi rotations (Golub & Van Loan Alg. 8.5.3).
    for _sweep in 0..60 {
        let mut off = 0.0;
        for i in 0..n {
            for j in i + 1..n {
                off += m[i][j] * m[i][j];
            }
        }
        if off < 1e-30 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                if m[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
                let t = theta.signum() / (theta.abs() + libm::sqrt(theta * theta + 1.0));
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / libm::sqrt(t * t + 1.0);
                let s = t * c;
                for k in 0..n {
                    let (mkp, mkq) = (m[k][p], m[k][q]);
                    m[k][p] = c * mkp - s * mkq;
                    m[k][q] = s * mkp + c * mkq;
                }
                for k in 0..n {
                    let (mpk, mqk) = (m[p][k], m[q][k]);
                    m[p][k] = c * mpk - s * mqk;
                    m[q][k] = s * mpk + c * mqk;
                }
            }
        }
    }
    let mut lo = f64::INFINITY;
    let mut hi = 0.0f64;
    for i in 0..n {
        lo = lo.min(m[i][i]);
        hi = hi.max(m[i][i]);
    }
    (lo > 0.0 && n > 0).then(|| hi / lo)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_cholesky_solve_and_inverse() {
        // A = [[4, 2, 0], [2, 5, 1], [0, 1, 3]] in a capacity-5 array.
        let mut a = [[0.0; 5]; 5];
        a[0][..3].copy_from_slice(&[4.0, 2.0, 0.0]);
        a[1][..3].copy_from_slice(&[2.0, 5.0, 1.0]);
        a[2][..3].copy_from_slice(&[0.0, 1.0, 3.0]);
        let mut l = [[9.0; 5]; 5];
        assert!(cholesky(&a, 3, &mut l));
        assert_eq!(l[0][0], 2.0);
        assert_eq!(l[1][0], 1.0);
        assert_eq!(l[1][1], 2.0);
        // x = [1, -1, 2] → b = A x = [2, -1, 5].
        let mut b = [2.0, -1.0, 5.0, 0.0, 0.0];
        cholesky_solve(&l, 3, &mut b);
        for (x, e) in b.iter().zip([1.0, -1.0, 2.0]) {
            assert!((x - e).abs() < 1e-14);
        }
        let mut inv = [[0.0; 5]; 5];
        cholesky_inverse(&l, 3, &mut inv);
        for i in 0..3 {
            for j in 0..3 {
                let s: f64 = (0..3).map(|k| a[i][k] * inv[k][j]).sum();
                assert!((s - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
        a[2][2] = -1.0;
        assert!(!cholesky(&a, 3, &mut l));
    }

    #[test]
    fn analytic_well_conditioned_threshold_on_a_2x2_correlation() {
        // Correlation ρ: scaled Cholesky pivots 1 and 1 − ρ²; ρ = 0.99 → 0.0199.
        let rho: f64 = 0.99;
        let a = [[4.0, rho * 6.0], [rho * 6.0, 9.0]];
        assert!(well_conditioned(&a, 2, 1.0, 0.019));
        assert!(!well_conditioned(&a, 2, 1.0, 0.0200));
        assert!(!well_conditioned(&[[0.0, 0.0], [0.0, 1.0]], 2, 1.0, 1e-8));
        // Size floor: regressors at 1e-10 (rounding-level excitation) are refused even though
        // their correlation matrix is perfect; at 1e-5 RMS over 100 samples they pass.
        let tiny = [[1e-20 * 100.0, 0.0], [0.0, 1e-20 * 100.0]];
        assert!(!well_conditioned(&tiny, 2, 100.0, 1e-8));
        let small = [[1e-10 * 100.0, 0.0], [0.0, 1e-10 * 100.0]];
        assert!(well_conditioned(&small, 2, 100.0, 1e-8));
    }

    #[test]
    fn analytic_condition_number_of_a_2x2_correlation() {
        // Correlation ρ: eigenvalues 1 ± ρ, condition (1 + ρ)/(1 − ρ).
        let rho: f64 = 0.9;
        let a = [[4.0, rho * 2.0 * 3.0], [rho * 2.0 * 3.0, 9.0]];
        let k = scaled_condition_number(&a, 2).unwrap();
        assert!((k - 19.0).abs() < 1e-10, "{k}");
    }
}
