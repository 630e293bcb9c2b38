//! Each correction judged on data it was not fitted on: the record's manoeuvres held out in
//! turn (the two halves of a record with one manoeuvre; [`MAX_FOLDS`] folds of consecutive
//! manoeuvres when there are more, "Folds"), the check redone on the others, and each of its
//! corrections applied to the held-out piece, whose initial states alone are then fitted (one
//! per manoeuvre). A correction that raises the held-out pieces' negative log-likelihood, beyond what
//! their noise explains, is one the record does not support, however small its σ: it fitted
//! something of the manoeuvres it was estimated on (a taxi segment, one manoeuvre's odd
//! sensor, a model error of one part of the flight) that the rest of the flight does not
//! share. This is the
//! cross-validation of a model's terms on data not used for their fit, applied to the
//! compatibility check's unknowns.
//!
//! The measure, per correction `c` and held-out piece `k`: `N_k/2 · (ln det R_k(with c) −
//! ln det R_k(without c))`, every other correction of the others' check applied both times and
//! `R_k` the maximum-likelihood residual covariance of piece `k` (over all its samples) with
//! its initial states fitted.
//! Summed over the pieces where the others' check estimated `c`: negative, `c` improves the
//! fit of data it was not fitted on.
//!
//! **When it fails.** The held-out cost has its own noise. Near its optimum the held-out
//! cost is quadratic in the applied value `a` of a correction, `J(a) = J* + ½ Iₖ (a − ĉₖ)²`
//! (in the white-noise units of `N/2 · ln det R`; `ĉₖ` the piece's own best value, `Iₖ` its
//! information with the piece's initial state free), so one more evaluation, at twice the
//! applied value `ĉ` (the others' estimate), measures `Dₖ = J(2ĉ) − 2J(ĉ) + J(0) = Iₖ ĉ²`.
//! Were `ĉ` the truth, the piece's own value would scatter about it with the variance `ρ²/Iₖ`
//! (`ρ` the joint check's reported σ over its Cramér–Rao σ: coloured residuals scatter the
//! estimates by that much more than white noise), and `ĉ` has its own variance `σ₋ₖ²` (the
//! others' reported σ): the change `J(ĉ) − J(0)` then has the mean `½ Iₖ σ₋ₖ² − Dₖ/2` and the
//! variance `ρ² Dₖ + ρ² Iₖ σ₋ₖ² + ½ (Iₖ σ₋ₖ²)²`, summed over the pieces into
//! [`HeldOutCorrection::expected`] and the square of [`HeldOutCorrection::spread`]. A
//! correction **fails** when it does not improve the held-out data (the change is positive)
//! and falls short of what it would do there were it true by more than [`FAIL_SPREADS`]
//! spreads (three: see that constant): the rest of the record contradicts it beyond the
//! noise. A positive change alone is not enough: a correction a few σ from none raises the
//! held-out cost by chance often
//! (measured: the yaw gyro's scale factor on the simulated AHRS-lag record, 3.75 σ, +5.2 on
//! halves; refusing it moved the filter-error method's Cl_p from −7 % to +12 % of the truth).
//! The piece's own information matters: a gyro bias shows as a ramp in the attitude, and a
//! half with its own initial state holds a quarter of the ramp's information, not a half.
//! Where the held-out cost shows no curvature along a correction (`Dₖ` ≤ 0: between 0 and
//! `2ĉ` it has no minimum near `ĉ`), the expectation is `0 ± 0` and any rise fails: the two
//! spurious α shifts measured (one manoeuvre's vane lag spread over three) failed that way,
//! with +4,506 and +1,420.
//!
//! **Folds.** Holding out each manoeuvre in turn redoes the whole check once per manoeuvre,
//! which is quadratic in the manoeuvres: an 80-minute flight's 105 windows took longer than
//! the joint check by a hundredfold. With more than [`MAX_FOLDS`] manoeuvres they are grouped
//! into that many folds ([`folds`]), each held out in turn as one piece: the check is redone
//! [`MAX_FOLDS`] times whatever the flight's length. With at most that many, each manoeuvre is
//! its own fold and nothing changes. A fold is one data set with several initial states; the
//! statistics above hold for it as they are: `Iₖ` is the fold's information along the
//! correction with all its initial states free, `Dₖ` is measured on the fold's own cost, and
//! the folds are disjoint data, so their changes add and their variances add as the pieces'
//! did. What changes is what is held out: a fifth of the flight at once rather than one
//! manoeuvre, so a correction that only one manoeuvre needs is contradicted by the other
//! manoeuvres of its fold as well as by the other folds' check.
//!
//! The folds are contiguous in time (consecutive manoeuvres in the order given, the record's),
//! not dealt round-robin: what the judgement is for is a correction that fits something of one
//! part of the flight (a taxi segment, one phase's sensor or model error) that the rest does
//! not share. Dealt round-robin, every fold's neighbours in time would be in the others' check,
//! which would fit such a part of the flight from them and carry it to the held-out fold; held
//! out together, the part must be predicted from the rest of the flight, as when the
//! corrections are applied to another flight.

