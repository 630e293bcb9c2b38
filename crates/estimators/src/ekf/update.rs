//! One filter step as named stages: predict ([`Ekf::predict`]), one scalar measurement
//! update per output ([`Ekf::measure`]), the divergence check ([`Ekf::check_state`]) and the
//! commit ([`Ekf::commit`]). A step is atomic: every stage before the commit works on a
//! [`Pending`] copy and the filter's own state changes only in the commit (or in a lock-out,
//! which restarts or stops the filter).

use super::{
    ADAPTIVE_Q_MEMORY_SAMPLES, Ekf, LockOutCounts, MAX_AUG, adapt_r, change, reanchor,
    reanchor_parameters, sensitivity,
};
use crate::EstimatorError;
use crate::estimator::EventKind;
use crate::flight_model::{ModelInputs, N_OUTPUTS, N_STATES, Output, state};
use crate::sample::AirDataSample;
use crate::vocabulary::MAX_PARAMS;

/// The process-noise statistic of one step (module doc, "State process noise from the
/// record"): the forgotten sum of earlier state corrections and the cross products of this
/// sample's corrections with it, formed only for the adapted states.
pub(super) struct QStats {
    on: bool,
    forget: f64,
    acc: [[f64; N_OUTPUTS]; N_STATES],
    tot: [f64; N_STATES],
    cross: [f64; N_STATES],
    /// Products of each output's correction with its own earlier ones (lags ≥ 1), for the
    /// states whose own-lag statistic is on.
    own: [f64; N_STATES],
    own_on: [bool; N_STATES],
    red: [[f64; 2]; N_STATES],
    p_prior: [f64; N_STATES],
}

/// Everything one step computes before it is committed.
pub(super) struct Pending {
    pub(super) z: [f64; MAX_AUG],
    z_pred: [f64; MAX_AUG],
    /// Predicted parameter variances (after any random walk), for the change test's uptake.
    p_pred: [f64; MAX_PARAMS],
    innovation: [Option<f64>; N_OUTPUTS],
    normalised: [Option<f64>; N_OUTPUTS],
    info: [[f64; MAX_PARAMS]; N_OUTPUTS],
    pub(super) counts: LockOutCounts,
    run_reanchored: [bool; N_OUTPUTS],
    r_var: [f64; N_OUTPUTS],
    r_count: [u32; N_OUTPUTS],
    nis_sum: f64,
    nis_count: u64,
    q: QStats,
}

/// What one output's measurement did to the step.
pub(super) enum Measured {
    /// Used, rejected by the gate, or absent from the sample: the step goes on.
    Done,
    /// The output failed the gate too many times in a row: the filter restarts or stops.
    LockedOut(Output),
}

impl Ekf {
    /// Prediction over `dt`: linearise at the interval start, propagate `P` (into `work`),
    /// integrate the mean, then linearise at the predicted state for the measurement update.
    /// Returns the predicted augmented state.
    ///
    /// # Errors
    /// A singular implicit α̇ equation (the filter diverges).
    pub(super) fn predict(
        &mut self,
        u0: &ModelInputs,
        u1: &ModelInputs,
        dt: f64,
        t_s: f64,
    ) -> Result<[f64; MAX_AUG], EstimatorError> {
        let (nx, np) = (self.nx, self.np);
        let n = nx + np;
        // `lin` is scratch (not state): written in place, no copy of its ~9 kB.
        let mut theta = [0.0; MAX_PARAMS];
        theta[..np].copy_from_slice(&self.z[nx..n]);
        let mut x0 = [0.0; N_STATES];
        x0[..nx].copy_from_slice(&self.z[..nx]);
        let singular = "EKF: implicit alpha-dot equation singular";
        if self.model.linearise(&theta[..np], u0, &x0[..nx], &mut self.lin).is_err() {
            return Err(self.diverge(singular, t_s));
        }
        self.propagate_covariance(dt);
        let Ok(xp) = self.rk4(u0, u1, dt) else {
            return Err(self.diverge(singular, t_s));
        };
        let mut z = self.z;
        z[..nx].copy_from_slice(&xp[..nx]);
        if self.model.linearise(&z[nx..n], u1, &z[..nx], &mut self.lin).is_err() {
            return Err(self.diverge(singular, t_s));
        }
        Ok(z)
    }

