//! `aeroident replay`: feed a recorded flight to an online estimator sample by sample.
//!
//! ```text
//! aeroident replay <data.csv|.asc|.mat|-> --map <map.toml> [--format csv|asc|mat|ulog|dataflash]
//!                  [--out <dir>]
//!                  [--model longitudinal|lateral|six-axis|FILE|auto[:longitudinal|lateral|six-axis]]
//!                  [--select swr|mof] [--candidates TERM,…] [--knots-deg K,…]
//!                  [--estimator rls|rls-iv|ftr|ekf|smpe|smpe-corrected|smpe-finite-time|gradient|oe|fem|fdoe]
//!                  [--band-hz F_MIN:F_MAX]
//!                  [--forgetting λ] [--instrument-delay N]
//!                  [--derivatives auto|differentiate] [--diff-window N] [--realtime]
//!                  [--validate-on <data2.csv>] [--window START:END …] [--and <more.csv> …]
//!                  [--cross-check] [--no-spike-screen] [--robust]
//! ```
//! Writes `<dir>/estimates.csv`, `<dir>/summary.json`, `<dir>/estimates.{png,svg}` (estimates
//! with shaded ±2σ), `<dir>/fit.{png,svg}` (model vs measured) and `<dir>/report.html`
//! ([`crate::report::replay`]), and prints the results table ([`crate::table`]) on stdout (on stderr in live mode, where stdout carries the estimates). With `-` the record is read from stdin and one CSV line of estimates per sample is
//! written to stdout (a live feed: buffered, flushed per line with `--realtime`; the history
//! kept for the figure and the settling times is bounded, see `History`); the summary then goes to stderr unless
//! `--out` is given. The model used is printed on stderr. A diverged estimator is an error
//! (non-zero exit) after the summary is written. `--estimator oe` is the batch output-error
//! fit: it reads the whole record first (it says so), prints its iterations and writes
//! `summary.json` (estimates, coloured-residual and Cramér–Rao σ, residual RMS). `--estimator
//! fdoe` is frequency-domain output error over `--band-hz` (docs/fdoe.md), in the same shape.
//!
//! SIGINT (Ctrl-C), SIGTERM or SIGHUP ends a real-time replay gracefully, the normal end of a
//! live feed ([`crate::interrupt`]): the sample in hand is finished, `estimates.csv`,
//! `summary.json` (status `interrupted`) and the report are written for the samples read until
//! then, and the exit code is 128 + signal. A batch fit of stdin (`-`) ends its read on the
//! signal and fits the rows read, or, with too few to fit, writes a summary saying so; a
//! signal during a batch fit stops it at its next iteration (a bootstrap before its next
//! replica, its σ then over the replicas done) and writes its last iterate. A signal during a
//! step over the whole record before or after the estimator (`--compat auto`'s check,
//! `--model auto`'s selection, `--validate-on`) abandons that step at once: the summary
//! says which, status `interrupted` (after `--validate-on`, with the fit's results). A second
//! signal before the results are written stops at once with `summary.json` alone; one while
//! they are written is ignored, so that no file is left half-written.
//!
//! Before any estimator, rows with an isolated one-sample spike in a measured channel, or a run
//! of up to 3 on a channel other than a control input, are rejected and listed
//! (`aeroident_pipelines::record::outliers`; `--no-spike-screen` turns it off); runs of 4–5
//! are warned of in `summary.json`, for every estimator. A batch fit also warns when one
//! sample dominates it; `--robust` fits output error with Huber's weights.
//!
//! The log format is `--format`, else the file's extension, else CSV
//! ([`aeroident_io::log`]; `docs/mapping.md` tells how columns are named in each).
//!
//! Every summary has `identifiability` and `validation` (the model's fit to the record:
//! RMSE, bias with 95 % interval, fit %, R², Theil's U, Ljung–Box, residual–input correlation,
//! ±2σ prediction intervals; `docs/validation.md`), printed as a short block on stderr.
//! `--validate-on FILE2` applies the final estimates to a second record (same mapping) and
//! reports the same metrics there under `validation_on`.
//!
//! `--model auto` chooses each coefficient's terms from the record by equation error
//! (`--select swr`, stepwise regression, or `mof`, orthogonal functions;
//! `aeroident_pipelines::structure::select_model`), prints the selection path, writes it in
//! `summary.json` (`structure_selection`) and the chosen model as `<dir>/model.toml`, then
//! fits that model with the estimator asked for.

