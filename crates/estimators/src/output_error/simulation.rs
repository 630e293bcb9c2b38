//! The output-error problem: the manoeuvres' inputs and measured outputs, the unknown vector
//! `β = (θ, output biases, free initial states)`, and the simulation of the model outputs with
//! their exact sensitivities `∂y/∂β`.
//!
//! # Simulation
//!
//! Classical RK4 over each sample interval with the inputs interpolated linearly between the two
//! samples (start, midpoint, end), as Jategaonkar 2015 ch. 4 `ruku4.m`; the outputs are
//! evaluated at every sample from the state there.
//!
//! # Sensitivities (exact, no finite differences)
//!
//! The sensitivities are the exact derivatives of the **discrete** RK4 map (Jategaonkar 2015
//! ch. 4 solves the sensitivity equations `Ẋ = A X + B` alongside the states; differentiating
//! the RK4 step itself gives the same equations integrated by the same scheme, so the result is
//! the derivative of the simulated outputs to rounding). With `X = ∂x/∂β` (`nx × nβ`) and, at
//! each RK4 stage `s` with stage state `x_s = x + c_s dt k_{s−1}`, `A_s = ∂f/∂x`, `B_s = ∂f/∂θ`
//! from [`FlightModel::linearise`] (forward-mode duals, exact):
//!
//! ```text
//! X_s = X + c_s dt K_{s−1},   K_s = A_s X_s + B_s,   X' = X + dt/6 (K1 + 2 K2 + 2 K3 + K4)
//! ∂y/∂β = C X + D (+ 1 in the column of the output's bias),  C = ∂h/∂x, D = ∂h/∂θ
//! ```
//!
//! and `X = ∂x0/∂β` at the first sample (the unit columns of the free initial states, else 0).

use crate::EstimatorError;
use crate::flight_model::{FlightModel, Linearisation, ModelInputs, N_STATES, Output, state};
use crate::sample::AirDataSample;
use std::vec;
use std::vec::Vec;

/// One manoeuvre, prepared: the model inputs and the measured outputs of every sample.
#[derive(Debug, Clone)]
pub(super) struct Manoeuvre {
    /// Model inputs per sample.
    pub u: Vec<ModelInputs>,
    /// Measured outputs, `n × ny` row-major.
    pub z: Vec<f64>,
    /// Measured integrated states at the first sample (filter order).
    pub x0_meas: [f64; N_STATES],
}

/// The prepared problem (module doc).
#[derive(Debug, Clone)]
pub(super) struct Problem {
    pub model: FlightModel,
    pub nx: usize,
    pub np: usize,
    pub outputs: Vec<Output>,
    /// For each selected output, the index of its bias in `β`, if estimated.
    pub bias_of: Vec<Option<usize>>,
    /// Filter-order indices of the integrated states whose initial values are estimated.
    pub x0_free: Vec<usize>,
    /// Filter-order indices of the integrated states with no measurement at the first sample
    /// of some manoeuvre: estimated (in `x0_free`) from a start of 0.
    pub unmeasured: Vec<usize>,
    pub man: Vec<Manoeuvre>,
    pub n_unknowns: usize,
    pub n_samples: usize,
}

/// Most values `N·ny·nβ` of the sensitivities `∂y/∂β` a problem may hold (1 GiB of f64).
/// The fit's peak memory is several times that ([`estimated_peak_bytes`]), which is what
/// [`MAX_FIT_BYTES`] limits; this bound is implied by it.
pub const MAX_SENSITIVITY_VALUES: usize = 1 << 27;

/// Most memory, bytes, a fit may be estimated to need at its peak ([`estimated_peak_bytes`]):
/// 2 GiB, checked before the manoeuvres are simulated.
pub const MAX_FIT_BYTES: f64 = 2.0 * (1u64 << 30) as f64;

