//! `aeroident_io::inspect` against facts it does not compute itself: synthetic logs written
//! here with known rates, gaps, units and parameters, and the real PX4/ArduPilot logs of
//! `../shared/flightdata/px4_ardupilot/` against their independent inventories (written with
//! pyulog and pymavlink) and the F-16 log's parameter list.
//!
//! The shared logs are skipped with a message when `../shared` is absent; under `CI=true`
//! their absence fails.

use aeroident_io::inspect::{InspectOptions, Inspection, inspect_log};
use aeroident_io::log_contents::base_topic;
use std::collections::BTreeMap;
use std::path::PathBuf;

use crate::common::logs;
use crate::common::shared as shared_data;

use logs::{Dataflash, tlog_record};

/// A file under the system's temp directory, unique to this test process.
fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("aeroident-inspect-{}-{name}", std::process::id()))
}

fn inspect(path: &std::path::Path, keep: &[&str]) -> Inspection {
    let options =
        InspectOptions { keep: keep.iter().map(|s| s.to_string()).collect(), ..Default::default() };
    inspect_log(&path.display().to_string(), &options).unwrap()
}

/// A 50 Hz CSV over 0–20 s with three holes written in: 25 samples missing after 4.98 s (a
/// 0.52 s gap), 3 after 11.98 s (0.08 s: four intervals) and one after 15.0 s (0.04 s: two
/// intervals, under the 2.5-interval gap rule); one row whose time is text. Every count below
/// is the test's own count of what it wrote.
#[test]
fn csv_rates_gaps_units_and_a_bad_time_row_are_as_written() {
    let missing = |k: i64| (250..275).contains(&k) || (600..603).contains(&k) || k == 751;
    let times: Vec<f64> = (0..=1000).filter(|&k| !missing(k)).map(|k| k as f64 * 0.02).collect();
    let mut text = String::from("time [s],de [deg],q [rad/s],note\n");
    for (i, t) in times.iter().enumerate() {
        text += &format!("{t},{},{},x\n", (t * 3.0).sin(), i);
        if i == 100 {
            text += "oops,1,2,x\n";
        }
    }
    let path = temp("rates.csv");
    std::fs::write(&path, text).unwrap();
    let ins = inspect(&path, &["q [rad/s]"]);
    std::fs::remove_file(&path).ok();
    let t = &ins.summary.topics[0];
    assert_eq!(t.messages, times.len() + 1);
    assert_eq!(t.time.samples, times.len());
    let span = times[times.len() - 1] - times[0];
    assert!((t.time.rate_hz.unwrap() - (times.len() - 1) as f64 / span).abs() < 1e-9);
    assert!((t.time.median_interval_s.unwrap() - 0.02).abs() < 1e-9);
    assert!((t.time.longest_gap_s.unwrap() - 0.52).abs() < 1e-9, "{:?}", t.time);
    assert!((t.time.longest_gap_at_s.unwrap() - 4.98).abs() < 1e-9);
    assert_eq!(t.time.gaps, 2);
    let units: Vec<Option<&str>> = t.fields.iter().map(|f| f.unit.as_deref()).collect();
    assert_eq!(units, [Some("s"), Some("deg"), Some("rad/s"), None]);
    let tc = ins.summary.time_column.as_ref().unwrap();
    assert_eq!((tc.name.as_str(), tc.source.as_str()), ("time [s]", "name"));
    let notes = ins.summary.notes.join("\n");
    assert!(notes.contains("row 103: column `time [s]`: `oops` is not a finite time"), "{notes}");
    // The surface by its name and the channel asked for, with their values.
    assert_eq!(ins.surfaces.len(), 1);
    assert_eq!(
        (ins.surfaces[0].column.as_str(), ins.surfaces[0].role.as_str()),
        ("de [deg]", "elevator")
    );
    let q = ins.signals.iter().find(|s| s.column == "q [rad/s]").unwrap();
    assert_eq!(q.values[..3], [0.0, 1.0, 2.0]);
    assert_eq!(q.t_s.len(), times.len());
}

