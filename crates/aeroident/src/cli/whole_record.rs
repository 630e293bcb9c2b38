//! The commands that analyse a whole record at once (`compat`, `freqresp`): their output
//! directory locked and checked before the work, and the work abandoned on a signal with a
//! `summary.json` saying so.
//!
//! Such an analysis has no safe point to stop at and nothing of it is worth keeping half done,
//! so a signal ends it at once ([`crate::interrupt::Interrupt::watched`]); the directory, opened
//! before the work, then holds only `summary.json`, status `interrupted`: a run into the
//! directory can neither lose its results to another run started meanwhile (the lock) nor
//! leave the previous results looking like its own (they were cleared when it began).

use crate::interrupt::Interrupt;
use crate::outdir::OutputDir;
use std::path::Path;

/// A whole-record command's run: its name, its signals and its output directory.
pub struct WholeRecord {
    command: &'static str,
    data: String,
    interrupt: Interrupt,
    out: Option<OutputDir>,
}

impl WholeRecord {
    /// Installs the signal handlers, then opens `out` (locked, the previous run's files of
    /// `command` cleared, `inputs` never touched), before any of the record is read.
    ///
    /// # Errors
    /// The handlers could not be installed; the output directory's errors (busy, another
    /// command's, an input, not a directory).
    pub fn begin(
        command: &'static str,
        data: &str,
        out: Option<&Path>,
        inputs: &[&Path],
    ) -> anyhow::Result<Self> {
        let interrupt =
            Interrupt::install().map_err(|e| anyhow::anyhow!("installing signal handlers: {e}"))?;
        let out = out.map(|d| OutputDir::open(d, command, inputs)).transpose()?;
        Ok(Self { command, data: data.to_string(), interrupt, out })
    }

    /// Runs `work` on a thread a signal abandons; its result, or on a signal the error ending
    /// the run (exit `128 + signal`) after `summary.json` marked `interrupted` is written.
    ///
    /// # Errors
    /// The work's own error; the interruption; an output I/O error writing the summary.
    pub fn run<T: Send + 'static>(
        &mut self,
        work: impl FnOnce() -> anyhow::Result<T> + Send + 'static,
    ) -> anyhow::Result<T> {
        // A long record takes tens of seconds: a terminal sees the work is alive.
        let spin = crate::progress::spinner(&format!("{} {}", self.command, self.data));
        let watched = self.interrupt.watched(work);
        spin.finish_and_clear();
        match watched? {
            Some(r) => r,
            None => Err(self.stopped()),
        }
    }

    /// The output directory, when `--out` was given; from here further signals are ignored
    /// until the results are written (crate::interrupt), which takes seconds at most.
    pub fn writing(&mut self) -> Option<&mut OutputDir> {
        self.interrupt.begin_writing();
        self.out.as_mut()
    }

    /// Writes the summary of a run a signal stopped and returns the error that ends it.
    fn stopped(&mut self) -> anyhow::Error {
        self.interrupt.begin_writing();
        let why = format!(
            "interrupted by {} during `{}` of {}, before any result",
            self.interrupt.signal_name().unwrap_or_default(),
            self.command,
            self.data
        );
        let summary = serde_json::json!({
            "command": self.command,
            "data": self.data,
            "status": aeroident_pipelines::replay::STATUS_INTERRUPTED,
            "status_reason": why,
            "warnings": [why],
        });
        let written = match (&mut self.out, serde_json::to_string_pretty(&summary)) {
            (Some(o), Ok(text)) => match o.write_bytes("summary.json", text.as_bytes()) {
                Ok(path) => {
                    o.finish();
                    format!("summary.json says why ({})", path.display())
                }
                Err(e) => return e.into(),
            },
            (None, _) => "nothing written (no --out)".to_string(),
            (_, Err(e)) => return e.into(),
        };
        aeroident_report::note!("{why}");
        self.interrupt
            .error(&written)
            .map_or_else(|| anyhow::anyhow!("internal: stopped without a signal"), Into::into)
    }
}