use aeroident_estimators::flight_model::N_STATES;
use aeroident_estimators::output_error::{InitialStates, StopFlag};
use aeroident_io::{
    FlightDataReader, LogFormat, Mapping, ModelSpec, open_log_with_notes, open_log_with_report,
};
use aeroident_pipelines::estimators::{EstimatorKind, OptionError, option_list, parse_options};
use aeroident_pipelines::replay::batch::BatchMethod;
use aeroident_pipelines::replay::{
    DerivativeSource, EstimateRows, Pacing, ReplayObserver, ReplayOptions, replay,
};
use aeroident_pipelines::structure::AutoSelection;
use aeroident_pipelines::window::TimeWindow;
use anyhow::Context;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `aeroident replay`.
#[derive(Debug, Clone, clap::Args)]
pub struct ReplayArgs {
    /// Recorded flight data: a CSV with one header row, a whitespace `.asc`, a MATLAB `.mat`,
    /// a PX4 ULog `.ulg`, an ArduPilot DataFlash `.bin`, `-` for stdin (live mode: CSV, or
    /// whitespace text with `--format asc`), or a live MAVLink feed
    /// `mavlink:udp:<host>:<port>[?timeout_s=<s>]` (docs/mavlink.md).
    pub data: String,
    /// Channel mapping TOML (see `mappings/*.toml` and `docs/mapping.md`).
    #[arg(long)]
    pub map: PathBuf,
    /// Log format (csv, asc, mat, ulog, dataflash); default: by the file's extension
    /// (`.asc`, `.mat`, `.ulg`, `.bin`), else CSV.
    #[arg(long)]
    pub format: Option<LogFormat>,
    /// Output directory: summary.json, report.html and the figures (PNG and SVG), and
    /// estimates.csv (real-time estimators).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Model: a preset (`longitudinal`, `lateral`, `six-axis`), a model file (TOML, see
    /// `models/`), or `auto[:longitudinal|lateral|six-axis]`: the terms chosen from the
    /// record (see `--select`). Default: the richest preset the record's first sample supports.
    #[arg(long)]
    pub model: Option<String>,
    /// How `--model auto` chooses terms: `swr` (stepwise regression, partial F cut-off 20,
    /// SIDPAC `swr`) or `mof` (multivariate orthogonal functions to the PSE minimum, SIDPAC
    /// `offit`).
    #[arg(long, value_parser = ["swr", "mof"], default_value = "swr")]
    pub select: String,
    /// `--model auto`: the candidate terms of every coefficient, comma-separated (vocabulary
    /// names: alpha, q, alphadot, de, V, alpha2, alpha_de, alpha_q, beta, p, r, da, dr,
    /// alpha_beta, alpha_p, alpha_r, alpha_da, alpha_dr, alpha_k1…alpha_k4, mach, mach2).
    /// Default: per coefficient, its preset's terms and the usual nonlinear ones; `alphadot`
    /// only when listed here (it also stands in for a lag of the α channel).
    #[arg(long, value_delimiter = ',')]
    pub candidates: Vec<String>,
    /// `--model auto`: the α knots of the spline candidates, degrees, ascending,
    /// comma-separated (at most four; e.g. a table's breakpoints). With the default candidates
    /// it offers `alpha_k1…alpha_kn` to the longitudinal coefficients. Default: knots at the
    /// record's α quantiles, as many as the highest `alpha_k<n>` in `--candidates`.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub knots_deg: Vec<f64>,
    /// The estimator.
    #[arg(long, value_parser = super::named::<EstimatorKind>(), default_value = "rls")]
    pub estimator: EstimatorKind,
    /// Forgetting factor of `rls`, `rls-iv`, `ftr` and `smpe-finite-time`, in (0, 1]; 1
    /// (default) = ordinary least squares. Refused with the other estimators, which have none
    /// (the estimator registry says which take it).
    #[arg(long)]
    pub forgetting: Option<f64>,
    /// Source of ṗ, q̇, ṙ and α̇: the record's channels where mapped (else the causal
    /// differentiator), or always differentiate p, q, r and α.
    #[arg(long, alias = "qdot", value_parser = super::named::<DerivativeSource>(), default_value = "auto")]
    pub derivatives: DerivativeSource,
    /// Causal differentiator window, samples (odd ≥ 3; lag = (N−1)/2 samples).
    #[arg(long, default_value_t = 5)]
    pub diff_window: usize,
    /// `--estimator rls-iv`: delay of the instruments (the state regressors' earlier values),
    /// samples, 1–64; it must exceed the regressor noise's correlation time and, when rates are
    /// differentiated, the differentiator's half-window. Default: the differentiator window.
    #[arg(long, value_name = "N")]
    pub instrument_delay: Option<usize>,
    /// Pace the replay at the record's own sample rate.
    #[arg(long)]
    pub realtime: bool,
    /// A time window `START:END` (record seconds) of the record to use; repeat it for several
    /// manoeuvres of one flight, each window its own manoeuvre (own initial state). Default:
    /// the whole record.
    #[arg(long = "window", value_name = "START:END", value_parser = parse_window)]
    pub windows: Vec<TimeWindow>,
    /// `--estimator oe | fem`: a further record of the same aircraft (same mapping and
    /// format), fitted together with the first, each file a manoeuvre of its own; repeat it
    /// for more. `--compat auto` is checked on the first record and applied to all.
    #[arg(long = "and", value_name = "FILE")]
    pub and: Vec<String>,
    /// Real-time estimators: also fit the record by output error with the same model and set
    /// the two side by side; a parameter further apart than 2 combined σ is flagged in the
    /// table, the warnings and `summary.json` `cross_check`, with its likely cause.
    #[arg(long)]
    pub cross_check: bool,
    /// A second record (same mapping) not used for the fit: the final estimates are applied
    /// to it and the validation metrics reported under `validation_on` in the summary.
    #[arg(long, value_name = "FILE2")]
    pub validate_on: Option<PathBuf>,
    /// `oe`, `fem`: each manoeuvre's initial state fixed at its first sample's measurements
    /// (default; Jategaonkar's `parFlagX0 = 0`) or estimated with the parameters (every
    /// integrated state of the model, per manoeuvre; `estimate`).
    #[arg(long, value_enum)]
    pub initial_states: Option<InitialStatesArg>,
    /// `oe`: the parametric bootstrap σ from N replicas of the record flown through the fitted
    /// model with the process and measurement noise a filter-error fit of the same record
    /// estimates, each refitted (N ≥ 2; 20–50 typical; at most 10 000, each replica being a
    /// whole refit; docs/uncertainty.md, "Output error: the parametric bootstrap"). Its σ
    /// becomes the reported `std_error`.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..))]
    pub bootstrap: Option<u32>,
    /// `oe`, `fem`: most Gauss–Newton iterations (default 50 for `oe`, 250 for `fem`). A fit
    /// that reaches it reports its last iterate, status `not_converged` (or
    /// `converged_in_cost` when the cost had stopped changing) and why.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub max_iterations: Option<u32>,
    /// `fem`: the states with process noise, comma-separated (`V`, `alpha`, `beta`, `p`, `q`,
    /// `r`, `phi`, `theta`; default `V,alpha,beta`), e.g. `V,alpha,theta,q` for the book's
    /// HFB-320 fit.
    #[arg(long, value_name = "STATES")]
    pub process_noise: Option<String>,
    /// `fem`: let the Kalman gain correct a state by more than its prediction error
    /// (`diag(K C) > 1`); by default every element is held at or below 1, as Jategaonkar's
    /// filter-error method (2015, ch. 5) does.
    #[arg(long)]
    pub no_gain_constraint: bool,
    /// Apply a data compatibility check's corrections before estimating: a `compat.json` of
    /// `aeroident compat`, or `auto` to run the check on this record first. Removes the
    /// inertial and vane biases and scale factors, undoes the time shifts, and fills a
    /// missing sideslip with the reconstructed one; the summary's warnings list what.
    #[arg(long, value_name = "FILE|auto")]
    pub compat: Option<String>,
    /// Do not screen the record for spikes before estimating (by default a row whose channel
    /// jumps far out of its neighbours and back, alone or in a run of up to 3 rows, is
    /// rejected and listed; `aeroident_pipelines::record::outliers`). For records whose inputs
    /// are genuine one-sample pulses on an otherwise constant channel.
    #[arg(long)]
    pub no_spike_screen: bool,
    /// `fdoe`: the band fitted, `F_MIN:F_MAX` in Hz (default 0.1:1.5, SIDPAC's rigid-body
    /// band, Klein & Morelli 2006 ch. 7). Choose it from the excitation: where the inputs have
    /// energy and the modes of the model lie, below Nyquist.
    #[arg(long, value_name = "F_MIN:F_MAX", value_parser = parse_band)]
    pub band_hz: Option<(f64, f64)>,
    /// `oe`: Huber's outlier-resistant fit (IRLS weights on the residuals normalised by their
    /// robust σ, k = 1.345) instead of the Gaussian maximum-likelihood one.
    #[arg(long)]
    pub robust: bool,
}

/// `--initial-states` of the batch fits (`aeroident_estimators::output_error::InitialStates`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum InitialStatesArg {
    /// Each manoeuvre starts at its first sample's measured states.
    FirstSample,
    /// Each manoeuvre's initial state is estimated with the parameters.
    Estimate,
}

impl InitialStatesArg {
    /// The estimator crate's setting: every integrated state free for `Estimate`.
    pub fn to_config(self) -> InitialStates {
        match self {
            Self::FirstSample => InitialStates::FirstSample,
            Self::Estimate => InitialStates::Estimate([true; N_STATES]),
        }
    }
}

/// The console's view of a replay: the model line and warnings on stderr (the estimates go to
/// an [`EstimateRows`] beside it), and the stop a signal asks for.
struct Console<'a> {
    interrupt: &'a crate::interrupt::Interrupt,
}

impl ReplayObserver for Console<'_> {
    fn stop_requested(&mut self) -> bool {
        self.interrupt.requested()
    }

    fn model(&mut self, line: &str) {
        eprintln!("{line}");
    }

    fn warning(&mut self, text: &str) {
        eprintln!("warning: {text}");
    }
}

fn parse_window(text: &str) -> Result<TimeWindow, String> {
    TimeWindow::parse(text)
}

/// `F_MIN:F_MAX` in Hz, `0 < F_MIN < F_MAX`.
fn parse_band(text: &str) -> Result<(f64, f64), String> {
    let bad = || format!("`{text}`: give the band as F_MIN:F_MAX in Hz with 0 < F_MIN < F_MAX");
    let (a, b) = text.split_once(':').ok_or_else(bad)?;
    let f0: f64 = a.trim().parse().map_err(|_| bad())?;
    let f1: f64 = b.trim().parse().map_err(|_| bad())?;
    if !(f0 > 0.0 && f1 > f0 && f1.is_finite()) {
        return Err(bad());
    }
    Ok((f0, f1))
}