    /// The uncommitted copy of the filter's counters for a step from predicted state `z`.
    pub(super) fn pending(&self, z: [f64; MAX_AUG]) -> Pending {
        let (nx, np) = (self.nx, self.np);
        let mut p_pred = [0.0; MAX_PARAMS];
        for (i, v) in p_pred.iter_mut().enumerate().take(np) {
            *v = self.work()[nx + i][nx + i];
        }
        Pending {
            z,
            z_pred: z,
            p_pred,
            innovation: [None; N_OUTPUTS],
            normalised: [None; N_OUTPUTS],
            info: [[0.0; MAX_PARAMS]; N_OUTPUTS],
            counts: LockOutCounts {
                rejections: self.rejections,
                consecutive: self.consecutive,
                reanchors: self.reanchors,
                new_reanchor: [false; N_OUTPUTS],
            },
            run_reanchored: self.run_reanchored,
            r_var: self.r_var,
            r_count: self.r_count,
            nis_sum: self.nis_sum,
            nis_count: self.nis_count,
            q: self.q_stats(),
        }
    }

    fn q_stats(&self) -> QStats {
        let mut q = QStats {
            on: self.cfg.adaptive_q_window > 0,
            forget: 1.0 - 1.0 / ADAPTIVE_Q_MEMORY_SAMPLES,
            acc: [[0.0; N_OUTPUTS]; N_STATES],
            tot: [0.0; N_STATES],
            cross: [0.0; N_STATES],
            own: [0.0; N_STATES],
            own_on: [false; N_STATES],
            red: [[0.0; 2]; N_STATES],
            p_prior: [0.0; N_STATES],
        };
        if q.on {
            for k in (0..self.nx).filter(|&k| self.adapted(k)) {
                for (a, b) in q.acc[k].iter_mut().zip(&self.q_acc[k]) {
                    *a = q.forget * b;
                    q.tot[k] += *a;
                }
                q.p_prior[k] = self.work()[k][k];
                q.own_on[k] = self.cfg.adaptive_q_own_lags[self.model.state_set().states()[k]];
            }
        }
        q
    }

    /// Whether the process noise of state `k` (model-state index) is estimated.
    fn adapted(&self, k: usize) -> bool {
        self.q_adapted(self.model.state_set().states()[k])
    }

    /// The scalar measurement update of output `o` from sample `s` into `pd` (and `work`):
    /// the innovation, the re-anchoring of a run of rejections, the gate, then the update of
    /// the state, the covariance and the noise statistics.
    ///
    /// # Errors
    /// A non-positive innovation variance (the filter diverges).
    pub(super) fn measure(
        &mut self,
        o: Output,
        s: &AirDataSample,
        pd: &mut Pending,
    ) -> Result<Measured, EstimatorError> {
        let (nx, np) = (self.nx, self.np);
        let n = nx + np;
        let oi = o.index();
        let Some(y) = o.measured(s) else { return Ok(Measured::Done) };
        let states = self.model.state_set().states();
        // Row of ∂h/∂z; a state output is a unit row.
        let unit = if oi < N_STATES { states.iter().position(|&j| j == oi) } else { None };
        let mut h = [0.0; MAX_AUG];
        let mut ph = [0.0; MAX_AUG];
        let mut yhat = self.lin.y[oi];
        if let Some(k) = unit {
            yhat += pd.z[k] - pd.z_pred[k];
        } else {
            h[..nx].copy_from_slice(&self.lin.dydx[oi][..nx]);
            h[nx..n].copy_from_slice(&self.lin.dydtheta[oi][..np]);
            for j in 0..n {
                yhat += h[j] * (pd.z[j] - pd.z_pred[j]);
            }
        }
        let mut hph = change::p_times_row(self.work(), unit, &h, n, &mut ph);
        let mut sv = hph + pd.r_var[oi];
        if !(sv > 0.0 && sv.is_finite()) {
            return Err(self.diverge("EKF innovation variance not positive", s.t_s));
        }
        let e = y - yhat;
        let reanchored = self.try_reanchor(oi, unit, &h, e, sv, pd);
        if reanchored {
            hph = change::p_times_row(self.work(), unit, &h, n, &mut ph);
            sv = hph + pd.r_var[oi];
        }
        if e.is_nan() || libm::fabs(e) > self.cfg.gate_sigmas * libm::sqrt(sv) {
            return Ok(self.reject(o, unit, &h, e, sv, hph, pd));
        }
        // A re-anchored innovation continues the run: a model that must be re-anchored at
        // every sample for `max_consecutive_rejections` samples does not explain the output,
        // and the divergence rule still fires.
        if reanchored {
            pd.counts.consecutive[oi] += 1;
            if !pd.run_reanchored[oi] {
                pd.run_reanchored[oi] = true;
                pd.counts.new_reanchor[oi] = true;
            }
            if pd.counts.consecutive[oi] >= self.cfg.max_consecutive_rejections {
                return Ok(Measured::LockedOut(o));
            }
        } else {
            pd.counts.consecutive[oi] = 0;
            pd.run_reanchored[oi] = false;
        }
        self.correct(oi, e, sv, hph, &ph, pd);
        Ok(Measured::Done)
    }

