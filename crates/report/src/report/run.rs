//! Results and `report.html` of the closed-loop `run` experiment: one table per estimator
//! (estimate ± σ against the simulator's truth at the end of the run, error %, status), the
//! run's settings and its figures ([`crate::aircraft::figures`]).

use super::{Figure, Report, common_settings};
use crate::outdir::{OutputDir, OutputError};
use aeroident_pipelines::aircraft::RunOutput;
use aeroident_pipelines::aircraft::summary::Summary;
use aeroident_pipelines::results::Results;
use std::path::Path;

/// One [`Results`] per estimator of `summary`, in order of appearance; the reference column is
/// the truth at the end of the run (after a damage step, the new value).
pub fn results(summary: &Summary) -> Vec<Results> {
    let mut out: Vec<Results> = Vec::new();
    for p in &summary.parameters {
        let title = format!("{} — {} ({}s)", summary.scenario, p.estimator, p.quantity);
        // The status is the library's (ParamSummary::judge); the table marks primaries.
        let mut row = p.result.clone();
        row.name = format!("{}{}", p.name, if p.primary { "*" } else { "" });
        match out.iter_mut().find(|r| r.title == title) {
            Some(r) => r.rows.push(row),
            None => out.push(Results {
                title,
                reference_label: "truth".into(),
                rows: vec![row],
                fit: Vec::new(),
                notes: Vec::new(),
            }),
        }
    }
    // Each estimator's events (other than restarts, which are warnings) under its table.
    for e in &summary.events {
        let head = format!("{} — {} (", summary.scenario, e.estimator);
        if let (Some(n), Some(r)) =
            (e.events.note(), out.iter_mut().find(|r| r.title.starts_with(&head)))
        {
            r.notes.push(n);
        }
    }
    if let Some(last) = out.last_mut() {
        last.notes.push(
            "* = primary derivative; targets: within ±10 % within 5 s of the excitation and of the damage, ±2σ covering the truth at the end".into(),
        );
        if let Some(t) = summary.damage_at_s {
            last.notes.push(format!("truth = the value after the damage at {t:.2} s"));
        }
    }
    out
}

/// The settings of a run, for the report: scenario, estimators, trim, excitation and damage
/// times, and one `batch fit` line per post-flight fit ([`crate::aircraft::outputs::batch_fit_line`]).
pub fn settings(out: &RunOutput, summary: &Summary) -> Vec<(String, String)> {
    let mut s = common_settings();
    let sc = &out.scenario;
    s.extend([
        ("scenario".into(), sc.name.clone()),
        ("estimators".into(), summary.estimator.clone()),
        ("duration".into(), format!("{} s", sc.duration_s)),
        ("solver".into(), summary.solver.clone()),
        (
            "trim".into(),
            format!(
                "V_T {:.1} ft/s, α {:.2}°, throttle {:.3}, δe {:.2}°",
                summary.trim[0],
                summary.trim[1].to_degrees(),
                summary.trim[2],
                summary.trim[3].to_degrees()
            ),
        ),
        (
            "excitation / damage".into(),
            format!(
                "from {} / at {}",
                summary.excitation_start_s.map_or("—".into(), |t| format!("{t:.2} s")),
                summary.damage_at_s.map_or("none".into(), |t| format!("{t:.2} s"))
            ),
        ),
        ("angular accelerations".into(), summary.angular_accelerations.clone().unwrap_or_default()),
        ("realtime factor".into(), format!("{:.0}×", summary.realtime_factor)),
    ]);
    // Batch (post-flight) fits: window, iterations, wall time, as the terminal prints them.
    s.extend(
        summary
            .batch_fits
            .iter()
            .map(|b| ("batch fit".into(), crate::aircraft::outputs::batch_fit_line(b))),
    );
    s
}

/// Writes `report.html` of a run into `od`.
///
/// # Errors
/// [`OutputError`] naming the file.
pub fn write(
    out: &RunOutput,
    summary: &Summary,
    figures: Vec<Figure>,
    od: &mut OutputDir,
) -> Result<(), OutputError> {
    let warnings = out
        .channels
        .iter()
        .filter_map(|c| {
            c.failure.as_ref().map(|(t, m)| format!("{} failed at {t:.2} s: {m}", c.label))
        })
        .chain(summary.event_warnings())
        .collect();
    Report {
        title: format!("aeroident run — {}", summary.scenario),
        settings: settings(out, summary),
        results: results(summary),
        figures,
        warnings,
        links: Vec::new(),
    }
    .write(od)?;
    Ok(())
}

/// Writes the top-level `report.html` of `run --all` into `od`: one link per scenario to its
/// own `<name>/report.html` with its one-line overview (`lines`: (scenario name, overview
/// cells)), then every scenario's results tables ([`results`]), in the order given.
///
/// # Errors
/// [`OutputError`] naming the file.
pub fn write_index(
    scenarios_dir: &Path,
    lines: &[(String, String)],
    summaries: &[&Summary],
    od: &mut OutputDir,
) -> Result<(), OutputError> {
    let mut settings = common_settings();
    settings.extend([
        ("scenarios".into(), scenarios_dir.display().to_string()),
        ("runs".into(), lines.len().to_string()),
        ("thesis comparison".into(), "report.md (thesis vs ours, per table)".into()),
    ]);
    let links = lines
        .iter()
        .map(|(name, cells)| {
            (format!("{name}/report.html"), format!("{name} — {cells} within 5 % of the truth"))
        })
        .collect();
    let warnings = summaries
        .iter()
        .flat_map(|s| {
            s.parameters.iter().filter_map(|p| {
                p.failure
                    .as_ref()
                    .map(|f| format!("{}: {} {} failed: {f}", s.scenario, p.estimator, p.name))
            })
        })
        .collect();
    Report {
        title: format!("aeroident run --all — {}", scenarios_dir.display()),
        settings,
        results: summaries.iter().flat_map(|s| results(s)).collect(),
        figures: Vec::new(),
        warnings,
        links,
    }
    .write(od)?;
    Ok(())
}
