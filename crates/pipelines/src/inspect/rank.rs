//! The candidates of a whole record judged in flight terms: the ground spans left out
//! ([`super::envelope`]), phugoids added ([`super::phugoid`]), and the rest ranked per axis by
//! the information they hold ([`super::information`]), with the best few of each axis formed
//! into a set of windows fitted together (`--window auto:N`).
//!
//! # Candidates
//!
//! The surface detector's windows joined where they overlap (one manoeuvre seen on two
//! surfaces), and each phugoid as a candidate of its own (it may overlap an input window: a
//! set takes only one of two that overlap). A candidate more than half of which lies in a
//! ground span is left out, naming the span; one that only touches a ground span is clipped
//! to its longest airborne piece. Every candidate's information is computed, the left-out
//! ones' too, so the listing shows why a taxi would have ranked low anyway.
//!
//! # Ranking and sets
//!
//! Per axis, the airborne candidates that identify it: first those that leave fewest of its
//! derivatives unidentified (a surface held still), then by score (lower first). The set of
//! an axis is `N` of them that do not overlap one another, in time order, taken in rank order
//! but preferring at each step one that identifies a derivative the set does not yet (an
//! aileron window and a rudder window before two aileron windows): the windows an engineer
//! fits jointly for that axis, each its own manoeuvre.

use super::envelope::Envelope;
use super::information::{Axis, AxisInformation, information};
use super::phugoid::{Phugoid, PhugoidRule, phugoids};
use crate::window::TimeWindow;
use aeroident_estimators::AirDataSample;
use serde::Serialize;
use std::collections::BTreeMap;

/// One candidate window of the record.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Candidate {
    /// Window start, s (clipped to flight where it touched a ground span).
    pub start_s: f64,
    /// Window end, s.
    pub end_s: f64,
    /// `input` (the surface detector's) or `phugoid`.
    pub kind: String,
    /// The surface channels moving in it (empty for a phugoid).
    pub channels: Vec<String>,
    /// The phugoid, for a phugoid candidate.
    pub phugoid: Option<Phugoid>,
    /// Why it is left out (a ground span), `None` when in flight.
    pub excluded: Option<String>,
    /// Per axis, what the window tells (over the window before any clipping).
    pub information: Vec<AxisInformation>,
}

impl Candidate {
    /// What the window tells about `axis`.
    pub fn info(&self, axis: Axis) -> Option<&AxisInformation> {
        self.information.iter().find(|i| i.axis == axis)
    }

    /// The rank key of `axis` (lower first): the derivatives it leaves unidentified, then its
    /// score; `None` when the window does not identify the axis.
    fn key(&self, axis: Axis) -> Option<(usize, f64)> {
        let info = self.info(axis)?;
        Some((info.not_identified.len(), info.score?))
    }
}

/// The flight-terms judgement of a record's candidates.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Ranking {
    /// The ground rule and spans; `None` for a record without an airspeed.
    pub envelope: Option<Envelope>,
    /// The phugoid rule used.
    pub phugoid_rule: PhugoidRule,
    /// The candidates, in time order.
    pub candidates: Vec<Candidate>,
    /// Per axis (`pitch`, `lateral`), indices into `candidates`, best first (airborne and
    /// identifying the axis only).
    pub ranked: BTreeMap<String, Vec<usize>>,
    /// How many windows a set takes per axis.
    pub set_size: usize,
    /// Per axis, the set: its best `set_size` non-overlapping windows, in time order.
    pub window_sets: BTreeMap<String, Vec<[f64; 2]>>,
    /// The surface detector over the ground spans alone, by their own levels (its
    /// candidates are the left-out ones); empty when the record has no ground span.
    pub ground_detections: Vec<super::detect::ChannelDetection>,
}

/// Windows per axis of the sets `inspect` lists: two, the pair an engineer fits jointly.
pub const DEFAULT_SET_SIZE: usize = 2;

/// Judges the input windows `inputs` (`(start, end, channel)`, s; those found in flight and
/// those found on the ground, each joined where they overlap) of the record `samples` (time
/// order) whose envelope is `envelope`: phugoids, information, ranks and sets of `set_size`
/// per axis (`ground_detections` left empty for the caller).
pub fn rank(
    samples: &[AirDataSample],
    envelope: Option<Envelope>,
    inputs: &[Vec<(f64, f64, String)>; 2],
    set_size: usize,
) -> Ranking {
    let phugoid_rule = PhugoidRule::default();
    let found = envelope.as_ref().map_or_else(Vec::new, |e| {
        phugoids(samples, e.airborne_speed_mps, |t| !on_ground(e, t), &phugoid_rule)
    });
    let mut candidates: Vec<Candidate> = inputs.iter().flat_map(|i| join_inputs(i)).collect();
    candidates.extend(found.into_iter().map(|p| Candidate {
        start_s: p.start_s,
        end_s: p.end_s,
        kind: "phugoid".into(),
        channels: vec![],
        phugoid: Some(p),
        excluded: None,
        information: vec![],
    }));
    candidates.sort_by(|a, b| a.start_s.total_cmp(&b.start_s));
    for c in &mut candidates {
        let lo = samples.partition_point(|s| s.t_s < c.start_s);
        let hi = samples.partition_point(|s| s.t_s <= c.end_s);
        c.information = Axis::ALL.iter().map(|&a| information(&samples[lo..hi], a)).collect();
        if let Some(e) = &envelope {
            judge_ground(c, e);
        }
    }
    let ranked: BTreeMap<String, Vec<usize>> =
        Axis::ALL.iter().map(|&a| (a.name().to_string(), ranked(&candidates, a))).collect();
    let window_sets = Axis::ALL
        .iter()
        .map(|&a| (a.name().to_string(), best_set(&candidates, &ranked[a.name()], a, set_size)))
        .collect();
    Ranking {
        envelope,
        phugoid_rule,
        candidates,
        ranked,
        set_size,
        window_sets,
        ground_detections: vec![],
    }
}

