//! Hostile records and mappings: one bad time stamp costs its own row only, a file without data
//! says so, mapping fields that would make a channel constant, doubled, absurd or reversed are
//! refused naming the file and the field, and an alignment whose table would not fit the memory
//! cap is refused before it is built.

use aeroident_io::align::{MAX_TABLE_BYTES, align};
use aeroident_io::flight_data::TIME_RUN_MAX;
use aeroident_io::mapping::Clock;
use aeroident_io::table::{Interpolation, Topic};
use aeroident_io::{FlightDataError, FlightDataReader, Mapping, RecordEvent, RowProblem};

use crate::common::shared::{shared, workspace};

const MAP: &str = "[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\n\
    vt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\n\
    q = { column = \"q\", unit = \"rad/s\" }\n\
    mass = { value = 1.0, unit = \"kg\" }\nS = { value = 1.0, unit = \"m2\" }\n\
    rho = { value = 1.0, unit = \"kg/m3\" }\n";

/// The events of `csv` read through `map`, every item unwrapped.
fn events(map: &str, csv: &str) -> Vec<RecordEvent> {
    let m = Mapping::from_toml_str(map, "m.toml").unwrap();
    FlightDataReader::new(csv.as_bytes(), "r.csv", &m).unwrap().map(|e| e.unwrap()).collect()
}

/// A record at the given times (V, α, q constant).
fn record(times: &[&str]) -> String {
    let mut csv = "t,V,a,q\n".to_string();
    for t in times {
        csv.push_str(&format!("{t},100,0.1,0.01\n"));
    }
    csv
}

/// What each event is, in order: `S t` sample, `R row kind`, `G row`.
fn outline(ev: &[RecordEvent]) -> Vec<String> {
    ev.iter()
        .map(|e| match e {
            RecordEvent::Sample { sample, .. } => format!("S {}", sample.t_s),
            RecordEvent::Rejected { row, problem } => format!("R {row} {}", problem.kind()),
            RecordEvent::Gap { row, .. } => format!("G {row}"),
        })
        .collect()
}

/// A time of 10000 s in the middle of a 0.1 s record is ahead of both neighbours: that row
/// alone is rejected, naming the time, both neighbours and the column; the record goes on.
#[test]
fn errors_isolated_time_jump_rejects_only_its_row() {
    let map = format!("nominal_dt_s = 0.1\n{MAP}");
    let ev = events(&map, &record(&["0", "0.1", "0.2", "10000", "0.3", "0.4"]));
    assert_eq!(
        outline(&ev),
        ["S 0", "S 0.1", "S 0.2", "R 5 time outlier", "S 0.3", "S 0.4"],
        "{ev:?}"
    );
    let RecordEvent::Rejected { problem, .. } = &ev[3] else { unreachable!() };
    assert_eq!(
        problem,
        &RowProblem::TimeOutlier {
            column: "t".into(),
            t_s: 10000.0,
            prev_t_s: Some(0.2),
            next_t_s: 0.3
        }
    );
    let text = problem.to_string();
    assert!(
        text.contains("column `t`") && text.contains("10000") && text.contains("0.3"),
        "{text}"
    );
}

/// A genuine gap (the times after it stay later) is a gap, not an outlier: no row is lost, and
/// the gap event precedes the sample after it. At the end of the record a jump has no next row
/// to judge it and is kept (as a gap).
#[test]
fn analytic_genuine_gap_and_last_row_jump_are_kept() {
    let map = format!("nominal_dt_s = 0.1\n{MAP}");
    let ev = events(&map, &record(&["0", "0.1", "5.0", "5.1", "5.2", "9.0"]));
    assert_eq!(outline(&ev), ["S 0", "S 0.1", "G 4", "S 5", "S 5.1", "S 5.2", "G 7", "S 9"]);
    let RecordEvent::Gap { dt_s, nominal_dt_s, .. } = ev[2] else { unreachable!() };
    assert!((dt_s - 4.9).abs() < 1e-12 && nominal_dt_s == 0.1, "{dt_s} {nominal_dt_s}");
}

