//! The estimator channels stepped through the flight a block at a time, on two threads.
//!
//! The channels are independent of each other and of the reference aircraft: each reads the
//! same sensed step and its own memory, and none feeds back into the flight. So while the
//! flight's thread flies block `k + 1`, a second thread steps some channels through block `k`
//! and the flight's thread steps the rest once its block is flown. Each channel sees its
//! steps in order, so its log is the same bit for bit whichever thread stepped it and however
//! the channels were split (`tests::a_channel_logs_the_same_alone_or_beside_others_on_either_thread`).
//!
//! The split follows the last block's measured costs: longest first to the thread with less
//! work, the flight's own block counted on its thread. Two-aircraft channels stay on the
//! flight's thread (their engines share the estimated increments through an `Rc`). With one
//! thread in rayon's pool, or inside a pool's job (a Monte Carlo campaign already fills the
//! cores), every channel steps on the flight's thread ([`second_thread_free`]).

use std::time::{Duration, Instant};

use aeroident_estimators::Status;
use aeroident_estimators::sample::AirDataSample;
use aeroident_estimators::smpe::SmpeSample;
use aeroident_models::f16::{F16Controls, F16State};
use aeroident_models::integrate::rk4_step_varying;

use super::{BatchChannel, ChannelLog, ChannelRun, Channelled, SampleChannel, TwoAircraft};

/// Steps flown before the channels take them: 1.28 s at 100 Hz. The second thread is handed
/// each block once, so a longer block spreads the hand-over thinner over its work
/// (docs/six-axis.md measures the default job with this length).
pub(super) const BLOCK_STEPS: usize = 128;

/// One step of the flight as the channels read it (module doc of `super`, step 3).
#[derive(Debug, Clone)]
pub(super) struct SensedStep {
    /// Time, s.
    pub t_s: f64,
    /// The truth epoch containing `t_s` (index into the run's epochs).
    pub epoch: usize,
    /// Measured state of the reference (two-aircraft estimators).
    pub z_m: F16State,
    /// Measured state derivative of the reference.
    pub zdot_m: F16State,
    /// The controls the estimators are given.
    pub u_est: F16Controls,
    /// The air-data sample, when one was formed this step.
    pub air: Option<AirDataSample>,
    /// The unsmoothed sample, alongside `air`.
    pub raw: Option<AirDataSample>,
    /// The flight ends at this step: no integration after it.
    pub last: bool,
}

/// A channel a second thread may step: its log and its estimator, both `Send`.
enum Fed<'a> {
    Sample(&'a mut ChannelLog, &'a mut SampleChannel),
    Batch(&'a mut ChannelLog, &'a mut BatchChannel),
}

impl Fed<'_> {
    /// The channel through `steps`, the truth of each step's epoch (`truth[p][epoch]`) logged
    /// beside its estimates.
    fn step(&mut self, steps: &[SensedStep], truth: &[Vec<Option<f64>>]) {
        for s in steps {
            let log = match self {
                Fed::Sample(log, c) => {
                    step_sample(log, c, s);
                    log
                }
                Fed::Batch(log, b) => {
                    step_batch(log, b, s);
                    log
                }
            };
            log_truth(log, truth, s);
        }
    }
}

/// A channel of the flight's thread.
enum Lane<'a> {
    Fed(Fed<'a>),
    Two(&'a mut ChannelLog, &'a mut TwoAircraft),
}

/// Which channels the second thread takes, from what each cost in the last block.
#[derive(Debug)]
pub(super) struct Split {
    /// Per channel, its last block's wall time.
    cost: Vec<Duration>,
    /// The flight's last block.
    flight_cost: Duration,
    /// Whether a second thread is used at all.
    parallel: bool,
}

/// Whether a second thread is free for the channels: rayon's pool has more than one thread
/// and this is not one of its jobs (a campaign's runs already fill the pool; a run waiting
/// there for its channels would take up other runs on its stack).
pub(super) fn second_thread_free() -> bool {
    rayon::current_num_threads() > 1 && rayon::current_thread_index().is_none()
}

impl Split {
    /// A split for `channels` channels, on a second thread of rayon's pool or not.
    pub(super) fn new(channels: usize, parallel: bool) -> Self {
        Split { cost: vec![Duration::ZERO; channels], flight_cost: Duration::ZERO, parallel }
    }

