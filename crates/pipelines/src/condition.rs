//! The conditioning stage, shared by every pipeline: from the samples a source gives (a log's
//! rows, or the closed-loop experiment's sensors) to the samples an estimator consumes.
//!
//! It supplies the time derivatives the record lacks — `ṗ`, `q̇`, `ṙ` (moment coefficients)
//! and `α̇` (`alphadot` terms) — from the causal least-squares-slope differentiator of
//! [`aeroident_signals::differentiate`], and brings every other channel to the instant of its
//! derivatives, the window centre `(N−1)/2` samples back, in one of two ways ([`Alignment`]):
//! - [`Alignment::Matched`]: every other channel passes the smoother matched to the
//!   differentiator ([`MatchedSmoother`]: the same parabolic weighting and lag), so both sides
//!   of an equation-error regression see the same filter. Without it the differentiator's
//!   smoothing (a sinusoid's derivative is attenuated by `G(ω)`, 0.988 at 1 Hz for 11 points at
//!   100 Hz) faces unfiltered regressors, and noise above the differentiator's band acts like
//!   regressor noise: the β and rate derivatives are biased towards zero.
//! - [`Alignment::Delay`]: every other channel is only delayed.
//!
//! The stage also keeps the **unsmoothed** sample behind each emitted one
//! ([`Conditioner::raw`]): the same time stamp and derivatives, the channels as measured (white
//! errors, as a maximum-likelihood method assumes).
//!
//! The first and last `(N−1)/2` samples of each continuous stretch (record start, end, either
//! side of a gap) never get a centred derivative; they are returned as unused, for the caller
//! to count and list. After a gap the stage restarts ([`Conditioner::flush`]); nothing is
//! bridged. With nothing to differentiate the stage passes samples through undelayed.
//!
//! **A hole of one sample** (an interval over [`GAP_FACTOR`] and up to [`ONE_SAMPLE_HOLE_MAX`]
//! differentiator intervals: one row rejected, by the reader or the spike screen, on an
//! otherwise regular grid) is no gap (the reader's module doc): the differentiators assume a
//! regular grid, so the stage puts a stand-in in the missing sample's place, every channel
//! interpolated linearly between its two neighbours, and goes on. The stand-in is never
//! emitted nor listed: the hole costs its own row only, not the `N − 1` samples of a restart.

use aeroident_estimators::AirDataSample;
use aeroident_io::flight_data::{GAP_FACTOR, ONE_SAMPLE_HOLE_MAX};
use aeroident_signals::differentiate::{CausalDifferentiator, DifferentiateError, MatchedSmoother};
use std::collections::VecDeque;

/// A derivative the stage can supply.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Derivative {
    /// `ṗ` from `p`.
    Pdot,
    /// `q̇` from `q`.
    Qdot,
    /// `ṙ` from `r`.
    Rdot,
    /// `α̇` from `α` (at the CG).
    Alphadot,
}

impl Derivative {
    /// All four.
    pub const ALL: [Derivative; 4] =
        [Derivative::Pdot, Derivative::Qdot, Derivative::Rdot, Derivative::Alphadot];

    /// The channel name (`pdot`, `qdot`, `rdot`, `alphadot`).
    pub fn name(self) -> &'static str {
        match self {
            Derivative::Pdot => "pdot",
            Derivative::Qdot => "qdot",
            Derivative::Rdot => "rdot",
            Derivative::Alphadot => "alphadot",
        }
    }

    /// The differentiated signal of sample `s`, if present.
    pub fn source(self, s: &AirDataSample) -> Option<f64> {
        match self {
            Derivative::Pdot => s.p_rad_s,
            Derivative::Qdot => s.q_rad_s,
            Derivative::Rdot => s.r_rad_s,
            Derivative::Alphadot => Some(s.alpha_rad),
        }
    }

    /// The derivative as recorded in sample `s`, if present.
    pub fn recorded(self, s: &AirDataSample) -> Option<f64> {
        match self {
            Derivative::Pdot => s.pdot_rad_s2,
            Derivative::Qdot => s.qdot_rad_s2,
            Derivative::Rdot => s.rdot_rad_s2,
            Derivative::Alphadot => s.alphadot_rad_s,
        }
    }

    /// Sets the derivative in sample `s`.
    pub fn set(self, s: &mut AirDataSample, v: Option<f64>) {
        match self {
            Derivative::Pdot => s.pdot_rad_s2 = v,
            Derivative::Qdot => s.qdot_rad_s2 = v,
            Derivative::Rdot => s.rdot_rad_s2 = v,
            Derivative::Alphadot => s.alphadot_rad_s = v,
        }
    }
}

/// How the other channels are brought to the instant of the differentiated ones (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Alignment {
    /// The smoother matched to the differentiator (same weighting, same lag).
    #[default]
    Matched,
    /// A pure delay by the differentiator's lag.
    Delay,
}

/// Largest relative disagreement between the nominal and the measured interval that is accepted
/// without a warning; beyond it the measured interval is used.
pub const DT_TOLERANCE: f64 = 0.01;

