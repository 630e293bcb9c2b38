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
//! expected, spread, verdict}], notes[]}` (each correction applied to the manoeuvres, to
//! runs of consecutive manoeuvres beyond five (`by = "fold"`), or to halves, held out in turn: [`aeroident_estimators::compat::held_out`]; `replay --compat`
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
    ChannelSummary, Corrected, Corrections, HeldOutRow, HeldOutSummary, InputLead,
    ReconstructedSummary,
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

pub mod long;
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
    /// Each surface the sign tests' timing search found leading its response by a determined
    /// 0.02 s and a sample or more (a commanded surface, or one recorded early:
    /// [`crate::replay::sign_tests::timing`]), measured on the record as logged; `--compat
    /// auto` reads each that much later unless the mapping declares the surface's `shift_s`.
    pub input_leads: Vec<InputLead>,
}

/// The surfaces the sign tests find leading their response on `slices` ([`InputLead`]).
fn input_leads(
    slices: &[&[aeroident_estimators::AirDataSample]],
    m: &aeroident_io::Mapping,
) -> Vec<InputLead> {
    let (tests, warned) = crate::replay::sign_tests::checked(slices, m);
    let warnings: aeroident_io::warning::Warnings = warned.into_iter().collect();
    let leads = crate::replay::sign_tests::refit::warned_leads(&tests, &warnings);
    leads
        .into_iter()
        .map(|(channel, lead_s)| {
            let test = tests.iter().find(|t| t.channel == channel);
            let (lo, hi) = test.and_then(|t| t.lead_interval_s).unwrap_or((f64::NAN, f64::NAN));
            InputLead { channel, lead_s, lead_sigma_s: (hi - lo) / (2.0 * 1.96) }
        })
        .collect()
}

