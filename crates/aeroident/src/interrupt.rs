//! Graceful shutdown of live and long runs on SIGINT (Ctrl-C), SIGTERM and SIGHUP.
//!
//! A live feed never ends by itself, so a signal is its normal end: the first signal only sets a
//! flag ([`Interrupt::requested`]) that the run polls between samples; the run then finishes the
//! sample in hand and writes its results marked `interrupted`, and the process exits with
//! `128 + signal` ([`Interrupted::exit_code`], the shell's convention for "ended by a signal").
//! A batch fit of stdin ends its read on the flag and fits the rows read; a signal during the
//! fit itself (of a file or of stdin read whole) stops it at its next iteration, a bootstrap
//! before its next replica, and the last iterate is written; a Monte Carlo campaign starts no
//! further run and writes its statistics over the runs done.
//!
//! **A second signal** weighs a fast stop against a valid output directory:
//! - *before the results are written* (the run still stopping, a batch fit still running) it
//!   asks for a stop at once ([`Interrupt::stop_now`]): the command skips what is left (the
//!   report and figures; an unfinished batch fit) and writes `summary.json` alone, status
//!   `interrupted`, saying so, then exits `128 + signal`. Whoever presses Ctrl-C twice wants the
//!   prompt stop, and still gets a summary telling what the run had done;
//! - *while the results are written* ([`Interrupt::begin_writing`] on) it is noted on stderr
//!   and ignored: writing them takes seconds at most, and a run killed halfway would leave a
//!   report without its figures or a hidden temporary file where a result should be. SIGKILL
//!   still ends the process at once.
//!
//! The signals are received by a thread of its own (`signal-hook`'s iterator), so that these
//! notes are printed the moment a signal arrives, outside the signal handler. Signals arriving
//! closer together than that thread wakes count as one. The handlers are installed only around
//! the runs that poll the flag, so every other command keeps the default behaviour of the
//! signals; dropping [`Interrupt`] stops the thread, after which `signal-hook` leaves its own
//! handler in place and a further signal is ignored (the command is returning by then).
//!
//! The signal handlers restart interrupted system calls, so a run blocked reading stdin would
//! not see the flag until a line arrives: [`InterruptibleStdin`] reads stdin on a thread of its
//! own and ends the record at a line boundary once the flag is set.

use std::io::{self, BufRead, Read};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU8, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, sync_channel};
use std::time::Duration;

#[cfg(unix)]
// SIGHUP too: closing the terminal a live feed runs in is as ordinary an end as Ctrl-C.
const SIGNALS: [i32; 3] =
    [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM, signal_hook::consts::SIGHUP];
#[cfg(not(unix))]
const SIGNALS: [i32; 1] = [signal_hook::consts::SIGINT];

/// The run has not begun writing its results; no second signal yet.
const RUNNING: u8 = 0;
/// A second signal arrived before the results were written: stop at once, summary only.
const STOP_NOW: u8 = 1;
/// The results are being written: further signals are ignored.
const WRITING: u8 = 2;

/// What the signal thread shares with the run.
#[derive(Debug, Default)]
struct Shared {
    /// The first signal's number (0: none yet); set before [`Interrupt::requested`].
    signal: AtomicUsize,
    /// [`RUNNING`], [`STOP_NOW`] or [`WRITING`].
    phase: AtomicU8,
}

/// The installed handlers and what they received (module doc). Dropping it stops listening.
#[derive(Debug)]
pub struct Interrupt {
    requested: Arc<AtomicBool>,
    shared: Arc<Shared>,
    handle: signal_hook::iterator::Handle,
    listener: Option<std::thread::JoinHandle<()>>,
}

impl Interrupt {
    /// Installs the handlers of SIGINT, SIGTERM and SIGHUP and the thread that answers them
    /// (module doc).
    ///
    /// # Errors
    /// The operating system refused a handler or the thread.
    pub fn install() -> io::Result<Self> {
        let mut signals = signal_hook::iterator::Signals::new(SIGNALS)?;
        let handle = signals.handle();
        let requested = Arc::new(AtomicBool::new(false));
        let shared = Arc::new(Shared::default());
        let (r, s) = (Arc::clone(&requested), Arc::clone(&shared));
        let listener = std::thread::Builder::new().name("signals".into()).spawn(move || {
            for sig in signals.forever() {
                on_signal(sig, &r, &s);
            }
        })?;
        Ok(Self { requested, shared, handle, listener: Some(listener) })
    }

