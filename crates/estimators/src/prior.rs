//! Prior values and standard deviations of the vocabulary's parameters, for the estimators that
//! start from a prior (Kalman filters, sliding-mode and gradient estimators).
//!
//! The generic prior is deliberately weak: a value of the right sign and order for a
//! conventional subsonic aircraft (signs from static stability and damping: Cm_alpha < 0,
//! Cn_beta > 0, Cl_beta < 0, Cm_q, Cl_p, Cn_r < 0) and a σ several times larger than the
//! magnitude. It is not taken from any record or reference result. A model file can override
//! every entry. The pitch rate normalised with the reference speed (`q0` = q c̄/(2 V0)) is q̂ at
//! `V = V0` and has q̂'s prior: the catch-all 0 ± 1 is a fifteenth of a typical `Cm_q`, and the
//! filter held it there (on the HFB-320 record `Cm_q0` was never identified and `Cm_de` ended
//! 20 % off).

use crate::vocabulary::{Coefficient as C, MAX_PARAMS, ModelStructure, Param, Term as T};

/// Prior of one parameter: mean and standard deviation (units of the parameter).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamPrior {
    /// Prior mean.
    pub value: f64,
    /// Prior standard deviation (> 0).
    pub sigma: f64,
}

impl ParamPrior {
    /// Largest prior `|value|` accepted: ten times the largest plausible coefficient
    /// ([`crate::sample::PLAUSIBILITY`]`.coefficient`, 1000), room for a derivative on a
    /// small normalised regressor (a `CL_q` of 100 on `q c̄/2V`) with margin.
    pub const MAX_ABS_VALUE: f64 = 1e4;
    /// Largest prior σ accepted (same bound): a wider prior says nothing a record could not
    /// say better, and it breaks the estimators that scale by it: the sliding-mode bounds
    /// `[v/ρ, vρ]`, `ρ = 1 + 3σ/|v|` (a 128-point root search over 10¹⁰ reports grid points and
    /// bounds as estimates), the EKF's `P₀ = σ²`.
    pub const MAX_SIGMA: f64 = 1e4;
    /// Smallest prior σ accepted, relative to `max(|value|, 1)`: below it the bounds
    /// `v ± 3σ` of the sliding-mode estimators are not distinct numbers and the EKF's `P₀`
    /// leaves the parameter fixed; a parameter known that well belongs out of the model.
    pub const MIN_RELATIVE_SIGMA: f64 = 1e-9;

    /// Checks the prior against the limits above.
    ///
    /// # Errors
    /// A sentence saying which limit the value or σ breaks (the caller names the parameter
    /// and where the prior came from). With the crate's `std` feature (it builds the message).
    #[cfg(feature = "std")]
    pub fn check(&self) -> Result<(), std::string::String> {
        use std::format;
        let (v, s) = (self.value, self.sigma);
        if !(v.is_finite() && v.abs() <= Self::MAX_ABS_VALUE) {
            return Err(format!(
                "value {v} is not finite or beyond ±{:e} (no aerodynamic parameter is that large)",
                Self::MAX_ABS_VALUE
            ));
        }
        if !(s.is_finite() && s > 0.0) {
            return Err(format!("sigma must be finite and > 0, got {s}"));
        }
        if s > Self::MAX_SIGMA {
            return Err(format!(
                "sigma {s} is beyond {:e}: a prior that wide says nothing and breaks the estimators that scale by it (give a σ of the parameter's plausible range, or leave the prior out for the generic one)",
                Self::MAX_SIGMA
            ));
        }
        let floor = Self::MIN_RELATIVE_SIGMA * v.abs().max(1.0);
        if s < floor {
            return Err(format!(
                "sigma {s} is below {floor:e} (10⁻⁹ of max(|value|, 1)): the estimators cannot hold a parameter that tight; leave the parameter out of the model instead"
            ));
        }
        Ok(())
    }
}