/// The peak memory, bytes, of an output-error fit of `samples` samples (the longest manoeuvre
/// `longest`), `ny` outputs and `nb` unknowns. With `S = 8·N·ny·nβ` the sensitivities' bytes
/// and `T = 16·ny·nβ·(P/2 + 1)` the longest manoeuvre's half-spectrum transforms (`P` the
/// power of two at or above twice its length, `coloured::batch::spectral`): the fit and the
/// coloured-residual σ hold about eight arrays the size of `S` (sensitivities, their weighted
/// copy, the prewhitened form's filtered copies, run beside the spectral one) and two of `T`
/// (a manoeuvre's transforms and the frequencies kept), and the allocator keeps about half as
/// much again (heap profile and peak RSS of `replay --estimator oe` on one 20,000-sample
/// manoeuvre, 7 outputs × 12 unknowns: heap 206 MB, RSS 309 MB; 80,000 samples: RSS 1.22 GB).
pub fn estimated_peak_bytes(samples: usize, longest: usize, ny: usize, nb: usize) -> f64 {
    let row = (ny * nb) as f64;
    let sens = 8.0 * samples as f64 * row;
    let half = ((2 * longest).max(2).next_power_of_two() / 2 + 1) as f64;
    let transforms = 16.0 * row * half;
    1.5 * (8.0 * sens + 2.0 * transforms)
}

fn invalid(field: &'static str, value: f64, reason: &'static str) -> EstimatorError {
    EstimatorError::InvalidConfig { field, value, reason }
}

impl Problem {
    /// Prepares the problem; the checks are documented on [`super::fit`].
    pub fn new(
        model: FlightModel,
        manoeuvres: &[&[AirDataSample]],
        outputs: Vec<Output>,
        biases: &[Output],
        x0_free_full: &[bool; N_STATES],
    ) -> Result<Self, EstimatorError> {
        if manoeuvres.is_empty() {
            return Err(invalid("manoeuvres", 0.0, "at least one manoeuvre is needed"));
        }
        let set = model.state_set();
        let states = set.states();
        let nx = states.len();
        let np = model.structure().n_params();
        let ny = outputs.len();
        if ny == 0 {
            return Err(invalid("outputs", 0.0, "no output selected"));
        }
        let mut seen = [false; crate::flight_model::N_OUTPUTS];
        for o in &outputs {
            if !set.outputs().contains(o) {
                return Err(invalid(
                    o.name(),
                    o.index() as f64,
                    "this output is not predicted by the structure's state set",
                ));
            }
            if core::mem::replace(&mut seen[o.index()], true) {
                return Err(invalid(o.name(), o.index() as f64, "output selected twice"));
            }
        }
        let mut bias_of = vec![None; ny];
        for (k, b) in biases.iter().enumerate() {
            let Some(j) = outputs.iter().position(|o| o == b) else {
                return Err(invalid(b.name(), b.index() as f64, "bias on an output not selected"));
            };
            if bias_of[j].is_some() {
                return Err(invalid(b.name(), b.index() as f64, "bias declared twice"));
            }
            bias_of[j] = Some(np + k);
        }
        // A state without a measurement is still a state: its initial value is estimated.
        let unmeasured: Vec<usize> = (0..nx)
            .filter(|&k| {
                manoeuvres.iter().any(|m| {
                    m.first().is_some_and(|s| Output::ALL[states[k]].measured(s).is_none())
                })
            })
            .collect();
        let x0_free: Vec<usize> =
            (0..nx).filter(|&k| x0_free_full[states[k]] || unmeasured.contains(&k)).collect();
        let mut man = Vec::with_capacity(manoeuvres.len());
        let mut n_samples = 0;
        for samples in manoeuvres {
            if samples.len() < 2 {
                return Err(invalid(
                    "manoeuvres",
                    samples.len() as f64,
                    "a manoeuvre needs at least two samples",
                ));
            }
            let mut u = Vec::with_capacity(samples.len());
            let mut z = Vec::with_capacity(samples.len() * ny);
            let mut last_t = f64::NEG_INFINITY;
            for s in samples.iter() {
                crate::estimator::check_finite(s)?;
                if s.t_s <= last_t {
                    return Err(invalid(
                        "t_s",
                        s.t_s,
                        "sample times must increase strictly within a manoeuvre",
                    ));
                }
                last_t = s.t_s;
                u.push(model.inputs(s)?);
                for o in &outputs {
                    z.push(o.measured(s).ok_or(EstimatorError::NonFiniteInput {
                        field: o.name(),
                        value: f64::NAN,
                        t_s: s.t_s,
                    })?);
                }
            }
            let mut dts: Vec<f64> = samples.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
            dts.sort_by(f64::total_cmp);
            let median = dts[dts.len() / 2];
            if let Some(w) =
                samples.windows(2).find(|w| w[1].t_s - w[0].t_s > super::GAP_FACTOR * median)
            {
                return Err(invalid(
                    "t_s",
                    w[1].t_s,
                    "a time gap (> 10 median sample intervals) within a manoeuvre: split the record at its gaps (output_error::split_at_gaps)",
                ));
            }
            let mut x0_meas = [0.0; N_STATES];
            for (k, &i) in states.iter().enumerate() {
                x0_meas[k] = Output::ALL[i].measured(&samples[0]).unwrap_or(0.0);
            }
            n_samples += samples.len();
            man.push(Manoeuvre { u, z, x0_meas });
        }
        let n_unknowns = np + biases.len() + x0_free.len() * man.len();
        let longest = man.iter().map(|m| m.u.len()).max().unwrap_or(0);
        let bytes = estimated_peak_bytes(n_samples, longest, ny, n_unknowns);
        if bytes > MAX_FIT_BYTES {
            return Err(EstimatorError::TooLarge {
                samples: n_samples,
                outputs: ny,
                unknowns: n_unknowns,
                longest,
                bytes,
                limit: MAX_FIT_BYTES,
            });
        }
        if n_samples * ny <= n_unknowns {
            return Err(invalid(
                "manoeuvres",
                (n_samples * ny) as f64,
                "fewer measured values than unknowns",
            ));
        }
        Ok(Self {
            model,
            nx,
            np,
            outputs,
            bias_of,
            x0_free,
            unmeasured,
            man,
            n_unknowns,
            n_samples,
        })
    }

