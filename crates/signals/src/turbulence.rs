//! Continuous Dryden turbulence, MIL-F-8785C form (§3.7.3.2, also MIL-HDBK-1797 appendix),
//! seeded and reproducible: linear gust velocities u_g, v_g, w_g in body axes (ft/s).
//!
//! # Spectra (one-sided, in temporal angular frequency ω, rad/s)
//! With airspeed `V` (ft/s), intensities σ (ft/s) and scale lengths L (ft), and the one-sided
//! convention `∫₀^∞ Φ(ω) dω = σ²`:
//!
//! ```text
//!   Φ_u(ω) = σ_u² · (2 L_u / (π V)) · 1 / (1 + (L_u ω / V)²)
//!   Φ_v(ω) = σ_v² · (L_v / (π V)) · (1 + 3 (L_v ω / V)²) / (1 + (L_v ω / V)²)²     (same for w)
//! ```
//!
//! (MIL-F-8785C eqs. for the Dryden form, spatial frequency Ω = ω / V; the temporal PSD is the
//! spatial one divided by V.) [`crate::turbulence::dryden_psd_one_sided`] evaluates them.
//!
//! # Shaping filters and their discretisation
//! Each component is the output of a shaping filter driven by unit-intensity continuous white
//! noise η (E[η(t)η(s)] = δ(t − s)), for which `Φ(ω) = |H(iω)|² / π`; with `a = V / L`:
//!
//! ```text
//!   H_u(s) = σ_u √(2a) / (s + a)
//!   H_v(s) = σ_v √a (√3 s + a) / (s + a)²            (same for w)
//! ```
//!
//! realised in controllable canonical form and discretised EXACTLY for the sample time `Ts`
//! with Van Loan's method (C. F. Van Loan, "Computing integrals involving the matrix
//! exponential", IEEE TAC 23(3), 1978): `x_{k+1} = Φ x_k + w_k`, `Φ = e^{A Ts}`,
//! `w_k ~ N(0, Q_d)`, `Q_d = ∫₀^Ts e^{Aτ} B Bᵀ e^{Aᵀτ} dτ`. The samples `y_k = C x_k` therefore
//! have exactly the autocovariance of continuous Dryden turbulence at the sample instants (no
//! Euler or Tustin approximation error, for any `Ts`); their spectrum is the Dryden PSD plus the
//! usual aliasing, which is below 0.1 % of Φ for ω < Ts⁻¹/5. The initial state is drawn from the
//! stationary distribution, so the sequence is stationary from `t = 0` (no start-up transient).
//!
//! # Assumptions (WARNING)
//! Frozen turbulence at the constant airspeed `V` and altitude given at construction (the trim
//! condition): the filters are not rescheduled when the aircraft speeds up or climbs. Angular
//! gust rates p_g, q_g, r_g are not modelled.

use nalgebra::{Cholesky, SMatrix, SVector, Vector3};
use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;
use rand_pcg::Pcg64Mcg;
use serde::Deserialize;

use crate::WindField;
use crate::error::{SignalError, non_negative, positive};

/// Knots to ft/s (1 kt = 1852 m / 3600 s, 1 ft = 0.3048 m; re-exported from
/// [`aeroident_physics::units`]).
pub use aeroident_physics::units::FPS_PER_KT;

/// Dryden medium/high-altitude scale length (ft) for all three components, MIL-F-8785C
/// §3.7.3.2 (above 2000 ft).
pub const L_HIGH_ALTITUDE_FT: f64 = 1750.0;

/// Turbulence severity, mapped as in MIL-F-8785C §3.7.3.2 and figure 7: low altitude by the
/// wind speed at 20 ft (W20: light 15 kt, moderate 30 kt, severe 45 kt), medium/high altitude by
/// the probability of exceeding the intensity (light 10⁻², moderate 10⁻³, severe 10⁻⁵).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TurbulenceSeverity {
    /// W20 = 15 kt; probability of exceedance 10⁻².
    Light,
    /// W20 = 30 kt; probability of exceedance 10⁻³.
    Moderate,
    /// W20 = 45 kt; probability of exceedance 10⁻⁵.
    Severe,
}

impl TurbulenceSeverity {
    /// Wind speed at 20 ft, W20 (ft/s), MIL-F-8785C §3.7.3.4.
    pub fn w20_fps(self) -> f64 {
        FPS_PER_KT
            * match self {
                TurbulenceSeverity::Light => 15.0,
                TurbulenceSeverity::Moderate => 30.0,
                TurbulenceSeverity::Severe => 45.0,
            }
    }

    fn table_row(self) -> &'static [f64; 12] {
        match self {
            TurbulenceSeverity::Light => &SIGMA_TABLE_FPS[0],
            TurbulenceSeverity::Moderate => &SIGMA_TABLE_FPS[1],
            TurbulenceSeverity::Severe => &SIGMA_TABLE_FPS[2],
        }
    }
}