/// Runs `aeroident replay`.
///
/// # Errors
/// Mapping, model-file or data errors (naming file, row or line, and column or key),
/// estimator errors (not available, bad option, diverged), and output I/O errors.
pub fn execute(args: ReplayArgs) -> anyhow::Result<()> {
    let mapping = Mapping::from_path(&args.map)?;
    let mavlink = crate::live::is_mavlink(&args.data);
    let live = args.data == "-" || mavlink;
    check_combination(&args, live, mavlink)?;
    // Lock the directory and clear the previous run's files before reading anything: a
    // directory that cannot take the results is refused before a long fit, not after it.
    let mut out_dir = open_out(&args)?;
    // From here a signal ends the run gracefully (crate::interrupt): the steps over the whole
    // record before the estimator too, with a summary saying so.
    let interrupt = crate::interrupt::Interrupt::install().context("installing signal handlers")?;
    let (a, m) = (args.clone(), mapping.clone());
    let stage = move || compat_corrections(&a, &m, live);
    let Some(compat) = stage_watched(&interrupt, stage)? else {
        let step = "--compat auto (the data compatibility check)";
        return stopped_before_fit(&args, &interrupt, out_dir.as_mut(), step);
    };
    let compat = compat?;
    let (a, m, c) = (args.clone(), mapping.clone(), compat.clone());
    let stage = move || resolve_model(&a, &m, c.as_ref(), live);
    let Some(resolved) = stage_watched(&interrupt, stage)? else {
        let step = "--model auto (the structure selection)";
        return stopped_before_fit(&args, &interrupt, out_dir.as_mut(), step);
    };
    let (model, selection) = resolved?;
    let opts = ReplayOptions {
        estimator: args.estimator,
        model,
        forgetting: args.forgetting.unwrap_or(1.0),
        derivatives: args.derivatives,
        diff_window: args.diff_window,
        instrument_delay: args.instrument_delay,
        pacing: if args.realtime { Pacing::Realtime } else { Pacing::Unpaced },
        compat,
        windows: args.windows.clone(),
        spike_screen: (!args.no_spike_screen)
            .then(aeroident_pipelines::record::outliers::SpikeScreen::default),
    };
    if args.estimator.is_batch() {
        let given = (opts.model, opts.compat);
        return execute_batch(&args, &mapping, given, selection, &interrupt, out_dir);
    }
    if !live && args.out.is_none() {
        anyhow::bail!("give --out <dir> (or read `-` from stdin for a live feed on stdout)");
    }
    execute_online(args, mapping, opts, selection, &interrupt, out_dir)
}

/// Runs `stage`, a step over a whole record that no estimator watches (`--compat auto`,
/// `--model auto`, `--validate-on`), on a thread of its own while answering the signals
/// (crate::interrupt): a signal abandons it at once, `None` (the thread ends with the process,
/// which writes its summary and exits). Such a step has no safe point to stop at and nothing
/// of it is worth keeping half done.
///
/// # Errors
/// The thread could not start or ended without a result (a panic).
fn stage_watched<T: Send + 'static>(
    interrupt: &crate::interrupt::Interrupt,
    stage: impl FnOnce() -> T + Send + 'static,
) -> anyhow::Result<Option<T>> {
    use std::sync::mpsc::RecvTimeoutError;
    if interrupt.requested() {
        return Ok(None);
    }
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("whole-record".into())
        .stack_size(aeroident_pipelines::WORKER_STACK_BYTES)
        .spawn(move || {
            let _ = tx.send(stage());
        })
        .context("starting a thread")?;
    loop {
        match rx.recv_timeout(std::time::Duration::from_millis(50)) {
            Ok(r) => return Ok(Some(r)),
            Err(RecvTimeoutError::Disconnected) => {
                anyhow::bail!("internal: a step over the whole record ended without a result")
            }
            Err(RecvTimeoutError::Timeout) if interrupt.requested() => return Ok(None),
            Err(RecvTimeoutError::Timeout) => {}
        }
    }
}

/// Ends a run that a signal stopped during `step` (an option's step over the whole record),
/// before any estimator ran: `summary.json` with status `interrupted` and why, exit
/// 128 + signal.
///
/// # Errors
/// Always: the interruption (or an output I/O error).
fn stopped_before_fit(
    args: &ReplayArgs,
    interrupt: &crate::interrupt::Interrupt,
    out: Option<&mut crate::outdir::OutputDir>,
    step: &str,
) -> anyhow::Result<()> {
    interrupt.begin_writing();
    let why = format!(
        "interrupted by {} during {step}, before any estimate",
        interrupt.signal_name().unwrap_or_default()
    );
    write_stopped_summary(args, out, None, &why)?;
    Err(stopped(interrupt, "no estimates; summary.json says why"))
}

/// Refuses options that do not go together (the estimator's own options, a batch fit of a
/// live feed), before anything is opened.
fn check_combination(args: &ReplayArgs, live: bool, mavlink: bool) -> anyhow::Result<()> {
    if args.robust && args.estimator != EstimatorKind::Oe {
        anyhow::bail!(
            "--robust is Huber's output-error fit (--estimator oe), not --estimator {}",
            args.estimator.name()
        );
    }
    check_estimator_options(args)?;
    if args.band_hz.is_some() && args.estimator != EstimatorKind::Fdoe {
        anyhow::bail!(
            "--band-hz is the band of frequency-domain output error (--estimator fdoe), not of --estimator {}",
            args.estimator.name()
        );
    }
    if args.estimator.is_batch() && mavlink {
        anyhow::bail!(
            "--estimator {} is a batch fit of a whole record, not for a live MAVLink feed",
            args.estimator.name()
        );
    }
    if args.estimator.is_batch() {
        return Ok(());
    }
    check_online_combination(args, live)
}

/// The flags that are estimator options, each with the registry's key
/// ([`EstimatorKind::options`]).
const ESTIMATOR_OPTION_FLAGS: [(&str, &str); 2] =
    [("forgetting", "--forgetting"), ("instrument_delay", "--instrument-delay")];

/// The flag of the registry's option `key`, as typed.
fn option_flag(key: &str) -> &str {
    ESTIMATOR_OPTION_FLAGS.iter().find(|f| f.0 == key).map_or(key, |f| f.1)
}

/// The estimator-option flags given (`--forgetting`, `--instrument-delay`) parsed by the
/// registry for `--estimator` ([`parse_options`]), which knows which kind takes which: one the
/// kind does not take is refused (it would be ignored), naming the flag, the kind and the
/// options it takes. The values' ranges are checked with the replay's other numbers, naming the
/// value exactly as typed.
fn check_estimator_options(args: &ReplayArgs) -> anyhow::Result<()> {
    let mut pairs = Vec::new();
    if let Some(f) = args.forgetting {
        pairs.push(("forgetting", toml::Value::Float(f)));
    }
    if let Some(d) = args.instrument_delay {
        // A delay beyond an i64 is out of range all the same; the range check names it.
        pairs
            .push(("instrument_delay", toml::Value::Integer(i64::try_from(d).unwrap_or(i64::MAX))));
    }
    match parse_options(args.estimator, pairs) {
        Ok(_) => Ok(()),
        Err(OptionError::Unknown { kind, key }) => anyhow::bail!(
            "{} is not an option of --estimator {}, which takes {} (it would be ignored)",
            option_flag(&key),
            kind.name(),
            option_list(kind)
        ),
        Err(OptionError::Invalid { key, reason, .. }) => {
            anyhow::bail!("option `{}`: {reason}", option_flag(&key))
        }
    }
}

