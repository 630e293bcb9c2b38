//! The estimator handle and its extern functions: create from a model's text and options,
//! update with one sample, read estimates, σ and state into caller buffers, reset, free.
//!
//! Every function checks its pointers, catches any panic at the boundary (a handle it happened
//! in is marked unusable) and returns an [`AeroidentResult`]; nothing unwinds into C.

use crate::error::{AeroidentResult, clear, fail};
use crate::sample::AeroidentSample;
use aeroident_estimators::{Estimator, EventKind, ModelStructure, Priors, Status};
use aeroident_io::ModelSpec;
use aeroident_registry::Named;
use aeroident_registry::estimators::{EstimatorKind, EstimatorOptions, build, parse_options};
use core::ffi::{CStr, c_char};
use std::ffi::CString;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// An estimator over one model (opaque to C). Made by [`aeroident_estimator_new`], released by
/// [`aeroident_estimator_free`]. Not synchronised: use a handle from one thread at a time (it
/// may move between threads).
pub struct AeroidentEstimator {
    pub(crate) est: Box<dyn Estimator + Send>,
    kind: EstimatorKind,
    structure: ModelStructure,
    priors: Priors,
    options: EstimatorOptions,
    method: CString,
    pub(crate) names: Vec<CString>,
    /// The model, for the verdict's plausibility check.
    pub(crate) spec: ModelSpec,
    /// Whether an accepted sample carried thrust (the drag terms are withdrawn without it).
    pub(crate) thrust_seen: bool,
    /// Each parameter's flags from the last verdicts, one per line
    /// ([`crate::verdict::aeroident_estimator_verdicts`]).
    pub(crate) flags: Vec<CString>,
    accepted: u64,
    refused: u64,
    /// A panic happened inside a call on this handle: its state may be half-updated.
    poisoned: bool,
}

/// The estimator's state of [`AeroidentState::status`].
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AeroidentStatus {
    /// Not every parameter is identified yet.
    Initialising = 0,
    /// Running; the identified parameters are usable.
    Running = 1,
    /// Diverged: its numbers are not a result (reset it).
    Diverged = 2,
}

/// The state of an estimator besides its estimates ([`aeroident_estimator_state`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AeroidentState {
    /// Time of the last sample used, s (0 before any).
    pub t_s: f64,
    /// Initialising, running or diverged.
    pub status: AeroidentStatus,
    /// Number of parameters (the model's, in its order).
    pub n_params: usize,
    /// How many of them are identified.
    pub n_identified: usize,
    /// Samples accepted since creation or the last reset.
    pub samples_accepted: u64,
    /// Samples refused since creation or the last reset.
    pub samples_refused: u64,
    /// Restarts from the priors after a divergence rule fired (the estimates then come from
    /// the samples after it only).
    pub restarts: u32,
    /// Re-anchored runs of innovation-gate rejections (Kalman filters).
    pub reanchors: u32,
    /// Detected parameter changes.
    pub changes_detected: u32,
    /// Whether `nis` is given (methods with innovations: the Kalman filters).
    pub has_nis: bool,
    /// Mean normalised innovation squared `e²/S` (1 for a consistent filter); NaN without
    /// `has_nis`.
    pub nis: f64,
}

/// Runs `f` with this thread's message cleared, catching a panic as [`AeroidentResult::Panic`].
fn guarded(f: impl FnOnce() -> AeroidentResult) -> AeroidentResult {
    clear();
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|payload| panicked(payload.as_ref()))
}

/// The result of a caught panic, its message kept.
fn panicked(payload: &(dyn std::any::Any + Send)) -> AeroidentResult {
    let what = payload
        .downcast_ref::<&str>()
        .copied()
        .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
        .unwrap_or("(no message)");
    fail(AeroidentResult::Panic, format_args!("internal error (a bug in aeroident): {what}"))
}

