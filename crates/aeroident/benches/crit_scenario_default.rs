//! Criterion benchmark: the whole main job (`scenarios/default.toml`, 40 s at 100 Hz: reference
//! F-16 with turbulence, air-data sensors with noise and the 21-point differentiator, RLS on the
//! six-axis preset), set-up included (trim, multisine design, turbulence generation, truth
//! derivatives); and 1 s of the combined run with every two-aircraft estimator
//! (`scenarios/f16/combined.toml`: published implicit and explicit, corrected; four aircraft).
//! Target: ≥ 500× real time, i.e. ≤ 80 ms for the 40 s main job and ≤ 2 ms per simulated
//! second of the combined run excluding the trim (benchmarked as `trim_only`).

#![allow(missing_docs)] // criterion_group! generates an undocumented pub fn.

use aeroident_pipelines::aircraft::{Scenario, run};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let default =
        Scenario::from_path(&root.join("scenarios/default.toml")).expect("default scenario");
    let mut combined =
        Scenario::from_path(&root.join("scenarios/f16/combined.toml")).expect("combined");
    combined.duration_s = 1.0;
    c.bench_function("main_job_default_40s_100hz", |b| {
        b.iter(|| run(black_box(&default)).expect("runs"))
    });
    // The trim alone, to subtract from the two runs above (the summary's realtime_factor
    // excludes it).
    let f16 = aeroident_models::f16::F16::new(0.30).expect("finite xcg");
    let cond = aeroident_models::trim::TrimCondition::level(20_000.0, 675.0);
    c.bench_function("trim_only", |b| {
        b.iter(|| aeroident_models::trim::trim(black_box(&f16), &cond).expect("trims"))
    });
    c.bench_function("closed_loop_combined_all_estimators_1s_100hz", |b| {
        b.iter(|| run(black_box(&combined)).expect("runs"))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
