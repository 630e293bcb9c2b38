//! The results of a run as data, for people to read: one row per parameter (estimate ± σ, the
//! reference or truth, the error, a status) and the fit quality of each modelled coefficient
//! (residual RMS, R², Theil's U), computed here (with the same formulas as the validation
//! metrics: [`crate::validation::fit_statistics`]) and rendered elsewhere (the command line's `table` on
//! the console, its `report` in `report.html`).
//!
//! Fit quality compares a measured coefficient `z` (from the record,
//! [`AirDataSample::measured_coefficients`]) with the model's prediction `y` from the final
//! estimates (`Σ θ_j ξ_j`, [`coefficient_value`]) over the samples the estimator was fed:
//! - residual RMS `√(mean (z − y)²)` (units of the coefficient);
//! - R² = `1 − Σ(z − y)² / Σ(z − z̄)²`, the coefficient of determination (Klein & Morelli
//!   2006 §5.4); `None` when `z` is constant;
//! - Theil's inequality coefficient U = `√mean(z − y)² / (√mean z² + √mean y²)` (Jategaonkar
//!   2015, model validation: 0 = perfect, 1 = no agreement); `None` when both are zero.

use aeroident_estimators::vocabulary::coefficient_value;
use aeroident_estimators::{AirDataSample, Coefficient, ModelStructure};

pub use aeroident_io::parameter::ParameterResult;

/// Fit quality of one coefficient (module doc).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FitQuality {
    /// What was measured: a coefficient (`Cm`, `CL` …) or an output-error output (`alpha_rad` …).
    pub coefficient: String,
    /// Samples compared.
    pub samples: usize,
    /// Residual RMS, units of the coefficient.
    pub residual_rms: f64,
    /// Coefficient of determination.
    pub r_squared: Option<f64>,
    /// Theil's inequality coefficient, 0…1.
    pub theil_u: Option<f64>,
}

impl From<&crate::validation::OutputValidation> for FitQuality {
    /// The fit-quality row of a validated output (its name, samples, RMSE, R², Theil U).
    fn from(o: &crate::validation::OutputValidation) -> Self {
        Self {
            coefficient: o.name.clone(),
            samples: o.n,
            residual_rms: o.rmse,
            r_squared: o.r_squared,
            theil_u: o.theil_u,
        }
    }
}

/// Fit quality of `predicted` against `measured` (module doc); pairs with a non-finite member
/// are skipped. `None` with no finite pair or lengths that differ.
pub fn fit_quality(coefficient: &str, measured: &[f64], predicted: &[f64]) -> Option<FitQuality> {
    if measured.len() != predicted.len() {
        return None;
    }
    let (z, y): (Vec<f64>, Vec<f64>) = measured
        .iter()
        .zip(predicted)
        .filter(|(z, y)| z.is_finite() && y.is_finite())
        .map(|(z, y)| (*z, *y))
        .unzip();
    if z.is_empty() {
        return None;
    }
    let s = crate::validation::fit_statistics(&z, &y);
    Some(FitQuality {
        coefficient: coefficient.to_string(),
        samples: z.len(),
        residual_rms: s.rmse,
        r_squared: s.r_squared,
        theil_u: s.theil_u,
    })
}

/// One coefficient's measured and predicted time series (for the overlay and residual figure).
#[derive(Debug, Clone, PartialEq)]
pub struct CoefficientFit {
    /// The coefficient.
    pub coefficient: Coefficient,
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Measured coefficient (NaN where the sample gives none).
    pub measured: Vec<f64>,
    /// Model prediction from the final estimates (NaN where a term is unavailable).
    pub predicted: Vec<f64>,
}

impl CoefficientFit {
    /// The fit quality of this series.
    pub fn quality(&self) -> Option<FitQuality> {
        fit_quality(self.coefficient.name(), &self.measured, &self.predicted)
    }
}

