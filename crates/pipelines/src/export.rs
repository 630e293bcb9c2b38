//! Exports for other tools: identified derivatives as a JSBSim `<aerodynamics>` fragment
//! ([`jsbsim`]) or a complete JSBSim aircraft ([`jsbsim_aircraft`]), an ArduPilot SITL plane coefficient file ([`ardupilot`]) and a Gazebo
//! `AdvancedLiftDrag` plugin element ([`gazebo`]), and planned inputs ([`design`]) in the
//! forms the autopilots fly ([`autopilot`]). Documented in `docs/export.md`.

pub mod ardupilot;
pub mod autopilot;
pub mod design;
pub mod gazebo;
pub mod jsbsim;
pub mod jsbsim_aircraft;
pub mod uav;
