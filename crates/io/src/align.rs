//! Multi-rate alignment: topics with their own timestamps onto one time base, as a [`Table`].
//!
//! # Method
//!
//! Output times are either a uniform grid at `rate_hz` over the span every topic covers
//! (`t_i = t_0 + i / rate_hz` from the latest first sample to the earliest last sample, each
//! time computed from `i`, not accumulated) or the timestamps of a chosen clock topic
//! ([`Clock`]). Each topic's value at an output time `t` is, with `t_k` its latest sample at or
//! before `t` and `h` its **hold interval** (`GAP_FACTOR` = 1.5 × the topic's median sample
//! interval, the gap threshold of [`crate::flight_data`]):
//!
//! - **no value** if `t` is before the topic's first sample, or if `t − t_k > h` (after the
//!   topic's last sample, or inside a gap in it): nothing is extrapolated or bridged;
//! - [`Interpolation::ZeroOrderHold`]: `x_k`, the value an on-board consumer would have seen;
//! - [`Interpolation::Linear`]: `x_k + (x_{k+1} − x_k)(t − t_k)/(t_{k+1} − t_k)` when the next
//!   sample exists and `t_{k+1} − t_k ≤ h`; otherwise (the last sample, or a gap follows) `x_k`,
//!   held for at most `h`. Exact on a ramp; error ≤ Δt²/8 · max|ẍ| on a smooth signal.
//!
//! A row in which any topic has no value is **dropped** (never filled with 0 or NaN); the
//! count, and which topic caused it, is in [`Aligned::dropped_by`]. A topic with one sample
//! has `h = 0`: it has a value only at its own timestamp.
//!
//! Columns are named `<topic>.<field>` ([`crate::table`]); the time column is
//! [`TIME_COLUMN`], in seconds. Use [`select`] first to keep only the columns a mapping needs:
//! a topic nobody needs must not drop rows.

use crate::FlightDataError;
use crate::flight_data::GAP_FACTOR;
/// The output time base, a setting of the mapping (`[time] rate_hz` or `clock`).
pub use crate::mapping::Clock;
use crate::table::{Interpolation, Table, Topic};
use std::collections::BTreeMap;

/// Name of the time column of an aligned table (seconds, the logs' time base).
pub const TIME_COLUMN: &str = "time_s";

/// Most rows an alignment may produce (a guard against a rate typo such as `5e6`).
pub const MAX_ROWS: usize = 50_000_000;

/// Most memory, bytes, the aligned table may take (`rows × columns × 8`, the time column
/// included): 1 GiB. A log at 200 Hz with 30 columns fits 6 hours; a rate typo such as
/// `rate_hz = 2e6` over a 20 s log (40 M rows × 16 columns = 5.1 GB) is refused before it is
/// allocated instead of exhausting the memory.
pub const MAX_TABLE_BYTES: u64 = 1 << 30;

/// Refuses a table of `rows` × `columns` `f64`s over [`MAX_TABLE_BYTES`]; `what` names the
/// setting that chose the rows (e.g. "[align] rate_hz = 2000000 Hz over 20 s").
fn check_table_size(
    rows: f64,
    columns: usize,
    what: &str,
    file: &str,
) -> Result<(), FlightDataError> {
    let bytes = rows * columns as f64 * 8.0;
    if bytes > MAX_TABLE_BYTES as f64 {
        return Err(FlightDataError::Align {
            file: file.to_string(),
            reason: format!(
                "{what} gives {rows} rows × {columns} columns × 8 bytes = {bytes} bytes, more than the cap of {MAX_TABLE_BYTES} bytes for an aligned table (lower the rate, or align on a clock topic)"
            ),
        });
    }
    Ok(())
}

