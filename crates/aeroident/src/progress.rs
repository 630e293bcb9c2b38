//! Progress on stderr (`indicatif`), drawn only when stderr is a terminal: a bar for work of
//! known size (bytes of a record, scenarios of `run --all`), a spinner with the elapsed time for
//! a single long computation (`run`, `montecarlo`), and the live status line of
//! `replay --realtime` ([`StatusSink`]: samples, record time and the first estimates). In a
//! pipe, a file or CI nothing is drawn, so logs and captured output stay clean.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

/// Whether progress is drawn (stderr is a terminal).
pub fn enabled() -> bool {
    std::io::stderr().is_terminal()
}

fn target() -> ProgressDrawTarget {
    if enabled() { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() }
}

/// A bar over `len` bytes with `msg` before it (hidden unless [`enabled`]).
pub fn bytes_bar(len: u64, msg: &str) -> ProgressBar {
    let pb = ProgressBar::with_draw_target(Some(len), target());
    if let Ok(style) =
        ProgressStyle::with_template("{msg} [{bar:20}] {percent}% {elapsed} {prefix}")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(msg.to_string());
    pb
}

/// A bar over `len` items (hidden unless [`enabled`]).
pub fn count_bar(len: u64, msg: &str) -> ProgressBar {
    let pb = ProgressBar::with_draw_target(Some(len), target());
    if let Ok(style) = ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} {elapsed}") {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(msg.to_string());
    pb
}

/// Turns `pb` (a [`spinner`]) into a [`count_bar`] over `len` items with `msg` once `done` > 0,
/// and sets its position to `done`. Work whose count starts after a first phase of unknown
/// length (a bootstrap's replicas after its fit) spins, then counts.
pub fn count_on(pb: &ProgressBar, len: usize, done: usize, msg: &str) {
    if done == 0 {
        return;
    }
    pb.set_position(done as u64);
    if pb.length() != Some(len as u64) {
        pb.set_length(len as u64);
        if let Ok(style) = ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} {elapsed}") {
            pb.set_style(style.progress_chars("=> "));
        }
        pb.set_message(msg.to_string());
    }
}

/// A spinner with the elapsed time, ticking by itself (hidden unless [`enabled`]).
pub fn spinner(msg: &str) -> ProgressBar {
    let pb = ProgressBar::with_draw_target(None, target());
    if let Ok(style) = ProgressStyle::with_template("{spinner} {msg} {elapsed}") {
        pb.set_style(style);
    }
    pb.set_message(msg.to_string());
    if enabled() {
        pb.enable_steady_tick(Duration::from_millis(120));
    }
    pb
}

/// A sink for the replay's estimates lines (`t_s, <names>, sigma_<names>`) that shows them as a
/// status line on `bar`: samples so far, the record time and the first estimates, at most 10
/// times a second. Writes nothing itself.
#[derive(Debug)]
pub struct StatusSink {
    bar: ProgressBar,
    names: Vec<String>,
    samples: usize,
    line: Vec<u8>,
    last: Option<Instant>,
}

/// Estimates shown in the status line.
const SHOWN: usize = 3;

impl StatusSink {
    /// A sink updating `bar`'s prefix.
    pub fn new(bar: ProgressBar) -> Self {
        Self { bar, names: Vec::new(), samples: 0, line: Vec::new(), last: None }
    }

    /// The status text of one estimates line (`None` for the header, which sets the names).
    pub fn status(&mut self, line: &str) -> Option<String> {
        let mut fields = line.trim_end().split(',');
        let first = fields.next()?;
        if self.names.is_empty() || first == "t_s" {
            self.names =
                fields.take_while(|f| !f.starts_with("sigma_")).map(String::from).collect();
            return None;
        }
        self.samples += 1;
        let est: Vec<String> = fields
            .zip(&self.names)
            .take(SHOWN)
            .map(|(v, n)| format!("{n} {}", crate::table::fmt_sig(v.parse::<f64>().ok(), 4)))
            .collect();
        let t = first.parse::<f64>().map_or(first.to_string(), |t| format!("{t:.2}"));
        Some(format!("{} samples, t = {t} s, {}", self.samples, est.join(", ")))
    }
}

impl Write for StatusSink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        for &b in buf {
            if b == b'\n' {
                let line = String::from_utf8_lossy(&self.line).into_owned();
                self.line.clear();
                let due = self.last.is_none_or(|l| l.elapsed() >= Duration::from_millis(100));
                // The header always; a data line when the display is due (the count of samples
                // is kept for every line).
                if let Some(s) = self.status(&line)
                    && due
                {
                    self.bar.set_prefix(s);
                    self.bar.tick();
                    self.last = Some(Instant::now());
                }
            } else {
                self.line.push(b);
            }
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_line_shows_count_time_and_first_estimates() {
        let mut s = StatusSink::new(ProgressBar::hidden());
        assert_eq!(s.status("t_s,Cm_0,Cm_alpha,Cm_q,Cm_de,sigma_Cm_0,sigma_Cm_alpha"), None);
        let a = s.status("0.1,,,,,,").unwrap();
        assert_eq!(a, "1 samples, t = 0.10 s, Cm_0 —, Cm_alpha —, Cm_q —");
        let b = s.status("12.345,0.1,-0.9,-12,-1.1,0.01,0.02").unwrap();
        assert_eq!(b, "2 samples, t = 12.35 s, Cm_0 0.1000, Cm_alpha -0.9000, Cm_q -12.00");
        // Through the Write interface, byte by byte: every line counted.
        let mut w = StatusSink::new(ProgressBar::hidden());
        for chunk in [&b"t_s,a,sigma_a\n0,1,"[..], b"0.1\n1,2,0.1\n"] {
            w.write_all(chunk).unwrap();
        }
        assert_eq!(w.samples, 2);
    }
}
