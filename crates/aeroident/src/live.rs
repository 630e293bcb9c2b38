//! The console's side of a live MAVLink feed (`mavlink:udp:<host>:<port>`, opened by
//! [`aeroident_io::Record::open`]): its problems printed as they arise, and its link
//! statistics printed and added to the replay summary.

use aeroident_io::mavlink::LinkStats;
use aeroident_io::replay_output::ReplaySummary;
use std::sync::Mutex;

/// A live feed's problem as it arises, on stderr.
pub fn problem(line: &str) {
    aeroident_report::note!("warning: {line}");
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
