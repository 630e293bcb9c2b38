//! Models whose constant parameters can be read and replaced, so that one set of equations
//! serves both as the truth model and as an estimator's estimated model (thesis Figure 3.2:
//! reference and estimated model share their structure and differ only in the parameters).

use nalgebra::SVector;

/// A model with `P` named constant parameters that can be replaced.
pub trait Parameterized<const P: usize>: Sized {
    /// Parameter names, the same strings as CSV headers (e.g. `"a1"`, `"dCm_alpha"`).
    fn param_names(&self) -> [&'static str; P];
    /// The current parameter values, units as documented by the model.
    fn params(&self) -> SVector<f64, P>;
    /// A copy of the model with the parameters replaced by `theta` (same order and units).
    fn with_params(&self, theta: &SVector<f64, P>) -> Self;
}
