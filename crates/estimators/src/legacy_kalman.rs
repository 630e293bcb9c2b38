//! Augmented-state extended Kalman filter for the longitudinal motion: states `(V, α, θ, q)` and
//! eleven aerodynamic parameters estimated together, sample by sample.
//!
//! This is the recursive counterpart of output-error estimation that Jategaonkar, *Flight
//! Vehicle System Identification*, AIAA 2015, ch. 7 (§7.3, `ekf_mod.m`, test case 4) applies to
//! the HFB-320 record. The model is the book's (eq. 5.86–5.89, `xdot_TC04_hfb_lon.m`,
//! `obs_TC04_hfb_lon.m`), with the aircraft constants as configuration:
//!
//! ```text
//! q̄ = ½ρV²,  q̂ = q c̄/(2V)
//! CD = CD_0 + CD_V V/V0 + CD_alpha α
//! CL = CL_0 + CL_V V/V0 + CL_alpha α
//! Cm = Cm_0 + Cm_V V/V0 + Cm_alpha α + Cm_q q̂ + Cm_de δe
//! V̇ = −q̄S CD/m + T cos(α+σT)/m + g sin(α−θ)
//! α̇ = −q̄S CL/(mV) − T sin(α+σT)/(mV) + q + g cos(α−θ)/V
//! θ̇ = q
//! q̇ = q̄S c̄ Cm/Iy + l_T T/Iy
//! observed: V, α, θ, q, q̇, ax = (q̄S CX + T cos σT)/m, az = (q̄S CZ − T sin σT)/m
//! CX = CL sin α − CD cos α,  CZ = −CL cos α − CD sin α
//! ```
//!
//! Note the book writes the `Cm_q` term with `V0`; we use `q̂ = q c̄/(2V)` (the convention of the
//! whole project), which differs by `V/V0` (within ±8 % on the HFB-320 record).
//!
//! Filter (Jategaonkar 2015, eq. 7.19–7.31): mean propagated by RK4 with the inputs held over
//! the sample interval; covariance by `Φ P Φᵀ + Q·dt` with `Φ = I + A dt + (A dt)²/2`, `A = ∂f/∂x`
//! by central differences; measurement update component by component (diagonal `R`), which is
//! exactly the joint update for a diagonal `R` and lets a sample omit any output. Parameter
//! standard errors are the square roots of the parameter block of `P`.
//!
//! Units: SI (m, kg, N, Pa, rad, s). Derivatives per rad, `Cm_q` per unit `q̂`, `_V` per unit
//! `V/V0`.
//!
//! **WARNING:** a Kalman filter's covariance is only as honest as `Q` and `R`. With zero
//! parameter process noise the parameter σ shrink like Cramér–Rao bounds of output error and
//! are optimistic on real data with unmodelled dynamics and coloured residuals.

use crate::{Estimate, EstimatorError, ParametricEstimator};
use nalgebra::{SMatrix, SVector};

/// Number of aerodynamic parameters estimated.
pub const N_PARAMS: usize = 11;
/// Number of dynamic states `(V, α, θ, q)`.
pub const N_STATES: usize = 4;
/// Augmented state length.
pub const N_AUG: usize = N_STATES + N_PARAMS;
/// Number of observed outputs `(V, α, θ, q, q̇, ax, az)`.
pub const N_OUT: usize = 7;

/// Parameter names in state order (after the four dynamic states).
pub const PARAM_NAMES: [&str; N_PARAMS] = [
    "CD_0", "CD_V", "CD_alpha", "CL_0", "CL_V", "CL_alpha", "Cm_0", "Cm_V", "Cm_alpha", "Cm_q",
    "Cm_de",
];

/// Output names in measurement order.
pub const OUTPUT_NAMES: [&str; N_OUT] =
    ["vt_mps", "alpha_rad", "theta_rad", "q_rad_s", "qdot_rad_s2", "ax_mps2", "az_mps2"];

