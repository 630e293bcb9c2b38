//! The data compatibility check of a record (`aeroident compat`): read → split into
//! manoeuvres → [`aeroident_estimators::compat::check`] → a summary per channel (bias, scale
//! factor, time shift with σ), the reconstructed air data, the residuals and findings in plain
//! words.
//!
//! `compat.json` keys: `file, sigma, status, status_reason, iterations, samples_read,
//! samples_rejected, manoeuvres, channels[{name, unit, bias, bias_sigma, scale, scale_sigma,
//! time_shift_s, time_shift_sigma_s}], ahrs_lag_tau_s, ahrs_lag_tau_sigma_s, residual_rms{output: value}, findings[], warnings[],
//! reconstructed[{manoeuvre, t_s[], vt_mps[], alpha_rad[], beta_rad[], beta_determined}],
//! held_out{by, pieces, corrections[{channel, correction, change_neg_log_likelihood, pieces,
//! expected, spread, verdict}], notes[]}` (each correction applied to the manoeuvres, or
//! halves, held out in turn: [`aeroident_estimators::compat::held_out`]; `replay --compat`
//! refuses each whose `verdict` is `fails`, recomputed from its numbers)
//! (`beta_determined` false: the side velocity and the ay bias were fixed at 0, and `replay
//! --compat` does not use that sideslip). `scale` is the
//! factor the channel reads the truth with (`1 + k`); a number the check did not estimate is
//! `null`. A gyro's `time_shift_s` (`CompatConfig::gyro_time_shifts`) is against the
//! accelerometers, as every shift is. `ahrs_lag_tau_s` is the time constant of the AHRS's
//! first-order filter on the gyros and attitudes (`CompatConfig::ahrs_lag`, `aeroident compat
//! --ahrs-lag`; `null` when not estimated); `replay --compat` then passes every other channel
//! through the same filter (`crate::record::corrections`). The `*_sigma` keys are the coloured-residual σ where it was formed (`sigma =
//! "coloured"`), else the Cramér–Rao σ (`"cramer_rao"`); findings are judged against them.

pub use crate::record::corrections::{
    ChannelSummary, Corrected, Corrections, HeldOutRow, HeldOutSummary, ReconstructedSummary,
};

use crate::record::corrections::{DETERMINED_SIGMAS, plausible, plausible_lag};
use crate::record::{RecordError, read_records};
use crate::results::OutputTrace;
use crate::window::TimeWindow;
use aeroident_estimators::compat::{self, Channel, CompatConfig, CompatResult, Unknown};
use aeroident_estimators::flight_model::G0_MPS2;
use aeroident_estimators::output_error::Termination;
use aeroident_io::{FlightDataReader, Rejection};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Read;

mod misaligned;
mod sensors;

/// `compat.json` (module doc).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CompatSummary {
    /// The record.
    pub file: String,
    /// Which σ the `*_sigma` keys are: `coloured` (the coloured-residual σ) or `cramer_rao`.
    pub sigma: &'static str,
    /// `converged`, `converged_in_cost` or `not_converged` (the last iterate).
    pub status: &'static str,
    /// How a fit that is not `converged` ended.
    pub status_reason: Option<String>,
    /// Gauss–Newton iterations.
    pub iterations: usize,
    /// Rows read.
    pub samples_read: usize,
    /// Rows rejected (listed in `rejections`).
    pub samples_rejected: usize,
    /// The rejected rows and gaps (the first ones and the last).
    pub rejections: Vec<Rejection>,
    /// Manoeuvres (split at the record's gaps).
    pub manoeuvres: usize,
    /// Per channel, its corrections.
    pub channels: Vec<ChannelSummary>,
    /// The time constant of the AHRS's first-order filter on the gyros and attitudes, s, when
    /// estimated.
    pub ahrs_lag_tau_s: Option<f64>,
    /// Its reported σ, s.
    pub ahrs_lag_tau_sigma_s: Option<f64>,
    /// Residual RMS per fitted output, its unit.
    pub residual_rms: BTreeMap<&'static str, f64>,
    /// What the numbers say, in words.
    pub findings: Vec<String>,
    /// What the check could not determine, and rows it could not read.
    pub warnings: Vec<String>,
    /// The reconstructed air data.
    pub reconstructed: Vec<ReconstructedSummary>,
    /// Each correction applied to data it was not fitted on (a record too short to split
    /// says so in its `notes`): `replay --compat` refuses each that fails.
    pub held_out: HeldOutSummary,
}

