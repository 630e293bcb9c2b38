//! `--window auto` of `replay` and `compat`: the windows are the candidate manoeuvres
//! `aeroident inspect` finds on the mapping's surfaces (docs/inspect.md), joined where they
//! overlap, and the command says which it chose.

use aeroident_io::inspect::InspectOptions;
use aeroident_io::{LogFormat, Mapping};
use aeroident_pipelines::inspect::detect::DetectionRule;
use aeroident_pipelines::inspect::{inspect, manoeuvre_windows};
use aeroident_pipelines::window::TimeWindow;
use anyhow::bail;

/// One `--window` argument: a span, or `auto`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WindowSpec {
    /// `START:END`, record seconds.
    Span(TimeWindow),
    /// `auto`: the detected manoeuvres.
    Auto,
}

/// Parses `auto` or `START:END`.
///
/// # Errors
/// [`TimeWindow::parse`]'s message, naming `auto` as the other choice.
pub fn parse(text: &str) -> Result<WindowSpec, String> {
    if text.trim().eq_ignore_ascii_case("auto") {
        return Ok(WindowSpec::Auto);
    }
    TimeWindow::parse(text).map(WindowSpec::Span).map_err(|e| format!("{e}, or `auto`"))
}

/// The time windows of `specs` for record `data`: the spans as given, or with `auto` (alone)
/// the manoeuvres detected on `mapping`'s `de`, `da`, `dr` columns, printed on stderr as the
/// `--window` arguments they stand for. `more_records`: other records given with `--and`.
///
/// # Errors
/// `auto` beside spans or twice, with stdin or a live feed, with `--and`; a record that
/// cannot be read; no surface in the mapping; no manoeuvre found.
pub fn resolve(
    specs: &[WindowSpec],
    data: &str,
    format: Option<LogFormat>,
    mapping: &Mapping,
    more_records: bool,
) -> anyhow::Result<Vec<TimeWindow>> {
    let spans: Vec<TimeWindow> = specs
        .iter()
        .filter_map(|s| match s {
            WindowSpec::Span(w) => Some(*w),
            WindowSpec::Auto => None,
        })
        .collect();
    if spans.len() == specs.len() {
        return Ok(spans);
    }
    check_auto(specs, data, more_records)?;
    let options = InspectOptions { format, mapping: Some(mapping), keep: Vec::new() };
    let outcome = inspect(data, &options, &DetectionRule::default())?;
    let report = &outcome.report;
    if report.surfaces.is_empty() {
        bail!(
            "--window auto: the mapping {} maps no surface column (`de`, `da`, `dr`) to detect manoeuvres on",
            mapping.file
        );
    }
    // Rounded outwards to 0.01 s, so the windows printed are the ones used.
    let windows: Vec<TimeWindow> = manoeuvre_windows(report)
        .into_iter()
        .map(|w| TimeWindow {
            start_s: super::inspect::floor2(w.start_s),
            end_s: super::inspect::ceil2(w.end_s),
        })
        .collect();
    let channels: Vec<&str> = report.surfaces.iter().map(|s| s.column.as_str()).collect();
    if windows.is_empty() {
        bail!(
            "--window auto: no manoeuvre found on {} (`aeroident inspect {data} --map {}` shows the levels; docs/inspect.md)",
            channels.join(", "),
            mapping.file
        );
    }
    let args: Vec<String> =
        windows.iter().map(|w| format!("--window {}:{}", w.start_s, w.end_s)).collect();
    aeroident_report::note!(
        "--window auto: {} window(s) from the manoeuvres on {}: {}",
        windows.len(),
        channels.join(", "),
        args.join(" ")
    );
    Ok(windows)
}

/// `auto` goes alone, on a file, for one record.
fn check_auto(specs: &[WindowSpec], data: &str, more_records: bool) -> anyhow::Result<()> {
    if specs.len() > 1 {
        bail!("option `--window`: give `auto` once, and not beside START:END windows");
    }
    if data == "-" || crate::live::is_mavlink(data) {
        bail!("--window auto reads the record twice (to find the manoeuvres first): give a file");
    }
    if more_records {
        bail!(
            "--window auto finds the manoeuvres of one record: with --and, give START:END windows"
        );
    }
    Ok(())
}
