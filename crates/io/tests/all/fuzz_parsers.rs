//! Fuzzing of the io parsers (their input is any file a user has, so none may panic): the CSV
//! flight-data reader, the mapping TOML and the model file, on arbitrary and on mutated valid
//! input. Bounded for CI by `PROPTEST_CASES`
//! (default 64); the long run and its measured rate are in `docs/reliability.md`.
//!
//! Relations checked, not only "no panic": every data row yields exactly one `Sample` or
//! `Rejected` event, in row order, a `Gap` only directly before the `Sample` of its row; every
//! sample is finite and within the estimators' plausibility limits; a row of sane values on the
//! time grid always yields a sample; every error names the file.

use aeroident_io::{FlightDataReader, Mapping, ModelSpec, RecordEvent};
use proptest::prelude::*;

use crate::common::mutate::mutate;

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(64)
}

const MAPPING: &str = include_str!("../data/min.toml");
const HEADER: &str = "t,V,a,q,ax,az,de,qbar,qd";
/// The file name errors must carry (distinctive so it cannot appear by chance).
const FILE: &str = "fuzz-target.input";

/// Valid seeds for the mutation fuzzing: the shipped mappings and model files.
const MAPPINGS: [&str; 9] = [
    MAPPING,
    include_str!("../../../../mappings/attas.toml"),
    include_str!("../../../../mappings/attas_lateral.toml"),
    include_str!("../../../../mappings/hfb320.toml"),
    include_str!("../../../../mappings/jsbsim.toml"),
    include_str!("../../../../mappings/jsbsim_clean.toml"),
    include_str!("../../../../mappings/twin_otter.toml"),
    include_str!("../../../../mappings/px4-fixedwing.toml"),
    include_str!("../../../../mappings/arduplane.toml"),
];
const MODELS: [&str; 3] = [
    include_str!("../../../../models/hfb320_book_q0.toml"),
    include_str!("../../../../models/hfb320_jategaonkar.toml"),
    include_str!("../../../../models/short_period_alphadot.toml"),
];

/// One field of a hostile row: numbers of every size and sign, text, blanks, NaN/inf.
fn field() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<f64>().prop_map(|v| v.to_string()),
        (-1e3f64..1e3).prop_map(|v| v.to_string()),
        prop::sample::select(vec![
            "",
            " ",
            "nan",
            "NaN",
            "inf",
            "-inf",
            "1e308",
            "-1e308",
            "1e-320",
            "0",
            "-0",
            "abc",
            "1,5",
            "0x10",
            "+",
            "1e",
            "--1",
            "\u{feff}1",
        ])
        .prop_map(str::to_string),
        "[0-9eE+.-]{1,8}",
    ]
    .prop_map(|s| s.replace(',', ";"))
}

/// A row: either sane values (must be a sample) or hostile fields (any count, time on the grid
/// or hostile). The time grid `k · 0.1 s` makes sane rows strictly later than every accepted
/// sample.
#[derive(Debug, Clone)]
enum Row {
    Sane([f64; 8]),
    Hostile { time_on_grid: bool, fields: Vec<String> },
}

fn row() -> impl Strategy<Value = Row> {
    prop_oneof![
        (
            100.0f64..300.0, // V, kt
            -10.0f64..10.0,  // alpha, deg
            -20.0f64..20.0,  // q, deg/s
            -2.0f64..2.0,    // ax, g
            -3.0f64..1.0,    // az, g
            -50.0f64..50.0,  // de, deg
            0.3f64..1.3,     // density, kg/m³ (q̄ is formed from it and V: ρ = 2 q̄ / V² is checked)
            -50.0f64..50.0,  // qdot, deg/s²
        )
            .prop_map(|(a, b, c, d, e, f, rho, h)| {
                let v_mps = a * 1852.0 / 3600.0;
                let qbar_psf = 0.5 * rho * v_mps * v_mps / 47.880_258_980_335_84;
                Row::Sane([a, b, c, d, e, f, qbar_psf, h])
            }),
        (any::<bool>(), prop::collection::vec(field(), 1..12))
            .prop_map(|(time_on_grid, fields)| Row::Hostile { time_on_grid, fields }),
    ]
}

