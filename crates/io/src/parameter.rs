//! One parameter's result, the same from the estimator to every `summary.json` (`run`,
//! `replay`, the batch fits, `montecarlo`, `poc`), the console table, `report.html` and Python.
//!
//! Keys (schema version [`SCHEMA_VERSION`]): `name`, `estimate`, `std_error`,
//! `std_error_source`, `crb_std_error`, `reference`, `status`, `flags`. A command adds its own
//! keys beside them (a settling time, a bootstrap bias …) in the same object. Schema 1 called
//! the estimate `final`, its σ `sigma` and the truth `truth` in `run`, `montecarlo` and `poc`,
//! and `crb_sigma` in the batch fits (docs/output-schema.md lists every renamed key).

use serde::{Deserialize, Serialize};

/// The version of the `summary.json` key set, written as `schema_version` in every summary.
pub const SCHEMA_VERSION: u32 = 2;

/// Values of magnitude below this are numerical noise around 0: a reference that small is
/// round-off of an exact zero (e.g. a simulator's 1e-44 truth) and is reported as 0.
pub const ZERO_THRESHOLD: f64 = 1e-12;

/// The status of an estimate with no verdict against it: identified, σ (if any) not too large,
/// no reference outside ±2σ, no flag.
pub const STATUS_OK: &str = "ok";

/// The status of a parameter the run gave no estimate of.
pub const STATUS_NOT_IDENTIFIED: &str = "not identified";

/// The status of an estimate whose reference lies further than 2σ from it.
pub const STATUS_OUTSIDE_2SIGMA: &str = "outside ±2σ";

/// Which standard error `std_error` is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StdErrorSource {
    /// The recursive estimator's own covariance at the end of the record (RLS, FTR, EKF, the
    /// finite-time sliding-mode estimator).
    Covariance,
    /// The Cramér–Rao bound of a batch fit, `sqrt(diag M⁻¹)` (Jategaonkar 2015 §4.17).
    CramerRao,
    /// The batch fit's σ corrected for coloured residuals (Morelli & Klein 1997).
    Coloured,
    /// The parametric bootstrap's scatter of refits (`--bootstrap N`).
    Bootstrap,
}

impl StdErrorSource {
    /// The key's value in `summary.json`: `covariance`, `cramer_rao`, `coloured`, `bootstrap`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Covariance => "covariance",
            Self::CramerRao => "cramer_rao",
            Self::Coloured => "coloured",
            Self::Bootstrap => "bootstrap",
        }
    }

    /// The source in words, for tables and reports (`Cramér–Rao`, `parametric bootstrap` …).
    pub fn words(self) -> &'static str {
        match self {
            Self::Covariance => "estimator covariance",
            Self::CramerRao => "Cramér–Rao",
            Self::Coloured => "coloured-residual",
            Self::Bootstrap => "parametric bootstrap",
        }
    }
}

/// One parameter's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterResult {
    /// Vocabulary name, e.g. `Cm_alpha` (per rad) or `Cm_q` (per unit q̂); tables may add a
    /// suffix such as `*` for the primary derivatives.
    pub name: String,
    /// Final estimate; `null` when not identified (the status and flags say why).
    pub estimate: Option<f64>,
    /// Its standard error, the one the status is judged against; `null` where the method gives
    /// none.
    pub std_error: Option<f64>,
    /// Which σ `std_error` is; `null` without one.
    pub std_error_source: Option<StdErrorSource>,
    /// The Cramér–Rao σ of a batch fit, beside a `std_error` of another source (or equal to
    /// it); `null` for recursive estimators.
    pub crb_std_error: Option<f64>,
    /// The truth (simulation) or a published value (a model file's `[reference.X]`); `null`
    /// without one. Below [`ZERO_THRESHOLD`] in magnitude it is 0.
    pub reference: Option<f64>,
    /// The verdict: `ok`, `not identified`, `outside ±2σ`, or a failure or flag the run put in
    /// its place (`diverged`, `differs from oe by 3.1σ`, `σ 32 % of |estimate|` …).
    pub status: String,
    /// Every warning of the run about this parameter, in its words (empty without one).
    pub flags: Vec<String>,
}

