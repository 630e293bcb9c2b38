//! Open-loop F-16 simulation: trim → fly with pilot inputs, gusts and turbulence →
//! sense → one [`SimRun`](crate::sim::SimRun) (the faces write `timeseries.csv` and figures from it).
//!
//! Run: `aeroident f16 sim scenarios/sim/elevator_doublet.toml --out out/sim`. The scenario
//! format is documented in [`crate::sim::scenario`].
//!
//! # What is simulated
//! * The Stevens–Lewis F-16 (`aeroident_models::f16`), trimmed wings-level at the scenario's
//!   altitude, airspeed and flight-path angle, with optional thesis increments about that trim.
//! * Surfaces through the F-16 actuators (or ideal), throttle through the engine lag.
//! * Commands = trim + Σ inputs of the channel (superposed). Wind = Σ disturbances, in body axes
//!   (signals crate convention), entering the aerodynamics through the air-relative velocity.
//! * RK4 with step `dt_s`; commands and wind are sampled at the start of each step and held over
//!   it (zero-order hold).
//! * Sensors sample the true channels (ZOH at their rate, noise, bias, delay, quantisation).
//!
//! # Output
//! `timeseries.csv`: one row per step, columns [`crate::sim::SimTable::columns`] (units in the names), the
//! sensed channels as `meas_<channel>`; `states.png` and `controls_wind.png`. Besides the state,
//! surfaces, wind, load factors and coefficients, the true channels include what identification
//! needs: ṗ, q̇, ṙ, α̇ from the state derivative and the accelerometer specific force
//! `ax/ay/az_fps2` (`az ≈ −g` level), so `mappings/aeroident-sim.toml` replays the file as it is.

pub mod aircraft;
pub mod scenario;
pub mod trim;

use crate::aircraft::scenario::AerodynamicsSpec;
use crate::aircraft::truth::{linearised, local_derivatives};
use crate::bail;
use crate::error::{Context, Result};
use aeroident_models::actuator::{F16WithActuators, SurfaceActuators};
use aeroident_models::f16::AeroIncrements;
use aeroident_models::f16::{ALPHA, P, Q, R};
use aeroident_models::f16::{
    F16, F16Controls, F16Outputs, F16State, IncrementReference, IncrementSchedule, N_STATES,
    STATE_NAMES,
};
use aeroident_models::integrate::rk4_step;
use aeroident_models::trim::{F16Trim, TrimCondition, TrimManeuver, trim};
use aeroident_signals::config::build_wind;
use aeroident_signals::{Input, InputSignal, SensorModel, Wind, WindField};
use nalgebra::SVector;
use scenario::{ActuatorChoice, Channel, SimScenario};
use std::path::Path;

/// The true channels written for every step, in CSV order after `t_s` (units in the names).
pub fn true_channel_names() -> Vec<String> {
    let mut v: Vec<String> = STATE_NAMES.iter().map(|s| s.to_string()).collect();
    for s in [
        "elevator_rad",
        "aileron_rad",
        "rudder_rad",
        "throttle",
        "elevator_cmd_rad",
        "aileron_cmd_rad",
        "rudder_cmd_rad",
        "wind_body_x_fps",
        "wind_body_y_fps",
        "wind_body_z_fps",
        "vt_air_fps",
        "alpha_air_rad",
        "beta_air_rad",
        "nx_g",
        "ny_g",
        "nz_g",
        "qbar_psf",
        "mach",
        "thrust_lbf",
        "CX",
        "CY",
        "CZ",
        "Cl",
        "Cm",
        "Cn",
        "CL",
        "CD",
        "pdot_rad_s2",
        "qdot_rad_s2",
        "rdot_rad_s2",
        "alphadot_rad_s",
        "ax_fps2",
        "ay_fps2",
        "az_fps2",
    ] {
        v.push(s.to_string());
    }
    v
}

