//! Applying a compatibility check's corrections to a record as it streams (`replay --compat`):
//! each channel's bias and scale factor removed, `(x − bias) / scale`, each time shift undone
//! (a channel that lags the kinematics by `τ` is read `τ` later, linearly interpolated), and
//! the reconstructed sideslip put where the record has none. Causal: a sample leaves the stage
//! once the record has reached its time plus the largest lag, so the stage delays the stream by
//! that much and keeps every time stamp.
//!
//! An AHRS's first-order lag (`compat --ahrs-lag`) is not undone: inverting a filter
//! differentiates the gyros' noise. Every channel not from the AHRS (the accelerometers, the air
//! data, the surfaces, thrust and density) is instead passed through the same filter
//! ([`aeroident_estimators::compat::lag_step`], from steady state at each manoeuvre's first
//! sample), after its own corrections, so that all channels share one lag: a linear system
//! whose every input and output passes through one linear filter keeps its parameters.
//!
//! Not applied: the airspeed bias (it also takes up any change of the wind over the manoeuvre,
//! and the aerodynamics need the airspeed the pitot measures, not the reconstructed speed).

use super::RecordError;
use aeroident_estimators::AirDataSample;
use aeroident_estimators::compat::{Channel, interpolate, wrap};
use aeroident_io::warning::{Warning, WarningKind};
use aeroident_io::{FlightDataError, RecordEvent};
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;
use std::path::Path;

mod held_out;

pub use held_out::{HeldOutRow, HeldOutSummary};

/// One channel's corrections: `measured = scale · true + bias`, read `time_shift_s` late (a
/// `compat.json` row, written and read back by `replay --compat`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelSummary {
    /// The sample field (`ax_mps2`, `alpha_rad` …).
    pub name: String,
    /// Its unit.
    #[serde(default)]
    pub unit: String,
    /// Bias, channel units.
    pub bias: Option<f64>,
    /// Its reported σ (`compat.json` `sigma`: coloured-residual where formed, else Cramér–Rao).
    pub bias_sigma: Option<f64>,
    /// Scale factor `1 + k`.
    pub scale: Option<f64>,
    /// Its reported σ (`compat.json` `sigma`: coloured-residual where formed, else Cramér–Rao).
    pub scale_sigma: Option<f64>,
    /// Time shift, s (> 0: the channel lags the kinematics).
    pub time_shift_s: Option<f64>,
    /// Its reported σ, s (as `bias_sigma`).
    pub time_shift_sigma_s: Option<f64>,
}

/// One manoeuvre's reconstructed air data at its sample times.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReconstructedSummary {
    /// Manoeuvre, from 1.
    pub manoeuvre: usize,
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Airspeed, m/s.
    pub vt_mps: Vec<f64>,
    /// Angle of attack, rad.
    pub alpha_rad: Vec<f64>,
    /// Sideslip, rad.
    pub beta_rad: Vec<f64>,
    /// Whether the check determined the sideslip (its initial side velocity and the `ay` bias
    /// estimated, not fixed at 0); only then does `replay --compat` use it as a measurement.
    /// Absent in older files: taken as determined.
    #[serde(default = "determined")]
    pub beta_determined: bool,
}

fn determined() -> bool {
    true
}

/// The largest correction of each kind a channel of kind `ch` plausibly needs: physical limits
/// of a sensor's installation and of air-data and attitude-system errors, set wide, never
/// fitted to a record. A correction beyond them says more about the record than the sensor
/// (a taxi segment in the check, a dead or mis-mapped channel, a typing error in a
/// hand-edited `compat.json`): the channel's corrections are then not applied, and the summary
/// says why.
/// - bias: 2 m/s² for an accelerometer (0.2 g; a load factor mapped as specific force is 1 g
///   off), 0.05 rad/s for a gyro (2.9°/s, beyond any navigation-grade or MEMS rate sensor's),
///   0.175 rad (10°) for a flow angle (vane misalignment and upwash offset) or an attitude;
///   the airspeed's bias is never applied (it also takes up a changing wind);
/// - scale: within 0.7–1.4 for a flow angle (local upwash and sidewash factors), 0.8–1.25
///   for the others;
/// - time shift: 0.5 s either way (vane and AHRS lags are tenths of a second), and no lead
///   of a gyro or an attitude beyond [`MAX_AHRS_LEAD_S`] (an AHRS's filters only delay).
///
/// # Errors
/// Which limit the correction passes, in words.
pub fn plausible(ch: Channel, bias: f64, scale: f64, shift_s: Option<f64>) -> Result<(), String> {
    let (max_bias, scale_range) = limits(ch);
    if bias.abs() > max_bias {
        return Err(format!(
            "bias {bias:+.4e} {} beyond the ±{max_bias} a {} plausibly has: not applied (check the record's segment and the channel's mapping)",
            ch.unit(),
            kind_name(ch)
        ));
    }
    if !(scale_range.0..=scale_range.1).contains(&scale) {
        return Err(format!(
            "scale {scale:.4} outside the {}–{} a {} plausibly has: not applied",
            scale_range.0,
            scale_range.1,
            kind_name(ch)
        ));
    }
    let ahrs = matches!(
        ch,
        Channel::P | Channel::Q | Channel::R | Channel::Phi | Channel::Theta | Channel::Psi
    );
    match shift_s {
        Some(t) if t.abs() > MAX_SHIFT_S => Err(format!(
            "time shift {t:+.3} s beyond the ±{MAX_SHIFT_S} s a sensor's lag plausibly reaches: not applied"
        )),
        Some(t) if ahrs && t < -MAX_AHRS_LEAD_S => Err(format!(
            "time shift {t:+.3} s: the {} would lead the kinematics by {:.3} s, which an attitude and heading system's filters cannot (they only delay; a lead says the accelerometers, the time reference, are late, or the fit traded it for another unknown): not applied",
            kind_name(ch),
            -t
        )),
        _ => Ok(()),
    }
}

/// The largest lead of a gyro or attitude over the kinematics taken as timing noise, s (a
/// sample at 50 Hz): beyond it a lead is refused ([`plausible`]).
pub const MAX_AHRS_LEAD_S: f64 = 0.02;

/// The largest time shift a sensor's lag plausibly reaches, either way, s ([`plausible`]):
/// the bound a mapping's `shift_s` is checked against too, defined once where the mapping is
/// read.
pub const MAX_SHIFT_S: f64 = aeroident_io::mapping::MAX_INPUT_SHIFT_S;

/// The largest time constant of an AHRS's first-order filter, s ([`plausible_lag`]): the
/// filters of the AHRS of a UAV or a business jet are 0.05–0.2 s.
pub const MAX_AHRS_LAG_S: f64 = 0.5;

/// Whether an AHRS lag of time constant `tau_s` is one a filter has: within 0 (less the timing
/// noise [`MAX_AHRS_LEAD_S`]) and [`MAX_AHRS_LAG_S`].
///
/// # Errors
/// Which limit it passes, in words.
pub fn plausible_lag(tau_s: f64) -> Result<(), String> {
    if tau_s < -MAX_AHRS_LEAD_S {
        return Err(format!(
            "time constant {tau_s:+.3} s: a filter's time constant is not negative (the gyros and attitudes would lead the accelerometers, the time reference): not applied"
        ));
    }
    if tau_s > MAX_AHRS_LAG_S {
        return Err(format!(
            "time constant {tau_s:.3} s beyond the {MAX_AHRS_LAG_S} s an attitude and heading system's filter plausibly has: not applied"
        ));
    }
    Ok(())
}

/// Channel `ch`'s largest plausible bias (its unit) and scale range ([`plausible`]).
pub fn limits(ch: Channel) -> (f64, (f64, f64)) {
    match ch {
        Channel::Ax | Channel::Ay | Channel::Az => (2.0, (0.8, 1.25)),
        Channel::P | Channel::Q | Channel::R => (0.05, (0.8, 1.25)),
        Channel::Alpha | Channel::Beta => (0.175, (0.7, 1.4)),
        Channel::Vt => (f64::INFINITY, (0.8, 1.25)),
        _ => (0.175, (0.8, 1.25)),
    }
}

/// The kind of sensor of channel `ch`, for messages.
fn kind_name(ch: Channel) -> &'static str {
    match ch {
        Channel::Ax | Channel::Ay | Channel::Az => "accelerometer",
        Channel::P | Channel::Q | Channel::R => "gyro",
        Channel::Alpha | Channel::Beta => "flow angle",
        Channel::Vt => "airspeed",
        _ => "attitude",
    }
}

/// The corrections of a compatibility check (from its `compat.json`, or its summary).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Corrections {
    /// `(channel, bias, scale)`: the stage replaces `x` by `(x − bias) / scale`.
    affine: Vec<(Channel, f64, f64)>,
    /// `(channel, τ)`: the stage reads the channel `τ` later.
    shifts: Vec<(Channel, f64)>,
    /// `(surface, τ)`: the stage reads the control surface `τ` later (a refit with a
    /// measured input lead undone, [`Corrections::with_input_shift`]).
    input_shifts: Vec<(aeroident_io::Channel, f64)>,
    /// The AHRS's time constant, s: the stage passes every other channel through its filter.
    lag_s: Option<f64>,
    /// Per manoeuvre, the reconstructed sideslip `(t_s, β)`, for records without one.
    beta: Vec<(Vec<f64>, Vec<f64>)>,
    /// What the stage applies, in words (for the summary).
    pub applied: Vec<String>,
    /// What it applies because the mapping declares it (a surface's `shift_s`), in words (the
    /// summary's `mapping applied: …` warnings, [`Corrections::with_mapping`]).
    pub mapped: Vec<String>,
    /// The channels whose corrections are not applied, each with why ([`plausible`]).
    pub refused: Vec<String>,
    /// The corrections the record does not determine, left out: within [`DETERMINED_SIGMAS`] of none.
    pub left_out: Vec<String>,
    /// The channels whose corrections were refused, or whose time shift failed on held-out
    /// data.
    pub refused_channels: Vec<Channel>,
    /// The channels whose time shift the check estimated.
    pub checked: Vec<Channel>,
    /// The surfaces the check found leading their response (`compat.json` `input_leads`), for
    /// the job to undo where the mapping declares no shift of its own.
    pub leads: Vec<InputLead>,
}

