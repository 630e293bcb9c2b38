//! `aeroident freqresp`: frequency responses of a sweep or chirp record, with coherence and
//! random error, and optional low-order transfer-function fits
//! ([`aeroident_pipelines::freqresp`]; method in docs/frequency-response.md).
//!
//! ```text
//! aeroident freqresp <log> --map M --input de --output q [--input da …] [--output …]
//!                    [--window a:b … | --window sysid[:AXIS] | --window auto] [--windows-s 60,30,15]
//!                    [--overlap 0.8] [--f-min-hz F] [--f-max-hz F]
//!                    [--fit "q/de:1/2+delay@1:10" …] [--min-coherence 0.6] [--out DIR]
//! ```
//! `--window sysid` (ArduPilot DataFlash logs): every SYSID sweep's span is a window
//! ([`aeroident_io::excitation`]); `sysid:AXIS` only the sweeps on that `SID_AXIS` (number or
//! name, e.g. `sysid:FW_MIX_PITCH`); without `--input` the input is the swept surface when the
//! mapping maps it, else the injected waveform `sysid`
//! ([`aeroident_pipelines::freqresp::sysid`]).
//! Prints a summary per pair and each fit; with `--out`, writes `DIR/freqresp.json`,
//! `DIR/freqresp.csv` (one row per pair and frequency), a Bode figure per pair with its
//! coherence (`bode_<output>_<input>.{png,svg}`) and `report.html`.