/// An aligned table and what alignment left out.
#[derive(Debug, Clone, PartialEq)]
pub struct Aligned {
    /// Time column [`TIME_COLUMN`] first, then `<topic>.<field>` columns in topic order.
    pub table: Table,
    /// Output times considered (rows kept + dropped).
    pub rows_considered: usize,
    /// Rows dropped because a topic had no value there: topic → count (a row is counted for
    /// the first topic, in input order, that lacked a value).
    pub dropped_by: BTreeMap<String, usize>,
}

impl Aligned {
    /// Total rows dropped.
    pub fn dropped(&self) -> usize {
        self.dropped_by.values().sum()
    }
}

/// Hold interval of a topic: `GAP_FACTOR` × its median sample interval, 0 for one sample.
pub fn hold_interval_s(t_s: &[f64]) -> f64 {
    if t_s.len() < 2 {
        return 0.0;
    }
    let mut d: Vec<f64> = t_s.windows(2).map(|w| w[1] - w[0]).collect();
    d.sort_by(f64::total_cmp);
    GAP_FACTOR * d[d.len() / 2]
}

/// One topic's cursor over increasing output times.
struct Cursor<'a> {
    topic: &'a Topic,
    hold: f64,
    k: usize,
}

impl Cursor<'_> {
    /// Index `k` of the latest sample at or before `t` and the interpolation weight of `k+1`,
    /// or `None` if the topic has no value at `t`. `t` must not decrease between calls.
    fn at(&mut self, t: f64, method: Interpolation) -> Option<(usize, f64)> {
        let ts = &self.topic.t_s;
        if ts.is_empty() || t < ts[0] {
            return None;
        }
        while self.k + 1 < ts.len() && ts[self.k + 1] <= t {
            self.k += 1;
        }
        let k = self.k;
        if t - ts[k] > self.hold {
            return None;
        }
        match method {
            Interpolation::ZeroOrderHold => Some((k, 0.0)),
            Interpolation::Linear => {
                if k + 1 < ts.len() && ts[k + 1] - ts[k] <= self.hold && t > ts[k] {
                    Some((k, (t - ts[k]) / (ts[k + 1] - ts[k])))
                } else {
                    Some((k, 0.0))
                }
            }
        }
    }
}

/// Aligns `topics` onto one time base (method in the module doc). `file` names the log in
/// errors.
///
/// # Errors
/// [`FlightDataError::Align`] for no topics, a topic without samples or with times that do
/// not increase, a rate that is not finite and > 0 or that would give more than [`MAX_ROWS`]
/// rows, a table over [`MAX_TABLE_BYTES`] (checked before it is allocated), topics that do not overlap in time, or every row dropped (naming the topics);
/// [`FlightDataError::MissingTopic`] for a clock topic that is not among `topics`.
pub fn align(
    topics: &[Topic],
    clock: &Clock,
    method: Interpolation,
    file: &str,
) -> Result<Aligned, FlightDataError> {
    align_with_room(topics, clock, method, file, 0)
}