/// Runs `f` on the handle behind `e` (checked non-NULL and not poisoned); a panic inside
/// poisons it.
///
/// # Safety
/// `e` is NULL or a live handle of [`aeroident_estimator_new`] used by no other thread.
pub(crate) unsafe fn with_handle(
    e: *mut AeroidentEstimator,
    f: impl FnOnce(&mut AeroidentEstimator) -> AeroidentResult,
) -> AeroidentResult {
    clear();
    if e.is_null() {
        return fail(AeroidentResult::NullPointer, format_args!("estimator is NULL"));
    }
    // SAFETY: non-NULL, and by the contract a live handle used by this thread only.
    let h = unsafe { &mut *e };
    if h.poisoned {
        return poisoned();
    }
    match catch_unwind(AssertUnwindSafe(|| f(h))) {
        Ok(r) => r,
        Err(payload) => {
            // SAFETY: as above; the closure's borrow ended with the unwind.
            unsafe { (*e).poisoned = true };
            panicked(payload.as_ref())
        }
    }
}

/// [`with_handle`] for the functions that only read.
///
/// # Safety
/// As [`with_handle`].
pub(crate) unsafe fn with_handle_ref(
    e: *const AeroidentEstimator,
    f: impl FnOnce(&AeroidentEstimator) -> AeroidentResult,
) -> AeroidentResult {
    clear();
    if e.is_null() {
        return fail(AeroidentResult::NullPointer, format_args!("estimator is NULL"));
    }
    // SAFETY: non-NULL, and by the contract a live handle not written concurrently.
    let h = unsafe { &*e };
    if h.poisoned {
        return poisoned();
    }
    catch_unwind(AssertUnwindSafe(|| f(h))).unwrap_or_else(|payload| panicked(payload.as_ref()))
}

fn poisoned() -> AeroidentResult {
    fail(
        AeroidentResult::Panic,
        format_args!("this estimator failed inside the library earlier (a bug); reset or free it"),
    )
}

/// The UTF-8 text of C string `p` (`what` names it in errors); `None` for NULL.
///
/// # Safety
/// `p` is NULL or a NUL-terminated string.
unsafe fn text<'a>(p: *const c_char, what: &str) -> Result<Option<&'a str>, AeroidentResult> {
    if p.is_null() {
        return Ok(None);
    }
    // SAFETY: non-NULL and NUL-terminated by the contract.
    let c = unsafe { CStr::from_ptr(p) };
    c.to_str().map(Some).map_err(|e| {
        fail(AeroidentResult::InvalidArgument, format_args!("{what} is not UTF-8: {e}"))
    })
}

/// The model of `text`: a preset name (`longitudinal`, `lateral`, `six-axis`), else a model
/// file's TOML.
fn model(text: &str) -> Result<ModelSpec, AeroidentResult> {
    if let Some(spec) = ModelSpec::preset(text.trim()) {
        return Ok(spec);
    }
    ModelSpec::from_toml_str(text, "model").map_err(|e| {
        fail(
            AeroidentResult::Model,
            format_args!(
                "{e} (give a preset name: longitudinal, lateral, six-axis, or a model file's text)"
            ),
        )
    })
}

/// The options of `kind` from the options text (`key = value` lines, TOML).
fn options(kind: EstimatorKind, text: &str) -> Result<EstimatorOptions, AeroidentResult> {
    let table: toml::Table = text.parse().map_err(|e| {
        fail(AeroidentResult::Option, format_args!("options: not `key = value` TOML: {e}"))
    })?;
    parse_options(kind, table.iter().map(|(k, v)| (k.as_str(), v.clone())))
        .map_err(|e| fail(AeroidentResult::Option, format_args!("options: {e}")))
}

/// The handle of `kind` over `spec` with `options`.
fn create(
    kind: EstimatorKind,
    spec: &ModelSpec,
    options: EstimatorOptions,
) -> Result<AeroidentEstimator, AeroidentResult> {
    let est = build(kind, spec.structure, spec.priors, &options)
        .map_err(|e| fail(AeroidentResult::Build, format_args!("{e}")))?;
    let c = |s: &str| CString::new(s).expect("names have no NUL");
    Ok(AeroidentEstimator {
        names: spec.structure.names().map(c).collect(),
        method: c(kind.name()),
        est,
        kind,
        structure: spec.structure,
        priors: spec.priors,
        options,
        spec: spec.clone(),
        thrust_seen: false,
        flags: Vec::new(),
        accepted: 0,
        refused: 0,
        poisoned: false,
    })
}

