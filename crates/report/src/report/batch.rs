//! Results, figures and `report.html` of `replay --estimator oe` (the batch output-error
//! fit): the parameter table (estimate ± the summary's `std_error`, the Cramér–Rao σ beside it,
//! against the model file's reference values, if it gives any), the fit quality of every simulated output (from the summary's
//! `validation` block: residual RMS, R², Theil's U) and `fit.{png,svg}` (per output the
//! measured and the simulated time history, and the residual).

use super::replay::{Reference, spec_references};
use super::{Report, common_settings, write_figure};
use crate::outdir::OutputDir;
use crate::plot::{HLine, LineKind, Panel, Series};
use crate::table::fmt_sig;
use aeroident_io::StdErrorSource;
use aeroident_pipelines::replay::batch::{BatchOutcome, OutputTrace};
use aeroident_pipelines::results::{FitQuality, Results};

/// What the summary's `std_error` is, in words: one source, or the parameters of each.
fn sigma_sources(s: &aeroident_pipelines::replay::batch::BatchSummary) -> String {
    let word = |k: Option<StdErrorSource>| k.map_or("none", StdErrorSource::words);
    let mut kinds: Vec<Option<StdErrorSource>> =
        s.parameters.iter().map(|p| p.std_error_source).collect();
    kinds.dedup();
    match kinds.as_slice() {
        [] => "none".into(),
        [k] => word(*k).into(),
        _ => s
            .parameters
            .iter()
            .map(|p| format!("{} {}", p.name, word(p.std_error_source)))
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// The results of a batch fit: one row per parameter (σ = the summary's `std_error`, the one
/// σ of the summary, the Python `sigma` and the ±2σ status; the Cramér–Rao σ beside it) and
/// one fit-quality row per validated output.
pub fn results(outcome: &BatchOutcome, title: &str, references: &[Reference]) -> Results {
    let s = &outcome.summary;
    let rows = s.parameters.iter().map(|p| p.result.clone()).collect();
    let v = &s.validation;
    let fit = v.outputs.iter().map(FitQuality::from).collect();
    let mut notes = vec![format!(
        "σ = the summary's std_error ({}); Cramér–Rao σ = the bound of the {} fit, optimistic when the residuals are coloured; fit quality of the simulated outputs over the fitted record",
        sigma_sources(s),
        if s.process_noise.is_empty() { "output-error" } else { "filter-error" }
    )];
    let coloured: Vec<String> = s
        .parameters
        .iter()
        .filter_map(|p| p.coloured_std_error.map(|c| format!("{} {}", p.name, fmt_sig(Some(c), 2))))
        .collect();
    if !coloured.is_empty() && s.bootstrap.is_some() {
        notes.push(format!("coloured-residual σ: {}", coloured.join(", ")));
    }
    if let Some(b) = &s.bootstrap {
        let sig: Vec<String> = s
            .parameters
            .iter()
            .filter_map(|p| {
                p.bootstrap_std_error.map(|c| format!("{} {}", p.name, fmt_sig(Some(c), 2)))
            })
            .collect();
        notes.push(format!(
            "parametric bootstrap σ ({} of {} replicas refitted): {}",
            b.refits - b.failed,
            b.refits,
            sig.join(", ")
        ));
        let bias: Vec<String> = s
            .parameters
            .iter()
            .filter_map(|p| {
                let (b, sb) = (p.bootstrap_bias?, p.bootstrap_std_error?);
                (sb > 0.0).then(|| format!("{} {:+.2}σ", p.name, b / sb))
            })
            .collect();
        let n = (b.refits - b.failed).max(1) as f64;
        notes.push(format!(
            "bootstrap bias estimate (the refits' mean less the estimate, not subtracted; its own error ±{:.2}σ): {}",
            1.0 / n.sqrt(),
            bias.join(", ")
        ));
    }
    let mut sources: Vec<&str> = Vec::new();
    for r in references {
        if !sources.contains(&r.source.as_str()) {
            sources.push(&r.source);
        }
    }
    notes.extend(sources.iter().map(|s| format!("reference: {s}")));
    notes.extend(v.notes.iter().cloned());
    Results { title: title.to_string(), reference_label: "reference".into(), rows, fit, notes }
}

/// Two panels per output: measured and simulated, and the residual.
pub fn trace_panels(traces: &[OutputTrace]) -> Vec<Panel> {
    measured_vs(traces, "simulated (estimated parameters)")
}

/// Two panels per output: measured against the model (`model`, for the title), and the
/// residual.
pub fn measured_vs(traces: &[OutputTrace], model: &str) -> Vec<Panel> {
    let mut v = Vec::new();
    for tr in traces {
        v.push(Panel {
            title: format!("{}: measured vs {model}", tr.name),
            y_label: tr.name.clone(),
            series: vec![
                Series {
                    label: "measured".into(),
                    t_s: tr.t_s.clone(),
                    values: tr.measured.clone(),
                    kind: LineKind::Solid,
                },
                Series {
                    label: "model".into(),
                    t_s: tr.t_s.clone(),
                    values: tr.simulated.clone(),
                    kind: LineKind::Solid,
                },
            ],
            signals: true,
            ..Default::default()
        });
        v.push(Panel {
            title: format!("{}: residual (measured − model)", tr.name),
            y_label: format!("Δ{}", tr.name),
            series: vec![Series {
                label: "residual".into(),
                t_s: tr.t_s.clone(),
                values: tr.measured.iter().zip(&tr.simulated).map(|(z, y)| z - y).collect(),
                kind: LineKind::Solid,
            }],
            hlines: vec![HLine { label: "0".into(), value: 0.0 }],
            signals: true,
            ..Default::default()
        });
    }
    v
}

/// The settings of a batch fit of `source`, for the report.
pub fn settings(source: &super::Source, outcome: &BatchOutcome) -> Vec<(String, String)> {
    let s = &outcome.summary;
    let mut v = common_settings();
    v.extend([
        ("data".into(), source.data.to_string()),
        ("mapping".into(), source.mapping.display().to_string()),
        ("model".into(), format!("{} — {}", outcome.model.name, outcome.model.description)),
        ("structure".into(), outcome.model.structure.names().collect::<Vec<_>>().join(", ")),
        (
            "estimator".into(),
            match s.estimator.as_str() {
                "fem" => {
                    "fem (batch maximum-likelihood filter error: output error with process noise)"
                        .to_string()
                }
                "fdoe" => match &s.frequency_domain {
                    Some(f) => format!(
                        "fdoe (frequency-domain output error, Klein & Morelli ch. 7) over {}–{} Hz; linear model states {}, inputs {}; not estimated (null): {}",
                        f.band_hz.0,
                        f.band_hz.1,
                        f.states.join(", "),
                        f.inputs.join(", "),
                        f.not_estimated.join(", ")
                    ),
                    None => "fdoe (frequency-domain output error)".to_string(),
                },
                _ => "oe (batch maximum-likelihood output error)".to_string(),
            },
        ),
        ("initial states".into(), s.initial_states.clone()),
        (
            "outputs".into(),
            outcome.result.outputs.iter().map(|o| o.name()).collect::<Vec<_>>().join(", "),
        ),
        (
            "samples".into(),
            format!(
                "{} read, {} rejected, {} manoeuvre(s); {} iterations in {:.3} s; status {}",
                s.samples_read,
                s.samples_rejected,
                s.manoeuvres,
                s.iterations.len().saturating_sub(1),
                s.fit_wall_s,
                s.status
            ),
        ),
    ]);
    if let Some(b) = &s.bootstrap {
        let f: Vec<String> = b
            .process_noise
            .iter()
            .map(|n| format!("{} {}", n.state, fmt_sig(Some(n.f), 2)))
            .collect();
        v.push((
            "σ".into(),
            format!(
                "parametric bootstrap: {} replicas flown through the fitted model with the filter-error fit's process noise F per √s ({}) and measurement noise, refitted; {} failed; seed {}; {:.2} s",
                b.refits,
                f.join(", "),
                b.failed,
                b.seed,
                b.wall_s
            ),
        ));
    }
    if let Some(v2) = &s.validation_on {
        v.push(("validated on".into(), v2.data.clone()));
    }
    v
}

/// Writes `fit.{png,svg}` (when an output could be traced) and `report.html` into `od`;
/// returns the results for the console.
///
/// # Errors
/// Figure or output errors, naming the file.
pub fn write(
    source: &super::Source,
    outcome: &BatchOutcome,
    title: &str,
    od: &mut OutputDir,
) -> anyhow::Result<Results> {
    let references = spec_references(&outcome.model);
    let res = results(outcome, title, &references);
    let mut figures = Vec::new();
    let panels = trace_panels(&outcome.traces);
    if !panels.is_empty() {
        figures.push(write_figure::<anyhow::Error>(
            od,
            "fit",
            &format!("{title}: model vs measured"),
            "Each output measured and simulated with the estimated parameters (integrated over each manoeuvre from its first sample), and the residual.",
            &panels,
            (1000, 200),
        )?);
    }
    let mut results = vec![res.clone()];
    if let Some(v2) = &outcome.summary.validation_on {
        results.push(Results {
            title: format!("validation on {}", v2.data),
            reference_label: "reference".into(),
            rows: Vec::new(),
            fit: v2.outputs.iter().map(FitQuality::from).collect(),
            notes: v2.notes.clone(),
        });
    }
    let (reader_settings, reader_warnings) = super::reader_rows(&outcome.summary.reader);
    let mut settings = settings(source, outcome);
    settings.extend(reader_settings);
    settings.extend(super::sign_tests_row(&outcome.summary.sign_tests));
    Report {
        title: format!("aeroident replay — {title}"),
        settings,
        results,
        figures,
        warnings: super::warning_texts(&outcome.summary.warnings, reader_warnings),
        ..Default::default()
    }
    .write(od)?;
    Ok(res)
}
