//! Software-in-the-loop simulator (std): the paper's octorotor, wind, sensor models, scenarios.
//! Lockstep: the simulator owns time and drives [`crate::scheduler`]'s tick every 2 ms.
//!
//! - [`physics`]: 6-DOF rigid body, per-motor lag, drag, ground contact.
//! - [`wind`]: mean wind + Dryden turbulence (MIL-F-8785C).
//! - [`sensor_models`]: MPU-9250, AK8963, MS5611, GPS, battery with datasheet noise.
//! - [`scenario`]: YAML scenario files; [`linux`]: the in-process mission computer;
//!   [`pilot`]: a scripted R/C pilot behind a simulated S.BUS receiver.
//! - [`pty`]: the board's UART as a pseudo-terminal the bridge opens like a serial port.
//! - [`sim`]: the lockstep loop; [`log`] and [`metrics`]: what a flight leaves and its figures.

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
