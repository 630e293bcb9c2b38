//! `aeroident montecarlo [scenario.toml] --runs N [--out DIR] [--json] [--seed S]`: N seeded
//! noisy closed-loop flights of the `run` experiment in parallel and their statistics per
//! estimator and parameter ([`aeroident_pipelines::montecarlo`]; the seed rule is there).
//! With `--aircraft MODEL.toml --map M [--summary S] [--estimator LIST]` the flights are a
//! model-file aircraft's through a `kind = "sim"` scenario
//! ([`aeroident_pipelines::montecarlo::aircraft`]).
//!
//! - default: a table on stdout, `DIR/montecarlo.json` (statistics, failed runs, CRB notes),
//!   `DIR/runs.json` (every run's final results), `DIR/histograms_<estimator>.png` (final
//!   estimates of each primary derivative with the truth line), `DIR/coverage.png` and
//!   `DIR/report.html` ([`crate::report::montecarlo`]);
//!   `DIR` defaults to `./aeroident-out/montecarlo`.
//! - `--json`: only the summary document of [`aeroident_pipelines::montecarlo::json_summary`] on stdout (no
//!   files); failed runs are listed on stderr.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::outdir::OutputDir;

use super::run::DEFAULT_SCENARIO;
use crate::plot::{GroupedBars, HistogramPanel, render_histograms_png, render_histograms_svg};
use aeroident_pipelines::aircraft::Scenario;
use aeroident_pipelines::montecarlo::aircraft::ModelFileExperiment;
use aeroident_pipelines::montecarlo::{
    Campaign, EstimatorStats, ParamStats, campaign_watched, json_summary,
};

/// Arguments of `aeroident montecarlo`.
#[derive(Debug, clap::Args)]
pub struct MonteCarloArgs {
    /// Scenario file (TOML). Without it, the built-in default scenario (`aeroident run`'s).
    pub scenario: Option<PathBuf>,
    /// Number of runs (1 to 10 000: every run's results are kept for the statistics).
    #[arg(long, default_value_t = 100)]
    pub runs: u64,
    /// Output directory (default `./aeroident-out/montecarlo`).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print only the JSON summary on stdout (no files).
    #[arg(long)]
    pub json: bool,
    /// Campaign seed (every run's seeds derive from it and the run index).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Skip the PNG figures.
    #[arg(long)]
    pub no_figures: bool,
    /// The aircraft: `f16` (the scenario's `kind = "run"` experiment), or a model file flying
    /// a `kind = "sim"` scenario (docs/aircraft.md).
    #[command(flatten)]
    pub aircraft: super::aircraft_args::AircraftArgs,
    /// Model-file aircraft: the estimators run on every record, comma-separated (`rls,oe`;
    /// default `oe`). The F-16's come from its scenario's `[[estimator]]` entries.
    #[arg(long, value_delimiter = ',')]
    pub estimator: Option<Vec<String>>,
}

/// The campaign a `montecarlo` command runs: the F-16's `run` experiment or a model-file
/// aircraft's ([`aeroident_pipelines::montecarlo::aircraft`]).
enum Experiment {
    F16(Box<Scenario>),
    ModelFile(Box<ModelFileExperiment>),
}

impl Experiment {
    /// The experiment `args` name (the F-16's default scenario without one).
    fn of(args: &MonteCarloArgs) -> anyhow::Result<Self> {
        if args.aircraft.is_f16()? {
            anyhow::ensure!(
                args.estimator.is_none(),
                "--estimator is for a model-file aircraft: the F-16 scenario's [[estimator]] entries name its estimators"
            );
            return Ok(Self::F16(Box::new(match &args.scenario {
                Some(p) => Scenario::from_path(p)?,
                None => Scenario::from_toml(
                    DEFAULT_SCENARIO,
                    aeroident_pipelines::aircraft::scenario::DEFAULT_ORIGIN,
                )?,
            })));
        }
        let scenario = args.scenario.as_deref().ok_or_else(|| {
            anyhow::anyhow!(
                "a model-file aircraft flies a `kind = \"sim\"` scenario: give its file"
            )
        })?;
        let x =
            super::aircraft_args::experiment(&args.aircraft, scenario, args.estimator.as_deref())?;
        x.check_campaign(args.runs).map_err(anyhow::Error::msg)?;
        Ok(Self::ModelFile(Box::new(x)))
    }

