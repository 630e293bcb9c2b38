//! Outputs of a run: `timeseries.csv`, `summary.json`, the terminal table, the figures
//! ([`super::figures`]) and the thesis-versus-ours report of `aeroident run --all`.
//!
//! Metrics per estimator and parameter (truth: the increment for two-aircraft estimators, the
//! reference's total local derivative for sample-driven ones, [`super::experiment`]):
//! - thesis metrics, ±5 % ([`CONVERGENCE_TOL_REL`]): `convergence_time_s` (settled before the
//!   entry's own step), `first_within_s`, `reconvergence_time_s` (after its own step);
//! - issue-8 metrics, ±10 % ([`TARGET_TOL_REL`]): `time_to_10pct_s`, from the start of the
//!   excitation until the estimate stays within ±10 % of the truth up to the damage (or the
//!   end); `reconvergence_10pct_s`, from the damage until it stays within ±10 % of the new truth
//!   to the end; `covers_truth_2sigma`, whether `|final − truth| ≤ 2σ` at the end.
//!
//! "Stays within" is the strict settling definition of [`crate::metrics`]: a later excursion
//! out of the band moves the time to after it.

use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

use super::experiment::{ChannelLog, ParamLog, Quantity, RunOutput, TRACKED_NAMES, tracked};
use crate::metrics::{self, CONVERGENCE_TOL_REL};
use crate::outdir::OutputDir;

/// Tolerance of the issue-8 targets: ±10 % of the truth.
pub const TARGET_TOL_REL: f64 = 0.10;

/// Time allowed by the issue-8 targets after the excitation starts and after the damage, s.
pub const TARGET_WINDOW_S: f64 = 5.0;

/// The primary derivatives of the default main job's targets (issue 8): pitch stiffness,
/// damping and control power, lift-curve slope, dihedral effect, roll damping and control
/// power, weathercock stability, yaw damping and control power, side-force slope.
pub const PRIMARY_DERIVATIVES: [&str; 11] = [
    "Cm_alpha", "Cm_q", "Cm_de", "CL_alpha", "Cl_beta", "Cl_p", "Cl_da", "Cn_beta", "Cn_r",
    "Cn_dr", "CY_beta",
];

/// Errors writing outputs. Each names the file.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// File system error.
    #[error("writing `{path}`: {source}")]
    Io {
        /// File.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// Figure error.
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
    /// Output directory error (lock, atomic write), naming the path.
    #[error(transparent)]
    Output(#[from] crate::outdir::OutputError),
    /// Metric error (a bug: lengths are built equal).
    #[error(transparent)]
    Metrics(#[from] metrics::MetricsError),
    /// JSON or CSV encoding.
    #[error("encoding `{path}`: {reason}")]
    Encode {
        /// File.
        path: String,
        /// Why.
        reason: String,
    },
}

pub(super) fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io { path: path.display().to_string(), source }
}

/// One estimator × parameter entry of `summary.json`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ParamSummary {
    /// Estimator label.
    pub estimator: String,
    /// Vocabulary name, e.g. `Cm_alpha`.
    pub name: String,
    /// `increment` (two-aircraft estimators: ΔC over the F-16) or `derivative` (the reference
    /// aircraft's total local derivative).
    pub quantity: &'static str,
    /// Whether it is one of [`PRIMARY_DERIVATIVES`] (derivatives only).
    pub primary: bool,
    /// True value at the end of the run (after a step, the new value); `null` if none exists.
    pub truth: Option<f64>,
    /// True value before the damage.
    pub truth_before: Option<f64>,
    /// True value after the damage (= `truth_before` without damage).
    pub truth_after: Option<f64>,
    /// Time the truth of this entry changes, s (`null`: constant).
    pub step_at_s: Option<f64>,
    /// Final estimate; `null` if never identified or the estimator diverged.
    pub r#final: Option<f64>,
    /// Final standard error where the method gives one.
    pub sigma: Option<f64>,
    /// `(final − truth)/|truth|`.
    pub rel_error: Option<f64>,
    /// Whether `|final − truth| ≤ 2σ` at the end (`null` without σ).
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
    /// Sample-driven estimators: the final status (`initialising`, `running`, `diverged`;
    /// batch: `converged` or `failed`).
    pub status: Option<&'static str>,
    /// Whether the estimator is a batch (post-flight) fit ([`super::batch`]): its estimate
    /// exists only at the end, so every time metric (`convergence_time_s`, `time_to_10pct_s`,
    /// …) and `meets_targets` are `null`, not "never converged".
    pub batch: bool,
}

