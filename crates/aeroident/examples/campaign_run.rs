//! Re-runs single runs of a Monte Carlo campaign, to look at one failure without the whole
//! campaign: run `i` of campaign seed `S` is the scenario with the seeds of the seed rule
//! ([`aeroident_pipelines::montecarlo::seeded_scenario`], docs/uncertainty.md "Seed rule"), so its
//! result is the campaign's. Prints each estimator's status, failure and fit line.
//!
//! Run: `cargo run --release -p aeroident --example campaign_run -- SCENARIO.toml SEED RUN...`
//! (e.g. `scenarios/montecarlo/with-oe.toml 1 66 77`).
#![allow(missing_docs)]

use aeroident_pipelines::aircraft::{Scenario, run};
use aeroident_pipelines::montecarlo::seeded_scenario;
use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [path, seed, runs @ ..] = args.as_slice() else {
        eprintln!("usage: campaign_run SCENARIO.toml SEED RUN...");
        return ExitCode::FAILURE;
    };
    let sc = match Scenario::from_path(Path::new(path)) {
        Ok(sc) => sc,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    let Ok(seed) = seed.parse::<u64>() else {
        eprintln!("SEED must be an unsigned integer, got {seed}");
        return ExitCode::FAILURE;
    };
    for r in runs {
        let Ok(i) = r.parse::<u64>() else {
            eprintln!("RUN must be an unsigned integer, got {r}");
            return ExitCode::FAILURE;
        };
        match run(&seeded_scenario(&sc, seed, i)) {
            Ok(out) => {
                for c in &out.channels {
                    let failure = c
                        .failure
                        .as_ref()
                        .map_or(String::new(), |(t, m)| format!(" failure at {t:.2} s: {m}"));
                    println!(
                        "run {i} {}: {}{failure} {}",
                        c.label,
                        c.status.unwrap_or("-"),
                        c.stats
                    );
                }
            }
            Err(e) => println!("run {i}: experiment failed: {e}"),
        }
    }
    ExitCode::SUCCESS
}