/// Altitude breakpoints (ft) of the medium/high-altitude intensity table, MIL-F-8785C figure 7.
const SIGMA_TABLE_ALT_FT: [f64; 12] = [
    500.0, 1750.0, 3750.0, 7500.0, 15000.0, 25000.0, 35000.0, 45000.0, 55000.0, 65000.0, 75000.0,
    80000.0,
];

/// RMS turbulence intensity σ (ft/s) versus altitude, MIL-F-8785C figure 7, for probability of
/// exceedance 10⁻² (light), 10⁻³ (moderate) and 10⁻⁵ (severe). Digitised values as used by the
/// MATLAB Aerospace Blockset Dryden blocks and many open implementations.
const SIGMA_TABLE_FPS: [[f64; 12]; 3] = [
    [6.6, 6.9, 7.4, 6.7, 4.6, 2.7, 0.4, 0.0, 0.0, 0.0, 0.0, 0.0],
    [8.6, 9.6, 10.6, 10.1, 8.0, 6.6, 5.0, 4.2, 2.7, 0.0, 0.0, 0.0],
    [15.6, 17.6, 23.0, 23.6, 22.1, 20.0, 16.0, 15.1, 12.1, 7.9, 6.2, 5.1],
];

/// Intensities (ft/s) and scale lengths (ft) of the three Dryden components.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DrydenParameters {
    /// σ_u, longitudinal intensity (ft/s), ≥ 0.
    pub sigma_u_fps: f64,
    /// σ_v, lateral intensity (ft/s), ≥ 0.
    pub sigma_v_fps: f64,
    /// σ_w, vertical intensity (ft/s), ≥ 0.
    pub sigma_w_fps: f64,
    /// L_u, longitudinal scale length (ft), > 0.
    pub L_u_ft: f64,
    /// L_v, lateral scale length (ft), > 0.
    pub L_v_ft: f64,
    /// L_w, vertical scale length (ft), > 0.
    pub L_w_ft: f64,
}

impl DrydenParameters {
    /// Checks every field: intensities finite and ≥ 0, scale lengths finite and > 0.
    ///
    /// # Errors
    /// [`SignalError::InvalidParameter`] naming the first bad field and its value.
    pub fn validate(&self) -> Result<(), SignalError> {
        non_negative("sigma_u_fps", self.sigma_u_fps)?;
        non_negative("sigma_v_fps", self.sigma_v_fps)?;
        non_negative("sigma_w_fps", self.sigma_w_fps)?;
        positive("L_u_ft", self.L_u_ft)?;
        positive("L_v_ft", self.L_v_ft)?;
        positive("L_w_ft", self.L_w_ft)?;
        Ok(())
    }

    /// MIL-F-8785C §3.7.3.2/§3.7.3.4 parameters at height above ground `h_ft` for a severity:
    ///
    /// * low altitude, 10 ft ≤ h ≤ 1000 ft: `L_w = h`, `L_u = L_v = h / (0.177 + 0.000823 h)^1.2`,
    ///   `σ_w = 0.1·W20`, `σ_u = σ_v = σ_w / (0.177 + 0.000823 h)^0.4` (below 10 ft the 10 ft
    ///   values are used: the formulas are not defined at the ground);
    /// * medium/high altitude, h ≥ 2000 ft: `L_u = L_v = L_w = 1750 ft`, `σ_u = σ_v = σ_w` from
    ///   figure 7 (linear in altitude between its breakpoints, held beyond 80,000 ft);
    /// * 1000–2000 ft: linear interpolation in altitude between the two models at 1000 and
    ///   2000 ft (the figures' transition, as in the MATLAB Aerospace Blockset).
    ///
    /// Example: 20,000 ft moderate → σ = 7.3 ft/s, L = 1750 ft (the thesis's trim altitude).
    ///
    /// # Errors
    /// [`SignalError::InvalidParameter`] if `h_ft` is negative or not finite.
    pub fn mil_f_8785c(h_ft: f64, severity: TurbulenceSeverity) -> Result<Self, SignalError> {
        let h = non_negative("altitude_ft", h_ft)?;
        Ok(if h <= 1000.0 {
            Self::low_altitude(h.max(10.0), severity)
        } else if h >= 2000.0 {
            Self::high_altitude(h, severity)
        } else {
            let lo = Self::low_altitude(1000.0, severity);
            let hi = Self::high_altitude(2000.0, severity);
            let f = (h - 1000.0) / 1000.0;
            let mix = |a: f64, b: f64| a + (b - a) * f;
            Self {
                sigma_u_fps: mix(lo.sigma_u_fps, hi.sigma_u_fps),
                sigma_v_fps: mix(lo.sigma_v_fps, hi.sigma_v_fps),
                sigma_w_fps: mix(lo.sigma_w_fps, hi.sigma_w_fps),
                L_u_ft: mix(lo.L_u_ft, hi.L_u_ft),
                L_v_ft: mix(lo.L_v_ft, hi.L_v_ft),
                L_w_ft: mix(lo.L_w_ft, hi.L_w_ft),
            }
        })
    }

