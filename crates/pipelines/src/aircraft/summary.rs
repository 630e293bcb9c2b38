//! The summary of a run (`summary.json`): per estimator and parameter the truth, the final
//! estimate and σ, convergence and target metrics, per estimator the targets met.
//!
//! Metrics per estimator and parameter (truth: the increment for two-aircraft estimators, the
//! reference's total local derivative for sample-driven ones, [`super::experiment`]):
//! - thesis metrics, ±5 % ([`CONVERGENCE_TOL_REL`]): `convergence_time_s` (settled before the
//!   entry's own step), `first_within_s`, `reconvergence_time_s` (after its own step);
//! - target metrics, ±10 % ([`TARGET_TOL_REL`]): `time_to_10pct_s`, from the start of the
//!   excitation until the estimate stays within ±10 % of the truth up to the damage (or the
//!   end); `reconvergence_10pct_s`, from the damage until it stays within ±10 % of the new truth
//!   to the end; `covers_truth_2sigma`, whether `|final − truth| ≤ 2σ` at the end.
//!
//! "Stays within" is the strict settling definition of [`crate::metrics`]: a later excursion
//! out of the band moves the time to after it.

use aeroident_io::parameter::STATUS_DIVERGED;
use aeroident_io::{ParameterResult, StdErrorSource};
use serde::Serialize;

use super::experiment::{ChannelLog, ParamLog, Quantity, RunOutput};
use crate::metrics::{self, CONVERGENCE_TOL_REL, MetricsError};
use crate::verdict::Evidence;

/// Tolerance of the main job's targets: ±10 % of the truth.
pub const TARGET_TOL_REL: f64 = 0.10;

/// Time allowed by the main job's targets after the excitation starts and after the damage, s.
pub const TARGET_WINDOW_S: f64 = 5.0;

/// The primary derivatives of the default main job's targets: pitch stiffness,
/// damping and control power, lift-curve slope, dihedral effect, roll damping and control
/// power, weathercock stability, yaw damping and control power, side-force slope.
pub const PRIMARY_DERIVATIVES: [&str; 11] = [
    "Cm_alpha", "Cm_q", "Cm_de", "CL_alpha", "Cl_beta", "Cl_p", "Cl_da", "Cn_beta", "Cn_r",
    "Cn_dr", "CY_beta",
];

/// One estimator × parameter entry of `summary.json`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ParamSummary {
    /// Estimator label.
    pub estimator: String,
    /// The common keys ([`ParameterResult`]): `name` (vocabulary name, e.g. `Cm_alpha`),
    /// `estimate` (the final one; `null` if never identified or the estimator diverged),
    /// `std_error` (the final σ where the method gives one) and its source, `crb_std_error`
    /// (a batch fit's Cramér–Rao σ), `reference` (the true value at the end of the run; after
    /// a step, the new value; `null` if none exists), `status` ([`ParamSummary::judge`]) and
    /// `flags`.
    #[serde(flatten)]
    pub result: ParameterResult,
    /// `increment` (two-aircraft estimators: ΔC over the F-16) or `derivative` (the reference
    /// aircraft's total local derivative).
    pub quantity: &'static str,
    /// Whether it is one of [`PRIMARY_DERIVATIVES`] (derivatives only).
    pub primary: bool,
    /// True value before the damage.
    pub truth_before: Option<f64>,
    /// True value after the damage (= `truth_before` without damage).
    pub truth_after: Option<f64>,
    /// Time the truth of this entry changes, s (`null`: constant).
    pub step_at_s: Option<f64>,
    /// `(estimate − reference)/|reference|`.
    pub rel_error: Option<f64>,
    /// Whether `|estimate − reference| ≤ 2σ` at the end (`null` without σ).
    pub covers_truth_2sigma: Option<bool>,
    /// First time after which the estimate stays within ±5 % of the truth (before the entry's
    /// step), s; `null` if it never settles.
    pub convergence_time_s: Option<f64>,
    /// First time the estimate enters the ±5 % band (it may leave it again), s.
    pub first_within_s: Option<f64>,
    /// The thesis's reported time, s, where legible.
    pub thesis_convergence_time_s: Option<f64>,
    /// The thesis's claim verbatim.
    pub thesis_note: Option<String>,
    /// Time from the entry's step until the estimate stays within ±5 % of the new truth, s;
    /// `null` without a step or if it never settles.
    pub reconvergence_time_s: Option<f64>,
    /// Time from the start of the excitation until the estimate stays within ±10 % of the
    /// truth up to the damage (or the end), s; `null` if it never does.
    pub time_to_10pct_s: Option<f64>,
    /// Time from the damage until the estimate stays within ±10 % of the new truth, s; `null`
    /// without damage or if it never does.
    pub reconvergence_10pct_s: Option<f64>,
    /// Primary derivatives: within ±10 % within 5 s of the excitation and of the damage, and
    /// ±2σ covering the truth at the end; `null` for the others.
    pub meets_targets: Option<bool>,
    /// Estimator failure (time and message), if any; estimates were held from then on.
    pub failure: Option<String>,
    /// Sample-driven estimators: the estimator's final status (`initialising`, `running`,
    /// `diverged`; batch: `converged`, `converged_in_cost`, `not_converged` (the last iterate)
    /// or `failed`). Schema 1 called it `status`.
    pub estimator_status: Option<&'static str>,
    /// Whether the estimator is a batch (post-flight) fit ([`super::batch`]): its estimate
    /// exists only at the end, so every time metric (`convergence_time_s`, `time_to_10pct_s`,
    /// …) and `meets_targets` are `null`, not "never converged".
    pub batch: bool,
}

