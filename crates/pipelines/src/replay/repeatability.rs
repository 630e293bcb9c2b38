//! Whether an estimate repeats across the record's manoeuvres: the flight-test engineer's own
//! test. A record with two or more manoeuvres (windows, gaps, `--and` files) is fitted by each
//! manoeuvre alone beside the joint fit; each parameter's solo estimates are tested for
//! agreement against their σ, as a flight-test report compares the estimates of repeated
//! manoeuvres.
//!
//! The statistic of one parameter over the `k` manoeuvres that determine it (solo σ at most
//! [`MAX_RELATIVE_SIGMA`] of |estimate|, a fit that converged): the weighted mean
//! `θ̄ = Σ θᵢ/σᵢ² / Σ 1/σᵢ²` and `χ² = Σ (θᵢ − θ̄)²/σᵢ²` with `k − 1` degrees of freedom. The
//! manoeuvres are disjoint stretches of data, so their errors are independent and, if each σ
//! covers its error and the aircraft is the same, `χ²` follows `χ²_{k−1}`. A p-value below
//! [`SIGNIFICANCE`] says the values differ by more than their σ: a model that does not hold
//! across the manoeuvres (a missing term, a nonlinearity over the flight envelope flown, a
//! time skew), or σ that understate the error. Either way the joint estimate is known no better
//! than the manoeuvres agree: its σ is scaled by the Birge ratio `√(χ²/(k−1))` (the Particle
//! Data Group's scale factor for averages of measurements that disagree) so that its ±2σ spans the manoeuvres' spread, the
//! source then `repeatability`, and a note gives the values.
//!
//! A note, not a flag: on the calibration corpus's tune half (`scripts/verdict_corpus`, 82
//! output-error estimates of primary derivatives that did not repeat) the joint value was no
//! more often 10 % off the truth (29 %) than where the manoeuvres agreed (30 %), while the
//! scaled σ covered the truth in 84 % of them against 58 %: the test says how well the value is
//! known, not that it is wrong.

use aeroident_io::warning::{Warning, WarningKind};
use aeroident_io::{ParameterResult, StdErrorSource};
use serde::Serialize;

/// p-value of the χ² test below which a parameter does not repeat (one false flag in a
/// hundred parameters whose σ are honest).
pub const SIGNIFICANCE: f64 = 0.01;

/// A manoeuvre whose solo σ exceeds this share of its |estimate| does not determine the
/// parameter (it does not fix even its sign to 1σ) and is left out of its test.
pub const MAX_RELATIVE_SIGMA: f64 = 1.0;

/// The status of a solo fit that converged (the only one compared).
pub const CONVERGED: &str = "converged";

/// One manoeuvre fitted alone.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SoloFit {
    /// The manoeuvre's index in the record (from 0, in time order; files in `--and` order).
    pub manoeuvre: usize,
    /// Its first sample time, s.
    pub t_start_s: f64,
    /// Its last sample time, s.
    pub t_end_s: f64,
    /// Its samples.
    pub samples: usize,
    /// [`CONVERGED`], `not converged` or `failed: why` (only a converged fit is compared).
    pub status: String,
    /// The estimates of a converged fit (σ finite and positive).
    #[serde(skip)]
    pub estimates: Vec<super::cross_check::ParameterEstimate>,
}

impl SoloFit {
    /// Manoeuvre `k` of samples `m`, not yet fitted (empty status, no estimates).
    pub fn of(k: usize, m: &[aeroident_estimators::AirDataSample]) -> Self {
        Self {
            manoeuvre: k,
            t_start_s: m.first().map_or(f64::NAN, |s| s.t_s),
            t_end_s: m.last().map_or(f64::NAN, |s| s.t_s),
            samples: m.len(),
            status: String::new(),
            estimates: Vec::new(),
        }
    }
}

/// One manoeuvre's estimate of a parameter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ManoeuvreValue {
    /// The manoeuvre ([`SoloFit::manoeuvre`]).
    pub manoeuvre: usize,
    /// Its solo estimate.
    pub estimate: f64,
    /// Its solo σ.
    pub std_error: f64,
}

/// The test of one parameter (module doc).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Repeat {
    /// The parameter.
    pub parameter: String,
    /// The manoeuvres that determine it, with their values.
    pub values: Vec<ManoeuvreValue>,
    /// The weighted mean θ̄.
    pub weighted_mean: f64,
    /// `Σ (θᵢ − θ̄)²/σᵢ²`.
    pub chi2: f64,
    /// `k − 1`.
    pub dof: usize,
    /// `P(χ²_{k−1} > chi2)`.
    pub p_value: f64,
    /// Whether the values agree (`p_value ≥ SIGNIFICANCE`).
    pub repeats: bool,
}