    /// A run of rejections: raise the predicted variance of what the output sees (a measured
    /// state, or the parameters of a settled filter) to the censored bound and use the
    /// innovation (module doc, "Re-anchoring"). Whether it re-anchored.
    fn try_reanchor(
        &mut self,
        oi: usize,
        unit: Option<usize>,
        h: &[f64; MAX_AUG],
        e: f64,
        sv: f64,
        pd: &mut Pending,
    ) -> bool {
        let (nx, n) = (self.nx, self.nx + self.np);
        let gate2 = self.cfg.gate_sigmas * self.cfg.gate_sigmas;
        let target = e * e / gate2 - pd.r_var[oi];
        let done = self.cfg.reanchor_after > 0
            && pd.counts.consecutive[oi] + 1 >= self.cfg.reanchor_after
            && e * e > gate2 * sv
            && match unit {
                Some(k) => reanchor(self.work_mut(), k, target),
                None => {
                    (0..self.np).all(|i| h[nx + i] == 0.0 || self.settled(i)) && {
                        // It reads and scales whole rows: the upper triangle made current.
                        change::mirror_lower(self.work_mut(), n);
                        reanchor_parameters(self.work_mut(), h, nx, n, target)
                    }
                }
            };
        if done {
            pd.counts.reanchors[oi] += 1;
        }
        done
    }

    /// An innovation outside the gate. An output of the adapted states' equations feeds `R`
    /// at the censored bound `e² > gate² S` (module doc, "Measurement noise from the
    /// record"), so a deficit of `Q` widens the gate instead of locking it.
    #[allow(clippy::too_many_arguments)]
    fn reject(
        &self,
        o: Output,
        unit: Option<usize>,
        h: &[f64; MAX_AUG],
        e: f64,
        sv: f64,
        hph: f64,
        pd: &mut Pending,
    ) -> Measured {
        let oi = o.index();
        pd.counts.rejections[oi] += 1;
        pd.counts.consecutive[oi] += 1;
        let sees_q = pd.q.on
            && match unit {
                Some(k) => self.adapted(k),
                None => {
                    matches!(o, Output::Ax | Output::Ay | Output::Az)
                        && (0..self.nx).any(|k| self.adapted(k) && h[k] != 0.0)
                }
            };
        if sees_q && self.cfg.adaptive_r_window > 0 && !e.is_nan() {
            let bound = self.cfg.gate_sigmas * self.cfg.gate_sigmas * sv;
            adapt_r(&self.cfg, oi, bound - hph, &mut pd.r_var, &mut pd.r_count);
        }
        if pd.counts.consecutive[oi] >= self.cfg.max_consecutive_rejections {
            Measured::LockedOut(o)
        } else {
            Measured::Done
        }
    }

    /// The accepted innovation `e` (variance `sv`, `ph = P hᵀ`) corrects the state and `P`
    /// and enters the statistics of `R`, `Q`, the NIS and the parameters' information.
    fn correct(
        &mut self,
        oi: usize,
        e: f64,
        sv: f64,
        hph: f64,
        ph: &[f64; MAX_AUG],
        pd: &mut Pending,
    ) {
        let (nx, np) = (self.nx, self.np);
        let n = nx + np;
        pd.innovation[oi] = Some(e);
        let inv = 1.0 / sv;
        pd.normalised[oi] = Some(e * libm::sqrt(inv));
        for i in 0..np {
            pd.info[oi][i] = ph[nx + i] * ph[nx + i] * inv;
        }
        pd.nis_sum += e * e / sv;
        pd.nis_count += 1;
        if self.cfg.adaptive_r_window > 0 {
            adapt_r(&self.cfg, oi, e * e - hph, &mut pd.r_var, &mut pd.r_count);
        }
        for i in 0..n {
            pd.z[i] += ph[i] * inv * e;
        }
        if pd.q.on {
            let q = &mut pd.q;
            for k in (0..nx).filter(|&k| self.adapted(k)) {
                let d = ph[k] * inv * e;
                q.cross[k] += 2.0 * d * (q.tot[k] - q.acc[k][oi]);
                // `acc[k][oi]` holds only earlier samples here: an output is used once a sample.
                q.own[k] += 2.0 * d * q.acc[k][oi];
                q.acc[k][oi] += d;
                q.tot[k] += d;
                let red = ph[k] * ph[k] * inv;
                q.red[k][0] += red;
                q.red[k][1] += red * red;
            }
        }
        // P ← P − k (Ph)ᵀ, k = Ph/s, on the lower triangle only: entry (i, j ≤ i) is
        // k_i · ph_j, which is what the upper entry (j, i) would be too (the gain of the
        // larger index times the other's ph), so P stays exactly symmetric, and the upper
        // triangle is copied from it once after the step's last output (`mirror_lower`).
        let w = self.work_mut();
        for i in 0..n {
            let ki = ph[i] * inv;
            for (wij, phj) in w[i][..=i].iter_mut().zip(&ph[..=i]) {
                *wij -= ki * phj;
            }
        }
    }

