//! Model structure determination on equation error: which candidate regressors a measured
//! coefficient needs.
//!
//! Two methods of Klein & Morelli, *Aircraft System Identification*, AIAA 2006, ch. 5, as NASA
//! SIDPAC implements them (`swr`, `offit`), both with a constant regressor always in the model:
//!
//! - [`stepwise`]: forward–backward stepwise regression (§5.4.1). At each step the candidate
//!   with the largest squared partial correlation with the residual enters when its partial F
//!   ratio `F = θ̂ⱼ² / var(θ̂ⱼ)` (eq. 5.63) exceeds the cut-off; a regressor in the model whose
//!   partial F falls below the cut-off leaves. SIDPAC's cut-off is 20, i.e. 95 % confidence
//!   (F ≈ 4) with a safety factor of 5 for the coloured residuals of real flight data.
//! - [`orthogonal`]: multivariate orthogonal functions (§5.4.2; Morelli, J. Aircraft 32(2),
//!   1995). The candidates are made orthogonal to the constant and to each other by
//!   Gram–Schmidt; each orthogonal function reduces the cost independently
//!   (`(zᵀpⱼ)² / pⱼᵀpⱼ`), so they are ranked by that reduction and kept up to the minimum of
//!   the predicted squared error; the kept functions expand back exactly into the ordinary
//!   candidates they were generated from.
//!
//! Both report the predicted squared error (eq. 5.81)
//! `PSE = (z − ŷ)ᵀ(z − ŷ)/N + 2 σ²_max p / N`, with `σ²_max = Σ(z − z̄)² / (2N)` (the variance
//! of a constant model for `z` under a uniform error distribution, SIDPAC's default) and `p`
//! the number of model terms including the constant; and `R² = 1 − SSE / Σ(z − z̄)²`.
//!
//! Batch and allocating (`std` only).

use nalgebra::{DMatrix, DVector};

/// SIDPAC's partial-F cut-off (`swr`: `Fval = 5·4`): a regressor enters or stays when its
/// partial F ratio exceeds it.
pub const SIDPAC_F_CUTOFF: f64 = 20.0;

/// Errors of the structure determination.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StructureError {
    /// Regressors and measurement disagree in length, or there are too few samples.
    #[error("structure determination: {0}")]
    Shape(String),
    /// A regressor or the measurement holds a non-finite value.
    #[error(
        "structure determination: candidate `{name}` has a non-finite value at sample {sample}"
    )]
    NonFinite {
        /// Candidate name (`z` for the measurement).
        name: String,
        /// Sample index, from 0.
        sample: usize,
    },
}

/// The candidate regressors of one measured quantity: `columns` is `N × m` (one column per
/// candidate, in `names` order), `z` the `N` measured values. The constant is implicit.
#[derive(Debug, Clone)]
pub struct Candidates {
    /// Candidate names, e.g. `alpha`, `q`, `alpha2`.
    pub names: Vec<String>,
    /// `N × m` regressor values.
    pub columns: DMatrix<f64>,
    /// `N` measured values (a coefficient, a force …).
    pub z: DVector<f64>,
}

impl Candidates {
    /// Checks shapes and finiteness.
    ///
    /// # Errors
    /// [`StructureError::Shape`] for mismatched lengths, no candidate names for the columns, or
    /// fewer samples than candidates + 2; [`StructureError::NonFinite`] naming the first
    /// non-finite value.
    pub fn check(&self) -> Result<(), StructureError> {
        let (n, m) = self.columns.shape();
        if self.names.len() != m || self.z.len() != n {
            return Err(StructureError::Shape(format!(
                "{} names and {} measurements for a {n} × {m} regressor matrix",
                self.names.len(),
                self.z.len()
            )));
        }
        if n < m + 2 {
            return Err(StructureError::Shape(format!(
                "{n} samples cannot decide among {m} candidates and a constant (need at least {})",
                m + 2
            )));
        }
        if let Some(k) = self.z.iter().position(|v| !v.is_finite()) {
            return Err(StructureError::NonFinite { name: "z".into(), sample: k });
        }
        for (j, name) in self.names.iter().enumerate() {
            if let Some(k) = self.columns.column(j).iter().position(|v| !v.is_finite()) {
                return Err(StructureError::NonFinite { name: name.clone(), sample: k });
            }
        }
        Ok(())
    }

