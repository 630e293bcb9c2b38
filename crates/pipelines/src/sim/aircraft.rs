//! Open-loop simulation of any [`FlyableAircraft`] (the model-file aircraft,
//! [`crate::airframe::ModelFileAircraft`]: a model file's structure with identified values and
//! a mapping's constants, is the one the faces load): trim wings-level → fly the scenario's
//! inputs → sense → one [`AircraftSimRun`], and the mapping that replays its record
//! ([`replay_mapping`]).
//!
//! Run: `aeroident sim SCENARIO --aircraft MODEL.toml --summary S --map M --out DIR`. The
//! scenario is the F-16's format ([`crate::sim::scenario`]) without `[aircraft]` (the aircraft
//! comes from the files), with `[trim]` in `vt_mps`/`alt_m` or `vt_fps`/`alt_ft`.
//!
//! # What is simulated
//! * The aircraft's own equations (the model-file aircraft's: [`crate::airframe`] module doc),
//!   integrated in its own states and recorded in SI, trimmed wings-level at
//!   `[trim]` (level only: `gamma_deg` must be 0), in still air: `[[wind]]` and
//!   `[increments]` are refused (the airframe has no wind input; change a derivative in its
//!   summary instead).
//! * Commands = trim + Σ inputs of the channel; each surface follows its command through the
//!   mapping's actuator of that surface (`actuator = { … }` on `de`, `da`, `dr`:
//!   [`aeroident_io::mapping::Actuator::step`], the command held from each step over it, as
//!   the replay's record stage models a commanded surface; between steps the surface ramps
//!   to the next step's value), or is the command without one; the record then also has
//!   `elevator_cmd_rad aileron_cmd_rad rudder_cmd_rad`;
//!   `throttle` inputs act on the engine command, in its own unit (thrust N, throttle 0–1 or
//!   propeller speed rad/s, [`crate::airframe::Propulsion`]).
//! * RK4 with step `dt_s`; between two steps the controls move linearly from one step's
//!   commands to the next's ([`rk4_step_varying`]), so a step input is a one-step ramp.
//!   That is what an estimator which interpolates the recorded surfaces assumes (output
//!   error, Jategaonkar 2015 ch. 4 `ruku4.m`); held commands instead (the F-16 simulation's
//!   zero-order hold, which its actuators smooth) put the steps of a doublet half a sample
//!   early in the replay, an O(dt) error: flown at 50 Hz with ideal surfaces, output error
//!   returned Cl_p 9 % and Cm_q 7 % off, at 200 Hz 2.5 % and 1.7 %.
//! * Sensors sample the true channels as in the F-16 simulation.
//!
//! # Output
//! Columns (SI, units in the names): `t_s`, the states ([`crate::airframe::STATE_NAMES`]),
//! the engine command, `elevator_rad aileron_rad rudder_rad thrust_n qbar_pa rho_kgpm3 mach`,
//! `pdot_rad_s2 qdot_rad_s2 rdot_rad_s2 alphadot_rad_s` (from the state derivative), the
//! accelerometer's specific force `ax_mps2 ay_mps2 az_mps2` (body axes, `az ≈ −g` level), then
//! each sensor's `meas_<channel>`.

use super::scenario::{Channel, SimScenario};
use super::{SimTable, build_inputs, build_sensors, step_count};
use crate::airframe::{AirframeOutputs, AirframeState, FlyableAircraft, STATE_NAMES, Trim};
use crate::bail;
use crate::error::{Context, Result};
use aeroident_models::aircraft::ControlVector;
use aeroident_models::integrate::rk4_step_varying;
use aeroident_models::rigid_body as rb;
use aeroident_signals::{Input, InputSignal};
use std::path::Path;

/// A finished run of a model-file aircraft.
#[derive(Debug, Clone)]
pub struct AircraftSimRun {
    /// The aircraft's name (its model file's description).
    pub aircraft: String,
    /// The record (module doc).
    pub table: SimTable,
    /// The trim the run started from (SI states, controls as [`ControlVector`]).
    pub trim: Trim,
    /// The engine command's column name, with its unit.
    pub engine_column: &'static str,
}

