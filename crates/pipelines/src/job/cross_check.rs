//! The check step of both jobs: the record's other applicable methods run on the same data,
//! model, corrections and windows, for the panel of [`crate::replay::cross_check`] to judge.
//! It runs by default without the filter-error method ([`Panel`]); `--cross-check` adds it,
//! `--no-cross-check` turns the panel off.
//!
//! The panel: equation error (`rls`), instrumental variables (`rls-iv`) and the EKF, which
//! read one record sample by sample (so only without `--and`), and output error, the
//! filter-error method and frequency-domain output error (over its default band,
//! [`aeroident_estimators::output_error::frequency::DEFAULT_BAND_HZ`], clipped below each
//! record's Nyquist frequency) over every record. The frequency-domain fit costs a fraction of
//! output error's since its transforms are FFTs; on the verdict audit's 156 estimates
//! (`scripts/verdict_audit.py --cross-check`) it took one `identified` more than 10 % off the
//! truth out of seven (RLS Cm_δe on a noisy c172 3-2-1-1) and cost none within 10 %.

use super::{Guard, JobLog, Records, Step};
use crate::estimators::EstimatorKind;
use crate::replay::ReplayError;
use crate::replay::ReplayOptions;
use crate::replay::batch::{BatchMethod, FitOptions};
use crate::replay::cross_check::CrossCheck;
use crate::replay::cross_check::{MethodEstimates, ParameterEstimate};
use crate::window::TimeWindow;
use aeroident_io::parameter::STATUS_NOT_CONVERGED;

/// The panel's real-time methods (one record only).
pub const ONLINE_METHODS: [EstimatorKind; 3] =
    [EstimatorKind::Rls, EstimatorKind::RlsIv, EstimatorKind::Ekf];

/// The panel's batch methods.
pub const BATCH_METHODS: [EstimatorKind; 3] =
    [EstimatorKind::Oe, EstimatorKind::Fem, EstimatorKind::Fdoe];

/// Which panel a job runs after its estimator.
///
/// By default ([`Panel::Fast`]) every method but the filter-error method: on the calibration
/// corpus (`scripts/verdict_corpus`, docs/validation.md) the others cost 3.6 s per record
/// together and `fem` 16 s on average (82 s at most), and that panel, its estimates compared
/// on their noise σ, took the precision of `identified` from 84.9 % to 92.9 % at a recall of
/// 85.4 % → 68.4 % on the tune half, and from 86.7 % to 92.4 % (recall 83.2 → 71.7 %) on the
/// held-out half. The panel *is* the verdict's test of method disagreement, so it runs
/// unless turned off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Panel {
    /// No panel (`--no-cross-check`): least squares keeps its own regressor-noise test
    /// ([`regressor_noise_test`]) and the summary says the panel was not run.
    Off,
    /// Every panel method but `fem` (the default).
    #[default]
    Fast,
    /// Every panel method, `fem` too (`--cross-check`).
    Full,
}

impl Panel {
    /// Whether the panel runs at all.
    pub fn runs(self) -> bool {
        self != Panel::Off
    }

    /// The panel of a face's two flags: `--cross-check` (full) and `--no-cross-check` (off);
    /// neither, the default.
    pub fn from_flags(full: bool, off: bool) -> Self {
        match (full, off) {
            (true, _) => Panel::Full,
            (false, true) => Panel::Off,
            (false, false) => Panel::Fast,
        }
    }

    /// Whether `kind` sits on this panel (every method for [`Panel::Full`], all but `fem` for
    /// [`Panel::Fast`], none when off).
    fn holds(self, kind: EstimatorKind) -> bool {
        match self {
            Panel::Off => false,
            Panel::Fast => kind != EstimatorKind::Fem,
            Panel::Full => true,
        }
    }
}

/// Why a panel [`Panel::Off`] was not run, in [`not_run_warning`].
pub const TURNED_OFF: &str = "turned off: --no-cross-check, Python cross_check=False";

