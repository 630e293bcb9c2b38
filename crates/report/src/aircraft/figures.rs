//! The thesis-style figures of a run, each as PNG and SVG: `controls` (pilot commands and wind,
//! cf. thesis Fig. 4.23), `convergence` (estimates vs truth, Fig. 4.24; sample-driven
//! estimators with their shaded ±2σ band) and `tracking` (reference vs estimated aircraft
//! states, Fig. 4.25).

use crate::outdir::OutputDir;

use aeroident_estimators::vocabulary::Param;

use super::outputs::ReportError;
use crate::plot::{Band, LineKind, Panel, Series};
use crate::report::{Figure, write_figure};
use aeroident_pipelines::aircraft::experiment::{Quantity, RunOutput, TRACKED_NAMES, tracked};
use aeroident_pipelines::aircraft::summary::PRIMARY_DERIVATIVES;

fn series(label: &str, t: &[f64], v: Vec<f64>, kind: LineKind) -> Series {
    Series { label: label.into(), t_s: t.to_vec(), values: v, kind }
}

fn opt(v: &[Option<f64>]) -> Vec<f64> {
    // Non-finite points are skipped by the plotter: a gap while not identified.
    v.iter().map(|x| x.unwrap_or(f64::NAN)).collect()
}

/// The parameters drawn in `convergence.png`: every increment of a two-aircraft estimator;
/// of the sample-driven ones, the primary derivatives and any whose truth changes.
fn plotted(out: &RunOutput) -> Vec<(Param, Quantity)> {
    let mut v: Vec<(Param, Quantity)> = Vec::new();
    for ch in &out.channels {
        for l in &ch.params {
            let changes = l.truth.windows(2).any(|w| w[0] != w[1]);
            let keep = ch.quantity == Quantity::Increment
                || PRIMARY_DERIVATIVES.contains(&l.param.name())
                || changes;
            if keep && !v.contains(&(l.param, ch.quantity)) {
                v.push((l.param, ch.quantity));
            }
        }
    }
    v
}

/// Writes `controls`, `convergence` and `tracking` (each `.png` and `.svg`, atomically) into
/// `od` and returns them as report figures.
///
/// # Errors
/// [`ReportError::Output`] naming the file.
pub fn write_figures(out: &RunOutput, od: &mut OutputDir) -> Result<Vec<Figure>, ReportError> {
    let mut figures = Vec::new();
    let name = &out.scenario.name;
    figures.push(write_figure::<ReportError>(
        od,
        "controls",
        &format!("{name}: control commands"),
        "Pilot commands and wind.",
        &controls_panels(out),
        (1000, 220),
    )?);
    let conv: Vec<Panel> =
        plotted(out).into_iter().filter_map(|(p, q)| convergence_panel(out, p, q)).collect();
    if !conv.is_empty() {
        figures.push(write_figure::<ReportError>(
            od,
            "convergence",
            &format!("{name}: parameter convergence"),
            "Estimates against the truth (dashed): a gap until identified, shaded ±2σ where the method gives σ; y-range from the converged part.",
            &conv,
            (1000, 240),
        )?);
    }
    figures.push(write_figure::<ReportError>(
        od,
        "tracking",
        &format!("{name}: reference vs estimated aircraft"),
        "Reference aircraft's states against the estimated aircraft's.",
        &tracking_panels(out),
        (1000, 220),
    )?);
    Ok(figures)
}

