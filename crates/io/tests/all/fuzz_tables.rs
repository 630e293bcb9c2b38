//! Fuzzing of the table readers: FVSysID `.asc` text (`log::asc_reader`), MATLAB level-5
//! `.mat` (`log::read_mat` + `log::table_reader`) and the multi-rate alignment tables
//! (`multirate::log_table`, the mapping's `[align]` over a log's topics). Bounded for CI by
//! `PROPTEST_CASES` (default 64). Checked: no panic; an error names the file (or the mapping);
//! the reader's event relation (one `Sample` or `Rejected` per data row, rows in order, every
//! sample finite and within the plausibility limits); a valid `.mat` built here reads back
//! bit for bit; an aligned table keeps its invariant (equal column lengths, time strictly
//! increasing and finite, within every topic's span).

use aeroident_estimators::sample::PLAUSIBILITY;
use aeroident_io::log::{asc_reader, read_mat, table_reader};
use aeroident_io::multirate::{log_table, needed_columns};
use aeroident_io::table::Topic;
use aeroident_io::{FlightDataError, Mapping, RecordEvent};
use proptest::prelude::*;
use std::io::Cursor;

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(64)
}

const FILE: &str = "fuzz-target.dat";

/// Columns by position (`.asc` without `[columns] names`; a `.mat` matrix likewise).
const MAP: &str = "nominal_dt_s = 0.1\n[time]\ncolumn = \"1\"\nunit = \"s\"\n[channels]\nvt = { column = \"2\", unit = \"m/s\" }\nalpha = { column = \"3\", unit = \"deg\" }\nqbar = { column = \"4\", unit = \"Pa\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\n";

fn mapping() -> Mapping {
    Mapping::from_toml_str(MAP, "fuzz.toml").unwrap()
}

/// Drains a reader: the event relation, and at most one fatal error, which ends the stream
/// and names the file. Returns the data rows (sample or rejected) in order.
fn drain(
    reader: impl Iterator<Item = Result<RecordEvent, FlightDataError>>,
) -> Result<Vec<u64>, TestCaseError> {
    let mut rows = Vec::new();
    let mut fatal = false;
    let mut gap_row = None;
    for ev in reader {
        prop_assert!(!fatal, "an event after a fatal error");
        match ev {
            Err(e) => {
                prop_assert!(e.to_string().contains(FILE), "{}", e);
                fatal = true;
            }
            Ok(RecordEvent::Gap { row, .. }) => gap_row = Some(row),
            Ok(RecordEvent::Sample { row, sample }) => {
                if let Some(g) = gap_row.take() {
                    prop_assert_eq!(g, row, "a gap directly precedes its row's sample");
                }
                prop_assert!(sample.vt_mps.is_finite() && sample.vt_mps > 0.0);
                prop_assert!(sample.vt_mps <= PLAUSIBILITY.vt_mps);
                prop_assert!(sample.alpha_rad.abs() <= PLAUSIBILITY.angle_rad);
                prop_assert!(sample.t_s.is_finite() && sample.qbar_pa.is_finite());
                rows.push(row);
            }
            Ok(RecordEvent::Rejected { row, .. }) => {
                prop_assert!(gap_row.is_none(), "a gap before a rejected row");
                rows.push(row);
            }
        }
    }
    prop_assert!(rows.windows(2).all(|w| w[0] < w[1]), "rows in order: {:?}", rows);
    Ok(rows)
}

/// A token of an `.asc` line: a number (any f64, extreme or ordinary) or hostile text.
fn token() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (0.0f64..200.0).prop_map(|v| format!("{v}")),
        1 => any::<f64>().prop_map(|v| format!("{v:e}")),
        1 => Just("NaN".to_string()),
        1 => Just("-inf".to_string()),
        1 => Just("1e308".to_string()),
        1 => "[a-z,;\"]{1,4}",
    ]
}

/// A `.asc` line: 4 tokens (sometimes 3 or 5) joined by spaces or tabs, LF or CRLF.
fn line() -> impl Strategy<Value = String> {
    (prop::collection::vec(token(), 3..6), prop::bool::ANY, prop::bool::ANY, 0.0f64..1.0).prop_map(
        |(mut toks, tab, crlf, p)| {
            if p < 0.7 {
                toks.truncate(4);
                while toks.len() < 4 {
                    toks.push("1".into());
                }
            }
            let sep = if tab { "\t" } else { "  " };
            format!("{}{}", toks.join(sep), if crlf { "\r\n" } else { "\n" })
        },
    )
}