/// A channel the log lacks is an error naming the file and listing what it has.
#[test]
fn errors_a_missing_channel_names_the_file_and_the_columns() {
    let path = temp("missing.csv");
    std::fs::write(&path, "t,a\n0,1\n1,2\n").unwrap();
    let options = InspectOptions { keep: vec!["b".into()], ..Default::default() };
    let e = inspect_log(&path.display().to_string(), &options).unwrap_err().to_string();
    std::fs::remove_file(&path).ok();
    assert!(e.contains("missing.csv: no column `b` (columns: t, a)"), "{e}");
}

/// `FMT` payloads for the unit messages, as ArduPilot's `LogStructure.h` defines them.
fn unit_formats(d: &mut Dataflash) {
    d.fmt(177, 3 + 8 + 1 + 64, "UNIT", "QbZ", "TimeUS,Id,Label");
    d.fmt(172, 3 + 8 + 1 + 8, "MULT", "Qbd", "TimeUS,Id,Mult");
    d.fmt(176, 3 + 8 + 1 + 16 + 16, "FMTU", "QBNN", "TimeUS,FmtType,UnitIds,MultIds");
}

fn padded(s: &str, n: usize) -> Vec<u8> {
    let mut v = s.as_bytes().to_vec();
    v.resize(n, 0);
    v
}

/// A DataFlash log with `UNIT`/`MULT`/`FMTU` for an `IMU` type (`TimeUS` s, `GyrX` rad/s
/// float, `Raw` an unscaled int16 in deg × 0.01) at 100 Hz with one 0.5 s hole, a `PARM`
/// `SERVO2_FUNCTION = 19` and an `RCOU` whose `C2` is then the elevator; `UNIT` and `PARM`
/// topics are not kept but have their times.
#[test]
fn dataflash_units_times_and_servo_surfaces_are_as_written() {
    let mut d = Dataflash::new();
    unit_formats(&mut d);
    d.fmt(200, 3 + 8 + 4 + 2, "IMU", "Qfh", "TimeUS,GyrX,Raw");
    d.fmt(201, 3 + 8 + 16 + 4, "PARM", "QNf", "TimeUS,Name,Value");
    d.fmt(202, 3 + 8 + 2 + 2, "RCOU", "QHH", "TimeUS,C1,C2");
    for (t, (id, label)) in [(b's', "s"), (b'E', "rad/s"), (b'd', "deg")].into_iter().enumerate() {
        let mut p = (t as u64 + 1).to_le_bytes().to_vec();
        p.push(id);
        p.extend(padded(label, 64));
        d.msg(177, &p);
    }
    for (id, m) in [(b'-', 0.0f64), (b'B', 1e-2)] {
        let mut p = 1u64.to_le_bytes().to_vec();
        p.push(id);
        p.extend(m.to_le_bytes());
        d.msg(172, &p);
    }
    let mut p = 1u64.to_le_bytes().to_vec();
    p.push(200);
    p.extend(padded("sEd", 16));
    p.extend(padded("--B", 16));
    d.msg(176, &p);
    let mut p = 2u64.to_le_bytes().to_vec();
    p.extend(padded("SERVO2_FUNCTION", 16));
    p.extend(19f32.to_le_bytes());
    d.msg(201, &p);
    let written: Vec<u64> = (0..1000u64).filter(|k| !(300..350).contains(k)).collect();
    for &k in &written {
        let t_us = 1_000_000 + k * 10_000;
        let mut p = t_us.to_le_bytes().to_vec();
        p.extend(0.5f32.to_le_bytes());
        p.extend(1234i16.to_le_bytes());
        d.msg(200, &p);
        if k % 5 == 0 {
            let mut p = t_us.to_le_bytes().to_vec();
            let c2 = if (500..600).contains(&k) { 1700u16 } else { 1500 };
            p.extend(1500u16.to_le_bytes());
            p.extend(c2.to_le_bytes());
            d.msg(202, &p);
        }
    }
    let path = temp("units.bin");
    std::fs::write(&path, &d.0).unwrap();
    let ins = inspect(&path, &[]);
    std::fs::remove_file(&path).ok();
    let imu = ins.summary.topics.iter().find(|t| t.name == "IMU").unwrap();
    let units: BTreeMap<&str, Option<&str>> =
        imu.fields.iter().map(|f| (f.name.as_str(), f.unit.as_deref())).collect();
    assert_eq!(units, BTreeMap::from([("GyrX", Some("rad/s")), ("Raw", Some("deg ×1e-2"))]));
    assert_eq!(imu.time.samples, written.len());
    assert!((imu.time.longest_gap_s.unwrap() - 0.51).abs() < 1e-9, "{:?}", imu.time);
    assert!((imu.time.longest_gap_at_s.unwrap() - 3.99).abs() < 1e-9);
    assert_eq!(imu.time.gaps, 1);
    assert!((imu.time.rate_hz.unwrap() - (written.len() - 1) as f64 / 9.99).abs() < 1e-9);
    assert_eq!(ins.summary.parameters.get("SERVO2_FUNCTION"), Some(&19.0));
    let unit = ins.summary.topics.iter().find(|t| t.name == "UNIT").unwrap();
    assert_eq!(unit.time.samples, 3);
    assert_eq!(ins.surfaces.len(), 1, "{:?}", ins.surfaces);
    assert_eq!(
        (ins.surfaces[0].column.as_str(), ins.surfaces[0].role.as_str()),
        ("RCOU.C2", "elevator")
    );
    let c2 = ins.signals.iter().find(|s| s.column == "RCOU.C2").unwrap();
    assert_eq!(c2.values.iter().filter(|v| **v == 1700.0).count(), 20);
}

