//! The files of a model-file aircraft's simulation (`aeroident sim --aircraft MODEL.toml`):
//! `timeseries.csv` (SI), `mapping.toml` that replays it, `states` and `controls` figures and
//! `report.html`.

use super::{DEG_PER_RAD, channel_panel, write_timeseries};
use crate::outdir::OutputDir;
use crate::plot::Panel;
use crate::report::{Report, common_settings, write_figure};
use aeroident_pipelines::sim::SimTable;
use aeroident_pipelines::sim::aircraft::AircraftSimRun;

/// Writes `timeseries.csv`, `mapping.toml` (the text `mapping`), `states.{png,svg}`,
/// `controls.{png,svg}` and `report.html` into the locked output directory `od`, each
/// atomically.
///
/// # Errors
/// I/O, CSV or plotting errors naming the file.
pub fn write_aircraft_outputs(
    run: &AircraftSimRun,
    mapping: &str,
    od: &mut OutputDir,
) -> anyhow::Result<()> {
    write_timeseries(&run.table, od)?;
    od.write_bytes("mapping.toml", mapping.as_bytes())?;
    let states = write_figure::<anyhow::Error>(
        od,
        "states",
        &format!("{}: open-loop response", run.aircraft),
        "The true states (solid) and the sensed channels (dashed, where the scenario has sensors).",
        &states_panels(&run.table),
        (1000, 230),
    )?;
    let controls = write_figure::<anyhow::Error>(
        od,
        "controls",
        &format!("{}: controls", run.aircraft),
        "Surfaces (they follow the commands: no actuator model) and the engine command.",
        &controls_panels(run),
        (1000, 230),
    )?;
    Report {
        title: "aeroident sim".into(),
        settings: settings(run),
        figures: vec![states, controls],
        ..Default::default()
    }
    .write(od)?;
    Ok(())
}

/// Airspeed, flow angles, body rates, attitude, accelerometers and altitude (angles in deg).
fn states_panels(run: &SimTable) -> [Panel; 6] {
    let d = DEG_PER_RAD;
    let panel = |title: &str, y_label: &str, chans: &[(&str, f64)]| {
        channel_panel(run, title, y_label, chans)
    };
    [
        panel("true airspeed", "vt (m/s)", &[("vt_mps", 1.0)]),
        panel("angle of attack and sideslip", "deg", &[("alpha_rad", d), ("beta_rad", d)]),
        panel("body rates", "deg/s", &[("p_rad_s", d), ("q_rad_s", d), ("r_rad_s", d)]),
        panel("attitude", "deg", &[("phi_rad", d), ("theta_rad", d)]),
        panel(
            "accelerometers (specific force)",
            "m/s²",
            &[("ax_mps2", 1.0), ("ay_mps2", 1.0), ("az_mps2", 1.0)],
        ),
        panel("altitude", "alt (m)", &[("alt_m", 1.0)]),
    ]
}

/// The surfaces (deg) and the engine command with the thrust.
fn controls_panels(run: &AircraftSimRun) -> [Panel; 3] {
    let d = DEG_PER_RAD;
    let t = &run.table;
    [
        channel_panel(t, "elevator", "deg", &[("elevator_rad", d)]),
        channel_panel(t, "aileron and rudder", "deg", &[("aileron_rad", d), ("rudder_rad", d)]),
        channel_panel(
            t,
            "engine",
            &format!("{} / thrust (N)", run.engine_column),
            &[(run.engine_column, 1.0), ("thrust_n", 1.0)],
        ),
    ]
}

/// The report's settings: the aircraft, the record's size, the trim and how to replay it.
fn settings(run: &AircraftSimRun) -> Vec<(String, String)> {
    let t = &run.table.data[0];
    let (x, u) = (&run.trim.state, &run.trim.controls);
    let mut s = common_settings();
    s.extend([
        ("aircraft".into(), run.aircraft.clone()),
        (
            "record".into(),
            format!(
                "{:.2} s, {} rows × {} columns (timeseries.csv)",
                t.last().copied().unwrap_or(0.0),
                t.len(),
                run.table.columns.len()
            ),
        ),
        (
            "trim".into(),
            format!(
                "{:.3} m/s, {:.1} m: α {:.4}°, elevator {:.4}°, {} {:.6} (residual {:.1e})",
                x[0],
                x[11],
                x[1].to_degrees(),
                u[1].to_degrees(),
                run.engine_column,
                u[0],
                run.trim.max_abs_residual
            ),
        ),
        ("replay it with".into(), "--map mapping.toml (written beside the record)".into()),
    ]);
    s
}
