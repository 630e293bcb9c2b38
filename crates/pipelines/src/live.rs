//! The live view of a replay: what a control room watches while a feed runs through the
//! replay job ([`crate::replay`]), as a state a server reads and as JSON messages.
//!
//! [`LiveObserver`] is a [`ReplayObserver`]: on the replay's thread it pushes each estimated
//! sample (time, estimates, σ, the control inputs) into a shared [`LiveState`], steps each
//! derivative's state machine ([`phase`]: waiting for excitation / converging / identified /
//! flagged, with the reason), counts the record's events (samples read, rejected rows, gaps)
//! and keeps the warnings. With a [`pace::Pace`] it also holds a recorded file at N × real
//! time. With a [`panel::Panel`] the record's other real-time methods follow the feed and the
//! cross-check judges the estimates once a second of record time, flagging the derivatives the
//! methods split on. The lock is held for a push only (microseconds), so a view that nobody
//! watches costs the replay nothing measurable.
//!
//! A server reads the state with [`LiveState::hello`] (names, references, rule, model line)
//! and [`LiveState::update`] from a [`Cursor`]: the points after the cursor, the latest sample
//! (always exact, whatever the history keeps), the states, the inputs' excitation, the feed's
//! statistics, new warnings and, at the end, the final verdicts ([`LiveState::conclude`]). A
//! client that connects late starts from a fresh cursor and so gets the whole history first.
//!
//! **History.** Every sample is kept up to [`LiveConfig::max_points`]; past it every other
//! point is dropped and from then on one sample in `stride` is kept (the stride doubling each
//! time), as the replay's own history does ([`crate::replay::History`]): a long feed stays
//! bounded and keeps its first sample and, through `latest`, its last.
//!
//! **Excitation.** Per control input (δe, δa, δr), the standard deviation about its mean over
//! the last [`LiveConfig::excitation_window_s`], rad: zero while the input is held, the size of
//! the manoeuvre while it is flown.

pub mod pace;
pub mod panel;
pub mod phase;

use crate::replay::ReplayObserver;
use crate::replay::cross_check::CrossCheck;
use aeroident_estimators::{AirDataSample, Param};
use aeroident_io::mavlink::LinkStats;
use aeroident_io::replay_output::ReplaySummary;
use aeroident_io::{ModelSpec, RecordEvent};
use pace::Pace;
use panel::Panel;
use phase::{Phase, PhaseRule, Tracker};
use serde::Serialize;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex, PoisonError};

/// The control inputs drawn and measured for excitation, by their sample field.
pub const INPUTS: [&str; 3] = ["de", "da", "dr"];

/// Settings of a live view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveConfig {
    /// The states' thresholds.
    pub rule: PhaseRule,
    /// Window of the excitation measure, s (default 2 s).
    pub excitation_window_s: f64,
    /// Points kept before the history is decimated (default 20,000: ≈ 3 min at 100 Hz in
    /// full, ≈ 10 MB for 30 derivatives).
    pub max_points: usize,
    /// Warnings kept (the first ones; later ones are counted; default 200).
    pub max_warnings: usize,
}

impl Default for LiveConfig {
    fn default() -> Self {
        Self {
            rule: PhaseRule::default(),
            excitation_window_s: 2.0,
            max_points: 20_000,
            max_warnings: 200,
        }
    }
}

/// One estimated sample: its index among the estimated samples, time (s), estimates, σ
/// (`null`: none) and control inputs δe, δa, δr (rad; `null`: not recorded).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Point {
    /// Index among the estimated samples (0 = first).
    pub seq: u64,
    /// Sample time, s.
    pub t: f64,
    /// Estimates, in the order of the names.
    pub v: Vec<Option<f64>>,
    /// σ, in the order of the names.
    pub s: Vec<Option<f64>>,
    /// δe, δa, δr, rad.
    pub u: [Option<f64>; 3],
}

/// What the feed delivered so far, from the record's events.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct FeedStats {
    /// Rows read (samples and rejected rows).
    pub rows_read: u64,
    /// Rows the reader rejected (unreadable, out of range, a spike).
    pub rows_rejected: u64,
    /// Samples estimated.
    pub samples_estimated: u64,
    /// Gaps in the time channel (each starts a new manoeuvre).
    pub gaps: u64,
    /// The longest gap, s.
    pub longest_gap_s: f64,
}

