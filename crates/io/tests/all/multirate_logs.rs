//! The multi-rate log readers on the real PX4 ULog and ArduPilot DataFlash logs in
//! `../shared/flightdata/px4_ardupilot/` (read its README): every topic / message type, its
//! sample count and its field names against the independent inventories shipped beside the
//! logs (`inventory/*.txt`, written with pyulog and pymavlink), and the F-16 log's parameters
//! against `inventory/…params.csv`.
//!
//! Skips with a message when `../shared` is absent; fails under `CI=true`.

use aeroident_estimators::AirDataSample;
use aeroident_io::align::{Clock, align, select};
use aeroident_io::dataflash::{read_dataflash, read_dataflash_contents};
use aeroident_io::multirate::log_table;
use aeroident_io::table::{Interpolation, Table, Topic};
use aeroident_io::ulog::{read_ulog, read_ulog_contents};
use aeroident_io::{Channel, FlightDataError, FlightDataReader, Mapping, RecordEvent};
use std::collections::BTreeMap;
use std::path::PathBuf;

fn mapping_text(name: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../mappings").join(name);
    std::fs::read_to_string(p).unwrap()
}

/// The aligned table as CSV text (the thin test-only path into the CSV reader; the CLI's log
/// dispatch does the same through the mapping). NaN (an undefined derived value) is written as
/// `NaN`, which the reader rejects naming the column.
fn table_csv(t: &Table) -> String {
    let mut s = t.names.join(",");
    s.push('\n');
    for r in 0..t.columns[0].len() {
        let row: Vec<String> = t.columns.iter().map(|c| format!("{}", c[r])).collect();
        s.push_str(&row.join(","));
        s.push('\n');
    }
    s
}

/// Samples and rejection reasons of a log read end to end through `mapping`.
struct EndToEnd {
    rows: usize,
    dropped_by_alignment: usize,
    samples: Vec<AirDataSample>,
    rejected: Vec<String>,
}

fn end_to_end(
    topics: &[Topic],
    mapping: &Mapping,
    file: &str,
) -> Result<EndToEnd, FlightDataError> {
    let aligned = log_table(topics, mapping, file)?;
    let csv = table_csv(&aligned.table);
    let reader = FlightDataReader::new(csv.as_bytes(), file, mapping)?;
    let mut out = EndToEnd {
        rows: aligned.table.columns[0].len(),
        dropped_by_alignment: aligned.dropped(),
        samples: Vec::new(),
        rejected: Vec::new(),
    };
    for ev in reader {
        match ev? {
            RecordEvent::Sample { sample, .. } => out.samples.push(sample),
            RecordEvent::Rejected { problem, .. } => out.rejected.push(problem.to_string()),
            RecordEvent::Gap { .. } => {}
        }
    }
    Ok(out)
}

fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    v.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)))
}