impl Corrections {
    /// The corrections of a check's summary (`--compat auto`).
    ///
    /// # Errors
    /// As [`Corrections::from_json`].
    pub fn from_summary(s: &CompatSummary) -> Result<Self, RecordError> {
        let lag = s.ahrs_lag_tau_s.map(|t| (t, s.ahrs_lag_tau_sigma_s));
        let mut c = Self::of_rows(&s.channels, lag, &s.reconstructed, Some(&s.held_out))
            .map_err(|reason| RecordError::Option { option: "compat", reason })?;
        c.leads = s.input_leads.clone();
        Ok(c)
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
/// (empty: the whole record; one record with a stretch longer than [`long::LONG_STRETCH_S`]
/// without a gap is checked on its best manoeuvres instead, and a warning names them:
/// [`long`]), each window and each file a manoeuvre of its own, every
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
    let one_file = readers.len() == 1;
    let mut rec = read_records(readers, screen, None, windows)?;
    let mut judged_note = None;
    if windows.is_empty() && one_file {
        match long::judged(&rec.manoeuvres) {
            long::Judged::Whole => {}
            long::Judged::WholeLong(why) => judged_note = Some(why),
            long::Judged::Windows(chosen, why) => {
                rec = long::within(rec, &chosen);
                judged_note = Some(why);
            }
        }
    }
    let slices: Vec<&[aeroident_estimators::AirDataSample]> =
        rec.manoeuvres.iter().map(Vec::as_slice).collect();
    let not_judged = match &mapping {
        Some(m) => sensors::believable(&slices, m)
            .map_err(|why| RecordError::Model(format!("compatibility check of {file}: {why}")))?,
        None => Vec::new(),
    };
    let result = compat::check(&slices, config).map_err(|e| {
        let why = in_user_terms(&e, &slices, &rec.origins, mapping.as_deref());
        RecordError::Model(format!("compatibility check of {file}: {why}"))
    })?;
    let (rejections, unlisted) = rec.rejections.finish();
    let mut warnings: Vec<String> = judged_note.into_iter().collect();
    warnings.extend(result.notes.iter().cloned());
    warnings.extend(not_judged);
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
    let input_leads = mapping.as_deref().map_or_else(Vec::new, |m| input_leads(&slices, m));
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
        input_leads,
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
/// Said, not applied: on the simulated records of `crates/aeroident/tests/all/compat_ahrs_lag.rs`
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
        let pieces = match h.by {
            "half" => "the record's two halves",
            "fold" => "folds of its consecutive manoeuvres",
            _ => "its manoeuvres",
        };
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

    fn with_values(pairs: &[(Unknown, f64, f64)]) -> CompatResult {
        result(
            pairs.iter().map(|p| p.0).collect(),
            pairs.iter().map(|p| p.1).collect(),
            pairs.iter().map(|p| p.2).collect(),
        )
    }

    #[test]
    fn findings_name_what_passes_each_edge_and_nothing_short_of_it() {
        let named = findings(
            &with_values(&[
                (Unknown::Bias(Channel::Az), 1.09 * G0_MPS2, 5.0),
                (Unknown::TimeShift(Channel::Alpha), 0.05, 0.01),
                (Unknown::TimeShift(Channel::Beta), -0.06, 0.01),
                (Unknown::AhrsLag, 0.15, 0.01),
                (Unknown::Bias(Channel::Vt), 2.0, 0.5),
                (Unknown::Bias(Channel::Ax), 0.76, 0.25),
                (Unknown::Scale(Channel::Alpha), 0.02, 0.001),
                (Unknown::Scale(Channel::Q), -0.03, 0.001),
            ]),
            0.1,
        );
        let expected = [
            "az_mps2 looks like load factor − 1 g",
            "alpha_rad lags the kinematics by 0.050 ± 0.010 s",
            "beta_rad leads the kinematics by 0.060 ± 0.010 s",
            "first-order lag of time constant 0.150 ± 0.010 s",
            "vt_mps reads +2.00 ± 0.50 m/s above the reconstructed speed",
            "ax_mps2 bias +0.7600 ± 0.2500 m/s^2",
            "alpha_rad reads 1.020 ± 0.001 × the kinematic value (vane upwash or calibration)",
            "q_rad_s reads 0.970 ± 0.001 × the kinematic value",
        ];
        for (text, f) in expected.iter().zip(&named) {
            assert!(f.contains(text), "{text}: {named:?}");
        }
        assert!(!named[7].contains("vane"), "{named:?}");
        let none = findings(
            &with_values(&[
                (Unknown::Bias(Channel::Az), 1.11 * G0_MPS2, 5.0),
                (Unknown::TimeShift(Channel::Theta), 0.2, 0.1),
                (Unknown::AhrsLag, 0.02, 0.01),
                (Unknown::Bias(Channel::Vt), 0.5, 1.0),
                (Unknown::Bias(Channel::Ay), 0.75, 0.25),
                (Unknown::Scale(Channel::Beta), 0.015, 0.001),
                (Unknown::Scale(Channel::Ax), 0.05, 0.02),
            ]),
            0.1,
        );
        assert!(none.is_empty(), "{none:?}");
        let below = with_values(&[(Unknown::Bias(Channel::Az), 0.89 * G0_MPS2, 0.01)]);
        let below = findings(&below, 0.1);
        assert_eq!(below.len(), 1, "{below:?}");
        assert!(below[0].starts_with("az_mps2 bias +8.7279"), "{below:?}");
    }

    #[test]
    fn the_drift_tolerance_is_a_tenth_of_each_kinds_limit_and_none_for_air_data_biases() {
        for c in [Channel::Vt, Channel::Alpha, Channel::Beta] {
            assert_eq!(tolerance(Unknown::Bias(c)), None, "{c:?}");
        }
        assert_eq!(tolerance(Unknown::Initial { manoeuvre: 0, state: 0 }), None);
        assert_eq!(tolerance(Unknown::Bias(Channel::Ay)), Some(0.2));
        let gyro = tolerance(Unknown::Bias(Channel::R)).unwrap();
        assert!((gyro - 0.005).abs() < 1e-15, "{gyro}");
        let attitude = tolerance(Unknown::Bias(Channel::Theta)).unwrap();
        assert!((attitude - 0.0175).abs() < 1e-15, "{attitude}");
        assert_eq!(tolerance(Unknown::Scale(Channel::Alpha)), Some(0.05));
        assert_eq!(tolerance(Unknown::TimeShift(Channel::Alpha)), Some(0.05));
        assert_eq!(tolerance(Unknown::AhrsLag), Some(0.05));
    }

    #[test]
    fn unknowns_are_named_in_words() {
        let names = [
            (Unknown::Bias(Channel::Ax), "ax_mps2 bias"),
            (Unknown::Scale(Channel::Alpha), "alpha_rad scale-factor error k"),
            (Unknown::TimeShift(Channel::Psi), "psi_rad time shift"),
            (Unknown::AhrsLag, "AHRS lag"),
            (Unknown::Initial { manoeuvre: 1, state: 2 }, "initial state"),
        ];
        for (u, name) in names {
            assert_eq!(unknown_name(u), name);
        }
    }

    #[test]
    fn the_median_interval_is_the_middle_one_within_the_manoeuvres() {
        let at = |t: &[f64]| -> Vec<aeroident_estimators::AirDataSample> {
            t.iter()
                .map(|&t_s| aeroident_estimators::AirDataSample { t_s, ..Default::default() })
                .collect()
        };
        let manoeuvres = vec![at(&[0.0, 0.25, 0.75]), at(&[10.0, 11.0, 13.0])];
        assert_eq!(median_interval(&manoeuvres), 1.0);
        let odd = vec![at(&[1.0, 1.5, 2.5, 2.75])];
        assert_eq!(median_interval(&odd), 0.5);
        assert_eq!(median_interval(&[]), 0.0);
    }

    #[test]
    fn channels_hold_every_channel_with_a_correction_and_the_scale_as_one_plus_k() {
        let r = with_values(&[
            (Unknown::Bias(Channel::Ax), 0.1, 0.01),
            (Unknown::Scale(Channel::Alpha), 0.02, 0.001),
            (Unknown::TimeShift(Channel::Theta), 0.05, 0.01),
            (Unknown::Initial { manoeuvre: 0, state: 0 }, 60.0, 0.1),
        ]);
        let rows = channels(&r);
        let names: Vec<&str> = rows.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["ax_mps2", "alpha_rad", "theta_rad"]);
        assert_eq!(
            (rows[0].bias, rows[0].bias_sigma, rows[0].scale),
            (Some(0.1), Some(0.01), None)
        );
        assert_eq!(
            (rows[1].scale, rows[1].scale_sigma, rows[1].bias),
            (Some(1.02), Some(0.001), None)
        );
        assert_eq!(rows[2].time_shift_s, Some(0.05));
    }