/// [`check_combination`] for the real-time estimators: the batch fits' options refused.
fn check_online_combination(args: &ReplayArgs, live: bool) -> anyhow::Result<()> {
    if args.cross_check && (live || args.estimator.is_batch()) {
        anyhow::bail!(
            "--cross-check sets a real-time estimator beside the batch fit of a whole record: not for a live feed or a batch estimator"
        );
    }
    if !args.and.is_empty() {
        anyhow::bail!(
            "--and fits several records together: it is for the batch fits (--estimator oe | fem); replay each record on its own with --estimator {}",
            args.estimator.name()
        );
    }
    if args.initial_states.is_some() {
        anyhow::bail!(
            "--initial-states applies to the batch fits (--estimator oe or fem), not to --estimator {}",
            args.estimator.name()
        );
    }
    if args.bootstrap.is_some() {
        anyhow::bail!(
            "--bootstrap applies to output error (--estimator oe), not to --estimator {}",
            args.estimator.name()
        );
    }
    if args.no_gain_constraint {
        anyhow::bail!(
            "--no-gain-constraint applies to the filter-error method (--estimator fem), not to --estimator {}",
            args.estimator.name()
        );
    }
    if args.process_noise.is_some() {
        anyhow::bail!(
            "--process-noise applies to the filter-error method (--estimator fem), not to --estimator {}",
            args.estimator.name()
        );
    }
    if args.max_iterations.is_some() {
        anyhow::bail!(
            "--max-iterations applies to the batch fits (--estimator oe or fem), not to --estimator {}",
            args.estimator.name()
        );
    }
    Ok(())
}

/// The real-time estimators' replay (`execute` past the checks): estimates per sample, then
/// the results, into `out_dir` (opened) when `--out` is given.
fn execute_online(
    args: ReplayArgs,
    mapping: Mapping,
    opts: ReplayOptions,
    selection: Option<AutoSelection>,
    interrupt: &crate::interrupt::Interrupt,
    mut out_dir: Option<crate::outdir::OutputDir>,
) -> anyhow::Result<()> {
    let mavlink = crate::live::is_mavlink(&args.data);
    let live = args.data == "-" || mavlink;
    let mut csv_file = match out_dir.as_mut() {
        Some(o) => Some(o.create("estimates.csv")?),
        None => None,
    };
    // Buffered: one write per 64 KiB, not per sample (the replay flushes per line only when
    // paced in real time).
    let mut stdout_lock: Box<dyn Write> = if mavlink {
        // A live feed: each line of estimates out as its message arrives.
        Box::new(std::io::LineWriter::new(std::io::stdout().lock()))
    } else {
        Box::new(std::io::BufWriter::with_capacity(1 << 16, std::io::stdout().lock()))
    };
    // Progress on stderr when it is a terminal: bytes of the file, and a status line with the
    // samples, the record time and the first estimates (the live view of `--realtime`).
    let bar = match std::fs::metadata(&args.data) {
        Ok(m) if !live => crate::progress::bytes_bar(
            m.len(),
            &Path::new(&args.data)
                .file_name()
                .map_or(args.data.clone(), |n| n.to_string_lossy().into()),
        ),
        _ => crate::progress::spinner("replay (live)"),
    };
    let mut status = crate::progress::StatusSink::new(bar.clone());
    let mut sinks: Vec<&mut dyn Write> = Vec::new();
    if let Some(f) = csv_file.as_mut() {
        sinks.push(f);
    }
    if live {
        sinks.push(&mut *stdout_lock);
    }
    if crate::progress::enabled() {
        sinks.push(&mut status);
    }
    let mut console = (Console { interrupt }, EstimateRows { sinks, flush_each: args.realtime });
    let format = args
        .format
        .or_else(|| LogFormat::from_extension(Path::new(&args.data)))
        .unwrap_or(LogFormat::Csv);
    let outcome = if mavlink {
        let (reader, stats) = crate::live::open_mavlink(&args.data, &mapping)?;
        replay(reader, &mapping, &opts, &mut console)
            .map(|mut outcome| {
                crate::live::finish(&mut outcome.summary, &stats);
                outcome
            })
            .inspect_err(|_| crate::live::report_failure(&stats))
    } else if live && matches!(format, LogFormat::Csv | LogFormat::Asc) {
        // stdin through a reader that ends the record on a signal even while no line arrives.
        let stdin = crate::interrupt::InterruptibleStdin::new(interrupt.flag());
        let reader = if format == LogFormat::Asc {
            aeroident_io::log::asc_reader(std::io::BufReader::new(stdin), "-", &mapping)
        } else {
            FlightDataReader::new(Box::new(stdin) as Box<dyn std::io::Read>, "-", &mapping)
        };
        // A header cut short by a signal is an interruption too (below), not a plain error.
        reader
            .map_err(aeroident_pipelines::replay::ReplayError::from)
            .and_then(|reader| replay(reader, &mapping, &opts, &mut console))
    } else if !live && format == LogFormat::Csv {
        // The CSV file itself, read through the progress bar (what `open_log` opens for CSV).
        let file =
            std::fs::File::open(&args.data).with_context(|| format!("opening {}", args.data))?;
        let reader = FlightDataReader::new(
            std::io::BufReader::new(bar.wrap_read(file)),
            &args.data,
            &mapping,
        )?;
        // Listed like every file read (a CSV reader leaves nothing out before the rows), as
        // the batch fits and Python list it.
        let report = aeroident_io::ReaderReport {
            file: args.data.clone(),
            format: format.name().to_string(),
            dropped: Vec::new(),
        };
        replay(reader, &mapping, &opts, &mut console).map(|mut outcome| {
            outcome.reader.push(report);
            outcome
        })
    } else {
        let (reader, report) = open_log_with_report(&args.data, Some(format), &mapping)?;
        for n in report.notes() {
            eprintln!("note: {n}");
        }
        replay(reader, &mapping, &opts, &mut console).map(|mut outcome| {
            outcome.reader.push(report);
            outcome
        })
    };
    bar.finish_and_clear();
    let mut outcome = match outcome {
        Ok(outcome) => outcome,
        // A live feed stopped before any sample was estimated (even before its header): no
        // results, but still a summary saying so.
        Err(e) if live && interrupt.requested() => {
            drop(csv_file);
            let read = match &e {
                aeroident_pipelines::replay::ReplayError::Interrupted { samples_read, .. } => {
                    Some(*samples_read)
                }
                _ => None,
            };
            let why = format!(
                "interrupted by {} before any sample was estimated: {e}",
                interrupt.signal_name().unwrap_or_default()
            );
            write_stopped_summary(&args, out_dir.as_mut(), read, &why)?;
            return Err(stopped(interrupt, "no sample was estimated"));
        }
        Err(e) => return Err(e.into()),
    };
    let mut interrupted = outcome.interrupted();
    if interrupted && (args.validate_on.is_some() || args.cross_check) {
        let w = "the run was interrupted: --validate-on / --cross-check not done".to_string();
        eprintln!("warning: {w}");
        outcome.summary.warnings.push(w);
    }
    if args.cross_check && !interrupted {
        let (reader, _) = open_log_with_notes(&args.data, Some(format), &mapping)?;
        eprintln!("cross-check: fitting the record by output error with the same model");
        aeroident_pipelines::replay::cross_check_record(&mut outcome, reader, &mapping, &opts);
        if let Some(c) = &outcome.cross_check {
            for w in aeroident_pipelines::replay::cross_check::warnings(c) {
                eprintln!("warning: {w}");
            }
        }
    }
    if let Some(f) = csv_file {
        f.commit()?;
    }
    let validation_on = match (&args.validate_on, outcome.diverged() || interrupted) {
        (Some(path), false) => {
            let (name, m, o, fitted) =
                (path.display().to_string(), mapping.clone(), opts.clone(), outcome.clone());
            let stage = move || -> anyhow::Result<_> {
                let (reader, notes) = open_log_with_notes(&name, None, &m)?;
                for n in &notes {
                    eprintln!("note: {n}");
                }
                Ok(aeroident_pipelines::replay::validate_on(reader, &m, &o, &fitted)?)
            };
            match stage_watched(interrupt, stage)? {
                Some(v) => Some(v?),
                None => {
                    interrupted = true;
                    let s = &mut outcome.summary;
                    s.status = aeroident_pipelines::replay::STATUS_INTERRUPTED.to_string();
                    s.warnings.push(validation_stopped(interrupt));
                    None
                }
            }
        }
        _ => None,
    };
    // From here further signals are ignored until the results are written (crate::interrupt);
    // a second one before this point leaves the report and figures out.
    let summary_only = begin_writing(
        Some(interrupt),
        interrupted,
        outcome.summary.samples_read,
        &mut outcome.summary.warnings,
    );
    let summary_text = summary_json(&outcome.document(validation_on.as_ref()), selection.as_ref())?;
    if let (Some(s), Some(o)) = (&selection, out_dir.as_mut()) {
        o.write_bytes("model.toml", s.model.to_toml().as_bytes())?;
    }
    match &args.out {
        Some(dir) if summary_only => {
            let o = out_dir.as_mut().context("internal: output directory not open")?;
            o.write_bytes("summary.json", summary_text.as_bytes())?;
            o.finish();
            eprintln!(
                "wrote {} and {}",
                dir.join("estimates.csv").display(),
                dir.join("summary.json").display()
            );
        }
        Some(dir) => {
            let o = out_dir.as_mut().context("internal: output directory not open")?;
            o.write_bytes("summary.json", summary_text.as_bytes())?;
            let name = Path::new(&args.data)
                .file_name()
                .map_or(args.data.clone(), |n| n.to_string_lossy().into_owned());
            let title = format!("{name} — {} — {}", args.estimator.name(), outcome.model.name);
            let source = crate::report::Source { data: &args.data, mapping: &args.map };
            let results = crate::report::replay::write(
                &source,
                &opts,
                &outcome,
                &title,
                &crate::report::replay::model_references(&outcome),
                o,
            )?;
            // Complete: a divergence or an interruption reported below keeps these files.
            o.finish();
            if live {
                // stdout carries the live stream of estimates: the table goes beside the log.
                eprint!("{}", crate::table::render(&results));
            } else {
                crate::cli::print_stdout(&crate::table::render(&results))?;
            }
            eprintln!(
                "{}: {} samples read, {} rejected, {:.0} samples/s, status {}; wrote {}",
                args.data,
                outcome.summary.samples_read,
                outcome.summary.samples_rejected,
                outcome.summary.throughput_samples_per_s,
                outcome.summary.status,
                dir.display()
            );
        }
        None => eprintln!("{summary_text}"),
    }
    if !outcome.summary.correlations.is_empty() {
        let pairs: Vec<String> = outcome
            .summary
            .correlations
            .iter()
            .map(|c| format!("{}/{} ({:+.3})", c.a, c.b, c.rho))
            .collect();
        eprintln!(
            "warning: strongly correlated estimates (|ρ| > 0.9; the data do not separate them): {}",
            pairs.join(", ")
        );
    }
    for v in outcome.validation.iter().chain(validation_on.iter()) {
        eprint!("{}", validation_block(v));
    }
    // The end-of-run diagnostics (sign plausibility, filter consistency, collinear
    // regressors); the record warnings were printed as they arose.
    for w in outcome.summary.warnings.iter().filter(|w| w.kind.is_diagnostic()) {
        eprintln!("warning: {w}");
    }
    if let Some(e) = outcome.diverged_error(args.estimator.name()) {
        anyhow::bail!(e);
    }
    if summary_only {
        return Err(stopped(interrupt, SUMMARY_ONLY));
    }
    if interrupted {
        if let Some(e) = interrupt.error(
            "the results of the samples read until then were written, with status `interrupted`",
        ) {
            return Err(e.into());
        }
    } else if outcome.summary.status != "running" {
        eprintln!(
            "warning: estimator status `{}`: not every parameter was identified (null in the summary)",
            outcome.summary.status
        );
    }
    Ok(())
}

