//! `aeroident freqresp` end to end: a record of a discrete lag whose response is known, the
//! files it writes, their agreement with the exact response, and its errors on bad input.

use std::path::{Path, PathBuf};
use std::process::Command;

const MAP: &str = "nominal_dt_s = 0.02\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nq = { column = \"q\", unit = \"rad/s\" }\nde = { column = \"de\", unit = \"rad\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\ncbar = { value = 1.5, unit = \"m\" }\nIyy = { value = 2000.0, unit = \"kg*m2\" }\n";
const DT: f64 = 0.02;
const A: f64 = 0.9;

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("aeroident-freqresp-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `q[k] = A q[k−1] + (1 − A) de[k−1]` driven by a deterministic pseudo-random elevator.
fn write_record(dir: &Path) {
    let mut csv = String::from("t,V,a,q,de\n");
    let (mut q, mut prev, mut seed) = (0.0f64, 0.0f64, 7u64);
    for k in 0..5000 {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let de = (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        q = A * q + (1.0 - A) * prev;
        prev = de;
        csv.push_str(&format!("{:.2},50,0.05,{q:.12e},{de:.12e}\n", k as f64 * DT));
    }
    std::fs::write(dir.join("r.csv"), csv).unwrap();
    std::fs::write(dir.join("m.toml"), MAP).unwrap();
}

#[test]
fn writes_json_csv_figures_and_report_matching_the_exact_response() {
    let d = scratch("files");
    write_record(&d);
    let out = d.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args([
            "freqresp", "r.csv", "--map", "m.toml", "--input", "de", "--output", "q", "--fit",
            "q/de:0/1",
        ])
        .arg("--out")
        .arg(&out)
        .current_dir(&d)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["freqresp.json", "freqresp.csv", "report.html", "bode_q_de.png", "bode_q_de.svg"] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("freqresp.json")).unwrap()).unwrap();
    let p = &j["pairs"][0];
    assert_eq!((p["input"].as_str(), p["output"].as_str()), (Some("de"), Some("q")));
    let f = p["frequency_hz"].as_array().unwrap();
    let mag = p["magnitude_db"].as_array().unwrap();
    for (f, m) in f.iter().zip(mag) {
        let w = 2.0 * std::f64::consts::PI * f.as_f64().unwrap() * DT;
        // |(1 − A) e^{−jw} / (1 − A e^{−jw})|
        let den = ((1.0 - A * w.cos()).powi(2) + (A * w.sin()).powi(2)).sqrt();
        let exact = 20.0 * ((1.0 - A) / den).log10();
        assert!((m.as_f64().unwrap() - exact).abs() < 0.3, "{f} Hz: {m} vs {exact}");
    }
    let csv = std::fs::read_to_string(out.join("freqresp.csv")).unwrap();
    assert_eq!(csv.lines().count(), f.len() + 1);
    assert!(csv.starts_with("output,input,frequency_hz,frequency_rad_s,magnitude_db"));
    assert!(j["fits"][0]["cost"].as_f64().unwrap() < 100.0);
}

