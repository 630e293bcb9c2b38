//! The end of a live view as a client sees it: whatever the time between the feed's end and
//! the summary's verdicts, and however soon the server is closed after them, every connected
//! client's last `update` holds the summary's status and verdicts, and `end` follows it. The
//! view is fed by a replay of a small record written here; the client reads the stream over
//! TCP as a browser's `EventSource` does.

use super::*;
use aeroident_io::replay_output::ReplaySummary;
use aeroident_io::{FlightDataReader, Mapping};
use aeroident_pipelines::live::{LiveConfig, LiveObserver, LiveState};
use aeroident_pipelines::replay::{ReplayOptions, replay};
use std::io::{Read, Write};

const MAP: &str = "nominal_dt_s = 0.1\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\n\
vt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\n\
q = { column = \"q\", unit = \"rad/s\" }\nax = { column = \"ax\", unit = \"m/s2\" }\n\
az = { column = \"az\", unit = \"m/s2\" }\nde = { column = \"de\", unit = \"rad\" }\n\
thrust = { value = 0.0, unit = \"N\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\n\
mass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\n\
cbar = { value = 1.5, unit = \"m\" }\nIyy = { value = 2000.0, unit = \"kg*m2\" }\n";

/// 100 samples at 0.1 s exciting α, q and δe independently.
fn record() -> String {
    let mut csv = String::from("t,V,a,q,ax,az,de\n");
    for k in 0..100 {
        let t = f64::from(k) * 0.1;
        let (a, q, d) =
            (0.05 + 0.02 * (1.3 * t).sin(), 0.1 * (0.7 * t).cos(), 0.03 * (2.9 * t).sin());
        let (ax, az) = (0.1 + 0.5 * a + 0.2 * d, -9.8 - 30.0 * a - 4.0 * d + q);
        csv.push_str(&format!("{t:.1},50,{a},{q},{ax},{az},{d}\n"));
    }
    csv
}

/// A view fed with the whole record (its feed ended, not yet concluded) and the replay's
/// summary.
fn fed_view() -> (SharedLive, ReplaySummary) {
    let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
    let csv = record();
    let reader = FlightDataReader::new(csv.as_bytes(), "d.csv", &m).unwrap();
    let shared = LiveState::new(LiveConfig::default(), None).shared();
    let opts = ReplayOptions { diff_window: 3, spike_screen: None, ..Default::default() };
    let mut observer = LiveObserver::new(shared.clone(), None);
    let out = replay(reader, &m, &opts, &mut observer).unwrap();
    (shared, out.summary)
}

/// The events of `/events` on `addr`, read to the stream's close: `(event, data)` pairs.
fn read_stream(addr: SocketAddr) -> Vec<(String, String)> {
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    write!(s, "GET /events HTTP/1.0\r\nHost: {addr}\r\n\r\n").unwrap();
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).unwrap();
    let text = String::from_utf8(raw).unwrap();
    let body = text.split_once("\r\n\r\n").unwrap().1;
    let mut events = Vec::new();
    for block in body.split("\n\n") {
        let field = |k: &str| block.lines().find_map(|l| l.strip_prefix(k)).map(str::to_string);
        if let Some(e) = field("event: ") {
            events.push((e, field("data: ").unwrap_or_default()));
        }
    }
    events
}

/// Starts a server on `shared`, connects one client, waits `work` (the end-of-feed work),
/// concludes with `summary` when given (else the job failed), closes at once, and returns
/// the client's events and whether the close saw every client done.
fn end_after(work: Duration, summary: Option<&ReplaySummary>) -> (Vec<(String, String)>, bool) {
    let (shared, _) = fed_view();
    let server = start("127.0.0.1:0".parse().unwrap(), shared.clone()).unwrap();
    let addr = server.addr();
    let client = std::thread::spawn(move || read_stream(addr));
    // The client is connected and on its tick before the end comes.
    std::thread::sleep(Duration::from_millis(250) + work);
    match summary {
        Some(s) => lock(&shared).conclude(s),
        None => lock(&shared).abandon("failed", "the fit did not start"),
    }
    let closed = server.close(Duration::from_secs(10));
    (client.join().unwrap(), closed)
}

/// The last `update` before `end`, parsed.
fn last_update(events: &[(String, String)]) -> serde_json::Value {
    assert_eq!(events.last().map(|e| e.0.as_str()), Some("end"), "{events:?}");
    assert!(events.len() >= 2, "{events:?}");
    let (kind, data) = &events[events.len() - 2];
    assert_eq!(kind, "update");
    serde_json::from_str::<serde_json::Value>(data).unwrap()["update"].clone()
}

fn assert_final(events: &[(String, String)], summary: &ReplaySummary) {
    let last = last_update(events);
    assert_eq!(last["ended"], true);
    assert_eq!(last["status"], summary.status.as_str());
    let verdicts = last["verdicts"].as_array().unwrap();
    assert_eq!(verdicts.len(), summary.parameters.len());
    for (v, p) in verdicts.iter().zip(&summary.parameters) {
        assert_eq!(v["status"], p.result.status.as_str(), "{}", p.result.name);
    }
}

#[test]
fn the_final_update_arrives_when_the_server_closes_at_once() {
    let (_, summary) = fed_view();
    let (events, closed) = end_after(Duration::ZERO, Some(&summary));
    assert!(closed);
    assert_final(&events, &summary);
}

#[test]
fn the_final_update_arrives_after_long_end_of_feed_work() {
    let (_, summary) = fed_view();
    // Many ticks pass between the feed's end and the verdicts; the stream stays open for them.
    let (events, closed) = end_after(Duration::from_secs(2), Some(&summary));
    assert!(closed);
    assert_final(&events, &summary);
    let updates = events.iter().filter(|e| e.0 == "update").count();
    assert!(updates >= 10, "{updates} updates over 2.25 s at one per tick");
}

#[test]
fn a_failed_job_ends_the_stream_with_its_reason() {
    let (events, closed) = end_after(Duration::ZERO, None);
    assert!(closed);
    let last = last_update(&events);
    assert_eq!(last["ended"], true);
    assert_eq!(last["status"], "failed");
    assert!(last["verdicts"].is_null());
    let warned = events.iter().any(|(_, d)| d.contains("failed: the fit did not start"));
    assert!(warned, "{events:?}");
}

/// With no client connected the close does not wait.
#[test]
fn closing_without_clients_is_immediate() {
    let (shared, summary) = fed_view();
    let server = start("127.0.0.1:0".parse().unwrap(), shared.clone()).unwrap();
    lock(&shared).conclude(&summary);
    let t0 = Instant::now();
    assert!(server.close(Duration::from_secs(10)));
    assert!(t0.elapsed() < Duration::from_secs(2), "{:?}", t0.elapsed());
}
