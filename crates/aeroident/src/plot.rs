//! Figures: stacked panels of time series rendered to a PNG with `plotters`.
//!
//! One generic helper, [`render_panels_png`](crate::plot::render_panels_png), draws any number of panels that share the time
//! axis (state tracking, parameter convergence, control commands). Text uses the DejaVu Sans
//! font embedded by the `dejavu` crate and registered with plotters' `ab_glyph` backend, so no
//! system font is needed.

use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};
use std::path::{Path, PathBuf};
use std::sync::Once;

/// Font family name under which DejaVu Sans is registered.
const FONT: &str = "sans-serif";

/// Errors of figure rendering. Each names the output file.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The figure had no panel, or a series had mismatched lengths.
    #[error("figure `{path}`: {reason}")]
    InvalidFigure {
        /// Output file.
        path: PathBuf,
        /// What was wrong.
        reason: String,
    },
    /// The drawing backend failed (e.g. the file could not be written).
    #[error("figure `{path}`: drawing failed: {detail}")]
    Backend {
        /// Output file.
        path: PathBuf,
        /// Backend message.
        detail: String,
    },
}

/// Line style of a series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineKind {
    /// Solid line (estimates, model states).
    Solid,
    /// Dashed line (truth, reference states).
    Dashed,
}

/// One time series: `values[k]` at `t_s[k]` (s). Non-finite points are skipped, not drawn.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Values, units as the panel's y label says.
    pub values: Vec<f64>,
    /// Line style.
    pub kind: LineKind,
}

/// One panel (a chart) of a figure: a y-axis label and its series.
#[derive(Debug, Clone)]
pub struct Panel {
    /// Panel caption.
    pub title: String,
    /// Y-axis label with unit, e.g. `"x"` or `"a1 (1/s²)"`.
    pub y_label: String,
    /// Series drawn in this panel.
    pub series: Vec<Series>,
}

/// Most points drawn per series; longer series are decimated by a fixed stride.
const MAX_POINTS: usize = 4000;

static REGISTER: Once = Once::new();

fn register_fonts() {
    REGISTER.call_once(|| {
        // The embedded DejaVu font is valid TrueType; a failure here would only mean text is
        // missing, which the backend then reports on first use.
        let _ = register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
        let _ = register_font(FONT, FontStyle::Bold, dejavu::sans::bold());
    });
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(0, 0, 0),
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
];

fn y_range(panel: &Panel) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for s in &panel.series {
        for &v in s.values.iter().filter(|v| v.is_finite()) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let span = hi - lo;
    let pad = if span > 1e-12 * (hi.abs() + lo.abs()).max(1e-300) {
        0.06 * span
    } else {
        0.5 * hi.abs().max(1.0)
    };
    (lo - pad, hi + pad)
}

/// Renders `panels` stacked vertically into a PNG at `path`, `width_px` wide and
/// `panel_height_px` per panel, with a figure `title` and a shared x label (time, s).
///
/// # Errors
/// [`PlotError::InvalidFigure`] when there is no panel, or a series's `t_s` and `values`
/// differ in length; [`PlotError::Backend`] when drawing or writing the file fails.
pub fn render_panels_png(
    path: &Path,
    title: &str,
    panels: &[Panel],
    width_px: u32,
    panel_height_px: u32,
) -> Result<(), PlotError> {
    register_fonts();
    let invalid = |reason: String| PlotError::InvalidFigure { path: path.to_path_buf(), reason };
    if panels.is_empty() {
        return Err(invalid("no panel to draw".into()));
    }
    for p in panels {
        for s in &p.series {
            if s.t_s.len() != s.values.len() {
                return Err(invalid(format!(
                    "series `{}` in panel `{}` has {} times but {} values",
                    s.label,
                    p.title,
                    s.t_s.len(),
                    s.values.len()
                )));
            }
        }
    }
    let backend_err = |e: &dyn std::fmt::Display| PlotError::Backend {
        path: path.to_path_buf(),
        detail: e.to_string(),
    };
    let height = 40 + panel_height_px * panels.len() as u32;
    let root = BitMapBackend::new(path, (width_px, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| backend_err(&e))?;
    let root = root
        .titled(title, (FONT, 22).into_font().style(FontStyle::Bold))
        .map_err(|e| backend_err(&e))?;
    let areas = root.split_evenly((panels.len(), 1));
    let (t_min, t_max) = panels
        .iter()
        .flat_map(|p| p.series.iter())
        .flat_map(|s| s.t_s.iter().copied())
        .filter(|t| t.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| (a.min(t), b.max(t)));
    let (t_min, t_max) = if t_min < t_max { (t_min, t_max) } else { (0.0, 1.0) };
    for (area, panel) in areas.iter().zip(panels) {
        let (y_lo, y_hi) = y_range(panel);
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, (FONT, 16))
            .margin(8)
            .x_label_area_size(32)
            .y_label_area_size(70)
            .build_cartesian_2d(t_min..t_max, y_lo..y_hi)
            .map_err(|e| backend_err(&e))?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .y_desc(panel.y_label.as_str())
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 14))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(|e| backend_err(&e))?;
        for (i, s) in panel.series.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            let stride = s.t_s.len().div_ceil(MAX_POINTS).max(1);
            let pts: Vec<(f64, f64)> = s
                .t_s
                .iter()
                .zip(&s.values)
                .step_by(stride)
                .filter(|(t, v)| t.is_finite() && v.is_finite())
                .map(|(&t, &v)| (t, v.clamp(y_lo, y_hi)))
                .collect();
            // 1 px: plotters joins thick polylines with miters, which spike far outside the
            // chart where a signal reverses sharply (chattering estimates).
            let style = ShapeStyle::from(&color).stroke_width(1);
            let anno = match s.kind {
                LineKind::Solid => chart.draw_series(LineSeries::new(pts, style)),
                LineKind::Dashed => chart.draw_series(DashedLineSeries::new(pts, 8, 5, style)),
            }
            .map_err(|e| backend_err(&e))?;
            anno.label(s.label.as_str()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
        }
        chart
            .configure_series_labels()
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| backend_err(&e))?;
    }
    root.present().map_err(|e| backend_err(&e))?;
    Ok(())
}

