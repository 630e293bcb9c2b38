//! A designed manoeuvre ([`super::design::Design`]) in the forms the autopilots fly
//! (docs/export.md, "`aeroident design`"):
//!
//! - ArduPlane: a Lua script ([`ardupilot_lua`]) that plays the injection table as offsets on
//!   the surface outputs about the command the pilot or autopilot holds. ArduPilot's scripting
//!   API (`libraries/AP_Scripting/docs/docs.lua`, ArduPilot/ardupilot): the vehicle's command
//!   per servo function from `SRV_Channels:get_output_scaled` (±4500 = full throw for the
//!   angle outputs aileron 4, elevator 19, rudder 21: ardupilot.org/plane/docs/servo-functions),
//!   the PWM of each output as `SRV_Channel::pwm_from_angle` computes it
//!   (`libraries/SRV_Channel/SRV_Channel.cpp`), written with
//!   `SRV_Channels:set_output_pwm_chan_timeout`, an override that lapses by itself
//!   (`SRV_Channels::set_output_pwm_chan_timeout`, `libraries/SRV_Channel/SRV_Channels.cpp`).
//! - PX4: a table of normalised torque-setpoint offsets ([`px4_torque_table`]) for an offboard
//!   node in PX4's thrust-and-torque offboard mode (PX4 ≥ 1.14 has no table player and no
//!   MAVLink actuator-control setpoint; its offboard interface takes `VehicleTorqueSetpoint`
//!   over ROS 2, and the control allocator maps it to the surfaces).
//!
//! Signs: aeroident's deflections are δe > 0 trailing edge down, δa > 0 a negative rolling
//! moment, δr > 0 trailing edge left (nose left). ArduPlane's scaled surface outputs and PX4's
//! torque setpoints are positive for a positive body moment (roll right, pitch up, yaw right;
//! the convention ArduPilot's SITL plane flies, `libraries/SITL/SIM_Plane.cpp`, see
//! [`super::ardupilot`]), so every surface's command fraction is `−δ / δmax` with `δmax` the
//! surface's full throw.

use super::design::{Design, Surface, centidegrees};
use std::fmt::Write as _;

/// ArduPlane's scaled output at full throw of an angle output (`SRV_Channel::set_angle(4500)`
/// for aileron, elevator and rudder).
pub const SCALED_FULL_THROW: f64 = 4500.0;

/// Largest throw accepted, degrees: beyond it a "surface" is not a flap-type control.
pub const MAX_THROW_DEG: f64 = 90.0;

/// Highest table rate the ArduPlane script is written for, Hz: a row of at least a
/// millisecond. ArduPilot's scripting scheduler counts in whole milliseconds: a script's
/// returned delay becomes `next_run_ms = AP_HAL::millis64() + (uint64_t)luaL_checknumber(L,
/// -1)`, waited with `hal.scheduler->delay(next_run_ms - now_ms)`, and the script reads the
/// time as `millis()` (ArduPilot/ardupilot `libraries/AP_Scripting/lua_scripts.cpp`, commit
/// 83eeca258621fe6efe14d0e5a1da432d8261be2f; later versions count the delay from the call's
/// start, in milliseconds still), so a row shorter than 1 ms can be neither timed nor asked
/// for. That is the only hard figure: the scheduler has no minimum delay, and ArduPilot
/// documents no rate a script is called at (scripts "are not guaranteed to be run on a
/// reliable schedule", ardupilot.org/dev/docs/common-lua-scripts.html); below this limit the
/// script measures the rate it gets and warns (its header).
pub const MAX_SCRIPT_RATE_HZ: f64 = 1000.0;

/// How the pilot starts and stops the ArduPlane script.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Start {
    /// The `SCR_USER1` parameter: 1 starts, 0 stops.
    ScrUser1,
    /// An RC input channel (1–16): above 1800 µs starts, below stops.
    RcChannel(u8),
}

/// What the autopilot forms need beyond the design.
#[derive(Debug, Clone, PartialEq)]
pub struct AutopilotOptions {
    /// Full throw of each surface, rad (the deflection at a full servo command, ±4500 scaled
    /// on ArduPlane, ±1 on PX4): every designed surface needs one.
    pub throws: Vec<(Surface, f64)>,
    /// The ArduPlane script's start switch.
    pub start: Start,
}

/// The ArduPilot servo function of a surface (ardupilot.org/plane/docs/servo-functions).
pub fn servo_function(s: Surface) -> u8 {
    match s {
        Surface::Da => 4,
        Surface::De => 19,
        Surface::Dr => 21,
    }
}

/// The sign taking aeroident's deflection to ArduPlane's scaled output and PX4's torque
/// setpoint: −1 for every surface (module doc).
pub fn autopilot_sign(_s: Surface) -> f64 {
    -1.0
}

