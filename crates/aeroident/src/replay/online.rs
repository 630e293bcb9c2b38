//! The estimators of `aeroident replay` behind one object-safe interface, so the pipeline can
//! drive any of them sample by sample.

use super::Prepared;
use aeroident_estimators::legacy_kalman::{
    self as kalman, EkfConfig, LongitudinalConstants, LongitudinalEkf, LongitudinalSample,
    SigmaCorrection,
};
use aeroident_estimators::legacy_rls::{Rls, RlsConfig};
use aeroident_estimators::regressors::LinearCoefficient;
use aeroident_estimators::{EstimatorError, ParametricEstimator};
use aeroident_io::mapping::EkfNoise;

/// A sample-by-sample estimator of named parameters with optional standard errors.
pub trait OnlineEstimator {
    /// Parameter names (CSV headers), e.g. `Cm_alpha`.
    fn names(&self) -> Vec<&'static str>;
    /// Whether the estimator needs the measured coefficients (and so `q̇`).
    fn needs_coefficients(&self) -> bool;
    /// Consumes one prepared sample.
    ///
    /// # Errors
    /// The estimator's error; its state is unchanged.
    fn update(&mut self, s: &Prepared) -> Result<(), EstimatorError>;
    /// Writes the current estimates and standard errors (`None` where the method has none).
    fn current(&self, values: &mut [f64], sigmas: &mut [Option<f64>]);
}

/// One RLS coefficient fit, object-safe over its parameter count.
trait CoefficientFit {
    fn names(&self) -> Vec<&'static str>;
    fn update(&mut self, s: &Prepared) -> Result<(), EstimatorError>;
    fn current(&self, values: &mut [f64], sigmas: &mut [Option<f64>]);
}

impl<const P: usize> CoefficientFit for Rls<LinearCoefficient<P>, P> {
    fn names(&self) -> Vec<&'static str> {
        self.param_names().to_vec()
    }
    fn update(&mut self, s: &Prepared) -> Result<(), EstimatorError> {
        let c = s.coefficients.ok_or(EstimatorError::NonFiniteInput {
            field: "qdot_rad_s2",
            value: f64::NAN,
            t_s: s.flight.t_s,
        })?;
        ParametricEstimator::update(self, &c).map(|_| ())
    }
    fn current(&self, values: &mut [f64], sigmas: &mut [Option<f64>]) {
        let e = self.estimate();
        for i in 0..P {
            values[i] = e.theta[i];
            sigmas[i] = e.std_error(i);
        }
    }
}

/// Model structure of the equation-error fits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ModelTerms {
    /// `Cm = Cm_0 + Cm_alpha α + Cm_q q̂ + Cm_de δe`, `CL = CL_0 + CL_alpha α`, `CD = CD_0 + CD_alpha α`.
    Basic,
    /// The above plus `V/V0` terms `Cm_V`, `CL_V`, `CD_V` (Jategaonkar's HFB-320 model).
    WithSpeed,
    /// `Cm`, `CL` and `CD` each with `_0, _alpha, _q, _de` terms (as the JSBSim README's
    /// cross-check regression).
    Full,
}

/// Three recursive least-squares fits (Cm, CL, CD), run side by side on the same sample.
pub struct RlsSet {
    fits: Vec<Box<dyn CoefficientFit>>,
}

impl RlsSet {
    /// Three RLS fits with forgetting factor `forgetting`.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] for a forgetting factor outside (0, 1].
    pub fn new(terms: ModelTerms, forgetting: f64) -> Result<Self, EstimatorError> {
        let cfg = RlsConfig { forgetting, init_samples: 0 };
        let fits: Vec<Box<dyn CoefficientFit>> = match terms {
            ModelTerms::Basic => vec![
                Box::new(Rls::new(LinearCoefficient::PITCH_MOMENT, cfg)?),
                Box::new(Rls::new(LinearCoefficient::LIFT, cfg)?),
                Box::new(Rls::new(LinearCoefficient::DRAG, cfg)?),
            ],
            ModelTerms::WithSpeed => vec![
                Box::new(Rls::new(LinearCoefficient::PITCH_MOMENT_V, cfg)?),
                Box::new(Rls::new(LinearCoefficient::LIFT_V, cfg)?),
                Box::new(Rls::new(LinearCoefficient::DRAG_V, cfg)?),
            ],
            ModelTerms::Full => vec![
                Box::new(Rls::new(LinearCoefficient::PITCH_MOMENT, cfg)?),
                Box::new(Rls::new(LinearCoefficient::LIFT_FULL, cfg)?),
                Box::new(Rls::new(LinearCoefficient::DRAG_FULL, cfg)?),
            ],
        };
        Ok(Self { fits })
    }
}

