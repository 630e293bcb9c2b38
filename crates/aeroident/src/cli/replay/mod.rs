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
//!                  [--validate-on <data2.csv>] [--validate-window START:END …]
//!                  [--window START:END … | --window auto] [--and <more.csv> …]
//!                  [--cross-check | --no-cross-check] [--no-spike-screen] [--robust]
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

mod batch;
mod online;
mod stop;

use aeroident_estimators::flight_model::N_STATES;
use aeroident_estimators::output_error::InitialStates;
use aeroident_io::{LogFormat, Mapping};
use aeroident_pipelines::estimators::{
    EstimatorKind, EstimatorOptions, OptionError, option_list, parse_options, quoted_list,
};
use aeroident_pipelines::job::cross_check::Panel;
use aeroident_pipelines::job::fit::FitJob;
use aeroident_pipelines::job::replay::ReplayJob;
use aeroident_pipelines::job::{CompatSource, ModelChoice, Ran, Records, ValidateOn};
use aeroident_pipelines::replay::batch::FitOptions;
use aeroident_pipelines::replay::{DerivativeSource, Pacing, ReplayObserver, ReplayOptions};
use aeroident_pipelines::window::TimeWindow;
use anyhow::Context;
use std::path::{Path, PathBuf};
use stop::{Stderr, Watched, stopped_before_fit};

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
    /// Log format (csv, asc, mat, ulog, dataflash, tlog); default: by the file's extension
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
    /// Any option of the estimator as `KEY=VALUE` (the scenario file's keys, a TOML value:
    /// `parameter_walk_per_sqrt_s=0.01`, `grid_hz=[0.1, 2.0, 0.04]`); repeat it for more. The
    /// estimator registry refuses a key the estimator does not take, listing those it takes.
    #[arg(long = "estimator-option", value_name = "KEY=VALUE", value_parser = parse_key_value)]
    pub estimator_options: Vec<(String, toml::Value)>,
    /// Pace the replay at the record's own sample rate.
    #[arg(long)]
    pub realtime: bool,
    /// A time window `START:END` (record seconds) of the record to use; repeat it for several
    /// manoeuvres of one flight, each window its own manoeuvre (own initial state). Or `auto`:
    /// the manoeuvres `aeroident inspect` finds on the mapping's surfaces (docs/inspect.md),
    /// printed as the windows chosen. Default: the whole record.
    #[arg(long = "window", value_name = "START:END|auto", value_parser = super::auto_window::parse, allow_hyphen_values = true)]
    pub window_specs: Vec<super::auto_window::WindowSpec>,
    /// The time windows used: `--window`'s, with `auto` resolved by [`execute`].
    #[arg(skip)]
    pub windows: Vec<TimeWindow>,
    /// `--estimator oe | fem`: a further record of the same aircraft (same mapping and
    /// format), fitted together with the first, each file a manoeuvre of its own; repeat it
    /// for more. `--compat auto` is checked on all of them (within `--window`) jointly and
    /// applied to all.
    #[arg(long = "and", value_name = "FILE")]
    pub and: Vec<String>,
    /// Fit a record given twice (the same file, or two files of the same content) as if new
    /// data; without it such a record is refused, as it would shrink every σ by √2.
    #[arg(long)]
    pub allow_duplicate_records: bool,
    /// Run the whole panel, the filter-error method (fem) too. By default the record's other
    /// methods but fem (rls, rls-iv, ekf, oe, fdoe; the real-time ones only without --and)
    /// run after the fit with the same model and each estimate is judged beside theirs: one
    /// the methods do not confirm is flagged with the camps and the tested cause (regressor
    /// noise, the EKF's noise model, process noise), in the table, the warnings and
    /// `summary.json` `cross_check`. Not for a live feed or stdin.
    #[arg(long, conflicts_with = "no_cross_check")]
    pub cross_check: bool,
    /// Run no other method beside the fit: faster, but a disagreement between methods can
    /// no longer flag an estimate (the summary says the panel was not run).
    #[arg(long)]
    pub no_cross_check: bool,
    /// A second record (same mapping) not used for the fit: the final estimates are applied
    /// to it and the validation metrics reported under `validation_on` in the summary.
    #[arg(long, value_name = "FILE2")]
    pub validate_on: Option<PathBuf>,
    /// A time window `START:END` of the validation record (`--validate-on`, else the fitted
    /// record itself: held-out manoeuvres of the same flight); repeat it for several. A window
    /// that overlaps the fitted data is validated with a warning that it is no independent check.
    #[arg(long = "validate-window", value_name = "START:END", value_parser = parse_window, allow_hyphen_values = true)]
    pub validate_windows: Vec<TimeWindow>,
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
    /// `estimates.csv` (and the live stream) at most one row per this many seconds of record
    /// time, the first and the last row always written (the last is the summary's final
    /// estimate); `0`: every estimate. Default: 0.1 for a file
    /// (`aeroident_pipelines::replay::DEFAULT_ESTIMATES_EVERY_S`), every estimate for a live
    /// feed. A 1-hour six-axis record at 100 Hz writes 48 MB at 0.1 (measured) and about ten
    /// times that at every estimate.
    #[arg(long = "estimates-every", value_name = "S", value_parser = parse_every_s)]
    pub estimates_every_s: Option<f64>,
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
        aeroident_report::note!("{line}");
    }

    fn warning(&mut self, text: &str) {
        aeroident_report::note!("warning: {text}");
    }
}