/// One row of [`true_channel_names`]: the state `x`, the surfaces `applied` and commands
/// `cmd`, the outputs `o`, the body angular accelerations and α̇ from the state derivative
/// `xdot`, and the accelerometer specific force at the CG in ft/s² (body axes, `az ≈ −g` in
/// level flight: `ax = nx·g`, `ay = ny·g`, `az = −nz·g` with the model's `g`), the channels
/// a replay through `mappings/aeroident-sim.toml` identifies from.
fn true_row(
    x: &F16State,
    xdot: &F16State,
    g_fps2: f64,
    applied: &F16Controls,
    cmd: &F16Controls,
    o: &F16Outputs,
) -> Vec<f64> {
    let mut v: Vec<f64> = x.iter().copied().collect();
    let c = &o.coefficients;
    v.extend_from_slice(&[
        applied.elevator_rad,
        applied.aileron_rad,
        applied.rudder_rad,
        applied.throttle,
        cmd.elevator_rad,
        cmd.aileron_rad,
        cmd.rudder_rad,
        applied.wind_body_fps[0],
        applied.wind_body_fps[1],
        applied.wind_body_fps[2],
        o.vt_air_fps,
        o.alpha_air_rad,
        o.beta_air_rad,
        o.nx_g,
        o.ny_g,
        o.nz_g,
        o.qbar_psf,
        o.mach,
        o.thrust_lbf,
        c.CX,
        c.CY,
        c.CZ,
        c.Cl,
        c.Cm,
        c.Cn,
        c.CL,
        c.CD,
        xdot[P],
        xdot[Q],
        xdot[R],
        xdot[ALPHA],
        o.nx_g * g_fps2,
        o.ny_g * g_fps2,
        -o.nz_g * g_fps2,
    ]);
    v
}

/// A simulation's record, of either aircraft: column names (first `t_s`, units in the names;
/// sensed channels are `meas_<channel>`) and column data of equal length.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SimTable {
    /// Column names.
    pub columns: Vec<String>,
    /// `data[c][k]`: column `c` at step `k`.
    pub data: Vec<Vec<f64>>,
}

impl SimTable {
    /// No rows yet, with room for `rows` of each of `columns`.
    pub fn with_capacity(columns: Vec<String>, rows: usize) -> Self {
        let data = vec![Vec::with_capacity(rows); columns.len()];
        Self { columns, data }
    }

    /// The column called `name`, if any.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.columns.iter().position(|c| c == name).map(|i| self.data[i].as_slice())
    }

    /// Appends the row at `t`: the time, the true channels `row`, then each sensor's
    /// measurement of the true channel it reads (`(index in row, sensor)`), in column order.
    fn push_row(&mut self, t: f64, row: &[f64], sensors: &mut [(usize, SensorModel)]) {
        self.data[0].push(t);
        for (c, v) in row.iter().enumerate() {
            self.data[c + 1].push(*v);
        }
        for (j, (idx, sensor)) in sensors.iter_mut().enumerate() {
            self.data[1 + row.len() + j].push(sensor.measure(t, row[*idx]));
        }
    }
}

/// A finished run of the F-16.
#[derive(Debug, Clone)]
pub struct SimRun {
    /// The record.
    pub table: SimTable,
    /// The trim the run started from.
    pub trim: aeroident_models::trim::F16Trim,
}

/// Reads and parses a scenario file.
///
/// # Errors
/// I/O errors and TOML errors (with line and column) naming the file.
pub fn load_scenario(path: &Path) -> Result<SimScenario> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading scenario `{}`", path.display()))?;
    parse_scenario(&text, path)
}

/// Parses scenario text; `path` names it in errors.
///
/// # Errors
/// TOML errors (with line and column) naming the file.
pub fn parse_scenario(text: &str, path: &Path) -> Result<SimScenario> {
    let file = path.display().to_string();
    crate::scenario_kind::check(text, &file, crate::scenario_kind::ScenarioKind::Sim)?;
    toml::from_str(text).with_context(|| format!("scenario `{}`", path.display()))
}

enum Plant {
    Ideal(F16),
    Actuated(F16WithActuators),
}

