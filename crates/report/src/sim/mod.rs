//! The files of an open-loop simulation ([`aeroident_pipelines::sim`], `aeroident f16 sim`;
//! [`aeroident_pipelines::sim::aircraft`], `aeroident sim --aircraft MODEL.toml`):
//! `timeseries.csv`, the figures and `report.html` (and the replay mapping of a model-file
//! aircraft's record).

mod aircraft;

pub use aircraft::write_aircraft_outputs;

use crate::outdir::OutputDir;
use crate::plot::{LineKind, Panel, Series};
use crate::report::{Report, common_settings, write_figure};
use aeroident_models::f16::ALPHA;
use aeroident_pipelines::sim::{SimRun, SimTable};
use anyhow::Context;

/// Writes `timeseries.csv`, `states.{png,svg}`, `controls_wind.{png,svg}` and `report.html`
/// (the trim, the record's size and the figures) into the locked output directory `od`, each
/// atomically.
///
/// # Errors
/// I/O, CSV or plotting errors naming the file.
pub fn write_outputs(run: &SimRun, od: &mut OutputDir) -> anyhow::Result<()> {
    write_timeseries(&run.table, od)?;
    let states = write_figure::<anyhow::Error>(
        od,
        "states",
        "F-16 open-loop response",
        "The true states (solid) and the sensed channels (dashed, where the scenario has sensors).",
        &states_panels(run),
        (1000, 230),
    )?;
    let controls = write_figure::<anyhow::Error>(
        od,
        "controls_wind",
        "F-16 controls and wind",
        "Surface commands and positions, throttle and engine power, and the wind in body axes.",
        &controls_panels(run),
        (1000, 230),
    )?;
    Report {
        title: "aeroident f16 sim".into(),
        settings: report_settings(run),
        figures: vec![states, controls],
        ..Default::default()
    }
    .write(od)?;
    Ok(())
}

/// Degrees per radian: the factor radian channels are drawn with.
const DEG_PER_RAD: f64 = 180.0 / std::f64::consts::PI;

/// `timeseries.csv`: the run's columns, one row per step, every value as `{:.10e}` (enough
/// digits to replay the record without loss that matters to identification).
fn write_timeseries(run: &SimTable, od: &mut OutputDir) -> anyhow::Result<()> {
    let mut file = od.create("timeseries.csv")?;
    let csv_path = file.path().to_path_buf();
    let mut w = csv::Writer::from_writer(&mut file);
    w.write_record(&run.columns).with_context(|| format!("writing `{}`", csv_path.display()))?;
    let n = run.data[0].len();
    for k in 0..n {
        w.write_record(run.data.iter().map(|c| format!("{:.10e}", c[k])))
            .with_context(|| format!("writing `{}`", csv_path.display()))?;
    }
    w.flush().with_context(|| format!("writing `{}`", csv_path.display()))?;
    drop(w);
    file.commit()?;
    Ok(())
}

/// A panel of the channels `chans` (name, factor to the plotted unit), each true channel solid
/// and its sensed `meas_` channel dashed where the run has one. Measured signals: the whole
/// record sets the range (a manoeuvre is not a transient).
fn channel_panel(run: &SimTable, title: &str, y_label: &str, chans: &[(&str, f64)]) -> Panel {
    // Legend names say the plotted unit: radian channels are drawn in degrees.
    let shown = |name: &str, scale: f64| -> String {
        if scale == DEG_PER_RAD {
            name.replace("_rad_s", "_deg_s").replace("_rad", "_deg")
        } else {
            name.to_string()
        }
    };
    let t = &run.data[0];
    let mut series = vec![];
    for &(ch, scale) in chans {
        if let Some(v) = run.column(ch) {
            series.push(Series {
                label: shown(ch, scale),
                t_s: t.clone(),
                values: v.iter().map(|x| x * scale).collect(),
                kind: LineKind::Solid,
            });
        }
        let m = format!("meas_{ch}");
        if let Some(v) = run.column(&m) {
            series.push(Series {
                label: shown(&m, scale),
                t_s: t.clone(),
                values: v.iter().map(|x| x * scale).collect(),
                kind: LineKind::Dashed,
            });
        }
    }
    Panel {
        title: title.to_string(),
        y_label: y_label.to_string(),
        series,
        signals: true,
        ..Default::default()
    }
}

