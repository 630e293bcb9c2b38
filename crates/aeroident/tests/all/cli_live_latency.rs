//! How far the live view lags a 100 Hz MAVLink feed: the JSBSim F-16 doublets (../shared),
//! 1,200 samples sent over UDP loopback at 100 samples a second (each sample's frame of
//! messages, the clock last) to `aeroident live mavlink:udp:…`, while this test reads the
//! page's event stream (`/events`) as the page does. For each update, its lag is the wall
//! time from sending the sample the update shows as latest to the update's arrival (the
//! record stage's look-ahead: the spike screen's 8 samples and the differentiator's 2, the
//! estimator, the stream); the page is furthest behind just before the next update arrives
//! (one server tick, 0.1 s, later). That worst case must stay below 0.5 s at every update;
//! the numbers are printed (docs/live.md quotes them).

use crate::common;
use aeroident_estimators::AirDataSample;
use aeroident_io::mavlink::feed::{Sender, end_of_stream, frame};
use aeroident_io::{FlightDataReader, Mapping, RecordEvent};
use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The JSBSim F-16 aileron/rudder doublets, as samples.
fn flight() -> Option<Vec<AirDataSample>> {
    let path = common::shared("jsbsim_samples/f16_ail_rud_doublets_20s_60Hz.csv")?;
    let m = Mapping::from_path(&common::workspace().join("mappings/jsbsim.toml")).unwrap();
    let file = std::fs::File::open(&path).unwrap();
    let reader = FlightDataReader::new(BufReader::new(file), "f16", &m).unwrap();
    Some(
        reader
            .filter_map(|e| match e.unwrap() {
                RecordEvent::Sample { sample, .. } => Some(sample),
                _ => None,
            })
            .collect(),
    )
}

/// Starts `aeroident live` on a MAVLink feed; returns the child, the UDP address it listens on
/// and the page's URL.
fn start(out: &std::path::Path) -> (std::process::Child, std::net::SocketAddr, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .arg("live")
        .arg("mavlink:udp:127.0.0.1:0?timeout_s=20")
        .arg("--map")
        .arg(common::workspace().join("mappings/mavlink-aeroident.toml"))
        .arg("--out")
        .arg(out)
        .args(["--serve", "127.0.0.1:0"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let (mut udp, mut url) = (None, None);
    let mut line = String::new();
    while udp.is_none() || url.is_none() {
        line.clear();
        assert!(stderr.read_line(&mut line).unwrap() > 0, "no address lines");
        if let Some(rest) = line.strip_prefix("listening on ") {
            udp = rest.split_whitespace().next().map(|a| a.parse().unwrap());
        }
        if let Some(rest) = line.trim().strip_prefix("live view on ") {
            url = Some(rest.to_string());
        }
    }
    // Drain stderr so that the child never blocks on it.
    std::thread::spawn(move || std::io::copy(&mut stderr, &mut std::io::sink()));
    (child, udp.unwrap(), url.unwrap())
}

/// Reads the event stream of `url` until it ends; returns, per update, its arrival and the
/// latest sample time it shows.
fn read_stream(url: &str) -> Vec<(Instant, f64)> {
    let host = url.trim_start_matches("http://").trim_end_matches('/');
    let mut s = std::net::TcpStream::connect(host).unwrap();
    write!(s, "GET /events HTTP/1.0\r\nHost: {host}\r\n\r\n").unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    let mut got = Vec::new();
    for line in BufReader::new(s).lines() {
        let Ok(line) = line else { break };
        let Some(json) = line.strip_prefix("data: ") else { continue };
        let now = Instant::now();
        let v: serde_json::Value = serde_json::from_str(json).unwrap();
        if let Some(t) = v["update"]["latest"]["t"].as_f64() {
            got.push((now, t));
        }
    }
    got
}

#[test]
fn live_view_keeps_within_half_a_second_of_a_100_hz_feed() {
    let Some(samples) = flight() else { return };
    let samples = &samples[..1200.min(samples.len())];
    let dir = std::env::temp_dir().join(format!("aeroident-live-lag-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (mut child, udp, url) = start(&dir);
    let reader = {
        let url = url.clone();
        std::thread::spawn(move || read_stream(&url))
    };
    // Each sample's send time, by its record time (ms, as the clock message carries it).
    let sent: Arc<Mutex<Vec<(f64, Instant)>>> = Arc::default();
    let mut tx = Sender::new(udp).unwrap();
    let t0 = Instant::now();
    for (k, s) in samples.iter().enumerate() {
        let due = t0 + Duration::from_millis(10 * k as u64);
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
        for m in frame(s) {
            tx.send(&m).unwrap();
        }
        sent.lock().unwrap().push(((s.t_s * 1000.0).round() / 1000.0, Instant::now()));
    }
    let feed_s = t0.elapsed().as_secs_f64();
    tx.send(&end_of_stream()).unwrap();
    let updates = reader.join().unwrap();
    assert!(child.wait().unwrap().success());
    let sent = sent.lock().unwrap();
    // When each update's latest sample was sent.
    let shown: Vec<(Instant, Instant)> = updates
        .iter()
        .filter_map(|(at, t)| {
            let k = sent.partition_point(|(ts, _)| ts < &(t - 5e-4));
            let (ts, when) = sent.get(k)?;
            assert!((ts - t).abs() < 1e-3, "update shows t = {t}, nearest sent {ts}");
            Some((*at, *when))
        })
        .collect();
    assert!(shown.len() > 50, "{} updates", shown.len());
    let secs = |a: Instant, b: Instant| a.saturating_duration_since(b).as_secs_f64();
    // The lag as an update arrives, and the most the page is behind: just before the next
    // update arrives, it still shows this one's sample.
    let mut lags: Vec<f64> = shown.iter().map(|(at, when)| secs(*at, *when)).collect();
    let mut behind: Vec<f64> = shown.windows(2).map(|w| secs(w[1].0, w[0].1)).collect();
    lags.sort_by(f64::total_cmp);
    behind.sort_by(f64::total_cmp);
    let q = |v: &[f64], p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    let rate = samples.len() as f64 / feed_s;
    eprintln!(
        "live view behind a {rate:.0} Hz MAVLink feed over {} updates: on arrival median {:.3} s, max {:.3} s; at most (before the next update) median {:.3} s, 95 % {:.3} s, max {:.3} s",
        shown.len(),
        q(&lags, 0.5),
        q(&lags, 1.0),
        q(&behind, 0.5),
        q(&behind, 0.95),
        q(&behind, 1.0)
    );
    assert!(rate > 90.0, "the feed ran at {rate} Hz");
    assert!(q(&behind, 1.0) < 0.5, "the view was behind the feed by up to {} s", q(&behind, 1.0));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["samples_read"], samples.len());
    let _ = std::fs::remove_dir_all(&dir);
}