/// A minimal MATLAB level-5 `.mat` (MathWorks "MAT-File Format", level 5): the 128-byte
/// header and one `rows × cols` real double matrix `name` (column-major `values`).
fn tiny_mat(name: &str, rows: usize, cols: usize, values: &[f64]) -> Vec<u8> {
    let mut b = b"MATLAB 5.0 MAT-file, fuzz test".to_vec();
    b.resize(116, b' ');
    b.extend_from_slice(&[0u8; 8]); // subsystem offset
    b.extend_from_slice(&0x0100u16.to_le_bytes());
    b.extend_from_slice(b"IM");
    let tag = |ty: u32, len: usize, out: &mut Vec<u8>| {
        out.extend_from_slice(&ty.to_le_bytes());
        out.extend_from_slice(&(len as u32).to_le_bytes());
    };
    let pad = |out: &mut Vec<u8>| out.resize(out.len().div_ceil(8) * 8, 0);
    let mut m = Vec::new();
    tag(6, 8, &mut m); // miUINT32 array flags: mxDOUBLE_CLASS (6)
    m.extend_from_slice(&[6, 0, 0, 0, 0, 0, 0, 0]);
    tag(5, 8, &mut m); // miINT32 dimensions
    m.extend_from_slice(&(rows as i32).to_le_bytes());
    m.extend_from_slice(&(cols as i32).to_le_bytes());
    tag(1, name.len(), &mut m); // miINT8 name
    m.extend_from_slice(name.as_bytes());
    pad(&mut m);
    tag(9, values.len() * 8, &mut m); // miDOUBLE real part
    for v in values {
        m.extend_from_slice(&v.to_le_bytes());
    }
    pad(&mut m);
    tag(14, m.len(), &mut b); // miMATRIX
    b.extend_from_slice(&m);
    b
}

/// A valid 3-row record: t, V, α (deg), q̄ by column.
fn mat_values() -> Vec<f64> {
    vec![0.0, 0.1, 0.2, 50.0, 51.0, 52.0, 2.0, 2.5, 3.0, 1500.0, 1510.0, 1520.0]
}

#[test]
fn analytic_tiny_mat_reads_back_bit_for_bit() {
    let v = mat_values();
    let t = read_mat(Cursor::new(tiny_mat("rec", 3, 4, &v)), FILE, None).unwrap();
    assert_eq!(t.names, vec!["1", "2", "3", "4"]);
    assert_eq!(t.columns.concat(), v);
    let rows = drain(table_reader(t, &mapping()).unwrap()).unwrap();
    assert_eq!(rows, vec![1, 2, 3]);
}

#[test]
fn analytic_asc_lines_read_one_event_each() {
    let text = "0 50 2 1500\n0.1 51 2.5 1510\n0.2 x 3 1520\n";
    let reader = asc_reader(Cursor::new(text.as_bytes().to_vec()), FILE, &mapping()).unwrap();
    let mut kinds = Vec::new();
    for ev in reader {
        match ev.unwrap() {
            RecordEvent::Sample { row, sample } => kinds.push((row, sample.vt_mps)),
            RecordEvent::Rejected { row, .. } => kinds.push((row, f64::NAN)),
            RecordEvent::Gap { .. } => {}
        }
    }
    assert_eq!(kinds.len(), 3);
    assert_eq!((kinds[0], kinds[1]), ((1, 50.0), (2, 51.0)));
    assert!(kinds[2].0 == 3 && kinds[2].1.is_nan());
}

/// The shipped PX4 fixed-wing mapping (an `[align]` table, attitude quaternion, air data from
/// the NED velocity) and the log columns it reads.
fn px4_mapping() -> (Mapping, Vec<String>) {
    let p =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../mappings/px4-fixedwing.toml");
    let m = Mapping::from_path(&p).unwrap();
    let cols = needed_columns(&m).into_iter().map(|(c, _)| c).collect();
    (m, cols)
}

