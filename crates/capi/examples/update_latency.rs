//! The latency of one `aeroident_estimator_update` through the C ABI, update by update: RLS,
//! FTR (as it is, and with `spread_sigma = true`) and the EKF over the six-axis preset, 10⁶
//! updates each, and the p50, p99, p99.99 and largest update time (docs/c-abi.md, "Timing").
//!
//! ```text
//! cargo run --release -p aeroident-capi --example update_latency [-- UPDATES]
//! ```
//!
//! The samples are the six-axis test aircraft's (`six_axis_stream`: the update bench's),
//! 20,000 at 50 Hz replayed again and again with the time moved on by 400 s each time and a
//! new manoeuvre started (outside the timed span). Each update is timed alone with
//! `std::time::Instant` (its own cost, about 20 ns, is in every number). Each estimator makes
//! five passes over the same samples from a fresh start; besides the first pass's times the
//! table gives, for each update, the least of its five times: the operating system's
//! interruptions (preemption on a shared machine) fall on different updates in each pass and
//! drop out, what an update costs by its own work stays.

#[path = "../../estimators/src/test_aircraft.rs"]
mod test_aircraft;

use aeroident_capi::*;
use std::ffi::CString;
use std::time::Instant;

const STREAM: usize = 20_000;
const DT_S: f64 = 0.02;

/// Timed passes over the same samples: an update slowed by the operating system (preempted,
/// interrupted) is slow in one pass only, one slow by its own work in every pass.
const PASSES: usize = 5;

fn main() {
    let updates: usize = std::env::args().nth(1).map_or(1_000_000, |a| a.parse().expect("UPDATES"));
    let stream: Vec<AeroidentSample> = test_aircraft::six_axis_stream(STREAM, DT_S, 20.0)
        .iter()
        .map(AeroidentSample::from_air_data)
        .collect();
    println!("{updates} updates each, six-axis preset, through the C ABI (ns per update)\n");
    println!(
        "| estimator | timing | p50 | p99 | p99.99 | max | max / p50 | updates > 5 × p50 | slowest update |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for (kind, options) in [("rls", ""), ("ftr", ""), ("ftr", "spread_sigma = true"), ("ekf", "")] {
        let switches = involuntary_switches();
        let passes: Vec<Vec<u64>> =
            (0..PASSES).map(|_| timed(kind, options, &stream, updates)).collect();
        let kind =
            if options.is_empty() { kind.to_string() } else { format!("{kind} ({options})") };
        let kind = kind.as_str();
        let switches = involuntary_switches().zip(switches).map(|(b, a)| b - a);
        let least: Vec<u64> =
            (0..updates).map(|i| passes.iter().map(|p| p[i]).min().unwrap()).collect();
        row(kind, "one pass", passes[0].clone());
        row(kind, &format!("least of {PASSES} passes"), least);
        if let Some(n) = switches {
            println!(
                "|  | involuntary context switches in the {PASSES} passes: {n} | | | | | | | |"
            );
        }
    }
}

/// One row of the table: the percentiles of `ns` and the number of the slowest update.
fn row(kind: &str, timing: &str, mut ns: Vec<u64>) {
    let slowest = (0..ns.len()).max_by_key(|&i| ns[i]).unwrap();
    ns.sort_unstable();
    let at = |q: f64| ns[((ns.len() as f64 * q) as usize).min(ns.len() - 1)];
    let (p50, max) = (at(0.5), *ns.last().unwrap());
    let over = ns.iter().filter(|&&t| t > 5 * p50).count();
    println!(
        "| {kind} | {timing} | {p50} | {} | {} | {max} | {:.1} | {over} ({:.3} %) | {slowest} |",
        at(0.99),
        at(0.9999),
        max as f64 / p50 as f64,
        100.0 * over as f64 / ns.len() as f64
    );
}

/// This process's involuntary context switches so far (Linux `/proc/self/status`), if known.
fn involuntary_switches() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("nonvoluntary_ctxt_switches"))?;
    line.split_whitespace().last()?.parse().ok()
}

/// The time of each of `updates` updates of a new `kind` estimator with `options` (TOML), ns.
fn timed(kind: &str, options: &str, stream: &[AeroidentSample], updates: usize) -> Vec<u64> {
    let (k, m) = (CString::new(kind).unwrap(), CString::new("six-axis").unwrap());
    let o = CString::new(options).unwrap();
    let mut e = std::ptr::null_mut();
    // SAFETY: valid strings and out pointer.
    let r = unsafe { aeroident_estimator_new(k.as_ptr(), m.as_ptr(), o.as_ptr(), &mut e) };
    assert_eq!(r, AeroidentResult::Ok, "{kind}");
    let mut ns = Vec::with_capacity(updates);
    let mut refused = 0;
    let period_s = STREAM as f64 * DT_S;
    for i in 0..updates {
        let (lap, j) = (i / stream.len(), i % stream.len());
        if j == 0 && lap > 0 {
            // SAFETY: a live handle.
            unsafe { aeroident_estimator_new_manoeuvre(e) };
        }
        let s = AeroidentSample { t_s: stream[j].t_s + lap as f64 * period_s, ..stream[j] };
        let t0 = Instant::now();
        // SAFETY: a live handle and an initialised sample.
        let r = unsafe { aeroident_estimator_update(e, &s) };
        ns.push(t0.elapsed().as_nanos() as u64);
        refused += usize::from(r != AeroidentResult::Ok);
    }
    // SAFETY: a live handle, freed once.
    unsafe { aeroident_estimator_free(e) };
    assert_eq!(refused, 0, "{kind}: {refused} updates refused");
    ns
}
