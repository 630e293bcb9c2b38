//! # aeroident-capi
//!
//! The embeddable estimator core with a C ABI: `libaeroident_capi.a` / `libaeroident_capi.so`
//! and the header `include/aeroident.h` (generated from this crate by cbindgen; a test checks
//! the committed copy is current). docs/c-abi.md is the guide.
//!
//! ```c
//! AeroidentEstimator *e = NULL;
//! if (aeroident_estimator_new("rls", model_toml, "forgetting = 0.999", &e) != AEROIDENT_RESULT_OK)
//!     fprintf(stderr, "%s\n", aeroident_last_error_message());
//! AeroidentSample s = {0};             /* SI, radians; optional fields flagged in s.present */
//! ...
//! aeroident_estimator_update(e, &s);   /* no allocation, no panic, no unwind */
//! aeroident_estimator_estimates(e, value, sigma, identified, n);
//! aeroident_estimator_free(e);
//! ```
//!
//! - [`estimator`]: the handle, [`aeroident_estimator_new`] (a kind, a model file's text or a
//!   preset, options as `key = value` TOML; built by the same registry as `aeroident replay`),
//!   [`aeroident_estimator_update`], [`aeroident_estimator_estimates`],
//!   [`aeroident_estimator_state`], [`aeroident_estimator_reset`], [`aeroident_estimator_free`].
//! - [`sample`]: [`AeroidentSample`], the conditioned sample in SI units with a presence mask.
//! - [`error`]: [`AeroidentResult`] codes and [`aeroident_last_error_message`].
//! - [`replayed`] (Rust only): the CSV form of the samples a C caller feeds, in which
//!   `examples/conditioned_samples.rs` writes the samples `aeroident replay` feeds its
//!   estimator for a record, so that a C caller can be fed exactly those.
//!
//! The crate links the estimator core, the model files (`aeroident-io`) and the registry
//! (`aeroident-registry`), not the pipelines or the reports.
//!
//! `unsafe` is confined to the extern functions (raw pointers from C), each pointer checked for
//! NULL before use; every extern function catches panics, so nothing unwinds into C.

pub mod error;
pub mod estimator;
pub mod replayed;
pub mod sample;
pub mod verdict;

pub use error::{AeroidentResult, aeroident_last_error_message};
pub use estimator::{
    AeroidentEstimator, AeroidentState, AeroidentStatus, aeroident_estimator_estimates,
    aeroident_estimator_free, aeroident_estimator_method, aeroident_estimator_n_params,
    aeroident_estimator_new, aeroident_estimator_new_manoeuvre, aeroident_estimator_param_name,
    aeroident_estimator_reset, aeroident_estimator_state, aeroident_estimator_update,
    aeroident_version,
};
pub use sample::AeroidentSample;
pub use verdict::{AeroidentVerdict, aeroident_estimator_flags, aeroident_estimator_verdicts};
