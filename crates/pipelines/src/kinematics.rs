//! Kinematic consistency of the body rates and the attitude: a rate channel read in the wrong
//! unit (rad/s data mapped as deg/s, or the reverse) is off by 180/π ≈ 57.3 against the
//! attitude it turns, and nothing else in the record says so.
//!
//! The Euler kinematics (Stevens & Lewis, *Aircraft Control and Simulation*, 2nd ed., eq.
//! 1.4-4) tie the rates to the attitude's rates:
//!
//! ```text
//! φ̇ = p + tanθ (q sinφ + r cosφ)
//! θ̇ = q cosφ − r sinφ
//! ψ̇ = (q sinφ + r cosφ) / cosθ
//! ```
//!
//! Over consecutive estimated samples (the interval at most 2.5 × the shortest seen, so a gap
//! is not differenced across), the attitude's rates by finite difference are regressed, by least
//! squares, on each rate channel's share of the right-hand side with one gain per channel
//! (`k_p`, `k_q`, `k_r`; 1 when the units agree) and one bias per equation (gyro biases). An
//! equation is used where its channels are mapped (θ̇: θ and q, with φ and r where mapped;
//! φ̇: φ and p, with θ, q, r where mapped; ψ̇: every one); samples with `|cos θ| < 0.1` are
//! left out (`tan θ` is not a rate's share there).
//!
//! A gain is a warning (`summary.json` `warnings`, and stderr) when it is determined (its σ
//! from the regression, white residuals, well under its distance from 1) and
//! - within a factor 1.5 of 57.3: the channel reads 57.3 times too small (rad/s data mapped as
//!   deg/s), or the attitude 57.3 times too large (deg data mapped as rad);
//! - within a factor 1.5 of 1/57.3: the reverse;
//! - otherwise below 0.5 (negative: a sign convention) or above 2, with the regression
//!   explaining most of the attitude's rates (R² ≥ 0.5).
//!
//! The finite difference's noise is in the regressand, so it does not bias the gains; noise on
//! the rates biases them towards 0 by their noise share, far less than the factors judged. A
//! channel that hardly moves has a large σ and is not judged.
//!
//! The kinematics the other stages share live here too, below the compatibility check, the
//! replay and `inspect`: the sideslip a record without a β vane implies ([`sideslip`]) and a
//! flow angle integrated from its rate less its line ([`integral_less_line`]).

use aeroident_estimators::AirDataSample;
use aeroident_io::Mapping;
use aeroident_io::warning::{Warning, WarningKind};
use aeroident_physics::rigid_body::{SinCos, euler_rates};
use nalgebra::{DMatrix, DVector};

pub mod sideslip;

/// Unknowns: gains of p, q, r, then the biases of the φ̇, θ̇, ψ̇ equations.
const N: usize = 6;

/// The rate channels whose gains are judged, as sample fields.
const RATES: [&str; 3] = ["p_rad_s", "q_rad_s", "r_rad_s"];

/// Degrees per radian: the factor of a rad/s–deg/s mismatch.
const DEG_PER_RAD: f64 = 180.0 / core::f64::consts::PI;

/// Fewest equations (attitude-rate samples) before any gain is judged.
const MIN_EQUATIONS: usize = 50;

/// A gain is judged only when `|k − 1|` exceeds this many of its σ.
const MIN_SIGMAS: f64 = 10.0;

