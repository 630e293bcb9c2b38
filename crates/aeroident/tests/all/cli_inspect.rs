//! `aeroident inspect` end to end through the binary: a synthetic record written here with
//! inputs at known times (the printed `--window` arguments must hold them, the `--json`
//! document must have the keys docs/inspect.md lists), plots, bad arguments, and the real
//! records of `../shared/flightdata` against what their READMEs say (UAV-OAT: one manoeuvre
//! per file on the surface its name says; the F-16 ULog: the pitch command ramps while
//! airborne, 53–60 s after the log starts).
//!
//! The shared records are skipped with a message when `../shared` is absent; under `CI=true`
//! their absence fails.

use crate::common;

use common::shared;
use serde_json::Value;
use std::path::PathBuf;
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_aeroident")).arg("inspect").args(args).output().unwrap()
}

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("aeroident-cli-inspect-{}-{name}", std::process::id()))
}

/// A 50 Hz record of 100 s: a doublet (±3°, 1 s halves) from 30 s and a 3-2-1-1 (±2°, 0.5 s
/// unit) from 60 s on `elevator_deg`, small noise, and a `q` column; in a file of its own
/// for each test (`tag`: tests run in parallel).
fn record(tag: &str) -> PathBuf {
    let mut text = String::from("time_s,elevator_deg,q\n");
    for k in 0..5000u64 {
        let t = k as f64 * 0.02;
        let doublet = match t {
            t if (30.0..31.0).contains(&t) => 3.0,
            t if (31.0..32.0).contains(&t) => -3.0,
            _ => 0.0,
        };
        let multistep = match t {
            t if (60.0..61.5).contains(&t) => 2.0,
            t if (61.5..62.5).contains(&t) => -2.0,
            t if (62.5..63.0).contains(&t) => 2.0,
            t if (63.0..63.5).contains(&t) => -2.0,
            _ => 0.0,
        };
        let noise = 0.02 * (((k * 7919) % 97) as f64 / 48.5 - 1.0);
        text += &format!("{t},{},{}\n", -1.0 + doublet + multistep + noise, 0.1 * t.sin());
    }
    let p = temp(&format!("{tag}.csv"));
    std::fs::write(&p, text).unwrap();
    p
}

/// The `--window START:END` arguments printed, in order.
fn windows(stdout: &str) -> Vec<(f64, f64)> {
    stdout
        .split("--window ")
        .skip(1)
        .map(|w| {
            let arg = w.split_whitespace().next().unwrap();
            let (a, b) = arg.split_once(':').unwrap();
            (a.parse().unwrap(), b.parse().unwrap())
        })
        .collect()
}

/// The keys docs/inspect.md lists for the document and for each topic and manoeuvre.
const TOP_KEYS: [&str; 14] = [
    "schema",
    "file",
    "format",
    "time_column",
    "gap_multiple",
    "topics",
    "parameters",
    "notes",
    "surfaces",
    "surface_hint",
    "detection_rule",
    "detections",
    "flight",
    "flight_note",
];
const TOPIC_KEYS: [&str; 13] = [
    "name",
    "messages",
    "fields",
    "samples",
    "first_s",
    "last_s",
    "span_s",
    "rate_hz",
    "median_interval_s",
    "longest_gap_s",
    "longest_gap_at_s",
    "gaps",
    "non_increasing",
];
const MANOEUVRE_KEYS: [&str; 9] = [
    "channel",
    "start_s",
    "end_s",
    "active_start_s",
    "active_end_s",
    "amplitude",
    "rms",
    "peak_hz",
    "band_hz",
];

fn keys(v: &Value) -> Vec<&str> {
    let mut k: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    k.sort_unstable();
    k
}

