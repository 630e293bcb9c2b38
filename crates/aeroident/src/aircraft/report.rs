//! Outputs of a run: `timeseries.csv`, `summary.json`, thesis-style figures, and the
//! thesis-versus-ours report of `aeroident run --all`.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use serde::Serialize;

use super::experiment::{RunOutput, TRACKED_NAMES, tracked};
use super::model::Increment;
use crate::metrics::{self, CONVERGENCE_TOL_REL};
use crate::plot::{LineKind, Panel, Series, render_panels_png};

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

/// One estimator × parameter entry of `summary.json`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ParamSummary {
    /// Estimator label.
    pub estimator: String,
    /// `dCm_alpha`, `dCm_q`, `dCL_alpha` or `dCD_alpha`.
    pub name: String,
    /// True value at the end of the run (after a step, the new value), per rad.
    pub truth: f64,
    /// Final estimate, per rad.
    pub r#final: f64,
    /// `(final − truth)/|truth|`.
    pub rel_error: f64,
    /// First time after which the estimate stays within ±5 % of the truth (before any step),
    /// s; `null` if it never settles.
    pub convergence_time_s: Option<f64>,
    /// First time the estimate enters the ±5 % band (it may leave it again), s.
    pub first_within_s: Option<f64>,
    /// The thesis's reported time, s, where legible.
    pub thesis_convergence_time_s: Option<f64>,
    /// The thesis's claim verbatim.
    pub thesis_note: Option<String>,
    /// Time from a step in the truth until the estimate stays within ±5 % of the new truth,
    /// s; `null` without a step or if it never settles.
    pub reconvergence_time_s: Option<f64>,
    /// Estimator failure (time and message), if any; estimates were held from then on.
    pub failure: Option<String>,
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// Estimator labels joined with `+`.
    pub estimator: String,
    /// Integrator and step.
    pub solver: String,
    /// Simulated time / wall-clock time of the closed loop (two aircraft per estimator
    /// channel, sensors, all estimators; no I/O).
    pub realtime_factor: f64,
    /// One entry per estimator and parameter.
    pub parameters: Vec<ParamSummary>,
    /// Worst re-convergence time over entries with a step, s; `null` without a step or if
    /// any entry never re-converged.
    pub reconvergence_time_s: Option<f64>,
    /// Trim: `[vt_fps, alpha_rad, throttle, elevator_rad]`.
    pub trim: [f64; 4],
}

