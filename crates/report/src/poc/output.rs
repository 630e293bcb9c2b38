//! Outputs of one run: `timeseries.csv`, `summary.json`, `estimates.{png,svg}`,
//! `states.{png,svg}` and `report.html` (the final estimates against the truth, the settings,
//! the figures).

use crate::plot::{HLine, LineKind, Panel, Series};
use crate::report::{Figure, Report, common_settings, write_figure};
use aeroident_pipelines::metrics::{CONVERGENCE_TOL_REL, convergence_time_s, rel_error};
use aeroident_pipelines::poc::run::{EstimatorKind, RunOutput, SolverReading};
use aeroident_pipelines::poc::scenario::PocScenario;
use aeroident_pipelines::results::{ParameterResult, Results};
use anyhow::Context;
use serde::Serialize;
use std::path::Path;

/// Per-parameter entry of `summary.json`: the common keys ([`ParameterResult`]: `name`,
/// `estimate` (at the last sample), `reference` (the truth) and `reference_check` (a final
/// value outside the convergence tolerance, ±5 %, is among its findings, saying how far),
/// `status` (`flagged`: the thesis's estimators report no σ, so nothing measured how well the
/// record determines them), `flags`, `notes`) and the thesis's metrics.
#[derive(Debug, Clone, Serialize)]
pub struct ParamSummary {
    /// The common keys.
    #[serde(flatten)]
    pub result: ParameterResult,
    /// `(estimate − truth)/|truth|`.
    pub rel_error: f64,
    /// First time after which the estimate stays within ±5 % of truth, s; `null` if never.
    pub convergence_time_s: Option<f64>,
    /// The thesis's reported convergence time, s; `null` where it gives none.
    pub thesis_convergence_time_s: Option<f64>,
}

impl std::ops::Deref for ParamSummary {
    type Target = ParameterResult;

    fn deref(&self) -> &ParameterResult {
        &self.result
    }
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// The key set's version, [`aeroident_io::SCHEMA_VERSION`].
    pub schema_version: u32,
    /// Scenario name.
    pub scenario: String,
    /// `published` or `corrected`.
    pub estimator: EstimatorKind,
    /// `implicit`, `explicit`, or `null` for the corrected estimator (no implicit equation).
    pub solver: Option<SolverReading>,
    /// Simulated seconds per wall second of the simulation loop.
    pub realtime_factor: f64,
    /// One entry per parameter.
    pub parameters: Vec<ParamSummary>,
}

/// Builds the summary of a run.
///
/// # Errors
/// When the metric inputs are inconsistent (a bug), with context.
pub fn summarize(sc: &PocScenario, out: &RunOutput) -> anyhow::Result<Summary> {
    let mut parameters = Vec::new();
    for (j, name) in out.param_names.iter().enumerate() {
        let est = &out.estimates[j];
        let truth = out.truth[j];
        let final_value = *est.last().context("empty run")?;
        // Over the simulated record; a run that stopped early says so in its notes.
        let tc = convergence_time_s(&out.t_s, est, truth, CONVERGENCE_TOL_REL)?;
        let rel = rel_error(final_value, truth);
        let mut result = ParameterResult::new(*name, Some(final_value), None, Some(truth), None);
        // A NaN error (no truth to compare with) is not within the tolerance either.
        let within = rel.abs() <= CONVERGENCE_TOL_REL;
        if !within {
            result.reference_finding(format!(
                "the final value is {:+.1} % from the truth (not within {:.0} %)",
                100.0 * rel,
                100.0 * CONVERGENCE_TOL_REL
            ));
        }
        parameters.push(ParamSummary {
            result,
            rel_error: rel,
            convergence_time_s: tc,
            thesis_convergence_time_s: sc.parameters[j].thesis_convergence_time_s,
        });
    }
    Ok(Summary {
        schema_version: aeroident_io::SCHEMA_VERSION,
        scenario: out.scenario.clone(),
        estimator: out.estimator,
        solver: out.solver,
        realtime_factor: out.simulated_s / out.wall_s.max(1e-9),
        parameters,
    })
}

