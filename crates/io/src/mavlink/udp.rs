//! The UDP side of a live feed: a receiving thread (so a slow consumer never makes the kernel
//! drop datagrams), frame parsing, sequence-gap counting, and the CSV text handed to the reader.

use super::{END_OF_STREAM_NAME, MavlinkError, MavlinkUrl, RowBuilder};
use crate::mapping::Mapping;
use mavlink::MavlinkReader;
use mavlink::dialects::ardupilotmega::MavMessage;
use mavlink::error::MessageReadError;
use std::collections::HashMap;
use std::io::Read;
use std::net::UdpSocket;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Unparseable datagrams reported one by one before only counting.
const REPORTED: u64 = 5;

/// What a feed received, shared with the caller while the reader owns the feed.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct LinkStats {
    /// Datagrams received.
    pub datagrams: u64,
    /// MAVLink messages decoded.
    pub messages: u64,
    /// Datagrams holding no valid MAVLink frame (bad CRC, truncated, not MAVLink).
    pub unparseable: u64,
    /// Frames with a valid CRC that did not decode (unknown message id, invalid enum value).
    pub undecodable: u64,
    /// Messages missing from the per-sender (system, component) sequence numbers.
    pub lost: u64,
    /// Rows produced.
    pub rows: u64,
    /// Clock messages that produced no row because a mapped column had not been received.
    pub clock_without_row: u64,
    /// Mapped columns never received (at the end).
    pub never_received: Vec<String>,
    /// Why the feed ended (`""` while running).
    pub end: String,
    /// The first problems, in words.
    pub problems: Vec<String>,
}

enum Received {
    Datagram(Vec<u8>),
    Idle,
    Failed(std::io::Error),
}

/// A live MAVLink feed as a [`Read`] of CSV text: the header (the mapped columns) and one row
/// per clock message (module doc of [`crate::mavlink`]). Give it to
/// [`crate::FlightDataReader::new`] with the same mapping.
pub struct MavlinkRows {
    url: MavlinkUrl,
    local: std::net::SocketAddr,
    rx: Receiver<Received>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    builder: RowBuilder,
    buf: Vec<u8>,
    pos: usize,
    stats: Arc<Mutex<LinkStats>>,
    seq: HashMap<(u32, u8), u8>,
    done: bool,
    on_problem: Option<fn(&str)>,
}

impl MavlinkRows {
    /// Binds the socket (returns once it listens) and starts receiving. `on_problem` is called
    /// with each of the first few problems (unparseable datagrams) as they occur.
    ///
    /// # Errors
    /// [`MavlinkError::Column`] for a mapped column that is not a numeric message field,
    /// [`MavlinkError::Io`] if the socket cannot be bound.
    pub fn open(
        url: &MavlinkUrl,
        mapping: &Mapping,
        on_problem: Option<fn(&str)>,
    ) -> Result<Self, MavlinkError> {
        let builder = RowBuilder::new(mapping)?;
        let io = |source| MavlinkError::Io { url: url.text.clone(), source };
        let socket = UdpSocket::bind(url.addr).map_err(io)?;
        let local = socket.local_addr().map_err(io)?;
        socket.set_read_timeout(Some(Duration::from_millis(50))).map_err(io)?;
        let (tx, rx) = channel();
        let stop = Arc::new(AtomicBool::new(false));
        let stop_thread = Arc::clone(&stop);
        let timeout = Duration::from_secs_f64(url.timeout_s);
        let thread = std::thread::spawn(move || {
            let mut last = Instant::now();
            let mut buf = vec![0u8; 65_536];
            while !stop_thread.load(Ordering::Relaxed) {
                let item = match socket.recv(&mut buf) {
                    Ok(n) => {
                        last = Instant::now();
                        Received::Datagram(buf[..n].to_vec())
                    }
                    Err(e)
                        if matches!(
                            e.kind(),
                            std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                        ) =>
                    {
                        if last.elapsed() < timeout {
                            continue;
                        }
                        Received::Idle
                    }
                    // An ICMP "port unreachable" from an earlier send is not ours to end on.
                    Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => continue,
                    Err(e) => Received::Failed(e),
                };
                let end = !matches!(item, Received::Datagram(_));
                if tx.send(item).is_err() || end {
                    break;
                }
            }
        });
        let buf = builder.header().into_bytes();
        Ok(Self {
            url: url.clone(),
            local,
            rx,
            stop,
            thread: Some(thread),
            builder,
            buf,
            pos: 0,
            stats: Arc::new(Mutex::new(LinkStats::default())),
            seq: HashMap::new(),
            done: false,
            on_problem,
        })
    }