/// A derivative's state as the view shows it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParamState {
    /// The state.
    pub phase: Phase,
    /// Why it is flagged.
    pub reason: Option<String>,
}

/// The final verdict of a derivative, from the summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    /// The summary's status (`identified`, `flagged`, …).
    pub status: String,
    /// The summary's reference, if any.
    pub reference: Option<f64>,
    /// Whether ±2σ covers the reference (the summary's `reference_check`), beside the verdict;
    /// `None` without a reference or a σ.
    pub within_2sigma: Option<bool>,
}

/// The first message to a client: what the view is about.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Hello {
    /// The model line (empty until the first sample chose the model).
    pub model: String,
    /// Parameter names.
    pub names: Vec<String>,
    /// Published references where known (a model file's `[reference.X]`).
    pub references: Vec<Option<f64>>,
    /// The control inputs' names.
    pub inputs: [&'static str; 3],
    /// σ / |estimate| of an identified derivative.
    pub sigma_fraction: f64,
    /// Its hold time, s.
    pub hold_s: f64,
}

/// What a client has been sent so far.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Cursor {
    /// Points up to this `seq + 1` were sent (0: none).
    pub next_seq: u64,
    /// Warnings sent.
    pub warnings: usize,
}

/// One update to a client ([`LiveState::update`]).
#[derive(Debug, Clone, Serialize)]
pub struct Update<'a> {
    /// History points not yet sent, in order.
    pub points: &'a [Point],
    /// The latest sample (also when the history skipped it).
    pub latest: Option<&'a Point>,
    /// Each derivative's state.
    pub states: Vec<ParamState>,
    /// The excitation of δe, δa, δr over the window, rad (`null`: not recorded).
    pub excitation: [Option<f64>; 3],
    /// The feed's counts.
    pub stats: FeedStats,
    /// The link's line (a live MAVLink feed).
    pub link: Option<String>,
    /// The running cross-check's line: the methods following the feed and the last
    /// judgement ([`panel`]); `None` without a panel.
    pub cross_check: Option<&'a str>,
    /// New warnings.
    pub warnings: &'a [String],
    /// Warnings beyond those kept.
    pub warnings_dropped: usize,
    /// Samples per kept history point.
    pub stride: u64,
    /// Whether the feed has ended.
    pub ended: bool,
    /// The summary's status once written (`complete`, `interrupted` …).
    pub status: Option<&'a str>,
    /// The final verdicts, once the summary is written.
    pub verdicts: Option<&'a [Verdict]>,
}

/// The state of a live view (module doc), shared between the replay and a server.
#[derive(Debug)]
pub struct LiveState {
    config: LiveConfig,
    /// The model file's (references, plausible ranges), else a preset's (conventional ranges).
    spec: ModelSpec,
    model_line: String,
    names: Vec<String>,
    params: Vec<Option<Param>>,
    references: Vec<Option<f64>>,
    trackers: Vec<Tracker>,
    /// Each derivative's running flags: plausibility, then the panel's.
    flags: Vec<[Option<String>; 2]>,
    cross_check: Option<String>,
    last_check: Option<CrossCheck>,
    points: Vec<Point>,
    stride: u64,
    latest: Option<Point>,
    recent_inputs: VecDeque<(f64, [Option<f64>; 3])>,
    stats: FeedStats,
    warnings: Vec<String>,
    warnings_dropped: usize,
    link: Option<Arc<Mutex<LinkStats>>>,
    ended: bool,
    status: Option<String>,
    verdicts: Option<Vec<Verdict>>,
}

/// A [`LiveState`] behind a lock, as the replay and a server share it.
pub type SharedLive = Arc<Mutex<LiveState>>;

impl LiveState {
    /// An empty view with `config`; `spec` is the model when known before the first sample (a
    /// model file: its references and plausible ranges), else the conventional ranges apply.
    pub fn new(config: LiveConfig, spec: Option<ModelSpec>) -> Self {
        Self {
            config,
            spec: spec.unwrap_or_else(conventional),
            model_line: String::new(),
            names: Vec::new(),
            params: Vec::new(),
            references: Vec::new(),
            trackers: Vec::new(),
            flags: Vec::new(),
            cross_check: None,
            last_check: None,
            points: Vec::new(),
            stride: 1,
            latest: None,
            recent_inputs: VecDeque::new(),
            stats: FeedStats::default(),
            warnings: Vec::new(),
            warnings_dropped: 0,
            link: None,
            ended: false,
            status: None,
            verdicts: None,
        }
    }

