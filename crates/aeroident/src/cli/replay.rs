//! `aeroident replay`: feed a recorded flight to an online estimator sample by sample.
//!
//! ```text
//! aeroident replay <data.csv|-> --map <map.toml> [--out <dir>] [--estimator rls|ekf|smpe|smpe-corrected]
//!                  [--terms basic|with-speed] [--forgetting λ] [--qdot auto|differentiate]
//!                  [--diff-window N] [--realtime]
//! ```
//! Writes `<dir>/estimates.csv`, `<dir>/summary.json` and `<dir>/estimates.png` (estimates with
//! ±2σ). With `-` the record is read from stdin and one CSV line of estimates per sample is
//! written to stdout as it is produced (a live feed); the summary then goes to stderr unless
//! `--out` is given.

use crate::plot::{LineKind, Panel, Series, render_panels_png};
use crate::replay::online::ModelTerms;
use crate::replay::{EstimatorKind, History, Pacing, QdotSource, ReplayOptions, replay};
use aeroident_io::{FlightDataReader, Mapping};
use anyhow::Context;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `aeroident replay`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// Recorded flight data: a CSV with one header row, or `-` for stdin (live mode).
    pub data: String,
    /// Channel mapping TOML (see `mappings/*.toml`).
    #[arg(long)]
    pub map: PathBuf,
    /// Output directory for estimates.csv, summary.json and estimates.png.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// The estimator.
    #[arg(long, value_enum, default_value_t = EstimatorKind::Rls)]
    pub estimator: EstimatorKind,
    /// Equation-error model structure (RLS): with or without the V/V0 terms.
    #[arg(long, value_enum, default_value_t = ModelTerms::Basic)]
    pub terms: ModelTerms,
    /// RLS forgetting factor in (0, 1]; 1 = ordinary least squares.
    #[arg(long, default_value_t = 1.0)]
    pub forgetting: f64,
    /// Source of q̇: the record's channel (else the differentiator), or always differentiate q.
    #[arg(long, value_enum, default_value_t = QdotSource::Auto)]
    pub qdot: QdotSource,
    /// Causal differentiator window, samples (odd ≥ 3; lag = (N−1)/2 samples).
    #[arg(long, default_value_t = 5)]
    pub diff_window: usize,
    /// Pace the replay at the record's own sample rate.
    #[arg(long)]
    pub realtime: bool,
}

/// Runs `aeroident replay`.
///
/// # Errors
/// Mapping or data errors (naming file, row and column), estimator configuration errors, and
/// output I/O errors.
pub fn execute(args: ReplayArgs) -> anyhow::Result<()> {
    let mapping = Mapping::from_path(&args.map)?;
    let opts = ReplayOptions {
        estimator: args.estimator,
        terms: args.terms,
        forgetting: args.forgetting,
        qdot: args.qdot,
        diff_window: args.diff_window,
        pacing: if args.realtime { Pacing::Realtime } else { Pacing::Unpaced },
    };
    let live = args.data == "-";
    if !live && args.out.is_none() {
        anyhow::bail!("give --out <dir> (or read `-` from stdin for a live feed on stdout)");
    }
    let mut csv_file = match &args.out {
        Some(dir) => {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            let p = dir.join("estimates.csv");
            Some(std::io::BufWriter::new(
                std::fs::File::create(&p).with_context(|| format!("creating {}", p.display()))?,
            ))
        }
        None => None,
    };
    let stdout = std::io::stdout();
    let mut stdout_lock = stdout.lock();
    let mut sinks: Vec<&mut dyn Write> = Vec::new();
    if let Some(f) = csv_file.as_mut() {
        sinks.push(f);
    }
    if live {
        sinks.push(&mut stdout_lock);
    }
    let outcome = if live {
        let reader = FlightDataReader::new(std::io::stdin().lock(), "-", &mapping)?;
        replay(reader, &mapping, &opts, sinks)?
    } else {
        let file =
            std::fs::File::open(&args.data).with_context(|| format!("opening {}", args.data))?;
        let reader = FlightDataReader::new(std::io::BufReader::new(file), &args.data, &mapping)?;
        replay(reader, &mapping, &opts, sinks)?
    };
    if let Some(mut f) = csv_file {
        f.flush()?;
    }
    let summary_text = serde_json::to_string_pretty(&outcome.summary)?;
    match &args.out {
        Some(dir) => {
            std::fs::write(dir.join("summary.json"), &summary_text)?;
            let name = Path::new(&args.data)
                .file_name()
                .map_or(args.data.clone(), |n| n.to_string_lossy().into_owned());
            let title = format!("{name} — {}", args.estimator.name());
            plot_estimates(&dir.join("estimates.png"), &title, &outcome.history)?;
            eprintln!(
                "{}: {} samples read, {} rejected, {:.0} samples/s; wrote {}",
                args.data,
                outcome.summary.samples_read,
                outcome.summary.samples_rejected,
                outcome.summary.throughput_samples_per_s,
                dir.display()
            );
        }
        None => eprintln!("{summary_text}"),
    }
    Ok(())
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
            let v: Vec<f64> = h.values.iter().map(|v| v[i]).collect();
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
