//! # fcc_firmware — the flight-control MCU program
//!
//! Paper A's MCU software: 500 Hz navigation and control for an octorotor, written `no_std`, no
//! heap, f32, with time passed in and hardware behind traits.
//!
//! Layers (bottom-up):
//! - [`sensors`]: sample types (body FRD, SI units, MCU µs) and the hardware traits
//!   (`SensorBoard`, `MotorOutputs`) a board or the simulator implements; [`geometry`]: the
//!   octorotor's motor layout (the mixer's and the simulator's one source).
//! - [`nav`]: wires samples into `fcc_nav`'s complementary filters → [`nav::NavState`] (NED);
//!   [`nav_health`]: the estimator-fault monitors; [`land_detector`]: touchdown and landed.
//! - [`control`]: plain controller structs with `update(dt_s, …)`: cross-track velocity
//!   tracking, forgetting-PI acceleration control on the Luenberger observer, vertical, attitude
//!   PID, yaw, octorotor mixer; [`control::cascade::Cascade`] wires them into the one cascade,
//!   `update(dt_s, &NavState, &Demand) -> motors`, with `reset()` and `set_params(&Params)`.
//! - [`flight`]: [`flight::FlightCore::step`]`(now_us, &SensorInputs) -> [f32; 8]` — modes
//!   (disarmed, hold, velocity, land, pilot), setpoint time-to-live, failsafes, limits,
//!   geofence, guidance, land detection → a `Demand` for the cascade; [`commands`]: what the operator may ask (commands, velocity setpoints) and the
//!   refusals; [`pilot`]: the R/C pilot override (switch, receiver failsafe, sticks → velocity);
//!   [`params`]: every gain and limit, documented defaults for the paper's vehicle.
//! - [`touchdown_gate`]: LAND's last decimetres wait for a lull in the gusts.
//! - [`link`]: the MCU end of the serial link to the Linux computer (`fcc_msgs` frames in →
//!   commands, setpoints, parameters; telemetry out).
//! - [`scheduler`]: [`scheduler::FlightComputer::tick`] — the one 500 Hz tick (link in → sensors
//!   → core → ESCs → link out) that the board, the simulator and the QEMU replay all run.
//!
//! Inputs: sensor samples, the link's bytes (velocity setpoints with time-to-live, commands,
//! parameters) and R/C frames. Outputs: ESC commands 0..1 per motor, the link's bytes
//! (telemetry, acknowledgements), plus [`flight::StepTelemetry`].
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
pub mod touchdown_gate;
