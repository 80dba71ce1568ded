//! # fcc_bridge — the Linux side of the fcc serial link, as a ROS 2 node
//!
//! Reads `fcc_msgs` frames from a serial device or pseudo-terminal, publishes them as standard
//! ROS 2 messages (ENU/FLU, REP-103/105), and forwards velocity setpoints and commands to the
//! MCU. See the README section "ROS 2 bridge" for topics, frames and parameters.
//!
//! Layers: [`ros_types`] (message structs, Jazzy), [`frames`] (every NED/FRD ↔ ENU/FLU
//! conversion), [`convert`] (pure link ↔ ROS conversions), [`timesync`], [`state`] (the
//! sans-IO bridge state machine and counters), [`diag`] (`/diagnostics`), [`bridge`] (serial
//! IO and DDS), [`record`] (the MCAP flight recorder), [`fake_mcu`] (a scripted MCU on a pty,
//! for tests).

pub mod bounded;
pub mod bridge;
pub mod convert;
pub mod diag;
pub mod fake_mcu;
pub mod frames;
pub mod mcu_params;
pub mod params;
pub mod record;
pub mod recover;
pub mod report;
pub mod ros_api;
pub mod ros_node;
pub mod ros_types;
pub mod startup;
pub mod state;
pub mod timesync;

/// Linux realtime clock in ns since the epoch (ROS time without `use_sim_time`).
pub fn now_ns() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as i64)
        .unwrap_or(0)
}
