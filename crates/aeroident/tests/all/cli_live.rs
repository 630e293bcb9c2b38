//! `aeroident live` in a real browser: the HFB-320 record (../shared) replayed at 10 × real
//! time with the live view on a loopback port, opened in headless Chromium twice — once while
//! the feed runs (it streams the run as it goes) and once after the feed's end (a late
//! joiner) — and a screenshot taken during the replay. Both pages must show, in the end, each
//! derivative's final estimate exactly as the same run's `summary.json` has it, its verdict,
//! and the whole history: as many points as `estimates.csv` has rows, from its first time to
//! its last. Ctrl-C ends the serving after the outputs are written.
//!
//! Needs the `chromium` binary (Debian package `chromium`; `.ci/run` installs it). Without it
//! the test is skipped with a message — and fails when `CI=true`.

use crate::common;
use std::io::Read;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use common::browser::{chromium, console_lines};

/// Headless Chromium on `url` with `extra` arguments and a fresh profile in `profile`;
/// returns (stdout, stderr), failing the test when it fails.
fn headless(chrome: &Path, url: &str, profile: &Path, extra: &[&str]) -> (String, String) {
    let (ok, out, err) = common::browser::headless(chrome, url, profile, extra);
    assert!(ok, "chromium failed on {url}: {err}");
    (out, err)
}

/// The value of attribute `name` in the first tag of `html` after `at`.
fn attribute<'a>(html: &'a str, at: &str, name: &str) -> Option<&'a str> {
    let start = html.find(at)?;
    let tag_end = start + html[start..].find('>')?;
    let tag = &html[start..tag_end];
    let key = format!("{name}=\"");
    let v = tag.find(&key)? + key.len();
    Some(&tag[v..v + tag[v..].find('"')?])
}

/// The row of parameter `name` in the page's table, from its `<tr` to its `</tr>`.
fn row<'a>(dom: &'a str, name: &str) -> &'a str {
    let at = format!("<tr id=\"p-{name}\"");
    let start = dom.find(&at).unwrap_or_else(|| panic!("no row for {name}"));
    let end = start + dom[start..].find("</tr>").unwrap();
    &dom[start..end]
}

/// What a finished page must show (module doc), against `summary` and the rows of
/// `estimates.csv` (its times).
fn check_page(which: &str, dom: &str, summary: &serde_json::Value, times: &[f64]) {
    let params = summary["parameters"].as_array().unwrap();
    assert!(params.len() >= 4, "{summary}");
    for p in params {
        let name = p["name"].as_str().unwrap();
        let r = row(dom, name);
        let shown = attribute(r, "class=\"est\"", "data-value").unwrap();
        match p["estimate"].as_f64() {
            // The page shows JavaScript's shortest round-trip text of the number the server
            // sent; serde_json's default float parser may be one unit in the last place off.
            Some(e) => {
                let v: f64 = shown.parse().unwrap_or_else(|_| panic!("{which} {name}: {shown:?}"));
                assert!(
                    (v - e).abs() <= 4.0 * f64::EPSILON * e.abs(),
                    "{which} {name}: {v} vs {e}"
                );
            }
            None => assert_eq!(shown, "", "{which} {name}"),
        }
        let status = attribute(r, "<tr", "data-status");
        assert_eq!(status, p["status"].as_str(), "{which} {name}");
        let flagged = !p["flags"].as_array().unwrap().is_empty();
        let phase = attribute(r, "<tr", "data-phase").unwrap();
        assert_eq!(phase == "flagged", flagged, "{which} {name}: {phase} vs {}", p["flags"]);
        if let Some(reference) = p["reference"].as_f64() {
            let shown: f64 = attribute(r, "class=\"ref\"", "data-value").unwrap().parse().unwrap();
            assert!((shown - reference).abs() <= 4.0 * f64::EPSILON * reference.abs());
        }
    }
    let h = |k: &str| attribute(dom, "<div id=\"history\"", k).unwrap().to_string();
    assert_eq!(h("data-points").parse::<usize>().unwrap(), times.len(), "{which}");
    assert_eq!(h("data-first-t").parse::<f64>().unwrap(), times[0], "{which}");
    assert_eq!(h("data-last-t").parse::<f64>().unwrap(), *times.last().unwrap(), "{which}");
    let status = attribute(dom, "<span id=\"status\"", "data-status").unwrap();
    assert_eq!(Some(status), summary["status"].as_str(), "{which}");
}

