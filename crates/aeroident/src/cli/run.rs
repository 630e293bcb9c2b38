//! `aeroident run`: aircraft estimation scenarios.
//!
//! - `aeroident run` — the built-in default scenario (`scenarios/default.toml`, embedded):
//!   six-axis RLS on the F-16 at the thesis condition, orthogonal multisines on elevator,
//!   aileron and rudder, sensor noise, light turbulence, damage at 20 s; prints a table and
//!   writes `./aeroident-out/`.
//! - `aeroident run <scenario.toml> [--out DIR]` — one scenario: `timeseries.csv`,
//!   `summary.json`, `controls`, `convergence`, `tracking` (`.png` and `.svg`) and
//!   `report.html` ([`crate::report::run`]) in `DIR` (default `./aeroident-out/<name>`); the
//!   results table per estimator (estimate ± σ, truth, error %, status) on stdout.
//! - `aeroident run --all [<dir>] [--out DIR]` — every `*.toml` in `<dir>` (default: the
//!   shipped `scenarios/f16/`, found from any working directory) in parallel, one
//!   sub-directory each, plus `DIR/report.md` (thesis versus ours); prints a one-screen
//!   overview, one line per scenario.
//! - `aeroident run SCENARIO --aircraft MODEL.toml --map M [--estimator LIST]` — a model-file
//!   aircraft's flight ([`super::run_model_file`]).
//!
//! Scenario files have `kind = "run"` ([`aeroident_pipelines::scenario_kind`]).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use rayon::prelude::*;

use crate::aircraft::outputs as report;
use crate::outdir::{OutputDir, safe_component};
use aeroident_pipelines::aircraft::evidence::Variant;
use aeroident_pipelines::aircraft::summary::{self, Summary};
use aeroident_pipelines::aircraft::{RunOutput, Scenario, run};
use aeroident_pipelines::scenario_kind::{ScenarioKind, shipped_dir};

pub use aeroident_pipelines::aircraft::scenario::DEFAULT_SCENARIO;

/// Arguments of `aeroident run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Scenario file (TOML). Without it, the built-in default scenario runs.
    pub scenario: Option<PathBuf>,
    /// Run every `*.toml` in this directory (default: the shipped `scenarios/f16`) and write
    /// `report.md`.
    #[arg(long, value_name = "DIR", conflicts_with = "scenario", num_args = 0..=1)]
    pub all: Option<Option<PathBuf>>,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Skip the PNG figures (faster).
    #[arg(long)]
    pub no_figures: bool,
    /// The aircraft: `f16` (a `kind = "run"` scenario), or a model file flying a
    /// `kind = "sim"` scenario with its sensor noise, scored against the values flown
    /// (docs/aircraft.md).
    #[command(flatten)]
    pub aircraft: super::aircraft_args::AircraftArgs,
    /// Model-file aircraft: the estimators run on the record, comma-separated (`rls,oe`;
    /// default `oe`). The F-16's come from its scenario's `[[estimator]]` entries.
    #[arg(long, value_delimiter = ',')]
    pub estimator: Option<Vec<String>>,
}

/// Runs one scenario (read from `inputs`, never removed or overwritten) and writes its outputs
/// into `dir`.
///
/// # Errors
/// Experiment or output errors, with the scenario name.
pub fn run_one(
    sc: &Scenario,
    dir: &Path,
    inputs: &[&Path],
    figures: bool,
) -> anyhow::Result<Summary> {
    // Lock and clear the directory before the run, so a failing run leaves no old outputs.
    let mut od = OutputDir::open(dir, "run", inputs)?;
    let out = run(sc).with_context(|| format!("scenario `{}`", sc.name))?;
    let summary =
        write_all(&out, &mut od, figures).with_context(|| format!("outputs of `{}`", sc.name))?;
    od.finish();
    Ok(summary)
}

/// Checks that every scenario name is a safe directory name ([`safe_component`]) and that no two
/// files use the same name.
///
/// # Errors
/// An unsafe name (naming the file) or a duplicate (naming both files).
pub fn check_names<'a>(named: impl IntoIterator<Item = (&'a str, &'a Path)>) -> anyhow::Result<()> {
    let mut seen: std::collections::BTreeMap<&str, &Path> = std::collections::BTreeMap::new();
    for (name, file) in named {
        safe_component(name).with_context(|| format!("scenario {}", file.display()))?;
        if let Some(first) = seen.insert(name, file) {
            anyhow::bail!(
                "scenario name `{name}` is used by both {} and {}: their outputs would overwrite each other",
                first.display(),
                file.display()
            );
        }
    }
    Ok(())
}