/// Standard gravity, m/s² (Jategaonkar 2015 `G0`).
pub const G0_MPS2: f64 = 9.80665;

/// Aircraft constants of the longitudinal model, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LongitudinalConstants {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Wing reference area, m².
    pub S_m2: f64,
    /// Mean aerodynamic chord, m.
    pub cbar_m: f64,
    /// Pitch moment of inertia, kg·m².
    pub Iyy_kgm2: f64,
    /// Pitching moment per unit thrust, m (positive nose-up): `M_T = l_T·T`.
    pub thrust_arm_m: f64,
    /// Thrust inclination to the body x axis, rad (positive nose-up; book `σT`).
    pub thrust_incidence_rad: f64,
    /// Reference speed for the `V/V0` terms, m/s.
    pub v0_mps: f64,
}

/// One measured sample. `None` outputs are not used in the measurement update.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LongitudinalSample {
    /// Time, s.
    pub t_s: f64,
    /// Elevator, rad (input).
    pub de_rad: f64,
    /// Total thrust, N (input).
    pub thrust_n: f64,
    /// Air density, kg/m³ (input).
    pub rho_kgpm3: f64,
    /// Measured outputs `(V m/s, α rad, θ rad, q rad/s, q̇ rad/s², ax m/s², az m/s²)`.
    pub y: [Option<f64>; N_OUT],
}

/// Configuration of [`LongitudinalEkf`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EkfConfig {
    /// Aircraft constants.
    pub constants: LongitudinalConstants,
    /// Prior parameter values, order of [`PARAM_NAMES`].
    pub theta0: [f64; N_PARAMS],
    /// Initial variances of the four states (units²).
    pub p0_states: [f64; N_STATES],
    /// Initial variances of the parameters.
    pub p0_params: [f64; N_PARAMS],
    /// Continuous process-noise spectral densities of the four states (units²/s).
    pub q_states: [f64; N_STATES],
    /// Process-noise spectral density of the parameters (random walk, units²/s); 0 = constant.
    pub q_params: f64,
    /// Measurement-noise variances of the seven outputs (units²).
    pub r: [f64; N_OUT],
    /// How the reported parameter covariance is formed from the filter's `P`.
    pub sigma: SigmaCorrection,
}

/// How [`Estimate::covariance`] is formed from the filter covariance `P`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SigmaCorrection {
    /// The parameter block of `P` as is (a Cramér–Rao-like bound if the model and `R` are right).
    Filter,
    /// `P` scaled by `(1 + ρ̄)/(1 − ρ̄)`, ρ̄ the mean lag-1 autocorrelation of the innovations
    /// (clamped to [0, 0.95]): the AR(1) effective-sample-size correction for coloured
    /// residuals (Bayley & Hammersley 1946; cf. Morelli & Klein's coloured-residual correction,
    /// Klein & Morelli 2006 ch. 5–6). On real data the filter `P` alone is overconfident.
    ColouredResiduals,
}

/// The augmented-state EKF. No allocation per update.
#[derive(Debug, Clone)]
pub struct LongitudinalEkf {
    cfg: EkfConfig,
    x: SVector<f64, N_AUG>,
    p: SMatrix<f64, N_AUG, N_AUG>,
    last: Option<LongitudinalSample>,
    est: Estimate<N_PARAMS>,
    innovations: [f64; N_OUT],
    /// Σe², Σe_k e_{k−1} of the innovations per output, for the coloured-residual factor.
    innov_s0: [f64; N_OUT],
    innov_s1: [f64; N_OUT],
    innov_prev: [Option<f64>; N_OUT],
}

type Aug = SVector<f64, N_AUG>;

struct ParamPartials {
    f: [[f64; N_PARAMS]; N_STATES],
    ax: [f64; N_PARAMS],
    az: [f64; N_PARAMS],
}