/// Why no panel runs on a live feed (stdin, MAVLink), in [`not_run_warning`]: the other
/// methods would have to read it again.
pub const LIVE_FEED: &str = "a live feed or stdin cannot be read again";

/// The summary warning of a job whose panel was not run, with `why` (about no parameter: it
/// flags none, it says what the verdict did not test).
pub fn not_run_warning(why: &str) -> aeroident_io::warning::Warning {
    let text = format!(
        "cross-check not run ({why}): no other method was set beside these estimates, so a disagreement between methods cannot flag them"
    );
    aeroident_io::warning::Warning::new(aeroident_io::warning::WarningKind::CrossCheck, text)
}

/// Every method of `panel` but `own`, each run on `records` with `base`'s model,
/// corrections, windows, spike screen and differentiation (each estimator with its own
/// default options). A method that fails, diverges, ends `initialising`, ends at its
/// iteration limit still moving, or whose filter degenerates is listed as failed, with why:
/// agreement with an estimator that has not converged confirms nothing.
///
/// `long`: the windows the costly methods (the EKF and the batch fits) run on instead of the
/// whole record, for a long one ([`long_record_windows`]).
///
/// The methods are independent, so they run on the thread pool (rayon), listed in the
/// panel's order whatever order they end in: each estimate is the one a run alone gives.
pub fn run_panel(
    records: &Records,
    own: EstimatorKind,
    base: &ReplayOptions,
    panel: Panel,
    long: Option<&[TimeWindow]>,
) -> Vec<MethodEstimates> {
    let on = |k: &&EstimatorKind| **k != own && panel.holds(**k);
    let windowed = long.map(|w| ReplayOptions { windows: w.to_vec(), ..base.clone() });
    let costly = windowed.as_ref().unwrap_or(base);
    let online = ONLINE_METHODS.iter().filter(|_| records.and.is_empty()).filter(on);
    let batch = BATCH_METHODS.iter().filter(on);
    let methods: Vec<(EstimatorKind, bool)> =
        online.map(|&k| (k, false)).chain(batch.map(|&k| (k, true))).collect();
    // Greedy, longest first: each method is taken in `cost_rank` order by the first thread
    // that is free (a FIFO scope), so the costliest does not start last on a thread the others
    // kept busy (the six-axis EKF over a 600-s record costs more than the rest together on
    // the other core). The results are put back in the panel's order.
    let mut order: Vec<usize> = (0..methods.len()).collect();
    order.sort_by_key(|&i| cost_rank(methods[i].0, long.is_some()));
    let (done, ran) = std::sync::mpsc::channel();
    rayon::scope_fifo(|scope| {
        for &i in &order {
            let done = done.clone();
            let method = methods[i];
            scope.spawn_fifo(move |_| {
                let estimates = match method {
                    (k, true) => run_batch(records, k, costly),
                    (k @ EstimatorKind::Ekf, false) => run_online(records, k, costly),
                    (k, false) => run_online(records, k, base),
                };
                // The receiver outlives the scope: the send cannot fail.
                let _ = done.send((i, estimates));
            });
        }
    });
    drop(done);
    let mut ran: Vec<(usize, MethodEstimates)> = ran.into_iter().collect();
    ran.sort_by_key(|(i, _)| *i);
    ran.into_iter().map(|(_, estimates)| estimates).collect()
}

