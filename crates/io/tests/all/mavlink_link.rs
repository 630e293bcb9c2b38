//! A live MAVLink feed over UDP loopback under link trouble: a feed where only the clock
//! arrives ends with an error naming what never arrived and the link statistics; duplicated
//! datagrams are counted as duplicates (not as 255 lost each) and not used twice; a message
//! arriving after its successor is late, not lost; a flood into
//! a paused consumer is bounded by the receive queue, whose drops are counted, and no row mixes
//! values from both sides of the hole.

use aeroident_io::mavlink::feed::end_of_stream;
use aeroident_io::mavlink::{LinkStats, MavlinkRows, MavlinkUrl, QUEUE_DATAGRAMS};
use aeroident_io::{FlightDataReader, Mapping, RecordEvent};
use mavlink::dialects::ardupilotmega::{
    AOA_SSA_DATA, ATTITUDE_DATA, MavMessage, NAMED_VALUE_FLOAT_DATA,
};
use mavlink::{MavHeader, MavlinkVersion};
use std::io::Read;
use std::net::{SocketAddr, UdpSocket};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The clock `ATTITUDE` (time in ms, q), V and δe as named values, α from `AOA_SSA`.
const MAP: &str = "[time]\ncolumn = \"ATTITUDE.time_boot_ms\"\nunit = \"ms\"\n[channels]\n\
    vt = { column = \"NAMED_VALUE_FLOAT[a].value\", unit = \"m/s\" }\n\
    alpha = { column = \"AOA_SSA.AOA\", unit = \"deg\" }\n\
    q = { column = \"ATTITUDE.pitchspeed\", unit = \"rad/s\" }\n\
    de = { column = \"NAMED_VALUE_FLOAT[b].value\", unit = \"deg\" }\n\
    mass = { value = 1.0, unit = \"kg\" }\nS = { value = 1.0, unit = \"m2\" }\n\
    rho = { value = 1.0, unit = \"kg/m3\" }\n";

fn mapping() -> Mapping {
    Mapping::from_toml_str(MAP, "link.toml").unwrap()
}

/// MAVLink 2 datagrams with sequence numbers of our choosing.
struct Link {
    socket: UdpSocket,
    to: SocketAddr,
    seq: u8,
    sent: u64,
}

impl Link {
    fn new(to: SocketAddr) -> Self {
        Self { socket: UdpSocket::bind("127.0.0.1:0").unwrap(), to, seq: 0, sent: 0 }
    }

    /// Sends `msg` `times` times with one sequence number (then steps it).
    fn send(&mut self, msg: &MavMessage, times: usize) {
        let header = MavHeader { system_id: 1, component_id: 1, sequence: self.seq };
        let mut buf = Vec::new();
        mavlink::write_versioned_msg(&mut buf, MavlinkVersion::V2, header, msg).unwrap();
        for _ in 0..times {
            self.socket.send_to(&buf, self.to).unwrap();
            self.sent += 1;
        }
        self.seq = self.seq.wrapping_add(1);
    }

    /// Sends `first` and `second` under the next two sequence numbers, `second` first: a pair
    /// swapped on the link.
    fn send_swapped(&mut self, first: &MavMessage, second: &MavMessage) {
        let (s0, s1) = (self.seq, self.seq.wrapping_add(1));
        for (msg, sequence) in [(second, s1), (first, s0)] {
            let header = MavHeader { system_id: 1, component_id: 1, sequence };
            let mut buf = Vec::new();
            mavlink::write_versioned_msg(&mut buf, MavlinkVersion::V2, header, msg).unwrap();
            self.socket.send_to(&buf, self.to).unwrap();
            self.sent += 1;
        }
        self.seq = self.seq.wrapping_add(2);
    }
}

fn named(name: &str, value: f32) -> MavMessage {
    MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
        time_boot_ms: 0,
        value,
        name: name.into(),
    })
}

