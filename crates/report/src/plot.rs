//! Figures: stacked panels of time series rendered with `plotters`, to PNG and to SVG.
//!
//! One generic helper draws any number of panels that share the time axis (state tracking,
//! parameter convergence, control commands, model versus measured):
//! [`render_panels_png`](crate::plot::render_panels_png) writes a PNG,
//! [`render_panels_svg`](crate::plot::render_panels_svg) returns the same figure as SVG text
//! (for a file beside the PNG and for inlining in `report.html`). Text uses the DejaVu Sans
//! font embedded by the `dejavu` crate and registered with plotters' `ab_glyph` backend, so no
//! system font is needed.
//!
//! What each panel shows, so a converged estimate is readable:
//! - **y-range from the converged part**: the 1–99 % quantiles of every series, band and line
//!   over the last [`CONVERGED_FRACTION`](crate::plot::CONVERGED_FRACTION) of the time axis, plus each series's last value and
//!   every reference line, with a 12 % margin. A start-up transient outside that range is
//!   clipped at the frame (the line leaves and re-enters the panel), it never sets the scale.
//!   Panels of signals ([`Panel::signals`](crate::plot::Panel::signals)) use the 0.2–99.8 % quantiles of the whole record.
//! - **gaps**: a non-finite value (an estimate that does not exist yet, `None`) breaks the
//!   line; nothing is drawn as 0.
//! - **bands** ([`Band`](crate::plot::Band)): shaded areas, e.g. ±2σ around an estimate, in the colour of their
//!   series.
//! - **reference lines** ([`HLine`](crate::plot::HLine)): horizontal lines across the panel (published value,
//!   truth).
//! - **legend outside the data**: in a column to the right of each panel.
//! - **ticks**: labels with as many decimals as the tick step needs, never `-0`; the label
//!   area is as wide as the longest label.
//! - **numerical noise**: a panel whose every value is below [`ZERO_THRESHOLD`](crate::plot::ZERO_THRESHOLD) in magnitude
//!   (e.g. 1e-27 round-off of a parameter that is exactly 0) is drawn as a flat line at 0 on
//!   ±1, and its caption says so.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};
use std::path::{Path, PathBuf};
use std::sync::Once;

/// Font family name under which DejaVu Sans is registered.
const FONT: &str = "sans-serif";

/// The fraction of the time axis, at its end, whose values set a panel's y-range.
pub const CONVERGED_FRACTION: f64 = 0.6;

pub use aeroident_pipelines::metrics::ZERO_THRESHOLD;

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

/// One time series: `values[k]` at `t_s[k]` (s). Non-finite values are gaps, not drawn.
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

/// A shaded band `lo[k]…hi[k]` at `t_s[k]` (e.g. estimate ± 2σ), drawn in the colour of series
/// `series` of its panel; non-finite bounds are gaps.
#[derive(Debug, Clone, Default)]
pub struct Band {
    /// Legend label (e.g. `±2σ`).
    pub label: String,
    /// Index of the series whose colour the band takes.
    pub series: usize,
    /// Times, s.
    pub t_s: Vec<f64>,
    /// Lower bound.
    pub lo: Vec<f64>,
    /// Upper bound.
    pub hi: Vec<f64>,
}

/// A horizontal reference line across the panel (a published value, a constant truth).
#[derive(Debug, Clone, PartialEq)]
pub struct HLine {
    /// Legend label.
    pub label: String,
    /// Its value, units of the panel.
    pub value: f64,
}

/// One panel (a chart) of a figure: a y-axis label, its series, bands and reference lines.
#[derive(Debug, Clone, Default)]
pub struct Panel {
    /// Panel caption.
    pub title: String,
    /// Y-axis label with unit, e.g. `"x"` or `"a1 (1/s²)"`.
    pub y_label: String,
    /// Series drawn in this panel.
    pub series: Vec<Series>,
    /// Shaded bands, drawn under the series.
    pub bands: Vec<Band>,
    /// Horizontal reference lines.
    pub hlines: Vec<HLine>,
    /// The panel shows signals over the whole record (measured vs model, residuals), not
    /// converging estimates: the y-range covers the whole time axis and lines are 1 px.
    pub signals: bool,
}

/// Most points drawn per series; longer series are decimated by a fixed stride.
const MAX_POINTS: usize = 4000;

static REGISTER: Once = Once::new();

