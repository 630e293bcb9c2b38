//! The Cramér–Rao bound of an experiment flown in turbulence: the Fisher information of the
//! output-error problem with the Dryden gusts as coloured process noise — the mean term exact
//! in the time domain (innovations form), the covariance term asymptotic (Whittle) in the
//! frequency domain.
//!
//! Sources: P. Whittle, "The analysis of multiple stationary time series", J. R. Stat. Soc. B
//! 15, 1953 (the asymptotic likelihood of a stationary Gaussian series from its DFT); L. Ljung,
//! *System Identification*, 2nd ed., 1999, ch. 9 (asymptotic covariance of prediction-error
//! estimates, the frequency-domain expressions); Klein & Morelli 2006 ch. 7 (frequency-domain
//! output error); F. C. Schweppe, "Evaluation of likelihood functions for Gaussian signals",
//! IEEE Trans. Inf. Theory 11, 1965 (the innovations form of the Gaussian likelihood);
//! C. F. Van Loan, "Computing integrals involving the matrix exponential", IEEE TAC 23, 1978
//! (exact discretisation of the noise model); Stevens & Lewis 3rd ed. §2.3 and §2.6 (wind-axis states from body
//! velocities). Section and equation numbers are not quoted: they were not checked against
//! the books.
//!
//! # Why
//!
//! [`super::predict_crb`] is the bound of a calm-air experiment: white sensor noise only. In
//! turbulence the gusts are noise on every output (and, through the covariance's dependence on
//! the parameters, extra information), so the achievable scatter of an experiment flown in
//! turbulence differs from that bound. This module gives the bound of the experiment actually
//! flown.
//!
//! # Model (linearised about the condition, frozen turbulence)
//!
//! The estimators' flight model integrates the **air-relative** `V, α, β` (module doc of
//! [`crate::flight_model`]). With the wind `g = (u_g, v_g, w_g)` in body axes (the air's
//! velocity over the ground; air-relative velocity = inertial − `g`), the force equations hold
//! for the inertial velocity: `u̇_i = r v_i − q w_i − g₀ sin θ + a_x(air-relative)` and so on.
//! Writing `u_a = u_i − u_g`, `u̇_a = u̇_i − u̇_g`; the kinematic terms `r v_g − q w_g …` are
//! products of two perturbations about wings-level trim (`p = q = r = 0`) and drop out of the
//! linearisation. With `(V, α, β) = Ψ(u_a, v_a, w_a)`, `d(V, α, β)/dt = ∂Ψ/∂(u,v,w) (u̇_i − ġ)`,
//! so the linearised model is `ẋ = A x + B δ − Γ ġ` with `Γ = ∂Ψ/∂(u, v, w)` at the condition
//! (rows of the integrated states among `V, α, β`):
//!
//! ```text
//! ∂V = cos α cos β ∂u + sin β ∂v + sin α cos β ∂w
//! ∂α = (cos α ∂w − sin α ∂u) / (V cos β)
//! ∂β = (−cos α sin β ∂u + cos β ∂v − sin α sin β ∂w) / V
//! ```
//!
//! (the derivatives of `V = |(u,v,w)|`, `α = atan(w/u)`, `β = asin(v/V)`). The outputs
//! `y = h(x, δ, θ)` see the gusts only through the states (air data are air-relative,
//! accelerometers measure aerodynamic + thrust specific force). The transfer from `g` to `y`
//! is `G_g(s) = −C (sI − A)⁻¹ Γ s` (zero at `s = 0`: a steady wind does not change the
//! air-relative motion). `A = ∂f/∂x`, `C = ∂h/∂x` are [`FlightModel::linearise`]'s exact
//! partials at the condition with the trim controls (the mean response and its sensitivities
//! stay those of the nonlinear simulation); `∂A/∂θ`, `∂C/∂θ` are central differences
//! of that linearisation in `θ` (exact for terms linear in `θ`, which is all of them except
//! through the implicit α̇ equation; step `10⁻⁴ max(1, |θ_j|)`).
//!
//! Approximations (stated, not hidden): linearisation about the condition (the turbulence
//! response and its parameter dependence are those of the small-perturbation model; the mean
//! response keeps the nonlinear simulation); frozen turbulence at the condition's airspeed
//! (the caller's spectra); no angular gusts (as the simulator); the continuous-time transfer
//! function evaluated at the DFT frequencies (aliasing neglected, accurate well below the
//! Nyquist frequency, covariance term only); an α̇ term's dependence on `ġ` is neglected; the
//! asymptotic independence of DFT bins in the covariance term (Whittle), whose error is of the
//! order of (correlation time of the noise) / (record length); the gusts sampled as the
//! continuous filters (the simulator interpolates its samples linearly).
//!
//! # Information
//!
//! The noise is Gaussian with the output covariance `K(θ)` of the augmented linear model
//! (flight states plus the gust shaping filters' states, [`GustModel`]) plus the plan's white
//! sensor noise `R = diag(σ_j²)`; the mean is the noise-free nonlinear response `μ(θ)`. The
//! Fisher information is `F = ∂μᵀ K⁻¹ ∂μ + ½ tr(K⁻¹ ∂K K⁻¹ ∂K)`, computed in two parts:
//!
//! 1. **Mean term, exact** ([`innovations_information`]): `∂μ` are the exact time-domain
//!    sensitivities of the output-error simulation ([`super::predict_crb`]'s `S = ∂y/∂β`,
//!    transients and initial conditions included), whitened by the time-varying Kalman filter
//!    of the augmented model discretised exactly (Van Loan 1978) at the sample interval; the
//!    flight states start known (as the fit's initial state), the gust filters stationary.
//!    With zero gust intensity the filter passes `S` unchanged and the term is the calm-air
//!    `Σ Sᵀ R⁻¹ S`: the two bounds coincide without turbulence (to rounding).
//! 2. **Covariance term, asymptotic (Whittle)**: with DFTs at `ω_k = 2πk/(NΔt)`,
//!    `k = 1 … ⌊N/2⌋`, the noise DFT is `CN(0, N Φ_y(ω_k))` asymptotically independent across
//!    bins, with the output spectral density (discrete normalisation, `E|Z_k|² ≈ N Φ(ω_k)`)
//!    `Φ_y = G_g Φ_g G_gᴴ + R`, `Φ_g = diag(|H_u|², |H_v|², |H_w|²)/Δt` (the shaping filters'
//!    responses: `π Φ(ω)/Δt` for a one-sided PSD `Φ`). Per complex bin
//!    `F_ij += tr(Φ_y⁻¹ ∂_iΦ_y Φ_y⁻¹ ∂_jΦ_y)`, half that at `k = N/2`; `∂Φ_y` from
//!    `∂G_g = ∂C X + C (sI − A)⁻¹ ∂A X`, `X = −(sI − A)⁻¹ Γ s` ([`add_bin_information`]).
//!
//! Why not Whittle for the mean term too: the gust enters through its rate, so the noise
//! spectrum has a zero at DC, where the record's end transients (the change of the wind over
//! the record) dominate the low DFT bins; the asymptotic mean term then overstates the
//! information grossly on records of a few correlation times (10× on a test system of 150
//! samples, tests). The covariance term has no such problem (tests: within 1 % at 400
//! samples, 10 % at 150).
//!
//! The covariance term is information an estimator gets only by modelling the turbulence
//! spectrum and how it depends on `θ` (a filter-error / full maximum-likelihood estimator); an
//! output-error fit that treats the response to the gusts as white noise cannot reach the
//! bound. The unknowns, identifiability analysis and reported σ are those of
//! [`super::predict_crb`].