impl std::ops::Deref for ParamSummary {
    type Target = ParameterResult;

    fn deref(&self) -> &ParameterResult {
        &self.result
    }
}

/// How many primary derivatives of one estimator meet the main job's targets.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct TargetSummary {
    /// Estimator label.
    pub estimator: String,
    /// Primary derivatives in its structure.
    pub total: usize,
    /// Of those, meeting every target.
    pub met: usize,
    /// The names of those missing a target.
    pub missed: Vec<String>,
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Summary {
    /// The key set's version, [`aeroident_io::SCHEMA_VERSION`].
    pub schema_version: u32,
    /// Scenario name.
    pub scenario: String,
    /// Estimator labels joined with `+`.
    pub estimator: String,
    /// Integrator and step.
    pub solver: String,
    /// Simulated time / wall-clock time of the closed loop (the reference aircraft, sensors,
    /// every estimator and the two-aircraft estimators' aircraft; no I/O).
    pub realtime_factor: f64,
    /// One entry per estimator and parameter.
    pub parameters: Vec<ParamSummary>,
    /// Worst ±5 % re-convergence time over entries with a step, s; `null` without a step or
    /// if any entry never re-converged.
    pub reconvergence_time_s: Option<f64>,
    /// Trim: `[vt_fps, alpha_rad, throttle, elevator_rad]`.
    pub trim: [f64; 4],
    /// First time a pilot command differs from trim, s.
    pub excitation_start_s: Option<f64>,
    /// Earliest sudden change of an increment (the damage), s.
    pub damage_at_s: Option<f64>,
    /// How the sample-driven estimators' angular accelerations are formed (`null` without
    /// them).
    pub angular_accelerations: Option<String>,
    /// Delay of the air-data samples behind the truth, s.
    pub sample_lag_s: Option<f64>,
    /// Per real-time sample-driven estimator: primary derivatives meeting the targets (batch
    /// estimators have no time metrics and are not listed).
    pub targets: Vec<TargetSummary>,
    /// Per batch estimator: the fitted window, iterations and wall time
    /// ([`super::batch::BatchFit`]; a failed fit is absent here and its reason is in the
    /// parameters' `failure`).
    pub batch_fits: Vec<super::batch::BatchFit>,
    /// Per sample-driven estimator: what it did to itself (restarts, re-anchored outputs,
    /// detected changes; [`aeroident_io::replay_output::EventsSummary`]).
    pub events: Vec<EstimatorEvents>,
}