pub(crate) fn register_fonts() {
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

/// Colours of reference lines (distinct from the series palette's first entries).
const LINE_PALETTE: [RGBColor; 3] =
    [RGBColor(0, 140, 70), RGBColor(200, 120, 0), RGBColor(120, 120, 120)];

/// Series colour `i` of a panel (black, red, blue, green, purple, orange, repeating).
fn series_color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// The `q`-quantile (0…1) of sorted `v` (nearest rank).
fn quantile(v: &[f64], q: f64) -> f64 {
    let k = ((v.len() - 1) as f64 * q).round() as usize;
    v[k.min(v.len() - 1)]
}

/// Whether every finite value of the panel is numerical noise around 0 (module doc); `false`
/// for a panel without any finite value.
pub fn is_noise_panel(panel: &Panel) -> bool {
    let mut any = false;
    let all_small = panel
        .series
        .iter()
        .flat_map(|s| s.values.iter())
        .chain(panel.bands.iter().flat_map(|b| b.lo.iter().chain(b.hi.iter())))
        .chain(panel.hlines.iter().map(|h| &h.value))
        .filter(|v| v.is_finite())
        .all(|v| {
            any = true;
            v.abs() < ZERO_THRESHOLD
        });
    any && all_small
}

/// The y-range of a panel over the time axis `t_range` (module doc).
pub fn y_range(panel: &Panel, t_range: (f64, f64)) -> (f64, f64) {
    if is_noise_panel(panel) {
        return (-1.0, 1.0);
    }
    let t_from = if panel.signals {
        f64::NEG_INFINITY
    } else {
        t_range.0 + (1.0 - CONVERGED_FRACTION) * (t_range.1 - t_range.0)
    };
    let window = |t: &[f64], v: &[f64], out: &mut Vec<f64>| {
        out.extend(
            t.iter().zip(v).filter(|(t, v)| **t >= t_from && v.is_finite()).map(|(_, v)| *v),
        );
    };
    let mut vals = Vec::new();
    for s in &panel.series {
        window(&s.t_s, &s.values, &mut vals);
    }
    for b in &panel.bands {
        window(&b.t_s, &b.lo, &mut vals);
        window(&b.t_s, &b.hi, &mut vals);
    }
    if vals.is_empty() {
        // Nothing in the converged part: every finite value counts.
        vals.extend(panel.series.iter().flat_map(|s| s.values.iter().copied()));
        vals.retain(|v| v.is_finite());
    }
    let mut must: Vec<f64> =
        panel.hlines.iter().map(|h| h.value).filter(|v| v.is_finite()).collect();
    must.extend(panel.series.iter().filter_map(|s| s.values.iter().rev().find(|v| v.is_finite())));
    vals.sort_by(f64::total_cmp);
    let (mut lo, mut hi) = if vals.is_empty() {
        (f64::INFINITY, f64::NEG_INFINITY)
    } else {
        let q = if panel.signals { 0.002 } else { 0.01 };
        (quantile(&vals, q), quantile(&vals, 1.0 - q))
    };
    for v in must {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (-1.0, 1.0);
    }
    let mid = 0.5 * (lo + hi);
    let span = (hi - lo).max(0.02 * mid.abs()).max(ZERO_THRESHOLD);
    let (lo, hi) = (mid - 0.5 * span, mid + 0.5 * span);
    (lo - 0.12 * span, hi + 0.12 * span)
}

/// Tick label of `x` on an axis spanning `span`: decimals as the tick step (≈ span/5) needs,
/// e-notation for very large or very small magnitudes, never `-0`.
pub fn tick_label(x: f64, span: f64, magnitude: f64) -> String {
    let step = (span / 5.0).abs();
    if !(step > 0.0 && step.is_finite()) {
        return format!("{}", x + 0.0);
    }
    // Values within a millionth of a step of 0 are 0 (no "-0.000", no "1e-17").
    let x = if x.abs() < 1e-6 * step { 0.0 } else { x };
    if !(1e-3..1e5).contains(&magnitude) {
        let digits = ((magnitude / step).log10().ceil().max(0.0) as usize + 1).min(6);
        if x == 0.0 {
            return "0".into();
        }
        return format!("{x:.digits$e}", digits = digits.saturating_sub(1).max(1));
    }
    let decimals = (-step.log10().floor()).clamp(0.0, 9.0) as usize;
    let s = format!("{x:.decimals$}");
    if s.trim_start_matches('-').chars().all(|c| c == '0' || c == '.') { "0".into() } else { s }
}

/// Splits the points into polylines: a non-finite value ends one, and the parts outside
/// `lo…hi` are cut at the boundary (linear interpolation), so nothing is drawn outside the
/// frame and nothing is invented.
fn clip_polylines(t: &[f64], v: &[f64], lo: f64, hi: f64, stride: usize) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let mut prev: Option<(f64, f64)> = None;
    let inside = |y: f64| (lo..=hi).contains(&y);
    let cross = |a: (f64, f64), b: (f64, f64), y: f64| {
        let f = (y - a.1) / (b.1 - a.1);
        (a.0 + f * (b.0 - a.0), y)
    };
    let n = t.len().min(v.len());
    let idx = (0..n)
        .step_by(stride.max(1))
        .chain((n > 0 && !(n - 1).is_multiple_of(stride.max(1))).then_some(n - 1));
    for k in idx {
        let p = (t[k], v[k]);
        if !(p.0.is_finite() && p.1.is_finite()) {
            if cur.len() > 1 {
                out.push(std::mem::take(&mut cur));
            }
            cur.clear();
            prev = None;
            continue;
        }
        match prev {
            None => {
                if inside(p.1) {
                    cur.push(p);
                }
            }
            Some(a) => {
                let (ia, ib) = (inside(a.1), inside(p.1));
                if ia && ib {
                    cur.push(p);
                } else if ia && !ib {
                    cur.push(cross(a, p, if p.1 > hi { hi } else { lo }));
                    if cur.len() > 1 {
                        out.push(std::mem::take(&mut cur));
                    }
                    cur.clear();
                } else if !ia && ib {
                    cur.push(cross(a, p, if a.1 > hi { hi } else { lo }));
                    cur.push(p);
                } else if (a.1 > hi && p.1 < lo) || (a.1 < lo && p.1 > hi) {
                    // Passes straight through the frame.
                    let (e, x) = if a.1 > hi { (hi, lo) } else { (lo, hi) };
                    out.push(vec![cross(a, p, e), cross(a, p, x)]);
                }
            }
        }
        prev = Some(p);
    }
    if cur.len() > 1 {
        out.push(cur);
    }
    out
}

