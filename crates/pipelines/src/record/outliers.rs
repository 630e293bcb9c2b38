//! The spike screen: a stage between the reader and every estimator that rejects a row whose
//! measured channel holds an isolated one-sample spike, or one of a short run of them (a
//! corrupt value that is still within the reader's plausibility limits, e.g. a thrust of 10⁶ N
//! in a record at 11.6 kN). One such row owns a least-squares or output-error fit (every batch
//! and recursive estimator minimises squared residuals); the screen keeps it out of all of them
//! alike.
//!
//! **Test** (per channel, per sample `x_i`, over the window of the [`SpikeScreen::half_width`]
//! `h` samples on each side within the same manoeuvre — a gap or a time window ends it; at a
//! manoeuvre's ends the window is shifted to hold `2h` others where it can, not cut):
//!
//! 1. **Hampel identifier**: `|x_i − med| > t · 1.4826 · MAD`, with `med` and `MAD` the median
//!    and the median absolute deviation of the window (`x_i` included), `t` =
//!    [`SpikeScreen::hampel_t`]. 1.4826·MAD is the standard deviation of Gaussian noise, so a
//!    noise sample passes (Hampel 1974; Pearson, "Outliers in process modeling and
//!    identification", IEEE Trans. Control Syst. Technol. 10(1), 2002).
//! 2. **Gross isolation guard**: `x_i` departs from each of its immediate neighbours, on the
//!    same side, by more than each of: [`SpikeScreen::isolation`] × the range of the other
//!    samples of the window; the whole range of the channel over its context (the last
//!    [`CONTEXT`] samples passed in the manoeuvre and the window's samples ahead); 5 % of the
//!    largest `|x|` of that context (a quantisation flick of one step on a constant
//!    channel is not a spike); and 10⁻⁶ (SI units, below any sensor's resolution). A step
//!    (doublet, 3-2-1-1) has its centre sample on the majority side of its window and passes
//!    1; a one-sample pulse of a 3-2-1-1 departs from its neighbours by no more than the
//!    manoeuvre spans, so it passes 2. The guard makes this a screen for gross spikes, a
//!    sample out of the envelope of everything around it (on the shipped HFB-320 record a
//!    genuine `V` sample departs 7 × its window's range, but stays within its context's
//!    range). A one-sample pulse on an otherwise constant channel cannot be told from a
//!    spike: such a record needs the screen off. The other spikes of the window (samples beyond
//!    the Hampel threshold on the same side with both neighbours within it,
//!    [`SpikeScreen::fellow_spikes`]) are left out of the range and of the context ahead, so
//!    a few spikes within one window do not hide each other; the output-error fit's dominance
//!    warning and its Huber option cover what the screen lets through.
//!
//! A sample failing both is rejected ([`RowProblem::Spike`], naming the channel, the value, the
//! median and the threshold), listed in the summary's rejections and counted. The screened
//! channels are every measured one of [`AirDataSample`] except `ψ` (which wraps at ±π).
//!
//! 3. **Short runs** (a corrupt value repeated over 2–3 rows, which 2 cannot see: each member's
//!    neighbour in the run is as far out as itself). For `k` = 2 to [`WARN_RUN_MAX`]
//!    consecutive samples from the tested one, with the `h` samples before the run and the `h`
//!    after it as *others* (at least 2 on each side; at a manoeuvre's start or end, where one
//!    side has fewer than 2, the `h` of the other side): every member departs from the sample
//!    just before the run and the one just after it (the one of them there is), on the same side, by more than the guard
//!    of 2 (isolation × the range of the others; the range of the context, the run left out;
//!    5 % of its largest `|x|`; the floor), and from the others' median by more than
//!    `t · 1.4826 · MAD` of the others. The channel is back at its level on both sides and the
//!    run is outside the envelope of everything around it. The other short runs of a cluster
//!    ahead (runs of up to [`RUN_MAX`] on the same side, a row or two apart,
//!    [`SpikeScreen::fellows`]) are left out of the samples after the run and of the context,
//!    as test 1–2 leaves out the other spikes of its window: a rigid airframe's rates and
//!    angles move continuously (finite moments over finite inertia), so a channel that jumps
//!    out and back within a sample, again and again, beyond everything its clean samples do
//!    around it, is a sensor or a link, not a motion. Runs of up to [`RUN_MAX`] are
//!    rejected whole (each row naming the run's length); runs of [`RUN_MAX`] + 1 to
//!    [`WARN_RUN_MAX`] are only a warning in the summary, for the real-time estimators as for
//!    the batch fits (a record re-gridded with a zero-order hold holds each genuine sample of
//!    a slower channel over several rows: on the UAV-OAT records, airspeed at 10 Hz on a
//!    50 Hz grid, a genuine 5-row level reaches 0.96 of this threshold, where no run of 2–4
//!    on any shipped record reaches 0.32). The control inputs (`δe`, `δa`, `δr`, throttle) are
//!    not tested: a short one-sided pulse is what a pilot's doublet or 3-2-1-1 unit is. A
//!    response channel does not come back within 3 samples from beyond its whole context
//!    range; the step-like parts of a manoeuvre do not come back at all.
//!
//! **Default: on.** A spike is never information an estimator should fit, and the records
//! shipped in `../shared` pass it unchanged (tests); the cost is a lookahead of `h` +
//! [`RUN_MAX`] samples (`2h` + [`RUN_MAX`] at a manoeuvre's start; 0.8 s at 10 Hz) before a
//! sample reaches the estimator, so a paced replay's estimates lag by that much.

