//! A signal ends a live or long replay gracefully: the binary is spawned on a live input
//! (stdin `-`), sent SIGINT, SIGTERM or SIGHUP after some rows, and must leave `estimates.csv`,
//! `summary.json` (status `interrupted`) and the report, no hidden temporary file, and exit
//! with 128 + signal. A second signal while the results are written is ignored; one before
//! that leaves `summary.json` alone. A batch fit (`--estimator oe`) reading stdin fits the rows
//! read before the signal; a signal during a batch fit (of a file or of stdin read whole)
//! stops it at its next iteration or bootstrap replica and writes what it had.

use crate::common;
use common::workspace;
use std::ffi::OsString;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroident"))
}

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("aeroident-cli-int-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A simulated record (`f16 sim`, 20 s at 100 Hz): its `timeseries.csv` lines.
fn sim_lines(dir: &Path) -> Vec<String> {
    let sc = dir.join("sim.toml");
    std::fs::write(
        &sc,
        "kind = \"sim\"\n[aircraft]\nxcg = 0.30\nactuators = \"f16\"\n[trim]\nalt_ft = 20000.0\nvt_fps = 675.0\n[run]\nduration_s = 20.0\ndt_s = 0.01\nseed = 1\n",
    )
    .unwrap();
    let out = dir.join("sim");
    let o = bin().args(["f16", "sim"]).arg(&sc).arg("--out").arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("timeseries.csv")).unwrap();
    text.lines().map(str::to_string).collect()
}

/// `replay - --map aeroident-sim.toml --out OUT` with stdin piped; its stderr collected by a
/// thread into the returned buffer.
fn spawn_live(out: &Path) -> (Child, Arc<Stderr>) {
    let map = workspace().join("mappings/aeroident-sim.toml");
    spawn_replay(&["--estimator".into(), "rls".into(), "--map".into(), map.into()], out)
}

/// `replay - ARGS --out OUT` with stdin piped; its stderr collected by a thread into the
/// returned buffer.
fn spawn_replay(args: &[OsString], out: &Path) -> (Child, Arc<Stderr>) {
    spawn_replay_of("-".as_ref(), args, out)
}

/// `replay DATA ARGS --out OUT` with stdin piped; its stderr collected by a thread into the
/// returned buffer.
fn spawn_replay_of(data: &std::ffi::OsStr, args: &[OsString], out: &Path) -> (Child, Arc<Stderr>) {
    let mut child = bin()
        .arg("replay")
        .arg(data)
        .args(args)
        .arg("--out")
        .arg(out)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let err = collect_stderr(&mut child);
    (child, err)
}

/// Starts the thread that collects `child`'s (piped) stderr line by line until it closes.
fn collect_stderr(child: &mut Child) -> Arc<Stderr> {
    let err = Arc::new(Stderr::default());
    let sink = Arc::clone(&err);
    let stderr = child.stderr.take().unwrap();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let mut s = sink.text.lock().unwrap();
            s.push_str(&line);
            s.push('\n');
        }
        sink.closed.store(true, Ordering::SeqCst);
    });
    err
}

/// A child's stderr, collected line by line by a thread until it closes.
#[derive(Debug, Default)]
struct Stderr {
    text: Mutex<String>,
    closed: AtomicBool,
}

impl Stderr {
    /// What has arrived so far.
    fn text(&self) -> String {
        self.text.lock().unwrap().clone()
    }
}

/// Waits until `err` shows `what` (the child has reached that point), at most 60 s.
fn wait_for(err: &Stderr, what: &str) {
    let start = Instant::now();
    while !err.text().contains(what) {
        assert!(start.elapsed() < Duration::from_secs(60), "no `{what}`: {}", err.text());
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn signal(child: &Child, sig: &str) {
    let ok = Command::new("kill").args([sig, &child.id().to_string()]).status().unwrap();
    assert!(ok.success());
}

/// The child's exit code, failing (and killing it) if it has not ended within 60 s; once it
/// has, waits for the rest of its stderr (at most 10 s), so that `err` holds all of it.
fn exit_code(child: &mut Child, err: &Stderr) -> i32 {
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("the replay did not end on the signal: {}", err.text());
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let end = Instant::now();
    while !err.closed.load(Ordering::SeqCst) && end.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(10));
    }
    status.code().unwrap_or_else(|| panic!("killed by a signal: {status:?}\n{}", err.text()))
}

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// The hidden temporary files left in `out` (a file being written when the run ended).
fn temporaries(out: &Path) -> Vec<String> {
    std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp") || n.starts_with(".tmp-"))
        .collect()
}