use super::super::simulation::Problem;
use super::{DesignPlan, DesignResult, Prepared, analyse_and_report, condition_sample, prepare};
use crate::EstimatorError;
use crate::flight_model::{FlightModel, Linearisation, ModelInputs, state};
use nalgebra::{Complex, DMatrix, DVector};
use std::vec;
use std::vec::Vec;

/// A complex matrix.
pub type CMatrix = DMatrix<Complex<f64>>;

/// A continuous-time shaping filter `ẋ = a x + b η`, `g = c·x` driven by unit-intensity white
/// noise `η` (`E[η(t)η(s)] = δ(t − s)`), so that the gust's one-sided PSD is
/// `Φ(ω) = |H(iω)|²/π` with `H(s) = c (sI − a)⁻¹ b` (`∫₀^∞ Φ dω = σ²`; the signals crate's
/// Dryden convention). Shapes: `a` `n × n`, `b` and `c` length `n`; gust output in m/s, time
/// in s.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapingFilter {
    /// State matrix, 1/s.
    pub a: DMatrix<f64>,
    /// Noise input vector.
    pub b: DVector<f64>,
    /// Output vector (m/s per unit state).
    pub c: DVector<f64>,
}

impl ShapingFilter {
    /// `H(iω)`.
    fn response(&self, omega: f64) -> Result<Complex<f64>, EstimatorError> {
        let n = self.a.nrows();
        let m = CMatrix::from_fn(n, n, |i, j| {
            Complex::new(-self.a[(i, j)], if i == j { omega } else { 0.0 })
        });
        let x = m.lu().solve(&self.b.map(|v| Complex::new(v, 0.0))).ok_or(singular())?;
        Ok(x.iter().zip(self.c.iter()).map(|(x, c)| x * *c).sum())
    }
}