/// One rate channel's gain: its sample field, the gain `k` and its σ.
pub type Gain = (&'static str, f64, f64);

/// The normal equations of the regression (module doc), accumulated sample by sample.
#[derive(Debug, Clone)]
pub struct Kinematics {
    xtx: [[f64; N]; N],
    xty: [f64; N],
    yty: f64,
    /// Σ y and the equations, per equation (φ̇, θ̇, ψ̇), for R².
    y_sum: [f64; 3],
    equations: [usize; 3],
    prev: Option<AirDataSample>,
    dt_min: f64,
}

impl Default for Kinematics {
    fn default() -> Self {
        Self {
            xtx: [[0.0; N]; N],
            xty: [0.0; N],
            yty: 0.0,
            y_sum: [0.0; 3],
            equations: [0; 3],
            prev: None,
            dt_min: f64::INFINITY,
        }
    }
}

/// `x` wrapped to (−π, π].
fn wrapped(x: f64) -> f64 {
    let two_pi = 2.0 * core::f64::consts::PI;
    x - two_pi * ((x + core::f64::consts::PI) / two_pi).ceil() + two_pi
}

impl Kinematics {
    /// Takes one estimated sample; the pair it makes with the one before (same stretch of the
    /// record) adds its equations.
    pub fn push(&mut self, s: &AirDataSample) {
        let prev = self.prev.replace(*s);
        let Some(a) = prev else { return };
        let dt = s.t_s - a.t_s;
        if !(dt > 0.0 && dt.is_finite()) {
            return;
        }
        self.dt_min = self.dt_min.min(dt);
        if dt > 2.5 * self.dt_min {
            return;
        }
        self.add_pair(&a, s, dt);
    }

    /// Starts a new stretch (a gap, a manoeuvre): no pair across it.
    pub fn new_segment(&mut self) {
        self.prev = None;
    }

    /// The check over the samples of each manoeuvre (no pair across two).
    pub fn of_manoeuvres<M: AsRef<[AirDataSample]>>(manoeuvres: &[M]) -> Self {
        let mut k = Self::default();
        for m in manoeuvres {
            k.new_segment();
            m.as_ref().iter().for_each(|s| k.push(s));
        }
        k
    }

    fn add_pair(&mut self, a: &AirDataSample, b: &AirDataSample, dt: f64) {
        let mid = |f: fn(&AirDataSample) -> Option<f64>| Some(0.5 * (f(a)? + f(b)?));
        let (p, q, r) = (mid(|s| s.p_rad_s), mid(|s| s.q_rad_s), mid(|s| s.r_rad_s));
        let phi = mid(|s| s.phi_rad).map(wrapped);
        let theta = mid(|s| s.theta_rad);
        let rate = |f: fn(&AirDataSample) -> Option<f64>| Some(wrapped(f(b)? - f(a)?) / dt);
        let th = theta.unwrap_or(0.0);
        if th.cos().abs() < 0.1 {
            return;
        }
        // The kinematics are linear in (p, q, r): column c of their matrix is the Euler rates
        // of a unit rate c, so each channel's share of each equation comes from the one
        // definition in the physics crate. A channel not mapped contributes nothing.
        let (sphi, stheta) = (SinCos::of(phi.unwrap_or(0.0)), SinCos::of(th));
        let unit =
            |c: usize| euler_rates(core::array::from_fn(|i| f64::from(i == c)), sphi, stheta);
        let columns = [unit(0), unit(1), unit(2)];
        let share = |eq: usize, rates: [Option<f64>; 3]| -> [f64; 3] {
            core::array::from_fn(|c| columns[c][eq] * rates[c].unwrap_or(0.0))
        };
        // φ̇ = p + tanθ (q sinφ + r cosφ), θ̇ = q cosφ − r sinφ, ψ̇ = (q sinφ + r cosφ)/cosθ.
        if let (Some(y), Some(_)) = (rate(|s| s.phi_rad), p) {
            self.add(share(0, [p, q, r]), 0, y);
        }
        if let (Some(y), Some(_)) = (rate(|s| s.theta_rad), q) {
            self.add(share(1, [None, q, r]), 1, y);
        }
        if let (Some(y), Some(_), Some(_), Some(_), Some(_)) =
            (rate(|s| s.psi_rad), q, r, phi, theta)
        {
            self.add(share(2, [None, q, r]), 2, y);
        }
    }

    /// One equation `y = Σ k_c x_c + b_eq`.
    fn add(&mut self, x_rates: [f64; 3], eq: usize, y: f64) {
        if !(y.is_finite() && x_rates.iter().all(|v| v.is_finite())) {
            return;
        }
        let mut x = [0.0; N];
        x[..3].copy_from_slice(&x_rates);
        x[3 + eq] = 1.0;
        for ((row, xi), b) in self.xtx.iter_mut().zip(&x).zip(&mut self.xty) {
            for (v, xj) in row.iter_mut().zip(&x) {
                *v += xi * xj;
            }
            *b += xi * y;
        }
        self.yty += y * y;
        self.y_sum[eq] += y;
        self.equations[eq] += 1;
    }

    /// The gains `(field, k, σ_k)` of the rate channels the equations determine, and R² of the
    /// regression (the biases taken out of the total); `None` with too few equations.
    pub fn gains(&self) -> Option<(Vec<Gain>, f64)> {
        let m: usize = self.equations.iter().sum();
        if m < MIN_EQUATIONS {
            return None;
        }
        // The unknowns with a regressor: a gain whose channel moves, a bias whose equation is used.
        let active: Vec<usize> = (0..N)
            .filter(|&i| if i < 3 { self.xtx[i][i] > 0.0 } else { self.equations[i - 3] > 0 })
            .collect();
        let a = DMatrix::from_fn(active.len(), active.len(), |i, j| self.xtx[active[i]][active[j]]);
        let b = DVector::from_fn(active.len(), |i, _| self.xty[active[i]]);
        let inv = a.clone().try_inverse()?;
        let beta = &inv * &b;
        let sse = (self.yty - 2.0 * beta.dot(&b) + beta.dot(&(&a * &beta))).max(0.0);
        let dof = m.checked_sub(active.len()).filter(|&d| d > 0)?;
        let s2 = sse / dof as f64;
        // Total about each equation's own mean (what the biases alone explain is not fit).
        let sst: f64 = self.yty
            - (0..3)
                .filter(|&e| self.equations[e] > 0)
                .map(|e| self.y_sum[e] * self.y_sum[e] / self.equations[e] as f64)
                .sum::<f64>();
        let r2 = if sst > 0.0 { 1.0 - sse / sst } else { 0.0 };
        let gains = active
            .iter()
            .enumerate()
            .filter(|&(_, &i)| i < 3)
            .map(|(k, &i)| (RATES[i], beta[k], (s2 * inv[(k, k)]).max(0.0).sqrt()))
            .collect();
        Some((gains, r2))
    }

    /// One warning per rate channel whose gain says its unit (or the attitude's) disagrees
    /// (module doc), naming the channel as `mapping` does and the likely unit.
    pub fn warnings(&self, mapping: &Mapping) -> Vec<Warning> {
        let Some((gains, r2)) = self.gains() else { return Vec::new() };
        gains
            .into_iter()
            .filter(|&(_, k, sigma)| (k - 1.0).abs() > MIN_SIGMAS * sigma)
            .filter_map(|(field, k, _)| {
                let label = mapping.field_label(field);
                let near = |target: f64| (k / target).ln().abs() < 1.5f64.ln() && k > 0.0;
                let likely = if near(DEG_PER_RAD) {
                    "the channel reads 57.3 times too small: likely rad/s data mapped as deg/s (or the attitude in deg mapped as rad)"
                } else if near(1.0 / DEG_PER_RAD) {
                    "the channel reads 57.3 times too large: likely deg/s data mapped as rad/s (or the attitude in rad mapped as deg)"
                } else if (0.5..=2.0).contains(&k) || r2 < 0.5 {
                    return None;
                } else if k < 0.0 {
                    "its sign is opposite to the attitude's: check the sign convention (scale = -1)"
                } else {
                    "check its unit and scale, and the attitude's"
                };
                let text = format!(
                    "unit mismatch: {label} disagrees with the attitude it turns: the Euler kinematics give the attitude's measured rates with {} × this channel (1 when the units agree; R² {r2:.2}); {likely}",
                    three_decimals(k)
                );
                Some(Warning::new(WarningKind::UnitMismatch, text))
            })
            .collect()
    }
}

/// `x` to at most 3 decimals.
fn three_decimals(x: f64) -> String {
    format!("{:.3}", x).trim_end_matches('0').trim_end_matches('.').to_string()
}

/// `y` at the times `t_s` less its least-squares line in time (`y` itself when the times do
/// not spread).
pub fn less_line(t_s: &[f64], y: &[f64]) -> Vec<f64> {
    let n = y.len() as f64;
    let t_mean = t_s.iter().sum::<f64>() / n;
    let y_mean = y.iter().sum::<f64>() / n;
    let stt: f64 = t_s.iter().map(|t| (t - t_mean).powi(2)).sum();
    let sty: f64 = t_s.iter().zip(y).map(|(t, v)| (t - t_mean) * (v - y_mean)).sum();
    let slope = if stt > 0.0 { sty / stt } else { 0.0 };
    t_s.iter().zip(y).map(|(t, v)| v - y_mean - slope * (t - t_mean)).collect()
}

/// The integral of `rate` over the times `t_s` (trapezoidal, from the first sample) less its
/// least-squares line in time ([`less_line`]): a flow angle reconstructed from its kinematic
/// rate when the rate's bias (which integrates to a line) and the start are unknown (Klein &
/// Morelli, *Aircraft System Identification*, 2006, §10.1). The kinematic sideslip
/// ([`sideslip`]) and the sensor screen's kinematic α both take it.
pub fn integral_less_line(t_s: &[f64], rate: &[f64]) -> Vec<f64> {
    let mut angle = vec![0.0; rate.len()];
    for i in 1..rate.len() {
        angle[i] = angle[i - 1] + 0.5 * (rate[i] + rate[i - 1]) * (t_s[i] - t_s[i - 1]);
    }
    less_line(t_s, &angle)
}

#[cfg(test)]
mod tests;
