//! Errors of the signals crate: every variant names the offending field (or file, row and
//! column) and the value that was rejected, so a bad scenario file can be fixed from the message.

use std::path::PathBuf;

/// Error building or reading a signal, disturbance or sensor model.
///
/// Signals are validated once, at construction; `value()` itself never fails and never returns
/// NaN for finite parameters.
#[derive(Debug, thiserror::Error)]
pub enum SignalError {
    /// A numeric parameter is out of its valid range, e.g. a negative sample time.
    #[error("invalid `{field}` = {value}: {reason}")]
    InvalidParameter {
        /// Name of the parameter as it appears in the API and in TOML (e.g. `sample_time_s`).
        field: &'static str,
        /// The rejected value.
        value: f64,
        /// Why it was rejected, e.g. "must be finite and > 0".
        reason: &'static str,
    },
    /// A quantity that can be given in two units was given in both or in neither, e.g.
    /// `amplitude` and `amplitude_deg`.
    #[error("give exactly one of `{first}` and `{second}` ({problem})")]
    UnitChoice {
        /// First accepted key, e.g. `amplitude`.
        first: &'static str,
        /// Second accepted key, e.g. `amplitude_deg`.
        second: &'static str,
        /// "both given" or "neither given".
        problem: &'static str,
    },
    /// A list-valued parameter is malformed, e.g. an empty harmonic list.
    #[error("invalid `{field}`: {reason}")]
    InvalidList {
        /// Name of the parameter.
        field: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// A recorded-input CSV file could not be opened or read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A recorded-input CSV file has a bad row (rows are 1-based data rows after the header).
    #[error("{}: row {row}, column `{column}`: {reason}", path.display())]
    Csv {
        /// The file.
        path: PathBuf,
        /// 1-based line number in the file (the header is line 1).
        row: usize,
        /// Column name (from the header) or index.
        column: String,
        /// What is wrong, with the offending text or value.
        reason: String,
    },
}

/// Checks that `value` is finite and strictly positive.
pub(crate) fn positive(field: &'static str, value: f64) -> Result<f64, SignalError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(SignalError::InvalidParameter { field, value, reason: "must be finite and > 0" })
    }
}

/// Checks that `value` is finite and ≥ 0.
pub(crate) fn non_negative(field: &'static str, value: f64) -> Result<f64, SignalError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(SignalError::InvalidParameter { field, value, reason: "must be finite and >= 0" })
    }
}

/// Checks that `value` is finite (any sign).
pub(crate) fn finite(field: &'static str, value: f64) -> Result<f64, SignalError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(SignalError::InvalidParameter { field, value, reason: "must be finite" })
    }
}