/// Whether `out/name` exists and is not empty.
fn written(out: &Path, name: &str) -> bool {
    std::fs::metadata(out.join(name)).is_ok_and(|m| m.len() > 0)
}

/// Checks the outputs of an interrupted run: status `interrupted`, one estimates line per
/// estimated sample, no hidden temporary file. Returns the summary's `samples_read`.
fn check_interrupted_outputs(out: &Path, fed: &[String]) -> usize {
    let read = check_interrupted_estimates(out, fed);
    assert!(out.join("report.html").exists());
    read
}

/// [`check_interrupted_outputs`] but for the report, which a second signal leaves out.
fn check_interrupted_estimates(out: &Path, fed: &[String]) -> usize {
    let v = summary(out);
    assert_eq!(v["status"], "interrupted", "{v}");
    let read = v["samples_read"].as_u64().unwrap() as usize;
    let rejected = v["samples_rejected"].as_u64().unwrap() as usize;
    assert!(read >= 1 && read < fed.len(), "{read} of {}", fed.len() - 1);
    assert!(v["warnings"].to_string().contains("interrupted after"), "{v}");
    let est = std::fs::read_to_string(out.join("estimates.csv")).unwrap();
    let rows: Vec<&str> = est.lines().skip(1).collect();
    assert_eq!(rows.len(), read - rejected, "one estimates line per estimated sample");
    // The last estimated sample is one of the record's (its time column is the first).
    let last_t: f64 = rows.last().unwrap().split(',').next().unwrap().parse().unwrap();
    let fed_t: Vec<f64> =
        fed[1..].iter().map(|l| l.split(',').next().unwrap().parse().unwrap()).collect();
    assert!(fed_t.iter().any(|t| (t - last_t).abs() < 1e-9), "t = {last_t}");
    let hidden = temporaries(out);
    assert!(hidden.is_empty(), "temporary files left: {hidden:?}");
    read
}

/// Ctrl-C while the live feed is silent (stdin open, no line arriving): the replay must not
/// wait for a line that never comes; it writes the results of the rows it had, status
/// `interrupted`, and exits 130.
#[test]
fn sigint_on_a_silent_live_feed_writes_an_interrupted_summary() {
    signal_a_silent_live_feed("silent", "INT", 130);
}

/// SIGHUP (the terminal the feed ran in closed) ends the replay as SIGINT does: results
/// written, status `interrupted`, exit 129.
#[test]
fn sighup_on_a_silent_live_feed_writes_an_interrupted_summary() {
    signal_a_silent_live_feed("hangup", "HUP", 129);
}

/// Feeds 300 rows to a live replay, leaves stdin open and silent, sends SIG`sig` and checks
/// the exit `code` and the interrupted outputs.
fn signal_a_silent_live_feed(tag: &str, sig: &str, code: i32) {
    let d = scratch(tag);
    let lines = sim_lines(&d);
    let out = d.join("out");
    let (mut child, err) = spawn_live(&out);
    let mut stdin = child.stdin.take().unwrap();
    let fed = &lines[..301];
    for l in fed {
        writeln!(stdin, "{l}").unwrap();
    }
    stdin.flush().unwrap();
    wait_for(&err, "model");
    std::thread::sleep(Duration::from_millis(500));
    signal(&child, &format!("-{sig}"));
    let got = exit_code(&mut child, &err);
    drop(stdin);
    let text = err.text();
    assert_eq!(got, code, "{text}");
    assert!(text.contains(&format!("interrupted by SIG{sig}")), "{text}");
    let read = check_interrupted_outputs(&out, &lines);
    assert!(read <= 300, "{read} rows read of 300 fed");
    let _ = std::fs::remove_dir_all(&d);
}

