//! Equation-error prediction of the measured coefficients over a record, for model validation
//! ([`crate::validation`]) and the data-based identifiability measures
//! ([`super::diagnostics`]).
//!
//! [`Recorder`] keeps, for every sample fed to the estimator, the measured coefficients
//! ([`AirDataSample::measured_coefficients`]), every term's regressor ([`Term::value`]) and the
//! control inputs `δe, δa, δr`, with the manoeuvre (segment) it belongs to. At most
//! [`Recorder::MAX_SAMPLES`] samples are kept (a live feed stays bounded), in whole blocks of
//! [`Recorder::BLOCK`] consecutive samples (a [`crate::sample_log::SampleLog`]): when the limit is reached every second kept block
//! is dropped and from then on only every `stride`-th block is kept (the stride doubles each
//! time), so the validation covers the whole record, not only its beginning, and each kept
//! block keeps its sample-to-sample structure (the residuals' autocorrelation and lagged
//! input correlations need consecutive samples; a kept block is its own segment, lagged sums
//! do not cross from one to the next). The report says when samples were not kept.
//!
//! [`validate_coefficients`] predicts each modelled coefficient from the regressors with given
//! parameter values, `Ĉ_t = Σ_j θ_j ξ_j(t)`, its variance from the parameter covariance
//! `ξ_tᵀ P ξ_t` where the estimator gives one, and computes the metrics of
//! [`crate::validation::validate`] against the measured coefficient (inputs: the controls).
//! A coefficient with an unidentified parameter is not validated (a note says which), except
//! an unidentified bias term (`_0`; the frequency-domain method drops biases and trims): the
//! bias is then re-fitted as the mean of `C − Σ_{j≠0} θ_j ξ_j` over the record, and a note says
//! so.

use crate::sample_log::SampleLog;
use crate::validation::{OutputData, OutputValidation, validate};
use aeroident_estimators::vocabulary::{AlphaKnots, N_TERMS};
use aeroident_estimators::{
    AirDataSample, Coefficient, Estimates, Estimator, ModelStructure, Status, Term,
    estimator::check_finite,
};
use serde::Serialize;

/// The control inputs correlated with the residuals (those the structure has a term of).
pub const INPUTS: [&str; 3] = ["de", "da", "dr"];

/// One kept sample: values `NaN` where absent.
#[derive(Debug, Clone, Copy)]
struct Row {
    coefs: [f64; 8],
    terms: [f64; N_TERMS],
    inputs: [f64; 3],
}

/// The samples fed to an estimator, as regressors and measured coefficients (module doc): a
/// [`SampleLog`] of [`Recorder::MAX_SAMPLES`] rows in blocks of [`Recorder::BLOCK`].
#[derive(Debug, Clone)]
pub struct Recorder {
    rows: SampleLog<Row>,
    /// The α knots of the spline terms' regressors (the structure's).
    knots: AlphaKnots,
}

impl Default for Recorder {
    fn default() -> Self {
        Self::for_structure(&ModelStructure::empty())
    }
}

fn nan(v: Option<f64>) -> f64 {
    v.unwrap_or(f64::NAN)
}

impl Recorder {
    /// Most samples kept: 65,536 (208 bytes each and an 8-byte segment number, 14 MB; a power
    /// of two, so the vector's capacity never exceeds it): 11 min at 100 Hz before the first
    /// decimation.
    pub const MAX_SAMPLES: usize = 65_536;

    /// Consecutive samples per kept block: 1,024 (10 s at 100 Hz, ≫ the 20 lags of the
    /// residual tests).
    pub const BLOCK: usize = 1_024;

    /// A recorder of the regressors of `structure` (its α knots form the spline terms).
    pub fn for_structure(structure: &ModelStructure) -> Self {
        Self { rows: SampleLog::new(Self::MAX_SAMPLES, Self::BLOCK), knots: *structure.knots() }
    }

    /// Keeps sample `s` (fed to the estimator), decimating by blocks (module doc).
    pub fn push(&mut self, s: &AirDataSample) {
        let knots = &self.knots;
        self.rows.push_with(|| Row {
            coefs: s.measured_coefficients().map(nan),
            terms: Term::ALL.map(|t| nan(t.value(s, knots))),
            inputs: [nan(s.de_rad), nan(s.da_rad), nan(s.dr_rad)],
        });
    }

