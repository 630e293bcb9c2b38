//! `aeroident bench`: simulation speed of the F-16.
//!
//! Measures one RK4 step of the 13-state F-16 (4 derivative evaluations) at a trimmed condition
//! (20 000 ft, 675 ft/s, xcg 0.30, the thesis's condition) on one core: the median over
//! `BATCHES` short batches (100 steps, ~0.1 ms: short enough that most batches run without
//! being preempted on a shared machine) of the mean time per step, and the real-time factor at 100 Hz
//! (`0.01 s / step time`). The criterion benchmark `crit_f16_rk4` measures the same step.

use aeroident_models::f16::{F16, F16Controls, F16State};
use aeroident_models::integrate::rk4_step;
use aeroident_models::trim::{TrimCondition, trim};
use anyhow::Context;
use serde_json::json;
use std::hint::black_box;
use std::time::Instant;

/// Arguments of `aeroident bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Print JSON `{"f16_rk4_step_ns", "f16_realtime_factor_100hz"}`.
    #[arg(long)]
    pub json: bool,
}

const BATCHES: usize = 1001;
const STEPS_PER_BATCH: usize = 100;

/// Result of [`measure_f16_rk4`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct F16Bench {
    /// Median time of one RK4 step, ns.
    pub rk4_step_ns: f64,
    /// Real-time factor at a 100 Hz step (0.01 s / step time).
    pub realtime_factor_100hz: f64,
}

/// Times the F-16 RK4 step (module doc).
///
/// # Errors
/// Trim failure or a model error during the run.
pub fn measure_f16_rk4() -> anyhow::Result<F16Bench> {
    let f16 = F16::new(0.30)?;
    let t = trim(&f16, &TrimCondition::level(20_000.0, 675.0)).context("trim for the benchmark")?;
    // A small elevator offset so the state moves and every branch is live.
    let u = F16Controls { elevator_rad: t.controls.elevator_rad + 0.002, ..t.controls };
    let dt = 0.01;
    let mut per_step = Vec::with_capacity(BATCHES);
    for _ in 0..BATCHES {
        let mut x: F16State = t.state;
        let start = Instant::now();
        for k in 0..STEPS_PER_BATCH {
            x = rk4_step(black_box(&f16), k as f64 * dt, &x, black_box(&u), dt)?;
        }
        let ns = start.elapsed().as_nanos() as f64 / STEPS_PER_BATCH as f64;
        black_box(x);
        per_step.push(ns);
    }
    per_step.sort_by(f64::total_cmp);
    let median = per_step[BATCHES / 2];
    Ok(F16Bench { rk4_step_ns: median, realtime_factor_100hz: 0.01e9 / median })
}

/// Runs `aeroident bench`.
///
/// # Errors
/// As [`measure_f16_rk4`].
pub fn execute(args: BenchArgs) -> anyhow::Result<()> {
    let b = measure_f16_rk4()?;
    if args.json {
        super::print_stdout(
            &json!({ "f16_rk4_step_ns": b.rk4_step_ns, "f16_realtime_factor_100hz": b.realtime_factor_100hz })
                .to_string(),
        )?;
    } else {
        super::print_stdout(&format!(
            "F-16 RK4 step (13 states, 4 derivative evaluations), median of {BATCHES} x {STEPS_PER_BATCH} steps: {:.0} ns\nreal-time factor at 100 Hz on one core: {:.0}x (target >= 5000x)",
            b.rk4_step_ns, b.realtime_factor_100hz
        ))?;
    }
    Ok(())
}