use aeroident_estimators::AirDataSample;
use aeroident_io::{FlightDataError, Mapping, RecordEvent, RowProblem};
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

/// Settings of the spike screen (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpikeScreen {
    /// Samples on each side of the tested one (default 5: a window of 11).
    pub half_width: usize,
    /// Hampel threshold `t`, in robust standard deviations `1.4826 · MAD` (default 5).
    pub hampel_t: f64,
    /// Isolation factor: the departure from each neighbour must exceed this multiple of the
    /// range of the rest of the window (default 10; the largest ratio of a genuine sample on
    /// the shipped records is 7, HFB-320 `V` at 39.1 s).
    pub isolation: f64,
}

impl Default for SpikeScreen {
    fn default() -> Self {
        Self { half_width: 5, hampel_t: 5.0, isolation: 10.0 }
    }
}

/// Smallest departure, as a fraction of the largest `|x|` of the context, that can be a spike.
const CONTEXT_FRACTION: f64 = 0.05;

/// Smallest departure that can be a spike, SI units.
const ABSOLUTE_FLOOR: f64 = 1e-6;

/// Samples passed before the tested one that make its context (module doc).
pub const CONTEXT: usize = 100;

/// Most events held ahead of the tested sample (rows the reader rejected in between count):
/// beyond it the sample is decided with the samples ahead it has, so memory stays bounded.
const MAX_AHEAD_EVENTS: usize = 10_000;

/// Fewest samples in a window (the tested one included) for a verdict: a manoeuvre shorter
/// than this is not screened.
const MIN_WINDOW: usize = 5;

/// Longest run of consecutive gross outliers on one channel that the screen rejects (module
/// doc, test 3).
pub const RUN_MAX: usize = 3;

/// Longest run that is reported (a warning, not rejected): runs of [`RUN_MAX`] + 1 to this
/// many samples.
pub const WARN_RUN_MAX: usize = 5;

/// The control inputs among the screened channels: a short pulse on them is the manoeuvre
/// itself (a doublet's half, a 3-2-1-1's units), so test 3 leaves them out (a single sample is
/// still tested, test 1–2).
const INPUTS: [&str; 4] = ["de_rad", "da_rad", "dr_rad", "throttle"];

/// Number of screened channels ([`channels`]).
const N_CHANNELS: usize = 23;