/// The order the panel's methods start in, costliest first, by what each costs on the
/// samples it runs on. On the whole record: the six-axis EKF (≈ 22 µs a sample,
/// docs/six-axis.md), then the frequency-domain and time-domain batch fits, then the
/// recursions (a few µs a sample). When the EKF and the batch fits run on a long record's
/// windows (`windowed`), the recursions, which still read the whole record, cost the most
/// (instrumental variables over an hour ≈ 1.4 s), then the batch fits (output error ≈ 1.5 s,
/// fdoe ≈ 1.3 s on the hour's windows), and the EKF least (≈ 0.1 s).
fn cost_rank(kind: EstimatorKind, windowed: bool) -> u8 {
    match (kind, windowed) {
        (EstimatorKind::Ekf, false) => 0,
        (EstimatorKind::Fdoe, false) => 1,
        (EstimatorKind::Fem, false) => 2,
        (EstimatorKind::Oe, false) => 3,
        (_, false) => 4,
        (EstimatorKind::Oe, true) => 1,
        (EstimatorKind::Fdoe, true) => 2,
        (EstimatorKind::Fem, true) => 3,
        (EstimatorKind::Ekf, true) => 4,
        (_, true) => 0,
    }
}

/// For a record held in memory ([`Records::held`]) with a stretch longer than
/// [`crate::compat::long::LONG_STRETCH_S`] without a gap, and no windows asked for: the best
/// manoeuvres per axis by the information they hold (the compatibility check's choice for a
/// long record, [`crate::compat::long::judged`]) and the warning that names them. The EKF and
/// the batch fits run on those: output error over an hour at 100 Hz would need tens of GB
/// (it refuses), the six-axis EKF costs 41 µs a sample (15 s an hour), and the information
/// of a whole flight is in its manoeuvres. Least squares and instrumental variables, whose
/// comparison is the regressor-noise test and so must see the same samples as the run's
/// own, stay on the whole record. `None` otherwise: the panel runs whole.
pub fn long_record_windows(
    records: &Records,
    base: &ReplayOptions,
) -> Option<(Vec<TimeWindow>, aeroident_io::warning::Warning)> {
    if !base.windows.is_empty() {
        return None;
    }
    let held = records.held_with(base.spike_screen)?;
    let read = crate::record::read_cached(held, base.compat.as_ref(), &[]).ok()?;
    let crate::compat::long::Judged::Windows(windows, _) =
        crate::compat::long::judged(&read.manoeuvres)
    else {
        return None;
    };
    let spans: Vec<String> =
        windows.iter().map(|w| format!("{:.2}–{:.2} s", w.start_s, w.end_s)).collect();
    let warning = format!(
        "cross-check: the record runs more than {:.0} s without a gap: the EKF and the batch fits \
         ran on its best {} manoeuvres per axis by the information they hold, {} window(s): {}; \
         least squares and instrumental variables on the whole record; give `--window \
         START:END` to check other spans",
        crate::compat::long::LONG_STRETCH_S,
        crate::compat::long::LONG_RECORD_SET_SIZE,
        windows.len(),
        spans.join(", ")
    );
    let kind = aeroident_io::warning::WarningKind::CrossCheck;
    Some((windows, aeroident_io::warning::Warning::new(kind, warning)))
}

/// The regressor-noise test of a least-squares replay (`rls`, `ftr`) whose own estimates are
/// `own`: the record replayed by instrumental variables with `base`'s model, corrections and
/// windows under `guard` ([`crate::replay::cross_check::regressor_noise`]), its warnings to
/// `log` and `warnings`; nothing for another estimator, several records, a live feed (stdin
/// or MAVLink: it cannot be read twice; a live view's running cross-check holds rls-iv), or a
/// stop (a warning says the test was not done).
///
/// # Errors
/// The face could not run the step.
pub fn regressor_noise_test(
    records: &Records,
    own: &MethodEstimates,
    base: ReplayOptions,
    guard: &mut impl Guard,
    log: &mut dyn JobLog,
    warnings: &mut aeroident_io::warning::Warnings,
) -> Result<(), ReplayError> {
    let least_squares = matches!(base.estimator, EstimatorKind::Rls | EstimatorKind::Ftr);
    if !least_squares || !records.and.is_empty() || records.live {
        return Ok(());
    }
    let records = records.clone();
    let step = move || run_online(&records, EstimatorKind::RlsIv, &base);
    let Some(iv) = guard.run(Step::RegressorNoise, step)? else {
        abandoned("the regressor-noise test", log, warnings);
        return Ok(());
    };
    for w in crate::replay::cross_check::regressor_noise(own, &iv) {
        log.warning(&w);
        warnings.push(w);
    }
    Ok(())
}