impl Corrections {
    /// The corrections of a check's summary (`--compat auto`).
    ///
    /// # Errors
    /// As [`Corrections::from_json`].
    pub fn from_summary(s: &CompatSummary) -> Result<Self, RecordError> {
        let lag = s.ahrs_lag_tau_s.map(|t| (t, s.ahrs_lag_tau_sigma_s));
        Self::of_rows(&s.channels, lag, &s.reconstructed, Some(&s.held_out))
            .map_err(|reason| RecordError::Option { option: "compat", reason })
    }
}

/// Checks the compatibility of the record `reader` reads with `config`, over the whole record
/// ([`check_records`] with no window).
///
/// # Errors
/// As [`check_records`].
pub fn check_record<R: Read>(
    reader: FlightDataReader<R>,
    config: &CompatConfig,
) -> Result<(CompatSummary, CompatResult), RecordError> {
    check_records(vec![reader], &[], config)
}

/// Checks the compatibility of the records `readers` read (one aircraft, one mapping) with
/// `config`, over exactly the data a fit of them uses: the time windows `windows` of each
/// (empty: the whole record), each window and each file a manoeuvre of its own, every
/// manoeuvre in one joint fit (one set of biases, scale factors and shifts per flight). A
/// taxi segment or a ground run outside the windows does not enter it.
///
/// # Errors
/// Fatal data errors, no usable sample, windows that miss the records, and the check's own
/// errors (a missing channel, a singular information matrix: [`RecordError::Model`] with the
/// reason).
pub fn check_records<R: Read>(
    readers: Vec<FlightDataReader<R>>,
    windows: &[TimeWindow],
    config: &CompatConfig,
) -> Result<(CompatSummary, CompatResult), RecordError> {
    let file = readers.iter().map(|r| r.file()).collect::<Vec<_>>().join(", ");
    let mapping = readers.first().map(FlightDataReader::mapping);
    let screen = Some(crate::record::outliers::SpikeScreen::default());
    let rec = read_records(readers, screen, None, windows)?;
    let slices: Vec<&[aeroident_estimators::AirDataSample]> =
        rec.manoeuvres.iter().map(Vec::as_slice).collect();
    if let Some(m) = &mapping {
        sensors::believable(&slices, m)
            .map_err(|why| RecordError::Model(format!("compatibility check of {file}: {why}")))?;
    }
    let result = compat::check(&slices, config).map_err(|e| {
        let why = in_user_terms(&e, &slices, &rec.origins, mapping.as_deref());
        RecordError::Model(format!("compatibility check of {file}: {why}"))
    })?;
    let (rejections, unlisted) = rec.rejections.finish();
    let mut warnings = result.notes.clone();
    warnings.extend(unlisted);
    let disagreements = consistency(&slices, config, &result);
    let judged = compat::held_out(&slices, config, &result)
        .map_err(|e| RecordError::Model(format!("compatibility check of {file}: {e}")))?;
    let held_out = HeldOutSummary::of(&judged);
    let dt = median_interval(&rec.manoeuvres);
    let pinned = result.notes.iter().any(|n| n == compat::SIDESLIP_PINNED_NOTE);
    let rows = channels(&result);
    let lengths: Vec<usize> = slices.iter().map(|s| s.len()).collect();
    let implausible = implausible_finding(&rows);
    let summary = CompatSummary {
        file,
        sigma: if result.sigma_coloured.is_some() { "coloured" } else { "cramer_rao" },
        status: result.termination.status(),
        status_reason: (result.termination != Termination::Converged)
            .then(|| result.termination.describe()),
        iterations: result.iterations,
        samples_read: rec.read,
        samples_rejected: rec.rejected,
        rejections,
        manoeuvres: slices.len(),
        channels: rows,
        ahrs_lag_tau_s: result.reported(Unknown::AhrsLag).map(|l| l.0),
        ahrs_lag_tau_sigma_s: result.reported(Unknown::AhrsLag).map(|l| l.1),
        residual_rms: result
            .outputs
            .iter()
            .map(|c| c.name())
            .zip(result.residual_rms.iter().copied())
            .collect(),
        findings: findings(&result, dt)
            .into_iter()
            .chain(disagreements)
            .chain(held_out_finding(&judged, &result))
            .chain(implausible)
            .chain(misaligned::misaligned(&lengths, &result, dt))
            .chain(unmodelled_lag(&slices, config, &result))
            .collect(),
        warnings: warnings.into_iter().chain(held_out.notes.iter().cloned()).collect(),
        reconstructed: result
            .reconstructed
            .iter()
            .enumerate()
            .map(|(m, r)| ReconstructedSummary {
                manoeuvre: m + 1,
                t_s: r.t_s.clone(),
                vt_mps: r.vt_mps.clone(),
                alpha_rad: r.alpha_rad.clone(),
                beta_rad: r.beta_rad.clone(),
                beta_determined: !pinned,
            })
            .collect(),
        held_out,
    };
    Ok((summary, result))
}

