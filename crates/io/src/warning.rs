//! Warnings as typed values: what a run tells its user beside the numbers, with a kind a face
//! can act on (print the end-of-run diagnostics, flag a parameter) without reading its words.
//!
//! A [`Warning`] is its text to a reader (`Display`, and `Deref` to `str` for the searches
//! tests make); `summary.json` lists the texts (`warnings: [..]`), as before the kinds existed.
//! [`Warnings`] is the list a summary keeps: it takes a plain `String` as a
//! [`WarningKind::Run`] warning, so every stage that only has words to say still can.

use serde::{Serialize, Serializer};

/// What a warning is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum WarningKind {
    /// The record or the run (rows, gaps, windows, corrections, pacing, an interruption).
    Run,
    /// An estimate whose sign a conventional aircraft does not have.
    Sign,
    /// A filter whose innovations disagree with its own covariance (normalised innovation
    /// squared far from 1).
    Consistency,
    /// Two regressors the record cannot separate.
    Collinear,
    /// A channel that holds one value over the record.
    ConstantChannel,
    /// A channel whose unit disagrees with the kinematics.
    UnitMismatch,
    /// A compatibility correction beyond what a sensor plausibly needs, not applied.
    RefusedCorrection,
    /// An estimate that disagrees with another method's on the same record.
    CrossCheck,
    /// A surface channel whose timing disagrees with the response it drives (a commanded
    /// surface, or a channel recorded early or late).
    InputTiming,
    /// A force or moment the record does not give (thrust unmapped) that can be inside the
    /// measured coefficient.
    UnmodelledForce,
    /// An estimate that a skew of half a sample between the rate gyros and the other channels
    /// moves by more than an identified estimate claims (the record's time stamps cannot rule
    /// such a skew out).
    SampleTiming,
}

impl WarningKind {
    /// Whether a face repeats it at the end of a run, after the results: the judgments of the
    /// answer and its data (sign, consistency, collinearity, constant channels, units, refused
    /// corrections, cross-checks, input timing), which a user reads beside the table rather than among the record's notes.
    pub fn is_diagnostic(self) -> bool {
        !matches!(self, WarningKind::Run)
    }
}

/// One warning: its kind, the parameter it is about (if one), and its text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Warning {
    /// What it is about.
    pub kind: WarningKind,
    /// The vocabulary name of the parameter it is about (`Cm_alpha`), or of the coefficient
    /// (`Cm`: every parameter of it), if one.
    pub parameter: Option<String>,
    /// The text a user reads.
    pub text: String,
}

impl Warning {
    /// A warning of `kind` with `text`, about no one parameter.
    pub fn new(kind: WarningKind, text: impl Into<String>) -> Self {
        Self { kind, parameter: None, text: text.into() }
    }

    /// The same warning, about `parameter` (`Cm_alpha`), or about every parameter of a
    /// coefficient when given the coefficient's name (`Cm`).
    pub fn about(mut self, parameter: impl Into<String>) -> Self {
        self.parameter = Some(parameter.into());
        self
    }
}

impl From<String> for Warning {
    fn from(text: String) -> Self {
        Warning::new(WarningKind::Run, text)
    }
}

impl From<&str> for Warning {
    fn from(text: &str) -> Self {
        Warning::new(WarningKind::Run, text)
    }
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text)
    }
}

impl std::ops::Deref for Warning {
    type Target = str;

    fn deref(&self) -> &str {
        &self.text
    }
}

impl std::borrow::Borrow<str> for Warning {
    fn borrow(&self) -> &str {
        &self.text
    }
}

impl Serialize for Warning {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.text)
    }
}

/// The warnings of a summary, in the order they arose.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize)]
#[serde(transparent)]
pub struct Warnings(Vec<Warning>);

impl Warnings {
    /// No warnings.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one (a plain `String` is a [`WarningKind::Run`] warning).
    pub fn push(&mut self, w: impl Into<Warning>) {
        self.0.push(w.into());
    }

    /// The texts, in order.
    pub fn texts(&self) -> impl Iterator<Item = &str> {
        self.0.iter().map(|w| w.text.as_str())
    }

    /// The texts of the warnings about `parameter` or its coefficient (`Cm` for `Cm_alpha`),
    /// in order (a parameter's `flags`).
    pub fn about(&self, parameter: &str) -> Vec<String> {
        let coefficient = parameter.split_once('_').map(|(c, _)| c);
        self.0
            .iter()
            .filter(|w| {
                let subject = w.parameter.as_deref();
                subject == Some(parameter) || (subject.is_some() && subject == coefficient)
            })
            .map(|w| w.text.clone())
            .collect()
    }
}

impl<W: Into<Warning>> Extend<W> for Warnings {
    fn extend<I: IntoIterator<Item = W>>(&mut self, iter: I) {
        self.0.extend(iter.into_iter().map(Into::into));
    }
}

impl<W: Into<Warning>> FromIterator<W> for Warnings {
    fn from_iter<I: IntoIterator<Item = W>>(iter: I) -> Self {
        Self(iter.into_iter().map(Into::into).collect())
    }
}

impl std::ops::Deref for Warnings {
    type Target = [Warning];

    fn deref(&self) -> &[Warning] {
        &self.0
    }
}

impl<'a> IntoIterator for &'a Warnings {
    type Item = &'a Warning;
    type IntoIter = std::slice::Iter<'a, Warning>;

    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A summary lists the texts alone (the schema before the kinds), whatever their kind; a
    /// plain string is a run warning; the diagnostics are the kinds a face repeats at the end.
    #[test]
    fn warnings_serialise_as_their_texts_and_keep_their_kinds() {
        let mut w = Warnings::new();
        w.push("gap: 2 s");
        w.push(Warning::new(WarningKind::Sign, "Cm_alpha = +0.3 …").about("Cm_alpha"));
        w.extend(["one".to_string(), "two".to_string()]);
        let json = serde_json::to_string(&w).unwrap();
        assert_eq!(json, r#"["gap: 2 s","Cm_alpha = +0.3 …","one","two"]"#);
        assert_eq!(w[0].kind, WarningKind::Run);
        assert_eq!(w[1].parameter.as_deref(), Some("Cm_alpha"));
        assert_eq!(w.about("Cm_alpha"), [w[1].text.clone()]);
        assert!(w.about("Cm_q").is_empty());
        // About a coefficient: each of its parameters, not another coefficient's.
        w.push(Warning::new(WarningKind::UnmodelledForce, "thrust …").about("Cm"));
        assert_eq!(w.about("Cm_q"), ["thrust …"]);
        assert_eq!(w.about("Cm_alpha").len(), 2);
        assert!(w.about("CL_q").is_empty() && w.about("Cmx").is_empty());
        w.0.pop();
        let diagnostic: Vec<&str> =
            w.iter().filter(|w| w.kind.is_diagnostic()).map(|w| &w.text[..]).collect();
        assert_eq!(diagnostic, ["Cm_alpha = +0.3 …"]);
        assert!(w.iter().any(|w| w.starts_with("gap")));
        assert_eq!(w.join(" | "), "gap: 2 s | Cm_alpha = +0.3 … | one | two");
    }
}