/// Whether time `t` lies inside a ground span of `e`.
fn on_ground(e: &Envelope, t: f64) -> bool {
    e.ground.iter().any(|g| (g.start_s..=g.end_s).contains(&t))
}

/// The input windows joined where they overlap, each with the channels it holds.
fn join_inputs(inputs: &[(f64, f64, String)]) -> Vec<Candidate> {
    let mut w: Vec<&(f64, f64, String)> = inputs.iter().collect();
    w.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<Candidate> = Vec::new();
    for (a, b, channel) in w {
        match out.last_mut() {
            Some(last) if *a <= last.end_s => {
                last.end_s = last.end_s.max(*b);
                if !last.channels.contains(channel) {
                    last.channels.push(channel.clone());
                }
            }
            _ => out.push(Candidate {
                start_s: *a,
                end_s: *b,
                kind: "input".into(),
                channels: vec![channel.clone()],
                phugoid: None,
                excluded: None,
                information: vec![],
            }),
        }
    }
    out
}

/// Leaves `c` out when more than half of it is on the ground, else clips it to its longest
/// airborne piece.
fn judge_ground(c: &mut Candidate, e: &Envelope) {
    let length = c.end_s - c.start_s;
    let overlap = e.ground_overlap_s(c.start_s, c.end_s);
    if overlap == 0.0 {
        return;
    }
    let piece = e.airborne_part(c.start_s, c.end_s);
    match piece {
        Some((a, b)) if overlap <= 0.5 * length => {
            c.start_s = a;
            c.end_s = b;
        }
        _ => {
            let spans: Vec<String> = e
                .ground
                .iter()
                .filter(|g| g.end_s > c.start_s && g.start_s < c.end_s)
                .map(|g| format!("{} {:.1}–{:.1} s", g.kind, g.start_s, g.end_s))
                .collect();
            c.excluded = Some(format!("on the ground ({})", spans.join(", ")));
        }
    }
}

/// The airborne candidates that identify `axis`, best first: fewest derivatives left
/// unidentified, then lowest score.
fn ranked(candidates: &[Candidate], axis: Axis) -> Vec<usize> {
    let mut order: Vec<(usize, (usize, f64))> = candidates
        .iter()
        .enumerate()
        .filter(|(_, c)| c.excluded.is_none())
        .filter_map(|(k, c)| Some((k, c.key(axis)?)))
        .collect();
    order.sort_by(|a, b| a.1.0.cmp(&b.1.0).then(a.1.1.total_cmp(&b.1.1)));
    order.into_iter().map(|(k, _)| k).collect()
}

/// `n` windows of `order` (ranked for `axis`) that overlap none taken before, in time order.
/// Each step takes the first in rank order that identifies a derivative the set does not yet
/// identify, else the first: an aileron window and a rudder window make a lateral set before
/// two aileron windows do.
fn best_set(candidates: &[Candidate], order: &[usize], axis: Axis, n: usize) -> Vec<[f64; 2]> {
    let mut set: Vec<[f64; 2]> = Vec::new();
    let mut covered: Vec<&String> = Vec::new();
    let mut left: Vec<usize> = order.to_vec();
    while set.len() < n {
        left.retain(|&k| {
            let c = &candidates[k];
            set.iter().all(|w| c.end_s <= w[0] || c.start_s >= w[1])
        });
        let identifies = |k: &usize| {
            candidates[*k].info(axis).map_or(Vec::new(), |i| i.sigma.keys().collect::<Vec<_>>())
        };
        let adds = left.iter().position(|k| identifies(k).iter().any(|d| !covered.contains(d)));
        let Some(pos) = adds.or((!left.is_empty()).then_some(0)) else { break };
        let k = left.remove(pos);
        covered.extend(identifies(&k));
        set.push([candidates[k].start_s, candidates[k].end_s]);
    }
    set.sort_by(|a, b| a[0].total_cmp(&b[0]));
    set
}

/// The windows of `sets` (every axis's), joined where they overlap, in time order: what
/// `--window auto:N` fits.
pub fn union_of_sets(sets: &BTreeMap<String, Vec<[f64; 2]>>) -> Vec<TimeWindow> {
    let mut w: Vec<[f64; 2]> = sets.values().flatten().copied().collect();
    w.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let mut out: Vec<TimeWindow> = Vec::new();
    for [a, b] in w {
        match out.last_mut() {
            Some(last) if a <= last.end_s => last.end_s = last.end_s.max(b),
            _ => out.push(TimeWindow { start_s: a, end_s: b }),
        }
    }
    out
}

/// The windows of every airborne candidate, joined where they overlap, in time order: what
/// `--window auto` fits.
pub fn airborne_windows(ranking: &Ranking) -> Vec<TimeWindow> {
    let all: BTreeMap<String, Vec<[f64; 2]>> = [(
        String::new(),
        ranking
            .candidates
            .iter()
            .filter(|c| c.excluded.is_none())
            .map(|c| [c.start_s, c.end_s])
            .collect(),
    )]
    .into();
    union_of_sets(&all)
}