/// A surface's measured lead over the response it drives (`compat.json` `input_leads`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InputLead {
    /// The surface's mapping key (`de`, `da`, `dr`).
    pub channel: String,
    /// The lead, s (> 0: the recorded surface acts later than recorded).
    pub lead_s: f64,
    /// Its σ, s: the 95 % interval's half-width over 1.96 (the timing search's Cramér–Rao
    /// bound).
    pub lead_sigma_s: f64,
}

/// A correction is applied only where the check determines it: its distance from no
/// correction (bias 0, scale 1, shift 0) at least [`DETERMINED_SIGMAS`] of its σ. One within
/// that is indistinguishable from none on this record; applying it would add the check's noise
/// to the data. Rows without a σ (a hand-written `compat.json`) are taken as given. Clears
/// each undetermined value in `entries` and returns them in words (`q_rad_s bias +1.0e-4 ±
/// 2.0e-4`).
fn undetermined(rows: &[ChannelSummary], entries: &mut [Entry]) -> Vec<String> {
    let mut out = Vec::new();
    for (row, e) in rows.iter().zip(entries.iter_mut()) {
        let parts = [
            ("bias", &mut e.1, row.bias_sigma, 0.0),
            ("scale", &mut e.2, row.scale_sigma, 1.0),
            ("time shift", &mut e.3, row.time_shift_sigma_s, 0.0),
        ];
        for (what, value, sigma, none) in parts {
            if let (Some(v), Some(s)) = (*value, sigma)
                && (v - none).abs() < DETERMINED_SIGMAS * s
            {
                out.push(format!("{} {what} {v:+.2e} ± {s:.1e}", row.name));
                *value = None;
            }
        }
    }
    out
}

/// A correction must lie this many σ from none to be applied (closer, it is indistinguishable from none on the record and is left out).
pub const DETERMINED_SIGMAS: f64 = 2.0;

/// What `replay --compat` reads of a `compat.json`: its channel rows and reconstructed air
/// data (the other keys are for people).
#[derive(Deserialize)]
struct CompatFile {
    /// The record(s) the check was made on, as `compat` writes them (`a.csv, b.csv`).
    #[serde(default)]
    file: Option<String>,
    channels: Vec<ChannelSummary>,
    #[serde(default)]
    reconstructed: Vec<ReconstructedSummary>,
    /// The AHRS's time constant, s, when the check estimated it.
    #[serde(default)]
    ahrs_lag_tau_s: Option<f64>,
    /// Its σ, s.
    #[serde(default)]
    ahrs_lag_tau_sigma_s: Option<f64>,
    /// Each correction judged on held-out data (absent in older files: none refused for it).
    #[serde(default)]
    held_out: Option<HeldOutSummary>,
    /// The surfaces' measured leads (absent in older files: none).
    #[serde(default)]
    input_leads: Vec<InputLead>,
}

impl CompatFile {
    /// The AHRS lag and its σ, when the file has one.
    fn lag(&self) -> Option<(f64, Option<f64>)> {
        self.ahrs_lag_tau_s.map(|t| (t, self.ahrs_lag_tau_sigma_s))
    }
}

/// The file name of a path as given (`dir/a.csv` → `a.csv`).
fn base_name(path: &str) -> &str {
    Path::new(path.trim()).file_name().and_then(|n| n.to_str()).unwrap_or(path.trim())
}

/// Whether a check made on `made_on` (its `file` key) belongs to `records`: one of their file
/// names among the check's. `Err` with why not, naming the key.
fn check_provenance(made_on: Option<&str>, records: &[String]) -> Result<(), String> {
    let Some(made_on) = made_on else {
        return Err("it has no `file` key, so nothing says which record it was made on: run `aeroident compat` on this record (its biases, time shifts and reconstructed sideslip are one record's)".into());
    };
    let theirs: Vec<&str> = made_on.split(", ").map(base_name).collect();
    if records.iter().any(|r| theirs.contains(&base_name(r))) {
        return Ok(());
    }
    let ours: Vec<&str> = records.iter().map(|r| base_name(r)).collect();
    Err(format!(
        "its `file` is `{made_on}`, not this record ({}): a check's biases, time shifts and reconstructed sideslip are its own record's; run `aeroident compat` on this record (or, for the same record renamed, edit `file`)",
        ours.join(", ")
    ))
}

/// One channel's row: `(channel, bias, scale, time shift)`.
type Entry = (Channel, Option<f64>, Option<f64>, Option<f64>);

