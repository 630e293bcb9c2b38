//! The corrected inertial inputs of one manoeuvre where the integration needs them: at each
//! sample time and each step's midpoint, every channel read at its own time shift.
//!
//! A gyro that lags the kinematics by `τ > 0` (an AHRS that filters its rates) is read `τ`
//! later, linearly interpolated between samples and held at the record's ends: the
//! interpolation [`interpolate`] gives the outputs. The accelerometers are the time reference
//! (their shift is always 0), so an unshifted channel is read at its samples and, between two,
//! at their mean: the linear interpolation at the midpoint.

use super::{Channel, Corrections, interpolate};
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
    /// `(z(t + τ) − b) / (1 + k)` per channel (module doc).
    pub(super) fn of(c: &Corrections, man: &[AirDataSample]) -> Self {
        let t: Vec<f64> = man.iter().map(|s| s.t_s).collect();
        let mid: Vec<f64> = t.windows(2).map(|w| w[0] + 0.5 * (w[1] - w[0])).collect();
        let mut at_s = vec![[0.0; 6]; t.len()];
        let mut at_m = vec![[0.0; 6]; mid.len()];
        for (j, ch) in Channel::INERTIAL.into_iter().enumerate() {
            let i = ch as usize;
            let z: Vec<f64> = man.iter().map(|s| ch.of(s).unwrap_or(0.0)).collect();
            let tau = c.shift[i];
            let correct = |v: f64| (v - c.bias[i]) / (1.0 + c.scale[i]);
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