/// The closed outline of each stretch where both bounds are finite, clamped to `lo…hi`.
fn band_polygons(b: &Band, lo: f64, hi: f64, stride: usize) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    let mut upper: Vec<(f64, f64)> = Vec::new();
    let mut lower: Vec<(f64, f64)> = Vec::new();
    let n = b.t_s.len().min(b.lo.len()).min(b.hi.len());
    let mut flush = |upper: &mut Vec<(f64, f64)>, lower: &mut Vec<(f64, f64)>| {
        if upper.len() > 1 {
            let mut poly = std::mem::take(upper);
            poly.extend(lower.drain(..).rev());
            out.push(poly);
        }
        upper.clear();
        lower.clear();
    };
    let idx = (0..n)
        .step_by(stride.max(1))
        .chain((n > 0 && !(n - 1).is_multiple_of(stride.max(1))).then_some(n - 1));
    for k in idx {
        let (t, l, h) = (b.t_s[k], b.lo[k], b.hi[k]);
        if t.is_finite() && l.is_finite() && h.is_finite() {
            upper.push((t, h.clamp(lo, hi)));
            lower.push((t, l.clamp(lo, hi)));
        } else {
            flush(&mut upper, &mut lower);
        }
    }
    flush(&mut upper, &mut lower);
    out
}

/// Legend entries of a panel: (label, colour, kind) with kind 0 = solid line, 1 = dashed line,
/// 2 = band.
fn legend_entries(panel: &Panel) -> Vec<(String, RGBColor, u8)> {
    let mut v = Vec::new();
    for (i, s) in panel.series.iter().enumerate() {
        v.push((s.label.clone(), series_color(i), u8::from(s.kind == LineKind::Dashed)));
    }
    for b in &panel.bands {
        v.push((b.label.clone(), series_color(b.series), 2));
    }
    for (i, h) in panel.hlines.iter().enumerate() {
        v.push((h.label.clone(), LINE_PALETTE[i % LINE_PALETTE.len()], 1));
    }
    v
}

fn validate(path: &Path, panels: &[Panel]) -> Result<(), PlotError> {
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
        for b in &p.bands {
            if b.t_s.len() != b.lo.len() || b.t_s.len() != b.hi.len() {
                return Err(invalid(format!(
                    "band `{}` in panel `{}` has {} times but {}/{} bounds",
                    b.label,
                    p.title,
                    b.t_s.len(),
                    b.lo.len(),
                    b.hi.len()
                )));
            }
        }
    }
    Ok(())
}

/// Draws the panels on `root` (any plotters backend): one shared time axis over every panel,
/// one legend column as wide as the longest label needs.
fn draw_panels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    panels: &[Panel],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(msg)?;
    let root = root.titled(title, (FONT, 22).into_font().style(FontStyle::Bold)).map_err(msg)?;
    let areas = root.split_evenly((panels.len(), 1));
    let t_range = time_range(panels);
    let legend_w = legend_width(panels);
    for (area, panel) in areas.iter().zip(panels) {
        draw_panel(area, panel, t_range, legend_w)?;
    }
    root.present().map_err(msg)?;
    Ok(())
}

/// A plotters error as the message [`PlotError::Backend`] carries.
fn msg(x: impl std::fmt::Display) -> String {
    x.to_string()
}

/// A panel's chart: time (s) against the panel's quantity.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The time range shared by all panels: the finite times of every series and band, or
/// `0..1` when there is none (or a single instant).
fn time_range(panels: &[Panel]) -> (f64, f64) {
    let (t_min, t_max) = panels
        .iter()
        .flat_map(|p| p.series.iter().map(|s| &s.t_s).chain(p.bands.iter().map(|b| &b.t_s)))
        .flat_map(|t| t.iter().copied())
        .filter(|t| t.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| (a.min(t), b.max(t)));
    if t_min < t_max { (t_min, t_max) } else { (0.0, 1.0) }
}

/// The legend column's width, px: room for the longest label of any panel (about 8 px a
/// character after a 34 px key), within 90–260 px.
fn legend_width(panels: &[Panel]) -> u32 {
    let legend_chars = panels
        .iter()
        .flat_map(legend_entries)
        .map(|(l, _, _)| l.chars().count())
        .max()
        .unwrap_or(0);
    (34 + 8 * legend_chars as u32).clamp(90, 260)
}

/// Draws one panel in `area`: the chart (bands, then reference lines, then series, so lines
/// stay visible over the shading) and its legend in a column `legend_w` px wide on the right.
/// A noise panel is drawn as 0 (module doc).
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    t_range: (f64, f64),
    legend_w: u32,
) -> Result<(), String> {
    let noise = is_noise_panel(panel);
    let y_lims = y_range(panel, t_range);
    let (w, _) = area.dim_in_pixel();
    let (chart_area, legend_area) = area.split_horizontally(w.saturating_sub(legend_w));
    let mut chart = build_chart(&chart_area, panel, noise, t_range, y_lims)?;
    draw_bands(&mut chart, panel, y_lims)?;
    draw_hlines(&mut chart, panel, noise, t_range, y_lims)?;
    draw_series_lines(&mut chart, panel, noise, y_lims)?;
    draw_panel_legend(&legend_area, panel)
}

/// The panel's chart on `chart_area` with its caption and mesh drawn; the y-label area is as
/// wide as the widest tick label needs.
fn build_chart<'a, DB: DrawingBackend>(
    chart_area: &'a DrawingArea<DB, Shift>,
    panel: &Panel,
    noise: bool,
    (t_min, t_max): (f64, f64),
    (y_lo, y_hi): (f64, f64),
) -> Result<Chart<'a, DB>, String> {
    let y_span = y_hi - y_lo;
    let y_mag = y_lo.abs().max(y_hi.abs());
    let y_fmt = move |y: &f64| tick_label(*y, y_span, y_mag);
    let x_span = t_max - t_min;
    let x_mag = t_min.abs().max(t_max.abs());
    let x_fmt = move |x: &f64| tick_label(*x, x_span, x_mag);
    let widest = [y_lo, y_hi, 0.5 * (y_lo + y_hi)]
        .iter()
        .map(|y| y_fmt(y).chars().count())
        .max()
        .unwrap_or(4) as u32;
    let caption = if noise {
        format!("{}  (|values| < {ZERO_THRESHOLD:e} everywhere: drawn as 0)", panel.title)
    } else {
        panel.title.clone()
    };
    let mut chart = ChartBuilder::on(chart_area)
        .caption(caption, (FONT, 16))
        .margin(8)
        .margin_right(16)
        .x_label_area_size(36)
        .y_label_area_size(30 + 8 * widest)
        .build_cartesian_2d(t_min..t_max, y_lo..y_hi)
        .map_err(msg)?;
    chart
        .configure_mesh()
        .x_desc("t (s)")
        .y_desc(panel.y_label.as_str())
        .x_labels(10)
        .y_labels(6)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()
        .map_err(msg)?;
    Ok(chart)
}

