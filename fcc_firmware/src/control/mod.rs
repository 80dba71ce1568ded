//! The control cascade of paper A (Fig. 10): velocity (with cross-track compensation) →
//! linear acceleration (feed-forward + forgetting PI on the observer's estimate) → roll/pitch
//! PID and yaw → rate feedback → octorotor mixing. Each stage is a plain struct with an
//! `update(dt_s, …)`; [`crate::flight::FlightCore`] wires them. [`heading`]: the NED ↔ heading
//! frame (forward, right) rotation the horizontal loops use.

pub mod accel;
pub mod attitude;
pub mod heading;
pub mod mixer;
pub mod pi;
pub mod velocity;
pub mod vertical;
