//! The replay summary's `rejections` list is bounded (it grew by ≈ 100 bytes per
//! rejected row, without bound in a 24 h live feed): the first
//! [`RejectionLog::DEFAULT_LIMIT`] entries and the last are listed, the rest counted per kind
//! in a warning, and `samples_rejected` still counts every rejected row.

use crate::common;
use aeroident_io::warning::{Warning, WarningKind, Warnings};
use aeroident_io::{FlightDataReader, Mapping, RejectionLog};
use aeroident_pipelines::replay::batch::FitOptions;
use aeroident_pipelines::replay::fit::fit_record;
use aeroident_pipelines::replay::{ReplayOptions, replay};

/// Longitudinal channels; the record's interval is 0.1 s but every other row is rejected, so
/// the accepted samples are 0.2 s apart: the nominal interval (no gaps).
const MAP: &str = "nominal_dt_s = 0.2\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nq = { column = \"q\", unit = \"rad/s\" }\nax = { column = \"ax\", unit = \"m/s2\" }\naz = { column = \"az\", unit = \"m/s2\" }\nde = { column = \"de\", unit = \"rad\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\ncbar = { value = 1.5, unit = \"m\" }\nIyy = { value = 2000.0, unit = \"kg*m2\" }\n";

/// 3,000 rows (file rows 2…3001), the odd-numbered ones (rows 3, 5, …, 3001: 1,500) with a
/// blank `de`; the differentiator (window 3, lag 1) cannot centre the first and the last
/// accepted sample: 1,502 rejected samples, 1,502 entries, of which 1,001 are listed.
#[test]
fn errors_many_rejected_rows_give_a_bounded_list_a_full_count_and_a_warning() {
    const ROWS: usize = 3_000;
    let mut csv = String::from("t,V,a,q,ax,az,de\n");
    for k in 0..ROWS {
        let t = k as f64 * 0.1;
        let (a, q, de) = (0.05 + 0.01 * (0.7 * t).sin(), 0.1 * t.sin(), 0.02 * (1.3 * t).cos());
        let az = -9.8 - 2.0 * a;
        if k % 2 == 1 {
            csv.push_str(&format!("{t:.1},50,{a},{q},0.1,{az},\n"));
        } else {
            csv.push_str(&format!("{t:.1},50,{a},{q},0.1,{az},{de}\n"));
        }
    }
    let m = Mapping::from_toml_str(MAP, "many.toml").unwrap();
    let reader = FlightDataReader::new(csv.as_bytes(), "many.csv", &m).unwrap();
    let opts = ReplayOptions { diff_window: 3, ..Default::default() };
    let o = replay(reader, &m, &opts, &mut ()).unwrap();
    let s = &o.summary;
    assert_eq!(s.samples_read, ROWS);
    assert_eq!(s.samples_rejected, ROWS / 2 + 2, "every rejected row counted");
    // Bounded: the first 1,000 entries and the last.
    assert_eq!(s.rejections.len(), RejectionLog::DEFAULT_LIMIT + 1);
    let blanks: Vec<u64> =
        s.rejections.iter().filter(|r| r.reason.contains("blank value")).map(|r| r.row).collect();
    assert_eq!(blanks[0], 3);
    assert!(blanks.windows(2).all(|w| w[1] == w[0] + 2), "the first ones, in order");
    // The last entry is the last event: the end-of-record sample the differentiator could not
    // centre (row 3000, the last accepted row).
    let last = s.rejections.last().unwrap();
    assert_eq!(last.row, ROWS as u64);
    assert!(last.reason.contains("end of record"), "{}", last.reason);
    // The other 501 entries (all blank `de`: rows 2003…3001) are counted in one warning.
    let w: Vec<&Warning> = s.warnings.iter().filter(|w| w.contains("not listed")).collect();
    assert_eq!(w.len(), 1, "{:?}", s.warnings);
    assert!(w[0].starts_with("501 further rejections not listed"), "{}", w[0]);
    assert!(w[0].contains("501 × blank value"), "{}", w[0]);
    // ≈ 100 bytes per listed entry: the JSON list stays small whatever the record's length.
    let json = serde_json::to_string(&s.rejections).unwrap();
    assert!(json.len() < 150 * (RejectionLog::DEFAULT_LIMIT + 1), "{} bytes", json.len());
}