/// One estimator's events in `summary.json`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct EstimatorEvents {
    /// Estimator label.
    pub estimator: String,
    /// Its events.
    #[serde(flatten)]
    pub events: aeroident_io::replay_output::EventsSummary,
}

impl Summary {
    /// The estimators' restart warnings
    /// ([`aeroident_io::replay_output::EventsSummary::restart_warnings`]), each prefixed with
    /// the estimator's label.
    pub fn event_warnings(&self) -> Vec<String> {
        self.events
            .iter()
            .flat_map(|e| {
                e.events
                    .restart_warnings()
                    .into_iter()
                    .map(move |w| format!("{}: {w}", e.estimator))
            })
            .collect()
    }
}

fn nan_for_none(v: &[Option<f64>]) -> Vec<f64> {
    v.iter().map(|x| x.unwrap_or(f64::NAN)).collect()
}

/// Settling time within ±`tol` of `truth` over samples `[from, to)`, measured from `t0`.
fn settle(
    t: &[f64],
    est: &[f64],
    truth: &[f64],
    from: usize,
    to: usize,
    tol: f64,
    t0: f64,
) -> Result<Option<f64>, MetricsError> {
    if from >= to {
        return Ok(None);
    }
    Ok(metrics::convergence_time_series_s(
        &t[from..to],
        &est[from..to],
        &truth[from..to],
        tol,
        f64::NEG_INFINITY,
    )?
    .map(|s| s - t0))
}

fn entry(
    out: &RunOutput,
    ch: &ChannelLog,
    index: usize,
    l: &ParamLog,
) -> Result<ParamSummary, MetricsError> {
    let sc = &out.scenario;
    let t = &out.t_s;
    let n = t.len();
    let est = nan_for_none(&l.estimate);
    let inc_entry = match ch.quantity {
        Quantity::Increment => sc.increment(l.param),
        Quantity::Derivative => None,
    };
    // When this entry's truth changes: the increment's own step, or the first change of the
    // derivative's truth.
    let step = match ch.quantity {
        Quantity::Increment => inc_entry.and_then(|e| e.step_at_s),
        Quantity::Derivative => (1..l.truth_epochs.len())
            .find(|&e| l.truth_epochs[e] != l.truth_epochs[e - 1])
            .map(|e| out.epochs[e].from_s),
    };
    let damage = sc.damage_at_s();
    let idx = |ts: f64| t.partition_point(|&x| x < ts);
    // A batch estimate exists only at the end: no time history to measure.
    let truth_known = l.truth.iter().all(Option::is_some) && !ch.is_batch();
    let truth = nan_for_none(&l.truth);
    let pre = step.map_or(n, idx);
    let (conv, first_within, reconv) = if truth_known {
        let conv = settle(t, &est, &truth, 0, pre, CONVERGENCE_TOL_REL, 0.0)?;
        let first = (0..pre)
            .find(|&k| {
                (est[k] - truth[k]).abs() <= metrics::band_half_width(truth[k], CONVERGENCE_TOL_REL)
            })
            .map(|k| t[k]);
        let reconv = match step {
            Some(t0) => metrics::reconvergence_time_s(t, &est, &truth, CONVERGENCE_TOL_REL, t0)?,
            None => None,
        };
        (conv, first, reconv)
    } else {
        (None, None, None)
    };
    let exc = out.excitation_start_s.unwrap_or(0.0);
    let dmg_idx = damage.map_or(n, idx);
    let (t10, r10) = if truth_known {
        (
            settle(t, &est, &truth, idx(exc), dmg_idx, TARGET_TOL_REL, exc)?,
            match damage {
                Some(d) => settle(t, &est, &truth, dmg_idx, n, TARGET_TOL_REL, d)?,
                None => None,
            },
        )
    } else {
        (None, None)
    };
    let fin = l.estimate.last().copied().flatten();
    let sig = l.sigma.last().copied().flatten();
    let tru = l.truth.last().copied().flatten();
    let covers = match (fin, sig, tru) {
        (Some(f), Some(s), Some(tr)) => Some((f - tr).abs() <= 2.0 * s),
        _ => None,
    };
    let primary =
        ch.quantity == Quantity::Derivative && PRIMARY_DERIVATIVES.contains(&l.param.name());
    let meets = (primary && !ch.is_batch()).then(|| {
        t10.is_some_and(|x| x <= TARGET_WINDOW_S)
            && (damage.is_none() || r10.is_some_and(|x| x <= TARGET_WINDOW_S))
            && covers == Some(true)
    });
    let before = l.truth_epochs.first().copied().flatten();
    let after = match damage {
        Some(d) => {
            let e = out.epochs.iter().rposition(|e| d >= e.from_s).unwrap_or(0);
            l.truth_epochs.get(e).copied().flatten()
        }
        None => before,
    };
    let result = ParameterResult::new(l.param.name(), fin, sig, tru, None)
        .with_source(std_error_source(ch))
        .with_crb_std_error(crb_std_error(ch, index));
    let mut entry = ParamSummary {
        estimator: ch.label.clone(),
        result,
        quantity: ch.quantity.name(),
        primary,
        truth_before: before,
        truth_after: after,
        step_at_s: step,
        rel_error: fin.zip(tru).map(|(f, tr)| metrics::rel_error(f, tr)),
        covers_truth_2sigma: covers,
        convergence_time_s: conv,
        first_within_s: first_within,
        thesis_convergence_time_s: inc_entry.and_then(|e| e.thesis_convergence_time_s),
        thesis_note: inc_entry.and_then(|e| e.thesis_note.clone()),
        reconvergence_time_s: reconv,
        time_to_10pct_s: t10,
        reconvergence_10pct_s: r10,
        meets_targets: meets,
        failure: ch.failure.as_ref().map(|(t, m)| format!("t = {t:.2} s: {m}")),
        estimator_status: ch.status,
        batch: ch.is_batch(),
    };
    entry.judge(damage);
    Ok(entry)
}

