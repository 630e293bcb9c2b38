//! Frequency-domain output error (`fdoe`): maximum-likelihood estimation of the derivatives of
//! a linear state-space model from the Fourier transforms of the measured inputs and outputs
//! over a band of frequencies (Klein & Morelli, *Aircraft System Identification*, AIAA 2006,
//! ch. 7, "frequency-domain output error"; SIDPAC `fdoe.m`).
//!
//! # Model
//!
//! The structure's [`FlightModel`] linearised about each manoeuvre's mean flight condition (the
//! mean of every model input and measured state over the manoeuvre): the parameters stay the
//! nondimensional derivatives of the time-domain output error (`CL_alpha`, `Cm_q` …), the
//! dimensional `A, B, C, D` follow from them through the mean `q̄, V`, mass, inertias and
//! geometry, by central differences of the nonlinear model's `ẋ = f` and `y = h`. The states
//! are the short-period pair `(α, q)` for a longitudinal structure, `(β, p, r, φ)` for a
//! lateral one, both for a coupled one; every other model input that varies over the manoeuvre
//! is an input of the linear model, measured: the controls, the thrust and its moment, and the
//! measured states the set does not integrate (`V`, `θ` on the short period; `V, α, q, θ` and
//! the measured `ax, az` on the lateral set). The speed's effect runs through the total
//! coefficients (`q̄ S CL` with `CL` at the reference), so the parameters not estimated enter
//! it at their starting values; on the Twin Otter records leaving `V` out (a constant-speed
//! short period) moved `CL_alpha`, `CL_de` and `Cm_q` 1.5–2.7 combined σ away from the
//! time-domain fit, with it they agree within 1.7 (docs/fdoe.md).
//!
//! The data are sampled with the inputs linear between samples (as the time-domain fit
//! integrates them), so the exact discrete model is the first-order hold
//! `x_{i+1} = Φ x_i + Γ0 u_i + Γ1 u_{i+1}` with `Φ = e^{AΔt}` and `Γ0, Γ1` from one matrix
//! exponential of the augmented system (Franklin, Powell & Workman, *Digital Control of Dynamic
//! Systems*, 3rd ed., §6.3.2). Its discrete Fourier transform at the transform's own
//! frequencies `f_k = k/(NΔt)` (`z_k = e^{j2πk/N}`, `z_k^N = 1`) is exact:
//!
//! ```text
//! Ŷ_k = C (z_k I − Φ)⁻¹ [ (Γ0 + z_k Γ1) U_k + z_k x_Δ ] + D U_k
//! ```
//!
//! where `x_Δ = x_0 − x_N − Γ1 (u_0 − u_N)` is the real vector through which the record's
//! start and end states enter (Klein & Morelli's initial/final-condition terms; estimated, one
//! per manoeuvre and state). Constant offsets (trim values, sensor biases, the zero-order
//! terms) have no component at `k ≠ 0` and drop out exactly, so no detrending is needed; on
//! this grid no leakage correction is either (what SIDPAC's end-point detrending and `fint`
//! cubic end corrections approximate on an arbitrary grid).
//!
//! # What is estimated
//!
//! The terms of the coefficients the linear model's states see (`CL` or `CZ` and `Cm` on the
//! short period; `CY`, `Cl`, `Cn` on the lateral set) whose regressor is a state or an input
//! that varies: `alpha, beta, p, q, r, q0, alphadot, de, da, dr`. The others (`CD`, `CX`, the
//! zero-order terms, `V` terms, products such as `alpha2` that a linearisation at one point
//! folds into the linear term) are held at the equation-error starting values and reported as
//! not estimated ([`FdoeResult::estimated`], σ `None`).
//!
//! # Cost and iteration
//!
//! With residuals `v_k = Z_k − Ŷ_k` at the `K` frequencies of all manoeuvres and the diagonal
//! residual spectral covariance `S = diag((1/K) Σ_k |v_kj|²)` (the maximum-likelihood estimate
//! for complex Gaussian residuals), the negative log-likelihood concentrated in `S` is
//! `K ln det S` + const. Each iteration fixes `S`, takes the Gauss–Newton step of
//! `J = Σ_k v_kᴴ S⁻¹ v_k` (`M = Re Σ J_kᴴ S⁻¹ J_k`, `g = Re Σ J_kᴴ S⁻¹ v_k`, `Δ = M⁻¹ g`,
//! sensitivities `J_k = ∂Ŷ_k/∂β` by central differences of the linearisation in the
//! parameters, exact in `x_Δ`), halved up to 10 times until `ln det S` falls (the relaxation
//! of Klein & Morelli ch. 6–7 and Jategaonkar 2015 ch. 4 with a step-halving safeguard).
//! Convergence as the time-domain fit: relative change of `det S` below
//! [`FdoeConfig::cost_tolerance`] and largest step below [`FdoeConfig::step_tolerance_sigma`]
//! Cramér–Rao σ. An accepted iterate whose sensitivities cannot be formed (the flight model
//! fails at a perturbed parameter) ends the fit at the last iterate whose were, as
//! [`NotConverged::NumericalFailure`] (output error's module doc, "Numerical failure").
//!
//! # Accuracy
//!
//! Cramér–Rao covariance `(2 Re Σ J_kᴴ S⁻¹ J_k)⁻¹`: the Fisher information of circular complex
//! Gaussian residuals of covariance `S` (each of the real and imaginary parts has variance
//! `S/2`). `S` is estimated within the band, so residual colour across frequencies outside the
//! band does not make it optimistic the way the time-domain bound is on coloured residuals.

use super::{NotConverged, OeIteration, StopFlag, Termination, equation_error_start};
use crate::flight_model::{FlightModel, ModelInputs, N_STATES, Output, StateSet, state};
use crate::sample::AirDataSample;
use crate::vocabulary::{Coefficient, ModelStructure, Term};
use nalgebra::{Complex, DMatrix, DVector};
use std::string::{String, ToString};
use std::vec::Vec;
use std::{format, vec};