/// The panels of `states`: airspeed, flow angles, body rates, attitude, load factors and
/// altitude (angles in deg).
fn states_panels(run: &SimRun) -> [Panel; 6] {
    let d = DEG_PER_RAD;
    let panel = |title: &str, y_label: &str, chans: &[(&str, f64)]| {
        channel_panel(&run.table, title, y_label, chans)
    };
    [
        panel("true airspeed", "vt (ft/s)", &[("vt_fps", 1.0)]),
        panel("angle of attack and sideslip", "deg", &[("alpha_rad", d), ("beta_rad", d)]),
        panel("body rates", "deg/s", &[("p_rad_s", d), ("q_rad_s", d), ("r_rad_s", d)]),
        panel("attitude", "deg", &[("phi_rad", d), ("theta_rad", d)]),
        panel("load factors", "g", &[("nz_g", 1.0), ("ny_g", 1.0), ("nx_g", 1.0)]),
        panel("altitude", "alt (ft)", &[("alt_ft", 1.0)]),
    ]
}

/// The panels of `controls_wind`: surface commands and positions (deg), throttle and engine
/// power, and the wind in body axes.
fn controls_panels(run: &SimRun) -> [Panel; 4] {
    let d = DEG_PER_RAD;
    let panel = |title: &str, y_label: &str, chans: &[(&str, f64)]| {
        channel_panel(&run.table, title, y_label, chans)
    };
    [
        panel("elevator", "deg", &[("elevator_cmd_rad", d), ("elevator_rad", d)]),
        panel(
            "aileron and rudder",
            "deg",
            &[("aileron_cmd_rad", d), ("aileron_rad", d), ("rudder_cmd_rad", d), ("rudder_rad", d)],
        ),
        panel(
            "throttle and power",
            "throttle (0-1) / power (%/100)",
            &[("throttle", 1.0), ("pow_pct", 0.01)],
        ),
        panel(
            "wind (body axes)",
            "ft/s",
            &[("wind_body_x_fps", 1.0), ("wind_body_y_fps", 1.0), ("wind_body_z_fps", 1.0)],
        ),
    ]
}

/// The report's settings: the common ones, the record's size, the trim the run started from
/// and how to replay the record.
fn report_settings(run: &SimRun) -> Vec<(String, String)> {
    let t = &run.table.data[0];
    let mut settings = common_settings();
    settings.extend([
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
                "throttle {:.4}, elevator {:.4}°, α {:.4}° (cost {:.1e})",
                run.trim.controls.throttle,
                run.trim.controls.elevator_rad.to_degrees(),
                run.trim.state[ALPHA].to_degrees(),
                run.trim.cost
            ),
        ),
        ("replay it with".into(), "--map mappings/aeroident-sim.toml (docs/mapping.md)".into()),
    ]);
    settings
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_pipelines::sim::{load_scenario, run};
    use std::path::Path;

    #[test]
    fn shipped_scenarios_run_and_write_outputs() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/sim");
        let mut n = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let p = entry.unwrap().path();
            if p.extension().and_then(|e| e.to_str()) != Some("toml") {
                continue;
            }
            let mut sc = load_scenario(&p).unwrap();
            sc.run.duration_s = sc.run.duration_s.min(3.0);
            let r = run(&sc, &dir).unwrap_or_else(|e| panic!("{}: {e:#}", p.display()));
            assert!(
                r.table.data.iter().all(|c| c.iter().all(|v| v.is_finite())),
                "{}",
                p.display()
            );
            n += 1;
            if n == 1 {
                let out =
                    std::env::temp_dir().join(format!("aeroident_sim_test_{}", std::process::id()));
                let mut od = OutputDir::open(&out, "f16 sim", &[]).unwrap();
                write_outputs(&r, &mut od).unwrap();
                od.finish();
                let csv = std::fs::read_to_string(out.join("timeseries.csv")).unwrap();
                assert_eq!(csv.lines().count(), r.table.data[0].len() + 1);
                assert!(out.join("states.png").exists() && out.join("controls_wind.png").exists());
                let _ = std::fs::remove_dir_all(&out);
            }
        }
        assert!(n >= 3);
    }
}