    #[test]
    fn implausible_corrections_are_judged_from_exactly_two_sigma_from_none() {
        let row =
            |name: &str, bias: Option<(f64, f64)>, scale: Option<(f64, f64)>| ChannelSummary {
                name: name.into(),
                unit: String::new(),
                bias: bias.map(|b| b.0),
                bias_sigma: bias.map(|b| b.1),
                scale: scale.map(|s| s.0),
                scale_sigma: scale.map(|s| s.1),
                time_shift_s: None,
                time_shift_sigma_s: None,
            };
        let at_two_sigma = [row("beta_rad", Some((0.2, 0.1)), None)];
        let f = implausible_finding(&at_two_sigma).unwrap();
        assert!(f.starts_with("implausible for its channel") && f.contains("beta_rad bias"), "{f}");
        assert_eq!(implausible_finding(&[row("beta_rad", Some((0.2, 0.1001)), None)]), None);
        let unsure_scale = [row("q_rad_s", None, Some((1.5, 0.3)))];
        assert_eq!(implausible_finding(&unsure_scale), None);
        let f = implausible_finding(&[row("q_rad_s", None, Some((1.5, 0.25)))]).unwrap();
        assert!(f.contains("q_rad_s scale 1.5"), "{f}");
        let f = implausible_finding(&[row("az_mps2", Some((3.0, 0.1)), None)]).unwrap();
        assert!(f.contains("az_mps2 bias"), "{f}");
    }