/// Without `nominal_dt_s` the first interval fixes the nominal one: a bad time in the second
/// row would fix it at hours and reject the rest, so it is judged by the third row too. A row
/// whose time cannot be read does not settle the held time; the next readable one does.
#[test]
fn errors_bad_second_time_without_nominal_interval_costs_its_row() {
    let ev = events(MAP, &record(&["0", "10000", "", "0.1", "0.2", "0.3", "0.6"]));
    assert_eq!(
        outline(&ev),
        ["S 0", "R 3 time outlier", "R 4 blank value", "S 0.1", "S 0.2", "S 0.3", "G 8", "S 0.6"],
        "{ev:?}"
    );
}

/// A jump whose next rows repeat its time and go on from it is the record's own time (a gap)
/// once more than `TIME_RUN_MAX` samples follow it; the repeat and a later row going backwards
/// are rejected as before. With fewer, a row going on from before the jump rejects it, and the
/// repeat (judged against a time that was bad) with it.
#[test]
fn analytic_rows_after_a_jump_make_it_a_gap() {
    assert_eq!(TIME_RUN_MAX, 4);
    let map = format!("nominal_dt_s = 0.1\n{MAP}");
    let ev = events(&map, &record(&["0", "0.1", "3", "3", "3.1", "3.2", "3.3", "3.4", "0.2"]));
    assert_eq!(
        outline(&ev),
        [
            "S 0",
            "S 0.1",
            "G 4",
            "S 3",
            "R 5 repeated time",
            "S 3.1",
            "S 3.2",
            "S 3.3",
            "S 3.4",
            "R 10 time goes backwards"
        ],
        "{ev:?}"
    );
    let ev = events(&map, &record(&["0", "0.1", "3", "3", "3.1", "0.2", "0.3"]));
    assert_eq!(
        outline(&ev),
        [
            "S 0",
            "S 0.1",
            "R 4 time outlier",
            "R 5 time outlier",
            "R 6 time outlier",
            "S 0.2",
            "S 0.3"
        ],
        "{ev:?}"
    );
}

/// The HFB-320 record (601 rows at 0.1 s) with `time_s` = 10000 on data row 22 (line 23):
/// exactly that row is rejected, as a time outlier, and the other 600 rows are
/// samples at their own times.
#[test]
fn errors_hfb320_with_one_bad_time_keeps_600_samples() {
    let Some(ev) = hfb320_with_times(&[(23, "10000")]) else { return };
    let (rejected, times) = split(&ev);
    assert_eq!(rejected.len(), 1, "{rejected:?}");
    assert_eq!(rejected[0].0, 23);
    assert!(matches!(rejected[0].1, RowProblem::TimeOutlier { t_s: 10000.0, .. }));
    assert_eq!(times.len(), 600);
    // The one hole is the rejected row's: one sample missing from the 0.1 s grid, no gap (the
    // record goes on on its grid), not a 9998 s one.
    let gaps = gaps(&ev);
    assert!(gaps.is_empty(), "{gaps:?}");
    // Every interval is the record's 0.1 s except the 0.2 s across the rejected row.
    let long: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).filter(|d| *d > 0.15).collect();
    assert_eq!(long.len(), 1, "{long:?}");
    assert!((long[0] - 0.2).abs() < 1e-9);
}

/// The gap events of `ev`: (row after the gap, interval in s).
fn gaps(ev: &[RecordEvent]) -> Vec<(u64, f64)> {
    ev.iter()
        .filter_map(|e| match e {
            RecordEvent::Gap { row, dt_s, .. } => Some((*row, *dt_s)),
            _ => None,
        })
        .collect()
}

/// The HFB-320 record with the times of `lines` (line number, header = 1) replaced: its events.
fn hfb320_with_times(lines_times: &[(usize, &str)]) -> Option<Vec<RecordEvent>> {
    let path = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv")?;
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    assert_eq!(lines.len(), 602, "a header and 601 data rows");
    for (line, t) in lines_times {
        let (first, rest) = lines[line - 1].split_once(',').unwrap();
        // Data row k (line k + 1) is at 0.1 (k − 1) s.
        let want = 0.1 * (*line as f64 - 2.0);
        assert!((first.parse::<f64>().unwrap() - want).abs() < 1e-4, "line {line}: {first}");
        lines[line - 1] = format!("{t},{rest}");
    }
    let csv = lines.join("\n") + "\n";
    let m = Mapping::from_path(&workspace().join("mappings/hfb320.toml")).unwrap();
    let reader = FlightDataReader::new(csv.as_bytes(), "hfb320-bad-times.csv", &m).unwrap();
    Some(reader.map(|e| e.unwrap()).collect())
}