    fn name(&self) -> String {
        match self {
            Self::F16(sc) => sc.name.clone(),
            Self::ModelFile(x) => {
                use aeroident_models::aircraft::Aircraft as _;
                x.aircraft.name()
            }
        }
    }

    fn campaign(
        &self,
        args: &MonteCarloArgs,
        stop: &std::sync::atomic::AtomicBool,
        on_run: &(dyn Fn() + Sync),
    ) -> Result<Campaign, String> {
        match self {
            Self::F16(sc) => campaign_watched(sc, args.runs, args.seed, Some(stop), on_run),
            Self::ModelFile(x) => x.campaign_watched(args.runs, args.seed, Some(stop), on_run),
        }
    }
}

/// The readable table of a campaign (`comfy-table`): per estimator and parameter the truth,
/// the mean estimate's bias and error %, the scatter against the mean σ and the Cramér–Rao
/// bounds (of the experiment flown, turbulence included, and calm: white sensor noise only;
/// `scat/CRB` against the first), the ±2σ coverage and the median time to ±10 %.
pub fn table(c: &Campaign) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Monte Carlo `{}`: {} runs, seed {}, {:.1} s wall on {} threads",
        c.scenario, c.runs, c.seed, c.wall_s, c.threads
    );
    if let Some(why) = &c.status_reason {
        let _ = writeln!(s, "{}: {why}", c.status.to_uppercase());
    }
    let _ = writeln!(s, "{}", statistics_table(c));
    for e in &c.estimators {
        s.push_str(&estimator_lines(e));
    }
    for n in &c.crb_notes {
        let _ = writeln!(s, "note: {n}");
    }
    let _ = writeln!(
        s,
        "* = primary derivative; error % = bias of the mean estimate / |truth|; t10 med = median time to stay within ±10 % (never: ≥ half the runs never do; batch: a post-flight fit, no estimate before the end)"
    );
    s
}

/// The statistics table: one row per estimator and parameter, numbers right-aligned.
fn statistics_table(c: &Campaign) -> comfy_table::Table {
    let mut t = comfy_table::Table::new();
    t.load_preset(comfy_table::presets::UTF8_FULL_CONDENSED).set_header(vec![
        "estimator",
        "param",
        "truth",
        "bias",
        "error %",
        "scatter",
        "mean σ",
        "σ_CRB",
        "σ_CRB calm",
        "cov2σ",
        "scat/CRB",
        "t10 med",
    ]);
    for i in 2..12 {
        if let Some(col) = t.column_mut(i) {
            col.set_cell_alignment(comfy_table::CellAlignment::Right);
        }
    }
    for e in &c.estimators {
        for p in &e.parameters {
            t.add_row(statistics_row(e, p));
        }
    }
    t
}

/// The cells of one parameter's row of [`statistics_table`].
fn statistics_row(e: &EstimatorStats, p: &ParamStats) -> Vec<String> {
    use crate::table::fmt_sig;
    vec![
        e.name.clone(),
        format!("{}{}", p.name, if p.primary { "*" } else { "" }),
        fmt_sig(p.truth_or_zero(), 4),
        fmt_sig(p.bias, 2),
        p.bias_percent_of_truth().map_or("—".into(), |x| format!("{x:+.1}")),
        fmt_sig(p.scatter, 2),
        fmt_sig(p.mean_std_error, 2),
        fmt_sig(p.crb_std_error, 2),
        fmt_sig(p.crb_std_error_calm, 2),
        p.coverage_2sigma.map_or("—".into(), |x| format!("{:.0} %", 100.0 * x)),
        p.scatter_over_crb().map_or("—".into(), |x| format!("{x:.1}")),
        if e.is_batch() {
            "batch".into()
        } else {
            p.median_time_to_10pct_s.map_or("never".into(), |t| format!("{t:.2} s"))
        },
    ]
}

