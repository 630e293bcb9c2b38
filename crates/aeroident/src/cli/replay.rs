//! `aeroident replay`: feed a recorded flight to an online estimator sample by sample.
//!
//! ```text
//! aeroident replay <data.csv|-> --map <map.toml> [--out <dir>]
//!                  [--model longitudinal|lateral|six-axis|FILE]
//!                  [--estimator rls|ftr|ekf|smpe|smpe-corrected|gradient|oe] [--forgetting λ]
//!                  [--derivatives auto|differentiate] [--diff-window N] [--realtime]
//! ```
//! Writes `<dir>/estimates.csv`, `<dir>/summary.json` and `<dir>/estimates.png` (estimates with
//! ±2σ). With `-` the record is read from stdin and one CSV line of estimates per sample is
//! written to stdout (a live feed: buffered, flushed per line with `--realtime`; the history
//! kept for the figure and the settling times is bounded, see `History`); the summary then goes to stderr unless
//! `--out` is given. The model used is printed on stderr. A diverged estimator is an error
//! (non-zero exit) after the summary is written. `--estimator oe` is the batch output-error
//! fit: it reads the whole record first (it says so), prints its iterations and writes
//! `summary.json` (estimates, coloured-residual and Cramér–Rao σ, residual RMS).

use crate::estimators::EstimatorKind;
use crate::plot::{LineKind, Panel, Series, render_panels_png};
use crate::replay::{DerivativeSource, History, Pacing, ReplayOptions, ReplayOutcome, replay};
use aeroident_io::{FlightDataReader, Mapping, ModelSpec};
use anyhow::Context;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `aeroident replay`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// Recorded flight data: a CSV with one header row, `-` for stdin (live mode), or a live
    /// MAVLink feed `mavlink:udp:<host>:<port>[?timeout_s=<s>]` (docs/mavlink.md).
    pub data: String,
    /// Channel mapping TOML (see `mappings/*.toml` and `docs/mapping.md`).
    #[arg(long)]
    pub map: PathBuf,
    /// Output directory for estimates.csv, summary.json and estimates.png.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Model: a preset (`longitudinal`, `lateral`, `six-axis`) or a model file (TOML, see
    /// `models/`). Default: the richest preset the record's first sample supports.
    #[arg(long)]
    pub model: Option<String>,
    /// The estimator.
    #[arg(long, value_enum, default_value_t = EstimatorKind::Rls)]
    pub estimator: EstimatorKind,
    /// RLS forgetting factor in (0, 1]; 1 = ordinary least squares.
    #[arg(long, default_value_t = 1.0)]
    pub forgetting: f64,
    /// Source of ṗ, q̇, ṙ and α̇: the record's channels where mapped (else the causal
    /// differentiator), or always differentiate p, q, r and α.
    #[arg(long, alias = "qdot", value_enum, default_value_t = DerivativeSource::Auto)]
    pub derivatives: DerivativeSource,
    /// Causal differentiator window, samples (odd ≥ 3; lag = (N−1)/2 samples).
    #[arg(long, default_value_t = 5)]
    pub diff_window: usize,
    /// Pace the replay at the record's own sample rate.
    #[arg(long)]
    pub realtime: bool,
}

fn announce(line: &str) {
    eprintln!("{line}");
}

