//! Candidate manoeuvres in one surface channel: spans where it moves with energy well above
//! its slow trend and above the record's quiet level.
//!
//! # The rule ([`DetectionRule`], defaults in brackets)
//!
//! 1. **Slow trend out.** The trend is the centred moving straight-line fit over `trend_s`
//!    [20 s] (a moving mean in the record's middle; at its ends, where the window is
//!    one-sided, the line follows a drift that a mean would lag); the detector works on the
//!    deviation from it. Trim changes, a phugoid (periods of 10–60 s)
//!    and a pilot's slow corrections live below ~0.05 Hz; the inputs that excite the short
//!    period and Dutch roll (0.2–5 Hz: 1–3 Hz on a small UAV, 0.3–1 Hz on a transport) and a
//!    3-2-1-1 or doublet built on them (pulses of 0.3–3 s) pass. A 20 s mean removes a slow
//!    drift but keeps a 3-2-1-1, whose mean over its ~7 s is near zero anyway.
//! 2. **Energy.** The RMS of the deviation over a centred window of `rms_window_s` [1 s]: long
//!    enough to average ten or more samples at a 10 Hz control rate, short enough to resolve
//!    a 1 s pulse.
//! 3. **Against the quiet level.** The quiet level is the `quiet_quantile` [10 %] quantile of
//!    that RMS over the record: a record is mostly held flight, and even a record cut to one
//!    manoeuvre has its trimmed lead-in. A span is active where the RMS exceeds
//!    `threshold_ratio` [4, 12 dB: 16 times the quiet energy] times the quiet level, capped
//!    at `cap_fraction` [25 %] of the channel's 0.5–99.5 % range over the record: an input
//!    whose RMS deviation reaches a quarter of everything the surface did is large whatever
//!    the quiet level, and a record cut to one manoeuvre (no quiet stretch: its 10 % RMS
//!    quantile is the manoeuvre's own) is found by the cap. Gaussian noise stays below it
//!    (a quarter of its 0.5–99.5 % range is 1.3 σ; the RMS of 10 samples or more reaches that
//!    for whole windows only rarely, and `min_duration_s` asks for more than one window).
//!    The threshold is at least two floors for a surface that never moves otherwise:
//!    `range_fraction` [2 %] of that range, and three quantisation steps (the smallest
//!    non-zero change between samples: a PWM microsecond, an AETR unit).
//! 4. **Spans.** Active spans closer than `merge_gap_s` [2 s: the settling of a ~1 Hz mode]
//!    are one manoeuvre (the parts of a 3-2-1-1 with a pause); a span shorter than
//!    `min_duration_s` [1.5 s: a period of a short-period mode and more than one RMS window,
//!    so that one burst of noise, which raises every window holding it over one window's
//!    length, is not a manoeuvre] is a twitch.
//! 5. **Window.** The suggested `--window` adds `lead_s` [1 s] of lead-in (the initial state
//!    of the estimators) and `tail_s` [3 s] of free response after the input stops (a few
//!    time constants of the modes above), clipped to the record and to the neighbouring
//!    manoeuvres' inputs.
//!
//! Per manoeuvre: the peak deviation from the trend (amplitude), the RMS, and the dominant
//! frequency band of the deviation over the active span: the frequency of the largest
//! Fourier amplitude and the band holding the central 80 % of the energy (10 % to 90 % of its
//! cumulative sum), from a direct Fourier sum at the samples' own times (a log's control
//! samples are not exactly uniform) between 1/(2·span) and the Nyquist frequency of the median
//! interval (at most 25 Hz).

use serde::Serialize;

/// The detection thresholds (module doc). Times in s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DetectionRule {
    /// Length of the centred moving mean taken as the slow trend, s.
    pub trend_s: f64,
    /// Length of the centred RMS window, s.
    pub rms_window_s: f64,
    /// Quantile (0–1) of the windowed RMS taken as the quiet level.
    pub quiet_quantile: f64,
    /// Active when the RMS exceeds this many quiet levels.
    pub threshold_ratio: f64,
    /// Cap of the threshold: this fraction of the channel's 0.5–99.5 % range.
    pub cap_fraction: f64,
    /// Floor of the threshold: this fraction of the channel's 0.5–99.5 % range.
    pub range_fraction: f64,
    /// Active spans closer than this are merged, s.
    pub merge_gap_s: f64,
    /// Spans shorter than this are dropped, s.
    pub min_duration_s: f64,
    /// Lead-in added before a manoeuvre's window, s.
    pub lead_s: f64,
    /// Free response added after it, s.
    pub tail_s: f64,
}