    fn judged(unknown: Unknown, change: f64, pieces: usize) -> compat::HeldOutCorrection {
        compat::HeldOutCorrection { unknown, change, pieces, expected: 0.0, spread: 1.0 }
    }

    #[test]
    fn held_out_failures_are_named_only_for_applied_corrections() {
        let r = with_values(&[
            (Unknown::Bias(Channel::Q), 0.01, 0.005),
            (Unknown::Bias(Channel::Vt), 5.0, 0.1),
            (Unknown::Bias(Channel::Ax), 0.1, 0.1),
            (Unknown::TimeShift(Channel::Alpha), 0.2, 0.01),
        ]);
        let mut h = compat::HeldOut {
            by: "half",
            pieces: 2,
            corrections: vec![
                judged(Unknown::Bias(Channel::Q), 10.0, 2),
                judged(Unknown::Bias(Channel::Vt), 10.0, 2),
                judged(Unknown::Bias(Channel::Ax), 10.0, 2),
                judged(Unknown::TimeShift(Channel::Alpha), 1.0, 2),
            ],
            notes: Vec::new(),
        };
        let f = held_out_finding(&h, &r).unwrap();
        assert!(f.starts_with("held out in turn (the record's two halves)"), "{f}");
        assert!(
            f.ends_with(
                ": q_rad_s bias (+10.0; a true one +0.0 ± 1.0); replay --compat does not apply them"
            ),
            "{f}"
        );
        h.by = "manoeuvre";
        let f = held_out_finding(&h, &r).unwrap();
        assert!(f.starts_with("held out in turn (its manoeuvres)"), "{f}");
        h.by = "fold";
        let f = held_out_finding(&h, &r).unwrap();
        assert!(f.starts_with("held out in turn (folds of its consecutive manoeuvres)"), "{f}");
        h.corrections[0].change = 1.0;
        assert_eq!(held_out_finding(&h, &r), None);
    }

    #[test]
    fn check_errors_name_the_short_manoeuvre_and_the_missing_channel_as_mapped() {
        use aeroident_estimators::{AirDataSample, EstimatorError};
        let at = |t_s: f64, q: Option<f64>| AirDataSample { t_s, q_rad_s: q, ..Default::default() };
        let first = [at(0.0, Some(0.1)), at(0.5, None), at(1.0, Some(0.1))];
        let second = [at(5.0, Some(0.1)), at(5.5, Some(0.1))];
        let slices: [&[AirDataSample]; 2] = [&first, &second];
        let origins = [("a.csv".to_string(), 2), ("b.csv".to_string(), 7)];
        let short = EstimatorError::InvalidConfig {
            field: "manoeuvre",
            value: 1.0,
            reason: "a manoeuvre needs at least 10 samples",
        };
        let text = in_user_terms(&short, &slices, &origins, None);
        assert!(
            text.starts_with("manoeuvre 2 of 2 (b.csv from row 7, t = 5.00–5.50 s, 2 samples) is too short: a manoeuvre needs at least 10 samples;"),
            "{text}"
        );
        let mapping = aeroident_io::Mapping::from_toml_str(
            "[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"v\", unit = \"m/s\" }\nalpha = { column = \"aoa\", unit = \"rad\" }\nq = { column = \"pitch_rate\", unit = \"rad/s\" }\nqbar = { value = 1000.0, unit = \"Pa\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\n",
            "m.toml",
        )
        .unwrap();
        let missing = |field| EstimatorError::InvalidConfig { field, value: 0.0, reason: "needed" };
        let q = in_user_terms(&missing("q_rad_s"), &slices, &origins, Some(&mapping));
        assert_eq!(q, "channel `q` (column `pitch_rate`) is missing in 1 of 5 samples: needed");
        let ay = in_user_terms(&missing("ay_mps2"), &slices, &origins, Some(&mapping));
        assert_eq!(ay, "channel `ay` (not in the mapping) is missing in 5 of 5 samples: needed");
        let other = EstimatorError::InvalidConfig { field: "steps", value: 0.0, reason: "needed" };
        assert_eq!(in_user_terms(&other, &slices, &origins, None), other.to_string());
    }