/// Creates an estimator.
///
/// - `kind`: the method, as `aeroident replay --estimator` names it: `rls`, `rls-iv`, `ftr`,
///   `ekf`, `smpe`, `smpe-corrected`, `smpe-finite-time`, `gradient` (the batch methods `oe`,
///   `fem`, `fdoe` have no per-sample update and are refused).
/// - `model`: a model file's text (TOML, docs/structure.md: `[coefficients]`, `[prior.X]` …)
///   or a preset name (`longitudinal`, `lateral`, `six-axis`).
/// - `options`: the method's options as TOML `key = value` lines, the keys of a scenario's
///   `[[estimator]]` entry (`forgetting = 0.99`, `grid_hz = [0.1, 2.0, 0.04]`,
///   `parameter_walk_per_sqrt_s = 0.01`, `instrument_delay = 5` …); NULL or `""` for the
///   defaults. An option the kind does not take is refused, naming those it takes.
/// - `out`: receives the handle on success, NULL on failure.
///
/// The estimator is built exactly as `aeroident replay` builds it (the same registry), so the
/// same samples give the same estimates. Allocates the estimator (fixed capacity over the whole
/// vocabulary: an RLS is about 0.2 MB); [`aeroident_estimator_update`] then never allocates.
///
/// # Safety
/// `kind` and `model` are NUL-terminated strings; `options` is one or NULL; `out` points to
/// writable storage for a pointer.
///
/// # Errors
/// `NULL_POINTER`, `INVALID_ARGUMENT` (not UTF-8, unknown kind), `MODEL`, `OPTION`, `BUILD`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aeroident_estimator_new(
    kind: *const c_char,
    model: *const c_char,
    options: *const c_char,
    out: *mut *mut AeroidentEstimator,
) -> AeroidentResult {
    guarded(|| {
        if out.is_null() {
            return fail(AeroidentResult::NullPointer, format_args!("out is NULL"));
        }
        // SAFETY: non-NULL, writable by the contract.
        unsafe { *out = core::ptr::null_mut() };
        // SAFETY: the strings' contract is the caller's.
        let made = unsafe { new_handle(kind, model, options) };
        match made {
            Ok(h) => {
                // SAFETY: as above.
                unsafe { *out = Box::into_raw(Box::new(h)) };
                AeroidentResult::Ok
            }
            Err(code) => code,
        }
    })
}

/// [`aeroident_estimator_new`]'s work, its errors already reported.
///
/// # Safety
/// As [`aeroident_estimator_new`].
unsafe fn new_handle(
    kind: *const c_char,
    model_text: *const c_char,
    options_text: *const c_char,
) -> Result<AeroidentEstimator, AeroidentResult> {
    // SAFETY: the caller's contract.
    let (kind, model_text, options_text) = unsafe {
        (text(kind, "kind")?, text(model_text, "model")?, text(options_text, "options")?)
    };
    let kind =
        kind.ok_or_else(|| fail(AeroidentResult::NullPointer, format_args!("kind is NULL")))?;
    let model_text = model_text
        .ok_or_else(|| fail(AeroidentResult::NullPointer, format_args!("model is NULL")))?;
    let kind = EstimatorKind::from_name(kind).ok_or_else(|| {
        fail(
            AeroidentResult::InvalidArgument,
            format_args!(
                "unknown estimator kind `{kind}` ({})",
                aeroident_registry::estimators::online_kinds().join(" | ")
            ),
        )
    })?;
    let spec = model(model_text)?;
    let options = options(kind, options_text.unwrap_or(""))?;
    create(kind, &spec, options)
}

