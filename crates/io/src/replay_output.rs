//! Writers for `aeroident replay` results: the per-sample `estimates.csv` and `summary.json`.
//!
//! `estimates.csv` header: `t_s,<name>...,sigma_<name>...` (one line per estimate). An empty
//! field means the value is not identified yet, or the method gives no standard error there —
//! never a made-up number.
//!
//! `summary.json` keys: `estimator, model, status, samples_read, samples_rejected,
//! rejections[{row, reason}], throughput_samples_per_s, parameters[{name, estimate, std_error,
//! settle_time_s}], coefficients[{name, condition_number}], correlations[{a, b, rho}]`.
//! `estimate`, `std_error`, `settle_time_s` and `condition_number` are `null` where undefined
//! (not identified, no covariance from the method).

use crate::flight_data::Rejection;
use serde::Serialize;
use std::io::Write;

/// One parameter's final result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterSummary {
    /// Parameter name, e.g. `Cm_alpha` (per rad) or `Cm_q` (per unit q̂).
    pub name: String,
    /// Final estimate; `null` until identified (and when the estimator diverged).
    pub estimate: Option<f64>,
    /// Final standard error, if the method gives one and the parameter is identified.
    pub std_error: Option<f64>,
    /// Settling time, s (see `aeroident::replay::settle_time_s` for the definition).
    pub settle_time_s: Option<f64>,
}

/// One modelled coefficient's diagnostics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CoefficientSummary {
    /// Coefficient name (`CL`, `Cm`, `Cn` …).
    pub name: String,
    /// 2-norm condition number of the correlation matrix of the coefficient's parameters
    /// (the estimator's covariance scaled to unit diagonal); large values (> 10³) flag terms
    /// the data cannot separate. `null` where the estimator gives no covariance.
    pub condition_number: Option<f64>,
}

/// A pair of parameters whose estimates are strongly correlated.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Correlation {
    /// First parameter.
    pub a: String,
    /// Second parameter.
    pub b: String,
    /// Correlation coefficient `cov(a,b)/(σ_a σ_b)`, |ρ| > 0.9.
    pub rho: f64,
}

/// The `summary.json` document.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReplaySummary {
    /// Estimator name (`rls`, `ekf`, …).
    pub estimator: String,
    /// The model: a preset name (`longitudinal`, `lateral`, `six-axis`) or the model file.
    pub model: String,
    /// Estimator status at the end: `running`, `initialising` or `diverged`.
    pub status: String,
    /// Data rows read (accepted + rejected).
    pub samples_read: usize,
    /// Rows rejected.
    pub samples_rejected: usize,
    /// The rejected rows and gaps (gap entries reject nothing; their reason starts with
    /// `gap`): the first [`crate::RejectionLog::DEFAULT_LIMIT`] and always the last; the
    /// others are counted per kind in `warnings` ([`crate::RejectionLog`]).
    pub rejections: Vec<Rejection>,
    /// Samples per second through the estimation stage (estimator update; CSV parsing,
    /// differentiation, pacing and output excluded), one core.
    pub throughput_samples_per_s: f64,
    /// Final parameter estimates.
    pub parameters: Vec<ParameterSummary>,
    /// Per modelled coefficient: the condition number.
    pub coefficients: Vec<CoefficientSummary>,
    /// Every pair of parameters with |ρ| > 0.9 (where the estimator gives covariances).
    pub correlations: Vec<Correlation>,
    /// Warnings about the record or the run (e.g. the mapping's `nominal_dt_s` disagrees with
    /// the measured interval; a time jump not slept across in real-time pacing).
    pub warnings: Vec<String>,
}

impl ReplaySummary {
    /// Writes the summary as pretty JSON.
    ///
    /// # Errors
    /// I/O errors of `w`.
    pub fn write_json<W: Write>(&self, w: W) -> std::io::Result<()> {
        serde_json::to_writer_pretty(w, self).map_err(std::io::Error::other)
    }
}

/// Writes the CSV header `t_s,<names>,sigma_<names>`.
///
/// # Errors
/// I/O errors of `w`.
pub fn write_estimates_header<W: Write>(w: &mut W, names: &[&str]) -> std::io::Result<()> {
    write!(w, "t_s")?;
    for n in names {
        write!(w, ",{n}")?;
    }
    for n in names {
        write!(w, ",sigma_{n}")?;
    }
    writeln!(w)
}

/// Writes one estimates line; `None` values become empty fields.
///
/// # Errors
/// I/O errors of `w`.
pub fn write_estimates_row<W: Write>(
    w: &mut W,
    t_s: f64,
    values: &[Option<f64>],
    sigmas: &[Option<f64>],
) -> std::io::Result<()> {
    write!(w, "{t_s}")?;
    for v in values {
        match v {
            Some(v) => write!(w, ",{v}")?,
            None => write!(w, ",")?,
        }
    }
    for s in sigmas {
        match s {
            Some(s) => write!(w, ",{s}")?,
            None => write!(w, ",")?,
        }
    }
    writeln!(w)
}
