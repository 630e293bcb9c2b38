//! Outputs of a run: `timeseries.csv`, `summary.json`, the terminal table, the figures
//! ([`super::figures`]) and the thesis-versus-ours report of `aeroident run --all`, rendered
//! from the run's outcome and [`Summary`].

use std::fmt::Write as _;
use std::path::Path;

use aeroident_pipelines::aircraft::experiment::{Quantity, RunOutput, TRACKED_NAMES, tracked};
use aeroident_pipelines::aircraft::summary::{
    ParamSummary, Summary, TARGET_WINDOW_S, TargetSummary,
};
use aeroident_pipelines::metrics;

use aeroident_io::decimal::push_f64;

/// Errors writing outputs. Each names the file.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// File system error.
    #[error("writing `{path}`: {source}")]
    Io {
        /// File.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// Figure error.
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
    /// Output directory error (lock, atomic write), naming the path.
    #[error(transparent)]
    Output(#[from] crate::outdir::OutputError),
    /// Metric error (a bug: lengths are built equal).
    #[error(transparent)]
    Metrics(#[from] metrics::MetricsError),
    /// JSON or CSV encoding.
    #[error("encoding `{path}`: {reason}")]
    Encode {
        /// File.
        path: String,
        /// Why.
        reason: String,
    },
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io { path: path.display().to_string(), source }
}

/// Writes `timeseries.csv` into `w` (one row per sample; columns `t_s`, controls, wind,
/// reference states `ref_*`, true increments `truth_<name>`, then per estimator
/// `<label>.<name>` (empty while not identified); sample-driven estimators add
/// `<label>.<name>.sigma` and `<label>.<name>.truth`; two-aircraft estimators add their
/// aircraft's `<label>.<state>` and, published ones, `<label>.K<g>`, `<label>.sdot<g>` per
/// group). `path` names the file in errors.
///
/// # Errors
/// [`ReportError::Io`] naming the file.
pub fn write_timeseries_to(
    out: &RunOutput,
    w: &mut dyn std::io::Write,
    path: &Path,
) -> Result<(), ReportError> {
    let mut header = String::from(
        "t_s,throttle,elevator_rad,aileron_rad,rudder_rad,wind_north_fps,wind_east_fps,wind_down_fps",
    );
    for n in TRACKED_NAMES {
        write!(header, ",ref_{n}").ok();
    }
    for r in &out.increments {
        write!(header, ",truth_{}", r.param.name()).ok();
    }
    let ngroups: Vec<usize> = out
        .channels
        .iter()
        .map(|c| c.diagnostics.iter().map(Vec::len).max().unwrap_or(0))
        .collect();
    for (ch, &ng) in out.channels.iter().zip(&ngroups) {
        for l in &ch.params {
            let n = l.param.name();
            write!(header, ",{}.{n}", ch.label).ok();
            if ch.quantity == Quantity::Derivative {
                write!(header, ",{0}.{n}.sigma,{0}.{n}.truth", ch.label).ok();
            }
        }
        if !ch.states.is_empty() {
            for n in TRACKED_NAMES {
                write!(header, ",{}.{n}", ch.label).ok();
            }
        }
        for g in 0..ng {
            write!(header, ",{0}.K{g},{0}.sdot{g}", ch.label).ok();
        }
    }
    writeln!(w, "{header}").map_err(io_err(path))?;
    let mut line = String::new();
    let mut buf = ryu::Buffer::new();
    for k in 0..out.t_s.len() {
        line.clear();
        timeseries_row(out, k, &ngroups, &mut buf, &mut line);
        w.write_all(line.as_bytes()).map_err(io_err(path))?;
    }
    w.flush().map_err(io_err(path))
}

/// Row `k` of `timeseries.csv` (with its newline) appended to `line`, numbers as `{}` writes
/// them ([`push_f64`]), an absent value as an empty cell.
fn timeseries_row(
    out: &RunOutput,
    k: usize,
    ngroups: &[usize],
    buf: &mut ryu::Buffer,
    line: &mut String,
) {
    push_f64(line, buf, out.t_s[k]);
    let mut cell = |line: &mut String, v: Option<f64>| {
        line.push(',');
        if let Some(x) = v {
            push_f64(line, buf, x);
        }
    };
    let (c, wd) = (out.controls[k], out.wind_ned_fps[k]);
    for x in c.into_iter().chain(wd).chain(tracked(&out.reference[k])) {
        cell(line, Some(x));
    }
    for r in &out.increments {
        cell(line, Some(r.at(out.t_s[k])));
    }
    for (ch, &ng) in out.channels.iter().zip(ngroups) {
        for l in &ch.params {
            cell(line, l.estimate[k]);
            if ch.quantity == Quantity::Derivative {
                cell(line, l.sigma[k]);
                cell(line, l.truth[k]);
            }
        }
        for v in ch.states.get(k).map(tracked).into_iter().flatten() {
            cell(line, Some(v));
        }
        for g in 0..ng {
            let d = ch.diagnostics.get(k).and_then(|d| d.get(g));
            cell(line, d.map(|d| d.K));
            cell(line, d.map(|d| d.sdot));
        }
    }
    line.push('\n');
}

fn sec(v: Option<f64>) -> String {
    v.map_or("—".to_string(), |x| format!("{x:.2} s"))
}

fn num(v: Option<f64>) -> String {
    v.map_or("null".to_string(), |x| format!("{x:.4e}"))
}

/// One line on an estimator's targets: met / total primary derivatives and the missed ones.
pub fn targets_line(t: &TargetSummary) -> String {
    let missed = if t.missed.is_empty() {
        String::new()
    } else {
        format!(" (missed: {})", t.missed.join(", "))
    };
    format!("{}: {}/{} primary derivatives meet the targets{missed}", t.estimator, t.met, t.total)
}

/// One line on a batch fit: window, initial state, iterations, wall time, σ kind.
pub fn batch_fit_line(b: &aeroident_pipelines::aircraft::batch::BatchFit) -> String {
    format!(
        "{}: post-flight fit of {} samples, t = {:.2}–{:.2} s (initial state: {}), {} iterations, {:.2} s wall; σ {}; time columns: batch (no estimate before the end)",
        b.estimator,
        b.samples,
        b.from_s,
        b.to_s,
        b.initial_states,
        b.iterations.map_or("—".into(), |i| i.to_string()),
        b.wall_s,
        if b.coloured_sigma { "coloured-residual" } else { "Cramér–Rao" },
    )
}

/// A terminal table of a summary: the thesis-style table for increments, the truth / estimate
/// ± σ / times table for derivatives.
pub fn table(summary: &Summary) -> String {
    let mut s = String::new();
    writeln!(
        s,
        "scenario {}  (realtime factor {:.0}×, {})",
        summary.scenario, summary.realtime_factor, summary.solver
    )
    .ok();
    let incs: Vec<&ParamSummary> =
        summary.parameters.iter().filter(|p| p.quantity == "increment").collect();
    if !incs.is_empty() {
        writeln!(
            s,
            "{:<22} {:<10} {:>11} {:>11} {:>9} {:>9} {:>9}",
            "estimator", "increment", "truth", "final", "rel.err", "t_conv", "thesis"
        )
        .ok();
        for p in incs {
            writeln!(
                s,
                "{:<22} {:<10} {:>11} {:>11} {:>9} {:>9} {:>9}",
                p.estimator,
                p.name,
                num(p.reference),
                num(p.estimate),
                p.rel_error.map_or("—".into(), |e| format!("{:.1}%", 100.0 * e)),
                sec(p.convergence_time_s),
                p.thesis_note.clone().unwrap_or_else(|| sec(p.thesis_convergence_time_s)),
            )
            .ok();
        }
        if let Some(r) = summary.reconvergence_time_s {
            writeln!(s, "worst re-convergence after the step: {r:.2} s").ok();
        }
    }
    let ders: Vec<&ParamSummary> =
        summary.parameters.iter().filter(|p| p.quantity == "derivative").collect();
    if !ders.is_empty() {
        if let Some(a) = &summary.angular_accelerations {
            writeln!(s, "angular accelerations: {a}").ok();
        }
        writeln!(
            s,
            "excitation from {}, damage at {}; times to stay within ±10 % of truth (target ≤ {TARGET_WINDOW_S} s); * = primary derivative",
            sec(summary.excitation_start_s),
            sec(summary.damage_at_s)
        )
        .ok();
        writeln!(
            s,
            "{:<10} {:<13} {:>11} {:>11} {:>11} {:>10} {:>8} {:>8} {:>6} {:>7}",
            "estimator",
            "derivative",
            "truth",
            "truth after",
            "final",
            "± σ",
            "t_10%",
            "re_10%",
            "2σ ok",
            "target"
        )
        .ok();
        for p in ders {
            writeln!(
                s,
                "{:<10} {:<13} {:>11} {:>11} {:>11} {:>10} {:>8} {:>8} {:>6} {:>7}",
                p.estimator,
                format!("{}{}", p.name, if p.primary { "*" } else { "" }),
                num(p.truth_before),
                if p.step_at_s.is_some() { num(p.truth_after) } else { "=".into() },
                num(p.estimate),
                p.std_error.map_or("—".into(), |x| format!("{x:.2e}")),
                if p.batch { "batch".into() } else { sec(p.time_to_10pct_s) },
                if p.batch {
                    "batch".into()
                } else if summary.damage_at_s.is_some() {
                    sec(p.reconvergence_10pct_s)
                } else {
                    "—".into()
                },
                p.covers_truth_2sigma.map_or("—", |b| if b { "yes" } else { "NO" }),
                p.meets_targets.map_or("", |b| if b { "met" } else { "MISSED" }),
            )
            .ok();
        }
        for b in &summary.batch_fits {
            writeln!(s, "{}", batch_fit_line(b)).ok();
        }
        for t in &summary.targets {
            writeln!(s, "{}", targets_line(t)).ok();
        }
    }
    s
}

fn opt_s(v: Option<f64>) -> String {
    v.map_or("never".to_string(), |x| format!("{x:.2} s"))
}

/// Verdict on a thesis time claim, from our settling time.
fn verdict(p: &ParamSummary) -> &'static str {
    match (p.convergence_time_s, p.thesis_convergence_time_s, p.thesis_note.as_deref()) {
        (None, _, _) => "never settles",
        (Some(t), Some(th), _) if t <= th => "settles, ≤ thesis",
        (Some(_), Some(_), _) => "settles, slower than thesis",
        (Some(t), None, Some(n)) if n.starts_with('>') => {
            if t < n
                .trim_start_matches('>')
                .trim_end_matches(" s")
                .trim()
                .parse::<f64>()
                .unwrap_or(0.0)
            {
                "settles, faster than thesis"
            } else {
                "settles, as slow as thesis"
            }
        }
        (Some(_), _, _) => "settles",
    }
}

/// The thesis-versus-ours tables of several runs (markdown), one section per thesis table
/// (scenarios grouped by the prefix of `thesis_table`), plus a realtime-factor column.
pub fn markdown(results: &[(aeroident_pipelines::aircraft::Scenario, Summary)]) -> String {
    let mut s = String::new();
    let mut groups: Vec<String> = Vec::new();
    for (sc, _) in results {
        let g = sc
            .thesis_table
            .clone()
            .map(|t| {
                t.split(" case").next().unwrap_or(&t).split(" (").next().unwrap_or(&t).to_string()
            })
            .unwrap_or_else(|| "other".into());
        if !groups.contains(&g) {
            groups.push(g);
        }
    }
    const ORDER: [&str; 7] = ["4.7", "4.8", "4.9", "4.10", "combined", "4.2.5", "beyond"];
    groups.sort_by_key(|g| ORDER.iter().position(|o| o == g).unwrap_or(ORDER.len()));
    for g in groups {
        let title = match g.as_str() {
            "4.7" => "Table 4.7 — ΔCm_α alone".to_string(),
            "4.8" => "Table 4.8 — ΔCm_q alone".to_string(),
            "4.9" => "Table 4.9 — ΔCL_α alone".to_string(),
            "4.10" => "Table 4.10 — ΔCD_α alone".to_string(),
            "combined" => {
                "Combined run (all four at once; thesis Figs 4.59–4.61, pages not in our copy)"
                    .to_string()
            }
            "4.2.5" => {
                "Model-reference gradient (3.3) vs SMPE (thesis §4.2.5, pages not in our copy)"
                    .to_string()
            }
            "beyond" => "Beyond the thesis".to_string(),
            other => other.to_string(),
        };
        writeln!(s, "\n### {title}\n").ok();
        writeln!(s, "| scenario | estimator | param | truth (1/rad) | final | rel. err | first in ±5 % | settled in ±5 % | thesis | verdict | re-conv. after step | RT factor |").ok();
        writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|").ok();
        for (sc, sm) in results.iter().filter(|(sc, _)| {
            sc.thesis_table.as_deref().is_some_and(|t| t.starts_with(&g))
                || (g == "other" && sc.thesis_table.is_none())
        }) {
            for p in &sm.parameters {
                let name = if p.quantity == "increment" {
                    format!("Δ{}", p.name)
                } else {
                    p.name.clone()
                };
                writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.0}× |",
                    sc.name,
                    p.estimator,
                    name,
                    p.reference.map_or("—".into(), |v| format!("{v:.4e}")),
                    p.estimate.map_or("null".into(), |v| format!("{v:.4e}")),
                    p.rel_error.map_or("—".into(), |e| format!("{:.1} %", 100.0 * e)),
                    opt_s(p.first_within_s),
                    opt_s(p.convergence_time_s),
                    p.thesis_note.clone().unwrap_or_else(|| "—".into()),
                    if p.failure.is_some() { "estimator failed" } else { verdict(p) },
                    if p.step_at_s.is_some() {
                        opt_s(p.reconvergence_time_s)
                    } else {
                        "—".into()
                    },
                    sm.realtime_factor,
                )
                .ok();
            }
        }
    }
    s
}