    /// Index in `β` of free initial state `q` (position in `x0_free`) of manoeuvre `m`.
    pub fn x0_index(&self, m: usize, q: usize) -> usize {
        self.np + self.n_biases() + m * self.x0_free.len() + q
    }

    pub fn n_biases(&self) -> usize {
        self.bias_of.iter().flatten().count()
    }

    pub fn ny(&self) -> usize {
        self.outputs.len()
    }

    /// Initial state of manoeuvre `m` (filter order) at `β`.
    pub fn x0(&self, m: usize, beta: &[f64]) -> [f64; N_STATES] {
        let mut x = self.man[m].x0_meas;
        for (q, &k) in self.x0_free.iter().enumerate() {
            x[k] = beta[self.x0_index(m, q)];
        }
        x
    }

    /// Simulated outputs `y` (`n_samples × ny`, manoeuvres concatenated) at `β`; with `sens`,
    /// also `∂y/∂β` (`n_samples × ny × nβ`, row-major).
    ///
    /// # Errors
    /// [`EstimatorError::Numerical`] when the simulated state leaves the physical domain (non
    /// finite, `V ≤ 0`, `|α|` or `|β| > 1.5 rad`) or the model's implicit α̇ equation is
    /// singular.
    pub fn simulate(
        &self,
        beta: &[f64],
        y: &mut Vec<f64>,
        mut sens: Option<&mut Vec<f64>>,
    ) -> Result<(), EstimatorError> {
        let (nx, np, ny, nb) = (self.nx, self.np, self.ny(), self.n_unknowns);
        let theta = &beta[..np];
        y.clear();
        y.resize(self.n_samples * ny, 0.0);
        if let Some(s) = sens.as_deref_mut() {
            s.clear();
            s.resize(self.n_samples * ny * nb, 0.0);
        }
        let with_sens = sens.is_some();
        let mut lin = Linearisation::default();
        // X (nx × nβ) and the stage derivatives K1..K4, each row-major.
        let mut xs = vec![0.0; if with_sens { nx * nb } else { 0 }];
        let mut xstage = xs.clone();
        let mut kk: [Vec<f64>; 4] = core::array::from_fn(|_| xs.clone());
        let mut row0 = 0;
        for (m, man) in self.man.iter().enumerate() {
            let mut x = self.x0(m, beta);
            if with_sens {
                xs.iter_mut().for_each(|v| *v = 0.0);
                for (q, &k) in self.x0_free.iter().enumerate() {
                    xs[k * nb + self.x0_index(m, q)] = 1.0;
                }
            }
            let n = man.u.len();
            for i in 0..n {
                let u = &man.u[i];
                self.check_state(&x, u.t_s)?;
                let yrow = &mut y[(row0 + i) * ny..(row0 + i + 1) * ny];
                let k1 = if let Some(sens) = sens.as_deref_mut() {
                    self.model.linearise(theta, u, &x[..nx], &mut lin)?;
                    let srow = &mut sens[(row0 + i) * ny * nb..(row0 + i + 1) * ny * nb];
                    for (j, o) in self.outputs.iter().enumerate() {
                        let k = o.index();
                        yrow[j] = lin.y[k];
                        let s = &mut srow[j * nb..(j + 1) * nb];
                        for c in 0..nx {
                            let cc = lin.dydx[k][c];
                            if cc != 0.0 {
                                for (sv, xv) in s.iter_mut().zip(&xs[c * nb..(c + 1) * nb]) {
                                    *sv += cc * xv;
                                }
                            }
                        }
                        for a in 0..np {
                            s[a] += lin.dydtheta[k][a];
                        }
                        if let Some(b) = self.bias_of[j] {
                            yrow[j] += beta[b];
                            s[b] += 1.0;
                        }
                    }
                    stage_sensitivity(&lin, nx, np, nb, &xs, &mut kk[0]);
                    lin.f
                } else {
                    self.outputs_at(beta, u, &x, yrow)?
                };
                if i + 1 == n {
                    break;
                }
                let u1 = &man.u[i + 1];
                if !with_sens {
                    x = self.rk4_step(theta, u, u1, &x, k1)?;
                    continue;
                }
                let dt = u1.t_s - u.t_s;
                let um = ModelInputs::lerp(u, u1, 0.5);
                let mut kf = [k1, [0.0; N_STATES], [0.0; N_STATES], [0.0; N_STATES]];
                for (s, (c, us)) in [(0.5, &um), (0.5, &um), (1.0, u1)].into_iter().enumerate() {
                    let mut xst = [0.0; N_STATES];
                    for r in 0..nx {
                        xst[r] = x[r] + c * dt * kf[s][r];
                    }
                    let (prev, next) = kk.split_at_mut(s + 1);
                    for (v, (x0v, kv)) in xstage.iter_mut().zip(xs.iter().zip(&prev[s])) {
                        *v = x0v + c * dt * kv;
                    }
                    self.model.linearise(theta, us, &xst[..nx], &mut lin)?;
                    stage_sensitivity(&lin, nx, np, nb, &xstage, &mut next[0]);
                    kf[s + 1] = lin.f;
                }
                for r in 0..nx {
                    x[r] += dt / 6.0 * (kf[0][r] + 2.0 * kf[1][r] + 2.0 * kf[2][r] + kf[3][r]);
                }
                for (idx, v) in xs.iter_mut().enumerate() {
                    *v +=
                        dt / 6.0 * (kk[0][idx] + 2.0 * kk[1][idx] + 2.0 * kk[2][idx] + kk[3][idx]);
                }
            }
            row0 += n;
        }
        Ok(())
    }

