//! Equation-error regressions `y = φᵀθ + e` for the longitudinal aerodynamic coefficients.
//!
//! Source: Klein & Morelli, *Aircraft System Identification*, AIAA 2006, ch. 5 (equation-error
//! method: the measured coefficient is the dependent variable, the measured states and controls
//! are the regressors); Jategaonkar, *Flight Vehicle System Identification*, AIAA 2015, eq.
//! (5.86)–(5.89) for the HFB-320 model with the `V/V0` terms.
//!
//! The models are linear in the parameters, e.g.
//!
//! ```text
//! Cm = Cm_0 + Cm_alpha·α + Cm_q·q̂ + Cm_de·δe (+ Cm_V·V/V0),   q̂ = q·c̄/(2V)
//! CL = CL_0 + CL_alpha·α (+ CL_V·V/V0)
//! CD = CD_0 + CD_alpha·α (+ CD_V·V/V0)
//! ```
//!
//! Derivatives are per rad (α, δe) and per unit q̂; `Cm_V` etc. per unit `V/V0`.

use nalgebra::SVector;

/// An equation-error regression: from one sample, the regressor vector `φ` (length `P`) and the
/// dependent variable `y`, so that `y = φᵀθ + e`.
pub trait Regressor<const P: usize> {
    /// The measurement sample the regression is formed from.
    type Sample;
    /// Parameter names in the order of `φ`, e.g. `["Cm_0", "Cm_alpha", "Cm_q", "Cm_de"]`.
    fn names(&self) -> [&'static str; P];
    /// `(φ, y)` for one sample. Values are whatever the sample holds; the caller checks
    /// finiteness (the RLS does).
    fn regress(&self, sample: &Self::Sample) -> (SVector<f64, P>, f64);
}

/// Measured non-dimensional coefficients and the regressors they are explained by, at one time.
///
/// Built by the replay pipeline from recorded data (see `aeroident::replay::coefficients`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CoefficientSample {
    /// Sample time, s.
    pub t_s: f64,
    /// Angle of attack at the CG, rad.
    pub alpha_rad: f64,
    /// Non-dimensional pitch rate `q̂ = q·c̄/(2V)`, –.
    pub qhat: f64,
    /// Elevator deflection, rad (sign as recorded; trailing edge down positive for all shipped
    /// mappings).
    pub de_rad: f64,
    /// Speed ratio `V/V0`, –.
    pub v_ratio: f64,
    /// Measured pitching-moment coefficient about the CG, –.
    pub Cm: f64,
    /// Measured lift coefficient (stability axes), –.
    pub CL: f64,
    /// Measured drag coefficient (stability axes), –.
    pub CD: f64,
}

/// A sample that carries its time, so an estimate can be stamped with it.
pub trait Timed {
    /// Sample time, s.
    fn t_s(&self) -> f64;
}

impl Timed for CoefficientSample {
    fn t_s(&self) -> f64 {
        self.t_s
    }
}

/// Which measured coefficient is the dependent variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coefficient {
    /// Pitching moment `Cm`.
    Cm,
    /// Lift `CL`.
    CL,
    /// Drag `CD`.
    CD,
}

/// One term of a linear coefficient model; its regressor value is taken from the sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Term {
    /// Constant 1 (the `_0` parameter).
    Bias,
    /// `α`, rad.
    Alpha,
    /// `q̂ = q c̄/(2V)`.
    Qhat,
    /// `δe`, rad.
    De,
    /// `V/V0`.
    VRatio,
}

impl Term {
    fn value(self, s: &CoefficientSample) -> f64 {
        match self {
            Term::Bias => 1.0,
            Term::Alpha => s.alpha_rad,
            Term::Qhat => s.qhat,
            Term::De => s.de_rad,
            Term::VRatio => s.v_ratio,
        }
    }
}

impl Coefficient {
    fn value(self, s: &CoefficientSample) -> f64 {
        match self {
            Coefficient::Cm => s.Cm,
            Coefficient::CL => s.CL,
            Coefficient::CD => s.CD,
        }
    }

    /// The parameter name of `term` in this coefficient's model, e.g. `(Cm, Qhat)` → `"Cm_q"`.
    pub fn param_name(self, term: Term) -> &'static str {
        use Coefficient as C;
        use Term as T;
        match (self, term) {
            (C::Cm, T::Bias) => "Cm_0",
            (C::Cm, T::Alpha) => "Cm_alpha",
            (C::Cm, T::Qhat) => "Cm_q",
            (C::Cm, T::De) => "Cm_de",
            (C::Cm, T::VRatio) => "Cm_V",
            (C::CL, T::Bias) => "CL_0",
            (C::CL, T::Alpha) => "CL_alpha",
            (C::CL, T::Qhat) => "CL_q",
            (C::CL, T::De) => "CL_de",
            (C::CL, T::VRatio) => "CL_V",
            (C::CD, T::Bias) => "CD_0",
            (C::CD, T::Alpha) => "CD_alpha",
            (C::CD, T::Qhat) => "CD_q",
            (C::CD, T::De) => "CD_de",
            (C::CD, T::VRatio) => "CD_V",
        }
    }
}