/// Topics for `columns` (`topic.field`): per topic a random time base (sorted or not, with
/// repeats, sometimes empty or non-finite) and random values for each of its fields.
fn topics_for(columns: &[String]) -> impl Strategy<Value = Vec<Topic>> {
    let mut names: Vec<String> = Vec::new();
    let mut fields: Vec<Vec<String>> = Vec::new();
    for c in columns {
        let (t, f) = c.split_once('.').unwrap_or((c.as_str(), "x"));
        match names.iter().position(|n| n == t) {
            Some(i) => fields[i].push(f.to_string()),
            None => {
                names.push(t.to_string());
                fields.push(vec![f.to_string()]);
            }
        }
    }
    let value = prop_oneof![
        6 => -2.0f64..2.0,
        1 => any::<f64>(),
        1 => Just(f64::NAN),
    ];
    let per_topic: Vec<_> = names
        .into_iter()
        .zip(fields)
        .map(move |(name, fields)| {
            let nf = fields.len();
            (
                prop::collection::vec((0.0f64..0.2, value.clone()), 0..40),
                prop::collection::vec(value.clone(), nf * 40),
                0.0f64..1.0,
            )
                .prop_map(move |(steps, vals, p)| {
                    let mut t = 0.0;
                    let mut t_s: Vec<f64> = steps
                        .iter()
                        .map(|(dt, _)| {
                            t += dt;
                            t
                        })
                        .collect();
                    if p < 0.1 {
                        t_s.reverse(); // not increasing
                    } else if p < 0.15 && !t_s.is_empty() {
                        t_s[0] = f64::NAN;
                    }
                    let n = t_s.len();
                    let fields = fields
                        .iter()
                        .enumerate()
                        .map(|(k, f)| (f.clone(), vals[k * 40..k * 40 + n].to_vec()))
                        .collect();
                    Topic { name: name.clone(), t_s, fields }
                })
        })
        .collect();
    per_topic
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), ..ProptestConfig::default() })]

    /// Arbitrary bytes as an `.asc` file: no panic; an error names the file.
    #[test]
    fn fuzz_asc_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..1024)) {
        match asc_reader(Cursor::new(bytes), FILE, &mapping()) {
            Ok(r) => { drain(r)?; }
            Err(e) => prop_assert!(e.to_string().contains(FILE), "{}", e),
        }
    }

    /// Hostile `.asc` lines (extreme numbers, NaN/inf, text, wrong field counts, tabs, CRLF):
    /// exactly one event per line, carrying its line number.
    #[test]
    fn fuzz_asc_lines_one_event_each(lines in prop::collection::vec(line(), 1..40)) {
        let first_ok = lines[0].split_whitespace().count() == 4;
        let text: String = lines.concat();
        match asc_reader(Cursor::new(text.into_bytes()), FILE, &mapping()) {
            Ok(r) => {
                let rows = drain(r)?;
                prop_assert_eq!(rows, (1..=lines.len() as u64).collect::<Vec<_>>());
            }
            Err(e) => {
                prop_assert!(!first_ok, "a 4-field first line is accepted: {}", e);
                prop_assert!(e.to_string().contains(FILE), "{}", e);
            }
        }
    }

    /// Arbitrary bytes after a valid `.mat` header: no panic; an error names the file.
    #[test]
    fn fuzz_mat_arbitrary_body(body in prop::collection::vec(any::<u8>(), 0..1024)) {
        let mut bytes = tiny_mat("rec", 0, 0, &[]);
        bytes.truncate(128);
        bytes.extend_from_slice(&body);
        match read_mat(Cursor::new(bytes), FILE, None) {
            Ok(t) => match table_reader(t, &mapping()) {
                Ok(r) => { drain(r)?; }
                Err(e) => prop_assert!(e.to_string().contains(FILE), "{}", e),
            },
            Err(e) => prop_assert!(e.to_string().contains(FILE), "{}", e),
        }
    }

    /// A valid `.mat` with random values, truncated and bit-flipped: no panic; an error names
    /// the file; a file read whole gives a table that keeps its invariant.
    #[test]
    fn fuzz_mat_mutated(
        vals in prop::collection::vec(any::<f64>(), 12),
        flips in prop::collection::vec((0usize..400, any::<u8>()), 0..6),
        cut in 0usize..400,
    ) {
        let mut bytes = tiny_mat("rec", 3, 4, &vals);
        for (at, x) in flips {
            let n = bytes.len();
            bytes[at % n] ^= x;
        }
        if cut < bytes.len() && cut % 3 == 0 {
            bytes.truncate(cut);
        }
        match read_mat(Cursor::new(bytes), FILE, None) {
            Ok(t) => {
                prop_assert_eq!(t.names.len(), t.columns.len());
                match table_reader(t, &mapping()) {
                    Ok(r) => { drain(r)?; }
                    Err(e) => prop_assert!(e.to_string().contains(FILE), "{}", e),
                }
            }
            Err(e) => prop_assert!(e.to_string().contains(FILE), "{}", e),
        }
    }

    /// Random topics for every column the shipped PX4 mapping reads (random time bases:
    /// empty, unsorted, NaN, overlapping or not; random and extreme values): no panic; an
    /// error names the log or the mapping; an aligned table has equal column lengths and a
    /// finite, strictly increasing time within every topic's span; its rows read with the
    /// event relation.
    #[test]
    fn fuzz_multirate_alignment(topics in topics_for(&px4_mapping().1)) {
        let (m, _) = px4_mapping();
        match log_table(&topics, &m, FILE) {
            Ok(a) => {
                let t = &a.table;
                prop_assert_eq!(t.names.len(), t.columns.len());
                let n = t.columns[0].len();
                prop_assert!(t.columns.iter().all(|c| c.len() == n));
                let time = &t.columns[0];
                prop_assert!(time.iter().all(|v| v.is_finite()));
                prop_assert!(time.windows(2).all(|w| w[0] < w[1]), "{:?}", time);
                for tp in &topics {
                    let lo = tp.t_s.iter().copied().fold(f64::INFINITY, f64::min);
                    prop_assert!(time.iter().all(|&x| x >= lo), "{} starts at {}", tp.name, lo);
                }
                prop_assert_eq!(a.rows_considered, n + a.dropped());
                let mut table = a.table;
                table.file = FILE.into();
                match table_reader(table, &m) {
                    Ok(r) => { drain(r)?; }
                    Err(e) => prop_assert!(e.to_string().contains(FILE), "{}", e),
                }
            }
            Err(e) => {
                let s = e.to_string();
                prop_assert!(s.contains(FILE) || s.contains("px4-fixedwing.toml"), "{}", s);
            }
        }
    }
}
