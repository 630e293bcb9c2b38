//! Live sources for `replay`: a MAVLink feed (`mavlink:udp:<host>:<port>`) opened as a
//! [`FlightDataReader`] over the same mapping as a file (`aeroident_io::mavlink`), and its link
//! statistics added to the replay summary.

use aeroident_io::mapping::Source;
use aeroident_io::mavlink::{LinkStats, MavlinkRows, MavlinkUrl};
use aeroident_io::replay_output::ReplaySummary;
use aeroident_io::{FlightDataReader, Mapping};
use std::sync::{Arc, Mutex};

fn problem(line: &str) {
    aeroident_report::note!("warning: {line}");
}

/// Whether a replay source names a MAVLink feed.
pub fn is_mavlink(source: &str) -> bool {
    source.starts_with("mavlink:")
}

/// Binds the feed's socket and returns the reader (named by the source text in messages) and a
/// handle on the link statistics. Says on stderr where it listens.
///
/// # Errors
/// A malformed source, a mapped column that is not a numeric MAVLink field, a socket that
/// cannot be bound.
pub fn open_mavlink(
    source: &str,
    mapping: &Mapping,
) -> anyhow::Result<(FlightDataReader<MavlinkRows>, Arc<Mutex<LinkStats>>)> {
    let url = MavlinkUrl::parse(source)?;
    let rows = MavlinkRows::open(&url, mapping, Some(problem))?;
    let stats = rows.stats();
    let clock = match &mapping.time.source {
        Source::Columns(c) => c.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join("+"),
        Source::Constant(_) => String::new(),
    };
    aeroident_report::note!(
        "listening on {} (clock {}, ends after {} s without a datagram or on NAMED_VALUE_FLOAT `{}`)",
        rows.local_addr(),
        clock,
        url.timeout_s,
        aeroident_io::mavlink::END_OF_STREAM_NAME
    );
    let reader = FlightDataReader::new(rows, &url.text, mapping)?;
    Ok((reader, stats))
}

/// One line on the link: counts and how it ended ([`LinkStats::line`]).
pub fn link_line(s: &LinkStats) -> String {
    s.line()
}

/// A replay of the feed failed: the link statistics on stderr, unless the error already
/// carries them (a feed that produced no row).
pub fn report_failure(stats: &Mutex<LinkStats>) {
    let s = stats.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    if s.rows > 0 {
        aeroident_report::note!("{}", s.line());
    }
}

/// Prints the link line and adds it (and any problem) to the summary's warnings.
pub fn finish(summary: &mut ReplaySummary, stats: &Mutex<LinkStats>) {
    let s = stats.lock().unwrap_or_else(std::sync::PoisonError::into_inner).clone();
    let line = link_line(&s);
    aeroident_report::note!("{line}");
    summary.warnings.push(line);
    if !s.never_received.is_empty() {
        let w = format!("mavlink: never received: {}", s.never_received.join(", "));
        aeroident_report::note!("warning: {w}");
        summary.warnings.push(w);
    }
    summary.warnings.extend(s.problems.iter().map(|p| format!("mavlink: {p}")));
}