    /// The view shared ([`SharedLive`]).
    pub fn shared(self) -> SharedLive {
        Arc::new(Mutex::new(self))
    }

    /// The first message to a client.
    pub fn hello(&self) -> Hello {
        Hello {
            model: self.model_line.clone(),
            names: self.names.clone(),
            references: self.references.clone(),
            inputs: INPUTS,
            sigma_fraction: self.config.rule.sigma_fraction,
            hold_s: self.config.rule.hold_s,
        }
    }

    /// The parameter names (empty before the first sample).
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The kept history (module doc).
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// The latest estimated sample.
    pub fn latest(&self) -> Option<&Point> {
        self.latest.as_ref()
    }

    /// Each derivative's state now.
    pub fn states(&self) -> Vec<ParamState> {
        self.trackers
            .iter()
            .map(|k| ParamState { phase: k.phase(), reason: k.reason().map(str::to_string) })
            .collect()
    }

    /// The feed's counts so far.
    pub fn stats(&self) -> FeedStats {
        self.stats
    }

    /// Whether the feed has ended.
    pub fn ended(&self) -> bool {
        self.ended
    }

    /// Whether the final verdicts are in ([`LiveState::conclude`]).
    pub fn concluded(&self) -> bool {
        self.verdicts.is_some()
    }

    /// The excitation of δe, δa, δr over the window (module doc), rad.
    pub fn excitation(&self) -> [Option<f64>; 3] {
        std::array::from_fn(|i| {
            let xs: Vec<f64> = self.recent_inputs.iter().filter_map(|(_, u)| u[i]).collect();
            if xs.is_empty() {
                return None;
            }
            let n = xs.len() as f64;
            let mean = xs.iter().sum::<f64>() / n;
            Some((xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt())
        })
    }

    /// The update after `cursor`, which it advances.
    pub fn update(&self, cursor: &mut Cursor) -> Update<'_> {
        let from = self.points.partition_point(|p| p.seq < cursor.next_seq);
        let points = &self.points[from..];
        if let Some(p) = self.points.last() {
            cursor.next_seq = cursor.next_seq.max(p.seq + 1);
        }
        let warnings = &self.warnings[cursor.warnings.min(self.warnings.len())..];
        cursor.warnings = self.warnings.len();
        Update {
            points,
            latest: self.latest.as_ref(),
            states: self.states(),
            excitation: self.excitation(),
            stats: self.stats,
            link: self
                .link
                .as_ref()
                .map(|l| l.lock().unwrap_or_else(PoisonError::into_inner).line()),
            cross_check: self.cross_check.as_deref(),
            warnings,
            warnings_dropped: self.warnings_dropped,
            stride: self.stride,
            ended: self.ended,
            status: self.status.as_deref(),
            verdicts: self.verdicts.as_deref(),
        }
    }

    /// A live MAVLink feed's link statistics, read at each update (datagrams, messages lost,
    /// dropped by a full queue, duplicates …: [`LinkStats::line`]).
    pub fn watch_link(&mut self, stats: Arc<Mutex<LinkStats>>) {
        self.link = Some(stats);
    }

    /// The methods of a running cross-check ([`panel`]), named on the page until it judges.
    pub fn watch_panel(&mut self, methods: &[&str]) {
        self.cross_check = Some(format!("{} follow the feed; not judged yet", methods.join(", ")));
    }

    /// A judgement of the running cross-check at `t_s`: each derivative the panel disputes
    /// ([`panel::disputed`]) is flagged with the panel's words until the next judgement.
    pub fn cross_checked(&mut self, t_s: f64, check: &CrossCheck) {
        let mut disputed = 0;
        for (i, name) in self.names.iter().enumerate() {
            let a = check.parameters.iter().find(|a| a.parameter == *name);
            let flag = a.filter(|a| panel::disputed(a)).and_then(|a| a.flag.clone());
            disputed += usize::from(flag.is_some());
            self.flags[i][1] = flag;
            self.trackers[i].flag(joined(&self.flags[i]));
        }
        let others: Vec<&str> = check.methods.iter().skip(1).map(|m| m.method.as_str()).collect();
        self.cross_check = Some(format!(
            "{} follow the feed; at t = {t_s:.1} s they dispute {disputed} of {} estimates",
            others.join(", "),
            check.compared
        ));
        self.last_check = Some(check.clone());
    }