impl Corrections {
    /// The summary warnings that say what was applied (`mapping applied: …`, one per item of
    /// [`Corrections::mapped`]; `compat applied: …`, one per item of
    /// [`Corrections::applied`]) and what was refused (`compat refused: …`, a
    /// [`WarningKind::RefusedCorrection`] a face repeats after the results).
    pub fn warnings(&self) -> impl Iterator<Item = Warning> + '_ {
        let mapped = self.mapped.iter().map(|a| Warning::from(format!("mapping applied: {a}")));
        let applied = self.applied.iter().map(|a| Warning::from(format!("compat applied: {a}")));
        let refused = self
            .refused
            .iter()
            .map(|r| Warning::new(WarningKind::RefusedCorrection, format!("compat refused: {r}")));
        let left_out = (!self.left_out.is_empty()).then(|| {
            Warning::from(format!(
                "compat left out, not determined by the record (within {DETERMINED_SIGMAS} σ of none): {}",
                self.left_out.join(", ")
            ))
        });
        mapped.chain(applied).chain(refused).chain(left_out)
    }

    /// The corrections of a `compat.json` file.
    ///
    /// # Errors
    /// [`RecordError::Option`] naming the file: unreadable, not a compat.json, an unknown
    /// channel, a scale that is not positive, or a non-finite number.
    pub fn from_json(path: &Path) -> Result<Self, RecordError> {
        let (file, bad) = Self::read_json(path)?;
        let mut c =
            Self::of_rows(&file.channels, file.lag(), &file.reconstructed, file.held_out.as_ref())
                .map_err(bad)?;
        c.leads = file.input_leads;
        Ok(c)
    }

    /// The corrections of a `compat.json` for the records `records` (file names as given):
    /// refused when its `file` names none of them (by file name). For a live feed or
    /// stdin (`records` empty) the channel corrections apply (a sensor's biases carry to the
    /// next flight) but the reconstructed sideslip, another record's time series, does not.
    ///
    /// # Errors
    /// As [`Corrections::from_json`], and a check made on another record.
    pub fn from_json_for(path: &Path, records: &[String]) -> Result<Self, RecordError> {
        let (file, bad) = Self::read_json(path)?;
        if records.is_empty() {
            let held = file.held_out.as_ref();
            let mut c = Self::of_rows(&file.channels, file.lag(), &[], held).map_err(bad)?;
            c.leads = file.input_leads.clone();
            if file.reconstructed.iter().any(|r| !r.t_s.is_empty()) {
                c.refused.push("beta_rad: the sideslip reconstructed on the check's record is that record's time series: not applied to a live feed".into());
            }
            return Ok(c);
        }
        check_provenance(file.file.as_deref(), records).map_err(&bad)?;
        let mut c =
            Self::of_rows(&file.channels, file.lag(), &file.reconstructed, file.held_out.as_ref())
                .map_err(bad)?;
        c.leads = file.input_leads;
        Ok(c)
    }

    /// A `compat.json` parsed, and the error maker naming it.
    fn read_json(
        path: &Path,
    ) -> Result<(CompatFile, impl Fn(String) -> RecordError + '_), RecordError> {
        let bad = move |reason: String| RecordError::Option {
            option: "compat",
            reason: format!("{}: {reason}", path.display()),
        };
        let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
        let file: CompatFile = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
        Ok((file, bad))
    }

    /// The corrections of a check's channel rows, AHRS lag `(τ, σ)` and reconstructed air
    /// data; a correction that failed the held-out judgement `held` is refused with why.
    pub(crate) fn of_rows(
        rows: &[ChannelSummary],
        lag: Option<(f64, Option<f64>)>,
        rec: &[ReconstructedSummary],
        held: Option<&HeldOutSummary>,
    ) -> Result<Self, String> {
        let mut entries: Vec<Entry> = Vec::new();
        for c in rows {
            let ch = Channel::from_name(&c.name)
                .ok_or_else(|| format!("unknown channel `{}`", c.name))?;
            if !c.unit.is_empty() && c.unit != ch.unit() {
                return Err(format!(
                    "`{}` has `unit` `{}`: a check's corrections are in the channel's SI unit `{}`, and a changed unit is not converted",
                    c.name,
                    c.unit,
                    ch.unit()
                ));
            }
            if entries.iter().any(|e| e.0 == ch) {
                return Err(format!(
                    "`{}` has two rows: each channel's corrections are one row",
                    c.name
                ));
            }
            entries.push((ch, c.bias, c.scale, c.time_shift_s));
        }
        // A check with a sideslip row fitted the record's own β: its reconstruction is for the
        // report, and the stage fills nothing (saying so would claim a sideslip it adds).
        let measured = rows.iter().any(|r| r.name == Channel::Beta.name());
        let usable = |r: &&ReconstructedSummary| r.beta_determined && !measured;
        let beta = rec.iter().filter(usable).map(|r| (r.t_s.clone(), r.beta_rad.clone())).collect();
        let checked = entries.iter().filter(|e| e.3.is_some()).map(|e| e.0).collect();
        let left_out = undetermined(rows, &mut entries);
        let (failed, untimed) = held.map(|h| h.refuse(&mut entries)).unwrap_or_default();
        let mut c = Self::new(entries, beta)?;
        c.refused.extend(failed);
        c.refused_channels.extend(untimed);
        if rec.iter().any(|r| !r.beta_determined && !r.t_s.is_empty()) {
            c.refused_channels.push(Channel::Beta);
            c.refused.push("beta_rad: the reconstructed sideslip is not used: without a sideslip channel the check could not determine its initial side velocity and the ay bias (too little roll) and fixed them at 0; the fits keep β as an unmeasured state".into());
        }
        c.left_out = left_out;
        c.checked = checked;
        match (lag, held.and_then(HeldOutSummary::lag_refusal)) {
            (Some((tau, _)), Some(why)) if tau.is_finite() => c.refused.push(why),
            (Some((tau, sigma)), _) => c.set_lag(tau, sigma)?,
            (None, _) => {}
        }
        Ok(c)
    }

    /// The AHRS lag `tau` (s) with its σ: applied when determined ([`DETERMINED_SIGMAS`]) and
    /// plausible ([`plausible_lag`]), else said why not.
    fn set_lag(&mut self, tau: f64, sigma: Option<f64>) -> Result<(), String> {
        if !tau.is_finite() {
            return Err("ahrs_lag_tau_s must be finite".into());
        }
        if let Some(s) = sigma.filter(|s| tau.abs() < DETERMINED_SIGMAS * s) {
            self.left_out.push(format!("AHRS lag {tau:+.2e} ± {s:.1e} s"));
            return Ok(());
        }
        match plausible_lag(tau) {
            Err(why) => self.refused.push(format!("AHRS lag: {why}")),
            Ok(()) if tau > 0.0 => {
                self.lag_s = Some(tau);
                self.applied.push(format!("every channel not from the AHRS (accelerometers, air data, surfaces, thrust) passed through the AHRS's first-order filter, τ = {tau:.3} s, so that all share its lag"));
            }
            Ok(()) => {}
        }
        Ok(())
    }

    fn new(entries: Vec<Entry>, beta: Vec<(Vec<f64>, Vec<f64>)>) -> Result<Self, String> {
        let checked = entries.iter().filter(|e| e.3.is_some()).map(|e| e.0).collect();
        let mut c = Corrections { beta, checked, ..Self::default() };
        for (ch, bias, scale, shift) in entries {
            let (b, k) = (bias.unwrap_or(0.0), scale.unwrap_or(1.0));
            if !(b.is_finite() && k.is_finite() && k > 0.0 && shift.is_none_or(f64::is_finite)) {
                return Err(format!(
                    "{}: bias, scale and time shift must be finite, the scale > 0",
                    ch.name()
                ));
            }
            if let Err(why) = plausible(ch, b, k, shift) {
                c.refused.push(format!("{}: {why}", ch.name()));
                c.refused_channels.push(ch);
                continue;
            }
            let k = c.flow_angle_scale(ch, k);
            if ch != Channel::Vt && (b != 0.0 || k != 1.0) {
                c.affine.push((ch, b, k));
                // Name only what is removed: a scale factor the check left out is not one.
                let removed = format!("bias {b:+.4e} {} removed", ch.unit());
                let divided = format!("scale {k:.4} divided out");
                let what = match (b != 0.0, k != 1.0) {
                    (true, true) => format!("{removed}, {divided}"),
                    (true, false) => removed,
                    _ => divided,
                };
                c.applied.push(format!("{}: {what}", ch.name()));
            }
            if let Some(t) = shift.filter(|t| *t != 0.0) {
                c.shifts.push((ch, t));
                c.applied.push(format!("{}: read {t:+.3} s later (its time shift)", ch.name()));
            }
        }
        if c.beta.iter().any(|(t, _)| !t.is_empty()) {
            c.applied.push("beta_rad: the reconstructed sideslip where the record has none".into());
        }
        Ok(c)
    }

    /// The scale factor `k` of channel `ch` to divide out: 1 for a flow angle, whose scale
    /// factor (local upwash or sidewash, the vane's calibration) would turn every α or β
    /// derivative into one per radian of the kinematic angle instead of the vane's, which the
    /// units of the results do not say; it is listed instead, with how to apply it on request
    /// (the mapping's `scale`, which then defines the channel).
    fn flow_angle_scale(&mut self, ch: Channel, k: f64) -> f64 {
        if !matches!(ch, Channel::Alpha | Channel::Beta) || k == 1.0 {
            return k;
        }
        self.refused.push(format!(
            "{}: scale {k:.4} not divided out: a flow angle's scale factor (upwash, the vane's calibration) would make its derivatives per radian of the kinematic angle, not of the recorded one; to apply it, multiply the channel's `scale` in the mapping by {:.4}",
            ch.name(),
            1.0 / k
        ));
        1.0
    }

    /// Whether the check judged channel `ch`'s timing and its result stands (its time shift
    /// was estimated, applied or found indistinguishable from none, and not refused).
    pub fn timing_checked(&self, ch: Channel) -> bool {
        self.checked.contains(&ch) && !self.refused_channels.contains(&ch)
    }

    /// The largest lag the stage undoes (its delay), s.
    fn lead_s(&self) -> f64 {
        self.all_shifts().fold(0.0, f64::max)
    }

    /// The largest lead it undoes (the history it keeps), s.
    fn history_s(&self) -> f64 {
        self.all_shifts().map(|t| -t).fold(0.0, f64::max)
    }

    fn all_shifts(&self) -> impl Iterator<Item = f64> + '_ {
        self.shifts.iter().map(|s| s.1).chain(self.input_shifts.iter().map(|s| s.1))
    }

    /// The same corrections with control surface `key` (`de`, `da`, `dr`) read `shift_s`
    /// later as well (`shift_s < 0`: earlier; linearly interpolated, held at a manoeuvre's
    /// ends). Undoes a surface's measured lead over its response (a commanded surface: its
    /// actuator's lag) for a refit that asks what the lead moves.
    ///
    /// # Errors
    /// A key that is no control surface, or a shift that is not finite or beyond
    /// ±[`MAX_SHIFT_S`], in words.
    pub fn with_input_shift(mut self, key: &str, shift_s: f64) -> Result<Self, String> {
        let surface = aeroident_io::Channel::ALL
            .iter()
            .copied()
            .find(|&c| c.key() == key && super::actuated::is_surface(c))
            .ok_or_else(|| format!("`{key}` is no control surface (de, da, dr)"))?;
        self.add_input_shift(surface, shift_s)?;
        self.applied.push(format!("{key}: read {shift_s:+.3} s later (its measured lead undone)"));
        Ok(self)
    }

    /// Surface `surface` read `shift_s` later than it already is: added to its shift, so a
    /// refit's measured lead adds to the mapping's `shift_s` rather than replacing it (the lead
    /// was measured on the shifted record).
    ///
    /// # Errors
    /// A total that is not finite or beyond ±[`MAX_SHIFT_S`], in words.
    fn add_input_shift(
        &mut self,
        surface: aeroident_io::Channel,
        shift_s: f64,
    ) -> Result<(), String> {
        let own = self.input_shifts.iter().position(|s| s.0 == surface);
        let total = own.map_or(0.0, |k| self.input_shifts[k].1) + shift_s;
        if !total.is_finite() || total.abs() > MAX_SHIFT_S {
            return Err(format!(
                "an input shift of {shift_s} s gives `{}` a shift of {total} s, beyond the ±{MAX_SHIFT_S} s a lag plausibly reaches",
                surface.key()
            ));
        }
        match own {
            Some(k) => self.input_shifts[k].1 = total,
            None => self.input_shifts.push((surface, total)),
        }
        Ok(())
    }

    /// The same corrections with the surfaces' time shifts `mapping` declares
    /// ([`aeroident_io::Mapping::input_shifts`]: surface `ch` with `shift_s = S` is used at
    /// time `t` as logged at `t − S`), each said in [`Corrections::mapped`]. A job applies
    /// them with any compatibility corrections, so every fit of the record, its model
    /// selection and its refits (timing, sample timing, cross-check, validation) see the
    /// same surfaces.
    ///
    /// The stage comes after the actuator of a commanded surface (`actuator = { … }`), so the
    /// deflection is shifted, not the command. The actuator is time-invariant (its lag and
    /// limits do not depend on t) and steps on the record's own samples, so the two orders
    /// agree exactly for a shift of whole samples, and for any shift without rate or position
    /// limits (both linear), except over the first and last `|S|` of each manoeuvre, where
    /// the actuator's start and the held ends differ (see the test
    /// `a_mapped_shift_after_the_actuator_is_the_shift_of_the_command`).
    ///
    /// # Errors
    /// A total shift beyond ±[`MAX_SHIFT_S`] (the mapping's own is checked against the same
    /// bound, [`aeroident_io::mapping::MAX_INPUT_SHIFT_S`]), in words naming the mapping.
    pub fn with_mapping(mut self, mapping: &aeroident_io::Mapping) -> Result<Self, String> {
        for (ch, shift_s) in mapping.input_shifts() {
            // The stage reads a channel `τ` later at `t + τ`; the mapping's S means `t − S`.
            self.add_input_shift(ch, -shift_s).map_err(|e| format!("{}: {e}", mapping.file))?;
            let (moved, sign) = if shift_s > 0.0 { ("delayed", '−') } else { ("advanced", '+') };
            let by = shift_s.abs();
            self.mapped.push(format!(
                "{}: shift_s = {shift_s:+.4} s, the surface {moved} by {by:.4} s (the value used at t is the logged one at t {sign} {by:.4} s)",
                ch.key()
            ));
        }
        Ok(self)
    }

    /// The same corrections with the rate gyros (`p`, `q`, `r`) read `shift_s` later than
    /// they already are (added to any time shift the corrections give them; `shift_s < 0`:
    /// earlier). A skew between the gyros and the other channels, for a refit that asks what
    /// a skew the record cannot rule out moves ([`crate::replay::sample_timing`]).
    ///
    /// # Errors
    /// A shift that is not finite or, with the gyros' own, beyond ±[`MAX_SHIFT_S`], in words.
    pub fn with_rate_skew(mut self, shift_s: f64) -> Result<Self, String> {
        for ch in [Channel::P, Channel::Q, Channel::R] {
            let own = self.shifts.iter().position(|s| s.0 == ch);
            let total = own.map_or(0.0, |k| self.shifts[k].1) + shift_s;
            if !total.is_finite() || total.abs() > MAX_SHIFT_S {
                return Err(format!(
                    "a gyro skew of {shift_s} s gives {} a shift of {total} s, beyond the ±{MAX_SHIFT_S} s a lag plausibly reaches",
                    ch.name()
                ));
            }
            match own {
                Some(k) => self.shifts[k].1 = total,
                None => self.shifts.push((ch, total)),
            }
        }
        self.applied.push(format!("p, q, r: read {shift_s:+.4} s later (the sample-timing test)"));
        Ok(self)
    }

    /// The warning when the reconstructed sideslip, listed as applied, left samples without β:
    /// `cover` is (samples without a sideslip of their own, those it gave one). The check's
    /// manoeuvres are its time spans; a record replayed on other windows, or another record's
    /// `compat.json`, falls outside them, and the fit then lacks β there. `None` when it
    /// covered every such sample.
    pub fn cover_warning(&self, cover: (usize, usize)) -> Option<String> {
        let (wanted, filled) = cover;
        if self.beta.is_empty() || filled == wanted {
            return None;
        }
        let spans: Vec<String> = self
            .beta
            .iter()
            .filter_map(|(t, _)| Some(format!("{:.2}–{:.2} s", t.first()?, t.last()?)))
            .collect();
        Some(format!(
            "beta_rad: the reconstructed sideslip covers {filled} of the {wanted} samples without a sideslip (the check's manoeuvres span {}): the others have no β; run the check on the windows replayed",
            spans.join(", ")
        ))
    }

    /// The reconstructed sideslip at `t_s`, if a manoeuvre of the check spans it.
    fn beta_at(&self, t_s: f64) -> Option<f64> {
        let (t, b) = self.beta.iter().find(|(t, b)| {
            t.len() == b.len()
                && t.first().is_some_and(|&a| a <= t_s)
                && t.last().is_some_and(|&z| t_s <= z)
        })?;
        Some(interpolate(t, b, t_s))
    }
}

