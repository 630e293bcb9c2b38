//! Steady-flight trim of the F-16 (Stevens & Lewis §3.6) from a request in textbook units,
//! shared by `f16 trim`, `f16 linearize` and the Python bindings so that all give the same
//! checks and the same error context.

use crate::error::{Context, Result};
use aeroident_models::f16::F16;
use aeroident_models::trim::{F16Trim, TrimCondition, TrimManeuver, trim};

/// A steady flight condition to trim at: wings level, a coordinated turn or a pull-up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrimRequest {
    /// Altitude, ft.
    pub alt_ft: f64,
    /// True airspeed, ft/s.
    pub vt_fps: f64,
    /// Centre of gravity, fraction of the mean aerodynamic chord.
    pub xcg: f64,
    /// Flight-path angle, deg.
    pub gamma_deg: f64,
    /// Steady coordinated turn at this turn rate, deg/s (takes precedence over a pull-up).
    pub turn_rate_deg_s: Option<f64>,
    /// Steady pull-up at this pitch rate, deg/s.
    pub pull_up_deg_s: Option<f64>,
}

/// The F-16 at `r.xcg` and its trim at `r`. The trim's `out_of_range` lists what lies outside
/// the range the F-16 data are meant for (the tables extrapolate): the faces warn with it.
///
/// # Errors
/// An `xcg` outside its range, or a trim that does not converge (naming the condition).
pub fn trim_at(r: &TrimRequest) -> Result<(F16, F16Trim)> {
    let f16 = F16::new(r.xcg)?;
    let maneuver = match (r.turn_rate_deg_s, r.pull_up_deg_s) {
        (Some(w), _) => TrimManeuver::CoordinatedTurn { turn_rate_rad_s: w.to_radians() },
        (None, Some(q)) => TrimManeuver::PullUp { pitch_rate_rad_s: q.to_radians() },
        (None, None) => TrimManeuver::WingsLevel,
    };
    let cond = TrimCondition {
        alt_ft: r.alt_ft,
        vt_fps: r.vt_fps,
        gamma_rad: r.gamma_deg.to_radians(),
        maneuver,
    };
    let t = trim(&f16, &cond)
        .with_context(|| format!("trim at {} ft, {} ft/s, xcg {}", r.alt_ft, r.vt_fps, r.xcg))?;
    Ok((f16, t))
}

/// The warning line for one `out_of_range` item of a trim.
pub fn out_of_range_warning(item: &str) -> String {
    format!(
        "trim has {item}: outside the range the F-16 data are meant for (the tables extrapolate)"
    )
}