/// What the stage does: which derivatives, over how many samples, how aligned.
#[derive(Debug, Clone, PartialEq)]
pub struct Conditioning {
    /// The derivatives to supply (empty: a pass-through).
    pub derivatives: Vec<Derivative>,
    /// Differentiator window `N`, samples (odd, ≥ 3).
    pub window: usize,
    /// The source's nominal sample interval, s (`None`: the first interval seen).
    pub nominal_dt_s: Option<f64>,
    /// How the other channels are aligned.
    pub alignment: Alignment,
}

/// The stage (module doc). Holds at most `N` samples.
#[derive(Debug, Clone)]
pub struct Conditioner {
    cfg: Conditioning,
    dt_s: Option<f64>,
    diffs: Vec<CausalDifferentiator>,
    /// Samples not yet emitted (at most `(N−1)/2 + 1`), with their rows (`None`: a stand-in
    /// for a one-sample hole, never emitted).
    delay: VecDeque<(Option<u64>, AirDataSample)>,
    /// The last `N` samples, oldest first (matched alignment only).
    window: VecDeque<AirDataSample>,
    /// Matched-smoother weights over the window, oldest first (matched alignment only).
    weights: Vec<f64>,
    raw: Option<AirDataSample>,
    warning: Option<String>,
}

impl Conditioner {
    /// A stage doing `cfg`. The first interval is always measured: if it differs from
    /// `cfg.nominal_dt_s` by more than [`DT_TOLERANCE`] (relative), the measured interval is
    /// used and [`Conditioner::take_warning`] says so.
    pub fn new(cfg: Conditioning) -> Self {
        let n = cfg.window;
        Self {
            dt_s: cfg.nominal_dt_s,
            cfg,
            diffs: Vec::new(),
            delay: VecDeque::with_capacity(n / 2 + 2),
            window: VecDeque::with_capacity(n + 1),
            weights: Vec::new(),
            raw: None,
            warning: None,
        }
    }

    /// The interval the differentiators use, s, once known.
    pub fn dt_s(&self) -> Option<f64> {
        if self.diffs.is_empty() { None } else { self.dt_s }
    }

    /// A warning raised since the last call (nominal and measured interval disagree).
    pub fn take_warning(&mut self) -> Option<String> {
        self.warning.take()
    }

    /// The derivatives this stage supplies.
    pub fn supplies(&self) -> &[Derivative] {
        &self.cfg.derivatives
    }

    /// The **unsmoothed** sample behind the last one emitted (module doc); `None` before the
    /// first emission.
    pub fn raw(&self) -> Option<&AirDataSample> {
        self.raw.as_ref()
    }

    /// Pushes a sample (row `row`); appends the sample ready now (with its derivatives) to
    /// `ready` and the rows that can never get a centred derivative to `unused`.
    ///
    /// # Errors
    /// [`DifferentiateError`] when the first sample interval is not positive or the window is
    /// not odd and ≥ 3.
    pub fn push(
        &mut self,
        row: u64,
        s: AirDataSample,
        ready: &mut Vec<(u64, AirDataSample)>,
        unused: &mut Vec<u64>,
    ) -> Result<(), DifferentiateError> {
        if self.cfg.derivatives.is_empty() {
            self.raw = Some(s);
            ready.push((row, s));
            return Ok(());
        }
        if self.diffs.is_empty() && !self.start(row, s)? {
            return Ok(());
        }
        if let Some(stand_in) = self.stand_in(&s) {
            self.push_running(None, stand_in, ready, unused);
        }
        self.push_running(Some(row), s, ready, unused);
        Ok(())
    }

    /// The stand-in for a one-sample hole before `s` (module doc), if there is one.
    fn stand_in(&self, s: &AirDataSample) -> Option<AirDataSample> {
        let (_, prev) = self.delay.back()?;
        let dt = self.dt_s?;
        let interval = s.t_s - prev.t_s;
        if !(interval > GAP_FACTOR * dt && interval <= ONE_SAMPLE_HOLE_MAX * dt) {
            return None;
        }
        let mut mid = *prev;
        mid.t_s = 0.5 * (prev.t_s + s.t_s);
        // A channel one neighbour lacks stays as the previous sample has it.
        for (get, set) in SMOOTHED {
            if let (Some(a), Some(b)) = (get(prev), get(s)) {
                set(&mut mid, 0.5 * (a + b));
            }
        }
        Some(mid)
    }

    /// Pushes a sample (a stand-in when `row` is `None`) through the running stage.
    fn push_running(
        &mut self,
        row: Option<u64>,
        s: AirDataSample,
        ready: &mut Vec<(u64, AirDataSample)>,
        unused: &mut Vec<u64>,
    ) {
        let half = self.cfg.window / 2;
        self.delay.push_back((row, s));
        if !self.weights.is_empty() {
            self.window.push_back(s);
            if self.window.len() > self.cfg.window {
                self.window.pop_front();
            }
        }
        let mut out = [None; 4];
        for (k, (d, w)) in self.diffs.iter_mut().zip(&self.cfg.derivatives).enumerate() {
            out[k] = d.update(w.source(&s).unwrap_or(f64::NAN));
        }
        if self.delay.len() > half + 1 {
            // Only during warm-up can the delay line overflow: these never get a centred value.
            if let Some((Some(r), _)) = self.delay.pop_front() {
                unused.push(r);
            }
        }
        if out[0].is_some()
            && let Some((r, mut c)) = self.delay.pop_front()
        {
            let Some(r) = r else { return };
            for (k, w) in self.cfg.derivatives.iter().enumerate() {
                w.set(&mut c, out[k].filter(|v| v.is_finite()));
            }
            self.raw = Some(c);
            if !self.weights.is_empty() {
                smooth(&self.weights, &self.window, &mut c);
            }
            ready.push((r, c));
        }
    }

