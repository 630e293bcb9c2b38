//! `aeroident freqresp --window sysid` on a DataFlash log written as ArduPlane writes a SYSID
//! flight: a `SIDS` message when each sweep starts, `SIDD` (`Time`, `Targ`, `F`, rates,
//! accelerations) on every loop while it runs, the waveform of ArduPilot's `Chirp::update`
//! (`AP_Math/chirp.cpp`) added to the elevator mixer output (`FW_MIX_PITCH`), the servo PWM in
//! `RCOU`. The aircraft is a known discrete second-order q/δe, so the recovered response is
//! checked against its exact transfer function, for the surface and for the injected waveform.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "../../../io/tests/all/common/log_writers.rs"]
mod log_writers;
use log_writers::Dataflash;

const DT: f64 = 0.01;
/// Plant: `q[k] = a1 q[k−1] + a2 q[k−2] + b1 δe[k−1]` (rad/s, rad): poles `e^{sΔt}` of
/// `s` at ωn = 7.5 rad/s, ζ = 0.4, static gain `GAIN`.
const WN: f64 = 7.5;
const ZETA: f64 = 0.4;
const GAIN: f64 = -2.0;
/// Elevator throw: mixer output ±1 is ±500 µs is ±20°.
const THROW_DEG: f64 = 20.0;

/// `(a1, a2, b1)` of the plant.
fn plant() -> (f64, f64, f64) {
    let (sr, si) = (-ZETA * WN, WN * (1.0 - ZETA * ZETA).sqrt());
    let a1 = 2.0 * (sr * DT).exp() * (si * DT).cos();
    let a2 = -(2.0 * sr * DT).exp();
    (a1, a2, GAIN * (1.0 - a1 - a2))
}

/// Its exact response at `f_hz`: magnitude dB and phase deg of `b1 z⁻¹ / (1 − a1 z⁻¹ − a2 z⁻²)`.
fn exact(f_hz: f64) -> (f64, f64) {
    let (a1, a2, b1) = plant();
    let w = 2.0 * PI * f_hz * DT;
    let (re_n, im_n) = (b1 * w.cos(), -b1 * w.sin());
    let (re_d, im_d) =
        (1.0 - a1 * w.cos() - a2 * (2.0 * w).cos(), a1 * w.sin() + a2 * (2.0 * w).sin());
    let mag = (re_n.hypot(im_n) / re_d.hypot(im_d)).log10() * 20.0;
    (mag, (im_n.atan2(re_n) - im_d.atan2(re_d)).to_degrees())
}

/// ArduPilot's `Chirp` (init + update), f64.
struct Chirp {
    record: f64,
    w_min: f64,
    w_max: f64,
    fade_in: f64,
    fade_out: f64,
    const_freq: f64,
}

impl Chirp {
    fn new(record: f64, f0: f64, f1: f64, fade_in: f64, fade_out: f64) -> Self {
        let const_freq = 2.0 / f0;
        Self { record, w_min: 2.0 * PI * f0, w_max: 2.0 * PI * f1, fade_in, fade_out, const_freq }
    }

    /// Waveform sample and its frequency, rad/s, at waveform time `t`.
    fn update(&self, t: f64, magnitude: f64) -> (f64, f64) {
        let window = if t <= 0.0 {
            0.0
        } else if t <= self.fade_in {
            0.5 - 0.5 * (PI * t / self.fade_in).cos()
        } else if t <= self.record - self.fade_out {
            1.0
        } else if t <= self.record {
            0.5 - 0.5 * (PI * (t - (self.record - self.fade_out)) / self.fade_out + PI).cos()
        } else {
            0.0
        };
        let b = (self.w_max / self.w_min).ln();
        if t <= 0.0 {
            (0.0, self.w_min)
        } else if t <= self.const_freq {
            (window * magnitude * (self.w_min * t - self.w_min * self.const_freq).sin(), self.w_min)
        } else if t <= self.record {
            let x = b * (t - self.const_freq) / (self.record - self.const_freq);
            let phase = (self.w_min * (self.record - self.const_freq) / b) * (x.exp() - 1.0);
            (window * magnitude * phase.sin(), self.w_min * x.exp())
        } else {
            (0.0, self.w_max)
        }
    }
}

/// One sweep: `SID_AXIS`, start time s, magnitude, band Hz, record s.
struct SweepSpec {
    axis: u8,
    start: f64,
    mag: f64,
    band: (f64, f64),
    record: f64,
}

const SWEEPS: [SweepSpec; 2] = [
    SweepSpec { axis: 23, start: 10.0, mag: 0.1, band: (0.2, 8.0), record: 80.0 },
    SweepSpec { axis: 22, start: 95.0, mag: 0.05, band: (0.5, 5.0), record: 10.0 },
];

fn f32s(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| (*x as f32).to_le_bytes()).collect()
}

