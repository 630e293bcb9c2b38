//! The report of `aeroident freqresp --out DIR`: per (output, input) pair a Bode figure
//! (magnitude with its ±random-error band, phase, and coherence, against frequency in rad/s on
//! a log axis, with each fitted transfer function dashed), `bode_<output>_<input>.{png,svg}`,
//! and a table of every fit's gain, delay, modes and cost in `report.html`.

use super::{Figure, Report, Source, common_settings};
use crate::outdir::OutputDir;
use aeroident_pipelines::freqresp::{FitSummary, FreqRespOutcome};
use aeroident_pipelines::results::{ParameterResult, Results};
use aeroident_signals::spectral::PairResponse;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::f64::consts::PI;

/// Writes the Bode figures and `report.html` into `od`.
///
/// # Errors
/// Figure or output errors, naming the file.
pub fn write(source: &Source, o: &FreqRespOutcome, od: &mut OutputDir) -> anyhow::Result<()> {
    let mut figures = Vec::new();
    for p in &o.pairs {
        let fits: Vec<&FitSummary> = o
            .fits
            .iter()
            .filter(|f| f.spec.starts_with(&format!("{}/{}:", p.output, p.input)))
            .collect();
        let stem = format!("bode_{}_{}", p.output, p.input);
        let title = format!("{}/{} (SI units)", p.output, p.input);
        od.write_path(&format!("{stem}.png"), |path| {
            let root = BitMapBackend::new(path, (900, 900)).into_drawing_area();
            draw(&root, &title, p, &fits).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
        })?;
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (900, 900)).into_drawing_area();
            draw(&root, &title, p, &fits).map_err(|e| anyhow::anyhow!("{stem}.svg: {e}"))?;
        }
        od.write_bytes(&format!("{stem}.svg"), svg.as_bytes())?;
        figures.push(Figure {
            caption: format!(
                "Frequency response of {} to {}: magnitude (shaded ± the random error 20 log₁₀(1 ± ε)), phase, and {} coherence; dashed: fitted transfer functions.",
                p.output,
                p.input,
                if o.pairs.iter().filter(|q| q.output == p.output).count() > 1 { "partial" } else { "ordinary" }
            ),
            svg,
        });
    }
    let results: Vec<Results> = o.fits.iter().map(fit_table).collect();
    let mut settings = vec![
        ("record".to_string(), source.data.to_string()),
        ("mapping".to_string(), source.mapping.display().to_string()),
        ("samples".to_string(), o.samples.to_string()),
        ("stretches".to_string(), o.stretches.to_string()),
        ("sample interval (s)".to_string(), o.dt_s.to_string()),
        (
            "window lengths (s)".to_string(),
            o.window_lengths_s.iter().map(|w| format!("{w:.2}")).collect::<Vec<_>>().join(", "),
        ),
        ("overlap".to_string(), o.overlap.to_string()),
    ];
    settings.extend(common_settings());
    Report {
        title: format!("aeroident freqresp — {}", o.file),
        settings,
        results,
        figures,
        warnings: o.warnings.clone(),
        ..Default::default()
    }
    .write(od)?;
    Ok(())
}

