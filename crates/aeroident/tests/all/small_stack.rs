//! A six-axis run fits in the 2 MiB stack of an ordinary spawned thread (`std::thread::spawn`'s
//! default, rayon's workers, the test harness's threads): a library user calling a pipeline
//! from such a thread needs no bigger stack. The estimators are fixed-capacity and built by
//! value before they are boxed (an `RlsIv` over the vocabulary is 0.4 MB), so a stack frame
//! that holds several of them at once overflows it.
//!
//! Every case runs on a thread built with an explicit 2 MiB stack, which `RUST_MIN_STACK`
//! does not enlarge. An overflow aborts this test binary ("has overflowed its stack", or
//! SIGSEGV): that is how these tests fail, which is why they have a binary of their own.

use aeroident::outdir::OutputDir;
use aeroident::sim::write_outputs;
use aeroident_io::{Mapping, ModelSpec, open_log};
use aeroident_pipelines::Named;
use aeroident_pipelines::aircraft::scenario::DEFAULT_SCENARIO;
use aeroident_pipelines::aircraft::{Scenario, run};
use aeroident_pipelines::estimators::EstimatorKind;
use aeroident_pipelines::montecarlo::campaign;
use aeroident_pipelines::replay::batch::{BatchMethod, FitOptions};
use aeroident_pipelines::replay::fit::fit_record;
use aeroident_pipelines::replay::{ReplayOptions, replay};
use std::path::{Path, PathBuf};

/// The default stack of a spawned thread, bytes.
const STACK_BYTES: usize = 2 << 20;

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `f`'s result, computed on a thread with a [`STACK_BYTES`] stack.
fn on_small_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let thread = std::thread::Builder::new().stack_size(STACK_BYTES).spawn(f).unwrap();
    thread.join().unwrap()
}

/// The built-in default scenario (`aeroident run`'s job: six-axis rls, ftr, ekf,
/// smpe-corrected and smpe-finite-time), flown for `duration_s`.
fn default_scenario(duration_s: f64) -> Scenario {
    let mut sc = Scenario::from_toml(DEFAULT_SCENARIO, "default").unwrap();
    sc.duration_s = duration_s;
    sc
}

#[test]
fn the_default_job_runs_on_a_2_mib_thread() {
    let out = on_small_stack(|| run(&default_scenario(10.0)).unwrap());
    let kinds: Vec<&str> = out.channels.iter().map(|c| c.kind).collect();
    assert_eq!(kinds, ["rls", "ftr", "ekf", "smpe-corrected", "smpe-finite-time"]);
    for c in &out.channels {
        assert!(c.failure.is_none(), "{}: {:?}", c.kind, c.failure);
        assert_eq!(c.params.len(), 30, "{}: the six-axis preset's parameters", c.kind);
        let identified =
            c.params.iter().filter(|p| p.estimate.last().copied().flatten().is_some()).count();
        assert!(identified >= 24, "{}: {identified} of 30 identified after 10 s", c.kind);
    }
}

#[test]
fn a_montecarlo_campaign_runs_on_2_mib_threads() {
    let campaign = on_small_stack(|| {
        let pool =
            rayon::ThreadPoolBuilder::new().num_threads(2).stack_size(STACK_BYTES).build().unwrap();
        pool.install(|| campaign(&default_scenario(5.0), 2, 1).unwrap())
    });
    assert_eq!(campaign.runs, 2);
    assert!(campaign.failed_runs.is_empty(), "{:?}", campaign.failed_runs);
    assert_eq!(campaign.estimators.len(), 5);
    for e in &campaign.estimators {
        assert_eq!(e.runs_ok, 2, "{}", e.name);
    }
}

/// The open-loop simulation of `scenarios/sim/default_excitation_measured.toml` (the default
/// scenario's inputs, measured channels) written as `timeseries.csv` under `dir`.
fn simulated_record(dir: &Path) -> String {
    let scenario = workspace().join("scenarios/sim/default_excitation_measured.toml");
    let sc = aeroident_pipelines::sim::load_scenario(&scenario).unwrap();
    let sim = aeroident_pipelines::sim::run(&sc, scenario.parent().unwrap()).unwrap();
    let mut od = OutputDir::open(dir, "f16 sim", &[]).unwrap();
    write_outputs(&sim, &mut od).unwrap();
    od.finish();
    dir.join("timeseries.csv").display().to_string()
}

#[test]
fn every_six_axis_replay_runs_on_a_2_mib_thread() {
    let dir = std::env::temp_dir().join(format!("aeroident-small-stack-{}", std::process::id()));
    let csv = simulated_record(&dir);
    let mapping = Mapping::from_path(&workspace().join("mappings/aeroident-sim.toml")).unwrap();
    let six_axis = || Some(ModelSpec::from_arg("six-axis").unwrap());
    let online = EstimatorKind::ALL.iter().copied().filter(|k| !k.is_batch());
    for kind in online {
        let (csv, mapping) = (csv.clone(), mapping.clone());
        let opts = ReplayOptions { estimator: kind, model: six_axis(), ..Default::default() };
        let out = on_small_stack(move || {
            let reader = open_log(&csv, None, &mapping).unwrap();
            replay(reader, &mapping, &opts, &mut ()).unwrap()
        });
        let (p, status) = (&out.summary.parameters, out.summary.status.as_str());
        assert_eq!(p.len(), 30, "{}", kind.name());
        // The gradient law runs away from this record's measured states at 2.5 s (the law's
        // property, not the stack's): its replay ends there, with its summary.
        if kind == EstimatorKind::Gradient {
            assert_eq!(status, "diverged");
            continue;
        }
        assert_eq!(out.summary.samples_read, 2001, "{}: status {status}", kind.name());
        let cm_alpha = p.iter().find(|p| p.name == "Cm_alpha").unwrap();
        assert!(cm_alpha.estimate.is_some(), "{}: Cm_alpha not identified", kind.name());
    }
    for method in [BatchMethod::Oe, BatchMethod::Fem] {
        let (csv, mapping) = (csv.clone(), mapping.clone());
        let options = FitOptions { method, max_iterations: Some(3), ..Default::default() };
        let out = on_small_stack(move || {
            let reader = open_log(&csv, None, &mapping).unwrap();
            fit_record(reader, &mapping, six_axis(), options).unwrap()
        });
        let p = &out.summary.parameters;
        assert!(p.len() >= 30, "{method:?}: {} parameters", p.len());
        assert!(p.iter().all(|p| p.estimate.is_some()), "{method:?}: a parameter not estimated");
    }
    std::fs::remove_dir_all(&dir).ok();
}