    /// Whether a signal has arrived.
    pub fn requested(&self) -> bool {
        self.requested.load(Ordering::SeqCst)
    }

    /// The flag the first signal sets (for readers that poll it, [`InterruptibleStdin`]).
    pub fn flag(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.requested)
    }

    /// Whether a second signal asked to stop at once, before the results were written (module
    /// doc): the run should write `summary.json` alone and end.
    pub fn stop_now(&self) -> bool {
        self.shared.phase.load(Ordering::SeqCst) == STOP_NOW
    }

    /// Marks the start of the results' writing, from which further signals are ignored; returns
    /// whether a second signal came first ([`Interrupt::stop_now`]), in which case only
    /// `summary.json` is to be written.
    pub fn begin_writing(&self) -> bool {
        self.shared.phase.swap(WRITING, Ordering::SeqCst) == STOP_NOW
    }

    /// The name of the first signal received (`SIGINT` …), if any.
    pub fn signal_name(&self) -> Option<String> {
        self.requested().then(|| signal_name(self.shared.signal.load(Ordering::SeqCst) as i32))
    }

    /// Runs `work`, a step over a whole record with no safe point to stop at (replay's
    /// `--compat auto`, `--model auto`; `compat`; `freqresp`), on a thread of its own while
    /// answering the signals: a signal abandons it at once, `None` (the thread ends with the
    /// process, which writes its summary and exits).
    ///
    /// # Errors
    /// The thread could not start or ended without a result (a panic).
    pub fn watched<T: Send + 'static>(
        &self,
        work: impl FnOnce() -> T + Send + 'static,
    ) -> anyhow::Result<Option<T>> {
        if self.requested() {
            return Ok(None);
        }
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::Builder::new()
            .name("whole-record".into())
            .stack_size(aeroident_pipelines::WORKER_STACK_BYTES)
            .spawn(move || {
                let _ = tx.send(work());
            })
            .map_err(|e| anyhow::anyhow!("starting a thread: {e}"))?;
        loop {
            match rx.recv_timeout(Duration::from_millis(50)) {
                Ok(r) => return Ok(Some(r)),
                Err(RecvTimeoutError::Disconnected) => {
                    anyhow::bail!("internal: a step over the whole record ended without a result")
                }
                Err(RecvTimeoutError::Timeout) if self.requested() => return Ok(None),
                Err(RecvTimeoutError::Timeout) => {}
            }
        }
    }

    /// The error that ends an interrupted run, if a signal arrived; `outcome` tells what was
    /// written (it follows the signal's name in the message).
    pub fn error(&self, outcome: &str) -> Option<Interrupted> {
        self.requested().then(|| Interrupted {
            signal: self.shared.signal.load(Ordering::SeqCst) as i32,
            outcome: outcome.to_string(),
        })
    }
}

/// What the signal thread does with signal `sig` (module doc): the first sets the flag; a
/// repeat asks for a stop at once before the writing, and is only noted during it.
fn on_signal(sig: i32, requested: &AtomicBool, shared: &Shared) {
    let name = signal_name(sig);
    let first = !requested.load(Ordering::SeqCst);
    if first {
        shared.signal.store(sig as usize, Ordering::SeqCst);
        requested.store(true, Ordering::SeqCst);
    }
    let phase = if first {
        shared.phase.load(Ordering::SeqCst)
    } else {
        match shared.phase.compare_exchange(RUNNING, STOP_NOW, Ordering::SeqCst, Ordering::SeqCst) {
            Ok(_) => {
                aeroident_report::note!(
                    "{name} again: stopping at once; summary.json is written, the report and figures are not"
                );
                return;
            }
            Err(phase) => phase,
        }
    };
    match phase {
        WRITING => aeroident_report::note!(
            "{name}: ignored while the results are written, so that none is left half-written (they take seconds at most; SIGKILL ends at once)"
        ),
        STOP_NOW => aeroident_report::note!("{name}: already stopping"),
        _ => {}
    }
}

