//! `aeroident f16`: the Stevens–Lewis F-16: state derivatives, trim, linearization
//! and open-loop simulation ([`crate::sim`]).
//!
//! ```text
//! aeroident f16 xdot --state 500,0.5,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,10000,90 \
//!                    --controls 0.9,20,-15,-20 --xcg 0.4 [--json]
//! aeroident f16 trim --alt-ft 20000 --vt-fps 675 [--xcg 0.35] [--gamma-deg 0] [--json]
//! aeroident f16 linearize --alt-ft 20000 --vt-fps 675 [--xcg 0.35] [--json]
//! aeroident f16 sim scenarios/sim/elevator_doublet.toml --out out/sim
//! ```
//! `xdot` takes the state in the textbook's units (ft/s, rad, rad/s, ft, percent) and the controls
//! as throttle 0–1 and surfaces in **degrees**, exactly as SLJ Table 3.5-2 gives them.

use aeroident_models::Dynamics;
use aeroident_models::f16::{
    ALPHA, BETA, F16, F16Controls, F16State, N_STATES, STATE_NAMES, THETA,
};
use aeroident_models::linearize::{eigenvalues, f16_modes, linearize_f16};
use aeroident_pipelines::sim::trim;
use anyhow::{Context, bail};
use serde_json::json;

/// Arguments of `aeroident f16`.
#[derive(Debug, clap::Args)]
pub struct F16Args {
    /// What to do.
    #[command(subcommand)]
    pub command: F16Command,
}

/// The `aeroident f16` subcommands.
#[derive(Debug, clap::Subcommand)]
pub enum F16Command {
    /// Print the 13 state derivatives at a state and controls (SLJ §3.5).
    Xdot(XdotArgs),
    /// Trim in steady wings-level flight, or a coordinated turn / pull-up (SLJ §3.6; thesis trim
    /// index 2.31).
    Trim(TrimArgs),
    /// Trim, then print A, B, eigenvalues and modes (SLJ §3.7–3.8).
    Linearize(TrimArgs),
    /// Open-loop simulation of a scenario from trim (format: `aeroident::sim::scenario`).
    Sim(SimArgs),
}