/// [`align`], counting `extra_columns` more columns of the table's length (columns the caller
/// derives from it afterwards) against [`MAX_TABLE_BYTES`].
///
/// # Errors
/// As [`align`].
pub fn align_with_room(
    topics: &[Topic],
    clock: &Clock,
    method: Interpolation,
    file: &str,
    extra_columns: usize,
) -> Result<Aligned, FlightDataError> {
    let bad = |reason: String| FlightDataError::Align { file: file.to_string(), reason };
    if topics.is_empty() {
        return Err(bad("no topics to align".into()));
    }
    for t in topics {
        if t.t_s.is_empty() {
            return Err(bad(format!("topic `{}` has no samples", t.name)));
        }
        if !t.t_s.iter().all(|x| x.is_finite()) || t.t_s.windows(2).any(|w| w[1] <= w[0]) {
            return Err(bad(format!("topic `{}`: times must be finite and increasing", t.name)));
        }
        if let Some((f, v)) = t.fields.iter().find(|(_, v)| v.len() != t.t_s.len()) {
            return Err(bad(format!(
                "topic `{}`: field `{f}` has {} values for {} times",
                t.name,
                v.len(),
                t.t_s.len()
            )));
        }
    }
    let columns = 1 + topics.iter().map(|t| t.fields.len()).sum::<usize>() + extra_columns;
    let times: Vec<f64> = match clock {
        Clock::RateHz(rate) => {
            if !(rate.is_finite() && *rate > 0.0) {
                return Err(bad(format!("rate {rate} Hz must be finite and > 0")));
            }
            let t0 = topics.iter().map(|t| t.t_s[0]).fold(f64::MIN, f64::max);
            let t1 =
                topics.iter().map(|t| *t.t_s.last().unwrap_or(&t.t_s[0])).fold(f64::MAX, f64::min);
            if t1 < t0 {
                let first = topics.iter().max_by(|a, b| a.t_s[0].total_cmp(&b.t_s[0]));
                let last = topics
                    .iter()
                    .min_by(|a, b| a.t_s[a.t_s.len() - 1].total_cmp(&b.t_s[b.t_s.len() - 1]));
                return Err(bad(format!(
                    "the topics do not overlap in time: `{}` starts at {t0} s after `{}` ends at {t1} s",
                    first.map_or("", |t| &t.name),
                    last.map_or("", |t| &t.name)
                )));
            }
            let n = ((t1 - t0) * rate).floor() + 1.0;
            let span = span_ends(topics, t0, t1);
            if n > MAX_ROWS as f64 {
                return Err(bad(format!(
                    "{rate} Hz over {} s ({span}) gives {n} rows (more than {MAX_ROWS})",
                    t1 - t0
                )));
            }
            let what = format!("[align] rate_hz = {rate} Hz over {} s ({span})", t1 - t0);
            check_table_size(n, columns, &what, file)?;
            (0..n as usize).map(|i| t0 + i as f64 / rate).filter(|t| *t <= t1).collect()
        }
        Clock::Topic(name) => {
            let t = topics.iter().find(|t| &t.name == name).ok_or_else(|| {
                FlightDataError::MissingTopic {
                    file: file.to_string(),
                    column: name.clone(),
                    needed_by: "the alignment clock".into(),
                    reason: format!(
                        "not among the aligned topics ({})",
                        topics.iter().map(|t| t.name.as_str()).collect::<Vec<_>>().join(", ")
                    ),
                }
            })?;
            let what = format!("[align] clock = `{name}`");
            check_table_size(t.t_s.len() as f64, columns, &what, file)?;
            t.t_s.clone()
        }
    };
    let mut cursors: Vec<Cursor> =
        topics.iter().map(|t| Cursor { topic: t, hold: hold_interval_s(&t.t_s), k: 0 }).collect();
    let mut names = vec![TIME_COLUMN.to_string()];
    for t in topics {
        names.extend(t.fields.iter().map(|(f, _)| format!("{}.{f}", t.name)));
    }
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    let mut dropped_by: BTreeMap<String, usize> = BTreeMap::new();
    let mut at: Vec<(usize, f64)> = vec![(0, 0.0); topics.len()];
    'rows: for &t in &times {
        for (i, c) in cursors.iter_mut().enumerate() {
            match c.at(t, method) {
                Some(kw) => at[i] = kw,
                None => {
                    *dropped_by.entry(c.topic.name.clone()).or_default() += 1;
                    continue 'rows;
                }
            }
        }
        columns[0].push(t);
        let mut col = 1;
        for (topic, &(k, w)) in topics.iter().zip(&at) {
            for (_, v) in &topic.fields {
                let x = if w > 0.0 { v[k] + (v[k + 1] - v[k]) * w } else { v[k] };
                columns[col].push(x);
                col += 1;
            }
        }
    }
    if columns[0].is_empty() {
        let why: Vec<String> =
            dropped_by.iter().map(|(t, n)| format!("`{t}` lacked {n}")).collect();
        return Err(bad(format!(
            "every one of the {} output times was dropped ({})",
            times.len(),
            why.join(", ")
        )));
    }
    Ok(Aligned {
        table: Table { file: file.to_string(), names, columns },
        rows_considered: times.len(),
        dropped_by,
    })
}