/// The rejections of `ev` (row, problem) and the times of its samples.
fn split(ev: &[RecordEvent]) -> (Vec<(u64, RowProblem)>, Vec<f64>) {
    let mut rejected = Vec::new();
    let mut times = Vec::new();
    for e in ev {
        match e {
            RecordEvent::Rejected { row, problem } => rejected.push((*row, problem.clone())),
            RecordEvent::Sample { sample, .. } => times.push(sample.t_s),
            RecordEvent::Gap { .. } => {}
        }
    }
    (rejected, times)
}

/// A time of 10000 s in the record's FIRST row has no previous time to be judged by; the rows
/// after it, all earlier, make it the bad one: that row alone is rejected, as a time outlier at
/// the record's start, and the 600 others are samples at their own 0.1 s intervals, no gap.
#[test]
fn errors_hfb320_with_a_bad_first_time_keeps_600_samples() {
    let Some(ev) = hfb320_with_times(&[(2, "10000")]) else { return };
    let (rejected, times) = split(&ev);
    assert_eq!(rejected.len(), 1, "{rejected:?}");
    assert_eq!(rejected[0].0, 2);
    assert_eq!(
        rejected[0].1,
        RowProblem::TimeOutlier {
            column: "time_s".into(),
            t_s: 10000.0,
            prev_t_s: None,
            next_t_s: 0.1
        }
    );
    let text = rejected[0].1.to_string();
    assert!(text.contains("10000") && text.contains("record's start"), "{text}");
    assert_eq!(times.len(), 600);
    assert!((times[0] - 0.1).abs() < 1e-9 && (times[599] - 60.0).abs() < 1e-4, "{times:?}");
    assert!(times.windows(2).all(|w| (w[1] - w[0] - 0.1).abs() < 1e-3));
    assert!(!ev.iter().any(|e| matches!(e, RecordEvent::Gap { .. })));
}

/// Two consecutive absurd times mid-record (10000, 10000.1 s on data rows 200–201) are a run
/// that the record goes on from before: both rows are rejected, each naming itself, and the
/// other 599 rows are samples; the one gap is the 0.3 s across the two rows.
#[test]
fn errors_hfb320_with_two_bad_times_keeps_599_samples() {
    let Some(ev) = hfb320_with_times(&[(201, "10000"), (202, "10000.1")]) else { return };
    let (rejected, times) = split(&ev);
    let rows: Vec<u64> = rejected.iter().map(|r| r.0).collect();
    assert_eq!(rows, [201, 202], "{rejected:?}");
    for ((_, problem), t) in rejected.iter().zip([10000.0, 10000.1]) {
        let RowProblem::TimeOutlier { t_s, prev_t_s, next_t_s, .. } = problem else {
            panic!("{problem}")
        };
        assert_eq!(*t_s, t);
        assert!((prev_t_s.unwrap() - 19.8).abs() < 1e-4 && (next_t_s - 20.1).abs() < 1e-4);
    }
    assert_eq!(times.len(), 599);
    let gaps = gaps(&ev);
    assert_eq!(gaps.len(), 1, "{gaps:?}");
    assert!(gaps[0].0 == 203 && (gaps[0].1 - 0.3).abs() < 1e-4, "{gaps:?}");
}