use super::{
    CompatConfig, CompatResult, MIN_SAMPLES, Problem, SIDESLIP_PINNED_NOTE, Unknown, check_warm,
    wings_level_without_ay,
};
use crate::EstimatorError;
use crate::sample::AirDataSample;
use core::ops::Range;

/// One correction's judgement on held-out data ([`held_out`]).
#[derive(Debug, Clone, PartialEq)]
pub struct HeldOutCorrection {
    /// The correction: a bias, scale factor, time shift or the AHRS lag.
    pub unknown: Unknown,
    /// Over the held-out pieces where the other pieces' check estimated it, the change of the
    /// held-out negative log-likelihood `N/2 · ln det R` when it is applied (module doc);
    /// negative: it improves the fit of data it was not fitted on.
    pub change: f64,
    /// The pieces it was judged on (0: not judged).
    pub pieces: usize,
    /// The mean of [`HeldOutCorrection::change`] were the others' value of the correction
    /// the truth, from each piece's measured curvature (module doc, "When it fails").
    pub expected: f64,
    /// Its standard deviation then (module doc, "When it fails").
    pub spread: f64,
}

impl HeldOutCorrection {
    /// Whether it was judged and failed: applying it raised the held-out cost, and by more
    /// than [`FAIL_SPREADS`] spreads above what a true correction would do.
    pub fn fails(&self) -> bool {
        fails(self.change, self.expected, self.spread, self.pieces)
    }
}

/// The failure rule of a held-out `change` whose mean and standard deviation were the
/// correction true are `expected` and `spread`, over `pieces` pieces (module doc, "When it
/// fails"): judged, a rise above [`MIN_FAILING_RISE`], and more than [`FAIL_SPREADS`] spreads
/// above `expected`.
pub fn fails(change: f64, expected: f64, spread: f64, pieces: usize) -> bool {
    pieces > 0 && change > MIN_FAILING_RISE && change - expected > FAIL_SPREADS * spread
}

/// The smallest held-out rise that can fail, in the units of `N/2 · ln det R`: half the 95 %
/// point of χ² with one degree of freedom (3.841 / 2), the likelihood-ratio test of one
/// parameter. Below it the held-out data cannot tell the correction from none whatever its
/// expectation; where that expectation is `0 ± 0` (no curvature, module doc) the rule would
/// otherwise refuse a correction on any rise at all, rounding included.
pub const MIN_FAILING_RISE: f64 = 3.841_458_820_694_124 / 2.0;

/// A correction fails when its held-out change lies more than this many spreads above its
/// expectation (module doc, "When it fails"). Three, not two: the spread leaves out the
/// errors of the other corrections applied with it, which move the piece's own best value
/// too; over 40 simulated records per case, the change of a true gyro bias scattered 1.8
/// times its spread at 4 σ from none and 1.4 times at 64 σ
/// (`compat::tests::the_held_out_change_of_a_true_correction_scatters_as_expected`), so three
/// spreads are about two of its standard deviations.
pub const FAIL_SPREADS: f64 = 3.0;

/// What one held-out piece says of one correction (module doc, "When it fails").
#[derive(Debug, Clone, Copy)]
struct PieceJudgement {
    /// `J(ĉ) − J(0)`.
    change: f64,
    /// `Dₖ = J(2ĉ) − 2J(ĉ) + J(0)`, floored at 0.
    curvature: f64,
    /// `Iₖ σ₋ₖ²`: the others' estimation variance in the piece's information (0 where `ĉ` = 0).
    others: f64,
}

impl HeldOutCorrection {
    /// Adds piece `j`'s judgement, the joint check's `ρ²` being `rho2`.
    fn add(&mut self, j: PieceJudgement, rho2: f64) {
        self.change += j.change;
        self.expected += 0.5 * j.others - 0.5 * j.curvature;
        let own = rho2 * (j.curvature + j.others);
        let variance = self.spread * self.spread + own + 0.5 * j.others * j.others;
        self.spread = variance.sqrt();
        self.pieces += 1;
    }
}

/// The held-out judgement of a check's corrections ([`held_out`]).
#[derive(Debug, Clone, PartialEq)]
pub struct HeldOut {
    /// What was held out in turn: `manoeuvre` (each manoeuvre), `fold` (each of [`MAX_FOLDS`]
    /// groups of consecutive manoeuvres, when there are more than that; module doc, "Folds") or
    /// `half` (the two halves of a record with one manoeuvre).
    pub by: &'static str,
    /// How many pieces the record was split into (manoeuvres, folds or halves).
    pub pieces: usize,
    /// Per correction of the joint check (its order), the judgement.
    pub corrections: Vec<HeldOutCorrection>,
    /// Pieces that could not be judged, with why.
    pub notes: Vec<String>,
}

