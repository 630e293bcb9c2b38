//! `aeroident inspect`: look at a log before mapping it (docs/inspect.md).
//!
//! ```text
//! aeroident inspect <log> [--format …] [--map MAPPING.toml] [--json FILE]
//!                   [--plot CH,CH,… [--window START:END] --out FILE.svg|png]
//! ```
//! Prints the topics (or columns) with their fields, units, sample counts, rates, spans and
//! gaps, the parameters of a ULog or DataFlash log, and the candidate manoeuvres found on the
//! surface channels as `--window START:END` arguments; `--json` writes the same as one
//! document; `--plot` draws raw channels against time.

mod render;

pub use render::{ceil2, floor2};

use aeroident_io::LogFormat;
use aeroident_io::inspect::{InspectOptions, Signal};
use aeroident_io::mapping::Mapping;
use aeroident_pipelines::inspect::detect::DetectionRule;
use aeroident_pipelines::inspect::{InspectOutcome, inspect};
use aeroident_pipelines::window::TimeWindow;
use aeroident_report::plot::{LineKind, Panel, Series, render_panels_png, render_panels_svg};
use anyhow::{Context as _, bail};
use std::path::{Path, PathBuf};

/// Arguments of `aeroident inspect`.
#[derive(Debug, Clone, clap::Args)]
pub struct InspectArgs {
    /// The log: CSV (one header row), whitespace `.asc`, MATLAB `.mat`, PX4 ULog `.ulg`,
    /// ArduPilot DataFlash `.bin`, MAVLink telemetry `.tlog` (by its extension); `-` for a CSV
    /// (or `--format asc`) on stdin.
    pub data: String,
    /// Log format (csv, asc, mat, ulog, dataflash); default: by the file's extension, else CSV.
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
}

/// Runs `aeroident inspect`.
///
/// # Errors
/// A bad combination of options, an unreadable mapping or log (naming the file and the byte or
/// row), a `--plot` channel the log lacks, an unwritable `--json` or `--out` file.
pub fn execute(args: InspectArgs) -> anyhow::Result<()> {
    check_args(&args)?;
    let mapping = args.map.as_deref().map(Mapping::from_path).transpose()?;
    let options = InspectOptions {
        format: args.format,
        mapping: mapping.as_ref(),
        keep: args.plot.iter().map(|c| c.trim().to_string()).collect(),
    };
    let outcome = inspect(&args.data, &options, &DetectionRule::default())?;
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&outcome.report)?;
        std::fs::write(path, text + "\n")
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if let Some(out) = &args.out {
        plot(&outcome, &options.keep, args.window, out)?;
    }
    super::print_stdout(&render::render(&outcome.report))?;
    if let Some(path) = &args.json {
        aeroident_report::note!("wrote {}", path.display());
    }
    if let Some(path) = &args.out {
        aeroident_report::note!("wrote {}", path.display());
    }
    Ok(())
}

/// The options that only go together: `--plot` with `--out` (`.svg` or `.png`), `--window`
/// with `--plot`.
fn check_args(args: &InspectArgs) -> anyhow::Result<()> {
    match (args.plot.is_empty(), &args.out) {
        (false, None) => bail!("--plot needs --out FILE.svg or FILE.png"),
        (true, Some(_)) => bail!("--out is the file of a plot: give the channels with --plot"),
        (false, Some(out)) if plot_kind(out).is_none() => {
            bail!("--out {}: give a file ending in .svg or .png", out.display())
        }
        _ => {}
    }
    if args.window.is_some() && args.plot.is_empty() {
        bail!("--window is the time span of a plot: give the channels with --plot");
    }
    Ok(())
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
        std::fs::write(out, svg).with_context(|| format!("cannot write {}", out.display()))?;
    } else {
        render_panels_png(out, &title, &panels, width, height)?;
    }
    Ok(())
}

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
