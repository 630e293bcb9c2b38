//! The measurements of `docs/change-detection.md`: `N` seeded runs of a scenario (the Monte
//! Carlo seed rule of `aeroident_pipelines::montecarlo`) and, per estimator and primary
//! derivative, the median time back within ±10 % after the damage (`montecarlo::statistics`,
//! the definition of `reconvergence_10pct_s`), the ±2σ coverage just before the damage and at
//! the end, and the change alarms: per equation, how many fired before the damage (false) and
//! the median delay of the first after it, and when in the flight the alarms fell (5-s bins).
//!
//! Run: `cargo run --release -p aeroident --example change_contest -- SCENARIO RUNS SEED
//! [--no-damage] [--duration-s T]` (`--no-damage`: the scenario's increments removed, every
//! alarm is false; `--duration-s`: the flight, and its turbulence, lengthened to `T`). Prints
//! markdown tables, the last the information limit: per run, each damaged derivative's step
//! against its σ just before the damage, beside the smallest step any test can detect within
//! 0.5 s at one false alarm per hour (`aeroident_estimators::change::detectable_step_sigmas`,
//! the estimator's own memory).
#![allow(missing_docs)]

use aeroident_estimators::change::{detectable_step_sigmas, detection_power};
use aeroident_pipelines::aircraft::Scenario;
use aeroident_pipelines::aircraft::summary::PRIMARY_DERIVATIVES;
use aeroident_pipelines::aircraft::{RunOutput, run};
use aeroident_pipelines::montecarlo::{
    RunResult, crb_sigmas, run_result, run_seed, seeded_scenario, statistics,
};
use aeroident_signals::config::WindConfig;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Per (estimator, parameter): runs covered within ±2σ just before the damage, and runs with
/// an estimate and σ there.
type Before = BTreeMap<(String, String), (usize, usize)>;
/// Per (estimator, equation): alarm times of one run.
type Alarms = BTreeMap<(String, String), Vec<f64>>;
/// Per (estimator, parameter whose truth steps, its coefficient): the step over the σ just
/// before it.
type Steps = BTreeMap<(String, String, &'static str), f64>;

/// Each stepped derivative's step (truth at the end less truth before the damage) over its σ
/// just before the damage.
fn steps_of(out: &RunOutput, damage_s: f64) -> Steps {
    let mut acc = Steps::new();
    let Some(k) = out.t_s.iter().rposition(|&t| t < damage_s) else { return acc };
    for ch in &out.channels {
        for p in &ch.params {
            let last = p.truth.last().copied().flatten();
            if let (Some(before), Some(after), Some(s)) = (p.truth[k], last, p.sigma[k])
                && (after - before).abs() > 1e-12 * before.abs().max(1e-12)
                && s > 0.0
            {
                let key =
                    (ch.label.clone(), p.param.name().to_string(), p.param.coefficient.name());
                acc.insert(key, (after - before).abs() / s);
            }
        }
    }
    acc
}

/// The memory `τ = dt/(1 − λ)` of estimator `label`'s `forgetting`; `None` without one (the
/// EKF's memory is its parameter walk: the limit, written for a forgetting factor, does not
/// apply).
fn memory_s(sc: &Scenario, label: &str) -> Option<f64> {
    let forgetting = sc.estimator.iter().find(|e| e.label() == label).and_then(|e| match e {
        aeroident_pipelines::aircraft::scenario::EstimatorSpec::Sample(s) => {
            s.options.get("forgetting").and_then(|v| v.as_float())
        }
        _ => None,
    });
    forgetting.map(|l| sc.dt_s / (1.0 - l))
}

/// The information-limit table: per stepped derivative, the median step/σ over the runs, the
/// runs in which it reaches the detectable step at even odds and at 95 %, and the best test's
/// mean detection probability; then per estimator the damage's (any equation detecting it,
/// each equation by its best-detected derivative).
fn print_information(sc: &Scenario, steps: &BTreeMap<(String, String, &'static str), Vec<f64>>) {
    println!(
        "| estimator | derivative | memory s | median step/σ | detectable at 50 %: σ, runs | at 95 %: σ, runs | best test detects, mean over runs |"
    );
    println!("|---|---|---|---|---|---|---|");
    // Per estimator, per equation, per run: the best test's probability.
    let mut per_eq: BTreeMap<&str, BTreeMap<&str, Vec<f64>>> = BTreeMap::new();
    for ((est, param, coefficient), q) in steps {
        let Some(tau) = memory_s(sc, est) else {
            println!(
                "| {est} | {param} | no forgetting factor: the limit does not apply | | | | |"
            );
            continue;
        };
        let limit = |power| detectable_step_sigmas(tau, 0.5, sc.dt_s, 3600.0, power);
        let (even, most) = (limit(0.5), limit(0.95));
        let over = |l: f64| q.iter().filter(|&&v| v >= l).count();
        let power: Vec<f64> =
            q.iter().map(|&v| detection_power(v, tau, 0.5, sc.dt_s, 3600.0)).collect();
        let eq = per_eq.entry(est).or_default().entry(coefficient).or_default();
        if eq.is_empty() {
            eq.resize(power.len(), 0.0);
        }
        for (e, p) in eq.iter_mut().zip(&power) {
            *e = e.max(*p);
        }
        println!(
            "| {est} | {param} | {tau:.1} | {:.1} | {even:.1}, {} of {} | {most:.1}, {} of {} | {:.0} % |",
            median(q.clone()).unwrap_or(f64::NAN),
            over(even),
            q.len(),
            over(most),
            q.len(),
            100.0 * power.iter().sum::<f64>() / power.len().max(1) as f64,
        );
    }
    println!();
    println!("| estimator | the damage detected by the best test within 0.5 s, mean over runs |");
    println!("|---|---|");
    for (est, eqs) in &per_eq {
        let runs = eqs.values().map(Vec::len).max().unwrap_or(0);
        let missed = |i: usize| eqs.values().map(move |p| 1.0 - p.get(i).copied().unwrap_or(0.0));
        let any: f64 = (0..runs).map(|i| 1.0 - missed(i).product::<f64>()).sum();
        println!("| {est} | {:.0} % |", 100.0 * any / runs.max(1) as f64);
    }
}

fn before_of(out: &RunOutput, damage_s: f64) -> Before {
    let mut acc = Before::new();
    let Some(k) = out.t_s.iter().rposition(|&t| t < damage_s) else { return acc };
    for ch in &out.channels {
        for p in &ch.params {
            let name = p.param.name();
            if !PRIMARY_DERIVATIVES.contains(&name) {
                continue;
            }
            let e = acc.entry((ch.label.clone(), name.to_string())).or_default();
            if let (Some(v), Some(s), Some(t)) = (p.estimate[k], p.sigma[k], p.truth[k]) {
                e.1 += 1;
                e.0 += usize::from((v - t).abs() <= 2.0 * s);
            }
        }
    }
    acc
}

fn alarms_of(out: &RunOutput) -> Alarms {
    let mut acc = Alarms::new();
    for ch in &out.channels {
        for e in ch.events.listed.iter().filter(|e| e.kind == "change_detected") {
            acc.entry((ch.label.clone(), e.subject.clone())).or_default().push(e.t_s);
        }
    }
    acc
}

/// Every estimator's alarms over all runs by when they fell in the flight, 5-s bins: the
/// start-up's alarms (the first seconds after identification) apart from the rest.
fn print_alarm_times(alarms: &BTreeMap<(String, String), Vec<Vec<f64>>>, duration_s: f64) {
    let bins = (duration_s / 5.0).ceil().max(1.0) as usize;
    let mut by_est: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for ((est, _), per_run) in alarms {
        let h = by_est.entry(est.as_str()).or_insert_with(|| vec![0; bins]);
        for &t in per_run.iter().flatten() {
            h[((t / 5.0) as usize).min(bins - 1)] += 1;
        }
    }
    println!("| estimator | alarms by 5-s bin of the flight, all runs and equations |");
    println!("|---|---|");
    for (est, h) in by_est {
        println!("| {est} | {h:?} |");
    }
    println!();
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    (!v.is_empty()).then(|| {
        let n = v.len();
        if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
    })
}

fn parse(args: &[String]) -> Result<(Scenario, u64, u64), String> {
    let path = args
        .get(1)
        .ok_or("usage: change_contest SCENARIO RUNS SEED [--no-damage] [--duration-s T]")?;
    let runs: u64 = args.get(2).and_then(|a| a.parse().ok()).ok_or("RUNS")?;
    let seed: u64 = args.get(3).and_then(|a| a.parse().ok()).ok_or("SEED")?;
    let mut sc = Scenario::from_path(std::path::Path::new(path)).map_err(|e| e.to_string())?;
    let mut k = 4;
    while k < args.len() {
        match args[k].as_str() {
            "--no-damage" => {
                sc.increments.clear();
                k += 1;
            }
            "--duration-s" => {
                let t: f64 = args.get(k + 1).and_then(|a| a.parse().ok()).ok_or("T")?;
                sc.duration_s = t;
                for w in &mut sc.wind {
                    if let WindConfig::Dryden { duration_s, .. } = w {
                        *duration_s = t + 1.0;
                    }
                }
                k += 2;
            }
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    Ok((sc, runs, seed))
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let (sc, runs, seed) = parse(&args)?;
    let damage_s = sc
        .increments
        .values()
        .filter_map(|i| i.step_at_s)
        .fold(f64::INFINITY, f64::min)
        .min(sc.duration_s);
    let crb = crb_sigmas(&sc)?;
    let t0 = std::time::Instant::now();
    type One = (RunResult, Option<(Before, Alarms, Steps)>);
    let results: Vec<One> = (0..runs)
        .into_par_iter()
        .map(|i| {
            let s = seeded_scenario(&sc, seed, i);
            let seed_i = run_seed(seed, i, 0);
            match run(&s) {
                Ok(out) => (
                    run_result(i, seed_i, &out),
                    Some((before_of(&out, damage_s), alarms_of(&out), steps_of(&out, damage_s))),
                ),
                Err(e) => {
                    (RunResult { index: i, sensor_seed: seed_i, outcome: Err(e.to_string()) }, None)
                }
            }
        })
        .collect();
    let wall = t0.elapsed().as_secs_f64();
    let mut before = Before::new();
    let mut alarms: BTreeMap<(String, String), Vec<Vec<f64>>> = BTreeMap::new();
    let mut steps: BTreeMap<(String, String, &'static str), Vec<f64>> = BTreeMap::new();
    for (b, a, q) in results.iter().filter_map(|r| r.1.as_ref()) {
        for (key, v) in q {
            steps.entry(key.clone()).or_default().push(*v);
        }
        for (key, v) in b {
            let e = before.entry(key.clone()).or_default();
            e.0 += v.0;
            e.1 += v.1;
        }
        for (key, v) in a {
            alarms.entry(key.clone()).or_default().push(v.clone());
        }
    }
    let ok = results.iter().filter(|r| r.1.is_some()).count();
    let runs_only: Vec<RunResult> = results.into_iter().map(|r| r.0).collect();
    let names: Vec<String> = sc.estimator.iter().map(|e| e.label()).collect();
    let stats = statistics(&runs_only, &names, &crb);
    let hours = ok as f64 * sc.duration_s / 3600.0;
    println!(
        "{}: {runs} runs ({ok} ok), seed {seed}, {} s each ({hours:.2} h of flight), damage at {damage_s} s; {wall:.0} s wall",
        args[1], sc.duration_s
    );
    println!("| estimator | derivative | re_10% s | ±2σ coverage before % | ±2σ coverage end % |");
    println!("|---|---|---|---|---|");
    let f = |v: Option<f64>, d: usize| v.map_or("—".to_string(), |v| format!("{v:.d$}"));
    for est in &stats {
        for p in est.parameters.iter().filter(|p| p.primary) {
            let b = before.get(&(est.name.clone(), p.name.clone()));
            let cb = b.filter(|b| b.1 > 0).map(|b| 100.0 * b.0 as f64 / b.1 as f64);
            println!(
                "| {} | {} | {} | {} | {} |",
                est.name,
                p.name,
                f(p.median_reconvergence_10pct_s, 2),
                f(cb, 1),
                f(p.coverage_2sigma.map(|c| 100.0 * c), 1),
            );
        }
    }
    println!();
    println!(
        "| estimator | equation | alarms before the damage | per hour (before) | runs with an alarm after | median delay of the first after, s | alarms after |"
    );
    println!("|---|---|---|---|---|---|---|");
    let pre_hours = ok as f64 * damage_s / 3600.0;
    for ((est, eq), per_run) in &alarms {
        let pre: usize = per_run.iter().map(|v| v.iter().filter(|&&t| t < damage_s).count()).sum();
        let post: usize =
            per_run.iter().map(|v| v.iter().filter(|&&t| t >= damage_s).count()).sum();
        let delays: Vec<f64> = per_run
            .iter()
            .filter_map(|v| v.iter().find(|&&t| t >= damage_s).map(|t| t - damage_s))
            .collect();
        println!(
            "| {est} | {eq} | {pre} | {:.2} | {} | {} | {post} |",
            pre as f64 / pre_hours,
            delays.len(),
            f(median(delays.clone()), 2),
        );
    }
    println!();
    print_alarm_times(&alarms, sc.duration_s);
    print_information(&sc, &steps);
    Ok(())
}