/// The gusts `(u_g, v_g, w_g)` in body axes (m/s, the air's velocity over the ground) as three
/// independent shaping filters (e.g. Dryden, MIL-F-8785C, frozen at the condition's airspeed).
#[derive(Debug, Clone, PartialEq)]
pub struct GustModel {
    /// `u_g`, `v_g`, `w_g`.
    pub filters: [ShapingFilter; 3],
}

fn singular() -> EstimatorError {
    EstimatorError::Numerical { what: "singular matrix in the turbulent CRB", t_s: 0.0 }
}

/// The mean term of the exact Gaussian Fisher information of a linear state-space noise model,
/// by the innovations (Kalman) factorisation of the output covariance `K = L B Lᵀ`:
/// `Σ_t ∂μ_tᵀ K⁻¹ ∂μ_t = Σ_t ε_tᵀ B_t⁻¹ ε_t`, with `ε` the innovations of the deterministic
/// sensitivity signals through the time-varying Kalman filter of the noise model
/// `z_{t+1} = Φ z_t + w_t` (`w ~ N(0, Q)`), `n_t = H z_t + v_t` (`v ~ N(0, diag(r))`),
/// `z_0 ~ N(0, P0)` (Klein & Morelli 2006 ch. 5, the filter-error cost; Schweppe's innovations
/// form of the Gaussian likelihood). Exact for any record length.
///
/// `s`: the mean sensitivities `n_t × ny × nb`, row-major (as the output-error simulation
/// writes them); returns `nb × nb`.
///
/// # Errors
/// [`EstimatorError::Numerical`] when an innovation covariance is not positive definite.
#[allow(clippy::too_many_arguments)]
pub fn innovations_information(
    phi: &DMatrix<f64>,
    q: &DMatrix<f64>,
    h: &DMatrix<f64>,
    r: &[f64],
    p0: &DMatrix<f64>,
    s: &[f64],
    n_t: usize,
    nb: usize,
) -> Result<DMatrix<f64>, EstimatorError> {
    let (ny, nz) = (h.nrows(), h.ncols());
    let mut p = p0.clone();
    let mut zhat = DMatrix::<f64>::zeros(nz, nb);
    let mut info = DMatrix::<f64>::zeros(nb, nb);
    let rm = DMatrix::from_diagonal(&DVector::from_column_slice(r));
    for t in 0..n_t {
        let st = DMatrix::from_row_slice(ny, nb, &s[t * ny * nb..(t + 1) * ny * nb]);
        let ph = &p * h.transpose();
        let b = h * &ph + &rm;
        let binv = b.cholesky().ok_or(EstimatorError::Numerical {
            what: "innovation covariance not positive definite",
            t_s: 0.0,
        })?;
        let e = st - h * &zhat;
        let be = binv.solve(&e);
        info += e.transpose() * &be;
        // Gain K = P Hᵀ B⁻¹: updated estimate and covariance, then the time update.
        zhat += &ph * &be;
        let kt = binv.solve(&ph.transpose());
        p -= &ph * kt;
        zhat = phi * zhat;
        p = phi * &p * phi.transpose() + q;
        p = (&p + p.transpose()) * 0.5;
    }
    Ok(info)
}