/// A file that is not DataFlash is an error naming the file and the byte.
#[test]
fn errors_not_a_log_names_the_file_and_byte() {
    let path = temp("garbage.bin");
    std::fs::write(&path, b"no header here at all").unwrap();
    let e = inspect_log(&path.display().to_string(), &InspectOptions::default())
        .unwrap_err()
        .to_string();
    std::fs::remove_file(&path).ok();
    assert!(e.contains("garbage.bin: byte 0: no DataFlash message"), "{e}");
    let path = temp("garbage.tlog");
    std::fs::write(&path, b"no MAVLink here either, just text").unwrap();
    let e = inspect_log(&path.display().to_string(), &InspectOptions::default())
        .unwrap_err()
        .to_string();
    std::fs::remove_file(&path).ok();
    assert!(e.contains("garbage.tlog: byte 0: no MAVLink telemetry record found"), "{e}");
}

/// One inventory line: name, count, mean rate, fields (ULog) or format and columns
/// (DataFlash).
struct Entry {
    name: String,
    samples: usize,
    rate_hz: f64,
    rest: Vec<String>,
}

fn inventory(rel: &str) -> Option<Vec<Entry>> {
    let text = std::fs::read_to_string(shared_data::shared(rel)?).unwrap();
    let body = text.lines().skip_while(|l| !l.starts_with("## ")).skip(1);
    Some(
        body.take_while(|l| !l.starts_with("##"))
            .filter(|l| !l.trim().is_empty())
            .map(|l| {
                let p: Vec<&str> = l.split_whitespace().collect();
                Entry {
                    name: p[0].strip_suffix("[0]").unwrap_or(p[0]).to_string(),
                    samples: p[1].parse().unwrap(),
                    rate_hz: p[2].parse().unwrap(),
                    rest: p[3..].iter().map(|s| s.to_string()).collect(),
                }
            })
            .collect(),
    )
}

/// The rate check: the inventory's one-decimal mean rate, whether it divides the samples or
/// the intervals by the span.
fn rate_agrees(ours: Option<f64>, e: &Entry) -> bool {
    let r = ours.unwrap_or(0.0);
    (r - e.rate_hz).abs() <= 0.05 + r / e.samples.max(1) as f64 + 1e-9
}