/// The record's events with [`Corrections`] applied to every sample (module doc).
pub struct Corrected<I> {
    inner: I,
    corr: Corrections,
    /// The current manoeuvre's raw samples: history, then those not yet emitted.
    window: VecDeque<(u64, AirDataSample)>,
    /// Index in `window` of the next sample to emit.
    next: usize,
    out: VecDeque<Result<RecordEvent, FlightDataError>>,
    done: bool,
    /// The AHRS lag's filter of the other channels.
    lag: LagFilter,
    /// Samples without a sideslip of their own, and how many of them the reconstruction gave
    /// one ([`Corrected::sideslip_cover`]).
    cover: SideslipCover,
}

/// Samples without a sideslip of their own, and how many of them the check's reconstructed
/// sideslip gave one, shared with whoever reads the notes after the events.
pub type SideslipCover = std::sync::Arc<std::sync::Mutex<(usize, usize)>>;

impl<I> Corrected<I> {
    /// The stage over the events `inner`.
    pub fn new(inner: I, corr: Corrections) -> Self {
        Self {
            inner,
            corr,
            window: VecDeque::new(),
            next: 0,
            out: VecDeque::new(),
            done: false,
            lag: LagFilter::default(),
            cover: SideslipCover::default(),
        }
    }

    /// How much of the record the reconstructed sideslip covered so far (samples without β,
    /// those given one), shared: read it after the events ([`Corrections::cover_warning`]).
    pub fn sideslip_cover(&self) -> SideslipCover {
        self.cover.clone()
    }

    /// Emits every sample the record has gone far enough past (all of them with `flush`), and
    /// drops the history no later sample needs.
    fn emit(&mut self, flush: bool) {
        let newest = self.window.back().map_or(f64::NEG_INFINITY, |s| s.1.t_s);
        while self.next < self.window.len()
            && (flush || self.window[self.next].1.t_s + self.corr.lead_s() <= newest)
        {
            let (row, mut sample) = (self.window[self.next].0, self.corrected(self.next));
            if let Some(tau) = self.corr.lag_s {
                self.lag.apply(&mut sample, tau);
            }
            self.out.push_back(Ok(RecordEvent::Sample { row, sample }));
            self.next += 1;
        }
        let first_needed =
            self.window.get(self.next).map_or(newest, |s| s.1.t_s) - self.corr.history_s();
        while self.next > 1 && self.window[1].1.t_s <= first_needed {
            self.window.pop_front();
            self.next -= 1;
        }
    }

    /// Channel `ch` of the window at time `at_s` (as `interpolate` over the window: linear
    /// between the two samples around it, held beyond its ends), heading the short way round
    /// ±π; `None` when a sample it needs lacks the channel (the sample is then left as read).
    /// Only the two neighbours are read: this runs for every sample and shifted channel.
    fn at(&self, ch: Channel, at_s: f64) -> Option<f64> {
        let (ya, yb, f) = self.around(at_s, |s| ch.of(s))?;
        Some(match ch {
            Channel::Psi => wrap(ya + f * wrap(yb - ya)),
            _ => ya + f * (yb - ya),
        })
    }

    /// `read` of the two samples of the window around `at_s` and the fraction of the way from
    /// the first to the second (both the end sample, fraction 0, beyond the window's ends).
    fn around(
        &self,
        at_s: f64,
        read: impl Fn(&AirDataSample) -> Option<f64>,
    ) -> Option<(f64, f64, f64)> {
        let w = &self.window;
        let k = w.partition_point(|s| s.1.t_s <= at_s);
        if k == 0 || k >= w.len() {
            let y = read(&w[k.min(w.len() - 1)].1)?;
            return Some((y, y, 0.0));
        }
        let (a, b) = (&w[k - 1].1, &w[k].1);
        Some((read(a)?, read(b)?, (at_s - a.t_s) / (b.t_s - a.t_s)))
    }

    /// Sample `k` of the window, corrected.
    fn corrected(&self, k: usize) -> AirDataSample {
        let mut s = self.window[k].1;
        for &(ch, tau) in &self.corr.shifts {
            if let Some(v) = self.at(ch, s.t_s + tau) {
                ch.set(&mut s, v);
            }
        }
        for &(ch, tau) in &self.corr.input_shifts {
            let moved = self.around(s.t_s + tau, |x| super::actuated::surface_value(x, ch));
            if let Some((ya, yb, f)) = moved {
                *super::actuated::surface(&mut s, ch) = Some(ya + f * (yb - ya));
            }
        }
        for &(ch, b, k) in &self.corr.affine {
            if let Some(x) = ch.of(&s) {
                ch.set(&mut s, (x - b) / k);
            }
        }
        if s.beta_rad.is_none() && !self.corr.beta.is_empty() {
            let filled = self.corr.beta_at(s.t_s);
            s.beta_rad = filled;
            let mut c = self.cover.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            c.0 += 1;
            c.1 += usize::from(filled.is_some());
        }
        s
    }
}

impl<I: Iterator<Item = Result<RecordEvent, FlightDataError>>> Iterator for Corrected<I> {
    type Item = Result<RecordEvent, FlightDataError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if let Some(e) = self.out.pop_front() {
                return Some(e);
            }
            if self.done {
                return None;
            }
            match self.inner.next() {
                None => {
                    self.emit(true);
                    self.done = true;
                }
                Some(Ok(RecordEvent::Sample { row, sample })) => {
                    self.window.push_back((row, sample));
                    self.emit(false);
                }
                Some(Ok(gap @ RecordEvent::Gap { .. })) => {
                    // The manoeuvre ends: its last samples leave (held at its end), then the gap.
                    self.emit(true);
                    self.window.clear();
                    self.next = 0;
                    self.lag = LagFilter::default();
                    self.out.push_back(Ok(gap));
                }
                Some(other) => self.out.push_back(other),
            }
        }
    }
}

/// The AHRS lag's first-order filter of every channel not from the AHRS (module doc), one
/// state per field: `(time, input, output)` of its last sample, `None` before a manoeuvre's
/// first sample with the field (where it starts in steady state).
#[derive(Default)]
struct LagFilter {
    state: [Option<(f64, f64, f64)>; LAGGED_FIELDS],
}

/// How many fields [`other_channels`] visits.
const LAGGED_FIELDS: usize = 15;