impl Default for DetectionRule {
    fn default() -> Self {
        Self {
            trend_s: 20.0,
            rms_window_s: 1.0,
            quiet_quantile: 0.1,
            threshold_ratio: 4.0,
            cap_fraction: 0.25,
            range_fraction: 0.02,
            merge_gap_s: 2.0,
            min_duration_s: 1.5,
            lead_s: 1.0,
            tail_s: 3.0,
        }
    }
}

/// One candidate manoeuvre of a channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Manoeuvre {
    /// The channel (`topic.field` or column).
    pub channel: String,
    /// Suggested window start and end (with lead-in and free response), s.
    pub start_s: f64,
    /// Suggested window end, s.
    pub end_s: f64,
    /// Where the input is active (the RMS above the threshold), s.
    pub active_start_s: f64,
    /// End of the active input, s.
    pub active_end_s: f64,
    /// Peak deviation from the slow trend over the active span, channel units.
    pub amplitude: f64,
    /// RMS deviation from the trend over the active span, channel units.
    pub rms: f64,
    /// Frequency of the largest Fourier amplitude, Hz.
    pub peak_hz: f64,
    /// Band holding the central 80 % of the energy, Hz.
    pub band_hz: [f64; 2],
}

/// What the detector found in a channel and the levels it judged by.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelDetection {
    /// The channel.
    pub channel: String,
    /// The quiet level (RMS), channel units.
    pub quiet: f64,
    /// The threshold the windowed RMS had to exceed, channel units.
    pub threshold: f64,
    /// The manoeuvres, in time order.
    pub manoeuvres: Vec<Manoeuvre>,
}

/// Fewest finite samples a channel needs to be judged.
const MIN_SAMPLES: usize = 8;

/// Detects the manoeuvres of channel `channel`: `values[k]` at `t_s[k]` (s, increasing);
/// non-finite values are left out. A channel of fewer than eight finite samples has none.
pub fn detect(
    channel: &str,
    t_s: &[f64],
    values: &[f64],
    rule: &DetectionRule,
) -> ChannelDetection {
    let (t, v): (Vec<f64>, Vec<f64>) = t_s
        .iter()
        .zip(values)
        .filter(|(t, v)| t.is_finite() && v.is_finite())
        .map(|(t, v)| (*t, *v))
        .unzip();
    let mut out = ChannelDetection {
        channel: channel.into(),
        quiet: 0.0,
        threshold: 0.0,
        manoeuvres: vec![],
    };
    if t.len() < MIN_SAMPLES {
        return out;
    }
    let trend = moving_line(&t, &v, rule.trend_s);
    let dev: Vec<f64> = v.iter().zip(&trend).map(|(v, m)| v - m).collect();
    let sq: Vec<f64> = dev.iter().map(|d| d * d).collect();
    let rms: Vec<f64> =
        moving_mean(&t, &sq, rule.rms_window_s).into_iter().map(|m| m.max(0.0).sqrt()).collect();
    out.quiet = quantile(&rms, rule.quiet_quantile);
    out.threshold = threshold(&v, out.quiet, rule);
    let spans = active_spans(&t, &rms, out.threshold, rule);
    out.manoeuvres = spans
        .iter()
        .enumerate()
        .map(|(k, &(a, b))| {
            let before = if k == 0 { t[0] } else { t[spans[k - 1].1] };
            let after = spans.get(k + 1).map_or(t[t.len() - 1], |s| t[s.0]);
            describe(channel, &t, &dev, (a, b), (before, after), rule)
        })
        .collect();
    out
}