fn clock(t_ms: u32, q: f32) -> MavMessage {
    MavMessage::ATTITUDE(ATTITUDE_DATA { time_boot_ms: t_ms, pitchspeed: q, ..Default::default() })
}

/// Frame `k`: every value follows `k` (V = 100 + k m/s, α = k/1000 deg, δe = k/1000 deg,
/// q = k/1000 rad/s), the clock at `10 k` ms last, so a row that mixes frames is visible.
fn frame(k: u32) -> Vec<MavMessage> {
    let small = k as f32 / 1000.0;
    vec![
        named("a", 100.0 + k as f32),
        MavMessage::AOA_SSA(AOA_SSA_DATA { time_usec: 0, AOA: small, SSA: 0.0 }),
        named("b", small),
        clock(10 * k, small),
    ]
}

/// Waits until the feed has taken `n` datagrams (flow control: loopback buffers hold only a
/// few hundred, and the test wants none lost in the kernel).
fn wait_taken(stats: &Mutex<LinkStats>, n: u64) {
    let deadline = Instant::now() + Duration::from_secs(20);
    while stats.lock().unwrap().datagrams + 100 < n && Instant::now() < deadline {
        std::thread::sleep(Duration::from_micros(200));
    }
}

fn open() -> (MavlinkRows, SocketAddr, Arc<Mutex<LinkStats>>, String) {
    let url = MavlinkUrl::parse("mavlink:udp:127.0.0.1:0?timeout_s=20").unwrap();
    let rows = MavlinkRows::open(&url, &mapping(), None).unwrap();
    let (to, stats) = (rows.local_addr(), rows.stats());
    (rows, to, stats, url.text)
}

/// Only the clock arrives: the reader's error names the feed, the columns never received with
/// their channels, and the link statistics (20 clock messages, none with a row).
#[test]
fn errors_feed_with_only_the_clock_names_what_never_arrived_and_the_link() {
    let (rows, to, stats, url) = open();
    let m = mapping();
    let reader = std::thread::spawn(move || {
        FlightDataReader::new(rows, &url, &m).unwrap().collect::<Vec<_>>()
    });
    let mut link = Link::new(to);
    for k in 1..=20 {
        link.send(&clock(10 * k, 0.0), 1);
    }
    link.send(&end_of_stream(), 1);
    let events = reader.join().unwrap();
    assert_eq!(events.len(), 1, "{events:?}");
    let e = events[0].as_ref().unwrap_err().to_string();
    assert!(
        e.starts_with("mavlink:udp:127.0.0.1:0?timeout_s=20: the feed ended without a row"),
        "{e}"
    );
    assert!(
        e.contains(
            "never received: NAMED_VALUE_FLOAT[a].value (channel `vt`), AOA_SSA.AOA (channel `alpha`), NAMED_VALUE_FLOAT[b].value (channel `de`);"
        ),
        "{e}"
    );
    assert!(e.contains("mavlink: 21 datagrams, 21 messages, 0 rows;"), "{e}");
    assert!(e.contains("20 of 20 clock messages before every column had arrived"), "{e}");
    assert!(e.contains("ended: end-of-stream"), "{e}");
    assert_eq!(stats.lock().unwrap().never_received.len(), 3);
}

/// Every datagram sent twice (same sequence number): 200 duplicates, none lost, each message
/// used once, so 50 rows and 50 samples with no repeated time.
#[test]
fn analytic_duplicated_datagrams_are_duplicates_not_losses() {
    let (rows, to, stats, url) = open();
    let m = mapping();
    let reader = std::thread::spawn(move || {
        FlightDataReader::new(rows, &url, &m).unwrap().map(|e| e.unwrap()).collect::<Vec<_>>()
    });
    let mut link = Link::new(to);
    for k in 1..=50 {
        for msg in frame(k) {
            link.send(&msg, 2);
        }
        wait_taken(&stats, link.sent);
    }
    link.send(&end_of_stream(), 1);
    let events = reader.join().unwrap();
    let s = stats.lock().unwrap().clone();
    assert_eq!(
        (s.datagrams, s.messages, s.duplicates, s.lost, s.out_of_order),
        (401, 401, 200, 0, 0)
    );
    assert_eq!(s.rows, 50);
    assert!(s.line().contains("0 messages lost (sequence gaps), 200 duplicates"), "{}", s.line());
    assert_eq!(events.len(), 50, "every event a sample: {events:?}");
    assert!(events.iter().all(|e| matches!(e, RecordEvent::Sample { .. })), "{events:?}");
}

