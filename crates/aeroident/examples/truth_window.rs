//! The batch fits of single campaign runs against three candidate truths, to tell a bias of
//! the estimate from a bias of the truth's definition (docs/uncertainty.md, "Bias: the
//! staircase inputs"): the truth the campaign scores with (the local derivatives at trim,
//! [`aeroident_pipelines::aircraft::truth::local_derivatives`], with the last epoch's increments), the
//! local derivatives at the fit window's **mean flown state and controls**, and the **mean of
//! the local derivatives over the window's flown samples**. Also prints the window's mean
//! state against the trim. Run `i` of seed `S` is the campaign's run (as `campaign_run`).
//!
//! Run: `cargo run --release -p aeroident --example truth_window -- SCENARIO.toml SEED RUN...`
#![allow(missing_docs)]

use aeroident_models::f16::{self, F16};
use aeroident_pipelines::aircraft::truth::{LocalDerivatives, local_derivatives};
use aeroident_pipelines::aircraft::{Scenario, run};
use aeroident_pipelines::montecarlo::seeded_scenario;
use nalgebra::SVector;
use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    match real_main() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}

fn real_main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [path, seed, runs @ ..] = args.as_slice() else {
        return Err("usage: truth_window SCENARIO.toml SEED RUN...".into());
    };
    let sc = Scenario::from_path(Path::new(path)).map_err(|e| e.to_string())?;
    let seed: u64 =
        seed.parse().map_err(|_| format!("SEED must be an unsigned integer, got {seed}"))?;
    let f = F16::new(sc.trim.xcg).map_err(|e| e.to_string())?;
    for r in runs {
        let i: u64 = r.parse().map_err(|_| format!("RUN must be an unsigned integer, got {r}"))?;
        let out = run(&seeded_scenario(&sc, seed, i)).map_err(|e| format!("run {i}: {e}"))?;
        let ep = out.epochs.last().ok_or("no truth epoch")?;
        let from = ep.from_s + out.sample_lag_s.unwrap_or(0.0);
        let idx: Vec<usize> = (0..out.t_s.len()).filter(|&k| out.t_s[k] >= from).collect();
        let n = idx.len() as f64;
        let mut xm = SVector::<f64, { f16::N_STATES }>::zeros();
        let mut um = SVector::<f64, 4>::zeros();
        for &k in &idx {
            xm += out.reference[k] / n;
            um += SVector::<f64, 4>::from(out.controls[k]) / n;
        }
        let (xt, ut) = (out.trim.state, out.trim.controls.to_vector());
        let deg = |v: f64| v.to_degrees();
        println!(
            "run {i}: trim alpha {:.3} deg, beta {:.3}, de {:.3}, V {:.1} ft/s; window mean alpha {:.3}, beta {:.3}, de {:.3}, da {:.3}, dr {:.3}, V {:.1}",
            deg(xt[f16::ALPHA]),
            deg(xt[f16::BETA]),
            deg(ut[1]),
            xt[f16::VT],
            deg(xm[f16::ALPHA]),
            deg(xm[f16::BETA]),
            deg(um[1]),
            deg(um[2]),
            deg(um[3]),
            xm[f16::VT]
        );
        let at_mean =
            local_derivatives(&f, &xm, &out.trim.controls.with_vector(&um), &ep.increments)
                .map_err(|e| e.to_string())?;
        let flown: Vec<LocalDerivatives> = idx
            .iter()
            .map(|&k| {
                let u = out.trim.controls.with_vector(&SVector::<f64, 4>::from(out.controls[k]));
                local_derivatives(&f, &out.reference[k], &u, &ep.increments)
            })
            .collect::<Result<_, _>>()
            .map_err(|e| e.to_string())?;
        for c in out.channels.iter().filter(|c| c.is_batch()) {
            println!("  {} {}", c.label, c.stats);
            for l in &c.params {
                let (Some(e), Some(t)) = (
                    l.estimate.last().copied().flatten(),
                    l.truth_epochs.last().copied().flatten(),
                ) else {
                    continue;
                };
                let (Some(dm), Some(sum)) = (
                    at_mean.derivative(l.param),
                    flown.iter().map(|d| d.derivative(l.param)).sum::<Option<f64>>(),
                ) else {
                    continue;
                };
                let avg = sum / n;
                let pct = |v: f64, of: f64| 100.0 * (v - of) / of.abs();
                println!(
                    "    {:10} est {:+.5} truth {:+.5} ({:+.2} %)  at-mean {:+.5} ({:+.2} % of truth)  flown-mean {:+.5} ({:+.2} % of truth)",
                    l.param.name(),
                    e,
                    t,
                    pct(e, t),
                    dm,
                    pct(dm, t),
                    avg,
                    pct(avg, t)
                );
            }
        }
    }
    Ok(())
}
