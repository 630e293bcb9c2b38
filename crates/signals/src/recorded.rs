//! A recorded input read from a CSV file of (time, value) pairs, replayed with linear
//! interpolation: a test input flown before (a pilot's, another tool's) flown again as it was.
//!
//! # File format
//! A header line, then one row per sample. By default the first column is the time (s) and the
//! second the value; other columns may be chosen by header name. Times must be finite and
//! strictly increasing; values finite. Values are in the caller's units unless converted with a
//! [`ValueUnit`] (e.g. a stick-trace recorded in degrees).
//!
//! ```csv
//! t_s,elevator_deg
//! 0.0,0.0
//! 1.0,0.5
//! 1.5,-0.5
//! ```
//!
//! # Outside the recorded span
//! Before the first sample the FIRST value is held, after the last sample the LAST value is held
//! (Simulink "From Workspace" with "hold final value"). A recorded deflection therefore stays where
//! the recording left it; end the file with a 0 row if the input should return to trim.

use std::io::Read;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::InputSignal;
use crate::error::SignalError;

/// Unit of the values in a recorded file, converted once on load.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ValueUnit {
    /// Values are already in the caller's units (radians for surfaces): used as they are.
    #[default]
    AsIs,
    /// Values are in degrees: multiplied by π/180.
    Deg,
}

impl ValueUnit {
    fn scale(self, v: f64) -> f64 {
        match self {
            ValueUnit::AsIs => v,
            ValueUnit::Deg => v.to_radians(),
        }
    }
}

/// Piecewise-linear replay of recorded `(t_s, value)` samples; holds the first/last value
/// outside the recorded span (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct RecordedInput {
    t_s: Vec<f64>,
    values: Vec<f64>,
}

impl RecordedInput {
    /// From samples in memory: `t_s` (s, finite, strictly increasing) and `values` (finite,
    /// same length, at least one).
    ///
    /// # Errors
    /// [`SignalError::InvalidList`] naming the first offending index.
    pub fn new(t_s: Vec<f64>, values: Vec<f64>) -> Result<Self, SignalError> {
        if t_s.is_empty() || t_s.len() != values.len() {
            return Err(SignalError::InvalidList {
                field: "t_s",
                reason: format!(
                    "need at least one sample and equal lengths, got {} times and {} values",
                    t_s.len(),
                    values.len()
                ),
            });
        }
        for i in 0..t_s.len() {
            if !t_s[i].is_finite() || (i > 0 && t_s[i] <= t_s[i - 1]) {
                return Err(SignalError::InvalidList {
                    field: "t_s",
                    reason: format!("entry {i} = {} is not finite or not increasing", t_s[i]),
                });
            }
            if !values[i].is_finite() {
                return Err(SignalError::InvalidList {
                    field: "values",
                    reason: format!("entry {i} = {} is not finite", values[i]),
                });
            }
        }
        Ok(Self { t_s, values })
    }

    /// Reads a CSV file (see the module docs). `time_column` / `value_column` select columns by
    /// header name (`None`: first / second column); `unit` converts the values.
    ///
    /// # Errors
    /// [`SignalError::Io`] if the file cannot be opened; [`SignalError::Csv`] naming the file,
    /// the line (the header is line 1) and the column for a missing column, a field that is not
    /// a number, a NaN/inf, a time that does not increase, or a file without data rows.
    pub fn from_csv_path(
        path: &Path,
        time_column: Option<&str>,
        value_column: Option<&str>,
        unit: ValueUnit,
    ) -> Result<Self, SignalError> {
        let file = std::fs::File::open(path)
            .map_err(|source| SignalError::Io { path: path.to_path_buf(), source })?;
        Self::from_csv_reader(file, path, time_column, value_column, unit)
    }

    /// As [`RecordedInput::from_csv_path`] but from any reader; `path` is only used in errors.
    ///
    /// # Errors
    /// As [`RecordedInput::from_csv_path`].
    pub fn from_csv_reader<R: Read>(
        reader: R,
        path: &Path,
        time_column: Option<&str>,
        value_column: Option<&str>,
        unit: ValueUnit,
    ) -> Result<Self, SignalError> {
        let err = |row: usize, column: &str, reason: String| SignalError::Csv {
            path: PathBuf::from(path),
            row,
            column: column.to_string(),
            reason,
        };
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(true)
            .flexible(true)
            .trim(csv::Trim::All)
            .from_reader(reader);
        let headers =
            rdr.headers().map_err(|e| err(1, "-", format!("cannot read header: {e}")))?.clone();
        let find = |name: Option<&str>, default: usize| -> Result<(usize, String), SignalError> {
            match name {
                Some(n) => {
                    headers.iter().position(|h| h == n).map(|i| (i, n.to_string())).ok_or_else(
                        || {
                            err(
                                1,
                                n,
                                format!(
                                    "no such column in header [{}]",
                                    headers.iter().collect::<Vec<_>>().join(", ")
                                ),
                            )
                        },
                    )
                }
                None => Ok((
                    default,
                    headers
                        .get(default)
                        .map_or_else(|| format!("#{}", default + 1), str::to_string),
                )),
            }
        };
        let (ti, tname) = find(time_column, 0)?;
        let (vi, vname) = find(value_column, 1)?;
        let mut t_s: Vec<f64> = Vec::new();
        let mut values = Vec::new();
        for rec in rdr.records() {
            let rec = rec.map_err(|e| {
                let line = e.position().map_or(0, |p| p.line() as usize);
                err(line, "-", format!("malformed CSV: {e}"))
            })?;
            let line = rec.position().map_or(0, |p| p.line() as usize);
            let field = |i: usize, name: &str| -> Result<f64, SignalError> {
                let text = rec.get(i).ok_or_else(|| err(line, name, "missing field".into()))?;
                let v: f64 = text
                    .parse()
                    .map_err(|_| err(line, name, format!("`{text}` is not a number")))?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(err(line, name, format!("`{text}` is not finite")))
                }
            };
            let t = field(ti, &tname)?;
            let v = field(vi, &vname)?;
            if let Some(&prev) = t_s.last()
                && t <= prev
            {
                return Err(err(
                    line,
                    &tname,
                    format!("time {t} does not increase (previous row {prev})"),
                ));
            }
            t_s.push(t);
            values.push(unit.scale(v));
        }
        if t_s.is_empty() {
            return Err(err(1, "-", "no data rows after the header".into()));
        }
        Ok(Self { t_s, values })
    }

    /// Recorded times (s).
    pub fn times_s(&self) -> &[f64] {
        &self.t_s
    }

    /// Recorded values (converted units).
    pub fn values(&self) -> &[f64] {
        &self.values
    }
}

