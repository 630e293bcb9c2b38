//! Model files: the aerodynamic model structure to identify and the priors of its parameters,
//! declared in TOML over the one vocabulary of [`aeroident_estimators::vocabulary`]
//! (coefficient × term, parameters `<coefficient>_<term>`), or a preset by name.
//!
//! ```toml
//! description = "short period with alpha-dot"
//!
//! [coefficients]                      # coefficient = [terms]; linear in the parameters
//! Cm = ["0", "alpha", "q", "alphadot", "de"]
//! CL = ["0", "alpha", "q", "de"]
//!
//! [knots]                             # the α knots of the spline terms alpha_k1 … alpha_k4
//! alpha_deg = [8.0]                   # or alpha_rad = [...]; ascending, at most four
//!
//! [prior.Cm_alpha]                    # optional, per parameter (units of the parameter)
//! value = -0.5
//! sigma = 2.0
//!
//! [reference.Cm_alpha]                # optional: a published value, shown beside the estimate
//! value = -1.002
//! source = "Jategaonkar 2015, test case 4, output error"
//!
//! [plausible.Cm_alpha]                # optional: this aircraft's range, replacing a conventional one's
//! min = -2.0
//! max = 0.5
//! ```
//!
//! - Coefficients: `CX CY CZ CL CD Cl Cm Cn` (case-sensitive: `CL` lift, `Cl` rolling moment).
//! - Terms: `0` (bias), `alpha`, `beta`, `p`, `q`, `r` (p̂ = pb/2V, q̂ = qc̄/2V, r̂ = rb/2V),
//!   `alphadot` (α̇c̄/2V), `de`, `da`, `dr`, `V` (V/V0), `alpha2`, `alpha_de`, `alpha_beta`,
//!   `q0`, `alpha_p`, `alpha_q`, `alpha_r`, `alpha_da`, `alpha_dr`, the α splines `alpha_k1` …
//!   `alpha_k4` (`(α − k_i)₊`, knot `k_i` from `[knots]`) and `mach`, `mach2` (Mach number at
//!   the standard temperature of the density altitude, [`AirDataSample::mach`]).
//! - Knots: `[knots]` with `alpha_deg` or `alpha_rad` (not both), finite, strictly ascending,
//!   within ±90°, at most four; the i-th is the knot of `alpha_k<i>`. A replay refuses knots
//!   outside the record's α range (their spline terms could not be identified).
//!
//! [`AirDataSample::mach`]: aeroident_estimators::AirDataSample::mach
//! - Priors not given are the generic weak priors of [`Priors::generic`]; a prior is used only
//!   by estimators that start from one (Kalman filters, sliding-mode and gradient estimators),
//!   RLS ignores it.
//!
//! Presets (no file): `longitudinal` (CL, CD, Cm × 0, alpha, q, de), `lateral` (CY, Cl, Cn ×
//! 0, beta, p, r, da, dr), `six-axis` (both); see [`ModelStructure::preset`].
//!
//! Every key is checked (`deny_unknown_fields`): errors name the file, the line and the key,
//! and an unknown coefficient or term lists the valid names.

use crate::mapping::line_of;
use aeroident_estimators::vocabulary::{
    AlphaKnots, Coefficient, KnotError, MAX_KNOTS, StructureError, Term,
};
use aeroident_estimators::{ModelStructure, Param, ParamPrior, Priors};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;
use toml::Spanned;

/// A model to identify: its structure, the priors of its parameters, and where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelSpec {
    /// The preset name, or the model file's path.
    pub name: String,
    /// Free-text description (the file's `description`, or the preset's).
    pub description: String,
    /// The structure (validated: non-empty, within capacity, CX/CZ not mixed with CL/CD).
    pub structure: ModelStructure,
    /// One prior per parameter, in parameter order.
    pub priors: Priors,
    /// Published reference values (`[reference.<param>]`), in file order of the names.
    pub references: Vec<ParamReference>,
    /// Plausible ranges that replace the conventional aircraft's
    /// ([`aeroident_estimators::prior::plausible_range`]) for this aircraft
    /// (`[plausible.<param>]` with `min` and `max`).
    pub plausible: Vec<PlausibleRange>,
}