/// Releases an estimator (NULL is ignored). The handle must not be used afterwards.
///
/// # Safety
/// `e` is NULL or a handle of [`aeroident_estimator_new`] not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aeroident_estimator_free(e: *mut AeroidentEstimator) {
    guarded(|| {
        if !e.is_null() {
            // SAFETY: a handle of `aeroident_estimator_new` (Box::into_raw), freed once.
            drop(unsafe { Box::from_raw(e) });
        }
        AeroidentResult::Ok
    });
}

/// Feeds one sample. Never allocates (on success or refusal) and never blocks.
///
/// `AEROIDENT_RESULT_SAMPLE_REFUSED`: the sample was not used (a channel the model needs is
/// absent, a value not finite or implausible, time not increasing); the state is unchanged and
/// the next sample may be fed. `AEROIDENT_RESULT_DIVERGED`: the estimator diverged; its numbers
/// are no longer a result until [`aeroident_estimator_reset`].
///
/// # Safety
/// `e` is a live handle; `sample` points to an initialised [`AeroidentSample`].
///
/// # Errors
/// `NULL_POINTER`, `INVALID_ARGUMENT` (undefined presence bits), `SAMPLE_REFUSED`, `DIVERGED`,
/// `PANIC`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aeroident_estimator_update(
    e: *mut AeroidentEstimator,
    sample: *const AeroidentSample,
) -> AeroidentResult {
    // SAFETY: the handle's contract is the caller's.
    unsafe {
        with_handle(e, |h| {
            if sample.is_null() {
                return fail(AeroidentResult::NullPointer, format_args!("sample is NULL"));
            }
            // SAFETY: non-NULL and initialised by the contract.
            let s = match (*sample).to_air_data() {
                Ok(s) => s,
                Err(bits) => {
                    return fail(
                        AeroidentResult::InvalidArgument,
                        format_args!("sample.present has undefined bits {bits:#x}"),
                    );
                }
            };
            h.update(&s)
        })
    }
}

impl AeroidentEstimator {
    fn update(&mut self, s: &aeroident_estimators::AirDataSample) -> AeroidentResult {
        let result = self.est.update(s).map(|_| ());
        if self.est.estimates().status == Status::Diverged {
            self.refused += u64::from(result.is_err());
            return match result {
                Err(err) => fail(
                    AeroidentResult::Diverged,
                    format_args!(
                        "estimator `{}` diverged at t = {} s ({err})",
                        self.kind.name(),
                        s.t_s
                    ),
                ),
                Ok(()) => fail(
                    AeroidentResult::Diverged,
                    format_args!("estimator `{}` diverged at t = {} s", self.kind.name(), s.t_s),
                ),
            };
        }
        match result {
            Ok(()) => {
                self.accepted += 1;
                self.thrust_seen |= s.thrust_n.is_some();
                AeroidentResult::Ok
            }
            Err(err) => {
                self.refused += 1;
                fail(
                    AeroidentResult::SampleRefused,
                    format_args!(
                        "estimator `{}` refused the sample at t = {} s: {err}",
                        self.kind.name(),
                        s.t_s
                    ),
                )
            }
        }
    }
}

/// Writes the current estimates, in the model's parameter order
/// ([`aeroident_estimator_param_name`]), into the caller's buffers of `len` elements each:
/// `value[i]` the estimate, NaN while parameter `i` is not identified (never a placeholder 0);
/// `sigma[i]` its standard error, NaN where not identified or the method gives none (the
/// sliding-mode estimators); `identified[i]` whether it is identified. Any of the three may be
/// NULL (not written). `len` must be at least [`aeroident_estimator_n_params`].
///
/// # Safety
/// `e` is a live handle; each non-NULL buffer has room for `len` elements.
///
/// # Errors
/// `NULL_POINTER`, `BUFFER_TOO_SMALL`, `PANIC`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aeroident_estimator_estimates(
    e: *const AeroidentEstimator,
    value: *mut f64,
    sigma: *mut f64,
    identified: *mut bool,
    len: usize,
) -> AeroidentResult {
    // SAFETY: the handle's contract is the caller's.
    unsafe {
        with_handle_ref(e, |h| {
            let est = h.est.estimates();
            let n = h.structure.n_params();
            if len < n {
                return fail(
                    AeroidentResult::BufferTooSmall,
                    format_args!("the buffers hold {len} elements; the model has {n} parameters"),
                );
            }
            for i in 0..n {
                // SAFETY: each non-NULL buffer has `len` ≥ n elements by the contract.
                if !value.is_null() {
                    *value.add(i) = est.value(i).unwrap_or(f64::NAN);
                }
                if !sigma.is_null() {
                    *sigma.add(i) = est.sigma(i).unwrap_or(f64::NAN);
                }
                if !identified.is_null() {
                    *identified.add(i) = est.is_identified(i);
                }
            }
            AeroidentResult::Ok
        })
    }
}