/// The true channels of every step after `t_s`, in column order (module doc).
pub fn true_channel_names<const N: usize>(a: &impl FlyableAircraft<N>) -> Vec<String> {
    let mut v: Vec<String> = STATE_NAMES.iter().map(|s| s.to_string()).collect();
    v.push(a.engine_column().to_string());
    v.extend(
        [
            "elevator_rad",
            "aileron_rad",
            "rudder_rad",
            "thrust_n",
            "qbar_pa",
            "rho_kgpm3",
            "mach",
            "pdot_rad_s2",
            "qdot_rad_s2",
            "rdot_rad_s2",
            "alphadot_rad_s",
            "ax_mps2",
            "ay_mps2",
            "az_mps2",
        ]
        .map(String::from),
    );
    if actuated(a) {
        v.extend(["elevator_cmd_rad", "aileron_cmd_rad", "rudder_cmd_rad"].map(String::from));
    }
    v
}

/// Whether any surface of `a` has an actuator (the record then has the commands too).
fn actuated<const N: usize>(a: &impl FlyableAircraft<N>) -> bool {
    a.actuators().iter().any(Option::is_some)
}

/// The controls one step `dt` after surfaces `u` under commands `cmd` (held over the step,
/// the actuator's convention: [`aeroident_io::mapping::Actuator::step`]), the engine and
/// the surfaces without an actuator at the next step's commands `cmd1`.
fn next_controls<const N: usize>(
    a: &impl FlyableAircraft<N>,
    u: &ControlVector,
    (cmd, cmd1): (&ControlVector, &ControlVector),
    dt: f64,
) -> ControlVector {
    let mut next = *cmd1;
    for (i, act) in a.actuators().iter().enumerate() {
        if let Some(act) = act {
            next[1 + i] = act.step(u[1 + i], cmd[1 + i], dt);
        }
    }
    next
}

/// One row of [`true_channel_names`] at state `x` under controls `u` (the surfaces), with the
/// surface commands `cmd` when the aircraft has actuators.
fn true_row(
    x: &AirframeState,
    u: &ControlVector,
    o: &AirframeOutputs,
    cmd: Option<&ControlVector>,
) -> Vec<f64> {
    let mut v: Vec<f64> = x.iter().copied().collect();
    v.extend_from_slice(u.as_slice());
    v.extend_from_slice(&[
        o.thrust_n,
        o.qbar_pa,
        o.rho_kgpm3,
        o.mach,
        o.xdot[rb::P],
        o.xdot[rb::Q],
        o.xdot[rb::R],
        o.xdot[rb::ALPHA],
        o.accel_mps2[0],
        o.accel_mps2[1],
        o.accel_mps2[2],
    ]);
    if let Some(c) = cmd {
        v.extend_from_slice(&c.as_slice()[1..4]);
    }
    v
}