/// The HFB-320 record (10 Hz, time in seconds) through its mapping with the time unit declared
/// `ms`: the record would last 0.06 s. The replay says so in the summary's warnings, for a
/// real-time estimator and for the batch fit alike, naming the unit that gives 10 Hz.
#[test]
fn errors_time_unit_off_by_1000_is_a_summary_warning() {
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let text = std::fs::read_to_string(common::workspace().join("mappings/hfb320.toml")).unwrap();
    let text = text.replace(
        "[time]\ncolumn = \"time_s\"\nunit = \"s\"",
        "[time]\ncolumn = \"time_s\"\nunit = \"ms\"",
    );
    assert!(text.contains("unit = \"ms\""));
    let m = Mapping::from_toml_str(&text, "hfb320-ms.toml").unwrap();
    let open = || {
        let f = std::fs::File::open(&data).unwrap();
        FlightDataReader::new(std::io::BufReader::new(f), "hfb320.csv", &m).unwrap()
    };
    let wanted = |warnings: &[Warning]| {
        let w: Vec<&Warning> = warnings.iter().filter(|w| w.contains("time column")).collect();
        assert_eq!(w.len(), 1, "{warnings:?}");
        assert!(
            w[0].contains("`time_s` in `ms`") && w[0].contains("0.0001 s (10000 Hz)"),
            "{}",
            w[0]
        );
        assert!(w[0].contains("with `unit = \"s\"` it would be 0.1 s (10 Hz)"), "{}", w[0]);
    };
    let o = replay(open(), &m, &ReplayOptions::default(), &mut ()).unwrap();
    wanted(&o.summary.warnings);
    let fit = fit_record(open(), &m, None, FitOptions::default()).unwrap();
    wanted(&fit.summary.warnings);
}

/// A row's problem names the mapping's channel and column, not the sample's SI field: a
/// one-row spike on `q` (column `Q_rate`) and a `de` made implausible by the mapping's offset
/// (every row rejected) both say `channel … (column …)`, the latter with the offset.
#[test]
fn errors_row_problems_name_the_mapping_channel_and_column() {
    let map = MAP.replace("column = \"q\"", "column = \"Q_rate\"");
    let mut csv = String::from("t,V,a,Q_rate,ax,az,de\n");
    for k in 0..200 {
        let t = k as f64 * 0.2;
        let (a, de) = (0.05 + 0.01 * (0.7 * t).sin(), 0.02 * (1.3 * t).cos());
        let q = if k == 100 { 5.0 } else { 0.1 * t.sin() };
        csv.push_str(&format!("{t:.1},50,{a},{q},0.1,{},{de}\n", -9.8 - 2.0 * a));
    }
    let m = Mapping::from_toml_str(&map, "names.toml").unwrap();
    let reader = FlightDataReader::new(csv.as_bytes(), "names.csv", &m).unwrap();
    let o = replay(reader, &m, &ReplayOptions::default(), &mut ()).unwrap();
    let spike = o.summary.rejections.iter().find(|r| r.row == 102).expect("row 102 rejected");
    assert!(
        spike.reason.starts_with("channel `q` (column `Q_rate`) = 5 is an isolated spike"),
        "{}",
        spike.reason
    );
    let map = map.replace(
        "de = { column = \"de\", unit = \"rad\" }",
        "de = { column = \"de\", unit = \"rad\", offset = 3.0 }",
    );
    let m = Mapping::from_toml_str(&map, "offset.toml").unwrap();
    let reader = FlightDataReader::new(csv.as_bytes(), "offset.csv", &m).unwrap();
    let Err(e) = replay(reader, &m, &ReplayOptions::default(), &mut ()) else {
        panic!("no usable samples expected")
    };
    let text = e.to_string();
    assert!(
        text.contains("row 2: channel `de` (column `de`, the mapping's offset 3 applied) = 3.02"),
        "{text}"
    );
}

