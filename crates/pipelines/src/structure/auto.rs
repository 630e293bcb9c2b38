//! `--model auto`: the model structure chosen from the record itself, coefficient by
//! coefficient, by equation error ([`super::select_on_samples`]), then handed to any estimator
//! as an ordinary [`ModelSpec`] (Klein & Morelli 2006 ch. 5: determine the structure by
//! regression, then estimate its parameters by output error).
//!
//! The record is read as the batch fits read it (split at gaps, spikes screened, compatibility
//! corrections and time windows applied). The time derivatives the record lacks (`ṗ`, `q̇`,
//! `ṙ` for the moment coefficients, `α̇` for the `alphadot` candidate) come from the
//! conditioning stage with the matched smoother ([`crate::condition::Alignment::Matched`]), so
//! both sides of the regression see the same filter.

mod excited;

use super::{
    CoefficientSelection, Method, Wanted, alpha_quantile_knots, condition, read_for_selection,
    select_on_samples, to_supply,
};
use crate::condition::Derivative;
use crate::record::RecordError;
use aeroident_estimators::structure::StepAction;
use aeroident_estimators::{
    AirDataSample, AlphaKnots, Coefficient, ModelStructure, Param, Priors, Term,
};
use aeroident_io::{FlightDataReader, Mapping, ModelSpec};
use serde::Serialize;
use std::io::Read;

/// Which coefficients the selection covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scope {
    /// `CL`, `CD`, `Cm`.
    Longitudinal,
    /// `CY`, `Cl`, `Cn`.
    Lateral,
    /// Both.
    SixAxis,
}

impl Scope {
    /// `longitudinal`, `lateral` or `six-axis` (the preset names).
    pub fn name(self) -> &'static str {
        match self {
            Scope::Longitudinal => "longitudinal",
            Scope::Lateral => "lateral",
            Scope::SixAxis => "six-axis",
        }
    }

    /// The coefficients selected, in vocabulary order.
    pub fn coefficients(self) -> Vec<Coefficient> {
        let lon = [Coefficient::CL, Coefficient::CD, Coefficient::Cm];
        let lat = [Coefficient::CY, Coefficient::Cl, Coefficient::Cn];
        let mut c: Vec<Coefficient> = match self {
            Scope::Longitudinal => lon.to_vec(),
            Scope::Lateral => lat.to_vec(),
            Scope::SixAxis => lon.into_iter().chain(lat).collect(),
        };
        c.sort();
        c
    }

    /// The default candidates of coefficient `c`: the preset's terms and the nonlinear ones a
    /// flight-test engineer tries next (Klein & Morelli 2006 §5.4: α², α·δe, α·q̂ and V/V0 for
    /// the longitudinal coefficients; for the lateral ones α times each preset term, the
    /// α-dependence of the lateral derivatives that tables such as the F-16's have). `alphadot` is offered only when
    /// asked for (`AutoModel::candidates`): in most manoeuvres α̇ and q̂ move together, and α̇
    /// also stands in for a lag of the α channel behind the kinematics. On the HFB-320 (α ~0.2 s
    /// late) it enters CL with partial F ≈ 1,700, and output error then gives CL_q −216 ± 1,325
    /// and CL_alphadot 312 ± 1,498: a pair the record cannot separate.
    pub fn default_candidates(c: Coefficient) -> Vec<Term> {
        use Term::*;
        if matches!(c, Coefficient::CY | Coefficient::Cl | Coefficient::Cn) {
            vec![Beta, P, R, Da, Dr, AlphaBeta, AlphaP, AlphaR, AlphaDa, AlphaDr]
        } else {
            vec![Alpha, Q, De, V, Alpha2, AlphaDe, AlphaQ]
        }
    }
}