/// Flies `sc` with `aircraft` (module doc). Relative paths inside the scenario (recorded
/// inputs) resolve against `base_dir`.
///
/// # Errors
/// An `[aircraft]` section, `[[wind]]`, `[increments]` or a non-zero `gamma_deg` (this
/// aircraft cannot take them), invalid run settings, unknown sensor channels, a trim that does
/// not converge, or a model error during the run (the time it happened at).
pub fn run<const N: usize, A: FlyableAircraft<N>>(
    aircraft: &A,
    sc: &SimScenario,
    base_dir: &Path,
) -> Result<AircraftSimRun> {
    check_scenario(sc)?;
    let n_steps = step_count(&sc.run)?;
    let (vt_mps, alt_m) = sc.trim.si()?;
    let t0 = aircraft
        .trim_level(vt_mps, alt_m)
        .with_context(|| format!("[trim] at {vt_mps} m/s, {alt_m} m"))?;
    let inputs = build_inputs(sc, base_dir)?;
    let mut columns = vec!["t_s".to_string()];
    let names = true_channel_names(aircraft);
    columns.extend(names.iter().cloned());
    let mut sensors = build_sensors(sc, &names, &mut columns)?;
    let mut table = SimTable::with_capacity(columns, n_steps + 1);
    let (mut x, dt) = (t0.state, sc.run.dt_s);
    // Each step's commands are evaluated once, at the step's own time k·dt: the ramp towards
    // the next step must end on the value that step records (t + dt may round to the other
    // side of an input's edge).
    let mut cmd = commands(&t0.controls, &inputs, 0.0);
    let mut u = cmd;
    let with_cmd = actuated(aircraft);
    for k in 0..=n_steps {
        let t = k as f64 * dt;
        let o = aircraft
            .outputs(t, &x, &u)
            .with_context(|| format!("model outputs at t = {t:.4} s"))?;
        let row = true_row(&aircraft.rigid_body_si(&x), &u, &o, with_cmd.then_some(&cmd));
        table.push_row(t, &row, &mut sensors);
        if k < n_steps {
            let cmd1 = commands(&t0.controls, &inputs, (k + 1) as f64 * dt);
            let u1 = next_controls(aircraft, &u, (&cmd, &cmd1), dt);
            let between = |s: f64| aircraft.input(&(u + (u1 - u) * ((s - t) / dt)));
            x = rk4_step_varying(aircraft, t, &x, between, dt)
                .with_context(|| format!("RK4 step at t = {t:.4} s"))?;
            (u, cmd) = (u1, cmd1);
        }
    }
    let mut trim = crate::airframe::handle::plain_trim(&t0);
    trim.state = aircraft.rigid_body_si(&t0.state).iter().copied().collect();
    let engine_column = aircraft.engine_column();
    Ok(AircraftSimRun { aircraft: aircraft.name(), table, trim, engine_column })
}

/// Refuses what a model-file aircraft cannot fly, naming the section.
fn check_scenario(sc: &SimScenario) -> Result<()> {
    if sc.aircraft.is_some() {
        bail!(
            "[aircraft] sets the F-16 (xcg, actuators, tables); a model-file aircraft takes its constants from --map: remove the section"
        );
    }
    if !sc.wind.is_empty() {
        bail!(
            "[[wind]]: a model-file aircraft flies in still air (its equations have no wind input)"
        );
    }
    if sc.increments.is_some() {
        bail!(
            "[increments]: a model-file aircraft flies its own derivatives: change them in its summary or model file"
        );
    }
    if sc.trim.gamma_deg != 0.0 {
        bail!(
            "[trim] gamma_deg = {}: a model-file aircraft is trimmed wings-level only",
            sc.trim.gamma_deg
        );
    }
    Ok(())
}

/// The controls at `t`: the trim plus every input of each channel (superposed), held over the
/// step.
fn commands(trim: &ControlVector, inputs: &[(Channel, Input)], t: f64) -> ControlVector {
    let mut u = *trim;
    for (ch, inp) in inputs {
        let k = match ch {
            Channel::Throttle => 0,
            Channel::Elevator => 1,
            Channel::Aileron => 2,
            Channel::Rudder => 3,
        };
        u[k] += inp.value(t);
    }
    u
}

/// A mapping (TOML text) that replays `run`'s `timeseries.csv` with the aircraft's constants:
/// each channel's sensed `meas_` column where the scenario has a sensor on it, else the true
/// column; thrust as a channel (so drag is drag whatever the engine law), the thrust line's arm
/// and incidence and `v0` as the aircraft has them.
///
/// A record with sensors is mapped as a flight record would be: the state derivatives
/// (`pdot`, `qdot`, `rdot`, `alphadot`) only where a sensor measures them. No instrument
/// system measures them exactly; left out, the estimators differentiate the sensed rates as on
/// a flight record, and output error does not read an exact angular acceleration as an output
/// (it would tell the moments without noise: over 16 noisy flights of the F-16's local
/// derivatives the fits then scattered 0.00–0.21 × their Cramér–Rao bound). A noise-free
/// record keeps them, for exact round trips.
pub fn replay_mapping<const N: usize>(
    aircraft: &impl FlyableAircraft<N>,
    run: &AircraftSimRun,
) -> String {
    const DERIVATIVES: [&str; 4] = ["pdot_rad_s2", "qdot_rad_s2", "rdot_rad_s2", "alphadot_rad_s"];
    let sensed = |col: &str| run.table.column(&format!("meas_{col}")).is_some();
    let any_sensor = run.table.columns.iter().any(|c| c.starts_with("meas_"));
    mapping_with(aircraft, run, |col| !any_sensor || !DERIVATIVES.contains(&col) || sensed(col))
}