/// The threshold: `threshold_ratio` quiet levels, at most the range cap, at least the range and
/// quantisation floors.
fn threshold(v: &[f64], quiet: f64, rule: &DetectionRule) -> f64 {
    let mut sorted = v.to_vec();
    sorted.sort_by(f64::total_cmp);
    let range = quantile(&sorted, 0.995) - quantile(&sorted, 0.005);
    let step = v
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    let step = if step.is_finite() { step } else { 0.0 };
    // The last floor is round-off: a channel that never changes deviates from its fitted
    // trend by rounding alone.
    let size = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    (rule.threshold_ratio * quiet)
        .min(rule.cap_fraction * range)
        .max(rule.range_fraction * range)
        .max(3.0 * step)
        .max(1e-9 * size)
}

/// The centred moving straight-line fit of `v` over `width_s` of time `t` (one-sided at the
/// ends), evaluated at each sample, by prefix sums: O(n). Times are taken from the first so
/// that the sums of squares keep their precision.
pub(super) fn moving_line(t: &[f64], v: &[f64], width_s: f64) -> Vec<f64> {
    let t: Vec<f64> = t.iter().map(|x| x - t[0]).collect();
    let tt: Vec<f64> = t.iter().map(|x| x * x).collect();
    let tv: Vec<f64> = t.iter().zip(v).map(|(a, b)| a * b).collect();
    let (m_t, m_v) = (moving_mean(&t, &t, width_s), moving_mean(&t, v, width_s));
    let (m_tt, m_tv) = (moving_mean(&t, &tt, width_s), moving_mean(&t, &tv, width_s));
    (0..t.len())
        .map(|k| {
            let var = m_tt[k] - m_t[k] * m_t[k];
            let slope = if var > 1e-12 { (m_tv[k] - m_t[k] * m_v[k]) / var } else { 0.0 };
            m_v[k] + slope * (t[k] - m_t[k])
        })
        .collect()
}

/// The centred moving mean of `v` over `width_s` of time `t` (one-sided at the ends), by
/// prefix sums: O(n).
pub(super) fn moving_mean(t: &[f64], v: &[f64], width_s: f64) -> Vec<f64> {
    let mut prefix = Vec::with_capacity(v.len() + 1);
    prefix.push(0.0);
    for x in v {
        prefix.push(prefix[prefix.len() - 1] + x);
    }
    let half = width_s / 2.0;
    let (mut lo, mut hi) = (0usize, 0usize);
    t.iter()
        .map(|&tk| {
            while t[lo] < tk - half {
                lo += 1;
            }
            while hi < t.len() && t[hi] <= tk + half {
                hi += 1;
            }
            (prefix[hi] - prefix[lo]) / (hi - lo) as f64
        })
        .collect()
}

/// The `q`-quantile (0–1, nearest rank) of `v` (sorted or not).
pub(super) fn quantile(v: &[f64], q: f64) -> f64 {
    let mut s = v.to_vec();
    let k = ((s.len() - 1) as f64 * q).round() as usize;
    let (_, x, _) = s.select_nth_unstable_by(k, f64::total_cmp);
    *x
}