type C64 = Complex<f64>;

/// Per frequency, the forced prediction `Ŷ_k` (without the transient) and the transient's
/// matrix `C (z_k I − Φ)⁻¹ z_k`.
type Prediction = (Vec<DVector<C64>>, Vec<DMatrix<C64>>);

/// SIDPAC's rigid-body band for frequency-domain estimation, Hz (Klein & Morelli 2006 ch. 7:
/// 0.1–1.5 Hz covers the short-period and Dutch-roll modes of transport and general-aviation
/// aircraft and the energy of the usual multistep inputs). A record whose excitation or modes
/// lie elsewhere needs its own band ([`FdoeConfig::band_hz`]).
pub const DEFAULT_BAND_HZ: (f64, f64) = (0.1, 1.5);

/// Largest relative deviation of a sample interval from the manoeuvre's median: the discrete
/// Fourier transform assumes uniform sampling.
pub const MAX_INTERVAL_DEVIATION: f64 = 0.01;

/// Configuration of [`fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct FdoeConfig {
    /// The model structure (its nondimensional parameters are the unknowns, module doc).
    pub structure: ModelStructure,
    /// The band `(f_min, f_max)`, Hz: every frequency `k/(NΔt)` of each manoeuvre's transform
    /// inside it (and below Nyquist) is fitted.
    pub band_hz: (f64, f64),
    /// Outputs; `None`: the linear model's states and the accelerations its set models
    /// (`az`, `q̇`; `ay`, `ṗ`, `ṙ`) that the first sample has.
    pub outputs: Option<Vec<Output>>,
    /// Most iterations (default 50).
    pub max_iterations: usize,
    /// Convergence: relative change of `det S` (default 10⁻⁶).
    pub cost_tolerance: f64,
    /// Convergence: largest step in Cramér–Rao σ (default 10⁻³).
    pub step_tolerance_sigma: f64,
    /// A request to stop, looked at before every iteration.
    pub stop: Option<StopFlag>,
}

impl FdoeConfig {
    /// The defaults for `structure`: [`DEFAULT_BAND_HZ`], default outputs, 50 iterations.
    pub fn new(structure: ModelStructure) -> Self {
        Self {
            structure,
            band_hz: DEFAULT_BAND_HZ,
            outputs: None,
            max_iterations: 50,
            cost_tolerance: 1e-6,
            step_tolerance_sigma: 1e-3,
            stop: None,
        }
    }
}

/// Why [`fit`] failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FdoeError {
    /// The configuration or the data cannot be fitted (the message names what and where).
    #[error("frequency-domain output error: {0}")]
    Invalid(String),
    /// The flight model failed at the reference condition.
    #[error("frequency-domain output error: {0}")]
    Model(#[from] crate::EstimatorError),
}

/// The result of [`fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct FdoeResult {
    /// The structure.
    pub structure: ModelStructure,
    /// The structure's parameter names, structure order.
    pub names: Vec<String>,
    /// Whether each parameter was estimated (module doc, "What is estimated").
    pub estimated: Vec<bool>,
    /// Estimates; the parameters not estimated keep their starting value.
    pub values: Vec<f64>,
    /// Cramér–Rao σ of the estimated parameters, `None` for the others.
    pub sigma: Vec<Option<f64>>,
    /// Cramér–Rao covariance between parameters `i, j` (`np × np` row-major), `None` where
    /// either is not estimated.
    pub covariance: Vec<Option<f64>>,
    /// The starting values (equation error), structure order.
    pub start: Vec<f64>,
    /// Outputs fitted.
    pub outputs: Vec<Output>,
    /// The linear model's states (full-state indices, [`state`]).
    pub states: Vec<usize>,
    /// The linear model's measured inputs (union over manoeuvres): `de_rad`, `thrust_n`,
    /// `vt_mps` …
    pub inputs: Vec<&'static str>,
    /// The band fitted, Hz.
    pub band_hz: (f64, f64),
    /// Frequencies fitted, per manoeuvre, Hz.
    pub frequencies_hz: Vec<Vec<f64>>,
    /// The residual spectral variances `S_jj` per output (the output's unit² · samples²; the
    /// transform is the plain sum `Σ x_i z^{−i}`).
    pub s_vv: Vec<f64>,
    /// Estimated `x_Δ` per manoeuvre (state units), the initial/final-condition terms.
    pub transients: Vec<Vec<f64>>,
    /// Iteration log (`ln_det_r` is `ln det S`, `cost` is `J/2` at the step's `S`).
    pub iterations: Vec<OeIteration>,
    /// How the iteration ended.
    pub termination: Termination,
    /// Per manoeuvre, the mean airspeed (m/s) and dynamic pressure (Pa) of the linearisation.
    pub flight_conditions: Vec<(f64, f64)>,
}

impl FdoeResult {
    /// Estimate and σ of the parameter named `name`, when estimated.
    pub fn get(&self, name: &str) -> Option<(f64, f64)> {
        let i = self.names.iter().position(|n| n == name)?;
        Some((self.values[i], self.sigma[i]?))
    }
}

impl core::fmt::Display for FdoeResult {
    /// A printable summary: band, iteration log, estimates with Cramér–Rao σ (`—` for the
    /// parameters not estimated).
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let k: usize = self.frequencies_hz.iter().map(Vec::len).sum();
        writeln!(
            f,
            "frequency-domain output error: {}–{} Hz, {k} frequencies in {} manoeuvre(s), {} outputs: {}",
            self.band_hz.0,
            self.band_hz.1,
            self.frequencies_hz.len(),
            self.outputs.len(),
            self.termination.describe()
        )?;
        writeln!(f, "{:>5} {:>14} {:>12}", "iter", "ln det S", "max step/σ")?;
        for it in &self.iterations {
            writeln!(f, "{:>5} {:>14.8} {:>12.3e}", it.iteration, it.ln_det_r, it.max_step_sigma)?;
        }
        writeln!(f, "{:<22} {:>14} {:>12}", "parameter", "estimate", "CR σ")?;
        for (i, name) in self.names.iter().enumerate() {
            match self.sigma[i].filter(|_| self.estimated[i]) {
                Some(s) => writeln!(f, "{name:<22} {:>14.6} {s:>12.6}", self.values[i])?,
                None => writeln!(f, "{name:<22} {:>14} {:>12}", "—", "—")?,
            }
        }
        Ok(())
    }
}