/// Runs `aeroident run`.
///
/// # Errors
/// Unreadable or invalid scenarios (file, line, field), failed runs, unwritable outputs.
pub fn execute(args: RunArgs) -> anyhow::Result<()> {
    if !args.aircraft.is_f16()? {
        anyhow::ensure!(
            args.all.is_none(),
            "--all runs the F-16's scenarios: leave out --aircraft"
        );
        let scenario = args.scenario.as_deref().ok_or_else(|| {
            anyhow::anyhow!(
                "a model-file aircraft flies a `kind = \"sim\"` scenario: give its file"
            )
        })?;
        let estimators = args.estimator.as_deref();
        return super::run_model_file::execute(&args.aircraft, scenario, estimators, args.out);
    }
    anyhow::ensure!(
        args.estimator.is_none(),
        "--estimator is for a model-file aircraft: the F-16 scenario's [[estimator]] entries name its estimators"
    );
    if let Some(dir) = &args.all {
        let dir = dir.clone().unwrap_or_else(|| shipped_dir(ScenarioKind::Run));
        let out = args.out.clone().unwrap_or_else(|| PathBuf::from("aeroident-out"));
        let (_, overview) = run_all(&dir, &out, !args.no_figures)?;
        // A closed pipe (e.g. `| head`) is not an error of the run.
        let _ = writeln!(
            std::io::stdout().lock(),
            "{overview}full report: {} and {}",
            out.join("report.md").display(),
            out.join("report.html").display()
        );
        return Ok(());
    }
    let (sc, default_dir) = match &args.scenario {
        Some(p) => {
            let sc = Scenario::from_path(p)?;
            let d = PathBuf::from("aeroident-out").join(&sc.name);
            (sc, d)
        }
        None => (
            Scenario::from_toml(
                DEFAULT_SCENARIO,
                aeroident_pipelines::aircraft::scenario::DEFAULT_ORIGIN,
            )?,
            PathBuf::from("aeroident-out"),
        ),
    };
    let dir = args.out.unwrap_or(default_dir);
    let spin =
        crate::progress::spinner(&format!("run `{}` ({} s simulated)", sc.name, sc.duration_s));
    let inputs: Vec<&Path> = args.scenario.iter().map(PathBuf::as_path).collect();
    let summary = run_one(&sc, &dir, &inputs, !args.no_figures);
    spin.finish_and_clear();
    let summary = summary?;
    let _ = writeln!(std::io::stdout().lock(), "{}wrote {}", results_text(&summary), dir.display());
    Ok(())
}

/// The console text of one run: the header line and target lines of [`report::table`] around
/// one [`crate::table`] per estimator.
fn results_text(summary: &Summary) -> String {
    let mut s = format!(
        "scenario {}  (realtime factor {:.0}×, {})\n",
        summary.scenario, summary.realtime_factor, summary.solver
    );
    for r in crate::report::run::results(summary) {
        s.push_str(&crate::table::render(&r));
    }
    for b in &summary.batch_fits {
        s.push_str(&crate::aircraft::outputs::batch_fit_line(b));
        s.push('\n');
    }
    for t in &summary.targets {
        s.push_str(&crate::aircraft::outputs::targets_line(t));
        s.push('\n');
    }
    for w in summary.event_warnings() {
        s.push_str(&format!("warning: {w}\n"));
    }
    s
}

