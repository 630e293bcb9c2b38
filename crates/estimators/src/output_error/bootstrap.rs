//! Parametric bootstrap of an output-error fit: the σ of the converged estimator, process noise
//! included (the parametric bootstrap of Efron & Tibshirani, *An Introduction to the
//! Bootstrap*, 1993; chapter numbers are not quoted: they were not checked against the book).
//!
//! # Why
//!
//! Output error's σ (Cramér–Rao, or the coloured-residual sandwich of
//! [`crate::coloured::batch`]) is the σ of the fit's **linearisation**. In turbulence the
//! converged fit scatters more than that: measured on the F-16 campaign with the exact model
//! (docs/uncertainty.md, "Output error in turbulence: what limits its coverage"), the
//! linearised estimator's coverage is 89–92 % on the yaw derivatives but the converged fit of
//! `CY_β, Cl_β, Cn_β, Cn_δr` scatters 1.3–1.7× more, and its ±2σ coverage falls to 77–82 %. A
//! residual bootstrap (additive noise of the residuals' spectrum) does not see this (its refits
//! scatter 0.98–1.06× the linearisation, measured): the excess comes from the gusts acting
//! through the dynamics, so the replicas must be flown through the model with process noise.
//!
//! # A replica
//!
//! At the fitted unknowns `β̂` (structure parameters, output biases, free initial states), per
//! manoeuvre from its fitted initial state, over the recorded inputs:
//!
//! ```text
//! x_{k+1} = RK4(x_k, u_k → u_{k+1}; θ̂) + F √Δt_k w_k,    z_k = h(x_k, u_k; θ̂) + b̂ + √R v_k
//! ```
//!
//! with `w_k, v_k` independent standard normal draws (supplied by the caller), `F` the process
//! noise per state (state unit per √s; Euler–Maruyama, the first-order `Q = F Fᵀ Δt` of the
//! filter-error method) and `R` the measurement-noise variances per output. The noise levels
//! come from the record itself, never from a reference: [`BootstrapNoise::from_fem`] takes the
//! filter-error method's `F` and `R` ([`super::filter_error`]), fitted to the same data. The
//! replica is then refitted by [`super::fit`] with the same configuration, started at `θ̂`; the
//! σ is the sample standard deviation of the refitted parameters over the replicas
//! ([`spread`]), and the mean of the refits less the estimate is the bootstrap's estimate of
//! the fit's bias ([`bias`]; reported, never subtracted: with `B` replicas it carries a
//! sampling error of `σ/√B`, and on the F-16 campaign it is right on average but uncorrelated
//! with each run's error, docs/uncertainty.md, "The bootstrap's bias estimate").
//!
//! # Cost
//!
//! One output-error fit per replica (fewer iterations than the original: the start is the
//! optimum of a nearby problem), plus the filter-error fit for the noise levels.

use super::filter_error::FemResult;
use super::{OeConfig, OeError, OeResult, Start, fit_prepared, prepare};
use crate::EstimatorError;
use crate::sample::AirDataSample;
use std::vec;
use std::vec::Vec;

/// The noise the replicas are flown with.
#[derive(Debug, Clone, PartialEq)]
pub struct BootstrapNoise {
    /// `(full-state index, F)` (indices of [`crate::flight_model::state`]): white process
    /// noise on that state equation, state unit per √s (e.g. rad/√s on `α`). States outside
    /// the structure's state set are ignored.
    pub process_noise: Vec<(usize, f64)>,
    /// Measurement-noise variance per output, order of the fitted result's `outputs`, the
    /// output's unit squared.
    pub measurement_var: Vec<f64>,
}

impl BootstrapNoise {
    /// The noise the filter-error method estimated on the same data: its process noise `F`
    /// per state and its measurement-noise variances `R` (not the innovations' variance).
    pub fn from_fem(fem: &FemResult) -> Self {
        let process_noise = fem
            .process_noise_states
            .iter()
            .filter_map(|&i| fem.process_noise(i).map(|(f, _)| (i, f)))
            .collect();
        Self { process_noise, measurement_var: fem.result.r.clone() }
    }
}