/// Runs `aeroident replay`.
///
/// # Errors
/// Mapping, model-file or data errors (naming file, row or line, and column or key),
/// estimator errors (not available, bad option, diverged), and output I/O errors.
pub fn execute(args: ReplayArgs) -> anyhow::Result<()> {
    let mapping = Mapping::from_path(&args.map)?;
    let model = args.model.as_deref().map(ModelSpec::from_arg).transpose()?;
    let opts = ReplayOptions {
        estimator: args.estimator,
        model,
        forgetting: args.forgetting,
        derivatives: args.derivatives,
        diff_window: args.diff_window,
        pacing: if args.realtime { Pacing::Realtime } else { Pacing::Unpaced },
        on_model: Some(announce),
    };
    let mavlink = crate::live::is_mavlink(&args.data);
    let live = args.data == "-" || mavlink;
    if args.estimator == EstimatorKind::Oe && mavlink {
        anyhow::bail!(
            "--estimator oe is a batch fit of a whole record, not for a live MAVLink feed"
        );
    }
    if args.estimator == EstimatorKind::Oe {
        return execute_batch(&args, &mapping, opts.model);
    }
    if !live && args.out.is_none() {
        anyhow::bail!("give --out <dir> (or read `-` from stdin for a live feed on stdout)");
    }
    // Lock the directory and clear the previous run's files before reading anything.
    let mut out_dir = args.out.as_deref().map(crate::outdir::OutputDir::open).transpose()?;
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
    let mut sinks: Vec<&mut dyn Write> = Vec::new();
    if let Some(f) = csv_file.as_mut() {
        sinks.push(f);
    }
    if live {
        sinks.push(&mut *stdout_lock);
    }
    let outcome = if mavlink {
        let (reader, stats) = crate::live::open_mavlink(&args.data, &mapping)?;
        let mut outcome = replay(reader, &mapping, &opts, sinks)?;
        crate::live::finish(&mut outcome.summary, &stats);
        outcome
    } else if live {
        let reader = FlightDataReader::new(std::io::stdin().lock(), "-", &mapping)?;
        replay(reader, &mapping, &opts, sinks)?
    } else {
        let file =
            std::fs::File::open(&args.data).with_context(|| format!("opening {}", args.data))?;
        let reader = FlightDataReader::new(std::io::BufReader::new(file), &args.data, &mapping)?;
        replay(reader, &mapping, &opts, sinks)?
    };
    if let Some(f) = csv_file {
        f.commit()?;
    }
    let summary_text = serde_json::to_string_pretty(&outcome.summary)?;
    match &args.out {
        Some(dir) => {
            let o = out_dir.as_mut().context("internal: output directory not open")?;
            o.write_bytes("summary.json", summary_text.as_bytes())?;
            let name = Path::new(&args.data)
                .file_name()
                .map_or(args.data.clone(), |n| n.to_string_lossy().into_owned());
            let title = format!("{name} — {} — {}", args.estimator.name(), outcome.model.name);
            o.write_path("estimates.png", |p| plot_estimates(p, &title, &outcome.history))?;
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
    // The end-of-run diagnostics (sign plausibility, filter consistency); the record warnings
    // were printed as they arose.
    for w in outcome
        .summary
        .warnings
        .iter()
        .filter(|w| w.contains("sign a conventional") || w.starts_with("normalised innovation"))
    {
        eprintln!("warning: {w}");
    }
    if let Some(e) = diverged_error(&outcome, args.estimator.name()) {
        anyhow::bail!(e);
    }
    if outcome.summary.status != "running" {
        eprintln!(
            "warning: estimator status `{}`: not every parameter was identified (null in the summary)",
            outcome.summary.status
        );
    }
    Ok(())
}

/// The error message for a diverged estimator (`None` if it did not diverge).
pub fn diverged_error(outcome: &ReplayOutcome, estimator: &str) -> Option<String> {
    if !outcome.diverged() {
        return None;
    }
    let at = outcome
        .summary
        .rejections
        .last()
        .map_or(String::new(), |r| format!(" (row {}: {})", r.row, r.reason));
    Some(format!(
        "estimator `{estimator}` diverged{at}; its estimates are not a result (summary written with status `diverged`)"
    ))
}

/// Figure: one panel per parameter, the estimate (solid) and ±2σ (dashed) where known.
///
/// # Errors
/// Plot errors naming the file.
pub fn plot_estimates(path: &Path, title: &str, h: &History) -> anyhow::Result<()> {
    let panels: Vec<Panel> = h
        .names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let v: Vec<f64> = h.values.iter().map(|v| v[i].unwrap_or(f64::NAN)).collect();
            let mut series = vec![Series {
                label: (*name).to_string(),
                t_s: h.t_s.clone(),
                values: v.clone(),
                kind: LineKind::Solid,
            }];
            if h.sigmas.iter().any(|s| s[i].is_some()) {
                for (label, sign) in [("+2σ", 1.0), ("−2σ", -1.0)] {
                    let band = h
                        .sigmas
                        .iter()
                        .zip(v.iter())
                        .map(|(s, v)| s[i].map_or(f64::NAN, |s| v + sign * 2.0 * s))
                        .collect();
                    series.push(Series {
                        label: label.into(),
                        t_s: h.t_s.clone(),
                        values: band,
                        kind: LineKind::Dashed,
                    });
                }
            }
            Panel { title: (*name).to_string(), y_label: (*name).to_string(), series }
        })
        .collect();
    render_panels_png(path, title, &panels, 1000, 180)?;
    Ok(())
}

/// `--estimator oe`: the batch output-error fit of the whole record.
fn execute_batch(
    args: &ReplayArgs,
    mapping: &Mapping,
    model: Option<ModelSpec>,
) -> anyhow::Result<()> {
    eprintln!(
        "output error is a batch method: reading the whole record before fitting (not real time)"
    );
    let outcome = if args.data == "-" {
        let reader = FlightDataReader::new(std::io::stdin().lock(), "-", mapping)?;
        crate::replay::batch::fit_record(reader, mapping, model)?
    } else {
        let file =
            std::fs::File::open(&args.data).with_context(|| format!("opening {}", args.data))?;
        let reader = FlightDataReader::new(std::io::BufReader::new(file), &args.data, mapping)?;
        crate::replay::batch::fit_record(reader, mapping, model)?
    };
    eprintln!("model: {}", outcome.model.name);
    crate::cli::print_stdout(&outcome.result.to_string())?;
    let text = serde_json::to_string_pretty(&outcome.summary)?;
    match &args.out {
        Some(dir) => {
            let mut out = crate::outdir::OutputDir::open(dir)?;
            out.write_bytes("summary.json", text.as_bytes())?;
            eprintln!(
                "{}: {} samples in {} manoeuvre(s), {} rejected, {} iterations in {:.3} s; wrote {}",
                args.data,
                outcome.summary.samples_read,
                outcome.summary.manoeuvres,
                outcome.summary.samples_rejected,
                outcome.summary.iterations.len().saturating_sub(1),
                outcome.summary.fit_wall_s,
                dir.display()
            );
        }
        None => eprintln!("{text}"),
    }
    Ok(())
}
