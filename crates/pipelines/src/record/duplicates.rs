//! Records given twice: the same file under two names, or two files of the same content.
//!
//! Records fitted together are taken as independent flights; one fitted twice adds no
//! information, yet counts its samples twice and shrinks every σ by √2 (√N for N copies), so
//! a typo in a list of `--and` files would pass for tighter results. A record is the same as an
//! earlier one when both name one file (device and inode, whatever path names it) or hold the
//! same bytes (compared only between files of equal size, by a content hash, so distinct
//! records are never read for it). Paths that name no regular file (stdin `-`, a MAVLink
//! address, a pipe) are not compared.

use super::RecordError;
use std::collections::HashMap;
use std::hash::Hasher;
use std::io::Read;
use std::path::Path;

/// The option that lets a record be given twice on purpose, as the command line spells it.
pub const ALLOW_FLAG: &str = "allow-duplicate-records";

/// Refuses a record of `files` (the main record first) that is the same file as, or has the
/// same content as, an earlier one (module doc), unless `allow`.
///
/// # Errors
/// [`RecordError::Option`] naming `--and`, both files and how they are the same; a file that
/// cannot be read while hashing it, naming it.
pub fn check_distinct<'a>(
    files: impl IntoIterator<Item = &'a str>,
    allow: bool,
) -> Result<(), RecordError> {
    if allow {
        return Ok(());
    }
    let mut seen: Vec<(&str, u64, u64, u64)> = Vec::new(); // name, device, inode, size
    let mut hashes: HashMap<&str, u64> = HashMap::new();
    for file in files {
        let Some((dev, ino, size)) = regular_file(Path::new(file)) else { continue };
        for &(earlier, d, i, s) in &seen {
            let how = if (d, i) == (dev, ino) {
                "is the same file as"
            } else if s == size && hash_of(earlier, &mut hashes)? == hash_of(file, &mut hashes)? {
                "has the same content as"
            } else {
                continue;
            };
            return Err(RecordError::Option {
                option: "and",
                reason: format!(
                    "`{file}` {how} `{earlier}`: a record fitted twice adds no data but counts its samples twice, shrinking every σ by √2; give each record once, or --{ALLOW_FLAG} to fit it again on purpose"
                ),
            });
        }
        seen.push((file, dev, ino, size));
    }
    Ok(())
}

/// Samples compared between two records of different bytes: two flights differ within their
/// first samples (noise alone), while a copy in another format or line ending repeats them all.
pub const COMPARED_SAMPLES: usize = 1000;

/// Refuses a record of `records` (name and its events, the main record first) whose first
/// [`COMPARED_SAMPLES`] samples, as the mapping reads them, equal an earlier record's: the same
/// flight in another format (`.asc` and its CSV) or with other line endings, which
/// [`check_distinct`] cannot see in the bytes. A record that cannot be read is skipped (the
/// estimating step reports it).
///
/// # Errors
/// [`RecordError::Option`] naming `--and` and both records.
pub fn check_distinct_samples<I>(records: Vec<(&str, I)>) -> Result<(), RecordError>
where
    I: Iterator<Item = Result<aeroident_io::RecordEvent, aeroident_io::FlightDataError>>,
{
    let mut seen: Vec<(&str, u64, usize)> = Vec::new();
    for (file, events) in records {
        let (hash, n) = samples_hash(events);
        if n == 0 {
            continue;
        }
        if let Some((earlier, ..)) = seen.iter().find(|(_, h, m)| (*h, *m) == (hash, n)) {
            return Err(RecordError::Option {
                option: "and",
                reason: format!(
                    "`{file}` holds the same samples as `{earlier}` (the first {n}, as the mapping reads them): the same flight in another format or copy, which counts its samples twice and shrinks every σ by √2; give it once, or --{ALLOW_FLAG} to fit it again on purpose"
                ),
            });
        }
        seen.push((file, hash, n));
    }
    Ok(())
}

/// A hash of the first [`COMPARED_SAMPLES`] samples of `events` (every field, exactly) and
/// how many there were; a read error ends them.
fn samples_hash<I>(events: I) -> (u64, usize)
where
    I: Iterator<Item = Result<aeroident_io::RecordEvent, aeroident_io::FlightDataError>>,
{
    let mut h = std::collections::hash_map::DefaultHasher::new();
    let mut n = 0;
    for e in events {
        match e {
            Ok(aeroident_io::RecordEvent::Sample { sample, .. }) => {
                // Debug writes each f64 as its shortest round trip: equal text, equal values.
                h.write(format!("{sample:?}").as_bytes());
                n += 1;
                if n == COMPARED_SAMPLES {
                    break;
                }
            }
            Ok(_) => {}
            Err(_) => break,
        }
    }
    (h.finish(), n)
}