    /// Measures the interval from the first two samples and builds the differentiators (and
    /// the smoother), replaying the held first sample into them; `false` while still holding.
    fn start(&mut self, row: u64, s: AirDataSample) -> Result<bool, DifferentiateError> {
        let measured = match self.delay.back() {
            Some((_, prev)) => s.t_s - prev.t_s,
            None => {
                self.delay.push_back((Some(row), s));
                return Ok(false);
            }
        };
        let dt = match self.dt_s {
            Some(nom) if (measured - nom).abs() > DT_TOLERANCE * nom.abs() => {
                self.warning = Some(format!(
                    "the mapping's nominal_dt_s = {nom} s differs from the record's measured interval {measured} s by more than {:.0} %: the differentiator uses the measured interval",
                    100.0 * DT_TOLERANCE
                ));
                measured
            }
            Some(nom) => nom,
            None => measured,
        };
        self.dt_s = Some(dt);
        for _ in &self.cfg.derivatives {
            self.diffs.push(CausalDifferentiator::new(self.cfg.window, dt)?);
        }
        if self.cfg.alignment == Alignment::Matched {
            self.weights = MatchedSmoother::new(self.cfg.window, dt)?.weights().to_vec();
        }
        for (_, held) in &self.delay {
            for (d, w) in self.diffs.iter_mut().zip(&self.cfg.derivatives) {
                d.update(w.source(held).unwrap_or(f64::NAN));
            }
            if !self.weights.is_empty() {
                self.window.push_back(*held);
            }
        }
        Ok(true)
    }

    /// Restarts (after a gap, or at the end): the delayed samples are unused.
    pub fn flush(&mut self, unused: &mut Vec<u64>) {
        for d in &mut self.diffs {
            d.reset();
        }
        self.window.clear();
        unused.extend(self.delay.drain(..).filter_map(|(r, _)| r));
    }
}

/// A channel of a sample the matched smoother filters: its value, and how to set it.
type Channel = (fn(&AirDataSample) -> Option<f64>, fn(&mut AirDataSample, f64));

/// The smoothed channels: air data, rates, attitude, specific forces, surfaces, throttle and
/// thrust (not the constants, density or the derivatives).
const SMOOTHED: [Channel; 18] = [
    (|s| Some(s.vt_mps), |s, v| s.vt_mps = v),
    (|s| Some(s.alpha_rad), |s, v| s.alpha_rad = v),
    (|s| Some(s.qbar_pa), |s, v| s.qbar_pa = v),
    (|s| s.beta_rad, |s, v| s.beta_rad = Some(v)),
    (|s| s.p_rad_s, |s, v| s.p_rad_s = Some(v)),
    (|s| s.q_rad_s, |s, v| s.q_rad_s = Some(v)),
    (|s| s.r_rad_s, |s, v| s.r_rad_s = Some(v)),
    (|s| s.phi_rad, |s, v| s.phi_rad = Some(v)),
    (|s| s.theta_rad, |s, v| s.theta_rad = Some(v)),
    (|s| s.psi_rad, |s, v| s.psi_rad = Some(v)),
    (|s| s.ax_mps2, |s, v| s.ax_mps2 = Some(v)),
    (|s| s.ay_mps2, |s, v| s.ay_mps2 = Some(v)),
    (|s| s.az_mps2, |s, v| s.az_mps2 = Some(v)),
    (|s| s.de_rad, |s, v| s.de_rad = Some(v)),
    (|s| s.da_rad, |s, v| s.da_rad = Some(v)),
    (|s| s.dr_rad, |s, v| s.dr_rad = Some(v)),
    (|s| s.throttle, |s, v| s.throttle = Some(v)),
    (|s| s.thrust_n, |s, v| s.thrust_n = Some(v)),
];

/// Replaces each channel of `centre` by its matched-smoother average over `window` (oldest
/// first, as `weights`). A channel some sample of the window lacks keeps the centre's value
/// (a missing channel stays missing): a weighted sum over a hole would be a different filter.
fn smooth(weights: &[f64], window: &VecDeque<AirDataSample>, centre: &mut AirDataSample) {
    if window.len() != weights.len() {
        return;
    }
    for (get, set) in SMOOTHED {
        let sum =
            weights.iter().zip(window).try_fold(0.0, |acc, (w, s)| get(s).map(|x| acc + w * x));
        if let Some(v) = sum
            && get(centre).is_some()
        {
            set(centre, v);
        }
    }
}

#[cfg(test)]
mod tests;