/// SIGTERM while rows keep arriving: the replay stops between samples (before the record's
/// end), writes its results, status `interrupted`, and exits 143.
#[test]
fn sigterm_on_a_flowing_live_feed_stops_between_samples() {
    let d = scratch("flowing");
    let lines = sim_lines(&d);
    let out = d.join("out");
    let (mut child, err) = spawn_live(&out);
    let mut stdin = child.stdin.take().unwrap();
    let feed = lines.clone();
    // About 2,000 rows a second: the record would last ~1 s more than the signal's delay.
    let feeder = std::thread::spawn(move || -> std::io::Result<()> {
        for chunk in feed.chunks(20) {
            for l in chunk {
                writeln!(stdin, "{l}")?;
            }
            stdin.flush()?;
            std::thread::sleep(Duration::from_millis(10));
        }
        // Keep the feed open, as a live one is.
        std::thread::sleep(Duration::from_secs(120));
        Ok(())
    });
    wait_for(&err, "model");
    std::thread::sleep(Duration::from_millis(300));
    signal(&child, "-TERM");
    let code = exit_code(&mut child, &err);
    let text = err.text();
    assert_eq!(code, 143, "{text}");
    assert!(text.contains("interrupted by SIGTERM"), "{text}");
    check_interrupted_outputs(&out, &lines);
    drop(feeder);
    let _ = std::fs::remove_dir_all(&d);
}

/// Starts a live replay of 300 rows and sends SIGINT once it estimates: the child, its stderr
/// and stdin (held open, silent), and the rows.
fn interrupted_live_feed(d: &Path, out: &Path) -> (Child, Arc<Stderr>, ChildStdin, Vec<String>) {
    let lines = sim_lines(d);
    let (mut child, err) = spawn_live(out);
    let mut stdin = child.stdin.take().unwrap();
    for l in &lines[..301] {
        writeln!(stdin, "{l}").unwrap();
    }
    stdin.flush().unwrap();
    wait_for(&err, "model");
    std::thread::sleep(Duration::from_millis(500));
    signal(&child, "-INT");
    (child, err, stdin, lines)
}

