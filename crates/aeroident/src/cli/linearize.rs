//! `aeroident linearize`: trim any aircraft wings-level and linearize it there — the F-16, or
//! an aircraft flying identified derivatives (a model file with a summary's estimates or its
//! reference values, and a mapping's constants). The work is the library's
//! ([`aeroident_models::aircraft::linearize_level`], [`aeroident_pipelines::airframe`]); this
//! module translates arguments and renders.
//!
//! ```text
//! aeroident linearize --aircraft f16 --vt-mps 205.7 --alt-m 6096 [--xcg 0.35] [--json]
//! aeroident linearize --aircraft models/my_uav.toml --summary out/summary.json \
//!                     --map mappings/my_uav.toml --vt-mps 18 --alt-m 100 [--json]
//! ```

use aeroident_models::aircraft::{Aircraft, CONTROL_NAMES, linearize_level};
use aeroident_models::f16::F16;
use aeroident_pipelines::airframe::Linear;
use anyhow::Context;
use serde_json::json;

/// Arguments of `aeroident linearize`.
#[derive(Debug, clap::Args)]
pub struct LinearizeArgs {
    /// The aircraft.
    #[command(flatten)]
    pub aircraft: super::aircraft_args::AircraftArgs,
    /// True airspeed of the trim, m/s.
    #[arg(long)]
    pub vt_mps: f64,
    /// Altitude of the trim, m.
    #[arg(long)]
    pub alt_m: f64,
    /// The F-16's cg, fraction of c̄ (`--aircraft f16` only).
    #[arg(long, default_value_t = 0.35)]
    pub xcg: f64,
    /// JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs `aeroident linearize`.
///
/// # Errors
/// Files that cannot be read or do not describe a flyable aircraft, no trim, or a model error.
pub fn execute(a: LinearizeArgs) -> anyhow::Result<()> {
    Ok(super::print_stdout(&report(&a)?)?)
}

/// The report of `aeroident linearize` (text, or JSON with keys aircraft, trim, states,
/// inputs, a, b, c, d, eigenvalues, modes: the state-space model `ẋ = A x + B u`, `y = C x + D u`
/// of the perturbations about the trim, every state an output). A model-file aircraft whose
/// mapping gives a surface an actuator has one more state per actuator (the surface, named as
/// `sim` records it) and that surface's input is its command
/// ([`aeroident_pipelines::airframe::Linear::with_actuators`]); the JSON then also has
/// `actuators` (surface, state, input, τ, pole, limits) and `notes`, the text an actuator
/// line each and the note that rate limits are not in a linear model.
///
/// # Errors
/// As [`execute`].
pub fn report(a: &LinearizeArgs) -> anyhow::Result<String> {
    if a.aircraft.is_f16()? {
        let f = F16::new(a.xcg)?;
        let lin = Linear::of_level(&f, &linearize_level(&f, a.vt_mps, a.alt_m)?);
        return render(&f.name(), f.length_unit_m(), &lin, a.json);
    }
    let m = a.aircraft.model_file()?;
    let lin = linearize_level(&m, a.vt_mps, a.alt_m)
        .with_context(|| format!("{} at {} m/s, {} m", a.aircraft.aircraft, a.vt_mps, a.alt_m))?;
    let flags = aeroident_pipelines::airframe::modes::mode_flags(&m, &lin.trim, &lin.modes);
    let lin = Linear::of_level(&m, &lin).with_actuators(&m.airframe().actuators);
    let mut out = render(&m.name(), m.length_unit_m(), &lin, a.json)?;
    if a.json {
        let mut v: serde_json::Value = serde_json::from_str(&out)?;
        v["mode_flags"] = json!(flags);
        out = v.to_string();
    } else {
        for f in &flags {
            out.push_str(&format!("flag: {f}\n"));
        }
    }
    Ok(out)
}

/// Renders a linearization of the aircraft `name` whose length unit is `unit` m (SI trim
/// values; A, B in the aircraft's state units).
fn render(name: &str, unit: f64, l: &Linear, json: bool) -> anyhow::Result<String> {
    let (x, u) = (&l.trim.state, &l.trim.controls);
    let mut controls: Vec<(String, f64)> = vec![(l.inputs[0].clone(), u[0])];
    controls.extend((1..4).map(|k| (CONTROL_NAMES[k].to_string(), u[k])));
    if json {
        return Ok(render_json(name, unit, l, &controls).to_string());
    }
    let mut out = format!(
        "{name}: trim at {:.3} m/s, {:.1} m: alpha {:.4} deg, theta {:.4} deg (residual {:.1e})\n",
        x[0] * unit,
        x[11] * unit,
        x[1].to_degrees(),
        x[4].to_degrees(),
        l.trim.max_abs_residual
    );
    for (n, v) in &controls {
        out.push_str(&format!("  {n:<32} {v:.6}\n"));
    }
    out.push_str(&eigen_text(&l.eigenvalues, &l.modes));
    out.push_str(&actuator_text(l));
    Ok(out)
}

/// The JSON document of [`render`] (keys of [`report`]); `actuators` and `notes` only when
/// the model has actuators, so a model without them reads as before.
fn render_json(name: &str, unit: f64, l: &Linear, controls: &[(String, f64)]) -> serde_json::Value {
    let n = l.a.len();
    let x = &l.trim.state;
    let modes = l.modes.iter().map(|m| {
        json!({"name": m.name.as_str(), "eigenvalue": [m.eigenvalue.re, m.eigenvalue.im],
               "wn_radps": m.wn_rad_s, "zeta": m.zeta})
    });
    let rows = |m: &dyn Fn(usize, usize) -> f64, nc: usize| -> Vec<Vec<f64>> {
        (0..n).map(|i| (0..nc).map(|j| m(i, j)).collect()).collect()
    };
    let mut v = json!({
        "aircraft": name,
        "trim": {"vt_mps": x[0] * unit, "alpha_rad": x[1], "theta_rad": x[4],
                 "controls": controls.iter().map(|(n, v)| json!({"name": n, "value": v})).collect::<Vec<_>>(),
                 "max_abs_residual": l.trim.max_abs_residual},
        "states": l.states,
        "inputs": l.inputs,
        "a": l.a,
        "b": l.b,
        "c": rows(&|i, j| if i == j { 1.0 } else { 0.0 }, n),
        "d": rows(&|_, _| 0.0, 4),
        "eigenvalues": l.eigenvalues.iter().map(|&(re, im)| [re, im]).collect::<Vec<_>>(),
        "modes": modes.collect::<Vec<_>>(),
    });
    if !l.actuators.is_empty() {
        let finite = |v: f64| v.is_finite().then_some(v);
        v["actuators"] = l
            .actuators
            .iter()
            .map(|s| {
                let (lo, hi) = s.actuator.position_limits_rad;
                json!({"surface": s.surface, "state": s.state, "input": s.input,
                       "tau_s": s.actuator.tau_s, "pole": [s.pole(), 0.0],
                       "rate_limit_rad_s": finite(s.actuator.rate_limit_rad_s),
                       "position_limits_rad": [finite(lo), finite(hi)], "trim_rad": s.trim_rad})
            })
            .collect();
        v["notes"] = json!(l.actuator_notes());
    }
    v
}

/// One line per actuator state (its pole `−1/τ` and limits) and the notes of
/// [`Linear::actuator_notes`]; empty without actuators.
fn actuator_text(l: &Linear) -> String {
    if l.actuators.is_empty() {
        return String::new();
    }
    let mut out = String::from("actuators (one state each; the input is the command):\n");
    for s in &l.actuators {
        let (lo, hi) = s.actuator.position_limits_rad;
        let rate = s.actuator.rate_limit_rad_s;
        out.push_str(&format!(
            "  actuator {:<9} {:>10.5} {:+10.5}j   tau {} s   {} <- {}   rate limit {}   position limits {}\n",
            s.surface,
            s.pole(),
            0.0,
            s.actuator.tau_s,
            s.state,
            s.input,
            if rate.is_finite() { format!("{rate} rad/s") } else { "none".into() },
            if lo.is_finite() { format!("[{lo}, {hi}] rad") } else { "none".into() },
        ));
    }
    for n in l.actuator_notes() {
        out.push_str(&format!("note: {n}\n"));
    }
    out
}

/// The eigenvalues `(re, im)` of an `n`-state A (`n` = `eigenvalues.len()`) and the modes of
/// its longitudinal and lateral 4 × 4 blocks, one per line, as `linearize` and `f16 linearize`
/// print them.
pub fn eigen_text(
    eigenvalues: &[(f64, f64)],
    modes: &[aeroident_models::linearize::Mode],
) -> String {
    let mut out = format!("eigenvalues ({}-state A):\n", eigenvalues.len());
    for (re, im) in eigenvalues {
        out.push_str(&format!("  {re:>12.6} {im:+12.6}j\n"));
    }
    out.push_str("modes (4-state longitudinal / lateral blocks, SLJ §3.7–3.8):\n");
    for m in modes {
        out.push_str(&format!(
            "  {:<18} {:>10.5} {:+10.5}j   wn {:8.4} rad/s   zeta {:7.4}\n",
            m.name.as_str(),
            m.eigenvalue.re,
            m.eigenvalue.im,
            m.wn_rad_s,
            m.zeta
        ));
    }
    out
}
