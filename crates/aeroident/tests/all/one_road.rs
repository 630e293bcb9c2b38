//! Every face and step opens a record through `aeroident_io::Record::open`: no library or face
//! source outside the io crate calls a reader directly (the path reader `open_log*`, the
//! `.asc` and table readers, the CSV reader's constructor, the MAVLink rows), so a new format
//! or source reaches replay, fit, compat, freqresp, inspect and Python at once. Unit tests
//! (after a file's `#[cfg(test)]`, or in a `tests.rs`) may build readers over literal text.

use crate::common::workspace;
use std::path::{Path, PathBuf};

/// The calls only `crates/io/src/record.rs` and the io crate's readers make.
const READERS: [&str; 7] = [
    "open_log(",
    "open_log_with_notes(",
    "open_log_with_report(",
    "asc_reader(",
    "table_reader(",
    "FlightDataReader::new(",
    "MavlinkRows::open(",
];

/// Every `.rs` file under `dir`, recursively.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for p in entries.flatten().map(|e| e.path()) {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// `line` calls one of [`READERS`] (as a call, not inside a word such as `my_open_log(`).
fn calls_a_reader(line: &str) -> Option<&'static str> {
    let code = line.split("//").next().unwrap_or("");
    READERS.into_iter().find(|r| {
        code.match_indices(r).any(|(i, _)| {
            code[..i].chars().next_back().is_none_or(|c| !(c.is_alphanumeric() || c == '_'))
        })
    })
}

/// The numbered lines of `text` before its inline unit-test module (`#[cfg(test)]` followed
/// by `mod … {`); a `#[cfg(test)] mod tests;` declaration does not end the scan.
fn library_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let lines: Vec<&str> = text.lines().collect();
    let end = (0..lines.len())
        .find(|&i| {
            lines[i].trim() == "#[cfg(test)]"
                && lines
                    .get(i + 1)
                    .is_some_and(|n| n.trim().starts_with("mod ") && n.trim().ends_with('{'))
        })
        .unwrap_or(lines.len());
    lines.into_iter().take(end).enumerate().map(|(i, l)| (i + 1, l))
}

#[test]
fn records_are_opened_only_through_record_open() {
    let mut files = Vec::new();
    for krate in std::fs::read_dir(workspace().join("crates")).unwrap().flatten() {
        if krate.file_name() != "io" {
            rust_files(&krate.path().join("src"), &mut files);
        }
    }
    assert!(files.len() > 100, "the sources were not found: {} files", files.len());
    let mut problems = Vec::new();
    for f in files.iter().filter(|f| f.file_name().is_some_and(|n| n != "tests.rs")) {
        let text = std::fs::read_to_string(f).unwrap();
        for (i, line) in library_lines(&text) {
            if let Some(r) = calls_a_reader(line) {
                problems
                    .push(format!("{}:{i}: calls `{r}`; open it with Record::open", f.display()));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_scan_finds_a_reader_call_and_passes_a_word_that_ends_like_one() {
    assert_eq!(calls_a_reader("    let r = open_log(p, None, &m)?;"), Some("open_log("));
    assert_eq!(
        calls_a_reader("let r = aeroident_io::open_log_with_report(p, f, m)?"),
        Some("open_log_with_report(")
    );
    assert_eq!(
        calls_a_reader("    FlightDataReader::new(read, name, mapping)"),
        Some("FlightDataReader::new(")
    );
    assert_eq!(calls_a_reader("    my_table_reader(x)"), None);
    assert_eq!(calls_a_reader("    // open_log(p) in a comment"), None);
    assert_eq!(calls_a_reader("    Record::open(source, None, &m)"), None);
    let text = "#[cfg(test)]\nmod tests;\nfn f() { open_log(p) }\n#[cfg(test)]\nmod tests {\n open_log(q)\n}";
    let scanned: Vec<usize> = library_lines(text).map(|(i, _)| i).collect();
    assert_eq!(scanned, [1, 2, 3], "a declared module does not end the scan; an inline one does");
}
