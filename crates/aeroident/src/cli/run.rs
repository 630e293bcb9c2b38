//! `aeroident run`: aircraft estimation scenarios (issue 4).
//!
//! - `aeroident run` — the built-in default scenario (`scenarios/default.toml`, embedded):
//!   combined estimation, 1 Hz 0.05° elevator sine, sensor noise on; prints a table and
//!   writes `./aeroident-out/`.
//! - `aeroident run <scenario.toml> [--out DIR]` — one scenario: `timeseries.csv`,
//!   `summary.json`, `controls.png`, `convergence.png`, `tracking.png` in `DIR`
//!   (default `./aeroident-out/<name>`).
//! - `aeroident run --all <dir> [--out DIR]` — every `*.toml` in `<dir>` in parallel, one
//!   sub-directory each, plus `DIR/report.md` (thesis versus ours).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use rayon::prelude::*;

use crate::aircraft::report::{self, Summary};
use crate::aircraft::{Scenario, run};

/// The default scenario, embedded so `aeroident run` works from any directory.
pub const DEFAULT_SCENARIO: &str = include_str!("../../../../scenarios/default.toml");

/// Arguments of `aeroident run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Scenario file (TOML). Without it, the built-in default scenario runs.
    pub scenario: Option<PathBuf>,
    /// Run every `*.toml` in this directory and write `report.md`.
    #[arg(long, value_name = "DIR", conflicts_with = "scenario")]
    pub all: Option<PathBuf>,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Skip the PNG figures (faster).
    #[arg(long)]
    pub no_figures: bool,
}

/// Runs one scenario and writes its outputs into `dir`.
///
/// # Errors
/// Experiment or output errors, with the scenario name.
pub fn run_one(sc: &Scenario, dir: &Path, figures: bool) -> anyhow::Result<Summary> {
    let out = run(sc).with_context(|| format!("scenario `{}`", sc.name))?;
    report::write_all(&out, dir, figures).with_context(|| format!("outputs of `{}`", sc.name))
}

/// Runs `aeroident run`.
///
/// # Errors
/// Unreadable or invalid scenarios (file, line, field), failed runs, unwritable outputs.
pub fn execute(args: RunArgs) -> anyhow::Result<()> {
    if let Some(dir) = &args.all {
        let out = args.out.clone().unwrap_or_else(|| PathBuf::from("aeroident-out"));
        let md = run_all(dir, &out, !args.no_figures)?;
        // A closed pipe (e.g. `| head`) is not an error of the run.
        let _ =
            writeln!(std::io::stdout().lock(), "{md}\nwrote {}", out.join("report.md").display());
        return Ok(());
    }
    let (sc, default_dir) = match &args.scenario {
        Some(p) => {
            let sc = Scenario::from_path(p)?;
            let d = PathBuf::from("aeroident-out").join(&sc.name);
            (sc, d)
        }
        None => (
            Scenario::from_toml(DEFAULT_SCENARIO, "<embedded scenarios/default.toml>")?,
            PathBuf::from("aeroident-out"),
        ),
    };
    let dir = args.out.unwrap_or(default_dir);
    let summary = run_one(&sc, &dir, !args.no_figures)?;
    let _ =
        writeln!(std::io::stdout().lock(), "{}wrote {}", report::table(&summary), dir.display());
    Ok(())
}

/// Runs every scenario in `scenarios_dir` (in parallel) into `out/<name>/` and writes
/// `out/report.md`; returns the report text.
///
/// # Errors
/// An unreadable directory or scenario, or a failed run (named).
pub fn run_all(scenarios_dir: &Path, out: &Path, figures: bool) -> anyhow::Result<String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(scenarios_dir)
        .with_context(|| format!("reading {}", scenarios_dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    anyhow::ensure!(!files.is_empty(), "no *.toml scenario in {}", scenarios_dir.display());
    let scenarios = files.iter().map(|f| Scenario::from_path(f)).collect::<Result<Vec<_>, _>>()?;
    let results: Vec<(Scenario, Summary)> = scenarios
        .into_par_iter()
        .map(|sc| {
            let s = run_one(&sc, &out.join(&sc.name), figures)?;
            Ok((sc, s))
        })
        .collect::<anyhow::Result<_>>()?;
    let md = report::markdown(&results);
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    std::fs::write(out.join("report.md"), &md)
        .with_context(|| format!("writing {}", out.join("report.md").display()))?;
    Ok(md)
}
