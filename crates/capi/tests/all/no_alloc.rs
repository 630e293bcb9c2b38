//! No heap allocation in `aeroident_estimator_update` after creation: a counting global
//! allocator counts every allocation, reallocation and release made on this test's thread
//! while RLS, FTR (also with `spread_sigma = true`) and the EKF over the six-axis preset each
//! take 2,000 samples through the C
//! ABI, with their estimates and state read after every sample, one refused sample and a new
//! manoeuvre among them. Creation is outside the counted span (it allocates the estimator).

#[path = "../../../estimators/src/test_aircraft.rs"]
mod test_aircraft;

use aeroident_capi::sample::{AEROIDENT_HAS_ALL, AeroidentSample};
use aeroident_capi::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ffi::CString;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The system allocator, counting the calls made on a thread while its `COUNTING` flag is set
/// (the test harness's other threads allocate as they like).
struct Counting;

static CALLS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
}

fn note() {
    if COUNTING.try_with(Cell::get).unwrap_or(false) {
        CALLS.fetch_add(1, Ordering::Relaxed);
    }
}

// SAFETY: every call is passed to the system allocator unchanged.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note();
        // SAFETY: the caller's layout, as `GlobalAlloc::alloc` requires.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note();
        // SAFETY: as `alloc`.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        // SAFETY: a block of this allocator with its layout, as `GlobalAlloc::realloc` requires.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        note();
        // SAFETY: a block of this allocator with its layout.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Feeds `samples` to a new `kind` with `options` (TOML) over the six-axis preset with
/// counting on: the calls to the allocator, and how many updates were accepted.
fn counted(kind: &str, options: &str, samples: &[AeroidentSample]) -> (usize, usize) {
    let (k, m) = (CString::new(kind).unwrap(), CString::new("six-axis").unwrap());
    let o = CString::new(options).unwrap();
    let mut e = std::ptr::null_mut();
    // SAFETY: valid strings and out pointer.
    let r = unsafe { aeroident_estimator_new(k.as_ptr(), m.as_ptr(), o.as_ptr(), &mut e) };
    assert_eq!(r, AeroidentResult::Ok);
    // SAFETY: a live handle.
    let n = unsafe { aeroident_estimator_n_params(e) };
    let (mut value, mut sigma, mut identified) = (vec![0.0; n], vec![0.0; n], vec![false; n]);
    // SAFETY: zeroes are a valid `AeroidentState` (a 0 status is `Initialising`).
    let mut state: AeroidentState = unsafe { std::mem::zeroed() };
    let refused = AeroidentSample { alpha_rad: f64::NAN, ..samples[0] };
    let mut accepted = 0;
    CALLS.store(0, Ordering::Relaxed);
    COUNTING.with(|c| c.set(true));
    for (i, s) in samples.iter().enumerate() {
        // SAFETY: a live handle; buffers of n elements; the samples are initialised.
        unsafe {
            if i == samples.len() / 2 {
                aeroident_estimator_update(e, &refused);
                aeroident_estimator_new_manoeuvre(e);
            }
            accepted += usize::from(aeroident_estimator_update(e, s) == AeroidentResult::Ok);
            aeroident_estimator_estimates(
                e,
                value.as_mut_ptr(),
                sigma.as_mut_ptr(),
                identified.as_mut_ptr(),
                n,
            );
            aeroident_estimator_state(e, &mut state);
        }
    }
    COUNTING.with(|c| c.set(false));
    let calls = CALLS.load(Ordering::Relaxed);
    // SAFETY: a live handle, freed once.
    unsafe { aeroident_estimator_free(e) };
    assert_eq!(state.samples_refused, 1, "{kind}: the refused sample");
    (calls, accepted)
}

#[test]
fn updates_allocate_nothing_after_creation() {
    let samples: Vec<AeroidentSample> = test_aircraft::six_axis_stream(2000, 0.02, 20.0)
        .iter()
        .map(AeroidentSample::from_air_data)
        .collect();
    assert_eq!(samples[0].present & AEROIDENT_HAS_ALL, samples[0].present);
    // FTR's spread σ keeps a solve's inputs in place between updates (no copy, no buffer).
    for (kind, options) in [("rls", ""), ("ftr", ""), ("ftr", "spread_sigma = true"), ("ekf", "")] {
        let (calls, accepted) = counted(kind, options, &samples);
        assert_eq!(accepted, samples.len(), "{kind}: every sample is used");
        assert_eq!(calls, 0, "{kind}: {calls} allocator calls in {} updates", samples.len());
    }
    // The counter counts: creating an estimator while counting allocates.
    COUNTING.with(|c| c.set(true));
    let before = CALLS.load(Ordering::Relaxed);
    let (k, m) = (CString::new("rls").unwrap(), CString::new("six-axis").unwrap());
    let mut e = std::ptr::null_mut();
    // SAFETY: valid strings and out pointer; the handle is freed once.
    unsafe {
        aeroident_estimator_new(k.as_ptr(), m.as_ptr(), std::ptr::null(), &mut e);
        aeroident_estimator_free(e);
    }
    COUNTING.with(|c| c.set(false));
    assert!(CALLS.load(Ordering::Relaxed) > before, "creation was not counted");
}
