//! One parameter's result, the same from the estimator to every `summary.json` (`run`,
//! `replay`, the batch fits, `montecarlo`, `poc`), the console table, `report.html` and Python.
//!
//! Keys (schema version [`SCHEMA_VERSION`]): `name`, `estimate`, `std_error`,
//! `std_error_source`, `crb_std_error`, `reference`, `reference_check`, `status`, `flags`,
//! `notes`. A command adds its own keys beside them (a settling time, a bootstrap bias …) in
//! the same object. Schema 1 called the estimate `final`, its σ `sigma` and the truth `truth`
//! in `run`, `montecarlo` and `poc`, and `crb_sigma` in the batch fits; schema 2 counted a
//! reference outside ±2σ and a σ above 10 % among the `flags` (docs/output-schema.md lists
//! every change).
//!
//! The reference (a simulation's truth, a model file's published value) is compared beside
//! the verdict, in `reference_check`, and is never an input to it: a verdict that read the
//! reference would measure the reference, not what the record supports.

use serde::{Deserialize, Serialize};

/// The version of the `summary.json` key set, written as `schema_version` in every summary.
pub const SCHEMA_VERSION: u32 = 3;

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
    /// The scatter of the record's manoeuvres fitted alone, where they do not repeat to their
    /// own σ: the weighted mean's σ scaled by the Birge ratio (`aeroident_pipelines::replay::
    /// repeatability`).
    Repeatability,
}

impl StdErrorSource {
    /// The key's value in `summary.json`: `covariance`, `cramer_rao`, `coloured`, `bootstrap`,
    /// `repeatability`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Covariance => "covariance",
            Self::CramerRao => "cramer_rao",
            Self::Coloured => "coloured",
            Self::Bootstrap => "bootstrap",
            Self::Repeatability => "repeatability",
        }
    }

    /// The source in words, for tables and reports (`Cramér–Rao`, `parametric bootstrap` …).
    pub fn words(self) -> &'static str {
        match self {
            Self::Covariance => "estimator covariance",
            Self::CramerRao => "Cramér–Rao",
            Self::Coloured => "coloured-residual",
            Self::Bootstrap => "parametric bootstrap",
            Self::Repeatability => "manoeuvre-to-manoeuvre scatter",
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
    /// The σ of the record's sample timing, included in `std_error` in quadrature: what a skew
    /// of half a sample between the rate gyros and the other channels moves the estimate,
    /// taken as a uniform error over that range (the move / √3;
    /// `aeroident_pipelines::replay::sample_timing`). `null` where the test was not made (a
    /// live feed, `run`, `montecarlo`).
    #[serde(default)]
    pub timing_std_error: Option<f64>,
    /// The σ of what the linear model of one record leaves unmodelled (biases beyond the noise
    /// σ: structure, input and sensor errors no test named), included in `std_error` in
    /// quadrature: a fixed share of `|estimate|` calibrated on simulated aircraft with a known
    /// truth (`aeroident_pipelines::replay::unmodelled`). `null` for a constant term and where
    /// it is not added (`run`, `montecarlo`: the simulation's own model).
    #[serde(default)]
    pub unmodelled_std_error: Option<f64>,
    /// The truth (simulation) or a published value (a model file's `[reference.X]`); `null`
    /// without one. Below [`ZERO_THRESHOLD`] in magnitude it is 0.
    pub reference: Option<f64>,
    /// The estimate set beside the reference ([`ReferenceCheck`]); `null` without a
    /// reference or an estimate. Never read by the verdict.
    #[serde(default)]
    pub reference_check: Option<ReferenceCheck>,
    /// The verdict: `identified` (no flag), `flagged` (see `flags`), `not identified`,
    /// `not converged` or `diverged` (module doc of the judging stage: docs/output-schema.md).
    /// Read back as empty where a hand-made summary leaves it out.
    #[serde(default)]
    pub status: String,
    /// Every doubt of the run about this parameter, in its words (empty without one): each
    /// blocks `identified`.
    #[serde(default)]
    pub flags: Vec<String>,
    /// What is worth knowing and is no doubt about the value (a σ above 10 % of the estimate
    /// says imprecise, not wrong): never blocks `identified`.
    #[serde(default)]
    pub notes: Vec<String>,
    /// The parameters the record fixes this one only in combination with (|ρ| > 0.9 in the
    /// run's correlations: Cm_q with Cm_α̇ in a short period, a constant with a speed term
    /// over a narrow speed range), each with ρ; empty without any. The same pairs are in
    /// `notes` in words; neither blocks `identified` (each value may be right, and its σ
    /// carries the spread along the combination the record leaves free).
    #[serde(default)]
    pub combines: Vec<Combination>,
}

