//! The data compatibility check on exactly the data a fit uses (../shared/flightdata; skipped
//! with a message when absent, a failure under CI): `compat --window … --and …` and the
//! replay's `--compat auto` check the fit's time windows jointly, not the whole record with its
//! taxi and ground runs.

use crate::common;
use aeroident_estimators::compat::CompatConfig;
use aeroident_io::{Mapping, open_log};
use aeroident_pipelines::compat::{Corrections, check_records};
use aeroident_pipelines::job::{CompatSource, InPlace, Ran, Records, corrections};
use aeroident_pipelines::window::TimeWindow;
use common::{shared, workspace};
use std::process::Command;

/// The HFB-320 record (10 Hz, 60 s) checked over two windows: the samples checked are the
/// record's rows inside the windows (counted here from its time column), each window a
/// manoeuvre of one joint fit; the replay's `--compat auto` stage gives exactly the
/// corrections of that check, not those of the whole record; and `aeroident compat --window`
/// writes the same `compat.json` numbers.
#[test]
fn val_compat_checks_the_windows_the_fit_uses() {
    let Some(data) = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let map = workspace().join("mappings/hfb320.toml");
    let m = Mapping::from_path(&map).unwrap();
    let path = data.display().to_string();
    let open = || open_log(&path, None, &m).unwrap();
    let windows = vec![TimeWindow::parse("5:25").unwrap(), TimeWindow::parse("30:55").unwrap()];
    let config = CompatConfig::default();
    let (whole, _) = check_records(vec![open()], &[], &config).unwrap();
    let (within, _) = check_records(vec![open()], &windows, &config).unwrap();
    let text = std::fs::read_to_string(&data).unwrap();
    let times = text.lines().skip(1).map(|l| l.split(',').next().unwrap().parse::<f64>().unwrap());
    let inside = times.filter(|t| (5.0..=25.0).contains(t) || (30.0..=55.0).contains(t)).count();
    assert_eq!((whole.samples_read, whole.manoeuvres), (601, 1));
    assert_eq!((within.samples_read, within.manoeuvres), (inside, 2));

    let records = Records::one(path.clone(), m.clone());
    let ran =
        corrections(&records, Some(&CompatSource::Auto), &windows, &mut InPlace, &mut ()).unwrap();
    let Ran::Done(Some(auto)) = ran else { panic!("the auto stage gave no corrections") };
    assert_eq!(auto, Corrections::from_summary(&within).unwrap());
    assert_ne!(auto, Corrections::from_summary(&whole).unwrap(), "the whole record was checked");

    let out = std::env::temp_dir().join(format!("aeroident-compat-windows-{}", std::process::id()));
    let o = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args(["compat", &path, "--map", &map.display().to_string()])
        .args(["--window", "5:25", "--window", "30:55", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("compat.json")).unwrap()).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    assert_eq!(json["samples_read"], inside);
    assert_eq!(json["manoeuvres"], 2);
    // The same numbers (to the last digits a JSON round trip keeps).
    let close = |a: &serde_json::Value, b: Option<f64>| match (a.as_f64(), b) {
        (Some(x), Some(y)) => (x - y).abs() <= 1e-12 * y.abs().max(1e-300),
        (None, None) => true,
        _ => false,
    };
    let channels = json["channels"].as_array().unwrap();
    assert_eq!(channels.len(), within.channels.len());
    for (j, c) in channels.iter().zip(&within.channels) {
        assert_eq!(j["name"], c.name.as_str());
        assert!(close(&j["bias"], c.bias) && close(&j["time_shift_s"], c.time_shift_s), "{j}");
    }
}