/// Which σ the estimator of `ch` reports: a batch fit's bootstrap, coloured-residual or
/// Cramér–Rao σ ([`super::batch::BatchFit`]), else the recursive estimator's covariance.
fn std_error_source(ch: &ChannelLog) -> StdErrorSource {
    match &ch.batch {
        Some(b) if b.bootstrap_failed.is_some() => StdErrorSource::Bootstrap,
        Some(b) if b.coloured_sigma => StdErrorSource::Coloured,
        Some(_) => StdErrorSource::CramerRao,
        None => StdErrorSource::Covariance,
    }
}

/// A batch fit's Cramér–Rao σ of structure parameter `index` (its `cramer_rao` candidate),
/// else `None`.
fn crb_std_error(ch: &ChannelLog, index: usize) -> Option<f64> {
    let b = ch.batch.as_ref()?;
    let (_, crb) = b.sigma_candidates.iter().find(|(k, _)| k == "cramer_rao")?;
    crb.get(index).copied()
}

impl ParamSummary {
    /// Sets the flags, notes and status through the one judge ([`crate::verdict`]): an
    /// estimator failure (estimates held from then on) and an estimator that ended
    /// `initialising` are doubts; `diverged` replaces the verdict. The truth is compared
    /// beside it (`reference_check`), with each missed target of a primary derivative of a
    /// real-time estimator among its findings ([`ParamSummary::missed_targets`]) and, without
    /// a σ, a final value further than 5 % from the truth: a verdict that read the truth
    /// would not say what a flight without one supports.
    pub fn judge(&mut self, damage_at_s: Option<f64>) {
        let misses = self.missed_targets(damage_at_s);
        let status = self.estimator_status;
        let r = &mut self.result;
        let evidence = Evidence {
            doubts: self.failure.iter().map(|f| format!("estimator failed at {f}")).collect(),
            plausibility: None,
            estimate_doubts: status.and_then(crate::verdict::unconverged).into_iter().collect(),
            failure: (status == Some(STATUS_DIVERGED)).then_some(STATUS_DIVERGED),
            notes: Vec::new(),
        };
        crate::verdict::judge(r, &evidence);
        misses.into_iter().for_each(|m| r.reference_finding(m));
        if let (None, Some(e)) = (r.std_error, r.error_pct())
            && e.abs() > 100.0 * CONVERGENCE_TOL_REL
        {
            r.reference_finding(format!("no σ, and the final value is {e:+.1} % from the truth"));
        }
    }