    #[test]
    fn traces_join_the_manoeuvres_with_a_break_and_add_the_residual_to_the_model() {
        let mut r = result(Vec::new(), Vec::new(), Vec::new());
        r.outputs = vec![Channel::Alpha, Channel::Theta];
        let manoeuvre = |t_s: Vec<f64>| compat::Reconstructed { t_s, ..Default::default() };
        r.reconstructed = vec![manoeuvre(vec![0.0, 1.0]), manoeuvre(vec![5.0])];
        r.predicted = vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        r.residuals = vec![0.5, 0.25, -1.0, 1.0, 0.0, 2.0];
        let t = traces(&r);
        assert_eq!(t.len(), 2);
        assert_eq!((t[0].name.as_str(), t[1].name.as_str()), ("alpha_rad", "theta_rad"));
        let finite =
            |v: &[f64]| v.iter().map(|x| if x.is_nan() { -99.0 } else { *x }).collect::<Vec<_>>();
        assert_eq!(finite(&t[0].t_s), [0.0, 1.0, -99.0, 5.0]);
        assert_eq!(finite(&t[0].simulated), [1.0, 3.0, -99.0, 5.0]);
        assert_eq!(finite(&t[0].measured), [1.5, 2.0, -99.0, 5.0]);
        assert_eq!(finite(&t[1].simulated), [2.0, 4.0, -99.0, 6.0]);
        assert_eq!(finite(&t[1].measured), [2.25, 5.0, -99.0, 8.0]);
        assert_eq!(t[0].stride, 1);
        r.residuals.pop();
        assert!(traces(&r).is_empty());
    }

    #[test]
    fn traces_keep_every_stride_th_sample_of_a_long_record() {
        let mut r = result(Vec::new(), Vec::new(), Vec::new());
        r.outputs = vec![Channel::Alpha];
        let n = 2 * OutputTrace::MAX_POINTS + 1;
        let t_s: Vec<f64> = (0..n).map(|k| k as f64).collect();
        r.reconstructed = vec![compat::Reconstructed { t_s: t_s.clone(), ..Default::default() }];
        r.predicted = t_s.clone();
        r.residuals = vec![0.0; n];
        let t = traces(&r);
        assert_eq!(t[0].stride, 3);
        assert_eq!(t[0].t_s.len(), 13_334);
        assert_eq!(&t[0].t_s[..3], [0.0, 3.0, 6.0]);
        assert_eq!(t[0].measured[2], 6.0);
    }

    fn flown(t: f64) -> [f64; 6] {
        flown_rolling(t, 1.0)
    }

    fn flown_rolling(t: f64, roll: f64) -> [f64; 6] {
        [
            60.0 + 2.0 * (0.7 * t).sin(),
            2.0 * (1.1 * t).sin(),
            4.0 + 2.0 * (1.3 * t).sin(),
            roll * (0.3 * (0.6 * t).sin() + 0.1 * (1.7 * t).sin()),
            0.05 + 0.08 * (0.9 * t).sin(),
            0.3 + 0.2 * (0.4 * t).sin(),
        ]
    }

    fn rates_and_forces(t: f64) -> ([f64; 3], [f64; 3]) {
        rates_and_forces_rolling(t, 1.0)
    }

