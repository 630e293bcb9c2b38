//! Which unknowns the record determines, judged at the start, before any iteration.
//!
//! A time shift is left out when its Cramér–Rao σ alone is above [`MAX_SHIFT_SIGMA_S`]: the
//! channel hardly varies. A scale-factor error is left out when its σ *with the other
//! unknowns* is above [`MAX_SCALE_SIGMA`]: what matters for a scale factor is not whether its
//! channel varies but whether another unknown does the same to the outputs. Without a sideslip
//! vane the lateral accelerometer reaches the outputs only through the reconstructed `v` (in
//! `ẇ` through `p v`, in the airspeed to second order), and its scale factor then trades with
//! its bias and the initial `v` (measured on a degraded F-16 record: left in, it ran to 10⁷ and
//! dragged the other accelerometers' scale factors and `α` with it). The σ uses the start's
//! white-noise variances ([`Problem::noise_variances`]), which are smaller than any fit's
//! residuals, so what it leaves out the fit could never have determined.

use super::blocks::Sensitivities;
use super::{CompatResult, EstimatorError, MAX_SHIFT_SIGMA_S, Problem, Unknown, sensitivity};
use nalgebra::DMatrix;

/// Largest Cramér–Rao σ of a scale-factor error, with the other unknowns estimated, that the
/// record determines (dimensionless): 2 % of the reading, the smallest scale-factor error of
/// the sensors a flight test carries (2–5 %). Known no better, its ±2σ cannot tell a typical
/// error from none, and the freedom it gives the fit goes elsewhere: on a calm 10 Hz F-16
/// record without a β vane the accelerometers' scale factors came out 0.74 ± 0.06 (truth 1.03,
/// 1.02) with the airspeed bias at −64 m/s, and output error on the corrected record lost
/// every lateral derivative.
pub(super) const MAX_SCALE_SIGMA: f64 = 0.02;

/// Relative ridge on the Jacobi-scaled information matrix, so that an exactly singular one
/// still yields a (huge) σ for the unknown that makes it singular.
const RIDGE: f64 = 1e-12;

impl Problem<'_> {
    /// The unknowns the record does not determine at the start (module doc), with a note for
    /// each.
    ///
    /// # Errors
    /// [`EstimatorError::Numerical`] when the kinematics leave the physical domain at the
    /// start.
    pub(super) fn undetermined(&self) -> Result<(Vec<Unknown>, Vec<String>), EstimatorError> {
        let (mut out, mut notes) = self.undetermined_shifts()?;
        if self.unknowns.iter().any(|u| matches!(u, Unknown::Scale(_))) {
            let (scales, scale_notes) = self.undetermined_scales(&out)?;
            out.extend(scales);
            notes.extend(scale_notes);
        }
        Ok((out, notes))
    }

    /// The time shifts and the AHRS lag whose σ alone is above [`MAX_SHIFT_SIGMA_S`].
    fn undetermined_shifts(&self) -> Result<(Vec<Unknown>, Vec<String>), EstimatorError> {
        let beta = self.start();
        let r = self.noise_variances();
        let mut out = (Vec::new(), Vec::new());
        for (i, &u) in self.unknowns.iter().enumerate() {
            let name = match u {
                Unknown::TimeShift(c) => format!("time shift of {}", c.name()),
                Unknown::AhrsLag => "AHRS lag".into(),
                _ => continue,
            };
            let s = sensitivity(self, &beta, i)?;
            let info: f64 = s.iter().enumerate().map(|(row, v)| v * v / r[row % r.len()]).sum();
            let sigma = 1.0 / info.sqrt();
            if sigma.is_nan() || sigma >= MAX_SHIFT_SIGMA_S {
                out.0.push(u);
                out.1.push(format!("{name} not estimated: the channel hardly varies (its σ alone would be {sigma:.2} s)"));
            }
        }
        Ok(out)
    }

    /// The scale-factor errors whose σ with the other unknowns (all but `excluded`) is above
    /// [`MAX_SCALE_SIGMA`], dropped one at a time, the least determined first, since dropping
    /// one can determine another it traded with.
    fn undetermined_scales(
        &self,
        excluded: &[Unknown],
    ) -> Result<(Vec<Unknown>, Vec<String>), EstimatorError> {
        let s = Sensitivities::of(self, &self.start())?;
        let r = self.noise_variances();
        let e = vec![0.0; self.n_samples() * self.ny()];
        let (m, _) = if self.unknowns.len() <= super::DENSE_MAX_UNKNOWNS {
            super::information(&s.dense(), &e, &r)
        } else {
            s.information(&e, &r)
        };
        let mut kept: Vec<usize> =
            (0..self.unknowns.len()).filter(|&i| !excluded.contains(&self.unknowns[i])).collect();
        let mut out = (Vec::new(), Vec::new());
        loop {
            let sigma = conditional_sigma(&m, &kept);
            let worst = kept
                .iter()
                .zip(&sigma)
                .filter(|(i, _)| matches!(self.unknowns[**i], Unknown::Scale(_)))
                .max_by(|a, b| a.1.total_cmp(b.1));
            let Some((&i, &sig)) = worst else { break };
            if sig <= MAX_SCALE_SIGMA {
                break;
            }
            out.0.push(self.unknowns[i]);
            out.1.push(scale_note(self.unknowns[i], sig));
            kept.retain(|&k| k != i);
        }
        Ok(out)
    }
}