/// The HFB-320 record with one channel mapped in the wrong unit, each against the physics of the
/// others: the check refuses before fitting and names the channel and the likely unit (fitted,
/// a q read in deg/s as rad/s came out as a −669 m/s airspeed bias and a 3.1-s α lag,
/// "converged"). The true mapping passes the same screen.
#[test]
fn errors_a_channel_in_the_wrong_unit_is_named_before_the_check() {
    let Some(data) = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let text = std::fs::read_to_string(workspace().join("mappings/hfb320.toml")).unwrap();
    let path = data.display().to_string();
    let check = |from: &str, to: &str| {
        assert!(text.contains(from), "the mapping no longer has {from}");
        let m = Mapping::from_toml_str(&text.replace(from, to), "wrong.toml").unwrap();
        check_records(vec![open_log(&path, None, &m).unwrap()], &[], &CompatConfig::default())
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    let cases = [
        (
            "q_radps\", unit = \"rad/s\"",
            "q_radps\", unit = \"deg/s\"",
            "channel `q`",
            "57.3 times too small",
        ),
        (
            "alpha_rad\", unit = \"rad\"",
            "alpha_rad\", unit = \"deg\"",
            "channel `alpha`",
            "radians mapped as degrees",
        ),
        (
            "az_mps2\", unit = \"m/s2\"",
            "az_mps2\", unit = \"g\"",
            "channel `az`",
            "m/s² data mapped in g",
        ),
        (
            "az_mps2\", unit = \"m/s2\"",
            "az_mps2\", unit = \"m/s2\", offset = 9.80665",
            "channel `az`",
            "likely gravity removed",
        ),
    ];
    for (from, to, channel, likely) in cases {
        let e = check(from, to).unwrap_err();
        assert!(e.contains("unit mismatch") && e.contains(channel) && e.contains(likely), "{e}");
    }
    check("", "").unwrap();
}

/// A copy of a CSV record in its own directory, removed when the copy is dropped.
struct Late {
    dir: std::path::PathBuf,
    csv: String,
    rows: usize,
}

impl Late {
    /// The record `data` with column `column` read `rows` rows late (each row holding the
    /// value `rows` rows before it, the first rows the first value), under `tag`: with `rows`
    /// beyond the record, a dead sensor.
    fn column(data: &std::path::Path, column: &str, rows: usize, tag: &str) -> Self {
        let text = std::fs::read_to_string(data).unwrap();
        let mut lines = text.lines();
        let header = lines.next().unwrap();
        let c = header.split(',').position(|h| h == column).expect("the column");
        let lines: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
        let body: Vec<String> = (0..lines.len())
            .map(|k| {
                let mut cells = lines[k].clone();
                cells[c] = lines[k.saturating_sub(rows)][c];
                cells.join(",")
            })
            .collect();
        let dir = std::env::temp_dir().join(format!("aeroident-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let csv = dir.join("late.csv");
        std::fs::write(&csv, format!("{header}\n{}\n", body.join("\n"))).unwrap();
        Self { dir, csv: csv.display().to_string(), rows: body.len() }
    }

    /// The check of the copy with mapping file `map` (of `mappings/`): its summary, or its
    /// error.
    fn check(&self, map: &str) -> Result<aeroident_pipelines::compat::CompatSummary, String> {
        let m = Mapping::from_path(&workspace().join("mappings").join(map)).unwrap();
        let reader = open_log(&self.csv, None, &m).unwrap();
        let checked = check_records(vec![reader], &[], &CompatConfig::default());
        checked.map(|c| c.0).map_err(|e| e.to_string())
    }
}

impl Drop for Late {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.dir).ok();
    }
}

/// The HFB-320 record with its pitch gyro dead (every `q_radps` row the first row's value):
/// the check refuses before fitting, naming the channel and its column as a dead or stuck
/// sensor, instead of fitting the kinematics to it (a dead pitch gyro "converged" with a 3.1-s
/// α lag and a 0.47-rad β bias). Its α vane 1 s late moves against the kinematic α (gain
/// −0.42 ± 0.05), 10 s late does not follow it (−0.01 ± 0.05): each is named as a channel
/// misaligned in time, not as a unit (it was "likely radians mapped as degrees" at 10 s).
#[test]
fn errors_a_dead_gyro_or_a_late_vane_is_named_before_the_check() {
    let Some(data) = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let dead = Late::column(&data, "q_radps", usize::MAX, "dead-gyro");
    let e = dead.check("hfb320.toml").unwrap_err();
    assert!(
        e.contains("channel `q`") && e.contains("q_radps") && e.contains("dead or stuck sensor"),
        "{e}"
    );
    assert!(e.contains(&format!("in all {} samples", dead.rows)), "{e}");
    for (rows, how) in [(10, "moves against"), (100, "does not follow")] {
        let late = Late::column(&data, "alpha_rad", rows, &format!("late-alpha-{rows}"));
        let e = late.check("hfb320.toml").unwrap_err();
        assert!(e.contains("channel `alpha`") && e.contains(how), "{rows}: {e}");
        assert!(e.contains("misaligned in time") && !e.contains("unit mismatch"), "{rows}: {e}");
    }
}

/// ATTAS AilRud1 (25 Hz, two manoeuvres) with its β vane 3 s late: beyond the shifts a sensor
/// plausibly has, the check settles at a shift of −0.74 s, and the channel is named with the
/// delay at which it matches the kinematics (measured +3.1 s in both manoeuvres, correlation
/// 0.99 against 0.6). The α screen, whose kinematic rate takes the side velocity from β, no
/// longer blames α for it (gain 0.35, "unit mismatch", before). The record as flown has no
/// such finding.
#[test]
fn val_a_channel_late_beyond_a_sensors_lag_is_named_with_its_delay() {
    let Some(data) = shared("jategaonkar_hfb320_attas/csv/fAttasAilRud1.csv") else { return };
    let misfit = |s: &aeroident_pipelines::compat::CompatSummary| {
        s.findings.iter().find(|f| f.contains("does not fit the kinematics")).cloned()
    };
    let as_flown = Late::column(&data, "beta_deg", 0, "beta-0").check("attas_lateral.toml");
    assert_eq!(misfit(&as_flown.unwrap()), None);
    let late =
        Late::column(&data, "beta_deg", 75, "beta-late").check("attas_lateral.toml").unwrap();
    let named = misfit(&late).expect("a misfit of β");
    assert!(named.starts_with("beta_rad"), "{named}");
    // Each manoeuvre's delay is the number before " s in manoeuvre ".
    let parts = named.split(" s in manoeuvre ");
    let delays: Vec<f64> = parts.filter_map(|p| p.rsplit(' ').next()?.parse().ok()).collect();
    assert_eq!(delays.len(), 2, "{named}");
    assert!(delays.iter().all(|d| (d - 3.0).abs() < 0.2), "{delays:?}: {named}");
}

/// ATTAS's elevator records with the shipped longitudinal mapping (p, r, φ mapped, no ay): they
/// fly within 4.4° of bank, so each is checked in the vertical plane with a note, where both
/// were refused for want of ay. The two flights' α-vane biases (one vane, two records) agree
/// within three combined σ, and neither needs an α scale factor beyond 3 σ.
#[test]
fn val_a_wings_level_record_without_ay_is_checked_in_the_vertical_plane() {
    use aeroident_estimators::compat::{Channel, Unknown, VERTICAL_PLANE_NOTE};
    let m = Mapping::from_path(&workspace().join("mappings/attas.toml")).unwrap();
    let mut biases = Vec::new();
    for name in ["fAttasElv1.csv", "fAttasElv2.csv"] {
        let Some(data) = shared(&format!("jategaonkar_hfb320_attas/csv/{name}")) else { return };
        let log = open_log(&data.display().to_string(), None, &m).unwrap();
        let (summary, result) = check_records(vec![log], &[], &CompatConfig::default()).unwrap();
        assert!(
            summary.warnings.iter().any(|w| w == VERTICAL_PLANE_NOTE),
            "{:?}",
            summary.warnings
        );
        assert!(result.get(Unknown::Bias(Channel::P)).is_none());
        assert!(!result.outputs.contains(&Channel::Phi));
        let (k, s) = result.get(Unknown::Scale(Channel::Alpha)).expect("α scale factor");
        assert!(k.abs() < 3.0 * s, "{name}: α scale error {k} ± {s}");
        biases.push(result.reported(Unknown::Bias(Channel::Alpha)).expect("α bias"));
    }
    let ((b1, s1), (b2, s2)) = (biases[0], biases[1]);
    assert!((b1 - b2).abs() < 3.0 * s1.hypot(s2), "α bias {b1} ± {s1} vs {b2} ± {s2}");
}

/// The check's errors in the user's words: a manoeuvre too short by its number, time span and
/// sample count (not the estimator's `manoeuvre` = 0), and a channel it needs by the mapping's
/// channel and how many samples lack it (not `q_rad_s` = NaN).
#[test]
fn val_compat_errors_name_the_manoeuvre_and_the_channel() {
    let Some(data) = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let map = workspace().join("mappings/hfb320.toml");
    let m = Mapping::from_path(&map).unwrap();
    let path = data.display().to_string();
    let open = |m: &Mapping| open_log(&path, None, m).unwrap();
    let config = CompatConfig::default();
    let windows = vec![TimeWindow::parse("5:25").unwrap(), TimeWindow::parse("30:30.7").unwrap()];
    let e = check_records(vec![open(&m)], &windows, &config).unwrap_err().to_string();
    assert!(
        e.contains(&format!(
            "manoeuvre 2 of 2 ({path} from row 302, t = 30.00–30.60 s, 7 samples) is too short"
        )) && !e.contains("`manoeuvre`"),
        "{e}"
    );
    let text = std::fs::read_to_string(&map).unwrap();
    let without: String =
        text.lines().filter(|l| !l.starts_with("q = ")).collect::<Vec<_>>().join("\n");
    assert_ne!(without, text.trim_end(), "the mapping's `q = ` line was not found");
    let edited =
        std::env::temp_dir().join(format!("aeroident-compat-noq-{}.toml", std::process::id()));
    std::fs::write(&edited, without).unwrap();
    let no_q = Mapping::from_path(&edited).unwrap();
    let _ = std::fs::remove_file(&edited);
    let e = check_records(vec![open(&no_q)], &[], &config).unwrap_err().to_string();
    assert!(
        e.contains("channel `q` (not in the mapping) is missing in 601 of 601 samples")
            && !e.contains("q_rad_s"),
        "{e}"
    );
}