/// Computes the summary of a run.
///
/// # Errors
/// [`ReportError::Metrics`] only on inconsistent logs (a bug).
pub fn summarize(out: &RunOutput) -> Result<Summary, ReportError> {
    let sc = &out.scenario;
    let mut parameters = Vec::new();
    let mut worst_reconv: Option<Option<f64>> = None;
    for ch in &out.channels {
        for inc in &ch.params {
            let i = inc.index();
            let est: Vec<f64> = ch.estimates.iter().map(|e| e[i]).collect();
            let truth: Vec<f64> = out.truth.iter().map(|e| e[i]).collect();
            let entry = sc.param(*inc);
            let step = entry.and_then(|p| p.step_at_s);
            let pre = step.map_or(out.t_s.len(), |t0| out.t_s.partition_point(|&t| t < t0));
            let conv = metrics::convergence_time_series_s(
                &out.t_s[..pre],
                &est[..pre],
                &truth[..pre],
                CONVERGENCE_TOL_REL,
                f64::NEG_INFINITY,
            )?;
            let reconv = match step {
                Some(t0) => {
                    let r = metrics::reconvergence_time_s(
                        &out.t_s,
                        &est,
                        &truth,
                        CONVERGENCE_TOL_REL,
                        t0,
                    )?;
                    worst_reconv =
                        Some(match (worst_reconv.flatten(), r, worst_reconv.is_some()) {
                            (_, None, _) => None,
                            (Some(w), Some(r), _) => Some(w.max(r)),
                            (None, Some(_), true) => None,
                            (None, Some(r), false) => Some(r),
                        });
                    r
                }
                None => None,
            };
            let first_within_s = (0..pre)
                .find(|&k| {
                    (est[k] - truth[k]).abs()
                        <= metrics::band_half_width(truth[k], CONVERGENCE_TOL_REL)
                })
                .map(|k| out.t_s[k]);
            let fin = est.last().copied().unwrap_or(f64::NAN);
            let tru = truth.last().copied().unwrap_or(f64::NAN);
            parameters.push(ParamSummary {
                estimator: ch.label.clone(),
                name: inc.name().into(),
                truth: tru,
                r#final: fin,
                rel_error: metrics::rel_error(fin, tru),
                convergence_time_s: conv,
                first_within_s,
                thesis_convergence_time_s: entry.and_then(|p| p.thesis_convergence_time_s),
                thesis_note: entry.and_then(|p| p.thesis_note.clone()),
                reconvergence_time_s: reconv,
                failure: ch.failure.as_ref().map(|(t, m)| format!("t = {t:.2} s: {m}")),
            });
        }
    }
    Ok(Summary {
        scenario: sc.name.clone(),
        estimator: out.channels.iter().map(|c| c.label.as_str()).collect::<Vec<_>>().join("+"),
        solver: format!("rk4, dt = {} s", sc.dt_s),
        realtime_factor: out.realtime_factor(),
        parameters,
        reconvergence_time_s: worst_reconv.flatten(),
        trim: [
            out.trim.state[aeroident_models::f16::VT],
            out.trim.state[aeroident_models::f16::ALPHA],
            out.trim.controls.throttle,
            out.trim.controls.elevator_rad,
        ],
    })
}

/// Writes `timeseries.csv` (one row per sample; columns `t_s`, controls, wind, reference
/// states `ref_*`, truths `truth_*`, then per estimator `<label>.<param>`, `<label>.<state>`,
/// and for published estimators `<label>.K<g>`, `<label>.sdot<g>` per coefficient group).
///
/// # Errors
/// [`ReportError::Io`] naming the file.
pub fn write_timeseries(out: &RunOutput, path: &Path) -> Result<(), ReportError> {
    let f = std::fs::File::create(path).map_err(io_err(path))?;
    let mut w = std::io::BufWriter::new(f);
    let mut header = String::from(
        "t_s,throttle,elevator_rad,aileron_rad,rudder_rad,wind_north_fps,wind_east_fps,wind_down_fps",
    );
    for n in TRACKED_NAMES {
        write!(header, ",ref_{n}").ok();
    }
    for inc in Increment::ALL {
        write!(header, ",truth_{}", inc.name()).ok();
    }
    let ngroups: Vec<usize> = out
        .channels
        .iter()
        .map(|c| c.diagnostics.iter().map(Vec::len).max().unwrap_or(0))
        .collect();
    for (ch, &ng) in out.channels.iter().zip(&ngroups) {
        for inc in &ch.params {
            write!(header, ",{}.{}", ch.label, inc.name()).ok();
        }
        for n in TRACKED_NAMES {
            write!(header, ",{}.{n}", ch.label).ok();
        }
        for g in 0..ng {
            write!(header, ",{0}.K{g},{0}.sdot{g}", ch.label).ok();
        }
    }
    writeln!(w, "{header}").map_err(io_err(path))?;
    let mut line = String::new();
    for k in 0..out.t_s.len() {
        line.clear();
        let c = out.controls[k];
        let wd = out.wind_ned_fps[k];
        write!(
            line,
            "{},{},{},{},{},{},{},{}",
            out.t_s[k], c[0], c[1], c[2], c[3], wd[0], wd[1], wd[2]
        )
        .ok();
        for v in tracked(&out.reference[k]) {
            write!(line, ",{v}").ok();
        }
        for v in out.truth[k] {
            write!(line, ",{v}").ok();
        }
        for (ch, &ng) in out.channels.iter().zip(&ngroups) {
            for inc in &ch.params {
                write!(line, ",{}", ch.estimates[k][inc.index()]).ok();
            }
            for v in tracked(&ch.states[k]) {
                write!(line, ",{v}").ok();
            }
            for g in 0..ng {
                match ch.diagnostics.get(k).and_then(|d| d.get(g)) {
                    Some(d) => write!(line, ",{},{}", d.K, d.sdot).ok(),
                    None => write!(line, ",,").ok(),
                };
            }
        }
        writeln!(w, "{line}").map_err(io_err(path))?;
    }
    w.flush().map_err(io_err(path))
}