/// The log: 1 … 110 s at 100 Hz; `FW_MIX_PITCH` swept 10–90 s, `FW_MIX_ROLL` 95–105 s.
fn write_log(path: &Path) {
    let mut d = Dataflash::new();
    d.fmt(200, 3 + 8 + 4, "ARSP", "Qf", "TimeUS,Airspeed")
        .fmt(201, 3 + 8 + 8, "AOA", "Qff", "TimeUS,AOA,SSA")
        .fmt(202, 3 + 8 + 12, "IMU", "Qfff", "TimeUS,GyrX,GyrY,GyrZ")
        .fmt(203, 3 + 8 + 4, "RCOU", "QHH", "TimeUS,C1,C2")
        .fmt(204, 3 + 8 + 1 + 28, "SIDS", "QBfffffff", "TimeUS,Ax,Mag,FSt,FSp,TFin,TC,TR,TFout")
        .fmt(205, 3 + 8 + 36, "SIDD", "Qfffffffff", "TimeUS,Time,Targ,F,Gx,Gy,Gz,Ax,Ay,Az");
    let (a1, a2, b1) = plant();
    let (mut q1, mut q2, mut de1) = (0.0f64, 0.0f64, 0.0f64);
    // The sweep, its waveform and its loop count (the waveform time is count × Δt).
    let mut running: Option<(&SweepSpec, Chirp, u32)> = None;
    for k in 100..=11_000u64 {
        let t = k as f64 * DT;
        let us = (k * 10_000).to_le_bytes();
        let msg = |d: &mut Dataflash, id: u8, body: &[u8]| {
            let mut p = us.to_vec();
            p.extend_from_slice(body);
            d.msg(id, &p);
        };
        if let Some(s) = SWEEPS.iter().find(|s| (s.start - t).abs() < DT / 2.0) {
            let chirp = Chirp::new(s.record, s.band.0, s.band.1, 2.0, 2.0);
            let mut body = vec![s.axis];
            let tc = chirp.const_freq;
            body.extend(f32s(&[s.mag, s.band.0, s.band.1, 2.0, tc, s.record, 2.0]));
            msg(&mut d, 204, &body);
            running = Some((s, chirp, 0));
        }
        // Plane's fw_update: the waveform time advances, the sample is applied and logged;
        // the sweep stops (and SIDD with it) once the waveform is complete.
        let mut offset = [0.0; 2];
        if let Some((s, chirp, n)) = running.as_mut() {
            *n += 1;
            let time = f64::from(*n) * DT;
            if time > s.record {
                running = None;
            } else {
                let (targ, w) = chirp.update(time, s.mag);
                offset[usize::from(s.axis == 23)] = targ;
                let q_dps = q1.to_degrees();
                msg(
                    &mut d,
                    205,
                    &f32s(&[time, targ, w / (2.0 * PI), 0.0, q_dps, 0.0, 0.0, 0.0, -9.8]),
                );
            }
        }
        let pwm = offset.map(|o| (1500.0 + 500.0 * o).round());
        let de = ((pwm[1] - 1500.0) / 500.0 * THROW_DEG).to_radians();
        let q = a1 * q1 + a2 * q2 + b1 * de1;
        (q2, q1, de1) = (q1, q, de);
        msg(&mut d, 200, &f32s(&[20.0]));
        msg(&mut d, 201, &f32s(&[3.0, 0.0]));
        msg(&mut d, 202, &f32s(&[0.0, q, 0.0]));
        let mut rcou = Vec::new();
        for p in pwm {
            rcou.extend((p as u16).to_le_bytes());
        }
        msg(&mut d, 203, &rcou);
    }
    std::fs::write(path, d.0).unwrap();
}

/// The mapping; `with_de`: the elevator mapped from the servo PWM (±500 µs is ±20°).
fn mapping(with_de: bool) -> String {
    let de = if with_de {
        "de = { column = \"RCOU.C2\", unit = \"deg\", scale = 0.04, offset = -60.0 }\n"
    } else {
        ""
    };
    format!(
        "nominal_dt_s = 0.01\n[time]\ncolumn = \"time_s\"\nunit = \"s\"\n[align]\nclock = \"IMU\"\nmethod = \"linear\"\n[channels]\nvt = {{ column = \"ARSP.Airspeed\", unit = \"m/s\" }}\nalpha = {{ column = \"AOA.AOA\", unit = \"deg\" }}\nq = {{ column = \"IMU.GyrY\", unit = \"rad/s\" }}\n{de}rho = {{ value = 1.2, unit = \"kg/m3\" }}\nmass = {{ value = 5.0, unit = \"kg\" }}\nS = {{ value = 0.8, unit = \"m2\" }}\n"
    )
}

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("aeroident-sysid-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    write_log(&d.join("sysid.bin"));
    for (name, with_de) in [("de.toml", true), ("plain.toml", false)] {
        std::fs::write(d.join(name), mapping(with_de)).unwrap();
    }
    d
}