/// The panel's bands, shaded in their series's colour and clipped to the y-range.
fn draw_bands<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    panel: &Panel,
    (y_lo, y_hi): (f64, f64),
) -> Result<(), String> {
    for b in &panel.bands {
        let color = series_color(b.series);
        let stride = b.t_s.len().div_ceil(MAX_POINTS).max(1);
        for poly in band_polygons(b, y_lo, y_hi, stride) {
            chart
                .draw_series(std::iter::once(Polygon::new(poly, color.mix(0.14).filled())))
                .map_err(msg)?;
        }
    }
    Ok(())
}

/// The panel's horizontal reference lines (dashed) that fall in the y-range; at 0 in a noise
/// panel, whose values are drawn as 0.
fn draw_hlines<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    panel: &Panel,
    noise: bool,
    (t_min, t_max): (f64, f64),
    (y_lo, y_hi): (f64, f64),
) -> Result<(), String> {
    for (i, h) in panel.hlines.iter().enumerate() {
        let color = LINE_PALETTE[i % LINE_PALETTE.len()];
        let v = if noise { 0.0 } else { h.value };
        if (y_lo..=y_hi).contains(&v) {
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(t_min, v), (t_max, v)],
                    10,
                    6,
                    ShapeStyle::from(&color).stroke_width(2),
                ))
                .map_err(msg)?;
        }
    }
    Ok(())
}

/// The panel's series, thinned to at most [`MAX_POINTS`] points and clipped to the y-range
/// (a noise panel's finite values drawn as 0).
fn draw_series_lines<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    panel: &Panel,
    noise: bool,
    (y_lo, y_hi): (f64, f64),
) -> Result<(), String> {
    for (i, s) in panel.series.iter().enumerate() {
        let color = series_color(i);
        let stride = s.t_s.len().div_ceil(MAX_POINTS).max(1);
        let values: Vec<f64> = if noise {
            s.values.iter().map(|v| if v.is_finite() { 0.0 } else { f64::NAN }).collect()
        } else {
            s.values.clone()
        };
        // Estimates 2 px, signals and dashed lines 1 px; plotters joins thick polylines
        // with miters, which spike where a signal reverses sharply, so no thicker.
        let width = if s.kind == LineKind::Solid && !panel.signals { 2 } else { 1 };
        let style = ShapeStyle::from(&color).stroke_width(width);
        for line in clip_polylines(&s.t_s, &values, y_lo, y_hi, stride) {
            match s.kind {
                LineKind::Solid => chart.draw_series(LineSeries::new(line, style)),
                LineKind::Dashed => chart.draw_series(DashedLineSeries::new(line, 8, 5, style)),
            }
            .map_err(msg)?;
        }
    }
    Ok(())
}

/// The legend, in its own column right of the chart: a key (band swatch, dashed or solid
/// line) and the label of each entry.
fn draw_panel_legend<DB: DrawingBackend>(
    legend_area: &DrawingArea<DB, Shift>,
    panel: &Panel,
) -> Result<(), String> {
    let font = (FONT, 13).into_font().color(&BLACK);
    for (k, (label, color, kind)) in legend_entries(panel).iter().enumerate() {
        let y = 34 + 20 * k as i32;
        let x = 6;
        match kind {
            2 => legend_area
                .draw(&Rectangle::new([(x, y - 6), (x + 22, y + 6)], color.mix(0.25).filled()))
                .map_err(msg)?,
            1 => {
                for seg in [(x, x + 6), (x + 9, x + 15), (x + 18, x + 22)] {
                    legend_area
                        .draw(&PathElement::new(
                            vec![(seg.0, y), (seg.1, y)],
                            color.stroke_width(2),
                        ))
                        .map_err(msg)?;
                }
            }
            _ => legend_area
                .draw(&PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(2)))
                .map_err(msg)?,
        }
        legend_area.draw(&Text::new(label.clone(), (x + 28, y - 8), font.clone())).map_err(msg)?;
    }
    Ok(())
}

/// Renders `panels` stacked vertically into a PNG at `path`, `width_px` wide and
/// `panel_height_px` per panel, with a figure `title` and a shared x label (time, s); what
/// each panel shows is in the module doc.
///
/// # Errors
/// [`PlotError::InvalidFigure`] when there is no panel, or a series's or band's lengths
/// differ; [`PlotError::Backend`] when drawing or writing the file fails.
pub fn render_panels_png(
    path: &Path,
    title: &str,
    panels: &[Panel],
    width_px: u32,
    panel_height_px: u32,
) -> Result<(), PlotError> {
    register_fonts();
    validate(path, panels)?;
    let height = 40 + panel_height_px * panels.len() as u32;
    let root = BitMapBackend::new(path, (width_px, height)).into_drawing_area();
    draw_panels(&root, title, panels)
        .map_err(|detail| PlotError::Backend { path: path.to_path_buf(), detail })
}