/// `--model auto[:longitudinal|lateral|six-axis]`: the scope (`None`: six-axis when the record
/// has β and the lateral channels, else longitudinal), the method and, optionally, the
/// candidates of every coefficient (else [`Scope::default_candidates`]).
#[derive(Debug, Clone, PartialEq)]
pub struct AutoModel {
    /// The coefficients covered; `None`: the richest the record supports.
    pub scope: Option<Scope>,
    /// Stepwise regression or orthogonal functions.
    pub method: Method,
    /// The candidates of every coefficient; `None`: the defaults.
    pub candidates: Option<Vec<Term>>,
    /// The α knots of the spline candidates, given by the user (e.g. at a table's
    /// breakpoints); `None`: at the record's α quantiles ([`alpha_quantile_knots`]). Given
    /// knots with the default candidates add `alpha_k1…alpha_kn` to every longitudinal
    /// coefficient's.
    pub knots: Option<AlphaKnots>,
}

impl AutoModel {
    /// Reads a `--model` argument: `None` when it does not start with `auto`.
    ///
    /// # Errors
    /// `auto:` followed by something other than a scope, naming the valid ones.
    pub fn parse(arg: &str, method: Method) -> Option<Result<Self, String>> {
        let rest = arg.strip_prefix("auto")?;
        let scope = match rest {
            "" => None,
            ":longitudinal" => Some(Scope::Longitudinal),
            ":lateral" => Some(Scope::Lateral),
            ":six-axis" => Some(Scope::SixAxis),
            _ => {
                return Some(Err(format!(
                    "--model {arg}: write `auto`, `auto:longitudinal`, `auto:lateral` or `auto:six-axis`"
                )));
            }
        };
        Some(Ok(Self { scope, method, candidates: None, knots: None }))
    }

    /// This selection with the spline knots `knots_deg` (degrees, ascending) given; empty
    /// leaves the knots to the record's α quantiles.
    ///
    /// # Errors
    /// Knots [`AlphaKnots::new`] refuses (unsorted, repeated, beyond ±90°, more than four).
    pub fn with_knots_deg(self, knots_deg: &[f64]) -> Result<Self, String> {
        if knots_deg.is_empty() {
            return Ok(self);
        }
        let rad: Vec<f64> = knots_deg.iter().map(|k| k.to_radians()).collect();
        let knots = AlphaKnots::new(&rad).map_err(|e| {
            let shown: Vec<String> =
                knots_deg.iter().map(|k| aeroident_io::message::short(*k)).collect();
            format!("α knots [{}]°: {e}", aeroident_io::message::list(&shown, 8))
        })?;
        Ok(Self { knots: Some(knots), ..self })
    }

    /// The candidates offered to coefficient `c`: the given ones, else the defaults and, with
    /// given knots, one spline per knot for the longitudinal coefficients (a symmetric
    /// aircraft's `CY`, `Cl`, `Cn` are odd in β: their α-dependence enters through the α
    /// products).
    fn offered(&self, c: Coefficient, alphadot: bool) -> Vec<Term> {
        if let Some(given) = &self.candidates {
            return given.clone();
        }
        let mut terms = Scope::default_candidates(c);
        if alphadot && matches!(c, Coefficient::CL | Coefficient::Cm) {
            terms.push(Term::Alphadot);
        }
        if !matches!(c, Coefficient::CY | Coefficient::Cl | Coefficient::Cn) {
            let n = self.knots.map_or(0, |k| k.len());
            terms.extend((0..n).filter_map(Term::spline));
        }
        terms
    }

    /// The knots of the spline candidates: the given ones, checked against the candidates and
    /// the record's α range, else the record's α quantiles.
    fn knots_on(
        &self,
        manoeuvres: &[&[AirDataSample]],
        candidates: &[Term],
    ) -> Result<AlphaKnots, String> {
        let Some(knots) = self.knots else {
            return alpha_quantile_knots(manoeuvres, candidates);
        };
        let splines = candidates.iter().filter_map(|t| t.knot());
        if let Some(i) = splines.clone().find(|&i| i >= knots.len()) {
            return Err(format!(
                "candidate `{}` needs {} α knots; {} given",
                Term::spline(i).map_or("", |t| t.name()),
                i + 1,
                knots.len()
            ));
        }
        if splines.count() == 0 {
            return Err(
                "α knots are given but no spline (`alpha_k1` …) is among the candidates".into()
            );
        }
        let probe = ModelStructure::empty().with_knots(knots);
        super::check_knots_in_range(&probe, manoeuvres, "the given α knots")?;
        Ok(knots)
    }