fn run(d: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args(["freqresp", "sysid.bin"])
        .args(args)
        .current_dir(d)
        .output()
        .unwrap()
}

/// `freqresp.json` of a run that must succeed.
fn json(d: &Path, args: &[&str]) -> serde_json::Value {
    let out = d.join("out");
    let o = run(d, &[args, &["--out", out.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&std::fs::read(out.join("freqresp.json")).unwrap()).unwrap()
}

/// The response of `pair` against `gain_db` + the plant's, over 0.3–6 Hz where γ² ≥ 0.95.
fn check_against_plant(pair: &serde_json::Value, gain_db: f64) {
    let col = |k: &str| -> Vec<f64> {
        pair[k].as_array().unwrap().iter().map(|v| v.as_f64().unwrap_or(f64::NAN)).collect()
    };
    let (f, mag, ph, coh) =
        (col("frequency_hz"), col("magnitude_db"), col("phase_deg"), col("coherence"));
    let mut checked = 0;
    for k in 0..f.len() {
        if !(0.3..=6.0).contains(&f[k]) || coh[k].is_nan() || coh[k] < 0.95 {
            continue;
        }
        let (m, p) = exact(f[k]);
        let dp = (ph[k] - p + 180.0).rem_euclid(360.0) - 180.0;
        assert!(
            (mag[k] - m - gain_db).abs() < 0.5 && dp.abs() < 3.0,
            "{} Hz: {} dB vs {}, {dp} deg",
            f[k],
            mag[k],
            m + gain_db
        );
        checked += 1;
    }
    assert!(checked > 40, "only {checked} coherent points in 0.3–6 Hz");
}

#[test]
fn sysid_sweeps_become_windows_and_the_surface_the_input() {
    let d = scratch("surface");
    let j = json(&d, &["--map", "de.toml", "--window", "sysid:FW_MIX_PITCH", "--output", "q"]);
    let s = &j["sweeps"];
    assert_eq!(s.as_array().unwrap().len(), 1, "{s}");
    assert_eq!(
        (s[0]["axis"].as_u64(), s[0]["axis_name"].as_str()),
        (Some(23), Some("FW_MIX_PITCH"))
    );
    assert_eq!(s[0]["band_hz"], serde_json::json!([0.2f32 as f64, 8.0]));
    // From the SIDS at 10 s to the last SIDD, the waveform's TR = 80 s later.
    let span: Vec<f64> =
        s[0]["span_s"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert!((span[0] - 10.0).abs() < 1e-9 && (span[1] - 90.0).abs() < 0.011, "{span:?}");
    assert_eq!(s[0]["sidd_samples"].as_u64(), Some(8000));
    let p = &j["pairs"][0];
    assert_eq!((p["input"].as_str(), p["output"].as_str()), (Some("de"), Some("q")));
    check_against_plant(p, 0.0);
}

#[test]
fn without_a_mapped_surface_the_input_is_the_injected_waveform() {
    let d = scratch("injected");
    let j = json(&d, &["--map", "plain.toml", "--window", "sysid:23", "--output", "q"]);
    let p = &j["pairs"][0];
    assert_eq!(p["input"].as_str(), Some("sysid"));
    // q per mixer unit: the plant's response times the throw in rad.
    check_against_plant(p, 20.0 * THROW_DEG.to_radians().log10());
}

#[test]
fn every_sweep_is_found_and_bad_choices_are_named() {
    let d = scratch("errors");
    let o = run(&d, &["--map", "plain.toml", "--window", "sysid", "--output", "q"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("FW_MIX_PITCH (23), FW_MIX_ROLL (22)"), "{err}");
    for (args, needle) in [
        (
            vec!["--window", "sysid:RATE_YAW"],
            "no sweep on that axis (it has: FW_MIX_PITCH (23), FW_MIX_ROLL (22))",
        ),
        (vec!["--window", "sysid:99"], "`99` is not a SID_AXIS"),
        (vec!["--window", "sysid", "--window", "1:2"], "not beside START:END"),
        (vec!["--input", "sysid", "--window", "20:30"], "give --window sysid"),
        (vec!["--window", "sysid", "--format", "ulog"], "PX4 logs no sweep setup message"),
    ] {
        let o = run(&d, &[&["--map", "plain.toml", "--output", "q"], args.as_slice()].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(needle), "{args:?}: {err}");
    }
    // Both sweeps with an explicit input: both spans are listed.
    let j = json(
        &d,
        &["--map", "plain.toml", "--window", "sysid", "--input", "sysid", "--output", "q"],
    );
    let names: Vec<&str> =
        j["sweeps"].as_array().unwrap().iter().map(|s| s["axis_name"].as_str().unwrap()).collect();
    assert_eq!(names, ["FW_MIX_PITCH", "FW_MIX_ROLL"]);
}