/// The warning of a step a stop abandoned (`what` not done), to `log` and `warnings`.
pub(super) fn abandoned(
    what: &str,
    log: &mut dyn JobLog,
    warnings: &mut aeroident_io::warning::Warnings,
) {
    let w = format!("the run was interrupted: {what} not done");
    log.warning(&w);
    warnings.push(w);
}

fn run_online(records: &Records, kind: EstimatorKind, base: &ReplayOptions) -> MethodEstimates {
    let opts = ReplayOptions {
        estimator: kind,
        estimator_options: crate::estimators::EstimatorOptions::default(),
        ..base.clone()
    };
    online_estimates(records, &opts)
}

/// The record replayed with `opts` (its estimator and options as given), as the panel reads
/// it: failed when the replay fails, diverges or ends `initialising`. Only the estimates are
/// formed ([`ReplayOptions::estimates_only`]): the panel and the refits read nothing else.
pub(super) fn online_estimates(records: &Records, opts: &ReplayOptions) -> MethodEstimates {
    let name = opts.estimator.name();
    match online_replay(records, opts) {
        Ok(o) => {
            let rows = o.summary.parameters.iter().filter_map(|p| ParameterEstimate::of(p));
            MethodEstimates::new(name, &o.summary.status, rows)
        }
        Err(why) => MethodEstimates::failed(name, &why),
    }
}

/// The record replayed with `opts`, estimates only ([`online_estimates`]); why not, when the
/// replay fails, diverges or ends `initialising`.
pub(super) fn online_replay(
    records: &Records,
    opts: &ReplayOptions,
) -> Result<crate::replay::ReplayOutcome, String> {
    let opts = &ReplayOptions { estimates_only: true, ..opts.clone() };
    let replayed = match records.held_with(opts.spike_screen) {
        Some(held) => crate::replay::replay_cached(held, &records.mapping, opts, &mut ()),
        None => match records.open(&records.data) {
            Ok(r) => crate::replay::replay(r, &records.mapping, opts, &mut ()),
            Err(e) => return Err(e.to_string()),
        },
    };
    match replayed {
        Ok(o) if o.diverged() => Err("diverged".into()),
        Ok(o) if crate::verdict::unconverged(&o.summary.status).is_some() => {
            Err("ended initialising (not every parameter left its prior)".into())
        }
        Ok(o) => Ok(o),
        Err(e) => Err(e.to_string()),
    }
}

fn run_batch(records: &Records, kind: EstimatorKind, base: &ReplayOptions) -> MethodEstimates {
    let method = match kind {
        EstimatorKind::Fem => BatchMethod::Fem,
        EstimatorKind::Fdoe => BatchMethod::Fdoe {
            band_hz: aeroident_estimators::output_error::frequency::DEFAULT_BAND_HZ,
        },
        _ => BatchMethod::Oe,
    };
    let options = FitOptions {
        method,
        compat: base.compat.clone(),
        windows: base.windows.clone(),
        spike_screen: base.spike_screen,
        ..FitOptions::default()
    };
    batch_estimates(records, kind, base.model.clone(), options)
}