/// Every file the replay reads (the records, mapping, model file, compatibility file and
/// validation record): the output directory never removes or overwrites them. A live source
/// or a preset name names no file and is left out by [`crate::outdir::OutputDir::open`].
fn input_paths(args: &ReplayArgs) -> Vec<&Path> {
    let mut p: Vec<&Path> = std::iter::once(&args.data).chain(&args.and).map(Path::new).collect();
    p.push(&args.map);
    p.extend(args.model.as_deref().map(Path::new));
    p.extend(args.compat.as_deref().filter(|c| *c != "auto").map(Path::new));
    p.extend(args.validate_on.as_deref());
    p
}

/// The console block of a validation report: one line per output.
pub fn validation_block(v: &aeroident_pipelines::replay::prediction::ValidationReport) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let what = if v.used_for_fit { "validation on the fitted record" } else { "validation on" };
    let _ = writeln!(
        s,
        "{what} {} ({}; {} samples):",
        v.data,
        v.outputs.first().map_or("-", |o| o.prediction.as_str()),
        v.samples
    );
    let opt = |x: Option<f64>, p: usize| x.map_or("—".to_string(), |x| format!("{x:.p$}"));
    for o in &v.outputs {
        let lb = o.ljung_box.as_ref().map_or("—".into(), |l| {
            format!(
                "Q({})={:.0} p={:.2}{}",
                l.lags,
                l.q,
                l.p_value,
                if l.white { "" } else { " (coloured)" }
            )
        });
        let xc: Vec<String> = o
            .input_correlation
            .iter()
            .map(|c| {
                format!("{} {:.2}{}", c.input, c.max_abs_rho, if c.within_band { "" } else { "*" })
            })
            .collect();
        let pi = o
            .prediction_interval
            .as_ref()
            .map_or("—".into(), |p| format!("{:.0} %", 100.0 * p.fraction_inside));
        let _ = writeln!(
            s,
            "  {:<11} fit {:>6} %  R² {:>6}  rmse {:.3e}  bias {:+.2e} [{:+.2e}, {:+.2e}]  U {}  {}  ρ(e,u) {}  in ±2σ {}",
            o.name,
            opt(o.fit_percent, 1),
            opt(o.r_squared, 3),
            o.rmse,
            o.bias,
            o.bias_ci95[0],
            o.bias_ci95[1],
            opt(o.theil_u, 3),
            lb,
            if xc.is_empty() { "—".into() } else { xc.join(", ") },
            pi
        );
    }
    for n in &v.notes {
        let _ = writeln!(s, "  note: {n}");
    }
    s
}

