//! Where a whole-flight record is not in flight: the ground, the taxi, the take-off and
//! landing rolls, told apart from flight by physics before any manoeuvre is judged.
//!
//! # The rule ([`EnvelopeRule`], defaults in brackets)
//!
//! A sample is on the ground (or rolling) when either
//! 1. its airspeed is below `speed_fraction` [0.6] of the record's airborne speed: the median
//!    airspeed of the samples faster than `airborne_share` (½) of the record's
//!    `reference_quantile` [95 %] airspeed. A taxi (5–15 m/s) and a take-off or landing roll
//!    are far below any cruise or manoeuvring speed (an approach at 1.3 stall speeds is about
//!    0.5–0.7 of a cruise speed of 2–2.5 stall speeds, so an approach may be left out too; a
//!    record flown all at one speed loses nothing); or
//! 2. its dynamic pressure is below `stall_margin`² [1.3²] × W/(S·`cl_max`) [`cl_max` = 2,
//!    above the flaps-down maximum lift coefficient of a business jet or transport]: a wing
//!    at that dynamic pressure would need a lift coefficient above `cl_max`/1.3² ≈ 1.18 to
//!    carry the aircraft, more than any manoeuvre at 1.3 stall speeds asks. Used only when
//!    the mapping gives the mass and wing area (W = m·g); the measured dynamic pressure is
//!    the sample's, so a constant density in a mapping does not bias it.
//!
//! Runs of such samples shorter than `min_span_s` [2 s] are a sensor's drop-out, not a
//! landing, and are kept. Each ground run is widened by `margin_s` [10 s] on both sides: the
//! rotation and lift-off, the flare and touch-down, with the gear and flaps moving and the
//! aircraft in ground effect, lie just above the speed floor.
//!
//! Altitude or height and an on-ground (weight-on-wheels) flag are not used: the air-data
//! sample carries neither (a mapping has no channel for them). The throttle, where mapped, is
//! reported with each span (take-off power on a roll, idle on a taxi) but decides nothing: a
//! throttle at take-off power is also a climb.

use aeroident_estimators::AirDataSample;
use serde::Serialize;

/// The thresholds of the ground rule (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EnvelopeRule {
    /// Quantile (0–1) of the airspeed taken as the record's top speed.
    pub reference_quantile: f64,
    /// Samples faster than this fraction of the top speed are airborne for the median.
    pub airborne_share: f64,
    /// On the ground below this fraction of the airborne median airspeed.
    pub speed_fraction: f64,
    /// Maximum lift coefficient of the dynamic-pressure floor.
    pub cl_max: f64,
    /// Margin on the stall speed of the dynamic-pressure floor (its square on q̄).
    pub stall_margin: f64,
    /// Ground runs shorter than this are kept as flight, s.
    pub min_span_s: f64,
    /// Ground runs are widened by this on both sides, s.
    pub margin_s: f64,
}

impl Default for EnvelopeRule {
    fn default() -> Self {
        Self {
            reference_quantile: 0.95,
            airborne_share: 0.5,
            speed_fraction: 0.6,
            cl_max: 2.0,
            stall_margin: 1.3,
            min_span_s: 2.0,
            margin_s: 10.0,
        }
    }
}

/// One stretch of the record left out as not in flight.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GroundSpan {
    /// First time left out (margin included), s.
    pub start_s: f64,
    /// Last time left out, s.
    pub end_s: f64,
    /// What it is: `before take-off`, `after landing` or `low speed in the record`.
    pub kind: String,
    /// Highest airspeed of the samples that broke the rule, m/s.
    pub max_speed_mps: f64,
    /// Throttle range over the span (where mapped), the mapping's unit.
    pub throttle: Option<[f64; 2]>,
}

/// The flight envelope of a record: its speeds and its ground spans.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Envelope {
    /// The rule used.
    pub rule: EnvelopeRule,
    /// The record's airborne median airspeed, m/s.
    pub airborne_speed_mps: f64,
    /// The airspeed floor, m/s: `speed_fraction` × the airborne speed.
    pub min_speed_mps: f64,
    /// The dynamic-pressure floor, Pa, when the mapping gives mass and wing area.
    pub min_qbar_pa: Option<f64>,
    /// The stretches left out, in time order.
    pub ground: Vec<GroundSpan>,
}