/// Writes the estimator's state (status, time, counts, events, NIS) into `*out`.
///
/// # Safety
/// `e` is a live handle; `out` points to writable storage for an [`AeroidentState`].
///
/// # Errors
/// `NULL_POINTER`, `PANIC`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aeroident_estimator_state(
    e: *const AeroidentEstimator,
    out: *mut AeroidentState,
) -> AeroidentResult {
    // SAFETY: the handle's contract is the caller's.
    unsafe {
        with_handle_ref(e, |h| {
            if out.is_null() {
                return fail(AeroidentResult::NullPointer, format_args!("out is NULL"));
            }
            let est = h.est.estimates();
            let n = h.structure.n_params();
            let events = h.est.events();
            let nis = h.est.nis();
            // SAFETY: non-NULL and writable by the contract.
            *out = AeroidentState {
                t_s: est.t_s,
                status: match est.status {
                    Status::Initialising => AeroidentStatus::Initialising,
                    Status::Running => AeroidentStatus::Running,
                    Status::Diverged => AeroidentStatus::Diverged,
                },
                n_params: n,
                n_identified: (0..n).filter(|&i| est.is_identified(i)).count(),
                samples_accepted: h.accepted,
                samples_refused: h.refused,
                restarts: events.count(EventKind::Restart),
                reanchors: events.count(EventKind::Reanchor),
                changes_detected: events.count(EventKind::ChangeDetected),
                has_nis: nis.is_some(),
                nis: nis.unwrap_or(f64::NAN),
            };
            AeroidentResult::Ok
        })
    }
}

/// The number of parameters of the estimator's model (the length its buffers need); 0 for a
/// NULL or unusable handle (a model has at least one parameter).
///
/// # Safety
/// `e` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aeroident_estimator_n_params(e: *const AeroidentEstimator) -> usize {
    let mut n = 0;
    // SAFETY: the handle's contract is the caller's.
    unsafe {
        with_handle_ref(e, |h| {
            n = h.structure.n_params();
            AeroidentResult::Ok
        })
    };
    n
}

/// The name of parameter `i` (`Cm_alpha`, `CL_0` …: `<coefficient>_<term>`, as in
/// `estimates.csv`); NULL when `i` is out of range or `e` is NULL. The text lives as long as
/// the handle.
///
/// # Safety
/// `e` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aeroident_estimator_param_name(
    e: *const AeroidentEstimator,
    i: usize,
) -> *const c_char {
    let mut name = core::ptr::null();
    // SAFETY: the handle's contract is the caller's.
    let r = unsafe {
        with_handle_ref(e, |h| match h.names.get(i) {
            Some(c) => {
                name = c.as_ptr();
                AeroidentResult::Ok
            }
            None => fail(
                AeroidentResult::InvalidArgument,
                format_args!("parameter {i} of {}: out of range", h.names.len()),
            ),
        })
    };
    if r == AeroidentResult::Ok { name } else { core::ptr::null() }
}