/// The throw of `s` in `o`, rad.
///
/// # Errors
/// None given for `s`, naming `--throw-deg`.
fn throw_of(o: &AutopilotOptions, s: Surface) -> crate::error::Result<f64> {
    o.throws.iter().find(|(t, _)| *t == s).map(|(_, v)| *v).ok_or_else(|| {
        crate::err!("--throw-deg: give the full throw of `{}`, a designed surface", s.name())
    })
}

/// Checks the options against the design: a throw for every designed surface, positive and
/// at most [`MAX_THROW_DEG`]; the start channel 1–16; and every surface's peak offset, added
/// to the trim deflection of the design's condition, within its throw.
///
/// # Errors
/// Each names the option and the surface (`--throw-deg de=…`, `--arm-rc`), and for a design
/// beyond a throw the trim, the peak offset and the throw in degrees.
pub fn check_limits(d: &Design, o: &AutopilotOptions) -> crate::error::Result<()> {
    if let Start::RcChannel(c) = o.start
        && !(1..=16).contains(&c)
    {
        crate::bail!("--arm-rc {c}: give an RC input channel 1–16");
    }
    let c = &d.plan.condition;
    for (s, u) in &d.inputs {
        let throw = throw_of(o, *s)?;
        let (name, deg) = (s.name(), throw.to_degrees());
        if !(throw.is_finite() && throw > 0.0 && deg <= MAX_THROW_DEG) {
            crate::bail!("--throw-deg {name}={deg}: give a positive throw up to {MAX_THROW_DEG}°");
        }
        let trim = match s {
            Surface::De => c.de_rad,
            Surface::Da => c.da_rad,
            Surface::Dr => c.dr_rad,
        };
        let peak = u.iter().fold(0f64, |a, v| a.max((trim + v).abs()));
        if peak > throw {
            let amp = u.iter().fold(0f64, |a, v| a.max(v.abs()));
            crate::bail!(
                "--throw-deg {name}={deg}: the design moves `{name}` to {:.2}° (trim {:.2}° and offsets up to ±{:.2}°), beyond its throw of {deg}°: lower --amplitude-deg or give the surface's real throw",
                peak.to_degrees(),
                trim.to_degrees(),
                amp.to_degrees()
            );
        }
    }
    Ok(())
}

/// Checks the design's table rate against what ArduPilot's scripting can time: at most
/// [`MAX_SCRIPT_RATE_HZ`].
///
/// # Errors
/// A faster design, naming `--rate-hz` and the limit.
pub fn check_script_rate(d: &Design) -> crate::error::Result<()> {
    let rate = design_rate_hz(d);
    if !(rate > 0.0 && rate <= MAX_SCRIPT_RATE_HZ) {
        crate::bail!(
            "--rate-hz {rate}: the ArduPlane script plays at most {MAX_SCRIPT_RATE_HZ} Hz (ArduPilot schedules scripts and reads the time in whole milliseconds): design at a lower rate"
        );
    }
    Ok(())
}

/// The design's table rate, Hz: the spec's rate back from its period (1/(1/r) can miss r in
/// the last bit, which would move the script's row boundaries by a row at exact multiples).
fn design_rate_hz(d: &Design) -> f64 {
    (1e6 / d.plan.manoeuvres[0].dt_s).round() / 1e6
}

/// The ArduPlane Lua script (module doc; how it flies and how it checks the rate it is called
/// at are in the script's own header): the design's injection table (integer centidegrees,
/// [`centidegrees`]) embedded per surface with its servo function, sign and throw.
///
/// # Errors
/// As [`check_limits`] and [`check_script_rate`].
pub fn ardupilot_lua(d: &Design, o: &AutopilotOptions) -> crate::error::Result<String> {
    check_limits(d, o)?;
    check_script_rate(d)?;
    let rate = design_rate_hz(d);
    let period_ms = (1000.0 / rate).floor().max(1.0);
    let mut surfaces = String::new();
    let (mut labels, mut format) = (String::from("TMs,Row"), String::from("Ii"));
    for (s, u) in &d.inputs {
        let throw_cdeg = centidegrees(throw_of(o, *s)?);
        let cap = capitalised(s.name());
        write!(labels, ",{cap}C,{cap}S").ok();
        format.push_str("if");
        let rows: Vec<String> = u.iter().map(|v| centidegrees(*v).to_string()).collect();
        writeln!(
            surfaces,
            "  {{ name = '{}', func = {}, sign = {}, throw_cdeg = {throw_cdeg},\n    offsets_cdeg = {{ {} }} }},",
            s.name(),
            servo_function(*s),
            autopilot_sign(*s),
            wrapped(&rows)
        )
        .ok();
    }
    let (start, stop) = match o.start {
        Start::ScrUser1 => ("set SCR_USER1 = 1".to_string(), "SCR_USER1 = 0".to_string()),
        Start::RcChannel(c) => (
            format!("move RC channel {c}'s switch high (> 1800 us)"),
            format!("moving it low (RC channel {c})"),
        ),
    };
    let replacements = [
        ("@DESCRIPTION@", description(d, o)),
        ("@START@", start),
        ("@STOP@", stop),
        ("@RATE_HZ@", format!("{rate}")),
        ("@ROWS@", d.t_s.len().to_string()),
        ("@ARM_RC@", arm_rc(o.start).to_string()),
        ("@PERIOD_MS@", format!("{period_ms}")),
        ("@OVERRIDE_MS@", format!("{}", (3.0 * period_ms).max(60.0))),
        ("@SURFACES@", surfaces.trim_end().to_string()),
        ("@LOG_LABELS@", format!("'{labels}'")),
        ("@LOG_FORMAT@", format!("'{format}'")),
    ];
    let mut lua = include_str!("ardupilot_sysid.lua").to_string();
    for (key, value) in replacements {
        lua = lua.replace(key, &value);
    }
    Ok(lua)
}