impl Repeat {
    /// The test of `parameter` over `values` (those of the manoeuvres that determine it);
    /// `None` with fewer than two.
    pub fn of(parameter: &str, values: Vec<ManoeuvreValue>) -> Option<Self> {
        if values.len() < 2 {
            return None;
        }
        let w = |v: &ManoeuvreValue| 1.0 / (v.std_error * v.std_error);
        let sum_w: f64 = values.iter().map(w).sum();
        let mean = values.iter().map(|v| w(v) * v.estimate).sum::<f64>() / sum_w;
        let chi2: f64 = values.iter().map(|v| w(v) * (v.estimate - mean).powi(2)).sum();
        let dof = values.len() - 1;
        let p_value = crate::validation::chi2_sf(chi2, dof as f64);
        Some(Self {
            parameter: parameter.to_string(),
            weighted_mean: mean,
            chi2,
            dof,
            p_value,
            repeats: p_value >= SIGNIFICANCE,
            values,
        })
    }

    /// The σ of the weighted mean scaled by the Birge ratio `√(χ²/dof)` when that exceeds 1
    /// (module doc): what the manoeuvres' spread says the joint estimate is known to.
    pub fn spread_sigma(&self) -> f64 {
        let sum_w: f64 = self.values.iter().map(|v| 1.0 / (v.std_error * v.std_error)).sum();
        (self.chi2 / self.dof as f64).max(1.0).sqrt() / sum_w.sqrt()
    }

    /// The note of a parameter that does not repeat, with the values.
    pub fn note(&self) -> String {
        let values: Vec<String> = self
            .values
            .iter()
            .map(|v| format!("#{} {:.4} ± {:.2e}", v.manoeuvre + 1, v.estimate, v.std_error))
            .collect();
        format!(
            "does not repeat across manoeuvres to their σ: {} (χ² {:.1} on {} dof, p = {:.1e} < {SIGNIFICANCE}): the model does not hold across them or their σ understate the error; σ scaled to their spread",
            values.join(", "),
            self.chi2,
            self.dof,
            self.p_value
        )
    }
}

/// The repeatability of a fit (`summary.json` `repeatability`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Repeatability {
    /// [`SIGNIFICANCE`].
    pub significance: f64,
    /// Each manoeuvre's solo fit.
    pub fits: Vec<SoloFit>,
    /// Each parameter determined by two or more manoeuvres.
    pub parameters: Vec<Repeat>,
}

impl Repeatability {
    /// The tests of `names` over the converged `fits` (module doc).
    pub fn assess(fits: Vec<SoloFit>, names: &[String]) -> Self {
        let parameters = names
            .iter()
            .filter_map(|name| {
                let values = fits
                    .iter()
                    .filter(|f| f.status == CONVERGED)
                    .filter_map(|f| {
                        let row = f.estimates.iter().find(|r| r.name == *name)?;
                        let (estimate, std_error) = (row.estimate, row.std_error);
                        (std_error <= MAX_RELATIVE_SIGMA * estimate.abs()).then_some(
                            ManoeuvreValue { manoeuvre: f.manoeuvre, estimate, std_error },
                        )
                    })
                    .collect();
                Repeat::of(name, values)
            })
            .collect();
        Self { significance: SIGNIFICANCE, fits, parameters }
    }

    /// The test of `parameter` that failed, if any.
    pub fn failed(&self, parameter: &str) -> Option<&Repeat> {
        self.parameters.iter().find(|r| r.parameter == parameter && !r.repeats)
    }

    /// Raises `r`'s σ to its manoeuvres' spread ([`Repeat::spread_sigma`], source
    /// `repeatability`) when `r` does not repeat and the spread is the larger.
    pub fn widen(&self, r: &mut ParameterResult) {
        let (Some(rep), Some(sigma)) = (self.failed(&r.name), r.std_error) else { return };
        if rep.spread_sigma() > sigma {
            r.std_error = Some(rep.spread_sigma());
            r.std_error_source = Some(StdErrorSource::Repeatability);
        }
    }

    /// One warning per parameter that does not repeat (naming it, not about it: the judge
    /// takes it as a note, [`Self::failed`]), and one naming the solo fits that did not
    /// converge.
    pub fn warnings(&self) -> Vec<Warning> {
        let flags = self.parameters.iter().filter(|r| !r.repeats).map(|r| {
            Warning::new(WarningKind::Consistency, format!("{}: {}", r.parameter, r.note()))
        });
        let unfit: Vec<String> = self
            .fits
            .iter()
            .filter(|f| f.status != CONVERGED)
            .map(|f| format!("#{} ({})", f.manoeuvre + 1, f.status))
            .collect();
        let note = (!unfit.is_empty()).then(|| {
            Warning::new(
                WarningKind::Consistency,
                format!(
                    "repeatability: manoeuvres fitted alone without a result, left out of the test: {}",
                    unfit.join(", ")
                ),
            )
        });
        flags.chain(note).collect()
    }
}

#[cfg(test)]
mod tests;