#[test]
fn ulog_f16_topics_fields_counts_rates_and_parameters_match_pyulog() {
    let rel = "px4_ardupilot/f16capstone_log_52_2021-5-22-12-42-56.ulg";
    let Some(path) = shared_data::shared(rel) else { return };
    let inv =
        inventory("px4_ardupilot/inventory/f16capstone_log_52_2021-5-22-12-42-56.ulg.txt").unwrap();
    let ins = inspect(&path, &[]);
    assert_eq!(ins.summary.topics.len(), inv.len());
    for e in &inv {
        let t = ins
            .summary
            .topics
            .iter()
            .find(|t| t.name == e.name)
            .unwrap_or_else(|| panic!("{}", e.name));
        let fields: Vec<&str> = t.fields.iter().map(|f| f.name.as_str()).collect();
        // pyulog lists nested `_padding` bytes as fields; they are not numeric data (the
        // reader's documented rule leaves them out).
        let expect: Vec<&str> =
            e.rest.iter().map(String::as_str).filter(|f| !f.contains("_padding")).collect();
        assert_eq!(fields, expect, "{}", e.name);
        assert_eq!(t.time.samples, e.samples, "{}", e.name);
        assert!(
            rate_agrees(t.time.rate_hz, e),
            "{}: {:?} vs {}",
            e.name,
            t.time.rate_hz,
            e.rate_hz
        );
        assert!(t.fields.iter().all(|f| f.unit.is_none()), "ULog states no units");
    }
    let params = std::fs::read_to_string(
        shared_data::shared(
            "px4_ardupilot/inventory/f16capstone_log_52_2021-5-22-12-42-56.params.csv",
        )
        .unwrap(),
    )
    .unwrap();
    let mut n = 0;
    for line in params.lines().filter(|l| !l.is_empty()) {
        let (name, value) = line.split_once(',').unwrap();
        let v: f64 = value.parse().unwrap();
        let ours = ins.summary.parameters[name];
        assert!((ours - v).abs() <= 1e-6 * v.abs().max(1.0), "{name}: {ours} vs {v}");
        n += 1;
    }
    assert_eq!(ins.summary.parameters.len(), n);
    // The known actuator topic's roll, pitch and yaw commands are the surfaces.
    let cols: Vec<&str> = ins.surfaces.iter().map(|s| s.column.as_str()).collect();
    assert_eq!(
        cols,
        [
            "actuator_controls_0.control[0]",
            "actuator_controls_0.control[1]",
            "actuator_controls_0.control[2]"
        ]
    );
}

#[test]
fn dataflash_types_counts_rates_fields_and_units_match_pymavlink() {
    let Some(path) = shared_data::shared("px4_ardupilot/pyflightcoach_center_0003.bin") else {
        return;
    };
    let inv = inventory("px4_ardupilot/inventory/pyflightcoach_center_0003.bin.txt").unwrap();
    let ins = inspect(&path, &[]);
    for e in inv.iter().filter(|e| e.rest[1].starts_with("TimeUS,")) {
        let parts: Vec<_> =
            ins.summary.topics.iter().filter(|t| base_topic(&t.name) == e.name).collect();
        let total: usize = parts.iter().map(|t| t.time.samples).sum();
        assert_eq!(total, e.samples, "{}", e.name);
        // The numeric fields: every column but TimeUS and the text ones (n, N, Z).
        let expect: Vec<&str> = e.rest[0]
            .chars()
            .zip(e.rest[1].split(','))
            .filter(|(c, name)| !"nNZ".contains(*c) && *name != "TimeUS")
            .map(|(_, name)| name)
            .collect();
        let fields: Vec<&str> = parts[0].fields.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(fields, expect, "{}", e.name);
        if parts.len() == 1 && e.samples > 10 && e.rate_hz < 1000.0 {
            assert!(
                rate_agrees(parts[0].time.rate_hz, e),
                "{}: {:?} vs {}",
                e.name,
                parts[0].time.rate_hz,
                e.rate_hz
            );
        }
    }
    // ArduPilot's LogStructure.h: ATT angles in degrees, GPS speed in m/s.
    let unit = |t: &str, f: &str| {
        let t = ins.summary.topics.iter().find(|x| x.name == t).unwrap();
        t.fields.iter().find(|x| x.name == f).unwrap().unit.clone()
    };
    assert_eq!(unit("ATT", "Roll").as_deref(), Some("deg"));
    assert_eq!(unit("GPS", "Spd").as_deref(), Some("m/s"));
    assert_eq!(ins.summary.parameters.get("SERVO2_FUNCTION"), Some(&19.0));
    assert!(ins.surfaces.is_empty(), "the log has no AETR, RCOU or SIDD: {:?}", ins.surfaces);
}

