//! # fcc_ros — the ROS 2 node plumbing of the project's nodes
//!
//! What `fcc-bridge` and `fcc-mission` share to be ROS 2 nodes, so that neither depends on the
//! other: the message structs themselves live in `fcc_msgs::ros` (feature `ros` of the `msg`
//! crate).
//!
//! Layers (bottom-up):
//! - [`frames`]: every NED/FRD ↔ ENU/FLU conversion (REP-103/105) — the only home of them.
//! - [`params`]: the command line after `--ros-args` (`-r`, `-p`, `--params-file`), remaps,
//!   and the DDS environment variables.
//! - [`ros_node`]: the DDS participant (built here only), nodes, publishers and subscriptions by
//!   ROS name, the QoS profiles, the ROS clock, [`now_ns`] and [`logger_name`].
//! - [`rmw`]: the middleware (`RMW_IMPLEMENTATION`: DDS or Zenoh) and the handles both nodes
//!   use on either: context, node, publisher, subscription, service server.
//! - [`topics`]: the topic table (name, message type, QoS, direction) that the bridge's
//!   publishers, subscriptions and recorder read; [`topics::QosInfo`].
//! - [`startup`]: start-up protection — the DDS set-up under a watchdog with a restart, and
//!   SIGTERM/SIGINT on a thread of their own.
//! - [`heap`]: the allocator's free pages handed back to the OS every 30 s (a flat RSS over
//!   hours; each node's `main` starts it).
//! - [`security`]: ROS 2 security at start-up: the `ROS_SECURITY_*` environment and
//!   `--enclave`, the enclave directory and its certificate and signature checks.
//! - [`security_events`]: what DDS Security refused (a participant that failed authentication,
//!   an endpoint denied by access control), counted for `/diagnostics`, told on `/rosout`.
//! - [`sros2`]: SROS2 (issue 19): the enclaves' roles and their governance and least-privilege
//!   permissions documents, derived from the topic table (signed by `fcc_bridge::keystore`).

pub mod frames;
pub mod heap;
pub mod params;
pub mod rmw;
pub mod ros_node;
pub mod security;
pub mod security_events;
pub mod sros2;
pub mod startup;
pub mod topics;

pub use ros_node::{logger_name, now_ns};