/// `--model`: a preset or file, or (`auto…`) the structure chosen from the record, whose
/// selection path is printed on stderr.
fn resolve_model(
    args: &ReplayArgs,
    mapping: &Mapping,
    compat: Option<&aeroident_pipelines::compat::Corrections>,
    live: bool,
) -> anyhow::Result<(Option<ModelSpec>, Option<AutoSelection>)> {
    let auto = args.model.as_deref().is_some_and(|m| m.starts_with("auto"));
    if auto && live {
        anyhow::bail!(
            "--model auto selects the terms on the whole record: give a file, not a live feed"
        );
    }
    if auto {
        eprintln!("structure: selecting the terms on the whole record (--model auto)");
    }
    let open = || {
        let files = std::iter::once(&args.data).chain(&args.and);
        files.map(|f| open_log_with_notes(f, args.format, mapping).map(|(r, _)| r)).collect()
    };
    let (model, selection) = aeroident_pipelines::structure::model_from_args(
        args.model.as_deref(),
        &args.select,
        &args.candidates,
        &args.knots_deg,
        open,
        mapping,
        compat,
        &args.windows,
        args.diff_window,
    )?;
    for line in selection.iter().flat_map(AutoSelection::path_lines) {
        eprintln!("{line}");
    }
    Ok((model, selection))
}

/// `summary.json`'s text: `summary` with the structure selection (`structure_selection`) of
/// `--model auto`.
fn summary_json(
    summary: &impl serde::Serialize,
    selection: Option<&AutoSelection>,
) -> anyhow::Result<String> {
    let mut doc = serde_json::to_value(summary)?;
    if let (Some(s), Some(map)) = (selection, doc.as_object_mut()) {
        map.insert("structure_selection".into(), serde_json::to_value(s.report())?);
    }
    Ok(serde_json::to_string_pretty(&doc)?)
}

/// `--compat FILE|auto`: the corrections to apply, if any (`auto` runs the check on the record,
/// which a live feed cannot give whole).
fn compat_corrections(
    args: &ReplayArgs,
    mapping: &Mapping,
    live: bool,
) -> anyhow::Result<Option<aeroident_pipelines::compat::Corrections>> {
    use aeroident_pipelines::compat::{Corrections, check_record};
    let Some(which) = args.compat.as_deref() else { return Ok(None) };
    if which != "auto" {
        return Ok(Some(Corrections::from_json(Path::new(which))?));
    }
    if live {
        anyhow::bail!("--compat auto needs the whole record; for a live feed give a compat.json");
    }
    eprintln!("compat: checking the record's data compatibility (--compat auto)");
    let (reader, _) = open_log_with_notes(&args.data, args.format, mapping)?;
    let config = aeroident_estimators::compat::CompatConfig::default();
    let (summary, _) = check_record(reader, &config)?;
    for f in &summary.findings {
        eprintln!("compat: {f}");
    }
    Ok(Some(Corrections::from_summary(&summary)?))
}

/// The warning of a run that a signal stopped during `--validate-on`.
fn validation_stopped(interrupt: &crate::interrupt::Interrupt) -> String {
    format!(
        "interrupted by {} during --validate-on: the fit's results are written, the validation on the second record is not done",
        interrupt.signal_name().unwrap_or_default()
    )
}

/// Enters the writing phase of `interrupt` (crate::interrupt: further signals are ignored from
/// here). Returns whether a second signal came first, in which case only the summary is to be
/// written and `warnings` says so; otherwise an `interrupted` run says on stderr what it writes.
fn begin_writing(
    interrupt: Option<&crate::interrupt::Interrupt>,
    interrupted: bool,
    samples_read: usize,
    warnings: &mut aeroident_io::warning::Warnings,
) -> bool {
    let summary_only = interrupt.is_some_and(crate::interrupt::Interrupt::begin_writing);
    if summary_only {
        warnings.push(SUMMARY_ONLY.to_string());
    } else if interrupted {
        eprintln!(
            "interrupted: writing the results of the {samples_read} samples read; a further signal is ignored until they are written"
        );
    }
    summary_only
}

/// The warning (and error) of a run that a second signal stopped before its results were
/// written (crate::interrupt): `summary.json` was written, nothing else.
const SUMMARY_ONLY: &str = "a second signal came before the results were written: only summary.json (and the real-time estimators' estimates.csv) was written, not report.html or the figures";

/// The error ending a run stopped by a signal, `what` saying what was written.
fn stopped(interrupt: &crate::interrupt::Interrupt, what: &str) -> anyhow::Error {
    interrupt
        .error(what)
        .map_or_else(|| anyhow::anyhow!("internal: stopped without a signal"), Into::into)
}

/// Writes the `summary.json` of a run a signal stopped before it had estimates: status
/// `interrupted`, `status_reason` why, the estimates `null`; into `out` (then marked
/// complete), or on stderr without `--out`.
///
/// # Errors
/// Output I/O errors.
fn write_stopped_summary(
    args: &ReplayArgs,
    out: Option<&mut crate::outdir::OutputDir>,
    samples_read: Option<usize>,
    why: &str,
) -> anyhow::Result<()> {
    let summary = serde_json::json!({
        "estimator": args.estimator.name(),
        "model": args.model,
        "status": aeroident_pipelines::replay::STATUS_INTERRUPTED,
        "status_reason": why,
        "samples_read": samples_read,
        "parameters": null,
        "warnings": [why],
    });
    let text = serde_json::to_string_pretty(&summary)?;
    match out {
        Some(o) => {
            let path = o.write_bytes("summary.json", text.as_bytes())?;
            o.finish();
            eprintln!("{why}; wrote {}", path.display());
        }
        None => eprintln!("{text}"),
    }
    Ok(())
}

/// What a batch fit reads and how it fits, owned so that the fit can run on a thread of its
/// own ([`fit_watched`]).
struct BatchInput {
    files: Vec<String>,
    format: Option<LogFormat>,
    mapping: Mapping,
    model: Option<ModelSpec>,
    options: aeroident_pipelines::replay::batch::FitOptions,
}

type Fitted = (aeroident_pipelines::replay::batch::BatchOutcome, Vec<aeroident_io::ReaderReport>);

impl BatchInput {
    /// Opens the records (`-` through `stdin` when given) and fits them.
    fn read_and_fit(
        self,
        mut stdin: Option<crate::interrupt::InterruptibleStdin>,
    ) -> anyhow::Result<Fitted> {
        let mut readers = Vec::new();
        let mut reports = Vec::new();
        for file in &self.files {
            let (reader, report) = match stdin.take_if(|_| file == "-") {
                Some(s) => open_stdin(s, self.format, &self.mapping)?,
                None => open_log_with_report(file, self.format, &self.mapping)?,
            };
            for n in report.notes() {
                eprintln!("note: {n}");
            }
            readers.push(reader);
            reports.push(report);
        }
        let fit = aeroident_pipelines::replay::fit::fit_records(
            readers,
            &self.mapping,
            self.model,
            self.options,
        )?;
        Ok((fit, reports))
    }
}

/// The record on stdin, read through `stdin` (which a signal ends at a line boundary); a
/// binary log is refused as [`open_log_with_report`] refuses it.
fn open_stdin(
    stdin: crate::interrupt::InterruptibleStdin,
    format: Option<LogFormat>,
    mapping: &Mapping,
) -> Result<(aeroident_io::LogReader, aeroident_io::ReaderReport), aeroident_io::FlightDataError> {
    use aeroident_io::log::{asc_reader, read_mat, table_reader};
    let format = format.unwrap_or(LogFormat::Csv);
    let reader = match format {
        LogFormat::Csv => {
            FlightDataReader::new(Box::new(stdin) as Box<dyn std::io::Read>, "-", mapping)?
        }
        LogFormat::Asc => asc_reader(std::io::BufReader::new(stdin), "-", mapping)?,
        LogFormat::Mat => {
            table_reader(read_mat(stdin, "-", mapping.column_names.as_deref())?, mapping)?
        }
        _ => return open_log_with_report("-", Some(format), mapping),
    };
    let report = aeroident_io::ReaderReport {
        file: "-".into(),
        format: format.name().to_string(),
        dropped: Vec::new(),
    };
    Ok((reader, report))
}

