//! A recorded flight sent as MAVLink messages over UDP loopback and replayed live gives the same
//! estimates as the file replay of the values as sent (f32-rounded, written to a CSV by this
//! test), to 1e-12; a garbage datagram is reported and changes nothing; the end-of-stream
//! message ends the replay. Also through the CLI (`replay mavlink:udp:127.0.0.1:0`).

use crate::common;
use aeroident_estimators::AirDataSample;
use aeroident_io::mavlink::feed::{Sender, end_of_stream, frame};
use aeroident_io::mavlink::{LinkStats, MavlinkRows, MavlinkUrl};
use aeroident_io::{FlightDataReader, Mapping, RecordEvent};
use aeroident_pipelines::estimators::EstimatorKind;
use aeroident_pipelines::replay::{EstimateRows, ReplayOptions, replay};
use common::{shared, workspace};
use std::io::BufRead;
use std::sync::{Arc, Mutex};

fn mapping(name: &str) -> Mapping {
    Mapping::from_path(&workspace().join("mappings").join(name)).unwrap()
}

/// The JSBSim F-16 aileron/rudder doublets (noisy sensors), as samples.
fn flight() -> Option<Vec<AirDataSample>> {
    let path = shared("jsbsim_samples/f16_ail_rud_doublets_20s_60Hz.csv")?;
    let m = mapping("jsbsim.toml");
    let file = std::fs::File::open(&path).unwrap();
    let reader = FlightDataReader::new(std::io::BufReader::new(file), "f16", &m).unwrap();
    let samples: Vec<AirDataSample> = reader
        .filter_map(|e| match e.unwrap() {
            RecordEvent::Sample { sample, .. } => Some(sample),
            _ => None,
        })
        .collect();
    assert!(samples.len() > 1000);
    Some(samples)
}

/// One as-sent column: its value from a sample.
type Column<'a> = Box<dyn Fn(&AirDataSample) -> f64 + 'a>;

/// The values as the messages carry them (each `f32`, exactly as `f64`), under the shipped
/// mapping's column names: written by this test from the samples, independently of the
/// receiver's row builder.
fn as_sent_csv(samples: &[AirDataSample]) -> String {
    let f = |x: f64| f64::from(x as f32);
    let o = |x: Option<f64>| f(x.unwrap());
    let mut cols: Vec<(&str, Column<'_>)> = vec![
        ("ATTITUDE.time_boot_ms", Box::new(|s| (s.t_s * 1000.0).round())),
        ("VFR_HUD.airspeed", Box::new(move |s| f(s.vt_mps))),
        ("AOA_SSA.AOA", Box::new(move |s| f(s.alpha_rad.to_degrees()))),
        ("AOA_SSA.SSA", Box::new(move |s| o(s.beta_rad.map(f64::to_degrees)))),
        ("ATTITUDE.roll", Box::new(move |s| o(s.phi_rad))),
        ("ATTITUDE.pitch", Box::new(move |s| o(s.theta_rad))),
        ("ATTITUDE.yaw", Box::new(move |s| o(s.psi_rad.map(|x| x.sin().atan2(x.cos()))))),
        ("ATTITUDE.rollspeed", Box::new(move |s| o(s.p_rad_s))),
        ("ATTITUDE.pitchspeed", Box::new(move |s| o(s.q_rad_s))),
        ("ATTITUDE.yawspeed", Box::new(move |s| o(s.r_rad_s))),
        ("HIGHRES_IMU.xacc", Box::new(move |s| o(s.ax_mps2))),
        ("HIGHRES_IMU.yacc", Box::new(move |s| o(s.ay_mps2))),
        ("HIGHRES_IMU.zacc", Box::new(move |s| o(s.az_mps2))),
        ("HIGHRES_IMU.diff_pressure", Box::new(move |s| f(s.qbar_pa / 100.0))),
        ("NAMED_VALUE_FLOAT[de].value", Box::new(move |s| o(s.de_rad))),
        ("NAMED_VALUE_FLOAT[da].value", Box::new(move |s| o(s.da_rad))),
        ("NAMED_VALUE_FLOAT[dr].value", Box::new(move |s| o(s.dr_rad))),
        ("NAMED_VALUE_FLOAT[throttle].value", Box::new(move |s| o(s.throttle))),
        ("NAMED_VALUE_FLOAT[thrust].value", Box::new(move |s| o(s.thrust_n))),
        ("NAMED_VALUE_FLOAT[thr_mom].value", Box::new(move |s| o(s.thrust_moment_nm))),
        ("NAMED_VALUE_FLOAT[rho].value", Box::new(move |s| o(s.rho_kgpm3))),
        ("NAMED_VALUE_FLOAT[mass].value", Box::new(move |s| f(s.constants.mass_kg))),
        ("NAMED_VALUE_FLOAT[S].value", Box::new(move |s| f(s.constants.S_m2))),
        ("NAMED_VALUE_FLOAT[cbar].value", Box::new(move |s| o(s.constants.cbar_m))),
        ("NAMED_VALUE_FLOAT[b].value", Box::new(move |s| o(s.constants.b_m))),
        ("NAMED_VALUE_FLOAT[Ixx].value", Box::new(move |s| o(s.constants.Ixx_kgm2))),
        ("NAMED_VALUE_FLOAT[Iyy].value", Box::new(move |s| o(s.constants.Iyy_kgm2))),
        ("NAMED_VALUE_FLOAT[Izz].value", Box::new(move |s| o(s.constants.Izz_kgm2))),
        ("NAMED_VALUE_FLOAT[Ixz].value", Box::new(move |s| o(s.constants.Ixz_kgm2))),
    ];
    // Column order is free: the reader finds columns by name. Reverse it to show that.
    cols.reverse();
    let mut text = cols.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(",");
    text.push('\n');
    for s in samples {
        let row: Vec<String> = cols.iter().map(|(_, v)| format!("{}", v(s))).collect();
        text.push_str(&row.join(","));
        text.push('\n');
    }
    text
}