    fn rates_and_forces_rolling(t: f64, roll: f64) -> ([f64; 3], [f64; 3]) {
        let h = 1e-4;
        let at = |t| flown_rolling(t, roll);
        let (x, ahead, behind) = (at(t), at(t + h), at(t - h));
        let d: [f64; 6] = core::array::from_fn(|j| (ahead[j] - behind[j]) / (2.0 * h));
        let [u, v, w, phi, theta, _] = x;
        let (sf, cf, st, ct) = (phi.sin(), phi.cos(), theta.sin(), theta.cos());
        let p = d[3] - d[5] * st;
        let q = d[4] * cf + d[5] * sf * ct;
        let r = -d[4] * sf + d[5] * cf * ct;
        let a = [
            d[0] + G0_MPS2 * st - (r * v - q * w),
            d[1] - G0_MPS2 * ct * sf - (p * w - r * u),
            d[2] - G0_MPS2 * ct * cf - (q * u - p * v),
        ];
        ([p, q, r], a)
    }

    fn manoeuvre(t0: f64, q_bias: f64, seed: u64) -> Vec<aeroident_estimators::AirDataSample> {
        manoeuvre_rolling(t0, q_bias, seed, 1.0)
    }

    fn manoeuvre_rolling(
        t0: f64,
        q_bias: f64,
        seed: u64,
        roll: f64,
    ) -> Vec<aeroident_estimators::AirDataSample> {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let mut noise = |deg: f64| Normal::new(0.0, deg.to_radians()).unwrap().sample(&mut rng);
        (0..150)
            .map(|k| {
                let t = t0 + 0.1 * k as f64;
                let ([p, q, r], [ax, ay, az]) = rates_and_forces_rolling(t, roll);
                let [u, v, w, phi, theta, psi] = flown_rolling(t, roll);
                let vt = (u * u + v * v + w * w).sqrt();
                aeroident_estimators::AirDataSample {
                    t_s: t,
                    vt_mps: vt + 2.0 * noise(0.05),
                    alpha_rad: w.atan2(u) + noise(0.05),
                    beta_rad: Some((v / vt).asin() + noise(0.05)),
                    qbar_pa: 0.6 * vt * vt,
                    p_rad_s: Some(p),
                    q_rad_s: Some(q + q_bias),
                    r_rad_s: Some(r),
                    phi_rad: Some(phi + noise(0.1)),
                    theta_rad: Some(theta + noise(0.1)),
                    psi_rad: Some(psi + noise(0.1)),
                    ax_mps2: Some(ax),
                    ay_mps2: Some(ay),
                    az_mps2: Some(az),
                    ..Default::default()
                }
            })
            .collect()
    }

    fn q_bias_named(text: &str) -> (f64, f64) {
        let number = |after: &str| -> f64 {
            let rest = &text[text.find(after).unwrap_or_else(|| panic!("{text}")) + after.len()..];
            rest.split([' ', ')']).next().unwrap().parse().unwrap()
        };
        (number("q_rad_s bias "), number("manoeuvres' median "))
    }

    fn joint_unknowns() -> CompatResult {
        with_values(&[
            (Unknown::Bias(Channel::Q), 0.0, 1.0),
            (Unknown::Bias(Channel::Alpha), 0.0, 1.0),
            (Unknown::Scale(Channel::Ax), 0.0, 1.0),
        ])
    }