/// Runs `fit` (the batch fit, of a file or of stdin) on a thread of its own while answering the
/// signals (crate::interrupt). Reading stdin (`stdin` tells when and how its read ended), the
/// first signal ends the read and the fit runs on what was read. A first signal once the
/// record is read raises `stop`: the fit ends at its next iteration with its last iterate, the
/// bootstrap before its next replica. A second signal abandons the fit at once: `None`.
///
/// # Errors
/// The fit's thread could not start or ended without a result (a panic).
fn fit_watched<T: Send + 'static>(
    fit: impl FnOnce() -> T + Send + 'static,
    interrupt: &crate::interrupt::Interrupt,
    stdin: Option<&crate::interrupt::StdinProgress>,
    stop: &StopFlag,
) -> anyhow::Result<Option<T>> {
    use std::sync::mpsc::RecvTimeoutError;
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("batch-fit".into())
        .stack_size(aeroident_pipelines::WORKER_STACK_BYTES)
        .spawn(move || {
            let _ = tx.send(fit());
        })
        .context("starting the batch fit's thread")?;
    let mut watch = FitWatch::default();
    loop {
        match rx.recv_timeout(std::time::Duration::from_millis(50)) {
            Ok(r) => return Ok(Some(r)),
            Err(RecvTimeoutError::Disconnected) => {
                anyhow::bail!("internal: the batch fit's thread ended without a result")
            }
            Err(RecvTimeoutError::Timeout) => {}
        }
        if interrupt.stop_now() {
            return Ok(None);
        }
        watch.look(interrupt, stdin, stop);
    }
}

/// What [`fit_watched`] has seen and said so far.
#[derive(Default)]
struct FitWatch {
    /// The record is read (stdin ended, or a file).
    read: bool,
    /// The first signal has been answered (it cut stdin, or it raised the stop).
    answered: bool,
}

impl FitWatch {
    /// Notes the end of stdin's read, and raises `stop` on a signal that came once the record
    /// was read (one that ended the read is answered by that).
    fn look(
        &mut self,
        interrupt: &crate::interrupt::Interrupt,
        stdin: Option<&crate::interrupt::StdinProgress>,
        stop: &StopFlag,
    ) {
        use crate::interrupt::StdinEnd;
        let sig = || interrupt.signal_name().unwrap_or_default();
        let again = "a second signal stops at once, writing summary.json alone";
        if !self.read {
            let Some(end) = stdin.map_or(Some(StdinEnd::Closed), |p| p.end()) else { return };
            self.read = true;
            let lines = stdin.map_or(0, |p| p.lines());
            match (end, stdin.is_some()) {
                (StdinEnd::Cut, _) => {
                    self.answered = true;
                    eprintln!(
                        "{}: stdin read ended after {lines} lines; fitting the samples read ({again})",
                        sig()
                    );
                }
                (StdinEnd::Closed, true) => eprintln!("stdin closed after {lines} lines: fitting"),
                (StdinEnd::Closed, false) => {}
            }
        }
        if !self.answered && interrupt.requested() {
            self.answered = true;
            stop.raise();
            eprintln!(
                "{}: stopping the fit at its next iteration (a bootstrap before its next replica), its last iterate reported; {again}",
                sig()
            );
        }
    }
}

/// `--estimator oe | fem`: the batch output-error (or filter-error) fit of the whole record,
/// into `out` (opened) when `--out` is given.
///
/// The record is read and fitted on a thread of its own under the signal handlers
/// ([`fit_watched`]). A signal while stdin is read ends the read and the fit is of the samples
/// read until then; too few to fit, the summary says so with no estimates. A signal during
/// the fit stops it at its next iteration (a bootstrap before its next replica) and its last
/// iterate is written. Either way `summary.json` has status `interrupted` and the exit code is
/// 128 + signal.
fn execute_batch(
    args: &ReplayArgs,
    mapping: &Mapping,
    (model, compat): (Option<ModelSpec>, Option<aeroident_pipelines::compat::Corrections>),
    selection: Option<AutoSelection>,
    interrupt: &crate::interrupt::Interrupt,
    mut out: Option<crate::outdir::OutputDir>,
) -> anyhow::Result<()> {
    let oe = args.estimator == EstimatorKind::Oe;
    let stop = StopFlag::default();
    let options = aeroident_pipelines::replay::batch::FitOptions {
        stop: Some(stop.clone()),
        ..fit_options(args, compat)?
    };
    eprintln!(
        "{} is a batch method: reading the whole record before fitting (not real time)",
        match args.estimator {
            EstimatorKind::Fem => "the filter-error method",
            EstimatorKind::Fdoe => "frequency-domain output error",
            _ => "output error",
        }
    );
    if let Some(n) = options.bootstrap_refits.filter(|_| oe) {
        eprintln!("bootstrap: a filter-error fit for the noise levels, then {n} replicas refitted");
    }
    let input = BatchInput {
        files: std::iter::once(&args.data).chain(&args.and).cloned().collect(),
        format: args.format,
        mapping: mapping.clone(),
        model,
        options,
    };
    let stdin =
        (args.data == "-").then(|| crate::interrupt::InterruptibleStdin::new(interrupt.flag()));
    let progress = stdin.as_ref().map(crate::interrupt::InterruptibleStdin::progress);
    let watched =
        fit_watched(move || input.read_and_fit(stdin), interrupt, progress.as_deref(), &stop)?;
    let Some(fitted) = watched else {
        interrupt.begin_writing();
        let why = format!(
            "a second {} stopped the fit before it ended: no estimates",
            interrupt.signal_name().unwrap_or_default()
        );
        write_stopped_summary(args, out.as_mut(), None, &why)?;
        return Err(stopped(interrupt, "the fit was abandoned; summary.json says so"));
    };
    let cut = progress.as_ref().is_some_and(|p| p.end() == Some(crate::interrupt::StdinEnd::Cut));
    let (mut outcome, reports) = match fitted {
        Ok(f) => f,
        // Nothing to report but why: the summary still says what happened.
        Err(e) if cut || stop.raised() => {
            interrupt.begin_writing();
            let what = match progress.filter(|_| cut) {
                Some(p) => format!(" after {} lines of stdin, too few to fit", p.lines()),
                None => ", with no fit".into(),
            };
            let why = format!(
                "interrupted by {}{what}: {e:#}",
                interrupt.signal_name().unwrap_or_default()
            );
            write_stopped_summary(args, out.as_mut(), None, &why)?;
            return Err(stopped(interrupt, "no fit; summary.json says why"));
        }
        Err(e) => return Err(e),
    };
    let signal = interrupt.signal_name().unwrap_or_default();
    if cut {
        mark_interrupted(&mut outcome.summary, &signal);
    } else if stop.raised() {
        mark_stopped(&mut outcome, &signal);
    }
    write_batch(args, mapping, outcome, reports, Some(interrupt), selection.as_ref(), out)
}

/// The output directory of `--out`, opened (locked, the previous run's files cleared).
fn open_out(args: &ReplayArgs) -> anyhow::Result<Option<crate::outdir::OutputDir>> {
    Ok(args
        .out
        .as_deref()
        .map(|d| crate::outdir::OutputDir::open(d, "replay", &input_paths(args)))
        .transpose()?)
}