/// The check's error `e` in the user's words: a manoeuvre too short by its number, record file
/// and first row (`origins`, per manoeuvre), time span and sample count; a channel the check
/// needs by the mapping's channel (its column or expression, or "not in the mapping") and how
/// many samples lack it; any other error as it is.
fn in_user_terms(
    e: &aeroident_estimators::EstimatorError,
    slices: &[&[aeroident_estimators::AirDataSample]],
    origins: &[crate::record::Origin],
    mapping: Option<&aeroident_io::Mapping>,
) -> String {
    use aeroident_estimators::EstimatorError as E;
    let E::InvalidConfig { field, value, reason } = e else { return e.to_string() };
    if *field == "manoeuvre" {
        let k = *value as usize;
        let Some(m) = slices.get(k).filter(|m| !m.is_empty()) else { return e.to_string() };
        let from =
            origins.get(k).map_or_else(String::new, |(f, row)| format!("{f} from row {row}, "));
        return format!(
            "manoeuvre {} of {} ({from}t = {:.2}–{:.2} s, {} samples) is too short: {reason}; each --window, each stretch between gaps and each --and record is a manoeuvre of its own: widen it or leave it out",
            k + 1,
            slices.len(),
            m[0].t_s,
            m[m.len() - 1].t_s,
            m.len()
        );
    }
    let Some(ch) = Channel::from_name(field) else { return e.to_string() };
    let io_channel = aeroident_io::Channel::of_sample_field(field);
    let label = match (mapping, io_channel) {
        (Some(m), Some(c)) if m.channels.contains_key(&c) => m.field_label(field),
        (_, Some(c)) => format!("channel `{}` (not in the mapping)", c.key()),
        _ => format!("`{field}`"),
    };
    let total: usize = slices.iter().map(|m| m.len()).sum();
    let missing = slices.iter().flat_map(|m| m.iter()).filter(|s| ch.of(s).is_none()).count();
    format!("{label} is missing in {missing} of {total} samples: {reason}")
}

