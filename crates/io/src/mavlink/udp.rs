//! The UDP side of a live feed: a receiving thread (so a slow consumer never makes the kernel
//! drop datagrams) feeding a bounded queue, frame parsing, sequence-number accounting, and the
//! CSV text handed to the reader.
//!
//! # The receive queue
//!
//! The queue holds at most [`QUEUE_DATAGRAMS`] datagrams and [`QUEUE_BYTES`] bytes: about 8 s
//! of a 100 Hz feed of 20 messages per sample (≈ 2 MB of MAVLink 2 datagrams), so a consumer's
//! start-up (building the estimator) and its jitter are absorbed, while a flood (or an
//! estimator slower than the feed) costs bounded memory and a bounded delay instead of growing
//! without limit. When it is full the **oldest** datagram is dropped:
//! a live estimate should follow the aircraft as it is now, and the newest messages supersede
//! the old ones under the zero-order hold, so it is the stale data that goes. Drops are counted
//! ([`LinkStats::dropped`]); after a drop the row builder forgets its held values, so no row
//! mixes values from both sides of the hole (rows resume once every column has arrived again,
//! and the reader reports the hole in time as a gap). Messages lost before the queue (in the
//! kernel when this thread falls behind, or on the link) leave a sequence gap: one of at least
//! as many messages as the mapping reads topics (a whole cycle may be gone), or a sender's
//! count seen to restart, makes the builder forget its held values in the same way; a shorter
//! loss (a radio link's lost packet) is held over, as a lower send rate would be.

use super::{END_OF_STREAM_NAME, MavlinkError, MavlinkUrl, RowBuilder};
use crate::mapping::Mapping;
use mavlink::dialects::ardupilotmega::MavMessage;
use mavlink::error::MessageReadError;
use mavlink::{MavHeader, MavlinkReader, Message};
use std::collections::HashMap;
use std::collections::VecDeque;
use std::hash::{BuildHasher, RandomState};
use std::io::Read;
use std::net::UdpSocket;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Unparseable datagrams reported one by one before only counting.
const REPORTED: u64 = 5;

/// Datagrams the receive queue holds at most (module doc).
pub const QUEUE_DATAGRAMS: usize = 16_384;

/// Bytes of datagrams the receive queue holds at most (module doc): 4 MiB, which bounds the
/// queue when a sender floods it with large datagrams.
pub const QUEUE_BYTES: usize = 4 << 20;

/// Consecutive messages behind a sender's sequence number after which the sender is taken to
/// have restarted its count (and its messages are used again).
const RESYNC_AFTER: u8 = 3;

/// Senders whose sequence number does not advance that [`LinkStats::stuck_senders`] lists one
/// by one (the others are counted together).
pub const NOTED_SENDERS: usize = 8;

/// A sender (system, component) whose sequence number did not advance across messages that
/// differ: one that does not number its messages.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct StuckSender {
    /// MAVLink system id.
    pub system: u32,
    /// MAVLink component id.
    pub component: u8,
    /// Its messages used although they repeated its last sequence number.
    pub messages: u64,
}

/// What a feed received, shared with the caller while the reader owns the feed.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct LinkStats {
    /// Datagrams received (taken from the queue).
    pub datagrams: u64,
    /// MAVLink messages decoded.
    pub messages: u64,
    /// Datagrams holding no valid MAVLink frame (bad CRC, truncated, not MAVLink).
    pub unparseable: u64,
    /// Frames with a valid CRC that did not decode (unknown message id, invalid enum value).
    pub undecodable: u64,
    /// Messages missing from the per-sender (system, component) sequence numbers (mod 256):
    /// lost on the link or in the kernel, not counting the datagrams the queue dropped
    /// ([`LinkStats::dropped`]). Counted when the gap is seen; a skipped message that arrives
    /// later (within 128 numbers) is taken back off and counted in
    /// [`LinkStats::out_of_order`] only. A gap of at least as many messages as the mapping
    /// reads topics makes the row builder forget its held values (every column may have
    /// missed an update), so the clock messages until every column has arrived again make no
    /// row ([`LinkStats::clock_without_row`]); a shorter one is held over.
    pub lost: u64,
    /// Messages repeating their sender's last sequence number and its bytes (message id and
    /// payload): the same message delivered twice, not used again.
    pub duplicates: u64,
    /// Messages repeating their sender's last sequence number with other bytes: a new message
    /// from a sender that does not advance its count (not a datagram received twice), used.
    pub stuck_sequence: u64,
    /// The senders of [`LinkStats::stuck_sequence`], the first [`NOTED_SENDERS`] of them, each
    /// with its count.
    pub stuck_senders: Vec<StuckSender>,
    /// Messages behind their sender's sequence number (late or reordered, e.g. arriving after
    /// their successor): older than what was already used, so not used.
    pub out_of_order: u64,
    /// Datagrams dropped because the receive queue was full (the oldest go first).
    pub dropped: u64,
    /// Rows produced.
    pub rows: u64,
    /// Clock messages received.
    pub clock_messages: u64,
    /// Clock messages that produced no row because a mapped column had not been received.
    pub clock_without_row: u64,
    /// Mapped columns never received (at the end), each with the channel that reads it, e.g.
    /// ``AOA_SSA.AOA (channel `alpha`)``.
    pub never_received: Vec<String>,
    /// Why the feed ended (`""` while running).
    pub end: String,
    /// The first problems, in words.
    pub problems: Vec<String>,
}