/// Measured versus predicted series of every coefficient of `structure` whose parameters are
/// all identified in `theta` (`theta[i]` = final estimate of parameter `i`) and that the
/// samples measure at least once.
pub fn coefficient_fits(
    structure: &ModelStructure,
    theta: &[Option<f64>],
    samples: &[AirDataSample],
) -> Vec<CoefficientFit> {
    let mut out = Vec::new();
    for c in structure.coefficients() {
        let first = structure.first_index(c);
        let n = structure.n_terms(c);
        if theta.len() < first + n || theta[first..first + n].iter().any(Option::is_none) {
            continue;
        }
        let full: Vec<f64> = theta.iter().map(|v| v.unwrap_or(f64::NAN)).collect();
        let mut fit = CoefficientFit {
            coefficient: c,
            t_s: Vec::with_capacity(samples.len()),
            measured: Vec::with_capacity(samples.len()),
            predicted: Vec::with_capacity(samples.len()),
        };
        for s in samples {
            fit.t_s.push(s.t_s);
            fit.measured.push(s.measured_coefficients()[c.index()].unwrap_or(f64::NAN));
            fit.predicted.push(coefficient_value(structure, &full, c, s).unwrap_or(f64::NAN));
        }
        if fit.measured.iter().any(|v| v.is_finite()) {
            out.push(fit);
        }
    }
    out
}

/// Most samples the replay keeps for the fit quality and the model-vs-measured figure
/// (a [`crate::sample_log::SampleLog`] of single samples): 16,384 (≈ 10 MB; a power of two, so
/// the log's capacity never exceeds it). Beyond it every second sample is dropped and the
/// stride doubles; the fit quality is then computed on the kept samples.
pub const MAX_FIT_SAMPLES: usize = 16_384;

/// The results of one run, ready to render.
#[derive(Debug, Clone, PartialEq)]
pub struct Results {
    /// Heading, e.g. `hfb320_1_10.csv — rls — longitudinal`.
    pub title: String,
    /// Header of the reference column: `reference` (published) or `truth` (simulation).
    pub reference_label: String,
    /// One row per parameter.
    pub rows: Vec<ParameterResult>,
    /// Fit quality per coefficient (may be empty).
    pub fit: Vec<FitQuality>,
    /// Lines printed under the tables (sources, caveats).
    pub notes: Vec<String>,
}

impl Results {
    /// Each row's flags as `name: flag` lines, in row order, at most `limit` of them and then
    /// one line counting the rest (the tables print them under the status column, which says
    /// only `flagged`).
    pub fn flag_lines(&self, limit: usize) -> Vec<String> {
        Self::lines(self.rows.iter().map(|r| (&r.name, &r.flags)), limit, "flags")
    }

    /// Each row's notes (no doubt about the value: a σ above 10 % of it) as `name: note`
    /// lines, as [`Self::flag_lines`].
    pub fn note_lines(&self, limit: usize) -> Vec<String> {
        Self::lines(self.rows.iter().map(|r| (&r.name, &r.notes)), limit, "notes")
    }

    fn lines<'a>(
        rows: impl Iterator<Item = (&'a String, &'a Vec<String>)>,
        limit: usize,
        key: &str,
    ) -> Vec<String> {
        let all: Vec<String> = rows
            .flat_map(|(name, texts)| texts.iter().map(move |f| format!("{name}: {f}")))
            .collect();
        let mut out: Vec<String> = all.iter().take(limit).cloned().collect();
        if all.len() > limit {
            out.push(format!(
                "… and {} more {key} (summary.json: parameters[].{key})",
                all.len() - limit
            ));
        }
        out
    }

    /// Whether any row carries a Cramér–Rao σ beside its σ (the tables then show that column).
    pub fn has_crb_std_error(&self) -> bool {
        self.rows.iter().any(|r| r.crb_std_error.is_some())
    }
}

/// One output of a batch fit over the record: measured `z` and the model's simulated `ŷ`
/// (`z − e`, the fit's residual `e`) against time. A NaN point separates manoeuvres; long
/// records keep every `stride`th sample (at most [`OutputTrace::MAX_POINTS`]).
#[derive(Debug, Clone, PartialEq)]
pub struct OutputTrace {
    /// Output name (`alpha`, `q`, `vt` … as the output-error fit names them).
    pub name: String,
    /// Record time, s.
    pub t_s: Vec<f64>,
    /// Measured output (the unit of the output: rad, rad/s, m/s …).
    pub measured: Vec<f64>,
    /// Simulated output with the estimated parameters, same unit.
    pub simulated: Vec<f64>,
    /// Every `stride`th sample kept.
    pub stride: usize,
}

impl OutputTrace {
    /// The most points a trace keeps (figures draw at most a few thousand anyway).
    pub const MAX_POINTS: usize = 20_000;
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::{AircraftConstants, Term};

