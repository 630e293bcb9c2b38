//! Model structure determination of a record: for each coefficient, which candidate terms the
//! measured coefficient needs, by equation error (stepwise regression or multivariate
//! orthogonal functions, [`aeroident_estimators::structure`]).
//!
//! The measured coefficients are those of [`AirDataSample::measured_coefficients`] (forces and
//! moments from the accelerations and angular accelerations); a sample where the coefficient
//! or a candidate is not measured is left out of that coefficient's selection and counted.

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
    for s in manoeuvres.iter().flat_map(|m| m.iter()) {
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
    if z.is_empty() {
        let first = manoeuvres.iter().flat_map(|m| m.iter()).next();
        let missing: Vec<&str> = candidates
            .iter()
            .filter(|t| first.is_some_and(|s| t.value(s).is_none()))
            .map(|t| t.name())
            .collect();
        return Err(format!(
            "{who}: no sample has the coefficient and every candidate measured (missing in the first sample: {})",
            if missing.is_empty() { "the coefficient".to_string() } else { missing.join(", ") }
        ));
    }
    let c = Candidates {
        names: candidates.iter().map(|t| t.name().to_string()).collect(),
        columns: DMatrix::from_row_slice(z.len(), candidates.len(), &rows),
        z: DVector::from_vec(z),
    };
    let selection = run(&c, method).map_err(|e| format!("{who}: {e}"))?;
    Ok(CoefficientSelection {
        coefficient,
        candidates: candidates.to_vec(),
        selection,
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

/// Reads the record (split at its gaps, spikes screened, as the batch fits read it) and selects
/// each of `coefficients`' terms among `candidates`.
///
/// # Errors
/// Reading errors, no usable samples, and [`select_on_samples`]'s ([`ReplayError::Model`]).
pub fn select_structure<R: Read>(
    reader: FlightDataReader<R>,
    coefficients: &[Coefficient],
    candidates: &[Term],
    method: Method,
) -> Result<Vec<CoefficientSelection>, ReplayError> {
    let rec = crate::replay::batch::read_manoeuvres(reader, None, &[])?;
    let slices: Vec<&[AirDataSample]> = rec.manoeuvres.iter().map(Vec::as_slice).collect();
    coefficients
        .iter()
        .map(|&c| select_on_samples(&slices, c, candidates, method).map_err(ReplayError::Model))
        .collect()
}
