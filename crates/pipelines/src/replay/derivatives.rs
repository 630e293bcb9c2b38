//! The causal derivative stage of the replay: supplies the time derivatives a model structure
//! needs and the record lacks — `ṗ`, `q̇`, `ṙ` (moment coefficients) and `α̇` (`alphadot`
//! terms) — from the causal least-squares-slope differentiator of
//! [`aeroident_signals::differentiate`], and delays the whole sample by the differentiator's
//! lag, `(N−1)/2` samples, so every channel of a sample stays aligned with its derivatives.
//!
//! The first and last `(N−1)/2` samples of each continuous stretch (record start, end, either
//! side of a gap) never get a centred derivative; they are returned as unused, for the caller
//! to count and list. After a gap the stage restarts ([`DerivativeStage::flush`]); nothing is
//! bridged.

use aeroident_estimators::AirDataSample;
use aeroident_signals::differentiate::{CausalDifferentiator, DifferentiateError};
use std::collections::VecDeque;

/// A derivative the stage can supply.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Derivative {
    /// `ṗ` from `p`.
    Pdot,
    /// `q̇` from `q`.
    Qdot,
    /// `ṙ` from `r`.
    Rdot,
    /// `α̇` from `α` (at the CG).
    Alphadot,
}

impl Derivative {
    /// All four.
    pub const ALL: [Derivative; 4] =
        [Derivative::Pdot, Derivative::Qdot, Derivative::Rdot, Derivative::Alphadot];

    /// The channel name (`pdot`, `qdot`, `rdot`, `alphadot`).
    pub fn name(self) -> &'static str {
        match self {
            Derivative::Pdot => "pdot",
            Derivative::Qdot => "qdot",
            Derivative::Rdot => "rdot",
            Derivative::Alphadot => "alphadot",
        }
    }

    /// The differentiated signal of sample `s`, if present.
    pub fn source(self, s: &AirDataSample) -> Option<f64> {
        match self {
            Derivative::Pdot => s.p_rad_s,
            Derivative::Qdot => s.q_rad_s,
            Derivative::Rdot => s.r_rad_s,
            Derivative::Alphadot => Some(s.alpha_rad),
        }
    }

    /// The derivative as recorded in sample `s`, if present.
    pub fn recorded(self, s: &AirDataSample) -> Option<f64> {
        match self {
            Derivative::Pdot => s.pdot_rad_s2,
            Derivative::Qdot => s.qdot_rad_s2,
            Derivative::Rdot => s.rdot_rad_s2,
            Derivative::Alphadot => s.alphadot_rad_s,
        }
    }

    /// Sets the derivative in sample `s`.
    pub fn set(self, s: &mut AirDataSample, v: Option<f64>) {
        match self {
            Derivative::Pdot => s.pdot_rad_s2 = v,
            Derivative::Qdot => s.qdot_rad_s2 = v,
            Derivative::Rdot => s.rdot_rad_s2 = v,
            Derivative::Alphadot => s.alphadot_rad_s = v,
        }
    }
}

/// The stage. Holds at most `(N−1)/2 + 1` samples.
#[derive(Debug)]
pub struct DerivativeStage {
    which: Vec<Derivative>,
    window: usize,
    dt_s: Option<f64>,
    diffs: Vec<CausalDifferentiator>,
    delay: VecDeque<(u64, AirDataSample)>,
    warning: Option<String>,
}

/// Largest relative disagreement between the nominal and the measured interval that is accepted
/// without a warning; beyond it the measured interval is used.
pub const DT_TOLERANCE: f64 = 0.01;

impl DerivativeStage {
    /// A stage that differentiates `which` (empty: a pass-through) over `window` samples
    /// spaced `dt_s` (the record's nominal interval; `None`: the first interval seen). The first
    /// interval is always measured: if it differs from `dt_s` by more than [`DT_TOLERANCE`]
    /// (relative), the measured interval is used and [`DerivativeStage::take_warning`] says so.
    pub fn new(which: Vec<Derivative>, window: usize, dt_s: Option<f64>) -> Self {
        Self {
            which,
            window,
            dt_s,
            diffs: Vec::new(),
            delay: VecDeque::with_capacity(window + 1),
            warning: None,
        }
    }

    /// The interval the differentiators use, s, once known.
    pub fn dt_s(&self) -> Option<f64> {
        if self.diffs.is_empty() { None } else { self.dt_s }
    }

    /// A warning raised since the last call (nominal and measured interval disagree).
    pub fn take_warning(&mut self) -> Option<String> {
        self.warning.take()
    }

    /// The derivatives this stage supplies.
    pub fn supplies(&self) -> &[Derivative] {
        &self.which
    }