/// Van Loan (1978): `(Φ, Q_d)` of `ż = F z + G η` (unit-intensity white `η`) over `dt`.
fn van_loan(f: &DMatrix<f64>, g: &DMatrix<f64>, dt: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = f.nrows();
    let q = g * g.transpose();
    let mut m = DMatrix::<f64>::zeros(2 * n, 2 * n);
    for i in 0..n {
        for j in 0..n {
            m[(i, j)] = -f[(i, j)] * dt;
            m[(i, n + j)] = q[(i, j)] * dt;
            m[(n + i, n + j)] = f[(j, i)] * dt;
        }
    }
    let e = m.exp();
    let phi = DMatrix::from_fn(n, n, |i, j| e[(n + j, n + i)]);
    let e12 = DMatrix::from_fn(n, n, |i, j| e[(i, n + j)]);
    let qd = &phi * e12;
    (phi, (&qd + qd.transpose()) * 0.5)
}

/// Stationary covariance of `z_{t+1} = Φ z_t + w`, `w ~ N(0, Q)` (doubling; `Φ` stable).
fn stationary_covariance(phi: &DMatrix<f64>, q: &DMatrix<f64>) -> DMatrix<f64> {
    let (mut a, mut p) = (phi.clone(), q.clone());
    for _ in 0..60 {
        p = &p + &a * &p * a.transpose();
        a = &a * &a;
        if a.norm() < 1e-14 {
            break;
        }
    }
    p
}

/// DFT `Z_k = Σ_t z_t e^{−i 2π k t / N}` of the `width` columns of the row-major `n × width`
/// array `x`, for `k = 0 … ⌊n/2⌋`: `out[k][c]`. Direct evaluation with a table of the `n`
/// roots of unity (`O(n² width / 2)`), exact to rounding.
pub fn dft_positive(x: &[f64], n: usize, width: usize) -> Vec<Vec<Complex<f64>>> {
    let tau = 2.0 * core::f64::consts::PI / n as f64;
    let table: Vec<Complex<f64>> =
        (0..n).map(|m| Complex::new((tau * m as f64).cos(), -(tau * m as f64).sin())).collect();
    (0..=n / 2)
        .map(|k| {
            let mut acc = vec![Complex::new(0.0, 0.0); width];
            let mut idx = 0usize;
            for t in 0..n {
                let w = table[idx];
                let row = &x[t * width..(t + 1) * width];
                for (a, &v) in acc.iter_mut().zip(row) {
                    if v != 0.0 {
                        *a += w * v;
                    }
                }
                idx += k;
                if idx >= n {
                    idx -= n;
                }
            }
            acc
        })
        .collect()
}