/// Writes `timeseries.csv`: `t_s`, then `<state>_true`, `<state>_est` per state, then
/// `<param>_true`, `<param>_est` per parameter.
///
/// # Errors
/// File creation or write failures, naming the file.
pub fn write_timeseries_csv(path: &Path, out: &RunOutput) -> anyhow::Result<()> {
    let mut w =
        csv::Writer::from_path(path).with_context(|| format!("creating {}", path.display()))?;
    let mut header = vec!["t_s".to_string()];
    for s in &out.state_names {
        header.push(format!("{s}_true"));
        header.push(format!("{s}_est"));
    }
    for p in &out.param_names {
        header.push(format!("{p}_true"));
        header.push(format!("{p}_est"));
    }
    w.write_record(&header).with_context(|| format!("writing {}", path.display()))?;
    let mut row = Vec::with_capacity(header.len());
    for k in 0..out.t_s.len() {
        row.clear();
        row.push(format!("{}", out.t_s[k]));
        for i in 0..out.state_names.len() {
            row.push(format!("{:e}", out.states_true[i][k]));
            row.push(format!("{:e}", out.states_est[i][k]));
        }
        for j in 0..out.param_names.len() {
            row.push(format!("{}", out.truth[j]));
            row.push(format!("{:e}", out.estimates[j][k]));
        }
        w.write_record(&row).with_context(|| format!("writing {}", path.display()))?;
    }
    w.flush().with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

fn label(out: &RunOutput) -> String {
    match out.solver {
        Some(s) => format!("{} ({:?}, {:?})", out.scenario, out.estimator, s).to_lowercase(),
        None => format!("{} ({:?})", out.scenario, out.estimator).to_lowercase(),
    }
}

/// Writes the thesis-style figures `estimates.{png,svg}` (one panel per parameter: the
/// estimate, the truth dashed) and `states.{png,svg}` (one panel per state: reference dashed,
/// estimated model solid); returns them for the report.
///
/// # Errors
/// Rendering or file errors, naming the file.
pub fn write_figures(
    od: &mut crate::outdir::OutputDir,
    out: &RunOutput,
) -> anyhow::Result<Vec<Figure>> {
    let t = &out.t_s;
    let est_panels: Vec<Panel> = out
        .param_names
        .iter()
        .enumerate()
        .map(|(j, p)| Panel {
            title: format!("parameter {p}"),
            y_label: (*p).to_string(),
            series: vec![Series {
                label: "estimate".into(),
                t_s: t.clone(),
                values: out.estimates[j].clone(),
                kind: LineKind::Solid,
            }],
            hlines: vec![HLine { label: "truth".into(), value: out.truth[j] }],
            ..Default::default()
        })
        .collect();
    let title = label(out);
    let estimates = write_figure::<anyhow::Error>(
        od,
        "estimates",
        &title,
        "Each parameter's estimate over the run; dashed: the truth.",
        &est_panels,
        (900, 260),
    )?;
    let state_panels: Vec<Panel> = out
        .state_names
        .iter()
        .enumerate()
        .map(|(i, s)| Panel {
            title: format!("state {s}"),
            y_label: (*s).to_string(),
            series: vec![
                Series {
                    label: format!("{s} reference"),
                    t_s: t.clone(),
                    values: out.states_true[i].clone(),
                    kind: LineKind::Dashed,
                },
                Series {
                    label: format!("{s} estimated model"),
                    t_s: t.clone(),
                    values: out.states_est[i].clone(),
                    kind: LineKind::Solid,
                },
            ],
            // States are signals: the whole run sets the range.
            signals: true,
            ..Default::default()
        })
        .collect();
    let states = write_figure::<anyhow::Error>(
        od,
        "states",
        &title,
        "Each state of the reference system and of the estimated model.",
        &state_panels,
        (900, 260),
    )?;
    Ok(vec![estimates, states])
}

/// The results of a run: the final estimate of each parameter against its truth, the status
/// beside it (module doc of [`ParamSummary`]).
pub fn results(summary: &Summary, title: &str) -> Results {
    let rows = summary.parameters.iter().map(|p| p.result.clone()).collect();
    let notes = summary
        .parameters
        .iter()
        .map(|p| {
            format!(
                "{}: within ±{:.0} % from {} (thesis: {})",
                p.name,
                100.0 * CONVERGENCE_TOL_REL,
                p.convergence_time_s.map_or("never".into(), |t| format!("{t:.2} s")),
                p.thesis_convergence_time_s.map_or("—".into(), |t| format!("{t:.2} s"))
            )
        })
        .collect();
    Results {
        title: title.to_string(),
        reference_label: "truth".into(),
        rows,
        fit: Vec::new(),
        notes,
    }
}

/// Writes the output files of one run into the locked output directory `od` (each file
/// written atomically; open it before the run so a failing run leaves no old outputs) and returns the summary.
///
/// # Errors
/// Directory, file or rendering errors, naming the path.
pub fn write_run(
    od: &mut crate::outdir::OutputDir,
    sc: &PocScenario,
    out: &RunOutput,
) -> anyhow::Result<Summary> {
    od.write_path("timeseries.csv", |p| write_timeseries_csv(p, out))?;
    let summary = summarize(sc, out)?;
    let json = serde_json::to_string_pretty(&summary)?;
    od.write_bytes("summary.json", (json + "\n").as_bytes())?;
    let figures = write_figures(od, out)?;
    let title = label(out);
    let mut settings = common_settings();
    settings.extend([
        ("scenario".into(), sc.case.name.clone()),
        ("estimator".into(), format!("{:?}", summary.estimator).to_lowercase()),
        (
            "solver".into(),
            summary
                .solver
                .map_or("— (no implicit equation)".into(), |s| format!("{s:?}").to_lowercase()),
        ),
        ("realtime factor".into(), format!("{:.0}×", summary.realtime_factor)),
    ]);
    Report {
        title: format!("aeroident poc — {title}"),
        settings,
        results: vec![results(&summary, &title)],
        figures,
        warnings: out.stopped_early.iter().cloned().collect(),
        links: Vec::new(),
    }
    .write(od)?;
    Ok(summary)
}
