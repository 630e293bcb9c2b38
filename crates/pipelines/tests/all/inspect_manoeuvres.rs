//! The manoeuvre detector of `aeroident inspect` on a synthetic record written here: a
//! 3-2-1-1 and a doublet at known times on a drifting, noisy surface, and a twitch too short
//! to be a manoeuvre. The expectations are the times the test put the inputs at and the
//! textbook spectrum of a doublet, not the detector's own output.

use aeroident_io::Mapping;
use aeroident_io::inspect::InspectOptions;
use aeroident_pipelines::inspect::detect::DetectionRule;
use aeroident_pipelines::inspect::{inspect, manoeuvre_windows};

/// The 3-2-1-1 (unit 0.5 s, from 40 s, ±2), the doublet (half-width 1 s, from 120 s, ±1.5)
/// and a 0.1 s twitch at 170 s, on a 0.01 Hz drift of ±0.5 and uniform noise of ±0.035.
fn surface(t: f64, k: u64) -> f64 {
    let pulse = |t0: f64, widths: &[f64], a: f64| {
        let mut start = t0;
        for (i, w) in widths.iter().enumerate() {
            if (start..start + w).contains(&t) {
                return if i % 2 == 0 { a } else { -a };
            }
            start += w;
        }
        0.0
    };
    let noise = 0.035 * (((k.wrapping_mul(2_654_435_761) >> 7) % 1000) as f64 / 500.0 - 1.0);
    let drift = 0.5 * (std::f64::consts::TAU * 0.01 * t).sin();
    drift
        + noise
        + pulse(40.0, &[1.5, 1.0, 0.5, 0.5], 2.0)
        + pulse(120.0, &[1.0, 1.0], 1.5)
        + pulse(170.0, &[0.1], 2.0)
}

/// A 50 Hz record of 200 s whose columns say nothing of what they are.
fn record() -> std::path::PathBuf {
    let mut text = String::from("t,c1,c2\n");
    for k in 0..10_000u64 {
        let t = k as f64 * 0.02;
        text += &format!("{t},{},{}\n", surface(t, k), 0.01 * (t * 0.3).sin());
    }
    let p = std::env::temp_dir().join(format!("aeroident-detect-{}.csv", std::process::id()));
    std::fs::write(&p, text).unwrap();
    p
}

const MAPPING: &str = r#"
[time]
column = "t"
unit = "s"
[channels]
vt = { value = 20.0, unit = "m/s" }
alpha = { column = "c2", unit = "rad" }
de = { column = "c1", unit = "deg" }
rho = { value = 1.2, unit = "kg/m3" }
mass = { value = 3.0, unit = "kg" }
S = { value = 0.4, unit = "m2" }
"#;

#[test]
fn inputs_are_found_where_they_were_put_and_a_twitch_is_not() {
    let path = record();
    let file = path.display().to_string();
    let rule = DetectionRule::default();
    // Unmapped, no column says surface: nothing is judged, and the hint says how to name one.
    let bare = inspect(&file, &InspectOptions::default(), &rule).unwrap();
    assert!(bare.report.detections.is_empty());
    assert!(bare.report.surface_hint.as_deref().unwrap().contains("--map MAPPING.toml"));
    // A mapping whose surface column the record lacks: said, not judged.
    let elsewhere =
        Mapping::from_toml_str(&MAPPING.replace("\"c1\"", "\"RCOU.C2\""), "t.toml").unwrap();
    let options = InspectOptions { mapping: Some(&elsewhere), ..Default::default() };
    let lacking = inspect(&file, &options, &rule).unwrap();
    assert!(lacking.report.detections.is_empty());
    let hint = lacking.report.surface_hint.unwrap();
    assert!(hint.contains("not in the log, not judged: `RCOU.C2` (elevator (`de`))"), "{hint}");
    let mapping = Mapping::from_toml_str(MAPPING, "test.toml").unwrap();
    let options = InspectOptions { mapping: Some(&mapping), ..Default::default() };
    let out = inspect(&file, &options, &rule).unwrap();
    std::fs::remove_file(&path).ok();
    let d = &out.report.detections;
    assert_eq!(d.len(), 1);
    assert_eq!(d[0].channel, "c1");
    let m = &d[0].manoeuvres;
    assert_eq!(m.len(), 2, "{m:#?}");
    for (m, (a, b)) in m.iter().zip([(40.0, 43.5), (120.0, 122.0)]) {
        // The active span covers the input, give or take the half RMS window.
        assert!(m.active_start_s <= a + 0.1 && m.active_start_s >= a - 1.0, "{m:?}");
        assert!(m.active_end_s >= b - 0.1 && m.active_end_s <= b + 1.0, "{m:?}");
        assert!(m.start_s <= m.active_start_s - 0.99 && m.end_s >= m.active_end_s + 2.99, "{m:?}");
        assert!(m.amplitude > 1.2 && m.amplitude < 2.7, "{m:?}");
    }
    // A doublet of half-width Δt has its spectral peak at ω·Δt ≈ 2.33 rad: 0.37 Hz for 1 s.
    let doublet = &m[1];
    assert!(doublet.band_hz[0] <= 0.371 && doublet.band_hz[1] >= 0.371, "{doublet:?}");
    assert!((doublet.peak_hz - 0.371).abs() < 0.12, "{doublet:?}");
    let windows = manoeuvre_windows(&out.report);
    assert_eq!(windows.len(), 2);
    assert!(windows[0].end_s < windows[1].start_s);
}