    /// A new manoeuvre starts (a gap): lagged sums will not cross it.
    pub fn new_segment(&mut self) {
        self.rows.new_segment();
    }

    /// Samples offered and not kept (blocks dropped by the decimation).
    pub fn dropped(&self) -> usize {
        self.rows.dropped()
    }

    /// Samples kept.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether no sample was kept.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The rows where coefficient `c` and the given terms are all present: their indices.
    fn usable(&self, c: Coefficient, terms: &[Term]) -> Vec<usize> {
        let rows = self.rows.items();
        (0..rows.len())
            .filter(|&k| {
                let r = &rows[k];
                r.coefs[c.index()].is_finite()
                    && terms.iter().all(|t| r.terms[t.index()].is_finite())
            })
            .collect()
    }

    /// Regressor `t` over rows `idx`.
    pub(crate) fn term_series(&self, t: Term, idx: &[usize]) -> Vec<f64> {
        idx.iter().map(|&k| self.rows.items()[k].terms[t.index()]).collect()
    }

    /// Measured coefficient `c` over rows `idx`.
    pub(crate) fn coef_series(&self, c: Coefficient, idx: &[usize]) -> Vec<f64> {
        idx.iter().map(|&k| self.rows.items()[k].coefs[c.index()]).collect()
    }

    /// The rows where every term of coefficient `c` in `structure` and `c` itself are present.
    pub(crate) fn rows_for(&self, structure: &ModelStructure, c: Coefficient) -> Vec<usize> {
        let terms: Vec<Term> = structure.terms_of(c).collect();
        self.usable(c, &terms)
    }

    /// Segment lengths over rows `idx` (in order).
    fn segments(&self, idx: &[usize]) -> Vec<usize> {
        let mut out: Vec<usize> = Vec::new();
        let mut last = None;
        for &k in idx {
            let s = self.rows.segments()[k];
            if last == Some(s) {
                if let Some(l) = out.last_mut() {
                    *l += 1;
                }
            } else {
                out.push(1);
                last = Some(s);
            }
        }
        out
    }

    /// The inputs of `structure` (controls whose term it has) present (finite) in every row
    /// of `idx`, with their series.
    fn inputs(&self, structure: &ModelStructure, idx: &[usize]) -> Vec<(&'static str, Vec<f64>)> {
        let modelled = |i: usize| {
            let t = [Term::De, Term::Da, Term::Dr][i];
            structure.params().any(|p| p.term == t)
        };
        let rows = self.rows.items();
        (0..3)
            .filter(|&i| modelled(i) && idx.iter().all(|&k| rows[k].inputs[i].is_finite()))
            .map(|i| (INPUTS[i], idx.iter().map(|&k| rows[k].inputs[i]).collect()))
            .collect()
    }
}

/// An "estimator" whose parameters are frozen at given values (with their covariance): it
/// carries a fitted model through the replay pipeline of a second record
/// ([`super::validate_on`]).
#[derive(Debug, Clone)]
pub struct Frozen {
    structure: ModelStructure,
    est: Estimates,
    cov: Vec<Option<f64>>,
}

impl Frozen {
    /// Parameters `values` (structure order; `None` stays not identified) and covariance
    /// `cov` (`n × n` row-major, may be empty).
    pub fn new(structure: ModelStructure, values: &[Option<f64>], cov: Vec<Option<f64>>) -> Self {
        let n = structure.n_params();
        let mut est = Estimates::new(n);
        for (i, v) in values.iter().enumerate().take(n) {
            if let Some(v) = v {
                let sigma = cov.get(i * n + i).copied().flatten().map(f64::sqrt);
                est.set(i, *v, sigma, true);
            }
        }
        est.status = Status::Running;
        Self { structure, est, cov }
    }
}

impl Estimator for Frozen {
    fn method(&self) -> &'static str {
        "frozen"
    }
    fn structure(&self) -> &ModelStructure {
        &self.structure
    }
    fn update(
        &mut self,
        s: &AirDataSample,
    ) -> Result<&Estimates, aeroident_estimators::EstimatorError> {
        check_finite(s)?;
        Ok(&self.est)
    }
    fn estimates(&self) -> &Estimates {
        &self.est
    }
    fn covariance(&self, i: usize, j: usize) -> Option<f64> {
        let n = self.structure.n_params();
        if !(self.est.is_identified(i) && self.est.is_identified(j)) {
            return None;
        }
        self.cov.get(i * n + j).copied().flatten()
    }
}

