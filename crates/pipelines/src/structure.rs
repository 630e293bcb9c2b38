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
use crate::record::RecordError;
use aeroident_estimators::structure::{
    self, Candidates, Ranking, Selection, StepwiseConfig, StructureError,
};
use aeroident_estimators::{AirDataSample, AlphaKnots, Coefficient, Term};
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
    /// Each offered candidate not kept, with its partial F were it added to the final model
    /// (`None`: the model already explains it, a collinear term) and the offered parent it
    /// waited for, if one is not in the model (the hierarchy).
    pub left_out: Vec<(Term, Option<f64>, Option<Term>)>,
}

/// The offered candidates (`c`'s first `offered`) not in `fit`, each with its partial F when
/// added to it: why each term was left out, not only the last one tried.
fn left_out(
    c: &Candidates,
    offered: usize,
    fit: &structure::Fit,
    terms: &[Term],
) -> Vec<(Term, Option<f64>, Option<Term>)> {
    let kept = |t: &Term| fit.terms.iter().any(|&k| terms[k] == *t);
    let offered_terms = &terms[..offered];
    (0..offered)
        .filter(|j| !fit.terms.contains(j))
        .map(|j| {
            let mut trial = fit.terms.clone();
            trial.push(j);
            trial.sort_unstable();
            let f = structure::fit(c, &trial)
                .partial_f(trial.iter().position(|&t| t == j).unwrap_or(0));
            let waiting = terms[j].parents().iter().find(|p| offered_terms.contains(p) && !kept(p));
            (terms[j], f.is_finite().then_some(f), waiting.copied())
        })
        .collect()
}

impl CoefficientSelection {
    /// The kept terms, in candidate order.
    pub fn kept(&self) -> Vec<Term> {
        self.selection.fit.terms.iter().map(|&k| self.candidates[k]).collect()
    }
}