    fn low_altitude(h: f64, severity: TurbulenceSeverity) -> Self {
        let k = 0.177 + 0.000823 * h;
        let sigma_w = 0.1 * severity.w20_fps();
        let sigma_uv = sigma_w / k.powf(0.4);
        let L_uv = h / k.powf(1.2);
        Self {
            sigma_u_fps: sigma_uv,
            sigma_v_fps: sigma_uv,
            sigma_w_fps: sigma_w,
            L_u_ft: L_uv,
            L_v_ft: L_uv,
            L_w_ft: h,
        }
    }

    fn high_altitude(h: f64, severity: TurbulenceSeverity) -> Self {
        let row = severity.table_row();
        let x = &SIGMA_TABLE_ALT_FT;
        let sigma = if h <= x[0] {
            row[0]
        } else if h >= x[11] {
            row[11]
        } else {
            let i = x.partition_point(|&b| b <= h) - 1;
            row[i] + (row[i + 1] - row[i]) * (h - x[i]) / (x[i + 1] - x[i])
        };
        Self {
            sigma_u_fps: sigma,
            sigma_v_fps: sigma,
            sigma_w_fps: sigma,
            L_u_ft: L_HIGH_ALTITUDE_FT,
            L_v_ft: L_HIGH_ALTITUDE_FT,
            L_w_ft: L_HIGH_ALTITUDE_FT,
        }
    }
}

/// A Dryden component: longitudinal (first-order form) or lateral/vertical (second-order form).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DrydenComponent {
    /// u_g, `Φ_u` form.
    U,
    /// v_g, `Φ_v` form.
    V,
    /// w_g, same form as v.
    W,
}

/// The analytic one-sided Dryden PSD `Φ(ω)` ((ft/s)² per rad/s) of a component at angular
/// frequency `omega_rad_s`, for airspeed `vt_fps`; see the module docs for the formulas
/// (MIL-F-8785C, temporal form).
pub fn dryden_psd_one_sided(
    params: &DrydenParameters,
    component: DrydenComponent,
    vt_fps: f64,
    omega_rad_s: f64,
) -> f64 {
    let pi = core::f64::consts::PI;
    match component {
        DrydenComponent::U => {
            let (s, L) = (params.sigma_u_fps, params.L_u_ft);
            let x = L * omega_rad_s / vt_fps;
            s * s * 2.0 * L / (pi * vt_fps) / (1.0 + x * x)
        }
        DrydenComponent::V | DrydenComponent::W => {
            let (s, L) = if component == DrydenComponent::V {
                (params.sigma_v_fps, params.L_v_ft)
            } else {
                (params.sigma_w_fps, params.L_w_ft)
            };
            let x2 = (L * omega_rad_s / vt_fps).powi(2);
            s * s * L / (pi * vt_fps) * (1.0 + 3.0 * x2) / ((1.0 + x2) * (1.0 + x2))
        }
    }
}

/// The continuous shaping filter of a component (module doc), as plain matrices for other
/// crates' use (e.g. the turbulent Cramér–Rao bound): `(a, b, c)` with `ẋ = a x + b η`,
/// `g = c·x` (ft/s), driven by unit-intensity white noise `η`, so that
/// `Φ(ω) = |c (iω − a)⁻¹ b|² / π` is [`dryden_psd_one_sided`]. The realisation the generator
/// discretises: `H_u = σ_u √(2a) / (s + a)` (1 state) and `H_v = σ_v √a (√3 s + a) / (s + a)²`
/// (2 states, controllable canonical form), `a = V / L`.
pub fn dryden_shaping_filter(
    params: &DrydenParameters,
    component: DrydenComponent,
    vt_fps: f64,
) -> (nalgebra::DMatrix<f64>, nalgebra::DVector<f64>, nalgebra::DVector<f64>) {
    use nalgebra::{DMatrix, DVector};
    match component {
        DrydenComponent::U => {
            let a = vt_fps / params.L_u_ft;
            (
                DMatrix::from_element(1, 1, -a),
                DVector::from_element(1, 1.0),
                DVector::from_element(1, params.sigma_u_fps * (2.0 * a).sqrt()),
            )
        }
        DrydenComponent::V | DrydenComponent::W => {
            let (sigma, L) = if component == DrydenComponent::V {
                (params.sigma_v_fps, params.L_v_ft)
            } else {
                (params.sigma_w_fps, params.L_w_ft)
            };
            let a = vt_fps / L;
            (
                DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -a * a, -2.0 * a]),
                DVector::from_column_slice(&[0.0, 1.0]),
                DVector::from_column_slice(&[sigma * a.sqrt() * a, sigma * a.sqrt() * 3f64.sqrt()]),
            )
        }
    }
}