impl Drop for Interrupt {
    fn drop(&mut self) {
        self.handle.close();
        if let Some(t) = self.listener.take() {
            let _ = t.join();
        }
    }
}

/// A run ended early by a signal; what it wrote is in the message (and in `summary.json`,
/// status `interrupted`).
#[derive(Debug, Clone, thiserror::Error)]
#[error("interrupted by {}: {outcome}", signal_name(*.signal))]
pub struct Interrupted {
    /// The signal's number.
    pub signal: i32,
    /// What was written.
    pub outcome: String,
}

impl Interrupted {
    /// The process exit code: `128 + signal` (130 for SIGINT, 143 for SIGTERM).
    pub fn exit_code(&self) -> u8 {
        u8::try_from(128 + self.signal).unwrap_or(1)
    }
}

fn signal_name(signal: i32) -> String {
    match signal {
        1 => "SIGHUP".into(),
        2 => "SIGINT".into(),
        15 => "SIGTERM".into(),
        n => format!("signal {n}"),
    }
}

/// Lines of stdin queued at most: a bounded queue, so a reader thread ahead of the replay
/// waits instead of holding the whole feed in memory.
const STDIN_QUEUE_LINES: usize = 1024;

/// How often a waiting read looks at the interrupt flag.
const POLL: Duration = Duration::from_millis(50);

/// How the record read through an [`InterruptibleStdin`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StdinEnd {
    /// The input closed (or failed to read).
    Closed,
    /// The interrupt flag ended it at a line boundary, the input still open.
    Cut,
}

/// How far an [`InterruptibleStdin`] got, for a caller that watches it from another thread
/// ([`InterruptibleStdin::progress`]).
#[derive(Debug, Default)]
pub struct StdinProgress {
    lines: AtomicUsize,
    /// 0: still reading; 1: [`StdinEnd::Closed`]; 2: [`StdinEnd::Cut`].
    end: AtomicU8,
}

impl StdinProgress {
    /// Lines handed to the reader so far (a header line included).
    pub fn lines(&self) -> usize {
        self.lines.load(Ordering::SeqCst)
    }

    /// How the record ended, `None` while it is still being read.
    pub fn end(&self) -> Option<StdinEnd> {
        match self.end.load(Ordering::SeqCst) {
            1 => Some(StdinEnd::Closed),
            2 => Some(StdinEnd::Cut),
            _ => None,
        }
    }

    fn set_end(&self, end: StdinEnd) {
        let code = if end == StdinEnd::Cut { 2 } else { 1 };
        let _ = self.end.compare_exchange(0, code, Ordering::SeqCst, Ordering::SeqCst);
    }
}

/// Standard input read on a thread of its own, line by line, so that a read waiting for the
/// next line can end when the interrupt flag is set (module doc): the record then ends at the
/// last complete line handed out, as if the feed had closed. The flag is looked at before
/// every line, so a feed that keeps flowing ends as promptly as a silent one.
#[derive(Debug)]
pub struct InterruptibleStdin {
    rx: Receiver<io::Result<Vec<u8>>>,
    flag: Arc<AtomicBool>,
    progress: Arc<StdinProgress>,
    buf: Vec<u8>,
    pos: usize,
    done: bool,
}

impl InterruptibleStdin {
    /// Starts the reading thread; `flag` ends the record when set. The thread ends at the end
    /// of stdin or when this reader is dropped (at its next line).
    pub fn new(flag: Arc<AtomicBool>) -> Self {
        Self::start(|tx| read_lines(&mut io::stdin().lock(), tx), flag)
    }

