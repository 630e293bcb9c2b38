//! One road from wherever a record comes to the reader every step takes: a file of any
//! format, stdin, a live MAVLink feed or columns already in memory all open through
//! [`Record::open`] into the same [`LogReader`] and [`ReaderReport`]. The faces (CLI, Python)
//! say where the record is and render; they do not pick readers.
//!
//! | source | formats | what the face may add |
//! |---|---|---|
//! | [`RecordSource::Path`] | every [`LogFormat`] (`-`: stdin, text and `.mat` only) | nothing |
//! | [`RecordSource::Watched`] | every format; CSV, `.asc` and `.mat` through the face's wrapper | a progress bar over the file's bytes |
//! | [`RecordSource::Bytes`] | CSV, `.asc`, `.mat` (CSV unless a format is given) | the byte source: stdin a signal can end |
//! | [`RecordSource::Mavlink`] | a `mavlink:udp:` feed ([`crate::mavlink`]) | where the link's problems are printed |
//! | [`RecordSource::Table`] | columns in memory (arrays, a simulated flight) | nothing |

use crate::error::FlightDataError;
use crate::flight_data::FlightDataReader;
use crate::log::{LogFormat, LogReader, open_log_with_report, stream_reader, table_reader};
use crate::mapping::{Mapping, Source};
use crate::mavlink::{LinkStats, MavlinkRows, MavlinkUrl};
use crate::reader_report::ReaderReport;
use crate::table::Table;
use std::io::{BufReader, Read};
use std::sync::{Arc, Mutex};

/// Where a record comes from.
pub enum RecordSource {
    /// A file of any format, read by [`crate::open_log_with_report`]; `-` is stdin (CSV,
    /// `.asc` or `.mat`; a binary log is read from a file only).
    Path(String),
    /// A file whose bytes pass through `watch` (a face's progress bar over them) for CSV,
    /// `.asc` and `.mat`; a binary log is read as [`RecordSource::Path`] reads it.
    Watched {
        /// The file.
        path: String,
        /// Wraps the opened file.
        watch: Watch,
    },
    /// Text or `.mat` bytes from a source the face chose (stdin through a reader a signal can
    /// end), named `name` in every message; CSV unless a format is given. A binary log (ULog,
    /// DataFlash, `.tlog`) is refused: it is read from a file.
    Bytes {
        /// The record's name in messages and the reader report (`-` for stdin).
        name: String,
        /// The bytes.
        read: Box<dyn Read + Send>,
    },
    /// A live MAVLink feed, `mavlink:udp:<host>:<port>[?timeout_s=<s>]`
    /// ([`MavlinkUrl::parse`]).
    Mavlink {
        /// The source as written.
        url: String,
        /// Called with each problem of the link as it arises (a stuck sender, a gap), beside
        /// its count in [`LinkStats`]; `None`: counted only.
        on_problem: Option<fn(&str)>,
    },
    /// Columns in memory, named by [`Table::file`] in messages.
    Table(Table),
}

/// What [`RecordSource::Watched`] passes the opened file through.
pub type Watch = Box<dyn FnOnce(std::fs::File) -> Box<dyn Read + Send>>;

/// Whether a record argument names a live MAVLink feed (`mavlink:…`).
pub fn is_mavlink(arg: &str) -> bool {
    arg.starts_with("mavlink:")
}

/// An opened record: the reader every step takes, what its reading left out, and a live
/// feed's link.
pub struct Record {
    /// The rows through the mapping.
    pub reader: LogReader,
    /// What the reading and alignment of a multi-rate log left out (empty for the others).
    pub report: ReaderReport,
    /// A live feed's link: its statistics, readable while and after the feed is read, and
    /// the line saying where it listens.
    pub link: Option<Link>,
}

/// A live MAVLink feed opened by [`Record::open`].
pub struct Link {
    /// The link's counts and how it ended ([`LinkStats::line`]).
    pub stats: Arc<Mutex<LinkStats>>,
    /// Where the feed listens, its clock and how it ends, for the face to show before the
    /// first sample: `listening on 127.0.0.1:14550 (clock …, ends after 10 s without a
    /// datagram or on NAMED_VALUE_FLOAT `aid_end`)`.
    pub listening: String,
}