/// A parameter's plausible range for one aircraft, `[plausible.<param>]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlausibleRange {
    /// The parameter.
    pub param: Param,
    /// Smallest plausible value, units of the parameter.
    pub min: f64,
    /// Largest plausible value.
    pub max: f64,
}

impl ModelSpec {
    /// The published reference value of the parameter named `name` (`[reference.X]`), if any.
    pub fn reference(&self, name: &str) -> Option<f64> {
        self.references.iter().find(|r| r.param.name() == name).map(|r| r.value)
    }

    /// The range parameter `p` of this aircraft is plausible in: the model file's
    /// `[plausible.X]` if it gives one, else a conventional aircraft's
    /// ([`aeroident_estimators::prior::plausible_range`]); `None` where neither bounds it.
    pub fn plausible_range(&self, p: Param) -> Option<(f64, f64)> {
        match self.plausible.iter().find(|r| r.param == p) {
            Some(r) => Some((r.min, r.max)),
            None => aeroident_estimators::prior::plausible_range(p),
        }
    }
}

/// Errors of reading a model file. Each names the file (and line and key where they apply).
#[derive(Debug, thiserror::Error)]
pub enum ModelFileError {
    /// The file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// File path.
        file: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// `--model` named neither a preset nor a readable file.
    #[error(
        "{arg}: not a preset (longitudinal, lateral, six-axis) and not a readable model file: {source}"
    )]
    NotFound {
        /// The argument.
        arg: String,
        /// The I/O error of reading it as a file.
        source: std::io::Error,
    },
    /// TOML syntax or an unknown key (the parser's message carries line and column).
    #[error("{file}: model syntax: {message}")]
    Syntax {
        /// File path.
        file: String,
        /// Parser message.
        message: String,
    },
    /// A `[coefficients]` key that is not a coefficient.
    #[error("{file}: line {line}: unknown coefficient `{name}` (valid: {valid})")]
    UnknownCoefficient {
        /// File path.
        file: String,
        /// Line of the key.
        line: usize,
        /// The key.
        name: String,
        /// The valid names.
        valid: String,
    },
    /// A term that is not in the vocabulary.
    #[error(
        "{file}: line {line}: coefficient `{coefficient}`: unknown term `{term}` (valid: {valid})"
    )]
    UnknownTerm {
        /// File path.
        file: String,
        /// Line of the term.
        line: usize,
        /// The coefficient.
        coefficient: String,
        /// The term as written.
        term: String,
        /// The valid names.
        valid: String,
    },
    /// A term listed twice for one coefficient.
    #[error("{file}: line {line}: coefficient `{coefficient}`: term `{term}` is listed twice")]
    DuplicateTerm {
        /// File path.
        file: String,
        /// Line of the repeated term.
        line: usize,
        /// The coefficient.
        coefficient: String,
        /// The term.
        term: String,
    },
    /// A `[prior.X]` for a parameter that is not a vocabulary name or not in the structure.
    #[error("{file}: line {line}: prior `{name}`: {reason}")]
    BadPrior {
        /// File path.
        file: String,
        /// Line of the key.
        line: usize,
        /// The key.
        name: String,
        /// Why.
        reason: String,
    },
    /// A `[reference.X]` for a parameter that is not a vocabulary name or not in the structure,
    /// or with a value that is not finite.
    #[error("{file}: line {line}: reference `{name}`: {reason}")]
    BadReference {
        /// File path.
        file: String,
        /// Line of the key.
        line: usize,
        /// The key.
        name: String,
        /// Why.
        reason: String,
    },
    /// A `[plausible.X]` range that is not usable.
    #[error("{file}: line {line}: plausible range `{name}`: {reason}")]
    BadPlausible {
        /// File path.
        file: String,
        /// Line of the key.
        line: usize,
        /// The key.
        name: String,
        /// Why.
        reason: String,
    },
    /// A coefficient declared with no terms (`CL = []`): it would be left out of the model
    /// without a word, though the file names it.
    #[error(
        "{file}: line {line}: coefficient `{coefficient}` has no terms (list at least one, e.g. `[\"0\"]` for a bias alone, or leave the coefficient out)"
    )]
    EmptyCoefficient {
        /// File path.
        file: String,
        /// 1-based line of the coefficient.
        line: usize,
        /// The coefficient.
        coefficient: String,
    },
    /// A `[knots]` list that is not a valid list of α knots.
    #[error("{file}: line {line}: knots `{key}`: {reason}")]
    BadKnots {
        /// File path.
        file: String,
        /// Line of the list.
        line: usize,
        /// The key (`alpha_deg`, `alpha_rad`).
        key: &'static str,
        /// Why.
        reason: String,
    },
    /// The declared structure is not valid.
    #[error("{file}: {source}")]
    Structure {
        /// File path.
        file: String,
        /// Why.
        source: StructureError,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFile {
    description: Option<String>,
    coefficients: BTreeMap<Spanned<String>, Vec<Spanned<String>>>,
    #[serde(default)]
    prior: BTreeMap<Spanned<String>, PriorEntry>,
    #[serde(default)]
    reference: BTreeMap<Spanned<String>, ReferenceEntry>,
    #[serde(default)]
    plausible: BTreeMap<Spanned<String>, PlausibleEntry>,
    knots: Option<Spanned<KnotsEntry>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlausibleEntry {
    min: f64,
    max: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct KnotsEntry {
    alpha_deg: Option<Spanned<Vec<f64>>>,
    alpha_rad: Option<Spanned<Vec<f64>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ReferenceEntry {
    value: f64,
    source: String,
}

/// A published reference value of one parameter (`[reference.<param>]` in a model file), shown
/// beside the estimate in the results table, the figures and `report.html`; never used by an
/// estimator.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamReference {
    /// The parameter.
    pub param: Param,
    /// The value, units of the parameter.
    pub value: f64,
    /// Where it is published (book, equation or table).
    pub source: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PriorEntry {
    value: f64,
    sigma: f64,
}

fn coefficient_names() -> String {
    Coefficient::ALL.iter().map(|c| c.name()).collect::<Vec<_>>().join(", ")
}

fn term_names() -> String {
    Term::ALL.iter().map(|t| format!("\"{}\"", t.name())).collect::<Vec<_>>().join(", ")
}

impl ModelSpec {
    /// A preset by name (`longitudinal`, `lateral`, `six-axis`) with generic priors, or `None`.
    pub fn preset(name: &str) -> Option<Self> {
        let structure = ModelStructure::preset(name)?;
        Some(Self {
            name: name.to_string(),
            description: format!("preset `{name}`"),
            structure,
            priors: Priors::generic(&structure),
            references: Vec::new(),
            plausible: Vec::new(),
        })
    }

    /// This model without parameter `p` (its prior and reference dropped with it; the same
    /// model when it has no `p`). The name says what was left out (`lateral without CY_0`).
    pub fn without(mut self, p: Param) -> Self {
        let Some(i) = self.structure.index_of(p) else { return self };
        let kept: Vec<_> =
            (0..self.priors.n).filter(|&k| k != i).map(|k| self.priors.prior[k]).collect();
        self.structure.remove(p);
        self.priors.n = kept.len();
        self.priors.prior[..kept.len()].copy_from_slice(&kept);
        self.references.retain(|r| r.param != p);
        self.plausible.retain(|r| r.param != p);
        self.name = format!("{} without {}", self.name, p.name());
        self
    }

    /// A preset name or a model file path (a preset name wins; write `./longitudinal` for a
    /// file of that name).
    ///
    /// # Errors
    /// [`ModelFileError`] for a file that cannot be read or is not valid.
    pub fn from_arg(arg: &str) -> Result<Self, ModelFileError> {
        match Self::preset(arg) {
            Some(m) => Ok(m),
            None => Self::from_path(Path::new(arg)).map_err(|e| match e {
                ModelFileError::Io { source, .. } => {
                    ModelFileError::NotFound { arg: arg.to_string(), source }
                }
                e => e,
            }),
        }
    }

    /// Reads a model file.
    ///
    /// # Errors
    /// [`ModelFileError`] naming the file, line and key.
    pub fn from_path(path: &Path) -> Result<Self, ModelFileError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|source| ModelFileError::Io { file: file.clone(), source })?;
        Self::from_toml_str(&text, &file)
    }

    /// Parses model-file TOML; `file` names it in errors.
    ///
    /// # Errors
    /// As [`ModelSpec::from_path`].
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, ModelFileError> {
        let raw: ModelFile = toml::from_str(text).map_err(|e| ModelFileError::Syntax {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        let mut structure = ModelStructure::empty();
        for (key, terms) in &raw.coefficients {
            let Some(c) = Coefficient::from_name(key.get_ref()) else {
                return Err(ModelFileError::UnknownCoefficient {
                    file: file.to_string(),
                    line: line_of(text, key.span().start),
                    name: key.get_ref().clone(),
                    valid: coefficient_names(),
                });
            };
            if terms.is_empty() {
                return Err(ModelFileError::EmptyCoefficient {
                    file: file.to_string(),
                    line: line_of(text, key.span().start),
                    coefficient: c.name().into(),
                });
            }
            for t in terms {
                let line = line_of(text, t.span().start);
                let Some(term) = Term::from_name(t.get_ref()) else {
                    return Err(ModelFileError::UnknownTerm {
                        file: file.to_string(),
                        line,
                        coefficient: c.name().into(),
                        term: t.get_ref().clone(),
                        valid: term_names(),
                    });
                };
                let p = Param::new(c, term);
                if structure.contains(p) {
                    return Err(ModelFileError::DuplicateTerm {
                        file: file.to_string(),
                        line,
                        coefficient: c.name().into(),
                        term: term.name().into(),
                    });
                }
                structure.insert(p);
            }
        }
        let structure = structure
            .with_knots(knots_of(raw.knots.as_ref(), text, file)?)
            .validated()
            .map_err(|source| ModelFileError::Structure { file: file.to_string(), source })?;
        let mut priors = Priors::generic(&structure);
        for (key, entry) in &raw.prior {
            let bad = |reason: String| ModelFileError::BadPrior {
                file: file.to_string(),
                line: line_of(text, key.span().start),
                name: key.get_ref().clone(),
                reason,
            };
            let p = Param::from_name(key.get_ref()).ok_or_else(|| {
                bad("not a parameter name `<coefficient>_<term>` of the vocabulary".into())
            })?;
            let i = structure.index_of(p).ok_or_else(|| {
                bad(format!(
                    "`{}` is not in the model (parameters: {})",
                    p.name(),
                    structure.names().collect::<Vec<_>>().join(", ")
                ))
            })?;
            let prior = ParamPrior { value: entry.value, sigma: entry.sigma };
            prior.check().map_err(bad)?;
            priors.set(i, prior);
        }
        let mut references = Vec::new();
        for (key, entry) in &raw.reference {
            let bad = |reason: String| ModelFileError::BadReference {
                file: file.to_string(),
                line: line_of(text, key.span().start),
                name: key.get_ref().clone(),
                reason,
            };
            let p = param_in(key.get_ref(), &structure).map_err(bad)?;
            // A reference is compared with the estimate (its difference in σ): a value no
            // aerodynamic parameter can take is a typo, refused as a prior's is.
            let v = entry.value;
            if !(v.is_finite() && v.abs() <= ParamPrior::MAX_ABS_VALUE) {
                return Err(bad(format!(
                    "value {v} is not finite or beyond ±{:e} (no aerodynamic parameter is that large)",
                    ParamPrior::MAX_ABS_VALUE
                )));
            }
            references.push(ParamReference {
                param: p,
                value: entry.value,
                source: entry.source.clone(),
            });
        }
        let plausible = plausible_of(&raw.plausible, &structure, text, file)?;
        Ok(Self {
            name: file.to_string(),
            description: raw.description.unwrap_or_default(),
            structure,
            priors,
            references,
            plausible,
        })
    }
}

/// The parameter a table key names, when it is one of `structure`'s; else why not.
fn param_in(key: &str, structure: &ModelStructure) -> Result<Param, String> {
    let p = Param::from_name(key)
        .ok_or("not a parameter name `<coefficient>_<term>` of the vocabulary")?;
    match structure.index_of(p) {
        Some(_) => Ok(p),
        None => Err(format!("`{}` is not in the model", p.name())),
    }
}

/// The `[plausible.X]` ranges: each of a parameter of the model, `min < max`, both finite.
fn plausible_of(
    raw: &BTreeMap<Spanned<String>, PlausibleEntry>,
    structure: &ModelStructure,
    text: &str,
    file: &str,
) -> Result<Vec<PlausibleRange>, ModelFileError> {
    let mut out = Vec::new();
    for (key, entry) in raw {
        let bad = |reason: String| ModelFileError::BadPlausible {
            file: file.to_string(),
            line: line_of(text, key.span().start),
            name: key.get_ref().clone(),
            reason,
        };
        let p = param_in(key.get_ref(), structure).map_err(bad)?;
        let (min, max) = (entry.min, entry.max);
        if !(min.is_finite() && max.is_finite() && min < max) {
            return Err(bad(format!("min = {min:e} and max = {max:e}: both finite, min < max")));
        }
        out.push(PlausibleRange { param: p, min, max });
    }
    Ok(out)
}

/// The α knots of a `[knots]` table, rad (none without one).
fn knots_of(
    entry: Option<&Spanned<KnotsEntry>>,
    text: &str,
    file: &str,
) -> Result<AlphaKnots, ModelFileError> {
    let Some(entry) = entry else { return Ok(AlphaKnots::NONE) };
    let bad = |key, at: usize, reason: String| ModelFileError::BadKnots {
        file: file.to_string(),
        line: line_of(text, at),
        key,
        reason,
    };
    let k = entry.get_ref();
    let (key, list, scale) = match (&k.alpha_deg, &k.alpha_rad) {
        (Some(d), None) => ("alpha_deg", d, 1f64.to_radians()),
        (None, Some(r)) => ("alpha_rad", r, 1.0),
        (Some(d), Some(_)) => {
            return Err(bad(
                "alpha_deg",
                d.span().start,
                "give alpha_deg or alpha_rad, not both".into(),
            ));
        }
        (None, None) => {
            return Err(bad(
                "alpha_deg",
                entry.span().start,
                "write alpha_deg = [..] or alpha_rad = [..]".into(),
            ));
        }
    };
    let rad: Vec<f64> = list.get_ref().iter().map(|v| v * scale).collect();
    AlphaKnots::new(&rad).map_err(|e| {
        let reason = match e {
            KnotError::TooMany(n) => format!("{n} knots; at most {MAX_KNOTS}"),
            KnotError::NotAnAngle { index, .. } => format!(
                "knot {} ({}) is not a finite angle within ±90°",
                index + 1,
                list.get_ref()[index]
            ),
            KnotError::NotAscending { index, .. } => format!(
                "knot {} ({}) is not above knot {} ({}): list the knots ascending, each once",
                index + 1,
                list.get_ref()[index],
                index,
                list.get_ref()[index - 1]
            ),
        };
        bad(key, list.span().start, reason)
    })
}

impl ModelSpec {
    /// The model as a model file ([`ModelSpec::from_toml_str`] reads it back to the same
    /// structure, priors and references): the description, the coefficients' terms in
    /// vocabulary order, and the priors that differ from [`Priors::generic`].
    pub fn to_toml(&self) -> String {
        use std::fmt::Write as _;
        let quoted = |s: &str| toml::Value::String(s.to_string()).to_string();
        let mut out = format!("description = {}\n\n[coefficients]\n", quoted(&self.description));
        let knots = self.structure.knots().as_slice();
        for c in Coefficient::ALL {
            let terms: Vec<String> = self
                .structure
                .params()
                .filter(|p| p.coefficient == c)
                .map(|p| quoted(p.term.name()))
                .collect();
            if !terms.is_empty() {
                let _ = writeln!(out, "{} = [{}]", c.name(), terms.join(", "));
            }
        }
        if !knots.is_empty() {
            // Radians, so that the file reads back the same bits; the degrees as a comment.
            let rad: Vec<String> = knots.iter().map(|k| format!("{k:?}")).collect();
            let deg: Vec<String> = knots.iter().map(|k| format!("{:.3}", k.to_degrees())).collect();
            let _ = write!(
                out,
                "\n[knots]\nalpha_rad = [{}]  # deg: {}\n",
                rad.join(", "),
                deg.join(", ")
            );
        }
        let generic = Priors::generic(&self.structure);
        for (i, p) in self.structure.params().enumerate() {
            let prior = self.priors.prior[i];
            if prior != generic.prior[i] {
                let _ = write!(
                    out,
                    "\n[prior.{}]\nvalue = {:?}\nsigma = {:?}\n",
                    p.name(),
                    prior.value,
                    prior.sigma
                );
            }
        }
        for r in &self.references {
            let _ = write!(
                out,
                "\n[reference.{}]\nvalue = {:?}\nsource = {}\n",
                r.param.name(),
                r.value,
                quoted(&r.source)
            );
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::prior::generic_prior;

    const GOOD: &str = r#"description = "short period with alpha-dot"
[coefficients]
Cm = ["0", "alpha", "q", "alphadot", "de"]
CL = ["0", "alpha", "q", "de"]

[prior.Cm_alpha]
value = -0.7
sigma = 1.5
"#;

    #[test]
    fn analytic_good_file_gives_structure_in_vocabulary_order_and_priors() {
        let m = ModelSpec::from_toml_str(GOOD, "sp.toml").unwrap();
        let names: Vec<_> = m.structure.names().collect();
        assert_eq!(
            names,
            [
                "CL_0",
                "CL_alpha",
                "CL_q",
                "CL_de",
                "Cm_0",
                "Cm_alpha",
                "Cm_q",
                "Cm_alphadot",
                "Cm_de"
            ]
        );
        assert_eq!(m.description, "short period with alpha-dot");
        assert_eq!(m.priors.n, 9);
        assert_eq!(m.priors.prior[5], ParamPrior { value: -0.7, sigma: 1.5 });
        // Parameters without a [prior.X] keep the generic prior.
        let cmq = Param::from_name("Cm_q").unwrap();
        assert_eq!(m.priors.prior[6], generic_prior(cmq));
        assert!(m.references.is_empty());
    }

    /// A model written by `to_toml` reads back to the same structure, priors and references,
    /// including a description that needs escaping.
    #[test]
    fn to_toml_reads_back_to_the_same_model() {
        let text = format!("{GOOD}[reference.Cm_q]\nvalue = -27.06\nsource = \"a \\\"book\\\"\"\n");
        let mut m = ModelSpec::from_toml_str(&text, "r.toml").unwrap();
        m.description = "selected by \"swr\"\non x.csv".into();
        let back = ModelSpec::from_toml_str(&m.to_toml(), "back.toml").unwrap();
        assert_eq!(back.structure, m.structure);
        assert_eq!(back.priors.prior[..back.priors.n], m.priors.prior[..m.priors.n]);
        assert_eq!(back.references, m.references);
        assert_eq!(back.description, m.description);
        assert_eq!(m.references[0].source, "a \"book\"");
    }

    /// `[reference.X]` gives published values; an unknown parameter or one outside the model
    /// is an error naming the line.
    #[test]
    fn references_are_read_and_checked() {
        let text = format!("{GOOD}[reference.Cm_q]\nvalue = -27.06\nsource = \"a book\"\n");
        let m = ModelSpec::from_toml_str(&text, "r.toml").unwrap();
        let cmq = Param::from_name("Cm_q").unwrap();
        assert_eq!(
            m.references,
            vec![ParamReference { param: cmq, value: -27.06, source: "a book".into() }]
        );
        let e = ModelSpec::from_toml_str(
            &format!("{GOOD}[reference.Cn_r]\nvalue = 1.0\nsource = \"x\"\n"),
            "r.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("r.toml: line 9")
                && e.contains("reference `Cn_r`")
                && e.contains("not in the model"),
            "{e}"
        );
        // Absurd values are refused with the line and the parameter, as a prior's are.
        for v in ["1e308", "-2e4", "nan", "inf"] {
            let e = ModelSpec::from_toml_str(
                &format!("{GOOD}[reference.Cm_q]\nvalue = {v}\nsource = \"x\"\n"),
                "r.toml",
            )
            .unwrap_err()
            .to_string();
            assert!(
                e.contains("r.toml: line 9")
                    && e.contains("reference `Cm_q`")
                    && e.contains("beyond ±1e4"),
                "{v}: {e}"
            );
        }
        let edge = format!("{GOOD}[reference.Cm_q]\nvalue = -1e4\nsource = \"x\"\n");
        assert_eq!(ModelSpec::from_toml_str(&edge, "r.toml").unwrap().references[0].value, -1e4);
    }

    /// `[plausible.X]` replaces the conventional range of one parameter; a reversed or
    /// non-finite range, or a parameter outside the model, is refused naming the line.
    #[test]
    fn plausible_ranges_are_read_and_checked() {
        let text = format!("{GOOD}[plausible.Cm_q]\nmin = -200.0\nmax = -1.0\n");
        let m = ModelSpec::from_toml_str(&text, "r.toml").unwrap();
        let cmq = Param::from_name("Cm_q").unwrap();
        assert_eq!(m.plausible_range(cmq), Some((-200.0, -1.0)));
        let cma = Param::from_name("Cm_alpha").unwrap();
        assert_eq!(m.plausible_range(cma), aeroident_estimators::prior::plausible_range(cma));
        for bad in ["min = 1.0\nmax = -1.0", "min = nan\nmax = 1.0", "min = 1.0"] {
            let e = ModelSpec::from_toml_str(&format!("{GOOD}[plausible.Cm_q]\n{bad}\n"), "r.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains("r.toml"), "{bad}: {e}");
        }
        let e = ModelSpec::from_toml_str(
            &format!("{GOOD}[plausible.Cn_r]\nmin = -1.0\nmax = 0.0\n"),
            "r.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("line 9") && e.contains("`Cn_r`") && e.contains("not in the model"),
            "{e}"
        );
    }

    #[test]
    fn presets_by_name() {
        for (name, n) in [("longitudinal", 12), ("lateral", 18), ("six-axis", 30)] {
            let m = ModelSpec::from_arg(name).unwrap();
            assert_eq!(m.structure.n_params(), n, "{name}");
            assert_eq!(m.priors.n, n);
        }
    }

    fn err(text: &str) -> String {
        ModelSpec::from_toml_str(text, "m.toml").unwrap_err().to_string()
    }

    #[test]
    fn errors_name_file_line_and_key() {
        let e = err("[coefficients]\nCm = [\"0\"]\nCM = [\"alpha\"]\n");
        assert!(e.starts_with("m.toml: line 3: unknown coefficient `CM`"), "{e}");
        assert!(e.contains("CX, CY, CZ, CL, CD, Cl, Cm, Cn"), "{e}");
        let e = err("[coefficients]\nCm = [\"0\",\n  \"alfa\"]\n");
        assert!(e.starts_with("m.toml: line 3: coefficient `Cm`: unknown term `alfa`"), "{e}");
        assert!(e.contains("\"alphadot\"") && e.contains("\"alpha_beta\""), "{e}");
        let e = err("[coefficients]\nCm = [\"q\", \"q\"]\n");
        assert!(e.contains("line 2: coefficient `Cm`: term `q` is listed twice"), "{e}");
        let e = err("[coefficients]\nCm = [\"q\"]\n[prior.Cm_alpha]\nvalue = 1.0\nsigma = 1.0\n");
        assert!(e.contains("line 3: prior `Cm_alpha`: `Cm_alpha` is not in the model"), "{e}");
        let e = err("[coefficients]\nCm = [\"q\"]\n[prior.Cm_qq]\nvalue = 1.0\nsigma = 1.0\n");
        assert!(e.contains("prior `Cm_qq`: not a parameter name"), "{e}");
        let e = err("[coefficients]\nCm = [\"q\"]\n[prior.Cm_q]\nvalue = 1.0\nsigma = 0.0\n");
        assert!(e.contains("sigma must be finite and > 0"), "{e}");
        let e =
            err("[coefficients]\nCm = [\"q\"]\n[prior.Cm_q]\nvalue = 1.0\nsigma = 1.0\nmean = 2\n");
        assert!(
            e.contains("m.toml: model syntax") && e.contains("mean") && e.contains("line 6"),
            "{e}"
        );
        let e = err("terms = 3\n[coefficients]\nCm = [\"q\"]\n");
        assert!(e.contains("terms") && e.contains("line 1"), "{e}");
        let e = err("[coefficients]\nCX = [\"alpha\"]\nCL = [\"alpha\"]\n");
        assert!(e.contains("m.toml") && e.contains("choose body axes"), "{e}");
        let e = err("[coefficients]\n");
        assert!(e.contains("declares no parameter"), "{e}");
        let e = ModelSpec::from_arg("no/such/model.toml").unwrap_err().to_string();
        assert!(e.starts_with("no/such/model.toml: not a preset (longitudinal"), "{e}");
    }

    /// A coefficient with an empty term list is refused where it is declared, not dropped.
    #[test]
    fn errors_empty_coefficient_names_file_line_and_coefficient() {
        let e = err("description = \"x\"\n[coefficients]\nCL = []\nCD = [\"0\"]\nCm = [\"q\"]\n");
        assert!(e.starts_with("m.toml: line 3: coefficient `CL` has no terms"), "{e}");
    }

    /// Knots in degrees read as radians; the model file written back reads to the same
    /// structure, knots bit for bit.
    #[test]
    fn knots_round_trip_through_the_model_file() {
        let text = "description = \"lift break\"\n[coefficients]\nCL = [\"0\", \"alpha\", \"alpha_k1\", \"alpha_k2\", \"mach\"]\nCD = [\"0\", \"mach2\"]\nCm = [\"0\", \"alpha\", \"alpha_k2\"]\n[knots]\nalpha_deg = [8.0, 12.5]\n";
        let m = ModelSpec::from_toml_str(text, "m.toml").unwrap();
        assert_eq!(m.structure.knots().as_slice(), &[8f64.to_radians(), 12.5f64.to_radians()]);
        assert_eq!(m.structure.names().nth(2), Some("CL_alpha_k1"));
        let back = ModelSpec::from_toml_str(&m.to_toml(), "back.toml").unwrap();
        assert_eq!(back.structure, m.structure);
        assert_eq!(back.structure.knots().as_slice(), m.structure.knots().as_slice());
        let rad = "[coefficients]\nCL = [\"alpha_k1\"]\n[knots]\nalpha_rad = [0.1]\n";
        assert_eq!(err_free(rad).structure.knots().as_slice(), &[0.1]);
    }

    fn err_free(text: &str) -> ModelSpec {
        ModelSpec::from_toml_str(text, "m.toml").unwrap()
    }

    /// Knots unsorted, repeated, not finite, beyond ±90°, too many, in both units, or fewer
    /// than the spline terms need, are refused naming the file, line and key.
    #[test]
    fn bad_knots_are_refused_with_file_line_and_key() {
        let with = |knots: &str| {
            err(&format!(
                "[coefficients]\nCL = [\"0\", \"alpha_k1\", \"alpha_k2\"]\n\n[knots]\n{knots}\n"
            ))
        };
        let e = with("alpha_deg = [12.0, 8.0]");
        assert!(
            e.starts_with("m.toml: line 5: knots `alpha_deg`: knot 2 (8) is not above knot 1 (12)"),
            "{e}"
        );
        let e = with("alpha_deg = [8.0, 8.0]");
        assert!(e.contains("line 5") && e.contains("knot 2 (8) is not above knot 1 (8)"), "{e}");
        let e = with("alpha_deg = [8.0, nan]");
        assert!(e.contains("line 5") && e.contains("knot 2 (NaN) is not a finite angle"), "{e}");
        let e = with("alpha_deg = [8.0, inf]");
        assert!(e.contains("knot 2 (inf) is not a finite angle"), "{e}");
        let e = with("alpha_deg = [8.0, 95.0]");
        assert!(e.contains("knot 2 (95) is not a finite angle within ±90°"), "{e}");
        let e = with("alpha_deg = [1.0, 2.0, 3.0, 4.0, 5.0]");
        assert!(e.contains("line 5") && e.contains("5 knots; at most 4"), "{e}");
        let e = with("alpha_deg = [8.0, 9.0]\nalpha_rad = [0.1, 0.2]");
        assert!(e.contains("line 5") && e.contains("not both"), "{e}");
        let e = with("alpha_deg = [8.0]");
        assert!(e.contains("m.toml") && e.contains("`alpha_k2` but only 1 α knot"), "{e}");
        let e = with("alpha = [8.0]");
        assert!(e.contains("m.toml: model syntax") && e.contains("alpha"), "{e}");
    }
}