/// One exactly discretised shaping filter with `N` states.
#[derive(Debug, Clone, PartialEq)]
struct DiscreteShapingFilter<const N: usize> {
    phi: SMatrix<f64, N, N>,
    /// Lower Cholesky factor of Q_d.
    q_chol: SMatrix<f64, N, N>,
    c: SVector<f64, N>,
    x: SVector<f64, N>,
}

impl<const N: usize> DiscreteShapingFilter<N> {
    /// Van Loan discretisation of `ẋ = A x + B η, y = C x` for sample time `dt_s`, with the
    /// initial state drawn from the stationary covariance `p_inf`.
    fn new(
        a: SMatrix<f64, N, N>,
        b: SVector<f64, N>,
        c: SVector<f64, N>,
        p_inf: SMatrix<f64, N, N>,
        dt_s: f64,
        rng: &mut Pcg64Mcg,
    ) -> Result<Self, SignalError> {
        let (phi, qd) = van_loan(&a, &b, dt_s);
        let q_chol = cholesky_or_err(qd, dt_s)?;
        let p_chol = cholesky_or_err(p_inf, dt_s)?;
        let x = p_chol * SVector::<f64, N>::from_fn(|_, _| rng.sample(StandardNormal));
        Ok(Self { phi, q_chol, c, x })
    }

    fn output(&self) -> f64 {
        self.c.dot(&self.x)
    }

    fn advance(&mut self, rng: &mut Pcg64Mcg) {
        let xi = SVector::<f64, N>::from_fn(|_, _| rng.sample(StandardNormal));
        self.x = self.phi * self.x + self.q_chol * xi;
    }
}

/// Lower Cholesky factor of a covariance; fails (naming the sample time) only when the
/// sample time is so small or large relative to L/V that the covariance is numerically singular.
fn cholesky_or_err<const N: usize>(
    m: SMatrix<f64, N, N>,
    dt_s: f64,
) -> Result<SMatrix<f64, N, N>, SignalError> {
    let sym = (m + m.transpose()) * 0.5;
    Cholesky::new(sym).map(|c| c.l()).ok_or(SignalError::InvalidParameter {
        field: "sample_time_s",
        value: dt_s,
        reason: "turbulence covariance is numerically singular for this sample time, \
                     airspeed and scale length",
    })
}

/// Van Loan (1978): `Φ = e^{A dt}`, `Q_d = ∫₀^dt e^{Aτ} B Bᵀ e^{Aᵀτ} dτ` from the exponential of
/// the block matrix `[[−A, BBᵀ], [0, Aᵀ]]·dt` (returns `(Φ, Q_d)`).
fn van_loan<const N: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SVector<f64, N>,
    dt_s: f64,
) -> (SMatrix<f64, N, N>, SMatrix<f64, N, N>) {
    // Built as a dynamic matrix (2N × 2N) because const-generic 2N is not expressible.
    let n = N;
    let mut m = nalgebra::DMatrix::<f64>::zeros(2 * n, 2 * n);
    let q = b * b.transpose();
    for i in 0..n {
        for j in 0..n {
            m[(i, j)] = -a[(i, j)] * dt_s;
            m[(i, n + j)] = q[(i, j)] * dt_s;
            m[(n + i, n + j)] = a[(j, i)] * dt_s;
        }
    }
    let e = m.exp();
    let phi = SMatrix::<f64, N, N>::from_fn(|i, j| e[(n + j, n + i)]);
    let e12 = SMatrix::<f64, N, N>::from_fn(|i, j| e[(i, n + j)]);
    (phi, phi * e12)
}

/// Streaming Dryden generator: call [`DrydenGenerator::next_body_fps`] once per sample time.
/// Reproducible bit for bit from the seed (one `Pcg64Mcg`, standard normals drawn in the fixed
/// order u, v₁, v₂, w₁, w₂ per sample).
#[derive(Debug, Clone, PartialEq)]
pub struct DrydenGenerator {
    u: DiscreteShapingFilter<1>,
    v: DiscreteShapingFilter<2>,
    w: DiscreteShapingFilter<2>,
    rng: Pcg64Mcg,
    sample_time_s: f64,
}

