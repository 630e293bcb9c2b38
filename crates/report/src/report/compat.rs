//! The report of a data-compatibility check (`aeroident compat --out DIR`): `report.html` with
//! the estimated biases, scale factors and time shifts (± the reported σ), the plain-language
//! findings, and per fitted channel the measured signal against what the reconstructed flight
//! path says it should read, with the residual (`compat.{png,svg}`).

use super::batch::measured_vs;
use super::{Report, Source, common_settings, write_figure};
use crate::outdir::OutputDir;
use aeroident_pipelines::compat::{ChannelSummary, CompatSummary};
use aeroident_pipelines::results::OutputTrace;
use aeroident_pipelines::results::{ParameterResult, Results};

/// One row per estimated bias, scale factor and time shift (the scale as its departure from 1).
fn rows(channels: &[ChannelSummary]) -> Vec<ParameterResult> {
    let mut rows = Vec::new();
    for c in channels {
        let unit = &c.unit;
        let mut add = |what: String, v: Option<f64>, s: Option<f64>| {
            if v.is_some() {
                rows.push(ParameterResult::new(what, v, s, None, None));
            }
        };
        add(format!("{} bias ({unit})", c.name), c.bias, c.bias_sigma);
        add(format!("{} scale − 1", c.name), c.scale.map(|k| k - 1.0), c.scale_sigma);
        add(format!("{} time shift (s)", c.name), c.time_shift_s, c.time_shift_sigma_s);
    }
    rows
}

/// Writes `compat.{png,svg}` (when a channel could be traced) and `report.html` into `od`.
///
/// # Errors
/// Figure or output errors, naming the file.
pub fn write(
    source: &Source,
    summary: &CompatSummary,
    traces: &[OutputTrace],
    od: &mut OutputDir,
) -> anyhow::Result<()> {
    let name = std::path::Path::new(&summary.file)
        .file_name()
        .map_or(summary.file.clone(), |n| n.to_string_lossy().into_owned());
    let title = format!("compatibility check of {name}");
    let mut figures = Vec::new();
    let panels = measured_vs(traces, "the reconstructed flight path");
    if !panels.is_empty() {
        figures.push(write_figure::<anyhow::Error>(
            od,
            "compat",
            &format!("{title}: measured vs reconstructed"),
            "Each channel as recorded and as the kinematics integrated from the accelerometers and rates say it should read (with its estimated bias, scale factor and time shift), and the residual.",
            &panels,
            (1000, 200),
        )?);
    }
    let results = Results {
        title: title.clone(),
        reference_label: "reference".into(),
        rows: rows(&summary.channels),
        fit: Vec::new(),
        notes: vec![format!("σ = {} σ", summary.sigma.replace('_', "-"))],
    };
    let mut settings = vec![
        ("record".to_string(), source.data.to_string()),
        ("mapping".to_string(), source.mapping.display().to_string()),
        ("status".to_string(), summary.status.to_string()),
        ("iterations".to_string(), summary.iterations.to_string()),
    ];
    settings.extend(common_settings());
    let mut warnings: Vec<String> =
        summary.findings.iter().map(|f| format!("finding: {f}")).collect();
    warnings.extend(summary.warnings.iter().cloned());
    Report {
        title: format!("aeroident compat — {}", summary.file),
        settings,
        results: vec![results],
        figures,
        warnings,
        ..Default::default()
    }
    .write(od)?;
    Ok(())
}
