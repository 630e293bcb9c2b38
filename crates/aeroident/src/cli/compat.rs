//! `aeroident compat`: the data compatibility check of a record (are its accelerations, rates,
//! attitudes and air data consistent, and with which biases, scale factors and time shifts).
//!
//! ```text
//! aeroident compat <log> --map <map.toml> [--format …] [--out DIR] [--window START:END … | auto]
//!                  [--and <more> …] [--no-time-shifts] [--gyro-time-shifts]
//!                  [--inertial-scale-factors] [--ahrs-lag] [--max-iterations N]
//! ```
//! Prints the corrections per channel and the findings; with `--out`, writes
//! `DIR/compat.json` ([`aeroident_pipelines::compat`] documents its keys).

use aeroident_estimators::compat::CompatConfig;
use aeroident_estimators::compat::CompatResult;
use aeroident_io::{LogFormat, Mapping, Record, RecordSource};
use aeroident_pipelines::compat::{ChannelSummary, CompatSummary, check_records};
use aeroident_pipelines::job::Records;
use aeroident_pipelines::window::TimeWindow;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `aeroident compat`.
#[derive(Debug, clap::Args)]
pub struct CompatArgs {
    /// Recorded flight data (CSV, `.asc`, `.mat`, PX4 `.ulg`, ArduPilot `.bin`), with the
    /// accelerometers, the gyros, roll and pitch attitude and the air data mapped.
    pub data: String,
    /// Channel mapping TOML (`docs/mapping.md`).
    #[arg(long)]
    pub map: PathBuf,
    /// Log format; default by the file's extension, else CSV.
    #[arg(long)]
    pub format: Option<LogFormat>,
    /// Output directory for `compat.json`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// A time window `START:END` (record seconds) to check, as `replay --window` fits it;
    /// repeat it for several manoeuvres; or `auto`, the manoeuvres `aeroident inspect` finds
    /// on the mapping's surfaces. Default: the whole record (taxi and ground runs included:
    /// give the fit's windows to check the data the fit uses); a record running more than ten
    /// minutes without a gap is checked on its best four manoeuvres per axis instead, named
    /// in a warning.
    #[arg(long = "window", value_name = "START:END|auto", value_parser = super::auto_window::parse, allow_hyphen_values = true)]
    pub windows: Vec<super::auto_window::WindowSpec>,
    /// A further record of the same aircraft (same mapping and format), checked jointly with
    /// the first (one set of corrections per flight), as `replay --and` fits it.
    #[arg(long = "and", value_name = "FILE")]
    pub and: Vec<String>,
    /// Check a record given twice (the same file, or two files of the same content) as if new
    /// data; without it such a record is refused, as it would be weighted twice.
    #[arg(long)]
    pub allow_duplicate_records: bool,
    /// Do not estimate the outputs' time shifts.
    #[arg(long)]
    pub no_time_shifts: bool,
    /// Estimate the time shift of each gyro (p, q, r) against the accelerometers too: the
    /// late rates of an AHRS (off by default: it can trade with slow model errors).
    #[arg(long)]
    pub gyro_time_shifts: bool,
    /// Estimate the accelerometers' and gyros' scale factors too (needs large, varied
    /// manoeuvres).
    #[arg(long)]
    pub inertial_scale_factors: bool,
    /// Model the AHRS's first-order filter on the gyros and attitudes, its time constant an
    /// unknown (instead of the gyros' time shifts); `replay --compat` then passes every other
    /// channel through the same filter.
    #[arg(long)]
    pub ahrs_lag: bool,
    /// Most Gauss–Newton iterations (default 50); past it the last iterate is reported.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub max_iterations: Option<u32>,
}

/// Refuses unknowns that exclude each other: the lag model replaces the gyros' shifts, so with
/// both the shifts were dropped without a word.
fn check_unknowns(args: &CompatArgs) -> anyhow::Result<()> {
    if args.ahrs_lag && args.gyro_time_shifts {
        anyhow::bail!(
            "--ahrs-lag models the gyros' delay as the AHRS filter, --gyro-time-shifts as shifts of their own: give one"
        );
    }
    Ok(())
}