/// Runs a scenario. Relative paths inside it (recorded inputs) resolve against `base_dir`.
///
/// # Errors
/// Invalid run settings, unknown sensor channels, input/wind/sensor construction errors, trim
/// failure, or a model error during the run (e.g. the aircraft left the model's domain), each
/// with the time or field it happened at.
pub fn run(sc: &SimScenario, base_dir: &Path) -> Result<SimRun> {
    let r = &sc.run;
    let n_steps = step_count(r)?;
    let (f16, t0) = trimmed_airframe(sc)?;
    let inputs = build_inputs(sc, base_dir)?;
    let wind = build_wind(&sc.wind).context("[[wind]]")?;

    let mut columns = vec!["t_s".to_string()];
    let names = true_channel_names();
    columns.extend(names.iter().cloned());
    let mut sensors = build_sensors(sc, &names, &mut columns)?;

    let plant = match f16_config(sc)?.actuators {
        ActuatorChoice::Ideal => Plant::Ideal(f16),
        ActuatorChoice::F16 => {
            Plant::Actuated(F16WithActuators { airframe: f16, actuators: SurfaceActuators::f16() })
        }
    };
    let mut flight = Flight::new(plant, &t0, SimTable::with_capacity(columns, n_steps + 1));
    for k in 0..=n_steps {
        let t = k as f64 * r.dt_s;
        let cmd = commands(&t0.controls, &inputs, &wind, t);
        flight.record(t, &cmd, &mut sensors)?;
        if k == n_steps {
            break;
        }
        flight.advance(t, &cmd, r.dt_s)?;
    }
    Ok(SimRun { table: flight.table, trim: t0 })
}

/// The fewest steps a run takes: ten samples, the least a differentiator window and one
/// estimator update of a record can use.
const MIN_STEPS: usize = 10;

/// The number of RK4 steps of the run (`duration_s / dt_s`, rounded), after checking both are
/// finite and positive, that the run has [`MIN_STEPS`] and fits in memory ([`MAX_STEPS`]).
fn step_count(r: &scenario::RunConfig) -> Result<usize> {
    if !(r.dt_s.is_finite() && r.dt_s > 0.0) {
        bail!("[run] dt_s = {} must be finite and > 0", r.dt_s);
    }
    if !(r.duration_s.is_finite() && r.duration_s > 0.0) {
        bail!("[run] duration_s = {} must be finite and > 0", r.duration_s);
    }
    let n_steps = (r.duration_s / r.dt_s).round() as usize;
    if n_steps < MIN_STEPS {
        // A record of one or two rows holds no motion any estimator or figure can use.
        bail!(
            "[run] duration_s / dt_s = {} / {} gives {n_steps} step(s): a run needs at least {MIN_STEPS}; lengthen duration_s or lower dt_s",
            aeroident_physics::text::Short(r.duration_s),
            aeroident_physics::text::Short(r.dt_s)
        );
    }
    if n_steps > MAX_STEPS {
        bail!(
            "[run] duration_s / dt_s = {n_steps} steps is too many (max {MAX_STEPS}: the run is held in memory for the figures, 8 bytes per column per step); shorten duration_s or raise dt_s"
        );
    }
    Ok(n_steps)
}

/// The airframe of `[aircraft]`, trimmed wings-level at `[trim]`, and the trim: linearised
/// about the trim when `aerodynamics = "linear"`, with the thesis increments of
/// `[increments]` about the trim (from `onset_s`, else always) when given.
fn trimmed_airframe(sc: &SimScenario) -> Result<(F16, F16Trim)> {
    let config = f16_config(sc)?;
    let mut f16 = F16::new(config.xcg).context("[aircraft] xcg")?;
    let (vt_fps, alt_ft) = sc.trim.english()?;
    let cond = TrimCondition {
        alt_ft,
        vt_fps,
        gamma_rad: sc.trim.gamma_deg.to_radians(),
        maneuver: TrimManeuver::WingsLevel,
    };
    let t0 = trim(&f16, &cond).with_context(|| format!("[trim] at {alt_ft} ft, {vt_fps} ft/s"))?;
    if config.aerodynamics == AerodynamicsSpec::Linear {
        let ld = local_derivatives(&f16, &t0.state, &t0.controls, &AeroIncrements::zero())
            .context("[aircraft] aerodynamics = \"linear\": the derivatives at the trim")?;
        f16 = f16.with_linear_aero(linearised(&ld, &t0.state, &t0.controls));
    }
    if let Some(inc) = &sc.increments {
        let reference = IncrementReference {
            alpha_rad: t0.state[ALPHA],
            q_rad_s: t0.state[Q],
            elevator_rad: t0.controls.elevator_rad,
            aileron_rad: t0.controls.aileron_rad,
            rudder_rad: t0.controls.rudder_rad,
            ..Default::default()
        };
        let schedule = match inc.onset_s {
            Some(t0_s) if t0_s.is_finite() => IncrementSchedule::StepAt { t0_s },
            Some(v) => bail!("[increments] onset_s = {v} must be finite"),
            None => IncrementSchedule::Always,
        };
        f16 = f16.with_increments(
            AeroIncrements::thesis(
                reference,
                inc.dCm_alpha,
                inc.dCm_q,
                inc.dCL_alpha,
                inc.dCD_alpha,
            ),
            schedule,
        );
    }
    Ok((f16, t0))
}

