//! Support shared by the integration tests.

pub mod jsbsim_mr;