/// `KEY=VALUE` with a TOML value (a bare word is read as a string). The key is a bare name
/// (letters, digits, `_`), and the value one TOML value: text that would read as more than
/// one (a newline and a second `KEY=VALUE`) is refused, not cut to its first.
fn parse_key_value(text: &str) -> Result<(String, toml::Value), String> {
    let (key, value) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}`: give KEY=VALUE, e.g. parameter_walk_per_sqrt_s=0.01"))?;
    let key = key.trim();
    let value = value.trim();
    if key.is_empty() || !key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(format!("`{text}`: the key must be a name of letters, digits and `_`"));
    }
    if value.is_empty() || value.chars().any(char::is_control) {
        return Err(format!(
            "`{text}`: give one value after `{key}=` on one line (repeat --estimator-option for another key)"
        ));
    }
    let parsed = toml::from_str::<toml::Table>(&format!("v = {value}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(value.to_string()));
    Ok((key.to_string(), parsed))
}

fn parse_window(text: &str) -> Result<TimeWindow, String> {
    TimeWindow::parse(text)
}

/// `--estimates-every`: a time in seconds, finite and not negative (`0`: every estimate).
fn parse_every_s(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(s) if s.is_finite() && s >= 0.0 => Ok(s),
        _ => Err(format!(
            "`{text}`: give a time in seconds, finite and 0 or above (0: every estimate)"
        )),
    }
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

/// Runs `aeroident replay`: the arguments become a replay job or a batch-fit job
/// ([`aeroident_pipelines::job`]), run with the console's signals and output.
///
/// # Errors
/// Mapping, model-file or data errors (naming file, row or line, and column or key),
/// estimator errors (not available, bad option, diverged), and output I/O errors.
pub fn execute(args: ReplayArgs) -> anyhow::Result<()> {
    execute_with(args, None)
}

/// [`execute`] with a live view watching the real-time estimator (`aeroident live`): `view`
/// sees every sample beside the console, and gets the final summary before the results are
/// written. A batch fit is refused with it.
///
/// # Errors
/// As [`execute`].
pub fn execute_with(
    mut args: ReplayArgs,
    view: Option<&mut aeroident_pipelines::live::LiveObserver>,
) -> anyhow::Result<()> {
    let mapping = Mapping::from_path(&args.map)?;
    args.windows = super::auto_window::resolve(
        &args.window_specs,
        &args.data,
        args.format,
        &mapping,
        !args.and.is_empty(),
        super::auto_window::axes_of_model(args.model.as_deref()),
    )?;
    let mavlink = aeroident_io::record::is_mavlink(&args.data);
    let live = args.data == "-" || mavlink;
    check_combination(&args, mavlink, view.is_some())?;
    let records = records(&args, mapping, live);
    // The options are parsed and the job checks what does not go together before the output
    // directory is touched.
    let (online, fit) = if args.estimator.is_batch() {
        let fit = fit_options(&args)?;
        fit.check()?;
        (None, Some(fit))
    } else {
        let job = replay_job(&args, records.clone())?;
        job.check()?;
        (Some(job), None)
    };
    // Lock the directory and clear the previous run's files before reading anything: a
    // directory that cannot take the results is refused before a long fit, not after it.
    records.check_distinct()?;
    let mut out_dir = open_out(&args)?;
    // From here a signal ends the run gracefully (crate::interrupt): the steps over the whole
    // record before the estimator too, with a summary saying so.
    let interrupt = crate::interrupt::Interrupt::install().context("installing signal handlers")?;
    let mut guard = Watched(&interrupt);
    let Some(job) = online else {
        let job = fit_job(&args, records, fit.context("internal: no batch fit options")?);
        return match job.prepare(&mut guard, &mut Stderr)? {
            Ran::Done(prepared) => batch::execute(&args, job, prepared, &interrupt, out_dir),
            Ran::Stopped(step) => {
                Err(stopped_before_fit(&args, &interrupt, out_dir.as_mut(), step))
            }
        };
    };
    let prepared = match job.prepare(&mut guard, &mut Stderr)? {
        Ran::Done(prepared) => prepared,
        Ran::Stopped(step) => {
            return Err(stopped_before_fit(&args, &interrupt, out_dir.as_mut(), step));
        }
    };
    if !live && args.out.is_none() {
        anyhow::bail!("give --out <dir> (or read `-` from stdin for a live feed on stdout)");
    }
    online::execute(&args, &job, prepared, (&interrupt, view), out_dir)
}

/// The batch-fit job of the command line's records and the fit's options.
fn fit_job(args: &ReplayArgs, records: Records, options: FitOptions) -> FitJob {
    FitJob {
        records,
        model: model_choice(args),
        compat: args.compat.as_deref().map(CompatSource::from_arg),
        options,
        cross_check: Panel::from_flags(args.cross_check, args.no_cross_check),
        validate_on: validate_on(args),
    }
}

/// The records of the command line: `DATA` and `--and`, in `--format`, through `mapping`.
fn records(args: &ReplayArgs, mapping: Mapping, live: bool) -> Records {
    Records {
        data: args.data.clone(),
        and: args.and.clone(),
        format: args.format,
        mapping,
        live,
        allow_duplicates: args.allow_duplicate_records,
        held: None,
    }
}

/// How the model is chosen: `--model`, `--select`, `--candidates`, `--knots-deg` (the
/// selection differentiates with `--diff-window`).
fn model_choice(args: &ReplayArgs) -> ModelChoice {
    ModelChoice {
        model: args.model.clone(),
        select: args.select.clone(),
        candidates: args.candidates.clone(),
        knots_deg: args.knots_deg.clone(),
        diff_window: args.diff_window,
    }
}

/// The replay job of the real-time estimators' arguments.
///
/// # Errors
/// An estimator option the estimator does not take, or of the wrong type.
fn replay_job(args: &ReplayArgs, records: Records) -> anyhow::Result<ReplayJob> {
    let estimator_options = estimator_options(args)?;
    let options = ReplayOptions {
        estimator: args.estimator,
        model: None,
        estimator_options,
        derivatives: args.derivatives,
        diff_window: args.diff_window,
        pacing: if args.realtime { Pacing::Realtime } else { Pacing::Unpaced },
        compat: None,
        windows: args.windows.clone(),
        spike_screen: (!args.no_spike_screen)
            .then(aeroident_pipelines::record::outliers::SpikeScreen::default),
        estimates_only: false,
    };
    Ok(ReplayJob {
        records,
        model: model_choice(args),
        compat: args.compat.as_deref().map(CompatSource::from_arg),
        options,
        cross_check: Panel::from_flags(args.cross_check, args.no_cross_check),
        validate_on: validate_on(args),
    })
}

/// The validation record and windows of `--validate-on` and `--validate-window`.
fn validate_on(args: &ReplayArgs) -> Option<ValidateOn> {
    let path = args.validate_on.as_ref().map(|p| p.display().to_string());
    ValidateOn::from_args(path, args.validate_windows.clone(), &args.data)
}

/// Refuses flags that do not go together (a batch fit of a live feed or under a live view, a
/// batch fit's flag with a real-time estimator), before anything is opened; which batch method
/// takes which option is the batch fit's parser's ([`fit_options`]).
pub(super) fn check_combination(
    args: &ReplayArgs,
    mavlink: bool,
    view: bool,
) -> anyhow::Result<()> {
    if view && args.estimator.is_batch() {
        anyhow::bail!(
            "the live view watches a real-time estimator; --estimator {} is a batch fit of the whole record (use `aeroident replay`)",
            args.estimator.name()
        );
    }
    if args.estimator.is_batch() && mavlink {
        anyhow::bail!(
            "--estimator {} is a batch fit of a whole record, not for a live MAVLink feed",
            args.estimator.name()
        );
    }
    if args.estimator.is_batch() && args.cross_check && args.data == "-" {
        // The other methods read the record again: stdin can be read once.
        anyhow::bail!(
            "--cross-check runs the record's other methods on it again: give a file, not stdin"
        );
    }
    if args.estimator.is_batch() {
        return Ok(());
    }
    check_online_combination(args)
}

/// The flags that are options of the estimator ([`EstimatorKind::options`]) or of the batch
/// fit ([`aeroident_pipelines::replay::fit::FIT_OPTION_KEYS`]), each with its key.
const ESTIMATOR_OPTION_FLAGS: [(&str, &str); 9] = [
    ("forgetting", "--forgetting"),
    ("instrument_delay", "--instrument-delay"),
    ("initial_states", "--initial-states"),
    ("bootstrap_refits", "--bootstrap"),
    ("max_iterations", "--max-iterations"),
    ("process_noise", "--process-noise"),
    ("gain_constraint", "--no-gain-constraint"),
    ("robust", "--robust"),
    ("band_hz", "--band-hz"),
];

/// The flag of the registry's option `key`, as typed (`--estimator-option KEY` for those
/// without a flag of their own).
fn option_flag(key: &str) -> String {
    ESTIMATOR_OPTION_FLAGS
        .iter()
        .find(|f| f.0 == key)
        .map_or_else(|| format!("--estimator-option {key}"), |f| f.1.to_string())
}

/// The estimator's options from the command line: `--forgetting`, `--instrument-delay` and
/// every `--estimator-option KEY=VALUE`, parsed by the registry for `--estimator`
/// ([`parse_options`]), which knows which kind takes which: one the kind does not take is
/// refused (it would be ignored), naming the flag, the kind and the options it takes. The
/// values' ranges are checked with the replay's other numbers, naming the value exactly as
/// typed (the delay as given, past an i64).
fn estimator_options(args: &ReplayArgs) -> anyhow::Result<EstimatorOptions> {
    let typed = option_pairs(args)?;
    let pairs: Vec<_> = typed.iter().map(|t| (t.key, t.value.clone())).collect();
    let options = parse_options(args.estimator, pairs).map_err(|e| match e {
        OptionError::Unknown { kind, key } => anyhow::anyhow!(
            "{} is not an option of --estimator {}, which takes {} (it would be ignored)",
            as_typed(&typed, &key),
            kind.name(),
            option_list(kind)
        ),
        OptionError::Invalid { key, reason, .. } => {
            anyhow::anyhow!("option `{}`: {reason}", as_typed(&typed, &key))
        }
    })?;
    // The delay as typed, past an i64: the replay's range check names it exactly.
    Ok(EstimatorOptions {
        instrument_delay: args.instrument_delay.or(options.instrument_delay),
        ..options
    })
}

/// One estimator or fit option from the command line: its registry key, its value, and the
/// option as the user typed it (`--forgetting 0.98`, `--estimator-option forgetting=0.99`).
struct TypedOption<'a> {
    key: &'a str,
    value: toml::Value,
    typed: String,
}

/// Every estimator and batch-fit option given, from its own flag or `--estimator-option`, as
/// [`TypedOption`]s. One setting has one value: a key given twice (a flag and an
/// `--estimator-option` of the same key, or the same `--estimator-option` repeated) is refused
/// naming both, instead of one silently winning.
fn option_pairs(args: &ReplayArgs) -> anyhow::Result<Vec<TypedOption<'_>>> {
    use toml::Value as V;
    let states = args.initial_states.map(|s| match s {
        InitialStatesArg::FirstSample => "first-sample",
        InitialStatesArg::Estimate => "estimate",
    });
    // A delay beyond an i64 is out of range all the same; the range check names it.
    let delay = args.instrument_delay.map(|d| i64::try_from(d).unwrap_or(i64::MAX));
    let flags: [(&str, Option<V>); 9] = [
        ("initial_states", states.map(|s| V::String(s.into()))),
        ("bootstrap_refits", args.bootstrap.map(|n| V::Integer(n.into()))),
        ("max_iterations", args.max_iterations.map(|n| V::Integer(n.into()))),
        ("process_noise", args.process_noise.clone().map(V::String)),
        ("gain_constraint", args.no_gain_constraint.then_some(V::Boolean(false))),
        ("robust", args.robust.then_some(V::Boolean(true))),
        ("band_hz", args.band_hz.map(|(a, b)| V::Array(vec![a.into(), b.into()]))),
        ("forgetting", args.forgetting.map(V::Float)),
        ("instrument_delay", delay.map(V::Integer)),
    ];
    let mut typed: Vec<TypedOption> = Vec::new();
    for (key, value) in flags {
        if let Some(value) = value {
            let shown = match &value {
                V::Boolean(_) => option_flag(key),
                V::String(s) => format!("{} {s}", option_flag(key)),
                v => format!("{} {v}", option_flag(key)),
            };
            typed.push(TypedOption { key, value, typed: shown });
        }
    }
    for (key, value) in &args.estimator_options {
        let shown = format!("--estimator-option {key}={value}");
        typed.push(TypedOption { key: key.as_str(), value: value.clone(), typed: shown });
    }
    for (k, t) in typed.iter().enumerate() {
        if let Some(first) = typed[..k].iter().find(|f| f.key == t.key) {
            anyhow::bail!(
                "`{}` is set twice, by {} and by {}: give it once",
                t.key,
                first.typed,
                t.typed
            );
        }
    }
    Ok(typed)
}

/// The option of registry key `key` as the user typed it (its flag, or `--estimator-option
/// KEY`), for an error about it.
fn as_typed(typed: &[TypedOption], key: &str) -> String {
    match typed.iter().find(|t| t.key == key) {
        Some(t) if t.typed.starts_with("--estimator-option") => format!("--estimator-option {key}"),
        _ => option_flag(key),
    }
}