/// One histogram panel: the values binned into `bins` equal bins over their range (widened to
/// include `line`), with a vertical dashed line at `line` (e.g. the truth).
#[derive(Debug, Clone, PartialEq)]
pub struct HistogramPanel {
    /// Panel caption.
    pub title: String,
    /// X-axis label with unit.
    pub x_label: String,
    /// The values (non-finite ones are skipped).
    pub values: Vec<f64>,
    /// Number of bins (≥ 1).
    pub bins: usize,
    /// Position of the vertical line, if any.
    pub line: Option<f64>,
}

/// Renders histogram panels in a grid of `columns` into a PNG at `path`, each cell
/// `cell_px` = (width, height).
///
/// # Errors
/// [`PlotError::InvalidFigure`] when there is no panel, a panel has 0 bins or `columns` = 0;
/// [`PlotError::Backend`] when drawing or writing fails.
pub fn render_histograms_png(
    path: &Path,
    title: &str,
    panels: &[HistogramPanel],
    columns: usize,
    cell_px: (u32, u32),
) -> Result<(), PlotError> {
    register_fonts();
    let invalid = |reason: String| PlotError::InvalidFigure { path: path.to_path_buf(), reason };
    if panels.is_empty() || columns == 0 {
        return Err(invalid("no panel to draw (or 0 columns)".into()));
    }
    if let Some(p) = panels.iter().find(|p| p.bins == 0) {
        return Err(invalid(format!("panel `{}` has 0 bins", p.title)));
    }
    let backend_err = |e: &dyn std::fmt::Display| PlotError::Backend {
        path: path.to_path_buf(),
        detail: e.to_string(),
    };
    let rows = panels.len().div_ceil(columns);
    let size = (cell_px.0 * columns as u32, 40 + cell_px.1 * rows as u32);
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| backend_err(&e))?;
    let root = root
        .titled(title, (FONT, 22).into_font().style(FontStyle::Bold))
        .map_err(|e| backend_err(&e))?;
    let areas = root.split_evenly((rows, columns));
    for (area, p) in areas.iter().zip(panels) {
        let vals: Vec<f64> = p.values.iter().copied().filter(|v| v.is_finite()).collect();
        let mut lo = vals.iter().copied().fold(f64::INFINITY, f64::min);
        let mut hi = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if let Some(l) = p.line.filter(|l| l.is_finite()) {
            lo = lo.min(l);
            hi = hi.max(l);
        }
        if !lo.is_finite() {
            (lo, hi) = (-1.0, 1.0);
        }
        let span = if hi - lo > 1e-12 * (hi.abs() + lo.abs()).max(1e-300) {
            hi - lo
        } else {
            hi.abs().max(1.0) * 1e-3
        };
        let (lo, hi) = (lo - 0.05 * span, hi + 0.05 * span);
        let w = (hi - lo) / p.bins as f64;
        let mut counts = vec![0u32; p.bins];
        for v in &vals {
            let k = (((v - lo) / w) as usize).min(p.bins - 1);
            counts[k] += 1;
        }
        let top = f64::from(counts.iter().copied().max().unwrap_or(0).max(1)) * 1.1;
        let mut chart = ChartBuilder::on(area)
            .caption(&p.title, (FONT, 15))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d(lo..hi, 0.0..top)
            .map_err(|e| backend_err(&e))?;
        chart
            .configure_mesh()
            .x_desc(p.x_label.as_str())
            .y_desc("runs")
            .x_labels(5)
            .label_style((FONT, 11))
            .axis_desc_style((FONT, 12))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(|e| backend_err(&e))?;
        chart
            .draw_series(counts.iter().enumerate().map(|(k, &c)| {
                let x0 = lo + k as f64 * w;
                Rectangle::new([(x0, 0.0), (x0 + w, f64::from(c))], PALETTE[2].mix(0.7).filled())
            }))
            .map_err(|e| backend_err(&e))?;
        if let Some(l) = p.line.filter(|l| l.is_finite()) {
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(l, 0.0), (l, top)],
                    6,
                    4,
                    ShapeStyle::from(&PALETTE[1]).stroke_width(2),
                ))
                .map_err(|e| backend_err(&e))?;
        }
    }
    root.present().map_err(|e| backend_err(&e))?;
    Ok(())
}