    /// Divergence checks before committing anything: a non-finite state or covariance,
    /// V ≤ 0, or |α|, |β| > 1.5 rad.
    ///
    /// # Errors
    /// The divergence (the filter stops).
    pub(super) fn check_state(
        &mut self,
        z: &[f64; MAX_AUG],
        t_s: f64,
    ) -> Result<(), EstimatorError> {
        let n = self.nx + self.np;
        let work = self.work();
        let finite = z[..n].iter().all(|v| v.is_finite())
            && (0..n).all(|i| work[i][i] > 0.0 && work[i][..n].iter().all(|v| v.is_finite()));
        let ss = self.model.state_set();
        let states = ss.states();
        let get = |i: usize| states.iter().position(|&j| j == i).map(|k| z[k]);
        let bad_v = ss.lon() && get(state::V).is_some_and(|v| v.is_nan() || v <= 0.0);
        let bad_a = get(state::ALPHA).is_some_and(|a| a.is_nan() || libm::fabs(a) > 1.5);
        let bad_b = get(state::BETA).is_some_and(|b| b.is_nan() || libm::fabs(b) > 1.5);
        if !finite || bad_v || bad_a || bad_b {
            return Err(self.diverge(
                "EKF diverged (non-finite state or covariance, V ≤ 0, or |alpha|, |beta| > 1.5 rad)",
                t_s,
            ));
        }
        Ok(())
    }

    /// Commits step `pd` of sample time `t_s` over `dt`: state, covariance, counters, noise
    /// statistics and the innovations' whiteness and information.
    pub(super) fn commit(&mut self, pd: Pending, t_s: f64, dt: f64) {
        let (nx, np) = (self.nx, self.np);
        self.z = pd.z;
        self.commit_covariance();
        let front = self.front;
        for (i, u) in self.uptake.iter_mut().enumerate().take(np) {
            u.add(pd.p_pred[i], self.cov[front][nx + i][nx + i]);
        }
        let LockOutCounts { rejections, consecutive, reanchors, new_reanchor } = pd.counts;
        self.consecutive = consecutive;
        self.rejections = rejections;
        self.reanchors = reanchors;
        self.run_reanchored = pd.run_reanchored;
        for o in Output::ALL.iter().filter(|o| new_reanchor[o.index()]) {
            self.events.push(t_s, EventKind::Reanchor, o.name());
        }
        self.r_var = pd.r_var;
        self.r_count = pd.r_count;
        self.nis_sum = pd.nis_sum;
        self.nis_count = pd.nis_count;
        // While an output is being rejected the model does not explain the record (module
        // doc): the corrections then come from model error, not from process noise.
        if pd.q.on && self.consecutive.iter().all(|&c| c == 0) {
            let q_stat = q_statistic(&pd.q, nx);
            self.adapt_process_noise(&pd.q.acc, &q_stat, dt);
        }
        for (oi, v) in pd.normalised.iter().enumerate() {
            if let Some(v) = *v {
                self.innov_acf[oi].add(v, 1.0);
                for i in 0..np {
                    self.innov_info[oi][i] += pd.info[oi][i];
                }
            }
        }
        self.innovation = pd.innovation;
    }
}

/// Each state's correction statistic divided by its sensitivity to a `Q` error, from the
/// fraction of its prediction variance this sample removed (module doc).
fn q_statistic(q: &QStats, nx: usize) -> [f64; N_STATES] {
    let mut q_stat = [0.0; N_STATES];
    for k in 0..nx {
        let [red, red2] = q.red[k];
        if red > 0.0 {
            let gain = (red / q.p_prior[k]).clamp(0.0, 1.0);
            q_stat[k] = if q.own_on[k] {
                // Every product but the same-sample squares: the whole lag correlation.
                (q.cross[k] + q.own[k]) / sensitivity(gain, q.forget, 1.0)
            } else {
                let cross_share = 1.0 - red2 / (red * red);
                q.cross[k] / sensitivity(gain, q.forget, cross_share)
            };
        }
    }
    q_stat
}