fn render(rows: &[Row], crlf: bool, final_newline: bool) -> String {
    let nl = if crlf { "\r\n" } else { "\n" };
    let mut s = format!("{HEADER}{nl}");
    for (k, r) in rows.iter().enumerate() {
        let t = format!("{:.1}", 0.1 * (k as f64 + 1.0));
        let line = match r {
            Row::Sane(v) => {
                let rest: Vec<String> = v.iter().map(|x| x.to_string()).collect();
                format!("{t},{}", rest.join(","))
            }
            Row::Hostile { time_on_grid, fields } => {
                let mut f = fields.clone();
                if *time_on_grid {
                    f[0] = t;
                }
                // A line that is blank after trimming is not a record (the CSV parser skips
                // it); keep at least two fields so every line is one.
                if f.len() == 1 {
                    f.push(String::new());
                }
                f.join(",")
            }
        };
        s.push_str(&line);
        if k + 1 < rows.len() || final_newline {
            s.push_str(nl);
        }
    }
    s
}

/// The relation every event stream must satisfy; returns the rows that gave a sample.
fn check_events(events: &[RecordEvent]) -> Result<Vec<u64>, TestCaseError> {
    let mut rows = Vec::new();
    let mut sampled = Vec::new();
    let mut last_t = f64::NEG_INFINITY;
    for (i, e) in events.iter().enumerate() {
        match e {
            RecordEvent::Sample { row, sample } => {
                prop_assert!(sample.first_non_finite().is_none(), "row {row}: {sample:?}");
                prop_assert!(
                    sample.first_implausible().is_none(),
                    "row {row}: {:?}",
                    sample.first_implausible()
                );
                prop_assert!(sample.t_s > last_t, "row {row}: time not increasing");
                last_t = sample.t_s;
                rows.push(*row);
                sampled.push(*row);
            }
            RecordEvent::Rejected { row, problem } => {
                prop_assert!(!problem.to_string().is_empty());
                rows.push(*row);
            }
            RecordEvent::Gap { row, dt_s, nominal_dt_s } => {
                prop_assert!(dt_s > nominal_dt_s, "gap {dt_s} ≤ nominal {nominal_dt_s}");
                let next = events.get(i + 1);
                prop_assert!(
                    matches!(next, Some(RecordEvent::Sample { row: r, .. }) if r == row),
                    "gap at row {row} not followed by its sample: {next:?}"
                );
            }
        }
    }
    prop_assert!(rows.windows(2).all(|w| w[0] < w[1]), "rows out of order: {rows:?}");
    Ok(sampled)
}