/// Selects `coefficient`'s terms among `candidates` on `manoeuvres`; the spline candidates
/// take their knots from `knots`.
///
/// # Errors
/// A candidate that is the constant or listed twice, no candidate, a candidate no sample can
/// evaluate, or [`StructureError`]s (too few samples), each naming the coefficient.
pub fn select_on_samples(
    manoeuvres: &[&[AirDataSample]],
    coefficient: Coefficient,
    candidates: &[Term],
    knots: &AlphaKnots,
    method: Method,
) -> Result<CoefficientSelection, String> {
    let who = coefficient.name();
    check_candidates(candidates).map_err(|e| format!("{who}: {e}"))?;
    let offered = candidates.len();
    let candidates = &with_parents(candidates);
    let mut rows = Vec::new();
    let mut z = Vec::new();
    let mut skipped = 0;
    let mut lengths = Vec::new();
    for m in manoeuvres {
        let before = z.len();
        for s in m.iter() {
            let y = s.measured_coefficients()[coefficient.index()];
            let x: Option<Vec<f64>> = candidates.iter().map(|t| t.value(s, knots)).collect();
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
            .filter(|t| first.is_some_and(|s| t.value(s, knots).is_none()))
            .map(|t| t.name())
            .collect();
        let measured = first.and_then(|s| s.measured_coefficients()[coefficient.index()]);
        return Err(if measured.is_none() {
            format!(
                "{who}: the record does not measure it: it {} (see the mapping)",
                crate::record::needs::coefficient_needs(coefficient)
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
    // The parents not offered are not selected, only kept beside a child.
    let offered = Candidates {
        names: c.names[..offered].to_vec(),
        columns: c.columns.columns(0, offered).into_owned(),
        z: c.z.clone(),
    };
    // A power or product term is offered once its offered parents are in the model.
    let parents: Vec<Vec<usize>> = candidates[..offered.names.len()]
        .iter()
        .map(|t| {
            let here = |p: &Term| candidates[..offered.names.len()].iter().position(|c| c == p);
            t.parents().iter().filter_map(here).collect()
        })
        .collect();
    let mut selection = run(&offered, method, &parents).map_err(|e| format!("{who}: {e}"))?;
    selection.names.clone_from(&c.names);
    let selection = keep_hierarchy(&c, candidates, selection);
    let std_error_coloured = structure::coloured_std_error(&c, &selection.fit, &lengths);
    let left_out = left_out(&c, offered.names.len(), &selection.fit, candidates);
    Ok(CoefficientSelection {
        coefficient,
        candidates: candidates.to_vec(),
        selection,
        std_error_coloured,
        samples: c.z.len(),
        skipped,
        left_out,
    })
}

/// `candidates` with the parents of each power or product term among them ([`Term::parents`];
/// appended after the given ones, never offered to the selection itself), so that the
/// hierarchy can be kept.
fn with_parents(candidates: &[Term]) -> Vec<Term> {
    let mut out = candidates.to_vec();
    for t in candidates {
        for p in t.parents() {
            if !out.contains(p) {
                out.push(*p);
            }
        }
    }
    out
}

/// `selection` with every parent of a kept power or product term kept too ([`Term::parents`],
/// the model hierarchy), refitted; the terms added are named in its `stopped` reason.
fn keep_hierarchy(c: &Candidates, candidates: &[Term], mut selection: Selection) -> Selection {
    let mut terms = selection.fit.terms.clone();
    let mut added = Vec::new();
    for &k in &selection.fit.terms {
        for p in candidates[k].parents() {
            if let Some(j) = candidates.iter().position(|t| t == p)
                && !terms.contains(&j)
            {
                terms.push(j);
                added.push(format!("{} (parent of {})", p.name(), candidates[k].name()));
            }
        }
    }
    if added.is_empty() {
        return selection;
    }
    terms.sort_unstable();
    selection.fit = structure::fit(c, &terms);
    selection.stopped =
        format!("{}; kept for the model hierarchy: {}", selection.stopped, added.join(", "));
    selection
}

fn run(
    c: &Candidates,
    method: Method,
    parents: &[Vec<usize>],
) -> Result<Selection, StructureError> {
    match method {
        Method::Stepwise(config) => structure::stepwise_in_hierarchy(c, config, parents),
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
/// differentiator window, the record's own sample interval, spline knots at the α quantiles,
/// [`alpha_quantile_knots`]).
///
/// # Errors
/// Reading errors, no usable samples, and [`select_on_samples`]'s ([`RecordError::Model`]).
pub fn select_structure<R: Read>(
    reader: FlightDataReader<R>,
    coefficients: &[Coefficient],
    candidates: &[Term],
    method: Method,
) -> Result<Vec<CoefficientSelection>, RecordError> {
    let (rec, first) = read_for_selection(vec![reader], None, &[])?;
    let supplied = to_supply(&Wanted { coefficients, candidates }, &first);
    let rec = condition(&rec, supplied, DIFF_WINDOW, None)?;
    let slices = rec.slices();
    let knots = alpha_quantile_knots(&slices, candidates).map_err(RecordError::Model)?;
    coefficients
        .iter()
        .map(|&c| {
            select_on_samples(&slices, c, candidates, &knots, method).map_err(RecordError::Model)
        })
        .collect()
}

/// The knots of the spline candidates among `candidates` (as many as the highest spline term
/// listed: `alpha_k3` asks for three): at the α quantiles `i/(n + 1)`, `i = 1 … n`, of every
/// sample of `manoeuvres`, so that each interval between knots holds the same share of the
/// data (Klein & Morelli 2006 §5.4 place spline knots where the data are; the order statistic
/// `⌊q (N − 1)⌋` of the sorted α is taken, no interpolation). No knot when no spline is listed.
///
/// # Errors
/// No sample, or α that does not spread over `n + 1` distinct values at those quantiles.
pub fn alpha_quantile_knots(
    manoeuvres: &[&[AirDataSample]],
    candidates: &[Term],
) -> Result<AlphaKnots, String> {
    let n = candidates.iter().filter_map(|t| t.knot()).max().map_or(0, |i| i + 1);
    if n == 0 {
        return Ok(AlphaKnots::NONE);
    }
    let mut alpha: Vec<f64> =
        manoeuvres.iter().flat_map(|m| m.iter().map(|s| s.alpha_rad)).collect();
    if alpha.is_empty() {
        return Err("no sample to place the α knots on".into());
    }
    alpha.sort_by(f64::total_cmp);
    let last = alpha.len() - 1;
    let knots: Vec<f64> =
        (1..=n).map(|i| alpha[(i as f64 / (n as f64 + 1.0) * last as f64) as usize]).collect();
    AlphaKnots::new(&knots).map_err(|e| {
        format!(
            "cannot place {n} α knot(s) at the α quantiles ({}°): {e}; the record's α spans {:.3}° to {:.3}°",
            knots.iter().map(|k| format!("{:.3}", k.to_degrees())).collect::<Vec<_>>().join(", "),
            alpha[0].to_degrees(),
            alpha[last].to_degrees()
        )
    })
}

/// Checks that every knot of `structure` lies inside the α range of `manoeuvres`: a knot
/// outside it makes its spline term zero on every sample, or equal to `α − k`, which the
/// constant and `alpha` already span, so its parameter could not be identified.
///
/// # Errors
/// The first knot outside the range, with the range, naming `model` (the model file).
pub fn check_knots_in_range(
    structure: &aeroident_estimators::ModelStructure,
    manoeuvres: &[&[AirDataSample]],
    model: &str,
) -> Result<(), String> {
    let knots = structure.knots();
    if knots.is_empty() {
        return Ok(());
    }
    let alpha = manoeuvres.iter().flat_map(|m| m.iter().map(|s| s.alpha_rad));
    let (lo, hi) = alpha.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), a| (l.min(a), h.max(a)));
    for (i, k) in knots.as_slice().iter().enumerate() {
        if !(lo < *k && *k < hi) {
            return Err(format!(
                "{model}: α knot {} ({:.3}°) lies outside the record's α range {:.3}° to {:.3}°: its spline term `{}` could not be identified",
                i + 1,
                k.to_degrees(),
                lo.to_degrees(),
                hi.to_degrees(),
                Term::spline(i).map_or("", |t| t.name())
            ));
        }
    }
    Ok(())
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
) -> Result<(crate::record::Manoeuvres, AirDataSample), RecordError> {
    let file = readers.first().map_or(String::new(), |r| r.file().to_string());
    let screen = Some(crate::record::outliers::SpikeScreen::default());
    let rec = crate::record::read_records(readers, screen, compat, windows)?;
    let first = rec.manoeuvres.iter().flatten().next().copied().ok_or_else(|| {
        RecordError::Model(format!("{file}: no usable sample to select a structure on"))
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
    rec: &crate::record::Manoeuvres,
    supplied: Vec<Derivative>,
    diff_window: usize,
    nominal_dt_s: Option<f64>,
) -> Result<Conditioned, RecordError> {
    let diff_err = |e: aeroident_signals::differentiate::DifferentiateError| RecordError::Option {
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

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::AircraftConstants;
    use aeroident_estimators::structure::StepwiseConfig;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    const BREAK_DEG: f64 = 8.0;

    /// The model hierarchy: `z = 3 α²` over α in [0.1, 0.3] rad, with a small deterministic
    /// noise, is fitted by `alpha2` alone, and stepwise regression stops there; the kept model has `alpha` beside it
    /// (refitted to ≈ 0, `alpha2` still 3), and the reason names the parent. A parent never
    /// offered is offered.
    #[test]
    fn a_power_term_keeps_its_parent() {
        let candidates = with_parents(&[Term::Alpha2]);
        assert_eq!(candidates, [Term::Alpha2, Term::Alpha]);
        let alpha: Vec<f64> = (0..200).map(|i| 0.1 + 0.001 * i as f64).collect();
        let mut rows = Vec::new();
        for a in &alpha {
            rows.extend([a * a, *a]);
        }
        let c = Candidates {
            names: vec!["alpha2".into(), "alpha".into()],
            columns: DMatrix::from_row_slice(alpha.len(), 2, &rows),
            z: DVector::from_iterator(
                alpha.len(),
                alpha.iter().enumerate().map(|(i, a)| 3.0 * a * a + 1e-3 * (37.0 * i as f64).sin()),
            ),
        };
        let plain = structure::stepwise(&c, StepwiseConfig::default()).unwrap();
        assert_eq!(plain.fit.terms, [0], "{:?}", plain.stopped);
        let kept = keep_hierarchy(&c, &candidates, plain);
        assert_eq!(kept.fit.terms, [0, 1]);
        let (alpha2, alpha) = (kept.fit.theta[0], kept.fit.theta[1]);
        assert!((alpha2 - 3.0).abs() < 0.2 && alpha.abs() < 0.1, "{:?}", kept.fit.theta);
        assert!(kept.stopped.ends_with("kept for the model hierarchy: alpha (parent of alpha2)"));
    }

    /// 40 s at 50 Hz of a record whose lift slope breaks at 8°: `CL = 0.2 + 4.5 α + 6 q̂ +
    /// 0.4 δe + dcla (α − 8°)₊` plus white noise of σ 0.01, `CD = 0.05 + 0.5 α²`, written
    /// into the specific forces (q̄S/m = 50 m/s²) so that the measured coefficients read them
    /// back. α swings 8° ± 8.5° about the break, symmetrically (its median is 8°).
    fn slope_break(dcla: f64, seed: u64) -> Vec<AirDataSample> {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let noise = Normal::new(0.0, 0.01).unwrap();
        let tau = std::f64::consts::TAU;
        (0..2000)
            .map(|i| {
                let t = i as f64 / 50.0;
                let alpha =
                    (BREAK_DEG + 7.0 * (tau * t / 10.0).sin() + 1.5 * (tau * t / 1.3).sin())
                        .to_radians();
                let q = 0.1 * (tau * t / 2.1).sin();
                let de = 2f64.to_radians() * (tau * t / 2.7).sin();
                let qhat = q * 2.0 / 200.0;
                let cl = 0.2
                    + 4.5 * alpha
                    + 6.0 * qhat
                    + 0.4 * de
                    + dcla * (alpha - BREAK_DEG.to_radians()).max(0.0)
                    + noise.sample(&mut rng);
                let cd = 0.05 + 0.5 * alpha * alpha;
                let (sa, ca) = alpha.sin_cos();
                let (cx, cz) = (-cd * ca + cl * sa, -cl * ca - cd * sa);
                AirDataSample {
                    t_s: t,
                    vt_mps: 100.0,
                    alpha_rad: alpha,
                    qbar_pa: 5000.0,
                    q_rad_s: Some(q),
                    de_rad: Some(de),
                    ax_mps2: Some(50.0 * cx),
                    az_mps2: Some(50.0 * cz),
                    constants: AircraftConstants {
                        mass_kg: 1000.0,
                        S_m2: 10.0,
                        cbar_m: Some(2.0),
                        ..Default::default()
                    },
                    ..Default::default()
                }
            })
            .collect()
    }

    const SWR: Method = Method::Stepwise(StepwiseConfig { f_in: 20.0, f_out: 20.0 });

    /// Stepwise regression keeps the spline of a lift slope that breaks at its knot and
    /// recovers the slope change within 3σ on five records, with the knot given (8°) or
    /// placed at the record's α median (the one-knot quantile); on records without a break the
    /// spline is left out.
    #[test]
    fn stepwise_selects_the_spline_of_a_slope_break_and_recovers_it() {
        let candidates = [Term::Alpha, Term::Q, Term::De, Term::AlphaK1];
        for seed in 0..5 {
            let rec = slope_break(-2.0, seed);
            let slices = [rec.as_slice()];
            let quantile = alpha_quantile_knots(&slices, &candidates).unwrap();
            let median = quantile.get(0).unwrap().to_degrees();
            assert!((median - BREAK_DEG).abs() < 0.3, "median knot {median}°");
            let given = AlphaKnots::new(&[BREAK_DEG.to_radians()]).unwrap();
            for knots in [given, quantile] {
                let sel =
                    select_on_samples(&slices, Coefficient::CL, &candidates, &knots, SWR).unwrap();
                assert_eq!(sel.kept(), candidates, "seed {seed}, knot {:?}", knots.as_slice());
                let fit = &sel.selection.fit;
                let (v, s) = (fit.theta[3], fit.std_error[3]);
                let tolerance = if knots == given { 3.0 * s } else { 3.0 * s + 0.1 };
                assert!((v + 2.0).abs() < tolerance, "seed {seed}: ΔCL_alpha {v} ± {s}");
            }
            let flat = slope_break(0.0, seed);
            let sel = select_on_samples(&[&flat], Coefficient::CL, &candidates, &given_knot(), SWR)
                .unwrap();
            assert!(!sel.kept().contains(&Term::AlphaK1), "seed {seed}: {:?}", sel.kept());
        }
    }

    fn given_knot() -> AlphaKnots {
        AlphaKnots::new(&[BREAK_DEG.to_radians()]).unwrap()
    }

    /// `alpha_k2` asks for two knots at the α terciles, ascending; a record of one α cannot
    /// place them; a knot outside the record's α is refused naming the model and the term.
    #[test]
    fn quantile_knots_and_knots_outside_the_record() {
        let rec = slope_break(-2.0, 1);
        let slices = [rec.as_slice()];
        let k = alpha_quantile_knots(&slices, &[Term::AlphaK2, Term::Alpha]).unwrap();
        let mut alpha: Vec<f64> = rec.iter().map(|s| s.alpha_rad).collect();
        alpha.sort_by(f64::total_cmp);
        let below = |x: f64| alpha.iter().filter(|a| **a < x).count() as f64 / alpha.len() as f64;
        assert_eq!(k.len(), 2);
        assert!((below(k.get(0).unwrap()) - 1.0 / 3.0).abs() < 0.01);
        assert!((below(k.get(1).unwrap()) - 2.0 / 3.0).abs() < 0.01);
        assert_eq!(alpha_quantile_knots(&slices, &[Term::Alpha]).unwrap().len(), 0);
        let constant: Vec<AirDataSample> =
            rec.iter().map(|s| AirDataSample { alpha_rad: 0.1, ..*s }).collect();
        let e = alpha_quantile_knots(&[&constant], &[Term::AlphaK1, Term::AlphaK2]).unwrap_err();
        assert!(e.contains("cannot place 2 α knot(s)") && e.contains("not above"), "{e}");
        let st = aeroident_estimators::ModelStructure::longitudinal()
            .with(Coefficient::CL, &[Term::AlphaK1])
            .with_knots(AlphaKnots::new(&[30f64.to_radians()]).unwrap());
        let e = check_knots_in_range(&st, &slices, "m.toml").unwrap_err();
        assert!(
            e.starts_with("m.toml: α knot 1 (30.000°) lies outside the record's α range"),
            "{e}"
        );
        assert!(e.contains("alpha_k1"), "{e}");
        let inside = st.with_knots(given_knot());
        assert!(check_knots_in_range(&inside, &slices, "m.toml").is_ok());
    }
}