/// The finding that the record's rates and attitudes come through a first-order filter that
/// `config` does not model: the check redone with the AHRS lag and the inertial scale factors
/// as unknowns from the corrections of `from`, the check under `config`
/// ([`compat::check_with_ahrs_lag`]) converges to a time constant more than
/// [`SIGNIFICANT_SIGMAS`] of its σ from 0 and within [`plausible_lag`]'s bounds; `None`
/// otherwise, when `config` models the lag already, and when `from` finds φ or θ late against
/// the gyros (an AHRS's filter delays both alike; attitudes alone late are their own delay,
/// which `from`'s shifts undo).
///
/// Said, not applied: on the simulated records of `crates/aeroident/tests/compat_ahrs_lag.rs`
/// (τ = 0.15 s, 10 Hz) the lag's corrections bring output error's Cl_p, Cl_δa, Cm_q and Cm_δe
/// from 19–35 % off to within 10 %, but move CY_β (−4 % to +11 % with a β vane, +24 % without),
/// so applying it is not "never worse than no correction", which `--compat auto` must be. An
/// unmodelled lag is what those 35 % are, so the user is told which check to run.
fn unmodelled_lag(
    slices: &[&[aeroident_estimators::AirDataSample]],
    config: &CompatConfig,
    from: &CompatResult,
) -> Option<String> {
    if config.ahrs_lag {
        return None;
    }
    // Attitudes late against the gyros are their own delay, which the check's shifts already
    // undo (a record whose attitudes alone were 0.1 s late read as τ = 0.069 s here).
    let attitude_late = [Channel::Phi, Channel::Theta].into_iter().any(|c| {
        from.reported(Unknown::TimeShift(c)).is_some_and(|(v, s)| v > SIGNIFICANT_SIGMAS * s)
    });
    if attitude_late {
        return None;
    }
    let r = compat::check_with_ahrs_lag(slices, config, from).ok()?;
    let (tau, sigma) = r.reported(Unknown::AhrsLag)?;
    let determined = r.termination == Termination::Converged && tau > SIGNIFICANT_SIGMAS * sigma;
    (determined && plausible_lag(tau).is_ok()).then(|| format!(
        "the rates and attitudes look lagged: with the AHRS's first-order lag as an unknown (and the inertial scale factors) the check finds τ = {tau:.3} ± {sigma:.3} s, which this check does not model and does not correct; an unmodelled lag of that size biases the damping and control derivatives (Cl_p, Cm_q +35 % on a simulated 0.15-s lag): run `aeroident compat --ahrs-lag --inertial-scale-factors` and `replay --compat DIR/compat.json`, and compare the sideslip derivatives with the uncorrected fit's (CY_β moved by 16–28 points there)"
    ))
}

/// The finding that names each correction of `rows` the record determines (at least
/// [`DETERMINED_SIGMAS`] of its σ from none) but that lies outside its channel kind's bounds
/// ([`plausible`]: a 13° sideslip-vane bias, a 1-s heading lag), which `replay --compat`
/// therefore refuses; `None` when there is none. The airspeed's bias is not named: it is never
/// applied.
fn implausible_finding(rows: &[ChannelSummary]) -> Option<String> {
    let determined = |v: Option<f64>, sigma: Option<f64>, none: f64| {
        v.filter(|v| sigma.is_none_or(|s| (v - none).abs() >= DETERMINED_SIGMAS * s))
    };
    let mut named = Vec::new();
    for row in rows {
        let Some(ch) = Channel::from_name(&row.name) else { continue };
        let bias = determined(row.bias, row.bias_sigma, 0.0).filter(|_| ch != Channel::Vt);
        let judged = [
            bias.map(|b| plausible(ch, b, 1.0, None)),
            determined(row.scale, row.scale_sigma, 1.0).map(|k| plausible(ch, 0.0, k, None)),
            determined(row.time_shift_s, row.time_shift_sigma_s, 0.0)
                .map(|t| plausible(ch, 0.0, 1.0, Some(t))),
        ];
        let why = judged.into_iter().flatten().filter_map(Result::err);
        named.extend(why.map(|w| format!("{} {w}", row.name)));
    }
    (!named.is_empty()).then(|| {
        format!("implausible for its channel, so replay --compat refuses it: {}", named.join("; "))
    })
}

