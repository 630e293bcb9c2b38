//! Deterministic pilot inputs (issue 3 item 6; thesis §4.1–§4.2 test inputs): step, pulse,
//! doublet, sine, and their superposition.
//!
//! Every type is built by a validating constructor (`new`, returning [`SignalError`] on bad
//! parameters) and then evaluated with [`InputSignal::value`], which is allocation-free, never
//! fails and never returns NaN for a finite `t_s`. Amplitudes are in the caller's units: radians
//! for surface deflections in the API (the TOML `amplitude_deg` keys are converted once on load,
//! see [`crate::config`]). All times are seconds of simulation time.
//!
//! Conventions shared by all inputs: a signal is 0 before its `start_s`; intervals are closed on
//! the left and open on the right, so at `t_s == start_s` the input is already "on" (a Simulink
//! Step block with the same step time behaves the same way).

use crate::InputSignal;
use crate::error::{SignalError, finite, non_negative, positive};

/// Step: `0` for `t < start_s`, `amplitude` for `t ≥ start_s`.
///
/// Source: the thesis's step inputs of tables 4.1, 4.3, 4.4 and 4.6 (Simulink Step block, initial
/// value 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    amplitude: f64,
    start_s: f64,
}

impl Step {
    /// Step of height `amplitude` (caller's units) at `start_s` (s).
    ///
    /// # Errors
    /// [`SignalError::InvalidParameter`] if either argument is not finite.
    pub fn new(amplitude: f64, start_s: f64) -> Result<Self, SignalError> {
        Ok(Self {
            amplitude: finite("amplitude", amplitude)?,
            start_s: finite("start_s", start_s)?,
        })
    }
}

impl InputSignal for Step {
    fn value(&self, t_s: f64) -> f64 {
        if t_s >= self.start_s { self.amplitude } else { 0.0 }
    }
}

/// Rectangular pulse: `amplitude` for `start_s ≤ t < start_s + width_s`, 0 otherwise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pulse {
    amplitude: f64,
    start_s: f64,
    width_s: f64,
}

impl Pulse {
    /// Pulse of height `amplitude` (caller's units) starting at `start_s` (s), lasting `width_s`
    /// (s).
    ///
    /// # Errors
    /// [`SignalError::InvalidParameter`] if a value is not finite or `width_s ≤ 0`.
    pub fn new(amplitude: f64, start_s: f64, width_s: f64) -> Result<Self, SignalError> {
        Ok(Self {
            amplitude: finite("amplitude", amplitude)?,
            start_s: finite("start_s", start_s)?,
            width_s: positive("width_s", width_s)?,
        })
    }
}

impl InputSignal for Pulse {
    fn value(&self, t_s: f64) -> f64 {
        let tau = t_s - self.start_s;
        if (0.0..self.width_s).contains(&tau) { self.amplitude } else { 0.0 }
    }
}

/// Doublet: `+amplitude` for `start_s ≤ t < start_s + pulse_width_s`, then `−amplitude` for the
/// next `pulse_width_s`, then 0. Total length `2·pulse_width_s`.
///
/// `pulse_width_s` is the width of EACH of the two half-pulses (the usual flight-test
/// definition, e.g. Klein & Morelli, *Aircraft System Identification*, 2006, §9.2). A negative
/// amplitude flips the doublet: the thesis's "Doublet, Mag = −0.05 deg" (tables 4.7–4.10) is
/// `amplitude = −0.05°`, i.e. −0.05° for the first half and +0.05° for the second.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Doublet {
    amplitude: f64,
    start_s: f64,
    pulse_width_s: f64,
}

impl Doublet {
    /// Doublet of height `amplitude` (caller's units) starting at `start_s` (s), each half
    /// lasting `pulse_width_s` (s).
    ///
    /// # Errors
    /// [`SignalError::InvalidParameter`] if a value is not finite or `pulse_width_s ≤ 0`.
    pub fn new(amplitude: f64, start_s: f64, pulse_width_s: f64) -> Result<Self, SignalError> {
        Ok(Self {
            amplitude: finite("amplitude", amplitude)?,
            start_s: finite("start_s", start_s)?,
            pulse_width_s: positive("pulse_width_s", pulse_width_s)?,
        })
    }
}

impl InputSignal for Doublet {
    fn value(&self, t_s: f64) -> f64 {
        let tau = t_s - self.start_s;
        if (0.0..self.pulse_width_s).contains(&tau) {
            self.amplitude
        } else if (self.pulse_width_s..2.0 * self.pulse_width_s).contains(&tau) {
            -self.amplitude
        } else {
            0.0
        }
    }
}