/// One estimator's lines under the table: runs used, failed and restarted, mean NIS, the
/// post-flight fit's cost, then each failed run.
fn estimator_lines(e: &EstimatorStats) -> String {
    let mut s = String::new();
    let _ = write!(s, "{}: {} runs used, {} failed", e.name, e.runs_ok, e.failed_runs.len());
    if !e.restarted_runs.is_empty() {
        let runs: Vec<String> = e.restarted_runs.iter().map(u64::to_string).collect();
        let _ = write!(
            s,
            ", {} restarted from the priors (runs {}; used)",
            e.restarted_runs.len(),
            runs.join(", ")
        );
    }
    if let Some(nis) = e.mean_nis {
        let _ = write!(s, "; mean NIS {nis:.2}");
    }
    if let (Some(it), Some(w)) = (e.mean_iterations, e.mean_fit_wall_s) {
        let _ = write!(s, "; post-flight fit: mean {it:.1} iterations, {w:.2} s wall");
    }
    let _ = writeln!(s);
    for f in &e.failed_runs {
        let _ = writeln!(s, "  run {} failed: {}", f.run, f.reason);
    }
    s
}

/// Writes `montecarlo.json`, `runs.json` and (unless `figures` is false) the figures into `od`.
///
/// # Errors
/// Unwritable files or figures, named.
pub fn write_outputs(c: &Campaign, od: &mut OutputDir, figures: bool) -> anyhow::Result<()> {
    od.write_bytes("montecarlo.json", serde_json::to_string_pretty(c)?.as_bytes())?;
    od.write_bytes("runs.json", serde_json::to_string(&c.results)?.as_bytes())?;
    if !figures {
        return Ok(());
    }
    for e in &c.estimators {
        write_histograms(c, e, od)?;
    }
    write_coverage(c, od)
}

/// `histograms_<k>_<estimator>.{png,svg}`: the final estimates of each of the estimator's
/// primary derivatives with the truth line (`k`: the estimator's position); nothing without
/// a primary derivative.
fn write_histograms(c: &Campaign, e: &EstimatorStats, od: &mut OutputDir) -> anyhow::Result<()> {
    let panels: Vec<HistogramPanel> = e
        .parameters
        .iter()
        .filter(|p| p.primary)
        .map(|p| HistogramPanel {
            title: p.name.clone(),
            x_label: p.name.clone(),
            values: c.final_estimates(&e.name, &p.name),
            bins: 20,
            line: p.reference,
            line_label: "truth".into(),
        })
        .collect();
    if panels.is_empty() {
        return Ok(());
    }
    let k = c.estimators.iter().position(|x| x.name == e.name).unwrap_or(0);
    let safe: String =
        e.name.chars().map(|ch| if ch.is_ascii_alphanumeric() { ch } else { '_' }).collect();
    let stem = format!("histograms_{k}_{safe}");
    let title = format!("{}: final estimates over {} runs", e.name, e.runs_ok);
    od.write_path(&format!("{stem}.png"), |p| {
        render_histograms_png(p, &title, &panels, 4, (380, 260))
    })?;
    let svg = render_histograms_svg(&format!("{stem}.svg"), &title, &panels, 4, (380, 260))?;
    od.write_bytes(&format!("{stem}.svg"), svg.as_bytes())?;
    Ok(())
}

