//! The cross-check of a live view while its feed runs: the record's other real-time methods
//! ([`crate::job::cross_check::ONLINE_METHODS`]: equation error, instrumental variables, the
//! EKF) follow the feed beside its own estimator, and the panel of
//! [`crate::replay::cross_check`] judges the latest estimates once a second of record time, so
//! a derivative the methods split on is flagged while the aircraft flies, not after the feed.
//!
//! Each member runs [`crate::replay::follow`] on its own thread, fed the events the feed's
//! replay has read, screened, corrected and windowed (its observer's
//! [`ReplayObserver::record_event`]), through a bounded queue of [`QUEUE_EVENTS`]: a member
//! that falls behind slows the feed's replay rather than holding an unbounded backlog. Each
//! member chooses its model as the feed's replay does, with its own default options.
//!
//! Only a split, or an estimate set aside by a tested cause, flags a derivative here
//! ([`disputed`]): early in a feed a member may have no estimate yet, and a derivative nothing
//! confirms is simply not checked yet. At the end the summary's own flags decide
//! ([`super::LiveState::conclude`]; with `--cross-check` on a file they include the whole panel,
//! batch methods too).

use crate::estimators::{EstimatorKind, EstimatorOptions};
use crate::job::cross_check::ONLINE_METHODS;
use crate::replay::cross_check::{
    Agreement, CrossCheck, MethodEstimates, ParameterEstimate, judge,
};
use crate::replay::{ReplayObserver, ReplayOptions};
use aeroident_io::RecordEvent;
use aeroident_io::mapping::Mapping;
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;

/// Events a member may lag behind the feed's replay before the replay waits for it.
pub const QUEUE_EVENTS: usize = 4096;

/// Record time between two judgements of the panel, s.
pub const JUDGE_EVERY_S: f64 = 1.0;

/// A member's latest estimates, as its thread leaves them.
#[derive(Debug, Default)]
struct Latest {
    names: Vec<String>,
    values: Vec<Option<f64>>,
    sigmas: Vec<Option<f64>>,
    /// `None` while it runs; then its status (`complete` …), or why it failed.
    ended: Option<Result<String, String>>,
}

/// The observer of a member's replay: keeps its latest estimates.
struct Keep(Arc<Mutex<Latest>>);

impl ReplayObserver for Keep {
    fn start(&mut self, names: &[&str]) -> std::io::Result<()> {
        lock(&self.0).names = names.iter().map(|n| n.to_string()).collect();
        Ok(())
    }

    fn estimate(&mut self, _t: f64, v: &[Option<f64>], s: &[Option<f64>]) -> std::io::Result<()> {
        let mut l = lock(&self.0);
        l.values.clear();
        l.values.extend_from_slice(v);
        l.sigmas.clear();
        l.sigmas.extend_from_slice(s);
        Ok(())
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// One method following the feed.
struct Member {
    method: &'static str,
    queue: Option<SyncSender<RecordEvent>>,
    latest: Arc<Mutex<Latest>>,
    thread: Option<JoinHandle<()>>,
}

impl Member {
    fn start(kind: EstimatorKind, file: &str, mapping: &Mapping, base: &ReplayOptions) -> Self {
        let (queue, events) = sync_channel(QUEUE_EVENTS);
        let latest = Arc::new(Mutex::new(Latest::default()));
        let opts = ReplayOptions {
            estimator: kind,
            estimator_options: EstimatorOptions::default(),
            compat: None,
            windows: Vec::new(),
            spike_screen: None,
            pacing: crate::replay::Pacing::Unpaced,
            ..base.clone()
        };
        let (file, mapping, keep) = (file.to_string(), mapping.clone(), latest.clone());
        let thread = std::thread::spawn(move || follow(events, &file, &mapping, &opts, keep));
        Self { method: kind.name(), queue: Some(queue), latest, thread: Some(thread) }
    }

    /// Its estimates now (a member that failed or diverged: failed, with why).
    fn estimates(&self) -> MethodEstimates {
        let l = lock(&self.latest);
        match &l.ended {
            Some(Err(why)) => MethodEstimates::failed(self.method, why),
            Some(Ok(status)) => {
                MethodEstimates::new(self.method, status, rows(&l.names, &l.values, &l.sigmas))
            }
            None => {
                MethodEstimates::new(self.method, "running", rows(&l.names, &l.values, &l.sigmas))
            }
        }
    }
}

/// A member's thread: the replay of `events` until the queue closes, its end in `keep`.
fn follow(
    events: Receiver<RecordEvent>,
    file: &str,
    mapping: &Mapping,
    opts: &ReplayOptions,
    keep: Arc<Mutex<Latest>>,
) {
    let mut observer = Keep(keep.clone());
    let ended = match crate::replay::follow(events, file, mapping, opts, &mut observer) {
        Ok(o) if o.diverged() => Err("diverged".to_string()),
        Ok(o) => Ok(o.summary.status),
        Err(e) => Err(e.to_string()),
    };
    lock(&keep).ended = Some(ended);
}

/// The members following a feed (module doc).
pub struct Panel {
    own: &'static str,
    members: Vec<Member>,
    next_judgement_s: f64,
}

impl std::fmt::Debug for Panel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let methods: Vec<&str> = self.members.iter().map(|m| m.method).collect();
        f.debug_struct("Panel").field("own", &self.own).field("members", &methods).finish()
    }
}

