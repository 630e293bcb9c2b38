//! `inspect` and `--window auto` on whole flights: a taxi (7.6 m/s, idle, a control check on
//! the elevator and steering on the rudder) and a take-off roll prepended to a flight. The
//! expectations are physics, not the code's own output: the taxi is where the airspeed is far
//! below flying speed, so its inputs are left out; a window at a dynamic pressure hundreds of
//! times smaller holds far less information; a held pull of the F-16 at 206 m/s sets off a
//! phugoid of period π√2·V/g ≈ 93 s; and fitting the real HFB-320 record's manoeuvres found
//! in a whole flight gives the derivatives the record gives alone, within 2σ.
//!
//! The HFB-320 record of `../shared/flightdata` is skipped with a message when `../shared`
//! is absent; under `CI=true` its absence fails.

use crate::common;

use common::{shared, workspace};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("aeroident-whole-flight-{}-{name}", std::process::id()))
}

/// A near-Gaussian unit-variance number keyed by `k` (sum of 12 hashed uniforms).
fn noise(k: u64) -> f64 {
    (0..12u64)
        .map(|i| {
            let h = (k.wrapping_mul(12) + i).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11;
            h as f64 / (1u64 << 53) as f64
        })
        .sum::<f64>()
        - 6.0
}

/// `csv` (header and rows) with a taxi of 100 s and a take-off roll of 20 s prepended, times
/// shifted by 120 s + `climb_s` of steady flight (the record's first row with rate noise).
/// `set(row, t, v_mps, taxi)` writes a ground row's channels into the first row's copy.
fn with_taxi(
    csv: &str,
    time: &str,
    v_flight_mps: f64,
    climb_s: f64,
    set: impl Fn(&mut Vec<(String, f64)>, f64, f64, u64),
) -> String {
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    let names: Vec<&str> = header.split(',').collect();
    let rows: Vec<Vec<f64>> =
        lines.map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    let dt = rows[1][0] - rows[0][0];
    let ti = names.iter().position(|n| *n == time).unwrap();
    let mut out = format!("{header}\n");
    let start = 120.0 + climb_s;
    for k in 0..(start / dt).round() as u64 {
        let t = k as f64 * dt;
        let mut row: Vec<(String, f64)> = names
            .iter()
            .map(|n| (n.to_string(), 0.0))
            .zip(&rows[0])
            .map(|((n, _), v)| (n, *v))
            .collect();
        let v = if t < 100.0 { 7.6 } else { 7.6 + (t - 100.0) / 20.0 * (v_flight_mps - 7.6) };
        if t < 120.0 {
            set(&mut row, t, v.min(v_flight_mps), k);
        } else {
            for (name, value) in &mut row {
                let rate = name.starts_with('p') || name.starts_with('q') || name.starts_with('r');
                if rate && !name.starts_with("qbar") && !name.starts_with("rudder") {
                    *value += 1e-3 * noise(k * 31 + name.len() as u64);
                }
            }
        }
        row[ti].1 = t;
        out += &row.iter().map(|(_, v)| v.to_string()).collect::<Vec<_>>().join(",");
        out.push('\n');
    }
    for r in &rows {
        let mut r = r.clone();
        r[ti] += start;
        out += &r.iter().map(f64::to_string).collect::<Vec<_>>().join(",");
        out.push('\n');
    }
    out
}

/// Sets `name` in a row.
fn put(row: &mut [(String, f64)], name: &str, value: f64) {
    if let Some(c) = row.iter_mut().find(|(n, _)| n == name) {
        c.1 = value;
    }
}

