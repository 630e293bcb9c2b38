//! `report.html` of a Monte Carlo campaign: per estimator the mean final estimate ± its
//! scatter over the runs against the truth, the campaign's settings and its figures (the
//! histograms and the coverage chart, inlined as PNG data).

use super::{Figure, Report, common_settings, png_figure};
use crate::outdir::{OutputDir, OutputError};
use aeroident_pipelines::montecarlo::Campaign;
use aeroident_pipelines::results::{ParameterResult, Results};

/// One [`Results`] per estimator: the mean final estimate (truth + bias) ± the scatter (the
/// standard deviation over the runs), the truth, the error of the mean and whether the truth
/// lies within 2 scatters of the mean.
pub fn results(c: &Campaign) -> Vec<Results> {
    c.estimators
        .iter()
        .map(|e| Results {
            title: format!(
                "{} — mean of {} runs ± scatter ({} failed, {} restarted from the priors)",
                e.name,
                e.runs_ok,
                e.failed_runs.len(),
                e.restarted_runs.len()
            ),
            reference_label: "truth".into(),
            rows: e
                .parameters
                .iter()
                .map(|p| {
                    let mean = p.reference.zip(p.bias).map(|(t, b)| t + b);
                    let name = format!("{}{}", p.name, if p.primary { "*" } else { "" });
                    ParameterResult::new(name, mean, p.scatter, p.reference, None)
                })
                .collect(),
            fit: Vec::new(),
            notes: vec![
                "estimate ± σ = mean of the final estimates over the runs ± their standard deviation (scatter); status: the truth within 2 scatters of the mean or not; * = primary derivative".into(),
            ],
        })
        .collect()
}

/// Writes `report.html` into `od`, inlining the figures the campaign wrote there
/// (`histograms_*.png`, `coverage.png`).
///
/// # Errors
/// [`OutputError`] naming the file.
pub fn write(c: &Campaign, od: &mut OutputDir) -> Result<(), OutputError> {
    // The SVG of each figure (the PNG where no SVG was written), of those this run wrote.
    let mut files: Vec<std::path::PathBuf> = od.written().map(|n| od.path().join(n)).collect();
    files.retain(|p| {
        let ext = p.extension().and_then(|x| x.to_str());
        ext == Some("svg") || (ext == Some("png") && !p.with_extension("svg").exists())
    });
    files.sort();
    let mut figures = Vec::new();
    for p in files {
        let name = p.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned());
        if p.extension().is_some_and(|x| x == "svg") {
            if let Ok(svg) = std::fs::read_to_string(&p) {
                figures.push(Figure { caption: name, svg });
            }
        } else if let Ok(bytes) = std::fs::read(&p) {
            figures.push(png_figure(&bytes, &name, &name));
        }
    }
    let mut settings = common_settings();
    settings.extend([
        ("scenario".into(), c.scenario.clone()),
        ("runs".into(), c.runs.to_string()),
        ("seed".into(), c.seed.to_string()),
        ("wall time".into(), format!("{:.1} s on {} threads", c.wall_s, c.threads)),
    ]);
    Report {
        title: format!("aeroident montecarlo — {}", c.scenario),
        settings,
        results: results(c),
        figures,
        warnings: c.crb_notes.clone(),
        links: Vec::new(),
    }
    .write(od)?;
    Ok(())
}
