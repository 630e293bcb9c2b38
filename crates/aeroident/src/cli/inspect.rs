//! `aeroident inspect`: look at a log before mapping it (docs/inspect.md).
//!
//! ```text
//! aeroident inspect <log> [--format …] [--map MAPPING.toml] [--json FILE]
//!                   [--plot CH,CH,… [--window START:END] --out FILE.svg|png] [--html FILE.html]
//!                   [--best N]
//! ```
//! Prints the topics (or columns) with their fields, units, sample counts, rates, spans and
//! gaps, the parameters of a ULog or DataFlash log, and the candidate manoeuvres found on the
//! surface channels as `--window START:END` arguments — with `--map`, also the ground spans
//! left out, phugoids, the candidates ranked per axis and the best `N` of each as a window set;
//! `--json` writes the same as one
//! document; `--plot` draws raw channels against time; `--html` writes them (or the surfaces)
//! as one page of zoomable, linked time plots with the manoeuvres shaded.

mod render;

pub use render::{ceil2, floor2};

use aeroident_io::LogFormat;
use aeroident_io::inspect::{InspectOptions, Signal};
use aeroident_io::mapping::Mapping;
use aeroident_pipelines::inspect::detect::DetectionRule;
use aeroident_pipelines::inspect::rank::DEFAULT_SET_SIZE;
use aeroident_pipelines::inspect::{InspectOutcome, inspect_ranked};
use aeroident_pipelines::window::TimeWindow;
use aeroident_report::interactive::{Span, TimeChannel, linked_time_plots_html};
use aeroident_report::outfile;
use aeroident_report::plot::{LineKind, Panel, Series, render_panels_png, render_panels_svg};
use anyhow::bail;
use std::path::{Path, PathBuf};

/// Arguments of `aeroident inspect`.
#[derive(Debug, Clone, clap::Args)]
pub struct InspectArgs {
    /// The log: CSV (one header row), whitespace `.asc`, MATLAB `.mat`, PX4 ULog `.ulg`,
    /// ArduPilot DataFlash `.bin`, MAVLink telemetry `.tlog` (by its extension); `-` for a CSV
    /// (or `--format asc`) on stdin.
    pub data: String,
    /// Log format (csv, asc, mat, ulog, dataflash, tlog); default: by the file's extension, else CSV.
    #[arg(long)]
    pub format: Option<LogFormat>,
    /// A channel mapping (`replay`'s, docs/mapping.md): its `de`, `da`, `dr` columns are the
    /// surfaces the manoeuvre detector reads, its `[time] column` a table's time. Without it:
    /// surfaces by column name (tables) or the known actuator topics (ULog, DataFlash).
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Write the listing and the manoeuvres as JSON to this file (schema: docs/inspect.md).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Channels to draw against time, comma-separated: `topic.field` (`RCOU.C2`,
    /// `actuator_controls_0.control[1]`) or a table's column names. Needs `--out`.
    #[arg(long, value_name = "CH,CH,…", value_delimiter = ',')]
    pub plot: Vec<String>,
    /// The time span `START:END` (log seconds) of the plot; default: the whole log.
    #[arg(long, value_name = "START:END", value_parser = TimeWindow::parse, allow_hyphen_values = true)]
    pub window: Option<TimeWindow>,
    /// The plot file: `.svg` or `.png`.
    #[arg(long, value_name = "FILE.svg|png")]
    pub out: Option<PathBuf>,
    /// Write one self-contained page of zoomable, linked time plots (one row per `--plot`
    /// channel, else per surface channel, at most 8) with the manoeuvres found shaded.
    #[arg(long, value_name = "FILE.html")]
    pub html: Option<PathBuf>,
    /// With `--map`: the window sets listed take the best N candidates per axis (what
    /// `--window auto:N` fits).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_SET_SIZE, value_parser = parse_best)]
    pub best: usize,
}

/// `--best N`: a whole number from 1.
fn parse_best(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!("`{text}`: give a whole number from 1")),
    }
}

/// Runs `aeroident inspect`.
///
/// # Errors
/// A bad combination of options, an unreadable mapping or log (naming the file and the byte or
/// row), a `--plot` channel the log lacks, an unwritable `--json` or `--out` file.
pub fn execute(args: InspectArgs) -> anyhow::Result<()> {
    check_args(&args)?;
    check_outputs(&args)?;
    let mapping = args.map.as_deref().map(Mapping::from_path).transpose()?;
    let options = InspectOptions {
        format: args.format,
        mapping: mapping.as_ref(),
        keep: args.plot.iter().map(|c| c.trim().to_string()).collect(),
    };
    let outcome = inspect_ranked(&args.data, &options, &DetectionRule::default(), args.best)?;
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&outcome.report)?;
        outfile::write_file("--json", path, (text + "\n").as_bytes())?;
    }
    if let Some(out) = &args.out {
        plot(&outcome, &options.keep, args.window, out)?;
    }
    if let Some(path) = &args.html {
        html(&outcome, &options.keep, args.window, path)?;
    }
    super::print_stdout(&render::render(&outcome.report))?;
    if let Some(path) = &args.json {
        aeroident_report::note!("wrote {}", path.display());
    }
    for path in [&args.out, &args.html].into_iter().flatten() {
        aeroident_report::note!("wrote {}", path.display());
    }
    Ok(())
}

