//! `aeroident live` as a child process, for the tests of the live view.

use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Command, Stdio};
use std::thread::JoinHandle;

/// Spawns `cmd` (an `aeroident live …` command with its arguments) with stdout discarded and
/// reads its stderr up to the `live view on URL` line; returns the child, the URL
/// (`http://127.0.0.1:PORT/`) and the thread collecting the rest of stderr.
pub fn spawn(mut cmd: Command) -> (Child, String, JoinHandle<String>) {
    let mut child = cmd.stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    let url = loop {
        line.clear();
        assert!(stderr.read_line(&mut line).unwrap() > 0, "no `live view on` line");
        if let Some(rest) = line.trim().strip_prefix("live view on ") {
            break rest.to_string();
        }
    };
    let rest = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stderr.read_to_string(&mut s);
        s
    });
    (child, url, rest)
}