    fn n(&self) -> usize {
        self.z.len()
    }

    /// `Σ(z − z̄)²`.
    fn total_ss(&self) -> f64 {
        let mean = self.z.mean();
        self.z.iter().map(|v| (v - mean).powi(2)).sum()
    }

    /// PSE and `R²` (module doc) of a model of `p` terms (constant included) leaving the
    /// residual sum of squares `sse`.
    fn pse_r2(&self, sse: f64, p: usize) -> (f64, f64) {
        let (n, sst) = (self.n() as f64, self.total_ss());
        let pse = sse / n + 2.0 * (sst / (2.0 * n)) * p as f64 / n;
        (pse, if sst > 0.0 { 1.0 - sse / sst } else { 0.0 })
    }
}

/// A least-squares fit of `z` on the constant and some candidates.
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// Candidate indices in the model (the constant is not listed).
    pub terms: Vec<usize>,
    /// Estimates of `terms` in order, then the constant.
    pub theta: Vec<f64>,
    /// Standard errors (`s² (XᵀX)⁻¹`, `s² = SSE / (N − p)`), as `theta`.
    pub std_error: Vec<f64>,
    /// Sum of squared residuals.
    pub sse: f64,
    /// Coefficient of determination, `1 − SSE / Σ(z − z̄)²` (0 for a constant `z`).
    pub r2: f64,
    /// Predicted squared error (module doc).
    pub pse: f64,
}

impl Fit {
    /// Partial F ratio `θ̂ⱼ² / var(θ̂ⱼ)` of the `k`-th term of the model (eq. 5.63); infinite
    /// for an exact fit.
    pub fn partial_f(&self, k: usize) -> f64 {
        let s = self.std_error[k];
        if s > 0.0 { (self.theta[k] / s).powi(2) } else { f64::INFINITY }
    }
}

/// The regressor matrix `[x_terms…, 1]`.
fn design(c: &Candidates, terms: &[usize]) -> DMatrix<f64> {
    let n = c.n();
    DMatrix::from_fn(n, terms.len() + 1, |i, j| {
        if j < terms.len() { c.columns[(i, terms[j])] } else { 1.0 }
    })
}

/// Ordinary least squares of `c.z` on the constant and `terms` (SVD, singular values below
/// `1e-12 · max` treated as zero, as SIDPAC's `svlim`; a dependent column gets σ = ∞).
pub fn fit(c: &Candidates, terms: &[usize]) -> Fit {
    let x = design(c, terms);
    let n = c.n();
    let p = x.ncols();
    let svd = x.clone().svd(true, true);
    let smax = svd.singular_values.max();
    let tol = 1e-12 * smax.max(f64::MIN_POSITIVE);
    let theta = svd.solve(&c.z, tol).unwrap_or_else(|_| DVector::zeros(p));
    let resid = &c.z - &x * &theta;
    let sse = resid.norm_squared();
    let s2 = sse / (n.saturating_sub(p)).max(1) as f64;
    let std_error: Vec<f64> = match (x.transpose() * &x).try_inverse() {
        Some(inv) if svd.singular_values.min() > tol => {
            (0..p).map(|k| (s2 * inv[(k, k)]).max(0.0).sqrt()).collect()
        }
        _ => vec![f64::INFINITY; p],
    };
    let (pse, r2) = c.pse_r2(sse, p);
    Fit { terms: terms.to_vec(), theta: theta.iter().copied().collect(), std_error, sse, r2, pse }
}

