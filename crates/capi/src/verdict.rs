//! The verdict on each current estimate, by the one judge every command uses
//! (`aeroident_registry::verdict::judge_estimate`): the status a C caller reports beside the
//! numbers, and the flags that explain it.
//!
//! A C caller feeds samples the library does not read the record for, so the verdict weighs
//! what the estimates themselves carry: the estimator's state, the plausibility of each value
//! for the model, and whether ±2σ (with the unmodelled share, docs/output-schema.md) keeps it
//! from zero. The record-level tests of `aeroident replay` (sign tests, sample timing, the
//! cross-check) need the record, and are not made here.

use crate::error::{AeroidentResult, fail};
use crate::estimator::{AeroidentEstimator, with_handle, with_handle_ref};
use aeroident_io::parameter::{STATUS_DIVERGED, STATUS_FLAGGED, STATUS_IDENTIFIED};
use aeroident_registry::verdict::judge_estimate;
use core::ffi::c_char;
use std::ffi::CString;

/// The verdict on one parameter ([`aeroident_estimator_verdicts`]), as `summary.json`'s
/// `status` names it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AeroidentVerdict {
    /// No doubt found: the estimate is a result.
    Identified = 0,
    /// A doubt was found ([`aeroident_estimator_flags`] says which).
    Flagged = 1,
    /// No estimate yet.
    NotIdentified = 2,
    /// The estimator diverged: no estimate is a result.
    Diverged = 3,
}

impl AeroidentVerdict {
    fn of(status: &str) -> Self {
        match status {
            STATUS_IDENTIFIED => Self::Identified,
            STATUS_FLAGGED => Self::Flagged,
            STATUS_DIVERGED => Self::Diverged,
            _ => Self::NotIdentified,
        }
    }
}

/// Judges every current estimate by the judge of every `aeroident` command (the estimator's
/// state; the plausibility of the value for the model, drag terms withdrawn until a sample
/// carried thrust; whether ±2σ, 5.5 % of |estimate| added in quadrature, keeps it from zero;
/// the record-level tests of `aeroident replay` need the record and are not made) and writes
/// the verdicts, in the model's parameter order, into the caller's buffer of `len` elements;
/// each parameter's flags are kept for [`aeroident_estimator_flags`] until the next call.
/// Allocates (the flags' text): a call for the report at the end or at a low rate, not in the
/// update loop.
///
/// # Safety
/// `e` is a live handle; `out` has room for `len` elements.
///
/// # Errors
/// `NULL_POINTER`, `BUFFER_TOO_SMALL`, `PANIC`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aeroident_estimator_verdicts(
    e: *mut AeroidentEstimator,
    out: *mut AeroidentVerdict,
    len: usize,
) -> AeroidentResult {
    // SAFETY: the handle's contract is the caller's.
    unsafe {
        with_handle(e, |h| {
            if out.is_null() {
                return fail(AeroidentResult::NullPointer, format_args!("out is NULL"));
            }
            let n = h.names.len();
            if len < n {
                return fail(
                    AeroidentResult::BufferTooSmall,
                    format_args!("the buffer holds {len} elements; the model has {n} parameters"),
                );
            }
            let est = h.est.estimates();
            let status = est.status.name();
            h.flags.clear();
            for (i, name) in h.names.iter().enumerate() {
                let name = name.to_str().unwrap_or_default();
                let (value, sigma) = (est.value(i), est.sigma(i));
                let r = judge_estimate(name, value, sigma, status, &h.spec, h.thrust_seen);
                // SAFETY: `out` has `len` ≥ n elements by the contract.
                *out.add(i) = AeroidentVerdict::of(&r.status);
                let text = r.flags.join("\n").replace('\0', " ");
                h.flags.push(CString::new(text).unwrap_or_default());
            }
            AeroidentResult::Ok
        })
    }
}

/// The flags of parameter `i` from the last [`aeroident_estimator_verdicts`], one per line
/// (`""` when it has none); NULL before any verdicts, when `i` is out of range or `e` is NULL.
/// The text lives until the next verdicts call, reset or free.
///
/// # Safety
/// `e` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn aeroident_estimator_flags(
    e: *const AeroidentEstimator,
    i: usize,
) -> *const c_char {
    let mut text = core::ptr::null();
    // SAFETY: the handle's contract is the caller's.
    unsafe {
        with_handle_ref(e, |h| match h.flags.get(i) {
            Some(c) => {
                text = c.as_ptr();
                AeroidentResult::Ok
            }
            None => fail(
                AeroidentResult::InvalidArgument,
                format_args!("no flags of parameter {i} (judged: {})", h.flags.len()),
            ),
        })
    };
    text
}