/// Adds one DFT bin's Whittle Fisher information (module doc) to `m` (`nb × nb`).
///
/// `n`: samples of the record; `real_bin`: `k = 0` or `k = N/2` (real DFT); `phi`: the output
/// spectral density `Φ_y` (`ny × ny`, Hermitian positive definite, discrete normalisation);
/// `dphi[i]`: `∂Φ_y/∂β_i` (`None`: independent of `β_i`; length `nb`); `dmu`: the DFT of the
/// mean sensitivities `∂μ_k/∂β` (`ny × nb`; `None`: the mean term is left out, e.g. when it is
/// computed exactly in the time domain by [`innovations_information`]).
///
/// # Errors
/// [`EstimatorError::Numerical`] when `Φ_y` is not positive definite.
pub fn add_bin_information(
    n: usize,
    real_bin: bool,
    phi: &CMatrix,
    dphi: &[Option<CMatrix>],
    dmu: Option<&CMatrix>,
    m: &mut DMatrix<f64>,
) -> Result<(), EstimatorError> {
    let inv = phi.clone().cholesky().map(|c| c.inverse()).ok_or(EstimatorError::Numerical {
        what: "output spectral density not positive definite",
        t_s: 0.0,
    })?;
    let nb = m.nrows();
    if let Some(dmu) = dmu {
        let w_mean = if real_bin { 1.0 } else { 2.0 } / n as f64;
        let fm = dmu.adjoint() * (&inv * dmu);
        for i in 0..nb {
            for j in 0..nb {
                m[(i, j)] += w_mean * fm[(i, j)].re;
            }
        }
    }
    let w_cov = if real_bin { 0.5 } else { 1.0 };
    let mats: Vec<(usize, CMatrix)> =
        dphi.iter().enumerate().filter_map(|(i, d)| d.as_ref().map(|d| (i, &inv * d))).collect();
    for (a, (i, mi)) in mats.iter().enumerate() {
        for (j, mj) in &mats[a..] {
            // tr(Mi Mj) = Σ_pq Mi[p,q] Mj[q,p].
            let mut tr = Complex::new(0.0, 0.0);
            for p in 0..mi.nrows() {
                for q in 0..mi.ncols() {
                    tr += mi[(p, q)] * mj[(q, p)];
                }
            }
            m[(*i, *j)] += w_cov * tr.re;
            if i != j {
                m[(*j, *i)] += w_cov * tr.re;
            }
        }
    }
    Ok(())
}

/// `Γ` (rows: the integrated states of `set` in filter order; columns `u, v, w`): the
/// linearised map from a body-axis velocity change to the air-relative `(V, α, β)` at
/// airspeed `vt`, angle of attack `alpha` and sideslip `beta` (module doc); zero rows for the
/// other states.
pub fn gust_input_matrix(states: &[usize], vt: f64, alpha: f64, beta: f64) -> DMatrix<f64> {
    let (sa, ca, sb, cb) = (alpha.sin(), alpha.cos(), beta.sin(), beta.cos());
    DMatrix::from_fn(states.len(), 3, |r, c| {
        let row = match states[r] {
            state::V => [ca * cb, sb, sa * cb],
            state::ALPHA => [-sa / (vt * cb), 0.0, ca / (vt * cb)],
            state::BETA => [-ca * sb / vt, cb / vt, -sa * sb / vt],
            _ => [0.0; 3],
        };
        row[c]
    })
}

/// The real state and output matrices `(A, C)` of the linearisation (`nx × nx`, `ny × nx`).
fn matrices(lin: &Linearisation, nx: usize, outputs: &[usize]) -> (DMatrix<f64>, DMatrix<f64>) {
    (
        DMatrix::from_fn(nx, nx, |r, c| lin.dfdx[r][c]),
        DMatrix::from_fn(outputs.len(), nx, |r, c| lin.dydx[outputs[r]][c]),
    )
}

fn to_c(m: &DMatrix<f64>) -> CMatrix {
    m.map(|v| Complex::new(v, 0.0))
}