fn check_positive(field: &'static str, v: f64) -> Result<(), EstimatorError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(EstimatorError::InvalidConfig { field, value: v, reason: "must be finite and > 0" })
    }
}

fn check_nonneg(field: &'static str, v: f64) -> Result<(), EstimatorError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(EstimatorError::InvalidConfig { field, value: v, reason: "must be finite and ≥ 0" })
    }
}

impl LongitudinalEkf {
    /// A new filter. It initialises its states from the first sample's measured `V, α, θ, q`.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] for non-positive constants, variances or densities.
    pub fn new(cfg: EkfConfig) -> Result<Self, EstimatorError> {
        let c = &cfg.constants;
        check_positive("mass_kg", c.mass_kg)?;
        check_positive("S_m2", c.S_m2)?;
        check_positive("cbar_m", c.cbar_m)?;
        check_positive("Iyy_kgm2", c.Iyy_kgm2)?;
        check_positive("v0_mps", c.v0_mps)?;
        if !c.thrust_arm_m.is_finite() || !c.thrust_incidence_rad.is_finite() {
            return Err(EstimatorError::InvalidConfig {
                field: "thrust_arm_m/thrust_incidence_rad",
                value: c.thrust_arm_m + c.thrust_incidence_rad,
                reason: "must be finite",
            });
        }
        for v in cfg.p0_states.iter().chain(cfg.p0_params.iter()) {
            check_positive("p0", *v)?;
        }
        for v in cfg.r.iter() {
            check_positive("r", *v)?;
        }
        for v in cfg.q_states.iter() {
            check_nonneg("q_states", *v)?;
        }
        check_nonneg("q_params", cfg.q_params)?;
        if let Some(v) = cfg.theta0.iter().find(|v| !v.is_finite()) {
            return Err(EstimatorError::InvalidConfig {
                field: "theta0",
                value: *v,
                reason: "must be finite",
            });
        }
        let mut x = Aug::zeros();
        let mut p = SMatrix::<f64, N_AUG, N_AUG>::zeros();
        for i in 0..N_STATES {
            p[(i, i)] = cfg.p0_states[i];
        }
        for j in 0..N_PARAMS {
            x[N_STATES + j] = cfg.theta0[j];
            p[(N_STATES + j, N_STATES + j)] = cfg.p0_params[j];
        }
        let mut est = Estimate::new(0.0, SVector::from(cfg.theta0));
        est.covariance = Some(p.fixed_view::<N_PARAMS, N_PARAMS>(N_STATES, N_STATES).into_owned());
        Ok(Self {
            cfg,
            x,
            p,
            last: None,
            est,
            innovations: [0.0; N_OUT],
            innov_s0: [0.0; N_OUT],
            innov_s1: [0.0; N_OUT],
            innov_prev: [None; N_OUT],
        })
    }

    /// The coloured-residual variance factor `(1 + ρ̄)/(1 − ρ̄)` (1 until innovations exist).
    pub fn coloured_residual_factor(&self) -> f64 {
        let mut sum = 0.0;
        let mut n = 0;
        for i in 0..N_OUT {
            if self.innov_s0[i] > 0.0 {
                sum += (self.innov_s1[i] / self.innov_s0[i]).clamp(0.0, 0.95);
                n += 1;
            }
        }
        if n == 0 {
            return 1.0;
        }
        let rho = sum / n as f64;
        (1.0 + rho) / (1.0 - rho)
    }

    /// The parameter block of the filter covariance `P`, uncorrected.
    pub fn filter_covariance(&self) -> SMatrix<f64, N_PARAMS, N_PARAMS> {
        self.p.fixed_view::<N_PARAMS, N_PARAMS>(N_STATES, N_STATES).into_owned()
    }

    /// Current state estimate `(V m/s, α rad, θ rad, q rad/s)`.
    pub fn states(&self) -> [f64; N_STATES] {
        [self.x[0], self.x[1], self.x[2], self.x[3]]
    }