impl LagFilter {
    /// Sample `s` with its non-AHRS channels through the filter of time constant `tau_s`.
    fn apply(&mut self, s: &mut AirDataSample, tau_s: f64) {
        let t = s.t_s;
        let state = &mut self.state;
        other_channels(s, |i, v| {
            let Some(x) = v else {
                state[i] = None;
                return;
            };
            let y = match state[i] {
                Some((t0, u0, y0)) if t > t0 => {
                    aeroident_estimators::compat::lag_step(y0, u0, *x, t - t0, tau_s)
                }
                Some((_, _, y0)) => y0,
                None => *x,
            };
            state[i] = Some((t, *x, y));
            *x = y;
        });
    }
}

/// Calls `f` with an index and each channel of `s` that does not come from an AHRS (the rates,
/// their derivatives and the attitudes do): airspeed, α, q̄, β, α̇, the accelerometers, the
/// surfaces, thrust, throttle, thrust moment and density (`None` where not recorded).
fn other_channels(s: &mut AirDataSample, mut f: impl FnMut(usize, Option<&mut f64>)) {
    f(0, Some(&mut s.vt_mps));
    f(1, Some(&mut s.alpha_rad));
    f(2, Some(&mut s.qbar_pa));
    let optional = [
        &mut s.beta_rad,
        &mut s.alphadot_rad_s,
        &mut s.ax_mps2,
        &mut s.ay_mps2,
        &mut s.az_mps2,
        &mut s.de_rad,
        &mut s.da_rad,
        &mut s.dr_rad,
        &mut s.thrust_n,
        &mut s.throttle,
        &mut s.thrust_moment_nm,
        &mut s.rho_kgpm3,
    ];
    for (i, v) in optional.into_iter().enumerate() {
        f(3 + i, v.as_mut());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t: f64) -> AirDataSample {
        AirDataSample {
            t_s: t,
            vt_mps: 50.0,
            // α lags a sine by 0.2 s and carries a bias of 0.01 rad and a scale of 1.05.
            alpha_rad: 1.05 * (0.5 * (t - 0.2)).sin() * 0.1 + 0.01,
            q_rad_s: Some(0.003 + (0.5 * t).cos()),
            ..Default::default()
        }
    }

    fn events(ts: &[f64], first_row: u64) -> Vec<Result<RecordEvent, FlightDataError>> {
        ts.iter()
            .enumerate()
            .map(|(i, &t)| Ok(RecordEvent::Sample { row: first_row + i as u64, sample: sample(t) }))
            .collect()
    }

    /// Corrections beyond what a sensor plausibly needs are not applied, channel by channel,
    /// and the warnings say which and why: a 92° α bias (a check that took in a taxi segment), a
    /// 30-s α shift (0.30 mistyped in a hand-edited compat.json), a 1 g a_z bias (load factor
    /// mapped as specific force), a gyro scale of 2; the plausible ones beside them (an
    /// accelerometer bias of 0.15 m/s², a 0.2-s vane lag, a gyro bias of 0.003 rad/s) are.
    #[test]
    fn errors_implausible_corrections_are_refused_not_applied() {
        let c = Corrections::new(
            vec![
                (Channel::Alpha, Some(1.6), None, None),
                (Channel::Beta, None, None, Some(30.0)),
                (Channel::Az, Some(9.81), None, None),
                (Channel::P, None, Some(2.0), None),
                (Channel::Ax, Some(0.15), None, None),
                (Channel::Theta, None, None, Some(0.2)),
                (Channel::Q, Some(0.003), None, None),
            ],
            Vec::new(),
        )
        .unwrap();
        let applied: Vec<Channel> = c.affine.iter().map(|a| a.0).collect();
        assert_eq!(applied, [Channel::Ax, Channel::Q]);
        assert_eq!(c.shifts, [(Channel::Theta, 0.2)]);
        let refused: Vec<&str> = c.refused.iter().map(|r| r.split(':').next().unwrap()).collect();
        assert_eq!(refused, ["alpha_rad", "beta_rad", "az_mps2", "p_rad_s"]);
        assert!(
            c.refused[0].contains("bias +1.6000e0 rad beyond the ±0.175 a flow angle"),
            "{}",
            c.refused[0]
        );
        assert!(
            c.refused[1].contains("time shift +30.000 s beyond the ±0.5 s"),
            "{}",
            c.refused[1]
        );
        assert!(
            c.refused[3].contains("scale 2.0000 outside the 0.8–1.25 a gyro"),
            "{}",
            c.refused[3]
        );
        let refused_kind = c.warnings().filter(|w| w.kind == WarningKind::RefusedCorrection);
        assert_eq!(refused_kind.count(), 4, "the refusals are repeated after the results");
        let warnings: Vec<String> = c.warnings().map(|w| w.text).collect();
        assert_eq!(warnings.iter().filter(|w| w.starts_with("compat refused: ")).count(), 4);
        assert_eq!(warnings.iter().filter(|w| w.starts_with("compat applied: ")).count(), 3);
    }

    /// A heading that turns through ±π, read 0.05 s later: each sample between two of a 0.1 s
    /// grid takes the mean of its neighbours the short way round (near ±π, never near 0), and
    /// a sample without heading leaves only its own neighbours uncorrected.
    #[test]
    fn a_shifted_heading_is_interpolated_across_plus_minus_pi() {
        use core::f64::consts::PI;
        let corr =
            Corrections::new(vec![(Channel::Psi, None, None, Some(0.05))], Vec::new()).unwrap();
        let psi = |k: usize| wrap(PI - 0.3 + 0.1 * k as f64);
        let input: Vec<_> = (0..8)
            .map(|k| {
                let mut s = AirDataSample { t_s: k as f64 * 0.1, ..Default::default() };
                s.psi_rad = (k != 6).then(|| psi(k));
                Ok(RecordEvent::Sample { row: k as u64, sample: s })
            })
            .collect();
        let out: Vec<RecordEvent> =
            Corrected::new(input.into_iter(), corr).map(Result::unwrap).collect();
        let got = |k: usize| match &out[k] {
            RecordEvent::Sample { sample, .. } => sample.psi_rad,
            e => panic!("{e:?}"),
        };
        for k in 0..5 {
            let want = wrap(PI - 0.25 + 0.1 * k as f64);
            let v = got(k).unwrap();
            assert!(wrap(v - want).abs() < 1e-12, "{k}: {v} vs {want}");
        }
        assert_eq!(got(5), Some(psi(5)), "its later neighbour has no heading: left as read");
        assert_eq!(got(6), None);
    }

    /// The lag and bias of α and the bias and scale of q are undone (α within the linear
    /// interpolation's error of the 0.1 s grid, 1e-4 rad, except the last 0.2 s, held), every
    /// sample leaves once with its time stamp and row, and a gap flushes the manoeuvre. α's
    /// scale factor is not divided out (its derivatives would change unit) but listed with
    /// the mapping's scale that applies it.
    #[test]
    fn lags_biases_and_scales_are_undone_sample_by_sample() {
        let corr = Corrections::new(
            vec![
                (Channel::Alpha, Some(0.01), Some(1.05), Some(0.2)),
                (Channel::Q, Some(0.003), Some(0.97), None),
            ],
            Vec::new(),
        )
        .unwrap();
        assert_eq!(corr.applied.len(), 3, "{:?}", corr.applied);
        assert!(corr.applied[0].ends_with("removed"), "{:?}", corr.applied);
        assert!(corr.applied[2].contains("scale 0.9700 divided out"), "{:?}", corr.applied);
        assert!(corr.refused[0].contains("by 0.9524"), "{:?}", corr.refused);
        let ts: Vec<f64> = (0..100).map(|k| k as f64 * 0.1).collect();
        let mut input = events(&ts[..50], 0);
        input.push(Ok(RecordEvent::Gap { row: 50, dt_s: 1.0, nominal_dt_s: 0.1 }));
        input.extend(events(&ts[50..], 50));
        let out: Vec<RecordEvent> =
            Corrected::new(input.into_iter(), corr).map(Result::unwrap).collect();
        assert_eq!(out.len(), 101);
        assert!(matches!(out[50], RecordEvent::Gap { row: 50, .. }));
        let samples: Vec<(u64, AirDataSample)> = out
            .into_iter()
            .filter_map(|e| match e {
                RecordEvent::Sample { row, sample } => Some((row, sample)),
                _ => None,
            })
            .collect();
        for (k, (row, s)) in samples.iter().enumerate() {
            assert_eq!(*row, k as u64);
            assert_eq!(s.t_s, ts[k]);
            assert!((s.q_rad_s.unwrap() - (0.5 * s.t_s).cos() / 0.97).abs() < 1e-12);
            let last_of_manoeuvre = if k < 50 { ts[49] } else { ts[99] };
            if s.t_s + 0.2 <= last_of_manoeuvre + 1e-9 {
                let want = 1.05 * (0.5 * s.t_s).sin() * 0.1;
                assert!(
                    (s.alpha_rad - want).abs() < 1e-4,
                    "t {}: {} vs {want}",
                    s.t_s,
                    s.alpha_rad
                );
            }
        }
    }

    /// A gyro that lags by 0.15 s with a bias (an AHRS's rate) is read 0.15 s later and its
    /// bias removed: the pitch rate of a sine within the linear interpolation's error of the
    /// 0.05 s grid (2e-4 rad/s), except the last 0.15 s, held; the stage says so.
    #[test]
    fn a_lagging_gyro_is_read_later() {
        let corr = Corrections::new(vec![(Channel::Q, Some(0.003), None, Some(0.15))], Vec::new())
            .unwrap();
        assert_eq!(
            corr.applied,
            [
                "q_rad_s: bias +3.0000e-3 rad/s removed",
                "q_rad_s: read +0.150 s later (its time shift)"
            ]
        );
        let q = |t: f64| 0.2 * (1.3 * t).sin();
        let input: Vec<_> = (0..200)
            .map(|k| {
                let t = k as f64 * 0.05;
                let s = AirDataSample {
                    t_s: t,
                    q_rad_s: Some(q(t - 0.15) + 0.003),
                    ..Default::default()
                };
                Ok(RecordEvent::Sample { row: k as u64, sample: s })
            })
            .collect();
        for e in Corrected::new(input.into_iter(), corr) {
            let RecordEvent::Sample { sample: s, .. } = e.unwrap() else { panic!("a gap") };
            if s.t_s + 0.15 <= 199.0 * 0.05 + 1e-9 {
                let v = s.q_rad_s.unwrap();
                assert!((v - q(s.t_s)).abs() < 2e-4, "t {}: {v} vs {}", s.t_s, q(s.t_s));
            }
        }
    }

    /// A `compat.json` as `aeroident compat` writes it (extra keys, `null` where not estimated)
    /// reads back to the corrections of its rows; an unknown channel is refused naming the file
    /// and the channel.
    #[test]
    fn a_compat_json_reads_back_to_its_rows() {
        let dir =
            std::env::temp_dir().join(format!("aeroident-compat-json-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("compat.json");
        let row = |name: &str, b: &str, k: &str, t: &str| {
            format!(
                r#"{{"name": "{name}", "unit": "{}", "bias": {b}, "bias_sigma": 0.001, "scale": {k}, "scale_sigma": null, "time_shift_s": {t}, "time_shift_sigma_s": null}}"#,
                Channel::from_name(name).unwrap().unit()
            )
        };
        let text = format!(
            r#"{{"file": "x.csv", "sigma": "coloured", "channels": [{}, {}], "findings": [], "reconstructed": [{{"manoeuvre": 1, "t_s": [0.0, 1.0], "vt_mps": [50.0, 50.0], "alpha_rad": [0.1, 0.1], "beta_rad": [0.0, 0.02]}}]}}"#,
            row("alpha_rad", "0.01", "1.05", "0.2"),
            row("q_rad_s", "0.003", "null", "null")
        );
        std::fs::write(&path, text).unwrap();
        let read = Corrections::from_json(&path).unwrap();
        let want = Corrections::new(
            vec![
                (Channel::Alpha, Some(0.01), Some(1.05), Some(0.2)),
                (Channel::Q, Some(0.003), None, None),
            ],
            vec![(vec![0.0, 1.0], vec![0.0, 0.02])],
        )
        .unwrap();
        assert_eq!(read, want);
        std::fs::write(&path, r#"{"channels": [{"name": "gamma_rad", "bias": 0.1}]}"#).unwrap();
        let e = Corrections::from_json(&path).unwrap_err().to_string();
        assert!(e.contains("compat.json") && e.contains("gamma_rad"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A correction within 2σ of none is left out and listed; one beyond is applied; a row
    /// without σ (hand-written) is taken as given. A gyro or attitude leading the kinematics by
    /// more than 0.02 s is refused; a lag, and a lead of α (a vane, not an AHRS), are not.
    #[test]
    fn undetermined_corrections_and_ahrs_leads_are_not_applied() {
        let row = |name: &str, bias: f64, sigma: Option<f64>, shift: Option<f64>| ChannelSummary {
            name: name.into(),
            unit: Channel::from_name(name).unwrap().unit().into(),
            bias: Some(bias),
            bias_sigma: sigma,
            scale: None,
            scale_sigma: None,
            time_shift_s: shift,
            time_shift_sigma_s: shift.map(|_| 0.005),
        };
        let rows = [
            row("q_rad_s", 1e-4, Some(2e-4), None),
            row("p_rad_s", 1e-3, Some(2e-4), None),
            row("r_rad_s", 1e-4, None, None),
            row("theta_rad", 0.0, None, Some(-0.09)),
            row("phi_rad", 0.0, None, Some(0.12)),
            row("alpha_rad", 0.0, None, Some(-0.05)),
        ];
        let c = Corrections::of_rows(&rows, None, &[], None).unwrap();
        assert_eq!(c.left_out, ["q_rad_s bias +1.00e-4 ± 2.0e-4"]);
        let applied = c.applied.join("; ");
        assert!(
            applied.contains("p_rad_s: bias") && applied.contains("r_rad_s: bias"),
            "{applied}"
        );
        assert!(
            applied.contains("phi_rad: read +0.120 s")
                && applied.contains("alpha_rad: read -0.050 s"),
            "{applied}"
        );
        assert_eq!(c.refused.len(), 1, "{:?}", c.refused);
        assert!(
            c.refused[0].starts_with("theta_rad: time shift -0.090 s")
                && c.refused[0].contains("lead")
        );
        let w: Vec<String> = c.warnings().map(|w| w.text).collect();
        assert!(
            w.iter()
                .any(|w| w.starts_with("compat left out, not determined") && w.contains("q_rad_s")),
            "{w:?}"
        );
    }

    /// A correction that failed the held-out judgement (a rise more than three spreads above a
    /// true correction's mean) is refused with why, whatever its σ, and its channel's other
    /// corrections stand; one within its spread, or not judged, is applied; a failed time shift leaves the channel's timing
    /// unchecked; a failed AHRS lag is not applied. A `compat.json` carries the judgement.
    #[test]
    fn corrections_that_fail_on_held_out_data_are_refused() {
        let held =
            |channel: Option<&str>, correction: &str, change: f64, pieces: usize| HeldOutRow {
                channel: channel.map(str::to_string),
                correction: correction.into(),
                change_neg_log_likelihood: change,
                pieces,
                expected: -2.0,
                spread: 3.0,
                verdict: String::new(),
            };
        let summary = HeldOutSummary {
            by: "half".into(),
            pieces: 2,
            corrections: vec![
                held(Some("alpha_rad"), "time_shift", 8.5, 2),
                held(Some("alpha_rad"), "bias", 6.5, 2),
                held(Some("q_rad_s"), "bias", 40.0, 0),
                held(None, "ahrs_lag", 11.0, 2),
            ],
            notes: Vec::new(),
        };
        let rows = [
            ChannelSummary {
                name: "alpha_rad".into(),
                unit: "rad".into(),
                bias: Some(0.02),
                bias_sigma: Some(0.001),
                scale: None,
                scale_sigma: None,
                time_shift_s: Some(0.2),
                time_shift_sigma_s: Some(0.01),
            },
            ChannelSummary {
                name: "q_rad_s".into(),
                unit: "rad/s".into(),
                bias: Some(0.003),
                bias_sigma: Some(1e-4),
                scale: None,
                scale_sigma: None,
                time_shift_s: None,
                time_shift_sigma_s: None,
            },
        ];
        let c = Corrections::of_rows(&rows, Some((0.15, Some(0.01))), &[], Some(&summary)).unwrap();
        assert_eq!(c.refused.len(), 2, "{:?}", c.refused);
        assert!(c.refused[0].starts_with("alpha_rad time shift: applied to the halves held out"));
        assert!(c.refused[0].contains("rises by 8.5") && c.refused[0].contains("-2.0 ± 3.0"));
        assert!(c.refused[1].starts_with("AHRS lag: applied to the halves"), "{:?}", c.refused);
        assert_eq!(c.lag_s, None);
        assert_eq!(c.shifts, []);
        assert_eq!(c.affine, [(Channel::Alpha, 0.02, 1.0), (Channel::Q, 0.003, 1.0)]);
        assert!(!c.timing_checked(Channel::Alpha));
        let without = Corrections::of_rows(&rows, None, &[], None).unwrap();
        assert_eq!(without.shifts, [(Channel::Alpha, 0.2)]);
        assert!(without.timing_checked(Channel::Alpha));
        let dir = std::env::temp_dir().join(format!("aeroident-held-out-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("compat.json");
        let doc = serde_json::json!({"file": "a.csv", "channels": rows, "held_out": summary});
        std::fs::write(&path, doc.to_string()).unwrap();
        let read = Corrections::from_json_for(&path, &["a.csv".into()]).unwrap();
        assert_eq!((read.shifts, read.refused.len()), (Vec::new(), 1));
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A check's reconstructed sideslip over 0–1 s (β from 0 to 0.02 rad), `determined` or
    /// pinned at 0 by the check.
    fn reconstructed(determined: bool) -> ReconstructedSummary {
        ReconstructedSummary {
            manoeuvre: 1,
            t_s: vec![0.0, 1.0],
            vt_mps: vec![50.0, 50.0],
            alpha_rad: vec![0.1, 0.1],
            beta_rad: vec![0.0, 0.02],
            beta_determined: determined,
        }
    }

    /// A reconstructed sideslip whose side velocity and ay bias the check fixed at 0 is not used
    /// as a measurement: it is refused with why, and β stays unmeasured; a determined one is
    /// used (and a file without the key is taken as determined), but not on a record with its
    /// own sideslip channel.
    #[test]
    fn a_pinned_reconstructed_sideslip_is_not_a_measurement() {
        let rec = reconstructed;
        let pinned = Corrections::of_rows(&[], None, &[rec(false)], None).unwrap();
        assert!(pinned.beta.is_empty() && pinned.beta_at(0.5).is_none());
        assert!(pinned.refused[0].contains("unmeasured state"), "{:?}", pinned.refused);
        assert!(!pinned.applied.iter().any(|a| a.contains("reconstructed")));
        let used = Corrections::of_rows(&[], None, &[rec(true)], None).unwrap();
        assert!(used.refused.is_empty() && (used.beta_at(0.5).unwrap() - 0.01).abs() < 1e-12);
        // A record with its own sideslip channel (the check's `beta_rad` row) gets none.
        let vane = ChannelSummary {
            name: "beta_rad".into(),
            unit: "rad".into(),
            bias: None,
            bias_sigma: None,
            scale: None,
            scale_sigma: None,
            time_shift_s: Some(0.0),
            time_shift_sigma_s: Some(0.01),
        };
        let own = Corrections::of_rows(&[vane], None, &[rec(true)], None).unwrap();
        assert!(own.beta.is_empty() && own.beta_at(0.5).is_none());
        assert!(!own.applied.iter().any(|a| a.contains("reconstructed")), "{:?}", own.applied);
        let old: ReconstructedSummary = serde_json::from_str(
            r#"{"manoeuvre": 1, "t_s": [0.0], "vt_mps": [50.0], "alpha_rad": [0.1], "beta_rad": [0.0]}"#,
        )
        .unwrap();
        assert!(old.beta_determined);
    }

    /// A reconstructed sideslip over 0–1 s on a record of 0–2 s without β: the samples past
    /// its span get none, and the stage counts 11 of 21 covered, which the warning states with
    /// the span (it was listed as applied, and the fit then failed on `CL_beta`); a record
    /// within the span is covered whole and warns of nothing.
    #[test]
    fn a_reconstructed_sideslip_that_misses_samples_says_how_many() {
        let corr = Corrections::of_rows(&[], None, &[reconstructed(true)], None).unwrap();
        let events = |n: u32| -> Vec<Result<RecordEvent, FlightDataError>> {
            (0..n)
                .map(|k| {
                    let sample = AirDataSample { t_s: f64::from(k) * 0.1, ..Default::default() };
                    Ok(RecordEvent::Sample { row: u64::from(k), sample })
                })
                .collect()
        };
        let stage = Corrected::new(events(21).into_iter(), corr.clone());
        let cover = stage.sideslip_cover();
        let with_beta = stage
            .filter_map(|e| match e {
                Ok(RecordEvent::Sample { sample, .. }) => Some(sample.beta_rad.is_some()),
                _ => None,
            })
            .filter(|b| *b)
            .count();
        let counted = *cover.lock().unwrap();
        assert_eq!((counted, with_beta), ((21, 11), 11));
        let w = corr.cover_warning(counted).unwrap();
        assert!(w.contains("covers 11 of the 21 samples") && w.contains("0.00–1.00 s"), "{w}");
        let stage = Corrected::new(events(11).into_iter(), corr.clone());
        let cover = stage.sideslip_cover();
        stage.for_each(drop);
        let counted = *cover.lock().unwrap();
        assert_eq!(counted, (11, 11));
        assert_eq!(corr.cover_warning(counted), None);
    }

    /// A check applies to the record it was made on: its `file` must name one of the records
    /// (by file name, whatever the directory); another record's check, one without `file`, a
    /// changed `unit` and a channel given twice are refused naming the key. On a live feed the
    /// channel corrections apply and the reconstructed sideslip is refused.
    #[test]
    fn a_compat_json_applies_to_its_own_record_only() {
        let dir =
            std::env::temp_dir().join(format!("aeroident-compat-prov-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("compat.json");
        let row = |name: &str, unit: &str| {
            format!(
                r#"{{"name": "{name}", "unit": "{unit}", "bias": 0.01, "scale": null, "time_shift_s": null}}"#
            )
        };
        let rec = r#""reconstructed": [{"manoeuvre": 1, "t_s": [0.0, 1.0], "vt_mps": [50.0, 50.0], "alpha_rad": [0.1, 0.1], "beta_rad": [0.0, 0.02]}]"#;
        let write = |file: &str, rows: &[String]| {
            std::fs::write(&path, format!(r#"{{{file}"channels": [{}], {rec}}}"#, rows.join(", ")))
                .unwrap();
        };
        let ours = vec!["data/flight_a.csv".to_string()];
        write(r#""file": "/elsewhere/flight_a.csv", "#, &[row("alpha_rad", "rad")]);
        let c = Corrections::from_json_for(&path, &ours).unwrap();
        assert!(c.refused.is_empty() && c.applied.len() == 2, "{c:?}");
        let two = vec!["b.csv".to_string(), "flight_a.csv".to_string()];
        write(r#""file": "x/flight_a.csv, x/c.csv", "#, &[row("alpha_rad", "rad")]);
        assert!(Corrections::from_json_for(&path, &two).is_ok());
        write(r#""file": "flight_b.csv", "#, &[row("alpha_rad", "rad")]);
        let e = Corrections::from_json_for(&path, &ours).unwrap_err().to_string();
        assert!(e.contains("`file` is `flight_b.csv`, not this record (flight_a.csv)"), "{e}");
        write("", &[row("alpha_rad", "rad")]);
        let e = Corrections::from_json_for(&path, &ours).unwrap_err().to_string();
        assert!(e.contains("no `file` key"), "{e}");
        let live = Corrections::from_json_for(&path, &[]).unwrap();
        assert!(live.beta.is_empty() && live.applied.len() == 1, "{live:?}");
        assert!(live.refused[0].contains("not applied to a live feed"), "{live:?}");
        write(r#""file": "flight_a.csv", "#, &[row("alpha_rad", "deg")]);
        let e = Corrections::from_json_for(&path, &ours).unwrap_err().to_string();
        assert!(e.contains("`alpha_rad` has `unit` `deg`"), "{e}");
        write(r#""file": "flight_a.csv", "#, &[row("q_rad_s", "rad/s"), row("q_rad_s", "rad/s")]);
        let e = Corrections::from_json_for(&path, &ours).unwrap_err().to_string();
        assert!(e.contains("`q_rad_s` has two rows"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A record without a sideslip channel gets the reconstructed one (interpolated in time),
    /// a record with one keeps its own; a scale of 0 is refused with the channel named.
    #[test]
    fn the_reconstructed_sideslip_fills_only_a_missing_channel() {
        let beta = vec![(vec![0.0, 1.0], vec![0.0, 0.02])];
        let corr = Corrections::new(Vec::new(), beta).unwrap();
        let mut with = sample(0.5);
        with.beta_rad = Some(0.3);
        let input = vec![
            Ok(RecordEvent::Sample { row: 0, sample: sample(0.5) }),
            Ok(RecordEvent::Sample { row: 1, sample: with }),
        ];
        let out: Vec<AirDataSample> = Corrected::new(input.into_iter(), corr)
            .filter_map(|e| match e.unwrap() {
                RecordEvent::Sample { sample, .. } => Some(sample),
                _ => None,
            })
            .collect();
        assert!((out[0].beta_rad.unwrap() - 0.01).abs() < 1e-15);
        assert_eq!(out[1].beta_rad, Some(0.3));
        let e = Corrections::new(vec![(Channel::Ax, Some(0.1), Some(0.0), None)], Vec::new())
            .unwrap_err();
        assert!(e.contains("ax_mps2"), "{e}");
    }

    /// An AHRS lag of τ = 0.15 s: the stage passes every other channel through the filter
    /// and leaves the AHRS's own as read. A ramp `α = 0.01 t` (sampled at 10 Hz) comes out,
    /// once the start's transient has died away (e^{−8/0.15}), as `0.01 (t − τ)`, the steady
    /// response of `τ ẏ + y = u` to a ramp; q passes unchanged; after a gap the filter starts
    /// again from the first sample. A lag beyond 0.5 s or below 0 is refused, one within 2σ of
    /// none left out, and neither filters.
    #[test]
    fn an_ahrs_lag_filters_every_other_channel() {
        let lagged = |tau: f64, sigma: Option<f64>| {
            let mut c = Corrections::default();
            c.set_lag(tau, sigma).unwrap();
            c
        };
        let ramp = |t: f64| AirDataSample {
            t_s: t,
            vt_mps: 50.0,
            alpha_rad: 0.01 * t,
            q_rad_s: Some((0.5 * t).cos()),
            ..Default::default()
        };
        let mut input: Vec<_> = (0..100)
            .map(|k| Ok(RecordEvent::Sample { row: k, sample: ramp(0.1 * k as f64) }))
            .collect();
        input.push(Ok(RecordEvent::Gap { row: 100, dt_s: 1.1, nominal_dt_s: 0.1 }));
        input.push(Ok(RecordEvent::Sample { row: 100, sample: ramp(11.0) }));
        let corr = lagged(0.15, Some(0.01));
        assert!(corr.applied.iter().any(|a| a.contains("τ = 0.150 s")), "{:?}", corr.applied);
        let out: Vec<AirDataSample> = Corrected::new(input.into_iter(), corr)
            .filter_map(|e| match e.unwrap() {
                RecordEvent::Sample { sample, .. } => Some(sample),
                _ => None,
            })
            .collect();
        for s in &out[80..100] {
            assert!((s.alpha_rad - 0.01 * (s.t_s - 0.15)).abs() < 1e-12, "{s:?}");
            assert_eq!(s.q_rad_s, ramp(s.t_s).q_rad_s);
            assert_eq!(s.vt_mps, 50.0);
        }
        assert!((out[100].alpha_rad - 0.11).abs() < 1e-15, "restarted in steady state");
        for (tau, why) in [(0.6, "beyond the 0.5 s"), (-0.05, "is not negative")] {
            let c = lagged(tau, Some(0.01));
            assert!(
                c.lag_s.is_none() && c.refused.iter().any(|r| r.contains(why)),
                "{:?}",
                c.refused
            );
        }
        let c = lagged(0.01, Some(0.01));
        assert!(c.lag_s.is_none() && c.left_out[0].starts_with("AHRS lag"), "{:?}", c.left_out);
    }

    /// The samples `sample_at(t)` at the times `ts`, streamed through the stage applying `corr`.
    fn corrected(
        ts: &[f64],
        sample_at: impl Fn(f64) -> AirDataSample,
        corr: Corrections,
    ) -> Vec<AirDataSample> {
        let input: Vec<Result<RecordEvent, FlightDataError>> = ts
            .iter()
            .enumerate()
            .map(|(i, &t)| Ok(RecordEvent::Sample { row: i as u64, sample: sample_at(t) }))
            .collect();
        Corrected::new(input.into_iter(), corr)
            .filter_map(|e| match e.unwrap() {
                RecordEvent::Sample { sample, .. } => Some(sample),
                _ => None,
            })
            .collect()
    }

    /// An input shift reads the surface earlier or later, by linear interpolation, and leaves
    /// every other channel as read: a ramp `de = 0.1 t` read 0.05 s earlier is `0.1 (t − 0.05)`
    /// inside the record and held at its first sample before it; the aileron it was not asked
    /// for is untouched. A key that is no surface and a shift beyond 0.5 s are refused by name.
    #[test]
    fn an_input_shift_reads_the_surface_at_its_shifted_time() {
        let ramp = |t: f64| AirDataSample { de_rad: Some(0.1 * t), da_rad: Some(t), ..sample(t) };
        let ts: Vec<f64> = (0..21).map(|i| i as f64 * 0.02).collect();
        let corr = Corrections::default().with_input_shift("de", -0.05).unwrap();
        assert_eq!(corr.applied, ["de: read -0.050 s later (its measured lead undone)"]);
        let out = corrected(&ts, ramp, corr);
        assert_eq!(out.len(), ts.len());
        for (s, &t) in out.iter().zip(&ts) {
            let want = 0.1 * (t - 0.05).max(0.0);
            assert!((s.de_rad.unwrap() - want).abs() < 1e-12, "t {t}: {:?}", s.de_rad);
            assert_eq!((s.t_s, s.da_rad, s.alpha_rad), (t, Some(t), sample(t).alpha_rad));
        }
        let e = Corrections::default().with_input_shift("ax", 0.01).unwrap_err();
        assert!(e.contains("`ax` is no control surface"), "{e}");
        let e = Corrections::default().with_input_shift("dr", 0.6).unwrap_err();
        assert!(e.contains("gives `dr` a shift of 0.6 s, beyond the ±0.5 s"), "{e}");
        assert!(Corrections::default().with_input_shift("dr", f64::NAN).is_err());
    }

    /// A gyro skew reads p, q and r later by the skew, adds it to a gyro's own time shift
    /// rather than replacing it, and leaves every other channel as read: ramps `p = t`,
    /// `q = 2t`, `r = 3t` with a compat shift of +0.02 s on `q`, skewed by −0.01 s, read
    /// `t − 0.01`, `2 (t + 0.01)` and `3 (t − 0.01)` inside the record. A skew that takes a
    /// gyro's total beyond 0.5 s is refused by name.
    #[test]
    fn a_rate_skew_reads_every_gyro_at_its_shifted_time() {
        let ramp = |t: f64| AirDataSample {
            p_rad_s: Some(t),
            q_rad_s: Some(2.0 * t),
            r_rad_s: Some(3.0 * t),
            de_rad: Some(t),
            ..sample(t)
        };
        let ts: Vec<f64> = (0..41).map(|i| i as f64 * 0.01).collect();
        let own = Corrections { shifts: vec![(Channel::Q, 0.02)], ..Default::default() };
        let corr = own.with_rate_skew(-0.01).unwrap();
        assert_eq!(corr.applied, ["p, q, r: read -0.0100 s later (the sample-timing test)"]);
        let out = corrected(&ts, ramp, corr);
        assert_eq!(out.len(), ts.len());
        for (s, &t) in out.iter().zip(&ts).skip(2).take(ts.len() - 4) {
            let got = (s.p_rad_s.unwrap(), s.q_rad_s.unwrap(), s.r_rad_s.unwrap());
            let want = (t - 0.01, 2.0 * (t + 0.01), 3.0 * (t - 0.01));
            assert!((got.0 - want.0).abs() < 1e-12, "t {t}: p {got:?} {want:?}");
            assert!((got.1 - want.1).abs() < 1e-12, "t {t}: q {got:?} {want:?}");
            assert!((got.2 - want.2).abs() < 1e-12, "t {t}: r {got:?} {want:?}");
            assert_eq!((s.t_s, s.de_rad), (t, Some(t)));
        }
        let e = Corrections::default().with_rate_skew(0.6).unwrap_err();
        assert!(e.contains("gives p_rad_s a shift of 0.6 s, beyond the ±0.5 s"), "{e}");
        assert!(Corrections::default().with_rate_skew(f64::NAN).is_err());
    }

    /// A mapping of `de` (with `shift_s`) over constant air data.
    fn shifted_mapping(shift_s: f64) -> aeroident_io::Mapping {
        let text = format!(
            "[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = {{ column = \"V\", unit = \"m/s\" }}\nalpha = {{ column = \"a\", unit = \"rad\" }}\nmass = {{ value = 1.0, unit = \"kg\" }}\nS = {{ value = 1.0, unit = \"m2\" }}\nrho = {{ value = 1.0, unit = \"kg/m3\" }}\nde = {{ column = \"c\", unit = \"rad\", shift_s = {shift_s:?} }}\n"
        );
        aeroident_io::Mapping::from_toml_str(&text, "m.toml").unwrap()
    }

    /// The mapping's `shift_s = -0.02` on `de` advances it: a ramp `de = 0.1 t` is read
    /// `0.1 (t + 0.02)` (held at the record's end), said as `mapping applied: …`; a refit's
    /// measured lead of +0.05 s on the same surface adds to it (`0.1 (t − 0.03)`), and a total
    /// beyond ±0.5 s is refused.
    #[test]
    fn a_mapped_shift_reads_the_surface_as_declared_and_adds_to_a_refit() {
        let ramp = |t: f64| AirDataSample { de_rad: Some(0.1 * t), ..sample(t) };
        let ts: Vec<f64> = (0..21).map(|i| i as f64 * 0.02).collect();
        let corr = Corrections::default().with_mapping(&shifted_mapping(-0.02)).unwrap();
        let said: Vec<String> = corr.warnings().map(|w| w.text).collect();
        assert_eq!(
            said,
            [
                "mapping applied: de: shift_s = -0.0200 s, the surface advanced by 0.0200 s (the value used at t is the logged one at t + 0.0200 s)"
            ]
        );
        let out = corrected(&ts, ramp, corr.clone());
        for (s, &t) in out.iter().zip(&ts) {
            let want = 0.1 * (t + 0.02).min(0.4);
            assert!((s.de_rad.unwrap() - want).abs() < 1e-12, "t {t}: {:?}", s.de_rad);
        }
        let refit = corr.with_input_shift("de", -0.05).unwrap();
        let out = corrected(&ts, ramp, refit.clone());
        for (s, &t) in out.iter().zip(&ts) {
            let want = 0.1 * (t - 0.03).max(0.0);
            assert!((s.de_rad.unwrap() - want).abs() < 1e-12, "t {t}: {:?}", s.de_rad);
        }
        let e = refit.with_input_shift("de", -0.48).unwrap_err();
        assert!(e.contains("gives `de` a shift of -0.51"), "{e}");
    }

    /// A commanded surface's actuator and the mapping's shift commute: the deflection shifted
    /// (the record stage's order: actuator, then corrections) equals the actuator driven by
    /// the shifted command, exactly for a delay of whole samples with a rate limit and for a
    /// delay of 1.5 samples without one; an advance differs only by the actuator's start
    /// transient (τ) and over the held last samples.
    #[test]
    fn a_mapped_shift_after_the_actuator_is_the_shift_of_the_command() {
        use super::super::actuated::Actuated;
        let dt = 0.01;
        let ts: Vec<f64> = (0..300).map(|i| i as f64 * dt).collect();
        let command = |t: f64| AirDataSample {
            de_rad: Some(0.1 * (7.0 * t).sin() + if t > 1.0 { 0.05 } else { 0.0 }),
            ..sample(t)
        };
        let de = |events: Box<dyn Iterator<Item = Result<RecordEvent, FlightDataError>>>| {
            let v: Vec<f64> = events
                .filter_map(|e| match e.unwrap() {
                    RecordEvent::Sample { sample, .. } => sample.de_rad,
                    _ => None,
                })
                .collect();
            v
        };
        let cases = [
            (0.03, 2.0, 0.05, 0, 0),
            (0.015, f64::INFINITY, 0.05, 0, 0),
            (-0.02, f64::INFINITY, 0.02, 60, 2),
        ];
        for (shift_s, rate, tau_s, skip, tail) in cases {
            let a = aeroident_io::mapping::Actuator {
                tau_s,
                rate_limit_rad_s: rate,
                position_limits_rad: (f64::NEG_INFINITY, f64::INFINITY),
            };
            let corr = Corrections::default().with_mapping(&shifted_mapping(shift_s)).unwrap();
            let raw = || {
                ts.iter()
                    .enumerate()
                    .map(|(i, &t)| Ok(RecordEvent::Sample { row: i as u64, sample: command(t) }))
            };
            let after = de(Box::new(Corrected::new(
                Actuated::new(raw(), [(aeroident_io::Channel::De, a)]),
                corr.clone(),
            )));
            let before = de(Box::new(Actuated::new(
                Corrected::new(raw(), corr),
                [(aeroident_io::Channel::De, a)],
            )));
            assert_eq!(after.len(), ts.len());
            for k in skip..ts.len() - tail {
                assert!(
                    (after[k] - before[k]).abs() < 1e-9,
                    "shift {shift_s}, k {k}: {} vs {}",
                    after[k],
                    before[k]
                );
            }
            assert!(
                after.iter().zip(&before).any(|(x, y)| (x - y).abs() > 1e-6) == (skip > 0),
                "shift {shift_s}"
            );
        }
    }
}