/// The F-16 flown open loop at 20,000 ft and 206 m/s for 300 s: an elevator doublet at 20 s,
/// an aileron doublet at 50 s, a rudder doublet at 70 s and a held pull (−0.25° for 4 s) at
/// 100 s, with a taxi and take-off prepended (130 s earlier).
fn f16_whole_flight() -> PathBuf {
    let scenario = temp("f16.toml");
    std::fs::write(
        &scenario,
        r#"kind = "sim"
[aircraft]
xcg = 0.30
actuators = "f16"
[trim]
alt_ft = 20000.0
vt_fps = 675.0
[run]
duration_s = 300.0
dt_s = 0.02
seed = 1
[[input]]
channel = "elevator"
kind = "doublet"
amplitude_deg = 1.0
start_s = 20.0
pulse_width_s = 0.5
[[input]]
channel = "aileron"
kind = "doublet"
amplitude_deg = 2.0
start_s = 50.0
pulse_width_s = 1.0
[[input]]
channel = "rudder"
kind = "doublet"
amplitude_deg = 2.0
start_s = 70.0
pulse_width_s = 1.0
[[input]]
channel = "elevator"
kind = "pulse"
amplitude_deg = -0.25
start_s = 100.0
width_s = 4.0
"#,
    )
    .unwrap();
    let out = temp("f16-sim");
    let run = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args(["f16", "sim"])
        .arg(&scenario)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let csv = std::fs::read_to_string(out.join("timeseries.csv")).unwrap();
    let text = with_taxi(&csv, "t_s", 205.74, 10.0, |row, t, v_mps, k| {
        let v = v_mps / 0.3048;
        put(row, "vt_air_fps", v);
        put(row, "vt_fps", v);
        put(row, "qbar_psf", 0.5 * 0.0023769 * v * v);
        put(row, "throttle", if t < 100.0 { 0.1 } else { 1.0 });
        for (i, c) in
            ["alpha_air_rad", "beta_air_rad", "p_rad_s", "q_rad_s", "r_rad_s"].iter().enumerate()
        {
            put(row, c, 1e-3 * noise(k * 7 + i as u64));
        }
        for (i, c) in ["pdot_rad_s2", "qdot_rad_s2", "rdot_rad_s2"].iter().enumerate() {
            put(row, c, 5e-3 * noise(k * 11 + i as u64));
        }
        let check =
            if (20.0..30.0).contains(&t) { 0.17 * (std::f64::consts::PI * t).sin() } else { 0.0 };
        put(row, "elevator_rad", -0.0342 + check);
        let steer = if (50.0..70.0).contains(&t) {
            0.09 * (0.4 * std::f64::consts::PI * t).sin()
        } else {
            0.0
        };
        put(row, "rudder_rad", steer);
        put(row, "aileron_rad", 0.0);
    });
    let p = temp("f16-flight.csv");
    std::fs::write(&p, text).unwrap();
    p
}

fn inspect_json(data: &Path, mapping: &str, extra: &[&str]) -> Value {
    let json = temp(&format!("{}.json", data.file_stem().unwrap().to_string_lossy()));
    let out = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .arg("inspect")
        .arg(data)
        .arg("--map")
        .arg(workspace().join(mapping))
        .arg("--json")
        .arg(&json)
        .args(extra)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    std::fs::remove_file(&json).ok();
    v
}

/// Whether candidate `c`'s window holds time `t`.
fn holds(c: &Value, t: f64) -> bool {
    c["start_s"].as_f64().unwrap() <= t && c["end_s"].as_f64().unwrap() >= t
}