#[test]
fn bad_input_names_the_option() {
    let d = scratch("bad");
    write_record(&d);
    for (args, needle) in [
        (vec!["--input", "de", "--output", "r"], "`r` is not in the record"),
        (vec!["--input", "de", "--output", "q", "--windows-s", "500"], "`--windows-s`: 500 s"),
        (vec!["--input", "de", "--output", "q", "--fit", "q/de:3/2"], "--fit"),
        // Options named as they are spelled, never `--f_max` or `--points_per_decade`.
        (vec!["--input", "de", "--output", "q", "--f-max-hz", "30"], "`--f-max-hz`: 30 Hz"),
        (
            vec!["--input", "de", "--output", "q", "--points-per-decade", "1000000000000"],
            "`--points-per-decade`: 1.000e12 is outside [1, 1000]",
        ),
        (
            vec!["--input", "de", "--output", "q", "--points-per-decade", "18446744073709551615"],
            "`--points-per-decade`: 1.845e19 is outside [1, 1000]",
        ),
        (
            vec!["--input", "de", "--output", "q", "--min-coherence", "nan"],
            "`--min-coherence`: NaN",
        ),
        (
            vec!["--input", "de", "--input", "de", "--output", "q"],
            "`--input`: `de` is given twice (an input conditioned on itself",
        ),
        (
            vec!["--input", "de", "--output", "q", "--output", "q"],
            "`--output`: `q` is given twice (each output's responses are computed once",
        ),
        (
            vec!["--input", "de", "--output", "q", "--window", "1:1.05"],
            "`--window`: no uniformly sampled stretch of 4 or more samples",
        ),
        (
            vec!["--input", "de", "--output", "q", "--window", "1:1.5"],
            "holds 26 samples (0.52 s): the default spectral windows",
        ),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_aeroident"))
            .args(["freqresp", "r.csv", "--map", "m.toml"])
            .args(&args)
            .current_dir(&d)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && !err.contains("panicked"), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
    }
}

/// An option out of range is refused before the output directory is opened (which clears the
/// previous run's files): the previous results stay.
#[test]
fn a_bad_option_leaves_the_previous_results() {
    let d = scratch("keep");
    write_record(&d);
    let out = d.join("out");
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_aeroident"))
            .args(["freqresp", "r.csv", "--map", "m.toml", "--input", "de", "--output", "q"])
            .args(extra)
            .arg("--out")
            .arg(&out)
            .current_dir(&d)
            .output()
            .unwrap()
    };
    let o = run(&[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for bad in
        [&["--points-per-decade", "0"][..], &["--min-coherence", "2"], &["--input", "elevator"]]
    {
        let o = run(bad);
        assert!(!o.status.success(), "{bad:?}");
        assert!(out.join("freqresp.json").exists(), "{bad:?} removed the previous results");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `--window auto`: a record quiet for 20 s, excited 20–60 s, quiet again to 80 s. The window
/// chosen brackets the excitation (the detector's 1 s lead-in and 3 s tail), and the analysis
/// equals the one given that window by hand.
#[test]
fn window_auto_finds_the_excitation_and_equals_the_window_given_by_hand() {
    let d = scratch("auto");
    let mut csv = String::from("t,V,a,q,de\n");
    let (mut q, mut prev, mut seed) = (0.0f64, 0.0f64, 11u64);
    for k in 0..4000 {
        let t = k as f64 * DT;
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let u = (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        let de = if (20.0..60.0).contains(&t) { u } else { 1e-4 * u };
        q = A * q + (1.0 - A) * prev;
        prev = de;
        csv.push_str(&format!("{t:.2},50,0.05,{q:.12e},{de:.12e}\n"));
    }
    std::fs::write(d.join("r.csv"), csv).unwrap();
    std::fs::write(d.join("m.toml"), MAP).unwrap();
    let run = |window: &str, out: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_aeroident"))
            .args(["freqresp", "r.csv", "--map", "m.toml", "--input", "de", "--output", "q"])
            .args(["--window", window, "--out", out])
            .current_dir(&d)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let err = run("auto", "auto");
    let chosen = err
        .lines()
        .find_map(|l| l.strip_prefix("--window auto: ").and_then(|r| r.split("--window ").nth(1)))
        .unwrap_or_else(|| panic!("no window printed: {err}"))
        .trim()
        .to_string();
    let (a, b) = chosen.split_once(':').unwrap();
    let (a, b): (f64, f64) = (a.parse().unwrap(), b.parse().unwrap());
    assert!((18.5..=20.0).contains(&a) && (60.0..=63.5).contains(&b), "{chosen}");
    run(&chosen, "by_hand");
    let json = |dir: &str| {
        let v: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(d.join(dir).join("freqresp.json")).unwrap(),
        )
        .unwrap();
        v["pairs"].clone()
    };
    assert!(!json("auto").is_null());
    assert_eq!(json("auto"), json("by_hand"));
}