/// [`render_panels_png`] as SVG text (the same layout); `name` only names the figure in
/// errors.
///
/// # Errors
/// As [`render_panels_png`].
pub fn render_panels_svg(
    name: &str,
    title: &str,
    panels: &[Panel],
    width_px: u32,
    panel_height_px: u32,
) -> Result<String, PlotError> {
    register_fonts();
    let path = Path::new(name);
    validate(path, panels)?;
    let height = 40 + panel_height_px * panels.len() as u32;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width_px, height)).into_drawing_area();
        draw_panels(&root, title, panels)
            .map_err(|detail| PlotError::Backend { path: path.to_path_buf(), detail })?;
    }
    Ok(svg)
}

/// One histogram panel: the values binned into `bins` equal bins over their range (widened to
/// include `line`), with a vertical dashed line at `line` (e.g. the truth) labelled
/// `line_label` in the legend.
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
    /// Legend label of the line (e.g. `truth`).
    pub line_label: String,
}

/// Renders histogram panels in a grid of `columns` into a PNG at `path`, each cell
/// `cell_px` = (width, height): the counts as bars, the line dashed, a legend in a column
/// right of each histogram (outside the data), tick labels as [`tick_label`] (never `-0`).
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
    validate_histograms(path, panels, columns)?;
    let rows = panels.len().div_ceil(columns);
    let size = (cell_px.0 * columns as u32, 40 + cell_px.1 * rows as u32);
    let root = BitMapBackend::new(path, size).into_drawing_area();
    draw_histograms(&root, title, panels, columns)
        .map_err(|detail| PlotError::Backend { path: path.to_path_buf(), detail })
}

/// [`render_histograms_png`] as SVG text (the same layout); `name` only names the figure in
/// errors.
///
/// # Errors
/// As [`render_histograms_png`].
pub fn render_histograms_svg(
    name: &str,
    title: &str,
    panels: &[HistogramPanel],
    columns: usize,
    cell_px: (u32, u32),
) -> Result<String, PlotError> {
    register_fonts();
    let path = Path::new(name);
    validate_histograms(path, panels, columns)?;
    let rows = panels.len().div_ceil(columns);
    let size = (cell_px.0 * columns as u32, 40 + cell_px.1 * rows as u32);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw_histograms(&root, title, panels, columns)
            .map_err(|detail| PlotError::Backend { path: path.to_path_buf(), detail })?;
    }
    Ok(svg)
}

fn validate_histograms(
    path: &Path,
    panels: &[HistogramPanel],
    columns: usize,
) -> Result<(), PlotError> {
    let invalid = |reason: String| PlotError::InvalidFigure { path: path.to_path_buf(), reason };
    if panels.is_empty() || columns == 0 {
        return Err(invalid("no panel to draw (or 0 columns)".into()));
    }
    if let Some(p) = panels.iter().find(|p| p.bins == 0) {
        return Err(invalid(format!("panel `{}` has 0 bins", p.title)));
    }
    Ok(())
}

/// Bin edges and counts of a histogram panel: (lo, bin width, counts).
fn histogram_bins(p: &HistogramPanel) -> (f64, f64, Vec<u32>) {
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
    (lo, w, counts)
}

/// Draws a legend of (label, colour, kind: 0 line, 1 dashed, 2 box filled at 70 % as the
/// histogram bars, 3 box filled solid as the grouped bars) at the top of `area`.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, RGBColor, u8)],
    font_px: u32,
    top_px: i32,
) -> Result<(), String> {
    let e = |e: &dyn std::fmt::Display| e.to_string();
    let font = (FONT, font_px).into_font().color(&BLACK);
    for (k, (label, color, kind)) in entries.iter().enumerate() {
        let y = top_px + 20 * k as i32;
        let x = 6;
        match kind {
            2 => area
                .draw(&Rectangle::new([(x, y - 6), (x + 22, y + 6)], color.mix(0.7).filled()))
                .map_err(|x| e(&x))?,
            3 => area
                .draw(&Rectangle::new([(x, y - 6), (x + 22, y + 6)], color.filled()))
                .map_err(|x| e(&x))?,
            1 => {
                for seg in [(x, x + 6), (x + 9, x + 15), (x + 18, x + 22)] {
                    area.draw(&PathElement::new(
                        vec![(seg.0, y), (seg.1, y)],
                        color.stroke_width(2),
                    ))
                    .map_err(|x| e(&x))?;
                }
            }
            _ => area
                .draw(&PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(2)))
                .map_err(|x| e(&x))?,
        }
        area.draw(&Text::new(label.clone(), (x + 28, y - 7), font.clone())).map_err(|x| e(&x))?;
    }
    Ok(())
}

