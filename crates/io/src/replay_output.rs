//! Writers for `aeroident replay` results: the per-sample `estimates.csv` and `summary.json`.
//!
//! `estimates.csv` header: `t_s,<name>...,sigma_<name>...` (one line per estimate; an empty
//! sigma field means the method gives no standard error there — never a made-up number).
//!
//! `summary.json` keys (issue 5): `estimator, samples_read, samples_rejected,
//! rejections[{row, reason}], throughput_samples_per_s, parameters[{name, estimate, std_error,
//! settle_time_s}]`. `std_error` and `settle_time_s` are `null` where undefined.

use crate::flight_data::Rejection;
use serde::Serialize;
use std::io::Write;

/// One parameter's final result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterSummary {
    /// Parameter name, e.g. `Cm_alpha` (per rad) or `Cm_q` (per unit q̂).
    pub name: String,
    /// Final estimate.
    pub estimate: f64,
    /// Final standard error, if the method gives one.
    pub std_error: Option<f64>,
    /// Settling time, s (see `aeroident::replay::settle_time_s` for the definition).
    pub settle_time_s: Option<f64>,
}

/// The `summary.json` document.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReplaySummary {
    /// Estimator name (`rls`, `ekf`, …).
    pub estimator: String,
    /// Data rows read (accepted + rejected).
    pub samples_read: usize,
    /// Rows rejected.
    pub samples_rejected: usize,
    /// Every rejected row and every gap (gap entries reject nothing; their reason starts with
    /// `gap`).
    pub rejections: Vec<Rejection>,
    /// Samples per second through the estimation stage (measured coefficients + estimator
    /// update; CSV parsing, pacing and output excluded), one core.
    pub throughput_samples_per_s: f64,
    /// Final parameter estimates.
    pub parameters: Vec<ParameterSummary>,
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
    values: &[f64],
    sigmas: &[Option<f64>],
) -> std::io::Result<()> {
    write!(w, "{t_s}")?;
    for v in values {
        write!(w, ",{v}")?;
    }
    for s in sigmas {
        match s {
            Some(s) => write!(w, ",{s}")?,
            None => write!(w, ",")?,
        }
    }
    writeln!(w)
}
