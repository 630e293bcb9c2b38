//! The [`Scalar`] trait: what a generic model function needs of its numbers, so that one code
//! path gives values (`f64`, implemented here) and exact first derivatives (the estimators'
//! forward-mode `Dual`, which implements it in `aeroident-estimators`).

use core::ops::{Add, Div, Mul, Neg, Sub};

/// A real scalar usable by the generic model code: `f64` (values) or a dual number (values and
/// exact derivatives). Arithmetic with `Self` and with `f64` on the right.
pub trait Scalar:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
{
    /// A constant (zero derivatives).
    fn cst(v: f64) -> Self;
    /// The value (real part).
    fn re(self) -> f64;
    /// Sine (argument in rad).
    fn sin(self) -> Self;
    /// Cosine (argument in rad).
    fn cos(self) -> Self;
    /// Tangent (argument in rad).
    fn tan(self) -> Self;
    /// Square root (derivative undefined at 0: gives ±∞ there, as `1/(2√0)`).
    fn sqrt(self) -> Self;
    /// Four-quadrant arctangent of `self / x`, rad.
    fn atan2(self, x: Self) -> Self;
}

/// Values through `libm`, so a `no_std` build and a `std` build give the same bits.
impl Scalar for f64 {
    #[inline]
    fn cst(v: f64) -> Self {
        v
    }
    #[inline]
    fn re(self) -> f64 {
        self
    }
    #[inline]
    fn sin(self) -> Self {
        libm::sin(self)
    }
    #[inline]
    fn cos(self) -> Self {
        libm::cos(self)
    }
    #[inline]
    fn tan(self) -> Self {
        libm::tan(self)
    }
    #[inline]
    fn sqrt(self) -> Self {
        libm::sqrt(self)
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        libm::atan2(self, x)
    }
}