/// A second Ctrl-C while the results are written is noted and ignored: the report and its
/// figures are all written, no temporary file is left, and the exit is still 130.
#[test]
fn a_second_sigint_while_the_results_are_written_is_ignored() {
    let d = scratch("repeat-writing");
    let out = d.join("out");
    let (mut child, err, stdin, lines) = interrupted_live_feed(&d, &out);
    // Printed once the writing has begun (the figures take a second or more after it).
    wait_for(&err, "writing the results");
    signal(&child, "-INT");
    let code = exit_code(&mut child, &err);
    drop(stdin);
    let text = err.text();
    assert_eq!(code, 130, "{text}");
    assert!(text.contains("SIGINT: ignored while the results are written"), "{text}");
    check_interrupted_outputs(&out, &lines);
    for f in ["estimates.png", "estimates.svg", "report.html"] {
        assert!(written(&out, f), "{f} missing or empty: {text}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Two Ctrl-C 20 ms apart: whichever phase the second lands in, the output directory is
/// valid: the estimates and `summary.json` (status `interrupted`), no temporary file, and
/// either the whole report or none of it with the summary saying why.
#[test]
fn two_quick_sigints_leave_a_valid_output_directory() {
    let d = scratch("repeat-quick");
    let out = d.join("out");
    let (mut child, err, stdin, lines) = interrupted_live_feed(&d, &out);
    std::thread::sleep(Duration::from_millis(20));
    signal(&child, "-INT");
    let code = exit_code(&mut child, &err);
    drop(stdin);
    let text = err.text();
    assert_eq!(code, 130, "{text}");
    check_interrupted_estimates(&out, &lines);
    let v = summary(&out);
    let summary_only = v["warnings"].to_string().contains("only summary.json");
    for f in ["estimates.png", "estimates.svg", "report.html"] {
        assert_eq!(written(&out, f), !summary_only, "{f}: {v}\n{text}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Ctrl-C before a live feed has sent a single row (only its header): no estimates, but still
/// a `summary.json` saying the run was interrupted and why, exit 130.
#[test]
fn sigint_before_a_live_feed_has_a_row_writes_a_summary_without_estimates() {
    let d = scratch("live-empty");
    let lines = sim_lines(&d);
    let out = d.join("out");
    let (mut child, err) = spawn_live(&out);
    let mut stdin = child.stdin.take().unwrap();
    writeln!(stdin, "{}", lines[0]).unwrap();
    stdin.flush().unwrap();
    // The output directory is locked after the handlers are installed, before any read.
    let start = Instant::now();
    while !out.join(".aeroident.lock").exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no output directory: {}", err.text());
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(300));
    signal(&child, "-INT");
    let code = exit_code(&mut child, &err);
    drop(stdin);
    let text = err.text();
    assert_eq!(code, 130, "{text}");
    let v = summary(&out);
    assert_eq!(v["status"], "interrupted", "{v}");
    assert!(v["parameters"].is_null(), "{v}");
    assert!(v["status_reason"].as_str().unwrap().contains("before any sample"), "{v}");
    assert!(!out.join("estimates.csv").exists() && temporaries(&out).is_empty());
    let _ = std::fs::remove_dir_all(&d);
}

/// The HFB-320 record (Jategaonkar 2015) as lines, or `None` when the shared data are absent.
fn hfb320_lines() -> Option<Vec<String>> {
    let path = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv")?;
    Some(std::fs::read_to_string(path).unwrap().lines().map(str::to_string).collect())
}

/// `replay - --map hfb320.toml --model longitudinal --estimator oe` and `extra` arguments.
fn oe_args(extra: &[&str]) -> Vec<OsString> {
    let mut a: Vec<OsString> =
        vec!["--map".into(), workspace().join("mappings/hfb320.toml").into()];
    a.extend(["--model", "longitudinal", "--estimator", "oe"].map(OsString::from));
    a.extend(extra.iter().map(OsString::from));
    a
}

/// The parameter estimates of a batch summary, by name.
fn estimates(v: &serde_json::Value) -> Vec<(String, f64)> {
    v["parameters"]
        .as_array()
        .unwrap_or_else(|| panic!("no parameters: {v}"))
        .iter()
        .map(|p| (p["name"].as_str().unwrap().to_string(), p["estimate"].as_f64().unwrap()))
        .collect()
}

/// SIGTERM while output error still reads a silent stdin (200 lines fed, the feed open):
/// the read ends, the fit is of the rows read (the same estimates as the fit of a file
/// holding just those rows), the results are written with status `interrupted`, exit 143.
#[test]
fn sigterm_while_a_batch_fit_reads_stdin_fits_the_rows_read() {
    let Some(lines) = hfb320_lines() else { return };
    let d = scratch("batch-read");
    let out = d.join("out");
    let (mut child, err) = spawn_replay(&oe_args(&[]), &out);
    let mut stdin = child.stdin.take().unwrap();
    for l in &lines[..200] {
        writeln!(stdin, "{l}").unwrap();
    }
    stdin.flush().unwrap();
    wait_for(&err, "reading the whole record");
    std::thread::sleep(Duration::from_millis(1500));
    signal(&child, "-TERM");
    let code = exit_code(&mut child, &err);
    drop(stdin);
    let text = err.text();
    assert_eq!(code, 143, "{text}");
    assert!(text.contains("interrupted by SIGTERM"), "{text}");
    let v = summary(&out);
    assert_eq!(v["status"], "interrupted", "{v}");
    assert!(v["warnings"].to_string().contains("interrupted after"), "{v}");
    let read = v["samples_read"].as_u64().unwrap() as usize;
    assert!((10..=199).contains(&read), "{read} rows read of 199 fed");
    assert!(written(&out, "report.html"));
    assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
    // The same fit of a file holding the rows read.
    let file = d.join("rows_read.csv");
    std::fs::write(&file, lines[..=read].join("\n") + "\n").unwrap();
    let whole = d.join("whole");
    let o = bin()
        .arg("replay")
        .arg(&file)
        .args(oe_args(&[]))
        .arg("--out")
        .arg(&whole)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let w = summary(&whole);
    assert_eq!(w["samples_read"].as_u64(), Some(read as u64));
    let reason = v["status_reason"].as_str().unwrap();
    assert!(
        reason.contains(&format!("own status was `{}`", w["status"].as_str().unwrap())),
        "{reason}"
    );
    let (got, want) = (estimates(&v), estimates(&w));
    assert_eq!(got.len(), want.len());
    for ((n, a), (m, b)) in got.iter().zip(&want) {
        assert_eq!(n, m);
        assert!(
            (a - b).abs() <= 1e-9 * b.abs().max(1e-6),
            "{n}: {a} from stdin, {b} from the file"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// SIGTERM before output error has a single row (only the header fed): no fit, but still a
/// `summary.json` saying the run was interrupted and why there are no estimates, exit 143.
#[test]
fn sigterm_before_a_batch_fit_has_a_row_writes_a_summary_without_estimates() {
    let Some(lines) = hfb320_lines() else { return };
    let d = scratch("batch-empty");
    let out = d.join("out");
    let (mut child, err) = spawn_replay(&oe_args(&[]), &out);
    let mut stdin = child.stdin.take().unwrap();
    writeln!(stdin, "{}", lines[0]).unwrap();
    stdin.flush().unwrap();
    wait_for(&err, "reading the whole record");
    std::thread::sleep(Duration::from_millis(500));
    signal(&child, "-TERM");
    let code = exit_code(&mut child, &err);
    drop(stdin);
    let text = err.text();
    assert_eq!(code, 143, "{text}");
    let v = summary(&out);
    assert_eq!(v["status"], "interrupted", "{v}");
    assert!(v["parameters"].is_null(), "{v}");
    assert!(v["status_reason"].as_str().unwrap().contains("too few to fit"), "{v}");
    assert!(!out.join("report.html").exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// SIGTERM while output error reads a silent stdin ends the read; the fit of the rows read
/// (with a 10 000-replica bootstrap, minutes) then runs on, saying that a second signal stops
/// it; the second abandons the fit at once and leaves a summary without estimates, exit 143.
#[test]
fn a_second_sigterm_during_a_batch_fit_abandons_it_with_a_summary() {
    let Some(lines) = hfb320_lines() else { return };
    let d = scratch("batch-fit");
    let out = d.join("out");
    let (mut child, err) = spawn_replay(&oe_args(&["--bootstrap", "10000"]), &out);
    let mut stdin = child.stdin.take().unwrap();
    for l in &lines[..200] {
        writeln!(stdin, "{l}").unwrap();
    }
    stdin.flush().unwrap();
    wait_for(&err, "reading the whole record");
    std::thread::sleep(Duration::from_millis(1500));
    signal(&child, "-TERM");
    wait_for(&err, "a second signal stops at once");
    signal(&child, "-TERM");
    let code = exit_code(&mut child, &err);
    drop(stdin);
    let text = err.text();
    assert_eq!(code, 143, "{text}");
    let v = summary(&out);
    assert_eq!(v["status"], "interrupted", "{v}");
    assert!(v["parameters"].is_null(), "{v}");
    assert!(
        v["status_reason"].as_str().unwrap().contains("stopped the fit before it ended"),
        "{v}"
    );
    assert!(!out.join("report.html").exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// The parameters of a batch summary by name: estimate and reported σ.
fn estimates_and_sigma(v: &serde_json::Value) -> Vec<(String, f64, f64)> {
    let p = v["parameters"].as_array().unwrap_or_else(|| panic!("no parameters: {v}"));
    p.iter()
        .map(|p| {
            let name = p["name"].as_str().unwrap().to_string();
            (name, p["estimate"].as_f64().unwrap(), p["std_error"].as_f64().unwrap())
        })
        .collect()
}

/// Checks a bootstrap that a signal stopped: 10 000 replicas asked for, fewer done, and the
/// reported σ are the spread of those done (their count in a warning); or, stopped before it
/// had 2, no bootstrap σ and a warning saying so.
fn check_stopped_bootstrap(v: &serde_json::Value) {
    let b = &v["bootstrap"];
    let warnings = v["warnings"].to_string();
    if b.is_null() {
        assert!(warnings.contains("bootstrap stopped on request before it had a σ"), "{v}");
        return;
    }
    assert_eq!(b["requested"], 10_000, "{v}");
    let done = b["refits"].as_u64().unwrap();
    assert!((2..10_000).contains(&done), "{done} replicas done");
    assert!(warnings.contains(&format!("after {done} of 10000 replicas")), "{warnings}");
    for p in v["parameters"].as_array().unwrap() {
        assert_eq!(p["std_error"], p["bootstrap_std_error"], "{p}");
        assert!(p["bootstrap_std_error"].as_f64().unwrap() > 0.0, "{p}");
    }
}

/// SIGINT during the bootstrap of a fit of a file (`--bootstrap 10000`: a quarter of an hour
/// whole): it stops before its next replica, and the fit's estimates (converged before the
/// bootstrap began: the same as a fit without it) are written with the σ of the replicas
/// done, status `interrupted`, exit 130.
#[test]
fn sigint_during_the_bootstrap_of_a_file_writes_the_replicas_done() {
    let Some(h) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let d = scratch("file-boot");
    let out = d.join("out");
    let (mut child, err) =
        spawn_replay_of(h.as_os_str(), &oe_args(&["--bootstrap", "10000"]), &out);
    wait_for(&err, "replicas refitted");
    std::thread::sleep(Duration::from_secs(4));
    signal(&child, "-INT");
    let sent = Instant::now();
    let code = exit_code(&mut child, &err);
    assert!(sent.elapsed() < Duration::from_secs(30), "{:?} after the signal", sent.elapsed());
    let text = err.text();
    assert_eq!(code, 130, "{text}");
    let v = summary(&out);
    assert_eq!(v["status"], "interrupted", "{v}");
    let reason = v["status_reason"].as_str().unwrap();
    assert!(reason.contains("SIGINT") && reason.contains("own status was `converged`"), "{v}");
    check_stopped_bootstrap(&v);
    assert!(written(&out, "report.html") && temporaries(&out).is_empty());
    let plain = d.join("plain");
    let o = bin().arg("replay").arg(&h).args(oe_args(&[])).arg("--out").arg(&plain).output();
    let o = o.unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let want = estimates(&summary(&plain));
    for ((n, a, _), (m, b)) in estimates_and_sigma(&v).iter().zip(&want) {
        assert_eq!(n, m);
        assert!((a - b).abs() <= 1e-9 * b.abs().max(1e-6), "{n}: {a} stopped, {b} whole");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// SIGINT at the start of a filter-error fit of a file (initial states estimated, process noise
/// on V, α, θ, q: 30-odd iterations whole): the fit stops at its next iteration and its last
/// iterate is written, status `interrupted` with the reason, fewer iterations than the whole
/// fit, exit 130.
#[test]
fn sigint_during_a_filter_error_fit_of_a_file_writes_its_last_iterate() {
    let Some(h) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let d = scratch("file-fem");
    let mut args: Vec<OsString> =
        vec!["--map".into(), workspace().join("mappings/hfb320.toml").into()];
    args.extend(
        [
            "--estimator",
            "fem",
            "--initial-states",
            "estimate",
            "--process-noise",
            "V,alpha,theta,q",
        ]
        .map(OsString::from),
    );
    let out = d.join("out");
    let (mut child, err) = spawn_replay_of(h.as_os_str(), &args, &out);
    wait_for(&err, "reading the whole record");
    signal(&child, "-INT");
    let code = exit_code(&mut child, &err);
    let text = err.text();
    assert_eq!(code, 130, "{text}");
    assert!(text.contains("stopping the fit at its next iteration"), "{text}");
    let v = summary(&out);
    assert_eq!(v["status"], "interrupted", "{v}");
    let reason = v["status_reason"].as_str().unwrap();
    assert!(reason.contains("during the fit: the estimates are its last iterate"), "{reason}");
    assert!(reason.contains("a stop was asked for before it converged"), "{reason}");
    let whole = d.join("whole");
    let o = bin().arg("replay").arg(&h).args(&args).arg("--out").arg(&whole).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let w = summary(&whole);
    let n = |v: &serde_json::Value| v["iterations"].as_array().unwrap().len();
    assert!(n(&v) < n(&w), "{} iterations stopped, {} whole", n(&v), n(&w));
    assert!(estimates_and_sigma(&v).iter().all(|(_, a, _)| a.is_finite()), "{v}");
    assert!(written(&out, "report.html") && temporaries(&out).is_empty());
    let _ = std::fs::remove_dir_all(&d);
}

/// One SIGINT while output error's 10 000-replica bootstrap runs on a record read whole from
/// stdin: the bootstrap stops before its next replica and the fit is written with the σ of
/// the replicas done, status `interrupted`, exit 130 (it used to run on to its end).
#[test]
fn one_sigint_stops_the_bootstrap_of_a_record_read_from_stdin() {
    let Some(lines) = hfb320_lines() else { return };
    let d = scratch("stdin-boot");
    let out = d.join("out");
    let (mut child, err) = spawn_replay(&oe_args(&["--bootstrap", "10000"]), &out);
    let mut stdin = child.stdin.take().unwrap();
    for l in &lines {
        writeln!(stdin, "{l}").unwrap();
    }
    drop(stdin);
    wait_for(&err, "stdin closed after");
    std::thread::sleep(Duration::from_secs(4));
    signal(&child, "-INT");
    let sent = Instant::now();
    let code = exit_code(&mut child, &err);
    assert!(sent.elapsed() < Duration::from_secs(30), "{:?} after the signal", sent.elapsed());
    let text = err.text();
    assert_eq!(code, 130, "{text}");
    let v = summary(&out);
    assert_eq!(v["status"], "interrupted", "{v}");
    assert_eq!(v["samples_read"], 601, "{v}");
    check_stopped_bootstrap(&v);
    let _ = std::fs::remove_dir_all(&d);
}

/// A simulated record of 300 s at 100 Hz (`f16 sim`, elevator, aileron and rudder doublets):
/// its path. Long enough that the steps over the whole record take seconds.
fn long_sim(dir: &Path) -> PathBuf {
    let sc = dir.join("long.toml");
    let mut scenario = String::from(
        "kind = \"sim\"\n[aircraft]\nxcg = 0.30\nactuators = \"f16\"\n[trim]\nalt_ft = 20000.0\nvt_fps = 675.0\n[run]\nduration_s = 300.0\ndt_s = 0.01\nseed = 1\n",
    );
    for (channel, start) in [("elevator", 2.0), ("aileron", 10.0), ("rudder", 20.0)] {
        scenario.push_str(&format!(
            "[[input]]\nchannel = \"{channel}\"\nkind = \"doublet\"\namplitude_deg = 2.0\nstart_s = {start}\npulse_width_s = 1.0\n"
        ));
    }
    std::fs::write(&sc, scenario).unwrap();
    let out = dir.join("long");
    let o = bin().args(["f16", "sim"]).arg(&sc).arg("--out").arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out.join("timeseries.csv")
}

/// SIGINT during the steps over the whole record that come before the estimator, the data
/// compatibility check of `--compat auto` and the structure selection of `--model auto` (each
/// seconds on a 30 000-sample record): the run stops at once, `summary.json` says during which
/// step, status `interrupted`, no temporary file, exit 130 (the signal used to kill the
/// process, leaving only the output directory's lock).
#[test]
fn sigint_during_compat_auto_or_model_auto_writes_an_interrupted_summary() {
    let d = scratch("whole-record");
    let data = long_sim(&d);
    let map = workspace().join("mappings/aeroident-sim.toml");
    for (option, announced) in
        [("--compat", "compat: checking"), ("--model", "structure: selecting")]
    {
        let out = d.join(&option[2..]);
        let args: Vec<OsString> = vec![
            "--map".into(),
            map.clone().into(),
            "--estimator".into(),
            "rls".into(),
            option.into(),
            "auto".into(),
        ];
        let (mut child, err) = spawn_replay_of(data.as_os_str(), &args, &out);
        wait_for(&err, announced);
        std::thread::sleep(Duration::from_millis(200));
        signal(&child, "-INT");
        let sent = Instant::now();
        let code = exit_code(&mut child, &err);
        let text = err.text();
        assert!(sent.elapsed() < Duration::from_secs(10), "{:?}: {text}", sent.elapsed());
        assert_eq!(code, 130, "{option}: {text}");
        let v = summary(&out);
        assert_eq!(v["status"], "interrupted", "{v}");
        let reason = v["status_reason"].as_str().unwrap();
        assert!(reason.contains(&format!("SIGINT during {option} auto")), "{reason}");
        assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
    }
    let _ = std::fs::remove_dir_all(&d);
}

// --- compat and freqresp: the whole-record commands ---------------------------------------

const LAG_MAP: &str = "nominal_dt_s = 0.02\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nq = { column = \"q\", unit = \"rad/s\" }\nde = { column = \"de\", unit = \"rad\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\ncbar = { value = 1.5, unit = \"m\" }\nIyy = { value = 2000.0, unit = \"kg*m2\" }\n";

/// `DIR/r.csv` as a record that never ends: a named pipe holding a header and two rows, kept
/// open for writing by the returned handle, so a command reading it waits in its read (its
/// whole-record analysis under way) until the handle is dropped. `DIR/m.toml` maps it.
fn endless_record(dir: &Path) -> std::fs::File {
    let fifo = dir.join("r.csv");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    // Read and write: opening a pipe so does not wait for a reader (Linux, the BSDs).
    let mut w = std::fs::OpenOptions::new().read(true).write(true).open(&fifo).unwrap();
    w.write_all(b"t,V,a,q,de\n0,50,0.05,0,0\n0.02,50,0.05,0,0.01\n").unwrap();
    std::fs::write(dir.join("m.toml"), LAG_MAP).unwrap();
    w
}

/// `aeroident ARGS` in `dir` with its stderr collected by a thread.
fn spawn_in(dir: &Path, args: &[&str]) -> (Child, Arc<Stderr>) {
    let mut child = bin()
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let err = collect_stderr(&mut child);
    (child, err)
}

/// Waits until `out` is locked by a run (the lock file exists; the run installs its signal
/// handlers before it locks), at most 60 s.
fn wait_for_lock(out: &Path, err: &Stderr) {
    let start = Instant::now();
    while !out.join(".aeroident.lock").exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no lock: {}", err.text());
        std::thread::sleep(Duration::from_millis(20));
    }
}

const FREQRESP: [&str; 8] =
    ["freqresp", "r.csv", "--map", "m.toml", "--input", "de", "--output", "q"];
const COMPAT: [&str; 4] = ["compat", "r.csv", "--map", "m.toml"];

/// A signal while `compat` or `freqresp` reads and analyses its record ends it with
/// `summary.json` alone, status `interrupted`, naming the signal and the command, and exit
/// 128 + signal (once they wrote nothing at all).
#[test]
fn a_signal_during_compat_or_freqresp_writes_an_interrupted_summary() {
    for (tag, cmd, sig, code) in
        [("fr-int", &FREQRESP[..], "INT", 130), ("co-term", &COMPAT[..], "TERM", 143)]
    {
        let d = scratch(tag);
        let writer = endless_record(&d);
        let args: Vec<&str> = cmd.iter().copied().chain(["--out", "out"]).collect();
        let (mut child, err) = spawn_in(&d, &args);
        let out = d.join("out");
        wait_for_lock(&out, &err);
        signal(&child, &format!("-{sig}"));
        let got = exit_code(&mut child, &err);
        drop(writer);
        let text = err.text();
        assert_eq!(got, code, "{tag}: {text}");
        let v = summary(&out);
        assert_eq!(v["status"], "interrupted", "{v}");
        let reason = v["status_reason"].as_str().unwrap();
        assert!(reason.contains(&format!("SIG{sig} during `{}`", cmd[0])), "{reason}");
        let files: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| !n.starts_with('.'))
            .collect();
        assert_eq!(files, ["summary.json"], "{tag}");
        let _ = std::fs::remove_dir_all(&d);
    }
}

/// A second `compat` or `freqresp` into a directory a first one is still working for is
/// refused at once, naming the directory, before it reads anything (it would otherwise wait on
/// the same endless record); so is an `--out` that cannot be a directory. Once both exited 0
/// and the later silently replaced the other's results.
#[test]
fn compat_and_freqresp_lock_and_check_their_output_before_the_work() {
    for (tag, cmd) in [("fr-busy", &FREQRESP[..]), ("co-busy", &COMPAT[..])] {
        let d = scratch(tag);
        let writer = endless_record(&d);
        let args: Vec<&str> = cmd.iter().copied().chain(["--out", "out"]).collect();
        let (mut first, first_err) = spawn_in(&d, &args);
        wait_for_lock(&d.join("out"), &first_err);
        let (mut second, err) = spawn_in(&d, &args);
        let code = exit_code(&mut second, &err);
        let text = err.text();
        assert_eq!(code, 1, "{tag}: {text}");
        assert!(text.contains("is in use by another aeroident run"), "{tag}: {text}");
        std::fs::write(d.join("file"), "not a directory").unwrap();
        let args: Vec<&str> = cmd.iter().copied().chain(["--out", "file"]).collect();
        let (mut third, err) = spawn_in(&d, &args);
        let code = exit_code(&mut third, &err);
        assert_eq!(code, 1, "{tag}: {}", err.text());
        assert!(err.text().contains("output directory `file`"), "{tag}: {}", err.text());
        signal(&first, "-TERM");
        assert_eq!(exit_code(&mut first, &first_err), 143, "{}", first_err.text());
        drop(writer);
        let _ = std::fs::remove_dir_all(&d);
    }
}
