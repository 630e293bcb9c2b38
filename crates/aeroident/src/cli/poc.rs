//! `aeroident poc`: the thesis's proof-of-concept cases.
//!
//! - `aeroident poc <scenario.toml> --out <dir> [--estimator published|corrected]
//!   [--solver implicit|explicit]` writes `timeseries.csv`, `summary.json`, `estimates.png`,
//!   `states.png` into `<dir>`.
//! - `aeroident poc --all [<scenarios dir>] --out <dir>` runs every scenario of the directory
//!   (default: the shipped `scenarios/poc/`, found from any working directory) with the
//!   published estimator (both readings) and the corrected one, in parallel, writes each run
//!   under `<dir>/<case>/<estimator>[-<solver>]/` and `<dir>/report.md`, and prints a
//!   one-screen overview per thesis table.
//!
//! Scenario files have `kind = "poc"` ([`aeroident_pipelines::scenario_kind`]).

use crate::poc::output;
use crate::poc::report::{CaseResult, overview, render};
use aeroident_pipelines::poc::{EstimatorKind, PocScenario, SolverReading, run};
use aeroident_pipelines::scenario_kind::{ScenarioKind, shipped_dir};
use anyhow::{Context, bail};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `aeroident poc`.
#[derive(Debug, clap::Args)]
pub struct PocArgs {
    /// Scenario file (TOML, see `scenarios/poc/`). Not with `--all`.
    #[arg(required_unless_present = "all", conflicts_with = "all")]
    pub scenario: Option<PathBuf>,
    /// Run every `*.toml` in this directory (default: the shipped `scenarios/poc`) and write
    /// `report.md`.
    #[arg(long, value_name = "DIR", num_args = 0..=1)]
    pub all: Option<Option<PathBuf>>,
    /// Output directory (created if needed).
    #[arg(long)]
    pub out: PathBuf,
    /// Estimator: the thesis's (`published`) or the corrected one.
    #[arg(long, value_parser = super::named::<EstimatorKind>(), default_value = "published")]
    pub estimator: EstimatorKind,
    /// Reading of the published estimator's implicit equation (ignored by `corrected`).
    #[arg(long, value_parser = super::named::<SolverReading>(), default_value = "implicit")]
    pub solver: SolverReading,
}

/// Runs `aeroident poc`.
///
/// # Errors
/// Bad scenario files (file, line/key, reason), estimator or model failures, output errors.
pub fn execute(args: PocArgs) -> anyhow::Result<()> {
    if let Some(dir) = args.all {
        let dir = dir.unwrap_or_else(|| shipped_dir(ScenarioKind::Poc));
        let files = scenario_files(&dir)?;
        let inputs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
        let mut top = crate::outdir::OutputDir::open(&args.out, "poc", &inputs)?;
        let (results, wall_s) = run_all(&dir, &mut top)?;
        let report = render(&results, wall_s);
        let path = top.write_bytes("report.md", report.as_bytes())?;
        top.finish();
        super::print_stdout(&format!(
            "{}full report: {}",
            overview(&results, wall_s),
            path.display()
        ))?;
        return Ok(());
    }
    let Some(path) = args.scenario else { bail!("give a scenario file or --all") };
    let sc = PocScenario::from_path(&path)?;
    let mut od = crate::outdir::OutputDir::open(&args.out, "poc", &[path.as_path()])?;
    let out = run(&sc, args.estimator, args.solver)?;
    let summary = output::write_run(&mut od, &sc, &out)?;
    od.finish();
    super::print_stdout(&serde_json::to_string_pretty(&summary)?)?;
    if let Some(s) = &out.stopped_early {
        super::print_stdout(&format!("note: {s}"))?;
    }
    Ok(())
}

/// Lists the `*.toml` files of `dir`, sorted.
///
/// # Errors
/// When the directory cannot be read or holds no scenario.
pub fn scenario_files(dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading scenario directory {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    if files.is_empty() {
        bail!("no *.toml scenario in {}", dir.display());
    }
    Ok(files)
}

/// Runs every scenario of `scenarios_dir` three ways (published implicit, published
/// explicit, corrected) in parallel, writing each run's files into a subdirectory of `top`
/// (registered there, so the next run or this one's failure clears it). Returns the results
/// and the wall time, s.
///
/// # Errors
/// The first failing scenario's error, naming it.
pub fn run_all(
    scenarios_dir: &Path,
    top: &mut crate::outdir::OutputDir,
) -> anyhow::Result<(Vec<CaseResult>, f64)> {
    let start = Instant::now();
    let files = scenario_files(scenarios_dir)?;
    let scenarios: Vec<PocScenario> =
        files.iter().map(|f| PocScenario::from_path(f)).collect::<Result<_, _>>()?;
    super::run::check_names(
        scenarios.iter().zip(&files).map(|(s, f)| (s.case.name.as_str(), f.as_path())),
    )?;
    let jobs: Vec<(usize, EstimatorKind, SolverReading)> = (0..scenarios.len())
        .flat_map(|i| {
            [
                (i, EstimatorKind::Published, SolverReading::Implicit),
                (i, EstimatorKind::Published, SolverReading::Explicit),
                (i, EstimatorKind::Corrected, SolverReading::Implicit),
            ]
        })
        .collect();
    let sub = |est, solver: SolverReading| match est {
        EstimatorKind::Published => format!("published-{solver:?}").to_lowercase(),
        EstimatorKind::Corrected => "corrected".to_string(),
    };
    for &(i, est, solver) in &jobs {
        top.register_dir(&format!("{}/{}", scenarios[i].case.name, sub(est, solver)))?;
    }
    let out = top.path().to_path_buf();
    let runs: Vec<_> = jobs
        .par_iter()
        .map(|&(i, est, solver)| -> anyhow::Result<_> {
            let sc = &scenarios[i];
            let dir = out.join(&sc.case.name).join(sub(est, solver));
            let mut od = crate::outdir::OutputDir::open(&dir, "poc", &[files[i].as_path()])?;
            let r = run(sc, est, solver)?;
            let summary = output::write_run(&mut od, sc, &r)?;
            od.finish();
            Ok((summary, r))
        })
        .collect::<anyhow::Result<_>>()?;
    let mut it = runs.into_iter();
    let mut results = Vec::new();
    for sc in scenarios {
        let (Some(implicit), Some(explicit), Some(corrected)) = (it.next(), it.next(), it.next())
        else {
            bail!("internal: run count mismatch");
        };
        results.push(CaseResult { scenario: sc, implicit, explicit, corrected });
    }
    Ok((results, start.elapsed().as_secs_f64()))
}