/// A linear model of one coefficient with `P` terms, e.g. the pitching moment
/// `Cm = Cm_0 + Cm_alpha α + Cm_q q̂ + Cm_de δe`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LinearCoefficient<const P: usize> {
    /// The dependent coefficient.
    pub coefficient: Coefficient,
    /// The terms, in parameter order.
    pub terms: [Term; P],
}

impl LinearCoefficient<4> {
    /// `Cm = Cm_0 + Cm_alpha α + Cm_q q̂ + Cm_de δe` (Klein & Morelli 2006, ch. 5).
    pub const PITCH_MOMENT: Self = Self {
        coefficient: Coefficient::Cm,
        terms: [Term::Bias, Term::Alpha, Term::Qhat, Term::De],
    };
}

impl LinearCoefficient<4> {
    /// `CL = CL_0 + CL_alpha α + CL_q q̂ + CL_de δe` (Klein & Morelli 2006, ch. 5).
    pub const LIFT_FULL: Self = Self {
        coefficient: Coefficient::CL,
        terms: [Term::Bias, Term::Alpha, Term::Qhat, Term::De],
    };
    /// `CD = CD_0 + CD_alpha α + CD_q q̂ + CD_de δe`.
    pub const DRAG_FULL: Self = Self {
        coefficient: Coefficient::CD,
        terms: [Term::Bias, Term::Alpha, Term::Qhat, Term::De],
    };
}

impl LinearCoefficient<5> {
    /// `Cm = Cm_0 + Cm_alpha α + Cm_q q̂ + Cm_de δe + Cm_V V/V0` (Jategaonkar 2015, eq. 5.87,
    /// HFB-320 model).
    pub const PITCH_MOMENT_V: Self = Self {
        coefficient: Coefficient::Cm,
        terms: [Term::Bias, Term::Alpha, Term::Qhat, Term::De, Term::VRatio],
    };
}

impl LinearCoefficient<2> {
    /// `CL = CL_0 + CL_alpha α`.
    pub const LIFT: Self = Self { coefficient: Coefficient::CL, terms: [Term::Bias, Term::Alpha] };
    /// `CD = CD_0 + CD_alpha α`.
    pub const DRAG: Self = Self { coefficient: Coefficient::CD, terms: [Term::Bias, Term::Alpha] };
}

impl LinearCoefficient<3> {
    /// `CL = CL_0 + CL_alpha α + CL_V V/V0` (Jategaonkar 2015, eq. 5.86).
    pub const LIFT_V: Self =
        Self { coefficient: Coefficient::CL, terms: [Term::Bias, Term::Alpha, Term::VRatio] };
    /// `CD = CD_0 + CD_alpha α + CD_V V/V0` (Jategaonkar 2015, eq. 5.86).
    pub const DRAG_V: Self =
        Self { coefficient: Coefficient::CD, terms: [Term::Bias, Term::Alpha, Term::VRatio] };
}

impl<const P: usize> Regressor<P> for LinearCoefficient<P> {
    type Sample = CoefficientSample;

    fn names(&self) -> [&'static str; P] {
        let mut out = [""; P];
        for (o, t) in out.iter_mut().zip(self.terms.iter()) {
            *o = self.coefficient.param_name(*t);
        }
        out
    }

    fn regress(&self, s: &CoefficientSample) -> (SVector<f64, P>, f64) {
        let phi = SVector::<f64, P>::from_fn(|i, _| self.terms[i].value(s));
        (phi, self.coefficient.value(s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_pitch_moment_regressor_reproduces_linear_model() {
        let s = CoefficientSample {
            t_s: 0.0,
            alpha_rad: 0.1,
            qhat: 0.002,
            de_rad: -0.01,
            v_ratio: 1.02,
            Cm: 0.0,
            CL: 0.4,
            CD: 0.05,
        };
        let r = LinearCoefficient::PITCH_MOMENT_V;
        let (phi, _) = r.regress(&s);
        let theta = SVector::<f64, 5>::new(0.1, -1.0, -27.0, -1.44, -0.01);
        let cm = theta.dot(&phi);
        let expect = 0.1 - 1.0 * 0.1 - 27.0 * 0.002 + 1.44 * 0.01 - 0.01 * 1.02;
        assert!((cm - expect).abs() < 1e-15);
        assert_eq!(r.names(), ["Cm_0", "Cm_alpha", "Cm_q", "Cm_de", "Cm_V"]);
        let (phi, y) = LinearCoefficient::LIFT.regress(&s);
        assert_eq!((phi[0], phi[1], y), (1.0, 0.1, 0.4));
        assert_eq!(LinearCoefficient::DRAG_V.names(), ["CD_0", "CD_alpha", "CD_V"]);
    }
}