/// The scenario's `[aircraft]`, which the F-16 needs.
///
/// # Errors
/// No `[aircraft]` section.
fn f16_config(sc: &SimScenario) -> Result<&scenario::AircraftConfig> {
    sc.aircraft.as_ref().ok_or_else(|| {
        crate::err!(
            "[aircraft] is missing: the F-16 needs its `xcg` (a model-file aircraft is given with `aeroident sim --aircraft MODEL.toml`)"
        )
    })
}

/// The `[[input]]` signals with their channels; recorded inputs resolve against `base_dir`.
/// An input that reaches the Nyquist frequency of the run's step is refused
/// ([`aeroident_signals::InputConfig::check_sampled_every`]).
fn build_inputs(sc: &SimScenario, base_dir: &Path) -> Result<Vec<(Channel, Input)>> {
    sc.input
        .iter()
        .enumerate()
        .map(|(k, ci)| {
            let what = || format!("[[input]] #{} ({:?})", k + 1, ci.channel);
            let input = ci.input.build_in(base_dir).with_context(what)?;
            if let Err(why) = ci.input.check_sampled_every(sc.run.dt_s) {
                bail!("{}: {why}", what());
            }
            Ok((ci.channel, input))
        })
        .collect::<Result<_>>()
}

/// The `[[sensor]]` models, each with the index of the true channel (of `names`) it senses;
/// appends each one's `meas_<channel>` column to `columns`.
fn build_sensors(
    sc: &SimScenario,
    names: &[String],
    columns: &mut Vec<String>,
) -> Result<Vec<(usize, SensorModel)>> {
    let mut sensors: Vec<(usize, SensorModel)> = Vec::with_capacity(sc.sensor.len());
    for (k, s) in sc.sensor.iter().enumerate() {
        let Some(idx) = names.iter().position(|n| *n == s.channel) else {
            bail!(
                "[[sensor]] #{}: unknown channel `{}`; known channels: {}",
                k + 1,
                s.channel,
                names.join(", ")
            );
        };
        sensors.push((
            idx,
            s.build(sc.run.seed)
                .with_context(|| format!("[[sensor]] #{} ({})", k + 1, s.channel))?,
        ));
        columns.push(format!("meas_{}", s.channel));
    }
    Ok(sensors)
}

/// The commands at `t`: the trim controls plus every input of each channel (superposed), and
/// the wind in body axes, both held over the step (zero-order hold).
fn commands(trim: &F16Controls, inputs: &[(Channel, Input)], wind: &Wind, t: f64) -> F16Controls {
    let mut cmd = *trim;
    for (ch, inp) in inputs {
        let v = inp.value(t);
        match ch {
            Channel::Throttle => cmd.throttle += v,
            Channel::Elevator => cmd.elevator_rad += v,
            Channel::Aileron => cmd.aileron_rad += v,
            Channel::Rudder => cmd.rudder_rad += v,
        }
    }
    let w = wind.wind_body_fps(t);
    cmd.wind_body_fps = [w[0], w[1], w[2]];
    cmd
}

