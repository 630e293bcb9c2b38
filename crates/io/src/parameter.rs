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

/// The status of an estimate nothing speaks against: identified, and no flag.
pub const STATUS_IDENTIFIED: &str = "identified";

/// The status of an estimate with at least one flag (its `flags` say which).
pub const STATUS_FLAGGED: &str = "flagged";

/// The status of a parameter the run gave no estimate of (its `flags` say why, where known).
pub const STATUS_NOT_IDENTIFIED: &str = "not identified";

/// The status of a batch fit's estimate that its last iterations still moved by more than its
/// σ.
pub const STATUS_NOT_CONVERGED: &str = "not converged";

/// The status of every estimate of an estimator that diverged (none is a result).
pub const STATUS_DIVERGED: &str = "diverged";

/// The flag of an estimate without a standard error: `identified` would claim what nothing
/// measured.
pub const NO_STD_ERROR: &str =
    "no σ: the method gives no standard error, so nothing says how well the record determines it";

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
    /// The verdict: `identified` (no flag), `flagged` (see `flags`), `not identified`,
    /// `not converged` or `diverged` (module doc of the judging stage: docs/output-schema.md).
    pub status: String,
    /// Every warning of the run about this parameter, in its words (empty without one).
    pub flags: Vec<String>,
}

impl ParameterResult {
    /// A result whose status is derived from the numbers ([`ParameterResult::judge`]).
    pub fn new(
        name: impl Into<String>,
        estimate: Option<f64>,
        std_error: Option<f64>,
        reference: Option<f64>,
        failure: Option<&str>,
    ) -> Self {
        let mut result = Self {
            name: name.into(),
            estimate,
            std_error,
            std_error_source: None,
            crb_std_error: None,
            reference: None,
            status: String::new(),
            flags: Vec::new(),
        };
        result.set_reference(reference);
        result.judge(failure);
        result
    }

    /// Sets the reference, a magnitude below [`ZERO_THRESHOLD`] as 0 (round-off of an exact
    /// zero, against which no error % is formed).
    pub fn set_reference(&mut self, reference: Option<f64>) {
        self.reference = reference.map(|r| if r.abs() < ZERO_THRESHOLD { 0.0 } else { r });
    }

    /// Sets the status from the current numbers and flags: `failure` if given (`diverged`,
    /// `not converged`), else `not identified` without an estimate; otherwise a reference
    /// further than 2σ from the estimate is one more flag, an estimate without any σ is one
    /// (nothing says how well the record determines it, [`NO_STD_ERROR`]), and the status is
    /// `flagged` with any flag, else `identified`.
    pub fn judge(&mut self, failure: Option<&str>) {
        if let Some(f) = failure {
            self.status = f.to_string();
            return;
        }
        if self.estimate.is_none() {
            self.status = STATUS_NOT_IDENTIFIED.into();
            return;
        }
        if let (true, Some(r), Some(e), Some(s)) =
            (self.outside_2sigma(), self.reference, self.estimate, self.std_error)
        {
            self.flag(format!(
                "the reference {r:.4} lies {:.1}σ from the estimate (outside ±2σ)",
                (e - r).abs() / s
            ));
        }
        if self.std_error.is_none() && !self.flags.iter().any(|f| f.starts_with("no σ")) {
            self.flag(NO_STD_ERROR);
        }
        self.status =
            if self.flags.is_empty() { STATUS_IDENTIFIED } else { STATUS_FLAGGED }.to_string();
    }

    /// Adds `text` to the flags, once.
    pub fn flag(&mut self, text: impl Into<String>) {
        let text = text.into();
        if !self.flags.contains(&text) {
            self.flags.push(text);
        }
    }

    /// The result with its estimate and σ withdrawn (`null`), status `not identified` and
    /// `why` its flag: a number the record cannot support is not reported.
    pub fn withdraw(&mut self, why: impl Into<String>) {
        (self.estimate, self.std_error, self.std_error_source, self.crb_std_error) =
            (None, None, None, None);
        self.flag(why);
        self.judge(None);
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
        assert_eq!(r.status, STATUS_FLAGGED);
        assert!(r.outside_2sigma());
        assert_eq!(r.flags, ["the reference -1.0000 lies 10.0σ from the estimate (outside ±2σ)"]);
        let mut r = ParameterResult::new("Cm_alpha", Some(-1.01), Some(0.01), Some(-1.0), None);
        assert_eq!((r.status.as_str(), r.flags.len()), (STATUS_IDENTIFIED, 0));
        // Judging again adds no second copy of a flag.
        r.flag("x");
        r.flag("x");
        r.judge(None);
        assert_eq!((r.status.as_str(), r.flags.len()), (STATUS_FLAGGED, 1));
        assert!((r.error_pct().unwrap() + 1.0).abs() < 1e-9, "sign: estimate more negative");
        r.withdraw("thrust is not mapped");
        assert_eq!(
            (r.estimate, r.std_error, r.status.as_str()),
            (None, None, STATUS_NOT_IDENTIFIED)
        );
        let r = ParameterResult::new("Cm_q", None, None, Some(-20.0), None);
        assert_eq!((r.status.as_str(), r.error_pct()), (STATUS_NOT_IDENTIFIED, None));
        let r = ParameterResult::new("Cl_0", Some(6e-5), None, Some(3.4e-44), None);
        assert_eq!((r.reference, r.error_pct()), (Some(0.0), None));
        assert_eq!(
            (r.status.as_str(), r.flags.clone()),
            (STATUS_FLAGGED, vec![NO_STD_ERROR.to_string()])
        );
        let r = ParameterResult::new("x", Some(1.0), None, None, Some(STATUS_DIVERGED));
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

    /// The reference rule at its edge, hand-set: a reference just inside ±2σ of the estimate
    /// leaves it `identified`, just outside flags it (either side); no σ is its own flag.
    #[test]
    fn the_reference_rule_at_its_edge() {
        let (e, s, d) = (-1.0, 0.05, 1e-9);
        #[rustfmt::skip]
        let table: [(f64, &str); 5] = [
            (e + 2.0 * s - d, STATUS_IDENTIFIED), (e - 2.0 * s + d, STATUS_IDENTIFIED),
            (e + 2.0 * s + d, STATUS_FLAGGED), (e - 2.0 * s - d, STATUS_FLAGGED),
            (e + 2.5 * s, STATUS_FLAGGED),
        ];
        for (reference, status) in table {
            let r = ParameterResult::new("Cm_alpha", Some(e), Some(s), Some(reference), None);
            assert_eq!(r.status, status, "reference {reference}: {:?}", r.flags);
            let outside = status == STATUS_FLAGGED;
            assert_eq!(r.flags.iter().any(|f| f.contains("outside ±2σ")), outside);
        }
        let r = ParameterResult::new("Cm_alpha", Some(e), None, None, None);
        assert_eq!(
            (r.status.as_str(), r.flags.as_slice()),
            (STATUS_FLAGGED, &[NO_STD_ERROR.to_string()][..])
        );
    }
}