use aeroident_io::excitation::{Axis, Excitation, axis_by_name, read_sysid};
use aeroident_io::{LogFormat, Mapping, Record, RecordSource};
use aeroident_pipelines::freqresp::sysid::{SweepSummary, choose_sweeps, default_input};
use aeroident_pipelines::freqresp::{
    FitSummary, FreqRespOptions, FreqRespOutcome, GOOD_COHERENCE, coherent_band, freqresp,
};
use aeroident_pipelines::window::TimeWindow;
use aeroident_signals::spectral::SpectralOptions;
use aeroident_signals::tf_fit::{Factor, FitOptions, TfSpec};
use anyhow::Context;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `aeroident freqresp`.
#[derive(Debug, clap::Args)]
pub struct FreqRespArgs {
    /// Recorded flight data (CSV, `.asc`, `.mat`, PX4 `.ulg`, ArduPilot `.bin`).
    pub data: String,
    /// Channel mapping TOML (`docs/mapping.md`).
    #[arg(long)]
    pub map: PathBuf,
    /// Log format; default by the file's extension, else CSV.
    #[arg(long)]
    pub format: Option<LogFormat>,
    /// Input channel (mapping key: de, da, dr, throttle …, or `sysid`, the injected waveform
    /// of an ArduPilot SYSID log); several: the conditioned multi-input responses (partial
    /// coherence). Required but with `--window sysid`, where it defaults to the swept surface
    /// if mapped, else `sysid`.
    #[arg(long = "input")]
    pub inputs: Vec<String>,
    /// Output channel (mapping key: p, q, r, alpha, beta, ax, ay, az …); several allowed.
    #[arg(long = "output", required = true)]
    pub outputs: Vec<String>,
    /// Time window `START:END` of the record, s; several allowed (each its own stretch). Or
    /// `sysid[:AXIS]`: the spans of an ArduPilot log's SYSID sweeps (on `SID_AXIS` AXIS,
    /// number or name), found from its SIDS and SIDD messages. Or `auto`: the manoeuvres
    /// `aeroident inspect` finds on the mapping's surfaces (printed as the windows chosen).
    #[arg(long = "window", value_parser = parse_window, allow_hyphen_values = true)]
    pub windows: Vec<WindowArg>,
    /// Spectral window lengths, s, comma-separated; default five from half the longest
    /// stretch down to an eighth of that.
    #[arg(long, value_delimiter = ',')]
    pub windows_s: Vec<f64>,
    /// Overlap of consecutive spectral windows, fraction in [0, 0.95].
    #[arg(long, default_value_t = 0.8)]
    pub overlap: f64,
    /// Lowest frequency, Hz (default two periods in the longest window).
    #[arg(long)]
    pub f_min_hz: Option<f64>,
    /// Highest frequency, Hz (default a fifth of the sample rate).
    #[arg(long)]
    pub f_max_hz: Option<f64>,
    /// Frequency points per decade.
    #[arg(long, default_value_t = 40)]
    pub points_per_decade: usize,
    /// Transfer-function fit `output/input:num/den[+delay][@lo:hi]` (band in rad/s), e.g.
    /// `q/de:1/2+delay@1:10`; several allowed.
    #[arg(long = "fit", value_parser = TfSpec::parse)]
    pub fits: Vec<TfSpec>,
    /// Lowest coherence of a frequency the fits use.
    #[arg(long, default_value_t = 0.6)]
    pub min_coherence: f64,
    /// Output directory for freqresp.json, freqresp.csv, the Bode figures and report.html.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// A `--window`: a span of the record, or the log's SYSID sweeps (on one axis).
#[derive(Debug, Clone)]
pub enum WindowArg {
    /// `START:END`, s.
    Span(TimeWindow),
    /// `sysid[:AXIS]`.
    Sysid(Option<&'static Axis>),
    /// `auto`: the manoeuvres `aeroident inspect` finds on the mapping's surfaces
    /// ([`super::auto_window`]).
    Auto,
}

fn parse_window(text: &str) -> Result<WindowArg, String> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("auto") {
        return Ok(WindowArg::Auto);
    }
    if !t.eq_ignore_ascii_case("sysid") && !t.to_ascii_lowercase().starts_with("sysid:") {
        return TimeWindow::parse(t).map(WindowArg::Span);
    }
    match t.split_once(':') {
        None => Ok(WindowArg::Sysid(None)),
        Some((_, a)) => axis_by_name(a).map(|a| WindowArg::Sysid(Some(a))).ok_or_else(|| {
            format!(
                "`{t}`: `{a}` is not a SID_AXIS (a number or a name such as FW_MIX_PITCH, RATE_ROLL)"
            )
        }),
    }
}

impl FreqRespArgs {
    /// The pipeline's options, with the time windows and the SYSID excitation resolved
    /// (`sysid` windows read the log's sweeps; the default input follows them).
    ///
    /// # Errors
    /// `sysid` beside time windows or twice, on a log that is not DataFlash, a log without a
    /// sweep (on the axis), the reader's errors, sweeps on several axes without `--input`.
    pub fn options(&self, mapping: &Mapping) -> anyhow::Result<FreqRespOptions> {
        let (windows, excitation) = self.resolve_windows(mapping)?;
        let mut inputs = self.inputs.clone();
        if let (true, Some(e)) = (inputs.is_empty(), &excitation) {
            inputs.push(default_input(&e.sweeps, mapping)?);
        }
        Ok(FreqRespOptions {
            inputs,
            outputs: self.outputs.clone(),
            windows,
            excitation,
            spectral: SpectralOptions {
                window_lengths_s: self.windows_s.clone(),
                overlap: self.overlap,
                f_min_hz: self.f_min_hz,
                f_max_hz: self.f_max_hz,
                points_per_decade: self.points_per_decade,
            },
            fits: self.fits.clone(),
            fit: FitOptions { min_coherence: self.min_coherence, ..FitOptions::default() },
        })
    }

