//! Graceful shutdown of live and long runs on SIGINT (Ctrl-C), SIGTERM and SIGHUP.
//!
//! A live feed never ends by itself, so a signal is its normal end: the first signal only sets a
//! flag ([`Interrupt::requested`]) that the run polls between samples; the run then finishes the
//! sample in hand and writes its results marked `interrupted`, and the process exits with
//! `128 + signal` ([`Interrupted::exit_code`], the shell's convention for "ended by a signal").
//! A second signal ends the process at once (exit `128 + signal`), for a run that does not
//! stop. The handlers are those of `signal-hook` (async-signal-safe, restores the previous
//! handlers when dropped); they are installed only around the runs that poll the flag, so every
//! other command keeps the default behaviour of the signals.
//!
//! The signal handlers restart interrupted system calls, so a run blocked reading stdin would
//! not see the flag until a line arrives: [`InterruptibleStdin`] reads stdin on a thread of its
//! own and ends the record at a line boundary once the flag is set.

use std::io::{self, BufRead, Read};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, sync_channel};
use std::time::Duration;

#[cfg(unix)]
// SIGHUP too: closing the terminal a live feed runs in is as ordinary an end as Ctrl-C.
const SIGNALS: [i32; 3] =
    [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM, signal_hook::consts::SIGHUP];
#[cfg(not(unix))]
const SIGNALS: [i32; 1] = [signal_hook::consts::SIGINT];

/// The installed handlers and what they received (module doc). Dropping it restores the
/// signals' previous behaviour.
#[derive(Debug)]
pub struct Interrupt {
    requested: Arc<AtomicBool>,
    signal: Arc<AtomicUsize>,
    ids: Vec<signal_hook::SigId>,
}

impl Interrupt {
    /// Installs the handlers of SIGINT and SIGTERM: the first sets the flag, a second one exits
    /// the process at once.
    ///
    /// # Errors
    /// The operating system refused a handler.
    pub fn install() -> io::Result<Self> {
        let requested = Arc::new(AtomicBool::new(false));
        let signal = Arc::new(AtomicUsize::new(0));
        let mut ids = Vec::new();
        for sig in SIGNALS {
            // Registered first, so it sees the flag as the previous signal left it: unset on
            // the first signal, set on the second.
            ids.push(signal_hook::flag::register_conditional_shutdown(
                sig,
                128 + sig,
                Arc::clone(&requested),
            )?);
            ids.push(signal_hook::flag::register_usize(sig, Arc::clone(&signal), sig as usize)?);
            ids.push(signal_hook::flag::register(sig, Arc::clone(&requested))?);
        }
        Ok(Self { requested, signal, ids })
    }

    /// Whether a signal has arrived.
    pub fn requested(&self) -> bool {
        self.requested.load(Ordering::SeqCst)
    }

    /// The flag the handlers set (for readers that poll it, [`InterruptibleStdin`]).
    pub fn flag(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.requested)
    }

    /// The error that ends an interrupted run (after its results are written), if a signal
    /// arrived.
    pub fn error(&self) -> Option<Interrupted> {
        self.requested().then(|| Interrupted { signal: self.signal.load(Ordering::SeqCst) as i32 })
    }
}

impl Drop for Interrupt {
    fn drop(&mut self) {
        for id in self.ids.drain(..) {
            signal_hook::low_level::unregister(id);
        }
    }
}

/// A run ended early by a signal; its results were written, marked `interrupted`.
#[derive(Debug, Clone, Copy, thiserror::Error)]
#[error("interrupted by {}: the results of the samples read until then were written, with status `interrupted`", signal_name(*.signal))]
pub struct Interrupted {
    /// The signal's number.
    pub signal: i32,
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

/// Standard input read on a thread of its own, line by line, so that a read waiting for the
/// next line can end when the interrupt flag is set (module doc): the record then ends at the
/// last complete line, as if the feed had closed.
#[derive(Debug)]
pub struct InterruptibleStdin {
    rx: Receiver<io::Result<Vec<u8>>>,
    flag: Arc<AtomicBool>,
    buf: Vec<u8>,
    pos: usize,
    done: bool,
}

impl InterruptibleStdin {
    /// Starts the reading thread; `flag` ends the record when set. The thread ends at the end
    /// of stdin or when this reader is dropped (at its next line).
    pub fn new(flag: Arc<AtomicBool>) -> Self {
        let (tx, rx) = sync_channel(STDIN_QUEUE_LINES);
        std::thread::spawn(move || read_lines(&mut io::stdin().lock(), &tx));
        Self { rx, flag, buf: Vec::new(), pos: 0, done: false }
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
            match self.rx.recv_timeout(POLL) {
                Ok(Ok(line)) => {
                    self.buf = line;
                    self.pos = 0;
                }
                Ok(Err(e)) => return Err(e),
                Err(RecvTimeoutError::Disconnected) => self.done = true,
                Err(RecvTimeoutError::Timeout) => {
                    self.done = self.flag.load(Ordering::SeqCst);
                }
            }
        }
        let n = out.len().min(self.buf.len() - self.pos);
        out[..n].copy_from_slice(&self.buf[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}