/// The simulation loop's state: the plant and its state (the 13 airframe states when the
/// surfaces are ideal, 16 with the actuator states), gravity for the accelerometer channels,
/// and the columns recorded so far.
struct Flight {
    plant: Plant,
    xi: F16State,
    xa: SVector<f64, 16>,
    g_fps2: f64,
    table: SimTable,
}

impl Flight {
    /// At the trim, recording into `table`.
    fn new(plant: Plant, t0: &F16Trim, table: SimTable) -> Self {
        let g_fps2 = match &plant {
            Plant::Ideal(m) => m.data().mass.g_ft_per_s2,
            Plant::Actuated(m) => m.airframe.data().mass.g_ft_per_s2,
        };
        let xa: SVector<f64, 16> = F16WithActuators::state(&t0.state, &t0.controls);
        let xi: F16State = t0.state;
        Self { plant, xi, xa, g_fps2, table }
    }

    /// Records the row at `t` under the commands `cmd`: time, the true channels (with the
    /// surfaces as applied through the actuators) and each sensor's measurement.
    fn record(
        &mut self,
        t: f64,
        cmd: &F16Controls,
        sensors: &mut [(usize, SensorModel)],
    ) -> Result<()> {
        let (x13, applied, evaluated) = match &self.plant {
            Plant::Ideal(m) => (self.xi, *cmd, m.evaluate(&self.xi, cmd, &m.increments_at(t))),
            Plant::Actuated(m) => {
                let x13: F16State = self.xa.fixed_rows::<N_STATES>(0).into_owned();
                let applied = F16WithActuators::surface_controls(&self.xa, cmd);
                let af = &m.airframe;
                (x13, applied, af.evaluate(&x13, &applied, &af.increments_at(t)))
            }
        };
        let (xdot, outputs) =
            evaluated.with_context(|| format!("model outputs at t = {t:.4} s"))?;
        let row = true_row(&x13, &xdot, self.g_fps2, &applied, cmd, &outputs);
        self.table.push_row(t, &row, sensors);
        Ok(())
    }

    /// One RK4 step of `dt` s from `t` with the commands held.
    fn advance(&mut self, t: f64, cmd: &F16Controls, dt: f64) -> Result<()> {
        match &self.plant {
            Plant::Ideal(m) => {
                self.xi = rk4_step(m, t, &self.xi, cmd, dt)
                    .with_context(|| format!("RK4 step at t = {t:.4} s"))?
            }
            Plant::Actuated(m) => {
                self.xa = rk4_step(m, t, &self.xa, cmd, dt)
                    .with_context(|| format!("RK4 step at t = {t:.4} s"))?
            }
        }
        Ok(())
    }
}