/// Arguments of `aeroident f16 xdot`.
#[derive(Debug, clap::Args)]
pub struct XdotArgs {
    /// 13 comma-separated state values: vt (ft/s), alpha, beta, phi, theta, psi (rad), p, q, r
    /// (rad/s), north, east, altitude (ft), power (percent).
    #[arg(long, allow_hyphen_values = true)]
    pub state: String,
    /// 4 comma-separated controls: throttle (0–1), elevator, aileron, rudder (deg).
    #[arg(long, allow_hyphen_values = true)]
    pub controls: String,
    /// Centre of gravity, fraction of the mean aerodynamic chord.
    #[arg(long, default_value_t = 0.35)]
    pub xcg: f64,
    /// Print JSON `{"xdot": [13 numbers]}` instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `aeroident f16 trim` and `aeroident f16 linearize`.
#[derive(Debug, clap::Args)]
pub struct TrimArgs {
    /// Altitude, ft.
    #[arg(long, allow_hyphen_values = true)]
    pub alt_ft: f64,
    /// True airspeed, ft/s.
    #[arg(long)]
    pub vt_fps: f64,
    /// Centre of gravity, fraction of the mean aerodynamic chord.
    #[arg(long, default_value_t = 0.35)]
    pub xcg: f64,
    /// Flight-path angle, deg.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub gamma_deg: f64,
    /// Steady coordinated turn at this turn rate, deg/s (SLJ §3.6 turn constraint) instead of
    /// wings-level flight.
    #[arg(long, allow_hyphen_values = true, conflicts_with = "pull_up_deg_s")]
    pub turn_rate_deg_s: Option<f64>,
    /// Steady pull-up at this pitch rate, deg/s (SLJ §3.6) instead of wings-level flight.
    #[arg(long, allow_hyphen_values = true)]
    pub pull_up_deg_s: Option<f64>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

impl TrimArgs {
    /// The condition these arguments ask for.
    pub fn request(&self) -> trim::TrimRequest {
        trim::TrimRequest {
            alt_ft: self.alt_ft,
            vt_fps: self.vt_fps,
            xcg: self.xcg,
            gamma_deg: self.gamma_deg,
            turn_rate_deg_s: self.turn_rate_deg_s,
            pull_up_deg_s: self.pull_up_deg_s,
        }
    }
}

/// Runs `aeroident f16`.
///
/// # Errors
/// Malformed numbers, a model evaluation outside its domain, or a trim that does not converge.
pub fn execute(args: F16Args) -> anyhow::Result<()> {
    match args.command {
        F16Command::Xdot(a) => super::print_stdout(&xdot(&a)?)?,
        F16Command::Trim(a) => super::print_stdout(&trim_report(&a)?)?,
        F16Command::Linearize(a) => super::print_stdout(&linearize_report(&a)?)?,
        F16Command::Sim(a) => execute_sim(a)?,
    }
    Ok(())
}

fn parse_list(what: &str, s: &str, n: usize) -> anyhow::Result<Vec<f64>> {
    let v: Vec<f64> = s
        .split(',')
        .enumerate()
        .map(|(k, t)| {
            t.trim().parse::<f64>().with_context(|| {
                format!("--{what}: element {} (`{}`) is not a number", k + 1, t.trim())
            })
        })
        .collect::<anyhow::Result<_>>()?;
    if v.len() != n {
        bail!("--{what}: expected {n} comma-separated values, got {}", v.len());
    }
    if let Some(k) = v.iter().position(|x| !x.is_finite()) {
        bail!("--{what}: element {} is not finite", k + 1);
    }
    Ok(v)
}

/// `aeroident f16 xdot` output (table or JSON).
///
/// # Errors
/// Malformed `--state`/`--controls` or a state outside the model's domain.
pub fn xdot(a: &XdotArgs) -> anyhow::Result<String> {
    let s = parse_list("state", &a.state, N_STATES)?;
    let c = parse_list("controls", &a.controls, 4)?;
    let x = F16State::from_row_slice(&s);
    let u = F16Controls::new(c[0], c[1].to_radians(), c[2].to_radians(), c[3].to_radians());
    let xd = F16::new(a.xcg)?.derivatives(0.0, &x, &u)?;
    if let Some(k) = xd.iter().position(|v| !v.is_finite()) {
        bail!(
            "--state: the derivative of `{}` is not finite ({}): the state is outside the range the model can evaluate",
            STATE_NAMES[k],
            xd[k]
        );
    }
    if a.json {
        return Ok(json!({ "xdot": xd.iter().copied().collect::<Vec<f64>>() }).to_string());
    }
    let mut out = String::from("state derivative (SLJ §3.5 order)\n");
    for (k, name) in STATE_NAMES.iter().enumerate() {
        out.push_str(&format!("  d/dt {name:<10} {:>16.9e}\n", xd[k]));
    }
    Ok(out)
}

/// The F-16 trimmed at `a` ([`aeroident_pipelines::sim::trim::trim_at`]), warning on stderr
/// of anything outside the range the F-16 data are meant for.
///
/// # Errors
/// An `xcg` outside its range, or a trim that does not converge (naming the condition).
pub fn trim_at(a: &TrimArgs) -> anyhow::Result<(F16, aeroident_models::trim::F16Trim)> {
    let (f16, t) = trim::trim_at(&a.request())?;
    for w in &t.out_of_range {
        aeroident_report::note!("warning: {}", trim::out_of_range_warning(w));
    }
    Ok((f16, t))
}

/// `aeroident f16 trim` output (table or JSON with keys throttle, elevator_deg, aileron_deg,
/// rudder_deg, alpha_deg, beta_deg, theta_deg, cost).
///
/// # Errors
/// Invalid condition or no convergence.
pub fn trim_report(a: &TrimArgs) -> anyhow::Result<String> {
    let (_, t) = trim_at(a)?;
    let c = &t.controls;
    let v = json!({
        "throttle": c.throttle,
        "elevator_deg": c.elevator_rad.to_degrees(),
        "aileron_deg": c.aileron_rad.to_degrees(),
        "rudder_deg": c.rudder_rad.to_degrees(),
        "alpha_deg": t.state[ALPHA].to_degrees(),
        "beta_deg": t.state[BETA].to_degrees(),
        "theta_deg": t.state[THETA].to_degrees(),
        "cost": t.cost,
    });
    if a.json {
        return Ok(v.to_string());
    }
    Ok(format!(
        "trim: {} ft, {} ft/s, xcg {}, gamma {} deg\n  throttle      {:.6}\n  elevator_deg  {:.6}\n  aileron_deg   {:.3e}\n  rudder_deg    {:.3e}\n  alpha_deg     {:.6}\n  beta_deg      {:.3e}\n  theta_deg     {:.6}\n  cost (2.31)   {:.3e}  (max |residual| {:.3e}; Nelder-Mead {} it, Newton {} it)",
        a.alt_ft,
        a.vt_fps,
        a.xcg,
        a.gamma_deg,
        c.throttle,
        c.elevator_rad.to_degrees(),
        c.aileron_rad.to_degrees(),
        c.rudder_rad.to_degrees(),
        t.state[ALPHA].to_degrees(),
        t.state[BETA].to_degrees(),
        t.state[THETA].to_degrees(),
        t.cost,
        t.max_abs_residual(),
        t.nelder_mead_iterations,
        t.newton_iterations
    ))
}

/// `aeroident f16 linearize` output (text or JSON with keys a, b, eigenvalues, modes).
///
/// # Errors
/// Invalid condition, no trim convergence, or a model error at a perturbed point.
pub fn linearize_report(a: &TrimArgs) -> anyhow::Result<String> {
    let (f16, t) = trim_at(a)?;
    let lin = linearize_f16(&f16, &t.state, &t.controls)?;
    let ev = eigenvalues(&lin.a);
    let modes = f16_modes(&lin.a);
    let rows = |m: &dyn Fn(usize, usize) -> f64, nr: usize, nc: usize| -> Vec<Vec<f64>> {
        (0..nr).map(|i| (0..nc).map(|j| m(i, j)).collect()).collect()
    };
    if a.json {
        let v = json!({
            "a": rows(&|i, j| lin.a[(i, j)], 13, 13),
            "b": rows(&|i, j| lin.b[(i, j)], 13, 4),
            "eigenvalues": ev.iter().map(|l| [l.re, l.im]).collect::<Vec<_>>(),
            "modes": modes.iter().map(|m| json!({
                "name": m.name.as_str(),
                "eigenvalue": [m.eigenvalue.re, m.eigenvalue.im],
                "wn_radps": m.wn_rad_s,
                "zeta": m.zeta,
            })).collect::<Vec<_>>(),
        });
        return Ok(v.to_string());
    }
    let mut out = format!(
        "linearization at {} ft, {} ft/s, xcg {} (trim cost {:.2e})\n",
        a.alt_ft, a.vt_fps, a.xcg, t.cost
    );
    out.push_str("states: ");
    out.push_str(&STATE_NAMES.join(", "));
    out.push_str("\ninputs: throttle, elevator_rad, aileron_rad, rudder_rad\nA =\n");
    for i in 0..13 {
        out.push_str(
            &(0..13).map(|j| format!("{:>11.4e}", lin.a[(i, j)])).collect::<Vec<_>>().join(" "),
        );
        out.push('\n');
    }
    out.push_str("B =\n");
    for i in 0..13 {
        out.push_str(
            &(0..4).map(|j| format!("{:>11.4e}", lin.b[(i, j)])).collect::<Vec<_>>().join(" "),
        );
        out.push('\n');
    }
    let ev: Vec<(f64, f64)> = ev.iter().map(|v| (v.re, v.im)).collect();
    out.push_str(&super::linearize::eigen_text(&ev, &modes));
    Ok(out)
}

/// Arguments of `aeroident f16 sim`.
#[derive(Debug, clap::Args)]
pub struct SimArgs {
    /// Scenario TOML file (format: `aeroident_pipelines::sim::scenario`).
    pub scenario: std::path::PathBuf,
    /// Output directory (created if missing).
    #[arg(long)]
    pub out: std::path::PathBuf,
}

/// Runs `aeroident f16 sim`.
///
/// # Errors
/// As [`load_scenario`](aeroident_pipelines::sim::load_scenario), [`run`](aeroident_pipelines::sim::run) and [`write_outputs`](crate::sim::write_outputs).
pub fn execute_sim(args: SimArgs) -> anyhow::Result<()> {
    let sc = aeroident_pipelines::sim::load_scenario(&args.scenario)?;
    let base = args.scenario.parent().unwrap_or(std::path::Path::new("."));
    // Lock and clear the directory first, so a failing run leaves no old outputs.
    let mut od = crate::outdir::OutputDir::open(&args.out, "f16 sim", &[args.scenario.as_path()])?;
    let r = aeroident_pipelines::sim::run(&sc, base)?;
    crate::sim::write_outputs(&r, &mut od)?;
    od.finish();
    super::print_stdout(&format!(
        "simulated {:.2} s ({} rows, {} columns) from trim: throttle {:.4}, elevator {:.4} deg, alpha {:.4} deg (trim cost {:.1e})\nwrote {}/timeseries.csv, report.html, states and controls_wind (.png, .svg)",
        r.table.data[0].last().copied().unwrap_or(0.0),
        r.table.data[0].len(),
        r.table.columns.len(),
        r.trim.controls.throttle,
        r.trim.controls.elevator_rad.to_degrees(),
        r.trim.state[aeroident_models::f16::ALPHA].to_degrees(),
        r.trim.cost,
        args.out.display()
    ))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn val_slj_table_3_5_2_via_cli_json() {
        // Published Table 3.5-2 derivatives (see aeroident_models f16 tests for the citation).
        let a = XdotArgs {
            state: "500,0.5,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,10000,90".into(),
            controls: "0.9,20,-15,-20".into(),
            xcg: 0.4,
            json: true,
        };
        let v: serde_json::Value = serde_json::from_str(&xdot(&a).unwrap()).unwrap();
        let xd: Vec<f64> =
            v["xdot"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        assert_eq!(xd.len(), 13);
        assert!((xd[0] + 75.23724).abs() / 75.23724 < 1e-5);
        assert!((xd[6] - 12.62679).abs() / 12.62679 < 1e-5);
    }

    #[test]
    fn bad_state_is_a_clear_error() {
        let a = XdotArgs {
            state: "500,abc".into(),
            controls: "0.9,20,-15,-20".into(),
            xcg: 0.4,
            json: false,
        };
        let e = xdot(&a).unwrap_err().to_string();
        assert!(e.contains("element 2"), "{e}");
        let a = XdotArgs {
            state: "500,1".into(),
            controls: "0.9,20,-15,-20".into(),
            xcg: 0.4,
            json: false,
        };
        assert!(xdot(&a).unwrap_err().to_string().contains("expected 13"));
    }

    #[test]
    fn trim_and_linearize_json_keys() {
        let a = TrimArgs {
            alt_ft: 0.0,
            vt_fps: 502.0,
            xcg: 0.30,
            gamma_deg: 0.0,
            turn_rate_deg_s: None,
            pull_up_deg_s: None,
            json: true,
        };
        let v: serde_json::Value = serde_json::from_str(&trim_report(&a).unwrap()).unwrap();
        for k in [
            "throttle",
            "elevator_deg",
            "aileron_deg",
            "rudder_deg",
            "alpha_deg",
            "beta_deg",
            "theta_deg",
            "cost",
        ] {
            assert!(v[k].is_number(), "missing {k}");
        }
        // SLJ Table 3.6-3, xcg 0.30: throttle 0.1485, elevator −1.931°.
        assert!((v["throttle"].as_f64().unwrap() - 0.1485).abs() < 6e-5);
        let v: serde_json::Value = serde_json::from_str(&linearize_report(&a).unwrap()).unwrap();
        assert_eq!(v["a"].as_array().unwrap().len(), 13);
        assert_eq!(v["b"].as_array().unwrap()[0].as_array().unwrap().len(), 4);
        assert_eq!(v["eigenvalues"].as_array().unwrap().len(), 13);
        let names: Vec<&str> =
            v["modes"].as_array().unwrap().iter().map(|m| m["name"].as_str().unwrap()).collect();
        for n in ["short_period", "phugoid", "roll", "spiral", "dutch_roll"] {
            assert!(names.contains(&n), "{names:?}");
        }
    }
}