/// The F-16 whole flight: the taxi is one ground span, named, ending ≈ 10 s after the roll
/// passes 0.6 × 206 m/s; its control check and steering are left out; the doublets rank
/// first on their axes (with the held pull on pitch); the held pull is a phugoid of about 93 s; a taxi window (q̄ ≈ 35 Pa
/// against ≈ 13,900 Pa in flight) scores far worse than every flight manoeuvre; `--best 1`
/// makes sets of one, and `--window auto:1` with a longitudinal model fits the pitch one.
#[test]
fn f16_whole_flight_leaves_the_taxi_out_and_ranks_the_manoeuvres() {
    let data = f16_whole_flight();
    let r = inspect_json(&data, "mappings/aeroident-sim.toml", &[]);
    let f = &r["flight"];
    let ground = f["envelope"]["ground"].as_array().unwrap();
    assert_eq!(ground.len(), 1, "{ground:?}");
    // The roll passes 123.5 m/s at 100 + (123.5 − 7.6)/(205.7 − 7.6) × 20 ≈ 111.7 s.
    let end = ground[0]["end_s"].as_f64().unwrap();
    assert!((end - 121.7).abs() < 1.0 && ground[0]["kind"] == "before take-off", "{ground:?}");
    let candidates = f["candidates"].as_array().unwrap();
    let left_out: Vec<&Value> = candidates.iter().filter(|c| !c["excluded"].is_null()).collect();
    assert!(left_out.iter().any(|c| holds(c, 25.0)), "control check not left out: {left_out:?}");
    assert!(left_out.iter().any(|c| holds(c, 60.0)), "steering not left out: {left_out:?}");
    for c in candidates.iter().filter(|c| c["excluded"].is_null()) {
        assert!(c["start_s"].as_f64().unwrap() >= end, "a flight window on the ground: {c}");
    }
    let score = |c: &Value, axis: &str| {
        c["information"].as_array().unwrap().iter().find(|i| i["axis"] == axis).unwrap()["score"]
            .as_f64()
    };
    let ranked = |axis: &str| -> Vec<&Value> {
        f["ranked"][axis]
            .as_array()
            .unwrap()
            .iter()
            .map(|k| &candidates[k.as_u64().unwrap() as usize])
            .collect()
    };
    // The sim's times are shifted by 130 s.
    // The two elevator inputs (the doublet, and the held pull with its long phugoid) lead
    // pitch, above the aileron and rudder windows that leave δe still.
    let pitch = ranked("pitch");
    assert!(pitch[..2].iter().any(|c| holds(c, 150.5)), "{pitch:?}");
    assert!(pitch[..2].iter().any(|c| holds(c, 231.0)), "{pitch:?}");
    assert!(holds(ranked("lateral")[0], 181.0), "{:?}", ranked("lateral"));
    let taxi = left_out.iter().find(|c| holds(c, 25.0)).unwrap();
    let taxi_pitch = score(taxi, "pitch").unwrap();
    // Against the flight windows that moved the elevator (all of Cm identified).
    let moved = |c: &&Value| c["information"][0]["not_identified"].as_array().unwrap().is_empty();
    for c in ranked("pitch").into_iter().filter(moved) {
        assert!(taxi_pitch > 100.0 * score(c, "pitch").unwrap(), "{taxi} against {c}");
    }
    let phugoid = candidates.iter().find(|c| c["kind"] == "phugoid").expect("no phugoid");
    let p = &phugoid["phugoid"];
    assert!((p["pull_at_s"].as_f64().unwrap() - 230.0).abs() <= 1.0, "{p}");
    assert!(p["pull_rad"].as_f64().unwrap() < 0.0, "{p}");
    assert!((p["period_s"].as_f64().unwrap() - 93.0).abs() < 10.0, "{p}");
    // The lateral set of two pairs the aileron window with the rudder window.
    let lateral = f["window_sets"]["lateral"].as_array().unwrap();
    assert_eq!(lateral.len(), 2);
    assert!(lateral[0][0].as_f64().unwrap() <= 181.0 && lateral[1][1].as_f64().unwrap() >= 201.0);
    let one = inspect_json(&data, "mappings/aeroident-sim.toml", &["--best", "1"]);
    for axis in ["pitch", "lateral"] {
        assert_eq!(one["flight"]["window_sets"][axis].as_array().unwrap().len(), 1);
    }
    let replay = |window: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_aeroident"))
            .arg("replay")
            .arg(&data)
            .arg("--map")
            .arg(workspace().join("mappings/aeroident-sim.toml"))
            .args(["--estimator", "oe", "--model", "longitudinal", "--window", window, "--out"])
            .arg(temp(&format!("replay-{window}")))
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    // A longitudinal model fits the pitch set alone: one window, a pitch input's.
    let stderr = replay("auto:1");
    let line = stderr.lines().find(|l| l.contains("--window auto:")).unwrap();
    assert_eq!(line.matches(" --window ").count(), 1, "{line}");
    assert!(line.contains("(pitch ") && !line.contains("lateral"), "{line}");
    assert!(stderr.contains("left out as ground"), "{stderr}");
    std::fs::remove_file(&data).ok();
}