    #[test]
    fn consistency_names_the_manoeuvres_whose_gyro_bias_left_the_median_of_five() {
        let biases = [0.0, 0.0, 0.02, 0.02, 0.02];
        let flown: Vec<_> = biases
            .iter()
            .enumerate()
            .map(|(k, &b)| manoeuvre(20.0 * k as f64, b, 3 + k as u64))
            .collect();
        let short = &manoeuvre(100.0, 0.0, 8)[..5];
        let mut slices: Vec<&[aeroident_estimators::AirDataSample]> =
            flown.iter().map(Vec::as_slice).collect();
        slices.push(short);
        let out = consistency(&slices, &CompatConfig::default(), &joint_unknowns());
        assert_eq!(out.len(), 3, "{out:?}");
        assert!(out[0].starts_with("manoeuvre 6: not checked alone ("), "{out:?}");
        for (k, text) in out[1..].iter().enumerate() {
            let head = format!(
                "manoeuvre {} disagrees with the other manoeuvres beyond 3 of its own σ",
                k + 1
            );
            assert!(text.starts_with(&head), "{out:?}");
            let (own, median) = q_bias_named(text);
            assert!(own.abs() < 0.002 && (median - 0.02).abs() < 0.002, "{out:?}");
            assert!(!text.contains("alpha_rad"), "{out:?}");
        }
    }
    #[test]
    fn consistency_of_two_names_both_against_their_mean() {
        let (a, c) = (manoeuvre(0.0, 0.0, 6), manoeuvre(20.0, 0.02, 7));
        let out = consistency(&[&a, &c], &CompatConfig::default(), &joint_unknowns());
        assert_eq!(out.len(), 2, "{out:?}");
        for (k, text) in out.iter().enumerate() {
            assert!(text.starts_with(&format!("manoeuvre {} disagrees", k + 1)), "{out:?}");
            let (own, median) = q_bias_named(text);
            assert!((median - 0.01).abs() < 0.001, "{out:?}");
            assert!((own - 0.02 * k as f64).abs() < 0.002, "{out:?}");
        }
        let short = &a[..5];
        assert!(consistency(&[short], &CompatConfig::default(), &joint_unknowns()).is_empty());
    }

    fn through_ahrs_filter(tau: f64) -> Vec<aeroident_estimators::AirDataSample> {
        let raw = |t: f64| {
            let ([p, q, r], _) = rates_and_forces(t);
            let x = flown(t);
            [p, q, r, x[3], x[4], x[5]]
        };
        let (h, fine) = (0.1 / 20.0, 20);
        let a = (-h / tau).exp();
        let mut y = raw(0.0);
        let mut out = manoeuvre(0.0, 0.0, 9);
        for (k, s) in out.iter_mut().enumerate() {
            for i in (k.max(1) - 1) * fine..k * fine {
                let (u0, u1) = (raw(i as f64 * h), raw((i + 1) as f64 * h));
                y = core::array::from_fn(|j| a * y[j] + (1.0 - a) * 0.5 * (u0[j] + u1[j]));
            }
            let truth = flown(s.t_s);
            (s.p_rad_s, s.q_rad_s, s.r_rad_s) = (Some(y[0]), Some(y[1]), Some(y[2]));
            s.phi_rad = s.phi_rad.map(|m| m - truth[3] + y[3]);
            s.theta_rad = s.theta_rad.map(|m| m - truth[4] + y[4]);
            s.psi_rad = s.psi_rad.map(|m| m - truth[5] + y[5]);
        }
        out
    }