    /// Innovations (measured − predicted) of the last update, order of [`OUTPUT_NAMES`]; 0 for
    /// outputs not measured.
    pub fn innovations(&self) -> [f64; N_OUT] {
        self.innovations
    }

    /// State derivative `f(x, u)` of the augmented state (parameters constant).
    fn f(&self, x: &Aug, u: &LongitudinalSample) -> Aug {
        let c = &self.cfg.constants;
        let (v, al, th, q) = (x[0], x[1], x[2], x[3]);
        let (cd, cl, cm) = self.coefficients(x, u.de_rad);
        let qbar = 0.5 * u.rho_kgpm3 * v * v;
        let t = u.thrust_n;
        let m = c.mass_kg;
        let mut d = Aug::zeros();
        d[0] = -qbar * c.S_m2 * cd / m
            + t * libm::cos(al + c.thrust_incidence_rad) / m
            + G0_MPS2 * libm::sin(al - th);
        d[1] = -qbar * c.S_m2 * cl / (m * v) - t * libm::sin(al + c.thrust_incidence_rad) / (m * v)
            + q
            + G0_MPS2 * libm::cos(al - th) / v;
        d[2] = q;
        d[3] = qbar * c.S_m2 * c.cbar_m * cm / c.Iyy_kgm2 + c.thrust_arm_m * t / c.Iyy_kgm2;
        d
    }

    fn coefficients(&self, x: &Aug, de: f64) -> (f64, f64, f64) {
        let c = &self.cfg.constants;
        let (v, al, q) = (x[0], x[1], x[3]);
        let th = |j: usize| x[N_STATES + j];
        let vr = v / c.v0_mps;
        let qhat = q * c.cbar_m / (2.0 * v);
        let cd = th(0) + th(1) * vr + th(2) * al;
        let cl = th(3) + th(4) * vr + th(5) * al;
        let cm = th(6) + th(7) * vr + th(8) * al + th(9) * qhat + th(10) * de;
        (cd, cl, cm)
    }

    /// Observation `h(x, u)`.
    fn h(&self, x: &Aug, u: &LongitudinalSample) -> SVector<f64, N_OUT> {
        let c = &self.cfg.constants;
        let (v, al) = (x[0], x[1]);
        let (cd, cl, _) = self.coefficients(x, u.de_rad);
        let qbar = 0.5 * u.rho_kgpm3 * v * v;
        let (sa, ca) = (libm::sin(al), libm::cos(al));
        let cx = cl * sa - cd * ca;
        let cz = -cl * ca - cd * sa;
        let m = c.mass_kg;
        let t = u.thrust_n;
        let xd = self.f(x, u);
        SVector::<f64, N_OUT>::from([
            v,
            al,
            x[2],
            x[3],
            xd[3],
            (qbar * c.S_m2 * cx + t * libm::cos(c.thrust_incidence_rad)) / m,
            (qbar * c.S_m2 * cz - t * libm::sin(c.thrust_incidence_rad)) / m,
        ])
    }

    /// Exact partial derivatives of `f` (rows V̇, α̇, θ̇, q̇) and of the `ax`, `az` outputs with
    /// respect to the eleven parameters (the model is linear in them).
    fn param_partials(&self, x: &Aug, de: f64, rho: f64) -> ParamPartials {
        let c = &self.cfg.constants;
        let (v, al, q) = (x[0], x[1], x[3]);
        let k = 0.5 * rho * v * v * c.S_m2 / c.mass_kg;
        let reg = [1.0, v / c.v0_mps, al];
        let kq = 0.5 * rho * v * v * c.S_m2 * c.cbar_m / c.Iyy_kgm2;
        let qhat = q * c.cbar_m / (2.0 * v);
        let (sa, ca) = (libm::sin(al), libm::cos(al));
        let mut g = ParamPartials {
            f: [[0.0; N_PARAMS]; N_STATES],
            ax: [0.0; N_PARAMS],
            az: [0.0; N_PARAMS],
        };
        for (i, r) in reg.iter().enumerate() {
            g.f[0][i] = -k * r;
            g.f[1][3 + i] = -k / v * r;
            g.ax[i] = -k * ca * r;
            g.ax[3 + i] = k * sa * r;
            g.az[i] = -k * sa * r;
            g.az[3 + i] = -k * ca * r;
        }
        for (i, r) in [1.0, v / c.v0_mps, al, qhat, de].iter().enumerate() {
            g.f[3][6 + i] = kq * r;
        }
        g
    }