fn arm_rc(s: Start) -> u8 {
    match s {
        Start::ScrUser1 => 0,
        Start::RcChannel(c) => c,
    }
}

/// `de` → `De` (the log labels).
fn capitalised(name: &str) -> String {
    let mut c = name.chars();
    c.next().map_or_else(String::new, |f| f.to_uppercase().chain(c).collect())
}

/// Comma-separated values, twenty to a line (a script a person can scroll).
fn wrapped(values: &[String]) -> String {
    values.chunks(20).map(|c| c.join(", ")).collect::<Vec<_>>().join(",\n      ")
}

/// The script header's lines on the design: waveform, surfaces and throws, rows, the rate the
/// table was designed at and what a slower call rate does to it.
fn description(d: &Design, o: &AutopilotOptions) -> String {
    let rate = design_rate_hz(d);
    let throws: Vec<String> = d
        .inputs
        .iter()
        .filter_map(|(s, _)| {
            throw_of(o, *s).ok().map(|t| format!("{} {}°", s.name(), t.to_degrees()))
        })
        .collect();
    format!(
        "Design: {} rows at {rate} Hz ({} s), surfaces {}; full throws {} (SIGN -1, servo functions {}).\n\
         The table was designed at {rate} Hz, a row every {} ms: ArduPilot does not promise to\n\
         call a script that often, and called slower the script skips rows and warns (below).",
        d.t_s.len(),
        d.t_s.last().copied().unwrap_or(0.0),
        d.inputs.iter().map(|(s, _)| s.name()).collect::<Vec<_>>().join(", "),
        throws.join(", "),
        d.inputs
            .iter()
            .map(|(s, _)| format!("{} {}", s.name(), servo_function(*s)))
            .collect::<Vec<_>>()
            .join(", "),
        (1e6 / rate).round() / 1e3
    )
}

/// The PX4 table: `t_us` (µs from the start) and the normalised torque-setpoint offsets
/// `roll`, `pitch`, `yaw` (`VehicleTorqueSetpoint.xyz`, −1…1, positive for a positive body
/// moment) of the designed surfaces, `−δ / δmax` (aileron → roll, elevator → pitch, rudder →
/// yaw); an axis without a designed surface is 0. A fraction of full throw for a surface whose
/// torque effectiveness is 1 (an aileron pair of ±0.5 each moves each aileron by it too).
///
/// # Errors
/// As [`check_limits`].
pub fn px4_torque_table(d: &Design, o: &AutopilotOptions) -> crate::error::Result<String> {
    check_limits(d, o)?;
    let column = |axis: Surface| -> crate::error::Result<Option<(f64, &Vec<f64>)>> {
        match d.inputs.iter().find(|(s, _)| *s == axis) {
            Some((s, u)) => Ok(Some((autopilot_sign(*s) / throw_of(o, *s)?, u))),
            None => Ok(None),
        }
    };
    let axes = [column(Surface::Da)?, column(Surface::De)?, column(Surface::Dr)?];
    let mut out = String::from("t_us,roll,pitch,yaw\n");
    for (k, t) in d.t_s.iter().enumerate() {
        write!(out, "{}", (t * 1e6).round() as i64).ok();
        for axis in &axes {
            // Rounded to the six decimals written, `+ 0.0` then writes a value within 5e-7 of
            // zero (a multisine's ends) as 0, not -0.
            let v = axis.map_or(0.0, |(scale, u)| scale * u[k]);
            let v = (v * 1e6).round() / 1e6 + 0.0;
            write!(out, ",{v:.6}").ok();
        }
        out.push('\n');
    }
    Ok(out)
}

#[cfg(test)]
mod tests;