/// A model input of the linear model, read from and written to [`ModelInputs`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Channel {
    De,
    Da,
    Dr,
    Thrust,
    ThrustMoment,
    Measured(usize),
    Accel(usize),
    Alphadot,
}

impl Channel {
    fn get(self, u: &ModelInputs) -> f64 {
        match self {
            Channel::De => u.de_rad,
            Channel::Da => u.da_rad,
            Channel::Dr => u.dr_rad,
            Channel::Thrust => u.thrust_n,
            Channel::ThrustMoment => u.thrust_moment_nm,
            Channel::Measured(i) => u.x_meas[i],
            Channel::Accel(i) => u.accel_meas[i],
            Channel::Alphadot => u.alphadot_meas,
        }
    }

    fn set(self, u: &mut ModelInputs, v: f64) {
        match self {
            Channel::De => u.de_rad = v,
            Channel::Da => u.da_rad = v,
            Channel::Dr => u.dr_rad = v,
            Channel::Thrust => u.thrust_n = v,
            Channel::ThrustMoment => u.thrust_moment_nm = v,
            Channel::Measured(i) => u.x_meas[i] = v,
            Channel::Accel(i) => u.accel_meas[i] = v,
            Channel::Alphadot => u.alphadot_meas = v,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Channel::De => "de_rad",
            Channel::Da => "da_rad",
            Channel::Dr => "dr_rad",
            Channel::Thrust => "thrust_n",
            Channel::ThrustMoment => "thrust_moment_nm",
            Channel::Measured(i) => crate::flight_model::STATE_NAMES[i],
            Channel::Accel(i) => ["ax_mps2", "ay_mps2", "az_mps2"][i],
            Channel::Alphadot => "alphadot_rad_s",
        }
    }

    fn candidates(states: &[usize]) -> Vec<Channel> {
        let mut v = vec![Channel::De, Channel::Da, Channel::Dr, Channel::Thrust];
        v.push(Channel::ThrustMoment);
        v.extend((0..N_STATES).filter(|i| !states.contains(i)).map(Channel::Measured));
        v.extend((0..3).map(Channel::Accel));
        v.push(Channel::Alphadot);
        v
    }
}

/// The linear model's states of a state set (module doc).
fn linear_states(set: StateSet) -> Vec<usize> {
    let lon = [state::ALPHA, state::Q];
    let lat = [state::BETA, state::P, state::R, state::PHI];
    match set {
        StateSet::Longitudinal => lon.to_vec(),
        StateSet::Lateral => lat.to_vec(),
        StateSet::Coupled => lon.iter().chain(&lat).copied().collect(),
    }
}

/// The outputs the linear model can predict beyond its states.
fn linear_outputs(set: StateSet, states: &[usize]) -> Vec<Output> {
    let mut v: Vec<Output> =
        Output::ALL.iter().copied().filter(|o| states.contains(&o.index())).collect();
    if set.lon() {
        v.extend([Output::Az, Output::Qdot]);
    }
    if set.lat() {
        v.extend([Output::Ay, Output::Pdot, Output::Rdot]);
    }
    v
}

/// Whether parameter `p` is seen by the linear model (module doc, "What is estimated").
fn seen(p: crate::vocabulary::Param, set: StateSet) -> bool {
    use Coefficient as C;
    let coefficient = match p.coefficient {
        C::CL | C::CZ | C::Cm => set.lon(),
        C::CY | C::Cl | C::Cn => set.lat(),
        C::CD | C::CX => false,
    };
    let term = matches!(
        p.term,
        Term::Alpha
            | Term::Beta
            | Term::P
            | Term::Q
            | Term::R
            | Term::Q0
            | Term::Alphadot
            | Term::De
            | Term::Da
            | Term::Dr
    );
    coefficient && term
}

/// One manoeuvre prepared: its reference condition, inputs and transforms.
struct Manoeuvre {
    reference: ModelInputs,
    channels: Vec<Channel>,
    dt_s: f64,
    /// `z_k`.
    z: Vec<C64>,
    /// `U_k` (`nu` per frequency).
    u: Vec<Vec<C64>>,
    /// `Z_k` (`ny` per frequency).
    y: Vec<Vec<C64>>,
    frequencies_hz: Vec<f64>,
}

/// The discrete Fourier transform `Σ_i x_i z_k^{−i}` of `x` at bins `bins` of its length, by
/// one fast transform of the whole record (O(N log N)): a sum per bin costs O(N) each, and the
/// band holds a number of bins proportional to the record's length, so the direct sums made the
/// fit's time grow with the square of the record.
/// `fft` is the forward transform of `x.len()` points.
fn dft(fft: &dyn rustfft::Fft<f64>, x: &[f64], bins: &[usize]) -> Vec<C64> {
    let mut buf: Vec<rustfft::num_complex::Complex64> =
        x.iter().map(|v| rustfft::num_complex::Complex64::new(*v, 0.0)).collect();
    fft.process(&mut buf);
    bins.iter().map(|&k| C64::new(buf[k].re, buf[k].im)).collect()
}

fn invalid(msg: String) -> FdoeError {
    FdoeError::Invalid(msg)
}