    /// The address the feed listens on (the bound port when the source gave port 0).
    pub fn local_addr(&self) -> std::net::SocketAddr {
        self.local
    }

    /// The column names of the CSV text (the header), time first.
    pub fn header(&self) -> String {
        self.builder.header()
    }

    /// A handle on the statistics, readable while and after the reader consumes the feed.
    pub fn stats(&self) -> Arc<Mutex<LinkStats>> {
        Arc::clone(&self.stats)
    }

    fn problem(&self, stats: &mut LinkStats, text: String) {
        if (stats.problems.len() as u64) < REPORTED {
            if let Some(f) = self.on_problem {
                f(&format!("{}: {text}", self.url.text));
            }
            stats.problems.push(text);
        }
    }

    /// Decodes one datagram, feeding its messages to the row builder.
    fn take(&mut self, bytes: &[u8]) {
        let stats = Arc::clone(&self.stats);
        let mut stats = stats.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        stats.datagrams += 1;
        let mut reader = MavlinkReader::new(bytes);
        let mut decoded = 0u64;
        let mut undecodable = 0u64;
        loop {
            match reader.read_any_message::<MavMessage>() {
                Ok((header, msg)) => {
                    decoded += 1;
                    let key = (header.system_id, header.component_id);
                    if let Some(prev) = self.seq.insert(key, header.sequence) {
                        stats.lost += u64::from(header.sequence.wrapping_sub(prev).wrapping_sub(1));
                    }
                    if let MavMessage::NAMED_VALUE_FLOAT(d) = &msg
                        && d.name.to_str() == Ok(END_OF_STREAM_NAME)
                    {
                        self.done = true;
                        stats.end = format!(
                            "end-of-stream message NAMED_VALUE_FLOAT `{END_OF_STREAM_NAME}`"
                        );
                        break;
                    }
                    if self.builder.push(&msg, &mut self.buf) {
                        stats.rows += 1;
                    }
                }
                Err(MessageReadError::Parse(e)) => {
                    undecodable += 1;
                    let n = stats.datagrams;
                    self.problem(&mut stats, format!("datagram {n}: frame does not decode: {e}"));
                }
                Err(_) => break,
            }
        }
        stats.messages += decoded;
        stats.undecodable += undecodable;
        if decoded == 0 && undecodable == 0 {
            stats.unparseable += 1;
            let head: Vec<String> = bytes.iter().take(12).map(|b| format!("{b:02x}")).collect();
            let n = stats.datagrams;
            let text = format!(
                "datagram {n} ({} bytes, starting {}) holds no valid MAVLink frame; skipped",
                bytes.len(),
                head.join(" ")
            );
            self.problem(&mut stats, text);
        }
        stats.clock_without_row = self.builder.clock_without_row();
    }

    fn finish(&mut self, end: Option<String>) {
        self.done = true;
        self.stop.store(true, Ordering::Relaxed);
        let mut stats = self.stats.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(e) = end {
            stats.end = e;
        }
        stats.never_received = self.builder.missing().iter().map(|s| (*s).to_string()).collect();
    }
}

impl Read for MavlinkRows {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        while self.pos == self.buf.len() && !self.done {
            self.buf.clear();
            self.pos = 0;
            match self.rx.recv_timeout(Duration::from_secs(1)) {
                Ok(Received::Datagram(d)) => {
                    self.take(&d);
                    if self.done {
                        self.finish(None);
                    }
                }
                Ok(Received::Idle) => {
                    let received = self.stats.lock().map_or(0, |s| s.datagrams);
                    self.finish(Some(format!(
                        "no datagram for {} s (timeout)",
                        self.url.timeout_s
                    )));
                    if received == 0 {
                        return Err(std::io::Error::other(MavlinkError::NothingReceived {
                            url: self.url.text.clone(),
                            timeout_s: self.url.timeout_s,
                        }));
                    }
                }
                Ok(Received::Failed(e)) => {
                    self.finish(Some(format!("socket error: {e}")));
                    return Err(e);
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => {
                    self.finish(Some("receiver stopped".into()));
                }
            }
        }
        let n = out.len().min(self.buf.len() - self.pos);
        out[..n].copy_from_slice(&self.buf[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

impl Drop for MavlinkRows {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