impl Record {
    /// Opens `source` through `mapping`: `format`, else the file's extension, else CSV
    /// ([`LogFormat::resolve`]).
    ///
    /// # Errors
    /// As [`crate::open_log_with_report`] for a path; [`FlightDataError::Format`] for a binary
    /// log from bytes; the CSV reader's header errors; [`FlightDataError::Mavlink`] for a feed
    /// that does not parse, maps a column that is not a numeric message field, or cannot bind
    /// its socket.
    pub fn open(
        source: RecordSource,
        format: Option<LogFormat>,
        mapping: &Mapping,
    ) -> Result<Record, FlightDataError> {
        match source {
            RecordSource::Path(path) => {
                let (reader, report) = open_log_with_report(&path, format, mapping)?;
                Ok(Record { reader, report, link: None })
            }
            RecordSource::Watched { path, watch } => match LogFormat::resolve(format, &path) {
                f @ (LogFormat::Csv | LogFormat::Asc | LogFormat::Mat) => {
                    let file = std::fs::File::open(&path)
                        .map_err(|source| FlightDataError::Io { file: path.clone(), source })?;
                    let reader =
                        stream_reader(Box::new(BufReader::new(watch(file))), &path, f, mapping)?;
                    Ok(Record { reader, report: ReaderReport::empty(&path, f.name()), link: None })
                }
                _ => Record::open(RecordSource::Path(path), format, mapping),
            },
            RecordSource::Bytes { name, read } => {
                let format = format.unwrap_or(LogFormat::Csv);
                let reader = stream_reader(Box::new(BufReader::new(read)), &name, format, mapping)?;
                Ok(Record { reader, report: ReaderReport::empty(&name, format.name()), link: None })
            }
            RecordSource::Mavlink { url, on_problem } => open_mavlink(&url, mapping, on_problem),
            RecordSource::Table(table) => {
                let report = ReaderReport::empty(&table.file, "arrays");
                Ok(Record { reader: table_reader(table, mapping)?, report, link: None })
            }
        }
    }

    /// What the reading left out, one line each ([`ReaderReport::notes`]).
    pub fn notes(&self) -> Vec<String> {
        self.report.notes()
    }
}