/// The estimates and σ of `summary.json` by name.
fn estimates(dir: &Path) -> Vec<(String, f64, f64)> {
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    s["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let name = p["name"].as_str().unwrap().to_string();
            (name, p["estimate"].as_f64().unwrap(), p["std_error"].as_f64().unwrap())
        })
        .collect()
}

/// The real HFB-320 record (Jategaonkar's test case 4) after a taxi, a take-off roll and
/// 60 s of steady flight: `--window auto` leaves the ground out and the output-error
/// derivatives equal those of the record fitted alone (the book's window: all of it) within
/// 2σ of the latter.
#[test]
fn hfb320_after_a_taxi_auto_windows_give_the_records_derivatives() {
    let Some(src) = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let csv = std::fs::read_to_string(&src).unwrap();
    let text = with_taxi(&csv, "time_s", 106.0, 60.0, |row, t, v, k| {
        put(row, "vtas_mps", v);
        put(row, "qbar_Pa", 0.5 * 1.225 * v * v);
        put(row, "thrust_N", if t < 100.0 { 3000.0 } else { 30000.0 });
        for (i, c) in
            ["alpha_rad", "beta_rad", "p_radps", "q_radps", "r_radps", "ay_mps2"].iter().enumerate()
        {
            put(row, c, 1e-3 * noise(k * 7 + i as u64));
        }
        for (i, c) in ["pdot_radps2", "qdot_radps2", "rdot_radps2"].iter().enumerate() {
            put(row, c, 5e-3 * noise(k * 11 + i as u64));
        }
        let check =
            if (20.0..30.0).contains(&t) { 0.15 * (std::f64::consts::PI * t).sin() } else { 0.0 };
        put(row, "elevator_rad", -0.008 + check);
        let steer = if (50.0..70.0).contains(&t) {
            0.1 * (0.4 * std::f64::consts::PI * t).sin()
        } else {
            0.0
        };
        put(row, "rudder_rad", steer);
        put(row, "aileron_rad", 0.0);
    });
    let data = temp("hfb-flight.csv");
    std::fs::write(&data, text).unwrap();
    let fit = |file: &Path, window: Option<&str>, tag: &str| {
        let out = temp(tag);
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_aeroident"));
        cmd.arg("replay")
            .arg(file)
            .arg("--map")
            .arg(workspace().join("mappings/hfb320.toml"))
            .args(["--estimator", "oe", "--model"])
            .arg(workspace().join("models/hfb320_jategaonkar.toml"))
            .arg("--out")
            .arg(&out);
        if let Some(w) = window {
            cmd.args(["--window", w]);
        }
        let run = cmd.output().unwrap();
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        (estimates(&out), String::from_utf8_lossy(&run.stderr).into_owned())
    };
    let (auto, stderr) = fit(&data, Some("auto"), "hfb-auto");
    let (hand, _) = fit(&src, None, "hfb-hand");
    let line = stderr.lines().find(|l| l.contains("--window auto:")).unwrap();
    for w in line.split("--window ").skip(2) {
        let start: f64 = w.split(':').next().unwrap().parse().unwrap();
        assert!(start >= 120.0, "a window on the ground: {line}");
    }
    assert!(stderr.contains("left out as ground"), "{stderr}");
    for ((name, a, _), (_, h, sigma)) in auto.iter().zip(&hand) {
        assert!(
            (a - h).abs() <= 2.0 * sigma,
            "{name}: auto {a} against the record's {h} ± {sigma}"
        );
    }
    std::fs::remove_file(&data).ok();
}