/// Device, inode and size of the regular file at `p` (links followed); `None` otherwise.
fn regular_file(p: &Path) -> Option<(u64, u64, u64)> {
    let m = std::fs::metadata(p).ok().filter(std::fs::Metadata::is_file)?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some((m.dev(), m.ino(), m.len()))
    }
    #[cfg(not(unix))]
    {
        // No inode: the canonical path stands for the file's identity.
        let mut h = std::collections::hash_map::DefaultHasher::new();
        std::hash::Hash::hash(&std::fs::canonicalize(p).ok()?, &mut h);
        Some((0, h.finish(), m.len()))
    }
}

/// The content hash of `file`, computed once.
fn hash_of<'a>(file: &'a str, hashes: &mut HashMap<&'a str, u64>) -> Result<u64, RecordError> {
    if let Some(h) = hashes.get(file) {
        return Ok(*h);
    }
    let io = |e: std::io::Error| {
        RecordError::Model(format!(
            "{file}: cannot be read to compare it with the other records: {e}"
        ))
    };
    let mut f = std::fs::File::open(file).map_err(io)?;
    let mut h = std::collections::hash_map::DefaultHasher::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf).map_err(io)?;
        if n == 0 {
            break;
        }
        h.write(&buf[..n]);
    }
    let v = h.finish();
    hashes.insert(file, v);
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> std::path::PathBuf {
        let d =
            std::env::temp_dir().join(format!("aeroident-duplicates-{}-{tag}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// The same file under another path, a copy, and a file given ten times are refused
    /// naming both files; a record differing in one byte, stdin and a missing file are not
    /// compared; the flag lets the copy through.
    #[test]
    fn a_record_given_twice_is_refused_unless_allowed() {
        let d = scratch("dup");
        let a = d.join("a.csv");
        std::fs::write(&a, "t,q\n0,1\n0.1,2\n").unwrap();
        std::fs::write(d.join("copy.csv"), "t,q\n0,1\n0.1,2\n").unwrap();
        std::fs::write(d.join("other.csv"), "t,q\n0,1\n0.1,3\n").unwrap();
        std::fs::create_dir(d.join("sub")).unwrap();
        let s = |p: &str| d.join(p).display().to_string();
        let dotted = d.join("sub").join("..").join("a.csv").display().to_string();
        let a = a.display().to_string();
        let e = check_distinct([a.as_str(), dotted.as_str()], false).unwrap_err().to_string();
        assert!(e.contains("--and") && e.contains("is the same file as") && e.contains(&a), "{e}");
        let copy = s("copy.csv");
        let e = check_distinct([a.as_str(), &s("other.csv"), &copy], false).unwrap_err();
        let e = e.to_string();
        assert!(e.contains(&format!("`{copy}` has the same content as `{a}`")), "{e}");
        assert!(e.contains(&format!("--{ALLOW_FLAG}")), "{e}");
        let ten: Vec<&str> = std::iter::repeat_n(a.as_str(), 10).collect();
        assert!(check_distinct(ten.iter().copied(), false).is_err());
        assert!(check_distinct(ten.iter().copied(), true).is_ok());
        check_distinct([a.as_str(), &s("other.csv"), "-", "-", &s("missing.csv")], false).unwrap();
        let _ = std::fs::remove_dir_all(&d);
    }

    /// The same samples in two files of other bytes (CRLF line endings, another number format)
    /// are refused naming both; one differing value in a later sample is not.
    #[test]
    fn the_same_samples_in_other_bytes_are_refused() {
        use aeroident_estimators::AirDataSample;
        use aeroident_io::RecordEvent;
        let flight = |last_q: f64| -> Vec<Result<RecordEvent, aeroident_io::FlightDataError>> {
            (0..20)
                .map(|i| {
                    let q = if i == 19 { last_q } else { 0.01 * i as f64 };
                    let sample = AirDataSample {
                        t_s: 0.1 * i as f64,
                        vt_mps: 100.0,
                        q_rad_s: Some(q),
                        ..AirDataSample::default()
                    };
                    Ok(RecordEvent::Sample { row: i + 2, sample })
                })
                .collect()
        };
        let e = check_distinct_samples(vec![
            ("a.csv", flight(0.5).into_iter()),
            ("b.csv", flight(0.6).into_iter()),
            ("a.asc", flight(0.5).into_iter()),
        ])
        .unwrap_err()
        .to_string();
        assert!(e.contains("`a.asc` holds the same samples as `a.csv` (the first 20"), "{e}");
        check_distinct_samples(vec![
            ("a.csv", flight(0.5).into_iter()),
            ("b.csv", flight(0.6).into_iter()),
        ])
        .unwrap();
    }
}