/// The finding of the held-out judgement `h`: the corrections of `r` determined beyond
/// [`crate::record::corrections::DETERMINED_SIGMAS`] of their σ (so otherwise applied) that
/// failed it ([`compat::HeldOutCorrection::fails`]), which `replay --compat` therefore
/// refuses; `None` when none did. The airspeed's bias is not named: it is never applied.
fn held_out_finding(h: &compat::HeldOut, r: &CompatResult) -> Option<String> {
    let applied = |u: Unknown| {
        u != Unknown::Bias(Channel::Vt)
            && r.reported(u).is_some_and(|(v, s)| v.abs() >= DETERMINED_SIGMAS * s)
    };
    let failed: Vec<String> = h
        .corrections
        .iter()
        .filter(|c| c.fails() && applied(c.unknown))
        .map(|c| {
            let name = unknown_name(c.unknown);
            format!("{name} (+{:.1}; a true one {:+.1} ± {:.1})", c.change, c.expected, c.spread)
        })
        .collect();
    (!failed.is_empty()).then(|| {
        let pieces = if h.by == "half" { "the record's two halves" } else { "its manoeuvres" };
        format!(
            "held out in turn ({pieces}), these corrections worsen the fit of the data they were not fitted on, beyond {} spreads of what a true correction would do (the change of that data's −ln L): {}; replay --compat does not apply them",
            compat::FAIL_SPREADS,
            failed.join(", ")
        )
    })
}

/// A manoeuvre's correction disagrees with the others' beyond this many of its own σ.
pub const CONSISTENCY_SIGMAS: f64 = 3.0;

/// The per-manoeuvre consistency test: each manoeuvre checked alone, and each correction the
/// joint check estimated compared across them. A manoeuvre whose own value lies more than
/// [`CONSISTENCY_SIGMAS`] of its σ, and more than a sensor drifts by ([`tolerance`]), from the
/// manoeuvres' median is named: one set of
/// corrections per flight assumes the sensors did not change between manoeuvres, and one that
/// disagrees holds a taxi segment, another configuration or a failed channel. The median, not
/// the joint value, is the reference, since the joint fit is pulled towards the odd manoeuvre
/// (with two manoeuvres that disagree both are named: the record cannot tell which changed).
/// A manoeuvre the check cannot fit alone is said so, not compared. Nothing with one manoeuvre.
fn consistency(
    slices: &[&[aeroident_estimators::AirDataSample]],
    config: &CompatConfig,
    joint: &CompatResult,
) -> Vec<String> {
    if slices.len() < 2 {
        return Vec::new();
    }
    let mut out = Vec::new();
    let alone: Vec<Option<CompatResult>> = slices
        .iter()
        .enumerate()
        .map(|(k, m)| match compat::check(std::slice::from_ref(m), config) {
            Ok(r) => Some(r),
            Err(e) => {
                out.push(format!("manoeuvre {}: not checked alone ({e}): its consistency with the others is not tested", k + 1));
                None
            }
        })
        .collect();
    let corrections = joint.unknowns.iter().filter(|&&u| tolerance(u).is_some());
    let mut differs: Vec<Vec<String>> = vec![Vec::new(); slices.len()];
    for &u in corrections {
        let own: Vec<Option<(f64, f64)>> =
            alone.iter().map(|r| r.as_ref().and_then(|r| r.reported(u))).collect();
        let mut values: Vec<f64> = own.iter().flatten().map(|v| v.0).collect();
        if values.len() < 2 {
            continue;
        }
        values.sort_by(f64::total_cmp);
        let n = values.len();
        let median =
            if n % 2 == 1 { values[n / 2] } else { 0.5 * (values[n / 2 - 1] + values[n / 2]) };
        for (k, v) in own.iter().enumerate() {
            if let Some((v, s)) = *v
                && (v - median).abs() > (CONSISTENCY_SIGMAS * s).max(tolerance(u).unwrap_or(0.0))
            {
                differs[k].push(format!(
                    "{} {v:+.4} ± {s:.4} (manoeuvres' median {median:+.4})",
                    unknown_name(u)
                ));
            }
        }
    }
    for (k, d) in differs.iter().enumerate().filter(|(_, d)| !d.is_empty()) {
        out.push(format!(
            "manoeuvre {} disagrees with the other manoeuvres beyond {CONSISTENCY_SIGMAS} of its own σ and what a sensor drifts by: {}; the joint check assumes one set of corrections for all (check this one for a taxi segment, another configuration or a failed channel)",
            k + 1,
            d.join(", ")
        ));
    }
    out
}