impl LinkStats {
    /// Counts a message of sender (`system`, `component`) used although its sequence number
    /// did not advance.
    fn count_stuck(&mut self, system: u32, component: u8) {
        self.stuck_sequence += 1;
        let full = self.stuck_senders.len() >= NOTED_SENDERS;
        let listed =
            self.stuck_senders.iter_mut().find(|s| (s.system, s.component) == (system, component));
        match listed {
            Some(s) => s.messages += 1,
            None if !full => {
                self.stuck_senders.push(StuckSender { system, component, messages: 1 });
            }
            None => {}
        }
    }

    /// The senders that do not number their messages, in words (empty when none).
    fn stuck_notes(&self) -> String {
        let mut notes = String::new();
        for s in &self.stuck_senders {
            notes.push_str(&format!(
                "; system {} component {}: its sequence number did not advance over {} differing messages (the sender does not number its messages); they were used",
                s.system, s.component, s.messages
            ));
        }
        let listed: u64 = self.stuck_senders.iter().map(|s| s.messages).sum();
        if self.stuck_sequence > listed {
            notes.push_str(&format!(
                "; {} more such messages from other senders, used",
                self.stuck_sequence - listed
            ));
        }
        notes
    }

    /// The statistics in one line, for stderr and the summary's warnings.
    pub fn line(&self) -> String {
        format!(
            "mavlink: {} datagrams, {} messages, {} rows; {} unparseable datagrams, {} undecodable frames, {} messages lost (sequence gaps), {} duplicates and {} out-of-order messages not used, {} datagrams dropped (receive queue full at {QUEUE_DATAGRAMS} datagrams or {QUEUE_BYTES} bytes), {} of {} clock messages before every column had arrived{}; ended: {}",
            self.datagrams,
            self.messages,
            self.rows,
            self.unparseable,
            self.undecodable,
            self.lost,
            self.duplicates,
            self.out_of_order,
            self.dropped,
            self.clock_without_row,
            self.clock_messages,
            self.stuck_notes(),
            self.end
        )
    }
}

/// How the receiving thread ended.
enum End {
    Idle,
    Failed(std::io::Error),
}

/// What the consumer takes from the queue.
enum Received {
    /// A datagram, and the datagrams dropped (in total) before it.
    Datagram(Vec<u8>, u64),
    End(End),
    /// Nothing within the wait.
    Nothing,
}

#[derive(Default)]
struct QueueState {
    datagrams: VecDeque<Vec<u8>>,
    bytes: usize,
    dropped: u64,
    end: Option<End>,
}

/// The bounded queue between the receiving thread and the reader (module doc).
#[derive(Default)]
struct Queue {
    state: Mutex<QueueState>,
    ready: Condvar,
}

impl Queue {
    fn lock(&self) -> std::sync::MutexGuard<'_, QueueState> {
        self.state.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Appends a datagram, dropping the oldest while over capacity.
    fn push(&self, datagram: Vec<u8>) {
        let mut s = self.lock();
        s.bytes += datagram.len();
        s.datagrams.push_back(datagram);
        while s.datagrams.len() > QUEUE_DATAGRAMS || s.bytes > QUEUE_BYTES {
            let Some(old) = s.datagrams.pop_front() else { break };
            s.bytes -= old.len();
            s.dropped += 1;
        }
        drop(s);
        self.ready.notify_one();
    }