/// The screened channels of `s` by SI name (`None`: not recorded).
fn channels(s: &AirDataSample) -> [(&'static str, Option<f64>); N_CHANNELS] {
    [
        ("vt_mps", Some(s.vt_mps)),
        ("alpha_rad", Some(s.alpha_rad)),
        ("qbar_pa", Some(s.qbar_pa)),
        ("beta_rad", s.beta_rad),
        ("p_rad_s", s.p_rad_s),
        ("q_rad_s", s.q_rad_s),
        ("r_rad_s", s.r_rad_s),
        ("pdot_rad_s2", s.pdot_rad_s2),
        ("qdot_rad_s2", s.qdot_rad_s2),
        ("rdot_rad_s2", s.rdot_rad_s2),
        ("alphadot_rad_s", s.alphadot_rad_s),
        ("phi_rad", s.phi_rad),
        ("theta_rad", s.theta_rad),
        ("ax_mps2", s.ax_mps2),
        ("ay_mps2", s.ay_mps2),
        ("az_mps2", s.az_mps2),
        ("de_rad", s.de_rad),
        ("da_rad", s.da_rad),
        ("dr_rad", s.dr_rad),
        ("thrust_n", s.thrust_n),
        ("throttle", s.throttle),
        ("thrust_moment_nm", s.thrust_moment_nm),
        ("rho_kgpm3", s.rho_kgpm3),
    ]
}

/// The median of `v` and its robust standard deviation `1.4826 · MAD`.
///
/// The screen asks this of every channel of every sample: one buffer per thread, not two
/// allocations per call, and one sort: the deviations' median is merged from the sorted values
/// ([`median_deviation`]), not sorted again.
fn robust(v: &[f64]) -> (f64, f64) {
    thread_local! {
        static SCRATCH: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
    }
    SCRATCH.with_borrow_mut(|buf| {
        buf.clear();
        buf.extend_from_slice(v);
        let med = median(buf);
        if !buf.iter().all(|x| x.is_finite()) {
            // A NaN or infinity breaks the ordering the merge relies on: sort the deviations.
            buf.iter_mut().zip(v).for_each(|(d, x)| *d = (x - med).abs());
            return (med, 1.4826 * median(buf));
        }
        (med, 1.4826 * median_deviation(buf, med))
    })
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// The median of `|x − med|` over the finite, ascending `sorted` (not empty), `med` its median:
/// the deviations of the values below `med` grow as they are read backwards and those of the
/// rest as they are read forwards, so merging the two runs to their middle gives the value
/// [`median`] of the deviations gives, bit for bit (the same differences, the same middle
/// elements), in O(n) instead of a second sort.
fn median_deviation(sorted: &[f64], med: f64) -> f64 {
    let n = sorted.len();
    let split = sorted.partition_point(|&x| x < med);
    let (mut below, mut above) = (split, split);
    let mut next = || {
        let lower = (below > 0).then(|| (sorted[below - 1] - med).abs());
        let upper = (above < n).then(|| (sorted[above] - med).abs());
        match (lower, upper) {
            (Some(l), Some(u)) if l <= u => (below -= 1, l).1,
            (Some(l), None) => (below -= 1, l).1,
            (_, u) => (above += 1, u.unwrap_or(f64::NAN)).1,
        }
    };
    // The deviations in ascending order, up to the one at n / 2.
    let mut previous = f64::NAN;
    for _ in 0..n / 2 {
        previous = next();
    }
    let middle = next();
    if n % 2 == 1 { middle } else { 0.5 * (previous + middle) }
}

impl SpikeScreen {
    /// Checks the settings.
    ///
    /// # Errors
    /// A message naming the setting when the half-width is not 2…500, `t` or the isolation
    /// factor not finite and positive.
    pub fn check(&self) -> Result<(), String> {
        if !(2..=500).contains(&self.half_width) {
            return Err(format!("half-width {} must be 2…500 samples", self.half_width));
        }
        for (name, v) in [("Hampel t", self.hampel_t), ("isolation factor", self.isolation)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} {v} must be finite and positive"));
            }
        }
        Ok(())
    }

    /// Whether `window[centre]` is a spike (module doc): `Some((median, threshold))` if so.
    /// `window` holds one channel's values around the tested sample, in time order;
    /// `context` the channel's values around it that set its scale (the tested one left out).
    pub fn spike(&self, window: &[f64], centre: usize, context: &[f64]) -> Option<(f64, f64)> {
        let x = window[centre];
        let (med, scale) = self.beyond_hampel(window, centre)?;
        let fellows = self.fellow_spikes(window, centre);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (k, &v) in window.iter().enumerate() {
            if k != centre && !fellows[k] {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        let range = if lo <= hi { hi - lo } else { 0.0 };
        let threshold = self.guard(range, med, context);
        let neighbours = [centre.checked_sub(1), Some(centre + 1).filter(|&k| k < window.len())];
        let mut sides = neighbours.iter().flatten().map(|&k| x - window[k]);
        let first = sides.next()?;
        let isolated = first.abs() > threshold
            && sides.all(|d| d.abs() > threshold && d.signum() == first.signum());
        isolated.then_some((med, threshold.max(self.hampel_t * scale)))
    }

    /// Test 1 alone (module doc): `Some((median, 1.4826 · MAD))` of `window` when
    /// `window[centre]` is beyond the Hampel threshold of a window of at least 5 (`MIN_WINDOW`)
    /// samples, else `None` (and then [`Self::spike`] is `None` whatever the context).
    pub fn beyond_hampel(&self, window: &[f64], centre: usize) -> Option<(f64, f64)> {
        if window.len() < MIN_WINDOW {
            return None;
        }
        let (med, scale) = robust(window);
        ((window[centre] - med).abs() > self.hampel_t * scale).then_some((med, scale))
    }

    /// The other samples of `window` that look like `window[centre]` does as a spike
    /// ([`Self::fellows`] beside the one sample `centre`).
    pub fn fellow_spikes(&self, window: &[f64], centre: usize) -> Vec<bool> {
        self.fellows(window, centre..centre + 1)
    }

    /// The other spikes of `window` beside the samples `own` (the tested sample or run, not
    /// empty): the maximal runs of at most [`RUN_MAX`] samples beyond the window's Hampel
    /// threshold on the side of `window[own.start]`, apart from `own`, with the samples just
    /// before and after each run within the threshold (a single sample may also end the
    /// window). A few spikes, or a cluster of short runs a row or two apart, would otherwise
    /// widen each other's range and context until none of them stood out; a genuine
    /// manoeuvre's samples are excluded from neither (a rigid airframe's rates and angles move
    /// continuously, so its excursions are not single rows or short runs back at the level on
    /// both sides; or they are the past the screen passed).
    pub fn fellows(&self, window: &[f64], own: std::ops::Range<usize>) -> Vec<bool> {
        let (med, scale) = robust(window);
        let limit = self.hampel_t * scale;
        let side = (window[own.start] - med).signum();
        let out = |k: usize| (window[k] - med).abs() > limit;
        let same = |k: usize| out(k) && (window[k] - med).signum() == side;
        let mut mask = vec![false; window.len()];
        let mut k = 0;
        while k < window.len() {
            let start = k;
            while k < window.len() && same(k) {
                k += 1;
            }
            if k == start {
                k += 1;
                continue;
            }
            let len = k - start;
            let bounded = |j: Option<usize>| j.is_none_or(|j| own.contains(&j) || !out(j));
            let after = Some(k).filter(|&j| j < window.len());
            let closed = start > 0 && after.is_some() || len == 1;
            let apart = k <= own.start || start >= own.end;
            if len <= RUN_MAX && closed && apart && bounded(start.checked_sub(1)) && bounded(after)
            {
                mask[start..k].iter_mut().for_each(|m| *m = true);
            }
        }
        mask
    }

    /// The gross-outlier guard of test 2 (module doc): the departure from the neighbours must
    /// exceed the isolation factor × `range` (of the window's other samples), the range of
    /// `context` (and `med`), 5 % of its largest `|x|` and the absolute floor.
    fn guard(&self, range: f64, med: f64, context: &[f64]) -> f64 {
        let (clo, chi, big) = context
            .iter()
            .fold((med, med, med.abs()), |(l, h, b), &v| (l.min(v), h.max(v), b.max(v.abs())));
        (self.isolation * range).max(chi - clo).max(CONTEXT_FRACTION * big).max(ABSOLUTE_FLOOR)
    }

    /// Whether `run`, one channel's consecutive values, is a run of gross outliers (module doc,
    /// test 3): `before` and `after` are the channel's values just before and after it (in
    /// time order, at least 2 each; at a manoeuvre's edge one side may have fewer, and the
    /// other must then have `h`), `context` its values around it that set its scale (the run
    /// left out). `Some((median, threshold))` of the samples around the run if so.
    pub fn run_spike(
        &self,
        before: &[f64],
        run: &[f64],
        after: &[f64],
        context: &[f64],
    ) -> Option<(f64, f64)> {
        let h = self.half_width;
        let judged = (before.len() >= 2 && after.len() >= 2)
            || (before.len() < 2 && after.len() >= h)
            || (after.len() < 2 && before.len() >= h);
        if !judged {
            return None;
        }
        // The level the run must depart from: the sample on each side that there is.
        let ends: Vec<f64> = before.last().into_iter().chain(after.first()).copied().collect();
        let first = *run.first()?;
        let others: Vec<f64> = before.iter().chain(after).copied().collect();
        let (lo, hi) = others
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
        let (med, scale) = robust(&others);
        let threshold = self.guard(hi - lo, med, context);
        let side = (first - ends[0]).signum();
        let far = run.iter().all(|&x| {
            ends.iter().all(|&e| (x - e) * side > threshold)
                && (x - med).abs() > self.hampel_t * scale
        });
        far.then_some((med, threshold.max(self.hampel_t * scale)))
    }
}

/// The rest of a run of spikes found at its first sample: the next `left` samples are rejected
/// as its members (their value of `channel`).
#[derive(Debug, Clone, Copy)]
struct RunRest {
    left: usize,
    channel: usize,
    samples: usize,
    median: f64,
    threshold: f64,
}

impl RunRest {
    /// The rejection of the sample on `row` as a member of the run, its channel named `field`.
    fn member(&self, row: u64, sample: &AirDataSample, field: String) -> RecordEvent {
        let value = channels(sample)[self.channel].1;
        let problem = RowProblem::Spike {
            field,
            value: value.unwrap_or(f64::NAN),
            median: self.median,
            threshold: self.threshold,
            samples: self.samples,
        };
        RecordEvent::Rejected { row, problem }
    }
}

/// Warnings of a [`Screened`] stage, shared with whoever reports them after the events are
/// consumed (the stage itself is then inside an iterator chain).
pub type ScreenNotes = Arc<Mutex<Vec<String>>>;

/// The spike screen over a reader's events (module doc); with `None` settings it passes
/// everything.
pub struct Screened<I> {
    inner: I,
    screen: Option<SpikeScreen>,
    /// Values of the last samples passed in the current manoeuvre (at most [`CONTEXT`], at
    /// least `2 half_width`).
    past: VecDeque<[Option<f64>; N_CHANNELS]>,
    /// Events read but not yet passed, the tested sample first.
    ahead: VecDeque<Result<RecordEvent, FlightDataError>>,
    ended: bool,
    rejected: usize,
    /// The members of a run of spikes still to reject.
    run: Option<RunRest>,
    notes: ScreenNotes,
    /// The mapping the record was read with, to name a channel as the user wrote it.
    mapping: Option<Arc<Mapping>>,
}

impl<I: Iterator<Item = Result<RecordEvent, FlightDataError>>> Screened<I> {
    /// The stage over `inner` (settings checked by the caller, [`SpikeScreen::check`]).
    pub fn new(inner: I, screen: Option<SpikeScreen>) -> Self {
        Self {
            inner,
            screen,
            past: VecDeque::new(),
            ahead: VecDeque::new(),
            ended: false,
            rejected: 0,
            run: None,
            notes: ScreenNotes::default(),
            mapping: None,
        }
    }

    /// The stage naming each channel in its messages as `mapping` does
    /// ([`Mapping::field_label`]); without it, by the sample field.
    pub fn named_by(mut self, mapping: Arc<Mapping>) -> Self {
        self.mapping = Some(mapping);
        self
    }

    /// Sample field `field` as the messages name it.
    fn label(&self, field: &str) -> String {
        match &self.mapping {
            Some(m) => m.field_label(field),
            None => format!("`{field}`"),
        }
    }

    /// Rows the screen rejected so far.
    pub fn rejected(&self) -> usize {
        self.rejected
    }

    /// The stage's warnings (runs that look like spikes but are not rejected, module doc),
    /// filled as the events are read.
    pub fn notes(&self) -> ScreenNotes {
        Arc::clone(&self.notes)
    }

    /// Samples ahead of the front event up to the next gap (or error), and whether that
    /// count is final (a gap, an error, the end of the record or the event bound reached).
    fn samples_ahead(&self) -> (usize, bool) {
        let mut n = 0;
        for e in self.ahead.iter().skip(1) {
            match e {
                Ok(RecordEvent::Sample { .. }) => n += 1,
                Ok(RecordEvent::Rejected { .. }) => {}
                Ok(RecordEvent::Gap { .. }) | Err(_) => return (n, true),
            }
        }
        (n, self.ended || self.ahead.len() >= MAX_AHEAD_EVENTS)
    }

    /// Samples wanted ahead of the tested one for test 1–2: `h`, more at a manoeuvre's start
    /// (`2h` others in all).
    fn lookahead(&self, screen: &SpikeScreen) -> usize {
        screen.half_width.max(2 * screen.half_width - self.past.len().min(2 * screen.half_width))
    }

    /// The channels of the samples ahead of the front one, up to the next gap: as many as
    /// test 3 looks at ([`RUN_MAX`] more than test 1–2).
    fn future(&self, screen: &SpikeScreen) -> Vec<[Option<f64>; N_CHANNELS]> {
        self.ahead
            .iter()
            .skip(1)
            .map_while(|e| match e {
                Ok(RecordEvent::Gap { .. }) | Err(_) => None,
                Ok(ev) => Some(ev),
            })
            .filter_map(|e| match e {
                RecordEvent::Sample { sample, .. } => Some(channels(sample).map(|c| c.1)),
                _ => None,
            })
            .take(self.lookahead(screen) + RUN_MAX)
            .collect()
    }

    /// The front sample's verdict: the problem if one of its channels is a spike (test 1–2)
    /// or starts a run of spikes (test 3; the rest of the run to reject with it).
    fn verdict(
        &self,
        screen: &SpikeScreen,
        sample: &AirDataSample,
    ) -> Option<(RowProblem, Option<RunRest>)> {
        let ahead = self.future(screen);
        let future = &ahead[..ahead.len().min(self.lookahead(screen))];
        // A window of 2h others where the manoeuvre has them: shifted, not cut, at its ends.
        let from_past =
            self.past.len().min(2 * screen.half_width - future.len().min(2 * screen.half_width));
        let past = self.past.range(self.past.len() - from_past..);
        let here = channels(sample);
        let mut window = Vec::with_capacity(2 * screen.half_width + 1);
        for (c, &(field, value)) in here.iter().enumerate() {
            let Some(value) = value else { continue };
            window.clear();
            window.extend(past.clone().filter_map(|v| v[c]));
            let centre = window.len();
            window.push(value);
            window.extend(future.iter().filter_map(|v| v[c]));
            // Most samples are within the Hampel threshold: no context is needed for them.
            if screen.beyond_hampel(&window, centre).is_none() {
                continue;
            }
            // The spikes ahead are not yet screened: they must not set the scale.
            let fellows = screen.fellow_spikes(&window, centre);
            let ahead = window.iter().zip(&fellows).skip(centre + 1).filter(|f| !f.1);
            let context: Vec<f64> =
                self.past.iter().filter_map(|v| v[c]).chain(ahead.map(|f| *f.0)).collect();
            if let Some((median, threshold)) = screen.spike(&window, centre, &context) {
                let field = self.label(field);
                return Some((
                    RowProblem::Spike { field, value, median, threshold, samples: 1 },
                    None,
                ));
            }
        }
        here.iter().enumerate().find_map(|(c, &(field, value))| {
            self.run_verdict(screen, sample.t_s, c, field, value?, &ahead)
        })
    }

    /// Test 3 on channel `c` (value `value` in the front sample at `t_s`, `ahead` the samples
    /// after it): the shortest run of 2 to [`WARN_RUN_MAX`] samples from the front one that
    /// is a run of gross outliers. Up to [`RUN_MAX`] samples it is rejected; longer, it is a
    /// warning only. Control inputs are not tested ([`INPUTS`]).
    fn run_verdict(
        &self,
        screen: &SpikeScreen,
        t_s: f64,
        c: usize,
        field: &str,
        value: f64,
        ahead: &[[Option<f64>; N_CHANNELS]],
    ) -> Option<(RowProblem, Option<RunRest>)> {
        if INPUTS.contains(&field) {
            return None;
        }
        let h = screen.half_width;
        let skip = self.past.len().saturating_sub(h);
        let before = || self.past.iter().skip(skip).filter_map(|v| v[c]);
        // A necessary condition first (the others hold `before`), so that the runs are built
        // (and anything allocated) for a sample far out only, not for every sample of every
        // channel.
        let (lo, hi) =
            before().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)));
        // At a manoeuvre's start there is nothing before to compare with: the runs are built.
        if let Some(prev) = before().next_back() {
            let departure = (value - prev).abs();
            if departure <= screen.isolation * (hi - lo) || departure <= ABSOLUTE_FLOOR {
                return None;
            }
        }
        let before: Vec<f64> = before().collect();
        let col: Vec<Option<f64>> = ahead.iter().map(|v| v[c]).collect();
        // Fewer samples ahead than the stage waits for: the manoeuvre ends there, and a run
        // may reach its last sample.
        let at_end = col.len() < self.lookahead(screen) + RUN_MAX;
        let longest = if at_end { col.len() + 1 } else { col.len().saturating_sub(1) };
        for k in 2..=WARN_RUN_MAX.min(longest) {
            let rest = col[..k - 1].iter().copied().collect::<Option<Vec<f64>>>()?;
            let run: Vec<f64> = std::iter::once(value).chain(rest).collect();
            // The other short runs of a cluster ahead must not set the scale (as in test 1–2).
            let next: Vec<f64> = col[k - 1..].iter().flatten().copied().collect();
            let window: Vec<f64> = before.iter().chain(&run).chain(&next).copied().collect();
            let own = before.len()..before.len() + k;
            let fellows = screen.fellows(&window, own.clone());
            let clean: Vec<f64> =
                next.iter().zip(&fellows[own.end..]).filter(|f| !f.1).map(|f| *f.0).collect();
            let after: Vec<f64> = clean.iter().take(h).copied().collect();
            let context: Vec<f64> =
                self.past.iter().filter_map(|v| v[c]).chain(clean.iter().copied()).collect();
            let Some((median, threshold)) = screen.run_spike(&before, &run, &after, &context)
            else {
                continue;
            };
            if k <= RUN_MAX {
                let rest = RunRest { left: k - 1, channel: c, samples: k, median, threshold };
                let problem = RowProblem::Spike {
                    field: self.label(field),
                    value,
                    median,
                    threshold,
                    samples: k,
                };
                return Some((problem, Some(rest)));
            }
            let note = format!(
                "spike screen: {} departs from the samples on both sides like a spike for {k} samples from t = {t_s} s (to {value}, median around them {median}, threshold {threshold}); not rejected (a run longer than {RUN_MAX} samples can be genuine): check those rows, or cut them out with a time window",
                self.label(field)
            );
            if let Ok(mut notes) = self.notes.lock() {
                notes.push(note);
            }
            return None;
        }
        None
    }
}