/// Sine: `amplitude · sin(ω·(t − start_s) + φ)` for `start_s ≤ t < start_s + duration_s`
/// (or for all `t ≥ start_s` without a duration), 0 otherwise.
///
/// The phase is measured from `start_s`, so with `start_s = 0` this is exactly the Simulink Sine
/// Wave block `A·sin(ω t + φ)` that the thesis used (tables 4.2, 4.3; "sine 0.05°, 1 Hz" on the
/// elevator in tables 4.7–4.10). With φ ≠ 0 the signal jumps from 0 to `A·sin φ` at `start_s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sine {
    amplitude: f64,
    frequency_rad_s: f64,
    phase_rad: f64,
    start_s: f64,
    duration_s: Option<f64>,
}

impl Sine {
    /// Sine of `amplitude` (caller's units), angular frequency `frequency_rad_s` (rad/s; use
    /// `2π·f_hz` for a frequency in Hz), phase `phase_rad` (rad) at `start_s` (s), lasting
    /// `duration_s` (s; `None` = forever).
    ///
    /// # Errors
    /// [`SignalError::InvalidParameter`] if a value is not finite, `frequency_rad_s < 0` or
    /// `duration_s ≤ 0`.
    pub fn new(
        amplitude: f64,
        frequency_rad_s: f64,
        phase_rad: f64,
        start_s: f64,
        duration_s: Option<f64>,
    ) -> Result<Self, SignalError> {
        Ok(Self {
            amplitude: finite("amplitude", amplitude)?,
            frequency_rad_s: non_negative("frequency_rad_s", frequency_rad_s)?,
            phase_rad: finite("phase_rad", phase_rad)?,
            start_s: finite("start_s", start_s)?,
            duration_s: duration_s.map(|d| positive("duration_s", d)).transpose()?,
        })
    }
}

impl InputSignal for Sine {
    fn value(&self, t_s: f64) -> f64 {
        let tau = t_s - self.start_s;
        let active = tau >= 0.0 && self.duration_s.is_none_or(|d| tau < d);
        if active {
            self.amplitude * (self.frequency_rad_s * tau + self.phase_rad).sin()
        } else {
            0.0
        }
    }
}

/// Superposition of signals: `value(t) = Σ parts[i].value(t)` (an empty sum is 0).
///
/// Generic over the part type so it can hold the concrete [`Input`] enum (what the TOML config
/// builds) or boxed trait objects, `Sum<Box<dyn InputSignal + Send + Sync>>`, for user-defined
/// signals. Evaluation iterates the parts in place and allocates nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct Sum<S = Input> {
    parts: Vec<S>,
}

impl<S> Sum<S> {
    /// Sum of `parts` (any number, including none).
    pub fn new(parts: Vec<S>) -> Self {
        Self { parts }
    }

    /// The summed parts, in the order given.
    pub fn parts(&self) -> &[S] {
        &self.parts
    }
}

impl<S: InputSignal> InputSignal for Sum<S> {
    fn value(&self, t_s: f64) -> f64 {
        self.parts.iter().map(|p| p.value(t_s)).sum()
    }
}

/// Any input the crate provides, as one concrete type (static dispatch, `Clone`, `Send`).
/// Built from TOML by [`crate::config::InputConfig::build`].
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// See [`Step`].
    Step(Step),
    /// See [`Pulse`].
    Pulse(Pulse),
    /// See [`Doublet`].
    Doublet(Doublet),
    /// See [`Sine`].
    Sine(Sine),
    /// See [`crate::noise::BandLimitedWhiteNoise`].
    Noise(crate::noise::BandLimitedWhiteNoise),
    /// See [`Sum`].
    Sum(Sum<Input>),
}

impl InputSignal for Input {
    fn value(&self, t_s: f64) -> f64 {
        match self {
            Input::Step(s) => s.value(t_s),
            Input::Pulse(s) => s.value(t_s),
            Input::Doublet(s) => s.value(t_s),
            Input::Sine(s) => s.value(t_s),
            Input::Noise(s) => s.value(t_s),
            Input::Sum(s) => s.value(t_s),
        }
    }
}

macro_rules! impl_from_for_input {
    ($($t:ident => $v:ident),* $(,)?) => {$(
        impl From<$t> for Input {
            fn from(s: $t) -> Self { Input::$v(s) }
        }
    )*};
}
use crate::noise::BandLimitedWhiteNoise;
impl_from_for_input!(Step => Step, Pulse => Pulse, Doublet => Doublet, Sine => Sine,
    BandLimitedWhiteNoise => Noise);