    /// The running cross-check's last judgement (`None` before the first, or without one).
    pub fn cross_check(&self) -> Option<&CrossCheck> {
        self.last_check.as_ref()
    }

    /// The end of the job: the summary's status, each derivative's verdict and reference,
    /// and its flags as the reason of a flagged state ([`phase::Tracker::conclude`]).
    pub fn conclude(&mut self, summary: &ReplaySummary) {
        self.ended = true;
        self.status = Some(summary.status.clone());
        let mut verdicts = Vec::with_capacity(self.names.len());
        for (i, name) in self.names.iter().enumerate() {
            let p = summary.parameters.iter().find(|p| p.result.name == *name);
            if let (Some(p), Some(k)) = (p, self.trackers.get_mut(i)) {
                k.conclude(&p.result.status, &p.result.flags);
            }
            let reference = p.and_then(|p| p.result.reference).or(self.references[i]);
            let status =
                p.map_or_else(|| "not in summary".to_string(), |p| p.result.status.clone());
            let within_2sigma =
                p.and_then(|p| p.result.reference_check.as_ref()).and_then(|c| c.within_2sigma);
            verdicts.push(Verdict { status, reference, within_2sigma });
        }
        self.verdicts = Some(verdicts);
    }

    /// The end of a job that wrote no summary's verdicts (it failed, or a signal stopped it
    /// before any): the feed is over with `status` (`failed`, `interrupted`) and `why` as a
    /// warning. A view already concluded keeps the summary's status.
    pub fn abandon(&mut self, status: &str, why: &str) {
        if self.concluded() {
            return;
        }
        self.ended = true;
        self.status = Some(status.to_string());
        self.warn(&format!("{status}: {why}"));
    }

    fn start(&mut self, names: &[&str]) {
        self.names = names.iter().map(|n| n.to_string()).collect();
        self.params = names.iter().map(|n| Param::from_name(n)).collect();
        self.references = names.iter().map(|n| self.spec.reference(n)).collect();
        self.trackers = vec![Tracker::default(); names.len()];
        self.flags = vec![[None, None]; names.len()];
        self.points.clear();
        self.stride = 1;
        self.latest = None;
    }

    fn push(&mut self, point: Point) {
        for (i, k) in self.trackers.iter_mut().enumerate() {
            let (v, s) = (point.v[i], point.s[i]);
            self.flags[i][0] = match (self.params[i], v) {
                (Some(p), Some(v)) => crate::plausibility::implausible(&self.spec, p, v, s),
                _ => None,
            };
            k.step(&self.config.rule, point.t, v, s, joined(&self.flags[i]));
        }
        let window = self.config.excitation_window_s;
        self.recent_inputs.push_back((point.t, point.u));
        while self.recent_inputs.front().is_some_and(|(t, _)| point.t - t > window) {
            self.recent_inputs.pop_front();
        }
        self.stats.samples_estimated += 1;
        if point.seq.is_multiple_of(self.stride) {
            self.points.push(point.clone());
            if self.points.len() > self.config.max_points.max(2) {
                let mut k = 0;
                self.points.retain(|_| (k % 2 == 0, k += 1).0);
                self.stride *= 2;
            }
        }
        self.latest = Some(point);
    }

    fn warn(&mut self, text: &str) {
        if self.warnings.len() < self.config.max_warnings {
            self.warnings.push(text.to_string());
        } else {
            self.warnings_dropped += 1;
        }
    }

    fn count(&mut self, event: &RecordEvent) {
        match event {
            RecordEvent::Sample { .. } => self.stats.rows_read += 1,
            RecordEvent::Rejected { .. } => {
                self.stats.rows_read += 1;
                self.stats.rows_rejected += 1;
            }
            RecordEvent::Gap { dt_s, .. } => {
                self.stats.gaps += 1;
                self.stats.longest_gap_s = self.stats.longest_gap_s.max(*dt_s);
            }
        }
    }
}

/// The running flags' reasons, joined (`None`: none).
fn joined(flags: &[Option<String>; 2]) -> Option<String> {
    let reasons: Vec<&str> = flags.iter().flatten().map(String::as_str).collect();
    (!reasons.is_empty()).then(|| reasons.join("; "))
}

