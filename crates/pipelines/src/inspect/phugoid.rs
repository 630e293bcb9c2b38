//! Phugoids: the slow exchange of airspeed and height a small held pull (or push) of the
//! elevator sets off, which the surface detector ([`super::detect`]) filters out as a trend
//! (its input is a step held for seconds, its response has a period of 10–150 s).
//!
//! # The rule ([`PhugoidRule`], defaults in brackets)
//!
//! 1. **Phugoid band of the airspeed.** The airspeed's deviation from its centred moving
//!    straight line over `trend_s` [200 s: more than a period of the slowest phugoid taken],
//!    smoothed by a centred moving mean over `smooth_s` [5 s: the short period and a
//!    3-2-1-1's speed ripple, at 0.2 Hz and above, go out].
//! 2. **Energy.** Its RMS over a centred `rms_window_s` [60 s] window, airborne samples only
//!    (the ground spans of [`super::envelope`] are not flight).
//! 3. **Threshold.** Active where that RMS exceeds `threshold_ratio` (4) times the record's
//!    10 % quantile of it and `min_fraction` [0.5 %] of the airborne speed (turbulence and a
//!    trimmed aircraft's drift stay below it: 0.5 m/s at 100 m/s).
//! 4. **An oscillation.** Active spans closer than 10 s are one; a span is a phugoid when its
//!    band signal crosses zero at least twice (a full period at least) and the period, twice
//!    the mean interval between crossings, is 10–150 s.
//! 5. **The pull.** The elevator's largest change of its 2 s mean after against its 5 s mean
//!    before, from 30 s before the active span to 10 s past half an RMS window into it (the
//!    60 s RMS rises half a window before the response does): where the pilot pulled (or
//!    pushed) and held. The window runs from 2 s before the pull (or the span's start when the
//!    record has no elevator) to the end of the span.

use aeroident_estimators::AirDataSample;
use serde::Serialize;

/// The phugoid thresholds (module doc). Times in s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PhugoidRule {
    /// Length of the moving straight line taken as the slow trend, s.
    pub trend_s: f64,
    /// Length of the moving mean smoothing the band signal, s.
    pub smooth_s: f64,
    /// Length of the RMS window, s.
    pub rms_window_s: f64,
    /// Active above this many times the 10 % quantile of the RMS.
    pub threshold_ratio: f64,
    /// Active above this fraction of the airborne speed (RMS, m/s per m/s).
    pub min_fraction: f64,
    /// Shortest and longest period taken, s.
    pub period_s: [f64; 2],
}

impl Default for PhugoidRule {
    fn default() -> Self {
        Self {
            trend_s: 200.0,
            smooth_s: 5.0,
            rms_window_s: 60.0,
            threshold_ratio: 4.0,
            min_fraction: 0.005,
            period_s: [10.0, 150.0],
        }
    }
}

/// One phugoid found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Phugoid {
    /// Suggested window start, s.
    pub start_s: f64,
    /// Suggested window end, s.
    pub end_s: f64,
    /// Where the elevator was pulled or pushed and held, s (`None`: no elevator mapped).
    pub pull_at_s: Option<f64>,
    /// The held elevator change, rad (after minus before; negative is a pull).
    pub pull_rad: Option<f64>,
    /// Period, s.
    pub period_s: f64,
    /// Peak airspeed deviation of the band signal, m/s.
    pub amplitude_mps: f64,
}

/// The phugoids of `samples` (time order), whose airborne speed is `airborne_speed_mps`;
/// `airborne(t)` says whether time t is in flight.
pub fn phugoids(
    samples: &[AirDataSample],
    airborne_speed_mps: f64,
    airborne: impl Fn(f64) -> bool,
    rule: &PhugoidRule,
) -> Vec<Phugoid> {
    let s: Vec<&AirDataSample> =
        samples.iter().filter(|s| airborne(s.t_s) && s.vt_mps.is_finite()).collect();
    if s.len() < 16 {
        return vec![];
    }
    let t: Vec<f64> = s.iter().map(|s| s.t_s).collect();
    let v: Vec<f64> = s.iter().map(|s| s.vt_mps).collect();
    let trend = super::detect::moving_line(&t, &v, rule.trend_s);
    let dev: Vec<f64> = v.iter().zip(&trend).map(|(v, m)| v - m).collect();
    let band = super::detect::moving_mean(&t, &dev, rule.smooth_s);
    let sq: Vec<f64> = band.iter().map(|b| b * b).collect();
    let rms: Vec<f64> = super::detect::moving_mean(&t, &sq, rule.rms_window_s)
        .into_iter()
        .map(|m| m.max(0.0).sqrt())
        .collect();
    let thr = (rule.threshold_ratio * super::detect::quantile(&rms, 0.1))
        .max(rule.min_fraction * airborne_speed_mps);
    let de: Vec<Option<f64>> = s.iter().map(|s| s.de_rad.filter(|x| x.is_finite())).collect();
    spans(&t, &rms, thr)
        .into_iter()
        .filter_map(|(a, b)| {
            let (period_s, amplitude_mps) = oscillation(&t[a..=b], &band[a..=b])?;
            if !(rule.period_s[0]..=rule.period_s[1]).contains(&period_s) {
                return None;
            }
            let pull = pull(&t, &de, t[a] - 30.0, t[a] + rule.rms_window_s / 2.0 + 10.0);
            let start_s = pull.map_or(t[a], |(at, _)| (at - 2.0).max(t[0]));
            Some(Phugoid {
                start_s,
                end_s: t[b],
                pull_at_s: pull.map(|p| p.0),
                pull_rad: pull.map(|p| p.1),
                period_s,
                amplitude_mps,
            })
        })
        .collect()
}