/// Standard errors of `fit` corrected for coloured residuals: the spectral sandwich
/// `(XᵀX)⁻¹ [Σ_i Σ_j x_i r̂(i − j) x_jᵀ] (XᵀX)⁻¹` that output error reports
/// ([`crate::coloured`], "Spectral form"; Klein & Morelli 2006 §5.2, Morelli & Klein, JGCD
/// 20(1), 1997), as `fit.std_error` (kept terms in order, then the constant).
///
/// The partial F of the selection keeps SIDPAC's white-residual `s²(XᵀX)⁻¹`: its cut-off of 20
/// already carries the allowance for coloured residuals. These are the σ to quote for the
/// estimates, which on flight data are correlated over the turbulence's and the model error's
/// time scales, and `fit.std_error` is then too small.
///
/// `lengths`: samples per manoeuvre of `c` in order (lags are taken within a manoeuvre),
/// summing to `N`. `None` when they do not, when the regressors are dependent, or when a
/// corrected variance comes out non-positive.
pub fn coloured_std_error(c: &Candidates, fit: &Fit, lengths: &[usize]) -> Option<Vec<f64>> {
    if lengths.iter().sum::<usize>() != c.n() || lengths.contains(&0) {
        return None;
    }
    let x = design(c, &fit.terms);
    let theta = DVector::from_column_slice(&fit.theta);
    let resid = &c.z - &x * theta;
    let minv = (x.transpose() * &x).try_inverse()?;
    // Row-major N × 1 × p: the regressor rows are the sensitivities of equation error.
    let rows = x.transpose();
    let cov =
        crate::coloured::batch::spectral(rows.as_slice(), resid.as_slice(), &[1.0], lengths, &minv)
            .covariance?;
    Some((0..cov.nrows()).map(|i| cov[(i, i)].sqrt()).collect())
}

/// What a step of a selection did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepAction {
    /// The candidate entered the model.
    Enter,
    /// The candidate left the model.
    Remove,
}

/// One step of a selection path, with the model after it.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// Enter or remove.
    pub action: StepAction,
    /// The candidate moved.
    pub candidate: usize,
    /// Its partial F ratio: after entering, or when it left.
    pub partial_f: f64,
    /// Predicted squared error of the model after the step.
    pub pse: f64,
    /// `R²` after the step.
    pub r2: f64,
}

/// A selected structure: the candidates kept, the path that led there and the final fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    /// Candidate names (as given).
    pub names: Vec<String>,
    /// The steps in order.
    pub path: Vec<Step>,
    /// The fit of the kept candidates (indices ascending) and the constant.
    pub fit: Fit,
    /// Why the selection stopped.
    pub stopped: String,
}

impl Selection {
    /// Names of the kept candidates, in candidate order.
    pub fn kept_names(&self) -> Vec<&str> {
        self.fit.terms.iter().map(|&k| self.names[k].as_str()).collect()
    }
}

/// Configuration of [`stepwise`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepwiseConfig {
    /// Partial F a candidate must exceed to enter.
    pub f_in: f64,
    /// Partial F below which a regressor leaves (≤ `f_in`, so a term cannot cycle).
    pub f_out: f64,
}

impl Default for StepwiseConfig {
    /// SIDPAC's cut-off, [`SIDPAC_F_CUTOFF`], both ways.
    fn default() -> Self {
        Self { f_in: SIDPAC_F_CUTOFF, f_out: SIDPAC_F_CUTOFF }
    }
}

/// Squared partial correlations with `z` of the candidates not in `terms`, each and `z`
/// conditioned on the model fit of `terms` (SIDPAC `swr`'s entry ranking), as (candidate, r²);
/// 0 for a candidate the model already explains. One projection serves every candidate.
fn partial_correlations2(c: &Candidates, terms: &[usize]) -> Vec<(usize, f64)> {
    let x = design(c, terms);
    let svd = x.clone().svd(true, true);
    let tol = 1e-12 * svd.singular_values.max().max(f64::MIN_POSITIVE);
    let resid = |v: DVector<f64>| -> DVector<f64> {
        let b = svd.solve(&v, tol).unwrap_or_else(|_| DVector::zeros(terms.len() + 1));
        v - &x * b
    };
    let zc = resid(c.z.clone());
    let szz = zc.norm_squared();
    (0..c.names.len())
        .filter(|j| !terms.contains(j))
        .map(|j| {
            let xj = c.columns.column(j).into_owned();
            let scale = xj.norm_squared().max(f64::MIN_POSITIVE);
            let xc = resid(xj);
            let sxx = xc.norm_squared();
            let r2 = if sxx <= 1e-12 * scale || szz == 0.0 {
                0.0
            } else {
                xc.dot(&zc).powi(2) / (sxx * szz)
            };
            (j, r2)
        })
        .collect()
}