    /// Per channel, whether the second thread takes it ([`longest_first`] of the fed channels).
    fn theirs(&self, channels: &[ChannelRun]) -> Vec<bool> {
        if !self.parallel {
            return vec![false; channels.len()];
        }
        let fed = channels.iter().map(|c| !matches!(c.ch, Channelled::Two(_)));
        let costs: Vec<(Duration, bool)> = self.cost.iter().copied().zip(fed).collect();
        longest_first(self.flight_cost, &costs)
    }

    /// Steps every channel through `steps` while `fly_next` flies the next block on this
    /// thread; `truths[c][p][epoch]` is logged beside each estimate. Returns `fly_next`'s
    /// result once every channel has stepped.
    pub(super) fn step<E>(
        &mut self,
        channels: &mut [ChannelRun],
        steps: &[SensedStep],
        truths: &[Vec<Vec<Option<f64>>>],
        controls: &(impl Fn(f64, F16Controls) -> F16Controls + Copy),
        dt_s: f64,
        fly_next: impl FnOnce() -> Result<(), E>,
    ) -> Result<(), E> {
        let theirs = self.theirs(channels);
        let (mut mine, mut other) = (Vec::new(), Vec::new());
        for (i, c) in channels.iter_mut().enumerate() {
            let fed = match &mut c.ch {
                Channelled::Two(two) => {
                    mine.push((i, Lane::Two(&mut c.log, two)));
                    continue;
                }
                Channelled::Sample(s) => Fed::Sample(&mut c.log, s),
                Channelled::Batch(b) => Fed::Batch(&mut c.log, b),
            };
            if theirs[i] { other.push((i, fed)) } else { mine.push((i, Lane::Fed(fed))) }
        }
        let mut other_cost = Vec::with_capacity(other.len());
        let mut flown = Ok(());
        rayon::in_place_scope(|scope| {
            if !other.is_empty() {
                let costs = &mut other_cost;
                scope.spawn(move |_| {
                    for (i, mut fed) in other {
                        let start = Instant::now();
                        fed.step(steps, &truths[i]);
                        costs.push((i, start.elapsed()));
                    }
                });
            }
            let start = Instant::now();
            flown = fly_next();
            self.flight_cost = start.elapsed();
            for (i, lane) in mine {
                let start = Instant::now();
                step_lane(lane, steps, &truths[i], controls, dt_s);
                self.cost[i] = start.elapsed();
            }
        });
        for (i, d) in other_cost {
            self.cost[i] = d;
        }
        flown
    }
}

/// Per channel `(last cost, may move)`, whether the second thread takes it: the channels that
/// may move, longest first, each to the thread with less work so far, the flight's thread
/// starting with `flight` and the channels that may not move (Graham's LPT rule, within 4/3 of
/// the best split).
fn longest_first(flight: Duration, costs: &[(Duration, bool)]) -> Vec<bool> {
    let mut mine = flight + costs.iter().filter(|c| !c.1).map(|c| c.0).sum::<Duration>();
    let mut order: Vec<usize> = (0..costs.len()).filter(|&i| costs[i].1).collect();
    order.sort_by(|&a, &b| costs[b].0.cmp(&costs[a].0));
    let (mut theirs, mut other) = (vec![false; costs.len()], Duration::ZERO);
    for i in order {
        if other <= mine {
            theirs[i] = true;
            other += costs[i].0;
        } else {
            mine += costs[i].0;
        }
    }
    theirs
}

/// A channel of the flight's thread through `steps`.
fn step_lane(
    lane: Lane<'_>,
    steps: &[SensedStep],
    truth: &[Vec<Option<f64>>],
    controls: &(impl Fn(f64, F16Controls) -> F16Controls + Copy),
    dt_s: f64,
) {
    match lane {
        Lane::Fed(mut fed) => fed.step(steps, truth),
        Lane::Two(log, two) => {
            for s in steps {
                step_two(log, two, s);
                log_truth(log, truth, s);
                if !s.last {
                    let u_est = s.u_est;
                    integrate_two(log, two, s.t_s, move |ts| controls(ts, u_est), dt_s);
                }
            }
        }
    }
}

/// The truth of the step's epoch beside each parameter's estimate.
fn log_truth(log: &mut ChannelLog, truth: &[Vec<Option<f64>>], s: &SensedStep) {
    for (l, tr) in log.params.iter_mut().zip(truth) {
        l.truth.push(tr[s.epoch]);
    }
}

