//! `--window auto` of `replay` and `compat`: the windows are the candidate manoeuvres
//! `aeroident inspect` finds on the mapping's surfaces and the phugoids it finds in the
//! airspeed (docs/inspect.md), in flight only (the ground, the taxi and the take-off and
//! landing rolls left out), joined where they overlap; `--window auto:N` takes the best `N`
//! per axis by the information they hold. The command says which it chose and what it left out.

use aeroident_io::inspect::InspectOptions;
use aeroident_io::{LogFormat, Mapping};
use aeroident_pipelines::inspect::detect::DetectionRule;
use aeroident_pipelines::inspect::rank::{
    DEFAULT_SET_SIZE, Ranking, airborne_windows, union_of_sets,
};
use aeroident_pipelines::inspect::{InspectReport, inspect_ranked, manoeuvre_windows};
use aeroident_pipelines::window::TimeWindow;
use anyhow::bail;

/// One `--window` argument: a span, or `auto`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WindowSpec {
    /// `START:END`, record seconds.
    Span(TimeWindow),
    /// `auto`: the detected manoeuvres in flight.
    Auto,
    /// `auto:N`: the best `N` per axis by the information they hold.
    AutoBest(usize),
}

/// Parses `auto`, `auto:N` (N ≥ 1) or `START:END`.
///
/// # Errors
/// [`TimeWindow::parse`]'s message, naming `auto` and `auto:N` as the other choices; an `N`
/// that is not a whole number from 1.
pub fn parse(text: &str) -> Result<WindowSpec, String> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("auto") {
        return Ok(WindowSpec::Auto);
    }
    if let Some((head, n)) = t.split_once(':')
        && head.trim().eq_ignore_ascii_case("auto")
    {
        return match n.trim().parse::<usize>() {
            Ok(n) if n >= 1 => Ok(WindowSpec::AutoBest(n)),
            _ => Err(format!(
                "`{text}`: give auto:N with N a whole number from 1 (the best N windows per axis)"
            )),
        };
    }
    TimeWindow::parse(text)
        .map(WindowSpec::Span)
        .map_err(|e| format!("{e}, or `auto`, or `auto:N`"))
}

/// The axes whose window sets `auto:N` takes for a `--model` choice: a longitudinal model the
/// pitch set, a lateral one the lateral set, any other model (six-axis, a model file, none
/// given) both: a lateral window adds nothing but its own initial state to a pitch-only fit.
pub fn axes_of_model(model: Option<&str>) -> &'static [&'static str] {
    match model.map(|m| m.trim().trim_start_matches("auto:")) {
        Some("longitudinal") => &["pitch"],
        Some("lateral") => &["lateral"],
        _ => &["pitch", "lateral"],
    }
}

/// The time windows of `specs` for record `data`: the spans as given, or with `auto` (alone)
/// the manoeuvres detected on `mapping`'s `de`, `da`, `dr` columns and the phugoids, in
/// flight, or with `auto:N` the best `N` per axis of `axes` ([`axes_of_model`]), printed on
/// stderr as the `--window` arguments they stand for. `more_records`: other records given
/// with `--and`.
///
/// # Errors
/// `auto` beside spans or twice, with stdin or a live feed, with `--and`; a record that
/// cannot be read; no surface in the mapping; no manoeuvre found in flight; `auto:N` on a
/// record the mapping cannot read as air-data samples.
pub fn resolve(
    specs: &[WindowSpec],
    data: &str,
    format: Option<LogFormat>,
    mapping: &Mapping,
    more_records: bool,
    axes: &[&str],
) -> anyhow::Result<Vec<TimeWindow>> {
    let spans: Vec<TimeWindow> = specs
        .iter()
        .filter_map(|s| match s {
            WindowSpec::Span(w) => Some(*w),
            WindowSpec::Auto | WindowSpec::AutoBest(_) => None,
        })
        .collect();
    if spans.len() == specs.len() {
        return Ok(spans);
    }
    check_auto(specs, data, more_records)?;
    let best = specs.iter().find_map(|s| match s {
        WindowSpec::AutoBest(n) => Some(*n),
        _ => None,
    });
    let options = InspectOptions { format, mapping: Some(mapping), keep: Vec::new() };
    let rule = DetectionRule::default();
    let outcome = inspect_ranked(data, &options, &rule, best.unwrap_or(DEFAULT_SET_SIZE))?;
    let report = &outcome.report;
    let channels: Vec<&str> = report.surfaces.iter().map(|s| s.column.as_str()).collect();
    if report.surfaces.is_empty() {
        bail!(
            "--window auto: the mapping {} maps no surface column (`de`, `da`, `dr`) to detect manoeuvres on",
            mapping.file
        );
    }
    let (windows, why) = chosen(report, best, axes)?;
    // Rounded outwards to 0.01 s, so the windows printed are the ones used.
    let windows: Vec<TimeWindow> = windows
        .into_iter()
        .map(|w| TimeWindow {
            start_s: super::inspect::floor2(w.start_s),
            end_s: super::inspect::ceil2(w.end_s),
        })
        .collect();
    if windows.is_empty() {
        bail!(
            "--window auto: no manoeuvre found in flight on {} (`aeroident inspect {data} --map {}` shows the levels, the ground spans and the ranks; docs/inspect.md)",
            channels.join(", "),
            mapping.file
        );
    }
    announce(&windows, &channels, &why, report.flight.as_ref());
    Ok(windows)
}