impl ParameterResult {
    /// A result whose status is derived from the numbers: `failure` if given (e.g.
    /// `diverged`), else `not identified` without an estimate, `outside ±2σ` when the
    /// reference lies further than 2σ from the estimate, else `ok`.
    pub fn new(
        name: impl Into<String>,
        estimate: Option<f64>,
        std_error: Option<f64>,
        reference: Option<f64>,
        failure: Option<&str>,
    ) -> Self {
        let reference = reference.map(|r| if r.abs() < ZERO_THRESHOLD { 0.0 } else { r });
        let mut result = Self {
            name: name.into(),
            estimate,
            std_error,
            std_error_source: None,
            crb_std_error: None,
            reference,
            status: String::new(),
            flags: Vec::new(),
        };
        result.judge(failure);
        result
    }

    /// Sets the status by the rule of [`ParameterResult::new`] from the current numbers.
    pub fn judge(&mut self, failure: Option<&str>) {
        self.status = match (failure, self.estimate) {
            (Some(f), _) => f.to_string(),
            (None, None) => STATUS_NOT_IDENTIFIED.into(),
            (None, Some(_)) if self.outside_2sigma() => STATUS_OUTSIDE_2SIGMA.into(),
            (None, Some(_)) => STATUS_OK.into(),
        };
    }

    /// The result with `source` named as its σ's (none without a σ).
    pub fn with_source(mut self, source: StdErrorSource) -> Self {
        self.std_error_source = self.std_error.map(|_| source);
        self
    }

    /// The result with the Cramér–Rao σ `crb` beside its σ.
    pub fn with_crb_std_error(mut self, crb: Option<f64>) -> Self {
        self.crb_std_error = crb;
        self
    }

    /// The result with `flags` added.
    pub fn with_flags(mut self, flags: impl IntoIterator<Item = String>) -> Self {
        self.flags.extend(flags);
        self
    }

    /// Whether a reference lies further than 2σ from the estimate.
    pub fn outside_2sigma(&self) -> bool {
        match (self.estimate, self.std_error, self.reference) {
            (Some(e), Some(s), Some(r)) => (e - r).abs() > 2.0 * s,
            _ => false,
        }
    }

    /// `100 (estimate − reference) / |reference|`, %; `None` without both or for a zero
    /// reference.
    pub fn error_pct(&self) -> Option<f64> {
        match (self.estimate, self.reference) {
            (Some(e), Some(r)) if r != 0.0 && r.is_finite() => Some(100.0 * (e - r) / r.abs()),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_from_the_numbers() {
        let r = ParameterResult::new("Cm_alpha", Some(-1.1), Some(0.01), Some(-1.0), None);
        assert!((r.error_pct().unwrap() + 10.0).abs() < 1e-9, "signed: estimate below");
        assert_eq!(r.status, STATUS_OUTSIDE_2SIGMA);
        assert!(r.outside_2sigma());
        let r = ParameterResult::new("Cm_alpha", Some(-1.01), Some(0.01), Some(-1.0), None);
        assert_eq!(r.status, STATUS_OK);
        assert!((r.error_pct().unwrap() + 1.0).abs() < 1e-9, "sign: estimate more negative");
        let r = ParameterResult::new("Cm_q", None, None, Some(-20.0), None);
        assert_eq!((r.status.as_str(), r.error_pct()), (STATUS_NOT_IDENTIFIED, None));
        let r = ParameterResult::new("Cl_0", Some(6e-5), None, Some(3.4e-44), None);
        assert_eq!((r.reference, r.error_pct()), (Some(0.0), None));
        let r = ParameterResult::new("x", Some(1.0), None, None, Some("diverged"));
        assert_eq!(r.status, "diverged");
    }

    #[test]
    fn keys_of_schema_2() {
        let r = ParameterResult::new("Cm_q", Some(-20.0), Some(1.0), None, None)
            .with_source(StdErrorSource::CramerRao)
            .with_crb_std_error(Some(0.5))
            .with_flags(["a flag".to_string()]);
        let v = serde_json::to_value(&r).unwrap();
        let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
        let mut want = [
            "name",
            "estimate",
            "std_error",
            "std_error_source",
            "crb_std_error",
            "reference",
            "status",
            "flags",
        ];
        want.sort_unstable();
        let mut keys = keys;
        keys.sort_unstable();
        assert_eq!(keys, want);
        assert_eq!(v["std_error_source"], "cramer_rao");
        // No σ: no source.
        let r = ParameterResult::new("x", Some(1.0), None, None, None)
            .with_source(StdErrorSource::Bootstrap);
        assert_eq!(r.std_error_source, None);
    }
}