/// [`Record::open`] of a MAVLink feed: the socket bound, the rows through `mapping`.
fn open_mavlink(
    url: &str,
    mapping: &Mapping,
    on_problem: Option<fn(&str)>,
) -> Result<Record, FlightDataError> {
    let url = MavlinkUrl::parse(url)?;
    let rows = MavlinkRows::open(&url, mapping, on_problem)?;
    let clock = match &mapping.time.source {
        Source::Columns(c) => c.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join("+"),
        Source::Constant(_) => String::new(),
    };
    let listening = format!(
        "listening on {} (clock {}, ends after {} s without a datagram or on NAMED_VALUE_FLOAT `{}`)",
        rows.local_addr(),
        clock,
        url.timeout_s,
        crate::mavlink::END_OF_STREAM_NAME
    );
    let stats = rows.stats();
    let reader = FlightDataReader::new(Box::new(rows) as Box<dyn Read + Send>, &url.text, mapping)?;
    let report = ReaderReport::empty(&url.text, "mavlink");
    Ok(Record { reader, report, link: Some(Link { stats, listening }) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flight_data::RecordEvent;
    use std::sync::atomic::{AtomicUsize, Ordering};

    const MAP: &str = "nominal_dt_s = 0.1\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nmass = { value = 1.0, unit = \"kg\" }\nS = { value = 1.0, unit = \"m2\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\n";
    const CSV: &str = "t,V,a\n0,100,0.05\n0.1,101,0.06\n0.2,102.5,0.07\n";

    fn mapping() -> Mapping {
        Mapping::from_toml_str(MAP, "m.toml").unwrap()
    }

    /// `(t, vt, alpha)` of every sample the record yields.
    fn samples(r: Record) -> Vec<(f64, f64, f64)> {
        r.reader
            .map(|e| match e.unwrap() {
                RecordEvent::Sample { sample: s, .. } => (s.t_s, s.vt_mps, s.alpha_rad),
                other => panic!("{other:?}"),
            })
            .collect()
    }

    /// The numbers written in [`CSV`].
    const EXPECTED: [(f64, f64, f64); 3] =
        [(0.0, 100.0, 0.05), (0.1, 101.0, 0.06), (0.2, 102.5, 0.07)];

    fn temp_csv(name: &str) -> String {
        let path =
            std::env::temp_dir().join(format!("aeroident-record-{}-{name}", std::process::id()));
        std::fs::write(&path, CSV).unwrap();
        path.display().to_string()
    }

    #[test]
    fn a_file_bytes_a_watched_file_and_a_table_give_the_numbers_written() {
        let (m, path) = (mapping(), temp_csv("same.csv"));
        let from_path = Record::open(RecordSource::Path(path.clone()), None, &m).unwrap();
        assert_eq!(samples(from_path), EXPECTED);
        let read = Box::new(std::io::Cursor::new(CSV.as_bytes().to_vec()));
        let bytes = Record::open(RecordSource::Bytes { name: "-".into(), read }, None, &m).unwrap();
        assert_eq!(bytes.report.file, "-");
        assert_eq!(samples(bytes), EXPECTED);
        let counted = Arc::new(AtomicUsize::new(0));
        let c = Arc::clone(&counted);
        let watch: Watch = Box::new(move |f| Box::new(Counting(f, c)));
        let watched = Record::open(RecordSource::Watched { path: path.clone(), watch }, None, &m);
        assert_eq!(samples(watched.unwrap()), EXPECTED);
        assert_eq!(counted.load(Ordering::Relaxed), CSV.len(), "every byte through the wrapper");
        let columns = vec![vec![0.0, 0.1, 0.2], vec![100.0, 101.0, 102.5], vec![0.05, 0.06, 0.07]];
        let names = ["t", "V", "a"].map(String::from).to_vec();
        let table = Table { file: "arrays".into(), names, columns };
        assert_eq!(samples(Record::open(RecordSource::Table(table), None, &m).unwrap()), EXPECTED);
        std::fs::remove_file(path).unwrap();
    }

    /// A reader that counts the bytes it passes.
    struct Counting(std::fs::File, Arc<AtomicUsize>);

    impl Read for Counting {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let n = self.0.read(buf)?;
            self.1.fetch_add(n, Ordering::Relaxed);
            Ok(n)
        }
    }

    #[test]
    fn errors_a_binary_log_from_a_stream_and_a_feed_that_is_not_udp_are_named() {
        let m = mapping();
        let read = Box::new(std::io::empty());
        let source = RecordSource::Bytes { name: "-".into(), read };
        let e = Record::open(source, Some(LogFormat::Ulog), &m).err().unwrap().to_string();
        assert!(e.contains("a ulog log is read from a file, not from stdin"), "{e}");
        let source =
            RecordSource::Mavlink { url: "mavlink:tcp:127.0.0.1:5760".into(), on_problem: None };
        let e = Record::open(source, None, &m).err().unwrap().to_string();
        assert!(e.contains("mavlink:tcp:127.0.0.1:5760") && e.contains("only UDP"), "{e}");
        let missing = RecordSource::Watched {
            path: "/no/such/record.csv".into(),
            watch: Box::new(|f| Box::new(f)),
        };
        let e = Record::open(missing, None, &m).err().unwrap().to_string();
        assert!(e.contains("/no/such/record.csv"), "{e}");
    }

    #[test]
    fn a_feed_says_where_it_listens_and_keeps_its_link() {
        let source = RecordSource::Mavlink {
            url: "mavlink:udp:127.0.0.1:0?timeout_s=1".into(),
            on_problem: None,
        };
        let r = Record::open(source, None, &mavlink_mapping()).unwrap();
        let link = r.link.as_ref().unwrap();
        assert!(link.listening.starts_with("listening on 127.0.0.1:"), "{}", link.listening);
        assert!(link.listening.contains("ends after 1 s"), "{}", link.listening);
        assert_eq!(link.stats.lock().unwrap().rows, 0);
        assert_eq!(r.report.format, "mavlink");
    }

    fn mavlink_mapping() -> Mapping {
        let text = "[time]\ncolumn = \"ATTITUDE.time_boot_ms\"\nunit = \"ms\"\n[channels]\nvt = { column = \"VFR_HUD.airspeed\", unit = \"m/s\" }\nalpha = { value = 0.0, unit = \"rad\" }\nmass = { value = 1.0, unit = \"kg\" }\nS = { value = 1.0, unit = \"m2\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\n";
        Mapping::from_toml_str(text, "mavlink.toml").unwrap()
    }
}