/// The manoeuvre's uniform sample interval, s.
fn sample_interval(m: &[AirDataSample]) -> Result<f64, FdoeError> {
    let mut dts: Vec<f64> = m.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
    dts.sort_by(f64::total_cmp);
    let dt = dts[dts.len() / 2];
    for w in m.windows(2) {
        let d = w[1].t_s - w[0].t_s;
        if !(dt > 0.0 && ((d - dt) / dt).abs() <= MAX_INTERVAL_DEVIATION) {
            return Err(invalid(format!(
                "the sample interval before t = {} s is {d} s, not the manoeuvre's {dt} s: the Fourier transform needs uniform sampling (within {} %); resample the record or fit a window of it",
                w[1].t_s,
                100.0 * MAX_INTERVAL_DEVIATION
            )));
        }
    }
    Ok(dt)
}

/// Reads and transforms one manoeuvre.
fn prepare_manoeuvre(
    model: &FlightModel,
    m: &[AirDataSample],
    states: &[usize],
    outputs: &[Output],
    band: (f64, f64),
) -> Result<Manoeuvre, FdoeError> {
    if m.len() < 8 {
        return Err(invalid(format!(
            "a manoeuvre of {} samples is too short to transform",
            m.len()
        )));
    }
    let dt_s = sample_interval(m)?;
    let inputs: Vec<ModelInputs> = m.iter().map(|s| model.inputs(s)).collect::<Result<_, _>>()?;
    let mut reference = inputs[0];
    for (k, u) in inputs.iter().enumerate().skip(1) {
        reference = ModelInputs::lerp(&reference, u, 1.0 / (k as f64 + 1.0));
    }
    let channels: Vec<Channel> = Channel::candidates(states)
        .into_iter()
        .filter(|c| inputs.iter().any(|u| c.get(u) != c.get(&inputs[0])))
        .collect();
    let n = m.len();
    let t_total = n as f64 * dt_s;
    let nyquist = 0.5 / dt_s;
    let bins: Vec<usize> = (1..n / 2)
        .filter(|&k| {
            let f = k as f64 / t_total;
            f >= band.0 && f <= band.1 && f < nyquist
        })
        .collect();
    if bins.is_empty() {
        return Err(invalid(format!(
            "the manoeuvre from t = {} s ({t_total:.1} s long, resolution {:.3} Hz) has no frequency in the band {}–{} Hz",
            m[0].t_s,
            1.0 / t_total,
            band.0,
            band.1
        )));
    }
    let u_series: Vec<Vec<f64>> =
        channels.iter().map(|c| inputs.iter().map(|u| c.get(u)).collect()).collect();
    let mut y_series = Vec::new();
    for o in outputs {
        let v: Option<Vec<f64>> = m.iter().map(|s| o.measured(s)).collect();
        let v = v.ok_or_else(|| {
            let t = m.iter().find(|s| o.measured(s).is_none()).map_or(0.0, |s| s.t_s);
            invalid(format!("output {} is absent at t = {t} s", o.name()))
        })?;
        y_series.push(v);
    }
    let fft = rustfft::FftPlanner::<f64>::new().plan_fft_forward(n);
    let ut: Vec<Vec<C64>> = u_series.iter().map(|x| dft(&*fft, x, &bins)).collect();
    let yt: Vec<Vec<C64>> = y_series.iter().map(|x| dft(&*fft, x, &bins)).collect();
    let per_k = |t: &[Vec<C64>], k: usize| t.iter().map(|c| c[k]).collect::<Vec<_>>();
    let w = |k: usize| 2.0 * core::f64::consts::PI * k as f64 / n as f64;
    Ok(Manoeuvre {
        reference,
        channels,
        dt_s,
        z: bins.iter().map(|&k| C64::from_polar(1.0, w(k))).collect(),
        u: (0..bins.len()).map(|k| per_k(&ut, k)).collect(),
        y: (0..bins.len()).map(|k| per_k(&yt, k)).collect(),
        frequencies_hz: bins.iter().map(|&k| k as f64 / t_total).collect(),
    })
}

/// The continuous linear model `(A, B, C, D)` at the manoeuvre's reference condition.
struct Linear {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    c: DMatrix<f64>,
    d: DMatrix<f64>,
}

/// `(ẋ of the states, y)` of the nonlinear model at the reference perturbed by `dx`, `du`.
fn evaluate(
    model: &FlightModel,
    theta: &[f64],
    m: &Manoeuvre,
    states: &[usize],
    outputs: &[Output],
    dx: &[f64],
    du: &[f64],
) -> Result<(Vec<f64>, Vec<f64>), FdoeError> {
    let mut u = m.reference;
    for (c, d) in m.channels.iter().zip(du) {
        let v = c.get(&u) + d;
        c.set(&mut u, v);
    }
    let mut x = u.x_meas;
    for (i, d) in states.iter().zip(dx) {
        x[*i] += d;
    }
    let z = [0.0; 8];
    let e = model.eval(theta, &u, &x, &z, &z, None)?;
    Ok((
        states.iter().map(|&i| e.xdot[i]).collect(),
        outputs.iter().map(|o| e.output(*o, &x)).collect(),
    ))
}