impl OnlineEstimator for RlsSet {
    fn names(&self) -> Vec<&'static str> {
        self.fits.iter().flat_map(|f| f.names()).collect()
    }
    fn needs_coefficients(&self) -> bool {
        true
    }
    fn update(&mut self, s: &Prepared) -> Result<(), EstimatorError> {
        // All or nothing: check first, so one failing fit does not desynchronise the others.
        if s.coefficients.is_none() {
            return Err(EstimatorError::NonFiniteInput {
                field: "qdot_rad_s2",
                value: f64::NAN,
                t_s: s.flight.t_s,
            });
        }
        for f in &mut self.fits {
            f.update(s)?;
        }
        Ok(())
    }
    fn current(&self, values: &mut [f64], sigmas: &mut [Option<f64>]) {
        let mut k = 0;
        for f in &self.fits {
            let n = f.names().len();
            f.current(&mut values[k..k + n], &mut sigmas[k..k + n]);
            k += n;
        }
    }
}

/// Default EKF measurement-noise σ (SI) where the mapping gives none: typical flight-test
/// sensor-plus-model-error levels (V 0.5 m/s, α 0.002 rad, θ 0.005 rad, q 0.002 rad/s,
/// q̇ 0.01 rad/s², ax 0.05 m/s², az 0.2 m/s²).
pub const DEFAULT_EKF_SIGMA: [f64; kalman::N_OUT] = [0.5, 0.002, 0.005, 0.002, 0.01, 0.05, 0.2];

/// Generic prior of the EKF parameters (order of [`kalman::PARAM_NAMES`]): a typical
/// subsonic transport; every variance is 10 (Jategaonkar 2015 `mDefCase04.m` uses 10 for all).
pub const EKF_PRIOR: [f64; kalman::N_PARAMS] =
    [0.05, 0.0, 0.3, 0.2, 0.0, 4.5, 0.0, 0.0, -0.5, -15.0, -1.0];

/// The augmented-state EKF wrapped for the replay.
pub struct EkfReplay {
    ekf: LongitudinalEkf,
}

impl EkfReplay {
    /// Builds the filter from the first prepared sample's constants and the mapping's noise.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] for invalid constants or noise.
    pub fn new(first: &Prepared, v0_mps: f64, noise: &EkfNoise) -> Result<Self, EstimatorError> {
        let f = &first.flight;
        let n = noise;
        let sig = [
            n.sigma_vt_mps,
            n.sigma_alpha_rad,
            n.sigma_theta_rad,
            n.sigma_q_rad_s,
            n.sigma_qdot_rad_s2,
            n.sigma_ax_mps2,
            n.sigma_az_mps2,
        ];
        let mut r = [0.0; kalman::N_OUT];
        for i in 0..kalman::N_OUT {
            let s = sig[i].unwrap_or(DEFAULT_EKF_SIGMA[i]);
            r[i] = s * s;
        }
        let cfg = EkfConfig {
            constants: LongitudinalConstants {
                mass_kg: f.mass_kg,
                S_m2: f.S_m2,
                cbar_m: f.cbar_m,
                Iyy_kgm2: f.Iyy_kgm2,
                thrust_arm_m: f.thrust_arm_m,
                thrust_incidence_rad: f.thrust_incidence_rad,
                v0_mps,
            },
            theta0: EKF_PRIOR,
            p0_states: [1.0, 1e-4, 1e-4, 1e-4],
            p0_params: [10.0; kalman::N_PARAMS],
            q_states: [0.0; kalman::N_STATES],
            q_params: 0.0,
            r,
            sigma: SigmaCorrection::ColouredResiduals,
        };
        Ok(Self { ekf: LongitudinalEkf::new(cfg)? })
    }
}

impl OnlineEstimator for EkfReplay {
    fn names(&self) -> Vec<&'static str> {
        kalman::PARAM_NAMES.to_vec()
    }
    fn needs_coefficients(&self) -> bool {
        false
    }
    fn update(&mut self, s: &Prepared) -> Result<(), EstimatorError> {
        let f = &s.flight;
        let theta = f.theta_rad.ok_or(EstimatorError::NonFiniteInput {
            field: "theta_rad",
            value: f64::NAN,
            t_s: f.t_s,
        })?;
        let sample = LongitudinalSample {
            t_s: f.t_s,
            de_rad: f.de_rad,
            thrust_n: f.thrust_n,
            rho_kgpm3: s.rho_kgpm3,
            y: [
                Some(f.vt_mps),
                Some(s.alpha_cg_rad),
                Some(theta),
                Some(f.q_rad_s),
                // Only a recorded q̇ is an independent measurement; a differentiated one is not.
                f.qdot_rad_s2,
                Some(f.ax_mps2),
                Some(f.az_mps2),
            ],
        };
        self.ekf.update(&sample).map(|_| ())
    }
    fn current(&self, values: &mut [f64], sigmas: &mut [Option<f64>]) {
        let e = self.ekf.estimate();
        for i in 0..kalman::N_PARAMS {
            values[i] = e.theta[i];
            sigmas[i] = e.std_error(i);
        }
    }
}