/// Runs every scenario in `scenarios_dir` (in parallel) into `out/<name>/` and writes
/// `out/report.md` and `out/report.html` (every scenario's tables, linking its own report); returns the report text and the one-screen [`overview`].
///
/// # Errors
/// An unreadable directory or scenario, or a failed run (named).
pub fn run_all(
    scenarios_dir: &Path,
    out: &Path,
    figures: bool,
) -> anyhow::Result<(String, String)> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(scenarios_dir)
        .with_context(|| format!("reading {}", scenarios_dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    anyhow::ensure!(!files.is_empty(), "no *.toml scenario in {}", scenarios_dir.display());
    let scenarios = files.iter().map(|f| Scenario::from_path(f)).collect::<Result<Vec<_>, _>>()?;
    check_names(scenarios.iter().zip(&files).map(|(s, f)| (s.name.as_str(), f.as_path())))?;
    let inputs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let mut top = OutputDir::open(out, "run", &inputs)?;
    for sc in &scenarios {
        top.register_dir(&sc.name)?;
    }
    let bar = crate::progress::count_bar(scenarios.len() as u64, "scenarios");
    let results: anyhow::Result<Vec<(Scenario, Summary)>> = scenarios
        .into_par_iter()
        .zip(&files)
        .map(|(sc, file)| {
            let s = run_one(&sc, &out.join(&sc.name), &[file.as_path()], figures)?;
            bar.inc(1);
            Ok((sc, s))
        })
        .collect();
    bar.finish_and_clear();
    let results = results?;
    let mut md = report::markdown(&results);
    md.push_str(&evidence(&results.iter().map(|(sc, _)| sc.clone()).collect::<Vec<_>>())?);
    top.write_bytes("report.md", md.as_bytes())?;
    let lines: Vec<(String, String)> = results
        .iter()
        .map(|r| {
            let line = overview(std::slice::from_ref(r));
            let cells = line.lines().nth(1).unwrap_or_default();
            let cells = cells.trim().strip_prefix(r.0.name.as_str()).unwrap_or(cells).trim();
            let cells = format!("realtime {cells}");
            (r.0.name.clone(), cells)
        })
        .collect();
    let summaries: Vec<&Summary> = results.iter().map(|(_, s)| s).collect();
    crate::report::run::write_index(scenarios_dir, &lines, &summaries, &mut top)?;
    top.finish();
    Ok((md, overview(&results)))
}

/// One line per scenario: per estimator, how many of its estimated quantities (increments
/// and derivatives with a truth) end within 5 % of the truth, and the realtime factor; then a
/// total per estimator. The per-entry numbers are in `report.md`.
pub fn overview(results: &[(Scenario, Summary)]) -> String {
    use std::fmt::Write as _;
    let mut s =
        format!("{:<24} {:>8}  final estimates within 5 % of the truth\n", "scenario", "realtime");
    // (estimator, within, scored) in order of first appearance
    let mut totals: Vec<(String, usize, usize)> = Vec::new();
    for (sc, sm) in results {
        let mut per: Vec<(String, usize, usize)> = Vec::new();
        for p in &sm.parameters {
            let Some(e) = p.rel_error else { continue };
            let ok = usize::from(e.abs() <= 0.05);
            for list in [&mut per, &mut totals] {
                match list.iter_mut().find(|x| x.0 == p.estimator) {
                    Some(x) => {
                        x.1 += ok;
                        x.2 += 1;
                    }
                    None => list.push((p.estimator.clone(), ok, 1)),
                }
            }
        }
        let cells: Vec<String> = per.iter().map(|(e, k, n)| format!("{e} {k}/{n}")).collect();
        let _ = writeln!(s, "{:<24} {:>7.0}×  {}", sc.name, sm.realtime_factor, cells.join(" · "));
    }
    let cells: Vec<String> = totals.iter().map(|(e, k, n)| format!("{e} {k}/{n}")).collect();
    let _ = writeln!(s, "{} scenarios; all: {}", results.len(), cells.join(" · "));
    s
}

/// Variants of thesis cases that decide the illegible λ of tables 4.7/4.8 and show the effect of
/// the lost η (published-implicit and -explicit estimators only; no files written,
/// [`aeroident_pipelines::aircraft::evidence`]): a `report.md` section, one table row per
/// variant, estimator and parameter. Empty when the base scenarios `t4_7_case4`,
/// `t4_8_case1`, `t4_10_case1` are not in the set.
///
/// # Errors
/// A failed run.
pub fn evidence(scenarios: &[Scenario]) -> anyhow::Result<String> {
    let variants = aeroident_pipelines::aircraft::evidence::variants(scenarios);
    if variants.is_empty() {
        return Ok(String::new());
    }
    let runs = aeroident_pipelines::aircraft::evidence::run_variants(variants)?;
    let mut s = String::from(
        "\n### Evidence: illegible λ and lost η (published estimators, one setting changed)\n\n\
         | base scenario | param | setting | estimator | final | rel. err | first in ±5 % | settled |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for (v, sm) in &runs {
        s.push_str(&evidence_rows(v, sm));
    }
    Ok(s)
}

/// The `report.md` rows of one variant: one per estimator and parameter of its summary.
fn evidence_rows(v: &Variant, sm: &Summary) -> String {
    use std::fmt::Write as _;
    let mut row = String::new();
    for p in &sm.parameters {
        let _ = writeln!(
            row,
            "| {} | {} | {} = {:e} | {} | {} | {} | {} | {} |",
            v.scenario.name,
            v.param,
            v.setting,
            v.value,
            p.estimator,
            p.estimate.map_or("null".into(), |x| format!("{x:.4e}")),
            p.rel_error.map_or("—".into(), |e| format!("{:.1} %", 100.0 * e)),
            p.first_within_s.map_or("never".into(), |t| format!("{t:.2} s")),
            p.convergence_time_s.map_or("never".into(), |t| format!("{t:.2} s")),
        );
    }
    row
}

/// Writes all outputs of one run into the locked output directory `od` (each file atomically)
/// and returns the summary.
///
/// # Errors
/// [`report::ReportError`] naming the file.
fn write_all(
    out: &RunOutput,
    od: &mut OutputDir,
    figures: bool,
) -> Result<Summary, report::ReportError> {
    let summary = summary::summarize(out)?;
    let mut f = od.create("timeseries.csv")?;
    let path = f.path().to_path_buf();
    report::write_timeseries_to(out, &mut f, &path)?;
    f.commit()?;
    let text = serde_json::to_string_pretty(&summary).map_err(|e| report::ReportError::Encode {
        path: od.path().join("summary.json").display().to_string(),
        reason: e.to_string(),
    })?;
    od.write_bytes("summary.json", (text + "\n").as_bytes())?;
    let figs = if figures { crate::aircraft::figures::write_figures(out, od)? } else { Vec::new() };
    crate::report::run::write(out, &summary, figs, od)?;
    Ok(summary)
}