/// Central-difference linearisation of the model at the manoeuvre's reference (module doc).
fn linearise(
    model: &FlightModel,
    theta: &[f64],
    m: &Manoeuvre,
    states: &[usize],
    outputs: &[Output],
) -> Result<Linear, FdoeError> {
    let (nx, nu, ny) = (states.len(), m.channels.len(), outputs.len());
    let mut lin = Linear {
        a: DMatrix::zeros(nx, nx),
        b: DMatrix::zeros(nx, nu),
        c: DMatrix::zeros(ny, nx),
        d: DMatrix::zeros(ny, nu),
    };
    let x_ref: Vec<f64> = states.iter().map(|&i| m.reference.x_meas[i]).collect();
    let u_ref: Vec<f64> = m.channels.iter().map(|c| c.get(&m.reference)).collect();
    let step = |v: f64| 1e-6 * v.abs().max(1.0);
    for j in 0..nx + nu {
        let h = if j < nx { step(x_ref[j]) } else { step(u_ref[j - nx]) };
        let mut dx = vec![0.0; nx];
        let mut du = vec![0.0; nu];
        let mut put = |s: f64| {
            if j < nx { dx[j] = s } else { du[j - nx] = s }
        };
        put(h);
        let (fp, yp) = evaluate(model, theta, m, states, outputs, &dx, &du)?;
        let mut dx = vec![0.0; nx];
        let mut du = vec![0.0; nu];
        if j < nx {
            dx[j] = -h
        } else {
            du[j - nx] = -h
        }
        let (fm, ym) = evaluate(model, theta, m, states, outputs, &dx, &du)?;
        for r in 0..nx {
            let v = (fp[r] - fm[r]) / (2.0 * h);
            if j < nx { lin.a[(r, j)] = v } else { lin.b[(r, j - nx)] = v }
        }
        for r in 0..ny {
            let v = (yp[r] - ym[r]) / (2.0 * h);
            if j < nx { lin.c[(r, j)] = v } else { lin.d[(r, j - nx)] = v }
        }
    }
    Ok(lin)
}

/// `(Φ, Γ0, Γ1)` of the first-order hold (module doc): the exponential of
/// `[[A, B, 0], [0, 0, I/Δt], [0, 0, 0]] Δt`, whose top block row is `[Φ, Γa, Γb]`,
/// `Γ0 = Γa − Γb`, `Γ1 = Γb`.
fn first_order_hold(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    dt: f64,
) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let (nx, nu) = (a.nrows(), b.ncols());
    let n = nx + 2 * nu;
    let mut m = DMatrix::<f64>::zeros(n, n);
    m.view_mut((0, 0), (nx, nx)).copy_from(&(a * dt));
    m.view_mut((0, nx), (nx, nu)).copy_from(&(b * dt));
    for i in 0..nu {
        m[(nx + i, nx + nu + i)] = 1.0;
    }
    let e = m.exp();
    let phi = e.view((0, 0), (nx, nx)).into_owned();
    let ga = e.view((0, nx), (nx, nu)).into_owned();
    let gb = e.view((0, nx + nu), (nx, nu)).into_owned();
    (phi, &ga - &gb, gb)
}

/// The model's prediction of one manoeuvre's output transforms without the transient term,
/// and the transient's matrices `C (zI − Φ)⁻¹ z` (`ny × nx`), per frequency.
fn predict(
    model: &FlightModel,
    theta: &[f64],
    m: &Manoeuvre,
    states: &[usize],
    outputs: &[Output],
) -> Result<Prediction, FdoeError> {
    let lin = linearise(model, theta, m, states, outputs)?;
    let (phi, g0, g1) = first_order_hold(&lin.a, &lin.b, m.dt_s);
    let cx = |x: &DMatrix<f64>| x.map(|v| C64::new(v, 0.0));
    let (phi, g0, g1, c, d) = (cx(&phi), cx(&g0), cx(&g1), cx(&lin.c), cx(&lin.d));
    let nx = states.len();
    let mut y = Vec::with_capacity(m.z.len());
    let mut tr = Vec::with_capacity(m.z.len());
    for (k, &z) in m.z.iter().enumerate() {
        let u = DVector::from_column_slice(&m.u[k]);
        let lhs = DMatrix::<C64>::identity(nx, nx) * z - &phi;
        let lu = lhs.lu();
        let forced = lu
            .solve(&((&g0 + &g1 * z) * &u))
            .ok_or_else(|| invalid(format!("z I − Φ is singular at {} Hz", m.frequencies_hz[k])))?;
        let resolvent = lu
            .try_inverse()
            .ok_or_else(|| invalid(format!("z I − Φ is singular at {} Hz", m.frequencies_hz[k])))?;
        y.push(&c * forced + &d * &u);
        tr.push(&c * resolvent * z);
    }
    Ok((y, tr))
}

/// Every manoeuvre's residuals `v_k = Z_k − Ŷ_k` at `theta` and transients `xd`.
fn residuals(
    ctx: &Context,
    theta: &[f64],
    xd: &[Vec<f64>],
) -> Result<Vec<Vec<DVector<C64>>>, FdoeError> {
    let mut out = Vec::with_capacity(ctx.man.len());
    for (mi, m) in ctx.man.iter().enumerate() {
        let (y, tr) = predict(&ctx.model, theta, m, &ctx.states, &ctx.outputs)?;
        let x = DVector::from_iterator(xd[mi].len(), xd[mi].iter().map(|v| C64::new(*v, 0.0)));
        out.push(
            y.iter()
                .zip(&tr)
                .zip(&m.y)
                .map(|((y, t), z)| DVector::from_column_slice(z) - y - t * &x)
                .collect(),
        );
    }
    Ok(out)
}

/// The ML diagonal `S` (mean `|v|²` per output over every frequency).
fn spectral_variances(v: &[Vec<DVector<C64>>], ny: usize) -> Vec<f64> {
    let mut s = vec![0.0; ny];
    let mut k = 0usize;
    for vk in v.iter().flatten() {
        for j in 0..ny {
            s[j] += vk[j].norm_sqr();
        }
        k += 1;
    }
    s.iter().map(|x| x / k.max(1) as f64).collect()
}

struct Context {
    model: FlightModel,
    man: Vec<Manoeuvre>,
    states: Vec<usize>,
    outputs: Vec<Output>,
    free: Vec<usize>,
}

impl Context {
    fn n_unknowns(&self) -> usize {
        self.free.len() + self.man.len() * self.states.len()
    }