/// One replica: the record re-flown at the fitted unknowns with `noise` (module doc), refitted
/// by output error with `config` started at the fitted parameters. Returns every refitted
/// unknown, order of `fitted.names`: the structure parameters, then the output biases, then
/// the free initial states (so the bootstrap σ covers the initial states too).
///
/// `manoeuvres` and `config` must be those of `fitted` (same outputs, biases and initial-state
/// setting); `normal` draws independent standard normal numbers (the caller seeds it).
///
/// # Errors
/// [`OeError::Estimator`] with [`EstimatorError::InvalidConfig`] when `noise` does not match
/// the fit (number of outputs, a negative or non-finite level); the replica's simulation
/// leaving the physical domain ([`EstimatorError::Numerical`]); the refit failing or not
/// converging ([`OeError`]).
pub fn refit(
    manoeuvres: &[&[AirDataSample]],
    config: &OeConfig,
    fitted: &OeResult,
    noise: &BootstrapNoise,
    normal: &mut dyn FnMut() -> f64,
) -> Result<Vec<f64>, OeError> {
    let mut p = prepare(manoeuvres, config)?;
    let (ny, np) = (p.ny(), p.np);
    let invalid = |field, value: f64, reason| -> OeError {
        EstimatorError::InvalidConfig { field, value, reason }.into()
    };
    if p.outputs != fitted.outputs || fitted.values.len() != p.n_unknowns {
        return Err(invalid(
            "fitted",
            fitted.values.len() as f64,
            "the fitted result is not a fit of these manoeuvres with this configuration",
        ));
    }
    if noise.measurement_var.len() != ny {
        return Err(invalid(
            "measurement_var",
            noise.measurement_var.len() as f64,
            "one measurement-noise variance per fitted output is needed",
        ));
    }
    let levels = noise.measurement_var.iter().chain(noise.process_noise.iter().map(|(_, f)| f));
    if let Some(bad) = levels.copied().find(|v| !(v.is_finite() && *v >= 0.0)) {
        return Err(invalid("noise", bad, "noise levels must be finite and non-negative"));
    }
    let states = p.model.state_set().states();
    let noisy: Vec<(usize, f64)> = noise
        .process_noise
        .iter()
        .filter_map(|&(i, f)| states.iter().position(|&s| s == i).map(|k| (k, f)))
        .collect();
    let sd: Vec<f64> = noise.measurement_var.iter().map(|v| libm::sqrt(*v)).collect();
    let beta = &fitted.values;
    let mut yrow = vec![0.0; ny];
    for m in 0..p.man.len() {
        let mut x = p.x0(m, beta);
        // The replica's own "first sample": where a fixed initial state is taken from.
        p.man[m].x0_meas = x;
        let n = p.man[m].u.len();
        for i in 0..n {
            let u = p.man[m].u[i];
            p.check_state(&x, u.t_s)?;
            let k1 = p.outputs_at(beta, &u, &x, &mut yrow)?;
            for j in 0..ny {
                p.man[m].z[i * ny + j] = yrow[j] + sd[j] * normal();
            }
            if i + 1 == n {
                break;
            }
            let u1 = p.man[m].u[i + 1];
            x = p.rk4_step(&beta[..np], &u, &u1, &x, k1)?;
            let sqrt_dt = libm::sqrt(u1.t_s - u.t_s);
            for &(k, f) in &noisy {
                x[k] += f * sqrt_dt * normal();
            }
        }
    }
    let mut cfg = config.clone();
    cfg.start = Start::Given(beta[..np].to_vec());
    // A replica that does not converge (not even in the cost) is a failed replica.
    let r = fit_prepared(p, manoeuvres, &cfg)?.into_outcome()?;
    Ok(r.values)
}

/// The bootstrap σ: per unknown, the sample standard deviation (`n − 1`) of the refits
/// (`refits[b][i]`, replica `b`, unknown `i`); `None` with fewer than two refits or refits of
/// different lengths.
pub fn spread(refits: &[Vec<f64>]) -> Option<Vec<f64>> {
    let n = refits.len();
    let np = refits.first()?.len();
    if n < 2 || refits.iter().any(|r| r.len() != np) {
        return None;
    }
    let nf = n as f64;
    Some(
        (0..np)
            .map(|i| {
                let mean = refits.iter().map(|r| r[i]).sum::<f64>() / nf;
                let ss = refits.iter().map(|r| (r[i] - mean) * (r[i] - mean)).sum::<f64>();
                libm::sqrt(ss / (nf - 1.0))
            })
            .collect(),
    )
}

/// The bootstrap's estimate of the fit's bias: per unknown, the mean of the refits
/// (`refits[b][i]`) less the estimate (`estimate[i]`), in the unknown's unit. Its own
/// sampling error is the bootstrap σ over `√refits.len()`. `None` with no refits or refits whose
/// length differs from `estimate`'s.
pub fn bias(refits: &[Vec<f64>], estimate: &[f64]) -> Option<Vec<f64>> {
    let np = estimate.len();
    if refits.is_empty() || refits.iter().any(|r| r.len() != np) {
        return None;
    }
    let nf = refits.len() as f64;
    Some((0..np).map(|i| refits.iter().map(|r| r[i]).sum::<f64>() / nf - estimate[i]).collect())
}