impl From<Sum<Input>> for Input {
    fn from(s: Sum<Input>) -> Self {
        Input::Sum(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use core::f64::consts::PI;
    use proptest::prelude::*;

    #[test]
    fn analytic_step_values() {
        let s = Step::new(3.0, 1.0).unwrap();
        assert_eq!(s.value(0.999), 0.0);
        assert_eq!(s.value(1.0), 3.0);
        assert_eq!(s.value(100.0), 3.0);
        assert_eq!(s.value(-1.0), 0.0);
    }

    #[test]
    fn analytic_pulse_values() {
        let p = Pulse::new(-2.0, 1.0, 0.5).unwrap();
        assert_eq!(p.value(0.99), 0.0);
        assert_eq!(p.value(1.0), -2.0);
        assert_eq!(p.value(1.49), -2.0);
        assert_eq!(p.value(1.5), 0.0);
    }

    #[test]
    fn analytic_doublet_halves_and_sign_flip() {
        let d = Doublet::new(0.5, 2.0, 1.0).unwrap();
        assert_eq!(d.value(1.99), 0.0);
        assert_eq!(d.value(2.0), 0.5);
        assert_eq!(d.value(2.99), 0.5);
        assert_eq!(d.value(3.0), -0.5);
        assert_eq!(d.value(3.99), -0.5);
        assert_eq!(d.value(4.0), 0.0);
        // Negative amplitude (thesis "Mag = -.05 deg"): first half negative.
        let n = Doublet::new(-0.5, 2.0, 1.0).unwrap();
        assert_eq!(n.value(2.5), -0.5);
        assert_eq!(n.value(3.5), 0.5);
        // Zero mean over its length: integral of both halves cancels.
        let dt = 1e-3;
        let area: f64 = (0..5000).map(|i| d.value(i as f64 * dt) * dt).sum();
        assert!(area.abs() < 1e-9, "doublet area {area}");
    }

    #[test]
    fn analytic_sine_values() {
        // 1 Hz, 0.05 deg elevator sine of thesis table 4.7 case 4 (in rad).
        let a = 0.05_f64.to_radians();
        let s = Sine::new(a, 2.0 * PI, 0.0, 0.0, None).unwrap();
        assert_relative_eq!(s.value(0.25), a, epsilon = 1e-15);
        assert_relative_eq!(s.value(0.75), -a, epsilon = 1e-15);
        assert!(s.value(0.5).abs() < 1e-15);
        // Phase and start: A sin(w (t - t0) + phi); cos at t0 for phi = pi/2.
        let c = Sine::new(3.0, 0.7, PI / 2.0, 1.0, Some(2.0)).unwrap();
        assert_eq!(c.value(0.5), 0.0);
        assert_relative_eq!(c.value(1.0), 3.0, epsilon = 1e-15);
        assert_relative_eq!(c.value(2.0), 3.0 * (0.7 + PI / 2.0).sin(), epsilon = 1e-14);
        assert_eq!(c.value(3.0), 0.0);
    }

    #[test]
    fn analytic_superposition_is_sum_of_parts() {
        let step = Step::new(1.0, 0.0).unwrap();
        let sine = Sine::new(2.0, 3.0, 0.1, 0.5, None).unwrap();
        let doublet = Doublet::new(-1.5, 1.0, 0.25).unwrap();
        let sum = Sum::new(vec![Input::from(step), sine.into(), doublet.into()]);
        for i in 0..300 {
            let t = i as f64 * 0.01;
            let expect = step.value(t) + sine.value(t) + doublet.value(t);
            assert_eq!(sum.value(t), expect, "t = {t}");
        }
        assert_eq!(Sum::<Input>::new(vec![]).value(1.0), 0.0);
        // Boxed trait objects superpose too.
        let boxed: Sum<Box<dyn InputSignal + Send + Sync>> =
            Sum::new(vec![Box::new(step), Box::new(sine)]);
        assert_eq!(boxed.value(1.3), step.value(1.3) + sine.value(1.3));
    }

    #[test]
    fn invalid_parameters_are_errors_naming_the_field() {
        let e = Doublet::new(1.0, 0.0, 0.0).unwrap_err();
        assert!(e.to_string().contains("pulse_width_s"), "{e}");
        let e = Sine::new(1.0, 1.0, 0.0, 0.0, Some(-1.0)).unwrap_err();
        assert!(e.to_string().contains("duration_s"), "{e}");
        assert!(Step::new(f64::NAN, 0.0).is_err());
        assert!(Pulse::new(1.0, f64::INFINITY, 1.0).is_err());
    }

    proptest! {
        #[test]
        fn prop_inputs_never_nan_for_finite_parameters(
            a in -1e3f64..1e3, w in 0.0f64..1e3, ph in -10.0f64..10.0,
            t0 in -10.0f64..10.0, width in 1e-3f64..10.0, t in -1e3f64..1e3,
        ) {
            let parts: Vec<Input> = vec![
                Step::new(a, t0).unwrap().into(),
                Pulse::new(a, t0, width).unwrap().into(),
                Doublet::new(a, t0, width).unwrap().into(),
                Sine::new(a, w, ph, t0, Some(width)).unwrap().into(),
            ];
            let s = Sum::new(parts);
            prop_assert!(s.value(t).is_finite());
        }
    }
}