    #[test]
    fn an_unmodelled_ahrs_lag_is_named_with_its_time_constant_unless_modelled_or_attitudes_late() {
        let lagged = through_ahrs_filter(0.15);
        let config = CompatConfig::default();
        let from = compat::check(&[&lagged], &config).unwrap();
        let text = unmodelled_lag(&[&lagged], &config, &from).expect("a 0.15-s lag is named");
        let tau: f64 =
            text.split("τ = ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
        assert!((tau - 0.15).abs() < 0.03, "{text}");
        let modelled = CompatConfig { ahrs_lag: true, ..config };
        assert_eq!(unmodelled_lag(&[&lagged], &modelled, &from), None);
        let mut late = from.clone();
        let theta =
            late.unknowns.iter().position(|u| *u == Unknown::TimeShift(Channel::Theta)).unwrap();
        late.values[theta] = 3.0 * late.reported_sigma()[theta];
        assert!(unmodelled_lag(&[&lagged], &config, &late).is_some(), "θ 3σ late is not late");
        late.values[theta] = 3.01 * late.reported_sigma()[theta];
        assert_eq!(unmodelled_lag(&[&lagged], &config, &late), None);
        let clean = manoeuvre(0.0, 0.0, 10);
        let from = compat::check(&[&clean], &config).unwrap();
        assert_eq!(unmodelled_lag(&[&clean], &config, &from), None);
    }

    fn checked_csv(samples: &[aeroident_estimators::AirDataSample], beta: bool) -> CompatSummary {
        const KEYS: [(&str, &str, &str); 12] = [
            ("vt", "m/s", "vt_mps"),
            ("alpha", "rad", "alpha_rad"),
            ("beta", "rad", "beta_rad"),
            ("p", "rad/s", "p_rad_s"),
            ("q", "rad/s", "q_rad_s"),
            ("r", "rad/s", "r_rad_s"),
            ("phi", "rad", "phi_rad"),
            ("theta", "rad", "theta_rad"),
            ("psi", "rad", "psi_rad"),
            ("ax", "m/s2", "ax_mps2"),
            ("ay", "m/s2", "ay_mps2"),
            ("az", "m/s2", "az_mps2"),
        ];
        let keys: Vec<_> = KEYS.iter().filter(|k| beta || k.0 != "beta").collect();
        let mut toml = String::from("[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\n");
        for (key, unit, _) in &keys {
            toml += &format!("{key} = {{ column = \"{key}\", unit = \"{unit}\" }}\n");
        }
        toml += "qbar = { value = 2000.0, unit = \"Pa\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\n";
        let mapping = aeroident_io::Mapping::from_toml_str(&toml, "m.toml").unwrap();
        let mut csv = String::from("t");
        keys.iter().for_each(|(key, _, _)| csv += &format!(",{key}"));
        for s in samples {
            csv += &format!("\n{}", s.t_s);
            keys.iter().for_each(|(_, _, field)| csv += &format!(",{:?}", s.field(field).unwrap()));
        }
        let reader = FlightDataReader::new(csv.as_bytes(), "flown.csv", &mapping).unwrap();
        check_record(reader, &CompatConfig::default()).unwrap().0
    }

    #[test]
    fn a_checked_csv_record_summarises_its_gyro_bias_as_a_correction_replay_applies() {
        let summary = checked_csv(&manoeuvre(0.0, 0.02, 11), true);
        assert_eq!((summary.status, summary.status_reason.as_deref()), ("converged", None));
        assert_eq!((summary.samples_read, summary.manoeuvres), (150, 1));
        let m = &summary.reconstructed[0];
        assert!(m.manoeuvre == 1 && m.beta_determined && m.t_s.len() == 150, "{m:?}");
        let q = summary.channels.iter().find(|c| c.name == "q_rad_s").unwrap();
        assert!((q.bias.unwrap() - 0.02).abs() < 3.0 * q.bias_sigma.unwrap(), "{q:?}");
        assert!(
            summary.findings.iter().any(|f| f.starts_with("q_rad_s bias +0.020")),
            "{:?}",
            summary.findings
        );
        let corrections = Corrections::from_summary(&summary).unwrap();
        let applied: Vec<String> = corrections.warnings().map(|w| w.text).collect();
        assert!(applied.iter().any(|w| w.contains("q_rad_s")), "{applied:?}");
    }

    #[test]
    fn a_note_other_than_the_pinned_sideslip_leaves_the_sideslip_determined() {
        let summary = checked_csv(&manoeuvre_rolling(0.0, 0.0, 12, 0.0), false);
        let phi_note = "time shift of phi_rad not estimated: the channel hardly varies";
        assert!(summary.warnings.iter().any(|w| w.starts_with(phi_note)), "{:?}", summary.warnings);
        assert!(!summary.warnings.iter().any(|w| w == compat::SIDESLIP_PINNED_NOTE));
        assert!(summary.reconstructed[0].beta_determined);
    }
}