    fn step(x: &Aug) -> Aug {
        x.map(|v| 1e-6 * v.abs().max(1e-2))
    }

    /// RK4 over one sample interval with the inputs interpolated linearly between the two
    /// samples (as Jategaonkar's `ruku4_aug.m`): start, midpoint and end values.
    fn rk4(&self, x: &Aug, u0: &LongitudinalSample, u1: &LongitudinalSample, dt: f64) -> Aug {
        let um = LongitudinalSample {
            de_rad: 0.5 * (u0.de_rad + u1.de_rad),
            thrust_n: 0.5 * (u0.thrust_n + u1.thrust_n),
            rho_kgpm3: 0.5 * (u0.rho_kgpm3 + u1.rho_kgpm3),
            ..*u0
        };
        let k1 = self.f(x, u0);
        let k2 = self.f(&(x + k1 * (0.5 * dt)), &um);
        let k3 = self.f(&(x + k2 * (0.5 * dt)), &um);
        let k4 = self.f(&(x + k3 * dt), u1);
        x + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0)
    }

    fn predict(
        &self,
        u: &LongitudinalSample,
        u_next: &LongitudinalSample,
        dt: f64,
    ) -> (Aug, SMatrix<f64, N_AUG, N_AUG>) {
        let x = &self.x;
        let h = Self::step(x);
        // A = ∂f/∂x has non-zero rows only for the N_STATES dynamic states, so
        // Φ = I + A dt + (A dt)²/2 = [[Φ_top], [0 I]] and only Φ_top (4 × 15) is formed:
        // (A dt)² top rows = A_top dt · (A dt)[:, :] = A11 dt · A_top dt.
        let mut a_top = SMatrix::<f64, N_STATES, N_AUG>::zeros();
        for j in 0..N_STATES {
            let mut xp = *x;
            let mut xm = *x;
            xp[j] += h[j];
            xm[j] -= h[j];
            let d = (self.f(&xp, u) - self.f(&xm, u)) / (2.0 * h[j]);
            for i in 0..N_STATES {
                a_top[(i, j)] = d[i] * dt;
            }
        }
        // The parameters enter f linearly: their columns are the regressors (exact).
        let g = self.param_partials(x, u.de_rad, u.rho_kgpm3);
        for j in 0..N_PARAMS {
            for i in 0..N_STATES {
                a_top[(i, N_STATES + j)] = g.f[i][j] * dt;
            }
        }
        let a11 = a_top.fixed_columns::<N_STATES>(0).into_owned();
        let mut phi_top = a_top + a11 * a_top * 0.5;
        for i in 0..N_STATES {
            phi_top[(i, i)] += 1.0;
        }
        // P ← Φ P Φᵀ using the block structure: first the top rows of Φ P, then the first
        // columns of (Φ P) Φᵀ; all other entries are unchanged.
        let mut p = self.p;
        let top = phi_top * self.p;
        p.fixed_rows_mut::<N_STATES>(0).copy_from(&top);
        let left = p * phi_top.transpose();
        p.fixed_columns_mut::<N_STATES>(0).copy_from(&left);
        for i in 0..N_STATES {
            p[(i, i)] += self.cfg.q_states[i] * dt;
        }
        for j in N_STATES..N_AUG {
            p[(j, j)] += self.cfg.q_params * dt;
        }
        (self.rk4(x, u, u_next, dt), p)
    }

    fn check_input(s: &LongitudinalSample) -> Result<(), EstimatorError> {
        let t_s = s.t_s;
        for (field, v) in [
            ("t_s", s.t_s),
            ("de_rad", s.de_rad),
            ("thrust_n", s.thrust_n),
            ("rho_kgpm3", s.rho_kgpm3),
        ] {
            if !v.is_finite() {
                return Err(EstimatorError::NonFiniteInput { field, value: v, t_s });
            }
        }
        for (i, y) in s.y.iter().enumerate() {
            if let Some(v) = y
                && !v.is_finite()
            {
                return Err(EstimatorError::NonFiniteInput {
                    field: OUTPUT_NAMES[i],
                    value: *v,
                    t_s,
                });
            }
        }
        Ok(())
    }

    fn initialise(&mut self, s: &LongitudinalSample) -> Result<(), EstimatorError> {
        let mut x0 = [0.0; N_STATES];
        for ((x, y), field) in x0.iter_mut().zip(s.y.iter()).zip(OUTPUT_NAMES.iter()) {
            *x = y.ok_or(EstimatorError::NonFiniteInput { field, value: f64::NAN, t_s: s.t_s })?;
        }
        if x0[0] <= 0.0 {
            return Err(EstimatorError::NonFiniteInput {
                field: "vt_mps",
                value: x0[0],
                t_s: s.t_s,
            });
        }
        for (i, v) in x0.iter().enumerate() {
            self.x[i] = *v;
        }
        Ok(())
    }
}

