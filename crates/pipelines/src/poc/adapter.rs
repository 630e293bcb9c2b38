//! One set of equations for truth and estimated model: any [`Dynamics`] + [`Parameterized`]
//! model becomes an estimator-side [`ParametricModel`] through [`ModelAdapter`]. The
//! estimators crate stays independent of the models crate; this crate joins them.
//!
//! For the F-16: implement `Parameterized<P>` for the aircraft-with-increments
//! model (replacing the increments), then `ModelAdapter(aircraft)` is the estimated model.

use aeroident_estimators::EstimatorError;
use aeroident_estimators::smpe::ParametricModel;
use aeroident_models::Dynamics;
use aeroident_models::parametric::Parameterized;
use nalgebra::SVector;

/// Wraps a truth model so an SMPE estimator can evaluate it with θ̂ in place of the true
/// parameters. Model errors become [`EstimatorError::Numerical`] naming the sample time.
#[derive(Debug, Clone)]
pub struct ModelAdapter<D>(pub D);

impl<D, const N: usize, const P: usize> ParametricModel<N, P> for ModelAdapter<D>
where
    D: Dynamics<N> + Parameterized<P>,
{
    type Input = D::Input;

    fn derivatives(
        &self,
        t_s: f64,
        z: &SVector<f64, N>,
        u: &D::Input,
        theta: &SVector<f64, P>,
    ) -> Result<SVector<f64, N>, EstimatorError> {
        self.0
            .with_params(theta)
            .derivatives(t_s, z, u)
            .map_err(|_| EstimatorError::Numerical { what: "estimated-model derivatives", t_s })
    }
}