    /// The selected outputs `h(x, u, θ) + b` at state `x` (filter order) into `yrow`
    /// (length `ny`), and `f(x, u, θ)` (returned, filter order).
    ///
    /// # Errors
    /// As [`FlightModel::eval`].
    pub fn outputs_at(
        &self,
        beta: &[f64],
        u: &ModelInputs,
        x: &[f64; N_STATES],
        yrow: &mut [f64],
    ) -> Result<[f64; N_STATES], EstimatorError> {
        let xf = self.model.full_state(&x[..self.nx], u);
        let z8 = [0.0; 8];
        let d = self.model.eval(&beta[..self.np], u, &xf, &z8, &z8, None)?;
        for (j, o) in self.outputs.iter().enumerate() {
            yrow[j] = d.output(*o, &xf) + self.bias_of[j].map_or(0.0, |b| beta[b]);
        }
        let mut f = [0.0; N_STATES];
        for (k, &s) in self.model.state_set().states().iter().enumerate() {
            f[k] = d.xdot[s];
        }
        Ok(f)
    }

    /// One classical RK4 step (module doc) from state `x` at the sample with inputs `u` to the
    /// next sample with inputs `u1`, given `k1 = f(x, u)`; returns the state there.
    ///
    /// # Errors
    /// As [`FlightModel::eval`].
    pub fn rk4_step(
        &self,
        theta: &[f64],
        u: &ModelInputs,
        u1: &ModelInputs,
        x: &[f64; N_STATES],
        k1: [f64; N_STATES],
    ) -> Result<[f64; N_STATES], EstimatorError> {
        let nx = self.nx;
        let dt = u1.t_s - u.t_s;
        let um = ModelInputs::lerp(u, u1, 0.5);
        let mut kf = [k1, [0.0; N_STATES], [0.0; N_STATES], [0.0; N_STATES]];
        for (s, (c, us)) in [(0.5, &um), (0.5, &um), (1.0, u1)].into_iter().enumerate() {
            let mut xst = [0.0; N_STATES];
            for r in 0..nx {
                xst[r] = x[r] + c * dt * kf[s][r];
            }
            kf[s + 1] = self.model.derivatives(theta, us, &xst[..nx])?;
        }
        let mut out = *x;
        for r in 0..nx {
            out[r] += dt / 6.0 * (kf[0][r] + 2.0 * kf[1][r] + 2.0 * kf[2][r] + kf[3][r]);
        }
        Ok(out)
    }