    /// The faces' arguments: a `--model` value, the method's name ([`Method::from_name`]) and
    /// candidate names (empty: the defaults). `None` when `model` does not start with `auto`.
    ///
    /// # Errors
    /// A bad scope or method, or a candidate that is not a vocabulary term (or is the constant).
    pub fn from_args(
        model: &str,
        method: &str,
        candidates: &[String],
    ) -> Option<Result<Self, String>> {
        let method = match Method::from_name(method) {
            Ok(m) => m,
            Err(e) if model.starts_with("auto") => return Some(Err(e)),
            Err(_) => return None,
        };
        let auto = match Self::parse(model, method)? {
            Ok(a) => a,
            Err(e) => return Some(Err(e)),
        };
        if candidates.is_empty() {
            return Some(Ok(auto));
        }
        let terms = candidates.iter().map(|n| {
            Term::from_name(n).filter(|t| *t != Term::Bias).ok_or_else(|| {
                let valid: Vec<&str> =
                    Term::ALL.iter().filter(|t| **t != Term::Bias).map(|t| t.name()).collect();
                format!("candidate `{n}` is not a term of the vocabulary ({})", valid.join(", "))
            })
        });
        Some(terms.collect::<Result<Vec<_>, _>>().map(|c| Self { candidates: Some(c), ..auto }))
    }
}

/// A structure chosen from the record: the model to fit and how it was chosen.
#[derive(Debug, Clone)]
pub struct AutoSelection {
    /// The model: each coefficient's constant and kept terms, generic priors.
    pub model: ModelSpec,
    /// The scope used (given; else the richest the record supports, narrowed to the axes
    /// the record excites: an axis whose moment equations keep a surface term and whose
    /// surfaces moved most; docs/structure.md).
    pub scope: Scope,
    /// Why the scope is narrower than the record supports (`None`: it is not).
    pub scope_reason: Option<String>,
    /// The method.
    pub method: Method,
    /// Each coefficient's selection.
    pub selections: Vec<CoefficientSelection>,
    /// Candidates the record cannot evaluate (a channel or constant unmapped), left out.
    pub unavailable: Vec<Term>,
    /// Derivatives the conditioning stage supplied.
    pub supplied: Vec<Derivative>,
    /// Samples read.
    pub samples_read: usize,
    /// Samples with their derivatives, over all manoeuvres (the derivative stage leaves out
    /// each manoeuvre's ends).
    pub samples_used: usize,
    /// Whether and why `alphadot` was offered by default (`None`: the candidates were given,
    /// or the scope has no `CL`, `Cm`).
    pub alphadot: Option<String>,
}

/// Why α̇ is or is not among the default candidates of `CL` and `Cm`: offered once α's timing
/// is checked (a compatibility check estimated α's time shift and it stands), since α̇ also
/// stands in for a lag of the α channel behind the kinematics ([`Scope::default_candidates`]).
fn alphadot_note(auto: &AutoModel, scope: Scope, alpha_timed: bool) -> Option<String> {
    if auto.candidates.is_some() || scope == Scope::Lateral {
        return None;
    }
    Some(if alpha_timed {
        "alphadot offered to CL and Cm: the compatibility check timed the α channel against the kinematics".into()
    } else {
        "alphadot not offered: the α channel's timing is unchecked, and α̇ would also absorb a lag of α behind the kinematics; run with --compat auto (or a compat.json that estimated α's time shift), or list alphadot in --candidates".into()
    })
}

