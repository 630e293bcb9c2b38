//! The thesis-style figures of a run: `controls.png` (pilot commands and wind, cf. thesis
//! Fig. 4.23), `convergence.png` (estimates vs truth, Fig. 4.24; sample-driven estimators with
//! their ±2σ band) and `tracking.png` (reference vs estimated aircraft states, Fig. 4.25).

use crate::outdir::OutputDir;

use aeroident_estimators::vocabulary::Param;

use super::experiment::{Quantity, RunOutput, TRACKED_NAMES, tracked};
use super::report::{PRIMARY_DERIVATIVES, ReportError};
use crate::plot::{LineKind, Panel, Series, render_panels_png};

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

/// Hides (as gaps) the points of every series but the first (the truth) that lie further than
/// the truth's largest magnitude outside the truth's range, so the start-up transient of an
/// estimator does not flatten the scale of the whole panel.
fn clip_to_truth_band(s: &mut [Series]) {
    let Some((truth, rest)) = s.split_first_mut() else { return };
    let (lo, hi) = truth
        .values
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    if !(lo.is_finite() && hi.is_finite()) {
        return;
    }
    let m = lo.abs().max(hi.abs()).max(1e-6);
    for series in rest {
        for v in &mut series.values {
            if *v < lo - m || *v > hi + m {
                *v = f64::NAN;
            }
        }
    }
}

/// Writes `controls.png`, `convergence.png` and `tracking.png` into `od` (each atomically).
///
/// # Errors
/// [`ReportError::Output`] naming the file.
pub fn write_figures(out: &RunOutput, od: &mut OutputDir) -> Result<(), ReportError> {
    let t = &out.t_s;
    let name = &out.scenario.name;
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
    od.write_path("controls.png", |p| {
        render_panels_png(p, &format!("{name}: control commands"), &controls, 1000, 220)
    })?;

    let mut conv = Vec::new();
    for (p, q) in plotted(out) {
        let chans: Vec<_> = out
            .channels
            .iter()
            .filter(|c| c.quantity == q)
            .filter_map(|c| c.param(p).map(|l| (c, l)))
            .collect();
        let Some((_, first)) = chans.first() else { continue };
        let mut s = vec![series("truth", t, opt(&first.truth), LineKind::Dashed)];
        for (c, l) in &chans {
            s.push(series(&c.label, t, opt(&l.estimate), LineKind::Solid));
            if l.sigma.iter().any(Option::is_some) {
                for (sign, tag) in [(1.0, "+2σ"), (-1.0, "−2σ")] {
                    let band: Vec<f64> = l
                        .estimate
                        .iter()
                        .zip(&l.sigma)
                        .map(|(e, s)| match (e, s) {
                            (Some(e), Some(s)) => e + sign * 2.0 * s,
                            _ => f64::NAN,
                        })
                        .collect();
                    s.push(series(&format!("{} {tag}", c.label), t, band, LineKind::Dashed));
                }
            }
        }
        if q == Quantity::Derivative {
            clip_to_truth_band(&mut s);
        }
        let title = match q {
            Quantity::Increment => format!("Δ{}", p.name()),
            Quantity::Derivative => p.name().to_string(),
        };
        conv.push(Panel {
            title: title.clone(),
            y_label: format!("{title} (per rad)"),
            series: s,
            ..Default::default()
        });
    }
    if !conv.is_empty() {
        od.write_path("convergence.png", |p| {
            render_panels_png(p, &format!("{name}: parameter convergence"), &conv, 1000, 240)
        })?;
    }

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
    od.write_path("tracking.png", |p| {
        render_panels_png(p, &format!("{name}: reference vs estimated aircraft"), &track, 1000, 220)
    })?;
    Ok(())
}