/// The note for a scale-factor error `u` left out with σ `sigma`.
pub(super) fn scale_note(u: Unknown, sigma: f64) -> String {
    let name = match u {
        Unknown::Scale(c) => c.name(),
        _ => "?",
    };
    format!(
        "scale factor of {name} not estimated: the record does not determine it with the other unknowns (its σ would be {sigma:.2})"
    )
}

impl CompatResult {
    /// The least determined scale-factor error whose reported σ (with the fit's residuals,
    /// [`CompatResult::reported_sigma`]) is above [`MAX_SCALE_SIGMA`], and that σ: the start's
    /// white-noise variances are smaller than a real record's residuals (turbulence, the
    /// model's errors), so the start's check alone lets through scale factors the fit then
    /// cannot determine.
    pub(super) fn undetermined_scale(&self) -> Option<(Unknown, f64)> {
        self.unknowns
            .iter()
            .zip(self.reported_sigma())
            .filter(|(u, s)| {
                matches!(u, Unknown::Scale(_)) && (s.is_nan() || **s > MAX_SCALE_SIGMA)
            })
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(u, s)| (*u, *s))
    }
}

/// `sqrt(diag M⁻¹)` of `m` restricted to `kept`, in the order of `kept`: Jacobi-scaled with
/// a relative [`RIDGE`], so a singular block gives huge σ rather than none; infinite for an
/// unknown without any information.
fn conditional_sigma(m: &DMatrix<f64>, kept: &[usize]) -> Vec<f64> {
    let informed: Vec<usize> = (0..kept.len()).filter(|&a| m[(kept[a], kept[a])] > 0.0).collect();
    let d: Vec<f64> = informed.iter().map(|&a| m[(kept[a], kept[a])].sqrt()).collect();
    let n = informed.len();
    let scaled = DMatrix::from_fn(n, n, |a, b| {
        let (i, j) = (kept[informed[a]], kept[informed[b]]);
        m[(i, j)] / (d[a] * d[b]) + if a == b { RIDGE } else { 0.0 }
    });
    let mut sigma = vec![f64::INFINITY; kept.len()];
    if let Some(c) = scaled.cholesky() {
        let inv = c.inverse();
        for (a, &k) in informed.iter().enumerate() {
            sigma[k] = inv[(a, a)].sqrt() / d[a];
        }
    }
    sigma
}