/// A sender that numbers every message 0 (it does not keep a sequence count) and sends each
/// clock message twice: consecutive messages differ, so only the repeated clock messages (same
/// number, same bytes) are duplicates; the other 80 are used, counted as not advancing the
/// sequence number, and the link line says so. 20 frames, 20 rows.
#[test]
fn analytic_sender_whose_sequence_number_never_advances_is_used_and_noted() {
    let (rows, to, stats, url) = open();
    let m = mapping();
    let reader = std::thread::spawn(move || {
        FlightDataReader::new(rows, &url, &m).unwrap().map(|e| e.unwrap()).collect::<Vec<_>>()
    });
    let mut link = Link::new(to);
    for k in 1..=20 {
        let f = frame(k);
        for msg in &f[..3] {
            link.seq = 0;
            link.send(msg, 1);
        }
        link.seq = 0;
        link.send(&f[3], 2);
        wait_taken(&stats, link.sent);
    }
    link.seq = 0;
    link.send(&end_of_stream(), 1);
    let events = reader.join().unwrap();
    let s = stats.lock().unwrap().clone();
    assert_eq!(
        (s.datagrams, s.messages, s.duplicates, s.lost, s.out_of_order, s.rows),
        (101, 101, 20, 0, 0, 20),
        "{s:?}"
    );
    assert_eq!(s.stuck_sequence, 80, "{s:?}");
    assert!(
        s.line().contains(
            "system 1 component 1: its sequence number did not advance over 80 differing messages (the sender does not number its messages); they were used"
        ),
        "{}",
        s.line()
    );
    let times: Vec<f64> = events
        .iter()
        .map(|e| match e {
            RecordEvent::Sample { sample, .. } => sample.t_s,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(times.len(), 20, "{times:?}");
    for (k, t) in (1..=20).zip(&times) {
        assert!((t - f64::from(k) / 100.0).abs() < 1e-12, "frame {k}: {t} s");
    }
}

/// 30 frames, each led by an unmapped value sent after its successor (sequence n + 1, then n):
/// 30 late messages, none lost, and every frame's row with its own values (the late ones are
/// not used, and mapped nothing).
#[test]
fn analytic_swapped_neighbours_are_late_not_lost() {
    let (mut rows, to, stats, _) = open();
    let reader = std::thread::spawn(move || {
        let mut text = String::new();
        rows.read_to_string(&mut text).unwrap();
        text
    });
    let mut link = Link::new(to);
    for k in 1..=30 {
        let f = frame(k);
        link.send_swapped(&named("c", -1.0), &f[0]);
        for msg in &f[1..] {
            link.send(msg, 1);
        }
        wait_taken(&stats, link.sent);
    }
    link.send(&end_of_stream(), 1);
    let text = reader.join().unwrap();
    let s = stats.lock().unwrap().clone();
    assert_eq!(
        (s.datagrams, s.messages, s.duplicates, s.lost, s.out_of_order),
        (151, 151, 0, 0, 30),
        "{s:?}"
    );
    assert!(s.line().contains("0 messages lost (sequence gaps), 0 duplicates and 30 out-of-order"));
    let parsed = parse_rows(&text);
    let want: Vec<[f64; 5]> = (1..=30)
        .map(|k| {
            let small = f64::from(k as f32 / 1000.0);
            [10.0 * f64::from(k), 100.0 + f64::from(k), small, small, small]
        })
        .collect();
    assert_eq!(parsed, want);
}

/// The CSV rows of the feed: (time ms, V, α, q, δe).
fn parse_rows(text: &str) -> Vec<[f64; 5]> {
    text.lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|f| f.parse().unwrap()).collect();
            [v[0], v[1], v[2], v[3], v[4]]
        })
        .collect()
}