    /// Marks the end (after the datagrams still queued).
    fn end(&self, end: End) {
        self.lock().end = Some(end);
        self.ready.notify_one();
    }

    /// The next datagram, else the end, waiting up to `wait` for either.
    fn pop(&self, wait: Duration) -> Received {
        let mut s = self.lock();
        if s.datagrams.is_empty() && s.end.is_none() {
            s = self
                .ready
                .wait_timeout(s, wait)
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .0;
        }
        if let Some(d) = s.datagrams.pop_front() {
            s.bytes -= d.len();
            return Received::Datagram(d, s.dropped);
        }
        s.end.take().map_or(Received::Nothing, Received::End)
    }
}

/// A sender's sequence numbers so far, and a fingerprint of its last message used.
#[derive(Debug, Clone, Copy)]
struct Sequence {
    /// The last number used.
    last: u8,
    /// Hash of the id and payload of the last message used: a repeat of `last` is a
    /// duplicate only with these bytes.
    bytes: u64,
    /// Messages behind `last` in a row (a restart after [`RESYNC_AFTER`]).
    behind: u8,
    /// Bit `k` set: number `last - 1 - k` was skipped (counted lost) and has not arrived since.
    gaps: u128,
}

/// What a message's sequence number says.
#[derive(Debug, Clone, Copy, PartialEq)]
enum SeqVerdict {
    /// Next in line, or after `n` missing ones.
    Use {
        missing: u8,
    },
    Duplicate,
    /// The last number used again, with other bytes: a new message from a sender that does
    /// not advance its count.
    NotAdvanced,
    /// The [`RESYNC_AFTER`]th message behind in a row: the sender restarted its count (or more
    /// than 128 messages were lost), used as its new start.
    Restarted,
    /// Behind the last number used; `was_lost` if it is one of the numbers a gap skipped
    /// (counted lost then, late now).
    OutOfOrder {
        was_lost: bool,
    },
}

impl Sequence {
    fn new(first: u8, bytes: u64) -> Self {
        Self { last: first, bytes, behind: 0, gaps: 0 }
    }

    /// Judges sequence number `seq` (mod 256) of a message whose id and payload hash to
    /// `bytes` against the last one used: equal with equal bytes is a duplicate (a datagram
    /// received twice, e.g. over two links), equal with other bytes a new message from a
    /// sender that does not number its messages; up to 128 ahead is new (the numbers between
    /// are missing); further ahead is behind (late). A late number a gap skipped was not lost
    /// after all (two messages swapped on the link); [`RESYNC_AFTER`] other late ones in a row
    /// mean the sender restarted its count.
    fn judge(&mut self, seq: u8, bytes: u64) -> SeqVerdict {
        let delta = seq.wrapping_sub(self.last);
        if delta == 0 {
            if bytes == self.bytes {
                return SeqVerdict::Duplicate;
            }
            self.bytes = bytes;
            self.behind = 0;
            return SeqVerdict::NotAdvanced;
        }
        if delta > 128 {
            let bit = 1u128 << (self.last.wrapping_sub(seq) - 1);
            if self.gaps & bit != 0 {
                self.gaps &= !bit;
                return SeqVerdict::OutOfOrder { was_lost: true };
            }
            self.behind += 1;
            if self.behind < RESYNC_AFTER {
                return SeqVerdict::OutOfOrder { was_lost: false };
            }
            *self = Self::new(seq, bytes);
            return SeqVerdict::Restarted;
        }
        // The old gaps move `delta` further behind; the `delta - 1` numbers skipped now are
        // the nearest behind the new last.
        let skipped = (1u128 << (delta - 1)) - 1;
        self.gaps = self.gaps.checked_shl(u32::from(delta)).unwrap_or(0) | skipped;
        self.last = seq;
        self.bytes = bytes;
        self.behind = 0;
        SeqVerdict::Use { missing: delta - 1 }
    }
}