/// The options that only go together: `--plot` with `--out` (`.svg` or `.png`), `--window`
/// with `--plot`.
fn check_args(args: &InspectArgs) -> anyhow::Result<()> {
    match (args.plot.is_empty(), &args.out) {
        (false, None) if args.html.is_none() => {
            bail!("--plot needs --out FILE.svg or FILE.png, or --html FILE.html")
        }
        (true, Some(_)) => bail!("--out is the file of a plot: give the channels with --plot"),
        (false, Some(out)) if plot_kind(out).is_none() => {
            bail!("--out {}: give a file ending in .svg or .png", out.display())
        }
        _ => {}
    }
    if args.window.is_some() && args.plot.is_empty() && args.html.is_none() {
        bail!("--window is the time span of a plot: give the channels with --plot or --html");
    }
    Ok(())
}

/// Refuses, before the log is read, an output that is not a regular file, that names the
/// log or the mapping, or that another output names too ([`outfile::check_outputs`]).
fn check_outputs(args: &InspectArgs) -> anyhow::Result<()> {
    let outputs: Vec<(&str, &Path)> =
        [("--json", &args.json), ("--out", &args.out), ("--html", &args.html)]
            .into_iter()
            .filter_map(|(o, p)| Some((o, p.as_deref()?)))
            .collect();
    let mut inputs = vec![("log", Path::new(&args.data))];
    inputs.extend(args.map.as_deref().map(|m| ("--map", m)));
    Ok(outfile::check_outputs(&outputs, &inputs)?)
}

/// Whether `path` is an SVG (`true`) or a PNG (`false`) by its extension.
fn plot_kind(path: &Path) -> Option<bool> {
    match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
        "svg" => Some(true),
        "png" => Some(false),
        _ => None,
    }
}

/// Draws `channels` (one panel each, raw values against log time) within `window` to `out`.
fn plot(
    outcome: &InspectOutcome,
    channels: &[String],
    window: Option<TimeWindow>,
    out: &Path,
) -> anyhow::Result<()> {
    let panels: Vec<Panel> = channels
        .iter()
        .filter_map(|c| outcome.signals.iter().find(|s| &s.column == c))
        .map(|s| panel(s, window))
        .collect::<anyhow::Result<_>>()?;
    let title = format!("{} (raw values)", outcome.report.log.file);
    let (width, height) = (1100, 220);
    if plot_kind(out) == Some(true) {
        let svg = render_panels_svg(&out.display().to_string(), &title, &panels, width, height)?;
        outfile::write_file("--out", out, svg.as_bytes())?;
    } else {
        outfile::write_file_with("--out", out, |tmp: &Path| {
            render_panels_png(tmp, &title, &panels, width, height)
        })?;
    }
    Ok(())
}

/// Writes the page of linked time plots of `channels` (else the surface channels) within
/// `window`, the manoeuvres found shaded.
///
/// # Errors
/// No channel to draw, more than [`MAX_HTML_ROWS`], a window without samples, an unwritable
/// file.
fn html(
    outcome: &InspectOutcome,
    channels: &[String],
    window: Option<TimeWindow>,
    path: &Path,
) -> anyhow::Result<()> {
    let names: Vec<String> = if channels.is_empty() {
        outcome.report.surfaces.iter().map(|s| s.column.clone()).collect()
    } else {
        channels.to_vec()
    };
    if names.is_empty() {
        bail!("--html: no surface channel is known in this log; name the channels with --plot");
    }
    if names.len() > MAX_HTML_ROWS {
        bail!("--html draws at most {MAX_HTML_ROWS} channels; {} given", names.len());
    }
    let panels: Vec<Panel> = names
        .iter()
        .filter_map(|c| outcome.signals.iter().find(|s| &s.column == c))
        .map(|s| panel(s, window))
        .collect::<anyhow::Result<_>>()?;
    let rows: Vec<TimeChannel> = panels
        .iter()
        .map(|p| TimeChannel {
            name: &p.title,
            label: &p.y_label,
            t_s: &p.series[0].t_s,
            values: &p.series[0].values,
        })
        .collect();
    let spans: Vec<Span> = outcome
        .report
        .detections
        .iter()
        .flat_map(|d| d.manoeuvres.iter())
        .map(|m| Span {
            start_s: m.start_s,
            end_s: m.end_s,
            label: format!("{} manoeuvre, --window {:.2}:{:.2}", m.channel, m.start_s, m.end_s),
        })
        .collect();
    let title =
        format!("{} (raw values; drag to zoom, double-click to reset)", outcome.report.log.file);
    let page = linked_time_plots_html(&title, &rows, &spans);
    Ok(outfile::write_file("--html", path, page.as_bytes())?)
}

/// Most rows of the `--html` page (the plotting library's y axes 1–8).
const MAX_HTML_ROWS: usize = 8;

/// One channel's panel within `window`.
///
/// # Errors
/// A window holding no sample of the channel.
fn panel(s: &Signal, window: Option<TimeWindow>) -> anyhow::Result<Panel> {
    let inside = |t: f64| window.is_none_or(|w| (w.start_s..=w.end_s).contains(&t));
    let (t_s, values): (Vec<f64>, Vec<f64>) =
        s.t_s.iter().zip(&s.values).filter(|(t, _)| inside(**t)).map(|(t, v)| (*t, *v)).unzip();
    if let (Some(w), true) = (window, t_s.is_empty()) {
        bail!("--window {}:{}: channel `{}` has no sample in it", w.start_s, w.end_s, s.column);
    }
    // A table's `name [unit]` column already says its unit.
    let y_label = match &s.unit {
        Some(u) if !s.column.contains(u.as_str()) => format!("{} ({u})", s.column),
        _ => s.column.clone(),
    };
    Ok(Panel {
        title: s.column.clone(),
        y_label,
        series: vec![Series { label: s.column.clone(), t_s, values, kind: LineKind::Solid }],
        signals: true,
        ..Panel::default()
    })
}