    fn split(&self, theta0: &[f64], beta: &[f64]) -> (Vec<f64>, Vec<Vec<f64>>) {
        let mut theta = theta0.to_vec();
        for (k, &i) in self.free.iter().enumerate() {
            theta[i] = beta[k];
        }
        let nx = self.states.len();
        let nf = self.free.len();
        let xd =
            (0..self.man.len()).map(|m| beta[nf + m * nx..nf + (m + 1) * nx].to_vec()).collect();
        (theta, xd)
    }

    /// Sensitivities `∂Ŷ_k/∂β` of every manoeuvre and frequency (`ny × nβ`).
    fn sensitivities(
        &self,
        theta0: &[f64],
        beta: &[f64],
    ) -> Result<Vec<Vec<DMatrix<C64>>>, FdoeError> {
        let nb = self.n_unknowns();
        let ny = self.outputs.len();
        let nx = self.states.len();
        let nf = self.free.len();
        #[cfg(test)]
        super::fault::check()?;
        let (theta, xd) = self.split(theta0, beta);
        let mut out: Vec<Vec<DMatrix<C64>>> =
            self.man.iter().map(|m| vec![DMatrix::zeros(ny, nb); m.z.len()]).collect();
        // The whole prediction, the transient term included (it depends on θ through Φ, C).
        let full = |theta: &[f64], mi: usize| -> Result<Vec<DVector<C64>>, FdoeError> {
            let m = &self.man[mi];
            let (y, tr) = predict(&self.model, theta, m, &self.states, &self.outputs)?;
            let x = DVector::from_iterator(nx, xd[mi].iter().map(|v| C64::new(*v, 0.0)));
            Ok(y.iter().zip(&tr).map(|(y, t)| y + t * &x).collect())
        };
        for (col, &i) in self.free.iter().enumerate() {
            let h = 1e-5 * theta[i].abs().max(1e-2);
            let mut tp = theta.clone();
            tp[i] += h;
            let mut tm = theta.clone();
            tm[i] -= h;
            for mi in 0..self.man.len() {
                let (yp, ym) = (full(&tp, mi)?, full(&tm, mi)?);
                for k in 0..yp.len() {
                    let d = (&yp[k] - &ym[k]) / C64::new(2.0 * h, 0.0);
                    out[mi][k].set_column(col, &d);
                }
            }
        }
        for (mi, m) in self.man.iter().enumerate() {
            let (_, tr) = predict(&self.model, &theta, m, &self.states, &self.outputs)?;
            for k in 0..m.z.len() {
                for s in 0..nx {
                    out[mi][k].set_column(nf + mi * nx + s, &tr[k].column(s));
                }
            }
        }
        Ok(out)
    }
}

/// `M = Re Σ Jᴴ W J` and `g = Re Σ Jᴴ W v`, `W = S⁻¹`.
fn normal_equations(
    sens: &[Vec<DMatrix<C64>>],
    v: &[Vec<DVector<C64>>],
    s: &[f64],
    nb: usize,
) -> (DMatrix<f64>, DVector<f64>) {
    let mut m = DMatrix::<f64>::zeros(nb, nb);
    let mut g = DVector::<f64>::zeros(nb);
    for (jm, vm) in sens.iter().zip(v) {
        for (j, vk) in jm.iter().zip(vm) {
            for (r, w) in s.iter().map(|x| 1.0 / x).enumerate() {
                for a in 0..nb {
                    let ja = j[(r, a)].conj() * w;
                    g[a] += (ja * vk[r]).re;
                    for b in a..nb {
                        m[(a, b)] += (ja * j[(r, b)]).re;
                    }
                }
            }
        }
    }
    for a in 0..nb {
        for b in 0..a {
            m[(a, b)] = m[(b, a)];
        }
    }
    (m, g)
}