/// Reads the records and selects each coefficient's terms (module doc).
///
/// # Errors
/// Reading errors, no usable sample, a scope the record cannot support (no β for the lateral
/// coefficients), a coefficient with no candidate left, and [`select_on_samples`]'s.
pub fn select_model<R: Read>(
    readers: Vec<FlightDataReader<R>>,
    mapping: &Mapping,
    auto: &AutoModel,
    compat: Option<&crate::compat::Corrections>,
    windows: &[crate::window::TimeWindow],
    diff_window: usize,
) -> Result<AutoSelection, RecordError> {
    let file = readers.first().map_or(String::new(), |r| r.file().to_string());
    let (raw, first) = read_for_selection(readers, compat, windows)?;
    let alpha_timed =
        compat.is_some_and(|c| c.timing_checked(aeroident_estimators::compat::Channel::Alpha));
    let offered = |c| auto.offered(c, alpha_timed);
    let scope = auto.scope.unwrap_or_else(|| richest_scope(&first));
    let coefficients = scope.coefficients();
    let candidates: Vec<Term> = coefficients.iter().flat_map(|&c| offered(c)).collect();
    let supplied =
        to_supply(&Wanted { coefficients: &coefficients, candidates: &candidates }, &first);
    let rec = condition(&raw, supplied, diff_window, mapping.nominal_dt_s)?;
    let probe = rec.first().copied().ok_or_else(|| {
        RecordError::Model(format!(
            "{file}: every manoeuvre is shorter than the differentiator window ({diff_window} samples)"
        ))
    })?;
    let slices = rec.slices();
    let knots = auto
        .knots_on(&slices, &candidates)
        .map_err(|e| RecordError::Model(format!("{file}: {e}")))?;
    let mut unavailable = Vec::new();
    let mut selections = Vec::new();
    for &c in &coefficients {
        let (usable, missing): (Vec<Term>, Vec<Term>) =
            offered(c).into_iter().partition(|t| t.value(&probe, &knots).is_some());
        for t in missing {
            if !unavailable.contains(&t) {
                unavailable.push(t);
            }
        }
        if usable.is_empty() {
            return Err(RecordError::Model(format!(
                "{file}: {}: no candidate term can be evaluated on this record (unmapped: {})",
                c.name(),
                names(&unavailable)
            )));
        }
        selections.push(
            select_on_samples(&slices, c, &usable, &knots, auto.method)
                .map_err(RecordError::Model)?,
        );
    }
    let (scope, scope_reason) = match (auto.scope, scope) {
        (None, Scope::SixAxis) => excited::excited_scope(&selections, &slices),
        _ => (scope, None),
    };
    let coefficients = scope.coefficients();
    selections.retain(|s| coefficients.contains(&s.coefficient));
    let model = model_of(&selections, knots, scope, auto.method, &file)?;
    let alphadot = alphadot_note(auto, scope, alpha_timed);
    Ok(AutoSelection {
        alphadot,
        model,
        scope,
        scope_reason,
        method: auto.method,
        selections,
        unavailable,
        supplied: rec.supplied.clone(),
        samples_read: rec.read,
        samples_used: slices.iter().map(|m| m.len()).sum(),
    })
}

/// The model of a face's arguments (`--model`, `--select`, `--candidates`, `--knots-deg`): a
/// preset or a
/// model file as [`ModelSpec::from_arg`] reads it, or, for `auto…`, the structure
/// [`select_model`] chooses on the records `open` gives (`None` and `None`: no model given).
///
/// # Errors
/// `method` other than `swr` or `candidates` without `auto`; a bad model argument or file;
/// `open`'s and [`select_model`]'s errors.
#[allow(clippy::too_many_arguments)]
pub fn model_from_args<R: Read>(
    model: Option<&str>,
    method: &str,
    candidates: &[String],
    alpha_knots_deg: &[f64],
    open: impl FnOnce() -> Result<Vec<FlightDataReader<R>>, aeroident_io::FlightDataError>,
    mapping: &Mapping,
    compat: Option<&crate::compat::Corrections>,
    windows: &[crate::window::TimeWindow],
    diff_window: usize,
) -> Result<(Option<ModelSpec>, Option<AutoSelection>), RecordError> {
    let arg = model.unwrap_or_default();
    let Some(auto) = AutoModel::from_args(arg, method, candidates) else {
        if !candidates.is_empty() || !alpha_knots_deg.is_empty() || method != "swr" {
            return Err(RecordError::Option {
                option: "select",
                reason: "a selection method, candidates and knots apply to the model `auto`".into(),
            });
        }
        let spec = model.map(ModelSpec::from_arg).transpose();
        return Ok((spec.map_err(|e| RecordError::Model(e.to_string()))?, None));
    };
    let auto = auto
        .and_then(|a| a.with_knots_deg(alpha_knots_deg))
        .map_err(|e| RecordError::Model(format!("model `{arg}`: {e}")))?;
    let selection = select_model(open()?, mapping, &auto, compat, windows, diff_window)?;
    Ok((Some(selection.model.clone()), Some(selection)))
}

