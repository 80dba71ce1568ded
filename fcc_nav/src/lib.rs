//! `fcc_nav` — `no_std`, heap-free navigation math for the multirotor flight computer
//! (paper A, "navigation: complementary filters at 500 Hz").
//!
//! # Modules
//!
//! | module | concern | inputs | outputs |
//! |---|---|---|---|
//! | [`complementary`] | 2nd-order complementary filters (eq. 1): [`AngleCf`], [`PosVelCf`] | rate / accel, angle / position measurement | angle + rate bias, position + velocity |
//! | [`attitude`] | roll/pitch/yaw estimation (eqs. 2–4), frame rotations | gyro \[rad/s] FRD, accel \[m/s²] FRD, mag \[µT] FRD | [`Euler`] \[rad], NED linear acceleration \[m/s²] |
//! | [`horizontal`] | NE position/velocity from GPS + NED accel | accel NE \[m/s²], GPS NE \[m] + delay steps | pos NE \[m], vel NE \[m/s] |
//! | [`vertical`] | altitude/vertical speed from baro + accel (eqs. 5–6) | accel down \[m/s²], baro altitude \[m] or pressure \[Pa] | altitude up \[m], vel down \[m/s] |
//! | [`range_aid`] | range-aided height: the rangefinder altitude replaces the baro in the vertical filter while valid, baro offset learnt, terrain steps re-anchored | altitude estimate, baro altitude \[m], height above ground \[m] | altitude measurement \[m] |
//! | [`observer`] | Luenberger linear-acceleration observer (eqs. 10–14) | tilt, tilt command \[rad], measured accel \[m/s²] | filtered accel \[m/s²] |
//! | [`math`] | the `f32` elementary functions every module uses (no `f64` on the single-precision FPU) | | |
//! | [`sysid`] | paper A's "3D curve fitting" of `a = k1·θ − k2·v`: streaming least squares ([`PlaneFit`]), and with a wind term per window by least squares (`WindPlaneFit`) or instrumental variables (`WindIvFit`, setpoints as instruments), with standard errors | tilt \[rad], vel \[m/s], accel \[m/s²] (+ instruments) | k1 \[m/s²/rad], k2 \[1/s], intervals |
//! | [`tilt_kf`] | roll/pitch and their rate biases from the GPS velocity's innovation against the latency-aligned inertial velocity, steady-state Kalman gains | NED accel NE \[m/s²] per step, GPS velocity NE \[m/s] + delay steps, yaw \[rad] | roll/pitch corrections \[rad], \[rad/s] |
//!
//! # Conventions
//!
//! * Navigation frame **NED** (north, east, down); body frame **FRD** (forward, right, down).
//! * Euler angles ZYX: `R_body→ned = Rz(ψ)·Ry(θ)·Rx(φ)`; roll positive right wing down, pitch
//!   positive nose up, yaw positive clockwise from north seen from above.
//! * Accelerometers measure **specific force** `f = a − g`: level at rest they read
//!   `[0, 0, −9.81]` m/s² in FRD. Gravity-compensated NED acceleration is `R·f + [0, 0, g]`.
//! * Altitude is reported **up positive** (`alt_m`); NED velocities are down positive.
//! * Units are in names (`_m`, `_mps`, `_mps2`, `_rad`, `_radps`, `_s`, `_pa`, `_ut`, `_deg`).
//!   Everything is `f32`. WGS-84 geodesy (`f64` lat/lon ↔ local NED) is `fcc_msgs::geodesy`,
//!   beside the messages that carry lat/lon.
//! * Every filter `update` takes its own `dt_s`; the design rate is 500 Hz (`dt_s = 0.002`).
#![no_std]
// The bare-metal ARM build (always cross-built with -Zbuild-std, i.e. nightly mode) takes the
// FPU square root from core; see `math::sqrtf`.
#![cfg_attr(all(target_arch = "arm", target_os = "none"), feature(core_float_math))]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

#[cfg(test)]
extern crate std;

pub mod attitude;
pub mod complementary;
pub mod ground_altitude;
pub mod horizontal;
pub mod lowpass;
pub mod math;
pub mod observer;
pub mod range_aid;
pub mod sysid;
pub mod tilt_kf;
pub mod vertical;

#[cfg(test)]
mod test_util;

pub use attitude::{AttitudeEstimator, Euler};
pub use complementary::{AngleCf, CfGains, PosVelCf};
pub use horizontal::HorizontalEstimator;
pub use observer::{AccelObserver, AccelObserverParams};
pub use sysid::{PlaneFit, PlaneFitResult};
pub use vertical::VerticalEstimator;

/// Standard gravity \[m/s²].
pub const GRAVITY_MPS2: f32 = 9.80665;
