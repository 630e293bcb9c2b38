//! The text `aeroident inspect` prints: the same content as its `--json` document.

use aeroident_io::inspect::TopicSummary;
use aeroident_pipelines::inspect::InspectReport;
use aeroident_pipelines::inspect::detect::ChannelDetection;
use std::fmt::Write as _;

/// Width the field lists are wrapped at.
const WRAP: usize = 100;

/// The whole listing.
pub fn render(r: &InspectReport) -> String {
    let mut s = header(r);
    s += &topics(r);
    s += &parameters(r);
    if !r.log.notes.is_empty() {
        s += "\nnotes (what the reader left out):\n";
        for n in &r.log.notes {
            let _ = writeln!(s, "  {n}");
        }
    }
    s += &manoeuvres(r);
    s
}

/// File, format, time column.
fn header(r: &InspectReport) -> String {
    let mut s = format!("{}: {} log, {} topic(s)\n", r.log.file, r.log.format, r.log.topics.len());
    if let Some(tc) = &r.log.time_column {
        let why = match tc.source.as_str() {
            "mapping" => "the mapping's [time] column",
            "name" => "its name says time",
            _ => "the first column: no column name says time; give --map to choose",
        };
        let _ = writeln!(s, "time column: `{}` ({why}; seconds = value × {})", tc.name, tc.to_s);
    }
    s
}

/// A number to `d` decimals, or `-`.
fn num(x: Option<f64>, d: usize) -> String {
    x.map_or_else(|| "-".to_string(), |x| format!("{x:.d$}"))
}

/// The topic table, each topic followed by its fields (with units where stated).
fn topics(r: &InspectReport) -> String {
    let w = r.log.topics.iter().map(|t| t.name.len()).max().unwrap_or(5).max(5);
    let mut s = format!(
        "\n{:<w$} {:>9} {:>9} {:>10} {:>12} {:>12} {:>11} {:>14} {:>5}\n",
        "topic",
        "samples",
        "messages",
        "rate_Hz",
        "first_s",
        "last_s",
        "median_dt_s",
        "longest_gap_s",
        "gaps"
    );
    for t in &r.log.topics {
        let m = &t.time;
        let gap = match (m.longest_gap_s, m.longest_gap_at_s) {
            (Some(g), Some(at)) => format!("{g:.3}@{at:.1}"),
            _ => "-".into(),
        };
        let _ = writeln!(
            s,
            "{:<w$} {:>9} {:>9} {:>10} {:>12} {:>12} {:>11} {:>14} {:>5}",
            t.name,
            m.samples,
            t.messages,
            num(m.rate_hz, 2),
            num(m.first_s, 3),
            num(m.last_s, 3),
            num(m.median_interval_s, 4),
            gap,
            m.gaps
        );
        s += &fields(t);
    }
    let _ = writeln!(
        s,
        "(gaps: intervals longer than {} × the median interval; longest_gap_s@its start, s)",
        r.log.gap_multiple
    );
    s
}

/// A topic's fields, wrapped, indented.
fn fields(t: &TopicSummary) -> String {
    let mut s = String::new();
    let mut line = String::from("    ");
    for f in &t.fields {
        let item = match &f.unit {
            Some(u) if !f.name.ends_with(']') || !f.name.contains(u.as_str()) => {
                format!("{} [{u}]", f.name)
            }
            _ => f.name.clone(),
        };
        if line.len() > 4 && line.len() + item.len() + 2 > WRAP {
            s += line.trim_end_matches(", ");
            s.push('\n');
            line = String::from("    ");
        }
        line += &item;
        line += ", ";
    }
    if line.len() > 4 {
        s += line.trim_end_matches(", ");
        s.push('\n');
    }
    s
}

/// The parameters, `NAME = value`, one a line.
fn parameters(r: &InspectReport) -> String {
    if r.log.parameters.is_empty() {
        return String::new();
    }
    let mut s = format!("\nparameters ({}):\n", r.log.parameters.len());
    for (k, v) in &r.log.parameters {
        let _ = writeln!(s, "  {k} = {v}");
    }
    s
}

/// The surfaces and their candidate manoeuvres as `--window` arguments.
fn manoeuvres(r: &InspectReport) -> String {
    let mut s = String::from("\ncandidate manoeuvres (detection rule: docs/inspect.md)\n");
    if let Some(h) = &r.surface_hint {
        let _ = writeln!(s, "  {h}");
    }
    for d in &r.detections {
        let role = r.surfaces.iter().find(|x| x.column == d.channel);
        let (role, source) = role.map_or(("", ""), |x| (x.role.as_str(), x.source.as_str()));
        let _ = writeln!(
            s,
            "  {} — {role} ({source}): quiet RMS {:.4}, threshold {:.4}: {} found",
            d.channel,
            d.quiet,
            d.threshold,
            d.manoeuvres.len()
        );
        s += &channel_manoeuvres(d);
    }
    s
}

/// One line per manoeuvre of a channel.
fn channel_manoeuvres(d: &ChannelDetection) -> String {
    let mut s = String::new();
    for m in &d.manoeuvres {
        let _ = writeln!(
            s,
            "    --window {:.2}:{:.2}   input {:.2}–{:.2} s, amplitude {:.4}, RMS {:.4}, \
             peak {:.2} Hz, 80 % of energy in {:.2}–{:.2} Hz",
            floor2(m.start_s),
            ceil2(m.end_s),
            m.active_start_s,
            m.active_end_s,
            m.amplitude,
            m.rms,
            m.peak_hz,
            m.band_hz[0],
            m.band_hz[1]
        );
    }
    s
}

/// `x` rounded down to 0.01 (a window start printed never cuts a sample off).
pub fn floor2(x: f64) -> f64 {
    (x * 100.0).floor() / 100.0
}

/// `x` rounded up to 0.01.
pub fn ceil2(x: f64) -> f64 {
    (x * 100.0).ceil() / 100.0
}