/// The generic prior of parameter `p` (module doc).
pub fn generic_prior(p: Param) -> ParamPrior {
    let (value, sigma) = match (p.coefficient, p.term) {
        (C::CL, T::Bias) => (0.2, 1.0),
        (C::CL, T::Alpha) => (4.5, 5.0),
        (C::CL, T::Q | T::Q0) => (5.0, 30.0),
        (C::CL, T::Alphadot) => (0.0, 10.0),
        (C::CL, T::De) => (0.3, 2.0),
        (C::CZ, T::Bias) => (-0.2, 1.0),
        (C::CZ, T::Alpha) => (-4.5, 5.0),
        (C::CZ, T::Q | T::Q0) => (-5.0, 30.0),
        (C::CZ, T::Alphadot) => (0.0, 10.0),
        (C::CZ, T::De) => (-0.3, 2.0),
        (C::CD | C::CX, T::Bias) => (if p.coefficient == C::CD { 0.03 } else { -0.03 }, 0.3),
        (C::CD, T::Alpha) => (0.3, 2.0),
        (C::CX, T::Alpha) => (0.1, 2.0),
        (C::CD | C::CX, T::Q | T::Q0) => (0.0, 10.0),
        (C::CD | C::CX, T::De) => (0.0, 1.0),
        (C::Cm, T::Bias) => (0.0, 0.5),
        (C::Cm, T::Alpha) => (-0.5, 2.0),
        (C::Cm, T::Q | T::Q0) => (-15.0, 30.0),
        (C::Cm, T::Alphadot) => (-5.0, 15.0),
        (C::Cm, T::De) => (-1.0, 2.0),
        (C::CY, T::Bias) => (0.0, 0.1),
        (C::CY, T::Beta) => (-0.5, 2.0),
        (C::CY, T::P) => (0.0, 1.0),
        (C::CY, T::R) => (0.3, 2.0),
        (C::CY, T::Da) => (0.0, 0.5),
        (C::CY, T::Dr) => (0.1, 0.5),
        (C::Cl, T::Bias) => (0.0, 0.05),
        (C::Cl, T::Beta) => (-0.1, 0.5),
        (C::Cl, T::P) => (-0.4, 1.0),
        (C::Cl, T::R) => (0.1, 0.5),
        // δa > 0 (right aileron down) rolls left: Cl_da < 0 on a conventional aircraft.
        (C::Cl, T::Da) => (-0.1, 0.5),
        (C::Cl, T::Dr) => (0.01, 0.1),
        (C::Cn, T::Bias) => (0.0, 0.05),
        (C::Cn, T::Beta) => (0.1, 0.5),
        (C::Cn, T::P) => (0.0, 0.5),
        (C::Cn, T::R) => (-0.2, 1.0),
        (C::Cn, T::Da) => (0.0, 0.1),
        (C::Cn, T::Dr) => (-0.05, 0.2),
        (_, T::V) => (0.0, 0.5),
        (_, T::Alpha2 | T::AlphaDe | T::AlphaBeta) => (0.0, 10.0),
        _ => (0.0, 1.0),
    };
    ParamPrior { value, sigma }
}

/// Priors of every parameter of a structure, in parameter order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Priors {
    /// Number of parameters.
    pub n: usize,
    /// The priors, first `n` used.
    pub prior: [ParamPrior; MAX_PARAMS],
}

impl Priors {
    /// The generic prior of every parameter of `structure`.
    pub fn generic(structure: &ModelStructure) -> Self {
        let mut prior = [ParamPrior { value: 0.0, sigma: 1.0 }; MAX_PARAMS];
        let mut n = 0;
        for (i, p) in structure.params().enumerate().take(MAX_PARAMS) {
            prior[i] = generic_prior(p);
            n = i + 1;
        }
        Self { n, prior }
    }

    /// Overrides the prior of parameter index `i`.
    pub fn set(&mut self, i: usize, prior: ParamPrior) {
        if i < self.n {
            self.prior[i] = prior;
        }
    }
}