/// Reads `rows` until `n` rows have arrived.
fn read_rows(rows: &mut MavlinkRows, text: &mut String, n: usize) {
    let mut buf = [0u8; 4096];
    while text.lines().count() < n + 1 {
        let k = rows.read(&mut buf).unwrap();
        assert!(k > 0, "feed ended early");
        text.push_str(std::str::from_utf8(&buf[..k]).unwrap());
    }
}

/// A consumer that stops while 24,000 datagrams arrive: the queue keeps at most
/// `QUEUE_DATAGRAMS`, the oldest are dropped and counted, and every row holds one frame's
/// values (none mixes values from before the hole with the clock after it, nor across a
/// whole cycle of messages a busy machine's kernel dropped before the queue; a shorter loss
/// is held over for one row).
#[test]
fn analytic_flood_into_a_paused_consumer_is_bounded_and_counted() {
    let (mut rows, to, stats, _) = open();
    let mut link = Link::new(to);
    let mut text = String::new();
    for k in 1..=10 {
        for msg in frame(k) {
            link.send(&msg, 1);
        }
    }
    read_rows(&mut rows, &mut text, 10);
    let before = stats.lock().unwrap().datagrams;
    // The consumer pauses: 6,000 frames (24,000 datagrams), paced so the receiving thread (not
    // the kernel) is what has to hold them.
    for k in 11..=6010 {
        for msg in frame(k) {
            link.send(&msg, 1);
        }
        if k % 20 == 0 {
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    // The end, sent three times: the first to arrive ends the feed, so the kernel dropping one
    // (a busy machine) does not leave it to end on the idle timeout.
    for _ in 0..3 {
        link.send(&end_of_stream(), 1);
        std::thread::sleep(Duration::from_millis(100));
    }
    let mut buf = [0u8; 4096];
    loop {
        let k = rows.read(&mut buf).unwrap();
        if k == 0 {
            break;
        }
        text.push_str(std::str::from_utf8(&buf[..k]).unwrap());
    }
    let s = stats.lock().unwrap().clone();
    let after = s.datagrams - before;
    assert!(after as usize <= QUEUE_DATAGRAMS, "{after} datagrams taken after the pause: {s:?}");
    assert!(s.dropped > 0 && s.datagrams + s.dropped <= link.sent, "{s:?}");
    assert!(s.end.contains("end-of-stream"), "{s:?}");
    assert!(s.line().contains(&format!("{} datagrams dropped (receive queue full", s.dropped)));
    let parsed = parse_rows(&text);
    // Each hole the kernel made (a gap, counted lost, or a burst seen as a restart, two
    // counted late) costs its two partial frames' rows; with none, every frame kept has a row.
    let holes = (s.lost + s.out_of_order) as usize;
    assert!(
        parsed.len() + 2 * holes > 10 + QUEUE_DATAGRAMS / 4 - 3,
        "{} rows: {s:?}",
        parsed.len()
    );
    // A loss shorter than a cycle of the four topics is held over (the lost column keeps its
    // previous frame's value for one row): at most one row per message lost before the queue
    // holds another frame's value; with none lost, no row does.
    let mixed: Vec<&[f64; 5]> = parsed
        .iter()
        .filter(|r| {
            let k = r[0] / 10.0;
            let small = f64::from(k as f32 / 1000.0);
            r[1] != 100.0 + k || [r[2], r[3], r[4]] != [small; 3]
        })
        .collect();
    assert!(mixed.len() as u64 <= s.lost, "rows mixing frames: {mixed:?}; {s:?}");
    // The rows jump over the hole: frames 11… up to the first kept are missing.
    assert!(parsed.windows(2).all(|w| w[1][0] > w[0][0]));
    assert!(parsed[10][0] > 110.0, "{:?}", parsed[10]);
}