fn draw_histograms<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    panels: &[HistogramPanel],
    columns: usize,
) -> Result<(), String> {
    let e = |e: &dyn std::fmt::Display| e.to_string();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let root =
        root.titled(title, (FONT, 22).into_font().style(FontStyle::Bold)).map_err(|x| e(&x))?;
    let rows = panels.len().div_ceil(columns);
    let areas = root.split_evenly((rows, columns));
    let bar_color = PALETTE[2];
    let line_color = PALETTE[1];
    for (area, p) in areas.iter().zip(panels) {
        let (lo, w, counts) = histogram_bins(p);
        let hi = lo + w * p.bins as f64;
        let top = f64::from(counts.iter().copied().max().unwrap_or(0).max(1)) * 1.1;
        let (aw, _) = area.dim_in_pixel();
        let legend_w = 92;
        let (chart_area, legend_area) = area.split_horizontally(aw.saturating_sub(legend_w));
        let (x_span, x_mag) = (hi - lo, lo.abs().max(hi.abs()));
        let x_fmt = move |x: &f64| tick_label(*x, x_span, x_mag);
        // Counts are whole runs: only integer ticks are labelled.
        let y_fmt = |y: &f64| {
            if (y - y.round()).abs() < 1e-9 {
                format!("{:.0}", y.round() + 0.0)
            } else {
                String::new()
            }
        };
        let mut chart = ChartBuilder::on(&chart_area)
            .caption(&p.title, (FONT, 15))
            .margin(8)
            .x_label_area_size(34)
            .y_label_area_size(40)
            .build_cartesian_2d(lo..hi, 0.0..top)
            .map_err(|x| e(&x))?;
        chart
            .configure_mesh()
            .x_desc(p.x_label.as_str())
            .y_desc("runs")
            .x_labels(5)
            .y_labels(((top as usize) + 1).min(6))
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .label_style((FONT, 11))
            .axis_desc_style((FONT, 12))
            .light_line_style(TRANSPARENT)
            .bold_line_style(RGBColor(215, 215, 215))
            .draw()
            .map_err(|x| e(&x))?;
        chart
            .draw_series(counts.iter().enumerate().map(|(k, &c)| {
                let x0 = lo + k as f64 * w;
                Rectangle::new([(x0, 0.0), (x0 + w, f64::from(c))], bar_color.mix(0.7).filled())
            }))
            .map_err(|x| e(&x))?;
        let mut legend = vec![("estimates".to_string(), bar_color, 2u8)];
        if let Some(l) = p.line.filter(|l| l.is_finite()) {
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(l, 0.0), (l, top)],
                    6,
                    4,
                    ShapeStyle::from(&line_color).stroke_width(2),
                ))
                .map_err(|x| e(&x))?;
            legend.push((p.line_label.clone(), line_color, 1));
        }
        draw_legend(&legend_area, &legend, 11, 34)?;
    }
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

/// Grouped bar chart: one group per category, one bar per series (`(label, values)`, one
/// value per category, `None` = no bar), values on a fixed y range, with an optional
/// horizontal dashed reference line (e.g. a 0.95 coverage target); the legend in a column
/// right of the chart (outside the bars), y tick labels as [`tick_label`].
#[derive(Debug, Clone, PartialEq)]
pub struct GroupedBars {
    /// Figure title.
    pub title: String,
    /// Y-axis label with unit.
    pub y_label: String,
    /// Category names under the groups.
    pub categories: Vec<String>,
    /// (label, one value per category).
    pub series: Vec<(String, Vec<Option<f64>>)>,
    /// Fixed y range.
    pub y_range: (f64, f64),
    /// A dashed horizontal line and its legend label.
    pub reference: Option<(f64, String)>,
}

impl GroupedBars {
    fn validate(&self, path: &Path) -> Result<(), PlotError> {
        let invalid =
            |reason: String| PlotError::InvalidFigure { path: path.to_path_buf(), reason };
        if self.categories.is_empty() || self.series.is_empty() {
            return Err(invalid("no category or no series".into()));
        }
        if let Some((l, v)) = self.series.iter().find(|(_, v)| v.len() != self.categories.len()) {
            return Err(invalid(format!(
                "series `{l}` has {} values for {} categories",
                v.len(),
                self.categories.len()
            )));
        }
        Ok(())
    }

    /// Renders the chart into a PNG at `path`, `size_px` = (width, height).
    ///
    /// # Errors
    /// [`PlotError::InvalidFigure`] when there is no category or series, or a series's length
    /// differs from the categories'; [`PlotError::Backend`] when drawing or writing fails.
    pub fn render_png(&self, path: &Path, size_px: (u32, u32)) -> Result<(), PlotError> {
        register_fonts();
        self.validate(path)?;
        let root = BitMapBackend::new(path, size_px).into_drawing_area();
        self.draw(&root).map_err(|detail| PlotError::Backend { path: path.to_path_buf(), detail })
    }