/// A two-aircraft channel's engines at one step: each updates from its own aircraft's state
/// and the measured one; the estimated increments move together once all succeeded.
fn step_two(log: &mut ChannelLog, two: &mut TwoAircraft, s: &SensedStep) {
    let sample = SmpeSample { t_s: s.t_s, z: two.x, z_m: s.z_m, zdot_m: s.zdot_m, u: s.u_est };
    if log.failure.is_none() {
        let mut next = two.current.get();
        let mut diag = Vec::new();
        for e in &mut two.engines {
            match e.update(&sample) {
                Ok(()) => {
                    e.write(&mut next);
                    if let Some(d) = e.diagnostics(&sample) {
                        diag.push(d);
                    }
                }
                Err(err) => {
                    log.failure = Some((s.t_s, err.to_string()));
                    break;
                }
            }
        }
        if log.failure.is_none() {
            two.current.set(next);
        }
        if !diag.is_empty() {
            log.diagnostics.push(diag);
        }
    }
    let cur = two.current.get();
    for l in &mut log.params {
        l.estimate.push(Some(super::super::increments::get(&cur, l.param)));
        l.sigma.push(None);
    }
    log.states.push(two.x);
}

/// RK4 of a two-aircraft estimator's own aircraft over `[t, t + dt]` under `controls`; a
/// failure is logged once and the aircraft held.
fn integrate_two(
    log: &mut ChannelLog,
    two: &mut TwoAircraft,
    t: f64,
    controls: impl Fn(f64) -> F16Controls + Copy,
    dt: f64,
) {
    two.f16.increments = two.current.get();
    match rk4_step_varying(&two.f16, t, &two.x, controls, dt) {
        Ok(x) => two.x = x,
        Err(e) => {
            if log.failure.is_none() {
                log.failure = Some((t, format!("estimated aircraft: {e}")));
            }
        }
    }
}

/// A sample-driven channel at one step: its estimator updated from the step's sample (the
/// raw one without the differentiated `ṗ q̇ ṙ` when it asks for it), its estimates logged.
fn step_sample(log: &mut ChannelLog, c: &mut SampleChannel, s: &SensedStep) {
    let without_accelerations = |r: &AirDataSample| AirDataSample {
        pdot_rad_s2: None,
        qdot_rad_s2: None,
        rdot_rad_s2: None,
        ..*r
    };
    let raw_feed = s.raw.as_ref().filter(|_| c.raw_samples).map(without_accelerations);
    let feed = if c.raw_samples { raw_feed.as_ref() } else { s.air.as_ref() };
    if log.failure.is_none()
        && let Some(sample) = feed
    {
        match c.est.update(sample) {
            Ok(e) if e.status == Status::Diverged => {
                log.failure = Some((s.t_s, "estimator diverged".into()));
            }
            Ok(_) => {}
            Err(err) => log.failure = Some((s.t_s, err.to_string())),
        }
    }
    let e = c.est.estimates();
    let diverged = e.status == Status::Diverged;
    log.status = Some(e.status.name());
    for (i, l) in log.params.iter_mut().enumerate() {
        l.estimate.push(if diverged { None } else { e.value(i) });
        l.sigma.push(if diverged { None } else { e.sigma(i) });
    }
}

/// A batch channel at one step: the sample recorded for the fit after the flight.
fn step_batch(log: &mut ChannelLog, b: &mut BatchChannel, s: &SensedStep) {
    if let Some(sample) = if b.raw_samples { s.raw.as_ref() } else { s.air.as_ref() } {
        b.samples.push(*sample);
    }
    for l in &mut log.params {
        l.estimate.push(None);
        l.sigma.push(None);
    }
}

#[cfg(test)]
mod tests {
    use super::super::{RunOutput, run_with};
    use super::*;
    use crate::aircraft::scenario::{DEFAULT_SCENARIO, Scenario};

    /// Bounded lift and drag increments, for the two-aircraft estimator.
    const INCREMENTS: &str = "[increments.CL_alpha]\ntruth = 0.01\nlower = 0.005\nupper = 0.05\nlambda_per_s = 1.0\neta = 1e-10\n\n[increments.CD_alpha]\ntruth = 0.001\nlower = 0.0005\nupper = 0.005\nlambda_per_s = 1.0\neta = 1e-10\n\n";

