//! The contest of `docs/smpe-finite-time.md`: `N` seeded runs of a scenario (the Monte Carlo
//! seed rule of `aeroident_pipelines::montecarlo`), and per estimator and primary derivative
//! the RMS relative error over the flight before and after the damage, the median time to
//! within ±10 % and back within ±10 % after the damage, the ±2σ coverage of the final
//! estimate, its scatter over the Cramér–Rao bound and mean σ over scatter.
//!
//! Run: `cargo run --release -p aeroident --example sliding_contest -- SCENARIO RUNS SEED
//! [--noise-scale K] [--calm]` (`K = 0`: no sensor noise; `--calm`: the scenario's winds
//! removed). Prints one markdown table.
//!
//! The RMS windows leave out the 5 s the targets allow after the start of the excitation and
//! after the damage: `[t_exc + 5, t_damage)` and `[t_damage + 5, end]`; a sample whose estimate
//! is not identified there counts as a 100 % error.
#![allow(missing_docs)]

use aeroident_pipelines::aircraft::Scenario;
use aeroident_pipelines::aircraft::summary::PRIMARY_DERIVATIVES;
use aeroident_pipelines::aircraft::{RunOutput, run};
use aeroident_pipelines::montecarlo::{
    RunResult, crb_sigmas, run_result, run_seed, seeded_scenario, statistics,
};
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Per (estimator, parameter): squared relative errors summed and counted, before and after.
type Rms = BTreeMap<(String, String), [(f64, usize); 2]>;

fn rms_of(out: &RunOutput, damage_s: f64) -> Rms {
    let start = out.excitation_start_s.unwrap_or(0.0) + 5.0;
    let mut acc = Rms::new();
    for ch in &out.channels {
        for p in &ch.params {
            let name = p.param.name();
            if !PRIMARY_DERIVATIVES.contains(&name) {
                continue;
            }
            let e = acc.entry((ch.label.clone(), name.to_string())).or_default();
            for (k, &t) in out.t_s.iter().enumerate() {
                let w = if t >= start && t < damage_s {
                    0
                } else if t >= damage_s + 5.0 {
                    1
                } else {
                    continue;
                };
                let Some(truth) = p.truth[k].filter(|v| *v != 0.0) else { continue };
                let rel = p.estimate[k].map_or(1.0, |v| (v - truth) / truth);
                e[w].0 += rel * rel;
                e[w].1 += 1;
            }
        }
    }
    acc
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .ok_or("usage: sliding_contest SCENARIO RUNS SEED [--noise-scale K] [--calm]")?;
    let runs: u64 = args.get(2).and_then(|a| a.parse().ok()).ok_or("RUNS")?;
    let seed: u64 = args.get(3).and_then(|a| a.parse().ok()).ok_or("SEED")?;
    let mut sc = Scenario::from_path(std::path::Path::new(path)).map_err(|e| e.to_string())?;
    let mut k = 4;
    while k < args.len() {
        match args[k].as_str() {
            "--noise-scale" => {
                let s: f64 = args.get(k + 1).and_then(|a| a.parse().ok()).ok_or("K")?;
                sc.sensors.noise = s > 0.0;
                sc.sensors.scale = if s > 0.0 { s } else { 1.0 };
                k += 2;
            }
            "--calm" => {
                sc.wind.clear();
                k += 1;
            }
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    let damage_s = sc
        .increments
        .values()
        .filter_map(|i| i.step_at_s)
        .fold(f64::INFINITY, f64::min)
        .min(sc.duration_s);
    let crb = crb_sigmas(&sc)?;
    let t0 = std::time::Instant::now();
    let results: Vec<(RunResult, Option<Rms>)> = (0..runs)
        .into_par_iter()
        .map(|i| {
            let s = seeded_scenario(&sc, seed, i);
            match run(&s) {
                Ok(out) => {
                    (run_result(i, run_seed(seed, i, 0), &out), Some(rms_of(&out, damage_s)))
                }
                Err(e) => (
                    RunResult {
                        index: i,
                        sensor_seed: run_seed(seed, i, 0),
                        outcome: Err(e.to_string()),
                    },
                    None,
                ),
            }
        })
        .collect();
    let wall = t0.elapsed().as_secs_f64();
    let mut total = Rms::new();
    for acc in results.iter().filter_map(|r| r.1.as_ref()) {
        for (key, v) in acc {
            let e = total.entry(key.clone()).or_default();
            for w in 0..2 {
                e[w].0 += v[w].0;
                e[w].1 += v[w].1;
            }
        }
    }
    let runs_only: Vec<RunResult> = results.into_iter().map(|r| r.0).collect();
    let names: Vec<String> = sc.estimator.iter().map(|e| e.label()).collect();
    let stats = statistics(&runs_only, &names, &crb);
    println!(
        "{path}: {runs} runs, seed {seed}, noise {}, winds {}; {wall:.0} s wall",
        if sc.sensors.noise { format!("×{}", sc.sensors.scale) } else { "×0".into() },
        sc.wind.len()
    );
    println!(
        "| estimator | derivative | RMS % before | RMS % after | t_10% s | re_10% s | ±2σ coverage % | scatter/CRB | σ/scatter |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let f = |v: Option<f64>, d: usize| v.map_or("—".to_string(), |v| format!("{v:.d$}"));
    for est in &stats {
        for p in est.parameters.iter().filter(|p| p.primary) {
            let r = total.get(&(est.name.clone(), p.name.clone()));
            let rms = |w: usize| {
                r.filter(|r| r[w].1 > 0).map(|r| 100.0 * (r[w].0 / r[w].1 as f64).sqrt())
            };
            println!(
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                est.name,
                p.name,
                f(rms(0), 1),
                f(rms(1), 1),
                f(p.median_time_to_10pct_s, 2),
                f(p.median_reconvergence_10pct_s, 2),
                f(p.coverage_2sigma.map(|c| 100.0 * c), 1),
                f(p.scatter.zip(p.crb_std_error).map(|(s, c)| s / c), 2),
                f(p.mean_std_error.zip(p.scatter).map(|(m, s)| m / s), 2),
            );
        }
        println!(
            "<!-- {}: {} runs ok, failed {} -->",
            est.name,
            est.runs_ok,
            est.failed_runs.len()
        );
    }
    Ok(())
}