impl ParametricEstimator<N_PARAMS> for LongitudinalEkf {
    type Sample = LongitudinalSample;

    fn param_names(&self) -> [&'static str; N_PARAMS] {
        PARAM_NAMES
    }

    fn update(&mut self, s: &LongitudinalSample) -> Result<&Estimate<N_PARAMS>, EstimatorError> {
        Self::check_input(s)?;
        let Some(prev) = self.last else {
            self.initialise(s)?;
            self.last = Some(*s);
            self.est.t_s = s.t_s;
            return Ok(&self.est);
        };
        let dt = s.t_s - prev.t_s;
        if dt.is_nan() || dt <= 0.0 {
            return Err(EstimatorError::NonFiniteInput { field: "dt_s", value: dt, t_s: s.t_s });
        }
        // Inputs interpolated linearly over the interval (RK4 in `predict`).
        let (mut x, mut p) = self.predict(&prev, s, dt);
        // Measurement update, component by component, linearised at the predicted state.
        let hx = self.h(&x, s);
        let step = Self::step(&x);
        let mut hjac = SMatrix::<f64, N_OUT, N_AUG>::zeros();
        for j in 0..N_STATES {
            let mut xp = x;
            let mut xm = x;
            xp[j] += step[j];
            xm[j] -= step[j];
            let d = (self.h(&xp, s) - self.h(&xm, s)) / (2.0 * step[j]);
            hjac.set_column(j, &d);
        }
        let g = self.param_partials(&x, s.de_rad, s.rho_kgpm3);
        for j in 0..N_PARAMS {
            hjac[(4, N_STATES + j)] = g.f[3][j];
            hjac[(5, N_STATES + j)] = g.ax[j];
            hjac[(6, N_STATES + j)] = g.az[j];
        }
        let mut innov = [0.0; N_OUT];
        let x_lin = x;
        for i in 0..N_OUT {
            let Some(yi) = s.y[i] else { continue };
            let hrow = hjac.row(i).transpose();
            // Linearised prediction of output i at the current (partly updated) state.
            let yhat = hx[i] + hrow.dot(&(x - x_lin));
            let ph = p * hrow;
            let sv = hrow.dot(&ph) + self.cfg.r[i];
            if !(sv.is_finite() && sv > 0.0) {
                return Err(EstimatorError::Numerical {
                    what: "EKF innovation variance",
                    t_s: s.t_s,
                });
            }
            let k = ph / sv;
            let e = yi - yhat;
            innov[i] = e;
            x += k * e;
            p -= k * ph.transpose();
        }
        p = (p + p.transpose()) * 0.5;
        if !x.iter().chain(p.iter()).all(|v| v.is_finite()) || x[0] <= 0.0 {
            return Err(EstimatorError::Numerical { what: "EKF update diverged", t_s: s.t_s });
        }
        self.x = x;
        self.p = p;
        self.innovations = innov;
        for (i, e) in innov.iter().copied().enumerate() {
            if s.y[i].is_some() {
                self.innov_s0[i] += e * e;
                if let Some(prev) = self.innov_prev[i] {
                    self.innov_s1[i] += e * prev;
                }
                self.innov_prev[i] = Some(e);
            } else {
                self.innov_prev[i] = None;
            }
        }
        self.last = Some(*s);
        self.est.t_s = s.t_s;
        self.est.theta = x.fixed_rows::<N_PARAMS>(N_STATES).into_owned();
        let factor = match self.cfg.sigma {
            SigmaCorrection::Filter => 1.0,
            SigmaCorrection::ColouredResiduals => self.coloured_residual_factor(),
        };
        self.est.covariance = Some(self.filter_covariance() * factor);
        Ok(&self.est)
    }

