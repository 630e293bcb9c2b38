//! `aeroident live`'s running cross-check on a real record: the HFB-320 flight (../shared)
//! replayed at 10 × real time through the EKF with Jategaonkar's model, whose pitch damping
//! the equation-error methods put at −43 to −47 and the EKF at −25 (docs/real-data.md). While
//! the feed runs, the page's stream must flag `Cm_q` with the panel's words, naming both
//! other real-time methods; at the end the summary's own flags decide, as the page's final
//! state must show. The stream is read as the page reads it (server-sent events), no browser.

use crate::common;
use std::io::{Read, Write};

/// Starts `aeroident live` with `extra`; returns the child and the page's `host:port`.
fn start(
    data: &std::path::Path,
    out: &std::path::Path,
    extra: &[&str],
) -> (std::process::Child, String) {
    let mut cmd = common::live::hfb320(data, "hfb320_jategaonkar.toml", out);
    cmd.args(["--estimator", "ekf", "--speed", "10"]).args(extra);
    let (child, url, _rest) = common::live::spawn(cmd);
    let host = url.trim_start_matches("http://").trim_end_matches('/').to_string();
    (child, host)
}

/// Every `update` event of the page's stream, from connecting to its `end`.
fn updates(host: &str) -> Vec<serde_json::Value> {
    let mut s = std::net::TcpStream::connect(host).unwrap();
    write!(s, "GET /events HTTP/1.0\r\nHost: {host}\r\n\r\n").unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    let body = text.split_once("\r\n\r\n").unwrap().1;
    body.split("\n\n")
        .filter_map(|e| e.strip_prefix("event: update\ndata: "))
        .map(|d| serde_json::from_str(d).unwrap())
        .collect()
}

/// The index of `name` in the stream's parameter names.
fn index(events: &[serde_json::Value], name: &str) -> usize {
    let names = events[0]["hello"]["names"].as_array().unwrap();
    names.iter().position(|n| n == name).unwrap_or_else(|| panic!("no {name}: {names:?}"))
}

#[test]
fn the_running_cross_check_flags_a_split_while_the_feed_runs() {
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("aeroident-live-cc-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (mut child, host) = start(&data, &dir.join("on"), &[]);
    let events = updates(&host);
    assert!(child.wait().unwrap().success());
    let q = index(&events, "Cm_q");
    let running: Vec<&serde_json::Value> =
        events.iter().map(|e| &e["update"]).filter(|u| u["ended"] == false).collect();
    assert!(running.len() >= 20, "{} updates while running", running.len());
    let flagged = running.iter().filter(|u| {
        let r = u["states"][q]["reason"].as_str().unwrap_or_default();
        u["states"][q]["phase"] == "flagged"
            && r.starts_with("cross-check: the methods split on Cm_q")
            && r.contains("rls ")
            && r.contains("rls-iv ")
            && r.contains("ekf ")
    });
    // From its first judgement after a few seconds of record on, to the feed's end.
    assert!(flagged.count() * 2 >= running.len(), "{:?}", running.last().unwrap()["states"][q]);
    let line = running.last().unwrap()["cross_check"].as_str().unwrap();
    assert!(line.starts_with("rls, rls-iv follow the feed; at t = "), "{line}");
    // At the end the summary decides: its flags, and the final state, agree.
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("on/summary.json")).unwrap()).unwrap();
    let last = &events.last().unwrap()["update"];
    assert_eq!(last["status"], "complete");
    for (i, p) in summary["parameters"].as_array().unwrap().iter().enumerate() {
        let flagged = !p["flags"].as_array().unwrap().is_empty();
        assert_eq!(last["states"][i]["phase"] == "flagged", flagged, "{p}");
    }

    // Both switched off (the running panel and the one after the feed): no panel, and no
    // flag but the plausibility range's, to the end; the summary says the panel did not run.
    let off = ["--no-live-cross-check", "--no-cross-check"];
    let (mut child, host) = start(&data, &dir.join("off"), &off);
    let events = updates(&host);
    assert!(child.wait().unwrap().success());
    for e in &events {
        let u = &e["update"];
        assert!(u["cross_check"].is_null(), "{}", u["cross_check"]);
        let r = u["states"][q]["reason"].as_str().unwrap_or_default();
        assert!(!r.starts_with("cross-check"), "{r}");
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("off/summary.json")).unwrap()).unwrap();
    let warnings = summary["warnings"].as_array().unwrap();
    let said = warnings.iter().any(|w| w.as_str().unwrap().starts_with("cross-check not run"));
    assert!(said, "{warnings:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