/// Six-axis when the record measures every coefficient (the lateral ones with β; the rates
/// whose derivatives the conditioning stage would supply count as measured), lateral when it
/// measures only the lateral ones (a lateral mapping without `q`), else longitudinal (whose
/// own gaps the selection then names).
fn richest_scope(first: &AirDataSample) -> Scope {
    let mut s = *first;
    for d in Derivative::ALL {
        if d.recorded(&s).is_none() && d.source(&s).is_some() {
            d.set(&mut s, Some(0.0));
        }
    }
    let measured = s.measured_coefficients();
    let all = |scope: Scope| scope.coefficients().iter().all(|c| measured[c.index()].is_some());
    match (all(Scope::Longitudinal), all(Scope::Lateral) && s.beta_rad.is_some()) {
        (true, true) => Scope::SixAxis,
        (false, true) => Scope::Lateral,
        _ => Scope::Longitudinal,
    }
}

fn names(terms: &[Term]) -> String {
    terms.iter().map(|t| t.name()).collect::<Vec<_>>().join(", ")
}

/// The model of the kept terms, each coefficient with its constant, and the knots the
/// spline candidates were offered with.
fn model_of(
    selections: &[CoefficientSelection],
    knots: AlphaKnots,
    scope: Scope,
    method: Method,
    file: &str,
) -> Result<ModelSpec, RecordError> {
    let mut structure = ModelStructure::empty().with_knots(knots);
    for s in selections {
        structure.insert(Param::new(s.coefficient, Term::Bias));
        for t in s.kept() {
            structure.insert(Param::new(s.coefficient, t));
        }
    }
    let structure = structure.validated().map_err(|e| {
        RecordError::Model(format!(
            "{file}: the selected model is not usable: {e} (offer fewer candidates with --candidates, select one scope at a time, or select with --select mof)"
        ))
    })?;
    Ok(ModelSpec {
        name: format!("auto:{} ({})", scope.name(), method.name()),
        description: format!(
            "selected by {} on {file} (aeroident --model auto)",
            match method {
                Method::Stepwise(_) => "stepwise regression",
                Method::Orthogonal(_) => "multivariate orthogonal functions",
            }
        ),
        priors: Priors::generic(&structure),
        structure,
        references: Vec::new(),
        plausible: Vec::new(),
    })
}

/// One step of a selection path, as `summary.json` gives it.
#[derive(Debug, Clone, Serialize)]
pub struct PathStep {
    /// `enter` or `remove`.
    pub action: &'static str,
    /// The term moved.
    pub term: &'static str,
    /// Its partial F ratio (after entering, or when it left); `null` when infinite.
    pub partial_f: Option<f64>,
    /// Predicted squared error of the model after the step.
    pub pse: f64,
    /// `R²` after the step.
    pub r2: f64,
}

/// One least-squares estimate of the selected structure, as `summary.json` gives it.
#[derive(Debug, Clone, Serialize)]
pub struct EquationErrorEstimate {
    /// Parameter name (`Cm_q`).
    pub name: String,
    /// The estimate (the name every per-parameter object of the summary uses).
    pub estimate: f64,
    /// Standard error corrected for coloured residuals (the spectral sandwich output error
    /// reports, [`aeroident_estimators::structure::coloured_std_error`]); `null` when it could
    /// not be formed.
    pub std_error: Option<f64>,
    /// The white-residual standard error `s²(XᵀX)⁻¹` the partial F uses; too small on flight
    /// data, whose residuals are correlated.
    pub white_std_error: f64,
}