/// The sign a conventional, statically stable aircraft has for parameter `p`, where physics
/// fixes it: damping derivatives negative (`Cm_q`, `Cl_p`, `Cn_r`), static stability
/// (`Cm_alpha` < 0, `Cn_beta` > 0, `Cl_beta` < 0 for dihedral effect), lift-curve slope
/// positive (`CL_alpha` > 0, `CZ_alpha` < 0), side-force slope `CY_beta` < 0. `None` where the
/// sign depends on the design (control derivatives, cross derivatives, biases). A violated
/// sign is a warning, not an error: an unstable airframe or a sign convention of the record
/// can explain it (Klein & Morelli 2006 ch. 3; Stevens & Lewis §2.3).
pub fn expected_sign(p: Param) -> Option<f64> {
    Some(match (p.coefficient, p.term) {
        (C::Cm, T::Q | T::Q0) | (C::Cl, T::P) | (C::Cn, T::R) => -1.0,
        (C::Cm, T::Alpha) | (C::Cl, T::Beta) | (C::CY, T::Beta) | (C::CZ, T::Alpha) => -1.0,
        (C::Cn, T::Beta) | (C::CL, T::Alpha) => 1.0,
        _ => return None,
    })
}

/// The range a conventional subsonic aircraft's parameter `p` lies in, `(min, max)` in the
/// parameter's unit (per rad, per unit p̂ q̂ r̂), where experience bounds it; `None` elsewhere.
/// Deliberately wide: a value outside is not a property of any conventional aircraft but of
/// the data or the set-up (a unit, a sign, a mass or inertia constant, missing thrust, a
/// correlated pair, no excitation). The signs are those of [`expected_sign`] and of the
/// surface conventions (Klein & Morelli 2006 ch. 3; Stevens & Lewis); the magnitudes are wide
/// margins around the values this project has measured or been given: the HFB-320's published
/// output-error values (`models/hfb320_book_q0.toml`) and the JSBSim F-16's and c172x's own
/// derivatives (`../shared/flightdata/jsbsim_samples/*_truth.json`), with a lift slope of 1.5
/// to 8 per rad (a wing's is below 2π), a zero-lift drag above 0, and control powers at least
/// the magnitude a surface in degrees mapped as radians (÷57.3) falls below. JSBSim's c172x
/// model has a lift slope of 9.9 per rad, outside: a record of it needs `[plausible.CL_alpha]`.
/// The surfaces' side forces and cross-control moments (`CY_da`, `CY_dr`, `Cl_dr`, `Cn_da`)
/// get ±0.2 to ±0.5 (`CY_dr` up to 1): four or more times the largest of the textbook F-16's
/// tables (Stevens & Lewis: `CY_da` 0.060, `CY_dr` 0.164, `Cl_dr` −0.021 to 0.044, `Cn_da`
/// −0.077 to 0.049 per rad over its whole α, β envelope) and of JSBSim's F-16 and c172x
/// (|·| ≤ 0.1).
/// A model file's `[plausible.X]` replaces the range for an unconventional aircraft.
pub fn plausible_range(p: Param) -> Option<(f64, f64)> {
    Some(match (p.coefficient, p.term) {
        (C::CL, T::Bias) => (-0.5, 1.5),
        (C::CL, T::Alpha) => (1.5, 8.0),
        (C::CZ, T::Alpha) => (-8.0, -1.5),
        (C::CD, T::Bias) => (0.0, 0.3),
        (C::CD, T::Alpha) => (-0.2, 3.0),
        (C::Cm, T::Alpha) => (-5.0, 1.0),
        (C::Cm, T::Q | T::Q0) => (-100.0, 0.0),
        (C::Cm, T::De) => (-5.0, -0.1),
        (C::CY, T::Beta) => (-2.0, 0.0),
        (C::Cl, T::Beta) => (-0.5, 0.05),
        (C::Cl, T::P) => (-1.5, 0.0),
        (C::Cl, T::Da) => (-1.0, -0.02),
        (C::Cn, T::Beta) => (-0.05, 0.5),
        (C::Cn, T::R) => (-1.0, 0.0),
        (C::Cn, T::Dr) => (-0.5, -0.01),
        // The surfaces' side forces and cross-control moments, small on every aircraft: a value
        // far outside is what a surface that barely moved, or moved with the other one, hands a
        // term it cannot determine.
        (C::CY, T::Da) => (-0.5, 0.5),
        (C::CY, T::Dr) => (-0.2, 1.0),
        (C::Cl, T::Dr) => (-0.2, 0.2),
        (C::Cn, T::Da) => (-0.2, 0.2),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ranges hold the HFB-320's published output-error values
    /// (`models/hfb320_book_q0.toml`: CL_α 3.212, Cm_α −1.002, Cm_q0 −27.06, Cm_δe −1.437) and
    /// the JSBSim F-16's lateral derivatives (`jsbsim_samples/f16_ail_rud_doublets_truth.json`,
    /// δa in our sign: Cl_p −0.435, Cn_r −0.387, CY_β −1.159, Cl_β −0.087, Cn_β 0.184, Cl_δa
    /// −0.051, Cn_δr −0.045); a surface in degrees mapped as radians (Cm_δe −1.44/57.3), a
    /// negative drag and the PX4 template log's CL_0 of 6.86 are outside.
    #[test]
    fn the_ranges_hold_published_aircraft_and_refuse_unit_slips() {
        let inside = |c, t, v: f64| {
            let (lo, hi) = plausible_range(Param::new(c, t)).unwrap();
            lo <= v && v <= hi
        };
        for (c, t, v) in [
            (C::CL, T::Alpha, 3.212),
            (C::Cm, T::Alpha, -1.002),
            (C::Cm, T::Q0, -27.06),
            (C::Cm, T::De, -1.437),
            (C::Cl, T::P, -0.435),
            (C::Cn, T::R, -0.387),
            (C::CY, T::Beta, -1.159),
            (C::Cl, T::Beta, -0.087),
            (C::Cn, T::Beta, 0.184),
            (C::Cl, T::Da, -0.051),
            (C::Cn, T::Dr, -0.045),
            // Side-force and cross-control terms: the textbook F-16's extremes over its
            // envelope (per rad: CY_δa 0.021·57.3/20, CY_δr 0.086·57.3/30, DLDR's and DNDA's
            // extremes ×57.3/30 and ×57.3/20) and JSBSim's c172x
            // (c172x_elevator_3211_truth.json).
            (C::CY, T::Da, 0.060),
            (C::CY, T::Dr, 0.164),
            (C::Cl, T::Dr, 0.044),
            (C::Cl, T::Dr, -0.021),
            (C::Cn, T::Da, -0.077),
            (C::Cn, T::Da, 0.049),
            (C::CY, T::Da, -0.05),
            (C::CY, T::Dr, 0.098),
        ] {
            assert!(inside(c, t, v), "{c:?} {t:?} {v}");
        }
        assert!(!inside(C::Cm, T::De, -1.44 / 57.3));
        assert!(!inside(C::CD, T::Bias, -0.068));
        assert!(!inside(C::CL, T::Bias, 6.86));
        // A side force of 22 per rad of aileron (a real UAV's rudder multistep, where the
        // aileron barely moved, fitted by rls-iv) belongs to no aircraft.
        assert!(!inside(C::CY, T::Da, -22.7));
        assert!(plausible_range(Param::new(C::Cl, T::R)).is_none());
        // Every range agrees with the expected sign where physics fixes one.
        for c in C::ALL {
            for t in T::ALL {
                let p = Param::new(c, t);
                if let (Some((lo, hi)), Some(sign)) = (plausible_range(p), expected_sign(p)) {
                    assert!(lo < hi && (sign > 0.0 || lo < 0.0) && (sign < 0.0 || hi > 0.0));
                }
            }
        }
    }

    /// `q0` is q̂ at the reference speed: the same prior and the same expected sign.
    #[test]
    fn pitch_rate_normalised_by_v0_has_the_prior_of_q_hat() {
        for c in [C::CL, C::CZ, C::CD, C::CX, C::Cm] {
            let (q, q0) = (Param::new(c, T::Q), Param::new(c, T::Q0));
            assert_eq!(generic_prior(q0), generic_prior(q), "{}", q0.name());
            assert_eq!(expected_sign(q0), expected_sign(q), "{}", q0.name());
        }
    }
}