impl DrydenGenerator {
    /// Generator for `params` at airspeed `vt_fps` (ft/s, > 0), sample time `sample_time_s`
    /// (s, > 0) and `seed`.
    ///
    /// # Errors
    /// [`SignalError::InvalidParameter`] naming the bad field (parameters, airspeed, sample
    /// time).
    pub fn new(
        params: &DrydenParameters,
        vt_fps: f64,
        sample_time_s: f64,
        seed: u64,
    ) -> Result<Self, SignalError> {
        params.validate()?;
        let vt = positive("vt_fps", vt_fps)?;
        let dt = positive("sample_time_s", sample_time_s)?;
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        // The continuous filters of [`dryden_shaping_filter`], discretised with their
        // stationary state covariance as the initial one.
        let filter = |component| dryden_shaping_filter(params, component, vt);
        // u: H = σ√(2a)/(s + a); stationary state variance 1/(2a).
        let au = vt / params.L_u_ft;
        let (fa, fb, fc) = filter(DrydenComponent::U);
        let u = DiscreteShapingFilter::<1>::new(
            SMatrix::<f64, 1, 1>::from_iterator(fa.iter().copied()),
            SVector::<f64, 1>::from_iterator(fb.iter().copied()),
            SVector::<f64, 1>::from_iterator(fc.iter().copied()),
            SMatrix::<f64, 1, 1>::new(0.5 / au),
            dt,
            &mut rng,
        )?;
        let second = |component, L: f64, rng: &mut Pcg64Mcg| {
            // H = σ√a (√3 s + a)/(s + a)², controllable canonical form:
            // A = [[0, 1], [−a², −2a]], B = [0, 1]ᵀ, C = σ√a [a, √3];
            // stationary covariance diag(1/(2 a0 a1), 1/(2 a1)) with a0 = a², a1 = 2a.
            let a = vt / L;
            let (a0, a1) = (a * a, 2.0 * a);
            let (fa, fb, fc) = filter(component);
            DiscreteShapingFilter::<2>::new(
                SMatrix::<f64, 2, 2>::from_iterator(fa.iter().copied()),
                SVector::<f64, 2>::from_iterator(fb.iter().copied()),
                SVector::<f64, 2>::from_iterator(fc.iter().copied()),
                SMatrix::<f64, 2, 2>::new(0.5 / (a0 * a1), 0.0, 0.0, 0.5 / a1),
                dt,
                rng,
            )
        };
        let v = second(DrydenComponent::V, params.L_v_ft, &mut rng)?;
        let w = second(DrydenComponent::W, params.L_w_ft, &mut rng)?;
        Ok(Self { u, v, w, rng, sample_time_s: dt })
    }

    /// Sample time (s).
    pub fn sample_time_s(&self) -> f64 {
        self.sample_time_s
    }

    /// The current sample `(u_g, v_g, w_g)` in body axes (ft/s), then advances one sample time.
    pub fn next_body_fps(&mut self) -> Vector3<f64> {
        let y = Vector3::new(self.u.output(), self.v.output(), self.w.output());
        self.u.advance(&mut self.rng);
        self.v.advance(&mut self.rng);
        self.w.advance(&mut self.rng);
        y
    }
}

/// Maximum number of precomputed samples (≈ 2.8 h at 100 Hz), guarding memory against a typo.
const MAX_SAMPLES: f64 = 1e7;

/// Dryden turbulence precomputed over `[0, duration_s]` at the sample time and then evaluated as
/// a [`WindField`] by LINEAR interpolation between samples (continuous forcing for the RK4
/// integrator). Before `t = 0` the first sample and after `duration_s` the last sample is held:
/// choose `duration_s` ≥ the run length. Because the field is a pure function of time, the
/// reference and the estimated aircraft can both read it.
#[derive(Debug, Clone, PartialEq)]
pub struct DrydenTurbulence {
    samples: Vec<Vector3<f64>>,
    sample_time_s: f64,
}

impl DrydenTurbulence {
    /// Generates `duration_s` (s) of turbulence; see [`DrydenGenerator::new`] for the other
    /// arguments.
    ///
    /// # Errors
    /// As [`DrydenGenerator::new`], plus `duration_s` not positive or needing more than 10⁷
    /// samples.
    pub fn generate(
        params: &DrydenParameters,
        vt_fps: f64,
        sample_time_s: f64,
        duration_s: f64,
        seed: u64,
    ) -> Result<Self, SignalError> {
        let mut g = DrydenGenerator::new(params, vt_fps, sample_time_s, seed)?;
        let duration_s = positive("duration_s", duration_s)?;
        let n = (duration_s / sample_time_s).ceil() + 1.0;
        if n > MAX_SAMPLES {
            return Err(SignalError::InvalidParameter {
                field: "duration_s",
                value: duration_s,
                reason: "needs more than 1e7 turbulence samples at this sample_time_s",
            });
        }
        let samples = (0..n as usize).map(|_| g.next_body_fps()).collect();
        Ok(Self { samples, sample_time_s })
    }

