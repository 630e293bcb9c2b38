//! Results, figures and `report.html` of a `replay`: the parameter table (estimate ± σ against
//! the model file's reference values, if it gives any), the fit quality of every modelled
//! coefficient the record measures, `estimates.{png,svg}` (estimates with shaded ±2σ and the
//! reference lines) and `fit.{png,svg}` (measured coefficient vs the model's prediction from
//! the final estimates, and the residual).

use super::{Report, common_settings, write_figure};
use crate::outdir::OutputDir;
use crate::plot::{Band, HLine, LineKind, Panel, Series};
use aeroident_pipelines::replay::{History, ReplayOutcome};
use aeroident_pipelines::replay::{Pacing, ReplayOptions};
use aeroident_pipelines::results::{CoefficientFit, Results, coefficient_fits};

/// A published reference value of a parameter (from the model file's `[reference.X]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// Parameter name, e.g. `Cm_alpha`.
    pub name: String,
    /// The value.
    pub value: f64,
    /// Where it comes from.
    pub source: String,
}

/// The references of the model `outcome` identified.
pub fn model_references(outcome: &ReplayOutcome) -> Vec<Reference> {
    spec_references(&outcome.model)
}

/// The references of a model file (its `[reference.X]` tables; none for a preset).
pub fn spec_references(model: &aeroident_io::ModelSpec) -> Vec<Reference> {
    model
        .references
        .iter()
        .map(|r| Reference {
            name: r.param.name().to_string(),
            value: r.value,
            source: r.source.clone(),
        })
        .collect()
}

/// The results of `outcome`: one row per parameter and the fit quality per coefficient.
pub fn results(outcome: &ReplayOutcome, title: &str, references: &[Reference]) -> Results {
    let diverged = outcome.diverged();
    // The verdicts are the library's (aeroident_pipelines::replay::verdict), judged once.
    let rows = outcome.summary.parameters.iter().map(|p| p.result.clone()).collect();
    let fit = if diverged {
        Vec::new()
    } else {
        fits(outcome).iter().filter_map(CoefficientFit::quality).collect()
    };
    let mut notes = Vec::new();
    let mut sources: Vec<&str> = Vec::new();
    for r in references {
        if !sources.contains(&r.source.as_str()) {
            sources.push(&r.source);
        }
    }
    for s in sources {
        notes.push(format!("reference: {s}"));
    }
    if let Some(n) = outcome.summary.events.note() {
        notes.push(n);
    }
    if outcome.samples.stride() > 1 {
        notes.push(format!(
            "fit quality on every {}th sample (the kept history of a long record)",
            outcome.samples.stride()
        ));
    }
    Results { title: title.to_string(), reference_label: "reference".into(), rows, fit, notes }
}

fn fits(outcome: &ReplayOutcome) -> Vec<CoefficientFit> {
    let theta: Vec<Option<f64>> = outcome.summary.parameters.iter().map(|p| p.estimate).collect();
    coefficient_fits(&outcome.model.structure, &theta, outcome.samples.items())
}

/// One panel per parameter: the estimate (a gap until identified), its shaded ±2σ band and
/// the reference line.
pub fn estimate_panels(h: &History, references: &[Reference]) -> Vec<Panel> {
    h.names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let v: Vec<f64> = h.values.iter().map(|v| v[i].unwrap_or(f64::NAN)).collect();
            let band = |sign: f64| -> Vec<f64> {
                h.sigmas
                    .iter()
                    .zip(&v)
                    .map(|(s, v)| s[i].map_or(f64::NAN, |s| v + sign * 2.0 * s))
                    .collect()
            };
            let bands = if h.sigmas.iter().any(|s| s[i].is_some()) {
                vec![Band {
                    label: "±2σ".into(),
                    series: 0,
                    t_s: h.t_s.clone(),
                    lo: band(-1.0),
                    hi: band(1.0),
                }]
            } else {
                Vec::new()
            };
            let hlines = references
                .iter()
                .filter(|r| r.name == *name)
                .map(|r| HLine { label: "reference".into(), value: r.value })
                .collect();
            Panel {
                title: (*name).to_string(),
                y_label: (*name).to_string(),
                series: vec![Series {
                    label: "estimate".into(),
                    t_s: h.t_s.clone(),
                    values: v,
                    kind: LineKind::Solid,
                }],
                bands,
                hlines,
                signals: false,
            }
        })
        .collect()
}

