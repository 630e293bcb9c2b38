//! Monte Carlo campaigns (`crates/pipelines/src/montecarlo.rs`): the whole campaign on rayon
//! (`backend="local"`), or its two halves for a distributed backend (Ray, in the Python
//! package): the seeded runs of one chunk (`montecarlo_runs`), and the reduction of every run's
//! result to the statistics of `aeroident montecarlo --json` (`montecarlo_reduce`). A run
//! depends only on (scenario, seed, index) (the module's seed rule), so the chunks can run
//! anywhere and the statistics equal the local campaign's.

use aeroident_pipelines::aircraft::Scenario;
use aeroident_pipelines::aircraft::scenario::{DEFAULT_ORIGIN, DEFAULT_SCENARIO};
use aeroident_pipelines::montecarlo::{
    Campaign, RunResult, assemble, check_runs, json_summary, run_range, run_result_from_json,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::{json_to_py, py_to_json};
use crate::{Signals, err, to_py};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(scenario_text, m)?)?;
    m.add_function(wrap_pyfunction!(montecarlo_local, m)?)?;
    m.add_function(wrap_pyfunction!(montecarlo_runs, m)?)?;
    m.add_function(wrap_pyfunction!(montecarlo_reduce, m)?)?;
    Ok(())
}

/// `(toml text, origin)` of a scenario path, or of the built-in default scenario for `None`
/// (so a remote worker needs no file).
#[pyfunction]
#[pyo3(signature = (scenario=None))]
fn scenario_text(scenario: Option<&str>) -> PyResult<(String, String)> {
    match scenario {
        None => Ok((DEFAULT_SCENARIO.to_owned(), DEFAULT_ORIGIN.to_owned())),
        Some(p) => {
            // Parsed here too, so a bad file fails before any task is sent, with the CLI's message.
            Scenario::from_path(std::path::Path::new(p)).map_err(to_py)?;
            let text = std::fs::read_to_string(p)
                .map_err(|e| err(format!("reading scenario {p}: {e}")))?;
            Ok((text, p.to_owned()))
        }
    }
}

fn parse(text: &str, origin: &str) -> PyResult<Scenario> {
    Scenario::from_toml(text, origin).map_err(to_py)
}

fn runs_to_py<'py>(py: Python<'py>, runs: &[RunResult]) -> PyResult<Bound<'py, PyList>> {
    let l = PyList::empty(py);
    for r in runs {
        let v = serde_json::to_value(r).map_err(|e| err(format!("internal: {e}")))?;
        l.append(json_to_py(py, &v)?)?;
    }
    Ok(l)
}

/// The whole campaign on this machine's rayon pool (see `aeroident.montecarlo`), run in
/// chunks so that Ctrl-C is seen between them (`KeyboardInterrupt`, nothing returned).
#[pyfunction]
#[pyo3(signature = (scenario_toml, origin, runs, seed=1, per_run=false))]
fn montecarlo_local<'py>(
    py: Python<'py>,
    scenario_toml: &str,
    origin: &str,
    runs: u64,
    seed: u64,
    per_run: bool,
) -> PyResult<Bound<'py, PyDict>> {
    check_runs(runs, "runs").map_err(err)?;
    let sc = parse(scenario_toml, origin)?;
    let signals = Signals::new();
    let c = py.detach(|| -> Result<Option<Campaign>, String> {
        let start = std::time::Instant::now();
        let Some(results) = runs_in_chunks(&sc, seed, 0, runs, &signals, None)? else {
            return Ok(None);
        };
        let wall_s = start.elapsed().as_secs_f64();
        Ok(Some(assemble(&sc, seed, results, wall_s, rayon::current_num_threads())))
    });
    signals.finish(py)?;
    let c = c.map_err(err)?.ok_or_else(|| err("montecarlo: interrupted"))?;
    summary_dict(py, &c, per_run)
}