    /// The samples `(u_g, v_g, w_g)` (ft/s) at `t = k·Ts`.
    pub fn samples(&self) -> &[Vector3<f64>] {
        &self.samples
    }
}

impl WindField for DrydenTurbulence {
    fn wind_body_fps(&self, t_s: f64) -> Vector3<f64> {
        let x = t_s / self.sample_time_s;
        let last = self.samples.len() - 1;
        if x.is_nan() || x <= 0.0 {
            return self.samples[0];
        }
        if x >= last as f64 {
            return self.samples[last];
        }
        let k = x.floor() as usize;
        let f = x - k as f64;
        self.samples[k] + (self.samples[k + 1] - self.samples[k]) * f
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn shaping_filter_response_is_the_dryden_psd() {
        let p = DrydenParameters::mil_f_8785c(20000.0, TurbulenceSeverity::Moderate).unwrap();
        for comp in [DrydenComponent::U, DrydenComponent::V, DrydenComponent::W] {
            let (a, b, c) = dryden_shaping_filter(&p, comp, 675.0);
            for w in [0.01, 0.4, 3.0, 40.0] {
                // H(iω) = c (iω − a)⁻¹ b, by the complex LU of iω − a.
                let n = a.nrows();
                let m = nalgebra::DMatrix::from_fn(n, n, |i, j| {
                    nalgebra::Complex::new(-a[(i, j)], if i == j { w } else { 0.0 })
                });
                let x = m.lu().solve(&b.map(|v| nalgebra::Complex::new(v, 0.0))).unwrap();
                let h: nalgebra::Complex<f64> = x.iter().zip(c.iter()).map(|(x, c)| x * *c).sum();
                let psd = h.norm_sqr() / core::f64::consts::PI;
                let want = dryden_psd_one_sided(&p, comp, 675.0, w);
                assert!((psd / want - 1.0).abs() < 1e-10, "{comp:?} at {w}: {psd} vs {want}");
            }
        }
    }

    use super::*;
    use core::f64::consts::{PI, TAU};

    #[test]
    fn val_mil_f_8785c_parameters() {
        // Low altitude, 500 ft, moderate (W20 = 30 kt = 50.634 ft/s). Hand computation:
        // k = 0.177 + 0.000823*500 = 0.5885; sigma_w = 5.0634; sigma_u = 5.0634/k^0.4 = 6.2596;
        // L_u = 500/k^1.2 = 944.657 ft; L_w = 500 ft.
        let p = DrydenParameters::mil_f_8785c(500.0, TurbulenceSeverity::Moderate).unwrap();
        assert!((p.sigma_w_fps - 5.063_43).abs() < 1e-4, "{p:?}");
        assert!((p.sigma_u_fps - 6.259_59).abs() < 1e-4);
        assert_eq!(p.sigma_u_fps, p.sigma_v_fps);
        assert!((p.L_u_ft - 944.657).abs() < 1e-2);
        assert_eq!(p.L_w_ft, 500.0);
        // At 1000 ft k = 1: all L = 1000 ft and all sigma = 0.1 W20 (continuity point).
        let p = DrydenParameters::mil_f_8785c(1000.0, TurbulenceSeverity::Light).unwrap();
        assert!((p.L_u_ft - 1000.0).abs() < 1e-9 && (p.L_w_ft - 1000.0).abs() < 1e-9);
        assert!((p.sigma_u_fps - 0.1 * 15.0 * FPS_PER_KT).abs() < 1e-12);
        // 20,000 ft (thesis trim), figure 7 midway between 15,000 and 25,000 ft.
        let m = DrydenParameters::mil_f_8785c(20000.0, TurbulenceSeverity::Moderate).unwrap();
        assert!((m.sigma_u_fps - 7.3).abs() < 1e-12 && m.L_w_ft == 1750.0);
        let l = DrydenParameters::mil_f_8785c(20000.0, TurbulenceSeverity::Light).unwrap();
        assert!((l.sigma_w_fps - 3.65).abs() < 1e-12);
        let s = DrydenParameters::mil_f_8785c(20000.0, TurbulenceSeverity::Severe).unwrap();
        assert!((s.sigma_v_fps - 21.05).abs() < 1e-12);
        // Transition 1500 ft: halfway between the 1000 ft low model and the 2000 ft table value
        // (light: 0.1 W20 = 2.5317 ft/s and 6.9 + 0.5*250/2000 = 6.9625 ft/s).
        let t = DrydenParameters::mil_f_8785c(1500.0, TurbulenceSeverity::Light).unwrap();
        let expect = 0.5 * (0.1 * 15.0 * FPS_PER_KT + 6.9625);
        assert!((t.sigma_u_fps - expect).abs() < 1e-9);
        assert!((t.L_u_ft - 1375.0).abs() < 1e-9);
        // 1 kt = 1.68781 ft/s.
        assert!((FPS_PER_KT - 1.687_81).abs() < 1e-5);
        assert!(DrydenParameters::mil_f_8785c(-1.0, TurbulenceSeverity::Light).is_err());
    }

    #[test]
    fn analytic_van_loan_first_order_matches_closed_form() {
        // dx = -a x + eta: Phi = e^{-a dt}, Qd = (1 - e^{-2 a dt}) / (2a).
        let (a, dt) = (0.4, 0.05);
        let (phi, qd) = van_loan(&SMatrix::<f64, 1, 1>::new(-a), &SVector::<f64, 1>::new(1.0), dt);
        assert!((phi[(0, 0)] - (-a * dt).exp()).abs() < 1e-14);
        assert!((qd[(0, 0)] - (1.0 - (-2.0 * a * dt).exp()) / (2.0 * a)).abs() < 1e-14);
        // Double integrator: Phi = [[1, dt],[0, 1]], Qd = [[dt^3/3, dt^2/2],[dt^2/2, dt]].
        let (phi, qd) = van_loan(
            &SMatrix::<f64, 2, 2>::new(0.0, 1.0, 0.0, 0.0),
            &SVector::<f64, 2>::new(0.0, 1.0),
            dt,
        );
        assert!((phi - SMatrix::<f64, 2, 2>::new(1.0, dt, 0.0, 1.0)).norm() < 1e-14);
        let q = SMatrix::<f64, 2, 2>::new(dt.powi(3) / 3.0, dt * dt / 2.0, dt * dt / 2.0, dt);
        assert!((qd - q).norm() < 1e-14);
    }

    /// One-sided Welch PSD estimate ((ft/s)² per rad/s) at DFT bin `k` of segments of length
    /// `m` with a Hann window and 50 % overlap, via the Goertzel recurrence (no FFT needed for a
    /// few bins). `Φ = Ts·|X|² / (π Σw²)`, consistent with `∫₀^∞ Φ dω = σ²`.
    fn welch_bin(x: &[f64], dt: f64, m: usize, k: usize) -> f64 {
        let w: Vec<f64> = (0..m).map(|i| 0.5 * (1.0 - (TAU * i as f64 / m as f64).cos())).collect();
        let s2: f64 = w.iter().map(|v| v * v).sum();
        let coeff = 2.0 * (TAU * k as f64 / m as f64).cos();
        let (mut acc, mut segs) = (0.0, 0);
        let mut start = 0;
        while start + m <= x.len() {
            let (mut s1, mut s0) = (0.0, 0.0);
            for i in 0..m {
                let s = x[start + i] * w[i] + coeff * s1 - s0;
                s0 = s1;
                s1 = s;
            }
            let power = s1 * s1 + s0 * s0 - coeff * s1 * s0;
            acc += dt * power / (PI * s2);
            segs += 1;
            start += m / 2;
        }
        acc / segs as f64
    }

    #[test]
    fn val_dryden_psd_and_variance_match_mil_f_8785c() {
        // 20,000 ft, moderate, V = 675 ft/s (thesis trim), Ts = 0.01 s, 2^21 samples (5.8 h).
        // Welch: 16384-sample Hann segments, 50 % overlap -> 255 segments; averaging 5 adjacent
        // bins the relative standard error is about 4 %, so 15 % is a ~3.5-sigma tolerance.
        // Sample variance: relative SE = sqrt(2 L/V / T) = 1.6 %; tolerance 6 %.
        let p = DrydenParameters::mil_f_8785c(20000.0, TurbulenceSeverity::Moderate).unwrap();
        let (vt, dt) = (675.0, 0.01);
        let mut g = DrydenGenerator::new(&p, vt, dt, 20101).unwrap();
        let n = 1 << 21;
        let mut ch = [Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n)];
        for _ in 0..n {
            let y = g.next_body_fps();
            for c in 0..3 {
                ch[c].push(y[c]);
            }
        }
        let m = 16384;
        let dw = TAU / (m as f64 * dt);
        let comps = [DrydenComponent::U, DrydenComponent::V, DrydenComponent::W];
        for (c, comp) in comps.iter().enumerate() {
            let x = &ch[c];
            let mean = x.iter().sum::<f64>() / n as f64;
            let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n as f64;
            eprintln!("{comp:?} variance / sigma^2 = {:.4}", var / 7.3f64.powi(2));
            assert!((var / 7.3f64.powi(2) - 1.0).abs() < 0.06, "{comp:?} variance {var}");
            for omega in [0.15, 0.4, 1.5, 6.0, 20.0] {
                let k0 = (omega / dw).round() as usize;
                let (mut est, mut ana) = (0.0, 0.0);
                for k in k0 - 2..=k0 + 2 {
                    est += welch_bin(x, dt, m, k) / 5.0;
                    ana += dryden_psd_one_sided(&p, *comp, vt, k as f64 * dw) / 5.0;
                }
                let ratio = est / ana;
                eprintln!("{comp:?} {omega:5.2} rad/s: Welch/Dryden = {ratio:.3}");
                assert!(
                    (ratio - 1.0).abs() < 0.15,
                    "{comp:?} at {omega} rad/s: Welch {est:.4e} vs Dryden {ana:.4e}"
                );
            }
        }
    }