impl InputSignal for RecordedInput {
    fn value(&self, t_s: f64) -> f64 {
        let n = self.t_s.len();
        // Index of the first sample strictly after t (binary search, no allocation).
        let i = self.t_s.partition_point(|&x| x <= t_s);
        if i == 0 {
            self.values[0]
        } else if i == n {
            self.values[n - 1]
        } else {
            let (t0, t1) = (self.t_s[i - 1], self.t_s[i]);
            let (v0, v1) = (self.values[i - 1], self.values[i]);
            v0 + (v1 - v0) * (t_s - t0) / (t1 - t0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<RecordedInput, SignalError> {
        RecordedInput::from_csv_reader(
            text.as_bytes(),
            Path::new("stick.csv"),
            None,
            None,
            ValueUnit::AsIs,
        )
    }

    #[test]
    fn analytic_linear_interpolation_and_hold_outside() {
        let r = read("t_s,de\n0.0,0.0\n1.0,2.0\n3.0,-2.0\n").unwrap();
        assert_eq!(r.value(-5.0), 0.0);
        assert_eq!(r.value(0.0), 0.0);
        assert_eq!(r.value(0.25), 0.5);
        assert_eq!(r.value(1.0), 2.0);
        assert_eq!(r.value(2.0), 0.0);
        assert_eq!(r.value(2.5), -1.0);
        assert_eq!(r.value(3.0), -2.0);
        assert_eq!(r.value(100.0), -2.0);
    }

    #[test]
    fn analytic_named_columns_and_degrees() {
        let r = RecordedInput::from_csv_reader(
            "a,t,de_deg\n9,0,0\n9,2,90\n".as_bytes(),
            Path::new("x.csv"),
            Some("t"),
            Some("de_deg"),
            ValueUnit::Deg,
        )
        .unwrap();
        assert!((r.value(1.0) - core::f64::consts::FRAC_PI_4).abs() < 1e-15);
        let e = RecordedInput::from_csv_reader(
            "a,t\n1,2\n".as_bytes(),
            Path::new("x.csv"),
            Some("time"),
            None,
            ValueUnit::AsIs,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("x.csv") && e.contains("`time`"), "{e}");
    }

    #[test]
    fn errors_name_file_row_and_column() {
        let e = read("t_s,de\n0,1\n1,abc\n").unwrap_err().to_string();
        assert!(
            e.contains("stick.csv")
                && e.contains("row 3")
                && e.contains("`de`")
                && e.contains("abc"),
            "{e}"
        );
        let e = read("t_s,de\n0,1\n1,NaN\n").unwrap_err().to_string();
        assert!(e.contains("row 3") && e.contains("not finite"), "{e}");
        let e = read("t_s,de\n0,1\n1,2\n0.5,3\n").unwrap_err().to_string();
        assert!(
            e.contains("row 4") && e.contains("`t_s`") && e.contains("does not increase"),
            "{e}"
        );
        let e = read("t_s,de\n0,1\n1\n").unwrap_err().to_string();
        assert!(e.contains("row 3") && e.contains("missing"), "{e}");
        let e = read("t_s,de\n").unwrap_err().to_string();
        assert!(e.contains("no data rows"), "{e}");
        let e = RecordedInput::from_csv_path(
            Path::new("/nonexistent/dir/f.csv"),
            None,
            None,
            ValueUnit::AsIs,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("/nonexistent/dir/f.csv"), "{e}");
    }

    #[test]
    fn analytic_single_sample_is_constant_and_new_validates() {
        let r = RecordedInput::new(vec![1.0], vec![4.0]).unwrap();
        assert_eq!(r.value(0.0), 4.0);
        assert_eq!(r.value(9.0), 4.0);
        assert!(RecordedInput::new(vec![0.0, 0.0], vec![1.0, 2.0]).is_err());
        assert!(RecordedInput::new(vec![], vec![]).is_err());
        assert!(RecordedInput::new(vec![0.0, 1.0], vec![1.0, f64::NAN]).is_err());
    }
}