/// The smallest difference between manoeuvres that says a sensor changed, in the unknown's unit:
/// a tenth of the largest bias or time shift a sensor of that kind plausibly needs
/// ([`crate::record::corrections::limits`]: 0.2 m/s² for an accelerometer, 0.005 rad/s for a
/// gyro, 0.05 s for a shift), and a scale-factor error of 5 % (between the 2 % the findings
/// call significant and the 20–25 % limits). Below it a difference between manoeuvres is within
/// what real sensors drift by. `None` for the biases of the airspeed and the flow angles: they
/// also take up the wind's change over each manoeuvre (shear, a climb through a wind gradient;
/// a steady wind does not reach them), which differs between manoeuvres, so they are not
/// compared.
fn tolerance(u: Unknown) -> Option<f64> {
    use crate::record::corrections::{MAX_SHIFT_S, limits};
    const DRIFT: f64 = 0.1;
    match u {
        Unknown::Bias(Channel::Vt | Channel::Alpha | Channel::Beta) => None,
        Unknown::Bias(c) => Some(DRIFT * limits(c).0),
        Unknown::Scale(_) => Some(0.05),
        Unknown::TimeShift(_) | Unknown::AhrsLag => Some(DRIFT * MAX_SHIFT_S),
        _ => None,
    }
}

/// `alpha_rad time shift`, `ax_mps2 bias`, `beta_rad scale`: an unknown in words.
fn unknown_name(u: Unknown) -> String {
    match u {
        Unknown::Bias(c) => format!("{} bias", c.name()),
        Unknown::Scale(c) => format!("{} scale-factor error k", c.name()),
        Unknown::TimeShift(c) => format!("{} time shift", c.name()),
        Unknown::AhrsLag => "AHRS lag".into(),
        _ => "initial state".into(),
    }
}

/// Per fitted channel, the measured and modelled time histories of a check (`report.html`'s
/// figure): the manoeuvres joined with a NaN break between them, at most
/// [`OutputTrace::MAX_POINTS`] points each (every `stride`th sample). Empty when the result's
/// arrays do not match its samples.
pub fn traces(r: &CompatResult) -> Vec<OutputTrace> {
    let ny = r.outputs.len();
    let total: usize = r.reconstructed.iter().map(|m| m.t_s.len()).sum();
    if r.residuals.len() != total * ny || r.predicted.len() != total * ny {
        return Vec::new();
    }
    let stride = total.div_ceil(OutputTrace::MAX_POINTS).max(1);
    let mut out = Vec::with_capacity(ny);
    for (j, ch) in r.outputs.iter().enumerate() {
        let mut tr = OutputTrace {
            name: ch.name().to_string(),
            t_s: Vec::new(),
            measured: Vec::new(),
            simulated: Vec::new(),
            stride,
        };
        let mut k = 0;
        for (mi, m) in r.reconstructed.iter().enumerate() {
            if mi > 0 {
                tr.t_s.push(f64::NAN);
                tr.measured.push(f64::NAN);
                tr.simulated.push(f64::NAN);
            }
            for (i, &t) in m.t_s.iter().enumerate() {
                if i % stride == 0 {
                    let y = r.predicted[k * ny + j];
                    tr.t_s.push(t);
                    tr.simulated.push(y);
                    tr.measured.push(y + r.residuals[k * ny + j]);
                }
                k += 1;
            }
        }
        out.push(tr);
    }
    out
}