fn corr(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

/// A PX4/ArduPilot log of `../shared/flightdata/px4_ardupilot` ([`shared_data::shared`]).
fn shared(rel: &str) -> Option<PathBuf> {
    shared_data::shared(&format!("px4_ardupilot/{rel}"))
}

use crate::common::shared as shared_data;

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
        assert!((0.0..20.309).contains(&t0), "{name}: {t0}");
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

#[test]
fn ulog_f16_reads_end_to_end_through_the_shipped_mapping() {
    let Some(path) = shared("f16capstone_log_52_2021-5-22-12-42-56.ulg") else { return };
    let file = path.display().to_string();
    let topics = read_ulog(&path).unwrap();
    let m =
        Mapping::from_toml_str(&mapping_text("px4-fixedwing.toml"), "px4-fixedwing.toml").unwrap();
    let e = end_to_end(&topics, &m, &file).unwrap();
    let t: Vec<f64> = e.samples.iter().map(|s| s.t_s).collect();
    let n = e.samples.len();
    eprintln!(
        "F-16 ULog: {} aligned rows at 50 Hz ({} dropped by alignment), {n} samples, {} rejected, t {:.2}..{:.2} s",
        e.rows,
        e.dropped_by_alignment,
        e.rejected.len(),
        t[0],
        t[n - 1]
    );
    // 60 s of log at 50 Hz; the rows below 3 m/s (taxi, ~50 s) are rejected for α.
    assert!((2900..=3010).contains(&e.rows), "{}", e.rows);
    assert!(
        e.rejected.iter().all(|r| r.contains("air.alpha") || r.contains("air.beta")),
        "{:?}",
        &e.rejected[..3.min(e.rejected.len())]
    );
    assert!(n > 300, "{n} samples (airborne 52.5–60 s, taxi above 3 m/s)");
    // Airborne part (takeoff detected at 52.5 s from the log start, 598.659 s since boot).
    let air: Vec<&AirDataSample> = e.samples.iter().filter(|s| s.t_s > 598.659 + 53.0).collect();
    assert!(air.len() > 300, "{}", air.len());
    let (vmin, vmax) = range(air.iter().map(|s| s.vt_mps));
    let (qmin, qmax) = range(air.iter().map(|s| s.q_rad_s.unwrap()));
    let (pmin, pmax) = range(air.iter().map(|s| s.p_rad_s.unwrap()));
    let (azmin, _) = range(air.iter().map(|s| s.az_mps2.unwrap()));
    let (demin, demax) = range(air.iter().map(|s| s.de_rad.unwrap()));
    let (rmin, rmax) = range(air.iter().map(|s| s.rho_kgpm3.unwrap()));
    eprintln!(
        "airborne: V {vmin:.1}..{vmax:.1} m/s, q {qmin:.2}..{qmax:.2} rad/s, p {pmin:.2}..{pmax:.2} rad/s, az min {azmin:.1} m/s², de {:.1}..{:.1} deg, rho {rmin:.3}..{rmax:.3}",
        demin.to_degrees(),
        demax.to_degrees()
    );
    // The README: IAS 7.6–21 m/s, roll rate ±110 °/s, pitch rate ±55 °/s, az to −39.5 m/s².
    assert!(vmin > 3.0 && vmax > 12.0 && vmax < 45.0, "{vmin} {vmax}");
    assert!(pmax > 1.2 && pmin < -1.2 && pmax < 2.5, "{pmin} {pmax}");
    assert!(qmax > 0.5 && qmax < 1.5, "{qmin} {qmax}");
    assert!(azmin < -25.0 && azmin > -45.0, "{azmin}");
    assert!(rmin > 1.0 && rmax < 1.3, "{rmin} {rmax}");
    // Near-full nose-up command → trailing edge up (de < 0) at some point.
    assert!(demin < -0.2, "{demin}");
    assert_eq!(e.samples[0].constants.mass_kg, 3.0);
}

#[test]
fn ulog_f16_surface_signs_follow_the_controls_through_pwm_reversal() {
    // actuator_outputs against actuator_controls_0 (both 10 Hz; PX4: control > 0 = roll right,
    // nose up, nose right): the shipped calibration must give da < 0 for roll-right (δa > 0
    // rolls left), de < 0 (trailing edge up) for nose-up, dr < 0 (trailing edge right) for
    // nose-right commands, whatever the mixer and PWM_MAIN_REVn do in between.
    let Some(path) = shared("f16capstone_log_52_2021-5-22-12-42-56.ulg") else { return };
    let topics = read_ulog(&path).unwrap();
    let m =
        Mapping::from_toml_str(&mapping_text("px4-fixedwing.toml"), "px4-fixedwing.toml").unwrap();
    let cols: Vec<(String, String)> = [
        "actuator_outputs.output[0]",
        "actuator_outputs.output[1]",
        "actuator_outputs.output[3]",
        "actuator_controls_0.control[0]",
        "actuator_controls_0.control[1]",
        "actuator_controls_0.control[2]",
    ]
    .iter()
    .map(|c| (c.to_string(), "test".to_string()))
    .collect();
    let sel = select(&topics, &cols, "f16").unwrap();
    let a =
        align(&sel, &Clock::Topic("actuator_outputs".into()), Interpolation::ZeroOrderHold, "f16")
            .unwrap();
    let col = |n: &str| a.table.columns[a.table.names.iter().position(|x| x == n).unwrap()].clone();
    let si = |ch: Channel, raw: Vec<f64>| -> Vec<f64> {
        raw.iter().map(|r| m.channels[&ch].to_si(*r)).collect()
    };
    let da = si(Channel::Da, col("actuator_outputs.output[0]"));
    let de = si(Channel::De, col("actuator_outputs.output[1]"));
    let dr = si(Channel::Dr, col("actuator_outputs.output[3]"));
    let c_da = corr(&da, &col("actuator_controls_0.control[0]"));
    let c_de = corr(&de, &col("actuator_controls_0.control[1]"));
    let c_dr = corr(&dr, &col("actuator_controls_0.control[2]"));
    eprintln!(
        "corr(da, roll cmd) {c_da:.3}, corr(de, pitch cmd) {c_de:.3}, corr(dr, yaw cmd) {c_dr:.3}"
    );
    // The roll command stays within −0.05…0.02 (README), so its correlation is weaker.
    assert!(c_da < -0.3, "{c_da}");
    assert!(c_de < -0.9, "{c_de}");
    assert!(c_dr < -0.9, "{c_dr}");
}

#[test]
fn ulog_vtol_reads_end_to_end_and_a_log_without_a_topic_names_it() {
    let Some(path) = shared("pyulog_sample_log_small.ulg") else { return };
    let file = path.display().to_string();
    let topics = read_ulog(&path).unwrap();
    let text = mapping_text("px4-fixedwing.toml");
    let m = Mapping::from_toml_str(&text, "px4-fixedwing.toml").unwrap();
    let e = end_to_end(&topics, &m, &file).unwrap();
    eprintln!(
        "VTOL ULog: {} aligned rows ({} dropped by alignment), {} samples, {} rejected",
        e.rows,
        e.dropped_by_alignment,
        e.samples.len(),
        e.rejected.len()
    );
    // A multicopter-mode hop: every row is a sample or rejected for the undefined flow angles.
    assert!(e.rows > 100);
    assert_eq!(e.samples.len() + e.rejected.len(), e.rows);
    assert!(e.rejected.iter().all(|r| r.contains("air.alpha") || r.contains("air.beta")));
    // Without `wind_estimate` the error names the topic and what needs it.
    let no_wind: Vec<Topic> = topics.into_iter().filter(|t| t.name != "wind_estimate").collect();
    let err = end_to_end(&no_wind, &m, &file).err().unwrap().to_string();
    assert!(
        err.contains("`wind_estimate.windspeed_north` for [air_data] wind_ne: the log has no topic/message `wind_estimate`"),
        "{err}"
    );
    assert!(err.starts_with(&file), "{err}");
}

#[test]
fn dataflash_arduplane_ground_log_lacks_imu_and_reads_with_the_rates_it_has() {
    let Some(path) = shared("pyflightcoach_center_0003.bin") else { return };
    let file = path.display().to_string();
    let topics = read_dataflash(&path).unwrap();
    let text = mapping_text("arduplane.toml");
    let m = Mapping::from_toml_str(&text, "arduplane.toml").unwrap();
    // LOG_BITMASK 1029 logs no IMU and no RCOU: the shipped mapping names the first missing.
    let err = end_to_end(&topics, &m, &file).err().unwrap().to_string();
    assert!(
        err.contains("`IMU.GyrX` for channel `p`: the log has no topic/message `IMU`"),
        "{err}"
    );
    // The same mapping with the rates this log has (PIDR/PIDP/PIDY.Act, deg/s) and without
    // the IMU accelerations and RCOU surfaces, and flow angles down to 0.5 m/s (the log is
    // carried on the ground at ≤ 1.9 m/s: its α, β are meaningless, this checks reading).
    let ground: String = text
        .lines()
        .filter(|l| !l.contains("\"IMU.") && !l.contains("\"RCOU."))
        .map(|l| l.replace("min_vt_mps = 3.0", "min_vt_mps = 0.5"))
        .chain([
            "p = { column = \"PIDR.Act\", unit = \"deg/s\" }".to_string(),
            "q = { column = \"PIDP.Act\", unit = \"deg/s\" }".to_string(),
            "r = { column = \"PIDY.Act\", unit = \"deg/s\" }".to_string(),
        ])
        .collect::<Vec<_>>()
        .join("\n");
    let m = Mapping::from_toml_str(&ground, "arduplane-ground.toml").unwrap();
    let e = end_to_end(&topics, &m, &file).unwrap();
    let n = e.samples.len();
    eprintln!(
        "ArduPlane DataFlash: {} aligned rows at 25 Hz ({} dropped by alignment), {n} samples, {} rejected",
        e.rows,
        e.dropped_by_alignment,
        e.rejected.len()
    );
    // ~48.9 s at 25 Hz.
    assert!((1150..=1225).contains(&e.rows), "{}", e.rows);
    assert!(n > 0 && n + e.rejected.len() == e.rows);
    let (vmin, vmax) = range(e.samples.iter().map(|s| s.vt_mps));
    assert!(vmin >= 0.5 && vmax < 5.0, "{vmin} {vmax}");
    let (thmin, thmax) = range(e.samples.iter().map(|s| s.theta_rad.unwrap().to_degrees()));
    assert!(thmin > -15.0 && thmax < 11.0, "{thmin} {thmax}");
    assert!(e.samples.iter().all(|s| s.de_rad.is_none() && s.ax_mps2.is_none()));
}

#[test]
fn dataflash_quaternion_conversion_follows_the_logged_euler_angles() {
    // XKQ (EKF3 quaternion) through [attitude] against ATT.Roll/Pitch (deg): an independent
    // check of the quaternion convention (a conjugated quaternion flips the angles' signs).
    // ATT is the AHRS attitude after the board trim (AHRS_TRIM_X/Y = −0.33°/+2.78° in this
    // log) and differs from the EKF's by a few degrees, so the check is on the variation and
    // on the mean offset, not sample by sample.
    let Some(path) = shared("pyflightcoach_center_0003.bin") else { return };
    let c = read_dataflash_contents(&path).unwrap();
    let text = mapping_text("arduplane.toml")
        .lines()
        .filter(|l| !l.contains("\"IMU.") && !l.contains("\"RCOU."))
        .collect::<Vec<_>>()
        .join("\n");
    let m = Mapping::from_toml_str(&text, "arduplane.toml").unwrap();
    let a = log_table(&c.topics, &m, "center").unwrap();
    let col = |n: &str| a.table.columns[a.table.names.iter().position(|x| x == n).unwrap()].clone();
    // Until EKF3 has aligned its tilt (MSG at 12.90 s) XKQ is the identity: from 15 s on.
    let keep: Vec<usize> = (0..col("time_s").len()).filter(|&k| col("time_s")[k] >= 15.0).collect();
    let pick = |v: Vec<f64>, deg: bool| -> Vec<f64> {
        keep.iter().map(|&k| if deg { v[k].to_degrees() } else { v[k] }).collect()
    };
    let (qphi, qth) = (pick(col("euler.phi"), true), pick(col("euler.theta"), true));
    let (aphi, ath) = (pick(col("ATT.Roll"), false), pick(col("ATT.Pitch"), false));
    let c_phi = corr(&qphi, &aphi);
    let c_th = corr(&qth, &ath);
    let mean =
        |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| y - x).sum::<f64>() / a.len() as f64;
    let (d_phi, d_th) = (mean(&qphi, &aphi), mean(&qth, &ath));
    eprintln!(
        "euler(XKQ) vs ATT over {} rows: corr roll {c_phi:.3}, pitch {c_th:.3}; mean ATT − euler roll {d_phi:.2}°, pitch {d_th:.2}°",
        keep.len()
    );
    assert!(keep.len() > 900);
    // Roll varies only within −4…8° (README), comparable to the AHRS–EKF difference.
    assert!(c_phi > 0.7 && c_th > 0.95, "{c_phi} {c_th}");
    let trim_y = c.parameters["AHRS_TRIM_Y"].to_degrees();
    assert!(d_phi.abs() < 3.0 && (d_th + trim_y).abs() < 2.0, "{d_phi} {d_th} {trim_y}");
}