/// A fit's numbers as a results table.
fn fit_table(f: &FitSummary) -> Results {
    let mut rows =
        vec![ParameterResult::new("gain K", Some(f.fit.gain), f.fit.gain_sigma, None, None)];
    if f.fit.delay_sigma_s.is_some() || f.fit.delay_s != 0.0 {
        rows.push(ParameterResult::new(
            "delay τ (s)",
            Some(f.fit.delay_s),
            f.fit.delay_sigma_s,
            None,
            None,
        ));
    }
    for (what, list) in [("pole", &f.fit.poles), ("zero", &f.fit.zeros)] {
        for (i, fac) in list.iter().enumerate() {
            rows.push(ParameterResult::new(
                format!("{what} factor {} ωn (rad/s)", i + 1),
                fac.wn_rad_s,
                fac.wn_sigma_rad_s,
                None,
                None,
            ));
            if fac.zeta.is_some() {
                rows.push(ParameterResult::new(
                    format!("{what} factor {} ζ", i + 1),
                    fac.zeta,
                    fac.zeta_sigma,
                    None,
                    None,
                ));
            }
        }
    }
    Results {
        title: format!("fit {}", f.spec),
        reference_label: "reference".into(),
        rows,
        fit: Vec::new(),
        notes: vec![format!(
            "J = {:.1} over {} frequencies, {:.3}–{:.3} rad/s, coherence ≥ {} ({}; J ≤ 100 is a good fit by Tischler & Remple's guideline). σ from the Gauss–Newton Hessian scaled by the misfit.",
            f.fit.cost,
            f.fit.frequencies_used,
            f.fit.band_rad_s.0,
            f.fit.band_rad_s.1,
            f.fit.min_coherence,
            f.fit.status
        )],
    }
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// Three panels (magnitude, phase, coherence) against ω on a log axis.
fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    p: &PairResponse,
    fits: &[&FitSummary],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    crate::plot::register_fonts();
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 20))?;
    let panels = root.split_evenly((3, 1));
    let w: Vec<f64> = p.frequency_hz.iter().map(|f| 2.0 * PI * f).collect();
    let (lo, hi) = (w[0], w[w.len() - 1]);
    let finite = |v: &[f64]| -> (f64, f64) {
        let (a, b) = v
            .iter()
            .filter(|x| x.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
        if a.is_finite() {
            (a - 0.05 * (b - a).max(1.0), b + 0.05 * (b - a).max(1.0))
        } else {
            (0.0, 1.0)
        }
    };
    let upper: Vec<f64> =
        p.magnitude_db.iter().zip(&p.magnitude_error_db).map(|(m, e)| m + e).collect();
    let lower: Vec<f64> = p
        .magnitude_db
        .iter()
        .zip(&p.random_error)
        .map(|(m, e)| m + 20.0 * (1.0 - e.min(0.99)).log10())
        .collect();
    let series = [
        ("magnitude (dB)", p.magnitude_db.clone(), finite(&p.magnitude_db), true),
        ("phase (deg)", p.phase_deg.clone(), finite(&p.phase_deg), false),
        ("coherence", p.coherence.clone(), (0.0, 1.05), false),
    ];
    for (k, (label, v, range, band)) in series.into_iter().enumerate() {
        let mut chart = ChartBuilder::on(&panels[k])
            .margin(8)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d((lo..hi).log_scale(), range.0..range.1)?;
        chart.configure_mesh().x_desc("frequency (rad/s)").y_desc(label).draw()?;
        if band {
            let poly: Vec<(f64, f64)> = w
                .iter()
                .zip(&upper)
                .chain(w.iter().zip(&lower).rev())
                .filter(|(_, y)| y.is_finite())
                .map(|(x, y)| (*x, y.clamp(range.0, range.1)))
                .collect();
            chart.draw_series(std::iter::once(Polygon::new(
                poly,
                RGBColor(31, 119, 180).mix(0.2),
            )))?;
        }
        chart.draw_series(LineSeries::new(
            w.iter().zip(&v).filter(|(_, y)| y.is_finite()).map(|(x, y)| (*x, *y)),
            BLACK.stroke_width(2),
        ))?;
        if k < 2 {
            for (i, f) in fits.iter().enumerate() {
                let model = if k == 0 { &f.fit.model_magnitude_db } else { &f.fit.model_phase_deg };
                let used = (f.fit.band_rad_s.0, f.fit.band_rad_s.1);
                let colour =
                    [RGBColor(214, 39, 40), RGBColor(44, 160, 44), RGBColor(148, 103, 189)][i % 3];
                let pts: Vec<(f64, f64)> = w
                    .iter()
                    .zip(model)
                    .filter(|(x, y)| y.is_finite() && **x >= used.0 && **x <= used.1)
                    .map(|(x, y)| (*x, y.clamp(range.0, range.1)))
                    .collect();
                chart.draw_series(DashedLineSeries::new(pts, 6, 4, colour.stroke_width(2)))?;
            }
        } else {
            chart.draw_series(LineSeries::new([(lo, 0.8), (hi, 0.8)], RGBColor(120, 120, 120)))?;
        }
    }
    root.present()?;
    Ok(())
}