impl<I: Iterator<Item = Result<RecordEvent, FlightDataError>>> Iterator for Screened<I> {
    type Item = Result<RecordEvent, FlightDataError>;

    fn next(&mut self) -> Option<Self::Item> {
        let Some(screen) = self.screen else { return self.inner.next() };
        loop {
            if self.ahead.is_empty() {
                if self.ended {
                    return None;
                }
                self.pull();
                continue;
            }
            match self.ahead.front() {
                Some(Ok(RecordEvent::Sample { .. })) => {}
                Some(Ok(RecordEvent::Gap { .. })) => {
                    self.past.clear();
                    self.run = None;
                    return self.ahead.pop_front();
                }
                _ => return self.ahead.pop_front(),
            }
            if let Some(rest) = self.run.filter(|r| r.left > 0) {
                self.run = Some(RunRest { left: rest.left - 1, ..rest });
                if let Some(Ok(RecordEvent::Sample { row, sample })) = self.ahead.pop_front() {
                    self.rejected += 1;
                    let field = self.label(channels(&sample)[rest.channel].0);
                    return Some(Ok(rest.member(row, &sample, field)));
                }
                continue;
            }
            let (n, last) = self.samples_ahead();
            if n < self.lookahead(&screen) + RUN_MAX && !last {
                self.pull();
                continue;
            }
            let verdict = match self.ahead.front() {
                Some(Ok(RecordEvent::Sample { sample, .. })) => self.verdict(&screen, sample),
                _ => None,
            };
            let Some(Ok(RecordEvent::Sample { row, sample })) = self.ahead.pop_front() else {
                continue;
            };
            if let Some((problem, rest)) = verdict {
                self.rejected += 1;
                self.run = rest;
                return Some(Ok(RecordEvent::Rejected { row, problem }));
            }
            if self.past.len() >= CONTEXT.max(2 * screen.half_width) {
                self.past.pop_front();
            }
            self.past.push_back(channels(&sample).map(|c| c.1));
            return Some(Ok(RecordEvent::Sample { row, sample }));
        }
    }
}

impl<I: Iterator<Item = Result<RecordEvent, FlightDataError>>> Screened<I> {
    /// Reads one more event into `ahead` (an error or the end stops the reading).
    fn pull(&mut self) {
        match self.inner.next() {
            Some(e) => {
                if e.is_err() {
                    self.ended = true;
                }
                self.ahead.push_back(e);
            }
            None => self.ended = true,
        }
    }
}

#[cfg(test)]
mod tests;
