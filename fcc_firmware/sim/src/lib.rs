//! # fcc_sim — the software-in-the-loop simulator of the flight-control MCU program
//!
//! std, host only; the MCU program (`fcc_firmware`, `no_std`) knows nothing of it. The
//! simulator implements the core's hardware traits (`SensorBoard`, `MotorOutputs`) with models
//! of the paper's octorotor and sensors, owns time (lockstep) and runs the flight computer's tick
//! ([`fcc_firmware::scheduler::FlightComputer::tick`], the one the board and the QEMU replay
//! run) every 2 ms.
//!
//! Layers (bottom-up):
//! - World: [`physics`] (6-DOF rigid body, per-motor lag, drag, landing gear and ground
//!   contact), [`wind`] (mean wind + Dryden turbulence, MIL-F-8785C), [`terrain`] (ground
//!   steps and dark patches).
//! - Sensors: [`sensor_models`] (MPU-9250, AK8963, MS5611, GPS, battery with datasheet noise),
//!   [`rangefinders`] (ILM-150-R laser, MB7076 sonar over the terrain), [`pilot`] (a scripted
//!   R/C pilot behind a simulated S.BUS receiver).
//! - Peers: [`linux`] (the in-process mission computer, `fcc_mission`'s waypoint logic) or
//!   [`pty`] (the board's UART as a pseudo-terminal the bridge opens like a serial port).
//! - Flight: [`scenario`] (YAML scenario files), [`sim`] (the lockstep loop).
//! - Scoring: [`log`] (what a flight leaves), [`metrics`] (paper A's figures), [`truth`]
//!   (contacts, crashes, excursions on the true state), [`campaign`] (Monte-Carlo families of
//!   flights scored on the truth).
//!
//! Binaries: `fcc-sitl` (one scenario, or the link served on a pty), `fcc-campaign` (the
//! campaign). Bench: `sitl_speed`.

pub mod campaign;
pub mod linux;
pub mod log;
pub mod metrics;
pub mod physics;
pub mod pilot;
pub mod pty;
pub mod rangefinders;
pub mod scenario;
pub mod sensor_models;
pub mod sim;
pub mod terrain;
pub mod truth;
pub mod wind;