/// How many primary derivatives of one estimator meet the issue-8 targets.
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
) -> Result<Option<f64>, ReportError> {
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

fn entry(out: &RunOutput, ch: &ChannelLog, l: &ParamLog) -> Result<ParamSummary, ReportError> {
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
    Ok(ParamSummary {
        estimator: ch.label.clone(),
        name: l.param.name().into(),
        quantity: ch.quantity.name(),
        primary,
        truth: tru,
        truth_before: before,
        truth_after: after,
        step_at_s: step,
        r#final: fin,
        sigma: sig,
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
        status: ch.status,
        batch: ch.is_batch(),
    })
}

/// Computes the summary of a run.
///
/// # Errors
/// [`ReportError::Metrics`] only on inconsistent logs (a bug).
pub fn summarize(out: &RunOutput) -> Result<Summary, ReportError> {
    let sc = &out.scenario;
    let mut parameters = Vec::new();
    let mut targets = Vec::new();
    for ch in &out.channels {
        let first = parameters.len();
        for l in &ch.params {
            parameters.push(entry(out, ch, l)?);
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

fn cell(v: Option<f64>) -> String {
    v.map_or(String::new(), |x| x.to_string())
}

/// Writes `timeseries.csv` (one row per sample; columns `t_s`, controls, wind, reference
/// states `ref_*`, true increments `truth_<name>`, then per estimator `<label>.<name>`
/// (empty while not identified); sample-driven estimators add `<label>.<name>.sigma` and
/// `<label>.<name>.truth`; two-aircraft estimators add their aircraft's `<label>.<state>` and,
/// published ones, `<label>.K<g>`, `<label>.sdot<g>` per group).
///
/// # Errors
/// [`ReportError::Io`] naming the file.
pub fn write_timeseries(out: &RunOutput, path: &Path) -> Result<(), ReportError> {
    let f = std::fs::File::create(path).map_err(io_err(path))?;
    write_timeseries_to(out, &mut std::io::BufWriter::new(f), path)
}

/// [`write_timeseries`] into any writer; `path` names the file in errors.
///
/// # Errors
/// [`ReportError::Io`] naming the file.
pub fn write_timeseries_to(
    out: &RunOutput,
    w: &mut dyn std::io::Write,
    path: &Path,
) -> Result<(), ReportError> {
    let mut header = String::from(
        "t_s,throttle,elevator_rad,aileron_rad,rudder_rad,wind_north_fps,wind_east_fps,wind_down_fps",
    );
    for n in TRACKED_NAMES {
        write!(header, ",ref_{n}").ok();
    }
    for r in &out.increments {
        write!(header, ",truth_{}", r.param.name()).ok();
    }
    let ngroups: Vec<usize> = out
        .channels
        .iter()
        .map(|c| c.diagnostics.iter().map(Vec::len).max().unwrap_or(0))
        .collect();
    for (ch, &ng) in out.channels.iter().zip(&ngroups) {
        for l in &ch.params {
            let n = l.param.name();
            write!(header, ",{}.{n}", ch.label).ok();
            if ch.quantity == Quantity::Derivative {
                write!(header, ",{0}.{n}.sigma,{0}.{n}.truth", ch.label).ok();
            }
        }
        if !ch.states.is_empty() {
            for n in TRACKED_NAMES {
                write!(header, ",{}.{n}", ch.label).ok();
            }
        }
        for g in 0..ng {
            write!(header, ",{0}.K{g},{0}.sdot{g}", ch.label).ok();
        }
    }
    writeln!(w, "{header}").map_err(io_err(path))?;
    let mut line = String::new();
    for k in 0..out.t_s.len() {
        line.clear();
        let c = out.controls[k];
        let wd = out.wind_ned_fps[k];
        write!(
            line,
            "{},{},{},{},{},{},{},{}",
            out.t_s[k], c[0], c[1], c[2], c[3], wd[0], wd[1], wd[2]
        )
        .ok();
        for v in tracked(&out.reference[k]) {
            write!(line, ",{v}").ok();
        }
        for r in &out.increments {
            write!(line, ",{}", r.at(out.t_s[k])).ok();
        }
        for (ch, &ng) in out.channels.iter().zip(&ngroups) {
            for l in &ch.params {
                write!(line, ",{}", cell(l.estimate[k])).ok();
                if ch.quantity == Quantity::Derivative {
                    write!(line, ",{},{}", cell(l.sigma[k]), cell(l.truth[k])).ok();
                }
            }
            if let Some(x) = ch.states.get(k) {
                for v in tracked(x) {
                    write!(line, ",{v}").ok();
                }
            }
            for g in 0..ng {
                match ch.diagnostics.get(k).and_then(|d| d.get(g)) {
                    Some(d) => write!(line, ",{},{}", d.K, d.sdot).ok(),
                    None => write!(line, ",,").ok(),
                };
            }
        }
        writeln!(w, "{line}").map_err(io_err(path))?;
    }
    w.flush().map_err(io_err(path))
}

/// Writes `summary.json`.
///
/// # Errors
/// [`ReportError`] naming the file.
pub fn write_summary(summary: &Summary, path: &Path) -> Result<(), ReportError> {
    let text = serde_json::to_string_pretty(summary).map_err(|e| ReportError::Encode {
        path: path.display().to_string(),
        reason: e.to_string(),
    })?;
    std::fs::write(path, text + "\n").map_err(io_err(path))
}

fn sec(v: Option<f64>) -> String {
    v.map_or("—".to_string(), |x| format!("{x:.2} s"))
}

fn num(v: Option<f64>) -> String {
    v.map_or("null".to_string(), |x| format!("{x:.4e}"))
}

/// One line on an estimator's targets: met / total primary derivatives and the missed ones.
pub fn targets_line(t: &TargetSummary) -> String {
    let missed = if t.missed.is_empty() {
        String::new()
    } else {
        format!(" (missed: {})", t.missed.join(", "))
    };
    format!("{}: {}/{} primary derivatives meet the targets{missed}", t.estimator, t.met, t.total)
}

/// One line on a batch fit: window, initial state, iterations, wall time, σ kind.
pub fn batch_fit_line(b: &super::batch::BatchFit) -> String {
    format!(
        "{}: post-flight fit of {} samples, t = {:.2}–{:.2} s (initial state: {}), {} iterations, {:.2} s wall; σ {}; time columns: batch (no estimate before the end)",
        b.estimator,
        b.samples,
        b.from_s,
        b.to_s,
        b.initial_states,
        b.iterations.map_or("—".into(), |i| i.to_string()),
        b.wall_s,
        if b.coloured_sigma { "coloured-residual" } else { "Cramér–Rao" },
    )
}

/// A terminal table of a summary: the thesis-style table for increments, the truth / estimate
/// ± σ / times table for derivatives.
pub fn table(summary: &Summary) -> String {
    let mut s = String::new();
    writeln!(
        s,
        "scenario {}  (realtime factor {:.0}×, {})",
        summary.scenario, summary.realtime_factor, summary.solver
    )
    .ok();
    let incs: Vec<&ParamSummary> =
        summary.parameters.iter().filter(|p| p.quantity == "increment").collect();
    if !incs.is_empty() {
        writeln!(
            s,
            "{:<22} {:<10} {:>11} {:>11} {:>9} {:>9} {:>9}",
            "estimator", "increment", "truth", "final", "rel.err", "t_conv", "thesis"
        )
        .ok();
        for p in incs {
            writeln!(
                s,
                "{:<22} {:<10} {:>11} {:>11} {:>9} {:>9} {:>9}",
                p.estimator,
                p.name,
                num(p.truth),
                num(p.r#final),
                p.rel_error.map_or("—".into(), |e| format!("{:.1}%", 100.0 * e)),
                sec(p.convergence_time_s),
                p.thesis_note.clone().unwrap_or_else(|| sec(p.thesis_convergence_time_s)),
            )
            .ok();
        }
        if let Some(r) = summary.reconvergence_time_s {
            writeln!(s, "worst re-convergence after the step: {r:.2} s").ok();
        }
    }
    let ders: Vec<&ParamSummary> =
        summary.parameters.iter().filter(|p| p.quantity == "derivative").collect();
    if !ders.is_empty() {
        if let Some(a) = &summary.angular_accelerations {
            writeln!(s, "angular accelerations: {a}").ok();
        }
        writeln!(
            s,
            "excitation from {}, damage at {}; times to stay within ±10 % of truth (target ≤ {TARGET_WINDOW_S} s); * = primary derivative",
            sec(summary.excitation_start_s),
            sec(summary.damage_at_s)
        )
        .ok();
        writeln!(
            s,
            "{:<10} {:<13} {:>11} {:>11} {:>11} {:>10} {:>8} {:>8} {:>6} {:>7}",
            "estimator",
            "derivative",
            "truth",
            "truth after",
            "final",
            "± σ",
            "t_10%",
            "re_10%",
            "2σ ok",
            "target"
        )
        .ok();
        for p in ders {
            writeln!(
                s,
                "{:<10} {:<13} {:>11} {:>11} {:>11} {:>10} {:>8} {:>8} {:>6} {:>7}",
                p.estimator,
                format!("{}{}", p.name, if p.primary { "*" } else { "" }),
                num(p.truth_before),
                if p.step_at_s.is_some() { num(p.truth_after) } else { "=".into() },
                num(p.r#final),
                p.sigma.map_or("—".into(), |x| format!("{x:.2e}")),
                if p.batch { "batch".into() } else { sec(p.time_to_10pct_s) },
                if p.batch {
                    "batch".into()
                } else if summary.damage_at_s.is_some() {
                    sec(p.reconvergence_10pct_s)
                } else {
                    "—".into()
                },
                p.covers_truth_2sigma.map_or("—", |b| if b { "yes" } else { "NO" }),
                p.meets_targets.map_or("", |b| if b { "met" } else { "MISSED" }),
            )
            .ok();
        }
        for b in &summary.batch_fits {
            writeln!(s, "{}", batch_fit_line(b)).ok();
        }
        for t in &summary.targets {
            writeln!(s, "{}", targets_line(t)).ok();
        }
    }
    s
}

/// Writes all outputs of one run into the locked output directory `od` (each file atomically)
/// and returns the summary.
///
/// # Errors
/// [`ReportError`] naming the file.
pub fn write_all(
    out: &RunOutput,
    od: &mut OutputDir,
    figures: bool,
) -> Result<Summary, ReportError> {
    let summary = summarize(out)?;
    let mut f = od.create("timeseries.csv")?;
    let path = f.path().to_path_buf();
    write_timeseries_to(out, &mut f, &path)?;
    f.commit()?;
    let text = serde_json::to_string_pretty(&summary).map_err(|e| ReportError::Encode {
        path: od.path().join("summary.json").display().to_string(),
        reason: e.to_string(),
    })?;
    od.write_bytes("summary.json", (text + "\n").as_bytes())?;
    let figs = if figures { super::figures::write_figures(out, od)? } else { Vec::new() };
    crate::report::run::write(out, &summary, figs, od)?;
    Ok(summary)
}

fn opt_s(v: Option<f64>) -> String {
    v.map_or("never".to_string(), |x| format!("{x:.2} s"))
}

/// Verdict on a thesis time claim, from our settling time.
fn verdict(p: &ParamSummary) -> &'static str {
    match (p.convergence_time_s, p.thesis_convergence_time_s, p.thesis_note.as_deref()) {
        (None, _, _) => "never settles",
        (Some(t), Some(th), _) if t <= th => "settles, ≤ thesis",
        (Some(_), Some(_), _) => "settles, slower than thesis",
        (Some(t), None, Some(n)) if n.starts_with('>') => {
            if t < n
                .trim_start_matches('>')
                .trim_end_matches(" s")
                .trim()
                .parse::<f64>()
                .unwrap_or(0.0)
            {
                "settles, faster than thesis"
            } else {
                "settles, as slow as thesis"
            }
        }
        (Some(_), _, _) => "settles",
    }
}

/// The thesis-versus-ours tables of several runs (markdown), one section per thesis table
/// (scenarios grouped by the prefix of `thesis_table`), plus a realtime-factor column.
pub fn markdown(results: &[(super::Scenario, Summary)]) -> String {
    let mut s = String::new();
    let mut groups: Vec<String> = Vec::new();
    for (sc, _) in results {
        let g = sc
            .thesis_table
            .clone()
            .map(|t| {
                t.split(" case").next().unwrap_or(&t).split(" (").next().unwrap_or(&t).to_string()
            })
            .unwrap_or_else(|| "other".into());
        if !groups.contains(&g) {
            groups.push(g);
        }
    }
    const ORDER: [&str; 7] = ["4.7", "4.8", "4.9", "4.10", "combined", "4.2.5", "beyond"];
    groups.sort_by_key(|g| ORDER.iter().position(|o| o == g).unwrap_or(ORDER.len()));
    for g in groups {
        let title = match g.as_str() {
            "4.7" => "Table 4.7 — ΔCm_α alone".to_string(),
            "4.8" => "Table 4.8 — ΔCm_q alone".to_string(),
            "4.9" => "Table 4.9 — ΔCL_α alone".to_string(),
            "4.10" => "Table 4.10 — ΔCD_α alone".to_string(),
            "combined" => {
                "Combined run (all four at once; thesis Figs 4.59–4.61, pages not in our copy)"
                    .to_string()
            }
            "4.2.5" => {
                "Model-reference gradient (3.3) vs SMPE (thesis §4.2.5, pages not in our copy)"
                    .to_string()
            }
            "beyond" => "Beyond the thesis".to_string(),
            other => other.to_string(),
        };
        writeln!(s, "\n### {title}\n").ok();
        writeln!(s, "| scenario | estimator | param | truth (1/rad) | final | rel. err | first in ±5 % | settled in ±5 % | thesis | verdict | re-conv. after step | RT factor |").ok();
        writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|").ok();
        for (sc, sm) in results.iter().filter(|(sc, _)| {
            sc.thesis_table.as_deref().is_some_and(|t| t.starts_with(&g))
                || (g == "other" && sc.thesis_table.is_none())
        }) {
            for p in &sm.parameters {
                let name = if p.quantity == "increment" {
                    format!("Δ{}", p.name)
                } else {
                    p.name.clone()
                };
                writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.0}× |",
                    sc.name,
                    p.estimator,
                    name,
                    p.truth.map_or("—".into(), |v| format!("{v:.4e}")),
                    p.r#final.map_or("null".into(), |v| format!("{v:.4e}")),
                    p.rel_error.map_or("—".into(), |e| format!("{:.1} %", 100.0 * e)),
                    opt_s(p.first_within_s),
                    opt_s(p.convergence_time_s),
                    p.thesis_note.clone().unwrap_or_else(|| "—".into()),
                    if p.failure.is_some() { "estimator failed" } else { verdict(p) },
                    if p.step_at_s.is_some() {
                        opt_s(p.reconvergence_time_s)
                    } else {
                        "—".into()
                    },
                    sm.realtime_factor,
                )
                .ok();
            }
        }
    }
    s
}