impl Envelope {
    /// The seconds of `[start_s, end_s]` that lie in a ground span.
    pub fn ground_overlap_s(&self, start_s: f64, end_s: f64) -> f64 {
        self.ground.iter().map(|g| (end_s.min(g.end_s) - start_s.max(g.start_s)).max(0.0)).sum()
    }

    /// The longest piece of `[start_s, end_s]` outside every ground span, if any.
    pub fn airborne_part(&self, start_s: f64, end_s: f64) -> Option<(f64, f64)> {
        let mut pieces = vec![(start_s, end_s)];
        for g in &self.ground {
            pieces = pieces
                .into_iter()
                .flat_map(|(a, b)| {
                    let left = (a, b.min(g.start_s));
                    let right = (a.max(g.end_s), b);
                    [left, right].into_iter().filter(|(x, y)| y > x)
                })
                .collect();
        }
        pieces.into_iter().max_by(|x, y| (x.1 - x.0).total_cmp(&(y.1 - y.0)))
    }
}

/// Standard gravity, m/s² (the weight of the dynamic-pressure floor).
const G_MPS2: f64 = 9.80665;

/// The envelope of `samples` (time order) by `rule` (module doc); `None` for a record of no
/// finite airspeed.
pub fn envelope(samples: &[AirDataSample], rule: &EnvelopeRule) -> Option<Envelope> {
    let mut speeds: Vec<f64> =
        samples.iter().map(|s| s.vt_mps).filter(|v| v.is_finite() && *v >= 0.0).collect();
    if speeds.is_empty() {
        return None;
    }
    speeds.sort_by(f64::total_cmp);
    let top = speeds[((speeds.len() - 1) as f64 * rule.reference_quantile).round() as usize];
    let airborne: Vec<f64> =
        speeds.iter().copied().filter(|v| *v >= rule.airborne_share * top).collect();
    let airborne_speed_mps = airborne[airborne.len() / 2];
    let min_speed_mps = rule.speed_fraction * airborne_speed_mps;
    let c = samples[0].constants;
    let min_qbar_pa = (c.mass_kg > 0.0 && c.S_m2 > 0.0)
        .then(|| rule.stall_margin.powi(2) * c.mass_kg * G_MPS2 / (c.S_m2 * rule.cl_max));
    let slow = |s: &AirDataSample| {
        let below = |x: f64, floor: f64| x.is_nan() || x < floor;
        below(s.vt_mps, min_speed_mps) || min_qbar_pa.is_some_and(|q| below(s.qbar_pa, q))
    };
    let ground = ground_spans(samples, slow, rule);
    Some(Envelope { rule: *rule, airborne_speed_mps, min_speed_mps, min_qbar_pa, ground })
}