/// Writes `summary.json`.
///
/// # Errors
/// [`ReportError`] naming the file.
pub fn write_summary(summary: &Summary, path: &Path) -> Result<(), ReportError> {
    let text = serde_json::to_string_pretty(summary).map_err(|e| ReportError::Encode {
        path: path.display().to_string(),
        reason: e.to_string(),
    })?;
    std::fs::write(path, text + "\n").map_err(io_err(path))
}

fn series(label: &str, t: &[f64], v: Vec<f64>, kind: LineKind) -> Series {
    Series { label: label.into(), t_s: t.to_vec(), values: v, kind }
}

/// Writes the thesis-style figures: `controls.png` (pilot commands, cf. thesis Fig. 4.23),
/// `convergence.png` (estimates vs truth, Fig. 4.24) and `tracking.png` (reference vs
/// estimated aircraft states, Fig. 4.25), into `dir`.
///
/// # Errors
/// [`ReportError::Plot`] naming the file.
pub fn write_figures(out: &RunOutput, dir: &Path) -> Result<(), ReportError> {
    let t = &out.t_s;
    let name = &out.scenario.name;
    let deg = |v: f64| v.to_degrees();
    let controls = vec![
        Panel {
            title: "elevator".into(),
            y_label: "δe (deg)".into(),
            series: vec![series(
                "elevator",
                t,
                out.controls.iter().map(|c| deg(c[1])).collect(),
                LineKind::Solid,
            )],
        },
        Panel {
            title: "throttle".into(),
            y_label: "throttle (0–1)".into(),
            series: vec![series(
                "throttle",
                t,
                out.controls.iter().map(|c| c[0]).collect(),
                LineKind::Solid,
            )],
        },
        Panel {
            title: "wind (NED)".into(),
            y_label: "wind (ft/s)".into(),
            series: ["north", "east", "down"]
                .iter()
                .enumerate()
                .map(|(k, n)| {
                    series(n, t, out.wind_ned_fps.iter().map(|w| w[k]).collect(), LineKind::Solid)
                })
                .collect(),
        },
    ];
    render_panels_png(
        &dir.join("controls.png"),
        &format!("{name}: control commands"),
        &controls,
        1000,
        220,
    )?;

    let mut conv = Vec::new();
    for inc in Increment::ALL {
        let chans: Vec<_> = out.channels.iter().filter(|c| c.params.contains(&inc)).collect();
        if chans.is_empty() {
            continue;
        }
        let mut s = vec![series(
            "truth",
            t,
            out.truth.iter().map(|v| v[inc.index()]).collect(),
            LineKind::Dashed,
        )];
        for c in chans {
            s.push(series(
                &c.label,
                t,
                c.estimates.iter().map(|v| v[inc.index()]).collect(),
                LineKind::Solid,
            ));
        }
        conv.push(Panel {
            title: inc.name().into(),
            y_label: format!("{} (1/rad)", inc.name()),
            series: s,
        });
    }
    render_panels_png(
        &dir.join("convergence.png"),
        &format!("{name}: parameter convergence"),
        &conv,
        1000,
        240,
    )?;

    let scale = [
        1.0,
        57.29577951308232,
        57.29577951308232,
        57.29577951308232,
        57.29577951308232,
        57.29577951308232,
    ];
    let units = ["V_T (ft/s)", "α (deg)", "β (deg)", "p (deg/s)", "q (deg/s)", "r (deg/s)"];
    let mut track = Vec::new();
    for (k, unit) in units.iter().enumerate() {
        if k == 2 || k == 3 || k == 5 {
            continue; // lateral states stay at zero in the longitudinal runs
        }
        let mut s = vec![series(
            "reference",
            t,
            out.reference.iter().map(|x| tracked(x)[k] * scale[k]).collect(),
            LineKind::Dashed,
        )];
        for c in &out.channels {
            s.push(series(
                &format!("{} aircraft", c.label),
                t,
                c.states.iter().map(|x| tracked(x)[k] * scale[k]).collect(),
                LineKind::Solid,
            ));
        }
        track.push(Panel { title: TRACKED_NAMES[k].into(), y_label: (*unit).into(), series: s });
    }
    render_panels_png(
        &dir.join("tracking.png"),
        &format!("{name}: reference vs estimated aircraft"),
        &track,
        1000,
        220,
    )?;
    Ok(())
}