/// Inverse of a symmetric positive definite matrix by Jacobi-scaled Cholesky.
fn spd_inverse(m: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = m.nrows();
    if (0..n).any(|i| !(m[(i, i)] > 0.0 && m[(i, i)].is_finite())) {
        return None;
    }
    let d: Vec<f64> = (0..n).map(|i| 1.0 / m[(i, i)].sqrt()).collect();
    let ms = DMatrix::from_fn(n, n, |i, j| m[(i, j)] * d[i] * d[j]);
    let inv = ms.cholesky()?.inverse();
    let out = DMatrix::from_fn(n, n, |i, j| inv[(i, j)] * d[i] * d[j]);
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// Sets up the problem: the linear model's states, outputs, free parameters and transforms.
fn context(manoeuvres: &[&[AirDataSample]], config: &FdoeConfig) -> Result<Context, FdoeError> {
    let model = FlightModel::new(config.structure)?;
    let set = model.state_set();
    let states = linear_states(set);
    let (f0, f1) = config.band_hz;
    if !(f0 > 0.0 && f1 > f0 && f1.is_finite()) {
        return Err(invalid(format!("the band {f0}–{f1} Hz must have 0 < f_min < f_max")));
    }
    let first =
        manoeuvres.iter().find_map(|m| m.first()).ok_or_else(|| invalid("no samples".into()))?;
    let allowed = linear_outputs(set, &states);
    let outputs = match &config.outputs {
        Some(o) => {
            if let Some(bad) = o.iter().find(|o| !allowed.contains(o)) {
                let names: Vec<&str> = allowed.iter().map(|o| o.name()).collect();
                return Err(invalid(format!(
                    "output {} is not one the linear model predicts ({})",
                    bad.name(),
                    names.join(", ")
                )));
            }
            o.clone()
        }
        None => allowed.into_iter().filter(|o| o.measured(first).is_some()).collect(),
    };
    if outputs.is_empty() {
        return Err(invalid("no output of the linear model is measured".into()));
    }
    let man = manoeuvres
        .iter()
        .map(|m| prepare_manoeuvre(&model, m, &states, &outputs, config.band_hz))
        .collect::<Result<Vec<_>, _>>()?;
    let varies = |name: &str| man.iter().any(|m| m.channels.iter().any(|c| c.name() == name));
    let free = config
        .structure
        .params()
        .enumerate()
        .filter(|(_, p)| seen(*p, set))
        .filter(|(_, p)| match p.term {
            Term::De => varies("de_rad"),
            Term::Da => varies("da_rad"),
            Term::Dr => varies("dr_rad"),
            _ => true,
        })
        .map(|(i, _)| i)
        .collect();
    Ok(Context { model, man, states, outputs, free })
}

/// Fits the structure's parameters to the manoeuvres by frequency-domain output error (module
/// doc). Each manoeuvre must be uniformly sampled and carry every channel the flight model
/// needs ([`FlightModel::inputs`]) and every output.
///
/// A fit that does not converge is returned with its last iterate and
/// [`FdoeResult::termination`] saying why.
///
/// # Errors
/// [`FdoeError::Invalid`] naming the problem (a band with no frequency of a manoeuvre, an
/// output absent, non-uniform sampling, no parameter the linear model sees, a singular
/// information matrix); [`FdoeError::Model`] when the flight model rejects the data.
pub fn fit(manoeuvres: &[&[AirDataSample]], config: &FdoeConfig) -> Result<FdoeResult, FdoeError> {
    let ctx = context(manoeuvres, config)?;
    if ctx.free.is_empty() {
        return Err(invalid(
            "the structure has no parameter the linear model sees (module doc: CL/CZ, Cm, CY, Cl, Cn terms in alpha, beta, p, q, r, q0, alphadot or a varying control)".into(),
        ));
    }
    let start = equation_error_start(&config.structure, manoeuvres);
    let mut it = FdIterate::new(&ctx, &start)?;
    let (converged, failure) = it.iterate(&ctx, config, &start)?;
    let mut termination = Termination::of(&it.log, converged, failure, config.cost_tolerance);
    // The final iterate's sensitivities were never formed unless the fit stopped where it
    // linearized: when they cannot be, the last iterate whose were is the answer.
    let sens = match ctx.sensitivities(&start, &it.beta) {
        Ok(sens) => sens,
        Err(err) => {
            let why = it.fall_back(err)?;
            termination = Termination::of(&it.log, false, why, config.cost_tolerance);
            ctx.sensitivities(&start, &it.beta)?
        }
    };
    fd_result(&ctx, config, start, it, &sens, termination)
}

/// Per manoeuvre, per frequency, the output error `V_k`.
type Residuals = Vec<Vec<DVector<C64>>>;

/// `ln det S_vv` of the diagonal spectral variances: the merit the iteration lowers.
fn ln_det(s: &[f64]) -> f64 {
    s.iter().map(|v| v.ln()).sum::<f64>()
}

/// The frequency-domain iteration's state: the unknowns β (free parameters, then the
/// transients), the residuals `V` and spectral variances `S_vv` at β, and the log.
struct FdIterate {
    beta: Vec<f64>,
    v: Residuals,
    s: Vec<f64>,
    log: Vec<OeIteration>,
    /// The last iterate whose residuals and sensitivities were both formed: β, `V`, `S_vv`
    /// and the length of the log up to it (`None` before the first sensitivities).
    good: Option<(Vec<f64>, Residuals, Vec<f64>, usize)>,
}

/// A step along the Gauss–Newton direction that lowered the merit: the new β, its residuals
/// and variances, and the step length α it was found at.
struct FdTrial {
    beta: Vec<f64>,
    v: Residuals,
    s: Vec<f64>,
    alpha: f64,
}

impl FdIterate {
    /// The state at the equation-error start `start` (transients 0), with its log entry 0.
    fn new(ctx: &Context, start: &[f64]) -> Result<Self, FdoeError> {
        let nb = ctx.n_unknowns();
        let ny = ctx.outputs.len();
        let mut beta: Vec<f64> = ctx.free.iter().map(|&i| start[i]).collect();
        beta.resize(nb, 0.0);
        let k_total: usize = ctx.man.iter().map(|m| m.z.len()).sum();
        let (theta, xd) = ctx.split(start, &beta);
        let v = residuals(ctx, &theta, &xd)?;
        let s = spectral_variances(&v, ny);
        let log = vec![OeIteration {
            iteration: 0,
            ln_det_r: ln_det(&s),
            cost: 0.5 * (k_total * ny) as f64,
            lambda: 0.0,
            max_step_sigma: f64::NAN,
        }];
        Ok(Self { beta, v, s, log, good: None })
    }

    /// After `err` at the current iterate: back to the last iterate whose sensitivities were
    /// formed, returning the reason the fit then ends with (output error's module doc,
    /// "Numerical failure").
    ///
    /// # Errors
    /// `err` itself when it is not a numerical failure of the flight model or no earlier
    /// iterate was linearized.
    fn fall_back(&mut self, err: FdoeError) -> Result<NotConverged, FdoeError> {
        let why = match &err {
            FdoeError::Model(e) => NotConverged::numerical(e),
            FdoeError::Invalid(_) => None,
        };
        let (Some(why), Some((beta, v, s, log_len))) = (why, self.good.take()) else {
            return Err(err);
        };
        if beta == self.beta {
            return Err(err);
        }
        (self.beta, self.v, self.s) = (beta, v, s);
        self.log.truncate(log_len);
        Ok(why)
    }

    /// Gauss–Newton iterations with step halving until converged, stopped or out of
    /// iterations: `(converged, why not)` (the reason is only read when not converged).
    fn iterate(
        &mut self,
        ctx: &Context,
        config: &FdoeConfig,
        start: &[f64],
    ) -> Result<(bool, NotConverged), FdoeError> {
        let nb = ctx.n_unknowns();
        for iteration in 1..=config.max_iterations {
            if config.stop.as_ref().is_some_and(StopFlag::raised) {
                return Ok((false, NotConverged::Stopped));
            }
            let sens = match ctx.sensitivities(start, &self.beta) {
                Ok(sens) => sens,
                Err(err) => return Ok((false, self.fall_back(err)?)),
            };
            let good = (self.beta.clone(), self.v.clone(), self.s.clone(), self.log.len());
            self.good = Some(good);
            let (m, g) = normal_equations(&sens, &self.v, &self.s, nb);
            let Some(minv) = spd_inverse(&m) else {
                return Ok((false, NotConverged::Unidentifiable));
            };
            let step = &minv * &g;
            let sigma: Vec<f64> = (0..nb).map(|i| (0.5 * minv[(i, i)]).sqrt()).collect();
            let Some(trial) = self.line_search(ctx, start, &step) else {
                // No descent along the Gauss–Newton direction: at the minimum to rounding when
                // the step is already negligible.
                let largest = (0..nb).map(|i| (step[i] / sigma[i]).abs()).fold(0.0, f64::max);
                return Ok((largest < config.step_tolerance_sigma, NotConverged::NoDescent));
            };
            if self.accept(iteration, trial, &step, &sigma, config) {
                return Ok((true, NotConverged::MaxIterations));
            }
        }
        Ok((false, NotConverged::MaxIterations))
    }

    /// The first of `β + α Δ`, α = 1, ½, … (11 lengths), whose residuals exist and lower
    /// `ln det S_vv` with every variance positive; `None` when none does.
    fn line_search(&self, ctx: &Context, start: &[f64], step: &DVector<f64>) -> Option<FdTrial> {
        let ny = ctx.outputs.len();
        let mut alpha = 1.0;
        for _ in 0..11 {
            let trial: Vec<f64> =
                self.beta.iter().zip(step.iter()).map(|(b, d)| b + alpha * d).collect();
            let (theta, xd) = ctx.split(start, &trial);
            if let Ok(vt) = residuals(ctx, &theta, &xd) {
                let st = spectral_variances(&vt, ny);
                if ln_det(&st) < ln_det(&self.s) && st.iter().all(|x| *x > 0.0) {
                    return Some(FdTrial { beta: trial, v: vt, s: st, alpha });
                }
            }
            alpha *= 0.5;
        }
        None
    }

    /// Moves to the accepted trial and logs the iteration (its cost `½ Σ |V|²/S_vv` with the
    /// variances the step was taken with); `true` when both the relative change of
    /// `det S_vv` and the step (in σ of the unknowns, `sigma`) are below their tolerances.
    fn accept(
        &mut self,
        iteration: usize,
        trial: FdTrial,
        step: &DVector<f64>,
        sigma: &[f64],
        config: &FdoeConfig,
    ) -> bool {
        let (nb, ny) = (sigma.len(), self.s.len());
        let largest = (0..nb).map(|i| (trial.alpha * step[i] / sigma[i]).abs()).fold(0.0, f64::max);
        let wc: f64 = trial
            .v
            .iter()
            .flatten()
            .map(|vk| (0..ny).map(|j| vk[j].norm_sqr() / self.s[j]).sum::<f64>())
            .sum();
        let change = (ln_det(&trial.s) - ln_det(&self.s)).exp_m1().abs();
        self.beta = trial.beta;
        self.v = trial.v;
        self.s = trial.s;
        self.log.push(OeIteration {
            iteration,
            ln_det_r: ln_det(&self.s),
            cost: 0.5 * wc,
            lambda: 0.0,
            max_step_sigma: largest,
        });
        change < config.cost_tolerance && largest < config.step_tolerance_sigma
    }
}

/// The result at the final iterate, whose sensitivities are `sens`: Cramér–Rao covariance
/// `(2M)⁻¹` of the free parameters
/// (none for an unidentifiable fit, which is then not converged), the inputs seen, and the
/// flight condition `(V, q̄)` of each manoeuvre's reference.
fn fd_result(
    ctx: &Context,
    config: &FdoeConfig,
    start: Vec<f64>,
    it: FdIterate,
    sens: &[Vec<DMatrix<C64>>],
    termination: Termination,
) -> Result<FdoeResult, FdoeError> {
    let FdIterate { beta, v, s, log, .. } = it;
    let nb = ctx.n_unknowns();
    let (m, _) = normal_equations(sens, &v, &s, nb);
    let cov = spd_inverse(&m).map(|mi| mi * 0.5);
    let (theta, xd) = ctx.split(&start, &beta);
    let np = config.structure.n_params();
    let pos = |i: usize| ctx.free.iter().position(|&f| f == i);
    let sigma = (0..np).map(|i| Some(cov.as_ref()?[(pos(i)?, pos(i)?)].sqrt())).collect();
    let covariance =
        (0..np * np).map(|ij| Some(cov.as_ref()?[(pos(ij / np)?, pos(ij % np)?)])).collect();
    let mut inputs: Vec<&'static str> = Vec::new();
    for c in ctx.man.iter().flat_map(|m| &m.channels) {
        if !inputs.contains(&c.name()) {
            inputs.push(c.name());
        }
    }
    let termination = if cov.is_none() && termination.is_converged() {
        Termination::NotConverged(NotConverged::Unidentifiable)
    } else {
        termination
    };
    Ok(FdoeResult {
        structure: config.structure,
        names: config.structure.params().map(|p| p.name().to_string()).collect(),
        estimated: (0..np).map(|i| pos(i).is_some()).collect(),
        values: theta,
        sigma,
        covariance,
        start,
        outputs: ctx.outputs.clone(),
        states: ctx.states.clone(),
        inputs,
        band_hz: config.band_hz,
        frequencies_hz: ctx.man.iter().map(|m| m.frequencies_hz.clone()).collect(),
        s_vv: s,
        transients: xd,
        iterations: log,
        termination,
        flight_conditions: ctx
            .man
            .iter()
            .map(|m| {
                let v = m.reference.x_meas[state::V];
                (v, 0.5 * m.reference.rho_kgpm3 * v * v)
            })
            .collect(),
    })
}

#[cfg(test)]
mod tests;