/// One coefficient's selection, as `summary.json` gives it.
#[derive(Debug, Clone, Serialize)]
pub struct CoefficientReport {
    /// The coefficient.
    pub coefficient: &'static str,
    /// The candidates offered.
    pub candidates: Vec<&'static str>,
    /// The terms kept (the constant is always in the model).
    pub kept: Vec<&'static str>,
    /// The path.
    pub path: Vec<PathStep>,
    /// Why the selection stopped.
    pub stopped: String,
    /// Equation-error estimates of the kept terms and the constant.
    pub equation_error: Vec<EquationErrorEstimate>,
    /// `R²` of the final fit.
    pub r2: f64,
    /// Predicted squared error of the final fit.
    pub pse: f64,
    /// Samples used, and left out (coefficient or a candidate not measured).
    pub samples: usize,
    /// Samples left out.
    pub skipped: usize,
    /// Each candidate not kept, with its partial F were it added to the final model (`null`:
    /// the model already explains it).
    pub left_out: Vec<LeftOut>,
}

/// A candidate the selection left out, and its partial F against the final model.
#[derive(Debug, Clone, Serialize)]
pub struct LeftOut {
    /// The candidate.
    pub term: &'static str,
    /// Its partial F were it added (`null`: collinear with the model).
    pub partial_f: Option<f64>,
    /// The parent it waited for, not in the model (a power or product term enters only after
    /// its parents); `null` when it was offered.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub waiting_for: Option<&'static str>,
}

/// `structure_selection` of `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct StructureReport {
    /// `swr` or `mof`.
    pub method: &'static str,
    /// Stepwise: partial F to enter and to leave; `null` for orthogonal functions.
    pub f_in: Option<f64>,
    /// As `f_in`.
    pub f_out: Option<f64>,
    /// The coefficients covered.
    pub scope: &'static str,
    /// Why the scope is narrower than the record's channels support: an axis whose moment
    /// equations keep no surface term is not excited ([`AutoSelection::scope_reason`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scope_reason: Option<String>,
    /// The α knots of the spline candidates, degrees (given, or the record's α quantiles,
    /// [`super::alpha_quantile_knots`]); empty when no spline was offered.
    pub alpha_knots_deg: Vec<f64>,
    /// Candidates the record cannot evaluate, left out.
    pub unavailable: Vec<&'static str>,
    /// Derivatives the conditioning stage supplied.
    pub derivatives_supplied: Vec<&'static str>,
    /// Samples read and used.
    pub samples_read: usize,
    /// As `samples_read`.
    pub samples_used: usize,
    /// Per coefficient.
    pub coefficients: Vec<CoefficientReport>,
    /// What the selection's reader should doubt ([`AutoSelection::warnings`]).
    pub warnings: Vec<String>,
    /// Whether and why `alphadot` was offered by default ([`AutoSelection::alphadot`]);
    /// absent when the candidates were given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alphadot: Option<String>,
}

/// Fewest samples per term of the largest regression (the candidates and the constant) for
/// which a selection is trusted without a warning. Equation error's partial F and PSE are
/// estimated from the residuals: with fewer than about ten samples per regressor the residual
/// variance has few degrees of freedom and the F cut-off (20) is met by chance (Klein &
/// Morelli 2006, ch. 5, recommend many samples per parameter).
pub const SAMPLES_PER_TERM: usize = 10;

impl AutoSelection {
    /// The report for `summary.json`.
    pub fn report(&self) -> StructureReport {
        let (f_in, f_out) = match self.method {
            Method::Stepwise(c) => (Some(c.f_in), Some(c.f_out)),
            Method::Orthogonal(_) => (None, None),
        };
        StructureReport {
            method: self.method.name(),
            f_in,
            f_out,
            scope: self.scope.name(),
            scope_reason: self.scope_reason.clone(),
            alpha_knots_deg: self
                .model
                .structure
                .knots()
                .as_slice()
                .iter()
                .map(|k| k.to_degrees())
                .collect(),
            unavailable: self.unavailable.iter().map(|t| t.name()).collect(),
            derivatives_supplied: self.supplied.iter().map(|d| d.name()).collect(),
            samples_read: self.samples_read,
            samples_used: self.samples_used,
            coefficients: self.selections.iter().map(coefficient_report).collect(),
            warnings: self.warnings(),
            alphadot: self.alphadot.clone(),
        }
    }

