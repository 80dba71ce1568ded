//! The control cascade of paper A (Fig. 10): velocity (with cross-track compensation) →
//! linear acceleration (feed-forward + forgetting PI on the observer's estimate) → roll/pitch
//! PID and yaw → rate feedback → octorotor mixing. Each stage is a plain struct with an
//! `update(dt_s, …)` ([`velocity`], [`accel`], [`vertical`], [`attitude`], [`mixer`], on the
//! forgetting-factor PI of [`pi`]); [`cascade::Cascade`] wires them into one struct with
//! `update(dt_s, nav, demand)`, which [`crate::flight::FlightCore`] calls with what its modes
//! ask for. [`heading`]: the NED ↔ heading frame (forward, right) rotation the horizontal loops
//! use; [`vec2`]: two 2-vector helpers (norm clamp, sign).

pub mod accel;
pub mod attitude;
pub mod cascade;
pub mod heading;
pub mod mixer;
pub mod pi;
pub mod vec2;
pub mod velocity;
pub mod vertical;