/// The median sample interval of the record, s.
fn median_interval(manoeuvres: &[Vec<aeroident_estimators::AirDataSample>]) -> f64 {
    let mut d: Vec<f64> =
        manoeuvres.iter().flat_map(|m| m.windows(2).map(|w| w[1].t_s - w[0].t_s)).collect();
    d.sort_by(f64::total_cmp);
    d.get(d.len() / 2).copied().unwrap_or(0.0)
}

/// Every channel with at least one estimated correction, inertial first.
fn channels(r: &CompatResult) -> Vec<ChannelSummary> {
    Channel::INERTIAL
        .into_iter()
        .chain(Channel::OUTPUTS)
        .filter_map(|c| {
            let bias = r.reported(Unknown::Bias(c));
            let scale = r.reported(Unknown::Scale(c));
            let shift = r.reported(Unknown::TimeShift(c));
            (bias.is_some() || scale.is_some() || shift.is_some()).then(|| ChannelSummary {
                name: c.name().into(),
                unit: c.unit().into(),
                bias: bias.map(|b| b.0),
                bias_sigma: bias.map(|b| b.1),
                scale: scale.map(|s| 1.0 + s.0),
                scale_sigma: scale.map(|s| s.1),
                time_shift_s: shift.map(|s| s.0),
                time_shift_sigma_s: shift.map(|s| s.1),
            })
        })
        .collect()
}

/// Significance of a finding: the estimate beyond this many σ.
const SIGNIFICANT_SIGMAS: f64 = 3.0;

