//! The corrected inertial inputs of one manoeuvre where the integration needs them: at each
//! sample time and each step's midpoint, every channel read at its own time shift, and the
//! accelerometers passed through the AHRS's filter when it has one.
//!
//! A gyro that lags the kinematics by `τ > 0` (an AHRS that filters its rates) is read `τ`
//! later, linearly interpolated between samples and held at the record's ends: the
//! interpolation [`interpolate`] gives the outputs. The accelerometers are the time reference
//! (their shift is always 0), so an unshifted channel is read at its samples and, between two,
//! at their mean: the linear interpolation at the midpoint.
//!
//! With an AHRS lag `τ` (module doc of [`super`], "The AHRS's lag") the gyros are read as
//! measured and the accelerometers through the same first-order filter, [`lag_step`] over the
//! linear interpolation, started in steady state at the first sample; a negative `τ`, which no
//! filter has but which the central differences at 0 and a record without a lag visit, reads
//! the accelerometers `|τ|` later instead: the same to first order in `τ`, so the cost is
//! smooth through 0.

use super::{Channel, Corrections, interpolate, lag_step};
use crate::sample::AirDataSample;

/// The corrected `(a, ω)` of one manoeuvre: `a` in m/s², `ω` in rad/s.
pub(super) struct Inputs {
    /// At each sample time.
    pub(super) at_samples: Vec<([f64; 3], [f64; 3])>,
    /// At the midpoint of each step, one fewer.
    pub(super) at_midpoints: Vec<([f64; 3], [f64; 3])>,
}

impl Inputs {
    /// The inputs of the samples `man` under the corrections `c`:
    /// `(z(t + τ) − b) / (1 + k)` per channel (module doc), the accelerometers filtered by an
    /// AHRS lag.
    pub(super) fn of(c: &Corrections, man: &[AirDataSample]) -> Self {
        let t: Vec<f64> = man.iter().map(|s| s.t_s).collect();
        let mid: Vec<f64> = t.windows(2).map(|w| w[0] + 0.5 * (w[1] - w[0])).collect();
        let mut at_s = vec![[0.0; 6]; t.len()];
        let mut at_m = vec![[0.0; 6]; mid.len()];
        for (j, ch) in Channel::INERTIAL.into_iter().enumerate() {
            let i = ch as usize;
            let z: Vec<f64> = man.iter().map(|s| ch.of(s).unwrap_or(0.0)).collect();
            let accelerometer = j < 3;
            let tau = if accelerometer && c.lag < 0.0 { -c.lag } else { c.shift[i] };
            let correct = |v: f64| (v - c.bias[i]) / (1.0 + c.scale[i]);
            if accelerometer && c.lag > 0.0 {
                let zc: Vec<f64> = z.iter().map(|&v| correct(v)).collect();
                filtered(&t, &zc, c.lag, j, &mut at_s, &mut at_m);
                continue;
            }
            for (k, out) in at_s.iter_mut().enumerate() {
                out[j] = correct(if tau == 0.0 { z[k] } else { interpolate(&t, &z, t[k] + tau) });
            }
            for (k, out) in at_m.iter_mut().enumerate() {
                let v = if tau == 0.0 {
                    0.5 * (z[k] + z[k + 1])
                } else {
                    interpolate(&t, &z, mid[k] + tau)
                };
                out[j] = correct(v);
            }
        }
        let split = |v: [f64; 6]| ([v[0], v[1], v[2]], [v[3], v[4], v[5]]);
        Self {
            at_samples: at_s.into_iter().map(split).collect(),
            at_midpoints: at_m.into_iter().map(split).collect(),
        }
    }
}

/// Channel `j` of `at_s` and `at_m`: the series `z` at the times `t` through the first-order
/// lag of time constant `tau > 0`, exact for `z` linear between samples, from steady state.
fn filtered(
    t: &[f64],
    z: &[f64],
    tau: f64,
    j: usize,
    at_s: &mut [[f64; 6]],
    at_m: &mut [[f64; 6]],
) {
    let mut y = z[0];
    at_s[0][j] = y;
    for k in 0..t.len() - 1 {
        let h = t[k + 1] - t[k];
        at_m[k][j] = lag_step(y, z[k], 0.5 * (z[k] + z[k + 1]), 0.5 * h, tau);
        y = lag_step(y, z[k], z[k + 1], h, tau);
        at_s[k + 1][j] = y;
    }
}
