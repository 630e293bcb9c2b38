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

/// `aeroident live DATA --map mappings/hfb320.toml --model models/MODEL --out OUT --serve
/// 127.0.0.1:0` (the HFB-320 record's view on any free port); the caller adds the rest.
pub fn hfb320(data: &std::path::Path, model: &str, out: &std::path::Path) -> Command {
    let ws = super::workspace();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_aeroident"));
    cmd.arg("live")
        .arg(data)
        .arg("--map")
        .arg(ws.join("mappings/hfb320.toml"))
        .arg("--model")
        .arg(ws.join("models").join(model))
        .arg("--out")
        .arg(out)
        .args(["--serve", "127.0.0.1:0"]);
    cmd
}
