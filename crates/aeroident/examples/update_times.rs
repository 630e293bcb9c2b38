//! Per-sample update-time distribution of the real-time estimators (target: worst
//! case ≤ 5× the median for RLS and FTR, ≤ 10× for the EKF).
//!
//! Flies the synthetic six-axis test aircraft (the update bench's generator,
//! `crates/estimators/src/test_aircraft.rs`) for `N` samples at 50 Hz with elevator, aileron and
//! rudder doublets repeated every 20 s, every channel present, and times each `update` with
//! `std::time::Instant` after a warm-up. Prints p50, p99, p99.9, max and max/p50 per estimator.
//!
//! Run: `cargo run --release -p aeroident --example update_times [N]` (default 60,000 samples,
//! 20 min of flight).
//!
//! The stream is replayed `REPEATS` times through a fresh estimator (the updates are
//! deterministic, so sample k costs the same computation every time). Two worst cases are
//! printed: `max` is the raw wall-clock maximum over all repeats (includes preemption and page
//! faults by the OS on a shared machine); `max-of-min` takes, per sample, the fastest of the
//! repeats and then the maximum over samples: the algorithm's own worst case (a sample whose
//! update does more work is slow in every repeat), with OS noise removed.
#![allow(missing_docs)]

#[path = "../../estimators/src/test_aircraft.rs"]
mod test_aircraft;

use aeroident_estimators::Priors;
use aeroident_estimators::vocabulary::ModelStructure;
use aeroident_pipelines::estimators::{EstimatorKind, EstimatorOptions, build};
use std::hint::black_box;
use std::time::Instant;

/// Samples discarded before timing (caches, branch predictors, estimator start-up).
const WARMUP: usize = 2000;
/// Replays of the stream (module doc).
const REPEATS: usize = 5;

fn pct(sorted: &[u64], p: f64) -> u64 {
    sorted[((p * (sorted.len() - 1) as f64).round() as usize).min(sorted.len() - 1)]
}

fn main() {
    let n: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(60_000);
    let data = test_aircraft::six_axis_stream(n.max(WARMUP + 1), 0.02, 20.0);
    println!(
        "{} samples at 50 Hz, {} timed after {WARMUP} warm-up",
        data.len(),
        data.len() - WARMUP
    );
    println!(
        "estimator        structure     p50 ns   p99 ns  p99.9 ns    max ns max/p50  max-of-min ns  /p50  refused"
    );
    let spread = EstimatorOptions { ftr_spread_sigma: true, ..EstimatorOptions::default() };
    let plain = EstimatorOptions::default();
    for (kind, st, label, options) in [
        (EstimatorKind::Rls, ModelStructure::six_axis(), "six-axis", &plain),
        (EstimatorKind::Ftr, ModelStructure::six_axis(), "six-axis", &plain),
        (EstimatorKind::Ftr, ModelStructure::six_axis(), "six, spread", &spread),
        (EstimatorKind::Ekf, ModelStructure::longitudinal(), "longitudinal", &plain),
        (EstimatorKind::Ekf, ModelStructure::lateral(), "lateral", &plain),
        (EstimatorKind::SmpeCorrected, ModelStructure::six_axis(), "six-axis", &plain),
    ] {
        let mut all = Vec::with_capacity(REPEATS * data.len());
        let mut best = vec![u64::MAX; data.len() - WARMUP];
        let mut refused = 0usize;
        for _ in 0..REPEATS {
            let mut e = match build(kind, st, Priors::generic(&st), options) {
                Ok(e) => e,
                Err(err) => {
                    println!("{:<16} {label:<12} not built: {err}", kind.name());
                    break;
                }
            };
            for (k, s) in data.iter().enumerate() {
                let t0 = Instant::now();
                let ok = e.update(black_box(s)).is_ok();
                let ns = t0.elapsed().as_nanos() as u64;
                refused += usize::from(!ok);
                if k >= WARMUP {
                    all.push(ns);
                    best[k - WARMUP] = best[k - WARMUP].min(ns);
                }
            }
        }
        if all.is_empty() {
            continue;
        }
        all.sort_unstable();
        let p50 = pct(&all, 0.5);
        let max = *all.last().unwrap();
        let wc = best.iter().copied().max().unwrap_or(0);
        println!(
            "{:<16} {label:<12} {p50:>8} {:>8} {:>9} {max:>9} {:>7.0} {wc:>14} {:>5.1} {refused:>8}",
            kind.name(),
            pct(&all, 0.99),
            pct(&all, 0.999),
            max as f64 / p50.max(1) as f64,
            wc as f64 / p50.max(1) as f64,
        );
    }
}