    /// The same chart as SVG text; `name` only names the figure in errors.
    ///
    /// # Errors
    /// As [`GroupedBars::render_png`].
    pub fn render_svg(&self, name: &str, size_px: (u32, u32)) -> Result<String, PlotError> {
        register_fonts();
        let path = Path::new(name);
        self.validate(path)?;
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, size_px).into_drawing_area();
            self.draw(&root)
                .map_err(|detail| PlotError::Backend { path: path.to_path_buf(), detail })?;
        }
        Ok(svg)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let e = |e: &dyn std::fmt::Display| e.to_string();
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let root = root
            .titled(&self.title, (FONT, 20).into_font().style(FontStyle::Bold))
            .map_err(|x| e(&x))?;
        let legend_chars = self
            .series
            .iter()
            .map(|(l, _)| l.chars().count())
            .chain(self.reference.iter().map(|(_, l)| l.chars().count()))
            .max()
            .unwrap_or(0);
        let legend_w = (40 + 8 * legend_chars as u32).clamp(90, 260);
        let (w, _) = root.dim_in_pixel();
        let (chart_area, legend_area) = root.split_horizontally(w.saturating_sub(legend_w));
        let nc = self.categories.len() as f64;
        let (y0, y1) = self.y_range;
        let (y_span, y_mag) = (y1 - y0, y0.abs().max(y1.abs()));
        let y_fmt = move |y: &f64| tick_label(*y, y_span, y_mag);
        let mut chart = ChartBuilder::on(&chart_area)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(56)
            .build_cartesian_2d(0.0..nc, y0..y1)
            .map_err(|x| e(&x))?;
        let cats = self.categories.clone();
        chart
            .configure_mesh()
            .x_labels(self.categories.len() * 2 + 1)
            .x_label_formatter(&move |x: &f64| {
                let k = x.floor() as usize;
                if (x - x.floor() - 0.5).abs() < 1e-6 && k < cats.len() {
                    cats[k].clone()
                } else {
                    String::new()
                }
            })
            .y_label_formatter(&y_fmt)
            .y_labels(8)
            .disable_x_mesh()
            .y_desc(self.y_label.as_str())
            .label_style((FONT, 12))
            .axis_desc_style((FONT, 13))
            .light_line_style(TRANSPARENT)
            .bold_line_style(RGBColor(215, 215, 215))
            .draw()
            .map_err(|x| e(&x))?;
        let ns = self.series.len() as f64;
        let bw = 0.8 / ns;
        let mut legend = Vec::new();
        for (j, (label, vals)) in self.series.iter().enumerate() {
            let color = PALETTE[(j + 1) % PALETTE.len()];
            chart
                .draw_series(vals.iter().enumerate().filter_map(|(k, v)| {
                    v.map(|v| {
                        let x0 = k as f64 + 0.1 + j as f64 * bw;
                        Rectangle::new([(x0, y0), (x0 + bw, v.clamp(y0, y1))], color.filled())
                    })
                }))
                .map_err(|x| e(&x))?;
            legend.push((label.clone(), color, 3u8));
        }
        if let Some((r, label)) = &self.reference {
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(0.0, *r), (nc, *r)],
                    8,
                    5,
                    ShapeStyle::from(&BLACK).stroke_width(1),
                ))
                .map_err(|x| e(&x))?;
            legend.push((label.clone(), BLACK, 1));
        }
        draw_legend(&legend_area, &legend, 12, 24)?;
        root.present().map_err(|x| e(&x))?;
        Ok(())
    }
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
            ..Default::default()
        };
        render_panels_png(&path, "test", &[panel("a"), panel("b")], 640, 200).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
        let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
        assert_eq!((w, h), (640, 40 + 2 * 200));
        std::fs::remove_dir_all(&dir).ok();
    }

    fn series(t: &[f64], v: Vec<f64>) -> Series {
        Series { label: "s".into(), t_s: t.to_vec(), values: v, kind: LineKind::Solid }
    }

    /// A start-up transient of ±1e6 in the first 10 % does not set the range: the range is
    /// that of the converged value 2.0 ± 0.01 (with margin) and includes the reference line.
    #[test]
    fn y_range_is_set_by_the_converged_part_not_the_transient() {
        let t: Vec<f64> = (0..1000).map(|k| k as f64 * 0.01).collect();
        let v: Vec<f64> = t
            .iter()
            .map(|&t| if t < 1.0 { 1e6 * (40.0 * t).sin() } else { 2.0 + 0.01 * (3.0 * t).sin() })
            .collect();
        let p = Panel {
            series: vec![series(&t, v)],
            hlines: vec![HLine { label: "ref".into(), value: 2.05 }],
            ..Default::default()
        };
        let (lo, hi) = y_range(&p, (0.0, 9.99));
        assert!(lo > 1.9 && lo < 1.99, "{lo}");
        assert!(hi > 2.05 && hi < 2.1, "{hi}");
        // The same as signals (measured data): the whole record sets the range.
        let p = Panel { signals: true, ..p };
        let (lo, hi) = y_range(&p, (0.0, 9.99));
        assert!(lo < -5e5 && hi > 5e5, "{lo} {hi}");
        // Round-off noise is a flat 0 on ±1.
        let p = Panel {
            series: vec![series(&t, t.iter().map(|t| 1e-27 * t.sin()).collect())],
            ..Default::default()
        };
        assert!(is_noise_panel(&p));
        assert_eq!(y_range(&p, (0.0, 9.99)), (-1.0, 1.0));
        // All gaps: not noise, a default range.
        let p = Panel { series: vec![series(&t, vec![f64::NAN; t.len()])], ..Default::default() };
        assert!(!is_noise_panel(&p));
        assert_eq!(y_range(&p, (0.0, 9.99)), (-1.0, 1.0));
    }

    #[test]
    fn tick_labels_have_no_negative_zero_and_enough_decimals() {
        assert_eq!(tick_label(-1e-17, 0.5, 1.0), "0");
        assert_eq!(tick_label(-0.0, 10.0, 10.0), "0");
        assert_eq!(tick_label(-0.02, 0.1, 1.0), "-0.02");
        assert_eq!(tick_label(10.0, 30.0, 30.0), "10");
        assert_eq!(tick_label(2.5, 4.0, 5.0), "2.5");
        assert_eq!(tick_label(-27.25, 2.0, 30.0), "-27.2");
        assert!(tick_label(2e-5, 1e-4, 1e-4).contains('e'));
    }

    /// A `None` (NaN) breaks the line; points outside the range are cut at the boundary by
    /// linear interpolation.
    #[test]
    fn polylines_break_at_gaps_and_clip_at_the_frame() {
        let t = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let v = [f64::NAN, 0.0, 0.5, f64::NAN, 0.0, 4.0];
        let lines = clip_polylines(&t, &v, -1.0, 1.0, 1);
        assert_eq!(lines, vec![vec![(1.0, 0.0), (2.0, 0.5)], vec![(4.0, 0.0), (4.25, 1.0)]]);
        // Straight through the frame from above to below.
        let lines = clip_polylines(&[0.0, 1.0], &[3.0, -3.0], -1.0, 1.0, 1);
        assert_eq!(lines.len(), 1);
        assert!((lines[0][0].0 - 1.0 / 3.0).abs() < 1e-12 && lines[0][0].1 == 1.0);
        assert!((lines[0][1].0 - 2.0 / 3.0).abs() < 1e-12 && lines[0][1].1 == -1.0);
        // A band stops where σ does not exist.
        let b = Band {
            label: "±2σ".into(),
            series: 0,
            t_s: t.to_vec(),
            lo: vec![f64::NAN, -1.0, -1.0, -1.0, f64::NAN, f64::NAN],
            hi: vec![f64::NAN, 1.0, 2.0, 1.0, f64::NAN, f64::NAN],
        };
        let polys = band_polygons(&b, -5.0, 1.5, 1);
        assert_eq!(
            polys,
            vec![vec![(1.0, 1.0), (2.0, 1.5), (3.0, 1.0), (3.0, -1.0), (2.0, -1.0), (1.0, -1.0)]]
        );
    }

    /// The SVG has the requested size, the title, the legend labels and a filled band.
    #[test]
    fn svg_has_title_legend_and_band() {
        let t: Vec<f64> = (0..200).map(|k| k as f64 * 0.05).collect();
        let p = Panel {
            title: "Cm_alpha".into(),
            y_label: "Cm_alpha (1/rad)".into(),
            series: vec![series(&t, t.iter().map(|t| -1.0 + 0.1 / (1.0 + t)).collect())],
            bands: vec![Band {
                label: "±2σ".into(),
                series: 0,
                t_s: t.clone(),
                lo: t.iter().map(|t| -1.1 + 0.1 / (1.0 + t)).collect(),
                hi: t.iter().map(|t| -0.9 + 0.1 / (1.0 + t)).collect(),
            }],
            hlines: vec![HLine { label: "reference".into(), value: -1.0 }],
            signals: false,
        };
        let svg = render_panels_svg("fig.svg", "a title", &[p], 800, 250).unwrap();
        assert!(
            svg.starts_with("<svg")
                && svg.contains("width=\"800\"")
                && svg.contains("height=\"290\""),
            "{}",
            &svg[..200]
        );
        for want in ["a title", "±2σ", "reference", "<polygon"] {
            assert!(svg.contains(want), "{want}");
        }
        assert!(!svg.contains(">-0<") && !svg.contains(">-0.0<"));
    }

    /// The `<text>` elements of an SVG from plotters: (x attribute, trimmed content).
    fn svg_texts(svg: &str) -> Vec<(f64, String)> {
        svg.split("<text")
            .skip(1)
            .filter_map(|t| {
                let (attrs, rest) = t.split_once('>')?;
                let content = rest.split("</text>").next()?.trim().to_string();
                let x = attrs.split("x=\"").nth(1)?.split('"').next()?.parse().ok()?;
                Some((x, content))
            })
            .collect()
    }

    /// Histograms as SVG: the title, the legend outside the bars (`runs`, `truth` right of the
    /// plotting area: `estimates`, `truth`), integer count ticks only and no `-0` tick, whatever the values' sign.
    #[test]
    fn histogram_svg_has_legend_outside_and_clean_ticks() {
        let values: Vec<f64> = (0..40).map(|k| -0.02 + 0.001 * f64::from(k % 9)).collect();
        let p = HistogramPanel {
            title: "Cm_alpha".into(),
            x_label: "Cm_alpha".into(),
            values,
            bins: 10,
            line: Some(-0.015),
            line_label: "truth".into(),
        };
        let svg = render_histograms_svg("h.svg", "final estimates", &[p], 1, (400, 260)).unwrap();
        let texts = svg_texts(&svg);
        let find = |label: &str| texts.iter().find(|(_, t)| t == label).map(|(x, _)| *x);
        assert!(find("final estimates").is_some());
        // The legend starts right of every bar (the chart area ends 92 px before the edge).
        for label in ["estimates", "truth"] {
            let x = find(label).unwrap_or_else(|| panic!("no legend entry {label}"));
            assert!(x > 400.0 - 92.0, "legend entry {label} at x = {x}, inside the chart");
        }
        assert!(texts.iter().all(|(_, t)| t != "-0" && t != "-0.0" && t != "-0.000"));
        // Count ticks are distinct integers (non-integer ticks rounded would repeat).
        let counts: Vec<&str> = texts
            .iter()
            .map(|(_, t)| t.as_str())
            .filter(|t| !t.is_empty() && t.chars().all(|c| c.is_ascii_digit()))
            .collect();
        assert!(counts.len() >= 3, "{counts:?}");
        let mut dedup = counts.clone();
        dedup.sort_unstable();
        dedup.dedup();
        assert_eq!(counts.len(), dedup.len(), "repeated count tick labels: {counts:?}");
    }

    /// Grouped bars: every series and the reference line are in the legend, right of the
    /// bars; a series of the wrong length is an error naming it.
    #[test]
    fn grouped_bars_legend_and_length_check() {
        let mut chart = GroupedBars {
            title: "coverage".into(),
            y_label: "fraction of runs".into(),
            categories: vec!["Cm_q".into(), "Cl_p".into()],
            series: vec![
                ("rls".into(), vec![Some(0.9), None]),
                ("ekf".into(), vec![Some(1.0), Some(0.95)]),
            ],
            y_range: (0.0, 1.05),
            reference: Some((0.95, "0.95 target".into())),
        };
        let svg = chart.render_svg("c.svg", (800, 400)).unwrap();
        let texts = svg_texts(&svg);
        let find = |label: &str| texts.iter().find(|(_, t)| t == label).map(|(x, _)| *x);
        for label in ["rls", "ekf", "0.95 target"] {
            let x = find(label).unwrap_or_else(|| panic!("no legend entry {label}"));
            assert!(x > 800.0 - 260.0, "legend entry {label} at x = {x}");
        }
        assert!(find("Cm_q").is_some() && find("Cl_p").is_some());
        chart.series[0].1.pop();
        let err = chart.render_svg("c.svg", (800, 400)).unwrap_err().to_string();
        assert!(err.contains("rls") && err.contains("c.svg"), "{err}");
    }

    #[test]
    fn empty_figure_is_an_error() {
        let err = render_panels_png(Path::new("/nonexistent/x.png"), "t", &[], 100, 100);
        assert!(matches!(err, Err(PlotError::InvalidFigure { .. })));
    }
}