    /// The time windows and, with `--window sysid`, the chosen sweeps and the injected
    /// waveform.
    fn resolve_windows(
        &self,
        mapping: &Mapping,
    ) -> anyhow::Result<(Vec<TimeWindow>, Option<Excitation>)> {
        if self.windows.iter().any(|w| matches!(w, WindowArg::Auto)) {
            anyhow::ensure!(
                self.windows.len() == 1,
                "option `--window`: give `auto` alone (not beside START:END or sysid windows)"
            );
            let auto = [super::auto_window::WindowSpec::Auto];
            let windows = super::auto_window::resolve(
                &auto,
                &self.data,
                self.format,
                mapping,
                false,
                super::auto_window::axes_of_model(None),
            )?;
            return Ok((windows, None));
        }
        let spans: Vec<TimeWindow> = self
            .windows
            .iter()
            .filter_map(|w| if let WindowArg::Span(s) = w { Some(*s) } else { None })
            .collect();
        let sysid: Vec<Option<&Axis>> = self
            .windows
            .iter()
            .filter_map(|w| if let WindowArg::Sysid(a) = w { Some(*a) } else { None })
            .collect();
        let axis = match (sysid.as_slice(), spans.is_empty()) {
            ([], _) => return Ok((spans, None)),
            ([a], true) => *a,
            _ => anyhow::bail!(
                "option `--window`: give `sysid[:AXIS]` once, and not beside START:END windows"
            ),
        };
        let path = Path::new(&self.data);
        if LogFormat::resolve(self.format, &self.data) != LogFormat::Dataflash {
            anyhow::bail!(
                "option `--window`: `sysid` reads an ArduPilot DataFlash log's SYSID sweeps (SIDS, SIDD); {} is not one (PX4 logs no sweep setup message: give the windows as START:END, section Finding the excitation of docs/frequency-response.md)",
                self.data
            );
        }
        let excitation = read_sysid(path)?;
        let (sweeps, windows) = choose_sweeps(&excitation, axis, &self.data)?;
        Ok((windows, Some(Excitation { sweeps, ..excitation })))
    }
}

/// Runs `aeroident freqresp`: `--out` is locked and checked before the record is read, and a
/// signal during the analysis writes `summary.json` marked `interrupted`
/// ([`super::whole_record`]).
///
/// # Errors
/// Unreadable mapping or record, a channel not mapped or not excited, a bad window or fit
/// spec, an unwritable output, a signal.
pub fn execute(args: FreqRespArgs) -> anyhow::Result<()> {
    let mapping = Mapping::from_path(&args.map)?;
    // The options first: a `--window sysid` on a log that cannot have sweeps is named as such.
    let options = args.options(&mapping)?;
    // Before the output directory is opened (which clears the previous run's results).
    aeroident_pipelines::freqresp::check(&options)?;
    let inputs = [Path::new(&args.data), args.map.as_path()];
    let mut run = super::whole_record::WholeRecord::begin(
        "freqresp",
        &args.data,
        args.out.as_deref(),
        &inputs,
    )?;
    let (data, format) = (args.data.clone(), args.format);
    let outcome = run.run(move || {
        let record = Record::open(RecordSource::Path(data), format, &mapping)?;
        record.notes().iter().for_each(|n| aeroident_report::note!("note: {n}"));
        Ok(freqresp(record.reader, &options)?)
    })?;
    // The files first: a console reader that has gone away (`| head`) must not cost them.
    let wrote = match (run.writing(), &args.out) {
        (Some(out), Some(dir)) => {
            out.write_bytes("freqresp.json", serde_json::to_string_pretty(&outcome)?.as_bytes())?;
            out.write_bytes("freqresp.csv", csv_text(&outcome)?.as_bytes())?;
            let source = crate::report::Source { data: &args.data, mapping: &args.map };
            crate::report::freqresp::write(&source, &outcome, out)?;
            out.finish();
            Some(dir.join("freqresp.json"))
        }
        _ => None,
    };
    super::print_stdout(&render(&outcome))?;
    if let Some(json) = wrote {
        aeroident_report::note!("wrote {} and report.html", json.display());
    }
    Ok(())
}

/// `freqresp.csv`: one row per pair and grid frequency (empty where not identified).
///
/// # Errors
/// A CSV error.
pub fn csv_text(o: &FreqRespOutcome) -> anyhow::Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "output",
        "input",
        "frequency_hz",
        "frequency_rad_s",
        "magnitude_db",
        "phase_deg",
        "coherence",
        "multiple_coherence",
        "random_error",
        "magnitude_error_db",
        "phase_error_deg",
    ])?;
    let num = |v: f64| if v.is_finite() { format!("{v:.8e}") } else { String::new() };
    for p in &o.pairs {
        for k in 0..p.frequency_hz.len() {
            let f = p.frequency_hz[k];
            let mut row = vec![
                p.output.clone(),
                p.input.clone(),
                num(f),
                num(2.0 * std::f64::consts::PI * f),
            ];
            for v in [
                p.magnitude_db[k],
                p.phase_deg[k],
                p.coherence[k],
                p.multiple_coherence[k],
                p.random_error[k],
                p.magnitude_error_db[k],
                p.phase_error_deg[k],
            ] {
                row.push(num(v));
            }
            w.write_record(&row)?;
        }
    }
    String::from_utf8(w.into_inner().context("writing freqresp.csv")?).context("freqresp.csv")
}