/// Runs of up to `TIME_RUN_MAX` bad times are rejected, one more is the record's own time (a
/// second segment of the record, which the rows after it must go on from).
#[test]
fn analytic_run_length_decides_between_bad_times_and_a_second_segment() {
    let map = format!("nominal_dt_s = 0.1\n{MAP}");
    let mut times = vec!["0", "0.1", "0.2"];
    let bad = ["500", "500.1", "500.2", "500.3"];
    times.extend(bad);
    times.extend(["0.3", "0.4"]);
    let ev = events(&map, &record(&times));
    let mut want = vec!["S 0".to_string(), "S 0.1".into(), "S 0.2".into()];
    want.extend((5..9).map(|r| format!("R {r} time outlier")));
    want.extend(["S 0.3".into(), "S 0.4".into()]);
    assert_eq!(outline(&ev), want, "{ev:?}");
    // One more sample after the jump: a genuine second segment; the rows going back are
    // rejected as going backwards, the segment is kept whole.
    times.insert(7, "500.4");
    let ev = events(&map, &record(&times));
    let mut want = vec!["S 0".to_string(), "S 0.1".into(), "S 0.2".into(), "G 5".into()];
    want.extend(bad.iter().chain(&["500.4"]).map(|t| format!("S {t}")));
    want.extend(["R 10 time goes backwards".into(), "R 11 time goes backwards".into()]);
    assert_eq!(outline(&ev), want, "{ev:?}");
}

/// A bad time a few rows after a genuine gap costs its own row (it starts a run of its own
/// within the segment after the gap; the hole of one sample it leaves is no gap); two bad
/// times in a row before the record goes on each cost their own row (a hole of two: a gap); a
/// bad SECOND row (earlier than the first) costs its own row, the first row kept.
#[test]
fn errors_bad_times_near_a_gap_or_the_start_cost_their_own_rows() {
    let map = format!("nominal_dt_s = 0.1\n{MAP}");
    let ev = events(&map, &record(&["0", "0.1", "5", "5.1", "1e4", "5.3", "5.4", "5.5", "5.6"]));
    assert_eq!(
        outline(&ev),
        [
            "S 0",
            "S 0.1",
            "G 4",
            "S 5",
            "S 5.1",
            "R 6 time outlier",
            "S 5.3",
            "S 5.4",
            "S 5.5",
            "S 5.6"
        ],
        "{ev:?}"
    );
    let ev = events(&map, &record(&["0", "0.1", "1e4", "5000", "0.4", "0.5"]));
    assert_eq!(
        outline(&ev),
        ["S 0", "S 0.1", "R 4 time outlier", "R 5 time outlier", "G 6", "S 0.4", "S 0.5"],
        "{ev:?}"
    );
    let ev = events(&map, &record(&["0", "-5", "0.2", "0.3", "0.4", "0.5", "0.6"]));
    assert_eq!(
        outline(&ev),
        ["S 0", "R 3 time goes backwards", "S 0.2", "S 0.3", "S 0.4", "S 0.5", "S 0.6"],
        "{ev:?}"
    );
}

/// A header without data rows, and an empty file, are "no data", naming the file, not "no
/// usable samples (0 rows rejected)".
#[test]
fn errors_file_without_data_says_so() {
    let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
    let all: Vec<Result<RecordEvent, FlightDataError>> =
        FlightDataReader::new("t,V,a,q\n".as_bytes(), "only-header.csv", &m).unwrap().collect();
    assert_eq!(all.len(), 1);
    let e = all[0].as_ref().unwrap_err().to_string();
    assert_eq!(e, "only-header.csv: the file has no data (a header row and no data rows)");
    let Err(e) = FlightDataReader::new("".as_bytes(), "empty.csv", &m) else { panic!() };
    assert!(e.to_string().starts_with("empty.csv: the file has no data (it is empty"), "{e}");
    // A file whose rows are all rejected is not "no data": its rejections are its events.
    let ev: Vec<_> =
        FlightDataReader::new("t,V,a,q\n0,,0.1,0\n".as_bytes(), "r.csv", &m).unwrap().collect();
    assert_eq!(ev.len(), 1);
    assert!(matches!(ev[0], Ok(RecordEvent::Rejected { row: 2, .. })), "{ev:?}");
}

/// The mapping error of `extra` added to the minimal mapping.
fn mapping_error(extra: &str) -> String {
    let text = format!("{MAP}{extra}");
    match Mapping::from_toml_str(&text, "m.toml") {
        Ok(_) => panic!("accepted: {extra}"),
        Err(e) => e.to_string(),
    }
}