/// Two panels per coefficient: measured and predicted, and the residual.
pub fn fit_panels(fits: &[CoefficientFit]) -> Vec<Panel> {
    let mut v = Vec::new();
    for f in fits {
        let c = f.coefficient.name();
        v.push(Panel {
            title: format!("{c}: measured vs model (final estimates)"),
            y_label: c.to_string(),
            series: vec![
                Series {
                    label: "measured".into(),
                    t_s: f.t_s.clone(),
                    values: f.measured.clone(),
                    kind: LineKind::Solid,
                },
                Series {
                    label: "model".into(),
                    t_s: f.t_s.clone(),
                    values: f.predicted.clone(),
                    kind: LineKind::Solid,
                },
            ],
            signals: true,
            ..Default::default()
        });
        v.push(Panel {
            title: format!("{c}: residual (measured − model)"),
            y_label: format!("Δ{c}"),
            series: vec![Series {
                label: "residual".into(),
                t_s: f.t_s.clone(),
                values: f.measured.iter().zip(&f.predicted).map(|(z, y)| z - y).collect(),
                kind: LineKind::Solid,
            }],
            hlines: vec![HLine { label: "0".into(), value: 0.0 }],
            signals: true,
            ..Default::default()
        });
    }
    v
}

/// The settings of a replay of `source` with `opts`, for the report.
pub fn settings(
    source: &super::Source,
    opts: &ReplayOptions,
    outcome: &ReplayOutcome,
) -> Vec<(String, String)> {
    let mut s = common_settings();
    let derived: Vec<&str> = outcome.differentiated.iter().map(|d| d.name()).collect();
    s.extend([
        ("data".into(), source.data.to_string()),
        ("mapping".into(), source.mapping.display().to_string()),
        (
            "model".into(),
            format!(
                "{}{} — {}",
                outcome.model.name,
                if outcome.model_defaulted { " (default: richest supported preset)" } else { "" },
                outcome.model.description
            ),
        ),
        ("structure".into(), outcome.model.structure.names().collect::<Vec<_>>().join(", ")),
        ("estimator".into(), format!("{} ({})", opts.estimator.name(), outcome.summary.estimator)),
        ("forgetting factor".into(), opts.estimator_options.forgetting.to_string()),
        (
            "derivatives".into(),
            format!(
                "{:?}; differentiated: {} (window {} samples)",
                opts.derivatives,
                if derived.is_empty() { "none".to_string() } else { derived.join(", ") },
                opts.diff_window
            ),
        ),
        (
            "pacing".into(),
            if opts.pacing == Pacing::Realtime { "real time".into() } else { "unpaced".into() },
        ),
        (
            "samples".into(),
            format!(
                "{} read, {} rejected; status {}",
                outcome.summary.samples_read,
                outcome.summary.samples_rejected,
                outcome.summary.status
            ),
        ),
    ]);
    s
}

/// Writes `estimates.{png,svg}`, `fit.{png,svg}` (when a coefficient can be compared) and
/// `report.html` into `od`; returns the results for the console.
///
/// # Errors
/// Figure or output errors, naming the file.
pub fn write(
    source: &super::Source,
    opts: &ReplayOptions,
    outcome: &ReplayOutcome,
    title: &str,
    references: &[Reference],
    od: &mut OutputDir,
) -> anyhow::Result<Results> {
    let res = results(outcome, title, references);
    let mut figures = Vec::new();
    let est = estimate_panels(&outcome.history, references);
    if !est.is_empty() {
        figures.push(write_figure::<anyhow::Error>(
            od,
            "estimates",
            &format!("{title}: estimates"),
            "Estimates over the record: a gap until identified, shaded ±2σ, dashed reference where the model file gives one; y-range from the converged part.",
            &est,
            (1000, 180),
        )?);
    }
    let fit = if outcome.diverged() { Vec::new() } else { fit_panels(&fits(outcome)) };
    if !fit.is_empty() {
        figures.push(write_figure::<anyhow::Error>(
            od,
            "fit",
            &format!("{title}: model vs measured"),
            "Measured coefficient against the model's prediction from the final estimates, and the residual.",
            &fit,
            (1000, 200),
        )?);
    }
    let (reader_settings, reader_warnings) = super::reader_rows(&outcome.reader);
    let mut settings = settings(source, opts, outcome);
    settings.extend(reader_settings);
    settings.extend(super::sign_tests_row(&outcome.summary.sign_tests));
    let report = Report {
        title: format!("aeroident replay — {title}"),
        settings,
        results: vec![res.clone()],
        figures,
        warnings: super::warning_texts(&outcome.summary.warnings, reader_warnings),
        links: Vec::new(),
    };
    report.write(od)?;
    Ok(res)
}