/// A MAVLink telemetry log written with the `mavlink` crate's own encoder: `ATTITUDE` at 50 Hz
/// (v2 frames) with a 0.5 s hole, `SERVO_OUTPUT_RAW` at 10 Hz (v1 frames) whose `servo2_raw`
/// is the elevator by `SERVO2_FUNCTION = 19` in a `PARAM_VALUE`, and six corrupt bytes: the
/// counts, the gap, ATTITUDE's fields as the MAVLink definition has them, the parameter, the
/// surface and the skipped bytes are what was written.
#[test]
fn tlog_topics_times_fields_parameters_and_corrupt_bytes_are_as_written() {
    use mavlink::MavlinkVersion::{V1, V2};
    use mavlink::dialects::ardupilotmega::{
        ATTITUDE_DATA, MavMessage, PARAM_VALUE_DATA, SERVO_OUTPUT_RAW_DATA,
    };
    let mut b = Vec::new();
    let t0 = 1_700_000_000_000_000u64;
    let param = PARAM_VALUE_DATA {
        param_id: "SERVO2_FUNCTION".into(),
        param_value: 19.0,
        ..Default::default()
    };
    tlog_record(&mut b, t0, V2, &MavMessage::PARAM_VALUE(param));
    let kept: Vec<u64> = (0..500).filter(|k| !(200..225).contains(k)).collect();
    let mut garbage_at = 0;
    for &k in &kept {
        let t = t0 + 1000 + k * 20_000;
        let att = ATTITUDE_DATA { time_boot_ms: k as u32 * 20, roll: 0.1, ..Default::default() };
        tlog_record(&mut b, t, V2, &MavMessage::ATTITUDE(att));
        if k % 5 == 0 {
            let raw =
                SERVO_OUTPUT_RAW_DATA { servo2_raw: 1500 + (k % 2) as u16, ..Default::default() };
            tlog_record(&mut b, t + 10, V1, &MavMessage::SERVO_OUTPUT_RAW(raw));
        }
        if k == 300 {
            garbage_at = b.len();
            b.extend([0x00, 0x11, 0x22, 0x33, 0x44, 0x55]);
        }
    }
    let path = temp("link.tlog");
    std::fs::write(&path, &b).unwrap();
    let ins = inspect(&path, &["ATTITUDE.roll"]);
    std::fs::remove_file(&path).ok();
    assert_eq!(ins.summary.format, "tlog");
    let att = ins.summary.topics.iter().find(|t| t.name == "ATTITUDE").unwrap();
    let fields: Vec<&str> = att.fields.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(
        fields,
        ["pitch", "pitchspeed", "roll", "rollspeed", "time_boot_ms", "yaw", "yawspeed"]
    );
    assert_eq!(att.time.samples, kept.len());
    assert!((att.time.longest_gap_s.unwrap() - 0.52).abs() < 1e-6, "{:?}", att.time);
    assert_eq!(att.time.gaps, 1);
    let servo = ins.summary.topics.iter().find(|t| t.name == "SERVO_OUTPUT_RAW").unwrap();
    assert_eq!(servo.time.samples, kept.iter().filter(|k| *k % 5 == 0).count());
    assert_eq!(ins.summary.parameters.get("SERVO2_FUNCTION"), Some(&19.0));
    assert_eq!(ins.surfaces.len(), 1);
    assert_eq!(ins.surfaces[0].column, "SERVO_OUTPUT_RAW.servo2_raw");
    let notes = ins.summary.notes.join("\n");
    assert!(notes.contains(&format!("byte {garbage_at}: 6 corrupt bytes skipped")), "{notes}");
    let roll = ins.signals.iter().find(|s| s.column == "ATTITUDE.roll").unwrap();
    assert!(roll.values.iter().all(|v| (*v - 0.1).abs() < 1e-7));
}