    /// The flag lines name their parameter, keep the rows' order and count what the limit
    /// leaves out.
    #[test]
    fn flag_lines_are_listed_then_counted() {
        let mut a = ParameterResult::new("Cm_q", Some(-5.0), Some(1.0), None, None);
        a.flag("one");
        a.flag("two");
        let mut b = ParameterResult::new("Cl_p", Some(-0.4), Some(0.1), None, None);
        b.flag("three");
        let r = Results {
            title: String::new(),
            reference_label: String::new(),
            rows: vec![a, b],
            fit: Vec::new(),
            notes: Vec::new(),
        };
        assert_eq!(r.flag_lines(5), ["Cm_q: one", "Cm_q: two", "Cl_p: three"]);
        let short = r.flag_lines(1);
        assert_eq!(short[0], "Cm_q: one");
        assert!(short[1].starts_with("… and 2 more flags"), "{short:?}");
    }

    /// Hand-computed values: z = [1, 2, 3, 4], y = [1, 2, 3, 5]: SS_res = 1, SS_tot = 5,
    /// RMS = 1/2, R² = 0.8, U = 0.5 / (√7.5 + √9.75).
    #[test]
    fn analytic_fit_quality_by_hand() {
        let q = fit_quality("Cm", &[1.0, 2.0, 3.0, 4.0], &[1.0, 2.0, 3.0, 5.0]).unwrap();
        assert_eq!(q.samples, 4);
        assert!((q.residual_rms - 0.5).abs() < 1e-15);
        assert!((q.r_squared.unwrap() - 0.8).abs() < 1e-15);
        let u = 0.5 / (7.5f64.sqrt() + 9.75f64.sqrt());
        assert!((q.theil_u.unwrap() - u).abs() < 1e-15);
        // A perfect fit: RMS 0, R² 1, U 0; NaN pairs are skipped.
        let q = fit_quality("CL", &[1.0, f64::NAN, 3.0], &[1.0, 7.0, 3.0]).unwrap();
        assert_eq!(
            (q.samples, q.residual_rms, q.r_squared, q.theil_u),
            (2, 0.0, Some(1.0), Some(0.0))
        );
        // Constant measurement: no R²; all zero: no U; nothing finite: no result.
        assert_eq!(fit_quality("CD", &[0.0, 0.0], &[0.0, 0.0]).unwrap().theil_u, None);
        assert_eq!(fit_quality("CD", &[2.0, 2.0], &[1.0, 3.0]).unwrap().r_squared, None);
        assert!(fit_quality("CD", &[f64::NAN], &[1.0]).is_none());
        assert!(fit_quality("CD", &[1.0], &[1.0, 2.0]).is_none());
    }

    /// The prediction is Σ θ ξ on each sample: with Cm = 0.1 − 0.5 α and samples generated
    /// from exactly that model (q̇ = Cm q̄ S c̄ / Iyy), R² = 1 and the residual is 0 to rounding.
    #[test]
    fn analytic_prediction_reproduces_an_exact_model() {
        let st = ModelStructure::empty().with(Coefficient::Cm, &[Term::Bias, Term::Alpha]);
        let k = AircraftConstants {
            mass_kg: 1000.0,
            S_m2: 10.0,
            cbar_m: Some(2.0),
            Iyy_kgm2: Some(4000.0),
            ..Default::default()
        };
        let samples: Vec<AirDataSample> = (0..50)
            .map(|i| {
                let t = i as f64 * 0.1;
                let alpha = 0.05 + 0.03 * (1.7 * t).sin();
                let qbar = 2000.0;
                let cm = 0.1 - 0.5 * alpha;
                AirDataSample {
                    t_s: t,
                    vt_mps: 60.0,
                    alpha_rad: alpha,
                    qbar_pa: qbar,
                    q_rad_s: Some(0.0),
                    qdot_rad_s2: Some(cm * qbar * 10.0 * 2.0 / 4000.0),
                    constants: k,
                    ..Default::default()
                }
            })
            .collect();
        let fits = coefficient_fits(&st, &[Some(0.1), Some(-0.5)], &samples);
        assert_eq!(fits.len(), 1);
        let q = fits[0].quality().unwrap();
        assert_eq!(q.samples, 50);
        assert!(q.residual_rms < 1e-12, "{q:?}");
        assert!((q.r_squared.unwrap() - 1.0).abs() < 1e-9, "{q:?}");
        // A parameter not identified: no fit for its coefficient.
        assert!(coefficient_fits(&st, &[Some(0.1), None], &samples).is_empty());
    }
}