/// Every record fitted by `kind` with `model` and `options`, as the panel reads it: failed
/// when the fit fails, ends at its iteration limit still moving or its filter degenerates.
/// Only the estimates are formed ([`FitOptions::estimates_only`]): the panel and the refits
/// read nothing else.
pub(super) fn batch_estimates(
    records: &Records,
    kind: EstimatorKind,
    model: Option<aeroident_io::ModelSpec>,
    options: FitOptions,
) -> MethodEstimates {
    let options = FitOptions { estimates_only: true, ..options };
    let name = kind.name();
    let mapping = &records.mapping;
    let fitted = match records.held_with(options.spike_screen) {
        Some(held) => crate::replay::fit::fit_cached(held, mapping, model, options),
        None => match records.open_all() {
            Ok(readers) => crate::replay::fit::fit_records(readers, mapping, model, options),
            Err(e) => return MethodEstimates::failed(name, &e.to_string()),
        },
    };
    let fit = match fitted {
        Ok(fit) => fit,
        Err(e) => return MethodEstimates::failed(name, &e.to_string()),
    };
    let s = &fit.summary;
    if s.parameters.iter().any(|p| p.status == STATUS_NOT_CONVERGED) {
        return MethodEstimates::failed(
            name,
            "not converged (its last iterations still move the estimates)",
        );
    }
    if s.collapsed_noise().is_some() {
        return MethodEstimates::failed(
            name,
            "degenerate filter (a measurement-noise variance collapsed)",
        );
    }
    let rows = s.parameters.iter().filter_map(|p| ParameterEstimate::of(p));
    MethodEstimates::new(name, &s.status, rows)
}

/// The run's own estimates as the panel reads them: those of `rows` with an estimate and a σ.
pub fn own_estimates<'a>(
    kind: EstimatorKind,
    status: &str,
    rows: impl Iterator<Item = &'a aeroident_io::parameter::ParameterResult>,
) -> MethodEstimates {
    let rows = rows.filter_map(ParameterEstimate::of);
    MethodEstimates::new(kind.name(), status, rows)
}

/// The check step on a run whose own estimates are `own`: `panel` ([`run_panel`], options
/// `base`) under `guard`, judged ([`crate::replay::cross_check::judge`]), its warnings to `log`
/// and `warnings`. `None` when a stop abandoned it (a warning says so).
///
/// # Errors
/// The face could not run the step.
pub fn check(
    records: &Records,
    own: &MethodEstimates,
    base: ReplayOptions,
    panel: Panel,
    guard: &mut impl Guard,
    log: &mut dyn JobLog,
    warnings: &mut aeroident_io::warning::Warnings,
) -> Result<Option<CrossCheck>, ReplayError> {
    log.note("cross-check: running the record's other methods with the same model");
    let long = long_record_windows(records, &base).map(|(windows, w)| {
        log.warning(&w);
        warnings.push(w);
        windows
    });
    let records = records.clone();
    let step = move || run_panel(&records, base.estimator, &base, panel, long.as_deref());
    let Some(others) = guard.run(Step::CrossCheck, step)? else {
        abandoned("--cross-check", log, warnings);
        return Ok(None);
    };
    let check = crate::replay::cross_check::judge(own, &others);
    for w in crate::replay::cross_check::warnings(&check) {
        log.warning(&w);
        warnings.push(w);
    }
    Ok(Some(check))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The faces' two flags: `--cross-check` wins (clap refuses both together), neither is
    /// the default panel; the default panel holds every method but `fem`, off holds none.
    #[test]
    fn the_flags_choose_the_panel_and_the_default_leaves_out_fem() {
        assert_eq!(Panel::from_flags(false, false), Panel::default());
        assert_eq!(Panel::from_flags(true, false), Panel::Full);
        assert_eq!(Panel::from_flags(false, true), Panel::Off);
        let all = ONLINE_METHODS.iter().chain(&BATCH_METHODS);
        let fast: Vec<&str> =
            all.clone().filter(|k| Panel::Fast.holds(**k)).map(|k| k.name()).collect();
        assert_eq!(fast, ["rls", "rls-iv", "ekf", "oe", "fdoe"]);
        assert_eq!(all.clone().filter(|k| Panel::Full.holds(**k)).count(), 6);
        assert!(!Panel::Off.runs() && all.clone().all(|k| !Panel::Off.holds(*k)));
    }
}