/// Runs `start..stop` ([`run_range`]) a few runs per thread at a time, asking `signals` between
/// chunks; `None` when interrupted. The results are those of one [`run_range`] call (each run
/// depends only on its index), in run order.
///
/// # Errors
/// More than [`aeroident_pipelines::montecarlo::MAX_RUNS`] runs, before any.
fn runs_in_chunks(
    sc: &aeroident_pipelines::aircraft::Scenario,
    seed: u64,
    start: u64,
    stop: u64,
    signals: &Signals,
    pool: Option<&rayon::ThreadPool>,
) -> Result<Option<Vec<RunResult>>, String> {
    let n = stop.saturating_sub(start);
    if n > 0 {
        check_runs(n, "runs")?;
    }
    let threads =
        pool.map_or_else(rayon::current_num_threads, rayon::ThreadPool::current_num_threads);
    let chunk = 4 * threads.max(1) as u64;
    let mut results = Vec::new();
    let mut a = start;
    while a < stop {
        // Asked on the calling thread: Python runs signal handlers on the main thread only.
        if signals.interrupted() {
            return Ok(None);
        }
        let b = a.saturating_add(chunk).min(stop);
        let go = || run_range(sc, seed, a..b);
        results.extend(match pool {
            Some(p) => p.install(go),
            None => go(),
        }?);
        a = b;
    }
    Ok(Some(results))
}

fn summary_dict<'py>(py: Python<'py>, c: &Campaign, per_run: bool) -> PyResult<Bound<'py, PyDict>> {
    let d = json_to_py(py, &json_summary(c))?.cast_into::<PyDict>()?;
    if per_run {
        d.set_item("per_run", runs_to_py(py, &c.results)?)?;
        d.set_item("wall_s", c.wall_s)?;
    }
    Ok(d)
}

/// Runs `start..stop` of the campaign (seed rule of `aeroident_pipelines::montecarlo`) on this process's
/// rayon pool (or on `threads` threads of its own when given: a Ray task uses the CPUs it
/// reserved, not the whole node); per-run results as dicts (the `runs.json` entries of the
/// CLI). At most [`aeroident_pipelines::montecarlo::MAX_RUNS`] runs.
#[pyfunction]
#[pyo3(signature = (scenario_toml, origin, seed, start, stop, threads=None))]
fn montecarlo_runs<'py>(
    py: Python<'py>,
    scenario_toml: &str,
    origin: &str,
    seed: u64,
    start: u64,
    stop: u64,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyList>> {
    let n = stop.saturating_sub(start);
    if n > 0 {
        check_runs(n, "stop - start").map_err(err)?;
    }
    let sc = parse(scenario_toml, origin)?;
    let pool = match threads {
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n.max(1))
                .stack_size(aeroident_pipelines::WORKER_STACK_BYTES)
                .build()
                .map_err(|e| err(format!("montecarlo: thread pool: {e}")))?,
        ),
        None => None,
    };
    let signals = Signals::new();
    let results = py.detach(|| runs_in_chunks(&sc, seed, start, stop, &signals, pool.as_ref()));
    signals.finish(py)?;
    let results = results.map_err(err)?.ok_or_else(|| err("montecarlo: interrupted"))?;
    runs_to_py(py, &results)
}

/// The statistics of `aeroident montecarlo --json` from every run's result (any order, each
/// index `0..runs` exactly once).
#[pyfunction]
#[pyo3(signature = (scenario_toml, origin, runs, seed, per_run, wall_s=0.0, threads=0, keep_per_run=false))]
#[allow(clippy::too_many_arguments)]
fn montecarlo_reduce<'py>(
    py: Python<'py>,
    scenario_toml: &str,
    origin: &str,
    runs: u64,
    seed: u64,
    per_run: &Bound<'py, PyList>,
    wall_s: f64,
    threads: usize,
    keep_per_run: bool,
) -> PyResult<Bound<'py, PyDict>> {
    check_runs(runs, "runs").map_err(err)?;
    let sc = parse(scenario_toml, origin)?;
    let mut results: Vec<RunResult> = per_run
        .iter()
        .map(|o| run_result_from_json(&py_to_json(&o)?).map_err(err))
        .collect::<PyResult<_>>()?;
    results.sort_by_key(|r| r.index);
    if !results.iter().map(|r| r.index).eq(0..runs) {
        return Err(err(format!(
            "montecarlo reduce: expected one result for each run 0..{runs}, got {} results",
            results.len()
        )));
    }
    let c = py.detach(move || assemble(&sc, seed, results, wall_s, threads));
    summary_dict(py, &c, keep_per_run)
}
