//! The fit from several starting points and the choice among them (module doc of
//! [`super`], "Time shifts"): with a gyro's time shift the cost has local minima a whole sample
//! apart in the common shift of the AHRS channels, so the fit starts from several common shifts
//! and keeps the best.

use super::{Channel, CompatConfig, CompatResult, GYROS, Problem, Unknown, ln_det};
use crate::EstimatorError;
use crate::output_error::Termination;

impl Problem<'_> {
    /// Iterates from each of [`Problem::starts`] and forms the result of the best fit
    /// ([`Problem::better`]; converged or not: its termination says); the first error when
    /// none ends.
    pub(super) fn solve(&self, config: &CompatConfig) -> Result<CompatResult, EstimatorError> {
        let mut best: Option<Ended> = None;
        let mut first_error = None;
        for mut beta in self.starts() {
            let ended = self.iterate(&mut beta, config).and_then(|(t, n)| {
                let cost = self.cost(&beta)?;
                Ok((cost, t, n))
            });
            match ended {
                Ok((cost, t, n)) if best.as_ref().is_none_or(|b| self.better((cost, t), b)) => {
                    best = Some((cost, beta, t, n));
                }
                Ok(_) => {}
                Err(e) => {
                    first_error.get_or_insert(e);
                }
            }
        }
        match best {
            Some((_, beta, t, n)) => self.finish(beta, t, n),
            None => Err(first_error.unwrap_or(EstimatorError::Numerical {
                what: "compatibility check: no starting point",
                t_s: self.man[0][0].t_s,
            })),
        }
    }

    /// Whether a fit that ended at cost `c` (`ln det R`) with termination `t` is better than
    /// `than`: a lower cost, but a converged fit is preferred to one that is not within half a
    /// unit of log-likelihood (`N/2 · Δ ln det R < 0.5`, statistically the same fit: the
    /// delays of whole samples put the optimum on a kink of the linear interpolation, where
    /// a fit from another start can stop a hair lower without converging).
    fn better(&self, (c, t): (f64, Termination), than: &Ended) -> bool {
        let same = 0.5 * self.n_samples() as f64 * (c - than.0).abs() < 0.5;
        match (same, t.is_converged(), than.2.is_converged()) {
            (true, true, false) => true,
            (true, false, true) => false,
            _ => c < than.0,
        }
    }

    /// `ln det R` at `beta`.
    pub(super) fn cost(&self, beta: &[f64]) -> Result<f64, EstimatorError> {
        let (mut y, mut e) = (Vec::new(), Vec::new());
        self.simulate(beta, &mut y)?;
        Ok(ln_det(&self.residuals(&y, &mut e)))
    }

    /// The starting points of the fit: [`Problem::start`] and, when a gyro's time shift is
    /// estimated, the same with the shifts of the gyros and attitudes all at a common offset
    /// `k·h`, `h` the first whole number of median sample intervals ≥ [`AHRS_START_STEP_S`],
    /// up to [`AHRS_START_MAX_S`] (module doc, "Time shifts": the local minima a whole sample
    /// apart); with an AHRS lag instead, the same with its time constant at each of
    /// [`AHRS_LAG_STARTS_S`]. With warm starting values ([`Problem::warm`]) only those.
    fn starts(&self) -> Vec<Vec<f64>> {
        let base = self.start();
        if !self.warm.is_empty() {
            return vec![base];
        }
        if let Some(i) = self.unknowns.iter().position(|u| *u == Unknown::AhrsLag) {
            return AHRS_LAG_STARTS_S
                .iter()
                .map(|&tau| {
                    let mut b = base.clone();
                    b[i] = tau;
                    b
                })
                .collect();
        }
        let gyro = |u: &Unknown| matches!(u, Unknown::TimeShift(c) if GYROS.contains(c));
        let dt = self.median_interval();
        if !(self.unknowns.iter().any(gyro) && dt > 0.0) {
            return vec![base];
        }
        let h = dt * (AHRS_START_STEP_S / dt).ceil();
        let offsets = (0..).map(|k| k as f64 * h).take_while(|o| *o <= AHRS_START_MAX_S + 1e-9);
        offsets
            .map(|o| {
                let mut b = base.clone();
                for (v, u) in b.iter_mut().zip(&self.unknowns) {
                    if matches!(u, Unknown::TimeShift(c) if AHRS.contains(c)) {
                        *v = o;
                    }
                }
                b
            })
            .collect()
    }

    /// The median interval between the samples of the manoeuvres, s (0 when there is none).
    fn median_interval(&self) -> f64 {
        let mut d: Vec<f64> =
            self.man.iter().flat_map(|m| m.windows(2).map(|w| w[1].t_s - w[0].t_s)).collect();
        d.sort_by(f64::total_cmp);
        d.get(d.len() / 2).copied().unwrap_or(0.0)
    }
}

/// A fit that ended: its cost `ln det R`, unknowns, termination and iterations.
type Ended = (f64, Vec<f64>, Termination, usize);

/// What an attitude and heading reference system delivers: the gyros and the attitudes.
const AHRS: [Channel; 6] =
    [Channel::P, Channel::Q, Channel::R, Channel::Phi, Channel::Theta, Channel::Psi];

/// The spacing of the common starting shifts of the AHRS channels, s, at least (a whole number
/// of samples): the lags of the AHRS of a UAV or a business jet, 0.1–0.2 s.
const AHRS_START_STEP_S: f64 = 0.1;

/// The largest common starting shift of the AHRS channels, s.
const AHRS_START_MAX_S: f64 = 0.3;

/// The starting time constants of an AHRS lag, s: none and the filters of the AHRS of a UAV or
/// a business jet, 0.1–0.2 s. The filter is smooth in `τ`, so these are not against local
/// minima of the interpolation but of the trade between the lag and the α vane's shift and
/// scale factor.
const AHRS_LAG_STARTS_S: [f64; 3] = [0.0, 0.1, 0.2];