/// Edits: inserted text leans on TOML's syntax characters and on numbers of every size.
fn edits() -> impl Strategy<Value = Vec<(usize, u8, String)>> {
    let text = prop_oneof![
        r#"[\[\]{}="',.#\n a-z0-9_-]{0,6}"#,
        prop::sample::select(vec![
            "nan",
            "inf",
            "-inf",
            "1e308",
            "-1",
            "0",
            "\"\"",
            "[[",
            "]]",
            "\"deg\"",
            "\"xyz\"",
            "true",
            "{}",
            "[]",
            "1e-320",
            "\"\\u0000\"",
        ])
        .prop_map(str::to_string),
        any::<String>(),
    ];
    prop::collection::vec((any::<usize>(), any::<u8>(), text), 1..6)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), ..ProptestConfig::default() })]

    /// Structured hostile rows: exactly one `Sample`/`Rejected` per data row, in order, and
    /// every sane row on the time grid is a sample.
    #[test]
    fn fuzz_csv_rows_one_event_each(
        rows in prop::collection::vec(row(), 0..40),
        crlf in any::<bool>(),
        final_newline in any::<bool>(),
    ) {
        let m = Mapping::from_toml_str(MAPPING, "min.toml").unwrap();
        let text = render(&rows, crlf, final_newline);
        let reader = FlightDataReader::new(text.as_bytes(), FILE, &m).unwrap();
        let events: Result<Vec<RecordEvent>, _> = reader.collect();
        if rows.is_empty() {
            // A header alone is "no data", naming the file.
            let e = events.err().map(|e| e.to_string()).unwrap_or_default();
            prop_assert!(e.starts_with(&format!("{FILE}: the file has no data")), "{}", e);
            return Ok(());
        }
        let events = events.map_err(|e| TestCaseError::fail(e.to_string()))?;
        let sampled = check_events(&events)?;
        let all: Vec<u64> = events
            .iter()
            .filter_map(|e| match e {
                RecordEvent::Sample { row, .. } | RecordEvent::Rejected { row, .. } => Some(*row),
                RecordEvent::Gap { .. } => None,
            })
            .collect();
        let expected: Vec<u64> = (2..rows.len() as u64 + 2).collect();
        prop_assert_eq!(all, expected, "one event per data row (line 2 = first row)");
        for (k, r) in rows.iter().enumerate() {
            if matches!(r, Row::Sane(_)) {
                prop_assert!(sampled.contains(&(k as u64 + 2)), "sane row {} rejected: {:?}", k + 2,
                    events.iter().find(|e| matches!(e, RecordEvent::Rejected { row, .. } if *row == k as u64 + 2)));
            }
        }
    }

    /// Arbitrary bytes after a valid header (quotes, line breaks, invalid UTF-8): no panic, the
    /// event relation holds, at most one error and it ends the stream and names the file.
    #[test]
    fn fuzz_csv_arbitrary_bytes(body in prop::collection::vec(any::<u8>(), 0..600), live in any::<bool>()) {
        let m = Mapping::from_toml_str(MAPPING, "min.toml").unwrap();
        let mut text = format!("{HEADER}\n").into_bytes();
        text.extend(body);
        let file = if live { "-" } else { FILE };
        let mut events = Vec::new();
        let mut errors = 0;
        for e in FlightDataReader::new(&text[..], file, &m).unwrap() {
            prop_assert_eq!(errors, 0, "an event after a fatal error");
            match e {
                Ok(ev) => events.push(ev),
                Err(err) => {
                    errors += 1;
                    let s = err.to_string();
                    prop_assert!(s.starts_with(file), "error does not name the file: {}", s);
                }
            }
        }
        check_events(&events)?;
    }

    /// Arbitrary headers and bodies: opening never panics; an error names the file.
    #[test]
    fn fuzz_csv_arbitrary_header(text in prop::collection::vec(any::<u8>(), 0..300)) {
        let m = Mapping::from_toml_str(MAPPING, "min.toml").unwrap();
        match FlightDataReader::new(&text[..], FILE, &m) {
            Ok(r) => {
                let events: Vec<RecordEvent> = r.filter_map(Result::ok).collect();
                check_events(&events)?;
            }
            Err(e) => prop_assert!(e.to_string().contains(FILE), "{}", e),
        }
    }

    /// Arbitrary text as a mapping or model file: never panics; an error names the file.
    #[test]
    fn fuzz_mapping_and_model_arbitrary(text in any::<String>()) {
        if let Err(e) = Mapping::from_toml_str(&text, FILE) {
            prop_assert!(e.to_string().contains(FILE), "{}", e);
        }
        if let Err(e) = ModelSpec::from_toml_str(&text, FILE) {
            prop_assert!(e.to_string().contains(FILE), "{}", e);
        }
    }

    /// Mutated shipped mappings: never panic; an error names the file; an accepted mapping
    /// reads the corpus header without panicking.
    #[test]
    fn fuzz_mapping_mutated(seed in 0..MAPPINGS.len(), e in edits()) {
        let text = mutate(MAPPINGS[seed], &e);
        match Mapping::from_toml_str(&text, FILE) {
            Ok(m) => {
                let csv = format!("{HEADER}\n0.1,200,2,0.5,0,-1,1,100,0\n");
                if let Ok(r) = FlightDataReader::new(csv.as_bytes(), "data.csv", &m) {
                    let events: Vec<RecordEvent> = r.filter_map(Result::ok).collect();
                    check_events(&events)?;
                }
            }
            Err(e) => prop_assert!(e.to_string().contains(FILE), "{}", e),
        }
    }

    /// Mutated shipped model files: never panic; an error names the file.
    #[test]
    fn fuzz_model_mutated(seed in 0..MODELS.len(), e in edits()) {
        let text = mutate(MODELS[seed], &e);
        if let Err(e) = ModelSpec::from_toml_str(&text, FILE) {
            prop_assert!(e.to_string().contains(FILE), "{}", e);
        }
    }
}

/// The seeds themselves are valid (else the mutation tests would only fuzz error paths).
#[test]
fn seeds_parse() {
    for (k, s) in MAPPINGS.iter().enumerate() {
        Mapping::from_toml_str(s, &format!("mapping seed {k}")).unwrap();
    }
    for (k, s) in MODELS.iter().enumerate() {
        ModelSpec::from_toml_str(s, &format!("model seed {k}")).unwrap();
    }
}