/// Mapping fields that would double a channel, make it constant, absurd or reversed are
/// refused with the file and the field named.
#[test]
fn errors_mapping_fields_that_would_corrupt_a_channel() {
    let cases: &[(&str, &str)] = &[
        // The same column twice sums it twice (Cm_q would halve).
        (
            "p = { columns = [\"q_radps\", \"q_radps\"], unit = \"rad/s\" }\n",
            "m.toml: channel `p`: column `q_radps` is given twice",
        ),
        // A zero weight drops its column; all-zero weights make the channel constant.
        (
            "da = { columns = [\"l\", \"r\"], weights = [0.5, 0.0], unit = \"deg\" }\n",
            "m.toml: channel `da`: weight 2 (column `r`) is 0",
        ),
        (
            "r = { column = \"\", unit = \"rad/s\" }\n",
            "m.toml: channel `r`: a column name is empty",
        ),
        // A scale so small that scale × unit factor underflows to 0 (or overflows).
        (
            "p = { column = \"p\", unit = \"deg/s\", scale = 1e-320 }\n",
            "m.toml: channel `p`: scale 1e-320 × unit `deg/s`",
        ),
        (
            "p = { column = \"p\", unit = \"deg/s\", scale = nan }\n",
            "m.toml: channel `p`: scale NaN",
        ),
        (
            "thrust = { column = \"T\", unit = \"lbf\", scale = 1e308 }\n",
            "m.toml: channel `thrust`: scale 1e308 × unit `lbf`",
        ),
        // A calibration whose values are all equal is a constant; one that folds back maps two
        // raw values to one deflection.
        (
            "de = { column = \"pwm\", calibration = [[1000, 5.0], [2000, 5.0]], unit = \"deg\" }\n",
            "m.toml: channel `de`: calibration values are all 5",
        ),
        (
            "de = { column = \"pwm\", calibration = [[1000, -20.0], [1500, 0.0], [2000, -20.0]], unit = \"deg\" }\n",
            "m.toml: channel `de`: calibration values rise and fall",
        ),
        // The quaternion's components must be four different columns; so must the velocity's.
        (
            "[align]\nrate_hz = 50.0\nmethod = \"linear\"\n[attitude]\nquaternion = [\"a.q[0]\", \"a.q[0]\", \"a.q[0]\", \"a.q[0]\"]\n",
            "m.toml: channel `attitude.quaternion`: `a.q[0]` is given twice (components 1 and 2)",
        ),
        (
            "[align]\nrate_hz = 50.0\nmethod = \"linear\"\n[attitude]\nquaternion = [\"a.q[0]\", \"a.q[1]\", \"a.q[2]\", \"a.q[3]\"]\n[air_data]\nned_velocity = [\"p.vx\", \"p.vx\", \"p.vz\"]\n",
            "m.toml: channel `air_data.ned_velocity`: `p.vx` is given twice (components 1 and 2)",
        ),
        (
            "[align]\nrate_hz = 50.0\nmethod = \"linear\"\n[attitude]\nquaternion = [\"a.q[0]\", \"a.q[1]\", \"a.q[2]\", \"a.q[3]\"]\n[air_data]\nned_velocity = [\"p.vx\", \"p.vy\", \"p.vz\"]\nwind_ne = [\"w.n\", \"w.n\"]\n",
            "m.toml: channel `air_data.wind_ne`: `w.n` is given twice",
        ),
    ];
    for (extra, want) in cases {
        let e = mapping_error(extra);
        assert!(e.starts_with(want), "{extra}\n→ {e}\nwant {want}");
    }
}