    pub fn check_state(&self, x: &[f64; N_STATES], t_s: f64) -> Result<(), EstimatorError> {
        let states = self.model.state_set().states();
        let bad = x[..self.nx].iter().zip(states).any(|(v, &i)| {
            !v.is_finite()
                || (i == state::V && *v <= 0.0)
                || ((i == state::ALPHA || i == state::BETA) && v.abs() > 1.5)
        });
        if bad {
            Err(EstimatorError::Numerical {
                what: "simulated state left the physical domain (non-finite, V <= 0 or |alpha|, |beta| > 1.5 rad)",
                t_s,
            })
        } else {
            Ok(())
        }
    }
}

/// `K = A X + B` at one stage: `A = ∂f/∂x` (`nx × nx`), `B = ∂f/∂θ` in the first `np` columns.
fn stage_sensitivity(
    lin: &Linearisation,
    nx: usize,
    np: usize,
    nb: usize,
    xs: &[f64],
    k: &mut [f64],
) {
    for r in 0..nx {
        let kr = &mut k[r * nb..(r + 1) * nb];
        kr.iter_mut().for_each(|v| *v = 0.0);
        for c in 0..nx {
            let a = lin.dfdx[r][c];
            if a != 0.0 {
                for (kv, xv) in kr.iter_mut().zip(&xs[c * nb..(c + 1) * nb]) {
                    *kv += a * xv;
                }
            }
        }
        for j in 0..np {
            kr[j] += lin.dfdtheta[r][j];
        }
    }
}