/// A channel a model term needs that holds one value over the whole record (an elevator not
/// moved, a rate channel stuck at 0) is named in a summary warning with the parameters it
/// leaves unidentifiable; a record where it varies gets no such warning.
#[test]
fn errors_a_constant_channel_is_named_with_the_parameters_it_leaves_unidentified() {
    let record = |de_fixed: Option<f64>, q_fixed: Option<f64>| {
        let mut csv = String::from("t,V,a,q,ax,az,de\n");
        for k in 0..300 {
            let t = k as f64 * 0.2;
            let a = 0.05 + 0.01 * (0.7 * t).sin();
            let q = q_fixed.unwrap_or(0.1 * t.sin());
            let de = de_fixed.unwrap_or(0.02 * (1.3 * t).cos());
            csv.push_str(&format!("{t:.1},50,{a},{q},0.1,{},{de}\n", -9.8 - 2.0 * a));
        }
        let m = Mapping::from_toml_str(MAP, "const.toml").unwrap();
        let reader = FlightDataReader::new(csv.as_bytes(), "const.csv", &m).unwrap();
        let o = replay(reader, &m, &ReplayOptions::default(), &mut ()).unwrap();
        o.summary.warnings
    };
    // Found by their kind, not their words.
    let constant = |w: &Warnings| -> Vec<String> {
        w.iter()
            .filter(|w| w.kind == WarningKind::ConstantChannel)
            .map(|w| w.text.clone())
            .collect()
    };
    assert!(constant(&record(None, None)).is_empty());
    let w = constant(&record(Some(0.01), None));
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("channel `de` (column `de`) does not vary"), "{}", w[0]);
    assert!(w[0].contains("0.01 in all") && w[0].contains("Cm_de"), "{}", w[0]);
    assert!(!w[0].contains("Cm_q") && !w[0].contains("Cm_alpha"), "{}", w[0]);
    let w = constant(&record(None, Some(0.0)));
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("channel `q` (column `q`)") && w[0].contains("Cm_q"), "{}", w[0]);
}

/// The HFB-320 record with `q` mapped as deg/s (its column is in rad/s), or `theta` as deg:
/// the Euler kinematics against the differentiated attitude give q a gain of 57.3 (or 1/57.3),
/// and the summary warns, naming the channel, its column and the likely unit, for the
/// real-time and the batch path; the shipped mapping warns of nothing.
#[test]
fn errors_a_rate_in_the_wrong_unit_is_warned_of() {
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else {
        return;
    };
    let text = std::fs::read_to_string(common::workspace().join("mappings/hfb320.toml")).unwrap();
    let warnings = |mapping: &str| {
        let m = Mapping::from_toml_str(mapping, "hfb.toml").unwrap();
        let open = || aeroident_io::open_log(&data.display().to_string(), None, &m).unwrap();
        let online = replay(open(), &m, &ReplayOptions::default(), &mut ()).unwrap();
        let batch = fit_record(open(), &m, None, FitOptions::default()).unwrap();
        let units = |w: &[Warning]| -> Vec<String> {
            let kind = |w: &&Warning| w.kind == WarningKind::UnitMismatch;
            w.iter().filter(kind).map(|w| w.text.clone()).collect()
        };
        (units(&online.summary.warnings), units(&batch.summary.warnings))
    };
    assert_eq!(warnings(&text), (vec![], vec![]));
    let q_deg = text.replace(
        "q = { column = \"q_radps\", unit = \"rad/s\" }",
        "q = { column = \"q_radps\", unit = \"deg/s\" }",
    );
    assert_ne!(q_deg, text);
    let (online, batch) = warnings(&q_deg);
    for w in [&online, &batch] {
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("channel `q` (column `q_radps`"), "{}", w[0]);
        assert!(w[0].contains("rad/s data mapped as deg/s"), "{}", w[0]);
    }
    let theta_deg = text.replace(
        "theta = { column = \"theta_rad\", unit = \"rad\" }",
        "theta = { column = \"theta_rad\", unit = \"deg\" }",
    );
    let (online, _) = warnings(&theta_deg);
    assert!(
        online.iter().any(|w| w.contains("channel `q`") && w.contains("57.3 times too large")),
        "{online:?}"
    );
}