/// The runs of samples `slow` says are not flying, at least `min_span_s` long, widened by
/// `margin_s`, joined where they then overlap, and named.
fn ground_spans(
    samples: &[AirDataSample],
    slow: impl Fn(&AirDataSample) -> bool,
    rule: &EnvelopeRule,
) -> Vec<GroundSpan> {
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut start = None;
    for (k, s) in samples.iter().enumerate() {
        match (slow(s), start) {
            (true, None) => start = Some(k),
            (false, Some(a)) => {
                runs.push((a, k - 1));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(a) = start {
        runs.push((a, samples.len() - 1));
    }
    runs.retain(|&(a, b)| samples[b].t_s - samples[a].t_s >= rule.min_span_s);
    let (t0, t1) = (samples[0].t_s, samples[samples.len() - 1].t_s);
    let mut spans: Vec<GroundSpan> = Vec::new();
    for (a, b) in runs {
        let run = &samples[a..=b];
        let (start_s, end_s) = (
            (run[0].t_s - rule.margin_s).max(t0),
            (run[run.len() - 1].t_s + rule.margin_s).min(t1),
        );
        let max_speed_mps =
            run.iter().map(|s| s.vt_mps).filter(|v| v.is_finite()).fold(0.0, f64::max);
        let throttle = throttle_range(run);
        match spans.last_mut() {
            Some(last) if start_s <= last.end_s => {
                last.end_s = end_s;
                last.max_speed_mps = last.max_speed_mps.max(max_speed_mps);
                last.throttle = match (last.throttle, throttle) {
                    (Some(x), Some(y)) => Some([x[0].min(y[0]), x[1].max(y[1])]),
                    (x, y) => x.or(y),
                };
            }
            _ => spans.push(GroundSpan {
                start_s,
                end_s,
                kind: String::new(),
                max_speed_mps,
                throttle,
            }),
        }
    }
    for g in &mut spans {
        g.kind = match (g.start_s <= t0, g.end_s >= t1) {
            (true, true) => "the whole record",
            (true, false) => "before take-off",
            (false, true) => "after landing",
            (false, false) => "low speed in the record",
        }
        .into();
    }
    spans
}

/// The lowest and highest finite throttle of `run`, if any.
fn throttle_range(run: &[AirDataSample]) -> Option<[f64; 2]> {
    run.iter()
        .filter_map(|s| s.throttle.filter(|x| x.is_finite()))
        .fold(None, |r, x| Some(r.map_or([x, x], |[lo, hi]: [f64; 2]| [lo.min(x), hi.max(x)])))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t_s: f64, vt_mps: f64) -> AirDataSample {
        let mut s = AirDataSample {
            t_s,
            vt_mps,
            qbar_pa: 0.5 * 1.225 * vt_mps * vt_mps,
            throttle: Some(if vt_mps < 30.0 { 0.1 } else { 0.7 }),
            ..Default::default()
        };
        s.constants.mass_kg = 7000.0;
        s.constants.S_m2 = 30.0;
        s
    }

    /// A taxi at 8 m/s (0–100 s), a take-off roll to 100 m/s (100–130 s), flight at 100 m/s
    /// (130–400 s), a landing roll and taxi (400–460 s): two spans, named, the first ending
    /// 10 s after the speed passed the floor, the flight between them kept.
    #[test]
    fn analytic_taxi_and_rolls_are_left_out_flight_kept() {
        let speed = |t: f64| match t {
            t if t < 100.0 => 8.0,
            t if t < 130.0 => 8.0 + (t - 100.0) / 30.0 * 92.0,
            t if t < 400.0 => 100.0,
            t if t < 430.0 => 100.0 - (t - 400.0) / 30.0 * 92.0,
            _ => 8.0,
        };
        let samples: Vec<AirDataSample> =
            (0..4600).map(|k| sample(k as f64 * 0.1, speed(k as f64 * 0.1))).collect();
        let e = envelope(&samples, &EnvelopeRule::default()).unwrap();
        assert!((e.airborne_speed_mps - 100.0).abs() < 1e-9, "{e:?}");
        assert_eq!(e.ground.len(), 2, "{e:?}");
        // 0.6 × 100 m/s is passed at 100 + 52/92 × 30 s ≈ 117 s, plus the 10 s margin.
        let (g0, g1) = (&e.ground[0], &e.ground[1]);
        assert!(g0.start_s == 0.0 && (g0.end_s - 127.0).abs() < 0.5, "{g0:?}");
        assert_eq!(g0.kind, "before take-off");
        assert!((g1.start_s - 403.0).abs() < 0.5 && (g1.end_s - 459.9).abs() < 1e-9, "{g1:?}");
        assert_eq!(g1.kind, "after landing");
        assert_eq!(g0.throttle, Some([0.1, 0.7]));
        assert_eq!(e.airborne_part(50.0, 200.0), Some((g0.end_s, 200.0)));
        assert!(e.ground_overlap_s(200.0, 300.0) == 0.0);
    }

    /// A record flown at one speed throughout loses nothing; a one-second drop-out of the
    /// airspeed is kept as flight.
    #[test]
    fn analytic_steady_record_and_dropout_lose_nothing() {
        let mut samples: Vec<AirDataSample> =
            (0..1000).map(|k| sample(k as f64 * 0.1, 100.0)).collect();
        for s in &mut samples[500..510] {
            s.vt_mps = 0.0;
        }
        let e = envelope(&samples, &EnvelopeRule::default()).unwrap();
        assert!(e.ground.is_empty(), "{e:?}");
    }
}
