//! Exports for other tools: identified derivatives as a JSBSim `<aerodynamics>` fragment
//! ([`jsbsim`]) and planned inputs for the autopilot ([`design`]). Documented in `docs/export.md`.

pub mod design;
pub mod jsbsim;
