//! # fcc_firmware — the flight-control MCU program
//!
//! Paper A's MCU software: 500 Hz navigation and control for an octorotor, written `no_std`, no
//! heap, f32, with time passed in and hardware behind traits.
//!
//! Layers (bottom-up):
//! - [`sensors`]: sample types (body FRD, SI units, MCU µs) and the hardware traits
//!   (`SensorBoard`, `MotorOutputs`) a board or the simulator implements.
//! - [`nav`]: wires samples into `fcc_nav`'s complementary filters → [`nav::NavState`] (NED).
//! - [`control`]: plain controller structs with `update(dt_s, …)`: cross-track velocity
//!   tracking, forgetting-PI acceleration control on the Luenberger observer, vertical, attitude
//!   PID, yaw, octorotor mixer.
//! - [`flight`]: [`flight::FlightCore::step`]`(now_us, &SensorInputs) -> [f32; 8]` — modes
//!   (disarmed, hold, velocity, land), setpoint time-to-live, failsafes, limits, geofence.
//! - [`scheduler`]: the 500 Hz tick that polls a board and drives the ESCs.
//! - [`pilot`]: the R/C pilot override (switch, receiver failsafe, sticks → velocity).
//! - [`params`]: every gain and limit, documented defaults for the paper's vehicle.
//!
//! Inputs: sensor samples, velocity setpoints with time-to-live and commands
//! ([`commands`]). Outputs: ESC commands 0..1 per motor, plus [`flight::StepTelemetry`].
//!
//! The simulator is a crate of its own beside this one (`fcc_firmware/sim`, package `fcc_sim`,
//! std): octorotor physics, wind, sensor models behind the same traits, scenario files and the
//! `fcc-sitl`/`fcc-campaign` binaries. This crate has no simulator dependency and is `no_std`
//! (unit tests link std).
#![cfg_attr(not(test), no_std)]

pub mod commands;
pub mod control;
pub mod flight;
pub mod geometry;
pub mod land_detector;
pub mod link;
pub mod nav;
pub mod nav_health;
pub mod params;
pub mod pilot;
pub mod scheduler;
pub mod sensors;