/// The estimator's method name (`rls`, `ekf` …); NULL for a NULL handle. The text lives as
/// long as the handle.
///
/// # Safety
/// `e` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aeroident_estimator_method(e: *const AeroidentEstimator) -> *const c_char {
    let mut name = core::ptr::null();
    // SAFETY: the handle's contract is the caller's.
    unsafe {
        with_handle_ref(e, |h| {
            name = h.method.as_ptr();
            AeroidentResult::Ok
        })
    };
    name
}

/// Starts the estimator afresh: the state it had right after [`aeroident_estimator_new`], with
/// the same kind, model and options (and the sample counts zero). Allocates, as creation does
/// (the estimator is rebuilt); also recovers a handle a caught internal error made unusable.
///
/// # Safety
/// `e` is a live handle.
///
/// # Errors
/// `NULL_POINTER`, `PANIC`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aeroident_estimator_reset(e: *mut AeroidentEstimator) -> AeroidentResult {
    if !e.is_null() {
        // SAFETY: a live handle by the contract; the rebuild below replaces all its state.
        unsafe { (*e).poisoned = false };
    }
    // SAFETY: the handle's contract is the caller's.
    unsafe {
        with_handle(e, |h| {
            match build(h.kind, h.structure, h.priors, &h.options) {
                Ok(est) => h.est = est,
                Err(err) => return fail(AeroidentResult::Build, format_args!("{err}")),
            }
            h.accepted = 0;
            h.refused = 0;
            h.thrust_seen = false;
            h.flags.clear();
            AeroidentResult::Ok
        })
    }
}

/// A new manoeuvre starts with the next sample (a gap in the data, a second run): the
/// estimators with a model state (the EKF, the sliding-mode and gradient estimators)
/// re-initialise it from the next sample and keep the parameters, as `aeroident replay` does at
/// a gap; the others are unaffected. Never allocates.
///
/// # Safety
/// `e` is a live handle.
///
/// # Errors
/// `NULL_POINTER`, `PANIC`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aeroident_estimator_new_manoeuvre(
    e: *mut AeroidentEstimator,
) -> AeroidentResult {
    // SAFETY: the handle's contract is the caller's.
    unsafe {
        with_handle(e, |h| {
            h.est.new_manoeuvre();
            AeroidentResult::Ok
        })
    }
}

/// The library's version (`0.1.0`), NUL-terminated, static.
#[unsafe(no_mangle)]
pub extern "C" fn aeroident_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message() -> String {
        // SAFETY: never NULL, NUL-terminated.
        let m = unsafe { CStr::from_ptr(crate::error::aeroident_last_error_message()) };
        m.to_str().unwrap().to_string()
    }

    /// A panic inside a call comes back as `PANIC` with its message instead of unwinding; the
    /// handle it happened in refuses further use until it is reset, which makes it usable again.
    #[test]
    fn a_panic_inside_a_call_is_a_code_and_poisons_the_handle() {
        assert_eq!(guarded(|| panic!("boom {}", 1)), AeroidentResult::Panic);
        assert!(message().contains("internal error (a bug in aeroident): boom 1"), "{}", message());
        let spec = ModelSpec::preset("longitudinal").unwrap();
        let h = create(EstimatorKind::Rls, &spec, EstimatorOptions::default()).unwrap();
        let e = Box::into_raw(Box::new(h));
        // SAFETY: a live handle, used by this thread only, freed once at the end.
        unsafe {
            let r = with_handle(e, |_| panic!("inside the estimator"));
            assert_eq!(r, AeroidentResult::Panic);
            assert!(message().contains("inside the estimator"), "{}", message());
            let s = AeroidentSample::default();
            assert_eq!(aeroident_estimator_update(e, &s), AeroidentResult::Panic);
            assert!(message().contains("reset or free it"), "{}", message());
            assert_eq!(aeroident_estimator_n_params(e), 0);
            assert_eq!(aeroident_estimator_reset(e), AeroidentResult::Ok);
            assert_eq!(aeroident_estimator_n_params(e), 12);
            assert_eq!(aeroident_estimator_update(e, &s), AeroidentResult::SampleRefused);
            aeroident_estimator_free(e);
        }
    }
}
