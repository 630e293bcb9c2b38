//! The multi-rate log readers on the real PX4 ULog and ArduPilot DataFlash logs in
//! `../shared/flightdata/px4_ardupilot/` (read its README): every topic / message type, its
//! sample count and its field names against the independent inventories shipped beside the
//! logs (`inventory/*.txt`, written with pyulog and pymavlink), and the F-16 log's parameters
//! against `inventory/…params.csv`.
//!
//! Skips with a message when `../shared` is absent; fails under `CI=true`.

use aeroident_io::dataflash::read_dataflash_contents;
use aeroident_io::table::Topic;
use aeroident_io::ulog::read_ulog_contents;
use std::collections::BTreeMap;
use std::path::PathBuf;

fn shared(rel: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/flightdata/px4_ardupilot")
        .join(rel);
    if p.exists() {
        Some(p)
    } else {
        assert!(
            std::env::var("CI").map_or(true, |v| v != "true"),
            "{} is absent under CI",
            p.display()
        );
        eprintln!(
            "SKIPPED: {} is absent (CI provides ../shared beside the repository)",
            p.display()
        );
        None
    }
}

/// One inventory line: name as the reader names it, sample count, field names.
struct Entry {
    name: String,
    samples: usize,
    fields: Vec<String>,
}

/// Parses the `## topics` / `## message types` table of an inventory file. ULog names
/// `x[0]` become `x` (instance 0 is the bare topic name in the reader's naming).
fn inventory(rel: &str) -> Vec<Entry> {
    let text = std::fs::read_to_string(shared(rel).unwrap()).unwrap();
    let mut out = Vec::new();
    let mut on = false;
    for line in text.lines() {
        if line.starts_with("## topics") || line.starts_with("## message types") {
            on = true;
            continue;
        }
        if line.starts_with("##") {
            on = false;
        }
        if !on || line.trim().is_empty() {
            continue;
        }
        let parts: Vec<&str> = line.split_whitespace().collect();
        let name = parts[0].strip_suffix("[0]").unwrap_or(parts[0]).to_string();
        let samples = parts[1].parse().unwrap();
        let fields = if rel.ends_with(".ulg.txt") {
            parts[3..].iter().map(|s| s.to_string()).collect()
        } else {
            // DataFlash: NAME count rate format columns
            parts.get(4).map_or(vec![], |c| c.split(',').map(str::to_string).collect())
        };
        out.push(Entry { name, samples, fields });
    }
    out
}

fn by_name(topics: &[Topic]) -> BTreeMap<&str, &Topic> {
    topics.iter().map(|t| (t.name.as_str(), t)).collect()
}

#[test]
fn ulog_f16_every_topic_count_and_field_matches_the_inventory() {
    let Some(path) = shared("f16capstone_log_52_2021-5-22-12-42-56.ulg") else { return };
    let c = read_ulog_contents(&path).unwrap();
    let inv = inventory("inventory/f16capstone_log_52_2021-5-22-12-42-56.ulg.txt");
    let topics = by_name(&c.topics);
    assert_eq!(topics.len(), inv.len(), "{:?}", topics.keys().collect::<Vec<_>>());
    for e in &inv {
        let t = topics.get(e.name.as_str()).unwrap_or_else(|| panic!("{} missing", e.name));
        let dropped = c.dropped.get(&e.name).copied().unwrap_or(0);
        assert_eq!(t.t_s.len() + dropped, e.samples, "{}", e.name);
        let names: Vec<&str> = t.fields.iter().map(|(n, _)| n.as_str()).collect();
        // The reader leaves padding out; pyulog lists nested padding.
        let want: Vec<&str> =
            e.fields.iter().map(String::as_str).filter(|f| !f.contains("_padding")).collect();
        assert_eq!(names, want, "{}", e.name);
        assert!(t.t_s.windows(2).all(|w| w[1] > w[0]), "{} increasing", e.name);
    }
    // Time base: µs since boot → s; the inventory's start 598659116 us, duration 60.043 s.
    let sc = topics["sensor_combined"];
    assert!((sc.t_s[0] - 598.659).abs() < 0.1, "{}", sc.t_s[0]);
    let span = sc.t_s.last().unwrap() - sc.t_s[0];
    assert!((59.5..60.1).contains(&span), "{span}");
    assert_eq!(c.truncated_at, None);
}