/// Validation of a model on one record (`validation` / `validation_on` in `summary.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ValidationReport {
    /// The record validated on (the fitted record itself, or the `--validate-on` file).
    pub data: String,
    /// Whether this record was used for the fit (`false`: a check on a second manoeuvre).
    pub used_for_fit: bool,
    /// How the predictions were formed.
    pub prediction: String,
    /// Samples compared (before per-output filtering).
    pub samples: usize,
    /// Per output: the metrics of [`crate::validation::OutputValidation`].
    pub outputs: Vec<OutputValidation>,
    /// Outputs not validated or treated specially, and why.
    pub notes: Vec<String>,
}

impl ValidationReport {
    /// The mean square residual (`rmse²`) of output `name`, if validated.
    pub fn mean_square(&self, name: &str) -> Option<f64> {
        self.outputs.iter().find(|o| o.name == name).map(|o| o.rmse * o.rmse)
    }
}

/// The prediction text of equation-error validation.
pub const EQUATION_ERROR: &str = "equation-error: each measured coefficient predicted from its regressors with the final estimates (prediction variance from the estimator's covariance where it gives one)";

/// Validates every modelled coefficient of `structure` on the recorded samples with parameter
/// values `values` (structure order, `None` = not identified) and covariance `cov(i, j)`
/// (module doc).
///
/// `fit`: the validation of the fitted record, when this is a second record: its mean square
/// residual per coefficient is the residual variance of the prediction interval.
pub fn validate_coefficients(
    rec: &Recorder,
    structure: &ModelStructure,
    values: &[Option<f64>],
    cov: &dyn Fn(usize, usize) -> Option<f64>,
    data: &str,
    fit: Option<&ValidationReport>,
) -> ValidationReport {
    let used_for_fit = fit.is_none();
    let mut outputs = Vec::new();
    let mut notes = Vec::new();
    if rec.dropped() > 0 {
        notes.push(format!(
            "{} samples kept for validation, in blocks of {} consecutive samples spread over the record ({} samples not compared)",
            rec.len(),
            Recorder::BLOCK,
            rec.dropped()
        ));
    }
    for c in structure.coefficients() {
        let first = structure.first_index(c);
        let terms: Vec<Term> = structure.terms_of(c).collect();
        let idx_of = |t: usize| first + t;
        let missing: Vec<&str> = terms
            .iter()
            .enumerate()
            .filter(|(j, t)| values[idx_of(*j)].is_none() && **t != Term::Bias)
            .map(|(j, _)| structure.param(idx_of(j)).map_or("?", |p| p.name()))
            .collect();
        if !missing.is_empty() {
            notes.push(format!(
                "{}: not validated: {} not identified",
                c.name(),
                missing.join(", ")
            ));
            continue;
        }
        let rows = rec.usable(c, &terms);
        if rows.len() < 3 {
            notes.push(format!(
                "{}: not validated: {} samples with the coefficient and its regressors",
                c.name(),
                rows.len()
            ));
            continue;
        }
        let y = rec.coef_series(c, &rows);
        let x: Vec<Vec<f64>> = terms.iter().map(|t| rec.term_series(*t, &rows)).collect();
        let mut y_hat = vec![0.0; rows.len()];
        let mut refit_bias = None;
        for (j, t) in terms.iter().enumerate() {
            match values[idx_of(j)] {
                Some(v) => y_hat.iter_mut().zip(&x[j]).for_each(|(p, xi)| *p += v * xi),
                None if *t == Term::Bias => refit_bias = Some(j),
                None => {}
            }
        }
        if refit_bias.is_some() {
            let b = y.iter().zip(&y_hat).map(|(a, p)| a - p).sum::<f64>() / y.len() as f64;
            y_hat.iter_mut().for_each(|p| *p += b);
            notes.push(format!(
                "{}: its bias term is not identified by the method; re-fitted as the mean residual ({b:.6})",
                c.name()
            ));
        }
        // x_tᵀ P x_t over the identified parameters, where every covariance entry exists.
        let ident: Vec<usize> = (0..terms.len()).filter(|j| values[idx_of(*j)].is_some()).collect();
        let mut p = vec![0.0; ident.len() * ident.len()];
        let mut have_cov = true;
        for (a, &ja) in ident.iter().enumerate() {
            for (b, &jb) in ident.iter().enumerate() {
                match cov(idx_of(ja), idx_of(jb)) {
                    Some(v) if v.is_finite() => p[a * ident.len() + b] = v,
                    _ => have_cov = false,
                }
            }
        }
        let var: Option<Vec<f64>> = have_cov.then(|| {
            (0..rows.len())
                .map(|t| {
                    let mut s = 0.0;
                    for (a, &ja) in ident.iter().enumerate() {
                        for (b, &jb) in ident.iter().enumerate() {
                            s += x[ja][t] * p[a * ident.len() + b] * x[jb][t];
                        }
                    }
                    s
                })
                .collect()
        });
        let segments = rec.segments(&rows);
        let inputs = rec.inputs(structure, &rows);
        let input_refs: Vec<(&str, &[f64])> =
            inputs.iter().map(|(n, u)| (*n, u.as_slice())).collect();
        let d = OutputData {
            name: c.name(),
            prediction: "equation-error",
            y: &y,
            y_hat: &y_hat,
            y_hat_var: var.as_deref(),
            residual_var: fit.and_then(|f| f.mean_square(c.name())),
            segments: &segments,
            inputs: &input_refs,
        };
        match validate(&d) {
            Ok(v) => outputs.push(v),
            Err(e) => notes.push(format!("{}: not validated: {e}", c.name())),
        }
    }
    ValidationReport {
        data: data.to_string(),
        used_for_fit,
        prediction: EQUATION_ERROR.into(),
        samples: rec.len(),
        outputs,
        notes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::AircraftConstants;

    fn sample(t: f64, cm: f64) -> AirDataSample {
        // q̇ chosen so the measured Cm equals `cm`: Cm = Iyy q̇ / (q̄ S c̄).
        let k = AircraftConstants {
            mass_kg: 1000.0,
            S_m2: 10.0,
            cbar_m: Some(2.0),
            Iyy_kgm2: Some(2000.0),
            ..Default::default()
        };
        AirDataSample {
            t_s: t,
            vt_mps: 50.0,
            alpha_rad: 0.05 + 0.02 * (1.3 * t).sin(),
            qbar_pa: 1500.0,
            q_rad_s: Some(0.0),
            qdot_rad_s2: Some(cm * 1500.0 * 10.0 * 2.0 / 2000.0),
            de_rad: Some(0.02 * (0.7 * t).sin()),
            constants: k,
            ..Default::default()
        }
    }

    /// Data generated by Cm = 0.1 − 0.8 α − 1.2 δe: the true parameters predict it exactly
    /// (fit 100 %); with the bias unknown it is re-fitted (fit 100 %, noted); with Cm_alpha
    /// unknown the coefficient is not validated and the note names it; a wrong Cm_alpha
    /// lowers the fit to the value computed by hand.
    #[test]
    fn analytic_equation_error_prediction() {
        let st =
            ModelStructure::empty().with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::De]);
        let mut rec = Recorder::default();
        let truth = |s: &AirDataSample| 0.1 - 0.8 * s.alpha_rad - 1.2 * s.de_rad.unwrap();
        let mut ys = Vec::new();
        for k in 0..300 {
            let t = k as f64 * 0.05;
            let s0 = sample(t, 0.0);
            let s = sample(t, truth(&s0));
            ys.push((truth(&s0), s.alpha_rad));
            rec.push(&s);
        }
        let none = |_: usize, _: usize| None;
        let r = validate_coefficients(
            &rec,
            &st,
            &[Some(0.1), Some(-0.8), Some(-1.2)],
            &none,
            "x",
            None,
        );
        let fit = r.outputs[0].fit_percent.unwrap();
        assert!((fit - 100.0).abs() < 1e-6, "{fit}");
        assert_eq!(r.outputs[0].input_correlation[0].input, "de");
        let r = validate_coefficients(&rec, &st, &[None, Some(-0.8), Some(-1.2)], &none, "x", None);
        assert!((r.outputs[0].fit_percent.unwrap() - 100.0).abs() < 1e-6);
        assert!(r.notes[0].contains("re-fitted"), "{:?}", r.notes);
        let r = validate_coefficients(&rec, &st, &[Some(0.1), None, Some(-1.2)], &none, "x", None);
        assert!(r.outputs.is_empty() && r.notes[0].contains("Cm_alpha not identified"));
        // Cm_alpha off by 0.1: residual e = −0.1 α' (α' = α … the prediction uses −0.9 α).
        let r = validate_coefficients(
            &rec,
            &st,
            &[Some(0.1), Some(-0.9), Some(-1.2)],
            &none,
            "x",
            None,
        );
        let y: Vec<f64> = ys.iter().map(|v| v.0).collect();
        let e: Vec<f64> = ys.iter().map(|v| 0.1 * v.1).collect();
        let ym = y.iter().sum::<f64>() / y.len() as f64;
        let hand = 100.0
            * (1.0
                - (e.iter().map(|v| v * v).sum::<f64>()
                    / y.iter().map(|v| (v - ym) * (v - ym)).sum::<f64>())
                .sqrt());
        assert!((r.outputs[0].fit_percent.unwrap() - hand).abs() < 1e-6);
        // With a covariance P = 10⁻² on Cm_alpha only, the prediction variance is 10⁻² α²:
        // the interval's parameter share is mean(10⁻² α² / (10⁻² α² + s²)), by hand.
        let cov = |i: usize, j: usize| Some(if i == 1 && j == 1 { 1e-2 } else { 0.0 });
        let r =
            validate_coefficients(&rec, &st, &[Some(0.1), Some(-0.9), Some(-1.2)], &cov, "x", None);
        let em = e.iter().sum::<f64>() / e.len() as f64;
        let s2 = e.iter().map(|v| (v - em) * (v - em)).sum::<f64>() / e.len() as f64;
        let share = ys.iter().map(|v| 1e-2 * v.1 * v.1 / (1e-2 * v.1 * v.1 + s2)).sum::<f64>()
            / ys.len() as f64;
        let pi = r.outputs[0].prediction_interval.as_ref().unwrap();
        assert!((pi.parameter_share - share).abs() < 1e-9, "{} vs {share}", pi.parameter_share);
    }

    /// A long feed is decimated by whole blocks spread over the record: at most MAX_SAMPLES
    /// kept, every sample counted (kept + dropped), the kept samples are the blocks whose index
    /// is a multiple of the final stride (so the end of the record is covered), each kept
    /// block is consecutive samples and its own segment.
    #[test]
    fn analytic_recorder_keeps_spread_whole_blocks_within_its_bound() {
        let b = Recorder::BLOCK;
        // 320 whole blocks and 17 samples: ends inside block 320, a kept one at stride 8.
        let n = 5 * Recorder::MAX_SAMPLES + 17;
        let mut rec = Recorder::default();
        for k in 0..n {
            let mut s = sample(k as f64 * 0.01, 0.0);
            s.alpha_rad = k as f64 * 1e-6; // the sample index, read back from the regressor
            rec.push(&s);
        }
        assert!(rec.len() <= Recorder::MAX_SAMPLES);
        assert_eq!(rec.len() + rec.dropped(), n);
        let all: Vec<usize> = (0..rec.len()).collect();
        let idx: Vec<usize> =
            rec.term_series(Term::Alpha, &all).iter().map(|a| (a * 1e6).round() as usize).collect();
        // Decimations at blocks 64, 128 and 256: stride 8.
        let stride = 8;
        let expected: Vec<usize> = (0..n).filter(|k| (k / b).is_multiple_of(stride)).collect();
        assert_eq!(idx, expected);
        assert_eq!(*idx.last().unwrap(), n - 1, "the end of the record is covered");
        let segs = rec.segments(&all);
        let mut lens = vec![b; expected.len() / b];
        lens.extend((!expected.len().is_multiple_of(b)).then_some(expected.len() % b));
        assert_eq!(segs, lens, "one segment per kept block");
        // Short records are untouched: every sample kept, one segment.
        let mut short = Recorder::default();
        for k in 0..3 * b {
            short.push(&sample(k as f64 * 0.01, 0.0));
        }
        assert_eq!((short.len(), short.dropped()), (3 * b, 0));
        assert_eq!(short.segments(&(0..3 * b).collect::<Vec<_>>()), vec![3 * b]);
    }
}
