//! The σ of what one record's linear model leaves unmodelled. The noise σ of every method
//! (Cramér–Rao, its coloured-residual correction, the bootstrap, a filter's covariance) and
//! the sample-timing σ describe the scatter of an unbiased fit; a record also holds biases no
//! test names (a lag, a scale factor or a structure term the model lacks, regressor noise).
//! Flight-test practice has long widened the Cramér–Rao σ by an empirical factor for them
//! (Maine & Iliff, "The theory and practice of estimating the accuracy of dynamic
//! flight-determined coefficients", NASA RP-1077, 1981). Here the widening is a fixed share
//! of each derivative's size, added in quadrature, because the misses it must cover are
//! biases proportional to the value (a timing or scale error scales the derivative), not
//! scatter.
//!
//! The share is calibrated on the verdict corpus (`scripts/verdict_corpus/`, docs/validation.md):
//! on the tune half's aircraft the smallest share on a 0.5 % grid for which ±2σ of the
//! `identified` primary derivatives covers the truth in at least 90 % (5.5 %: 90.8 %, from
//! 68.2 % without); reported on the held-out aircraft (92.1 %, from 71.6 %).

/// The share of `|estimate|` added to every derivative's σ in quadrature (module doc;
/// `aeroident_io::ParameterResult::add_unmodelled_std_error`).
pub const UNMODELLED_FRACTION: f64 = 0.055;