    /// [`InterruptibleStdin::new`] on another line source (for tests).
    pub fn from_source<R: BufRead + Send + 'static>(mut source: R, flag: Arc<AtomicBool>) -> Self {
        Self::start(move |tx| read_lines(&mut source, tx), flag)
    }

    fn start<F>(read: F, flag: Arc<AtomicBool>) -> Self
    where
        F: FnOnce(&SyncSender<io::Result<Vec<u8>>>) + Send + 'static,
    {
        let (tx, rx) = sync_channel(STDIN_QUEUE_LINES);
        std::thread::spawn(move || read(&tx));
        let progress = Arc::new(StdinProgress::default());
        Self { rx, flag, progress, buf: Vec::new(), pos: 0, done: false }
    }

    /// The reader's progress, shared (it stays readable after the reader has moved on).
    pub fn progress(&self) -> Arc<StdinProgress> {
        Arc::clone(&self.progress)
    }

    fn end(&mut self, end: StdinEnd) {
        self.done = true;
        self.progress.set_end(end);
    }
}

fn read_lines(input: &mut dyn BufRead, tx: &SyncSender<io::Result<Vec<u8>>>) {
    loop {
        let mut line = Vec::new();
        match input.read_until(b'\n', &mut line) {
            Ok(0) => return,
            Ok(_) => {
                if tx.send(Ok(line)).is_err() {
                    return;
                }
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => {
                let _ = tx.send(Err(e));
                return;
            }
        }
    }
}

impl Read for InterruptibleStdin {
    fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
        while self.pos == self.buf.len() && !self.done {
            if self.flag.load(Ordering::SeqCst) {
                self.end(StdinEnd::Cut);
                break;
            }
            match self.rx.recv_timeout(POLL) {
                Ok(Ok(line)) => {
                    self.buf = line;
                    self.pos = 0;
                    self.progress.lines.fetch_add(1, Ordering::SeqCst);
                }
                Ok(Err(e)) => {
                    self.end(StdinEnd::Closed);
                    return Err(e);
                }
                Err(RecvTimeoutError::Disconnected) => self.end(StdinEnd::Closed),
                Err(RecvTimeoutError::Timeout) => {}
            }
        }
        let n = out.len().min(self.buf.len() - self.pos);
        out[..n].copy_from_slice(&self.buf[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A source that never ends and never pauses: one CSV line after another.
    struct Endless;

    impl Read for Endless {
        fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
            let line = b"1.0,2.0\n";
            let n = out.len().min(line.len());
            out[..n].copy_from_slice(&line[..n]);
            Ok(n)
        }
    }

    /// A feed that keeps flowing (no pause for the poll to notice) still ends at the first
    /// line boundary after the flag is set, and says it was cut.
    #[test]
    fn a_flowing_feed_ends_at_the_next_line_once_the_flag_is_set() {
        let flag = Arc::new(AtomicBool::new(false));
        let mut stdin =
            InterruptibleStdin::from_source(io::BufReader::new(Endless), Arc::clone(&flag));
        let progress = stdin.progress();
        let mut lines = io::BufReader::new(&mut stdin).lines();
        for _ in 0..3 {
            assert_eq!(lines.next().unwrap().unwrap(), "1.0,2.0");
        }
        assert_eq!(progress.end(), None);
        flag.store(true, Ordering::SeqCst);
        // The BufReader may hold a little more than it has handed out: at most what one read
        // delivered, which is one line.
        let rest = lines.by_ref().take(10_000).count();
        assert!(rest <= 1, "{rest} lines after the flag");
        assert_eq!(progress.end(), Some(StdinEnd::Cut));
        assert!(progress.lines() <= 4, "{} lines handed out", progress.lines());
    }

    /// A closed input ends the record as closed, every line delivered.
    #[test]
    fn a_closed_input_ends_as_closed_with_every_line() {
        let flag = Arc::new(AtomicBool::new(false));
        let mut stdin = InterruptibleStdin::from_source(&b"t,a\n1,2\n3,4"[..], flag);
        let mut text = String::new();
        stdin.read_to_string(&mut text).unwrap();
        assert_eq!(text, "t,a\n1,2\n3,4");
        assert_eq!(stdin.progress().end(), Some(StdinEnd::Closed));
        assert_eq!(stdin.progress().lines(), 3);
    }
}
