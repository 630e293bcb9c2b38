//! `aeroident live`: the replay job of `aeroident replay` with a live control-room view served
//! on a loopback address.
//!
//! ```text
//! aeroident live <data|-|mavlink:udp:HOST:PORT> --map <map.toml> --out <dir>
//!                [--serve 127.0.0.1:8321] [--speed N] [--linger-s S]
//!                [--sigma-fraction F] [--hold-s T] [--no-live-cross-check]
//!                [any option of `replay`]
//! ```
//! While the feed runs through the real-time estimator, `http://ADDR/` shows each
//! derivative's estimate with its ±2σ band over time (and the reference where a model file
//! gives one), its state (waiting for excitation / converging / identified / flagged with the
//! reason, [`aeroident_pipelines::live::phase`]), the control inputs and their excitation, and
//! the feed's counts (rows read and rejected, gaps; a MAVLink link's datagrams, losses and
//! drops) and the running cross-check (the record's other real-time methods following the
//! feed, [`aeroident_pipelines::live::panel`]), updated ten times a second
//! (`live/server.rs`). A browser that connects late gets the whole history first. The bound
//! address is printed on stderr (`--serve 127.0.0.1:0` takes any free port). A recorded file is paced at `--speed` × real time (default 1); stdin and a
//! MAVLink feed come at their own pace. Ctrl-C or the feed's end writes the usual outputs of
//! `replay` into `--out`; every connected page then gets the final verdicts (or what stopped
//! the job) before the server closes, and `--linger-s` keeps the page served that long
//! afterwards (Ctrl-C ends it sooner). The page is one self-contained HTML file with no external resource.

mod server;

use super::replay::ReplayArgs;
use aeroident_pipelines::live::pace::Pace;
use aeroident_pipelines::live::phase::PhaseRule;
use aeroident_pipelines::live::{LiveConfig, LiveObserver, LiveState};
use anyhow::Context;
use std::net::SocketAddr;
use std::time::{Duration, Instant};

/// Arguments of `aeroident live`.
#[derive(Debug, Clone, clap::Args)]
pub struct LiveArgs {
    /// The replay: every argument of `aeroident replay` (a real-time estimator).
    #[command(flatten)]
    pub replay: ReplayArgs,
    /// Where to serve the page: a loopback address and port (port 0: any free one; the URL
    /// is printed on stderr).
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:8321")]
    pub serve: SocketAddr,
    /// Pace a recorded file at N × real time (default 1; stdin and a MAVLink feed come at
    /// their own pace).
    #[arg(long, value_name = "N")]
    pub speed: Option<f64>,
    /// Keep serving the page this long after the feed's end and the outputs, s (Ctrl-C ends
    /// it sooner).
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    pub linger_s: f64,
    /// A derivative is identified when σ ≤ this fraction of |estimate| …
    #[arg(long, value_name = "F", default_value_t = PhaseRule::default().sigma_fraction)]
    pub sigma_fraction: f64,
    /// … continuously for this long, s, with the estimate within that band.
    #[arg(long, value_name = "T", default_value_t = PhaseRule::default().hold_s)]
    pub hold_s: f64,
    /// Do not run the record's other real-time methods beside the estimator while the feed
    /// runs (by default they follow it and the cross-check flags, once a second of record
    /// time, the derivatives they split on).
    #[arg(long)]
    pub no_live_cross_check: bool,
}