/// Grouped bar chart: one group per category, one bar per series (`(label, values)`, one
/// value per category, `None` = no bar), values on a fixed y range, with an optional
/// horizontal dashed reference line (e.g. a 0.95 coverage target).
///
/// # Errors
/// [`PlotError::InvalidFigure`] when there is no category or series, or a series's length
/// differs from the categories'; [`PlotError::Backend`] when drawing or writing fails.
#[allow(clippy::too_many_arguments)]
pub fn render_grouped_bars_png(
    path: &Path,
    title: &str,
    y_label: &str,
    categories: &[String],
    series: &[(String, Vec<Option<f64>>)],
    y_range: (f64, f64),
    reference: Option<f64>,
    size_px: (u32, u32),
) -> Result<(), PlotError> {
    register_fonts();
    let invalid = |reason: String| PlotError::InvalidFigure { path: path.to_path_buf(), reason };
    if categories.is_empty() || series.is_empty() {
        return Err(invalid("no category or no series".into()));
    }
    if let Some((l, v)) = series.iter().find(|(_, v)| v.len() != categories.len()) {
        return Err(invalid(format!(
            "series `{l}` has {} values for {} categories",
            v.len(),
            categories.len()
        )));
    }
    let backend_err = |e: &dyn std::fmt::Display| PlotError::Backend {
        path: path.to_path_buf(),
        detail: e.to_string(),
    };
    let root = BitMapBackend::new(path, size_px).into_drawing_area();
    root.fill(&WHITE).map_err(|e| backend_err(&e))?;
    let nc = categories.len() as f64;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 20))
        .margin(10)
        .x_label_area_size(60)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..nc, y_range.0..y_range.1)
        .map_err(|e| backend_err(&e))?;
    let cats = categories.to_vec();
    chart
        .configure_mesh()
        .x_labels(categories.len() * 2 + 1)
        .x_label_formatter(&move |x: &f64| {
            let k = x.floor() as usize;
            if (x - x.floor() - 0.5).abs() < 1e-6 && k < cats.len() {
                cats[k].clone()
            } else {
                String::new()
            }
        })
        .disable_x_mesh()
        .y_desc(y_label)
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 13))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| backend_err(&e))?;
    let ns = series.len() as f64;
    let bw = 0.8 / ns;
    for (j, (label, vals)) in series.iter().enumerate() {
        let color = PALETTE[(j + 1) % PALETTE.len()];
        let lo = y_range.0;
        chart
            .draw_series(vals.iter().enumerate().filter_map(|(k, v)| {
                v.map(|v| {
                    let x0 = k as f64 + 0.1 + j as f64 * bw;
                    Rectangle::new(
                        [(x0, lo), (x0 + bw, v.clamp(y_range.0, y_range.1))],
                        color.filled(),
                    )
                })
            }))
            .map_err(|e| backend_err(&e))?
            .label(label.as_str())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], color.filled()));
    }
    if let Some(r) = reference {
        chart
            .draw_series(DashedLineSeries::new(
                vec![(0.0, r), (nc, r)],
                8,
                5,
                ShapeStyle::from(&BLACK).stroke_width(1),
            ))
            .map_err(|e| backend_err(&e))?;
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 12))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(|e| backend_err(&e))?;
    root.present().map_err(|e| backend_err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent check: the written file is a PNG (signature bytes and IHDR size match the
    /// requested geometry), so the font registration and backend worked end to end.
    #[test]
    fn png_signature_and_size() {
        let dir = std::env::temp_dir().join(format!("aeroident_plot_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("fig.png");
        let t: Vec<f64> = (0..500).map(|k| k as f64 * 0.01).collect();
        let panel = |name: &str| Panel {
            title: name.into(),
            y_label: "x".into(),
            series: vec![
                Series {
                    label: "truth".into(),
                    t_s: t.clone(),
                    values: t.iter().map(|t| t.sin()).collect(),
                    kind: LineKind::Dashed,
                },
                Series {
                    label: "estimate".into(),
                    t_s: t.clone(),
                    values: t.iter().map(|t| t.cos()).collect(),
                    kind: LineKind::Solid,
                },
            ],
        };
        render_panels_png(&path, "test", &[panel("a"), panel("b")], 640, 200).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
        let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
        assert_eq!((w, h), (640, 40 + 2 * 200));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn empty_figure_is_an_error() {
        let err = render_panels_png(Path::new("/nonexistent/x.png"), "t", &[], 100, 100);
        assert!(matches!(err, Err(PlotError::InvalidFigure { .. })));
    }
}