/// A live MAVLink feed as a [`Read`] of CSV text: the header (the mapped columns) and one row
/// per clock message (module doc of [`crate::mavlink`]). Give it to
/// [`crate::FlightDataReader::new`] with the same mapping.
pub struct MavlinkRows {
    url: MavlinkUrl,
    local: std::net::SocketAddr,
    queue: Arc<Queue>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    builder: RowBuilder,
    buf: Vec<u8>,
    pos: usize,
    stats: Arc<Mutex<LinkStats>>,
    seq: HashMap<(u32, u8), Sequence>,
    /// Keys the hash of [`Sequence::bytes`]: chosen per feed, so a sender cannot aim two
    /// different messages at one hash (8 bytes per sender, where the bytes would be up to 259).
    hasher: RandomState,
    dropped_seen: u64,
    done: bool,
    on_problem: Option<fn(&str)>,
}

/// The receiving thread: datagrams into `queue` until `stop`, an idle `timeout` or a socket
/// error.
fn receive(socket: UdpSocket, queue: &Queue, stop: &AtomicBool, timeout: Duration) {
    let mut last = Instant::now();
    let mut buf = vec![0u8; 65_536];
    while !stop.load(Ordering::Relaxed) {
        match socket.recv(&mut buf) {
            Ok(n) => {
                last = Instant::now();
                queue.push(buf[..n].to_vec());
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                if last.elapsed() >= timeout {
                    return queue.end(End::Idle);
                }
            }
            // An ICMP "port unreachable" from an earlier send is not ours to end on.
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => {}
            Err(e) => return queue.end(End::Failed(e)),
        }
    }
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
        let queue = Arc::new(Queue::default());
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let (queue, stop) = (Arc::clone(&queue), Arc::clone(&stop));
            let timeout = Duration::from_secs_f64(url.timeout_s);
            std::thread::spawn(move || receive(socket, &queue, &stop, timeout))
        };
        let buf = builder.header().into_bytes();
        Ok(Self {
            url: url.clone(),
            local,
            queue,
            stop,
            thread: Some(thread),
            builder,
            buf,
            pos: 0,
            stats: Arc::new(Mutex::new(LinkStats::default())),
            seq: HashMap::new(),
            hasher: RandomState::new(),
            dropped_seen: 0,
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

    /// Whether a message is used, by its sender's sequence number and, when that repeats,
    /// `bytes` (the hash of its id and payload); counted in `stats`. A gap of a whole cycle
    /// before it or a restart of the count makes the builder forget its held values (module
    /// doc).
    fn in_sequence(&mut self, stats: &mut LinkStats, header: &MavHeader, bytes: u64) -> bool {
        let key = (header.system_id, header.component_id);
        let Some(seq) = self.seq.get_mut(&key) else {
            self.seq.insert(key, Sequence::new(header.sequence, bytes));
            return true;
        };
        match seq.judge(header.sequence, bytes) {
            SeqVerdict::Use { missing } => {
                stats.lost += u64::from(missing);
                // A hole that may have held an update of every column: no row across it. A
                // shorter loss leaves the other columns' values current, and the zero-order
                // hold carries the lost one a message longer, as a sender's lower rate would.
                if usize::from(missing) >= self.builder.topics() {
                    self.builder.forget();
                }
                true
            }
            SeqVerdict::Restarted => {
                // What came between is unknown, as after a gap.
                self.builder.forget();
                true
            }
            SeqVerdict::NotAdvanced => {
                stats.count_stuck(header.system_id, header.component_id);
                true
            }
            SeqVerdict::Duplicate => {
                stats.duplicates += 1;
                false
            }
            SeqVerdict::OutOfOrder { was_lost } => {
                if was_lost {
                    stats.lost -= 1;
                }
                stats.out_of_order += 1;
                false
            }
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
        // The reader ends (an error) at the end of the datagram or where no frame follows.
        while let Ok(raw) = reader.read_any_raw_message::<MavMessage>() {
            let (id, payload) = (raw.message_id(), raw.payload());
            let msg = match MavMessage::parse(raw.version(), id, payload) {
                Ok(msg) => msg,
                Err(e) => {
                    undecodable += 1;
                    let (n, e) = (stats.datagrams, MessageReadError::Parse(e));
                    self.problem(&mut stats, format!("datagram {n}: frame does not decode: {e}"));
                    continue;
                }
            };
            decoded += 1;
            let header = MavHeader {
                system_id: raw.system_id(),
                component_id: raw.component_id(),
                sequence: raw.sequence(),
            };
            let bytes = self.hasher.hash_one((id, payload));
            if !self.in_sequence(&mut stats, &header, bytes) {
                continue;
            }
            if let MavMessage::NAMED_VALUE_FLOAT(d) = &msg
                && d.name.to_str() == Ok(END_OF_STREAM_NAME)
            {
                self.done = true;
                stats.end =
                    format!("end-of-stream message NAMED_VALUE_FLOAT `{END_OF_STREAM_NAME}`");
                break;
            }
            if self.builder.push(&msg, &mut self.buf) {
                stats.rows += 1;
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
        stats.clock_messages = self.builder.clock_messages();
        stats.clock_without_row = self.builder.clock_without_row();
    }

    /// Datagrams the queue dropped before the next one: the held values are forgotten, so no
    /// row mixes values from before and after the hole, and so are the senders' sequence
    /// numbers (the hole is counted as dropped, not again as lost).
    fn after_drops(&mut self, dropped: u64) {
        if dropped > self.dropped_seen {
            self.dropped_seen = dropped;
            self.builder.forget();
            self.seq.clear();
            self.stats.lock().unwrap_or_else(std::sync::PoisonError::into_inner).dropped = dropped;
        }
    }

    /// Ends the feed: stops the receiving thread and completes the statistics. Returns the
    /// error that a feed which produced no row ends with (what never arrived, and the link
    /// statistics), `None` when it produced rows.
    fn finish(&mut self, end: Option<String>) -> Option<MavlinkError> {
        self.done = true;
        self.stop.store(true, Ordering::Relaxed);
        let mut stats = self.stats.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(e) = end {
            stats.end = e;
        }
        stats.never_received = self.builder.missing_with_channels();
        (stats.rows == 0 && stats.datagrams > 0).then(|| MavlinkError::NoRows {
            clock: self.builder.clock_topic().to_string(),
            never_received: stats.never_received.clone(),
            link: stats.line(),
        })
    }
}

impl Read for MavlinkRows {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        while self.pos == self.buf.len() && !self.done {
            self.buf.clear();
            self.pos = 0;
            let ended = match self.queue.pop(Duration::from_secs(1)) {
                Received::Datagram(d, dropped) => {
                    self.after_drops(dropped);
                    self.take(&d);
                    if self.done { self.finish(None) } else { None }
                }
                Received::End(End::Idle) => {
                    let received = self.stats.lock().map_or(0, |s| s.datagrams);
                    let no_rows = self.finish(Some(format!(
                        "no datagram for {} s (timeout)",
                        self.url.timeout_s
                    )));
                    if received == 0 {
                        return Err(std::io::Error::other(MavlinkError::NothingReceived {
                            url: self.url.text.clone(),
                            timeout_s: self.url.timeout_s,
                        }));
                    }
                    no_rows
                }
                Received::End(End::Failed(e)) => {
                    self.finish(Some(format!("socket error: {e}")));
                    return Err(e);
                }
                Received::Nothing => None,
            };
            if let Some(e) = ended {
                return Err(std::io::Error::other(e));
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Sequence numbers mod 256: next in line, a gap, a duplicate, a late message, the wrap
    /// from 255 to 0, and a sender restarting its count.
    #[test]
    fn analytic_sequence_numbers_count_gaps_duplicates_and_late_messages() {
        let late = |was_lost| SeqVerdict::OutOfOrder { was_lost };
        let mut s = Sequence::new(10, 0);
        assert_eq!(s.judge(11, 0), SeqVerdict::Use { missing: 0 });
        assert_eq!(s.judge(11, 0), SeqVerdict::Duplicate);
        assert_eq!(s.judge(14, 0), SeqVerdict::Use { missing: 2 });
        // 13 and 12 were counted missing: each arrives late once, then is only behind.
        assert_eq!(s.judge(13, 0), late(true));
        assert_eq!(s.judge(13, 0), late(false));
        assert_eq!(s.judge(15, 0), SeqVerdict::Use { missing: 0 });
        assert_eq!(s.judge(12, 0), late(true));
        assert_eq!(s.judge(11, 0), late(false));
        let mut s = Sequence::new(254, 0);
        assert_eq!(s.judge(255, 0), SeqVerdict::Use { missing: 0 });
        assert_eq!(s.judge(0, 0), SeqVerdict::Use { missing: 0 });
        assert_eq!(s.judge(0, 0), SeqVerdict::Duplicate);
        assert_eq!(s.judge(3, 0), SeqVerdict::Use { missing: 2 });
        // A restart (from 100 back to 0, 156 "ahead" mod 256, so behind): two messages are not
        // used, the third resyncs.
        let mut s = Sequence::new(100, 0);
        assert_eq!(s.judge(0, 0), late(false));
        assert_eq!(s.judge(1, 0), late(false));
        assert_eq!(s.judge(2, 0), SeqVerdict::Restarted);
        assert_eq!(s.judge(3, 0), SeqVerdict::Use { missing: 0 });
    }

    /// A repeated number is a duplicate only with the bytes of the last message used: with
    /// other bytes it is a new message (the sender does not advance its count), used, and the
    /// next repeat is judged against it; a number that moves on is judged as before.
    #[test]
    fn analytic_a_repeated_number_with_other_bytes_is_a_new_message() {
        let (a, b, c) = (1, 2, 3);
        let mut s = Sequence::new(0, a);
        assert_eq!(s.judge(0, b), SeqVerdict::NotAdvanced);
        assert_eq!(s.judge(0, b), SeqVerdict::Duplicate);
        assert_eq!(s.judge(0, a), SeqVerdict::NotAdvanced);
        assert_eq!(s.judge(0, a), SeqVerdict::Duplicate);
        assert_eq!(s.judge(2, c), SeqVerdict::Use { missing: 1 });
        assert_eq!(s.judge(2, c), SeqVerdict::Duplicate);
        assert_eq!(s.judge(2, a), SeqVerdict::NotAdvanced);
        // Behind stays behind whatever its bytes: 1 was counted missing, arrives late.
        assert_eq!(s.judge(1, b), SeqVerdict::OutOfOrder { was_lost: true });
        // The line names each sender that did not advance, with its count.
        let mut stats = LinkStats::default();
        for _ in 0..3 {
            stats.count_stuck(7, 1);
        }
        stats.count_stuck(9, 200);
        let line = stats.line();
        assert_eq!(stats.stuck_sequence, 4);
        assert!(line.contains("; system 7 component 1: its sequence number did not advance over 3 differing messages (the sender does not number its messages); they were used; system 9 component 200: its sequence number did not advance over 1 differing messages"), "{line}");
        // Past the senders listed one by one, the rest are counted together.
        let mut stats = LinkStats::default();
        for sys in 0..NOTED_SENDERS as u32 + 2 {
            stats.count_stuck(sys, 1);
        }
        assert_eq!(stats.stuck_senders.len(), NOTED_SENDERS);
        assert!(stats.line().contains("; 2 more such messages from other senders, used"));
    }

    /// A gap is remembered across the wrap for as long as its number counts as behind (127).
    #[test]
    fn analytic_a_late_message_is_matched_to_its_gap_within_128_numbers() {
        let late = |was_lost| SeqVerdict::OutOfOrder { was_lost };
        let mut s = Sequence::new(250, 0);
        assert_eq!(s.judge(253, 0), SeqVerdict::Use { missing: 2 }); // 251, 252 skipped
        for k in 254..=255 + 124 {
            assert_eq!(s.judge((k % 256) as u8, 0), SeqVerdict::Use { missing: 0 });
        }
        // 252 is 127 behind 123 (mod 256), 251 128 behind: as far ahead, so new.
        assert_eq!((s.last, s.judge(252, 0), s.judge(252, 0)), (123, late(true), late(false)));
        assert_eq!(s.judge(251, 0), SeqVerdict::Use { missing: 127 });
        // A gap of 128 (the most ahead that counts as new).
        let mut s = Sequence::new(0, 0);
        assert_eq!(s.judge(128, 0), SeqVerdict::Use { missing: 127 });
        assert_eq!(s.judge(1, 0), late(true));
        assert_eq!(s.judge(127, 0), late(true));
        assert_eq!(s.judge(1, 0), late(false));
    }

    /// Frame `k` of a sender as in `tests/all/mavlink_link.rs`: V = 100 + k, α = δe = q = k/1000,
    /// the clock `ATTITUDE` at 10 k ms last.
    fn frame(k: u32) -> Vec<MavMessage> {
        use mavlink::dialects::ardupilotmega::{
            AOA_SSA_DATA, ATTITUDE_DATA, NAMED_VALUE_FLOAT_DATA,
        };
        let small = k as f32 / 1000.0;
        let named = |name: &str, value| {
            MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
                time_boot_ms: 0,
                value,
                name: name.into(),
            })
        };
        vec![
            named("a", 100.0 + k as f32),
            MavMessage::AOA_SSA(AOA_SSA_DATA { time_usec: 0, AOA: small, SSA: 0.0 }),
            named("b", small),
            MavMessage::ATTITUDE(ATTITUDE_DATA {
                time_boot_ms: 10 * k,
                pitchspeed: small,
                ..Default::default()
            }),
        ]
    }

    /// The frame of each row of `text` (no header; time ms, V, α, q, δe), each row checked to
    /// hold the values of the frame its time names.
    fn rows_of_one_frame(text: &str) -> Vec<u32> {
        let mut frames = Vec::new();
        for line in text.lines() {
            let v: Vec<f64> = line.split(',').map(|f| f.parse().unwrap()).collect();
            let k = (v[0] / 10.0) as u32;
            let small = f64::from(k as f32 / 1000.0);
            assert_eq!(
                v[1..],
                [100.0 + f64::from(k), small, small, small],
                "`{line}` mixes frames"
            );
            frames.push(k);
        }
        frames
    }

    /// A link reading frames of [`frame`] (four topics: `a`, AOA_SSA, `b`, the clock), its
    /// buffer emptied of the header.
    fn gap_rows() -> MavlinkRows {
        let map = "[time]\ncolumn = \"ATTITUDE.time_boot_ms\"\nunit = \"ms\"\n[channels]\n\
            vt = { column = \"NAMED_VALUE_FLOAT[a].value\", unit = \"m/s\" }\n\
            alpha = { column = \"AOA_SSA.AOA\", unit = \"deg\" }\n\
            q = { column = \"ATTITUDE.pitchspeed\", unit = \"rad/s\" }\n\
            de = { column = \"NAMED_VALUE_FLOAT[b].value\", unit = \"deg\" }\n\
            mass = { value = 1.0, unit = \"kg\" }\nS = { value = 1.0, unit = \"m2\" }\n\
            rho = { value = 1.0, unit = \"kg/m3\" }\n";
        let mapping = Mapping::from_toml_str(map, "m.toml").unwrap();
        let url = MavlinkUrl::parse("mavlink:udp:127.0.0.1:0").unwrap();
        let mut rows = MavlinkRows::open(&url, &mapping, None).unwrap();
        rows.buf.clear();
        rows
    }

    /// Message `msg` as one datagram with sequence number `n mod 256` into `rows`.
    fn deliver(rows: &mut MavlinkRows, n: usize, msg: &MavMessage) {
        let header = MavHeader { system_id: 1, component_id: 1, sequence: n as u8 };
        let mut datagram = Vec::new();
        mavlink::write_versioned_msg(&mut datagram, mavlink::MavlinkVersion::V2, header, msg)
            .unwrap();
        MavlinkRows::take(rows, &datagram);
    }

    /// A loss shorter than a cycle of the mapped topics (one lost packet on a radio link) is
    /// held over: the lost `a` of frame 4711 leaves frame 4710's V in frame 4711's row, the
    /// other columns current, and no row is withheld.
    #[test]
    fn analytic_a_lost_message_shorter_than_a_cycle_is_held_over() {
        let mut rows = gap_rows();
        let sent: Vec<MavMessage> = (4710..=4712).flat_map(frame).collect();
        for n in (0..sent.len()).filter(|&n| n != 4) {
            deliver(&mut rows, n, &sent[n]);
        }
        let text = String::from_utf8(rows.buf.clone()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3, "{text}");
        assert_eq!(rows_of_one_frame(&format!("{}\n{}", lines[0], lines[2])), [4710, 4712]);
        let v: Vec<f64> = lines[1].split(',').map(|f| f.parse().unwrap()).collect();
        let small = f64::from(4711f32 / 1000.0);
        assert_eq!(v, [47110.0, 4810.0, small, small, small], "{text}");
        assert_eq!(rows.stats.lock().unwrap().lost, 1);
    }

    /// At the edge of the rule, a cycle of the four mapped topics (`a`, α, `b`, the clock):
    /// three lost (frame 4711's `a`, α and `b`) are held over, so frame 4711's clock makes a
    /// row of frame 4710's values and its own q; four lost (frame 4711's α, `b` and clock and
    /// frame 4712's `a`) forget, so frame 4712's clock makes no row (held over, it would carry
    /// frame 4711's `a`) and the next row is frame 4713's own.
    #[test]
    fn analytic_a_gap_of_a_whole_cycle_forgets_and_one_short_of_it_holds() {
        let sent: Vec<MavMessage> = (4710..=4713).flat_map(frame).collect();
        let run = |lost: std::ops::Range<usize>| {
            let mut rows = gap_rows();
            for n in (0..sent.len()).filter(|n| !lost.contains(n)) {
                deliver(&mut rows, n, &sent[n]);
            }
            let text = String::from_utf8(rows.buf.clone()).unwrap();
            (text, rows.stats.lock().unwrap().clone())
        };
        let (text, s) = run(4..7);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!((lines.len(), s.lost, s.clock_without_row), (4, 3, 0), "{text}");
        let v: Vec<f64> = lines[1].split(',').map(|f| f.parse().unwrap()).collect();
        let (held, q) = (f64::from(4710f32 / 1000.0), f64::from(4711f32 / 1000.0));
        assert_eq!(v, [47110.0, 4810.0, held, q, held], "{text}");
        let (text, s) = run(5..9);
        assert_eq!(rows_of_one_frame(&text), [4710, 4713], "{text}");
        assert_eq!((s.lost, s.clock_without_row), (4, 1), "{s:?}");
    }

    /// Messages lost before the queue (in the kernel under load, or on the link) leave a
    /// sequence gap, not a queue drop. Frames 4710 and 4711 arrive whole, then the 15 messages
    /// from frame 4712's `a` to frame 4715's `b` are lost: frame 4715's clock must not make a
    /// row of frame 4711's held values under frame 4715's time (what the flood test once saw
    /// under load). Then 200 lost, which the 8-bit numbers see as the sender restarting its
    /// count (two messages late, the third used): again no mixed row. Rows resume with the
    /// next whole frame.
    #[test]
    fn analytic_a_sequence_gap_makes_no_row_mixing_frames() {
        let mut rows = gap_rows();
        // Message n of frames 4710… has sequence number n mod 256; one message per datagram.
        let sent: Vec<MavMessage> = (4710..=4780).flat_map(frame).collect();
        let mut deliver_range = |range: std::ops::Range<usize>| {
            for n in range {
                deliver(&mut rows, n, &sent[n]);
            }
        };
        // 4710, 4711; lost 8..23; 4715's clock, 4716, 4717; lost 32..232; 4768 (its `a` and
        // α late), 4769.
        deliver_range(0..8);
        deliver_range(23..32);
        deliver_range(232..240);
        let text = String::from_utf8(rows.buf.clone()).unwrap();
        let s = rows.stats.lock().unwrap().clone();
        assert_eq!(rows_of_one_frame(&text), [4710, 4711, 4716, 4717, 4769], "{text}");
        assert_eq!((s.lost, s.out_of_order, s.clock_without_row), (15, 2, 2), "{s:?}");
    }

    /// The queue keeps the newest [`QUEUE_DATAGRAMS`], counting the oldest it drops, and
    /// hands out the end only after the datagrams.
    #[test]
    fn analytic_queue_drops_the_oldest_and_counts_them() {
        let q = Queue::default();
        let n = QUEUE_DATAGRAMS + 10;
        for k in 0..n {
            q.push((k as u32).to_le_bytes().to_vec());
        }
        q.end(End::Idle);
        let Received::Datagram(first, dropped) = q.pop(Duration::ZERO) else { panic!() };
        assert_eq!(dropped, 10);
        assert_eq!(u32::from_le_bytes(first.try_into().unwrap()), 10);
        let mut count = 1;
        while let Received::Datagram(..) = q.pop(Duration::ZERO) {
            count += 1;
        }
        assert_eq!(count, QUEUE_DATAGRAMS);
        assert!(matches!(q.pop(Duration::ZERO), Received::Nothing));
        // Bytes bound too: 100 datagrams of 60 kB are over 4 MiB.
        let q = Queue::default();
        for _ in 0..100 {
            q.push(vec![0; 60_000]);
        }
        let Received::Datagram(_, dropped) = q.pop(Duration::ZERO) else { panic!() };
        assert_eq!(dropped, 100 - QUEUE_BYTES as u64 / 60_000);
    }
}