/// Prints the windows chosen as the `--window` arguments they stand for, and the ground spans
/// left out.
fn announce(windows: &[TimeWindow], channels: &[&str], why: &str, flight: Option<&Ranking>) {
    let args: Vec<String> =
        windows.iter().map(|w| format!("--window {}:{}", w.start_s, w.end_s)).collect();
    aeroident_report::note!(
        "--window auto: {} window(s) from the manoeuvres on {}{why}: {}",
        windows.len(),
        channels.join(", "),
        args.join(" ")
    );
    if let Some(f) = flight {
        left_out_note(f);
    }
}

/// The windows `auto` (every candidate in flight) or `auto:N` (the union of the best `N` of
/// each axis of `axes`) stands for, and the words that say which; without a flight judgement
/// `auto` falls back to every candidate, `auto:N` is refused.
fn chosen(
    report: &InspectReport,
    best: Option<usize>,
    axes: &[&str],
) -> anyhow::Result<(Vec<TimeWindow>, String)> {
    let Some(f) = &report.flight else {
        let why = report.flight_note.as_deref().unwrap_or("-");
        if best.is_some() {
            bail!("--window auto:N ranks the candidates by the air-data samples, and {why}");
        }
        return Ok((manoeuvre_windows(report), format!(" (not judged in flight terms: {why})")));
    };
    let Some(n) = best else {
        return Ok((airborne_windows(f), " and the phugoids, in flight".into()));
    };
    let taken: std::collections::BTreeMap<String, Vec<[f64; 2]>> = f
        .window_sets
        .iter()
        .filter(|(axis, _)| axes.contains(&axis.as_str()))
        .map(|(axis, set)| (axis.clone(), set.clone()))
        .collect();
    let sets: Vec<String> = taken
        .iter()
        .map(|(axis, set)| {
            let w: Vec<String> = set
                .iter()
                .map(|w| {
                    format!("{}:{}", super::inspect::floor2(w[0]), super::inspect::ceil2(w[1]))
                })
                .collect();
            format!("{axis} {}", if w.is_empty() { "none".into() } else { w.join(", ") })
        })
        .collect();
    Ok((union_of_sets(&taken), format!(", the best {n} per axis ({})", sets.join("; "))))
}

/// Says which ground spans `auto` left out and how many candidates they held.
fn left_out_note(f: &Ranking) {
    let Some(e) = &f.envelope else { return };
    if e.ground.is_empty() {
        return;
    }
    let spans: Vec<String> =
        e.ground.iter().map(|g| format!("{} {:.2}–{:.2} s", g.kind, g.start_s, g.end_s)).collect();
    let n = f.candidates.iter().filter(|c| c.excluded.is_some()).count();
    aeroident_report::note!(
        "--window auto: left out as ground (airspeed below {:.1} m/s{}): {}; {n} candidate(s) there not used",
        e.min_speed_mps,
        e.min_qbar_pa.map_or(String::new(), |q| format!(" or q̄ below {q:.0} Pa")),
        spans.join(", ")
    );
}

/// `auto` goes alone, on a file, for one record.
fn check_auto(specs: &[WindowSpec], data: &str, more_records: bool) -> anyhow::Result<()> {
    if specs.len() > 1 {
        bail!("option `--window`: give `auto` once, and not beside START:END windows");
    }
    if data == "-" || aeroident_io::record::is_mavlink(data) {
        bail!("--window auto reads the record twice (to find the manoeuvres first): give a file");
    }
    if more_records {
        bail!(
            "--window auto finds the manoeuvres of one record: with --and, give START:END windows"
        );
    }
    Ok(())
}