    /// Warnings about the selection: too few samples for the candidates offered (fewer than
    /// [`SAMPLES_PER_TERM`] per term of the largest regression).
    pub fn warnings(&self) -> Vec<String> {
        let terms = self.selections.iter().map(|s| s.candidates.len() + 1).max().unwrap_or(0);
        let mut out = Vec::new();
        if self.samples_used < SAMPLES_PER_TERM * terms {
            out.push(format!(
                "structure selection on {} samples for up to {terms} terms (candidates and the constant): fewer than {SAMPLES_PER_TERM} samples per term, so its partial F tests mean little; select on a longer record or offer fewer candidates (--candidates)",
                self.samples_used
            ));
        }
        out
    }

    /// The selection path for people: per coefficient, one line per step and the result.
    pub fn path_lines(&self) -> Vec<String> {
        let mut lines = self.path_head();
        lines.extend(self.scope_reason.iter().map(|n| format!("  {n}")));
        lines.extend(self.alphadot.iter().map(|n| format!("  {n}")));
        lines.extend(self.coefficient_lines());
        lines
    }

    fn path_head(&self) -> Vec<String> {
        vec![format!(
            "structure: {} on {} samples, {} coefficients{}",
            self.method.name(),
            self.samples_used,
            self.scope.name(),
            if self.unavailable.is_empty() {
                String::new()
            } else {
                format!(" (not in the record: {})", names(&self.unavailable))
            }
        )]
    }

    fn coefficient_lines(&self) -> Vec<String> {
        let mut lines = Vec::new();
        for r in self.selections.iter().map(coefficient_report) {
            let steps: Vec<String> = r
                .path
                .iter()
                .map(|s| {
                    let sign = if s.action == "enter" { "+" } else { "−" };
                    let f = s.partial_f.map_or(String::new(), |f| format!("F {f:.1}, "));
                    format!("{sign}{} ({f}PSE {:.3e})", s.term, s.pse)
                })
                .collect();
            // Orthogonal functions are expanded back into the ordinary terms they are made of.
            let keeps = match self.method {
                Method::Stepwise(_) => "keeps",
                Method::Orthogonal(_) => "functions expanded back to",
            };
            lines.push(format!(
                "  {}: {} → {keeps} 0, {} (R² {:.3}); {}",
                r.coefficient,
                steps.join(", "),
                r.kept.join(", "),
                r.r2,
                r.stopped
            ));
            if !r.left_out.is_empty() {
                lines.push(format!("    left out: {}", left_out_text(&r.left_out, self.method)));
            }
        }
        lines.extend(self.warnings().into_iter().map(|w| format!("warning: {w}")));
        lines
    }
}

/// `alpha_de (F 2.8 ≤ 20), alpha_q (explained by the kept terms)`: each term left out and why.
fn left_out_text(left: &[LeftOut], method: Method) -> String {
    let cut = match method {
        Method::Stepwise(c) => format!(" ≤ {}", c.f_in),
        Method::Orthogonal(_) => " against the kept terms; the PSE minimum".to_string(),
    };
    let items: Vec<String> = left
        .iter()
        .map(|l| match (l.partial_f, l.waiting_for) {
            (_, Some(p)) => {
                format!("{} (not offered: its parent `{p}` is not in the model)", l.term)
            }
            (Some(f), None) => format!("{} (partial F {f:.1}{cut})", l.term),
            (None, None) => format!("{} (explained by the kept terms)", l.term),
        })
        .collect();
    items.join(", ")
}