fn sorted<const N: usize>(mut k: [&'static str; N]) -> Vec<&'static str> {
    k.sort_unstable();
    k.to_vec()
}

#[test]
fn windows_printed_hold_the_inputs_and_the_json_has_the_documented_keys() {
    let (data, json) = (record("r1"), temp("out.json"));
    let o = run(&[data.to_str().unwrap(), "--json", json.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let w = windows(&stdout);
    assert_eq!(w.len(), 2, "{stdout}");
    for ((a, b), (t0, t1)) in w.iter().zip([(30.0, 32.0), (60.0, 63.5)]) {
        assert!(*a <= t0 && *b >= t1, "window {a}:{b} misses the input {t0}–{t1}\n{stdout}");
        assert!(*a >= t0 - 3.0 && *b <= t1 + 5.0, "window {a}:{b} is far wider than the input");
    }
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    std::fs::remove_file(&json).ok();
    std::fs::remove_file(&data).ok();
    assert_eq!(keys(&doc), sorted(TOP_KEYS));
    assert_eq!(doc["schema"], "aeroident-inspect/1");
    assert_eq!(keys(&doc["topics"][0]), sorted(TOPIC_KEYS));
    assert_eq!(doc["topics"][0]["samples"], 5000);
    assert_eq!(doc["topics"][0]["gaps"], 0);
    assert_eq!(doc["time_column"]["name"], "time_s");
    let m = &doc["detections"][0]["manoeuvres"];
    assert_eq!(keys(&m[0]), sorted(MANOEUVRE_KEYS));
    // The JSON's windows are the printed ones (rounded outwards to 0.01 s there).
    for (k, (a, b)) in w.iter().enumerate() {
        let (s, e) = (m[k]["start_s"].as_f64().unwrap(), m[k]["end_s"].as_f64().unwrap());
        assert!(*a <= s && s - a < 0.01 && *b >= e && b - e < 0.01);
    }
}

#[test]
fn plots_are_written_as_svg_and_png() {
    let data = record("r2");
    for (ext, magic) in [("svg", &b"<svg"[..]), ("png", &b"\x89PNG"[..])] {
        let out = temp(&format!("plot.{ext}"));
        let o = run(&[
            data.to_str().unwrap(),
            "--plot",
            "elevator_deg,q",
            "--window",
            "25:40",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let bytes = std::fs::read(&out).unwrap();
        std::fs::remove_file(&out).ok();
        assert!(bytes.starts_with(magic), "{ext}");
        if ext == "svg" {
            let text = String::from_utf8_lossy(&bytes);
            // Each panel is titled by its channel: the texts of the `<text>` elements.
            let texts: Vec<&str> = text
                .split("</text>")
                .filter_map(|e| e.rsplit_once('>').map(|(_, t)| t.trim()))
                .collect();
            assert!(texts.contains(&"elevator_deg") && texts.contains(&"q"), "{texts:?}");
        }
    }
    std::fs::remove_file(&data).ok();
}

#[test]
fn errors_bad_arguments_and_input_are_named() {
    let data = record("r3");
    let d = data.to_str().unwrap();
    let err = |args: &[&str]| {
        let o = run(args);
        assert!(!o.status.success(), "{args:?}");
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    assert!(err(&[d, "--plot", "q"]).contains("--plot needs --out"));
    assert!(err(&[d, "--plot", "q", "--out", "x.pdf"]).contains(".svg or .png"));
    assert!(err(&[d, "--window", "1:2"]).contains("--window is the time span of a plot"));
    let e = err(&[d, "--plot", "nope", "--out", "x.svg"]);
    assert!(e.contains(".csv: no column `nope` (columns: time_s, elevator_deg, q)"), "{e}");
    let e = err(&[d, "--plot", "q", "--window", "500:600", "--out", "x.svg"]);
    assert!(e.contains("channel `q` has no sample in it"), "{e}");
    assert!(err(&["/nonexistent/log.ulg"]).contains("/nonexistent/log.ulg"));
    std::fs::remove_file(&data).ok();
}

/// The JSON document of `inspect` on `path`.
fn document(path: &std::path::Path) -> Value {
    let json = temp(&format!("{}.json", path.file_stem().unwrap().to_string_lossy()));
    let o = run(&[path.to_str().unwrap(), "--json", json.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    std::fs::remove_file(&json).ok();
    doc
}

#[test]
fn uav_oat_each_record_has_one_manoeuvre_on_the_surface_its_name_says() {
    let Some(dir) = shared("uav_oat/csv") else { return };
    let mut files: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    assert_eq!(files.len(), 14);
    for f in files {
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        let surface = ["el", "ail", "rud"].iter().zip(["delta_e", "delta_a", "delta_r"]).find_map(
            |(k, col)| name.contains(&format!("_{k}_")).then(|| format!("{col} [AETR_units]")),
        );
        let surface = surface.unwrap();
        let doc = document(&f);
        let span = doc["topics"][0]["span_s"].as_f64().unwrap();
        let det = doc["detections"].as_array().unwrap();
        let mine = det.iter().find(|d| d["channel"] == surface.as_str()).unwrap();
        let m = mine["manoeuvres"].as_array().unwrap();
        assert_eq!(m.len(), 1, "{name}: {m:?}");
        let active =
            m[0]["active_end_s"].as_f64().unwrap() - m[0]["active_start_s"].as_f64().unwrap();
        assert!(active >= 0.5 * span, "{name}: active {active} s of {span} s");
        // One surface at a time: the named one moves the most.
        let amp = |d: &Value| {
            d["manoeuvres"]
                .as_array()
                .unwrap()
                .iter()
                .map(|m| m["amplitude"].as_f64().unwrap())
                .fold(0.0, f64::max)
        };
        assert!(det.iter().all(|d| amp(d) <= amp(mine)), "{name}");
    }
}

#[test]
fn px4_f16_pitch_command_is_found_while_airborne() {
    let Some(log) = shared("px4_ardupilot/f16capstone_log_52_2021-5-22-12-42-56.ulg") else {
        return;
    };
    let doc = document(&log);
    // The README: the log starts at 598 659 116 µs; airborne from 52.5 s to its end at 60 s,
    // the pitch command ramping to 0.7–0.8.
    let (air0, air1) = (598.659 + 53.0, 598.659 + 60.0);
    let d = doc["detections"].as_array().unwrap();
    let pitch = d.iter().find(|d| d["channel"] == "actuator_controls_0.control[1]").unwrap();
    let hit = pitch["manoeuvres"].as_array().unwrap().iter().any(|m| {
        m["active_start_s"].as_f64().unwrap() < air1
            && m["active_end_s"].as_f64().unwrap() > air0
            && m["amplitude"].as_f64().unwrap() > 0.4
    });
    assert!(hit, "{pitch}");
}

#[test]
fn dataflash_without_surfaces_says_how_to_name_one() {
    let Some(log) = shared("px4_ardupilot/pyflightcoach_center_0003.bin") else { return };
    let o = run(&[log.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    assert!(stdout.contains("no surface channel is known"), "{stdout}");
    assert!(stdout.contains("--map MAPPING.toml"));
    assert!(stdout.contains("SERVO2_FUNCTION = 19"));
}

/// A mapping of the synthetic record: `elevator_deg` is `de` (the constants only make it a
/// valid mapping).
const RECORD_MAPPING: &str = r#"
[time]
column = "time_s"
unit = "s"
[channels]
vt = { value = 20.0, unit = "m/s" }
alpha = { column = "q", unit = "rad" }
de = { column = "elevator_deg", unit = "deg" }
rho = { value = 1.2, unit = "kg/m3" }
mass = { value = 3.0, unit = "kg" }
S = { value = 0.4, unit = "m2" }
"#;

/// `--window auto` of replay and compat: the windows are the manoeuvres found, each holding
/// an input the record has; `auto` beside a span, with stdin or with `--and` is refused.
#[test]
fn window_auto_resolves_to_windows_holding_the_inputs() {
    use aeroident::cli::auto_window::{WindowSpec, axes_of_model, parse, resolve};
    let data = record("r4");
    let d = data.to_str().unwrap();
    let mapping = aeroident_io::Mapping::from_toml_str(RECORD_MAPPING, "m.toml").unwrap();
    let both = axes_of_model(None);
    let w = resolve(&[parse("auto").unwrap()], d, None, &mapping, false, both).unwrap();
    assert_eq!(w.len(), 2, "{w:?}");
    for (w, (t0, t1)) in w.iter().zip([(30.0, 32.0), (60.0, 63.5)]) {
        assert!(w.start_s <= t0 && w.end_s >= t1, "{w:?}");
        assert!((w.start_s * 100.0).fract().abs() < 1e-6, "rounded to 0.01 s: {w:?}");
    }
    let span = parse("1:2").unwrap();
    assert!(matches!(span, WindowSpec::Span(_)));
    let e = |specs: &[WindowSpec], data: &str, more: bool| {
        resolve(specs, data, None, &mapping, more, both).unwrap_err().to_string()
    };
    assert!(e(&[WindowSpec::Auto, span], d, false).contains("give `auto` once"));
    assert!(e(&[WindowSpec::Auto], "-", false).contains("give a file"));
    assert!(e(&[WindowSpec::Auto], d, true).contains("with --and"));
    assert!(parse("soon").unwrap_err().contains("or `auto`"));
    std::fs::remove_file(&data).ok();
}

/// The figure `Plotly.newPlot` draws in an `--html` page: its `data` and `layout`.
fn plotly_figure(page: &str) -> Value {
    // The last call: the embedded library mentions `Plotly.newPlot(` in its own messages.
    let at = page.rfind("Plotly.newPlot(").expect("no Plotly.newPlot call");
    let start = at + page[at..].find('{').unwrap();
    let mut stream = serde_json::Deserializer::from_str(&page[start..]).into_iter::<Value>();
    stream.next().unwrap().unwrap()
}

/// `--html`: one self-contained page (no script loaded from elsewhere) whose rows hold the
/// record's own samples on one shared time axis, the two manoeuvres shaded where the listing
/// puts them; it renders in headless Chromium with no network.
#[test]
fn html_page_holds_the_records_samples_and_shades_the_manoeuvres() {
    let data = record("html");
    let page = temp("page.html");
    let o = run(&[
        data.to_str().unwrap(),
        "--plot",
        "elevator_deg,q",
        "--html",
        page.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&page).unwrap();
    assert!(!text.contains("<script src=\"http"), "a script loaded from the network");
    let fig = plotly_figure(&text);
    let csv = std::fs::read_to_string(&data).unwrap();
    let rows: Vec<Vec<f64>> =
        csv.lines().skip(1).map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    for (i, (col, y)) in [(1, "y"), (2, "y2")].into_iter().enumerate() {
        let trace = &fig["data"][i];
        assert_eq!((trace["xaxis"].as_str(), trace["yaxis"].as_str()), (Some("x"), Some(y)));
        let (xs, ys) = (trace["x"].as_array().unwrap(), trace["y"].as_array().unwrap());
        assert_eq!(xs.len(), rows.len());
        for (k, r) in rows.iter().enumerate() {
            assert!((xs[k].as_f64().unwrap() - r[0]).abs() < 1e-9);
            assert!((ys[k].as_f64().unwrap() - r[col]).abs() < 1e-9 * (1.0 + r[col].abs()));
        }
    }
    let spans: Vec<(f64, f64)> = fig["layout"]["shapes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| (s["x0"].as_f64().unwrap(), s["x1"].as_f64().unwrap()))
        .collect();
    assert_eq!(spans.len(), 2, "{spans:?}");
    assert!(spans[0].0 < 30.0 && spans[0].1 > 32.0 && spans[1].0 < 60.0 && spans[1].1 > 63.5);
    let Some(chrome) = common::browser::chromium() else {
        assert!(std::env::var("CI").as_deref() != Ok("true"), "CI=true but no chromium on PATH");
        eprintln!("SKIPPED the render of the inspect page: no chromium on PATH");
        return;
    };
    let (ok, dom, err) = common::browser::headless(
        &chrome,
        &common::browser::page_url(&page),
        &temp("profile"),
        &["--dump-dom", "--virtual-time-budget=5000"],
    );
    assert!(ok, "chromium failed: {err}");
    assert!(dom.contains("main-svg"), "the plot did not render");
    assert!(common::browser::console_lines(&err).is_empty(), "{err}");
}