/// The note of a record too short to split: nothing is judged.
pub const PIECE_TOO_SHORT: &str = "the record is too short to hold a part out (each piece needs at least 10 samples): its corrections are not judged on held-out data";

/// Judges each correction of `joint` (the check of `manoeuvres` with `config`) on held-out
/// data (module doc).
///
/// # Errors
/// As [`super::check`]'s preparation of the record (a rolling record without `ay`). A piece
/// the check cannot fit is a note, not an error.
pub fn held_out(
    manoeuvres: &[&[AirDataSample]],
    config: &CompatConfig,
    joint: &CompatResult,
) -> Result<HeldOut, EstimatorError> {
    Ok(match wings_level_without_ay(manoeuvres)? {
        Some(planar) => {
            let slices: Vec<&[AirDataSample]> = planar.iter().map(Vec::as_slice).collect();
            held_out_as_given(&slices, config, joint)
        }
        None => held_out_as_given(manoeuvres, config, joint),
    })
}

/// The most pieces a record of several manoeuvres is held out in (module doc, "Folds"): the
/// check is redone once per piece, so this bounds the judgement's cost at that many checks of
/// most of the record. Five, the usual number of folds of cross-validation (Hastie, Tibshirani
/// & Friedman, *The Elements of Statistical Learning*, 2nd ed., 2009, §7.10.1): each check
/// still fits four fifths of the record, and a record of up to five manoeuvres keeps one
/// manoeuvre per piece.
pub const MAX_FOLDS: usize = 5;

/// The folds of `n` manoeuvres (module doc, "Folds"): each manoeuvre alone up to
/// [`MAX_FOLDS`], else that many runs of consecutive manoeuvres whose sizes differ by at most
/// one (the larger last).
pub fn folds(n: usize) -> Vec<Range<usize>> {
    let f = n.min(MAX_FOLDS);
    (0..f).map(|k| k * n / f..(k + 1) * n / f).collect()
}

/// The pieces held out in turn, each a group of manoeuvres: the manoeuvres or their
/// [`folds`], or the two halves of a single one.
fn pieces<'a>(manoeuvres: &[&'a [AirDataSample]]) -> (&'static str, Vec<Vec<&'a [AirDataSample]>>) {
    match manoeuvres {
        [one] => {
            let (a, b) = one.split_at(one.len() / 2);
            ("half", vec![vec![a], vec![b]])
        }
        _ => {
            let by = if manoeuvres.len() > MAX_FOLDS { "fold" } else { "manoeuvre" };
            (by, folds(manoeuvres.len()).into_iter().map(|f| manoeuvres[f].to_vec()).collect())
        }
    }
}

fn held_out_as_given(
    manoeuvres: &[&[AirDataSample]],
    config: &CompatConfig,
    joint: &CompatResult,
) -> HeldOut {
    let (by, pieces) = pieces(manoeuvres);
    let judged: Vec<Unknown> =
        joint.unknowns.iter().copied().filter(|u| !matches!(u, Unknown::Initial { .. })).collect();
    let mut corrections: Vec<HeldOutCorrection> = judged
        .iter()
        .map(|&unknown| HeldOutCorrection {
            unknown,
            change: 0.0,
            pieces: 0,
            expected: 0.0,
            spread: 0.0,
        })
        .collect();
    // ρ² per correction: the reported variance over the Cramér–Rao one (at least 1).
    let rho2: Vec<f64> = judged
        .iter()
        .map(|&u| match (joint.get(u), joint.reported(u)) {
            (Some((_, cr)), Some((_, s))) if cr > 0.0 => (s / cr).powi(2).max(1.0),
            _ => 1.0,
        })
        .collect();
    let mut out = HeldOut { by, pieces: pieces.len(), corrections: Vec::new(), notes: Vec::new() };
    if pieces.iter().flatten().any(|p| p.len() < MIN_SAMPLES) {
        out.notes.push(PIECE_TOO_SHORT.into());
        out.corrections = corrections;
        return out;
    }
    let pinned = joint.notes.iter().any(|n| n == SIDESLIP_PINNED_NOTE);
    // The others' check starts from the joint corrections, near its optimum, rather than from
    // none at the several starts a check of unknown corrections needs.
    let warm: Vec<(Unknown, f64)> =
        judged.iter().filter_map(|&u| joint.get(u).map(|(v, _)| (u, v))).collect();
    let judge = |k: usize| {
        let others: Vec<&[AirDataSample]> = pieces
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != k)
            .flat_map(|(_, p)| p.clone())
            .collect();
        check_warm(&others, config, &warm)
            .and_then(|fitted| piece_changes(&pieces[k], config, &fitted, &judged, pinned))
    };
    // Each piece's check and fits are independent of the others': on a second core the
    // judgement takes half the time. Added up in the pieces' order, as one after another.
    let judgements: Vec<_> = std::thread::scope(|scope| {
        let judge = &judge;
        let running: Vec<_> = (0..pieces.len()).map(|k| scope.spawn(move || judge(k))).collect();
        running
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)))
            .collect()
    });
    for (k, changes) in judgements.into_iter().enumerate() {
        match changes {
            Ok(changes) => {
                for ((c, j), &rho2) in corrections.iter_mut().zip(changes).zip(&rho2) {
                    if let Some(j) = j {
                        c.add(j, rho2);
                    }
                }
            }
            Err(e) => out.notes.push(format!("{by} {} not judged held out: {e}", k + 1)),
        }
    }
    out.corrections = corrections;
    out
}

