//! The text `aeroident inspect` prints: the same content as its `--json` document.

use aeroident_io::inspect::TopicSummary;
use aeroident_pipelines::inspect::InspectReport;
use aeroident_pipelines::inspect::detect::ChannelDetection;
use aeroident_pipelines::inspect::envelope::Envelope;
use aeroident_pipelines::inspect::information::Axis;
use aeroident_pipelines::inspect::rank::{Candidate, Ranking};
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
    s += &flight(r);
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
    if let Some(e) =
        r.flight.as_ref().and_then(|f| f.envelope.as_ref()).filter(|e| !e.ground.is_empty())
    {
        let spans: Vec<String> =
            e.ground.iter().map(|g| format!("{:.2}–{:.2} s", g.start_s, g.end_s)).collect();
        let _ = writeln!(
            s,
            "  (levels of the flight part; the ground spans {} are judged apart, their candidates left out below)",
            spans.join(", ")
        );
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

/// The flight-terms judgement: ground spans, phugoids, ranks per axis, window sets; or why
/// there is none.
fn flight(r: &InspectReport) -> String {
    let mut s = String::from("\nin flight terms (docs/inspect.md, \"Ranked\")\n");
    let Some(f) = &r.flight else {
        let _ = writeln!(s, "  not judged: {}", r.flight_note.as_deref().unwrap_or("-"));
        return s;
    };
    match &f.envelope {
        Some(e) => s += &envelope(e),
        None => s += "  no airspeed: nothing left out as ground\n",
    }
    for axis in Axis::ALL {
        s += &ranked(f, axis);
    }
    let out: Vec<&Candidate> = f.candidates.iter().filter(|c| c.excluded.is_some()).collect();
    if !out.is_empty() {
        let _ = writeln!(s, "  left out ({}):", out.len());
        for c in out {
            let scores: Vec<String> = Axis::ALL
                .iter()
                .filter_map(|&a| Some(format!("{} {:.2e}", a.name(), c.info(a)?.score?)))
                .collect();
            let scores =
                if scores.is_empty() { "identifies no axis".into() } else { scores.join(", ") };
            let _ = writeln!(
                s,
                "    {}  {} — {}; it would have scored {scores}",
                window(c.start_s, c.end_s),
                what(c),
                c.excluded.as_deref().unwrap_or("")
            );
        }
    }
    let _ = writeln!(
        s,
        "  window sets, the best {} per axis (fit a set's windows together, each its own manoeuvre; `--window auto:{}` fits every axis's):",
        f.set_size, f.set_size
    );
    for (axis, set) in &f.window_sets {
        let args: Vec<String> = set.iter().map(|w| window(w[0], w[1])).collect();
        let text = if args.is_empty() { "none identifies it".to_string() } else { args.join(" ") };
        let _ = writeln!(s, "    {axis}: {text}");
    }
    s
}

/// The airborne speed, the floors and the spans left out.
fn envelope(e: &Envelope) -> String {
    let mut s = format!(
        "  airborne speed {:.1} m/s (median of the samples above half the 95 % airspeed); on the \
         ground below {:.1} m/s ({} × it)",
        e.airborne_speed_mps, e.min_speed_mps, e.rule.speed_fraction
    );
    if let Some(q) = e.min_qbar_pa {
        let _ =
            write!(s, " or below q̄ {q:.0} Pa ({}² × W/(S·{}))", e.rule.stall_margin, e.rule.cl_max);
    }
    let _ = writeln!(s, ", widened by {} s", e.rule.margin_s);
    if e.ground.is_empty() {
        s += "  ground spans: none (all of the record is flight)\n";
    }
    for g in &e.ground {
        let throttle =
            g.throttle.map_or(String::new(), |[a, b]| format!(", throttle {a:.2}–{b:.2}"));
        let _ = writeln!(
            s,
            "  ground span: {} {:.2}–{:.2} s (airspeed up to {:.1} m/s{throttle}): its candidates left out",
            g.kind, g.start_s, g.end_s, g.max_speed_mps
        );
    }
    s
}

/// The ranked list of one axis.
fn ranked(f: &Ranking, axis: Axis) -> String {
    let order = f.ranked.get(axis.name()).map_or(&[][..], Vec::as_slice);
    let mut s = format!(
        "  ranked for {} (score: geometric mean of the derivatives' Cramér–Rao σ; lower holds more): {} candidate(s)\n",
        axis.name(),
        order.len()
    );
    for (k, &i) in order.iter().enumerate() {
        let c = &f.candidates[i];
        let Some(info) = c.info(axis) else { continue };
        let sigmas: Vec<String> = info.sigma.iter().map(|(n, v)| format!("{n} {v:.2e}")).collect();
        let still = if info.not_identified.is_empty() {
            String::new()
        } else {
            format!("; not identified: {}", info.not_identified.join(", "))
        };
        let _ = writeln!(
            s,
            "    {:>2}. {}  {}  score {:.2e} (σ {}{}{still})",
            k + 1,
            window(c.start_s, c.end_s),
            what(c),
            info.score.unwrap_or(f64::NAN),
            sigmas.join(", "),
            if info.nondimensional { "" } else { "; scaled by q̄ and V only" }
        );
    }
    s
}

/// A candidate's kind and channels (or its phugoid).
fn what(c: &Candidate) -> String {
    match &c.phugoid {
        Some(p) => {
            let pull = match (p.pull_at_s, p.pull_rad) {
                (Some(at), Some(d)) => {
                    format!(", elevator {:+.2}° held from {at:.1} s", d.to_degrees())
                }
                _ => String::new(),
            };
            format!("phugoid (period {:.0} s, ±{:.1} m/s{pull})", p.period_s, p.amplitude_mps)
        }
        None => format!("input on {}", c.channels.join(", ")),
    }
}

/// `--window START:END`, rounded outwards to 0.01 s.
fn window(a: f64, b: f64) -> String {
    format!("--window {:.2}:{:.2}", floor2(a), ceil2(b))
}