/// The panels of `controls`: the elevator always, aileron and rudder when they move (deg),
/// throttle (0–1) and the wind (NED, ft/s), drawn as signals.
fn controls_panels(out: &RunOutput) -> Vec<Panel> {
    let t = &out.t_s;
    let deg = |v: f64| v.to_degrees();
    let mut controls = Vec::new();
    for (k, surface, sym) in [(1, "elevator", "δe"), (2, "aileron", "δa"), (3, "rudder", "δr")] {
        let v: Vec<f64> = out.controls.iter().map(|c| deg(c[k])).collect();
        let first = v.first().copied().unwrap_or(0.0);
        if k == 1 || v.iter().any(|x| *x != first) {
            controls.push(Panel {
                title: surface.into(),
                y_label: format!("{sym} (deg)"),
                series: vec![series(surface, t, v, LineKind::Solid)],
                ..Default::default()
            });
        }
    }
    controls.push(Panel {
        title: "throttle".into(),
        y_label: "throttle (0–1)".into(),
        series: vec![series(
            "throttle",
            t,
            out.controls.iter().map(|c| c[0]).collect(),
            LineKind::Solid,
        )],
        ..Default::default()
    });
    controls.push(Panel {
        title: "wind (NED)".into(),
        y_label: "wind (ft/s)".into(),
        series: ["north", "east", "down"]
            .iter()
            .enumerate()
            .map(|(k, n)| {
                series(n, t, out.wind_ned_fps.iter().map(|w| w[k]).collect(), LineKind::Solid)
            })
            .collect(),
        ..Default::default()
    });
    for p in &mut controls {
        p.signals = true;
    }
    controls
}

/// The `convergence` panel of parameter `p` as quantity `q`: the truth (dashed) and every
/// channel's estimate, with its ±2σ band where the channel gives σ; `None` when no channel
/// estimates it.
fn convergence_panel(out: &RunOutput, p: Param, q: Quantity) -> Option<Panel> {
    let t = &out.t_s;
    let chans: Vec<_> = out
        .channels
        .iter()
        .filter(|c| c.quantity == q)
        .filter_map(|c| c.param(p).map(|l| (c, l)))
        .collect();
    let (_, first) = chans.first()?;
    let mut s = vec![series("truth", t, opt(&first.truth), LineKind::Dashed)];
    let mut bands = Vec::new();
    for (c, l) in &chans {
        s.push(series(&c.label, t, opt(&l.estimate), LineKind::Solid));
        if l.sigma.iter().any(Option::is_some) {
            let bound = |sign: f64| -> Vec<f64> {
                l.estimate
                    .iter()
                    .zip(&l.sigma)
                    .map(|(e, s)| match (e, s) {
                        (Some(e), Some(s)) => e + sign * 2.0 * s,
                        _ => f64::NAN,
                    })
                    .collect()
            };
            bands.push(Band {
                label: format!("{} ±2σ", c.label),
                series: s.len() - 1,
                t_s: t.to_vec(),
                lo: bound(-1.0),
                hi: bound(1.0),
            });
        }
    }
    let title = match q {
        Quantity::Increment => format!("Δ{}", p.name()),
        Quantity::Derivative => p.name().to_string(),
    };
    Some(Panel {
        title: title.clone(),
        y_label: format!("{title} (per rad)"),
        series: s,
        bands,
        ..Default::default()
    })
}

/// The panels of `tracking`: each tracked state of the reference aircraft (dashed) against
/// every estimated aircraft's (angles and rates in deg); β, p and r are left out of a run
/// where the reference keeps them at zero (a longitudinal run).
fn tracking_panels(out: &RunOutput) -> Vec<Panel> {
    let t = &out.t_s;
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
        let lateral_still = out.reference.iter().all(|x| tracked(x)[k].abs() < 1e-9);
        if (k == 2 || k == 3 || k == 5) && lateral_still {
            continue; // lateral states stay at zero in the longitudinal runs
        }
        let mut s = vec![series(
            "reference",
            t,
            out.reference.iter().map(|x| tracked(x)[k] * scale[k]).collect(),
            LineKind::Dashed,
        )];
        for c in out.channels.iter().filter(|c| !c.states.is_empty()) {
            s.push(series(
                &format!("{} aircraft", c.label),
                t,
                c.states.iter().map(|x| tracked(x)[k] * scale[k]).collect(),
                LineKind::Solid,
            ));
        }
        track.push(Panel {
            title: TRACKED_NAMES[k].into(),
            y_label: (*unit).into(),
            series: s,
            ..Default::default()
        });
    }
    for p in &mut track {
        p.signals = true;
    }
    track
}