/// `NAMED_VALUE_FLOAT` messages of three names interleaved in a telemetry log (the live feed's
/// surfaces and thrust) are three topics, `NAMED_VALUE_FLOAT[de]` …, each with every value
/// written, as a live feed names them: one topic for all merged them, and 14 of 15 values of a
/// time were lost, so the live mapping could not read the recorded traffic.
#[test]
fn tlog_named_values_are_one_topic_per_name() {
    use mavlink::MavlinkVersion::V2;
    use mavlink::dialects::ardupilotmega::{MavMessage, NAMED_VALUE_FLOAT_DATA};
    let mut b = Vec::new();
    let t0 = 1_700_000_000_000_000u64;
    let names = ["de", "da", "thrust"];
    for k in 0..100u64 {
        for (j, name) in names.iter().enumerate() {
            let value = k as f32 * 0.01 + j as f32;
            let m =
                NAMED_VALUE_FLOAT_DATA { time_boot_ms: k as u32 * 20, name: (*name).into(), value };
            tlog_record(&mut b, t0 + k * 20_000 + j as u64, V2, &MavMessage::NAMED_VALUE_FLOAT(m));
        }
    }
    let path = temp("named.tlog");
    std::fs::write(&path, &b).unwrap();
    let columns: Vec<String> =
        names.iter().map(|n| format!("NAMED_VALUE_FLOAT[{n}].value")).collect();
    let ins = inspect(&path, &columns.iter().map(String::as_str).collect::<Vec<_>>());
    std::fs::remove_file(&path).ok();
    for (j, name) in names.iter().enumerate() {
        let topic = format!("NAMED_VALUE_FLOAT[{name}]");
        let t = ins.summary.topics.iter().find(|t| t.name == topic).unwrap_or_else(|| {
            panic!(
                "no {topic}: {:?}",
                ins.summary.topics.iter().map(|t| &t.name).collect::<Vec<_>>()
            )
        });
        assert_eq!(t.time.samples, 100, "{topic}");
        let column = format!("{topic}.value");
        let s = ins.signals.iter().find(|s| s.column == column).unwrap();
        for (k, v) in s.values.iter().enumerate() {
            let want = f64::from(k as f32 * 0.01 + j as f32);
            assert!((v - want).abs() < 1e-6, "{column}[{k}]: {v} vs {want}");
        }
    }
    assert!(ins.summary.topics.iter().all(|t| t.name != "NAMED_VALUE_FLOAT"));
}

/// A compressed `.mat` whose deflate stream holds carriage-return bytes (0x0D; the test checks
/// that it does) is read as it is: 400 rows of `time` and `x`. Inspect once passed `.mat`
/// files through the text formats' line-end conversion, which turned those bytes into line
/// feeds and the stream into "corrupt deflate stream" (the UAV-OAT team's `.mat` files).
#[test]
fn a_compressed_mat_with_carriage_return_bytes_is_read_as_it_is() {
    let n = 400;
    let time: Vec<f64> = (0..n).map(|k| k as f64 * 0.02).collect();
    let x: Vec<f64> = (0..n).map(|k| (k as f64 * 0.37).sin() * 13.0 + 13.0).collect();
    let vars = [
        logs::mat_compressed(&logs::mat_matrix("time", &[n as i32, 1], &time)),
        logs::mat_compressed(&logs::mat_matrix("x", &[n as i32, 1], &x)),
    ];
    assert!(vars.iter().any(|v| v[8..].contains(&b'\r')), "the test needs a CR byte in a stream");
    let path = temp("cr.mat");
    std::fs::write(&path, logs::mat_file(&vars)).unwrap();
    let r = inspect(&path, &[]);
    std::fs::remove_file(&path).ok();
    assert_eq!(r.summary.topics.len(), 1);
    assert_eq!(r.summary.topics[0].messages, n);
}
