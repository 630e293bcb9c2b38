//! Model structure determination of a record: for each coefficient, which candidate terms the
//! measured coefficient needs, by equation error (stepwise regression or multivariate
//! orthogonal functions, [`aeroident_estimators::structure`]).
//!
//! The measured coefficients are those of [`AirDataSample::measured_coefficients`] (forces and
//! moments from the accelerations and angular accelerations); a sample where the coefficient
//! or a candidate is not measured is left out of that coefficient's selection and counted.

mod auto;
pub use auto::{
    AutoModel, AutoSelection, CoefficientReport, EquationErrorEstimate, PathStep, SAMPLES_PER_TERM,
    Scope, StructureReport, model_from_args, select_model,
};

use crate::condition::{Alignment, Conditioner, Conditioning, Derivative};
use crate::replay::ReplayError;
use aeroident_estimators::structure::{
    self, Candidates, Ranking, Selection, StepwiseConfig, StructureError,
};
use aeroident_estimators::{AirDataSample, Coefficient, Term};
use aeroident_io::FlightDataReader;
use nalgebra::{DMatrix, DVector};
use std::io::Read;

/// How the terms are chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Stepwise regression with partial-F cut-offs (SIDPAC `swr`).
    Stepwise(StepwiseConfig),
    /// Multivariate orthogonal functions stopped at the PSE minimum (SIDPAC `offit`).
    Orthogonal(Ranking),
}

impl Method {
    /// `swr` (stepwise regression, SIDPAC's cut-off) or `mof` (orthogonal functions, SIDPAC
    /// `offit`'s ranking).
    ///
    /// # Errors
    /// Another name, listing the two.
    pub fn from_name(name: &str) -> Result<Self, String> {
        match name {
            "swr" => Ok(Method::Stepwise(StepwiseConfig::default())),
            "mof" => Ok(Method::Orthogonal(Ranking::Generation)),
            _ => Err(format!("unknown selection method `{name}` (swr or mof)")),
        }
    }

    /// `swr` or `mof`, as the summary names it.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Stepwise(_) => "swr",
            Method::Orthogonal(_) => "mof",
        }
    }
}

/// The selection of one coefficient's terms.
#[derive(Debug, Clone)]
pub struct CoefficientSelection {
    /// The coefficient.
    pub coefficient: Coefficient,
    /// The candidates offered, in the order given (the constant is always in the model).
    pub candidates: Vec<Term>,
    /// The selection (path, kept candidates, fit).
    pub selection: Selection,
    /// The final fit's standard errors corrected for coloured residuals
    /// ([`structure::coloured_std_error`]), as `selection.fit.std_error`; `None` when the
    /// correction could not be formed.
    pub std_error_coloured: Option<Vec<f64>>,
    /// Samples used.
    pub samples: usize,
    /// Samples left out (coefficient or a candidate not measured).
    pub skipped: usize,
}

impl CoefficientSelection {
    /// The kept terms, in candidate order.
    pub fn kept(&self) -> Vec<Term> {
        self.selection.fit.terms.iter().map(|&k| self.candidates[k]).collect()
    }
}

/// Selects `coefficient`'s terms among `candidates` on `manoeuvres`.
///
/// # Errors
/// A candidate that is the constant or listed twice, no candidate, a candidate no sample can
/// evaluate, or [`StructureError`]s (too few samples), each naming the coefficient.
pub fn select_on_samples(
    manoeuvres: &[&[AirDataSample]],
    coefficient: Coefficient,
    candidates: &[Term],
    method: Method,
) -> Result<CoefficientSelection, String> {
    let who = coefficient.name();
    check_candidates(candidates).map_err(|e| format!("{who}: {e}"))?;
    let mut rows = Vec::new();
    let mut z = Vec::new();
    let mut skipped = 0;
    let mut lengths = Vec::new();
    for m in manoeuvres {
        let before = z.len();
        for s in m.iter() {
            let y = s.measured_coefficients()[coefficient.index()];
            let x: Option<Vec<f64>> = candidates.iter().map(|t| t.value(s)).collect();
            match (y, x) {
                (Some(y), Some(x)) if y.is_finite() => {
                    rows.extend(x);
                    z.push(y);
                }
                _ => skipped += 1,
            }
        }
        if z.len() > before {
            lengths.push(z.len() - before);
        }
    }
    if z.is_empty() {
        let first = manoeuvres.iter().flat_map(|m| m.iter()).next();
        let missing: Vec<&str> = candidates
            .iter()
            .filter(|t| first.is_some_and(|s| t.value(s).is_none()))
            .map(|t| t.name())
            .collect();
        let measured = first.and_then(|s| s.measured_coefficients()[coefficient.index()]);
        return Err(if measured.is_none() {
            format!(
                "{who}: the record does not measure it: it {} (see the mapping)",
                crate::replay::coefficient_needs(coefficient)
            )
        } else {
            format!(
                "{who}: no sample has every candidate measured (missing in the first sample: {})",
                missing.join(", ")
            )
        });
    }
    let c = Candidates {
        names: candidates.iter().map(|t| t.name().to_string()).collect(),
        columns: DMatrix::from_row_slice(z.len(), candidates.len(), &rows),
        z: DVector::from_vec(z),
    };
    let selection = run(&c, method).map_err(|e| format!("{who}: {e}"))?;
    let std_error_coloured = structure::coloured_std_error(&c, &selection.fit, &lengths);
    Ok(CoefficientSelection {
        coefficient,
        candidates: candidates.to_vec(),
        selection,
        std_error_coloured,
        samples: c.z.len(),
        skipped,
    })
}