/// The time channel must increase with the column: a negative scale reverses every interval
/// and a calibration has no meaning for a clock.
#[test]
fn errors_time_channel_reversed_or_calibrated() {
    let e = Mapping::from_toml_str(
        &MAP.replace("unit = \"s\"\n", "unit = \"s\"\nscale = -1.0\n"),
        "m.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("m.toml: channel `time`: `scale = -1`"), "{e}");
    let e = Mapping::from_toml_str(
        &MAP.replace("unit = \"s\"\n", "unit = \"s\"\ncalibration = [[0, 0], [1, 2]]\n"),
        "m.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("m.toml: channel `time`: `calibration`"), "{e}");
}

/// What the same checks let through: a sign flip, a weighted difference, a reversed servo
/// table with a dead band, a column reused by an expression.
#[test]
fn analytic_legitimate_mappings_still_parse() {
    for extra in [
        "p = { column = \"p\", unit = \"deg/s\", scale = -1.0 }\n",
        "da = { columns = [\"l\", \"r\"], weights = [0.5, -0.5], unit = \"deg\" }\n",
        "de = { column = \"pwm\", calibration = [[1000, 25.0], [1480, 0.0], [1520, 0.0], [2000, -25.0]], unit = \"deg\" }\n",
        "thrust = { expr = \"T * T / 1000\", unit = \"N\" }\n",
    ] {
        let text = format!("{MAP}{extra}");
        Mapping::from_toml_str(&text, "m.toml").unwrap_or_else(|e| panic!("{extra}: {e}"));
    }
}

/// `rate_hz = 2e6` over 20 s is 40 M rows, under the row guard, but 40 M × 16 columns × 8 bytes
/// = 5.1 GB: refused before anything is allocated, naming the field and the numbers.
#[test]
fn errors_alignment_over_the_memory_cap_is_refused_before_allocating() {
    let t: Vec<f64> = (0..=200).map(|k| f64::from(k) * 0.1).collect();
    let fields: Vec<(String, Vec<f64>)> =
        (0..15).map(|k| (format!("f{k}"), vec![0.0; t.len()])).collect();
    let topics = vec![Topic { name: "imu".into(), t_s: t, fields }];
    let e = align(&topics, &Clock::RateHz(2e6), Interpolation::Linear, "big.ulg").unwrap_err();
    let e = e.to_string();
    let rows: u64 = 40_000_001;
    let bytes = rows * 16 * 8;
    assert!(e.starts_with("big.ulg: alignment: [align] rate_hz = 2000000 Hz"), "{e}");
    assert!(e.contains(&format!("{rows} rows × 16 columns × 8 bytes = {bytes} bytes")), "{e}");
    assert!(e.contains(&MAX_TABLE_BYTES.to_string()), "{e}");
    // The same topics at 50 Hz fit.
    let ok = align(&topics, &Clock::RateHz(50.0), Interpolation::Linear, "big.ulg").unwrap();
    assert_eq!(ok.table.columns[0].len(), 1001);
}

/// Physically absurd aircraft constants are refused with the mapping file, the channel, the
/// line and the value named (after the unit conversion: slug and ft² are checked in SI); a
/// 1 g micro air vehicle's and an A380's constants pass. A column's value outside the range
/// rejects its row.
#[test]
fn errors_absurd_constants_are_refused_naming_file_field_and_value() {
    let minimal = MAP.replace("mass = { value = 1.0, unit = \"kg\" }\n", "");
    let refuse = |extra: &str, channel: &str, value: &str| {
        let text = format!("{minimal}{extra}\n");
        let e = Mapping::from_toml_str(&text, "absurd.toml").unwrap_err().to_string();
        assert!(e.starts_with(&format!("absurd.toml: channel `{channel}`: line ")), "{e}");
        assert!(e.contains(value) && e.contains("outside the physical range"), "{e}");
    };
    refuse("mass = { value = 1e-300, unit = \"kg\" }", "mass", "`value = 1e-300` kg");
    refuse("mass = { value = 1e9, unit = \"kg\" }", "mass", "1e9 kg");
    refuse("mass = { value = 1e9, unit = \"slug\" }", "mass", "`value = 1000000000.0` slug");
    let kg = "mass = { value = 1.0, unit = \"kg\" }\n";
    refuse(&format!("{kg}cbar = {{ value = 1e-9, unit = \"m\" }}"), "cbar", "1e-9 m");
    refuse(&format!("{kg}b = {{ value = 5e3, unit = \"m\" }}"), "b", "5e3 m");
    refuse(&format!("{kg}Iyy = {{ value = 1e12, unit = \"kg*m2\" }}"), "Iyy", "1e12 kg·m²");
    refuse(&format!("{kg}Ixz = {{ value = -1e11, unit = \"kg*m2\" }}"), "Ixz", "-1e11 kg·m²");
    let area =
        MAP.replace("S = { value = 1.0, unit = \"m2\" }", "S = { value = 2e6, unit = \"ft2\" }");
    let e = Mapping::from_toml_str(&area, "absurd.toml").unwrap_err().to_string();
    assert!(e.contains("channel `S`") && e.contains("1.858e5 m²"), "{e}");
    // A 1 g micro air vehicle and an A380, with margin.
    for (m, s, c, b, i) in [(1e-3, 1e-4, 1e-3, 1e-2, 1e-9), (5.75e5, 845.0, 12.0, 79.8, 1e8)] {
        let text = format!(
            "{minimal}mass = {{ value = {m}, unit = \"kg\" }}\ncbar = {{ value = {c}, unit = \"m\" }}\nb = {{ value = {b}, unit = \"m\" }}\nIyy = {{ value = {i}, unit = \"kg*m2\" }}\n"
        )
        .replace("S = { value = 1.0, unit = \"m2\" }", &format!("S = {{ value = {s}, unit = \"m2\" }}"));
        Mapping::from_toml_str(&text, "fine.toml").unwrap();
    }
    // From a column: the row is rejected, naming the column and the range.
    let map = format!("{}mass = {{ column = \"m\", unit = \"kg\" }}\n", minimal);
    let csv = "t,V,a,q,m\n0,100,0.1,0.01,5\n0.1,100,0.1,0.01,1e-300\n0.2,100,0.1,0.01,5\n";
    let ev = events(&map, csv);
    assert_eq!(outline(&ev), ["S 0", "R 3 value outside its domain", "S 0.2"]);
    let RecordEvent::Rejected { problem, .. } = &ev[1] else { unreachable!() };
    let text = problem.to_string();
    assert!(text.contains("column `m`") && text.contains("1e-300 kg is outside"), "{text}");
}

/// A time unit that makes the record's rate implausible is warned of (not an error), naming the
/// column, the declared unit and the unit that would give a plausible rate: a 10 Hz record in
/// seconds declared `ms` (median interval 0.0001 s: 10 kHz), a 100 Hz record in ms declared `s`
/// (10 s: 0.1 Hz). The right units give no warning; the record is read either way.
#[test]
fn errors_implausible_time_unit_is_warned_of_with_the_plausible_one() {
    let notes = |unit: &str, step: f64| {
        let map = MAP.replace("unit = \"s\"", &format!("unit = \"{unit}\""));
        let times: Vec<String> = (0..601).map(|k| format!("{}", k as f64 * step)).collect();
        let times: Vec<&str> = times.iter().map(String::as_str).collect();
        let m = Mapping::from_toml_str(&map, "unit.toml").unwrap();
        let csv = record(&times);
        let reader = FlightDataReader::new(csv.as_bytes(), "unit.csv", &m).unwrap();
        let handle = reader.notes();
        let n = reader.filter(|e| matches!(e, Ok(RecordEvent::Sample { .. }))).count();
        assert_eq!(n, 601, "every row read");
        handle.lock().unwrap().clone()
    };
    let n = notes("ms", 0.1);
    assert_eq!(n.len(), 1, "{n:?}");
    assert!(n[0].starts_with("unit.csv: time column `t` in `ms` (unit.toml [time])"), "{}", n[0]);
    assert!(n[0].contains("0.0001 s (10000 Hz)"), "{}", n[0]);
    assert!(n[0].contains("with `unit = \"s\"` it would be 0.1 s (10 Hz)"), "{}", n[0]);
    let n = notes("s", 10.0);
    assert_eq!(n.len(), 1, "{n:?}");
    assert!(
        n[0].contains("10 s (0.1 Hz)")
            && n[0].contains("`unit = \"ms\"` it would be 0.01 s (100 Hz)"),
        "{}",
        n[0]
    );
    assert!(notes("s", 0.1).is_empty());
    assert!(notes("ms", 10.0).is_empty());
    assert!(notes("us", 20_000.0).is_empty());
}