/// Runs `aeroident compat`: `--out` is locked and checked before the record is read, and a
/// signal during the check writes `summary.json` marked `interrupted`
/// ([`super::whole_record`]).
///
/// # Errors
/// Unreadable mapping or record, a missing channel, a check that fails, an unwritable output,
/// a signal.
pub fn execute(args: CompatArgs) -> anyhow::Result<()> {
    check_unknowns(&args)?;
    let mapping = Mapping::from_path(&args.map)?;
    let mut config = CompatConfig {
        time_shifts: !args.no_time_shifts,
        gyro_time_shifts: args.gyro_time_shifts,
        inertial_scale_factors: args.inertial_scale_factors,
        ahrs_lag: args.ahrs_lag,
        ..CompatConfig::default()
    };
    if let Some(n) = args.max_iterations {
        config.max_iterations = n as usize;
    }
    let files: Vec<String> = std::iter::once(&args.data).chain(&args.and).cloned().collect();
    let records = Records {
        and: args.and.clone(),
        format: args.format,
        allow_duplicates: args.allow_duplicate_records,
        ..Records::one(args.data.clone(), mapping.clone())
    };
    records.check_distinct()?;
    let mut inputs: Vec<&Path> =
        std::iter::once(&args.data).chain(&args.and).map(Path::new).collect();
    inputs.push(args.map.as_path());
    let mut run = super::whole_record::WholeRecord::begin(
        "compat",
        &args.data,
        args.out.as_deref(),
        &inputs,
    )?;
    let windows = super::auto_window::resolve(
        &args.windows,
        &args.data,
        args.format,
        &mapping,
        !args.and.is_empty(),
        super::auto_window::axes_of_model(None),
    )?;
    let format = args.format;
    let (summary, result) = run.run(move || check(&files, format, &mapping, &windows, &config))?;
    // The files first: a console reader that has gone away (`| head`) must not cost them.
    let wrote = match (run.writing(), &args.out) {
        (Some(out), Some(dir)) => {
            out.write_bytes("compat.json", serde_json::to_string_pretty(&summary)?.as_bytes())?;
            let source = crate::report::Source { data: &args.data, mapping: &args.map };
            let traces = aeroident_pipelines::compat::traces(&result);
            crate::report::compat::write(&source, &summary, &traces, out)?;
            out.finish();
            Some(dir.join("compat.json"))
        }
        _ => None,
    };
    super::print_stdout(&render(&summary))?;
    if let Some(json) = wrote {
        aeroident_report::note!("wrote {} and report.html", json.display());
    }
    Ok(())
}

/// Reads `files` (the record, then each `--and`) and checks them jointly.
fn check(
    files: &[String],
    format: Option<LogFormat>,
    mapping: &Mapping,
    windows: &[TimeWindow],
    config: &CompatConfig,
) -> anyhow::Result<(CompatSummary, CompatResult)> {
    let mut readers = Vec::new();
    for file in files {
        let record = Record::open(RecordSource::Path(file.clone()), format, mapping)?;
        record.notes().iter().for_each(|n| aeroident_report::note!("note: {n}"));
        readers.push(record.reader);
    }
    Ok(check_records(readers, windows, config)?)
}

/// The console text: status, the channel table, residuals, findings and warnings.
fn render(s: &CompatSummary) -> String {
    let mut t = format!(
        "{}: {} samples in {} manoeuvre(s), {} rejected; {} after {} iterations{}\n",
        s.file,
        s.samples_read,
        s.manoeuvres,
        s.samples_rejected,
        s.status,
        s.iterations,
        s.status_reason.as_ref().map_or(String::new(), |r| format!(" ({r})"))
    );
    let _ = writeln!(
        t,
        "{:<11} {:>22} {:>18} {:>20}  unit",
        "channel", "bias ± σ", "scale ± σ", "time shift ± σ (s)"
    );
    for c in &s.channels {
        let _ = writeln!(t, "{}", row(c));
    }
    if let (Some(tau), Some(sigma)) = (s.ahrs_lag_tau_s, s.ahrs_lag_tau_sigma_s) {
        let _ = writeln!(t, "AHRS lag (first-order time constant): {tau:.3} ± {sigma:.3} s");
    }
    let rms: Vec<String> = s.residual_rms.iter().map(|(k, v)| format!("{k} {v:.3e}")).collect();
    let _ = writeln!(t, "residual RMS: {}", rms.join(", "));
    for f in &s.findings {
        let _ = writeln!(t, "finding: {f}");
    }
    for w in &s.warnings {
        let _ = writeln!(t, "warning: {w}");
    }
    t
}

fn row(c: &ChannelSummary) -> String {
    let pm = |v: Option<f64>, s: Option<f64>, prec: usize| match (v, s) {
        (Some(v), Some(s)) => format!("{v:+.prec$} ± {s:.prec$}"),
        _ => "—".into(),
    };
    format!(
        "{:<11} {:>22} {:>18} {:>20}  {}",
        c.name,
        pm(c.bias, c.bias_sigma, 5),
        pm(c.scale, c.scale_sigma, 4),
        pm(c.time_shift_s, c.time_shift_sigma_s, 3),
        c.unit
    )
}