    /// Which of the targets a primary derivative of a real-time estimator missed, and by how
    /// much (empty when it met them or has none): within ±10 % of the truth within
    /// [`TARGET_WINDOW_S`] of the excitation and of the damage (at `damage_at_s`, if any),
    /// ±2σ covering the truth.
    pub fn missed_targets(&self, damage_at_s: Option<f64>) -> Vec<String> {
        if self.meets_targets != Some(false) {
            return Vec::new();
        }
        let w = TARGET_WINDOW_S;
        let late = |t: Option<f64>, from: &str| match t {
            Some(t) if t <= w => None,
            Some(t) => {
                Some(format!("target missed: within ±10 % {t:.1} s after {from} (target {w} s)"))
            }
            None => Some(format!("target missed: never stays within ±10 % after {from}")),
        };
        let mut out: Vec<String> =
            late(self.time_to_10pct_s, "the excitation").into_iter().collect();
        if damage_at_s.is_some() {
            out.extend(late(self.reconvergence_10pct_s, "the damage"));
        }
        if self.covers_truth_2sigma != Some(true) {
            out.push(match self.covers_truth_2sigma {
                Some(false) => "target missed: ±2σ does not cover the truth at the end".into(),
                _ => "target missed: no σ to cover the truth with".into(),
            });
        }
        out
    }
}