    /// The default flight cut to 3 s with its damage at 1.5 s and [`INCREMENTS`], flown by
    /// `estimators`.
    fn scenario(estimators: &[&str]) -> Scenario {
        let head = &DEFAULT_SCENARIO[..DEFAULT_SCENARIO.find("[[estimator]]").unwrap()];
        let head = head.to_string() + INCREMENTS;
        let head = head.replace("duration_s = 40.0", "duration_s = 3.0");
        assert_eq!(head.matches("step_at_s = 20.0").count(), 2, "the default damage changed");
        let text = head.replace("step_at_s = 20.0", "step_at_s = 1.5") + &estimators.join("\n");
        Scenario::from_toml(&text, "cut.toml").unwrap()
    }

    const ESTIMATORS: [&str; 5] = [
        "[[estimator]]\nkind = \"rls\"\nmodel = \"six-axis\"\nforgetting = 0.995\n",
        "[[estimator]]\nkind = \"ekf\"\nmodel = \"six-axis\"\nparameter_walk_per_sqrt_s = 0.001\n",
        "[[estimator]]\nkind = \"corrected\"\nparams = [\"CL_alpha\", \"CD_alpha\"]\ninformation_per_s = 1e+12\nforgetting_per_s = 2.0\n",
        "[[estimator]]\nkind = \"smpe-finite-time\"\nmodel = \"six-axis\"\nforgetting = 0.995\n",
        "[[estimator]]\nkind = \"oe\"\nmodel = \"longitudinal\"\n",
    ];

    /// The first index where two logs differ in a bit, if any.
    fn first_difference(x: &[Option<f64>], y: &[Option<f64>]) -> Option<usize> {
        let bits = |o: &Option<f64>| o.map(f64::to_bits);
        (x.len() != y.len())
            .then_some(x.len().min(y.len()))
            .or_else(|| x.iter().zip(y).position(|(a, b)| bits(a) != bits(b)))
    }

    /// Every logged number of channel `a` of `x` and `b` of `y`, bit for bit.
    fn same_log(x: &RunOutput, a: usize, y: &RunOutput, b: usize) {
        let (p, q) = (&x.channels[a], &y.channels[b]);
        assert_eq!((&p.label, p.params.len()), (&q.label, q.params.len()));
        for (l, m) in p.params.iter().zip(&q.params) {
            let name = format!("{} {}", p.label, l.param.name());
            assert_eq!(first_difference(&l.estimate, &m.estimate), None, "{name}");
            assert_eq!(first_difference(&l.sigma, &m.sigma), None, "{name} σ");
            assert_eq!(first_difference(&l.truth, &m.truth), None, "{name} truth");
        }
        let states = |v: &[F16State]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(states(&p.states) == states(&q.states), "{} states", p.label);
        assert_eq!((&p.failure, p.status), (&q.failure, q.status));
    }

    #[test]
    fn a_channel_logs_the_same_alone_or_beside_others_on_either_thread() {
        let together = run_with(&scenario(&ESTIMATORS), true).unwrap();
        assert_eq!(together.t_s.len(), 301);
        for c in &together.channels {
            let estimated = c.params.iter().filter(|l| l.estimate.last().unwrap().is_some());
            assert!(estimated.count() > 0, "{}: nothing estimated, nothing compared", c.label);
        }
        for (k, e) in ESTIMATORS.iter().enumerate() {
            let alone = run_with(&scenario(&[e]), false).unwrap();
            assert_eq!(alone.channels[0].params[0].estimate.len(), 301);
            same_log(&together, k, &alone, 0);
        }
    }

    /// Inside a pool's job (a campaign's run) no second thread is asked for, whatever the
    /// pool's size; with one thread in the pool neither.
    #[test]
    fn a_run_inside_a_pool_job_keeps_one_thread() {
        let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
        assert!(!pool(2).install(second_thread_free));
        assert!(!pool(1).install(second_thread_free));
    }

    #[test]
    fn the_longest_channel_goes_to_the_thread_with_less_work() {
        let ms = Duration::from_millis;
        // An EKF-like channel (12), four light ones and a two-aircraft one that may not move;
        // the flight itself costs 3 on its thread.
        let costs = [(ms(2), true), (ms(12), true), (ms(3), true), (ms(2), true), (ms(1), false)];
        assert_eq!(longest_first(ms(3), &costs), [false, true, false, false, false]);
        // Nothing measured yet: every channel that may move goes across, while the flight's
        // thread flies the next block.
        let zero = [(ms(0), false), (ms(0), true), (ms(0), true)];
        assert_eq!(longest_first(ms(0), &zero), [false, true, true]);
        // Two equal heavy channels and a light flight: one each side.
        let two = [(ms(10), true), (ms(10), true)];
        assert_eq!(longest_first(ms(1), &two), [true, false]);
    }
}