/// The console text: the record, each pair's coherent band and each fit.
fn render(o: &FreqRespOutcome) -> String {
    let mut t = format!(
        "{}: {} samples in {} stretch(es), Δt {} s; windows {} s, overlap {}\n",
        o.file,
        o.samples,
        o.stretches,
        o.dt_s,
        o.window_lengths_s.iter().map(|w| format!("{w:.2}")).collect::<Vec<_>>().join(", "),
        o.overlap
    );
    for s in &o.sweeps {
        t.push_str(&sweep_line(s));
    }
    for p in &o.pairs {
        let band = match coherent_band(p, GOOD_COHERENCE) {
            Some(b) => format!(
                "{:.3}–{:.3} rad/s ({} of {} points)",
                b.lo_rad_s, b.hi_rad_s, b.points, b.of
            ),
            None => "none".into(),
        };
        let _ = writeln!(t, "{}/{}: coherence ≥ 0.8 over {band}", p.output, p.input);
    }
    for f in &o.fits {
        t.push_str(&fit_lines(f));
    }
    for w in &o.warnings {
        let _ = writeln!(t, "warning: {w}");
    }
    t
}

/// One SYSID sweep's line: its axis, band, magnitude, span and SIDD samples.
fn sweep_line(s: &SweepSummary) -> String {
    format!(
        "sweep {} ({}): {}–{} Hz, magnitude {} {}, {:.3}–{:.3} s ({} SIDD samples)\n",
        s.axis_name,
        s.axis,
        s.band_hz.0,
        s.band_hz.1,
        s.magnitude,
        s.injected_unit,
        s.span_s.0,
        s.span_s.1,
        s.sidd_samples
    )
}

/// One fit's lines: its cost, band, gain and delay, then each pole and zero.
fn fit_lines(f: &FitSummary) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "fit {}: J = {:.1} over {} frequencies ({:.3}–{:.3} rad/s), {}; K = {:.5}{}, τ = {:.4} s{}",
        f.spec,
        f.fit.cost,
        f.fit.frequencies_used,
        f.fit.band_rad_s.0,
        f.fit.band_rad_s.1,
        f.fit.status,
        f.fit.gain,
        pm(f.fit.gain_sigma),
        f.fit.delay_s,
        pm(f.fit.delay_sigma_s)
    );
    for (what, list) in [("pole", &f.fit.poles), ("zero", &f.fit.zeros)] {
        for fac in list {
            let _ = writeln!(t, "  {what} {}", factor_text(fac));
        }
    }
    t
}

/// A pole or zero factor: its roots, then ωn and ζ (complex pair) or |root| (real root).
fn factor_text(fac: &Factor) -> String {
    let roots: Vec<String> =
        fac.roots.iter().map(|r| format!("{:.4}{:+.4}j", r[0], r[1])).collect();
    let modal = match (fac.wn_rad_s, fac.zeta) {
        (Some(w), Some(z)) => {
            format!("  ωn {w:.4}{} rad/s  ζ {z:.4}{}", pm(fac.wn_sigma_rad_s), pm(fac.zeta_sigma))
        }
        (Some(w), None) => format!("  |root| {w:.4}{} rad/s", pm(fac.wn_sigma_rad_s)),
        _ => String::new(),
    };
    format!("{}{modal}", roots.join(", "))
}

fn pm(s: Option<f64>) -> String {
    s.map_or(String::new(), |s| format!(" ± {s:.4}"))
}