/// Sends the samples as MAVLink frames to `to`, a garbage datagram first, then the
/// end-of-stream message.
///
/// The loopback receive buffer holds only a few hundred datagrams, and on a loaded machine the
/// receiver thread may not run for tens of milliseconds: an unpaced sender then loses datagrams
/// in the kernel (which the feed counts as `lost`, but the test wants the whole record). With
/// `received` (the feed's own statistics, in-process) the sender keeps at most
/// [`WINDOW`] datagrams in flight — flow control, as a real link's rate limit would give;
/// without it (a separate process) it paces itself by time.
fn send(
    samples: &[AirDataSample],
    to: std::net::SocketAddr,
    received: Option<Arc<Mutex<LinkStats>>>,
) {
    const WINDOW: u64 = 100;
    let mut tx = Sender::new(to).unwrap();
    tx.send_raw(b"not a MAVLink frame").unwrap();
    let mut sent = 1u64;
    for s in samples {
        for m in frame(s) {
            tx.send(&m).unwrap();
            sent += 1;
        }
        match &received {
            Some(stats) => {
                let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
                while stats.lock().unwrap().datagrams + WINDOW < sent
                    && std::time::Instant::now() < deadline
                {
                    std::thread::sleep(std::time::Duration::from_micros(100));
                }
            }
            None => std::thread::sleep(std::time::Duration::from_millis(2)),
        }
    }
    tx.send(&end_of_stream()).unwrap();
}

/// The estimates CSV of a replay: (header, rows of fields).
fn parse(text: &[u8]) -> (String, Vec<Vec<Option<f64>>>) {
    let text = std::str::from_utf8(text).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let rows = lines
        .map(|l| l.split(',').map(|f| (!f.is_empty()).then(|| f.parse::<f64>().unwrap())).collect())
        .collect();
    (header, rows)
}

/// Largest |live − file| over every estimate and σ; panics on any structural difference.
fn max_difference(file: &[u8], live: &[u8]) -> f64 {
    let (hf, rf) = parse(file);
    let (hl, rl) = parse(live);
    assert_eq!(hf, hl);
    assert_eq!(rf.len(), rl.len(), "rows of estimates");
    let mut worst = 0.0f64;
    for (k, (a, b)) in rf.iter().zip(&rl).enumerate() {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            match (x, y) {
                (Some(x), Some(y)) => worst = worst.max((x - y).abs()),
                (None, None) => {}
                _ => panic!("row {k}: identified in one replay only: {a:?} vs {b:?}"),
            }
        }
    }
    worst
}