/// Forward–backward stepwise regression (module doc), from the constant alone.
///
/// Each pass first removes the regressor of smallest partial F when it is below `f_out`, else
/// enters the candidate of largest squared partial correlation when its partial F after
/// entering exceeds `f_in`, else stops. A model met before ends the selection (a cycle).
///
/// # Errors
/// [`Candidates::check`]'s.
pub fn stepwise(c: &Candidates, config: StepwiseConfig) -> Result<Selection, StructureError> {
    stepwise_in_hierarchy(c, config, &[])
}

/// [`stepwise`] keeping the model hierarchy as SIDPAC's practice does (Morelli, "Global
/// nonlinear aerodynamic modeling using multivariate orthogonal functions", J. Aircraft 1995;
/// Klein & Morelli 2006 §5.4): a power or product term enters only once its parents are in the
/// model, and a parent leaves only when none of its children is in. `parents[k]` lists the
/// candidates that are parents of candidate `k` (empty, or shorter than the candidates: none).
/// Without that, a nonlinear term collinear with its parent (α² and α over a small α range,
/// ρ 0.999) can enter first and stand in for it.
///
/// # Errors
/// [`Candidates::check`]'s.
pub fn stepwise_in_hierarchy(
    c: &Candidates,
    config: StepwiseConfig,
    parents: &[Vec<usize>],
) -> Result<Selection, StructureError> {
    c.check()?;
    let parents_of = |k: usize| parents.get(k).map_or(&[][..], Vec::as_slice);
    let eligible = |j: usize, terms: &[usize]| parents_of(j).iter().all(|p| terms.contains(p));
    let removable = |t: usize, terms: &[usize]| !terms.iter().any(|&k| parents_of(k).contains(&t));
    let mut terms: Vec<usize> = Vec::new();
    let mut current = fit(c, &terms);
    let mut path = Vec::new();
    let mut seen: Vec<Vec<usize>> = vec![terms.clone()];
    let stopped = loop {
        let weakest = (0..terms.len())
            .filter(|&k| removable(terms[k], &terms))
            .map(|k| (k, current.partial_f(k)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((k, f)) = weakest.filter(|&(_, f)| f < config.f_out) {
            let candidate = terms.remove(k);
            current = fit(c, &terms);
            path.push(Step {
                action: StepAction::Remove,
                candidate,
                partial_f: f,
                pse: current.pse,
                r2: current.r2,
            });
        } else {
            let best = partial_correlations2(c, &terms)
                .into_iter()
                .filter(|&(j, _)| eligible(j, &terms))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            let Some((j, r2)) = best.filter(|&(_, r2)| r2 > 0.0) else {
                break "every candidate is in the model or explained by it".to_string();
            };
            let mut trial = terms.clone();
            trial.push(j);
            trial.sort_unstable();
            let next = fit(c, &trial);
            let f = next.partial_f(trial.iter().position(|&t| t == j).unwrap_or(0));
            if f.is_nan() || f <= config.f_in {
                break format!(
                    "the best remaining candidate `{}` (squared partial correlation {r2:.3}) has partial F {f:.1} ≤ {}",
                    c.names[j], config.f_in
                );
            }
            terms = trial;
            current = next;
            path.push(Step {
                action: StepAction::Enter,
                candidate: j,
                partial_f: f,
                pse: current.pse,
                r2: current.r2,
            });
        }
        if seen.contains(&terms) {
            break "the model repeats an earlier one (a cycle); stopped there".to_string();
        }
        seen.push(terms.clone());
    };
    Ok(Selection { names: c.names.clone(), path, fit: current, stopped })
}

/// One orthogonal function of [`orthogonal`], in rank order.
#[derive(Debug, Clone, PartialEq)]
pub struct OrthogonalFunction {
    /// The candidate it was generated from (`None`: the constant).
    pub candidate: Option<usize>,
    /// Cost reduction `(zᵀp)² / pᵀp`.
    pub cost_reduction: f64,
    /// PSE of the model of this and every higher-ranked function.
    pub pse: f64,
    /// `R²` of that model.
    pub r2: f64,
}

/// The result of [`orthogonal`].
#[derive(Debug, Clone, PartialEq)]
pub struct OrthogonalSelection {
    /// The orthogonal functions in the order chosen, the constant first, until no candidate
    /// is left that is independent of the chosen ones.
    pub ranked: Vec<OrthogonalFunction>,
    /// How many of `ranked` are kept (the PSE minimum), the constant included.
    pub kept_functions: usize,
    /// The ordinary-term model: the candidates of the kept functions, refitted by least
    /// squares (they span exactly the kept orthogonal functions).
    pub selection: Selection,
}

/// How [`orthogonal`] orders the Gram–Schmidt orthogonalisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Ranking {
    /// Greedy: each next function is the remaining candidate of largest cost
    /// reduction, orthogonalised against the chosen ones; the kept functions span exactly
    /// their candidates.
    Greedy,
    /// SIDPAC `offit` (the default, the reference's method): the candidates orthogonalised
    /// once in the order given (lowest polynomial order first), then ranked by cost reduction;
    /// a kept function expands into every candidate before it, and the ordinary terms under
    /// 0.1 % of `rms(z)` are dropped.
    #[default]
    Generation,
}

/// Multivariate orthogonal functions (module doc). [`Ranking::Greedy`]: starting from the
/// constant, every remaining candidate is orthogonalised against the functions chosen so far
/// and the one of largest cost reduction is chosen next (Klein & Morelli 2006 §5.4.2). So the
/// chosen functions span exactly their generating candidates, and the ranking does not depend
/// on the order the candidates are listed in, as a fixed Gram–Schmidt order would (a term
/// listed early takes the share of a correlated later one).
///
/// # Errors
/// [`Candidates::check`]'s.
pub fn orthogonal(c: &Candidates, ranking: Ranking) -> Result<OrthogonalSelection, StructureError> {
    c.check()?;
    if ranking == Ranking::Generation {
        return Ok(generation_order(c));
    }
    let n = c.n();
    let ones = DVector::from_element(n, 1.0);
    // Remaining candidates, each kept orthogonal to every chosen function.
    let mut remaining: Vec<(usize, DVector<f64>, f64)> = (0..c.names.len())
        .map(|j| {
            let x = c.columns.column(j).into_owned();
            let scale = x.norm_squared();
            (j, x, scale)
        })
        .collect();
    let reduction = |p: &DVector<f64>| c.z.dot(p).powi(2) / p.norm_squared();
    let mut sse = c.z.norm_squared();
    let mut ranked = Vec::new();
    let mut chosen: Option<DVector<f64>> = Some(ones);
    let mut candidate = None;
    while let Some(p) = chosen.take() {
        push_ranked(c, &mut ranked, &mut sse, candidate, reduction(&p));
        let pn = p.norm_squared();
        for (_, x, _) in &mut remaining {
            *x -= &p * (p.dot(x) / pn);
        }
        // Numerically dependent on the chosen functions: no function of its own.
        remaining.retain(|(_, x, scale)| x.norm_squared() > 1e-10 * scale.max(f64::MIN_POSITIVE));
        let best = (0..remaining.len())
            .max_by(|&a, &b| reduction(&remaining[a].1).total_cmp(&reduction(&remaining[b].1)));
        if let Some(b) = best {
            let (j, x, _) = remaining.swap_remove(b);
            candidate = Some(j);
            chosen = Some(x);
        }
    }
    let kept_functions = pse_minimum(&ranked);
    let kept = &ranked[..kept_functions];
    let mut terms: Vec<usize> = kept.iter().filter_map(|f| f.candidate).collect();
    terms.sort_unstable();
    let stopped = format!(
        "minimum of the predicted squared error at {kept_functions} orthogonal functions (constant included)"
    );
    let selection = selection_of(c, kept, &terms, stopped);
    Ok(OrthogonalSelection { ranked, kept_functions, selection })
}

/// Appends the next ranked function (its candidate, cost reduction `dj`) with the PSE and `R²`
/// of the model of every function so far; `sse` is the residual sum of squares before it.
fn push_ranked(
    c: &Candidates,
    ranked: &mut Vec<OrthogonalFunction>,
    sse: &mut f64,
    candidate: Option<usize>,
    dj: f64,
) {
    *sse = (*sse - dj).max(0.0);
    let (pse, r2) = c.pse_r2(*sse, ranked.len() + 1);
    ranked.push(OrthogonalFunction { candidate, cost_reduction: dj, pse, r2 });
}

/// How many of `ranked` the PSE minimum keeps (the constant included).
fn pse_minimum(ranked: &[OrthogonalFunction]) -> usize {
    ranked.iter().enumerate().min_by(|a, b| a.1.pse.total_cmp(&b.1.pse)).map_or(1, |(k, _)| k + 1)
}

/// The selection of ordinary `terms` after the `kept` orthogonal functions (each an entry of
/// the path), refitted on `c`.
fn selection_of(
    c: &Candidates,
    kept: &[OrthogonalFunction],
    terms: &[usize],
    stopped: String,
) -> Selection {
    let path = kept
        .iter()
        .filter_map(|f| {
            f.candidate.map(|candidate| Step {
                action: StepAction::Enter,
                candidate,
                partial_f: f64::NAN,
                pse: f.pse,
                r2: f.r2,
            })
        })
        .collect();
    Selection { names: c.names.clone(), path, fit: fit(c, terms), stopped }
}

/// [`Ranking::Generation`] of [`orthogonal`] (checked candidates).
fn generation_order(c: &Candidates) -> OrthogonalSelection {
    let n = c.n();
    let mut psi: Vec<DVector<f64>> = vec![DVector::from_element(n, 1.0)];
    let mut source: Vec<Option<usize>> = vec![None];
    for j in 0..c.names.len() {
        let x = c.columns.column(j).into_owned();
        let mut p = x.clone();
        // Twice: one pass loses orthogonality on nearly dependent candidates.
        for _ in 0..2 {
            for q in &psi {
                p -= q * (q.dot(&p) / q.norm_squared());
            }
        }
        if p.norm_squared() > 1e-10 * x.norm_squared().max(f64::MIN_POSITIVE) {
            psi.push(p);
            source.push(Some(j));
        }
    }
    let reduction = |p: &DVector<f64>| c.z.dot(p).powi(2) / p.norm_squared();
    let mut order: Vec<usize> = (1..psi.len()).collect();
    order.sort_by(|&a, &b| reduction(&psi[b]).total_cmp(&reduction(&psi[a])));
    order.insert(0, 0);
    let mut sse = c.z.norm_squared();
    let mut ranked = Vec::with_capacity(order.len());
    for &i in &order {
        push_ranked(c, &mut ranked, &mut sse, source[i], reduction(&psi[i]));
    }
    let kept_functions = pse_minimum(&ranked);
    // The kept model's output, expanded over every candidate up to the last kept one.
    let y = order[..kept_functions].iter().fold(DVector::zeros(n), |acc: DVector<f64>, &i| {
        let p = &psi[i];
        acc + p * (c.z.dot(p) / p.norm_squared())
    });
    let last = ranked[..kept_functions].iter().filter_map(|f| f.candidate).max();
    let span: Vec<usize> = last.map_or_else(Vec::new, |l| (0..=l).collect());
    let expanded =
        fit(&Candidates { names: c.names.clone(), columns: c.columns.clone(), z: y }, &span);
    let rms = |v: f64| (v / n as f64).sqrt();
    let z_rms = rms(c.z.norm_squared());
    let terms: Vec<usize> = span
        .iter()
        .enumerate()
        .filter(|&(k, &j)| {
            (expanded.theta[k] * rms(c.columns.column(j).norm_squared())).abs() > 1e-3 * z_rms
        })
        .map(|(_, &j)| j)
        .collect();
    let stopped = format!(
        "minimum of the predicted squared error at {kept_functions} orthogonal functions (constant included), expanded into {} ordinary terms",
        terms.len()
    );
    let selection = selection_of(c, &ranked[..kept_functions], &terms, stopped);
    OrthogonalSelection { ranked, kept_functions, selection }
}

#[cfg(test)]
mod tests;