/// [`replay_mapping`] with the channels whose true column `keep` refuses left out.
fn mapping_with<const N: usize>(
    aircraft: &impl FlyableAircraft<N>,
    run: &AircraftSimRun,
    keep: impl Fn(&str) -> bool,
) -> String {
    let pick = |col: &str| -> String {
        let m = format!("meas_{col}");
        if run.table.column(&m).is_some() { m } else { col.to_string() }
    };
    let mut s = format!(
        "# Written by `aeroident sim` for {}: replays its timeseries.csv.\ndescription = \"aeroident sim output ({})\"\n\n[time]\ncolumn = \"t_s\"\nunit = \"s\"\n\n[channels]\n",
        aircraft.name(),
        aircraft.name().replace('"', "'")
    );
    for (key, col, unit) in REPLAY_CHANNELS.into_iter().filter(|(_, col, _)| keep(col)) {
        s.push_str(&format!("{key} = {{ column = \"{}\", unit = \"{unit}\" }}\n", pick(col)));
    }
    let c = aircraft.constants();
    let constants = [
        ("mass", Some(c.mass_kg), "kg"),
        ("Ixx", c.Ixx_kgm2, "kg*m2"),
        ("Iyy", c.Iyy_kgm2, "kg*m2"),
        ("Izz", c.Izz_kgm2, "kg*m2"),
        ("Ixz", c.Ixz_kgm2, "kg*m2"),
        ("S", Some(c.S_m2), "m2"),
        ("cbar", c.cbar_m, "m"),
        ("b", c.b_m, "m"),
        ("thrust_arm", Some(c.thrust_arm_m), "m"),
        ("thrust_incidence", Some(c.thrust_incidence_rad), "rad"),
        ("v0", c.v0_mps, "m/s"),
    ];
    for (key, v, unit) in constants {
        if let Some(v) = v {
            s.push_str(&format!("{key} = {{ value = {v:?}, unit = \"{unit}\" }}\n"));
        }
    }
    s
}