/// A parameter another one is fixed only in combination with ([`ParameterResult::combines`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Combination {
    /// The partner's vocabulary name.
    pub with: String,
    /// Their correlation coefficient `cov(a,b)/(σ_a σ_b)`, |ρ| > 0.9.
    pub rho: f64,
}

/// An estimate set beside its reference: the comparison the verdict never reads.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReferenceCheck {
    /// `100 (estimate − reference) / |reference|`, %; `null` for a zero reference.
    pub error_pct: Option<f64>,
    /// `|estimate − reference| / σ`; `null` without a σ.
    pub distance_sigma: Option<f64>,
    /// Whether ±2σ of the estimate covers the reference; `null` without a σ.
    pub within_2sigma: Option<bool>,
    /// Further comparisons with the reference in words (`run`: a missed convergence target),
    /// empty without any.
    #[serde(default)]
    pub findings: Vec<String>,
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
            timing_std_error: None,
            unmodelled_std_error: None,
            reference: None,
            reference_check: None,
            status: String::new(),
            flags: Vec::new(),
            notes: Vec::new(),
            combines: Vec::new(),
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
    /// `not converged`), else `not identified` without an estimate; otherwise an estimate
    /// without any σ is one more flag (nothing says how well the record determines it,
    /// [`NO_STD_ERROR`]), and the status is `flagged` with any flag, else `identified`. Notes
    /// never count. The reference is compared beside it ([`Self::check_reference`]), whatever
    /// the status.
    pub fn judge(&mut self, failure: Option<&str>) {
        self.check_reference();
        if let Some(f) = failure {
            self.status = f.to_string();
            return;
        }
        if self.estimate.is_none() {
            self.status = STATUS_NOT_IDENTIFIED.into();
            return;
        }
        if self.std_error.is_none() && !self.flags.iter().any(|f| f.starts_with("no σ")) {
            self.flag(NO_STD_ERROR);
        }
        self.status =
            if self.flags.is_empty() { STATUS_IDENTIFIED } else { STATUS_FLAGGED }.to_string();
    }

    /// Sets `reference_check` from the estimate, σ and reference (`None` without an estimate
    /// or a reference), keeping the findings it already holds.
    pub fn check_reference(&mut self) {
        let (Some(e), Some(r)) = (self.estimate, self.reference) else {
            self.reference_check = None;
            return;
        };
        let findings = self.reference_check.take().map(|c| c.findings).unwrap_or_default();
        let distance = self.std_error.filter(|s| *s > 0.0).map(|s| (e - r).abs() / s);
        self.reference_check = Some(ReferenceCheck {
            error_pct: self.error_pct(),
            distance_sigma: distance,
            within_2sigma: self.std_error.map(|_| !self.outside_2sigma()),
            findings,
        });
    }

    /// Adds `text` to the reference check's findings, once (a check is made for it when
    /// there is an estimate and a reference; without them there is nothing to compare).
    pub fn reference_finding(&mut self, text: impl Into<String>) {
        if self.reference_check.is_none() {
            self.check_reference();
        }
        let text = text.into();
        if let Some(c) = &mut self.reference_check
            && !c.findings.contains(&text)
        {
            c.findings.push(text);
        }
    }

    /// Adds `text` to the notes, once.
    pub fn note(&mut self, text: impl Into<String>) {
        let text = text.into();
        if !self.notes.contains(&text) {
            self.notes.push(text);
        }
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

    /// Adds the sample-timing σ `timing` (finite, ≥ 0) to `std_error` in quadrature and keeps
    /// it in `timing_std_error`; a result without a σ keeps none. A second call replaces the
    /// first's share, not adds to it.
    pub fn add_timing_std_error(&mut self, timing: f64) {
        if let Some(s) = self.swapped_share(self.timing_std_error, timing) {
            self.std_error = Some(s);
            self.timing_std_error = Some(timing);
        }
    }

    /// Adds `fraction` (finite, ≥ 0) of `|estimate|` to `std_error` in quadrature as the σ of
    /// what the model leaves unmodelled and keeps it in `unmodelled_std_error`; a constant term
    /// (`…_0`: its size is the trim's) or a result without an estimate or a finite σ keeps none
    /// (a NaN σ, written `null`, stays one). A second call replaces the first's share, not adds
    /// to it.
    pub fn add_unmodelled_std_error(&mut self, fraction: f64) {
        let Some(e) = self.estimate.filter(|_| !self.name.ends_with("_0")) else { return };
        let share = fraction * e.abs();
        if let Some(s) = self.swapped_share(self.unmodelled_std_error, share) {
            self.std_error = Some(s);
            self.unmodelled_std_error = Some(share);
        }
    }

    /// `std_error` without the shares a record's fit adds beyond its noise
    /// (`timing_std_error`, `unmodelled_std_error`), in quadrature: the σ of the fit's random
    /// error. Two methods fitting one record with one model share those two errors, so a
    /// difference between their estimates is judged against this σ, not the full one. `None`
    /// without a finite σ.
    pub fn noise_std_error(&self) -> Option<f64> {
        let s = self.std_error.filter(|s| s.is_finite())?;
        let shares =
            self.timing_std_error.unwrap_or(0.0).hypot(self.unmodelled_std_error.unwrap_or(0.0));
        Some((s * s - shares * shares).max(0.0).sqrt())
    }

    /// `std_error` with the share `old` taken out and `new` put in, in quadrature; `None`
    /// without a finite σ or for a `new` that is not finite and ≥ 0 (nothing to change).
    fn swapped_share(&self, old: Option<f64>, new: f64) -> Option<f64> {
        let s = self.std_error.filter(|s| s.is_finite())?;
        if !(new.is_finite() && new >= 0.0) {
            return None;
        }
        let old = old.unwrap_or(0.0);
        Some((s * s - old * old).max(0.0).sqrt().hypot(new))
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

    /// The shares in quadrature by hand: σ 0.1 and 5 % of |−2| give √0.02; a second call
    /// replaces the share; the timing share and the unmodelled one replace only themselves;
    /// a constant term and a result without σ keep none.
    #[test]
    fn unmodelled_share_in_quadrature() {
        let mut r = ParameterResult::new("Cm_alpha", Some(-2.0), Some(0.1), None, None);
        r.add_unmodelled_std_error(0.05);
        assert!((r.std_error.unwrap() - 0.02f64.sqrt()).abs() < 1e-15);
        assert_eq!(r.unmodelled_std_error, Some(0.1));
        r.add_unmodelled_std_error(0.1);
        assert!((r.std_error.unwrap() - 0.05f64.sqrt()).abs() < 1e-15);
        r.add_timing_std_error(0.3);
        assert!((r.std_error.unwrap() - 0.14f64.sqrt()).abs() < 1e-15);
        r.add_unmodelled_std_error(0.0);
        assert!((r.std_error.unwrap() - 0.1f64.hypot(0.3)).abs() < 1e-15);
        r.add_timing_std_error(0.0);
        assert!((r.std_error.unwrap() - 0.1).abs() < 1e-15);
        let mut c = ParameterResult::new("Cm_0", Some(0.05), Some(0.001), None, None);
        c.add_unmodelled_std_error(0.05);
        assert_eq!((c.std_error, c.unmodelled_std_error), (Some(0.001), None));
        let mut bare = ParameterResult::new("Cl_p", Some(-0.4), None, None, None);
        bare.add_unmodelled_std_error(0.05);
        assert_eq!((bare.std_error, bare.unmodelled_std_error), (None, None));
        let mut singular = ParameterResult::new("Cl_p", Some(-0.4), Some(f64::NAN), None, None);
        singular.add_unmodelled_std_error(0.05);
        assert!(singular.std_error.unwrap().is_nan() && singular.unmodelled_std_error.is_none());
    }

    /// The noise σ by hand: σ 0.1 with a timing share 0.3 and 5 % of |−2| (0.1) reads 0.1
    /// back; with no share it is `std_error`; without a finite σ there is none.
    #[test]
    fn the_noise_sigma_is_the_sigma_without_the_shares() {
        let mut r = ParameterResult::new("Cm_alpha", Some(-2.0), Some(0.1), None, None);
        assert_eq!(r.noise_std_error(), Some(0.1));
        r.add_timing_std_error(0.3);
        r.add_unmodelled_std_error(0.05);
        assert!((r.std_error.unwrap() - 0.11f64.sqrt()).abs() < 1e-15);
        assert!((r.noise_std_error().unwrap() - 0.1).abs() < 1e-15);
        let bare = ParameterResult::new("Cl_p", Some(-0.4), None, None, None);
        assert_eq!(bare.noise_std_error(), None);
    }

    #[test]
    fn status_from_the_numbers() {
        let r = ParameterResult::new("Cm_alpha", Some(-1.1), Some(0.01), Some(-1.0), None);
        assert!((r.error_pct().unwrap() + 10.0).abs() < 1e-9, "signed: estimate below");
        // The reference 10σ away is compared beside the verdict and does not change it.
        assert_eq!((r.status.as_str(), r.flags.len()), (STATUS_IDENTIFIED, 0));
        assert!(r.outside_2sigma());
        let c = r.reference_check.clone().unwrap();
        assert_eq!(c.within_2sigma, Some(false));
        assert!((c.distance_sigma.unwrap() - 10.0).abs() < 1e-9);
        assert!((c.error_pct.unwrap() + 10.0).abs() < 1e-9);
        let mut r = ParameterResult::new("Cm_alpha", Some(-1.01), Some(0.01), Some(-1.0), None);
        assert_eq!((r.status.as_str(), r.flags.len()), (STATUS_IDENTIFIED, 0));
        // Judging again adds no second copy of a flag; a note is no flag.
        r.flag("x");
        r.flag("x");
        r.note("σ wide");
        r.note("σ wide");
        r.judge(None);
        assert_eq!((r.status.as_str(), r.flags.len(), r.notes.len()), (STATUS_FLAGGED, 1, 1));
        assert!((r.error_pct().unwrap() + 1.0).abs() < 1e-9, "sign: estimate more negative");
        r.withdraw("thrust is not mapped");
        assert_eq!(
            (r.estimate, r.std_error, r.status.as_str(), r.reference_check.is_none()),
            (None, None, STATUS_NOT_IDENTIFIED, true)
        );
        let r = ParameterResult::new("Cm_q", None, None, Some(-20.0), None);
        assert_eq!((r.status.as_str(), r.error_pct()), (STATUS_NOT_IDENTIFIED, None));
        let r = ParameterResult::new("Cl_0", Some(6e-5), None, Some(3.4e-44), None);
        assert_eq!((r.reference, r.error_pct()), (Some(0.0), None));
        assert_eq!(
            (r.status.as_str(), r.flags.clone()),
            (STATUS_FLAGGED, vec![NO_STD_ERROR.to_string()])
        );
        let c = r.reference_check.unwrap();
        assert_eq!((c.error_pct, c.distance_sigma, c.within_2sigma), (None, None, None));
        let r = ParameterResult::new("x", Some(1.0), None, None, Some(STATUS_DIVERGED));
        assert_eq!(r.status, "diverged");
        let mut r = ParameterResult::new("x", Some(1.0), Some(0.1), Some(2.0), None);
        r.reference_finding("target missed");
        r.reference_finding("target missed");
        r.judge(None);
        let c = r.reference_check.as_ref().unwrap();
        assert_eq!((c.findings.len(), r.status.as_str()), (1, STATUS_IDENTIFIED));
    }

    #[test]
    fn keys_of_schema_3() {
        let r = ParameterResult::new("Cm_q", Some(-20.0), Some(1.0), Some(-21.0), None)
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
            "timing_std_error",
            "unmodelled_std_error",
            "reference",
            "reference_check",
            "status",
            "flags",
            "notes",
            "combines",
        ];
        want.sort_unstable();
        let mut keys = keys;
        keys.sort_unstable();
        assert_eq!(keys, want);
        assert_eq!(v["std_error_source"], "cramer_rao");
        assert_eq!(v["reference_check"]["within_2sigma"], true);
        // No σ: no source.
        let r = ParameterResult::new("x", Some(1.0), None, None, None)
            .with_source(StdErrorSource::Bootstrap);
        assert_eq!(r.std_error_source, None);
        // A schema-2 object (no notes, no reference check) still reads.
        let old = r#"{"name":"x","estimate":1.0,"std_error":null,"std_error_source":null,
            "crb_std_error":null,"reference":null,"status":"flagged","flags":["f"]}"#;
        let back: ParameterResult = serde_json::from_str(old).unwrap();
        assert_eq!((back.notes.len(), back.reference_check), (0, None));
    }

    /// The reference check at its edge, hand-set: a reference just inside ±2σ of the
    /// estimate is within, just outside is not (either side), and neither moves the status.
    #[test]
    fn the_reference_check_at_its_edge() {
        let (e, s, d) = (-1.0, 0.05, 1e-9);
        #[rustfmt::skip]
        let table: [(f64, bool); 5] = [
            (e + 2.0 * s - d, true), (e - 2.0 * s + d, true),
            (e + 2.0 * s + d, false), (e - 2.0 * s - d, false), (e + 2.5 * s, false),
        ];
        for (reference, within) in table {
            let r = ParameterResult::new("Cm_alpha", Some(e), Some(s), Some(reference), None);
            assert_eq!(r.status, STATUS_IDENTIFIED, "reference {reference}: {:?}", r.flags);
            assert_eq!(r.reference_check.unwrap().within_2sigma, Some(within), "{reference}");
        }
        let r = ParameterResult::new("Cm_alpha", Some(e), None, None, None);
        assert_eq!(
            (r.status.as_str(), r.flags.as_slice()),
            (STATUS_FLAGGED, &[NO_STD_ERROR.to_string()][..])
        );
    }
}