impl Panel {
    /// The real-time methods other than `base.estimator`, each started on its own thread to
    /// follow the events of `file` read through `mapping` with `base`'s model and
    /// differentiation.
    pub fn start(file: &str, mapping: &Mapping, base: &ReplayOptions) -> Self {
        let others = ONLINE_METHODS.iter().filter(|&&k| k != base.estimator);
        Self {
            own: base.estimator.name(),
            members: others.map(|&k| Member::start(k, file, mapping, base)).collect(),
            next_judgement_s: f64::NEG_INFINITY,
        }
    }

    /// The methods following the feed.
    pub fn methods(&self) -> Vec<&'static str> {
        self.members.iter().map(|m| m.method).collect()
    }

    /// Hands one event of the feed to every member still running (waits while a member's
    /// queue is full).
    pub fn forward(&mut self, event: &RecordEvent) {
        for m in &mut self.members {
            let Some(q) = &m.queue else { continue };
            let sent = match q.try_send(event.clone()) {
                Err(TrySendError::Full(e)) => q.send(e).is_ok(),
                r => r.is_ok(),
            };
            if !sent {
                // The member's replay ended (it failed or diverged): it keeps its last word.
                m.queue = None;
            }
        }
    }

    /// Whether a judgement is due at record time `t_s` ([`JUDGE_EVERY_S`] after the last; the
    /// first sample's is): when it is, the next is counted from `t_s`.
    pub fn due(&mut self, t_s: f64) -> bool {
        if t_s < self.next_judgement_s {
            return false;
        }
        self.next_judgement_s = t_s + JUDGE_EVERY_S;
        true
    }

    /// The panel's verdict on the feed's own estimates now.
    pub fn judge(
        &self,
        names: &[String],
        values: &[Option<f64>],
        sigmas: &[Option<f64>],
    ) -> CrossCheck {
        let own = MethodEstimates::new(self.own, "running", rows(names, values, sigmas));
        let others: Vec<MethodEstimates> = self.members.iter().map(Member::estimates).collect();
        judge(&own, &others)
    }

    /// The feed's end: closes every queue and waits for each member to estimate what it was
    /// sent, so the next [`judge`](Self::judge) sees each method's estimates over the whole feed.
    pub fn finish(&mut self) {
        for m in &mut self.members {
            m.queue = None;
            if let Some(t) = m.thread.take()
                && t.join().is_err()
            {
                lock(&m.latest).ended = Some(Err("its thread panicked".into()));
            }
        }
    }
}

impl Drop for Panel {
    fn drop(&mut self) {
        self.finish();
    }
}

/// The estimates of the parameters with both a value and a σ.
fn rows<'a>(
    names: &'a [String],
    values: &'a [Option<f64>],
    sigmas: &'a [Option<f64>],
) -> impl Iterator<Item = ParameterEstimate> + 'a {
    let all = names.iter().zip(values.iter().zip(sigmas));
    all.filter_map(|(n, (v, s))| Some(ParameterEstimate::new(n.clone(), (*v)?, (*s)?)))
}

/// Whether the panel disputes the feed's own estimate of a parameter: it is set aside by a
/// tested cause, or another method estimates it and the methods split. A parameter no other
/// method estimates yet is not disputed (module doc).
pub fn disputed(a: &Agreement) -> bool {
    let own_set_aside =
        a.estimates.first().is_some_and(|me| a.set_aside.iter().any(|s| s.method == me.method));
    let kept = a.estimates.iter().filter(|e| !a.set_aside.iter().any(|s| s.method == e.method));
    a.flag.is_some() && (own_set_aside || kept.count() >= 2)
}