/// The body of `GET <url><path>` (HTTP/1.0, loopback).
fn http_get(url: &str, path: &str) -> String {
    use std::io::Write;
    let host = url.trim_start_matches("http://").trim_end_matches('/');
    let mut s = std::net::TcpStream::connect(host).unwrap();
    write!(s, "GET /{path} HTTP/1.0\r\nHost: {host}\r\n\r\n").unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    text.split("\r\n\r\n").nth(1).unwrap_or_default().to_string()
}

/// The times of `estimates.csv`'s rows.
fn estimate_times(csv: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(csv).unwrap();
    text.lines().skip(1).map(|l| l.split(',').next().unwrap().parse().unwrap()).collect()
}

/// Starts `aeroident live` on the HFB-320 record at 5× with `out`; returns the child, the
/// page's URL and the thread collecting the rest of its stderr.
fn start_live(
    data: &Path,
    out: &Path,
) -> (std::process::Child, String, std::thread::JoinHandle<String>) {
    let mut cmd = common::live::hfb320(data, "hfb320_book_q0.toml", out);
    cmd.args(["--speed", "5", "--linger-s", "120"]);
    common::live::spawn(cmd)
}

#[test]
fn live_page_streams_the_replay_and_ends_as_its_summary() {
    let Some(chrome) = chromium() else {
        assert!(
            std::env::var("CI").map_or(true, |v| v != "true"),
            "CI=true but no chromium on PATH: .ci/run must install the Debian package `chromium`"
        );
        eprintln!("SKIPPED cli_live: no chromium on PATH (install the Debian package `chromium`)");
        return;
    };
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("aeroident-live-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("out");
    let (mut child, url, rest) = start_live(&data, &out);
    let started = Instant::now();
    // The page opened while the feed runs (60 s of record at 5×: ≈ 12 s): its stream closes
    // after the final verdicts, and then the DOM is dumped.
    let (c, u, p) = (chrome.clone(), url.clone(), dir.join("profile-early"));
    let early = std::thread::spawn(move || {
        headless(&c, &u, &p, &["--dump-dom", "--virtual-time-budget=2000", "--timeout=90000"])
    });
    std::thread::sleep(Duration::from_millis(2500));
    let shot = dir.join("live.png");
    let arg = format!("--screenshot={}", shot.display());
    let (_, shot_log) = headless(
        &chrome,
        &url,
        &dir.join("profile-shot"),
        &[&arg, "--window-size=1400,1000", "--timeout=1500"],
    );
    let during = http_get(&url, "latest");
    let (early_dom, early_log) = early.join().unwrap();
    while !out.join("summary.json").exists() {
        assert!(started.elapsed() < Duration::from_secs(90), "no summary.json");
        std::thread::sleep(Duration::from_millis(100));
    }
    // A late joiner: the feed has ended and the outputs are written.
    let (late_dom, late_log) = headless(
        &chrome,
        &url,
        &dir.join("profile-late"),
        &["--dump-dom", "--virtual-time-budget=2000", "--timeout=30000"],
    );
    let kill = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let status = child.wait().unwrap();
    let log = rest.join().unwrap();
    assert!(status.success(), "Ctrl-C during the linger ends it cleanly: {status:?}\n{log}");

    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "complete", "{log}");
    let times = estimate_times(&out.join("estimates.csv"));
    assert!(times.len() > 500, "{}", times.len());
    check_page("early page", &early_dom, &summary, &times);
    check_page("late page", &late_dom, &summary, &times);
    // The early page followed the run (one update per tick for seconds), the late one got
    // the history at once.
    let updates = |dom: &str| -> u32 {
        attribute(dom, "<div id=\"history\"", "data-updates").unwrap().parse().unwrap()
    };
    assert!(updates(&early_dom) >= 10, "early page: {} updates", updates(&early_dom));
    assert!(updates(&late_dom) <= 2, "late page: {} updates", updates(&late_dom));
    for l in [&early_log, &late_log, &shot_log] {
        assert!(console_lines(l).is_empty(), "console messages: {:?}", console_lines(l));
    }
    // The screenshot was taken while the feed ran (≈ 12 s).
    assert!(during.contains("\"ended\":false"), "the feed had ended: {during}");
    let png = std::fs::read(&shot).unwrap();
    assert!(png.starts_with(b"\x89PNG") && png.len() > 20_000, "{} bytes", png.len());
    let _ = std::fs::remove_dir_all(&dir);
}