/// Predicts the Cramér–Rao σ of every unknown of `plan` flown in the turbulence `gusts`
/// (module doc): the exact mean term by the innovations factorisation
/// ([`innovations_information`]) plus the Whittle covariance term, with the gusts as process
/// noise and the plan's sensors as white measurement noise. With zero gust intensity it equals
/// [`super::predict_crb`]. Same result type, unknowns and identifiability analysis as
/// [`super::predict_crb`]; `information` is this `F`.
///
/// # Errors
/// As [`super::predict_crb`]; [`EstimatorError::InvalidConfig`] naming `gusts` when a shaping
/// filter's shapes disagree or it is not finite; [`EstimatorError::Numerical`] when a matrix of
/// the computation is singular (e.g. `sI − A` with an undamped mode exactly on the DFT grid).
pub fn predict_crb_turbulent(
    plan: &DesignPlan,
    gusts: &GustModel,
) -> Result<DesignResult, EstimatorError> {
    check_gust_filters(gusts)?;
    let Prepared { problem: p, beta, weights } = prepare(plan)?;
    let (nb, ny) = (p.n_unknowns, p.ny());
    let (mut y, mut s) = (Vec::new(), Vec::new());
    p.simulate(&beta, &mut y, Some(&mut s))?;
    let noise = TurbulentNoise::new(plan, gusts, &p, &weights)?;
    let mut info = DMatrix::<f64>::zeros(nb, nb);
    let mut row0 = 0;
    for (man, planned) in p.man.iter().zip(&plan.manoeuvres) {
        let n = man.u.len();
        let dt = planned.dt_s;
        let block = &s[row0 * ny * nb..(row0 + n) * ny * nb];
        info += noise.mean_information(n, dt, block, nb)?;
        noise.add_covariance_information(n, dt, &mut info)?;
        row0 += n;
    }
    info *= plan.repeats as f64;
    analyse_and_report(plan, &p, beta, &y, info)
}

/// Refuses a shaping filter whose `a` is not square, whose `b`, `c` are not of its size, that
/// is empty, or that has a non-finite entry: the noise model below assumes all of them.
fn check_gust_filters(gusts: &GustModel) -> Result<(), EstimatorError> {
    for f in &gusts.filters {
        let n = f.a.nrows();
        if f.a.ncols() != n || f.b.len() != n || f.c.len() != n || n == 0 {
            return Err(EstimatorError::InvalidConfig {
                field: "gusts",
                value: n as f64,
                reason: "a shaping filter needs a square `a` and `b`, `c` of its size",
            });
        }
        if let Some(v) = f.a.iter().chain(f.b.iter()).chain(f.c.iter()).find(|v| !v.is_finite()) {
            return Err(EstimatorError::InvalidConfig {
                field: "gusts",
                value: *v,
                reason: "shaping filter entries must be finite",
            });
        }
    }
    Ok(())
}

/// The θ-derivatives `(∂A/∂θ_j, ∂C/∂θ_j)` of the linearisation, by central differences with
/// step `10⁻⁴ · max(|θ_j|, 1)`, for the first `np` of the `nb` unknowns (biases and initial
/// states do not enter `A`, `C`); `None` where both vanish (a parameter the linear model does
/// not see). `lin` is the linearisation buffer, overwritten.
fn theta_derivatives(
    model: &FlightModel,
    theta: &[f64],
    u: &ModelInputs,
    active: &[f64],
    out_idx: &[usize],
    (nb, np): (usize, usize),
    lin: &mut Linearisation,
) -> Result<Vec<Option<(CMatrix, CMatrix)>>, EstimatorError> {
    let nx = active.len();
    let mut da: Vec<Option<(CMatrix, CMatrix)>> = vec![None; nb];
    for (j, slot) in da.iter_mut().enumerate().take(np) {
        let h = 1e-4 * theta[j].abs().max(1.0);
        let mut th = theta.to_vec();
        th[j] += h;
        model.linearise(&th, u, active, lin)?;
        let (ap, cp) = matrices(lin, nx, out_idx);
        th[j] -= 2.0 * h;
        model.linearise(&th, u, active, lin)?;
        let (am, cmm) = matrices(lin, nx, out_idx);
        let dam = (ap - am) / (2.0 * h);
        let dcm = (cp - cmm) / (2.0 * h);
        if dam.iter().chain(dcm.iter()).any(|v| *v != 0.0) {
            *slot = Some((to_c(&dam), to_c(&dcm)));
        }
    }
    Ok(da)
}