/// Runs `aeroident live` (module doc).
///
/// # Errors
/// A non-loopback address or one that cannot be bound, bad pacing or state options, and
/// every error of `aeroident replay`.
pub fn execute(args: LiveArgs) -> anyhow::Result<()> {
    let pace = pacing(&args)?;
    let rule = PhaseRule { sigma_fraction: args.sigma_fraction, hold_s: args.hold_s };
    // A σ above the estimate itself says nothing is known: no fraction above 1 identifies.
    if !(rule.sigma_fraction > 0.0 && rule.sigma_fraction <= 1.0) {
        anyhow::bail!(
            "--sigma-fraction must be > 0 and at most 1, got {}",
            aeroident_io::message::short(rule.sigma_fraction)
        );
    }
    if !(rule.hold_s >= 0.0 && rule.hold_s.is_finite()) {
        anyhow::bail!(
            "--hold-s must be ≥ 0 s (finite), got {}",
            aeroident_io::message::short(rule.hold_s)
        );
    }
    if !(args.linger_s >= 0.0 && args.linger_s.is_finite()) {
        anyhow::bail!("--linger-s must be ≥ 0 s (finite), got {}", args.linger_s);
    }
    if !args.serve.ip().is_loopback() {
        anyhow::bail!(
            "--serve {}: the live view serves loopback addresses only (127.0.0.1, [::1]); it has no access control",
            args.serve
        );
    }
    // Refused before the server starts and prints its address.
    let mavlink = aeroident_io::record::is_mavlink(&args.replay.data);
    super::replay::check_combination(&args.replay, mavlink, true)?;
    let spec = model_spec(&args.replay);
    let shared = LiveState::new(LiveConfig { rule, ..Default::default() }, spec).shared();
    let server = server::start(args.serve, shared.clone())
        .with_context(|| format!("serving the live view on {}", args.serve))?;
    aeroident_report::note!("live view on http://{}/", server.addr());
    let mut observer =
        LiveObserver::new(shared.clone(), pace).with_cross_check(!args.no_live_cross_check);
    let result = super::replay::execute_with(args.replay, Some(&mut observer));
    let interrupted =
        result.as_ref().is_err_and(|e| e.downcast_ref::<crate::interrupt::Interrupted>().is_some());
    if let Err(e) = &result {
        // A job that ended without its summary's verdicts still ends the page's stream, with
        // what stopped it; a concluded view keeps the summary's status.
        let status = if interrupted { "interrupted" } else { "failed" };
        server::lock(&shared).abandon(status, &format!("{e:#}"));
    }
    if !interrupted {
        linger(args.linger_s)?;
    }
    if !server.close(CLOSE_WAIT) {
        aeroident_report::note!(
            "warning: live view: a client did not take the final update within {} s",
            CLOSE_WAIT.as_secs()
        );
    }
    result
}

/// How long the end waits for every connected page to take its final update: ample for a
/// client on the loopback reading as it should, bounded for one that stopped reading.
const CLOSE_WAIT: Duration = Duration::from_secs(10);

/// The pace of a recorded file (`--speed`, default 1×); none for stdin and a MAVLink feed.
fn pacing(args: &LiveArgs) -> anyhow::Result<Option<Pace>> {
    let feed = args.replay.data == "-" || aeroident_io::record::is_mavlink(&args.replay.data);
    match args.speed {
        Some(_) if feed => anyhow::bail!(
            "--speed paces a recorded file; {} comes at its own pace",
            args.replay.data
        ),
        Some(s) if args.replay.realtime => anyhow::bail!(
            "--speed {s} paces the file at {s} × real time and --realtime at 1×: give one"
        ),
        Some(s) => {
            Pace::new(s).map(Some).with_context(|| format!("--speed must be a number > 0, got {s}"))
        }
        None if feed || args.replay.realtime => Ok(None),
        None => Ok(Pace::new(1.0)),
    }
}

/// The model file given with `--model` (its references and plausible ranges), if any; a
/// preset or `auto` gives none here (the view then uses the conventional ranges). A file that
/// does not read is left to the replay, which reports it.
fn model_spec(args: &ReplayArgs) -> Option<aeroident_io::ModelSpec> {
    let m = args.model.as_deref()?;
    if m.starts_with("auto") || aeroident_io::ModelSpec::preset(m).is_some() {
        return None;
    }
    aeroident_io::ModelSpec::from_arg(m).ok()
}

/// Serves on for `linger_s` after the run, or until a signal.
fn linger(linger_s: f64) -> anyhow::Result<()> {
    if linger_s <= 0.0 {
        return Ok(());
    }
    let interrupt = crate::interrupt::Interrupt::install().context("installing signal handlers")?;
    aeroident_report::note!("live view: serving {linger_s} s more (Ctrl-C ends it)");
    let end = Instant::now() + Duration::from_secs_f64(linger_s.min(1e9));
    while Instant::now() < end && !interrupt.requested() {
        std::thread::sleep(Duration::from_millis(50));
    }
    Ok(())
}