/// Which topics bound the common span `t0`–`t1` (the latest first sample, the earliest last
/// one), so that a span too long to align names the time stamps that make it so.
fn span_ends(topics: &[Topic], t0: f64, t1: f64) -> String {
    let named = |pick: fn(&Topic) -> f64, t: f64| {
        let names: Vec<String> =
            topics.iter().filter(|x| pick(x) == t).map(|x| format!("`{}`", x.name)).collect();
        names.join(", ")
    };
    let first = named(|x| x.t_s[0], t0);
    let last = named(|x| x.t_s[x.t_s.len() - 1], t1);
    format!("from {t0} s, where {first} starts, to {t1} s, where {last} ends")
}

/// Splits a column name `<topic>.<field>` (the topic may carry `[instance]`; `topic[0]` is
/// the same topic as `topic`).
pub fn split_column(column: &str) -> Option<(String, &str)> {
    let (topic, field) = column.split_once('.')?;
    let topic = topic.strip_suffix("[0]").unwrap_or(topic);
    (!topic.is_empty() && !field.is_empty()).then(|| (topic.to_string(), field))
}

/// The topics holding `columns` (`(column, needed by)` pairs, e.g. `("vehicle_attitude.q[0]",
/// "channel `phi`")`), each with only the needed fields, in order of first need.
///
/// # Errors
/// [`FlightDataError::MissingTopic`] naming the column, what needs it and what the log has
/// instead (the topics, or the topic's fields).
pub fn select(
    topics: &[Topic],
    columns: &[(String, String)],
    file: &str,
) -> Result<Vec<Topic>, FlightDataError> {
    let missing = |column: &str, needed_by: &str, reason: String| FlightDataError::MissingTopic {
        file: file.to_string(),
        column: column.to_string(),
        needed_by: needed_by.to_string(),
        reason,
    };
    let mut out: Vec<Topic> = Vec::new();
    for (column, needed_by) in columns {
        let (tname, field) = split_column(column).ok_or_else(|| {
            missing(column, needed_by, "not a `<topic>.<field>` column name".into())
        })?;
        let topic = topics.iter().find(|t| t.name == tname).ok_or_else(|| {
            let mut have: Vec<&str> = topics.iter().map(|t| t.name.as_str()).collect();
            have.sort_unstable();
            missing(
                column,
                needed_by,
                format!("the log has no topic/message `{tname}` (it has: {})", have.join(", ")),
            )
        })?;
        let (_, values) = topic.fields.iter().find(|(f, _)| f == field).ok_or_else(|| {
            let have: Vec<&str> = topic.fields.iter().map(|(f, _)| f.as_str()).collect();
            missing(
                column,
                needed_by,
                format!("topic `{tname}` has no field `{field}` (it has: {})", have.join(", ")),
            )
        })?;
        let i = match out.iter().position(|t| t.name == tname) {
            Some(i) => i,
            None => {
                out.push(Topic { name: tname, t_s: topic.t_s.clone(), fields: Vec::new() });
                out.len() - 1
            }
        };
        if !out[i].fields.iter().any(|(f, _)| f == field) {
            out[i].fields.push((field.to_string(), values.clone()));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn topic(name: &str, t_s: Vec<f64>, f: impl Fn(f64) -> f64) -> Topic {
        let v = t_s.iter().map(|&t| f(t)).collect();
        Topic { name: name.into(), t_s, fields: vec![("x".into(), v)] }
    }

    fn grid(t0: f64, dt: f64, n: usize) -> Vec<f64> {
        (0..n).map(|i| t0 + i as f64 * dt).collect()
    }

    fn col<'a>(a: &'a Aligned, name: &str) -> &'a [f64] {
        let i = a.table.names.iter().position(|n| n == name).unwrap();
        &a.table.columns[i]
    }

    #[test]
    fn analytic_linear_is_exact_on_ramps_sampled_at_two_rates() {
        // 100 Hz and 30 Hz ramps, aligned at 50 Hz.
        let a = topic("a", grid(0.0, 0.01, 301), |t| 2.0 * t - 1.0);
        let b = topic("b", grid(0.005, 1.0 / 30.0, 90), |t| -3.0 * t + 0.5);
        let out = align(&[a, b], &Clock::RateHz(50.0), Interpolation::Linear, "m").unwrap();
        let t = col(&out, TIME_COLUMN);
        assert_eq!(out.dropped(), 0);
        assert!((t[0] - 0.005).abs() < 1e-15, "starts where both topics have data");
        assert!(t.len() > 140);
        for (i, &ti) in t.iter().enumerate() {
            assert!((col(&out, "a.x")[i] - (2.0 * ti - 1.0)).abs() < 1e-12);
            assert!((col(&out, "b.x")[i] - (-3.0 * ti + 0.5)).abs() < 1e-12);
        }
    }

    #[test]
    fn analytic_linear_error_on_a_sine_is_within_the_second_derivative_bound() {
        // |error| ≤ Δt²/8 · max|ẍ| = Δt²/8 · ω² for sin(ω t).
        let w = 2.0 * std::f64::consts::PI * 1.5;
        let dt = 0.02;
        let s = topic("s", grid(0.0, dt, 200), |t| (w * t).sin());
        let c = topic("c", grid(0.0, 0.001, 3900), |_| 0.0);
        let out = align(&[c, s], &Clock::Topic("c".into()), Interpolation::Linear, "m").unwrap();
        let bound = dt * dt / 8.0 * w * w;
        let mut worst: f64 = 0.0;
        for (t, x) in col(&out, TIME_COLUMN).iter().zip(col(&out, "s.x")) {
            worst = worst.max((x - (w * t).sin()).abs());
        }
        assert!(worst <= bound * (1.0 + 1e-9), "{worst} > {bound}");
        assert!(worst > 0.5 * bound, "the bound is nearly reached: {worst} vs {bound}");
    }

    #[test]
    fn analytic_zero_order_hold_gives_the_latest_sample_at_or_before() {
        let s = topic("s", grid(0.0, 0.1, 21), |t| (3.0 * t).sin());
        let c = topic("c", grid(0.005, 0.01, 200), |_| 0.0);
        let out =
            align(&[c, s], &Clock::Topic("c".into()), Interpolation::ZeroOrderHold, "m").unwrap();
        assert_eq!(out.table.columns[0].len(), 200);
        for (t, x) in col(&out, TIME_COLUMN).iter().zip(col(&out, "s.x")) {
            let k = (t / 0.1).floor();
            assert_eq!(*x, (3.0 * (k * 0.1)).sin(), "t = {t}");
        }
    }

    #[test]
    fn no_value_before_first_sample_and_no_hold_beyond_one_interval() {
        // Clock 0.005..2.995 s at 100 Hz; `late` covers 1.0..2.0 s at 10 Hz (hold 0.15 s).
        let c = topic("c", grid(0.005, 0.01, 300), |t| t);
        let late = topic("late", grid(1.0, 0.1, 11), |t| 10.0 * t);
        for method in [Interpolation::Linear, Interpolation::ZeroOrderHold] {
            let out =
                align(&[c.clone(), late.clone()], &Clock::Topic("c".into()), method, "m").unwrap();
            let t = col(&out, TIME_COLUMN);
            assert!((t[0] - 1.005).abs() < 1e-12, "{method:?}: first row after the first sample");
            let last = *t.last().unwrap();
            assert!((last - 2.145).abs() < 1e-12, "{method:?}: held 1.5 intervals: {last}");
            // Past 2.0 s the last value is held, never extrapolated.
            for (ti, x) in t.iter().zip(col(&out, "late.x")) {
                if *ti > 2.0 + 1e-9 {
                    assert_eq!(*x, 20.0);
                }
            }
            // Rows before 1.0 s (100) and after 2.15 s (85) are dropped and counted.
            assert_eq!(out.dropped_by["late"], 100 + 85, "{method:?}");
            assert_eq!(out.rows_considered, 300);
            assert_eq!(t.len(), 300 - 185);
        }
    }

    #[test]
    fn a_gap_in_a_topic_is_not_bridged() {
        let c = topic("c", grid(0.005, 0.01, 400), |t| t);
        let mut ts = grid(0.0, 0.1, 11);
        ts.extend(grid(3.0, 0.1, 11));
        let g = topic("g", ts, |t| t);
        let out = align(&[c, g], &Clock::Topic("c".into()), Interpolation::Linear, "m").unwrap();
        let t = col(&out, TIME_COLUMN);
        assert!(t.iter().all(|&x| x <= 1.15 + 1e-9 || x >= 3.0 - 1e-9), "nothing in the gap");
        // Clock times 1.155..2.995 s (185) have no value of `g`.
        assert_eq!(out.dropped_by["g"], 185);
    }

    /// A span too long to align names the topics and time stamps that bound it.
    #[test]
    fn errors_span_too_long_names_its_topics_and_times() {
        let b = topic("b", [grid(0.5, 0.1, 10), vec![86_400.0]].concat(), |t| t);
        let d = topic("d", grid(0.0, 0.1, 900_000), |t| t);
        let e = align(&[b, d], &Clock::RateHz(1000.0), Interpolation::Linear, "log.ulg")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("over 86399.5 s (from 0.5 s, where `b` starts, to 86400 s, where `b` ends)"),
            "{e}"
        );
    }

    #[test]
    fn errors_name_the_problem() {
        let a = topic("a", grid(0.0, 0.1, 10), |t| t);
        let e =
            align(std::slice::from_ref(&a), &Clock::RateHz(0.0), Interpolation::Linear, "log.ulg")
                .unwrap_err()
                .to_string();
        assert!(e.starts_with("log.ulg: alignment: rate 0 Hz"), "{e}");
        let e = align(
            std::slice::from_ref(&a),
            &Clock::Topic("imu".into()),
            Interpolation::Linear,
            "log.ulg",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("`imu` for the alignment clock") && e.contains("(a)"), "{e}");
        let b = topic("b", grid(5.0, 0.1, 10), |t| t);
        let e = align(&[a.clone(), b], &Clock::RateHz(10.0), Interpolation::Linear, "log.ulg")
            .unwrap_err()
            .to_string();
        assert!(e.contains("do not overlap") && e.contains("`b` starts at 5"), "{e}");
        let e =
            select(std::slice::from_ref(&a), &[("a.y".into(), "channel `q`".into())], "log.ulg")
                .unwrap_err()
                .to_string();
        assert_eq!(e, "log.ulg: `a.y` for channel `q`: topic `a` has no field `y` (it has: x)");
        let e = select(&[a], &[("ATT.Roll".into(), "channel `phi`".into())], "log.bin")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`ATT.Roll` for channel `phi`: the log has no topic/message `ATT`"),
            "{e}"
        );
    }

    #[test]
    fn select_keeps_needed_fields_and_reads_instance_zero_as_the_bare_topic() {
        let mut a = topic("act", grid(0.0, 0.1, 3), |t| t);
        a.fields.push(("y".into(), vec![7.0, 8.0, 9.0]));
        let s =
            select(&[a], &[("act[0].y".into(), "de".into()), ("act.y".into(), "da".into())], "m")
                .unwrap();
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].fields, vec![("y".to_string(), vec![7.0, 8.0, 9.0])]);
    }
}
