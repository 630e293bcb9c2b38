//! # aeroident-physics
//!
//! The physics every other crate shares, written once: the physical constants and unit
//! conversions ([`units`]), the [`Scalar`] trait that lets one generic function give values
//! (`f64`) and exact derivatives (the estimators' forward-mode `Dual`), and the flat-earth
//! rigid-body equations ([`rigid_body`]) as small generic functions.
//!
//! `no_std`, no allocation, `libm` only, so the same equations run in the simulator (`models`,
//! English units, f64), in the estimators (SI, f64 and `Dual`) and on a flight computer.
//!
//! Source of the equations: Stevens, Lewis & Johnson, *Aircraft Control and Simulation*,
//! 3rd ed., Wiley 2015 (SLJ) §1.3 (Euler angles), §2.3 (wind axes), §2.5 (flat-earth 6-DOF
//! equations) and §3.5 (their mechanisation in the F-16 subroutine `F`).
#![no_std]

pub mod isa;
pub mod rigid_body;
pub mod scalar;
pub mod text;
pub mod units;

pub use scalar::Scalar;