/// Most RK4 steps of one simulation: the run is held in memory for the figures (8 bytes per
/// column per step, so some hundred MB at the limit); longer runs are refused before any
/// allocation.
pub const MAX_STEPS: usize = 1_000_000;

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_models::linearize::linearize_f16;

    fn scenario(extra: &str, actuators: &str, duration_s: f64) -> SimScenario {
        let text = format!(
            "kind = \"sim\"\n[aircraft]\nxcg = 0.30\nactuators = \"{actuators}\"\n[trim]\nalt_ft = 20000.0\nvt_fps = 675.0\n[run]\nduration_s = {duration_s}\ndt_s = 0.01\nseed = 1\n{extra}"
        );
        toml::from_str(&text).unwrap()
    }

    #[test]
    fn analytic_no_input_stays_at_trim() {
        let r = run(&scenario("", "f16", 10.0), Path::new(".")).unwrap();
        assert_eq!(r.table.columns.len(), r.table.data.len());
        assert_eq!(r.table.data[0].len(), 1001);
        let vt = r.table.column("vt_fps").unwrap();
        let a = r.table.column("alpha_rad").unwrap();
        assert!(vt.iter().all(|v| (v - 675.0).abs() < 1e-6));
        assert!(a.iter().all(|v| (v - r.trim.state[ALPHA]).abs() < 1e-9));
        // Level-flight force balance along the vertical: nz·cosα + nx·sinα = 1 g (θ = α, γ = 0).
        let (nz, nx) = (r.table.column("nz_g").unwrap()[0], r.table.column("nx_g").unwrap()[0]);
        let al = r.trim.state[ALPHA];
        assert!((nz * al.cos() + nx * al.sin() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn analytic_inputs_on_one_channel_superpose() {
        let two = "[[input]]\nchannel = \"elevator\"\nkind = \"step\"\namplitude_deg = 0.2\nstart_s = 1.0\n[[input]]\nchannel = \"elevator\"\nkind = \"step\"\namplitude_deg = 0.3\nstart_s = 1.0\n";
        let one = "[[input]]\nchannel = \"elevator\"\nkind = \"step\"\namplitude_deg = 0.5\nstart_s = 1.0\n";
        let a = run(&scenario(two, "f16", 3.0), Path::new(".")).unwrap();
        let b = run(&scenario(one, "f16", 3.0), Path::new(".")).unwrap();
        let (qa, qb) = (a.table.column("q_rad_s").unwrap(), b.table.column("q_rad_s").unwrap());
        assert!(qa.iter().zip(qb).all(|(x, y)| (x - y).abs() < 1e-12));
        assert!(qa.iter().any(|x| x.abs() > 1e-3), "the step must move the aircraft");
    }

    /// Independent check of the sim's input path: a small elevator doublet flown through the
    /// nonlinear model (ideal actuators) agrees with the same doublet through the linearized
    /// model δẋ = A δx + B δu (A, B by central differences, integrated with RK4 separately).
    #[test]
    fn independent_small_doublet_matches_linear_model() {
        let doublet = "[[input]]\nchannel = \"elevator\"\nkind = \"doublet\"\namplitude_deg = 0.1\nstart_s = 0.5\npulse_width_s = 0.5\n";
        let r = run(&scenario(doublet, "ideal", 6.0), Path::new(".")).unwrap();
        let f16 = F16::new(0.30).unwrap();
        let lin = linearize_f16(&f16, &r.trim.state, &r.trim.controls).unwrap();
        let de = r.table.column("elevator_cmd_rad").unwrap();
        let dt = 0.01;
        let mut dx = SVector::<f64, 13>::zeros();
        let mut worst = 0.0f64;
        let mut peak = 0.0f64;
        let alpha = r.table.column("alpha_rad").unwrap();
        let q = r.table.column("q_rad_s").unwrap();
        for k in 0..alpha.len() {
            let da_nl = alpha[k] - r.trim.state[ALPHA];
            worst = worst.max((da_nl - dx[ALPHA]).abs()).max((q[k] - dx[Q]).abs() * 0.2);
            peak = peak.max(da_nl.abs());
            if k + 1 == alpha.len() {
                break;
            }
            let mut du = SVector::<f64, 4>::zeros();
            du[1] = de[k] - r.trim.controls.elevator_rad;
            let f = |x: &SVector<f64, 13>| lin.a * x + lin.b * du;
            let k1 = f(&dx);
            let k2 = f(&(dx + k1 * (dt / 2.0)));
            let k3 = f(&(dx + k2 * (dt / 2.0)));
            let k4 = f(&(dx + k3 * dt));
            dx += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0);
        }
        assert!(peak > 1e-4, "the doublet must excite alpha (peak {peak})");
        assert!(worst < 0.02 * peak, "nonlinear vs linear: worst {worst:e}, peak {peak:e}");
    }

    #[test]
    fn unknown_sensor_channel_is_named() {
        let s =
            scenario("[[sensor]]\nchannel = \"alpha_deg\"\nsample_rate_hz = 50.0\n", "f16", 1.0);
        let e = format!("{:#}", run(&s, Path::new(".")).unwrap_err());
        assert!(e.contains("alpha_deg") && e.contains("alpha_rad"), "{e}");
    }

    /// An absurd step count (5e7) is refused before anything is allocated, with an error
    /// naming the fields and the limit.
    #[test]
    fn errors_too_many_steps_are_refused_clearly() {
        let s = scenario("", "f16", 5e5);
        let e = format!("{:#}", run(&s, Path::new(".")).unwrap_err());
        assert!(
            e.contains("duration_s / dt_s") && e.contains("50000000") && e.contains("1000000"),
            "{e}"
        );
    }
}