/// Computes the summary of a run.
///
/// # Errors
/// [`MetricsError`] only on inconsistent logs (a bug).
pub fn summarize(out: &RunOutput) -> Result<Summary, MetricsError> {
    let sc = &out.scenario;
    let mut parameters = Vec::new();
    let mut targets = Vec::new();
    for ch in &out.channels {
        let first = parameters.len();
        for (index, l) in ch.params.iter().enumerate() {
            parameters.push(entry(out, ch, index, l)?);
        }
        if ch.quantity == Quantity::Derivative && !ch.is_batch() {
            let mine: Vec<&ParamSummary> =
                parameters[first..].iter().filter(|p| p.primary).collect();
            targets.push(TargetSummary {
                estimator: ch.label.clone(),
                total: mine.len(),
                met: mine.iter().filter(|p| p.meets_targets == Some(true)).count(),
                missed: mine
                    .iter()
                    .filter(|p| p.meets_targets != Some(true))
                    .map(|p| p.name.clone())
                    .collect(),
            });
        }
    }
    let with_step: Vec<Option<f64>> = parameters
        .iter()
        .filter(|p| p.step_at_s.is_some())
        .map(|p| p.reconvergence_time_s)
        .collect();
    let worst = if with_step.is_empty() || with_step.iter().any(Option::is_none) {
        None
    } else {
        with_step.iter().flatten().copied().reduce(f64::max)
    };
    let has_sample = out.channels.iter().any(|c| c.quantity == Quantity::Derivative);
    Ok(Summary {
        schema_version: aeroident_io::SCHEMA_VERSION,
        scenario: sc.name.clone(),
        estimator: out.channels.iter().map(|c| c.label.as_str()).collect::<Vec<_>>().join("+"),
        solver: format!("rk4, dt = {} s", sc.dt_s),
        realtime_factor: out.realtime_factor(),
        parameters,
        reconvergence_time_s: worst,
        trim: [
            out.trim.state[aeroident_models::f16::VT],
            out.trim.state[aeroident_models::f16::ALPHA],
            out.trim.controls.throttle,
            out.trim.controls.elevator_rad,
        ],
        excitation_start_s: out.excitation_start_s,
        damage_at_s: sc.damage_at_s(),
        angular_accelerations: has_sample.then(|| {
            format!(
                "causal {}-point least-squares differentiator of the noisy gyros (and α vane for α̇); every other channel {}",
                sc.sensors.differentiator_window,
                match sc.sensors.alignment {
                    super::scenario::Alignment::Matched => "through the matched smoother (same weighting and lag)",
                    super::scenario::Alignment::Delay => "delayed by the differentiator's lag",
                }
            )
        }),
        sample_lag_s: out.sample_lag_s,
        targets,
        batch_fits: out.channels.iter().filter_map(|c| c.batch.clone()).collect(),
        events: out
            .channels
            .iter()
            .filter(|c| c.quantity == Quantity::Derivative && !c.is_batch())
            .map(|c| EstimatorEvents { estimator: c.label.clone(), events: c.events.clone() })
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A primary derivative at −0.95 ± 0.01 against a truth of −1 (5 % off, the truth 5σ away).
    fn entry(meets: Option<bool>, t10: Option<f64>, r10: Option<f64>) -> ParamSummary {
        ParamSummary {
            estimator: "rls".into(),
            result: ParameterResult::new("Cm_alpha", Some(-0.95), Some(0.01), Some(-1.0), None),
            quantity: "derivative",
            primary: true,
            truth_before: Some(-1.0),
            truth_after: Some(-1.0),
            step_at_s: None,
            rel_error: Some(0.05),
            covers_truth_2sigma: Some(false),
            convergence_time_s: None,
            first_within_s: None,
            thesis_convergence_time_s: None,
            thesis_note: None,
            reconvergence_time_s: None,
            time_to_10pct_s: t10,
            reconvergence_10pct_s: r10,
            meets_targets: meets,
            failure: None,
            estimator_status: Some("running"),
            batch: false,
        }
    }

    /// Each missed target is named with its number among the truth's findings, beside the
    /// verdict: late after the excitation (7.3 s against 5 s), never back after the damage,
    /// ±2σ not covering the truth; the truth 5σ away is in the same check. None is a flag: the
    /// status is `identified`. Without damage the damage target is not named; σ 42 % of the
    /// estimate is a note; an estimator that ended `initialising` flags the estimate; a
    /// diverged estimator is `diverged` whatever its numbers.
    #[test]
    fn a_missed_target_is_compared_beside_the_verdict() {
        let mut e = entry(Some(false), Some(7.3), None);
        e.judge(Some(20.0));
        assert_eq!((e.status.as_str(), e.flags.len()), ("identified", 0), "{:?}", e.flags);
        let check = e.reference_check.clone().unwrap();
        assert_eq!(check.within_2sigma, Some(false));
        assert!((check.distance_sigma.unwrap() - 5.0).abs() < 1e-9);
        assert_eq!(
            check.findings,
            [
                "target missed: within ±10 % 7.3 s after the excitation (target 5 s)",
                "target missed: never stays within ±10 % after the damage",
                "target missed: ±2σ does not cover the truth at the end",
            ]
        );
        let mut e = entry(Some(false), Some(2.0), None);
        e.judge(None);
        assert_eq!(e.result.reference_check.unwrap().findings.len(), 1);
        let mut e = entry(Some(true), Some(2.0), Some(1.0));
        e.covers_truth_2sigma = Some(true);
        e.result = ParameterResult::new("Cm_alpha", Some(-0.99), Some(0.01), Some(-1.0), None);
        e.judge(Some(20.0));
        assert_eq!((e.status.as_str(), e.flags.len()), ("identified", 0));
        assert!(e.result.reference_check.unwrap().findings.is_empty());
        // Within ±2σ of the truth but σ 42 % of itself (the default job's CD_q): a note.
        let mut e = entry(None, None, None);
        e.result = ParameterResult::new("CD_q", Some(2.839), Some(1.2), Some(0.4536), None);
        e.judge(None);
        assert_eq!(e.status, "identified");
        assert_eq!(e.notes, ["σ 42 % of |estimate|: the record does not determine it to 10 %"]);
        let mut e = entry(None, None, None);
        e.estimator_status = Some("initialising");
        e.judge(None);
        assert_eq!(e.status, "flagged");
        assert!(e.flags[0].contains("ended `initialising`"), "{:?}", e.flags);
        let mut e = entry(Some(false), None, None);
        e.estimator_status = Some("diverged");
        e.judge(None);
        assert_eq!(e.status, "diverged");
    }
}