fn run(c: &Candidates, method: Method) -> Result<Selection, StructureError> {
    match method {
        Method::Stepwise(config) => structure::stepwise(c, config),
        Method::Orthogonal(ranking) => structure::orthogonal(c, ranking).map(|o| o.selection),
    }
}

fn check_candidates(candidates: &[Term]) -> Result<(), String> {
    if candidates.is_empty() {
        return Err("no candidate term".into());
    }
    for (k, t) in candidates.iter().enumerate() {
        if *t == Term::Bias {
            return Err("the constant is always in the model; it is not a candidate".into());
        }
        if candidates[..k].contains(t) {
            return Err(format!("candidate `{}` listed twice", t.name()));
        }
    }
    Ok(())
}

/// Reads the record and selects each of `coefficients`' terms among `candidates`, as
/// [`select_model`] does for `--model auto` (the same reading and conditioning, default
/// differentiator window, the record's own sample interval).
///
/// # Errors
/// Reading errors, no usable samples, and [`select_on_samples`]'s ([`ReplayError::Model`]).
pub fn select_structure<R: Read>(
    reader: FlightDataReader<R>,
    coefficients: &[Coefficient],
    candidates: &[Term],
    method: Method,
) -> Result<Vec<CoefficientSelection>, ReplayError> {
    let (rec, first) = read_for_selection(vec![reader], None, &[])?;
    let supplied = to_supply(&Wanted { coefficients, candidates }, &first);
    let rec = condition(&rec, supplied, DIFF_WINDOW, None)?;
    let slices = rec.slices();
    coefficients
        .iter()
        .map(|&c| select_on_samples(&slices, c, candidates, method).map_err(ReplayError::Model))
        .collect()
}

/// The differentiator window of [`select_structure`], samples: the replay's default.
pub const DIFF_WINDOW: usize = 5;

/// What a selection needs from the record: the coefficients (`q̇` for `Cm`, `ṗ` and `ṙ` for
/// `Cl` and `Cn`) and the candidates (`α̇` for `alphadot`).
struct Wanted<'a> {
    coefficients: &'a [Coefficient],
    candidates: &'a [Term],
}

impl Wanted<'_> {
    fn needs(&self, d: Derivative) -> bool {
        let has = |c| self.coefficients.contains(&c);
        match d {
            Derivative::Qdot => has(Coefficient::Cm),
            Derivative::Pdot | Derivative::Rdot => has(Coefficient::Cl) || has(Coefficient::Cn),
            Derivative::Alphadot => self.candidates.contains(&Term::Alphadot),
        }
    }
}

/// A record read for a selection: its manoeuvres with the derivatives supplied.
struct Conditioned {
    manoeuvres: Vec<Vec<AirDataSample>>,
    supplied: Vec<Derivative>,
    read: usize,
}

impl Conditioned {
    fn slices(&self) -> Vec<&[AirDataSample]> {
        self.manoeuvres.iter().map(Vec::as_slice).collect()
    }

    fn first(&self) -> Option<&AirDataSample> {
        self.manoeuvres.iter().flatten().next()
    }
}

/// Reads the records as the batch fits read them (split at gaps, spikes screened, `compat`
/// and `windows` applied); the samples read and the first usable one.
fn read_for_selection<R: Read>(
    readers: Vec<FlightDataReader<R>>,
    compat: Option<&crate::compat::Corrections>,
    windows: &[crate::window::TimeWindow],
) -> Result<(crate::replay::batch::Manoeuvres, AirDataSample), ReplayError> {
    let file = readers.first().map_or(String::new(), |r| r.file().to_string());
    let screen = Some(crate::replay::outliers::SpikeScreen::default());
    let rec = crate::replay::batch::read_records(readers, screen, compat, windows)?;
    let first = rec.manoeuvres.iter().flatten().next().copied().ok_or_else(|| {
        ReplayError::Model(format!("{file}: no usable sample to select a structure on"))
    })?;
    Ok((rec, first))
}

/// The derivatives `wanted` needs that the record lacks (judged on its `first` sample).
fn to_supply(wanted: &Wanted, first: &AirDataSample) -> Vec<Derivative> {
    Derivative::ALL
        .into_iter()
        .filter(|&d| wanted.needs(d) && d.recorded(first).is_none() && d.source(first).is_some())
        .collect()
}

/// Supplies the derivatives `wanted` needs and the record lacks through the conditioning stage
/// with the matched smoother ([`Alignment::Matched`]: both sides of the regression see the
/// same filter); only then are the other channels smoothed. The first and last `(N−1)/2`
/// samples of each manoeuvre get no centred derivative and are left out.
fn condition(
    rec: &crate::replay::batch::Manoeuvres,
    supplied: Vec<Derivative>,
    diff_window: usize,
    nominal_dt_s: Option<f64>,
) -> Result<Conditioned, ReplayError> {
    let diff_err = |e: aeroident_signals::differentiate::DifferentiateError| ReplayError::Option {
        option: "diff-window",
        reason: e.to_string(),
    };
    let mut manoeuvres = Vec::with_capacity(rec.manoeuvres.len());
    for m in &rec.manoeuvres {
        let mut stage = Conditioner::new(Conditioning {
            derivatives: supplied.clone(),
            window: diff_window,
            nominal_dt_s,
            alignment: Alignment::Matched,
        });
        let (mut ready, mut unused) = (Vec::new(), Vec::new());
        for (row, s) in m.iter().enumerate() {
            stage.push(row as u64, *s, &mut ready, &mut unused).map_err(diff_err)?;
        }
        manoeuvres.push(ready.into_iter().map(|(_, s)| s).collect());
    }
    Ok(Conditioned { manoeuvres, supplied, read: rec.read })
}