/// `coverage.{png,svg}`: the ±2σ coverage of each primary derivative per estimator against the
/// 0.95 target; nothing without a primary derivative or a coverage.
fn write_coverage(c: &Campaign, od: &mut OutputDir) -> anyhow::Result<()> {
    let categories = c.primary_parameters();
    let coverage = c.coverage_by_estimator(&categories);
    if categories.is_empty() || coverage.is_empty() {
        return Ok(());
    }
    let chart = GroupedBars {
        title: format!("±2σ coverage of the truth over {} runs", c.runs),
        y_label: "fraction of runs".into(),
        categories,
        series: coverage,
        y_range: (0.0, 1.05),
        reference: Some((0.95, "0.95 target".into())),
    };
    od.write_path("coverage.png", |p| chart.render_png(p, (1200, 500)))?;
    od.write_bytes("coverage.svg", chart.render_svg("coverage.svg", (1200, 500))?.as_bytes())?;
    Ok(())
}

/// Runs `aeroident montecarlo`.
///
/// SIGINT, SIGTERM or SIGHUP stops the campaign (crate::interrupt): no further run starts, the
/// runs under way finish, and the outputs are written over the runs done with `montecarlo.json`
/// status `interrupted`; a second signal before then leaves the figures and the report out.
/// The exit code is then 128 + signal. A campaign whose every run failed, or none gave an
/// estimate, writes its (empty) statistics with that status and exits 1.
///
/// # Errors
/// An unreadable or invalid scenario, `--runs` 0 or above
/// [`aeroident_pipelines::montecarlo::MAX_RUNS`], unwritable outputs, an interruption, a
/// campaign `failed` or with `no_estimates`.
pub fn execute(args: MonteCarloArgs) -> anyhow::Result<()> {
    aeroident_pipelines::montecarlo::check_runs(args.runs, "--runs").map_err(anyhow::Error::msg)?;
    let experiment = Experiment::of(&args)?;
    let name = experiment.name();
    let dir = args.out.clone().unwrap_or_else(|| PathBuf::from("aeroident-out").join("montecarlo"));
    let mut inputs: Vec<&Path> = args.scenario.iter().map(PathBuf::as_path).collect();
    if !args.aircraft.is_f16()? {
        inputs.extend(args.aircraft.files()?);
    }
    // Refused before the runs, not after them.
    let od = (!args.json).then(|| OutputDir::open(&dir, "montecarlo", &inputs)).transpose()?;
    let interrupt = crate::interrupt::Interrupt::install()?;
    let bar = crate::progress::count_bar(args.runs, &format!("Monte Carlo `{name}`: runs"));
    let flag = interrupt.flag();
    let c = experiment.campaign(&args, &flag, &|| bar.inc(1));
    bar.finish_and_clear();
    let c = c.map_err(anyhow::Error::msg)?;
    if let (Some(why), Some(signal)) = (&c.status_reason, interrupt.signal_name()) {
        aeroident_report::note!("{signal}: {why}");
    }
    // From here further signals are ignored until the outputs are written.
    let summary_only = interrupt.begin_writing();
    match od {
        None => print_json(&c)?,
        Some(mut od) => {
            write_outputs(&c, &mut od, !args.no_figures && !summary_only)?;
            if !summary_only {
                crate::report::montecarlo::write(&c, &mut od)?;
            }
            od.finish();
            super::print_stdout(&format!("{}wrote {}", table(&c), dir.display()))?;
        }
    }
    if let Some(e) =
        interrupt.error("the outputs over the runs done were written, status `interrupted`")
    {
        return Err(e.into());
    }
    // Empty statistics are written (they say why), but are not a result to go on from.
    match &c.status_reason {
        Some(why) if c.status != "complete" => {
            anyhow::bail!("campaign `{name}` {}: {why}", c.status)
        }
        _ => Ok(()),
    }
}

/// `--json`: the summary document on stdout, the failed and restarted runs on stderr.
fn print_json(c: &Campaign) -> anyhow::Result<()> {
    for e in &c.estimators {
        for f in &e.failed_runs {
            aeroident_report::note!("{}: run {} failed: {}", e.name, f.run, f.reason);
        }
        for r in &e.restarted_runs {
            aeroident_report::note!("{}: run {r} restarted from the priors (used)", e.name);
        }
    }
    super::print_stdout(&serde_json::to_string_pretty(&json_summary(c))?).map_err(Into::into)
}
