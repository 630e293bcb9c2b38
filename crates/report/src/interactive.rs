//! One self-contained HTML page of zoomable, linked time plots: one row per channel, every row
//! on one time axis (zooming or panning one zooms them all), spans shaded across the rows
//! (`aeroident inspect --html`).
//!
//! Drawn by plotly.js through the `plotly` crate, which embeds the library in the page
//! (feature `plotly_embed_js`), so the page opens with no network and the tree carries no
//! JavaScript of ours or of anyone else's. A channel of more than [`WEBGL_ABOVE`] samples is
//! drawn with WebGL, which keeps a long log responsive; the samples are never thinned.

use plotly::common::{Line, Mode, Title};
use plotly::layout::{Axis, GridPattern, LayoutGrid, Shape, ShapeLayer, ShapeLine, ShapeType};
use plotly::{Layout, Plot, Scatter};

/// Samples above which a channel is drawn with WebGL instead of SVG.
pub const WEBGL_ABOVE: usize = 20_000;

/// One channel to draw: its values against time.
#[derive(Debug, Clone, Copy)]
pub struct TimeChannel<'a> {
    /// The name shown beside its row.
    pub name: &'a str,
    /// The y-axis label (name and unit).
    pub label: &'a str,
    /// Sample times, s.
    pub t_s: &'a [f64],
    /// Values, same length (NaN: a gap).
    pub values: &'a [f64],
}

/// A span shaded across every row (a manoeuvre), with its label.
#[derive(Debug, Clone, PartialEq)]
pub struct Span {
    /// Start, s.
    pub start_s: f64,
    /// End, s.
    pub end_s: f64,
    /// What it is (shown on hover of its label).
    pub label: String,
}

/// The page (module doc): `title`, one row per channel in order, `spans` shaded.
pub fn linked_time_plots_html(title: &str, channels: &[TimeChannel], spans: &[Span]) -> String {
    let mut plot = Plot::new();
    for (i, c) in channels.iter().enumerate() {
        let y = if i == 0 { "y".to_string() } else { format!("y{}", i + 1) };
        let trace = Scatter::new(c.t_s.to_vec(), c.values.to_vec())
            .name(c.name)
            .mode(Mode::Lines)
            .line(Line::new().width(1.0))
            .x_axis("x")
            .y_axis(&y)
            .web_gl_mode(c.t_s.len() > WEBGL_ABOVE);
        plot.add_trace(trace);
    }
    plot.set_layout(layout(title, channels, spans));
    plot.to_html()
}

fn layout(title: &str, channels: &[TimeChannel], spans: &[Span]) -> Layout {
    let rows = channels.len().max(1);
    let mut l = Layout::new()
        .title(Title::with_text(title))
        .height(180 * rows + 120)
        .show_legend(false)
        .grid(LayoutGrid::new().rows(rows).columns(1).pattern(GridPattern::Coupled))
        .x_axis(Axis::new().title(Title::with_text("time, s")));
    for (i, c) in channels.iter().enumerate() {
        let axis = Axis::new().title(Title::with_text(c.label));
        l = match i {
            0 => l.y_axis(axis),
            1 => l.y_axis2(axis),
            2 => l.y_axis3(axis),
            3 => l.y_axis4(axis),
            4 => l.y_axis5(axis),
            5 => l.y_axis6(axis),
            6 => l.y_axis7(axis),
            _ => l.y_axis8(axis),
        };
    }
    for s in spans {
        l.add_shape(
            Shape::new()
                .shape_type(ShapeType::Rect)
                .x_ref("x")
                .y_ref("paper")
                .x0(s.start_s)
                .x1(s.end_s)
                .y0(0)
                .y1(1)
                .fill_color("rgba(255, 160, 0, 0.15)")
                .line(ShapeLine::new().width(0.0))
                .layer(ShapeLayer::Below)
                .name(&s.label),
        );
    }
    l
}