/// The findings in words: a significant time shift of half a sample or more, a significant
/// bias, a scale factor off by 2 % or more, and an `az` whose bias is `+g` (the channel holds
/// load factor − 1 g, not the specific force).
fn findings(r: &CompatResult, dt_s: f64) -> Vec<String> {
    let mut out = Vec::new();
    let significant = |v: f64, s: f64| v.abs() > SIGNIFICANT_SIGMAS * s;
    if let Some((b, s)) = r.reported(Unknown::Bias(Channel::Az))
        && (b - G0_MPS2).abs() < 0.1 * G0_MPS2
    {
        out.push(format!("az_mps2 looks like load factor − 1 g, not the specific force (bias {b:+.2} ± {s:.2} m/s² ≈ +g): map it as (n_z·g) with the sign of a specific force (≈ −g level)"));
    }
    for (u, (&v, &s)) in r.unknowns.iter().zip(r.values.iter().zip(r.reported_sigma())) {
        match *u {
            Unknown::TimeShift(c) if significant(v, s) && v.abs() >= 0.5 * dt_s => out.push(format!(
                "{} {} the kinematics by {:.3} ± {:.3} s",
                c.name(),
                if v > 0.0 { "lags" } else { "leads" },
                v.abs(),
                s
            )),
            Unknown::AhrsLag if significant(v, s) => out.push(format!(
                "the AHRS filters its rates and attitudes with a first-order lag of time constant {v:.3} ± {s:.3} s"
            )),
            Unknown::Bias(Channel::Vt) if significant(v, s) => out.push(format!(
                "vt_mps reads {v:+.2} ± {s:.2} m/s above the reconstructed speed (a pitot bias or position error, or a wind that changed during the manoeuvre; a steady wind does not show here: the reconstructed initial velocity absorbs it)"
            )),
            Unknown::Bias(c) if significant(v, s) => {
                out.push(format!("{} bias {v:+.4} ± {s:.4} {}", c.name(), c.unit()));
            }
            Unknown::Scale(c) if significant(v, s) && v.abs() >= 0.02 => out.push(format!(
                "{} reads {:.3} ± {s:.3} × the kinematic value{}",
                c.name(),
                1.0 + v,
                if c == Channel::Alpha { " (vane upwash or calibration)" } else { "" }
            )),
            _ => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(unknowns: Vec<Unknown>, values: Vec<f64>, sigma: Vec<f64>) -> CompatResult {
        CompatResult {
            unknowns,
            values,
            sigma,
            sigma_coloured: None,
            outputs: Vec::new(),
            residual_rms: Vec::new(),
            residual_mean: Vec::new(),
            predicted: Vec::new(),
            residuals: Vec::new(),
            reconstructed: Vec::new(),
            termination: Termination::Converged,
            iterations: 3,
            notes: Vec::new(),
        }
    }

    /// An az bias of +g is load factor − 1 g; a lag of 0.18 ± 0.01 s at 10 Hz is a finding, a
    /// gyro's as an output's, a shift below half a sample or within 3σ of zero is not; a bias
    /// within 3σ is not.
    #[test]
    fn findings_name_load_factor_lags_and_significant_biases_only() {
        let r = result(
            vec![
                Unknown::Bias(Channel::Az),
                Unknown::TimeShift(Channel::Alpha),
                Unknown::TimeShift(Channel::Theta),
                Unknown::TimeShift(Channel::Phi),
                Unknown::Bias(Channel::Q),
                Unknown::TimeShift(Channel::Q),
            ],
            vec![9.75, 0.18, 0.04, 0.2, 1e-4, 0.15],
            vec![0.02, 0.01, 0.001, 0.1, 1e-4, 0.01],
        );
        let f = findings(&r, 0.1);
        assert!(f[0].starts_with("az_mps2 looks like load factor − 1 g"), "{f:?}");
        assert!(
            f.contains(&"alpha_rad lags the kinematics by 0.180 ± 0.010 s".to_string()),
            "{f:?}"
        );
        assert!(!f.iter().any(|x| x.starts_with("theta_rad") || x.starts_with("phi_rad")), "{f:?}");
        let q: Vec<&String> = f.iter().filter(|x| x.starts_with("q_rad_s")).collect();
        assert_eq!(q, ["q_rad_s lags the kinematics by 0.150 ± 0.010 s"], "{f:?}");
        let rows = channels(&r);
        let q = rows.iter().find(|c| c.name == "q_rad_s").unwrap();
        assert_eq!((q.time_shift_s, q.time_shift_sigma_s), (Some(0.15), Some(0.01)));
    }

    /// Each determined correction beyond its channel kind's bounds is named with the bound it
    /// passes: a 13° β bias, a 1-s heading lag, a gyro scale of 1.5. Within bounds, within 2σ
    /// of none, or the airspeed's bias (never applied): not named; none named: no finding.
    #[test]
    fn implausible_corrections_are_named_with_their_bound() {
        let row = |name: &str, bias: (f64, f64), scale: (f64, f64), shift: (f64, f64)| {
            let some = |v: f64| (v != 0.0).then_some(v);
            ChannelSummary {
                name: name.into(),
                unit: String::new(),
                bias: some(bias.0),
                bias_sigma: some(bias.1),
                scale: (scale.0 != 1.0).then_some(scale.0),
                scale_sigma: some(scale.1),
                time_shift_s: some(shift.0),
                time_shift_sigma_s: some(shift.1),
            }
        };
        let none = (0.0, 0.0);
        let rows = [
            row("beta_rad", (-0.235, 0.031), (1.0, 0.0), none),
            row("psi_rad", none, (1.0, 0.0), (1.015, 0.21)),
            row("q_rad_s", none, (1.5, 0.01), none),
            row("alpha_rad", (0.3, 0.2), (1.0, 0.0), none),
            row("vt_mps", (-500.0, 1.0), (1.0, 0.0), none),
            row("ax_mps2", (0.5, 0.01), (1.0, 0.0), (0.1, 0.01)),
        ];
        let f = implausible_finding(&rows).unwrap();
        for named in ["beta_rad bias", "±0.175", "psi_rad time shift +1.015 s", "q_rad_s scale 1.5"]
        {
            assert!(f.contains(named), "{named}: {f}");
        }
        for not in ["alpha_rad", "vt_mps", "ax_mps2"] {
            assert!(!f.contains(not), "{not}: {f}");
        }
        assert_eq!(implausible_finding(&rows[3..]), None);
    }
}