    /// Pushes a sample (row `row`); appends the samples ready now (with their derivatives)
    /// to `ready` and the rows that can never get a centred derivative to `unused`.
    ///
    /// # Errors
    /// [`DifferentiateError`] when the first sample interval is not positive.
    pub fn push(
        &mut self,
        row: u64,
        s: AirDataSample,
        ready: &mut Vec<(u64, AirDataSample)>,
        unused: &mut Vec<u64>,
    ) -> Result<(), DifferentiateError> {
        if self.which.is_empty() {
            ready.push((row, s));
            return Ok(());
        }
        if self.diffs.is_empty() {
            // Until the interval is known, hold the first sample.
            let measured = match self.delay.back() {
                Some((_, prev)) => s.t_s - prev.t_s,
                None => {
                    self.delay.push_back((row, s));
                    return Ok(());
                }
            };
            let dt = match self.dt_s {
                Some(nom) if (measured - nom).abs() > DT_TOLERANCE * nom.abs() => {
                    self.warning = Some(format!(
                        "the mapping's nominal_dt_s = {nom} s differs from the record's measured interval {measured} s by more than {:.0} %: the differentiator uses the measured interval",
                        100.0 * DT_TOLERANCE
                    ));
                    measured
                }
                Some(nom) => nom,
                None => measured,
            };
            self.dt_s = Some(dt);
            for _ in &self.which {
                self.diffs.push(CausalDifferentiator::new(self.window, dt)?);
            }
            for (_, held) in &self.delay {
                for (d, w) in self.diffs.iter_mut().zip(self.which.iter()) {
                    d.update(w.source(held).unwrap_or(f64::NAN));
                }
            }
        }
        let half = self.window / 2;
        self.delay.push_back((row, s));
        let mut out = [None; 4];
        for (k, (d, w)) in self.diffs.iter_mut().zip(self.which.iter()).enumerate() {
            out[k] = d.update(w.source(&s).unwrap_or(f64::NAN));
        }
        if self.delay.len() > half + 1 {
            // Only during warm-up can the delay line overflow: these never get a centred value.
            if let Some((r, _)) = self.delay.pop_front() {
                unused.push(r);
            }
        }
        if out[0].is_some()
            && let Some((r, mut c)) = self.delay.pop_front()
        {
            for (k, w) in self.which.iter().enumerate() {
                w.set(&mut c, out[k].filter(|v| v.is_finite()));
            }
            ready.push((r, c));
        }
        Ok(())
    }

    /// Restarts (after a gap, or at the end): the delayed samples are unused.
    pub fn flush(&mut self, unused: &mut Vec<u64>) {
        for d in &mut self.diffs {
            d.reset();
        }
        unused.extend(self.delay.drain(..).map(|(r, _)| r));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Quadratic rates and α: the least-squares slope is exact for quadratics, so every
    /// supplied derivative equals the analytic one at the (delayed) sample's own time, and
    /// the other channels come from the same sample (alignment).
    /// Issue 10 #9: a wrong nominal interval (2 × the real one) is detected on the first
    /// interval; the measured one is used, so the derivative of q = 0.3 t is 0.3 (the nominal
    /// would give 0.15), and a warning names both intervals.
    #[test]
    fn analytic_wrong_nominal_interval_uses_the_measured_one_and_warns() {
        let dt = 0.02;
        let mut st = DerivativeStage::new(vec![Derivative::Qdot], 5, Some(2.0 * dt));
        let (mut ready, mut unused) = (Vec::new(), Vec::new());
        for k in 0..20u64 {
            let t = k as f64 * dt;
            let s = AirDataSample { t_s: t, q_rad_s: Some(0.3 * t), ..Default::default() };
            st.push(k, s, &mut ready, &mut unused).unwrap();
        }
        let w = st.take_warning().expect("warning");
        assert!(w.contains("0.04") && w.contains("0.02"), "{w}");
        assert_eq!(st.dt_s(), Some(dt));
        assert!(ready.len() > 10);
        for (_, s) in &ready {
            assert!((s.qdot_rad_s2.unwrap() - 0.3).abs() < 1e-9, "{:?}", s.qdot_rad_s2);
        }
        // A nominal within 1 % is kept without warning.
        let mut st = DerivativeStage::new(vec![Derivative::Qdot], 5, Some(dt * 1.005));
        for k in 0..3u64 {
            let s = AirDataSample { t_s: k as f64 * dt, ..Default::default() };
            st.push(k, s, &mut ready, &mut unused).unwrap();
        }
        assert!(st.take_warning().is_none());
        assert_eq!(st.dt_s(), Some(dt * 1.005));
    }

    #[test]
    fn analytic_quadratic_signals_are_differentiated_exactly_and_stay_aligned() {
        let dt = 0.02;
        let mut st = DerivativeStage::new(Derivative::ALL.to_vec(), 5, Some(dt));
        let (mut ready, mut unused) = (Vec::new(), Vec::new());
        for k in 0..40u64 {
            let t = k as f64 * dt;
            let s = AirDataSample {
                t_s: t,
                vt_mps: 100.0 + t,
                alpha_rad: 0.1 + 0.3 * t - 0.2 * t * t,
                qbar_pa: 1.0,
                p_rad_s: Some(0.5 * t * t),
                q_rad_s: Some(-0.4 * t + 0.1),
                r_rad_s: Some(2.0 * t * t - t),
                qdot_rad_s2: Some(99.0),
                ..Default::default()
            };
            st.push(k + 2, s, &mut ready, &mut unused).unwrap();
        }
        st.flush(&mut unused);
        assert_eq!(ready.len(), 36);
        assert_eq!(unused, vec![2, 3, 40, 41]);
        for (row, s) in &ready {
            let t = s.t_s;
            assert_eq!(*row, (t / dt).round() as u64 + 2);
            assert!((s.vt_mps - (100.0 + t)).abs() < 1e-12);
            assert!((s.pdot_rad_s2.unwrap() - t).abs() < 1e-9, "{t}");
            assert!((s.qdot_rad_s2.unwrap() + 0.4).abs() < 1e-9, "overrides the recorded q̇");
            assert!((s.rdot_rad_s2.unwrap() - (4.0 * t - 1.0)).abs() < 1e-9);
            assert!((s.alphadot_rad_s.unwrap() - (0.3 - 0.4 * t)).abs() < 1e-9);
        }
    }

    #[test]
    fn pass_through_when_nothing_is_differentiated() {
        let mut st = DerivativeStage::new(Vec::new(), 5, None);
        let (mut ready, mut unused) = (Vec::new(), Vec::new());
        let s = AirDataSample { qdot_rad_s2: Some(1.0), ..Default::default() };
        st.push(2, s, &mut ready, &mut unused).unwrap();
        assert_eq!(ready, vec![(2, s)]);
        assert!(unused.is_empty());
    }
}