/// Per correction of `judged`, what held-out `piece` (its manoeuvres) says of it ([`PieceJudgement`], costs of
/// [`PieceFit::cost`]), the others of `fitted` (the check of the other pieces) applied
/// throughout; `None` where `fitted` did not estimate it.
fn piece_changes(
    piece: &[&[AirDataSample]],
    config: &CompatConfig,
    fitted: &CompatResult,
    judged: &[Unknown],
    pinned: bool,
) -> Result<Vec<Option<PieceJudgement>>, EstimatorError> {
    let base: Vec<(Unknown, f64)> = fitted
        .unknowns
        .iter()
        .zip(&fitted.values)
        .filter(|(u, _)| judged.contains(u))
        .map(|(&u, &v)| (u, v))
        .collect();
    let (fit, with_all, x0) = PieceFit::first(piece, config, &base, pinned)?;
    judged
        .iter()
        .map(|u| {
            let Some(&(_, value)) = base.iter().find(|(b, _)| b == u) else { return Ok(None) };
            let with = |a: f64| {
                let fixed = base.iter().map(|&(b, v)| (b, if b == *u { a } else { v })).collect();
                fit.cost(fixed, &x0)
            };
            let (none, twice) = (with(0.0)?, with(2.0 * value)?);
            let curvature = (twice - 2.0 * with_all + none).max(0.0);
            let sigma_others = fitted.reported(*u).map_or(0.0, |r| r.1);
            let others = if value == 0.0 {
                0.0
            } else {
                curvature / (value * value) * sigma_others * sigma_others
            };
            Ok(Some(PieceJudgement { change: with_all - none, curvature, others }))
        })
        .collect()
}

/// The fits of one held-out piece with its initial states alone free.
struct PieceFit<'a> {
    piece: &'a [&'a [AirDataSample]],
    config: &'a CompatConfig,
    /// Whether the initial side velocity is estimated (not where the check fixed it, or where
    /// the piece does not determine it).
    with_v0: bool,
}

impl<'a> PieceFit<'a> {
    /// The piece's fit with the corrections `base`: the fitter, its cost and initial state.
    fn first(
        piece: &'a [&'a [AirDataSample]],
        config: &'a CompatConfig,
        base: &[(Unknown, f64)],
        pinned: bool,
    ) -> Result<(Self, f64, Vec<f64>), EstimatorError> {
        let fit = |with_v0| Self { piece, config, with_v0 };
        let tried = if pinned { None } else { fit(true).fitted(base.to_vec(), None).ok() };
        let (f, (cost, x0)) = match tried {
            Some(done) => (fit(true), done),
            None => {
                let f = fit(false);
                let done = f.fitted(base.to_vec(), None)?;
                (f, done)
            }
        };
        Ok((f, cost, x0))
    }

    /// `N/2 · ln det R` of the piece with the corrections `fixed`, its initial states fitted from
    /// `x0` (another fit's of the same piece: it differs by one correction).
    fn cost(&self, fixed: Vec<(Unknown, f64)>, x0: &[f64]) -> Result<f64, EstimatorError> {
        Ok(self.fitted(fixed, Some(x0))?.0)
    }

    /// The cost and the fitted initial states, from `x0` or each manoeuvre's first sample.
    fn fitted(
        &self,
        fixed: Vec<(Unknown, f64)>,
        x0: Option<&[f64]>,
    ) -> Result<(f64, Vec<f64>), EstimatorError> {
        let mut p = Problem::new(self.piece, self.config, Vec::new())?;
        let with_v0 = self.with_v0;
        p.unknowns
            .retain(|u| matches!(u, Unknown::Initial { state, .. } if with_v0 || *state != 1));
        p.fixed = fixed;
        let mut beta = x0.map_or_else(|| p.start(), <[f64]>::to_vec);
        p.iterate(&mut beta, self.config)?;
        let cost = 0.5 * p.n_samples() as f64 * p.cost(&beta)?;
        Ok((cost, beta))
    }
}
