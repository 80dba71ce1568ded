//! # fcc_bridge — the Linux side of the fcc serial link, as a ROS 2 node
//!
//! Reads `fcc_msgs` frames from a serial device or pseudo-terminal, publishes them as standard
//! ROS 2 messages (ENU/FLU, REP-103/105), and forwards velocity setpoints and commands to the
//! MCU; records every message into MCAP; reads the recordings back for reports and replay.
//! See the README section "ROS 2 bridge" for topics, frames and parameters.
//!
//! Below this crate: `fcc_msgs` (the link codec and, feature `ros`, the ROS 2 message structs)
//! and `fcc_ros` (`fcc_bridge/ros`: frames, `--ros-args`, the DDS participant, the topic table
//! `fcc_ros::topics` that the publishers, subscriptions and recorder read, start-up protection
//! — shared with `fcc-mission`).
//!
//! Layers (bottom-up; a module uses only modules above it in this list, tests aside):
//! 1. Pure pieces: [`bounded`] (bounded input and rate-limited logs), [`mcu_params`] (the MCU
//!    parameters as ROS parameters), [`timesync`] (MCU clock → ROS time).
//! 2. Conversions: [`convert`] (pure link ↔ ROS message conversions), [`health`] (sensor-health
//!    rules and their `/rosout` transitions).
//! 3. State: [`state`] (the sans-IO bridge state machine and counters), [`diag`]
//!    (`/diagnostics` from the state).
//! 4. Recording: [`record`] (the MCAP flight recorder and its options), [`recover`] (rebuilding
//!    a bag the recorder could not finish).
//! 5. IO: [`ros_api`] (ROS parameters, services, `/rosout`), [`bridge`] (serial IO and DDS, the
//!    session loop).
//! 6. Reading bags back: [`report`] (`bag`, `series`, `figures`, `plot`, `sysid` — for
//!    `fcc-report` and `fcc-replay`).
//! 7. Test tools: [`fake_mcu`] (a scripted MCU on a pty).
//! 8. Security tooling: [`keystore`] (SROS2 keystores with openssl; the documents are
//!    `fcc_ros::sros2`'s).
//!
//! Binaries: `fcc-bridge` (`main.rs`), `fcc-fake-mcu`, `fcc-bag-recover`, `fcc-report`,
//! `fcc-replay`, `fcc-record-bench`, `fcc-keystore` (`src/bin/`). `scripts/check-deps.sh`
//! checks that no module import circles back.

pub mod bounded;
pub mod bridge;
pub mod convert;
pub mod diag;
pub mod fake_mcu;
pub mod health;
pub mod keystore;
pub mod mcu_params;
pub mod record;
pub mod recover;
pub mod report;
pub mod ros_api;
pub mod state;
pub mod timesync;