/// Index spans where `rms` exceeds `thr`, joined across gaps under 10 s.
fn spans(t: &[f64], rms: &[f64], thr: f64) -> Vec<(usize, usize)> {
    let mut out: Vec<(usize, usize)> = Vec::new();
    let mut start = None;
    for k in 0..=rms.len() {
        let active = k < rms.len() && rms[k] > thr;
        match (active, start) {
            (true, None) => start = Some(k),
            (false, Some(a)) => {
                match out.last_mut() {
                    Some(last) if t[a] - t[last.1] < 10.0 => last.1 = k - 1,
                    _ => out.push((a, k - 1)),
                }
                start = None;
            }
            _ => {}
        }
    }
    out
}

/// The period (twice the mean interval between zero crossings, at least two crossings) and
/// the peak of `band` over times `t`.
fn oscillation(t: &[f64], band: &[f64]) -> Option<(f64, f64)> {
    let crossings: Vec<f64> = t
        .windows(2)
        .zip(band.windows(2))
        .filter(|(_, b)| b[0] * b[1] < 0.0)
        .map(|(t, b)| t[0] + (t[1] - t[0]) * b[0] / (b[0] - b[1]))
        .collect();
    if crossings.len() < 2 {
        return None;
    }
    let period =
        2.0 * (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let amplitude = band.iter().fold(0.0f64, |m, b| m.max(b.abs()));
    Some((period, amplitude))
}

/// The elevator's largest held change (2 s after against 5 s before) from `from_s` to
/// `to_s`: its time and size, rad; `None` without an elevator or a change.
fn pull(t: &[f64], de: &[Option<f64>], from_s: f64, to_s: f64) -> Option<(f64, f64)> {
    let mean = |a: f64, b: f64| {
        let v: Vec<f64> =
            t.iter().zip(de).filter(|(t, _)| (a..b).contains(*t)).filter_map(|(_, d)| *d).collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    let lo = t.partition_point(|x| *x < from_s);
    let hi = t.partition_point(|x| *x <= to_s);
    // Every fifth sample is enough to place a pull held for seconds.
    (lo..hi)
        .step_by(5)
        .filter_map(|k| Some((t[k], mean(t[k], t[k] + 2.0)? - mean(t[k] - 5.0, t[k])?)))
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .filter(|p| p.1 != 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 600 s at 10 Hz, 100 m/s: an elevator pull of 0.5° held from 200 s, then a phugoid of
    /// 40 s period and 3 m/s amplitude decaying slowly, with a 3-2-1-1-like 1 Hz ripple of
    /// 0.3 m/s throughout: one phugoid, the pull placed within a second, the period within
    /// 10 %; the same record without the phugoid has none.
    #[test]
    fn analytic_held_pull_and_phugoid_are_found() {
        let record = |with: bool| -> Vec<AirDataSample> {
            (0..6000)
                .map(|k| {
                    let t = k as f64 * 0.1;
                    let after = t - 201.0;
                    let phugoid = if with && after > 0.0 {
                        3.0 * (-after / 300.0).exp() * (std::f64::consts::TAU * after / 40.0).sin()
                    } else {
                        0.0
                    };
                    AirDataSample {
                        t_s: t,
                        vt_mps: 100.0 + phugoid + 0.3 * (std::f64::consts::TAU * t).sin(),
                        qbar_pa: 5000.0,
                        de_rad: Some(if with && t >= 200.0 { -0.5f64.to_radians() } else { 0.0 }),
                        ..Default::default()
                    }
                })
                .collect()
        };
        let found = phugoids(&record(true), 100.0, |_| true, &PhugoidRule::default());
        assert_eq!(found.len(), 1, "{found:?}");
        let p = &found[0];
        assert!((p.pull_at_s.unwrap() - 200.0).abs() <= 1.0, "{p:?}");
        assert!(p.pull_rad.unwrap() < 0.0, "{p:?}");
        assert!((p.period_s / 40.0 - 1.0).abs() < 0.1, "{p:?}");
        assert!(p.end_s > 400.0, "{p:?}");
        assert!(phugoids(&record(false), 100.0, |_| true, &PhugoidRule::default()).is_empty());
    }
}