/// Index spans `(first, last)` where `rms` exceeds `thr`, merged across gaps under
/// `merge_gap_s` and at least `min_duration_s` long.
fn active_spans(t: &[f64], rms: &[f64], thr: f64, rule: &DetectionRule) -> Vec<(usize, usize)> {
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut start: Option<usize> = None;
    for (k, r) in rms.iter().enumerate() {
        match (*r > thr, start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                runs.push((s, k - 1));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        runs.push((s, rms.len() - 1));
    }
    let mut merged: Vec<(usize, usize)> = Vec::new();
    for (a, b) in runs {
        match merged.last_mut() {
            Some(last) if t[a] - t[last.1] < rule.merge_gap_s => last.1 = b,
            _ => merged.push((a, b)),
        }
    }
    merged.retain(|&(a, b)| t[b] - t[a] >= rule.min_duration_s);
    merged
}

/// The manoeuvre of active span `(a, b)` (indices), its window clipped to `(before, after)`:
/// the neighbouring inputs or the record's ends.
fn describe(
    channel: &str,
    t: &[f64],
    dev: &[f64],
    (a, b): (usize, usize),
    (before, after): (f64, f64),
    rule: &DetectionRule,
) -> Manoeuvre {
    let d = &dev[a..=b];
    let amplitude = d.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
    let (peak_hz, band_hz) = spectrum_band(&t[a..=b], d);
    Manoeuvre {
        channel: channel.into(),
        start_s: (t[a] - rule.lead_s).max(before),
        end_s: (t[b] + rule.tail_s).min(after),
        active_start_s: t[a],
        active_end_s: t[b],
        amplitude,
        rms,
        peak_hz,
        band_hz,
    }
}

/// Most frequencies of the Fourier sum.
const MAX_FREQUENCIES: usize = 1000;

/// The peak frequency and the 10–90 % energy band of `x` at times `t` (module doc), Hz.
fn spectrum_band(t: &[f64], x: &[f64]) -> (f64, [f64; 2]) {
    let n = t.len();
    let span = t[n - 1] - t[0];
    if n < 4 || span <= 0.0 {
        return (0.0, [0.0, 0.0]);
    }
    let mut dt: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    dt.sort_by(f64::total_cmp);
    let f_max = (0.5 / dt[dt.len() / 2]).min(25.0);
    let f_min = 0.5 / span;
    let step = (f_min / 2.0).max((f_max - f_min) / MAX_FREQUENCIES as f64);
    let freqs: Vec<f64> =
        (0..).map(|k| f_min + k as f64 * step).take_while(|f| *f <= f_max).collect();
    let power: Vec<f64> = freqs
        .iter()
        .map(|f| {
            let w = std::f64::consts::TAU * f;
            let (re, im) = t.iter().zip(x).fold((0.0, 0.0), |(re, im), (tk, xk)| {
                let (s, c) = (w * (tk - t[0])).sin_cos();
                (re + xk * c, im - xk * s)
            });
            re * re + im * im
        })
        .collect();
    let total: f64 = power.iter().sum();
    let peak = power.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map_or(0, |p| p.0);
    let at = |share: f64| {
        let mut acc = 0.0;
        let k = power.iter().position(|p| {
            acc += p;
            acc >= share * total
        });
        freqs[k.unwrap_or(freqs.len() - 1)]
    };
    (freqs[peak], [at(0.1), at(0.9)])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1 Hz square pulse train over 20–26 s in a 50 Hz record of 60 s of small noise: one
    /// manoeuvre whose active span covers the pulses and whose peak is near 1 Hz.
    #[test]
    fn analytic_pulse_train_is_found_where_it_is() {
        let t: Vec<f64> = (0..3000).map(|k| k as f64 * 0.02).collect();
        let v: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(k, &t)| {
                let noise = 0.01 * ((k * 7919 % 101) as f64 / 50.0 - 1.0);
                let pulse = if (20.0..26.0).contains(&t) {
                    if (t * 2.0).floor() as i64 % 2 == 0 { 1.0 } else { -1.0 }
                } else {
                    0.0
                };
                5.0 + pulse + noise
            })
            .collect();
        let d = detect("x", &t, &v, &DetectionRule::default());
        assert_eq!(d.manoeuvres.len(), 1, "{d:?}");
        let m = &d.manoeuvres[0];
        assert!(m.active_start_s <= 20.1 && m.active_end_s >= 25.9, "{m:?}");
        assert!(m.active_start_s >= 19.0 && m.active_end_s <= 27.0, "{m:?}");
        assert!((m.peak_hz - 1.0).abs() < 0.15, "{m:?}");
        assert!(m.band_hz[0] <= 1.0 && m.band_hz[1] >= 1.0, "{m:?}");
        assert!((m.amplitude - 1.0).abs() < 0.2, "{m:?}");
    }

    /// A channel that never moves has no manoeuvre; nor has one of too few samples.
    #[test]
    fn analytic_still_channel_has_none() {
        let t: Vec<f64> = (0..500).map(|k| k as f64 * 0.1).collect();
        let v = vec![1500.0; 500];
        assert!(detect("x", &t, &v, &DetectionRule::default()).manoeuvres.is_empty());
        assert!(detect("x", &t[..5], &v[..5], &DetectionRule::default()).manoeuvres.is_empty());
    }
}