/// [`check_combination`] for the real-time estimators: a batch fit's option (one of a batch
/// method's [`EstimatorKind::fit_options`]) refused, naming the methods that take it.
fn check_online_combination(args: &ReplayArgs) -> anyhow::Result<()> {
    for t in option_pairs(args)? {
        let takers: Vec<&str> = <EstimatorKind as aeroident_pipelines::Named>::ALL
            .iter()
            .filter(|k| k.fit_options().contains(&t.key))
            .map(|k| k.name())
            .collect();
        if let [init @ .., last] = &takers[..] {
            let kinds = if init.is_empty() {
                last.to_string()
            } else {
                format!("{} or {last}", init.join(", "))
            };
            anyhow::bail!(
                "{} applies to the batch fit{} (--estimator {kinds}), not to --estimator {}",
                as_typed(std::slice::from_ref(&t), t.key),
                if init.is_empty() { "" } else { "s" },
                args.estimator.name()
            );
        }
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

/// The output directory of `--out`, opened (locked, the previous run's files cleared).
fn open_out(args: &ReplayArgs) -> anyhow::Result<Option<crate::outdir::OutputDir>> {
    Ok(args
        .out
        .as_deref()
        .map(|d| crate::outdir::OutputDir::open(d, "replay", &input_paths(args)))
        .transpose()?)
}

/// The batch fit's options from the command line (the job sets the corrections): its flags and
/// every `--estimator-option KEY=VALUE` as key/value pairs, parsed by the one parser of a batch
/// fit's options ([`FitOptions::from_pairs`]), which refuses a key no batch fit has; the time
/// windows and the spike screen are the record's.
fn fit_options(args: &ReplayArgs) -> anyhow::Result<FitOptions> {
    let typed = option_pairs(args)?;
    let pairs = typed.iter().map(|t| (t.key, t.value.clone())).collect::<Vec<_>>();
    let options = FitOptions::from_pairs(args.estimator, pairs).map_err(|e| match e {
        OptionError::Unknown { kind, key } => anyhow::anyhow!(
            "{} is not an option of --estimator {}, which takes {} (it would be ignored)",
            as_typed(&typed, &key),
            kind.name(),
            quoted_list(kind.fit_options())
        ),
        OptionError::Invalid { key, reason, .. } => {
            anyhow::anyhow!("option `{}`: {reason}", as_typed(&typed, &key))
        }
    })?;
    let spike_screen =
        (!args.no_spike_screen).then(aeroident_pipelines::record::outliers::SpikeScreen::default);
    Ok(FitOptions { windows: args.windows.clone(), spike_screen, ..options })
}