/// A short terminal table of a summary.
pub fn table(summary: &Summary) -> String {
    let mut s = String::new();
    writeln!(
        s,
        "scenario {}  (realtime factor {:.0}×, {})",
        summary.scenario, summary.realtime_factor, summary.solver
    )
    .ok();
    writeln!(
        s,
        "{:<22} {:<10} {:>11} {:>11} {:>9} {:>9} {:>9}",
        "estimator", "param", "truth", "final", "rel.err", "t_conv", "thesis"
    )
    .ok();
    for p in &summary.parameters {
        let opt = |v: Option<f64>| v.map_or("—".to_string(), |x| format!("{x:.2} s"));
        writeln!(
            s,
            "{:<22} {:<10} {:>11.4e} {:>11.4e} {:>8.1}% {:>9} {:>9}",
            p.estimator,
            p.name,
            p.truth,
            p.r#final,
            100.0 * p.rel_error,
            opt(p.convergence_time_s),
            p.thesis_note.clone().unwrap_or_else(|| opt(p.thesis_convergence_time_s)),
        )
        .ok();
    }
    if let Some(r) = summary.reconvergence_time_s {
        writeln!(s, "worst re-convergence after the step: {r:.2} s").ok();
    }
    s
}

/// Writes all outputs of one run into `dir` (created if needed) and returns the summary.
///
/// # Errors
/// [`ReportError`] naming the file.
pub fn write_all(out: &RunOutput, dir: &Path, figures: bool) -> Result<Summary, ReportError> {
    std::fs::create_dir_all(dir).map_err(io_err(dir))?;
    let summary = summarize(out)?;
    write_timeseries(out, &dir.join("timeseries.csv"))?;
    write_summary(&summary, &dir.join("summary.json"))?;
    if figures {
        write_figures(out, dir)?;
    }
    Ok(summary)
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
pub fn markdown(results: &[(super::Scenario, Summary)]) -> String {
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
                let step = Increment::from_name(&p.name)
                    .and_then(|i| sc.param(i))
                    .and_then(|e| e.step_at_s);
                writeln!(
                    s,
                    "| {} | {} | {} | {:.4e} | {:.4e} | {:.1} % | {} | {} | {} | {} | {} | {:.0}× |",
                    sc.name,
                    p.estimator,
                    p.name,
                    p.truth,
                    p.r#final,
                    100.0 * p.rel_error,
                    opt_s(p.first_within_s),
                    opt_s(p.convergence_time_s),
                    p.thesis_note.clone().unwrap_or_else(|| "—".into()),
                    if p.failure.is_some() { "estimator failed" } else { verdict(p) },
                    if step.is_some() { opt_s(p.reconvergence_time_s) } else { "—".into() },
                    sm.realtime_factor,
                )
                .ok();
            }
        }
    }
    s
}