    fn estimate(&self) -> &Estimate<N_PARAMS> {
        &self.est
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact parameter partials agree with central differences of `f` and `h`.
    #[test]
    fn analytic_param_partials_match_finite_differences() {
        let cfg = EkfConfig {
            constants: LongitudinalConstants {
                mass_kg: 7472.0,
                S_m2: 30.1,
                cbar_m: 2.43,
                Iyy_kgm2: 91_400.0,
                thrust_arm_m: -0.64,
                thrust_incidence_rad: 0.0524,
                v0_mps: 104.67,
            },
            theta0: [0.1, -0.05, 0.23, -0.2, 0.36, 3.2, 0.13, -0.01, -1.0, -27.0, -1.4],
            p0_states: [1.0; 4],
            p0_params: [1.0; N_PARAMS],
            q_states: [0.0; 4],
            q_params: 0.0,
            r: [1.0; N_OUT],
            sigma: SigmaCorrection::Filter,
        };
        let ekf = LongitudinalEkf::new(cfg).unwrap();
        let mut x = ekf.x;
        x[0] = 107.0;
        x[1] = 0.11;
        x[2] = 0.09;
        x[3] = 0.02;
        let u = LongitudinalSample {
            t_s: 0.0,
            de_rad: -0.01,
            thrust_n: 11_600.0,
            rho_kgpm3: 0.792,
            y: [None; N_OUT],
        };
        let g = ekf.param_partials(&x, u.de_rad, u.rho_kgpm3);
        for j in 0..N_PARAMS {
            let d = 1e-6;
            let mut xp = x;
            let mut xm = x;
            xp[N_STATES + j] += d;
            xm[N_STATES + j] -= d;
            let df = (ekf.f(&xp, &u) - ekf.f(&xm, &u)) / (2.0 * d);
            let dh = (ekf.h(&xp, &u) - ekf.h(&xm, &u)) / (2.0 * d);
            for i in 0..N_STATES {
                assert!((df[i] - g.f[i][j]).abs() < 1e-6 * (1.0 + g.f[i][j].abs()), "f{i} p{j}");
            }
            assert!((dh[4] - g.f[3][j]).abs() < 1e-6 * (1.0 + g.f[3][j].abs()));
            assert!((dh[5] - g.ax[j]).abs() < 1e-6 * (1.0 + g.ax[j].abs()), "ax p{j}");
            assert!((dh[6] - g.az[j]).abs() < 1e-6 * (1.0 + g.az[j].abs()), "az p{j}");
        }
    }
}
