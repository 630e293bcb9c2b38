//! The bad-input corpus (`tests/data/`, small synthetic files written for these tests): every
//! documented error names the file, row and column; nothing panics; nothing is dropped without
//! an event.

use aeroident_io::{FlightDataError, FlightDataReader, Mapping, RecordEvent, RowProblem};
use proptest::prelude::*;
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

fn mapping() -> Mapping {
    Mapping::from_path(&data("min.toml")).unwrap()
}

fn events(csv: &str) -> Vec<RecordEvent> {
    let m = mapping();
    let f = std::fs::File::open(data(csv)).unwrap();
    FlightDataReader::new(f, csv, &m).unwrap().map(|e| e.unwrap()).collect()
}

#[test]
fn analytic_good_file_converts_units_to_si() {
    let ev = events("good.csv");
    assert_eq!(ev.len(), 3);
    let RecordEvent::Sample { row, sample } = &ev[2] else { panic!("{:?}", ev[2]) };
    assert_eq!(*row, 4);
    assert!((sample.vt_mps - 201.0 * 1852.0 / 3600.0).abs() < 1e-12);
    assert!((sample.alpha_rad - 2.2f64.to_radians()).abs() < 1e-15);
    assert!((sample.q_rad_s - 0.3f64.to_radians()).abs() < 1e-15);
    assert!((sample.az_mps2 + 1.01 * 9.80665).abs() < 1e-12);
    // SI = (raw·scale + offset)·unit: (−1.5 + 0.5) deg.
    assert!((sample.de_rad - (-1.0f64).to_radians()).abs() < 1e-15);
    assert!((sample.qbar_pa.unwrap() - 100.0 * 47.880_258_980_335_84).abs() < 1e-9);
    assert!((sample.mass_kg - 100.0 * 14.593_902_937_206_364).abs() < 1e-9);
    assert_eq!(sample.theta_rad, None);
    assert_eq!(sample.thrust_n, 0.0);
}

#[test]
fn errors_bad_rows_are_rejected_with_row_column_and_reason() {
    let ev = events("bad_values.csv");
    let rejected: Vec<(u64, RowProblem)> = ev
        .iter()
        .filter_map(|e| match e {
            RecordEvent::Rejected { row, problem } => Some((*row, problem.clone())),
            _ => None,
        })
        .collect();
    let expect = [
        (3, "column `a`: blank value"),
        (4, "column `q`: non-finite value `NaN`"),
        (5, "column `ax`: `abc` is not a number"),
        (7, "column `t`: repeated time 0.3 s"),
        (8, "column `t`: time 0.25 s goes backwards (previous 0.3 s)"),
        (9, "6 fields, header has 9"),
        (10, "column `V`: vt must be > 0, got -2.57"),
        (11, "column `qbar`: non-finite value `inf`"),
    ];
    assert_eq!(rejected.len(), expect.len(), "{rejected:?}");
    for ((row, problem), (erow, msg)) in rejected.iter().zip(expect.iter()) {
        assert_eq!(row, erow);
        assert!(problem.to_string().starts_with(msg), "row {row}: `{problem}` vs `{msg}`");
    }
    // Gaps are reported before the sample that follows them, never bridged silently.
    let gaps: Vec<(u64, f64)> = ev
        .iter()
        .filter_map(|e| match e {
            RecordEvent::Gap { row, dt_s, .. } => Some((*row, *dt_s)),
            _ => None,
        })
        .collect();
    assert_eq!(gaps.len(), 2);
    assert_eq!(gaps[0].0, 6);
    assert!((gaps[0].1 - 0.3).abs() < 1e-12);
    assert_eq!(gaps[1].0, 12);
    // Every data row produced exactly one sample or rejection.
    let samples = ev.iter().filter(|e| matches!(e, RecordEvent::Sample { .. })).count();
    assert_eq!(samples + rejected.len(), 12);
}

#[test]
fn errors_missing_column_names_file_channel_and_column() {
    let m = mapping();
    let f = std::fs::File::open(data("missing_column.csv")).unwrap();
    let e = FlightDataReader::new(f, "missing_column.csv", &m).err().unwrap();
    assert!(matches!(e, FlightDataError::MissingColumn { .. }));
    assert_eq!(
        e.to_string(),
        "missing_column.csv: row 1 (header): column `a` for channel `alpha` is missing"
    );
}

#[test]
fn errors_bad_mappings_name_file_and_channel() {
    let cases: [(&str, &str); 6] = [
        ("bad_unit.toml", "channel `vt`: unit `furlongs/fortnight` is not recognised"),
        ("wrong_dimension.toml", "channel `alpha`: unit `deg/s` is not a angle (rad, deg) unit"),
        ("missing_channel.toml", "required channel `q` is not mapped"),
        ("unknown_channel.toml", "unknown channel `airspeed`"),
        ("syntax.toml", "mapping syntax"),
        ("two_sources.toml", "channel `mass`: give exactly one of"),
    ];
    for (file, msg) in cases {
        let e =
            Mapping::from_path(&data(file)).err().unwrap_or_else(|| panic!("{file} should fail"));
        let s = e.to_string();
        assert!(s.contains(file), "{s}");
        assert!(s.contains(msg), "{file}: `{s}` lacks `{msg}`");
    }
    // The TOML syntax error carries the line.
    let s = Mapping::from_path(&data("syntax.toml")).err().unwrap().to_string();
    assert!(s.contains("line 4"), "{s}");
    let e = Mapping::from_path(&data("nope.toml")).err().unwrap();
    assert!(matches!(e, FlightDataError::Io { .. }));
}

proptest! {
    /// Arbitrary bytes after a valid header never panic and every row yields one event.
    #[test]
    fn prop_random_rows_never_panic(body in proptest::collection::vec(any::<u8>(), 0..400)) {
        let mut text = b"t,V,a,q,ax,az,de,qbar,qd\n".to_vec();
        text.extend(body);
        let m = mapping();
        if let Ok(r) = FlightDataReader::new(&text[..], "fuzz", &m) {
            for e in r {
                let _ = e;
            }
        }
    }
}