/// A model of no aircraft in particular: the conventional plausible ranges
/// ([`ModelSpec::plausible_range`] without a model file's own), no references.
fn conventional() -> ModelSpec {
    ModelSpec::preset("six-axis").expect("six-axis is a preset")
}

fn lock(shared: &SharedLive) -> std::sync::MutexGuard<'_, LiveState> {
    shared.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The [`ReplayObserver`] of a live view (module doc): pushes into the shared state, and
/// paces a recorded file when given a [`Pace`].
#[derive(Debug)]
pub struct LiveObserver {
    shared: SharedLive,
    pace: Option<Pace>,
    panel_wanted: bool,
    panel: Option<Panel>,
    inputs: [Option<f64>; 3],
    seq: u64,
}

impl LiveObserver {
    /// An observer pushing into `shared`, at `pace` when given.
    pub fn new(shared: SharedLive, pace: Option<Pace>) -> Self {
        Self { shared, pace, panel_wanted: false, panel: None, inputs: [None; 3], seq: 0 }
    }

    /// The observer with a running cross-check when `on` (module doc); the panel starts with
    /// the feed's options ([`Self::begin`]).
    pub fn with_cross_check(mut self, on: bool) -> Self {
        self.panel_wanted = on;
        self
    }

    /// The feed begins: the page lists the corrections the replay applies and refuses
    /// (`--compat`, which the summary lists at the end) at once, and the running cross-check
    /// starts if asked for ([`Self::with_cross_check`]): the other real-time methods follow
    /// the events of `file`, read through `mapping` with the feed's `opts` ([`Panel::start`]).
    /// Returns whether the cross-check runs.
    pub fn begin(
        &mut self,
        file: &str,
        mapping: &aeroident_io::Mapping,
        opts: &crate::replay::ReplayOptions,
    ) -> bool {
        if let Some(c) = &opts.compat {
            let mut live = lock(&self.shared);
            c.warnings().for_each(|w| live.warn(&w.to_string()));
        }
        if !self.panel_wanted || self.panel.is_some() {
            return self.panel.is_some();
        }
        let panel = Panel::start(file, mapping, opts);
        lock(&self.shared).watch_panel(&panel.methods());
        self.panel = Some(panel);
        true
    }

    /// The state it pushes into.
    pub fn shared(&self) -> SharedLive {
        self.shared.clone()
    }
}

impl ReplayObserver for LiveObserver {
    fn model(&mut self, line: &str) {
        lock(&self.shared).model_line = line.to_string();
    }

    fn start(&mut self, names: &[&str]) -> std::io::Result<()> {
        lock(&self.shared).start(names);
        Ok(())
    }

    fn record_event(&mut self, event: &RecordEvent) {
        if let Some(p) = self.panel.as_mut() {
            p.forward(event);
        }
        lock(&self.shared).count(event);
    }

    fn sample(&mut self, sample: &AirDataSample) {
        self.inputs = [sample.de_rad, sample.da_rad, sample.dr_rad];
    }

    fn estimate(
        &mut self,
        t_s: f64,
        values: &[Option<f64>],
        sigmas: &[Option<f64>],
    ) -> std::io::Result<()> {
        if let Some(p) = self.pace.as_mut() {
            let wait = p.wait(t_s, std::time::Instant::now());
            if !wait.is_zero() {
                std::thread::sleep(wait);
            }
        }
        let point =
            Point { seq: self.seq, t: t_s, v: values.to_vec(), s: sigmas.to_vec(), u: self.inputs };
        self.seq += 1;
        lock(&self.shared).push(point);
        if let Some(p) = self.panel.as_mut()
            && p.due(t_s)
        {
            let mut live = lock(&self.shared);
            let check = p.judge(&live.names, values, sigmas);
            live.cross_checked(t_s, &check);
        }
        Ok(())
    }

    fn warning(&mut self, text: &str) {
        lock(&self.shared).warn(text);
    }

    /// The feed's end; a panel's members finish what they were sent and judge once more,
    /// on every method's estimates over the whole feed.
    fn finish(&mut self) -> std::io::Result<()> {
        if let Some(p) = self.panel.as_mut() {
            p.finish();
            let mut live = lock(&self.shared);
            if let Some(last) = live.latest.clone() {
                let check = p.judge(&live.names, &last.v, &last.s);
                live.cross_checked(last.t, &check);
            }
        }
        lock(&self.shared).ended = true;
        Ok(())
    }
}

#[cfg(test)]
mod tests;