fn coefficient_report(s: &CoefficientSelection) -> CoefficientReport {
    let term = |k: usize| s.candidates[k].name();
    let fit = &s.selection.fit;
    // The kept terms in order, then the constant, as the fit holds them.
    let terms = fit.terms.iter().map(|&k| s.candidates[k]).chain([Term::Bias]);
    let equation_error = terms
        .enumerate()
        .map(|(i, t)| EquationErrorEstimate {
            name: Param::new(s.coefficient, t).name().to_string(),
            estimate: fit.theta[i],
            std_error: s.std_error_coloured.as_ref().map(|c| c[i]),
            white_std_error: fit.std_error[i],
        })
        .collect();
    CoefficientReport {
        coefficient: s.coefficient.name(),
        candidates: s.candidates.iter().map(|t| t.name()).collect(),
        kept: s.kept().iter().map(|t| t.name()).collect(),
        path: s
            .selection
            .path
            .iter()
            .map(|p| PathStep {
                action: match p.action {
                    StepAction::Enter => "enter",
                    StepAction::Remove => "remove",
                },
                term: term(p.candidate),
                partial_f: p.partial_f.is_finite().then_some(p.partial_f),
                pse: p.pse,
                r2: p.r2,
            })
            .collect(),
        stopped: s.selection.stopped.clone(),
        equation_error,
        r2: fit.r2,
        pse: fit.pse,
        samples: s.samples,
        skipped: s.skipped,
        left_out: s
            .left_out
            .iter()
            .map(|(t, f, p)| LeftOut {
                term: t.name(),
                partial_f: *f,
                waiting_for: p.map(|p| p.name()),
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Refused knots are shown short whatever was typed: a million knots as the first eight and
    /// a count (once a 9.9 MB message), 1e300° and a 310-digit number in scientific form.
    #[test]
    fn refused_knots_are_shown_short() {
        let auto = || AutoModel::from_args("auto", "swr", &[]).unwrap().unwrap();
        let many: Vec<f64> = (0..1_000_000).map(|k| k as f64 * 1e-4).collect();
        let e = auto().with_knots_deg(&many).unwrap_err();
        assert!(
            e.len() < 300 && e.contains("… and 999992 more") && e.contains("1000000 α knots"),
            "{e}"
        );
        let huge: f64 = format!("1{}", "0".repeat(309)).parse().unwrap();
        for (knot, shown) in [(1e300, "1.000e300"), (huge, "inf"), (123.456_789, "123.4568")] {
            let e = auto().with_knots_deg(&[knot]).unwrap_err();
            assert!(e.len() < 200 && e.contains(&format!("[{shown}]°")), "{e}");
        }
    }

    #[test]
    fn from_args_reads_scope_method_and_candidates() {
        let a = AutoModel::from_args("auto:lateral", "mof", &[]).unwrap().unwrap();
        assert_eq!(a.scope, Some(Scope::Lateral));
        assert_eq!(a.method.name(), "mof");
        assert_eq!(a.candidates, None);
        let b = AutoModel::from_args("auto", "swr", &["alphadot".into(), "q".into()]);
        let b = b.unwrap().unwrap();
        assert_eq!((b.scope, b.candidates), (None, Some(vec![Term::Alphadot, Term::Q])));
        assert!(AutoModel::from_args("longitudinal", "swr", &[]).is_none());
        assert!(AutoModel::from_args("auto:pitch", "swr", &[]).unwrap().is_err());
        assert!(AutoModel::from_args("auto", "lasso", &[]).unwrap().is_err());
        let e = AutoModel::from_args("auto", "swr", &["0".into()]).unwrap().unwrap_err();
        assert!(e.contains("`0`") && e.contains("alpha_beta"), "{e}");
    }

    #[test]
    fn scopes_cover_their_coefficients() {
        let six = Scope::SixAxis.coefficients();
        assert_eq!(six.len(), 6);
        for c in Scope::Longitudinal.coefficients().into_iter().chain(Scope::Lateral.coefficients())
        {
            assert!(six.contains(&c));
            assert!(!Scope::default_candidates(c).contains(&Term::Alphadot));
        }
    }
}