/// The augmented continuous noise model `(F_z, G_z)` over `z = (x, gust filter states)`
/// (module doc): `ẋ = A x − Γ ġ`, `ġ = Cg (Ag xg + Bg η)`, `ẋg = Ag xg + Bg η`, one white
/// `η` per gust component.
fn augmented_noise_model(
    a: &DMatrix<f64>,
    gamma: &DMatrix<f64>,
    gusts: &GustModel,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let nx = a.nrows();
    let ng: usize = gusts.filters.iter().map(|f| f.a.nrows()).sum();
    let nz = nx + ng;
    let mut fz = DMatrix::<f64>::zeros(nz, nz);
    let mut gz = DMatrix::<f64>::zeros(nz, 3);
    fz.view_mut((0, 0), (nx, nx)).copy_from(a);
    let mut off = nx;
    for (k, f) in gusts.filters.iter().enumerate() {
        let n = f.a.nrows();
        let cga = f.c.transpose() * &f.a; // 1 × n
        let cgb = f.c.dot(&f.b);
        for i in 0..nx {
            for j in 0..n {
                fz[(i, off + j)] = -gamma[(i, k)] * cga[(0, j)];
            }
            gz[(i, k)] = -gamma[(i, k)] * cgb;
        }
        fz.view_mut((off, off), (n, n)).copy_from(&f.a);
        for j in 0..n {
            gz[(off + j, k)] = f.b[j];
        }
        off += n;
    }
    (fz, gz)
}

/// The turbulent experiment's noise model at the condition, the same for every manoeuvre:
/// the augmented model `(F_z, G_z, H_z)` for the exact mean term, the linearisation
/// `(A, C, Γ)` and its θ-derivatives (complex) for the Whittle covariance term, and the
/// sensors' white noise variances `R`.
struct TurbulentNoise<'a> {
    gusts: &'a GustModel,
    nx: usize,
    ng: usize,
    fz: DMatrix<f64>,
    gz: DMatrix<f64>,
    hz: DMatrix<f64>,
    r: Vec<f64>,
    rc: CMatrix,
    ac: CMatrix,
    cc: CMatrix,
    gc: CMatrix,
    da: Vec<Option<(CMatrix, CMatrix)>>,
}

impl<'a> TurbulentNoise<'a> {
    /// Linearises the flight model at the plan's condition (trim controls), differentiates the
    /// linearisation in θ and builds the augmented noise model; `weights` are the sensors'
    /// `1/R`.
    fn new(
        plan: &DesignPlan,
        gusts: &'a GustModel,
        p: &Problem,
        weights: &[f64],
    ) -> Result<Self, EstimatorError> {
        let (nb, ny, np) = (p.n_unknowns, p.ny(), p.np);
        // Linearisation at the condition (trim controls) and its θ-derivatives.
        let model: FlightModel = p.model;
        let set = model.state_set();
        let states = set.states();
        let nx = states.len();
        let c = &plan.condition;
        let trim = condition_sample(&plan.constants, c, set, 0.0, [c.de_rad, c.da_rad, c.dr_rad]);
        let u = model.inputs(&trim)?;
        let active = super::condition_states(c, set);
        let out_idx: Vec<usize> = p.outputs.iter().map(|o| o.index()).collect();
        let mut lin = Linearisation::default();
        model.linearise(&plan.theta, &u, &active[..nx], &mut lin)?;
        let (a, cm) = matrices(&lin, nx, &out_idx);
        let da = theta_derivatives(
            &model,
            &plan.theta,
            &u,
            &active[..nx],
            &out_idx,
            (nb, np),
            &mut lin,
        )?;
        // Wings-level condition: β = 0.
        let gamma = gust_input_matrix(states, c.vt_mps, c.alpha_rad, 0.0);
        let (fz, gz) = augmented_noise_model(&a, &gamma, gusts);
        let ng = fz.nrows() - nx;
        let mut hz = DMatrix::<f64>::zeros(ny, nx + ng);
        hz.view_mut((0, 0), (ny, nx)).copy_from(&cm);
        let r: Vec<f64> = weights.iter().map(|w| 1.0 / w).collect();
        let rc = CMatrix::from_fn(ny, ny, |i, j| c64(if i == j { r[i] } else { 0.0 }));
        let (ac, cc, gc) = (to_c(&a), to_c(&cm), to_c(&gamma));
        Ok(Self { gusts, nx, ng, fz, gz, hz, r, rc, ac, cc, gc, da })
    }