#[test]
fn loopback_feed_equals_the_file_replay() {
    let Some(samples) = flight() else { return };
    let map = mapping("mavlink-aeroident.toml");
    let csv = as_sent_csv(&samples);
    for estimator in [EstimatorKind::Rls, EstimatorKind::Ftr] {
        let opts = ReplayOptions { estimator, ..ReplayOptions::default() };
        let mut file_out = Vec::new();
        let reader = FlightDataReader::new(csv.as_bytes(), "as-sent.csv", &map).unwrap();
        let file = replay(
            reader,
            &map,
            &opts,
            &mut EstimateRows {
                sinks: vec![&mut file_out],
                flush_each: false,
                rate: Default::default(),
            },
        )
        .unwrap();

        let url = MavlinkUrl::parse("mavlink:udp:127.0.0.1:0?timeout_s=20").unwrap();
        let rows = MavlinkRows::open(&url, &map, None).unwrap();
        let to = rows.local_addr();
        let stats = rows.stats();
        let sender = {
            let samples = samples.clone();
            let received = Arc::clone(&stats);
            std::thread::spawn(move || send(&samples, to, Some(received)))
        };
        let reader = FlightDataReader::new(rows, &url.text, &map).unwrap();
        let mut live_out = Vec::new();
        let live = replay(
            reader,
            &map,
            &opts,
            &mut EstimateRows {
                sinks: vec![&mut live_out],
                flush_each: false,
                rate: Default::default(),
            },
        )
        .unwrap();
        sender.join().unwrap();

        let s = stats.lock().unwrap().clone();
        assert_eq!(s.rows as usize, samples.len(), "{s:?}");
        assert_eq!((s.lost, s.unparseable, s.undecodable), (0, 1, 0), "{s:?}");
        assert!(s.problems[0].contains("holds no valid MAVLink frame"), "{:?}", s.problems);
        assert!(s.end.contains("end-of-stream"), "{}", s.end);
        assert_eq!(live.summary.samples_read, file.summary.samples_read);
        assert_eq!(live.summary.samples_rejected, file.summary.samples_rejected);
        let worst = max_difference(&file_out, &live_out);
        eprintln!(
            "{}: {} samples, {} estimate rows, max |live − file| = {worst:e}",
            estimator.name(),
            samples.len(),
            file_out.iter().filter(|b| **b == b'\n').count() - 1
        );
        assert!(worst <= 1e-12, "max difference {worst:e}");
        // Something was identified (the comparison is not of empty columns).
        assert!(live.summary.parameters.iter().filter(|p| p.estimate.is_some()).count() >= 6);
    }
}

#[test]
fn cli_replays_a_live_feed_and_writes_the_summary() {
    let Some(samples) = flight() else { return };
    let out = std::env::temp_dir().join(format!("aeroident-mavlink-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .arg("replay")
        .arg("mavlink:udp:127.0.0.1:0?timeout_s=20")
        .arg("--map")
        .arg(workspace().join("mappings/mavlink-aeroident.toml"))
        .arg("--out")
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    let addr = loop {
        line.clear();
        assert!(stderr.read_line(&mut line).unwrap() > 0, "no `listening on` line");
        if let Some(rest) = line.strip_prefix("listening on ") {
            break rest.split_whitespace().next().unwrap().parse().unwrap();
        }
    };
    let n = 300;
    send(&samples[..n], addr, None);
    let stdout = child.stdout.take().unwrap();
    let lines = std::io::BufReader::new(stdout).lines().count();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    let status = child.wait().unwrap();
    assert!(status.success(), "{line}{rest}");
    // Header + one line per sample estimated (the differentiator's warm-up rows are not).
    assert!(lines > n - 10 && lines <= n + 1, "{lines} lines");
    assert!(
        rest.contains("1 unparseable datagrams") && rest.contains("ended: end-of-stream"),
        "{rest}"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["samples_read"], n);
    let warnings = summary["warnings"].to_string();
    assert!(warnings.contains("holds no valid MAVLink frame"), "{warnings}");
    let _ = std::fs::remove_dir_all(&out);
}
