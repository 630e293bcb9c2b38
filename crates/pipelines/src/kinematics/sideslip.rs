//! The sideslip a record without a β vane implies, for the lateral sign tests.
//!
//! The lateral moment regressions need β. Standing `a_y` in for it fails on the rudder: the
//! side force is `Y_β β + Y_δr δr`, so `N_β β` read through `a_y` puts `−N_β Y_δr / Y_β` into
//! the rudder's coefficient, which outweighs `N_δr` where `|Y_β|` is small (a business jet's
//! rudder then read "reversed" with its yaw fit at R² 0.99). The force equation gives β
//! itself (Stevens & Lewis, *Aircraft Control and Simulation*, 2nd ed., eq. 2.5-17 at small
//! β, with the gravity term of Table 2.5-1):
//!
//! ```text
//! β̇ = (a_y + g cosθ sinφ) / V + p sinα − r cosα
//! ```
//!
//! integrated (trapezoidal) over each contiguous run of samples. An accelerometer bias or a
//! wind change integrates to a drift, and the start is unknown: each run's least-squares line
//! in time is taken out, which leaves the β a manoeuvre flown from and back to trim holds
//! (Klein & Morelli, *Aircraft System Identification*, 2006, §10.1, reconstruct the flow
//! angles from the kinematics the same way).

use aeroident_estimators::AirDataSample;
use aeroident_physics::units::G0_MPS2;

/// How the β of a record without a vane was formed, for the sign tests' evidence.
pub const HOW: &str =
    "β from the kinematics (∫ (a_y + g cosθ sinφ)/V + p sinα − r cosα dt, less its line per run)";

/// The manoeuvres with `beta_rad` set to the reconstructed sideslip (module doc) on every
/// sample of a run that carries `a_y`, `r` and `φ`, and `None` elsewhere. `p` and `θ` count
/// as 0 where missing (their terms are second order at small α and θ). A run also ends at an
/// interval beyond 2.5 times the record's shortest (a gap). `None` when no run has a sample
/// that carries them.
pub fn filled<M: AsRef<[AirDataSample]>>(manoeuvres: &[M]) -> Option<Vec<Vec<AirDataSample>>> {
    let dt_max_s = 2.5
        * manoeuvres
            .iter()
            .flat_map(|m| m.as_ref().windows(2).map(|w| w[1].t_s - w[0].t_s))
            .filter(|d| *d > 0.0)
            .fold(f64::INFINITY, f64::min);
    let out: Vec<Vec<AirDataSample>> =
        manoeuvres.iter().map(|m| with_sideslip(m.as_ref(), dt_max_s)).collect();
    out.iter().flatten().any(|s| s.beta_rad.is_some()).then_some(out)
}

/// β̇ of one sample (module doc), `None` without `a_y`, `r`, `φ` or a positive airspeed.
fn beta_rate(s: &AirDataSample) -> Option<f64> {
    let (ay, r, phi) = (s.ay_mps2?, s.r_rad_s?, s.phi_rad?);
    let (p, theta) = (s.p_rad_s.unwrap_or(0.0), s.theta_rad.unwrap_or(0.0));
    let gravity = G0_MPS2 * theta.cos() * phi.sin();
    let rate = (ay + gravity) / s.vt_mps + p * s.alpha_rad.sin() - r * s.alpha_rad.cos();
    (s.vt_mps > 0.0 && rate.is_finite()).then_some(rate)
}

/// One manoeuvre with its reconstructed β, run by run: a run ends where a sample lacks a
/// field or an interval is not in (0, `dt_max_s`].
fn with_sideslip(samples: &[AirDataSample], dt_max_s: f64) -> Vec<AirDataSample> {
    let mut out: Vec<AirDataSample> =
        samples.iter().map(|s| AirDataSample { beta_rad: None, ..*s }).collect();
    let mut start = 0;
    while start < samples.len() {
        let mut end = start;
        while end < samples.len() && beta_rate(&samples[end]).is_some() {
            let joined = end == start || {
                let d = samples[end].t_s - samples[end - 1].t_s;
                d > 0.0 && d <= dt_max_s
            };
            if !joined {
                break;
            }
            end += 1;
        }
        if end > start + 2 {
            let run = &samples[start..end];
            let t: Vec<f64> = run.iter().map(|s| s.t_s).collect();
            let rates: Vec<f64> = run.iter().map(|s| beta_rate(s).unwrap_or(0.0)).collect();
            for (s, b) in out[start..end].iter_mut().zip(super::integral_less_line(&t, &rates)) {
                s.beta_rad = Some(b);
            }
        }
        start = end.max(start + 1);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A coordinated sideslip history β = 0.02 sin(0.8 t) at 60 m/s, wings level, α = 0: the
    /// side force that carries it (`a_y = V β̇ + V r`, r = 0.1 cos t) gives back β, and an
    /// accelerometer bias of 0.3 m/s² (a drift of 0.005 rad/s) is taken out with the line.
    #[test]
    fn the_side_force_integrates_to_the_sideslip_less_its_line() {
        let v = 60.0;
        let beta = |t: f64| 0.02 * (0.8 * t).sin();
        let samples: Vec<AirDataSample> = (0..=1000)
            .map(|k| {
                let t = 0.01 * k as f64;
                let r = 0.1 * t.cos();
                let beta_dot = 0.016 * (0.8 * t).cos();
                AirDataSample {
                    t_s: t,
                    vt_mps: v,
                    ay_mps2: Some(v * beta_dot + v * r + 0.3),
                    r_rad_s: Some(r),
                    phi_rad: Some(0.0),
                    ..AirDataSample::default()
                }
            })
            .collect();
        let out = filled(&[&samples]).unwrap();
        let truth: Vec<f64> = samples.iter().map(|s| beta(s.t_s)).collect();
        let t: Vec<f64> = samples.iter().map(|s| s.t_s).collect();
        let expected = super::super::less_line(&t, &truth);
        for (s, e) in out[0].iter().zip(expected) {
            assert!((s.beta_rad.unwrap() - e).abs() < 1e-5, "{} {e}", s.t_s);
        }
        let no_phi: Vec<AirDataSample> =
            samples.iter().map(|s| AirDataSample { phi_rad: None, ..*s }).collect();
        assert!(filled(&[&no_phi]).is_none());
    }

    /// A gap or a sample without a field ends a run; each run is integrated on its own.
    #[test]
    fn a_gap_starts_a_new_run() {
        let sample = |t: f64| AirDataSample {
            t_s: t,
            vt_mps: 50.0,
            ay_mps2: Some(1.0),
            r_rad_s: Some(0.0),
            phi_rad: Some(0.0),
            ..AirDataSample::default()
        };
        let mut samples: Vec<AirDataSample> = (0..10).map(|k| sample(0.1 * k as f64)).collect();
        samples.extend((0..10).map(|k| sample(5.0 + 0.1 * k as f64)));
        samples[15].ay_mps2 = None;
        let out = &filled(&[&samples]).unwrap()[0];
        // A constant β̇ is a line: nothing is left of it in any run.
        assert!(out[..10].iter().all(|s| s.beta_rad.unwrap().abs() < 1e-12));
        assert!(out[10..15].iter().all(|s| s.beta_rad.unwrap().abs() < 1e-12));
        assert!(out[15].beta_rad.is_none());
    }
}