/// A batch summary of a fit a signal stopped at a safe point: status `interrupted`, and why,
/// with the fit's own status (how many bootstrap replicas were done is in their own warning).
fn mark_stopped(outcome: &mut aeroident_pipelines::replay::batch::BatchOutcome, signal: &str) {
    use aeroident_estimators::output_error::{NotConverged, Termination};
    let s = &mut outcome.summary;
    let what = match outcome.result.termination {
        Termination::NotConverged(NotConverged::Stopped)
        | Termination::CostConverged(NotConverged::Stopped) => format!(
            "during the fit: the estimates are its last iterate ({} iterations)",
            s.iterations.len().saturating_sub(1)
        ),
        _ => "after the fit had ended: the estimates are its result, and the warnings say what the stop cut short".to_string(),
    };
    let why = format!(
        "interrupted by {signal} {what}; the fit's own status was `{}`{}",
        s.status,
        s.status_reason.as_deref().map_or(String::new(), |r| format!(" ({r})"))
    );
    s.warnings.push(why.clone());
    s.status = aeroident_pipelines::replay::STATUS_INTERRUPTED.to_string();
    s.status_reason = Some(why);
}

/// A batch summary of a record a signal cut short: status `interrupted`, and why, with the
/// fit's own status.
fn mark_interrupted(s: &mut aeroident_pipelines::replay::batch::BatchSummary, signal: &str) {
    let why = format!(
        "interrupted after {} rows by {signal}: the estimates are those of the samples read until then; the fit's own status was `{}`{}",
        s.samples_read,
        s.status,
        s.status_reason.as_deref().map_or(String::new(), |r| format!(" ({r})"))
    );
    s.warnings.push(why.clone());
    s.status = aeroident_pipelines::replay::STATUS_INTERRUPTED.to_string();
    s.status_reason = Some(why);
}

/// The batch fit's options from the command line.
fn fit_options(
    args: &ReplayArgs,
    compat: Option<aeroident_pipelines::compat::Corrections>,
) -> anyhow::Result<aeroident_pipelines::replay::batch::FitOptions> {
    Ok(aeroident_pipelines::replay::batch::FitOptions {
        method: match args.estimator {
            EstimatorKind::Fem => BatchMethod::Fem,
            EstimatorKind::Fdoe => BatchMethod::Fdoe {
                band_hz: args
                    .band_hz
                    .unwrap_or(aeroident_estimators::output_error::frequency::DEFAULT_BAND_HZ),
            },
            _ => BatchMethod::Oe,
        },
        initial_states: args.initial_states.unwrap_or(InitialStatesArg::FirstSample).to_config(),
        bootstrap_refits: args.bootstrap.map(|n| n as usize),
        max_iterations: args.max_iterations.map(|n| n as usize),
        process_noise: args
            .process_noise
            .as_deref()
            .map(aeroident_pipelines::replay::batch::parse_process_noise_states)
            .transpose()
            .map_err(|e| anyhow::anyhow!("--process-noise: {e}"))?,
        gain_constraint: !args.no_gain_constraint,
        compat,
        windows: args.windows.clone(),
        spike_screen: (!args.no_spike_screen)
            .then(aeroident_pipelines::record::outliers::SpikeScreen::default),
        robust: args.robust.then(aeroident_estimators::output_error::Huber::default),
        stop: None,
    })
}

/// Validates (`--validate-on`), prints and writes a batch fit's results into `out` (opened
/// before the fit), else on stdout and stderr. With `interrupt`: an interrupted fit skips
/// `--validate-on`, further signals are ignored
/// while the results are written, and a second signal before then leaves the report out
/// (crate::interrupt); an interrupted run ends with the [`crate::interrupt::Interrupted`] error.
fn write_batch(
    args: &ReplayArgs,
    mapping: &Mapping,
    mut outcome: aeroident_pipelines::replay::batch::BatchOutcome,
    reports: Vec<aeroident_io::ReaderReport>,
    interrupt: Option<&crate::interrupt::Interrupt>,
    selection: Option<&AutoSelection>,
    out: Option<crate::outdir::OutputDir>,
) -> anyhow::Result<()> {
    outcome.summary.reader = reports;
    let mut interrupted = outcome.summary.status == aeroident_pipelines::replay::STATUS_INTERRUPTED;
    match &args.validate_on {
        Some(_) if interrupted => {
            let w = "the run was interrupted: --validate-on not done".to_string();
            outcome.summary.warnings.push(w);
        }
        Some(path) => {
            let (name, m, fitted) = (path.display().to_string(), mapping.clone(), outcome.clone());
            let stage = move || -> anyhow::Result<_> {
                let (reader, notes) = open_log_with_notes(&name, None, &m)?;
                for n in &notes {
                    eprintln!("note: {n}");
                }
                Ok(aeroident_pipelines::replay::batch::validate_on(reader, &fitted)?)
            };
            match interrupt {
                Some(i) => match stage_watched(i, stage)? {
                    Some(v) => outcome.summary.validation_on = Some(v?),
                    None => {
                        interrupted = true;
                        let why = validation_stopped(i);
                        let s = &mut outcome.summary;
                        s.warnings.push(why.clone());
                        s.status = aeroident_pipelines::replay::STATUS_INTERRUPTED.to_string();
                        s.status_reason = Some(why);
                    }
                },
                None => outcome.summary.validation_on = Some(stage()?),
            }
        }
        None => {}
    }
    eprintln!("model: {}", outcome.model.name);
    let s = &outcome.summary;
    for v in std::iter::once(&s.validation).chain(s.validation_on.iter()) {
        eprint!("{}", validation_block(v));
    }
    for w in &s.warnings {
        eprintln!("warning: {w}");
    }
    let summary_only = begin_writing(
        interrupt,
        interrupted,
        outcome.summary.samples_read,
        &mut outcome.summary.warnings,
    );
    let text = summary_json(&outcome.summary, selection)?;
    match out {
        Some(mut out) => {
            let path = out.write_bytes("summary.json", text.as_bytes())?;
            if let Some(s) = selection {
                out.write_bytes("model.toml", s.model.to_toml().as_bytes())?;
            }
            if summary_only {
                out.finish();
                eprintln!("wrote {}", path.display());
            } else {
                write_batch_report(args, &outcome, &mut out)?;
            }
        }
        None => {
            let table = match &outcome.frequency {
                Some(f) => f.to_string(),
                None => outcome.result.to_string(),
            };
            crate::cli::print_stdout(&table)?;
            eprintln!("{text}");
        }
    }
    match interrupt {
        Some(i) if summary_only => Err(stopped(i, SUMMARY_ONLY)),
        Some(i) if interrupted => {
            Err(stopped(i, "the results so far were written, with status `interrupted`"))
        }
        _ => Ok(()),
    }
}

/// The batch fit's report, figures and table (`summary.json` is written), and its line on
/// stderr; marks `out` complete.
fn write_batch_report(
    args: &ReplayArgs,
    outcome: &aeroident_pipelines::replay::batch::BatchOutcome,
    out: &mut crate::outdir::OutputDir,
) -> anyhow::Result<()> {
    let name = Path::new(&args.data)
        .file_name()
        .map_or(args.data.clone(), |n| n.to_string_lossy().into_owned());
    let title = format!("{name} — {} — {}", args.estimator.name(), outcome.model.name);
    let source = crate::report::Source { data: &args.data, mapping: &args.map };
    let results = crate::report::batch::write(&source, outcome, &title, out)?;
    out.finish();
    crate::cli::print_stdout(&crate::table::render(&results))?;
    eprintln!(
        "{}: {} samples in {} manoeuvre(s), {} rejected, {} iterations in {:.3} s; wrote {}",
        args.data,
        outcome.summary.samples_read,
        outcome.summary.manoeuvres,
        outcome.summary.samples_rejected,
        outcome.summary.iterations.len().saturating_sub(1),
        outcome.summary.fit_wall_s,
        out.path().display()
    );
    Ok(())
}