    /// The mean term of one manoeuvre of `n` samples at interval `dt` (s), exact: the flight
    /// states start known (as the output-error fit's initial state), the gust filters
    /// stationary. `block` is the manoeuvre's output sensitivities.
    fn mean_information(
        &self,
        n: usize,
        dt: f64,
        block: &[f64],
        nb: usize,
    ) -> Result<DMatrix<f64>, EstimatorError> {
        let (nx, ng) = (self.nx, self.ng);
        let nz = nx + ng;
        let (phi, qd) = van_loan(&self.fz, &self.gz, dt);
        let mut p0 = DMatrix::<f64>::zeros(nz, nz);
        let pg = stationary_covariance(
            &phi.view((nx, nx), (ng, ng)).into_owned(),
            &qd.view((nx, nx), (ng, ng)).into_owned(),
        );
        p0.view_mut((nx, nx), (ng, ng)).copy_from(&pg);
        innovations_information(&phi, &qd, &self.hz, &self.r, &p0, block, n, nb)
    }

    /// Adds the covariance term of one manoeuvre of `n` samples at interval `dt` (s) to
    /// `info`, Whittle: one DFT bin `k = 1…n/2` at a time, the output spectrum
    /// `Φ_y = G Φ_g Gᴴ + R` and its θ-derivatives (the gusts through `X = −(sI − A)⁻¹ Γ s`,
    /// states per unit gust, and `G = C X`).
    fn add_covariance_information(
        &self,
        n: usize,
        dt: f64,
        info: &mut DMatrix<f64>,
    ) -> Result<(), EstimatorError> {
        let (nx, ac, cc) = (self.nx, &self.ac, &self.cc);
        for k in 1..=n / 2 {
            let omega = 2.0 * core::f64::consts::PI * k as f64 / (n as f64 * dt);
            let real_bin = 2 * k == n;
            let mut phi_g = CMatrix::zeros(3, 3);
            for (i, f) in self.gusts.filters.iter().enumerate() {
                phi_g[(i, i)] = c64(f.response(omega)?.norm_sqr() / dt);
            }
            let sc = Complex::new(0.0, omega);
            let si_a =
                CMatrix::from_fn(nx, nx, |i, j| (if i == j { sc } else { c64(0.0) }) - ac[(i, j)]);
            let hinv = si_a.lu().try_inverse().ok_or(singular())?;
            // X = −(sI − A)⁻¹ Γ s (states per unit gust), G = C X.
            let x = (&hinv * &self.gc) * (-sc);
            let g = cc * &x;
            let phi_y = &g * &phi_g * g.adjoint() + &self.rc;
            let dphi: Vec<Option<CMatrix>> = self
                .da
                .iter()
                .map(|d| {
                    d.as_ref().map(|(dai, dci)| {
                        let dg = dci * &x + cc * (&hinv * (dai * &x));
                        let t = &dg * &phi_g * g.adjoint();
                        &t + t.adjoint()
                    })
                })
                .collect();
            add_bin_information(n, real_bin, &phi_y, &dphi, None, info)?;
        }
        Ok(())
    }
}

fn c64(v: f64) -> Complex<f64> {
    Complex::new(v, 0.0)
}

#[cfg(test)]
mod tests;