    #[test]
    fn analytic_dryden_psd_integrates_to_variance() {
        // Independent check of the PSD formulas: numerical integral over [0, inf) = sigma^2.
        let p = DrydenParameters {
            sigma_u_fps: 2.0,
            sigma_v_fps: 3.0,
            sigma_w_fps: 4.0,
            L_u_ft: 500.0,
            L_v_ft: 300.0,
            L_w_ft: 200.0,
        };
        for (comp, s) in
            [(DrydenComponent::U, 2.0), (DrydenComponent::V, 3.0), (DrydenComponent::W, 4.0)]
        {
            // Substitute omega = tan(theta) * V/L-ish scale to integrate to infinity.
            let n = 200_000;
            let scale = 1.0;
            let mut integral = 0.0;
            for i in 0..n {
                let th = (i as f64 + 0.5) / n as f64 * PI / 2.0;
                let w = scale * th.tan();
                let jac = scale / th.cos().powi(2) * (PI / 2.0) / n as f64;
                integral += dryden_psd_one_sided(&p, comp, 100.0, w) * jac;
            }
            assert!((integral / (s * s) - 1.0).abs() < 1e-4, "{comp:?}: {integral}");
        }
    }

    #[test]
    fn repro_dryden_bit_for_bit_and_seeds_differ() {
        let p = DrydenParameters::mil_f_8785c(300.0, TurbulenceSeverity::Severe).unwrap();
        let a = DrydenTurbulence::generate(&p, 300.0, 0.01, 10.0, 5).unwrap();
        let b = DrydenTurbulence::generate(&p, 300.0, 0.01, 10.0, 5).unwrap();
        let c = DrydenTurbulence::generate(&p, 300.0, 0.01, 10.0, 6).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.samples().len(), 1001);
        let diff = a.samples().iter().zip(c.samples()).filter(|(x, y)| x == y).count();
        assert_eq!(diff, 0);
        // Linear interpolation between samples, hold outside.
        let (s0, s1) = (a.samples()[10], a.samples()[11]);
        let mid = a.wind_body_fps(0.105);
        assert!((mid - (s0 + s1) * 0.5).norm() < 1e-9);
        assert_eq!(a.wind_body_fps(-1.0), a.samples()[0]);
        assert_eq!(a.wind_body_fps(50.0), a.samples()[1000]);
    }

    #[test]
    fn invalid_dryden_configuration_is_an_error() {
        let p = DrydenParameters::mil_f_8785c(20000.0, TurbulenceSeverity::Light).unwrap();
        let e = DrydenGenerator::new(&p, 0.0, 0.01, 1).unwrap_err();
        assert!(e.to_string().contains("vt_fps"), "{e}");
        let e = DrydenGenerator::new(&p, 600.0, -0.01, 1).unwrap_err();
        assert!(e.to_string().contains("sample_time_s"), "{e}");
        let bad = DrydenParameters { L_w_ft: 0.0, ..p };
        let e = DrydenGenerator::new(&bad, 600.0, 0.01, 1).unwrap_err();
        assert!(e.to_string().contains("L_w_ft"), "{e}");
        assert!(DrydenTurbulence::generate(&p, 600.0, 1e-6, 1e3, 1).is_err());
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        #[test]
        fn prop_dryden_finite_for_valid_parameters(
            h in 0.0f64..90_000.0, sev in 0usize..3, vt in 1.0f64..3000.0,
            dt in 1e-4f64..1.0, seed in 0u64..1000, t in -10.0f64..100.0,
        ) {
            let sev = [
                TurbulenceSeverity::Light,
                TurbulenceSeverity::Moderate,
                TurbulenceSeverity::Severe,
            ][sev];
            let p = DrydenParameters::mil_f_8785c(h, sev).unwrap();
            let d = DrydenTurbulence::generate(&p, vt, dt, 2.0, seed).unwrap();
            let w = d.wind_body_fps(t);
            proptest::prop_assert!(w.iter().all(|c| c.is_finite()));
        }
    }
}