/// `(mapping key, column, unit)` of every channel [`replay_mapping`] maps.
const REPLAY_CHANNELS: [(&str, &str, &str); 22] = [
    ("vt", "vt_mps", "m/s"),
    ("alpha", "alpha_rad", "rad"),
    ("beta", "beta_rad", "rad"),
    ("phi", "phi_rad", "rad"),
    ("theta", "theta_rad", "rad"),
    ("psi", "psi_rad", "rad"),
    ("p", "p_rad_s", "rad/s"),
    ("q", "q_rad_s", "rad/s"),
    ("r", "r_rad_s", "rad/s"),
    ("pdot", "pdot_rad_s2", "rad/s2"),
    ("qdot", "qdot_rad_s2", "rad/s2"),
    ("rdot", "rdot_rad_s2", "rad/s2"),
    ("alphadot", "alphadot_rad_s", "rad/s"),
    ("ax", "ax_mps2", "m/s2"),
    ("ay", "ay_mps2", "m/s2"),
    ("az", "az_mps2", "m/s2"),
    ("de", "elevator_rad", "rad"),
    ("da", "aileron_rad", "rad"),
    ("dr", "rudder_rad", "rad"),
    ("thrust", "thrust_n", "N"),
    ("qbar", "qbar_pa", "Pa"),
    ("rho", "rho_kgpm3", "kg/m3"),
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airframe::ModelFileAircraft;
    use crate::airframe::tests::{ALT_FT, VT_FPS, as_model_file, f16_trim};
    use aeroident_physics::units::M_PER_FT;

    const ELEVATOR: &str = "[[input]]\nchannel = \"elevator\"\nkind = \"doublet\"\namplitude_deg = 0.1\nstart_s = 0.5\npulse_width_s = 0.5\n";
    const AILERON: &str = "[[input]]\nchannel = \"aileron\"\nkind = \"doublet\"\namplitude_deg = 0.2\nstart_s = 0.5\npulse_width_s = 0.5\n";

    fn scenario(aircraft: &str, trim_extra: &str, extra: &str) -> SimScenario {
        let text = format!(
            "kind = \"sim\"\n{aircraft}[trim]\nalt_ft = {ALT_FT}\nvt_fps = {VT_FPS}\n{trim_extra}[run]\nduration_s = 5.0\ndt_s = 0.01\nseed = 3\n{extra}"
        );
        toml::from_str(&text).unwrap()
    }

    fn aircraft() -> ModelFileAircraft {
        let (f, t) = f16_trim();
        as_model_file(&f, &t)
    }

    /// An elevator actuator (τ 0.05 s, no limit reached) in the airframe: the record has the
    /// command beside the surface, and the surface follows a held command step as the
    /// continuous first-order lag `δ = δ0 + A (1 − e^(−t/τ))` at every sample (the discrete
    /// step is exact for a held command); the aircraft responds to the lagged surface (its
    /// pitch rate 0.05 s after the step is below the ideal surface's).
    #[test]
    fn analytic_a_surface_follows_its_command_through_the_actuator() {
        use aeroident_io::mapping::Actuator;
        let ideal = aircraft();
        let mut airframe = *ideal.airframe();
        let lag =
            Actuator { tau_s: 0.05, rate_limit_rad_s: 10.0, position_limits_rad: (-0.5, 0.5) };
        airframe.actuators[0] = Some(lag);
        let lagged = ModelFileAircraft::new(
            "f16-local",
            ideal.structure(),
            ideal.theta().to_vec(),
            airframe,
        )
        .unwrap()
        .with_atmosphere(crate::airframe::Atmosphere::Textbook(
            f16_trim().0.data().atmosphere.clone(),
        ));
        let sc = scenario("", "", ELEVATOR);
        let (r, i) =
            (run(&lagged, &sc, Path::new(".")).unwrap(), run(&ideal, &sc, Path::new(".")).unwrap());
        let col = |run: &AircraftSimRun, n: &str| run.table.column(n).unwrap().to_vec();
        let (cmd, de) = (col(&r, "elevator_cmd_rad"), col(&r, "elevator_rad"));
        let k0 = cmd.iter().position(|c| *c != cmd[0]).unwrap();
        let step = cmd[k0] - cmd[0];
        for (i, got) in de[k0..k0 + 40].iter().enumerate() {
            let want = cmd[0] + step * (1.0 - (-(i as f64) * 0.01 / 0.05).exp());
            assert!((got - want).abs() < 1e-12 * step.abs(), "sample {}: {got} vs {want}", k0 + i);
        }
        assert!(
            i.table.column("elevator_cmd_rad").is_none(),
            "an ideal aircraft records no command"
        );
        let (q_lag, q_ideal) = (col(&r, "q_rad_s")[k0 + 5], col(&i, "q_rad_s")[k0 + 5]);
        assert!(q_lag.abs() < q_ideal.abs(), "{q_lag} vs {q_ideal}");
    }

    /// Level trim with no input: the record holds the trim, the accelerometer reads gravity
    /// (`ax = g sin θ`, `az = −g cos θ` at φ = 0) and `q̄ = ½ρV²`.
    #[test]
    fn analytic_no_input_holds_the_trim_and_reads_gravity() {
        let r = run(&aircraft(), &scenario("", "", ""), Path::new(".")).unwrap();
        assert_eq!(r.table.columns.len(), r.table.data.len());
        assert_eq!(r.table.data[0].len(), 501);
        let (vt, alpha) = (r.table.column("vt_mps").unwrap(), r.table.column("alpha_rad").unwrap());
        assert!(vt.iter().all(|v| (v / (VT_FPS * M_PER_FT) - 1.0).abs() < 1e-6), "{vt:?}");
        assert!(alpha.iter().all(|a| (a - r.trim.state[rb::ALPHA]).abs() < 1e-6));
        let g = 9.80665;
        let theta = r.table.column("theta_rad").unwrap()[0];
        let (ax, ay, az) = (
            r.table.column("ax_mps2").unwrap(),
            r.table.column("ay_mps2").unwrap(),
            r.table.column("az_mps2").unwrap(),
        );
        assert!(
            (ax[0] - g * theta.sin()).abs() < 1e-6 && ay[0].abs() < 1e-9,
            "{} {}",
            ax[0],
            ay[0]
        );
        assert!((az[0] + g * theta.cos()).abs() < 1e-6, "{}", az[0]);
        let (qbar, rho) =
            (r.table.column("qbar_pa").unwrap()[0], r.table.column("rho_kgpm3").unwrap()[0]);
        assert!((qbar - 0.5 * rho * vt[0] * vt[0]).abs() < 1e-9 * qbar);
        assert_eq!(
            r.table.column("thrust_cmd_n").unwrap()[0],
            r.table.column("thrust_n").unwrap()[0]
        );
    }

    /// The largest difference between the responses `(v_k − v_0)` of column `theirs` of `f16`
    /// (times `scale`) and `mine` of `ours`, relative to the F-16's peak response.
    fn relative_difference(
        f16: &crate::sim::SimRun,
        ours: &AircraftSimRun,
        (theirs, mine, scale): (&str, &str, f64),
    ) -> f64 {
        let (a, b) = (f16.table.column(theirs).unwrap(), ours.table.column(mine).unwrap());
        let delta = |v: &[f64], k: usize, s: f64| (v[k] - v[0]) * s;
        let peak = (0..a.len()).map(|k| delta(a, k, scale).abs()).fold(0.0, f64::max);
        let worst =
            (0..a.len()).map(|k| (delta(a, k, scale) - delta(b, k, 1.0)).abs()).fold(0.0, f64::max);
        eprintln!("{mine}: peak {peak:.3e}, worst difference {:.2e} of it", worst / peak);
        assert!(peak > 0.0, "{mine} does not move");
        worst / peak
    }

    /// Independent check of the whole path (scenario, unit conversion, trim, inputs,
    /// recording): the F-16's local derivatives flown as a model-file aircraft answer a small
    /// elevator doublet, and an aileron doublet, as the F-16 simulation does with its tables'
    /// first-order expansion at the same trim (`aerodynamics = "linear"`, ideal actuators),
    /// its own equations and units: every response within 1 % of its peak. The airspeed is left out: the F-16's thrust at a held throttle follows Mach, the
    /// commanded thrust here does not, which moves V's 2-cm/s response by 3 %. One surface a
    /// run: with both, the F-16 engine's angular momentum (absent here) turns the pitch rate
    /// into 1.5 % of the aileron's sideslip.
    #[test]
    fn independent_doublets_fly_as_the_f16_with_its_linear_aerodynamics() {
        let f16_section =
            "[aircraft]\nxcg = 0.30\nactuators = \"ideal\"\naerodynamics = \"linear\"\n";
        let longitudinal = [
            ("alpha_rad", "alpha_rad", 1.0),
            ("q_rad_s", "q_rad_s", 1.0),
            ("theta_rad", "theta_rad", 1.0),
            ("az_fps2", "az_mps2", M_PER_FT),
        ];
        let lateral = [
            ("beta_rad", "beta_rad", 1.0),
            ("p_rad_s", "p_rad_s", 1.0),
            ("r_rad_s", "r_rad_s", 1.0),
            ("phi_rad", "phi_rad", 1.0),
            ("ay_fps2", "ay_mps2", M_PER_FT),
        ];
        for (input, channels) in [(ELEVATOR, &longitudinal[..]), (AILERON, &lateral[..])] {
            // The F-16 holds each command over a step, this aircraft ramps between them: half
            // a step apart, so the step is short enough for that to stay below 1 % (≤ 0.6 %).
            let fine = |mut sc: SimScenario| {
                sc.run.dt_s = 0.002;
                sc
            };
            let f16 =
                crate::sim::run(&fine(scenario(f16_section, "", input)), Path::new(".")).unwrap();
            let ours = run(&aircraft(), &fine(scenario("", "", input)), Path::new(".")).unwrap();
            for pair in channels {
                let d = relative_difference(&f16, &ours, *pair);
                assert!(d < 0.01, "{}: {d}", pair.1);
            }
        }
    }

    #[test]
    fn sensors_add_their_columns_and_the_mapping_replays_them() {
        let sensor =
            "[[sensor]]\nchannel = \"q_rad_s\"\nwhite_sigma = 0.001\nsample_rate_hz = 100.0\n";
        let a = aircraft();
        let r = run(&a, &scenario("", "", sensor), Path::new(".")).unwrap();
        let (q, m) = (r.table.column("q_rad_s").unwrap(), r.table.column("meas_q_rad_s").unwrap());
        let sd =
            (q.iter().zip(m).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / q.len() as f64).sqrt();
        assert!((sd / 0.001 - 1.0).abs() < 0.2, "noise σ {sd}");
        let text = replay_mapping(&a, &r);
        assert!(
            text.contains("q = { column = \"meas_q_rad_s\"")
                && text.contains("p = { column = \"p_rad_s\""),
            "{text}"
        );
        let mapping = aeroident_io::mapping::Mapping::from_toml_str(&text, "written.toml").unwrap();
        let back = crate::airframe::airframe_from_mapping(&mapping).unwrap();
        assert_eq!(back.mass, a.airframe().mass);
        assert_eq!(back.geometry, a.airframe().geometry);
    }

    #[test]
    fn what_a_model_file_aircraft_cannot_fly_is_refused_by_name() {
        let a = aircraft();
        let cases = [
            (scenario("[aircraft]\nxcg = 0.3\n", "", ""), "[aircraft]"),
            (
                scenario(
                    "",
                    "",
                    "[[wind]]\nkind = \"one_minus_cosine\"\naxis = \"z\"\namplitude_fps = 1.0\nrise_time_s = 1.0\n",
                ),
                "[[wind]]",
            ),
            (scenario("", "", "[increments]\ndCm_alpha = -0.1\n"), "[increments]"),
            (scenario("", "gamma_deg = 3.0\n", ""), "gamma_deg"),
            (scenario("", "vt_mps = 200.0\n", ""), "not both"),
        ];
        for (sc, needle) in cases {
            let e = format!("{:#}", run(&a, &sc, Path::new(".")).unwrap_err());
            assert!(e.contains(needle), "{needle}: {e}");
        }
    }

    /// The written mapping maps the exact state derivatives of a noise-free record (an exact
    /// round trip), and of a sensed one only those a sensor measures; the sensed channels read
    /// their `meas_` column.
    #[test]
    fn a_sensed_record_s_mapping_has_no_exact_state_derivative() {
        let a = aircraft();
        let mapped = |extra: &str| {
            let r = run(&a, &scenario("", "", extra), Path::new(".")).unwrap();
            let m = aeroident_io::Mapping::from_toml_str(&replay_mapping(&a, &r), "m").unwrap();
            let column = |c: aeroident_io::Channel| m.channels.get(&c).map(|x| format!("{x:?}"));
            use aeroident_io::Channel as C;
            [C::Pdot, C::Qdot, C::Rdot, C::Alphadot, C::Q].map(column)
        };
        assert!(mapped("").iter().all(|c| c.as_ref().is_some_and(|c| !c.contains("meas_"))));
        let sensor = |ch: &str| {
            format!("[[sensor]]\nchannel = \"{ch}\"\nwhite_sigma = 0.01\nsample_rate_hz = 100.0\n")
        };
        let [p, q, r, alpha, rate] = mapped(&sensor("q_rad_s"));
        assert_eq!((p, q, r, alpha), (None, None, None, None));
        assert!(rate.is_some_and(|c| c.contains("meas_q_rad_s")));
        let [_, q, ..] = mapped(&format!("{}{}", sensor("q_rad_s"), sensor("qdot_rad_s2")));
        assert!(q.is_some_and(|c| c.contains("meas_qdot_rad_s2")));
    }
}