#[test]
fn ulog_f16_parameters_match_the_params_csv() {
    let Some(path) = shared("f16capstone_log_52_2021-5-22-12-42-56.ulg") else { return };
    let c = read_ulog_contents(&path).unwrap();
    let csv = std::fs::read_to_string(
        shared("inventory/f16capstone_log_52_2021-5-22-12-42-56.params.csv").unwrap(),
    )
    .unwrap();
    let mut n = 0;
    for line in csv.lines() {
        let Some((k, v)) = line.split_once(',') else { continue };
        let Ok(v) = v.parse::<f64>() else { continue };
        let got = c.parameters.get(k).unwrap_or_else(|| panic!("parameter {k} missing"));
        assert!((got - v).abs() <= 1e-6 * v.abs().max(1.0), "{k}: {got} vs {v}");
        n += 1;
    }
    assert!(n > 700, "{n} parameters compared");
    assert_eq!(c.parameters["PWM_MAIN_REV2"], 1.0);
    assert_eq!(c.parameters["SYS_AUTOSTART"], 2100.0);
}

#[test]
fn ulog_vtol_every_topic_count_matches_and_early_timestamps_do_not_wrap() {
    let Some(path) = shared("pyulog_sample_log_small.ulg") else { return };
    let c = read_ulog_contents(&path).unwrap();
    let inv = inventory("inventory/pyulog_sample_log_small.ulg.txt");
    let topics = by_name(&c.topics);
    assert_eq!(topics.len(), inv.len());
    for e in &inv {
        let t = topics.get(e.name.as_str()).unwrap_or_else(|| panic!("{} missing", e.name));
        let dropped = c.dropped.get(&e.name).copied().unwrap_or(0);
        assert_eq!(t.t_s.len() + dropped, e.samples, "{}", e.name);
    }
    // The README's pitfall: topics stamped before the file start (20.309 s) stay before it.
    for name in ["vehicle_command", "sensor_selection", "position_setpoint_triplet", "test_motor"] {
        let t0 = topics[name].t_s[0];
        assert!(t0 < 20.309 && t0 >= 0.0, "{name}: {t0}");
    }
    assert!(topics.contains_key("actuator_outputs[1]"));
    assert!((topics["vehicle_angular_velocity"].t_s.len() as f64 / 6.5) > 250.0);
}

#[test]
fn dataflash_arduplane_every_message_count_and_field_matches_the_inventory() {
    let Some(path) = shared("pyflightcoach_center_0003.bin") else { return };
    let c = read_dataflash_contents(&path).unwrap();
    assert_eq!(c.skipped, vec![], "no corrupt bytes in this log");
    let inv = inventory("inventory/pyflightcoach_center_0003.bin.txt");
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for t in &c.topics {
        let base = t.name.split('[').next().unwrap().to_string();
        *counts.entry(base).or_default() +=
            t.t_s.len() + c.dropped.get(&t.name).copied().unwrap_or(0);
    }
    let topics = by_name(&c.topics);
    for e in &inv {
        if !e.fields.iter().any(|f| f == "TimeUS") {
            assert!(!counts.contains_key(&e.name), "{} has no time and is no topic", e.name);
            continue;
        }
        assert_eq!(counts.get(&e.name).copied(), Some(e.samples), "{}", e.name);
        // An instance-split type (`STAK[11]`, `ORGN[1]`): any of its topics has the fields.
        let t = c.topics.iter().find(|t| t.name.split('[').next() == Some(&e.name)).unwrap();
        let names: Vec<&str> = t.fields.iter().map(|(n, _)| n.as_str()).collect();
        // Text fields (`n`, `N`, `Z`) are not numeric and are not fields of a topic.
        assert!(names.iter().all(|n| e.fields.iter().any(|f| f == n)), "{}: {names:?}", e.name);
    }
    // Ranges the README states: 48.9 s, pitch within −14…10°, roll within −4…8°.
    let att = topics["ATT"];
    let span = att.t_s.last().unwrap() - att.t_s[0];
    assert!((48.0..49.0).contains(&span), "{span}");
    let field = |t: &Topic, f: &str| t.fields.iter().find(|(n, _)| n == f).unwrap().1.clone();
    let pitch = field(att, "Pitch");
    let roll = field(att, "Roll");
    let (pmin, pmax) = pitch.iter().fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
    let (rmin, rmax) = roll.iter().fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
    assert!(pmin > -15.0 && pmin < -13.0 && pmax > 9.0 && pmax < 11.0, "{pmin} {pmax}");
    assert!(rmin > -5.0 && rmin < -3.0 && rmax > 7.0 && rmax < 9.0, "{rmin} {rmax}");
    // Parameters the README names.
    assert_eq!(c.parameters["SERVO2_FUNCTION"], 19.0);
    assert_eq!(c.parameters["SCHED_LOOP_RATE"], 50.0);
    assert_eq!(c.parameters["LOG_BITMASK"], 1029.0);
    // Lat/Lon (`L`) scaled to degrees like pymavlink.
    let lat = field(topics["POS"], "Lat");
    assert!(lat.iter().all(|v| v.abs() <= 90.0 && v.abs() > 1.0), "{}", lat[0]);
}
